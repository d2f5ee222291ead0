"""Training presets: the pillar grid, the network's widths and the optimiser, by name.

- ``paper``: the paper's configuration (Sec. III-C): 0.4 m pillars over [-200, 200] m in x and y and [-20, 40] m
  in z, a learning rate of 2e-3, batch 4, 30 epochs. Meant for a GPU. One difference: the paper trains with Adam,
  every preset here with AdamW (:func:`mmusv.learn.train.train`), whose decoupled weight decay is ``weight_decay``
  (0.01 by default, in ``paper`` too); kept as it is, since the recorded ``paper`` runs in
  ``docs/studies/detection.md`` were trained so.
- ``cpu``: chosen to train on a 2-core CPU in under 45 minutes on the bundled detection dataset (three models:
  single, early, intermediate, side by side in three one-thread processes, ``mmusv train``'s default on a CPU):
  2 m pillars over the same ±200 m (the evaluation range), two narrow backbone stages, output cells of 4 m, every
  second frame of each training sequence (consecutive frames at 5 Hz are nearly the same scene), 12 epochs;
  targets only for boxes with a point of the model's input (``min_points`` 1) and the z column of the regression
  weighted 0.1 (``code_weights``: measured on 270 s single-model runs, this doubled the test AP@0.5; see
  docs/studies/detection.md). 12 epochs side by side took 28 min 53 s on the 2-core machine and raised the
  refined early-fusion AP@0.5 on the bundled test split from 0.406 (6 epochs) to 0.498.
- ``tiny``: for the tests (a few frames, seconds).

All lengths in metres; ranges in the ego LiDAR frame (x forward, y left, z up).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields, replace
from typing import Any

__all__ = ["PRESETS", "Preset", "parse_overrides", "preset"]


@dataclass(frozen=True)
class Preset:
    """One training configuration.

    ``pillar_m``: pillar edge; ``x_range``/``y_range``/``z_range``: ``(lo, hi)`` of the grid (points outside are
    dropped); ``max_pillars``, ``max_points``: the non-empty pillars kept per cloud and points per pillar (the
    rest dropped, in a seeded order); ``pfn_channels``: pillar feature width; ``blocks``: ``(channels, layers,
    stride)`` of each backbone stage; ``up_channels``: each stage's upsampled width; ``out_stride``: output cell
    = ``out_stride * pillar_m``; ``head_channels``: the head's shared conv width; ``lr``, ``batch``, ``epochs``,
    ``weight_decay``; augmentation: ``flip``, ``rot_deg`` (uniform ±), ``scale`` (uniform ``(lo, hi)``);
    ``frame_stride``: train on every k-th frame of a sequence; ``min_radius``: CenterPoint's least Gaussian
    radius (cells); ``score_threshold``, ``top_k``, ``nms_iou``: decoding; ``yaw_double``: regress ``sin 2ψ,
    cos 2ψ`` instead of ``sin ψ, cos ψ`` (a BEV box is the same at ψ and ψ + π, and a hull seen from one side
    rarely shows which end is the bow: regressing ψ itself makes the head average the two answers; the study's
    IoU does not depend on the direction). Default off, so checkpoints from before it was added decode as they
    were trained; every preset sets it. ``reg_radius``: cells around each centre that also get regression rows
    (:mod:`mmusv.learn.targets`; 0 = CenterPoint's centre row only). ``min_points``: training targets only for
    the boxes with at least this many points of the model's own input inside (the ego's cloud for ``single``, the
    ego's and its neighbours' for ``early`` and ``intermediate``; :func:`mmusv.learn.targets.points_in_boxes`),
    so that a model is not taught to put a centre on empty water where a vessel no sensor saw happens to lie (as
    KITTI-style pipelines drop boxes without points); 0 keeps every box. Evaluation always scores every box.
    ``code_weights``: CenterPoint's per-column weights of the L1 regression loss, in the order of
    :data:`mmusv.learn.targets.REG_COLUMNS` (``dx, dy, z, log l, log w, log h, sin, cos``; CenterPoint's
    default, all 1, is tuned for cars, whose centre heights spread over about a metre: vessels' box centres
    spread over about 15 m in z, and with weight 1 the z error made up about 70 % of the regression loss of a
    ``cpu`` model after 1,100 steps, starving the offset, size and heading that the BEV IoU depends on)."""

    name: str
    pillar_m: float
    x_range: tuple[float, float]
    y_range: tuple[float, float]
    z_range: tuple[float, float]
    max_pillars: int
    max_points: int
    pfn_channels: int
    blocks: tuple[tuple[int, int, int], ...]
    up_channels: int
    out_stride: int
    head_channels: int
    lr: float
    batch: int
    epochs: int
    weight_decay: float = 1e-2
    flip: bool = True
    rot_deg: float = 45.0
    scale: tuple[float, float] = (0.95, 1.05)
    frame_stride: int = 1
    min_radius: int = 2
    score_threshold: float = 0.1
    top_k: int = 100
    nms_iou: float = 0.1
    yaw_double: bool = False
    reg_radius: int = 0
    min_points: int = 0
    code_weights: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0)

    @property
    def grid(self) -> tuple[int, int]:
        """``(nx, ny)`` pillars along x and y."""
        nx = round((self.x_range[1] - self.x_range[0]) / self.pillar_m)
        ny = round((self.y_range[1] - self.y_range[0]) / self.pillar_m)
        return nx, ny

    @property
    def out_grid(self) -> tuple[int, int]:
        """``(nx, ny)`` cells of the head's output maps."""
        nx, ny = self.grid
        return nx // self.out_stride, ny // self.out_stride

    def to_dict(self) -> dict[str, Any]:
        """Plain values (tuples as lists), for checkpoints and logs."""
        return asdict(self)

    @staticmethod
    def from_dict(d: dict[str, Any]) -> Preset:
        """The inverse of :meth:`to_dict`."""
        v = dict(d)
        for k in ("x_range", "y_range", "z_range", "scale", "code_weights"):
            if k in v:
                v[k] = tuple(v[k])
        v["blocks"] = tuple(tuple(b) for b in v["blocks"])
        v.setdefault("reg_radius", 0)  # checkpoints from before these were added
        v.setdefault("min_points", 0)
        return Preset(**v)


PRESETS: dict[str, Preset] = {
    "paper": Preset(
        name="paper",
        pillar_m=0.4,
        x_range=(-200.0, 200.0),
        y_range=(-200.0, 200.0),
        z_range=(-20.0, 40.0),
        max_pillars=40000,
        max_points=32,
        pfn_channels=64,
        blocks=((64, 3, 2), (128, 5, 2), (256, 5, 2)),
        up_channels=128,
        out_stride=2,
        head_channels=64,
        lr=2e-3,
        batch=4,
        epochs=30,
        yaw_double=True,
    ),
    "cpu": Preset(
        name="cpu",
        pillar_m=2.0,
        x_range=(-200.0, 200.0),
        y_range=(-200.0, 200.0),
        z_range=(-20.0, 40.0),
        max_pillars=12000,
        max_points=8,
        pfn_channels=16,
        blocks=((24, 1, 2), (48, 1, 2)),
        up_channels=32,
        out_stride=2,
        head_channels=16,
        lr=2e-3,
        batch=4,
        epochs=12,
        frame_stride=2,
        yaw_double=True,
        min_points=1,
        code_weights=(1.0, 1.0, 0.1, 1.0, 1.0, 1.0, 1.0, 1.0),
    ),
    "tiny": Preset(
        name="tiny",
        pillar_m=1.0,
        x_range=(-32.0, 32.0),
        y_range=(-32.0, 32.0),
        z_range=(-5.0, 15.0),
        max_pillars=2000,
        max_points=8,
        pfn_channels=16,
        blocks=((16, 1, 1), (32, 1, 2)),
        up_channels=16,
        out_stride=1,
        head_channels=16,
        lr=3e-3,
        batch=2,
        epochs=1,
        rot_deg=0.0,
        flip=False,
        scale=(1.0, 1.0),
        min_radius=1,
        yaw_double=True,
    ),
}


def preset(name: str, **overrides: Any) -> Preset:
    """The preset ``name`` (``paper``, ``cpu``, ``tiny``) with ``overrides`` applied; raises ``KeyError`` naming
    the allowed ones for an unknown name."""
    if name not in PRESETS:
        raise KeyError(f"preset {name!r}: allowed: {', '.join(PRESETS)}")
    return replace(PRESETS[name], **overrides)


def parse_overrides(items: Sequence[str]) -> dict[str, Any]:
    """``{field: value}`` from ``KEY=VALUE`` strings (``--set`` on the command line): ``KEY`` a :class:`Preset`
    field other than ``name``, ``VALUE`` JSON of that field's kind (a number, ``true``/``false``, or a list for
    the tuple fields, e.g. ``code_weights=[1,1,0.1,1,1,1,1,1]``); ``blocks`` as a list of ``[channels, layers,
    stride]`` lists. Raises the training core's input error naming the item (``items[0] = 'k=v'``; ``--set 'k=v'``
    on the command line) and what is allowed."""
    from mmusv.learn._errors import input_error
    from mmusv.text import named

    defaults = {f.name: getattr(PRESETS["paper"], f.name) for f in fields(Preset) if f.name != "name"}
    out: dict[str, Any] = {}
    if isinstance(items, str):  # one string was read as its characters ("min_points=1" as 'm', 'i', ...)
        raise input_error(f"items = {items!r}: must be a list of KEY=VALUE strings, e.g. [{items!r}]")
    for i, item in enumerate(items):
        # the item as its user gave it: --set 'k=v' on the command line, items[i] = 'k=v' in Python
        said = f"items[{i}] = {item!r}" if named("items") == "items" else f"{named('items')} {item!r}"
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or key not in defaults:
            raise input_error(f"{said}: expected KEY=VALUE with KEY one of {', '.join(defaults)}")
        try:
            value = json.loads(text)
        except json.JSONDecodeError:
            raise input_error(f"{said}: the value is not JSON (a number, true/false or a list)") from None
        old = defaults[key]
        if isinstance(old, tuple):
            ok = isinstance(value, list) and (key != "code_weights" or len(value) == len(old))
            if ok and key == "blocks":
                ok = all(isinstance(b, list) and len(b) == 3 and all(type(v) is int for v in b) for b in value)
                value = tuple(tuple(b) for b in value) if ok else value
            elif ok:
                ok = all(type(v) in (int, float) for v in value) and (key == "code_weights" or len(value) == 2)
                value = tuple(float(v) for v in value) if ok else value
            what = "a list of [channels, layers, stride]" if key == "blocks" else f"a list of {len(old)} numbers"
        elif isinstance(old, bool):
            ok, what = type(value) is bool, "true or false"
        elif isinstance(old, int):
            ok, what = type(value) is int, "an integer"
        else:
            ok, what = type(value) in (int, float), "a number"
            value = float(value) if ok else value
        if not ok:
            raise input_error(f"{said}: {key} must be {what}")
        out[key] = value
    return out
