"""User vessel meshes from files: OBJ, STL, PLY, OFF, GLB/glTF and the rest trimesh reads.

:func:`load_mesh_file` first checks what trimesh would report obscurely or not at all (an empty file, an extension
trimesh cannot read, a GLB shorter than its header says, a glTF buffer or image file that is missing), reads the file
unprocessed, refuses non-finite vertex coordinates (trimesh's processing would drop the faces touching them without
a word), then processes each piece as ``trimesh.load(process=True)`` would. glTF/GLB files bring their PBR materials
as glTF 2.0 defines them, each texture by its mean over its texels: base colour = ``baseColorFactor`` times the
``baseColorTexture`` (sRGB-encoded, averaged in linear RGB); roughness and metallic = ``roughnessFactor`` and
``metallicFactor`` (default 1) times the mean of the ``metallicRoughnessTexture``'s green and blue channels (linear);
emission = ``emissiveFactor`` (default 0) times the ``emissiveTexture`` (sRGB, averaged in linear RGB) times
``KHR_materials_emissive_strength`` (default 1), scaled by :data:`GLTF_EMISSIVE_SCALE`. They are registered in
:mod:`mmusv.world.materials`, one id per face; other formats (and glTF primitives without a material) get material
0, the class's default look. :func:`mesh_asset` turns a file's mesh into the body frame of a
:class:`~mmusv.world.vessels.VesselAsset` (:mod:`mmusv.world.vessels` builds the asset around it), by the entry's
``up_axis``/``forward_axis`` or, when it gives neither, the file format's convention
(:data:`~mmusv.world.asset_spec.FORMAT_AXES`: glTF is +Y up, front +Z).
"""

from __future__ import annotations

import json
import math
import os
import struct
import warnings
from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import unquote

import numpy as np

from mmusv.errors import ConfigError
from mmusv.validation import join
from mmusv.world.asset_spec import AXES, FORMAT_AXES, AssetSpecError, MeshAssetSpec, dimension_problem
from mmusv.world.materials import NAV_LAMP_RADIANCE, Material, register_material
from mmusv.world.primitives import TriMesh

if TYPE_CHECKING:
    from trimesh.resolvers import FilePathResolver

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


def _texture_mean(tex: object, *, srgb: bool) -> np.ndarray:
    """The mean RGB of a texture image over its texels, in [0, 1]: decoded from sRGB to linear first when ``srgb``
    (colour textures), as stored otherwise (data textures: metallic-roughness)."""
    pix = np.asarray(tex.convert("RGB"), dtype=np.float64).reshape(-1, 3) / 255.0  # type: ignore[attr-defined]
    return np.asarray((_srgb_to_linear(pix) if srgb else pix).mean(axis=0), dtype=np.float64)


def _pbr_material(mat: object, name: str, emissive_strength: float = 1.0) -> Material:
    """A :class:`Material` from a trimesh material (glTF PBR; a plain material's diffuse colour otherwise).

    As glTF 2.0 defines it (module docstring), each texture by its mean: ``baseColorFactor`` (linear) times the
    sRGB ``baseColorTexture``; ``roughnessFactor`` / ``metallicFactor`` (default 1) times the green / blue channel
    of the linear ``metallicRoughnessTexture``; ``emissiveFactor`` (default 0) times the sRGB ``emissiveTexture``
    times ``emissive_strength`` (``KHR_materials_emissive_strength``), scaled by :data:`GLTF_EMISSIVE_SCALE`.
    """
    base = np.ones(3)
    rough, metal, emis = 1.0, 1.0, np.zeros(3)
    factor = getattr(mat, "baseColorFactor", None)
    if factor is not None or hasattr(mat, "roughnessFactor"):
        base = _unit_factor(factor, 3, 1.0)
        tex = getattr(mat, "baseColorTexture", None)
        if tex is not None:
            base = base * _texture_mean(tex, srgb=True)
        r = getattr(mat, "roughnessFactor", None)
        m = getattr(mat, "metallicFactor", None)
        rough = 1.0 if r is None else float(r)
        metal = 1.0 if m is None else float(m)
        mr = getattr(mat, "metallicRoughnessTexture", None)
        if mr is not None:
            mr_mean = _texture_mean(mr, srgb=False)
            rough, metal = rough * float(mr_mean[1]), metal * float(mr_mean[2])
        e = getattr(mat, "emissiveFactor", None)
        if e is not None:
            emis = _unit_factor(e, 3, 0.0) * emissive_strength * GLTF_EMISSIVE_SCALE
            etex = getattr(mat, "emissiveTexture", None)
            if etex is not None:
                emis = emis * _texture_mean(etex, srgb=True)
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


def _material_ids(mat: object, stem: str, cache: dict[int, int], strengths: dict[str | None, float]) -> int:
    """The registered id of a trimesh material (named ``<file stem>:<material name>``, suffixed if that name is
    taken by another material); ``strengths``: the file's ``KHR_materials_emissive_strength`` by material name."""
    key = id(mat)
    if key in cache:
        return cache[key]
    raw = getattr(mat, "name", None)
    label = str(raw or "material")
    strength = strengths.get(raw if isinstance(raw, str) else None, 1.0)
    k = 1
    while True:
        name = f"{stem}:{label}" if k == 1 else f"{stem}:{label}#{k}"
        m = _pbr_material(mat, name, strength)
        try:
            cache[key] = register_material(m)
            return cache[key]
        except ConfigError as exc:
            if "already registered" not in str(exc):
                raise
            k += 1


def _one_line(exc: BaseException) -> str:
    """An exception as one line of text (its type too where its message alone says little, a ``KeyError``'s)."""
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if isinstance(exc, LookupError) or not text else text


_MESH_FORMATS = frozenset({"3mf", "dae", "glb", "gltf", "obj", "off", "ply", "stl"})
"""The triangle-mesh formats named in the error for a file trimesh cannot read (those of them it can read in this
install; it also reads archives of them and formats of other kinds)."""

_GLB_MAGIC = b"glTF"
_GLB_JSON = 0x4E4F534A


def _gltf_json(path: Path, where: str) -> dict[str, object]:
    """The JSON of a .gltf file or of a GLB's first chunk; a GLB whose header or JSON chunk runs past the file's end
    is refused as truncated, and either whose JSON does not parse as not glTF."""
    shown = repr(str(path))
    try:
        if path.suffix.lower() == ".glb":
            size = path.stat().st_size
            with path.open("rb") as f:
                head = f.read(20)
                if len(head) < 12 or head[:4] != _GLB_MAGIC:
                    raise AssetSpecError(
                        where, f"{shown} is not a binary glTF (GLB) file: it does not start with the 'glTF' magic"
                    )
                declared = struct.unpack_from("<I", head, 8)[0]
                if declared > size:
                    raise AssetSpecError(
                        where, f"{shown} is truncated: its GLB header declares {declared} bytes, the file holds {size}"
                    )
                chunk, kind = struct.unpack_from("<II", head, 12) if len(head) == 20 else (0, 0)
                if kind != _GLB_JSON or 20 + chunk > declared:
                    raise AssetSpecError(
                        where, f"{shown} is not a valid GLB file: it does not begin with a JSON chunk within its length"
                    )
                text = f.read(chunk)
        else:
            text = path.read_bytes()
        data = json.loads(text)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise AssetSpecError(where, f"{shown} is not a glTF file: its JSON does not parse ({_one_line(exc)})") from exc
    if not isinstance(data, dict):
        raise AssetSpecError(where, f"{shown} is not a glTF file: its JSON is not an object")
    return data


def _check_image(target: Path, what: str, where: str) -> None:
    """Refuses a texture file that is not an image Pillow reads (trimesh would leave the texture out silently)."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(target) as img:
            img.verify()
    except (OSError, UnidentifiedImageError, SyntaxError, ValueError) as exc:
        raise AssetSpecError(where, f"{what} is not an image mmusv can read ({_one_line(exc)})") from None


def _gltf_checks(path: Path, data: dict[str, object], where: str) -> dict[str | None, float]:
    """Refuses a glTF whose external buffers or images are missing (trimesh would fail with the bare file name, or
    leave a texture out without a word); returns ``KHR_materials_emissive_strength`` by material name (trimesh
    drops the extension), refusing a material name that stands for two different strengths."""
    shown = repr(str(path))
    for kind in ("buffers", "images"):
        items = data.get(kind)
        for i, item in enumerate(items if isinstance(items, list) else []):
            uri = item.get("uri") if isinstance(item, dict) else None
            if not isinstance(uri, str) or uri.startswith("data:"):
                continue
            target = path.parent / unquote(uri)
            if not target.is_file():
                raise AssetSpecError(
                    where,
                    f"{shown} needs the file {uri!r} ({kind}[{i}].uri), which is missing (looked for "
                    f"{str(target)!r}); keep a .gltf's .bin and texture files beside it",
                )
            if kind == "images":
                _check_image(target, f"{shown}: its texture {uri!r} ({kind}[{i}].uri)", where)
    strengths: dict[str | None, float] = {}
    materials = data.get("materials")
    for i, m in enumerate(materials if isinstance(materials, list) else []):
        if not isinstance(m, dict):
            continue
        ext = m.get("extensions")
        ks = ext.get("KHR_materials_emissive_strength") if isinstance(ext, dict) else None
        value = ks.get("emissiveStrength", 1.0) if isinstance(ks, dict) else 1.0
        ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value >= 0
        if not ok:
            raise AssetSpecError(
                where,
                f"{shown}: materials[{i}] has KHR_materials_emissive_strength {value!r}; it must be a number >= 0",
            )
        name = m.get("name") if isinstance(m.get("name"), str) else None
        if strengths.get(name, float(value)) != float(value):
            raise AssetSpecError(
                where,
                f"{shown}: two materials named {name!r} have different KHR_materials_emissive_strength; give them "
                "different names",
            )
        strengths[name] = float(value)
    return strengths


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


def _check_file(path: Path, where: str, formats: list[str]) -> dict[str | None, float]:
    """Refuses what trimesh would read obscurely or not at all (module docstring); returns a glTF's emissive
    strengths by material name (empty for other formats)."""
    shown = repr(str(path))
    name = path.name.lower()
    if not any(name.endswith("." + f) for f in formats):
        ext = f"a {path.suffix!r} file" if path.suffix else "a file without an extension"
        known = ", ".join("." + f for f in sorted(_MESH_FORMATS.intersection(formats)))
        raise AssetSpecError(where, f"{shown} is {ext}; mesh files are read by their extension: {known}")
    if path.stat().st_size == 0:
        raise AssetSpecError(where, f"{shown} is empty (0 bytes): it holds no triangles")
    if path.suffix.lower() not in FORMAT_AXES:
        return {}
    return _gltf_checks(path, _gltf_json(path, where), where)


def load_mesh_file(path: Path, where: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices ``(V, 3)``, faces ``(F, 3)`` and material ids ``(F,)`` of a mesh file (glTF/GLB: its PBR
    materials, registered; other formats: material 0). Every problem is one :class:`AssetSpecError` at ``where``
    naming the file and what is wrong with it."""
    if not path.is_file():
        what = "is a folder, not a mesh file" if path.is_dir() else "does not exist"
        raise AssetSpecError(where, f"mesh file {str(path)!r} {what}")
    try:
        import trimesh
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise AssetSpecError(where, "loading mesh files needs the 'trimesh' package (pip install trimesh)") from exc
    strengths = _check_file(path, where, list(trimesh.available_formats()))
    gltf = path.suffix.lower() in FORMAT_AXES
    try:
        # Read unprocessed: trimesh's processing silently drops every face touching a NaN/inf vertex, so the raw
        # arrays are checked first; each piece is then processed exactly as ``trimesh.load(process=True)`` would.
        resolver = _resolver(path) if gltf else None
        scene = trimesh.load(str(path), force="scene", process=False, resolver=resolver)
    except Exception as exc:  # trimesh raises many types for unreadable files
        raise AssetSpecError(where, f"cannot read {str(path)!r}: {_one_line(exc)}") from exc
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
        raise AssetSpecError(where, f"cannot read {str(path)!r}: {_one_line(exc)}") from exc
    if gltf and isinstance(loaded, trimesh.Scene):
        pieces = [g for g in loaded.dump() if isinstance(g, trimesh.Trimesh)]
        cache: dict[int, int] = {}
        try:
            mats = [
                np.full(
                    len(g.faces),
                    _material_ids(getattr(g.visual, "material", None), path.stem, cache, strengths)
                    if hasattr(g.visual, "material")
                    else 0,
                    dtype=np.uint16,
                )
                for g in pieces
            ]
        except ConfigError as exc:
            raise AssetSpecError(where, f"{str(path)!r}: {_one_line(exc)}") from None
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
    up_name, fwd_name = spec.axes(str(mesh_path))
    up, fwd = _axis(up_name), _axis(fwd_name)
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
    if (spec.up_axis is None or spec.forward_axis is None) and ext[1] > ext[0]:
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
    than long: its bow probably does not point along the forward axis assumed (or the file is z-up glTF)."""
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
    warnings.warn(
        f"{join(path, 'mesh')}: {str(mesh_path)!r}, read with {given} given (up {axes[0]}, forward {axes[1]}), is "
        f"{ext[1]:.4g} m wide but {ext[0]:.4g} m long: if its bow does not point along "
        f"{axes[1]}, set forward_axis and up_axis in the entry (giving both also silences this warning).{hint}",
        MmusvWarning,
        stacklevel=5,
    )
