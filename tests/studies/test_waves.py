"""The wave study (Table I): monotonic, linear in H, deterministic."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import polars as pl
from mmusv.config import load_scenario
from mmusv.studies.waves import run_wave_study

ROOT = Path(__file__).resolve().parents[2]


def test_wave_study_on_bundled_scenario(tmp_path: Path) -> None:
    s = load_scenario(ROOT / "scenarios" / "island_port_waves.yaml")
    s = s.model_copy(update={"acquisition": s.acquisition.model_copy(update={"frames": 300})})
    study = run_wave_study(s)
    t = study.table
    assert t["wave"].to_list() == ["W0", "W1", "W2", "W3"]
    for col in ("heave_rms_m", "roll_rms_deg", "pitch_rms_deg"):
        values = t[col].to_numpy()
        assert np.all(np.diff(values) > 0), col
        assert study.r2[col] >= 0.99
    # Same seed, same numbers.
    assert run_wave_study(s).table.equals(t)
    # Magnitudes in the range of the paper's Table I for USV-sized vessels.
    assert 0.005 < t["heave_rms_m"][0] < 0.06 and 0.05 < t["roll_rms_deg"][0] < 0.5
    paths = study.write(tmp_path)
    assert pl.read_csv(paths["csv"]).shape == (4, 7)
    assert paths["png"].stat().st_size > 10_000
