"""Test helpers shared by test folders (on the test path through pytest's ``pythonpath``)."""

from __future__ import annotations

from pathlib import Path


def rechunk(src: Path, dst: Path, chunk_size: int) -> None:
    """Copies a recording record by record into small zstd chunks (with CRCs) using the official writer (a real
    run's chunks are ~4 MiB)."""
    from mcap.records import Channel, Message, Metadata, Schema
    from mcap.stream_reader import StreamReader
    from mcap.writer import CompressionType, Writer

    with src.open("rb") as f, dst.open("wb") as g:
        w = Writer(g, chunk_size=chunk_size, compression=CompressionType.ZSTD)
        w.start(profile="", library="test")
        schemas: dict[int, int] = {}
        channels: dict[int, int] = {}
        for rec in StreamReader(f).records:
            if isinstance(rec, Schema):
                schemas[rec.id] = w.register_schema(rec.name, rec.encoding, rec.data)
            elif isinstance(rec, Channel):
                channels[rec.id] = w.register_channel(
                    rec.topic, rec.message_encoding, schemas.get(rec.schema_id, 0), rec.metadata
                )
            elif isinstance(rec, Message):
                w.add_message(channels[rec.channel_id], rec.log_time, rec.data, rec.publish_time, rec.sequence)
            elif isinstance(rec, Metadata):
                w.add_metadata(rec.name, rec.metadata)
        w.finish()  # type: ignore[no-untyped-call]
