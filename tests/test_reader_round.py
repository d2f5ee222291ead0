"""The recording reader as a researcher uses it in a notebook (a helper's round): each test failed before its fix.

Decoded images are arrays of their own (writable, like the point clouds); a point cloud or raw image whose bytes do
not match its layout is an ``IoError`` (not a bare ``KeyError``/``ValueError`` or a silently shortened array);
``read_table`` and ``find_recordings`` refuse a path that is not what they read (not an empty result); a frame lost
to damage is an ``IoError`` from ``frame_messages`` (as its docstring says) and a frame outside the recording names
the frames it holds; ``FrameStream(frames=...)`` takes numpy integers as ``frame_messages`` does and refuses a
range that holds none of the recording's frames.
"""

from __future__ import annotations

import io
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from mmusv.errors import ConfigError, IoError
from PIL import Image
from tiny_scenario import lidar_scenario


def _tiny(name: str, frames: int = 3) -> dict[str, Any]:
    """The tiny scenario (:func:`tiny_scenario.lidar_scenario`): one USV with an 8-channel LiDAR, one target."""
    return lidar_scenario(name, frames=frames)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from mmusv.acquire import run

    out = tmp_path_factory.mktemp("reader_round")
    res = run(_tiny("tiny"), out_dir=out, checks=False)
    assert res.status == "complete" and res.frames_written == 3
    return out


def test_decoded_images_are_writable_arrays_of_their_own() -> None:
    from mmusv.recording import decode_image

    depth = np.array([[1.0, np.inf], [2.0, 3.5]], dtype="<f4")
    raw = SimpleNamespace(encoding="32FC1", width=2, height=2, step=8, data=depth.tobytes())
    got = decode_image(raw)
    got[np.isinf(got)] = 0.0  # was: ValueError: assignment destination is read-only
    assert got.tolist() == [[1.0, 0.0], [2.0, 3.5]]
    buf = io.BytesIO()
    Image.fromarray(np.array([[1, 65535]], dtype=np.uint16)).save(buf, format="PNG")
    png = decode_image(SimpleNamespace(format="png", data=buf.getvalue()))
    assert png.dtype == np.uint16 and png.tolist() == [[1, 65535]]
    png[png == 65535] = 0
    assert png.tolist() == [[1, 0]]


def test_malformed_point_clouds_and_raw_images_are_io_errors_naming_what_is_wrong() -> None:
    from mmusv.recording import decode_image, decode_point_cloud

    x = SimpleNamespace(name="x", offset=0, type=7)
    data = np.arange(3, dtype="<f4").tobytes()
    cases = [
        (SimpleNamespace(point_stride=4, data=data, fields=[SimpleNamespace(name="x", offset=0, type=0)]), "type 0"),
        (SimpleNamespace(point_stride=4, data=data, fields=[SimpleNamespace(name="x", offset=2, type=7)]), "fit"),
        (SimpleNamespace(point_stride=4, data=data[:-1], fields=[x]), "whole number of points"),  # was 2 points
        (SimpleNamespace(point_stride=0, data=data, fields=[x]), "whole number of points"),  # was 0 points
    ]
    for msg, what in cases:
        with pytest.raises(IoError, match=what):
            decode_point_cloud(msg)
    assert decode_point_cloud(SimpleNamespace(point_stride=4, data=data, fields=[x]))["x"].tolist() == [0, 1, 2]
    # a step that is not a whole number of pixels, and data that is not step x height bytes
    img = np.zeros((2, 3), dtype="<f4").tobytes()
    for step in (13, 14):
        with pytest.raises(IoError, match=r"step x height"):
            decode_image(SimpleNamespace(encoding="32FC1", width=3, height=2, step=step, data=img))
    with pytest.raises(IoError, match="encodings: rgb8"):
        decode_image(SimpleNamespace(encoding="bgr8", width=1, height=1, step=3, data=b"\0\0\0"))


def test_read_table_refuses_a_path_that_is_not_a_tables_folder(run_dir: Path, tmp_path: Path) -> None:
    from mmusv.recording.tables import read_table

    assert read_table(run_dir / "tables", "world_state", expected=range(3)).rows.height == 6
    assert read_table(run_dir / "tables", "world_state", expected=[0, 1, 2, 3]).missing == [3]
    # the run folder instead of its tables: was an empty table
    with pytest.raises(IoError, match=r"not the tables folder.*tables: give that"):
        read_table(run_dir, "world_state")
    for bad in (tmp_path / "nope", run_dir / "tiny.mcap"):
        with pytest.raises(IoError, match=r"root = .*(does not exist|is not a folder)"):
            read_table(bad, "world_state")
    for root in (None, 3):  # was a bare TypeError
        with pytest.raises(ConfigError, match="root = "):
            read_table(root, "world_state")  # type: ignore[arg-type]
    for expected in (5, "0:3", [-1], range(-1, 2)):  # a bare TypeError; the negative: "frames -1 have no rows"
        with pytest.raises(ConfigError, match=r"expected = .*range.*frame numbers >= 0"):
            read_table(run_dir / "tables", "world_state", expected=expected)  # type: ignore[arg-type]
    # numpy's frame numbers as numpy gives them (an array was refused, its integers taken)
    import numpy as np

    assert read_table(run_dir / "tables", "world_state", expected=np.arange(4)).missing == [3]
    (tmp_path / "empty").mkdir()  # an empty tables folder: a run that wrote no rows yet
    assert read_table(tmp_path / "empty", "world_state").rows.height == 0


def test_find_recordings_refuses_what_is_not_a_folder(run_dir: Path, tmp_path: Path) -> None:
    from mmusv.recording.folders import find_recordings

    assert find_recordings(run_dir) == [run_dir / "tiny.mcap"]
    for bad in (tmp_path / "nope", run_dir / "tiny.mcap"):  # was [] for both
        with pytest.raises(IoError, match=r"folder = .*(does not exist|is not a folder)"):
            find_recordings(bad)
    for wrong in (None, 3, b"x"):  # was a bare TypeError
        with pytest.raises(ConfigError, match="folder = "):
            find_recordings(wrong)  # type: ignore[arg-type]


def test_frame_messages_a_lost_frame_is_an_io_error_and_a_frame_outside_names_the_range(
    run_dir: Path, tmp_path: Path
) -> None:
    from mmusv.recording import frame_messages

    rec = run_dir / "tiny.mcap"
    assert sorted(frame_messages(rec, 2)) == ["/tf", "/u/annotations", "/u/boxes", "/u/lidar", "/world/state"]
    for k in (3, -1):
        with pytest.raises(ConfigError, match=r"frame = .*: not in .*which holds frames 0\.\.2"):
            frame_messages(rec, k)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(rec.read_bytes()[: rec.stat().st_size // 2])  # the one chunk is cut: every frame lost
    for k in range(3):  # was a ConfigError "not in", though the docstring promises an IoError naming the damage
        # (its run metadata are cut off with the end: it may never have been written, as for a killed run's)
        with pytest.raises(
            IoError, match=rf"frame {k} of .*cut\.mcap is lost to damage \(or was never written.*truncated"
        ):
            frame_messages(cut, k)
    with pytest.raises(ConfigError, match="not in"):
        frame_messages(cut, 7)


def test_frame_stream_takes_numpy_integers_as_frame_messages_does(run_dir: Path) -> None:
    from mmusv.recording import read_info
    from mmusv.recording.stream import FrameStream

    info = read_info(run_dir / "tiny.mcap")
    ks = np.arange(3)
    stream = FrameStream(info, want=lambda _t: False, frames=(ks[1], ks[2]))  # was a ConfigError
    assert [fr.index for fr in stream] == [1] and stream.missing() == []
    assert [fr.index for fr in FrameStream(info, want=lambda _t: False, frames=(np.int32(2), None))] == [2]
    with pytest.raises(ConfigError, match="frames = "):
        FrameStream(info, want=lambda _t: False, frames=(np.float64(1.0), 2))


def test_a_frame_range_outside_the_recording_is_refused_not_an_empty_stream(run_dir: Path) -> None:
    from mmusv.recording import frame_messages, read_info
    from mmusv.recording.stream import FrameStream

    info = read_info(run_dir / "tiny.mcap")
    with pytest.raises(ConfigError, match=r"frames = \(5, 9\): none is in .*tiny\.mcap, which holds frames 0\.\.2"):
        FrameStream(info, want=lambda _t: False, frames=(5, 9))  # was: no frame, no missing frame, no report
    with pytest.raises(ConfigError, match=r"frames = \(3, None\): none is in"):
        FrameStream(info, want=lambda _t: False, frames=(3, None))
    overlap = FrameStream(info, want=lambda _t: False, frames=(2, 9))  # a range that overlaps is cut to it
    assert [fr.index for fr in overlap] == [2] and overlap.missing() == [] and overlap.report() is None
    with pytest.raises(ConfigError, match=r"frame = 4: not in .*tiny\.mcap, which holds frames 0\.\.2"):
        frame_messages(run_dir / "tiny.mcap", 4)


def test_a_recording_cut_inside_its_metadata_is_named_damaged_not_foreign(run_dir: Path, tmp_path: Path) -> None:
    """A copy of a recording cut inside its first metadata record was "an MCAP file not written by mmusv run": its
    header still says mmusv wrote it. A ROS 2 bag's does not."""
    from mmusv.recording.contents import summary
    from mmusv.recording.info import written_by_mmusv

    rec = run_dir / "tiny.mcap"
    data = rec.read_bytes()
    meta = data.index(b"\x0c", 8 + 9 + 4)  # the first metadata record after the header (opcode 0x0C)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: meta + 200])
    assert written_by_mmusv(rec) and written_by_mmusv(cut)
    got = summary(cut)
    assert got["frames"] is None and "metadata_problem" in got, got
    other = tmp_path / "other.mcap"  # an MCAP file of another writer
    from mcap.writer import Writer

    with other.open("wb") as f:
        w = Writer(f)
        w.start(profile="ros2", library="rosbag2")
        w.finish()
    assert not written_by_mmusv(other) and "metadata_problem" not in summary(other)
    assert not written_by_mmusv(tmp_path / "missing.mcap")
