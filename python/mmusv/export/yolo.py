"""``--to yolo``: the Ultralytics detection layout.

``images/<split>/<scenario>/<agent>/<camera>/<frame>.png`` (the recorded RGB PNG, copied),
``labels/<split>/<same path>.txt`` (one line per kept 2D box: ``class x_centre y_centre width height``, the box
normalised by the image width and height, 6 decimals; an empty file for an image without boxes) and ``data.yaml``
(``train``/``val``/``test``: the image folders of the splits that hold images, relative to the file's folder,
which Ultralytics takes as the dataset root when ``path`` is absent; ``names``: class index → name;
``mmusv_box`` and ``mmusv_box_definition``: the option ``box`` the boxes were written with and what it means, keys
Ultralytics does not read). Splits are made by recording (:mod:`mmusv.export.splits`); without a split,
``images/all`` is both ``train`` and ``val``, and ``val`` is the ``train`` folder when no recording went to
``validate`` (Ultralytics requires both keys).

The box (option ``box``, :meth:`mmusv.export.camera.CameraWriter.boxes_of`, the COCO export's boxes and filters):
``visible`` (the default) the tight box of the vessel's pixels in the camera's instance image, so only cameras that
record ``rgb`` and ``instance`` images are converted (:class:`YoloVisibleWriter`); ``projected`` the recording's
box (the vessel's projected 3D box clipped to the image, reaching down to the keel), from ``rgb`` cameras alone
(with ``min_contrast``, which measures each vessel on its pixels, ``rgb`` and ``instance``:
:class:`YoloContrastWriter`).

Ultralytics finds an image's label file by replacing the *last* ``images`` folder of the image's path with
``labels``, so a scenario, agent or camera named ``images`` would send it to a label file that does not exist
(its boxes silently read as none): :func:`yolo_key` writes such a folder, and any ``images_``, ``images__``, …,
with one more ``_`` (``images`` → ``images_``), which keeps distinct names distinct.

Class index = the position of the vessel's semantic class in :data:`mmusv.export.camera.CATEGORIES` (every mmusv
class but ``none``, by id), so ``names`` lists the classes in id order.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from mmusv.export.camera import (
    CATEGORIES,
    ContrastBoxes,
    ProjectedBoxes,
    Sample,
    Shared,
    VisibleBoxes,
    box_writer,
    category_names,
)
from mmusv.export.common import BOX_DEFINITIONS, Options, Sink, dump_yaml, png_bytes
from mmusv.export.splits import SPLIT_NAMES

__all__ = ["YoloContrastWriter", "YoloVisibleWriter", "YoloWriter", "yolo_class", "yolo_key"]

_YOLO_SPLIT = {"train": "train", "validate": "val", "test": "test"}
_IMAGES_FOLDER = re.compile(r"images_*")


def yolo_class(semantic_class: int) -> int:
    """The YOLO class index of an mmusv semantic class (its position in ``CATEGORIES``)."""
    return CATEGORIES.index(int(semantic_class))


def yolo_key(key: str) -> str:
    """A sample key (``<scenario>/<agent>/<camera>/<frame>``) as a path under ``images/<split>/`` and
    ``labels/<split>/``: a folder named ``images``, ``images_``, … gets one more ``_`` (see the module docstring)."""
    return "/".join(p + "_" if _IMAGES_FOLDER.fullmatch(p) else p for p in key.split("/"))


class _YoloShared(Shared):
    def __init__(self, out: Path, box: str) -> None:
        super().__init__(out=out)
        self.box = box
        self.splits: set[str] = set()


class YoloWriter(ProjectedBoxes):
    """Writes the Ultralytics layout (see the module docstring); this class with ``box="projected"``, which needs
    only RGB images, :class:`YoloVisibleWriter` with ``box="visible"``."""

    @classmethod
    def for_options(cls, options: Options) -> type[YoloWriter]:
        return box_writer(options, projected=YoloWriter, visible=YoloVisibleWriter, contrast=YoloContrastWriter)

    @classmethod
    def format_name(cls) -> str:
        return "yolo"

    @classmethod
    def start(cls, out: Path, options: Options, sink: Sink) -> Any:
        return _YoloShared(out, options.box)

    def write_sample(self, sample: Sample) -> None:
        self.shared.splits.add(sample.split)
        cam = sample.camera
        key = yolo_key(sample.key)
        self.put(self.file("images", sample.split, f"{key}.png"), png_bytes(sample.message("rgb")))
        lines = []
        for b in self.boxes_of(sample):
            cx, cy = (b.x_min + b.x_max) / 2.0 / cam.width, (b.y_min + b.y_max) / 2.0 / cam.height
            w, h = b.width / cam.width, b.height / cam.height
            lines.append(f"{yolo_class(b.semantic_class)} {cx:.6f} {cy:.6f} {w:.6f} {h:.6f}\n")
        self.put(self.file("labels", sample.split, f"{key}.txt"), "".join(lines).encode())

    @classmethod
    def finish_all(cls, shared: Any, out: Path, sink: Sink) -> None:
        st: _YoloShared = shared
        if not st.splits:
            return
        doc: dict[str, Any] = {}
        for split in [*SPLIT_NAMES, "all"]:
            if split in st.splits:
                doc[_YOLO_SPLIT.get(split, "train")] = f"images/{split}"
        doc.setdefault("train", doc.get("val", doc.get("test")))
        doc.setdefault("val", doc["train"])  # Ultralytics requires both keys
        names = category_names()
        doc["names"] = {i: names[c] for i, c in enumerate(CATEGORIES)}
        doc["mmusv_box"] = st.box
        doc["mmusv_box_definition"] = BOX_DEFINITIONS[st.box]
        sink.write(out / "data.yaml", dump_yaml(doc))


class YoloVisibleWriter(VisibleBoxes, YoloWriter):
    """:class:`YoloWriter` with ``box="visible"``: the boxes come from the instance images, so a camera must record
    them too."""


class YoloContrastWriter(ContrastBoxes, YoloWriter):
    """:class:`YoloWriter` with ``box="projected"`` and ``min_contrast``: the contrast is measured on the vessel's
    pixels in the instance images, so a camera must record them too."""
