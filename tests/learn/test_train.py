"""Training: a tiny model overfits a few synthetic frames, the loss falls, the same seed gives the same weights,
and an interrupted run resumes."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from mmusv.learn.detector import load_models
from mmusv.learn.plots import plot_losses
from mmusv.learn.presets import preset
from mmusv.learn.train import TrainingSet, train
from mmusv.studies.detection.evaluate import FrameMatch, summarize

from learn.scenes import SCENES, MemorySource

# 150 steps passed with the torch earlier CI runs installed, but torch 2.15.0 on one thread reaches only AP@0.5 0.17
# there (1.0 at 200): the model was at the edge. 250 steps reach 1.0 with seeds 0-3 on 2.15.0, a margin.
OVERFIT_STEPS = 250


def _losses(out: Path) -> list[float]:
    rows = [json.loads(x) for x in (out / "log.jsonl").read_text().splitlines()]
    return [r["loss"] for r in rows if "loss" in r]


def test_tiny_model_overfits_a_few_frames(tmp_path: Path) -> None:
    src = MemorySource(SCENES)
    p = preset("tiny", score_threshold=0.3)
    r = train(
        src, p=p, mode="single", out=tmp_path, epochs=10_000, max_steps=OVERFIT_STEPS, progress=False, augment=False
    )
    assert r.steps == OVERFIT_STEPS
    det = load_models(tmp_path / "model.pt")
    frames = []
    for k in range(len(src)):
        pts, _, gt = src.sample(k)
        boxes, scores = det(pts)
        frames.append(FrameMatch.evaluate(boxes, det_scores=scores, gt_boxes=gt))
    m = summarize(frames)
    assert m["ap50"] >= 0.9, m
    # the geometric second stage: off by default for the tiny preset, on request it keeps the network's scores
    assert det.refine is None and "no box refinement" in det.describe()
    refined = load_models(tmp_path / "model.pt", refine=True)
    assert refined.refine is not None and "refinement on the points" in refined.describe()
    for k in range(len(src)):
        pts, _, _ = src.sample(k)
        _, s0 = det(pts)
        b1, s1 = refined(pts)
        assert b1.shape == (len(s1), 7) and set(s1.tolist()) <= set(s0.tolist())
    losses = _losses(tmp_path)
    assert np.mean(losses[-3:]) < 0.25 * np.mean(losses[:3])  # the loss falls
    png = plot_losses(tmp_path / "log.jsonl", tmp_path / "loss.png")
    assert png.stat().st_size > 0


def test_same_seed_same_weights_and_resume(tmp_path: Path) -> None:
    src = MemorySource(SCENES[:2])
    p = preset("tiny")
    runs = []
    for name, seed in (("a", 4), ("b", 4), ("c", 5)):
        train(src, p=p, mode="intermediate", out=tmp_path / name, seed=seed, epochs=3, progress=False)
        runs.append(torch.load(tmp_path / name / "model.pt", weights_only=True)["model"])
    assert all(torch.equal(runs[0][k], runs[1][k]) for k in runs[0])
    assert any(not torch.equal(runs[0][k], runs[2][k]) for k in runs[0] if runs[0][k].is_floating_point())
    # interrupted after one epoch, then started again: the same weights as the run that went through
    train(src, p=p, mode="intermediate", out=tmp_path / "d", seed=4, epochs=1, progress=False)
    r = train(src, p=p, mode="intermediate", out=tmp_path / "d", seed=4, epochs=3, progress=False)
    assert r.epochs == 3
    resumed = torch.load(tmp_path / "d" / "model.pt", weights_only=True)["model"]
    assert all(torch.equal(runs[0][k], resumed[k]) for k in runs[0])


def test_min_points_drops_the_targets_of_unseen_boxes() -> None:
    # scene 0's two boxes have points; a third box on empty water gets no heatmap peak with min_points 1, but
    # one with min_points 0 (CenterPoint's default: every box)
    src = MemorySource(SCENES[:1])
    empty = np.array([[-20.0, 20.0, 1.0, 6.0, 2.0, 2.0, 0.0]])
    pts, _, gt = src.sample(0)
    src.items = [(pts, np.concatenate([gt, empty]))]
    peaks = {}
    for n in (0, 1):
        ex = TrainingSet(src, preset("tiny", min_points=n), "single", seed=0, augment=False)[0]
        assert ex.targets is not None
        peaks[n] = int((ex.targets.heatmap == 1.0).sum())
    assert peaks == {0: 3, 1: 2}


def test_channels_last_model_is_the_same_function() -> None:
    """The layout training uses on every device and inference on CUDA (PillarNet.channels_last) changes no output:
    the same weights in NCHW and NHWC give the same maps on the same batch (here on CPU), in training mode and after
    a step."""
    from mmusv.learn.example import collate, make_example
    from mmusv.learn.loss import centerpoint_loss
    from mmusv.learn.model import PillarNet

    src = MemorySource(SCENES[:2])
    p = preset("tiny")
    samples = [src.sample(k) for k in range(2)]
    batch = collate([make_example(ego, neighbours=nbs, boxes=gt, mode="single", p=p) for ego, nbs, gt in samples])
    torch.manual_seed(3)
    a = PillarNet(p, "single")
    b = PillarNet(p, "single")
    b.load_state_dict(a.state_dict())
    b.channels_last()
    assert any(
        w.dim() == 4 and w.is_contiguous(memory_format=torch.channels_last) and not w.is_contiguous()
        for w in b.parameters()
    )
    # The same maps before training (rounding apart: NHWC convolutions sum in another order, and training-mode batch
    # norm divides by small batch variances; a wrong layout would differ by the maps' own size, O(1)) ...
    oa, ob = a(batch), b(batch)
    assert oa.keys() == ob.keys()
    for k in oa:
        torch.testing.assert_close(oa[k], ob[k], rtol=1e-3, atol=1e-3)
    # ... and after a step of the same gradients (those rounding differences grown by one update).
    for model in (a, b):
        opt = torch.optim.SGD(model.parameters(), lr=0.1)
        out = model(batch)
        loss = centerpoint_loss(
            out, heatmap=batch.heatmap, index=batch.index, mask=batch.reg_mask, reg=batch.reg, weight=batch.reg_weight
        )
        opt.zero_grad()
        loss["loss"].backward()
        opt.step()
    oa, ob = a(batch), b(batch)
    for k in oa:
        torch.testing.assert_close(oa[k], ob[k], rtol=5e-3, atol=5e-2)


def test_a_model_trained_further_than_asked_is_kept_and_said_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``epochs`` fewer than the folder's model has trained: the model was kept and reported as done, and nothing
    said that the epochs asked for were not those of the model."""
    src = MemorySource(SCENES[:1])
    p = preset("tiny")
    train(src, p=p, mode="single", out=tmp_path, seed=1, epochs=2, progress=False)
    before = (tmp_path / "model.pt").read_bytes()
    capsys.readouterr()
    r = train(src, p=p, mode="single", out=tmp_path, seed=1, epochs=1, progress=False)
    out = capsys.readouterr().out
    assert "has trained 2 epochs, more than the 1 asked for: it is kept as it is" in out, out
    assert r.epochs == 2 and (tmp_path / "model.pt").read_bytes() == before


def test_a_stop_swallowed_in_a_step_ends_the_training(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # A stop whose KeyboardInterrupt a library swallowed (noted by the command's handler, then not raised) went on
    # training to the last epoch; the next step raises it again (held_signals.raise_noted_stop).
    import signal

    import mmusv.learn.train as train_module
    from mmusv.held_signals import note_stop

    calls: list[int] = []
    original = train_module.centerpoint_loss

    def loss(*args: Any, **kwargs: Any) -> Any:
        calls.append(len(calls))
        note_stop(signal.SIGINT)
        return original(*args, **kwargs)

    monkeypatch.setattr(train_module, "centerpoint_loss", loss)
    try:
        with pytest.raises(KeyboardInterrupt):
            train(
                MemorySource(SCENES[:2]), p=preset("tiny"), mode="single", out=tmp_path / "m", epochs=3, progress=False
            )
    finally:
        note_stop(None)
    assert calls == [0]
