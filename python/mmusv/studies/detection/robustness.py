"""Settings of the robustness study (Table IV): what the ego receives from its neighbours.

- ``clean``: the neighbours' current points and poses.
- ``delay:k``: each non-ego USV's points *and* pose from ``k`` frames earlier (``k / f`` seconds: 200–600 ms at
  5 Hz for k = 1..3); the ego and the ground truth stay current.
- ``noise:σ_xyz/σ_rpy``: zero-mean Gaussian noise, σ_xyz metres on each of x, y, z and σ_rpy degrees on each of
  roll, pitch, yaw, added to every non-ego USV's body pose (so to its LiDAR pose). The draws are seeded by
  (seed, sequence, frame, ego, neighbour, setting): late and early fusion see the same draws.
"""

from __future__ import annotations

import zlib
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from mmusv.errors import InputError
from mmusv.frames import matrix_to_pose, pose_matrices
from mmusv.studies.detection.data import AgentFrame, SequenceData

__all__ = ["DEFAULT_SETTINGS", "Setting", "neighbours_for", "parse_settings"]


@dataclass(frozen=True)
class Setting:
    """One robustness setting: ``delay_frames`` ≥ 0 and noise ``sigma_xyz_m``, ``sigma_rpy_deg`` ≥ 0."""

    delay_frames: int = 0
    sigma_xyz_m: float = 0.0
    sigma_rpy_deg: float = 0.0

    @property
    def name(self) -> str:
        """``clean``, ``delay:k`` or ``noise:σxyz/σrpy``."""
        if self.delay_frames:
            return f"delay:{self.delay_frames}"
        if self.sigma_xyz_m or self.sigma_rpy_deg:
            return f"noise:{self.sigma_xyz_m:g}/{self.sigma_rpy_deg:g}"
        return "clean"

    @property
    def kind(self) -> str:
        """``clean``, ``delay`` or ``noise``."""
        return self.name.split(":")[0]


DEFAULT_SETTINGS = (
    Setting(),
    Setting(delay_frames=1),
    Setting(delay_frames=2),
    Setting(delay_frames=3),
    Setting(sigma_xyz_m=0.5, sigma_rpy_deg=0.5),
    Setting(sigma_xyz_m=1.0, sigma_rpy_deg=1.0),
    Setting(sigma_xyz_m=2.0, sigma_rpy_deg=2.0),
)


def parse_settings(text: str | Sequence[str]) -> tuple[Setting, ...]:
    """Settings from ``"clean,delay:1,delay:2,noise:0.5/0.5"`` (or a list of such items); ``clean`` is always
    included first."""
    items = [s.strip() for s in (text.split(",") if isinstance(text, str) else text) if s.strip()]
    if not items:  # "" ran the clean setting alone, a robustness study of nothing
        raise InputError("--settings is empty: give clean, delay:K or noise:SIGMA_XYZ_M/SIGMA_RPY_DEG items")
    out: list[Setting] = [Setting()]
    for it in items:
        kind, _, val = it.partition(":")
        try:
            if kind == "clean" and not val:
                continue
            if kind == "delay":
                k = int(val)
                if k < 1:
                    raise ValueError
                st = Setting(delay_frames=k)
            elif kind == "noise":
                a, _, b = val.partition("/")
                sx, sr = float(a), float(b if b else a)
                if not (sx >= 0 and sr >= 0) or (sx == 0 and sr == 0) or not np.isfinite([sx, sr]).all():
                    raise ValueError
                st = Setting(sigma_xyz_m=sx, sigma_rpy_deg=sr)
            else:
                raise ValueError
        except ValueError:
            raise InputError(
                f"--settings item {it!r}: expected clean, delay:K (K ≥ 1 frames) or "
                "noise:SIGMA_XYZ_M/SIGMA_RPY_DEG (non-negative, not both 0)"
            ) from None
        if st not in out:
            out.append(st)
    return tuple(out)


def _seed_words(seed: int, seq: str, frame: int, ego: str, nb: str, setting: Setting) -> list[int]:
    return [
        seed & 0xFFFFFFFF,
        zlib.crc32(seq.encode()),
        frame,
        zlib.crc32(ego.encode()),
        zlib.crc32(nb.encode()),
        zlib.crc32(setting.name.encode()),
    ]


def neighbours_for(seq: SequenceData, index: int, ego_id: str, setting: Setting, *, seed: int) -> list[AgentFrame]:
    """The non-ego USVs of ``seq.frames[index]`` as ``ego_id`` receives them under ``setting``. ``index`` must be
    ≥ ``setting.delay_frames``."""
    if index < setting.delay_frames:
        raise InputError(f"frame index {index} has no data {setting.delay_frames} frames earlier")
    now = seq.frames[index]
    past = seq.frames[index - setting.delay_frames]
    by_id = {a.id: a for a in past.agents}
    out: list[AgentFrame] = []
    for a in now.agents:
        if a.id == ego_id or a.id not in by_id:
            continue
        nb = by_id[a.id]
        if setting.sigma_xyz_m or setting.sigma_rpy_deg:
            rng = np.random.default_rng(_seed_words(seed, seq.name, now.frame, ego_id, a.id, setting))
            noise = np.concatenate(
                [rng.normal(0.0, setting.sigma_xyz_m, 3), np.radians(rng.normal(0.0, setting.sigma_rpy_deg, 3))]
            )
            nb = replace(nb, body=pose_matrices(matrix_to_pose(nb.body) + noise))
        out.append(nb)
    return out
