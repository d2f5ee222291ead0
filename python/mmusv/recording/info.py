"""The metadata of an ``mmusv run`` recording, read without decoding any message: what a recording says about
itself (:class:`RecordingInfo`: scenario, config hash, seed, rate, frames, its instrumented agents and ``run``).

:func:`read_info` reads the metadata records (``scenario``, ``manifest``, ``sensors``, ``run``) from the summary
section when the file has one, otherwise from the records before the first chunk (a truncated or ``.partial``
file; :mod:`mmusv.recording.scan` hops over the chunks). Given a parts manifest (:mod:`mmusv.recording.parts`) it
merges the recorded parts' metadata (``run.status`` is ``complete`` only when every part is; ``run.frames_written``
sums what each part says, and for a part killed before its ``run`` metadata, the complete frames read from it).
Mounts are ``(4, 4)`` sensor → vessel body matrices (metres; body frame x forward, y left, z up); camera
intrinsics are pixels. :func:`check_mcap` says whether a path is an MCAP file at all, :func:`recording_name` and
:func:`mmusv.recording.folders.find_recordings` name and find recordings (an ``.mcap`` or a parts manifest, which
stands for its parts).
The frames themselves: :mod:`mmusv.recording.stream`.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import yaml

from mmusv import arguments
from mmusv.errors import IoError
from mmusv.recording.parts import is_parts_manifest, part_files, read_parts_manifest
from mmusv.recording.scan import MAGIC, Scan

if TYPE_CHECKING:
    from mmusv.recording.decode import WorldFrame

__all__ = [
    "AgentInfo",
    "CameraInfo",
    "RecordingInfo",
    "check_mcap",
    "ends_in_header",
    "read_info",
    "recording_name",
    "written_by_mmusv",
]


@dataclass(frozen=True)
class CameraInfo:
    """A pinhole camera of an agent: image size (``width``, ``height`` pixels), horizontal field of view
    ``hfov_deg`` degrees, intrinsics ``(fx, fy, cx, cy)`` pixels, ``mount`` ``(4, 4)`` float64 camera body (x
    forward = optical axis, y left, z up) → vessel body (metres), recorded outputs, and its
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
    ``(4, 4)`` float64 sensor → vessel body (metres; ``None`` without that sensor), its cameras and the rig as
    recorded."""

    id: str
    index: int
    asset: str
    lidar_mount: np.ndarray | None
    radar_mount: np.ndarray | None
    cameras: dict[str, CameraInfo]
    rig: dict[str, Any]

    def sensor_poses(self, world: WorldFrame) -> tuple[np.ndarray, np.ndarray | None, dict[str, np.ndarray]]:
        """``(body, lidar, cameras)`` at ``world``: ``(4, 4)`` float64 vessel body → world (metres; from the
        world-state pose) and sensor → world = body · the recorded mount (LiDAR ``None`` without one; cameras by
        name, camera body frame x forward = optical axis). The one place a reader of the file composes body and
        mount."""
        from mmusv.frames import pose_matrices

        body = pose_matrices(world.poses[self.index])
        lidar = None if self.lidar_mount is None else body @ self.lidar_mount
        return body, lidar, {name: body @ c.mount for name, c in self.cameras.items()}

    @property
    def ppi_metres_per_pixel(self) -> float | None:
        """Metres per pixel of the recorded radar PPI (``ppi_metres_per_pixel``, default ``range_m / (ppi_size_px
        // 2)``, as :func:`mmusv.sensors.radar.ppi_request` drew it; :class:`mmusv.sensors.config.RadarConfig`);
        ``None`` without a radar."""
        radar = self.rig.get("radar")
        if not radar:
            return None
        mpp = radar.get("ppi_metres_per_pixel")
        return float(mpp) if mpp else float(radar["range_m"]) / max(int(radar["ppi_size_px"]) // 2, 1)


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
    planned: tuple[int, int] | None = None
    """``(first, count)``: the acquisition indices the run set out to write, as its ``manifest`` metadata said
    from the start (also in a ``.partial`` of a killed run); ``None`` for recordings that predate it."""
    planned_range: bool = False
    """Whether :attr:`planned` is a frame range recorded alone (one part of a split recording, ``acquire.run(
    frame_range=...)``, a preview's one frame) rather than a whole run from index 0 (the ``manifest`` metadata's
    ``frame_range: true``): a part 0 says so, where a whole run cut short by ``--frames`` does not."""

    @property
    def vessel_ids(self) -> list[str]:
        """Scenario vessel ids in file order (rows ``0..n-1`` of every world state)."""
        return [str(v["id"]) for v in self.scenario.get("vessels", [])]


def check_mcap(path: str | Path) -> Path:
    """``path`` as a Path after checking it is an existing, readable, non-empty file that starts with the MCAP
    magic; :class:`~mmusv.errors.IoError` naming the file otherwise."""
    p = Path(path)
    try:
        if not p.exists():
            raise IoError(f"recording {p} does not exist")
        if not p.is_file():
            if p.is_dir():
                from mmusv.recording.folders import folder_hint

                raise IoError(f"recording {p} is not a file (it is a directory){folder_hint(p)}")
            raise IoError(f"recording {p} is not a file")
        with p.open("rb") as f:
            head = f.read(len(MAGIC))
    except OSError as exc:
        raise IoError(f"recording {p} cannot be read: {exc.strerror or exc}") from None
    if not head:
        raise IoError(f"{p} is empty (0 bytes): not an MCAP recording")
    if len(head) < len(MAGIC) and MAGIC.startswith(head):  # a copy cut short: not "another kind of file"
        raise IoError(
            f"{p} is cut off inside the MCAP magic bytes ({len(head)} of {len(MAGIC)}): not a readable MCAP recording"
        )
    if head != MAGIC:
        raise IoError(f"{p} is not an MCAP file (it does not start with the MCAP magic bytes)")
    return p


def written_by_mmusv(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is an MCAP file whose header names mmusv as its writer (``mmusv run``, ``mmusv recover``),
    read from its first bytes alone: a recording whose metadata is damaged or cut off is still one, and a ROS 2 bag
    (another library) is not. ``False`` for anything unreadable."""
    import struct

    try:
        with open(path, "rb") as f:
            head = f.read(512)
    except OSError:
        return False
    if not head.startswith(MAGIC) or len(head) < len(MAGIC) + 13 or head[len(MAGIC)] != 0x01:
        return False
    at = len(MAGIC) + 9  # the header record's opcode and length, then its profile and library strings
    (n,) = struct.unpack_from("<I", head, at)
    at += 4 + n
    if at + 4 > len(head):
        return False
    (n,) = struct.unpack_from("<I", head, at)
    return head[at + 4 : at + 4 + n].startswith(b"mmusv")


def ends_in_header(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` starts with the MCAP magic but ends before its header record does (a copy cut short right
    at its start): which program wrote it cannot be told. ``False`` for anything unreadable."""
    import struct

    try:
        with open(path, "rb") as f:
            head = f.read(len(MAGIC) + 9)
            size = os.fstat(f.fileno()).st_size
    except OSError:
        return False
    if not head.startswith(MAGIC):
        return False
    if len(head) < len(MAGIC) + 9:
        return True
    if head[len(MAGIC)] != 0x01:  # not a header record: damaged, not cut
        return False
    (n,) = struct.unpack_from("<Q", head, len(MAGIC) + 1)
    return bool(size < len(MAGIC) + 9 + n)


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


def another_run(folder: Path, recording: str) -> str | None:
    """The file name of the recording whose finished run ``folder`` holds, when it is not ``recording`` (a file
    name) and is still there; ``None`` otherwise (no ``manifest.json``, one that is not a run's, or its recording
    gone). A run or a recovery of ``recording`` into ``folder`` would replace that run's ``manifest.json`` and
    tables."""
    try:
        manifest = json.loads((folder / "manifest.json").read_bytes())
    except (OSError, ValueError):
        return None
    other = manifest.get("recording") if isinstance(manifest, dict) else None
    if not isinstance(other, str) or other == recording or "/" in other or "\\" in other or other in ("", ".", ".."):
        return None
    return other if (folder / other).is_file() else None


def recording_name(path: str | os.PathLike[str]) -> str:
    """The name of the recording at ``path``: the file name without ``.mcap`` (``.mcap.partial``) or
    ``.parts.json``."""
    name = Path(path).name
    for suffix in (".parts.json", ".mcap.partial", ".mcap"):
        if name.endswith(suffix):
            return name[: -len(suffix)]
    return Path(path).stem


def _read_parts_info(p: Path) -> RecordingInfo:
    m = read_parts_manifest(p)
    files = part_files(p)
    infos = [(first, read_info(f)) for first, _stop, f in files if f is not None]
    stops = {first: stop for first, stop, _f in files}
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
        # A finished part says which frames it was asked for: a whole recording put in its place says nothing.
        if i.run.get("status") is not None and got is None:
            raise IoError(
                f"{p}: {i.path} is a whole recording, not a part (no first_frame); the manifest puts frames "
                f"{first}..{stops[first] - 1} there"
            )
        asked = i.run.get("frames_requested")
        if got is not None and asked is not None and int(asked) != stops[first] - first:
            raise IoError(
                f"{p}: part {i.path} holds frames {first}..{first + int(asked) - 1}, the manifest says "
                f"{first}..{stops[first] - 1}"
            )
    base = infos[0][1]
    done = sum(1 for _f, i in infos if i.run.get("status") == "complete")
    status = "complete" if done == len(files) else f"incomplete ({done} of {len(files)} parts complete)"
    run = {k: v for k, v in base.run.items() if k not in ("status", "error", "first_frame")}
    run.update(
        status=status,
        frames_written=str(sum(_part_frames(i) for _f, i in infos)),
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


def _part_frames(part: RecordingInfo) -> int:
    """The frames one part of a split recording holds: as its ``run`` metadata says, or, for a part killed before it
    could say (a ``.partial`` without ``run`` metadata), the complete frames read from it. Counted as 0, a killed
    split run's parts made ``mmusv info`` say 0 frames written where they held every frame."""
    said = part.run.get("frames_written")
    if said is not None:
        return int(said or 0)
    from mmusv.recording.stream import FrameStream

    stream = FrameStream(part, want=lambda _t: False)
    for _ in stream:
        pass
    return len(set(stream.yielded))


def recording_arg(path: object) -> Path:
    """The ``path`` argument of the readers as a :class:`~pathlib.Path`: a ``str`` or ``os.PathLike`` naming a
    recording, else a :class:`~mmusv.errors.ConfigError` (``bytes``, numbers and ``None`` are not paths)."""
    return arguments.path(path, name="recording path")


def read_info(path: str | Path) -> RecordingInfo:
    """The metadata of the recording at ``path`` (an ``.mcap`` or a parts manifest; see the module docstring)."""
    path = recording_arg(path)
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
    _check_run_counts(p, run)
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
        planned=_planned(manifest),
        planned_range=manifest.get("frame_range") == "true",
    )


RUN_COUNTS = ("first_frame", "frames_configured", "frames_requested", "frames_written")
"""The ``run`` metadata fields that are whole numbers of frames (the readers take them as ``int``)."""


def _check_run_counts(p: Path, run: dict[str, str]) -> None:
    """Refuses (:class:`~mmusv.errors.IoError` naming the file and the field) a ``run`` metadata count of
    :data:`RUN_COUNTS` that is not a whole number in ``0..MAX_FRAMES``: ``frames_written = "x"`` was a bare
    ``ValueError`` traceback in the middle of a conversion, ``"-3"`` was taken."""
    from mmusv.config import MAX_FRAMES

    for key in RUN_COUNTS:
        value = run.get(key)
        if value in (None, ""):  # not said (an older or interrupted run): the readers fall back
            continue
        text = str(value).strip()
        if not (text.isascii() and text.isdigit() and int(text) <= MAX_FRAMES):
            raise IoError(
                f"{p}: damaged run metadata: {key} = {arguments.shown(value)}, must be a whole number of frames in "
                f"0..{MAX_FRAMES:,}"
            )


def _planned(manifest: dict[str, str]) -> tuple[int, int] | None:
    """``(first, count)`` from the ``manifest`` metadata, or ``None`` when it does not say (or says nonsense)."""
    try:
        first, count = int(manifest["first_frame"]), int(manifest["frames_requested"])
    except (KeyError, ValueError):
        return None
    from mmusv.config import MAX_FRAMES

    ok = 0 <= first <= MAX_FRAMES and 0 < count <= MAX_FRAMES  # a damaged file's 10**18 would be iterated
    return (first, count) if ok else None
