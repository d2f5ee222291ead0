"""The ``mmusv`` command line.

Subcommands: ``run`` (a scenario or a folder of them into MCAP + Parquet; folders through :mod:`mmusv.batch`, on a
local pool or Ray), ``dataset`` (spec → recordings → OPV2V, :mod:`mmusv.batch.dataset`), ``info`` and ``preview``
(inspect a recording), ``convert`` (to OPV2V, KITTI, ROS 2, COCO, YOLO, MaSTr1325, SemanticKITTI, MOTChallenge),
``generate`` (batch scenario generation), ``recover`` (finish a killed run), ``assets`` (the vessel library, or a
user's own assets), ``study waves`` (Table I) and ``study agreement`` (Table II), ``study detection`` / ``study
robustness`` (Tables III, IV), ``editor`` (the scenario editor in the browser), ``schema`` (the JSON Schema of
scenario and spec files, for editors), ``version``.
Errors in the input end with a one-line message naming the problem and exit status 2, never a traceback.

The arguments are :mod:`mmusv.cli_parser`'s; the subcommands run from :mod:`mmusv.cli_run`,
:mod:`mmusv.cli_recordings` (``info``, ``preview``, ``recover``), :mod:`mmusv.cli_library` (``assets``,
``scenarios``), :mod:`mmusv.cli_schema` and the ``cli`` modules of their packages.
"""

from __future__ import annotations

import argparse
import sys

from mmusv import cli_console
from mmusv.cli_library import cmd_assets, cmd_scenarios
from mmusv.cli_parser import BUNDLED_WAVE_SCENARIO as BUNDLED_WAVE_SCENARIO  # importable from here as before
from mmusv.cli_parser import parser as _parser
from mmusv.cli_recordings import cmd_info, cmd_preview, cmd_recover
from mmusv.cli_run import cmd_run
from mmusv.cli_schema import cmd_schema
from mmusv.errors import MmusvError
from mmusv.held_signals import StopSignals, forget_handled_interrupt


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``mmusv`` command; returns the exit status."""
    cli_console.open_missing_streams()  # a closed stdout (``mmusv run ... >&-``) was an AttributeError traceback
    with cli_console.lenient_output():
        try:
            code = _main(argv)
        except SystemExit as exc:  # argparse: --help, usage errors (its own message, its own status)
            failed = cli_console.flush_stdout(0) if exc.code in (0, None) else 0
            if failed:
                raise SystemExit(failed) from None
            raise
        return cli_console.flush_stdout(code)


def _main(argv: list[str] | None) -> int:
    args = _parser().parse_args(sys.argv[1:] if argv is None else argv)
    import warnings

    from mmusv.scenario_checks import MmusvWarning

    def _show(message: Warning | str, category: type[Warning], *rest: object, **kw: object) -> None:
        prefix = "mmusv: warning: " if issubclass(category, MmusvWarning) else f"{category.__name__}: "
        cli_console.say(prefix + str(message))

    before = warnings.showwarning
    warnings.showwarning = _show  # one line per warning, never a source excerpt
    try:
        return _run_command(args)
    finally:  # main() called in a process that goes on (a notebook, a test) leaves its warnings as they were
        if warnings.showwarning is _show:
            warnings.showwarning = before


def _run_command(args: argparse.Namespace) -> int:
    """:func:`_dispatch` of ``args`` with the command line's signal handling and one-line errors."""
    with StopSignals() as signals:
        try:
            cli_console.check_thread_environment()  # before the core's or Polars' thread pools exist
            code = _dispatch(args)
        except MmusvError as exc:
            cli_console.say(f"mmusv: error: {exc}{cli_console.cwd_hint()}")
            code = 2
        except BrokenPipeError as exc:  # the reader of stdout went away (``mmusv info X | head -1``): quietly
            if not cli_console.stdout_broken():
                cli_console.say(f"mmusv: error: {exc.filename + ': ' if exc.filename else ''}{exc.strerror or exc}")
                return signals.status(2)
            cli_console.drop(sys.stdout)
            code = 1
        except OSError as exc:  # a file the command reads or writes (a full disk, a read-only folder): one line
            where = f"{exc.filename}: " if exc.filename else ""
            if not exc.filename and cli_console.stdout_fails():  # ``> /dev/full``: the console's write, not a file's
                where = "cannot write to the standard output: "
                cli_console.drop(sys.stdout)
            cli_console.say(
                f"mmusv: error: {where}{exc.strerror or exc}{cli_console.os_hint(exc)}{cli_console.cwd_hint()}"
            )
            code = 2
        except MemoryError as exc:  # Python's or numpy's allocation (the core's own aborts: see the report)
            cli_console.say(
                f"mmusv: error: out of memory{': ' + str(exc) if str(exc) else ''}{cli_console.memory_hint()}"
            )
            code = 2
        except KeyboardInterrupt:
            code = _stopped(signals)
        except Exception:
            # A stop a library turned into an error of its own: the KeyboardInterrupt raised while pydantic built a
            # scenario model came out as pydantic-core's SchemaError, or Python's RuntimeError from __set_name__.
            if signals.received is None:
                raise
            code = _stopped(signals)
        if signals.received is not None and not signals.said:
            # A stop the command did not end on: its KeyboardInterrupt was swallowed after the last step's
            # raise_noted_stop (a library's, in a recording's last frame: the run finished whole, "complete"), or
            # the command said an error of its own meanwhile. Every stop ends with the one line and 128 + signal.
            code = _stopped(signals)
    if signals.received is not None:  # the command ends with its own status, not CPython's for an interrupt
        forget_handled_interrupt()
    return signals.status(code)


def _stopped(signals: StopSignals) -> int:
    """Says that the command was stopped (``mmusv: interrupted``, or ``terminated (SIGTERM)``), once; returns 130,
    which :meth:`StopSignals.status` makes 128 + the signal received."""
    name = "terminated (SIGTERM)" if signals.received not in (None, 2) else "interrupted"
    cli_console.say(f"mmusv: {name}")
    signals.said = True
    return 130


def _dispatch(args: argparse.Namespace) -> int:
    """Runs the parsed command; returns its exit status."""
    if args.command == "version":
        from mmusv import __version__

        print(f"mmusv {__version__}")
        return 0
    if args.command == "assets":
        return cmd_assets(args)
    if args.command == "scenarios":
        return cmd_scenarios(args)
    if args.command == "study" and args.study == "waves":
        from mmusv.studies.cli import study_waves

        return study_waves(args)
    if args.command == "study" and args.study == "agreement":
        from mmusv.studies.cli import study_agreement

        return study_agreement(args)
    if args.command == "study" and args.study in ("detection", "robustness"):
        from mmusv.studies.detection.cli import run as _run_detection

        return _run_detection(args)
    if args.command == "run":
        return cmd_run(args)
    if args.command == "info":
        return cmd_info(args)
    if args.command == "recover":
        return cmd_recover(args)
    if args.command == "preview":
        return cmd_preview(args)
    if args.command == "convert":
        from mmusv.export.cli import run as _run_convert

        return _run_convert(args)
    if args.command == "generate":
        from mmusv.generate.cli import run as _run_generate

        return _run_generate(args)
    if args.command == "train":
        from mmusv.learn.cli import run as _run_train

        return _run_train(args)
    if args.command == "editor":
        from mmusv.editor.cli import run as _run_editor

        return _run_editor(args)
    if args.command == "schema":
        return cmd_schema(args)
    if args.command == "dataset":
        from mmusv.batch.cli import run_dataset

        return run_dataset(args)
    return 2


if __name__ == "__main__":
    sys.exit(main())
