"""The native boundary fuzzed for crashes (scripts/fuzz_native.py: every function and method of ``mmusv._core`` and
the Python wrappers that feed it, one adversarial argument at a time, each case in a worker under a memory limit
and a timeout). What it found, each refused now with an ``mmusv.errors`` class naming the argument and what is
allowed, each case run here in a subprocess (4 GiB address space, 60 s), so a regression shows as a failed test
rather than a dead test run:

- ``_core._pinhole_directions(width=10**6, height=10**6)`` and ``_core.uniform_elevations(channels=10**9)``
  allocated what they were asked for: the allocation failed and the process aborted (a Jupyter kernel dies).
- ``Fleet.poses_at_times`` allocated times × vessels × 48 bytes with no bound (64 vessels at 2**20 times: 3 GiB).
- ``_core.Recorder("")`` wrote ``.partial`` into the working directory (and renamed it to "" on finish).
- ``mmusv.sensors.mounts.inside_mesh(rays=10**7)`` aborted the process; negative rays a bare ValueError, a point
  of the wrong shape an IndexError.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

PRELUDE = """
import resource
resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))
import numpy as np
from mmusv import _core
from mmusv.errors import MmusvError
"""


def _run(code: str, cwd: Path | None = None) -> dict[str, str]:
    """Runs ``code`` in a fresh interpreter under the limits; returns what it raised (or ``ok``) or how it died."""
    body = textwrap.indent(textwrap.dedent(code), "    ")
    src = (
        PRELUDE
        + "import json\ntry:\n"
        + body
        + "\n    print(json.dumps({'outcome': 'ok', 'message': ''}))\n"
        + "except Exception as e:\n"
        + "    mm = isinstance(e, MmusvError)\n"
        + "    print(json.dumps({'outcome': type(e).__name__, 'mmusv': mm, 'message': str(e)}))\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT / "python")}
    try:
        p = subprocess.run(
            [sys.executable, "-c", src], capture_output=True, text=True, timeout=60, env=env, cwd=cwd or ROOT
        )
    except subprocess.TimeoutExpired:
        return {"outcome": "timeout", "message": ""}
    if p.returncode != 0:
        return {"outcome": f"died rc={p.returncode}", "message": p.stderr[-2000:]}
    out: dict[str, str] = json.loads(p.stdout.strip().splitlines()[-1])
    return out


def _refused(code: str, cls: str, *words: str, cwd: Path | None = None) -> None:
    r = _run(code, cwd)
    assert r["outcome"] == cls, r
    assert r.get("mmusv"), r
    for w in words:
        assert w in r["message"], r


@pytest.mark.parametrize(
    ("code", "words"),
    [
        ("_core._pinhole_directions(width=10**6, height=10**6, hfov=1.0)", ("resolution", "1..=16384")),
        ("_core._pinhole_directions(width=8, height=2**31, hfov=1.0)", ("resolution", "1..=16384")),
        ("_core.uniform_elevations(channels=10**9, lower=-0.1, upper=0.1)", ("channels", "1..=1024")),
        ("_core.uniform_elevations(channels=2**31, lower=-0.1, upper=0.1)", ("channels", "1..=1024")),
    ],
)
def test_huge_ray_pattern_requests_are_refused_not_aborted(code: str, words: tuple[str, ...]) -> None:
    _refused(code, "ConfigError", *words)


def test_the_largest_allowed_patterns_still_come() -> None:
    r = _run(
        """
        assert _core.uniform_elevations(channels=1024, lower=-0.1, upper=0.1).shape == (1024,)
        assert _core._pinhole_directions(width=16384, height=1, hfov=1.0).shape == (16384, 3)
        """
    )
    assert r["outcome"] == "ok", r


def test_poses_at_times_refuses_more_poses_than_allowed() -> None:
    fleet = """
        route = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 50.0]])
        n = 64
        f = _core.Fleet(routes=[route] * n, end_behaviours=['loop'] * n, speeds=np.ones(n), start_offsets=np.zeros(n),
                        z_base=np.zeros(n), dims=np.tile([10.0, 3.0, 2.0], (n, 1)), amplitudes=np.zeros((n, 3)), seed=0,
                        wave='W1')
        assert f.poses_at_times(np.arange(3.0)).shape == (3, 64, 6)
    """
    _refused(fleet + "    f.poses_at_times(np.zeros(2**20 + 1))", "InputError", "times", "67108864")


def test_an_empty_recording_path_is_refused_and_nothing_written(tmp_path: Path) -> None:
    _refused("_core.Recorder('', overwrite=True)", "InputError", "path", "empty", cwd=tmp_path)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("args", "words"),
    [
        ("rays=10**7", ("rays", "1..1024")),
        ("rays=-1", ("rays", "1..1024")),
        ("rays=0", ("rays", "1..1024")),
        ("rays=2.5", ("rays", "1..1024")),
    ],
)
def test_inside_mesh_checks_its_ray_count(args: str, words: tuple[str, ...]) -> None:
    code = f"""
        from mmusv.sensors.mounts import inside_mesh
        v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
        f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],
                      [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
        assert inside_mesh(v, f, point=np.zeros(3)) and not inside_mesh(v, f, point=np.array([5.0, 0.0, 0.0]))
        inside_mesh(v, f, point=np.zeros(3), {args})
    """
    _refused(code, "InputError", *words)


@pytest.mark.parametrize("point", ["np.zeros((0, 0))", "np.zeros(2)", "[float('nan')] * 3", "'abc'"])
def test_inside_mesh_checks_its_point(point: str) -> None:
    code = f"""
        from mmusv.sensors.mounts import inside_mesh
        inside_mesh(np.zeros((3, 3)), np.array([[0, 1, 2]]), point={point})
    """
    _refused(code, "InputError", "point")


def test_the_harness_finds_no_crash_in_the_ray_pattern_helpers(tmp_path: Path) -> None:
    """The harness itself, on a small slice: every case of these helpers ends with a Python exception or a result,
    never a dead worker, a hang or an allocation past the limit."""
    out = tmp_path / "fuzz.jsonl"
    env = {**os.environ, "PYTHONPATH": str(ROOT / "python")}
    for only in ("_core.uniform_elevations(", "_core._pinhole_directions("):
        p = subprocess.run(
            [sys.executable, str(ROOT / "scripts/fuzz_native.py"), "--only", only, "-o", str(out), "--timeout", "30"],
            capture_output=True,
            text=True,
            timeout=600,
            env=env,
        )
        results = [json.loads(line) for line in out.read_text().splitlines()]
        assert len(results) > 20, p.stderr[-2000:]
        bad = [r for r in results if r["outcome"].startswith(("crash", "timeout", "memory", "rss"))]
        assert not bad, bad
        assert p.returncode == 0, p.stderr[-2000:]
