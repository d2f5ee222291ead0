"""The frames of an ``mmusv run`` recording, one at a time: :class:`FrameStream` walks the file once, front to back
(:mod:`mmusv.recording.scan`), decodes only the topics asked for and yields one :class:`Frame` per log time (every
message of a frame shares its log time; the frame's index is its ``/world/state`` frame number). It works on
finished, truncated and ``.partial`` files alike: a file that ends in the middle of a record (a killed writer)
yields every frame read so far and says where it stopped in :attr:`FrameStream.truncated`; the ``run`` metadata,
written last, is picked up when present. The metadata it starts from: :func:`mmusv.recording.info.read_info`.

A recording split into frame ranges (:mod:`mmusv.recording.parts`) is walked part by part in frame order as one
sequence; a part not recorded yet is left out (its frames are missing, as those of an interrupted run).
:func:`warn_missing` says when frames are missing, :func:`frame_ranges` writes frame indices as ``0..3, 7``
(:func:`frames_text`: ``frames 0..3, 7``, ``frame 7``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mmusv import arguments
from mmusv.errors import ConfigError, IoError
from mmusv.recording.decode import WorldFrame
from mmusv.recording.info import RecordingInfo
from mmusv.recording.parts import is_parts_manifest, part_files
from mmusv.recording.scan import Scan
from mmusv.recording.topics import WORLD_STATE

__all__ = ["Frame", "FrameStream", "frame_ranges", "frames_text", "held_text", "warn_missing"]


@dataclass
class Frame:
    """Every decoded message of acquisition index ``index``: ``log_time_ns`` its log time (simulation time
    ``k / f``, integer nanoseconds), ``world`` its decoded ``/world/state``, ``messages`` the decoded messages by
    topic."""

    index: int
    log_time_ns: int
    world: WorldFrame | None
    messages: dict[str, Any] = field(default_factory=dict)


def frame_ranges(frames: Sequence[int]) -> str:
    """Frame indices as text, ``0..3, 7, 9..12`` (sorted, each index once; runs of consecutive indices as
    ``first..last``)."""
    out: list[str] = []
    run: list[int] = []
    for k in sorted(set(frames)):
        if run and k == run[-1] + 1:
            run.append(k)
            continue
        if run:
            out.append(f"{run[0]}..{run[-1]}" if len(run) > 1 else str(run[0]))
        run = [k]
    if run:
        out.append(f"{run[0]}..{run[-1]}" if len(run) > 1 else str(run[0]))
    return ", ".join(out)


def frames_text(frames: Sequence[int]) -> str:
    """``"frame 7"`` for one frame, ``"frames 0..3, 7"`` (:func:`frame_ranges`) for more: "frames 7 missing" was
    read as a count of seven."""
    return f"frame {frame_ranges(frames)}" if len(set(frames)) == 1 else f"frames {frame_ranges(frames)}"


@dataclass
class _Open:
    """A frame being read: its topics so far, whether it borders damaged bytes, why it is unusable (or None)."""

    frame: Frame
    suspect: bool = False
    topics: set[str] = field(default_factory=set)
    bad: str | None = None


class FrameStream:
    """Iterates the frames of a recording once (see the module docstring).

    Args:
        info: from :func:`~mmusv.recording.info.read_info`.
        want: which topics to decode (``/world/state`` always is); others are skipped undecoded.
        frames: only the acquisition indices ``start <= k < stop`` (``stop`` ``None``: to the end), found by their
            log times (``k / frequency``); the other frames are neither read nor yielded, chunks holding none of
            these frames are not even decompressed, and :meth:`expected` is limited to the range. ``None``: every
            frame.

    Damaged input (:mod:`mmusv.recording.scan`): a damaged chunk is skipped and the walk goes on after it; a file
    that ends inside a record yields what came before. Only complete frames are yielded: a frame whose messages
    were (partly) in a damaged chunk, or that borders damaged bytes and lacks a topic the intact frames have, is
    left out and listed in :attr:`incomplete`. After the iteration :attr:`damage` lists every damaged region,
    :attr:`truncated` says it in one line (``None`` for an intact file), :meth:`missing` gives the frames the run
    set out to write that were not yielded and :meth:`report` one line for the user (``None`` when nothing is
    missing). :attr:`topic_counts`, :attr:`messages`, :attr:`start_ns`, :attr:`end_ns`, :attr:`metadata` and
    :attr:`attachments` describe what was read (every message, decoded or not).
    """

    def __init__(
        self, info: RecordingInfo, want: Callable[[str], bool], *, frames: tuple[int, int | None] | None = None
    ) -> None:
        if not isinstance(info, RecordingInfo):
            raise ConfigError(
                f"info = {info!r:.80}: must be a RecordingInfo (mmusv.recording.read_info(path)), "
                f"not {type(info).__name__}"
            )
        if not callable(want):
            raise ConfigError(f"want = {want!r:.80}: must be a function of a topic name returning True or False")
        arguments.callback(want, name="want", nargs=1)  # `lambda: True` was a bare TypeError once reading began
        if isinstance(frames, tuple):  # numpy integers (an index taken from an array) count as ints
            frames = tuple(int(k) if isinstance(k, np.integer) else k for k in frames)  # type: ignore[assignment]
        if frames is not None and not (
            isinstance(frames, tuple)
            and len(frames) == 2
            and all(isinstance(k, int) and not isinstance(k, bool) for k in frames if k is not None)
            and frames[0] is not None
            and frames[0] >= 0
            and (frames[1] is None or frames[0] < frames[1])
        ):
            raise ConfigError(
                f"frames = {frames!r:.80}: must be (start, stop) with 0 <= start < stop, or (start, None)"
            )
        self.info = info
        self.want = want
        self.frames = frames
        self.truncated: str | None = None
        self.damage: list[str] = []
        self.incomplete: list[tuple[int, str]] = []
        self.yielded: list[int] = []
        self.run: dict[str, str] = dict(info.run)
        self.out_of_order: list[int] = []
        # log time -> whether a clean copy of its frame was whole, and the topics of its copies
        self._copies: dict[int, tuple[bool, set[str]]] = {}
        self._reading: Path = info.path  # the file (or part) being read
        self.topic_counts: dict[str, int] = {}
        self.topic_schemas: dict[str, tuple[str, str]] = {}
        self.messages = 0
        self.start_ns = -1
        self.end_ns = -1
        self.metadata: dict[str, dict[str, str]] = {}
        self.attachments: list[str] = []
        self.complete = True
        """Every file read ends with its data end, summary and footer, without damage."""
        self.chunks_skipped = 0
        """Chunks hopped over unread because they hold no frame of :attr:`frames`."""
        self._missing_parts: list[tuple[int, int, str]] = []
        self._ended = False
        held, said, why = self.held()
        if frames is not None and said and not self._in_range(held.start, held.stop - 1):
            # The run said which frames it wrote and none is in the range: an empty stream would look like a
            # recording without frames (and a conversion of it wrote an empty dataset).
            raise ConfigError(f"frames = {frames!r}: none is in {info.path}, which holds {held_text(held)}{why}")

    def _index(self, log_time_ns: int, world: WorldFrame | None) -> int:
        if world is not None:
            return world.frame
        return round(log_time_ns * self.info.frequency_hz / 1e9)

    def _in_range(self, first: int, last: int) -> bool:
        """Whether acquisition indices ``first..last`` (inclusive) meet :attr:`frames`."""
        if self.frames is None:
            return True
        start, stop = self.frames
        return last >= start and (stop is None or first < stop)

    def _wanted_times(self) -> Callable[[int, int], bool] | None:
        """Whether a span of log times (ns, inclusive) may hold a frame of :attr:`frames` (``None``: all may).
        The frame of log time ``t`` is ``round(t · frequency)``, monotonic in ``t``."""
        if self.frames is None or not self.info.frequency_hz > 0:
            return None
        f = self.info.frequency_hz
        return lambda t0, t1: self._in_range(round(t0 * f / 1e9), round(t1 * f / 1e9))

    def __iter__(self) -> Iterator[Frame]:
        seen: set[int] = set()
        if is_parts_manifest(self.info.path):
            for first, stop, f in part_files(self.info.path):
                if not self._in_range(first, stop - 1):
                    continue
                if f is None:
                    self._missing_parts.append((first, stop, f"part {first}..{stop - 1}"))
                    self.complete = False
                    continue
                yield from self._ranged(self._file(f, seen))
        else:
            yield from self._ranged(self._file(self.info.path, seen))
        self._ended = True

    def _ranged(self, frames: Iterator[Frame]) -> Iterator[Frame]:
        """The frames of :attr:`frames` (the log times leave out the others unless the frequency is unknown)."""
        return (fr for fr in frames if self._in_range(fr.index, fr.index))

    def _note(self, line: str) -> None:
        self.damage.append(line)
        self.truncated = "; ".join(self.damage)

    def _file(self, path: Path, seen: set[int]) -> Iterator[Frame]:
        from mcap_protobuf.decoder import DecoderFactory

        factory = DecoderFactory()
        decoders: dict[int, Callable[[bytes], Any] | None] = {}
        where = f"part {path.name} of {self.info.path.name}" if self.info.parts else "the file"
        self._reading = path
        times = self._wanted_times()
        scan = Scan(path, keep=times)
        lost: list[tuple[int, int]] = []  # log times of damaged chunks
        reference: set[str] = set()  # topics of the intact frames so far
        pending: list[_Open] = []  # frames next to damage, waiting for an intact frame to compare with
        cur: _Open | None = None
        after_damage = False
        try:
            for msg, dmg in scan.messages():
                if dmg is not None:
                    text = dmg.describe(self.info.frequency_hz)
                    self._note(f"{where} is truncated: {text}" if dmg.truncated else f"{where} is damaged at {text}")
                    if dmg.times is not None:
                        lost.append(dmg.times)
                    if cur is not None:
                        cur.suspect = True
                    after_damage = True
                    continue
                if times is not None and not times(msg.log_time, msg.log_time):
                    after_damage = False  # damage before it borders this frame, not one asked for
                    continue  # a frame outside the range asked for
                if cur is None or msg.log_time != cur.frame.log_time_ns:
                    if cur is not None:
                        yield from self._close(cur, pending, lost, reference, scan, seen, final=False)
                    cur = _Open(Frame(index=-1, log_time_ns=msg.log_time, world=None), suspect=after_damage)
                    after_damage = False
                ch = scan.channels.get(msg.channel_id)
                self.messages += 1
                self.start_ns = msg.log_time if self.start_ns < 0 else min(self.start_ns, msg.log_time)
                self.end_ns = max(self.end_ns, msg.log_time)
                if ch is None:
                    cur.bad = (
                        cur.bad or f"a message on channel {msg.channel_id}, whose definition was in a damaged chunk"
                    )
                    continue
                topic = ch.topic
                self.topic_counts[topic] = self.topic_counts.get(topic, 0) + 1
                if topic not in self.topic_schemas:
                    schema = scan.schemas.get(ch.schema_id)
                    self.topic_schemas[topic] = ("" if schema is None else schema.name, ch.message_encoding)
                if topic in cur.topics:
                    cur.bad = cur.bad or f"it holds two {topic} messages"
                cur.topics.add(topic)
                if topic != WORLD_STATE and not self.want(topic):
                    if not msg.data:  # as a decoding reader finds it (a cloud without fields): alike undecoded
                        cur.bad = cur.bad or f"its {topic} message is empty (0 bytes)"
                    continue
                try:
                    if msg.channel_id not in decoders:
                        decoders[msg.channel_id] = factory.decoder_for(
                            ch.message_encoding, scan.schemas.get(ch.schema_id)
                        )
                    dec = decoders[msg.channel_id]
                    if dec is None:
                        continue
                    decoded = dec(msg.data)
                    if topic == WORLD_STATE:
                        cur.frame.world = WorldFrame.from_message(decoded)
                except Exception as exc:  # a message whose bytes do not decode: the frame is not usable
                    cur.bad = cur.bad or f"its {topic} message does not decode ({type(exc).__name__})"
                    continue
                hollow = self._hollow(topic, decoded, cur.frame.world)
                if hollow is None and not msg.data:  # no message of an mmusv run is empty: not only those checked
                    hollow = "is empty (0 bytes)"
                if hollow is not None:  # bytes that decode to a message without what every reader takes from it
                    cur.bad = cur.bad or f"its {topic} message {hollow}"
                    if topic == WORLD_STATE:  # its frame number (0, from empty bytes) is not the frame's
                        cur.frame.world = None
                    continue
                cur.frame.messages[topic] = decoded
            if cur is not None:
                yield from self._close(cur, pending, lost, reference, scan, seen, final=True)
            elif pending:
                yield from self._flush(pending, lost, reference, scan, seen)
        except OSError as exc:
            raise IoError(f"{path} cannot be read: {exc.strerror or exc}") from None
        self.chunks_skipped += scan.skipped_chunks
        if scan.damage or not scan.complete:
            self.complete = False
        if not self.info.parts:
            if "run" in scan.metadata:  # parts: the merged run of read_info stands
                self.run = dict(scan.metadata["run"])
            self.metadata = dict(scan.metadata)
            self.attachments = list(scan.attachments)
        elif not self.metadata:
            self.metadata = dict(scan.metadata)
            self.attachments = list(scan.attachments)

    def _hollow(self, topic: str, decoded: Any, world: WorldFrame | None) -> str | None:
        """What a decoded message lacks that an mmusv recording's always holds, or ``None``: a world state without a
        row for each USV (its ``index``), a point cloud without x, y and z fields. Bytes of an empty message (or one
        cut at a field's end) decode without error to such a message, which the exporters then read as a bare
        ``IndexError`` or ``KeyError`` traceback."""
        if topic == WORLD_STATE and world is not None:
            need = max((a.index for a in self.info.agents), default=-1) + 1
            if len(world.ids) < need:
                return f"holds {len(world.ids)} vessels, fewer than the USVs' rows ({need})"
        elif type(decoded).__name__ == "PointCloud" and hasattr(decoded, "fields"):
            names = {f.name for f in decoded.fields}
            if not {"x", "y", "z"} <= names:
                return f"is a point cloud without {', '.join(sorted({'x', 'y', 'z'} - names))} fields"
        return None

    def _close(
        self,
        op: _Open,
        pending: list[_Open],
        lost: list[tuple[int, int]],
        reference: set[str],
        scan: Scan,
        seen: set[int],
        *,
        final: bool,
    ) -> Iterator[Frame]:
        """Yields the frames decided by closing ``op``: a frame next to damage waits (in ``pending``) until an
        intact frame says which topics a frame has; an intact frame settles the waiting ones, then itself."""
        if op.suspect and not reference and not final:
            pending.append(op)
            return
        if not op.suspect:
            why = self._why(op, lost, reference, scan)
            if why is None:
                reference |= op.topics
            yield from self._flush(pending, lost, reference, scan, seen)
            self._split(op, lost, whole=why is None)
            if why is None:
                yield self._accept(op.frame, seen)
            else:
                self.incomplete.append((self._index(op.frame.log_time_ns, op.frame.world), why))
            return
        pending.append(op)
        yield from self._flush(pending, lost, reference, scan, seen)

    def _flush(
        self, pending: list[_Open], lost: list[tuple[int, int]], reference: set[str], scan: Scan, seen: set[int]
    ) -> Iterator[Frame]:
        for op in pending:
            why = self._why(op, lost, reference, scan)
            self._split(op, lost, whole=why is None)
            if why is None:
                yield self._accept(op.frame, seen)
            else:
                self.incomplete.append((self._index(op.frame.log_time_ns, op.frame.world), why))
        pending.clear()

    def _split(self, op: _Open, lost: list[tuple[int, int]], *, whole: bool) -> None:
        """Raises :class:`~mmusv.errors.IoError` when the messages of one log time come in two runs away from any
        damage and neither is a whole frame holding the other's topics: a file whose messages are not in frame order
        (each topic in turn, as a tool that copies channel by channel writes them), whose every frame would be read
        in pieces. A frame recorded twice is read once when a copy is whole and holds the other's topics, the later
        one too (a frame written incomplete, then whole after later frames: ``tests/export/test_ros2_odometry.py``)."""
        t = op.frame.log_time_ns
        if op.suspect or any(a <= t <= b for a, b in lost):
            return
        prev = self._copies.get(t)
        # one copy holds the other's topics and is whole: a frame written again, not a frame in pieces
        if prev is not None and not (whole and op.topics >= prev[1]) and not (prev[0] and prev[1] >= op.topics):
            raise IoError(
                f"{self._reading}: the messages of the frame at {t / 1e9:.3f} s are not together in the file (not "
                "in log-time order: written topic by topic?); mmusv reads a recording frame by frame in file "
                "order, as mmusv run writes it: rewrite it in log-time order (the mcap package's "
                "iter_messages(log_time_order=True) into a new file)"
            )
        was_whole, topics = prev if prev is not None else (False, set())
        self._copies[t] = (was_whole or whole, topics | set(op.topics))

    def _why(self, op: _Open, lost: list[tuple[int, int]], reference: set[str], scan: Scan) -> str | None:
        """Why the frame of ``op`` is incomplete, or None."""
        t = op.frame.log_time_ns
        if op.bad is not None:
            return op.bad
        if op.frame.world is None:
            return f"it has no {WORLD_STATE} message"
        if any(a <= t <= b for a, b in lost):
            return "some of its messages were in a damaged chunk"
        if op.suspect:
            expected = reference or {c.topic for c in scan.channels.values()}
            gone = sorted(expected - op.topics)
            if gone:
                return f"it borders damaged bytes and lacks {', '.join(gone[:3])}" + (
                    f" and {len(gone) - 3} more" if len(gone) > 3 else ""
                )
        return None

    def _accept(self, fr: Frame, seen: set[int]) -> Frame:
        fr.index = self._index(fr.log_time_ns, fr.world)
        if fr.index in seen:
            self.out_of_order.append(fr.index)
        seen.add(fr.index)
        self.yielded.append(fr.index)
        return fr

    def set_out(self) -> range:
        """Every frame the run set out to write, as its ``run`` metadata says (``frames_requested`` from
        ``first_frame``), else as its ``manifest`` metadata said before the first frame (a killed run; a recovered
        one, whose run metadata count the frames kept), else the scenario's ``frames_configured``; a parts
        manifest's frames. Not narrowed to :attr:`frames`."""
        run = self.run
        if is_parts_manifest(self.info.path):
            return self._expected_all()[0]
        first = int(run.get("first_frame", 0) or 0)
        if "frames_requested" in run:
            return range(first, first + int(run.get("frames_requested") or 0))
        if self.info.planned is not None:
            start, count = self.info.planned
            return range(start, start + count)
        return range(first, first + int(run.get("frames_configured", self.info.frames_configured) or 0))

    def expected(self) -> tuple[range, bool]:
        """The frames the run set out to write (those in :attr:`frames` when given) and whether its ``run``
        metadata says so (``False``: it did not finish; the range is then the one its ``manifest`` metadata gave
        at the start, or for recordings that predate it the scenario's configured range)."""
        span, said = self._expected_all()
        if self.frames is not None:
            start, stop = self.frames
            span = range(max(span.start, start), span.stop if stop is None else min(span.stop, stop))
        return span, said

    def held(self) -> tuple[range, bool, str]:
        """The frames the recording holds as its ``run`` metadata says (all of :attr:`frames`, unlike
        :meth:`expected`), whether it says so (``False``: the run did not finish, and the range is what it set out
        to write), and why it holds fewer than it set out to write, as ``" (its run is interrupted: 297 of the 5000
        frames it set out to write)"`` (``""`` for a complete run). An interrupted or failed run holds its first
        ``frames_written`` frames: they are written in frame order (a recovered one says only those). A parts
        manifest's parts may be missing anywhere: it holds what its parts set out to write."""
        span, said = self._expected_all()
        status, written = self.run.get("status"), str(self.run.get("frames_written", ""))
        if (
            not said
            or is_parts_manifest(self.info.path)
            or status in (None, "complete")
            or not written.isdigit()
            or int(written) >= len(span)
        ):
            return span, said, ""
        n = int(written)
        why = f" (its run is {status}: {n} of the {len(span)} frames it set out to write)"
        return range(span.start, span.start + n), said, why

    def _expected_all(self) -> tuple[range, bool]:
        run = self.run
        if is_parts_manifest(self.info.path):
            return range(int(run.get("frames_requested", self.info.frames_configured) or 0)), True
        first = int(run.get("first_frame", 0) or 0)
        if "frames_requested" in run or "frames_written" in run:
            n = int(run.get("frames_requested", run.get("frames_written", 0)) or 0)
            return range(first, first + n), True
        if self.info.planned is not None:  # a run that did not finish: what it set out to write
            start, count = self.info.planned
            return range(start, start + count), False
        return range(first, first + self.info.frames_configured), False

    def missing(self) -> list[int]:
        """The frames of :meth:`expected` that were not yielded (call after the iteration)."""
        got = set(self.yielded)
        return [k for k in self.expected()[0] if k not in got]

    def report(self) -> str | None:
        """One line saying which frames are missing and why, or ``None`` when every expected frame was read and
        the file is intact (call after the iteration)."""
        missing = self.missing()
        if not missing and not self.damage and not self.incomplete:
            return None
        span, said = self.expected()
        parts = [f"{self.info.path}: {len(set(self.yielded))} of {len(span)} frames read"]
        if missing:
            # a killed run's .partial has no run metadata (written last); nor has a finished run's copy cut short
            killed = any(str(f).endswith(".partial") for f in (self.info.path, *self.info.parts))
            unsaid = "the run did not finish" + ("" if killed else ", or this copy is cut before its end")
            why = [] if said else [f"{unsaid} (no run metadata)"]
            status = self.run.get("status")
            if said and status and status != "complete":
                why.append(f"run status {status}: {self.run.get('frames_written', '?')} frames written")
            parts.append(f"{frames_text(missing)} missing" + (f" ({'; '.join(why)})" if why else ""))
        if self.incomplete:
            parts.append(
                "incomplete frames left out: "
                + "; ".join(f"frame {k} ({why})" for k, why in self.incomplete[:4])
                + (f" and {len(self.incomplete) - 4} more" if len(self.incomplete) > 4 else "")
            )
        for first, stop, name in self._missing_parts:
            parts.append(f"{name} (frames {first}..{stop - 1}) is not recorded")
        parts += self.damage
        return "; ".join(parts)


def held_text(frames: range) -> str:
    """``"frames 0..296"`` (``"frame 0"`` for one, ``"no frames"`` for none): what a recording holds, in
    messages."""
    if len(frames) == 1:
        return f"frame {frames.start}"
    return f"frames {frames.start}..{frames.stop - 1}" if len(frames) else "no frames"


def warn_missing(stream: FrameStream, *, reader: str) -> None:
    """Warns (:class:`mmusv.scenario_checks.MmusvWarning`, one ``mmusv: warning:`` line on the command line)
    when ``stream`` read fewer frames than the run set out to write or met damaged bytes; ``reader`` says who
    read it (``"the detection study"``)."""
    import warnings

    from mmusv.scenario_checks import MmusvWarning

    line = stream.report()
    if line is not None:
        warnings.warn(f"{reader}: {line}", MmusvWarning, stacklevel=2)
