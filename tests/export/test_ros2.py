"""``--to ros2``: the bag read back with rosbags (Humble and Jazzy typestores) and with mcap-ros2-support, against
the source recording (point counts and values, image sizes, the /tf chain, stamps)."""

from __future__ import annotations

import io
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mmusv.export import convert
from mmusv.export.ros2 import MAP_FRAME, TIME_OFFSET_NS, base_link, camera_info_topic, odom_frame, optical_frame
from mmusv.recording import decode_image, decode_point_cloud, read_info, read_messages, topics
from PIL import Image
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from scipy.spatial.transform import Rotation

_NUMPY = {1: "i1", 2: "u1", 3: "<i2", 4: "<u2", 5: "<i4", 6: "<u4", 7: "<f4", 8: "<f8"}  # sensor_msgs/PointField


@pytest.fixture(scope="module")
def bag(coop_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("ros2") / "o"
    rep = convert(coop_rec, to="ros2", out_dir=out)
    assert rep.frames == 3
    return out / "export_coop"


def raw_messages(bag: Path) -> tuple[list[Any], list[tuple[str, str, int, bytes]]]:
    """The bag's connections and every message ``(topic, type, log time, CDR bytes)``."""
    with AnyReader([bag]) as r:
        return list(r.connections), [(c.topic, c.msgtype, t, bytes(raw)) for c, t, raw in r.messages()]


def recording(rec: Path) -> dict[str, list[tuple[int, Any]]]:
    out: dict[str, list[tuple[int, Any]]] = defaultdict(list)
    for topic, t, msg in read_messages(rec):
        out[topic].append((t, msg))
    return out


def matrix(translation: Any, rotation: Any) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = Rotation.from_quat([rotation.x, rotation.y, rotation.z, rotation.w]).as_matrix()
    m[:3, 3] = [translation.x, translation.y, translation.z]
    return m


def chain(edges: dict[str, tuple[str, np.ndarray]], child: str, root: str) -> np.ndarray:
    """child → root by walking the parents."""
    m = np.eye(4)
    while child != root:
        parent, tr = edges[child]
        m = tr @ m
        child = parent
    return m


def test_layout_and_profile(bag: Path) -> None:
    from mcap.reader import make_reader

    assert sorted(p.name for p in bag.iterdir()) == ["export_coop.mcap", "metadata.yaml"]
    with (bag / "export_coop.mcap").open("rb") as f:
        reader = make_reader(f)
        assert reader.get_header().profile == "ros2"
        summ = reader.get_summary()
        assert summ is not None
        assert {s.encoding for s in summ.schemas.values()} == {"ros2msg"}
        assert {c.message_encoding for c in summ.channels.values()} == {"cdr"}


@pytest.mark.parametrize("store", [Stores.ROS2_HUMBLE, Stores.ROS2_JAZZY])
def test_every_message_deserialises_with_the_ros2_typestore(bag: Path, store: Stores) -> None:
    conns, msgs = raw_messages(bag)
    ts = get_typestore(store)
    bag_types: dict[str, Any] = {}
    for c in conns:
        bag_types.update(get_types_from_msg(c.msgdef.data, c.msgtype))
    used = {c.msgtype for c in conns}
    missing = {t for t in used if t not in ts.fielddefs}
    assert {t.split("/")[0] for t in missing} == {"vision_msgs"}  # the only package not in the stores
    for t in sorted(used - missing):  # the bag's definitions have the store's fields
        assert bag_types[t][1] == ts.fielddefs[t][1], t
    ts.register({k: v for k, v in bag_types.items() if k not in ts.fielddefs})
    if store == Stores.ROS2_HUMBLE:  # the schema text is exactly the one rosbag2 would write (Humble store)
        for c in conns:
            if c.msgtype not in missing:
                assert c.msgdef.data == ts.generate_msgdef(c.msgtype, ros_version=2)[0]
    for topic, msgtype, _t, raw in msgs:
        msg = ts.deserialize_cdr(raw, msgtype)
        assert msg.__msgtype__ == msgtype, topic
    assert {
        "sensor_msgs/msg/PointCloud2",
        "sensor_msgs/msg/Image",
        "sensor_msgs/msg/CompressedImage",
        "sensor_msgs/msg/CameraInfo",
        "tf2_msgs/msg/TFMessage",
        "nav_msgs/msg/Odometry",
        "vision_msgs/msg/Detection3DArray",
        "vision_msgs/msg/Detection2DArray",
        "visualization_msgs/msg/MarkerArray",
        "rosgraph_msgs/msg/Clock",
    } <= used


def test_mcap_ros2_support_decodes_the_same_bag(bag: Path) -> None:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    _conns, msgs = raw_messages(bag)
    seen = []
    with (bag / "export_coop.mcap").open("rb") as f:
        for _s, ch, m, dec in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            seen.append((ch.topic, m.log_time))
            if ch.topic == "/clock":
                assert dec.clock.sec * 10**9 + dec.clock.nanosec == m.log_time
    assert sorted(seen) == sorted((topic, t) for topic, _m, t, _r in msgs)


def test_points_images_and_stamps_equal_the_recording(bag: Path, coop_rec: Path) -> None:
    src = recording(coop_rec)
    info = read_info(coop_rec)
    got: dict[str, list[tuple[int, Any]]] = defaultdict(list)
    with AnyReader([bag]) as r:
        for c, t, raw in r.messages():
            got[c.topic].append((t, r.deserialize(raw, c.msgtype)))
    # the bag's time is the sim time + TIME_OFFSET_NS (no stamp at time 0, tf2's "latest")
    assert [t for t, _ in got["/clock"]] == [t + TIME_OFFSET_NS for t, _ in src[topics.WORLD_STATE]]
    for a in info.agents:
        lidar = topics.lidar(a.id)
        assert len(got[lidar]) == len(src[lidar]) == 3
        for (t, pc), (t0, msg) in zip(got[lidar], src[lidar], strict=True):
            ref = decode_point_cloud(msg)
            assert t == t0 + TIME_OFFSET_NS
            assert pc.header.stamp.sec * 10**9 + pc.header.stamp.nanosec == t0 + TIME_OFFSET_NS
            assert pc.width * pc.height == len(ref["x"]) and pc.header.frame_id == topics.lidar_frame(a.id)
            dt = np.dtype(
                {
                    "names": [f.name for f in pc.fields],
                    "formats": [_NUMPY[f.datatype] for f in pc.fields],
                    "offsets": [f.offset for f in pc.fields],
                    "itemsize": pc.point_step,
                }
            )
            pts = np.frombuffer(bytes(pc.data), dtype=dt)
            for name in ("x", "y", "z", "intensity", "ring", "class", "instance"):
                np.testing.assert_array_equal(pts[name], ref[name])
        for name, cam in a.cameras.items():
            rgb = topics.camera(a.id, name, kind="rgb")
            for (_t, img), (_t0, msg) in zip(got[rgb + "/compressed"], src[rgb], strict=True):
                arr = np.asarray(Image.open(io.BytesIO(bytes(img.data))))
                assert arr.shape == (cam.height, cam.width, 3) and img.header.frame_id == optical_frame(a.id, name)
                np.testing.assert_array_equal(arr, decode_image(msg))
            depth = topics.camera(a.id, name, kind="depth")
            for (_t, img), (_t0, msg) in zip(got[depth], src[depth], strict=True):
                assert (img.height, img.width, img.encoding) == (cam.height, cam.width, "32FC1")
                np.testing.assert_array_equal(
                    np.frombuffer(bytes(img.data), "<f4").reshape(cam.height, cam.width), decode_image(msg)
                )
            for kind in ("semantic", "instance"):
                topic = topics.camera(a.id, name, kind=kind)
                for (_t, img), (_t0, msg) in zip(got[topic], src[topic], strict=True):
                    arr = np.frombuffer(bytes(img.data), "<u2").reshape(img.height, img.width)
                    np.testing.assert_array_equal(arr, decode_image(msg))
            infos = got[camera_info_topic(a.id, name)]
            assert len(infos) == 3
            ci = infos[0][1]
            fx, fy, cx, cy = cam.intrinsics
            assert (ci.width, ci.height) == (cam.width, cam.height)
            # ROS's pixel centres are whole numbers (OpenCV's), mmusv's at +0.5: half a pixel less.
            np.testing.assert_allclose(ci.k, [fx, 0, cx - 0.5, 0, fy, cy - 0.5, 0, 0, 1])
        ann = src[topics.agent_annotations(a.id)]
        dets = got[f"/{a.id}/detections"]
        for (_t, d), (_t0, msg) in zip(dets, ann, strict=True):
            assert [x.id for x in d.detections] == [b.target_id for b in msg.boxes_lidar]
            for x, b in zip(d.detections, msg.boxes_lidar, strict=True):
                np.testing.assert_allclose([x.bbox.size.x, x.bbox.size.y, x.bbox.size.z], list(b.size))
                p = x.bbox.center.position
                np.testing.assert_allclose([p.x, p.y, p.z], list(b.center))


def test_tf_chain_equals_the_recording(bag: Path, coop_rec: Path) -> None:
    src = recording(coop_rec)
    info = read_info(coop_rec)
    with AnyReader([bag]) as r:
        tf = [(t, r.deserialize(raw, c.msgtype)) for c, t, raw in r.messages() if c.topic == "/tf"]
        static = [r.deserialize(raw, c.msgtype) for c, _t, raw in r.messages() if c.topic == "/tf_static"]
    assert len(static) == 1 and len(tf) == 3
    edges_static = {
        x.child_frame_id: (x.header.frame_id, matrix(x.transform.translation, x.transform.rotation))
        for x in static[0].transforms
    }
    for (t, msg), (t0, ref) in zip(tf, src[topics.TF], strict=True):
        assert t == t0 + TIME_OFFSET_NS
        edges = dict(edges_static)
        edges.update(
            {
                x.child_frame_id: (x.header.frame_id, matrix(x.transform.translation, x.transform.rotation))
                for x in msg.transforms
            }
        )
        rec = {(x.parent_frame_id, x.child_frame_id): matrix(x.translation, x.rotation) for x in ref.transforms}
        for a in info.agents:
            assert edges[base_link(a.id)][0] == odom_frame(a.id) and edges[odom_frame(a.id)][0] == MAP_FRAME
            body = rec[(topics.WORLD_FRAME, a.id)]
            np.testing.assert_allclose(chain(edges, base_link(a.id), MAP_FRAME), body, atol=1e-9)
            lidar = body @ rec[(a.id, topics.lidar_frame(a.id))]
            np.testing.assert_allclose(chain(edges, topics.lidar_frame(a.id), MAP_FRAME), lidar, atol=1e-9)
            for name in a.cameras:
                cam = body @ rec[(a.id, topics.camera_frame(a.id, name))]  # the recording's optical frame
                np.testing.assert_allclose(chain(edges, optical_frame(a.id, name), MAP_FRAME), cam, atol=1e-9)
        for vid in ("tgt", "boat"):
            np.testing.assert_allclose(
                chain(edges, base_link(vid), MAP_FRAME), rec[(topics.WORLD_FRAME, vid)], atol=1e-9
            )


def test_split_is_refused_and_output_is_deterministic(coop_rec: Path, tmp_path: Path) -> None:
    from mmusv.errors import ConfigError

    with pytest.raises(ConfigError, match="never split"):
        convert(coop_rec, to="ros2", out_dir=tmp_path / "x", splits=(0.5, 0.5, 0.0))
    assert not (tmp_path / "x").exists()
    a, b = tmp_path / "a", tmp_path / "b"
    convert(coop_rec, to="ros2", out_dir=a, splits=None)
    convert(coop_rec, to="ros2", out_dir=b)
    for name in ("metadata.yaml", "export_coop.mcap"):
        assert (a / "export_coop" / name).read_bytes() == (b / "export_coop" / name).read_bytes()


def test_camera_info_carries_the_lens_distortion(
    no_lidar_rec: Path, no_lidar_distortion: list[float], tmp_path: Path
) -> None:
    convert(no_lidar_rec, to="ros2", out_dir=tmp_path / "o")
    with AnyReader([tmp_path / "o" / "export_no_lidar"]) as r:
        infos = [r.deserialize(raw, c.msgtype) for c, _t, raw in r.messages() if c.topic.endswith("/camera_info")]
    assert len(infos) == 2  # two USVs, one camera each, one frame
    for ci in infos:
        assert ci.distortion_model == "plumb_bob"
        np.testing.assert_array_equal(ci.d, no_lidar_distortion)


def test_max_occlusion_and_min_box_px_filter_the_2d_detections(coop_rec: Path, tmp_path: Path) -> None:
    """The export review's: ``Detection2DArray`` holds the boxes of wholly hidden vessels, and ``Detection2D`` has no
    field to say so. ``max_occlusion`` and ``min_box_px`` (COCO's, YOLO's and MOT's filters) now apply here too, on
    the recorded box and occlusion; the default keeps every box, as before."""
    from mmusv.export.ros2_names import detections_2d_topic

    src = recording(coop_rec)
    info = read_info(coop_rec)
    cases = {"all": {}, "filtered": {"max_occlusion": 0.5, "min_box_px": 4.0}}
    kept: dict[str, int] = {}
    for name, options in cases.items():
        out = tmp_path / name
        rep = convert(coop_rec, to="ros2", out_dir=out, **options)  # type: ignore[arg-type]
        got: dict[str, list[Any]] = defaultdict(list)
        with AnyReader([out / "export_coop"]) as r:
            for c, _t, raw in r.messages():
                if c.msgtype == "vision_msgs/msg/Detection2DArray":
                    got[c.topic].append(r.deserialize(raw, c.msgtype))
        occ, px = options.get("max_occlusion", 1.0), options.get("min_box_px", 0.0)
        kept[name] = 0
        for a in info.agents:
            ann = [msg for _t, msg in src[topics.agent_annotations(a.id)]]
            for cam in a.cameras:
                msgs = got[detections_2d_topic(a.id, cam)]
                assert len(msgs) == len(ann) == 3
                for d, frame in zip(msgs, ann, strict=True):
                    want = [
                        b.target_id
                        for b in frame.boxes_camera
                        if b.camera == cam and b.occlusion <= occ and min(b.x_max - b.x_min, b.y_max - b.y_min) >= px
                    ]
                    assert [x.id for x in d.detections] == want
                    kept[name] += len(want)
        notes = " ".join(n for r in rep.recordings for n in r.notes)
        assert ("2D boxes left out of the Detection2DArray" in notes) == (name == "filtered"), notes
    assert 0 < kept["filtered"] < kept["all"], kept
