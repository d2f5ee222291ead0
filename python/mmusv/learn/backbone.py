"""The 2D BEV backbone of PointPillars (Lang et al., CVPR 2019, Sec. 2.2, after SECOND's RPN): stages of 3×3
convolutions, each starting with a strided one, whose outputs are brought to a common stride by transposed
convolutions and concatenated.

Input ``(B, C_in, ny, nx)`` pillar canvas; output ``(B, up_channels · stages, ny / out_stride, nx / out_stride)``.
The grid must be divisible by every stage's cumulative stride (checked: the size-mismatch OpenCOOD users meet as
"125 vs 126").
"""

from __future__ import annotations

import torch
from torch import nn

from mmusv.learn._errors import input_error
from mmusv.learn.presets import Preset

__all__ = ["Backbone", "check_grid"]


def _conv(c_in: int, c_out: int, stride: int) -> list[nn.Module]:
    return [
        nn.Conv2d(c_in, c_out, 3, stride=stride, padding=1, bias=False),
        nn.BatchNorm2d(c_out, eps=1e-3, momentum=0.1),
        nn.ReLU(inplace=True),
    ]


def check_grid(p: Preset) -> None:
    """Raises when preset ``p``'s grid is not divisible by the backbone's strides, naming the sizes allowed."""
    nx, ny = p.grid
    total = 1
    for _, _, s in p.blocks:
        total *= s
    step = max(total, p.out_stride)
    if nx % step or ny % step:
        raise input_error(
            f"preset {p.name}: grid {nx} x {ny} pillars ({p.pillar_m} m over x {p.x_range}, y {p.y_range}) is not a "
            f"multiple of the backbone's total stride {step}; choose a range / pillar size giving a multiple of {step}"
        )


class Backbone(nn.Module):
    """The stages and upsampling of preset ``p`` on ``c_in`` input channels (module docstring)."""

    def __init__(self, p: Preset, c_in: int) -> None:
        super().__init__()
        check_grid(p)
        self.stages = nn.ModuleList()
        self.ups = nn.ModuleList()
        cum = 1
        c = c_in
        for ch, layers, stride in p.blocks:
            mods = _conv(c, ch, stride)
            for _ in range(layers):
                mods += _conv(ch, ch, 1)
            self.stages.append(nn.Sequential(*mods))
            cum *= stride
            c = ch
            if cum >= p.out_stride:
                f = cum // p.out_stride
                up: nn.Module = nn.ConvTranspose2d(ch, p.up_channels, f, stride=f, bias=False)
            else:
                f = p.out_stride // cum
                up = nn.Conv2d(ch, p.up_channels, f, stride=f, bias=False)
            self.ups.append(
                nn.Sequential(up, nn.BatchNorm2d(p.up_channels, eps=1e-3, momentum=0.1), nn.ReLU(inplace=True))
            )
        self.out_channels = p.up_channels * len(p.blocks)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        outs = []
        for stage, up in zip(self.stages, self.ups, strict=True):
            x = stage(x)
            outs.append(up(x))
        return torch.cat(outs, dim=1)
