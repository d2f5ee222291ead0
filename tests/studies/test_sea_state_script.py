"""scripts/sea_state_detection.py (the side-by-side table of docs/studies/detection.md, *Sea state*): its rows and
changes against values worked out here, and its picture."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path
from types import ModuleType

import polars as pl
import pytest
from mmusv.studies.detection.report import BINS

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "sea_state_detection.py"


@pytest.fixture(scope="module")
def script() -> ModuleType:
    spec = importlib.util.spec_from_file_location("sea_state_detection", SCRIPT)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def table(scale: float, wave_hidden: float) -> pl.DataFrame:
    cols = ["ap50", "ap70", *(f"ap50_{b}" for b in BINS), "recall50_visible", "recall50_hidden"]
    rows = []
    for k, mode in enumerate(("none", "late")):
        r = {c: scale * (0.1 + 0.05 * j + 0.2 * k) for j, c in enumerate(cols)}
        r["recall50_wave_hidden"] = wave_hidden
        rows.append({"mode": mode, **r, "gt_wave_hidden": 7.0, "gt": 100.0})
    return pl.DataFrame(rows)


def test_rows_and_changes(script: ModuleType) -> None:
    a, b = table(1.0, 0.0), table(0.8, math.nan)
    md = script.markdown([a, b], ["W1", "W3"]).splitlines()
    assert md[0].startswith("| mode | sea | AP@0.5 | AP@0.7 |") and md[0].endswith("| wave-hidden / all gt |")
    assert len(md) == 2 + 2 * 3  # header, rule, then each mode at each sea and its change
    none_w1, none_w3, none_change = (row.split(" | ") for row in md[2:5])
    assert none_w1[1] == "W1" and none_w3[1] == "W3" and none_change[1] == "W1 → W3"
    assert none_w1[2] == f"{0.1:.3f}" and none_w3[2] == f"{0.08:.3f}"
    assert none_change[2] == f"{100 * (0.08 / 0.1 - 1):+.0f} %" == "-20 %"
    # wave-hidden recall: 0 at W1 gives no ratio, NaN at W3 shows as a dash
    i = 2 + 2 + len(BINS) + 2
    assert none_w3[i] == "–" and none_change[i] == "–"
    assert none_w1[-1].rstrip(" |") == "7 / 100"


def test_picture(script: ModuleType, tmp_path: Path) -> None:
    out = tmp_path / "ap.png"
    script.plot([table(1.0, 0.1), table(0.8, 0.1)], ["W1", "W3"], out, "test")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
