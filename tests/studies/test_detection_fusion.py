"""Fusion transforms, the baseline detector, and the robustness settings."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from mmusv.errors import InputError
from mmusv.frames import invert, pose_matrices, transform_points
from mmusv.studies.detection.data import (
    AgentFrame,
    SceneFrame,
    SequenceData,
    boxes_in_frame,
    gt_in_ego,
)
from mmusv.studies.detection.detector import (
    BaselineParams,
    baseline_detect,
    closeness_axis,
    fit_box,
    load_detector,
    water_plane,
)
from mmusv.studies.detection.evaluate import bev_iou
from mmusv.studies.detection.fusion import (
    early_points,
    fuse,
    fuse_boxes,
    parse_modes,
    relative,
    rotated_nms,
    transform_boxes,
)
from mmusv.studies.detection.robustness import Setting, neighbours_for, parse_settings

MOUNT = pose_matrices([0.45, 0.0, 2.3, 0.0, 0.0, 0.0])


def water(rng: np.random.Generator, *, z: float = -2.3, n: int = 3000, r: float = 60.0) -> np.ndarray:
    xy = rng.uniform(-r, r, (n, 2))
    return np.column_stack([xy, z + rng.normal(0, 0.05, n), np.full(n, 0.1)])


def box_surface(b: np.ndarray, rng: np.random.Generator, *, n: int = 1500) -> np.ndarray:
    """Points on the four sides of box ``b`` (x, y, z, l, w, h, yaw); not on its top, which the boxes of these
    tests raise above the LiDAR that would see it."""
    u = rng.uniform(-0.5, 0.5, (n, 3))
    face = rng.integers(0, 4, n)
    u[face == 0, 0] = 0.5
    u[face == 1, 0] = -0.5
    u[face == 2, 1] = 0.5
    u[face == 3, 1] = -0.5
    local = u * b[3:6]
    c, s = math.cos(b[6]), math.sin(b[6])
    x = b[0] + c * local[:, 0] - s * local[:, 1]
    y = b[1] + s * local[:, 0] + c * local[:, 1]
    return np.column_stack([x, y, b[2] + local[:, 2], np.full(n, 0.5)])


def yaw_diff(a: float, b: float) -> float:
    return abs((a - b + math.pi / 2) % math.pi - math.pi / 2)


# ---- detector ----------------------------------------------------------------------------------------------------


def test_detector_finds_an_isolated_box_with_size_and_yaw() -> None:
    rng = np.random.default_rng(0)
    target = np.array([40.0, 10.0, -0.8, 10.0, 4.0, 3.0, math.radians(30)])
    pts = np.concatenate([water(rng), box_surface(target, rng)]).astype(np.float32)
    boxes, scores = baseline_detect(pts)
    assert len(boxes) == 1 and 0 < scores[0] < 1
    b = boxes[0]
    assert np.hypot(b[0] - 40, b[1] - 10) < 0.3
    assert b[3] == pytest.approx(10.0, abs=0.4) and b[4] == pytest.approx(4.0, abs=0.4)
    assert yaw_diff(b[6], target[6]) < math.radians(3)
    assert bev_iou(boxes, target[None])[0, 0] > 0.8


def test_detector_ignores_water_own_platform_and_is_deterministic() -> None:
    rng = np.random.default_rng(1)
    w = water(rng)
    own = np.column_stack([rng.uniform(-1, 1, (200, 2)), rng.uniform(-1.5, 0.5, 200), np.zeros(200)])
    pts = np.concatenate([w, own]).astype(np.float32)
    assert len(baseline_detect(pts)[0]) == 0
    assert len(baseline_detect(np.zeros((0, 4), np.float32))[0]) == 0
    t = np.array([-30.0, 25.0, -1.0, 6.0, 2.5, 2.0, 1.0])
    pts2 = np.concatenate([pts, box_surface(t, rng, n=400)]).astype(np.float32)
    a, b = baseline_detect(pts2), baseline_detect(pts2.copy())
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])


def _convoy_agents(rain: float) -> list[AgentFrame]:
    """The three USVs of ``open_sea_convoy`` at frame 0, LiDAR only, in rain of ``rain`` mm/h (0: its own overcast
    sky)."""
    import yaml
    from mmusv.bundled import resolve_scenario
    from mmusv.simulation import Simulation

    with open(resolve_scenario("open_sea_convoy")) as fh:
        spec = yaml.safe_load(fh)
    if rain:
        spec["environment"].update(weather="rain", rain_mm_per_h=rain)
    cap = Simulation(spec).capture(0, sensors=["lidar"])
    out = []
    for name, ac in sorted(cap.agents.items()):
        assert ac.lidar is not None and ac.lidar_pose is not None
        cloud = np.column_stack([ac.lidar.xyz, ac.lidar.intensity]).astype(np.float32)
        out.append(AgentFrame(name, cloud, ac.lidar_pose, np.eye(4)))
    return out


def _at(sensors: np.ndarray, boxes: np.ndarray, scores: np.ndarray) -> np.ndarray:
    """The scores of the ``boxes`` centred within 3 m (BEV) of any of the ``sensors`` ``(K, 2)``."""
    d = np.hypot(boxes[:, None, 0] - sensors[None, :, 0], boxes[:, None, 1] - sensors[None, :, 1])
    out: np.ndarray = scores[(d < 3.0).any(axis=1)]
    return out


def test_detector_leaves_out_the_rain_drops_about_the_sensor() -> None:
    """In rain (10 mm/h) the LiDAR's drop returns about the sensor (``sensors/lidar_rain.rs``) made a box there,
    scored 0.98, without the rain step; with it no box lies within 6 m, and the boxes of the same frame without rain
    are the same with the step and without it (it leaves a dry cloud alone). Early fusion: the drops about each
    neighbour's sensor made a box there, scored 0.97-0.99; each cloud now leaves its drops out in its own frame
    first (``rain_free``), which leaves the dry clouds' early fusion as it was."""
    dry, wet = _convoy_agents(0.0), _convoy_agents(10.0)
    off = BaselineParams(rain_radius_m=0.0)
    wet_on, wet_off = baseline_detect(wet[0].points)[0], baseline_detect(wet[0].points, off)[0]
    assert (np.hypot(wet_off[:, 0], wet_off[:, 1]) < 3.0).any(), "the drops no longer make a box: test is void"
    assert len(wet_on) and (np.hypot(wet_on[:, 0], wet_on[:, 1]) > 6.0).all()
    dry_on, dry_off = baseline_detect(dry[0].points), baseline_detect(dry[0].points, off)
    assert len(dry_on[0]) and np.array_equal(dry_on[0], dry_off[0]) and np.array_equal(dry_on[1], dry_off[1])
    for agents, raining in ((wet, True), (dry, False)):
        for k, ego in enumerate(agents):
            nbs = agents[:k] + agents[k + 1 :]
            sensors = np.array([relative(ego, nb)[:2, 3] for nb in nbs])
            fused, scores = fuse("early", ego, nbs, detector=baseline_detect)
            raw, raw_scores = baseline_detect(early_points(ego, nbs, crop_m=220.0))
            if raining:
                assert (_at(sensors, raw, raw_scores) > 0.9).any(), "no drop box at a neighbour: test is void"
                assert (_at(sensors, fused, scores) < 0.9).all(), f"{ego.id}: {_at(sensors, fused, scores)}"
            else:
                assert np.array_equal(fused, raw) and np.array_equal(scores, raw_scores)
    # A bright hull 4 m off is no drop: kept.
    rng = np.random.default_rng(3)
    near = np.array([4.5, 0.0, -0.5, 5.0, 2.0, 2.0, 0.0])
    pts = np.concatenate([water(rng), box_surface(near, rng, n=400)]).astype(np.float32)
    assert (np.hypot(*baseline_detect(pts)[0][:, :2].T) < 8.0).any()


def test_water_plane_follows_tilt() -> None:
    rng = np.random.default_rng(2)
    xy = rng.uniform(-80, 80, (4000, 2))
    z = 0.03 * xy[:, 0] - 0.02 * xy[:, 1] - 2.0
    pts = np.column_stack([xy, z, np.zeros(len(z))])
    assert np.allclose(water_plane(pts), [0.03, -0.02, -2.0], atol=1e-3)


def test_edge_on_face_is_widened_away_from_the_sensor() -> None:
    xy = np.column_stack([np.linspace(-4, 4, 30), np.full(30, 20.0)])  # near side of a boat abeam, at y = 20
    b = fit_box(xy, z_low=-2.0, z_high=1.0, min_width_m=3.0, beam_ratio=0.25)  # 3 > 0.25 · 8
    assert b[3] == pytest.approx(8.0, abs=1e-6) and b[4] == pytest.approx(3.0)
    assert b[1] == pytest.approx(21.5, abs=1e-6)  # pushed 1.5 m away from the sensor
    assert yaw_diff(b[6], 0.0) < 1e-9


def test_load_detector() -> None:
    assert load_detector("baseline") is baseline_detect
    assert load_detector("mmusv.studies.detection.detector:baseline_detect") is baseline_detect
    for bad in ("nope", "no.such.module:f", "mmusv.studies.detection.detector:missing"):
        with pytest.raises(Exception, match=f"^spec = '{bad}': "):
            load_detector(bad)


# ---- fusion ------------------------------------------------------------------------------------------------------


def scene(rng: np.random.Generator) -> tuple[SceneFrame, AgentFrame, AgentFrame, np.ndarray]:
    ego_body = pose_matrices([100.0, -50.0, 0.2, 0.0, 0.0, math.radians(35)])
    nb_body = pose_matrices([180.0, 40.0, -0.1, 0.0, 0.0, math.radians(-120)])
    target = pose_matrices([150.0, 20.0, 0.0, 0.0, 0.0, math.radians(75)])
    target[:3, 3] = [150.0, 20.0, 1.0]
    sizes = np.array([[12.0, 4.0, 3.0]])
    ego = AgentFrame("usv_1", water(rng), ego_body, MOUNT)
    nb_box = boxes_in_frame(invert(nb_body @ MOUNT), boxes=target[None], sizes=sizes)[0]
    nb = AgentFrame("usv_2", np.concatenate([water(rng), box_surface(nb_box, rng)]).astype(np.float32), nb_body, MOUNT)
    usv = np.stack([ego_body, nb_body])
    frame = SceneFrame(0, (ego, nb), ("t",), target[None], sizes, usv, np.tile([5.0, 2.4, 2.5], (2, 1)))
    return frame, ego, nb, nb_box


def test_box_seen_by_a_neighbour_lands_on_the_ego_ground_truth() -> None:
    frame, ego, nb, nb_box = scene(np.random.default_rng(3))
    gt = gt_in_ego(frame, ego)
    assert len(gt) == 1
    moved = transform_boxes(relative(ego, nb), nb_box[None])[0]
    assert np.allclose(moved[:6], gt[0, :6], atol=1e-9) and yaw_diff(moved[6], gt[0, 6]) < 1e-9
    # the same through a hand-made world round trip: neighbour LiDAR -> world -> ego LiDAR
    centre_world = transform_points(nb.lidar, nb_box[None, :3])
    assert np.allclose(transform_points(invert(ego.lidar), centre_world), gt[:, :3], atol=1e-9)


def test_late_and_early_fusion_find_what_only_the_neighbour_sees() -> None:
    frame, ego, nb, _ = scene(np.random.default_rng(4))
    gt = gt_in_ego(frame, ego)
    none = fuse("none", ego, [nb], detector=baseline_detect)
    assert len(none[0]) == 0  # the ego sees only water
    for mode in ("late", "early"):
        boxes, _ = fuse(mode, ego, [nb], detector=baseline_detect)
        assert len(boxes) == 1, mode
        assert bev_iou(boxes, gt)[0, 0] > 0.7, mode
    pts = early_points(ego, [nb], crop_m=1000.0)
    assert pts.dtype == np.float32 and len(pts) == len(ego.points) + len(nb.points)


def test_late_fusion_merges_duplicates_with_rotated_nms() -> None:
    frame, ego, nb, nb_box = scene(np.random.default_rng(5))
    gt = gt_in_ego(frame, ego)
    answers = {
        id(ego.points): (gt + np.array([0.3, 0, 0, 0, 0, 0, 0.05]), np.array([0.6])),
        id(nb.points): (nb_box[None], np.array([0.9])),
    }

    def stub(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return answers[id(points)]

    boxes, scores = fuse("late", ego, [nb], detector=stub)
    assert len(boxes) == 1
    assert scores[0] == 0.9
    assert np.allclose(boxes[0, :3], gt[0, :3], atol=1e-9)


def test_late_fusion_wbf_averages_the_agreeing_boxes() -> None:
    frame, ego, nb, nb_box = scene(np.random.default_rng(5))
    gt = gt_in_ego(frame, ego)
    mine = gt + np.array([0.3, 0, 0, 0, 0, 0, 0.05])
    answers = {id(ego.points): (mine, np.array([0.6])), id(nb.points): (nb_box[None], np.array([0.2]))}

    def stub(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return answers[id(points)]

    boxes, scores = fuse("late", ego, [nb], detector=stub, late_merge="wbf")
    assert len(boxes) == 1
    assert scores[0] == pytest.approx(1 - 0.4 * 0.8)  # noisy-OR of the two USVs
    # weights 0.6/0.8 and 0.2/0.8; the neighbour's box lands on the ground truth
    assert np.allclose(boxes[0, :6], 0.75 * mine[0, :6] + 0.25 * gt[0, :6], atol=1e-9)
    assert boxes[0, 6] == pytest.approx(gt[0, 6] + 0.75 * 0.05, abs=1e-3)
    with pytest.raises(InputError, match="late merge"):
        fuse("late", ego, [nb], detector=stub, late_merge="mean")


def test_fuse_boxes_groups_by_iou_and_agent() -> None:
    a = np.array([0.0, 0, 0, 10, 4, 2, np.pi / 2 - 0.05])
    same = np.array([0.5, 0, 0, 10, 4, 2, -np.pi / 2 + 0.05])  # the same heading across ±π/2
    far = np.array([30.0, 0, 0, 10, 4, 2, 0.0])
    boxes = np.stack([a, same, far, same])
    scores = np.array([0.5, 0.5, 0.9, 0.4])
    agents = np.array([0, 1, 0, 0])  # the last: a second box of agent 0 on the same vessel
    fb, fs = fuse_boxes(boxes, scores=scores, agents=agents)
    assert fs.tolist() == pytest.approx([0.9, 0.75])  # agent 0's second box does not add confidence
    np.testing.assert_array_equal(fb[0], far)
    assert fb[1, 0] == pytest.approx(0.25)
    assert abs(abs(fb[1, 6]) - np.pi / 2) < 1e-9  # not the naive mean 0
    # one agent alone: its boxes as they are (a box under the threshold is not merged)
    one, sc = fuse_boxes(boxes[:3], scores=np.array([0.5, 0.4, 0.9]), agents=np.zeros(3, int), iou_threshold=0.95)
    assert sc.tolist() == [0.9, 0.5, 0.4]
    np.testing.assert_array_equal(one, boxes[[2, 0, 1]])
    empty = fuse_boxes(np.zeros((0, 7)), scores=np.zeros(0), agents=np.zeros(0, int))
    assert empty[0].shape == (0, 7) and empty[1].shape == (0,)


def test_closeness_axis_follows_the_legs_of_an_l() -> None:
    yaw = 0.4
    u, v = np.array([np.cos(yaw), np.sin(yaw)]), np.array([-np.sin(yaw), np.cos(yaw)])
    legs = [t * u for t in np.linspace(0, 20, 81)] + [t * v for t in np.linspace(0, 6, 25)]
    pts = np.array(legs) + np.array([50.0, 10.0])
    axis = closeness_axis(pts)
    assert axis is not None
    assert min(abs(float(axis @ u)), abs(float(axis @ v))) < 1e-9  # along a leg, not the hypotenuse
    box = fit_box(pts, z_low=0.0, z_high=1.0, min_width_m=0.0, beam_ratio=0.0, criterion="closeness")
    assert box[3] == pytest.approx(20.0) and box[4] == pytest.approx(6.0)
    assert box[6] == pytest.approx(yaw)
    with pytest.raises(ValueError, match="criterion"):
        fit_box(pts, z_low=0.0, z_high=1.0, criterion="hull")
    assert closeness_axis(pts[:2]) is None  # too few
    line = closeness_axis(pts[:81])  # one leg: its own direction (or None where shapely finds no area)
    assert line is None or abs(abs(float(line @ u)) - 1.0) < 1e-6


def test_point_sets_give_the_multipoints_hull_and_rectangle_to_the_bit() -> None:
    """The detector hands shapely its points as one line string (fast to build); the convex hull and the oriented
    envelope are those of the multipoint of the same points, coordinate for coordinate, scattered, duplicated,
    collinear, coincident and on a grid, and for one and two points."""
    import shapely
    from mmusv.studies.detection.detector import _coordinates

    rng = np.random.default_rng(5)
    cases = [np.array([[1.0, 2.0]]), np.array([[1.0, 2.0], [3.0, 5.0]]), np.array([[1.0, 2.0], [1.0, 2.0]])]
    for i in range(250):
        n = int(rng.integers(3, 300))
        t = rng.uniform(0, 10, n)
        cases.append(
            [
                rng.normal(size=(n, 2)) * [20, 3],
                np.round(rng.normal(size=(n, 2)) * 5, 1),
                np.c_[t, 2 * t + 1],
                np.repeat(rng.normal(size=(1, 2)), n, 0),
                np.round(rng.uniform(0, 3, (n, 2))),
            ][i % 5]
        )
    for pts in cases:
        for f in (shapely.convex_hull, shapely.minimum_rotated_rectangle):
            a, b = f(shapely.multipoints(pts)), f(_coordinates(pts))
            assert a.geom_type == b.geom_type
            np.testing.assert_array_equal(shapely.get_coordinates(a), shapely.get_coordinates(b))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_linked_pairs_are_every_pair_within_the_smaller_gap(seed: int) -> None:
    """The baseline's cell links, searched level by level, against every pair checked by brute force: a dense
    near cluster (the least gap), far sparse cells (range-adaptive gaps up to 15 m) and exact ties at the gaps."""
    from mmusv.studies.detection.detector import linked_pairs

    rng = np.random.default_rng(seed)
    near = (np.floor(rng.normal(size=(300, 2)) * 8 / 0.5) + 0.5) * 0.5
    r, a = rng.uniform(20, 300, 300), rng.uniform(0, 2 * np.pi, 300)
    far = (np.floor(np.c_[r * np.cos(a), r * np.sin(a)] / 0.5) + 0.5) * 0.5
    tie = np.array([[100.25, 0.25], [100.25 + 5.0125, 0.25]])  # 5.0125 m apart, both gaps 5.0125 m
    c = np.unique(np.concatenate([near, far, tie]), axis=0)
    gap = np.maximum(1.5, 0.05 * np.hypot(c[:, 0], c[:, 1]))
    gap[np.all(np.isin(c, tie), axis=1)] = 5.0125
    i, j = np.triu_indices(len(c), k=1)
    d = np.hypot(*(c[i] - c[j]).T)
    want = {(int(x), int(y)) for x, y, ok in zip(i, j, d <= np.minimum(gap[i], gap[j]), strict=True) if ok}
    got = linked_pairs(c, gap)
    assert len(got) == len(want) and {(int(x), int(y)) for x, y in got} == want  # each pair once, i < j
    assert linked_pairs(c[:1], gap[:1]).shape == (0, 2)


def test_cell_keys_order_and_group_cells_as_the_rows_do() -> None:
    """np.unique on cell_keys gives np.unique(cell, axis=0)'s cells, order and grouping (negative indices, the
    extremes of the range the keys are for, duplicates)."""
    from mmusv.studies.detection.detector import cell_keys

    rng = np.random.default_rng(3)
    cell = rng.integers(-600, 600, size=(5000, 2))
    cell[:40] = cell[40:80]  # duplicates
    cell[80:84] = [[-(2**31), 2**31 - 1], [2**31 - 1, -(2**31)], [0, -(2**31)], [-1, 2**31 - 1]]
    want, want_inv = np.unique(cell, axis=0, return_inverse=True)
    _, first, inv = np.unique(cell_keys(cell), return_index=True, return_inverse=True)
    np.testing.assert_array_equal(cell[first], want)
    np.testing.assert_array_equal(inv.reshape(-1), want_inv.reshape(-1))


def test_rotated_nms_threshold() -> None:
    a = np.array([[0, 0, 0, 4, 2, 1, 0]], float)
    near = np.array([[1.0, 0, 0, 4, 2, 1, 0]])  # IoU 0.6: suppressed
    far = np.array([[3.8, 0, 0, 4, 2, 1, 0]])  # IoU 0.2/7.8 ≈ 0.026: kept
    boxes = np.concatenate([a, near, far])
    keep = rotated_nms(boxes, np.array([0.9, 0.8, 0.7]))
    assert keep.tolist() == [0, 2]
    assert rotated_nms(np.zeros((0, 7)), np.zeros(0)).tolist() == []


def test_parse_modes() -> None:
    assert parse_modes("early,none") == ("none", "early")
    with pytest.raises(InputError, match="unknown mode"):
        parse_modes("none,middle")


# ---- robustness --------------------------------------------------------------------------------------------------


def sequence(n: int = 6) -> SequenceData:
    frames = []
    for t in range(n):
        agents = tuple(
            AgentFrame(
                f"usv_{k}",
                np.full((3, 4), t * 10 + k, np.float32),
                pose_matrices([t * 1.0, 10.0 * k, 0, 0, 0, 0.1 * k]),
                MOUNT,
            )
            for k in range(3)
        )
        frames.append(
            SceneFrame(t, agents, (), np.zeros((0, 4, 4)), np.zeros((0, 3)), np.zeros((0, 4, 4)), np.zeros((0, 3)))
        )
    return SequenceData("seq", tuple(frames))


def test_delay_takes_points_and_pose_from_earlier_frames() -> None:
    seq = sequence()
    nbs = neighbours_for(seq, 4, "usv_0", Setting(delay_frames=2), seed=0)
    assert [a.id for a in nbs] == ["usv_1", "usv_2"]
    for a in nbs:
        old = next(x for x in seq.frames[2].agents if x.id == a.id)
        assert a.points is old.points and np.array_equal(a.body, old.body)
    with pytest.raises(InputError):
        neighbours_for(seq, 1, "usv_0", Setting(delay_frames=2), seed=0)


def test_pose_noise_is_seeded_shared_and_zero_mean() -> None:
    seq = sequence()
    s = Setting(sigma_xyz_m=1.0, sigma_rpy_deg=1.0)
    a = neighbours_for(seq, 3, "usv_0", s, seed=7)
    b = neighbours_for(seq, 3, "usv_0", s, seed=7)
    assert all(np.array_equal(x.body, y.body) for x, y in zip(a, b, strict=True))  # same draws for late and early
    c = neighbours_for(seq, 3, "usv_0", s, seed=8)
    assert not np.array_equal(a[0].body, c[0].body)
    clean = neighbours_for(seq, 3, "usv_0", Setting(), seed=7)
    assert np.array_equal(clean[0].body, seq.frames[3].agents[1].body)
    from mmusv.frames import matrix_to_pose

    draws = np.array(
        [
            matrix_to_pose(neighbours_for(seq, 3, "usv_0", s, seed=k)[0].body)
            - matrix_to_pose(seq.frames[3].agents[1].body)
            for k in range(400)
        ]
    )
    assert np.all(np.abs(draws[:, :3].mean(axis=0)) < 0.2)
    assert np.allclose(draws[:, :3].std(axis=0), 1.0, atol=0.15)
    assert np.allclose(np.degrees(draws[:, 3:].std(axis=0)), 1.0, atol=0.15)


def test_parse_settings() -> None:
    got = parse_settings("delay:1,noise:0.5/0.5,delay:3")
    assert [s.name for s in got] == ["clean", "delay:1", "delay:3", "noise:0.5/0.5"]
    # sorted whatever the order given (the study's tables were in the order of the command line)
    got = parse_settings("noise:2/1,delay:3,noise:1/2,clean,delay:1,noise:1/1")
    assert [s.name for s in got] == ["clean", "delay:1", "delay:3", "noise:1/1", "noise:1/2", "noise:2/1"]
    for bad in ("delay:0", "delay:x", "noise:-1/1", "noise:0/0", "jitter:1"):
        with pytest.raises(InputError, match=rf"^text = '{bad}': item '{bad}': expected clean"):
            parse_settings(bad)


def test_baseline_params_are_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        BaselineParams().gap_m = 3.0  # type: ignore[misc]


def test_gt_visibility_counts_points_inside_the_box() -> None:
    from mmusv.studies.detection.study import gt_visibility

    gt = np.array([[10.0, 0.0, 0.0, 4.0, 2.0, 2.0, math.pi / 2], [50.0, 50.0, 0.0, 4.0, 2.0, 2.0, 0.0]])
    pts = np.array(
        [
            [10.0, 1.9, 0.0],
            [10.9, -1.5, 0.5],
            [10.0, 2.1, 0.0],  # inside, inside, beyond the long side
            [10.0, 0.0, 1.4],
            [10.0, 0.0, 1.6],
            [50.0, 50.0, -2.0],
        ]
    )  # z within h/2 + 0.5, too high, too low
    assert gt_visibility(gt, pts).tolist() == [3, 0]
    assert gt_visibility(gt, np.zeros((0, 3))).tolist() == [0, 0]


def test_ground_truth_and_detections_follow_the_one_target_rule() -> None:
    """A target exactly at the evaluation range counts (BEV distance <= range, as annotations and export)."""
    from mmusv.studies.detection.study import _keep

    centres = np.array([[200.0, 0.0, 1.0], [120.0, -160.0, 0.0], [0.0, 200.000001, 0.0], [150.0, 140.0, 0.0]])
    targets = np.tile(np.eye(4), (len(centres), 1, 1))
    targets[:, :3, 3] = centres
    sizes = np.tile([10.0, 3.0, 2.0], (len(centres), 1))
    ego = AgentFrame("usv_1", np.zeros((0, 4), np.float32), np.eye(4), np.eye(4))  # LiDAR frame = world
    frame = SceneFrame(0, (ego,), ("a", "b", "c", "d"), targets, sizes, np.zeros((0, 4, 4)), np.zeros((0, 3)))
    gt = gt_in_ego(frame, ego, range_m=200.0)
    assert gt[:, :3].tolist() == centres[:2].tolist()  # 200 m and 120-160-200 m in, the others beyond
    boxes = np.column_stack([centres, sizes, np.zeros(len(centres))])
    kept, scores = _keep(boxes, np.arange(4.0), np.zeros((0, 7)), range_m=200.0, margin=5.0)
    assert kept[:, :3].tolist() == centres[:2].tolist() and scores.tolist() == [0.0, 1.0]
