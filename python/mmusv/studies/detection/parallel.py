"""The detection and robustness studies over several processes (``--jobs N``): one task per sequence.

Each task loads its sequence, takes the detector its process built from a :class:`DetectorSpec` (the baseline, a
``package.module:function``, a learned model's folder, or a predictions Parquet: what can be named, so nothing large
is pickled; built at the process's first task) and runs :func:`~mmusv.studies.detection.study.run_study` on it
alone; the parent merges the results in sequence order (:meth:`~mmusv.studies.detection.study.StudyResult.merge`).
Every sequence is scored exactly as in one process: the detections of a cloud depend on that cloud only, the pose
noise is drawn per (seed, sequence, frame, ego, neighbour, setting), and AP sorts all detections of the merged result
once. So the tables and the boxes Parquet are the same, byte for byte, with any number of jobs (tested).

Workers are started with ``spawn`` (a clean interpreter: safe after torch has started its threads, and the same on
every platform); with a learned model each sets torch to ``threads`` CPU threads (1 by default: ``jobs`` processes
share the cores). Each task runs in the :func:`mmusv.text.command_line` block of its caller (:func:`mmusv.text.flags`,
passed with it), so that a worker's messages name what the caller's do: ``--detector ...`` and ``--predictions ...``
from ``mmusv study``, ``spec = ...`` and ``path = ...`` from Python.
"""

from __future__ import annotations

import multiprocessing
import signal
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, replace
from typing import Any

from mmusv import arguments
from mmusv.batch.executors import refuse_in_daemon, stop_pool, workers_skip_unimportable_main
from mmusv.errors import InputError, MmusvError
from mmusv.held_signals import raise_noted_stop
from mmusv.studies.detection.sources import Dataset
from mmusv.studies.detection.study import StudyOptions, StudyResult, check_predictions_used, run_study
from mmusv.text import command_line, flags, given, named

__all__ = ["DetectorSpec", "run_study_jobs"]


@dataclass(frozen=True)
class DetectorSpec:
    """What a task builds its detector from: ``detector`` (``"baseline"`` or ``package.module:function``), or
    ``model`` (a learned model's path, with its ``refine`` / ``rescore`` switches and torch ``threads``), or
    ``predictions`` (a predictions Parquet)."""

    detector: str = "baseline"
    model: str | None = None
    refine: bool | None = None
    rescore: bool | None = None
    threads: int = 1
    predictions: str | None = None
    modes: tuple[str, ...] | None = None
    """The study's fusion modes, whose models are loaded (``None``: every model at ``model``)."""

    def build(self) -> tuple[Any, Any]:
        """``(detector, predictions)`` for :class:`~mmusv.studies.detection.study.StudyOptions`."""
        if self.predictions is not None:
            from mmusv.studies.detection.predictions import load_predictions

            return None, load_predictions(self.predictions)
        if self.model is not None:
            import torch

            from mmusv.learn.cli import load_for_study

            torch.set_num_threads(self.threads)
            return load_for_study(self.model, refine=self.refine, rescore=self.rescore, modes=self.modes), None
        from mmusv.studies.detection.detector import load_detector

        return load_detector(self.detector), None


_BUILT: dict[DetectorSpec, tuple[Any, Any]] = {}
"""In a worker process: the detector and predictions each spec built, once per process (a model loaded, a Parquet
read), for every sequence the process is given, as the one process of ``--jobs 1`` does."""


def _task(
    dataset: Dataset, name: str, options: StudyOptions, spec: DetectorSpec, said: dict[str, str]
) -> tuple[str, Any, list[int]]:
    """One sequence's study: ``("ok", StudyResult, shared bytes)`` or ``("error", message, [])`` for bad input
    (re-raised in the parent as :class:`~mmusv.errors.InputError`, whose own class need not pickle). ``said``: the
    flags of the caller's :func:`mmusv.text.command_line` block, which a worker process does not inherit."""
    with command_line(said):
        return _run_task(dataset, name, options, spec)


def _run_task(dataset: Dataset, name: str, options: StudyOptions, spec: DetectorSpec) -> tuple[str, Any, list[int]]:
    try:
        if spec not in _BUILT:
            _BUILT[spec] = spec.build()
        detector, predictions = _BUILT[spec]
        shared = getattr(detector, "shared_bytes", None)
        before = len(shared) if shared is not None else 0
        opts = replace(options, detector=detector, predictions=predictions)
        res = run_study([dataset.load(name)], options=opts, check_predictions=False)
        return "ok", res, list(shared[before:]) if shared is not None else []
    except MmusvError as exc:
        return "error", str(exc), []


def run_study_jobs(
    dataset: Dataset,
    *,
    options: StudyOptions,
    spec: DetectorSpec,
    jobs: int,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[StudyResult, list[int]]:
    """The study of every sequence of ``dataset`` on ``jobs`` processes (module docstring): the merged
    :class:`~mmusv.studies.detection.study.StudyResult` and, for a learned model, the bytes its intermediate
    fusion shared per call (in sequence order). ``options``' detector and predictions are ignored: each task
    builds them from ``spec``. ``progress(done, total)`` counts frames, a sequence at a time."""
    jobs = arguments.whole(jobs, name=named("jobs"), lo=1, error=InputError)  # "2" was a TypeError of <
    refuse_in_daemon(f"the detection study with {given('jobs', jobs)}")  # the batch's rules for spawned workers
    names = sorted(dataset.sources)
    frames = dataset.frames_by_sequence()
    total = sum(frames.values())
    bare = replace(options, detector=None, predictions=None)
    parts: dict[str, StudyResult] = {}
    shared: dict[str, list[int]] = {}
    done = 0
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=min(jobs, max(1, len(names))), mp_context=ctx) as pool:
        with workers_skip_unimportable_main():  # the submissions start the workers
            pending: dict[Future[tuple[str, Any, list[int]]], str] = {
                pool.submit(_task, dataset, n, bare, spec, flags()): n for n in names
            }
        try:
            while pending:
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                raise_noted_stop()  # a stop whose KeyboardInterrupt a library swallowed (held_signals)
                for fut in finished:
                    name = pending.pop(fut)
                    status, value, nbytes = fut.result()
                    if status == "error":
                        raise InputError(value)
                    parts[name], shared[name] = value, nbytes
                    done += frames.get(name, 0)
                    if progress is not None:
                        progress(done, total)
        except BaseException:  # a stop, or a sequence's error: the pool's exit waited for every sequence submitted
            # (a stop of --jobs 1 over six sequences ran all six); the jobs write nothing, their results are dropped
            stop_pool(pool, signum=signal.SIGTERM, grace_s=5.0)
            raise
    res = StudyResult.merge(options, [parts[n] for n in names])
    check_predictions_used(res)
    return res, [b for n in names for b in shared[n]]
