"""The detector network: PointPillars' pillar encoder and scatter (:mod:`~mmusv.learn.pillars`), its 2D
backbone (:mod:`~mmusv.learn.backbone`) and the CenterPoint head (:mod:`~mmusv.learn.head`).

For intermediate fusion the neighbours' pillars go through the same encoder and are max-fused into the ego's
canvas (:func:`~mmusv.learn.pillars.scatter_max`) before the backbone (F-Cooper's voxel-feature fusion,
Chen et al., SEC 2019). Output: the head's maps, each ``(B, C, ny / out_stride, nx / out_stride)``.
"""

from __future__ import annotations

from dataclasses import MISSING
from typing import Any

import torch
from torch import nn

from mmusv.learn._errors import input_error, input_error_types
from mmusv.learn.backbone import Backbone
from mmusv.learn.example import MODES, Batch
from mmusv.learn.head import CenterHead
from mmusv.learn.pillars import PillarEncoder, scatter, scatter_max
from mmusv.learn.presets import Preset

__all__ = ["PillarNet", "from_checkpoint"]


def torch_device(device: str | None) -> torch.device:
    """The torch device named ``device`` (``cpu``, ``cuda``, ``cuda:1``, ...) or, when ``None``, CUDA where it is
    available, else the CPU: the one rule of training, inference and ``mmusv train --jobs``."""
    return torch.device(device or ("cuda" if torch.cuda.is_available() else "cpu"))


def checked_device(device: str | None) -> torch.device:
    """:func:`torch_device`, refusing a ``device`` that names no device (``tpu``: a torch traceback) or CUDA on a
    machine without it, naming ``device`` as its user gave it (:func:`mmusv.text.given`)."""
    from mmusv.text import given

    try:
        dev = torch_device(device)
    except (RuntimeError, ValueError, TypeError):
        raise input_error(f"{given('device', device)}: not a device; allowed: cpu, cuda, cuda:N or mps") from None
    if dev.type == "cuda" and not torch.cuda.is_available():
        raise input_error(f"{given('device', device)}: CUDA is not available on this machine; use cpu")
    return dev


class PillarNet(nn.Module):
    """PointPillars + CenterPoint of preset ``p`` for training ``mode`` (``single``, ``early``,
    ``intermediate``)."""

    def __init__(self, p: Preset, mode: str) -> None:
        super().__init__()
        if mode not in MODES:
            raise input_error(f"mode {mode!r}: allowed: {', '.join(MODES)}")
        self.preset, self.mode = p, mode
        self.encoder = PillarEncoder(p.pfn_channels)
        self.backbone = Backbone(p, p.pfn_channels)
        self.head = CenterHead(self.backbone.out_channels, p.head_channels)

    def channels_last(self) -> PillarNet:
        """Stores the backbone's and the head's convolution weights channels-last (NHWC) and returns the model:
        the same function (a test compares the outputs), but cuDNN then runs the convolutions and batch norms
        without converting between layouts around every layer. Measured on one H200 (bf16 autocast, the `paper`
        preset, batch 4, model step alone): 11.8 → 24.3 steps/s; batch-norm kernels and NCHW↔NHWC conversions were
        70 % of the step's GPU time before. On a CPU (oneDNN) a training step of the `cpu` preset, one thread, batch
        4, took 0.175 s against 0.225 s in NCHW (2-core Xeon, 2026-11-29); inference gains little there (0.014 against
        0.015 s a frame). Used by training on every device and by inference on CUDA."""
        self.backbone.to(memory_format=torch.channels_last)
        self.head.to(memory_format=torch.channels_last)
        return self

    def canvas(self, b: Batch) -> torch.Tensor:
        """The BEV pillar canvas ``(B, C, ny, nx)`` (neighbours max-fused in intermediate mode)."""
        f = self.encoder(b.features, b.mask)
        out = scatter(f, coords=b.coords, batch=b.batch, size=b.size, grid=self.preset.grid)
        if self.mode == "intermediate" and len(b.nb_cells):
            g = self.encoder(b.nb_features, b.nb_mask)
            out = scatter_max(out, features=g, cells=b.nb_cells, batch=b.nb_batch)
        return out

    def forward(self, b: Batch) -> dict[str, torch.Tensor]:
        out: dict[str, torch.Tensor] = self.head(self.backbone(self.canvas(b)))
        return out


def from_checkpoint(ck: dict[str, Any], what: str, *, mode: str | None = None) -> PillarNet:
    """The model a checkpoint dict of :mod:`mmusv.learn.train` holds (``model.pt``), its weights loaded, on the CPU;
    ``what`` names the file for the errors (``"--model OUT/single/model.pt: not an mmusv.learn model.pt"``),
    ``mode``: the model the file must be (the folder it lies in: ``OUT/single/model.pt`` holding the early model
    served no and late fusion without a word). Raises the training core's input error naming the file and the field:
    a preset of another mmusv version (fields it does not know or lacks; it was a ``TypeError`` of
    ``Preset.__init__``), an unknown or other ``mode``, ``epoch``/``step`` that are not counts (a ``KeyError``
    traceback in the study), weights of another shape, or weights that are not finite (a training that diverged:
    such a model finds nothing)."""
    from dataclasses import fields

    preset = ck.get("preset")
    if not isinstance(preset, dict):
        raise input_error(f"{what} (preset: {type(preset).__name__}, not the preset's fields)")
    known = {f.name for f in fields(Preset)}
    required = {f.name for f in fields(Preset) if f.default is MISSING and f.default_factory is MISSING}
    unknown = sorted(set(preset) - known)
    missing = sorted(required - set(preset))
    if unknown or missing:
        parts = ([f"unknown field(s) {', '.join(unknown)}"] if unknown else []) + (
            [f"missing field(s) {', '.join(missing)}"] if missing else []
        )
        raise input_error(
            f"{what} (preset: {'; '.join(parts)}: written by another version of mmusv; train it again with this one)"
        )
    m = ck.get("mode")
    if m not in MODES:
        raise input_error(f"{what} (mode: {m!r}; allowed: {', '.join(MODES)})")
    if mode is not None and m != mode:
        raise input_error(f"{what} (mode: it holds the {m} model, where the {mode} model belongs; put it in {m}/)")
    for key in ("epoch", "step"):
        v = ck.get(key)
        if type(v) is not int or v < 0:
            raise input_error(f"{what} ({key}: {v!r}; a count, 0 or more)")
    state = ck.get("model")
    if not isinstance(state, dict):
        raise input_error(f"{what} (model: {type(state).__name__}, not the model's weights)")
    try:
        net = PillarNet(Preset.from_dict(preset), m)
        net.load_state_dict(state)
    except input_error_types() as exc:  # the preset's own checks (a grid the backbone cannot divide)
        raise input_error(f"{what} (preset: {exc})") from None
    except (KeyError, TypeError, RuntimeError, ValueError) as exc:
        raise input_error(f"{what} ({type(exc).__name__}: {exc})") from None
    bad = [
        k for k, t in state.items() if isinstance(t, torch.Tensor) and t.is_floating_point() and not t.isfinite().all()
    ]
    if bad:
        raise input_error(
            f"{what} (model: weights that are not finite (NaN or inf) in {', '.join(bad[:3])}"
            f"{f' and {len(bad) - 3} more' if len(bad) > 3 else ''}: its training diverged; train it again, e.g. with "
            "a lower lr)"
        )
    return net
