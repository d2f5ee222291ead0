"""The wave study (Table I of the paper): heave, roll and pitch RMS of the USVs under W0..W3.

A controlled scenario, routes and sensors fixed, only the wave setting varied. Heave RMS is taken after removing
each USV's mean height over the sequence; roll and pitch RMS are in degrees; all statistics pool every USV and
every acquisition frame. A straight-line fit of each statistic against H gives R².
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import polars as pl

from mmusv.config import Scenario
from mmusv.motion import scenario_poses
from mmusv.world.environment import WAVE_PRESETS, wave_height_m

__all__ = ["WaveStudy", "run_wave_study"]


@dataclass(frozen=True)
class WaveStudy:
    """Result: ``table`` (one row per wave setting: wave, H_m, heave_rms_m, roll_rms_deg, pitch_rms_deg, usvs,
    frames) and ``r2`` (R² of a linear fit against H per statistic)."""

    table: pl.DataFrame
    r2: dict[str, float]

    def write(self, out_dir: Path) -> dict[str, Path]:
        """Writes ``wave_study.csv`` and ``wave_study.png`` into ``out_dir`` (created); returns their paths."""
        out_dir.mkdir(parents=True, exist_ok=True)
        csv = out_dir / "wave_study.csv"
        self.table.write_csv(csv)
        png = out_dir / "wave_study.png"
        _plot(self, png)
        return {"csv": csv, "png": png}


def _rms_stats(poses: np.ndarray) -> tuple[float, float, float]:
    """RMS of heave (mean per vessel removed), roll and pitch (degrees) over ``(T, V, 6)`` poses."""
    z = poses[:, :, 2]
    heave = z - z.mean(axis=0, keepdims=True)
    roll = np.degrees(poses[:, :, 3])
    pitch = np.degrees(poses[:, :, 4])
    return _rms(heave), _rms(roll), _rms(pitch)


def _rms(a: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(a))))


def _r2(x: np.ndarray, y: np.ndarray) -> float:
    slope, intercept = np.polyfit(x, y, 1)
    resid = y - (slope * x + intercept)
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    return 1.0 - float(np.sum(resid**2)) / ss_tot if ss_tot > 0 else 1.0


def run_wave_study(scenario: Scenario, *, waves: tuple[str | float, ...] = tuple(WAVE_PRESETS)) -> WaveStudy:
    """Runs the study on ``scenario``'s USVs for each wave setting (names ``W0``.. or heights in metres)."""
    usv_idx = [i for i, v in enumerate(scenario.vessels) if v.role == "usv"]
    if not usv_idx:
        from mmusv.errors import ConfigError

        raise ConfigError("invalid config vessels: the wave study needs at least one vessel with role: usv")
    rows = []
    for w in waves:
        poses = scenario_poses(scenario, wave=w)[:, usv_idx, :]
        heave, roll, pitch = _rms_stats(poses)
        rows.append(
            {
                "wave": w if isinstance(w, str) else f"H={w:g}",
                "H_m": wave_height_m(w),
                "heave_rms_m": heave,
                "roll_rms_deg": roll,
                "pitch_rms_deg": pitch,
                "usvs": len(usv_idx),
                "frames": poses.shape[0],
            }
        )
    table = pl.DataFrame(rows)
    h = table["H_m"].to_numpy()
    r2 = {k: _r2(h, table[k].to_numpy()) for k in ("heave_rms_m", "roll_rms_deg", "pitch_rms_deg")}
    return WaveStudy(table, r2)


def _plot(study: WaveStudy, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = study.table
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.2), constrained_layout=True)
    for ax, (col, label) in zip(
        axes,
        [("heave_rms_m", "heave RMS (m)"), ("roll_rms_deg", "roll RMS (°)"), ("pitch_rms_deg", "pitch RMS (°)")],
        strict=False,
    ):
        ax.plot(t["H_m"], t[col], "o-")
        for name, x, y in zip(t["wave"], t["H_m"], t[col], strict=False):
            ax.annotate(str(name), (x, y), textcoords="offset points", xytext=(4, -10), fontsize=8)
        ax.set_xlabel("wave height H (m)")
        ax.set_ylabel(label)
        ax.set_title(f"R² = {study.r2[col]:.4f}", fontsize=9)
        ax.grid(alpha=0.3)
    fig.suptitle("mmusv wave study: USV pose perturbation vs wave setting")
    fig.savefig(path, dpi=110)
    plt.close(fig)
