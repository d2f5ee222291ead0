"""The predictions file of the detection and robustness studies (``mmusv study ... --predictions``): reading it into
the study's per-frame detections and refusing what it cannot score, each refusal naming the file, the column and
the row.

**Predictions file** (``--predictions``, instead of a detector): a Parquet file with one row per detection and
columns ``sequence`` (recording stem or OPV2V scenario folder name), ``frame`` (acquisition index), ``ego``
(USV id, or CAV id for OPV2V), ``mode`` (``none``/``late``/``early``/``intermediate``), ``x, y, z, l, w, h,
yaw`` (ego LiDAR frame, mmusv axes: x forward, y left, z up; metres, radians), ``score``; optionally
``setting`` (robustness study, e.g. ``delay:2``; missing = ``clean``) and ``kind``: rows of kind ``det`` are the
detections; a row of kind ``frame`` (its box and score null) says the file covers its (sequence, frame, ego,
mode, setting), so that a covered frame without a ``det`` row is scored as one without a detection (a model that
found nothing is AP 0, not a file that says nothing); ``gt`` rows, as this study writes, say the same; other
kinds are skipped. Without a ``kind`` column every row is a detection. A frame with no row has no detection. The
study refuses a file that covers no frame of a (setting, mode) it scores
(:func:`check_prediction_coverage`). :mod:`mmusv.learn.replay` writes a ``frame`` row for every (sequence, frame,
ego, mode) it covers, and the Parquet this study writes has that layout, so its output can be re-scored.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import polars as pl

from mmusv.errors import InputError
from mmusv.studies.detection.evaluate import BOX_COLUMNS
from mmusv.studies.detection.fusion import MODES
from mmusv.studies.detection.robustness import Setting
from mmusv.text import given, named

__all__ = ["COVERAGE_KINDS", "Predictions", "check_prediction_coverage", "load_predictions"]

COVERAGE_KINDS = ("frame", "gt")
"""The ``kind`` values of a predictions file's rows that say which (sequence, frame, ego, mode, setting) it covers
without being detections (module docstring)."""

Predictions = dict[tuple[str, int, str, str, str], tuple[np.ndarray, np.ndarray]]
"""Detections keyed by (sequence, frame, ego, mode, setting): boxes ``(N, 7)`` float64 ``x, y, z, l, w, h, yaw``
(ego LiDAR frame; metres, radians) and scores ``(N,)`` float64; a covered key without a detection maps to
``N = 0``."""


def load_predictions(path: str | Path) -> Predictions:
    """The detections of a predictions Parquet (module docstring) keyed by (sequence, frame, ego, mode,
    setting); a key the file covers (a ``frame`` or ``gt`` row) without a detection maps to no box. Its refusals name
    ``path`` as its user gave it (:func:`mmusv.text.given`: ``path = '...'``, ``--predictions ...`` from ``mmusv
    study``)."""
    p = Path(path)
    shown = given("path", p)
    if not p.is_file():
        raise InputError(f"{shown}: {'a folder; give the predictions Parquet file' if p.is_dir() else 'no such file'}")
    try:
        df = pl.read_parquet(p, glob=False)  # a file a[1].parquet is a name, not a pattern
    except (OSError, pl.exceptions.PolarsError) as exc:
        raise InputError(f"{shown}: not a readable Parquet file ({type(exc).__name__})") from None
    need = ["sequence", "frame", "ego", "mode", *BOX_COLUMNS, "score"]
    missing = [c for c in need if c not in df.columns]
    if missing:
        raise InputError(f"{shown}: missing column(s) {missing}; required: {need}")
    if df.height == 0:  # no row (and columns of type Null, written without a schema): it covers nothing
        return {}
    df = df.with_row_index("_row")
    if "setting" not in df.columns:
        df = df.with_columns(pl.lit("clean").alias("setting"))
    if "kind" in df.columns:
        kind = pl.col("kind").cast(pl.Utf8, strict=False)
        covered = df.filter(kind.is_in(list(COVERAGE_KINDS)))
        df = df.filter(kind == "det")
    else:
        covered = df.clear()
    _check_prediction_keys(shown, df, rows="det")
    _check_prediction_values(shown, df)
    _check_prediction_keys(shown, covered, rows=" or ".join(COVERAGE_KINDS))
    out: Predictions = {}
    keys = ["sequence", "frame", "ego", "mode", "setting"]

    def typed(d: pl.DataFrame) -> pl.DataFrame:
        return d.with_columns(
            pl.col("frame").cast(pl.Int64), pl.col("ego").cast(pl.Utf8), pl.col("sequence").cast(pl.Utf8)
        )

    for row in typed(covered).select(keys).unique(maintain_order=True).iter_rows():
        k = (str(row[0]), int(row[1]), str(row[2]), str(row[3]), str(row[4]))
        out[k] = (np.zeros((0, 7)), np.zeros(0))
    for key, g in typed(df).group_by(keys, maintain_order=True):
        k = (str(key[0]), int(key[1]), str(key[2]), str(key[3]), str(key[4]))
        out[k] = (g.select(list(BOX_COLUMNS)).to_numpy().astype(np.float64), g["score"].to_numpy().astype(np.float64))
    return out


def _check_prediction_keys(shown: str, df: pl.DataFrame, *, rows: str) -> None:
    """Refuses rows (``_row`` = the row in the file) of a predictions table with a null key, a frame that is not a
    whole number or a mode that is not one: a null frame was a TypeError traceback and 1.5 was read as frame 1.
    ``shown``: the file as its user gave it; ``rows``: the kind of the rows, for the message."""

    def first(mask: pl.Series) -> str:
        return f"row {int(df['_row'].filter(mask)[0])}"

    for c in ("sequence", "frame", "ego", "mode", "setting"):
        nulls = df[c].is_null()
        if nulls.any():
            raise InputError(
                f"{shown}: column {c} has {int(nulls.sum())} null value(s) (first: {first(nulls)}); "
                f"every {rows} row needs one"
            )
    frame = df["frame"]
    if not frame.dtype.is_numeric():
        raise InputError(f"{shown}: column frame must hold integer acquisition indices, not {frame.dtype}")
    if frame.dtype.is_float():
        values = frame.to_numpy()
        bad = pl.Series(~np.isfinite(values) | (values != np.round(values)) | (np.abs(values) > 2**62))
        if bad.any():
            raise InputError(
                f"{shown}: column frame must hold integer acquisition indices; {first(bad)} has "
                f"{float(values[bad.to_numpy()][0])!r}"
            )
    unknown = sorted(set(df["mode"].cast(pl.Utf8).to_list()) - set(MODES))
    if unknown:
        raise InputError(f"{shown}: column mode has unknown value(s) {unknown}; allowed: {', '.join(MODES)}")


def _check_prediction_values(shown: str, df: pl.DataFrame) -> None:
    """Refuses a predictions table (its ``det`` rows, ``_row`` = the row in the file) with a box or score that is
    null or not a finite number: a NaN box was dropped and a NaN score ranked anyhow, each without a word."""

    def first(mask: pl.Series) -> str:
        return f"row {int(df['_row'].filter(mask)[0])}"

    for c in (*BOX_COLUMNS, "score"):
        nulls = df[c].is_null()
        if nulls.any():
            raise InputError(
                f"{shown}: column {c} has {int(nulls.sum())} null value(s) (first: {first(nulls)}); "
                "every det row needs one"
            )
    for c in (*BOX_COLUMNS, "score"):
        col = df[c]
        if not col.dtype.is_numeric():
            unit = "" if c == "score" else " (metres, radians)"
            raise InputError(f"{shown}: column {c} must hold finite numbers{unit}, not {col.dtype}")
        bad = pl.Series(~np.isfinite(col.to_numpy().astype(np.float64)))
        if bad.any():
            raise InputError(
                f"{shown}: column {c} must hold finite numbers; {first(bad)} has {float(col.filter(bad)[0])!r}"
            )
    for c in ("l", "w", "h"):  # a negative size was scored without a word
        col = df[c]
        bad = pl.Series(col.to_numpy().astype(np.float64) < 0)
        if bad.any():
            raise InputError(
                f"{shown}: column {c} must hold box sizes in metres, not negative; {first(bad)} has "
                f"{float(col.filter(bad)[0])!r}"
            )


def check_prediction_coverage(
    path: str | Path,
    predictions: Predictions,
    *,
    modes: Sequence[str],
    settings: Sequence[Setting],
) -> None:
    """Refuses predictions that cover no frame of a (setting, mode) the study scores (no ``det`` row, nor a
    ``frame`` or ``gt`` row saying it was covered): Table III's boxes (setting ``clean`` only) scored as Table IV
    gave AP 0 for every delay and noise setting, as if measured. A covered (setting, mode) without a detection is a
    model that found nothing: AP 0, as a learned model is scored. The message names ``path``, ``modes`` and
    ``settings`` as their user gave them (:func:`mmusv.text.given`; ``--predictions``, ``--modes`` and
    ``--settings`` from ``mmusv study``)."""
    held = {(k[4], k[3]) for k in predictions}
    wanted = [(s.name, m) for s in settings for m in modes if m != "none" or s.name == "clean"]
    missing = [w for w in wanted if w not in held]
    if not missing:
        return

    def listed(pairs: Sequence[tuple[str, str]]) -> str:
        by: dict[str, list[str]] = {}
        for setting, mode in pairs:
            by.setdefault(setting, []).append(mode)
        return "; ".join(f"setting {setting} (modes {', '.join(m)})" for setting, m in by.items())

    holds = (
        f"the file covers {listed(sorted(held))}"
        if held
        else "the file holds no detection and covers no frame (no row of kind det, frame or gt; a file of a model "
        "that found nothing needs a row of kind frame for each (sequence, frame, ego, mode) it covers, as "
        "mmusv.learn.replay writes)"
    )
    raise InputError(
        f"{given('path', path)}: no row of {listed(missing)}; {holds}. Give the detections of every setting "
        f"({named('settings')}) and mode ({named('modes')}) scored, or leave those out"
    )
