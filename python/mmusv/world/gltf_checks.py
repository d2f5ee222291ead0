"""The checks of a glTF/GLB file's JSON made before trimesh reads it (:func:`check_gltf`), for
:mod:`mmusv.world.mesh_files`: what trimesh would report obscurely or read wrong without a word. A GLB shorter than
its header says or without a JSON chunk; a buffer or image file that is missing (or an image Pillow cannot read); an
extension the file requires that mmusv does not read (:data:`READ_EXTENSIONS`), Draco geometry without DracoPy to
decode it, a normalized or sparse ``POSITION``; a ``COLOR_0`` glTF 2.0 does not allow or that does not fit its
primitive; two materials of one name and one factor with different ``KHR_materials_emissive_strength``; an index
into one of its lists that is not in it (a scene, node, mesh, material, accessor, buffer view, buffer or image); a
material factor outside glTF's [0, 1]. Each is one
:class:`~mmusv.world.asset_spec.AssetSpecError` at the asset entry naming the file and the glTF entry.
"""

from __future__ import annotations

import json
import math
import struct
from collections.abc import Iterator
from pathlib import Path
from typing import TypeGuard
from urllib.parse import unquote

from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.mesh_materials import EmissiveKey, check_image, emissive_key, one_line

__all__ = ["READ_EXTENSIONS", "check_gltf"]


def check_gltf(path: Path, where: str) -> tuple[dict[EmissiveKey, float], list[str]]:
    """Checks the glTF/GLB file ``path`` (module docstring; errors at the asset entry ``where``); returns its
    ``KHR_materials_emissive_strength`` by material name and ``emissiveFactor`` (trimesh drops the extension) and
    the name (``meshes[i].primitives[j]``) of each primitive trimesh makes a geometry of, in its order."""
    data = _gltf_json(path, where)
    _extension_checks(path, data, where)
    strengths, names = _gltf_checks(path, data, where), _color_0_checks(path, data, where)
    _reference_checks(repr(str(path)), data, where)  # after the checks that say more of their own entries
    return strengths, names


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
        raise AssetSpecError(where, f"{shown} is not a glTF file: its JSON does not parse ({one_line(exc)})") from exc
    if not isinstance(data, dict):
        raise AssetSpecError(where, f"{shown} is not a glTF file: its JSON is not an object")
    return data


def _gltf_checks(path: Path, data: dict[str, object], where: str) -> dict[EmissiveKey, float]:
    """Refuses a glTF whose external buffers or images are missing (trimesh would fail with the bare file name, or
    leave a texture out without a word); returns ``KHR_materials_emissive_strength`` by material name and
    ``emissiveFactor`` (:func:`~mmusv.world.mesh_materials.emissive_key`; trimesh drops the extension), refusing two
    materials of one name and one factor with different strengths."""
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
                check_image(target, what=f"{shown}: its texture {uri!r} ({kind}[{i}].uri)", where=where)
    strengths: dict[EmissiveKey, float] = {}
    materials = data.get("materials")
    for i, m in enumerate(materials if isinstance(materials, list) else []):
        if not isinstance(m, dict):
            continue
        _factor_checks(shown, i, m, where)
        ext = m.get("extensions")
        ks = ext.get("KHR_materials_emissive_strength") if isinstance(ext, dict) else None
        value = ks.get("emissiveStrength", 1.0) if isinstance(ks, dict) else 1.0
        ok = _finite_number(value) and value >= 0
        if not ok:
            raise AssetSpecError(
                where,
                f"{shown}: materials[{i}] has KHR_materials_emissive_strength {value!r}; it must be a number >= 0",
            )
        key = emissive_key(m.get("name"), m.get("emissiveFactor"))
        if key is None:  # emits nothing: the strength changes nothing
            continue
        if strengths.get(key, float(value)) != float(value):
            raise AssetSpecError(
                where,
                f"{shown}: two materials named {key[0]!r} with the same emissiveFactor have different "
                "KHR_materials_emissive_strength; give them different names",
            )
        strengths[key] = float(value)
    return strengths


def _references(data: dict[str, object]) -> Iterator[tuple[str, object, str]]:
    """Every index the glTF's JSON gives into one of its lists: ``(where it is, the index, the list's name)``."""

    def items(name: str) -> list[object]:
        v = data.get(name)
        return v if isinstance(v, list) else []

    if "scene" in data:
        yield "scene", data["scene"], "scenes"
    for i, sc in enumerate(items("scenes")):
        for j, n in enumerate(
            sc.get("nodes", []) if isinstance(sc, dict) and isinstance(sc.get("nodes"), list) else []
        ):
            yield f"scenes[{i}].nodes[{j}]", n, "nodes"
    for i, nd in enumerate(items("nodes")):
        if not isinstance(nd, dict):
            continue
        if "mesh" in nd:
            yield f"nodes[{i}].mesh", nd["mesh"], "meshes"
        kids = nd.get("children")
        for j, n in enumerate(kids if isinstance(kids, list) else []):
            yield f"nodes[{i}].children[{j}]", n, "nodes"
    for i, me in enumerate(items("meshes")):
        prims = me.get("primitives") if isinstance(me, dict) else None
        for j, pr in enumerate(prims if isinstance(prims, list) else []):
            if not isinstance(pr, dict):
                continue
            at = f"meshes[{i}].primitives[{j}]"
            if "material" in pr:
                yield f"{at}.material", pr["material"], "materials"
            if "indices" in pr:
                yield f"{at}.indices", pr["indices"], "accessors"
            attrs = pr.get("attributes")
            for name, a in attrs.items() if isinstance(attrs, dict) else []:
                yield f"{at}.attributes.{name}", a, "accessors"
    for i, ac in enumerate(items("accessors")):
        if isinstance(ac, dict) and "bufferView" in ac:
            yield f"accessors[{i}].bufferView", ac["bufferView"], "bufferViews"
    for i, bv in enumerate(items("bufferViews")):
        if isinstance(bv, dict) and "buffer" in bv:
            yield f"bufferViews[{i}].buffer", bv["buffer"], "buffers"
    for i, tx in enumerate(items("textures")):
        if isinstance(tx, dict) and "source" in tx:
            yield f"textures[{i}].source", tx["source"], "images"


def _reference_checks(shown: str, data: dict[str, object], where: str) -> None:
    """Refuses an index into one of the glTF's lists that is not in it (``scene: 5`` with one scene, a primitive's
    ``material: 7`` with one material): trimesh failed on them with a bare ``IndexError: list index out of range``."""
    for at, index, kind in _references(data):
        items = data.get(kind)
        n = len(items) if isinstance(items, list) else 0
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < n:
            have = f"indices 0..{n - 1}" if n else "none"
            raise AssetSpecError(where, f"{shown}: {at} is {index!r}, but the file has {n} {kind} ({have})")


def _finite_number(value: object) -> TypeGuard[float]:
    """Whether a JSON value is a finite number (``true`` and ``false`` are not)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


_FACTORS = (
    ("pbrMetallicRoughness", "baseColorFactor", 4),
    ("pbrMetallicRoughness", "metallicFactor", 0),
    ("pbrMetallicRoughness", "roughnessFactor", 0),
    (None, "emissiveFactor", 3),
)
"""A material's factors glTF 2.0 bounds to [0, 1]: (the object holding it, its name, its length; 0: a number)."""


def _factor_checks(shown: str, i: int, material: dict[str, object], where: str) -> None:
    """Refuses a factor of ``materials[i]`` outside glTF 2.0's [0, 1] (or not a number): trimesh keeps colour
    factors as bytes, so ``baseColorFactor [5, -1, 0.5]`` was read as (1, 0, 0.5) and ``roughnessFactor -3`` as
    0.02, without a word, where an OBJ's ``Kd 5 -1 0.5`` is refused."""
    for holder, name, n in _FACTORS:
        obj = material.get(holder) if holder else material
        if not isinstance(obj, dict) or name not in obj:
            continue
        value = obj[name]
        shaped = not n or (isinstance(value, list) and len(value) == n)  # n > 0: a list of n numbers
        values = value if n and shaped else [value]
        field = f"materials[{i}].{holder + '.' if holder else ''}{name}"
        if not shaped or not all(_finite_number(v) and 0.0 <= v <= 1.0 for v in values):
            what = f"{n} numbers in [0, 1]" if n else "a number in [0, 1]"
            raise AssetSpecError(where, f"{shown}: {field} is {value!r}; glTF 2.0 allows {what}")


_GLTF_MODES = frozenset({0, 1, 4, 5})
"""The primitive modes trimesh's glTF loader reads (points, lines, triangles, triangle strips), one geometry each."""

_COLOR_TYPES = {5126: "float", 5121: "unsigned byte", 5123: "unsigned short"}
"""The component types glTF 2.0 allows for ``COLOR_n`` (the integer ones normalized)."""


def _accessor(data: dict[str, object], index: object) -> dict[str, object] | None:
    """``accessors[index]`` of a glTF JSON, ``None`` when ``index`` names none."""
    accessors = data.get("accessors")
    ok = isinstance(index, int) and not isinstance(index, bool) and isinstance(accessors, list)
    if not ok or not 0 <= index < len(accessors):  # type: ignore[operator,arg-type]
        return None
    a = accessors[index]  # type: ignore[index]
    return a if isinstance(a, dict) else None


READ_EXTENSIONS = {
    "KHR_draco_mesh_compression": "decoded with DracoPy",
    "KHR_materials_emissive_strength": "read here",
    "KHR_materials_pbrSpecularGlossiness": "converted to metallic-roughness by trimesh",
    "KHR_mesh_quantization": "integer positions read as their numbers (normalized ones refused)",
    "KHR_texture_transform": "textures are taken by their mean, whatever their coordinates",
    "EXT_texture_webp": "read by Pillow",
}
"""The glTF extensions a file may require (``extensionsRequired``) that its meshes and materials are read right
with, and how; glTF 2.0 asks a reader to refuse a file that requires any other (trimesh would read such a file on,
e.g. meshopt-compressed geometry as zeros, without a word)."""


def _primitives(data: dict[str, object]) -> Iterator[tuple[int, int, dict[str, object]]]:
    """``(i, j, primitive)`` of every ``meshes[i].primitives[j]`` of a glTF JSON that is an object, in file order
    (entries of other kinds are skipped: trimesh's loader reports them)."""
    meshes = data.get("meshes")
    for i, m in enumerate(meshes if isinstance(meshes, list) else []):
        prims = m.get("primitives") if isinstance(m, dict) else None
        for j, p in enumerate(prims if isinstance(prims, list) else []):
            if isinstance(p, dict):
                yield i, j, p


def _extension_checks(path: Path, data: dict[str, object], where: str) -> None:
    """Refuses a glTF that requires an extension outside :data:`READ_EXTENSIONS`, that needs Draco decoding
    without DracoPy installed (Draco required, or a Draco primitive without uncompressed fallback accessors: trimesh
    would read the geometry as zeros with a printed warning), or whose ``POSITION`` is a normalized or sparse
    accessor (trimesh would read the raw integers, or leave the sparse substitutions out)."""
    shown = repr(str(path))
    required = data.get("extensionsRequired", [])
    if not isinstance(required, list) or not all(isinstance(e, str) for e in required):
        raise AssetSpecError(where, f"{shown}: extensionsRequired must be a list of extension names, got {required!r}")
    for name in required:
        if name not in READ_EXTENSIONS:
            known = ", ".join(sorted(READ_EXTENSIONS))
            raise AssetSpecError(
                where,
                f"{shown} requires the glTF extension {name!r} (extensionsRequired), which mmusv does not read; the "
                f"ones it reads are {known}: export the file without {name}",
            )
    draco = "KHR_draco_mesh_compression" in required
    for i, j, p in _primitives(data):
        ext = p.get("extensions")
        attrs = p.get("attributes")
        if isinstance(ext, dict) and "KHR_draco_mesh_compression" in ext:
            # Only geometry without an uncompressed fallback needs decoding: where every accessor has its
            # bufferView (Draco only in extensionsUsed), trimesh reads those when it cannot decode.
            used = [p.get("indices"), *(attrs.values() if isinstance(attrs, dict) else [])]
            accs = [_accessor(data, a) for a in used if a is not None]
            draco = draco or not all(a is not None and "bufferView" in a for a in accs)
        k = attrs.get("POSITION") if isinstance(attrs, dict) else None
        acc = _accessor(data, k)
        if acc is None:
            continue
        at = f"{shown}: meshes[{i}].primitives[{j}].attributes.POSITION (accessors[{k}])"
        if acc.get("normalized") is True:
            raise AssetSpecError(
                where,
                f"{at} is a normalized integer accessor, which trimesh's glTF reader would take as the raw "
                "integers (a mesh hundreds of times too large); write positions as float, or as integers without "
                "normalized with the scale in the node",
            )
        if "sparse" in acc:
            raise AssetSpecError(
                where,
                f"{at} is a sparse accessor, whose substitutions trimesh's glTF reader does not apply (the shape "
                "would be wrong without a word); write POSITION as a plain accessor",
            )
    if draco:
        try:
            import DracoPy  # noqa: F401
        except ImportError:
            raise AssetSpecError(
                where,
                f"{shown} holds Draco-compressed geometry (KHR_draco_mesh_compression), which needs the DracoPy "
                "package to decode (pip install DracoPy; mmusv's install has it); else trimesh reads it as zeros",
            ) from None


def _color_0_checks(path: Path, data: dict[str, object], where: str) -> list[str]:
    """Refuses a ``COLOR_0`` that glTF 2.0 does not allow or that does not fit its primitive (not an accessor, not
    VEC3/VEC4, not float or normalized unsigned byte/short, sparse, another count than ``POSITION``'s: trimesh would
    drop or misread it without a word); returns the name (``meshes[i].primitives[j]``) of each primitive trimesh makes a
    geometry of, in its order."""
    shown = repr(str(path))
    names: list[str] = []
    for i, j, p in _primitives(data):
        label = f"meshes[{i}].primitives[{j}]"
        mode = p.get("mode", 4)
        if isinstance(mode, int) and mode in _GLTF_MODES:
            names.append(label)
        attrs = p.get("attributes")
        if not isinstance(attrs, dict) or "COLOR_0" not in attrs:
            continue
        at = f"{shown}: {label}.attributes.COLOR_0"
        k = attrs["COLOR_0"]
        acc = _accessor(data, k)
        if acc is None:
            raise AssetSpecError(where, f"{at} is {k!r}, which names no accessor of the file")
        at = f"{at} (accessors[{k}])"
        kind, comp = acc.get("type"), acc.get("componentType")
        if kind not in ("VEC3", "VEC4"):
            raise AssetSpecError(where, f"{at} is of type {kind!r}; a vertex colour must be VEC3 or VEC4")
        if comp not in _COLOR_TYPES or (comp != 5126 and acc.get("normalized") is not True):
            what = _COLOR_TYPES.get(comp, "")  # type: ignore[call-overload]
            got = f"{comp!r} ({what}, not normalized)" if what else repr(comp)
            raise AssetSpecError(
                where,
                f"{at} has componentType {got}; a vertex colour must be float (5126), or unsigned byte (5121) "
                "or unsigned short (5123) with normalized: true",
            )
        if "sparse" in acc:
            read = "its bufferView's values" if "bufferView" in acc else "zeros (black)"
            raise AssetSpecError(
                where,
                f"{at} is a sparse accessor, whose substitutions trimesh's glTF reader does not apply (it would "
                f"read {read}); write COLOR_0 as a plain accessor, as Blender's and trimesh's exporters do",
            )
        pos = _accessor(data, attrs.get("POSITION"))
        count, vertices = acc.get("count"), None if pos is None else pos.get("count")
        if vertices is not None and count != vertices:
            raise AssetSpecError(
                where, f"{at} has {count!r} colours for the {vertices!r} vertices of its POSITION accessor"
            )
    return names
