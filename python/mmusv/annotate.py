"""Per-agent annotations derived from the world state and the agent's own captures.

For every agent (USV) and frame, for every other vessel whose bird's-eye-view footprint comes within the LiDAR's
range (:func:`footprint_in_range`: a long ship whose centre lies beyond it but whose stern is near gets its box; the
agent's own hull is never a target):
* a 3D box in the agent's LiDAR frame (centre, size = length/beam/height, rotation quaternion xyzw, yaw) with the
  number of LiDAR points on the vessel (exact: points carry instance ids) and its range;
* the vessel's ``role`` (``target``, ``usv`` — another instrumented USV, never a detection target — or
  ``moored``) and ``static`` flag (moored ships, and scenario vessels that never move), so users can filter;
* an ego-centric BEV box: the 3D box's footprint in the LiDAR frame's xy plane (x, y, length, width, yaw: the 3D
  box's centre, first two sizes and yaw, counter-clockwise from the LiDAR's x axis in [-π, π]); the LiDAR frame
  pitches and rolls with the hull, so that plane is the hull's, not the water's (to place a box in the world, take
  the 3D box, its centre's z included, through the LiDAR's pose);
* per pinhole camera, a 2D box: the bounding box of the projected 3D-box corners (edges clipped at the near plane;
  through a camera's lens distortion, the projected edges); where the image border cuts it, the bounding box of the
  part of the 3D box's image inside the image (its faces' images united and clipped to the border, so a long hull
  seen at a slant and cut by a corner gets no empty band), with ``truncation`` = 1 − the area of the bounding box
  clipped to the image / its unclipped area (a box reaching behind the camera, a hull alongside or passing within a
  few metres abeam, has an image without bound: its truncation is close to 1 whatever part of the picture it fills,
  e.g. 0.9999 for a patrol boat 1 m off the camera filling 13 % of it, and depends on the near plane
  :data:`~mmusv.image_boxes.NEAR_M`; ``visible_pixels`` tells how much of it the picture shows),
  ``visible_pixels`` (pixels whose instance is the vessel),
  ``box_pixels`` (the pixels the recorded box touches, ``(ceil(x_max) − floor(x_min)) · (ceil(y_max) −
  floor(y_min))``, not its area in pixels²: the window ``visible_pixels`` is counted in) and
  ``occlusion`` = 1 − visible / silhouette over the vessel's part above the still water level (world z > 0):
  the silhouette is the pixels whose rays, cast against the vessel alone, meet it above that level (the part of
  the hull a flat calm sea never hides; all of them for a vessel met only below it, a small craft wholly in a wave
  trough, but none where the image border cuts off all of the box's part above it:
  :func:`~mmusv.wave_occlusion.exposed_rays`), visible those of them whose pixel shows the vessel; so a vessel in
  plain view on flat water has occlusion 0, and other objects and the waves' crests raise it (the waves' own share
  is ``wave_occlusion``, below). The 2D box is the projected 3D box, which reaches down to the keel.
* over a displaced sea (a scene with a wave surface), per 3D box and per 2D box, ``wave_occlusion``: the share of
  the vessel's part above the still water level that the water hides from that sensor (:mod:`mmusv.wave_occlusion`);
  0 over a flat sea.

Frames: LiDAR frame x forward, y left, z up; image u right, v down, pixel centres at +0.5.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from mmusv import arguments
from mmusv.agent_annotations import Annotations
from mmusv.boxes3d import _range, box_corners, footprint_in_range, in_target_range
from mmusv.errors import InputError
from mmusv.frames import BODY_TO_OPTICAL, translation
from mmusv.image_boxes import (
    camera_lens,
    clip_box,
    faces_above,
    faces_in_image_box,
    in_image_box,
    pinhole_truncation,
    project_box,
)
from mmusv.lidar_wave_shares import lidar_wave_shares
from mmusv.scene import Scene
from mmusv.silhouettes import SilhouetteCache
from mmusv.wave_occlusion import exposed_hidden_boxes, exposed_rays, pattern_angles, share

__all__ = [
    "Annotations",
    "SilhouetteCache",
    "annotate_agent",
    "box_corners",
    "footprint_in_range",
    "in_target_range",
    "pinhole_truncation",
]


def _world_to_optical(points: np.ndarray, world_to_body: np.ndarray) -> np.ndarray:
    """World points ``(n, 3)`` in a camera's optical frame (x right, y down, z forward; metres), through its
    ``(4, 4)`` world → camera-body transform."""
    out: np.ndarray = (points @ world_to_body[:3, :3].T + world_to_body[:3, 3]) @ BODY_TO_OPTICAL.T
    return out


def _agent_arguments(
    *,
    agent_id: Any,
    agent_index: Any,
    frame: Any,
    time_s: Any,
    vessels: Any,
    lidar_pose: Any,
    cameras: Any,
    silhouettes: Any,
    max_range_m: Any,
) -> tuple[int, int, float]:
    """:func:`annotate_agent`'s arguments checked (an :class:`InputError` naming the first that is wrong):
    ``agent_index``, ``frame`` and ``time_s`` in their one accepted form."""
    if not isinstance(agent_id, str):
        raise InputError(f"agent_id = {arguments.shown(agent_id)}: must be the agent's id (a str)")
    if not isinstance(vessels, (list, tuple)):
        raise InputError(f"vessels = {arguments.shown(vessels)}: must be the list of the world state's VesselInfo")
    hi = len(vessels) - 1
    index = arguments.whole(agent_index, name="agent_index", lo=0, hi=max(hi, 0), error=InputError)
    if index > hi:
        raise InputError(f"agent_index = {index}: there are no vessels to index")
    frame = arguments.whole(frame, name="frame", lo=0, error=InputError)
    time_s = arguments.real(time_s, name="time_s", unit="seconds", error=InputError)
    if lidar_pose is not None:
        what = "a (4, 4) LiDAR -> world transform (or None: the vessel's body)"
        m = arguments.reals(lidar_pose, name="lidar_pose", tail=(4, 4), what=what, error=InputError)
        if m.ndim != 2 or not np.isfinite(m).all():
            raise InputError(f"lidar_pose must be {what}, finite, got {arguments.shown(lidar_pose)}")
    if not isinstance(cameras, Mapping):
        raise InputError(
            f"cameras = {arguments.shown(cameras)}: must be a dict name -> (camera, (4, 4) pose, (H, W) instance "
            "image), {} for none"
        )
    if not isinstance(silhouettes, SilhouetteCache):
        raise InputError(f"silhouettes = {arguments.shown(silhouettes)}: must be a SilhouetteCache")
    arguments.real(max_range_m, name="max_range_m", unit="metres", lo=0.0, finite=False, error=InputError)
    return index, frame, time_s


def annotate_agent(
    *,
    agent_id: str,
    agent_index: int,
    frame: int,
    time_s: float,
    vessels: list[Any],
    state: Any,
    lidar_pose: np.ndarray | None,
    lidar_instances: np.ndarray | None,
    cameras: Mapping[str, tuple[Any, np.ndarray, np.ndarray] | tuple[Any, np.ndarray, np.ndarray, float]],
    silhouettes: SilhouetteCache,
    max_range_m: float,
    scene: Scene | None = None,
    lidar_pattern: np.ndarray | None = None,
    lidar_beams: np.ndarray | None = None,
) -> Annotations:
    """Annotations of one agent (see the module docstring).

    Args:
        vessels: ``VesselInfo`` of every vessel of the world state (same order as ``state``).
        state: the ``WorldState`` of the frame.
        lidar_pose: ``(4, 4)`` LiDAR → world (boxes are expressed in this frame; the vessel body if ``None``).
        lidar_instances: ``(N,)`` instance id of each LiDAR point (for the point counts).
        cameras: name -> (native camera, ``(4, 4)`` camera body → world, ``(H, W)`` instance image[, range_m]):
            ``range_m`` the camera's :attr:`~mmusv.sensors.config.CameraConfig.range_m` (metres; ``inf`` when left
            out): the part of a vessel beyond it is neither seen nor hidden (the camera draws the sea there), so a
            vessel wholly beyond it gets no 2D box, and the water drawn in front of it counts for no
            ``wave_occlusion``.
        max_range_m: vessels whose BEV footprint lies wholly beyond this range of the LiDAR
            (:func:`footprint_in_range`) get no 3D/BEV box.
        scene: the full scene; where it has a wave surface, the boxes' ``wave_occlusion`` is computed (else 0).
        lidar_pattern: ``(M, 3)`` float32 unit beam directions in the LiDAR frame (for the 3D boxes' share).
        lidar_beams: ``(M,)`` int32 instance each beam of the pattern met first in the capture (-1: none;
            :attr:`~mmusv.simulation.AgentCapture.lidar_beams`): the full scene's answer for the 3D boxes' share,
            read instead of casting the beams again.

    Arguments that are not what is described here (an ``agent_index`` that is no vessel's, a ``lidar_pose`` that
    is no finite ``(4, 4)`` matrix, ...) raise :class:`mmusv.InputError` naming them.
    """
    agent_index, frame, time_s = _agent_arguments(
        agent_id=agent_id,
        agent_index=agent_index,
        frame=frame,
        time_s=time_s,
        vessels=vessels,
        lidar_pose=lidar_pose,
        cameras=cameras,
        silhouettes=silhouettes,
        max_range_m=max_range_m,
    )
    if lidar_instances is not None:
        lidar_instances = np.asarray(lidar_instances)
        if lidar_instances.dtype.kind not in "iu" and lidar_instances.size:
            raise InputError(
                f"lidar_instances must be the (N,) instance ids (integers) of the LiDAR's points, got dtype "
                f"{lidar_instances.dtype}"
            )
    waves = scene is not None and scene.wave_top is not None
    angles = pattern_angles(lidar_pattern) if waves and lidar_pattern is not None else None
    ann = Annotations(agent=agent_id, frame=frame, time_s=time_s)
    ref = lidar_pose if lidar_pose is not None else state.matrices[agent_index]
    ref_inv = np.linalg.inv(ref)
    counts: dict[int, int] = {}
    if lidar_instances is not None and lidar_instances.size:
        ids, cnt = np.unique(lidar_instances, return_counts=True)
        counts = {int(i): int(c) for i, c in zip(ids, cnt, strict=True)}
    # Per pinhole camera, once: intrinsics, the world → camera-body transform and the pose as the binding takes it.
    views = {}
    reaches: dict[str, float] = {}
    for name, entry in cameras.items():
        if not isinstance(entry, (tuple, list)) or len(entry) not in (3, 4):
            raise InputError(
                f"cameras[{name!r}] = {arguments.shown(entry)}: must be (camera, (4, 4) pose, (H, W) instance image"
                "[, range_m])"
            )
        cam, pose, inst_img = entry[0], entry[1], entry[2]
        if cam.intrinsics is not None:
            inv, p = np.linalg.inv(pose), np.ascontiguousarray(pose, dtype=np.float64)
            views[name] = (cam, cam.intrinsics, inv, p, inst_img, camera_lens(cam, pose=p, world_to_body=inv))
            reaches[name] = _range(entry[3]) if len(entry) > 3 else float("inf")
    rotations: list[np.ndarray] = []  # the 3D boxes' rotation matrices, turned into quaternions in one call
    share_boxes: list[tuple[int, np.ndarray, str, np.ndarray]] = []  # 3D box row, corners, asset, pose
    # 2D box row, its pixels' rays (origins, unit directions), distances to the vessel alone, instances seen first
    cam_shares: list[tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray, bool]] = []
    for vi, info in enumerate(vessels):
        if vi == agent_index:
            continue
        box_world = state.matrices[vi] @ translation(info.box_center_body)
        box_ref = ref_inv @ box_world
        rng = float(np.linalg.norm(box_ref[:3, 3]))
        corners_world = box_corners(box_world, info.box_size)
        if footprint_in_range(box_ref, size=info.box_size, range_m=max_range_m):
            ann.lidar_ids.append(info.id)
            ann.lidar_instance.append(info.instance_id)
            ann.lidar_class.append(info.semantic_class)
            ann.lidar_center.append(box_ref[:3, 3].copy())
            ann.lidar_size.append(np.asarray(info.box_size, dtype=np.float64))
            rotations.append(box_ref[:3, :3])
            ann.lidar_yaw.append(float(np.arctan2(box_ref[1, 0], box_ref[0, 0])))
            ann.lidar_points.append(counts.get(info.instance_id, 0))
            ann.lidar_range.append(rng)
            ann.lidar_role.append(info.role)
            ann.lidar_static.append(bool(info.static))
            # the wave-occlusion share: worked out below for all boxes at once (0 where there is none to work out)
            share_boxes.append((len(ann.lidar_wave_occlusion), corners_world, info.asset, state.matrices[vi]))
            ann.lidar_wave_occlusion.append(0.0)
        for name, (cam, k, inv, pose, inst_img, lens) in views.items():
            h, w = inst_img.shape
            corners_opt = _world_to_optical(corners_world, inv)
            box = project_box(corners_opt, intrinsics=k, lens=lens)
            if box is None:
                continue
            clipped, area, carea = clip_box(box, width=w, height=h)
            if carea <= 0:
                continue
            cut = box[0] < 0.0 or box[1] < 0.0 or box[2] > w or box[3] > h
            if cut:  # its part inside the image
                inside = in_image_box(corners_opt, intrinsics=k, lens=lens, width=w, height=h)
                if inside is None:
                    continue
                clipped = inside
            u0, v0 = int(np.floor(clipped[0])), int(np.floor(clipped[1]))
            u1, v1 = int(np.ceil(clipped[2])), int(np.ceil(clipped[3]))
            window = inst_img[v0:v1, u0:u1]
            visible = int(np.count_nonzero(window == info.instance_id))
            vv, uu = np.mgrid[v0:v1, u0:u1]
            pix = np.ascontiguousarray((vv * w + uu).reshape(-1), dtype=np.int64)
            o, d = cam.pixel_rays(pose, pix)
            t_alone = silhouettes.distances(info.asset, pose=state.matrices[vi], origins=o, directions=d)
            # Beyond the camera's range the vessel is not drawn (the sea is): that part is neither seen nor hidden.
            t_alone = np.where(np.asarray(t_alone) <= reaches[name], t_alone, np.inf)
            alone = np.isfinite(t_alone)
            sil = int(np.count_nonzero(alone))
            if sil == 0 and visible == 0:
                continue
            # The silhouette above the still water level, and the part of it the camera sees (a flat sea hides the
            # hull below the waterline: that is no occlusion).
            dn = d / np.linalg.norm(d, axis=1, keepdims=True)
            z = o[:, 2] + dn[:, 2] * np.where(alone, t_alone, 0.0)
            # Met only below the still level: a craft wholly in a trough, whose whole silhouette counts; but where
            # the border cuts off all of the box's part above that level, the lower hull of a ship whose upper part
            # is out of the picture (no exposed silhouette in this image).
            whole_when_low = True
            if cut and sil and not (alone & (z > 0.0)).any():
                above_opt = [_world_to_optical(f, inv) for f in faces_above(corners_world)]
                if above_opt:  # (none: the whole box lies below the still level)
                    seen_above = faces_in_image_box(above_opt, intrinsics=k, lens=lens, width=w, height=h)
                    whole_when_low = seen_above is not None
            above = exposed_rays(alone, z, whole_when_low=np.array([whole_when_low]))
            exposed = int(np.count_nonzero(above))
            seen = int(np.count_nonzero(above & (window.reshape(-1) == info.instance_id)))
            ann.cam_ids.append(info.id)
            ann.cam_camera.append(name)
            ann.cam_box.append(clipped)
            ann.cam_truncation.append(float(1.0 - carea / area))
            ann.cam_visible.append(visible)
            ann.cam_box_pixels.append(int((u1 - u0) * (v1 - v0)))
            ann.cam_occlusion.append(float(1.0 - seen / exposed) if exposed else float(sil > 0 and visible == 0))
            ann.cam_role.append(info.role)
            ann.cam_static.append(bool(info.static))
            if waves and sil:  # the wave-occlusion share: worked out below for every 2D box at once
                cam_shares.append((len(ann.cam_wave_occlusion), o, dn, t_alone, window.reshape(-1), whole_when_low))
            ann.cam_wave_occlusion.append(0.0)
    if cam_shares and scene is not None:
        rows_2d, origins, directions, distances, seen_first, whole = zip(*cam_shares, strict=True)
        offsets = np.concatenate(([0], np.cumsum([t.size for t in distances])))
        n_exposed, n_hidden = exposed_hidden_boxes(
            scene,
            origins=np.concatenate(origins),
            directions=np.concatenate(directions),
            vessel_t=np.concatenate(distances),
            starts=offsets,
            scene_instance=np.concatenate(seen_first),
            whole_when_low=np.array(whole, dtype=bool),
        )
        for row, e, h in zip(rows_2d, n_exposed, n_hidden, strict=True):
            ann.cam_wave_occlusion[row] = share(int(e), int(h))
    if (
        share_boxes
        and scene is not None
        and lidar_pose is not None
        and lidar_pattern is not None
        and angles is not None
    ):
        rows, corners, assets, poses = zip(*share_boxes, strict=True)
        shares = lidar_wave_shares(
            scene,
            lidar_pattern,
            angles,
            lidar_pose,
            np.stack(corners),
            list(assets),
            list(poses),
            silhouettes,
            lidar_beams,
            max_range_m,
        )
        for row, value in zip(rows, shares, strict=True):
            ann.lidar_wave_occlusion[row] = value
    if rotations:
        # One call for every box (scipy converts a stack row by row, the same bits as one matrix at a time).
        ann.lidar_rotation = list(Rotation.from_matrix(np.stack(rotations)).as_quat())
    return ann
