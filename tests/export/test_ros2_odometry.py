"""``/<usv>/odom``'s angular velocity (``--to ros2``): it was 0 of hulls rolling and pitching in the waves, and
turning. Checked against the Euler-angle rates of the recorded poses (the kinematic relation ``ω = T(Θ)⁻¹·Θ̇``,
Fossen 2011 eq. 2.29: a computation of its own, not the exporter's rotation-vector differences), and
:func:`mmusv.frames.body_rates` against a constant rate, exactly. Also: a ros2 conversion stopped midway closes its
bag."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import coop
from mmusv.acquire import run
from mmusv.export import convert
from mmusv.frames import body_rates
from mmusv.recording import read_messages, topics
from mmusv.recording.decode import WorldFrame
from rosbags.highlevel import AnyReader
from scipy.spatial.transform import Rotation


def test_body_rates_of_a_constant_rate_are_that_rate_at_every_sample() -> None:
    omega = np.array([0.05, -0.2, 0.4])  # rad/s, body axes
    start = Rotation.from_euler("zyx", [0.3, 0.1, -0.2])
    times = np.array([0.0, 0.1, 0.25, 0.3, 0.7])  # uneven steps
    rots = [(start * Rotation.from_rotvec(omega * t)).as_matrix() for t in times]  # R(t) = R0·exp(t[ω]×)
    np.testing.assert_allclose(body_rates(times, rots), np.tile(omega, (5, 1)), atol=1e-12)
    assert body_rates([0.0], [np.eye(3)]).shape == (1, 3)


def _euler_rates(times: np.ndarray, eta: np.ndarray) -> np.ndarray:
    """Body angular velocity from ``[roll, pitch, yaw]`` and their np.gradient derivatives (zyx convention)."""
    ang = np.unwrap(eta[:, 3:6], axis=0)
    d = np.gradient(ang, times, axis=0)
    phi, theta = ang[:, 0], ang[:, 1]
    p = d[:, 0] - np.sin(theta) * d[:, 2]
    q = np.cos(phi) * d[:, 1] + np.sin(phi) * np.cos(theta) * d[:, 2]
    r = -np.sin(phi) * d[:, 1] + np.cos(phi) * np.cos(theta) * d[:, 2]
    return np.stack([p, q, r], axis=1)


@pytest.fixture(scope="module")
def rolling(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The coop scenario in the physical sea at W3, 10 Hz, 8 frames, LiDAR-only; ``usv_b`` turns at its
    waypoint."""
    cfg: dict[str, Any] = coop(
        environment={"time_of_day": "11:00", "weather": "clear", "wave": "W3"},
        acquisition={"frequency_hz": 10, "frames": 8},
        rigs={"r": {"preset": "lidar_only", "lidar": {"channels": 16, "points_per_second": 20000}}},
    )
    cfg["vessels"][2]["route"] = [[90, -30], [88, -28], [60, -28]]
    out = tmp_path_factory.mktemp("rolling")
    run(cfg, out_dir=out)
    return out / "export_coop.mcap"


def test_odometry_angular_velocity_is_the_body_rate_of_the_recorded_poses(rolling: Path, tmp_path: Path) -> None:
    convert(rolling, to="ros2", out_dir=tmp_path)
    worlds = [WorldFrame.from_message(m) for topic, _t, m in read_messages(rolling) if topic == topics.WORLD_STATE]
    times = np.array([w.time_s for w in worlds])
    got: dict[str, list[tuple[int, np.ndarray, np.ndarray]]] = {}
    with AnyReader([tmp_path / "export_coop"]) as r:
        conns = [c for c in r.connections if c.topic.endswith("/odom")]
        for c, _t, raw in r.messages(connections=conns):
            msg = r.deserialize(raw, c.msgtype)
            stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
            ang, lin = msg.twist.twist.angular, msg.twist.twist.linear
            got.setdefault(c.topic, []).append(
                (stamp, np.array([ang.x, ang.y, ang.z]), np.array([lin.x, lin.y, lin.z]))
            )
    assert sorted(got) == ["/usv_a/odom", "/usv_b/odom"]
    for usv in ("usv_a", "usv_b"):
        msgs = sorted(got[f"/{usv}/odom"], key=lambda m: m[0])
        assert len(msgs) == len(worlds) == 8  # one per frame, the last one too
        i = worlds[0].ids.index(usv)
        eta = np.array([w.poses[i] for w in worlds])
        want = _euler_rates(times, eta)
        angular = np.array([a for _s, a, _l in msgs])
        assert np.abs(angular).max() > 0.01, angular  # the hull rolls, pitches and turns: not 0
        # The two are second-order differences of the same motion, differing by O((|ω|·Δt)²)·|ω| (the WAM-V rolls
        # at up to 0.9 rad/s here): compared as vectors, within 2 % of the rate.
        err = np.linalg.norm(angular - want, axis=1)
        scale = np.linalg.norm(want, axis=1)
        assert np.all(err[1:-1] <= 0.02 * scale[1:-1] + 1e-3), (usv, err, scale)
        # the ends: the one step beside them (the Euler rates of those two samples; first order, so within 10 %)
        for k, ends in ((0, slice(0, 2)), (-1, slice(-2, None))):
            one_step = _euler_rates(times[ends], eta[ends])[k]
            assert np.linalg.norm(angular[k] - one_step) <= 0.1 * np.linalg.norm(one_step) + 1e-3, (usv, k)
        linear = np.array([lin for _s, _a, lin in msgs])  # unchanged: the recorded velocity in the hull frame
        assert np.abs(linear).max() > 1.0


def test_a_stopped_ros2_conversion_leaves_a_closed_bag_of_the_frames_converted(coop_rec: Path, tmp_path: Path) -> None:
    """Ctrl-C mid-conversion left the bag's file open, with no summary and no ``metadata.yaml`` (rosbags could not
    open it), to a Python session that went on; it is closed whole, holding the frames converted so far."""
    import os

    import yaml

    def stop(done: int, total: int) -> None:
        if done == 2:
            raise KeyboardInterrupt

    out = tmp_path / "o"
    with pytest.raises(KeyboardInterrupt):
        convert(coop_rec, to="ros2", out_dir=out, progress=stop)
    assert yaml.safe_load((out / "conversion.yaml").read_text())["status"] == "interrupted"
    bag = out / "export_coop"
    assert (bag / "metadata.yaml").is_file()
    # the bag itself says it was cut short (peers read a closed bag as a whole one; only conversion.yaml said so)
    custom = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]["custom_data"]
    assert custom["mmusv.status"] == "interrupted"
    open_files = {os.path.realpath(f"/proc/self/fd/{fd}") for fd in os.listdir("/proc/self/fd")}
    assert str((bag / "export_coop.mcap").resolve()) not in open_files
    with AnyReader([bag]) as r:
        clock = [t for c, t, _raw in r.messages() if c.topic == "/clock"]
        odom = [t for c, t, _raw in r.messages() if c.topic == "/usv_a/odom"]
    assert len(clock) == 2 and odom == clock  # frames 0 and 1, the odometry of frame 1 too


def test_a_frame_that_comes_back_complete_after_later_ones_gets_its_odometry(coop_rec: Path, tmp_path: Path) -> None:
    """Frame 1 recorded first without its /world/state (skipped as incomplete), then whole after frame 2:
    the writer got frames 0, 2, 1, and the rates of times going back refused the conversion ('times: must
    increase'). Each USV's odometry is written once a frame, each from the frames beside it in order of conversion."""
    from mcap.reader import make_reader
    from mcap.writer import CompressionType, Writer
    from mcap_rechunk import write_records

    with coop_rec.open("rb") as f:
        reader = make_reader(f)
        meta = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
        msgs = list(reader.iter_messages())
    t1 = sorted({m.log_time for _, _, m in msgs})[1]
    first = [t for t in msgs if not (t[2].log_time == t1 and t[1].topic == "/world/state")]
    src = tmp_path / "in" / coop_rec.name
    src.parent.mkdir()
    with src.open("wb") as g:
        w = Writer(g, compression=CompressionType.NONE)
        write_records(w, meta, first + [t for t in msgs if t[2].log_time == t1])
        w.finish()  # type: ignore[no-untyped-call]
    rep = convert(src, to="ros2", out_dir=tmp_path / "o")
    assert rep.frames == 3
    with AnyReader([tmp_path / "o" / "export_coop"]) as r:
        stamps = [t for c, t, _raw in r.messages() if c.topic == "/usv_b/odom"]
    assert sorted(stamps) == sorted({t for _c, t, _raw in _messages_of(tmp_path / "o" / "export_coop", "/clock")})


def _messages_of(bag: Path, topic: str) -> list[tuple[Any, int, bytes]]:
    with AnyReader([bag]) as r:
        return [(c, t, bytes(raw)) for c, t, raw in r.messages() if c.topic == topic]
