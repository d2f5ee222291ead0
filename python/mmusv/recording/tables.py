"""The Parquet tables of a run: ``world_state``, ``boxes_3d`` and ``boxes_2d``, one row per vessel / box and frame.

:class:`TableWriter` gathers each frame's rows column-wise (one array per column and frame, no per-row
objects) and writes them as numbered parts ``<root>/<table>/part-NNNNN.parquet`` (polars) on :meth:`flush`.
Column names, order and dtypes are fixed by :data:`SCHEMAS`; a table without rows in a part writes no file.

Units and frames: metres, seconds, radians; ``world_state`` in the world frame (x east, y north, z up; poses
``x, y, z, roll, pitch, yaw``, velocities m/s), ``boxes_3d`` in the agent's LiDAR frame (quaternion ``qx, qy,
qz, qw``), ``boxes_2d`` in pixels (origin top-left). See ``docs/recording.md``.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import polars as pl

from mmusv import arguments
from mmusv.errors import ConfigError, IoError
from mmusv.forking import check_polars

if TYPE_CHECKING:
    from mmusv.agent_annotations import Annotations
    from mmusv.simulation import FrameCapture, VesselInfo

__all__ = [
    "BOX_3D_VECTORS",
    "SCHEMAS",
    "WORLD_STATE_VECTORS",
    "TableRead",
    "TableWriter",
    "read_table",
    "spread_columns",
]

_F = pl.Float64
_I = pl.Int64
_S = pl.String
_B = pl.Boolean

SCHEMAS: dict[str, dict[str, Any]] = {
    "world_state": {
        "frame": _I,
        "time_s": _F,
        "vessel_id": _S,
        "asset": _S,
        "role": _S,
        "static": _B,
        "semantic_class": _I,
        "instance_id": _I,
        **dict.fromkeys(("x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz"), _F),
        **dict.fromkeys(("box_cx", "box_cy", "box_cz", "length", "beam", "height"), _F),
    },
    "boxes_3d": {
        "frame": _I,
        "time_s": _F,
        "agent": _S,
        "target_id": _S,
        "instance_id": _I,
        "semantic_class": _I,
        **dict.fromkeys(("x", "y", "z", "length", "beam", "height", "qx", "qy", "qz", "qw", "yaw"), _F),
        "lidar_points": _I,
        "range_m": _F,
        "role": _S,
        "static": _B,
        "wave_occlusion": _F,
    },
    "boxes_2d": {
        "frame": _I,
        "time_s": _F,
        "agent": _S,
        "camera": _S,
        "target_id": _S,
        **dict.fromkeys(("x_min", "y_min", "x_max", "y_max", "truncation"), _F),
        "visible_pixels": _I,
        "box_pixels": _I,
        "occlusion": _F,
        "role": _S,
        "static": _B,
        "wave_occlusion": _F,
    },
}
"""Column name → polars dtype of each table, in column order. ``wave_occlusion`` (boxes): the share of the
target's part above the still water level that the waves hide from the agent's LiDAR (``boxes_3d``) or that
camera (``boxes_2d``), 0..1, 0 over a flat sea; tables written before it existed read with it null."""

LEGACY_MISSING: dict[str, tuple[str, ...]] = {"boxes_3d": ("wave_occlusion",), "boxes_2d": ("wave_occlusion",)}
"""Columns each table gained after its first release: a part without them (written by an older mmusv) reads with
them null (not recorded), never as zeros."""


WORLD_STATE_VECTORS: tuple[tuple[str, ...], ...] = (
    ("x", "y", "z", "roll", "pitch", "yaw"),
    ("vx", "vy", "vz"),
    ("box_cx", "box_cy", "box_cz"),
    ("length", "beam", "height"),
)
"""The ``world_state`` columns that hold vectors, one name per component: the pose, the velocity, the box centre and
the box size (:func:`spread_columns`)."""

BOX_3D_VECTORS: tuple[tuple[str, ...], ...] = (("x", "y", "z"), ("length", "beam", "height"), ("qx", "qy", "qz", "qw"))
"""The ``boxes_3d`` columns that hold vectors, one name per component: the box centre, its size and its rotation
quaternion (:func:`spread_columns`)."""


def spread_columns(cols: dict[str, Any], blocks: Sequence[np.ndarray], names: Sequence[Sequence[str]]) -> None:
    """Adds a table's vector fields to its columns ``cols``, one column per component: column ``j`` of the ``(n, k)``
    array ``blocks[i]`` under the name ``names[i][j]`` (:data:`WORLD_STATE_VECTORS`, :data:`BOX_3D_VECTORS`)."""
    for block, keys in zip(blocks, names, strict=True):
        for j, k in enumerate(keys):
            cols[k] = block[:, j]


class TableWriter:
    """Collects table rows column-wise and flushes them as numbered Parquet parts under ``root``."""

    def __init__(self, root: Path) -> None:
        check_polars("writing the tables")
        self.root = root
        self.part = 0
        self.frames = 0
        """Frames added since the last flush."""
        self._cols: dict[str, dict[str, list[Any]]] = {t: {c: [] for c in s} for t, s in SCHEMAS.items()}
        self._rows = dict.fromkeys(SCHEMAS, 0)

    def add_rows(self, table: str, n: int, columns: dict[str, Any]) -> None:
        """``n`` rows of ``table``: one array (or list) of ``n`` values per column of :data:`SCHEMAS`."""
        self._add(table, n, columns)

    def _add(self, table: str, n: int, columns: dict[str, Any]) -> None:
        if n == 0:
            return
        cols = self._cols[table]
        for name in SCHEMAS[table]:
            cols[name].append(columns[name])
        self._rows[table] += n

    def add_frame(
        self,
        vessels: list[VesselInfo],
        cap: FrameCapture,
        annotations: dict[str, tuple[Annotations, dict[str, Any]]],
    ) -> None:
        """The rows of one frame: every vessel's state, and each agent's boxes; ``annotations`` maps an agent to
        its :class:`~mmusv.agent_annotations.Annotations` and their ``columns()``."""
        self.add_world(vessels, cap)
        for ann, cols in annotations.values():
            self.add_annotations(ann, cols)
        self.frames += 1

    def add_world(self, vessels: list[VesselInfo], cap: FrameCapture) -> None:
        """One ``world_state`` row per vessel (``cap.world`` holds them in the order of ``vessels``)."""
        st = cap.world
        n = len(vessels)
        poses = np.asarray(st.poses, dtype=np.float64).reshape(n, 6)
        vel = np.asarray(st.velocities, dtype=np.float64).reshape(n, 3)
        centres = np.asarray(st.box_centers, dtype=np.float64).reshape(n, 3)
        size = np.array([v.box_size for v in vessels], dtype=np.float64).reshape(n, 3)
        cols: dict[str, Any] = {
            "frame": np.full(n, cap.frame, dtype=np.int64),
            "time_s": np.full(n, cap.time_s, dtype=np.float64),
            "vessel_id": [v.id for v in vessels],
            "asset": [v.asset for v in vessels],
            "role": [v.role for v in vessels],
            "static": np.array([bool(v.static) for v in vessels], dtype=bool),
            "semantic_class": np.array([v.semantic_class for v in vessels], dtype=np.int64),
            "instance_id": np.array([v.instance_id for v in vessels], dtype=np.int64),
        }
        spread_columns(cols, (poses, vel, centres, size), WORLD_STATE_VECTORS)
        self._add("world_state", n, cols)

    def add_annotations(self, ann: Annotations, cols: dict[str, Any]) -> None:
        """One ``boxes_3d`` row per LiDAR box and one ``boxes_2d`` row per camera box of one agent's annotations;
        ``cols`` is ``ann.columns()``."""
        lid = cols["lidar"]
        n = len(lid["target_id"])
        c = np.asarray(lid["center"], dtype=np.float64).reshape(n, 3)
        s = np.asarray(lid["size"], dtype=np.float64).reshape(n, 3)
        q = np.asarray(lid["rotation"], dtype=np.float64).reshape(n, 4)
        box3: dict[str, Any] = {
            "frame": np.full(n, ann.frame, dtype=np.int64),
            "time_s": np.full(n, ann.time_s, dtype=np.float64),
            "agent": [ann.agent] * n,
            "target_id": list(lid["target_id"]),
            "instance_id": np.asarray(lid["instance_id"], dtype=np.int64),
            "semantic_class": np.asarray(lid["semantic_class"], dtype=np.int64),
            "yaw": np.asarray(lid["yaw"], dtype=np.float64),
            "lidar_points": np.asarray(lid["lidar_points"], dtype=np.int64),
            "range_m": np.asarray(lid["range_m"], dtype=np.float64),
            "role": list(lid["role"]),
            "static": np.asarray(lid["static"], dtype=bool),
            "wave_occlusion": np.asarray(lid["wave_occlusion"], dtype=np.float64),
        }
        spread_columns(box3, (c, s, q), BOX_3D_VECTORS)
        self._add("boxes_3d", n, box3)
        cam = cols["camera"]
        m = len(cam["target_id"])
        box2: dict[str, Any] = {
            "frame": np.full(m, ann.frame, dtype=np.int64),
            "time_s": np.full(m, ann.time_s, dtype=np.float64),
            "agent": [ann.agent] * m,
            "camera": list(cam["camera"]),
            "target_id": list(cam["target_id"]),
            "visible_pixels": np.asarray(cam["visible_pixels"], dtype=np.int64),
            "box_pixels": np.asarray(cam["box_pixels"], dtype=np.int64),
            "role": list(cam["role"]),
            "static": np.asarray(cam["static"], dtype=bool),
        }
        for k in ("x_min", "y_min", "x_max", "y_max", "truncation", "occlusion", "wave_occlusion"):
            box2[k] = np.asarray(cam[k], dtype=np.float64)
        self._add("boxes_2d", m, box2)

    def flush(self) -> None:
        """Writes the rows gathered since the last flush as part ``part`` of every table that has rows; a part
        that cannot be written raises ``OSError`` (and leaves no file)."""
        for table, schema in SCHEMAS.items():
            if not self._rows[table]:
                continue
            data: dict[str, Any] = {}
            for name, dtype in schema.items():
                parts = self._cols[table][name]
                if dtype == _S:
                    data[name] = [x for p in parts for x in p]
                elif name in LEGACY_MISSING.get(table, ()):
                    # NaN marks a value not recorded (a rebuilt table of an older recording): null in the table.
                    data[name] = pl.Series(name, np.concatenate([np.asarray(p) for p in parts]), dtype=dtype).fill_nan(
                        None
                    )
                else:
                    data[name] = np.concatenate([np.asarray(p) for p in parts])
                parts.clear()
            d = self.root / table
            d.mkdir(parents=True, exist_ok=True)
            # written under a temporary name and renamed: a part file is complete or absent, never half-written
            final = d / f"part-{self.part:05d}.parquet"
            tmp = final.with_name(final.name + ".tmp")
            try:
                df = pl.DataFrame(data, schema=schema)
                df.write_parquet(tmp, metadata={ROWS_DIGEST_KEY: rows_digest(df)})
            except pl.exceptions.PolarsError as exc:  # a failed write (a full disk) comes back as a polars error
                tmp.unlink(missing_ok=True)
                raise OSError(f"{final}: the Parquet part could not be written ({exc})") from exc
            os.replace(tmp, final)
            self._rows[table] = 0
        self.part += 1
        self.frames = 0


ROWS_DIGEST_KEY = "mmusv_rows_sha256"
"""The key of a part's file-level Parquet metadata holding :func:`rows_digest` of the rows written: Parquet's own
page checksums are optional and Polars writes none, so changed bytes inside a page read back as other numbers
(a ``range_m`` of 100.49 read as -0.045) without it."""


def rows_digest(df: pl.DataFrame) -> str:
    """SHA-256 (hex) of a table's rows: per column its name, its null mask and its values (numbers and flags as
    their little-endian bytes, strings length-prefixed UTF-8), independent of how Parquet encodes them."""
    import hashlib

    h = hashlib.sha256()
    for name in df.columns:
        col = df[name]
        h.update(len(name).to_bytes(4, "little") + name.encode("utf-8"))
        h.update(np.ascontiguousarray(col.is_null().to_numpy()).tobytes())
        if col.dtype == pl.String:
            for v in col.to_list():
                b = b"" if v is None else v.encode("utf-8", "surrogatepass")
                h.update(len(b).to_bytes(8, "little") + b)
        else:
            values = np.ascontiguousarray(col.to_numpy())
            h.update(values.astype(values.dtype.newbyteorder("<"), copy=False).tobytes())
    return h.hexdigest()


def _said_digest(part: Path) -> str | None:
    """The :func:`rows_digest` ``part`` was written with, or ``None`` for a part written before it was kept."""
    try:
        return pl.read_parquet_metadata(part).get(ROWS_DIGEST_KEY)
    except BaseException as exc:  # its footer read with the rows just before: a failure here is a part from elsewhere
        if not _unreadable(exc):
            raise
        return None


def _unreadable(exc: BaseException) -> bool:
    """Whether ``exc``, raised reading a Parquet file, says the file cannot be read: any error, and a panic of
    Polars' Rust code (pyo3's ``PanicException`` is a ``BaseException``: changed bytes in a page made it escape
    as a traceback), but not a stop (Ctrl-C, SIGTERM, exit)."""
    return isinstance(exc, Exception) or type(exc).__name__ == "PanicException"


@dataclass
class TableRead:
    """One table read back from its parts: the rows of every readable part (``frame`` order), the parts that
    could not be read (``damaged``: one line each, naming the file and why) and the frames of ``expected`` that
    are not in the rows (``missing``)."""

    table: str
    rows: pl.DataFrame
    damaged: list[str] = field(default_factory=list)
    missing: list[int] = field(default_factory=list)

    def report(self) -> str | None:
        """One line about what is wrong, or ``None``."""
        if not self.damaged and not self.missing:
            return None
        from mmusv.recording.stream import frame_ranges

        parts = list(self.damaged)
        if self.missing:
            parts.append(f"frames {frame_ranges(self.missing)} have no {self.table} rows")
        return f"table {self.table}: " + "; ".join(parts)


def read_table(root: str | os.PathLike[str], table: str, *, expected: range | Sequence[int] | None = None) -> TableRead:
    """The table ``table`` of the tables folder ``root`` (``<root>/<table>/part-*.parquet``), every part that
    reads and has the table's columns; a damaged part is left out and named. ``expected``: the frames the run
    wrote (their absence from the rows is reported in ``missing``; only meaningful for ``world_state``, which
    has rows in every frame: a ``range`` or a list of frame numbers). A ``root`` that is not a folder holding
    tables (a missing path, a file, a run folder instead of its ``tables``) is an :class:`~mmusv.errors.IoError`,
    not an empty table."""
    check_polars("reading the tables")
    root = arguments.path(root, name="root")
    if not isinstance(table, str) or table not in SCHEMAS:
        raise ConfigError(f"table = {table!r:.60}: not a table of a recording; tables: {', '.join(SCHEMAS)}")
    if isinstance(expected, np.ndarray) and expected.ndim == 1:  # an array of frame numbers, as numpy gives them
        expected = expected.tolist()
    if expected is not None and not (
        isinstance(expected, (range, list, tuple))
        and all(isinstance(k, (int, np.integer)) and not isinstance(k, bool) and k >= 0 for k in expected)
    ):
        raise ConfigError(
            f"expected = {arguments.shown(expected)}: must be the frames the run wrote, a range (range(0, 50)), a "
            "list or a 1-D array of frame numbers >= 0, or None"
        )
    if not root.is_dir():
        what = "does not exist" if not root.exists() else "is not a folder"
        raise IoError(f"root = {root} {what}: give the tables folder of a run (<run folder>/tables)")
    # an empty folder is the tables folder of a run that wrote no rows yet; a folder of other things is a mistake
    if not any((root / t).is_dir() for t in SCHEMAS) and any(root.iterdir()):
        hint = f"; it holds {root / 'tables'}: give that" if (root / "tables").is_dir() else ""
        raise IoError(
            f"root = {root} is not the tables folder of a run: it has none of the folders {', '.join(SCHEMAS)}{hint}"
        )
    schema = SCHEMAS[table]
    frames: list[pl.DataFrame] = []
    damaged: list[str] = []
    for part in sorted((root / table).glob("part-*.parquet")):
        try:
            df = pl.read_parquet(part, glob=False)  # a folder a[1] is a name, not a pattern
        except BaseException as exc:  # polars raises several kinds for a damaged file; any means unreadable
            if not _unreadable(exc):
                raise
            first = str(exc).strip().splitlines()[0][:120] if str(exc).strip() else ""
            damaged.append(
                f"{part} is not a readable Parquet file ({type(exc).__name__}{': ' + first if first else ''})"
            )
            continue
        said = _said_digest(part)
        if said is not None and said != rows_digest(df):
            damaged.append(f"{part} holds rows that differ from those written (damaged bytes: its checksum fails)")
            continue
        legacy = [c for c in LEGACY_MISSING.get(table, ()) if c not in df.columns]
        if legacy and list(df.columns) == [c for c in schema if c not in legacy]:
            df = df.with_columns(pl.lit(None, dtype=schema[c]).alias(c) for c in legacy).select(list(schema))
        if list(df.columns) != list(schema) or any(df.schema[c] != t for c, t in schema.items()):
            damaged.append(f"{part} does not have the columns and types of table {table}")
            continue
        frames.append(df)
    rows = pl.concat(frames) if frames else pl.DataFrame(schema=schema)
    rows = rows.sort("frame", maintain_order=True)
    missing: list[int] = []
    if expected is not None:
        have = set(rows["frame"].to_list())
        missing = [k for k in expected if k not in have]
    return TableRead(table, rows, damaged, missing)
