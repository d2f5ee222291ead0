"""The run process of the editor (``python -m mmusv.editor.job``) reports one JSON object per line, and its status
line must stay a line of its own even when the stop cuts a progress line short.

CI saw ``test_a_stopped_run_names_its_recording_and_frames`` get ``"recording": null``: ``print`` wrote a progress
line's text and its newline apart, a stop (SIGINT) between the two ran the status line on after it
(``{"done": 1, "total": 200}{"status": "interrupted", ...}``), the editor could not read that line and said
"stopped before the first frame" of a run whose recording held frames.
"""

from __future__ import annotations

import json
import signal
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import mmusv.acquire
import pytest
from mmusv.editor import job


@pytest.fixture(autouse=True)
def _sigint_handler_kept() -> Iterator[None]:
    """The run process ignores SIGINT once its run is stopped: this test process (and the run processes the later
    tests start, which inherit it) gets its handler back."""
    kept = signal.getsignal(signal.SIGINT)
    yield
    signal.signal(signal.SIGINT, kept)


def _cut_run(*args: Any, progress: Any, **kwargs: Any) -> Any:
    """A run stopped while its progress line was being written: the text out, the newline not."""
    import sys

    progress(1, 200)
    sys.stdout.write(json.dumps({"done": 2, "total": 200}))  # the stop comes before its newline
    raise KeyboardInterrupt


def test_the_status_line_after_a_stop_is_a_line_of_its_own(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "port_entry.mcap").write_bytes(b"x")
    manifest = {"recording": "port_entry.mcap", "frames_written": 2, "status": "interrupted"}
    (out / "manifest.json").write_text(json.dumps(manifest), encoding="utf-8")
    monkeypatch.setattr(mmusv.acquire, "run", _cut_run)
    assert job.main(["scenario.yaml", str(out)]) == 130
    lines = capsys.readouterr().out.splitlines()
    read = []
    for line in lines:
        try:
            read.append(json.loads(line))
        except json.JSONDecodeError:
            read.append(None)
    status = [m for m in read if isinstance(m, dict) and "status" in m]
    # was: no line to read ('{"done": 2, "total": 200}{"status": "interrupted", ...}')
    assert len(status) == 1, lines
    assert status[0]["status"] == "interrupted" and status[0]["recording"] == str(out / "port_entry.mcap"), lines
    assert status[0]["frames"] == 2
    assert read[0] == {"done": 1, "total": 200}  # the lines before the stop as they were
