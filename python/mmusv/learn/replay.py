"""The detection study's predictions Parquet from the heatmap peaks of :mod:`mmusv.learn.infer` (inference done
elsewhere, e.g. on a GPU machine without mmusv installed), for ``mmusv study detection --predictions``.

Each cloud's or sample's peaks get the rotated NMS of :func:`mmusv.learn.decode.decode` (the study's own
:func:`~mmusv.studies.detection.fusion.rotated_nms` at the preset's ``nms_iou``): that is ``none`` (the ego's own
cloud), ``early`` and ``intermediate``. With ``refine`` (``--refine``) the boxes then go through the geometric
second stage as :class:`mmusv.learn.detector.LearnedDetector` applies it (:func:`mmusv.learn.refine.refine_boxes`
on the points the model was given, then the rotated NMS again): the cloud's own points for ``none`` and
``intermediate``, the ego's and its neighbours' points in the ego frame
(:func:`mmusv.learn.example.early_cloud`) for ``early``; the points are the cache's, the model's very input.
``late`` is made by the study's :func:`~mmusv.studies.detection.fusion.fuse` from the (refined) single-agent
detections of the ego and its current neighbours, merged by rotated NMS or WBF (``late_merge``), as ``--model``
would. Clean setting only (the robustness settings re-run early and intermediate fusion on delayed or noisy
inputs: use ``--model``).

Beside the detections (rows of ``kind`` ``det``), the file holds one row of kind ``frame`` (box and score null)
for every (sequence, frame, ego, mode) it covers, detections or not: a model that finds nothing writes a file that
says which frames it looked at, and the study scores it as AP 0 (a file without a row said nothing, and was
refused).

With ``--scorers DIR`` (and ``--refine``) the refined boxes are rescored by the IoU scorers of
:mod:`mmusv.learn.scorer` as the detector does (:func:`mmusv.learn.scorer.second_stage`); a scorer fitted for other
weights than the model whose peaks are replayed is refused (the peaks record each model's weights digest).

The peaks must be those of this cache (one item per cloud or sample: the peaks of another cache, or of an ``infer
--limit`` run, are refused), and the cache must hold every sequence of ``split`` of the recordings given (or of
the OPV2V folder, ``--opv2v``, for a cache ``mmusv train --opv2v`` built), recorded the same (a cache of another
split wrote a predictions file without a row): ``--split``, ``--split-ratios`` and ``--seed`` must be those the
cache was built with (``mmusv train``'s and ``mmusv study``'s options of the same names; defaults ``test``,
``0.7,0.15,0.15`` and 0). Run as a command, a bad input is one line, ``mmusv: error: ...``, and exit status 2.

``python -m mmusv.learn.replay PEAKS.npz CACHE.npz RECORDINGS...|--opv2v FOLDER [--split test] [--split-ratios
0.7,0.15,0.15] [--seed 0] [--refine [--scorers DIR]] [--late-merge wbf] -o PREDICTIONS.parquet``
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path

import numpy as np

from mmusv.learn._errors import input_error, input_error_types
from mmusv.learn.cache import Cache
from mmusv.learn.example import early_cloud
from mmusv.learn.infer import check_out_file
from mmusv.learn.modes import MODELS
from mmusv.learn.refine import RefineParams
from mmusv.learn.scorer import SCORER_FILE, IoUScorer, load_scorer, second_stage
from mmusv.text import command_line, given, named

__all__ = ["main", "write_predictions"]

Key = tuple[str, int, str]


def _no_detector(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Late fusion reads the cached single-agent detections only; this is never called."""
    raise AssertionError("late fusion called the detector")


def _rows(z: dict[str, np.ndarray], mode: str, i: int) -> tuple[np.ndarray, np.ndarray]:
    o = z[f"{mode}_offsets"]
    return z[f"{mode}_boxes"][o[i] : o[i + 1]].astype(np.float64), z[f"{mode}_scores"][o[i] : o[i + 1]].astype(
        np.float64
    )


def _aggregate(cache: Cache, k: int) -> np.ndarray:
    """Sample ``k``'s ego and neighbour points in the ego frame: the early-fusion model's input."""
    ego, nbs, _ = cache.sample(k)
    return early_cloud(ego, nbs)


def _read_peaks(peaks: str | Path, cache: Cache) -> dict[str, np.ndarray]:
    """The arrays of the peaks file ``peaks`` (:mod:`mmusv.learn.infer`), checked against ``cache``: one item per
    cloud (``single``) or sample (``early``, ``intermediate``) of the cache. The peaks of another cache, or of a run
    with ``--limit``, were an ``IndexError`` traceback, or boxes put on the clouds of other frames. The message names
    that limit as the caller's side gives it: ``infer_cache``'s ``limit`` to a Python caller,
    ``python -m mmusv.learn.infer --limit`` to this module's command (it said ``--limit`` to both)."""
    limited = named("limit") if named("limit") != "limit" else "mmusv.learn.infer.infer_cache's limit"
    import zipfile

    try:
        with open(peaks, "rb") as fh, np.load(fh, allow_pickle=False) as f:
            z = {k: f[k] for k in f.files}
    except (ValueError, EOFError, TypeError, zipfile.BadZipFile) as exc:
        raise input_error(f"{peaks}: not a peaks .npz of mmusv.learn.infer ({type(exc).__name__})") from None
    found = [m for m in MODELS if f"{m}_offsets" in z]
    if not found:
        raise input_error(f"{peaks}: holds no peaks ({', '.join(f'{m}_offsets' for m in MODELS)} missing)")
    n_clouds = len(cache.arrays["cloud_offsets"]) - 1
    for m in found:
        n, what = (n_clouds, "clouds") if m == "single" else (len(cache), "samples")
        o, b, sc = z[f"{m}_offsets"], z.get(f"{m}_boxes"), z.get(f"{m}_scores")
        if len(o) != n + 1:
            raise input_error(
                f"{peaks}: {m}_offsets: peaks of {len(o) - 1} items, where the cache {cache.path} has {n} {what}: the "
                f"peaks of another cache, or of an inference of its first items only ({limited}); infer them on this "
                "cache"
            )
        if b is None or sc is None or b.ndim != 2 or b.shape[1] != 7 or len(b) != len(sc) or o[-1] != len(sc):
            raise input_error(f"{peaks}: {m}_boxes/{m}_scores: not (M, 7) boxes and (M,) scores as {m}_offsets says")
    return z


def _check_scorers(z: dict[str, np.ndarray], peaks: str | Path, scorers: dict[str, IoUScorer]) -> None:
    """Refuses a scorer fitted for other weights than those of the model whose peaks ``z`` holds (the digest
    :mod:`mmusv.learn.infer` records per model, ``<mode>_model``, against the one the fit saved): it ranked the boxes
    of another model, and the predictions were written rescored by it without a word. A scorer that records no
    model (not fitted by ``mmusv train``) is taken, as the detector takes it."""
    for mode in sorted(scorers):
        fitted_for = scorers[mode].info.get("model")
        if fitted_for is None or f"{mode}_offsets" not in z:
            continue
        held = z.get(f"{mode}_model")
        if held is None or held.shape != () or held.dtype.kind != "U":
            raise input_error(
                f"{named('scorers')}: {peaks} records no digest of its {mode} model (written by an mmusv.learn.infer "
                "of before 2026-12-05), so the scorer cannot be matched to it; infer the peaks again, or leave "
                f"out {named('scorers')}"
            )
        if str(held) != fitted_for:
            raise input_error(
                f"{named('scorers')}: the {mode} scorer was fitted for other weights than the {mode} model whose "
                f"peaks {peaks} holds (model {str(held)[:12]}, scorer fitted for {str(fitted_for)[:12]}); give the "
                "scorers of that model (its mmusv train folder), or refit them: mmusv train --scorers-only"
            )


def _check_same_sequences(ds: object, cache: Cache, split: str) -> None:
    """Refuses a cache that lacks a sequence of the dataset's split, or holds one of the same name recorded otherwise:
    its peaks were never matched to a frame, and the predictions file was written without a row."""
    from mmusv.learn.cache import dataset_fingerprints

    held = {str(x) for x in cache.arrays["sequences"]}
    recorded = cache.meta.get("fingerprints")
    theirs: dict[str, str] = recorded if isinstance(recorded, dict) else {}
    asked = dataset_fingerprints(ds)
    names = sorted(getattr(ds, "sources", {}))
    missing = [n for n in names if n not in held]
    other = [n for n in names if n in held and n in asked and n in theirs and asked[n] != theirs[n]]
    if missing or other:
        why = f"holds no sequence {', '.join(missing)}" if missing else f"holds {', '.join(other)} recorded differently"
        raise input_error(
            f"{given('cache', cache.path)}: {why} of split {split!r} of the recordings given (it holds "
            f"{', '.join(sorted(held))}{_built_with(cache, '; it was built with ')}); give the {named('inputs')}, "
            f"{named('split')}, {named('ratios')} and {named('seed')} the cache was built from"
        )


def _built_with(cache: Cache, lead: str) -> str:
    """``lead`` and the ``split``, ``ratios`` and ``seed`` the cache records it was built with, as its user gives
    them (``--split``, ``--split-ratios`` and ``--seed`` on the command line); ``""`` where it does not."""
    split, ratios, seed = (cache.meta.get(k) for k in ("split", "ratios", "seed"))
    if not isinstance(ratios, list) or not all(isinstance(r, (int, float)) for r in ratios):
        return ""
    shown = [given("split", split), given("ratios", [float(r) for r in ratios]), given("seed", seed)]
    return lead + (" " if named("split") != "split" else ", ").join(shown)


def write_predictions(
    peaks: str | Path,
    cache: Cache,
    *,
    inputs: Sequence[str | Path],
    out: str | Path,
    opv2v: str | Path | None = None,
    split: str = "test",
    ratios: Sequence[float] = (0.7, 0.15, 0.15),
    seed: int = 0,
    nms_iou: float = 0.1,
    refine: RefineParams | None = None,
    late_merge: str = "nms",
    scorers: dict[str, IoUScorer] | None = None,
) -> Path:
    """Writes the predictions Parquet (module docstring) of ``peaks`` on ``cache`` (built from the same
    ``inputs``, or OPV2V folder ``opv2v``, and split) to ``out``; returns ``out``. ``refine``: the second stage's
    parameters, or ``None`` for the network's boxes; ``late_merge``: one of
    :data:`mmusv.studies.detection.fusion.LATE_MERGES`; ``scorers``: the IoU scorers by model (``single``, ``early``,
    ``intermediate``) for the refined boxes."""
    import polars as pl

    from mmusv.studies.detection.data import AgentFrame
    from mmusv.studies.detection.fusion import LATE_MERGES, fuse, rotated_nms
    from mmusv.studies.detection.robustness import Setting, neighbours_for
    from mmusv.studies.detection.sources import resolve_dataset

    if late_merge not in LATE_MERGES:
        raise input_error(f"{given('late_merge', late_merge)}: allowed: {', '.join(LATE_MERGES)}")
    check_out_file(out)  # before the work: a folder failed only when written, naming no -o
    z = _read_peaks(peaks, cache)
    _check_scorers(z, peaks, scorers or {})
    try:
        ds = resolve_dataset(list(inputs), opv2v=opv2v, split=split, ratios=tuple(ratios), seed=seed)
    except input_error_types() as exc:  # an empty split: say how the cache was made
        hint = _built_with(cache, f"; the cache {cache.path} was built with ")
        if not hint:
            raise
        raise input_error(f"{exc}{hint}") from None
    _check_same_sequences(ds, cache, split)

    def nms(b: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        keep = rotated_nms(b, s, iou_threshold=nms_iou)
        return b[keep], s[keep]

    def stage(
        b: np.ndarray, s: np.ndarray, points: Callable[[], np.ndarray], model: str
    ) -> tuple[np.ndarray, np.ndarray]:
        b, s = nms(b, s)
        if refine is None or len(s) == 0:
            return b, s
        scorer = (scorers or {}).get(model)
        return second_stage(points(), boxes=b, scores=s, refine=refine, scorer=scorer, nms_iou=nms_iou)

    own: dict[Key, tuple[np.ndarray, np.ndarray]] = {}
    fused: dict[tuple[Key, str], tuple[np.ndarray, np.ndarray]] = {}
    n_clouds = len(cache.arrays["cloud_offsets"]) - 1
    for c in range(n_clouds):
        if "single_offsets" in z:
            own[cache.key(c)] = stage(*_rows(z, "single", c), partial(cache.cloud, c), "single")
    for k in range(len(cache)):
        ego_cloud = int(cache.arrays["sample_cloud"][k])
        key = cache.key(ego_cloud)
        if "early_offsets" in z:
            fused[(key, "early")] = stage(*_rows(z, "early", k), partial(_aggregate, cache, k), "early")
        if "intermediate_offsets" in z:
            fused[(key, "intermediate")] = stage(
                *_rows(z, "intermediate", k), partial(cache.cloud, ego_cloud), "intermediate"
            )
    box = ("x", "y", "z", "l", "w", "h", "yaw")
    cols: dict[str, list[object]] = {c: [] for c in ("sequence", "frame", "ego", "mode", "kind", *box, "score")}

    def row(key: Key, mode: str, kind: str, values: Sequence[float | None], score: float | None) -> None:
        for name, v in zip(("sequence", "frame", "ego", "mode", "kind"), (*key, mode, kind), strict=True):
            cols[name].append(v)
        for name, x in zip(box, values, strict=True):
            cols[name].append(x)
        cols["score"].append(score)

    def add(key: Key, mode: str, b: np.ndarray, s: np.ndarray) -> None:
        row(key, mode, "frame", [None] * len(box), None)  # covered, whether or not anything was found
        for r, sc in zip(b, s, strict=True):
            row(key, mode, "det", [float(v) for v in r], float(sc))

    for seq in ds.sequences():
        for t, frame in enumerate(seq.frames):
            for ego in frame.agents:
                key = (seq.name, frame.frame, ego.id)
                if key in own:
                    add(key, "none", *own[key])
                    nbs = neighbours_for(seq, t, ego.id, Setting(), seed=seed)

                    def mine(a: AgentFrame, f: int = frame.frame, s: str = seq.name) -> tuple[np.ndarray, np.ndarray]:
                        return own[(s, f, a.id)]

                    late = fuse("late", ego, nbs, detector=_no_detector, own_detections=mine, late_merge=late_merge)
                    add(key, "late", *late)
                for mode in ("early", "intermediate"):
                    if (key, mode) in fused:
                        add(key, mode, *fused[(key, mode)])
    out_p = Path(out)
    out_p.parent.mkdir(parents=True, exist_ok=True)
    pl.DataFrame(
        cols,
        schema={
            **dict.fromkeys(("sequence", "ego", "mode", "kind"), pl.Utf8),
            "frame": pl.Int64,
            **dict.fromkeys((*box, "score"), pl.Float64),
        },
    ).select(list(cols)).write_parquet(out_p)
    return out_p


def main(argv: Sequence[str] | None = None) -> int:
    """The command line of the module docstring."""
    ap = argparse.ArgumentParser(description=" ".join((__doc__ or "").split("\n\n")[0].split()))
    ap.add_argument("peaks", help="the peaks .npz of mmusv.learn.infer (scripts/learn_train.py infer) on CACHE")
    ap.add_argument("cache", help="the tensor cache the peaks were inferred on (mmusv train --cache-only)")
    ap.add_argument("inputs", nargs="*", help="the recordings (.mcap) or folders of them the cache was built from")
    ap.add_argument("--opv2v", default=None, help="the OPV2V folder the cache was built from (instead of recordings)")
    ap.add_argument("--split", default="test", help="the split the cache holds (default test)")
    ap.add_argument(
        "--split-ratios",
        default="0.7,0.15,0.15",
        help="train,validate,test fractions the cache's split was made with (default 0.7,0.15,0.15)",
    )
    ap.add_argument("--seed", type=int, default=0, help="seed of the split the cache was made with (default 0)")
    ap.add_argument(
        "--refine", action="store_true", help="the geometric second stage on every box (mmusv.learn.refine)"
    )
    ap.add_argument("--late-merge", default="nms", help="late fusion's merge: nms (default) or wbf")
    ap.add_argument(
        "--scorers",
        default=None,
        metavar="DIR",
        help="with --refine: rescore by the IoU scorers DIR/<single|early|intermediate>/scorer.pt (mmusv train's "
        "output folder)",
    )
    ap.add_argument("-o", "--out", required=True, help="the predictions Parquet to write")
    a = ap.parse_intermixed_args(argv)  # recordings after the options too (inputs may be none, with --opv2v)
    from mmusv.learn.cli import split_ratios

    ratios = split_ratios(a.split_ratios)  # as mmusv train and mmusv study take it
    refine = RefineParams() if a.refine else None
    scorers = None
    if a.scorers is not None:
        if refine is None:
            raise input_error("--scorers needs --refine (the scorers read the refined boxes)")
        root = Path(a.scorers)
        scorers = {m: load_scorer(root / m / SCORER_FILE) for m in MODELS if (root / m / SCORER_FILE).is_file()}
        if not scorers:
            raise input_error(f"--scorers {root}: no <{'|'.join(MODELS)}>/{SCORER_FILE} there")
    flags = {"cache": "cache", "inputs": "recordings", "split": "--split", "ratios": "--split-ratios", "seed": "--seed"}
    flags["opv2v"] = "--opv2v"  # an OPV2V folder given as a recording is told to be given so
    flags["limit"] = "python -m mmusv.learn.infer --limit"  # how the peaks were cut short, for _read_peaks
    flags |= {"late_merge": "--late-merge", "scorers": "--scorers", "out": "-o"}
    with command_line(flags):  # the messages name what it takes
        return _write(a, ratios, refine, scorers)


def _write(
    a: argparse.Namespace,
    ratios: Sequence[float],
    refine: RefineParams | None,
    scorers: dict[str, IoUScorer] | None,
) -> int:
    path = write_predictions(
        a.peaks,
        Cache(a.cache, name="cache"),
        inputs=a.inputs,
        opv2v=a.opv2v,
        out=a.out,
        split=a.split,
        ratios=ratios,
        seed=a.seed,
        refine=refine,
        late_merge=a.late_merge,
        scorers=scorers,
    )
    print(path)
    return 0


if __name__ == "__main__":
    from mmusv.learn._errors import command

    raise SystemExit(command(main))
