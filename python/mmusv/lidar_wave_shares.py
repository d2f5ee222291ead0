"""The LiDAR's wave-occlusion share of a frame's 3D boxes (:func:`lidar_wave_shares`): every box's beams selected,
cast against its vessel alone and counted against the full scene in one pass, with the LiDAR's own rule for a box
none of whose beams reaches its part above the still water level. The share itself, and the rule it follows, are
:mod:`mmusv.wave_occlusion`'s; :func:`mmusv.annotate.annotate_agent` records the result.

Frames: world x east, y north, z up, metres; a LiDAR pose is the ``(4, 4)`` rigid LiDAR → world transform.
"""

from __future__ import annotations

import numpy as np

from mmusv.scene import Scene
from mmusv.silhouettes import SilhouetteCache
from mmusv.wave_occlusion import BeamAngles, exposed_hidden_boxes, lidar_beam_rays, lidar_boxes_beams, share

__all__ = ["lidar_wave_shares"]


def lidar_wave_shares(
    scene: Scene,
    pattern: np.ndarray,
    angles: BeamAngles,
    lidar_pose: np.ndarray,
    corners: np.ndarray,
    assets: list[str],
    poses: list[np.ndarray],
    silhouettes: SilhouetteCache,
    lidar_beams: np.ndarray | None,
    max_range_m: float,
) -> list[float]:
    """The LiDAR's wave-occlusion share of each of ``B`` boxes (``corners`` ``(B, 8, 3)`` world, of vessels
    ``assets`` at ``poses``), all boxes' beams selected, cast against their vessels and counted in one pass:
    the shares :func:`~mmusv.wave_occlusion.share` gives box by box."""
    beams, starts = lidar_boxes_beams(angles, lidar_pose=lidar_pose, corners_world=corners)
    o, d = lidar_beam_rays(pattern, lidar_pose=lidar_pose, beams=beams)
    t = silhouettes.distances_boxes(assets, poses=poses, origins=o, directions=d, starts=starts)
    first = None if lidar_beams is None else np.asarray(lidar_beams)[beams]
    # The LiDAR's vertical field of view is its border, as the image's is a camera's: a box whose part above the
    # still level no beam reaches is met only on its lower hull, which a calm sea hides too; none of it is exposed.
    whole_when_low = _beams_reach_above(o, d, corners, starts, max_range_m)
    n_exposed, n_hidden = exposed_hidden_boxes(
        scene,
        origins=o,
        directions=d,
        vessel_t=t,
        starts=starts,
        scene_instance=first,
        max_range_m=max_range_m,
        whole_when_low=whole_when_low,
    )
    return [share(e, h) for e, h in zip(n_exposed, n_hidden, strict=True)]


def _beams_reach_above(
    origins: np.ndarray, directions: np.ndarray, corners: np.ndarray, starts: np.ndarray, max_range_m: float
) -> np.ndarray:
    """``(B,)`` bool: whether any of box ``b``'s rays (rows ``starts[b]:starts[b + 1]`` of the world ``origins``
    and ``directions``, ``(N, 3)``) passes through the part of the box above the still level (world z > 0) within
    ``max_range_m`` of its origin; true for a box wholly below that level (a craft in a trough: nothing above to
    reach). ``corners`` ``(B, 8, 3)`` world, in :func:`~mmusv.boxes3d.box_corners`' order (corner 0 at (−x, −y,
    −z), bits 0, 1, 2 of ``i`` the signs of x, y, z), so box ``b`` is ``corners[b, 0] + u·ex + v·ey + w·ez`` over
    ``[0, 1]³``."""
    n_boxes = corners.shape[0]
    top: np.ndarray = corners[:, :, 2].max(axis=1) > 0.0
    if origins.shape[0] == 0:
        return ~top
    box = np.repeat(np.arange(n_boxes), np.diff(starts))
    c0 = corners[box, 0]
    axes = np.stack([corners[box, 1] - c0, corners[box, 2] - c0, corners[box, 4] - c0], axis=1)  # (N, 3 axes, 3)
    sq = np.maximum(np.einsum("nij,nij->ni", axes, axes), 1e-12)
    o = np.asarray(origins, dtype=np.float64)
    d = np.asarray(directions, dtype=np.float64)
    a = np.einsum("nij,nj->ni", axes, o - c0) / sq  # the origin in the box's [0, 1]^3 coordinates
    b = np.einsum("nij,nj->ni", axes, d) / sq  # the direction's rate along each axis
    with np.errstate(divide="ignore", invalid="ignore"):
        t0, t1 = -a / b, (1.0 - a) / b
    lo, hi = np.minimum(t0, t1), np.maximum(t0, t1)
    flat = b == 0.0  # parallel to a slab: inside it for every t or for none
    inside = (a >= 0.0) & (a <= 1.0)
    lo = np.where(flat, np.where(inside, -np.inf, np.inf), lo)
    hi = np.where(flat, np.where(inside, np.inf, -np.inf), hi)
    enter = np.maximum(lo.max(axis=1), 0.0)
    leave = np.minimum(hi.min(axis=1), max_range_m / np.linalg.norm(d, axis=1))
    # above the still level: o_z + t d_z > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        cross = -o[:, 2] / d[:, 2]
    up, down = d[:, 2] > 0.0, d[:, 2] < 0.0
    enter = np.where(up, np.maximum(enter, cross), enter)
    leave = np.where(down, np.minimum(leave, cross), leave)
    level = (d[:, 2] != 0.0) | (o[:, 2] > 0.0)
    hit = level & (enter < leave)
    reached = np.bincount(box[hit], minlength=n_boxes) > 0
    out: np.ndarray = reached | ~top
    return out
