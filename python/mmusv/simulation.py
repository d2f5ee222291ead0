"""A scenario made runnable: map, vessels, motion and every USV's sensors, captured on one frozen state per frame.

``Simulation(cfg)`` builds the world once (map meshes, one mesh per vessel asset, the fleet's routes and waves,
the native sensors with their ray patterns). ``capture(frame)`` sets every vessel's pose at ``t_k = k / f``
(only the scene's top level is rebuilt) and then runs every sensor of every USV on that one state, so there is
no skew between sensors or agents. The state at frame ``k`` is a pure function of (scenario, seed, k).

Frames: world x east, y north, z up (metres); vessel/sensor body frames x forward, y left, z up. Sensor poses
are ``(4, 4)`` float64 sensor → world matrices. What a capture gives (world state, agent captures) is defined in
:mod:`mmusv.captures` and re-exported here.

One simulation moves one scene: its calls that move it (``capture``, ``set_frame``, ``prefetch_frame``,
``set_sea_surface``) take turns, also across a fork (:mod:`mmusv.turns`), so threads sharing a simulation each get
the frame they asked for. A simulation pickles as what rebuilds it (its scenario, the map it was given, the sea it
was set to), so it can be handed to spawned processes (``multiprocessing``, a PyTorch ``DataLoader`` with
``multiprocessing_context="spawn"``): each rebuilds the world once and captures the same bytes.
"""

from __future__ import annotations

import math
from collections.abc import Collection
from functools import cached_property
from typing import Any

import numpy as np
import numpy.typing as npt

from mmusv import arguments
from mmusv._native import core
from mmusv.agents import Agent, build_agent, frozen
from mmusv.captures import AgentCapture, FrameCapture, SensorMount, VesselInfo, WorldState
from mmusv.config import Scenario, VesselConfig, load_scenario
from mmusv.errors import ConfigError
from mmusv.motion import build_fleet, build_moored_fleet
from mmusv.scenario_assets import holding_library
from mmusv.sea_surface import MAX_SURFACE_TILES, SURFACE_TILE_M, SeaState, check_sea, surface_taper, surface_tiles
from mmusv.seeds import sensor_seed
from mmusv.sensors.camera import CameraImages
from mmusv.sensors.config import RigConfig
from mmusv.sensors.env import sensor_env
from mmusv.sensors.lidar import LidarPoints
from mmusv.sensors.mounts import rpy_matrix
from mmusv.sensors.radar import RadarReturns, ppi_request
from mmusv.thread_env import check_thread_environment
from mmusv.turns import one_at_a_time, take_turns
from mmusv.world.build import WorldScene, build_world_scene, pose_matrices
from mmusv.world.buoys import buoy_matrices
from mmusv.world.environment import Environment
from mmusv.world.hydrostatics import hull_particulars
from mmusv.world.maps import MapWorld, generate_map_from
from mmusv.world.vessels import VesselAsset, get_asset

__all__ = [
    "Agent",
    "AgentCapture",
    "FrameCapture",
    "SensorMount",
    "Simulation",
    "VesselInfo",
    "WorldState",
    "sensor_seed",
]

SENSOR_KINDS = ("lidar", "cameras", "top_view", "radar")


class Simulation:
    """A runnable scenario (see the module docstring). ``source``: a path, a dict or a :class:`Scenario`.

    ``vessels``: a :class:`VesselInfo` per vessel, in world-state row order (scenario vessels, then moored ships);
    ``assets``: the :class:`~mmusv.world.vessels.VesselAsset` of each asset name it uses, as they were when it was
    built (a scenario read later may hold another under the same name); ``agents``: the USVs (:class:`Agent`);
    ``ws``: the scene and its instance ids; ``sea``: the physical sea (``None``: flat water).
    """

    def __init__(self, source: Any, *, world: MapWorld | None = None) -> None:
        if world is not None and not isinstance(world, MapWorld):
            raise ConfigError(
                f"world = {arguments.shown(world)}: must be a MapWorld (mmusv.world.maps.generate_map) or None (the "
                "scenario's map)"
            )
        check_thread_environment()  # RAYON_NUM_THREADS / POLARS_MAX_THREADS, before the first thread pool starts
        self._lock = take_turns(self)
        self._given_world = world
        self._sea_set: tuple[SeaState | None] | None = None  # the sea of set_sea_surface, when it was called
        # The library is held for this scenario from its reading until every asset it uses has been looked up
        # (scenario_assets.holding_library): another thread reading another scenario waits.
        with holding_library():
            self.scenario: Scenario = load_scenario(source)
            sc = self.scenario
            self.environment: Environment = sc.environment.resolve()
            self.world: MapWorld = world if world is not None else generate_map_from(sc.map.params, seed=sc.map.seed)
            # The assets it is built with, by name, kept: the library is one per process, and a scenario read later
            # may hold another asset under a name of these (a user's own `skiff`) when a wake or a label asks again.
            used = {v.asset for v in sc.vessels} | {name for name, _ in self.world.moored}
            self.assets: dict[str, VesselAsset] = {name: get_asset(name) for name in sorted(used)}
            self.fleet = build_fleet(sc)
            # The physical sea (``environment.motion: physical``, the default) displaces the water every sensor sees;
            # with ``motion: paper`` the water stays the flat plane of the paper.
            self.sea: SeaState | None = None
            # The wave field the map's buoys ride (mmusv.world.buoys), as the moored ships do: the scenario's own sea
            # where it is physical and has height; with `motion: paper` (the paper's flat water) they stand at rest.
            self._buoy_field: Any | None = None
            if sc.environment.motion == "physical":
                spec = sc.environment.sea_spec()
                self.sea = spec if spec.hs_m > 0.0 else None
                if spec.hs_m > 0.0 and len(self.world.priors.buoys):
                    self._buoy_field = spec.field(scenario_seed=sc.seed)
            self.sensor_env: core.SensorEnv = self._sensor_env()
            poses0 = np.asarray(self.fleet.poses_at_times(np.zeros(1)))[0]
            # Over a physical sea the moored ships heave, roll and pitch at their berths (motion.build_moored_fleet).
            self._moored_fleet = build_moored_fleet(sc, self.world.moored)
            self.ws: WorldScene = build_world_scene(
                self.world,
                [(v.asset, v.role) for v in sc.vessels],
                poses0,
                moored_move=self._moored_fleet is not None,
                buoys_move=self._buoy_field is not None,
            )
            self.vessels: list[VesselInfo] = []
            for v, inst in zip(sc.vessels, self.ws.vessel_instances, strict=True):
                self.vessels.append(self._info(v.id, v.asset, v.role, int(inst), static=v.static))
            for k, ((asset_name, _berth), inst) in enumerate(
                zip(self.world.moored, self.ws.moored_instances, strict=True)
            ):
                self.vessels.append(self._info(f"moored_{k:02d}", asset_name, "moored", inst, static=True))
            berths = [berth for _, berth in self.world.moored]
            self._moored_eta = np.array([[x, y, 0.0, 0.0, 0.0, yaw] for x, y, yaw in berths]).reshape(-1, 6)
            self.agents: list[Agent] = [self._agent(i, v) for i, v in enumerate(sc.vessels) if v.role == "usv"]
            # COLREG lights burn on the vessels under way (not on moored ships or vessels at speed 0).
            under_way = [
                int(inst) for v, inst in zip(sc.vessels, self.ws.vessel_instances, strict=True) if not v.static
            ]
            self.ws.scene.set_lights(under_way, on=True)
        self._frame: int | None = None
        # The world state `prefetch_frame` worked out, for the `set_frame` of that frame to take (once).
        self._ahead: tuple[int, WorldState] | None = None

    def _after_fork_in_child(self) -> None:
        """In a forked child (:mod:`mmusv.turns`): the scene may be half-way to another frame; the next capture
        sets it anew."""
        self._frame = None

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickled as what rebuilds it (see the module docstring): its scenario, the map it was given (``None``:
        the scenario's, made again from its seed) and the sea :meth:`set_sea_surface` set, if it was called."""
        return (_rebuilt, (self.scenario, self._given_world, self._sea_set))

    # ------------------------------------------------------------------------------------------ building

    def _info(self, vid: str, asset_name: str, role: str, instance: int, *, static: bool) -> VesselInfo:
        a = self.assets[asset_name]
        lo, hi = a.bbox[0], a.bbox[1]
        cls = 11 if role == "usv" else int(a.semantic_class)
        # Read-only: every frame's annotations read these boxes, so they must not change under them.
        return VesselInfo(vid, asset_name, role, cls, instance, frozen((lo + hi) / 2.0), frozen(hi - lo), static)

    def _agent(self, index: int, v: VesselConfig) -> Agent:
        rig = self.scenario.rigs[v.rig] if v.rig is not None else RigConfig()
        return build_agent(index, v, rig, rig_name=v.rig)

    # ------------------------------------------------------------------------------------------ state

    @property
    def frames(self) -> int:
        """Number of acquisition indices."""
        return self.scenario.acquisition.frames

    def _frame_index(self, frame: Any) -> int:
        """``frame`` as an acquisition index: a whole number (``int`` or numpy integer) in ``0..frames - 1``."""
        k = arguments.whole(frame, name="frame")
        if not 0 <= k < self.frames:
            raise ConfigError(f"frame {k} is outside the acquisition (0..{self.frames - 1})")
        return k

    def time_of(self, frame: int) -> float:
        """``t_k = k / f`` in seconds of acquisition index ``frame`` (a whole number in ``0..frames - 1``)."""
        return self._frame_index(frame) / self.scenario.acquisition.frequency_hz

    def world_state(self, frame: int) -> WorldState:
        """Poses, velocities and boxes of every vessel at acquisition index ``frame`` (a whole number in
        ``0..frames - 1``; does not move the scene)."""
        frame = self._frame_index(frame)
        t = self.time_of(frame)
        eta = np.asarray(self.fleet.poses_at_times(np.array([t])))[0]
        vel = np.asarray(self.fleet.velocities_at(t))
        n_moored = self._moored_eta.shape[0]
        if self._moored_fleet is not None:
            eta_moored = np.asarray(self._moored_fleet.poses_at_times(np.array([t])))[0]
            vel_moored = np.asarray(self._moored_fleet.velocities_at(t))
        else:
            eta_moored, vel_moored = self._moored_eta, np.zeros((n_moored, 3))
        eta_all = np.concatenate([eta, eta_moored]) if n_moored else eta
        vel_all = np.concatenate([vel, vel_moored]) if n_moored else vel
        mats = pose_matrices(eta_all)
        centres_body = np.array([v.box_center_body for v in self.vessels]).reshape(-1, 3)
        centres = np.einsum("vij,vj->vi", mats[:, :3, :3], centres_body) + mats[:, :3, 3]
        return WorldState(frame, t, eta_all, vel_all, centres, mats)

    @one_at_a_time
    def set_sea_surface(self, sea: SeaState | None) -> None:
        """Makes the water the displaced surface of the physical sea ``sea`` (its wave field drawn from the
        scenario's sea seed) from the next :meth:`set_frame` on, or flat again with ``None``. The water only: the
        vessels, the moored ships and the buoys keep the motion of the scenario's own sea.

        Scenarios with ``environment.motion: physical`` (the default) start with their ``environment.sea_spec()``.
        Every frame then samples the surface at the frame time, finest around the USVs (the same surface for
        every sensor of every agent): crests occlude, LiDAR beams meet wave faces, the radar's sea clutter follows
        sea state and grazing angle, and the annotations carry each box's ``wave_occlusion``.
        """
        check_sea(sea, name="sea", error=ConfigError)
        self._sea_set = (sea,)
        self.sea = sea if sea is None or sea.hs_m > 0.0 else None
        self.sensor_env = self._sensor_env()
        if self.sea is None:
            self.ws.scene.set_wave_surface(None, scenario_seed=self.scenario.seed, time_s=0.0, foci=np.zeros((0, 2)))
        self._frame = None

    def _sensor_env(self) -> core.SensorEnv:
        """The sensors' view of the environment, whose sea state (their wind, whitecaps, water returns and
        clutter) is the physical sea's significant height where there is one (``environment.sea``, or the sea of
        ``environment.wave``), else the ``wave`` setting's: a scenario giving ``sea: {state: 6}`` alone is a rough
        sea to every sensor, not the default W0's calm one. The wind is ``environment.sea.wind_10m_mps`` when given,
        else that of a fully developed sea of that height."""
        sea = self.scenario.environment.sea
        return sensor_env(
            self.environment,
            wave_height_m=self.sea.hs_m if self.sea is not None else None,
            wind_speed_m_s=sea.wind_10m_mps if sea is not None else None,
        )

    @one_at_a_time
    def set_frame(self, frame: int, *, sea_radius_m: float = 320.0, shading_detail: bool = True) -> WorldState:
        """Moves every vessel to its pose at ``frame`` (and, over a physical sea, the water to its surface at the
        frame time, displaced out to ``sea_radius_m`` around every USV: :meth:`set_sea_surface`, and the map's
        buoys onto that water, their motion tapered where its waves are: :mod:`mmusv.world.buoys`) and returns the
        world state. ``shading_detail``: sample the waves' slopes the cameras shade with, the short waves' too
        (:meth:`mmusv.scene.Scene.set_wave_surface`'s ``slopes`` and ``detail``); only rendering reads them."""
        frame = self._frame_index(frame)
        sea_radius_m = arguments.real(sea_radius_m, name="sea_radius_m", unit="metres", above=0.0)
        shading_detail = arguments.flag(shading_detail, name="shading_detail")
        ahead, self._ahead = self._ahead, None
        state = ahead[1] if ahead is not None and ahead[0] == frame else self.world_state(frame)
        # The surface's arguments first: a surface too large for one grid refuses the frame before anything moves.
        surface = self.sea is not None and "water" in self.ws.static_instances
        waves = self._surface_of(state, sea_radius_m, shading_detail) if surface else None
        n = len(self.scenario.vessels)
        self.ws.scene.set_poses(self.ws.vessel_instances, state.matrices[:n])
        if self._moored_fleet is not None:
            self.ws.scene.set_poses(self.ws.moored_instances, state.matrices[n:])
        if self._buoy_field is not None:
            rest = self.world.priors.buoys
            # On the sampled surface's taper (and the still water beyond) the buoys float as that water lies.
            taper = surface_taper(rest, foci=waves["foci"], radius_m=sea_radius_m) if waves is not None else None
            poses = buoy_matrices(self._buoy_field, rest, state.time_s, taper=taper)
            self.ws.scene.set_poses(self.ws.buoy_instances, poses)
        if waves is not None:
            self.ws.scene.set_wave_surface(self.sea, **waves)
        self._frame = frame
        return state

    @one_at_a_time
    def prefetch_frame(self, frame: int, *, sea_radius_m: float = 320.0, shading_detail: bool = True) -> None:
        """Starts sampling the sea surface :meth:`set_frame` will set for ``frame`` with the same arguments, on a
        thread of its own (:meth:`mmusv.scene.Scene.prefetch_wave_surface`), so that it is ready when the frame
        is set: a recording asks for the next frame's while it annotates and writes this one. The same surface
        bit for bit; nothing to do without a physical sea, or for a frame outside the acquisition (``frame`` must
        still be a whole number)."""
        frame = arguments.whole(frame, name="frame")
        sea_radius_m = arguments.real(sea_radius_m, name="sea_radius_m", unit="metres", above=0.0)
        shading_detail = arguments.flag(shading_detail, name="shading_detail")
        if self.sea is None or "water" not in self.ws.static_instances or not 0 <= frame < self.frames:
            return
        state = self.world_state(frame)
        self._ahead = (frame, state)  # a function of the frame alone: set_frame(frame) takes it
        self.ws.scene.prefetch_wave_surface(self.sea, **self._surface_of(state, sea_radius_m, shading_detail))

    def _foci(self, state: WorldState) -> np.ndarray:
        """``(F, 2)`` float32 world x, y of the USVs in ``state``: the foci of the sampled sea surface."""
        return np.array([state.poses[a.index, :2] for a in self.agents], dtype=np.float32).reshape(-1, 2)

    def _surface_of(self, state: WorldState, radius_m: float, detail: bool) -> dict[str, Any]:
        """The wave surface arguments of ``state`` (after the sea): finest around the USVs, which must lie close
        enough together for one sampled surface to span them (:data:`~mmusv.sea_surface.MAX_SURFACE_TILES`)."""
        foci = self._foci(state)
        if surface_tiles(foci, radius_m=radius_m) > MAX_SURFACE_TILES:
            lo, hi = foci.min(axis=0), foci.max(axis=0)
            # The side of the largest square surface, less the tile the rounding may add.
            side = (math.sqrt(MAX_SURFACE_TILES) - 1.0) * SURFACE_TILE_M
            what = (
                f"the sea's surface around one USV with sea_radius_m = {radius_m:g} would exceed it: give at most "
                f"{side / 2.0:.0f} m"
                if 2.0 * radius_m > side
                else f"keep the USVs within about {(side - 2.0 * radius_m) / 1000.0:.0f} km of each other, or use "
                "`environment.motion: paper` (flat water)"
            )
            raise ConfigError(
                f"frame {state.frame}: the USVs {[a.id for a in self.agents]} span {hi[0] - lo[0]:.0f} m x "
                f"{hi[1] - lo[1]:.0f} m; the physical sea's surface around them is sampled as one rectangle of at "
                f"most {MAX_SURFACE_TILES} tiles of {SURFACE_TILE_M:g} m: {what}"
            )
        return {
            "scenario_seed": self.scenario.seed,
            "time_s": state.time_s,
            "foci": foci,
            "radius_m": radius_m,
            "detail": detail,
            "slopes": detail,
            "fine_m": self._top_view_reach_m if detail else 0.0,
        }

    @cached_property
    def _top_view_reach_m(self) -> float:
        """How far from its USV the farthest RGB top view sees (half its diagonal, metres; 0 without one): the
        sea's coarser tiles that near carry the finest grid's shading slopes, so a top view's one footprint sees
        every level alike (``Scene.set_wave_surface``'s ``fine_m``)."""
        reach = [
            0.5 * a.rig.top_view.metres_per_pixel * math.hypot(*a.rig.top_view.resolution)
            for a in self.agents
            if a.rig.top_view is not None and "rgb" in a.rig.top_view.outputs
        ]
        return max(reach, default=0.0)

    def renders(self, *, agents: Collection[str] | None = None, sensors: Collection[str] | None = None) -> bool:
        """Whether a :meth:`capture` with these ``agents`` and ``sensors`` renders (a camera or a top view): only
        then are the short waves' shading slopes sampled. Arguments as for :meth:`capture`."""
        return self._renders(*self._selection(agents, sensors))

    def _renders(self, agents: frozenset[str] | None, kinds: set[str]) -> bool:
        """:meth:`renders` of a selection already checked (:meth:`_selection`)."""
        return any(
            (("cameras" in kinds and a.cameras) or ("top_view" in kinds and a.top_view is not None))
            for a in self.agents
            if agents is None or a.id in agents
        )

    def _selection(self, agents: Any, sensors: Any) -> tuple[frozenset[str] | None, set[str]]:
        """:meth:`capture`'s ``agents`` (``None``: all) and sensor kinds, checked: lists of names, every agent a
        USV of the scenario and every kind one of :data:`SENSOR_KINDS`."""
        ids = arguments.names(agents, name="agents", example="['usv_1']")
        if ids is not None:
            unknown = sorted(ids - {a.id for a in self.agents})
            if unknown:
                raise ConfigError(
                    f"no USV named {', '.join(map(repr, unknown))}; the USVs are {[a.id for a in self.agents]}"
                )
        given = arguments.names(sensors, name="sensors", example="['lidar', 'cameras']")
        kinds = set(SENSOR_KINDS if given is None else given)
        if kinds - set(SENSOR_KINDS):
            raise ConfigError(
                f"unknown sensor kind(s) {sorted(kinds - set(SENSOR_KINDS))}; allowed: {', '.join(SENSOR_KINDS)}"
            )
        return ids, kinds

    def wakes(self, state: WorldState) -> np.ndarray:
        """``(K, 9)`` float32 rows ``x, y, heading, speed, length, beam, reach_m, age_s, displacement_m3`` (world
        metres, radians, m/s, s, m³) of the scenario vessels under way (horizontal speed above 0.3 m/s) in ``state``,
        and of those lying at rest at a ``stop`` route's end whose foam has not yet faded (their speed under way, every
        row as old as it was on arrival plus the time since): the wakes the cameras draw and the LiDARs see. A wake
        follows its vessel's path round the bends, as straight pieces, newest first. The first row is the vessel itself
        (its pose), its foam drawn straight back from the stern along its heading for ``reach_m`` metres (until its path
        leaves that line by half a beam; ``inf``: as far as the foam lasts). Each further row of the same vessel is a
        piece of the path from there: its stern on the path where the piece starts (the row's ``x, y`` half a length
        ahead of it, ``heading`` along the piece's chord to the next one's start), ``reach_m`` the chord's length,
        ``age_s`` how long ago the vessel's stern passed the piece's start (at least 1 ms: a row older than 0 is a piece
        further back). A vessel's rows come together, newest first: the core bends the Kelvin arms along them. No foam
        where the vessel never went, nor under its hull; its older foam and arms round the bends too (a vessel at rest
        draws no arms: its Kelvin waves have run off). ``displacement_m3`` (the hull's ``Cb·L·B·T``,
        :func:`~mmusv.world.hydrostatics.hull_particulars`) sets the Kelvin waves the cameras draw behind it."""
        _check_state(state)
        n = len(self.scenario.vessels)
        beams = np.array([float(v.box_size[1]) for v in self.vessels[:n]], dtype=np.float64)
        pieces = self.fleet.wake_pieces(state.time_s, 0.5 * beams) if n else np.zeros((0, 6))
        rows = []
        for i in range(n):
            vx, vy = float(state.velocities[i, 0]), float(state.velocities[i, 1])
            mine = pieces[pieces[:, 0] == i]
            # At rest at a ``stop`` route's end, its foam (the core's pieces as it arrived, aged since) is that of
            # its speed under way.
            rest = float(mine[0, 5]) if len(mine) else 0.0
            speed = math.hypot(vx, vy) or float(self.scenario.vessels[i].speed_mps)
            if speed <= 0.3 or len(mine) == 0:
                continue
            length, beam = float(self.vessels[i].box_size[0]), float(beams[i])
            volume = self._displacements[i]
            half = 0.5 * length
            # The vessel's own piece where it is now (its pose), its foam from the stern back to where its path left
            # the line (the core's reach runs from the vessel's centre); at rest, as old as its stop (at least a
            # millisecond: the core draws no Kelvin arms or waves of a row older than 0).
            x, y, yaw = (float(state.poses[i, k]) for k in (0, 1, 5))
            own_age = max(rest, 1e-3) if rest > 0.0 else 0.0
            rows.append((x, y, yaw, speed, length, beam, max(float(mine[0, 4]) - half, 0.0), own_age, volume))
            # The older pieces: each row's stern on the path where the piece starts (the row's "vessel" half a length
            # ahead of it along the piece), its foam as old as the time since the stern passed there; a piece the
            # stern has not yet passed all of starts where it is.
            for _, px, py, heading, reach, age in mine[1:]:
                c, s = math.cos(heading), math.sin(heading)
                lag = (age - rest) * speed - half  # how far the stern is past the piece's start, along the path
                cut = max(-lag, 0.0)
                if reach <= cut:
                    continue
                px, py, reach = px - cut * c, py - cut * s, reach - cut
                # (At least a millisecond old: a row older than 0 is a piece further back, its arms bent by the core.)
                old = max(rest + lag / speed, 1e-3)
                rows.append((px + half * c, py + half * s, heading, speed, length, beam, reach, old, volume))
        return np.asarray(rows, dtype=np.float32).reshape(-1, 9)

    @cached_property
    def _displacements(self) -> list[float]:
        """Each scenario vessel's displaced volume ``Cb·L·B·T``, m³ (its hull particulars)."""
        out = []
        for v in self.scenario.vessels:
            length, beam, draft, cb, _gm = hull_particulars(self.assets[v.asset])
            out.append(cb * length * beam * draft)
        return out

    def agent(self, agent_id: str) -> Agent:
        """The agent (USV) named ``agent_id`` (a ``str``, a USV's ``id`` in the scenario), else a ``ConfigError``
        listing the USVs."""
        if not isinstance(agent_id, str):
            raise ConfigError(
                f"agent_id = {arguments.shown(agent_id)}: must be a USV's id (a str), not {type(agent_id).__name__}; "
                f"the USVs are {[a.id for a in self.agents]}"
            )
        for a in self.agents:
            if a.id == agent_id:
                return a
        raise ConfigError(f"no USV named {agent_id!r}; the USVs are {[a.id for a in self.agents]}")

    def sensor_poses(self, agent: Agent, state: WorldState) -> dict[str, np.ndarray]:
        """``(4, 4)`` float64 sensor → world matrices (metres; sensor frames x forward, y left, z up) of every sensor
        of ``agent`` in ``state``: keys ``lidar``, ``radar``, ``camera/<name>``, ``top_view``. ``agent`` is one of
        this simulation's agents (or one equal to it: of a simulation of the same scenario), ``state`` a world state
        of this simulation (:meth:`world_state`)."""
        if not isinstance(agent, Agent):
            raise ConfigError(
                f"agent = {arguments.shown(agent)}: must be an Agent (Simulation.agent(id) or Simulation.agents), "
                f"not {type(agent).__name__}"
            )
        if agent not in self.agents:  # another scenario's: its index would pick another vessel's pose
            raise ConfigError(
                f"agent {agent.id!r} (vessel index {agent.index}) is not an agent of this simulation: give "
                f"Simulation.agent(id) of this one (its USVs are {[a.id for a in self.agents]})"
            )
        _check_state(state)
        if state.matrices.shape[0] != len(self.vessels):
            raise ConfigError(
                f"state holds {state.matrices.shape[0]} vessels, this simulation {len(self.vessels)}: give a state "
                "of this simulation (Simulation.world_state(frame))"
            )
        return self._sensor_poses(agent, state)

    def _sensor_poses(self, agent: Agent, state: WorldState) -> dict[str, np.ndarray]:
        """:meth:`sensor_poses` without its checks: for an agent and a state this simulation made (the capture's,
        once per agent per frame)."""
        body = state.matrices[agent.index]
        out = {key: body @ m for key, m in agent.mounts().items()}
        if agent.top_view is not None and agent.rig.top_view is not None:
            tv = agent.rig.top_view
            x, y, _, _, _, yaw = state.poses[agent.index]
            heading = yaw if tv.orientation == "heading_up" else math.pi / 2
            out["top_view"] = pose_matrices(np.array([x, y, tv.altitude_m, 0.0, 0.0, heading])) @ rpy_matrix(
                (0.0, 0.0, 0.0), (0.0, 90.0, 0.0)
            )
        return out

    # ------------------------------------------------------------------------------------------ capture

    @one_at_a_time
    def capture(
        self,
        frame: int,
        *,
        agents: Collection[str] | None = None,
        sensors: Collection[str] | None = None,
        radar: bool = True,
    ) -> FrameCapture:
        """Moves the world to ``frame`` and runs every sensor of every USV on that state.

        ``frame`` is an acquisition index, a whole number (``int`` or numpy integer) in ``0..frames - 1``.
        ``agents`` limits the USVs (a list of ids, e.g. ``['usv_1']``), ``sensors`` the sensor kinds (a list of
        ``lidar``, ``cameras``, ``top_view``, ``radar``); ``None`` means all. ``radar=False`` leaves the radar out
        whatever ``sensors`` says. Anything else (a single string, an unknown id or kind) is a ``ConfigError``.

        Every selected sensor of every selected USV runs in one native call (``core.capture_frame``: concurrent
        tasks over all cores, GIL released), with the outputs bit-identical to calling :func:`~mmusv.sensors.
        lidar.scan`, :func:`~mmusv.sensors.camera.render`, :func:`~mmusv.sensors.radar.radar_sweep` and
        :func:`~mmusv.sensors.radar.ppi_image` one by one with the same poses and :func:`sensor_seed` seeds.
        """
        frame = self._frame_index(frame)
        agents, kinds = self._selection(agents, sensors)
        if not arguments.flag(radar, name="radar"):
            kinds.discard("radar")
        # The short waves' shading slopes only for frames that render.
        state = self.set_frame(frame, shading_detail=self._renders(agents, kinds))
        sc = self.scenario
        out: dict[str, AgentCapture] = {}
        tasks: list[core._CaptureTask] = []
        slots: list[tuple[Agent, AgentCapture, str]] = []  # where each task's output goes
        for agent in self.agents:
            if agents is not None and agent.id not in agents:
                continue
            poses = self._sensor_poses(agent, state)
            body = state.matrices[agent.index]
            mounts = agent.mounts()
            cap = AgentCapture(agent.id, None, None, {}, {}, None, None, body=body)
            for key, p in poses.items():
                # A copy of the agent's (read-only) mount: the capture's arrays are its own.
                m = mounts[key].copy() if key in mounts else np.linalg.inv(body) @ p
                cap.sensors[key] = SensorMount(mount=m, pose=p)
            if agent.lidar is not None and "lidar" in kinds:
                cap.lidar_pose = poses["lidar"]
                tasks.append(
                    (
                        agent.lidar,
                        _pose(cap.lidar_pose),
                        sensor_seed(sc.seed, frame=frame, agent=agent.index, sensor="lidar"),
                    )
                )
                slots.append((agent, cap, "lidar"))
            for k, (name, (cam, _, _)) in enumerate(agent.cameras.items()):
                if "cameras" not in kinds:
                    break
                p = poses[f"camera/{name}"]
                cap.camera_poses[name] = p
                tasks.append(
                    (cam, _pose(p), sensor_seed(sc.seed, frame=frame, agent=agent.index, sensor="camera", index=k))
                )
                slots.append((agent, cap, f"camera/{name}"))
            if agent.top_view is not None and "top_view" in kinds:
                cap.top_view_pose = poses["top_view"]
                seed = sensor_seed(sc.seed, frame=frame, agent=agent.index, sensor="top_view")
                tasks.append((agent.top_view, _pose(cap.top_view_pose), seed))
                slots.append((agent, cap, "top_view"))
            if "radar" in kinds and agent.radar is not None and agent.rig.radar is not None:
                cap.radar_pose = _pose(poses["radar"])
                cfg = agent.rig.radar
                ppi = ppi_request(
                    agent.radar,
                    pose=cap.radar_pose,
                    size_px=cfg.ppi_size_px,
                    metres_per_pixel=cfg.ppi_metres_per_pixel,
                    orientation=cfg.ppi_orientation,
                )
                tasks.append(
                    (
                        agent.radar,
                        cap.radar_pose,
                        sensor_seed(sc.seed, frame=frame, agent=agent.index, sensor="radar"),
                        ppi,
                    )
                )
                slots.append((agent, cap, "radar"))
            out[agent.id] = cap
        wakes = self.wakes(state)
        results = (
            core.capture_frame(self.ws.scene.native, env=self.sensor_env, tasks=tasks, wakes=wakes) if tasks else []
        )
        secs: dict[str, float] = {}
        for (agent, cap, key), (d, seconds, ppi_seconds) in zip(slots, results, strict=True):
            secs[f"{agent.id}/{key}"] = seconds
            if key == "lidar":
                cap.lidar = LidarPoints.from_native(d)
                cap.lidar_beams = d["beam_instance"]
            elif key == "top_view":
                cap.top_view = CameraImages.from_native(d)
            elif key == "radar" and agent.radar is not None and cap.radar_pose is not None:
                cap.radar = RadarReturns.from_native(d, pose=cap.radar_pose, radar=agent.radar, config=agent.rig.radar)
                cap.radar_ppi = d["ppi"]
                secs[f"{agent.id}/ppi"] = ppi_seconds
            else:
                cap.cameras[key.removeprefix("camera/")] = CameraImages.from_native(d)
        return FrameCapture(frame, state.time_s, state, out, secs)


def _rebuilt(scenario: Scenario, world: MapWorld | None, sea: tuple[SeaState | None] | None) -> Simulation:
    """The simulation a pickled :class:`Simulation` stands for (:meth:`Simulation.__reduce__`)."""
    sim = Simulation(scenario, world=world)
    if sea is not None:
        sim.set_sea_surface(sea[0])
    return sim


def _check_state(state: Any) -> None:
    """A :class:`WorldState`, else a ``ConfigError`` saying where one comes from."""
    if not isinstance(state, WorldState):
        raise ConfigError(
            f"state = {arguments.shown(state)}: must be a WorldState (Simulation.world_state(frame)), "
            f"not {type(state).__name__}"
        )


def _pose(m: np.ndarray) -> npt.NDArray[np.float64]:
    """A ``(4, 4)`` pose as the core takes it: C-contiguous float64."""
    return np.ascontiguousarray(m, dtype=np.float64)
