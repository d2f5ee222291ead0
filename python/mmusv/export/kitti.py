"""KITTI-style per-agent folders: the same scenario/agent/timestamp structure as the OPV2V writer, KITTI files.

``<scenario>/<cav_id>/velodyne/<ts>.bin`` (float32 x, y, z, intensity in the LiDAR frame, x forward, y left,
z up — KITTI's Velodyne axes, so no mirror), ``image_2/<ts>.png`` (front camera), ``calib/<ts>.txt`` (``P0..P3``
= the front camera's ``K·[I|0]``, ``R0_rect`` = I, ``Tr_velo_to_cam`` LiDAR → front optical frame,
``Tr_imu_to_velo`` vessel body → LiDAR), ``label_2/<ts>.txt`` and ``pose/<ts>.txt`` (LiDAR → mmusv world,
3×4 row-major, for cooperative use); ``<ts>`` is the 6-digit acquisition index k, the same in every agent folder,
taken at sim time k / ``frequency_hz`` s (``mmusv_kitti.yaml``). Labels, one line per target within the evaluation
range (same filter as OPV2V): ``type truncated occluded alpha x1 y1 x2 y2 h w l x y z rotation_y`` in the front
camera frame (location = the box centre moved h/2 down the camera's y axis: KITTI's bottom centre of an upright
box, so that readers adding h/2 back get the box centre, also when the hull or the USV rolls in waves); the 2D box,
truncation and occlusion come from the recording's camera annotations (occluded 0: < 25 % hidden, 1: < 60 %,
2: more, 3: no box in the front image — out of its view, or in it with no pixel seen, hidden wholly by the crests
or by hulls — with box ``0 0 0 0`` and truncated the share of the target out of the image:
``1.00`` behind or beside the camera, the projected box's share for one in view too small for any pixel centre).
After the targets, a ``DontCare`` line (KITTI's own form, :func:`dont_care_lines`) for each vessel the front image
shows that is not a target (beyond the range by its centre, or another USV): KITTI's evaluation ignores detections
there.
An agent without a front camera has no ``image_2``, zero ``P0..P3`` and, as camera, the LiDAR's own optical axes
(``Tr_velo_to_cam`` = the rotation x right, y down, z forward): its labels keep KITTI's camera conventions, so
KITTI's readers turn them into LiDAR boxes with the right heading. A front camera's lens distortion (KITTI's
images are rectified; ``P2`` is a pinhole) is in ``mmusv_kitti.yaml`` and the conversion's notes.
Extras: ``depth_2`` (uint16 cm, 0 = no hit, 65535 = 655.35 m or farther), ``semantic_2``, ``instance_2``,
``radar_ppi``, ``top_view_rgb``, ``top_view_semantic`` (their size, scale, orientation and pixel mapping in
``mmusv_kitti.yaml``'s ``top_views`` and ``top_view_png``: :func:`mmusv.export.common.top_view_protocol`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from mmusv.boxes3d import box_corners
from mmusv.classes import class_name
from mmusv.export.common import cav_id, depth_png, dump_yaml, png_bytes, top_view_protocol
from mmusv.export.geometry import AgentView, Target
from mmusv.export.writer import DatasetWriter
from mmusv.frames import BODY_TO_OPTICAL, invert, wrap_rad
from mmusv.image_boxes import pinhole_truncation
from mmusv.recording import topics
from mmusv.recording.decode import WorldFrame
from mmusv.recording.info import AgentInfo
from mmusv.recording.stream import Frame

__all__ = [
    "DONT_CARE_TAIL",
    "LEVEL_TOLERANCE_DEG",
    "LIDAR_OPTICAL",
    "OBJECT_CALIB_KEYS",
    "KittiWriter",
    "calib_text",
    "camera0",
    "dont_care_lines",
    "front_calib",
    "front_camera_turn",
    "kitti_label",
    "kitti_numbers",
    "label_lines",
    "occlusion_level",
    "truncation_level",
]


LIDAR_OPTICAL = np.eye(4)
LIDAR_OPTICAL[:3, :3] = BODY_TO_OPTICAL
"""``(4, 4)``: a body frame (x forward, y left, z up) in optical axes (x right, y down, z forward), no
translation: the ``Tr_velo_to_cam`` of an agent without a front camera, and the last step of every other's."""


def occlusion_level(occlusion: float | None) -> int:
    """KITTI's occluded flag from the fraction of the target hidden (``None``: not in the image → 3)."""
    if occlusion is None:
        return 3
    return 0 if occlusion < 0.25 else 1 if occlusion < 0.6 else 2


def kitti_numbers(values: Any) -> str:
    """The values of an array, row-major, as KITTI's calibration and pose files write them (``%.6e``)."""
    return " ".join(f"{float(v) + 0.0:.6e}" for v in np.asarray(values, dtype=np.float64).reshape(-1))


def front_calib(agent: AgentInfo, view: AgentView) -> tuple[np.ndarray, np.ndarray]:
    """KITTI's camera 0 of ``agent`` at ``view``: the front camera's ``K·[I|0]`` ``(3, 4)`` float64 (pixels) and
    the LiDAR → front optical frame (x right, y down, z forward) transform ``(4, 4)`` float64 (metres); zeros and
    the identity when the agent has no front camera. Both sensors are rigid on the hull: the transform is that of
    their mounts, the same bits in every frame (from the frame's world poses, its rounding moved with the hull's
    pose: entries of 1e-19 where 0 is exact, another in each frame's calibration file)."""
    assert view.lidar is not None and agent.lidar_mount is not None
    cam = agent.cameras.get("front")
    if cam is None:
        return np.zeros((3, 4)), np.eye(4)
    velo_to_cam = _lidar_to_front(agent.lidar_mount, cam.mount)
    fx, fy, cx, cy = cam.intrinsics
    return np.array([[fx, 0.0, cx, 0.0], [0.0, fy, cy, 0.0], [0.0, 0.0, 1.0, 0.0]]), velo_to_cam


def _lidar_to_front(lidar_mount: np.ndarray, camera_mount: np.ndarray) -> np.ndarray:
    """The LiDAR → front optical frame transform ``(4, 4)`` of a LiDAR and a camera rigid on the hull, from their
    mounts (sensor → hull)."""
    out: np.ndarray = LIDAR_OPTICAL @ invert(camera_mount) @ lidar_mount
    return out


LEVEL_TOLERANCE_DEG = 0.005
"""The largest turn (degrees) of a front camera against the LiDAR's own optical axes that :func:`front_camera_turn`
reports as none: below what its note's two decimals show."""


def front_camera_turn(agent: AgentInfo) -> tuple[float, float, float] | None:
    """How ``agent``'s front camera is turned against its LiDAR (both rigid on the hull, so the same in every frame):
    ``(angle, tilt, yaw)`` degrees, the angle of the rotation from the LiDAR's own optical axes
    (:data:`LIDAR_OPTICAL`) to the camera's, the angle between the camera's y axis (down) and the LiDAR's -z, and the
    bearing of the camera's optical axis from the LiDAR's x in the LiDAR's x-y plane (counter-clockwise, to the left
    positive); ``None`` without a front camera or LiDAR, or for a camera turned by at most
    :data:`LEVEL_TOLERANCE_DEG` (the rigs' default mounts: level and forward). KITTI's readers that turn labels into
    LiDAR boxes without the calibration's rotation (OpenPCDet's ``boxes3d_kitti_camera_to_lidar``: h/2 along the
    LiDAR's z, heading ``-(rotation_y + pi/2)``) are right only for a camera that is not turned."""
    cam = agent.cameras.get("front")
    if cam is None or agent.lidar_mount is None:
        return None
    r = _lidar_to_front(agent.lidar_mount, cam.mount)[:3, :3]  # LiDAR -> front optical, rotation
    rel = r @ BODY_TO_OPTICAL.T  # the turn: identity for a level, forward camera
    angle = math.degrees(math.acos(max(-1.0, min(1.0, (float(np.trace(rel)) - 1.0) / 2.0))))
    if angle <= LEVEL_TOLERANCE_DEG:
        return None
    down, axis = r[1], r[2]  # the camera's y (down) and z (optical axis) in LiDAR coordinates
    tilt = math.degrees(math.acos(max(-1.0, min(1.0, -float(down[2])))))
    yaw = math.degrees(math.atan2(float(axis[1]), float(axis[0])))
    return angle, tilt, yaw


def camera0(agent: AgentInfo, view: AgentView) -> tuple[np.ndarray, np.ndarray]:
    """KITTI's camera 0 of ``agent`` at ``view`` as the labels and calibration files use it: :func:`front_calib`,
    with, for an agent without a front camera, the LiDAR's own optical axes (:data:`LIDAR_OPTICAL`) as the camera,
    so that its labels keep KITTI's camera conventions (y down, ``rotation_y`` about y)."""
    k, velo_to_cam = front_calib(agent, view)
    return k, (velo_to_cam if "front" in agent.cameras else LIDAR_OPTICAL)


OBJECT_CALIB_KEYS = ("R0_rect:", "Tr_velo_to_cam:", "Tr_imu_to_velo:")
"""The names KITTI's object benchmark gives ``R0_rect``, ``Tr_velo_to_cam`` and ``Tr_imu_to_velo`` in its calibration
files (``calib/<ts>.txt``), with their colons; the tracking benchmark spells them otherwise."""


def calib_text(k: np.ndarray, *, velo_to_cam: np.ndarray, lidar_mount: np.ndarray, keys: tuple[str, ...]) -> bytes:
    """A KITTI calibration file: ``P0..P3`` = ``k`` (3×4), then the rectification (the identity), LiDAR → camera 0
    (``velo_to_cam``, 4×4) and vessel body → LiDAR (the inverse of ``lidar_mount``), named by ``keys``
    (:data:`OBJECT_CALIB_KEYS` or the tracking benchmark's)."""
    calib = [f"P{i}: {kitti_numbers(k)}" for i in range(4)]
    rect, velo, imu = keys
    calib += [
        f"{rect} {kitti_numbers(np.eye(3))}",
        f"{velo} {kitti_numbers(velo_to_cam[:3, :])}",
        f"{imu} {kitti_numbers(invert(lidar_mount)[:3, :])}",
    ]
    return ("\n".join(calib) + "\n").encode()


def label_lines(
    view: AgentView,
    targets: list[Target],
    messages: dict[str, Any],
    velo_to_cam: np.ndarray,
    kind: str | None = None,
    *,
    levels: bool = False,
) -> list[str]:
    """The ``label_2`` lines of ``targets`` (:func:`kitti_label`) for camera 0 ``velo_to_cam`` (:func:`camera0`), their
    2D boxes from the frame's ``messages`` (the agent's annotations: the front camera's boxes; none without a front
    camera), ``kind`` the type written for every target (``None``: each target's class name); ``levels``: truncation
    as the tracking benchmark's level (:func:`truncation_level`)."""
    cam = view.agent.cameras.get("front")
    boxes = {b.target_id: b for b in _front_boxes(view, messages)}
    lines = []
    for t in targets:
        box2d = boxes.get(t.id)
        unseen = 1.0  # no front camera, or a target out of its view
        if box2d is not None and box2d.visible_pixels == 0:
            # In view but no pixel of it seen (hidden wholly by the crests or by hulls): not a ground truth of the
            # image (KITTI's annotators label what they see; its evaluation ignores occluded 3), its share out of it
            # as recorded.
            unseen = float(box2d.truncation)
            box2d = None
        elif box2d is None and cam is not None:  # in view but too small for a pixel centre to meet it?
            corners = box_corners(velo_to_cam @ t.box_in_lidar, np.asarray(t.size, dtype=np.float64))
            unseen = pinhole_truncation(corners, intrinsics=cam.intrinsics, width=cam.width, height=cam.height)
        lines.append(kitti_label(t, velo_to_cam, box2d=box2d, kind=kind, levels=levels, unseen_truncation=unseen))
    return lines


DONT_CARE_TAIL = "-1 -1 -1 -1000 -1000 -1000 -10"
"""What follows a ``DontCare`` line's 2D box: KITTI's own (its ``label_2`` files: ``DontCare -1 -1 -10 x1 y1 x2 y2
-1 -1 -1 -1000 -1000 -1000 -10``)."""


def dont_care_lines(view: AgentView, targets: list[Target], messages: dict[str, Any]) -> list[str]:
    """KITTI's ``DontCare`` lines (type ``DontCare``, truncated and occluded -1, alpha -10, the 2D box, no 3D box:
    :data:`DONT_CARE_TAIL`) of the vessels the front image shows (a recorded front box with a visible pixel) that are
    not among ``targets``: beyond the evaluation range (a long ship whose centre is out of range while its bow is in
    the picture), or another USV without ``--include-usvs``. KITTI's evaluation ignores detections in these regions,
    as its own labels mark the objects they leave out, so a detector is not counted wrong for finding them. Sorted
    by the box's position in the image."""
    kept = {t.id for t in targets}
    boxes = sorted(
        (b.x_min, b.y_min, b.x_max, b.y_max)
        for b in _front_boxes(view, messages)
        if b.target_id not in kept and b.visible_pixels > 0
    )
    return [f"DontCare -1 -1 -10 {_label_numbers(bb)} {DONT_CARE_TAIL}" for bb in boxes]


def _front_boxes(view: AgentView, messages: dict[str, Any]) -> list[Any]:
    """The front camera's 2D boxes in the frame's ``messages`` (the agent's annotations); none without a front
    camera or without annotations."""
    ann = messages.get(topics.agent_annotations(view.agent.id))
    if ann is None or "front" not in view.agent.cameras:
        return []
    return [b for b in ann.boxes_camera if b.camera == "front"]


def _label_numbers(values: Any) -> str:
    """Numbers as a ``label_2`` line writes them: two decimals, no negative zero."""
    return " ".join(f"{round(float(v), 2) + 0.0:.2f}" for v in values)


def truncation_level(fraction: float | None) -> int:
    """The KITTI tracking benchmark's truncation (its raw data's tracklet levels: 0 in the image, 1 cut by the image
    border, 2 out of the image) of a target whose box in the image is cut by ``fraction`` (0..1, taken at the object
    labels' two decimals, so the two exports agree; ``None``: no part of it in the image, 2). A target with a box is in
    the image, so 1 however much of it is cut (a sliver of a long ship whose fraction rounds to 1.00 too)."""
    if fraction is None:
        return 2
    return 0 if round(float(fraction), 2) <= 0.0 else 1


def kitti_label(
    target: Target,
    velo_to_cam: np.ndarray,
    *,
    box2d: Any | None,
    kind: str | None = None,
    levels: bool = False,
    unseen_truncation: float = 1.0,
) -> str:
    """One ``label_2`` line of ``target`` (box in the LiDAR frame) for the camera ``velo_to_cam`` (4×4); ``kind``:
    the type written (``None``: the target's class name, capitalised); ``levels``: truncation written as the
    tracking benchmark's integer level (:func:`truncation_level`) instead of the object benchmark's fraction.
    Without ``box2d`` (no recorded box in the front image) occluded is 3 ("unknown"), the box ``0 0 0 0`` and
    truncated ``unseen_truncation``: the share of the target "leaving image boundaries" — 1 (the tracking level 2)
    for a target behind or beside the camera or without one, the share of its projected box outside the image
    (:func:`mmusv.image_boxes.pinhole_truncation`) for one in view that no pixel centre meets (:func:`label_lines`)."""
    length, beam, height = (float(x) for x in target.size)
    box_cam = velo_to_cam @ target.box_in_lidar
    centre = box_cam[:3, 3]
    # KITTI's box is upright in the camera frame (its height along the camera's y, down): the location is the box
    # centre h/2 down that axis, so that readers adding h/2 back get the centre. The bottom of the box itself, of a
    # hull rolling and pitching in waves, put that centre h/2 · tilt away (metres for a tall ship, every frame).
    bottom = centre + np.array([0.0, height / 2.0, 0.0])
    d = box_cam[:3, 0]
    ry = float(wrap_rad(math.atan2(-d[2], d[0])))
    alpha = float(wrap_rad(ry - math.atan2(centre[0], centre[2])))
    if box2d is None:  # no recorded box: state unknown, the share of it out of the image as given
        trunc, occ, bb = float(unseen_truncation), 3, (0.0, 0.0, 0.0, 0.0)
    else:
        trunc, occ = float(box2d.truncation), occlusion_level(float(box2d.occlusion))
        bb = (box2d.x_min, box2d.y_min, box2d.x_max, box2d.y_max)
    name = kind if kind is not None else class_name(target.semantic_class).capitalize()
    vals = [trunc, occ, alpha, *bb, height, beam, length, *bottom, ry]
    out_of_image = box2d is None and trunc >= 1.0
    cut = f"{truncation_level(None if out_of_image else trunc)}" if levels else f"{vals[0]:.2f}"
    return f"{name} {cut} {int(vals[1])} {_label_numbers(vals[2:])}"


class KittiWriter(DatasetWriter):
    """Writes one recording as KITTI-style per-agent folders (see the module docstring)."""

    format_version: ClassVar[int] = 4
    """2 (2026-12-02): ``truncated`` of a target without a front box is its share out of the image (it was 0); 3
    (2026-12-06): ``DontCare`` lines for the vessels the front image shows that are not targets; 4 (2026-12-06): a
    target in view with no pixel seen (hidden wholly) is occluded 3 with box ``0 0 0 0`` (it was occluded 2 with its
    projected box, a ground truth KITTI's evaluation scored)."""
    cameras: ClassVar[dict[str, int]] = {"front": 2}
    needs_agent: ClassVar[bool] = True
    image_folder: ClassVar[str] = "image_2"
    """The front images' folder (the notes name it)."""
    velo_key: ClassVar[str] = "Tr_velo_to_cam"
    """LiDAR → camera 0's name in the calibration files (the notes name it)."""
    distortion_file: ClassVar[str] = "; coefficients in mmusv_kitti.yaml"
    """Where else the notes say a front camera's lens distortion is written."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        image = self.image_folder
        for a in self.agents:
            cam = a.cameras.get("front")
            if cam is None:
                self.notes.append(
                    f"agent {a.id} has no front camera: no {image}, P0..P3 are zeros and {self.velo_key} is the "
                    "LiDAR's own optical axes (labels without 2D boxes, occluded 3)"
                )
                continue
            if "rgb" not in cam.outputs:
                self.notes.append(f"agent {a.id}: front camera records no rgb images: no {image}")
            if cam.distortion is not None and any(cam.distortion):
                self.notes.append(
                    f"agent {a.id}: front camera has lens distortion {list(cam.distortion)} [k1, k2, p1, p2, k3]: "
                    f"{image} is not rectified (P2 is its pinhole K{self.distortion_file})"
                )
            turn = front_camera_turn(a)
            if turn is not None:
                angle, tilt, yaw = turn
                self.notes.append(
                    f"agent {a.id}: front camera turned {angle:.2f} deg against the LiDAR (its y axis {tilt:.2f} deg "
                    f"off the LiDAR's -z, its optical axis {yaw:+.2f} deg off the LiDAR's x in bird's-eye view): the "
                    f"labels are in its frame, as KITTI's devkit reads them, but readers that take the camera as "
                    f"level and forward (OpenPCDet's boxes3d_kitti_camera_to_lidar: h/2 added along the LiDAR's z, "
                    f"heading -(rotation_y + pi/2)) get LiDAR boxes h * sin({tilt / 2:.2f} deg) off centre (h the box "
                    f"height) and turned by about {-yaw:+.2f} deg; turn the labels with the inverse of {self.velo_key} "
                    f"instead"
                )

    def optional_topics(self) -> list[str]:
        return super().optional_topics() + [topics.agent_annotations(a.id) for a in self.agents]

    def _dir(self, agent: AgentInfo, sub: str) -> Path:
        return self.sink.mkdir(self.folder / str(cav_id(agent.index)) / sub)

    def frame_file(self, agent: AgentInfo, folder: str, *, index: int, ext: str) -> Path:
        """Where the file of ``agent`` at acquisition index ``index`` in ``folder`` (KITTI's object layout's name:
        ``velodyne``, ``image_2``, ``depth_2``, …, ``top_view_semantic``) goes, its folder created."""
        return self._dir(agent, folder) / f"{index:06d}{ext}"

    def write_sensors(self, frame: Frame, view: AgentView) -> None:
        """The agent's LiDAR scan (``velodyne``), front image (``image_2``) and extras of ``frame``."""
        from mmusv.recording import decode_point_cloud

        a = view.agent
        msgs = frame.messages
        cloud = decode_point_cloud(msgs[topics.lidar(a.id)])
        n = len(cloud["x"])
        pts = np.column_stack([cloud["x"], cloud["y"], cloud["z"], cloud.get("intensity", np.zeros(n))]).astype("<f4")
        self.put(self.frame_file(a, "velodyne", index=frame.index, ext=".bin"), pts.tobytes())
        if "front" in a.cameras:
            base = topics.camera(a.id, "front") + "/"
            if base + "rgb" in msgs:
                self.put(self.frame_file(a, "image_2", index=frame.index, ext=".png"), png_bytes(msgs[base + "rgb"]))
            if "depth" in self.options.extras and base + "depth" in msgs:
                self.put(
                    self.frame_file(a, "depth_2", index=frame.index, ext=".png"),
                    depth_png(msgs[base + "depth"]),
                    "depth",
                )
            for kind in ("semantic", "instance"):
                if kind in self.options.extras and base + kind in msgs:
                    path = self.frame_file(a, f"{kind}_2", index=frame.index, ext=".png")
                    self.put(path, png_bytes(msgs[base + kind]), kind)
        if "radar" in self.options.extras and topics.radar_ppi(a.id) in msgs:
            path = self.frame_file(a, "radar_ppi", index=frame.index, ext=".png")
            self.put(path, png_bytes(msgs[topics.radar_ppi(a.id)]), "radar")
        if "top_view" in self.options.extras:
            for kind in ("rgb", "semantic"):
                m = msgs.get(topics.top_view(a.id, kind))
                if m is not None:
                    self.put(
                        self.frame_file(a, f"top_view_{kind}", index=frame.index, ext=".png"), png_bytes(m), "top_view"
                    )

    def write_agent(self, frame: Frame, world: WorldFrame, view: AgentView, targets: list[Target]) -> None:
        a = view.agent
        assert view.lidar is not None and a.lidar_mount is not None
        ts = f"{frame.index:06d}"
        self.write_sensors(frame, view)
        self.put(self._dir(a, "pose") / f"{ts}.txt", (kitti_numbers(view.lidar[:3, :]) + "\n").encode())
        k, velo_to_cam = camera0(a, view)
        self.put(
            self._dir(a, "calib") / f"{ts}.txt",
            calib_text(k, velo_to_cam=velo_to_cam, lidar_mount=a.lidar_mount, keys=OBJECT_CALIB_KEYS),
        )
        lines = label_lines(view, targets, frame.messages, velo_to_cam) + dont_care_lines(view, targets, frame.messages)
        self.put(self._dir(a, "label_2") / f"{ts}.txt", "".join(line + "\n" for line in lines).encode())

    def finish(self, frames: list[int], skipped: list[dict[str, Any]]) -> None:
        super().finish(frames, skipped)
        if not frames:
            return
        o = self.options
        self.put(
            self.folder / "mmusv_kitti.yaml",
            dump_yaml(
                {
                    "source": self.info.path.name,
                    "scenario": self.info.scenario_name,
                    "config_hash": self.info.config_hash,
                    "agents": {cav_id(a.index): a.id for a in self.agents},
                    # Brown–Conrady [k1, k2, p1, p2, k3] of image_2 (OpenCV's order); null: no front camera
                    "front_camera_distortion": {
                        cav_id(a.index): (
                            None
                            if "front" not in a.cameras
                            else [float(v) for v in (a.cameras["front"].distortion or (0.0,) * 5)]
                        )
                        for a in self.agents
                    },
                    "eval_range_m": o.eval_range_m,
                    # the files' <ts> is the acquisition index k, taken at k / frequency_hz s (sim time)
                    "frequency_hz": self.info.frequency_hz,
                    "include_usvs": o.include_usvs,
                    "extras": list(o.extras),
                    **(
                        top_view_protocol(self.agents, frame="kitti", files="<cav_id>/top_view_{rgb,semantic}/<ts>.png")
                        if "top_view" in o.extras
                        else {}
                    ),
                    "frames_converted": len(frames),
                    "frames_skipped": skipped,
                }
            ),
        )
