"""``--to ros2``: one rosbag2 folder per recording (``<out>/<scenario>/metadata.yaml`` + ``<scenario>.mcap``).

Written with rosbags' rosbag2 writer (:class:`rosbags.rosbag2.Writer`, format version 8, MCAP storage: profile
``ros2``, ``ros2msg`` schemas, ``cdr`` messages, zstd chunks; it also writes ``metadata.yaml`` and the ``rosbag2``
metadata record), messages serialised by rosbags' CDR serialiser from the types of
:func:`mmusv.export.ros2_types.typestore`. Standard message types only; ``docs/exports.md`` lists every topic.

Stamps (header, log time) are the scenario's sim time plus :data:`TIME_OFFSET_NS` (1 s: no stamp is time 0, which
tf2 reads as "the latest transform"), published on ``/clock``. Frames (REP 105/103): ``map`` (the
mmusv world: x east, y north, z up); per instrumented USV ``<usv>/odom`` (= ``map``, static) → ``<usv>/base_link``
(x forward, y left, z up; ``/tf`` every frame) → ``<usv>/lidar``, ``<usv>/radar``, ``<usv>/camera_<name>`` (x
forward) → ``<usv>/camera_<name>_optical`` (x right, y down, z forward) on ``/tf_static`` (transient local);
every other vessel ``map`` → ``<vessel>/base_link`` on ``/tf``; the top-view camera ``map`` →
``<usv>/top_view_optical`` on ``/tf`` (its scale and size in ``metadata.yaml``'s ``custom_data``,
``mmusv.top_view.<usv>``: :func:`top_view_custom_data`). Topic names spell vessel ids and camera names as ROS 2
name tokens (:func:`ros_token`: ``usv-1`` → ``usv_1``, ``2b`` → ``_2b``); frame ids keep them as they are.

The frame ids and topic names are :mod:`mmusv.export.ros2_names`'s, the messages built by
:mod:`mmusv.export.ros2_msgs`; this module writes them into the bag.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np
from scipy.spatial.transform import Rotation

from mmusv.classes import ROLE_COLOURS, class_name
from mmusv.errors import ConfigError
from mmusv.export.common import naming, top_view_entry
from mmusv.export.ros2_msgs import Msgs, stamp
from mmusv.export.ros2_names import (
    MAP_FRAME,
    base_link,
    camera_frame,
    camera_info_topic,
    detections_2d_topic,
    detections_3d_topic,
    odom_frame,
    odom_topic,
    optical_frame,
    ros_token,
    ros_topic,
    top_view_frame,
)
from mmusv.export.writer import DatasetWriter
from mmusv.frames import OPTICAL_IN_BODY, body_rates, pose_matrices
from mmusv.recording import topics
from mmusv.recording.decode import WorldFrame
from mmusv.recording.info import AgentInfo, RecordingInfo
from mmusv.recording.stream import Frame
from mmusv.sensors.camera import PIXEL_CENTRE, opencv_intrinsics

__all__ = [
    "MAP_FRAME",
    "TIME_OFFSET_NS",
    "Ros2Writer",
    "base_link",
    "camera_distortion",
    "camera_frame",
    "camera_info_topic",
    "detections_2d_topic",
    "detections_3d_topic",
    "odom_frame",
    "odom_topic",
    "optical_frame",
    "ros_token",
    "ros_topic",
    "top_view_custom_data",
    "top_view_frame",
]

TF_TOPIC = "/tf"
TF_STATIC_TOPIC = "/tf_static"
CLOCK_TOPIC = "/clock"
BAG_VERSION: Literal[8] = 8
"""rosbag2 metadata version (Jazzy's)."""
TIME_OFFSET_NS = 1_000_000_000
"""What the bag's stamps and log times add to the scenario's sim time (ns): frame k at ``1 + k / f`` s. ROS keeps
time 0 for "no time": tf2 looks a transform up at the *latest* stamp it holds for a request at time 0
(``tf2::TimeCache::findClosest``), and rclcpp's clock is not ``started()`` at 0, so a first frame stamped 0 would be
placed with the newest pose in the buffer and its ``/clock`` read as "not yet". The same for every frame and every
conversion (``--frames`` too); written in ``metadata.yaml``'s ``custom_data`` as ``mmusv.time_offset_ns``."""


def camera_distortion(agent: AgentInfo, name: str) -> np.ndarray:
    """``(5,)`` float64 ``[k1, k2, p1, p2, k3]`` of the agent's camera ``name`` as recorded beside its intrinsics
    (or, in older recordings, in its rig; OpenCV's order, which is ROS's ``plumb_bob``); zeros for a camera
    without distortion."""
    cam = agent.cameras.get(name)
    if cam is not None and cam.distortion is not None:
        return np.asarray(cam.distortion, dtype=np.float64)
    for c in agent.rig.get("cameras") or []:
        if isinstance(c, dict) and c.get("name") == name and c.get("distortion") is not None:
            return np.asarray(c["distortion"], dtype=np.float64).reshape(5)
    return np.zeros(5)


def top_view_custom_data(top_view: dict[str, Any]) -> str:
    """``metadata.yaml``'s ``custom_data`` ``mmusv.top_view.<usv>`` of a recorded rig's ``top_view``: JSON
    ``{"altitude_m", "metres_per_pixel", "orientation", "resolution": [W, H]}``. Pixel ``(u, v)`` (column, row of
    the image) has its centre at ``((u + 0.5 − W/2) · m, (v + 0.5 − H/2) · m, 0)`` in ``<usv>/top_view_optical``
    (``m`` = ``metres_per_pixel``), the frame ``/tf`` places ``altitude_m`` over the USV, looking straight down."""
    import json

    return json.dumps(top_view_entry(top_view), sort_keys=True)


@dataclass(frozen=True)
class _Odom:
    """One frame's odometry of a USV before its angular velocity is known: stamp (ns), sim time (s), body → map
    ``(4, 4)`` and linear velocity in the body frame ``(3,)`` m/s."""

    stamp_ns: int
    time_s: float
    body: np.ndarray
    linear: np.ndarray


class Ros2Writer(DatasetWriter):
    """Writes one recording as one rosbag2 folder (see the module docstring)."""

    format_version: ClassVar[int] = 2
    """2 (2026-12-02): the bag's time is the sim time plus :data:`TIME_OFFSET_NS` (it was the sim time)."""
    owns_folder: ClassVar[bool] = False
    splits: ClassVar[bool] = False
    needs_agent: ClassVar[bool] = False
    no_agent_reason: ClassVar[str] = "no instrumented USV"

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        from mmusv.export.ros2_types import typestore

        self.extra_counts = {}
        self.boxes_left_out = 0
        """2D boxes left out by ``min_box_px`` and ``max_occlusion`` (the recorded box, its recorded occlusion)."""
        self.ts = typestore()
        self.m = Msgs(self.ts)
        self.bag: Any = None
        self.connections: dict[str, Any] = {}
        self._odom: dict[str, list[_Odom]] = {}
        """Per USV, the odometry not yet written and the one before it (see :meth:`_odometry`)."""
        for a in self.agents:
            renamed = [n for n in (a.id, *sorted(a.cameras)) if ros_token(n) != n]
            if renamed:
                self.notes.append(
                    f"agent {a.id}: {', '.join(f'{n} is {ros_token(n)}' for n in renamed)} in the topic names (ROS 2 "
                    "names: letters, digits and '_', not starting with a digit); the frame ids keep the mmusv names"
                )

    @classmethod
    def check(cls, info: RecordingInfo) -> None:
        try:
            import rosbags.rosbag2  # noqa: F401
        except ImportError:
            raise ConfigError("--to ros2 needs the Python package rosbags: pip install 'mmusv[export]'") from None
        super().check(info)
        # names that ros_token makes equal would share topics: refused before anything is written
        groups = [("USVs", [a.id for a in info.agents])]
        groups += [(f"cameras of {a.id}", list(a.cameras)) for a in info.agents]
        for what, names in groups:
            seen: dict[str, str] = {}
            for n in names:
                other = seen.setdefault(ros_token(n), n)
                if other != n:
                    raise ConfigError(
                        f"{info.path}: cannot convert to ros2: the {what} {other!r} and {n!r} would both be "
                        f"{ros_token(n)!r} in the bag's topic names (ROS 2 names: letters, digits and '_', not "
                        "starting with a digit); rename one in the scenario"
                    )

    @classmethod
    def uses_agent(cls, agent: AgentInfo) -> str | None:
        return None

    # ------------------------------------------------------------------------------------------ topics

    def required_topics(self) -> list[str]:
        return [topics.WORLD_STATE]

    def optional_topics(self) -> list[str]:
        out = []
        for a in self.agents:
            out += [topics.lidar(a.id), topics.radar_returns(a.id), topics.radar_ppi(a.id)]
            out += [topics.agent_annotations(a.id), topics.TF]
            for name in a.cameras:
                out += [topics.camera(a.id, name, kind=kind) for kind in topics.CAMERA_KINDS]
            out += [topics.top_view(a.id, kind) for kind in topics.CAMERA_KINDS]
        return out

    # ------------------------------------------------------------------------------------------ writing

    def _open(self) -> None:
        from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
        from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

        self.bag = Writer(self.folder, version=BAG_VERSION, storage_plugin=StoragePlugin.MCAP)
        self.bag.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        self.bag.open()
        never = QosTime(0, 0)
        self.latched = Qos(
            QosHistory.KEEP_LAST,
            1,
            QosReliability.RELIABLE,
            QosDurability.TRANSIENT_LOCAL,
            never,
            never,
            QosLiveliness.AUTOMATIC,
            never,
            False,
        )

    def _put(self, topic: str, msgtype: str, msg: Any, t_ns: int, *, latched: bool = False) -> None:
        topic = ros_topic(topic)  # mmusv's names as ROS 2 names (usv-1 → usv_1)
        conn = self.connections.get(topic)
        if conn is None:
            qos = (self.latched,) if latched else ()
            conn = self.bag.add_connection(topic, msgtype, typestore=self.ts, offered_qos_profiles=qos)
            self.connections[topic] = conn
        data = self.ts.serialize_cdr(msg, msgtype)
        try:
            self.bag.write(conn, t_ns, data)
        except OSError as exc:
            raise self._failed(exc) from exc

    def _failed(self, exc: OSError) -> OSError:
        """After a failed write of the bag (a full disk): the bag closed without its summary (rosbags' ``abort``; its
        file was left open) and ``exc`` naming the bag's file (rosbags' ``OSError`` names none)."""
        self._abort()
        return naming(exc, self.folder / f"{self.folder.name}.mcap")

    def _abort(self) -> None:
        """Closes the bag's file without its summary (rosbags' ``abort``), if a bag is open."""
        bag, self.bag = self.bag, None
        if bag is not None:
            with contextlib.suppress(Exception):
                bag.abort()

    def _odometry(self, a: AgentInfo, now: _Odom | None) -> None:
        """Writes ``a``'s odometry of the frame before ``now`` (``None``: the last frame): the recording holds no
        angular velocity, so it is the body rate of the poses before and after (:func:`mmusv.frames.body_rates`),
        and an odometry message waits one frame for its successor. ``/<usv>/odom`` said angular 0 of a hull rolling
        and pitching in the waves, and turning. A frame earlier than the one held (a recording whose frames come out
        of order) is no successor: the one held is written from the frames before it, and ``now`` starts afresh."""
        if now is not None and self._odom.get(a.id) and now.time_s <= self._odom[a.id][-1].time_s:
            self._odometry(a, None)
        held = self._odom.pop(a.id, [])
        if now is not None:
            self._odom[a.id] = [*held[-1:], now]  # (before, now): ``now`` is written with the next frame
        if not held:
            return
        window = [*held, now] if now is not None else held  # (before, this, after) or the ends' two
        this = held[-1]
        rates = body_rates([o.time_s for o in window], [o.body[:3, :3] for o in window])
        m = self.m
        twist = self.T("geometry_msgs/msg/Twist")(
            linear=m.vector3(this.linear), angular=m.vector3(rates[len(held) - 1])
        )
        odom = self.T("nav_msgs/msg/Odometry")(
            header=m.header(this.stamp_ns, odom_frame(a.id)),
            child_frame_id=base_link(a.id),
            pose=self.T("geometry_msgs/msg/PoseWithCovariance")(pose=m.pose(this.body), covariance=np.zeros(36)),
            twist=self.T("geometry_msgs/msg/TwistWithCovariance")(twist=twist, covariance=np.zeros(36)),
        )
        self._put(odom_topic(a.id), "nav_msgs/msg/Odometry", odom, this.stamp_ns)

    def write_frame(self, frame: Frame) -> None:
        world = frame.world
        assert world is not None
        t = self.stamp_ns(frame)
        m = self.m
        if self.bag is None:
            self._open()
            self._put(TF_STATIC_TOPIC, "tf2_msgs/msg/TFMessage", m.tf(self._static(t)), t, latched=True)
        self._put(
            CLOCK_TOPIC,
            "rosgraph_msgs/msg/Clock",
            self.ts.types["rosgraph_msgs/msg/Clock"](clock=stamp(self.ts, t)),
            t,
        )
        self._put(TF_TOPIC, "tf2_msgs/msg/TFMessage", m.tf(self._dynamic(frame, world)), t)
        for a in self.agents:
            self._agent(frame, world, a)

    @staticmethod
    def stamp_ns(frame: Frame) -> int:
        """The bag's time of ``frame`` (header stamps and log time), ns: its sim time plus :data:`TIME_OFFSET_NS`."""
        return frame.log_time_ns + TIME_OFFSET_NS

    def _static(self, t: int) -> list[Any]:
        """map → odom of every USV, and its sensor mounts (constant)."""
        m = self.m
        out = []
        for a in self.agents:
            out.append(m.transform(t, parent=MAP_FRAME, child=odom_frame(a.id), m=np.eye(4)))
            base = base_link(a.id)
            if a.lidar_mount is not None:
                out.append(m.transform(t, parent=base, child=topics.lidar_frame(a.id), m=a.lidar_mount))
            if a.radar_mount is not None:
                out.append(m.transform(t, parent=base, child=topics.radar_frame(a.id), m=a.radar_mount))
            for name, cam in sorted(a.cameras.items()):
                out.append(m.transform(t, parent=base, child=camera_frame(a.id, name), m=cam.mount))
                out.append(
                    m.transform(t, parent=camera_frame(a.id, name), child=optical_frame(a.id, name), m=OPTICAL_IN_BODY)
                )
        return out

    def _dynamic(self, frame: Frame, world: WorldFrame) -> list[Any]:
        """Every vessel's body pose (USVs through their odom frame) and the top-view cameras."""
        m, t = self.m, self.stamp_ns(frame)
        agents = {a.id for a in self.agents}
        mats = pose_matrices(world.poses)
        out = [
            m.transform(t, parent=odom_frame(vid) if vid in agents else MAP_FRAME, child=base_link(vid), m=mats[i])
            for i, vid in enumerate(world.ids)
        ]
        tf = frame.messages.get(topics.TF)
        if tf is not None:
            tops = {topics.top_view_frame(a.id): a.id for a in self.agents}
            for x in tf.transforms:
                if x.child_frame_id in tops and x.parent_frame_id == topics.WORLD_FRAME:
                    mat = np.eye(4)
                    mat[:3, 3] = (x.translation.x, x.translation.y, x.translation.z)
                    q = (x.rotation.x, x.rotation.y, x.rotation.z, x.rotation.w)
                    mat[:3, :3] = Rotation.from_quat(q).as_matrix()
                    out.append(m.transform(t, parent=MAP_FRAME, child=top_view_frame(tops[x.child_frame_id]), m=mat))
        return out

    def _agent(self, frame: Frame, world: WorldFrame, a: AgentInfo) -> None:
        from mmusv.recording import decode_image

        m, t, msgs = self.m, self.stamp_ns(frame), frame.messages
        body = pose_matrices(world.poses[a.index])
        self._odometry(a, _Odom(t, frame.log_time_ns * 1e-9, body, body[:3, :3].T @ world.velocities[a.index]))
        lidar_fields = ["x", "y", "z", "intensity", "ring", "azimuth", "class", "instance"]
        self._point_cloud(frame, topics.lidar(a.id), topics.lidar_frame(a.id), lidar_fields)
        radar_fields = ["x", "y", "z", "range", "azimuth", "elevation", "intensity", "instance"]
        self._point_cloud(frame, topics.radar_returns(a.id), topics.radar_frame(a.id), radar_fields)
        ppi = msgs.get(topics.radar_ppi(a.id))
        if ppi is not None:
            img = decode_image(ppi)
            enc = "rgb8" if img.ndim == 3 else "mono8"
            self._put(
                topics.radar_ppi(a.id),
                "sensor_msgs/msg/Image",
                m.image(t, topics.radar_frame(a.id), img=img, encoding=enc),
                t,
            )
        for name in sorted(a.cameras):
            self._camera(frame, optical_frame(a.id, name), topics.camera(a.id, name))
            self._put(camera_info_topic(a.id, name), "sensor_msgs/msg/CameraInfo", self._camera_info(t, a, name), t)
        self._camera(frame, top_view_frame(a.id), topics.top_view(a.id))
        ann = msgs.get(topics.agent_annotations(a.id))
        if ann is not None:
            self._annotations(t, world, a, ann)

    def T(self, name: str) -> Any:
        """The message class ``name``."""
        return self.ts.types[name]

    def _point_cloud(self, frame: Frame, topic: str, frame_id: str, fields: list[str]) -> None:
        """The recorded point cloud on ``topic`` (a LiDAR's, the radar's returns), if the frame holds one, as a
        ``PointCloud2`` of ``fields`` on the same topic."""
        from mmusv.recording import decode_point_cloud

        msg = frame.messages.get(topic)
        if msg is not None:
            t = self.stamp_ns(frame)
            self._put(
                topic,
                "sensor_msgs/msg/PointCloud2",
                self.m.point_cloud(t, frame_id, decode_point_cloud(msg), fields),
                t,
            )

    def _camera(self, frame: Frame, frame_id: str, base: str) -> None:
        """The images of one camera (or the top view): RGB as PNG ``CompressedImage`` on ``<base>/rgb/compressed``
        (image_transport's name), depth ``32FC1`` metres (+inf: no hit), semantic and instance ``16UC1``."""
        from mmusv.recording import decode_image

        m, t, msgs = self.m, self.stamp_ns(frame), frame.messages
        rgb = msgs.get(f"{base}/rgb")
        if rgb is not None:
            if str(getattr(rgb, "format", "")).lower() == "png":
                self._put(
                    f"{base}/rgb/compressed",
                    "sensor_msgs/msg/CompressedImage",
                    m.compressed(t, frame_id, data=bytes(rgb.data), fmt="png"),
                    t,
                )
            else:
                self._put(
                    f"{base}/rgb",
                    "sensor_msgs/msg/Image",
                    m.image(t, frame_id, img=decode_image(rgb), encoding="rgb8"),
                    t,
                )
        depth = msgs.get(f"{base}/depth")
        if depth is not None:
            img = np.asarray(decode_image(depth), dtype=np.float32)
            self._put(f"{base}/depth", "sensor_msgs/msg/Image", m.image(t, frame_id, img=img, encoding="32FC1"), t)
        for kind in ("semantic", "instance"):
            msg = msgs.get(f"{base}/{kind}")
            if msg is not None:
                img = np.asarray(decode_image(msg), dtype=np.uint16)
                self._put(f"{base}/{kind}", "sensor_msgs/msg/Image", m.image(t, frame_id, img=img, encoding="16UC1"), t)

    def _camera_info(self, t: int, a: AgentInfo, name: str) -> Any:
        """Pinhole intrinsics in ROS's (OpenCV's) pixel coordinates, where pixel centres are whole numbers: the
        recorded principal point (mmusv's, centres at +0.5) less half a pixel
        (:data:`mmusv.sensors.camera.PIXEL_CENTRE`); ``plumb_bob``
        distortion = the camera's Brown–Conrady ``[k1, k2, p1, p2, k3]`` as recorded in its rig
        (:func:`camera_distortion`), zeros without; R = I, P = [K | 0]."""
        cam = a.cameras[name]
        fx, fy, cx, cy = opencv_intrinsics(cam.intrinsics)
        k = np.array([fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0])
        p = np.array([fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0])
        roi = self.T("sensor_msgs/msg/RegionOfInterest")(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
        return self.T("sensor_msgs/msg/CameraInfo")(
            header=self.m.header(t, optical_frame(a.id, name)),
            height=cam.height,
            width=cam.width,
            distortion_model="plumb_bob",
            d=camera_distortion(a, name),
            k=k,
            r=np.eye(3).reshape(9),
            p=p,
            binning_x=0,
            binning_y=0,
            roi=roi,
        )

    def _annotations(self, t: int, world: WorldFrame, a: AgentInfo, ann: Any) -> None:
        """``Detection3DArray`` and a ``MarkerArray`` of boxes in the LiDAR frame (the hull's ``base_link`` for a
        USV without a LiDAR: the recorded boxes are then in its body frame, :mod:`mmusv.annotate`); a
        ``Detection2DArray`` per camera in its optical frame. Class ids are mmusv class names (``vessel``,
        ``usv``), score 1 (ground truth), detection ids the vessel ids."""
        m = self.m
        row = {vid: i for i, vid in enumerate(world.ids)}
        lidar = topics.lidar_frame(a.id) if a.lidar_mount is not None else base_link(a.id)
        hyp = self.T("vision_msgs/msg/ObjectHypothesis")
        hyp_pose = self.T("vision_msgs/msg/ObjectHypothesisWithPose")
        pwc = self.T("geometry_msgs/msg/PoseWithCovariance")
        marker = self.T("visualization_msgs/msg/Marker")
        dets3, markers = [], [self._marker(t, lidar, marker.DELETEALL, 0, np.eye(4), (0.0, 0.0, 0.0), (0, 0, 0, 0))]
        for i, b in enumerate(ann.boxes_lidar):
            mat = np.eye(4)
            mat[:3, :3] = Rotation.from_quat(list(b.rotation)).as_matrix()
            mat[:3, 3] = list(b.center)
            pose = m.pose(mat)
            name = class_name(int(b.semantic_class))
            dets3.append(
                self.T("vision_msgs/msg/Detection3D")(
                    header=m.header(t, lidar),
                    results=[
                        hyp_pose(hypothesis=hyp(class_id=name, score=1.0), pose=pwc(pose=pose, covariance=np.zeros(36)))
                    ],
                    bbox=self.T("vision_msgs/msg/BoundingBox3D")(center=pose, size=m.vector3(list(b.size))),
                    id=b.target_id,
                )
            )
            role = world.roles[row[b.target_id]] if b.target_id in row else "target"
            markers.append(
                self._marker(t, lidar, marker.ADD, i, mat, list(b.size), ROLE_COLOURS.get(role, (1, 1, 1, 0.5)))
            )
        self._put(
            detections_3d_topic(a.id),
            "vision_msgs/msg/Detection3DArray",
            self.T("vision_msgs/msg/Detection3DArray")(header=m.header(t, lidar), detections=dets3),
            t,
        )
        self._put(
            topics.boxes(a.id),
            "visualization_msgs/msg/MarkerArray",
            self.T("visualization_msgs/msg/MarkerArray")(markers=markers),
            t,
        )
        by_cam: dict[str, list[Any]] = {name: [] for name in a.cameras}
        ident = m.pose(np.eye(4))
        o = self.options
        for b in ann.boxes_camera:
            if b.camera not in by_cam:
                continue
            # Detection2D has no field for occlusion: max_occlusion leaves out the vessels hidden by more (1, the
            # default: every recorded box, wholly hidden ones too), min_box_px the small boxes
            if b.occlusion > o.max_occlusion or min(b.x_max - b.x_min, b.y_max - b.y_min) < o.min_box_px:
                self.boxes_left_out += 1
                continue
            j = row.get(b.target_id)
            name = class_name(int(world.classes[j])) if j is not None else "unknown"
            centre = self.T("vision_msgs/msg/Pose2D")(
                position=self.T("vision_msgs/msg/Point2D")(
                    x=(b.x_min + b.x_max) / 2.0 - PIXEL_CENTRE, y=(b.y_min + b.y_max) / 2.0 - PIXEL_CENTRE
                ),
                theta=0.0,
            )
            by_cam[b.camera].append(
                self.T("vision_msgs/msg/Detection2D")(
                    header=m.header(t, optical_frame(a.id, b.camera)),
                    results=[
                        hyp_pose(
                            hypothesis=hyp(class_id=name, score=1.0), pose=pwc(pose=ident, covariance=np.zeros(36))
                        )
                    ],
                    bbox=self.T("vision_msgs/msg/BoundingBox2D")(
                        center=centre, size_x=float(b.x_max - b.x_min), size_y=float(b.y_max - b.y_min)
                    ),
                    id=b.target_id,
                )
            )
        for cam, dets in sorted(by_cam.items()):
            msg = self.T("vision_msgs/msg/Detection2DArray")(
                header=m.header(t, optical_frame(a.id, cam)), detections=dets
            )
            self._put(detections_2d_topic(a.id, cam), "vision_msgs/msg/Detection2DArray", msg, t)

    def _marker(self, t: int, frame_id: str, action: int, i: int, mat: np.ndarray, size: Any, rgba: Any) -> Any:
        T = self.T
        return T("visualization_msgs/msg/Marker")(
            header=self.m.header(t, frame_id),
            ns="targets",
            id=i,
            type=T("visualization_msgs/msg/Marker").CUBE,
            action=action,
            pose=self.m.pose(mat),
            scale=self.m.vector3(size),
            color=T("std_msgs/msg/ColorRGBA")(r=float(rgba[0]), g=float(rgba[1]), b=float(rgba[2]), a=float(rgba[3])),
            lifetime=T("builtin_interfaces/msg/Duration")(sec=0, nanosec=0),
            frame_locked=False,
            points=[],
            colors=[],
            texture_resource="",
            texture=T("sensor_msgs/msg/CompressedImage")(
                header=self.m.header(0, ""), format="", data=np.zeros(0, dtype=np.uint8)
            ),
            uv_coordinates=[],
            text="",
            mesh_resource="",
            mesh_file=T("visualization_msgs/msg/MeshFile")(filename="", data=np.zeros(0, dtype=np.uint8)),
            mesh_use_embedded_materials=False,
        )

    def stop(self, *, interrupted: bool) -> None:
        """A stop: the bag is closed whole (summary, ``metadata.yaml``: a bag ``ros2 bag play`` and rosbags read)
        holding the frames converted so far, their odometry included, and ``mmusv.status: interrupted`` in
        ``metadata.yaml``'s ``custom_data``; an error: the bag is closed without its
        summary (rosbags' ``abort``). Either way its file is closed: a Ctrl-C left it open, without
        ``metadata.yaml``, to a Python session that went on."""
        if self.bag is None:
            return
        if interrupted:
            with contextlib.suppress(Exception):  # a disk that cannot take the rest: aborted below
                self._close(status="interrupted")
                return
        self._abort()

    def _close(self, *, status: str) -> None:
        """Writes each USV's last odometry (held for a successor that never came) and the bag's custom data, its
        ``mmusv.status`` ``status`` (``complete``, or ``interrupted``: the bag itself says it holds only the frames
        converted before a stop, which peers otherwise read as a whole one) and each USV's top view
        (``mmusv.top_view.<usv>``: :func:`top_view_custom_data`), and closes the bag."""
        for a in self.agents:
            self._odometry(a, None)
        self.bag.set_custom_data("mmusv.source", self.info.path.name)
        self.bag.set_custom_data("mmusv.scenario", self.info.scenario_name)
        self.bag.set_custom_data("mmusv.config_hash", self.info.config_hash)
        self.bag.set_custom_data("mmusv.time_offset_ns", str(TIME_OFFSET_NS))
        self.bag.set_custom_data("mmusv.status", status)
        for a in self.agents:  # what places the top view's pixels: an orthographic camera has no CameraInfo
            tv = a.rig.get("top_view")
            if tv:
                self.bag.set_custom_data(f"mmusv.top_view.{a.id}", top_view_custom_data(tv))
        try:
            self.bag.close()
        except OSError as exc:
            raise self._failed(exc) from exc
        self.bag = None

    def finish(self, frames: list[int], skipped: list[dict[str, Any]]) -> None:
        o = self.options
        if o.max_occlusion != 1.0 or o.min_box_px != 0.0:
            self.notes.append(
                f"{self.boxes_left_out} 2D boxes left out of the Detection2DArray messages (max_occlusion = "
                f"{o.max_occlusion:g}, min_box_px = {o.min_box_px:g}, on the recorded box and occlusion)"
            )
        super().finish(frames, skipped)
        if self.bag is None:
            return
        self._close(status="complete")
        for p in sorted(self.folder.iterdir()):
            self.sink.count(p)
