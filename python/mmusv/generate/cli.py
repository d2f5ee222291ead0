"""``mmusv generate SPEC.yaml -o DIR``: the command-line face of :func:`mmusv.generate.generate`.

:func:`add_parser` adds the subcommand to the ``mmusv`` argparse sub-parsers and :func:`run` executes it: a rich
progress bar while generating, the report table at the end, the wall time on the console only (never in
``report.json``). Exit status 0 when every quota is met, 1 when some quota is not (the report says why); bad
input raises :class:`mmusv.errors.MmusvError`, which the ``mmusv`` entry point prints as one line (status 2).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from mmusv.text import counted

__all__ = ["add_parser", "run", "seed_arg"]


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Adds ``generate`` to ``subparsers`` (the object ``ArgumentParser.add_subparsers`` returned)."""
    p: argparse.ArgumentParser = subparsers.add_parser(
        "generate",
        help="generate scenarios from a spec under constraints",
        description="Samples scenarios from a generation spec, rejects those that break a constraint, writes one "
        "scenario YAML per accepted sample and report.json into the output directory.",
    )
    p.add_argument(
        "spec", help="generation spec YAML, or a bundled spec by name (island_demo, scenarios/specs/island_demo.yaml)"
    )
    p.add_argument("-o", "--output", default=None, help="output directory (default scenarios/generated/<spec name>)")
    p.add_argument(
        "--force", action="store_true", help="replace scenario files and report.json already in the directory"
    )
    p.add_argument(
        "--seed",
        default=None,
        metavar="N",
        help="replaces the spec's seed, from which every random draw derives: a whole number in 0..2**63-1; the "
        "same spec and seed give the same files byte for byte (default: the spec's own seed)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p


def seed_arg(text: str, *, flag: str = "--seed") -> int:
    """The value of ``--seed`` as a whole number in ``0 .. 2**63 - 1`` (the range of a spec's ``seed``), else a
    :class:`~mmusv.errors.ConfigError` naming the flag and that range."""
    import re

    from mmusv.errors import ConfigError
    from mmusv.generate.spec_models import SEED_LIMIT

    t = text.strip()
    if not re.fullmatch(r"[+-]?[0-9]+", t) or not 0 <= int(t) < SEED_LIMIT:
        raise ConfigError(
            f"{flag} {text!r}: must be a whole number in 0..{SEED_LIMIT - 1} (it replaces the spec's seed)"
        )
    return int(t)


def run(args: argparse.Namespace) -> int:
    """Runs ``mmusv generate``; returns the exit status (0 all quotas met, 1 otherwise)."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from mmusv.cli_console import rich_console
    from mmusv.cli_paths import check_output_folder, output_arg, path_arg
    from mmusv.generate.mapctx import map_context
    from mmusv.generate.runner import check_output, generate, infeasible_error
    from mmusv.generate.spec import load_spec, with_seed

    console = rich_console()
    if args.output is not None:  # an empty -o took the default folder without a word
        output_arg(args.output)
    from mmusv.bundled import resolve_spec

    seed = None if args.seed is None else seed_arg(args.seed)  # before the spec is read: a bad flag is said first
    # A bundled spec by name from any folder (island_demo, coop_detection), as mmusv dataset takes it.
    spec_path = resolve_spec(path_arg(args.spec, flag="spec"))
    spec = load_spec(spec_path)
    if seed is not None:
        spec = with_seed(spec, seed, name="--seed")
    out = Path(args.output) if args.output is not None else Path("scenarios/generated") / spec.name
    check_output_folder(str(out))  # before the map is built: a file there was named after it
    check_output(
        out, force=args.force, spec_path=spec_path
    )  # an earlier run's files, without --force: refused before the maps
    total = sum(c.quota for c in spec.combinations)
    t0 = time.perf_counter()
    maps = {(m.type, m.seed): m for m in (spec.map_of(c) for c in spec.combinations)}
    for (kind, seed), m in sorted(maps.items()):
        with console.status(f"building map {kind} seed {seed}", spinner="dots"):
            _ = map_context(
                m.type, seed=m.seed, params=m.param_values()
            ).scene  # built here, so the progress bar is generation
    t_map = time.perf_counter() - t0
    contexts = [map_context(m.type, seed=m.seed, params=m.param_values()) for m in map(spec.map_of, spec.combinations)]
    refused = infeasible_error(spec, contexts, source=str(spec_path))
    if refused is not None:  # a clearance no water offers: said before the progress bar, and nothing written
        raise refused
    t0 = time.perf_counter()
    if args.no_progress:
        with _resume_hint(out):
            report = generate(spec, out, force=args.force, source=str(spec_path))
    else:
        columns = (
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[attempts]} attempts"),
            TimeElapsedColumn(),
        )
        with Progress(*columns, console=console, transient=False) as bar:
            task = bar.add_task("generating", total=total, attempts=0)

            def tick(name: str, accepted: int, attempts: int) -> None:
                bar.update(task, completed=accepted, attempts=attempts, description=name)

            with _resume_hint(out):
                report = generate(spec, out, force=args.force, progress=tick, source=str(spec_path))
            bar.update(task, completed=total, description="done")
    elapsed = time.perf_counter() - t0
    report.print(console)
    rate = report.accepted / elapsed if elapsed > 0 else float("inf")
    console.print(
        f"wrote {counted(report.accepted, 'scenario')} and report.json to {out}: map built in {t_map:.1f} s, "
        f"generated in {elapsed:.1f} s ({rate:.1f} scenarios/s, {counted(report.attempts, 'attempt')})"
    )
    return 0 if report.all_met else 1


@contextmanager
def _resume_hint(out: Path) -> Iterator[None]:
    """On Ctrl-C (or SIGTERM): one line saying what is left in ``out`` and how to start again."""
    try:
        yield
    except KeyboardInterrupt:
        print(
            f"mmusv: generation stopped; the scenario files written so far stay in {out} (listed in its "
            ".generate.partial): run the same command with --force to generate the set from the start",
            file=sys.stderr,
        )
        raise
