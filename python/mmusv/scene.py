"""The low-level ray-casting scene: build it from numpy arrays, place instances, cast rays.

Frames and units: world frame right-handed (x east, y north, z up), metres. A pose is a ``(4, 4)`` homogeneous
rigid transform (body → world). Distances are metres along the normalised ray direction.

Example::

    scene = Scene()
    mesh = scene.add_mesh(vertices, faces, classes=10)
    boat = scene.add_instance(mesh, pose=np.eye(4))
    hits = scene.cast_rays(origins, directions, max_range=200.0)
    hits.distance  # (N,) float32, inf where nothing was hit
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from mmusv import arguments
from mmusv._native import core
from mmusv.errors import GeometryError, InputError, NotFoundError

# MAX_SURFACE_TILES, SURFACE_TAPER_M, SURFACE_TILE_M, surface_taper and surface_tiles lived here until 2026-12-07
# and are still importable from here; mmusv.sea_surface is their home.
from mmusv.sea_surface import (  # noqa: F401
    MAX_SURFACE_TILES,
    SURFACE_TAPER_M,
    SURFACE_TILE_M,
    SeaState,
    surface_args,
    surface_taper,
    surface_tiles,
)

__all__ = [
    "NO_HIT",
    "RayHits",
    "Scene",
    "demo_scene",
]

NO_HIT = -1
"""Value of ``RayHits.instance_id`` and ``triangle_id`` where the ray hit nothing."""

MAX_DEMO_CELLS: int = core.MAX_DEMO_SIZE
"""Largest ``terrain_cells`` and ``vessels`` of :func:`demo_scene` (4096² cells: 33 million terrain triangles; the
core's bound, which it checks itself)."""


@dataclass(frozen=True)
class RayHits:
    """Per-ray results of :meth:`Scene.cast_rays` (N rays); arrays are owned, not copies of Rust memory views.

    Attributes:
        distance: ``(N,)`` float32, metres along the unit direction; ``inf`` for a miss.
        instance_id: ``(N,)`` int32, instance hit or ``-1``.
        triangle_id: ``(N,)`` int32, triangle index within that instance's mesh, or ``-1``.
        normal: ``(N, 3)`` float32, unit geometric normal (world frame, triangle winding); zeros for a miss.
        semantic_class: ``(N,)`` uint16, class of the triangle hit (see :mod:`mmusv.classes`); 0 for a miss.
        backface: ``(N,)`` bool, the ray hit the triangle's back side (``normal · direction > 0``).
    """

    distance: npt.NDArray[np.float32]
    instance_id: npt.NDArray[np.int32]
    triangle_id: npt.NDArray[np.int32]
    normal: npt.NDArray[np.float32]
    semantic_class: npt.NDArray[np.uint16]
    backface: npt.NDArray[np.bool_]

    @property
    def hit(self) -> npt.NDArray[np.bool_]:
        """``(N,)`` bool, True where the ray hit something within range."""
        return self.instance_id >= 0

    def points(self, origins: npt.ArrayLike, directions: npt.ArrayLike) -> npt.NDArray[np.float32]:
        """``(N, 3)`` float32 world hit points (``nan`` rows for misses) of the ``(N, 3)`` ``origins`` and
        non-zero ``directions`` the rays were cast with."""
        n = self.distance.shape[0]
        o = arguments.rows(origins, name="origins", dtype=np.float32, tail=(3,), error=InputError)
        d = arguments.rows(directions, name="directions", dtype=np.float32, tail=(3,), error=InputError)
        if o.shape[0] != n or d.shape[0] != n:
            raise InputError(
                f"points: got {o.shape[0]} origins and {d.shape[0]} directions for {n} rays; give the arrays the rays "
                "were cast with"
            )
        norm = np.linalg.norm(d, axis=1, keepdims=True)
        if n and not (np.isfinite(norm).all() and (norm > 0).all()):
            raise InputError("points: every direction must be finite and non-zero")
        d = d / norm
        with np.errstate(invalid="ignore"):
            p: npt.NDArray[np.float32] = o + d * self.distance[:, None]
        p[~self.hit] = np.nan
        return p.astype(np.float32, copy=False)


def _floats(value: Any, *, name: str) -> np.ndarray:
    """``value`` as a float64 array of real numbers (:func:`mmusv.arguments.reals`: not true/false, text, None or
    complex numbers), or an :class:`InputError` naming ``name``."""
    return arguments.reals(value, name=name, what="an array", error=InputError)


def _uint16s(value: Any, *, name: str) -> np.ndarray:
    """``value``, one integer or a 1-D integer array of ids in ``0..65535`` (classes, materials), as a ``(N,)``
    C-contiguous uint16 array (``(1,)`` for one id); else an :class:`InputError` naming ``name``."""
    a = np.atleast_1d(np.asarray(value))
    if a.ndim != 1 or not np.issubdtype(a.dtype, np.integer):
        raise InputError(f"{name} must be an int or a 1-D integer array, got {a.dtype} with shape {a.shape}")
    if a.size and (a.min() < 0 or a.max() > 65535):
        raise InputError(f"{name} must be in 0..65535")
    return np.ascontiguousarray(a, dtype=np.uint16)


def _id(value: Any, *, name: str, kind: str) -> int:
    """A non-negative integer id that fits in uint32, else :class:`InputError` / :class:`NotFoundError`."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise InputError(f"{name} must be an integer id, got {value!r}")
    i = int(value)
    if not 0 <= i < 2**32:
        raise NotFoundError(f"unknown {kind} id {i}: {name} must be a non-negative id returned by the scene")
    return i


def _instance_ids(values: npt.ArrayLike) -> np.ndarray:
    """``instance_ids`` as a contiguous ``(K,)`` uint32 array: not a 1-D integer array is :class:`InputError`, an id
    below 0 or from 2³² on is :class:`NotFoundError` (as an id the scene does not hold is, from the core)."""
    ids = np.atleast_1d(np.asarray(values))
    if ids.size == 0:
        return np.zeros(0, dtype=np.uint32)
    if ids.ndim != 1 or not np.issubdtype(ids.dtype, np.integer):
        raise InputError(f"instance_ids must be a 1-D integer array, got {ids.dtype} with shape {ids.shape}")
    if ids.min() < 0 or ids.max() >= 2**32:
        bad = int(ids.min()) if ids.min() < 0 else int(ids.max())
        raise NotFoundError(f"unknown instance id {bad}: instance ids are the non-negative ids add_instance returned")
    return np.ascontiguousarray(ids, dtype=np.uint32)


def _pose(pose: Any, *, name: str) -> np.ndarray:
    arr = _floats(pose, name=name)
    if arr.shape != (4, 4):
        raise InputError(f"{name} must be a (4, 4) homogeneous matrix, got shape {arr.shape}")
    return np.ascontiguousarray(arr)


class Scene:
    """Meshes (each with a bottom-level BVH built once) placed as instances under a top-level BVH.

    Moving instances with :meth:`set_poses` only rebuilds the top level. All ray casting releases the GIL
    and uses every core.
    """

    def __init__(self) -> None:
        self._native = core.Scene()

    @classmethod
    def _from_native(cls, native: Any) -> Scene:
        obj = cls.__new__(cls)
        obj._native = native
        return obj

    @property
    def native(self) -> Any:
        """The underlying ``mmusv._core.Scene``."""
        return self._native

    def add_mesh(
        self,
        vertices: npt.ArrayLike,
        faces: npt.ArrayLike,
        *,
        classes: int | npt.ArrayLike = 0,
        name: str = "",
        materials: int | npt.ArrayLike | None = None,
    ) -> int:
        """Adds a triangle mesh and returns its mesh id.

        Args:
            vertices: ``(V, 3)`` float32/float64 positions, metres, in the mesh's own frame.
            faces: ``(F, 3)`` integer vertex indices in ``0..V``.
            classes: one semantic class id for the whole mesh, or ``(F,)`` ids, one per face (0..65535).
            name: free text, shown in errors and exports.
            materials: one material id or ``(F,)`` ids into the table of :meth:`set_materials` (0: the class's
                default look; the cameras' shading only). ``None``: no materials.
        """
        if not isinstance(name, str):
            raise InputError(f"name = {arguments.shown(name)}: must be a str (free text), not {type(name).__name__}")
        v = arguments.rows(vertices, name="vertices", dtype=np.float32, tail=(3,), error=InputError)
        raw_faces = np.asarray(faces)
        if raw_faces.dtype.kind == "u" and raw_faces.size and int(raw_faces.max()) >= 2**63:
            raise GeometryError(
                f"invalid geometry in faces: index {int(raw_faces.max())} lies outside the {v.shape[0]} vertices; "
                f"indices must be in 0..{v.shape[0] - 1}"
            )
        f = arguments.rows(raw_faces, name="faces", dtype=np.int64, tail=(3,), error=InputError)
        c = _uint16s(classes, name="classes")
        if v.shape[0] and not np.isfinite(np.asarray(vertices, dtype=np.float64)).all():
            bad = int(np.argwhere(~np.isfinite(np.asarray(vertices, dtype=np.float64)).all(axis=1))[0, 0])
            raise GeometryError(f"invalid geometry in vertices[{bad}]: vertex is not finite; remove NaN/inf vertices")
        m = None if materials is None else _uint16s(materials, name="materials")
        return int(self._native.add_mesh(v, f, c, name, m))

    def set_materials(self, table: npt.ArrayLike) -> None:
        """Sets the material table: ``(M, 11)`` float rows ``r, g, b, roughness, metallic, er, eg, eb, nav_light,
        arc_centre, arc_half`` (linear base colour and roughness, metallic in [0, 1]; emitted radiance in cd/m²;
        nav_light 0 or 1, a light that glows only on instances whose lights are on and only towards bearings
        within its arc: centre in [-180, 180] and half-width in (0, 180] degrees in the instance's body frame, 0
        right ahead and +90 to port, 180 all round). ``(M, 9)`` rows (without the arc) light all round. Row 0 is
        never read (material id 0 means none). :func:`mmusv.world.materials.material_table` gives the library's."""
        t = np.ascontiguousarray(_floats(table, name="materials"), dtype=np.float32)
        if t.ndim != 2 or t.shape[1] not in (9, 11):
            raise InputError(f"materials must have shape (M, 11) or (M, 9) (lights all round), got {t.shape}")
        if t.shape[1] == 9:
            arcs = np.tile(np.array([0.0, 180.0], dtype=np.float32), (t.shape[0], 1))
            t = np.ascontiguousarray(np.hstack([t, arcs]))
        self._native.set_materials(t)

    @property
    def num_materials(self) -> int:
        """Rows of the material table (0 before :meth:`set_materials`)."""
        return int(self._native.num_materials)

    def set_seabed(
        self, heights: npt.ArrayLike | None, *, x0: float = 0.0, y0: float = 0.0, spacing: float = 1.0
    ) -> None:
        """Sets the seabed the cameras see through shallow water: ``heights`` ``(ny, nx)`` world z in metres
        (negative below the sea surface) at vertices ``(x0 + j·spacing, y0 + i·spacing)``, row ``i`` northwards;
        ``None`` clears it (water is then deep everywhere). Outside the grid the water is deep."""
        if heights is None:
            self._native.set_seabed(None)
            return
        z = np.ascontiguousarray(_floats(heights, name="seabed heights"), dtype=np.float32)
        if z.ndim != 2:
            raise InputError(f"seabed heights must have shape (ny, nx), got {z.shape}")
        xy0 = [arguments.real(v, name=k, unit="metres", error=InputError) for k, v in (("x0", x0), ("y0", y0))]
        step = arguments.real(spacing, name="spacing", unit="metres", above=0.0, error=InputError)
        self._native.set_seabed(z, x0=xy0[0], y0=xy0[1], spacing=step)

    def set_lights(self, instance_ids: npt.ArrayLike, *, on: bool) -> None:
        """Turns the navigation lights (materials with ``nav_light``) of ``instance_ids`` ``(K,)`` on or off (``on``:
        a ``bool``); an id the scene does not hold is :class:`NotFoundError`."""
        on = arguments.flag(on, name="on", error=InputError)
        ids = _instance_ids(instance_ids)
        if ids.size:
            self._native.set_lights(ids, bool(on))

    def add_instance(
        self, mesh_id: int, *, pose: npt.ArrayLike | None = None, class_override: int | None = None
    ) -> int:
        """Places mesh ``mesh_id`` at ``pose`` (``(4, 4)`` body → world, default identity); returns the instance id.

        ``class_override`` replaces the mesh's per-face classes for this instance (e.g. a vessel asset placed
        as a USV).
        """
        p = _pose(np.eye(4) if pose is None else pose, name="pose")
        if class_override is not None and (
            isinstance(class_override, bool) or not isinstance(class_override, (int, np.integer))
        ):
            raise InputError(f"class_override must be an integer class id in 0..65535, got {class_override!r}")
        if class_override is not None and not 0 <= int(class_override) <= 65535:
            raise InputError(f"class_override must be in 0..65535, got {class_override}")
        cls = None if class_override is None else int(class_override)
        return int(self._native.add_instance(_id(mesh_id, name="mesh_id", kind="mesh"), p, cls))

    def set_poses(self, instance_ids: npt.ArrayLike, poses: npt.ArrayLike) -> None:
        """Moves instances: ``instance_ids`` ``(K,)`` ints, each once, ``poses`` ``(K, 4, 4)`` float body → world
        (metres; one ``(4, 4)`` for one id). Only the top level is rebuilt; a bad or repeated id or a bad pose is an
        :class:`~mmusv.errors.InputError` (or :class:`~mmusv.errors.NotFoundError`) and moves nothing."""
        p = _floats(poses, name="poses")
        if np.size(instance_ids) == 0 and p.size == 0:
            return
        ids = _instance_ids(instance_ids)
        if p.ndim == 2:
            p = p[None]
        if p.ndim != 3 or p.shape[1:] != (4, 4):
            raise InputError(f"poses must have shape (K, 4, 4) (or (4, 4) for one id), got {np.shape(poses)}")
        self._native.set_poses(ids, np.ascontiguousarray(p))

    def set_sea(self, surface: int, *, moving: npt.ArrayLike = ()) -> None:
        """Declares instance ``surface`` the sea surface, a horizontal plane (else :class:`InputError`), and
        ``moving`` the instances that will move (vessels).

        Rays that can then only meet the surface or the sky are answered from a height map of everything else
        instead of a full trace: exactly the same hits (the surface hit is still computed by its mesh), fewer
        node visits. Moving another instance later is allowed (it is treated as moving from then on); moving
        the surface itself switches the shortcuts off.
        """
        ids = np.atleast_1d(np.asarray(moving))
        if ids.size and (ids.ndim != 1 or not np.issubdtype(ids.dtype, np.integer)):
            raise InputError(f"moving must be a 1-D list of integer instance ids, got {ids.dtype} of shape {ids.shape}")
        ids = ids.astype(np.int64)
        if ids.size and (ids.min() < 0 or ids.max() >= 2**32):
            raise NotFoundError(f"unknown instance id in moving: {ids.tolist()}")
        self._native.set_sea(_id(surface, name="surface", kind="instance"), np.ascontiguousarray(ids, np.uint32))

    def set_wave_surface(
        self,
        sea: SeaState | None,
        *,
        scenario_seed: int,
        time_s: float,
        foci: npt.ArrayLike,
        radius_m: float = 320.0,
        detail: bool = True,
        slopes: bool = True,
        fine_m: float = 0.0,
    ) -> None:
        """Sets the displaced sea surface of one frame time (``mmusv_core::sea::WaveSurface``), which replaces the
        sea instance's flat mesh for every ray: crests occlude, beams meet wave faces. The scene must have a sea
        (:meth:`set_sea`); ``sea=None`` clears it.

        Args:
            sea: the directional JONSWAP sea; its wave field is drawn from the scenario's sea seed, the one field
                the hulls ride.
            scenario_seed: the scenario's seed.
            time_s: the frame time, seconds, within ±1e9 (about 32 years; the waves' phases lose precision
                past it).
            foci: ``(F, 2)`` float world x, y (metres) the sampling is finest around (the USVs); the same foci for
                every sensor of a frame give every sensor the same surface.
            radius_m: the waves taper to still water this far from the nearest focus (metres, > 0).
            detail: the finest tiles (1 m cells, within 40 m of a focus) also carry the slopes of the waves 1–2 m
                long on a 0.5 m grid, so the cameras shade them as normals rather than roughness; the geometry,
                and so every ray's hit, is the same either way. Costs sampling time; without cameras, leave it
                off (:meth:`~mmusv.simulation.Simulation.capture` does).
            slopes: the tiles carry the slopes of the waves they resolve, which only the cameras' shading reads;
                off, the heights alone are sampled (cheaper; ``detail`` is then off too, and every ray's hit is the
                same). :meth:`~mmusv.simulation.Simulation.capture` leaves them out for frames nothing renders.
            fine_m: with ``detail``, the coarser tiles within this distance of a focus (metres, >= 0; 0: none) also
                carry the slopes of the waves a 1 m grid resolves, drawn where a pixel's footprint resolves them:
                an orthographic top view, one footprint everywhere, then shades every level alike instead of
                showing the levels' edges as squares around its USV. The simulation sets it to its top views'
                reach; the geometry is the same either way.
        """
        hs, kw = surface_args(
            sea,
            scenario_seed=scenario_seed,
            time_s=time_s,
            foci=foci,
            radius_m=radius_m,
            detail=detail,
            slopes=slopes,
            fine_m=fine_m,
        )
        self._native.set_wave_surface(hs, **kw)

    def prefetch_wave_surface(
        self,
        sea: SeaState | None,
        *,
        scenario_seed: int,
        time_s: float,
        foci: npt.ArrayLike,
        radius_m: float = 320.0,
        detail: bool = True,
        slopes: bool = True,
        fine_m: float = 0.0,
    ) -> None:
        """Starts sampling, on a thread of its own, the surface a later :meth:`set_wave_surface` with the same
        arguments will set (the next frame's, while this one is annotated and written: what
        :meth:`~mmusv.simulation.Simulation.prefetch_frame` does); that call then takes it instead of sampling it
        again, and any other call leaves it unused. The same surface bit for bit. Arguments as for
        :meth:`set_wave_surface`, checked now; ``sea=None`` drops a surface being sampled ahead."""
        hs, kw = surface_args(
            sea,
            scenario_seed=scenario_seed,
            time_s=time_s,
            foci=foci,
            radius_m=radius_m,
            detail=detail,
            slopes=slopes,
            fine_m=fine_m,
        )
        self._native.prefetch_wave_surface(hs, **kw)

    def wave_heights(self, xy: npt.ArrayLike) -> npt.NDArray[np.float32]:
        """``(N,)`` float32 world z of the sea surface at ``xy`` ``(N, 2)`` finite world x, y (metres): the
        displaced surface of :meth:`set_wave_surface`, or the still level 0 where there is none."""
        p = arguments.rows(xy, name="xy", dtype=np.float32, tail=(2,), error=InputError)
        bad = np.flatnonzero(~np.isfinite(p).all(axis=1))
        if bad.size:
            raise InputError(f"invalid xy[{int(bad[0])}]: {p[bad[0]].tolist()} is not finite; give world x, y, metres")
        return self._native.wave_heights(p)

    @property
    def wave_top(self) -> float | None:
        """The crest bound (highest world z, metres) of the displaced sea surface, or ``None`` when none is set."""
        top: float | None = self._native.wave_top
        return top

    def clear_sea(self) -> None:
        """Forgets the sea surface: every ray is traced fully again (results are the same either way)."""
        self._native.clear_sea()

    @property
    def sea_instance(self) -> int | None:
        """The sea surface instance id (see :meth:`set_sea`), or ``None``."""
        sea: int | None = self._native.sea_instance
        return sea

    def cast_rays(
        self, origins: npt.ArrayLike, directions: npt.ArrayLike, *, max_range: float = float("inf")
    ) -> RayHits:
        """Casts ``N`` rays and returns the closest hit of each.

        Args:
            origins: ``(N, 3)`` float, world frame, metres.
            directions: ``(N, 3)`` float, world frame; any non-zero length (normalised internally).
            max_range: metres; hits farther than this are misses.
        """
        o = arguments.rows(origins, name="origins", dtype=np.float32, tail=(3,), error=InputError)
        d = arguments.rows(directions, name="directions", dtype=np.float32, tail=(3,), error=InputError)
        limit = arguments.real(max_range, name="max_range", unit="metres", above=0.0, finite=False, error=InputError)
        dist, inst, tri, normal, cls, back = self._native.cast_rays(o, d, limit)
        return RayHits(dist, inst, tri, normal, cls, back)

    def world_mesh(self) -> dict[str, np.ndarray]:
        """The world triangles at the current poses: ``vertices`` ``(V, 3)`` float32 world metres, ``faces``
        ``(F, 3)`` uint32 vertex indices, ``classes`` ``(F,)`` uint16, ``instance_ids`` and ``triangle_ids`` ``(F,)``
        uint32."""
        v, f, c, i, t = self._native.world_mesh()
        return {"vertices": v, "faces": f, "classes": c, "instance_ids": i, "triangle_ids": t}

    def export(self, path: str | os.PathLike[str]) -> None:
        """Writes the world triangles at the current poses to ``path`` (a ``str`` or ``os.PathLike``: ``.ply``
        with per-face class and instance, or ``.obj``); written atomically."""
        self._native.export(os.fspath(arguments.path(path, name="path", error=InputError)))

    def instance_aabb(self, instance_id: int) -> np.ndarray:
        """``(2, 3)`` float32 world AABB (min row, max row), metres, of an instance at its current pose."""
        return np.asarray(self._native.instance_aabb(_id(instance_id, name="instance_id", kind="instance")))

    def instance_pose(self, instance_id: int) -> np.ndarray:
        """``(4, 4)`` float64 current pose of an instance (body → world, metres)."""
        return np.asarray(self._native.instance_pose(_id(instance_id, name="instance_id", kind="instance")))

    @property
    def num_instances(self) -> int:
        """Number of instances."""
        return int(self._native.num_instances)

    @property
    def num_meshes(self) -> int:
        """Number of meshes."""
        return int(self._native.num_meshes)

    @property
    def num_world_triangles(self) -> int:
        """Number of triangles placed in the world."""
        return int(self._native.num_world_triangles)

    def __repr__(self) -> str:
        return repr(self._native)


def demo_scene(
    *, seed: int = 1, extent: float = 2000.0, terrain_cells: int = 512, vessels: int = 48
) -> tuple[Scene, list[int]]:
    """The synthetic maritime benchmark scene: seabed/islands heightfield (``2·terrain_cells²`` triangles,
    instance 0), water plane at z = 0 (instance 1) and ``vessels`` hull instances around the origin.

    ``seed``: a whole number in ``0..2**64 - 1``; ``extent``: side of the square world centred on the origin,
    metres (>= 100); ``terrain_cells`` in ``1..MAX_DEMO_CELLS`` and ``vessels`` in ``0..MAX_DEMO_CELLS`` (whole
    numbers).
    Returns ``(scene, vessel_instance_ids)``. Deterministic from ``seed``.
    """
    seed = arguments.whole(seed, name="seed", lo=0, hi=2**64 - 1, error=InputError)
    extent = arguments.real(extent, name="extent", unit="metres", error=InputError)
    terrain_cells = arguments.whole(terrain_cells, name="terrain_cells", lo=1, hi=MAX_DEMO_CELLS, error=InputError)
    vessels = arguments.whole(vessels, name="vessels", lo=0, hi=MAX_DEMO_CELLS, error=InputError)
    native, ids = core.demo_scene(seed=seed, extent=extent, terrain_cells=terrain_cells, vessels=vessels)
    return Scene._from_native(native), [int(i) for i in ids]
