"""The Parquet tables of a run rebuilt from its recording (:func:`rebuild_tables`), and what is wrong with a run's
tables (:func:`check_tables`), for ``mmusv recover`` (:mod:`mmusv.recording.recover`) and ``mmusv info``.

A run writes ``world_state``, ``boxes_3d`` and ``boxes_2d`` as it records; every row comes from what the recording
holds too: ``/world/state`` and each agent's ``/<agent>/annotations``, roles from the world state and static flags
from the recorded scenario. Parts end at the frames where a run flushes them (:data:`mmusv.acquire.TABLE_PART_FRAMES`),
so the tables rebuilt from a whole recording are the bytes its run wrote. They are built beside the tables folder
(:func:`staging`, :func:`stage_tables`) and put in place at once (:func:`install_tables`), so an error or a stop
while they are built leaves the folder as it was.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Collection, Sequence
from pathlib import Path
from typing import Any

from mmusv.errors import IoError
from mmusv.recording.info import RecordingInfo, read_info
from mmusv.recording.stream import FrameStream
from mmusv.recording.tables import BOX_3D_VECTORS, WORLD_STATE_VECTORS, TableWriter, spread_columns

__all__ = ["check_tables", "install_tables", "listed_tables", "rebuild_tables", "stage_tables", "staging"]


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
    at the frames where a run flushes them, so the parts of a whole recording are the bytes its run wrote. With
    ``keep_if_empty``, a recording without one complete frame leaves ``tables_dir`` as it was. The tables are
    built beside ``tables_dir`` first (``<tables_dir>.rebuilding``, removed whatever happens), so an error or a
    stop while they are built leaves ``tables_dir`` as it was. Returns the stream that read it (its damage and
    missing frames)."""
    root = Path(tables_dir)
    staged = staging(root)
    try:
        stream = stage_tables(recording, staged)
        if not (keep_if_empty and not stream.yielded):
            install_tables(staged, root)
    finally:
        shutil.rmtree(staged, ignore_errors=True)
    return stream


def staging(root: Path) -> Path:
    """The folder the tables of ``root`` are built in before they replace its parts (emptied first)."""
    staged = root.with_name(root.name + ".rebuilding")
    shutil.rmtree(staged, ignore_errors=True)
    return staged


def stage_tables(recording: str | os.PathLike[str], staged: Path) -> FrameStream:
    """The tables of every complete frame of ``recording`` written into the folder ``staged`` (see
    :func:`rebuild_tables`); the stream that read it."""
    from mmusv.acquire import TABLE_PART_FRAMES

    info = read_info(Path(recording))
    static = _static_flags(info)
    tables = TableWriter(staged)
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
    except OSError as exc:
        raise IoError(f"cannot write the tables into {staged}: {exc.strerror or exc}") from None
    return stream


def install_tables(staged: Path, root: Path) -> None:
    """Replaces the table parts of ``root`` with those built in ``staged``; a stop meanwhile waits until it is
    done (half the old parts and half the new were no tables of anything)."""
    from mmusv.held_signals import HeldSignals

    try:
        with HeldSignals():
            for old in sorted(root.glob("*/part-*.parquet")):
                old.unlink()
            for new in sorted(staged.glob("*/part-*.parquet")):
                dest = root / new.parent.name / new.name
                dest.parent.mkdir(parents=True, exist_ok=True)
                os.replace(new, dest)
    except OSError as exc:
        raise IoError(f"cannot write the tables into {root}: {exc.strerror or exc}") from None


def check_tables(
    tables: str | os.PathLike[str], frames: range | None, lacking: Collection[int] = (), *, listed: Sequence[str] = ()
) -> tuple[list[str], list[int]]:
    """What is wrong with the tables folder ``tables`` of a run whose recording holds the frames ``frames`` (the
    run's; ``None``: not known) but ``lacking`` (damaged or never written): ``(problems, held)``, one line per
    problem (a missing folder, a damaged part, frames without ``world_state`` rows, a table ``listed`` in the
    run's ``manifest.json`` whose folder is gone; ``[]`` when the tables are whole), and the frames of ``lacking``
    that readable parts still hold rows of (tables rebuilt from the recording would lose them). A folder without
    tables where the recording holds no frame is whole. A ``tables`` that is not a tables folder at all (a folder
    of other things): :class:`~mmusv.errors.IoError`, as :func:`~mmusv.recording.tables.read_table` says."""
    from mmusv.recording.tables import SCHEMAS, read_table

    root = Path(tables)
    lack = set(lacking)
    if not root.is_dir():
        if frames is not None and all(k in lack for k in frames):  # no frame recorded, so no table either
            return [], []
        return [f"{root} {'is not a folder' if root.exists() or root.is_symlink() else 'does not exist'}"], []
    problems: list[str] = []
    held: set[int] = set()
    for name in SCHEMAS:
        got = read_table(root, name, expected=frames if name == "world_state" else None)
        got.missing = [k for k in got.missing if k not in lack]  # frames the recording lacks too: said there
        line = got.report()
        if line is None and name in listed and not (root / name).is_dir():
            line = f"table {name}: {root / name} does not exist (manifest.json lists it)"
        if line is not None:
            problems.append(line)
        if lack and got.rows.height:
            held |= lack & {int(k) for k in got.rows["frame"].unique().to_list()}
    return problems, sorted(held)


def listed_tables(folder: Path, recording: str) -> list[str]:
    """The tables the run's ``manifest.json`` in ``folder`` lists, when it is the manifest of ``recording`` (a file
    name); else none."""
    import json

    try:
        manifest = json.loads((folder / "manifest.json").read_bytes())
    except (OSError, ValueError):
        return []
    if not isinstance(manifest, dict) or manifest.get("recording") != recording:
        return []
    names = manifest.get("tables")
    return [str(n) for n in names if isinstance(n, str)] if isinstance(names, list) else []
