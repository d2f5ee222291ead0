"""The OPV2V layout: one scenario folder per recording, one integer folder per agent.

``<scenario>/<cav_id>/<ts>.yaml``, ``<ts>.pcd``, ``<ts>_camera0..3.png`` (+ ``<scenario>/data_protocol.yaml``);
``<ts>`` is the 6-digit acquisition index, the same for every agent; ``cav_id`` = 1000 + the vessel's index in
the scenario (:func:`~mmusv.export.common.cav_id`), also the key of ``vehicles``. Everything is in the CARLA
frame (left-handed, x forward, y right, z up, metres, degrees, poses ``[x, y, z, roll, yaw, pitch]``), obtained
from mmusv's frames only through :mod:`mmusv.frames` (a mirror of y).

Per-frame yaml (keys sorted, as OpenCDA writes them): ``camera0..3`` (``cords`` world pose, ``intrinsic``,
``extrinsic`` LiDAR → camera), ``ego_speed`` (km/h), ``lidar_pose``, ``plan_trajectory`` (the scenario route:
``[x, y, speed km/h]``), ``predicted_ego_pos`` = ``true_ego_pos`` (the vessel pose), ``vehicles``
(``{id: {angle: [roll, yaw, pitch], center, extent (half sizes), location, speed km/h}}``, box centre =
location + center component-wise). Camera order: 0 front, 1 right, 2 left, 3 rear. Both speeds are the norm of
the world-state velocity ``(vx, vy, vz)``, as CARLA's 3D velocity in OpenCDA's ``get_speed``: in waves the heave
rate ``vz`` is part of it, so a vessel sailing at ``speed_mps`` shows a little more, changing from frame to frame
(0.4 m/s for a 9 m/s speedboat at W2); the speed over ground is ``hypot(vx, vy)`` of the world state (=
``speed_mps`` under way).

``data_protocol.yaml``: OpenCDA's ``world`` and ``vehicle_base`` (one LiDAR for every CAV: the first agent's, as
CARLA's attributes ``channels``, ``range``, ``upper_fov``, ...), and under ``mmusv`` the source, ``cavs`` and
``lidars``, each agent's LiDAR by ``cav_id`` (the conversion's notes say when they differ); with the ``top_view``
extra, ``top_views`` (each agent's top view by ``cav_id``: ``resolution``, ``metres_per_pixel``, ``orientation``,
``altitude_m``) and ``top_view_png`` (where each pixel lies, from ``true_ego_pos``:
:func:`mmusv.export.common.top_view_protocol`).

Files beyond stock OPV2V, which stock loaders skip: ``<ts>_additional.yaml`` (our names, classes, LiDAR point
counts and wave-occlusion shares of the listed vehicles: ``wave_occlusion``, the recorded share of the vessel's part
above the still level that the waves hide from this agent's LiDAR, 0 over a flat sea, ``null`` for a recording made
before the field existed), ``<ts>_depth{i}.png`` (HEAL's OPV2V-H depth: 8-bit grayscale, whole metres
along the optical axis, 255 = no hit or 254.5 m and farther; :func:`heal_depth_png`), ``<ts>_depth_cm{i}.png`` (the
same depth as uint16 centimetres, 0 = no hit, 65535 = 655.35 m or farther), ``<ts>_semantic{i}.png``,
``<ts>_instance{i}.png`` (uint16 ids), ``<ts>_radar_ppi.png``, ``<ts>_topview_{rgb,semantic}.png``.

HEAL (``yifanlu0227/HEAL``, ``opencood/data_utils/datasets/basedataset/opv2v_basedataset.py``) reads
``<ts>_depth{i}.png`` with ``PIL.Image.open`` and turns it into its depth channel with
``torchvision.transforms.ToTensor()(img) * 255`` (``intermediate_heter_fusion_dataset.py`` and the other fusion
datasets), which its LSS encoders bin as metres (``ddiscr`` ``[2, 50, 48]`` …, values past the last bin clamped to it).
That is only metres for an 8-bit image: ``ToTensor`` divides a mode ``L`` image by 255, but returns a 16-bit PNG
(mode ``I;16``) as int16 counts, unscaled, which the ``* 255`` then overflows. HEAL looks for the depth files under
the camera folder's path with ``OPV2V`` replaced by ``OPV2V_Hetero``: beside the cameras when the path has no
``OPV2V`` in it, otherwise in that mirror folder (``docs/opencood.md``).

Beside the export, ``opencood/point_pillar_{early,late,intermediate}_fusion.yaml``: OpenCOOD hypes sized from
the exported vessels and distances (:mod:`mmusv.export.opencood`, ``docs/opencood.md``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from mmusv.classes import class_name
from mmusv.export.common import (
    DEPTH_UNIT_M,
    cav_id,
    depth_metres,
    depth_units_png,
    dump_yaml,
    encode_png,
    png_bytes,
    rounded,
    rounded_share,
    top_view_protocol,
    wave_share,
)
from mmusv.export.geometry import AgentView, Target
from mmusv.export.opencood import HypesStats, constants, hypes
from mmusv.export.pcd import pcd_bytes
from mmusv.export.writer import DatasetWriter
from mmusv.frames import carla_matrix, carla_pose, invert, mirror_points
from mmusv.recording import topics
from mmusv.recording.decode import WorldFrame
from mmusv.recording.stream import Frame

__all__ = ["HEAL_DEPTH_FAR", "OPV2V_CAMERAS", "Opv2vWriter", "heal_depth_png", "timestamp"]

OPV2V_CAMERAS = {"front": 0, "right": 1, "left": 2, "rear": 3, "back": 3}
"""Our camera name → OPV2V camera index."""


HEAL_DEPTH_FAR = 255
"""The value of ``<ts>_depth{i}.png`` for no hit (sky) and for 254.5 m or farther: the largest 8-bit value, which
HEAL's depth binning clamps into its farthest bin (a 0 would be its nearest)."""


def heal_depth_png(d: np.ndarray) -> bytes:
    """``(H, W)`` depths in metres along the optical axis (+inf or 0 = no hit; :func:`~mmusv.export.common.depth_metres`
    of a depth image message) as HEAL reads ``<ts>_depth{i}.png``: an 8-bit grayscale PNG (PIL mode ``L``) whose pixel
    value is the depth in metres, rounded to the nearest metre; no hit and anything from 254.5 m on are
    :data:`HEAL_DEPTH_FAR`. ``ToTensor()(img) * 255`` gives back the pixel values as metres."""
    hit = np.isfinite(d) & (d > 0)
    # 254.5 m itself is far too: np.rint rounds that half to the even 254.
    near = hit & (d < HEAL_DEPTH_FAR - 0.5)
    metres = np.clip(np.rint(np.where(near, d, 0.0)), 0, HEAL_DEPTH_FAR - 1)
    return encode_png(np.where(near, metres, HEAL_DEPTH_FAR).astype(np.uint8), compress_level=1)


def _fov(lidar: dict[str, Any]) -> list[Any]:
    """``[lower, upper]`` degrees of a recorded LiDAR rig's rings: its ``elevations_deg`` (which replace the
    uniform ``vertical_fov_deg`` pattern, :class:`~mmusv.sensors.config.LidarConfig`) when given, else its
    ``vertical_fov_deg``; ``[None, None]`` without either."""
    rings = lidar.get("elevations_deg")
    if rings:
        return [min(rings), max(rings)]
    return list(lidar.get("vertical_fov_deg") or [None, None])


def _lidar_protocol(lidar: dict[str, Any]) -> dict[str, Any]:
    """OpenCDA's ``lidar`` entry of ``data_protocol.yaml`` (CARLA's LiDAR attributes) for a recorded rig's LiDAR
    (``{}``: every value ``None``)."""
    lower, upper = _fov(lidar)  # degrees
    return {
        "channels": lidar.get("channels"),
        "range": lidar.get("range_m"),
        "points_per_second": lidar.get("points_per_second"),
        "rotation_frequency": lidar.get("rotation_hz"),
        "upper_fov": upper,
        "lower_fov": lower,
        "noise_stddev": lidar.get("range_noise_std_m"),
        "dropoff_general_rate": lidar.get("dropout"),
    }


def _lidar_summary(p: dict[str, Any]) -> str:
    """One :func:`_lidar_protocol` entry in a few words, for a note (``?`` for a value the rig lacks)."""
    g = {k: "?" if v is None else f"{v:g}" for k, v in p.items()}
    return (
        f"{g['channels']} channels over {g['lower_fov']}..{g['upper_fov']} degrees, "
        f"{g['points_per_second']} points/s at {g['rotation_frequency']} Hz, {g['range']} m"
    )


def timestamp(frame: int) -> str:
    """The OPV2V timestamp of acquisition index ``frame`` (6 digits, zero-padded)."""
    return f"{frame:06d}"


def _matrix_list(m: np.ndarray) -> list[list[float]]:
    return [rounded(row, 9) for row in np.asarray(m)]


class Opv2vWriter(DatasetWriter):
    """Writes one recording as one OPV2V scenario folder (see the module docstring)."""

    format_version: ClassVar[int] = 2
    """2 (2026-12-02): ``<ts>_depth{i}.png`` is HEAL's 8-bit metres, the centimetres ``<ts>_depth_cm{i}.png``."""
    cameras: ClassVar[dict[str, int]] = {k: v for k, v in OPV2V_CAMERAS.items() if k != "back"}
    needs_agent: ClassVar[bool] = True

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        speeds = {str(v["id"]): float(v.get("speed_mps", 0.0)) * 3.6 for v in self.info.scenario.get("vessels", [])}
        self.static_ids = {vid for vid, kmh in speeds.items() if kmh == 0.0}  # VesselConfig.static: speed 0
        self.plans: dict[str, list[list[float]]] = {}
        self.empty_scans: dict[str, list[int]] = {}
        """Per agent, the frames whose LiDAR scan has no point (their ``.pcd`` has ``POINTS 0``)."""
        for v in self.info.scenario.get("vessels", []):
            route = np.asarray(v.get("route", []), dtype=np.float64).reshape(-1, 2)
            self.plans[str(v["id"])] = [rounded([x, -y, speeds[str(v["id"])]]) for x, y in route]
        for a in self.agents:
            names = [n for n, _ in self.agent_cameras(a)]
            if len(names) < 4:
                self.notes.append(
                    f"agent {a.id}: cameras {names} cover {len(names)} of the 4 OPV2V cameras "
                    "(front, right, left, rear)"
                )
            other = sorted(set(a.cameras) - set(self.cameras))
            if other:
                self.notes.append(f"agent {a.id}: cameras {other} have no OPV2V slot and are left out")
        lidars = self.lidars()
        if len({tuple(v.items()) for v in lidars.values()}) > 1:
            # OPV2V's data_protocol.yaml has one vehicle_base for every CAV: it gave the first agent's LiDAR as
            # every agent's, without a word, where a rig of another agent fired another pattern.
            ids = {cav_id(a.index): a.id for a in self.agents}
            first = next(iter(lidars))
            each = "; ".join(f"{ids[c]}: {_lidar_summary(v)}" for c, v in lidars.items())
            self.notes.append(
                f"the agents' LiDARs differ ({each}): "
                f"data_protocol.yaml's vehicle_base, one LiDAR for every CAV, describes {ids[first]}'s (cav {first}); "
                "mmusv.lidars there gives each agent's"
            )

    @classmethod
    def start(cls, out: Path, options: Any, sink: Any) -> HypesStats:
        """The vessel sizes and distances of the whole export, for the OpenCOOD hypes files."""
        return HypesStats(range_m=float(options.eval_range_m))

    @classmethod
    def finish_all(cls, shared: Any, out: Path, sink: Any) -> None:
        """Writes ``opencood/point_pillar_{early,late,intermediate}_fusion.yaml`` (:mod:`mmusv.export.opencood`)."""
        st: HypesStats = shared
        if not st.usv_positions:
            return
        # OpenCOOD lists the folders root_dir and validate_dir name (validate_dir: its validation, and the set its
        # inference scores): a split without a recording in validate (or train) names another split's folder, as
        # YOLO's val does, rather than one that is not there
        held = [d for d in ("train", "validate", "test") if (out / d).is_dir()]
        root = next((d for d in ("train", "validate", "test") if d in held), ".")
        val = next((d for d in ("validate", "test", "train") if d in held), ".")
        stand_in = "".join(
            f"# {key} is {given}: no recording went to {wanted} (a split takes whole recordings).\n"
            for key, given, wanted in (("root_dir", root, "train"), ("validate_dir", val, "validate"))
            if held and given != wanted
        )
        consts = constants(st)
        header = (
            "# OpenCOOD hypes written by mmusv convert --to opv2v (docs/opencood.md). root_dir and validate_dir are\n"
            "# relative to the export folder (run OpenCOOD from there, or make them absolute).\n"
            + stand_in
            + "# Also change in OpenCOOD's code:\n"
            + "".join(f"#   {k}: {v}\n" for k, v in consts.items())
        ).encode("utf-8")
        sink.mkdir(out / "opencood")
        for stem, doc in hypes(st, root_dir=root, validate_dir=val).items():
            sink.write(out / "opencood" / f"{stem}.yaml", header + dump_yaml(doc))

    def optional_topics(self) -> list[str]:
        """The extras' topics and every agent's annotations (``_additional.yaml``'s ``wave_occlusion``)."""
        return super().optional_topics() + [topics.agent_annotations(a.id) for a in self.agents]

    def agent_dir(self, view: AgentView) -> Path:
        return self.sink.mkdir(self.folder / str(cav_id(view.agent.index)))

    def write_agent(self, frame: Frame, world: WorldFrame, view: AgentView, targets: list[Target]) -> None:
        from mmusv.recording import decode_point_cloud

        a = view.agent
        assert view.lidar is not None
        d = self.agent_dir(view)
        ts = timestamp(frame.index)
        msgs = frame.messages
        cloud = decode_point_cloud(msgs[topics.lidar(a.id)])
        xyz = np.column_stack([cloud["x"], cloud["y"], cloud["z"]]).astype(np.float64)
        if not len(xyz):
            self.empty_scans.setdefault(a.id, []).append(frame.index)
        self.put(d / f"{ts}.pcd", pcd_bytes(mirror_points(xyz), cloud.get("intensity", np.zeros(len(xyz)))))
        lidar_pose = rounded(carla_pose(view.lidar))
        lidar_m = carla_matrix(np.array(lidar_pose))
        ego = rounded(carla_pose(view.body))
        doc: dict[str, Any] = {
            "lidar_pose": lidar_pose,
            "true_ego_pos": ego,
            "predicted_ego_pos": list(ego),
            "ego_speed": round(view.speed_mps * 3.6, 6),
            "plan_trajectory": self.plans.get(a.id, []),
            "vehicles": {cav_id(t.index): self._vehicle(t) for t in targets},
        }
        for name, idx in self.agent_cameras(a):
            cam = a.cameras[name]
            cords = rounded(carla_pose(view.cameras[name]))
            fx, fy, cx, cy = cam.intrinsics
            doc[f"camera{idx}"] = {
                "cords": cords,
                "intrinsic": _matrix_list(np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])),
                # Brown–Conrady [k1, k2, p1, p2, k3] (OpenCV's order); zeros for an ideal pinhole.
                "distortion": rounded(cam.distortion or (0.0, 0.0, 0.0, 0.0, 0.0), 9),
                "extrinsic": _matrix_list(invert(carla_matrix(np.array(cords))) @ lidar_m),
            }
            rgb = msgs.get(topics.camera(a.id, name, kind="rgb"))
            if rgb is not None:
                self.put(d / f"{ts}_camera{idx}.png", png_bytes(rgb))
            base = topics.camera(a.id, name) + "/"
            if "depth" in self.options.extras and base + "depth" in msgs:
                # HEAL's name and encoding (8-bit metres), and the centimetres beside it.
                metres = depth_metres(msgs[base + "depth"])
                self.put(d / f"{ts}_depth{idx}.png", heal_depth_png(metres), "depth")
                self.put(d / f"{ts}_depth_cm{idx}.png", depth_units_png(metres), "depth")
            for kind in ("semantic", "instance"):
                if kind in self.options.extras and base + kind in msgs:
                    self.put(d / f"{ts}_{kind}{idx}.png", png_bytes(msgs[base + kind]), kind)
        self.put(d / f"{ts}.yaml", dump_yaml(doc))
        if isinstance(self.shared, HypesStats):
            boxes = [[*t.box_in_lidar[:3, 3], *t.size, 0.0] for t in targets]
            self.shared.add(
                key=(str(self.folder), frame.index), lidar_world=view.lidar[:3, 3], boxes_lidar=np.array(boxes)
            )
        self.put(d / f"{ts}_additional.yaml", dump_yaml(self._additional(frame, world, view, targets, cloud)))
        if "radar" in self.options.extras and topics.radar_ppi(a.id) in msgs:
            self.put(d / f"{ts}_radar_ppi.png", png_bytes(msgs[topics.radar_ppi(a.id)]), "radar")
        if "top_view" in self.options.extras:
            for kind in ("rgb", "semantic"):
                m = msgs.get(topics.top_view(a.id, kind))
                if m is not None:
                    self.put(d / f"{ts}_topview_{kind}.png", png_bytes(m), "top_view")

    @staticmethod
    def _vehicle(t: Target) -> dict[str, Any]:
        loc = mirror_points(t.body[:3, 3])[0]
        centre = mirror_points(t.box[:3, 3])[0] - loc
        pose = carla_pose(t.body)
        return {
            "location": rounded(loc),
            "center": rounded(centre),
            "extent": rounded(np.asarray(t.size) / 2.0),
            "angle": rounded(pose[3:6]),
            "speed": round(t.speed_mps * 3.6, 6),
        }

    def _additional(
        self, frame: Frame, world: WorldFrame, view: AgentView, targets: list[Target], cloud: dict[str, np.ndarray]
    ) -> dict[str, Any]:
        counts: dict[int, int] = {}
        inst = cloud.get("instance")
        if inst is not None and inst.size:
            ids, n = np.unique(inst, return_counts=True)
            counts = {int(i): int(c) for i, c in zip(ids, n, strict=True)}
        # The share of each target the waves hide from this LiDAR, as recorded (its 3D box of the agent's annotations).
        ann = frame.messages.get(topics.agent_annotations(view.agent.id))
        shares = {str(b.target_id): wave_share(b) for b in getattr(ann, "boxes_lidar", ())}
        return {
            "mmusv": {
                "agent": view.agent.id,
                "frame": frame.index,
                "time_s": round(world.time_s, 9),
                "vehicles": {
                    cav_id(t.index): {
                        "name": t.id,
                        "asset": t.asset,
                        "role": t.role,
                        "static": self._static(t),
                        "semantic_class": t.semantic_class,
                        "class_name": class_name(t.semantic_class),
                        "instance_id": t.instance_id,
                        "lidar_points": counts.get(t.instance_id, 0),
                        "wave_occlusion": rounded_share(shares.get(t.id)),
                    }
                    for t in targets
                },
            }
        }

    def lidars(self) -> dict[int, dict[str, Any]]:
        """Each converted agent's LiDAR as OpenCDA's ``lidar`` entry (:func:`_lidar_protocol`), keyed by its
        ``cav_id``: ``data_protocol.yaml``'s ``mmusv.lidars``; its ``vehicle_base`` gives the first one's."""
        return {cav_id(a.index): _lidar_protocol(a.rig["lidar"]) for a in self.agents if a.rig.get("lidar")}

    def _static(self, t: Target) -> bool:
        """The vessel never travels (it rides the waves): a moored ship, or a scenario vessel at speed 0
        (``VesselConfig.static``)."""
        return t.role == "moored" or t.id in self.static_ids

    def finish(self, frames: list[int], skipped: list[dict[str, Any]]) -> None:
        super().finish(frames, skipped)
        for agent, empty in sorted(self.empty_scans.items()):
            shown = ", ".join(map(str, empty[:8])) + (f" and {len(empty) - 8} more" if len(empty) > 8 else "")
            self.notes.append(
                f"agent {agent}: the LiDAR has no point in frames {shown}: their .pcd files hold 0 points, which "
                "Open3D reads as an empty cloud after a warning ('PCD has no data')"
            )
        if not frames:
            return
        info, o = self.info, self.options
        lidars = self.lidars()
        acq = info.scenario.get("acquisition", {})
        # The OPV2V cameras (camera0..3) some agent writes, by index: none for a LiDAR-only rig.
        indices = {i: n for a in self.agents for n, i in self.agent_cameras(a)}
        written = [indices[i] for i in sorted(indices)]
        protocol: dict[str, Any] = {
            "description": f"mmusv scenario {info.scenario_name} converted to the OPV2V layout",
            "world": {
                "sync_mode": True,
                "fixed_delta_seconds": round(1.0 / float(acq.get("frequency_hz", 1.0)), 9),
                "seed": info.seed,
                "environment": info.scenario.get("environment", {}),
                "map": info.scenario.get("map", {}),
            },
            "vehicle_base": {
                "sensing": {
                    "perception": {
                        "lidar": dict(next(iter(lidars.values()), _lidar_protocol({}))),  # a copy: no YAML alias
                        "camera": {"num": len(written), "order": written},
                    }
                }
            },
            "mmusv": {
                "source": info.path.name,
                "scenario": info.scenario_name,
                "config_hash": info.config_hash,
                "mmusv_version": info.mmusv_version,
                "frame": "CARLA/UE world, left-handed: x forward, y right, z up; metres; degrees; "
                "poses [x, y, z, roll, yaw, pitch]; mmusv's right-handed frames (world x east, y north, z up; "
                "body x forward, y left, z up) with y mirrored",
                "cavs": {cav_id(a.index): a.id for a in self.agents},
                "lidars": lidars,
                "eval_range_m": o.eval_range_m,
                "gt_filter": "vehicles: every vessel whose box centre has hypot(x, y) <= eval_range_m "
                "in the agent's LiDAR frame; the agent itself never, other USVs only if include_usvs",
                "include_usvs": o.include_usvs,
                "extras": list(o.extras),
                "depth_png": {
                    "file": "<ts>_depth{i}.png",
                    "dtype": "uint8",
                    "unit_m": 1.0,
                    "no_hit": HEAL_DEPTH_FAR,
                    "saturated": HEAL_DEPTH_FAR,
                    "along": "optical axis",
                    "read_as": "HEAL: torchvision ToTensor()(img) * 255 = metres",
                },
                "depth_cm_png": {
                    "file": "<ts>_depth_cm{i}.png",
                    "dtype": "uint16",
                    "unit_m": DEPTH_UNIT_M,
                    "no_hit": 0,
                    "saturated": 65535,
                    "along": "optical axis",
                },
                **(
                    top_view_protocol(self.agents, frame="carla", files="<ts>_topview_{rgb,semantic}.png")
                    if "top_view" in o.extras
                    else {}
                ),
                "frames_converted": len(frames),
                "frames_skipped": skipped,
            },
        }
        self.put(self.folder / "data_protocol.yaml", dump_yaml(protocol))
