"""Presenting a detection study: rich tables, CSV, a plot (matplotlib) and the Parquet of every scored box.

:func:`detection_files` and :func:`robustness_files` make a report's files in memory; the command writes those of
all its runs together, once every run is computed, with :func:`~mmusv.jsonio.write_files_atomic` (an error or a
Ctrl-C half-way left the first files of a report, or the first run's whole report, beside nothing or an earlier
run's others). :func:`write_detection` and :func:`write_robustness` do both for one run.
"""

from __future__ import annotations

import io
import math
from collections.abc import Sequence
from pathlib import Path
from typing import IO, Any

import polars as pl

from mmusv.jsonio import write_files_atomic
from mmusv.studies.detection.detector import BASELINE_NOTE
from mmusv.studies.detection.evaluate import RANGE_BINS, bin_label
from mmusv.studies.detection.study import StudyResult
from mmusv.studies.plotting import default_style

__all__ = [
    "DETECTION_FILES",
    "DETECTION_METRICS",
    "ROBUSTNESS_FILES",
    "detection_files",
    "detection_table",
    "fmt",
    "none_only_line",
    "robustness_files",
    "robustness_table",
    "write_detection",
    "write_files",
    "write_robustness",
]

BINS = [bin_label(k) for k in range(len(RANGE_BINS))]

DETECTION_FILES = ("detection_table.csv", "detection_boxes.parquet", "detection_ap.png", "detection_note.txt")
"""The files of :func:`detection_files`, in its order."""
ROBUSTNESS_FILES = (
    "robustness_table.csv",
    "robustness_metrics.csv",
    "robustness_boxes.parquet",
    "robustness_ap.png",
    "robustness_note.txt",
)
"""The files of :func:`robustness_files`, in its order."""

DETECTION_METRICS: tuple[tuple[str, str | None], ...] = (
    ("ap30", "AP@0.3"),
    ("ap50", "AP@0.5"),
    ("ap70", "AP@0.7"),
    ("precision50", "P@0.5"),
    ("recall50", "R@0.5"),
    *((f"ap50_{b}", f"AP@0.5 {b} m") for b in BINS),
    ("recall50_visible", "R@0.5 visible"),
    ("recall50_hidden", "R@0.5 hidden"),
    ("recall50_unseen", None),
    ("recall30_visible", None),
    ("recall30_hidden", "R@0.3 hidden"),
    ("recall30_unseen", None),
    ("recall50_wave_hidden", "R@0.5 wave-hidden"),
    ("recall30_wave_hidden", None),
)
"""Table III's metric columns in CSV order, each with its heading in the printed table (``None``: CSV only)."""


def fmt(v: float) -> str:
    """Three decimals, ``-`` for NaN."""
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.3f}"


def detection_table(res: StudyResult) -> pl.DataFrame:
    """Table III: one row per fusion mode (clean setting)."""
    t = res.table().filter(pl.col("setting") == "clean")
    cols = ["mode", *(c for c, _ in DETECTION_METRICS), "gt_visible", "gt_hidden", "gt_unseen"]
    cols += ["gt_wave_hidden", "gt", "det", "frames", "ego_frames"]
    return t.select(cols)


def robustness_table(res: StudyResult) -> pl.DataFrame:
    """Table IV: AP@0.5 per setting (rows) and mode (columns); no fusion only under ``clean``."""
    t = res.table()
    wide = t.pivot(on="mode", index=["setting", "kind", "delay_frames", "sigma_xyz_m", "sigma_rpy_deg"], values="ap50")
    order = {s.name: i for i, s in enumerate(res.options.settings)}
    wide = wide.with_columns(pl.col("setting").replace_strict(order, return_dtype=pl.Int64).alias("_o")).sort("_o")
    return wide.drop("_o")


def _detector_name(res: StudyResult, detector: str) -> str:
    return "predictions file" if res.options.predictions is not None else detector


Files = dict[str, tuple[Path, bytes]]
"""A report made in memory: ``{key: (path, bytes)}``."""


def detection_files(res: StudyResult, out: Path, *, detector: str, notes: Sequence[str] = ()) -> Files:
    """``detection_table.csv``, ``detection_boxes.parquet``, ``detection_ap.png`` and ``detection_note.txt`` (with
    the lines ``notes``: a learned detector's models and second stage) of ``out``, made in memory, the note last."""
    table = detection_table(res)
    png = io.BytesIO()
    _plot_detection(table, png)
    csv, parquet, plot, note = (out / name for name in DETECTION_FILES)
    return {
        "csv": (csv, table.write_csv().encode("utf-8")),
        "parquet": (parquet, _parquet(res.boxes_frame(with_setting=False))),
        "png": (plot, png.getvalue()),
        "note": (note, _note(res, detector, notes).encode("utf-8")),
    }


def robustness_files(res: StudyResult, out: Path, *, detector: str, notes: Sequence[str] = ()) -> Files:
    """``robustness_table.csv`` (AP@0.5 per setting and mode), ``robustness_metrics.csv`` (every metric),
    ``robustness_boxes.parquet``, ``robustness_ap.png`` and ``robustness_note.txt`` (with the lines ``notes``) of
    ``out``, made in memory, the note last."""
    png = io.BytesIO()
    _plot_robustness(res, png)
    csv, metrics, parquet, plot, note = (out / name for name in ROBUSTNESS_FILES)
    return {
        "csv": (csv, robustness_table(res).write_csv().encode("utf-8")),
        "metrics": (metrics, res.table().write_csv().encode("utf-8")),
        "parquet": (parquet, _parquet(res.boxes_frame(with_setting=True))),
        "png": (plot, png.getvalue()),
        "note": (note, _note(res, detector, notes).encode("utf-8")),
    }


def write_files(files: Files) -> dict[str, Path]:
    """Writes ``files`` (of one report or of several, keys distinct) with
    :func:`~mmusv.jsonio.write_files_atomic`; returns their paths by key."""
    write_files_atomic(dict(files.values()))
    return {key: path for key, (path, _) in files.items()}


def write_detection(res: StudyResult, out: Path, *, detector: str, notes: Sequence[str] = ()) -> dict[str, Path]:
    """Writes :func:`detection_files` into ``out`` (created); returns the paths."""
    return write_files(detection_files(res, out, detector=detector, notes=notes))


def write_robustness(res: StudyResult, out: Path, *, detector: str, notes: Sequence[str] = ()) -> dict[str, Path]:
    """Writes :func:`robustness_files` into ``out`` (created); returns the paths."""
    return write_files(robustness_files(res, out, detector=detector, notes=notes))


def _parquet(df: pl.DataFrame) -> bytes:
    buf = io.BytesIO()
    df.write_parquet(buf)
    return buf.getvalue()


def none_only_line(res: StudyResult) -> str | None:
    """The line saying which sequences had one USV with a LiDAR, so were scored in mode ``none`` only (or, without
    mode ``none``, not at all); ``None`` when there were none. Worded for the command line and the Python API
    alike (it said "--modes has no none" in a report of ``modes=...``)."""
    if not res.none_only:
        return None
    names = ", ".join(res.none_only)
    if "none" in res.options.modes:
        return f"scored in mode none only (one USV with a LiDAR: nothing to fuse): {names}"
    return f"not scored (one USV with a LiDAR: nothing to fuse, and mode none was not asked for): {names}"


def _note(res: StudyResult, detector: str, notes: Sequence[str] = ()) -> str:
    lines = [f"detector: {_detector_name(res, detector)}", *notes]
    if detector == "baseline" and res.options.predictions is None:
        lines.append(BASELINE_NOTE)
    lines += [
        f"sequences: {len(res.sequences)} ({', '.join(res.sequences)})",
        *([line] if (line := none_only_line(res)) is not None else []),
        f"frames: {res.frames}",
        f"ego-frames: {res.ego_frames}",
        f"ground-truth boxes: {res.gt_boxes}",
        f"range: {res.options.range_m:g} m; seed: {res.options.seed}",
        f"late fusion merge: {res.options.late_merge}",
    ]
    return "\n".join(lines) + "\n"


def _plot_detection(table: pl.DataFrame, path: Path | IO[bytes]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with default_style():  # not the user's matplotlibrc or style: the same bytes wherever it is drawn
        fig, ax = plt.subplots(1, 2, figsize=(10, 4))
        modes = table["mode"].to_list()
        for m in modes:
            r = table.filter(pl.col("mode") == m).row(0, named=True)
            ax[0].plot([0.3, 0.5, 0.7], [r["ap30"], r["ap50"], r["ap70"]], marker="o", label=m)
            ax[1].plot(range(len(BINS)), [r[f"ap50_{b}"] for b in BINS], marker="o", label=m)
        ax[1].set_xticks(range(len(BINS)), BINS)
        _finish(
            fig, ax, [("IoU threshold", "AP"), ("range bin (m)", "AP@0.5")], "Cooperative detection (Table III)", path
        )


def _finish(fig: Any, ax: Any, labels: list[tuple[str, str]], title: str, path: Path | IO[bytes]) -> None:
    """Axis labels, limits, grid and legends of the two panels; saves ``fig`` (no timestamp) and closes it."""
    import matplotlib.pyplot as plt

    for a, (xl, yl) in zip(ax, labels, strict=True):
        a.set_xlabel(xl)
        a.set_ylabel(yl)
        a.set_ylim(0, 1)
        a.grid(alpha=0.3)
        a.legend()
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, format="png", dpi=100, metadata={"Software": None})
    plt.close(fig)


def _plot_robustness(res: StudyResult, path: Path | IO[bytes]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with default_style():  # not the user's matplotlibrc or style: the same bytes wherever it is drawn
        t = res.table()
        fig, ax = plt.subplots(1, 2, figsize=(10, 4))
        clean = {r["mode"]: r["ap50"] for r in t.filter(pl.col("setting") == "clean").iter_rows(named=True)}
        for a, kind, xcol in ((ax[0], "delay", "delay_frames"), (ax[1], "noise", "sigma_xyz_m")):
            for m in res.options.modes:
                if m == "none":
                    if "none" in clean:
                        a.axhline(clean["none"], color="grey", ls="--", label="none")
                    continue
                sub = t.filter((pl.col("mode") == m) & (pl.col("kind") == kind)).sort(xcol)
                xs = [0.0, *sub[xcol].cast(pl.Float64).to_list()]
                ys = [clean.get(m, math.nan), *sub["ap50"].to_list()]
                a.plot(xs, ys, marker="o", label=m)
        _finish(
            fig,
            ax,
            [("delay (frames)", "AP@0.5"), ("pose noise σ_xyz (m) = σ_rpy (°)", "AP@0.5")],
            "Robustness (Table IV)",
            path,
        )


def rescore(boxes: pl.DataFrame) -> dict[str, float]:
    """:func:`~mmusv.studies.detection.evaluate.summarize` of the rows of a boxes Parquet (one mode and setting,
    e.g. after filtering by sequence): every (sequence, frame, ego) is matched again from its det and gt rows."""
    from mmusv.studies.detection.evaluate import BOX_COLUMNS, FrameMatch, summarize

    frames = []
    for _, g in boxes.group_by(["sequence", "frame", "ego"], maintain_order=True):
        d = g.filter(pl.col("kind") == "det")
        t = g.filter(pl.col("kind") == "gt")
        frames.append(
            FrameMatch.evaluate(
                d.select(list(BOX_COLUMNS)).to_numpy(),
                det_scores=d["score"].to_numpy(),
                gt_boxes=t.select(list(BOX_COLUMNS)).to_numpy(),
            )
        )
    return summarize(frames)
