"""The ROS 2 message types of the ``--to ros2`` export: rosbags' Humble typestore plus ``vision_msgs``.

Every type but ``vision_msgs`` is in rosbags' ROS 2 typestores, whose definitions the bag's ``ros2msg`` schemas are
generated from (:meth:`rosbags.typesys.store.Typestore.generate_msgdef`: the type's own ``.msg`` text followed by
every type it uses, each after a line of 80 ``=`` and ``MSG: pkg/Type``, as ``rosbag2`` writes them). The types
used have the same fields in the Humble and Jazzy stores (``visualization_msgs/Marker`` differs only in Jazzy's
extra constant ``ARROW_STRIP``), so the bag reads with either.

``vision_msgs`` is in neither store, so its definitions are here: the field lines of ``vision_msgs`` 4.1.1 (the
release in Humble and Jazzy; ``ros-perception/vision_msgs``, branch ``ros2``, ``vision_msgs/msg/*.msg``), parsed by
rosbags (:func:`rosbags.typesys.get_types_from_msg`) and registered beside the standard types.
"""

from __future__ import annotations

from functools import cache
from typing import Any

__all__ = ["VISION_MSGS", "typestore"]

VISION_MSGS: dict[str, str] = {
    "vision_msgs/msg/Point2D": "float64 x\nfloat64 y\n",
    "vision_msgs/msg/Pose2D": "vision_msgs/Point2D position\nfloat64 theta\n",
    "vision_msgs/msg/BoundingBox2D": "vision_msgs/Pose2D center\nfloat64 size_x\nfloat64 size_y\n",
    "vision_msgs/msg/BoundingBox3D": "geometry_msgs/Pose center\ngeometry_msgs/Vector3 size\n",
    "vision_msgs/msg/ObjectHypothesis": "string class_id\nfloat64 score\n",
    "vision_msgs/msg/ObjectHypothesisWithPose": "ObjectHypothesis hypothesis\ngeometry_msgs/PoseWithCovariance pose\n",
    "vision_msgs/msg/Detection2D": (
        "std_msgs/Header header\nObjectHypothesisWithPose[] results\nBoundingBox2D bbox\nstring id\n"
    ),
    "vision_msgs/msg/Detection2DArray": "std_msgs/Header header\nDetection2D[] detections\n",
    "vision_msgs/msg/Detection3D": (
        "std_msgs/Header header\nObjectHypothesisWithPose[] results\nBoundingBox3D bbox\nstring id\n"
    ),
    "vision_msgs/msg/Detection3DArray": "std_msgs/Header header\nDetection3D[] detections\n",
}
"""``vision_msgs`` 4.1.1 message definitions (field lines; comments left out), by ROS 2 type name."""


@cache
def typestore() -> Any:
    """rosbags' ROS 2 Humble typestore with :data:`VISION_MSGS` registered (one per process)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types: dict[str, Any] = {}
    for name, text in VISION_MSGS.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store
