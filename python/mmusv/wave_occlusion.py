"""Wave occlusion: the share of a target hidden by the sea surface, per annotated box.

A target's *exposed silhouette* is the set of a sensor's rays that meet the vessel when it is alone in the
world (:class:`~mmusv.silhouettes.SilhouetteCache`) at a point above the still water level (world z > 0): the part
of the hull a flat calm sea would never hide. Its wave-occlusion share is the fraction of those rays that the
full scene stops at the water first — a crest in front, or the local surface over that part of the hull. With a
flat sea the share is 0 by construction; it is only computed where the scene has a displaced wave surface
(:meth:`~mmusv.scene.Scene.set_wave_surface`).

A target that no ray meets above the still level while some meet it below (a small craft wholly in a wave
trough) has its whole silhouette as its exposed silhouette, so that a craft the crests hide is counted hidden
rather than left out. A camera's box whose part above the still level the image border cuts off entirely is the
exception: its rays then meet only the lower hull of a ship whose upper part is out of the picture, and its exposed
silhouette is empty. So is a LiDAR's box through whose part above the still level none of its beams passes (the
vertical field of view, tilted with the hull, runs below it): the annotations pass ``whole_when_low`` false for it.
:func:`exposed_rays` is the one home of this rule; the cameras' ``occlusion`` (:mod:`mmusv.annotate`) uses it too.

* Cameras: the rays of the box's pixels; "stopped at the water" reads the captured instance image (the water
  instance there).
* LiDAR: the LiDAR's own beams within the box's angular extent (the azimuths of its corners and the elevations of
  every point of its edges seen from the LiDAR: a box seen broadside reaches higher and lower between its corners;
  every beam when the LiDAR's z axis passes through the box), cast against the vessel alone and then against the
  full scene; in a capture the full scene's answer is the one the LiDAR's own cast found
  (:attr:`~mmusv.simulation.AgentCapture.lidar_beams`), read rather than cast again. Only the part of the vessel
  within the LiDAR's range counts.

Frames: world x east, y north, z up, metres; directions need not be unit length. The LiDAR frame is the LiDAR's
body frame (x forward, y left, z up); a LiDAR pose is the ``(4, 4)`` rigid LiDAR → world transform.

Every function checks its arguments: an array of the wrong shape or dtype, a value that is not finite (where one
must be), a count or index out of range is an :class:`~mmusv.errors.InputError` naming the argument and what it must
be.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt

from mmusv import arguments
from mmusv.errors import InputError
from mmusv.scene import Scene

__all__ = [
    "BeamAngles",
    "exposed_hidden",
    "exposed_hidden_boxes",
    "exposed_rays",
    "lidar_beam_rays",
    "lidar_box_beams",
    "lidar_box_rays",
    "lidar_boxes_beams",
    "pattern_angles",
    "share",
]


def share(exposed: int, hidden: int) -> float:
    """``hidden / exposed`` (a float in ``[0, 1]``), 0 for an empty exposed silhouette: the counts of
    :func:`exposed_hidden`, whole numbers (``int`` or numpy integers) with ``0 <= hidden <= exposed``."""
    exposed = arguments.whole(exposed, name="exposed", lo=0, error=InputError)
    hidden = arguments.whole(hidden, name="hidden", lo=0, error=InputError)
    if hidden > exposed:
        raise InputError(f"hidden = {hidden}: must be <= exposed = {exposed} (the hidden rays are exposed rays)")
    return float(hidden / exposed) if exposed else 0.0


def exposed_rays(
    hit: npt.NDArray[np.bool_],
    z: npt.NDArray[np.float64],
    *,
    box: npt.NDArray[np.int64] | None = None,
    n_boxes: int = 1,
    whole_when_low: npt.NDArray[np.bool_] | None = None,
) -> npt.NDArray[np.bool_]:
    """The rays of each target's exposed silhouette (module docstring), ``(N,)`` bool.

    Args:
        hit: ``(N,)`` bool, whether each ray meets its target (alone in the world).
        z: ``(N,)`` float world height (metres, z up) where it meets it (any value where it does not).
        box: ``(N,)`` integer, each ray's target in ``0..n_boxes - 1``; ``None``: all rays are one target's.
        n_boxes: the number of targets ``B``, ``>= 1``.
        whole_when_low: ``(B,)`` bool, whether a target that no ray meets above the still level (while some meet
            it below) counts all the rays that meet it; ``None``: every target does.

    Returns the rays meeting their target above the still level 0, and every ray meeting a target met only below
    it where ``whole_when_low`` allows."""
    hit = np.asarray(hit)
    if hit.dtype != np.bool_ or hit.ndim != 1:
        raise InputError(f"hit must be an (N,) bool array, got {arguments.shown(hit)}")
    n = hit.size
    z = _array(z, name="z", shape=(n,), what=f"(N,) world heights in metres, N = {n}")
    n_boxes = arguments.whole(n_boxes, name="n_boxes", lo=1, error=InputError)
    if box is None:
        if n_boxes != 1:
            raise InputError(f"box is needed for n_boxes = {n_boxes}: each ray's target in 0..{n_boxes - 1}")
        box = np.zeros(n, dtype=np.int64)
    box = _array(box, name="box", shape=(n,), what=f"(N,) targets in 0..{n_boxes - 1}, N = {n}", integer=True)
    if box.size and (box.min() < 0 or box.max() >= n_boxes):
        raise InputError(f"box must be (N,) targets in 0..{n_boxes - 1}: it holds {int(box.min())}..{box.max()}")
    whole_when_low = _flags(whole_when_low, n_boxes)
    return _exposed(hit, z, box.astype(np.int64, copy=False), n_boxes, whole_when_low)


def _flags(whole_when_low: Any, n_boxes: int) -> np.ndarray | None:
    """``whole_when_low`` as a ``(n_boxes,)`` bool array (``None`` stays ``None``), else an :class:`InputError`."""
    if whole_when_low is None:
        return None
    given = np.asarray(whole_when_low)
    if given.shape != (n_boxes,) or given.dtype != np.bool_:
        raise InputError(
            f"whole_when_low must be a ({n_boxes},) bool array, a flag per target; got "
            f"{arguments.shown(whole_when_low)}"
        )
    return given


def _exposed(
    hit: np.ndarray, z: np.ndarray, box: np.ndarray, n_boxes: int, whole_when_low: np.ndarray | None
) -> npt.NDArray[np.bool_]:
    """:func:`exposed_rays`, its arguments checked."""
    exposed: npt.NDArray[np.bool_] = hit & (z > 0.0)
    low = (np.bincount(box[exposed], minlength=n_boxes) == 0) & (np.bincount(box[hit], minlength=n_boxes) > 0)
    if whole_when_low is not None:
        low &= whole_when_low
    return exposed | (hit & low[box]) if low.any() else exposed


def _array(value: Any, *, name: str, shape: tuple[int | None, ...], what: str, integer: bool = False) -> np.ndarray:
    """``value`` as an array (not copied when it is one) of real numbers (``integer``: of integers) whose shape is
    ``shape`` (``None``: any length on that axis), else an :class:`InputError` naming ``name`` and ``what`` it must
    be. Booleans, complex numbers, strings and objects are refused."""
    try:
        a = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be {what}: {exc}") from None
    kinds = "iu" if integer else "fiu"
    kind = "integers" if integer else "real numbers"
    if a.dtype.kind not in kinds and not (integer and a.size == 0 and a.dtype.kind == "f"):
        raise InputError(f"{name} must be {what} ({kind}), got dtype {a.dtype}")
    if arguments.holds_true_false(value, a):
        raise InputError(f"{name} must be {what} ({kind}): it holds true/false")
    if a.ndim != len(shape) or any(n is not None and a.shape[i] != n for i, n in enumerate(shape)):
        raise InputError(f"{name} must be {what}, got shape {a.shape}")
    return a


def _finite(a: np.ndarray, *, name: str, what: str) -> None:
    """An :class:`InputError` naming ``name`` and the first row of ``a`` that is not finite."""
    bad = ~np.isfinite(a)
    if bad.any():
        row = int(np.argwhere(bad)[0][0]) if a.ndim else 0
        raise InputError(f"{name} must be {what}: row {row} ({a[row].tolist()}) is not finite")


def _nonzero_rows(a: np.ndarray, *, name: str, what: str) -> None:
    """An :class:`InputError` naming ``name`` and the first row of the ``(N, 3)`` ``a`` that is all zeros (no
    direction)."""
    zero = ~a.any(axis=1)
    if zero.any():
        raise InputError(f"{name} must be {what}: row {int(np.argmax(zero))} is (0, 0, 0), which has no direction")


def _rigid(value: Any, *, name: str) -> np.ndarray:
    """``value`` as a ``(4, 4)`` array (its own real dtype, so that the arithmetic on it is what it was without the
    check) of a rigid transform (finite; rotation block orthonormal within 1e-5, last row ``0 0 0 1``), else an
    :class:`InputError` naming ``name``."""
    what = "a (4, 4) rigid LiDAR → world transform (metres; rotation, translation, last row 0 0 0 1)"
    given = _array(value, name=name, shape=(4, 4), what=what)
    m = np.asarray(given, dtype=np.float64)
    if not np.isfinite(m).all():
        raise InputError(f"{name} must be {what}: it holds values that are not finite")
    r = m[:3, :3]
    if np.abs(m[3] - (0.0, 0.0, 0.0, 1.0)).max() > 1e-9 or np.abs(r @ r.T - np.eye(3)).max() > 1e-5:
        raise InputError(f"{name} must be {what}: got {np.round(m, 6).tolist()}")
    return given


def exposed_hidden(
    scene: Scene,
    *,
    origins: npt.NDArray[np.float32],
    directions: npt.NDArray[np.float32],
    vessel_t: npt.NDArray[np.float32],
    scene_instance: npt.NDArray[np.int32] | None = None,
    max_range_m: float = float("inf"),
) -> tuple[int, int]:
    """``(exposed, hidden)`` ray counts of one target (see the module docstring): ``int``, ``0 <= hidden <=
    exposed <= N``. One target of :func:`exposed_hidden_boxes`.

    Args:
        scene: the full scene (a :class:`~mmusv.scene.Scene`), with its sea and wave surface set.
        origins: ``(N, 3)`` float32 (any real dtype) world ray origins, metres, finite.
        directions: ``(N, 3)`` float32 (any real dtype) world ray directions, finite, any non-zero length.
        vessel_t: ``(N,)`` float32 (any real dtype) distance, in units of each direction's length (metres for unit
            directions), at which each ray meets the vessel alone, ``>= 0``, ``inf`` where it misses it (not NaN).
            :meth:`Scene.cast_rays <mmusv.scene.Scene.cast_rays>` gives metres along the normalised direction: give
            unit directions with its distances.
        scene_instance: ``(N,)`` int32 (any integer dtype) instance each ray meets first in the full scene, when
            already known (a camera's instance image, a LiDAR's beams); else the rays are cast here.
        max_range_m: only the part of the vessel within this distance (metres, ``> 0``, ``inf``: all of it) of the
            origins counts (a LiDAR's range: what lies beyond it is neither seen nor hidden).
    """
    exposed, hidden = _counts(scene, origins, directions, vessel_t, None, scene_instance, max_range_m)
    return int(exposed[0]), int(hidden[0])


def exposed_hidden_boxes(
    scene: Scene,
    *,
    origins: npt.NDArray[np.float32],
    directions: npt.NDArray[np.float32],
    vessel_t: npt.NDArray[np.float32],
    starts: npt.NDArray[np.int64],
    scene_instance: npt.NDArray[np.int32] | None = None,
    max_range_m: float = float("inf"),
    whole_when_low: npt.NDArray[np.bool_] | None = None,
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """``(exposed, hidden)`` ray counts of ``B`` targets at once, each ``(B,)`` int64 with ``0 <= hidden <=
    exposed``: target ``b``'s rays are rows ``starts[b]:starts[b + 1]`` of the arrays, and its counts are those
    :func:`exposed_hidden` gives for them alone (a ray may appear in several targets' rows).

    Args:
        scene, origins, directions, vessel_t, scene_instance, max_range_m: as for :func:`exposed_hidden`, over all
            ``N`` rows (``vessel_t``: each row's distance to its own target alone).
        starts: ``(B + 1,)`` integer row offsets, non-decreasing, from 0 to ``N`` (:func:`lidar_boxes_beams`).
        whole_when_low: ``(B,)`` bool, whether a target that no ray meets above the still level counts its whole
            silhouette as exposed (:func:`exposed_rays`); ``None``: every target does. A camera passes ``False``
            for a box whose part above the still level lies wholly outside the image.
    """
    return _counts(scene, origins, directions, vessel_t, starts, scene_instance, max_range_m, whole_when_low)


def _counts(
    scene: Any,
    origins: Any,
    directions: Any,
    vessel_t: Any,
    starts: Any,
    scene_instance: Any,
    max_range_m: Any,
    whole_when_low: Any = None,
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """:func:`exposed_hidden_boxes` (``starts`` ``None``: all rows are one target), its arguments checked here."""
    if not isinstance(scene, Scene):
        raise InputError(
            f"scene = {arguments.shown(scene)}: must be a mmusv.scene.Scene (the full scene, with its sea), not "
            f"{type(scene).__name__}"
        )
    origins = _array(origins, name="origins", shape=(None, 3), what="(N, 3) world ray origins (float, metres)")
    n_rays = origins.shape[0]
    directions = _array(
        directions, name="directions", shape=(n_rays, 3), what=f"(N, 3) world ray directions (float), N = {n_rays}"
    )
    vessel_t = _array(
        vessel_t, name="vessel_t", shape=(n_rays,), what=f"(N,) float distances along the rays, N = {n_rays}"
    )
    _finite(origins, name="origins", what="finite world points (metres)")
    _finite(directions, name="directions", what="finite directions")
    _nonzero_rows(directions, name="directions", what="directions of any non-zero length")
    if np.isnan(vessel_t).any() or (vessel_t < 0).any():
        row = int(np.argmax(np.isnan(vessel_t) | (vessel_t < 0)))
        raise InputError(
            f"vessel_t must be distances >= 0 (inf where a ray misses the vessel): row {row} is {vessel_t[row]}"
        )
    what = f"(B + 1,) row offsets rising from 0 to N = {n_rays}"
    starts = (
        np.array([0, n_rays])
        if starts is None
        else _array(starts, name="starts", shape=(None,), what=what, integer=True)
    )
    # Compared pairwise, not by np.diff: a difference of unsigned offsets wraps round (uint8 2 - 3 is 255, a rise).
    if starts.size == 0 or starts[0] != 0 or starts[-1] != n_rays or (starts[1:] < starts[:-1]).any():
        raise InputError(f"starts must be {what}, got {starts.tolist()[:8]}{' ...' if starts.size > 8 else ''}")
    starts = starts.astype(np.int64, copy=False)  # within 0..N now: uint64 offsets are counts np.repeat takes
    if scene_instance is not None:
        scene_instance = _array(
            scene_instance,
            name="scene_instance",
            shape=(n_rays,),
            what=f"(N,) instance ids, N = {n_rays}",
            integer=True,
        )
    max_range_m = arguments.real(
        max_range_m, name="max_range_m", unit="metres", above=0.0, finite=False, error=InputError
    )
    n_boxes = starts.size - 1
    whole_when_low = _flags(whole_when_low, n_boxes)
    box = np.repeat(np.arange(n_boxes), np.diff(starts))
    o = np.asarray(origins, dtype=np.float64)
    d = np.asarray(directions, dtype=np.float64)
    t = np.asarray(vessel_t, dtype=np.float64)
    hit = np.isfinite(t)
    if np.isfinite(max_range_m):
        hit &= np.where(hit, t, 0.0) * np.linalg.norm(d, axis=1) <= max_range_m
    z = o[:, 2] + d[:, 2] * np.where(hit, t, 0.0)
    exposed = _exposed(hit, z, box, n_boxes, whole_when_low)
    counts = np.bincount(box[exposed], minlength=n_boxes).astype(np.int64)
    water = scene.sea_instance
    if not exposed.any() or water is None or scene.wave_top is None:
        return counts, np.zeros(n_boxes, dtype=np.int64)
    if scene_instance is None:
        hits = scene.cast_rays(o[exposed].astype(np.float32), d[exposed].astype(np.float32))
        first = hits.instance_id
    else:
        first = np.asarray(scene_instance)[exposed]
    hidden = np.bincount(box[exposed][first == water], minlength=n_boxes).astype(np.int64)
    return counts, hidden


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
    """The :class:`BeamAngles` (azimuth, elevation, radians, float64) of a LiDAR's unit beam directions ``pattern``
    ``(M, 3)`` float32 (any real dtype, taken as float32; LiDAR frame; finite, none ``(0, 0, 0)``), to pass to
    :func:`lidar_box_rays`. Remembered by content: a rig's pattern is worked out once, not per frame; a read-only
    array that owns its data (``Agent.lidar_pattern``), passed again, is recognised by identity without hashing
    it."""
    same = _LAST.get(id(pattern))
    if same is not None and same[0] is pattern and _frozen(pattern):
        return same[1]  # the very (read-only) array of the last call: a rig's pattern, passed every frame
    _pattern(pattern)
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


_PATTERN = "(M, 3) float32 unit beam directions in the LiDAR frame"


def _pattern(value: Any) -> np.ndarray:
    """``value`` checked as a LiDAR pattern (:data:`_PATTERN`: finite, no ``(0, 0, 0)`` row), else an
    :class:`InputError`."""
    p = _array(value, name="pattern", shape=(None, 3), what=_PATTERN)
    _finite(p, name="pattern", what="finite directions")
    _nonzero_rows(p, name="pattern", what=_PATTERN)
    return p


def _angles(value: Any) -> BeamAngles:
    """``value`` when it is the :class:`BeamAngles` of a pattern (:func:`pattern_angles`), else an
    :class:`InputError`."""
    if not isinstance(value, BeamAngles):
        raise InputError(
            f"angles = {arguments.shown(value)}: must be the BeamAngles of the pattern (pattern_angles(pattern)), "
            f"not {type(value).__name__}"
        )
    return value


def _box(value: Any) -> np.ndarray:
    """``value`` checked as ``(8, 3)`` finite world box corners, else an :class:`InputError`."""
    what = "the (8, 3) world corners of a box (float, metres)"
    c = _array(value, name="corners_world", shape=(8, 3), what=what)
    _finite(c, name="corners_world", what=what)
    return c


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
    *,
    lidar_pose: npt.NDArray[np.float64],
    corners_world: npt.NDArray[np.float64],
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
    """The LiDAR's world rays ``(origins, directions)`` (each ``(K, 3)`` float32, world frame: origins in metres,
    unit directions, in pattern order) whose direction lies within the azimuth and elevation extent of the box
    ``corners_world`` ``(8, 3)`` float64 (world, metres) seen from the LiDAR at ``lidar_pose`` ``(4, 4)`` float64
    rigid LiDAR → world; ``pattern`` ``(M, 3)`` float32 unit directions in the LiDAR frame, ``angles`` their
    :func:`pattern_angles` (of the same ``M`` beams). The rays of :func:`lidar_box_beams`' beams."""
    m = _pattern(pattern).shape[0]
    n = _angles(angles).az.shape[0]
    if n != m:
        raise InputError(
            f"angles are of a pattern of {n} beams, pattern has {m}: give pattern_angles(pattern) of this pattern"
        )
    beams = lidar_box_beams(angles, lidar_pose=lidar_pose, corners_world=corners_world)
    return lidar_beam_rays(pattern, lidar_pose=lidar_pose, beams=beams)


def lidar_box_beams(
    angles: BeamAngles,
    *,
    lidar_pose: npt.NDArray[np.float64],
    corners_world: npt.NDArray[np.float64],
) -> npt.NDArray[np.int64]:
    """``(K,)`` int64 pattern indices (ascending) of the beams whose direction lies within the azimuth and
    elevation extent of the box ``corners_world`` ``(8, 3)`` float64 (world, metres) seen from the LiDAR at
    ``lidar_pose`` ``(4, 4)`` float64 rigid LiDAR → world; ``angles`` the pattern's :func:`pattern_angles`. One box
    of :func:`lidar_boxes_beams`."""
    beams, _ = lidar_boxes_beams(angles, lidar_pose=lidar_pose, corners_world=_box(corners_world)[None])
    return beams


def lidar_boxes_beams(
    angles: BeamAngles,
    *,
    lidar_pose: npt.NDArray[np.float64],
    corners_world: npt.NDArray[np.float64],
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """The beams of many boxes at once, as :func:`lidar_box_beams` finds them one box at a time: ``(beams,
    starts)``, where box ``b``'s beams are ``beams[starts[b]:starts[b + 1]]`` (pattern indices, int64, ascending
    within each box; a beam in two boxes' extents is listed in both) and ``starts`` ``(B + 1,)`` int64 begins at 0.

    Args:
        angles: the pattern's :func:`pattern_angles`.
        lidar_pose: ``(4, 4)`` float64 rigid LiDAR → world.
        corners_world: ``(B, 8, 3)`` float64 world corners of ``B`` boxes (metres, finite; ``B`` may be 0).
    """
    angles = _angles(angles)
    lidar_pose = _rigid(lidar_pose, name="lidar_pose")
    what = "the (B, 8, 3) world corners of B boxes (float, metres)"
    corners = _array(corners_world, name="corners_world", shape=(None, 8, 3), what=what)
    bad = ~np.isfinite(corners).all(axis=2)
    if bad.any():
        b, k = (int(i) for i in np.argwhere(bad)[0])
        raise InputError(f"corners_world must be {what}: box {b} corner {k} ({corners[b, k].tolist()}) is not finite")
    n_boxes = corners.shape[0]
    starts = np.zeros(n_boxes + 1, dtype=np.int64)
    if n_boxes == 0:
        return np.zeros(0, dtype=np.int64), starts
    inv = np.linalg.inv(lidar_pose)
    c = corners @ inv[:3, :3].T + inv[:3, 3]  # (B, 8, 3): box by box, the same product as one (8, 3) box alone
    az = np.arctan2(c[..., 1], c[..., 0])
    # Azimuths relative to each box's mean direction, so a box straddling ±π is one interval.
    mids = [np.arctan2(s, co) for s, co in zip(np.sin(az).mean(axis=1), np.cos(az).mean(axis=1), strict=True)]
    mid = np.array(mids, dtype=np.float64)
    rel = np.angle(np.exp(1j * (az - mid[:, None])))
    rel_lo, rel_hi = rel.min(axis=1), rel.max(axis=1)
    el_lo, el_hi, around = _elevation_extent(c, az)
    # A box the LiDAR's z axis passes through surrounds it: every azimuth, every elevation.
    rel_lo, rel_hi = np.where(around, -np.pi, rel_lo), np.where(around, np.pi, rel_hi)
    el_lo, el_hi = np.where(around, -np.pi / 2, el_lo), np.where(around, np.pi / 2, el_hi)
    # Candidates: the beams whose azimuth lies in the window (a margin wider, wrapped into [-π, π]) by binary
    # search on the sorted azimuths; the exact test below then keeps what testing every beam would keep.
    cands = [
        _azimuth_window(angles, float(mid[b] + rel_lo[b] - 1e-6), float(mid[b] + rel_hi[b] + 1e-6))
        for b in range(n_boxes)
    ]
    cand = np.concatenate(cands)
    box = np.repeat(np.arange(n_boxes), [len(k) for k in cands])
    paz, pel = angles.az[cand], angles.el[cand]
    prel = np.angle(np.exp(1j * (paz - mid[box])))
    keep = (pel >= el_lo[box]) & (pel <= el_hi[box]) & (prel >= rel_lo[box]) & (prel <= rel_hi[box])
    np.cumsum(np.bincount(box[keep], minlength=n_boxes), out=starts[1:])
    beams: npt.NDArray[np.int64] = cand[keep].astype(np.int64, copy=False)
    return beams, starts


_PAIRS = np.array([(a, b) for a in range(8) for b in range(a + 1, 8)], dtype=np.int64)
"""Every pair of a box's corners: its twelve edges among them, whatever order the corners come in."""


def _elevation_extent(c: np.ndarray, az: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(el_lo, el_hi, around)`` of ``B`` boxes' corners ``c`` ``(B, 8, 3)`` in the LiDAR frame (``az`` ``(B, 8)``
    their azimuths, radians): the lowest and
    highest elevation (radians) of any point of each box, and whether the LiDAR's z axis passes through it (then
    the box surrounds the LiDAR in azimuth and reaches ±π/2; ``el_lo``/``el_hi`` are not meaningful there).

    A box seen broadside reaches higher and lower between its corners than at them (the elevation of its top edge
    is greatest where the edge passes nearest), so the corners alone bound too narrow a band. The extremes of the
    elevation over a convex box that the z axis misses lie on its edges; along a segment ``p(t)``, ``tan el = z(t)
    / r(t)`` has one stationary point, ``t = (z0·B/2 − dz·C) / (dz·B/2 − z0·A)`` with ``r(t)² = A·t² + B·t + C``,
    so each edge's extremes are its ends or that point (every pair of corners is tried: the edges are among them
    whatever the corners' order, and the other pairs lie inside the box). The z axis passes through the box when the
    corners' azimuths leave no gap wider than π (the origin lies in their convex hull in the xy plane)."""
    x0 = c[:, _PAIRS[:, 0]]  # (B, 28, 3)
    d = c[:, _PAIRS[:, 1]] - x0
    a = d[..., 0] ** 2 + d[..., 1] ** 2
    b = 2.0 * (x0[..., 0] * d[..., 0] + x0[..., 1] * d[..., 1])
    cc = x0[..., 0] ** 2 + x0[..., 1] ** 2
    num = x0[..., 2] * b / 2.0 - d[..., 2] * cc
    den = d[..., 2] * b / 2.0 - x0[..., 2] * a
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(den != 0.0, num / np.where(den != 0.0, den, 1.0), 0.0)
    t = np.clip(np.nan_to_num(t, nan=0.0, posinf=1.0, neginf=0.0), 0.0, 1.0)[..., None]
    p = np.concatenate([c, x0 + t * d], axis=1)  # the corners and each pair's stationary point
    el = np.arctan2(p[..., 2], np.hypot(p[..., 0], p[..., 1]))
    r = np.hypot(c[..., 0], c[..., 1])
    az = np.sort(az, axis=1)
    gaps = np.concatenate([np.diff(az, axis=1), (az[:, :1] + 2 * np.pi) - az[:, -1:]], axis=1)
    around = (gaps.max(axis=1) <= np.pi + 1e-9) | (r.min(axis=1) <= 1e-9)
    lo: np.ndarray = el.min(axis=1)
    hi: np.ndarray = el.max(axis=1)
    return lo, hi, around


def lidar_beam_rays(
    pattern: npt.NDArray[np.float32], *, lidar_pose: npt.NDArray[np.float64], beams: npt.NDArray[np.int64]
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
    """The world rays ``(origins, directions)`` (each ``(K, 3)`` float32, world frame: origins in metres,
    directions the beams' turned by the pose) of the pattern's ``beams`` (``(K,)`` integer indices in ``0..M - 1``,
    in the order given) from the LiDAR at ``lidar_pose`` ``(4, 4)`` float64 rigid LiDAR → world; ``pattern``
    ``(M, 3)`` float32 unit directions in the LiDAR frame."""
    p = _array(pattern, name="pattern", shape=(None, 3), what=_PATTERN)
    lidar_pose = _rigid(lidar_pose, name="lidar_pose")
    m = p.shape[0]
    beams = _array(beams, name="beams", shape=(None,), what=f"(K,) beam indices in 0..{m - 1}", integer=True)
    if beams.size == 0:
        beams = beams.astype(np.int64)
    elif beams.min() < 0 or beams.max() >= m:
        bad = beams[(beams < 0) | (beams >= m)][0]
        raise InputError(f"beams must be indices of the pattern's beams, in 0..{m - 1}: got {bad}")
    # Only the selected beams are checked, and widened to float64 (the same values as widening the whole pattern).
    chosen = p[beams]
    bad = ~np.isfinite(chosen).all(axis=1) | ~chosen.any(axis=1)
    if bad.any():
        k = int(beams[np.argmax(bad)])
        raise InputError(f"pattern must be {_PATTERN}: row {k} ({p[k].tolist()}) is not a finite non-zero direction")
    dirs = (chosen.astype(np.float64) @ lidar_pose[:3, :3].T).astype(np.float32)
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
