"""A copy cut short inside a closed chunk (an interrupted copy, power loss after the recorder filled in the chunk's
length): the readers read every frame whose records all lie before the cut, as far as the chunk's compressed stream
decodes, and none past it; ``mmusv recover`` keeps them. They dropped the whole chunk (``0 of 6 frames read``): only
a chunk whose length was still the writer's placeholder was read as far as it goes."""

from __future__ import annotations

import io
import shutil
import struct
from pathlib import Path

import pytest
from mcap_rechunk import write_records

from .conftest import chunk_spans, cli_main, frames_of, scenario

FRAMES = 6


@pytest.fixture(scope="module")
def dense(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[int, dict[str, bytes]]]:
    """A complete 6-frame run of the 32-channel rig (its folder; ``dense.mcap``: one zstd chunk of ~600 kB, several
    zstd blocks) and its reference frames."""
    from mmusv.acquire import run

    out = tmp_path_factory.mktemp("cut_chunk") / "run"
    run(scenario("dense", frames=FRAMES, dense=True), out_dir=out)
    reference, stream = frames_of(out / "dense.mcap")
    assert sorted(reference) == list(range(FRAMES)) and stream.report() is None
    assert len(chunk_spans(out / "dense.mcap")) == 1
    return out, reference


def _one_chunk(src: Path, dst: Path, compression: str) -> Path:
    """``src`` rewritten by the official writer with every message in one chunk of ``compression`` (``lz4`` or
    ``none``), its metadata first."""
    from mcap.reader import make_reader
    from mcap.writer import CompressionType, Writer

    with src.open("rb") as f:
        reader = make_reader(f)
        meta = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
        msgs = list(reader.iter_messages())
    with dst.open("wb") as out:
        w = Writer(out, chunk_size=1 << 30, compression=CompressionType[compression.upper()])
        write_records(w, meta, msgs)
        w.finish()  # type: ignore[no-untyped-call]
    return dst


def _whole_frames(src: Path, cut: int) -> set[int]:
    """The frames of ``src`` whose messages all lie in the records of its one chunk that ``src[:cut]`` still holds
    in full: decoded independently of mmusv's reader (the zstd or lz4 streaming decompressor on the chunk's compressed
    bytes up to the cut, the ``mcap`` package's record parsing up to the record cut off)."""
    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    from mcap.records import Message
    from mcap.stream_reader import StreamReader
    from mmusv.recording.info import read_info

    data = src.read_bytes()
    ((start, end),) = chunk_spans(src)
    clen = struct.unpack_from("<I", data, start + 9 + 28)[0]
    compression = data[start + 9 + 32 : start + 9 + 32 + clen]
    stream = data[start + 9 + 40 + clen : min(cut, end)]
    if compression == b"zstd":
        import zstandard

        try:
            raw = zstandard.ZstdDecompressor().decompressobj().decompress(stream)
        except zstandard.ZstdError:
            raw = b""
    elif compression == b"lz4":
        import lz4.frame

        raw = lz4.frame.LZ4FrameDecompressor().decompress(stream)
    else:
        raw = stream
    got: dict[int, int] = {}
    try:
        for rec in StreamReader(io.BytesIO(raw), skip_magic=True).records:
            if isinstance(rec, Message):
                got[rec.log_time] = got.get(rec.log_time, 0) + 1
    except McapError:
        pass  # the record cut off
    want: dict[int, int] = {}
    with src.open("rb") as f:
        for _schema, _ch, m in make_reader(f).iter_messages():
            want[m.log_time] = want.get(m.log_time, 0) + 1
    f_hz = read_info(src).frequency_hz
    return {round(t * f_hz / 1e9) for t, n in want.items() if got.get(t, 0) == n}


def _cuts(src: Path) -> list[int]:
    """Offsets inside the one chunk of ``src``: in its header, in its first compressed bytes, at 40 % and 70 % of
    it, and 175 bytes and 1 byte short of its end."""
    ((start, end),) = chunk_spans(src)
    return [
        start + 30,
        start + 400,
        start + (end - start) * 2 // 5,
        start + (end - start) * 7 // 10,
        end - 175,
        end - 1,
    ]


def _cut(src: Path, cut: int, tmp: Path) -> Path:
    """A copy of ``src`` cut ``cut`` bytes from its start (in ``tmp``)."""
    path = tmp / f"{src.stem}_{cut}.mcap"
    path.write_bytes(src.read_bytes()[:cut])
    return path


def _check_cut(src: Path, reference: dict[int, dict[str, bytes]], cut: int, tmp: Path) -> set[int]:
    """Reads ``src[:cut]``: exactly the frames that lie whole before the cut, byte for byte, and the file's end
    reported. Returns those frames."""
    whole = _whole_frames(src, cut)
    frames, stream = frames_of(_cut(src, cut, tmp))
    assert sorted(frames) == sorted(whole), (cut, sorted(frames), sorted(whole), stream.report())
    for k, msgs in frames.items():
        assert msgs == reference[k], (cut, k)
    assert stream.missing() == [k for k in range(FRAMES) if k not in whole], (cut, stream.report())
    text = stream.truncated or ""
    assert "the file is truncated" in text and "the file ends inside a chunk record" in text, text
    if whole:
        assert "complete messages before the cut were read" in text, text
    return whole


def test_a_copy_cut_inside_a_closed_zstd_chunk_keeps_the_frames_before_the_cut(
    dense: tuple[Path, dict[int, dict[str, bytes]]], tmp_path: Path
) -> None:
    run_dir, reference = dense
    src = run_dir / "dense.mcap"
    read = [_check_cut(src, reference, cut, tmp_path) for cut in _cuts(src)]
    assert [len(w) for w in read[:2]] == [0, 0]  # cut in the header or the first zstd block: nothing decodes
    assert all(read[2:]) and read[-1] == set(range(FRAMES - 1)), read  # the last frame is in the last zstd block
    # the command line says how many were read, and where the file ends
    cut = _cuts(src)[-2]
    code, out, err = cli_main("info", str(tmp_path / f"dense_{cut}.mcap"))
    assert code == 0 and "Traceback" not in err
    said = " ".join(out.split())  # (the console wraps its lines at 80 columns, where the byte counts put them)
    assert f"{len(read[-2])} of {FRAMES} frames read" in said and "ends inside a chunk record" in said, out


@pytest.mark.parametrize("compression", ["lz4", "none"])
def test_a_copy_cut_inside_an_lz4_or_uncompressed_chunk_keeps_the_frames_before_the_cut(
    dense: tuple[Path, dict[int, dict[str, bytes]]], tmp_path: Path, compression: str
) -> None:
    run_dir, reference = dense
    src = _one_chunk(run_dir / "dense.mcap", tmp_path / f"{compression}.mcap", compression)
    assert frames_of(src)[0] == reference
    cuts = _cuts(src)
    read = [_check_cut(src, reference, cut, tmp_path) for cut in cuts[:-1]]
    assert all(read[2:]) and len(read[-1]) >= FRAMES - 1, read
    if compression == "lz4":  # cut in the stream's end mark: every record is there, and checked against the CRC
        frames, stream = frames_of(_cut(src, cuts[-1], tmp_path))
        assert frames == reference and "every record of the chunk was read, its CRC checks" in (stream.truncated or "")
    else:
        assert _check_cut(src, reference, cuts[-1], tmp_path) == set(range(FRAMES - 1))


def test_a_damaged_chunk_that_is_not_cut_off_is_still_skipped(
    dense: tuple[Path, dict[int, dict[str, bytes]]], tmp_path: Path
) -> None:
    """Flipped bytes in a chunk the file holds in full: its CRC fails and it is skipped whole, as before; so is a cut
    copy whose chunk's header disagrees with its record length."""
    run_dir, _reference = dense
    src = run_dir / "dense.mcap"
    ((start, end),) = chunk_spans(src)
    data = bytearray(src.read_bytes())
    data[end - 500] ^= 0x21
    bad = tmp_path / "flipped.mcap"
    bad.write_bytes(bytes(data))
    frames, stream = frames_of(bad)
    assert frames == {} and f"bytes {start}..{end} (frames 0..5): damaged chunk, skipped" in (stream.truncated or "")
    # a copy cut inside the chunk whose header disagrees with the chunk's record length: not read
    clen = struct.unpack_from("<I", data, start + 9 + 28)[0]
    data[start + 9 + 32 + clen] ^= 0x01  # the compressed data's length
    cut = tmp_path / "header.mcap"
    cut.write_bytes(bytes(data[: end - 175]))
    frames, stream = frames_of(cut)
    assert frames == {} and "ends inside a chunk record" in (stream.truncated or ""), stream.truncated


def test_recover_keeps_the_frames_before_a_cut_inside_a_closed_chunk(
    dense: tuple[Path, dict[int, dict[str, bytes]]], tmp_path: Path
) -> None:
    run_dir, reference = dense
    src = run_dir / "dense.mcap"
    ((_start, end),) = chunk_spans(src)
    folder = shutil.copytree(run_dir, tmp_path / "run")
    (folder / "dense.mcap").unlink()
    partial = folder / "dense.mcap.partial"
    partial.write_bytes(src.read_bytes()[: end - 175])
    whole = _whole_frames(src, end - 175)
    assert whole
    code, out, err = cli_main("recover", str(folder))
    assert code == 0, err
    assert f"recovered {len(whole)} of {FRAMES} frames" in out, out
    frames, _stream = frames_of(folder / "dense.mcap")
    assert frames == {k: reference[k] for k in whole}
