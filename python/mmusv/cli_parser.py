"""The arguments of the ``mmusv`` command (:func:`parser`): its subcommands and their options, those of
``convert``, ``generate``, ``editor``, ``train``, ``dataset`` and ``study detection`` / ``robustness`` added by
their own ``cli`` modules. :func:`mmusv.cli.main` parses with it.
"""

from __future__ import annotations

import argparse
import contextlib
import difflib
import re
import sys
from collections.abc import Sequence
from typing import Any, ClassVar, NoReturn

__all__ = ["BUNDLED_WAVE_SCENARIO", "CommandParser", "parser"]

BUNDLED_WAVE_SCENARIO = "scenarios/island_port_waves.yaml"


class CommandParser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line, as the command's other errors are: ``mmusv: error:
    argument --jobs: invalid int value: 'abc' (see mmusv run --help)``, exit status 2. argparse's own printed its
    usage block first (a dozen lines for ``run``) and named the subcommand only there. ``--help`` is unchanged.
    The subcommands' parsers are of this class too (``add_subparsers`` makes them of the parent's class)."""

    _deepest: CommandParser | None = None
    """The innermost (sub)parser of the parse under way: the one an unrecognised argument, which argparse
    reports from the top parser, belongs to."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        # No abbreviations: ``--frame 3`` was taken as ``--frames 3`` without a word, and a script using a
        # shortened flag would change meaning the day a second flag shares its prefix. A shortened flag is
        # now an unrecognised argument, with the flag it may mean (see :meth:`error`).
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        CommandParser._deepest = self
        if " " not in self.prog:  # the top parser: sub-parsers' progs are ``mmusv run`` and the like
            CommandParser._argv = list(sys.argv[1:] if args is None else args)
        return super().parse_known_args(args, namespace)

    _argv: ClassVar[list[str]] = []
    """The arguments of the parse under way (the top parser's), for :func:`_misplaced_options` and
    :func:`_dash_value`."""

    def error(self, message: str) -> NoReturn:
        prog = self.prog
        deepest = CommandParser._deepest
        misplaced = _misplaced_options(self)
        if misplaced:
            message, prog = misplaced, self.prog.split()[0]
        elif message.startswith("unrecognized arguments") and deepest is not None:
            prog = deepest.prog
            message += _did_you_mean(deepest, message)
        message = " ".join(message.split()) + _dash_value(message)
        choice = re.fullmatch(r"argument (\w+): invalid choice: (.*)", message)  # a subcommand (``command``)
        if choice:
            message = f"unknown {choice[1]} {choice[2]}"
        line = f"{prog.split()[0]}: error: {message} (see {prog} --help)"
        with contextlib.suppress(OSError, ValueError):
            print(line, file=sys.stderr, flush=True)
        self.exit(2)


def _misplaced_options(parser: argparse.ArgumentParser) -> str | None:
    """The error for options given before the command's name (``mmusv --frames 1 run x``), which argparse
    reported as ``unknown command '1'`` or as an argument ``mmusv run`` does not know (it knows ``--frames``);
    None when ``parser`` is not the top parser or no option precedes the command."""
    commands = next((a.choices for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)
    if " " in parser.prog or not commands:
        return None
    given = CommandParser._argv
    own = {o for a in parser._actions for o in a.option_strings}
    at = next((i for i, word in enumerate(given) if word in commands), None)
    before = given[: len(given) if at is None else at]
    options = [w for w in before if w.startswith("-") and w != "-" and w.split("=", 1)[0] not in own]
    if not options:
        return None
    if at is None:
        return (
            f"option {options[0]} is given before any command: mmusv itself takes only --help and --version; "
            "a command's options go after its name (mmusv COMMAND --help lists them)"
        )
    command = given[at]
    return (
        f"option {' '.join(options)} is given before the command {command!r}: a command's options go after its "
        f"name, as in: mmusv {' '.join([command, *given[at + 1 :], *before])}"
    )


def _dash_value(message: str) -> str:
    """``"; a value that begins with '-' is given as --split=-1,1,1"`` when ``message`` says an option got no value
    and the word after it begins with ``-`` (argparse takes ``-1,1,1`` for an option, and said only "expected one
    argument"); empty otherwise."""
    got = re.fullmatch(r"argument (\S+): expected one argument", message)
    if got is None:
        return ""
    flags = got[1].split("/")
    argv = CommandParser._argv
    at = next((i for i, word in enumerate(argv) if word in flags), None)
    if at is None or at + 1 >= len(argv) or not re.match(r"-[0-9.]", argv[at + 1]):  # a negative number's start
        return ""
    return f"; a value that begins with '-' is given as {argv[at]}={argv[at + 1]}"


def _did_you_mean(parser: argparse.ArgumentParser, message: str) -> str:
    """``; did you mean --frames?`` for each unrecognised ``--flag`` (or ``--flag=value``) of ``message`` that is
    the prefix of, or close to, one of ``parser``'s own flags; empty when none is."""
    flags = sorted(o for a in parser._actions for o in a.option_strings if o.startswith("--"))
    hints = []
    for word in message.partition(":")[2].split():
        given = word.split("=", 1)[0]
        if not given.startswith("--") or given in flags:
            continue
        near = [f for f in flags if f.startswith(given)] or difflib.get_close_matches(given, flags, n=3, cutoff=0.75)
        if near:
            hints.append(f"{given}: did you mean {' or '.join(near)}?")
    return "; " + "; ".join(hints) if hints else ""


def parser() -> argparse.ArgumentParser:
    """The ``mmusv`` command's argument parser, every subcommand in it."""
    p = CommandParser(prog="mmusv", description="Headless maritime multi-USV simulator and dataset generator.")
    from mmusv import __version__

    p.add_argument("--version", action="version", version=f"mmusv {__version__}", help="print the version and exit")
    sub = p.add_subparsers(dest="command", required=True)
    sub.add_parser("version", help="print the version")
    p_assets = sub.add_parser(
        "assets",
        help="list the vessel library, or your own assets (of asset files, or of scenarios' assets: lists)",
        description="Lists the built-in vessel library; given FILEs, lists instead the user's own assets they hold "
        "(with the file each comes from), built as mmusv run builds them: to check a mesh's size, triangles, parts "
        "and materials before a run. --render draws the assets listed.",
    )
    p_assets.add_argument(
        "files",
        nargs="*",
        metavar="FILE",
        help="a scenario YAML (the asset files its assets: lists) or an asset YAML (one asset, or a list of them); "
        "without FILE, the built-in library",
    )
    p_assets.add_argument(
        "--render", metavar="DIR", help="also write a close-up PNG per asset listed and contact_sheet.png"
    )
    p_assets.add_argument(
        "--overwrite", action="store_true", help="with --render: replace files of those names already in DIR"
    )
    p_assets.add_argument(
        "--materials",
        action="store_true",
        help="also list each asset's materials: the faces of each, its base colour (linear RGB and 8-bit sRGB), "
        "roughness, metallic, emitted radiance and, for a navigation lamp, its arc",
    )
    sub.add_parser("scenarios", help="list the bundled scenarios (mmusv run NAME runs one from any directory)")
    study = sub.add_parser("study", help="reproduce the paper's experiments")
    studies = study.add_subparsers(dest="study", required=True)
    waves = studies.add_parser("waves", help="Table I: heave/roll/pitch RMS under W0..W3")
    waves.add_argument(
        "--scenario", default=BUNDLED_WAVE_SCENARIO, help=f"scenario YAML (default {BUNDLED_WAVE_SCENARIO})"
    )
    waves.add_argument(
        "-o",
        "--output",
        default="out/wave_study",
        help="output folder (default out/wave_study): wave_study.csv and .png with --motion paper, "
        "wave_study_physical.csv and wave_study_vessels.csv with --motion physical",
    )
    waves.add_argument("--frames", type=int, default=None, help="override the scenario's frame count")
    waves.add_argument("--overwrite", action="store_true", help="replace the files of its names already in -o")
    waves.add_argument(
        "--motion",
        choices=("paper", "physical"),
        default="paper",
        help="paper: Table I with the paper's formula (default); physical: every hull's response to the sea",
    )
    waves.add_argument(
        "--usvs",
        choices=("scenario", "reference"),
        default="scenario",
        help="scenario: the scenario's USVs at their own sizes (default); reference: every USV at the paper's "
        "reference size, 5 x 2.5 x 1.5 m (alpha_v = 1), on its own route, which gives Table I (--motion paper only)",
    )
    agree = studies.add_parser("agreement", help="Table II: 3D-box annotations vs top-view semantic rendering")
    agree.add_argument("scenarios", nargs="*", help="scenario YAMLs (default: the three bundled map scenarios)")
    agree.add_argument(
        "-o", "--output", default="out/agreement_study", help="output folder (default out/agreement_study)"
    )
    agree.add_argument("--frames", type=int, default=None, help="frames per scenario (default: all)")
    agree.add_argument("--overwrite", action="store_true", help="replace the files of its names already in -o")
    from mmusv.studies.detection.cli import add_parsers as add_detection_parsers

    add_detection_parsers(studies)
    run = sub.add_parser("run", help="run a scenario (or a folder of them) into an MCAP recording + Parquet tables")
    run.add_argument(
        "scenario",
        help="scenario YAML, or a folder of scenario YAMLs (a batch: OUT/<file stem>/ each, and OUT/dataset.json); "
        "one file given --ray, --retries, --split-frames or --cpus-per-task runs as a batch of one, in that layout",
    )
    run.add_argument("-o", "--output", default="out", help="output folder (default out/)")
    run.add_argument("--overwrite", action="store_true", help="replace an existing recording")
    run.add_argument("--frames", type=int, default=None, help="run only the first N frames")
    run.add_argument(
        "--jobs", type=int, default=1, help="for a folder: scenarios run in parallel processes (default 1)"
    )
    from mmusv.batch.cli import add_dataset_parser, add_run_options

    add_run_options(run)
    add_dataset_parser(sub)
    run.add_argument(
        "--no-checks",
        action="store_true",
        help="skip the route checks on the map (in water: an error; clearances, separation: warnings)",
    )
    run.add_argument(
        "--profile",
        action="store_true",
        help="print the time per stage per frame (each sensor, annotation, encoding, writing, the rest)",
    )
    info = sub.add_parser(
        "info", help="agents, topics, frames and duration of a recording; damage and missing frames if any"
    )
    info.add_argument(
        "recording",
        help="an .mcap (or .mcap.partial, .parts.json) written by mmusv run, or its folder; a folder of run folders "
        "(a batch's output, links to run folders followed): one row per recording below, and one per recording its "
        "dataset.json or a run's manifest.json names that is gone; exits 1 when the recording (or one of them) is "
        "gone, cannot be read at all or holds no readable frame",
    )
    rec = sub.add_parser(
        "recover",
        help="finish the .partial recording of a killed run into a valid MCAP (summary, index) and rebuild its "
        "tables; for a finished run, rebuild its tables when they are missing or damaged",
    )
    rec.add_argument("target", help="the run folder (holding NAME.mcap.partial, or a finished NAME.mcap) or the file")
    rec.add_argument("--overwrite", action="store_true", help="replace an existing NAME.mcap")
    prev = sub.add_parser("preview", help="one picture of a recorded frame (surround RGB, depth, semantic, PPI, BEV)")
    prev.add_argument("recording", help="an .mcap (or .mcap.partial, .parts.json) written by mmusv run")
    prev.add_argument("--frame", type=int, default=0, help="acquisition index (default 0)")
    prev.add_argument("--agent", default=None, help="USV id (default: the first that recorded a picture)")
    prev.add_argument(
        "-o",
        "--output",
        default=None,
        help="picture path (.png, .jpg) or an existing folder (default: next to the recording, "
        "NAME_frameNNNNNN_AGENT.png)",
    )
    schema = sub.add_parser(
        "schema", help="print the JSON Schema of scenario or spec files (for editors: yaml-language-server)"
    )
    schema.add_argument("kind", choices=("scenario", "spec"), help="scenario files or generation specs")
    schema.add_argument(
        "-o", "--output", default=None, help="write it to this file (default, or -: the standard output)"
    )
    from mmusv.editor.cli import add_parser as add_editor_parser
    from mmusv.export.cli import add_parser as add_convert_parser
    from mmusv.generate.cli import add_parser as add_generate_parser
    from mmusv.learn.cli import add_parser as add_train_parser

    add_generate_parser(sub)
    add_convert_parser(sub)
    add_editor_parser(sub)
    add_train_parser(sub)
    return p
