"""The 2D boxes of a recording, computed for the export tests from what it recorded, never from an exporter's code:
the annotations' projected boxes and the tight boxes of the vessels' pixels in the instance images, brute force
(``test_box_convention.py``'s COCO/YOLO boxes, ``test_mot.py``'s MOTChallenge boxes, ``test_peer_readers.py``'s
boxes the peers' readers must give).

Boxes are in pixel-edge coordinates: pixel ``(i, j)`` covers ``[i, i + 1) × [j, j + 1)``, so the tight box of
columns ``c0..c1`` is ``[c0, c1 + 1)``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from mmusv.recording import decode_image, frame_messages, read_info, topics

Boxes = dict[tuple[str, str, int], dict[str, dict[str, Any]]]
"""Per image ``(agent, camera, frame)``, per vessel id: :func:`recorded`'s entry."""


def tight_box(inst: np.ndarray, instance_id: int) -> list[float] | None:
    """``[x_min, y_min, x_max, y_max]`` in pixel edges of ``inst``'s pixels equal to ``instance_id`` (``None``:
    no such pixel)."""
    ys, xs = np.nonzero(inst == instance_id)
    if xs.size == 0:
        return None
    return [float(xs.min()), float(ys.min()), float(xs.max() + 1), float(ys.max() + 1)]


def recorded(rec: Path, frames: int) -> Boxes:
    """Per image ``(agent, camera, frame)`` of the first ``frames`` frames, per vessel id with a recorded 2D box that
    has a visible pixel: ``projected``, the recorded (projected, clipped) box; ``visible``, the tight box of the
    vessel's pixels in the instance image (whole-number floats; such a vessel must have a pixel there); ``class``, its
    semantic class; ``instance``, its instance id; the box's recorded ``occlusion`` and ``truncation``; ``size``, the
    image's (width, height)."""
    info = read_info(rec)
    out: Boxes = {}
    for k in range(frames):
        msgs = frame_messages(rec, k)
        world = {v.id: v for v in msgs[topics.WORLD_STATE].vessels}
        for a in info.agents:
            ann = msgs[topics.agent_annotations(a.id)]
            for name, cam in a.cameras.items():
                inst = np.asarray(decode_image(msgs[topics.camera(a.id, name, kind="instance")]))
                per: dict[str, dict[str, Any]] = {}
                for b in ann.boxes_camera:
                    if b.camera != name or b.visible_pixels == 0:
                        continue
                    v = world[b.target_id]
                    visible = tight_box(inst, v.instance_id)
                    assert visible is not None, f"{a.id}/{name} frame {k}: {b.target_id} has no pixel"
                    per[b.target_id] = {
                        "projected": [b.x_min, b.y_min, b.x_max, b.y_max],
                        "visible": visible,
                        "class": int(v.semantic_class),
                        "instance": int(v.instance_id),
                        "occlusion": float(b.occlusion),
                        "truncation": float(b.truncation),
                        "size": (cam.width, cam.height),
                    }
                out[(a.id, name, k)] = per
    return out
