"""The materials of user mesh files: glTF PBR, OBJ+MTL, and vertex/face colours, as :mod:`mmusv.world.materials` rows.

:mod:`mmusv.world.mesh_files` reads the geometry; this module turns what a file says about its look into one
registered material id per face (:func:`mmusv.world.materials.register_material`). Each texture is taken by its
mean over its texels (mmusv shades with one material per face).

**glTF/GLB** (glTF 2.0's metallic-roughness model): base colour = ``baseColorFactor`` times the
``baseColorTexture`` (sRGB-encoded, averaged in linear RGB); roughness and metallic = ``roughnessFactor`` and
``metallicFactor`` (default 1) times the mean of the ``metallicRoughnessTexture``'s green and blue channels
(linear); emission = ``emissiveFactor`` (default 0) times the ``emissiveTexture`` (sRGB, averaged in linear RGB)
times ``KHR_materials_emissive_strength`` (default 1), scaled by :data:`GLTF_EMISSIVE_SCALE`. A primitive's
``COLOR_0`` vertex colours (glTF 2.0 section 3.9.2: "an additional linear multiplier to base color"; float, or
unsigned byte/short normalized; RGB or RGBA, alpha not read) are taken as linear RGB as stored (glTF defines them
linear; Blender's glTF importer stores them unconverted as a Color Attribute multiplied into Base Color, white
without a material: KhronosGroup/glTF-Blender-IO #227 and #1649; three.js's GLTFLoader sets ``vertexColors``, a
multiplier of the material colour): a face's colour is the mean of its three vertices' (linear), times the
material's base colour, quantised as vertex colours are below; each distinct result is one material
``<material>:#rrggbb``, the glTF material with that base colour (its roughness, metallic and emission kept). A
primitive with ``COLOR_0`` and no material gets the vertex colour materials ``vertex_colour:#rrggbb`` below
(without ``COLOR_0``: material 0, the class's default look). A ``COLOR_0`` of another count than ``POSITION``,
another type than VEC3/VEC4, another component type than float or normalized unsigned byte/short, a sparse
accessor (trimesh does not apply its values), or with non-finite values or values outside [0, 1] is an error
(:mod:`mmusv.world.mesh_files`).

**OBJ with MTL** (:func:`obj_materials`): each face takes the material its ``usemtl`` names, read from the files
its ``mtllib`` lines name (relative to the OBJ; texture files relative to the MTL, as the Wavefront MTL spec and
Blender's importer read them, else by their file name beside the MTL, as obj2gltf looks for an absolute path
written on another machine). The conversion is Blender's OBJ importer's (``source/blender/io/wavefront_obj/
importer/obj_import_mtl.cc``, Blender 3.x-4.x), which CesiumGS obj2gltf (``lib/loadMtl.js``) agrees with on colour:

* base colour = ``Kd`` taken as linear RGB as stored (Blender sets it as the Principled BSDF's scene-linear Base
  Color, and its exporter writes that Base Color as ``Kd``, so a model round-trips to what Blender showed; obj2gltf
  writes it as the linear ``baseColorFactor``; three.js's MTLLoader, which decodes it from sRGB, differs); a
  ``map_Kd`` texture replaces ``Kd`` (Blender links it to Base Color; obj2gltf sets the factor to 1), by its mean
  in linear RGB (sRGB-encoded, as for glTF). No ``Kd`` and no ``map_Kd``: 0.8 grey, Blender's default.
* roughness = ``Pr`` where given (the PBR extension), else ``1 - sqrt(clamp(Ns, 0, 1000) / 1000)`` (Blender's
  importer), 1 without ``Ns`` (obj2gltf's default ``Ns`` 0); clamped to the table's [0.02, 1].
* metallic = ``Pm`` where given, else 0 (obj2gltf; Blender reads the mean of ``Ka`` as metallic only for
  ``illum 3``, which mmusv does not follow: most files' ``Ka`` is an ambient colour, often white).
* emission = ``Ke`` (or a ``map_Ke`` texture's linear mean in its place, as for ``map_Kd``) times
  :data:`GLTF_EMISSIVE_SCALE`: Blender imports ``Ke`` as Emission Color at strength 1, and its glTF exporter writes
  that as ``emissiveFactor``, so ``Ke 1 1 1`` glows as ``emissiveFactor [1, 1, 1]`` does.
* not read: ``d``/``Tr`` (every face is opaque), ``Ka``, ``Ks``, ``Ni``, ``illum``, bump/normal maps.

A missing ``.mtl`` or texture, a ``usemtl`` naming no material of the MTL files, or a value out of range is one
:class:`~mmusv.world.asset_spec.AssetSpecError` naming the OBJ, the entry and the path looked for (trimesh would
leave each out without a word). An OBJ without ``mtllib`` gets material 0, the class's default look (its ``usemtl``
lines name nothing to read), as do faces before its first ``usemtl``.

**Vertex and face colours** (:func:`colour_material_ids`: PLY ``red/green/blue``, OBJ ``v x y z r g b``, and any
colours trimesh reads from other formats; glTF ``COLOR_0`` is linear, above): taken as sRGB-encoded (Blender's
PLY importer and exporter default, three.js's PLYLoader); a face's colour is the mean of its three vertices'
colours in linear RGB (the mean over the face of the colour a modelling tool interpolates across it), re-encoded
to sRGB and quantised to :data:`COLOUR_LEVELS` levels per channel (1/63 steps); each distinct colour is one material
``vertex_colour:#rrggbb`` (roughness 0.5, metallic 0, the class default's), shared by every file. A file with more
than :data:`MAX_COLOUR_MATERIALS` distinct face colours is quantised coarser (32, 16, ... down to 2 levels) until
it has no more (glTF ``COLOR_0`` materials counted with them; should they still be more at 2 levels, each glTF
material its ``COLOR_0`` multiplies takes the mean of its faces' colours), with a
:class:`~mmusv.scenario_checks.MmusvWarning`. OBJ faces with an MTL material keep it.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mmusv.errors import ConfigError
from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.materials import Material, all_materials, register_material

__all__ = [
    "COLOUR_LEVELS",
    "GLTF_EMISSIVE_SCALE",
    "MAX_COLOUR_MATERIALS",
    "ObjMaterials",
    "check_image",
    "colour_material_ids",
    "emissive_key",
    "face_colours",
    "gltf_material_id",
    "obj_materials",
    "one_line",
]

GLTF_EMISSIVE_SCALE = 1.0e3
"""cd/m² of a glTF ``emissiveFactor`` (or an MTL ``Ke``) of 1 (glTF's emission is relative; 1e3 cd/m² is a bright
lit panel)."""

COLOUR_LEVELS = 64
"""Levels per sRGB channel of a vertex/face colour material (steps of 1/63)."""

MAX_COLOUR_MATERIALS = 256
"""The most vertex/face colour materials one file registers (coarser quantisation beyond, with a warning)."""

MTL_DEFAULT_KD = 0.8
"""The base colour of an MTL material without ``Kd`` or ``map_Kd`` (Blender's default Base Color)."""


def one_line(exc: BaseException) -> str:
    """An exception as one line of text (its type too where its message alone says little, a ``KeyError``'s)."""
    text = " ".join(str(exc).split())
    if not text:  # an AssertionError of a reader: its type alone (it said "AssertionError: ")
        return type(exc).__name__
    return f"{type(exc).__name__}: {text}" if isinstance(exc, LookupError) else text


def check_image(target: Path, *, what: str, where: str) -> None:
    """Refuses a texture file that is not an image Pillow reads (trimesh would leave the texture out silently).
    Any exception counts: other libraries replace ``PIL.Image.open`` (Ultralytics, once imported, answers a file
    Pillow cannot identify with its HEIF plugin's ``ModuleNotFoundError``)."""
    from PIL import Image

    try:
        with Image.open(target) as img:
            img.verify()
    except Exception as exc:
        raise AssetSpecError(where, f"{what} is not an image mmusv can read ({one_line(exc)})") from None


def _srgb_to_linear(c: np.ndarray) -> np.ndarray:
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    """Linear RGB in [0, 1] (clipped) encoded with the sRGB transfer function (IEC 61966-2-1), in [0, 1]."""
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1.0 / 2.4) - 0.055)


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
    # Counted per 8-bit level (256 bins a channel), not converted per texel: a 4000 x 4000 texture (a 2 kB PNG) took
    # 2.1 GB as float64 texels, and one near PIL's size limit would have been killed for memory. The mean is the same
    # sum over the same levels.
    if str(getattr(tex, "mode", "")).startswith("I"):  # a 16-bit grey PNG (I;16, I): convert("RGB") clipped it at 255
        counts = np.bincount(np.clip(np.asarray(tex), 0, 65535).astype(np.int64).ravel(), minlength=65536)
        grey = np.arange(65536, dtype=np.float64) / 65535.0
        mean = float(counts @ (_srgb_to_linear(grey) if srgb else grey) / max(int(counts.sum()), 1))
        return np.full(3, mean)
    levels = np.arange(256, dtype=np.float64) / 255.0
    if srgb:
        levels = _srgb_to_linear(levels)
    hist = np.asarray(tex.convert("RGB").histogram(), dtype=np.float64).reshape(3, 256)  # type: ignore[attr-defined]
    return np.asarray(hist @ levels / np.maximum(hist.sum(axis=1), 1.0), dtype=np.float64)


def _material(name: str, base: np.ndarray, rough: float, metal: float, emis: np.ndarray) -> Material:
    return Material(
        name=name,
        base_color=(float(base[0]), float(base[1]), float(base[2])),
        roughness=float(np.clip(rough, 0.02, 1.0)),
        metallic=float(np.clip(metal, 0.0, 1.0)),
        emissive=(float(emis[0]), float(emis[1]), float(emis[2])),
    )


def _pbr_material(
    mat: object, name: str, emissive_strength: float = 1.0, base_color: tuple[float, ...] | None = None
) -> Material:
    """A :class:`Material` from a trimesh material (glTF PBR; a plain material's diffuse colour otherwise).

    As glTF 2.0 defines it (module docstring), each texture by its mean: ``baseColorFactor`` (linear) times the
    sRGB ``baseColorTexture``; ``roughnessFactor`` / ``metallicFactor`` (default 1) times the green / blue channel
    of the linear ``metallicRoughnessTexture``; ``emissiveFactor`` (default 0) times the sRGB ``emissiveTexture``
    times ``emissive_strength`` (``KHR_materials_emissive_strength``), scaled by :data:`GLTF_EMISSIVE_SCALE`.
    ``base_color``: the ``baseColorFactor`` RGB as the file writes it, in place of trimesh's (rounded to 1/255).
    """
    base = np.ones(3)
    rough, metal, emis = 1.0, 1.0, np.zeros(3)
    factor = getattr(mat, "baseColorFactor", None)
    if factor is not None or hasattr(mat, "roughnessFactor"):
        base = _unit_factor(factor, 3, 1.0) if base_color is None else np.array(base_color[:3], dtype=np.float64)
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
    return _material(name, base, rough, metal, emis)


def _register(stem: str, label: str, make: object) -> int:
    """Registers ``make(name)`` as ``<stem>:<label>``, suffixed ``#2``, ``#3`` ... while that name is taken by a
    material with other values (another file of the same name)."""
    k = 1
    while True:
        name = f"{stem}:{label}" if k == 1 else f"{stem}:{label}#{k}"
        try:
            return register_material(make(name))  # type: ignore[operator]
        except ConfigError as exc:
            if "already registered" not in str(exc):
                raise
            k += 1


EmissiveKey = tuple[str | None, tuple[float, ...]]
"""A glTF material's name and ``emissiveFactor``: what its ``KHR_materials_emissive_strength`` is found by."""


def emissive_key(name: object, factor: object) -> EmissiveKey | None:
    """The key of a glTF material's ``KHR_materials_emissive_strength`` (trimesh drops the extension, so the strength
    is read from the file's JSON and found again by the material's name and ``emissiveFactor``); ``None`` for a
    material that emits nothing (no ``emissiveFactor``, or all zero: its strength changes nothing)."""
    if factor is None:
        return None
    try:
        f = tuple(float(x) for x in np.asarray(factor, dtype=np.float64).reshape(-1))
    except (TypeError, ValueError):
        return None
    if not any(f):
        return None
    return (name if isinstance(name, str) else None, f)


def gltf_material_id(
    mat: object,
    stem: str,
    cache: dict[tuple[int, tuple[float, ...] | None], int],
    strengths: dict[EmissiveKey, float],
    base_color: tuple[float, ...] | None = None,
) -> int:
    """The registered id of a trimesh material (named ``<file stem>:<material name>``, suffixed if that name is
    taken by another material); ``strengths``: the file's ``KHR_materials_emissive_strength`` by
    :func:`emissive_key`; ``base_color``: its ``baseColorFactor`` RGB as the file writes it (trimesh rounds it to
    1/255)."""
    key = (id(mat), base_color)
    if key not in cache:
        raw = getattr(mat, "name", None)
        found = emissive_key(raw, getattr(mat, "emissiveFactor", None))
        strength = 1.0 if found is None else strengths.get(found, 1.0)
        cache[key] = _register(
            stem, str(raw or "material"), lambda name: _pbr_material(mat, name, strength, base_color)
        )
    return cache[key]


# ------------------------------------------------------------------------------------------------- OBJ + MTL


_MAP_NUMBERS = {"-bm": 1, "-boost": 1, "-texres": 1, "-mm": 2, "-o": 3, "-s": 3, "-t": 3}
"""The MTL spec's texture-map options that take numbers, and how many at most (``-o``/``-s``/``-t``: u [v [w]])."""
_MAP_WORDS = {"-blendu", "-blendv", "-clamp", "-cc", "-imfchan", "-type"}
"""The MTL spec's texture-map options that take one word (``on``/``off``, a channel, a reflection type)."""


@dataclass
class _MtlEntry:
    """One ``newmtl`` of an MTL file, as read (``None``: not given)."""

    name: str
    mtl: Path
    line: int
    values: dict[str, tuple[float, ...]] = field(default_factory=dict)
    maps: dict[str, tuple[str, Path]] = field(default_factory=dict)


@dataclass
class ObjMaterials:
    """The MTL materials an OBJ uses: :meth:`resolver_text` for trimesh's OBJ reader (so that each of its pieces
    names the material's index) and :meth:`material_id` to register them."""

    path: Path
    where: str
    entries: list[_MtlEntry]
    ids: dict[int, int] = field(default_factory=dict)
    aliases: dict[str, int] = field(default_factory=dict)
    """A ``usemtl`` name as trimesh's OBJ reader takes it (the rest of the line, a ``#`` comment included) → the
    index of the material it names, where that differs from the material's name."""

    def resolver_text(self) -> bytes:
        """An MTL text naming every material with its index, for trimesh (it reads no texture from it)."""
        named = [(e.name, i) for i, e in enumerate(self.entries)] + list(self.aliases.items())
        return "".join(f"newmtl {name}\nmmusv_index {i}\n" for name, i in named).encode()

    def material_id(self, index: int) -> int:
        """The registered id of material ``index`` (``<OBJ stem>:<newmtl name>``)."""
        if index not in self.ids:
            e = self.entries[index]
            try:
                m = _mtl_values(e, self.path, self.where)
                self.ids[index] = _register(self.path.stem, e.name, lambda name: _material(name, *m))
            except ConfigError as exc:
                raise AssetSpecError(self.where, f"{str(self.path)!r}: {one_line(exc)}") from None
        return self.ids[index]


def _obj_lines(text: str) -> list[tuple[int, list[str]]]:
    """The OBJ/MTL ``text``'s lines as (line number, tokens), without comments and blank lines; ``\\`` continues."""
    out = []
    for n, raw in enumerate(text.replace("\\\r\n", "").replace("\\\n", "").splitlines(), start=1):
        tokens = raw.split("#", 1)[0].split()
        if tokens:
            out.append((n, tokens))
    return out


def _relative(folder: Path, name: str) -> Path:
    """A file name of an OBJ/MTL line, relative to ``folder`` (Windows separators read as ``/``)."""
    return folder / name.replace("\\", "/")


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _map_file(tokens: list[str]) -> str:
    """The file name of a texture-map line's values, after its options (``-s 1 1 1 hull.png``: ``hull.png``)."""
    i = 0
    while i < len(tokens) - 1:
        opt = tokens[i].lower()
        if opt in _MAP_WORDS:
            i += 2
        elif opt in _MAP_NUMBERS:
            i += 1
            for _ in range(_MAP_NUMBERS[opt]):
                if i < len(tokens) - 1 and _is_number(tokens[i]):
                    i += 1
        else:
            break
    return " ".join(tokens[i:])


def _read_mtl(obj: Path, entry: str, mtl: Path, where: str) -> list[_MtlEntry]:
    """The materials of one MTL file (``entry``: the OBJ's ``mtllib`` name of it), texture files checked."""
    shown = repr(str(obj))
    entries: list[_MtlEntry] = []
    text = mtl.read_bytes().decode("utf-8", errors="replace")
    for n, tokens in _obj_lines(text):
        key = tokens[0].lower()
        at = f"{shown}: its material library {entry!r} line {n}"
        if key == "newmtl":
            entries.append(_MtlEntry(" ".join(tokens[1:]), mtl, n))
        elif not entries:
            continue
        elif key in ("kd", "ke", "ns", "pr", "pm"):
            try:
                vals = tuple(float(t) for t in tokens[1:])
            except ValueError:
                raise AssetSpecError(
                    where, f"{at} ({tokens[0]}) must give numbers, got {' '.join(tokens[1:])!r}"
                ) from None
            if not vals or not all(math.isfinite(v) for v in vals):
                raise AssetSpecError(where, f"{at} ({tokens[0]}) must give finite numbers")
            entries[-1].values[key] = vals
        elif key in ("map_kd", "map_ke"):
            name = _map_file(tokens[1:])
            target = _relative(mtl.parent, name)
            beside = mtl.parent / Path(name.replace("\\", "/")).name  # obj2gltf's second place: beside the .mtl
            what = f"{shown}: its material library {entry!r} ({tokens[0]} {name!r}, material {entries[-1].name!r})"
            if not target.is_file() and beside.is_file():
                target = beside
            elif not target.is_file():
                also = f" and {str(beside)!r}" if beside != target else ""
                raise AssetSpecError(
                    where,
                    f"{what} needs the texture {name!r}, which is missing (looked for {str(target)!r}{also}); keep "
                    "texture files where the .mtl names them",
                )
            check_image(target, what=what, where=where)
            entries[-1].maps[key] = (name, target)
    return entries


def _colour(e: _MtlEntry, key: str, label: str, at: str, where: str) -> np.ndarray | None:
    """An MTL colour statement's three numbers (one number: grey, as the MTL spec says); ``None`` when absent."""
    vals = e.values.get(key)
    if vals is None:
        return None
    if len(vals) not in (1, 3):
        raise AssetSpecError(where, f"{at}: {label} must give one or three numbers, got {list(vals)}")
    return np.array(vals * 3 if len(vals) == 1 else vals, dtype=np.float64)


def _mapped_colour(e: _MtlEntry, key: str, value: np.ndarray) -> np.ndarray:
    """The ``(3,)`` float64 linear RGB in [0, 1] of MTL material ``e``'s texture map ``key`` (``map_kd``,
    ``map_ke``): the mean of its texels decoded from sRGB, when it has that map; else ``value``, the colour its
    plain statement (or the default) gives."""
    if key not in e.maps:
        return value
    from PIL import Image

    with Image.open(e.maps[key][1]) as img:
        return _texture_mean(img, srgb=True)


def _mtl_values(e: _MtlEntry, obj: Path, where: str) -> tuple[np.ndarray, float, float, np.ndarray]:
    """Base colour, roughness, metallic and emission of an MTL material (module docstring)."""
    at = f"{str(obj)!r}: material {e.name!r} of {e.mtl.name!r} (line {e.line})"
    kd = _colour(e, "kd", "Kd", at, where)
    if kd is not None and not np.all((kd >= 0.0) & (kd <= 1.0)):
        raise AssetSpecError(where, f"{at}: Kd {kd.tolist()} must be in [0, 1]")
    base = _mapped_colour(e, "map_kd", kd if kd is not None else np.full(3, MTL_DEFAULT_KD))
    scalars = {}
    for key, label, top in (("ns", "Ns", math.inf), ("pr", "Pr", 1.0), ("pm", "Pm", 1.0)):
        vals = e.values.get(key)
        if vals is not None and not 0.0 <= vals[0] <= top:
            bound = ">= 0" if top == math.inf else f"in [0, {top:g}]"
            raise AssetSpecError(where, f"{at}: {label} {vals[0]:g} must be {bound}")
        scalars[key] = None if vals is None else vals[0]
    pr, ns, pm = scalars["pr"], scalars["ns"], scalars["pm"]
    rough = pr if pr is not None else (1.0 if ns is None else 1.0 - math.sqrt(min(ns, 1000.0) / 1000.0))
    ke = _colour(e, "ke", "Ke", at, where)
    if ke is not None and np.any(ke < 0.0):
        raise AssetSpecError(where, f"{at}: Ke {ke.tolist()} must be >= 0")
    emis = _mapped_colour(e, "map_ke", ke if ke is not None else np.zeros(3))
    return base, rough, 0.0 if pm is None else pm, emis * GLTF_EMISSIVE_SCALE


def obj_materials(path: Path, where: str) -> ObjMaterials | None:
    """The MTL materials of the OBJ ``path`` (``None`` when it names no ``mtllib``: the class's default look).

    Every ``mtllib`` file (several per line, or one name with spaces, relative to the OBJ) and every ``map_Kd`` /
    ``map_Ke`` texture must exist, and every ``usemtl`` name a material of them: else one
    :class:`~mmusv.world.asset_spec.AssetSpecError` at ``where`` naming the OBJ, the entry and the path looked for.
    """
    shown = repr(str(path))
    text = path.read_bytes().decode("utf-8", errors="replace")
    lines = _obj_lines(text)
    libs = [(n, toks[1:]) for n, toks in lines if toks[0] == "mtllib" and len(toks) > 1]
    if not libs:
        return None
    entries: list[_MtlEntry] = []
    for n, names in libs:
        whole = " ".join(names)
        files = [whole] if _relative(path.parent, whole).is_file() else names
        for name in files:
            target = _relative(path.parent, name)
            if not target.is_file():
                raise AssetSpecError(
                    where,
                    f"{shown} needs its material library {name!r} (mtllib, line {n}), which is missing (looked for "
                    f"{str(target)!r}); keep the .mtl beside the .obj, or delete the mtllib line for the class's "
                    "default look",
                )
            entries.extend(_read_mtl(path, name, target, where))
    known = {e.name for e in entries}
    for n, toks in lines:
        if toks[0] == "usemtl" and " ".join(toks[1:]) not in known:
            raise AssetSpecError(
                where,
                f"{shown}: usemtl {' '.join(toks[1:])!r} (line {n}) names no material of its material libraries "
                f"({', '.join(repr(k) for k in sorted(known)) or 'none'})",
            )
    index = {e.name: i for i, e in enumerate(entries)}  # a name given twice: the last, as trimesh keeps it
    aliases = {}
    for raw in text.splitlines():  # trimesh names a usemtl by the rest of its line: 'Deck#2', 'Hull # red'
        line = raw.strip()
        if line.startswith("usemtl "):
            name = line[6:].strip()
            ours = " ".join(name.split("#", 1)[0].split())
            if name != ours and ours in index:
                aliases[name] = index[ours]
    return ObjMaterials(path, where, entries, aliases=aliases)


# ------------------------------------------------------------------------------------------ vertex/face colours


def face_colours(mesh: object) -> np.ndarray | None:
    """``(F, 3)`` linear RGB per face of a trimesh mesh with vertex or face colours (sRGB-encoded; a face's the
    mean of its vertices' in linear RGB), ``None`` without."""
    visual = getattr(mesh, "visual", None)
    kind = getattr(visual, "kind", None)
    if kind == "vertex":
        lin = _srgb_to_linear(np.asarray(visual.vertex_colors)[:, :3] / 255.0)  # type: ignore[union-attr]
        return np.asarray(lin[np.asarray(mesh.faces)].mean(axis=1))  # type: ignore[attr-defined]
    if kind == "face":
        return _srgb_to_linear(np.asarray(visual.face_colors)[:, :3] / 255.0)  # type: ignore[union-attr]
    return None


def _colour_material(name: str, byte: np.ndarray) -> Material:
    return _material(name, _srgb_to_linear(byte / 255.0), 0.5, 0.0, np.zeros(3))


def _quantise(srgb: np.ndarray, levels: int) -> np.ndarray:
    """sRGB values in [0, 1] rounded to ``levels`` (>= 2) levels per channel, as bytes (``int64``)."""
    return np.round(np.round(srgb * (levels - 1)) * 255.0 / (levels - 1)).astype(np.int64)


def colour_material_ids(colours: np.ndarray, path: Path, where: str, tints: np.ndarray | None = None) -> np.ndarray:
    """The material ids ``(F,)`` of faces of linear colours ``(F, 3)`` (module docstring: quantised in sRGB to
    :data:`COLOUR_LEVELS` levels, coarser with a warning beyond :data:`MAX_COLOUR_MATERIALS` materials).

    ``tints`` ``(F,)``: per face, the registered glTF material its colour (``COLOR_0``) multiplies, or -1 for a
    plain vertex colour material (all -1 when not given)."""
    tint = np.full(len(colours), -1, dtype=np.int64) if tints is None else np.asarray(tints, dtype=np.int64)
    table = all_materials()
    base = np.ones((len(colours), 3))
    for t in np.unique(tint[tint >= 0]).tolist():
        base[tint == t] = table[t].base_color
    srgb = linear_to_srgb(np.asarray(colours, dtype=np.float64) * base)
    levels = COLOUR_LEVELS
    while True:
        byte = _quantise(srgb, levels)
        uniq, inverse = np.unique(np.c_[tint, byte], axis=0, return_inverse=True)
        if len(uniq) <= MAX_COLOUR_MATERIALS or levels <= 2:
            break
        levels //= 2
    per_material = len(uniq) > MAX_COLOUR_MATERIALS  # only COLOR_0 gets here: 2 levels are 8 plain colours at most
    if per_material:
        for t in np.unique(tint[tint >= 0]).tolist():
            mean = (np.asarray(colours, dtype=np.float64) * base)[tint == t].mean(axis=0)
            byte[tint == t] = _quantise(linear_to_srgb(mean), COLOUR_LEVELS)
        uniq, inverse = np.unique(np.c_[tint, byte], axis=0, return_inverse=True)
    if levels < COLOUR_LEVELS:
        from mmusv.scenario_checks import MmusvWarning  # here: scenario_checks imports the config, which imports us

        how = (
            "even at 2 levels its COLOR_0 vertex colours give more, so each glTF material they multiply takes the "
            "mean of its faces' colours, the other faces 2 levels"
            if per_material
            else f"quantised to {levels} levels"
        )
        warnings.warn(
            f"{where}: {str(path)!r} has more than {MAX_COLOUR_MATERIALS} distinct face colours at {COLOUR_LEVELS} "
            f"levels per channel; {how} ({len(uniq)} materials)",
            MmusvWarning,
            stacklevel=6,
        )
    ids = np.empty(len(uniq), dtype=np.uint16)
    try:
        for k, row in enumerate(uniq):
            t, b = int(row[0]), row[1:].astype(np.float64)
            label = "#{:02x}{:02x}{:02x}".format(*(int(c) for c in b))
            if t < 0:
                m = _colour_material(f"vertex_colour:{label}", b)
            else:
                lin = _srgb_to_linear(b / 255.0)
                rgb = (float(lin[0]), float(lin[1]), float(lin[2]))
                m = dataclasses.replace(table[t], name=f"{table[t].name}:{label}", base_color=rgb)
            ids[k] = register_material(m)
    except ConfigError as exc:
        raise AssetSpecError(where, f"{str(path)!r}: {one_line(exc)}") from None
    return ids[inverse.reshape(-1)]
