"""User vessel meshes from files: OBJ, STL, PLY, OFF, GLB/glTF and the rest trimesh reads.

:func:`load_mesh_file` first checks what trimesh would report obscurely or not at all (an empty file, an extension
trimesh cannot read, a GLB shorter than its header says, a glTF buffer or image file that is missing, a ``COLOR_0``
that does not fit its primitive, a glTF that requires an extension it does not read or a ``POSITION`` it would
misread: a glTF's are :mod:`mmusv.world.gltf_checks`'s; Draco-compressed glTF geometry is decoded with DracoPy),
reads the file unprocessed, refuses non-finite vertex coordinates (trimesh's processing would drop the faces
touching them without a word), takes each face's colours (merging vertices would keep one colour per place), then
processes each piece as ``trimesh.load(process=True)`` would. Each face gets a registered material
(:mod:`mmusv.world.mesh_materials`, which says how each is converted): a glTF/GLB file's PBR materials (times its
primitives' ``COLOR_0`` vertex colours, read here from the loader's raw arrays), an OBJ's MTL materials by
``usemtl`` (a missing ``.mtl`` or texture is an error, an OBJ without ``mtllib`` the class's default look), vertex
or face colours (PLY, OBJ) quantised to at most :data:`~mmusv.world.mesh_materials.MAX_COLOUR_MATERIALS` materials a
file; other faces get material 0, the class's default look. :func:`mesh_asset` turns a file's mesh into the body
frame of a :class:`~mmusv.world.vessels.VesselAsset` (:mod:`mmusv.world.vessels` builds the asset around it), by the
entry's ``up_axis``/``forward_axis`` or, when it gives neither, the file format's convention
(:data:`~mmusv.world.asset_spec.FORMAT_AXES`: glTF is +Y up, front +Z).
"""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import unquote

import numpy as np

from mmusv.errors import ConfigError
from mmusv.validation import join
from mmusv.world.asset_spec import AXES, FORMAT_AXES, AssetSpecError, MeshAssetSpec, dimension_problem
from mmusv.world.gltf_checks import PrimitiveMaterial, check_gltf
from mmusv.world.gltf_graph import TEXTURE_SLOTS
from mmusv.world.mesh_materials import (
    GLTF_EMISSIVE_SCALE,
    EmissiveKey,
    ObjMaterials,
    colour_material_ids,
    face_colours,
    gltf_material_id,
    obj_materials,
    one_line,
)
from mmusv.world.primitives import TriMesh

if TYPE_CHECKING:
    from trimesh.resolvers import FilePathResolver

__all__ = ["GLTF_EMISSIVE_SCALE", "MAX_COORDINATE", "load_mesh_file", "mesh_asset"]


MAX_COORDINATE = 9.0e10
"""The largest vertex coordinate (file units) a mesh file may hold: trimesh merges vertices by their coordinates
rounded to 1e-8 as 64-bit integers, which overflow past about 9.2e10, so distinct vertices there became one point
(the mesh was then refused as holding "no triangle of any area", or lost faces)."""


def _axis(name: str) -> np.ndarray:
    """The unit vector of a validated axis name (``x`` ... ``-z``)."""
    return (-1.0 if name.startswith("-") else 1.0) * np.array(AXES[name[-1]])


_MESH_FORMATS = frozenset({"3mf", "dae", "glb", "gltf", "obj", "off", "ply", "stl"})
"""The triangle-mesh formats named in the error for a file trimesh cannot read (those of them it can read in this
install; it also reads archives of them and formats of other kinds)."""


def _color_0_linear(raw: object, at: str, where: str) -> np.ndarray:
    """A primitive's raw ``COLOR_0`` (trimesh's copy of the accessor) as ``(V, 3)`` linear RGB in [0, 1] (glTF
    stores it linear; normalized integers divided by their maximum; alpha dropped); non-finite values or values
    outside [0, 1] are refused."""
    a = np.asarray(raw)
    top = {"u1": 255.0, "u2": 65535.0}.get(f"{a.dtype.kind}{a.dtype.itemsize}")
    if a.ndim != 2 or a.shape[1] not in (3, 4) or (top is None and a.dtype.kind != "f"):
        raise AssetSpecError(where, f"{at} is not RGB or RGBA colours (read as {a.dtype} {list(a.shape)})")
    rgb = a[:, :3].astype(np.float64) / (top or 1.0)
    bad = ~np.isfinite(rgb)
    if bad.any():
        raise AssetSpecError(
            where,
            f"{at} has non-finite (NaN/inf) values at {int(bad.any(axis=1).sum())} of its {len(rgb)} vertices; "
            "every vertex colour must be finite",
        )
    out = (rgb < 0.0) | (rgb > 1.0)
    if out.any():
        raise AssetSpecError(
            where,
            f"{at} has values outside [0, 1] at {int(out.any(axis=1).sum())} of its {len(rgb)} vertices (e.g. "
            f"{rgb[out.any(axis=1)][0].tolist()}); a vertex colour is a linear multiplier in [0, 1]",
        )
    return rgb


_COLOR_0 = "mmusv_color_0"
"""The metadata key of a glTF piece's ``COLOR_0`` as linear RGB per vertex, before processing."""


def _load_gltf(trimesh: object, path: Path, where: str, names: list[str], materials: list[PrimitiveMaterial]) -> object:
    """The glTF ``path`` as an unprocessed trimesh scene whose pieces keep their ``COLOR_0`` exactly
    (metadata :data:`_COLOR_0`): trimesh's loader is called for its keyword arguments, and the raw colours it passes
    on are taken out before trimesh turns them into 8-bit visual colours (a float colour of 0.002 would become
    1/255) or into an unread vertex attribute. ``names`` and ``materials``: :func:`~mmusv.world.gltf_checks.
    check_gltf`'s, for the errors and for each piece's material as the file writes it (:func:`_file_material`)."""
    from trimesh.exchange.gltf import load_glb, load_gltf

    loader = load_glb if path.suffix.lower() == ".glb" else load_gltf
    with path.open("rb") as f:
        kwargs = loader(file_obj=f, resolver=_resolver(path))
    geometry = kwargs.get("geometry", {}) if isinstance(kwargs, dict) else {}
    aligned = len(names) == len(geometry) == len(materials)
    labels = names if aligned else [f"mesh {k!r}" for k in geometry]
    for n, (label, (key, g)) in enumerate(zip(labels, geometry.items(), strict=True)):
        if not isinstance(g, dict):
            continue
        if aligned:
            _file_material(g, materials[n], path, where)
        raw = g.pop("vertex_colors", None)
        attrs = getattr(g.get("visual"), "vertex_attributes", None)
        if attrs is not None and "color" in attrs:
            raw = attrs.pop("color")
        if raw is not None:
            at = f"{str(path)!r}: {label}.attributes.COLOR_0 (geometry {key!r})"
            g.setdefault("metadata", {})[_COLOR_0] = _color_0_linear(raw, at, where)
    return trimesh.load(kwargs, force="scene", process=False)  # type: ignore[attr-defined]


_BASE_COLOR = "mmusv_base_color_factor"
"""The metadata key of a glTF piece's ``baseColorFactor`` RGB as the file writes it (trimesh keeps it as bytes)."""


def _file_material(g: dict[str, object], material: PrimitiveMaterial, path: Path, where: str) -> None:
    """Checks a piece's material against the file's JSON ``material`` and keeps its exact ``baseColorFactor``
    (metadata :data:`_BASE_COLOR`; trimesh rounds it to 1/255, so a dark linear 0.018 became 0.0196 and 0.001
    black). A texture slot mmusv reads (:data:`~mmusv.world.gltf_graph.TEXTURE_SLOTS`) that the file gives but
    trimesh left out (an image Pillow cannot decode, ``image/ktx2``, a texture without ``source``: trimesh logs
    them at debug level) is an error: the hull came out in the factor's colour, white by default."""
    if material is None:
        return
    k, m = material
    pbr = m.get("pbrMetallicRoughness")
    factor = pbr.get("baseColorFactor") if isinstance(pbr, dict) else None
    if isinstance(factor, list) and len(factor) == 4:
        meta = g.setdefault("metadata", {})
        if isinstance(meta, dict):
            meta[_BASE_COLOR] = tuple(float(c) for c in factor[:3])
    read = getattr(g.get("visual"), "material", None)
    if read is None:
        return
    for holder, name in TEXTURE_SLOTS:
        obj = m.get(holder) if holder else m
        info = obj.get(name) if isinstance(obj, dict) else None
        if not isinstance(info, dict) or getattr(read, name, None) is not None:
            continue
        if name == "metallicRoughnessTexture" and getattr(read, "roughnessFactor", None) is None:
            continue  # a specular-glossiness material trimesh converted: its textures are its own
        at = f"materials[{k}].{holder + '.' if holder else ''}{name}"
        tex_index = info.get("index")
        textures = _json_list(path, "textures")
        tex = textures[tex_index] if isinstance(tex_index, int) and 0 <= tex_index < len(textures) else None
        source = tex.get("source") if isinstance(tex, dict) else None
        why = (
            f"textures[{tex_index}] names no image (no source)"
            if source is None
            else f"its image images[{source}] could not be read (not an image Pillow decodes, or image/ktx2)"
        )
        raise AssetSpecError(
            where,
            f"{str(path)!r}: {at} (textures[{tex_index}]): {why}; trimesh's reader would leave the texture out "
            "without a word",
        )


def _json_list(path: Path, key: str) -> list[object]:
    """The list ``key`` of the glTF ``path``'s JSON (read again: only for an error's message)."""
    from mmusv.world.gltf_checks import gltf_json

    value = gltf_json(path, "").get(key)
    return value if isinstance(value, list) else []


def _resolver(path: Path) -> FilePathResolver:
    """A trimesh file resolver for the glTF ``path`` that reads its buffers and images as glTF means their URIs:
    percent-decoded (``hull%20paint.png`` is the file ``hull paint.png``; trimesh would look for the literal name and
    leave such a texture out without a word) and relative to the file, ``../textures/`` included (trimesh 5 reads
    only below the file's folder by default, and would leave a texture there out as silently)."""
    from trimesh.resolvers import FilePathResolver

    class GltfResolver(FilePathResolver):  # type: ignore[misc,unused-ignore]
        def get(self, name: str) -> bytes:
            decoded = unquote(name)
            if decoded != name:
                try:
                    return super().get(decoded)  # type: ignore[no-any-return,unused-ignore]
                except (OSError, ValueError):
                    pass
            return super().get(name)  # type: ignore[no-any-return,unused-ignore]

    try:
        return GltfResolver(str(path), allow_anywhere=True)
    except TypeError:  # trimesh 4: no such argument, and it reads anywhere already
        return GltfResolver(str(path))


def _check_file(
    path: Path, where: str, formats: list[str]
) -> tuple[dict[EmissiveKey, float], list[str], list[PrimitiveMaterial]]:
    """Refuses what trimesh would read obscurely or not at all (module docstring); returns a glTF's emissive
    strengths by material name and factor, the names of its primitives and their materials
    (:func:`~mmusv.world.gltf_checks.check_gltf`), all empty for other formats."""
    shown = repr(str(path))
    name = path.name.lower()
    if not any(name.endswith("." + f) for f in formats):
        ext = f"a {path.suffix!r} file" if path.suffix else "a file without an extension"
        known = ", ".join("." + f for f in sorted(_MESH_FORMATS.intersection(formats)))
        raise AssetSpecError(where, f"{shown} is {ext}; mesh files are read by their extension: {known}")
    if path.stat().st_size == 0:
        raise AssetSpecError(where, f"{shown} is empty (0 bytes): it holds no triangles")
    if path.suffix.lower() not in FORMAT_AXES:
        return {}, [], []
    return check_gltf(path, where)


_FACE_COLOURS = "mmusv_face_colours"
"""The metadata key of a piece's face colours, taken before trimesh's processing merges vertices."""


def _mtl_resolver(path: Path, mtl: ObjMaterials) -> FilePathResolver:
    """A trimesh file resolver for the OBJ ``path`` that answers its ``mtllib`` with every material's name and index
    (:meth:`ObjMaterials.resolver_text`): trimesh then groups the faces by ``usemtl`` and names the material of each
    piece, and reads no file itself (it would leave a missing one out without a word)."""
    from trimesh.resolvers import FilePathResolver

    class MtlResolver(FilePathResolver):  # type: ignore[misc,unused-ignore]
        def get(self, name: str) -> bytes:
            return mtl.resolver_text()

    return MtlResolver(str(path))


def _face_materials(
    pieces: Sequence[object],
    path: Path,
    where: str,
    strengths: dict[EmissiveKey, float] | None,
    mtl: ObjMaterials | None,
) -> np.ndarray:
    """The material id of every face of the file's ``pieces`` (trimesh meshes), in order: a glTF's PBR materials
    (``strengths`` given), times its ``COLOR_0`` where a primitive has one (a ``COLOR_0`` without a material: vertex
    colour materials), an OBJ's MTL materials, else its vertex/face colours, else 0, the class default."""
    out: list[np.ndarray] = []
    colour_at: list[tuple[int, np.ndarray, int]] = []
    cache: dict[tuple[int, tuple[float, ...] | None], int] = {}
    for g in pieces:
        n = len(g.faces)  # type: ignore[attr-defined]
        visual = getattr(g, "visual", None)
        mat = getattr(visual, "material", None)
        colours = getattr(g, "metadata", {}).get(_FACE_COLOURS)
        if strengths is not None:
            has = hasattr(visual, "material")
            try:
                exact = getattr(g, "metadata", {}).get(_BASE_COLOR)
                mid = gltf_material_id(mat, path.stem, cache, strengths, exact) if has else 0
            except ConfigError as exc:
                raise AssetSpecError(where, f"{str(path)!r}: {one_line(exc)}") from None
            if colours is not None:
                colour_at.append((len(out), colours, mid if has else -1))
            out.append(np.full(n, mid, dtype=np.uint16))
            continue
        index = getattr(mat, "kwargs", {}).get("mmusv_index") if mtl is not None else None
        if index is not None:
            out.append(np.full(n, mtl.material_id(int(index[0])), dtype=np.uint16))  # type: ignore[union-attr]
            continue
        if colours is not None:
            colour_at.append((len(out), colours, -1))
        out.append(np.zeros(n, dtype=np.uint16))
    if colour_at:
        tints = np.concatenate([np.full(len(c), t, dtype=np.int64) for _, c, t in colour_at])
        ids = colour_material_ids(np.concatenate([c for _, c, _ in colour_at]), path, where, tints)
        start = 0
        for k, c, _ in colour_at:
            out[k] = ids[start : start + len(c)]
            start += len(c)
    return np.concatenate(out)


def load_mesh_file(path: Path, where: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices ``(V, 3)`` float64 (the file's own units and axes, unused vertices dropped), faces ``(F, 3)``
    int64 and material ids ``(F,)`` uint16 of a mesh file (its glTF PBR or OBJ MTL
    materials, or its vertex/face colours, registered; else material 0). Every problem is one
    :class:`AssetSpecError` at ``where`` naming the file and what is wrong with it."""
    if not path.is_file():
        what = "is a folder, not a mesh file" if path.is_dir() else "does not exist"
        raise AssetSpecError(where, f"mesh file {str(path)!r} {what}")
    try:
        import trimesh
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise AssetSpecError(where, "loading mesh files needs the 'trimesh' package (pip install trimesh)") from exc
    strengths, names, materials = _check_file(path, where, list(trimesh.available_formats()))
    gltf = path.suffix.lower() in FORMAT_AXES
    mtl = obj_materials(path, where) if path.suffix.lower() == ".obj" else None
    if path.suffix.lower() == ".obj":
        _check_obj_indices(path, where)
    try:
        # Read unprocessed: trimesh's processing silently drops every face touching a NaN/inf vertex, so the raw
        # arrays are checked first; each piece is then processed exactly as ``trimesh.load(process=True)`` would.
        if gltf:
            scene = _load_gltf(trimesh, path, where, names, materials)
        else:
            resolver = _mtl_resolver(path, mtl) if mtl is not None else None
            scene = trimesh.load(str(path), force="scene", process=False, resolver=resolver)
    except AssetSpecError:
        raise
    except Exception as exc:  # trimesh raises many types for unreadable files
        hint = (
            " (trimesh's glTF reader failed inside: a buffer's length or base64 data, an accessor or the index data "
            "does not fit the file; the Khronos glTF Validator names the entry)"
            if gltf and isinstance(exc, (AssertionError, LookupError, ValueError, TypeError))
            else ""
        )
        raise AssetSpecError(where, f"cannot read {str(path)!r}: {one_line(exc)}{hint}") from exc
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
        far = float(np.abs(np.asarray(g.vertices, dtype=np.float64)).max(initial=0.0))
        if far > MAX_COORDINATE:
            raise AssetSpecError(
                where,
                f"{str(path)!r} has a vertex coordinate of {far:.3g} file units; a mesh is read with coordinates "
                f"within ±{MAX_COORDINATE:.2g} (past that, trimesh merges distinct vertices into one point): write it "
                "in larger units and set scale, or move it nearer its origin",
            )
        faces = np.asarray(g.faces)
        outside = (faces < 0) | (faces >= len(g.vertices))
        if outside.any():
            raise AssetSpecError(
                where,
                f"{str(path)!r}: {int(outside.any(axis=-1).sum())} of its {len(faces)} faces name a vertex it does "
                f"not hold (index {int(faces[outside][0])}; its {len(g.vertices)} vertices are numbered 0.."
                f"{len(g.vertices) - 1}): the file is damaged",
            )
    try:
        for g in geoms:  # face colours before processing: it merges vertices at one place whatever their colours
            if gltf:
                lin = g.metadata.pop(_COLOR_0, None)
                g.metadata[_FACE_COLOURS] = None if lin is None else lin[np.asarray(g.faces)].mean(axis=1)
            else:
                g.metadata[_FACE_COLOURS] = face_colours(g)
            g.process()
        pieces = [g for g in scene.dump() if isinstance(g, trimesh.Trimesh)]
    except Exception as exc:  # trimesh raises many types for unreadable files
        raise AssetSpecError(where, f"cannot read {str(path)!r}: {one_line(exc)}") from exc
    if not pieces:
        raise AssetSpecError(where, f"{str(path)!r} holds no triangles")
    fm = _face_materials(pieces, path, where, strengths if gltf else None, mtl)
    offsets = np.cumsum([0] + [len(g.vertices) for g in pieces[:-1]])
    v = np.concatenate([np.asarray(g.vertices, dtype=np.float64).reshape(-1, 3) for g in pieces])
    fc = np.concatenate(
        [np.asarray(g.faces, dtype=np.int64).reshape(-1, 3) + o for g, o in zip(pieces, offsets, strict=True)]
    )
    v = v.reshape(-1, 3)
    fc = fc.reshape(-1, 3)
    if fc.shape[0] == 0:
        raise AssetSpecError(where, f"{str(path)!r} holds no triangles")
    used, inverse = np.unique(fc.reshape(-1), return_inverse=True)
    v, fc = v[used], inverse.reshape(-1, 3).astype(np.int64)
    if not np.all(np.isfinite(v)):
        raise AssetSpecError(where, f"{str(path)!r} has non-finite vertices")
    if not _any_area(v, fc):
        raise AssetSpecError(
            where,
            f"{str(path)!r} holds no triangle of any area: each of its {len(fc)} faces has its corners at one point "
            "or on one line (no sensor would see the vessel, yet it would be labelled in every frame)",
        )
    return v, fc, fm


def _any_area(v: np.ndarray, fc: np.ndarray) -> bool:
    """Whether a face of the mesh ``v``, ``fc`` encloses an area: twice its area past 1e-12 of the square of the
    mesh's largest extent (rounding leaves a face of three points on one line an area of about 1e-16 of it), measured
    in units of that extent (a mesh of 1e-300 units is not taken for a point)."""
    with np.errstate(over="ignore", invalid="ignore"):  # huge coordinates: inf areas, refused by their size later
        extent = float(np.max(np.ptp(v, axis=0)))
        if not extent > 0.0:
            return False
        corners = (v[fc] - v.min(axis=0)) / extent
        doubled = np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
        return bool(np.any(~(doubled <= 1e-12)))


_SEPARATOR = np.zeros(256, dtype=bool)
_SEPARATOR[list(b" \t/+-")] = True
_AFTER = np.zeros(256, dtype=bool)
_AFTER[list(b" \t/#\r\n0")] = True
_ZERO_INDEX = re.compile(r"[+-]?0+")


def _check_obj_indices(path: Path, where: str) -> None:
    """Refuses an OBJ face naming index 0 (``f 0 1 2``, ``f 1/0 2/0 3/0``): OBJ numbers vertices, texture
    coordinates and normals from 1 (negative numbers count back from the last), so 0 names nothing, and trimesh read
    it as -1, the last one, without a word (a file written counting from 0, or damaged). The bytes are searched with
    numpy for a ``0`` standing alone on a line starting ``f`` (a regular expression took a second for 1 million
    faces); the few lines found are then read as text."""
    raw = np.frombuffer(path.read_bytes() + b"\n", dtype=np.uint8)
    zeros = np.flatnonzero(raw == ord("0"))
    zeros = zeros[zeros > 0]
    zeros = zeros[_SEPARATOR[raw[zeros - 1]] & _AFTER[raw[zeros + 1]]]
    if len(zeros) == 0:
        return
    breaks = np.flatnonzero(raw == ord("\n"))
    starts = np.concatenate(([0], breaks + 1))  # line k runs from starts[k] to breaks[k]
    lines = np.unique(np.searchsorted(breaks, zeros))
    lines = lines[raw[starts[lines]] == ord("f")]
    for k in lines:
        line = raw[starts[k] : breaks[k]].tobytes().decode("utf-8", errors="replace").split("#", 1)[0]
        tokens = line.split()
        if tokens[:1] == ["f"] and any(_ZERO_INDEX.fullmatch(part) for t in tokens[1:] for part in t.split("/")):
            raise AssetSpecError(
                where,
                f"{str(path)!r}: the face on line {int(k) + 1} names index 0 ({line.strip()!r}); OBJ numbers "
                "vertices, texture coordinates and normals from 1 (negative numbers count back from the last), so 0 "
                "names none: the file is damaged or was written counting from 0",
            )


def mesh_asset(spec: MeshAssetSpec, *, path: str, base_dir: Path | None, cls: int) -> TriMesh:
    """The body-frame mesh of a mesh entry ``spec`` (``path`` its field path in errors; a relative ``spec.mesh`` is
    taken from ``base_dir``, else the current folder): the file read (:func:`load_mesh_file`), turned to the body
    frame by its up and forward axes, scaled to metres, its waterline moved to z = 0, every face of class ``cls``.
    Raises :class:`~mmusv.world.asset_spec.AssetSpecError` naming the field at fault."""
    mesh_path = Path(os.fspath(spec.mesh)).expanduser()
    if not mesh_path.is_absolute():
        mesh_path = (base_dir or Path.cwd()) / mesh_path
    up_name, fwd_name = spec.axes(str(mesh_path))
    up, fwd = _axis(up_name), _axis(fwd_name)
    v, fc, fm = load_mesh_file(mesh_path, join(path, "mesh"))
    rot = np.stack([fwd, np.cross(up, fwd), up])  # rows: body x, y, z in file coordinates
    body = v @ rot.T  # a signed axis permutation: exact, no overflow
    # Python floats: an overflowing product is inf (no numpy warning), which the range check then refuses.
    lo3, hi3 = body.min(axis=0), body.max(axis=0)
    ext = [float(hi) * spec.scale - float(lo) * spec.scale for lo, hi in zip(lo3, hi3, strict=True)]
    problem = dimension_problem(length=ext[0], beam=ext[1], height=ext[2])
    if problem is not None:
        raise AssetSpecError(
            join(path, "scale"),
            f"{spec.scale:g} (file units -> metres) applied to {str(mesh_path)!r} {problem}; "
            "check the mesh's units and scale",
        )
    if (spec.up_axis is None or spec.forward_axis is None) and max(ext[1], ext[2]) > ext[0]:
        _warn_sideways(spec, mesh_path, path, (up_name, fwd_name), ext)
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
                f"(after scaling, up_axis {up_name}{_defaulted(spec, mesh_path)}; check up_axis and scale)",
            )
        body[:, 2] -= wl
    return TriMesh(body, fc, np.array([cls]), fm)


def _defaulted(spec: MeshAssetSpec, mesh_path: Path) -> str:
    """Where the axes came from when the entry gave neither (glTF's convention or the default), else ``""``."""
    if spec.up_axis is not None or spec.forward_axis is not None:
        return ""
    suffix = mesh_path.suffix.lower()
    return f", glTF's convention for a {suffix} file" if suffix in FORMAT_AXES else ", the default"


def _warn_sideways(spec: MeshAssetSpec, mesh_path: Path, path: str, axes: tuple[str, str], ext: list[float]) -> None:
    """Warns (:class:`~mmusv.scenario_checks.MmusvWarning`) that a mesh read with a defaulted axis came out wider
    or taller than long: its bow probably does not point along the forward axis assumed (or the file is z-up glTF,
    or y-up OBJ/PLY as Blender exports them by default, which stands the hull on end). A dinghy whose mast is taller
    than its hull is long warns too: giving both axes silences it."""
    from mmusv.scenario_checks import MmusvWarning  # here: scenario_checks imports the config, which imports us

    given = (
        "neither up_axis nor forward_axis"
        if spec.up_axis is None and spec.forward_axis is None
        else ("no forward_axis" if spec.forward_axis is None else "no up_axis")
    )
    gltf = mesh_path.suffix.lower() in FORMAT_AXES
    hint = (
        " glTF files are read +Y up and bow +Z when the entry gives neither axis (glTF 2.0's convention; before, every "
        "file was read z up, x forward): a glTF/GLB written z-up needs up_axis: z, forward_axis: x."
        if gltf and given.startswith("neither")
        else ""
    )
    tall = ext[2] > ext[1]
    if tall and not hint:
        hint = (
            " A y-up file (Blender's OBJ and PLY export default) is read standing on end: give up_axis: y and "
            "forward_axis the bow's direction in the file."
        )
    size = f"{ext[2]:.4g} m tall" if tall else f"{ext[1]:.4g} m wide"
    warnings.warn(
        f"{join(path, 'mesh')}: {str(mesh_path)!r}, read with {given} given (up {axes[0]}, forward {axes[1]}), is "
        f"{size} but {ext[0]:.4g} m long: if its bow does not point along "
        f"{axes[1]}, set forward_axis and up_axis in the entry (giving both also silences this warning).{hint}",
        MmusvWarning,
        stacklevel=5,
    )
