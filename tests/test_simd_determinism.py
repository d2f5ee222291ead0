"""The same bytes on any x86-64: the core picks its AVX2 + FMA code paths at run time where the CPU has them and
the portable ones elsewhere (``MMUSV_SIMD=portable`` forces them; ``crates/mmusv-core/src/simd.rs``), and a
recording must not depend on which ran. The core's own tests check the ray casts at both levels; this one checks
a whole recording: every sensor (LiDAR, radar with its PPI, a camera at ``standard`` quality with its glossy
reflections and anti-aliasing, a top view) over the physical sea at W2, with a wake, made twice in fresh
processes, once per level."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from tiny_scenario import lidar_scenario

_RUN = """
import json, sys
from mmusv.acquire import run
from mmusv._native import core
res = run(json.loads(sys.argv[1]), out_dir=sys.argv[2])
print(core.simd_level(), res.recording)
"""


def _scenario() -> dict[str, Any]:
    sc = lidar_scenario("simd_levels", frames=2)
    sc["environment"] = {"motion": "physical", "wave": "W2", "time_of_day": "10:00"}
    sc["rigs"]["r"] = {
        "lidar": {"channels": 8, "points_per_second": 20480},
        "radar": {"azimuth_bins": 90, "rays_el": 4, "range_m": 400, "ppi_size_px": 32},
        "cameras": [
            {"name": "front", "resolution": [96, 64], "quality": "standard", "mount": {"point": "camera_front"}}
        ],
        "top_view": {"resolution": [48, 48], "quality": "standard"},
    }
    sc["vessels"][1]["speed_mps"] = 8.0  # a wake behind the target, in the camera's view
    return sc


def _record(tmp: Path, level: str | None) -> tuple[str, str]:
    """The level the core ran at and the recording's SHA-256, made in a fresh process with ``MMUSV_SIMD`` set to
    ``level`` (``None``: unset)."""
    env = {k: v for k, v in os.environ.items() if k != "MMUSV_SIMD"}
    if level is not None:
        env["MMUSV_SIMD"] = level
    out = tmp / (level or "detected")
    done = subprocess.run(
        [sys.executable, "-c", _RUN, json.dumps(_scenario()), str(out)],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    ran, path = done.stdout.split()
    return ran, hashlib.sha256(Path(path).read_bytes()).hexdigest()


def test_a_recording_is_the_same_bytes_on_the_avx2_and_the_portable_paths(tmp_path: Path) -> None:
    from mmusv._native import core

    if core.simd_level() != "avx2":
        pytest.skip("this CPU runs the portable paths only")
    detected, portable = _record(tmp_path, None), _record(tmp_path, "portable")
    assert (detected[0], portable[0]) == ("avx2", "portable")  # each process ran the level it was given
    assert detected[1] == portable[1]
