"""Walking the records of an MCAP file that may be damaged: the ground floor of the reader
(:mod:`mmusv.recording.info`, :mod:`mmusv.recording.stream`, :mod:`mmusv.recording.messages`,
:mod:`mmusv.recording.contents`).

:class:`Scan` reads one file front to back, record by record, with plain reads (no memory map: a file that
shrinks under a reader must not crash it) and never trusts a length it has not checked against the file size:

- every chunk is decompressed into at most its stated size (bounded by :data:`MAX_CHUNK_BYTES`) and its CRC of
  the uncompressed records is checked; a chunk that fails (CRC mismatch, bad compression, records that do not
  parse) is skipped and reported as a :class:`Damage`, and the walk goes on after it, so the frames after a
  damaged chunk are kept;
- a record whose header is garbage (an unknown opcode, a length running past the end of the file) is skipped by
  searching forward for the next record that checks out in full (a chunk, metadata, a message index or the data
  end, each with lengths that agree with each other); the bytes in between are one damaged region;
- a file that ends inside a record (a killed writer, a ``.partial`` file, a truncated copy) yields everything
  before that record and reports where it ends; a chunk the file ends inside is read as far as its compressed
  stream and records are complete (zstd and lz4 decode whole blocks only; a record cut off is never read), without
  a CRC to check them against: the chunk the recorder was writing when it was killed (its length still the
  placeholder ``2**64 - 1``) and a closed chunk cut short (an interrupted copy, power loss after its length was
  filled in), whose header must then agree with its record length;
- the data section's CRC (in the data end record) is checked as well, so damage outside the chunks (metadata,
  message indexes) is reported too.

A reader that wants only some log times (one frame for a preview, ``convert --frames``) gives ``keep``: a chunk
whose messages all lie outside it is hopped over unread, when the file's summary (its CRC checked) holds every
schema and channel and indexes that chunk with the times its header gives (a file without a summary, e.g. a
``.partial`` file, is read in full; a chunk whose header disagrees with the index is read and checked). A chunk
hopped over is not checked, nor is the data section's CRC then; the chunks read are, each against its own CRC.

Schemas and channels come from the chunks as they appear and, when the file has a readable summary, from the
summary up front (so the messages of a channel whose defining chunk is damaged still decode).
"""

from __future__ import annotations

import io
import struct
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

__all__ = ["MAGIC", "MAX_CHUNK_BYTES", "Damage", "Scan"]

MAGIC = b"\x89MCAP0\r\n"
MAX_CHUNK_BYTES = 1 << 30
"""Largest uncompressed chunk a reader accepts (the recorder writes chunks of 4 MiB): a damaged size field can
never make it allocate more."""

_HEADER, _FOOTER, _SCHEMA, _CHANNEL, _MESSAGE, _CHUNK, _MESSAGE_INDEX = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07
_CHUNK_INDEX, _ATTACHMENT, _ATTACHMENT_INDEX, _STATISTICS, _METADATA = 0x08, 0x09, 0x0A, 0x0B, 0x0C
_METADATA_INDEX, _SUMMARY_OFFSET, _DATA_END = 0x0D, 0x0E, 0x0F
_NAMES = {
    _HEADER: "header",
    _FOOTER: "footer",
    _SCHEMA: "schema",
    _CHANNEL: "channel",
    _MESSAGE: "message",
    _CHUNK: "chunk",
    _MESSAGE_INDEX: "message index",
    _CHUNK_INDEX: "chunk index",
    _ATTACHMENT: "attachment",
    _ATTACHMENT_INDEX: "attachment index",
    _STATISTICS: "statistics",
    _METADATA: "metadata",
    _METADATA_INDEX: "metadata index",
    _SUMMARY_OFFSET: "summary offset",
    _DATA_END: "data end",
}
_BLOCK = 1 << 20
_OPEN = (1 << 64) - 1
"""The length of a chunk record while the ``mcap`` crate (the core's recorder) still writes it: the record is
streamed to the file and its lengths, times and CRC are filled in when the chunk is closed."""


class _Bad(Exception):
    """A record that does not check out (the message says why)."""


@dataclass(frozen=True)
class Damage:
    """A damaged or missing region of a file: bytes ``start .. end`` (``end`` = the file size for a file that ends
    inside a record), ``what`` happened, and the log times (ns) of the messages lost there when the damaged
    chunk's header still says so (``None`` otherwise; for a chunk the file ends inside whose first records were
    read, from the log time of the message cut off, or just after the last one read)."""

    start: int
    end: int
    what: str
    times: tuple[int, int] | None = None
    truncated: bool = False

    def describe(self, frequency_hz: float = 0.0) -> str:
        """One line: where, what, and which frames when known (``frequency_hz`` > 0)."""
        where = f"bytes {self.start}..{self.end}"
        frames = ""
        if self.times is not None and frequency_hz > 0:
            a, b = (round(t * frequency_hz / 1e9) for t in self.times)
            frames = f" (frame{'s' if a != b else ''} {a}{f'..{b}' if a != b else ''})"
        return f"{where}{frames}: {self.what}"


@dataclass
class _Cut:
    """What a chunk the file ends inside gave: its complete ``messages`` (in file order), whether it was ``whole``
    (every record decompressed and read, its CRC checked: the file ends in the compressed stream's last bytes) and
    the log time of the message record that is cut off, when its header was decompressed (``cut_time``)."""

    messages: list[Any]
    whole: bool = False
    cut_time: int | None = None


@dataclass
class _Chunk:
    start: int
    end: int
    usize: int
    crc: int
    compression: str
    data: bytes


def _u64(b: bytes, at: int) -> int:
    return int(struct.unpack_from("<Q", b, at)[0])


def _u32(b: bytes, at: int) -> int:
    return int(struct.unpack_from("<I", b, at)[0])


def _string(b: bytes, at: int) -> tuple[str, int]:
    n = _u32(b, at)
    if at + 4 + n > len(b):
        raise _Bad("a string runs past its record")
    return b[at + 4 : at + 4 + n].decode("utf-8"), at + 4 + n


def _parse_chunk(body: bytes) -> _Chunk:
    if len(body) < 40:
        raise _Bad(f"a chunk record of {len(body)} bytes is shorter than its fixed fields")
    start, end, usize, crc = struct.unpack_from("<QQQI", body, 0)
    clen = _u32(body, 28)
    if clen > 16 or 32 + clen + 8 > len(body):
        raise _Bad("the chunk's compression field is unreadable")
    compression = body[32 : 32 + clen].decode("ascii", errors="replace")
    rlen = _u64(body, 32 + clen)
    if 40 + clen + rlen != len(body):
        raise _Bad(f"the chunk's data length ({rlen}) does not match its record length ({len(body)})")
    return _Chunk(int(start), int(end), int(usize), int(crc), compression, body[40 + clen :])


def _decompress(c: _Chunk) -> bytes:
    if c.usize > MAX_CHUNK_BYTES:
        raise _Bad(f"the chunk says it holds {c.usize} bytes, more than any chunk mmusv writes")
    if c.compression == "zstd":
        import zstandard

        try:
            with zstandard.ZstdDecompressor().stream_reader(io.BytesIO(c.data), read_across_frames=True) as r:
                raw = r.read(c.usize + 1)
        except zstandard.ZstdError as exc:
            raise _Bad(f"its zstd data does not decompress ({exc})") from None
    elif c.compression == "lz4":
        import lz4.frame

        try:
            with lz4.frame.LZ4FrameFile(io.BytesIO(c.data), "rb") as r:
                raw = r.read(c.usize + 1)
        except (RuntimeError, EOFError, OSError) as exc:
            raise _Bad(f"its lz4 data does not decompress ({exc})") from None
    elif c.compression == "":
        raw = c.data
    else:
        raise _Bad(f"unknown compression {c.compression!r}")
    if len(raw) != c.usize:
        raise _Bad(f"it decompresses to {len(raw)} bytes, its header says {c.usize}")
    if c.crc != 0 and zlib.crc32(raw) != c.crc:
        raise _Bad("CRC mismatch: its records are not the bytes that were written")
    return raw


def _decompress_cut(compression: bytes, data: bytes, limit: int) -> bytes:
    """The records of a chunk whose compressed bytes ``data`` are cut short, as far as they decompress: the zstd or
    lz4 stream up to its last block that is there in full, uncompressed records as they are; at most ``limit``
    bytes (and :data:`MAX_CHUNK_BYTES`); nothing for an unknown compression."""
    limit = min(limit, MAX_CHUNK_BYTES)
    if compression == b"":
        return data[:limit]
    pieces: list[bytes] = []
    got = 0
    if compression == b"zstd":
        import zstandard

        try:
            with zstandard.ZstdDecompressor().stream_reader(io.BytesIO(data), read_across_frames=True) as r:
                while got < limit:
                    piece = r.read(min(1 << 16, limit - got))
                    if not piece:
                        break
                    pieces.append(piece)
                    got += len(piece)
        except zstandard.ZstdError:
            pass  # the stream ends where the file does: keep what decoded
    elif compression == b"lz4":
        import lz4.frame

        dec = lz4.frame.LZ4FrameDecompressor()
        try:
            for at in range(0, len(data), 1 << 16):
                if got >= limit or dec.eof:
                    break
                piece = dec.decompress(data[at : at + (1 << 16)], max_length=limit - got)
                pieces.append(piece)
                got += len(piece)
        except RuntimeError:
            pass  # the stream ends where the file does: keep what decoded
    return b"".join(pieces)[:limit]


def _read_record(opcode: int, body: bytes) -> Any:
    """The mcap record class of ``opcode`` read from ``body``, which it must use exactly (``Message`` and
    unknown opcodes: ``None`` for unknown)."""
    from mcap.data_stream import ReadDataStream
    from mcap.exceptions import McapError
    from mcap.records import Attachment, Channel, Message, Metadata, Schema

    cls: Any = {_SCHEMA: Schema, _CHANNEL: Channel, _METADATA: Metadata, _ATTACHMENT: Attachment}.get(opcode)
    stream = ReadDataStream(io.BytesIO(body))
    try:
        if opcode == _MESSAGE:
            if len(body) < 22:
                raise _Bad("a message record is shorter than its fixed fields")
            return Message.read(stream, len(body))
        if cls is None:
            return None
        rec = cls.read(stream)
    except (struct.error, UnicodeDecodeError, McapError, ValueError) as exc:
        raise _Bad(f"a {_NAMES.get(opcode, 'record')} record does not parse ({type(exc).__name__})") from None
    if stream.count != len(body):
        raise _Bad(f"a {_NAMES[opcode]} record does not fill its length")
    return rec


def _inner(raw: bytes) -> list[tuple[int, Any]]:
    """``(opcode, record)`` of the records inside a chunk (schemas, channels, messages; others are skipped)."""
    out: list[tuple[int, Any]] = []
    at = 0
    while at < len(raw):
        if at + 9 > len(raw):
            raise _Bad("its last record header is cut off")
        op, n = raw[at], _u64(raw, at + 1)
        if at + 9 + n > len(raw):
            raise _Bad("a record inside it runs past its end")
        body = raw[at + 9 : at + 9 + n]
        if op in (_SCHEMA, _CHANNEL, _MESSAGE):
            out.append((op, _read_record(op, body)))
        at += 9 + n
    return out


def _plausible(head: bytes, size: int, at: int) -> bool:
    """Whether a record starting at file offset ``at`` with the first bytes ``head`` checks out in full (the
    records the resynchronisation looks for)."""
    if len(head) < 9:
        return False
    op, n = head[0], _u64(head, 1)
    if at + 9 + n > size:
        return False
    b = head[9:]
    try:
        if op == _CHUNK:
            if n < 40 or len(b) < 40:
                return False
            clen = _u32(b, 28)
            if clen not in (0, 3, 4) or len(b) < 40 + clen:
                return False
            comp = b[32 : 32 + clen]
            if comp not in (b"", b"lz4", b"zstd"):
                return False
            return 40 + clen + _u64(b, 32 + clen) == n and _u64(b, 16) <= MAX_CHUNK_BYTES and _u64(b, 0) <= _u64(b, 8)
        if op == _MESSAGE_INDEX:
            if n < 6 or len(b) < 6:
                return False
            rl = _u32(b, 2)
            return 2 + 4 + rl == n and rl % 16 == 0
        if op == _METADATA:
            if len(b) < 4:
                return False
            nl = _u32(b, 0)
            if 4 + nl + 4 > len(b) or nl > 256:
                return False
            b[4 : 4 + nl].decode("utf-8")
            return 4 + nl + 4 + _u32(b, 4 + nl) == n
        if op == _DATA_END:
            return n == 4
    except (struct.error, UnicodeDecodeError):
        return False
    return False


@dataclass
class Scan:
    """One walk over the MCAP file at ``path`` (see the module docstring).

    ``chunks``: decompress and check the chunks and yield their messages; without it the chunks are hopped over
    (for the metadata alone). ``keep``: called with a chunk's first and last message log times (ns), whether to
    read it (``None``: every chunk); with a readable summary the others are hopped over, see the module docstring,
    and counted in ``skipped_chunks``. After :meth:`messages` ran: ``damage`` (every damaged region, in file order),
    ``complete`` (the file ends with its data end, summary and footer), ``metadata`` by name, ``attachments``
    (names), ``schemas`` and ``channels`` by id.
    """

    path: Path
    chunks: bool = True
    keep: Callable[[int, int], bool] | None = None
    skipped_chunks: int = 0
    size: int = 0
    damage: list[Damage] = field(default_factory=list)
    complete: bool = False
    data_end: bool = False
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    attachments: list[str] = field(default_factory=list)
    schemas: dict[int, Any] = field(default_factory=dict)
    channels: dict[int, Any] = field(default_factory=dict)
    has_summary: bool = False
    _summary_bad: bool = False
    _chunk_index: dict[int, tuple[int, int, int]] = field(default_factory=dict)
    """The summary's chunk indexes: file offset → (first and last log time, record length)."""

    def messages(self) -> Iterator[tuple[Any, Damage | None]]:
        """Yields ``(message, None)`` for every message of every intact chunk in file order, and ``(None,
        damage)`` where a damaged region lies between them."""
        with self.path.open("rb") as f:
            f.seek(0, io.SEEK_END)
            self.size = f.tell()
            self._summary(f)
            yield from self._walk(f)

    # ------------------------------------------------------------------------------------------ summary

    def _summary(self, f: IO[bytes]) -> None:
        """Schemas and channels of the summary section, when the file ends with a readable footer and the
        summary's CRC matches."""
        size = self.size
        if size < 8 + 9 + 20 + 8:
            return
        f.seek(size - 8 - 29)
        tail = f.read(29 + 8)
        if tail[-8:] != MAGIC or tail[0] != _FOOTER or _u64(tail, 1) != 20:
            return
        start = _u64(tail, 9)
        end = size - 8 - 29
        if not 8 <= start <= end or end - start > 256 << 20:
            return
        f.seek(start)
        data = f.read(end - start)
        stored = _u32(tail, 25)
        if stored != 0 and zlib.crc32(tail[:25], zlib.crc32(data)) != stored:
            self._summary_bad = True  # the summary was changed: its schemas and channels are not trusted
            return
        at = 0
        found: list[tuple[int, Any]] = []
        chunks: dict[int, tuple[int, int, int]] = {}
        try:
            while at < len(data):
                if at + 9 > len(data):
                    return
                op, n = data[at], _u64(data, at + 1)
                if at + 9 + n > len(data):
                    return
                if op in (_SCHEMA, _CHANNEL):
                    found.append((op, _read_record(op, data[at + 9 : at + 9 + n])))
                elif op == _CHUNK_INDEX and n >= 32:  # first and last log times, offset, record length
                    t0, t1, offset, length = struct.unpack_from("<QQQQ", data, at + 9)
                    chunks[int(offset)] = (int(t0), int(t1), int(length))
                at += 9 + n
        except _Bad:
            return
        for op, rec in found:
            (self.schemas if op == _SCHEMA else self.channels)[rec.id] = rec
        self._chunk_index = chunks
        self.has_summary = True

    # ------------------------------------------------------------------------------------------ data section

    def _walk(self, f: IO[bytes]) -> Iterator[tuple[Any, Damage | None]]:
        size = self.size
        f.seek(0)
        head = f.read(8)
        crc = zlib.crc32(head)
        crc_valid = head == MAGIC
        pos = 8
        while True:
            if pos >= size:
                d = Damage(pos, size, "the file ends without its data end, summary and footer", truncated=True)
                self.damage.append(d)
                yield None, d
                return
            f.seek(pos)
            head = f.read(9)
            if len(head) < 9:
                d = Damage(pos, size, f"the file ends inside a record header at byte {size}", truncated=True)
                self.damage.append(d)
                yield None, d
                return
            op, n = head[0], _u64(head, 1)
            end = pos + 9 + n
            if op == _CHUNK and n == _OPEN and self.chunks:  # the chunk being written when the writer stopped
                cut = self._cut_chunk(f, pos, n)
                for rec in [] if cut is None else cut.messages:
                    yield rec, None
                d = Damage(
                    pos,
                    size,
                    "the file ends inside the chunk that was being written (a killed writer): its complete records "
                    "were read, without a CRC to check them against",
                    truncated=True,
                )
                self.damage.append(d)
                yield None, d
                return
            if op not in _NAMES or end > size:
                nxt = self._resync(f, pos + 1)
                if nxt is None and op in _NAMES:
                    what = (
                        f"the file ends inside a {_NAMES[op]} record: it starts at byte {pos} and needs {n + 9} "
                        f"bytes, {size - pos} are there"
                    )
                    times: tuple[int, int] | None = None
                    f.seek(pos + 9)
                    if op == _CHUNK and size - pos - 9 >= 16:  # the lost frames start here
                        t0, t1 = struct.unpack("<QQ", f.read(16))
                        if t0 <= t1:
                            times = (int(t0), int(t1))
                    cut = self._cut_chunk(f, pos, n) if op == _CHUNK and self.chunks else None
                    if cut is not None and cut.messages:  # an interrupted copy, power loss after the length was set
                        for rec in cut.messages:
                            yield rec, None
                        if cut.whole:
                            what += "; every record of the chunk was read, its CRC checks"
                            times = None
                        else:
                            what += (
                                f"; its {len(cut.messages)} complete messages before the cut were read, without the "
                                "chunk's CRC to check them against"
                            )
                            # the messages lost: from the one cut off when its header was read, else after the
                            # last one read (whether that frame is whole is then up to the reader of its topics)
                            last = max(int(m.log_time) for m in cut.messages)
                            first = cut.cut_time if cut.cut_time is not None else last + 1
                            times = (first, times[1]) if times is not None and first <= times[1] else None
                    d = Damage(pos, size, what, times, truncated=True)
                    self.damage.append(d)
                    yield None, d
                    return
                what = f"unknown record type 0x{op:02x}" if op not in _NAMES else f"a {_NAMES[op]} record's length"
                d = Damage(
                    pos,
                    size if nxt is None else nxt,
                    f"unreadable bytes ({what} is garbage); "
                    + ("nothing readable follows" if nxt is None else f"reading goes on at byte {nxt}"),
                )
                self.damage.append(d)
                yield None, d
                if nxt is None:
                    return
                pos, crc_valid = nxt, False
                continue
            if op == _CHUNK and not self.chunks:
                f.seek(end)
                pos, crc_valid = end, False
                continue
            if op == _CHUNK and self.keep is not None and pos in self._chunk_index and n >= 40:
                t0, t1 = struct.unpack("<QQ", f.read(16))
                # the chunk's own times agree with the summary's index (whose CRC was checked): hop over it unread
                if self._chunk_index[pos] == (t0, t1, 9 + n) and t0 <= t1 and not self.keep(int(t0), int(t1)):
                    self.skipped_chunks += 1
                    pos, crc_valid = end, False
                    continue
                f.seek(pos + 9)
            body = f.read(n)
            if op == _DATA_END:
                stored = _u32(body, 0) if len(body) >= 4 else 0
                self.data_end = True
                if self.chunks and crc_valid and stored != 0 and stored != crc:
                    d = Damage(
                        0,
                        pos,
                        "the data section's CRC does not match: bytes outside the chunks (metadata, indexes) "
                        "were changed",
                    )
                    self.damage.append(d)
                    yield None, d
                self._footer(f)
                if not self.complete:
                    d = Damage(
                        end,
                        size,
                        "the summary section after the data is cut off or damaged (every message is before it)",
                        truncated=True,
                    )
                    self.damage.append(d)
                    yield None, d
                elif self._summary_bad:
                    d = Damage(end, size, "the summary section's CRC does not match (every message is before it)")
                    self.damage.append(d)
                    yield None, d
                return
            crc = zlib.crc32(body, zlib.crc32(head, crc))
            if op == _CHUNK:
                try:
                    chunk = _parse_chunk(body)
                except _Bad as exc:  # its own length may be the damage: look for the next record right after
                    nxt = self._resync(f, pos + 1)
                    d = Damage(pos, size if nxt is None else nxt, f"damaged chunk: {exc}")
                    self.damage.append(d)
                    yield None, d
                    if nxt is None:
                        return
                    pos, crc_valid = nxt, False
                    continue
                try:
                    records = _inner(_decompress(chunk))
                except _Bad as exc:
                    d = Damage(pos, end, f"damaged chunk, skipped: {exc}", (chunk.start, chunk.end))
                    self.damage.append(d)
                    yield None, d
                    pos = end
                    continue
                for rop, rec in records:
                    if rop == _SCHEMA:
                        self.schemas[rec.id] = rec
                    elif rop == _CHANNEL:
                        self.channels[rec.id] = rec
                    else:
                        yield rec, None
            elif op in (_METADATA, _ATTACHMENT, _SCHEMA, _CHANNEL, _MESSAGE):
                try:
                    rec = _read_record(op, body)
                except _Bad as exc:
                    d = Damage(pos, end, f"damaged {_NAMES[op]} record: {exc}")
                    self.damage.append(d)
                    yield None, d
                    pos = end
                    continue
                if op == _METADATA:
                    self.metadata[rec.name] = dict(rec.metadata)
                elif op == _ATTACHMENT:
                    self.attachments.append(rec.name)
                elif op == _SCHEMA:
                    self.schemas[rec.id] = rec
                elif op == _CHANNEL:
                    self.channels[rec.id] = rec
                else:
                    yield rec, None
            elif op == _FOOTER:  # a footer without a data end: the data section ends here
                return
            pos = end

    def _cut_chunk(self, f: IO[bytes], pos: int, n: int) -> _Cut | None:
        """The complete records of the chunk record at ``pos`` (record length ``n``) that the file ends inside: its
        compressed stream decompressed as far as it goes (:func:`_decompress_cut`), its records read up to the
        first one cut off; schemas and channels are taken in as they come. ``n`` is :data:`_OPEN` for the chunk a
        killed writer was writing (whose other lengths and CRC are placeholders too); a closed chunk's header must
        agree with ``n`` and name a known compression, and the records are read up to its uncompressed size.
        ``None`` when its header is cut off or does not check out, or when it decompresses in full but its CRC
        does not match (its records are damaged, not just cut off)."""
        f.seek(pos + 9)
        body = f.read(min(n, self.size - pos - 9))
        if len(body) < 40:
            return None
        clen = _u32(body, 28)
        if clen > 16 or len(body) < 40 + clen:
            return None
        comp, data = body[32 : 32 + clen], body[40 + clen :]
        limit = MAX_CHUNK_BYTES
        usize = crc = 0
        if n != _OPEN:
            t0, t1, usize, crc = struct.unpack_from("<QQQI", body, 0)
            if (
                comp not in (b"", b"lz4", b"zstd")
                or 40 + clen + _u64(body, 32 + clen) != n
                or usize > MAX_CHUNK_BYTES
                or t0 > t1
            ):
                return None
            limit = int(usize)
        raw = _decompress_cut(comp, data, limit)
        whole = n != _OPEN and len(raw) == usize
        if whole and crc != 0 and zlib.crc32(raw) != crc:
            return None
        found: list[tuple[int, Any]] = []
        at = 0
        cut_time = None
        while at + 9 <= len(raw):
            op, m = raw[at], _u64(raw, at + 1)
            if at + 9 + m > len(raw):
                if op == _MESSAGE and at + 9 + 14 <= len(raw):  # the message cut off: channel, sequence, log time
                    cut_time = _u64(raw, at + 9 + 6)
                break
            try:
                if op in (_SCHEMA, _CHANNEL, _MESSAGE):
                    found.append((op, _read_record(op, raw[at + 9 : at + 9 + m])))
            except _Bad:  # read up to here; a chunk whose CRC was checked is damaged, as one not cut off is
                if whole:
                    return None
                break
            at += 9 + m
        out: list[Any] = []
        for op, rec in found:
            if op == _SCHEMA:
                self.schemas[rec.id] = rec
            elif op == _CHANNEL:
                self.channels[rec.id] = rec
            else:
                out.append(rec)
        return _Cut(out, whole=whole and at == len(raw), cut_time=cut_time)

    def _footer(self, f: IO[bytes]) -> None:
        size = self.size
        if size >= 8 + 29:
            f.seek(size - 8 - 29)
            tail = f.read(37)
            self.complete = tail[-8:] == MAGIC and tail[0] == _FOOTER

    def _resync(self, f: IO[bytes], start: int) -> int | None:
        """The offset of the first record at or after ``start`` that checks out in full (see :func:`_plausible`),
        or ``None``."""
        size = self.size
        at = start
        while at < size:
            f.seek(at)
            block = f.read(_BLOCK + 64)
            if not block:
                return None
            limit = min(len(block), _BLOCK)
            i = 0
            while i < limit:
                # the nearest candidate opcode from i
                cands = [j for j in (block.find(bytes([o]), i, limit) for o in (6, 7, 12, 15)) if j >= 0]
                if not cands:
                    break
                j = min(cands)
                head = block[j : j + 9 + 64]
                if len(head) < 9 + 64 and at + j + len(head) < size:
                    f.seek(at + j)
                    head = f.read(9 + 64)
                if _plausible(head, size, at + j):
                    return at + j
                i = j + 1
            at += _BLOCK
        return None
