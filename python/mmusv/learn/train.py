"""Training loop: seeded shuffling and augmentation, Adam with a warm-up and cosine decay, a tqdm progress bar,
a JSON-lines log, a checkpoint after every epoch and resumption from it.

Run from a tensor cache (:mod:`mmusv.learn.cache`) with torch and numpy alone::

    PYTHONPATH=python python3 scripts/learn_train.py --cache CACHE.npz --preset paper --mode single -o OUT

or through ``mmusv train`` (which builds the cache first). Files in the output folder:

- ``last.pt``: the latest checkpoint (model, optimiser, epoch, step, log; written to a temporary file and
  renamed, so an interruption leaves the previous one whole); training resumes from it when started again (a run
  stopped inside an epoch, by ``time_limit_s`` or ``max_steps``, resumes at that epoch's start with the weights
  it had reached);
- ``model.pt``: the weights, preset and mode for inference (:mod:`mmusv.learn.detector`), after every epoch, with
  the epochs asked for (``epochs``), why the run stopped short of them (``stopped``: ``"time limit"``, ``"max
  steps"``, or ``None`` while it is still going or was interrupted) and the data it was trained on (``data``:
  :meth:`mmusv.learn.cache.Cache.identity`), so an unfinished model, and a model evaluated on its own training
  sequences, can be told; without the wall-clock time (``last.pt`` has it), so two runs of the same seed on a CPU
  write the same bytes;
- ``log.jsonl``: one line per logged step (``epoch, step, loss, heatmap, regression, lr, seconds``) and one per
  epoch (``"epoch_end": true``); :func:`mmusv.learn.plots.plot_losses` draws it.

Determinism: weights are initialised after ``torch.manual_seed(seed)``; the order of an epoch is a permutation
drawn from ``(seed, epoch)``; each sample's augmentation from ``(seed, epoch, index)``, so it does not depend on
the number of loader workers. On CPU with ``torch.use_deterministic_algorithms`` (and a given thread count), the
same seed gives the same weights. The model trains channels-last (:meth:`PillarNet.channels_last`) on every
device. With ``time_limit_s`` the run stops at the first step past the limit (mid-epoch, checkpointed), and the
learning-rate schedule runs on elapsed time instead of steps; started again with the same limit, a run that
reached it does nothing (it took one more step and rewrote its model every time).

A training whose loss or gradient becomes NaN or infinite (a learning rate too high for the data) stops there with an
input error naming the step, before that step changes the weights: it went on and saved NaN weights as a finished
model, which finds nothing.

A ``last.pt`` is resumed only by the same run (:mod:`mmusv.learn.resume`: the same preset, mode and seed, and the
same data; the first cache was trained on again without a word when the recordings given changed)."""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from mmusv.held_signals import raise_noted_stop
from mmusv.learn._errors import input_error
from mmusv.learn.augment import apply, draw
from mmusv.learn.cache import Cache
from mmusv.learn.checkpoint import remove_stale_temporaries, save_checkpoint
from mmusv.learn.example import MODES, Example, collate, early_cloud, make_example
from mmusv.learn.loss import centerpoint_loss
from mmusv.learn.model import PillarNet, checked_device
from mmusv.learn.presets import PRESETS, Preset, parse_overrides, preset
from mmusv.learn.resume import not_a_checkpoint, resumable_checkpoint
from mmusv.learn.targets import points_in_boxes
from mmusv.text import command_line, counted, given

__all__ = ["TrainResult", "TrainingSet", "main", "train"]

WARMUP_STEPS = 100
LOG_EVERY = 10


class TrainingSet(torch.utils.data.Dataset[Example]):
    """The cache's samples (every ``frame_stride``-th frame of each sequence, or ``indices``) as augmented
    examples of ``mode`` (targets: the boxes with the preset's ``min_points`` in the mode's input cloud);
    :attr:`epoch` selects the augmentation draws. ``cache`` is a :class:`Cache` or any
    object with its ``__len__``, ``sample`` and ``frame_position``."""

    def __init__(
        self,
        cache: Cache,
        p: Preset,
        mode: str,
        *,
        seed: int,
        augment: bool = True,
        indices: Sequence[int] | None = None,
    ) -> None:
        self.cache, self.p, self.mode, self.seed, self.augment = cache, p, mode, seed, augment
        if indices is None:
            indices = [k for k in range(len(cache)) if cache.frame_position(k) % p.frame_stride == 0]
        self.indices = list(indices)
        self.epoch = 0

    def __len__(self) -> int:
        return len(self.indices)

    def __getitem__(self, i: int) -> Example:
        k = self.indices[i]
        ego, nbs, gt = self.cache.sample(k)
        if self.augment:
            rng = np.random.default_rng([self.seed, self.epoch, k])
            ego, nbs, gt = apply(draw(rng, self.p), ego=ego, neighbours=nbs, boxes=gt)
        if self.p.min_points > 0 and len(gt):
            seen = ego if self.mode == "single" else early_cloud(ego, nbs)
            gt = gt[points_in_boxes(seen, gt) >= self.p.min_points]
        return make_example(ego, neighbours=nbs, boxes=gt, mode=self.mode, p=self.p)


@dataclass(frozen=True)
class TrainResult:
    """Where the run wrote (``out``), the epochs completed, the optimiser steps and the wall time (s)."""

    out: Path
    epochs: int
    steps: int
    seconds: float
    finished: bool
    stopped: str | None = None
    """Why the run stopped before its epochs: ``"time limit"``, ``"max steps"`` (``None``: it did not)."""


def _lr(p: Preset, step: int, progress: float) -> float:
    warm = min(1.0, (step + 1) / WARMUP_STEPS)
    return p.lr * warm * (0.02 + 0.98 * 0.5 * (1 + math.cos(math.pi * min(1.0, progress))))


def _save(obj: dict[str, Any], path: Path) -> None:
    """``obj`` saved to ``path`` (:func:`mmusv.learn.checkpoint.save_checkpoint`: through a temporary file, so an
    interruption leaves the previous file whole and no temporary behind)."""
    save_checkpoint(obj, path)


def _whole(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _check_options(
    *,
    epochs: int | None,
    time_limit_s: float | None,
    max_steps: int | None,
    seed: int,
    workers: int,
    device: str | None,
) -> torch.device:
    """The device of :func:`train`, its other options checked before anything is written: ``scripts/learn_train.py``
    (which checked none, ``mmusv train`` checks its own flags) trained nothing with ``--epochs 0`` or ``-3`` or
    ``--time-limit -1`` and said ``finished=True`` or wrote no model, ignored ``--time-limit nan``, and ``--seed -1``,
    ``--workers -1`` and ``--device tpu`` were tracebacks of numpy and torch."""
    if epochs is not None and not (_whole(epochs) and epochs >= 1):
        raise input_error(f"{given('epochs', epochs)}: must be a whole number >= 1 (or left out for the preset's)")
    if time_limit_s is not None and not (
        isinstance(time_limit_s, (int, float)) and math.isfinite(time_limit_s) and time_limit_s > 0
    ):
        raise input_error(
            f"{given('time_limit_s', time_limit_s)}: seconds, a finite number > 0 (or left out for no limit)"
        )
    if max_steps is not None and not (_whole(max_steps) and max_steps >= 1):
        raise input_error(f"{given('max_steps', max_steps)}: must be a whole number >= 1 (or left out for no limit)")
    if not (_whole(seed) and 0 <= seed < 2**63):
        raise input_error(f"{given('seed', seed)}: must be a whole number in 0..{2**63 - 1}")
    if not (_whole(workers) and workers >= 0):
        raise input_error(f"{given('workers', workers)}: must be a whole number >= 0 (0: load data in this process)")
    return checked_device(device)


def _write_log(path: Path, log: list[dict[str, Any]]) -> None:
    """``log.jsonl`` (one JSON object a line) written whole, through a temporary ``.log.jsonl.<pid>.tmp`` renamed
    into place: written in place, a run interrupted while writing it left it cut short, and the same command run
    again, with no epoch left to train, failed plotting it (a ``JSONDecodeError`` traceback)."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text("".join(json.dumps(r) + "\n" for r in log), encoding="utf-8")
        tmp.replace(path)
    except BaseException:  # a full disk, a Ctrl-C: no temporary file is left behind
        tmp.unlink(missing_ok=True)
        raise


def train(
    cache: Cache | str | Path,
    *,
    p: Preset,
    mode: str,
    out: str | Path,
    seed: int = 0,
    epochs: int | None = None,
    time_limit_s: float | None = None,
    max_steps: int | None = None,
    device: str | None = None,
    workers: int = 0,
    progress: bool = True,
    indices: Sequence[int] | None = None,
    augment: bool = True,
) -> TrainResult:
    """Trains model ``mode`` of preset ``p`` on ``cache`` into ``out`` (module docstring); resumes from
    ``out/last.pt`` when present. ``epochs`` defaults to the preset's; ``max_steps`` stops early (tests)."""
    if mode not in MODES:
        raise input_error(f"{given('mode', mode)}: allowed: {', '.join(MODES)}")
    dev = _check_options(
        epochs=epochs, time_limit_s=time_limit_s, max_steps=max_steps, seed=seed, workers=workers, device=device
    )
    c = Cache(cache, name="cache") if isinstance(cache, (str, Path)) else cache
    out_p = Path(out)
    out_p.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(out_p)  # of a run killed while it saved (they were left in the folder for good)
    if dev.type == "cpu":
        torch.use_deterministic_algorithms(True)
        # Deterministic mode also fills every new tensor with NaN, to expose reads of memory never written; no
        # algorithm's result depends on it, and it was 18 % of a `cpu` preset step on one core (3,954 fills a step).
        torch.utils.deterministic.fill_uninitialized_memory = False  # type: ignore[attr-defined]
    else:
        torch.backends.cuda.matmul.allow_tf32 = True
        torch.backends.cudnn.allow_tf32 = True
        torch.backends.cudnn.benchmark = True
    n_epochs = epochs if epochs is not None else p.epochs
    torch.manual_seed(seed)
    model = PillarNet(p, mode).to(dev).channels_last()
    opt = torch.optim.AdamW(model.parameters(), lr=p.lr, weight_decay=p.weight_decay)
    data = TrainingSet(c, p, mode, seed=seed, augment=augment, indices=indices)
    if len(data) == 0:
        raise input_error(f"{given('cache', getattr(c, 'path', c))}: no training sample")
    identity = c.identity() if isinstance(c, Cache) else None
    steps_per_epoch = math.ceil(len(data) / p.batch)
    start_epoch, step, log, spent = 0, 0, [], 0.0
    last = out_p / "last.pt"
    ck = resumable_checkpoint(out_p, p=p, mode=mode, seed=seed, identity=identity, device=dev)
    if ck is not None:
        try:
            model.load_state_dict(ck["model"])
            opt.load_state_dict(ck["optimizer"])
            start_epoch, step, log, spent = int(ck["epoch"]), int(ck["step"]), list(ck["log"]), float(ck["seconds"])
        except (KeyError, TypeError, RuntimeError, ValueError) as exc:
            raise input_error(f"{not_a_checkpoint(last)} ({type(exc).__name__}: {exc})") from None
    log_path = out_p / "log.jsonl"
    if ck is not None:  # whole again from last.pt's log, also when nothing is left to train (plot_losses reads it)
        _write_log(log_path, log)
    t0 = time.perf_counter() - spent
    finished = True
    stop: str | None = None
    # A run that stopped at its time limit or step budget, started again with the same one, stops there: it took one
    # more step (and rewrote its model) every time it was started.
    if start_epoch < n_epochs and time_limit_s and spent > time_limit_s:
        stop = "time limit"
    elif start_epoch < n_epochs and max_steps is not None and step >= max_steps:
        stop = "max steps"
    if start_epoch > n_epochs:  # kept as it is: said, not taken for a model of the epochs asked for
        print(
            f"{mode}: {last} has trained {start_epoch} epochs, more than the {n_epochs} asked for: it is kept as it "
            "is (train into another folder for a model of fewer epochs)",
            flush=True,
        )
    if start_epoch < n_epochs and stop is None:
        if step:
            print(f"{mode}: resuming {last} at epoch {start_epoch + 1}/{n_epochs}, step {step}", flush=True)
        _warn_without_targets(c, p, mode, data.indices)
    amp = dev.type == "cuda"
    bar: Any = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=n_epochs * steps_per_epoch, initial=step, desc=f"train {mode} ({p.name})", unit="step")
    epoch = start_epoch
    while epoch < n_epochs and stop is None:
        data.epoch = epoch
        order = np.random.default_rng([seed, epoch, 7]).permutation(len(data))
        sampler = [int(i) for i in order]
        loader = torch.utils.data.DataLoader(
            data,
            batch_size=p.batch,
            sampler=sampler,
            collate_fn=collate,
            num_workers=workers,
            drop_last=False,
            pin_memory=dev.type == "cuda",
        )
        model.train()
        stopped = False
        for batch in loader:
            raise_noted_stop()  # a stop whose KeyboardInterrupt a library swallowed (held_signals)
            elapsed = time.perf_counter() - t0
            prog = step / max(1, n_epochs * steps_per_epoch)
            if time_limit_s:
                prog = max(prog, elapsed / time_limit_s)
            lr = _lr(p, step, prog)
            for g in opt.param_groups:
                g["lr"] = lr
            b = batch.to(dev)
            with torch.autocast(device_type=dev.type, dtype=torch.bfloat16, enabled=amp):
                outs = model(b)
            assert b.heatmap is not None and b.index is not None and b.reg_mask is not None and b.reg is not None
            losses = centerpoint_loss(
                outs,
                heatmap=b.heatmap,
                index=b.index,
                mask=b.reg_mask,
                reg=b.reg,
                weight=b.reg_weight,
                code_weights=p.code_weights,
            )
            opt.zero_grad(set_to_none=True)
            losses["loss"].backward()  # type: ignore[no-untyped-call]
            norm = torch.nn.utils.clip_grad_norm_(model.parameters(), 35.0)
            if not bool(torch.isfinite(losses["loss"]) & torch.isfinite(norm)):
                # it stepped on, and saved NaN weights as a finished model that finds nothing
                if bar is not None:
                    bar.close()
                what = f"the loss is {float(losses['loss'].item())}, the gradient norm {float(norm.item())}"
                kept = (
                    f"{last} and model.pt are as the last save before it left them"
                    if last.is_file()
                    else "no model.pt was written"
                )
                raise input_error(
                    f"{mode}: the training diverged: {what} at step {step + 1} (epoch {epoch + 1}, learning rate "
                    f"{lr:.3g}); {kept}. Train it again with a lower lr (preset {p.name}: {p.lr:g}) or other data"
                )
            opt.step()
            step += 1
            if bar is not None:
                bar.update(1)
                bar.set_postfix(loss=f"{losses['loss'].item():.3f}", epoch=epoch + 1)
            if step % LOG_EVERY == 0 or step == 1:
                rec = {k: round(float(v.item()), 6) for k, v in losses.items()}
                log.append({"epoch": epoch, "step": step, **rec, "lr": lr, "seconds": round(elapsed, 2)})
            if max_steps is not None and step >= max_steps:
                stopped, stop = True, "max steps"
                break
            if time_limit_s and time.perf_counter() - t0 > time_limit_s:
                stopped, stop = True, "time limit"
                break
        epoch_done = not stopped
        if epoch_done:
            epoch += 1
            log.append({"epoch": epoch, "step": step, "epoch_end": True, "seconds": round(time.perf_counter() - t0, 2)})
            if bar is None:
                print(
                    f"{mode}: epoch {epoch}/{n_epochs}, step {step}, loss {losses['loss'].item():.4f}, "
                    f"{time.perf_counter() - t0:.1f} s",
                    flush=True,
                )
        state = {
            "preset": p.to_dict(),
            "mode": mode,
            "seed": seed,
            "epoch": epoch,
            "epochs": n_epochs,
            "stopped": stop,
            "step": step,
            "log": log,
            "seconds": time.perf_counter() - t0,
            "data": identity,
        }
        _save({**state, "model": model.state_dict(), "optimizer": opt.state_dict()}, last)
        # model.pt without the wall-clock time (last.pt and train_summary.json have it): the same seed, the same bytes
        _save(
            {**{k: v for k, v in state.items() if k != "seconds"}, "model": model.state_dict(), "log": []},
            out_p / "model.pt",
        )
        _write_log(log_path, log)
        if stopped:
            finished = max_steps is not None and step >= max_steps
            break
    if bar is not None:
        bar.close()
    if stop is not None:
        finished = stop == "max steps"
    return TrainResult(out_p, epoch, step, time.perf_counter() - t0, finished and epoch >= n_epochs, stop)


def _warn_without_targets(cache: Any, p: Preset, mode: str, indices: Sequence[int]) -> None:
    """Says on stderr when no training sample has a ground-truth box centred in the preset's grid: the model is
    then taught empty water alone (recordings without targets, or a ``tiny`` grid of ±32 m around USVs whose
    targets are farther), which trained without a word and scored AP 0."""
    import sys

    n_in, n_all = 0, 0
    arrays = getattr(cache, "arrays", None)
    for k in indices:
        if arrays is not None:
            gt = arrays["gt"][arrays["gt_offsets"][k] : arrays["gt_offsets"][k + 1]]
        else:
            gt = cache.sample(k)[2]
        n_all += len(gt)
        if len(gt):
            x, y = gt[:, 0], gt[:, 1]
            inside = (x >= p.x_range[0]) & (x < p.x_range[1]) & (y >= p.y_range[0]) & (y < p.y_range[1])
            n_in += int(inside.sum())
    if n_in:
        return
    where = (
        f"the {n_all} ground-truth boxes lie outside the {p.name} preset's grid (x {p.x_range[0]:g}..{p.x_range[1]:g} "
        f"m, y {p.y_range[0]:g}..{p.y_range[1]:g} m)"
        if n_all
        else "they hold no ground-truth box (no vessel other than the USVs)"
    )
    print(
        f"{mode}: warning: none of the {len(indices)} training samples has a target to learn: {where}; the model "
        "learns empty water only",
        file=sys.stderr,
        flush=True,
    )


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m mmusv.learn.train`` / ``scripts/learn_train.py``: train one or more modes from a cache."""
    ap = argparse.ArgumentParser(description="Train mmusv.learn models from a tensor cache (torch + numpy only).")
    ap.add_argument("--cache", required=True, help="the .npz tensor cache (mmusv train --cache-only writes one)")
    ap.add_argument("--preset", default="cpu", choices=sorted(PRESETS), help="cpu (default), paper (a GPU) or tiny")
    ap.add_argument("--modes", default="single,early,intermediate", help="models to train, in turn")
    ap.add_argument("-o", "--out", required=True, help="output folder (one sub-folder per mode)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the weights and the augmentation (default 0)")
    ap.add_argument("--epochs", type=int, default=None, help="epochs (default: the preset's)")
    ap.add_argument("--time-limit", type=float, default=None, help="seconds per mode (stops at the limit)")
    ap.add_argument("--max-steps", type=int, default=None, help="stop after this many steps (smoke tests)")
    ap.add_argument("--workers", type=int, default=0, help="data-loader worker processes")
    ap.add_argument("--device", default=None, help="cpu or cuda (default: cuda when available)")
    ap.add_argument("--threads", type=int, default=None, help="CPU threads of torch (default: torch's)")
    ap.add_argument("--no-progress", action="store_true", help="no progress bar")
    ap.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a field of the preset (repeatable; VALUE as JSON), e.g. --set min_points=1 "
        "--set code_weights=[1,1,0.1,1,1,1,1,1]; the checkpoint records the preset as trained",
    )
    a = ap.parse_args(argv)
    flags = {"cache": "--cache", "items": "--set", "mode": "--modes", "epochs": "--epochs", "seed": "--seed"}
    flags.update(time_limit_s="--time-limit", max_steps="--max-steps", workers="--workers", device="--device")
    with command_line(flags):  # the messages name these flags
        return _main(a)


def _main(a: argparse.Namespace) -> int:
    if a.threads is not None:
        # (0 and negative counts were taken as 1 without a word)
        if a.threads < 1:
            raise input_error(f"--threads {a.threads}: must be a whole number >= 1 (or left out for torch's)")
        torch.set_num_threads(a.threads)
    overrides = parse_overrides(a.set)
    p = preset(a.preset, **overrides)
    if overrides:
        print(f"preset {p.name} with {overrides}", flush=True)
    # before the cache is read (train checks them again)
    _check_options(
        epochs=a.epochs,
        time_limit_s=a.time_limit,
        max_steps=a.max_steps,
        seed=a.seed,
        workers=a.workers,
        device=a.device,
    )
    cache = Cache(a.cache, name="cache")
    for mode in [m.strip() for m in a.modes.split(",") if m.strip()]:
        r = train(
            cache,
            p=p,
            mode=mode,
            out=Path(a.out) / mode,
            seed=a.seed,
            epochs=a.epochs,
            time_limit_s=a.time_limit,
            max_steps=a.max_steps,
            device=a.device,
            workers=a.workers,
            progress=not a.no_progress,
        )
        print(
            f"{mode}: {counted(r.epochs, 'epoch')}, {counted(r.steps, 'step')}, {r.seconds:.1f} s "
            f"({r.steps / max(r.seconds, 1e-9):.2f} steps/s), finished={r.finished} -> {r.out}",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    from mmusv.learn._errors import command

    raise SystemExit(command(main))
