"""The command-line faces of the batch runner: the batch options of ``mmusv run`` (:func:`add_run_options`,
:func:`run_batch`) and ``mmusv dataset SPEC -o DIR`` (:func:`add_dataset_parser`, :func:`run_dataset`).

Both show a rich progress bar over the frames of the whole batch (on a terminal), then the table of every
scenario (done, skipped, failed with its error, retried) and one summary line; the exit status is 1 when a
scenario failed or the index could not be written (a full disk: the warning says why). Bad options raise
:class:`mmusv.errors.MmusvError` (one line, exit status 2).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mmusv.errors import ConfigError
from mmusv.text import counted

if TYPE_CHECKING:
    from rich.console import Console

    from mmusv.batch.runner import BatchReport

__all__ = [
    "add_dataset_parser",
    "add_run_options",
    "check_batch_options",
    "print_report",
    "run_batch",
    "run_dataset",
    "uses_batch",
]


def _batch_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--ray",
        nargs="?",
        const="local",
        default=None,
        metavar="ADDRESS",
        help="run every scenario as a Ray task: no ADDRESS starts a local Ray instance, 'auto' or HOST:PORT joins "
        "a cluster (the output folder must be on storage every node sees); needs pip install 'mmusv[ray]'",
    )
    p.add_argument(
        "--cpus-per-task",
        type=int,
        default=None,
        metavar="N",
        help="CPUs (= core threads, RAYON_NUM_THREADS) per task (default: 1 on Ray, the CPUs shared between --jobs)",
    )
    p.add_argument(
        "--retries", type=int, default=0, metavar="N", help="run a failed task up to N more times (default 0)"
    )
    p.add_argument(
        "--stop-on-full-disk",
        action="store_true",
        help="stop the batch when a recording fails because the disk is full (default: mark it failed, go on)",
    )
    p.add_argument(
        "--split-frames",
        type=int,
        default=None,
        metavar="N",
        help="record scenarios longer than N frames as parts of N frames, one task each, tied by <name>.parts.json",
    )


def add_run_options(run: argparse.ArgumentParser) -> None:
    """Adds the batch options (``--ray``, ``--cpus-per-task``, ``--retries``, ``--split-frames``) to ``run``."""
    _batch_options(run)


def uses_batch(args: argparse.Namespace) -> bool:
    """Whether a ``mmusv run FILE`` asks for the batch runner (then it runs as a batch of one)."""
    return args.ray is not None or args.retries or args.split_frames is not None or args.cpus_per_task is not None


def _console() -> Console:
    from mmusv.cli_console import rich_console

    return rich_console()


@contextmanager
def _bar(console: Console, title: str) -> Iterator[Callable[[str, int, int], None]]:
    """A progress callback ``(stage, done, total)``: one bar per stage on a terminal, nothing otherwise."""
    if not console.is_terminal:
        yield lambda stage, done, total: None
        return
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(
        TextColumn(f"[bold]{title}" + " {task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=console,
    ) as bar:
        tasks: dict[str, Any] = {}

        def update(stage: str, done: int, total: int) -> None:
            if stage not in tasks:
                tasks[stage] = bar.add_task(stage, total=total)
            bar.update(tasks[stage], completed=done, total=total)

        yield update


@contextmanager
def _resume_hint(args: argparse.Namespace) -> Iterator[None]:
    """On Ctrl-C: one line saying that the same command finishes the run."""
    try:
        yield
    except KeyboardInterrupt:
        print(
            "mmusv: stopped; complete recordings are kept, run the same command again to record the rest",
            file=sys.stderr,
        )
        raise


def print_report(report: BatchReport, console: Console) -> None:
    """The table of a batch run, its warnings and the summary line."""
    from rich.table import Table
    from rich.text import Text

    table = Table(
        title=f"mmusv run: {counted(len(report.outcomes), 'scenario')} on {report.backend} -> {report.out_dir}"
    )
    for col in ("scenario", "status", "frames", "parts", "retried", "result"):
        table.add_column(col, overflow="fold", justify="right" if col in ("frames", "parts", "retried") else "left")
    colour = {"done": "green", "skipped": "cyan", "failed": "red"}

    def where(path: Path | None) -> str:
        return "" if path is None else str(path.relative_to(report.out_dir))

    for o in report.outcomes:
        if o.status == "failed":
            result = o.error or ""
        elif o.status == "skipped":
            result = f"complete, same config hash: {where(o.recording)}"
        else:
            result = f"{counted(o.frames, 'frame')} in {o.seconds:.1f} s -> {where(o.recording)}"
        table.add_row(
            o.file.name,
            Text(o.status, style=colour[o.status]),
            f"{o.frames}/{o.frames_requested}",
            str(o.parts),
            str(o.retried),
            result,
        )
    console.print(table)
    for o in report.outcomes:
        for w in o.warnings:
            console.print(f"mmusv: warning: {w}", markup=False, highlight=False)
    if report.index_error is not None:
        console.print(f"mmusv: warning: {report.index_error}", markup=False, highlight=False)
    if report.kept:
        console.print(
            f"mmusv: note: {report.index.name} keeps listing {counted(len(report.kept), 'recording')} of an earlier "
            f"run that this run does not record: {', '.join(report.kept)}",
            markup=False,
            highlight=False,
        )
    index = (
        f"index {report.index}"
        if report.index_error is None
        else f"no index written to {report.index} (one there from an earlier run is out of date)"
    )
    console.print(f"{report.summary()} in {report.seconds:.1f} s; {index}")


MAX_RETRIES = 100
"""``--retries`` at most: a task that keeps failing is run at most this many more times (10**20 was accepted)."""

JOBS_PER_CPU = 4
"""``--jobs`` of a local pool at most: this many processes per CPU of the machine."""


def check_batch_options(args: argparse.Namespace) -> None:
    """The batch options (``--jobs``, ``--retries``, ``--split-frames``, ``--cpus-per-task``, ``--ray``) checked
    before anything is generated or recorded: ``mmusv dataset`` refused them only after writing the scenario set.
    On a local pool ``--jobs`` and ``--cpus-per-task`` are bounded by this machine's CPUs: ``--jobs 10**11`` was
    a multiprocessing traceback, ``--cpus-per-task 100000`` as many core threads per process, a hang."""
    from mmusv.batch.executors import available_cpus

    if not 0 <= args.retries <= MAX_RETRIES:
        raise ConfigError(f"--retries {args.retries}: must be in 0..{MAX_RETRIES} (more runs of a task per failure)")
    if args.split_frames is not None and args.split_frames < 1:
        raise ConfigError(f"--split-frames {args.split_frames}: must be at least 1 frame per part")
    if args.cpus_per_task is not None and args.cpus_per_task < 1:
        raise ConfigError(f"--cpus-per-task {args.cpus_per_task}: must be at least 1")
    if args.ray is not None:  # the cluster's CPUs: the Ray executor checks --cpus-per-task against them
        if not args.ray.strip():  # --ray "$ADDRESS" with the variable unset started a local instance without a word
            raise ConfigError(
                f"--ray {args.ray!r}: an empty address; give HOST:PORT or 'auto' to join a cluster, or --ray without "
                "an address for a local instance"
            )
        _check_ray_address(args.ray)
        return
    cpus = available_cpus()
    if args.jobs > JOBS_PER_CPU * cpus:
        raise ConfigError(
            f"--jobs {args.jobs}: must be in 1..{JOBS_PER_CPU * cpus} ({JOBS_PER_CPU} processes per CPU at most; "
            f"this machine has {cpus})"
        )
    if args.cpus_per_task is not None and args.cpus_per_task > cpus:
        raise ConfigError(
            f"--cpus-per-task {args.cpus_per_task}: must be in 1..{cpus} (the CPUs of this machine; --ray for more)"
        )


def _check_ray_address(address: str) -> None:
    """``--ray HOST:PORT`` (or ``ray://HOST:PORT``) reachable: Ray itself retried an address where nothing listens
    for minutes, without a word on the console. Other forms (``local``, ``auto``) are left to Ray."""
    import socket

    from mmusv.errors import IoError

    hostport = address.removeprefix("ray://")
    host, sep, port = hostport.rpartition(":")
    if not sep or not host or not port.isdigit():
        return
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=5):
            pass
    except (OSError, OverflowError, UnicodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc) or type(exc).__name__
        raise IoError(
            f"--ray {address}: nothing answers at {host} port {port} ({reason}); give the address of a running Ray "
            "head (HOST:PORT), 'auto' for the cluster this machine is part of, or no ADDRESS for a local instance"
        ) from None


def run_batch(args: argparse.Namespace, source: Path | list[Path]) -> int:
    """``mmusv run DIR`` (or a file with batch options): runs the batch, prints the table; 1 if a scenario failed
    or the index could not be written."""
    from mmusv.batch.runner import run_many

    check_batch_options(args)
    _check_file_names(source)

    console = _console()
    with _bar(console, "mmusv run") as update, _resume_hint(args):
        report = run_many(
            source,
            out_dir=args.output,
            jobs=int(args.jobs),
            ray=args.ray if args.ray is not None else False,
            cpus_per_task=args.cpus_per_task,
            retries=int(args.retries),
            split_frames=args.split_frames,
            frames=args.frames,
            overwrite=args.overwrite,
            checks=not args.no_checks,
            progress=lambda done, total: update("frames", done, total),
            stop_on_full_disk=args.stop_on_full_disk,
        )
    print_report(report, console)
    return 0 if report.ok and report.index_error is None else 1  # an index that could not be written: not done


def _check_file_names(source: Path | list[Path]) -> None:
    """Every scenario file of a folder named in UTF-8, checked before any recording: a file whose name holds
    other bytes (``x\\xe9.yaml``, from a Latin-1 system) was recorded, then the batch ended in a
    UnicodeEncodeError traceback writing ``dataset.json``, whose names must be UTF-8."""
    if not isinstance(source, Path) or not source.is_dir():
        return
    from mmusv.arguments import shown
    from mmusv.batch.plan import scenario_files

    for f in scenario_files(source):  # the files the batch runs
        try:
            f.name.encode("utf-8")
        except UnicodeEncodeError:
            raise ConfigError(
                f"{source}: the scenario file {shown(f.name)} has a name that is not UTF-8 (the batch index "
                "dataset.json names every file); rename it"
            ) from None


def add_dataset_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Adds ``dataset`` to the ``mmusv`` sub-parsers."""
    p: argparse.ArgumentParser = subparsers.add_parser(
        "dataset",
        help="generate a spec, record every scenario, convert to OPV2V and index it (dataset.json), restartable",
        description="Generates SPEC into DIR/scenarios, records every scenario into DIR/recordings (local pool or "
        "Ray), converts the complete recordings to OPV2V into DIR/opv2v and writes DIR/dataset.json. Run the "
        "same command again to finish an interrupted or partly failed dataset: what is complete is skipped.",
    )
    p.add_argument("spec", help="generation spec YAML (or a bundled spec name, e.g. coop_detection)")
    p.add_argument("-o", "--output", required=True, help="dataset folder")
    p.add_argument("--jobs", type=int, default=1, help="local pool processes (default 1); ignored with --ray")
    p.add_argument("--no-checks", action="store_true", help="skip the route checks when recording")
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="record every scenario again, replacing what DIR/recordings holds for it (a re-run without it "
        "records only what is missing, and again what a changed spec changed)",
    )
    _batch_options(p)
    return p


def run_dataset(args: argparse.Namespace) -> int:
    """Runs ``mmusv dataset``; 0 when every quota of the spec was met and every scenario was recorded and converted,
    1 otherwise (a quota not met: as ``mmusv generate``, which exits 1 then)."""
    from mmusv.batch.dataset import build_dataset
    from mmusv.cli_paths import check_output_folder, path_arg

    path_arg(args.spec, flag="spec")
    check_output_folder(args.output)  # an empty -o wrote the dataset into the current folder
    if args.jobs < 1:
        raise ConfigError(f"--jobs {args.jobs}: must be at least 1")
    check_batch_options(args)
    console = _console()
    with _bar(console, "mmusv dataset") as update, _resume_hint(args):
        rep = build_dataset(
            args.spec,
            out_dir=args.output,
            jobs=args.jobs,
            ray=args.ray if args.ray is not None else False,
            cpus_per_task=args.cpus_per_task,
            retries=args.retries,
            split_frames=args.split_frames,
            checks=not args.no_checks,
            progress=update,
            stop_on_full_disk=args.stop_on_full_disk,
            overwrite=getattr(args, "overwrite", False),
        )
    console.print(
        f"scenarios: {'generated' if rep.generated else 'kept (same spec)'} in {rep.out_dir / 'scenarios'}"
        + (f"; quota not met: {', '.join(rep.shortfall)}" if rep.shortfall else "")
    )
    if rep.removed:  # an edited spec: the recordings of the scenarios it no longer makes are gone, said so
        console.print(
            f"recordings: removed those of {counted(len(rep.removed), 'scenario')} the spec no longer makes "
            f"({', '.join(rep.removed)}) from {rep.out_dir / 'recordings'}",
            markup=False,
            highlight=False,
        )
    print_report(rep.batch, console)
    if rep.converted == 0:
        console.print("opv2v: nothing to convert (no complete recording)")
    else:
        console.print(
            f"opv2v: {counted(rep.converted, 'frame')} converted into {rep.opv2v}"
            if rep.converted is not None
            else f"opv2v: {rep.opv2v} is up to date"
        )
    return 0 if rep.ok and not rep.shortfall else 1
