"""``mmusv train``: builds the tensor cache of a detection dataset's training split (:mod:`mmusv.learn.cache`)
and trains the single-agent, early- and intermediate-fusion models of a preset (:mod:`mmusv.learn.train`), each
into ``OUT/<mode>/`` with its checkpoint, log and loss plot (``loss.png``); started again, it resumes.
``mmusv study detection|robustness --model OUT`` then scores them (:func:`load_for_study`).

Without the ``learn`` extra (PyTorch) both raise :class:`mmusv.errors.InputError` saying how to install it.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

from mmusv.errors import InputError

__all__ = ["add_parser", "load_for_study", "run"]

_INSTALL = "needs the learn extra (PyTorch): pip install 'mmusv[learn]' (or pip install torch tqdm)"


def _torch() -> None:
    try:
        import torch  # noqa: F401
        import tqdm  # noqa: F401
    except ImportError:
        raise InputError(f"mmusv.learn {_INSTALL}") from None


def load_for_study(path: str, *, refine: bool | None = None) -> Any:
    """The :class:`~mmusv.learn.detector.LearnedDetector` at ``path`` (``--model``); ``refine``: the geometric
    second stage on or off (``None``: the default of :func:`~mmusv.learn.detector.load_models`)."""
    _torch()
    from mmusv.learn.detector import load_models

    return load_models(path, refine=refine)


def add_parser(sub: Any) -> None:
    """Adds ``train`` to the ``mmusv`` sub-parsers."""
    from mmusv.learn.presets import PRESETS
    from mmusv.studies.detection.cli import add_dataset_arguments

    p = sub.add_parser(
        "train",
        help="train the learned detector (PointPillars + CenterPoint) on a detection dataset",
        description="Trains the single-agent (no/late fusion), early- and intermediate-fusion models on the train "
        "split (by sequence, agent as ego, the detection study's ground truth). Needs the learn extra.",
    )
    add_dataset_arguments(p, into="OUT/dataset", then="train")
    p.add_argument("--split", default="train", help="the split to train on (default train)")
    p.add_argument("--split-ratios", default="0.7,0.15,0.15", help="train,validate,test fractions")
    p.add_argument("--seed", type=int, default=0, help="seed of the split, the weights and the augmentation")
    p.add_argument("--preset", default="cpu", choices=sorted(PRESETS), help="cpu (default), paper (a GPU) or tiny")
    p.add_argument("--modes", default="single,early,intermediate", help="models to train, in turn")
    p.add_argument("--epochs", type=int, default=None, help="epochs per model (default: the preset's)")
    p.add_argument("--time-limit", type=float, default=None, help="seconds per model at most")
    p.add_argument("--workers", type=int, default=0, help="data-loader worker processes (default 0)")
    p.add_argument("--device", default=None, help="cpu or cuda (default: cuda when available)")
    p.add_argument(
        "--threads",
        type=int,
        default=None,
        help="CPU threads of torch (default: torch's; 1 on a machine other jobs share: spinning threads that wait "
        "for a core made a 2-thread step 30x slower than a 1-thread one on the shared 2-core machine)",
    )
    p.add_argument("--cache-only", action="store_true", help="build OUT/cache_<split>.npz and stop")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("-o", "--output", default="out/train", help="output folder (default out/train)")


def run(args: argparse.Namespace) -> int:
    """Runs ``mmusv train``; returns the exit status."""
    from mmusv.export.splits import parse_ratios

    _torch()
    from mmusv.learn.cache import build_cache
    from mmusv.learn.example import MODES
    from mmusv.learn.presets import preset
    from mmusv.learn.train import plot_losses, train

    modes = [m.strip() for m in args.modes.split(",") if m.strip()]
    bad = [m for m in modes if m not in MODES]
    if bad or not modes:
        raise InputError(f"--modes {args.modes}: unknown {bad}; allowed: {', '.join(MODES)}")
    out = Path(args.output)
    inputs: list[Any] = list(args.inputs)
    if args.generate is not None:
        if inputs or args.opv2v:
            raise InputError("--generate makes its own recordings: give no recordings and no --opv2v with it")
        from mmusv.studies.detection.sources import generate_dataset

        inputs = generate_dataset(out / "dataset", spec=args.generate)
    if not inputs and args.opv2v is None:
        raise InputError("no dataset: give recordings, --opv2v or --generate")
    cache = out / f"cache_{args.split}.npz"
    t0 = time.perf_counter()
    if not cache.is_file():
        build_cache(
            inputs, cache, opv2v=args.opv2v, split=args.split, ratios=parse_ratios(args.split_ratios), seed=args.seed
        )
        print(f"cache: {cache} ({cache.stat().st_size / 2**20:.1f} MiB, {time.perf_counter() - t0:.1f} s)", flush=True)
    if args.cache_only:
        return 0
    if args.threads is not None:
        if args.threads < 1:
            raise InputError(f"--threads {args.threads}: must be >= 1")
        import torch

        torch.set_num_threads(args.threads)
    p = preset(args.preset)
    summary: dict[str, Any] = {"preset": p.to_dict(), "seed": args.seed, "models": {}}
    for mode in modes:
        r = train(
            cache,
            p=p,
            mode=mode,
            out=out / mode,
            seed=args.seed,
            epochs=args.epochs,
            time_limit_s=args.time_limit,
            device=args.device,
            workers=args.workers,
            progress=not args.no_progress,
        )
        png = plot_losses(out / mode / "log.jsonl", out / mode / "loss.png")
        summary["models"][mode] = {
            "epochs": r.epochs,
            "steps": r.steps,
            "seconds": round(r.seconds, 1),
            "finished": r.finished,
        }
        print(
            f"{mode}: {r.epochs} epochs, {r.steps} steps, {r.seconds:.1f} s of training -> {r.out} ({png.name})",
            flush=True,
        )
    (out / "train_summary.json").write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    print(f"total {time.perf_counter() - t0:.1f} s; score with: mmusv study detection --model {out} ...", flush=True)
    return 0
