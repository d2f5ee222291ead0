"""The records of an MCAP file, one at a time, trusting nothing: the parsing under the damage-tolerant walk of
:mod:`mmusv.recording.scan`.

The record layout is the MCAP specification's (https://mcap.dev/spec: an opcode byte, a little-endian u64 length,
the body); the classes of the records the reader keeps (schema, channel, message, metadata, attachment) are the
official ``mcap`` package's. Here: a chunk record's fixed fields (:func:`parse_chunk`), its records decompressed
into at most their stated size and checked against its CRC (:func:`decompress`), or, for a chunk the file ends
inside, as far as its zstd or lz4 blocks are there in full (:func:`decompress_cut`); one record read so that it
fills its length exactly (:func:`read_record`); the records inside a chunk (:func:`inner_records`); and whether
bytes at an offset are a record that checks out in full (:func:`plausible`), which the walk uses to find its feet
again after garbage. Anything that does not check out raises :class:`BadRecord`, saying why.
"""

from __future__ import annotations

import io
import struct
import zlib
from dataclasses import dataclass
from typing import Any

__all__ = [
    "ATTACHMENT",
    "ATTACHMENT_INDEX",
    "BLOCK",
    "CHANNEL",
    "CHUNK",
    "CHUNK_INDEX",
    "DATA_END",
    "FOOTER",
    "HEADER",
    "MAGIC",
    "MAX_CHUNK_BYTES",
    "MESSAGE",
    "MESSAGE_INDEX",
    "METADATA",
    "METADATA_INDEX",
    "NAMES",
    "OPEN_LENGTH",
    "SCHEMA",
    "STATISTICS",
    "SUMMARY_OFFSET",
    "BadRecord",
    "ChunkRecord",
    "decompress",
    "decompress_cut",
    "inner_records",
    "parse_chunk",
    "plausible",
    "read_record",
    "string_at",
    "u32",
    "u64",
]

MAGIC = b"\x89MCAP0\r\n"
MAX_CHUNK_BYTES = 1 << 30
"""Largest uncompressed chunk a reader accepts (the recorder writes chunks of 4 MiB): a damaged size field can
never make it allocate more."""

HEADER, FOOTER, SCHEMA, CHANNEL, MESSAGE, CHUNK, MESSAGE_INDEX = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07
CHUNK_INDEX, ATTACHMENT, ATTACHMENT_INDEX, STATISTICS, METADATA = 0x08, 0x09, 0x0A, 0x0B, 0x0C
METADATA_INDEX, SUMMARY_OFFSET, DATA_END = 0x0D, 0x0E, 0x0F
NAMES = {
    HEADER: "header",
    FOOTER: "footer",
    SCHEMA: "schema",
    CHANNEL: "channel",
    MESSAGE: "message",
    CHUNK: "chunk",
    MESSAGE_INDEX: "message index",
    CHUNK_INDEX: "chunk index",
    ATTACHMENT: "attachment",
    ATTACHMENT_INDEX: "attachment index",
    STATISTICS: "statistics",
    METADATA: "metadata",
    METADATA_INDEX: "metadata index",
    SUMMARY_OFFSET: "summary offset",
    DATA_END: "data end",
}
BLOCK = 1 << 20
OPEN_LENGTH = (1 << 64) - 1
"""The length of a chunk record while the ``mcap`` crate (the core's recorder) still writes it: the record is
streamed to the file and its lengths, times and CRC are filled in when the chunk is closed."""


class BadRecord(Exception):
    """A record that does not check out (the message says why)."""


@dataclass
class ChunkRecord:
    """A chunk record's fields (MCAP spec, *Chunk*): the log time span of its messages (ns), the size and CRC-32 of
    its uncompressed records, its compression (``""``, ``"zstd"`` or ``"lz4"``) and its compressed records."""

    start: int
    end: int
    usize: int
    crc: int
    compression: str
    data: bytes


def u64(b: bytes, at: int) -> int:
    """The little-endian u64 at ``at`` of ``b`` (:class:`struct.error` past its end)."""
    return int(struct.unpack_from("<Q", b, at)[0])


def u32(b: bytes, at: int) -> int:
    """The little-endian u32 at ``at`` of ``b`` (:class:`struct.error` past its end)."""
    return int(struct.unpack_from("<I", b, at)[0])


def string_at(b: bytes, at: int) -> tuple[str, int]:
    """The MCAP string (u32 length, UTF-8 bytes) at ``at`` of ``b`` and the offset after it."""
    n = u32(b, at)
    if at + 4 + n > len(b):
        raise BadRecord("a string runs past its record")
    return b[at + 4 : at + 4 + n].decode("utf-8"), at + 4 + n


def parse_chunk(body: bytes) -> ChunkRecord:
    """The chunk record whose body is ``body``; :class:`BadRecord` when its lengths disagree with each other."""
    if len(body) < 40:
        raise BadRecord(f"a chunk record of {len(body)} bytes is shorter than its fixed fields")
    start, end, usize, crc = struct.unpack_from("<QQQI", body, 0)
    clen = u32(body, 28)
    if clen > 16 or 32 + clen + 8 > len(body):
        raise BadRecord("the chunk's compression field is unreadable")
    compression = body[32 : 32 + clen].decode("ascii", errors="replace")
    rlen = u64(body, 32 + clen)
    if 40 + clen + rlen != len(body):
        raise BadRecord(f"the chunk's data length ({rlen}) does not match its record length ({len(body)})")
    return ChunkRecord(int(start), int(end), int(usize), int(crc), compression, body[40 + clen :])


def decompress(c: ChunkRecord) -> bytes:
    """The records of chunk ``c``, decompressed into at most its stated size (and :data:`MAX_CHUNK_BYTES`) and
    checked against its CRC; :class:`BadRecord` when they do not decompress to it or do not match."""
    if c.usize > MAX_CHUNK_BYTES:
        raise BadRecord(f"the chunk says it holds {c.usize} bytes, more than any chunk mmusv writes")
    if c.compression == "zstd":
        import zstandard

        try:
            with zstandard.ZstdDecompressor().stream_reader(io.BytesIO(c.data), read_across_frames=True) as r:
                raw = r.read(c.usize + 1)
        except zstandard.ZstdError as exc:
            raise BadRecord(f"its zstd data does not decompress ({exc})") from None
    elif c.compression == "lz4":
        import lz4.frame

        try:
            with lz4.frame.LZ4FrameFile(io.BytesIO(c.data), "rb") as r:
                raw = r.read(c.usize + 1)
        except (RuntimeError, EOFError, OSError) as exc:
            raise BadRecord(f"its lz4 data does not decompress ({exc})") from None
    elif c.compression == "":
        raw = c.data
    else:
        raise BadRecord(f"unknown compression {c.compression!r}")
    if len(raw) != c.usize:
        raise BadRecord(f"it decompresses to {len(raw)} bytes, its header says {c.usize}")
    if c.crc != 0 and zlib.crc32(raw) != c.crc:
        raise BadRecord("CRC mismatch: its records are not the bytes that were written")
    return raw


def decompress_cut(compression: bytes, data: bytes, limit: int) -> bytes:
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


def read_record(opcode: int, body: bytes) -> Any:
    """The mcap record class of ``opcode`` read from ``body``, which it must use exactly (``Message`` and
    unknown opcodes: ``None`` for unknown)."""
    from mcap.data_stream import ReadDataStream
    from mcap.exceptions import McapError
    from mcap.records import Attachment, Channel, Message, Metadata, Schema

    cls: Any = {SCHEMA: Schema, CHANNEL: Channel, METADATA: Metadata, ATTACHMENT: Attachment}.get(opcode)
    stream = ReadDataStream(io.BytesIO(body))
    try:
        if opcode == MESSAGE:
            if len(body) < 22:
                raise BadRecord("a message record is shorter than its fixed fields")
            return Message.read(stream, len(body))
        if cls is None:
            return None
        rec = cls.read(stream)
    except (struct.error, UnicodeDecodeError, McapError, ValueError) as exc:
        raise BadRecord(f"a {NAMES.get(opcode, 'record')} record does not parse ({type(exc).__name__})") from None
    if stream.count != len(body):
        raise BadRecord(f"a {NAMES[opcode]} record does not fill its length")
    return rec


def inner_records(raw: bytes) -> list[tuple[int, Any]]:
    """``(opcode, record)`` of the records inside a chunk (schemas, channels, messages; others are skipped)."""
    out: list[tuple[int, Any]] = []
    at = 0
    while at < len(raw):
        if at + 9 > len(raw):
            raise BadRecord("its last record header is cut off")
        op, n = raw[at], u64(raw, at + 1)
        if at + 9 + n > len(raw):
            raise BadRecord("a record inside it runs past its end")
        body = raw[at + 9 : at + 9 + n]
        if op in (SCHEMA, CHANNEL, MESSAGE):
            out.append((op, read_record(op, body)))
        at += 9 + n
    return out


def plausible(head: bytes, size: int, at: int) -> bool:
    """Whether a record starting at file offset ``at`` with the first bytes ``head`` checks out in full (the
    records the resynchronisation looks for)."""
    if len(head) < 9:
        return False
    op, n = head[0], u64(head, 1)
    if at + 9 + n > size:
        return False
    b = head[9:]
    try:
        if op == CHUNK:
            if n < 40 or len(b) < 40:
                return False
            clen = u32(b, 28)
            if clen not in (0, 3, 4) or len(b) < 40 + clen:
                return False
            comp = b[32 : 32 + clen]
            if comp not in (b"", b"lz4", b"zstd"):
                return False
            return 40 + clen + u64(b, 32 + clen) == n and u64(b, 16) <= MAX_CHUNK_BYTES and u64(b, 0) <= u64(b, 8)
        if op == MESSAGE_INDEX:
            if n < 6 or len(b) < 6:
                return False
            rl = u32(b, 2)
            return 2 + 4 + rl == n and rl % 16 == 0
        if op == METADATA:
            if len(b) < 4:
                return False
            nl = u32(b, 0)
            if 4 + nl + 4 > len(b) or nl > 256:
                return False
            b[4 : 4 + nl].decode("utf-8")
            return 4 + nl + 4 + u32(b, 4 + nl) == n
        if op == DATA_END:
            return n == 4
    except (struct.error, UnicodeDecodeError):
        return False
    return False
