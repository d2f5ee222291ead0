"""A scenario recorded in parts (``--split-frames``) is checked as the whole run is: every part's route checks
cover the whole run's frames, so a close pass is warned once, as a whole run warns it. Each part checked the
routes up to its own last frame: the pass of ``u`` and ``t`` below was warned twice, 10.3 m apart at t = 3.8 s
(the second part's frames) and 4.0 m at t = 5.8 s (the whole run's closest)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import mmusv
import pytest
from mmusv.batch import run_many
from mmusv.errors import ConfigError
from mmusv.scenario_checks import MmusvWarning

from .conftest import write


def close_pass() -> dict[str, Any]:
    """30 frames at 5 Hz: the fishing boat crosses 12 m ahead of the WAM-V's start, closest at t = 5.8 s."""
    return {
        "name": "closepass",
        "seed": 1,
        "map": {"type": "open_sea", "seed": 0},
        "acquisition": {"frequency_hz": 5, "frames": 30},
        "rigs": {"r": {"preset": "lidar_only", "lidar": {"channels": 8, "points_per_second": 20480}}},
        "vessels": [
            {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": [[0, 0], [60, 0]]},
            {"id": "t", "asset": "fishing_boat_12m", "speed_mps": 3, "route": [[12, -30], [12, 30]]},
        ],
    }


def test_a_split_run_warns_a_close_pass_once_as_the_whole_run_does(tmp_path: Path) -> None:
    src = tmp_path / "src"
    src.mkdir()
    file = write(src / "closepass.yaml", close_pass())
    with pytest.warns(MmusvWarning) as caught:
        mmusv.run(file, out_dir=tmp_path / "whole")
    whole = sorted(str(w.message) for w in caught if "separation" in str(w.message))
    assert len(whole) == 1 and "4.0 m apart" in whole[0], whole
    report = run_many(src, out_dir=tmp_path / "split", split_frames=10)
    assert report.ok and report.outcomes[0].parts == 3
    assert [w for w in report.outcomes[0].warnings if "separation" in w] == whole


def test_check_frames_is_checked(tmp_path: Path) -> None:
    file = write(tmp_path / "closepass.yaml", close_pass())
    with pytest.raises(ConfigError, match=r"check_frames = 5: must be in 10\.\.30"):
        mmusv.run(file, out_dir=tmp_path / "a", frame_range=(0, 10), check_frames=5)
    with pytest.raises(ConfigError, match=r"check_frames = 31: must be in 10\.\.30"):
        mmusv.run(file, out_dir=tmp_path / "b", frame_range=(0, 10), check_frames=31)
    # A part of the first 10 frames checked as far as the whole run: the closest pass (t = 5.8 s, frame 29).
    with pytest.warns(MmusvWarning, match=r"4\.0 m apart \(hulls\) at t=5\.8 s"):
        mmusv.run(file, out_dir=tmp_path / "c", frame_range=(0, 10), check_frames=30)
