"""Procedural maps and their priors: generation, determinism, parameter errors, and agreement between the
priors and the map meshes, checked with an independent numpy vertical-ray caster on small maps."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import shapely
import yaml
from mmusv.classes import SemanticClass
from mmusv.world.maps import (
    MAP_KINDS,
    WATER_REACH_M,
    IslandParams,
    MapConfigError,
    MapWorld,
    OpenSeaParams,
    PortParams,
    generate_map,
    make_params,
)
from mmusv.world.primitives import TriMesh

ROOT = Path(__file__).resolve().parents[2]

WATER = int(SemanticClass.WATER)

SMALL: dict[str, dict[str, Any]] = {
    "island": {
        "extent_m": 400.0,
        "n_islands": 2,
        "island_radius_m": (30.0, 60.0),
        "min_gap_m": 30.0,
        "clearance_m": 15.0,
    },
    "open_sea": {
        "extent_m": 400.0,
        "islet_probability": 1.0,
        "islet_radius_m": (15.0, 25.0),
        "n_buoys": 2,
        "clearance_m": 15.0,
    },
    "port": {
        "extent_m": 800.0,
        "coast_offset_m": 120.0,
        "harbour_width_m": 420.0,
        "harbour_depth_m": 230.0,
        "entrance_width_m": 90.0,
        "n_piers": 1,
        "pier_length_m": (60.0, 110.0),
        "n_cranes": 2,
        "n_buildings": 3,
        "n_channel_buoy_pairs": 1,
        "n_moored": 2,
        "n_buoys": 1,
        "hill_height_m": 20.0,
    },
}


def small(kind: str, seed: int = 1, **extra: Any) -> MapWorld:
    return generate_map(kind, seed=seed, **{**SMALL[kind], **extra})


# ------------------------------------------------------------------ independent vertical ray caster (numpy)


class VerticalCaster:
    """Casts vertical rays down from far above through the triangles of the given meshes (numpy, exact).

    For each query point it reports the class of the top-most surface and an obstacle height: the highest
    terrain (TERRAIN/VEGETATION) surface below the point, or ``+inf`` where any structure (any other non-water
    class) is there at any depth; ``-inf`` where there is neither. Triangles with no area seen from above (walls)
    are ignored: a vertical ray cannot hit them first. Triangles are bucketed on a uniform xy grid.
    """

    def __init__(self, meshes: list[TriMesh], bucket: float = 20.0) -> None:
        tri = np.concatenate([m.vertices[m.faces] for m in meshes])
        cls = np.concatenate([m.classes for m in meshes]).astype(np.int64)
        a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
        area2 = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
        keep = np.abs(area2) > 1e-9
        self.tri, self.cls, self.area2 = tri[keep], cls[keep], area2[keep]
        lo = self.tri[:, :, :2].min(axis=1) - 1e-6
        hi = self.tri[:, :, :2].max(axis=1) + 1e-6
        self.origin = lo.min(axis=0)
        self.bucket = bucket
        b0 = np.floor((lo - self.origin) / bucket).astype(np.int64)
        b1 = np.floor((hi - self.origin) / bucket).astype(np.int64)
        self.nb = b1.max(axis=0) + 1
        ids: list[np.ndarray] = []
        keys: list[np.ndarray] = []
        for dx in range(int((b1 - b0)[:, 0].max()) + 1):
            for dy in range(int((b1 - b0)[:, 1].max()) + 1):
                ok = (b0[:, 0] + dx <= b1[:, 0]) & (b0[:, 1] + dy <= b1[:, 1])
                t = np.nonzero(ok)[0]
                ids.append(t)
                keys.append((b0[t, 0] + dx) * self.nb[1] + b0[t, 1] + dy)
        key = np.concatenate(keys)
        order = np.argsort(key, kind="stable")
        self.tri_of = np.concatenate(ids)[order]
        self.start = np.searchsorted(key[order], np.arange(self.nb[0] * self.nb[1] + 1))

    def cast(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = xy.shape[0]
        bi = np.floor((xy - self.origin) / self.bucket).astype(np.int64)
        inside = np.all((bi >= 0) & (bi < self.nb), axis=1)
        key = np.where(inside, bi[:, 0] * self.nb[1] + bi[:, 1], 0)
        count = np.where(inside, self.start[key + 1] - self.start[key], 0)
        pi = np.repeat(np.arange(n), count)
        first = np.repeat(self.start[key] - np.r_[0, np.cumsum(count)[:-1]], count)
        ti = self.tri_of[first + np.arange(pi.size)]
        t, q = self.tri[ti], xy[pi]
        e = 1e-9 * np.abs(self.area2[ti]) + 1e-12

        def cr(u: np.ndarray, v: np.ndarray) -> np.ndarray:
            out: np.ndarray = (u[:, 0] - q[:, 0]) * (v[:, 1] - q[:, 1]) - (u[:, 1] - q[:, 1]) * (v[:, 0] - q[:, 0])
            return out

        w0, w1, w2 = cr(t[:, 1], t[:, 2]), cr(t[:, 2], t[:, 0]), cr(t[:, 0], t[:, 1])
        sgn = np.sign(self.area2[ti])
        hit = (w0 * sgn >= -e) & (w1 * sgn >= -e) & (w2 * sgn >= -e)
        pi, ti, t = pi[hit], ti[hit], t[hit]
        w = np.column_stack([w0[hit], w1[hit], w2[hit]]) / self.area2[ti][:, None]
        z = np.einsum("ij,ij->i", w, t[:, :, 2])
        c = self.cls[ti]
        top_cls = np.zeros(n, dtype=np.int64)
        order = np.lexsort((z, pi))  # per point, ascending z: the last one is the top surface
        last = np.r_[pi[order][1:] != pi[order][:-1], True] if pi.size else np.zeros(0, dtype=bool)
        top_cls[pi[order][last]] = c[order][last]
        obstacle = np.full(n, -np.inf)
        terrain = (c == int(SemanticClass.TERRAIN)) | (c == int(SemanticClass.VEGETATION))
        np.maximum.at(obstacle, pi[terrain], z[terrain])
        obstacle[pi[(c != WATER) & ~terrain]] = np.inf
        return top_cls, obstacle


def on_the_map(world: MapWorld) -> list[TriMesh]:
    """The static meshes with the water cut to its tiles over the map (the sea goes on 1,000 km past the map's edge,
    ``maps.WATER_REACH_M``, in triangles that would fill every bucket of :class:`VerticalCaster`)."""
    half = world.params.extent_m / 2.0
    out = []
    for name, m in world.static_meshes.items():
        if name == "water":
            keep = np.all(np.abs(m.vertices[m.faces][:, :, :2]) <= half + 1e-6, axis=(1, 2))
            m = TriMesh(m.vertices, m.faces[keep], m.classes[keep])
        out.append(m)
    return out


def cells_sample(world: MapWorld, cells: np.ndarray, k: int, rng: np.random.Generator, pad: float = 0.0) -> np.ndarray:
    """``k x k`` grid of points per cell (corners included), over the cell grown by ``pad`` metres."""
    pr = world.priors
    t = np.linspace(0.0, 1.0, k)
    gu, gv = np.meshgrid(t, t)
    size = pr.resolution + 2 * pad
    x0 = pr.origin[0] + cells[:, 1] * pr.resolution - pad
    y0 = pr.origin[1] + cells[:, 0] * pr.resolution - pad
    return np.stack([x0[:, None] + gu.ravel()[None] * size, y0[:, None] + gv.ravel()[None] * size], axis=2)


# ------------------------------------------------------------------------------------------- generation


@pytest.mark.parametrize("kind", MAP_KINDS)
def test_each_kind_generates(kind: str) -> None:
    w = small(kind)
    assert w.kind == kind and w.seed == 1
    assert list(w.static_meshes) == sorted(w.static_meshes)
    assert "water" in w.static_meshes
    for mesh in w.static_meshes.values():
        assert mesh.num_triangles > 0
        assert mesh.faces.max() < mesh.vertices.shape[0]
        assert np.isfinite(mesh.vertices).all()
    half = w.params.extent_m / 2.0
    for name, mesh in w.static_meshes.items():
        # Everything but the sea lies on the map; the sea goes on past its edge (maps.WATER_REACH_M).
        if name != "water":
            assert np.all(np.abs(mesh.vertices[:, :2]) <= half + 1e-6), name
    water = w.static_meshes["water"]
    assert np.abs(water.vertices[:, :2]).max() == half + WATER_REACH_M
    assert np.all(water.vertices[:, 2] == 0.0) and np.all(water.classes == WATER)
    classes = set(np.concatenate([m.classes for m in w.static_meshes.values()]).tolist())
    expected = {
        "island": {SemanticClass.WATER, SemanticClass.TERRAIN, SemanticClass.BUOY},
        "open_sea": {SemanticClass.WATER, SemanticClass.TERRAIN, SemanticClass.BUOY},
        "port": {
            SemanticClass.WATER,
            SemanticClass.TERRAIN,
            SemanticClass.PORT_STRUCTURE,
            SemanticClass.CONTAINER,
            SemanticClass.CRANE,
            SemanticClass.BUILDING,
            SemanticClass.BUOY,
        },
    }[kind]
    assert {int(c) for c in expected} <= classes
    pr = w.priors
    n = round(w.params.extent_m / w.params.prior_resolution_m)
    assert pr.water_mask.shape == (n, n) and pr.water_mask.dtype == np.bool_
    assert pr.shore_distance.dtype == np.float32 and pr.valid_zones.dtype == np.bool_
    assert pr.water_mask.any() and (~pr.water_mask).any()
    assert pr.shoreline and pr.land and pr.occlusion_regions
    if kind == "port":
        assert pr.structure_boundaries and len(w.moored) == 2
        for name, (x, y, yaw) in w.moored:
            assert isinstance(name, str) and -np.pi <= yaw <= np.pi
            assert w.heightfield.sample(np.array([[x, y]]))[0] < -w.params.draft_margin_m
        assert not shapely.union_all(list(pr.moored_footprints)).intersects(
            shapely.union_all(list(pr.structure_boundaries))
        )


def test_open_sea_can_be_water_only() -> None:
    w = generate_map("open_sea", seed=0, extent_m=600.0, islet_probability=0.0, n_buoys=0)
    assert set(w.static_meshes) == {"water"}
    assert w.priors.water_mask.all() and np.isinf(w.priors.shore_distance).all()
    assert w.priors.shoreline == () and w.priors.land == ()
    assert w.priors.valid_zones.any()


@pytest.mark.parametrize("kind", MAP_KINDS)
def test_default_maps_stay_within_triangle_budget(kind: str) -> None:
    w = generate_map(kind, seed=3)
    assert 0 < w.num_triangles <= 400_000
    if kind != "open_sea":
        assert w.static_meshes["terrain"].num_triangles < 250_000


@pytest.mark.parametrize("side", ["north", "south", "east", "west"])
def test_port_coast_side_puts_land_on_that_side(side: str) -> None:
    w = small("port", coast_side=side)
    d = {"north": (0.0, 1.0), "south": (0.0, -1.0), "east": (1.0, 0.0), "west": (-1.0, 0.0)}[side]
    far = np.array([[d[0] * 380.0 + d[1] * t, d[1] * 380.0 + d[0] * t] for t in (-300.0, 0.0, 300.0)])
    near_sea = -far
    assert np.all(w.heightfield.sample(far) > 0.0)
    assert np.all(w.heightfield.sample(near_sea) < -2.0)
    assert not w.priors.is_water(far).any() and w.priors.is_water(near_sea).all()


# ------------------------------------------------------------------------------------------- determinism


def _fingerprint(w: MapWorld) -> list[Any]:
    out: list[Any] = [w.kind, w.seed, repr(w.params), w.moored]
    for name, m in w.static_meshes.items():
        out += [name, m.vertices, m.faces, m.classes]
    pr = w.priors
    out += [pr.water_mask, pr.shore_distance, pr.valid_zones, pr.buoys, w.heightfield.z, *pr.shoreline]
    out += [
        shapely.to_wkb(g) for g in (*pr.land, *pr.structure_boundaries, *pr.occlusion_regions, *pr.moored_footprints)
    ]
    return out


def _same(a: list[Any], b: list[Any]) -> bool:
    if len(a) != len(b):
        return False
    for x, y in zip(a, b, strict=True):
        if isinstance(x, np.ndarray):
            if not (isinstance(y, np.ndarray) and x.dtype == y.dtype and np.array_equal(x, y)):
                return False
        elif x != y:
            return False
    return True


@pytest.mark.parametrize("kind", MAP_KINDS)
def test_same_seed_gives_identical_arrays(kind: str) -> None:
    assert _same(_fingerprint(small(kind, seed=7)), _fingerprint(small(kind, seed=7)))


@pytest.mark.parametrize("kind", MAP_KINDS)
def test_different_seed_gives_a_different_map(kind: str) -> None:
    a, b = small(kind, seed=7), small(kind, seed=8)
    assert not np.array_equal(a.heightfield.z, b.heightfield.z)
    assert not np.array_equal(a.priors.water_mask, b.priors.water_mask)


# ------------------------------------------------------------------------------------- priors vs meshes


@pytest.mark.parametrize(
    ("kind", "extra"),
    [
        ("island", {}),
        ("island", {"grid_m": 8.0, "prior_resolution_m": 5.0}),
        ("open_sea", {}),
        ("port", {}),
        ("port", {"coast_side": "west", "grid_m": 4.0, "prior_resolution_m": 6.0}),
    ],
)
def test_priors_agree_with_the_meshes(kind: str, extra: dict[str, Any]) -> None:
    w = small(kind, seed=2, **extra)
    pr = w.priors
    margin = pr.draft_margin
    caster = VerticalCaster(on_the_map(w))
    rng = np.random.default_rng(0)
    water = pr.water_mask
    # Water cells: all of them next to non-water (the hard ones) and a random share of the rest.
    nonwater = ~water
    near = np.zeros_like(water)
    near[1:] |= nonwater[:-1]
    near[:-1] |= nonwater[1:]
    near[:, 1:] |= nonwater[:, :-1]
    near[:, :-1] |= nonwater[:, 1:]
    edge_cells = np.argwhere(water & near)
    other = np.argwhere(water & ~near)
    cells = np.vstack([edge_cells[rng.permutation(len(edge_cells))[:600]], other[rng.permutation(len(other))[:200]]])
    pts = np.vstack(
        [
            cells_sample(w, cells, 3, rng).reshape(-1, 2),
            pr.cell_to_world(cells) + rng.uniform(-0.5, 0.5, size=(len(cells), 2)) * pr.resolution,
        ]
    )
    assert pr.is_water(pts[len(cells) * 9 :]).all()
    top_cls, obstacle = caster.cast(pts)
    assert np.all(top_cls == WATER), "a point of a water cell hits something above the water surface"
    assert np.all(obstacle <= -margin + 1e-9), "a water cell holds a structure or terrain shallower than the margin"
    # Non-water cells: a structure lies in the cell grown by 3 m (for structures that only graze it), or a
    # terrain vertex above -margin lies in the cell. When the raster cell is not a whole number of terrain
    # cells, the terrain bound is taken over the terrain cells it touches, so that vertex may be up to one
    # terrain spacing outside.
    land = np.argwhere(nonwater)
    land = land[rng.permutation(len(land))[:400]]
    ratio = pr.resolution / w.heightfield.spacing
    aligned = abs(ratio - round(ratio)) < 1e-9
    _, grown = caster.cast(cells_sample(w, land, 11, rng, pad=3.0).reshape(-1, 2))
    witness = grown.reshape(len(land), -1).max(axis=1) > -margin
    tv = w.static_meshes["terrain"].vertices
    tv = tv[tv[:, 2] > -margin]
    pad = (0.0 if aligned else w.heightfield.spacing) + 1e-6
    box_lo = pr.cell_to_world(land) - pr.resolution / 2.0 - pad
    for i in np.nonzero(~witness)[0]:
        inside = np.all((tv[:, :2] >= box_lo[i]) & (tv[:, :2] <= box_lo[i] + pr.resolution + 2 * pad), axis=1)
        witness[i] = bool(inside.any())
    assert witness.all()
    if aligned:  # then the terrain bound is exact: nearly every cell holds its witness itself
        _, inner = caster.cast(cells_sample(w, land, 7, rng).reshape(-1, 2))
        assert np.mean(inner.reshape(len(land), -1).max(axis=1) > -margin) >= 0.97


def test_priors_agree_with_the_native_scene() -> None:
    scene_mod = pytest.importorskip("mmusv.scene")
    w = small("port", seed=4)
    scene = scene_mod.Scene()
    for name, m in w.static_meshes.items():
        scene.add_instance(scene.add_mesh(m.vertices, m.faces, classes=m.classes, name=name))
    pr = w.priors
    rng = np.random.default_rng(1)
    xy = rng.uniform(-w.params.extent_m / 2.0, w.params.extent_m / 2.0, size=(20000, 2))
    origins = np.column_stack([xy, np.full(len(xy), 500.0)])
    dirs = np.tile([0.0, 0.0, -1.0], (len(xy), 1))
    hits = scene.cast_rays(origins, dirs, max_range=1000.0)
    wet = pr.is_water(xy)
    assert np.all(hits.semantic_class[wet] == WATER)
    dry_hit = hits.semantic_class[~wet] != WATER
    assert dry_hit.mean() > 0.7  # the rest is shallow water or cells a structure or the coast only grazes


# ------------------------------------------------------------------------------------- priors contents


def test_shore_distance_is_zero_on_land_and_grows_away_from_it() -> None:
    w = small("island", seed=3)
    pr = w.priors
    assert np.all(pr.shore_distance[~pr.water_mask] == 0.0)
    assert np.all(pr.shore_distance[pr.water_mask] >= pr.resolution - 1e-4)
    land_c = pr.cell_to_world(np.argwhere(~pr.water_mask))
    rng = np.random.default_rng(0)
    wc = np.argwhere(pr.water_mask)
    wc = wc[rng.permutation(len(wc))[:300]]
    brute = np.array([np.min(np.hypot(*(land_c - p).T)) for p in pr.cell_to_world(wc)])
    np.testing.assert_allclose(pr.shore_distance[wc[:, 0], wc[:, 1]], brute, rtol=1e-5)
    # Walking away from an island's coast, the distance never decreases while it stays the nearest land.
    c = np.array(shapely.centroid(pr.land[0]).coords[0])
    ray = c + np.linspace(0, 1, 200)[:, None] * np.array([0.0, 1.0]) * 150.0
    d = pr.shore_distance_at(ray)
    start = int(np.argmax(d > 0))
    assert d[start] > 0 and np.all(np.diff(d[start : start + 10]) >= 0)


def test_valid_zones_respect_the_clearance() -> None:
    for kind in MAP_KINDS:
        w = small(kind, seed=5)
        pr = w.priors
        v = pr.valid_zones
        assert v.any()
        assert not (v & ~pr.water_mask).any()
        assert np.all(pr.shore_distance[v] >= pr.clearance)
        centres = pr.cell_to_world(np.argwhere(v))
        half = w.params.extent_m / 2.0
        assert np.all(half - np.abs(centres) >= pr.clearance)
        if pr.moored_footprints:
            boats = shapely.union_all(list(pr.moored_footprints))
            assert np.all(shapely.distance(boats, shapely.points(centres)) >= pr.clearance)
        pts = pr.sample_water_points(500, rng=np.random.default_rng(2))
        assert pts.shape == (500, 2) and pr.is_valid(pts).all() and pr.is_water(pts).all()
        assert np.all(pr.shore_distance_at(pts) >= pr.clearance)
        far = pr.sample_water_points(200, rng=np.random.default_rng(3), min_clearance=40.0)
        assert np.all(pr.shore_distance_at(far) >= 40.0)


def test_cell_conversions_round_trip() -> None:
    pr = small("island").priors
    rc = np.array([[0, 0], [3, 7], [pr.shape[0] - 1, pr.shape[1] - 1]])
    assert np.array_equal(pr.world_to_cell(pr.cell_to_world(rc)), rc)
    assert np.allclose(pr.cell_to_world([[0, 0]]), np.array(pr.origin) + pr.resolution / 2.0)
    assert not pr.is_water(np.array([[1e6, 0.0]])).any()
    assert pr.shore_distance_at(np.array([[1e6, 0.0]]))[0] == 0.0


def test_shoreline_lies_on_the_waterline_and_occlusion_blocks_sight() -> None:
    w = small("island", seed=6)
    pr = w.priors
    pts = np.vstack(pr.shoreline)
    assert np.allclose(w.heightfield.sample(pts), 0.0, atol=1e-6)
    isl = max(pr.land, key=lambda g: g.area)
    assert w.heightfield.sample(np.array(isl.representative_point().coords)).item() > 0.0
    # A sight line straight through the highest point of the biggest island is blocked; far out at sea it is free.
    xs, ys = w.heightfield.axes()
    i, j = np.unravel_index(np.argmax(w.heightfield.z), w.heightfield.z.shape)
    top = np.array([xs[j], ys[i]])
    assert w.heightfield.z[i, j] > w.params.occlusion_height_m
    a, b = top + np.array([-300.0, 0.0]), top + np.array([300.0, 0.0])
    assert not pr.line_of_sight(a[None], b[None])[0]
    assert pr.line_of_sight(np.array([[-190.0, -190.0]]), np.array([[-189.0, -189.0]]))[0]


def test_port_priors_hold_structures_and_tall_occluders() -> None:
    w = small("port", seed=2)
    pr = w.priors
    structs = shapely.union_all(list(pr.structure_boundaries))
    mesh = w.static_meshes["port_structures"]
    tall = mesh.vertices[mesh.faces][mesh.classes == int(SemanticClass.CRANE)].reshape(-1, 3)
    assert shapely.contains_xy(structs.buffer(1e-6), tall[:, 0], tall[:, 1]).all()
    occl = shapely.union_all(list(pr.occlusion_regions))
    assert shapely.contains_xy(occl.buffer(1e-6), tall[:, 0], tall[:, 1]).all()
    assert pr.buoys.shape[0] >= 2 and not pr.is_water(pr.buoys).any()


# ------------------------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("kind", "params", "field"),
    [
        ("volcano", {}, "kind"),
        ("island", {"n_islnds": 3}, "n_islnds"),
        ("island", {"n_islands": -1}, "n_islands"),
        ("island", {"n_islands": 2.5}, "n_islands"),
        ("island", {"island_radius_m": (300.0, 100.0)}, "island_radius_m"),
        ("island", {"island_radius_m": "big"}, "island_radius_m"),
        ("island", {"extent_m": "big"}, "extent_m"),
        ("island", {"grid_m": 0.1}, "grid_m"),
        ("open_sea", {"islet_probability": 1.5}, "islet_probability"),
        ("port", {"coast_side": "up"}, "coast_side"),
        ("port", {"entrance_width_m": 5000.0}, "entrance_width_m"),
        ("port", {"n_cranes": 100}, "n_cranes"),
        ("port", {"moored_assets": [["ship", -1.0, 5.0]]}, "moored_assets"),
        ("port", {"moored_assets": [["tug_32m", 32.0, 9.0], ["tug_32", 32.0, 9.0]]}, "moored_assets"),
        ("port", {"vegetation": "yes"}, "vegetation"),
    ],
)
def test_bad_parameters_are_rejected_naming_the_field(kind: str, params: dict[str, Any], field: str) -> None:
    with pytest.raises(MapConfigError) as err:
        generate_map(kind, seed=0, **params)
    assert isinstance(err.value, ValueError)
    assert err.value.field == field
    assert field in str(err.value) and "allowed" in str(err.value)


@pytest.mark.parametrize(
    ("kind", "params", "field", "said"),
    [
        ("port", {"draft_margin_m": 12.0}, "basin_depth_m", "lower bound is draft_margin_m + 3"),
        ("open_sea", {"extent_m": 200.0, "islet_radius_m": (30.0, 60.0)}, "islet_radius_m", "extent_m / 4"),
    ],
)
def test_a_default_out_of_a_range_set_by_another_knob_says_which(
    kind: str, params: dict[str, Any], field: str, said: str
) -> None:
    """A knob left at its default whose range another knob moved was blamed alone ("basin_depth_m = 14: must be in
    [15, 40]" for draft_margin_m = 12, which the user did set): the message now says where the bound comes from."""
    with pytest.raises(MapConfigError) as err:
        generate_map(kind, seed=0, **params)
    assert err.value.field == field and said in str(err.value), str(err.value)


def test_unknown_kind_lists_the_kinds_and_bad_seed_is_rejected() -> None:
    with pytest.raises(MapConfigError, match=r"island \| open_sea \| port"):
        make_params("volcano")
    with pytest.raises(MapConfigError) as err:
        generate_map("island", seed=-3)
    assert err.value.field == "seed"


def test_a_map_of_any_allowed_extent_builds_with_the_other_knobs_at_their_defaults() -> None:
    """Only ``extent_m`` set, within its range: an island map of 200 m was refused for the default island radii
    (``island_radius_m`` (60, 280): "the upper bound is extent_m / 2"), one of 600 m for the default five islands
    that did not fit, and any map past 10 km for the default ``grid_m`` (5 m: "must be >= extent_m / 2000"). Now a
    default outside the range the extent allows is cut to it, ``n_islands`` left at its default places as many as
    fit up to 5 (and the built map's parameters say how many), and the defaults the extent allows are the ones they
    were, so every map that built before builds the same."""
    built = [generate_map("island", seed=seed, extent_m=extent) for extent in (200.0, 300.0, 600.0) for seed in (0, 1)]
    for w in built:
        p = w.params
        assert isinstance(p, IslandParams)
        lo, hi = p.island_radius_m or (0.0, 0.0)
        assert 15.0 <= lo <= hi <= p.extent_m / 2 and p.min_gap_m is not None and p.min_gap_m <= p.extent_m / 2
        assert 1 <= p.n_islands <= 5 and p.model_dump(exclude_unset=True) == {"extent_m": p.extent_m}
    assert min(w.params.n_islands for w in built) < 5  # some small maps hold fewer
    assert generate_map("open_sea", seed=0, extent_m=200.0).params.islet_radius_m == (25.0, 50.0)
    for kind in ("island", "open_sea", "port"):
        assert make_params(kind, extent_m=20000.0).grid_m == 10.0
    island, sea, port = make_params("island"), make_params("open_sea"), make_params("port")
    assert isinstance(island, IslandParams) and isinstance(sea, OpenSeaParams)
    assert (island.island_radius_m, island.min_gap_m, island.n_islands, island.grid_m) == ((60.0, 280.0), 120.0, 5, 5)
    assert sea.islet_radius_m == (25.0, 70.0) and sea.grid_m == port.grid_m == 5.0
    # A number of islands the scenario sets is built exactly, or refused.
    with pytest.raises(MapConfigError) as err:
        generate_map("island", seed=1, extent_m=200.0, n_islands=5)
    assert err.value.field == "n_islands" and "of the 5 islands of island_radius_m [60, 100]" in str(err.value)


def test_islands_that_cannot_fit_are_reported() -> None:
    with pytest.raises(MapConfigError) as err:
        generate_map("island", seed=0, extent_m=400.0, n_islands=20, island_radius_m=(90.0, 100.0), min_gap_m=150.0)
    assert err.value.field == "n_islands"


def test_an_unknown_moored_asset_is_named_with_its_entry_in_the_scenario() -> None:
    """The malformed-input review's: an unknown name in ``moored_assets`` was refused only when the port was built,
    as "unknown vessel asset 'no_such_ship'", naming no field; now with its path and entry, as a vessel's asset."""
    from mmusv.config import load_scenario
    from mmusv.errors import ConfigError

    doc = yaml.safe_load((ROOT / "scenarios" / "port_entry.yaml").read_text())
    doc["map"]["params"] = {"moored_assets": [["tug_32m", 32, 9], ["tug_32", 32, 9]]}
    with pytest.raises(ConfigError) as err:
        load_scenario(doc)
    said = str(err.value)
    assert "map.params.moored_assets" in said and "entry 1 ('tug_32')" in said and "did you mean tug_32m" in said


def test_params_accept_yaml_style_lists_and_keep_defaults() -> None:
    p = make_params("port", pier_length_m=[100, 150], moored_assets=[["tug_32m", 30, 10]])
    assert isinstance(p, PortParams)
    assert p.pier_length_m == (100.0, 150.0) and p.moored_assets == (("tug_32m", 30.0, 10.0),)
    assert IslandParams().extent_m == 2000.0 and OpenSeaParams().extent_m == 4000.0 and PortParams().extent_m == 2000.0


@pytest.mark.parametrize("seed", range(12))
def test_every_moored_ship_floats_over_the_basin_floor(seed: int) -> None:
    """The default port moored the 300 m container ship (draft 14.5 m) in its 14 m basin in 7 of these 12 seeds,
    its keel in the floor; a ship that would ground gives way to the longest that fits its berth and floats. The
    depth is read from the map's heightfield over the ship's whole waterplane (a 2 m grid over its footprint)."""
    from mmusv.world.hydrostatics import hull_particulars
    from mmusv.world.vessels import get_asset

    world = generate_map("port", seed=seed)
    assert world.moored
    for name, (x, y, yaw) in world.moored:
        length, beam, draft, _, _ = hull_particulars(get_asset(name))
        u, v = np.meshgrid(
            np.linspace(-length / 2, length / 2, int(length / 2) + 2), np.linspace(-beam / 2, beam / 2, 5)
        )
        c, s = np.cos(yaw), np.sin(yaw)
        points = np.column_stack([x + c * u.ravel() - s * v.ravel(), y + s * u.ravel() + c * v.ravel()])
        depth = -world.heightfield.sample(points)
        assert depth.min() > draft, (name, float(depth.min()), draft)


def test_a_basin_deep_enough_moors_the_large_ship_where_it_was_drawn() -> None:
    deep = generate_map("port", seed=0, basin_depth_m=16.0)
    shallow = generate_map("port", seed=0)
    assert "container_ship_300m" in [a for a, _ in deep.moored]
    assert "container_ship_300m" not in [a for a, _ in shallow.moored]
    # the berth the large ship was drawn for holds the longest ship that floats, alongside the same quay face
    (big,) = [pose for a, pose in deep.moored if a == "container_ship_300m"]
    (instead,) = [(a, pose) for a, pose in shallow.moored if abs(pose[0] - big[0]) < 1e-6 and a != "pilot_boat_16m"]
    assert instead[0] == "feeder_container_140m"
    assert abs(abs(instead[1][1] - big[1]) - (48.2 - 22.5) / 2) < 1e-6


def test_a_moored_ship_a_user_gives_that_would_ground_is_refused_naming_the_basin() -> None:
    # Given by a user, an entry whose draft reaches the basin's floor left its berths to others (or the port empty)
    # without a word; the default list keeps its large ship for deep basins and gives way in shallow ones.
    with pytest.raises(MapConfigError, match=r"entry 1 \('container_ship_300m'\): its draft, 14\.5 m, reaches"):
        make_params("port", moored_assets=[["tug_32m", 32, 12], ["container_ship_300m", 300, 48.2]])
    with pytest.raises(MapConfigError, match=r"basin_depth_m = 7 m"):
        make_params("port", basin_depth_m=7, moored_assets=[["feeder_container_140m", 140, 22.5]])
    assert make_params("port", basin_depth_m=16, moored_assets=[["container_ship_300m", 300, 48.2]])
    assert make_params("port", basin_depth_m=7)  # the default list: the ships that float are moored
