"""Frames and poses in one place: every change of frame mmusv makes goes through these functions.

mmusv's own frames are right-handed: world x east, y north, z up; vessel and sensor body frames x forward, y left,
z up; poses ``η = [x, y, z, roll, pitch, yaw]`` (metres, radians) with ``R = Rz(yaw)·Ry(pitch)·Rx(roll)``. Camera
optical frames (OpenCV) are x right, y down, z forward.

The CARLA / Unreal frame that OPV2V uses is left-handed: x forward, y right, z up, metres, angles in degrees,
poses ``[x, y, z, roll, yaw, pitch]``. Going from ours to CARLA mirrors the y axis of *both* the world and the
body frames: a point becomes ``S·p`` and a transform ``S·T·S`` with ``S = diag(1, -1, 1)``. Since
``S·Rz(a)·S = Rz(-a)``, ``S·Rx(a)·S = Rx(-a)`` and ``S·Ry(a)·S = Ry(a)``, and the CARLA loader rotation is
``Rz(yaw)·Ry(-pitch)·Rx(-roll)`` in right-handed terms, a pose ``[x, y, z, φ, θ, ψ]`` of ours is the CARLA pose

    ``[x, -y, z, roll = deg(φ), yaw = -deg(ψ), pitch = -deg(θ)]``

(:func:`carla_pose_from_eta`); for an arbitrary rotation :func:`carla_pose` reads the angles off ``S·R·S``.
Mirroring is its own inverse, so the same functions take CARLA data back.

Every function checks the shapes it documents and raises :class:`mmusv.InputError` naming the argument for any
other (or for values that are not numbers): ``(N, 4)`` homogeneous points, say, are refused, not read as
``4N / 3`` points of three.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from mmusv import arguments
from mmusv.errors import InputError

__all__ = [
    "BODY_TO_OPTICAL",
    "MIRROR_Y",
    "OPTICAL_IN_BODY",
    "body_rates",
    "carla_matrix",
    "carla_pose",
    "carla_pose_from_eta",
    "carla_rotation",
    "invert",
    "matrix_to_pose",
    "mirror_points",
    "mirror_transform",
    "pose_matrices",
    "transform_points",
    "translation",
    "wrap_deg",
    "wrap_rad",
    "x1_to_x2",
]

MIRROR_Y = np.diag([1.0, -1.0, 1.0, 1.0])
"""``(4, 4)`` float64 the y mirror ``S`` between mmusv's right-handed frames and CARLA's left-handed ones."""

BODY_TO_OPTICAL = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
"""``(3, 3)`` float64 rotation, camera body (x forward, y left, z up) → optical (x right, y down, z forward)."""

OPTICAL_IN_BODY = np.eye(4)
OPTICAL_IN_BODY[:3, :3] = BODY_TO_OPTICAL.T
"""``(4, 4)`` float64 optical frame → camera body frame (the inverse of :data:`BODY_TO_OPTICAL`, homogeneous)."""


def _floats(value: Any, *, name: str, tail: tuple[int, ...], what: str) -> np.ndarray:
    """:func:`mmusv.arguments.reals` with this module's :class:`InputError`."""
    return arguments.reals(value, name=name, tail=tail, what=what, error=InputError)


def _points(value: Any, *, name: str) -> np.ndarray:
    """``value`` as ``(N, 3)`` float64 points (one point ``(3,)`` becomes ``(1, 3)``), else an
    :class:`InputError`."""
    p = _floats(value, name=name, tail=(3,), what="(N, 3) points (or one (3,) point)")
    if p.ndim > 2:
        raise InputError(f"{name} must be (N, 3) points (or one (3,) point), got shape {p.shape}")
    return p.reshape(-1, 3)


def _transforms(value: Any, *, name: str) -> np.ndarray:
    return _floats(value, name=name, tail=(4, 4), what="(..., 4, 4) transforms")


def pose_matrices(eta: npt.ArrayLike) -> np.ndarray:
    """``(..., 4, 4)`` float64 body -> world matrices from poses ``η = [x, y, z, roll, pitch, yaw]`` ``(..., 6)``
    (metres, radians, R = Rz(yaw)·Ry(pitch)·Rx(roll))."""
    eta = _floats(eta, name="eta", tail=(6,), what="(..., 6) poses [x, y, z, roll, pitch, yaw]")
    cr, sr = np.cos(eta[..., 3]), np.sin(eta[..., 3])
    cp, sp = np.cos(eta[..., 4]), np.sin(eta[..., 4])
    cy, sy = np.cos(eta[..., 5]), np.sin(eta[..., 5])
    m = np.zeros((*eta.shape[:-1], 4, 4), dtype=np.float64)
    m[..., 0, 0] = cy * cp
    m[..., 0, 1] = cy * sp * sr - sy * cr
    m[..., 0, 2] = cy * sp * cr + sy * sr
    m[..., 1, 0] = sy * cp
    m[..., 1, 1] = sy * sp * sr + cy * cr
    m[..., 1, 2] = sy * sp * cr - cy * sr
    m[..., 2, 0] = -sp
    m[..., 2, 1] = cp * sr
    m[..., 2, 2] = cp * cr
    m[..., :3, 3] = eta[..., :3]
    m[..., 3, 3] = 1.0
    return m


def body_rates(times: npt.ArrayLike, rotations: npt.ArrayLike) -> np.ndarray:
    """``(n, 3)`` float64 angular velocity (rad/s) in the body frame of ``n`` body → world rotations ``(n, 3, 3)``
    at times ``times`` ``(n,)`` (seconds, increasing): the rotation vector of ``R_kᵀ·R_{k+1}`` over its step is
    the rate between two samples; a sample between two gets their mean weighted as :func:`numpy.gradient` weights
    an uneven grid's differences (second order), the first and last the one step beside them; zeros for fewer
    than two samples."""
    from scipy.spatial.transform import Rotation

    t = _floats(times, name="times", tail=(), what="(n,) times").reshape(-1)
    r = _floats(rotations, name="rotations", tail=(3, 3), what="(n, 3, 3) rotations").reshape(-1, 3, 3)
    if len(t) != len(r):
        raise InputError(f"times: {len(t)} times for {len(r)} rotations")
    n = len(t)
    if n < 2:
        return np.zeros((n, 3))
    steps = np.diff(t)
    if not np.all(steps > 0):
        raise InputError("times: must increase")
    try:
        rot = Rotation.from_matrix(r)
    except ValueError as exc:  # scipy's: a matrix of determinant <= 0 (a mirror, zeros) is no rotation
        raise InputError(f"rotations must be rotation matrices: {exc}") from None
    step_rates = (rot[:-1].inv() * rot[1:]).as_rotvec() / steps[:, None]  # R_k^T R_{k+1}: body axes
    omega = np.empty((n, 3))
    omega[0], omega[-1] = step_rates[0], step_rates[-1]
    if n > 2:
        before, after = steps[:-1, None], steps[1:, None]  # np.gradient's weights: h_s·forward + h_d·backward
        omega[1:-1] = (before * step_rates[1:] + after * step_rates[:-1]) / (before + after)
    return omega


def translation(v: npt.ArrayLike) -> np.ndarray:
    """``(4, 4)`` float64 pure translation by ``v`` ``(3,)`` metres."""
    t = _floats(v, name="v", tail=(), what="3 numbers (x, y, z)")
    if t.size != 3:
        raise InputError(f"v must be 3 numbers (x, y, z), got shape {t.shape}")
    m = np.eye(4)
    m[:3, 3] = t.reshape(3)
    return m


def matrix_to_pose(m: npt.ArrayLike) -> np.ndarray:
    """``(..., 6)`` float64 poses ``[x, y, z, roll, pitch, yaw]`` (metres, radians; roll and yaw in [-π, π]) of
    ``(..., 4, 4)`` rigid transforms, e.g. body → world (the inverse of :func:`pose_matrices`; pitch in [-π/2, π/2],
    roll = 0 at gimbal lock)."""
    m = _transforms(m, name="m")
    r = m[..., :3, :3]
    pitch = np.arcsin(np.clip(-r[..., 2, 0], -1.0, 1.0))
    lock = np.hypot(r[..., 0, 0], r[..., 1, 0]) < 1e-9
    yaw = np.where(lock, np.arctan2(-r[..., 0, 1], r[..., 1, 1]), np.arctan2(r[..., 1, 0], r[..., 0, 0]))
    roll = np.where(lock, 0.0, np.arctan2(r[..., 2, 1], r[..., 2, 2]))
    out: np.ndarray = np.concatenate([m[..., :3, 3], np.stack([roll, pitch, yaw], axis=-1)], axis=-1)
    return out


def invert(m: npt.ArrayLike) -> np.ndarray:
    """``(..., 4, 4)`` float64 inverse of ``(..., 4, 4)`` rigid transforms (Rᵀ, −Rᵀt): a → b becomes b → a."""
    m = _transforms(m, name="m")
    out = np.zeros_like(m)
    rt = np.swapaxes(m[..., :3, :3], -1, -2)
    out[..., :3, :3] = rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", rt, m[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def transform_points(m: npt.ArrayLike, points: npt.ArrayLike) -> np.ndarray:
    """``(N, 3)`` float64 points (``points``: ``(N, 3)``, or one ``(3,)`` point as ``(1, 3)``) moved by the
    ``(4, 4)`` transform ``m``."""
    t = _floats(m, name="m", tail=(4, 4), what="a (4, 4) transform")
    if t.ndim != 2:
        raise InputError(f"m must be a (4, 4) transform, got shape {t.shape}")
    p = _points(points, name="points")
    out: np.ndarray = p @ t[:3, :3].T + t[:3, 3]
    return out


def mirror_points(points: npt.ArrayLike) -> np.ndarray:
    """``(N, 3)`` float64 points with y negated (``points``: ``(N, 3)``, or one ``(3,)`` point as ``(1, 3)``):
    mmusv frame ↔ CARLA frame (the same for world and body frames)."""
    p: np.ndarray = _points(points, name="points").copy()
    p[:, 1] *= -1.0
    return p


def mirror_transform(m: npt.ArrayLike) -> np.ndarray:
    """``(..., 4, 4)`` float64 ``S·m·S`` for ``(..., 4, 4)`` transforms: a right-handed body → world transform as
    the left-handed (CARLA) one, metres (and back)."""
    out: np.ndarray = MIRROR_Y @ _transforms(m, name="m") @ MIRROR_Y
    return out


def carla_rotation(*, roll_deg: npt.ArrayLike, yaw_deg: npt.ArrayLike, pitch_deg: npt.ArrayLike) -> np.ndarray:
    """``(..., 3, 3)`` float64 rotation (left-handed CARLA frame) that CARLA/OpenCOOD loaders build from
    ``[roll, yaw, pitch]`` degrees, three arrays that broadcast together to ``...``."""
    angles = {"roll_deg": roll_deg, "yaw_deg": yaw_deg, "pitch_deg": pitch_deg}
    given = [_floats(a, name=k, tail=(), what="angles in degrees") for k, a in angles.items()]
    try:
        r, y, p = np.broadcast_arrays(*(np.radians(a) for a in given))
    except ValueError:
        shapes = ", ".join(f"{k} {a.shape}" for k, a in zip(angles, given, strict=True))
        raise InputError(f"roll_deg, yaw_deg and pitch_deg must broadcast together; got {shapes}") from None
    cr, sr, cy, sy, cp, sp = np.cos(r), np.sin(r), np.cos(y), np.sin(y), np.cos(p), np.sin(p)
    rows = [
        [cp * cy, cy * sp * sr - sy * cr, -cy * sp * cr - sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, -sy * sp * cr + cy * sr],
        [sp, -cp * sr, cp * cr],
    ]
    out: np.ndarray = np.stack([np.stack(np.broadcast_arrays(*row), axis=-1) for row in rows], axis=-2)
    return out


def carla_matrix(pose: npt.ArrayLike) -> np.ndarray:
    """``(..., 4, 4)`` float64 CARLA body → world transform (left-handed, metres) of ``[x, y, z, roll, yaw, pitch]``
    poses ``(..., 6)`` (metres, degrees)."""
    pose = _floats(pose, name="pose", tail=(6,), what="(..., 6) CARLA poses [x, y, z, roll, yaw, pitch]")
    m = np.zeros((*pose.shape[:-1], 4, 4), dtype=np.float64)
    m[..., :3, :3] = carla_rotation(roll_deg=pose[..., 3], yaw_deg=pose[..., 4], pitch_deg=pose[..., 5])
    m[..., :3, 3] = pose[..., :3]
    m[..., 3, 3] = 1.0
    return m


def carla_pose(m: npt.ArrayLike) -> np.ndarray:
    """``(..., 6)`` float64 CARLA pose ``[x, y, z, roll, yaw, pitch]`` (metres, degrees) of a right-handed body → world
    transform ``m`` ``(..., 4, 4)`` in mmusv frames: the mirrored transform ``S·m·S`` read with the loader's
    rotation convention, so that ``carla_matrix(carla_pose(m)) == S·m·S``."""
    c = mirror_transform(m)
    r = c[..., :3, :3]
    pitch = np.arcsin(np.clip(r[..., 2, 0], -1.0, 1.0))
    lock = np.hypot(r[..., 0, 0], r[..., 1, 0]) < 1e-9
    yaw = np.where(lock, np.arctan2(-r[..., 0, 1], r[..., 1, 1]), np.arctan2(r[..., 1, 0], r[..., 0, 0]))
    roll = np.where(lock, 0.0, np.arctan2(-r[..., 2, 1], r[..., 2, 2]))
    out: np.ndarray = np.concatenate([c[..., :3, 3], np.degrees(np.stack([roll, yaw, pitch], axis=-1))], axis=-1)
    return out


def carla_pose_from_eta(eta: npt.ArrayLike) -> np.ndarray:
    """``(..., 6)`` float64 CARLA pose (metres, degrees) of mmusv poses ``[x, y, z, roll, pitch, yaw]``
    ``(..., 6)`` (metres, radians): ``[x, -y, z, deg(roll), -deg(yaw), -deg(pitch)]`` (closed form of
    :func:`carla_pose` for Euler poses)."""
    eta = _floats(eta, name="eta", tail=(6,), what="(..., 6) poses [x, y, z, roll, pitch, yaw]")
    out: np.ndarray = np.stack(
        [
            eta[..., 0],
            -eta[..., 1],
            eta[..., 2],
            np.degrees(eta[..., 3]),
            -np.degrees(eta[..., 5]),
            -np.degrees(eta[..., 4]),
        ],
        axis=-1,
    )
    return out


def x1_to_x2(pose1: npt.ArrayLike, pose2: npt.ArrayLike) -> np.ndarray:
    """``(4, 4)`` float64 transform (left-handed, metres) from the frame of CARLA pose ``pose1`` to that of
    ``pose2``, each ``(6,)`` ``[x, y, z, roll, yaw, pitch]`` metres, degrees (``inv(T2)·T1``)."""
    out: np.ndarray = invert(carla_matrix(pose2)) @ carla_matrix(pose1)
    return out


def wrap_deg(a: npt.ArrayLike) -> np.ndarray:
    """float64 angles in degrees wrapped to (-180, 180], the shape of ``a``."""
    w: np.ndarray = 180.0 - np.mod(180.0 - _floats(a, name="a", tail=(), what="angles in degrees"), 360.0)
    return w


def wrap_rad(a: npt.ArrayLike) -> np.ndarray:
    """float64 angles in radians wrapped to (-π, π], the shape of ``a``."""
    w: np.ndarray = math.pi - np.mod(math.pi - _floats(a, name="a", tail=(), what="angles in radians"), 2 * math.pi)
    return w
