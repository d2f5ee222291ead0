"""What a recording holds, in one dictionary (``mmusv info``): :func:`summary` counts messages per topic, the
log-time span (integer nanoseconds, seconds), metadata, attachments, damage and, for a recording of mmusv, the
frames read and missing (through :class:`~mmusv.recording.stream.FrameStream`, every chunk read and its CRC
checked). A file that is MCAP but not a recording of ``mmusv run`` gets the message counts only; a parts manifest
(:mod:`mmusv.recording.parts`) the sums over its recorded parts.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from mmusv.errors import IoError
from mmusv.recording.info import check_mcap, read_info, recording_arg, written_by_mmusv
from mmusv.recording.parts import is_parts_manifest
from mmusv.recording.scan import Scan
from mmusv.recording.stream import FrameStream

__all__ = ["summary"]


def summary(path: str | os.PathLike[str]) -> dict[str, Any]:
    """What a recording holds: ``{"path", "complete", "messages", "start_ns", "end_ns", "duration_s",
    "topics": {topic: {"schema", "encoding", "messages"}}, "metadata": {name: {key: value}},
    "attachments": [name, ...], "damage": [line, ...], "frames": {...} or None}`` (and ``"metadata_problem"``, why
    a recording of mmusv run whose metadata is damaged is read as messages only), counted by reading every
    chunk (checking its CRC). ``complete`` is False for a ``.partial`` file, one without a summary section or one
    with damage. ``frames`` (for a recording of mmusv): ``{"read", "expected", "first", "missing", "incomplete",
    "report"}``, the complete frames read, how many the run set out to write (from acquisition index ``first``:
    0, or where one part of a split recording starts), the missing ones (sorted), those
    left out because some of their messages are damaged, and the one-line report of
    :meth:`~mmusv.recording.stream.FrameStream.report` (``None`` when all is well). A parts manifest gives the
    sums over its recorded parts, the metadata of the first with the merged ``run`` of
    :func:`~mmusv.recording.info.read_info`, and ``parts`` (how many there are)."""
    p = recording_arg(path)
    if is_parts_manifest(p):
        return _parts_summary(p)
    check_mcap(p)
    try:
        info = read_info(p)
    except IoError as exc:  # not a recording of mmusv run (or its metadata is damaged): messages only
        plain = _plain_summary(p)
        # damaged, not absent: say why it is not read (metadata cut off or damaged: its header says mmusv wrote it;
        # a whole file whose header says so and that holds no such metadata is one of the Recording API's)
        if {"scenario", "sensors"} <= set(plain["metadata"]) or (written_by_mmusv(p) and plain["damage"]):
            plain["metadata_problem"] = str(exc)
        return plain
    stream = FrameStream(info, want=lambda _t: False)
    for _ in stream:
        pass
    return _summary_dict(p, stream, complete=stream.complete and not str(p).endswith(".partial"))


def _summary_dict(p: Path, stream: FrameStream, *, complete: bool) -> dict[str, Any]:
    start, end = max(stream.start_ns, 0), max(stream.end_ns, 0)
    topics = {
        t: {"schema": stream.topic_schemas[t][0], "encoding": stream.topic_schemas[t][1], "messages": n}
        for t, n in stream.topic_counts.items()
    }
    span, _said = stream.expected()
    missing = stream.missing()
    return {
        "path": str(p),
        "complete": complete,
        "messages": stream.messages,
        "start_ns": start,
        "end_ns": end,
        "duration_s": (end - start) * 1e-9,
        "topics": dict(sorted(topics.items())),
        "metadata": stream.metadata,
        "attachments": stream.attachments,
        "damage": list(stream.damage),
        "frames": {
            "read": len(set(stream.yielded)),
            "expected": len(span),
            "first": span.start,
            "missing": missing,
            "incomplete": [k for k, _ in stream.incomplete],
            "report": stream.report(),
        },
    }


def _plain_summary(p: Path) -> dict[str, Any]:
    scan = Scan(p)
    topics: dict[str, dict[str, Any]] = {}
    start, end, total = -1, -1, 0
    damage: list[str] = []
    try:
        for msg, dmg in scan.messages():
            if dmg is not None:
                damage.append(dmg.describe())
                continue
            total += 1
            start = msg.log_time if start < 0 else min(start, msg.log_time)
            end = max(end, msg.log_time)
            ch = scan.channels.get(msg.channel_id)
            if ch is None:
                continue
            schema = scan.schemas.get(ch.schema_id)
            entry = topics.setdefault(
                ch.topic,
                {"schema": "" if schema is None else schema.name, "encoding": ch.message_encoding, "messages": 0},
            )
            entry["messages"] += 1
    except OSError as exc:
        raise IoError(f"{p} cannot be read: {exc.strerror or exc}") from None
    start, end = max(start, 0), max(end, 0)
    return {
        "path": str(p),
        "complete": scan.complete and not scan.damage and not str(p).endswith(".partial"),
        "messages": total,
        "start_ns": start,
        "end_ns": end,
        "duration_s": (end - start) * 1e-9,
        "topics": dict(sorted(topics.items())),
        "metadata": scan.metadata,
        "attachments": scan.attachments,
        "damage": damage,
        "frames": None,
    }


def _parts_summary(path: Path) -> dict[str, Any]:
    info = read_info(path)
    stream = FrameStream(info, want=lambda _t: False)
    for _ in stream:
        pass
    out = _summary_dict(path, stream, complete=info.run["status"] == "complete" and stream.complete)
    first = summary(info.parts[0])
    out["metadata"] = {**first["metadata"], "run": dict(info.run)}
    out["attachments"] = first["attachments"]
    out["parts"] = int(info.run["parts"])
    return out
