"""Per frame and agent: where the agent's sensors are and which vessels are its targets (mmusv frames).

Everything here stays in mmusv's right-handed frames; the dataset writers change frames only through
:mod:`mmusv.frames`. Sensor poses follow the recorder: sensor → world = vessel body → world (from the world
state pose) · sensor mount in body, composed by :meth:`mmusv.recording.info.AgentInfo.sensor_poses`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mmusv.boxes3d import in_target_range
from mmusv.frames import invert, pose_matrices
from mmusv.recording.decode import WorldFrame
from mmusv.recording.info import AgentInfo

__all__ = ["AgentView", "Target", "agent_view", "targets_of"]


@dataclass(frozen=True)
class AgentView:
    """An agent at one frame: ``body``, ``lidar`` and ``cameras[name]`` are ``(4, 4)`` float64 vessel body / LiDAR
    / camera body (x forward = optical axis, y left, z up) → world matrices, metres (``lidar`` ``None`` without a
    LiDAR); ``speed_mps`` the agent's speed (norm of its world velocity), m/s."""

    agent: AgentInfo
    body: np.ndarray
    lidar: np.ndarray | None
    cameras: dict[str, np.ndarray]
    speed_mps: float


@dataclass(frozen=True)
class Target:
    """A vessel seen as a target by one agent: ``index`` its world-state row, ``body`` ``(4, 4)`` body → world,
    ``box`` ``(4, 4)`` box → world (body rotation, box centre), ``box_in_lidar`` ``(4, 4)`` box → agent LiDAR (the
    agent's body frame when it has no LiDAR), all float64 metres; ``size`` ``(3,)`` float64 length, beam, height,
    metres; ``speed_mps`` its speed (norm of its world velocity), m/s."""

    index: int
    id: str
    asset: str
    role: str
    semantic_class: int
    instance_id: int
    body: np.ndarray
    box: np.ndarray
    box_in_lidar: np.ndarray
    size: np.ndarray
    speed_mps: float


def agent_view(agent: AgentInfo, world: WorldFrame) -> AgentView:
    """The sensor poses of ``agent`` in ``world``."""
    body, lidar, cams = agent.sensor_poses(world)
    return AgentView(agent, body, lidar, cams, float(np.linalg.norm(world.velocities[agent.index])))


def targets_of(view: AgentView, world: WorldFrame, *, eval_range_m: float, include_usvs: bool) -> list[Target]:
    """The targets of ``view``'s agent, in world-state order: every vessel but the agent itself (and other USVs
    unless ``include_usvs``) whose box centre lies within ``eval_range_m`` of the agent's LiDAR (its body frame
    when it has no LiDAR) by the box-centre rule, :func:`mmusv.boxes3d.in_target_range` (BEV distance)."""
    ref = view.lidar if view.lidar is not None else view.body
    ref_inv = invert(ref)
    out: list[Target] = []
    mats = pose_matrices(world.poses)
    for i, vid in enumerate(world.ids):
        if i == view.agent.index or (world.roles[i] == "usv" and not include_usvs):
            continue
        box = mats[i].copy()
        box[:3, 3] = world.box_centers[i]
        in_lidar = ref_inv @ box
        if not in_target_range(in_lidar[:3, 3], eval_range_m):
            continue
        out.append(
            Target(
                index=i,
                id=vid,
                asset=world.assets[i],
                role=world.roles[i],
                semantic_class=int(world.classes[i]),
                instance_id=int(world.instance_ids[i]),
                body=mats[i],
                box=box,
                box_in_lidar=in_lidar,
                size=world.box_sizes[i].copy(),
                speed_mps=float(np.linalg.norm(world.velocities[i])),
            )
        )
    return out
