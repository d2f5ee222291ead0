"""KITTI's GPS/IMU ``oxts`` lines of a vessel's poses, for ``--to kitti_tracking``'s ``oxts/<seq>.txt``.

One line per frame, KITTI raw's 30 values (its devkit's ``dataformat.txt``; pykitti's ``OxtsPacket``): ``lat lon
alt roll pitch yaw vn ve vf vl vu ax ay az af al au wx wy wz wf wl wu pos_accuracy vel_accuracy navstat numsats
posmode velmode orimode``, of the vessel body (x forward, y left, z up: the IMU frame, ``Tr_imu_velo`` of the
sequence's calibration) in mmusv's world (local east-north-up metres).

Position: the world's east and north laid on the KITTI devkit's Mercator projection (``convertOxtsToPose``,
pykitti's ``pose_from_oxts_packet``: ``tx = s·R·lon·π/180``, ``ty = s·R·ln(tan((90 + lat)·π/360))``,
``R`` = :data:`EARTH_RADIUS_M`, ``s = cos(lat)`` of the sequence's first line), the world origin at the geodetic
``origin`` (:data:`DEFAULT_ORIGIN`; ``--oxts-origin``, ``convert(..., oxts_origin=)``) and ``s`` that of the first
frame's latitude, so that those readers recover east and north to float precision: ``tx − tx(origin) = east``,
``ty − ty(origin) = north``;
``alt`` = world z of the body origin (its waterline point; still water at 0). Orientation: the body's rotation as
KITTI's ``Rz(yaw)·Ry(pitch)·Rx(roll)`` (yaw 0 = east, counter-clockwise; pitch positive = bow down; roll positive =
port side up).

Rates, from the poses at the frames' times (acquisition index / ``frequency_hz``) by finite differences as
:func:`numpy.gradient` takes them: central (weighted by the two steps where frames were skipped) inside the
sequence, one-sided at its ends, zero for a single frame. Velocity: of the body origin, ``vn``, ``ve`` (world),
``vf``, ``vl`` (level frame: the horizontal axes turned by yaw) and ``vu``. Acceleration: the derivative of that
velocity, written as an accelerometer (KITTI's OXTS RT3003) measures it, the specific force ``a + g·up``
(g = :data:`GRAVITY`): a level vessel at rest reads ``az`` = ``au`` = 9.80665; ``ax ay az`` in the body frame, ``af al
au`` in the level frame. Angular rate: the body frame's, ``wx wy wz`` (the rotation vectors of the relative
rotations between neighbouring frames over their time steps, weighted as the velocity's), and the same vector in
the level frame, ``wf wl wu``. Status: simulated truth with fixed, plausible values: ``pos_accuracy``
:data:`POS_ACCURACY_M`, ``vel_accuracy`` :data:`VEL_ACCURACY_MPS`, ``navstat numsats posmode velmode orimode``
:data:`STATUS` (those of KITTI's own files: 4, 11 satellites, RTK integer 6).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from mmusv import arguments
from mmusv.errors import ConfigError
from mmusv.frames import body_rates

__all__ = [
    "DEFAULT_ORIGIN",
    "EARTH_RADIUS_M",
    "GRAVITY",
    "MAX_LATITUDE_DEG",
    "OXTS_COLUMNS",
    "POS_ACCURACY_M",
    "STATUS",
    "VEL_ACCURACY_MPS",
    "euler_zyx",
    "latlon",
    "mercator_scale",
    "oxts_lines",
    "parse_origin",
]

OXTS_COLUMNS = (
    *("lat", "lon", "alt", "roll", "pitch", "yaw", "vn", "ve", "vf", "vl", "vu"),
    *("ax", "ay", "az", "af", "al", "au", "wx", "wy", "wz", "wf", "wl", "wu"),
    *("pos_accuracy", "vel_accuracy", "navstat", "numsats", "posmode", "velmode", "orimode"),
)
"""The 30 values of an oxts line (KITTI raw's ``dataformat.txt``)."""
EARTH_RADIUS_M = 6378137.0
"""The KITTI devkit's and pykitti's Earth radius (WGS 84's equatorial radius) in their Mercator projection."""
DEFAULT_ORIGIN = (45.0, -2.0)
"""The geodetic point (latitude, longitude in degrees) of the world origin without ``--oxts-origin``: at sea in
the Bay of Biscay, at the latitude that lights the default scene (``environment.latitude_deg`` 45)."""
MAX_LATITUDE_DEG = 85.0
"""The largest ``|latitude|`` of an origin: Mercator's north grows without bound towards the poles."""
GRAVITY = 9.80665
"""Standard gravity (m/s²), added to the accelerations as an accelerometer measures them."""
POS_ACCURACY_M = 0.02
"""``pos_accuracy`` written on every line (m; simulated truth: a fixed, RTK-like value)."""
VEL_ACCURACY_MPS = 0.01
"""``vel_accuracy`` written on every line (m/s)."""
STATUS = (4, 11, 6, 6, 6)
"""``navstat numsats posmode velmode orimode`` written on every line: those of KITTI's own oxts files."""


def parse_origin(value: Any, name: str = "--oxts-origin") -> tuple[float, float]:
    """``value`` (``"LAT,LON"`` or a pair of numbers in order: a tuple, a list or a numpy array) as ``(lat, lon)`` in
    degrees; :class:`~mmusv.errors.ConfigError` in one line naming ``name`` unless both are finite numbers (not
    true/false), ``|lat|`` <= :data:`MAX_LATITUDE_DEG` and ``|lon|`` <= 180. A set or a dict is refused: it has no
    order, so its latitude and longitude could be swapped."""
    lat, lon = DEFAULT_ORIGIN
    why = (
        f"{name} {arguments.shown(value)}: must be LAT,LON in degrees, LAT in [-{MAX_LATITUDE_DEG:g}, "
        f"{MAX_LATITUDE_DEG:g}] and LON in [-180, 180] (default {lat:g},{lon:g})"
    )
    if not isinstance(value, (str, Sequence, np.ndarray)) or isinstance(value, bytes):
        # a set or a dict has no order: {45.0, 10.0} iterated as (10.0, 45.0), latitude and longitude swapped
        raise ConfigError(f"{why}; a pair in order (a tuple or a list), not {type(value).__name__}")
    try:
        parts = value.split(",") if isinstance(value, str) else list(value)
        if not isinstance(value, str) and not all(arguments.is_number(p) for p in parts):
            raise TypeError  # a pair holds numbers: not true/false (read as 1 and 0), not texts
        got = [float(p) for p in parts]
    except (TypeError, ValueError):
        raise ConfigError(why) from None
    if len(got) != 2:
        raise ConfigError(why)
    lat, lon = got
    if not (math.isfinite(lat) and math.isfinite(lon) and abs(lat) <= MAX_LATITUDE_DEG and abs(lon) <= 180.0):
        raise ConfigError(why)
    return lat + 0.0, lon + 0.0


def mercator_scale(lat_deg: float) -> float:
    """The devkit's Mercator scale of a sequence whose first latitude is ``lat_deg``: ``cos(lat)``."""
    return float(np.cos(lat_deg * np.pi / 180.0))


def _mercator_y(lat_deg: float) -> float:
    return float(np.log(np.tan((90.0 + lat_deg) * np.pi / 360.0)))


def latlon(*, east: np.ndarray, north: np.ndarray, origin: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Latitudes and longitudes (degrees) of world points ``east``, ``north`` (metres, world origin at ``origin``)
    such that the devkit's Mercator projection with the scale of the first point's latitude gives them back:
    the scale is solved for by fixed-point iteration (it converges in a few steps: metres move it by ~1e-7)."""
    east = np.asarray(east, dtype=np.float64)
    north = np.asarray(north, dtype=np.float64)
    lat0, lon0 = origin
    y0 = _mercator_y(lat0)
    scale = mercator_scale(lat0)
    for _ in range(50):
        first = 360.0 / np.pi * np.arctan(np.exp(y0 + north.flat[0] / (scale * EARTH_RADIUS_M))) - 90.0
        again = mercator_scale(float(first))
        if again == scale:
            break
        scale = again
    lat = 360.0 / np.pi * np.arctan(np.exp(y0 + north / (scale * EARTH_RADIUS_M))) - 90.0
    lon = lon0 + east / (scale * EARTH_RADIUS_M) * 180.0 / np.pi
    return lat, lon


def euler_zyx(rotation: np.ndarray) -> tuple[float, float, float]:
    """``(roll, pitch, yaw)`` of a rotation matrix ``Rz(yaw)·Ry(pitch)·Rx(roll)`` (pitch in [-π/2, π/2])."""
    r = np.asarray(rotation, dtype=np.float64)
    yaw = math.atan2(r[1, 0], r[0, 0])
    pitch = math.atan2(-r[2, 0], math.hypot(r[2, 1], r[2, 2]))
    roll = math.atan2(r[2, 1], r[2, 2])
    return roll, pitch, yaw


def _rates(times: np.ndarray, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World velocity and acceleration of the poses' origins and the body-frame angular rate, ``(n, 3)`` each."""
    n = len(times)
    if n < 2:
        return np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
    vel = np.gradient(poses[:, :3, 3], times, axis=0)
    acc = np.gradient(vel, times, axis=0)
    return vel, acc, body_rates(times, poses[:, :3, :3])


def _number(v: float) -> str:
    """The shortest text that reads back as the same double (``repr``; -0 written 0)."""
    return repr(float(v) + 0.0)


def oxts_lines(times: Sequence[float], poses: Sequence[np.ndarray], origin: tuple[float, float]) -> list[str]:
    """The oxts lines (see the module docstring) of body → world poses ``(4, 4)`` at sim times ``times`` (s,
    increasing), the world origin at geodetic ``origin`` (``(lat, lon)``, degrees)."""
    t = np.asarray(times, dtype=np.float64)
    p = np.asarray(poses, dtype=np.float64).reshape(-1, 4, 4)
    if len(t) != len(p):
        raise ValueError(f"{len(t)} times for {len(p)} poses")
    if not len(t):
        return []
    lat, lon = latlon(east=p[:, 0, 3], north=p[:, 1, 3], origin=origin)
    vel, acc, omega = _rates(t, p)
    up = np.array([0.0, 0.0, GRAVITY])
    lines = []
    for k in range(len(t)):
        r = p[k, :3, :3]
        roll, pitch, yaw = euler_zyx(r)
        c, s = math.cos(yaw), math.sin(yaw)
        level = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])  # level frame → world
        v, f = vel[k], acc[k] + up
        values = [
            lat[k],
            lon[k],
            p[k, 2, 3],
            roll,
            pitch,
            yaw,
            v[1],
            v[0],
            *(level.T @ v),
            *(r.T @ f),
            *(level.T @ f),
            *omega[k],
            *(level.T @ r @ omega[k]),
            POS_ACCURACY_M,
            VEL_ACCURACY_MPS,
        ]
        lines.append(" ".join([*map(_number, values), *map(str, STATUS)]))
    return lines
