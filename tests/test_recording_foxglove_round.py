"""The recording as Foxglove's Image and 3D panels read it: each camera's ``foxglove.CameraCalibration`` and its 2D
boxes as ``foxglove.ImageAnnotations`` (both added 2026-12-06; before, the intrinsics were only in the ``sensors``
metadata, so the panels could not project onto the images, and the 2D boxes only in ``mmusv.AgentAnnotations``).

Read with the peers' code only (the ``mcap`` reader, ``mcap-protobuf-support``'s decoder, OpenCV's projection):

* the calibration of every camera, every frame: its frame id is the camera's optical frame in ``/tf``; K is the
  recorded intrinsics in OpenCV's convention (the principal point half a pixel less than mmusv's), D the rig's
  Brown–Conrady distortion as ``plumb_bob``, R = I, P = [K | 0];
* the LiDAR's points of each vessel, taken through ``/tf`` into a camera's optical frame and projected with
  ``cv2.projectPoints`` (K, D of the calibration), land on that vessel's pixels of the camera's instance image
  (most of them: the LiDAR sees some parts the camera does not), with and without lens distortion;
* the image annotations are the camera's 2D boxes of ``mmusv.AgentAnnotations``, one outlined rectangle (a line
  loop through its four corners) and one label each.
"""

from __future__ import annotations

import copy
import io
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory
from scipy.spatial.transform import Rotation

REPO = Path(__file__).resolve().parents[1]
K1 = [-0.12, 0.03, 0.0005, -0.0003, 0.0]


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``port_entry``, 2 frames, small cameras (the front one 4:3 with lens distortion, the left one 16:9), every
    vessel annotated."""
    from mmusv.acquire import run

    sc = yaml.safe_load((REPO / "scenarios/port_entry.yaml").read_text())
    sc["rigs"]["usv_standard"] = {
        "cameras": [
            {
                "name": "front",
                "resolution": [320, 240],
                "hfov_deg": 90.0,
                "quality": "draft",
                "distortion": K1,
                "mount": {"point": "camera_front"},
            },
            {
                "name": "left",
                "resolution": [320, 180],
                "hfov_deg": 90.0,
                "quality": "draft",
                "mount": {"point": "camera_left"},
            },
        ],
        "radar": None,
        "top_view": None,
    }
    out = tmp_path_factory.mktemp("fox")
    path = out / "port.yaml"
    path.write_text(yaml.safe_dump(copy.deepcopy(sc)))
    return Path(run(path, out_dir=out / "run", frames=2).recording)


def _messages(path: Path) -> list[tuple[str, int, Any]]:
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [(c.topic, m.log_time, d) for _s, c, m, d in reader.iter_decoded_messages()]


def _sensors(path: Path) -> dict[str, Any]:
    import json

    with path.open("rb") as f:
        meta = {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}
    return dict(json.loads(meta["sensors"]["json"]))


def _tf(msg: Any) -> dict[tuple[str, str], np.ndarray]:
    out = {}
    for t in msg.transforms:
        m = np.eye(4)
        q = t.rotation
        m[:3, :3] = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix()
        m[:3, 3] = [t.translation.x, t.translation.y, t.translation.z]
        out[(t.parent_frame_id, t.child_frame_id)] = m
    return out


def test_each_camera_has_its_calibration_every_frame(recording: Path) -> None:
    msgs = _messages(recording)
    sensors = _sensors(recording)
    times = sorted({t for _topic, t, _d in msgs})
    assert len(times) == 2
    for agent, s in sensors.items():
        for name, cam in s["cameras"].items():
            topic = f"/{agent}/camera/{name}/calibration"
            got = [(t, d) for tp, t, d in msgs if tp == topic]
            assert [t for t, _d in got] == times, topic
            for t, d in got:
                tf = next(m for tp, tt, m in msgs if tp == "/tf" and tt == t)
                assert (agent, d.frame_id) in _tf(tf) and d.frame_id == f"{agent}/camera/{name}"
                fx, fy, cx, cy = cam["intrinsics"]
                k = [fx, 0, cx - 0.5, 0, fy, cy - 0.5, 0, 0, 1]
                assert list(d.K) == pytest.approx(k, abs=1e-9) and list(d.R) == [1, 0, 0, 0, 1, 0, 0, 0, 1]
                assert list(d.P) == pytest.approx([fx, 0, cx - 0.5, 0, 0, fy, cy - 0.5, 0, 0, 0, 1, 0], abs=1e-9)
                assert (d.width, d.height) == tuple(cam["resolution"]) and d.distortion_model == "plumb_bob"
                assert list(d.D) == pytest.approx(K1 if name == "front" else [0.0] * 5, abs=1e-12)
                assert d.timestamp.seconds * 10**9 + d.timestamp.nanos == t


def test_lidar_points_projected_with_the_calibration_land_on_their_vessels_pixels(recording: Path) -> None:
    import cv2
    from PIL import Image

    msgs = _messages(recording)
    t = min(tt for _tp, tt, _d in msgs)
    frame = {tp: d for tp, tt, d in msgs if tt == t}
    tf = _tf(frame["/tf"])
    checked = 0
    for agent in sorted({tp.split("/")[1] for tp in frame if tp.endswith("/lidar")}):
        cloud = frame[f"/{agent}/lidar"]
        fields = {f.name: f.offset for f in cloud.fields}
        raw = np.frombuffer(cloud.data, dtype=np.uint8).reshape(-1, cloud.point_stride)
        xyz = np.stack([raw[:, fields[k] : fields[k] + 4].copy().view("<f4")[:, 0] for k in "xyz"], axis=1)
        inst = raw[:, fields["instance"] : fields["instance"] + 4].copy().view("<i4")[:, 0]
        lidar = tf[(agent, f"{agent}/lidar")]
        for name in ("front", "left"):
            cal = frame[f"/{agent}/camera/{name}/calibration"]
            cam = tf[(agent, cal.frame_id)]
            to_cam = np.linalg.inv(cam) @ lidar
            p = xyz.astype(np.float64) @ to_cam[:3, :3].T + to_cam[:3, 3]
            ahead = p[:, 2] > 1.0
            k = np.array(cal.K).reshape(3, 3)
            uv, _ = cv2.projectPoints(p[ahead], np.zeros(3), np.zeros(3), k, np.array(cal.D))
            uv = uv.reshape(-1, 2)
            image = np.array(Image.open(io.BytesIO(frame[f"/{agent}/camera/{name}/instance"].data)))
            h, w = image.shape
            # OpenCV's pixel (u, v) has its centre at whole numbers: the pixel holding it is round(u), round(v)
            col, row = np.rint(uv[:, 0]).astype(int), np.rint(uv[:, 1]).astype(int)
            inside = (col >= 2) & (col < w - 2) & (row >= 2) & (row < h - 2)
            ids = inst[ahead][inside]
            seen = image[row[inside], col[inside]].astype(np.int64)
            for vessel in sorted(set(ids[(ids >= 0)].tolist())):
                mine = ids == vessel
                if mine.sum() < 30:
                    continue
                share = float(np.mean(seen[mine] == vessel))
                assert share > 0.7, (agent, name, vessel, share, int(mine.sum()))
                checked += 1
    assert checked >= 3, checked


def test_the_image_annotations_are_the_cameras_2d_boxes(recording: Path) -> None:
    msgs = _messages(recording)
    for t in sorted({tt for _tp, tt, _d in msgs}):
        frame = {tp: d for tp, tt, d in msgs if tt == t}
        for topic, ann in frame.items():
            if not topic.endswith("/annotations"):
                continue
            agent = topic.split("/")[1]
            for name in ("front", "left"):
                want = sorted(
                    (b.target_id, round(b.x_min, 6), round(b.y_min, 6), round(b.x_max, 6), round(b.y_max, 6))
                    for b in ann.boxes_camera
                    if b.camera == name
                )
                boxes = frame[f"/{agent}/camera/{name}/boxes"]
                got = []
                for loop, text in zip(boxes.points, boxes.texts, strict=True):
                    assert loop.type == 2 and len(loop.points) == 4  # LINE_LOOP
                    xs, ys = [p.x for p in loop.points], [p.y for p in loop.points]
                    assert (text.position.x, text.position.y) == (min(xs), min(ys))
                    got.append((text.text, *(round(v, 6) for v in (min(xs), min(ys), max(xs), max(ys)))))
                assert sorted(got) == want and len(want) == len(boxes.points), (agent, name)


def test_preview_keeps_a_cameras_aspect_ratio(recording: Path) -> None:
    """``mmusv preview`` drew every camera panel 320 × 240: a 16:9 camera came out a third taller than it is (its
    boxes placed with two scales). Its panels now keep the image's aspect ratio (320 × 180 here, one scale), a 4:3
    one's as before."""
    from mmusv.preview import compose_preview

    _, panels = compose_preview(recording, frame=0, agent="usv_1")
    for cam, (w, h) in (("left", (320, 180)), ("front", (320, 240))):
        mine = [p for p in panels if f" · {cam} camera · " in p.title]
        assert len(mine) == 3, [p.title for p in panels]
        for p in mine:
            left, top, right, bottom = p.box
            assert (right - left, bottom - top) == (w, h) and p.scale == pytest.approx(1.0), (p.title, p.box)
