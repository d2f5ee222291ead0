"""The CenterPoint head (Yin, Zhou and Krähenbühl, "Center-based 3D Object Detection and Tracking", CVPR 2021,
Sec. 3 and 4): a shared 3×3 convolution, then one small branch per output on the BEV map of the backbone:

- ``heatmap`` ``(B, 1, H, W)``: logits of the object-centre heatmap (one class: vessel);
- ``offset`` ``(B, 2, H, W)``: the centre's sub-cell position ``(dx, dy)`` in cells;
- ``z`` ``(B, 1, H, W)``: the box centre height, metres (LiDAR frame);
- ``size`` ``(B, 3, H, W)``: ``log l, log w, log h`` (metres);
- ``rot`` ``(B, 2, H, W)``: ``sin yaw, cos yaw`` (of twice the yaw with the preset's ``yaw_double``).

The heatmap bias starts at −2.19 (prior 0.1, as in CenterNet/CenterPoint), so training starts stable.
"""

from __future__ import annotations

import torch
from torch import nn

__all__ = ["OUTPUTS", "CenterHead"]

OUTPUTS: dict[str, int] = {"heatmap": 1, "offset": 2, "z": 1, "size": 3, "rot": 2}
"""Each branch and its channels."""


class CenterHead(nn.Module):
    """Branches of :data:`OUTPUTS` over ``c_in`` channels, ``channels`` wide."""

    def __init__(self, c_in: int, channels: int) -> None:
        super().__init__()
        self.shared = nn.Sequential(
            nn.Conv2d(c_in, channels, 3, padding=1, bias=False),
            nn.BatchNorm2d(channels, eps=1e-3, momentum=0.1),
            nn.ReLU(inplace=True),
        )
        self.branches = nn.ModuleDict()
        for name, out in OUTPUTS.items():
            last = nn.Conv2d(channels, out, 1)
            if name == "heatmap":
                assert last.bias is not None
                nn.init.constant_(last.bias, -2.19)
            self.branches[name] = nn.Sequential(
                nn.Conv2d(channels, channels, 3, padding=1, bias=False),
                nn.BatchNorm2d(channels, eps=1e-3, momentum=0.1),
                nn.ReLU(inplace=True),
                last,
            )

    def forward(self, x: torch.Tensor) -> dict[str, torch.Tensor]:
        y = self.shared(x)
        return {name: branch(y) for name, branch in self.branches.items()}
