"""The image of a 3D box in a camera: its pixel bounding box, the part of it inside the image, and how much of it
the image border cuts off — the geometry of the 2D boxes :mod:`mmusv.annotate` records and the exports
(:mod:`mmusv.export.kitti`) write.

* :func:`project_box`: the bounding box of a box's projected image, its edges clipped at the near plane
  (:data:`NEAR_M`); through a camera's Brown–Conrady lens distortion, the edges are sampled (their images bend).
* :func:`in_image_box`: where the image border cuts that image, the bounding box of its part inside the image (the
  faces' images united and clipped to the border; shapely), so a long hull seen at a slant gets no empty band.
* :func:`clip_box`, :func:`pinhole_truncation`: the projected box clipped to the image and the share cut off.
* :func:`camera_lens`: a distorted camera with its reach, the largest undistorted radius its image sees.

Frames: a box is its ``(8, 3)`` corners (corner bits as :func:`mmusv.boxes3d.box_corners`: bit 0 → +x, bit 1 →
+y, bit 2 → +z) in the camera's optical frame (x right, y down, z forward; metres); pixels u right, v down, with
pixel centres at +0.5, intrinsics ``(fx, fy, cx, cy)`` pixels.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np

from mmusv import arguments
from mmusv.errors import InputError
from mmusv.frames import BODY_TO_OPTICAL

__all__ = [
    "EDGE_STEPS",
    "NEAR_M",
    "camera_lens",
    "clip_box",
    "faces_above",
    "faces_in_image_box",
    "in_image_box",
    "pinhole_truncation",
    "project_box",
]

NEAR_M = 0.05
"""The near plane (metres along the optical axis): a box's edges are clipped there before they are projected."""

_EDGES = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]
"""The box's twelve edges, as pairs of corner indices one bit apart."""

EDGE_STEPS = 32
"""Pieces each box edge is cut into for a camera with lens distortion, which bends the edges' images."""


def project_box(
    corners_opt: np.ndarray, *, intrinsics: tuple[float, float, float, float], lens: tuple[Any, float] | None = None
) -> np.ndarray | None:
    """Pixel bounding box ``[x0, y0, x1, y1]`` of a box given by its corners in the optical frame, with edges
    clipped at the near plane; ``None`` when the box is entirely behind the camera. ``lens``: the camera with
    lens distortion and its reach (:func:`camera_lens`), or ``None`` for an ideal pinhole, where the corners
    alone bound the image; through a lens the box's edges are sampled (their images are curves)."""
    fx, fy, cx, cy = _intrinsics(intrinsics)
    corners_opt = _corners(corners_opt, name="corners_opt")
    lens = _lens(lens)
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
as :func:`mmusv.boxes3d.box_corners`)."""


def _near_face(face: np.ndarray) -> np.ndarray:
    """The part of a convex polygon ``(n, 3)`` (optical frame) in front of the near plane ``z >= NEAR_M`` (one
    Sutherland–Hodgman pass), ``(m, 3)``, ``m`` 0 when none of it is."""
    return _clip_face(face, NEAR_M)


def _clip_face(face: np.ndarray, at: float) -> np.ndarray:
    """The part of a convex polygon ``(n, 3)`` where ``z >= at`` (one Sutherland–Hodgman pass), ``(m, 3)``, ``m`` 0
    when none of it is."""
    out = []
    for i in range(len(face)):
        a, b = face[i], face[(i + 1) % len(face)]
        ina, inb = a[2] >= at, b[2] >= at
        if ina:
            out.append(a)
        if ina != inb:
            out.append(a + (at - a[2]) / (b[2] - a[2]) * (b - a))
    return np.array(out).reshape(-1, 3)


def faces_above(corners_world: np.ndarray, *, level: float = 0.0) -> list[np.ndarray]:
    """The faces of the part of a box above the world height ``level`` (metres; the still water level 0 by
    default): each of its six faces clipped to ``z >= level`` and the cap where the plane ``z = level`` cuts it,
    as ``(n, 3)`` world polygons (metres, z up; none left empty), from the box's ``(8, 3)`` world corners. An empty
    list when the whole box lies below ``level``."""
    c = _corners(corners_world, name="corners_world")
    level = arguments.real(level, name="level", unit="metres", error=InputError)
    faces = [f for f in (_clip_face(c[face], level) for face in _FACES) if len(f) >= 3]
    za, zb = c[[a for a, _ in _EDGES], 2] - level, c[[b for _, b in _EDGES], 2] - level
    cross = [c[a] + za[i] / (za[i] - zb[i]) * (c[b] - c[a]) for i, (a, b) in enumerate(_EDGES) if za[i] * zb[i] < 0]
    cross += [p for p in c if p[2] == level]
    if faces and len(cross) >= 3:  # a convex polygon in the horizontal plane: its points in turn round its centre
        cap = np.array(cross)
        mid = cap.mean(axis=0)
        faces.append(cap[np.argsort(np.arctan2(cap[:, 1] - mid[1], cap[:, 0] - mid[0]))])
    return faces


def in_image_box(
    corners_opt: np.ndarray,
    *,
    intrinsics: tuple[float, float, float, float],
    lens: tuple[Any, float] | None,
    width: int,
    height: int,
) -> np.ndarray | None:
    """The pixel box ``[x0, y0, x1, y1]`` of the part of a box's image that lies inside the ``width × height`` image
    (the union of its faces' images, each face clipped at the near plane, intersected with the image), ``None`` when
    none of it does. Tighter than the box's projected bounding box clipped to the image where the border cuts the
    image of a long box seen at a slant; the same where the image lies wholly inside. Through a lens each face's
    pinhole image, clipped to the lens's reach, has its edges sampled (:data:`EDGE_STEPS`) in the image plane and
    distorted. ``corners_opt``: the box's ``(8, 3)`` corners in the optical frame."""
    c = _corners(corners_opt, name="corners_opt")
    return faces_in_image_box(
        [c[face] for face in _FACES], intrinsics=intrinsics, lens=lens, width=width, height=height
    )


def faces_in_image_box(
    faces_opt: list[np.ndarray],
    *,
    intrinsics: tuple[float, float, float, float],
    lens: tuple[Any, float] | None,
    width: int,
    height: int,
) -> np.ndarray | None:
    """:func:`in_image_box` of the convex solid whose faces are ``faces_opt``, convex ``(n, 3)`` polygons in the
    optical frame (metres; :func:`faces_above` gives those of a box's part above the water): the pixel box of its
    image's part inside the image, ``None`` when none of it is inside."""
    from shapely import MultiPoint, Polygon, box, unary_union

    fx, fy, cx, cy = _intrinsics(intrinsics)
    lens = _lens(lens)
    width = arguments.whole(width, name="width", lo=1, error=InputError)
    height = arguments.whole(height, name="height", lo=1, error=InputError)
    faces = [f for f in (_near_face(g) for g in _faces(faces_opt)) if len(f) >= 3]
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


def clip_box(box: np.ndarray, *, width: int, height: int) -> tuple[np.ndarray, float, float]:
    """A pixel box ``[x0, y0, x1, y1]`` clipped to the ``width × height`` image: the clipped box, the box's own area
    and the clipped area (pixels²; 0 when the box is empty or lies wholly outside the image)."""
    box = arguments.reals(box, name="box", what="a pixel box [x0, y0, x1, y1]", error=InputError)
    if box.shape != (4,) or not np.isfinite(box).all():
        raise InputError(f"box must be a pixel box [x0, y0, x1, y1] of four finite numbers, got {arguments.shown(box)}")
    width = arguments.whole(width, name="width", lo=1, error=InputError)
    height = arguments.whole(height, name="height", lo=1, error=InputError)
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
    box = project_box(corners_opt, intrinsics=intrinsics)
    if box is None:
        return 1.0
    _clipped, area, carea = clip_box(box, width=width, height=height)
    return 1.0 if carea <= 0 else float(1.0 - carea / area)


def camera_lens(cam: Any, *, pose: np.ndarray, world_to_body: np.ndarray) -> tuple[Any, float] | None:
    """A pinhole camera with lens distortion (``mmusv._core.Camera``) and its reach (the largest undistorted
    normalised radius the centres of its four corner pixels see, from the camera's own rays there), or ``None``
    without distortion. Within the reach the camera's distortion maps every point to the pixel whose ray meets it;
    beyond it, where the polynomial may fold back into the image, points are carried radially outwards (so a point
    in the outer half of a corner pixel, past its centre's ray, lands just outside the image)."""
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


def _corners(value: Any, *, name: str) -> np.ndarray:
    """``value`` as a box's ``(8, 3)`` float64 corners, else an :class:`InputError` naming ``name``."""
    c = arguments.reals(value, name=name, what="a box's (8, 3) corners in metres", error=InputError)
    if c.shape != (8, 3) or not np.isfinite(c).all():
        raise InputError(
            f"{name} must be a box's (8, 3) corners, finite metres (corner bits as mmusv.annotate.box_corners), got "
            f"{arguments.shown(value)}"
        )
    return c


def _intrinsics(value: Any) -> tuple[float, float, float, float]:
    """``(fx, fy, cx, cy)`` pixels, finite, the focal lengths > 0, else an :class:`InputError`."""
    k = arguments.reals(value, name="intrinsics", what="(fx, fy, cx, cy) pixels", error=InputError)
    fx, fy, cx, cy = (float(v) for v in k) if k.shape == (4,) else (math.nan,) * 4
    if not (math.isfinite(cx) and math.isfinite(cy) and math.isfinite(fx) and math.isfinite(fy) and fx > 0 and fy > 0):
        raise InputError(
            f"intrinsics must be (fx, fy, cx, cy) pixels, finite, fx and fy > 0, got {arguments.shown(value)}"
        )
    return fx, fy, cx, cy


def _faces(value: Any) -> list[np.ndarray]:
    """``value`` as a list of ``(n, 3)`` float64 polygons (optical frame, finite metres), else an
    :class:`InputError` naming ``faces_opt``."""
    what = "a list of convex (n, 3) polygons in the optical frame (finite metres)"
    if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
        raise InputError(f"faces_opt must be {what}, got {arguments.shown(value)}")
    faces = []
    for i, g in enumerate(value):
        f = arguments.reals(
            g, name=f"faces_opt[{i}]", tail=(3,), what="a convex (n, 3) polygon (finite metres)", error=InputError
        )
        if f.ndim != 2 or not np.isfinite(f).all():
            raise InputError(
                f"faces_opt[{i}] must be a convex (n, 3) polygon (finite metres), got {arguments.shown(g)}"
            )
        faces.append(f)
    return faces


def _lens(value: Any) -> tuple[Any, float] | None:
    """``value`` as a lens: ``None`` (an ideal pinhole) or ``(camera, reach)`` as :func:`camera_lens` gives it, else
    an :class:`InputError`."""
    if value is None:
        return None
    if not (isinstance(value, tuple) and len(value) == 2 and callable(getattr(value[0], "distort", None))):
        raise InputError(
            f"lens = {arguments.shown(value)}: must be None (an ideal pinhole) or the (camera, reach) of camera_lens"
        )
    reach = arguments.real(value[1], name="lens reach", above=0.0, finite=False, error=InputError)
    return value[0], reach
