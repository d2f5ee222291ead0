"""Stops (SIGINT) at the edges of a run: while it is finished, and in the editor's run process after it ended."""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from mmusv.acquire import run
from test_acquire import small_scenario


@pytest.fixture(autouse=True)
def _sigint_handler_kept() -> Any:
    """The editor's run process ignores SIGINT once its run is over: this test process gets its handler back."""
    kept = signal.getsignal(signal.SIGINT)
    yield
    signal.signal(signal.SIGINT, kept)


def _lidar_only(frames: int) -> dict[str, Any]:
    sc = small_scenario(frames=frames)
    sc["rigs"] = {"usv_standard": {"preset": "lidar_only", "lidar": {"channels": 16, "points_per_second": 20000}}}
    return sc


def test_a_stop_while_the_recording_is_finished_still_finishes_it_and_writes_the_manifest(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A Ctrl-C as the last frame was written (inside the recorder's finish) left ``port_entry.mcap.partial``
    unfinished and no manifest.json; it is held until the manifest is written, then raised."""
    from mmusv.recording.frames import FrameRecorder

    original = FrameRecorder.finish

    def interrupted_finish(self: FrameRecorder, **kw: Any) -> Any:
        os.kill(os.getpid(), signal.SIGINT)  # Python's handler runs at the next bytecode: inside finish, unheld
        return original(self, **kw)

    monkeypatch.setattr(FrameRecorder, "finish", interrupted_finish)
    with pytest.raises(KeyboardInterrupt):
        run(_lidar_only(2), out_dir=tmp_path)
    rec = tmp_path / "port_entry.mcap"
    assert rec.is_file() and not (tmp_path / "port_entry.mcap.partial").exists()
    with rec.open("rb") as f:
        meta = {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert meta["run"]["status"] == manifest["status"] == "complete"  # every frame was written before the stop
    assert manifest["frames_written"] == 2 and manifest["recording"] == rec.name


def test_the_editors_run_process_stopped_after_its_run_ended_reports_the_complete_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The editor's stop button pressed as the run ended: the stop came after ``run`` returned, the run process
    ended with a traceback and no status line, and the page said "stopped before the first frame" with no
    recording, of a complete one."""
    import yaml
    from mmusv import acquire
    from mmusv.editor import job

    scenario = tmp_path / "s.yaml"
    scenario.write_text(yaml.safe_dump(_lidar_only(2)))
    original = acquire.run

    def run_then_stop(*a: Any, **kw: Any) -> Any:
        res = original(*a, **kw)
        os.kill(os.getpid(), signal.SIGINT)
        return res

    monkeypatch.setattr(acquire, "run", run_then_stop)
    code = job.main([str(scenario), str(tmp_path / "out")])
    lines = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert code == 0 and lines[-1]["status"] == "complete", lines
    assert lines[-1]["recording"] == str(tmp_path / "out" / "port_entry.mcap") and lines[-1]["frames"] == 2


def test_the_editors_run_process_stopped_as_it_says_its_status_still_says_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The stop lands after ``run`` returned, as the status line is written: it escaped as a traceback."""
    import yaml
    from mmusv.editor import job

    scenario = tmp_path / "s.yaml"
    scenario.write_text(yaml.safe_dump(_lidar_only(2)))
    original = job._say

    def say(obj: dict[str, Any]) -> None:
        if "status" in obj:
            os.kill(os.getpid(), signal.SIGINT)
        original(obj)

    monkeypatch.setattr(job, "_say", say)
    code = job.main([str(scenario), str(tmp_path / "out")])
    last = json.loads(capsys.readouterr().out.splitlines()[-1])
    assert code == 0 and last["status"] == "complete" and last["frames"] == 2, last
