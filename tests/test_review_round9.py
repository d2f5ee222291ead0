"""Review of the session 920680f..d2da72c: the split of ``mmusv.annotate`` and ``mmusv.generate.spec`` (the names
they still give are the very objects of their new homes, no second copy), and two stops of ``mmusv run`` that the
command's signal handling (``held_signals.note_stop``/``raise_noted_stop``, ``cli._run_command``) does not end as
a stop: they are marked ``xfail`` (the files they need, ``cli.py``, ``acquire.py``, ``held_signals.py``, are being
edited elsewhere)."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

# A scenario of four frames that records in a second: one USV with a LiDAR, one target, open sea.
_TINY = {
    "name": "tiny",
    "seed": 1,
    "acquisition": {"frequency_hz": 5, "frames": 4},
    "map": {"type": "open_sea", "seed": 0, "params": {"extent_m": 800, "islet_probability": 0.0, "n_buoys": 0}},
    "rigs": {"r": {"preset": "lidar_only"}},
    "vessels": [
        {"id": "usv", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2.0, "route": [[0, 0], [90, 0]]},
        {"id": "tug", "role": "target", "asset": "tug_32m", "speed_mps": 2.0, "route": [[40, 20], [140, 20]]},
    ],
}

# `mmusv run` of the tiny scenario whose Simulation.capture, at frame AT, sends the process SIGINT and lets a
# "library" deal with the KeyboardInterrupt as HOW says: swallow it, or wrap it in an error of its own.
_RUN = """\
import os, signal, sys, time
sys.argv = ['mmusv', 'run', {scenario!r}, '-o', {out!r}]
import mmusv.simulation as simulation
original, calls = simulation.Simulation.capture, []
def capture(self, frame, **kwargs):
    calls.append(frame)
    if frame == {at}:
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)
        except KeyboardInterrupt as exc:
            if {how!r} == 'wrap':
                raise RuntimeError("Error calling __set_name__ on 'Field' instance") from exc
    return original(self, frame, **kwargs)
simulation.Simulation.capture = capture
from mmusv._launch import main
code = main()
print('calls', calls)
sys.exit(code)
"""


def _run_stopped(tmp_path: Path, *, at: int, how: str) -> tuple[subprocess.CompletedProcess[str], dict[str, object]]:
    scenario = tmp_path / "tiny.yaml"
    scenario.write_text(yaml.safe_dump(_TINY), encoding="utf-8")
    out = tmp_path / "out"
    code = _RUN.format(scenario=str(scenario), out=str(out), at=at, how=how)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False, timeout=120)
    assert done.stdout.splitlines()[-1] == f"calls {list(range(at + 1))}", (done.stdout, done.stderr)
    manifest = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
    return done, manifest


@pytest.mark.parametrize(
    ("module", "home", "names"),
    [
        ("mmusv.annotate", "mmusv.boxes3d", ["box_corners", "footprint_in_range", "in_target_range"]),
        ("mmusv.annotate", "mmusv.silhouettes", ["SilhouetteCache"]),
        ("mmusv.annotate", "mmusv.agent_annotations", ["Annotations"]),
        ("mmusv.annotate", "mmusv.image_boxes", ["pinhole_truncation"]),
        (
            "mmusv.generate.spec",
            "mmusv.generate.spec_models",
            ["Combination", "Difficulty", "GenerationSpec", "SizeClass", "UsvRoles", "class_assets"],
        ),
    ],
)
def test_the_split_modules_still_name_the_objects_of_their_new_homes(module: str, home: str, names: list[str]) -> None:
    # The names the old module's __all__ gives (and the docs cite as mmusv.annotate.in_target_range, ...) are the
    # new home's objects themselves, not a copy left behind: an isinstance check or a class compared by identity
    # holds whichever module a caller imported from.
    old, new = importlib.import_module(module), importlib.import_module(home)
    for name in names:
        assert name in old.__all__ and name in new.__all__, name
        assert getattr(old, name) is getattr(new, name), name
        assert getattr(new, name).__module__ == home, name


@pytest.mark.xfail(
    strict=True,
    reason="a stop a library wraps in an error of its own during the frame loop (Python 3.11's RuntimeError from "
    "__set_name__ while a lazy import defines a dataclass, pydantic-core's SchemaError) ends `mmusv run` as "
    "'interrupted', status 130, but acquire._record's `except Exception` records the run as 'failed' with that "
    "error in manifest.json and the recording's run metadata; needs acquire.py (held_signals' noted stop read there)",
)
def test_a_stop_wrapped_by_a_library_in_a_frame_is_recorded_as_interrupted(tmp_path: Path) -> None:
    done, manifest = _run_stopped(tmp_path, at=1, how="wrap")
    assert done.stderr == "mmusv: interrupted\n", done.stderr
    assert done.returncode == 130
    assert manifest["status"] == "interrupted", manifest  # it says "failed"


@pytest.mark.xfail(
    strict=True,
    reason="a stop a library swallows in the last frame (after the loop's last raise_noted_stop) is never raised "
    "again: `mmusv run` prints its success line and exits 130 with nothing on stderr, not 'mmusv: interrupted' as "
    "every other stop (a stop held while the run finishes ends so, acquire._record); needs acquire.py or cli.py",
)
def test_a_stop_swallowed_in_the_last_frame_still_ends_in_the_one_line(tmp_path: Path) -> None:
    done, manifest = _run_stopped(tmp_path, at=3, how="swallow")
    assert manifest["status"] == "complete"  # every frame was captured: the recording is whole
    assert done.returncode == 130
    assert done.stderr == "mmusv: interrupted\n", done.stderr  # it is empty
