"""The MCAP recorder (:mod:`mmusv.recording` over ``mmusv._core.Recorder``).

Every message kind is written from Python and read back with the ``mcap`` reader plus
``mcap-protobuf-support`` (the same decoders Foxglove-compatible tools use); every field value is compared with
what went in. Point clouds are decoded independently with numpy from the field offsets, PNGs with Pillow.
"""

from __future__ import annotations

import io
import threading
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import pytest
from mcap.reader import make_reader
from mmusv.errors import InputError, IoError
from mmusv.recording import Recording, read_messages, summary, to_ns
from PIL import Image

# foxglove.PackedElementField.NumericType → numpy dtype
NUMERIC = {1: "u1", 2: "i1", 3: "<u2", 4: "<i2", 5: "<u4", 6: "<i4", 7: "<f4", 8: "<f8"}

RNG = np.random.default_rng(5)
N_POINTS = 500
CLOUD: dict[str, npt.NDArray[Any]] = {
    "x": RNG.normal(size=N_POINTS).astype(np.float32),
    "y": RNG.normal(size=N_POINTS).astype(np.float32),
    "z": RNG.normal(size=N_POINTS).astype(np.float32),
    "intensity": RNG.random(N_POINTS).astype(np.float32),
    "ring": RNG.integers(0, 64, N_POINTS).astype(np.uint16),
    "instance": RNG.integers(-1, 50, N_POINTS).astype(np.int32),
    "range": RNG.random(N_POINTS) * 100.0,
}
RGB = RNG.integers(0, 256, (24, 32, 3)).astype(np.uint8)
SEMANTIC = RNG.integers(0, 12, (24, 32)).astype(np.uint8)
INSTANCE = RNG.integers(0, 65535, (24, 32)).astype(np.uint16)
DEPTH = (RNG.random((24, 32)) * 300).astype(np.float32)
WORLD: dict[str, Any] = {
    "ids": ["usv0", "target1"],
    "assets": ["usv_small", "cargo_ship"],
    "roles": ["usv", "target"],
    "classes": [11, 10],
    "instance_ids": [2, 3],
    "poses": [[1.0, 2.0, 0.1, 0.01, -0.02, 0.5], [100.0, -50.0, 0.0, 0.0, 0.0, 3.0]],
    "velocities": [[1.0, 0.5, 0.0], [-3.0, 0.0, 0.01]],
    "box_centers": [[1.0, 2.0, 1.0], [100.0, -50.0, 5.0]],
    "box_sizes": [[5.0, 2.0, 1.5], [120.0, 20.0, 30.0]],
}
LIDAR: dict[str, Any] = {
    "target_id": ["target1", "target2"],
    "instance_id": [3, 4],
    "semantic_class": [10, 10],
    "center": [[50.0, 1.0, 2.0], [80.0, -4.0, 1.5]],
    "size": [[120.0, 20.0, 30.0], [10.0, 3.0, 2.0]],
    "rotation": [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.7071067811865476, 0.7071067811865476]],
    "yaw": [0.0, 1.5707963267948966],
    "lidar_points": [1200, 37],
    "range_m": [50.05, 80.1],
    "wave_occlusion": [0.0, 0.375],
}
BEV: dict[str, Any] = {
    "target_id": ["target1"],
    "x": [50.0],
    "y": [1.0],
    "length": [120.0],
    "width": [20.0],
    "yaw": [0.25],
}
CAMERA: dict[str, Any] = {
    "target_id": ["target1", "target2"],
    "camera": ["front", "left"],
    "x_min": [10.0, 0.0],
    "y_min": [5.0, 6.5],
    "x_max": [30.0, 12.0],
    "y_max": [20.0, 9.0],
    "truncation": [0.0, 0.4],
    "visible_pixels": [250, 12],
    "box_pixels": [300, 20],
    "occlusion": [1 - 250 / 300, 0.4],
    "wave_occlusion": [0.125, 0.0],
}
POSE = [1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0]


def write_everything(rec: Recording, frames: int = 2) -> None:
    """One message of every kind per frame, plus metadata and an attachment."""
    for k in range(frames):
        t = to_ns(0.1 * k)
        rec.point_cloud("/usv0/lidar", log_time_ns=t, frame_id="usv0/lidar", columns=CLOUD, pose=POSE)
        rec.png_image("/usv0/camera/front/rgb", log_time_ns=t, frame_id="usv0/camera/front", image=RGB)
        rec.png_image("/usv0/camera/front/semantic", log_time_ns=t, frame_id="usv0/camera/front", image=SEMANTIC)
        rec.png_image("/usv0/camera/front/instance", log_time_ns=t, frame_id="usv0/camera/front", image=INSTANCE)
        rec.raw_image("/usv0/camera/front/depth", log_time_ns=t, frame_id="usv0/camera/front", image=DEPTH)
        rec.raw_image("/usv0/top_view/rgb", log_time_ns=t, frame_id="world", image=RGB)
        rec.frame_transforms(
            "/tf",
            log_time_ns=t,
            transforms=[
                ("world", "usv0", [float(k), 2.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
                ("usv0", "usv0/lidar", [0.0, 0.0, 2.5], [0.0, 0.0, 0.7071067811865476, 0.7071067811865476]),
            ],
        )
        rec.boxes(
            "/usv0/boxes",
            log_time_ns=t,
            frame_id="usv0/lidar",
            entity_id="targets",
            ids=LIDAR["target_id"],
            centers=LIDAR["center"],
            quaternions=LIDAR["rotation"],
            sizes=LIDAR["size"],
            colors=[[1.0, 0.0, 0.0, 0.5], [0.0, 1.0, 0.0, 0.5]],
            labels=["ship", ""],
        )
        rec.world_state("/world/state", log_time_ns=t, frame=k, time_s=0.1 * k, **WORLD)
        rec.annotations(
            "/usv0/annotations", log_time_ns=t, frame=k, time_s=0.1 * k, agent_id="usv0", lidar=LIDAR, bev=BEV,
            camera=CAMERA,
        )  # fmt: skip
    rec.metadata("scenario", {"name": "demo", "seed": 7})
    rec.attachment("scenario.yaml", b"name: demo\n", media_type="application/yaml")


TOPIC_COUNT = 10


@pytest.fixture
def recording(tmp_path: Path) -> Path:
    path = tmp_path / "run.mcap"
    with Recording(path) as rec:
        write_everything(rec)
    return path


def by_topic(path: Path) -> dict[str, list[tuple[int, Any]]]:
    out: dict[str, list[tuple[int, Any]]] = {}
    for topic, t, msg in read_messages(path):
        out.setdefault(topic, []).append((t, msg))
    return out


def test_every_channel_decodes_and_sequences_count_per_channel(recording: Path) -> None:
    msgs = by_topic(recording)
    assert len(msgs) == TOPIC_COUNT
    assert all([t for t, _ in v] == [0, 100_000_000] for v in msgs.values())
    with open(recording, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        seqs: dict[str, list[int]] = {}
        for schema, channel, message in reader.iter_messages():
            assert message.publish_time == message.log_time
            assert channel.message_encoding == "protobuf" and schema is not None and schema.encoding == "protobuf"
            seqs.setdefault(channel.topic, []).append(message.sequence)
    assert all(s == [0, 1] for s in seqs.values())


def test_point_cloud_bytes_decode_to_the_same_columns(recording: Path) -> None:
    (_, msg), _ = by_topic(recording)["/usv0/lidar"]
    assert msg.frame_id == "usv0/lidar" and msg.timestamp.seconds == 0 and msg.timestamp.nanos == 0
    assert [f.name for f in msg.fields] == list(CLOUD)
    dtype = np.dtype(
        {
            "names": [f.name for f in msg.fields],
            "formats": [NUMERIC[f.type] for f in msg.fields],
            "offsets": [f.offset for f in msg.fields],
            "itemsize": msg.point_stride,
        }
    )
    points = np.frombuffer(msg.data, dtype=dtype)
    assert len(points) == N_POINTS
    for name, values in CLOUD.items():
        assert points[name].dtype == values.dtype.newbyteorder("<")
        np.testing.assert_array_equal(points[name], values)
    p = msg.pose
    assert [p.position.x, p.position.y, p.position.z] == POSE[:3]
    assert [p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w] == POSE[3:]


def test_png_images_decode_with_pillow_to_the_same_pixels(recording: Path) -> None:
    msgs = by_topic(recording)
    cases: list[tuple[str, npt.NDArray[Any]]] = [("rgb", RGB), ("semantic", SEMANTIC), ("instance", INSTANCE)]
    for topic, want in cases:
        _, msg = msgs[f"/usv0/camera/front/{topic}"][1]
        assert msg.format == "png" and msg.frame_id == "usv0/camera/front"
        assert (msg.timestamp.seconds, msg.timestamp.nanos) == (0, 100_000_000)
        got = np.asarray(Image.open(io.BytesIO(msg.data)))
        np.testing.assert_array_equal(got.astype(want.dtype), want)
        assert got.shape == want.shape


def test_raw_images_keep_encoding_step_and_values(recording: Path) -> None:
    msgs = by_topic(recording)
    _, depth = msgs["/usv0/camera/front/depth"][0]
    assert (depth.width, depth.height, depth.encoding, depth.step) == (32, 24, "32FC1", 32 * 4)
    np.testing.assert_array_equal(np.frombuffer(depth.data, "<f4").reshape(24, 32), DEPTH)
    _, rgb = msgs["/usv0/top_view/rgb"][0]
    assert (rgb.encoding, rgb.step) == ("rgb8", 32 * 3)
    np.testing.assert_array_equal(np.frombuffer(rgb.data, np.uint8).reshape(24, 32, 3), RGB)


def test_transforms_and_boxes(recording: Path) -> None:
    msgs = by_topic(recording)
    _, tf = msgs["/tf"][1]
    assert [(t.parent_frame_id, t.child_frame_id) for t in tf.transforms] == [("world", "usv0"), ("usv0", "usv0/lidar")]
    assert tf.transforms[0].translation.x == 1.0 and tf.transforms[1].translation.z == 2.5
    assert tf.transforms[1].rotation.w == pytest.approx(0.7071067811865476)
    _, update = msgs["/usv0/boxes"][0]
    (entity,) = update.entities
    assert entity.id == "targets" and entity.frame_id == "usv0/lidar" and entity.frame_locked
    assert entity.lifetime.seconds == 0 and entity.lifetime.nanos == 0
    assert [(kv.key, kv.value) for kv in entity.metadata] == [("target1", "ship"), ("target2", "")]
    assert len(entity.cubes) == 2 and [t.text for t in entity.texts] == ["ship"]
    cube = entity.cubes[1]
    assert [cube.pose.position.x, cube.pose.position.y, cube.pose.position.z] == LIDAR["center"][1]
    assert [cube.size.x, cube.size.y, cube.size.z] == LIDAR["size"][1]
    q = cube.pose.orientation
    assert [q.x, q.y, q.z, q.w] == LIDAR["rotation"][1]
    assert [cube.color.r, cube.color.g, cube.color.b, cube.color.a] == [0.0, 1.0, 0.0, 0.5]
    assert entity.texts[0].pose.position.z == pytest.approx(2.0 + 15.0 + 0.5)


def test_world_state_round_trips(recording: Path) -> None:
    _, ws = by_topic(recording)["/world/state"][1]
    assert type(ws).DESCRIPTOR.full_name == "mmusv.WorldState"
    assert ws.frame == 1 and ws.time_s == 0.1
    assert [v.id for v in ws.vessels] == WORLD["ids"]
    assert [v.asset for v in ws.vessels] == WORLD["assets"]
    assert [v.role for v in ws.vessels] == WORLD["roles"]
    assert [v.semantic_class for v in ws.vessels] == WORLD["classes"]
    assert [v.instance_id for v in ws.vessels] == WORLD["instance_ids"]
    for field in ("poses", "velocities", "box_centers", "box_sizes"):
        proto = {"poses": "pose", "velocities": "velocity", "box_centers": "box_center", "box_sizes": "box_size"}
        assert [list(getattr(v, proto[field])) for v in ws.vessels] == WORLD[field]


def test_annotations_round_trip(recording: Path) -> None:
    _, ann = by_topic(recording)["/usv0/annotations"][0]
    assert type(ann).DESCRIPTOR.full_name == "mmusv.AgentAnnotations"
    assert (ann.frame, ann.time_s, ann.agent_id) == (0, 0.0, "usv0")
    for table, boxes in [(LIDAR, ann.boxes_lidar), (BEV, ann.boxes_bev), (CAMERA, ann.boxes_camera)]:
        assert len(boxes) == len(table["target_id"])
        for key, column in table.items():
            got = [list(v) if isinstance(column[0], list) else v for v in (getattr(b, key) for b in boxes)]
            assert got == column, key


def test_metadata_attachment_and_summary(recording: Path) -> None:
    s = summary(recording)
    assert s["complete"] and s["messages"] == 2 * TOPIC_COUNT
    assert (s["start_ns"], s["end_ns"]) == (0, 100_000_000)
    assert s["metadata"] == {"scenario": {"name": "demo", "seed": "7"}}
    assert s["attachments"] == ["scenario.yaml"]
    assert s["topics"]["/world/state"] == {"schema": "mmusv.WorldState", "encoding": "protobuf", "messages": 2}
    assert s["topics"]["/usv0/lidar"]["schema"] == "foxglove.PointCloud"


def test_two_identical_runs_are_byte_identical(tmp_path: Path) -> None:
    blobs = []
    for name in ("a.mcap", "b.mcap"):
        with Recording(tmp_path / name) as rec:
            write_everything(rec)
        blobs.append((tmp_path / name).read_bytes())
    assert len(blobs[0]) > 10_000 and blobs[0] == blobs[1]


def test_partial_name_until_finish_and_existing_file_refused(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    rec = Recording(path)
    write_everything(rec, frames=1)
    assert rec.partial_path == tmp_path / "run.mcap.partial"
    assert rec.partial_path.exists() and not path.exists()
    info = rec.finish()
    assert info == {"path": str(path), "messages": TOPIC_COUNT, "channels": TOPIC_COUNT, "bytes": path.stat().st_size}
    assert path.exists() and not rec.partial_path.exists() and rec.closed
    with pytest.raises(IoError, match="closed"):
        rec.metadata("late", {})

    with pytest.raises(IoError, match=r"exists.*overwrite=True.*--overwrite"):
        Recording(path)
    before = path.read_bytes()
    with Recording(path, overwrite=True) as again:
        again.metadata("only", {"a": "b"})
        assert path.read_bytes() == before  # replaced only on finish
    assert summary(path)["metadata"] == {"only": {"a": "b"}}


def test_exception_inside_with_leaves_a_readable_partial_file(tmp_path: Path) -> None:
    path = tmp_path / "crash.mcap"
    with pytest.raises(RuntimeError, match="boom"), Recording(path) as rec:
        write_everything(rec, frames=1)
        raise RuntimeError("boom")
    assert not path.exists()
    partial = tmp_path / "crash.mcap.partial"
    assert len(list(read_messages(partial))) == TOPIC_COUNT
    s = summary(partial)
    assert not s["complete"] and s["messages"] == TOPIC_COUNT
    assert rec.closed


def test_bad_inputs_are_refused(tmp_path: Path) -> None:
    with Recording(tmp_path / "bad.mcap") as rec:
        with pytest.raises(InputError, match="dtype"):
            rec.point_cloud("/p", log_time_ns=0, frame_id="f", columns={"x": np.zeros(3, np.complex64)})
        with pytest.raises(InputError, match="values but the first column"):
            rec.point_cloud("/p", log_time_ns=0, frame_id="f", columns={"x": np.zeros(3), "y": np.zeros(2)})
        with pytest.raises(InputError, match="image"):
            rec.raw_image("/i", log_time_ns=0, frame_id="f", image=np.zeros((4, 4, 2), np.uint8))
        with pytest.raises(InputError, match="PNG"):
            rec.png_image("/i", log_time_ns=0, frame_id="f", image=np.zeros((4, 4), np.float32))
        rec.raw_image("/i", log_time_ns=0, frame_id="f", image=np.zeros((4, 4), np.uint8))
        with pytest.raises(InputError, match=r"already carries foxglove\.RawImage"):
            rec.world_state("/i", log_time_ns=0, frame=0, time_s=0.0, **WORLD)
        with pytest.raises(InputError, match="unit length"):
            rec.frame_transforms("/tf", log_time_ns=0, transforms=[("a", "b", [0, 0, 0], [0, 0, 0, 2])])
        with pytest.raises(InputError, match="repeated"):
            rec.boxes(
                "/b", log_time_ns=0, frame_id="f", entity_id="e", ids=["a", "a"], centers=np.zeros((2, 3)),
                quaternions=[[0, 0, 0, 1]] * 2, sizes=np.ones((2, 3)), colors=np.ones((2, 4)),
            )  # fmt: skip
        with pytest.raises(InputError, match="lidar: missing column"):
            rec.annotations("/a", log_time_ns=0, frame=0, time_s=0.0, agent_id="u", lidar={"target_id": ["t"]})
        with pytest.raises(InputError, match="2 entries for 1 ids"):
            rec.world_state("/w", log_time_ns=0, frame=0, time_s=0.0, **{**WORLD, "ids": ["one"]})


def test_threads_share_one_recorder(tmp_path: Path) -> None:
    path = tmp_path / "threads.mcap"
    with Recording(path) as rec:

        def work(i: int) -> None:
            for k in range(20):
                rec.png_image(f"/usv{i}/camera/front/rgb", log_time_ns=k, frame_id="f", image=RGB)

        threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(timeout=60)
    s = summary(path)
    assert s["messages"] == 80 and all(v["messages"] == 20 for v in s["topics"].values())


def test_images_batch_writes_the_bytes_of_one_call_per_image(tmp_path: Path) -> None:
    """Encoded in parallel, written in list order: the same file as png_image / raw_image one by one."""
    items = [
        ("/c/rgb", "cam", RGB, "png"),
        ("/c/depth", "cam", DEPTH, "raw"),
        ("/c/semantic", "cam", SEMANTIC, "png"),
        ("/c/instance", "cam", INSTANCE, "png"),
        ("/d/rgb", "cam_d", RGB[::-1].copy(), "png"),
    ]
    with Recording(tmp_path / "one.mcap") as rec:
        for k in range(3):
            for topic, frame_id, image, fmt in items:
                call = rec.png_image if fmt == "png" else rec.raw_image
                call(topic, log_time_ns=to_ns(0.2 * k), frame_id=frame_id, image=image)
    with Recording(tmp_path / "batch.mcap") as rec:
        for k in range(3):
            encode_s, write_s = rec.images(log_time_ns=to_ns(0.2 * k), images=items)  # type: ignore[arg-type]
            assert encode_s >= 0 and write_s >= 0
    one, batch = (tmp_path / "one.mcap").read_bytes(), (tmp_path / "batch.mcap").read_bytes()
    assert len(one) > 5_000 and one == batch
    msgs = list(read_messages(tmp_path / "batch.mcap", topics=["/c/instance"]))
    assert len(msgs) == 3
    got = np.asarray(Image.open(io.BytesIO(msgs[0][2].data)))
    np.testing.assert_array_equal(got, INSTANCE)


def test_images_batch_refuses_bad_images_before_writing_any(tmp_path: Path) -> None:
    with Recording(tmp_path / "bad.mcap") as rec:
        good = ("/ok", "f", RGB, "png")
        with pytest.raises(InputError, match=r"images\[1\]: PNG holds uint8 or uint16"):
            rec.images(log_time_ns=0, images=[good, ("/d", "f", DEPTH, "png")])
        with pytest.raises(InputError, match=r"images\[1\] format 'jpeg'"):
            rec.images(log_time_ns=0, images=[good, ("/j", "f", RGB, "jpeg")])  # type: ignore[list-item]
        with pytest.raises(InputError, match=r"invalid images\[0\]"):
            rec.images(log_time_ns=0, images=[("/x", "f", np.zeros((4, 4, 2), np.uint8), "raw")])
        with pytest.raises(InputError, match="topic"):
            rec.images(log_time_ns=0, images=[good, ("", "f", RGB, "png")])
    assert summary(tmp_path / "bad.mcap")["messages"] == 0  # nothing of a refused batch was written
