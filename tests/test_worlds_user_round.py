"""The maps and worlds as a scenario designer and a perception researcher meet them (a helper's round): each check
against an independent computation written out here (shapely on the meshes' own triangles, barycentric heights by
hand, a ray/plane intersection, the top view's pixel geometry from its documented formula), not the project's code.

Checked and right, no change:

* Land: on an island, an open-sea (islet) and two port maps (coast north and west), 20,000 random points each: the
  priors' ``land`` polygons hold exactly the points where the terrain mesh's own triangles (barycentric height by
  hand) stand above the water; LiDAR points labelled terrain lie on the heightfield (0.00 m).
* Moored ships (ports of seeds 0, 1, 3, 7, coast north and east, six ships each): their hulls (the asset meshes'
  footprints at their berths, shapely) overlap no port structure's triangles and no land, 2.0-3.0 m off the quays and
  piers; their library sizes are the sizes their berths were laid out for.
* Route checks in ``mmusv run``: a route over land, into a breakwater and off the map are refused naming the file,
  the check, the vessel, the point and the route's field (off the map: the map's span).
* Determinism: the same kind, seed and parameters give the same meshes, berths and priors, byte for byte, also in
  two processes of different hash seeds (one sha256 over the three kinds' meshes, berths, rasters and polygons).
* The editor's map: its terrain picture (800 x 800 px, a port with its coast east and an island map) shows land on
  exactly the pixels whose centres the priors' ``land`` polygons hold.
* Sensors against the geometry (``port_entry``, one frame): camera pixels labelled water, terrain and vegetation,
  taken to the world through the documented pinhole (depth along the optical axis), lie on the water plane and on
  the heightfield (0.000 m); the radar's terrain and vegetation returns lie on the land polygons, its structure
  returns on the structures' footprints (p95 within 1.6-3.4 m, its range bins 3 m), its sea clutter on water.
* Bad map parameters in a scenario file (17 kinds: unknown knob, kind, negative seed, text for a number, sizes out
  of range, too many islands or moored ships, unknown or undersized moored asset, a list for ``params``) name the
  file, the field and what is allowed.

Found by the round (each test below failed before its fix):

* No sea beyond the map's edge on the flat sea (``environment.motion: paper``): the water mesh ended at the map's
  square, so a ray leaving the map downwards met nothing. A USV 15 m inside the edge of a 400 m open-sea map, bow
  out: its top view drew the sky's grey (mean RGB 162, 157, 164) over the 36 % of the image beyond the edge, under
  semantic labels that said water (on the map: 60, 72, 88); its front camera drew sky between the map's edge and
  the horizon; its LiDAR had 1 water return past the edge against 576 as far astern. The water mesh now reaches
  1,000 km past the edge (``maps.WATER_REACH_M``, the longest camera range) in rings twice as wide each, the map's
  own tiles unchanged: the top view's water beyond is (59, 70, 83), the LiDAR's returns past the edge 528. The
  physical sea (the default) already went on past the map and records the same bytes as before (port_entry, one
  frame, every sensor); so do the flat sea's sensors whose rays stay on the map.
* ``shore_clearance`` called the map's edge a shore: ``port_entry`` with ``usv_1`` sailing south to 10 m off the
  map's southern edge, open sea all round, was warned that it "comes within 10 m of the shore (hull) near
  (-170, -984)". The check counts the edge with land, shallows and structures (as its spec says); the warning now
  names what is there: "comes within 10 m of the map's edge (hull) near (-170, -984) (the map spans x -1000..1000
  m, y -1000..1000 m)", and a real shore is still called the shore.
* A route straight through a ship moored in the port was let through with two warnings ("comes within 15 m of a
  port structure, buoy or moored ship"): ``port_entry``'s yacht sailing along y = 226 m through the ferry moored at
  (-91, 233) (its hull overlapping the ferry's by 4.5 m, by the hulls' inscribed capsules, and by shapely on the two
  hull rectangles). Two of the scenario's own vessels doing so is an error (``hulls_intersect``), and the moored
  ships are vessels too (world state, boxes, LiDAR labels); ``mmusv run`` and the editor now refuse it alike,
  naming the moored ship, where, and the route to move (in blocks of time samples, so its memory stays bounded).
* Which class each part of the world carries was nowhere said (the lights on the breakwater heads are BUILDING,
  the seabed of the terrain cells within 2 m of the surface TERRAIN, a target of a USV asset USV, a ship's deck
  containers VESSEL): ``SemanticClass`` now says it, each claim checked on the meshes.
* A port of the smallest extent allowed (``extent_m: 600``, "a port needs at least 600 m"), every other knob at its
  default, was refused for every seed tried (10 of 10; 6 of 10 at 700 and 800 m, 3 of 10 at 1200 m), the error
  blaming ``n_moored``, which the scenario never set: the default 4 ships did not fit. Left at its default,
  ``n_moored`` is now as many as fit, up to 4 (2 or 3 at 600 m), and ``MapWorld.params.n_moored`` says how many
  (the same map again when set to that number); a number the scenario sets is still moored exactly or refused.
* A port's ``n_channel_buoy_pairs`` was built as far as the fairway had room, without a word: ``10`` on the default
  2000 m port built 5 (``MapWorld.params`` saying 10). A number the scenario sets is now built exactly or refused
  when the port is built, naming the field and the most that fit (as ``n_moored`` is); left at its default, 3, it is
  as many as fit, as ``PortParams`` now says. ``n_buildings`` is placed at random (each at up to 40 spots), so the
  most that fit depends on the number asked: it stays "at most this many", now said, with what it gives
  (``n_buildings: 200`` on the default port of seed 3: 84; an 800 m port: none of its default 8).
* ``PortParams.coast_offset_m`` is "the quay line", but the quay wall's seaward face stands ``grid_m + 1`` m seaward
  of it (244 m for the default 250 m, 229 m at ``grid_m: 20``, measured on the quay's top faces with shapely): a
  designer putting a vessel alongside at 245 m put it in the quay. Now said, with both numbers.
* ``PortParams.entrance_width_m`` is "the gap between the breakwater heads, at their toes", but each arm's head
  reaches 19 m into it: along the arms' line the open gap measures ``entrance_width_m - 38`` m on the meshes
  (shapely: 162 m for the default 200, 62 m for 100; 22 m at the least allowed, 60), at the crest and at the toe
  alike (the arms' ends are vertical). Now said as built; making the gap what the knob says changes every port map
  (``port_entry`` among them) and is left to the project (see the report).
* ``IslandParams.island_radius_m`` was the "range of mean coast radii"; it is the radius ``R`` the island is drawn
  in: three islands in four are a 0.72 ``R`` dome with lobes out to ``R``, so their mean coast radius is 0.75-0.82
  ``R``: ``[100, 120]`` (smooth coasts, 12 seeds) gave islands of 77-119 m area-equivalent radius, 20 of 24 below
  100 m. Now said as it is built. Likewise ``island_height_m``, the "range of peak heights": the relief on top
  makes summits of 34-47 m of ``[40, 40]`` (20 islands), 86 m of the default ``[15, 80]``; now said.
"""

from __future__ import annotations

import inspect
import itertools
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import pytest
import shapely
import shapely.affinity
import yaml
from mmusv.classes import SemanticClass
from mmusv.config import load_scenario
from mmusv.editor.evaluate import evaluate
from mmusv.scenario_checks import MmusvWarning, check_routes
from mmusv.world.build import build_static_scene
from mmusv.world.maps import IslandParams, MapConfigError, PortParams, generate_map
from mmusv.world.vessels import get_asset

WATER = int(SemanticClass.WATER)
ROOT = Path(__file__).resolve().parents[1]


def _edge_scenario(x0: float, *, motion: str = "paper") -> dict[str, Any]:
    """A USV at ``(x0, 0)`` heading east on a 400 m open-sea map (edge at x = 200), with a LiDAR whose water
    returns reach 60 m and a 64 x 64 top view at 2 m a pixel, heading up (its top rows lie ahead, to the east)."""
    return {
        "name": "edge",
        "seed": 1,
        "map": {"type": "open_sea", "seed": 0, "params": {"extent_m": 400, "islet_probability": 0, "n_buoys": 0}},
        "acquisition": {"frames": 1},
        "environment": {"motion": motion, "wave": "W2"},
        "rigs": {
            "r": {
                "lidar": {"channels": 16, "points_per_second": 80000, "water_range_m": 60, "water_probability": 0.5},
                "cameras": [],
                "top_view": {"resolution": [64, 64], "metres_per_pixel": 2.0, "outputs": ["rgb", "semantic"]},
                "radar": None,
            }
        },
        "vessels": [
            {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 1, "route": [[x0, 0], [x0 + 1, 0]]}
        ],
    }


def test_rays_leaving_the_map_downwards_meet_the_sea() -> None:
    world = generate_map("open_sea", seed=0, extent_m=400, islet_probability=0.0, n_buoys=0)
    scene = build_static_scene(world).scene
    # Straight down at 10 m over points off the map, up to 900 km out; and slanting down 1 degree from the edge.
    xs = np.array([201.0, 350.0, 5_000.0, 80_000.0, 900_000.0])
    origins = np.column_stack([xs, -xs / 3.0, np.full(xs.size, 10.0)])
    hits = scene.cast_rays(origins, np.tile([0.0, 0.0, -1.0], (xs.size, 1)))
    assert hits.hit.all() and (hits.semantic_class == WATER).all()
    np.testing.assert_allclose(hits.distance, 10.0, rtol=1e-5)
    dip = np.deg2rad(1.0)
    d = np.array([[np.cos(dip), 0.0, -np.sin(dip)]])
    slant = scene.cast_rays(np.array([[195.0, 0.0, 10.0]]), d)
    # The plane z = 0 is 10 / sin(1 deg) = 573 m along the ray, 378 m past the edge.
    assert slant.hit.all() and slant.semantic_class[0] == WATER
    np.testing.assert_allclose(slant.distance, 10.0 / np.sin(dip), rtol=1e-5)


@pytest.fixture(scope="module")
def near_the_edge() -> Any:
    return mmusv.Simulation(_edge_scenario(185.0)).capture(0).agents["u"]


def test_the_top_view_draws_the_sea_beyond_the_map(near_the_edge: Any) -> None:
    tv = near_the_edge.top_view
    h, m = 64, 2.0
    x_usv = float(near_the_edge.top_view_pose[0, 3])
    ahead = (h / 2.0 - np.arange(h) - 0.5) * m  # the documented pixel-centre formula, rows
    off = x_usv + ahead > 200.0 + m  # rows wholly beyond the map's edge (a pixel's margin)
    on = x_usv + ahead < 200.0 - m
    assert off.sum() >= 10 and on.sum() >= 10
    water = tv.semantic == WATER
    assert water[off].mean() > 0.95 and water[on].mean() > 0.95  # labelled water on both sides, before too
    rgb = tv.rgb.astype(np.float64)
    mean_off = rgb[off][water[off]].mean(axis=0)
    mean_on = rgb[on][water[on]].mean(axis=0)
    # Before: (162, 157, 164) beyond the edge, the sky's grey, against (60, 72, 88) on the map.
    assert np.abs(mean_off - mean_on).max() < 15.0, (mean_off, mean_on)


def test_the_lidar_sees_water_beyond_the_map(near_the_edge: Any) -> None:
    a = near_the_edge
    pts = (a.lidar_pose[:3, :3] @ a.lidar.xyz.T.astype(np.float64)).T + a.lidar_pose[:3, 3]
    water = pts[a.lidar.semantic_class == WATER]
    x0 = float(a.lidar_pose[0, 3])
    gap = 200.0 - x0  # the edge lies 15 m ahead
    beyond, astern = water[:, 0] > x0 + gap, water[:, 0] < x0 - gap
    # The sea is the same all round: as many returns past the edge as as far astern (528 and 576). Before: 1.
    assert beyond.sum() > 0.8 * astern.sum() and astern.sum() > 500


def test_the_physical_sea_beyond_the_map_is_unchanged() -> None:
    """The physical sea already went on past the map; the longer water mesh changes none of its bytes' meaning:
    water returns beyond the edge, and the top view's water the same on both sides."""
    a = mmusv.Simulation(_edge_scenario(185.0, motion="physical")).capture(0).agents["u"]
    pts = (a.lidar_pose[:3, :3] @ a.lidar.xyz.T.astype(np.float64)).T + a.lidar_pose[:3, 3]
    assert (pts[a.lidar.semantic_class == WATER][:, 0] > 200.0).sum() > 100
    assert (a.top_view.semantic == WATER).mean() > 0.95


def _port_entry_with(route: list[list[float]]) -> tuple[Any, Any]:
    """``port_entry`` with ``usv_1`` on ``route``, and its map."""
    raw = yaml.safe_load((ROOT / "scenarios" / "port_entry.yaml").read_text())
    raw["vessels"][0]["route"] = route
    sc = load_scenario(raw)
    return sc, mmusv.Simulation(sc).world


def test_a_route_near_the_maps_edge_is_not_said_to_near_a_shore() -> None:
    sc, world = _port_entry_with([[-170.0, -110.0], [-170.0, -990.0]])
    # Independently: the nearest land or structure to the route's end is far; the map's edge is 10 m away.
    end = np.array([-170.0, -990.0])
    land = [*world.priors.land, *world.priors.structure_boundaries]
    assert min(shapely.distance(p, shapely.Point(end)) for p in land) > 400.0
    with pytest.warns(MmusvWarning):
        found = check_routes(sc, world, source="port.yaml")
    shore = [m for m in found if "shore_clearance" in m]
    assert len(shore) == 1, found
    assert "of the map's edge (hull)" in shore[0] and "the shore" not in shore[0], shore[0]
    assert "(the map spans x -1000..1000 m, y -1000..1000 m)" in shore[0]


def test_a_route_near_land_is_still_said_to_near_the_shore() -> None:
    # West of the port, north towards the natural coast (its shallows begin at y = 230 there).
    sc, world = _port_entry_with([[-800.0, -300.0], [-800.0, 218.0]])
    with pytest.warns(MmusvWarning):
        found = check_routes(sc, world, source="port.yaml")
    shore = [m for m in found if "shore_clearance" in m]
    assert shore and "of the shore (hull)" in shore[0], found


def _building_footprints(world: Any) -> int:
    """Separate footprints (shapely) of the port's BUILDING faces: each building and each breakwater head light."""
    m = world.static_meshes["port_structures"]
    tri = m.vertices[m.faces[m.classes == int(SemanticClass.BUILDING)]][:, :, :2]
    polys = [p.buffer(0.01) for p in shapely.polygons(tri) if p.area > 1e-6]
    return len(shapely.get_parts(shapely.union_all(polys)))


def test_a_set_number_of_channel_buoy_pairs_is_built_or_refused() -> None:
    # The documented layout: pairs 150 m apart from 70 m off the breakwater arms, the last 40 m inside the edge.
    half, q, hd = 1000.0, 250.0, 420.0
    fit = int(np.floor(((q - hd - 70.0) - (-half + 40.0)) / 150.0)) + 1
    with pytest.raises(MapConfigError) as info:
        generate_map("port", seed=3, n_channel_buoy_pairs=fit + 1)
    assert info.value.field == "n_channel_buoy_pairs" and f"at most {fit} " in str(info.value)
    assert len(generate_map("port", seed=3, n_channel_buoy_pairs=fit).priors.buoys) == 2 * fit


def test_buildings_are_as_many_as_fit_and_said_so() -> None:
    w = generate_map("port", seed=0, extent_m=800, n_moored=1)  # no room behind the quay of an 800 m port
    assert _building_footprints(w) == 2 and w.params.n_buildings == 8  # the two breakwater head lights only
    assert _building_footprints(generate_map("port", seed=3, n_buildings=200)) == 84 + 2
    src = inspect.getsource(PortParams)  # the knob's attribute docstring
    doc = src[src.index("n_buildings: int") :].split('"""')[1]
    assert "at most this many" in doc and "none" in doc and "84" in doc


@pytest.mark.parametrize(("grid", "side"), [(5.0, "north"), (20.0, "north"), (10.0, "east")])
def test_the_quay_face_stands_where_the_docs_say(grid: float, side: str) -> None:
    w = generate_map("port", seed=3, grid_m=grid, coast_side=side, n_moored=0)
    m = w.static_meshes["port_structures"]
    tri = m.vertices[m.faces[m.classes == int(SemanticClass.PORT_STRUCTURE)]]
    top = tri[np.all(np.abs(tri[:, :, 2] - w.params.quay_height_m) < 1e-6, axis=1)]  # the quay's and piers' decks
    deck = shapely.union_all([p for p in shapely.polygons(top[:, :, :2]) if p.area > 1e-6])
    across = [(-250.0, 0.0), (-250.0, 1000.0)] if side == "north" else [(0.0, -250.0), (1000.0, -250.0)]
    face = shapely.get_coordinates(deck.intersection(shapely.LineString(across)))[:, 1 if side == "north" else 0].min()
    assert face == pytest.approx(w.params.coast_offset_m - grid - 1.0, abs=1e-6)
    src = inspect.getsource(PortParams)
    doc = src[src.index("coast_offset_m: float") :].split('"""')[1]
    assert "``grid_m`` (its effective value) + 1 m seaward" in doc and "244 m" in doc and "229 m" in doc


def test_island_radius_is_the_radius_the_island_is_drawn_in() -> None:
    radii = []
    for seed in range(12):
        w = generate_map("island", seed=seed, n_islands=2, island_radius_m=[100, 120], coast_roughness=0.0)
        radii += [np.sqrt(p.area / np.pi) for p in w.priors.land]
    r = np.array(radii)
    assert len(r) == 24 and r.max() <= 121.0 and r.min() >= 0.75 * 100.0 - 2.0
    assert (r < 100.0).sum() >= 12  # most lie below the range: not the mean coast radius
    src = inspect.getsource(IslandParams)
    doc = src[src.index("island_radius_m: tuple") :].split('"""')[1]
    assert "mean coast radius ``0.75 R`` to ``R``" in doc and "Range of mean coast radii" not in doc


def _hull(asset: str, x: float, y: float, yaw: float) -> Any:
    """The hull rectangle (shapely) of ``asset`` at ``(x, y, yaw)``: its library length and beam, centred."""
    a = get_asset(asset)
    return shapely.affinity.rotate(
        shapely.box(x - a.length / 2, y - a.beam / 2, x + a.length / 2, y + a.beam / 2),
        yaw,
        origin=(x, y),
        use_radians=True,
    )


def test_a_route_through_a_moored_ship_is_refused() -> None:
    sc, world = _port_entry_with([[-170.0, -110.0], [-170.0, -30.0], [-120.0, 40.0]])
    yacht = next(i for i, v in enumerate(sc.vessels) if v.id == "yacht")
    raw = sc.model_dump(mode="json", exclude_unset=True)
    raw["vessels"][yacht]["route"] = [[-120.0, 226.0], [-60.0, 226.0]]
    sc = load_scenario(raw)
    asset, (x, y, yaw) = world.moored[3]
    # Independently: the yacht's hull rectangle at its start overlaps the moored ferry's.
    assert asset == "ropax_ferry_90m"
    assert _hull("motor_yacht_20m", -120.0, 226.0, 0.0).intersection(_hull(asset, x, y, yaw)).area > 50.0
    with pytest.raises(mmusv.ConfigError) as info:
        check_routes(sc, world, source="port.yaml")
    msg = str(info.value)
    assert msg.startswith("port.yaml: hulls_intersect: the hulls of yacht and moored_03 (a ropax_ferry_90m moored at")
    assert f"(vessels[{yacht}].route)" in msg
    # The editor's map says the same, as an error on the yacht (its route is what to move).
    hits = [p for p in evaluate(raw)["problems"] if p["check"] == "hulls_intersect"]
    assert len(hits) == 1 and hits[0]["severity"] == "error" and hits[0]["vessels"] == ["yacht"]
    assert hits[0]["field"] == f"vessels[{yacht}]" and "moored_03" in hits[0]["message"]
    # Alongside the same ship, 12 m off its side, it is a close pass (a warning), not an intersection.
    raw["vessels"][yacht]["route"] = [[-120.0, 212.0], [-60.0, 212.0]]
    assert not _hull("motor_yacht_20m", -120.0, 212.0, 0.0).intersects(_hull(asset, x, y, yaw))
    with pytest.warns(MmusvWarning):
        check_routes(load_scenario(raw), world, source="port.yaml")


def _face_centroids(mesh: Any, cls: SemanticClass) -> tuple[np.ndarray, np.ndarray]:
    """Centroids ``(F, 3)`` and unit normals ``(F, 3)`` of ``mesh``'s faces of class ``cls``."""
    tri = mesh.vertices[mesh.faces[mesh.classes == int(cls)]]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    return tri.mean(axis=1), n / np.linalg.norm(n, axis=1, keepdims=True)


def test_the_classes_of_the_world_are_what_semantic_class_says() -> None:
    doc = SemanticClass.__doc__ or ""
    for words in ("lights on its breakwater heads", "ships moored in a port", "reach less than 2 m under the surface"):
        assert words in doc
    port = generate_map("port", seed=3)
    ps = port.static_meshes["port_structures"]
    # BUILDING: the warehouses stand on land; the rest are the two head lights, 2.5 m columns on the breakwater arms.
    c, _ = _face_centroids(ps, SemanticClass.BUILDING)
    wet = port.heightfield.sample(c[:, :2]) < 0.0
    assert wet.any()
    lights = shapely.get_parts(shapely.union_all(shapely.buffer(shapely.points(c[wet, :2]), 0.5)))
    assert len(lights) == 2 and all(shapely.minimum_bounding_radius(g) <= 3.0 for g in lights)
    arms, _ = _face_centroids(ps, SemanticClass.PORT_STRUCTURE)
    for g in lights:
        assert np.min(np.hypot(*(arms[:, :2] - np.asarray(g.centroid.coords[0])).T)) < 15.0
    # CONTAINER: on the port's land; the container ship's own stacks are VESSEL.
    c, _ = _face_centroids(ps, SemanticClass.CONTAINER)
    assert len(c) and (port.heightfield.sample(c[:, :2]) > 0.0).all()
    assert set(np.unique(get_asset("container_ship_300m").mesh.classes)) == {int(SemanticClass.VESSEL)}
    # VEGETATION: gentle slopes (normal z >= 0.6) above 2.5 m over the port's land (quay height - 0.3), 4 m on islands.
    for world, above in ((port, port.params.quay_height_m - 0.3 + 2.5), (generate_map("island", seed=4), 4.0)):
        c, n = _face_centroids(world.static_meshes["terrain"], SemanticClass.VEGETATION)
        assert len(c) and (n[:, 2] >= 0.6).all() and (c[:, 2] > above).all()
        t = world.static_meshes["terrain"]
        cells = t.vertices[t.faces][:, :, 2].reshape(-1, 6)  # two triangles a grid cell, in order
        assert (cells.max(axis=1) > -2.0).all() and cells.min() < -2.0  # every cell reaches above 2 m under
    # BUOY: every face within a float's 1.2 m of a listed buoy, and every buoy drawn.
    c, _ = _face_centroids(port.static_meshes["buoys"], SemanticClass.BUOY)
    d = np.hypot(*(c[:, None, :2] - port.priors.buoys[None, :, :]).transpose(2, 0, 1))
    assert (d.min(axis=1) <= 1.2).all() and (d.min(axis=0) <= 1.2).all()


def test_a_small_port_with_default_knobs_builds_as_many_moored_ships_as_fit() -> None:
    for seed in range(3):
        w = generate_map("port", seed=seed, extent_m=600)  # refused before, for every seed: n_moored=4 did not fit
        k = len(w.moored)
        assert 0 < k < 4 and w.params.n_moored == k and "n_moored" not in w.params.model_dump(exclude_unset=True)
        # Independently: no hull (the library's rectangles) overlaps the port's structures or another hull.
        hulls = [_hull(a, x, y, yaw) for a, (x, y, yaw) in w.moored]
        m = w.static_meshes["port_structures"]
        solid = shapely.union_all([p for p in shapely.polygons(m.vertices[m.faces][:, :, :2]) if p.area > 1e-6])
        assert not any(h.intersects(solid) for h in hulls)
        assert not any(a.intersects(b) for i, a in enumerate(hulls) for b in hulls[i + 1 :])
        # The number it says gives the same map; one more, set, is refused naming the most that fit.
        again = generate_map("port", seed=seed, extent_m=600, n_moored=k)
        assert again.moored == w.moored and again.priors.buoys.tobytes() == w.priors.buoys.tobytes()
        with pytest.raises(MapConfigError, match=f"n_moored={k + 1} .*at most {k} "):
            generate_map("port", seed=seed, extent_m=600, n_moored=k + 1)


def test_moored_hulls_are_compared_in_bounded_memory(monkeypatch: pytest.MonkeyPatch) -> None:
    """The check holds a block of time samples at a time (``_PAIR_BLOCK`` distances), not every sample x vessel x
    moored ship at once (2.5e8 distances at the sample budget with 50 moored ships); the findings are the same."""
    import tracemalloc

    import mmusv.generate.checks as checks
    from mmusv.generate.mapctx import MapContext
    from mmusv.scenario_checks import scenario_samples

    sc, world = _port_entry_with([[-170.0, -110.0], [-170.0, -30.0], [-120.0, 40.0]])
    raw = sc.model_dump(mode="json", exclude_unset=True)
    raw["acquisition"]["frames"] = 2000
    raw["vessels"][5]["route"] = [[-190.0, 226.0], [200.0, 226.0]]  # the yacht through the moored ferry
    s = scenario_samples(load_scenario(raw), MapContext(world))
    whole = [f.message for f in checks.MooredHullsIntersect().findings(s)]
    monkeypatch.setattr(checks, "_PAIR_BLOCK", 1024)
    tracemalloc.start()
    try:
        blocks = [f.message for f in checks.MooredHullsIntersect().findings(s)]
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert blocks == whole and len(whole) == 2 and "moored_03" in whole[0]  # the ferry, then a fishing boat
    assert peak < 2_000_000, peak  # 8.5 MB for the 2,000 x 8 x 4 distances at once


@pytest.mark.parametrize("width", [None, 100.0])
def test_the_harbour_entrance_is_as_wide_as_the_docs_say(width: float | None) -> None:
    w = generate_map("port", seed=3, n_moored=0, **({} if width is None else {"entrance_width_m": width}))
    p = w.params
    y_out = float(p.coast_offset_m) - float(p.harbour_depth_m)  # the line of the outer arms
    m = w.static_meshes["port_structures"]
    tri = m.vertices[m.faces[m.classes == int(SemanticClass.PORT_STRUCTURE)]]
    arms = shapely.union_all([g for g in shapely.polygons(tri[:, :, :2]) if g.area > 1e-6])
    cut = sorted(
        g.bounds for g in shapely.get_parts(arms.intersection(shapely.LineString([(-2e3, y_out), (2e3, y_out)])))
    )
    gaps = [b[0] - a[2] for a, b in itertools.pairwise(cut)]
    assert len(gaps) == 1 and gaps[0] == pytest.approx(float(p.entrance_width_m) - 38.0, abs=1e-6)
    src = inspect.getsource(PortParams)
    doc = src[src.index("entrance_width_m: float") :].split('"""')[1]
    assert "``entrance_width_m - 38`` m: 162 m by default" in doc


def test_island_summits_stand_within_the_relief_the_docs_give() -> None:
    summits = []
    for seed in range(5):
        w = generate_map("island", seed=seed, n_islands=2, island_radius_m=[200, 250], island_height_m=[40, 40])
        xs, ys = w.heightfield.axes()
        gx, gy = np.meshgrid(xs, ys)
        summits += [float(w.heightfield.z[shapely.contains_xy(p, gx, gy)].max()) for p in w.priors.land]
    assert min(summits) >= 0.65 * 40.0 and max(summits) <= 1.35 * 40.0 and max(summits) > 40.0
    src = inspect.getsource(IslandParams)
    doc = src[src.index("island_height_m: tuple") :].split('"""')[1]
    assert "relief adds up to 35 %" in doc and "34-47 m" in doc
