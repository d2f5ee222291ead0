"""Conventions of the ROS 2, OPV2V, OpenCOOD, KITTI oxts and PCD exports checked against what their peers' code does
with each field (a second round of ``test_exports_round.py``'s kind of checks)."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path
from typing import Any

import pytest
from mmusv.export import convert
from mmusv.recording import read_messages, topics

# ------------------------------------------------------------------------------------------ ROS 2: time zero


def _stamps(msg: Any) -> list[int]:
    """Every ``builtin_interfaces/Time`` of a decoded message that stamps it (headers, transforms, the clock), ns."""
    out = []
    if hasattr(msg, "header"):
        out.append(msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec)
    if hasattr(msg, "clock"):
        out.append(msg.clock.sec * 10**9 + msg.clock.nanosec)
    for name in ("transforms", "detections", "markers"):
        for x in getattr(msg, name, []):
            out += _stamps(x)
    return out


def test_ros2_no_stamp_is_time_zero_and_stamps_keep_the_sim_time_steps(coop_rec: Path, tmp_path: Path) -> None:
    """tf2 reads a stamp of 0 as "the latest transform" (``TimeCache::findClosest``: "If time == 0 return the
    latest"), and rclcpp's clock is not ``started()`` at 0: a first frame stamped at sim time 0 would be placed with
    whatever transform is newest in the buffer, and its ``/clock`` means "no time yet". Every stamp and log time is
    the sim time plus :data:`~mmusv.export.ros2.TIME_OFFSET_NS` (> 0), the same offset for every frame, named in
    ``metadata.yaml``'s ``custom_data``."""
    import yaml
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from mmusv.export.ros2 import TIME_OFFSET_NS

    convert(coop_rec, to="ros2", out_dir=tmp_path / "o")
    bag = tmp_path / "o" / "export_coop"
    src = sorted({t for _topic, t, _m in read_messages(coop_rec, [topics.WORLD_STATE])})
    assert src[0] == 0  # the recording's own time starts at 0
    by_topic: dict[str, list[int]] = defaultdict(list)
    with (bag / "export_coop.mcap").open("rb") as f:
        for _s, ch, m, dec in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            stamps = _stamps(dec)
            assert m.log_time > 0 and all(s > 0 for s in stamps), ch.topic
            if ch.topic != "/tf_static":
                assert set(stamps) <= {m.log_time}, ch.topic
            by_topic[ch.topic].append(m.log_time)
    assert TIME_OFFSET_NS > 0
    assert by_topic["/clock"] == [t + TIME_OFFSET_NS for t in src]
    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["starting_time"]["nanoseconds_since_epoch"] == TIME_OFFSET_NS
    assert int(meta["custom_data"]["mmusv.time_offset_ns"]) == TIME_OFFSET_NS
    assert meta["custom_data"]["mmusv.status"] == "complete"


@pytest.mark.parametrize("start", [0, 1])
def test_ros2_time_base_does_not_depend_on_the_frames_converted(coop_rec: Path, tmp_path: Path, start: int) -> None:
    """``--frames 1:`` stamps frame 1 as the whole conversion does: the offset is a constant, not "the first frame"."""
    from mcap.reader import make_reader
    from mmusv.export.ros2 import TIME_OFFSET_NS

    convert(coop_rec, to="ros2", out_dir=tmp_path / "o", frames=(start, None))
    src = sorted({t for _topic, t, _m in read_messages(coop_rec, [topics.WORLD_STATE])})[start:]
    with (tmp_path / "o" / "export_coop" / "export_coop.mcap").open("rb") as f:
        clock = [m.log_time for _s, ch, m in make_reader(f).iter_messages() if ch.topic == "/clock"]
    assert clock == [t + TIME_OFFSET_NS for t in src]


# ------------------------------------------------------------------------------------------ OPV2V: depth for HEAL


def test_opv2v_depth_png_is_read_as_metres_by_heals_loader(coop_rec: Path, tmp_path: Path) -> None:
    """HEAL (``yifanlu0227/HEAL``) reads ``<ts>_depth{i}.png`` with ``PIL.Image.open`` and takes
    ``torchvision.transforms.ToTensor()(img) * 255`` as the depth in metres (its LSS encoders bin that tensor with
    ``ddiscr`` in metres). ``ToTensor`` divides only an 8-bit image by 255: a uint16 PNG (PIL mode ``I;16``) comes back
    as int16 counts, which ``* 255`` overflows, so the centimetre PNG once written under this name was read as garbage.
    The file is now 8-bit whole metres (no hit and 254.5 m or farther: 255, HEAL's farthest bin after its clamp), and
    the centimetres stay available as ``<ts>_depth_cm{i}.png`` (uint16, 0 = no hit, 65535 = saturated)."""
    import numpy as np
    import yaml
    from mmusv.export.opv2v import OPV2V_CAMERAS
    from mmusv.recording import decode_image
    from PIL import Image

    torchvision = pytest.importorskip("torchvision")
    convert(coop_rec, to="opv2v", out_dir=tmp_path / "o", splits=None, extras=("depth",))
    out = tmp_path / "o" / "export_coop"
    protocol = yaml.safe_load((out / "data_protocol.yaml").read_text())["mmusv"]
    frame_times = sorted({t for _topic, t, _m in read_messages(coop_rec, [topics.WORLD_STATE])})
    to_tensor = torchvision.transforms.ToTensor()
    checked = sky = 0
    for cav, agent in protocol["cavs"].items():
        depth_topics = {
            topics.camera(agent, name, kind="depth"): idx for name, idx in OPV2V_CAMERAS.items() if name != "back"
        }
        for topic, t, msg in read_messages(coop_rec, list(depth_topics)):
            idx = depth_topics[topic]
            ts = f"{frame_times.index(t):06d}"
            d = np.asarray(decode_image(msg), dtype=np.float64)
            hit = np.isfinite(d) & (d > 0)
            with Image.open(out / str(cav) / f"{ts}_depth{idx}.png") as img:
                assert img.mode == "L"
                heal_m = (to_tensor(img) * 255).numpy()[0]  # HEAL's depth channel
            want = np.where(hit, np.minimum(np.rint(np.where(hit, d, 0.0)), 255.0), 255.0)
            np.testing.assert_array_equal(heal_m, want)
            assert np.all(np.abs(heal_m[hit & (d < 254.5)] - d[hit & (d < 254.5)]) <= 0.5)
            with Image.open(out / str(cav) / f"{ts}_depth_cm{idx}.png") as img:
                assert img.mode in ("I;16", "I")  # 16-bit grayscale (older Pillow opens it as "I")
                cm = np.asarray(img).astype(np.int64)
            np.testing.assert_array_equal(cm[~hit], 0)
            np.testing.assert_array_equal(cm[hit], np.clip(np.rint(d[hit] * 100), 1, 65535))
            checked += 1
            sky += int((~hit).sum())
    assert checked > 0 and sky > 0  # the rig's cameras see sky: the no-hit value is exercised
    assert protocol["depth_png"]["file"] == "<ts>_depth{i}.png" and protocol["depth_png"]["unit_m"] == 1.0
    assert protocol["depth_cm_png"]["file"] == "<ts>_depth_cm{i}.png" and protocol["depth_cm_png"]["unit_m"] == 0.01
