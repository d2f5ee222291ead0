"""The wave study (Table I of the paper): heave, roll and pitch RMS of the USVs under W0..W3.

A controlled scenario, routes and sensors fixed, only the wave setting varied. Heave RMS is taken after removing
each USV's mean height over the sequence; roll and pitch RMS are in degrees; all statistics pool every USV and
every acquisition frame. A straight-line fit of each statistic against H gives R².

``motion="paper"`` (the default) moves the vessels by the paper's formula, whose amplitudes are fitted to Table I
for a USV of the reference size (a 5 × 2.5 × 1.5 m box, ``α_v = 1``): on the bundled ``island_port_waves``, whose
USVs are three 4.88 m WAM-Vs and a 12 m patrol boat (``α_v`` 0.85 and 0.42), every statistic is 0.76–0.77 times
Table I's, the shape (monotonic, linear in H) the paper's (``docs/sea.md``, *mmusv study waves against Table I*);
``usvs="reference"`` (``--usvs reference``) moves them as USVs of the reference size on the same routes, which gives
Table I itself. With
``motion="physical"`` every vessel responds to the fully developed sea of each setting (Hs = H, Pierson–Moskowitz
Tp; :mod:`mmusv.world.sea_state`) through its hull's RAOs; :func:`run_physical_wave_study` then reports, beside
the paper's Table I (:data:`PAPER_TABLE_I`) and the paper mode, the RMS of the USVs and of every vessel of the
mixed fleet, one row per vessel and sea state.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
import polars as pl

from mmusv import arguments
from mmusv.config import AcquisitionConfig, Scenario
from mmusv.errors import ConfigError
from mmusv.forking import check_polars
from mmusv.held_signals import raise_noted_stop
from mmusv.jsonio import write_files_atomic
from mmusv.motion import scenario_poses
from mmusv.world.environment import WAVE_PRESETS, wave_height_m

__all__ = [
    "PAPER_FILES",
    "PAPER_TABLE_I",
    "PHYSICAL_FILES",
    "USV_SIZES",
    "PhysicalWaveStudy",
    "WaveStudy",
    "check_scenario",
    "run_physical_wave_study",
    "run_wave_study",
]

PAPER_TABLE_I: dict[str, tuple[float, float, float]] = {
    "W0": (0.0274, 0.2054, 0.0684),
    "W1": (0.0818, 0.6134, 0.2062),
    "W2": (0.1379, 1.0345, 0.3395),
    "W3": (0.1923, 1.4421, 0.4774),
}
"""The paper's Table I: (heave RMS m, roll RMS °, pitch RMS °) of its USVs under W0..W3."""

PAPER_FILES = ("wave_study.csv", "wave_study.png")
"""The files :meth:`WaveStudy.write` writes (the table, the plot)."""
PHYSICAL_FILES = ("wave_study_physical.csv", "wave_study_vessels.csv")
"""The files :meth:`PhysicalWaveStudy.write` writes (the summary, per vessel)."""

USV_SIZES = ("scenario", "reference")
""":func:`run_wave_study`'s ``usvs``: the scenario's USVs at their assets' sizes, or at the paper's reference size."""


@dataclass(frozen=True)
class WaveStudy:
    """Result: ``table`` (one row per wave setting: wave, H_m, heave_rms_m, roll_rms_deg, pitch_rms_deg, usvs,
    usv_size (``scenario``: the USVs at their assets' sizes; ``reference``: at the paper's reference size, 5 × 2.5 ×
    1.5 m), frames) and ``r2`` (R² of a linear fit against H per statistic; NaN with fewer than 3 settings)."""

    table: pl.DataFrame
    r2: dict[str, float]

    def write(self, out_dir: Path) -> dict[str, Path]:
        """Writes ``wave_study.csv`` and ``wave_study.png`` into ``out_dir`` (created) with
        :func:`~mmusv.jsonio.write_files_atomic`; returns their paths."""
        paths = {key: out_dir / name for key, name in zip(("csv", "png"), PAPER_FILES, strict=True)}
        png = io.BytesIO()
        _plot(self, png)
        write_files_atomic({paths["csv"]: self.table.write_csv().encode("utf-8"), paths["png"]: png.getvalue()})
        return paths


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
    """R² of a straight-line fit of ``y`` against ``x``; NaN with fewer than 3 distinct ``x`` (one setting was
    numpy's RankWarning, two a line through both points, R² = 1 whatever the data)."""
    if np.unique(x).size < 3:
        return float("nan")
    slope, intercept = np.polyfit(x, y, 1)
    resid = y - (slope * x + intercept)
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    return 1.0 - float(np.sum(resid**2)) / ss_tot if ss_tot > 0 else 1.0


def check_scenario(scenario: Scenario, *, record_s: float | None = None) -> list[int]:
    """The indices of ``scenario``'s USVs; :class:`~mmusv.errors.ConfigError` naming the scenario when it has none,
    or when the study would record fewer than 2 frames (the scenario's, or ``record_s`` seconds when longer, as
    :func:`run_physical_wave_study`): heave about each USV's mean over one frame is 0 at every wave setting, and a
    one-frame scenario gave a table of zeros with R² = 1. The studies' checks, for a caller to make before it
    prepares anything."""
    usv_idx = [i for i, v in enumerate(scenario.vessels) if v.role == "usv"]
    if not usv_idx:
        raise ConfigError(
            f"invalid config vessels: scenario {scenario.name!r}: the wave study needs at least one vessel with "
            "role: usv"
        )
    frames = _record_frames(scenario.acquisition, record_s)
    if frames < 2:
        raise ConfigError(
            f"acquisition.frames = {frames}: scenario {scenario.name!r}: the wave study needs at least 2 frames "
            "(heave is taken about each USV's mean over the sequence); give more frames (--frames N)"
        )
    return usv_idx


def _record_frames(acq: AcquisitionConfig, record_s: float | None) -> int:
    """The frames a study records: the scenario's, or ``record_s`` seconds at its frequency when longer."""
    if record_s is not None and record_s * acq.frequency_hz > acq.frames:
        return round(record_s * acq.frequency_hz)
    return acq.frames


def run_wave_study(
    scenario: Scenario,
    *,
    waves: tuple[str | float, ...] = tuple(WAVE_PRESETS),
    motion: Literal["paper", "physical"] = "paper",
    usvs: Literal["scenario", "reference"] = "scenario",
) -> WaveStudy:
    """Runs the study on ``scenario``'s USVs for each wave setting (names ``W0``.. or heights in metres), with the
    paper's motion formula (default) or the physical response to the fully developed sea of each setting.
    ``usvs="reference"`` (paper motion only) moves every USV as the paper's reference USV (5 × 2.5 × 1.5 m,
    ``α_v = 1``: :func:`~mmusv.motion.build_fleet`'s ``reference_usvs``) on its own route: Table I itself."""
    check_polars("mmusv study waves")
    if usvs not in USV_SIZES:
        raise ConfigError(f"usvs = {arguments.shown(usvs)}: must be one of {', '.join(USV_SIZES)}")
    if usvs == "reference" and motion != "paper":
        raise ConfigError(
            f"usvs = 'reference' with motion = {arguments.shown(motion)}: the reference USV is a size of the "
            "paper's formula (motion: paper); the physical response reads each hull's own particulars"
        )
    usv_idx = check_scenario(scenario)
    scenario = scenario.with_sea(None, motion=motion)
    rows = []
    for w in waves:
        raise_noted_stop()  # a stop whose KeyboardInterrupt a library swallowed (held_signals)
        poses = scenario_poses(scenario, wave=w, reference_usvs=usvs == "reference")[:, usv_idx, :]
        heave, roll, pitch = _rms_stats(poses)
        rows.append(
            {
                "wave": w if isinstance(w, str) else f"H={w:g}",
                "H_m": wave_height_m(w),
                "heave_rms_m": heave,
                "roll_rms_deg": roll,
                "pitch_rms_deg": pitch,
                "usvs": len(usv_idx),
                "usv_size": usvs,
                "frames": poses.shape[0],
            }
        )
    table = pl.DataFrame(rows)
    h = table["H_m"].to_numpy()
    r2 = {k: _r2(h, table[k].to_numpy()) for k in ("heave_rms_m", "roll_rms_deg", "pitch_rms_deg")}
    return WaveStudy(table, r2)


@dataclass(frozen=True)
class PhysicalWaveStudy:
    """Result of :func:`run_physical_wave_study`: ``summary`` (one row per setting: wave, Hs_m, Tp_s, the paper's
    Table I, the paper mode and the physical mode for the USVs, and the physical mode pooled over the whole fleet)
    and ``vessels`` (one row per setting and vessel: wave, id, asset, role, heave_rms_m, roll_rms_deg,
    pitch_rms_deg), sorted by setting then vessel order."""

    summary: pl.DataFrame
    vessels: pl.DataFrame

    def monotonic(self) -> dict[str, bool]:
        """Per vessel id: whether heave, roll and pitch RMS all rise strictly from setting to setting."""
        out = {}
        for vid in self.vessels["id"].unique(maintain_order=True).to_list():
            v = self.vessels.filter(pl.col("id") == vid)
            out[str(vid)] = all(
                bool(np.all(np.diff(v[c].to_numpy()) > 0)) for c in ("heave_rms_m", "roll_rms_deg", "pitch_rms_deg")
            )
        return out

    def write(self, out_dir: Path) -> dict[str, Path]:
        """Writes ``wave_study_physical.csv`` (summary) and ``wave_study_vessels.csv`` into ``out_dir`` (created)
        with :func:`~mmusv.jsonio.write_files_atomic`; returns their paths."""
        paths = {key: out_dir / name for key, name in zip(("summary", "vessels"), PHYSICAL_FILES, strict=True)}
        write_files_atomic(
            {
                paths["summary"]: self.summary.write_csv().encode("utf-8"),
                paths["vessels"]: self.vessels.write_csv().encode("utf-8"),
            }
        )
        return paths


def _per_vessel_rms(poses: np.ndarray) -> np.ndarray:
    """``(V, 3)``: heave (mean removed), roll (°), pitch (°) RMS per vessel of ``(T, V, 6)`` poses."""
    z = poses[:, :, 2] - poses[:, :, 2].mean(axis=0, keepdims=True)
    return np.stack(
        [
            np.sqrt(np.mean(z**2, axis=0)),
            np.sqrt(np.mean(np.degrees(poses[:, :, 3]) ** 2, axis=0)),
            np.sqrt(np.mean(np.degrees(poses[:, :, 4]) ** 2, axis=0)),
        ],
        axis=1,
    )


PHYSICAL_RECORD_S = 1200.0
"""Default record length of the physical study: 20 minutes, the usual length of a seakeeping record, so that the
RMS of waves of 4–10 s periods are estimated to a few per cent (the scenario's own frames are used when longer)."""


def run_physical_wave_study(
    scenario: Scenario,
    *,
    waves: tuple[str, ...] = tuple(WAVE_PRESETS),
    record_s: float | None = PHYSICAL_RECORD_S,
) -> PhysicalWaveStudy:
    """Heave, roll and pitch RMS of every vessel of ``scenario`` (a mixed fleet) under the physical sea of each
    preset in ``waves`` (``W0``..``W3``), beside the paper's Table I and the paper mode (USVs pooled). The record
    lasts ``record_s`` seconds at the scenario's frequency, or the scenario's own frames when longer or when
    ``record_s`` is ``None``."""
    check_polars("mmusv study waves")
    from mmusv.world.sea_state import SEA_PRESETS

    usv_idx = check_scenario(scenario, record_s=record_s)
    acq = scenario.acquisition
    if (frames := _record_frames(acq, record_s)) != acq.frames:
        scenario = scenario.model_copy(update={"acquisition": acq.model_copy(update={"frames": frames})})
    physical = scenario.with_sea(None, motion="physical")
    paper = scenario.with_sea(None, motion="paper")
    rows, vessel_rows = [], []
    for w in waves:
        raise_noted_stop()
        p_phys = scenario_poses(physical, wave=w)
        p_paper = scenario_poses(paper, wave=w)[:, usv_idx, :]
        phys_usv = _rms_stats(p_phys[:, usv_idx, :])
        fleet = _rms_stats(p_phys)
        ref = PAPER_TABLE_I.get(w, (float("nan"),) * 3)
        preset = SEA_PRESETS[w]
        rows.append(
            {
                "wave": w,
                "Hs_m": preset.hs_m,
                "Tp_s": preset.tp_s,
                "frames": p_phys.shape[0],
                **{f"table1_{k}": v for k, v in zip(_COLS, ref, strict=True)},
                **{f"paper_{k}": v for k, v in zip(_COLS, _rms_stats(p_paper), strict=True)},
                **{f"physical_{k}": v for k, v in zip(_COLS, phys_usv, strict=True)},
                **{f"fleet_{k}": v for k, v in zip(_COLS, fleet, strict=True)},
            }
        )
        for v, r in zip(scenario.vessels, _per_vessel_rms(p_phys), strict=True):
            vessel_rows.append(
                {
                    "wave": w,
                    "id": v.id,
                    "asset": v.asset,
                    "role": v.role,
                    "heave_rms_m": float(r[0]),
                    "roll_rms_deg": float(r[1]),
                    "pitch_rms_deg": float(r[2]),
                }
            )
    return PhysicalWaveStudy(pl.DataFrame(rows), pl.DataFrame(vessel_rows))


_COLS = ("heave_rms_m", "roll_rms_deg", "pitch_rms_deg")


def _plot(study: WaveStudy, path: Path | io.BytesIO) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mmusv.studies.plotting import default_style

    with default_style():  # not the user's matplotlibrc or style: the same bytes wherever it is drawn
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
        sized = " (USVs of the paper's reference size)" if t["usv_size"][0] == "reference" else ""
        fig.suptitle(f"mmusv wave study: USV pose perturbation vs wave setting{sized}")
        fig.savefig(path, dpi=110, format="png")
    plt.close(fig)
