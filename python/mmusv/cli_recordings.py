"""The subcommands that read a recorded run: ``mmusv info`` (agents, topics, frames and duration; damage,
missing frames and table problems), ``mmusv preview`` (one picture of a frame) and ``mmusv recover`` (a killed
run's ``.partial`` finished into a valid recording).
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mmusv.cli_console import rich_console
from mmusv.cli_paths import output_arg, path_arg
from mmusv.errors import MmusvError
from mmusv.text import counted

if TYPE_CHECKING:
    from mmusv.recording.folders import MissingRecording

__all__ = ["cmd_info", "cmd_preview", "cmd_recover"]


def cmd_info(args: argparse.Namespace) -> int:
    from rich.table import Table
    from rich.text import Text

    from mmusv.recording import summary
    from mmusv.recording.folders import find_recordings, missing_recordings, unreadable_listings
    from mmusv.recording.info import recording_name

    target = Path(path_arg(args.recording, flag="recording"))
    folder: Path | None = None
    if target.is_dir():  # a run folder: its recording (finished, else the .partial) and its tables
        folder = target
        found = sorted(target.glob("*.parts.json")) or sorted(target.glob("*.mcap"))
        found = found or sorted(target.glob("*.mcap.partial"))
        if not found:
            below = find_recordings(target, unfinished=True)
            gone = missing_recordings(target)
            own = [m for m in gone if m.path.parent == target]
            if own and not below:  # a run folder whose recording is gone
                raise MmusvError(
                    f"{target} is a folder without a recording: {own[0].path.name} is gone, though "
                    + " and ".join(f"{by.name} names it ({what})" for by, what in own[0].named_by)
                )
            damaged = unreadable_listings(target)  # a dataset.json that no longer reads: said, not passed over
            if below or gone or damaged:  # a batch's output folder: one line per recording
                return _overview(target, below, gone, damaged)
            raise MmusvError(f"{target} is a folder without a recording (*.mcap, *.mcap.partial or *.parts.json)")
        if len(found) > 1:
            raise MmusvError(f"{target} holds {len(found)} recordings ({', '.join(f.name for f in found)}); name one")
        target = found[0]
    info = summary(target)
    console = rich_console()
    meta = info.get("metadata", {})
    run_meta = meta.get("run", {})
    frames = info.get("frames") or {}
    if not info.get("complete", True):
        from mmusv.recording.parts import is_parts_manifest

        if is_parts_manifest(target):  # no part is a .partial or damaged when one was not recorded yet
            what = "incomplete split recording (a part not recorded, unfinished or damaged): counts come from reading "
            what += "every part's chunks"
        else:
            what = "incomplete recording (.partial, no summary or damaged): counts come from reading every chunk"
        console.print(f"[yellow]{what}[/yellow]", markup=True)
    if info.get("frames") is None:  # an MCAP file, but not a recording of mmusv run: its messages only
        from mmusv.recording.info import ends_in_header

        if ends_in_header(target):  # its header, which names the program that wrote it, is cut off
            why = "the file ends inside its MCAP header (which program wrote it cannot be told)"
        elif info.get("metadata_problem"):
            why = "its mmusv metadata cannot be read"
        else:
            why = "an MCAP file not written by mmusv run (no scenario/sensors metadata)"
        console.print(Text.assemble((str(target), "bold"), f": {why}: its messages only"), highlight=False)
    else:
        written = run_meta.get("frames_written", "?")
        if frames:  # the complete frames read: a killed run's .partial has no run metadata saying it ("? frames")
            read, expected = frames["read"], frames["expected"]
            written = counted(read, "frame") if read == expected else f"{read} of {counted(expected, 'frame')}"
        elif isinstance(written, int) or (isinstance(written, str) and written.isdigit()):  # a parts manifest's "4"
            written = counted(int(written), "frame")
        else:
            written = f"{written} frames"
        console.print(
            Text.assemble(
                (str(target), "bold"),
                f": scenario {run_meta.get('scenario') or _scenario_of(meta, target)}, "
                f"status {_status(run_meta, info, _UNSAID)}"
                f", {written}, agents {run_meta.get('agents') or _agents_of(meta)}",
            ),
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
        table.add_row(Text(topic), Text(t["schema"]), str(t["messages"]))
    console.print(table)
    problems = [frames["report"]] if frames and frames.get("report") else list(info.get("damage", []))
    if info.get("metadata_problem"):  # "unreadable ... metadata (...)": it was shown as a file of another program
        problems.insert(0, info["metadata_problem"])
    rebuild: list[Path] = []
    if folder is not None and frames:
        tables, rebuild = _table_problems(target, frames)
        problems += tables
    for line in problems:
        console.print(f"mmusv: warning: {line}", markup=False, highlight=False, style="yellow")
    for run_folder in rebuild:
        console.print(
            f"`mmusv recover {run_folder}` rebuilds the tables from the recording", markup=False, highlight=False
        )
    if target.name.endswith(".mcap.partial"):
        if frames and frames.get("read"):
            console.print(
                f"`mmusv recover {target.parent}` finishes it into {recording_name(target)}.mcap with its tables"
            )
        else:  # recover refuses a .partial without a complete frame: nothing to finish
            console.print(
                f"it holds no complete frame: nothing to recover (`mmusv run` on {target.parent} records it again)"
            )
    # Exit 1 when not one frame reads, as a folder's overview does for such a row: there is nothing to convert,
    # study or preview (a damaged or unfinished recording that reads in part warns and exits 0).
    if frames:
        return 1 if not frames.get("read") and frames.get("expected") else 0
    return 1 if info.get("frames") is None and problems and not info.get("messages") else 0


_UNSAID = "unfinished (no run metadata: the run was killed or is still going)"
"""The status of a recording without ``run`` metadata, which a run writes last."""


def _status(run_meta: dict[str, str], info: dict[str, Any], unsaid: str) -> str:
    """The run's status as its ``run`` metadata says (``unsaid`` without it), and, for a run that says
    ``complete`` in a file that is damaged or cut, that the file is not: a bare "complete" beside frames lost to the
    damage read as a whole recording."""
    status = str(run_meta.get("status", unsaid))
    return f"{status} (file damaged)" if status == "complete" and not info.get("complete", True) else status


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


def _overview(folder: Path, found: list[Path], gone: list[MissingRecording], damaged: list[tuple[Path, str]]) -> int:
    """``mmusv info`` on a folder of recordings: one row each (scenario, status, frames, agents, problems), and one
    for each recording that a ``dataset.json`` or a run's ``manifest.json`` below names but that is gone
    (:func:`~mmusv.recording.folders.missing_recordings`), and one for each such file that cannot be read
    (:func:`~mmusv.recording.folders.unreadable_listings`). Exits 1 when a recording is gone, cannot be read at all
    (``mmusv info`` on it alone is an error too) or holds no readable frame (a killed run's ``.partial`` of none,
    a file damaged throughout): a dataset to convert or study lacks it. A damaged or unfinished one that reads is
    a row with its problems, as ``mmusv info`` on it alone warns and exits 0."""
    from rich.table import Table
    from rich.text import Text

    from mmusv.recording import summary

    def short(name: str, problems: list[str]) -> str:  # relative paths, cut: `mmusv info` on one says it all
        text = "; ".join(problems).replace(f"{folder}{os.sep}", "").removeprefix(f"{name}: ")
        return text if len(text) <= 100 else text[:99] + "…"

    def rel(p: Path) -> str:
        try:
            return str(p.relative_to(folder))
        except ValueError:
            return str(p)

    closed = [rec for rec in found if rec.is_dir()]  # folders below that could not be searched (find_recordings)
    title = f"{counted(len(found) - len(closed), 'recording')} below {folder}"
    title += f", {len(gone)} missing" if gone else ""
    title += f", {counted(len(damaged), 'listing')} that cannot be read" if damaged else ""
    table = Table(title=Text(title + (f", {counted(len(closed), 'folder')} that cannot be read" if closed else "")))
    for col in ("recording", "scenario", "status", "frames", "agents", "problems"):
        table.add_column(col, overflow="fold")
    troubled = unreadable = empty = 0
    rows: list[tuple[str, tuple[str, ...]]] = []
    for m in gone:
        name = rel(m.path)
        named = " and ".join(f"{rel(by)} ({what})" for by, what in m.named_by)
        count = "?" if m.frames_requested is None else f"0 of {m.frames_requested}"
        why = f"gone; named by {named}"
        rows.append((name, (name, m.scenario or "?", "missing", count, ",".join(m.agents) or "?", short(name, [why]))))
    for f, why in damaged:
        name = rel(f)
        rows.append((name, (name, "?", "unreadable listing", "?", "?", short(name, [why]))))
    for rec in found:
        name = str(rec.relative_to(folder))
        if rec in closed:
            unreadable += 1
            try:
                os.listdir(rec)
                why = "the folder could not be read when it was searched (it can now: run again)"
            except OSError as exc:
                why = f"cannot read the folder: {exc.strerror or type(exc).__name__}"
            rows.append((name, (name, "?", "unreadable", "?", "?", why)))
            continue
        try:
            info = summary(rec)
        except MmusvError as exc:
            troubled += 1
            unreadable += 1
            rows.append((name, (name, "?", "unreadable", "?", "?", short(name, [str(exc)]))))
            continue
        meta = info.get("metadata", {})
        run_meta = meta.get("run", {})
        frames = info.get("frames") or {}
        if info.get("frames") is None:
            troubled += 1
            hurt = [info["metadata_problem"]] if info.get("metadata_problem") else list(info.get("damage", []))
            if hurt and not info.get("messages"):  # damaged throughout: not one message reads
                empty += 1
            rows.append((name, (name, "?", "not a recording of mmusv run", "?", "?", short(name, hurt))))
            continue
        problems = [frames["report"]] if frames.get("report") else list(info.get("damage", []))
        problems += _table_problems(rec, frames)[0]
        troubled += bool(problems) or not info.get("complete", True)
        read, expected = frames.get("read"), frames.get("expected")
        empty += not read and bool(expected)
        cells: tuple[str, ...] = (
            name,
            str(run_meta.get("scenario") or _scenario_of(meta, rec)),
            _status(run_meta, info, "unfinished"),
            f"{read}" if read == expected else f"{read} of {expected}",
            str(run_meta.get("agents") or _agents_of(meta)),
            short(name, problems),
        )
        rows.append((name, cells))
    for _name, cells in sorted(rows, key=lambda r: Path(r[0])):  # (the order of find_recordings)
        table.add_row(*map(Text, cells))  # Text: a name like a[/b] is no markup
    console = rich_console()
    console.print(table)
    if troubled:
        console.print(
            f"{counted(troubled, 'recording')} unfinished, damaged or unreadable: `mmusv info` on one says more",
            markup=False,
            highlight=False,
        )
    if empty:
        console.print(
            f"{counted(empty, 'recording')} {'holds' if empty == 1 else 'hold'} no readable frame",
            markup=False,
            highlight=False,
        )
    if gone:
        console.print(
            f"{counted(len(gone), 'recording')} missing: named by the batch's dataset.json or its run's manifest.json, "
            "but not there (a batch re-run records it again)",
            markup=False,
            highlight=False,
        )
    if closed:
        console.print(
            f"{counted(len(closed), 'folder')} below cannot be read: the recordings in it are not listed",
            markup=False,
            highlight=False,
        )
    if damaged:
        console.print(
            f"{counted(len(damaged), 'file')} listing recordings (dataset.json, manifest.json) cannot be read: "
            "whether the recordings they name are there is not checked",
            markup=False,
            highlight=False,
        )
    return 1 if unreadable or empty or gone or damaged else 0


def _table_problems(recording: Path, frames: dict[str, object]) -> tuple[list[str], list[Path]]:
    """What is wrong with the Parquet tables beside ``recording`` (a missing folder, damaged parts, frames without
    rows): those of its run folder, or for a parts manifest those of each recorded part's folder; and the run
    folders whose tables ``mmusv recover`` rebuilds from their finished recording (a ``.partial``'s recovery
    rebuilds them anyway; none where the recording lacks frames whose rows the tables still hold, which recover
    refuses to lose)."""
    from mmusv.recording.parts import is_parts_manifest, part_files

    missing = set(frames.get("missing", []))  # type: ignore[call-overload]
    if not is_parts_manifest(recording):
        first = frames.get("first", 0)
        expected = frames.get("expected")
        span = range(first, first + expected) if isinstance(first, int) and isinstance(expected, int) else None
        return _tables_of(recording, span, missing)
    out: list[str] = []
    rebuild: list[Path] = []
    for first, stop, f in part_files(recording):
        if f is not None:  # a part not recorded yet: its frames are said missing above
            lines, folders = _tables_of(f, range(first, stop), missing)
            out += lines
            rebuild += folders
    return out, rebuild


def _tables_of(recording: Path, span: range | None, missing: set[int]) -> tuple[list[str], list[Path]]:
    from mmusv.recording.info import recording_name
    from mmusv.recording.rebuild import check_tables, listed_tables

    tables = recording.parent / "tables"
    try:
        problems, held = check_tables(tables, span, missing, listed=listed_tables(recording.parent, recording.name))
    except MmusvError as exc:  # a tables folder that holds no tables (read_table says what it holds)
        return [str(exc)], []
    partial = recording.name.endswith(".partial")
    killed = recording.with_name(recording.name + ".partial")
    if not partial and killed.exists():
        # a later run of it (mmusv run --overwrite) killed: the earlier recording stays until the new one finishes,
        # but its manifest, tables and scenario.yaml were replaced when the new one opened; shown as complete and
        # whole, the folder read as the earlier run's while its tables held the killed run's frames
        problems.insert(
            0,
            f"{killed} lies beside it: a later run of it (mmusv run --overwrite) was killed, so the tables and "
            f"scenario.yaml here are that run's, not {recording.name}'s; `mmusv recover {recording.parent} "
            f"--overwrite` finishes it into {recording.name} with its tables",
        )
        return problems, []
    if problems and problems[0].startswith(f"{tables} does not exist"):
        why = (
            f"a run killed before its first table flush; `mmusv recover {recording.parent}` rebuilds it"
            if partial
            else f"`mmusv recover {recording.parent}` rebuilds it from {recording_name(recording)}.mcap"
        )
        problems[0] += f" ({why})"
        return problems, []
    rebuilds = (  # as recover does: a finished recording of some frame, beside a tables folder it may replace
        bool(problems) and not partial and not held and tables.is_dir() and any(k not in missing for k in span or ())
    )
    return problems, [recording.parent] if rebuilds else []


def cmd_recover(args: argparse.Namespace) -> int:
    from mmusv.recording.recover import recover

    res = recover(path_arg(args.target, flag="target"), overwrite=args.overwrite)
    for line in res.lines():
        print(line)
    return 0


def cmd_preview(args: argparse.Namespace) -> int:
    from mmusv import arguments
    from mmusv.preview import write_preview
    from mmusv.text import command_line

    path_arg(args.recording, flag="recording")
    if args.output is not None:
        output_arg(args.output)
    arguments.whole(args.frame, name="--frame", lo=0)  # -1 was "frame -1 is not in ...", not what is allowed
    # the API's messages name the flags typed (`--frame 5: not in ...`, not `frame = 5`)
    with command_line({"frame": "--frame", "agent": "--agent", "output": "-o/--output"}):
        out = write_preview(args.recording, frame=args.frame, agent=args.agent, output=args.output)
    print(f"wrote {out}")
    return 0
