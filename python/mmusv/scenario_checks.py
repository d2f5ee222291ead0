"""Checks of a hand-written scenario against its map, with the generator's own named checks.

:func:`check_routes` runs, on the scenario's routes and motion, the checks ``mmusv generate`` applies to every
scenario it writes (:mod:`mmusv.generate.checks`): ``in_water`` (every vessel's centre on navigable water,
along the whole route and at every sampled time) is an error, since a vessel sailing over land makes every
label wrong, and so is ``hulls_intersect`` (two hulls running into each other, a ship moored in the port among
them: a LiDAR inside the other hull sees only its inside); ``shore_clearance``, ``structure_clearance`` and
``separation`` are warnings (a close pass can be what a user wants). ``mmusv run --no-checks`` and
``mmusv.run(..., checks=False)`` skip them.

:func:`check_mounts` warns about sensor mounts far from their hull (a units mistake: millimetres for metres).
:func:`check_lidar_water` warns about a LiDAR's flat-sea water knobs (``water_probability`` and the three others of
:class:`~mmusv.sensors.config.LidarConfig`) set on the physical sea, where they change nothing but for both
probabilities 0, which switch the water returns off.
:func:`check_top_view_land` refuses a top view lower than the land within its view (it drew that land as water;
:func:`top_view_land` finds them, for ``mmusv run`` and the editor).
``under_keel`` (:func:`keel_findings`, a warning of :func:`check_routes` and a finding of :func:`map_findings`): a
vessel whose draft reaches the seabed under it at some frame (``in_water`` takes every hull's water alike, 2 m deep:
a 300 m ship could sail a port's shallows with its keel in the floor).
:func:`check_rain_visibility` warns about a visibility given clearer than its rain's drops alone allow.
:func:`check_sensors` warns about a scenario that records no sensor at all: no vessel with ``role: usv``, or USVs
whose rigs switch every sensor off (``preset: lidar_only`` with ``lidar: null``); such a run records the world state
and the boxes only, which may be meant (ground-truth trajectories), so it is a warning.
Warnings are :class:`MmusvWarning` through :mod:`warnings`; the CLI prints each as one line.

:func:`map_findings` is what the scenario editor (``mmusv editor``) shows: the same samples and named checks, plus
the frame-based ones (sensing range at the USVs' LiDAR range, cooperation distance, line of sight), every failure
with the vessels and the place it concerns (:class:`~mmusv.generate.checks.Finding`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mmusv.errors import ConfigError

if TYPE_CHECKING:
    from mmusv.config import Scenario
    from mmusv.generate.checks import Finding
    from mmusv.generate.mapctx import MapContext
    from mmusv.generate.samples import Samples
    from mmusv.generate.spec_models import GenerationSpec
    from mmusv.sensors.config import RigConfig
    from mmusv.simulation import Simulation
    from mmusv.world.maps import MapWorld

__all__ = [
    "LIDAR_WATER_KNOBS",
    "MOUNT_WARN_FACTOR",
    "SHARP_TURN_RATIO",
    "MapFinding",
    "MmusvWarning",
    "TopViewLand",
    "check_lidar_water",
    "check_mounts",
    "check_rain_visibility",
    "check_routes",
    "check_sensors",
    "check_top_view_land",
    "keel_findings",
    "map_check_spec",
    "map_findings",
    "scenario_samples",
    "sensing_range_m",
    "sharp_turns",
    "top_view_land",
]

MOUNT_WARN_FACTOR = 2.0
"""A mount farther than this many hull lengths (at least 10 m) from the hull's box gets a warning."""


class MmusvWarning(UserWarning):
    """A scenario that runs but is probably not what was meant (a close pass, a far-away mount)."""


def scenario_samples(scenario: Scenario, ctx: MapContext, spec: GenerationSpec | None = None) -> Samples:
    """The generator's samples (:func:`~mmusv.generate.samples.take_samples`) of a hand-written scenario: the first
    USV is the ego, every other vessel a role target; ``spec`` gives the thresholds (default: the generator's)."""
    from mmusv.generate.sampler import CandidateMeta
    from mmusv.generate.samples import take_samples
    from mmusv.generate.spec_models import GenerationSpec

    usvs = [v.id for v in scenario.vessels if v.role == "usv"]
    targets = tuple(v.id for v in scenario.vessels if v.role != "usv")
    ego = usvs[0] if usvs else scenario.vessels[0].id
    meta = CandidateMeta(
        combination="scenario",
        family="scenario",
        difficulty="scenario",
        attempt=0,
        ego=ego,
        cooperating=tuple(usvs[1:]),
        targets=targets,
        primary=targets[0] if targets else ego,
        ranged=(),
        distractors=(),
        range_m=(0.0, math.inf),
        occlusion_share=None,
    )
    if spec is None:
        spec = GenerationSpec.model_validate({"combinations": [{"family": "crossing"}]})
    return take_samples(scenario, meta, ctx, spec)


def check_routes(scenario: Scenario, world: MapWorld, *, source: str) -> list[str]:
    """Runs the generator's ``in_water`` check (an error) and clearance/separation checks and ``under_keel``
    (:func:`keel_findings`) (warnings, also returned) on ``scenario`` sailing on ``world``; ``source`` names the file
    in messages.

    The checks sample the scenario's whole acquisition (:func:`mmusv.run` passes it cut to the frames it runs); a
    scenario whose checks would take more than :data:`~mmusv.generate.samples.MAX_CHECK_SAMPLES` samples is refused
    (a ``ConfigError`` that says how many and how to skip them) before anything is sampled."""
    from mmusv.generate.checks import (
        HullsIntersect,
        InWater,
        MooredHullsIntersect,
        Separation,
        ShoreClearance,
        StructureClearance,
    )
    from mmusv.generate.mapctx import MapContext
    from mmusv.generate.samples import FEWER_TIMES, budget_problem, sample_counts
    from mmusv.generate.spec_models import GenerationSpec

    spec = GenerationSpec.model_validate({"combinations": [{"family": "crossing"}]})
    n_motion, n_route = sample_counts(scenario, spec)
    problem = budget_problem(scenario, n_motion=n_motion, n_route=n_route)
    if problem is not None:
        raise ConfigError(
            f"{source}: {problem} (they cover every frame that is run): skip them with --no-checks "
            f"(checks=False), run fewer frames (--frames), or {FEWER_TIMES}"
        )
    samples = scenario_samples(scenario, MapContext(world), spec)
    cons = spec.constraints
    index = {v.id: i for i, v in enumerate(scenario.vessels)}  # each finding names the vessel's field by its index
    stranded = InWater().findings(samples)
    if stranded:
        # Every vessel that leaves the water, each named by the field to edit.
        fails = "; ".join(f"{f.message} (vessels[{index[f.vessels[0]]}].route)" for f in stranded)
        raise ConfigError(f"{source}: in_water: {fails}; routes must stay on navigable water (--no-checks skips this)")
    crossing = HullsIntersect().findings(samples)
    if crossing:
        fails = "; ".join(
            f"{f.message} (vessels[{index[f.vessels[0]]}] and vessels[{index[f.vessels[1]]}])" for f in crossing
        )
        raise ConfigError(
            f"{source}: hulls_intersect: {fails}; move a route or a start_offset_m apart (--no-checks skips this)"
        )
    aground = MooredHullsIntersect().findings(samples)
    if aground:
        fails = "; ".join(f"{f.message} (vessels[{index[f.vessels[0]]}].route)" for f in aground)
        raise ConfigError(
            f"{source}: hulls_intersect: {fails}; keep the route off the moored ships (--no-checks skips this)"
        )
    found: list[str] = [f"{source}: sharp_turn: {m}" for m in sharp_turns(scenario, samples)]
    for check in (
        ShoreClearance(cons.shore_clearance),
        StructureClearance(cons.structure_clearance),
        Separation(cons.separation),
    ):
        msg = check.check(samples)
        if msg is not None:
            found.append(f"{source}: {check.name}: {msg}")
    found += [
        f"{source}: under_keel: vessels[{index[f.vessels[0]]}] {f.message}"
        for f in keel_findings(scenario, world, samples)
    ]
    for w in found:
        warnings.warn(w, MmusvWarning, stacklevel=2)
    return found


SHARP_TURN_RATIO = 0.1
"""A route whose path turns at a radius below this many hull lengths gets a warning (:func:`sharp_turns`): a
ship's turning circle is a few lengths across, the generator's tightest harbour turns are about 0.2 lengths, and a
reversal on the spot (a waypoint that doubles back) measures well under 0.01."""


def sharp_turns(scenario: Scenario, samples: Samples) -> list[str]:
    """One line per moving vessel whose route turns tighter than :data:`SHARP_TURN_RATIO` hull lengths somewhere:
    the path's radius there (its sample spacing over its heading change, from ``samples.geo``), where, and the
    waypoint nearest to it. The spline goes through every waypoint, so a waypoint that doubles back (or legs a few
    metres apart) makes a hull pivot on the spot, or a 300 m ship swing about at hundreds of degrees a second, and
    the boxes, wakes and headings follow. A warning: the motion is what the route says."""
    from mmusv.world.vessels import get_asset

    out = []
    for vi, v in enumerate(scenario.vessels):
        if v.static:
            continue
        length = get_asset(v.asset).length
        xy, yaw = samples.geo[:, vi], np.unwrap(samples.geo_yaw[:, vi])
        ds = np.hypot(*np.diff(xy, axis=0).T)
        turn = np.abs(np.diff(yaw))
        radius = np.full(len(ds), np.inf)
        np.divide(ds, turn, out=radius, where=turn > 1e-9)
        k = int(np.argmin(radius))
        if radius[k] >= SHARP_TURN_RATIO * length:
            continue
        at = (xy[k] + xy[k + 1]) / 2.0
        route = np.asarray(v.route, dtype=np.float64)
        d = np.hypot(*(route - at).T)
        d[[0, -1]] += 1e-6  # a doubling-back waypoint on top of an end is named as the turn's
        w = int(np.argmin(d))
        out.append(
            f"{v.id} turns at a radius of {radius[k]:.1f} m near ({at[0]:.0f}, {at[1]:.0f}) "
            f"(vessels[{vi}].route[{w}]), far tighter than its {length:g} m hull can (a ship turns in a few lengths; "
            f"this warns below {SHARP_TURN_RATIO:g} of one): widen the corner or spread the waypoints"
        )
    return out


def sensing_range_m(scenario: Scenario) -> float:
    """The largest LiDAR range (metres) of the scenario's USVs (a USV without ``rig`` carries the default rig);
    the default LiDAR range when no USV has a LiDAR."""
    from mmusv.sensors.config import LidarConfig, RigConfig

    ranges = [
        lidar.range_m
        for v in scenario.usvs
        if (lidar := (scenario.rigs[v.rig] if v.rig is not None else RigConfig()).lidar) is not None
    ]
    return max(ranges, default=LidarConfig().range_m)


@dataclass(frozen=True)
class MapFinding:
    """One failure of a named check on a scenario: ``check`` (``in_water``, ``shore_clearance``, ...),
    ``severity`` (``error``: ``mmusv run`` refuses the scenario; ``warning``: it runs) and the ``finding``."""

    check: str
    severity: str
    finding: Finding


def map_check_spec(scenario: Scenario) -> GenerationSpec:
    """The thresholds :func:`map_findings` applies: the generator's defaults, the sensing range at the USVs' LiDAR
    range (:func:`sensing_range_m`) and the line-of-sight check switched on."""
    from mmusv.generate.spec_models import GenerationSpec

    return GenerationSpec.model_validate(
        {
            "combinations": [{"family": "crossing"}],
            "constraints": {
                "sensing_range": {"range_m": sensing_range_m(scenario)},
                "line_of_sight": {"enabled": True},
            },
        }
    )


def map_findings(
    scenario: Scenario, ctx: MapContext, spec: GenerationSpec | None = None
) -> tuple[Samples, list[MapFinding]]:
    """The samples and every failure of the named checks on ``scenario`` sailing on ``ctx``'s map, in check order:
    ``in_water`` and ``hulls_intersect`` (errors, as in ``mmusv run``), then as warnings ``shore_clearance``,
    ``structure_clearance``, ``separation``, ``sensing_range`` (every target within range of a USV in a share of
    the frames), ``cooperation`` (each USV's nearest USV within a distance band) and ``line_of_sight`` (each
    target seen past the static map by a USV within range in a share of the frames) and ``under_keel`` (a keel that
    reaches the seabed at a frame, :func:`keel_findings`), with ``spec``'s thresholds (default
    :func:`map_check_spec`)."""
    from mmusv.generate.checks import (
        Cooperation,
        HullsIntersect,
        InWater,
        LineOfSight,
        MooredHullsIntersect,
        SensingRange,
        Separation,
        ShoreClearance,
        StructureClearance,
    )

    spec = spec if spec is not None else map_check_spec(scenario)
    samples = scenario_samples(scenario, ctx, spec)
    cons = spec.constraints
    checks = (
        InWater(),
        HullsIntersect(),
        MooredHullsIntersect(),
        ShoreClearance(cons.shore_clearance),
        StructureClearance(cons.structure_clearance),
        Separation(cons.separation),
        SensingRange(cons.sensing_range),
        Cooperation(cons.cooperation),
        LineOfSight(cons.line_of_sight),
    )
    found = [
        MapFinding(c.name, "error" if c.name in ("in_water", "hulls_intersect") else "warning", f)
        for c in checks
        for f in c.findings(samples)
    ]
    keels = keel_findings(scenario, ctx.world, samples)
    return samples, found + [MapFinding("under_keel", "warning", f) for f in keels]


def check_mounts(scenario: Scenario, *, source: str) -> list[str]:
    """Warns (and returns the warnings) for every sensor mount farther than :data:`MOUNT_WARN_FACTOR` hull
    lengths (at least 10 m) from its vessel's box."""
    from mmusv.sensors.mounts import mount_matrix
    from mmusv.world.vessels import get_asset

    found: list[str] = []
    for v in scenario.vessels:
        if v.role != "usv" or v.rig is None:
            continue
        rig = scenario.rigs[v.rig]
        asset = get_asset(v.asset)
        lo, hi = np.asarray(asset.bbox[0], dtype=float), np.asarray(asset.bbox[1], dtype=float)
        limit = max(MOUNT_WARN_FACTOR * asset.length, 10.0)
        for path, m in rig.mounts():
            where = f"rigs.{v.rig}.{path}"
            p = mount_matrix(asset, m, where=where)[:3, 3]  # the sensor origin in the body frame, as simulated
            dist = float(np.linalg.norm(np.maximum(np.maximum(lo - p, p - hi), 0.0)))
            if dist > limit:
                found.append(
                    f"{source}: {where} (vessel {v.id}) is {dist:.0f} m from the {asset.name} hull; xyz is in metres"
                )
    for w in found:
        warnings.warn(w, MmusvWarning, stacklevel=2)
    return found


def check_rain_visibility(scenario: Scenario, *, source: str) -> list[str]:
    """Warns (and returns the warning) when ``environment.visibility_m`` is given clearer than the drops of its rain
    alone allow: the visibility in rain of air otherwise clear, ``3 / σ_rain`` for Marshall–Palmer drops
    (:func:`mmusv.world.rain.visibility_in_rain`: 3.4 km at 4 mm/h, 1.1 km at 25, 0.7 km at 50). The visibility
    given is the air's whole extinction for the cameras and the LiDAR, the rain's drops included, and is kept; such
    a one lets them see through the rain as through clearer air (the LiDAR takes the rain through the visibility
    alone). A warning, not an error: real drop sizes stray from Marshall and Palmer's, and a test may hold the air
    fixed on purpose."""
    from mmusv.world.rain import visibility_in_rain

    env = scenario.environment
    found: list[str] = []
    if env.visibility_m is None:
        return found
    weather = env.resolve().weather
    if weather.rain_mm_per_h <= 0.0:
        return found
    limit = visibility_in_rain(math.inf, weather.rain_mm_per_h)
    if env.visibility_m > limit:
        found.append(
            f"{source}: environment.visibility_m = {env.visibility_m:g} is clearer than rain of "
            f"{weather.rain_mm_per_h:g} mm/h allows: its drops alone (Marshall-Palmer) limit the visibility to "
            f"{limit:.0f} m, and the cameras' air and the LiDAR take the visibility given, drops included; "
            "lower visibility_m, or leave it out (the weather's air with the rain's drops in it)"
        )
    for w in found:
        warnings.warn(w, MmusvWarning, stacklevel=2)
    return found


LIDAR_WATER_KNOBS = ("water_probability", "water_probability_per_wave_m", "water_range_m", "water_range_per_wave_m")
"""The :class:`~mmusv.sensors.config.LidarConfig` fields of the flat sea's empirical water returns."""


def check_lidar_water(scenario: Scenario, *, source: str) -> list[str]:
    """Warns (and returns the warnings) for every rig of a USV whose LiDAR sets one of :data:`LIDAR_WATER_KNOBS` to
    other than its default in a scenario on the physical sea (``environment.motion: physical``, the default): they
    are the flat sea's empirical rule (``motion: paper``), and over the physical sea the water returns follow the
    physical model (``sensors/lidar_water.rs``) whatever they are, but for ``water_probability`` and
    ``water_probability_per_wave_m`` both 0, which switch the water returns off on either sea (no warning then).
    Before, such a setting was ignored without a word."""
    from mmusv.sensors.config import LidarConfig

    found: list[str] = []
    if scenario.environment.motion != "physical":
        return found
    for name in sorted({v.rig for v in scenario.vessels if v.role == "usv" and v.rig is not None}):
        lidar = scenario.rigs[name].lidar
        if lidar is None:
            continue
        if lidar.water_probability == 0 and lidar.water_probability_per_wave_m == 0:
            continue  # no water returns on either sea: the ranges do not matter
        given = [(k, getattr(lidar, k)) for k in LIDAR_WATER_KNOBS]
        given = [(k, v) for k, v in given if v != LidarConfig.model_fields[k].default]
        if given:
            values = ", ".join(f"{k} = {v:g}" for k, v in given)
            it = ("it is", "changes") if len(given) == 1 else ("they are", "change")
            found.append(
                f"{source}: rigs.{name}.lidar: {values} {it[1]} nothing: {it[0]} the flat sea's water rule "
                "(environment.motion: paper), and on the physical sea (motion: physical, the default) the LiDAR's "
                "water returns follow the physical model (wave facets, whitecaps, wake foam); water_probability "
                "and water_probability_per_wave_m both 0 switch them off"
            )
    for w in found:
        warnings.warn(w, MmusvWarning, stacklevel=2)
    return found


@dataclass(frozen=True)
class TopViewLand:
    """A USV's top view lower than the land within its view (:func:`top_view_land`): the vessel's index in the
    scenario, the field to change, the message (without the file) and where the highest ground it sees stands
    (world ``x, y`` metres)."""

    index: int
    field: str
    message: str
    point: tuple[float, float]


def top_view_land(scenario: Scenario, world: MapWorld, positions: dict[int, np.ndarray]) -> list[TopViewLand]:
    """Every USV whose top view, from some of its ``positions`` (vessel index → ``(N, 2)`` world ``x, y`` of its
    origin), sees the map's ground (its heightfield: the islands, the port's land and hills) rising to or above the
    view's ``altitude_m`` within half its footprint's diagonal (and one grid step). The terrain is a surface seen
    from above: rays that start under it never meet it, so those pixels showed the water beneath (semantic water,
    the sea's instance) without a word. A ship or a structure taller than the top view stays itself in the picture
    (the camera sees its decks below the cut), so only the ground counts."""
    from scipy.spatial import cKDTree

    from mmusv.sensors.config import RigConfig

    hf = world.heightfield
    xs, ys = hf.axes()
    out: list[TopViewLand] = []
    for i, pos in sorted(positions.items()):
        v = scenario.vessels[i]
        tv = (scenario.rigs[v.rig] if v.rig is not None else RigConfig()).top_view
        if tv is None or not len(pos):
            continue
        high = hf.z >= tv.altitude_m
        if not high.any():
            continue
        iy, ix = np.nonzero(high)
        reach = 0.5 * tv.metres_per_pixel * math.hypot(*tv.resolution) + hf.spacing
        dist, _ = cKDTree(np.asarray(pos, dtype=np.float64)).query(
            np.column_stack([xs[ix], ys[iy]]), distance_upper_bound=reach
        )
        seen = np.isfinite(dist)
        if not seen.any():
            continue
        k = int(np.argmax(np.where(seen, hf.z[iy, ix], -np.inf)))
        top = float(hf.z[iy[k], ix[k]])
        field = f"rigs.{v.rig}.top_view.altitude_m" if v.rig is not None else "the default rig's top_view.altitude_m"
        message = (
            f"{field} = {tv.altitude_m:g}: the top view of {v.id!r} (vessels[{i}]) looks down from "
            f"{tv.altitude_m:g} m over land that rises to {top:.1f} m within its view: the ground above the camera is "
            f"not drawn, its pixels would show the water beneath it (semantic water); altitude_m must be above "
            f"{top:.1f} m (default 120)"
        )
        out.append(TopViewLand(i, field, message, (float(xs[ix[k]]), float(ys[iy[k]]))))
    return out


def check_top_view_land(sim: Simulation, frames: range, *, source: str) -> None:
    """Refuses a top view lower than the land it sees at some frame of ``frames`` (:func:`top_view_land`, the
    USVs' positions from the world state of every frame): a :class:`ConfigError` naming ``source``, the field and
    the height to pass."""
    positions = {
        a.index: np.array([sim.world_state(k).poses[a.index, :2] for k in frames]).reshape(-1, 2)
        for a in sim.agents
        if a.rig.top_view is not None and bool((sim.world.heightfield.z >= a.rig.top_view.altitude_m).any())
    }
    found = top_view_land(sim.scenario, sim.world, positions)
    if found:
        raise ConfigError(f"{source}: {found[0].message} (--no-checks skips this)")


def check_sensors(scenario: Scenario, *, source: str) -> list[str]:
    """Warns (and returns the warning) when no vessel of ``scenario`` carries a sensor: none has ``role: usv``,
    or every USV's rig has its LiDAR, radar and top view off and no camera. The run then records the world state
    (and each USV's boxes) only; before, it did so without a word."""
    usvs = [v for v in scenario.vessels if v.role == "usv"]
    found: list[str] = []
    if not usvs:
        found.append(
            f"{source}: no vessel has role: usv, so the recording holds no sensor data and no per-agent boxes, "
            "only the world state (give a vessel `role: usv` and a `rig`)"
        )
    else:
        empty = sorted({v.rig for v in usvs if v.rig is not None and _no_sensor(scenario.rigs[v.rig])})
        if len(empty) == len({v.rig for v in usvs}):
            rigs = ", ".join(f"rigs.{r}" for r in empty)
            found.append(
                f"{source}: {rigs} switch{'es' if len(empty) == 1 else ''} every sensor off (lidar, radar and "
                "top_view null, cameras empty), so the recording holds no sensor data, only the world state and "
                "the boxes"
            )
    for w in found:
        warnings.warn(w, MmusvWarning, stacklevel=2)
    return found


def _no_sensor(rig: RigConfig) -> bool:
    return rig.lidar is None and rig.radar is None and rig.top_view is None and not rig.cameras


KEEL_SPAN = 0.45
"""The keel's reach fore and aft of a hull's centre, as a share of its length (:func:`keel_findings`): a ship's flat
bottom runs most of its length, its draft all along it."""

KEEL_STEP_M = 10.0
"""The most metres between two points of a keel :func:`keel_findings` checks."""


def keel_findings(scenario: Scenario, world: MapWorld, samples: Samples) -> list[Finding]:
    """``under_keel``: every vessel of ``scenario`` whose draft (its hull particulars,
    :func:`mmusv.world.hydrostatics.hull_particulars`) reaches the seabed under its keel at some acquisition frame
    of ``samples`` (``Samples.frames``), the depth the map's heightfield's (the still water's; the sea floor of open
    water is 25 m down). The keel is the hull's centre line, :data:`KEEL_SPAN` of its length fore and aft of its
    centre, at the frame's heading, checked every :data:`KEEL_STEP_M` at most (the centre alone let a 330 m tanker
    stop with its centre over 25 m of water and its bow over 14 m, its draft 22.5 m, without a word). One finding
    per vessel, where it is shallowest (its first frame so, the centre first). The sensors do not see the floor (the
    terrain is drawn to 2 m below the surface), but the hull stands on it; a vessel off the map is ``in_water``'s."""
    from mmusv.generate.checks import Finding
    from mmusv.world.hydrostatics import hull_particulars
    from mmusv.world.vessels import get_asset

    port = " (a port's water is map.params.basin_depth_m deep, 14 m by default)" if world.kind == "port" else ""
    found: list[Finding] = []
    for v in scenario.vessels:
        length, _, draft, _, _ = hull_particulars(get_asset(v.asset))
        i = samples.index(v.id)
        xy, yaw = samples.frames[:, i], samples.frames_yaw[:, i]
        reach = KEEL_SPAN * length
        n = math.ceil(reach / KEEL_STEP_M)
        ahead = np.linspace(0.0, reach, n + 1)[1:] if n > 0 else np.zeros(0)
        offsets = np.concatenate([[0.0], ahead, -ahead])  # the centre first: it is named on a tie
        heading = np.stack([np.cos(yaw), np.sin(yaw)], axis=-1)
        points = xy[:, None, :] + offsets[None, :, None] * heading[:, None, :]  # (frames, points, 2)
        depth = -world.heightfield.sample(points.reshape(-1, 2)).reshape(points.shape[:2])
        if not np.isfinite(depth).any():
            continue
        k, j = np.unravel_index(int(np.nanargmin(depth)), depth.shape)
        if depth[k, j] < draft:
            x, y = (float(c) for c in points[k, j])
            off = float(offsets[j])
            where = "" if off == 0.0 else f" {abs(off):.0f} m {'ahead of' if off > 0 else 'astern of'} its centre"
            found.append(
                Finding(
                    f"{v.id} ({v.asset}, draft {draft:.1f} m) sails over {max(depth[k, j], 0.0):.1f} m of water at "
                    f"({x:.0f}, {y:.0f}) m in frame {k}: its keel is in the seabed{where}; route it over deeper "
                    f"water{port}, or give it a smaller asset",
                    (v.id,),
                    (x, y),
                )
            )
    return found
