"""The vessel asset library: procedural vessels from 3 m to 330 m, instrumented USVs, and user assets.

Every asset is a :class:`VesselAsset`: a triangle mesh of closed, outward-facing pieces with a material per face
(:mod:`mmusv.world.materials`) in the vessel **body frame**
(x forward with the bow at +x, y left, z up; origin at the waterline centre of the bounding box in x/y; z = 0 is
the waterline, so the hull reaches down to ``z = -draft``) plus its dimensions, which are always the mesh's
bounding box: ``length`` = x extent, ``beam`` = y extent, ``height`` = z extent (keel to top), ``draft`` =
``-min z``. All in metres.

Built-in assets are described in ``vessel_catalog.yaml`` (entries validated by the schema in
:mod:`mmusv.world.asset_spec`, procedural meshes built by :mod:`mmusv.world.vessel_shapes`) and built on first use,
then cached. Users add their own with
:func:`load_asset_file` (a mesh file, OBJ/STL/PLY/GLB via trimesh, a glTF/GLB read +Y up and bow +Z as glTF
defines unless the entry says otherwise, or a procedural hull/parts entry) and
:func:`register_asset`; glTF/GLB files bring their PBR materials (registered with
:func:`mmusv.world.materials.register_material`; the files are read by :mod:`mmusv.world.mesh_files`)::

    from mmusv.world.vessels import get_asset, library
    ship = get_asset("container_ship_300m")
    ship.length, ship.mesh.vertices.shape        # 300.0, (V, 3)
    [a.name for a in library(category="tug")]
"""

from __future__ import annotations

import difflib
import os
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np
import yaml

from mmusv.classes import SemanticClass
from mmusv.errors import ConfigError, NotFoundError
from mmusv.validation import join
from mmusv.world.asset_spec import (
    MOUNT_REACH,
    NAME_PATTERN,
    AssetSpecError,
    ProceduralAssetSpec,
    dimension_problem,
    mount_reach,
    parse_asset,
)
from mmusv.world.mesh_files import mesh_asset
from mmusv.world.primitives import TriMesh
from mmusv.world.vessel_shapes import build_procedural
from mmusv.yamlio import parse_yaml, read_yaml

__all__ = [
    "AssetNameError",
    "AssetSpecError",
    "MountPoint",
    "UnknownAssetError",
    "VesselAsset",
    "asset_names",
    "categories",
    "get_asset",
    "known_asset",
    "library",
    "load_asset_catalog",
    "load_asset_file",
    "register_asset",
    "unregister_asset",
]

_ALLOWED_CLASSES = (SemanticClass.VESSEL, SemanticClass.USV)
_YamlLoader: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class MountPoint(NamedTuple):
    """A sensor mount in the vessel body frame: ``xyz`` metres, ``rpy_deg`` roll/pitch/yaw degrees (R = Rz·Ry·Rx).

    The sensor's own body frame (x forward, y left, z up) is rotated by ``rpy_deg``: yaw 90 looks to port,
    pitch 90 looks straight down.
    """

    xyz: tuple[float, float, float]
    rpy_deg: tuple[float, float, float]


def _as_mount(m: object, where: str) -> MountPoint:
    try:
        pair: Sequence[Any] = m  # type: ignore[assignment]
        xyz, rpy = pair
        a = tuple(float(x) for x in xyz)
        b = tuple(float(x) for x in rpy)
    except (TypeError, ValueError) as exc:
        raise AssetSpecError(where, f"must be (xyz, rpy_deg), two triples of numbers; got {m!r}") from exc
    if len(a) != 3 or len(b) != 3 or not all(np.isfinite(a + b)):
        raise AssetSpecError(where, f"must be (xyz, rpy_deg), two finite triples; got {m!r}")
    return MountPoint((a[0], a[1], a[2]), (b[0], b[1], b[2]))


class UnknownAssetError(NotFoundError, KeyError):
    """No asset has this name (a :class:`mmusv.NotFoundError`, and a ``KeyError`` as before).

    ``suggestions`` holds close matches; ``str()`` is a readable message.
    """

    def __init__(self, name: str, known: Sequence[str]) -> None:
        self.name = name
        self.suggestions = _suggest(name, known)
        hint = f"did you mean {', '.join(repr(s) for s in self.suggestions)}?" if self.suggestions else "no close match"
        self.message = (
            f"unknown vessel asset {name!r}; {hint} (mmusv.world.vessels.asset_names() lists all {len(known)} assets)"
        )
        super().__init__(self.message)

    def __str__(self) -> str:
        return self.message

    def __reduce__(self) -> tuple[Any, ...]:
        return (_unknown_asset_error, (self.name, tuple(self.suggestions), self.message))


def _unknown_asset_error(name: str, suggestions: tuple[str, ...], message: str) -> UnknownAssetError:
    err = UnknownAssetError.__new__(UnknownAssetError)
    NotFoundError.__init__(err, message)
    err.name, err.suggestions, err.message = name, list(suggestions), message
    return err


def _suggest(name: str, known: Sequence[str]) -> list[str]:
    key = str(name).lower()
    out = difflib.get_close_matches(key, list(known), n=5, cutoff=0.5)
    for k in known:
        if len(out) >= 5:
            break
        if key and key in k.lower() and k not in out:
            out.append(k)
    return out


@dataclass(frozen=True, eq=False)
class VesselAsset:
    """One vessel asset: a labelled body-frame mesh, its bounding-box dimensions and sensor mounts.

    Constructed from ``name``, ``category``, ``semantic_class`` (VESSEL or USV), ``mesh`` and optionally
    ``mounts``/``description``/``source``; ``length``, ``beam``, ``height``, ``draft`` (metres, floats) and
    ``bbox`` (``(2, 3)`` float64, min/max corner, metres, body frame) are computed from the mesh. The mesh
    arrays are copied and made read-only. The mesh must be centred in x/y (|centre| <= 1e-6 of its size)
    and must cross the waterline (``min z < 0 < max z``), its size must lie in
    :data:`mmusv.world.asset_spec.DIMENSION_RANGES` and every mount within
    :func:`mmusv.world.asset_spec.mount_reach` of its bounding box; otherwise ``ValueError``.
    """

    name: str
    category: str
    semantic_class: SemanticClass
    mesh: TriMesh = field(repr=False)
    mounts: Mapping[str, MountPoint] = field(default_factory=dict, repr=False)
    description: str = field(default="", repr=False)
    source: str = "builtin"
    parts: tuple[str, ...] = field(default=(), repr=False)
    """The part types of a procedural asset, in catalogue order (empty for a mesh file)."""
    length: float = field(init=False)
    beam: float = field(init=False)
    height: float = field(init=False)
    draft: float = field(init=False)
    bbox: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not NAME_PATTERN.match(self.name):
            raise AssetSpecError("name", f"must be letters, digits, '_', '-' or '.', got {self.name!r}")
        cls = SemanticClass(self.semantic_class)
        if cls not in _ALLOWED_CLASSES:
            raise AssetSpecError(f"{self.name}.semantic_class", f"must be vessel or usv, got {cls.name.lower()}")
        object.__setattr__(self, "semantic_class", cls)
        v = np.array(self.mesh.vertices, dtype=np.float64)
        fc = np.array(self.mesh.faces, dtype=np.int64)
        c = np.array(self.mesh.classes, dtype=np.uint16)
        mat = np.array(self.mesh.materials, dtype=np.uint16)
        if fc.shape[0] == 0 or v.shape[0] == 0:
            raise AssetSpecError(f"{self.name}.mesh", "mesh has no triangles")
        if not np.all(np.isfinite(v)):
            raise AssetSpecError(f"{self.name}.mesh", "mesh has non-finite vertices")
        if fc.min() < 0 or fc.max() >= v.shape[0]:
            raise AssetSpecError(f"{self.name}.mesh", "face indices out of range")
        for a in (v, fc, c, mat):
            a.setflags(write=False)
        mesh = TriMesh(v, fc, c, mat)
        used = np.zeros(v.shape[0], dtype=bool)
        used[fc.reshape(-1)] = True
        lo, hi = v[used].min(axis=0), v[used].max(axis=0)
        ext = hi - lo
        centre = (lo[:2] + hi[:2]) / 2.0
        if np.any(np.abs(centre) > 1e-6 * max(1.0, float(ext.max()))):
            raise AssetSpecError(f"{self.name}.mesh", f"x/y bounding box centre is {centre.tolist()}, not the origin")
        if not lo[2] < 0.0 < hi[2]:
            raise AssetSpecError(
                f"{self.name}.mesh", f"mesh spans z [{lo[2]:g}, {hi[2]:g}] m; it must cross the waterline z = 0"
            )
        problem = dimension_problem(length=float(ext[0]), beam=float(ext[1]), height=float(ext[2]))
        if problem is not None:
            raise AssetSpecError(f"{self.name}.mesh", f"the mesh's bounding box {problem}")
        bbox = np.stack([lo, hi])
        bbox.setflags(write=False)
        mounts = {str(k): _as_mount(m, f"{self.name}.mounts.{k}") for k, m in dict(self.mounts).items()}
        reach = mount_reach(float(ext[0]))
        for k, m in mounts.items():
            p = np.asarray(m.xyz, dtype=np.float64)
            off = float(np.linalg.norm(p - np.clip(p, lo, hi)))
            if off > reach:
                box = ", ".join(f"[{a:.6g}, {b:.6g}]" for a, b in zip(lo, hi, strict=True))
                raise AssetSpecError(
                    f"{self.name}.mounts.{k}.xyz",
                    f"{list(m.xyz)} lies {off:.6g} m outside the hull's bounding box (x, y, z: {box} m); a mount "
                    f"must lie within max({MOUNT_REACH[0]:g} x length, {MOUNT_REACH[1]:g} m) = {reach:g} m of it",
                )
        object.__setattr__(self, "mesh", mesh)
        object.__setattr__(self, "mounts", MappingProxyType(mounts))
        object.__setattr__(self, "bbox", bbox)
        object.__setattr__(self, "parts", tuple(str(t) for t in self.parts))
        object.__setattr__(self, "length", float(ext[0]))
        object.__setattr__(self, "beam", float(ext[1]))
        object.__setattr__(self, "height", float(ext[2]))
        object.__setattr__(self, "draft", float(-lo[2]))

    def __getstate__(self) -> dict[str, Any]:
        """Pickling (a ``DataLoader`` worker, ``copy.deepcopy``): the mounts as a plain dict (a read-only view
        cannot be pickled)."""
        state = dict(self.__dict__)
        state["mounts"] = dict(self.mounts)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        """Unpickling: the mounts read-only again."""
        state = dict(state)
        state["mounts"] = MappingProxyType(dict(state["mounts"]))
        self.__dict__.update(state)

    @property
    def air_draft(self) -> float:
        """Height of the highest point above the waterline, metres (``height - draft``)."""
        return float(self.bbox[1, 2])

    @property
    def num_triangles(self) -> int:
        """Number of mesh triangles."""
        return self.mesh.num_triangles

    @property
    def num_parts(self) -> int:
        """Number of catalogue parts of a procedural asset (0 for a mesh file)."""
        return len(self.parts)

    @property
    def is_usv(self) -> bool:
        """Whether this is an (instrumentable) USV asset."""
        return self.semantic_class == SemanticClass.USV


# ------------------------------------------------------------------------------------------------- library

_lock = threading.RLock()
_entries: dict[str, Mapping[str, Any]] | None = None
_built: dict[str, VesselAsset] = {}
_user: dict[str, VesselAsset] = {}


def _builtin_entries() -> dict[str, Mapping[str, Any]]:
    global _entries
    with _lock:
        if _entries is None:
            text = resources.files("mmusv.world").joinpath("vessel_catalog.yaml").read_text(encoding="utf-8")
            data = parse_yaml(text, "vessel_catalog.yaml", trusted=True)
            _entries = _index_entries(data, source="vessel_catalog.yaml")
        return _entries


def _index_entries(data: object, *, source: str) -> dict[str, Mapping[str, Any]]:
    items = data.get("vessels") if isinstance(data, Mapping) else data
    if not isinstance(items, list):
        raise AssetSpecError("vessels", f"{source} must hold a list of entries (or a 'vessels:' list)")
    out: dict[str, Mapping[str, Any]] = {}
    for i, item in enumerate(items):
        if not isinstance(item, Mapping):
            raise AssetSpecError(f"vessels[{i}]", "must be a mapping")
        name = item.get("name")
        if not isinstance(name, str):
            raise AssetSpecError(f"vessels[{i}].name", "is required (a string)")
        if name in out:
            raise AssetSpecError(f"vessels[{i}].name", f"duplicate asset name {name!r} in {source}")
        out[name] = item
    return out


def asset_names() -> list[str]:
    """Names of all assets (built-in and registered), sorted. Builds nothing."""
    with _lock:
        return sorted(set(_builtin_entries()) | set(_user))


class AssetNameError(ConfigError, ValueError):  # type: ignore[misc,unused-ignore]
    """:func:`known_asset` refused a name: a :class:`mmusv.ConfigError`, and the ``ValueError`` schema validators
    take."""


def known_asset(name: str) -> str:
    """``name`` when the library has an asset of that name; else an :class:`AssetNameError` (a ``ConfigError`` and,
    for schema validators, a ``ValueError``) naming up to three close matches and the command that lists them all.
    Builds nothing."""
    if not isinstance(name, str):
        raise AssetNameError(f"an asset name is a string, not {type(name).__name__} (`mmusv assets` lists them)")
    names = asset_names()
    if name not in names:
        close = difflib.get_close_matches(name, names, n=3, cutoff=0.5)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise AssetNameError(
            f"unknown asset{hint} (`mmusv assets` lists all {len(names)}; a vessel of your own: list its asset file "
            "under the scenario's `assets:`, docs/assets.md)"
        )
    return name


def get_asset(name: str) -> VesselAsset:
    """The asset called ``name`` (built on first use, then cached).

    Raises :class:`UnknownAssetError` (a ``KeyError``) listing close matches when no asset has that name, and
    :class:`~mmusv.errors.ConfigError` when ``name`` is not a string.
    """
    if not isinstance(name, str):
        raise ConfigError(
            f"asset name = {name!r:.60}: must be a string, not {type(name).__name__} "
            "(mmusv.world.vessels.asset_names() lists the assets)"
        )
    with _lock:
        if name in _user:
            return _user[name]
        if name in _built:
            return _built[name]
        entries = _builtin_entries()
        if name in entries:
            asset = _build_entry(entries[name], base_dir=None, source="builtin", builtin=True)
            _built[name] = asset
            return asset
    raise UnknownAssetError(name, asset_names())


def library(*, category: str | None = None, semantic_class: SemanticClass | int | None = None) -> list[VesselAsset]:
    """All assets sorted by name, optionally only one ``category`` (one of :func:`categories`) and/or
    ``semantic_class`` (a :class:`~mmusv.classes.SemanticClass` or its id). Builds them all. An unknown category or
    class is a :class:`~mmusv.errors.ConfigError` naming the valid ones (not an empty list)."""
    if category is not None and category not in categories():
        raise ConfigError(f"category = {category!r:.60}: unknown; the categories are {', '.join(categories())}")
    if semantic_class is not None:
        try:
            if isinstance(semantic_class, (bool, np.bool_)):
                raise ValueError(semantic_class)
            semantic_class = SemanticClass(semantic_class)
        except ValueError:
            known = ", ".join(f"{c.value} ({c.name.lower()})" for c in SemanticClass)
            raise ConfigError(
                f"semantic_class = {semantic_class!r:.60}: not a semantic class; the classes are {known}"
            ) from None
    assets = [get_asset(n) for n in asset_names()]
    if category is not None:
        assets = [a for a in assets if a.category == category]
    if semantic_class is not None:
        assets = [a for a in assets if a.semantic_class == SemanticClass(semantic_class)]
    return assets


def categories() -> list[str]:
    """Sorted distinct categories of all assets."""
    with _lock:
        cats = {str(e.get("category", "")) for e in _builtin_entries().values()} | {a.category for a in _user.values()}
    return sorted(cats)


def register_asset(asset: VesselAsset) -> VesselAsset:
    """Adds ``asset`` to this process's library and returns it; a name already taken raises :class:`AssetSpecError`."""
    if not isinstance(asset, VesselAsset):
        raise ConfigError(
            f"register_asset() takes a VesselAsset (load_asset_file(...) builds one), got {type(asset).__name__}"
        )
    with _lock:
        if asset.name in _builtin_entries():
            raise AssetSpecError("name", f"{asset.name!r} is a built-in asset; choose another name")
        if asset.name in _user:
            raise AssetSpecError("name", f"an asset named {asset.name!r} is already registered")
        _user[asset.name] = asset
    return asset


def unregister_asset(name: str) -> None:
    """Removes a registered user asset (built-ins cannot be removed)."""
    if not isinstance(name, str):
        raise ConfigError(f"asset name = {name!r:.60}: must be a string, not {type(name).__name__}")
    with _lock:
        if name in _user:
            del _user[name]
            return
        if name in _builtin_entries():
            raise AssetSpecError("name", f"{name!r} is a built-in asset and cannot be unregistered")
    raise UnknownAssetError(name, asset_names())


# ------------------------------------------------------------------------------------------- user assets


def _build_entry(entry: object, *, base_dir: Path | None, source: str, builtin: bool = False) -> VesselAsset:
    name_guess = entry.get("name") if isinstance(entry, Mapping) else None
    path = name_guess if isinstance(name_guess, str) and NAME_PATTERN.match(name_guess) else ""
    spec = parse_asset(entry, path=path)
    cls = spec.semantic_class
    mounts = {k: MountPoint(_triple(m.xyz), _triple(m.rpy_deg)) for k, m in spec.mounts.items()}
    part_types: tuple[str, ...] = ()
    if isinstance(spec, ProceduralAssetSpec):
        mesh = build_procedural(hull=spec.hull, parts=spec.parts, path=path, cls=int(cls))
        part_types = tuple(p.type for p in spec.parts)
    else:
        if builtin:
            raise AssetSpecError(join(path, "mesh"), "built-in assets are procedural")
        mesh = mesh_asset(spec, path=path, base_dir=base_dir, cls=int(cls))
    b = mesh.bounds
    shift = np.array([(b[0, 0] + b[1, 0]) / 2.0, (b[0, 1] + b[1, 1]) / 2.0, 0.0])
    if np.any(np.abs(shift) > 1e-9 * max(1.0, float((b[1] - b[0]).max()))):
        mesh = TriMesh(mesh.vertices - shift, mesh.faces, mesh.classes, mesh.materials)
        if isinstance(spec, ProceduralAssetSpec):
            mounts = {
                k: MountPoint((m.xyz[0] - shift[0], m.xyz[1] - shift[1], m.xyz[2]), m.rpy_deg)
                for k, m in mounts.items()
            }
    return VesselAsset(
        name=spec.name,
        category=spec.category,
        semantic_class=cls,
        mesh=mesh,
        mounts=mounts,
        description=spec.description,
        source=source,
        parts=part_types,
    )


def _triple(v: tuple[float, ...]) -> tuple[float, float, float]:
    return (v[0], v[1], v[2])


def load_asset_file(
    entry: Mapping[str, Any] | str | os.PathLike[str],
    *,
    base_dir: str | os.PathLike[str] | None = None,
    register: bool = False,
) -> VesselAsset:
    """Builds one user asset from a mapping or a YAML file holding one mapping.

    Mesh entry keys: ``name`` (required), ``category`` ("custom"), ``description``, ``semantic_class``
    (``vessel`` | ``usv``), ``mesh`` (path, OBJ/STL/PLY/OFF/GLB/glTF/... read with trimesh by
    :mod:`mmusv.world.mesh_files`; relative to the YAML file's folder, or ``base_dir``/cwd for a mapping), ``scale``
    (file units -> metres, 1.0), ``up_axis`` and ``forward_axis`` (the up and bow directions in the file, any of
    ±x/±y/±z, perpendicular; when neither is given, the format's convention: ``y`` up and ``z`` forward for a
    ``.gltf``/``.glb`` file as glTF 2.0 defines, ``z`` up and ``x`` forward for the rest; when one is given, the
    other defaults to ``z`` / ``x`` for every format; a mesh that comes out wider than long under a defaulted axis
    gets a :class:`~mmusv.scenario_checks.MmusvWarning`), ``waterline_z`` (waterline height along ``up_axis`` in
    file units, 0.0) or ``draft`` (metres above the lowest point), ``mounts`` (``{name: {xyz, rpy_deg}}`` in the
    asset frame).
    A procedural entry gives ``hull`` and ``parts`` instead of ``mesh`` (see :mod:`mmusv.world.asset_spec`).

    The mesh is rotated to the body frame, scaled, shifted so the waterline is z = 0 and re-centred in x/y;
    dimensions come from its bounding box. Raises :class:`AssetSpecError` (a ``ValueError``) naming the field.
    ``register=True`` also adds it with :func:`register_asset`.
    """
    if isinstance(entry, Mapping):
        data: object = entry
        base = Path(base_dir) if base_dir is not None else None
        source = "<mapping>"
    else:
        path = _asset_path(entry, "entry")
        data = _read_yaml(path)
        if not isinstance(data, Mapping) or "vessels" in data:
            raise AssetSpecError(
                "file", f"{str(path)!r} must hold one asset mapping; use load_asset_catalog() for a list of assets"
            )
        base = Path(base_dir) if base_dir is not None else path.parent
        source = str(path)
    asset = _build_entry(data, base_dir=base, source=source)
    return register_asset(asset) if register else asset


def load_asset_catalog(path: str | os.PathLike[str], *, register: bool = False) -> list[VesselAsset]:
    """Builds every asset of a YAML file holding a list of entries (or ``{vessels: [...]}``), in file order.

    Entries are those of :func:`load_asset_file`; relative mesh paths are relative to the file's folder.
    """
    p = _asset_path(path, "path")
    entries = _index_entries(_read_yaml(p), source=str(p))
    assets = [_build_entry(e, base_dir=p.parent, source=str(p)) for e in entries.values()]
    if register:
        for a in assets:
            register_asset(a)
    return assets


def _asset_path(value: object, name: str) -> Path:
    """An asset file argument as a path (``~`` expanded), else an :class:`AssetSpecError` naming ``name``."""
    if isinstance(value, bytes) or not isinstance(value, (str, os.PathLike)) or not os.fspath(value):
        raise AssetSpecError(
            name, f"must be a YAML file path (str or pathlib.Path) or an asset mapping, got {value!r:.60}"
        )
    return Path(os.fspath(value)).expanduser()


def _read_yaml(path: Path) -> object:
    if not path.is_file():
        what = "is a folder, not an asset file" if path.is_dir() else "does not exist"
        raise AssetSpecError("file", f"asset file {str(path)!r} {what}")
    try:
        return read_yaml(path, kind="asset")
    except ConfigError as exc:
        raise AssetSpecError("file", str(exc)) from None
