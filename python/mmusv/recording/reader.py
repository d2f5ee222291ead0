"""Reading ``mmusv run`` recordings: the one reader used by ``mmusv info``, ``mmusv preview``, export and studies.

:func:`read_messages` iterates decoded messages, :func:`summary` says what a file holds, :func:`frame_messages`
gives every decoded message of one frame (:mod:`mmusv.recording.decode` turns Foxglove messages into arrays).
Frame by frame, for conversion (also a truncated or ``.partial`` file):

:func:`read_info` reads the metadata (``scenario``, ``manifest``, ``sensors``, ``run``) without decoding any
message: from the summary section when the file has one, otherwise from the records before the first chunk.
:class:`FrameStream` then walks the file once, front to back, with the streaming MCAP reader, decodes only the
topics asked for and yields one :class:`Frame` per log time (every message of a frame shares its log time). A
file that ends in the middle of a record (a killed writer) yields every frame read so far and says where it
stopped in :attr:`FrameStream.truncated`; the ``run`` metadata, written last, is picked up when present.

A recording split into frame ranges (:mod:`mmusv.recording.parts`) is read through its ``<name>.parts.json``
manifest wherever an ``.mcap`` is accepted: :func:`read_info` merges the parts' metadata (``run.status`` is
``complete`` only when every part is), :class:`FrameStream`, :func:`read_messages`, :func:`summary` and
:func:`frame_messages` walk the parts in frame order as one sequence. A part not recorded yet is left out (its
frames are missing, as those of an interrupted run); :func:`recording_name` is the sequence's name either way.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from mmusv.errors import ConfigError, IoError
from mmusv.recording.parts import is_parts_manifest, read_parts_manifest
from mmusv.recording.scan import Scan
from mmusv.recording.topics import WORLD_STATE

__all__ = [
    "MCAP_MAGIC",
    "AgentInfo",
    "CameraInfo",
    "Frame",
    "FrameStream",
    "RecordingInfo",
    "WorldFrame",
    "check_mcap",
    "find_recordings",
    "frame_messages",
    "read_info",
    "read_messages",
    "recording_name",
    "summary",
    "warn_missing",
]

MCAP_MAGIC = b"\x89MCAP0\r\n"


@dataclass(frozen=True)
class CameraInfo:
    """A pinhole camera of an agent: image size, intrinsics ``(fx, fy, cx, cy)`` pixels, ``mount``
    ``(4, 4)`` camera body (x forward = optical axis, y left, z up) → vessel body, recorded outputs, and its
    Brown–Conrady ``distortion`` ``(k1, k2, p1, p2, k3)`` (OpenCV's order; ``None``: an ideal pinhole)."""

    name: str
    width: int
    height: int
    hfov_deg: float
    intrinsics: tuple[float, float, float, float]
    mount: np.ndarray
    outputs: tuple[str, ...]
    distortion: tuple[float, float, float, float, float] | None = None


def _distortion(value: Any) -> tuple[float, float, float, float, float] | None:
    """A recorded camera's ``distortion`` entry: five finite numbers, or ``None`` (absent or null)."""
    if value is None:
        return None
    vals = [float(x) for x in value]
    if len(vals) != 5 or not all(math.isfinite(x) for x in vals):
        raise IoError(f"camera distortion must be five finite numbers [k1, k2, p1, p2, k3], got {value!r}")
    return (vals[0], vals[1], vals[2], vals[3], vals[4])


@dataclass(frozen=True)
class AgentInfo:
    """An instrumented USV: ``index`` in the scenario's vessel list (= its row in the world state), mounts
    ``(4, 4)`` sensor → vessel body, its cameras and the rig as recorded."""

    id: str
    index: int
    asset: str
    lidar_mount: np.ndarray | None
    radar_mount: np.ndarray | None
    cameras: dict[str, CameraInfo]
    rig: dict[str, Any]

    def sensor_poses(self, world: WorldFrame) -> tuple[np.ndarray, np.ndarray | None, dict[str, np.ndarray]]:
        """``(body, lidar, cameras)`` at ``world``: ``(4, 4)`` vessel body → world (from the world-state pose) and
        sensor → world = body · the recorded mount (LiDAR ``None`` without one; cameras by name, camera body frame
        x forward = optical axis). The one place a reader of the file composes body and mount."""
        from mmusv.frames import pose_matrices

        body = pose_matrices(world.poses[self.index])
        lidar = None if self.lidar_mount is None else body @ self.lidar_mount
        return body, lidar, {name: body @ c.mount for name, c in self.cameras.items()}

    @property
    def ppi_metres_per_pixel(self) -> float | None:
        """Metres per pixel of the recorded radar PPI (``ppi_metres_per_pixel``, default ``range_m / (ppi_size_px
        / 2)``, as in :class:`mmusv.sensors.config.RadarConfig`); ``None`` without a radar."""
        radar = self.rig.get("radar")
        if not radar:
            return None
        mpp = radar.get("ppi_metres_per_pixel")
        return float(mpp) if mpp else float(radar["range_m"]) / (int(radar["ppi_size_px"]) / 2)


@dataclass
class RecordingInfo:
    """What a recording says about itself (metadata only)."""

    path: Path
    scenario_name: str
    scenario: dict[str, Any]
    config_hash: str
    seed: int | None
    mmusv_version: str
    frequency_hz: float
    frames_configured: int
    agents: list[AgentInfo]
    run: dict[str, str]
    has_summary: bool
    parts: tuple[Path, ...] = ()
    """For a parts manifest: the recorded part files in frame order (``path`` is the manifest); else empty."""

    @property
    def vessel_ids(self) -> list[str]:
        """Scenario vessel ids in file order (rows ``0..n-1`` of every world state)."""
        return [str(v["id"]) for v in self.scenario.get("vessels", [])]


@dataclass(frozen=True)
class WorldFrame:
    """One ``/world/state``: per vessel (scenario vessels in file order, then moored ships) its id, asset,
    role, class, instance, pose ``(V, 6)`` [x, y, z, roll, pitch, yaw], velocity ``(V, 3)``, box centre
    ``(V, 3)`` (world) and box size ``(V, 3)`` (length, beam, height)."""

    frame: int
    time_s: float
    ids: list[str]
    assets: list[str]
    roles: list[str]
    classes: np.ndarray
    instance_ids: np.ndarray
    poses: np.ndarray
    velocities: np.ndarray
    box_centers: np.ndarray
    box_sizes: np.ndarray

    @staticmethod
    def from_message(msg: Any) -> WorldFrame:
        """From a decoded ``mmusv.WorldState``."""
        vs = list(msg.vessels)

        def rows(attr: str, k: int) -> np.ndarray:
            return np.array([list(getattr(v, attr)) for v in vs], dtype=np.float64).reshape(len(vs), k)

        return WorldFrame(
            frame=int(msg.frame),
            time_s=float(msg.time_s),
            ids=[v.id for v in vs],
            assets=[v.asset for v in vs],
            roles=[v.role for v in vs],
            classes=np.array([v.semantic_class for v in vs], dtype=np.int64),
            instance_ids=np.array([v.instance_id for v in vs], dtype=np.int64),
            poses=rows("pose", 6),
            velocities=rows("velocity", 3),
            box_centers=rows("box_center", 3),
            box_sizes=rows("box_size", 3),
        )


@dataclass
class Frame:
    """Every decoded message of one acquisition index: ``messages`` by topic."""

    index: int
    log_time_ns: int
    world: WorldFrame | None
    messages: dict[str, Any] = field(default_factory=dict)


def check_mcap(path: str | Path) -> Path:
    """``path`` as a Path after checking it is an existing, readable, non-empty file that starts with the MCAP
    magic; :class:`~mmusv.errors.IoError` naming the file otherwise."""
    p = Path(path)
    try:
        if not p.exists():
            raise IoError(f"recording {p} does not exist")
        if not p.is_file():
            raise IoError(f"recording {p} is not a file" + (" (it is a directory)" if p.is_dir() else ""))
        with p.open("rb") as f:
            head = f.read(len(MCAP_MAGIC))
    except OSError as exc:
        raise IoError(f"recording {p} cannot be read: {exc.strerror or exc}") from None
    if not head:
        raise IoError(f"{p} is empty (0 bytes): not an MCAP recording")
    if head != MCAP_MAGIC:
        raise IoError(f"{p} is not an MCAP file (it does not start with the MCAP magic bytes)")
    return p


def _scan_metadata(p: Path) -> Scan:
    """A walk over the records of ``p`` that hops over the chunks: its metadata, whether it is complete."""
    scan = Scan(p, chunks=False)
    try:
        for _ in scan.messages():
            pass
    except OSError as exc:
        raise IoError(f"recording {p} cannot be read: {exc.strerror or exc}") from None
    return scan


def _mat(v: Any) -> np.ndarray | None:
    if v is None:
        return None
    return np.asarray(v, dtype=np.float64).reshape(4, 4)


def recording_name(path: str | os.PathLike[str]) -> str:
    """The name of the recording at ``path``: the file name without ``.mcap`` (``.mcap.partial``) or
    ``.parts.json``."""
    name = Path(path).name
    for suffix in (".parts.json", ".mcap.partial", ".mcap"):
        if name.endswith(suffix):
            return name[: -len(suffix)]
    return Path(path).stem


def find_recordings(folder: str | os.PathLike[str]) -> list[Path]:
    """The recordings below ``folder``, sorted: every parts manifest and every ``.mcap`` that is not one of a
    manifest's parts."""
    root = Path(folder)
    manifests = sorted(root.rglob("*.parts.json"))
    parts = set()
    for m in manifests:
        parts |= {(m.parent / p.recording).resolve() for p in read_parts_manifest(m).parts}
    mcaps = [p for p in sorted(root.rglob("*.mcap")) if p.resolve() not in parts]
    return sorted([*manifests, *mcaps])


def _part_files(path: Path) -> list[tuple[int, int, Path | None]]:
    """``(first_frame, stop, file or None)`` of every part of the manifest at ``path``: the finished ``.mcap``,
    else its ``.partial`` (an interrupted part), else None (not recorded yet)."""
    m = read_parts_manifest(path)
    out: list[tuple[int, int, Path | None]] = []
    for part in m.parts:
        f = path.parent / part.recording
        partial = f.with_name(f.name + ".partial")
        out.append((part.first_frame, part.stop, f if f.is_file() else partial if partial.is_file() else None))
    return out


def _read_parts_info(p: Path) -> RecordingInfo:
    m = read_parts_manifest(p)
    files = _part_files(p)
    infos = [(first, read_info(f)) for first, _stop, f in files if f is not None]
    if not infos:
        raise IoError(
            f"{p}: none of its {len(files)} parts is recorded yet (the first is {p.parent / m.parts[0].recording})"
        )
    for first, i in infos:
        if i.config_hash != m.config_hash:
            raise IoError(
                f"{p}: part {i.path} was recorded from another configuration (config hash {i.config_hash[:12]}, "
                f"the manifest says {m.config_hash[:12]})"
            )
        got = i.run.get("first_frame")
        if got is not None and int(got) != first:
            raise IoError(f"{p}: part {i.path} starts at frame {got}, the manifest says {first}")
    base = infos[0][1]
    done = sum(1 for _f, i in infos if i.run.get("status") == "complete")
    status = "complete" if done == len(files) else f"incomplete ({done} of {len(files)} parts complete)"
    run = {k: v for k, v in base.run.items() if k not in ("status", "error", "first_frame")}
    run.update(
        status=status,
        frames_written=str(sum(int(i.run.get("frames_written", 0) or 0) for _f, i in infos)),
        frames_requested=str(m.frames),
        parts=str(len(files)),
    )
    return RecordingInfo(
        path=p,
        scenario_name=base.scenario_name,
        scenario=base.scenario,
        config_hash=m.config_hash,
        seed=base.seed,
        mmusv_version=base.mmusv_version,
        frequency_hz=base.frequency_hz,
        frames_configured=base.frames_configured,
        agents=base.agents,
        run=run,
        has_summary=status == "complete" and all(i.has_summary for _f, i in infos),
        parts=tuple(i.path for _f, i in infos),
    )


def read_info(path: str | Path) -> RecordingInfo:
    """The metadata of the recording at ``path`` (an ``.mcap`` or a parts manifest; see the module docstring)."""
    if is_parts_manifest(path):
        return _read_parts_info(Path(path))
    p = check_mcap(path)
    scan = _scan_metadata(p)
    meta = scan.metadata
    if "sensors" not in meta or "scenario" not in meta:
        hurt = "; ".join(d.describe() for d in scan.damage if not d.truncated or not meta)
        raise IoError(
            f"{p} has no scenario/sensors metadata; was it written by mmusv run?"
            + (f" (damaged: {hurt})" if hurt else "")
        )
    try:
        return _info(p, meta, scan.complete and not scan.damage)
    except (KeyError, IndexError, TypeError, ValueError, AttributeError, yaml.YAMLError) as exc:
        raise IoError(f"{p}: unreadable scenario/sensors metadata ({type(exc).__name__}: {exc})") from None


def _info(p: Path, meta: dict[str, dict[str, str]], has_summary: bool) -> RecordingInfo:
    sensors = json.loads(meta["sensors"]["json"])
    scenario = yaml.safe_load(meta["scenario"]["yaml"])
    if not isinstance(sensors, dict) or not isinstance(scenario, dict):
        raise ValueError("the scenario and sensors metadata must be mappings")
    manifest = meta.get("manifest", {})
    run = meta.get("run", {})
    ids = [str(v["id"]) for v in scenario.get("vessels", [])]
    acq = scenario.get("acquisition", {})
    agents: list[AgentInfo] = []
    for aid, s in sensors.items():
        if aid not in ids:
            raise IoError(f"{p}: sensors metadata names agent {aid!r}, which is not a scenario vessel")
        cams = {
            name: CameraInfo(
                name=name,
                width=int(c["resolution"][0]),
                height=int(c["resolution"][1]),
                hfov_deg=float(c["hfov_deg"]),
                intrinsics=(
                    float(c["intrinsics"][0]),
                    float(c["intrinsics"][1]),
                    float(c["intrinsics"][2]),
                    float(c["intrinsics"][3]),
                ),
                mount=np.asarray(c["mount_in_body"], dtype=np.float64).reshape(4, 4),
                outputs=tuple(c.get("outputs", ())),
                distortion=_distortion(c.get("distortion")),
            )
            for name, c in s.get("cameras", {}).items()
        }
        agents.append(
            AgentInfo(
                id=aid,
                index=ids.index(aid),
                asset=str(s.get("asset", "")),
                lidar_mount=_mat(s.get("lidar_mount_in_body")),
                radar_mount=_mat(s.get("radar_mount_in_body")),
                cameras=cams,
                rig=dict(s.get("rig", {})),
            )
        )
    agents.sort(key=lambda a: a.index)
    seed = manifest.get("seed", scenario.get("seed"))
    frequency = float(run.get("frequency_hz", acq.get("frequency_hz", 0.0)) or acq.get("frequency_hz", 0.0))
    frames = int(run.get("frames_configured", acq.get("frames", 0)) or 0)
    if not (math.isfinite(frequency) and frequency > 0 and frames > 0):  # damaged metadata, not a run's
        raise ValueError(f"acquisition frequency_hz = {frequency}, frames = {frames}")
    return RecordingInfo(
        path=p,
        scenario_name=str(meta["scenario"].get("name", scenario.get("name", p.stem))),
        scenario=scenario,
        config_hash=str(manifest.get("config_hash", "")),
        seed=None if seed in (None, "None") else int(seed),
        mmusv_version=str(manifest.get("mmusv_version", "")),
        frequency_hz=frequency,
        frames_configured=frames,
        agents=agents,
        run=dict(run),
        has_summary=has_summary,
    )


def _ranges(frames: Sequence[int]) -> str:
    """``0..3, 7, 9..12`` of sorted frame indices."""
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
        info: from :func:`read_info`.
        want: which topics to decode (``/world/state`` always is); others are skipped undecoded.

    Damaged input (:mod:`mmusv.recording.scan`): a damaged chunk is skipped and the walk goes on after it; a file
    that ends inside a record yields what came before. Only complete frames are yielded: a frame whose messages
    were (partly) in a damaged chunk, or that borders damaged bytes and lacks a topic the intact frames have, is
    left out and listed in :attr:`incomplete`. After the iteration :attr:`damage` lists every damaged region,
    :attr:`truncated` says it in one line (``None`` for an intact file), :meth:`missing` gives the frames the run
    set out to write that were not yielded and :meth:`report` one line for the user (``None`` when nothing is
    missing). :attr:`topic_counts`, :attr:`messages`, :attr:`start_ns`, :attr:`end_ns`, :attr:`metadata` and
    :attr:`attachments` describe what was read (every message, decoded or not).
    """

    def __init__(self, info: RecordingInfo, want: Callable[[str], bool]) -> None:
        self.info = info
        self.want = want
        self.truncated: str | None = None
        self.damage: list[str] = []
        self.incomplete: list[tuple[int, str]] = []
        self.yielded: list[int] = []
        self.run: dict[str, str] = dict(info.run)
        self.out_of_order: list[int] = []
        self.topic_counts: dict[str, int] = {}
        self.topic_schemas: dict[str, tuple[str, str]] = {}
        self.messages = 0
        self.start_ns = -1
        self.end_ns = -1
        self.metadata: dict[str, dict[str, str]] = {}
        self.attachments: list[str] = []
        self.complete = True
        """Every file read ends with its data end, summary and footer, without damage."""
        self._missing_parts: list[tuple[int, int, str]] = []
        self._ended = False

    def _index(self, log_time_ns: int, world: WorldFrame | None) -> int:
        if world is not None:
            return world.frame
        return round(log_time_ns * self.info.frequency_hz / 1e9)

    def __iter__(self) -> Iterator[Frame]:
        seen: set[int] = set()
        if is_parts_manifest(self.info.path):
            for first, stop, f in _part_files(self.info.path):
                if f is None:
                    self._missing_parts.append((first, stop, f"part {first}..{stop - 1}"))
                    self.complete = False
                    continue
                yield from self._file(f, seen)
        else:
            yield from self._file(self.info.path, seen)
        self._ended = True

    def _note(self, line: str) -> None:
        self.damage.append(line)
        self.truncated = "; ".join(self.damage)

    def _file(self, path: Path, seen: set[int]) -> Iterator[Frame]:
        from mcap_protobuf.decoder import DecoderFactory

        factory = DecoderFactory()
        decoders: dict[int, Callable[[bytes], Any] | None] = {}
        where = f"part {path.name} of {self.info.path.name}" if self.info.parts else "the file"
        scan = Scan(path)
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
                cur.frame.messages[topic] = decoded
            if cur is not None:
                yield from self._close(cur, pending, lost, reference, scan, seen, final=True)
            elif pending:
                yield from self._flush(pending, lost, reference, scan, seen)
        except OSError as exc:
            raise IoError(f"{path} cannot be read: {exc.strerror or exc}") from None
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
            if why is None:
                yield self._accept(op.frame, seen)
            else:
                self.incomplete.append((self._index(op.frame.log_time_ns, op.frame.world), why))
        pending.clear()

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

    def expected(self) -> tuple[range, bool]:
        """The frames the run set out to write and whether the run said so itself (``False``: it did not finish,
        so this is the scenario's configured range)."""
        run = self.run
        if is_parts_manifest(self.info.path):
            return range(int(run.get("frames_requested", self.info.frames_configured) or 0)), True
        first = int(run.get("first_frame", 0) or 0)
        if "frames_requested" in run or "frames_written" in run:
            n = int(run.get("frames_requested", run.get("frames_written", 0)) or 0)
            return range(first, first + n), True
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
            why = [] if said else ["the run did not finish (no run metadata)"]
            status = self.run.get("status")
            if said and status and status != "complete":
                why.append(f"run status {status}: {self.run.get('frames_written', '?')} frames written")
            parts.append(f"frames {_ranges(missing)} missing" + (f" ({'; '.join(why)})" if why else ""))
        if self.incomplete:
            parts.append(
                "incomplete frames left out: "
                + "; ".join(f"{k} ({why})" for k, why in self.incomplete[:4])
                + (f" and {len(self.incomplete) - 4} more" if len(self.incomplete) > 4 else "")
            )
        for first, stop, name in self._missing_parts:
            parts.append(f"{name} (frames {first}..{stop - 1}) is not recorded")
        parts += self.damage
        return "; ".join(parts)


def warn_missing(stream: FrameStream, *, reader: str) -> None:
    """Warns (:class:`mmusv.scenario_checks.MmusvWarning`, one ``mmusv: warning:`` line on the command line)
    when ``stream`` read fewer frames than the run set out to write or met damaged bytes; ``reader`` says who
    read it (``"the detection study"``)."""
    import warnings

    from mmusv.scenario_checks import MmusvWarning

    line = stream.report()
    if line is not None:
        warnings.warn(f"{reader}: {line}", MmusvWarning, stacklevel=2)


def read_messages(
    path: str | os.PathLike[str], topics: Sequence[str] | None = None, *, damage: list[str] | None = None
) -> Iterator[tuple[str, int, Any]]:
    """Yields ``(topic, log_time_ns, decoded_protobuf_message)`` in file order (= log-time order for files of
    mmusv), optionally only ``topics``. Works on finished files, on ``.partial`` files and on parts manifests (the
    recorded parts in order); damaged chunks are skipped (:mod:`mmusv.recording.scan`) and described in
    ``damage`` when a list is given."""
    from mcap_protobuf.decoder import DecoderFactory

    if is_parts_manifest(path):
        for _first, _stop, part in _part_files(Path(path)):
            if part is not None:
                yield from read_messages(part, topics, damage=damage)
            elif damage is not None:
                damage.append(f"{path}: part {_first}..{_stop - 1} is not recorded")
        return
    p = check_mcap(Path(path))
    wanted = None if topics is None else set(topics)
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
            if dec is None:
                continue
            try:
                decoded = dec(msg.data)
            except Exception as exc:
                if damage is not None:
                    damage.append(f"{p}: a {ch.topic} message does not decode ({type(exc).__name__})")
                continue
            yield ch.topic, msg.log_time, decoded
    except OSError as exc:
        raise IoError(f"{p} cannot be read: {exc.strerror or exc}") from None


def summary(path: str | os.PathLike[str]) -> dict[str, Any]:
    """What a recording holds: ``{"path", "complete", "messages", "start_ns", "end_ns", "duration_s",
    "topics": {topic: {"schema", "encoding", "messages"}}, "metadata": {name: {key: value}},
    "attachments": [name, ...], "damage": [line, ...], "frames": {...} or None}``, counted by reading every
    chunk (checking its CRC). ``complete`` is False for a ``.partial`` file, one without a summary section or one
    with damage. ``frames`` (for a recording of mmusv): ``{"read", "expected", "missing", "report"}``, the
    complete frames read, how many the run set out to write, the missing ones and the one-line report of
    :meth:`FrameStream.report` (``None`` when all is well). A parts manifest gives the sums over its recorded parts,
    the metadata of the first with the merged ``run`` of :func:`read_info`, and ``parts`` (how many there are)."""
    p = Path(path)
    if is_parts_manifest(p):
        return _parts_summary(p)
    check_mcap(p)
    try:
        info: RecordingInfo | None = read_info(p)
    except IoError:
        info = None  # not a recording of mmusv run (or its metadata is damaged): messages only
    if info is None:
        return _plain_summary(p)
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
    info = _read_parts_info(path)
    stream = FrameStream(info, want=lambda _t: False)
    for _ in stream:
        pass
    out = _summary_dict(path, stream, complete=info.run["status"] == "complete" and stream.complete)
    first = summary(info.parts[0])
    out["metadata"] = {**first["metadata"], "run": dict(info.run)}
    out["attachments"] = first["attachments"]
    out["parts"] = int(info.run["parts"])
    return out


def frame_messages(path: str | Path, frame: int) -> dict[str, Any]:
    """Every decoded message of acquisition index ``frame``, by topic; for a parts manifest, from the part
    holding ``frame``. Raises :class:`~mmusv.errors.IoError` when the frame is damaged (naming the damage) and
    :class:`~mmusv.errors.ConfigError` when the recording does not hold it."""
    p = Path(path)
    if is_parts_manifest(p):
        for first, stop, part in _part_files(p):
            if first <= frame < stop:
                if part is None:
                    raise ConfigError(f"frame {frame} is not in {p}: its part is not recorded yet")
                return frame_messages(part, frame)
        raise ConfigError(f"frame {frame} is not in {p}")
    info = read_info(p)
    stream = FrameStream(info, want=lambda _t: True)
    for fr in stream:
        if fr.index == frame:
            return dict(fr.messages)
        if fr.index > frame and not stream.damage:
            break
    bad = [why for k, why in stream.incomplete if k == frame]
    if bad:
        raise IoError(f"frame {frame} of {p} is damaged: {bad[0]}; {stream.truncated}")
    where = f" ({stream.truncated})" if stream.truncated else ""
    raise ConfigError(f"frame {frame} is not in {p}{where}")
