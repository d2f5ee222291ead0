"""The checks of a glTF/GLB file's JSON made before trimesh reads it (:func:`check_gltf`), for
:mod:`mmusv.world.mesh_files`: what trimesh would report obscurely or read wrong without a word. A GLB shorter than
its header says or without a JSON chunk; a buffer or image file that is missing (or an image Pillow cannot read); an
extension the file requires that mmusv does not read (:data:`READ_EXTENSIONS`), Draco geometry without DracoPy to
decode it, a normalized or sparse ``POSITION``; a ``COLOR_0`` glTF 2.0 does not allow or that does not fit its
primitive; two materials of one name and one factor with different ``KHR_materials_emissive_strength``; a material
factor outside glTF's [0, 1]; an accessor or primitive mode glTF 2.0 does not define; a buffer without the ``uri`` it
needs. The checks of the document's graph (an index into one of its lists that is not in it, node transforms and
trees, a scene that draws no triangle) are in :mod:`mmusv.world.gltf_graph`. Each is one
:class:`~mmusv.world.asset_spec.AssetSpecError` at the asset entry naming the file and the glTF entry.
"""

from __future__ import annotations

import json
import struct
from pathlib import Path
from urllib.parse import unquote

from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.gltf_graph import (
    MODES,
    finite_number,
    node_checks,
    primitives,
    reference_checks,
    surface_checks,
)
from mmusv.world.mesh_materials import EmissiveKey, check_image, emissive_key, one_line

__all__ = ["READ_EXTENSIONS", "PrimitiveMaterial", "check_gltf", "gltf_json"]


PrimitiveMaterial = tuple[int, dict[str, object]] | None
"""A primitive's material: its index in the file's ``materials`` and its JSON object (``None``: no material)."""


def check_gltf(path: Path, where: str) -> tuple[dict[EmissiveKey, float], list[str], list[PrimitiveMaterial]]:
    """Checks the glTF/GLB file ``path`` (module docstring; errors at the asset entry ``where``); returns its
    ``KHR_materials_emissive_strength`` by material name and ``emissiveFactor`` (trimesh drops the extension), the
    name (``meshes[i].primitives[j]``) of each primitive trimesh makes a geometry of, in its order, and the material
    of each of them (:data:`PrimitiveMaterial`)."""
    data = gltf_json(path, where)
    shown = repr(str(path))
    _asset_checks(shown, data, where)
    _extension_checks(path, data, where)
    strengths, names = _gltf_checks(path, data, where), _color_0_checks(path, data, where)
    reference_checks(shown, data, where)  # after the checks that say more of their own entries
    _accessor_checks(shown, data, where)
    node_checks(shown, data, where)
    _buffer_checks(path, data, where)
    surface_checks(shown, data, where)
    return strengths, names, _primitive_materials(data)


_GLB_MAGIC = b"glTF"
_GLB_JSON = 0x4E4F534A


def gltf_json(path: Path, where: str) -> dict[str, object]:
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
        ok = finite_number(value) and value >= 0
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
        if not shaped or not all(finite_number(v) and 0.0 <= v <= 1.0 for v in values):
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
    for i, j, p in primitives(data):
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
    for i, j, p in primitives(data):
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


def _asset_checks(shown: str, data: dict[str, object], where: str) -> None:
    """Refuses JSON that is not glTF 2.x: glTF 2.0 requires ``asset.version`` (``"2.0"``), and a reader refuses a
    major version it does not know (glTF 1.0's JSON is laid out otherwise) or a ``minVersion`` above its own."""
    asset = data.get("asset")
    version = asset.get("version") if isinstance(asset, dict) else None
    if not isinstance(version, str):
        raise AssetSpecError(
            where,
            f"{shown} is not a glTF file: its JSON has no asset.version (glTF 2.0 requires "
            '"asset": {"version": "2.0"})',
        )
    minimum = asset.get("minVersion", "2.0") if isinstance(asset, dict) else "2.0"
    if version.split(".")[0] != "2" or not isinstance(minimum, str) or minimum.split(".")[0] != "2":
        raise AssetSpecError(where, f"{shown} is glTF {version!r} (minVersion {minimum!r}); mmusv reads glTF 2.x files")


_COMPONENTS = {5120: "byte", 5121: "unsigned byte", 5122: "short", 5123: "unsigned short", 5125: "unsigned int"}
_COMPONENTS[5126] = "float"
_TYPES = frozenset({"SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"})
_POSITION_COMPONENTS = frozenset({5126, 5120, 5121, 5122, 5123})
"""float, and the integer types ``KHR_mesh_quantization`` allows for ``POSITION``."""
_INDEX_COMPONENTS = frozenset({5121, 5123, 5125})


def _accessor_checks(shown: str, data: dict[str, object], where: str) -> None:
    """Refuses an accessor of a ``componentType`` or ``type`` glTF 2.0 does not define, a primitive ``mode`` it does
    not define or trimesh leaves out (``TRIANGLE_FAN``: its triangles were dropped without a word), a triangle
    primitive without ``POSITION``, a ``POSITION`` that is not VEC3 of float (or the integers
    ``KHR_mesh_quantization`` allows), and ``indices`` that are not SCALAR unsigned integers: trimesh failed on them
    inside (a bare ``IndexError`` for a VEC2 ``POSITION``) or read them wrong."""
    accessors = data.get("accessors")
    for i, acc in enumerate(accessors if isinstance(accessors, list) else []):
        if not isinstance(acc, dict):
            raise AssetSpecError(where, f"{shown}: accessors[{i}] is {acc!r:.60}, not an object")
        comp, kind = acc.get("componentType"), acc.get("type")
        if isinstance(comp, bool) or comp not in _COMPONENTS:
            known = ", ".join(f"{k} ({v})" for k, v in _COMPONENTS.items())
            raise AssetSpecError(where, f"{shown}: accessors[{i}].componentType is {comp!r}; glTF 2.0 defines {known}")
        if kind not in _TYPES:
            raise AssetSpecError(
                where, f"{shown}: accessors[{i}].type is {kind!r}; glTF 2.0 defines {', '.join(sorted(_TYPES))}"
            )
    for i, j, p in primitives(data):
        at = f"{shown}: meshes[{i}].primitives[{j}]"
        mode = p.get("mode", 4)
        if isinstance(mode, bool) or mode not in MODES:
            raise AssetSpecError(where, f"{at}.mode is {mode!r}; glTF 2.0 defines modes 0..6")
        if mode == 6:
            raise AssetSpecError(
                where,
                f"{at} is a TRIANGLE_FAN (mode 6), which trimesh's glTF reader leaves out (the vessel would lose "
                "its triangles without a word); export it as TRIANGLES (mode 4)",
            )
        attrs = p.get("attributes")
        if mode not in (4, 5):  # points and lines: no surface, left out
            continue
        if not isinstance(attrs, dict) or "POSITION" not in attrs:
            raise AssetSpecError(where, f"{at} has no attributes.POSITION: its triangles have no vertices to read")
        pos = _accessor(data, attrs["POSITION"])
        if pos is not None and (pos.get("type") != "VEC3" or pos.get("componentType") not in _POSITION_COMPONENTS):
            raise AssetSpecError(
                where,
                f"{at}.attributes.POSITION (accessors[{attrs['POSITION']}]) is {pos.get('type')!r} of "
                f"{_COMPONENTS.get(pos.get('componentType'), '?')!r}; glTF 2.0 positions are VEC3 of float (or of the "  # type: ignore[call-overload]
                "integers KHR_mesh_quantization allows)",
            )
        idx = _accessor(data, p.get("indices"))
        if idx is not None and (idx.get("type") != "SCALAR" or idx.get("componentType") not in _INDEX_COMPONENTS):
            raise AssetSpecError(
                where,
                f"{at}.indices (accessors[{p.get('indices')}]) is {idx.get('type')!r} of componentType "
                f"{idx.get('componentType')!r}; glTF 2.0 indices are SCALAR unsigned byte, short or int "
                "(5121, 5123, 5125)",
            )


def _buffer_checks(path: Path, data: dict[str, object], where: str) -> None:
    """Refuses a buffer without ``uri`` where glTF 2.0 asks for one (every buffer of a ``.gltf``, every buffer but the
    first of a GLB), and a GLB whose first buffer has no ``uri`` but that holds no binary chunk to take its place:
    trimesh failed on them with a bare ``KeyError: 'uri'`` or ``IndexError``."""
    shown = repr(str(path))
    buffers = data.get("buffers")
    glb = path.suffix.lower() == ".glb"
    for i, b in enumerate(buffers if isinstance(buffers, list) else []):
        if not isinstance(b, dict):
            raise AssetSpecError(where, f"{shown}: buffers[{i}] is {b!r:.60}, not an object")
        if "uri" in b:
            continue
        if not glb or i > 0:
            raise AssetSpecError(
                where,
                f"{shown}: buffers[{i}] has no uri; glTF 2.0 leaves it out only for a GLB's first buffer (its "
                "binary chunk): give the .bin file's name or a data: URI",
            )
        if not _glb_has_bin(path):
            raise AssetSpecError(
                where,
                f"{shown}: buffers[0] has no uri, so it is the GLB's binary chunk, but the file holds no binary "
                "chunk after its JSON: the file is truncated or damaged",
            )


def _glb_has_bin(path: Path) -> bool:
    """Whether the GLB ``path`` holds a chunk after its JSON chunk, of type BIN."""
    with path.open("rb") as f:
        head = f.read(20)
        json_length = struct.unpack_from("<I", head, 12)[0]
        f.seek(20 + json_length)
        chunk = f.read(8)
    return len(chunk) == 8 and struct.unpack_from("<I", chunk, 4)[0] == 0x004E4942


def _primitive_materials(data: dict[str, object]) -> list[PrimitiveMaterial]:
    """The material of each primitive trimesh makes a geometry of (those of :func:`_color_0_checks`'s names), in
    its order."""
    materials = data.get("materials")
    out: list[PrimitiveMaterial] = []
    for _, _, p in primitives(data):
        mode = p.get("mode", 4)
        if not (isinstance(mode, int) and mode in _GLTF_MODES):
            continue
        k = p.get("material")
        ok = isinstance(k, int) and not isinstance(k, bool) and isinstance(materials, list)
        m = materials[k] if ok else None  # type: ignore[index]
        out.append((k, m) if isinstance(m, dict) else None)  # type: ignore[arg-type]
    return out
