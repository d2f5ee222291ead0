"""``mmusv train``: builds the tensor cache of a detection dataset's training split (:mod:`mmusv.learn.cache`)
and trains the single-agent, early- and intermediate-fusion models of a preset (:mod:`mmusv.learn.train`), each
into ``OUT/<mode>/`` with its checkpoint, log and loss plot (``loss.png``); started again, it resumes. After each
model's training, in the same process, it fits that model's IoU scorer (:mod:`mmusv.learn.scorer`) on the same
training cache, into ``OUT/<mode>/scorer.pt`` (``--no-scorers`` leaves them out, ``--scorers-only`` fits them for
models already trained).
``mmusv study detection|robustness --model OUT`` then scores them (:func:`load_for_study`).

On a CPU the models train side by side, each in a process of its own (``--jobs``, by default one per model), with
the cores shared out among them as torch threads (``--threads``, by default the cores over the jobs, at least
one): a small network keeps one core busy far better than it keeps two, so three one-thread processes on two cores
finish well before three models trained in turn. On a GPU they train in turn.
A model trained in a process of its own with one thread has the same weights as one trained in turn with one
thread (CPU training is deterministic for a given thread count).

Without the ``learn`` extra (PyTorch) both raise :class:`mmusv.errors.InputError` saying how to install it.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import signal
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from mmusv.errors import InputError
from mmusv.held_signals import raise_noted_stop
from mmusv.jsonio import read_json_or_none
from mmusv.learn.modes import MODELS, models_for
from mmusv.learn.scorer_fit import fit_scorers
from mmusv.text import command_line, counted

__all__ = ["add_parser", "load_for_study", "run"]

_NAMES = {"cache": "cache", "path": "model", "mode": "--modes", "out": "-o"}
"""How ``mmusv train``'s messages name what the API's name ``cache``, ``path``, ``mode`` and ``out``: the cache and
the models it writes under ``-o`` (``cache OUT/cache_train.npz: ...``), the ``--modes`` it was given, its ``-o``
(:func:`mmusv.text.command_line`)."""

_INSTALL = "needs the learn extra (PyTorch): pip install 'mmusv[learn]' (or pip install torch tqdm)"


def _torch() -> None:
    try:
        import torch  # noqa: F401
        import tqdm  # noqa: F401
    except ImportError:
        raise InputError(f"mmusv.learn {_INSTALL}") from None


def load_for_study(
    path: str,
    *,
    refine: bool | None = None,
    rescore: bool | None = None,
    modes: Sequence[str] | None = None,
) -> Any:
    """The :class:`~mmusv.learn.detector.LearnedDetector` at ``path`` (``--model``); ``refine``: the geometric
    second stage on or off, ``rescore``: the IoU scorers on or off (``None``: the defaults of
    :func:`~mmusv.learn.detector.load_models`); ``modes``: the study's fusion modes (``none``, ``late``, ``early``,
    ``intermediate``) to load the models of (``None``: every model there). ``--modes none,late`` read the early
    and intermediate models too: one damaged, or of another version, stopped a study that does not run it."""
    _torch()
    from mmusv.learn.detector import load_models

    models = None if modes is None else models_for(modes)
    # the messages name the flags of mmusv study (--model, not load_models' path)
    with command_line({"path": "--model", "refine": "--refine on", "rescore": "--rescore on"}):
        return load_models(path, refine=refine, rescore=rescore, models=models)


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
    p.add_argument("--modes", default="single,early,intermediate", help="models to train")
    p.add_argument(
        "--jobs",
        default="auto",
        help="models trained at once, each in a process of its own (default auto: on a CPU one per model, sharing "
        "the cores; on a GPU 1, in turn)",
    )
    p.add_argument("--epochs", type=int, default=None, help="epochs per model, at least 1 (default: the preset's)")
    p.add_argument("--time-limit", type=float, default=None, help="seconds per model at most, > 0 (default: no limit)")
    p.add_argument("--workers", type=int, default=0, help="data-loader worker processes, 0 or more (default 0)")
    p.add_argument("--device", default=None, help="cpu, cuda, cuda:N or mps (default: cuda when available, else cpu)")
    p.add_argument(
        "--threads",
        type=int,
        default=None,
        help="CPU threads of torch per model (default: the cores over the jobs, at least 1; with one job, torch's "
        "own default). 1 on a machine other jobs share: spinning threads that wait for a core made a 2-thread step "
        "30x slower than a 1-thread one on the shared 2-core machine",
    )
    p.add_argument("--cache-only", action="store_true", help="build OUT/cache_<split>.npz and stop")
    p.add_argument(
        "--no-scorers",
        action="store_true",
        help="do not fit the IoU scorers (mmusv.learn.scorer) of the trained models after training",
    )
    p.add_argument(
        "--scorers-only",
        action="store_true",
        help="fit the IoU scorers of the models already trained in OUT (and nothing else)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("-o", "--output", default="out/train", help="output folder (default out/train)")


def run(args: argparse.Namespace) -> int:
    """Runs ``mmusv train``; returns the exit status. The dataset's messages name its flags
    (:data:`mmusv.studies.detection.cli.DATASET_FLAGS`: ``--opv2v x: not a folder``, not ``opv2v = 'x'``)."""
    from mmusv.studies.detection.cli import DATASET_FLAGS

    with command_line(DATASET_FLAGS), contextlib.ExitStack() as stack:
        return _run(args, stack)


def _run(args: argparse.Namespace, stack: contextlib.ExitStack) -> int:
    from mmusv.cli_paths import check_output_folder, made_output_folder, path_arg

    _check_numbers(args)
    check_output_folder(args.output)  # an empty -o wrote the cache and the models into the current folder
    for item in args.inputs:
        path_arg(item, flag="recording")
    if args.opv2v is not None:
        path_arg(args.opv2v, flag="--opv2v")
    ratios = split_ratios(args.split_ratios)
    from mmusv.studies.detection.data import check_split

    # before --generate, which refused a bad --split or --seed only after generating and recording the whole dataset
    check_split(args.split, args.seed if args.opv2v is None else 0)
    _torch()
    _check_device(args.device)
    from mmusv.jsonio import write_bytes_atomic
    from mmusv.learn.cache import build_cache
    from mmusv.learn.presets import preset

    modes = [m.strip() for m in args.modes.split(",") if m.strip()]
    bad = [m for m in modes if m not in MODELS]
    if bad or not modes:
        what = f"unknown {', '.join(bad)}" if bad else "no model named"
        raise InputError(f"--modes {args.modes!r}: {what}; allowed: {', '.join(MODELS)}")
    twice = sorted({m for m in modes if modes.count(m) > 1})
    if twice:  # side by side, two processes trained the same model into the same folder at once
        raise InputError(f"--modes {args.modes!r}: {', '.join(twice)} given twice; each model once")
    jobs = _jobs(args.jobs, len(modes), args.device)
    out = Path(args.output)
    if args.scorers_only and args.no_scorers:
        raise InputError("--scorers-only and --no-scorers: give one")
    if args.scorers_only and args.cache_only:  # --cache-only was ignored: the scorers were fitted (minutes)
        raise InputError("--scorers-only and --cache-only: give one")
    # made, or named when it cannot be ("/x: Permission denied" named no -o), before the work; removed again if still
    # empty when the run fails or is interrupted
    _check_in_the_way(out, args.split, modes)
    stack.enter_context(made_output_folder(args.output))
    if args.scorers_only:
        cache_file = out / f"cache_{args.split}.npz"
        if not cache_file.is_file():
            raise InputError(f"--scorers-only: no {cache_file}; train first (mmusv train ... -o {out})")
        with command_line({**_NAMES, "out": "--scorers-only -o"}):
            fits = fit_scorers(out, cache_file, modes, seed=args.seed, threads=args.threads)
        _record_scorers(out / "train_summary.json", fits)
        return 0
    inputs: list[Any] = list(args.inputs)
    if args.generate is not None:
        if inputs or args.opv2v:
            raise InputError("--generate makes its own recordings: give no recordings and no --opv2v with it")
        from mmusv.studies.detection.sources import generate_dataset

        shortfalls: list[str] = []
        with command_line({"spec": "--generate"}):
            inputs = generate_dataset(out / "dataset", spec=args.generate, shortfall=shortfalls.append)
        if shortfalls:  # said by mmusv study detection --generate; training went on without a word
            print(f"generate: quotas not met: {shortfalls[0]}", file=sys.stderr, flush=True)
            for line in shortfalls[1:]:
                print(f"generate: {line}", file=sys.stderr, flush=True)
    if not inputs and args.opv2v is None:
        raise InputError("no dataset: give recordings, --opv2v or --generate")
    cache = out / f"cache_{args.split}.npz"
    t0 = time.perf_counter()
    if cache.is_file():
        _check_cache(cache, inputs, opv2v=args.opv2v, split=args.split, ratios=ratios, seed=args.seed)
    else:
        build_cache(inputs, cache, opv2v=args.opv2v, split=args.split, ratios=ratios, seed=args.seed)
        print(f"cache: {cache} ({cache.stat().st_size / 2**20:.1f} MiB, {time.perf_counter() - t0:.1f} s)", flush=True)
    if args.cache_only:
        return 0
    threads = args.threads
    if threads is None and jobs > 1:
        threads = max(1, (os.cpu_count() or 1) // jobs)
    p = preset(args.preset)
    from mmusv.learn.cache import cache_identity

    identity = cache_identity(cache)
    _check_same_run(out, modes, p=p, seed=args.seed, identity=identity)
    summary = _summary_to_keep(out / "train_summary.json", modes, p=p.to_dict(), seed=args.seed, jobs=jobs)
    task = {
        "cache": str(cache),
        "preset": args.preset,
        "seed": args.seed,
        "epochs": args.epochs,
        "time_limit": args.time_limit,
        "device": args.device,
        "workers": args.workers,
        "threads": threads,
        "progress": not args.no_progress and jobs == 1,
        "scorer": not args.no_scorers,
    }
    # A model that fails side by side does not stop the others: each failure is reported, the summary holds the
    # models that finished, and the first failure is raised after them (as training in turn would raise it).
    finished: list[tuple[str, dict[str, Any]]] = []
    failures: list[BaseException] = []
    if jobs == 1:
        finished = [(mode, _train_one({**task, "mode": mode, "out": str(out / mode)})) for mode in modes]
    else:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor, as_completed

        from mmusv.batch.executors import stop_pool

        print(
            f"training {', '.join(modes)} side by side: {counted(jobs, 'process', plural='processes')}, "
            f"{counted(threads, 'torch thread')} each",
            flush=True,
        )
        ctx = multiprocessing.get_context("spawn")  # a fresh interpreter per model: no forked torch thread pools
        done: dict[str, dict[str, Any]] = {}
        with ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool:
            futures = {pool.submit(_train_one, {**task, "mode": mode, "out": str(out / mode)}): mode for mode in modes}
            try:
                for f in as_completed(futures):
                    raise_noted_stop()  # a stop whose KeyboardInterrupt a library swallowed (held_signals)
                    try:
                        done[futures[f]] = f.result()
                    except Exception as e:  # reported here, the first one raised after the others
                        failures.append(e)
                        print(f"{futures[f]}: failed: {e}", file=sys.stderr, flush=True)
            except BaseException:  # Ctrl-C, a kill: the models stop too (leaving the pool waited for them, hours)
                # each running model gets SIGINT and stops as Ctrl-C stops one trained in turn (its last.pt and
                # model.pt whole, as saved last), killed if not stopped within 10 s
                stop_pool(pool, signum=signal.SIGINT, grace_s=10.0)
                raise
        finished = [(mode, done[mode]) for mode in modes if mode in done]
    for mode, r in finished:
        summary["models"][mode] = {k: r[k] for k in ("epochs", "steps", "seconds", "finished", "stopped")}
        short = ""
        if r["stopped"] == "time limit":  # the line read as a run that went through
            short = (
                f" (stopped at --time-limit {args.time_limit:g} s, "
                f"{r['epochs']} of {counted(r['planned'], 'epoch')} done; "
                "started again with a higher limit, it goes on)"
            )
        print(
            f"{mode}: {counted(r['epochs'], 'epoch')}, {counted(r['steps'], 'step')}, "
            f"{r['seconds']:.1f} s of training -> {r['out']} "
            f"({r['plot']}){short}",
            flush=True,
        )
        if "scorer" in r:
            summary.setdefault("scorers", {})[mode] = r["scorer"]
    for key in ("models", "scorers"):  # in the order of MODELS, the kept ones and this run's together
        if key in summary:
            summary[key] = {m: summary[key][m] for m in MODELS if m in summary[key]}
    # whole or not at all (a Ctrl-C while writing it)
    write_bytes_atomic(out / "train_summary.json", (json.dumps(summary, indent=2) + "\n").encode("utf-8"))
    if failures:
        raise failures[0]
    print(f"total {time.perf_counter() - t0:.1f} s; score with: mmusv study detection --model {out} ...", flush=True)
    return 0


def _check_same_run(out: Path, modes: list[str], *, p: Any, seed: int, identity: dict[str, Any] | None) -> None:
    """Refuses, before any model trains, a run into an ``-o`` holding a checkpoint of another run (another preset,
    seed or data) for any model, the ones this run trains or not: the models of one ``-o`` are scored together
    (:func:`load_for_study`). Refused only where every model would refuse, the others trained: a ``--preset cpu``
    run into a folder of ``tiny`` models left ``single`` of one preset beside ``early`` of the other, and the
    summary named only the new ones; and refused in each model's process, each printed its refusal and the summary
    was replaced by one of no model."""
    from mmusv.learn.resume import resumable_checkpoint

    for mode in [*modes, *(m for m in MODELS if m not in modes)]:
        try:
            resumable_checkpoint(out / mode, p=p, mode=mode, seed=seed, identity=identity)
        except InputError as exc:
            others = [m for m in modes if m != mode]
            if mode not in modes:
                hint = f" (the {mode} model there is scored with the ones this run trains)"
            elif others:
                hint = f", or leave {mode} out (--modes {','.join(others)})"
            else:
                hint = ""
            raise InputError(f"{exc}{hint}") from None


def _summary_to_keep(path: Path, modes: list[str], *, p: dict[str, Any], seed: int, jobs: int) -> dict[str, Any]:
    """The ``train_summary.json`` to write for a run training ``modes``: the earlier summary's entries for the other
    models there of the same preset and seed (``--modes early`` after ``--modes single`` replaced the summary with one
    naming ``early`` alone), less the entries this run writes again."""
    summary: dict[str, Any] = {"preset": p, "seed": seed, "jobs": jobs, "models": {}}
    before = read_json_or_none(path)
    if before is None or before.get("preset") != json.loads(json.dumps(p)) or before.get("seed") != seed:  # as read
        return summary
    for key in ("models", "scorers"):
        kept = before.get(key)
        if isinstance(kept, dict):
            # a model folder removed since is not named
            kept = {m: v for m, v in kept.items() if m not in modes and (path.parent / m / "model.pt").is_file()}
            if kept:
                summary[key] = kept
    return summary


_WRITTEN = ("model.pt", "last.pt", "log.jsonl", "loss.png", "scorer.pt", "scorer_skipped.json")
"""The files a model's folder ``OUT/<mode>/`` is written."""


def _check_in_the_way(out: Path, split: str, modes: list[str]) -> None:
    """Refuses, before the work, a folder (or another non-file) where ``mmusv train -o OUT`` writes a file
    (``OUT/train_summary.json``, the cache, a model's ``model.pt``, ...): each failed when written, naming a temporary
    file (``OUT/.train_summary.json.<pid>.tmp: Is a directory``), the summary after every model had trained. (A file
    where a model's folder goes fails that model alone, in its process, before it trains.)"""
    from mmusv.cli_paths import refuse_replacing

    names = [f"cache_{split}.npz", "train_summary.json", *(f"{m}/{n}" for m in modes for n in _WRITTEN)]
    refuse_replacing(out, names, overwrite=True)  # overwrite: the files are replaced (resumed); only others refused


def _record_scorers(path: Path, fits: dict[str, dict[str, Any]]) -> None:
    """``fits`` (what :func:`fit_scorers` measured, by model) in place of the ``scorers`` entries of the summary at
    ``path``, if there is one: ``--scorers-only`` left them as the training wrote them, so a summary went on saying
    why a model had no scorer (``skipped``) beside the ``scorer.pt`` fitted since, or gave another fit's ``beta``."""
    from mmusv.jsonio import write_bytes_atomic

    summary = read_json_or_none(path)
    if summary is None:
        return
    kept = summary.get("scorers")
    both = {**(kept if isinstance(kept, dict) else {}), **fits}
    summary["scorers"] = {m: both[m] for m in MODELS if m in both}  # in the order of MODELS, as training writes it
    write_bytes_atomic(path, (json.dumps(summary, indent=2) + "\n").encode("utf-8"))


def _check_cache(
    cache: Path, inputs: list[Any], *, opv2v: str | None, split: str, ratios: tuple[float, float, float], seed: int
) -> None:
    """Refuses ``cache`` (``OUT/cache_<split>.npz`` of an earlier run) when it was built from other data than
    ``inputs`` / ``opv2v`` give for ``split``: it was reused without a word, so the models trained again on the
    sequences of the first run (and a resumed model went on with them)."""
    import json
    import zipfile

    import numpy as np

    from mmusv.learn.cache import dataset_fingerprints, same_data
    from mmusv.studies.detection.sources import resolve_dataset

    try:
        with open(cache, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            meta = json.loads(str(z["meta"]))
    except (OSError, ValueError, KeyError, EOFError, TypeError, zipfile.BadZipFile) as exc:  # TypeError: a .npy
        raise InputError(
            f"{cache}: not a readable mmusv.learn cache ({type(exc).__name__}); remove it to build it again"
        ) from None
    ds = resolve_dataset(inputs, opv2v=opv2v, split=split, ratios=ratios, seed=seed)
    asked = {"sources": sorted(ds.sources), "fingerprints": dataset_fingerprints(ds)}
    if same_data(meta, asked):
        return
    old = meta.get("sources", [])
    what = (
        f"sequences {', '.join(old)}; asked for {', '.join(asked['sources'])}"
        if old != asked["sources"]
        else f"sequences of the same names recorded differently: {', '.join(old)}"
    )
    raise InputError(
        f"{cache}: built from other data (split {meta.get('split', split)!r}: {what}); use another -o, or remove "
        f"{cache} and the models beside it to start again"
    )


def _check_numbers(args: argparse.Namespace) -> None:
    """``--epochs``, ``--time-limit``, ``--workers`` and ``--seed`` checked before anything is built or written: a
    negative or NaN time limit stopped training after one step with a model that looked complete."""
    if args.epochs is not None and args.epochs < 1:
        raise InputError(f"--epochs {args.epochs}: must be >= 1 (or left out for the preset's)")
    if args.time_limit is not None and not (math.isfinite(args.time_limit) and args.time_limit > 0):
        raise InputError(f"--time-limit {args.time_limit}: seconds, a finite number > 0 (or left out for no limit)")
    if args.workers < 0:
        raise InputError(f"--workers {args.workers}: must be >= 0 (0: load data in the training process)")
    if not 0 <= args.seed < 2**63:  # -1 failed each model after the cache was built, a numpy traceback
        raise InputError(
            f"--seed {args.seed}: the seed of the split, the weights and the augmentation must be a whole number in "
            f"0..{2**63 - 1}"
        )
    from mmusv.batch.executors import available_cpus

    check_threads(args.threads)
    cpus = available_cpus()
    if args.workers > cpus:  # each a process: 10**11 of them froze the data loader
        raise InputError(f"--workers {args.workers}: must be in 0..{cpus} (the CPUs of this machine)")


def check_threads(threads: int | None) -> None:
    """``--threads`` (``None``: the default) in 1..the CPUs of this machine: ``10**11`` was a torch traceback and
    ``100000`` as many threads started (a crash on exit)."""
    from mmusv.batch.executors import available_cpus

    if threads is None:
        return
    cpus = available_cpus()
    if threads < 1:
        raise InputError(f"--threads {threads}: must be >= 1")
    if threads > cpus:
        raise InputError(f"--threads {threads}: must be at most {cpus} (the CPUs of this machine)")


def split_ratios(text: str) -> tuple[float, float, float]:
    """``--split-ratios`` (of ``mmusv train``, ``mmusv study`` and :mod:`mmusv.learn.replay`) as three fractions;
    its errors name the option as typed (``--split-ratios 1,2: ...``; they said "split", then "--split-ratios:
    split '1,2'"), where a Python caller of :func:`mmusv.export.splits.parse_ratios` reads its ``ratios``."""
    from mmusv.export.splits import parse_ratios

    with command_line({"ratios": "--split-ratios"}):
        return parse_ratios(text)


_DEVICES = "cpu, cuda, cuda:N or mps"


def _check_device(value: str | None) -> None:
    """``--device``: a torch device of this machine (``None``: the default of
    :func:`mmusv.learn.model.torch_device`)."""
    if value is None:
        return
    import torch

    try:
        dev = torch.device(value)
    except (RuntimeError, ValueError, TypeError):
        raise InputError(f"--device {value!r}: not a device; allowed: {_DEVICES}") from None
    if dev.type == "cpu":
        return
    if dev.type == "cuda":
        if not torch.cuda.is_available():
            raise InputError(f"--device {value!r}: CUDA is not available on this machine; use --device cpu")
        count = torch.cuda.device_count()
        if dev.index is not None and dev.index >= count:
            raise InputError(f"--device {value!r}: this machine has {count} CUDA device(s), cuda:0 to cuda:{count - 1}")
        return
    if dev.type == "mps":
        mps = getattr(torch.backends, "mps", None)
        if mps is None or not mps.is_available():
            raise InputError(f"--device {value!r}: MPS is not available on this machine; use --device cpu")
        return
    raise InputError(f"--device {value!r}: allowed: {_DEVICES}")


def _jobs(value: str, models: int, device: str | None) -> int:
    """``--jobs``: a positive count (at most ``models``), or ``auto`` (on a CPU ``models``; 1 on a GPU)."""
    if value == "auto":
        from mmusv.learn.model import torch_device

        return 1 if torch_device(device).type != "cpu" else max(1, models)
    try:
        n = int(value)
    except ValueError:
        raise InputError(f"--jobs {value}: a positive whole number or auto") from None
    if n < 1:
        raise InputError(f"--jobs {value}: must be >= 1 (or auto)")
    return min(n, models)


def _train_one(task: dict[str, Any]) -> dict[str, Any]:
    """Trains one model (``task``: the cache, preset name, mode, output folder and the run's options), plots
    its losses and, unless ``--no-scorers``, fits its IoU scorer; returns its epochs, steps, seconds, whether it
    finished, where it wrote and what the scorer's fit measured. Runs in this process or in a worker process of
    ``--jobs``: side by side, a model's scorer is fitted while the others still train, so the core a finished model
    leaves is not idle (the scorers took 6 min 40 s after the training in turn, on the 2-core Xeon)."""
    import torch

    if task["threads"] is not None:
        torch.set_num_threads(task["threads"])
    with command_line(_NAMES):  # also in a worker process of --jobs, which the caller's block does not reach
        return _train_and_fit(task)


def _train_and_fit(task: dict[str, Any]) -> dict[str, Any]:
    from mmusv.learn.plots import plot_losses
    from mmusv.learn.presets import preset
    from mmusv.learn.train import train

    out = Path(task["out"])
    r = train(
        task["cache"],
        p=preset(task["preset"]),
        mode=task["mode"],
        out=out,
        seed=task["seed"],
        epochs=task["epochs"],
        time_limit_s=task["time_limit"],
        device=task["device"],
        workers=task["workers"],
        progress=task["progress"],
    )
    png = plot_losses(out / "log.jsonl", out / "loss.png")
    done = {
        "epochs": r.epochs,
        "planned": task["epochs"] if task["epochs"] is not None else preset(task["preset"]).epochs,
        "steps": r.steps,
        "seconds": round(r.seconds, 1),
        "finished": r.finished,
        "stopped": r.stopped,
        "out": str(r.out),
        "plot": png.name,
    }
    if task["scorer"]:
        fits = fit_scorers(out.parent, Path(task["cache"]), [task["mode"]], seed=task["seed"], keep_current=True)
        done["scorer"] = fits[task["mode"]]
    return done
