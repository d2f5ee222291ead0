"""Topic names and frame ids of an ``mmusv run`` recording: the one place they are spelled (``docs/recording.md``).

Topics: ``/tf``, ``/world/state``, ``/{agent}/lidar``, ``/{agent}/camera/{name}/{rgb|depth|semantic|instance}``,
``/{agent}/camera/{name}/calibration``, ``/{agent}/camera/{name}/boxes``,
``/{agent}/top_view/{rgb|semantic|instance}``, ``/{agent}/radar/returns``, ``/{agent}/radar/ppi``,
``/{agent}/boxes``, ``/{agent}/annotations``. Frame ids: ``world``, ``{vessel}`` (body: x forward, y left, z up),
``{agent}/lidar``, ``{agent}/radar`` (sensor frames, x forward, y left, z up), ``{agent}/camera/{name}`` and
``{agent}/top_view`` (optical frames: x right, y down, z forward).
"""

from __future__ import annotations

from collections.abc import Callable

__all__ = [
    "CAMERA_KINDS",
    "TF",
    "WORLD_FRAME",
    "WORLD_STATE",
    "agent_annotations",
    "agent_of",
    "boxes",
    "camera",
    "camera_boxes",
    "camera_calibration",
    "camera_frame",
    "lidar",
    "lidar_frame",
    "radar_frame",
    "radar_ppi",
    "radar_returns",
    "top_view",
    "top_view_frame",
]

TF = "/tf"
"""``foxglove.FrameTransforms``, one message per frame."""
WORLD_STATE = "/world/state"
"""``mmusv.WorldState``, one message per frame."""
WORLD_FRAME = "world"
"""Frame id of the world frame (x east, y north, z up, water at z = 0)."""
CAMERA_KINDS: tuple[str, ...] = ("rgb", "depth", "semantic", "instance")
"""Image kinds a camera or the top view may publish, in this order."""


def _per_agent(pattern: str, doc: str) -> Callable[[str], str]:
    """A function ``agent -> pattern.format(agent=agent)`` documented as ``doc``."""

    def name(agent: str) -> str:
        return pattern.format(agent=agent)

    name.__doc__ = f"``{pattern}``: {doc}"
    return name


lidar = _per_agent("/{agent}/lidar", "foxglove.PointCloud in the LiDAR frame.")
radar_returns = _per_agent("/{agent}/radar/returns", "foxglove.PointCloud in the radar frame.")
radar_ppi = _per_agent("/{agent}/radar/ppi", "colour-mapped PPI, PNG foxglove.CompressedImage.")
boxes = _per_agent(
    "/{agent}/boxes", "foxglove.SceneUpdate in the LiDAR frame (the vessel body frame when the rig has no LiDAR)."
)
agent_annotations = _per_agent("/{agent}/annotations", "mmusv.AgentAnnotations.")
lidar_frame = _per_agent("{agent}/lidar", "frame id of the agent's LiDAR.")
radar_frame = _per_agent("{agent}/radar", "frame id of the agent's radar.")
top_view_frame = _per_agent("{agent}/top_view", "frame id (optical) of the agent's top-view camera.")


def camera(agent: str, name: str, *, kind: str | None = None) -> str:
    """``/{agent}/camera/{name}`` (prefix) or ``/{agent}/camera/{name}/{kind}``."""
    base = f"/{agent}/camera/{name}"
    return base if kind is None else f"{base}/{kind}"


def camera_calibration(agent: str, name: str) -> str:
    """``/{agent}/camera/{name}/calibration``: ``foxglove.CameraCalibration`` of the camera (its optical frame,
    OpenCV's pixel convention), one per frame, so that Foxglove's Image and 3D panels can project onto its images."""
    return camera(agent, name, kind="calibration")


def camera_boxes(agent: str, name: str) -> str:
    """``/{agent}/camera/{name}/boxes``: ``foxglove.ImageAnnotations``, the camera's 2D boxes of the frame (as
    ``/{agent}/annotations`` holds them), outlined and labelled, for Foxglove's Image panel."""
    return camera(agent, name, kind="boxes")


def top_view(agent: str, kind: str | None = None) -> str:
    """``/{agent}/top_view`` (prefix) or ``/{agent}/top_view/{kind}``."""
    base = f"/{agent}/top_view"
    return base if kind is None else f"{base}/{kind}"


def camera_frame(agent: str, name: str) -> str:
    """Frame id (optical) of camera ``name`` of the agent."""
    return f"{agent}/camera/{name}"


def agent_of(topic: str) -> str | None:
    """The agent id of a per-agent topic (``/{agent}/...``), ``None`` for ``/tf`` and ``/world/...``."""
    parts = topic.split("/")
    if len(parts) < 3 or parts[1] == "world":
        return None
    return parts[1]
