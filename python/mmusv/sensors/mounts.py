"""Where a sensor sits on a vessel: the ``(4, 4)`` sensor → body transform of a :class:`~mmusv.sensors.config.Mount`
on a vessel asset (:func:`mount_matrix`), a camera's mount where its config gives none (:func:`camera_mount`), and
the test that a sensor's origin is not inside the hull
(:func:`inside_mesh`: a sensor there would see nothing but the hull's inside).

Frames: vessel body x forward, y left, z up (metres); angles roll, pitch, yaw in degrees (applied as in
:func:`mmusv.world.build.pose_matrices`).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from mmusv.errors import ConfigError, InputError
from mmusv.sensors.config import CameraConfig, Mount
from mmusv.world.build import pose_matrices
from mmusv.world.vessels import VesselAsset

__all__ = ["camera_mount", "inside_mesh", "mount_matrix", "rpy_matrix"]


def rpy_matrix(xyz: tuple[float, float, float], rpy_deg: tuple[float, float, float]) -> np.ndarray:
    """``(4, 4)`` float64 transform translating by ``xyz`` (m) and rotating by roll, pitch, yaw ``rpy_deg`` (°)."""
    r, p, y = (math.radians(a) for a in rpy_deg)
    return pose_matrices(np.array([*xyz, r, p, y], dtype=np.float64))


_TURNED = {"camera_left": 90.0, "camera_rear": 180.0, "camera_right": -90.0}
"""The mount points named for a direction, and the yaw (degrees) of the hull-top fall-back of each
(:func:`mount_matrix`)."""


def camera_mount(asset: VesselAsset, camera: CameraConfig) -> Mount:
    """The mount of ``camera`` on ``asset``: its own, when its config gives one; else the asset's mount point named
    after it (``camera_<name>``: a camera ``left`` sits on ``camera_left``, looking left), else its ``camera_front``,
    else the top of the hull turned as the name says (:func:`mount_matrix`'s fall-back for ``camera_<name>``). Before,
    a camera without a mount sat at the vessel origin, midship at the waterline: under the crests at W3, it labelled
    the water above it sky and saw no vessel.

    A mount written out in full as the default (``point`` null, ``xyz`` and ``rpy_deg`` zero, all three given) counts
    as none: a scenario written out in full (the run's resolved ``scenario.yaml``, the recording's ``scenario``
    metadata) gives every camera's mount so, and read back it put the camera at the vessel origin, where the run that
    wrote it had it on its mount point (with the same config hash). A mount that gives only some of them, such as
    ``{xyz: [0, 0, 0]}``, is the user's own: the vessel origin.

    A camera named ``rear``, ``left`` or ``right`` whose point the asset lacks takes the hull's top turned as its name
    says, not ``camera_front``: on an asset that gives ``camera_front`` alone (a user's own), a surround rig's four
    cameras all looked ahead from the bow."""
    written_out = camera.mount.model_fields_set == set(Mount.model_fields)  # every field given, as a dump does
    if "mount" in camera.model_fields_set and not (written_out and camera.mount.model_dump() == Mount().model_dump()):
        return camera.mount
    own = f"camera_{camera.name}"
    if own in asset.mounts or own in _TURNED or "camera_front" not in asset.mounts:
        return Mount(point=own)
    return Mount(point="camera_front")


def mount_matrix(asset: VesselAsset, mount: Mount, *, where: str) -> np.ndarray:
    """``(4, 4)`` float64 sensor → vessel body transform (metres; both frames x forward, y left, z up) of
    ``mount`` on ``asset`` (see :class:`~mmusv.sensors.config.Mount`)."""
    base = np.eye(4)
    if mount.point is not None:
        if mount.point in asset.mounts:
            mp = asset.mounts[mount.point]
            base = rpy_matrix(mp.xyz, mp.rpy_deg)
        else:
            # Fall back to the top of the hull: above the deck, looking where the mount name says.
            yaw = _TURNED.get(mount.point, 0.0)
            top = float(asset.bbox[1, 2]) + 0.5
            base = rpy_matrix((0.0, 0.0, top), (0.0, 0.0, yaw))
    m: np.ndarray = base @ rpy_matrix(mount.xyz, mount.rpy_deg)
    if not np.all(np.isfinite(m)):
        raise ConfigError(f"invalid config {where}: the mount is not a finite pose")
    return m


MAX_INSIDE_RAYS = 1024
"""Most rays :func:`inside_mesh` casts (each re-cast up to 64 times)."""


def inside_mesh(vertices: np.ndarray, faces: np.ndarray, *, point: np.ndarray, rays: int = 9) -> bool:
    """Whether ``point`` lies inside the closed (union of) mesh(es) ``vertices``/``faces`` (same frame).

    Along each of ``rays`` directions every crossing is found by re-casting past the previous hit; the winding
    number is (back-face exits − front-face entries). The point is inside when most rays give a positive one.
    ``point``: 3 finite coordinates; ``rays``: a whole number in ``1..=MAX_INSIDE_RAYS``.
    """
    from mmusv.scene import Scene

    if isinstance(rays, bool) or not isinstance(rays, (int, np.integer)) or not 1 <= rays <= MAX_INSIDE_RAYS:
        raise InputError(f"rays = {rays!r}: must be a whole number in 1..{MAX_INSIDE_RAYS}")
    rays = int(rays)
    try:
        p = np.asarray(point, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise InputError(f"point must be 3 finite coordinates (x, y, z): {e}") from None
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise InputError(f"point must be 3 finite coordinates (x, y, z), got shape {p.shape}")

    scene = Scene()
    scene.add_instance(scene.add_mesh(vertices, faces, classes=0))
    dirs = _sphere_directions(rays)
    origin = np.tile(p, (rays, 1))
    winding = np.zeros(rays, dtype=np.int64)
    active = np.ones(rays, dtype=bool)
    for _ in range(64):
        if not active.any():
            break
        hits = scene.cast_rays(origin[active], dirs[active])
        idx = np.nonzero(active)[0]
        hit = hits.hit
        winding[idx[hit]] += np.where(hits.backface[hit], 1, -1)
        active[idx[~hit]] = False
        step = hits.distance[hit].astype(np.float64) + 1e-4
        origin[idx[hit]] += dirs[idx[hit]] * step[:, None]
    return bool(np.count_nonzero(winding > 0) * 2 > rays)


def _sphere_directions(n: int) -> npt.NDArray[np.float64]:
    """``n`` unit vectors spread over the sphere (Fibonacci lattice)."""
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    r = np.sqrt(1 - z * z)
    phi = i * math.pi * (3 - math.sqrt(5))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
