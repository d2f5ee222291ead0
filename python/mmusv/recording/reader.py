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
import os
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np
import yaml

from mmusv.errors import ConfigError, IoError
from mmusv.recording.parts import is_parts_manifest, read_parts_manifest

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
]

MCAP_MAGIC = b"\x89MCAP0\r\n"


@dataclass(frozen=True)
class CameraInfo:
    """A pinhole camera of an agent: image size, intrinsics ``(fx, fy, cx, cy)`` pixels, ``mount``
    ``(4, 4)`` camera body (x forward = optical axis, y left, z up) → vessel body, recorded outputs."""

    name: str
    width: int
    height: int
    hfov_deg: float
    intrinsics: tuple[float, float, float, float]
    mount: np.ndarray
    outputs: tuple[str, ...]


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
    """``path`` as a Path after checking it is an existing file that starts with the MCAP magic."""
    p = Path(path)
    if not p.exists():
        raise IoError(f"recording {p} does not exist")
    if not p.is_file():
        raise IoError(f"recording {p} is not a file")
    with p.open("rb") as f:
        head = f.read(len(MCAP_MAGIC))
    if head != MCAP_MAGIC:
        raise IoError(f"{p} is not an MCAP file (it does not start with the MCAP magic bytes)")
    return p


def _metadata_from_summary(f: IO[bytes]) -> dict[str, dict[str, str]] | None:
    from mcap.reader import make_reader

    try:
        reader = make_reader(f)
        summary = reader.get_summary()
        if summary is None:
            return None
        return {m.name: dict(m.metadata) for m in reader.iter_metadata()}
    except Exception:  # a truncated file has no usable summary: fall back to streaming
        return None


def _metadata_from_head(f: IO[bytes]) -> dict[str, dict[str, str]]:
    from mcap.records import Chunk, DataEnd, Message, Metadata
    from mcap.stream_reader import StreamReader

    out: dict[str, dict[str, str]] = {}
    f.seek(0)
    try:
        for rec in StreamReader(f, emit_chunks=True).records:
            if isinstance(rec, Metadata):
                out[rec.name] = dict(rec.metadata)
            elif isinstance(rec, (Chunk, Message, DataEnd)):
                break
    except Exception:
        pass
    return out


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
    with p.open("rb") as f:
        meta = _metadata_from_summary(f)
        has_summary = meta is not None
        if meta is None:
            meta = _metadata_from_head(f)
    if "sensors" not in meta or "scenario" not in meta:
        raise IoError(f"{p} has no scenario/sensors metadata; was it written by mmusv run?")
    try:
        sensors = json.loads(meta["sensors"]["json"])
        scenario = yaml.safe_load(meta["scenario"]["yaml"])
    except (KeyError, ValueError, yaml.YAMLError) as exc:
        raise IoError(f"{p}: unreadable scenario/sensors metadata ({exc})") from None
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
    return RecordingInfo(
        path=p,
        scenario_name=str(meta["scenario"].get("name", scenario.get("name", p.stem))),
        scenario=scenario,
        config_hash=str(manifest.get("config_hash", "")),
        seed=None if seed in (None, "None") else int(seed),
        mmusv_version=str(manifest.get("mmusv_version", "")),
        frequency_hz=float(run.get("frequency_hz", acq.get("frequency_hz", 0.0)) or acq.get("frequency_hz", 0.0)),
        frames_configured=int(run.get("frames_configured", acq.get("frames", 0)) or 0),
        agents=agents,
        run=dict(run),
        has_summary=has_summary,
    )


class FrameStream:
    """Iterates the frames of a recording once (see the module docstring).

    Args:
        info: from :func:`read_info`.
        want: which topics to decode (``/world/state`` always is); others are skipped undecoded.
    """

    def __init__(self, info: RecordingInfo, want: Callable[[str], bool]) -> None:
        self.info = info
        self.want = want
        self.truncated: str | None = None
        self.run: dict[str, str] = dict(info.run)
        self.out_of_order: list[int] = []

    def _index(self, log_time_ns: int, world: WorldFrame | None) -> int:
        if world is not None:
            return world.frame
        return round(log_time_ns * self.info.frequency_hz / 1e9)

    def __iter__(self) -> Iterator[Frame]:
        seen: set[int] = set()
        for path in self.info.parts or (self.info.path,):
            yield from self._file(path, seen)

    def _file(self, path: Path, seen: set[int]) -> Iterator[Frame]:
        from mcap.records import Channel, Message, Metadata, Schema
        from mcap.stream_reader import StreamReader
        from mcap_protobuf.decoder import DecoderFactory

        factory = DecoderFactory()
        schemas: dict[int, Schema] = {}
        channels: dict[int, Channel] = {}
        decoders: dict[int, Callable[[bytes], Any] | None] = {}
        current: Frame | None = None
        with path.open("rb") as f:
            size = path.stat().st_size
            records = StreamReader(f, emit_chunks=False).records
            good = 0
            while True:
                try:
                    rec = next(records)
                except StopIteration:
                    break
                except Exception as exc:  # ends mid-record: keep what was read
                    where = f"part {path.name} of {self.info.path.name}" if self.info.parts else "the file"
                    truncated = (
                        f"{where} is truncated: it ends inside a record ({type(exc).__name__}) at byte {size}; "
                        f"the last complete record ends at byte {good}"
                    )
                    self.truncated = truncated if self.truncated is None else f"{self.truncated}; {truncated}"
                    break
                good = f.tell()
                if isinstance(rec, Schema):
                    schemas[rec.id] = rec
                elif isinstance(rec, Channel):
                    channels[rec.id] = rec
                elif isinstance(rec, Metadata):
                    if rec.name == "run" and not self.info.parts:  # parts: the merged run of read_info stands
                        self.run = dict(rec.metadata)
                elif isinstance(rec, Message):
                    ch = channels.get(rec.channel_id)
                    if ch is None:
                        continue
                    topic = ch.topic
                    if topic != "/world/state" and not self.want(topic):
                        continue
                    if rec.channel_id not in decoders:
                        decoders[rec.channel_id] = factory.decoder_for(ch.message_encoding, schemas.get(ch.schema_id))
                    dec = decoders[rec.channel_id]
                    if dec is None:
                        continue
                    if current is None or rec.log_time != current.log_time_ns:
                        if current is not None:
                            yield self._close(current, seen)
                        current = Frame(index=-1, log_time_ns=rec.log_time, world=None)
                    msg = dec(rec.data)
                    if topic == "/world/state":
                        current.world = WorldFrame.from_message(msg)
                    current.messages[topic] = msg
        if current is not None:
            yield self._close(current, seen)

    def _close(self, fr: Frame, seen: set[int]) -> Frame:
        fr.index = self._index(fr.log_time_ns, fr.world)
        if fr.index in seen:
            self.out_of_order.append(fr.index)
        seen.add(fr.index)
        return fr


def read_messages(path: str | os.PathLike[str], topics: Sequence[str] | None = None) -> Iterator[tuple[str, int, Any]]:
    """Yields ``(topic, log_time_ns, decoded_protobuf_message)`` in log-time order, optionally only ``topics``.
    Works on finished files, on completed ``.partial`` files and on parts manifests (the recorded parts in order)."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    if is_parts_manifest(path):
        for _first, _stop, part in _part_files(Path(path)):
            if part is not None:
                yield from read_messages(part, topics)
        return
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        wanted = None if topics is None else list(topics)
        for _schema, channel, message, decoded in reader.iter_decoded_messages(topics=wanted):
            yield channel.topic, message.log_time, decoded


def summary(path: str | os.PathLike[str]) -> dict[str, Any]:
    """What a recording holds: ``{"path", "complete", "messages", "start_ns", "end_ns", "duration_s",
    "topics": {topic: {"schema", "encoding", "messages"}}, "metadata": {name: {key: value}},
    "attachments": [name, ...]}``. ``complete`` is False for a ``.partial`` file or one without a summary
    section (counted by scanning every message). A parts manifest gives the sums over its recorded parts, the
    metadata of the first with the merged ``run`` of :func:`read_info`, and ``parts`` (how many there are)."""
    from mcap.reader import make_reader

    if is_parts_manifest(path):
        return _parts_summary(Path(path))
    topics: dict[str, dict[str, Any]] = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        summ = reader.get_summary()
        stats = None if summ is None else summ.statistics
        if summ is not None and stats is not None:
            for cid, ch in sorted(summ.channels.items()):
                schema = summ.schemas.get(ch.schema_id)
                topics[ch.topic] = {
                    "schema": "" if schema is None else schema.name,
                    "encoding": ch.message_encoding,
                    "messages": int(stats.channel_message_counts.get(cid, 0)),
                }
            total, start, end = int(stats.message_count), int(stats.message_start_time), int(stats.message_end_time)
            attachments = [a.name for a in summ.attachment_indexes]
        else:
            start, end, total = -1, -1, 0
            for schema, channel, message in reader.iter_messages(log_time_order=False):
                entry = topics.setdefault(
                    channel.topic,
                    {
                        "schema": "" if schema is None else schema.name,
                        "encoding": channel.message_encoding,
                        "messages": 0,
                    },
                )
                entry["messages"] += 1
                total += 1
                start = message.log_time if start < 0 else min(start, message.log_time)
                end = max(end, message.log_time)
            start, end = max(start, 0), max(end, 0)
            attachments = [a.name for a in reader.iter_attachments()]
        metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
    return {
        "path": str(path),
        "complete": summ is not None and not str(path).endswith(".partial"),
        "messages": total,
        "start_ns": start,
        "end_ns": end,
        "duration_s": (end - start) * 1e-9,
        "topics": dict(sorted(topics.items())),
        "metadata": metadata,
        "attachments": attachments,
    }


def _parts_summary(path: Path) -> dict[str, Any]:
    info = _read_parts_info(path)
    sums = [summary(p) for p in info.parts]
    topics: dict[str, dict[str, Any]] = {}
    for s in sums:
        for topic, t in s["topics"].items():
            topics.setdefault(topic, {**t, "messages": 0})["messages"] += t["messages"]
    start, end = min(s["start_ns"] for s in sums), max(s["end_ns"] for s in sums)
    return {
        "path": str(path),
        "complete": info.run["status"] == "complete" and all(s["complete"] for s in sums),
        "messages": sum(s["messages"] for s in sums),
        "start_ns": start,
        "end_ns": end,
        "duration_s": (end - start) * 1e-9,
        "topics": dict(sorted(topics.items())),
        "metadata": {**sums[0]["metadata"], "run": dict(info.run)},
        "attachments": sums[0]["attachments"],
        "parts": int(info.run["parts"]),
    }


def frame_messages(path: str | Path, frame: int) -> dict[str, Any]:
    """Every decoded message of acquisition index ``frame``, by topic (log time = frame / f); for a parts
    manifest, from the part holding ``frame``."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    p = Path(path)
    if is_parts_manifest(p):
        for first, stop, part in _part_files(p):
            if first <= frame < stop:
                if part is None:
                    raise ConfigError(f"frame {frame} is not in {p}: its part is not recorded yet")
                return frame_messages(part, frame)
        raise ConfigError(f"frame {frame} is not in {p}")
    if not p.is_file():
        raise IoError(f"recording {p} does not exist")
    out: dict[str, Any] = {}
    with p.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        freq = float(meta.get("run", {}).get("frequency_hz", "0") or 0)
        if freq <= 0:
            raise IoError(f"{p} has no run metadata (frequency_hz); was it written by mmusv run?")
        t = round(frame / freq * 1e9)
        # messages come in log-time order from t on; the frame ends at the first later log time
        for _schema, channel, message, decoded in reader.iter_decoded_messages(starting_at=t):
            if message.log_time != t:
                break
            out[channel.topic] = decoded
    if not out:
        raise ConfigError(f"frame {frame} is not in {p}")
    return out
