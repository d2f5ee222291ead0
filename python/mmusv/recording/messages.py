"""Decoded messages of an ``mmusv run`` recording as they are: :func:`read_messages` iterates
``(topic, log_time_ns, message)`` in file order (every message, optionally only some topics), :func:`frame_messages`
gives every message of one acquisition index by topic (through :class:`~mmusv.recording.stream.FrameStream`). The
messages are decoded protobuf objects; :mod:`mmusv.recording.decode` turns them into numpy arrays. Both work on
finished, truncated and ``.partial`` files (damaged chunks skipped, :mod:`mmusv.recording.scan`) and on parts
manifests (:mod:`mmusv.recording.parts`: the recorded parts in frame order, as one sequence).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

from mmusv import arguments
from mmusv.errors import ConfigError, IoError
from mmusv.recording.info import check_mcap, read_info, recording_arg
from mmusv.recording.parts import is_parts_manifest, part_files
from mmusv.recording.scan import Scan
from mmusv.recording.stream import FrameStream, held_text
from mmusv.text import given, named

__all__ = ["frame_messages", "read_messages"]


def read_messages(
    path: str | os.PathLike[str], topics: Sequence[str] | None = None, *, damage: list[str] | None = None
) -> Iterator[tuple[str, int, Any]]:
    """Yields ``(topic, log_time_ns, decoded_protobuf_message)`` in file order (= log-time order for files of
    mmusv), optionally only ``topics``. Works on finished files, on ``.partial`` files and on parts manifests (the
    recorded parts in order); damaged chunks are skipped (:mod:`mmusv.recording.scan`) and described in
    ``damage`` when a list is given.

    ``topics`` is a list of topic names (``["/world/state"]``; a single string is refused, not read as its
    characters). A topic the recording does not have is a :class:`~mmusv.errors.ConfigError` listing the ones it
    has, raised once the file has been read (after the messages of the topics it has) unless the file is damaged.
    The arguments are checked when iteration starts. A message of a channel that is not protobuf-encoded (an MCAP
    file not written by mmusv) is an :class:`~mmusv.errors.IoError` naming the channel, not skipped."""
    from mcap_protobuf.decoder import DecoderFactory

    path = recording_arg(path)
    wanted = arguments.names(topics, name="topics", example="['/world/state']")
    if damage is not None and not isinstance(damage, list):
        raise ConfigError(f"damage = {arguments.shown(damage)}: must be a list (lines are appended to it), or None")
    if is_parts_manifest(path):
        for _first, _stop, part in part_files(path):
            if part is not None:
                yield from read_messages(part, topics, damage=damage)
            elif damage is not None:
                damage.append(f"{path}: part {_first}..{_stop - 1} is not recorded")
        return
    p = check_mcap(path)
    factory = DecoderFactory()
    decoders: dict[int, Callable[[bytes], Any] | None] = {}
    scan = Scan(p)
    try:
        for msg, dmg in scan.messages():
            if dmg is not None:
                if damage is not None:
                    damage.append(f"{p}: {dmg.describe()}")
                continue
            ch = scan.channels.get(msg.channel_id)
            if ch is None or (wanted is not None and ch.topic not in wanted):
                continue
            if msg.channel_id not in decoders:
                try:
                    decoders[msg.channel_id] = factory.decoder_for(ch.message_encoding, scan.schemas.get(ch.schema_id))
                except Exception as exc:
                    raise IoError(f"{p}: channel {ch.topic} has an unreadable schema ({type(exc).__name__})") from None
            dec = decoders[msg.channel_id]
            if dec is None:  # not protobuf: no recording of mmusv's (yielding nothing would look like an empty one)
                raise IoError(
                    f"{p}: channel {ch.topic} holds {ch.message_encoding or 'unencoded'!r} messages, not protobuf: "
                    "not a recording of mmusv run (read other MCAP files with the mcap package)"
                )
            try:
                decoded = dec(msg.data)
            except Exception as exc:
                if damage is not None:
                    damage.append(f"{p}: a {ch.topic} message does not decode ({type(exc).__name__})")
                continue
            yield ch.topic, msg.log_time, decoded
    except OSError as exc:
        raise IoError(f"{p} cannot be read: {exc.strerror or exc}") from None
    have = {ch.topic for ch in scan.channels.values()}
    if wanted is not None and not scan.damage and wanted - have:
        raise ConfigError(
            f"{p} has no topic {', '.join(map(repr, sorted(wanted - have)))}; its topics: {', '.join(sorted(have))}"
        )


def frame_messages(path: str | Path, frame: int) -> dict[str, Any]:
    """Every decoded message of acquisition index ``frame``, by topic; for a parts manifest, from the part
    holding ``frame``. Raises :class:`~mmusv.errors.IoError` when the frame is damaged or lost with damaged or
    missing bytes (naming the damage) and :class:`~mmusv.errors.ConfigError` when the recording does not hold it
    (``frame`` must be a whole number)."""
    p = recording_arg(path)
    frame = arguments.whole(frame, name=named("frame"))
    said_frame = given("frame", frame)  # `--frame 5` from mmusv preview, `frame = 5` from Python
    if is_parts_manifest(p):
        files = part_files(p)
        for first, stop, part in files:
            if first <= frame < stop:
                if part is None:
                    raise ConfigError(f"{said_frame}: not in {p} yet: its part is not recorded")
                return frame_messages(part, frame)
        held = range(files[0][0], files[-1][1]) if files else range(0)
        raise ConfigError(f"{said_frame}: not in {p}, which holds {held_text(held)}")
    info = read_info(p)
    probe = FrameStream(info, want=lambda _t: False)
    span, _said = probe.expected()  # the frames the run set out to write
    held, said, why = probe.held()  # of them, those it wrote (an interrupted run: its first frames_written)
    if said and frame not in held:
        # "holds frames 0..4999" was said of a run stopped after 297
        raise ConfigError(f"{said_frame}: not in {p}, which holds {held_text(held)}{why}")
    # only the chunks around the frame are decompressed (a negative frame is in no recording: read to say so)
    stream = FrameStream(info, want=lambda _t: True, frames=(frame, frame + 1) if frame >= 0 else None)
    for fr in stream:
        if fr.index == frame:
            return dict(fr.messages)
        if fr.index > frame and not stream.damage:
            break
    bad = [why for k, why in stream.incomplete if k == frame]
    if bad:
        raise IoError(f"frame {frame} of {p} is damaged: {bad[0]}; {stream.truncated}")
    if stream.truncated and frame in span:  # a frame of the run, lost with a damaged chunk or a cut-off end
        # without run metadata (a killed run's .partial, or a copy cut short) it may never have been written
        unsure = "" if said else " (or was never written: the run's metadata, written at its end, is not there)"
        raise IoError(f"frame {frame} of {p} is lost to damage{unsure} ({stream.truncated})")
    where = f" ({stream.truncated})" if stream.truncated else ""
    raise ConfigError(
        f"{said_frame}: not in {p}, {'which holds' if said else 'whose run set out to write'} {held_text(span)}{where}"
    )
