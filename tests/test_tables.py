"""The Parquet tables (:mod:`mmusv.recording.tables`): gathered column-wise, they equal the row-wise ones."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import polars as pl
from mmusv.acquire import annotations_for
from mmusv.agent_annotations import Annotations
from mmusv.recording.tables import ROWS_DIGEST_KEY, SCHEMAS, TableWriter, rows_digest
from mmusv.silhouettes import SilhouetteCache
from mmusv.simulation import FrameCapture, Simulation
from test_acquire import small_scenario


class _RowWise:
    """The tables as main built them before issue #12: one dict per row (the reference)."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.rows: dict[str, list[dict[str, Any]]] = {"world_state": [], "boxes_3d": [], "boxes_2d": []}
        self.part = 0

    def add_world(self, sim: Simulation, cap: FrameCapture) -> None:
        st = cap.world
        for i, v in enumerate(sim.vessels):
            x, y, z, r, p, yaw = (float(a) for a in st.poses[i])
            self.rows["world_state"].append(
                {
                    "frame": cap.frame,
                    "time_s": cap.time_s,
                    "vessel_id": v.id,
                    "asset": v.asset,
                    "role": v.role,
                    "static": v.static,
                    "semantic_class": v.semantic_class,
                    "instance_id": v.instance_id,
                    "x": x,
                    "y": y,
                    "z": z,
                    "roll": r,
                    "pitch": p,
                    "yaw": yaw,
                    "vx": float(st.velocities[i, 0]),
                    "vy": float(st.velocities[i, 1]),
                    "vz": float(st.velocities[i, 2]),
                    "box_cx": float(st.box_centers[i, 0]),
                    "box_cy": float(st.box_centers[i, 1]),
                    "box_cz": float(st.box_centers[i, 2]),
                    "length": float(v.box_size[0]),
                    "beam": float(v.box_size[1]),
                    "height": float(v.box_size[2]),
                }
            )

    def add_annotations(self, ann: Annotations, cols: dict[str, Any]) -> None:
        """Rows of one agent's annotations; ``cols`` is ``ann.columns()``."""
        lid = cols["lidar"]
        for j, tid in enumerate(lid["target_id"]):
            c, s, q = lid["center"][j], lid["size"][j], lid["rotation"][j]
            self.rows["boxes_3d"].append(
                {
                    "frame": ann.frame,
                    "time_s": ann.time_s,
                    "agent": ann.agent,
                    "target_id": tid,
                    "instance_id": int(lid["instance_id"][j]),
                    "semantic_class": int(lid["semantic_class"][j]),
                    "x": float(c[0]),
                    "y": float(c[1]),
                    "z": float(c[2]),
                    "length": float(s[0]),
                    "beam": float(s[1]),
                    "height": float(s[2]),
                    "qx": float(q[0]),
                    "qy": float(q[1]),
                    "qz": float(q[2]),
                    "qw": float(q[3]),
                    "yaw": float(lid["yaw"][j]),
                    "lidar_points": int(lid["lidar_points"][j]),
                    "range_m": float(lid["range_m"][j]),
                    "role": lid["role"][j],
                    "static": bool(lid["static"][j]),
                    "wave_occlusion": float(lid["wave_occlusion"][j]),
                }
            )
        cam = cols["camera"]
        for j, tid in enumerate(cam["target_id"]):
            self.rows["boxes_2d"].append(
                {
                    "frame": ann.frame,
                    "time_s": ann.time_s,
                    "agent": ann.agent,
                    "camera": cam["camera"][j],
                    "target_id": tid,
                    "x_min": float(cam["x_min"][j]),
                    "y_min": float(cam["y_min"][j]),
                    "x_max": float(cam["x_max"][j]),
                    "y_max": float(cam["y_max"][j]),
                    "truncation": float(cam["truncation"][j]),
                    "visible_pixels": int(cam["visible_pixels"][j]),
                    "box_pixels": int(cam["box_pixels"][j]),
                    "occlusion": float(cam["occlusion"][j]),
                    "role": cam["role"][j],
                    "static": bool(cam["static"][j]),
                    "wave_occlusion": float(cam["wave_occlusion"][j]),
                }
            )

    def flush(self) -> None:
        for name, rows in self.rows.items():
            if not rows:
                continue
            d = self.root / name
            d.mkdir(parents=True, exist_ok=True)
            df = pl.DataFrame(rows)
            df.write_parquet(d / f"part-{self.part:05d}.parquet", metadata={ROWS_DIGEST_KEY: rows_digest(df)})
            rows.clear()
        self.part += 1


def test_column_wise_tables_equal_the_row_wise_ones(tmp_path: Path) -> None:
    sim = Simulation(small_scenario(frames=4))
    silhouettes = SilhouetteCache()
    new, ref = TableWriter(tmp_path / "new"), _RowWise(tmp_path / "ref")
    for k in range(4):
        cap = sim.capture(k)
        anns = annotations_for(sim, cap, silhouettes)
        cols = {agent: a.columns() for agent, a in anns.items()}
        new.add_frame(sim.vessels, cap, {agent: (a, cols[agent]) for agent, a in anns.items()})
        ref.add_world(sim, cap)
        for agent, a in anns.items():
            ref.add_annotations(a, cols[agent])
        if k == 1:  # two parts
            new.flush()
            ref.flush()
    new.flush()
    ref.flush()
    for table, schema in SCHEMAS.items():
        parts = sorted(p.name for p in (tmp_path / "ref" / table).glob("*.parquet"))
        assert parts == ["part-00000.parquet", "part-00001.parquet"], table
        assert sorted(p.name for p in (tmp_path / "new" / table).glob("*.parquet")) == parts
        for part in parts:
            a = pl.read_parquet(tmp_path / "new" / table / part)
            b = pl.read_parquet(tmp_path / "ref" / table / part)
            assert a.height > 0 and a.schema == b.schema and dict(a.schema) == schema
            assert a.equals(b), (table, part)
            assert (tmp_path / "new" / table / part).read_bytes() == (tmp_path / "ref" / table / part).read_bytes()
    b2 = pl.read_parquet(tmp_path / "new/boxes_2d/*.parquet")
    assert b2.height > 0 and set(b2["camera"]) <= {"front", "rear"} and (b2["visible_pixels"] <= b2["box_pixels"]).all()


def test_a_table_without_rows_writes_no_part(tmp_path: Path) -> None:
    sim = Simulation(small_scenario(frames=1))
    cap = sim.capture(0)
    empty = Annotations(agent="usv_1", frame=0, time_s=0.0)
    w = TableWriter(tmp_path)
    w.add_frame(sim.vessels, cap, {"usv_1": (empty, empty.columns())})
    w.flush()
    assert [p.name for p in tmp_path.iterdir()] == ["world_state"]
    ws = pl.read_parquet(tmp_path / "world_state/part-00000.parquet")
    assert ws.height == len(sim.vessels)
    np.testing.assert_array_equal(ws["x"].to_numpy(), cap.world.poses[:, 0])
    assert ws["vessel_id"].to_list() == [v.id for v in sim.vessels]


def _write_tables(root: Path, *, frames: int) -> None:
    """The tables of the first ``frames`` frames of the small scenario, one part, written into ``root``."""
    sim = Simulation(small_scenario(frames=frames))
    silhouettes = SilhouetteCache()
    w = TableWriter(root)
    for k in range(frames):
        cap = sim.capture(k)
        anns = annotations_for(sim, cap, silhouettes)
        w.add_frame(sim.vessels, cap, {agent: (a, a.columns()) for agent, a in anns.items()})
    w.flush()


def test_parts_written_before_wave_occlusion_read_with_it_null(tmp_path: Path) -> None:
    """A part of an older mmusv (no ``wave_occlusion`` column) reads with that column null, not as damaged and
    not as zeros; a part missing any other column is still damaged."""
    from mmusv.recording.tables import read_table

    _write_tables(tmp_path / "new", frames=2)
    for table in ("boxes_3d", "boxes_2d"):
        new = pl.read_parquet(tmp_path / "new" / table / "part-00000.parquet")
        assert new["wave_occlusion"].null_count() == 0
        old_dir = tmp_path / "old" / table
        old_dir.mkdir(parents=True)
        new.drop("wave_occlusion").write_parquet(old_dir / "part-00000.parquet")
        new.drop("wave_occlusion", "role").write_parquet(old_dir / "part-00001.parquet")
        got = read_table(tmp_path / "old", table)
        assert got.rows.columns == list(SCHEMAS[table])
        assert got.rows["wave_occlusion"].null_count() == new.height
        assert got.rows.drop("wave_occlusion").equals(new.drop("wave_occlusion"))
        assert len(got.damaged) == 1 and "part-00001" in got.damaged[0]


def test_changed_bytes_in_a_part_are_named_damaged_never_read_as_other_rows(tmp_path: Path) -> None:
    """Bytes flipped inside a data page read back as other numbers (a range of 100.49 as -0.045) with no word: the
    part's rows checksum (file metadata) names it damaged; a part without one (an older mmusv) still reads."""
    from mmusv.recording.tables import read_table

    _write_tables(tmp_path / "good", frames=2)
    for table in SCHEMAS:
        good = read_table(tmp_path / "good", table)
        src = (tmp_path / "good" / table / "part-00000.parquet").read_bytes()
        assert not good.damaged and good.rows.height > 0
        assert pl.read_parquet_metadata(tmp_path / "good" / table / "part-00000.parquet")[ROWS_DIGEST_KEY] == (
            rows_digest(pl.read_parquet(tmp_path / "good" / table / "part-00000.parquet"))
        )
        bad = tmp_path / "bad" / table / "part-00000.parquet"
        bad.parent.mkdir(parents=True, exist_ok=True)
        outcomes = {"damaged": 0, "same": 0}
        for at in range(4, len(src) - 8, 29):
            flipped = bytearray(src)
            for i in range(at, at + 8):
                flipped[i] ^= 0xFF
            bad.write_bytes(bytes(flipped))
            got = read_table(tmp_path / "bad", table)
            if got.damaged:
                outcomes["damaged"] += 1
            else:
                assert got.rows.equals(good.rows), (table, at)  # never other values without a word
                outcomes["same"] += 1
        assert outcomes["damaged"] > 0, outcomes
        old = tmp_path / "old" / table / "part-00000.parquet"  # no checksum: read as before
        old.parent.mkdir(parents=True, exist_ok=True)
        good.rows.write_parquet(old)
        again = read_table(tmp_path / "old", table)
        assert not again.damaged and again.rows.equals(good.rows)


def test_an_unknown_table_name_is_a_config_error_listing_the_tables(tmp_path: Path) -> None:
    import pytest
    from mmusv.errors import ConfigError
    from mmusv.recording.tables import read_table

    for bad in ("worldstate", ["world_state"], None):
        with pytest.raises(ConfigError, match=r"table = .*tables: world_state"):
            read_table(tmp_path, bad)  # type: ignore[arg-type]
