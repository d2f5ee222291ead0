"""The instrumented USVs of a simulation: an :class:`Agent` holds one USV's rig, its native sensors (built once
from the rig by the core) and their mounts on the hull; :func:`build_agent` makes one from the scenario's vessel and
rig, its configuration errors naming the field by its path in the scenario."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt

from mmusv._equality import same
from mmusv._native import core
from mmusv.config import VesselConfig
from mmusv.errors import ConfigError
from mmusv.sensors.camera import camera_from_config, top_view_from_config
from mmusv.sensors.config import CameraConfig, RigConfig
from mmusv.sensors.lidar import lidar_from_config
from mmusv.sensors.mounts import camera_mount, inside_mesh, mount_matrix
from mmusv.sensors.radar import radar_from_config
from mmusv.world.vessels import VesselAsset, get_asset

__all__ = ["Agent", "build_agent"]

_T = TypeVar("_T")


def _built(where: str, kind: str, build: Callable[[], _T]) -> _T:
    """``build()`` (a sensor made from its configuration by the core), its configuration errors naming the field
    by its path in the scenario (``where``, e.g. ``rigs.usv_standard.cameras[1]``) instead of the core's own
    ``kind.`` prefix (``camera.distortion``), so that a rig of several cameras says which one is at fault."""
    try:
        return build()
    except ConfigError as exc:
        prefix = f"invalid config {kind}."
        msg = str(exc)
        if not msg.startswith(prefix):
            raise
        raise ConfigError(f"invalid config {where}.{msg[len(prefix) :]}") from None


@dataclass(eq=False)
class Agent:
    """An instrumented USV and its native sensors (each configured once from the rig).

    ``lidar_mount``, ``radar_mount``: ``(4, 4)`` float64 sensor → vessel body matrices (metres; read-only; ``None``
    without that sensor); ``cameras``: name → (native camera, its :class:`CameraConfig`, ``(4, 4)`` float64 camera
    body → vessel body mount, read-only); :meth:`mounts` gathers them.

    Two agents compare equal (``==``) when they hold the same values, as captures do (:mod:`mmusv.captures`): the
    same index, vessel, asset, rig and mounts (arrays by dtype, shape and value), and the same sensors present.
    The native sensors are built from the rig, so they are compared through it: the agents of two simulations of
    the same scenario are equal. Agents are not hashable (their fields can change): key them by :attr:`id`.

    An agent pickles as what builds it (its index, vessel, asset and rig): unpickled, its sensors are built again from
    the rig, so it equals the original and captures the same bytes.
    """

    index: int  # position in Simulation.vessels
    vessel: VesselConfig
    asset: VesselAsset
    rig: RigConfig
    lidar: core.Lidar | None
    lidar_mount: np.ndarray | None
    radar_mount: np.ndarray | None
    cameras: dict[str, tuple[core.Camera, CameraConfig, np.ndarray]] = field(default_factory=dict)
    top_view: core.Camera | None = None
    radar: core.Radar | None = None

    def __eq__(self, other: object) -> bool:
        """Whether ``other`` is an agent holding the same values (see the class docstring)."""
        if type(other) is not type(self):
            return NotImplemented
        assert isinstance(other, Agent)
        return same(self._compared(), other._compared())

    __hash__ = None  # type: ignore[assignment]

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickled as what builds it (see the class docstring): the native sensors do not pickle."""
        return (_rebuilt, (self.index, self.vessel, self.asset, self.rig))

    def _compared(self) -> tuple[Any, ...]:
        """What :meth:`__eq__` compares: the values the agent's sensors are built from, and which sensors it has."""
        present = (self.lidar is not None, self.radar is not None, self.top_view is not None, tuple(self.cameras))
        return (self.index, self.vessel, self.asset, self.rig, self.mounts(), present)

    @property
    def id(self) -> str:
        """The vessel id."""
        return self.vessel.id

    @cached_property
    def lidar_pattern(self) -> npt.NDArray[np.float32] | None:
        """``(M, 3)`` float32 unit beam directions of the LiDAR, LiDAR frame, in pattern order (read-only; worked
        out once: the rig never changes), or ``None`` without a LiDAR."""
        if self.lidar is None:
            return None
        p = np.array(self.lidar.pattern(), dtype=np.float32, order="C", copy=True)
        p.flags.writeable = False
        return p

    def mounts(self) -> dict[str, np.ndarray]:
        """``(4, 4)`` float64 sensor → vessel body matrices of the body-mounted sensors, read-only (the rig never
        changes; copy one to change it): keys ``lidar``, ``radar``, ``camera/<name>`` (camera body frame: x forward,
        y left, z up). The top view is not body-mounted."""
        out: dict[str, np.ndarray] = {}
        if self.lidar_mount is not None:
            out["lidar"] = self.lidar_mount
        if self.radar_mount is not None:
            out["radar"] = self.radar_mount
        for name, (_, _, m) in self.cameras.items():
            out[f"camera/{name}"] = m
        return out


def build_agent(
    index: int, vessel: VesselConfig, rig: RigConfig, *, rig_name: str | None, asset: VesselAsset | None = None
) -> Agent:
    """The agent of USV ``vessel`` (position ``index`` in the scenario's vessels) with ``rig`` (the scenario's rig
    ``rig_name``; ``None``: the default rig), its sensors built by the core, on ``asset`` (default: the catalogue's
    ``vessel.asset``). Configuration errors name the field by its path in the scenario
    (``rigs.<name>.cameras[1].distortion``); a sensor mounted inside the hull is refused."""
    where = f"rigs.{rig_name or '<default>'}"
    asset = get_asset(vessel.asset) if asset is None else asset
    agent = Agent(index=index, vessel=vessel, asset=asset, rig=rig, lidar=None, lidar_mount=None, radar_mount=None)
    # The mounts are read-only: every frame's poses are made from them (a capture gets copies).
    if rig.lidar is not None:
        agent.lidar = _built(f"{where}.lidar", "lidar", functools.partial(lidar_from_config, rig.lidar))
        agent.lidar_mount = frozen(mount_matrix(asset, rig.lidar.mount, where=f"{where}.lidar.mount"))
    if rig.radar is not None:
        agent.radar_mount = frozen(mount_matrix(asset, rig.radar.mount, where=f"{where}.radar.mount"))
        agent.radar = _built(f"{where}.radar", "radar", functools.partial(radar_from_config, rig.radar))
    for i, c in enumerate(rig.cameras):
        # The path as the YAML spells it (cameras is a list), as the schema's own errors say it.
        m = frozen(mount_matrix(asset, camera_mount(asset, c), where=f"{where}.cameras[{i}].mount"))
        camera = _built(f"{where}.cameras[{i}]", "camera", functools.partial(camera_from_config, c))
        agent.cameras[c.name] = (camera, c, m)
    if rig.top_view is not None:
        top = functools.partial(top_view_from_config, rig.top_view)
        agent.top_view = _built(f"{where}.top_view", "camera", top)
    _check_mounts(agent, where)
    return agent


def _rebuilt(index: int, vessel: VesselConfig, asset: VesselAsset, rig: RigConfig) -> Agent:
    """The agent a pickled :class:`Agent` stands for (:meth:`Agent.__reduce__`)."""
    return build_agent(index, vessel, rig, rig_name=vessel.rig, asset=asset)


def _check_mounts(agent: Agent, where: str) -> None:
    """A sensor whose origin lies inside its own hull would see only the hull's inside, and one under the still
    water (its vessel's ``z_base_m`` counted) the sea from below, hulls under their waterlines and a sky below the
    horizon: refuse both."""
    index = {f"camera/{c.name}": i for i, c in enumerate(agent.rig.cameras)}
    for key, m in agent.mounts().items():
        name = f"{where}.cameras[{index[key]}].mount" if key in index else f"{where}.{key}.mount"
        z = float(m[2, 3]) + agent.vessel.z_base_m  # the origin's height over the still water, at rest
        if z < 0.0:
            xyz = np.round(m[:3, 3], 3).tolist()
            zb = agent.vessel.z_base_m
            base, fix = ("", "z > 0 in the vessel frame")
            if zb:
                base, fix = (
                    f" (the vessel's z_base_m = {zb:g} lowers it)",
                    f"z > {-zb:g} m in the vessel frame, or raise z_base_m",
                )
            raise ConfigError(
                f"invalid config {name} = {xyz}: the sensor sits {-z:.2f} m under the still water{base} on vessel "
                f"{agent.id!r} ({agent.asset.name}); cameras, LiDAR and radar see nothing through water: mount it "
                f"above the waterline ({fix}), e.g. on a mount point (`mmusv assets` lists them)"
            )
        if inside_mesh(agent.asset.mesh.vertices, agent.asset.mesh.faces, point=m[:3, 3]):
            xyz = np.round(m[:3, 3], 3).tolist()
            raise ConfigError(
                f"invalid config {name} = {xyz}: the sensor sits inside the hull of vessel {agent.id!r} "
                f"({agent.asset.name}, top at z = {agent.asset.bbox[1, 2]:.2f} m); move it outside the hull, "
                "e.g. onto a mount point (`mmusv assets` lists them) or above the deck"
            )


def frozen(a: np.ndarray) -> np.ndarray:
    """``a`` made read-only (in place) and returned."""
    a.flags.writeable = False
    return a
