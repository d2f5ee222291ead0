"""Procedural maps (island, open sea, port) with map priors for scenario generation.

``generate_map("port", seed=3, extent_m=2000)`` returns a :class:`MapWorld`: static meshes (terrain heightfield,
water surface, port structures, buoys), berths for moored ships as ``(asset_name, (x, y, yaw))`` to be
instantiated from the vessel library, and :class:`~mmusv.world.priors.MapPriors`.

Frame and units: world frame, x east, y north, z up, metres, radians; the water surface is z = 0 and the map
is the square ``[-extent_m/2, extent_m/2]^2`` centred at the origin (the water mesh alone reaches beyond it, the sea
going on past the map: :data:`WATER_REACH_M`). A moored ship's ``(x, y)`` is its hull
centre on the water surface and ``yaw`` the heading of its bow (body x axis) from +x, counter-clockwise.

Determinism: every random draw comes from ``numpy.random.default_rng(seed)`` in a fixed order, so the same
kind, seed and parameters give bitwise-identical arrays.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np
import shapely
from pydantic import BaseModel
from shapely.geometry import Polygon
from shapely.geometry.base import BaseGeometry

from mmusv.classes import SemanticClass
from mmusv.world.map_params import (
    MAP_KINDS,
    IslandParams,
    MapConfigError,
    MapParams,
    OpenSeaParams,
    PortParams,
    make_params,
    resolved,
)
from mmusv.world.port import buoy_mesh, plan_port, port_structures, port_terrain
from mmusv.world.primitives import TriMesh, merge, transformed
from mmusv.world.priors import MapPriors, build_priors
from mmusv.world.terrain import FaceClassifier, FractalNoise, Heightfield, IslandSpec, fbm, island_heights

__all__ = [
    "MAP_KINDS",
    "TERRAIN_MESH_MIN_Z",
    "WATER_REACH_M",
    "IslandParams",
    "MapConfigError",
    "MapParams",
    "MapPriors",
    "MapWorld",
    "OpenSeaParams",
    "PortParams",
    "generate_island",
    "generate_map",
    "generate_map_from",
    "generate_open_sea",
    "generate_port",
    "island_fit_problem",
    "make_params",
]

TERRAIN_MESH_MIN_Z = -2.0
"""Terrain cells whose four vertices are all at or below this height (m) are left out of the terrain mesh."""

WATER_REACH_M = 1.0e6
"""How far (metres) the water mesh reaches beyond the map's edge: the longest range any sensor takes (a camera's
``range_m`` bound, :class:`mmusv.sensors.config.CameraConfig`), so that a ray leaving the map downwards meets the sea
within its range, as the LiDAR's water returns and the cameras' and top view's shading need it to (a flat sea,
``environment.motion: paper``, ended at the map's edge: the top view drew the sky's grey beyond it, under labels that
said water, and the LiDAR had no water returns there)."""


# ---------------------------------------------------------------------------------------------- the world


@dataclass(frozen=True, eq=False)
class MapWorld:
    """One generated map.

    Attributes:
        kind: ``"island"``, ``"open_sea"`` or ``"port"``.
        seed: the generation seed.
        params: the validated parameters (a pydantic model of :mod:`mmusv.world.map_params`).
        static_meshes: name -> TriMesh in the world frame (metres), keys sorted; a subset of ``"buoys"``,
            ``"port_structures"``, ``"terrain"``, ``"water"`` (empty parts are left out; ``"water"`` always there,
            reaching :data:`WATER_REACH_M` beyond the map's square, every other mesh inside it).
        moored: ships to instantiate from the vessel library: ``(asset_name, (x, y, yaw))``, world metres and
            radians (see module docstring).
        priors: the map priors.
        heightfield: the terrain heightfield the terrain mesh was built from (exact heights via ``sample``).
    """

    kind: str
    seed: int
    params: MapParams
    static_meshes: dict[str, TriMesh]
    moored: list[tuple[str, tuple[float, float, float]]]
    priors: MapPriors
    heightfield: Heightfield

    @property
    def num_triangles(self) -> int:
        """Total triangles over the static meshes."""
        return sum(m.num_triangles for m in self.static_meshes.values())

    def merged_mesh(self) -> TriMesh:
        """All static meshes merged into one (in key order)."""
        return merge(list(self.static_meshes.values()))


def _grid(extent: float, target: float) -> tuple[float, np.ndarray]:
    n = max(round(extent / target), 1)
    s = extent / n
    return s, -extent / 2.0 + np.arange(n + 1) * s


def _water(extent: float, tiles: int = 4) -> TriMesh:
    """Water surface (class WATER) at z = 0, normals up: ``tiles x tiles`` quads over the map's square, then square
    rings of 8 quads around it, each ring reaching twice as far from the centre as the one inside it, out to
    :data:`WATER_REACH_M` beyond the map's edge (the sea goes on past the map, as sensors see it from near the edge).
    Triangles near any point are about as large as the point is far from the centre, so a hit on them is as precise
    (in float32) as the point's own coordinates allow; the map's own tiles are those it always had."""
    half = extent / 2.0
    xs = np.linspace(-half, half, tiles + 1)
    gx, gy = np.meshgrid(xs, xs)
    verts = [np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])]
    i, j = np.meshgrid(np.arange(tiles), np.arange(tiles), indexing="ij")
    v00 = (i * (tiles + 1) + j).ravel()
    faces = [
        np.concatenate(
            [np.column_stack([v00, v00 + 1, v00 + tiles + 2]), np.column_stack([v00, v00 + tiles + 2, v00 + tiles + 1])]
        )
    ]
    # A ring between the squares of half-sides r and R: the 3 x 3 quads of the grid [-R, -r, r, R]^2 less the middle.
    ring = np.array([(a * 4 + b) for a in range(3) for b in range(3) if (a, b) != (1, 1)])
    ring_faces = np.concatenate(
        [np.column_stack([ring, ring + 1, ring + 5]), np.column_stack([ring, ring + 5, ring + 4])]
    )
    n, r, reach = verts[0].shape[0], half, half + WATER_REACH_M
    while r < reach:
        big = min(2.0 * r, reach)
        rx, ry = np.meshgrid(np.array([-big, -r, r, big]), np.array([-big, -r, r, big]))
        verts.append(np.column_stack([rx.ravel(), ry.ravel(), np.zeros(16)]))
        faces.append(ring_faces + n)
        n, r = n + 16, big
    return TriMesh(np.concatenate(verts), np.concatenate(faces), np.array([int(SemanticClass.WATER)]))


def _vegetation(rng: np.random.Generator, extent: float, enabled: bool, min_z: float) -> FaceClassifier:
    """Face classifier: VEGETATION on gentle slopes above ``min_z`` in noise patches, TERRAIN elsewhere."""
    patches = FractalNoise(rng=rng, half_extent_m=extent / 2.0, cell_m=90.0, octaves=3)

    def classify(c: np.ndarray, n: np.ndarray) -> np.ndarray:
        cls = np.full(c.shape[0], int(SemanticClass.TERRAIN), dtype=np.uint16)
        if enabled:
            veg = (c[:, 2] > min_z) & (n[:, 2] > 0.6) & (patches(c[:, 0], c[:, 1]) > -0.35)
            cls[veg] = int(SemanticClass.VEGETATION)
        return cls

    return classify


def _harmonics(rng: np.random.Generator, roughness: float) -> tuple[tuple[float, float, float], ...]:
    return tuple(
        (float(k), float(rng.uniform(0.0, roughness * 0.6) / (k - 1)), float(rng.uniform(0, 2 * np.pi)))
        for k in range(2, 6)
    )


def _free_buoys(
    n: int, *, rng: np.random.Generator, hf: Heightfield, reach: float, avoid: BaseGeometry | None, depth: float
) -> list[np.ndarray]:
    """Up to ``n`` buoy positions in open water within ``[-reach, reach]^2``: terrain below ``-depth`` within
    25 m, 60 m from ``avoid`` (shapely geometry or None) and 80 m from each other."""
    out: list[np.ndarray] = []
    ring = 25.0 * np.column_stack([np.cos(np.arange(8) * np.pi / 4), np.sin(np.arange(8) * np.pi / 4)])
    for _ in range(50 * n):
        if len(out) >= n:
            break
        p = rng.uniform(-reach, reach, size=2)
        pts = np.vstack([p, p + ring])
        z = hf.sample(pts)
        if not np.all(z < -depth):
            continue
        if avoid is not None and shapely.distance(avoid, shapely.Point(p)) < 60.0:
            continue
        if any(np.hypot(*(p - q)) < 80.0 for q in out):
            continue
        out.append(p)
    return out


def _assemble(
    kind: str,
    seed: int,
    params: MapParams,
    *,
    hf: Heightfield,
    classify: FaceClassifier,
    structures: list[TriMesh],
    buoys: list[np.ndarray],
    moored: list[tuple[str, tuple[float, float, float]]],
    moored_fp: list[Polygon],
) -> MapWorld:
    buoy_meshes = [buoy_mesh(float(p[0]), float(p[1])) for p in buoys]
    meshes: dict[str, TriMesh] = {}
    if buoy_meshes:
        meshes["buoys"] = merge(buoy_meshes)
    if structures:
        meshes["port_structures"] = merge(structures)
    terrain = hf.to_mesh(min_z=TERRAIN_MESH_MIN_Z, classify=classify)
    if terrain is not None:
        meshes["terrain"] = terrain
    meshes["water"] = _water(params.extent_m)
    priors = build_priors(
        heightfield=hf,
        structures=structures + buoy_meshes,
        buoys=np.array(buoys).reshape(-1, 2),
        moored_footprints=moored_fp,
        extent_m=params.extent_m,
        resolution_m=params.prior_resolution_m,
        draft_margin_m=params.draft_margin_m,
        clearance_m=params.clearance_m,
        occlusion_height_m=params.occlusion_height_m,
    )
    return MapWorld(
        kind=kind,
        seed=seed,
        params=params,
        static_meshes=dict(sorted(meshes.items())),
        moored=moored,
        priors=priors,
        heightfield=hf,
    )


def _check_params(params: object, model: type[Any], kind: str) -> Any:
    """``params`` when it is ``None`` (the defaults) or an instance of ``model`` (the parameters of a ``kind`` map),
    else a :class:`MapConfigError` saying how to make one."""
    if params is None:
        return model()
    if not isinstance(params, model):
        raise MapConfigError(
            "params",
            params if not isinstance(params, BaseModel) else type(params).__name__,
            f"{model.__name__}, the parameters of the {kind!r} map (make_params({kind!r}, ...)), or None; "
            f"generate_map({kind!r}, seed=..., **values) takes plain values",
        )
    return params


def _check_seed(seed: object) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise MapConfigError("seed", seed, "a non-negative integer")
    return int(seed)


_P = TypeVar("_P", IslandParams, PortParams)


def _place_islands(p: IslandParams, rng: np.random.Generator) -> tuple[list[IslandSpec], int]:
    """The domes of the map's islands and how many islands they make: ``n_islands``, or, left at its default, as
    many as fit up to it (a small map); an ``n_islands`` the parameters set that does not fit is refused."""
    half = p.extent_m / 2.0
    (lo, hi), gap = resolved(p.island_radius_m), resolved(p.min_gap_m)
    radii = np.sort(rng.uniform(lo, hi, size=p.n_islands))[::-1]
    placed: list[tuple[np.ndarray, float]] = []
    specs: list[IslandSpec] = []
    for r0 in radii:
        r = float(r0)
        harm = _harmonics(rng, p.coast_roughness)
        # Radius bound: harmonics at their sum, domain warp (fractal noise rarely past +-0.6) at 0.6 roughness.
        grow = (1.0 + sum(a for _, a, _ in harm)) * (1.0 + 0.6 * p.coast_roughness)
        for attempt in range(1200):
            if attempt and attempt % 200 == 0:
                r = max(0.85 * r, 15.0)
            lim = half - r * grow - min(60.0, 0.1 * half)
            if lim <= 0.0:
                continue
            c = rng.uniform(-lim, lim, size=2)
            if all(np.hypot(*(c - c2)) >= (r + r2) * grow + gap for c2, r2 in placed):
                break
        else:
            if "n_islands" not in p.model_fields_set:
                continue  # the default: as many as fit (a smaller one may yet)
            raise MapConfigError(
                "n_islands",
                p.n_islands,
                f"fewer or smaller islands: with this map seed only {len(placed)} of the {p.n_islands} islands of "
                f"island_radius_m [{lo:g}, {hi:g}] fit in extent_m = {p.extent_m:g} at least min_gap_m = "
                f"{gap:g} apart (lower n_islands or island_radius_m, lower min_gap_m, or raise extent_m)",
            )
        placed.append((c, r))
        peak = min(float(rng.uniform(*p.island_height_m)), 0.35 * r)
        # A main dome and 0-3 lower lobes inside the island's radius make irregular, multi-peaked islands.
        n_lobes = int(rng.integers(0, 4))
        main = r if n_lobes == 0 else 0.72 * r
        specs.append(IslandSpec(center=(float(c[0]), float(c[1])), radius_m=main, peak_m=peak, harmonics=harm))
        for _ in range(n_lobes):
            ang = float(rng.uniform(0.0, 2.0 * np.pi))
            lr = float(rng.uniform(0.3, 0.45)) * r
            off = r - lr
            lc = (float(c[0] + off * np.cos(ang)), float(c[1] + off * np.sin(ang)))
            specs.append(
                IslandSpec(
                    center=lc,
                    radius_m=lr,
                    peak_m=peak * float(rng.uniform(0.3, 0.8)),
                    harmonics=_harmonics(rng, p.coast_roughness),
                )
            )
    return specs, len(placed)


def island_fit_problem(seed: int, params: IslandParams) -> str | None:
    """Why the islands of an ``island`` map of ``seed`` and ``params`` cannot be placed (what is allowed instead),
    or None when they fit. It runs the placement of :func:`generate_island` itself, the first draws of the map's
    random stream, so the answer is the build's for this seed; it builds no terrain (milliseconds), so
    :class:`mmusv.config.MapConfig` refuses such a map when the scenario or spec loads (``map.params.n_islands``)
    rather than when a run builds its world."""
    try:
        _place_islands(params, np.random.default_rng(_check_seed(seed)))
    except MapConfigError as exc:
        return exc.allowed
    return None


def _island_terrain(
    rng: np.random.Generator, xs: np.ndarray, spacing: float, islands: list[IslandSpec], roughness: float, extent: float
) -> Heightfield:
    gx, gy = np.meshgrid(xs, xs)
    half = extent / 2.0
    warp = roughness * fbm(rng=rng, x=gx, y=gy, half_extent_m=half, cell_m=220.0, octaves=4)
    detail = fbm(rng=rng, x=gx, y=gy, half_extent_m=half, cell_m=120.0, octaves=4)
    z = island_heights(
        gx, gy, islands=islands, floor_z=-25.0, shelf_slope=0.08, warp=warp, detail=detail, detail_frac=0.35
    )
    return Heightfield(x0=float(xs[0]), y0=float(xs[0]), spacing=spacing, z=z)


def generate_island(*, seed: int, params: IslandParams | None = None) -> MapWorld:
    """``island`` map: ``n_islands`` islands (sizes from ``island_radius_m``) at least ``min_gap_m`` apart."""
    seed = _check_seed(seed)
    p: IslandParams = _check_params(params, IslandParams, "island")
    rng = np.random.default_rng(seed)
    spacing, xs = _grid(p.extent_m, resolved(p.grid_m))
    islands, n_islands = _place_islands(p, rng)
    if n_islands < p.n_islands:  # left at its default on a map too small for it: say how many were built
        p = _unset_copy(p, n_islands=n_islands)
    hf = _island_terrain(rng, xs, spacing, islands, p.coast_roughness, p.extent_m)
    classify = _vegetation(rng, p.extent_m, p.vegetation, 4.0)
    buoys = _free_buoys(
        p.n_buoys, rng=rng, hf=hf, reach=p.extent_m / 2.0 - 100.0, avoid=None, depth=p.draft_margin_m + 3.0
    )
    return _assemble("island", seed, p, hf=hf, classify=classify, structures=[], buoys=buoys, moored=[], moored_fp=[])


def generate_open_sea(*, seed: int, params: OpenSeaParams | None = None) -> MapWorld:
    """``open_sea`` map: open water with up to ``n_buoys`` buoys near the centre and, with probability
    ``islet_probability``, one small islet far from the centre."""
    seed = _check_seed(seed)
    p: OpenSeaParams = _check_params(params, OpenSeaParams, "open_sea")
    rng = np.random.default_rng(seed)
    spacing, xs = _grid(p.extent_m, resolved(p.grid_m))
    half = p.extent_m / 2.0
    islands: list[IslandSpec] = []
    if rng.uniform() < p.islet_probability:
        r = float(rng.uniform(*resolved(p.islet_radius_m)))
        dist, ang = rng.uniform(0.55, 0.8) * half, rng.uniform(0.0, 2.0 * np.pi)
        dist = min(float(dist), half - 2.0 * r - 60.0)
        peak = min(float(rng.uniform(*p.islet_height_m)), 0.4 * r)
        islands.append(
            IslandSpec(
                center=(dist * float(np.cos(ang)), dist * float(np.sin(ang))),
                radius_m=r,
                peak_m=peak,
                harmonics=_harmonics(rng, 0.2),
            )
        )
    hf = _island_terrain(rng, xs, spacing, islands, 0.2, p.extent_m)
    classify = _vegetation(rng, p.extent_m, p.vegetation, 3.0)
    buoys = _free_buoys(p.n_buoys, rng=rng, hf=hf, reach=0.75 * half, avoid=None, depth=p.draft_margin_m + 3.0)
    return _assemble("open_sea", seed, p, hf=hf, classify=classify, structures=[], buoys=buoys, moored=[], moored_fp=[])


_COAST_ROT: dict[str, tuple[tuple[int, int], tuple[int, int], float]] = {
    # canonical (land north) -> world: rows of the 2x2 matrix M, and the yaw added to headings.
    "north": ((1, 0), (0, 1), 0.0),
    "south": ((-1, 0), (0, -1), float(np.pi)),
    "east": ((0, 1), (-1, 0), float(-np.pi / 2)),
    "west": ((0, -1), (1, 0), float(np.pi / 2)),
}


def _wrap(a: float) -> float:
    return float((a + np.pi) % (2.0 * np.pi) - np.pi)


def generate_port(*, seed: int, params: PortParams | None = None) -> MapWorld:
    """``port`` map (see :class:`PortParams`), land on the ``coast_side`` of the map. A port whose quay and piers
    have fewer free berths than an ``n_moored`` the parameters set is refused (:class:`MapConfigError` on
    ``n_moored``, naming the most that fit); left at its default, as many as fit are moored (up to 4), and
    ``MapWorld.params.n_moored`` says how many."""
    seed = _check_seed(seed)
    p: PortParams = _check_params(params, PortParams, "port")
    rng = np.random.default_rng(seed)
    spacing, xs = _grid(p.extent_m, resolved(p.grid_m))
    r0, r1, dyaw = _COAST_ROT[p.coast_side]
    m = np.array([r0, r1], dtype=np.float64)
    rot3 = np.eye(3)
    rot3[:2, :2] = m
    plan = plan_port(p, grid=spacing, rng=rng)
    gx, gy = np.meshgrid(xs, xs)
    # World -> canonical is M^T; with 0/±1 entries this only swaps and negates coordinates (exact).
    cx = m[0, 0] * gx + m[1, 0] * gy
    cy = m[0, 1] * gx + m[1, 1] * gy
    half = p.extent_m / 2.0
    coast_noise = fbm(rng=rng, x=cx, y=np.zeros_like(cx), half_extent_m=half, cell_m=220.0, octaves=3)
    hill_noise = fbm(rng=rng, x=cx, y=cy, half_extent_m=half, cell_m=260.0, octaves=4)
    z = port_terrain(plan, x=cx, y=cy, coast_noise=coast_noise, hill_noise=hill_noise, hill_m=p.hill_height_m)
    hf = Heightfield(x0=float(xs[0]), y0=float(xs[0]), spacing=spacing, z=z)
    classify = _vegetation(rng, p.extent_m, p.vegetation, plan.land_h + 2.5)

    def ground(c: np.ndarray) -> np.ndarray:
        return hf.sample(np.asarray(c, dtype=np.float64) @ m.T)

    built = port_structures(p, plan, ground=ground, rng=rng)
    if len(built.berths) < p.n_moored and "n_moored" not in p.model_fields_set:
        # Left at its default: as many as fit, and `params` records them (the same map again: the berths are drawn
        # alike and the first free ones taken whatever the number asked).
        p = _unset_copy(p, n_moored=len(built.berths))
    if len(built.berths) < p.n_moored:
        # Refused, as islands that do not fit are: fewer ships than asked would be a map other than the one given
        # (and `params` records what was built).
        raise MapConfigError(
            "n_moored",
            p.n_moored,
            f"at most {len(built.berths)} with this map seed and layout: the quay and piers of this port have free "
            f"berths for only {len(built.berths)} of the {p.n_moored} moored ships (lower n_moored, add piers with "
            "n_piers, or give shorter moored_assets, or ones whose draft is less than basin_depth_m: a ship "
            "that would ground is not moored)",
        )
    _channel_fits(p, len(built.buoys) // 2)
    structures = [transformed(s, rotation=rot3) for s in built.parts]
    buoys = [np.asarray(b, dtype=np.float64) @ m.T for b in built.buoys]
    moored: list[tuple[str, tuple[float, float, float]]] = []
    moored_fp: list[Polygon] = []
    for b in built.berths:
        x, y = np.array(b.pose[:2]) @ m.T
        moored.append((b.asset, (float(x), float(y), _wrap(b.pose[2] + dyaw))))
        moored_fp.append(Polygon(np.asarray(b.footprint().exterior.coords) @ m.T))
    avoid = shapely.union_all(
        [shapely.convex_hull(shapely.multipoints(s.vertices[:, :2])) for s in structures]
        + moored_fp
        + [shapely.Point(b) for b in buoys]
    )
    buoys += _free_buoys(p.n_buoys, rng=rng, hf=hf, reach=half - 100.0, avoid=avoid, depth=p.draft_margin_m + 3.0)
    return _assemble(
        "port",
        seed,
        p,
        hf=hf,
        classify=classify,
        structures=structures,
        buoys=buoys,
        moored=moored,
        moored_fp=moored_fp,
    )


def _unset_copy(p: _P, **values: Any) -> _P:
    """``p`` with ``values`` replaced and the same fields counted as set (a dump with ``exclude_unset`` still gives
    back only what the user set)."""
    out = p.model_copy(update=values)
    object.__setattr__(out, "__pydantic_fields_set__", set(p.model_fields_set))
    return out


def _channel_fits(p: PortParams, n_pairs: int) -> None:
    """A :class:`MapConfigError` when the fairway has room for fewer channel buoy pairs than the scenario set
    (``n_channel_buoy_pairs: 10`` built 5 without a word); left at its default, they are as many as fit."""
    if n_pairs < p.n_channel_buoy_pairs and "n_channel_buoy_pairs" in p.model_fields_set:
        raise MapConfigError(
            "n_channel_buoy_pairs",
            p.n_channel_buoy_pairs,
            f"at most {n_pairs} with this layout: the fairway from the harbour entrance to 40 m inside the map's edge "
            f"holds only {n_pairs} pairs 150 m apart (lower n_channel_buoy_pairs, raise extent_m, lower "
            "harbour_depth_m, or leave it out: as many as fit, up to 3)",
        )


def generate_map(kind: str, *, seed: int, **params: Any) -> MapWorld:
    """Generates a map of ``kind`` (``"island"``, ``"open_sea"`` or ``"port"``) from ``seed`` and parameter
    values (the fields of :class:`IslandParams`, :class:`OpenSeaParams` or :class:`PortParams`).

    Raises :class:`MapConfigError` (a ``ValueError``) naming the unknown kind or the bad field and what is allowed.
    """
    return generate_map_from(make_params(kind, **params), seed=seed)


def generate_map_from(params: MapParams, *, seed: int) -> MapWorld:
    """Generates the map that validated ``params`` describe (their type says the kind), e.g. a scenario's
    ``map.params`` (:class:`mmusv.config.MapConfig`); anything else is a :class:`MapConfigError`."""
    if isinstance(params, IslandParams):
        return generate_island(seed=seed, params=params)
    if isinstance(params, OpenSeaParams):
        return generate_open_sea(seed=seed, params=params)
    if isinstance(params, PortParams):
        return generate_port(seed=seed, params=params)
    raise MapConfigError(
        "params",
        params if not isinstance(params, BaseModel) else type(params).__name__,
        "IslandParams, OpenSeaParams or PortParams (make_params(kind, ...)); "
        "generate_map(kind, seed=..., **values) takes plain values",
    )
