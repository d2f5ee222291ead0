"""User vessel meshes from files: OBJ, STL, PLY, GLB/glTF and the rest trimesh reads.

:func:`load_mesh_file` reads a file unprocessed, refuses non-finite vertex coordinates (trimesh's processing would
drop the faces touching them without a word), then processes each piece as ``trimesh.load(process=True)`` would;
glTF/GLB files bring their PBR materials (``baseColorFactor`` times the mean of the sRGB ``baseColorTexture`` in
linear RGB, ``roughnessFactor``, ``metallicFactor``, ``emissiveFactor`` scaled by :data:`GLTF_EMISSIVE_SCALE`),
registered in :mod:`mmusv.world.materials`, one id per face. :func:`mesh_asset` turns a file's mesh into the body
frame of a :class:`~mmusv.world.vessels.VesselAsset` (:mod:`mmusv.world.vessels` builds the asset around it).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from mmusv.errors import ConfigError
from mmusv.validation import join
from mmusv.world.asset_spec import AXES, AssetSpecError, MeshAssetSpec, dimension_problem
from mmusv.world.materials import NAV_LAMP_RADIANCE, Material, register_material
from mmusv.world.primitives import TriMesh

__all__ = ["GLTF_EMISSIVE_SCALE", "load_mesh_file", "mesh_asset"]


def _axis(name: str) -> np.ndarray:
    """The unit vector of a validated axis name (``x`` ... ``-z``)."""
    return (-1.0 if name.startswith("-") else 1.0) * np.array(AXES[name[-1]])


GLTF_EMISSIVE_SCALE = 0.05 * NAV_LAMP_RADIANCE
"""cd/m² of a glTF ``emissiveFactor`` of 1 (glTF's emission is relative; 1e3 cd/m² is a bright lit panel)."""


def _srgb_to_linear(c: np.ndarray) -> np.ndarray:
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _unit_factor(value: object, n: int, default: float) -> np.ndarray:
    """A trimesh colour/factor as floats in [0, 1] (trimesh keeps colour factors as uint8)."""
    if value is None:
        return np.full(n, default)
    a = np.asarray(value).reshape(-1)[:n]
    f = a.astype(np.float64) / 255.0 if a.dtype.kind in "ui" else a.astype(np.float64)
    return np.pad(f, (0, n - f.shape[0]), constant_values=default)


def _pbr_material(mat: object, name: str) -> Material:
    """A :class:`Material` from a trimesh material (glTF PBR; a plain material's diffuse colour otherwise).

    glTF's ``baseColorFactor`` is linear and multiplies the sRGB-encoded ``baseColorTexture``, whose mean is
    taken in linear RGB; roughness and metallic factors default to 1 as in glTF; ``emissiveFactor`` is scaled by
    :data:`GLTF_EMISSIVE_SCALE`.
    """
    base = np.ones(3)
    rough, metal, emis = 1.0, 1.0, np.zeros(3)
    factor = getattr(mat, "baseColorFactor", None)
    if factor is not None or hasattr(mat, "roughnessFactor"):
        base = _unit_factor(factor, 3, 1.0)
        tex = getattr(mat, "baseColorTexture", None)
        if tex is not None:
            pix = np.asarray(tex.convert("RGB"), dtype=np.float64).reshape(-1, 3) / 255.0
            base = base * _srgb_to_linear(pix).mean(axis=0)
        r = getattr(mat, "roughnessFactor", None)
        m = getattr(mat, "metallicFactor", None)
        rough = 1.0 if r is None else float(r)
        metal = 1.0 if m is None else float(m)
        e = getattr(mat, "emissiveFactor", None)
        emis = np.zeros(3) if e is None else _unit_factor(e, 3, 0.0) * GLTF_EMISSIVE_SCALE
    else:
        diffuse = getattr(mat, "diffuse", None)
        base = _srgb_to_linear(_unit_factor(diffuse, 3, 1.0)) if diffuse is not None else np.full(3, 0.5)
        rough, metal = 0.5, 0.0
    return Material(
        name=name,
        base_color=(float(base[0]), float(base[1]), float(base[2])),
        roughness=float(np.clip(rough, 0.02, 1.0)),
        metallic=float(np.clip(metal, 0.0, 1.0)),
        emissive=(float(emis[0]), float(emis[1]), float(emis[2])),
    )


def _material_ids(mat: object, stem: str, cache: dict[int, int]) -> int:
    """The registered id of a trimesh material (named ``<file stem>:<material name>``, suffixed if that name is
    taken by another material)."""
    key = id(mat)
    if key in cache:
        return cache[key]
    label = str(getattr(mat, "name", None) or "material")
    k = 1
    while True:
        name = f"{stem}:{label}" if k == 1 else f"{stem}:{label}#{k}"
        m = _pbr_material(mat, name)
        try:
            cache[key] = register_material(m)
            return cache[key]
        except ConfigError as exc:
            if "already registered" not in str(exc):
                raise
            k += 1


def load_mesh_file(path: Path, where: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices ``(V, 3)``, faces ``(F, 3)`` and material ids ``(F,)`` of a mesh file (glTF/GLB: its PBR
    materials, registered; other formats: material 0)."""
    if not path.is_file():
        what = "is a folder, not a mesh file" if path.is_dir() else "does not exist"
        raise AssetSpecError(where, f"mesh file {str(path)!r} {what}")
    try:
        import trimesh
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise AssetSpecError(where, "loading mesh files needs the 'trimesh' package (pip install trimesh)") from exc
    gltf = path.suffix.lower() in (".glb", ".gltf")
    try:
        # Read unprocessed: trimesh's processing silently drops every face touching a NaN/inf vertex, so the raw
        # arrays are checked first; each piece is then processed exactly as ``trimesh.load(process=True)`` would.
        scene = trimesh.load(str(path), force="scene", process=False)
    except Exception as exc:  # trimesh raises many types for unreadable files
        raise AssetSpecError(where, f"cannot read {str(path)!r}: {exc}") from exc
    if not isinstance(scene, trimesh.Scene):
        raise AssetSpecError(where, f"{str(path)!r} does not hold a triangle mesh")
    geoms = [g for g in scene.geometry.values() if isinstance(g, trimesh.Trimesh)]
    for g in geoms:
        bad = ~np.isfinite(np.asarray(g.vertices, dtype=np.float64))
        if bad.any():
            raise AssetSpecError(
                where,
                f"{str(path)!r} has non-finite (NaN/inf) coordinates at {int(bad.any(axis=-1).sum())} of its "
                f"{len(g.vertices)} vertices; every vertex coordinate must be a finite number",
            )
    try:
        for g in geoms:
            g.process()
        loaded = scene if gltf else scene.to_mesh()
    except Exception as exc:  # trimesh raises many types for unreadable files
        raise AssetSpecError(where, f"cannot read {str(path)!r}: {exc}") from exc
    if gltf and isinstance(loaded, trimesh.Scene):
        pieces = [g for g in loaded.dump() if isinstance(g, trimesh.Trimesh)]
        cache: dict[int, int] = {}
        mats = [
            np.full(
                len(g.faces),
                _material_ids(getattr(g.visual, "material", None), path.stem, cache)
                if hasattr(g.visual, "material")
                else 0,
                dtype=np.uint16,
            )
            for g in pieces
        ]
        if not pieces:
            raise AssetSpecError(where, f"{str(path)!r} holds no triangles")
        offsets = np.cumsum([0] + [len(g.vertices) for g in pieces[:-1]])
        v = np.concatenate([np.asarray(g.vertices, dtype=np.float64) for g in pieces])
        fc = np.concatenate([np.asarray(g.faces, dtype=np.int64) + o for g, o in zip(pieces, offsets, strict=True)])
        fm = np.concatenate(mats)
    elif isinstance(loaded, trimesh.Trimesh):
        v = np.asarray(loaded.vertices, dtype=np.float64).reshape(-1, 3)
        fc = np.asarray(loaded.faces, dtype=np.int64).reshape(-1, 3)
        fm = np.zeros(fc.shape[0], dtype=np.uint16)
    else:
        raise AssetSpecError(where, f"{str(path)!r} does not hold a triangle mesh")
    v = v.reshape(-1, 3)
    fc = fc.reshape(-1, 3)
    if fc.shape[0] == 0:
        raise AssetSpecError(where, f"{str(path)!r} holds no triangles")
    used, inverse = np.unique(fc.reshape(-1), return_inverse=True)
    v, fc = v[used], inverse.reshape(-1, 3).astype(np.int64)
    if not np.all(np.isfinite(v)):
        raise AssetSpecError(where, f"{str(path)!r} has non-finite vertices")
    return v, fc, fm


def mesh_asset(spec: MeshAssetSpec, *, path: str, base_dir: Path | None, cls: int) -> TriMesh:
    """The body-frame mesh of a mesh entry ``spec`` (``path`` its field path in errors; a relative ``spec.mesh`` is
    taken from ``base_dir``, else the current folder): the file read (:func:`load_mesh_file`), turned to the body
    frame by its up and forward axes, scaled to metres, its waterline moved to z = 0, every face of class ``cls``.
    Raises :class:`~mmusv.world.asset_spec.AssetSpecError` naming the field at fault."""
    mesh_path = Path(os.fspath(spec.mesh)).expanduser()
    if not mesh_path.is_absolute():
        mesh_path = (base_dir or Path.cwd()) / mesh_path
    up, fwd = _axis(spec.up_axis), _axis(spec.forward_axis)
    v, fc, fm = load_mesh_file(mesh_path, join(path, "mesh"))
    rot = np.stack([fwd, np.cross(up, fwd), up])  # rows: body x, y, z in file coordinates
    body = v @ rot.T  # a signed axis permutation: exact, no overflow
    # Python floats: an overflowing product is inf (no numpy warning), which the range check then refuses.
    lo3, hi3 = body.min(axis=0), body.max(axis=0)
    ext = [float(hi) * spec.scale - float(lo) * spec.scale for lo, hi in zip(lo3, hi3, strict=True)]
    problem = dimension_problem(*ext)
    if problem is not None:
        raise AssetSpecError(
            join(path, "scale"),
            f"{spec.scale:g} (file units -> metres) applied to {str(mesh_path)!r} {problem}; "
            "check the mesh's units and scale",
        )
    body = body * spec.scale
    zmin, zmax = float(body[:, 2].min()), float(body[:, 2].max())
    if spec.draft is not None:
        if spec.draft >= zmax - zmin:
            raise AssetSpecError(
                join(path, "draft"), f"{spec.draft:g} m is not less than the mesh height {zmax - zmin:g} m"
            )
        body[:, 2] -= zmin + spec.draft
    else:
        wl = (spec.waterline_z or 0.0) * spec.scale
        if not zmin < wl < zmax:
            raise AssetSpecError(
                join(path, "waterline_z"),
                f"waterline {wl:g} m must lie inside the mesh's vertical extent [{zmin:g}, {zmax:g}] m "
                "(after scaling; check up_axis and scale)",
            )
        body[:, 2] -= wl
    return TriMesh(body, fc, np.array([cls]), fm)
