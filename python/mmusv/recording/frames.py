"""Writing captured frames into the MCAP recording: which topic gets what (the layout of ``docs/recording.md``).

Per frame k (log time = t_k in ns, the same for every message of the frame):

* ``/tf`` — ``foxglove.FrameTransforms``: ``world → <vessel>`` for every vessel, and for every agent
  ``<agent> → <agent>/lidar``, ``<agent>/radar``, ``<agent>/camera/<name>`` (optical frame: x right, y down,
  z forward), ``world → <agent>/top_view`` (optical frame of the top-view camera);
* ``/world/state`` — ``mmusv.WorldState``;
* per agent: ``/<agent>/lidar`` (``foxglove.PointCloud``: x, y, z, intensity float32, ring uint16, azimuth
  float32, class uint16, instance int32; LiDAR frame), ``/<agent>/camera/<name>/rgb`` (PNG),
  ``.../depth`` (RawImage 32FC1, metres along the optical axis, +inf = sky), ``.../semantic`` (PNG uint16 class
  ids), ``.../instance`` (PNG uint16 instance ids, 65535 = sky), ``.../calibration``
  (``foxglove.CameraCalibration``: the intrinsics in OpenCV's pixel convention and the ``plumb_bob`` distortion),
  ``.../boxes`` (``foxglove.ImageAnnotations``: the camera's 2D boxes, when the run annotates),
  ``/<agent>/top_view/{rgb,semantic,instance}``,
  ``/<agent>/radar/returns`` (PointCloud: x, y, z, range, azimuth, elevation, intensity float32, instance int32;
  radar frame), ``/<agent>/radar/ppi`` (PNG, colour-mapped PPI), ``/<agent>/boxes`` (``foxglove.SceneUpdate`` in
  the LiDAR frame, or in the vessel's body frame ``<agent>`` when the rig has no LiDAR) and
  ``/<agent>/annotations`` (``mmusv.AgentAnnotations``, boxes in the same frame).

Metadata records: ``scenario`` (the resolved YAML), ``manifest`` (mmusv version, seed, config hash, and the
frames the run sets out to write: ``first_frame``, ``frames_requested``), ``sensors`` (JSON: per agent, mounts and
camera intrinsics), ``run`` (status, frames written, frequency, agents; written last).
"""

from __future__ import annotations

import contextlib
import json
import threading
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from scipy.spatial.transform import Rotation

from mmusv.classes import ROLE_COLOURS
from mmusv.config import scenario_hash
from mmusv.errors import MmusvError
from mmusv.frames import OPTICAL_IN_BODY
from mmusv.held_signals import HeldSignals
from mmusv.recording import topics
from mmusv.recording.writer import ImageFormat, Recording
from mmusv.sensors.camera import CameraImages
from mmusv.simulation import FrameCapture, Simulation

__all__ = ["OPTICAL_IN_BODY", "FrameRecorder", "pose7"]


def _images(
    topic: str, frame_id: str, img: CameraImages, outputs: Sequence[str]
) -> list[tuple[str, str, np.ndarray, ImageFormat]]:
    """The images of one camera as :meth:`Recording.images` takes them, in topic order: ``rgb`` (PNG), ``depth``
    (raw float32 metres), ``semantic`` (PNG uint16), ``instance`` (PNG uint16, 65535 = sky)."""
    out: list[tuple[str, str, np.ndarray, ImageFormat]] = []
    if img.rgb is not None and "rgb" in outputs:
        out.append((f"{topic}/rgb", frame_id, img.rgb, "png"))
    if "depth" in outputs:
        out.append((f"{topic}/depth", frame_id, np.ascontiguousarray(img.depth, dtype=np.float32), "raw"))
    if "semantic" in outputs:
        out.append((f"{topic}/semantic", frame_id, img.semantic, "png"))
    if "instance" in outputs:
        out.append(
            (f"{topic}/instance", frame_id, np.where(img.instance < 0, 65535, img.instance).astype(np.uint16), "png")
        )
    return out


def pose7(m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Translation ``(3,)`` (``m``'s dtype and unit: metres for a pose) and unit quaternion ``(4,)`` float64
    (x, y, z, w) of a ``(4, 4)`` rigid transform."""
    return m[:3, 3].copy(), Rotation.from_matrix(m[:3, :3]).as_quat()


def _sensors(sim: Simulation) -> dict[str, Any]:
    """The ``sensors`` metadata of ``sim``: per agent, its asset, mounts, cameras and rig."""
    sensors: dict[str, Any] = {}
    for a in sim.agents:
        cams = {}
        for name, (cam, cfg, mount) in a.cameras.items():
            cams[name] = {
                "resolution": list(cfg.resolution),
                "hfov_deg": cfg.hfov_deg,
                "intrinsics": list(cam.intrinsics or ()),
                "distortion": None if cfg.distortion is None else list(cfg.distortion),
                "quality": cfg.quality,
                "mount_in_body": np.round(mount, 9).tolist(),
                "outputs": list(cfg.outputs),
            }
        sensors[a.id] = {
            "asset": a.asset.name,
            "lidar_mount_in_body": None if a.lidar_mount is None else np.round(a.lidar_mount, 9).tolist(),
            "radar_mount_in_body": None if a.radar_mount is None else np.round(a.radar_mount, 9).tolist(),
            "cameras": cams,
            "rig": a.rig.model_dump(mode="json"),
        }
    return sensors


class FrameRecorder:
    """Streams :class:`~mmusv.simulation.FrameCapture` frames of ``sim`` into ``path``.

    Threads may share one: each :meth:`write_frame` writes its frame's messages together, as the readers need
    (:class:`~mmusv.recording.stream.FrameStream` reads a frame from its messages in a row; two threads writing
    frames at once interleaved them, and each frame was read back with a few of its topics).
    """

    def __init__(
        self,
        path: Path,
        sim: Simulation,
        *,
        overwrite: bool = False,
        frames: tuple[int, int] | None = None,
        frame_range: bool = False,
    ) -> None:
        """``frames``: ``(first, count)``, the acquisition indices the run sets out to write, kept in the
        ``manifest`` metadata from the start, so that a run killed before :meth:`finish` still says what it
        meant to record (``None``: the scenario's ``acquisition.frames`` from index 0). ``frame_range``: these
        frames are a range recorded alone (one part of a split recording, ``acquire.run(frame_range=...)``), not a
        whole run from index 0 cut short by ``frames``; the ``manifest`` metadata then says ``frame_range: true``,
        so that a killed part 0 recovered away from its parts manifest still says where it starts."""
        self.sim = sim
        self._lock = threading.Lock()
        self.encode_seconds = 0.0
        """Wall seconds spent encoding images so far (for profiling)."""
        self.roles = {v.id: v.role for v in sim.vessels}
        sc = sim.scenario
        from mmusv import __version__

        first, count = (0, sc.acquisition.frames) if frames is None else frames
        metadata: dict[str, dict[str, Any]] = {
            "scenario": {"name": sc.name, "yaml": yaml.safe_dump(sc.model_dump(mode="json"), sort_keys=False)},
            "manifest": {
                "mmusv_version": __version__,
                "seed": sc.seed,
                "config_hash": scenario_hash(sc),
                "first_frame": first,
                "frames_requested": count,
                **({"frame_range": "true"} if frame_range else {}),
            },
            "sensors": {"json": json.dumps(_sensors(sim), sort_keys=True)},
        }
        # The file and every metadata record together: a stop (SIGINT, SIGTERM) that comes meanwhile is held until
        # they are written, and a failure removes the file, so a .partial always says what it is (a stop here left
        # one without its manifest and sensors, which `mmusv info` and `mmusv recover` could not read).
        with HeldSignals():
            self.rec = Recording(path, overwrite=overwrite)
            try:
                for name, values in metadata.items():
                    self.rec.metadata(name, values)
            except BaseException:
                self.discard()
                raise

    def discard(self) -> None:
        """Closes and removes the ``.partial`` of a recording just opened, before any frame: one that could not be
        opened whole, or that the run will not write after all."""
        partial = self.rec.partial_path
        with contextlib.suppress(MmusvError):
            self.rec.abandon()
        with contextlib.suppress(OSError):
            partial.unlink()

    # ------------------------------------------------------------------------------------------ per frame

    def write_frame(self, cap: FrameCapture, annotations: dict[str, dict[str, Any]]) -> None:
        """Writes every message of one frame, together (one thread at a time); ``annotations`` maps an agent to its
        ``Annotations.columns()``."""
        with self._lock:
            self._write_frame(cap, annotations)

    def _write_frame(self, cap: FrameCapture, annotations: dict[str, dict[str, Any]]) -> None:
        """:meth:`write_frame` under the lock."""
        t = round(cap.time_s * 1e9)
        sim, st, rec = self.sim, cap.world, self.rec
        tfs: list[tuple[str, str, np.ndarray, np.ndarray]] = []
        for i, v in enumerate(sim.vessels):
            tfs.append((topics.WORLD_FRAME, v.id, *pose7(st.matrices[i])))
        for a in sim.agents:
            ac = cap.agents.get(a.id)
            if ac is None:
                continue
            mounts = ac.sensors  # sensor → body as resolved for the capture (not recomputed from the poses)
            if ac.lidar_pose is not None:
                tfs.append((a.id, topics.lidar_frame(a.id), *pose7(mounts["lidar"].mount)))
            if ac.radar_pose is not None:
                tfs.append((a.id, topics.radar_frame(a.id), *pose7(mounts["radar"].mount)))
            for name in ac.camera_poses:
                mount = mounts[f"camera/{name}"].mount
                tfs.append((a.id, topics.camera_frame(a.id, name), *pose7(mount @ OPTICAL_IN_BODY)))
            if ac.top_view_pose is not None:
                tfs.append(
                    (topics.WORLD_FRAME, topics.top_view_frame(a.id), *pose7(ac.top_view_pose @ OPTICAL_IN_BODY))
                )
        rec.frame_transforms(topics.TF, log_time_ns=t, transforms=tfs)
        rec.world_state(
            topics.WORLD_STATE,
            log_time_ns=t,
            frame=cap.frame,
            time_s=cap.time_s,
            ids=[v.id for v in sim.vessels],
            assets=[v.asset for v in sim.vessels],
            roles=[v.role for v in sim.vessels],
            classes=[v.semantic_class for v in sim.vessels],
            instance_ids=[v.instance_id for v in sim.vessels],
            poses=st.poses,
            velocities=st.velocities,
            box_centers=st.box_centers,
            box_sizes=np.array([v.box_size for v in sim.vessels]).reshape(-1, 3),
        )
        for a in sim.agents:
            ac = cap.agents.get(a.id)
            if ac is None:
                continue
            if ac.lidar is not None:
                pts = ac.lidar
                rec.point_cloud(
                    topics.lidar(a.id),
                    log_time_ns=t,
                    frame_id=topics.lidar_frame(a.id),
                    columns={
                        "x": pts.xyz[:, 0],
                        "y": pts.xyz[:, 1],
                        "z": pts.xyz[:, 2],
                        "intensity": pts.intensity,
                        "ring": pts.ring,
                        "azimuth": pts.azimuth,
                        "class": pts.semantic_class,
                        "instance": pts.instance,
                    },
                )
            images: list[tuple[str, str, np.ndarray, ImageFormat]] = []
            for name, img in ac.cameras.items():
                outputs = a.cameras[name][1].outputs
                images += _images(topics.camera(a.id, name), topics.camera_frame(a.id, name), img, outputs)
            if ac.top_view is not None and a.rig.top_view is not None:
                top = a.rig.top_view.outputs
                images += _images(topics.top_view(a.id), topics.top_view_frame(a.id), ac.top_view, top)
            if images:  # one call per agent: encoded in parallel, written in this order
                self.encode_seconds += rec.images(log_time_ns=t, images=images)[0]
            self._camera_extras(a, list(ac.cameras), t, annotations.get(a.id))
            if ac.radar is not None:
                self._radar(a.id, t, ac.radar, ac.radar_ppi)
            cols = annotations.get(a.id)
            if cols is not None:
                rec.annotations(
                    topics.agent_annotations(a.id),
                    log_time_ns=t,
                    frame=cap.frame,
                    time_s=cap.time_s,
                    agent_id=a.id,
                    lidar=cols["lidar"],
                    bev=cols["bev"],
                    camera=cols["camera"],
                )
                lid = cols["lidar"]
                colours = np.array(
                    [ROLE_COLOURS.get(self.roles.get(i, "target"), (1, 1, 1, 0.5)) for i in lid["target_id"]]
                ).reshape(-1, 4)
                # The boxes are in the LiDAR frame, or in the vessel's body frame when the rig has no LiDAR
                # (mmusv.annotate): name the frame /tf defines for them, or Foxglove cannot place them.
                box_frame = topics.lidar_frame(a.id) if ac.lidar_pose is not None else a.id
                rec.boxes(
                    topics.boxes(a.id),
                    log_time_ns=t,
                    frame_id=box_frame,
                    entity_id=f"{a.id}/targets",
                    ids=lid["target_id"],
                    centers=lid["center"],
                    quaternions=lid["rotation"],
                    sizes=lid["size"],
                    colors=colours,
                )

    def _camera_extras(self, a: Any, names: list[str], t: int, cols: dict[str, Any] | None) -> None:
        """Each camera's ``foxglove.CameraCalibration`` and, with the frame's annotation columns ``cols``, its 2D
        boxes as ``foxglove.ImageAnnotations`` (coloured by role, labelled with the target's id)."""
        from mmusv.sensors.camera import opencv_intrinsics

        if cols is not None:  # the agent's 2D boxes, every camera's, once
            c = cols["camera"]
            which = np.array(c["camera"], dtype=object)
            corners = np.column_stack([c[k] for k in ("x_min", "y_min", "x_max", "y_max")]).reshape(-1, 4)
            colours = [(*ROLE_COLOURS.get(r, (1, 1, 1, 1))[:3], 1.0) for r in c["role"]]
            colours_rgba = np.array(colours, np.float32).reshape(-1, 4)
            target_ids = np.array(c["target_id"], dtype=object)
        for name in names:
            cam, cfg, _mount = a.cameras[name]
            if cam.intrinsics:
                self.rec.camera_calibration(
                    topics.camera_calibration(a.id, name),
                    log_time_ns=t,
                    frame_id=topics.camera_frame(a.id, name),
                    width=int(cfg.resolution[0]),
                    height=int(cfg.resolution[1]),
                    intrinsics=opencv_intrinsics(tuple(cam.intrinsics)),
                    distortion=cfg.distortion,
                )
            if cols is not None:
                mine = which == name
                self.rec.image_boxes(
                    topics.camera_boxes(a.id, name),
                    log_time_ns=t,
                    corners=corners[mine],
                    colors=colours_rgba[mine],
                    labels=[str(i) for i in target_ids[mine]],
                )

    def _radar(self, agent: str, t: int, returns: Any, ppi: np.ndarray | None) -> None:
        from mmusv.sensors.radar import ppi_colormap

        r, az, el = returns.range, returns.azimuth, returns.elevation
        ce = np.cos(el)
        self.rec.point_cloud(
            topics.radar_returns(agent),
            log_time_ns=t,
            frame_id=topics.radar_frame(agent),
            columns={
                "x": (r * ce * np.cos(az)).astype(np.float32),
                "y": (r * ce * np.sin(az)).astype(np.float32),
                "z": (r * np.sin(el)).astype(np.float32),
                "range": r,
                "azimuth": az,
                "elevation": el,
                "intensity": returns.intensity,
                "instance": returns.instance_id,
            },
        )
        if ppi is not None:
            self.rec.png_image(
                topics.radar_ppi(agent), log_time_ns=t, frame_id=topics.radar_frame(agent), image=ppi_colormap(ppi)
            )

    # ------------------------------------------------------------------------------------------ end

    def finish(
        self,
        *,
        status: str,
        frames: int,
        error: str | None = None,
        requested: int | None = None,
        first_frame: int | None = None,
    ) -> dict[str, Any]:
        """Writes the ``run`` metadata and completes the file (also after an interruption: the file then holds
        every completed frame and says ``status: interrupted``). ``first_frame``: the first acquisition index of
        a part of a recording split into frame ranges (then ``requested`` frames from there)."""
        sc = self.sim.scenario
        meta = {
            "scenario": sc.name,
            "status": status,
            "frames_written": frames,
            "frames_configured": sc.acquisition.frames,
            "frequency_hz": sc.acquisition.frequency_hz,
            "agents": ",".join(a.id for a in self.sim.agents),
        }
        if requested is not None:  # a run limited to its first N frames (--frames N)
            meta["frames_requested"] = requested
        if first_frame is not None:  # one part of a split recording: frames first_frame .. + requested - 1
            meta["first_frame"] = first_frame
        if error:
            meta["error"] = error
        with self._lock:  # after a frame being written by another thread
            self.rec.metadata("run", meta)
            summary: dict[str, Any] = self.rec.finish()
        return summary
