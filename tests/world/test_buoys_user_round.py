"""A user's round on the buoys riding the waves (each buoy its own instance, posed on the physical sea).

Every check here is worked out apart from the code under test: which buoy a LiDAR point or a camera pixel shows is
found from the geometry (the nearest rest position, the depth along the optical axis), the buoy's waterline and
tilt from rays cast up at its float's flat bottom in the simulation's scene (three rays give the bottom's plane, so
its axis, and the centre ray its height), and the water it should float in is the surface the sensors meet
(``Scene.wave_heights``). The recording and its exports are read back as a user reads them.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mmusv.acquire import run
from mmusv.classes import SemanticClass
from mmusv.export import convert
from mmusv.recording import decode_image, decode_point_cloud, read_messages, topics
from mmusv.simulation import Simulation
from mmusv.world import buoys as buoys_module
from mmusv.world.buoys import buoy_matrices
from mmusv.world.port import buoy_mesh
from mmusv.world.sea_state import sea_spec_for_preset
from PIL import Image

BUOY = int(SemanticClass.BUOY)
FLOAT_R_M = 1.2
"""The float's radius (``mmusv.world.port.buoy_mesh``)."""
DRAFT_M = 1.0
"""The float's flat bottom below its waterline (``buoy_mesh``: the body's base at z = -1)."""
MARK_TOP_M = 3.8
"""The top mark's tip above the waterline."""
SWAY_M = FLOAT_R_M + MARK_TOP_M * np.sin(np.radians(30.0)) + 0.1
"""How far from its rest position (horizontally) a point of a buoy tilted by up to 30 degrees can lie."""
BUOY_XY = np.array([[40.49, -222.19], [17.25, -106.98], [-335.69, 239.93], [281.36, -237.80]])
"""The rest positions of the four buoys of ``open_sea`` seed 2 (1 km, no islet), to the centimetre."""


def _scenario(
    *, wave: Any = "W3", motion: str = "physical", frames: int = 4, cameras: bool = True, target: bool = False
) -> dict[str, Any]:
    """The ``open_sea`` map with four buoys; one USV 25 m west of buoy 0, heading east at it (slowly)."""
    rig: dict[str, Any] = {
        "preset": "lidar_only",
        "lidar": {"channels": 32, "points_per_second": 32 * 1800 * 5, "vertical_fov_deg": [-15, 5]},
    }
    if cameras:
        rig["cameras"] = [{"name": "front", "resolution": [320, 160], "hfov_deg": 40}]
    usv = {"id": "usv", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 0.5,
           "route": [[15.5, -222.2], [20.5, -222.2]]}  # fmt: skip
    vessels = [usv]
    if target:
        vessels.append({"id": "boat", "role": "target", "asset": "fishing_boat_12m", "speed_mps": 1.0,
                        "route": [[80.0, -240.0], [80.0, -200.0]]})  # fmt: skip
    return {
        "name": "buoys_user",
        "seed": 3,
        "map": {"type": "open_sea", "seed": 2, "params": {"extent_m": 1000, "islet_probability": 0.0, "n_buoys": 4}},
        "environment": {"time_of_day": "11:00", "weather": "clear", "wave": wave, "motion": motion},
        "acquisition": {"frequency_hz": 5, "frames": frames},
        "rigs": {"r": rig},
        "vessels": vessels,
    }


def _nearest_buoy(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index of the nearest rest position and the horizontal distance to it, for ``(N, 2)`` points."""
    d = np.linalg.norm(xy[:, None, :] - BUOY_XY[None, :, :], axis=2)
    return d.argmin(axis=1), d.min(axis=1)


def test_the_map_has_the_buoys_this_file_assumes() -> None:
    sim = Simulation(_scenario(cameras=False))
    np.testing.assert_allclose(sim.world.priors.buoys, BUOY_XY, atol=0.01)


def test_each_buoy_is_one_id_of_its_own_in_the_lidar_and_the_camera() -> None:
    """Class ``buoy`` exactly where the id is a buoy's, in the LiDAR's points and the camera's pixels alike, and the
    id names the same buoy (found from the geometry) in both, at every frame."""
    sim = Simulation(_scenario())
    ids = [int(i) for i in sim.ws.buoy_instances]
    assert len(set(ids)) == len(BUOY_XY)
    others = set(sim.ws.static_instances.values()) | {v.instance_id for v in sim.vessels}
    assert not set(ids) & others
    for frame in (0, 3):
        a = sim.capture(frame, radar=False).agents["usv"]
        # LiDAR: each buoy point lies on the buoy its id names.
        pts = a.lidar
        world = pts.xyz.astype(np.float64) @ a.lidar_pose[:3, :3].T + a.lidar_pose[:3, 3]
        on_buoy = np.isin(pts.instance, ids)
        np.testing.assert_array_equal(on_buoy, pts.semantic_class == BUOY)
        k, dist = _nearest_buoy(world[on_buoy, :2])
        np.testing.assert_array_equal(np.asarray(ids)[k], pts.instance[on_buoy])
        assert dist.max() < SWAY_M
        lidar_seen = {int(i) for i in np.unique(pts.instance[on_buoy])}
        assert {ids[0], ids[1]} <= lidar_seen and (pts.instance == ids[0]).sum() > 50
        # Camera: the pixels of buoy k lie at its distance along the optical axis (the pose's x axis).
        cam, pose = a.cameras["front"], a.camera_poses["front"]
        inst = cam.instance
        np.testing.assert_array_equal(np.isin(inst, ids), cam.semantic == BUOY)
        camera_seen = {int(i) for i in np.unique(inst[np.isin(inst, ids)])}
        assert ids[0] in camera_seen and (inst == ids[0]).sum() > 200
        for i in camera_seen:
            along = (np.append(BUOY_XY[ids.index(i)], 0.0) - pose[:3, 3]) @ pose[:3, 0]
            depth = cam.depth[inst == i]
            assert np.abs(depth - along).max() < SWAY_M, (frame, i)
        assert ids[0] in lidar_seen & camera_seen  # one id, one buoy, in both sensors


def test_ids_and_images_are_the_same_in_a_second_simulation() -> None:
    one, two = Simulation(_scenario()), Simulation(_scenario())
    assert one.ws.buoy_instances == two.ws.buoy_instances
    a, b = one.capture(2, radar=False).agents["usv"], two.capture(2, radar=False).agents["usv"]
    for kind in ("instance", "semantic", "depth"):
        assert getattr(a.cameras["front"], kind).tobytes() == getattr(b.cameras["front"], kind).tobytes()
    assert a.lidar.instance.tobytes() == b.lidar.instance.tobytes() and a.lidar.xyz.tobytes() == b.lidar.xyz.tobytes()


def _bottom(sim: Simulation, frame: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rays cast straight up from 40 m below at each buoy's rest position and 0.7 m east and north of it, after
    ``set_frame(frame)``: the instance met at the centre, the buoy's waterline height (from the centre hit on the
    float's flat bottom and the bottom's plane) and its axis (the bottom plane's normal), ``(B,)``, ``(B,)``,
    ``(B, 3)``."""
    sim.set_frame(frame, shading_detail=False)
    b = len(BUOY_XY)
    offsets = np.array([[0.0, 0.0], [0.7, 0.0], [0.0, 0.7]])
    xy = (BUOY_XY[:, None, :] + offsets[None]).reshape(-1, 2)
    hits = sim.ws.scene.cast_rays(
        np.column_stack([xy, np.full(len(xy), -40.0)]), np.tile([0.0, 0.0, 1.0], (len(xy), 1))
    )
    z = (-40.0 + hits.distance).reshape(b, 3)
    inst = hits.instance_id.reshape(b, 3)
    assert (inst == inst[:, :1]).all()
    n = np.column_stack([-(z[:, 1] - z[:, 0]) / 0.7, -(z[:, 2] - z[:, 0]) / 0.7, np.ones(b)])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    # The bottom's centre is the waterline point less DRAFT_M along the axis; the vertical at the rest position
    # meets the bottom's plane at z[:, 0]: waterline = z0 + DRAFT·n_z + DRAFT·(n_x² + n_y²)/n_z.
    waterline = z[:, 0] + DRAFT_M * (n[:, 2] + (n[:, 0] ** 2 + n[:, 1] ** 2) / n[:, 2])
    return inst[:, 0], waterline, n


@pytest.mark.parametrize("wave", ["W1", "W2", "W3"])
def test_buoys_near_the_usv_float_in_the_water_the_sensors_see(wave: str) -> None:
    """Over a physical sea the buoys near the USV ride the water the sensors meet there and move from frame to
    frame: the waterline at that water's height to 8 cm 25 m out (1 m cells), to 30 cm 115 m out (4 m cells, which
    leave out the elevation of the waves shorter than about 8 m the buoy still rides)."""
    sim = Simulation(_scenario(wave=wave, cameras=False, frames=12))
    ids = np.asarray(sim.ws.buoy_instances)
    near = [0, 1]  # 25 m and 115 m from the USV
    lines = []
    for frame in range(0, 12, 3):
        inst, waterline, _axis = _bottom(sim, frame)
        np.testing.assert_array_equal(inst, ids)
        water = sim.ws.scene.wave_heights(BUOY_XY).astype(np.float64)
        assert abs(waterline[0] - water[0]) < 0.08 and abs(waterline[1] - water[1]) < 0.3, (frame, waterline, water)
        lines.append(waterline)
    assert np.ptp(np.array(lines)[:, near], axis=0).min() > 0.2


@pytest.mark.parametrize("case", [{"motion": "paper"}, {"wave": 0.0}, {"wave": "W3", "motion": "paper"}])
def test_buoys_stand_at_rest_with_paper_motion_or_a_calm_sea(case: dict[str, Any]) -> None:
    """At rest: upright, the waterline at the still level (to the float32 rays' precision), the same at every frame."""
    sim = Simulation(_scenario(cameras=False, frames=12, **case))
    first = _bottom(sim, 0)
    for frame in (0, 5, 11):
        inst, waterline, axis = _bottom(sim, frame)
        np.testing.assert_array_equal(inst, sim.ws.buoy_instances)
        np.testing.assert_allclose(waterline, 0.0, atol=1e-4)
        np.testing.assert_allclose(axis, np.tile([0.0, 0.0, 1.0], (len(BUOY_XY), 1)), atol=1e-4)
        assert np.array_equal(waterline, first[1]) and np.array_equal(axis, first[2])


def test_a_recording_and_its_exports_treat_the_buoys_as_documented(tmp_path: Path) -> None:
    """docs/recording.md: each buoy an instance id of its own, class ``buoy``, in the camera's instance images and
    the LiDAR's ``instance``; the same bytes for the same scenario. docs/exports.md: SemanticKITTI gives buoy points
    instance 0 (stuff) and class ``buoy``; MaSTr masks them 0 (obstacle); COCO annotates vessels only."""
    recs = [run(_scenario(target=True, frames=2), out_dir=tmp_path / k, checks=False).recording for k in "ab"]
    assert recs[0].read_bytes() == recs[1].read_bytes()
    rec = recs[0]
    msgs: dict[str, list[Any]] = {}
    for topic, _t, msg in read_messages(rec):
        msgs.setdefault(topic, []).append(msg)
    buoy_ids = sorted(Simulation(_scenario(target=True, frames=2)).ws.buoy_instances)
    vessel_ids = [v.instance_id for v in msgs[topics.WORLD_STATE][0].vessels]
    assert not set(buoy_ids) & set(vessel_ids)
    clouds = [decode_point_cloud(m) for m in msgs["/usv/lidar"]]
    inst_images = [np.asarray(decode_image(m)) for m in msgs["/usv/camera/front/instance"]]
    sem_images = [np.asarray(decode_image(m)) for m in msgs["/usv/camera/front/semantic"]]
    for cloud, inst, sem in zip(clouds, inst_images, sem_images, strict=True):
        np.testing.assert_array_equal(np.isin(cloud["instance"], buoy_ids), cloud["class"] == BUOY)
        np.testing.assert_array_equal(np.isin(inst, buoy_ids), sem == BUOY)
        assert buoy_ids[0] in set(cloud["instance"].tolist()) & set(inst.ravel().tolist())
    out = tmp_path / "out"
    for to in ("semantickitti", "mastr", "coco"):
        convert(rec, to=to, out_dir=out / to, splits=None)
    labels = sorted((out / "semantickitti" / "sequences" / "00" / "labels").glob("*.label"))
    for path, cloud in zip(labels, clouds, strict=True):
        lab = np.fromfile(path, dtype="<u4")
        on_buoy = np.isin(cloud["instance"], buoy_ids)
        assert on_buoy.any() and (lab[on_buoy] == BUOY).all()  # instance 0, class buoy
        on_vessel = np.isin(cloud["instance"], vessel_ids)
        np.testing.assert_array_equal(lab[on_vessel] >> 16, cloud["instance"][on_vessel])
    masks = sorted((out / "mastr" / "masks").rglob("*m.png"))
    for path, inst in zip(masks, inst_images, strict=True):
        mask = np.asarray(Image.open(path))
        assert (mask[np.isin(inst, buoy_ids)] == 0).all()
    coco = json.loads(next((out / "coco" / "annotations").glob("*.json")).read_text())
    anns = coco["annotations"]
    assert anns and {a["instance_id"] for a in anns} <= set(vessel_ids)
    assert all(a["category_id"] != BUOY for a in anns)


def _tilts_deg(field: Any, xy: np.ndarray, times: np.ndarray) -> np.ndarray:
    return np.degrees(np.concatenate([np.arccos(buoy_matrices(field, xy, t)[:, 2, 2]) for t in times]))


def test_a_buoy_does_not_tilt_with_waves_shorter_than_itself() -> None:
    """At W0 (Hs 0.5 m, waves of 19 m at the peak) a 2.4 m float follows the waves at least twice its diameter
    long: its rms tilt is about that of those waves' slopes, not that of the ripples' (worked out from the field's
    components: the slope variance of a linear sea is the sum of a²k²/2)."""
    field = sea_spec_for_preset("W0").field(scenario_seed=7)
    a, _omega, k, _dir, _phase = np.asarray(field.components()).T
    longer = 2.0 * np.pi / k >= 2.0 * (2.0 * FLOAT_R_M)
    rms_long = np.degrees(np.sqrt(np.sum((a**2 * k**2 / 2.0)[longer])))
    xy = np.random.default_rng(0).uniform(-400.0, 400.0, size=(200, 2))
    tilt = _tilts_deg(field, xy, np.arange(0.0, 10.0, 0.2))
    assert np.sqrt(np.mean(tilt**2)) < 1.25 * rms_long


def test_a_buoy_far_from_the_usvs_floats_in_the_water_the_sensors_see() -> None:
    """The surface the sensors meet tapers to still water 260-320 m from the nearest USV (a level of detail: the
    sea beyond is drawn flat, its slopes shading it as roughness). A buoy out there floats in that water, not in
    the full waves: 580 m out it stands upright at the still level (it sank 1.3 m into it, or lifted its float
    clear, riding the full W3 field), and 262-266 m out, in the taper, it rides the tapered waves, its waterline
    at the tapered water's height to 15 cm (8 m cells there) and its tilt tapered with it."""
    sim = Simulation(_scenario(wave="W3", cameras=False, frames=8))
    far, band = 2, 3  # 580 m and 262-266 m from the USV
    band_lines = []
    for frame in (0, 2, 4, 6):
        _inst, waterline, axis = _bottom(sim, frame)
        water = sim.ws.scene.wave_heights(BUOY_XY).astype(np.float64)
        assert water[far] == 0.0 and abs(waterline[far]) < 1e-4, (frame, waterline[far])
        np.testing.assert_allclose(axis[far], [0.0, 0.0, 1.0], atol=1e-4)
        assert abs(waterline[band] - water[band]) < 0.15, (frame, waterline[band], water[band])
        band_lines.append(waterline[band])
    assert np.ptp(band_lines) > 0.05  # it still moves there


def test_the_module_states_the_draft_the_mesh_has() -> None:
    """mmusv.world.buoys said "a 2.5 m draft gives a heave period of about 3.5 s" while the buoy's float reaches
    1.0 m below its waterline (the mesh's lowest vertex at z = -1.0): the heave period it works out (and so the
    claim that the resonance lies near W0's peak period) was that of a float 2.5 times as deep."""
    lowest = float(np.asarray(buoy_mesh(0.0, 0.0).vertices)[:, 2].min())
    stated = re.findall(r"\ba\s+([0-9.]+) m\s+draft", buoys_module.__doc__ or "")
    assert stated and all(float(s) == pytest.approx(-lowest) for s in stated)
