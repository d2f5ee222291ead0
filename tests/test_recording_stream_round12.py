"""A recording whose bytes are whole (every CRC matches) but one message of which is empty: protobuf decodes empty
bytes to a message of defaults, so a ``/world/state`` of no vessels or a LiDAR cloud of no fields was taken as a
complete frame, and ``mmusv convert`` ended with a bare ``IndexError`` (``agent_view``) or ``KeyError: 'x'`` (the
KITTI, OPV2V and SemanticKITTI writers). Such a frame is now incomplete, as one whose message does not decode: the
converters skip it and say so."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import mmusv
import pytest
from mcap_rechunk import emptied
from mmusv.recording import read_info
from mmusv.recording.stream import FrameStream
from tiny_scenario import lidar_scenario


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("rec")
    return mmusv.run(lidar_scenario("hollow", frames=2), out_dir=out).recording


@pytest.mark.parametrize(("topic", "said"), [("/world/state", "holds 0 vessels"), ("/u/lidar", "without x, y, z")])
def test_an_empty_message_makes_its_frame_incomplete(recording: Path, tmp_path: Path, topic: str, said: str) -> None:
    path = emptied(recording, topic, 1, tmp_path / "hollow" / recording.name)
    stream = FrameStream(read_info(path), lambda t: True)
    assert [f.index for f in stream] == [0]
    assert len(stream.incomplete) == 1 and said in stream.incomplete[0][1], stream.incomplete


@pytest.mark.parametrize("topic", ["/world/state", "/u/lidar"])
@pytest.mark.parametrize("to", ["kitti", "opv2v"])
def test_convert_skips_the_frame_instead_of_a_traceback(recording: Path, tmp_path: Path, topic: str, to: str) -> None:
    path = emptied(recording, topic, 0, tmp_path / "hollow" / recording.name)
    done = subprocess.run(
        [sys.executable, "-m", "mmusv", "convert", str(path), "-o", str(tmp_path / "out"), "--to", to, "--no-progress"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert "1 frames" in done.stdout + done.stderr or "1 frame" in done.stdout + done.stderr, done.stdout + done.stderr
