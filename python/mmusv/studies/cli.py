"""``mmusv study waves`` (Table I, paper and physical motion) and ``mmusv study agreement`` (Table II): the
commands' checks, tables and files (``mmusv study detection`` and ``robustness`` are in
:mod:`mmusv.studies.detection.cli`). :func:`mmusv.cli.main` parses the arguments and calls these."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from mmusv.cli_console import rich_console
from mmusv.cli_paths import check_output_folder, made_output_folder, path_arg, refuse_replacing
from mmusv.config import MAX_FRAMES  # also the bound of `study waves --frames`
from mmusv.text import counted

if TYPE_CHECKING:
    from mmusv.config import Scenario

__all__ = ["MAX_FRAMES", "study_agreement", "study_waves"]


def study_waves(args: argparse.Namespace) -> int:
    """``mmusv study waves``: heave, roll and pitch RMS against the sea state (``--motion paper``: the paper's
    formula, Table I; ``physical``: the wave field's response, beside both); prints the table, writes its files into
    ``-o``; exit status 0."""
    from rich.table import Table

    from mmusv import arguments
    from mmusv.bundled import resolve_scenario
    from mmusv.config import load_scenario
    from mmusv.errors import ConfigError, MmusvError, located
    from mmusv.studies.waves import (
        PAPER_FILES,
        PAPER_TABLE_I,
        PHYSICAL_FILES,
        PHYSICAL_RECORD_S,
        check_scenario,
        run_wave_study,
    )

    # --frames first, within a scenario's own bound: a bad count made the output folder before it was refused,
    # and 10**30 was a numpy traceback (the copy of the scenario below is not validated).
    if args.frames is not None:
        arguments.whole(args.frames, name="--frames", lo=2, hi=MAX_FRAMES)
    if args.usvs == "reference" and args.motion != "paper":
        raise ConfigError(
            f"--usvs reference with --motion {args.motion}: the reference USV is a size of the paper's formula "
            "(--motion paper); the physical response reads each hull's own particulars"
        )
    try:  # "scenario '/tmp' is a directory, not a file" did not say which flag gave it
        source = resolve_scenario(path_arg(args.scenario, flag="--scenario"))
        scenario = load_scenario(source)
    except MmusvError as exc:
        raise located(exc, "--scenario") from None
    if args.frames is not None:
        scenario = scenario.model_copy(
            update={"acquisition": scenario.acquisition.model_copy(update={"frames": args.frames})}
        )
    # The scenario's own checks (a USV, 2 frames) before the output folder: a scenario without USVs left an empty
    # folder behind, and one of a single frame a table of zeros.
    try:  # named by its file: "scenario 'island_occlusion'" named the name: inside it, not the file given
        check_scenario(
            scenario, record_s=PHYSICAL_RECORD_S if args.motion == "physical" and args.frames is None else None
        )
    except MmusvError as exc:
        raise located(exc, str(source)) from None
    check_output_folder(args.output)
    # files of its names already there (a user's wave_study.csv) were replaced without a word, after the study
    refuse_replacing(
        args.output, PHYSICAL_FILES if args.motion == "physical" else PAPER_FILES, overwrite=args.overwrite
    )
    with made_output_folder(args.output):  # removed again if still empty when the study fails or is interrupted
        if args.motion == "physical":
            return _physical_wave_study(scenario, args)
        study = run_wave_study(scenario, usvs=args.usvs)
        sized = " of the paper's reference size, 5 × 2.5 × 1.5 m," if args.usvs == "reference" else ""
        table = Table(
            title=f"Wave study on {scenario.name} "
            f"({counted(int(study.table['usvs'][0]), 'USV')}{sized} × {study.table['frames'][0]} frames)"
        )
        for col in ("wave", "H (m)", "heave RMS (m)", "roll RMS (°)", "pitch RMS (°)", "paper Table I"):
            table.add_column(col, justify="right")
        for r in study.table.iter_rows(named=True):
            paper = PAPER_TABLE_I.get(str(r["wave"]))
            table.add_row(
                str(r["wave"]),
                f"{r['H_m']:.1f}",
                f"{r['heave_rms_m']:.4f}",
                f"{r['roll_rms_deg']:.4f}",
                f"{r['pitch_rms_deg']:.4f}",
                "" if paper is None else " / ".join(f"{x:.4f}" for x in paper),
            )
        console = rich_console()
        console.print(table)
        console.print("R² of a linear fit in H: " + ", ".join(f"{k} {v:.4f}" for k, v in study.r2.items()))
        paths = study.write(Path(args.output))
        console.print(f"wrote {paths['csv']} and {paths['png']}")
        return 0


def _physical_wave_study(scenario: Scenario, args: argparse.Namespace) -> int:
    """``study waves --motion physical``: the table per sea state, then per vessel."""
    from rich.table import Table

    from mmusv.studies.waves import PHYSICAL_RECORD_S, run_physical_wave_study

    study = run_physical_wave_study(scenario, record_s=None if args.frames is not None else PHYSICAL_RECORD_S)
    s = study.summary
    frames, hz = int(s["frames"][0]), scenario.acquisition.frequency_hz
    table = Table(
        title=f"Wave study, physical motion, on {scenario.name}: USVs pooled, {frames} frames ({frames / hz:.0f} s) "
        "per sea state; heave m / roll ° / pitch ° RMS"
    )
    for col in ("wave", "Hs (m)", "Tp (s)", "paper Table I", "paper mode", "physical (USVs)", "physical (fleet)"):
        table.add_column(col, justify="right")

    def trio(r: dict[str, object], prefix: str) -> str:
        return (
            f"{r[prefix + '_heave_rms_m']:.3f} / {r[prefix + '_roll_rms_deg']:.2f} / {r[prefix + '_pitch_rms_deg']:.2f}"
        )

    for r in s.iter_rows(named=True):
        table.add_row(
            str(r["wave"]),
            f"{r['Hs_m']:.1f}",
            f"{r['Tp_s']:.1f}",
            trio(r, "table1"),
            trio(r, "paper"),
            trio(r, "physical"),
            trio(r, "fleet"),
        )
    console = rich_console()
    console.print(table)
    per = Table(title="Physical motion per vessel: heave m / roll ° / pitch ° RMS")
    per.add_column("vessel")
    per.add_column("asset")
    waves = s["wave"].to_list()
    for w in waves:
        per.add_column(str(w), justify="right")
    v = study.vessels
    for vid in v["id"].unique(maintain_order=True).to_list():
        rows = v.filter(v["id"] == vid)
        cells = [
            f"{r['heave_rms_m']:.3f} / {r['roll_rms_deg']:.2f} / {r['pitch_rms_deg']:.2f}"
            for r in rows.iter_rows(named=True)
        ]
        per.add_row(str(vid), str(rows["asset"][0]), *cells)
    console.print(per)
    mono = study.monotonic()
    rising = sorted(k for k, ok in mono.items() if ok)
    console.print(f"all three RMS rise with the sea state for {len(rising)} of {counted(len(mono), 'vessel')}")
    paths = study.write(Path(args.output))
    console.print(f"wrote {paths['summary']} and {paths['vessels']}")
    return 0


def study_agreement(args: argparse.Namespace) -> int:
    """``mmusv study agreement``: the annotations against the top-view rendering (Table II); prints the table,
    writes its files into ``-o``; exit status 0."""
    from rich.table import Table

    from mmusv.studies.agreement import BUNDLED_SCENARIOS, FILES, check_counts, load_scenarios, run_agreement_study

    check_counts(args.frames)  # before the output folder is made
    for scenario in args.scenarios:
        path_arg(scenario, flag="scenario")
    check_output_folder(args.output)
    refuse_replacing(args.output, FILES, overwrite=args.overwrite)  # a user's files of its names were replaced
    # Every scenario loaded and checked (a top-view camera) before the output folder and the first run: a missing
    # or broken one left an empty folder behind, after the scenarios before it had run.
    scenarios = load_scenarios(args.scenarios or BUNDLED_SCENARIOS)
    with made_output_folder(args.output):  # removed again if still empty when the study fails or is interrupted
        study = run_agreement_study(scenarios, frames=args.frames)
        table = Table(title="Annotation vs top-view rendering (Table II)")
        for col in (
            "map",
            "valid samples",
            "median centre error (px)",
            "median centroid error (px)",
            "mean containment",
            "mean hull occupancy",
        ):
            table.add_column(col, justify="right")
        for r in study.summary.iter_rows(named=True):
            table.add_row(
                str(r["map"]),
                str(r["valid_samples"]),
                f"{r['median_centre_error_px']:.3f}",
                f"{r['median_centroid_error_px']:.3f}",
                f"{r['mean_containment']:.4f}",
                f"{r['mean_hull_occupancy']:.3f}",
            )
        console = rich_console()
        console.print(table)
        paths = study.write(Path(args.output))
        console.print(f"wrote {paths['samples']} and {paths['summary']}")
        return 0
