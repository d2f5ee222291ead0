"""The detector network: PointPillars' pillar encoder and scatter (:mod:`~mmusv.learn.pillars`), its 2D
backbone (:mod:`~mmusv.learn.backbone`) and the CenterPoint head (:mod:`~mmusv.learn.head`).

For intermediate fusion the neighbours' pillars go through the same encoder and are max-fused into the ego's
canvas (:func:`~mmusv.learn.pillars.scatter_max`) before the backbone (F-Cooper's voxel-feature fusion,
Chen et al., SEC 2019). Output: the head's maps, each ``(B, C, ny / out_stride, nx / out_stride)``.
"""

from __future__ import annotations

import torch
from torch import nn

from mmusv.learn._errors import input_error
from mmusv.learn.backbone import Backbone
from mmusv.learn.example import MODES, Batch
from mmusv.learn.head import CenterHead
from mmusv.learn.pillars import PillarEncoder, scatter, scatter_max
from mmusv.learn.presets import Preset

__all__ = ["PillarNet"]


def torch_device(device: str | None) -> torch.device:
    """The torch device named ``device`` (``cpu``, ``cuda``, ``cuda:1``, ...) or, when ``None``, CUDA where it is
    available, else the CPU: the one rule of training, inference and ``mmusv train --jobs``."""
    return torch.device(device or ("cuda" if torch.cuda.is_available() else "cpu"))


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
        out = scatter(f, b.coords, b.batch, size=b.size, grid=self.preset.grid)
        if self.mode == "intermediate" and len(b.nb_cells):
            g = self.encoder(b.nb_features, b.nb_mask)
            out = scatter_max(out, g, b.nb_cells, b.nb_batch)
        return out

    def forward(self, b: Batch) -> dict[str, torch.Tensor]:
        out: dict[str, torch.Tensor] = self.head(self.backbone(self.canvas(b)))
        return out
