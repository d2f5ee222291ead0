"""A user's round through ``mmusv convert``: exports read back with the peers' own readers (mcap-ros2-support for the
bags, PyYAML and the file tree for MaSTr) and checked against what the recording itself says (its world state),
not against the writers' code.

* a USV without a LiDAR: its ROS 2 boxes must sit in a frame the bag's TF tree holds, where the world state puts them;
* vessel and camera names that are valid in mmusv but not in ROS 2 (``usv-a``, ``2b``, ``front-wide``): the bag's
  topics must be valid ROS 2 names (``ros2 bag play`` refuses the others), and names that would meet are refused;
* ``mastr.yaml`` names the layout actually written, with and without a split.
"""

from __future__ import annotations

import re
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from mmusv.errors import ConfigError
from mmusv.export import convert
from mmusv.export.ros2 import TIME_OFFSET_NS
from mmusv.recording import decode_point_cloud, read_messages, topics
from mmusv.recording.decode import WorldFrame
from scipy.spatial.transform import Rotation


def _matrix(tr: Any) -> np.ndarray:
    m = np.eye(4)
    q = tr.rotation
    m[:3, :3] = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix()
    m[:3, 3] = [tr.translation.x, tr.translation.y, tr.translation.z]
    return m


def _bag_messages(bag: Path) -> dict[str, list[tuple[int, Any]]]:
    """Every message of the bag by topic, ``(log time, message)``, decoded by mcap-ros2-support from the bag's own
    schemas."""
    out: dict[str, list[tuple[int, Any]]] = defaultdict(list)
    with next(bag.glob("*.mcap")).open("rb") as f:
        for _s, ch, m, msg in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            out[ch.topic].append((m.log_time, msg))
    return out


def _world_states(rec: Path) -> dict[int, WorldFrame]:
    return {t: WorldFrame.from_message(msg) for _, t, msg in read_messages(rec, [topics.WORLD_STATE])}


# ------------------------------------------------------------------------------------------ ROS 2: no LiDAR


def test_ros2_boxes_of_a_usv_without_lidar_are_in_its_tf_tree(no_lidar_rec: Path, tmp_path: Path) -> None:
    """The recorded 3D boxes of a USV without a LiDAR are in its hull frame (mmusv.annotate); the bag must put them
    in a frame its TF tree holds (RViz drops a marker whose frame is unknown), at the world state's box centres."""
    convert(no_lidar_rec, to="ros2", out_dir=tmp_path / "o")
    msgs = _bag_messages(tmp_path / "o" / "export_no_lidar")
    static = {
        x.child_frame_id: (x.header.frame_id, _matrix(x.transform))
        for t, msg in msgs["/tf_static"]
        for x in msg.transforms
    }
    dynamic = {
        t: {x.child_frame_id: (x.header.frame_id, _matrix(x.transform)) for x in msg.transforms}
        for t, msg in msgs["/tf"]
    }
    worlds = _world_states(no_lidar_rec)

    def in_map(frame: str, t: int) -> np.ndarray:
        edges = {**static, **dynamic[t]}
        m = np.eye(4)
        while frame != "map":
            assert frame in edges, f"frame {frame!r} is not in the bag's TF tree ({sorted(edges)})"
            parent, tr = edges[frame]
            m, frame = tr @ m, parent
        return m

    checked = 0
    for agent in ("usv_a", "usv_b"):
        for t, msg in msgs[f"/{agent}/detections"]:
            w = worlds[t - TIME_OFFSET_NS]  # the bag's time is the sim time + TIME_OFFSET_NS
            for det in msg.detections:
                assert det.header.frame_id == msg.header.frame_id
                to_map = in_map(det.header.frame_id, t)
                p = det.bbox.center.position
                centre = (to_map @ [p.x, p.y, p.z, 1.0])[:3]
                np.testing.assert_allclose(centre, w.box_centers[w.ids.index(det.id)], atol=1e-6)
                checked += 1
        for t, msg in msgs[f"/{agent}/boxes"]:
            for mk in msg.markers:
                in_map(mk.header.frame_id, t)
    assert checked >= 4  # both USVs see the tug and the speedboat


# ------------------------------------------------------------------------------------------ ROS 2: names

# rmw_validate_full_topic_name / rcl_validate_topic_name: absolute, tokens of alphanumerics and '_' that do not
# start with a digit, no empty token, no trailing '/'.
_ROS_TOPIC = re.compile(r"(/[A-Za-z_][A-Za-z0-9_]*)+")


def _renamed_rec(cfg: dict[str, Any], root: Path, usv_ids: tuple[str, str], camera: str) -> Path:
    """``cfg`` (conftest's ``coop``) for 1 frame, its USVs renamed ``usv_ids``, one 32 × 24 camera ``camera``."""
    from mmusv.acquire import run

    rig = cfg["rigs"]["r"]
    rig.update(radar=None, top_view=None, cameras=[{**rig["cameras"][0], "name": camera, "resolution": [32, 24]}])
    cfg["acquisition"] = {"frequency_hz": 5, "frames": 1}
    cfg["vessels"][0]["id"], cfg["vessels"][2]["id"] = usv_ids
    return Path(run(cfg, out_dir=root).recording)


def test_ros2_topic_names_are_valid_ros2_names(make_coop: Callable[..., dict[str, Any]], tmp_path: Path) -> None:
    # valid mmusv names that are not ROS 2 name tokens
    odd_names_rec = _renamed_rec(make_coop(name="export_odd_names"), tmp_path / "r", ("usv-a", "2b"), "front-wide")
    rep = convert(odd_names_rec, to="ros2", out_dir=tmp_path / "o")
    bag = tmp_path / "o" / "export_odd_names"
    msgs = _bag_messages(bag)
    bad = sorted(t for t in msgs if not _ROS_TOPIC.fullmatch(t))
    assert not bad, f"topics ros2 bag play cannot publish: {bad}"
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert all(_ROS_TOPIC.fullmatch(t["topic_metadata"]["name"]) for t in meta["topics_with_message_count"])
    # the data are still there, under the ROS names (each odd character an '_', a leading digit after an '_'), in
    # frames that keep the vessel and camera ids
    rec = {t: msg for t, _, msg in read_messages(odd_names_rec)}
    for agent, ros in (("usv-a", "usv_a"), ("2b", "_2b")):
        cloud = msgs[f"/{ros}/lidar"][0][1]
        assert cloud.header.frame_id == f"{agent}/lidar"
        assert cloud.width == len(decode_point_cloud(rec[topics.lidar(agent)])["x"]) > 0
        info = msgs[f"/{ros}/camera/front_wide/camera_info"][0][1]
        assert info.header.frame_id == f"{agent}/camera_front-wide_optical" and (info.width, info.height) == (32, 24)
        assert f"/{ros}/camera/front_wide/rgb/compressed" in msgs and f"/{ros}/odom" in msgs
    assert any("usv-a" in n and "usv_a" in n for r in rep.recordings for n in r.notes)  # the renaming is said


def test_ros2_names_that_would_meet_are_refused(make_coop: Callable[..., dict[str, Any]], tmp_path: Path) -> None:
    rec = _renamed_rec(make_coop(name="export_clash"), tmp_path / "r", ("usv-a", "usv_a"), "front")
    with pytest.raises(ConfigError, match=r"usv-a.*usv_a|usv_a.*usv-a"):
        convert(rec, to="ros2", out_dir=tmp_path / "o")
    assert not (tmp_path / "o").exists()


# ------------------------------------------------------------------------------------------ MaSTr


@pytest.mark.parametrize("splits", [None, (1, 0, 0)], ids=["no-split", "split"])
def test_mastr_yaml_names_the_layout_written(no_lidar_rec: Path, tmp_path: Path, splits: Any) -> None:
    out = tmp_path / "o"
    convert(no_lidar_rec, to="mastr", out_dir=out, splits=splits)
    doc = yaml.safe_load((out / "mastr.yaml").read_text())
    written = {p.relative_to(out).as_posix() for p in out.rglob("*.png")}
    named = set()
    for key in ("images", "masks"):  # the one camera (front) of both USVs, frame 0, the one split "train"
        for agent in ("usv_a", "usv_b"):
            values = {"<split>": "train", "<scenario>": "export_no_lidar", "<agent>": agent, "<camera>": "front"}
            path = doc[key]
            for k, v in {**values, "<frame>": "000000"}.items():
                path = path.replace(k, v)
            named.add(path)
    assert named == written
