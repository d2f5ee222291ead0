"""The ``mmusv`` command line.

Subcommands: ``run`` (a scenario or a folder of them into MCAP + Parquet; folders through :mod:`mmusv.batch`,
on a local pool or Ray), ``dataset`` (spec → recordings → OPV2V, :mod:`mmusv.batch.dataset`), ``info`` and
``preview`` (inspect a recording), ``convert`` (to OPV2V, KITTI, ROS 2, COCO, YOLO, MaSTr1325, SemanticKITTI),
``generate`` (batch scenario generation), ``recover`` (finish a killed run), ``assets`` (the vessel library),
``study waves`` (Table I) and ``study agreement`` (Table II), ``study detection`` / ``study robustness``
(Tables III, IV), ``editor`` (the scenario editor in the browser), ``schema`` (the JSON Schema of scenario and
spec files, for editors), ``version``.
Errors in the input end with a one-line message naming the problem and exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mmusv import cli_console
from mmusv.cli_console import rich_console
from mmusv.cli_paths import output_arg, path_arg, ready_output_folder
from mmusv.errors import ConfigError, MmusvError

BUNDLED_WAVE_SCENARIO = "scenarios/island_port_waves.yaml"


def _cmd_assets(args: argparse.Namespace) -> int:
    from rich.table import Table

    from mmusv.world.vessels import library

    if args.render is not None:  # its folder made first: one that cannot be was named after the table
        ready_output_folder(args.render, flag="--render")
    table = Table(title="mmusv vessel library")
    for col in ("name", "category", "class", "length m", "beam m", "height m", "draft m", "triangles", "parts"):
        table.add_column(col, justify="right" if col.endswith(("m", "triangles", "parts")) else "left")
    for a in library():
        table.add_row(
            a.name,
            a.category,
            a.semantic_class.name.lower(),
            f"{a.length:.1f}",
            f"{a.beam:.1f}",
            f"{a.height:.1f}",
            f"{a.draft:.1f}",
            str(a.num_triangles),
            str(a.num_parts),
        )
    rich_console().print(table)
    if args.render is not None:  # one close-up per asset and a contact sheet of them all
        from mmusv.world.contact_sheet import write_contact_sheet

        rich_console().print(f"wrote {write_contact_sheet(args.render)}")
    return 0


def _run_one(
    path: str,
    out: str,
    overwrite: bool,
    frames: int | None,
    show_progress: bool,
    checks: bool = True,
    profile: bool = False,
) -> str:
    """Runs one scenario; returns a one-line report. Used directly and in worker processes."""
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
        f"{scenario.name}: {res.frames_written} frames in {res.seconds:.1f} s ({fps:.2f} frames/s), "
        f"{res.messages} messages, {res.bytes / 1e6:.1f} MB -> {res.recording}"
    )
    return line if res.profile is None else f"{res.profile.render()}\n{line}"


def _cmd_run(args: argparse.Namespace) -> int:
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
    output_arg(args.output)
    check_batch_options(args)
    if src.is_dir():
        if args.profile:
            raise MmusvError("--profile times one scenario; give a scenario file, not a folder")
        return run_batch(args, src)
    if uses_batch(args):  # one file with --ray, --retries, --split-frames: a batch of one (OUT/<stem>/)
        if args.profile:
            raise MmusvError("--profile times one run in this process; leave out --ray, --retries and --split-frames")
        return run_batch(args, [src])
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


def _cmd_scenarios(args: argparse.Namespace) -> int:
    from rich.table import Table

    from mmusv.bundled import bundled_scenarios

    table = Table(title="Bundled scenarios (mmusv run NAME)")
    for col in ("name", "map", "USVs", "targets", "frames", "description"):
        table.add_column(col, justify="right" if col in ("USVs", "targets", "frames") else "left")
    for b in bundled_scenarios():
        table.add_row(b.name, b.map, str(b.usvs), str(b.targets), str(b.frames), b.description)
    rich_console().print(table)
    return 0


def _cmd_info(args: argparse.Namespace) -> int:
    from rich.table import Table

    from mmusv.recording import summary
    from mmusv.recording.info import recording_name

    target = Path(path_arg(args.recording, flag="recording"))
    folder: Path | None = None
    if target.is_dir():  # a run folder: its recording (finished, else the .partial) and its tables
        folder = target
        found = sorted(target.glob("*.parts.json")) or sorted(target.glob("*.mcap"))
        found = found or sorted(target.glob("*.mcap.partial"))
        if not found:
            raise MmusvError(
                f"{target} is a folder without a recording (*.mcap, *.mcap.partial or *.parts.json)"
                + _recordings_below(target)
            )
        if len(found) > 1:
            raise MmusvError(f"{target} holds {len(found)} recordings ({', '.join(f.name for f in found)}); name one")
        target = found[0]
    info = summary(target)
    console = rich_console()
    meta = info.get("metadata", {})
    run_meta = meta.get("run", {})
    frames = info.get("frames") or {}
    if not info.get("complete", True):
        console.print(
            "[yellow]incomplete recording (.partial, no summary or damaged): counts come from reading every "
            "chunk[/yellow]"
        )
    if info.get("frames") is None:  # an MCAP file, but not a recording of mmusv run: its messages only
        console.print(
            f"[bold]{target}[/bold]: an MCAP file not written by mmusv run (no scenario/sensors metadata): its "
            "messages only",
            markup=True,
            highlight=False,
        )
    else:
        written = run_meta.get("frames_written", "?")
        if frames:  # the complete frames read: a killed run's .partial has no run metadata saying it ("? frames")
            read, expected = frames["read"], frames["expected"]
            written = str(read) if read == expected else f"{read} of {expected}"
        console.print(
            f"[bold]{target}[/bold]: scenario {run_meta.get('scenario') or _scenario_of(meta, target)}, "
            f"status {run_meta.get('status', 'unfinished (no run metadata: the run was killed or is still going)')}, "
            f"{written} frames, agents {run_meta.get('agents') or _agents_of(meta)}",
            markup=True,
            highlight=False,
        )
    start, end = info.get("start_ns", 0), info.get("end_ns", 0)
    console.print(
        f"time {start / 1e9:.3f} .. {end / 1e9:.3f} s (duration {(end - start) / 1e9:.3f} s), "
        f"{info.get('messages', 0)} messages"
    )
    table = Table(title="topics")
    for col in ("topic", "schema", "messages"):
        table.add_column(col)
    for topic, t in sorted(info.get("topics", {}).items()):
        table.add_row(topic, t["schema"], str(t["messages"]))
    console.print(table)
    problems = [frames["report"]] if frames and frames.get("report") else list(info.get("damage", []))
    if folder is not None and frames:
        problems += _table_problems(target, frames)
    for line in problems:
        console.print(f"mmusv: warning: {line}", markup=False, highlight=False, style="yellow")
    if target.name.endswith(".mcap.partial"):
        if frames and frames.get("read"):
            console.print(
                f"`mmusv recover {target.parent}` finishes it into {recording_name(target)}.mcap with its tables"
            )
        else:  # recover refuses a .partial without a complete frame: nothing to finish
            console.print(
                f"it holds no complete frame: nothing to recover (`mmusv run` on {target.parent} records it again)"
            )
    return 0


def _scenario_of(meta: dict[str, dict[str, str]], target: Path) -> str:
    """The scenario's name as its ``scenario`` metadata says (a killed run has no ``run`` metadata), else the
    recording's name."""
    from mmusv.recording.info import recording_name

    name = (meta.get("scenario") or {}).get("name")
    return str(name) if name else recording_name(target)


def _agents_of(meta: dict[str, dict[str, str]]) -> str:
    """The agents the ``sensors`` metadata names (a killed run has no ``run`` metadata saying them), else ``?``."""
    import json

    try:
        sensors = json.loads(meta["sensors"]["json"])
    except (KeyError, TypeError, ValueError):
        return "?"
    return ",".join(map(str, sensors)) if isinstance(sensors, dict) and sensors else "?"


def _recordings_below(folder: Path) -> str:
    """``"; below it: a, b (name one)"``: the recordings in the folders below ``folder`` (a batch's output
    folder), or ``""``."""
    from mmusv.recording.info import find_recordings

    try:
        found = find_recordings(folder)
    except MmusvError:
        return ""
    if not found:
        return ""
    names = [str(f.relative_to(folder)) for f in found[:5]]
    more = f" and {len(found) - 5} more" if len(found) > 5 else ""
    return f"; below it: {', '.join(names)}{more} (name one)"


def _table_problems(recording: Path, frames: dict[str, object]) -> list[str]:
    """What is wrong with the Parquet tables beside ``recording`` (damaged parts, frames without rows): those of
    its run folder, or for a parts manifest those of each recorded part's folder."""
    from mmusv.recording.parts import is_parts_manifest, part_files

    missing = set(frames.get("missing", []))  # type: ignore[call-overload]
    if not is_parts_manifest(recording):
        first = frames.get("first", 0)
        expected = frames.get("expected")
        span = range(first, first + expected) if isinstance(first, int) and isinstance(expected, int) else None
        return _tables_of(recording.parent / "tables", span, missing)
    out = []
    for first, stop, f in part_files(recording):
        if f is not None:  # a part not recorded yet: its frames are said missing above
            out += _tables_of(f.parent / "tables", range(first, stop), missing)
    return out


def _tables_of(tables: Path, span: range | None, missing: set[int]) -> list[str]:
    from mmusv.recording.tables import SCHEMAS, read_table

    if not tables.is_dir():
        if span is not None and all(k in missing for k in span):  # no frame recorded, so no table either
            return []
        return [f"{tables} does not exist (a run killed before its first table flush; `mmusv recover` rebuilds it)"]
    out = []
    for name in SCHEMAS:
        got = read_table(tables, name, expected=span if name == "world_state" else None)
        got.missing = [k for k in got.missing if k not in missing]  # frames the recording lacks too: said above
        line = got.report()
        if line is not None:
            out.append(line)
    return out


def _cmd_recover(args: argparse.Namespace) -> int:
    from mmusv.recording.recover import recover

    res = recover(path_arg(args.target, flag="target"), overwrite=args.overwrite)
    for line in res.lines():
        print(line)
    return 0


def _cmd_preview(args: argparse.Namespace) -> int:
    from mmusv import arguments
    from mmusv.preview import write_preview

    path_arg(args.recording, flag="recording")
    if args.output is not None:
        output_arg(args.output)
    arguments.whole(args.frame, name="--frame", lo=0)  # -1 was "frame -1 is not in ...", not what is allowed
    out = write_preview(args.recording, frame=args.frame, agent=args.agent, output=args.output)
    print(f"wrote {out}")
    return 0


def _cmd_schema(args: argparse.Namespace) -> int:
    from mmusv.errors import IoError
    from mmusv.jsonio import write_bytes_atomic
    from mmusv.schema import schema_text

    text = schema_text(args.kind)
    if args.output is None:
        sys.stdout.write(text)
        return 0
    out = Path(output_arg(args.output, flag="-o/--output"))
    if out.is_file() and not _is_our_schema(out):  # `-o my_scenario.yaml` replaced the scenario, for good
        raise IoError(
            f"-o/--output {args.output}: the file exists and is not a schema mmusv wrote; choose another name or "
            "remove it first"
        )
    try:  # through a temporary beside it and a rename: an editor never reads half a schema
        if out.is_dir():
            raise IsADirectoryError(21, "is a folder, not a file")
        write_bytes_atomic(out, text.encode("utf-8"))
    except OSError as exc:
        raise IoError(f"-o/--output {args.output}: cannot write the schema: {exc.strerror or exc}") from None
    print(f"wrote {out}")
    return 0


def _is_our_schema(path: Path) -> bool:
    """Whether ``path`` holds a JSON Schema ``mmusv schema`` wrote (one it may replace with a newer one)."""
    import json

    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return False
    return isinstance(doc, dict) and "$schema" in doc and str(doc.get("title", "")).startswith("mmusv ")


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="mmusv", description="Headless maritime multi-USV simulator and dataset generator."
    )
    from mmusv import __version__

    p.add_argument("--version", action="version", version=f"mmusv {__version__}", help="print the version and exit")
    sub = p.add_subparsers(dest="command", required=True)
    sub.add_parser("version", help="print the version")
    p_assets = sub.add_parser("assets", help="list the vessel library")
    p_assets.add_argument("--render", metavar="DIR", help="also write a close-up PNG per asset and contact_sheet.png")
    sub.add_parser("scenarios", help="list the bundled scenarios (mmusv run NAME runs one from any directory)")
    study = sub.add_parser("study", help="reproduce the paper's experiments")
    studies = study.add_subparsers(dest="study", required=True)
    waves = studies.add_parser("waves", help="Table I: heave/roll/pitch RMS under W0..W3")
    waves.add_argument(
        "--scenario", default=BUNDLED_WAVE_SCENARIO, help=f"scenario YAML (default {BUNDLED_WAVE_SCENARIO})"
    )
    waves.add_argument(
        "-o", "--output", default="out/wave_study", help="output folder for CSV and plot (default out/wave_study)"
    )
    waves.add_argument("--frames", type=int, default=None, help="override the scenario's frame count")
    waves.add_argument(
        "--motion",
        choices=("paper", "physical"),
        default="paper",
        help="paper: Table I with the paper's formula (default); physical: every hull's response to the sea",
    )
    agree = studies.add_parser("agreement", help="Table II: 3D-box annotations vs top-view semantic rendering")
    agree.add_argument("scenarios", nargs="*", help="scenario YAMLs (default: the three bundled map scenarios)")
    agree.add_argument(
        "-o", "--output", default="out/agreement_study", help="output folder (default out/agreement_study)"
    )
    agree.add_argument("--frames", type=int, default=None, help="frames per scenario (default: all)")
    from mmusv.studies.detection.cli import add_parsers as add_detection_parsers

    add_detection_parsers(studies)
    run = sub.add_parser("run", help="run a scenario (or a folder of them) into an MCAP recording + Parquet tables")
    run.add_argument("scenario", help="scenario YAML, or a folder of scenario YAMLs")
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
    info.add_argument("recording", help="an .mcap (or .mcap.partial, .parts.json) written by mmusv run, or its folder")
    rec = sub.add_parser(
        "recover",
        help="finish the .partial recording of a killed run into a valid MCAP (summary, index) and rebuild its tables",
    )
    rec.add_argument("target", help="the run folder (holding NAME.mcap.partial) or the .partial file")
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
    schema.add_argument("-o", "--output", default=None, help="write it to this file (default: the standard output)")
    from mmusv.editor.cli import add_parser as add_editor_parser
    from mmusv.export.cli import add_parser as add_convert_parser
    from mmusv.generate.cli import add_parser as add_generate_parser
    from mmusv.learn.cli import add_parser as add_train_parser

    add_generate_parser(sub)
    add_convert_parser(sub)
    add_editor_parser(sub)
    add_train_parser(sub)
    return p


class _Signals:
    """While a command runs: SIGTERM (a ``kill``, a service manager) and SIGINT (Ctrl-C) both end it the way
    Ctrl-C always did — raised as ``KeyboardInterrupt`` in the main thread, so the current frame is finished or
    abandoned, files are closed and background jobs are stopped — and the exit status is 128 + the signal's
    number. The previous handlers come back afterwards (``main`` may be called in-process)."""

    SIGNALS = ("SIGINT", "SIGTERM")

    def __init__(self) -> None:
        self.received: int | None = None
        self._old: dict[int, object] = {}

    def _handle(self, signum: int, frame: object) -> None:
        if self.received is None:
            self.received = signum
        raise KeyboardInterrupt

    def __enter__(self) -> _Signals:
        import signal
        import threading

        if threading.current_thread() is threading.main_thread():
            for name in self.SIGNALS:
                num = getattr(signal, name, None)
                if num is not None:
                    self._old[num] = signal.signal(num, self._handle)
        return self

    def __exit__(self, *exc: object) -> None:
        import signal

        for num, old in self._old.items():
            signal.signal(num, old)  # type: ignore[arg-type]

    def status(self, default: int) -> int:
        """128 + the signal received, else ``default``."""
        return default if self.received is None else 128 + self.received


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
    with _Signals() as signals:
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
            name = "terminated (SIGTERM)" if signals.received not in (None, 2) else "interrupted"
            cli_console.say(f"mmusv: {name}")
            return signals.status(130)
        return signals.status(code)


def _dispatch(args: argparse.Namespace) -> int:
    """Runs the parsed command; returns its exit status."""
    if args.command == "version":
        from mmusv import __version__

        print(f"mmusv {__version__}")
        return 0
    if args.command == "assets":
        return _cmd_assets(args)
    if args.command == "scenarios":
        return _cmd_scenarios(args)
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
        return _cmd_run(args)
    if args.command == "info":
        return _cmd_info(args)
    if args.command == "recover":
        return _cmd_recover(args)
    if args.command == "preview":
        return _cmd_preview(args)
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
        return _cmd_schema(args)
    if args.command == "dataset":
        from mmusv.batch.cli import run_dataset

        return run_dataset(args)
    return 2


if __name__ == "__main__":
    sys.exit(main())
