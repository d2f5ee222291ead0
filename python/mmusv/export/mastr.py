"""``--to mastr``: obstacle / water / sky masks in the MaSTr1325 label convention, beside the RGB images.

Per split (``train``, ``validate``, ``test``, by recording; no split folder without a split):
``<split>/images/<scenario>/<agent>/<camera>/<frame>.png`` (the recorded RGB PNG, copied) and
``<split>/masks/<scenario>/<agent>/<camera>/<frame>m.png`` (uint8, one value per pixel), the ``images``/``masks``
folders and ``m.png`` suffix of MaSTr1325 (its loaders take ``img_suffix='.png'`` here: the images are PNG, not
JPEG). ``mastr.yaml`` at the root lists the label values and the mapping.

MaSTr1325 values: 0 obstacles and environment, 1 water, 2 sky, 4 ignore. From the camera's semantic image
(:mod:`mmusv.classes`): ``none`` (0, no surface hit: the sky) → 2, ``water`` (1) → 1, every other class (terrain,
vegetation, port structure, container, crane, buoy, building, vessel, USV, and any id not known) → 0. mmusv has
no pixel it cannot label, so 4 does not occur.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from mmusv.classes import SemanticClass, class_name
from mmusv.export.camera import CameraWriter, Sample
from mmusv.export.common import Sink, dump_yaml, encode_png, png_bytes

__all__ = ["MASTR_LABELS", "MastrWriter", "mastr_lut", "mastr_mask"]

OBSTACLE, WATER, SKY, IGNORE = 0, 1, 2, 4
MASTR_LABELS = {OBSTACLE: "obstacle", WATER: "water", SKY: "sky", IGNORE: "ignore"}
"""MaSTr1325 label value → meaning."""


def mastr_lut() -> np.ndarray:
    """``(65536,)`` uint8: MaSTr label of every semantic class id (see the module docstring)."""
    lut = np.full(65536, OBSTACLE, dtype=np.uint8)
    lut[int(SemanticClass.NONE)] = SKY
    lut[int(SemanticClass.WATER)] = WATER
    return lut


def mastr_mask(semantic: np.ndarray) -> np.ndarray:
    """The MaSTr mask ``(H, W)`` uint8 of an ``(H, W)`` semantic class image (integer class ids)."""
    return mastr_lut()[np.asarray(semantic).astype(np.int64)]


class MastrWriter(CameraWriter):
    """Writes MaSTr1325-style masks beside the images (see the module docstring)."""

    kinds: ClassVar[tuple[str, ...]] = ("rgb", "semantic")
    no_agent_reason: ClassVar[str] = "no camera recording rgb and semantic images"

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.lut = mastr_lut()

    def write_sample(self, sample: Sample) -> None:
        from mmusv.recording import decode_image

        base = () if sample.split == "all" else (sample.split,)
        self.put(self.file(*base, "images", f"{sample.key}.png"), png_bytes(sample.message("rgb")))
        sem = np.asarray(decode_image(sample.message("semantic"))).astype(np.int64)
        self.put(self.file(*base, "masks", f"{sample.key}m.png"), encode_png(self.lut[sem]))

    @classmethod
    def finish_all(cls, shared: Any, out: Path, sink: Sink) -> None:
        # the layout as written: without a split the images and masks folders are at the root
        root = "" if (out / "images").is_dir() else "<split>/"
        doc = {
            "labels": MASTR_LABELS,
            "from_mmusv_class": {
                class_name(int(c)): int(v) for c, v in ((c, mastr_lut()[int(c)]) for c in SemanticClass)
            },
            "other_class_ids": OBSTACLE,
            "images": f"{root}images/<scenario>/<agent>/<camera>/<frame>.png",
            "masks": f"{root}masks/<scenario>/<agent>/<camera>/<frame>m.png",
        }
        if any(out.glob("*/images")) or (out / "images").is_dir():
            sink.write(out / "mastr.yaml", dump_yaml(doc))
