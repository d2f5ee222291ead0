"""Per-agent annotations derived from the world state and the agent's own captures.

For every agent (USV) and frame, for every other vessel whose bird's-eye-view footprint comes within the LiDAR's
range (:func:`footprint_in_range`: a long ship whose centre lies beyond it but whose stern is near gets its box; the
agent's own hull is never a target):
* a 3D box in the agent's LiDAR frame (centre, size = length/beam/height, rotation quaternion xyzw, yaw) with the
  number of LiDAR points on the vessel (exact: points carry instance ids) and its range;
* the vessel's ``role`` (``target``, ``usv`` — another instrumented USV, never a detection target — or
  ``moored``) and ``static`` flag (moored ships, and scenario vessels that never move), so users can filter;
* an ego-centric BEV box: the 3D box's footprint in the LiDAR frame's xy plane (x, y, length, width, yaw);
* per pinhole camera, a 2D box: the bounding box of the projected 3D-box corners (edges clipped at the near plane;
  through a camera's lens distortion, the projected edges); where the image border cuts it, the bounding box of the
  part of the 3D box's image inside the image (its faces' images united and clipped to the border, so a long hull
  seen at a slant and cut by a corner gets no empty band), with ``truncation`` = 1 − the area of the bounding box
  clipped to the image / its unclipped area, ``visible_pixels`` (pixels whose instance is the vessel),
  ``box_pixels`` (the recorded box's area, whole pixels) and
  ``occlusion`` = 1 − visible / silhouette over the vessel's part above the still water level (world z > 0):
  the silhouette is the pixels whose rays, cast against the vessel alone, meet it above that level (the part of
  the hull a flat calm sea never hides; all of them for a vessel met only below it, a small craft wholly in a wave
  trough), visible those of them whose pixel shows the vessel; so a vessel in plain view on flat water has
  occlusion 0, and other objects and the waves' crests raise it (the waves' own share is ``wave_occlusion``,
  below). The 2D box is the projected 3D box, which reaches down to the keel.
* over a displaced sea (a scene with a wave surface), per 3D box and per 2D box, ``wave_occlusion``: the share of
  the vessel's part above the still water level that the water hides from that sensor (:mod:`mmusv.wave_occlusion`);
  0 over a flat sea.

Frames: LiDAR frame x forward, y left, z up; image u right, v down, pixel centres at +0.5.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from mmusv._equality import same
from mmusv.errors import InputError
from mmusv.frames import BODY_TO_OPTICAL, translation
from mmusv.scene import Scene
from mmusv.wave_occlusion import (
    BeamAngles,
    exposed_hidden_boxes,
    lidar_beam_rays,
    lidar_boxes_beams,
    pattern_angles,
    share,
)
from mmusv.world.vessels import get_asset

__all__ = [
    "Annotations",
    "SilhouetteCache",
    "annotate_agent",
    "box_corners",
    "footprint_in_range",
    "in_target_range",
    "pinhole_truncation",
]

# Corner order of a box: bit 0 → +x, bit 1 → +y, bit 2 → +z.
_SIGNS = np.array(
    [[(i & 1) * 2 - 1, ((i >> 1) & 1) * 2 - 1, ((i >> 2) & 1) * 2 - 1] for i in range(8)], dtype=np.float64
)
_EDGES = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]
NEAR_M = 0.05


def in_target_range(centres: np.ndarray, range_m: float) -> np.ndarray:
    """The box-centre target rule: which box centres lie within ``range_m`` metres of the ego LiDAR in bird's-eye
    view, ``hypot(x, y) <= range_m`` (height ignored). ``centres``: ``(..., 3)`` (or ``(..., 2)``) in the ego's
    LiDAR frame (its body frame when it has none), metres; returns a bool array of shape ``centres.shape[:-1]``
    (a 0-d array for one centre).

    Used by the OPV2V and KITTI exports (which vessels are labelled) and the detection study (the BEV distance it
    evaluates within), as OpenCOOD selects its objects; the recording's own 3D/BEV boxes reach farther, to every
    vessel whose footprint comes within range (:func:`footprint_in_range`), and the ROS 2 export's 3D detections are
    those boxes.
    """
    c = np.asarray(centres, dtype=np.float64)
    if c.ndim == 0 or c.shape[-1] not in (2, 3):
        raise InputError(f"centres must have shape (..., 3) or (..., 2) (x, y[, z] metres), got {c.shape}")
    return np.asarray(np.hypot(c[..., 0], c[..., 1]) <= range_m)


def footprint_in_range(box: np.ndarray, *, size: np.ndarray, range_m: float) -> bool:
    """Whether a box's bird's-eye-view footprint comes within ``range_m`` metres of the ego LiDAR: the distance from
    the origin to the rectangle of ``size[0]`` (length) by ``size[1]`` (beam) centred at the box's ``(x, y)`` and
    turned by its yaw (the BEV box), 0 inside it. ``box``: ``(4, 4)`` box → ego LiDAR frame (centred), metres.

    The annotations' rule (:func:`annotate_agent`): a 330 m ship whose stern lies 45 m from the USV has its centre
    beyond a 200 m LiDAR's range, yet the LiDAR sees it; the centre rule of :func:`in_target_range` stays the
    exports' and the detection study's (OpenCOOD's convention)."""
    m = np.asarray(box, dtype=np.float64)
    yaw = np.arctan2(m[1, 0], m[0, 0])
    c, s = np.cos(yaw), np.sin(yaw)
    # The origin in the box's yaw-only frame, then its distance to the rectangle (0 inside).
    x, y = -m[0, 3], -m[1, 3]
    u, v = c * x + s * y, -s * x + c * y
    du = max(abs(u) - float(size[0]) / 2.0, 0.0)
    dv = max(abs(v) - float(size[1]) / 2.0, 0.0)
    return bool(np.hypot(du, dv) <= range_m)


def box_corners(matrix: np.ndarray, size: np.ndarray) -> np.ndarray:
    """``(8, 3)`` float64 corners of a box with pose ``matrix`` (``(4, 4)`` box → frame, centred) and full ``size``
    (length, beam, height along the box's x, y, z; metres), in the frame ``matrix`` maps to. Corner ``i`` lies at
    ``±size / 2`` in the box frame, the sign of x from bit 0 of ``i``, of y from bit 1 and of z from bit 2 (set:
    +; corner 0 is (−x, −y, −z), corner 7 (+x, +y, +z)). Other shapes raise :class:`mmusv.InputError`."""
    matrix, size = np.asarray(matrix, dtype=np.float64), np.asarray(size, dtype=np.float64)
    if matrix.shape != (4, 4) or size.shape != (3,):
        raise InputError(f"box_corners takes a (4, 4) matrix and a (3,) size, got {matrix.shape} and {size.shape}")
    local = _SIGNS * (size / 2.0)
    out: np.ndarray = local @ matrix[:3, :3].T + matrix[:3, 3]
    return out


@dataclass(eq=False)
class Annotations:
    """Columns of one agent's annotations at acquisition index ``frame``, ``time_s`` seconds (see the module
    docstring), as lists, one entry per box, in the units and frames of :meth:`columns`. Lengths: ``n3d`` for
    ``lidar_*``, ``n2d`` for ``cam_*``. Two compare equal (``==``) when they hold the same values
    (arrays by dtype, shape and value)."""

    agent: str
    frame: int
    time_s: float
    lidar_ids: list[str] = field(default_factory=list)
    lidar_instance: list[int] = field(default_factory=list)
    lidar_class: list[int] = field(default_factory=list)
    lidar_center: list[np.ndarray] = field(default_factory=list)
    lidar_size: list[np.ndarray] = field(default_factory=list)
    lidar_rotation: list[np.ndarray] = field(default_factory=list)
    lidar_yaw: list[float] = field(default_factory=list)
    lidar_points: list[int] = field(default_factory=list)
    lidar_range: list[float] = field(default_factory=list)
    lidar_role: list[str] = field(default_factory=list)
    lidar_static: list[bool] = field(default_factory=list)
    lidar_wave_occlusion: list[float] = field(default_factory=list)
    cam_ids: list[str] = field(default_factory=list)
    cam_camera: list[str] = field(default_factory=list)
    cam_box: list[np.ndarray] = field(default_factory=list)
    cam_truncation: list[float] = field(default_factory=list)
    cam_visible: list[int] = field(default_factory=list)
    cam_box_pixels: list[int] = field(default_factory=list)
    cam_occlusion: list[float] = field(default_factory=list)
    cam_role: list[str] = field(default_factory=list)
    cam_static: list[bool] = field(default_factory=list)
    cam_wave_occlusion: list[float] = field(default_factory=list)

    def __eq__(self, other: object) -> bool:
        """Field by field, arrays by dtype, shape and value (:mod:`mmusv._equality`)."""
        return same(self, other) if type(other) is type(self) else NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def columns(self) -> dict[str, Any]:
        """Numpy columns, the ``Recording.annotations`` groups: ``{"lidar", "bev", "camera"}``, each a dict of
        columns in the order the vessels are in the world state (``n3d`` rows for ``lidar``/``bev``, ``n2d`` for
        ``camera``, which goes vessel by vessel, camera by camera; ``role`` and ``static`` go to the Parquet tables
        only: the MCAP's ``AgentAnnotations`` has no such fields and ``Recording.annotations`` ignores them):

        - ``lidar`` (the agent's LiDAR frame, metres, radians): ``target_id``, ``role`` lists of str;
          ``instance_id``, ``semantic_class``, ``lidar_points`` ``(n3d,)`` uint32; ``center`` ``(n3d, 3)``,
          ``size`` ``(n3d, 3)`` length, beam, height, ``rotation`` ``(n3d, 4)`` quaternion x, y, z, w, ``yaw``,
          ``range_m`` (``|center|``), ``wave_occlusion`` ``(n3d,)`` float64; ``static`` ``(n3d,)`` bool;
        - ``bev``: ``target_id``; ``x``, ``y``, ``length``, ``width``, ``yaw`` ``(n3d,)`` float64 (the 3D box's
          footprint in the LiDAR frame's xy plane);
        - ``camera`` (pixels, origin top-left, clipped to the image): ``target_id``, ``camera``, ``role`` lists of
          str; ``x_min``, ``y_min``, ``x_max``, ``y_max``, ``truncation``, ``occlusion``, ``wave_occlusion``
          ``(n2d,)`` float64; ``visible_pixels``, ``box_pixels`` ``(n2d,)`` uint32; ``static`` ``(n2d,)`` bool.
        """
        n = len(self.lidar_ids)
        centre = np.array(self.lidar_center, dtype=np.float64).reshape(n, 3)
        size = np.array(self.lidar_size, dtype=np.float64).reshape(n, 3)
        lidar = {
            "target_id": list(self.lidar_ids),
            "instance_id": np.array(self.lidar_instance, dtype=np.uint32),
            "semantic_class": np.array(self.lidar_class, dtype=np.uint32),
            "center": centre,
            "size": size,
            "rotation": np.array(self.lidar_rotation, dtype=np.float64).reshape(n, 4),
            "yaw": np.array(self.lidar_yaw, dtype=np.float64),
            "lidar_points": np.array(self.lidar_points, dtype=np.uint32),
            "range_m": np.array(self.lidar_range, dtype=np.float64),
            "role": list(self.lidar_role),
            "static": np.array(self.lidar_static, dtype=bool),
            "wave_occlusion": np.array(self.lidar_wave_occlusion, dtype=np.float64),
        }
        bev = {
            "target_id": list(self.lidar_ids),
            "x": centre[:, 0].copy(),
            "y": centre[:, 1].copy(),
            "length": size[:, 0].copy(),
            "width": size[:, 1].copy(),
            "yaw": np.array(self.lidar_yaw, dtype=np.float64),
        }
        m = len(self.cam_ids)
        box = np.array(self.cam_box, dtype=np.float64).reshape(m, 4)
        camera = {
            "target_id": list(self.cam_ids),
            "camera": list(self.cam_camera),
            "x_min": box[:, 0].copy(),
            "y_min": box[:, 1].copy(),
            "x_max": box[:, 2].copy(),
            "y_max": box[:, 3].copy(),
            "truncation": np.array(self.cam_truncation, dtype=np.float64),
            "visible_pixels": np.array(self.cam_visible, dtype=np.uint32),
            "box_pixels": np.array(self.cam_box_pixels, dtype=np.uint32),
            "occlusion": np.array(self.cam_occlusion, dtype=np.float64),
            "role": list(self.cam_role),
            "static": np.array(self.cam_static, dtype=bool),
            "wave_occlusion": np.array(self.cam_wave_occlusion, dtype=np.float64),
        }
        return {"lidar": lidar, "bev": bev, "camera": camera}


class SilhouetteCache:
    """One single-instance scene per vessel asset, to render a vessel with nothing else in the way."""

    def __init__(self) -> None:
        self._scenes: dict[str, tuple[Scene, int]] = {}

    def hits(self, asset: str, *, pose: np.ndarray, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """``(N,)`` bool: which rays (``origins``, ``directions`` ``(N, 3)`` world, metres) hit the vessel ``asset``
        at ``pose`` (``(4, 4)`` body → world), alone in the world."""
        hit: np.ndarray = np.isfinite(self.distances(asset, pose=pose, origins=origins, directions=directions))
        return hit

    def distances(self, asset: str, *, pose: np.ndarray, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """``(N,)`` float32 distance (metres along each normalised direction) at which each ray meets the vessel
        ``asset`` at ``pose`` (body → world), alone in the world; ``inf`` where it misses."""
        if asset not in self._scenes:
            a = get_asset(asset)
            s = Scene()
            mid = s.add_mesh(a.mesh.vertices, a.mesh.faces, classes=a.mesh.classes, name=asset)
            self._scenes[asset] = (s, s.add_instance(mid))
        scene, inst = self._scenes[asset]
        scene.set_poses([inst], pose[None])
        if origins.shape[0] == 0:
            return np.zeros(0, dtype=np.float32)
        return scene.cast_rays(origins, directions).distance

    def distances_boxes(
        self,
        assets: list[str],
        *,
        poses: list[np.ndarray],
        origins: np.ndarray,
        directions: np.ndarray,
        starts: np.ndarray,
    ) -> np.ndarray:
        """:meth:`distances` of many vessels' rays at once: ``(N,)`` float32, rows ``starts[b]:starts[b + 1]`` of
        ``origins`` and ``directions`` (``(N, 3)``, world) cast against vessel ``assets[b]`` at ``poses[b]`` (body
        → world) alone; ``starts`` ``(B + 1,)`` row offsets from 0 to ``N``."""
        parts = [
            self.distances(
                a, pose=p, origins=origins[starts[b] : starts[b + 1]], directions=directions[starts[b] : starts[b + 1]]
            )
            for b, (a, p) in enumerate(zip(assets, poses, strict=True))
        ]
        return np.concatenate(parts) if parts else np.zeros(0, dtype=np.float32)


EDGE_STEPS = 32
"""Pieces each box edge is cut into for a camera with lens distortion, which bends the edges' images."""


def _project_box(
    corners_opt: np.ndarray, k: tuple[float, float, float, float], lens: tuple[Any, float] | None = None
) -> np.ndarray | None:
    """Pixel bounding box ``[x0, y0, x1, y1]`` of a box given by its corners in the optical frame, with edges
    clipped at the near plane; ``None`` when the box is entirely behind the camera. ``lens``: the camera with
    lens distortion and its reach (:func:`_lens`), or ``None`` for an ideal pinhole, where the corners
    alone bound the image; through a lens the box's edges are sampled (their images are curves)."""
    fx, fy, cx, cy = k
    pts = [c for c in corners_opt if c[2] >= NEAR_M]
    ends = []
    for a, b in _EDGES:
        pa, pb = corners_opt[a], corners_opt[b]
        za, zb = pa[2], pb[2]
        if (za - NEAR_M) * (zb - NEAR_M) < 0:
            cut = pa + (NEAR_M - za) / (zb - za) * (pb - pa)
            pts.append(cut)
            ends.append((pa, cut) if za >= NEAR_M else (cut, pb))
        elif za >= NEAR_M and zb >= NEAR_M:
            ends.append((pa, pb))
    if not pts:
        return None
    if lens is None:
        p = np.array(pts)
        u = fx * p[:, 0] / p[:, 2] + cx
        v = fy * p[:, 1] / p[:, 2] + cy
    else:
        t = np.linspace(0.0, 1.0, EDGE_STEPS + 1)[:, None]
        p = np.concatenate([pa + t * (pb - pa) for pa, pb in ends])
        x, y = _distort(p[:, 0] / p[:, 2], p[:, 1] / p[:, 2], *lens)
        u = fx * x + cx
        v = fy * y + cy
    return np.array([u.min(), v.min(), u.max(), v.max()])


_FACES = [[0, 2, 6, 4], [1, 3, 7, 5], [0, 1, 5, 4], [2, 3, 7, 6], [0, 1, 3, 2], [4, 5, 7, 6]]
"""The box's six faces (−x, +x, −y, +y, −z, +z), each as its four corner indices in order round it (corner bits
as :func:`box_corners`)."""


def _near_face(face: np.ndarray) -> np.ndarray:
    """The part of a convex polygon ``(n, 3)`` (optical frame) in front of the near plane ``z >= NEAR_M`` (one
    Sutherland–Hodgman pass), ``(m, 3)``, ``m`` 0 when none of it is."""
    out = []
    for i in range(len(face)):
        a, b = face[i], face[(i + 1) % len(face)]
        ina, inb = a[2] >= NEAR_M, b[2] >= NEAR_M
        if ina:
            out.append(a)
        if ina != inb:
            out.append(a + (NEAR_M - a[2]) / (b[2] - a[2]) * (b - a))
    return np.array(out).reshape(-1, 3)


def _in_image_box(
    corners_opt: np.ndarray,
    k: tuple[float, float, float, float],
    lens: tuple[Any, float] | None,
    width: int,
    height: int,
) -> np.ndarray | None:
    """The pixel box ``[x0, y0, x1, y1]`` of the part of a box's image that lies inside the ``width × height`` image
    (the union of its faces' images, each face clipped at the near plane, intersected with the image), ``None`` when
    none of it does. Tighter than the box's projected bounding box clipped to the image where the border cuts the
    image of a long box seen at a slant; the same where the image lies wholly inside. Through a lens each face's
    pinhole image, clipped to the lens's reach, has its edges sampled (:data:`EDGE_STEPS`) in the image plane and
    distorted."""
    from shapely import MultiPoint, Polygon, box, unary_union

    fx, fy, cx, cy = k
    faces = [f for f in (_near_face(corners_opt[face]) for face in _FACES) if len(f) >= 3]
    if lens is None:  # a pinhole keeps straight lines straight: the image is the corners' convex hull
        p = np.concatenate(faces) if faces else np.zeros((0, 3))
        image = MultiPoint(np.column_stack([fx * p[:, 0] / p[:, 2] + cx, fy * p[:, 1] / p[:, 2] + cy])).convex_hull
    else:
        # Each face's pinhole image (a convex polygon in undistorted normalised coordinates, exact) clipped to the
        # square of half side the lens's reach (beyond it `_distort` carries points out of the image), then its
        # edges sampled evenly there and distorted: sampled in 3D, a face cut at the near plane put most samples
        # ~10^5 px out, and the chords between them crossed the image where the curved edge does not.
        reach = min(float(lens[1]), 1e6)
        square = box(-reach, -reach, reach, reach)
        t = np.linspace(0.0, 1.0, EDGE_STEPS, endpoint=False)[:, None]
        shapes = []
        for f in faces:
            flat = MultiPoint(np.column_stack([f[:, 0] / f[:, 2], f[:, 1] / f[:, 2]])).convex_hull.intersection(square)
            if flat.is_empty or flat.geom_type != "Polygon":
                continue
            ring = np.asarray(flat.exterior.coords)[:-1]
            pts = np.concatenate([a + t * (b - a) for a, b in zip(ring, np.roll(ring, -1, axis=0), strict=True)])
            x, y = _distort(pts[:, 0], pts[:, 1], *lens)
            shape = Polygon(np.column_stack([fx * x + cx, fy * y + cy]))
            shapes.append(shape if shape.is_valid else shape.buffer(0))
        image = unary_union(shapes)
    inside = image.intersection(box(0.0, 0.0, float(width), float(height)))
    if inside.is_empty:
        return None
    return np.array(inside.bounds, dtype=np.float64)


def _clip_box(box: np.ndarray, width: int, height: int) -> tuple[np.ndarray, float, float]:
    """A pixel box ``[x0, y0, x1, y1]`` clipped to the ``width × height`` image: the clipped box, the box's own area
    and the clipped area (pixels²; 0 when the box is empty or lies wholly outside the image)."""
    area = max(box[2] - box[0], 0.0) * max(box[3] - box[1], 0.0)
    clipped = np.array([max(box[0], 0.0), max(box[1], 0.0), min(box[2], float(width)), min(box[3], float(height))])
    if clipped[2] <= clipped[0] or clipped[3] <= clipped[1] or area <= 0:
        return clipped, float(area), 0.0
    return clipped, float(area), float((clipped[2] - clipped[0]) * (clipped[3] - clipped[1]))


def pinhole_truncation(
    corners_opt: np.ndarray, *, intrinsics: tuple[float, float, float, float], width: int, height: int
) -> float:
    """The share of a box's pinhole image that lies outside a ``width × height`` image: ``1 −`` clipped area /
    unclipped area of the projected box (as the 2D boxes' ``truncation``, without lens distortion), from its ``(8,
    3)`` corners in the optical frame (x right, y down, z forward; metres) and ``intrinsics`` ``(fx, fy, cx, cy)``
    pixels; 1.0 when the box lies wholly behind the camera or outside the image. For a target without a recorded 2D
    box (too small or too far for any pixel centre to meet it), so that an export can tell one in view from one
    out of it."""
    box = _project_box(np.asarray(corners_opt, dtype=np.float64), intrinsics)
    if box is None:
        return 1.0
    _clipped, area, carea = _clip_box(box, width, height)
    return 1.0 if carea <= 0 else float(1.0 - carea / area)


def _lens(cam: Any, pose: np.ndarray, world_to_body: np.ndarray) -> tuple[Any, float] | None:
    """A pinhole camera with lens distortion (``mmusv._core.Camera``) and its reach (the largest undistorted
    normalised radius its image corners see, from the camera's own corner rays), or ``None`` without distortion.
    Within the reach the camera's distortion maps every point to the pixel whose ray meets it; beyond it, where the
    polynomial may fold back into the image, points are carried radially outwards, outside the image."""
    if cam.distortion is None:
        return None
    w, h = cam.resolution
    corners = np.array([0, w - 1, (h - 1) * w, h * w - 1], dtype=np.int64)
    _, d = cam.pixel_rays(pose, corners)
    opt = np.asarray(d, dtype=np.float64) @ world_to_body[:3, :3].T @ BODY_TO_OPTICAL.T
    reach = float(np.max(np.hypot(opt[:, 0], opt[:, 1]) / opt[:, 2]))
    # A single pixel's centre is the image centre: nothing to fold past, the polynomial alone.
    return cam, reach if reach > 0.0 else np.inf


def _distort(x: np.ndarray, y: np.ndarray, cam: Any, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """Distorted normalised coordinates of undistorted ``(x, y)`` through ``cam``'s own Brown–Conrady model (the
    core's ``Distortion::distort``, which the render uses); a point beyond ``reach`` is distorted at the reach and
    scaled back out radially."""
    r = np.hypot(x, y)
    s = np.where(r > reach, reach / np.maximum(r, 1e-300), 1.0)
    d = cam.distort(np.column_stack([x * s, y * s]).astype(np.float64))
    return d[:, 0] / s, d[:, 1] / s


def _lidar_wave_shares(
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
    n_exposed, n_hidden = exposed_hidden_boxes(
        scene, origins=o, directions=d, vessel_t=t, starts=starts, scene_instance=first, max_range_m=max_range_m
    )
    return [share(e, h) for e, h in zip(n_exposed, n_hidden, strict=True)]


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
    cameras: dict[str, tuple[Any, np.ndarray, np.ndarray]],
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
        cameras: name -> (native camera, ``(4, 4)`` camera body → world, ``(H, W)`` instance image).
        max_range_m: vessels whose BEV footprint lies wholly beyond this range of the LiDAR
            (:func:`footprint_in_range`) get no 3D/BEV box.
        scene: the full scene; where it has a wave surface, the boxes' ``wave_occlusion`` is computed (else 0).
        lidar_pattern: ``(M, 3)`` float32 unit beam directions in the LiDAR frame (for the 3D boxes' share).
        lidar_beams: ``(M,)`` int32 instance each beam of the pattern met first in the capture (-1: none;
            :attr:`~mmusv.simulation.AgentCapture.lidar_beams`): the full scene's answer for the 3D boxes' share,
            read instead of casting the beams again.
    """
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
    for name, (cam, pose, inst_img) in cameras.items():
        if cam.intrinsics is not None:
            inv, p = np.linalg.inv(pose), np.ascontiguousarray(pose, dtype=np.float64)
            views[name] = (cam, cam.intrinsics, inv, p, inst_img, _lens(cam, p, inv))
    rotations: list[np.ndarray] = []  # the 3D boxes' rotation matrices, turned into quaternions in one call
    share_boxes: list[tuple[int, np.ndarray, str, np.ndarray]] = []  # 3D box row, corners, asset, pose
    # 2D box row, its pixels' rays (origins, unit directions), distances to the vessel alone, instances seen first
    cam_shares: list[tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
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
            body = corners_world @ inv[:3, :3].T + inv[:3, 3]
            box = _project_box(body @ BODY_TO_OPTICAL.T, k, lens)
            if box is None:
                continue
            clipped, area, carea = _clip_box(box, w, h)
            if carea <= 0:
                continue
            if box[0] < 0.0 or box[1] < 0.0 or box[2] > w or box[3] > h:  # cut by the border: its part inside
                inside = _in_image_box(body @ BODY_TO_OPTICAL.T, k, lens, w, h)
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
            alone = np.isfinite(t_alone)
            sil = int(np.count_nonzero(alone))
            if sil == 0 and visible == 0:
                continue
            # The silhouette above the still water level, and the part of it the camera sees (a flat sea hides the
            # hull below the waterline: that is no occlusion).
            dn = d / np.linalg.norm(d, axis=1, keepdims=True)
            above = alone & (o[:, 2] + dn[:, 2] * np.where(alone, t_alone, 0.0) > 0.0)
            if sil and not above.any():
                above = alone  # wholly below the still level (a craft in a trough): its whole silhouette counts
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
                cam_shares.append((len(ann.cam_wave_occlusion), o, dn, t_alone, window.reshape(-1)))
            ann.cam_wave_occlusion.append(0.0)
    if cam_shares and scene is not None:
        rows_2d, origins, directions, distances, seen_first = zip(*cam_shares, strict=True)
        offsets = np.concatenate(([0], np.cumsum([t.size for t in distances])))
        n_exposed, n_hidden = exposed_hidden_boxes(
            scene,
            origins=np.concatenate(origins),
            directions=np.concatenate(directions),
            vessel_t=np.concatenate(distances),
            starts=offsets,
            scene_instance=np.concatenate(seen_first),
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
        shares = _lidar_wave_shares(
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
