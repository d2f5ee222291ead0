"""Wave occlusion: the share of a target hidden by the sea surface, per annotated box.

A target's *exposed silhouette* is the set of a sensor's rays that meet the vessel when it is alone in the
world (:class:`~mmusv.annotate.SilhouetteCache`) at a point above the still water level (world z > 0): the part
of the hull a flat calm sea would never hide. Its wave-occlusion share is the fraction of those rays that the
full scene stops at the water first — a crest in front, or the local surface over that part of the hull. With a
flat sea the share is 0 by construction; it is only computed where the scene has a displaced wave surface
(:meth:`~mmusv.scene.Scene.set_wave_surface`).

* Cameras: the rays of the box's pixels; "stopped at the water" reads the captured instance image (the water
  instance there).
* LiDAR: the LiDAR's own beams within the box's angular extent (azimuth and elevation of its corners seen from
  the LiDAR), cast against the vessel alone and then against the full scene; in a capture the full scene's
  answer is the one the LiDAR's own cast found (:attr:`~mmusv.simulation.AgentCapture.lidar_beams`), read
  rather than cast again. Only the part of the vessel within the LiDAR's range counts.

Frames: world x east, y north, z up, metres; directions need not be unit length.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from mmusv.scene import Scene

__all__ = [
    "BeamAngles",
    "exposed_hidden",
    "lidar_beam_rays",
    "lidar_box_beams",
    "lidar_box_rays",
    "pattern_angles",
    "share",
]


def share(exposed: int, hidden: int) -> float:
    """``hidden / exposed``, 0 for an empty exposed silhouette."""
    return float(hidden / exposed) if exposed else 0.0


def exposed_hidden(
    scene: Scene,
    origins: npt.NDArray[np.float32],
    directions: npt.NDArray[np.float32],
    vessel_t: npt.NDArray[np.float32],
    *,
    scene_instance: npt.NDArray[np.int32] | None = None,
    max_range_m: float = float("inf"),
) -> tuple[int, int]:
    """``(exposed, hidden)`` ray counts of one target (see the module docstring).

    Args:
        scene: the full scene, with its sea and wave surface set.
        origins, directions: ``(N, 3)`` float32 world rays (any non-zero direction length).
        vessel_t: ``(N,)`` float32 distance (in units of each direction's length) at which each ray meets the
            vessel alone, ``inf`` where it misses it.
        scene_instance: ``(N,)`` int32 instance each ray meets first in the full scene, when already known (a
            camera's instance image, a LiDAR's beams); else the rays are cast here.
        max_range_m: only the part of the vessel within this distance (metres) of the origins counts (a LiDAR's
            range: what lies beyond it is neither seen nor hidden).
    """
    o = np.asarray(origins, dtype=np.float64)
    d = np.asarray(directions, dtype=np.float64)
    t = np.asarray(vessel_t, dtype=np.float64)
    hit = np.isfinite(t)
    z = o[:, 2] + d[:, 2] * np.where(hit, t, 0.0)
    exposed = hit & (z > 0.0)
    if np.isfinite(max_range_m):
        exposed &= np.where(hit, t, 0.0) * np.linalg.norm(d, axis=1) <= max_range_m
    n = int(np.count_nonzero(exposed))
    water = scene.sea_instance
    if n == 0 or water is None or scene.wave_top is None:
        return n, 0
    if scene_instance is None:
        hits = scene.cast_rays(o[exposed].astype(np.float32), d[exposed].astype(np.float32))
        first = hits.instance_id
    else:
        first = np.asarray(scene_instance)[exposed]
    return n, int(np.count_nonzero(first == water))


class BeamAngles(NamedTuple):
    """A LiDAR pattern's beam angles (:func:`pattern_angles`): ``az``, ``el`` ``(M,)`` radians in pattern order,
    and the beams sorted by azimuth (``order``, ``az_sorted``) to find a box's beams without testing them all."""

    az: npt.NDArray[np.float64]
    el: npt.NDArray[np.float64]
    order: npt.NDArray[np.int64]
    az_sorted: npt.NDArray[np.float64]


_ANGLES: dict[tuple[tuple[int, ...], int], tuple[npt.NDArray[np.float32], BeamAngles]] = {}
_LAST: dict[int, tuple[npt.NDArray[np.float32], BeamAngles]] = {}


def pattern_angles(pattern: npt.NDArray[np.float32]) -> BeamAngles:
    """The :class:`BeamAngles` (azimuth, elevation, radians) of a LiDAR's unit beam directions ``pattern``
    ``(M, 3)`` (LiDAR frame), to pass to :func:`lidar_box_rays`. Remembered by content: a rig's pattern is worked
    out once, not per frame; a read-only array that owns its data (``Agent.lidar_pattern``), passed again, is
    recognised by identity without hashing it."""
    same = _LAST.get(id(pattern))
    if same is not None and same[0] is pattern and _frozen(pattern):
        return same[1]  # the very (read-only) array of the last call: a rig's pattern, passed every frame
    p = np.ascontiguousarray(pattern, dtype=np.float32)
    key = (p.shape, hash(p.tobytes()))
    hit = _ANGLES.get(key)
    if hit is not None and np.array_equal(hit[0], p):  # a hash is not proof: the pattern itself is compared
        _remember(pattern, hit[1])
        return hit[1]
    q = p.astype(np.float64)
    az = np.arctan2(q[:, 1], q[:, 0])
    el = np.arctan2(q[:, 2], np.hypot(q[:, 0], q[:, 1]))
    order = np.argsort(az, kind="stable")
    out = BeamAngles(az, el, order, az[order])
    if len(_ANGLES) >= 16:
        _ANGLES.clear()
    _ANGLES[key] = (p.copy(), out)
    _remember(pattern, out)
    return out


def _frozen(a: object) -> bool:
    """Whether ``a`` is an array whose values cannot change: read-only and owning its data (not a view)."""
    return isinstance(a, np.ndarray) and not a.flags.writeable and a.flags.owndata


def _remember(pattern: npt.NDArray[np.float32], angles: BeamAngles) -> None:
    """Keeps ``pattern`` (when :func:`_frozen`: it cannot change under the cache) and its angles for the
    identity check of :func:`pattern_angles`; the reference held keeps its ``id`` from being reused."""
    if _frozen(pattern):
        if len(_LAST) >= 16:
            _LAST.clear()
        _LAST[id(pattern)] = (pattern, angles)


def lidar_box_rays(
    pattern: npt.NDArray[np.float32],
    angles: BeamAngles,
    lidar_pose: npt.NDArray[np.float64],
    corners_world: npt.NDArray[np.float64],
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
    """The LiDAR's world rays ``(origins, directions)`` (each ``(K, 3)`` float32, in pattern order) whose
    direction lies within the azimuth and elevation extent of the box ``corners_world`` ``(8, 3)`` seen from the
    LiDAR at ``lidar_pose`` ``(4, 4)`` LiDAR → world; ``pattern`` ``(M, 3)`` unit directions in the LiDAR frame,
    ``angles`` their :func:`pattern_angles`. The rays of :func:`lidar_box_beams`' beams."""
    return lidar_beam_rays(pattern, lidar_pose, lidar_box_beams(angles, lidar_pose, corners_world))


def lidar_box_beams(
    angles: BeamAngles,
    lidar_pose: npt.NDArray[np.float64],
    corners_world: npt.NDArray[np.float64],
) -> npt.NDArray[np.int64]:
    """``(K,)`` pattern indices (ascending) of the beams whose direction lies within the azimuth and elevation
    extent of the box ``corners_world`` ``(8, 3)`` seen from the LiDAR at ``lidar_pose`` ``(4, 4)`` LiDAR →
    world; ``angles`` the pattern's :func:`pattern_angles`."""
    inv = np.linalg.inv(lidar_pose)
    c = corners_world @ inv[:3, :3].T + inv[:3, 3]
    az = np.arctan2(c[:, 1], c[:, 0])
    el = np.arctan2(c[:, 2], np.hypot(c[:, 0], c[:, 1]))
    # Azimuths relative to the box's mean direction, so a box straddling ±π is one interval.
    mid = np.arctan2(np.sin(az).mean(), np.cos(az).mean())
    rel = np.angle(np.exp(1j * (az - mid)))
    # Candidates: the beams whose azimuth lies in the window (a margin wider, wrapped into [-π, π]) by binary
    # search on the sorted azimuths; the exact test below then keeps what testing every beam would keep.
    lo, hi = mid + rel.min() - 1e-6, mid + rel.max() + 1e-6
    cand = _azimuth_window(angles, lo, hi)
    paz, pel = angles.az[cand], angles.el[cand]
    near = (pel >= el.min()) & (pel <= el.max())
    prel = np.angle(np.exp(1j * (paz[near] - mid)))
    idx: npt.NDArray[np.int64] = cand[near][(prel >= rel.min()) & (prel <= rel.max())]
    return idx


def lidar_beam_rays(
    pattern: npt.NDArray[np.float32], lidar_pose: npt.NDArray[np.float64], beams: npt.NDArray[np.int64]
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
    """The world rays ``(origins, directions)`` (each ``(K, 3)`` float32) of the pattern's ``beams`` (indices)
    from the LiDAR at ``lidar_pose`` ``(4, 4)`` LiDAR → world."""
    # Only the selected beams are widened to float64 (the same values as widening the whole pattern first).
    dirs = (np.asarray(pattern)[beams].astype(np.float64) @ lidar_pose[:3, :3].T).astype(np.float32)
    origins = np.tile(lidar_pose[:3, 3].astype(np.float32), (dirs.shape[0], 1))
    return origins, dirs


def _azimuth_window(angles: BeamAngles, lo: float, hi: float) -> npt.NDArray[np.int64]:
    """Pattern indices (ascending) of the beams with azimuth in ``[lo, hi]`` taken modulo 2π (all beams when the
    window spans a whole turn)."""
    width = hi - lo
    if width >= 2 * np.pi:
        return np.arange(angles.az.shape[0])
    start = (lo + np.pi) % (2 * np.pi) - np.pi  # in [-π, π)
    end = start + width
    s = angles.az_sorted
    a = int(np.searchsorted(s, start, side="left"))
    if end <= np.pi:
        idx = angles.order[a : int(np.searchsorted(s, end, side="right"))]
    else:  # the window wraps past π
        b = int(np.searchsorted(s, end - 2 * np.pi, side="right"))
        idx = np.concatenate([angles.order[a:], angles.order[:b]])
    return np.sort(idx)
