"""CenterPoint's loss: the regression part against a hand computation (row weights, code weights)."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from mmusv.learn.loss import REG_WEIGHT, centerpoint_loss, regression_loss
from mmusv.learn.presets import Preset, preset


def _outputs(rng: np.random.Generator, h: int = 3, w: int = 4) -> dict[str, torch.Tensor]:
    chans = {"heatmap": 1, "offset": 2, "z": 1, "size": 3, "rot": 2}
    return {k: torch.from_numpy(rng.normal(size=(1, c, h, w)).astype(np.float32)) for k, c in chans.items()}


def test_regression_loss_weights_rows_and_columns_by_hand() -> None:
    rng = np.random.default_rng(0)
    out = _outputs(rng)
    index = torch.tensor([[5, 0, 11]])
    weight = torch.tensor([[1.0, 0.5, 0.0]])
    reg = torch.from_numpy(rng.normal(size=(1, 3, 8)).astype(np.float32))
    code = (1.0, 2.0, 0.1, 1.0, 1.0, 1.0, 3.0, 1.0)
    pred = np.concatenate([out[k][0].numpy().reshape(out[k].shape[1], -1) for k in ("offset", "z", "size", "rot")])
    want = sum(
        wt * sum(c * abs(pred[j, i] - reg[0, r, j].item()) for j, c in enumerate(code))
        for r, (i, wt) in enumerate(zip((5, 0, 11), (1.0, 0.5, 0.0), strict=True))
    )
    got = regression_loss(out, index=index, weight=weight, reg=reg, code_weights=code).item()
    assert got == pytest.approx(want, rel=1e-5)
    # without code weights every column counts once; a bool mask is a 0/1 weight
    plain = regression_loss(out, index=index, weight=torch.tensor([[True, True, False]]), reg=reg).item()
    want1 = sum(abs(pred[j, i] - reg[0, r, j].item()) for r, i in enumerate((5, 0)) for j in range(8))
    assert plain == pytest.approx(want1, rel=1e-5)
    # centerpoint_loss: the L1 part per unit of row weight, times REG_WEIGHT
    parts = centerpoint_loss(
        out,
        heatmap=torch.zeros(1, 1, 3, 4),
        index=index,
        mask=torch.tensor([[True, False, False]]),
        reg=reg,
        weight=weight,
        code_weights=code,
    )
    assert parts["regression"].item() == pytest.approx(REG_WEIGHT * want / 1.5, rel=1e-5)


def test_presets_from_before_the_new_fields_load() -> None:
    d = preset("cpu").to_dict()
    for k in ("reg_radius", "min_points", "code_weights"):
        d.pop(k)
    p = Preset.from_dict(d)
    assert p.reg_radius == 0 and p.min_points == 0 and p.code_weights == (1.0,) * 8
    assert Preset.from_dict(preset("cpu").to_dict()) == preset("cpu")
