"""Tables III and IV as a perception researcher reproduces them (a QA round): ``mmusv study detection`` and
``study robustness`` on tiny recordings, their numbers against computations written here from the recording alone
(the world-state table, the LiDAR mounts and clouds, shapely polygons, a VOC AP), and the errors on bad input.

Independent of the study's code: the ground truth, BEV IoU, matching, AP and range bins, the late-fusion transform
and NMS, the early-fusion aggregate, the delay (the frame k - d by acquisition index) and the pose noise (recovered
from a probe detector's boxes). The baseline detector is used as a black box on the clouds.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import polars as pl
import pytest
import yaml
from mmusv.cli import main
from mmusv.errors import InputError
from mmusv.recording import decode_point_cloud, read_info, read_messages
from mmusv.recording import topics as topic_names
from mmusv.studies.detection.data import AgentFrame, SceneFrame, SequenceData
from mmusv.studies.detection.detector import baseline_detect
from mmusv.studies.detection.robustness import Setting, parse_settings
from mmusv.studies.detection.study import StudyOptions, run_study
from scipy.spatial.transform import Rotation
from shapely.geometry import Point, Polygon

BOX = ["x", "y", "z", "l", "w", "h", "yaw"]
BINS = ((0.0, 50.0), (50.0, 100.0), (100.0, 150.0), (150.0, 200.0))


def scenario(name: str, frames: int) -> dict[str, Any]:
    """A port with two 16-channel LiDAR USVs: a tug between them, a fishing boat lying still beside usv_1, a tanker
    far beyond 200 m and the map's moored ships (moored_03 within 200 m of usv_2 only)."""
    return {
        "name": name,
        "seed": 1,
        "map": {"type": "port", "seed": 3},
        "environment": {"wave": "W0", "motion": "paper"},
        "acquisition": {"frequency_hz": 5, "frames": frames},
        "rigs": {"r": {"preset": "lidar_only", "lidar": {"channels": 16, "points_per_second": 80000}}},
        "vessels": [
            {"id": "usv_1", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2,
             "route": [[-170, -110], [-170, -30]]},
            {"id": "usv_2", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2,
             "route": [[-110, 60], [-80, 60]]},
            {"id": "tug", "asset": "tug_32m", "speed_mps": 3.0, "route": [[-150, -60], [-100, -10]]},
            {"id": "still", "asset": "fishing_boat_12m", "speed_mps": 0.0, "route": [[-190, -100], [-195, -100]]},
            {"id": "far", "asset": "coastal_tanker_100m", "speed_mps": 5.0, "route": [[400, -600], [900, -600]]},
        ],
    }  # fmt: skip


@pytest.fixture(scope="module")
def rec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from mmusv.acquire import run

    return run(scenario("moor", 5), out_dir=tmp_path_factory.mktemp("moor"), checks=False).recording


@pytest.fixture(scope="module")
def gap(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The same scenario, 6 frames recorded in parts of 2, the middle part (frames 2..3) missing."""
    root = tmp_path_factory.mktemp("gap")
    spec = root / "gap.yaml"
    spec.write_text(yaml.safe_dump(scenario("gap", 6)), encoding="utf-8")
    assert main(["run", str(spec), "--split-frames", "2", "--no-checks", "-o", str(root / "out")]) == 0
    shutil.rmtree(root / "out" / "gap" / "parts" / "000002-000003")
    return root / "out" / "gap" / "gap.parts.json"


def study(args: list[str], out: Path) -> Path:
    assert main([*args, "-o", str(out), "--no-progress"]) == 0
    return out


def refused(args: list[str], out: Path, capsys: pytest.CaptureFixture[str]) -> str:
    capsys.readouterr()
    assert main([*args, "-o", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: ") and "Traceback" not in err and err.count("\n") == 1, err
    assert not (out / "detection_table.csv").exists() and not (out / "robustness_table.csv").exists()
    return err


# --- independent geometry -------------------------------------------------------------------------------------


def rot(roll: float, pitch: float, yaw: float) -> np.ndarray:
    return Rotation.from_euler("ZYX", [yaw, pitch, roll]).as_matrix()


class World:
    """A recording read here: poses from its world-state table, mounts from its metadata, clouds by frame."""

    def __init__(self, rec: Path) -> None:
        info = read_info(rec)
        self.freq = info.frequency_hz
        self.mounts = {a.id: a.lidar_mount for a in info.agents}
        self.agents = [a.id for a in info.agents if a.lidar_mount is not None]
        self.ws = pl.read_parquet(rec.parent / "tables" / "world_state")
        self.clouds: dict[tuple[int, str], np.ndarray] = {}
        for topic, t, msg in read_messages(rec, [topic_names.lidar(a) for a in self.agents]):
            c = decode_point_cloud(msg)
            key = (round(t * self.freq / 1e9), str(topic_names.agent_of(topic)))
            self.clouds[key] = np.column_stack([c["x"], c["y"], c["z"], c["intensity"]]).astype(np.float32)

    def row(self, frame: int, vessel: str) -> dict[str, Any]:
        return self.ws.filter((pl.col("frame") == frame) & (pl.col("vessel_id") == vessel)).row(0, named=True)

    @staticmethod
    def matrix(r: dict[str, Any], *, box: bool = False) -> np.ndarray:
        m = np.eye(4)
        m[:3, :3] = rot(r["roll"], r["pitch"], r["yaw"])
        m[:3, 3] = [r["box_cx"], r["box_cy"], r["box_cz"]] if box else [r["x"], r["y"], r["z"]]
        return m

    def body(self, frame: int, vessel: str) -> np.ndarray:
        return self.matrix(self.row(frame, vessel))

    def lidar(self, frame: int, agent: str) -> np.ndarray:
        return self.body(frame, agent) @ self.mounts[agent]

    def boxes_in(self, frame: int, ego: str, *, role: str) -> list[tuple[str, list[float]]]:
        """``(vessel id, box)`` of every vessel (``role`` ``usv`` or not) in ``ego``'s LiDAR frame, any range."""
        inv = np.linalg.inv(self.lidar(frame, ego))
        out = []
        for r in self.ws.filter(pl.col("frame") == frame).iter_rows(named=True):
            if (r["role"] == "usv") != (role == "usv"):
                continue
            m = inv @ self.matrix(r, box=True)
            yaw = math.atan2(m[1, 0], m[0, 0])
            out.append((r["vessel_id"], [*m[:3, 3], r["length"], r["beam"], r["height"], yaw]))
        return out


def polygon(b: Any) -> Polygon:
    c, s = math.cos(b[6]), math.sin(b[6])
    half = ((b[3] / 2, b[4] / 2), (-b[3] / 2, b[4] / 2), (-b[3] / 2, -b[4] / 2), (b[3] / 2, -b[4] / 2))
    return Polygon([(b[0] + c * dx - s * dy, b[1] + s * dx + c * dy) for dx, dy in half])


def iou(a: Any, b: Any) -> float:
    pa, pb = polygon(a), polygon(b)
    inter = pa.intersection(pb).area
    union = pa.area + pb.area - inter
    return inter / union if union > 0 else 0.0


def greedy(dets: np.ndarray, scores: np.ndarray, gts: np.ndarray, thr: float) -> list[int]:
    """OpenCOOD's caluclate_tp_fp: in descending score, the highest-IoU ground truth still free; TP at >= thr."""
    free = list(range(len(gts)))
    out = [-1] * len(dets)
    for i in sorted(range(len(dets)), key=lambda k: -scores[k]):
        if not free:
            break
        ious = [iou(dets[i], gts[j]) for j in free]
        k = int(np.argmax(ious))
        if ious[k] >= thr:
            out[i] = free.pop(k)
    return out


def voc_ap(scores: list[float], tp: list[bool], n_gt: int) -> float:
    """VOC all-point AP after one global sort; detections of equal score enter the curve together."""
    if n_gt == 0:
        return math.nan
    if not scores:
        return 0.0
    s = np.asarray(scores)
    order = np.argsort(-s, kind="stable")
    t = np.asarray(tp, dtype=bool)[order]
    last = np.append(s[order][1:] != s[order][:-1], True)
    ctp, cfp = np.cumsum(t)[last], np.cumsum(~t)[last]
    mrec = np.r_[0.0, ctp / n_gt, 1.0]
    mpre = np.r_[0.0, ctp / (ctp + cfp), 0.0]
    for i in range(len(mpre) - 2, -1, -1):
        mpre[i] = max(mpre[i], mpre[i + 1])
    steps = np.nonzero(mrec[1:] != mrec[:-1])[0]
    return float(np.sum((mrec[steps + 1] - mrec[steps]) * mpre[steps + 1]))


def range_bin(b: Any) -> int:
    r = math.hypot(b[0], b[1])
    return next((k for k, (lo, hi) in enumerate(BINS) if lo <= r < hi), -1)


def move(m: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    out = []
    for b in boxes:
        c = m @ np.r_[b[:3], 1.0]
        h = m[:3, :3] @ [math.cos(b[6]), math.sin(b[6]), 0.0]
        out.append([*c[:3], *b[3:6], math.atan2(h[1], h[0])])
    return np.array(out, dtype=np.float64).reshape(-1, 7)


def nms(boxes: np.ndarray, scores: np.ndarray, thr: float = 0.10) -> list[int]:
    keep: list[int] = []
    for i in sorted(range(len(scores)), key=lambda k: -scores[k]):
        if all(iou(boxes[i], boxes[k]) <= thr for k in keep):
            keep.append(i)
    return keep


def same(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or a == pytest.approx(b, abs=1e-9)


# --- Table III against the recording --------------------------------------------------------------------------


def test_ground_truth_is_every_vessel_but_the_usvs_within_the_range(rec: Path, tmp_path: Path) -> None:
    """Moored and still vessels count, the USVs and the tanker beyond 200 m do not; boxes in the ego LiDAR frame as
    the world-state table and the mounts give them; the CSV's counts are the recording's."""
    w = World(rec)
    for rng in (200, 100):
        out = study(["study", "detection", str(rec), "--range", str(rng)], tmp_path / f"r{rng}")
        gt = pl.read_parquet(out / "detection_boxes.parquet").filter(pl.col("kind") == "gt")
        seen_ids = set()
        for (frame, ego, mode), g in gt.group_by(["frame", "ego", "mode"]):
            want = [(i, b) for i, b in w.boxes_in(frame, ego, role="target") if math.hypot(b[0], b[1]) <= rng]
            seen_ids |= {i for i, _ in want}
            got = np.array(sorted(g.select(BOX).rows()))
            exp = np.array(sorted(b for _, b in want))
            assert got.shape == exp.shape and np.allclose(got, exp, atol=1e-3), (frame, ego, mode)
        if rng == 200:
            assert seen_ids == {"tug", "still", "moored_03"}  # moored and still in, far and the USVs out
        table = pl.read_csv(out / "detection_table.csv")
        n_frames = len(set(gt["frame"].to_list()))
        assert n_frames == 5
        for r in table.iter_rows(named=True):
            assert r["frames"] == n_frames  # was the ego-frame count (10) beside a note saying 5 frames
            assert r["ego_frames"] == 2 * n_frames
            assert r["gt"] == len(gt.filter(pl.col("mode") == r["mode"]))
        note = (out / "detection_note.txt").read_text(encoding="utf-8")
        assert f"frames: {n_frames}\n" in note and f"ego-frames: {2 * n_frames}\n" in note


def test_ap_matching_and_range_bins_are_the_documented_rule(rec: Path, tmp_path: Path) -> None:
    """AP@0.3/0.5/0.7, P/R@0.5, AP@0.5 per range bin and the ``matched`` and ``range_bin`` columns, recomputed here
    from the boxes Parquet with shapely polygons, greedy matching and a VOC all-point AP."""
    out = study(["study", "detection", str(rec)], tmp_path / "det")
    boxes = pl.read_parquet(out / "detection_boxes.parquet")
    table = pl.read_csv(out / "detection_table.csv")
    labels = [f"{lo:g}-{hi:g}" for lo, hi in BINS]
    for row in table.iter_rows(named=True):
        sub = boxes.filter(pl.col("mode") == row["mode"])
        scores: list[float] = []
        tps: dict[float, list[bool]] = {0.3: [], 0.5: [], 0.7: []}
        per_bin: dict[int, tuple[list[float], list[bool]]] = {k: ([], []) for k in range(4)}
        gt_bin = [0, 0, 0, 0]
        n_gt = 0
        for _, g in sub.group_by(["frame", "ego"], maintain_order=True):
            d, t = g.filter(pl.col("kind") == "det"), g.filter(pl.col("kind") == "gt")
            db, ds, gb = d.select(BOX).to_numpy(), d["score"].to_numpy(), t.select(BOX).to_numpy()
            n_gt += len(gb)
            scores += ds.tolist()
            for thr in tps:
                m = greedy(db, ds, gb, thr)
                tps[thr] += [j >= 0 for j in m]
                if thr == 0.5:
                    assert d["matched"].to_list() == [j >= 0 for j in m]
                    assert t["matched"].to_list() == [j in m for j in range(len(gb))]
                    for i, j in enumerate(m):
                        k = range_bin(gb[j] if j >= 0 else db[i])
                        assert d["range_bin"][i] == (labels[k] if k >= 0 else "out")
                        if k >= 0:
                            per_bin[k][0].append(ds[i])
                            per_bin[k][1].append(j >= 0)
                    for b in gb:
                        gt_bin[range_bin(b)] += 1
        assert row["gt"] == n_gt and row["det"] == len(scores)
        for thr, name in ((0.3, "ap30"), (0.5, "ap50"), (0.7, "ap70")):
            assert same(row[name], voc_ap(scores, tps[thr], n_gt)), (row["mode"], name)
        assert same(row["precision50"], sum(tps[0.5]) / len(scores))
        assert same(row["recall50"], sum(tps[0.5]) / n_gt)
        for k, label in enumerate(labels):
            assert same(row[f"ap50_{label}"], voc_ap(*per_bin[k], gt_bin[k])), (row["mode"], label)
    assert table.filter(pl.col("mode") == "early")["ap50"][0] > 0  # the data is not trivially empty


def expected_modes(w: World, frame: int, ego: str, nb_frame: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """No, late and early fusion for ``ego`` at ``frame`` with the neighbour's cloud and pose of ``nb_frame``, the
    detections beyond 200 m or centred on a USV platform (grown by 2 m) dropped."""
    nbs = [a for a in w.agents if a != ego]
    to_ego = np.linalg.inv(w.lidar(frame, ego))
    own = baseline_detect(w.clouds[(frame, ego)])
    boxes, scores = [own[0]], [own[1]]
    pts = [w.clouds[(frame, ego)].astype(np.float64)]
    for nb in nbs:
        rel = to_ego @ w.lidar(nb_frame, nb)
        b, s = baseline_detect(w.clouds[(nb_frame, nb)])
        boxes.append(move(rel, b))
        scores.append(s)
        p = w.clouds[(nb_frame, nb)].astype(np.float64)
        pts.append(np.column_stack([p[:, :3] @ rel[:3, :3].T + rel[:3, 3], p[:, 3]]))
    bb, ss = np.concatenate(boxes), np.concatenate(scores)
    keep = nms(bb, ss)
    agg = np.concatenate(pts)
    agg = agg[np.hypot(agg[:, 0], agg[:, 1]) <= 220.0].astype(np.float32)
    modes = {"none": own, "late": (bb[keep], ss[keep]), "early": baseline_detect(agg)}
    plats = [polygon(b).buffer(2.0) for _, b in w.boxes_in(frame, ego, role="usv")]
    out = {}
    for mode, (b, s) in modes.items():
        sel = [
            i
            for i in range(len(b))
            if math.hypot(b[i][0], b[i][1]) <= 200.0 and not any(p.contains(Point(b[i][0], b[i][1])) for p in plats)
        ]
        out[mode] = (b[sel], s[sel])
    return out


def check_detections(boxes: pl.DataFrame, w: World, frames: list[int], delay: int) -> int:
    n = 0
    for frame in frames:
        for ego in w.agents:
            for mode, (b, s) in expected_modes(w, frame, ego, frame - delay).items():
                if delay and mode == "none":
                    continue
                got = boxes.filter((pl.col("frame") == frame) & (pl.col("ego") == ego) & (pl.col("mode") == mode))
                got = got.sort(["score", "x"], descending=[True, False]).select([*BOX, "score"]).to_numpy()
                o = np.lexsort((b[:, 0], -s))
                exp = np.column_stack([b[o], s[o]])
                assert got.shape == exp.shape, (frame, ego, mode)
                diff = np.abs(got - exp)
                diff[:, 6] = np.abs((diff[:, 6] + np.pi / 2) % np.pi - np.pi / 2)  # a box at ψ is one at ψ + π
                assert diff.max(initial=0.0) < 1e-6, (frame, ego, mode)
                n += len(exp)
    return n


def test_no_late_and_early_fusion_are_the_documented_fusion(rec: Path, tmp_path: Path) -> None:
    w = World(rec)
    out = study(["study", "detection", str(rec)], tmp_path / "det")
    det = pl.read_parquet(out / "detection_boxes.parquet").filter(pl.col("kind") == "det")
    assert check_detections(det, w, list(range(5)), 0) == len(det) > 0


def test_delay_takes_the_neighbour_of_frame_k_minus_d(rec: Path, tmp_path: Path) -> None:
    w = World(rec)
    out = study(["study", "robustness", str(rec), "--settings", "delay:2,delay:1"], tmp_path / "rob")
    boxes = pl.read_parquet(out / "robustness_boxes.parquet")
    assert sorted(set(boxes["frame"].to_list())) == [2, 3, 4]  # every setting scores the same frames
    for d in (1, 2):
        det = boxes.filter((pl.col("kind") == "det") & (pl.col("setting") == f"delay:{d}"))
        assert check_detections(det, w, [2, 3, 4], d) == len(det) > 0
    gt = boxes.filter(pl.col("kind") == "gt").drop("matched")
    clean = gt.filter((pl.col("setting") == "clean") & (pl.col("mode") == "late")).drop("setting")
    for s in ("delay:1", "delay:2"):  # the ground truth stays current
        assert clean.equals(gt.filter((pl.col("setting") == s) & (pl.col("mode") == "late")).drop("setting"))
    # the table in the settings' order, not the command line's (delay:2 came first)
    table = pl.read_csv(out / "robustness_table.csv")
    assert table["setting"].to_list() == ["clean", "delay:1", "delay:2"]


@pytest.mark.filterwarnings("default::mmusv.scenario_checks.MmusvWarning")  # the missing frames, said on stderr
def test_delay_counts_acquisition_indices_across_missing_frames(
    gap: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Frames 2..3 of the recording are missing: delay:1 at frame 4 has no frame 3, so frame 4 is not scored (it
    was, with frame 1's neighbour: 600 ms labelled 200 ms); frame 5 uses frame 4's."""
    from mmusv.acquire import run

    out = study(["study", "robustness", str(gap), "--settings", "delay:1"], tmp_path / "rob")
    assert "frames 2..3 missing" in capsys.readouterr().err
    boxes = pl.read_parquet(out / "robustness_boxes.parquet")
    assert sorted(set(boxes["frame"].to_list())) == [1, 5]
    # the same rows for frame 5 as on the whole recording

    full = run(scenario("gap", 6), out_dir=tmp_path / "full", checks=False).recording
    ref = study(["study", "robustness", str(full), "--settings", "delay:1"], tmp_path / "ref")
    a = boxes.filter(pl.col("frame") == 5)
    b = pl.read_parquet(ref / "robustness_boxes.parquet").filter(pl.col("frame") == 5)
    assert len(a) and a.equals(b)
    jobs = study(["study", "robustness", str(gap), "--settings", "delay:1", "--jobs", "2"], tmp_path / "jobs")
    for name in ("robustness_table.csv", "robustness_boxes.parquet"):
        assert (out / name).read_bytes() == (jobs / name).read_bytes(), name


# --- pose noise, recovered from a probe detector --------------------------------------------------------------

OFFSETS = np.array([[10.0, 10.0, 0.0], [20.0, 10.0, 0.0], [10.0, 20.0, 0.0], [20.0, 20.0, 8.0]])


class Probe:
    """A detector that finds four small boxes at fixed places of any cloud's own LiDAR frame (so late fusion shows
    where the neighbour's LiDAR was put), and keeps the clouds early fusion hands it."""

    def __init__(self) -> None:
        self.early_clouds: list[np.ndarray] = []

    def __call__(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        b = np.zeros((4, 7))
        b[:, :3] = OFFSETS
        b[:, 3:6] = 1.0
        return b, np.array([0.9, 0.8, 0.7, 0.6])

    def early(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self.early_clouds.append(np.array(points))
        return np.zeros((0, 7)), np.zeros(0)


MOUNT = np.eye(4)
MOUNT[:3, 3] = [0.5, 0.0, 2.0]


def pose(x: float, y: float, z: float, roll: float, pitch: float, yaw: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = rot(roll, pitch, yaw)
    m[:3, 3] = [x, y, z]
    return m


def probe_sequence(n: int) -> SequenceData:
    frames = []
    for t in range(n):
        agents = tuple(
            AgentFrame(
                f"usv_{k}",
                np.array([[5.0 + k, -3.0, 1.0 + t * 0.01, 0.5], [30.0, 7.0 * k, -1.0, 0.2]], np.float32),
                pose(60.0 * k + t, 5.0 * k, 0.1 * k, 0.02 * k, -0.01, 0.3 * k + 0.01 * t),
                MOUNT,
            )
            for k in range(2)
        )
        usv = np.stack([a.body for a in agents])
        frames.append(
            SceneFrame(t, agents, (), np.zeros((0, 4, 4)), np.zeros((0, 3)), usv, np.tile([5.0, 2.5, 2.0], (2, 1)))
        )
    return SequenceData("probe", tuple(frames))


def placed_neighbour(g: pl.DataFrame) -> np.ndarray:
    """``(4, 4)`` the neighbour's LiDAR frame -> the ego's as late fusion placed it: the rigid transform mapping
    :data:`OFFSETS` onto the neighbour's four probe boxes (those not at the ego's own offsets, by score)."""
    p = g.select(["x", "y", "z"]).to_numpy()
    s = g["score"].to_numpy()
    mine = [int(np.argmin(np.linalg.norm(p - o, axis=1))) for o in OFFSETS]
    assert np.allclose(p[mine], OFFSETS)
    others = [i for i in range(len(p)) if i not in mine]
    assert len(others) == 4
    q = p[others][np.argsort(-s[others], kind="stable")]
    a, b = OFFSETS - OFFSETS.mean(0), q - q.mean(0)
    u, _, vt = np.linalg.svd(a.T @ b)
    r = (u @ vt).T
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = r, q.mean(0) - r @ OFFSETS.mean(0)
    return out


def recovered(det: pl.DataFrame, seq: SequenceData, *, delay: int = 0) -> np.ndarray:
    """Per (frame, ego) of late fusion: the neighbour's body pose as the study placed it minus its true pose of frame
    k - ``delay`` (x, y, z in metres, roll, pitch, yaw in degrees)."""
    out = []
    for (frame, ego), g in det.group_by(["frame", "ego"], maintain_order=True):
        e = next(x for x in seq.frames[frame].agents if x.id == ego)
        nb = next(x for x in seq.frames[frame - delay].agents if x.id != ego)
        placed = e.body @ e.mount @ placed_neighbour(g) @ np.linalg.inv(nb.mount)
        got = Rotation.from_matrix(placed[:3, :3]).as_euler("ZYX", degrees=True)[::-1]
        true = Rotation.from_matrix(nb.body[:3, :3]).as_euler("ZYX", degrees=True)[::-1]
        out.append(np.r_[placed[:3, 3] - nb.body[:3, 3], (got - true + 180.0) % 360.0 - 180.0])
    return np.array(out)


def test_pose_noise_is_the_documented_gaussian_and_shared_by_late_and_early() -> None:
    seq = probe_sequence(150)
    probe = Probe()
    settings = parse_settings("noise:2/3,delay:1")
    res = run_study([seq], options=StudyOptions(modes=("late", "early"), settings=settings, detector=probe, seed=4))
    boxes = res.boxes_frame(with_setting=True).filter(pl.col("kind") == "det")
    late = boxes.filter(pl.col("mode") == "late")
    clean = recovered(late.filter(pl.col("setting") == "clean"), seq)
    assert np.abs(clean).max() < 1e-6
    delayed = recovered(late.filter(pl.col("setting") == "delay:1"), seq, delay=1)
    assert np.abs(delayed).max() < 1e-6  # the neighbour's pose of frame k - 1, exactly
    noise = recovered(late.filter(pl.col("setting") == "noise:2/3"), seq)
    n = len(noise)
    assert n == 2 * 149  # frame 0 is left out for every setting (delay:1)
    sigma = np.array([2.0, 2.0, 2.0, 3.0, 3.0, 3.0])
    assert np.all(np.abs(noise.mean(0)) < 4 * sigma / math.sqrt(n)), noise.mean(0)
    assert np.allclose(noise.std(0), sigma, rtol=0.2), noise.std(0)
    assert np.abs(np.corrcoef(noise.T) - np.eye(6)).max() < 0.25  # independent components
    # Early fusion: the ego's points, then the neighbour's moved by the same draw that placed its late boxes.
    order = [(t, e.id, s.name) for t in range(1, 150) for e in seq.frames[t].agents for s in settings]
    assert len(probe.early_clouds) == len(order)
    for cloud, (t, ego, setting) in zip(probe.early_clouds, order, strict=True):
        e = next(a for a in seq.frames[t].agents if a.id == ego)
        nb = next(a for a in seq.frames[t - (setting == "delay:1")].agents if a.id != ego)
        g = late.filter((pl.col("frame") == t) & (pl.col("ego") == ego) & (pl.col("setting") == setting))
        rel = placed_neighbour(g)
        assert np.array_equal(cloud[: len(e.points)], e.points)
        moved = nb.points[:, :3].astype(np.float64) @ rel[:3, :3].T + rel[:3, 3]
        assert np.allclose(cloud[len(e.points) :, :3], moved, atol=1e-3), (t, ego, setting)


def noise_of(seed: int, frames: int = 6) -> np.ndarray:
    seq = probe_sequence(frames)
    opts = StudyOptions(modes=("late",), settings=parse_settings("noise:1/1"), detector=Probe(), seed=seed)
    det = run_study([seq], options=opts).boxes_frame(with_setting=True).filter(pl.col("kind") == "det")
    return recovered(det.filter(pl.col("setting") == "noise:1/1"), seq)


def test_every_seed_draws_its_own_pose_noise() -> None:
    """The noise seed was ``seed & 0xFFFFFFFF``: --seed 4294967296 drew seed 0's noise, --seed -1 seed 4294967295's,
    while the note named the seed given."""
    a, b = noise_of(0), noise_of(2**32)
    assert not np.allclose(a, b)
    assert not np.allclose(noise_of(-1), noise_of(2**32 - 1))
    assert np.array_equal(noise_of(7), noise_of(7)) and not np.allclose(noise_of(7), a)


def test_noise_settings_that_print_alike_stay_apart(rec: Path, tmp_path: Path) -> None:
    """``noise:1/1`` and ``noise:1.0000001/1`` were both named ``noise:1/1`` (``%g``): one key, so each row held the
    frames of both (twice the ground truth) and both drew the same noise."""
    got = parse_settings("noise:1/1,noise:1.0000001/1,noise:0.5,noise:0.50/0.5")
    assert [s.name for s in got] == ["clean", "noise:0.5/0.5", "noise:1/1", "noise:1.0000001/1"]  # sorted
    out = study(["study", "robustness", str(rec), "--settings", "noise:1/1,noise:1.0000001/1"], tmp_path / "rob")
    metrics = pl.read_csv(out / "robustness_metrics.csv")
    assert metrics["setting"].unique(maintain_order=True).to_list() == ["clean", "noise:1/1", "noise:1.0000001/1"]
    assert set(metrics["gt"].to_list()) == {25.0}
    assert len(pl.read_csv(out / "robustness_table.csv")) == 3


@pytest.mark.parametrize("item", ["noise:1e308/1", "noise:1/1e308", "noise:2e6/1", "noise:1/400"])
def test_pose_noise_beyond_any_pose_is_refused(
    item: str, rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """σ = 1e308 overflowed the noisy pose to inf and ended in a shapely traceback."""
    err = refused(["study", "robustness", str(rec), "--settings", f"delay:1,{item}"], tmp_path / "o", capsys)
    assert f"--settings delay:1,{item}: item {item!r}" in err and "1e+06" in err and "360" in err, err
    with pytest.raises(InputError, match=r"^text = '.*': item '.*': expected clean") as said:
        parse_settings(item)
    assert "--settings" not in str(said.value)
    assert parse_settings("noise:1e6/360")[1] == Setting(sigma_xyz_m=1e6, sigma_rpy_deg=360.0)


def test_predictions_without_a_setting_are_refused(
    rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Table III's boxes (setting clean only) scored as Table IV gave AP 0.000 for every delay and noise setting, as
    if measured, with exit status 0."""
    det = study(["study", "detection", str(rec)], tmp_path / "det")
    pred = det / "detection_boxes.parquet"
    err = refused(
        ["study", "robustness", str(rec), "--settings", "delay:1,noise:1/1", "--predictions", str(pred)],
        tmp_path / "rob",
        capsys,
    )
    assert str(pred) in err and "delay:1" in err and "noise:1/1" in err and "clean" in err, err
    # the study's own robustness boxes hold every setting: re-scored, the same table
    rob = study(["study", "robustness", str(rec), "--settings", "delay:1"], tmp_path / "rob2")
    again = study(
        [
            "study",
            "robustness",
            str(rec),
            "--settings",
            "delay:1",
            "--predictions",
            str(rob / "robustness_boxes.parquet"),
        ],
        tmp_path / "rob3",
    )
    assert (rob / "robustness_table.csv").read_bytes() == (again / "robustness_table.csv").read_bytes()
    # a predictions file whose path holds [ ] (a run's name): polars read it as a glob ("not a readable Parquet
    # file (ComputeError)")
    odd = tmp_path / "runs[1]" / "boxes[a].parquet"
    odd.parent.mkdir()
    shutil.copyfile(rob / "robustness_boxes.parquet", odd)
    rob4 = study(["study", "robustness", str(rec), "--settings", "delay:1", "--predictions", str(odd)], tmp_path / "r4")
    assert (rob4 / "robustness_table.csv").read_bytes() == (rob / "robustness_table.csv").read_bytes()


@pytest.mark.parametrize(
    ("column", "value", "why"),
    [
        ("frame", None, "null"),
        ("frame", "x", "integer"),
        ("frame", 1.5, "integer"),
        ("score", None, "null"),
        ("score", math.nan, "finite"),
        ("x", math.nan, "finite"),
        ("l", math.inf, "finite"),
        ("ego", None, "null"),
    ],
)
def test_bad_values_in_a_predictions_file_are_named(
    column: str, value: Any, why: str, rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A null frame was a TypeError traceback, a text frame a Polars one; a fractional frame was truncated, null
    or NaN scores ranked anyhow and a NaN box silently dropped: each gave a table, exit status 0."""
    det = pl.read_parquet(study(["study", "detection", str(rec)], tmp_path / "det") / "detection_boxes.parquet")
    det = det.filter(pl.col("kind") == "det")
    bad = det.with_columns(
        pl.when(pl.int_range(pl.len()) == 3).then(pl.lit(value)).otherwise(pl.col(column)).alias(column)
        if not isinstance(value, str)
        else pl.col(column).cast(pl.Utf8).str.replace(r"^1$", value).alias(column)
    )
    path = tmp_path / "bad.parquet"
    bad.write_parquet(path)
    err = refused(["study", "detection", str(rec), "--predictions", str(path)], tmp_path / "o", capsys)
    assert f"--predictions {path}" in err and f"column {column}" in err and why in err, err


DETECTORS = """
import numpy as np
def nan_box(points):
    b = np.zeros((2, 7)); b[:, 0] = [10, np.nan]; b[:, 3:6] = 4.0
    return b, np.array([0.4, 0.5])
def nan_score(points):
    b = np.zeros((2, 7)); b[:, 0] = [10, 30]; b[:, 3:6] = 4.0
    return b, np.array([np.nan, 0.5])
def six_columns(points):
    return np.zeros((3, 6)), np.zeros(3)
"""


@pytest.mark.parametrize(("fn", "why"), [("nan_box", "finite"), ("nan_score", "finite"), ("six_columns", "(M, 7)")])
def test_a_detectors_bad_output_names_the_detector(
    fn: str, why: str, rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """NaN boxes and (M, 6) boxes were a shapely / numpy traceback; NaN scores were ranked anyhow, exit status 0."""
    import sys

    (tmp_path / "round_detectors.py").write_text(DETECTORS, encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "round_detectors", raising=False)
    spec = f"round_detectors:{fn}"
    err = refused(["study", "detection", str(rec), "--detector", spec], tmp_path / "o", capsys)
    assert f"--detector {spec} " in err and why in err, err


def test_a_recording_without_lidar_says_so(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Without LiDAR the error advised --modes none, which then said the sequence held no frame to evaluate."""
    from mmusv.acquire import run

    data = scenario("nolidar", 2)
    data["rigs"]["r"]["lidar"] = None
    if not any(data["rigs"]["r"].get(k) for k in ("radar", "cameras", "top_view")):  # no sensor at all: said
        from mmusv.scenario_checks import MmusvWarning

        with pytest.warns(MmusvWarning, match="switches every sensor off"):
            rec = run(data, out_dir=tmp_path / "rec", checks=False).recording
    else:
        rec = run(data, out_dir=tmp_path / "rec", checks=False).recording
    for modes in ("none,late,early", "none"):
        err = refused(["study", "detection", str(rec), "--modes", modes], tmp_path / "o", capsys)
        assert "sequence nolidar" in err and "no LiDAR" in err and "--modes none" not in err, err


def test_one_recording_given_twice_is_named(rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A recording given twice (here through a batch folder's link to its run folder and by its own folder) was
    refused as "the same recording is given twice", naming neither: the two paths and the file are named."""
    batch = tmp_path / "batch"
    batch.mkdir()
    (batch / "run").symlink_to(rec.parent, target_is_directory=True)
    err = refused(["study", "detection", str(batch), str(rec.parent)], tmp_path / "o", capsys)
    assert "the same recording is given twice" in err and str(batch / "run" / rec.name) in err, err
    assert str(rec.resolve()) in err, err


def test_copies_of_one_run_are_refused_not_counted_twice(
    rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A copy of a run folder beside the run was studied as a second sequence: the same frames counted twice, and
    split across the training and the test split. Two runs of one scenario configuration are refused, as convert
    refuses them."""
    from mmusv.studies.detection.sources import resolve_dataset

    copy = tmp_path / "copy"
    shutil.copytree(rec.parent, copy)
    with pytest.raises(InputError, match="runs of the same scenario configuration"):
        resolve_dataset([rec.parent, copy], opv2v=None, split="all")
    err = refused(["study", "detection", str(rec), str(copy / rec.name)], tmp_path / "o", capsys)
    assert "same scenario configuration" in err and str(copy / rec.name) in err, err
    assert len(resolve_dataset([rec.parent], opv2v=None, split="all").sources) == 1
