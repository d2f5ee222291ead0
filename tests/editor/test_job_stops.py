"""The editor's Stop in the run process (``python -m mmusv.editor.job``) where a library meets the stop's
``KeyboardInterrupt``, as ``mmusv run`` has handled it since the command's own rounds (``tests/test_launch.py``):

- swallowed by the library (an ``except`` around the code the stop landed in; importlib's module-lock callback, which
  Python reports and goes on): the run went on to its last frame and said ``complete``;
- made an error of its own by the library (Python's ``RuntimeError`` from ``__set_name__``): a traceback, no status
  line, and the editor said "the run process ended with status 1";
- swallowed while the run's modules loaded (a library's ``except`` around an optional import): the run went on.

The run process now notes the stop as the command does (``held_signals``): the frame loop raises it again, an error
after it is the stop, and the signals are held while the modules load.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from test_launch import _SWALLOWS, TINY

# the swallowed stops of ``mmusv run``'s own test (``except``, ``finalizer``), and a library's error made of it
_IN_A_FRAME = {
    **_SWALLOWS,
    "wrapped": "        try:\n            stop()\n        except KeyboardInterrupt as exc:\n"
    "            raise RuntimeError('Error building a validator: KeyboardInterrupt') from exc\n",
}


def _job(tmp_path: Path, patch: str) -> tuple[subprocess.CompletedProcess[str], list[dict[str, Any]]]:
    scenario = tmp_path / "tiny.yaml"
    scenario.write_text(json.dumps(TINY), encoding="utf-8")
    code = (
        "import json, os, signal, sys, time\n"
        "def stop():\n    os.kill(os.getpid(), signal.SIGINT)\n    time.sleep(5)\n"
        f"{patch}"
        "from mmusv.editor.job import main\n"
        f"code = main([{str(scenario)!r}, {str(tmp_path / 'out')!r}])\n"
        "sys.exit(code)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False, timeout=300)
    lines = []
    for line in out.stdout.splitlines():
        try:
            lines.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return out, lines


@pytest.mark.parametrize("how", sorted(_IN_A_FRAME))
def test_a_stop_a_library_meets_in_a_frame_ends_the_run_as_a_stop(tmp_path: Path, how: str) -> None:
    patch = (
        "import mmusv.simulation as simulation\n"
        "original, calls = simulation.Simulation.capture, []\n"
        "def capture(self, frame, **kwargs):\n"
        "    calls.append(frame)\n"
        "    print(json.dumps({'captured': frame}), flush=True)\n"
        "    if len(calls) == 2:\n"
        f"{_IN_A_FRAME[how]}"
        "    return original(self, frame, **kwargs)\n"
        "simulation.Simulation.capture = capture\n"
    )
    out, lines = _job(tmp_path, patch)
    status = [m for m in lines if "status" in m]
    # was: {"status": "complete", "frames": 6, ...} (except, finalizer); no line and status 1 (wrapped)
    assert [m["status"] for m in status] == ["interrupted"], (out.stdout, out.stderr)
    assert [m["captured"] for m in lines if "captured" in m] == [0, 1]  # no frame captured after the stop
    frames = 1 if how == "wrapped" else 2  # the wrapped stop ends frame 1 itself; a swallowed one lets it finish
    assert status[0]["frames"] == frames and Path(status[0]["recording"]).is_file()
    assert out.returncode == 130
    assert "Traceback" not in out.stderr, out.stderr


def test_a_stop_a_library_swallows_while_the_run_loads_ends_it_before_the_first_frame(tmp_path: Path) -> None:
    patch = (
        "import builtins\n"
        "real_import, seen = builtins.__import__, []\n"
        "def loading(name, *args, **kwargs):\n"
        "    if name == 'mmusv.acquire' and not seen:\n"
        "        seen.append(name)\n"
        "        try:  # a library's optional import\n"
        "            stop()\n"
        "        except KeyboardInterrupt:\n"
        "            pass\n"
        "    return real_import(name, *args, **kwargs)\n"
        "builtins.__import__ = loading\n"
    )
    out, lines = _job(tmp_path, patch)
    # was: the run went on, {"status": "complete", "frames": 6, ...}
    assert [m for m in lines if "status" in m] == [{"status": "interrupted", "error": "stopped before the first frame"}]
    assert not (tmp_path / "out").exists()
    assert out.returncode == 130, out.stderr
