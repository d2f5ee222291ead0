"""A tracking and forecasting researcher's round: the labels' identities, times, kinematics and frames, checked
frame to frame on small recordings with computations of our own (the recording read with the ``mcap`` reader and
its protobuf decoder; poses, boxes and times computed here, never with mmusv's helpers).

Findings, each with its test:

1. KITTI ``label_2`` location was the bottom of the *tilted* box (the hull's own z axis), while KITTI's box is
   upright in the camera frame and every reader (the devkits, OpenPCDet's ``boxes3d_kitti_camera_to_lidar``) adds
   h/2 along the camera's y axis to find the centre: in waves that centre was h/2 · tilt away from the vessel, and
   moved with the USV's roll every frame (up to 3 m for the port's 35 m high ferry, 4.8 m of drift over 1.4 s for
   a moored ship in ``port_entry``); the same vessel seen by two USVs landed in two places. Now the location is
   the box centre h/2 down the camera's y axis
   (``test_kitti_label_centres_are_the_vessels_box_centres_in_every_frame_and_agent``).
2. The KITTI export gave no time base: its files are named by acquisition index, but nothing in it said the
   frequency, so a tracker could not get Δt from it (OPV2V has ``fixed_delta_seconds``, SemanticKITTI
   ``times.txt``). ``mmusv_kitti.yaml`` now has ``frequency_hz``
   (``test_kitti_export_gives_the_time_of_every_file``).
3. OPV2V's ``ego_speed`` and ``vehicles[].speed`` are the norm of the 3D velocity, heave rate included (as
   OpenCDA's ``get_speed``, and pinned by ``tests/export/test_opv2v.py``), so they differ from the scenario's
   ``speed_mps`` and change from frame to frame in waves; undocumented before, now in the module's docstring
   (``test_opv2v_speeds_are_the_3d_norm_as_documented``).
4. The world state's kinematic conventions a forecaster needs were undocumented: yaw in ``[-π, π]`` (wraps),
   the π turn from one frame to the next at each end of a ``ping_pong`` route, ``vz`` the heave rate; now in
   docs/recording.md (``test_route_end_turns_and_yaw_wrap_are_as_documented``).
"""

from __future__ import annotations

import itertools
import math
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from kitti_files import read_calib
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory
from mmusv.acquire import run
from mmusv.export import convert

REPO = Path(__file__).resolve().parents[1]


def scenario() -> dict[str, Any]:
    """Open sea at W3 (the physical sea: the USVs roll by degrees); USV ``a`` with a small front camera, USV ``b``
    with a LiDAR alone, both within 100 m of a 90 m ferry (35 m high) sailing between them."""
    lidar = {"channels": 8, "points_per_second": 20480}
    cam = {"name": "front", "resolution": [64, 48], "quality": "draft", "outputs": ["rgb"]}
    return {
        "name": "tracking_round",
        "seed": 5,
        "map": {"type": "open_sea", "seed": 0},
        "environment": {"wave": "W3"},
        "acquisition": {"frequency_hz": 4, "frames": 4},
        "rigs": {
            "cam": {"preset": "lidar_only", "lidar": lidar, "cameras": [{**cam, "mount": {"point": "camera_front"}}]},
            "lid": {"preset": "lidar_only", "lidar": lidar},
        },
        "vessels": [
            {"id": "a", "role": "usv", "asset": "usv_wamv", "rig": "cam", "speed_mps": 2, "route": [[0, 0], [60, 0]]},
            {"id": "ferry", "asset": "ropax_ferry_90m", "speed_mps": 3, "route": [[-20, 50], [80, 52]]},
            {"id": "b", "role": "usv", "asset": "usv_wamv", "rig": "lid", "speed_mps": 2, "route": [[0, 99], [9, 99]]},
        ],
    }


@pytest.fixture(scope="module")
def rec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return Path(run(scenario(), out_dir=tmp_path_factory.mktemp("rec")).recording)


def read(rec: Path) -> tuple[float, dict[int, Any], dict[str, list[int]]]:
    """The recording's frequency, its world state per frame and the log times (ns) of every topic."""
    with rec.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        world: dict[int, Any] = {}
        times: dict[str, list[int]] = defaultdict(list)
        for _, channel, message, msg in reader.iter_decoded_messages(log_time_order=True):
            times[channel.topic].append(message.log_time)
            if channel.topic == "/world/state":
                world[msg.frame] = msg
    return float(meta["run"]["frequency_hz"]), world, times


def homogeneous(rows: np.ndarray) -> np.ndarray:
    m = np.eye(4)
    m[:3, :] = rows.reshape(3, 4)
    return m


@pytest.fixture(scope="module")
def kitti(rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("kitti") / "k"
    convert(rec, to="kitti", out_dir=out, splits=None, include_usvs=True)
    return out / "tracking_round"


def test_kitti_label_centres_are_the_vessels_box_centres_in_every_frame_and_agent(rec: Path, kitti: Path) -> None:
    """A KITTI reader's box centre (location through ``(R0_rect · Tr_velo_to_cam)⁻¹``, raised by h/2 along the
    LiDAR's z, OpenPCDet's ``boxes3d_kitti_camera_to_lidar``), taken to the world with ``pose/<ts>.txt``, is the
    vessel's world-state box centre in every frame, for the USV with a front camera and the one without; so two
    USVs' labels of one vessel agree. Tolerance 0.03 m: the labels' 2 decimals (≤ 0.009 m) and the pose files'
    7 digits."""
    _, world, _ = read(rec)
    agents = yaml.safe_load((kitti / "mmusv_kitti.yaml").read_text())["agents"]
    seen: dict[tuple[int, str], list[np.ndarray]] = defaultdict(list)
    tilt = 0.0
    for cav, agent in agents.items():
        for k, ws in world.items():
            ts = f"{k:06d}"
            calib = read_calib(kitti / str(cav) / "calib" / f"{ts}.txt")
            r0 = np.eye(4)
            r0[:3, :3] = calib["R0_rect"].reshape(3, 3)
            cam_to_lidar = np.linalg.inv(r0 @ homogeneous(calib["Tr_velo_to_cam"]))
            lidar_to_world = homogeneous(np.loadtxt(kitti / str(cav) / "pose" / f"{ts}.txt"))
            vessels = {v.id: v for v in ws.vessels}
            tilt = max(tilt, abs(vessels[agent].pose[3]), abs(vessels[agent].pose[4]))
            for line in (kitti / str(cav) / "label_2" / f"{ts}.txt").read_text().splitlines():
                f = line.split()
                h = float(f[8])
                centre = cam_to_lidar @ [float(f[11]), float(f[12]), float(f[13]), 1.0]
                centre[2] += h / 2.0
                in_world = (lidar_to_world @ centre)[:3]
                match = min(vessels.values(), key=lambda v: float(np.linalg.norm(np.subtract(v.box_center, in_world))))
                err = float(np.linalg.norm(np.subtract(match.box_center, in_world)))
                seen[(k, match.id)].append(in_world)
                assert err < 0.03, (agent, k, match.id, err)
    assert tilt > math.radians(2.0), tilt  # the USVs do roll: the old bottom was h/2 · tilt off
    shared = [v for v in seen.values() if len(v) > 1]
    assert len(shared) >= len(world)  # the ferry is in both USVs' labels of every frame
    for centres in shared:
        assert float(np.ptp(np.array(centres), axis=0).max()) < 0.05


def test_kitti_export_gives_the_time_of_every_file(rec: Path, kitti: Path) -> None:
    """``mmusv_kitti.yaml`` holds the recording's ``frequency_hz``; each file's 6-digit index k gives the log time
    ``round(k / f · 1e9)`` of that frame's messages in the recording, strictly increasing."""
    freq, world, times = read(rec)
    meta = yaml.safe_load((kitti / "mmusv_kitti.yaml").read_text())
    assert meta["frequency_hz"] == pytest.approx(freq)
    for cav in meta["agents"]:
        stems = sorted(int(p.stem) for p in (kitti / str(cav) / "label_2").glob("*.txt"))
        assert stems == sorted(world)
        ns = [round(k / meta["frequency_hz"] * 1e9) for k in stems]
        assert ns == times["/world/state"] == times[f"/{meta['agents'][cav]}/lidar"]
        assert all(a < b for a, b in itertools.pairwise(ns))


def test_opv2v_speeds_are_the_3d_norm_as_documented(rec: Path, tmp_path: Path) -> None:
    """OPV2V's ``ego_speed`` and ``speed`` (km/h) are |(vx, vy, vz)| of the world state, which in waves is not the
    speed over ground ``hypot(vx, vy)`` = ``speed_mps``; the OPV2V docstring says which."""
    import mmusv.export.opv2v as opv2v

    doc = " ".join((opv2v.__doc__ or "").split())
    assert "(vx, vy, vz)" in doc and "hypot(vx, vy)" in doc and "heave" in doc
    _, world, _ = read(rec)
    convert(rec, to="opv2v", out_dir=tmp_path / "o", splits=None)
    folder = tmp_path / "o" / "tracking_round" / "1000"  # usv a, world-state row 0
    gap = 0.0
    for k, ws in world.items():
        got = yaml.safe_load((folder / f"{k:06d}.yaml").read_text())["ego_speed"]
        v = np.array(ws.vessels[0].velocity)
        assert got == pytest.approx(float(np.linalg.norm(v)) * 3.6, abs=1e-5)
        assert math.hypot(v[0], v[1]) == pytest.approx(2.0, abs=1e-9)
        gap = max(gap, abs(got / 3.6 - 2.0))
    assert gap > 0.01  # heave shows in the speed


def test_route_end_turns_and_yaw_wrap_are_as_documented(tmp_path: Path) -> None:
    """docs/recording.md says how the world state moves: at a ``ping_pong`` end the yaw turns by π and the velocity
    reverses from one frame to the next; yaws are in ``[-π, π]``; speed over ground is ``speed_mps``."""
    text = " ".join((REPO / "docs" / "recording.md").read_text().split())
    assert "`ping_pong`" in text and "its yaw turns by π" in text and "`[-π, π]`" in text
    cfg = {
        "name": "ends",
        "seed": 1,
        "map": {"type": "open_sea", "seed": 0},
        "environment": {"motion": "paper"},
        "acquisition": {"frequency_hz": 2, "frames": 12},
        "rigs": {"r": {"preset": "lidar_only", "lidar": {"channels": 2, "points_per_second": 2048}}},
        "vessels": [
            {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": [[0, 0], [0, 50]]},
            # westwards: yaw next to -π; the ping-pong end after 4 m (frame 8 at 2 Hz and 1 m/s), then yaw next to 0
            {"id": "w", "asset": "speedboat_5m", "speed_mps": 1, "end": "ping_pong", "route": [[0, -40], [-4, -40.02]]},
        ],
    }
    _, world, _ = read(Path(run(cfg, out_dir=tmp_path).recording))
    yaw = np.array([world[k].vessels[1].pose[5] for k in sorted(world)])
    vel = np.array([world[k].vessels[1].velocity[:2] for k in sorted(world)])
    assert np.all(np.abs(yaw) <= math.pi)
    step = np.abs((np.diff(yaw) + math.pi) % (2 * math.pi) - math.pi)
    turns = np.nonzero(step > 1.0)[0]
    assert len(turns) == 1 and step[turns[0]] == pytest.approx(math.pi, abs=1e-6), step
    i = int(turns[0])
    assert vel[i] @ vel[i + 1] == pytest.approx(-1.0, abs=1e-9)  # 1 m/s, reversed
    np.testing.assert_allclose(np.hypot(vel[:, 0], vel[:, 1]), 1.0, atol=1e-9)
