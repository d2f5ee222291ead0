"""Writing MCAP recordings (reading them back: :mod:`mmusv.recording.info`, :mod:`mmusv.recording.stream`,
:mod:`mmusv.recording.messages`, :mod:`mmusv.recording.contents`).

:class:`Recording` streams every USV's sensors and the world state of each frame into ONE MCAP file that opens
in Foxglove and whose channels all decode with the ``mcap`` + ``mcap-protobuf-support`` readers. It wraps the
compiled ``mmusv._core.Recorder``: arrays are coerced to the dtype and layout the core takes, then encoded and
written with the GIL released.

File-level conventions (see ``docs/recording.md``):

- the file is written as ``<path>.partial`` and renamed to ``path`` by :meth:`Recording.finish` (or a clean
  exit from ``with``); after an exception inside ``with`` the file is still completed (a valid MCAP holding
  everything written) but keeps the ``.partial`` name, so an interrupted run never looks complete;
- log time = publish time = simulation time in integer nanoseconds (:func:`to_ns`); no wall clock anywhere, so
  the same calls give byte-identical files;
- Foxglove well-known schemas (protobuf) for sensors, transforms and boxes; the project's own
  ``mmusv.WorldState`` and ``mmusv.AgentAnnotations`` (protobuf, descriptor set embedded) for ground truth.

Frames: world x east, y north, z up, metres; sensor frames x forward, y left, z up; quaternions ``x, y, z, w``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from mmusv import arguments
from mmusv._native import core
from mmusv.errors import InputError

__all__ = ["POINT_DTYPES", "ImageFormat", "Recording", "to_ns"]

ImageFormat = Literal["png", "raw"]
"""How :meth:`Recording.images` stores an image: ``foxglove.CompressedImage`` PNG or ``foxglove.RawImage``."""

POINT_DTYPES: tuple[str, ...] = ("uint8", "int8", "uint16", "int16", "uint32", "int32", "float32", "float64")
"""dtypes a point-cloud column may have (others are refused; bool is stored as uint8)."""


def to_ns(time_s: float) -> int:
    """Simulation time in seconds (a real number, ``0 <= time_s < 2**64 ns``, about 584 years) → integer
    nanoseconds (rounded), the time unit of every record call (an MCAP log time is an unsigned 64-bit count)."""
    if not arguments.is_number(time_s):
        raise InputError(f"invalid time_s: {time_s!r:.60} must be a number of seconds, not {type(time_s).__name__}")
    if not np.isfinite(time_s) or time_s < 0:
        raise InputError(f"invalid time_s: {time_s} must be finite and >= 0")
    ns = round(float(time_s) * 1e9)
    if ns >= 2**64:
        raise InputError(f"invalid time_s: {time_s} s is past the largest MCAP log time (2**64 ns, about 584 years)")
    return ns


def _f64(a: npt.ArrayLike, name: str, cols: int) -> npt.NDArray[np.float64]:
    """(N, cols) C-contiguous float64; a 1-D array is taken as one column when ``cols == 1``."""
    arr = np.asarray(a, dtype=np.float64)
    if arr.size == 0:
        return np.zeros((0, cols))
    if cols == 1 and arr.ndim == 1:
        arr = arr.reshape(-1, 1)
    if arr.ndim != 2 or arr.shape[1] != cols:
        raise InputError(f"invalid {name}: must have shape (N, {cols}), got {arr.shape}")
    return np.ascontiguousarray(arr)


def _u32(a: npt.ArrayLike, name: str) -> npt.NDArray[np.uint32]:
    """(N,) C-contiguous uint32 from non-negative integers."""
    arr = np.asarray(a)
    if arr.size == 0:
        return np.zeros(0, dtype=np.uint32)
    if arr.ndim != 1 or not np.issubdtype(arr.dtype, np.integer):
        raise InputError(f"invalid {name}: must be a 1-D array of integers, got {arr.shape} {arr.dtype}")
    if arr.min() < 0 or arr.max() > np.iinfo(np.uint32).max:
        raise InputError(f"invalid {name}: values must be in 0..2^32-1")
    return np.ascontiguousarray(arr, dtype=np.uint32)


def _block(table: Mapping[str, Any], group: str, n: int, floats: Sequence[tuple[str, int]]) -> npt.NDArray[np.float64]:
    """The float columns ``floats`` (key, width) of a dict table with ``n`` rows, side by side: (n, Σ width)."""
    parts = []
    for key, width in floats:
        if key not in table and n:
            raise InputError(f"invalid {group}: missing column {key!r}")
        part = _f64(table.get(key, []), f"{group}.{key}", width)
        if len(part) != n:
            raise InputError(f"invalid {group}.{key}: {len(part)} rows for {n} target ids")
        parts.append(part)
    return np.ascontiguousarray(np.hstack(parts))


def _int_block(table: Mapping[str, Any], group: str, n: int, keys: Sequence[str]) -> npt.NDArray[np.uint32]:
    """The integer columns ``keys`` of a dict table with ``n`` rows, side by side: (n, len(keys)) uint32."""
    parts = []
    for key in keys:
        if key not in table and n:
            raise InputError(f"invalid {group}: missing column {key!r}")
        part = _u32(table.get(key, []), f"{group}.{key}")
        if len(part) != n:
            raise InputError(f"invalid {group}.{key}: {len(part)} rows for {n} target ids")
        parts.append(part)
    return np.ascontiguousarray(np.stack(parts, axis=1))


def _column(name: str, values: npt.ArrayLike) -> npt.NDArray[Any]:
    arr = np.asarray(values)
    if arr.dtype == np.bool_:
        arr = arr.astype(np.uint8)
    if arr.ndim != 1:
        raise InputError(f"invalid columns[{name!r}]: must be 1-D (one value per point), got shape {arr.shape}")
    if arr.dtype.name not in POINT_DTYPES:
        raise InputError(f"invalid columns[{name!r}]: dtype {arr.dtype} is not one of {POINT_DTYPES}")
    return np.ascontiguousarray(arr.astype(arr.dtype.newbyteorder("<"), copy=False))


def _image(image: npt.ArrayLike, name: str = "image") -> npt.NDArray[Any]:
    arr = np.asarray(image)
    ok = (arr.ndim == 2 and arr.dtype in (np.uint8, np.uint16, np.float32)) or (
        arr.ndim == 3 and arr.shape[2] == 3 and arr.dtype == np.uint8
    )
    if not ok:
        raise InputError(
            f"invalid {name}: must be (H, W) uint8/uint16/float32 or (H, W, 3) uint8, got {arr.shape} {arr.dtype}"
        )
    return np.ascontiguousarray(arr)


def _strs(values: Sequence[str], name: str) -> list[str]:
    if isinstance(values, str):
        raise InputError(f"invalid {name}: give a sequence of strings, not one string")
    return [str(v) for v in values]


class Recording:
    """One MCAP recording; use as a context manager.

    >>> with Recording("run.mcap") as rec:  # doctest: +SKIP
    ...     rec.world_state("/world/state", log_time_ns=to_ns(t), frame=k, time_s=t, ...)

    Every method takes ``topic`` and ``log_time_ns`` (simulation time, integer nanoseconds); a topic is created
    on first use and keeps one schema.
    """

    def __init__(self, path: str | os.PathLike[str], *, overwrite: bool = False) -> None:
        """Starts writing ``<path>.partial``. An existing ``path`` raises :class:`mmusv.IoError` unless
        ``overwrite`` (the old file is replaced only when :meth:`finish` succeeds), and so does a ``path`` another
        recording is still writing, in this process or another (its ``.partial`` is locked until it is finished,
        abandoned or dropped)."""
        self._rec = core.Recorder(os.fspath(path), overwrite=overwrite)

    @property
    def path(self) -> Path:
        """The final file name."""
        return Path(self._rec.path)

    @property
    def partial_path(self) -> Path:
        """``<path>.partial``, written to until :meth:`finish`."""
        return Path(self._rec.partial_path)

    @property
    def closed(self) -> bool:
        """True once :meth:`finish` or :meth:`abandon` ran."""
        return self._rec.closed

    def point_cloud(
        self,
        topic: str,
        *,
        log_time_ns: int,
        frame_id: str,
        columns: Mapping[str, npt.ArrayLike],
        pose: Sequence[float] | npt.ArrayLike | None = None,
    ) -> None:
        """``foxglove.PointCloud``. ``columns`` maps a field name to a 1-D array, one value per point, of a dtype
        in :data:`POINT_DTYPES` (e.g. ``{"x": f32, "y": f32, "z": f32, "intensity": f32, "ring": u16}``; Foxglove
        needs at least two of x, y, z, in metres in ``frame_id``). Fields are packed back to back in the order
        given, little-endian. ``pose``: ``(x, y, z, qx, qy, qz, qw)`` of the cloud origin in ``frame_id`` or
        None (identity)."""
        names = [str(n) for n in columns]
        cols = [_column(n, v) for n, v in columns.items()]
        p = None if pose is None else [float(v) for v in np.asarray(pose, dtype=np.float64).reshape(-1)]
        if p is not None and len(p) != 7:
            raise InputError(f"invalid pose: give 7 numbers (x, y, z, qx, qy, qz, qw), got {len(p)}")
        self._rec.point_cloud(topic, log_time_ns=log_time_ns, frame_id=frame_id, names=names, columns=cols, pose=p)

    def raw_image(self, topic: str, *, log_time_ns: int, frame_id: str, image: npt.ArrayLike) -> None:
        """``foxglove.RawImage`` with the encoding given by the array: (H, W) uint8 → ``mono8``, (H, W, 3) uint8
        → ``rgb8``, (H, W) uint16 → ``16UC1``, (H, W) float32 → ``32FC1`` (e.g. depth in metres). Row 0 is the
        top of the image."""
        self._rec.raw_image(topic, log_time_ns=log_time_ns, frame_id=frame_id, image=_image(image))

    def png_image(self, topic: str, *, log_time_ns: int, frame_id: str, image: npt.ArrayLike) -> None:
        """``foxglove.CompressedImage`` (format ``png``, lossless, deterministic) of an (H, W) uint8, (H, W, 3)
        uint8 RGB or (H, W) uint16 image (e.g. semantic or instance ids)."""
        arr = _image(image)
        if arr.dtype == np.float32:
            raise InputError("invalid image: PNG holds uint8 or uint16; record float32 images with raw_image")
        self._rec.png_image(topic, log_time_ns=log_time_ns, frame_id=frame_id, image=arr)

    def images(
        self,
        *,
        log_time_ns: int,
        images: Sequence[tuple[str, str, npt.ArrayLike, ImageFormat]],
    ) -> tuple[float, float]:
        """Several images at ``log_time_ns``, each ``(topic, frame_id, image, format)`` with format ``"png"``
        (as :meth:`png_image`) or ``"raw"`` (as :meth:`raw_image`). They are encoded in parallel, on all cores
        and before the recording is locked, then written in the order given: the file gets the bytes of one
        call per image. Returns the wall seconds spent encoding and writing (for profiling)."""
        topics, frame_ids, arrays, formats = [], [], [], []
        for i, (topic, frame_id, image, fmt) in enumerate(images):
            arr = _image(image, f"images[{i}]")
            if fmt == "png" and arr.dtype == np.float32:
                raise InputError(f"invalid images[{i}]: PNG holds uint8 or uint16; store float32 images as 'raw'")
            if fmt not in ("png", "raw"):
                raise InputError(f"invalid images[{i}] format {fmt!r}: use 'png' or 'raw'")
            topics.append(topic)
            frame_ids.append(frame_id)
            arrays.append(arr)
            formats.append(fmt)
        encode_s, write_s = self._rec.images(
            log_time_ns=log_time_ns, topics=topics, frame_ids=frame_ids, images=arrays, formats=formats
        )
        return float(encode_s), float(write_s)

    def frame_transforms(
        self,
        topic: str,
        *,
        log_time_ns: int,
        transforms: Sequence[tuple[str, str, npt.ArrayLike, npt.ArrayLike]],
    ) -> None:
        """``foxglove.FrameTransforms``: each ``(parent, child, translation (3,) m, rotation (4,) x, y, z, w)`` is
        the pose of ``child`` in ``parent`` (e.g. ``("world", "usv0", ...)``)."""
        self._rec.frame_transforms(
            topic,
            log_time_ns=log_time_ns,
            parents=[str(t[0]) for t in transforms],
            children=[str(t[1]) for t in transforms],
            translations=_f64([np.asarray(t[2], dtype=np.float64).reshape(3) for t in transforms], "translations", 3),
            rotations=_f64([np.asarray(t[3], dtype=np.float64).reshape(4) for t in transforms], "rotations", 4),
        )

    def boxes(
        self,
        topic: str,
        *,
        log_time_ns: int,
        frame_id: str,
        entity_id: str,
        ids: Sequence[str],
        centers: npt.ArrayLike,
        quaternions: npt.ArrayLike,
        sizes: npt.ArrayLike,
        colors: npt.ArrayLike,
        labels: Sequence[str] | None = None,
    ) -> None:
        """``foxglove.SceneUpdate``: one frame-locked entity ``entity_id`` in ``frame_id`` holding one cube per
        box — ``centers`` (N, 3) m, ``quaternions`` (N, 4) x, y, z, w, ``sizes`` (N, 3) m along the box axes,
        ``colors`` (N, 4) RGBA 0..1 — and a text above each box with a non-empty label (default: its id).
        ``ids`` must be unique; they are kept in the entity metadata (id → label)."""
        ids_l = _strs(ids, "ids")
        self._rec.boxes(
            topic,
            log_time_ns=log_time_ns,
            frame_id=frame_id,
            entity_id=entity_id,
            ids=ids_l,
            centers=_f64(centers, "centers", 3),
            quaternions=_f64(quaternions, "quaternions", 4),
            sizes=_f64(sizes, "sizes", 3),
            colors=np.ascontiguousarray(_f64(colors, "colors", 4).astype(np.float32)),
            labels=ids_l if labels is None else _strs(labels, "labels"),
        )

    def camera_calibration(
        self,
        topic: str,
        *,
        log_time_ns: int,
        frame_id: str,
        width: int,
        height: int,
        intrinsics: Sequence[float],
        distortion: Sequence[float] | None = None,
    ) -> None:
        """``foxglove.CameraCalibration`` of a ``width`` x ``height`` pinhole camera in ``frame_id`` (its optical
        frame: x right, y down, z forward): ``intrinsics`` ``(fx, fy, cx, cy)`` pixels in OpenCV's convention
        (pixel centres at whole numbers: :func:`mmusv.sensors.camera.opencv_intrinsics` of mmusv's),
        ``distortion`` OpenCV's ``(k1, k2, p1, p2, k3)`` (``plumb_bob``; default none)."""
        fx, fy, cx, cy = (float(v) for v in intrinsics)
        d = (0.0,) * 5 if distortion is None else tuple(float(v) for v in distortion)
        if len(d) != 5:
            raise InputError(f"distortion must be (k1, k2, p1, p2, k3), got {len(d)} values")
        self._rec.camera_calibration(
            topic,
            log_time_ns=log_time_ns,
            frame_id=frame_id,
            width=width,
            height=height,
            intrinsics=(fx, fy, cx, cy),
            distortion=d,
        )

    def image_boxes(
        self,
        topic: str,
        *,
        log_time_ns: int,
        corners: npt.ArrayLike,
        colors: npt.ArrayLike,
        labels: Sequence[str],
    ) -> None:
        """``foxglove.ImageAnnotations`` of 2D boxes: ``corners`` (N, 4) ``[x0, y0, x1, y1]`` pixels (origin at the
        top-left corner of the top-left pixel, mmusv's and Foxglove's convention), ``colors`` (N, 4) RGBA 0..1,
        ``labels`` N strings (a non-empty one drawn at its box's top-left corner)."""
        self._rec.image_boxes(
            topic,
            log_time_ns=log_time_ns,
            corners=_f64(corners, "corners", 4),
            colors=np.ascontiguousarray(_f64(colors, "colors", 4).astype(np.float32)),
            labels=_strs(labels, "labels"),
        )

    def world_state(
        self,
        topic: str,
        *,
        log_time_ns: int,
        frame: int,
        time_s: float,
        ids: Sequence[str],
        assets: Sequence[str],
        roles: Sequence[str],
        classes: npt.ArrayLike,
        instance_ids: npt.ArrayLike,
        poses: npt.ArrayLike,
        velocities: npt.ArrayLike,
        box_centers: npt.ArrayLike,
        box_sizes: npt.ArrayLike,
    ) -> None:
        """``mmusv.WorldState``, one vessel per row: ``classes`` / ``instance_ids`` (N,) non-negative ints,
        ``poses`` (N, 6) x, y, z, roll, pitch, yaw (world frame, m, rad), ``velocities`` (N, 3) world m/s,
        ``box_centers`` (N, 3) world m, ``box_sizes`` (N, 3) length, beam, height m."""
        self._rec.world_state(
            topic,
            log_time_ns=log_time_ns,
            frame=int(frame),
            time_s=float(time_s),
            ids=_strs(ids, "ids"),
            assets=_strs(assets, "assets"),
            roles=_strs(roles, "roles"),
            classes=_u32(classes, "classes"),
            instance_ids=_u32(instance_ids, "instance_ids"),
            poses=_f64(poses, "poses", 6),
            velocities=_f64(velocities, "velocities", 3),
            box_centers=_f64(box_centers, "box_centers", 3),
            box_sizes=_f64(box_sizes, "box_sizes", 3),
        )

    def annotations(
        self,
        topic: str,
        *,
        log_time_ns: int,
        frame: int,
        time_s: float,
        agent_id: str,
        lidar: Mapping[str, Any] | None = None,
        bev: Mapping[str, Any] | None = None,
        camera: Mapping[str, Any] | None = None,
    ) -> None:
        """``mmusv.AgentAnnotations`` of one agent at one frame. Each of ``lidar``, ``bev``, ``camera`` is a dict
        of equal-length columns keyed by the protobuf field names (None or ``{}``: no boxes):

        - ``lidar`` (LiDAR frame): ``target_id`` [str], ``instance_id``, ``semantic_class``, ``lidar_points``
          [ints], ``center`` (N, 3) m, ``size`` (N, 3) length, width, height m, ``rotation`` (N, 4) x, y, z, w,
          ``yaw`` (N,) rad, ``range_m`` (N,) m, ``wave_occlusion`` (N,) share of the target's part above the still
          water level hidden by the waves, 0..1 (optional: 0 when absent);
        - ``bev``: ``target_id`` [str], ``x``, ``y``, ``length``, ``width`` (N,) m, ``yaw`` (N,) rad;
        - ``camera`` (pixels, origin top-left): ``target_id``, ``camera`` [str], ``x_min``, ``y_min``, ``x_max``,
          ``y_max``, ``truncation``, ``occlusion``, ``wave_occlusion`` (optional: 0 when absent) (N,) floats,
          ``visible_pixels``, ``box_pixels`` (N,) ints.
        """
        lid, bev_t, cam = dict(lidar or {}), dict(bev or {}), dict(camera or {})
        lidar_ids = _strs(lid.get("target_id", []), "lidar.target_id")
        bev_ids = _strs(bev_t.get("target_id", []), "bev.target_id")
        camera_ids = _strs(cam.get("target_id", []), "camera.target_id")
        n, m, k = len(lidar_ids), len(bev_ids), len(camera_ids)
        # The wave-occlusion shares are optional: absent, the boxes were not hidden by waves (a flat sea).
        lid.setdefault("wave_occlusion", np.zeros(n))
        cam.setdefault("wave_occlusion", np.zeros(k))
        lidar_spec = (("center", 3), ("size", 3), ("rotation", 4), ("yaw", 1), ("range_m", 1), ("wave_occlusion", 1))
        camera_keys = ("x_min", "y_min", "x_max", "y_max", "truncation", "occlusion", "wave_occlusion")
        camera_spec = [(key, 1) for key in camera_keys]
        self._rec.annotations(
            topic,
            log_time_ns=log_time_ns,
            frame=int(frame),
            time_s=float(time_s),
            agent_id=str(agent_id),
            lidar_ids=lidar_ids,
            lidar_ints=_int_block(lid, "lidar", n, ("instance_id", "semantic_class", "lidar_points")),
            lidar_values=_block(lid, "lidar", n, lidar_spec),
            bev_ids=bev_ids,
            bev_values=_block(bev_t, "bev", m, [(key, 1) for key in ("x", "y", "length", "width", "yaw")]),
            camera_ids=camera_ids,
            camera_names=_strs(cam.get("camera", []), "camera.camera"),
            camera_ints=_int_block(cam, "camera", k, ("visible_pixels", "box_pixels")),
            camera_values=_block(cam, "camera", k, camera_spec),
        )

    def metadata(self, name: str, mapping: Mapping[str, Any]) -> None:
        """An MCAP metadata record ``name`` (e.g. ``"scenario"``); values are stored as strings."""
        self._rec.metadata(name, {str(k): str(v) for k, v in mapping.items()})

    def attachment(
        self, name: str, data: bytes, *, media_type: str = "application/octet-stream", log_time_ns: int = 0
    ) -> None:
        """An MCAP attachment, e.g. the scenario YAML (``media_type="application/yaml"``)."""
        self._rec.attachment(name, media_type=media_type, data=bytes(data), log_time_ns=log_time_ns)

    def finish(self) -> dict[str, Any]:
        """Completes the file and renames it to :attr:`path`; returns ``{"path", "messages", "channels",
        "bytes"}``."""
        return self._rec.finish()

    def abandon(self) -> Path:
        """Completes the file but keeps the ``.partial`` name; returns that path. Once closed, a no-op that returns
        where the file is (its final name after :meth:`finish`)."""
        return Path(self._rec.abandon())

    def __enter__(self) -> Recording:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc_type is None:
            if not self._rec.closed:
                self._rec.finish()
        else:
            self._rec.abandon()

    def __repr__(self) -> str:
        return f"Recording({self._rec!r})"
