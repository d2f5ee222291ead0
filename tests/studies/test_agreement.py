"""Table II: 3D-box annotations agree with the top-view rendering; a displaced box is caught."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mmusv.config import load_scenario
from mmusv.frames import translation
from mmusv.simulation import Simulation
from mmusv.studies.agreement import run_agreement_study, sample_agreement

ROOT = Path(__file__).resolve().parents[2]


def test_bundled_scenarios_agree_within_a_pixel() -> None:
    study = run_agreement_study(
        [str(ROOT / "scenarios/open_sea_convoy.yaml"), str(ROOT / "scenarios/port_entry.yaml")], frames=1
    )
    s = study.summary
    assert s.height == 2 and (s["valid_samples"] > 0).all()
    assert (s["median_centre_error_px"] <= 1.0).all()
    assert (s["mean_containment"] >= 0.999).all()
    assert ((s["mean_hull_occupancy"] > 0.2) & (s["mean_hull_occupancy"] <= 1.0)).all()


def test_a_box_displaced_by_five_pixels_is_reported() -> None:
    # The paper's motion (sub-degree roll and pitch), so that the boxes in place agree to a pixel: in the physical
    # W2 sea a hull tilted by degrees shifts its top-view silhouette's centre by about a pixel (1.2 px measured).
    scenario = load_scenario(ROOT / "scenarios/open_sea_convoy.yaml").with_sea(None, motion="paper")
    sim = Simulation(scenario)
    cap = sim.capture(0, sensors=["top_view"])
    agent = sim.agents[0]
    tv = cap.agents[agent.id]
    assert tv.top_view is not None and tv.top_view_pose is not None and agent.rig.top_view is not None
    m = agent.rig.top_view.metres_per_pixel
    results = []
    for shift in (0.0, 5.0):
        for vi, info in enumerate(sim.vessels):
            if vi == agent.index:
                continue
            box = cap.world.matrices[vi].copy()
            box[:3, 3] = box[:3, :3] @ info.box_center_body + box[:3, 3] + np.array([shift * m, 0.0, 0.0])
            r = sample_agreement(
                semantic=tv.top_view.semantic,
                instance=tv.top_view.instance,
                camera_pose=tv.top_view_pose,
                metres_per_pixel=m,
                box_matrix=box,
                box_size=info.box_size,
                instance_id=info.instance_id,
            )
            if r is not None:
                results.append((shift, info.id, r))
    # Compare vessels valid both in place and displaced (a displaced hull can newly fit the image).
    both = {i for s, i, _ in results if s == 0.0} & {i for s, i, _ in results if s == 5.0}
    exact = [r for s, i, r in results if s == 0.0 and i in both]
    moved = [r for s, i, r in results if s == 5.0 and i in both]
    assert exact and moved
    assert max(r["centre_error_px"] for r in exact) <= 1.0
    assert min(r["centre_error_px"] for r in moved) >= 4.0
    assert max(r["containment"] for r in moved) < 0.9
    assert min(r["containment"] for r in exact) == 1.0


def _rasterised_mask(
    vertices: np.ndarray, faces: np.ndarray, camera_pose: np.ndarray, metres_per_pixel: float, shape: tuple[int, int]
) -> tuple[np.ndarray, tuple[int, int, int, int]] | None:
    """An independent top view of one mesh over flat water at z = 0: each pixel centre's downward ray (the top
    view's axis) meets the mesh where shapely finds the centre inside a projected triangle; the pixel shows the
    vessel when the highest such point (the first met) lies above the water. Returns the mask over the window
    ``(v0, v1, u0, u1)`` of the mesh's footprint, or ``None`` when the mesh leaves the image.

    ``vertices``: ``(N, 3)`` world metres; ``faces``: ``(M, 3)`` indices."""
    import shapely

    h, w = shape
    inv = np.linalg.inv(camera_pose)
    body = vertices @ inv[:3, :3].T + inv[:3, 3]
    uv = np.stack([w / 2.0 - body[:, 1] / metres_per_pixel, h / 2.0 - body[:, 2] / metres_per_pixel], axis=1)
    if uv.min() < 0 or uv[:, 0].max() > w or uv[:, 1].max() > h:
        return None
    tri = faces[(vertices[faces][:, :, 2] > 0.0).any(axis=1)]  # faces wholly under water cannot show
    corners = uv[tri]
    tree = shapely.STRtree(shapely.polygons(np.concatenate([corners, corners[:, :1]], axis=1)))
    u0, v0 = (int(np.floor(c)) for c in uv.min(axis=0))
    u1, v1 = (int(np.ceil(c)) for c in uv.max(axis=0))
    vv, uu = np.mgrid[v0:v1, u0:u1]
    p = np.stack([uu.ravel() + 0.5, vv.ravel() + 0.5], axis=1)
    pi, tj = tree.query(shapely.points(p), predicate="intersects")
    # Barycentric weights of each pixel centre in its triangle, for the height above water and the distance
    # along the axis (body x) of the point met.
    a, b, c = corners[tj, 0], corners[tj, 1], corners[tj, 2]
    q = p[pi]
    den = (b[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (a[:, 1] - c[:, 1])
    den = np.where(np.abs(den) > 1e-12, den, np.nan)  # edge-on triangles meet no ray
    l0 = ((b[:, 1] - c[:, 1]) * (q[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (q[:, 1] - c[:, 1])) / den
    l1 = ((c[:, 1] - a[:, 1]) * (q[:, 0] - c[:, 0]) + (a[:, 0] - c[:, 0]) * (q[:, 1] - c[:, 1])) / den
    weights = np.stack([l0, l1, 1.0 - l0 - l1], axis=1)
    z = (weights * vertices[tri[tj]][:, :, 2]).sum(axis=1)
    along = (weights * body[tri[tj]][:, :, 0]).sum(axis=1)
    first = np.full(p.shape[0], np.inf)
    z_first = np.full(p.shape[0], -np.inf)
    order = np.argsort(np.where(np.isnan(along), -np.inf, along))[::-1]  # nearest last: it wins the writes
    order = order[~np.isnan(along[order])]
    first[pi[order]] = along[order]
    z_first[pi[order]] = z[order]
    return (np.isfinite(first) & (z_first > 0.0)).reshape(vv.shape), (v0, v1, u0, u1)


def test_top_view_masks_and_centre_errors_match_an_independent_rasterisation() -> None:
    # Table II's centre error is not zero (median 0.45-0.55 px on the bundled maps): is that the labels or the
    # renderer, or the vessels' own shapes? Over flat water (the paper's motion) every vessel's top-view pixels
    # are drawn again from its labelled pose and its asset's mesh by shapely (no mmusv ray casting): the masks
    # agree pixel for pixel and the study's centre error is the same number on both, so what remains is the
    # meshes' shapes at the pixel centres (a pointed bow's tip narrower than a pixel), not a misplaced label.
    from mmusv.world.vessels import get_asset

    scenario = load_scenario(ROOT / "scenarios/open_sea_convoy.yaml").with_sea(None, motion="paper")
    sim = Simulation(scenario)
    cap = sim.capture(3, sensors=["top_view"])
    compared = 0
    for agent in sim.agents:
        tv = cap.agents[agent.id]
        assert tv.top_view is not None and tv.top_view_pose is not None and agent.rig.top_view is not None
        m = agent.rig.top_view.metres_per_pixel
        sem, inst = tv.top_view.semantic, tv.top_view.instance
        for vi, info in enumerate(sim.vessels):
            if vi == agent.index:
                continue
            mesh = get_asset(info.asset).mesh
            pose = cap.world.matrices[vi]
            world = np.asarray(mesh.vertices, dtype=np.float64) @ pose[:3, :3].T + pose[:3, 3]
            drawn = _rasterised_mask(world, np.asarray(mesh.faces), tv.top_view_pose, m, inst.shape)
            if drawn is None:
                continue
            mask, (v0, v1, u0, u1) = drawn
            rendered = inst[v0:v1, u0:u1] == info.instance_id
            assert mask.any(), info.id
            assert np.array_equal(mask, rendered), (agent.id, info.id, int(np.count_nonzero(mask != rendered)))
            whole = np.zeros(inst.shape, dtype=bool)
            whole[v0:v1, u0:u1] = mask
            box = pose @ translation(info.box_center_body)
            common = {
                "camera_pose": tv.top_view_pose,
                "metres_per_pixel": m,
                "box_matrix": box,
                "box_size": info.box_size,
                "instance_id": info.instance_id,
            }
            got = sample_agreement(semantic=sem, instance=inst, **common)
            ref = sample_agreement(
                semantic=np.where(whole, info.semantic_class, 1).astype(sem.dtype),
                instance=np.where(whole, info.instance_id, -1).astype(inst.dtype),
                **common,
            )
            assert got is not None and ref is not None
            for key in ("centre_error_px", "forward_offset_px", "port_offset_px"):
                assert got[key] == pytest.approx(ref[key], abs=1e-9), (agent.id, info.id, key)
            compared += 1
    assert compared >= 6  # the three USVs and the yacht, seen from each other's top views


def test_the_centre_error_of_pointed_bows_lies_along_the_bow_axis() -> None:
    # The remaining centre error is the pixel sampling of a pointed bow: the mask's extent ends short of the bow's
    # tip, not of the transom, so the offset is aft along the bow axis, and not across it.
    study = run_agreement_study([str(ROOT / "scenarios/open_sea_convoy.yaml")], frames=4)
    s = study.samples
    assert s.height >= 20
    assert float(s["forward_offset_px"].median()) < -0.1
    assert abs(float(s["port_offset_px"].median())) < 0.1
    # (The box's axes seen from above are orthogonal up to its roll and pitch: the two offsets add up to the
    # error as the legs of a right triangle, nearly.)
    ce = np.hypot(s["forward_offset_px"].to_numpy(), s["port_offset_px"].to_numpy())
    np.testing.assert_allclose(ce, s["centre_error_px"].to_numpy(), atol=0.01)
