"""The ``mmusv`` command line.

Subcommands: ``assets`` (list the vessel library), ``study waves`` (Table I of the paper), ``version``.
Errors in the input end with a one-line message naming the problem and exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rich.console import Console

from mmusv.errors import MmusvError

BUNDLED_WAVE_SCENARIO = "scenarios/island_port_waves.yaml"


def _console() -> Console:
    """A rich console; wide when not writing to a terminal so piped tables are not wrapped."""
    from rich.console import Console

    return Console(width=None if sys.stdout.isatty() else 160)


def _cmd_assets(args: argparse.Namespace) -> int:
    from rich.table import Table

    from mmusv.world.vessels import library

    table = Table(title="mmusv vessel library")
    for col in ("name", "category", "class", "length m", "beam m", "height m", "draft m", "triangles"):
        table.add_column(col, justify="right" if col.endswith(("m", "triangles")) else "left")
    for a in library():
        table.add_row(a.name, a.category, a.semantic_class.name.lower(), f"{a.length:.1f}", f"{a.beam:.1f}", f"{a.height:.1f}", f"{a.draft:.1f}", str(a.num_triangles))
    _console().print(table)
    return 0


def _cmd_study_waves(args: argparse.Namespace) -> int:
    from rich.table import Table

    from mmusv.config import load_scenario
    from mmusv.studies.waves import run_wave_study

    scenario = load_scenario(args.scenario)
    if args.frames is not None:
        if args.frames < 2:
            raise MmusvError("--frames must be at least 2")
        scenario = scenario.model_copy(update={"acquisition": scenario.acquisition.model_copy(update={"frames": args.frames})})
    study = run_wave_study(scenario)
    table = Table(title=f"Wave study on {scenario.name} ({study.table['usvs'][0]} USVs × {study.table['frames'][0]} frames)")
    for col in ("wave", "H (m)", "heave RMS (m)", "roll RMS (°)", "pitch RMS (°)"):
        table.add_column(col, justify="right")
    for r in study.table.iter_rows(named=True):
        table.add_row(str(r["wave"]), f"{r['H_m']:.1f}", f"{r['heave_rms_m']:.4f}", f"{r['roll_rms_deg']:.4f}", f"{r['pitch_rms_deg']:.4f}")
    console = _console()
    console.print(table)
    console.print("R² of a linear fit in H: " + ", ".join(f"{k} {v:.4f}" for k, v in study.r2.items()))
    paths = study.write(Path(args.output))
    console.print(f"wrote {paths['csv']} and {paths['png']}")
    return 0


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="mmusv", description="Headless maritime multi-USV simulator and dataset generator.")
    sub = p.add_subparsers(dest="command", required=True)
    sub.add_parser("version", help="print the version")
    sub.add_parser("assets", help="list the vessel library")
    study = sub.add_parser("study", help="reproduce the paper's experiments")
    studies = study.add_subparsers(dest="study", required=True)
    waves = studies.add_parser("waves", help="Table I: heave/roll/pitch RMS under W0..W3")
    waves.add_argument("--scenario", default=BUNDLED_WAVE_SCENARIO, help=f"scenario YAML (default {BUNDLED_WAVE_SCENARIO})")
    waves.add_argument("-o", "--output", default="out/wave_study", help="output folder for CSV and plot")
    waves.add_argument("--frames", type=int, default=None, help="override the scenario's frame count")
    return p


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``mmusv`` command; returns the exit status."""
    args = _parser().parse_args(sys.argv[1:] if argv is None else argv)
    try:
        if args.command == "version":
            from mmusv import __version__

            print(f"mmusv {__version__}")
            return 0
        if args.command == "assets":
            return _cmd_assets(args)
        if args.command == "study" and args.study == "waves":
            return _cmd_study_waves(args)
    except MmusvError as exc:
        print(f"mmusv: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("mmusv: interrupted", file=sys.stderr)
        return 130
    return 2


if __name__ == "__main__":
    sys.exit(main())
