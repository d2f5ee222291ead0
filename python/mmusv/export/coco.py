"""``--to coco``: COCO instance annotations, one file per split.

Layout: ``images/<split>/<scenario>/<agent>/<camera>/<frame>.png`` (the recorded RGB PNG, copied) and
``annotations/instances_<split>.json`` (``split`` = ``train``, ``validate``, ``test``, or ``all`` without a split;
the split is made by recording, :mod:`mmusv.export.splits`). Each file: ``info`` (with ``mmusv_box``, the option
``box`` the boxes were written with, and ``mmusv_box_definition``, what it means), ``licenses`` (empty),
``images`` (``id`` from 1, ``file_name`` relative to ``images/<split>``, ``width``, ``height``, and mmusv's
``scenario``, ``agent``, ``camera``, ``frame``, ``time_s``; ``scenario`` is the scenario folder, the first part of
``file_name``, as MOT's and KITTI tracking's CSVs name it: the scenario's name, ``<name>_<hash8>`` where converted
recordings share a name), ``annotations`` and ``categories`` (every mmusv
semantic class but ``none``: ``id`` = the class id of :mod:`mmusv.classes`, ``name`` its name).

An annotation per kept 2D box (:meth:`mmusv.export.camera.CameraWriter.boxes_of`): ``bbox`` ``[x, y, w, h]``
pixels (origin at the image's top-left corner, pixel ``(i, j)`` over ``[i, i + 1) × [j, j + 1)``), with
``box="visible"`` (the default, COCO's convention) the tight box of the vessel's segmentation, what pycocotools'
``toBbox`` gives for it, and with ``box="projected"`` the recording's box (the vessel's projected 3D box clipped to
the image: it reaches down to the keel below the waterline and over what hides the vessel); ``category_id`` the
vessel's semantic class, ``segmentation`` the run-length encoding (pycocotools, ``counts`` as a string) of the
instance image's pixels equal to the vessel's instance id, ``area`` that mask's pixel count, ``iscrowd`` 0, and the
extra fields ``truncation`` (as recorded: the share of the projected box outside the image), ``occlusion`` (as
recorded: the share of the vessel's silhouette above the still water level, within the image, that other objects or
the waves' crests hide), ``wave_occlusion`` (as recorded: the part of that share the waves hide, 6 decimals; 0 over a
flat sea, ``null`` for a recording made before the field existed), ``role``, ``mmusv_id`` (vessel id),
``instance_id``, ``visible_pixels`` and ``contrast`` (the vessel's apparent Weber contrast in the RGB image,
:func:`mmusv.export.contrast.apparent_contrast`, 6 decimals; ``null`` where undefined).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from mmusv.errors import ConfigError
from mmusv.export.camera import CATEGORIES, CameraWriter, Sample, Shared, category_names
from mmusv.export.common import BOX_DEFINITIONS, Options, Sink, png_bytes, rounded_share
from mmusv.export.splits import SPLIT_NAMES
from mmusv.jsonio import dump_json
from mmusv.recording.info import RecordingInfo

__all__ = ["CocoWriter", "annotations_file"]


def annotations_file(split: str) -> str:
    """``annotations/instances_<split>.json``."""
    return f"annotations/instances_{split}.json"


class _CocoShared(Shared):
    def __init__(self, out: Path, box: str) -> None:
        super().__init__(out=out)
        self.box = box
        self.images: dict[str, list[dict[str, Any]]] = {}
        self.annotations: dict[str, list[dict[str, Any]]] = {}


class CocoWriter(CameraWriter):
    """Writes COCO instance annotations (see the module docstring)."""

    kinds: ClassVar[tuple[str, ...]] = ("rgb", "instance")
    boxes: ClassVar[bool] = True
    contrast: ClassVar[bool] = True
    no_agent_reason: ClassVar[str] = "no camera recording rgb and instance images (COCO masks need instance images)"

    @classmethod
    def check(cls, info: RecordingInfo) -> None:
        try:
            import pycocotools.mask  # noqa: F401
        except ImportError:
            raise ConfigError("--to coco needs the Python package pycocotools: pip install 'mmusv[export]'") from None
        super().check(info)

    @classmethod
    def start(cls, out: Path, options: Options, sink: Sink) -> Any:
        return _CocoShared(out, options.box)

    def write_sample(self, sample: Sample) -> None:
        from pycocotools import mask as mask_util

        st: _CocoShared = self.shared
        images = st.images.setdefault(sample.split, [])
        anns = st.annotations.setdefault(sample.split, [])
        name = f"{sample.key}.png"
        self.put(self.file("images", sample.split, name), png_bytes(sample.message("rgb")))
        inst = sample.instance
        h, w = inst.shape
        image_id = len(images) + 1
        images.append(
            {
                "id": image_id,
                "file_name": name,
                "width": w,
                "height": h,
                "scenario": self.folder.name,  # the scenario folder: recordings sharing a name stay apart
                "agent": sample.agent.id,
                "camera": sample.camera.name,
                "frame": sample.frame.index,
                "time_s": round(sample.world.time_s, 9),
            }
        )
        for b in self.boxes_of(sample):
            rle = mask_util.encode(np.asfortranarray(inst == b.instance_id, dtype=np.uint8))
            area = int(mask_util.area(rle))
            anns.append(
                {
                    "id": len(anns) + 1,
                    "image_id": image_id,
                    "category_id": b.semantic_class,
                    "bbox": [round(v, 3) + 0.0 for v in (b.x_min, b.y_min, b.width, b.height)],
                    "area": area,
                    "iscrowd": 0,
                    "segmentation": {"size": [h, w], "counts": rle["counts"].decode("ascii")},
                    "truncation": round(b.truncation, 6),
                    "occlusion": round(b.occlusion, 6),
                    "role": b.role,
                    "mmusv_id": b.target_id,
                    "instance_id": b.instance_id,
                    "visible_pixels": b.visible_pixels,
                    "contrast": None if b.contrast is None else round(b.contrast, 6) + 0.0,
                    "wave_occlusion": rounded_share(b.wave_occlusion),
                }
            )

    @classmethod
    def finish_all(cls, shared: Any, out: Path, sink: Sink) -> None:
        st: _CocoShared = shared
        names = category_names()
        cats = [{"id": c, "name": names[c], "supercategory": "maritime"} for c in CATEGORIES]
        for split in [*SPLIT_NAMES, "all"]:
            if split not in st.images:
                continue
            doc = {
                "info": {
                    "description": f"mmusv recordings, split {split}",
                    "version": "1.0",
                    "mmusv_box": st.box,
                    "mmusv_box_definition": BOX_DEFINITIONS[st.box],
                },
                "licenses": [],
                "images": st.images[split],
                "annotations": st.annotations.get(split, []),
                "categories": cats,
            }
            path = out / annotations_file(split)
            sink.mkdir(path.parent)
            sink.write(path, dump_json(doc))
