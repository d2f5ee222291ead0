"""The schema of a vessel asset entry: frozen pydantic models, and their errors as :class:`AssetSpecError`.

An entry (one item of ``vessel_catalog.yaml``, or a user's YAML/mapping) is either a **mesh asset** (``mesh``: a
file read by :mod:`mmusv.world.vessels`) or a **procedural asset** (``hull`` and ``parts``, built by
:mod:`mmusv.world.vessel_shapes`). Every number is in metres (angles in degrees where the key ends in ``_deg``), in
the vessel body frame: x forward (bow at +x), y left, z up, z = 0 at the waterline, x measured from midship. A key
set to ``null`` counts as not given. Checks that need the hull's shape (a part's base on the deck, ``fit``, the
footprint) belong to the mesh builder; everything a part can say about itself is checked here.

Hull keys (``type: mono | twin``)::

    length, beam, draft, depth        overall length, beam, hull draft, keel-to-deck depth at midship
    demi_beam                         twin only: beam of each of the two demihulls
    bow=0.2, stern=0.1                fractions of the length over which the hull tapers at bow / stern
    bow_shape=pointed|round           plan form of the bow taper; bow_power=2.0 is its fullness (>= 1)
    bow_width=0                       half-width left at the stem (1 = square barge bow; needs bow=0)
    transom=0.9                       half-width fraction at the transom (must be 1 when stern=0)
    sheer=0                           deck rise at the stem above the midship deck, rising quadratically
    rake=0.05, overhang=0.0           fractions of length by which the keel is shorter at bow / stern
    bottom=0.8, flare=1.0             half-width fraction at the keel / at the waterline (deck is 1)
    bulb=0                            mono only: width of a bulbous bow as a fraction of the beam (0 = none)
    topside=hull_black, deck=deck_steel   materials (mmusv.world.materials) of the topsides and the deck;
                                      below them the boot-top band and antifouling red

Part types (:mod:`mmusv.world.part_spec`; each ``{type: ..., ...}``; ``base`` defaults to the deck height at the
part's x; vertical extent is ``top`` (absolute z) or ``height`` (above ``base``); ``fit: m`` narrows a part so it
stays ``m`` metres inside the deck outline; every part takes ``material`` (a name of
:mod:`mmusv.world.materials`, default per type: :data:`mmusv.world.part_spec.DEFAULT_MATERIALS`))::

    box        x, y=0, size [lx, ly], base, top|height, taper=1, yaw_deg=0, fit, windows [w, h, pitch]
    house      x, y=0, align=center|aft|fore, base, tiers [[lx, ly, h(, dx)], ...], taper=1, fit,
               wings [lx, ly] (bridge wings beside the top tier), windows [w, h, pitch] (a band on every tier)
    hull_block x0, x1, inset=0, base, top|height, taper=1          (a block following the deck outline)
    row        x0, x1, count, gap=0, y=0, width, heights [h, ...] (cycled), base, fit  (hatches, stacks)
    funnel     x, y=0, size [lx, ly], base, top|height, shape=box|round, taper=0.9
    mast       x, y=0, base, top|height, width=0.3, yard=0, yard_at=0.8
    cylinder   x, y=0, radius, base, top|height, top_radius, segments=12
    hcylinder  x0, x1, y=0, z, radius, segments=12                 (axis along x)
    dome       x, y=0, radius, top, base, segments=16              (sphere cap on a skirt)
    strut      from [x, y, z], to [x, y, z], width, thickness=width (absolute coordinates)
    plate      y=0, thickness, points [[x, z], ...] (convex profile extruded across y)
    gantry     x, span, base, top|height, leg=0.5, lean=0           (A-frame / portal)
    crane      x, y=0, base, pedestal [radius, height], jib [length, elevation_deg, yaw_deg], width=0.6
    gun        x, y=0, base, radius, height, barrel, yaw_deg=0, elevation_deg=5
    railing    x0, x1 (default: the whole hull), side=both|port|starboard, inset=0.1, height=1, spacing=1.5,
               rails=2, base, bow=false, stern=false, radius, posts=true, lift=0; or width (+ y, x0, x1, base):
               round a rectangle
    windows    x0, x1, z, width, height, pitch, rows=1, row_pitch=2.8, side, y | inset (wall=outline|hull),
               shape=rect|round
    containers x0, x1, bays, rows, tiers [n, ...] (cycled), width, base, gap=0.6, height=2.59, seed=0, fit
    hatches    x0, x1, count, gap=0, width, height, base, fit, ribs=6
    lifeboats  x, y, z (keel), length, count=1, pitch=0, side, kind=davit|freefall
    fenders    x0, x1, count, z, radius, side, kind=tyre|cylinder
    nav_lights masthead [[x, y, z], ...] ([] for none), sides [x, |y|, z], stern [x, y, z] (each defaults from
               the masts, bridge wings, bow and transom), size=0.3
    radar      x, y=0, base, length=2, yaw_deg=0
    antennas   at [[x, y, z, height], ...], radius=0.03
    bollards   x0, x1, count, inset=0.8, radius=0.2, side
    tube       from [x, y, z], to [x, y, z], radius, end_radius, segments=12
    pipes      x0, x1, ys [y, ...], z, radius=0.2, support=6, base
    winch      x, y=0, base, radius, width

Mesh asset keys: ``mesh`` (file path), ``scale=1``, ``up_axis``, ``forward_axis`` (any of ±x/±y/±z; when neither
is given, the file format's convention: ``y`` up and ``z`` forward for ``.gltf``/``.glb`` as glTF 2.0 defines,
:data:`FORMAT_AXES`, else ``z`` up and ``x`` forward, :data:`DEFAULT_AXES`, which also fills in the one left out when
only one is given), ``waterline_z`` or ``draft``. Both kinds: ``name``, ``category=custom``, ``description``,
``semantic_class=vessel`` (``vessel`` | ``usv``), ``mounts`` (``{name: {xyz, rpy_deg=[0, 0, 0]}}``).

:func:`parse_asset` validates an entry; errors are one :class:`AssetSpecError` whose ``field`` is the dotted path
of the first problem (``tug_32m.hull.beam``, ``tug_32m.parts[3].top``) and whose message says what is allowed.
Bounds (so that every accepted entry builds real faces in seconds): hull ``draft``, freeboard and ``demi_beam`` at
least :data:`HULL_MIN_SIZE`, a non-zero ``bow``/``stern`` taper at least :data:`MIN_TAPER`, at most
:data:`MAX_PARTS` parts; part sizes at least 1 mm and coordinates within ±500 m, lists of at most 200 items and
counts of at most 20,000 pieces (:mod:`mmusv.world.part_spec`); the built vessel at most 500 m tall.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import PurePath
from typing import Annotated, Literal

from pydantic import BaseModel, BeforeValidator, Field, ValidationError, model_validator

from mmusv.classes import SemanticClass
from mmusv.errors import ConfigError
from mmusv.validation import (
    Fraction,
    Number,
    Positive,
    Spec,
    Text,
    Vec3,
    describe,
    invalid,
    invalid_field,
    join,
    sequence,
)
from mmusv.world.part_spec import MaterialName, PartSpec

__all__ = [
    "AXES",
    "DEFAULT_AXES",
    "DIMENSION_RANGES",
    "FORMAT_AXES",
    "HULL_MIN_SIZE",
    "MAX_PARTS",
    "MIN_TAPER",
    "MOUNT_REACH",
    "NAME_PATTERN",
    "AssetSpec",
    "AssetSpecError",
    "HullSpec",
    "MeshAssetSpec",
    "MountSpec",
    "ProceduralAssetSpec",
    "dimension_problem",
    "mount_reach",
    "parse_asset",
    "spec_error",
]


class AssetSpecError(ConfigError, ValueError):
    """A vessel asset entry is invalid (a :class:`mmusv.ConfigError`, and a ``ValueError`` as before).

    ``field`` is the dotted path of the offending key (``tug_32m.hull.beam``), ``reason`` what is wrong with it.
    """

    def __init__(self, field: str, message: str) -> None:
        super().__init__(f"{field}: {message}")
        self.field = field
        self.reason = message

    def __reduce__(self) -> tuple[type[AssetSpecError], tuple[str, str]]:
        return (type(self), (self.field, self.reason))


NAME_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.\-]*$")
"""What an asset name may be: letters, digits, ``_``, ``-`` and ``.``, starting with a letter or digit."""

AXES: dict[str, tuple[float, float, float]] = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
"""The axis letters of a mesh file's ``up_axis`` / ``forward_axis`` (optionally with a sign) as unit vectors."""

DEFAULT_AXES: tuple[str, str] = ("z", "x")
"""``(up_axis, forward_axis)`` of a mesh file whose format has no convention of its own (OBJ, STL, PLY, OFF) when the
entry gives neither; for every format, the default of the one axis an entry leaves out when it gives the other."""

FORMAT_AXES: dict[str, tuple[str, str]] = {".gltf": ("y", "z"), ".glb": ("y", "z")}
"""``(up_axis, forward_axis)`` by file extension, for formats that define their axes, when the entry gives neither:
glTF 2.0 (section 3.4, "Coordinate System and Units") is +Y up, metres, and an asset's front faces +Z (Blender's
glTF export writes it so). Until this table existed every format defaulted to :data:`DEFAULT_AXES`: a glTF/GLB file
written z-up needs ``up_axis: z, forward_axis: x`` in its entry now."""


DIMENSION_RANGES: dict[str, tuple[float, float]] = {
    "length": (0.5, 500.0),
    "beam": (0.1, 500.0),
    "height": (0.1, 500.0),
}
"""The allowed bounding-box size of an asset in metres, ``(min, max)`` per dimension (the built-in catalogue spans
3-330 m in length, 0.65-60 m in beam and 1.1-73 m in height)."""

HULL_MIN_SIZE = 0.01
"""The smallest ``draft``, freeboard (``depth - draft``) and ``demi_beam`` of a hull, metres (thinner would give
near-zero-area faces)."""

MIN_TAPER = 0.01
"""The smallest non-zero ``bow`` / ``stern`` taper fraction of a hull."""

MAX_PARTS = 1000
"""The most parts a procedural asset may have (the built-in catalogue uses at most a few dozen)."""

MOUNT_REACH: tuple[float, float] = (2.0, 50.0)
"""A mount may lie at most ``max(MOUNT_REACH[0] * length, MOUNT_REACH[1])`` metres outside the asset's bounding box."""


def dimension_problem(*, length: float, beam: float, height: float) -> str | None:
    """What is wrong with an asset of this bounding-box size (metres), or ``None`` when every dimension lies in
    :data:`DIMENSION_RANGES`; non-finite sizes are always wrong."""
    size = {"length": length, "beam": beam, "height": height}
    bad = [k for k, v in size.items() if not DIMENSION_RANGES[k][0] <= v <= DIMENSION_RANGES[k][1]]
    if not bad:
        return None
    got = " x ".join(f"{size[k]:.6g}" for k in size)
    allowed = ", ".join(f"{k} {lo:g}..{hi:g} m" for k, (lo, hi) in DIMENSION_RANGES.items())
    return f"gives {', '.join(bad)} out of range: length x beam x height = {got} m; allowed: {allowed}"


def mount_reach(length: float) -> float:
    """How far (metres) a mount may lie outside the bounding box of an asset ``length`` metres long."""
    return max(MOUNT_REACH[0] * length, MOUNT_REACH[1])


def _axis_name(value: object) -> str:
    s = value.strip().lower() if isinstance(value, str) else ""
    letter = s.lstrip("+-")
    if letter not in AXES or len(s) - len(letter) > 1:
        raise invalid(f"must be one of x, y, z, -x, -y, -z; got {value!r}")
    return ("-" if s.startswith("-") else "") + letter


def _semantic_class(value: object) -> SemanticClass:
    cls: SemanticClass | None = None
    try:
        if isinstance(value, str):
            cls = SemanticClass[value.upper()]
        elif isinstance(value, int) and not isinstance(value, bool):
            cls = SemanticClass(value)
    except (KeyError, ValueError):
        cls = None
    if cls not in (SemanticClass.VESSEL, SemanticClass.USV):
        raise invalid(f"must be 'vessel' or 'usv', got {value!r}")
    assert cls is not None
    return cls


def _asset_name(value: object) -> object:
    if isinstance(value, str) and value and not NAME_PATTERN.match(value):
        raise invalid(f"must be letters, digits, '_', '-' or '.', got {value!r}")
    return value


Axis = Annotated[str, BeforeValidator(_axis_name)]
"""A body axis of a mesh file, normalised to ``x``, ``y``, ``z``, ``-x``, ``-y`` or ``-z``."""


# ------------------------------------------------------------------------------------------------------ hull


class HullSpec(Spec):
    """The hull of a procedural asset (module docstring); lengths in metres, the rest dimensionless."""

    type: Literal["mono", "twin"] = "mono"
    length: Annotated[Number, Field(ge=DIMENSION_RANGES["length"][0], le=DIMENSION_RANGES["length"][1])]
    beam: Annotated[Number, Field(ge=DIMENSION_RANGES["beam"][0], le=DIMENSION_RANGES["beam"][1])]
    draft: Annotated[Number, Field(ge=HULL_MIN_SIZE, le=DIMENSION_RANGES["height"][1])]
    depth: Annotated[Number, Field(ge=HULL_MIN_SIZE, le=DIMENSION_RANGES["height"][1])]
    """Keel-to-deck depth at midship; at least ``draft + HULL_MIN_SIZE``."""
    demi_beam: Annotated[Number, Field(ge=HULL_MIN_SIZE, le=DIMENSION_RANGES["beam"][1])] | None = None
    """Twin hulls only (required there): beam of each demihull, less than ``beam / 2``."""
    bow: Annotated[Number, Field(ge=0.0, le=0.95)] = 0.2
    stern: Annotated[Number, Field(ge=0.0, le=0.95)] = 0.1
    """Taper fractions; ``bow + stern <= 1``."""
    bow_width: Fraction | None = None
    """Half-width fraction left at the stem; default 0 with a bow taper, and it must be 1 without one."""
    transom: Annotated[Number, Field(ge=0.02, le=1.0)] | None = None
    """Half-width fraction at the transom; default 0.9 with a stern taper, and it must be 1 without one."""
    rake: Annotated[Number, Field(ge=0.0, le=0.45)] = 0.05
    overhang: Annotated[Number, Field(ge=0.0, le=0.45)] = 0.0
    bow_power: Annotated[Number, Field(ge=1.0, le=8.0)] = 2.0
    bow_shape: Literal["pointed", "round"] = "pointed"
    sheer: Annotated[Number, Field(ge=0.0, le=DIMENSION_RANGES["height"][1])] = 0.0
    bottom: Annotated[Number, Field(ge=0.02, le=1.0)] = 0.8
    flare: Annotated[Number, Field(ge=0.02, le=1.0)] = 1.0
    bulb: Annotated[Number, Field(ge=0.0, le=0.5)] = 0.0
    """Mono hulls: bulbous bow width as a fraction of the beam (0 = no bulb)."""
    topside: MaterialName = "hull_black"
    deck: MaterialName = "deck_steel"

    @model_validator(mode="after")
    def _consistent(self) -> HullSpec:
        if self.depth < self.draft + HULL_MIN_SIZE:
            raise invalid_field(
                "depth", f"must be >= draft + {HULL_MIN_SIZE:g} ({self.draft + HULL_MIN_SIZE:g}), got {self.depth}"
            )
        for key in ("bow", "stern"):
            if 0.0 < getattr(self, key) < MIN_TAPER:
                raise invalid_field(key, f"must be 0 (no taper) or {MIN_TAPER:g} to 0.95, got {getattr(self, key)}")
        if self.type == "twin" and self.demi_beam is None:
            raise invalid_field("demi_beam", "is required for a twin hull")
        if self.type == "mono" and self.demi_beam is not None:
            raise invalid_field("demi_beam", "is for twin hulls only (type: twin)")
        if self.demi_beam is not None and self.demi_beam > self.beam / 2.0:
            raise invalid_field("demi_beam", f"must be <= beam / 2 ({self.beam / 2.0}), got {self.demi_beam}")
        if self.bow + self.stern > 1.0:
            raise invalid_field("stern", f"bow + stern must be <= 1, got {self.bow} + {self.stern}")
        if self.bow == 0 and self.bow_width not in (None, 1.0):
            raise invalid_field("bow_width", "must be 1 when bow is 0 (no taper)")
        if self.bulb > 0 and self.type == "twin":
            raise invalid_field("bulb", "is for mono hulls only")
        if self.stern == 0 and self.transom not in (None, 1.0):
            raise invalid_field("transom", "must be 1 when stern is 0 (no taper)")
        return self

    @property
    def freeboard(self) -> float:
        """Deck height above the waterline at midship, metres."""
        return self.depth - self.draft

    @property
    def demi_width(self) -> float:
        """The beam of one demihull (twin), or the beam (mono), metres."""
        return self.beam if self.demi_beam is None else self.demi_beam

    @property
    def stem_width(self) -> float:
        """``bow_width`` with its default resolved."""
        if self.bow_width is not None:
            return self.bow_width
        return 0.0 if self.bow > 0 else 1.0

    @property
    def transom_width(self) -> float:
        """``transom`` with its default resolved."""
        if self.transom is not None:
            return self.transom
        return 0.9 if self.stern > 0 else 1.0


# ---------------------------------------------------------------------------------------------------- entries


class MountSpec(Spec):
    """A sensor mount in the body frame: ``xyz`` metres and ``rpy_deg`` roll/pitch/yaw degrees."""

    xyz: Vec3
    rpy_deg: Vec3 = (0.0, 0.0, 0.0)


class _AssetSpec(Spec):
    """What every asset entry says about itself."""

    name: Annotated[Text, BeforeValidator(_asset_name)]
    category: Text = "custom"
    description: Annotated[str, BeforeValidator(str)] = ""
    semantic_class: Annotated[SemanticClass, BeforeValidator(_semantic_class)] = SemanticClass.VESSEL
    mounts: dict[Annotated[str, BeforeValidator(str)], MountSpec] = Field(default_factory=dict)


class MeshAssetSpec(_AssetSpec):
    """An asset whose mesh is read from a file and turned into the body frame."""

    mesh: Text
    """The mesh file (OBJ/STL/PLY/GLB/... read with trimesh); relative to the YAML file's folder."""
    scale: Positive = 1.0
    """File units -> metres."""
    up_axis: Axis | None = None
    """The up direction in the file. Not given: ``y`` for ``.gltf``/``.glb`` when ``forward_axis`` is not given either
    (:data:`FORMAT_AXES`, glTF's convention), else ``z`` (:data:`DEFAULT_AXES`)."""
    forward_axis: Axis | None = None
    """The bow direction in the file, perpendicular to ``up_axis``. Not given: ``z`` for ``.gltf``/``.glb`` when
    ``up_axis`` is not given either (:data:`FORMAT_AXES`), else ``x`` (:data:`DEFAULT_AXES`)."""
    waterline_z: Number | None = None
    """Waterline height along ``up_axis`` in file units (default 0); or give ``draft``."""
    draft: Positive | None = None
    """Metres of the mesh below the waterline, measured from its lowest point."""

    @model_validator(mode="after")
    def _consistent(self) -> MeshAssetSpec:
        if self.up_axis is not None or self.forward_axis is not None:
            up, fwd = self.axes("")
            if up[-1] == fwd[-1]:
                if self.forward_axis is None:  # the default filled in: say so, and which key to give
                    raise invalid_field(
                        "forward_axis",
                        f"is not given, so it is {fwd} (the default), which is not perpendicular to up_axis {up}; "
                        "give forward_axis (the bow's direction in the file)",
                    )
                if self.up_axis is None:
                    raise invalid_field(
                        "up_axis",
                        f"is not given, so it is {up} (the default), which is not perpendicular to forward_axis "
                        f"{fwd}; give up_axis (the up direction in the file)",
                    )
                raise invalid_field("forward_axis", "must be perpendicular to up_axis")
        if self.waterline_z is not None and self.draft is not None:
            raise invalid_field("draft", "give either waterline_z or draft, not both")
        return self

    def axes(self, mesh_path: str) -> tuple[str, str]:
        """``(up_axis, forward_axis)`` for the mesh file ``mesh_path``: the entry's; its file format's when it gives
        neither (:data:`FORMAT_AXES`, else :data:`DEFAULT_AXES`); the one it leaves out from :data:`DEFAULT_AXES`."""
        if self.up_axis is None and self.forward_axis is None:
            return FORMAT_AXES.get(PurePath(mesh_path).suffix.lower(), DEFAULT_AXES)
        return (self.up_axis or DEFAULT_AXES[0], self.forward_axis or DEFAULT_AXES[1])


class ProceduralAssetSpec(_AssetSpec):
    """An asset built from a hull and superstructure parts (module docstring)."""

    hull: HullSpec
    parts: Annotated[tuple[PartSpec, ...], sequence(0, MAX_PARTS, f"a list of at most {MAX_PARTS} parts")] = ()


AssetSpec = MeshAssetSpec | ProceduralAssetSpec
"""One asset entry: a mesh file or a procedural hull with parts."""


def parse_asset(data: object, *, path: str) -> AssetSpec:
    """Validates one asset entry; ``path`` (the asset's name, or ``""``) starts the field paths of errors.

    An entry with ``hull`` is procedural, one with ``mesh`` a mesh asset; giving both or neither is an error at
    ``<path>.mesh``. Raises :class:`AssetSpecError` naming the first invalid key and what is allowed there.
    """
    if not isinstance(data, Mapping):
        raise AssetSpecError(path or "entry", f"must be a mapping, got {type(data).__name__}")
    given = {k for k in ("mesh", "hull") if data.get(k) is not None}
    if len(given) != 1:
        raise AssetSpecError(join(path, "mesh"), "give exactly one of 'mesh' (a mesh file) or 'hull' (procedural)")
    model: type[MeshAssetSpec] | type[ProceduralAssetSpec] = MeshAssetSpec if "mesh" in given else ProceduralAssetSpec
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        raise spec_error(exc, model=model, path=path) from None


def spec_error(err: ValidationError, *, model: type[BaseModel], path: str) -> AssetSpecError:
    """``err`` (from validating ``model``) as one :class:`AssetSpecError`: the first problem's dotted path below
    ``path`` is its ``field``; its message lists every problem with what is allowed there."""
    problems = [describe(e, model, path) for e in err.errors()]
    (field, first), rest = problems[0], problems[1:]
    return AssetSpecError(field, "; ".join([first, *(f"{f}: {m}" for f, m in rest)]))
