"""Finishing what a killed run left behind: ``mmusv recover DIR`` / :func:`recover`.

A run killed hard (SIGKILL, a power cut, out of memory) leaves ``<name>.mcap.partial``: every chunk written before
the kill, no ``run`` metadata, no summary or index, and the tables only up to their last flush. :func:`recover`
turns it into what a stopped run leaves:

1. reads the ``.partial`` with the damage-tolerant reader (:mod:`mmusv.recording.scan`): every complete frame,
   damaged chunks skipped;
2. writes ``<name>.mcap``, a valid MCAP with summary, chunk and message indexes (the official ``mcap`` writer,
   zstd chunks), holding the metadata and every message of the complete frames in their order, and ``run``
   metadata saying ``status: interrupted``, the frames kept and where they came from;
3. rebuilds the Parquet tables of those frames from the recorded world state and annotations (the same rows and
   parts as the run would have written: :data:`mmusv.acquire.TABLE_PART_FRAMES` frames per part), replacing any
   table parts the killed run left;
4. writes ``manifest.json`` (status ``interrupted``, so a batch re-run records the scenario again) and removes the
   ``.partial`` once everything else is in place. Each file is written under a temporary name and renamed.

The messages keep their bytes; the file around them differs from the recorder's (another writer), so a
recovered recording is not byte-identical to an unbroken run's, but decodes to the same messages frame by frame.
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mmusv.errors import IoError
from mmusv.recording.info import RecordingInfo, another_run, check_mcap, read_info
from mmusv.recording.scan import Scan
from mmusv.recording.stream import FrameStream
from mmusv.recording.tables import BOX_3D_VECTORS, WORLD_STATE_VECTORS, TableWriter, spread_columns
from mmusv.text import counted

__all__ = ["Recovered", "find_partial", "rebuild_tables", "recover"]

_CHUNK_BYTES = 4 << 20


@dataclass
class Recovered:
    """What :func:`recover` did: the recording written, the ``.partial`` it came from, the frames kept (of those
    the scenario configures, and of those the run set out to write), frames left out as incomplete (with why), the
    damage met and the tables folder."""

    recording: Path
    source: Path
    frames: list[int]
    frames_configured: int
    incomplete: list[tuple[int, str]] = field(default_factory=list)
    damage: list[str] = field(default_factory=list)
    tables: Path | None = None
    frames_requested: int | None = None
    """The frames the run set out to write (``mmusv run --frames N``), when the recording says so."""

    def lines(self) -> list[str]:
        """What to tell the user, one line each."""
        from mmusv.recording.stream import frame_ranges

        got = f"frames {frame_ranges(self.frames)}" if self.frames else "no complete frame"
        out = [
            f"recovered {len(self.frames)} of {counted(self.frames_requested or self.frames_configured, 'frame')} "
            f"({got}) from "
            f"{self.source} "
            f"into {self.recording}"
        ]
        out += [f"left out frame {k}: {why}" for k, why in self.incomplete]
        out += [f"damage: {d}" for d in self.damage]
        if self.tables is not None:
            out.append(f"tables rebuilt from the recording in {self.tables}")
        return out


def find_partial(target: str | os.PathLike[str]) -> Path:
    """The ``.partial`` recording ``target`` names: the file itself, or the one ``.mcap.partial`` in the folder."""
    p = Path(target)
    if not p.exists():
        raise IoError(f"{p} does not exist; recover takes a run folder or a .mcap.partial file left by a killed run")
    if p.is_dir():
        found = sorted(p.glob("*.mcap.partial"))
        if not found:
            done = sorted(p.glob("*.mcap"))
            hint = f" ({', '.join(f.name for f in done)} {'is' if len(done) == 1 else 'are'} finished)" if done else ""
            raise IoError(f"nothing to recover in {p}: it holds no .mcap.partial recording{hint}")
        if len(found) > 1:
            raise IoError(f"{p} holds {len(found)} .partial recordings ({', '.join(f.name for f in found)}); name one")
        return found[0]
    if not p.name.endswith(".mcap.partial"):
        raise IoError(f"{p}: recover takes a run folder or a .mcap.partial file left by a killed run")
    return check_mcap(p)


def _part_of(recording: Path) -> tuple[int, int] | None:
    """``(first_frame, frames)`` when ``recording`` is one part of a split recording (a parts manifest in a folder
    above it lists it), else ``None``. A killed part's ``.partial`` has no ``run`` metadata, so without this its
    recovery said nothing of where it starts, and the manifest then refused it as "a whole recording, not a
    part" (every reader of the manifest failed)."""
    from mmusv.errors import MmusvError
    from mmusv.recording.parts import PARTS_SUFFIX, read_parts_manifest

    want = recording.resolve()
    for folder in list(recording.resolve().parents)[:4]:
        for manifest in sorted(folder.glob(f"*{PARTS_SUFFIX}")):
            try:
                parts = read_parts_manifest(manifest).parts
            except MmusvError:
                continue
            for p in parts:
                if (manifest.parent / p.recording).resolve() == want:
                    return p.first_frame, p.frames
    return None


def _static_flags(info: RecordingInfo) -> dict[str, bool]:
    """Vessel id -> static (moored ships, scenario vessels at speed 0), as the run's tables say."""
    vessels = info.scenario.get("vessels", [])
    out: dict[str, bool] = {}
    for v in vessels if isinstance(vessels, list) else []:
        if isinstance(v, dict) and "id" in v:
            out[str(v["id"])] = float(v.get("speed_mps", 1.0) or 0.0) == 0.0
    return out


def _world_rows(w: Any, static: dict[str, bool]) -> dict[str, Any]:
    import numpy as np

    n = len(w.ids)
    cols: dict[str, Any] = {
        "frame": np.full(n, w.frame, dtype=np.int64),
        "time_s": np.full(n, w.time_s, dtype=np.float64),
        "vessel_id": list(w.ids),
        "asset": list(w.assets),
        "role": list(w.roles),
        "static": np.array([r == "moored" or static.get(i, False) for i, r in zip(w.ids, w.roles, strict=True)]),
        "semantic_class": w.classes.astype(np.int64),
        "instance_id": w.instance_ids.astype(np.int64),
    }
    spread_columns(cols, (w.poses, w.velocities, w.box_centers, w.box_sizes), WORLD_STATE_VECTORS)
    return cols


def _box_rows(ann: Any, roles: dict[str, str], static: dict[str, bool]) -> tuple[dict[str, Any], dict[str, Any]]:
    import numpy as np

    lid, cam = list(ann.boxes_lidar), list(ann.boxes_camera)

    def role(i: str) -> str:
        return roles.get(i, "target")

    def stat(i: str) -> bool:
        return role(i) == "moored" or static.get(i, False)

    def col(rows: list[Any], attr: str, k: int, dtype: Any = np.float64) -> np.ndarray:
        return np.array([list(getattr(r, attr)) for r in rows], dtype=dtype).reshape(len(rows), k)

    n, m = len(lid), len(cam)
    c, s, q = col(lid, "center", 3), col(lid, "size", 3), col(lid, "rotation", 4)
    box3: dict[str, Any] = {
        "frame": np.full(n, ann.frame, dtype=np.int64),
        "time_s": np.full(n, ann.time_s, dtype=np.float64),
        "agent": [ann.agent_id] * n,
        "target_id": [b.target_id for b in lid],
        "instance_id": np.array([b.instance_id for b in lid], dtype=np.int64),
        "semantic_class": np.array([b.semantic_class for b in lid], dtype=np.int64),
        "yaw": np.array([b.yaw for b in lid], dtype=np.float64),
        "lidar_points": np.array([b.lidar_points for b in lid], dtype=np.int64),
        "range_m": np.array([b.range_m for b in lid], dtype=np.float64),
        "role": [role(b.target_id) for b in lid],
        "static": np.array([stat(b.target_id) for b in lid], dtype=bool),
        "wave_occlusion": _waves(lid),
    }
    spread_columns(box3, (c, s, q), BOX_3D_VECTORS)
    box2: dict[str, Any] = {
        "frame": np.full(m, ann.frame, dtype=np.int64),
        "time_s": np.full(m, ann.time_s, dtype=np.float64),
        "agent": [ann.agent_id] * m,
        "camera": [b.camera for b in cam],
        "target_id": [b.target_id for b in cam],
        "visible_pixels": np.array([b.visible_pixels for b in cam], dtype=np.int64),
        "box_pixels": np.array([b.box_pixels for b in cam], dtype=np.int64),
        "role": [role(b.target_id) for b in cam],
        "static": np.array([stat(b.target_id) for b in cam], dtype=bool),
    }
    for k in ("x_min", "y_min", "x_max", "y_max", "truncation", "occlusion"):
        box2[k] = np.array([getattr(b, k) for b in cam], dtype=np.float64)
    box2["wave_occlusion"] = _waves(cam)
    return box3, box2


def _waves(boxes: list[Any]) -> Any:
    """The boxes' ``wave_occlusion``; NaN (null in the table) for boxes from a recording made before the field
    existed (its embedded schema lacks it)."""
    import numpy as np

    return np.array([getattr(b, "wave_occlusion", np.nan) for b in boxes], dtype=np.float64)


def _want(topic: str) -> bool:
    return topic.endswith("/annotations")


def rebuild_tables(
    recording: str | os.PathLike[str], tables_dir: str | os.PathLike[str], *, keep_if_empty: bool = False
) -> FrameStream:
    """Writes the Parquet tables of every complete frame of ``recording`` into ``tables_dir`` (replacing the parts
    there): ``world_state`` from ``/world/state``, ``boxes_3d`` and ``boxes_2d`` from each agent's
    ``/<agent>/annotations``, roles from the world state and static flags from the recorded scenario; parts end
    at the frames where a run flushes them. With ``keep_if_empty``, a recording without one complete frame leaves
    ``tables_dir`` as it was. Returns the stream that read it (its damage and missing frames)."""
    from mmusv.acquire import TABLE_PART_FRAMES

    info = read_info(Path(recording))
    static = _static_flags(info)
    root = Path(tables_dir)
    tmp = root.with_name(root.name + ".rebuilding")
    shutil.rmtree(tmp, ignore_errors=True)
    tables = TableWriter(tmp)
    stream = FrameStream(info, _want)
    try:
        for fr in stream:
            if fr.world is None:
                continue
            tables.add_rows("world_state", len(fr.world.ids), _world_rows(fr.world, static))
            roles = dict(zip(fr.world.ids, fr.world.roles, strict=True))
            for topic, msg in fr.messages.items():
                if _want(topic):
                    box3, box2 = _box_rows(msg, roles, static)
                    tables.add_rows("boxes_3d", len(box3["target_id"]), box3)
                    tables.add_rows("boxes_2d", len(box2["target_id"]), box2)
            tables.frames += 1
            if (fr.index + 1) % TABLE_PART_FRAMES == 0:
                tables.flush()
        tables.flush()
        if keep_if_empty and not stream.yielded:
            return stream
        for old in sorted(root.glob("*/part-*.parquet")):
            old.unlink()
        for new in sorted(tmp.glob("*/part-*.parquet")):
            dest = root / new.parent.name / new.name
            dest.parent.mkdir(parents=True, exist_ok=True)
            os.replace(new, dest)
    except OSError as exc:
        raise IoError(f"cannot write the tables into {root}: {exc.strerror or exc}") from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return stream


def recover(target: str | os.PathLike[str], *, overwrite: bool = False) -> Recovered:
    """Finishes the ``.partial`` recording of ``target`` (a run folder or the file; see the module docstring).

    Raises:
        IoError: nothing to recover, the finished name exists (without ``overwrite``), the file is not a
            recording of ``mmusv run``, or the folder cannot be written.
    """
    from mcap.writer import CompressionType, Writer

    src = find_partial(target)
    final = src.with_name(src.name[: -len(".partial")])
    if final.exists() and not overwrite:
        raise IoError(f"{final} already exists; pass --overwrite to replace it with the recovery of {src.name}")
    info = read_info(src)
    planned = info.planned[1] if info.planned is not None else info.frames_configured
    folder = src.parent
    other = None if overwrite else another_run(folder, final.name)
    if other is not None:  # its tables and manifest.json would be rebuilt from this one's: the other run's lost
        raise IoError(
            f"{folder} holds the run of another recording, {other} (its manifest.json and tables/), which "
            f"recovering {src.name} there would replace; move {src.name} into a folder of its own first, or pass "
            f"--overwrite to replace them ({other} itself is kept); {src} is left as it was"
        )
    # pass 1: which frames are complete (and their tables)
    tables_dir = folder / "tables"
    stream = rebuild_tables(src, tables_dir, keep_if_empty=True)
    keep = set(stream.yielded)
    if not keep:
        # Nothing to finish: a recording of no frame would replace the .partial (and its chance of a better tool).
        raise IoError(
            f"{src} holds no complete frame (the run stopped before its first frame was written, or the file is "
            "damaged there): nothing to recover; it is left as it was"
        )
    times = {round(k / info.frequency_hz * 1e9) for k in keep} if info.frequency_hz > 0 else set()
    # pass 2: copy their messages into a finished MCAP
    tmp = final.with_name(final.name + ".recovering")
    scan = Scan(src)
    try:
        with tmp.open("wb") as f:
            w = Writer(f, chunk_size=_CHUNK_BYTES, compression=CompressionType.ZSTD)
            w.start(profile="", library="mmusv recover")
            schemas: dict[int, int] = {}
            channels: dict[int, int] = {}
            for msg, dmg in scan.messages():
                if dmg is not None or msg.log_time not in times:
                    continue
                ch = scan.channels.get(msg.channel_id)
                if ch is None:
                    continue
                if ch.id not in channels:
                    sc = scan.schemas.get(ch.schema_id)
                    if sc is not None and sc.id not in schemas:
                        schemas[sc.id] = w.register_schema(sc.name, sc.encoding, sc.data)
                    channels[ch.id] = w.register_channel(
                        ch.topic, ch.message_encoding, schemas.get(ch.schema_id, 0), dict(ch.metadata)
                    )
                w.add_message(channels[ch.id], msg.log_time, msg.data, msg.publish_time, msg.sequence)
            for name in ("scenario", "manifest", "sensors"):
                if name in scan.metadata:
                    w.add_metadata(name, scan.metadata[name])
            run = dict(scan.metadata.get("run", {}))
            run.update(
                scenario=info.scenario_name,
                status="interrupted",
                frames_written=str(len(keep)),
                frames_configured=str(info.frames_configured),
                frequency_hz=str(info.frequency_hz),
                agents=",".join(a.id for a in info.agents),
                recovered_from=f"{src.name}: {len(keep)} complete frames"
                + (f", {len(stream.incomplete)} incomplete left out" if stream.incomplete else ""),
            )
            run.pop("frames_requested", None)
            part = _part_of(final)
            if part is not None:  # one part of a split recording: its manifest checks where it starts
                run["first_frame"] = str(part[0])
            elif "first_frame" in run and keep:
                run["frames_requested"] = str(len(keep))
            elif info.planned is not None and (info.planned[0] > 0 or info.planned_range):
                # a frame range recorded alone (acquire.run(frame_range=...)), or a part recovered away from its
                # parts manifest: the manifest metadata, written before the first frame, says where it starts (the
                # recovered run and manifest.json said nothing of it, as for a whole run from frame 0); a range
                # from frame 0 (a split run's part 0) says frame_range there, as a whole run cut short does not
                run["first_frame"] = str(info.planned[0])
            w.add_metadata("run", run)
            w.finish()  # type: ignore[no-untyped-call]
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, final)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise IoError(f"cannot write {final}: {exc.strerror or exc}; {src} is left as it was") from None
    manifest_path = folder / "manifest.json"
    if (folder / "scenario.yaml").is_file() or manifest_path.is_file() or tables_dir.is_dir():
        from mmusv.jsonio import write_json

        meta = scan.metadata.get("manifest", {})
        manifest: dict[str, Any] = {
            "mmusv_version": meta.get("mmusv_version", info.mmusv_version),
            "scenario": info.scenario_name,
            "seed": info.seed,
            "config_hash": info.config_hash,
            "status": "interrupted",
            "frames_written": len(keep),
            "frames_requested": int(run.get("frames_requested", planned)),
            "frequency_hz": info.frequency_hz,
            "agents": [a.id for a in info.agents],
            "recording": final.name,
            "tables": sorted(p.name for p in tables_dir.iterdir()) if tables_dir.is_dir() else [],
            "recovered_from": src.name,
        }
        if "first_frame" in run:
            manifest["first_frame"] = int(run["first_frame"])
        write_json(manifest_path, manifest)
    src.unlink()
    return Recovered(
        recording=final,
        source=src,
        frames=sorted(keep),
        frames_configured=info.frames_configured,
        frames_requested=planned,
        incomplete=list(stream.incomplete),
        damage=list(stream.damage),
        tables=tables_dir,
    )
