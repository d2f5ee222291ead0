"""The ROS 2 names of the ``--to ros2`` export: frame ids (REP 105/103: ``map``, ``<usv>/odom``,
``<usv>/base_link``, camera and optical frames) and topic names, mmusv's vessel ids and camera names spelled as
ROS 2 name tokens (:func:`ros_token`). The writer is :mod:`mmusv.export.ros2`."""

from __future__ import annotations

import re

from mmusv.recording import topics

__all__ = [
    "MAP_FRAME",
    "base_link",
    "camera_frame",
    "camera_info_topic",
    "detections_2d_topic",
    "detections_3d_topic",
    "odom_frame",
    "odom_topic",
    "optical_frame",
    "ros_token",
    "ros_topic",
    "top_view_frame",
]

MAP_FRAME = "map"


def base_link(vessel: str) -> str:
    """``<vessel>/base_link``: the vessel body (x forward, y left, z up)."""
    return f"{vessel}/base_link"


def odom_frame(agent: str) -> str:
    """``<usv>/odom``: the odometry frame of an instrumented USV (ground truth: the same as ``map``)."""
    return f"{agent}/odom"


def camera_frame(agent: str, name: str) -> str:
    """``<usv>/camera_<name>``: camera body frame (x forward = optical axis, y left, z up)."""
    return f"{agent}/camera_{name}"


def optical_frame(agent: str, name: str) -> str:
    """``<usv>/camera_<name>_optical``: the camera's optical frame (x right, y down, z forward; REP 103)."""
    return f"{camera_frame(agent, name)}_optical"


def top_view_frame(agent: str) -> str:
    """``<usv>/top_view_optical``: optical frame of the agent's top-view camera."""
    return f"{agent}/top_view_optical"


_NOT_IN_ROS_NAMES = re.compile(r"[^A-Za-z0-9_]")


def ros_token(name: str) -> str:
    """``name`` (a vessel id, a camera name) as a ROS 2 name token: letters, digits and ``_``, not starting with a
    digit (``rcl_validate_topic_name``). mmusv's names may hold ``-`` and start with a digit: each other character
    becomes ``_`` and a leading digit gets a ``_`` before it (``usv-1`` → ``usv_1``, ``2b`` → ``_2b``); a valid token
    is kept as it is."""
    token = _NOT_IN_ROS_NAMES.sub("_", name)
    return f"_{token}" if token[:1].isdigit() else token


def ros_topic(topic: str) -> str:
    """The bag's name for a topic spelled from mmusv names (``/usv-1/camera/front-wide/rgb`` →
    ``/usv_1/camera/front_wide/rgb``): every token through :func:`ros_token`, so ``ros2 bag play`` can publish it."""
    return "/".join(ros_token(t) if t else t for t in topic.split("/"))


def odom_topic(agent: str) -> str:
    """``/<usv>/odom``: ``nav_msgs/Odometry``."""
    return ros_topic(f"/{agent}/odom")


def camera_info_topic(agent: str, name: str) -> str:
    """``/<usv>/camera/<name>/camera_info``."""
    return ros_topic(f"{topics.camera(agent, name)}/camera_info")


def detections_2d_topic(agent: str, name: str) -> str:
    """``/<usv>/camera/<name>/detections``: ``vision_msgs/Detection2DArray``."""
    return ros_topic(f"{topics.camera(agent, name)}/detections")


def detections_3d_topic(agent: str) -> str:
    """``/<usv>/detections``: ``vision_msgs/Detection3DArray`` in the LiDAR frame."""
    return ros_topic(f"/{agent}/detections")
