"""``--to kitti_tracking``'s ``oxts/<seq>.txt``: KITTI's GPS/IMU lines of each sequence's vessel, read with pykitti's
own code (``pykitti.utils.load_oxts_packets_and_poses``, the Mercator conversion of the KITTI devkit's
``convertOxtsToPose``), give back the exporter's poses; the rates are the poses' finite differences; a bad
``--oxts-origin`` is refused in one line before anything is written.

The ``port`` recording (conftest: 3 frames, 3 USVs rolling and pitching in the port's waves) for the export, a
synthetic turn 3 km from the origin for the maths.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mmusv.export import convert
from mmusv.export.kitti_oxts import (
    DEFAULT_ORIGIN,
    EARTH_RADIUS_M,
    GRAVITY,
    OXTS_COLUMNS,
    STATUS,
    oxts_lines,
)

pykitti_utils = pytest.importorskip(
    "pykitti.utils", reason="pykitti is not installed (pip install -e '.[test]' installs it)"
)

FRAMES = 3
OPTIONS: dict[str, Any] = {"splits": None, "extras": None}


def homogeneous(rows: Any) -> np.ndarray:
    m = np.eye(4)
    m[:3, :] = np.asarray(rows, dtype=np.float64).reshape(3, 4)
    return m


def tr_imu_velo(path: Path) -> np.ndarray:
    """``Tr_imu_velo`` (vessel body → LiDAR) of a KITTI tracking ``calib/<seq>.txt``."""
    for line in path.read_text().splitlines():
        key, *vals = line.split()
        if key == "Tr_imu_velo":
            return homogeneous([float(v) for v in vals])
    raise AssertionError(f"{path}: no Tr_imu_velo")


def mercator(lat: float, lon: float, scale: float) -> np.ndarray:
    """The devkit's (and pykitti's) Mercator east, north of a latitude and longitude."""
    return np.array(
        [
            scale * EARTH_RADIUS_M * lon * math.pi / 180.0,
            scale * EARTH_RADIUS_M * math.log(math.tan((90.0 + lat) * math.pi / 360.0)),
        ]
    )


def check_sequences(train: Path, origin: tuple[float, float]) -> int:
    """Every sequence of ``train``: pykitti's ``T_w_imu`` (the vessel body → world, translated to the first frame's
    position) times ``Tr_imu_velo⁻¹`` is ``pose/<seq>.txt``'s LiDAR → world, the rotation to 1e-6 (the pose files'
    ``%.6e``) and the position to 1 mm once the constant offset is added back: the world position of the first
    frame's body, whose Mercator coordinates minus the origin's are its east and north. Returns the sequences seen."""
    seqs = sorted(p.stem for p in (train / "oxts").iterdir())
    assert seqs == sorted(p.stem for p in (train / "pose").iterdir()) and seqs
    for s in seqs:
        text = (train / "oxts" / f"{s}.txt").read_text()
        rows = [line.split() for line in text.splitlines()]
        assert len(rows) == FRAMES and {len(r) for r in rows} == {len(OXTS_COLUMNS)} == {30}
        oxts = pykitti_utils.load_oxts_packets_and_poses([str(train / "oxts" / f"{s}.txt")])
        poses = [homogeneous(r) for r in np.loadtxt(train / "pose" / f"{s}.txt").reshape(-1, 12)]
        imu_to_velo = tr_imu_velo(train / "calib" / f"{s}.txt")
        first_body = poses[0] @ imu_to_velo  # body → world of frame 0
        assert len(oxts) == len(poses) == FRAMES
        for k, (o, pose) in enumerate(zip(oxts, poses, strict=True)):
            velo = o.T_w_imu @ np.linalg.inv(imu_to_velo)
            np.testing.assert_allclose(velo[:3, :3], pose[:3, :3], rtol=0, atol=1e-6, err_msg=f"{s} {k}")
            moved = velo[:3, 3] + first_body[:3, 3]
            np.testing.assert_allclose(moved, pose[:3, 3], rtol=0, atol=1e-3, err_msg=f"{s} {k}")
            p = o.packet
            assert (p.navstat, p.numsats, p.posmode, p.velmode, p.orimode) == STATUS
        # the geodetic origin is the world's: Mercator of the first packet minus the origin's is the body's east, north
        p0 = oxts[0].packet
        scale = math.cos(p0.lat * math.pi / 180.0)
        east_north = mercator(p0.lat, p0.lon, scale) - mercator(*origin, scale)
        np.testing.assert_allclose(east_north, first_body[:2, 3], rtol=0, atol=1e-3)
        assert p0.alt == pytest.approx(first_body[2, 3], abs=1e-3)
        # hulls move: the first sequence's vessel has a speed, the rates are not all zero
        assert any(math.hypot(o.packet.vn, o.packet.ve) > 0.1 for o in oxts), s
    return len(seqs)


def test_pykitti_reads_the_oxts_as_the_pose_files(port_rec: Path, tmp_path: Path) -> None:
    out = tmp_path / "o"
    convert(port_rec, to="kitti_tracking", out_dir=out, **OPTIONS)
    assert check_sequences(out / "train", DEFAULT_ORIGIN) == 3
    notes = yaml.safe_load((out / "conversion.yaml").read_text())["recordings"][0]["notes"]
    assert "oxts: the world origin is at latitude 45.0, longitude -2.0 (--oxts-origin)" in notes


def test_the_command_takes_the_origin(port_rec: Path, tmp_path: Path) -> None:
    from mmusv.cli import main

    out = tmp_path / "c"
    argv = ["convert", str(port_rec), "--to", "kitti_tracking", "-o", str(out), "--no-split", "--extras", ""]
    assert main([*argv, "--oxts-origin=-33.85,151.3", "--agents", "usv_1", "--no-progress"]) == 0
    assert check_sequences(out / "train", (-33.85, 151.3)) == 1
    lat = float((out / "train" / "oxts" / "0000.txt").read_text().split()[0])
    assert lat == pytest.approx(-33.85, abs=0.05)  # a few hundred metres from the origin
    # the Python API's way: the same bytes, and the origin in the conversion's options
    convert(
        port_rec, to="kitti_tracking", out_dir=tmp_path / "p", agents="usv_1", oxts_origin=(-33.85, 151.3), **OPTIONS
    )
    options = yaml.safe_load((tmp_path / "p" / "conversion.yaml").read_text())["options"]
    assert options["oxts_origin"] == [-33.85, 151.3]
    assert (tmp_path / "p" / "train" / "oxts" / "0000.txt").read_bytes() == (
        out / "train" / "oxts" / "0000.txt"
    ).read_bytes()


BAD_ORIGINS = ["91,0", "45", "45,181", "a,b", "nan,0", "45,0,1", "-85.5,0", ""]


@pytest.mark.parametrize(
    ("value", "to"), [*((v, "kitti_tracking") for v in BAD_ORIGINS), ("45,-2", "coco"), ("91,0", "coco")]
)
def test_a_bad_oxts_origin_is_refused_in_one_line_before_writing(
    port_rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], value: str, to: str
) -> None:
    from mmusv.cli import main

    out = tmp_path / "bad"
    capsys.readouterr()
    assert main(["convert", str(port_rec), "--to", to, "-o", str(out), "--no-progress", f"--oxts-origin={value}"]) == 2
    err = capsys.readouterr().err
    said = (
        f"--oxts-origin '{value}': must be LAT,LON in degrees, LAT in [-85, 85] and LON in [-180, 180] (default 45,-2)"
        if to == "kitti_tracking"
        else f"--oxts-origin '{value}': only --to kitti_tracking writes it, not --to coco"
    )
    assert err.startswith("mmusv: error: ") and err.count("\n") == 1 and said in err, err
    assert not out.exists()


@pytest.mark.parametrize(
    ("value", "to", "said"),
    [
        ((91.0, 0.0), "kitti_tracking", "oxts_origin = (91.0, 0.0): must be LAT,LON in degrees, LAT in [-85, 85]"),
        ("45", "kitti_tracking", "oxts_origin = '45': must be LAT,LON in degrees"),
        # were read as 1, 0 and 45, -2: true/false and texts are not numbers (as the API's other numbers say)
        ((True, False), "kitti_tracking", "oxts_origin = (True, False): must be LAT,LON in degrees"),
        (("45", "-2"), "kitti_tracking", "oxts_origin = ('45', '-2'): must be LAT,LON in degrees"),
        ((45.0, -2.0), "mot", "oxts_origin = (45.0, -2.0): only to = 'kitti_tracking' writes it, not to = 'mot'"),
    ],
)
def test_the_api_refuses_a_bad_oxts_origin_before_writing(
    port_rec: Path, tmp_path: Path, value: Any, to: str, said: str
) -> None:
    from mmusv.errors import ConfigError

    with pytest.raises(ConfigError) as err:
        convert(port_rec, to=to, out_dir=tmp_path / "bad", oxts_origin=value, **OPTIONS)
    assert said in str(err.value) and "\n" not in str(err.value)
    assert not (tmp_path / "bad").exists()


@pytest.mark.parametrize(("value", "kind"), [({45.0, 10.0}, "set"), ({45.0: 0, -2.0: 0}, "dict")])
def test_an_origin_without_order_is_refused_not_read_swapped(value: Any, kind: str) -> None:
    """A set has no order: ``{45.0, 10.0}`` was read as latitude 10, longitude 45 (a dict as its keys), silently."""
    from mmusv.errors import ConfigError
    from mmusv.export.kitti_oxts import parse_origin

    with pytest.raises(ConfigError, match=f"a pair in order \\(a tuple or a list\\), not {kind}$"):
        parse_origin(value, "oxts_origin =")
    assert parse_origin(np.array([45.0, 10.0]), "oxts_origin =") == (45.0, 10.0)  # an array keeps its order


def test_a_huge_origin_is_shown_shortened() -> None:
    """The message echoed the whole value: a megabyte of text was a megabyte of error line."""
    from mmusv.errors import ConfigError
    from mmusv.export.kitti_oxts import parse_origin

    with pytest.raises(ConfigError) as err:
        parse_origin("45," * 100_000)
    assert len(str(err.value)) < 300 and str(err.value).startswith("--oxts-origin '45,45,")


# ------------------------------------------------------------------------------------------------- the maths


def rot(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """KITTI's ``Rz(yaw)·Ry(pitch)·Rx(roll)``, with pykitti's own matrices."""
    r: np.ndarray = pykitti_utils.rotz(yaw) @ pykitti_utils.roty(pitch) @ pykitti_utils.rotx(roll)
    return r


def read(lines: list[str], tmp_path: Path) -> list[Any]:
    path = tmp_path / "0000.txt"
    path.write_text("".join(x + "\n" for x in lines))
    return list(pykitti_utils.load_oxts_packets_and_poses([str(path)]))


def test_a_turn_3_km_out_comes_back_exactly(tmp_path: Path) -> None:
    """A vessel turning left at 0.1 rad/s and 5 m/s on a circle 3 km north-east of the origin, heeled and trimmed
    (constant roll and pitch), with a gap in its frame times: pykitti gives back every position to 1 µm and every
    rotation to 1e-12; the velocity is the circle's (5 m/s forward, to the central differences' O(dt²)), the
    acceleration the centripetal one plus gravity, the angular rate 0.1 rad/s about the body's z turned by the
    heel and trim, in both frames."""
    speed, rate, radius = 5.0, 0.1, 50.0
    times = np.array([0.0, 0.1, 0.2, 0.4, 0.5, 0.6, 0.7])  # index 3 (0.3 s) skipped
    centre = np.array([3000.0, 2000.0])
    roll, pitch = 0.05, -0.02
    poses = []
    for t in times:
        a = rate * t
        body = np.eye(4)
        body[:2, 3] = centre + radius * np.array([math.sin(a), -math.cos(a)])  # heading a: east, turning north
        body[2, 3] = 0.3 * math.sin(t)
        body[:3, :3] = rot(roll, pitch, a)
        poses.append(body)
    lines = oxts_lines(times, poses, (54.2, 7.9))
    packets = read(lines, tmp_path)
    for k, (o, body) in enumerate(zip(packets, poses, strict=True)):
        p = o.packet
        np.testing.assert_allclose(o.T_w_imu[:3, 3], body[:3, 3] - poses[0][:3, 3], rtol=0, atol=1e-6)
        np.testing.assert_allclose(o.T_w_imu[:3, :3], body[:3, :3], rtol=0, atol=1e-12)
        assert (p.roll, p.pitch, p.yaw) == pytest.approx((roll, pitch, rate * times[k]), abs=1e-12)
        heading = np.array([math.cos(rate * times[k]), math.sin(rate * times[k])])
        assert math.hypot(p.vf, p.vl) == pytest.approx(speed, rel=1e-3), k
        left = np.array([-heading[1], heading[0]])
        assert (p.ve, p.vn) == pytest.approx(tuple(p.vf * heading + p.vl * left), abs=1e-9)
        omega_body = np.linalg.inv(body[:3, :3]) @ [0.0, 0.0, rate]
        assert (p.wx, p.wy, p.wz) == pytest.approx(tuple(omega_body), abs=1e-9), k
        omega_level = rot(0.0, 0.0, -rate * times[k]) @ [0.0, 0.0, rate]
        assert (p.wf, p.wl, p.wu) == pytest.approx(tuple(omega_level), abs=1e-9), k
        if 0 < k < len(times) - 1:  # inside: central differences, the velocity along the heading
            assert abs(p.vl) < 1e-3 and p.vu == pytest.approx(0.3 * math.cos(times[k]), abs=1e-3), k
        if 1 < k < len(times) - 2:  # the acceleration is the turn's, v·ω to the left, and the heave's, plus gravity
            assert p.al == pytest.approx(speed * rate, rel=0.05) and abs(p.af) < 0.02, k
            force = np.array([*(speed * rate * left), GRAVITY - 0.3 * math.sin(times[k])])
            assert p.au == pytest.approx(force[2], abs=0.02), k
            np.testing.assert_allclose([p.ax, p.ay, p.az], body[:3, :3].T @ force, rtol=0, atol=0.05)
    # the text reads back as the same doubles: the shortest round-trip form, no precision lost
    for line in lines:
        assert [repr(float(v)) for v in line.split()[:25]] == line.split()[:25]


def test_a_vessel_at_rest_and_a_single_frame(tmp_path: Path) -> None:
    """Still: zero velocity and rates, the accelerometer reads gravity in the heeled body's axes; one frame: the
    same (no difference to take), every status column as documented."""
    body = np.eye(4)
    body[:3, :3] = rot(0.1, 0.0, -2.0)
    body[:3, 3] = [-120.0, 40.0, 0.0]
    for n in (1, 3):
        packets = read(oxts_lines(np.arange(n) * 0.2, [body] * n, DEFAULT_ORIGIN), tmp_path)
        for o in packets:
            p = o.packet
            assert (p.vn, p.ve, p.vf, p.vl, p.vu, p.wx, p.wy, p.wz, p.wf, p.wl, p.wu) == (0.0,) * 11
            np.testing.assert_allclose([p.ax, p.ay, p.az], body[:3, :3].T @ [0.0, 0.0, GRAVITY], atol=1e-12)
            assert (p.af, p.al, p.au) == (0.0, 0.0, GRAVITY)
            assert (p.pos_accuracy, p.vel_accuracy) == (0.02, 0.01)
            assert (p.navstat, p.numsats, p.posmode, p.velmode, p.orimode) == STATUS
    assert oxts_lines([], [], DEFAULT_ORIGIN) == []
