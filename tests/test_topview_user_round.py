"""The top view (orthographic camera) and the BEV ground truth as a BEV-perception / segmentation researcher meets
them (a helper's round): each check against an independent computation written out here (``mcap`` and
``mcap_protobuf`` to read the recording, PIL for the PNGs, the projection and the footprints by hand).

* Geometry: pixel ``(u, v)``'s centre is ``(u + 0.5 − W/2, v + 0.5 − H/2) · metres_per_pixel`` in the recorded
  ``world → <usv>/top_view`` optical frame (a non-square 200 × 150 image at 0.4 m and a 150 × 200 one at 0.5 m,
  heading-up and north-up, W2 waves): image up is the bow (heading-up) or north, image right starboard or east (not
  mirrored), the camera ``altitude_m`` over the USV's origin. Each vessel's instance pixels, put back in the world,
  lie on its recorded box's footprint within 0.3 m (measured ≤ 0.22 m at W3: the hulls' roll and pitch) and cover
  ≥ 75 % of it (measured 80–100 %; a WAM-V, two hulls and open deck, 45–55 %), semantic class 10 (vessel) or 11
  (USV). A 120 m cargo ship cut by the image border is seen on its part inside.
* BEV boxes: ``boxes_bev`` = the 3D box's centre ``x, y``, ``size[0:2]`` and yaw (``atan2(R[1, 0], R[0, 0])`` of the
  box in the LiDAR frame, which equals ``Box3D.yaw``); mapped through the recorded ``/tf`` (with the 3D centre's z)
  they land on the world state's box of the same vessel (0 m, 0°) from either USV. The LiDAR frame pitches and
  rolls with the hull: ``(x, y, 0)`` or a level 2D pose is 0.1–0.7 m and up to 0.5° off at 30–60 m at W3
  (``docs/recording.md`` now says so and which frame, axis and range the BEV yaw has).
* A top view over an island (island map seed 4, 2 m per pixel): terrain and vegetation pixels are where the map's
  heightfield is above the water (99.7 % of the pixels agree; the others within 0.3 m of the waterline).
* A top view lower than the land it sees (5 m up beside an islet that rises to 28.9 m) drew that land as water:
  1354 pixels of semantic 1 and the sea's instance where the ground stands above the camera, the terrain being a
  surface seen from above. ``mmusv run`` now refuses it (``mmusv.scenario_checks.check_top_view_land``, skipped by
  ``--no-checks`` with the other map checks) and the scenario editor lists it as an error (check ``top_view``).
* A vessel taller than the top view (a 67 m cruise ship beside a top view at 20 m): the camera sits inside it, its
  rays start there and meet its decks below (depth 0 to 6 m); the ship's footprint is still all its instance, so
  the segmentation stays right; ``TopViewConfig`` now says so. The USV's own hull taller than the top view is
  refused (``tests/test_run_fuzz_round14.py``).
* The exports: OPV2V's ``<ts>_topview_{rgb,semantic}.png`` and KITTI's ``top_view_{rgb,semantic}`` carried nothing
  to place them: no scale, size, orientation or centre anywhere in the export (``data_protocol.yaml``,
  ``mmusv_kitti.yaml``), so a BEV label could not be matched to the labelled boxes. Both now give each agent's top
  view (``top_views`` by ``cav_id``) and the pixel mapping in their frames (``top_view_png``); read with yaml and
  PIL, the listed vehicles' footprints land on the vessel pixels. The ROS 2 bag placed its top view by ``/tf``
  (``map → <usv>/top_view_optical``) but, an orthographic camera having no ``CameraInfo``, gave its metres per pixel
  nowhere; ``metadata.yaml``'s ``custom_data`` now has ``mmusv.top_view.<usv>``, and read with ``mcap_ros2`` the
  ``/<usv>/detections`` boxes, through ``/tf`` and ``/tf_static``, land on the ``16UC1`` semantic image's vessels.
  KITTI tracking's ``top_view_*`` images came without it too (that export writes no ``mmusv_kitti.yaml``): its
  root now has ``top_views.yaml``, by ``<split>/<seq>``, with the mapping from ``pose/<seq>.txt`` and ``Tr_imu_velo``.
* ``mmusv preview`` resized a portrait or landscape top view to a square panel (150 × 200: 2.84 panel pixels per
  source pixel across, 2.13 down), so its hulls were a third wider than long; it now keeps one scale both ways.
* Bad top-view values in a scenario file name the file, the field and what it may be; the same seed gives the same
  bytes; the quality changes the RGB only (the labels and depth are the same at draft, standard and high).

Checked outside the tests (one-off scripts, same independent maths): on ``port_entry`` at W3 the moored ships' BEV
boxes map onto their world-state boxes (6e-14 m, 0°; ``static`` true, role ``moored``) and their top-view pixels stay
within 0.65 m of the upright footprint (an 85 m supply vessel 40.5 m tall rolled 3.3°); the set of vessels given
boxes is exactly those whose BEV rectangle comes within 200 m of the LiDAR (shapely's distance; 208.9 m and 219.2 m
left out); an odd 201 × 151 top view at 0.37 m maps the same way (pixels ≤ 0.065 m off the footprints); every
library ship above 15 m (23 assets) keeps the same top-view footprint cover (0.90–1.00) with the top view at 0.5 and
0.8 of its height as from 120 m; top-view depth is the altitude less the surface height, within each box's z range;
the detection study's BEV IoU matches a Monte Carlo IoU of random rotated boxes within 0.011 (the sampling's error).
"""

from __future__ import annotations

import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from kitti_files import label_corners, read_calib
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory
from mmusv import ConfigError, Simulation
from mmusv.acquire import run
from mmusv.config import load_scenario
from mmusv.export import convert
from PIL import Image
from scipy.spatial.transform import Rotation

SCENARIO: dict[str, Any] = {
    "name": "tv_round",
    "seed": 11,
    "map": {"type": "open_sea", "seed": 0},
    "environment": {"wave": "W2"},
    "acquisition": {"frequency_hz": 5, "frames": 1},
    "rigs": {
        "a": {
            "cameras": [],
            "radar": None,
            "lidar": {"channels": 16, "points_per_second": 20000},
            "top_view": {"resolution": [200, 150], "metres_per_pixel": 0.4, "quality": "draft"},
        },
        "b": {
            "cameras": [],
            "radar": None,
            "lidar": {"channels": 16, "points_per_second": 20000},
            "top_view": {
                "resolution": [150, 200],
                "metres_per_pixel": 0.5,
                "orientation": "north_up",
                "quality": "draft",
            },
        },
    },
    "vessels": [
        {
            "id": "u",
            "role": "usv",
            "asset": "usv_patrol_12m",
            "rig": "a",
            "speed_mps": 2.0,
            "route": [[0, 0], [60, 35]],
        },
        {"id": "v", "role": "usv", "asset": "usv_wamv", "rig": "b", "speed_mps": 2.0, "route": [[20, -15], [80, -40]]},
        {"id": "fish", "role": "target", "asset": "fishing_boat_12m", "speed_mps": 0.0, "route": [[28, 10], [43, 18]]},
        {
            "id": "yacht",
            "role": "target",
            "asset": "motor_yacht_20m",
            "speed_mps": 3.0,
            "route": [[-10, -28], [-60, -28]],
        },
        {
            "id": "cargo",
            "role": "target",
            "asset": "general_cargo_120m",
            "speed_mps": 1.0,
            "route": [[-22.7, 38.9], [60, 87.2]],
        },
    ],
}
SPILL_M = 0.3
"""How far a hull's pixels may reach out of its box's upright footprint: the hull rolls and pitches in the waves."""


@pytest.fixture(scope="module")
def rec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("tv")
    return Path(run(SCENARIO, out_dir=out / "rec").recording)


def _matrix(t: Any, q: Any) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix()
    m[:3, 3] = [t.x, t.y, t.z]
    return m


def _png(data: bytes) -> np.ndarray:
    with Image.open(io.BytesIO(data)) as img:
        return np.asarray(img)


def _read(path: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    """The ``sensors`` metadata and the messages of the (one) frame, decoded by ``mcap_protobuf``."""
    msgs: dict[str, Any] = {}
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
        for _, channel, _, decoded in reader.iter_decoded_messages():
            msgs[channel.topic] = decoded
    return json.loads(meta["sensors"]["json"]), msgs


def _footprint_distance(xy: np.ndarray, centre: np.ndarray, yaw: float, length: float, beam: float) -> np.ndarray:
    """How far each point ``xy`` ``(N, 2)`` lies outside the rectangle ``length`` × ``beam`` at ``centre`` turned by
    ``yaw`` (negative inside: the distance in to its nearer edge along the box's axes)."""
    d = xy - centre
    along = math.cos(yaw) * d[:, 0] + math.sin(yaw) * d[:, 1]
    across = -math.sin(yaw) * d[:, 0] + math.cos(yaw) * d[:, 1]
    out: np.ndarray = np.maximum(np.abs(along) - length / 2, np.abs(across) - beam / 2)
    return out


# ---------------------------------------------------------------------------------------- the recorded top view


def test_recorded_top_view_pixels_map_onto_the_vessels_boxes(rec: Path) -> None:
    sensors, msgs = _read(rec)
    tf = {(t.parent_frame_id, t.child_frame_id): _matrix(t.translation, t.rotation) for t in msgs["/tf"].transforms}
    vessels = msgs["/world/state"].vessels
    checked = 0
    for agent, info in sensors.items():
        tv = info["rig"]["top_view"]
        m, (w, h) = tv["metres_per_pixel"], tv["resolution"]
        cam = tf[("world", f"{agent}/top_view")]
        me = next(v for v in vessels if v.id == agent)
        # Centred over the USV's origin at altitude_m, level; image up = the bow or north, right = starboard or east.
        np.testing.assert_allclose(cam[:3, 3], [me.pose[0], me.pose[1], tv["altitude_m"]], atol=1e-6)
        up_angle = me.pose[5] if tv["orientation"] == "heading_up" else math.pi / 2
        up = np.array([math.cos(up_angle), math.sin(up_angle), 0.0])
        np.testing.assert_allclose(cam[:3, :3] @ [0.0, -1.0, 0.0], up, atol=1e-9)
        np.testing.assert_allclose(cam[:3, :3] @ [1.0, 0.0, 0.0], [up[1], -up[0], 0.0], atol=1e-9)
        np.testing.assert_allclose(cam[:3, :3] @ [0.0, 0.0, 1.0], [0.0, 0.0, -1.0], atol=1e-9)
        inst = _png(msgs[f"/{agent}/top_view/instance"].data).astype(np.int64)
        sem = _png(msgs[f"/{agent}/top_view/semantic"].data)
        assert inst.shape == sem.shape == (h, w)
        vv, uu = np.mgrid[0:h, 0:w]
        optical = np.stack([(uu + 0.5 - w / 2) * m, (vv + 0.5 - h / 2) * m, np.zeros((h, w))], -1).reshape(-1, 3)
        xy = (optical @ cam[:3, :3].T + cam[:3, 3])[:, :2]
        for v in vessels:
            mask = inst.ravel() == v.instance_id
            out = _footprint_distance(xy, np.array(v.box_center[:2]), v.pose[5], v.box_size[0], v.box_size[1])
            inside = out <= 0.0
            if not inside.any():
                assert not mask.any(), f"{agent} sees {v.id} off its footprint"
                continue
            assert out[mask].max() <= SPILL_M, (agent, v.id, float(out[mask].max()))
            cover = float((mask & inside).sum() / inside.sum())
            assert cover >= (0.4 if v.asset == "usv_wamv" else 0.75), (agent, v.id, cover)
            assert set(np.unique(sem.ravel()[mask])) == {11 if v.role == "usv" else 10}, (agent, v.id)
            checked += 1
        if agent == "u":  # the cargo ship is cut by the left border of u's picture
            cargo = next(v for v in vessels if v.id == "cargo")
            on = inst == cargo.instance_id
            assert on.any() and on[:, 0].any(), "the cargo ship reaches out of the left border"
    assert checked >= 8, checked


def test_bev_boxes_are_the_3d_boxes_footprints_in_the_lidar_frame(rec: Path) -> None:
    sensors, msgs = _read(rec)
    tf = {(t.parent_frame_id, t.child_frame_id): _matrix(t.translation, t.rotation) for t in msgs["/tf"].transforms}
    vessels = {v.id: v for v in msgs["/world/state"].vessels}
    worst_level = 0.0
    for agent in sensors:
        lidar = tf[("world", agent)] @ tf[(agent, f"{agent}/lidar")]
        ann = msgs[f"/{agent}/annotations"]
        assert [b.target_id for b in ann.boxes_bev] == [b.target_id for b in ann.boxes_lidar]
        assert {b.target_id for b in ann.boxes_bev} == set(vessels) - {agent}
        for b3, bev in zip(ann.boxes_lidar, ann.boxes_bev, strict=True):
            rot = Rotation.from_quat(list(b3.rotation)).as_matrix()
            assert (bev.x, bev.y) == (b3.center[0], b3.center[1])
            assert (bev.length, bev.width) == (b3.size[0], b3.size[1])
            assert bev.yaw == pytest.approx(math.atan2(rot[1, 0], rot[0, 0]), abs=1e-12) == b3.yaw
            assert -math.pi <= bev.yaw <= math.pi
            # Through the recorded poses, with the 3D centre's z: the world state's box, from either USV.
            v = vessels[bev.target_id]
            world = lidar @ np.array([bev.x, bev.y, b3.center[2], 1.0])
            np.testing.assert_allclose(world[:3], v.box_center, atol=1e-6)
            box_x = lidar[:3, :3] @ rot[:, 0]
            yaw = math.atan2(box_x[1], box_x[0])
            assert abs(math.remainder(yaw - v.pose[5], 2 * math.pi)) < 1e-6
            # A level 2D pose of the LiDAR and (x, y) alone: off by the hull's roll and pitch.
            lyaw = math.atan2(lidar[1, 0], lidar[0, 0])
            level = lidar[:2, 3] + [
                math.cos(lyaw) * bev.x - math.sin(lyaw) * bev.y,
                math.sin(lyaw) * bev.x + math.cos(lyaw) * bev.y,
            ]
            worst_level = max(worst_level, float(np.hypot(*(level - np.array(v.box_center[:2])))))
    assert 0.01 < worst_level < 2.0, worst_level


# ------------------------------------------------------------------------------------------------- the exports


def _carla_footprints(doc: dict[str, Any]) -> list[tuple[np.ndarray, float, float, float]]:
    """Each listed vehicle's footprint in the CARLA world (x, y metres): centre, yaw (rad), length, width."""
    out = []
    for veh in doc["vehicles"].values():
        centre = np.add(veh["location"], veh["center"])[:2]
        out.append((centre, math.radians(veh["angle"][1]), 2 * veh["extent"][0], 2 * veh["extent"][1]))
    return out


def _check_semantic(sem: np.ndarray, xy: np.ndarray, boxes: list[tuple[np.ndarray, float, float, float]]) -> int:
    """Each box's footprint pixels are vessel pixels (class 10) for the most part, and every vessel pixel lies on
    some box (the export lists the targets, not the USVs: class 11 is left out)."""
    vessel = sem.ravel() == 10
    near = np.zeros(len(xy), dtype=bool)
    seen = 0
    for centre, yaw, length, width in boxes:
        out = _footprint_distance(xy, centre, yaw, length, width)
        inside = out <= 0.0
        near |= out <= SPILL_M
        if inside.any():
            assert (vessel & inside).sum() / inside.sum() >= 0.75, (centre, yaw)
            seen += 1
    assert not (vessel & ~near).any(), int((vessel & ~near).sum())
    return seen


def test_opv2v_top_view_says_where_its_pixels_are(rec: Path, tmp_path: Path) -> None:
    out = tmp_path / "opv2v"
    convert(rec, to="opv2v", out_dir=out, splits=None, extras=("top_view",))
    scen = out / SCENARIO["name"]
    protocol = yaml.safe_load((scen / "data_protocol.yaml").read_text())["mmusv"]
    assert "top_views" in protocol, "data_protocol.yaml says nothing of the top views' scale and orientation"
    assert "top_view_png" in protocol and "pixel" in protocol["top_view_png"]
    seen = 0
    for cav, tv in protocol["top_views"].items():
        m, (w, h) = tv["metres_per_pixel"], tv["resolution"]
        doc = yaml.safe_load((scen / str(cav) / "000000.yaml").read_text())
        sem = _png((scen / str(cav) / "000000_topview_semantic.png").read_bytes())
        assert sem.shape == (h, w)
        # The documented mapping, in the CARLA frame (x forward or east, y starboard or south).
        x0, y0, yaw = doc["true_ego_pos"][0], doc["true_ego_pos"][1], math.radians(doc["true_ego_pos"][4])
        vv, uu = np.mgrid[0:h, 0:w]
        right, ahead = ((uu + 0.5 - w / 2) * m).ravel(), ((h / 2 - vv - 0.5) * m).ravel()
        if tv["orientation"] == "heading_up":
            xy = np.stack(
                [
                    x0 + ahead * math.cos(yaw) - right * math.sin(yaw),
                    y0 + ahead * math.sin(yaw) + right * math.cos(yaw),
                ],
                1,
            )
        else:
            xy = np.stack([x0 + right, y0 - ahead], 1)
        seen += _check_semantic(sem, xy, _carla_footprints(doc))
    assert seen >= 5, seen


def test_kitti_top_view_says_where_its_pixels_are(rec: Path, tmp_path: Path) -> None:
    out = tmp_path / "kitti"
    convert(rec, to="kitti", out_dir=out, splits=None, extras=("top_view",))
    scen = out / SCENARIO["name"]
    meta = yaml.safe_load((scen / "mmusv_kitti.yaml").read_text())
    assert "top_views" in meta, "mmusv_kitti.yaml says nothing of the top views' scale and orientation"
    assert "top_view_png" in meta and "pixel" in meta["top_view_png"]
    seen = 0
    for cav, tv in meta["top_views"].items():
        m, (w, h) = tv["metres_per_pixel"], tv["resolution"]
        folder = scen / str(cav)
        calib = read_calib(folder / "calib" / "000000.txt")
        pose = np.vstack([np.loadtxt(folder / "pose" / "000000.txt").reshape(3, 4), [0, 0, 0, 1]])
        imu_to_velo = np.vstack([calib["Tr_imu_to_velo"].reshape(3, 4), [0, 0, 0, 1]])
        velo_to_cam = np.vstack([calib["Tr_velo_to_cam"].reshape(3, 4), [0, 0, 0, 1]])
        body = pose @ imu_to_velo
        x0, y0, yaw = body[0, 3], body[1, 3], math.atan2(body[1, 0], body[0, 0])
        sem = _png((folder / "top_view_semantic" / "000000.png").read_bytes())
        assert sem.shape == (h, w)
        vv, uu = np.mgrid[0:h, 0:w]
        left, ahead = ((w / 2 - uu - 0.5) * m).ravel(), ((h / 2 - vv - 0.5) * m).ravel()
        if tv["orientation"] == "heading_up":
            xy = np.stack(
                [x0 + ahead * math.cos(yaw) - left * math.sin(yaw), y0 + ahead * math.sin(yaw) + left * math.cos(yaw)],
                1,
            )
        else:
            xy = np.stack([x0 - left, y0 + ahead], 1)
        boxes = []
        for line in (folder / "label_2" / "000000.txt").read_text().splitlines():
            fields = line.split()
            if fields[0] == "DontCare":
                continue
            cam = label_corners(fields)
            world = (np.c_[cam, np.ones(8)] @ np.linalg.inv(velo_to_cam).T) @ pose.T
            # The box's centre and the direction of its length (label_corners: x ± l/2 on corners 0 and 3); the
            # label's box is upright in the LiDAR frame, which tilts with the hull: not its bottom face alone.
            side = world[0, :2] - world[3, :2]
            boxes.append((world[:, :2].mean(axis=0), math.atan2(side[1], side[0]), float(fields[10]), float(fields[9])))
        seen += _check_semantic(sem, xy, boxes)
    assert seen >= 5, seen


def test_kitti_tracking_top_view_says_where_its_pixels_are(rec: Path, tmp_path: Path) -> None:
    out = tmp_path / "tracking"
    convert(rec, to="kitti_tracking", out_dir=out, splits=None, extras=("top_view",))
    assert (out / "top_views.yaml").is_file(), "the tracking export says nothing of the top views' scale"
    meta = yaml.safe_load((out / "top_views.yaml").read_text())
    assert "pose/<seq>.txt" in meta["top_view_png"]["pixel"]
    sequences = {row.split(",")[1]: row.split(",") for row in (out / "sequences.csv").read_text().splitlines()[1:]}
    assert set(meta["top_views"]) == {f"train/{seq}" for seq in sequences}
    _, msgs = _read(rec)  # the world state's boxes: the tracking labels are the KITTI export's, checked above
    boxes = [
        (np.array(v.box_center[:2]), v.pose[5], v.box_size[0], v.box_size[1])
        for v in msgs["/world/state"].vessels
        if v.role != "usv"
    ]
    seen = 0
    for key, tv in meta["top_views"].items():
        split, seq = key.split("/")
        m, (w, h) = tv["metres_per_pixel"], tv["resolution"]
        calib: dict[str, np.ndarray] = {}
        for line in (out / split / "calib" / f"{seq}.txt").read_text().splitlines():
            name, _, vals = line.partition(" ")
            calib[name.rstrip(":")] = np.array([float(x) for x in vals.split()])
        pose = np.vstack([np.loadtxt(out / split / "pose" / f"{seq}.txt", ndmin=2)[0].reshape(3, 4), [0, 0, 0, 1]])
        body = pose @ np.vstack([calib["Tr_imu_velo"].reshape(3, 4), [0, 0, 0, 1]])
        x0, y0, yaw = body[0, 3], body[1, 3], math.atan2(body[1, 0], body[0, 0])
        sem = _png((out / split / "top_view_semantic" / seq / "000000.png").read_bytes())
        assert sem.shape == (h, w)
        vv, uu = np.mgrid[0:h, 0:w]
        left, ahead = ((w / 2 - uu - 0.5) * m).ravel(), ((h / 2 - vv - 0.5) * m).ravel()
        if tv["orientation"] == "heading_up":
            c, s_ = math.cos(yaw), math.sin(yaw)
            xy = np.stack([x0 + ahead * c - left * s_, y0 + ahead * s_ + left * c], 1)
        else:
            xy = np.stack([x0 - left, y0 + ahead], 1)
        seen += _check_semantic(sem, xy, boxes)
    assert seen >= 5, seen


def test_ros2_top_view_says_where_its_pixels_are(rec: Path, tmp_path: Path) -> None:
    from mcap_ros2.decoder import DecoderFactory as Ros2Decoders

    out = tmp_path / "ros2"
    convert(rec, to="ros2", out_dir=out)
    bag = out / SCENARIO["name"]
    custom = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]["custom_data"]
    assert "mmusv.top_view.u" in custom, "the bag says nothing of the top views' scale and orientation"
    tf: dict[str, tuple[str, np.ndarray]] = {}
    msgs: dict[str, Any] = {}
    with (bag / f"{SCENARIO['name']}.mcap").open("rb") as f:
        for _, channel, message, decoded in make_reader(f, decoder_factories=[Ros2Decoders()]).iter_decoded_messages():
            if message.log_time != 1_000_000_000:  # the first frame (1 s: the bag's time offset)
                continue
            if channel.topic in ("/tf", "/tf_static"):
                for t in decoded.transforms:
                    tf[t.child_frame_id] = (t.header.frame_id, _matrix(t.transform.translation, t.transform.rotation))
            else:
                msgs[channel.topic] = decoded

    def to_map(frame: str) -> np.ndarray:
        m = np.eye(4)
        while frame != "map":
            frame, step = tf[frame]
            m = step @ m
        return m

    seen = 0
    for agent in ("u", "v"):
        tv = json.loads(custom[f"mmusv.top_view.{agent}"])
        m, (w, h) = tv["metres_per_pixel"], tv["resolution"]
        img = msgs[f"/{agent}/top_view/semantic"]
        assert (img.width, img.height, img.encoding) == (w, h, "16UC1")
        sem = np.frombuffer(bytes(img.data), dtype="<u2").reshape(h, w)
        cam = to_map(img.header.frame_id)
        vv, uu = np.mgrid[0:h, 0:w]
        optical = np.stack([(uu + 0.5 - w / 2) * m, (vv + 0.5 - h / 2) * m, np.zeros((h, w))], -1).reshape(-1, 3)
        xy = (optical @ cam[:3, :3].T + cam[:3, 3])[:, :2]
        boxes = []
        dets = msgs[f"/{agent}/detections"]
        lidar = to_map(dets.header.frame_id)
        for d in dets.detections:
            if d.results[0].hypothesis.class_id != "vessel":
                continue
            c, q = d.bbox.center.position, d.bbox.center.orientation
            box = lidar @ _matrix(c, q)
            boxes.append((box[:2, 3], math.atan2(box[1, 0], box[0, 0]), d.bbox.size.x, d.bbox.size.y))
        seen += _check_semantic(sem, xy, boxes)
    assert seen >= 5, seen


def test_preview_draws_a_portrait_top_view_unstretched(rec: Path) -> None:
    """``mmusv preview`` of v's 150 × 200 (portrait) top view: the panels resized it to a square, 2.84 panel pixels
    per source pixel across and 2.13 down, so every hull and distance in them was a third wider than long (and the
    panel's ``scale``, 2.84, held across only). Now one scale both ways, the panel as tall as the square."""
    from mmusv.preview import compose_preview

    _, panels = compose_preview(rec, frame=0, agent="v")
    tops = [p for p in panels if " · top view · " in p.title]
    assert len(tops) == 2, [p.title for p in panels]
    for p in tops:
        left, top, right, bottom = p.box
        assert (right - left) == pytest.approx(150 * p.scale, abs=1) and (bottom - top) == pytest.approx(
            200 * p.scale, abs=1
        ), (p.title, p.box, p.scale)


# --------------------------------------------------------------------------------------------------- the edges


def _one_usv(top_view: dict[str, Any], **extra: Any) -> dict[str, Any]:
    return {
        "name": "tv_edge",
        "seed": 3,
        "map": {"type": "open_sea", "seed": 0},
        "environment": {"wave": "W0"},
        "acquisition": {"frequency_hz": 5, "frames": 1},
        "rigs": {"r": {"cameras": [], "radar": None, "lidar": None, "top_view": {"quality": "draft", **top_view}}},
        "vessels": [
            {
                "id": "u",
                "role": "usv",
                "asset": "usv_patrol_12m",
                "rig": "r",
                "speed_mps": 0.0,
                "route": [[0, 0], [60, 0]],
            }
        ],
        **extra,
    }


def test_a_vessel_taller_than_the_top_view_still_fills_its_footprint() -> None:
    sc = _one_usv({"altitude_m": 20.0, "resolution": [100, 100], "metres_per_pixel": 1.0})
    sc["vessels"].append(
        {"id": "big", "role": "target", "asset": "cruise_ship_300m", "speed_mps": 0.0, "route": [[0, 30], [100, 30]]}
    )
    sim = Simulation(sc)
    cap = sim.capture(0, sensors=["top_view"])
    big = sim.vessels[1]
    top = cap.world.box_centers[1][2] + big.box_size[2] / 2
    assert top > 60.0, "a ship three times the top view's height"
    img = cap.agents["u"].top_view
    assert img is not None
    on = img.instance == big.instance_id
    # Its footprint: columns u with (50 - u - 0.5) m to port within 30 ± beam / 2, every row (it is 300 m long).
    left = 50 - np.arange(100) - 0.5
    cols = np.abs(left - 30.0) < big.box_size[1] / 2
    assert on[:, cols].all() and not on[:, ~cols].any()
    assert float(img.depth[on].max()) < 20.0, "its decks below the camera, not the water"


def test_a_top_view_over_an_island_shows_land_where_the_map_has_it() -> None:
    from mmusv.world.maps import generate_map

    sc = _one_usv(
        {"resolution": [160, 160], "metres_per_pixel": 2.0, "orientation": "north_up", "outputs": ["semantic"]},
        map={"type": "island", "seed": 4},
    )
    sc["vessels"][0].update(asset="usv_wamv", route=[[510, -300], [560, -300]])
    sim = Simulation(sc)
    cap = sim.capture(0, sensors=["top_view"])
    img, pose = cap.agents["u"].top_view, cap.agents["u"].top_view_pose
    assert img is not None and pose is not None
    hf = generate_map("island", seed=4).heightfield
    vv, uu = np.mgrid[0:160, 0:160]
    xy = np.stack([pose[0, 3] + (uu + 0.5 - 80) * 2.0, pose[1, 3] + (80 - vv - 0.5) * 2.0], -1).reshape(-1, 2)
    fx, fy = (xy[:, 0] - hf.x0) / hf.spacing, (xy[:, 1] - hf.y0) / hf.spacing
    j, i = np.floor(fx).astype(int), np.floor(fy).astype(int)
    fx, fy, z = fx - j, fy - i, hf.z
    height = (z[i, j] * (1 - fx) + z[i, j + 1] * fx) * (1 - fy) + (z[i + 1, j] * (1 - fx) + z[i + 1, j + 1] * fx) * fy
    sem = img.semantic.ravel()
    land, water = np.isin(sem, [2, 3]), sem == 1
    assert land.sum() > 1000
    wrong = (land & (height < -0.5)) | (water & (height > 0.5))
    assert not wrong.any(), int(wrong.sum())
    assert ((land == (height > 0.0)) | ~(land | water)).mean() > 0.99


def test_a_top_view_below_the_land_it_sees_is_refused(tmp_path: Path) -> None:
    """The islet of island map seed 4 rises to 28.9 m, 60–140 m off a WAM-V: a top view 5 m up (above the WAM-V's
    2.2 m hull, so it loaded) drew the 1354 pixels where the land stands above the camera as water (semantic 1, the
    sea's instance, depth 5 m to the still water under the ground), without a word: the terrain is a surface seen
    from above, and rays starting under it never meet it. ``mmusv run`` refuses it now, naming the file, the field
    and the height the altitude must pass (``--no-checks`` skips it), and the scenario editor lists it as an error;
    at 60 m it runs."""
    sc = _one_usv(
        {"altitude_m": 5.0, "resolution": [160, 160], "metres_per_pixel": 2.0, "outputs": ["semantic"]},
        map={"type": "island", "seed": 4},
    )
    sc["vessels"][0].update(asset="usv_wamv", route=[[490, -320], [560, -320]])
    path = tmp_path / "low.yaml"
    path.write_text(yaml.safe_dump(sc))
    with pytest.raises(ConfigError) as err:
        run(path, out_dir=tmp_path / "low")
    said = str(err.value)
    assert str(path) in said and "rigs.r.top_view.altitude_m = 5:" in said, said
    assert "altitude_m must be above" in said and "--no-checks" in said, said
    assert not (tmp_path / "low").exists() or not any((tmp_path / "low").iterdir())
    # The scenario editor lists it as an error at the field, with the highest ground it sees.
    from mmusv.editor.evaluate import evaluate

    found = [p for p in evaluate(sc)["problems"] if p["check"] == "top_view"]
    assert [(p["severity"], p["field"], p["vessels"]) for p in found] == [
        ("error", "rigs.r.top_view.altitude_m", ["u"])
    ]
    assert "rises to 28.9 m" in found[0]["message"], found[0]["message"]
    sc["rigs"]["r"]["top_view"]["altitude_m"] = 60.0
    assert not [p for p in evaluate(sc)["problems"] if p["check"] == "top_view"]
    path.write_text(yaml.safe_dump(sc))
    assert Path(run(path, out_dir=tmp_path / "high").recording).is_file()


@pytest.mark.parametrize(
    "field,value,said",
    [
        ("orientation", "north-up", "Input should be 'heading_up' or 'north_up'"),
        ("metres_per_pixel", 0, "greater than or equal to 0.001"),
        ("resolution", [0, 100], "width and height must be in 1..16384 pixels"),
        ("outputs", ["depth"], "Input should be 'rgb', 'semantic' or 'instance'"),
        ("heading", 3, "allowed keys: altitude_m, resolution, metres_per_pixel, orientation"),
    ],
)
def test_a_bad_top_view_names_file_field_and_values(tmp_path: Path, field: str, value: Any, said: str) -> None:
    doc = _one_usv({field: value})
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(doc))
    with pytest.raises(ConfigError) as err:
        load_scenario(path)
    text = str(err.value)
    assert str(path) in text and f"rigs.r.top_view.{field}" in text and said in text, text


def test_the_same_seed_gives_the_same_top_view() -> None:
    sc = _one_usv({"resolution": [64, 48], "metres_per_pixel": 0.5}, environment={"wave": "W3"})
    sc["vessels"].append(
        {"id": "t", "role": "target", "asset": "rib_4_5m", "speed_mps": 4.0, "route": [[5, 8], [50, 8]]}
    )
    first, second = (Simulation(sc).capture(0, sensors=["top_view"]).agents["u"].top_view for _ in range(2))
    assert first is not None and first == second
    sc["seed"] = 4
    other = Simulation(sc).capture(0, sensors=["top_view"]).agents["u"].top_view
    assert other is not None and other.rgb is not None and first.rgb is not None
    assert not np.array_equal(other.rgb, first.rgb)


def test_the_labels_do_not_depend_on_the_quality() -> None:
    """``quality`` (draft, standard, high) changes the RGB shading only: the semantic, instance and depth images
    are the same bytes (each pixel's centre ray), so a BEV set may be rendered at draft for speed."""
    images = []
    for quality in ("draft", "standard", "high"):
        sc = _one_usv({"resolution": [96, 96], "metres_per_pixel": 0.5, "quality": quality}, environment={"wave": "W2"})
        sc["vessels"].append(
            {"id": "t", "role": "target", "asset": "fishing_boat_12m", "speed_mps": 2.0, "route": [[10, 12], [60, 12]]}
        )
        img = Simulation(sc).capture(0, sensors=["top_view"]).agents["u"].top_view
        assert img is not None
        images.append(img)
    for img in images[1:]:
        for name in ("semantic", "instance", "depth"):
            assert np.array_equal(getattr(img, name), getattr(images[0], name)), name
