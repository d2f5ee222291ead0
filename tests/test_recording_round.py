"""docs/recording.md read back the way a robotics developer reads an ``mmusv run`` recording with other people's
tools: the official ``mcap`` reader (header, summary, statistics, chunk indexes, metadata and attachments), every
channel decoded with the schema stored in the file (its ``FileDescriptorSet`` built with ``google.protobuf``, no
mmusv code), the official ``foxglove-schemas-protobuf`` classes and Pillow; then mmusv's own reader
(:mod:`mmusv.recording`) compared with what those give.

The recordings are tiny (two USVs with two 64 x 48 cameras, an 8-channel LiDAR, a small radar and top view, two
frames; the same without a LiDAR for one frame), and a run killed with SIGKILL whose frames are single large
depth images, so that a chunk is closed on disk before the kill.
"""

from __future__ import annotations

import collections
import hashlib
import importlib
import io
import json
import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from mcap.exceptions import McapError
from mcap.reader import NonSeekingReader, make_reader
from mcap.stream_reader import StreamReader
from PIL import Image
from scipy.spatial.transform import Rotation
from tiny_scenario import lidar_scenario

ROOT = Path(__file__).resolve().parents[1]
FREQUENCY_HZ = 5.0

# foxglove.PackedElementField.NumericType → (numpy little-endian type, bytes)
NUMERIC = {1: ("u1", 1), 2: ("i1", 1), 3: ("<u2", 2), 4: ("<i2", 2), 5: ("<u4", 4), 6: ("<i4", 4), 7: ("<f4", 4)}
NUMERIC[8] = ("<f8", 8)
RAW_BYTES = {"mono8": 1, "rgb8": 3, "16UC1": 2, "32FC1": 4}
LIDAR_FIELDS = [("x", 7), ("y", 7), ("z", 7), ("intensity", 7), ("ring", 3), ("azimuth", 7), ("class", 3)]
LIDAR_FIELDS.append(("instance", 6))
RADAR_FIELDS = [(n, 7) for n in ("x", "y", "z", "range", "azimuth", "elevation", "intensity")] + [("instance", 6)]


def _rig(*, lidar: bool = True) -> dict[str, Any]:
    """Two 64 x 48 cameras, a 64 x 64 top view and (``lidar``) an 8-channel LiDAR and a small radar."""
    cams = [
        {"name": n, "resolution": [64, 48], "hfov_deg": 90, "mount": {"point": f"camera_{n}"}}
        for n in ("front", "left")
    ]
    radar = {"azimuth_bins": 256, "rays_el": 4, "rays_az": 1, "ppi_size_px": 64, "range_m": 1000}
    return {
        "lidar": {"channels": 8, "points_per_second": 20480, "rotation_hz": 5} if lidar else None,
        "cameras": cams,
        "radar": radar if lidar else None,
        "top_view": {"resolution": [64, 64], "metres_per_pixel": 2.0},
    }


def _scenario(name: str, frames: int, *, lidar: bool = True) -> dict[str, Any]:
    """The export tests' ``coop`` scenario (a tug and a speedboat between two USVs) with a smaller rig."""
    return {
        "name": name,
        "seed": 11,
        "map": {"type": "open_sea", "seed": 2, "params": {"extent_m": 1000, "islet_probability": 0.0}},
        "environment": {"time_of_day": "11:00", "weather": "clear", "wave": "W1", "motion": "paper"},
        "acquisition": {"frequency_hz": FREQUENCY_HZ, "frames": frames},
        "rigs": {"r": _rig(lidar=lidar)},
        "vessels": [
            {"id": "usv_a", "role": "usv", "asset": "usv_patrol_12m", "rig": "r", "speed_mps": 3.0,
             "route": [[0, 0], [300, 200]]},
            {"id": "tgt", "role": "target", "asset": "tug_32m", "speed_mps": 3.0,
             "route": [[34.1, 30.0], [334.1, 230.0]]},
            {"id": "usv_b", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2.0,
             "route": [[90, -30], [60, 0]]},
            {"id": "boat", "role": "target", "asset": "speedboat_5m", "speed_mps": 4.0,
             "route": [[20, 60], [80, 20]]},
        ],
    }  # fmt: skip


@pytest.fixture(scope="module")
def coop(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from mmusv.acquire import run

    return Path(run(_scenario("round_coop", 2), out_dir=tmp_path_factory.mktemp("coop")).recording)


@pytest.fixture(scope="module")
def no_lidar(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from mmusv.acquire import run

    cfg = _scenario("round_no_lidar", 1, lidar=False)
    return Path(run(cfg, out_dir=tmp_path_factory.mktemp("no_lidar")).recording)


# ---------------------------------------------------------------------------------------------- independent decode


@dataclass
class Rec:
    topic: str
    schema: str
    channel_id: int
    sequence: int
    log_time: int
    publish_time: int
    data: bytes
    msg: Any


def _message_class(schema: Any) -> Any:
    """The message class of an MCAP schema record, built from the ``FileDescriptorSet`` it holds."""
    fds = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    pool = descriptor_pool.DescriptorPool()
    for fd in fds.file:
        pool.Add(fd)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name))


def _decode(path: Path) -> list[Rec]:
    """Every message in file order, decoded with the schema stored in the file."""
    classes: dict[int, Any] = {}
    out = []
    with path.open("rb") as f:
        for schema, ch, m in make_reader(f).iter_messages(log_time_order=False):
            if schema.id not in classes:
                classes[schema.id] = _message_class(schema)
            msg = classes[schema.id].FromString(m.data)
            out.append(Rec(ch.topic, schema.name, ch.id, m.sequence, m.log_time, m.publish_time, m.data, msg))
    return out


def _frames(recs: list[Rec]) -> dict[int, dict[str, Rec]]:
    frames: dict[int, dict[str, Rec]] = collections.defaultdict(dict)
    for r in recs:
        assert r.topic not in frames[r.log_time], (r.topic, r.log_time)
        frames[r.log_time][r.topic] = r
    return dict(frames)


def _matrix(t: Any, q: Any) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix()
    m[:3, 3] = [t.x, t.y, t.z]
    return m


class Tree:
    """The ``/tf`` of one frame: every child's pose in its parent, chained to ``world``."""

    def __init__(self, tf: Any) -> None:
        self.parent: dict[str, str] = {}
        self.pose: dict[str, np.ndarray] = {}
        for t in tf.transforms:
            assert t.child_frame_id not in self.parent, t.child_frame_id
            self.parent[t.child_frame_id] = t.parent_frame_id
            self.pose[t.child_frame_id] = _matrix(t.translation, t.rotation)

    def resolves(self, frame: str) -> bool:
        for _ in range(16):
            if frame == "world":
                return True
            if frame not in self.parent:
                return False
            frame = self.parent[frame]
        return False

    def world(self, frame: str) -> np.ndarray:
        m = np.eye(4)
        while frame != "world":
            m = self.pose[frame] @ m
            frame = self.parent[frame]
        return m


def _frame_ids(r: Rec) -> list[str]:
    if r.schema == "foxglove.SceneUpdate":
        return [e.frame_id for e in r.msg.entities]
    if r.schema.startswith("foxglove.") and r.schema not in ("foxglove.FrameTransforms", "foxglove.ImageAnnotations"):
        return [r.msg.frame_id]  # an image's annotations have no frame: they are drawn on its image
    return []


def _unresolved(path: Path) -> list[str]:
    """``topic: frame id`` of every frame id a message names that the same frame's ``/tf`` does not chain to
    ``world``."""
    bad = []
    for frame in _frames(_decode(path)).values():
        tree = Tree(frame["/tf"].msg)
        bad += [f"{r.topic}: {f!r}" for r in frame.values() for f in _frame_ids(r) if not tree.resolves(f)]
    return sorted(set(bad))


# ---------------------------------------------------------------------------------------------- the file


def test_header_statistics_and_indexes_are_those_of_the_records(coop: Path) -> None:
    import mmusv

    recs = _decode(coop)
    with coop.open("rb") as f:
        reader = make_reader(f)
        header, s = reader.get_header(), reader.get_summary()
    assert s is not None and s.statistics is not None
    assert (header.profile, header.library) == ("", f"mmusv {mmusv.__version__}")
    st = s.statistics
    assert st.message_count == len(recs)
    assert st.channel_message_counts == dict(collections.Counter(r.channel_id for r in recs))
    assert st.channel_count == len(s.channels) == len({r.topic for r in recs})
    assert st.schema_count == len(s.schemas) == len({sc.name for sc in s.schemas.values()})  # deduplicated
    assert (st.message_start_time, st.message_end_time) == (0, round(1 / FREQUENCY_HZ * 1e9))
    assert (st.metadata_count, st.attachment_count) == (4, 0) and not s.attachment_indexes
    assert [m.name for m in s.metadata_indexes] == ["scenario", "manifest", "sensors", "run"]
    assert st.chunk_count == len(s.chunk_indexes) >= 1
    for c in s.chunk_indexes:
        assert c.compression == "zstd" and c.uncompressed_size <= 8 << 20
        assert set(c.message_index_offsets) <= set(s.channels)
    assert set().union(*(c.message_index_offsets for c in s.chunk_indexes)) == set(s.channels)
    assert {ch.message_encoding for ch in s.channels.values()} == {"protobuf"}
    assert {sc.encoding for sc in s.schemas.values()} == {"protobuf"}
    # every CRC (chunks, data section, summary) checks out record by record
    with coop.open("rb") as f:
        kinds = collections.Counter(type(r).__name__ for r in StreamReader(f, validate_crcs=True).records)
    assert kinds["Message"] == len(recs) and kinds["Footer"] == 1 and kinds["ChunkIndex"] == st.chunk_count


def test_every_message_decodes_with_its_own_schema_at_its_frames_time(coop: Path) -> None:
    recs = _decode(coop)
    topics = {r.topic for r in recs}
    frames = _frames(recs)
    assert sorted(frames) == [round(k / FREQUENCY_HZ * 1e9) for k in range(2)]
    assert [r.log_time for r in recs] == sorted(r.log_time for r in recs)  # monotonic in file order
    per_topic: dict[str, list[int]] = collections.defaultdict(list)
    for r in recs:
        per_topic[r.topic].append(r.sequence)
        assert r.publish_time == r.log_time
        if r.schema.startswith("mmusv."):
            assert r.log_time == round(r.msg.time_s * 1e9) and r.msg.frame == round(r.msg.time_s * FREQUENCY_HZ)
        elif r.schema == "foxglove.FrameTransforms":
            assert {t.timestamp.ToNanoseconds() for t in r.msg.transforms} == {r.log_time}
        elif r.schema == "foxglove.SceneUpdate":
            assert {e.timestamp.ToNanoseconds() for e in r.msg.entities} == {r.log_time}
        else:
            assert r.msg.timestamp.ToNanoseconds() == r.log_time, r.topic
    assert all(seq == list(range(len(seq))) for seq in per_topic.values())
    for frame in frames.values():
        assert set(frame) == topics  # every topic once per frame
    want = {"/tf", "/world/state"}
    for a in ("usv_a", "usv_b"):
        want |= {f"/{a}/{t}" for t in ("lidar", "radar/returns", "radar/ppi", "boxes", "annotations")}
        want |= {f"/{a}/top_view/{k}" for k in ("rgb", "semantic", "instance")}
        kinds = ("rgb", "depth", "semantic", "instance", "calibration", "boxes")
        want |= {f"/{a}/camera/{c}/{k}" for c in ("front", "left") for k in kinds}
    assert topics == want


def _without_json_names(fd: descriptor_pb2.FileDescriptorProto) -> descriptor_pb2.FileDescriptorProto:
    def strip(messages: Any) -> None:
        for m in messages:
            for fld in m.field:
                fld.ClearField("json_name")  # protoc's compiled descriptors leave the default json_name out
            strip(m.nested_type)

    strip(fd.message_type)
    return fd


def test_foxglove_schemas_are_the_official_ones_and_decode_with_their_classes(coop: Path) -> None:
    with coop.open("rb") as f:
        s = make_reader(f).get_summary()
    assert s is not None
    names = set()
    for schema in s.schemas.values():
        if not schema.name.startswith("foxglove."):
            continue
        short = schema.name.split(".")[1]
        module = importlib.import_module(f"foxglove_schemas_protobuf.{short}_pb2")
        assert short in module.DESCRIPTOR.message_types_by_name  # the name Foxglove renders by
        official = {}
        todo = [module.DESCRIPTOR]
        while todo:
            fd = todo.pop()
            official[fd.name] = _without_json_names(descriptor_pb2.FileDescriptorProto.FromString(fd.serialized_pb))
            todo += fd.dependencies
        embedded = {
            f.name: _without_json_names(f) for f in descriptor_pb2.FileDescriptorSet.FromString(schema.data).file
        }
        assert embedded == official, schema.name
        names.add(schema.name)
    kinds = ("FrameTransforms", "PointCloud", "CompressedImage", "RawImage", "SceneUpdate", "CameraCalibration")
    assert names == {f"foxglove.{n}" for n in (*kinds, "ImageAnnotations")}
    for r in _decode(coop):
        if r.schema.startswith("foxglove."):
            short = r.schema.split(".")[1]
            cls = getattr(importlib.import_module(f"foxglove_schemas_protobuf.{short}_pb2"), short)
            assert cls.FromString(r.data).SerializeToString() == r.data, r.topic


def test_the_project_schema_is_the_documented_proto(coop: Path) -> None:
    block = (ROOT / "docs" / "recording.md").read_text(encoding="utf-8").split("```proto", 1)[1].split("```", 1)[0]
    documented: dict[str, list[tuple[bool, str, str, int]]] = {}
    current = ""
    for line in block.splitlines():
        if m := re.match(r"\s*message (\w+)", line):
            current = m.group(1)
            documented[current] = []
        elif m := re.match(r"\s*(repeated )?(\w+) (\w+) = (\d+);", line):
            documented[current].append((bool(m.group(1)), m.group(2), m.group(3), int(m.group(4))))
    kinds = {v: k[len("TYPE_") :].lower() for k, v in descriptor_pb2.FieldDescriptorProto.Type.items()}
    with coop.open("rb") as f:
        s = make_reader(f).get_summary()
    assert s is not None
    own = [sc for sc in s.schemas.values() if sc.name.startswith("mmusv.")]
    assert sorted(sc.name for sc in own) == ["mmusv.AgentAnnotations", "mmusv.WorldState"]
    for sc in own:
        (fd,) = descriptor_pb2.FileDescriptorSet.FromString(sc.data).file
        assert (fd.name, fd.package, fd.syntax) == ("mmusv/record.proto", "mmusv", "proto3")
        got = {
            m.name: [
                (
                    f.label == f.LABEL_REPEATED,
                    f.type_name.rsplit(".", 1)[-1] if f.type == f.TYPE_MESSAGE else kinds[f.type],
                    f.name,
                    f.number,
                )
                for f in m.field
            ]
            for m in fd.message_type
        }
        assert got == documented, sc.name


# ---------------------------------------------------------------------------------------------- frames and geometry


def test_every_frame_id_of_a_full_rig_is_in_the_tf_tree(coop: Path) -> None:
    assert _unresolved(coop) == []


def test_boxes_of_a_usv_without_lidar_name_a_frame_of_the_tf_tree(no_lidar: Path) -> None:
    # The boxes of a rig without LiDAR are in the vessel's body frame (mmusv.annotate); /boxes named
    # "{agent}/lidar", a frame no /tf message defines, so Foxglove could not place them.
    assert _unresolved(no_lidar) == []
    frame = next(iter(_frames(_decode(no_lidar)).values()))
    assert [e.frame_id for e in frame["/usv_a/boxes"].msg.entities] == ["usv_a"]


def _check_boxes(path: Path) -> int:
    """Every ``/boxes`` cube, through ``/tf``, is its vessel's box of ``/world/state`` (centre, size, orientation),
    and the annotations' LiDAR boxes are the cubes. Returns the number of boxes checked."""
    n = 0
    for frame in _frames(_decode(path)).values():
        tree = Tree(frame["/tf"].msg)
        vessels = {v.id: v for v in frame["/world/state"].msg.vessels}
        for topic, r in frame.items():
            if r.schema != "foxglove.SceneUpdate":
                continue
            (e,) = r.msg.entities
            assert e.frame_locked and e.lifetime.ToNanoseconds() == 0 and not r.msg.deletions
            ann = frame[topic.replace("/boxes", "/annotations")].msg
            ids = [kv.key for kv in e.metadata]
            assert ids == [b.target_id for b in ann.boxes_lidar] and len(e.cubes) == len(ids) == len(e.texts)
            ref = tree.world(e.frame_id)
            for tid, cube, text, b in zip(ids, e.cubes, e.texts, ann.boxes_lidar, strict=True):
                v = vessels[tid]
                p = cube.pose.position
                o = cube.pose.orientation
                assert [p.x, p.y, p.z] == list(b.center) and [o.x, o.y, o.z, o.w] == list(b.rotation)
                assert [cube.size.x, cube.size.y, cube.size.z] == list(b.size) == list(v.box_size)
                assert (ref @ [p.x, p.y, p.z, 1])[:3] == pytest.approx(list(v.box_center), abs=1e-6)
                rot = ref[:3, :3] @ Rotation.from_quat([o.x, o.y, o.z, o.w]).as_matrix()
                assert rot == pytest.approx(tree.world(tid)[:3, :3], abs=1e-6)
                assert b.range_m == pytest.approx(float(np.linalg.norm(b.center)), abs=1e-6)
                assert text.text == tid and text.billboard and text.scale_invariant and text.font_size == 14
                assert text.pose.position.z == pytest.approx(p.z + cube.size.z / 2 + 0.5)
                n += 1
    return n


def test_boxes_through_tf_are_the_world_states_vessels(coop: Path, no_lidar: Path) -> None:
    assert _check_boxes(coop) >= 4
    assert _check_boxes(no_lidar) >= 2


def test_world_state_units_and_the_tf_of_vessels_and_sensors(coop: Path) -> None:
    frames = list(_frames(_decode(coop)).values())
    states = [f["/world/state"].msg for f in frames]
    for frame, ws in zip(frames, states, strict=True):
        tree = Tree(frame["/tf"].msg)
        for v in ws.vessels:
            body = tree.world(v.id)
            assert body[:3, 3] == pytest.approx(list(v.pose[:3]), abs=1e-9)
            # roll, pitch, yaw in rad: R = Rz(yaw) Ry(pitch) Rx(roll)
            assert body[:3, :3] == pytest.approx(Rotation.from_euler("xyz", v.pose[3:]).as_matrix(), abs=1e-9)
    for i, v in enumerate(states[0].vessels):  # m/s: the displacement over one frame period
        step = (np.array(states[1].vessels[i].pose[:3]) - v.pose[:3]) * FREQUENCY_HZ
        assert step[:2] == pytest.approx(list(v.velocity[:2]), abs=0.05)
    # agent → sensor transforms: the mounts of the sensors metadata, the same in every frame
    with coop.open("rb") as f:
        meta = {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}
    sensors = json.loads(meta["sensors"]["json"])
    optical = np.eye(4)
    optical[:3, :3] = [[0, 0, 1], [-1, 0, 0], [0, -1, 0]]  # x right, y down, z forward in x forward, y left, z up
    mounts = [
        [(t.parent_frame_id, t.child_frame_id, t.translation, t.rotation) for t in f["/tf"].msg.transforms]
        for f in frames
    ]
    assert [m for m in mounts[0] if m[0] != "world"] == [m for m in mounts[1] if m[0] != "world"]
    tree = Tree(frames[0]["/tf"].msg)
    for agent, s in sensors.items():
        assert tree.pose[f"{agent}/lidar"] == pytest.approx(np.array(s["lidar_mount_in_body"]), abs=1e-9)
        assert tree.pose[f"{agent}/radar"] == pytest.approx(np.array(s["radar_mount_in_body"]), abs=1e-9)
        for name, cam in s["cameras"].items():
            want = np.array(cam["mount_in_body"]) @ optical
            assert tree.pose[f"{agent}/camera/{name}"] == pytest.approx(want, abs=1e-9)


def _cloud(msg: Any) -> np.ndarray:
    names = [f.name for f in msg.fields]
    formats = [NUMERIC[f.type][0] for f in msg.fields]
    offsets = [f.offset for f in msg.fields]
    dtype = np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": msg.point_stride})
    return np.frombuffer(msg.data, dtype=dtype)


def test_point_clouds_and_images_have_the_documented_layouts(coop: Path) -> None:
    checked = collections.Counter()
    for frame in _frames(_decode(coop)).values():
        for topic, r in frame.items():
            m = r.msg
            if r.schema == "foxglove.PointCloud":
                offset = 0
                for f in m.fields:
                    assert f.offset == offset, (topic, f.name)  # packed back to back, no padding
                    offset += NUMERIC[f.type][1]
                assert m.point_stride == offset and len(m.data) % offset == 0 and not m.HasField("pose")
                fields = [(f.name, f.type) for f in m.fields]
                assert fields == (LIDAR_FIELDS if topic.endswith("/lidar") else RADAR_FIELDS), topic
                pts = _cloud(m)
                xyz = np.stack([pts["x"], pts["y"], pts["z"]], axis=1)
                if topic.endswith("/lidar"):
                    az = np.arctan2(pts["y"], pts["x"]) % (2 * np.pi)
                    assert np.abs(np.angle(np.exp(1j * (az - pts["azimuth"])))).max() < 1e-4
                else:
                    assert np.linalg.norm(xyz, axis=1) == pytest.approx(pts["range"], abs=1e-3)
            elif r.schema == "foxglove.RawImage":
                assert m.encoding == "32FC1" and topic.endswith("/depth")
                assert m.step == m.width * RAW_BYTES[m.encoding] and len(m.data) == m.step * m.height
                depth = np.frombuffer(m.data, "<f4").reshape(m.height, m.width)
                inst = np.array(Image.open(io.BytesIO(frame[topic[: -len("depth")] + "instance"].msg.data)))
                assert np.array_equal(np.isinf(depth), inst == 65535) and (depth[np.isfinite(depth)] > 0).all()
            elif r.schema == "foxglove.CompressedImage":
                assert m.format == "png"
                img = Image.open(io.BytesIO(m.data))
                img.load()
                kind = topic.rsplit("/", 1)[1]
                assert img.mode == ("RGB" if kind in ("rgb", "ppi") else "I;16"), topic
            checked[r.schema] += 1
    assert checked["foxglove.PointCloud"] == 8 and checked["foxglove.RawImage"] == 8
    assert checked["foxglove.CompressedImage"] == 2 * 2 * (3 * 2 + 3 + 1)


def test_metadata_records_are_the_documented_ones(coop: Path) -> None:
    import mmusv
    from mmusv.config import load_scenario, scenario_hash

    with coop.open("rb") as f:
        reader = make_reader(f)
        meta = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
        assert list(reader.iter_attachments()) == []
    assert [n for n, _ in meta] == ["scenario", "manifest", "sensors", "run"]
    md = dict(meta)
    assert set(md["scenario"]) == {"name", "yaml"} and md["scenario"]["name"] == "round_coop"
    scenario = yaml.safe_load(md["scenario"]["yaml"])
    assert md["manifest"] == {
        "config_hash": scenario_hash(load_scenario(scenario)),
        "seed": "11",
        "mmusv_version": mmusv.__version__,
        "first_frame": "0",
        "frames_requested": "2",
    }
    assert set(json.loads(md["sensors"]["json"])) == {"usv_a", "usv_b"}
    run = md["run"]
    assert run["status"] == "complete" and run["agents"] == "usv_a,usv_b"
    assert (run["frames_configured"], run["frames_written"], float(run["frequency_hz"])) == ("2", "2", FREQUENCY_HZ)


# ---------------------------------------------------------------------------------------------- mmusv's reader


def test_mmusv_reader_gives_what_the_independent_decode_gives(coop: Path) -> None:
    from mmusv.recording import decode_image, decode_point_cloud, read_info, read_messages, summary
    from mmusv.recording.decode import WorldFrame
    from mmusv.recording.stream import FrameStream

    recs = _decode(coop)
    ours = list(read_messages(coop))
    assert [(t, lt, m.SerializeToString()) for t, lt, m in ours] == [(r.topic, r.log_time, r.data) for r in recs]
    for (_t, _lt, m), r in zip(ours, recs, strict=True):
        if r.schema == "foxglove.PointCloud":
            cloud, pts = decode_point_cloud(m), _cloud(r.msg)
            assert list(cloud) == list(pts.dtype.names)
            assert all(np.array_equal(cloud[k], pts[k]) and cloud[k].dtype == pts[k].dtype for k in cloud)
        elif r.schema == "foxglove.CompressedImage":
            want = np.array(Image.open(io.BytesIO(r.msg.data)))
            got = decode_image(m)
            assert got.dtype == want.dtype and np.array_equal(got, want)
        elif r.schema == "foxglove.RawImage":
            want = np.frombuffer(r.msg.data, "<f4").reshape(r.msg.height, r.msg.width)
            assert np.array_equal(decode_image(m), want)
        elif r.schema == "mmusv.WorldState":
            w = WorldFrame.from_message(m)
            assert w.ids == [v.id for v in r.msg.vessels] and w.frame == r.msg.frame
            assert np.array_equal(w.poses, [list(v.pose) for v in r.msg.vessels])
            assert np.array_equal(w.box_sizes, [list(v.box_size) for v in r.msg.vessels])
    s = summary(coop)
    with coop.open("rb") as f:
        reader = make_reader(f)
        st = reader.get_summary().statistics  # type: ignore[union-attr]
        meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
    assert s["complete"] and s["messages"] == st.message_count and s["metadata"] == meta
    assert (s["start_ns"], s["end_ns"], s["attachments"], s["damage"]) == (0, st.message_end_time, [], [])
    assert {t: d["messages"] for t, d in s["topics"].items()} == dict(collections.Counter(r.topic for r in recs))
    assert {t: d["schema"] for t, d in s["topics"].items()} == {r.topic: r.schema for r in recs}
    assert s["frames"]["read"] == s["frames"]["expected"] == 2 and s["frames"]["report"] is None
    info = read_info(coop)
    assert (info.frequency_hz, info.seed, info.config_hash) == (FREQUENCY_HZ, 11, meta["manifest"]["config_hash"])
    assert [a.id for a in info.agents] == ["usv_a", "usv_b"] and info.planned == (0, 2) and info.has_summary
    frames = list(FrameStream(info, want=lambda _t: True))
    assert [(fr.index, fr.log_time_ns, len(fr.messages)) for fr in frames] == [
        (k, t, len(f)) for k, (t, f) in enumerate(sorted(_frames(recs).items()))
    ]


# ---------------------------------------------------------------------------------------------- writing, interrupted


def _write(path: Path, *, fail: bool = False) -> None:
    from mmusv.recording import Recording

    rng = np.random.default_rng(0)
    with Recording(path) as rec:
        rec.attachment("notes.txt", b"hello", media_type="text/plain", log_time_ns=5)
        rec.metadata("m", {"a": 1, "b": 2.5})
        for k in range(2):
            t = round(k * 0.1 * 1e9)
            rec.raw_image("/img", log_time_ns=t, frame_id="c", image=rng.integers(0, 255, (8, 8, 3), dtype=np.uint8))
            rec.raw_image("/mono16", log_time_ns=t, frame_id="c", image=np.arange(12, dtype=np.uint16).reshape(3, 4))
            rec.png_image("/png16", log_time_ns=t, frame_id="c", image=np.arange(12, dtype=np.uint16).reshape(3, 4))
            cols = {"x": np.arange(3, dtype=np.float32), "b": np.array([1, 0, 1], bool), "d": np.arange(3.0)}
            rec.point_cloud("/pc", log_time_ns=t, frame_id="l", columns=cols)
        if fail:
            raise RuntimeError("stopped")


def test_recording_api_files_are_deterministic_and_complete_after_an_exception(tmp_path: Path) -> None:
    from mmusv.errors import IoError
    from mmusv.recording import Recording

    _write(tmp_path / "a.mcap")
    _write(tmp_path / "b.mcap")
    digest = [hashlib.sha256((tmp_path / n).read_bytes()).digest() for n in ("a.mcap", "b.mcap")]
    assert digest[0] == digest[1]
    with pytest.raises(IoError, match="overwrite"):
        Recording(tmp_path / "a.mcap")
    with pytest.raises(RuntimeError):
        _write(tmp_path / "c.mcap", fail=True)
    assert not (tmp_path / "c.mcap").exists()
    with (tmp_path / "c.mcap.partial").open("rb") as f:
        reader = make_reader(f, validate_crcs=True)
        s = reader.get_summary()
        assert s is not None and s.statistics is not None and s.statistics.message_count == 8
        assert [(a.name, a.media_type, a.data_size) for a in s.attachment_indexes] == [("notes.txt", "text/plain", 5)]
        assert [(a.name, a.data) for a in reader.iter_attachments()] == [("notes.txt", b"hello")]
        assert [(m.name, m.metadata) for m in reader.iter_metadata()] == [("m", {"a": "1", "b": "2.5"})]
    recs = {r.topic: r.msg for r in _decode(tmp_path / "c.mcap.partial")}
    assert (recs["/mono16"].encoding, recs["/mono16"].step) == ("16UC1", 8)
    assert np.array(Image.open(io.BytesIO(recs["/png16"].data))).tolist() == np.arange(12).reshape(3, 4).tolist()
    pc = recs["/pc"]
    assert [(f.name, f.offset, f.type) for f in pc.fields] == [("x", 0, 7), ("b", 4, 1), ("d", 5, 8)]
    assert pc.point_stride == 13 and _cloud(pc)["d"].tolist() == [0.0, 1.0, 2.0]


# ---------------------------------------------------------------------------------------------- killed


_KILLER = """
import os, signal, sys
import mmusv
def progress(done, total):
    if done == int(sys.argv[3]):
        os.kill(os.getpid(), signal.SIGKILL)
mmusv.run(sys.argv[1], out_dir=sys.argv[2], progress=progress)
"""


def test_a_killed_run_reads_with_the_official_reader_up_to_its_last_closed_chunk(tmp_path: Path) -> None:
    from mmusv.recording import read_messages, summary

    # frames of one 960 x 720 depth image (2.7 MB): the 4 MiB chunks close every other frame
    cfg = lidar_scenario("killed", frames=6)
    cam = {"name": "front", "resolution": [960, 720], "hfov_deg": 90, "quality": "draft", "outputs": ["depth"]}
    cfg["rigs"]["r"]["cameras"] = [{**cam, "mount": {"point": "camera_front"}}]
    src = tmp_path / "killed.yaml"
    src.write_text(yaml.safe_dump(cfg), encoding="utf-8")
    env = {**os.environ, "PYTHONPATH": str(ROOT / "python") + os.pathsep + os.environ.get("PYTHONPATH", "")}
    argv = [sys.executable, "-c", _KILLER, str(src), str(tmp_path / "out"), "5"]
    proc = subprocess.run(argv, cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == -9, proc.stderr
    partial = tmp_path / "out" / "killed.mcap.partial"
    with partial.open("rb") as f, pytest.raises(McapError):
        make_reader(f).get_summary()  # a seeking reader needs the footer
    official = []
    with partial.open("rb") as f, pytest.raises(McapError):  # at the chunk being written (or the end)
        for _schema, ch, m in NonSeekingReader(f).iter_messages(log_time_order=False):
            official.append((ch.topic, m.log_time, m.data))
    topics = {"/tf", "/world/state", "/u/lidar", "/u/camera/front/depth", "/u/annotations", "/u/boxes"}
    topics |= {"/u/camera/front/calibration", "/u/camera/front/boxes"}
    assert {t for t, lt, _ in official if lt == 0} == topics  # at least frame 0, in a closed chunk
    names = []
    with partial.open("rb") as f, pytest.raises(McapError):
        for record in StreamReader(f).records:
            names += [record.name] if type(record).__name__ == "Metadata" else []
    assert names == ["scenario", "manifest", "sensors"]
    # mmusv's reader: the same messages first, then the complete records of the open chunk
    ours = [(t, lt, m.SerializeToString()) for t, lt, m in read_messages(partial)]
    assert ours[: len(official)] == official
    s = summary(partial)
    assert not s["complete"] and s["frames"]["expected"] == 6 and 1 <= s["frames"]["read"] < 6
