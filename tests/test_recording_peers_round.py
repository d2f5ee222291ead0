"""An ``mmusv run`` recording as a Foxglove / robotics-tools user reads it, with other people's code (a helper's
round): the official ``mcap`` reader (its record stream, its indexed and time-ordered reads), ``mcap-protobuf-support``
and ``zstandard``, then mmusv's own reader and ``mmusv info`` on the same file cut and damaged.

What was checked (``tests/test_recording_round.py`` already checks the statistics, CRCs, schemas, timestamps, the
``/tf`` tree, the metadata and mmusv's reader against an independent decode; this adds what it leaves out):

* The indexes a seeking reader trusts, on the real recorder's output (80 frames of a 32-channel LiDAR, two 4 MiB
  chunks with frame 43 split across them): every chunk index equals its chunk's header and names its message
  indexes by their offsets and total length; every message index lists exactly the (log time, offset) of its
  channel's messages in the decompressed chunk; each chunk's start and end times are its messages' first and last;
  the summary offsets point at their groups, the metadata indexes at their records. The peer's time-ordered read
  (forward and reverse) is file order, its decoded messages are mmusv's, and its indexed read of the split frame
  (``starting_at``/``ending_before`` one log time) gives all five topics; 400 messages in all, as the statistics say.
* The same file cut at every kind of record boundary (inside the header, after it, inside the metadata, inside
  a chunk, inside a message index, before and after the data end, inside the summary and the footer, the last
  byte): ``summary`` never says ``complete``, every message mmusv reads is the peer's message at that place, and
  ``mmusv info`` warns in one line naming the file, without a traceback.

Found and fixed (each test below failed before):

* A damaged chunk (its CRC, or one bit of its data) was reported twice: once rightly, then as "the data section's
  CRC does not match: bytes outside the chunks (metadata, indexes) were changed", a false statement (the data
  section's CRC covers the chunk's bytes too, so the damaged chunk alone breaks it). The data section's CRC is now
  blamed on the bytes outside the chunks only when every chunk checked out (``mmusv.recording.scan``).
* A recording cut inside its MCAP header (8 to 35 bytes of a real one) was "an MCAP file not written by mmusv run":
  which program wrote it cannot be told. ``mmusv info`` now says the file ends inside its header.
* A recording cut inside its first 8 bytes (the magic) was "not an MCAP file (it does not start with the MCAP
  magic bytes)", though it starts with as many of them as it has; now "cut off inside the MCAP magic bytes".
* A whole, undamaged MCAP file written with the ``Recording`` API (its header says mmusv) but without the scenario
  and sensors metadata of ``mmusv run`` was said to have "mmusv metadata [that] cannot be read", as if damaged;
  it is now what it is, an MCAP file not written by ``mmusv run``.
* One frame missing was "79 of 80 frames read; frames 79 missing", read as a count, and ``mmusv recover`` said
  "recovered 1 of 80 frames (frames 0)": one frame is now "frame 79" (``mmusv.recording.stream.frames_text``).
* A frame with an empty message (whole bytes, 0 of them for one message: a peer tool's or a writer's fault) was
  named or counted wrongly: an empty ``/world/state`` decodes to frame 0, so the frame left out was reported as
  "frame 0" (which was read) instead of its own index; an empty LiDAR cloud left its frame out of ``mmusv convert``
  while ``mmusv info``, which does not decode the clouds, counted it ("80 frames"). Every reader of the frames now
  leaves such a frame out alike and names it by its log time (``mmusv.recording.stream``).
* A valid MCAP copy whose messages are not in frame order (written channel by channel, as a tool that copies topic
  by topic leaves them) was read as pieces of frames: ``mmusv info`` said every frame was read beside hundreds of
  "incomplete frames left out", ``mmusv convert`` found no complete frame. The reader now stops with an error
  naming the file, the frame whose messages are apart and how to rewrite it in log-time order; a frame recorded
  twice, each copy whole, is still read once (``tests/export/test_convert.py``).
* ``mmusv convert`` of such a whole file said "skipped frames 79..79: lost from the recording (run complete: 80 of
  80 frames written)": now "skipped frame 79: in the recording but incomplete: its /u/lidar message is ..."
  (``mmusv.export.conversion``, ``convert_report``).
* A whole recording followed by padding (4096 zero bytes after its closing magic, as a copy written in whole
  blocks leaves it) was "truncated: ... the summary section after the data is cut off or damaged"; it now says how
  many bytes follow the end of the MCAP file and that the recording is whole before them (``mmusv.recording.scan``;
  the official ``make_reader`` cannot open it at all).
* ``mmusv recover`` on a run folder whose ``.mcap`` is a copy cut short, or has a damaged chunk, beside whole tables
  said "nothing to recover: dense.mcap is finished and its tables are whole" without reading the recording; it now
  reads it through and says what it lacks (``mmusv.recording.recover``). A recording without run metadata that is
  not a ``.partial`` is no longer only "the run did not finish": its copy may be cut before its end.
* A recording finished by ``mmusv recover`` held its scenario, manifest and sensors metadata after every message
  (a run writes them before its first chunk), so a copy of it cut short held no readable frame; they now come first.
* ``mmusv info`` gave a damaged recording of a complete run the status "complete", alone beside "43 of 80 frames"
  (and so did a folder's overview in its status column): now "complete (file damaged)".

Reported here and added since in the core's recorder: a ``foxglove.CameraCalibration`` beside the camera images (the
intrinsics were only in the ``sensors`` metadata, so the 3D panel could not project them) and
``foxglove.ImageAnnotations`` for the 2D boxes (only in ``mmusv.AgentAnnotations``;
``tests/test_recording_foxglove_round.py``). Also reported and fixed since: a file finished by ``mmusv recover`` had
no data-section CRC (the official Python writer leaves it 0 unless asked), so changes outside its chunks went
unseen. Also reported and fixed since: the recorder defined every schema and channel only inside the chunk of its
first message, so a file without a readable summary (a killed run's ``.partial``, a copy cut short) whose first
chunk was damaged lost every frame, the whole chunks after it included (one flipped bit in the 80-frame file's first
chunk: 0 of 80 frames, where 36 are intact); the first frame's schemas and channels now come in a small chunk of
their own before its messages (:func:`test_a_damaged_first_frame_chunk_loses_its_own_frames_alone`).
"""

from __future__ import annotations

import collections
import contextlib
import io
import struct
import zlib
from pathlib import Path
from typing import Any

import pytest
import zstandard
from mcap.reader import make_reader
from mcap.records import (
    Attachment,
    AttachmentIndex,
    Chunk,
    ChunkIndex,
    DataEnd,
    Footer,
    MessageIndex,
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
    SummaryOffset,
)
from mcap.records import Channel as ChannelRecord
from mcap.stream_reader import StreamReader
from mcap_protobuf.decoder import DecoderFactory
from tiny_scenario import lidar_scenario

MESSAGE = 0x05
GROUPS = {0x03: Schema, 0x04: ChannelRecord, 0x08: ChunkIndex, 0x0A: AttachmentIndex, 0x0B: Statistics}
GROUPS[0x0D] = MetadataIndex


@pytest.fixture(scope="module")
def dense(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """80 frames of a 32-channel LiDAR: two chunks of the real recorder, frame 43 split between them."""
    from mmusv.acquire import run

    out = tmp_path_factory.mktemp("dense")
    return Path(run(lidar_scenario("dense", frames=80, dense=True), out_dir=out).recording)


def _records(data: bytes) -> list[tuple[int, int, Any]]:
    """``(start, end, record)`` of every record of an MCAP file, chunks undecoded, CRCs checked by the peer."""
    f = io.BytesIO(data)
    out, start = [], 8
    for rec in StreamReader(f, emit_chunks=True, validate_crcs=True).records:
        out.append((start, f.tell(), rec))
        start = f.tell()
    return out


def _inner(chunk: Chunk) -> list[tuple[int, int, bytes]]:
    """``(offset, opcode, body)`` of every record in a chunk, decompressed with ``zstandard``."""
    assert chunk.compression == "zstd"
    raw = zstandard.ZstdDecompressor().decompress(chunk.data, max_output_size=chunk.uncompressed_size)
    assert len(raw) == chunk.uncompressed_size and zlib.crc32(raw) == chunk.uncompressed_crc
    out, pos = [], 0
    while pos < len(raw):
        op, n = raw[pos], struct.unpack_from("<Q", raw, pos + 1)[0]
        out.append((pos, op, raw[pos + 9 : pos + 9 + n]))
        pos += 9 + n
    assert pos == len(raw)
    return out


def _cli(*args: str) -> tuple[int, str, str]:
    from mmusv.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(args))
    return code, " ".join(out.getvalue().split()), err.getvalue()


# ---------------------------------------------------------------------------------------------- the indexes


def test_every_index_points_at_the_records_it_indexes(dense: Path) -> None:
    data = dense.read_bytes()
    recs = _records(data)
    at = {start: (end, rec) for start, end, rec in recs}
    chunks = [(s, e, r) for s, e, r in recs if isinstance(r, Chunk)]
    index = {r.chunk_start_offset: r for _s, _e, r in recs if isinstance(r, ChunkIndex)}
    assert len(chunks) == len(index) == 3
    counts: collections.Counter[int] = collections.Counter()
    for k, (start, end, chunk) in enumerate(chunks):
        ci = index[start]
        assert ci.chunk_length == end - start
        assert (ci.message_start_time, ci.message_end_time) == (chunk.message_start_time, chunk.message_end_time)
        assert (ci.compression, ci.compressed_size) == (chunk.compression, len(chunk.data))
        assert ci.uncompressed_size == chunk.uncompressed_size
        if k == 0:  # the first frame's schemas and channels alone, in a chunk of their own before its messages
            ops = [op for _pos, op, _body in _inner(chunk)]
            assert set(ops) == {0x03, 0x04} and ops.count(0x04) == 5 and not ci.message_index_offsets, ops
            continue
        listed: dict[int, list[tuple[int, int]]] = collections.defaultdict(list)
        for pos, op, body in _inner(chunk):
            if op == MESSAGE:
                channel, _seq, log_time, publish_time = struct.unpack_from("<HIQQ", body)
                assert publish_time == log_time
                listed[channel].append((log_time, pos))
                counts[channel] += 1
        times = [t for entries in listed.values() for t, _ in entries]
        assert (min(times), max(times)) == (chunk.message_start_time, chunk.message_end_time)
        after = range(end, end + ci.message_index_length)
        indexes = [(s, e, r) for s, e, r in recs if isinstance(r, MessageIndex) and s in after]
        assert {r.channel_id: s for s, _e, r in indexes} == ci.message_index_offsets
        assert indexes[-1][1] - end == ci.message_index_length
        assert {r.channel_id: sorted(r.records) for _s, _e, r in indexes} == {c: sorted(v) for c, v in listed.items()}
    reader = make_reader(io.BytesIO(data))
    summary = reader.get_summary()
    assert summary is not None and summary.statistics is not None
    assert summary.statistics.channel_message_counts == dict(counts) and sum(counts.values()) == 400
    footer = recs[-1][2]
    assert isinstance(footer, Footer)
    offsets = [r for _s, _e, r in recs if isinstance(r, SummaryOffset)]
    assert {o.group_opcode for o in offsets} == {0x03, 0x04, 0x08, 0x0B, 0x0D}
    for o in offsets:
        group = [(s, e) for s, e, r in recs if s >= footer.summary_start and isinstance(r, GROUPS[o.group_opcode])]
        assert (o.group_start, o.group_length) == (group[0][0], group[-1][1] - group[0][0])
    for m in summary.metadata_indexes:
        end, rec = at[m.offset]
        assert isinstance(rec, Metadata) and (rec.name, end - m.offset) == (m.name, m.length)
    assert not summary.attachment_indexes and not any(isinstance(r, Attachment) for _s, _e, r in recs)
    assert any(isinstance(r, DataEnd) for _s, _e, r in recs)


def test_the_peers_ordered_and_indexed_reads_are_mmusvs_messages(dense: Path) -> None:
    from mmusv.recording import read_messages

    with dense.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        in_file = [(c.topic, m.log_time, m.data) for _s, c, m in reader.iter_messages(log_time_order=False)]
        ordered = [(c.topic, m.log_time, m.data) for _s, c, m in reader.iter_messages(log_time_order=True)]
        backwards = [(c.topic, m.log_time, m.data) for _s, c, m in reader.iter_messages(reverse=True)]
        decoded = [(c.topic, m.log_time, d.SerializeToString()) for _s, c, m, d in reader.iter_decoded_messages()]
        split = 43 * 200_000_000  # frame 43 at 5 Hz: its messages are in both chunks
        window = [c.topic for _s, c, _m in reader.iter_messages(starting_at=split, ending_before=split + 1)]
    assert in_file == ordered and len(in_file) == 400
    assert sorted(backwards) == sorted(ordered) and [lt for _t, lt, _d in backwards] == sorted(
        (lt for _t, lt, _d in ordered), reverse=True
    )
    assert sorted(window) == ["/tf", "/u/annotations", "/u/boxes", "/u/lidar", "/world/state"]
    assert [(t, lt, m.SerializeToString()) for t, lt, m in read_messages(dense)] == decoded


# ---------------------------------------------------------------------------------------------- cut and damaged


def _cuts(data: bytes) -> dict[str, int]:
    recs = _records(data)

    def first(kind: type, k: int = 0) -> tuple[int, int]:
        return [(s, e) for s, e, r in recs if isinstance(r, kind)][k]

    chunk, index = first(Chunk), first(MessageIndex)
    return {
        "inside the header": 20,
        "after the header": 8 + 9 + struct.unpack_from("<Q", data, 9)[0],
        "inside the second metadata record": first(Metadata, 1)[0] + 20,
        "after the metadata": first(Metadata, 2)[1],
        "inside the first chunk": chunk[0] + 5000,
        "after the first chunk": chunk[1],
        "inside a message index": index[0] + 10,
        "before the data end": first(DataEnd)[0],
        "after the data end": first(DataEnd)[1],
        "inside the summary": first(ChunkIndex)[0] + 3,
        "before the footer": first(Footer)[0],
        "inside the closing magic": len(data) - 4,
        "one byte short": len(data) - 1,
    }


def test_a_recording_cut_anywhere_is_never_called_complete(dense: Path, tmp_path: Path) -> None:
    from mmusv.recording import read_messages, summary

    data = dense.read_bytes()
    with dense.open("rb") as f:
        peer = [(c.topic, m.log_time, m.data) for _s, c, m in make_reader(f).iter_messages(log_time_order=False)]
    for where, size in _cuts(data).items():
        cut = tmp_path / f"{where.replace(' ', '_')}.mcap"
        cut.write_bytes(data[:size])
        got = summary(cut)
        assert not got["complete"] and got["damage"], where
        damage: list[str] = []
        ours = [(t, lt, m.SerializeToString()) for t, lt, m in read_messages(cut, damage=damage)]
        assert ours == peer[: len(ours)] and damage, where
        code, out, err = _cli("info", str(cut))
        assert not err and "mmusv: warning: " in out, (where, out, err)
        assert "Traceback" not in out and code == (0 if got["frames"] and got["frames"]["read"] else 1), where


def _damaged(data: bytes, chunk: int, *, field: bool) -> bytes:
    """``data`` with the chunk ``chunk`` of those that hold messages damaged (the first one holds the first frame's
    schemas and channels alone): its stored CRC changed (``field``), else one bit in its data."""
    chunks = [(s, e, r) for s, e, r in _records(data) if isinstance(r, Chunk)]
    start, end, rec = [(s, e, r) for s, e, r in chunks if any(op == MESSAGE for _p, op, _b in _inner(r))][chunk]
    out = bytearray(data)
    if field:  # opcode, length, start and end times, uncompressed size, then the CRC
        out[start + 33 : start + 37] = struct.pack("<I", rec.uncompressed_crc ^ 1)
    else:
        out[(start + end) // 2] ^= 0x40
    return bytes(out)


def test_a_damaged_first_frame_chunk_loses_its_own_frames_alone(dense: Path, tmp_path: Path) -> None:
    """A copy without its summary (cut where the data section ends, as a killed run's ``.partial`` has none) whose
    first chunk of messages has one flipped bit: the frames whose messages all lie in the chunks after it are read,
    the same messages as the intact file's (found here from the chunks' own records, decompressed with
    ``zstandard``). With the channels defined beside frame 0's first messages, not one frame was read."""
    from mmusv.recording import read_messages, summary

    data = dense.read_bytes()
    recs = _records(data)
    chunks = [r for _s, _e, r in recs if isinstance(r, Chunk)]
    times = [{struct.unpack_from("<HIQ", b)[2] for _p, op, b in _inner(c) if op == MESSAGE} for c in chunks]
    times = [t for t in times if t]
    assert len(times) == 2
    kept = sorted(times[1] - times[0])  # frames wholly in the second chunk of messages
    data_end = next(s for s, _e, r in recs if isinstance(r, DataEnd))
    path = tmp_path / "damaged.mcap"
    path.write_bytes(_damaged(data, 0, field=False)[:data_end])
    got = summary(path)
    assert got["frames"]["read"] == len(kept) == 36 and got["damage"], got
    with dense.open("rb") as f:
        peer = [(c.topic, m.log_time, m.data) for _s, c, m in make_reader(f).iter_messages(log_time_order=False)]
    ours = [(t, lt, m.SerializeToString()) for t, lt, m in read_messages(path, damage=[]) if lt in kept]
    assert ours == [p for p in peer if p[1] in kept] and len(ours) == 5 * len(kept)


@pytest.mark.parametrize("field", [True, False], ids=["its CRC", "a bit of its data"])
def test_a_damaged_chunk_is_not_also_blamed_on_the_bytes_outside_the_chunks(
    dense: Path, tmp_path: Path, field: bool
) -> None:
    """The data section's CRC covers the chunks' bytes too: it was reported as "bytes outside the chunks
    (metadata, indexes) were changed" beside every damaged chunk."""
    from mmusv.recording import summary

    path = tmp_path / "damaged.mcap"
    path.write_bytes(_damaged(dense.read_bytes(), 1, field=field))
    got = summary(path)
    assert not got["complete"] and got["frames"]["read"] == 43, got["frames"]
    assert len(got["damage"]) == 1 and "damaged chunk, skipped: CRC mismatch" in got["damage"][0], got["damage"]
    code, out, _err = _cli("info", str(path))
    assert code == 0 and "CRC mismatch" in out and "outside the chunks" not in out, out
    # a change outside the chunks is still named so
    data = dense.read_bytes()
    changed = tmp_path / "changed.mcap"
    status = data.rindex(b"complete")  # the run metadata's status
    changed.write_bytes(data[:status] + b"c0mplete" + data[status + 8 :])
    got = summary(changed)
    assert not got["complete"] and got["frames"]["read"] == 80
    assert ["outside the chunks (metadata, indexes) were changed" in line for line in got["damage"]] == [True]


# ---------------------------------------------------------------------------------------------- what a file is called


@pytest.mark.parametrize("size", [12, 20, 35])
def test_a_recording_cut_inside_its_header_is_not_called_another_programs(
    dense: Path, tmp_path: Path, size: int
) -> None:
    """It was "an MCAP file not written by mmusv run": the header that says which program wrote it is cut off."""
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(dense.read_bytes()[:size])
    code, out, err = _cli("info", str(cut))
    assert code == 1 and not err, (out, err)
    assert "not written by mmusv run" not in out and f"{cut}: the file ends inside its MCAP header" in out, out


@pytest.mark.parametrize("size", [1, 4, 7])
def test_a_recording_cut_inside_its_magic_is_said_to_be_cut(dense: Path, tmp_path: Path, size: int) -> None:
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(dense.read_bytes()[:size])
    code, _out, err = _cli("info", str(cut))
    assert code == 2 and err == (
        f"mmusv: error: {cut} is cut off inside the MCAP magic bytes ({size} of 8): not a readable MCAP recording\n"
    ), err
    code, _out, err = _cli("info", str(dense.parent / "scenario.yaml"))
    assert code == 2 and "does not start with the MCAP magic bytes" in err, err


def test_a_whole_file_of_the_recording_api_is_not_called_damaged(tmp_path: Path) -> None:
    """Its header says mmusv (the ``Recording`` API writes it too), so a file without ``mmusv run``'s metadata
    was said to have mmusv metadata that "cannot be read", as if it were damaged."""
    import numpy as np
    from mmusv.recording import Recording, summary

    path = tmp_path / "api.mcap"
    with Recording(path) as rec:
        rec.raw_image("/img", log_time_ns=0, frame_id="c", image=np.zeros((2, 2), np.uint8))
    got = summary(path)
    assert got["complete"] and got["frames"] is None and "metadata_problem" not in got, got
    code, out, _err = _cli("info", str(path))
    assert code == 0 and "an MCAP file not written by mmusv run (no scenario/sensors metadata)" in out, out
    assert "cannot be read" not in out, out


def test_one_frame_is_named_as_one_frame_not_as_a_count(dense: Path, tmp_path: Path) -> None:
    """A report of "79 of 80 frames read; frames 79 missing" read as 79 frames missing, and "recovered 1 of 80
    frames (frames 0)" likewise: one frame is now "frame 79", "frame 0"."""
    from mcap_rechunk import emptied, killed_copy
    from mmusv.recording import read_info
    from mmusv.recording.stream import FrameStream

    path = emptied(dense, "/u/lidar", 79, tmp_path / "dense.mcap")  # a LiDAR cloud without points: incomplete
    stream = FrameStream(read_info(path), want=lambda _t: True)
    assert [fr.index for fr in stream][-1] == 78
    report = stream.report()
    assert report is not None and report.startswith(f"{path}: 79 of 80 frames read; frame 79 missing;"), report
    run = tmp_path / "run"
    run.mkdir()
    (run / "scenario.yaml").write_bytes((dense.parent / "scenario.yaml").read_bytes())
    killed_copy(dense, run / "dense.mcap.partial", messages=7)  # frame 0 whole, frame 1 cut short
    code, out, err = _cli("recover", str(run))
    assert code == 0 and "recovered 1 of 80 frames (frame 0) from" in out, (out, err)


def test_a_frame_with_an_empty_message_is_named_by_its_index_and_counted_alike_everywhere(
    dense: Path, tmp_path: Path
) -> None:
    """Bytes whole (every CRC matches) but one message empty (0 bytes, a peer tool's or a writer's fault): an empty
    ``/world/state`` decodes to frame 0, and the frame left out was called "frame 0" (which was read) instead of
    frame 5; an empty LiDAR cloud left its frame out of ``mmusv convert`` but ``mmusv info`` (which does not
    decode the clouds) counted it, "80 frames"."""
    from mcap_rechunk import emptied
    from mmusv.recording import read_info, summary
    from mmusv.recording.stream import FrameStream

    path = emptied(dense, "/world/state", 5, tmp_path / "state" / "dense.mcap")
    for want in (lambda _t: False, lambda _t: True):
        stream = FrameStream(read_info(path), want=want)
        assert 5 not in [fr.index for fr in stream] and [k for k, _why in stream.incomplete] == [5]
    report = summary(path)["frames"]["report"]
    assert "frame 5 missing; incomplete frames left out: frame 5 (its /world/state message" in report, report
    path = emptied(dense, "/u/lidar", 79, tmp_path / "lidar" / "dense.mcap")
    for want in (lambda _t: False, lambda _t: True):
        stream = FrameStream(read_info(path), want=want)
        assert [fr.index for fr in stream] == list(range(79)) and [k for k, _why in stream.incomplete] == [79]
    got = summary(path)["frames"]
    assert got["read"] == 79 and "frame 79 (its /u/lidar message is empty (0 bytes))" in got["report"], got


def _reordered(src: Path, out: Path, key: Any) -> Path:
    """``src`` written again by the official writer with its messages in the order of ``key(topic, log_time)``."""
    from mcap.writer import Writer
    from mcap_rechunk import write_records

    with src.open("rb") as f:
        reader = make_reader(f)
        meta = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
        msgs = sorted(reader.iter_messages(), key=lambda t: key(t[1].topic, t[2].log_time))
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("wb") as g:
        w = Writer(g)
        write_records(w, meta, msgs)
        w.finish()  # type: ignore[no-untyped-call]
    return out


@pytest.mark.parametrize("first", ["/tf", "/world/state"])
def test_a_copy_written_topic_by_topic_is_refused_not_read_in_pieces(dense: Path, tmp_path: Path, first: str) -> None:
    """A valid MCAP may hold its messages in any order; one copied channel by channel (every /tf, then every world
    state, ...) was read as pieces of frames: ``mmusv info`` said every frame was read beside "incomplete frames
    left out: frame 0 (it has no /world/state message) ...", and ``mmusv convert`` found "no complete frame" (or
    frames without sensors). It is now an error that says what is wrong and how to mend it."""
    from mmusv.recording import summary

    path = _reordered(dense, tmp_path / "by_topic" / "dense.mcap", lambda t, lt: (t != first, t, lt))
    code, out, err = _cli("info", str(path))
    assert code == 2 and not out and err.startswith(f"mmusv: error: {path}: the messages of the frame at 0.000 s"), err
    assert "not in log-time order" in err and "iter_messages(log_time_order=True)" in err, err
    # sorted back into log-time order by the peer, it is the recording's 80 frames
    again = _reordered(path, tmp_path / "sorted" / "dense.mcap", lambda _t, lt: lt)
    got = summary(again)["frames"]
    assert (got["read"], got["report"]) == (80, None), got


def test_convert_names_one_skipped_frame_and_why_it_is_incomplete(dense: Path, tmp_path: Path) -> None:
    """It said "skipped frames 79..79: lost from the recording (run complete: 80 of 80 frames written)" of a frame
    that is in the whole file, its LiDAR message empty."""
    from mcap_rechunk import emptied

    path = emptied(dense, "/u/lidar", 79, tmp_path / "lidar" / "dense.mcap")
    code, out, err = _cli("convert", str(path), "--to", "kitti", "-o", str(tmp_path / "kitti"), "--no-progress")
    assert code == 0 and "79 frames" in out, (out, err)
    assert "skipped frame 79: in the recording but incomplete: its /u/lidar message is" in out, out
    assert "79..79" not in out and "lost from the recording" not in out, out


def test_bytes_after_the_end_of_a_whole_recording_are_not_called_a_cut(dense: Path, tmp_path: Path) -> None:
    """A copy padded after its closing magic (a tool that writes whole blocks): every record is there, yet it was
    "truncated: ... the summary section after the data is cut off or damaged"."""
    from mmusv.recording import summary

    data = dense.read_bytes()
    path = tmp_path / "padded.mcap"
    path.write_bytes(data + bytes(4096))
    got = summary(path)
    assert not got["complete"] and got["frames"]["read"] == 80, got["frames"]
    assert got["damage"] == [
        f"the file is damaged at bytes {len(data)}..{len(data) + 4096}: 4096 bytes follow the end of the MCAP file "
        f"(its footer and closing magic end at byte {len(data)}): not part of the recording, whole before them"
    ], got["damage"]


@pytest.mark.parametrize("damage", ["cut", "chunk"])
def test_recover_does_not_call_a_cut_or_damaged_recording_finished(dense: Path, tmp_path: Path, damage: str) -> None:
    """``mmusv recover`` on a run folder whose recording is a copy cut short (or has a damaged chunk) and whose
    tables are whole said "nothing to recover: dense.mcap is finished and its tables are whole", without reading
    the recording."""
    import shutil

    run = shutil.copytree(dense.parent, tmp_path / "run")
    data = dense.read_bytes()
    (run / dense.name).write_bytes(data[:3_000_000] if damage == "cut" else _damaged(data, 1, field=False))
    code, _out, err = _cli("recover", str(run))
    assert code == 2 and "is finished" not in err, err
    assert err.startswith(f"mmusv: error: nothing to recover in {run}: the tables of dense.mcap are whole, but "), err
    said = {
        "cut": "48 of 80 frames read; frames 48..79 missing (the run did not finish, or this copy is cut before its "
        "end (no run metadata))",
        "chunk": "43 of 80 frames read; frames 43..79 missing;",
    }
    assert said[damage] in err and "does not mend a damaged recording" in err, err
    code, _out, err = _cli("recover", str(dense.parent))  # a whole one still is
    assert code == 2 and "dense.mcap is finished and its tables are whole" in err, err


def test_a_recovered_recording_keeps_its_metadata_before_its_frames(dense: Path, tmp_path: Path) -> None:
    """``mmusv run`` writes the scenario, manifest and sensors metadata before the first chunk, so that a copy cut
    short still reads up to the cut; ``mmusv recover`` wrote them after every message, and a recovered recording
    cut short held no frame ("has no scenario/sensors metadata; was it written by mmusv run?")."""
    from mcap_rechunk import killed_copy
    from mmusv.recording import summary

    run = tmp_path / "run"
    run.mkdir()
    (run / "scenario.yaml").write_bytes((dense.parent / "scenario.yaml").read_bytes())
    killed_copy(dense, run / "dense.mcap.partial", messages=300)  # frames 0..59
    code, out, err = _cli("recover", str(run))
    assert code == 0 and "recovered 60 of 80 frames (frames 0..59)" in out, (out, err)
    data = (run / "dense.mcap").read_bytes()
    kinds = [type(r).__name__ for _s, _e, r in _records(data)]
    assert kinds[:4] == ["Header", "Metadata", "Metadata", "Metadata"] and kinds.count("Metadata") == 4, kinds
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    got = summary(cut)
    assert got["frames"] is not None and 0 < got["frames"]["read"] < 60 and not got["complete"], got


def test_a_recovered_recording_has_its_data_sections_crc(dense: Path, tmp_path: Path) -> None:
    """``mmusv recover`` wrote its file with the official Python writer, which leaves the data section's CRC 0
    unless asked: a change outside the chunks of a recovered recording (its metadata) went unseen. The CRC is now
    the data section's (zlib's CRC-32 of every byte from the magic to the data end record, written out here), and
    a changed metadata byte is reported."""
    from mcap_rechunk import killed_copy
    from mmusv.recording import summary

    run = tmp_path / "run"
    run.mkdir()
    (run / "scenario.yaml").write_bytes((dense.parent / "scenario.yaml").read_bytes())
    killed_copy(dense, run / "dense.mcap.partial", messages=300)
    code, _out, err = _cli("recover", str(run))
    assert code == 0, err
    data = (run / "dense.mcap").read_bytes()
    (start, _end, end_record) = next((s, e, r) for s, e, r in _records(data) if isinstance(r, DataEnd))
    assert end_record.data_section_crc == zlib.crc32(data[:start]) != 0
    assert summary(run / "dense.mcap")["complete"]
    changed = tmp_path / "changed.mcap"
    at = data.index(b"dense")  # the scenario metadata's text, outside every chunk
    changed.write_bytes(data[:at] + b"Dense" + data[at + 5 :])
    got = summary(changed)
    assert not got["complete"] and any("outside the chunks" in line for line in got["damage"]), got["damage"]


def test_info_does_not_call_a_damaged_recording_of_a_complete_run_complete(dense: Path, tmp_path: Path) -> None:
    """The run's status, "complete", stood alone beside "43 of 80 frames" (``mmusv info`` on the file) and in the
    status column of a folder's overview, for a file with a damaged chunk or bytes after its end."""
    import shutil

    data = dense.read_bytes()
    for name, damaged in (("chunk", _damaged(data, 1, field=True)), ("padded", data + bytes(4096))):
        run = shutil.copytree(dense.parent, tmp_path / "runs" / name)
        (run / dense.name).write_bytes(damaged)
        code, out, _err = _cli("info", str(run / dense.name))
        assert code == 0 and f"{run / dense.name}: scenario dense, status complete (file damaged), " in out, out
    code, out, _err = _cli("info", str(tmp_path / "runs"))
    for name in ("chunk", "padded"):
        assert f"│ {name}/dense.mcap │ dense │ complete (file damaged) │" in out, out
    code, out, _err = _cli("info", str(dense))
    assert code == 0 and "status complete, 80 frames" in out, out
