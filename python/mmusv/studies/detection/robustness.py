"""Settings of the robustness study (Table IV): what the ego receives from its neighbours.

- ``clean``: the neighbours' current points and poses.
- ``delay:k``: each non-ego USV's points *and* pose from ``k`` frames earlier (``k / f`` seconds: 200–600 ms at
  5 Hz for k = 1..3), the frame whose acquisition index is ``k`` less (not the ``k``-th frame read before: a
  recording with missing frames has none there); the ego and the ground truth stay current.
- ``noise:σ_xyz/σ_rpy``: zero-mean Gaussian noise, σ_xyz metres on each of x, y, z and σ_rpy degrees on each of
  roll, pitch, yaw, added to every non-ego USV's body pose (so to its LiDAR pose). The draws are seeded by
  (seed, sequence, frame, ego, neighbour, setting): late and early fusion see the same draws.
"""

from __future__ import annotations

import zlib
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from mmusv.config import MAX_COORDINATE_M
from mmusv.errors import InputError
from mmusv.frames import matrix_to_pose, pose_matrices
from mmusv.studies.detection.data import AgentFrame, SequenceData
from mmusv.text import counted

__all__ = ["DEFAULT_SETTINGS", "MAX_SIGMA_RPY_DEG", "MAX_SIGMA_XYZ_M", "Setting", "neighbours_for", "parse_settings"]

MAX_SIGMA_XYZ_M = MAX_COORDINATE_M
"""The largest position noise σ (metres): the extent of a scenario's world (σ = 1e308 overflowed the pose)."""
MAX_SIGMA_RPY_DEG = 360.0
"""The largest attitude noise σ (degrees): a full turn."""


def _num(x: float) -> str:
    """``x`` as ``%g`` writes it where that reads back as ``x`` (``0.5``, ``1``), else in full (``1.0000001``): two
    settings that differ never share a name (the key of their results and of their noise draws)."""
    short = f"{x:g}"
    return short if float(short) == x else repr(float(x))


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
            return f"noise:{_num(self.sigma_xyz_m)}/{_num(self.sigma_rpy_deg)}"
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
    """Settings from ``"clean,delay:1,delay:2,noise:0.5/0.5"`` (or a list of such items; ``noise:S`` is
    ``noise:S/S``); ``clean`` first, then the delays by ``K``, then the noises by their σs, each setting once (the
    study's tables follow this order, whatever the order given)."""
    from mmusv.text import given

    items = [s.strip() for s in (text.split(",") if isinstance(text, str) else text) if s.strip()]
    if not items:  # "" ran the clean setting alone, a robustness study of nothing
        raise InputError(f"{given('text', text)}: empty; give clean, delay:K or noise:SIGMA_XYZ_M/SIGMA_RPY_DEG items")
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
                if not (0 <= sx <= MAX_SIGMA_XYZ_M and 0 <= sr <= MAX_SIGMA_RPY_DEG) or (sx == 0 and sr == 0):
                    raise ValueError
                st = Setting(sigma_xyz_m=sx, sigma_rpy_deg=sr)
            else:
                raise ValueError
        except ValueError:
            raise InputError(
                f"{given('text', text)}: item {it!r}: expected clean, delay:K (K ≥ 1 frames) or "
                f"noise:SIGMA_XYZ_M/SIGMA_RPY_DEG (0 ≤ SIGMA_XYZ_M ≤ {MAX_SIGMA_XYZ_M:g} m, 0 ≤ SIGMA_RPY_DEG ≤ "
                f"{MAX_SIGMA_RPY_DEG:g}°, not both 0)"
            ) from None
        if st not in out:
            out.append(st)
    order = {"clean": 0, "delay": 1, "noise": 2}
    return tuple(sorted(out, key=lambda st: (order[st.kind], st.delay_frames, st.sigma_xyz_m, st.sigma_rpy_deg)))


def _seed_words(seed: int, seq: str, frame: int, ego: str, nb: str, setting: Setting) -> list[int]:
    words = [
        seed & 0xFFFFFFFF,
        zlib.crc32(seq.encode()),
        frame,
        zlib.crc32(ego.encode()),
        zlib.crc32(nb.encode()),
        zlib.crc32(setting.name.encode()),
    ]
    if not 0 <= seed <= 0xFFFFFFFF:  # the sign and the rest of the seed: 2**32 drew seed 0's noise, -1 2**32 - 1's
        words.append(int(seed < 0))
        high = abs(seed) >> 32
        while high:
            words.append(high & 0xFFFFFFFF)
            high >>= 32
    return words


def neighbours_for(seq: SequenceData, index: int, ego_id: str, setting: Setting, *, seed: int) -> list[AgentFrame]:
    """The non-ego USVs of ``seq.frames[index]`` as ``ego_id`` receives them under ``setting``. With a delay of
    ``k`` frames, the sequence must hold the frame of acquisition index ``seq.frames[index].frame - k``."""
    now = seq.frames[index]
    past = seq.frame_at(now.frame - setting.delay_frames)
    if past is None:
        raise InputError(
            f"sequence {seq.name}: frame {now.frame} has no data {counted(setting.delay_frames, 'frame')} earlier "
            f"(frame {now.frame - setting.delay_frames} is not in the sequence)"
        )
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
