"""``mmusv run``: one scenario in this process (a progress bar on a terminal, a one-line report), or a folder of
them, or one with the batch options, through :mod:`mmusv.batch.cli`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mmusv.cli_paths import check_output_folder, path_arg
from mmusv.errors import ConfigError, MmusvError
from mmusv.text import counted

__all__ = ["cmd_run"]


def _run_one(
    path: str,
    out: str,
    overwrite: bool,
    frames: int | None,
    show_progress: bool,
    checks: bool = True,
    profile: bool = False,
) -> str:
    """Runs one scenario for `mmusv run SCENARIO`; returns a one-line report (batches of scenarios run through
    :mod:`mmusv.batch.task` instead)."""
    from mmusv.acquire import run
    from mmusv.config import load_scenario

    scenario = load_scenario(path)
    notes: list[str] = []
    try:
        if show_progress:
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

            with Progress(
                TextColumn(f"[bold]{scenario.name}"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn()
            ) as bar:
                task = bar.add_task("frames", total=frames or scenario.acquisition.frames)
                try:
                    res = run(
                        path,
                        out_dir=out,
                        overwrite=overwrite,
                        frames=frames,
                        checks=checks,
                        profile=profile,
                        progress=lambda done, total: bar.update(task, completed=done),
                        notes=notes,
                    )
                except KeyboardInterrupt:
                    from mmusv.acquire import recording_path

                    rec = recording_path(Path(out), scenario)
                    print(
                        f"mmusv: interrupted; {rec} is a valid recording holding every completed frame",
                        file=sys.stderr,
                    )
                    raise
        else:
            res = run(
                path, out_dir=out, overwrite=overwrite, frames=frames, checks=checks, profile=profile, notes=notes
            )
    finally:
        for note in notes:  # e.g. an interrupted run found in the folder and recorded again
            print(f"mmusv: note: {note}", file=sys.stderr)
    fps = res.frames_written / res.seconds if res.seconds > 0 else float("nan")
    line = (
        f"{scenario.name}: {counted(res.frames_written, 'frame')} in {res.seconds:.1f} s "
        f"({fps:.2f} frames/s), "
        f"{res.messages} messages, {res.bytes / 1e6:.1f} MB -> {res.recording}"
    )
    return line if res.profile is None else f"{res.profile.render()}\n{line}"


def cmd_run(args: argparse.Namespace) -> int:
    from mmusv.batch.cli import check_batch_options, run_batch, uses_batch
    from mmusv.bundled import resolve_scenario

    src = resolve_scenario(path_arg(args.scenario, flag="scenario"))
    # Checked for one file as for a folder (a single file used to take --jobs 0 without a word).
    if args.jobs < 1:
        raise ConfigError(f"--jobs {args.jobs}: must be at least 1")
    if args.frames is not None and args.frames < 1:
        raise ConfigError(f"--frames {args.frames}: must be at least 1")
    if not str(args.output).strip():
        raise ConfigError("-o/--output is empty: give the output folder (default out/)")
    check_output_folder(args.output)  # a file there or above was "cannot create output folder: File exists"
    check_batch_options(args)
    if src.is_dir():
        if args.profile:
            raise MmusvError("--profile times one scenario; give a scenario file, not a folder")
        return run_batch(args, src)
    if uses_batch(args):  # one file with --ray, --retries, --split-frames: a batch of one (OUT/<stem>/)
        if args.profile:
            raise MmusvError("--profile times one run in this process; leave out --ray, --retries and --split-frames")
        return run_batch(args, [src])
    if args.stop_on_full_disk:  # taken without a word
        print(
            "mmusv: note: --stop-on-full-disk stops a batch's other recordings when one fails for a full disk; one "
            "scenario's run stops there anyway",
            file=sys.stderr,
        )
    if args.jobs > 1:  # taken without a word: one scenario runs in this process, on every core
        print(
            f"mmusv: note: --jobs {args.jobs} runs the scenarios of a folder side by side; one scenario runs in "
            "this process (its sensors use every core)",
            file=sys.stderr,
        )
    print(
        _run_one(
            str(src), args.output, args.overwrite, args.frames, sys.stdout.isatty(), not args.no_checks, args.profile
        )
    )
    return 0
