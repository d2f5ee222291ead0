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
  message indexes) is reported too; when a damaged chunk was found, that chunk alone may break it (the CRC covers
  every byte of the data section), so it is not blamed on the bytes outside the chunks then.

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

from mmusv.recording.mcap_records import (
    ATTACHMENT,
    BLOCK,
    CHANNEL,
    CHUNK,
    CHUNK_INDEX,
    DATA_END,
    FOOTER,
    MAGIC,
    MAX_CHUNK_BYTES,
    MESSAGE,
    METADATA,
    NAMES,
    OPEN_LENGTH,
    SCHEMA,
    BadRecord,
    decompress,
    decompress_cut,
    inner_records,
    parse_chunk,
    plausible,
    read_record,
    u32,
    u64,
)

__all__ = ["MAGIC", "MAX_CHUNK_BYTES", "Damage", "Scan"]


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
        if tail[-8:] != MAGIC or tail[0] != FOOTER or u64(tail, 1) != 20:
            return
        start = u64(tail, 9)
        end = size - 8 - 29
        if not 8 <= start <= end or end - start > 256 << 20:
            return
        f.seek(start)
        data = f.read(end - start)
        stored = u32(tail, 25)
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
                op, n = data[at], u64(data, at + 1)
                if at + 9 + n > len(data):
                    return
                if op in (SCHEMA, CHANNEL):
                    found.append((op, read_record(op, data[at + 9 : at + 9 + n])))
                elif op == CHUNK_INDEX and n >= 32:  # first and last log times, offset, record length
                    t0, t1, offset, length = struct.unpack_from("<QQQQ", data, at + 9)
                    chunks[int(offset)] = (int(t0), int(t1), int(length))
                at += 9 + n
        except BadRecord:
            return
        for op, rec in found:
            (self.schemas if op == SCHEMA else self.channels)[rec.id] = rec
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
            op, n = head[0], u64(head, 1)
            end = pos + 9 + n
            if op == CHUNK and n == OPEN_LENGTH and self.chunks:  # the chunk being written when the writer stopped
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
            if op not in NAMES or end > size:
                nxt = self._resync(f, pos + 1)
                if nxt is None and op in NAMES:
                    what = (
                        f"the file ends inside a {NAMES[op]} record: it starts at byte {pos} and needs {n + 9} "
                        f"bytes, {size - pos} are there"
                    )
                    times: tuple[int, int] | None = None
                    f.seek(pos + 9)
                    if op == CHUNK and size - pos - 9 >= 16:  # the lost frames start here
                        t0, t1 = struct.unpack("<QQ", f.read(16))
                        if t0 <= t1:
                            times = (int(t0), int(t1))
                    cut = self._cut_chunk(f, pos, n) if op == CHUNK and self.chunks else None
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
                what = f"unknown record type 0x{op:02x}" if op not in NAMES else f"a {NAMES[op]} record's length"
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
            if op == CHUNK and not self.chunks:
                f.seek(end)
                pos, crc_valid = end, False
                continue
            if op == CHUNK and self.keep is not None and pos in self._chunk_index and n >= 40:
                t0, t1 = struct.unpack("<QQ", f.read(16))
                # the chunk's own times agree with the summary's index (whose CRC was checked): hop over it unread
                if self._chunk_index[pos] == (t0, t1, 9 + n) and t0 <= t1 and not self.keep(int(t0), int(t1)):
                    self.skipped_chunks += 1
                    pos, crc_valid = end, False
                    continue
                f.seek(pos + 9)
            body = f.read(n)
            if op == DATA_END:
                stored = u32(body, 0) if len(body) >= 4 else 0
                self.data_end = True
                # blamed on the bytes outside the chunks only when every chunk checked out: the CRC covers the
                # chunks' bytes too, so a damaged chunk (already reported) breaks it alone
                if self.chunks and crc_valid and stored != 0 and stored != crc and not self.damage:
                    d = Damage(
                        0,
                        pos,
                        "the data section's CRC does not match: bytes outside the chunks (metadata, indexes) "
                        "were changed",
                    )
                    self.damage.append(d)
                    yield None, d
                self._footer(f)
                ends = None if self.complete else self._end_before(f, end)
                if ends is not None:  # whole up to its closing magic, with bytes after it (a copy padded to blocks)
                    d = Damage(
                        ends,
                        size,
                        f"{size - ends} bytes follow the end of the MCAP file (its footer and closing magic end at "
                        f"byte {ends}): not part of the recording, whole before them",
                    )
                    self.damage.append(d)
                    yield None, d
                elif not self.complete:
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
            if op == CHUNK:
                try:
                    chunk = parse_chunk(body)
                except BadRecord as exc:  # its own length may be the damage: look for the next record right after
                    nxt = self._resync(f, pos + 1)
                    d = Damage(pos, size if nxt is None else nxt, f"damaged chunk: {exc}")
                    self.damage.append(d)
                    yield None, d
                    if nxt is None:
                        return
                    pos, crc_valid = nxt, False
                    continue
                try:
                    records = inner_records(decompress(chunk))
                except BadRecord as exc:
                    d = Damage(pos, end, f"damaged chunk, skipped: {exc}", (chunk.start, chunk.end))
                    self.damage.append(d)
                    yield None, d
                    pos = end
                    continue
                for rop, rec in records:
                    if rop == SCHEMA:
                        self.schemas[rec.id] = rec
                    elif rop == CHANNEL:
                        self.channels[rec.id] = rec
                    else:
                        yield rec, None
            elif op in (METADATA, ATTACHMENT, SCHEMA, CHANNEL, MESSAGE):
                try:
                    rec = read_record(op, body)
                except BadRecord as exc:
                    d = Damage(pos, end, f"damaged {NAMES[op]} record: {exc}")
                    self.damage.append(d)
                    yield None, d
                    pos = end
                    continue
                if op == METADATA:
                    self.metadata[rec.name] = dict(rec.metadata)
                elif op == ATTACHMENT:
                    self.attachments.append(rec.name)
                elif op == SCHEMA:
                    self.schemas[rec.id] = rec
                elif op == CHANNEL:
                    self.channels[rec.id] = rec
                else:
                    yield rec, None
            elif op == FOOTER:  # a footer without a data end: the data section ends here
                return
            pos = end

    def _cut_chunk(self, f: IO[bytes], pos: int, n: int) -> _Cut | None:
        """The complete records of the chunk record at ``pos`` (record length ``n``) that the file ends inside: its
        compressed stream decompressed as far as it goes (:func:`decompress_cut`), its records read up to the
        first one cut off; schemas and channels are taken in as they come. ``n`` is :data:`OPEN_LENGTH` for the chunk a
        killed writer was writing (whose other lengths and CRC are placeholders too); a closed chunk's header must
        agree with ``n`` and name a known compression, and the records are read up to its uncompressed size.
        ``None`` when its header is cut off or does not check out, or when it decompresses in full but its CRC
        does not match (its records are damaged, not just cut off)."""
        f.seek(pos + 9)
        body = f.read(min(n, self.size - pos - 9))
        if len(body) < 40:
            return None
        clen = u32(body, 28)
        if clen > 16 or len(body) < 40 + clen:
            return None
        comp, data = body[32 : 32 + clen], body[40 + clen :]
        limit = MAX_CHUNK_BYTES
        usize = crc = 0
        if n != OPEN_LENGTH:
            t0, t1, usize, crc = struct.unpack_from("<QQQI", body, 0)
            if (
                comp not in (b"", b"lz4", b"zstd")
                or 40 + clen + u64(body, 32 + clen) != n
                or usize > MAX_CHUNK_BYTES
                or t0 > t1
            ):
                return None
            limit = int(usize)
        raw = decompress_cut(comp, data, limit)
        whole = n != OPEN_LENGTH and len(raw) == usize
        if whole and crc != 0 and zlib.crc32(raw) != crc:
            return None
        found: list[tuple[int, Any]] = []
        at = 0
        cut_time = None
        while at + 9 <= len(raw):
            op, m = raw[at], u64(raw, at + 1)
            if at + 9 + m > len(raw):
                if op == MESSAGE and at + 9 + 14 <= len(raw):  # the message cut off: channel, sequence, log time
                    cut_time = u64(raw, at + 9 + 6)
                break
            try:
                if op in (SCHEMA, CHANNEL, MESSAGE):
                    found.append((op, read_record(op, raw[at + 9 : at + 9 + m])))
            except BadRecord:  # read up to here; a chunk whose CRC was checked is damaged, as one not cut off is
                if whole:
                    return None
                break
            at += 9 + m
        out: list[Any] = []
        for op, rec in found:
            if op == SCHEMA:
                self.schemas[rec.id] = rec
            elif op == CHANNEL:
                self.channels[rec.id] = rec
            else:
                out.append(rec)
        return _Cut(out, whole=whole and at == len(raw), cut_time=cut_time)

    def _end_before(self, f: IO[bytes], start: int) -> int | None:
        """Where the MCAP file ends (after its footer and closing magic) when that is before the end of the file:
        the summary records from ``start`` (just after the data end) lead to a footer and the magic. ``None`` when
        they do not (a summary cut off or damaged)."""
        at = start
        while at + 9 <= self.size:
            f.seek(at)
            head = f.read(9)
            op, n = head[0], u64(head, 1)
            if op == FOOTER:
                if n != 20:
                    return None
                f.seek(at + 9 + 20)
                return at + 9 + 20 + 8 if f.read(8) == MAGIC and at + 37 < self.size else None
            if op not in NAMES or at + 9 + n > self.size:
                return None
            at += 9 + n
        return None

    def _footer(self, f: IO[bytes]) -> None:
        size = self.size
        if size >= 8 + 29:
            f.seek(size - 8 - 29)
            tail = f.read(37)
            self.complete = tail[-8:] == MAGIC and tail[0] == FOOTER

    def _resync(self, f: IO[bytes], start: int) -> int | None:
        """The offset of the first record at or after ``start`` that checks out in full (see :func:`plausible`),
        or ``None``."""
        size = self.size
        at = start
        while at < size:
            f.seek(at)
            block = f.read(BLOCK + 64)
            if not block:
                return None
            limit = min(len(block), BLOCK)
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
                if plausible(head, size, at + j):
                    return at + j
                i = j + 1
            at += BLOCK
        return None
