"""Review of the session 920680f..d2da72c: the split of ``mmusv.annotate`` and ``mmusv.generate.spec`` (the names
they still give are the very objects of their new homes, no second copy), and the stops of ``mmusv run``, ``mmusv
convert`` and a serial batch (``mmusv run FOLDER``) that the command's signal handling
(``held_signals.note_stop``/``raise_noted_stop``, ``cli._run_command``) did not end as a stop: one a library wraps
in an error of its own during a frame (or as a batch's task loads its scenario) was recorded as ``failed`` with that
error (manifest.json, the recording's run metadata, conversion.yaml, the batch's scenario) while the command said
``interrupted`` (now ``held_signals.stops_unwrapped``), and one a library swallows in the last frame (after the
loop's last ``raise_noted_stop``) exited 130 with nothing on stderr (now ``cli._run_command`` says the stop)."""

from __future__ import annotations

import importlib
import json
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
import yaml
from mmusv.errors import ConfigError

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


def test_a_stop_wrapped_by_a_library_in_a_frame_is_recorded_as_interrupted(tmp_path: Path) -> None:
    done, manifest = _run_stopped(tmp_path, at=1, how="wrap")
    assert done.stderr == "mmusv: interrupted\n", done.stderr
    assert done.returncode == 130
    assert manifest["status"] == "interrupted", manifest  # it said "failed"
    assert "error" not in manifest, manifest
    from mmusv.recording.info import read_info

    run = read_info(tmp_path / "out" / str(manifest["recording"])).run
    assert run["status"] == "interrupted" and not run.get("error"), run  # it said failed, RuntimeError: ...
    assert 0 < int(manifest["frames_written"]) <= 2, manifest  # the frames before the stop (frame 1 may be whole)


def test_a_stop_swallowed_in_the_last_frame_still_ends_in_the_one_line(tmp_path: Path) -> None:
    done, manifest = _run_stopped(tmp_path, at=3, how="swallow")
    assert manifest["status"] == "complete"  # every frame was captured: the recording is whole
    assert done.returncode == 130
    assert done.stderr == "mmusv: interrupted\n", done.stderr  # it was empty


# `mmusv convert` of a recording of the tiny scenario whose frame stream, once frame AT was converted, sends the
# process SIGINT and lets a "library" swallow the KeyboardInterrupt or wrap it in an error of its own (as _RUN above):
# after the last frame, the loop's raise_noted_stop (at the top of each frame) does not look again.
_CONVERT = """\
import os, signal, sys, time
sys.argv = ['mmusv', 'convert', {recording!r}, '--to', {to!r}, '-o', {out!r}, '--no-progress']
import mmusv.export.conversion as conversion
calls = []
class Stream(conversion.FrameStream):
    def __iter__(self):
        for frame in super().__iter__():
            calls.append(frame.index)
            yield frame
            if frame.index == {at}:  # once the frame was converted
                try:
                    os.kill(os.getpid(), signal.SIGINT)
                    time.sleep(5)
                except KeyboardInterrupt as exc:
                    if {how!r} == 'wrap':
                        raise RuntimeError('wrapped') from exc
conversion.FrameStream = Stream
from mmusv._launch import main
code = main()
print('calls', calls)
sys.exit(code)
"""


def _convert_stopped(
    tmp_path: Path, *, to: str, at: int, how: str
) -> tuple[subprocess.CompletedProcess[str], dict[str, object]]:
    from mmusv.acquire import run

    recording = run(dict(_TINY), out_dir=tmp_path / "rec").recording
    out = tmp_path / "out"
    code = _CONVERT.format(recording=str(recording), to=to, out=str(out), at=at, how=how)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False, timeout=120)
    assert done.stdout.splitlines()[-1] == f"calls {list(range(at + 1))}", (done.stdout, done.stderr)
    return done, yaml.safe_load((out / "conversion.yaml").read_text(encoding="utf-8"))


@pytest.mark.parametrize("to", ["kitti", "ros2"])
def test_a_stop_wrapped_by_a_library_in_a_conversion_frame_is_recorded_as_interrupted(tmp_path: Path, to: str) -> None:
    # conversion.yaml said `status: failed, error: 'RuntimeError: wrapped'` under `mmusv: interrupted`, 130, and the
    # ROS 2 bag was aborted (no metadata.yaml) where a plain Ctrl-C closes it whole, saying interrupted
    done, report = _convert_stopped(tmp_path, to=to, at=1, how="wrap")
    assert done.stderr == "mmusv: interrupted\n", done.stderr
    assert done.returncode == 130
    assert report["status"] == "interrupted" and "error" not in report, report
    if to == "ros2":
        bag = yaml.safe_load((tmp_path / "out" / "tiny" / "metadata.yaml").read_text(encoding="utf-8"))
        assert bag["rosbag2_bagfile_information"]["custom_data"]["mmusv.status"] == "interrupted"


def test_a_stop_swallowed_in_a_conversion_s_last_frame_still_ends_in_the_one_line(tmp_path: Path) -> None:
    # every command, not only `mmusv run`: the conversion is whole ("complete"), the command ends as a stop
    done, report = _convert_stopped(tmp_path, to="kitti", at=3, how="swallow")
    assert report["status"] == "complete" and report["frames_converted"] == 4, report
    assert done.returncode == 130
    assert done.stderr == "mmusv: interrupted\n", done.stderr  # it was empty


# `mmusv run FOLDER` (a serial batch: the tasks run in the command's process) of the tiny scenario, whose capture of
# frame 1 ("frame") or whose task's loading of the scenario ("load") sends the process SIGINT and lets a "library"
# wrap the KeyboardInterrupt in an error of its own.
_BATCH = """\
import os, signal, sys, time
sys.argv = ['mmusv', 'run', {folder!r}, '-o', {out!r}]
import mmusv.acquire as acquire, mmusv.simulation as simulation
def stopped(original, when):
    def wrapped(*args, **kwargs):
        if when(*args):
            try:
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(5)
            except KeyboardInterrupt as exc:
                raise RuntimeError("Error calling __set_name__ on 'Field' instance") from exc
        return original(*args, **kwargs)
    return wrapped
if {where!r} == 'frame':
    simulation.Simulation.capture = stopped(simulation.Simulation.capture, lambda sim, frame: frame == 1)
else:
    acquire.load_scenario = stopped(acquire.load_scenario, lambda cfg: True)
from mmusv._launch import main
sys.exit(main())
"""


@pytest.mark.parametrize("where", ["frame", "load"])
def test_a_stop_wrapped_by_a_library_in_a_serial_batch_stops_the_batch(tmp_path: Path, where: str) -> None:
    # The scenario was marked failed ("internal error RuntimeError: ...", its recording's manifest "failed" too) and
    # the batch said neither that it stopped nor how to record the rest, under `mmusv: interrupted`, 130.
    folder = tmp_path / "scenarios"
    folder.mkdir()
    (folder / "tiny.yaml").write_text(yaml.safe_dump(_TINY), encoding="utf-8")
    out = tmp_path / "out"
    code = _BATCH.format(folder=str(folder), out=str(out), where=where)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False, timeout=120)
    assert done.returncode == 130, (done.stdout, done.stderr)
    assert done.stderr == (
        "mmusv: stopped; complete recordings are kept, run the same command again to record the rest\n"
        "mmusv: interrupted\n"
    ), done.stderr
    assert "failed" not in done.stdout and "RuntimeError" not in done.stdout + done.stderr, done.stdout
    index = json.loads((out / "dataset.json").read_text(encoding="utf-8"))
    assert index["recordings"][0]["status"] == "pending" and index["totals"]["failed"] == 0, index  # said failed
    assert "RuntimeError" not in json.dumps(index), index
    manifest = out / "tiny" / "manifest.json"
    if where == "frame":  # the recording says interrupted, as a plain Ctrl-C leaves it
        assert json.loads(manifest.read_text(encoding="utf-8"))["status"] == "interrupted"
    else:  # stopped before its recording was opened: nothing of it written
        assert not manifest.exists()


def _swallowing_command(signum: int, *, then: Exception | None) -> Callable[[object], int]:
    """A command (``cli._dispatch``) in which a library swallows the stop ``signum`` brings, then that ends with
    ``then`` raised, or returns 0."""
    import os
    import time

    def command(args: object) -> int:
        try:
            os.kill(os.getpid(), signum)
            time.sleep(5)
        except KeyboardInterrupt:
            pass  # swallowed
        if then is not None:
            raise then
        return 0

    return command


@pytest.mark.parametrize(
    ("signum", "then", "said"),
    [
        (signal.SIGINT, None, ["mmusv: interrupted"]),
        (signal.SIGTERM, None, ["mmusv: terminated (SIGTERM)"]),
        (signal.SIGINT, ConfigError("bad"), ["mmusv: error: bad", "mmusv: interrupted"]),
    ],
)
def test_every_command_ends_a_stop_it_did_not_end_on_with_the_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], signum: int, then: Exception | None,
    said: list[str],
) -> None:  # fmt: skip
    # Said by the command line after any command (cli._run_command), not by each command's loops: the command's own
    # error, if it said one, goes first.
    import mmusv.cli as cli

    monkeypatch.setattr(cli, "_dispatch", _swallowing_command(signum, then=then))
    assert cli.main(["version"]) == 128 + signum
    assert capsys.readouterr().err.splitlines() == said
