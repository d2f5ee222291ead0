"""Reading a range of frames (``FrameStream(frames=...)``, ``frame_messages``, ``convert --frames``): chunks holding
none of the frames asked for are hopped over unread, and what comes back is the full reading's frames byte for
byte, on intact, damaged and truncated files alike."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest
from mmusv.errors import ConfigError, IoError
from mmusv.recording.info import read_info
from mmusv.recording.messages import frame_messages
from mmusv.recording.stream import FrameStream

from .conftest import chunk_spans, cli_main

Chunky = tuple[Path, dict[int, dict[str, bytes]]]


def _read(path: Path, frames: tuple[int, int | None]) -> tuple[dict[int, dict[str, bytes]], FrameStream]:
    stream = FrameStream(read_info(path), want=lambda _t: True, frames=frames)
    out = {fr.index: {t: m.SerializeToString() for t, m in fr.messages.items()} for fr in stream}
    return out, stream


@pytest.mark.parametrize("frames", [(0, 1), (4, 7), (11, None), (10, 40), (0, None)])
def test_a_range_reads_only_its_chunks_and_gives_the_same_frames(
    chunky: Chunky, frames: tuple[int, int | None]
) -> None:
    path, reference = chunky
    got, stream = _read(path, frames)
    start, stop = frames
    want = [k for k in sorted(reference) if k >= start and (stop is None or k < stop)]
    assert sorted(got) == want
    assert all(got[k] == reference[k] for k in want)
    assert stream.report() is None and stream.missing() == []  # the frames past the run's end are not "missing"
    outside = len(reference) - len(want)
    # about one frame a chunk: most chunks of the frames outside the range are not read at all
    assert stream.chunks_skipped >= outside - 2 if outside else stream.chunks_skipped == 0, stream.chunks_skipped


def test_a_damaged_chunk_outside_the_range_is_not_read_and_one_inside_is_named(chunky: Chunky, tmp_path: Path) -> None:
    path, reference = chunky
    spans = chunk_spans(path)
    _start, end = spans[len(spans) // 2]
    data = bytearray(path.read_bytes())
    data[end - 40] ^= 0x21
    bad = tmp_path / "tiny.mcap"
    bad.write_bytes(bytes(data))
    full, stream = _read(bad, (0, None))
    lost = sorted(set(reference) - set(full))
    assert lost and "damaged chunk" in (stream.truncated or "")
    kept = [k for k in reference if k not in lost and all(abs(k - j) > 1 for j in lost)]
    for k in kept:
        got, st = _read(bad, (k, k + 1))
        assert got == {k: reference[k]} and st.report() is None, (k, st.report())
        assert {t: m.SerializeToString() for t, m in frame_messages(bad, k).items()} == reference[k]
    for k in lost:
        got, st = _read(bad, (k, k + 1))
        assert got == {} and st.missing() == [k] and "damaged chunk" in (st.report() or "")
        with pytest.raises((IoError, ConfigError), match="damaged"):
            frame_messages(bad, k)


def test_a_chunk_whose_header_disagrees_with_the_index_is_read(chunky: Chunky, tmp_path: Path) -> None:
    """A damaged header that moves a chunk's log times out of the range does not hide its frame: the summary's
    chunk index (CRC-checked) must agree before a chunk is hopped over."""
    path, reference = chunky
    target = 5
    full = _read(path, (0, None))[1]
    data = bytearray(path.read_bytes())
    info = read_info(path)
    t_target = round(target / info.frequency_hz * 1e9)
    moved = round(11 / info.frequency_hz * 1e9)
    hit = 0
    for start, _end in chunk_spans(path):
        t0, t1 = struct.unpack_from("<QQ", data, start + 9)
        if t0 <= t_target <= t1:
            struct.pack_into("<QQ", data, start + 9, moved, moved)
            hit += 1
    assert hit >= 1 and full.report() is None
    bad = tmp_path / "moved.mcap"
    bad.write_bytes(bytes(data))
    got, _stream = _read(bad, (target, target + 1))
    assert got == {target: reference[target]}, sorted(got)
    assert {t: m.SerializeToString() for t, m in frame_messages(bad, target).items()} == reference[target]


def test_a_file_without_summary_is_read_in_full(chunky: Chunky, tmp_path: Path) -> None:
    path, reference = chunky
    data = path.read_bytes()
    spans = chunk_spans(path)
    cut = tmp_path / "cut.mcap.partial"
    cut.write_bytes(data[: spans[-2][1]])  # ends after a whole chunk: no summary, no footer
    got, stream = _read(cut, (3, 5))
    assert got == {3: reference[3], 4: reference[4]} and stream.chunks_skipped == 0
    assert "truncated" in (stream.truncated or "")


def test_convert_frames_reads_a_part_and_writes_the_full_conversion_s_files(chunky: Chunky, tmp_path: Path) -> None:
    from mmusv.export.conversion import convert

    path, _reference = chunky
    assert cli_main("convert", str(path), "-o", str(tmp_path / "all"), "--no-progress", "--no-split")[0] == 0
    ticks: list[tuple[int, int]] = []
    convert(
        path,
        to="opv2v",
        out_dir=tmp_path / "part",
        frames="3:6",
        splits=None,
        progress=lambda d, n: ticks.append((d, n)),
    )
    assert ticks[-1] == (3, 3), ticks  # progress counts the frames of the range, and ends at its total
    part = {p.relative_to(tmp_path / "part"): p.read_bytes() for p in (tmp_path / "part").rglob("*.pcd")}
    full = {p.relative_to(tmp_path / "all"): p.read_bytes() for p in (tmp_path / "all").rglob("*.pcd")}
    assert len(part) == 3 and all(full[name] == b for name, b in part.items())
    assert sorted(p.stem for p in part) == ["000003", "000004", "000005"]
