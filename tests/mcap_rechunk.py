"""Test helpers shared by test folders (on the test path through pytest's ``pythonpath``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def rechunk(src: Path, dst: Path, chunk_size: int, *, run_changes: dict[str, str] | None = None) -> None:
    """Copies a recording record by record into small zstd chunks (with CRCs) using the official writer (a real
    run's chunks are ~4 MiB); ``run_changes``, when given, are made to its ``run`` metadata."""
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
                changed = {**rec.metadata, **run_changes} if run_changes and rec.name == "run" else rec.metadata
                w.add_metadata(rec.name, changed)
        w.finish()  # type: ignore[no-untyped-call]


def emptied(src: Path, topic: str, frame: int, out: Path) -> Path:
    """``src`` written again to ``out`` with its ``topic`` message of acquisition ``frame`` (the frame-th distinct log
    time) empty (0 bytes): a frame the reader leaves out as incomplete."""
    from mcap.reader import make_reader
    from mcap.writer import Writer

    out.parent.mkdir(parents=True, exist_ok=True)
    with src.open("rb") as f, out.open("wb") as g:
        r, w = make_reader(f), Writer(g)
        summary, head = r.get_summary(), r.get_header()
        assert summary is not None
        w.start(profile=head.profile, library=head.library)
        schemas = {k: w.register_schema(s.name, s.encoding, s.data) for k, s in summary.schemas.items()}
        chans = {
            k: w.register_channel(c.topic, c.message_encoding, schemas.get(c.schema_id, 0), c.metadata)
            for k, c in summary.channels.items()
        }
        times = sorted({m.log_time for _, _, m in r.iter_messages()})
        for _, ch, m in r.iter_messages():
            data = b"" if ch.topic == topic and m.log_time == times[frame] else m.data
            w.add_message(chans[ch.id], m.log_time, data, m.publish_time, m.sequence)
        for md in r.iter_metadata():
            w.add_metadata(md.name, md.metadata)
        w.finish()
    return out


def killed_copy(src: Path, dst: Path, *, messages: int | None = None) -> Path:
    """``dst``: what a run killed after the first ``messages`` messages of ``src`` (all: ``None``) leaves, as the
    recorder writes it (the header, the scenario, manifest and sensors metadata, complete chunks, no ``run``
    metadata, no summary or footer)."""
    from mcap.reader import make_reader
    from mcap.writer import CompressionType, Writer

    with src.open("rb") as f:
        reader = make_reader(f)
        meta = [(m.name, dict(m.metadata)) for m in reader.iter_metadata() if m.name != "run"]
        msgs = list(reader.iter_messages())[:messages]
    with dst.open("wb") as out:
        w = Writer(out, chunk_size=1, compression=CompressionType.NONE)  # every message in a chunk of its own
        write_records(w, meta, msgs)
        # no w.finish(): the process was killed
    return dst


def write_records(w: Any, meta: list[tuple[str, dict[str, str]]], msgs: list[Any]) -> None:
    """Starts the official writer ``w`` and writes ``meta`` (name, metadata) and the ``(schema, channel, message)``
    triples ``msgs`` of ``make_reader(...).iter_messages()`` into it, registering each schema and channel once."""
    w.start(profile="", library="mmusv test")
    for name, md in meta:
        w.add_metadata(name, md)
    schemas: dict[int, int] = {}
    channels: dict[int, int] = {}
    for schema, ch, m in msgs:
        assert schema is not None
        if schema.id not in schemas:
            schemas[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
        if ch.id not in channels:
            channels[ch.id] = w.register_channel(ch.topic, ch.message_encoding, schemas[schema.id], ch.metadata)
        w.add_message(channels[ch.id], m.log_time, m.data, m.publish_time, m.sequence)


def no_ray_cluster(monkeypatch: Any) -> None:
    """Ray "installed" (a stand-in module, through ``mmusv.batch.ray_backend.import_ray``) with no cluster to join:
    ``ray.init`` raises Ray's own ``ConnectionError``."""
    import types

    from mmusv.batch import ray_backend

    def init(**_kw: Any) -> None:
        raise ConnectionError("Could not find any running Ray instance. Please specify the one to connect to.")

    fake = types.SimpleNamespace(is_initialized=lambda: False, init=init)
    monkeypatch.setattr(ray_backend, "import_ray", lambda: fake)
