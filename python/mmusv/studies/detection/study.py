"""The detection study (Table III) and the robustness study (Table IV) over a set of sequences.

For every sequence of the chosen split, every frame and every instrumented USV as the ego in turn, each fusion
mode (and, for Table IV, each robustness setting) yields boxes in the ego LiDAR frame; a sequence of one USV with
a LiDAR, which has nothing to fuse, is scored in mode ``none`` only (:attr:`StudyResult.none_only`). Detections
farther than ``range_m`` from the ego, or centred within ``platform_margin_m`` of a USV's platform (the ego's or a
neighbour's: USVs are not targets), are dropped; the rest are matched against the ground truth
(:func:`~mmusv.studies.detection.data.gt_in_ego`) by :mod:`~mmusv.studies.detection.evaluate`.

Every ground truth also records ``ego_points``, the number of the ego's own LiDAR points inside it (BEV rectangle,
height within ±0.5 m), and ``neighbour_points``, the same summed over the other USVs' current clouds. With
``SEEN_POINTS`` = 5 (about the fewest points a box can be put on), a target is *visible* (ego_points ≥ 5),
*hidden* (fewer from the ego but ≥ 5 from the neighbours: behind an island or another hull, or too small for the
ego's beams at that range, but seen by cooperating USVs: the case cooperation exists for) or *unseen* (neither).
Recall at IoU 0.5 and 0.3 is reported for each class. Over waves, each ground truth also records
``wave_occlusion``, the share of it the waves hide from the ego's LiDAR (the recording's annotations, or an OPV2V
export's ``<ts>_additional.yaml``; NaN where the source has none), and the targets the waves hide at least
:data:`WAVE_HIDDEN_SHARE` of from the ego are a class of their own, *wave-hidden*, with its recall
(``recall50_wave_hidden``, ...; a target may be wave-hidden and visible, hidden or unseen as well).

The detections may come from a predictions file instead of a detector (``--predictions``; its layout and checks
are :mod:`~mmusv.studies.detection.predictions`'s).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import polars as pl
import shapely

from mmusv.boxes3d import in_target_range
from mmusv.errors import InputError
from mmusv.forking import check_polars
from mmusv.frames import transform_points
from mmusv.held_signals import raise_noted_stop
from mmusv.studies.detection.data import (
    AgentFrame,
    SceneFrame,
    SequenceData,
    gt_with_ids,
    usv_boxes_in_ego,
    wave_shares,
)
from mmusv.studies.detection.detector import Detector
from mmusv.studies.detection.evaluate import (
    BOX_COLUMNS,
    RANGE_BINS,
    FrameMatch,
    bin_label,
    box_polygons,
    range_bin,
    summarize,
)
from mmusv.studies.detection.fusion import DEFAULT_MODES, _as_boxes, detector_name, fuse, relative
from mmusv.studies.detection.predictions import Predictions
from mmusv.studies.detection.robustness import Setting, neighbours_for
from mmusv.text import named

__all__ = [
    "StudyOptions",
    "StudyResult",
    "gt_visibility",
    "run_study",
]

Key = tuple[str, str]  # (setting name, mode)
SEEN_POINTS = 5
"""LiDAR points inside a target for it to count as seen by a USV (module docstring)."""
WAVE_HIDDEN_SHARE = 0.5
"""The share of a target the waves hide from the ego's LiDAR from which it counts as wave-hidden (module
docstring)."""


@dataclass(frozen=True)
class StudyOptions:
    """What to evaluate: ``modes``, ``settings`` (``(Setting(),)`` for Table III), range, seed of the pose
    noise, either a ``detector`` or ``predictions`` (from
    :func:`~mmusv.studies.detection.predictions.load_predictions`), and how late fusion merges the USVs' boxes
    (``late_merge``, :data:`~mmusv.studies.detection.fusion.LATE_MERGES`)."""

    modes: tuple[str, ...] = DEFAULT_MODES
    settings: tuple[Setting, ...] = (Setting(),)
    detector: Detector | None = None
    predictions: Predictions | None = None
    range_m: float = 200.0
    platform_margin_m: float = 2.0
    seed: int = 0
    late_merge: str = "nms"


@dataclass
class StudyResult:
    """Matches per (setting, mode), the rows of every scored box, and what was evaluated."""

    options: StudyOptions
    matches: dict[Key, list[FrameMatch]] = field(default_factory=dict)
    visibility: dict[Key, list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]] = field(default_factory=dict)
    """Per key and ego-frame: visibility class of each ground truth (0 visible, 1 hidden, 2 unseen), matched at
    0.5, matched at 0.3, and its wave-occlusion share from the ego (NaN where unknown)."""
    rows: dict[str, list[Any]] = field(default_factory=dict)
    sequences: list[str] = field(default_factory=list)
    none_only: list[str] = field(default_factory=list)
    """The sequences of one USV with a LiDAR (nothing to fuse), scored in mode ``none`` only (of :attr:`sequences`)
    or, where ``none`` is not among the modes, not at all (not in :attr:`sequences`)."""
    key_frames: dict[Key, int] = field(default_factory=dict)
    """The frames scored per (setting, mode): fewer for the fusion modes where sequences were :attr:`none_only`."""
    frames: int = 0
    ego_frames: int = 0
    gt_boxes: int = 0
    predictions_used: int = 0

    @classmethod
    def merge(cls, options: StudyOptions, parts: Sequence[StudyResult]) -> StudyResult:
        """One result of ``parts`` (studies of disjoint sequences, in the order one study would have met them),
        equal to that study's: lists concatenated in order, counts summed."""
        out = cls(options=options)
        for part in parts:
            for key, fms in part.matches.items():
                out.matches.setdefault(key, []).extend(fms)
            for key, vis in part.visibility.items():
                out.visibility.setdefault(key, []).extend(vis)
            for col, values in part.rows.items():
                out.rows.setdefault(col, []).extend(values)
            out.sequences.extend(part.sequences)
            out.none_only.extend(part.none_only)
            for key, n in part.key_frames.items():
                out.key_frames[key] = out.key_frames.get(key, 0) + n
            out.frames += part.frames
            out.ego_frames += part.ego_frames
            out.gt_boxes += part.gt_boxes
            out.predictions_used += part.predictions_used
        return out

    def metrics(self, key: Key) -> dict[str, float]:
        """:func:`~mmusv.studies.detection.evaluate.summarize` of ``key`` plus the recall at IoU 0.5 and 0.3
        of the visible, hidden, unseen and wave-hidden ground truths (``recall50_hidden``, ``recall30_hidden``,
        ...; module docstring) and their counts ``gt_visible``, ``gt_hidden``, ``gt_unseen``, ``gt_wave_hidden``;
        ``frames`` is the number of frames scored, ``ego_frames`` that of (frame, ego USV) pairs."""
        out = summarize(self.matches.get(key, []))
        # summarize counts the ego-frames (one per USV of a frame); a fusion mode has fewer frames than none where a
        # sequence of one USV was scored in none only
        out["frames"] = float(self.key_frames.get(key, self.frames))
        vis = self.visibility.get(key, [])
        cls = np.concatenate([v[0] for v in vis]) if vis else np.zeros(0)
        hit50 = np.concatenate([v[1] for v in vis]) if vis else np.zeros(0, dtype=bool)
        hit30 = np.concatenate([v[2] for v in vis]) if vis else np.zeros(0, dtype=bool)
        wave = np.concatenate([v[3] for v in vis]) if vis else np.zeros(0)
        with np.errstate(invalid="ignore"):
            wave_hidden = wave >= WAVE_HIDDEN_SHARE  # NaN (unknown) is not
        for name, sel in (
            ("visible", cls == 0),
            ("hidden", cls == 1),
            ("unseen", cls == 2),
            ("wave_hidden", wave_hidden),
        ):
            n = int(sel.sum())
            out[f"recall50_{name}"] = float(hit50[sel].sum()) / n if n else math.nan
            out[f"recall30_{name}"] = float(hit30[sel].sum()) / n if n else math.nan
            out[f"gt_{name}"] = float(n)
        return out

    def table(self) -> pl.DataFrame:
        """One row per (setting, mode) evaluated, with every metric of :meth:`metrics`."""
        recs = []
        for s in self.options.settings:
            for m in self.options.modes:
                if (s.name, m) in self.matches:
                    recs.append(
                        {
                            "setting": s.name,
                            "kind": s.kind,
                            "delay_frames": s.delay_frames,
                            "sigma_xyz_m": s.sigma_xyz_m,
                            "sigma_rpy_deg": s.sigma_rpy_deg,
                            "mode": m,
                            **self.metrics((s.name, m)),
                        }
                    )
        return pl.DataFrame(recs)

    def boxes_frame(self, *, with_setting: bool) -> pl.DataFrame:
        """Every scored detection and ground-truth box (see the CLI help for the columns)."""
        df = pl.DataFrame(self.rows, schema=_ROW_SCHEMA)
        if not with_setting:
            df = df.drop("setting")
        keys = ["sequence", "frame", "ego", *(["setting"] if with_setting else []), "mode", "kind", "x", "y"]
        return df.sort(keys, maintain_order=True)


_ROW_SCHEMA: dict[str, Any] = {
    "sequence": pl.Utf8,
    "frame": pl.Int64,
    "ego": pl.Utf8,
    "setting": pl.Utf8,
    "mode": pl.Utf8,
    "kind": pl.Utf8,
    **dict.fromkeys(BOX_COLUMNS, pl.Float64),
    "score": pl.Float64,
    "range_bin": pl.Utf8,
    "matched": pl.Boolean,
    "ego_points": pl.Int64,
    "neighbour_points": pl.Int64,
    "wave_occlusion": pl.Float64,
}


def gt_visibility(gt: np.ndarray, points: np.ndarray, *, z_margin_m: float = 0.5) -> np.ndarray:
    """``(G,)`` int64 number of ``points`` ``(N, ≥3)`` inside each box of ``gt`` ``(G, 7)`` (same frame): BEV
    rectangle and height within ``z ± (h/2 + z_margin_m)``."""
    out = np.zeros(len(gt), dtype=np.int64)
    if len(gt) == 0 or len(points) == 0:
        return out
    p = np.asarray(points, dtype=np.float64)
    for i, (poly, b) in enumerate(zip(box_polygons(gt), gt, strict=True)):
        near = np.abs(p[:, 2] - b[2]) <= b[5] / 2 + z_margin_m
        q = p[near]
        if len(q):
            out[i] = int(shapely.contains_xy(poly, q[:, 0], q[:, 1]).sum())
    return out


def _keep(
    boxes: np.ndarray, scores: np.ndarray, usv: np.ndarray, *, range_m: float, margin: float
) -> tuple[np.ndarray, np.ndarray]:
    sel = in_target_range(boxes[:, :3], range_m)
    if len(usv) and len(boxes):
        plat = shapely.union_all(shapely.buffer(box_polygons(usv), margin))
        sel &= ~shapely.contains_xy(plat, boxes[:, 0], boxes[:, 1])
    return boxes[sel], scores[sel]


def run_study(
    sequences: Iterable[SequenceData],
    *,
    options: StudyOptions,
    total_frames: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    check_predictions: bool = True,
) -> StudyResult:
    """Evaluates ``sequences`` (see the module docstring). With delays, a frame ``k`` is scored only where the
    sequence holds the frame ``k - d`` of every delay ``d`` (so the first ``max delay`` frames of every sequence, and
    those just after missing frames, are left out), for every setting: all settings are scored on the same frames.
    A sequence of one USV with a LiDAR has nothing to fuse: it is scored in mode ``none`` only, and listed in
    :attr:`StudyResult.none_only`. ``check_predictions``:
    raise when a predictions file matched nothing evaluated (:func:`check_predictions_used`; off for one
    sequence of many, :mod:`~mmusv.studies.detection.parallel`)."""
    check_polars("the detection study")
    o = options
    if o.detector is None and o.predictions is None:
        raise InputError("no detector and no predictions given")
    res = StudyResult(options=o)
    for k in (
        "sequence",
        "frame",
        "ego",
        "setting",
        "mode",
        "kind",
        *BOX_COLUMNS,
        "score",
        "range_bin",
        "matched",
        "ego_points",
        "neighbour_points",
        "wave_occlusion",
    ):
        res.rows[k] = []
    delays = sorted({s.delay_frames for s in o.settings if s.delay_frames})
    fusion = [m for m in o.modes if m != "none"]
    done = 0
    for seq in sequences:
        if not seq.frames:
            continue
        if not seq.agent_ids:  # was "use --modes none", which then found no frame to evaluate
            raise InputError(
                f"sequence {seq.name}: no LiDAR: none of its instrumented USVs carries one (a rig with lidar: null), "
                "and the study detects in LiDAR clouds"
            )
        modes = o.modes
        if fusion and len(seq.agent_ids) < 2:
            # one USV: nothing to fuse, so no cooperative mode (it refused the whole dataset); none alone is scored
            res.none_only.append(seq.name)
            modes = tuple(m for m in o.modes if m == "none")
            if not modes:
                continue
        res.sequences.append(seq.name)
        keys = [(s.name, m) for s in o.settings for m in modes if m != "none" or s.name == "clean"]
        own = _OwnDetections(o.detector)
        for t, frame in enumerate(seq.frames):
            raise_noted_stop()  # a stop whose KeyboardInterrupt a library swallowed (held_signals)
            if any(seq.frame_at(frame.frame - d) is None for d in delays):
                continue  # a delay has no frame k - d here: left out for every setting
            res.frames += 1
            for key in keys:
                res.key_frames[key] = res.key_frames.get(key, 0) + 1
            for ego in frame.agents:
                _score_ego(res, seq, t, frame, ego, own, modes)
            done += 1
            if progress is not None:
                progress(done, total_frames or done)
    if check_predictions:
        check_predictions_used(res)
    return res


def check_predictions_used(res: StudyResult) -> None:
    """Raises :class:`~mmusv.errors.InputError` when ``res`` was scored from predictions of which no row matched
    any (sequence, frame, ego, mode) evaluated: a misnamed file, not a detector that found nothing. The message
    names the options' ``predictions`` (``--predictions`` from ``mmusv study``, :func:`mmusv.text.named`)."""
    if res.options.predictions is not None and res.predictions_used == 0 and res.ego_frames:
        raise InputError(
            f"{named('predictions')}: no row matches any (sequence, frame, ego, mode) evaluated; check the "
            f"sequence names ({', '.join(res.sequences[:3])}, ...) and the ego ids"
        )


class _OwnDetections:
    """The detector's output on an agent's own cloud, computed once per cloud (a neighbour's cloud serves every
    ego, delay and noise setting: noise changes only its pose)."""

    def __init__(self, detector: Detector | None) -> None:
        self.detector = detector
        self.cache: dict[tuple[str, int], tuple[np.ndarray, np.ndarray]] = {}

    def __call__(self, a: AgentFrame) -> tuple[np.ndarray, np.ndarray]:
        key = (a.id, id(a.points))
        if key not in self.cache:
            if self.detector is None:
                raise InputError("no detector given")
            self.cache[key] = _as_boxes(self.detector(a.points), detector_name(self.detector))
        return self.cache[key]


def _score_ego(
    res: StudyResult,
    seq: SequenceData,
    t: int,
    frame: SceneFrame,
    ego: AgentFrame,
    own: Callable[[AgentFrame], tuple[np.ndarray, np.ndarray]],
    modes: Sequence[str],
) -> None:
    o = res.options
    res.ego_frames += 1
    gt, gt_ids = gt_with_ids(frame, ego, range_m=o.range_m)
    wave = wave_shares(ego, gt_ids)
    res.gt_boxes += len(gt)
    usv = usv_boxes_in_ego(frame, ego)
    vis = gt_visibility(gt, ego.points)
    nb_vis = np.zeros(len(gt), dtype=np.int64)
    for nb in frame.agents:
        if nb.id != ego.id and len(gt):
            nb_vis += gt_visibility(gt, transform_points(relative(ego, nb), nb.points[:, :3]))
    cls = np.where(vis >= SEEN_POINTS, 0, np.where(nb_vis >= SEEN_POINTS, 1, 2))
    gbin = range_bin(gt[:, :2])
    for s in o.settings:
        nbs = neighbours_for(seq, t, ego.id, s, seed=o.seed)
        for mode in modes:
            if mode == "none" and s.name != "clean":
                continue  # no fusion does not depend on the neighbours
            if o.predictions is not None:
                got = o.predictions.get((seq.name, frame.frame, ego.id, mode, s.name))
                if got is not None:
                    res.predictions_used += 1
                boxes, scores = got if got is not None else (np.zeros((0, 7)), np.zeros(0))
            else:
                assert o.detector is not None
                boxes, scores = fuse(
                    mode,
                    ego,
                    nbs,
                    detector=o.detector,
                    own_detections=own,
                    crop_m=o.range_m + 20.0,
                    late_merge=o.late_merge,
                )
            boxes, scores = _keep(boxes, scores, usv, range_m=o.range_m, margin=o.platform_margin_m)
            fm = FrameMatch.evaluate(boxes, det_scores=scores, gt_boxes=gt)
            key = (s.name, mode)
            res.matches.setdefault(key, []).append(fm)
            gm = fm.gt_matched(0.5)
            res.visibility.setdefault(key, []).append((cls, gm, fm.gt_matched(0.3), wave))
            _add_rows(res, seq.name, frame.frame, ego.id, s.name, mode, fm, gm, gbin, (vis, nb_vis, wave))


def _add_rows(
    res: StudyResult,
    seq: str,
    frame: int,
    ego: str,
    setting: str,
    mode: str,
    fm: FrameMatch,
    gm: np.ndarray,
    gbin: np.ndarray,
    seen: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> None:
    vis, nb_vis, wave = seen
    r = res.rows
    dbin = fm.det_bins(0.5)
    tp = fm.matches[0.5] >= 0
    none: list[Any] = [None] * len(fm.det_boxes)
    for kind, boxes, scores, bins, matched, pts, nb_pts, waves in (
        ("det", fm.det_boxes, fm.det_scores, dbin, tp, none, none, none),
        ("gt", fm.gt_boxes, [math.nan] * len(fm.gt_boxes), gbin, gm, vis.tolist(), nb_vis.tolist(), wave.tolist()),
    ):
        n = len(boxes)
        r["sequence"] += [seq] * n
        r["frame"] += [frame] * n
        r["ego"] += [ego] * n
        r["setting"] += [setting] * n
        r["mode"] += [mode] * n
        r["kind"] += [kind] * n
        for j, c in enumerate(BOX_COLUMNS):
            r[c] += [float(v) for v in np.asarray(boxes)[:, j]] if n else []
        r["score"] += [float(v) for v in scores]
        r["range_bin"] += [bin_label(int(b)) for b in bins]
        r["matched"] += [bool(v) for v in matched]
        r["ego_points"] += list(pts)
        r["neighbour_points"] += list(nb_pts)
        r["wave_occlusion"] += list(waves)


def range_bin_labels() -> list[str]:
    """``["0-50", "50-100", ...]``."""
    return [bin_label(k) for k in range(len(RANGE_BINS))]


def sequence_list(seqs: Sequence[SequenceData]) -> list[str]:
    """Names of ``seqs``."""
    return [s.name for s in seqs]
