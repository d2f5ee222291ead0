"""``mmusv.sensors.mounts``: a mount's transform against the rotation worked out by hand, the fall-back mount on
the hull's top, and the inside-the-hull test against a box whose inside is known."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mmusv.sensors.config import Mount
from mmusv.sensors.mounts import inside_mesh, mount_matrix, rpy_matrix
from mmusv.world.vessels import get_asset


def _box(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """An axis-aligned box's 8 vertices and 12 outward-facing triangles (two per face)."""
    v = np.array([[(lo, hi)[i >> k & 1][k] for k in range(3)] for i in range(8)], dtype=np.float64)
    quads = [(0, 2, 6, 4), (1, 5, 7, 3), (0, 4, 5, 1), (2, 3, 7, 6), (0, 1, 3, 2), (4, 6, 7, 5)]
    f = [(a, b, c) for a, b, c, d in quads] + [(a, c, d) for a, b, c, d in quads]
    # each triangle turned to face outward: (b - a) x (c - a) away from the centre
    centre = 0.5 * (np.array(lo) + np.array(hi))
    f = [(a, b, c) if np.dot(np.cross(v[b] - v[a], v[c] - v[a]), v[a] - centre) > 0 else (a, c, b) for a, b, c in f]
    faces = np.array(f, dtype=np.uint32)
    return v, faces


def test_rpy_matrix_is_the_rotation_worked_out_by_hand() -> None:
    m = rpy_matrix((1.0, 2.0, 3.0), (0.0, 0.0, 90.0))  # yaw 90°: x forward -> y
    np.testing.assert_allclose(m[:3, 3], [1, 2, 3])
    np.testing.assert_allclose(m[:3, :3] @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    p = rpy_matrix((0.0, 0.0, 0.0), (0.0, 30.0, 0.0))  # pitch about y: x tips down (z up, right-handed)
    np.testing.assert_allclose(p[:3, :3] @ [1, 0, 0], [math.cos(math.radians(30)), 0, -0.5], atol=1e-12)


def test_a_mount_point_the_asset_lacks_falls_back_to_the_hull_top() -> None:
    asset = get_asset("bulk_carrier_190m")
    assert "camera_left" not in asset.mounts
    m = mount_matrix(asset, Mount(point="camera_left", xyz=(1.0, 0.0, 0.0)), where="rigs.r.cameras[left].mount")
    np.testing.assert_allclose(m[:3, 3], [0.0, 1.0, float(asset.bbox[1, 2]) + 0.5], atol=1e-9)  # looks left
    np.testing.assert_allclose(m[:3, :3] @ [1, 0, 0], [0, 1, 0], atol=1e-12)


def test_a_mount_that_is_not_a_finite_pose_is_refused_by_name() -> None:
    bad = Mount.model_construct(point=None, xyz=(0.0, 0.0, math.nan), rpy_deg=(0.0, 0.0, 0.0))
    with pytest.raises(Exception, match=r"rigs\.r\.lidar\.mount: the mount is not a finite pose"):
        mount_matrix(get_asset("bulk_carrier_190m"), bad, where="rigs.r.lidar.mount")


@pytest.mark.parametrize(
    ("point", "inside"),
    [((0.5, 0.5, 0.5), True), ((0.9, 0.1, 0.2), True), ((1.5, 0.5, 0.5), False), ((0.5, 0.5, -0.01), False)],
)
def test_inside_mesh_of_a_box(point: tuple[float, float, float], inside: bool) -> None:
    v, f = _box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    assert inside_mesh(v, f, point=np.array(point)) is inside


def test_inside_mesh_of_two_boxes_is_their_union() -> None:
    a, fa = _box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    b, fb = _box((3.0, 0.0, 0.0), (4.0, 1.0, 1.0))
    v, f = np.concatenate([a, b]), np.concatenate([fa, fb + 8])
    assert inside_mesh(v, f, point=np.array([3.5, 0.5, 0.5]))  # rays through the first box count it in and out
    assert inside_mesh(v, f, point=np.array([0.5, 0.5, 0.5]))
    assert not inside_mesh(v, f, point=np.array([2.0, 0.5, 0.5]))  # between them


def test_a_camera_without_a_mount_sits_on_the_assets_camera_point_not_at_the_waterline() -> None:
    """A rig's camera given no ``mount`` sat at the vessel origin, midship at the waterline: at W3 a 160 x 120 camera
    on a WAM-V saw the water above it labelled sky in its bottom rows and a 90 m ferry 162 m ahead not at all (the
    acceptance audit's finding). It now sits on the asset's ``camera_<name>`` point, else ``camera_front``, else the
    hull's top turned as its name says; a mount given stays."""
    from mmusv.sensors.config import CameraConfig
    from mmusv.sensors.mounts import camera_mount
    from mmusv.simulation import Simulation

    wamv, bulk = get_asset("usv_wamv"), get_asset("bulk_carrier_190m")
    assert camera_mount(wamv, CameraConfig(name="left")) == Mount(point="camera_left")
    assert camera_mount(wamv, CameraConfig(name="mast")) == Mount(point="camera_front")
    assert "camera_left" not in bulk.mounts and "camera_front" not in bulk.mounts
    assert camera_mount(bulk, CameraConfig(name="left")) == Mount(point="camera_left")  # the hull's top, looking left
    given = Mount(xyz=(0.0, 0.0, 3.0))
    assert camera_mount(wamv, CameraConfig(name="left", mount=given)) == given
    sim = Simulation(
        {
            "seed": 1,
            "environment": {"wave": "W3"},
            "acquisition": {"frequency_hz": 5, "frames": 1},
            "rigs": {
                "r": {
                    "lidar": None,
                    "radar": None,
                    "top_view": None,
                    "cameras": [{"name": "cam", "resolution": [160, 120]}],
                }
            },
            "vessels": [
                {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 0, "route": [[0, 0], [10, 0]]},
                {"id": "f", "asset": "ropax_ferry_90m", "speed_mps": 0, "route": [[162, 0], [300, 0]]},
            ],
        }
    )
    front = wamv.mounts["camera_front"]
    np.testing.assert_allclose(sim.agents[0].mounts()["camera/cam"][:3, 3], front.xyz, atol=1e-12)
    img = sim.capture(0).agents["u"].cameras["cam"]
    assert np.all(img.instance[:10] == -1) and not np.any(img.instance[-10:] == -1)  # sky above, water below
    ferry = sim.vessels[1].instance_id
    assert np.count_nonzero(img.instance == ferry) > 100
