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
2: more, 3: not in the front image, with box ``0 0 0 0``).
An agent without a front camera has no ``image_2``, zero ``P0..P3`` and, as camera, the LiDAR's own optical axes
(``Tr_velo_to_cam`` = the rotation x right, y down, z forward): its labels keep KITTI's camera conventions, so
KITTI's readers turn them into LiDAR boxes with the right heading. A front camera's lens distortion (KITTI's
images are rectified; ``P2`` is a pinhole) is in ``mmusv_kitti.yaml`` and the conversion's notes.
Extras: ``depth_2`` (uint16 cm), ``semantic_2``, ``instance_2``, ``radar_ppi``, ``top_view_rgb``,
``top_view_semantic``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from mmusv.classes import class_name
from mmusv.export.common import cav_id, depth_png, dump_yaml, png_bytes
from mmusv.export.geometry import AgentView, Target
from mmusv.export.writer import DatasetWriter
from mmusv.frames import BODY_TO_OPTICAL, invert, wrap_rad
from mmusv.recording import topics
from mmusv.recording.decode import WorldFrame
from mmusv.recording.info import AgentInfo
from mmusv.recording.stream import Frame

__all__ = ["LIDAR_OPTICAL", "KittiWriter", "front_calib", "kitti_label", "kitti_numbers", "occlusion_level"]


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
    """KITTI's camera 0 of ``agent`` at ``view``: the front camera's ``K·[I|0]`` ``(3, 4)`` and the LiDAR → front
    optical frame transform ``(4, 4)``; zeros and the identity when the agent has no front camera."""
    assert view.lidar is not None
    cam = agent.cameras.get("front")
    if cam is None:
        return np.zeros((3, 4)), np.eye(4)
    velo_to_cam = LIDAR_OPTICAL @ invert(view.cameras["front"]) @ view.lidar
    fx, fy, cx, cy = cam.intrinsics
    return np.array([[fx, 0.0, cx, 0.0], [0.0, fy, cy, 0.0], [0.0, 0.0, 1.0, 0.0]]), velo_to_cam


def kitti_label(target: Target, velo_to_cam: np.ndarray, box2d: Any | None) -> str:
    """One ``label_2`` line of ``target`` (box in the LiDAR frame) for the camera ``velo_to_cam`` (4×4)."""
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
    if box2d is None:
        trunc, occ, bb = 0.0, 3, (0.0, 0.0, 0.0, 0.0)
    else:
        trunc, occ = float(box2d.truncation), occlusion_level(float(box2d.occlusion))
        bb = (box2d.x_min, box2d.y_min, box2d.x_max, box2d.y_max)
    name = class_name(target.semantic_class).capitalize()
    vals = [trunc, occ, alpha, *bb, height, beam, length, *bottom, ry]
    return f"{name} {vals[0]:.2f} {int(vals[1])} " + " ".join(f"{round(float(v), 2) + 0.0:.2f}" for v in vals[2:])


class KittiWriter(DatasetWriter):
    """Writes one recording as KITTI-style per-agent folders (see the module docstring)."""

    cameras: ClassVar[dict[str, int]] = {"front": 2}
    needs_agent: ClassVar[bool] = True

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        for a in self.agents:
            cam = a.cameras.get("front")
            if cam is None:
                self.notes.append(
                    f"agent {a.id} has no front camera: no image_2, P0..P3 are zeros and Tr_velo_to_cam is the "
                    "LiDAR's own optical axes (labels without 2D boxes, occluded 3)"
                )
                continue
            if "rgb" not in cam.outputs:
                self.notes.append(f"agent {a.id}: front camera records no rgb images: no image_2")
            if cam.distortion is not None and any(cam.distortion):
                self.notes.append(
                    f"agent {a.id}: front camera has lens distortion {list(cam.distortion)} [k1, k2, p1, p2, k3]: "
                    "image_2 is not rectified (P2 is its pinhole K; coefficients in mmusv_kitti.yaml)"
                )

    def optional_topics(self) -> list[str]:
        return super().optional_topics() + [topics.agent_annotations(a.id) for a in self.agents]

    def _dir(self, agent: AgentInfo, sub: str) -> Path:
        return self.sink.mkdir(self.folder / str(cav_id(agent.index)) / sub)

    def write_agent(self, frame: Frame, world: WorldFrame, view: AgentView, targets: list[Target]) -> None:
        from mmusv.recording import decode_point_cloud

        a = view.agent
        assert view.lidar is not None and a.lidar_mount is not None
        ts = f"{frame.index:06d}"
        msgs = frame.messages
        cloud = decode_point_cloud(msgs[topics.lidar(a.id)])
        n = len(cloud["x"])
        pts = np.column_stack([cloud["x"], cloud["y"], cloud["z"], cloud.get("intensity", np.zeros(n))]).astype("<f4")
        self.put(self._dir(a, "velodyne") / f"{ts}.bin", pts.tobytes())
        self.put(self._dir(a, "pose") / f"{ts}.txt", (kitti_numbers(view.lidar[:3, :]) + "\n").encode())
        cam = a.cameras.get("front")
        k, velo_to_cam = front_calib(a, view)
        if cam is None:
            velo_to_cam = LIDAR_OPTICAL  # labels in KITTI's camera axes (y down, rotation_y about y) at the LiDAR
        calib = [f"P{i}: {kitti_numbers(k)}" for i in range(4)]
        calib += [
            f"R0_rect: {kitti_numbers(np.eye(3))}",
            f"Tr_velo_to_cam: {kitti_numbers(velo_to_cam[:3, :])}",
            f"Tr_imu_to_velo: {kitti_numbers(invert(a.lidar_mount)[:3, :])}",
        ]
        self.put(self._dir(a, "calib") / f"{ts}.txt", ("\n".join(calib) + "\n").encode())
        boxes: dict[str, Any] = {}
        ann = msgs.get(topics.agent_annotations(a.id))
        if ann is not None:
            boxes = {b.target_id: b for b in ann.boxes_camera if b.camera == "front"}
        lines = [kitti_label(t, velo_to_cam, boxes.get(t.id) if cam is not None else None) for t in targets]
        self.put(self._dir(a, "label_2") / f"{ts}.txt", "".join(line + "\n" for line in lines).encode())
        if cam is not None:
            base = topics.camera(a.id, "front") + "/"
            if base + "rgb" in msgs:
                self.put(self._dir(a, "image_2") / f"{ts}.png", png_bytes(msgs[base + "rgb"]))
            if "depth" in self.options.extras and base + "depth" in msgs:
                self.put(self._dir(a, "depth_2") / f"{ts}.png", depth_png(msgs[base + "depth"]), "depth")
            for kind in ("semantic", "instance"):
                if kind in self.options.extras and base + kind in msgs:
                    self.put(self._dir(a, f"{kind}_2") / f"{ts}.png", png_bytes(msgs[base + kind]), kind)
        if "radar" in self.options.extras and topics.radar_ppi(a.id) in msgs:
            self.put(self._dir(a, "radar_ppi") / f"{ts}.png", png_bytes(msgs[topics.radar_ppi(a.id)]), "radar")
        if "top_view" in self.options.extras:
            for kind in ("rgb", "semantic"):
                m = msgs.get(topics.top_view(a.id, kind))
                if m is not None:
                    self.put(self._dir(a, f"top_view_{kind}") / f"{ts}.png", png_bytes(m), "top_view")

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
                    "frames_converted": len(frames),
                    "frames_skipped": skipped,
                }
            ),
        )
