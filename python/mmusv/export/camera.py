"""What the image datasets (COCO, YOLO, MaSTr) share: one sample per agent camera per frame, its key, its 2D boxes
and the box filter.

A sample is one camera image of one agent at one frame; its key ``<scenario>/<agent>/<camera>/<frame:06d>`` names
its files in every layout, so no two samples of a conversion share a name. Boxes come from the recording's 2D camera
annotations (``mmusv.AgentAnnotations.boxes_camera``: the vessel's projected 3D box clipped to the image, with
truncation, visible pixels and occlusion; :mod:`mmusv.annotate`), with the vessel's class, instance and role from
the frame's world state. The box written is the option ``box`` (:data:`mmusv.export.common.BOXES`): ``visible``
(the default), the tight box of the instance image's pixels equal to the vessel's instance id (:func:`mask_box`),
or ``projected``, the recorded box; truncation, occlusion and visible pixels are the recording's either way. A box's
``contrast`` is measured on the recorded RGB image (:func:`mmusv.export.contrast.apparent_contrast`: the vessel's
Weber contrast, row by row, against the background beside its pixels), for the formats that write it (COCO) and for the
option ``min_contrast``.

Pixel coordinates (every box): origin at the top-left corner of the image, x right, y down, pixel ``(i, j)`` over
``[i, i + 1) × [j, j + 1)``, so the tight box of pixels ``x_min..x_max``, ``y_min..y_max`` (inclusive) is
``[x_min, y_min, x_max + 1, y_max + 1]``, as pycocotools' ``toBbox`` gives it for the same mask.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path
from typing import Any, ClassVar, TypeVar

import numpy as np

from mmusv.classes import SemanticClass, class_name
from mmusv.export.common import Options, Sink, mask_box, wave_share
from mmusv.export.contrast import apparent_contrast
from mmusv.export.writer import DatasetWriter
from mmusv.recording import topics
from mmusv.recording.decode import WorldFrame
from mmusv.recording.info import AgentInfo, CameraInfo
from mmusv.recording.stream import Frame

__all__ = [
    "CATEGORIES",
    "CameraWriter",
    "ContrastBoxes",
    "ImageBox",
    "ProjectedBoxes",
    "Sample",
    "Shared",
    "VisibleBoxes",
    "box_writer",
    "mask_box",
]

_W = TypeVar("_W", bound="CameraWriter")

CATEGORIES: tuple[int, ...] = tuple(int(c) for c in SemanticClass if c != SemanticClass.NONE)
"""The detection categories: every semantic class of :mod:`mmusv.classes` but ``NONE`` (0, nothing hit), by id."""


@dataclass(frozen=True)
class ImageBox:
    """One vessel's 2D box in one image: pixels ``x_min, y_min, x_max, y_max`` (origin at the top-left corner of
    the image, x right, y down), its vessel id, semantic class, instance id and role (``target``, ``usv``,
    ``moored``), truncation and occlusion (fractions, 0..1), visible pixels, where measured ``contrast`` (the
    vessel's Weber contrast in the RGB image, :func:`mmusv.export.contrast.apparent_contrast`; ``None`` when not
    measured or undefined) and ``wave_occlusion``, the recorded share (0..1) of the vessel's part above the still
    level that the waves hide from this camera (:mod:`mmusv.wave_occlusion`; 0 over a flat sea, ``None`` for a
    recording made before the field existed)."""

    target_id: str
    semantic_class: int
    instance_id: int
    role: str
    x_min: float
    y_min: float
    x_max: float
    y_max: float
    truncation: float
    occlusion: float
    visible_pixels: int
    contrast: float | None = None
    wave_occlusion: float | None = None

    @property
    def width(self) -> float:
        return self.x_max - self.x_min

    @property
    def height(self) -> float:
        return self.y_max - self.y_min


@dataclass(frozen=True)
class Sample:
    """One camera image of one agent at one frame: ``key`` (``<scenario>/<agent>/<camera>/<frame:06d>``), the
    split it belongs to (``all`` without a split) and the frame's decoded messages."""

    key: str
    split: str
    agent: AgentInfo
    camera: CameraInfo
    frame: Frame
    world: WorldFrame

    def message(self, kind: str) -> Any:
        """The camera's ``kind`` image message (``rgb``, ``depth``, ``semantic``, ``instance``)."""
        return self.frame.messages[topics.camera(self.agent.id, self.camera.name, kind=kind)]

    @cached_property
    def instance(self) -> np.ndarray:
        """The camera's instance image, ``(H, W)`` (decoded once)."""
        from mmusv.recording import decode_image

        return np.asarray(decode_image(self.message("instance")))

    @cached_property
    def rgb(self) -> np.ndarray:
        """The camera's RGB image as recorded, ``(H, W, 3)`` uint8 sRGB (decoded once)."""
        from mmusv.recording import decode_image

        return np.asarray(decode_image(self.message("rgb")))


@dataclass
class Shared:
    """State of one conversion shared by its recordings: the output root."""

    out: Path


class CameraWriter(DatasetWriter):
    """Base of the image datasets: :meth:`write_sample` per camera image (see the module docstring).

    Subclasses set :attr:`kinds` (the image kinds a camera must record to be used) and :attr:`boxes` (whether
    the samples need the agent's annotations).
    """

    owns_folder: ClassVar[bool] = False
    needs_agent: ClassVar[bool] = True
    kinds: ClassVar[tuple[str, ...]] = ("rgb",)
    boxes: ClassVar[bool] = False
    contrast: ClassVar[bool] = False
    """Whether the format writes each box's ``contrast`` (then measured for every box; otherwise only for the option
    ``min_contrast``, which needs the camera's instance images: see :attr:`kinds`)."""
    left_out_why: ClassVar[str] = ""
    """Said after the cameras left out for lacking one of :attr:`kinds` (what would keep them)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.extra_counts = {}
        self.visible_boxes = 0
        """2D boxes with a visible pixel in the converted images (before ``min_box_px`` and ``max_occlusion``)."""
        self.kept_boxes = 0
        """Of those, the boxes :meth:`boxes_of` kept."""
        self.faint_boxes = 0
        """Of the visible boxes, those whose contrast is under ``min_contrast`` (left out, whatever the other
        filters say)."""
        self.cams: dict[str, list[str]] = {}
        for a in self.agents:
            self.cams[a.id] = [n for n, c in sorted(a.cameras.items()) if self.camera_ok(c)]
            other = [n for n in sorted(a.cameras) if n not in self.cams[a.id]]
            if other:
                self.notes.append(
                    f"agent {a.id}: cameras {other} do not record {' and '.join(self.kinds)} images and are left out"
                    + self.left_out_why
                )

    @classmethod
    def camera_ok(cls, cam: CameraInfo) -> bool:
        """The camera records every image kind of :attr:`kinds`."""
        return all(k in cam.outputs for k in cls.kinds)

    @classmethod
    def uses_agent(cls, agent: AgentInfo) -> str | None:
        if any(cls.camera_ok(c) for c in agent.cameras.values()):
            return None
        return f"has no camera recording {' and '.join(cls.kinds)} images"

    @classmethod
    def start(cls, out: Path, options: Options, sink: Sink) -> Any:
        return Shared(out=out)

    @property
    def root(self) -> Path:
        """The conversion's output folder."""
        out: Path = self.shared.out
        return out

    @property
    def split_name(self) -> str:
        """The recording's split, ``all`` without a split."""
        return self.split or "all"

    def required_topics(self) -> list[str]:
        out = [topics.WORLD_STATE]
        for a in self.agents:
            out += [topics.camera(a.id, n, kind=k) for n in self.cams[a.id] for k in self.kinds]
            if self.boxes:
                out.append(topics.agent_annotations(a.id))
        return out

    def optional_topics(self) -> list[str]:
        return []

    def write_frame(self, frame: Frame) -> None:
        world = frame.world
        assert world is not None
        for a in self.agents:
            for name in self.cams[a.id]:
                key = f"{self.folder.name}/{a.id}/{name}/{frame.index:06d}"
                self.write_sample(Sample(key, self.split_name, a, a.cameras[name], frame, world))

    def write_sample(self, sample: Sample) -> None:
        raise NotImplementedError

    def file(self, *parts: str) -> Path:
        """``root/parts...``, its folder created."""
        p = self.root.joinpath(*parts)
        self.sink.mkdir(p.parent)
        return p

    def boxes_of(self, sample: Sample) -> list[ImageBox]:
        """The sample's 2D boxes kept by the options, each the box of option ``box``: ``visible``, the tight box of the
        vessel's pixels in the instance image (:func:`mask_box`), or ``projected``, the recorded box. A box with no
        visible pixel is always left out, and so are boxes whose shorter side (of the box written) is under
        ``min_box_px``, whose occlusion is above ``max_occlusion`` or, with ``min_contrast`` set, whose contrast in the
        RGB image is under it (a box whose contrast is undefined, :func:`~mmusv.export.contrast.apparent_contrast`
        ``None``, is kept). ``contrast`` is measured when the format writes it (:attr:`contrast`) or
        ``min_contrast`` is set, else left ``None``."""
        ann = sample.frame.messages[topics.agent_annotations(sample.agent.id)]
        w = sample.world
        row = {vid: i for i, vid in enumerate(w.ids)}
        visible = self.options.box == "visible"
        min_contrast = self.options.min_contrast
        measure = self.contrast or min_contrast is not None
        vessel_ids = [int(i) for i in w.instance_ids]
        out = []
        for b in ann.boxes_camera:
            if b.camera != sample.camera.name or b.target_id not in row:
                continue
            i = row[b.target_id]
            box = ImageBox(
                target_id=b.target_id,
                semantic_class=int(w.classes[i]),
                instance_id=int(w.instance_ids[i]),
                role=w.roles[i],
                x_min=float(b.x_min),
                y_min=float(b.y_min),
                x_max=float(b.x_max),
                y_max=float(b.y_max),
                truncation=float(b.truncation),
                occlusion=float(b.occlusion),
                visible_pixels=int(b.visible_pixels),
                wave_occlusion=wave_share(b),
            )
            if box.visible_pixels == 0:
                continue
            tight = None  # the tight box of the vessel's pixels, where worked out (``visible``)
            if visible:
                tight = mask_box(sample.instance, box.instance_id)
                if tight is None:  # no pixel of the vessel in the image
                    continue
                x0, y0, x1, y1 = (float(v) for v in tight)
                box = replace(box, x_min=x0, y_min=y0, x_max=x1, y_max=y1)
            if measure:
                c = apparent_contrast(
                    rgb=sample.rgb,
                    instance=sample.instance,
                    instance_id=box.instance_id,
                    other_ids=vessel_ids,
                    box=tight,
                )
                box = replace(box, contrast=c)
            self.visible_boxes += 1
            faint = min_contrast is not None and box.contrast is not None and box.contrast < min_contrast
            self.faint_boxes += faint
            if (
                faint
                or box.occlusion > self.options.max_occlusion
                or min(box.width, box.height) < self.options.min_box_px
            ):
                continue
            out.append(box)
        self.kept_boxes += len(out)
        return out

    def finish(self, frames: list[int], skipped: list[dict[str, Any]]) -> None:
        """Says so when a format with boxes kept none of this recording's (no vessel in view, or every box left
        out by the filters), as its label files are then all empty; with ``min_contrast``, how many boxes it left
        out."""
        super().finish(frames, skipped)
        o = self.options
        if self.boxes and frames and o.min_contrast is not None:
            self.notes.append(
                f"min_contrast = {o.min_contrast:g}: {self.faint_boxes} of {self.visible_boxes} visible 2D boxes have "
                "a lower contrast in the RGB image and are left out"
            )
        if not (self.boxes and frames) or self.kept_boxes:
            return
        if self.visible_boxes == 0:
            self.notes.append("no vessel is visible in any converted image: no 2D box, every image is background")
        else:
            filters = f"min_box_px = {o.min_box_px:g}"
            if o.min_contrast is None:
                filters += f" and max_occlusion = {o.max_occlusion:g}"
            else:
                filters += f", max_occlusion = {o.max_occlusion:g} and min_contrast = {o.min_contrast:g}"
            self.notes.append(
                f"all {self.visible_boxes} visible 2D boxes were left out by {filters}: no 2D box, every image is "
                "background"
            )


class ProjectedBoxes(CameraWriter):
    """Base of a box format's writer whose ``box="projected"`` boxes (the recorded ones) need only the RGB images
    (YOLO, MOT): the writer for that option itself; its ``box="visible"`` and ``min_contrast`` variants put
    :class:`VisibleBoxes` or :class:`ContrastBoxes` first among their bases (:func:`box_writer` picks one)."""

    kinds: ClassVar[tuple[str, ...]] = ("rgb",)
    boxes: ClassVar[bool] = True
    no_agent_reason: ClassVar[str] = "no camera recording rgb images"


class VisibleBoxes(CameraWriter):
    """Base to put first among the bases of a box format's writer for ``box="visible"`` (YOLO, MOT): the boxes come
    from the instance images, so a camera must record them too (COCO always needs them for its masks)."""

    kinds: ClassVar[tuple[str, ...]] = ("rgb", "instance")
    no_agent_reason: ClassVar[str] = (
        "no camera recording rgb and instance images (--box visible, the default, takes each box from the instance "
        "image; --box projected writes the recorded boxes from rgb images alone)"
    )
    left_out_why: ClassVar[str] = " (--box visible takes the boxes from the instance images; --box projected does not)"


class ContrastBoxes(CameraWriter):
    """Base to put first among the bases of a box format's writer for ``box="projected"`` with ``min_contrast``: the
    contrast is measured on the vessel's pixels in the instance images, so a camera must record them too."""

    kinds: ClassVar[tuple[str, ...]] = ("rgb", "instance")
    no_agent_reason: ClassVar[str] = (
        "no camera recording rgb and instance images (--min-contrast measures each vessel on its pixels in the "
        "instance image)"
    )
    left_out_why: ClassVar[str] = " (--min-contrast measures each vessel on its pixels in the instance images)"


def box_writer(options: Options, *, projected: type[_W], visible: type[_W], contrast: type[_W]) -> type[_W]:
    """The writer of a box format that needs only RGB images for ``box="projected"``: ``visible`` for
    ``box="visible"``, ``contrast`` for ``box="projected"`` with ``min_contrast``, else ``projected``."""
    if options.box == "visible":
        return visible
    return projected if options.min_contrast is None else contrast


def category_names() -> dict[int, str]:
    """:data:`CATEGORIES` by id → class name."""
    return {c: class_name(c) for c in CATEGORIES}
