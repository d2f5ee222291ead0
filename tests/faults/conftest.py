"""Shared pieces of the fault-injection tests: tiny LiDAR-only recordings, a copy with small chunks (so damage in
one chunk leaves frames on both sides), the reference frames every reader must give back byte for byte, every
reader of a recording (the API and the command line, in this process), and helpers to run ``mmusv`` as a child.
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml
from mcap_rechunk import rechunk
from tiny_scenario import lidar_scenario

ROOT = Path(__file__).resolve().parents[2]


scenario = lidar_scenario
"""The fault tests' scenario (:func:`tiny_scenario.lidar_scenario`)."""


def write_yaml(path: Path, data: dict[str, Any]) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def chunk_spans(path: Path, *, declarations: bool = False) -> list[tuple[int, int]]:
    """``(start, end)`` byte offsets of every chunk record of a file that holds messages (from the intact file's
    structure); with ``declarations``, the chunks that hold none too (the recorder writes the first frame's schemas
    and channels in a chunk of their own, before its messages)."""
    from mcap.records import Chunk, Message
    from mcap.stream_reader import StreamReader, breakup_chunk

    spans = []
    with path.open("rb") as f:
        start = 8
        for rec in StreamReader(f, emit_chunks=True).records:
            end = f.tell()
            if isinstance(rec, Chunk) and (declarations or any(isinstance(r, Message) for r in breakup_chunk(rec))):
                spans.append((start, end))
            start = end
    return spans


def frames_of(path: Path) -> tuple[dict[int, dict[str, bytes]], Any]:
    """``({frame: {topic: message bytes}}, stream)``: every frame the one reader yields, every topic decoded."""
    from mmusv.recording.info import read_info
    from mmusv.recording.stream import FrameStream

    stream = FrameStream(read_info(path), want=lambda _t: True)
    out = {fr.index: {t: m.SerializeToString() for t, m in fr.messages.items()} for fr in stream}
    return out, stream


def cli_main(*args: str) -> tuple[int, str, str]:
    """``mmusv ARGS`` in this process: ``(exit status, stdout, stderr)``. An exception other than the ones the
    command line turns into a one-line message escapes (and fails the test)."""
    from mmusv.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(args))
    return code, out.getvalue(), err.getvalue()


def api_readers(path: Path) -> dict[str, Any]:
    """Every API reader of the recording at ``path``: the result of each, or the ``MmusvError`` it raised."""
    from mmusv.errors import MmusvError
    from mmusv.recording.contents import summary
    from mmusv.recording.info import read_info
    from mmusv.recording.messages import frame_messages, read_messages

    results: dict[str, Any] = {}
    calls: dict[str, Callable[[], Any]] = {
        "read_info": lambda: read_info(path),
        "frames": lambda: frames_of(path),
        "summary": lambda: summary(path),
        "read_messages": lambda: [(t, lt, m.SerializeToString()) for t, lt, m in read_messages(path)],
        "frame_messages": lambda: {t: m.SerializeToString() for t, m in frame_messages(path, 1).items()},
    }
    for name, call in calls.items():
        try:
            results[name] = call()
        except MmusvError as exc:
            results[name] = exc
    return results


def check_against(results: dict[str, Any], reference: dict[int, dict[str, bytes]]) -> None:
    """What the readers gave back is right: every frame yielded is the reference frame byte for byte, the frames
    not yielded are reported as missing, and frame 1 (when returned) is the reference's."""
    from mmusv.errors import MmusvError

    got = results["frames"]
    if isinstance(got, MmusvError):
        return
    frames, stream = got
    for k, msgs in frames.items():
        assert msgs == reference[k], f"frame {k} differs from the intact recording"
    absent = sorted(set(reference) - set(frames))
    if absent:
        assert set(absent) <= set(stream.missing()), (absent, stream.missing())
        assert stream.report() is not None
    fm = results["frame_messages"]
    if not isinstance(fm, MmusvError):
        assert fm == reference[1]


def child_env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT / "python") + os.pathsep + os.environ.get("PYTHONPATH", "")}


def mmusv(*args: str, **kw: Any) -> subprocess.Popen[str]:
    """``python -m mmusv.cli ARGS`` as a child in its own session."""
    return subprocess.Popen(
        [sys.executable, "-m", "mmusv.cli", *args],
        cwd=kw.pop("cwd", ROOT),
        env=child_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        **kw,
    )


def wait_for(cond: Callable[[], bool], *, timeout: float, what: str) -> None:
    end = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(0.02)


@pytest.fixture(scope="session")
def small(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A complete 12-frame run of the light rig (its folder: ``tiny.mcap``, tables, manifest)."""
    from mmusv.acquire import run

    out = tmp_path_factory.mktemp("small")
    run(scenario("tiny", frames=12), out_dir=out / "run")
    return out / "run"


@pytest.fixture(scope="session")
def chunky(small: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[int, dict[str, bytes]]]:
    """The small recording rewritten in 6 kB chunks (about one frame each), and its reference frames."""
    out = tmp_path_factory.mktemp("chunky") / "tiny.mcap"
    rechunk(small / "tiny.mcap", out, 6000)
    reference, stream = frames_of(out)
    assert sorted(reference) == list(range(12)) and stream.report() is None
    assert len(chunk_spans(out)) >= 8
    return out, reference


def copy_run(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)
    return dst
