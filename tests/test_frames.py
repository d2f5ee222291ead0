"""mmusv.frames: pose matrices, the mmusv ↔ CARLA (OPV2V) mirror and the derived angle mapping.

The CARLA loader rotation is written out here again from the OPV2V/OpenCOOD formula, independently of
``mmusv.frames.carla_rotation``, so the mapping is checked against the loaders' convention, not against itself.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from mmusv import frames
from mmusv.world.build import pose_matrices as reexported
from scipy.spatial.transform import Rotation

S = np.diag([1.0, -1.0, 1.0])


def loader_matrix(pose: list[float] | np.ndarray) -> np.ndarray:
    """OpenCOOD ``x_to_world``: [x, y, z, roll, yaw, pitch] (degrees) → 4×4."""
    x, y, z, roll, yaw, pitch = (float(v) for v in pose)
    c_y, s_y = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    c_r, s_r = math.cos(math.radians(roll)), math.sin(math.radians(roll))
    c_p, s_p = math.cos(math.radians(pitch)), math.sin(math.radians(pitch))
    m = np.identity(4)
    m[0, 3], m[1, 3], m[2, 3] = x, y, z
    m[0, 0] = c_p * c_y
    m[0, 1] = c_y * s_p * s_r - s_y * c_r
    m[0, 2] = -c_y * s_p * c_r - s_y * s_r
    m[1, 0] = s_y * c_p
    m[1, 1] = s_y * s_p * s_r + c_y * c_r
    m[1, 2] = -s_y * s_p * c_r + c_y * s_r
    m[2, 0] = s_p
    m[2, 1] = -c_p * s_r
    m[2, 2] = c_p * c_r
    return m


def random_eta(rng: np.random.Generator, n: int) -> np.ndarray:
    xyz = rng.uniform(-500, 500, (n, 3))
    ang = np.column_stack(
        [rng.uniform(-math.pi, math.pi, n), rng.uniform(-1.5, 1.5, n), rng.uniform(-math.pi, math.pi, n)]
    )
    return np.column_stack([xyz, ang])


def test_pose_matrices_reexported_and_rigid() -> None:
    assert reexported is frames.pose_matrices
    eta = random_eta(np.random.default_rng(0), 50)
    m = frames.pose_matrices(eta)
    r = m[:, :3, :3]
    np.testing.assert_allclose(r @ np.swapaxes(r, 1, 2), np.broadcast_to(np.eye(3), r.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(r), 1.0, atol=1e-12)
    ref = Rotation.from_euler("ZYX", eta[:, [5, 4, 3]]).as_matrix()  # intrinsic z-y'-x'' = Rz·Ry·Rx
    np.testing.assert_allclose(r, ref, atol=1e-12)


def test_matrix_to_pose_inverts_pose_matrices() -> None:
    eta = random_eta(np.random.default_rng(1), 200)
    np.testing.assert_allclose(frames.matrix_to_pose(frames.pose_matrices(eta)), eta, atol=1e-9)
    lock = np.array([1.0, 2.0, 3.0, 0.0, math.pi / 2, 0.7])
    np.testing.assert_allclose(
        frames.pose_matrices(frames.matrix_to_pose(frames.pose_matrices(lock))), frames.pose_matrices(lock), atol=1e-9
    )


def test_invert_and_transform_points() -> None:
    m = frames.pose_matrices(random_eta(np.random.default_rng(2), 20))
    np.testing.assert_allclose(frames.invert(m) @ m, np.broadcast_to(np.eye(4), m.shape), atol=1e-9)
    p = np.random.default_rng(3).normal(size=(10, 3))
    back = frames.transform_points(frames.invert(m[0]), frames.transform_points(m[0], p))
    np.testing.assert_allclose(back, p, atol=1e-9)


@pytest.mark.parametrize("seed", range(3))
def test_carla_pose_reproduces_the_mirrored_transform_with_the_loader_rotation(seed: int) -> None:
    eta = random_eta(np.random.default_rng(seed), 300)
    m = frames.pose_matrices(eta)
    poses = frames.carla_pose(m)
    np.testing.assert_allclose(poses, frames.carla_pose_from_eta(eta), atol=1e-7)  # closed form = matrix form
    for pose, mi in zip(poses, m, strict=True):
        mirrored = np.eye(4)
        mirrored[:3, :3] = S @ mi[:3, :3] @ S
        mirrored[:3, 3] = S @ mi[:3, 3]
        np.testing.assert_allclose(loader_matrix(pose), mirrored, atol=1e-9)
    np.testing.assert_allclose(frames.carla_matrix(poses), frames.mirror_transform(m), atol=1e-9)


def test_carla_pose_of_arbitrary_rotations_and_gimbal_lock() -> None:
    rots = Rotation.random(200, random_state=4).as_matrix()
    m = np.tile(np.eye(4), (200, 1, 1))
    m[:, :3, :3] = rots
    m[:, :3, 3] = np.random.default_rng(5).normal(size=(200, 3))
    for pose, mi in zip(frames.carla_pose(m), m, strict=True):
        np.testing.assert_allclose(loader_matrix(pose), frames.mirror_transform(mi), atol=1e-9)
    down = frames.pose_matrices(np.array([0.0, 0.0, 120.0, 0.0, math.pi / 2, 0.3]))  # a camera looking straight down
    np.testing.assert_allclose(loader_matrix(frames.carla_pose(down)), frames.mirror_transform(down), atol=1e-9)


def test_angle_mapping_meaning() -> None:
    # heading north (our yaw +90°, counter-clockwise from east) is CARLA yaw -90° (clockwise from x).
    pose = frames.carla_pose_from_eta(np.array([10.0, 20.0, 1.0, 0.0, 0.0, math.pi / 2]))
    np.testing.assert_allclose(pose, [10.0, -20.0, 1.0, 0.0, -90.0, 0.0], atol=1e-12)
    # bow up: our pitch is negative about y-left; CARLA pitch positive; the bow point rises in both.
    eta = np.array([0.0, 0.0, 0.0, 0.0, -0.2, 0.0])
    carla = frames.carla_pose_from_eta(eta)
    assert carla[5] > 0
    bow = frames.transform_points(loader_matrix(carla), np.array([[1.0, 0.0, 0.0]]))
    assert bow[0, 2] > 0
    # a roll moves the starboard side (our -y, CARLA +y) to the same place in both frames
    eta = np.array([0.0, 0.0, 0.0, 0.3, 0.0, 0.0])
    ours = frames.transform_points(frames.pose_matrices(eta), np.array([[0.0, -1.0, 0.0]]))
    theirs = frames.transform_points(loader_matrix(frames.carla_pose_from_eta(eta)), np.array([[0.0, 1.0, 0.0]]))
    np.testing.assert_allclose(frames.mirror_points(ours), theirs, atol=1e-12)


def test_points_and_x1_to_x2_commute_with_the_mirror() -> None:
    rng = np.random.default_rng(6)
    a, b = frames.pose_matrices(random_eta(rng, 2))
    p = rng.normal(size=(20, 3)) * 30
    # a point in frame a moved to frame b: mirror after = mirror before and use the CARLA poses
    ours = frames.transform_points(frames.invert(b) @ a, p)
    t = np.linalg.inv(loader_matrix(frames.carla_pose(b))) @ loader_matrix(frames.carla_pose(a))
    np.testing.assert_allclose(
        frames.mirror_points(ours), frames.transform_points(t, frames.mirror_points(p)), atol=1e-8
    )
    np.testing.assert_allclose(frames.x1_to_x2(frames.carla_pose(a), frames.carla_pose(b)), t, atol=1e-9)
    np.testing.assert_allclose(frames.mirror_points(frames.mirror_points(p)), p)


def test_wrap() -> None:
    np.testing.assert_allclose(
        frames.wrap_deg([180.0, -180.0, 190.0, -190.0, 360.0]), [180.0, 180.0, -170.0, 170.0, 0.0]
    )
    np.testing.assert_allclose(frames.wrap_rad([3 * math.pi, -math.pi / 2]), [math.pi, -math.pi / 2])


def test_carla_rotation_broadcasts_its_angles() -> None:
    """One roll and pitch with several yaws is the stack of each yaw's rotation (the rows were broadcast one by one,
    and the last row, without yaw, refused arrays of other shapes)."""
    together = frames.carla_rotation(roll_deg=10.0, yaw_deg=[0.0, 45.0, -120.0], pitch_deg=-5.0)
    one_by_one = [frames.carla_rotation(roll_deg=10.0, yaw_deg=y, pitch_deg=-5.0) for y in (0.0, 45.0, -120.0)]
    assert together.shape == (3, 3, 3)
    np.testing.assert_array_equal(together, np.stack(one_by_one))
