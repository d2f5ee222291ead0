"""Every accepted scenario satisfies every enabled constraint, re-checked independently of mmusv.generate.checks.

The re-check re-implements the route geometry (centripetal Catmull-Rom through the waypoints, sampled every few
centimetres), samples the motion ~40x denser than the generator's check step, and measures clearances with
shapely against the map's vector layers (land polygons, structure footprints, moored hulls) using the hull
*rectangles* at their yaw (in motion, and along the whole route at the tangent heading), separation between hull
rectangles, and line of sight with its own ray casts.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import shapely
from mmusv.config import Scenario, load_scenario
from mmusv.generate import generate
from mmusv.motion import build_fleet
from mmusv.world.build import build_static_scene
from mmusv.world.maps import MapWorld, generate_map_from
from mmusv.world.vessels import get_asset

TOL = 1e-6

ISLAND_SPEC: dict[str, Any] = {
    "name": "recheck_island",
    "seed": 11,
    "map": {"type": "island", "seed": 4},
    "acquisition": {"frequency_hz": 2, "frames": 30},
    "environment": {"weather": ["clear", "fog"], "wave": ["W0", "W2"]},
    "usv": {"assets": ["usv_wamv", "usv_patrol_12m"]},
    "difficulties": {
        "easy": {"range_m": [80, 250]},
        "medium": {"range_m": [150, 500], "extra_targets": [1, 2], "extra_classes": ["small", "medium"]},
    },
    "combinations": [
        {"family": "crossing", "difficulty": "easy", "cooperating": 1, "targets": ["small", "medium"], "quota": 2},
        {"family": "head_on", "difficulty": "medium", "cooperating": 1, "targets": ["medium"], "quota": 2},
        {"family": "overtaking", "difficulty": "easy", "targets": ["small"], "quota": 1},
        {"family": "convoy", "difficulty": "medium", "cooperating": 1, "targets": ["medium", "small"], "quota": 2},
        {"family": "surround", "difficulty": "easy", "cooperating": 2, "targets": ["small"], "quota": 1},
        {"family": "occluded_by_island", "difficulty": "medium", "cooperating": 1, "targets": ["small"], "quota": 2},
    ],
    "constraints": {
        "shore_clearance": {"min_m": 12},
        "structure_clearance": {"min_m": 15},
        "separation": {"min_m": 18},
        "route_separation": {"min_m": 25, "pairs": ["usv-usv"]},
        "sensing_range": {"range_m": 1000, "min_share": 0.8, "targets": "all"},
        "cooperation": {"min_m": 20, "max_m": 800, "min_share": 1.0},
        "line_of_sight": {"enabled": True, "min_share": 0.5},
        "occlusion": {"min_occluded_share": 0.3, "min_visible_other_share": 0.5},
    },
}

PORT_SPEC: dict[str, Any] = {
    "name": "recheck_port",
    "seed": 5,
    "map": {"type": "port", "seed": 3},
    "acquisition": {"frequency_hz": 2, "frames": 40},
    "combinations": [
        {"family": "port_entry", "difficulty": "easy", "cooperating": 1, "targets": ["medium"], "quota": 2},
        {"family": "crossing", "difficulty": "easy", "targets": ["small"], "quota": 1},
    ],
    "constraints": {
        "shore_clearance": {"min_m": 10},
        "structure_clearance": {"min_m": 20},
        "separation": {"min_m": 15},
        "line_of_sight": {"enabled": True, "min_share": 0.5},
    },
}


# --------------------------------------------------------------------------------- independent geometry


def catmull_rom(waypoints: np.ndarray, per_segment: int = 400) -> np.ndarray:
    """Dense points on the open centripetal Catmull-Rom spline through ``waypoints`` (phantom end points)."""
    p = np.asarray(waypoints, dtype=np.float64)
    ext = np.vstack([2 * p[0] - p[1], p, 2 * p[-1] - p[-2]])
    u = np.linspace(0.0, 1.0, per_segment + 1)[:, None]
    out = []
    for i in range(len(p) - 1):
        p0, p1, p2, p3 = ext[i], ext[i + 1], ext[i + 2], ext[i + 3]
        d0, d1, d2 = (float(np.linalg.norm(b - a)) ** 0.5 for a, b in ((p0, p1), (p1, p2), (p2, p3)))
        m1 = (p1 - p0) / d0 - (p2 - p0) / (d0 + d1) + (p2 - p1) / d1
        m2 = (p2 - p1) / d1 - (p3 - p1) / (d1 + d2) + (p3 - p2) / d2
        c, e = d1 * m1, d1 * m2
        out.append((2 * p1 - 2 * p2 + c + e) * u**3 + (-3 * p1 + 3 * p2 - 2 * c - e) * u**2 + c * u + p1)
    return np.vstack(out)


def hull_rects(asset: str, poses: np.ndarray) -> np.ndarray:
    """Shapely hull rectangles (length x beam) at poses ``(T, 6)``."""
    a = get_asset(asset)
    corners = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]]) * [a.length / 2, a.beam / 2]
    c, s = np.cos(poses[:, 5]), np.sin(poses[:, 5])
    x = poses[:, None, 0] + c[:, None] * corners[None, :, 0] - s[:, None] * corners[None, :, 1]
    y = poses[:, None, 1] + s[:, None] * corners[None, :, 0] + c[:, None] * corners[None, :, 1]
    return shapely.polygons(np.stack([x, y], axis=-1))


_WORLDS: dict[tuple[str, int], MapWorld] = {}


def world_of(sc: Scenario) -> MapWorld:
    key = (sc.map.type, sc.map.seed)
    if key not in _WORLDS:
        _WORLDS[key] = generate_map_from(sc.map.params, seed=sc.map.seed)
    return _WORLDS[key]


def recheck(sc: Scenario, roles: dict[str, Any], cons: dict[str, Any]) -> None:
    """Asserts every constraint of ``cons`` (the spec's constraint block, defaults filled in) on ``sc``."""
    world = world_of(sc)
    pri = world.priors
    ids = [v.id for v in sc.vessels]
    idx = {v: i for i, v in enumerate(ids)}
    usvs = [i for i, v in enumerate(sc.vessels) if v.role == "usv"]
    t_last = (sc.acquisition.frames - 1) / sc.acquisition.frequency_hz
    vmax = max(v.speed_mps for v in sc.vessels)
    times = np.linspace(0.0, t_last, max(int(t_last * vmax / 0.05), 2) + 1)  # <= 5 cm between samples
    fleet = build_fleet(sc)
    dense = np.asarray(fleet.poses_at_times(times))
    frames = np.asarray(fleet.poses_at_times(np.arange(sc.acquisition.frames) / sc.acquisition.frequency_hz))
    routes = [catmull_rom(np.asarray(v.route)) for v in sc.vessels]
    for i, v in enumerate(sc.vessels):  # the motion runs on the re-implemented curve
        d = shapely.distance(shapely.linestrings(routes[i]), shapely.points(dense[:, i, :2]))
        assert float(np.max(d)) < 0.05, f"{v.id}: motion leaves the resampled route by {np.max(d)} m"

    land = shapely.union_all([*pri.land, *pri.structure_boundaries, *pri.moored_footprints])
    struct = shapely.union_all([*pri.structure_boundaries, *pri.moored_footprints])
    shapely.prepare(land)
    shapely.prepare(struct)
    for i, v in enumerate(sc.vessels):
        pts = np.vstack([routes[i], dense[:, i, :2]])
        # in_water: every route sample and position in the priors' water mask
        assert pri.is_water(pts).all(), f"{sc.name}: {v.id} leaves the water"
        rect = hull_rects(v.asset, dense[:, i])
        # the hull along the whole route, heading along the curve's tangent
        tangent = np.gradient(routes[i], axis=0)
        along = np.zeros((len(routes[i]), 6))
        along[:, :2] = routes[i]
        along[:, 5] = np.arctan2(tangent[:, 1], tangent[:, 0])
        rect_route = hull_rects(v.asset, along)
        for name, geom in (("shore_clearance", land), ("structure_clearance", struct)):
            c = cons[name]
            if not c["enabled"] or geom.is_empty:
                continue
            assert not shapely.dwithin(geom, rect, c["min_m"] - TOL).any(), (
                f"{sc.name}: {v.id} {name} (hull) at some time"
            )
            assert not shapely.dwithin(geom, rect_route, c["min_m"] - TOL).any(), f"{sc.name}: {v.id} {name} on route"

    if cons["separation"]["enabled"]:
        rects = [hull_rects(v.asset, dense[:, i]) for i, v in enumerate(sc.vessels)]
        for i in range(len(ids)):
            for j in range(i + 1, len(ids)):
                d = float(np.min(shapely.distance(rects[i], rects[j])))
                assert d >= cons["separation"]["min_m"] - TOL, f"{sc.name}: {ids[i]}-{ids[j]} {d:.2f} m apart"
    if cons["route_separation"]["enabled"] and "usv-usv" in cons["route_separation"]["pairs"]:
        for a in usvs:
            for b in usvs:
                if a < b:
                    d = float(shapely.distance(shapely.linestrings(routes[a]), shapely.linestrings(routes[b])))
                    assert d >= cons["route_separation"]["min_m"] - TOL, (
                        f"{sc.name}: routes {ids[a]}-{ids[b]} {d:.2f} m"
                    )

    xy = frames[:, :, :2]
    ego = idx[roles["ego"]]
    if cons["target_range"]["enabled"]:
        lo, hi = roles["range_m"]
        for t in roles["ranged"]:
            dmin = float(np.min(np.hypot(*(xy[:, ego] - xy[:, idx[t]]).T)))
            assert lo - TOL <= dmin <= hi + TOL, f"{sc.name}: {t} closest approach {dmin:.1f} m"
    sens = cons["sensing_range"]
    if sens["enabled"]:
        tids = roles["targets"] + (roles["distractors"] if sens["targets"] == "all" else [])
        for t in tids:
            near = [np.hypot(*(xy[:, u] - xy[:, idx[t]]).T) <= sens["range_m"] for u in usvs]
            assert np.mean(np.any(near, axis=0)) >= sens["min_share"] - TOL, f"{sc.name}: {t} out of sensing range"
    coop = cons["cooperation"]
    if coop["enabled"] and len(usvs) > 1:
        for u in usvs:
            nearest = np.min([np.hypot(*(xy[:, u] - xy[:, w]).T) for w in usvs if w != u], axis=0)
            ok = (nearest >= coop["min_m"] - TOL) & (nearest <= coop["max_m"] + TOL)
            assert ok.mean() >= coop["min_share"] - TOL, f"{sc.name}: {ids[u]} cooperation distance"

    # line of sight, with this test's own rays: sensor 2.5 m up, target point at half its above-water height
    scene = build_static_scene(world, include_water=False).scene

    def blocked(u: int, t: int) -> np.ndarray:
        a = get_asset(sc.vessels[t].asset)
        org = np.column_stack([xy[:, u], np.full(len(xy), 2.5)])
        dst = np.column_stack([xy[:, t], np.full(len(xy), max(a.height - a.draft, 0.2) / 2)])
        seg = dst - org
        n = np.linalg.norm(seg, axis=1)
        hits = scene.cast_rays(org.astype(np.float32), (seg / n[:, None]).astype(np.float32), max_range=float(n.max()))
        out: np.ndarray = np.isfinite(hits.distance) & (hits.distance < n - 1e-3)
        return out

    def visible(u: int, t: int) -> np.ndarray:
        out: np.ndarray = ~blocked(u, t) & (np.hypot(*(xy[:, u] - xy[:, t]).T) <= sens["range_m"])
        return out

    if cons["line_of_sight"]["enabled"]:
        for t in roles["targets"]:
            seen = np.any([visible(u, idx[t]) for u in usvs], axis=0)
            assert seen.mean() >= cons["line_of_sight"]["min_share"] - TOL, f"{sc.name}: {t} not seen enough"
    if cons["occlusion"]["enabled"] and roles["occlusion_share"] is not None:
        p = idx[roles["primary"]]
        hidden = blocked(ego, p)
        assert hidden.mean() >= roles["occlusion_share"] - TOL, f"{sc.name}: primary hidden {hidden.mean():.0%}"
        seen = np.any([visible(u, p) for u in usvs if u != ego], axis=0)
        assert seen[hidden].mean() >= cons["occlusion"]["min_visible_other_share"] - TOL


def _constraints(spec: dict[str, Any]) -> dict[str, Any]:
    from mmusv.generate.spec import load_spec

    return load_spec(spec).constraints.model_dump()


@pytest.mark.parametrize("spec", [ISLAND_SPEC, PORT_SPEC], ids=["island", "port"])
def test_every_accepted_scenario_passes_an_independent_dense_recheck(spec: dict[str, Any], tmp_path: Path) -> None:
    report = generate(spec, tmp_path)
    assert report.all_met, [c.why() for c in report.combos]
    data = json.loads((tmp_path / "report.json").read_text())
    cons = _constraints(spec)
    files = sorted(tmp_path.glob("*.yaml"))
    assert len(files) == data["accepted"] == sum(c["quota"] for c in spec["combinations"])
    for entry in data["scenarios"]:
        sc = load_scenario(tmp_path / entry["file"])
        assert sc.name == Path(entry["file"]).stem
        recheck(sc, entry["roles"], cons)


def test_the_recheck_is_not_vacuous(tmp_path: Path) -> None:
    """Scenarios generated with loose thresholds fail the re-check run with strict ones."""
    spec = dict(ISLAND_SPEC, combinations=ISLAND_SPEC["combinations"][:2])
    generate(spec, tmp_path)
    data = json.loads((tmp_path / "report.json").read_text())
    strict = _constraints(spec)
    for key, tightened in (
        ("separation", {"min_m": 400.0}),
        ("shore_clearance", {"min_m": 300.0}),
        ("route_separation", {"min_m": 500.0}),
        ("sensing_range", {"range_m": 20.0}),
    ):
        cons = {k: dict(v) for k, v in strict.items()}
        cons[key].update(tightened)
        failures = 0
        for entry in data["scenarios"]:
            try:
                recheck(load_scenario(tmp_path / entry["file"]), entry["roles"], cons)
            except AssertionError:
                failures += 1
        assert failures > 0, key
