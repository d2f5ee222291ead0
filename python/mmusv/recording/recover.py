"""Finishing what a killed run left behind: ``mmusv recover DIR`` / :func:`recover`.

A run killed hard (SIGKILL, a power cut, out of memory) leaves ``<name>.mcap.partial``: every chunk written before
the kill, no ``run`` metadata, no summary or index, and the tables only up to their last flush. :func:`recover`
turns it into what a stopped run leaves:

1. reads the ``.partial`` with the damage-tolerant reader (:mod:`mmusv.recording.scan`): every complete frame,
   damaged chunks skipped;
2. writes ``<name>.mcap``, a valid MCAP with summary, chunk and message indexes (the official ``mcap`` writer,
   zstd chunks), holding the metadata and every message of the complete frames in their order, and ``run``
   metadata saying ``status: interrupted``, the frames kept and where they came from;
3. rebuilds the Parquet tables of those frames from the recorded world state and annotations (the same rows and
   parts as the run would have written: :data:`mmusv.acquire.TABLE_PART_FRAMES` frames per part), replacing any
   table parts the killed run left;
4. writes ``manifest.json`` (status ``interrupted``, so a batch re-run records the scenario again) and removes the
   ``.partial`` once everything else is in place. The recording is written as ``<name>.mcap.recovering`` and the
   tables in ``tables.rebuilding``; both are put in place together at the end (a Ctrl-C or SIGTERM then waits
   until they are), and an error or a stop before that removes them: the folder is left as it was.

The messages keep their bytes; the file around them differs from the recorder's (another writer), so a
recovered recording is not byte-identical to an unbroken run's, but decodes to the same messages frame by frame.

Given a finished run (a folder without a ``.partial``, or its ``.mcap``), :func:`recover` rebuilds its tables when
they are missing or damaged (:func:`rebuild_finished_tables`; :func:`check_tables` says what is wrong, as ``mmusv
info`` does): from a whole recording they are the bytes the run wrote. Whole tables are left alone ("nothing to
recover"), and so are tables holding rows of frames that a damaged recording lacks (a rebuild would lose them).
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mmusv.errors import IoError
from mmusv.recording.guard import FolderLock
from mmusv.recording.info import RecordingInfo, another_run, check_mcap, read_info, recording_arg
from mmusv.recording.rebuild import (
    check_tables,
    install_tables,
    listed_tables,
    rebuild_tables,
    stage_tables,
    staging,
)
from mmusv.recording.scan import Scan
from mmusv.recording.stream import FrameStream
from mmusv.text import counted

__all__ = [
    "Recovered",
    "check_tables",
    "find_partial",
    "listed_tables",
    "rebuild_finished_tables",
    "rebuild_tables",
    "recover",
]

_CHUNK_BYTES = 4 << 20


@dataclass
class Recovered:
    """What :func:`recover` did: the recording written, the ``.partial`` it came from, the frames kept (of those
    the scenario configures, and of those the run set out to write), frames left out as incomplete (with why), the
    damage met and the tables folder; for a finished recording whose tables it rebuilt, what was wrong with them
    (:attr:`tables_only`)."""

    recording: Path
    source: Path
    frames: list[int]
    frames_configured: int
    incomplete: list[tuple[int, str]] = field(default_factory=list)
    damage: list[str] = field(default_factory=list)
    tables: Path | None = None
    frames_requested: int | None = None
    """The frames the run set out to write (``mmusv run --frames N``), when the recording says so."""
    tables_only: list[str] = field(default_factory=list)
    """For a finished recording whose tables were rebuilt (:func:`rebuild_finished_tables`; ``source`` is then the
    recording itself): what was wrong with them, one line each. Empty when a ``.partial`` was finished."""

    def lines(self) -> list[str]:
        """What to tell the user, one line each."""
        from mmusv.recording.stream import frames_text

        got = frames_text(self.frames) if self.frames else "no complete frame"
        if self.tables_only:
            return [
                f"rebuilt the tables of {self.recording} ({len(self.frames)} of "
                f"{counted(self.frames_requested or self.frames_configured, 'frame')}, {got}) in {self.tables}: "
                "the recording is finished, its tables were missing or damaged",
                *(f"before: {line}" for line in self.tables_only),
                *(f"left out frame {k}: {why}" for k, why in self.incomplete),
                *(f"damage: {d}" for d in self.damage),
            ]
        out = [
            f"recovered {len(self.frames)} of {counted(self.frames_requested or self.frames_configured, 'frame')} "
            f"({got}) from "
            f"{self.source} "
            f"into {self.recording}"
        ]
        out += [f"left out frame {k}: {why}" for k, why in self.incomplete]
        out += [f"damage: {d}" for d in self.damage]
        if self.tables is not None:
            out.append(f"tables rebuilt from the recording in {self.tables}")
        return out


def find_partial(target: str | os.PathLike[str]) -> Path:
    """The ``.partial`` recording ``target`` names: the file itself, or the one ``.mcap.partial`` in the folder."""
    p = Path(target)
    if not p.exists():
        raise IoError(f"{p} does not exist; recover takes a run folder or a .mcap.partial file left by a killed run")
    if p.is_dir():
        found = sorted(p.glob("*.mcap.partial"))
        if not found:
            done = sorted(p.glob("*.mcap"))
            hint = f" ({', '.join(f.name for f in done)} {'is' if len(done) == 1 else 'are'} finished)" if done else ""
            raise IoError(f"nothing to recover in {p}: it holds no .mcap.partial recording{hint}")
        if len(found) > 1:
            raise IoError(f"{p} holds {len(found)} .partial recordings ({', '.join(f.name for f in found)}); name one")
        return found[0]
    if not p.name.endswith(".mcap.partial"):
        raise IoError(f"{p}: recover takes a run folder or a .mcap.partial file left by a killed run")
    return check_mcap(p)


def _part_of(recording: Path) -> tuple[int, int] | None:
    """``(first_frame, frames)`` when ``recording`` is one part of a split recording (a parts manifest in a folder
    above it lists it), else ``None``. A killed part's ``.partial`` has no ``run`` metadata, so without this its
    recovery said nothing of where it starts, and the manifest then refused it as "a whole recording, not a
    part" (every reader of the manifest failed)."""
    from mmusv.errors import MmusvError
    from mmusv.recording.parts import PARTS_SUFFIX, read_parts_manifest

    want = recording.resolve()
    for folder in list(recording.resolve().parents)[:4]:
        for manifest in sorted(folder.glob(f"*{PARTS_SUFFIX}")):
            try:
                parts = read_parts_manifest(manifest).parts
            except MmusvError:
                continue
            for p in parts:
                if (manifest.parent / p.recording).resolve() == want:
                    return p.first_frame, p.frames
    return None


def recover(target: str | os.PathLike[str], *, overwrite: bool = False) -> Recovered:
    """Finishes the ``.partial`` recording of ``target`` (a run folder or the file; see the module docstring), or,
    for a finished recording (a run folder without a ``.partial``, or the ``.mcap``), rebuilds its tables when they
    are missing or damaged (:func:`rebuild_finished_tables`). An error or a stop (Ctrl-C, SIGTERM) on the way
    leaves the folder as it was: the recording and tables are written under temporary names, removed then, and
    put in place together at the end (a stop then waits until that is done).

    Raises:
        IoError: nothing to recover, the finished name exists (without ``overwrite``), the file is not a
            recording of ``mmusv run``, or the folder cannot be written.
    """
    src = _recover_target(target)
    # a run still writing the folder holds its lock: recovering its .partial meanwhile replaced its tables
    with FolderLock(src.parent, what="mmusv process (a run, or a recover)"):
        return _recover(src, overwrite)


def _recover(src: Path, overwrite: bool) -> Recovered:
    """:func:`recover` of the recording ``src``, its folder locked."""
    if not src.name.endswith(".partial"):
        return rebuild_finished_tables(src)
    final = src.with_name(src.name[: -len(".partial")])
    if final.exists() and not overwrite:
        raise IoError(f"{final} already exists; pass --overwrite to replace it with the recovery of {src.name}")
    info = read_info(src)
    folder = src.parent
    other = None if overwrite else another_run(folder, final.name)
    if other is not None:  # its tables and manifest.json would be rebuilt from this one's: the other run's lost
        raise IoError(
            f"{folder} holds the run of another recording, {other} (its manifest.json and tables/), which "
            f"recovering {src.name} there would replace; move {src.name} into a folder of its own first, or pass "
            f"--overwrite to replace them ({other} itself is kept); {src} is left as it was"
        )
    tables_dir = folder / "tables"
    staged = staging(tables_dir)
    tmp = final.with_name(final.name + ".recovering")
    try:
        return _finish(src, info, final, tmp, staged, tables_dir)
    except BaseException:  # an error or a stop (KeyboardInterrupt): the temporary file goes, the .partial stays
        tmp.unlink(missing_ok=True)
        raise
    finally:
        shutil.rmtree(staged, ignore_errors=True)


def _recover_target(target: str | os.PathLike[str]) -> Path:
    """The recording ``target`` names for :func:`recover`: its ``.partial`` (:func:`find_partial`), else, in a
    run folder without one, its one finished ``.mcap``, or the ``.mcap`` named."""
    p = Path(target)
    if not p.exists():
        raise IoError(
            f"{p} does not exist; recover takes a run folder, a .mcap.partial file left by a killed run, or a "
            "finished .mcap whose tables are missing or damaged"
        )
    if p.is_dir() and not any(p.glob("*.mcap.partial")):
        done = sorted(p.glob("*.mcap"))
        if len(done) > 1:
            raise IoError(
                f"{p} holds {len(done)} finished recordings ({', '.join(f.name for f in done)}) and no .partial; "
                "name the one whose tables to rebuild"
            )
        if done:
            return check_mcap(done[0])
        split = sorted(f.name for f in p.glob("*.parts.json"))
        hint = f" ({split[0]} is a split run: give the folder of one of its parts)" if split else _runs_below(p)
        raise IoError(
            f"nothing to recover in {p}: it holds no .mcap.partial recording of a killed run, nor a finished .mcap"
            + hint
        )
    if p.is_file() and p.name.endswith(".mcap"):
        return check_mcap(p)
    if not p.is_dir() and not p.name.endswith(".mcap.partial"):
        raise IoError(
            f"{p}: recover takes a run folder, a .mcap.partial file left by a killed run, or a finished .mcap "
            "whose tables are missing or damaged"
        )
    return find_partial(p)


def _runs_below(folder: Path) -> str:
    """For a folder of runs (a batch's ``OUT``, a dataset's ``recordings/``) given to recover: the run folders below
    it holding a killed run's ``.partial`` (``mmusv recover`` takes one at a time), else the finished ones, as
    ``" (it is a folder of runs: 2 below it hold a killed run's .partial: OUT/a, OUT/b; recover each: mmusv recover
    OUT/a)"``; ``""`` when none is below it or it cannot be read."""
    from mmusv.recording.folders import find_recordings

    try:
        found = find_recordings(folder, unfinished=True)
    except IoError:
        return ""
    killed = sorted({f.parent for f in found if f.name.endswith(".mcap.partial")})
    done = sorted({f.parent for f in found if f.suffix == ".mcap"})
    runs, what = (killed, "a killed run's .partial") if killed else (done, "a finished recording")
    if not runs:
        return ""
    shown = ", ".join(str(r) for r in runs[:3]) + (", ..." if len(runs) > 3 else "")
    many = f"{len(runs)} below it hold" if len(runs) > 1 else "one below it holds"
    todo = "recover each" if killed else "to rebuild a run's tables, give its folder"
    return f" (it is a folder of runs: {many} {what}: {shown}; {todo}: mmusv recover {runs[0]})"


def rebuild_finished_tables(recording: str | os.PathLike[str]) -> Recovered:
    """Rebuilds the tables of the finished recording ``recording`` from it (:func:`rebuild_tables`) when they are
    missing or damaged (:func:`check_tables`): the parts its run wrote, byte for byte, for a whole recording. The
    recording and ``manifest.json`` are left as they are. Refused (:class:`~mmusv.errors.IoError`, nothing
    changed): whole tables (nothing to recover), tables of another recording's run in the folder, a recording of
    no readable frame, and a damaged recording lacking frames whose rows the tables still hold (a rebuild would
    lose them)."""
    from mmusv.recording.stream import frames_text

    rec = check_mcap(recording_arg(recording))
    folder = rec.parent
    tables_dir = folder / "tables"
    other = another_run(folder, rec.name)
    if other is not None:
        raise IoError(
            f"{folder} holds the run of another recording, {other}: its tables/ are that run's, not those of "
            f"{rec.name}; move {rec.name} into a folder of its own to rebuild its tables there; nothing changed"
        )
    if tables_dir.exists() and not tables_dir.is_dir():
        raise IoError(
            f"{tables_dir} is not a folder, where {rec.name}'s run keeps its tables; move it away and run recover "
            "again to rebuild them; nothing changed"
        )
    info = read_info(rec)
    listed = listed_tables(folder, rec.name)
    held = FrameStream(info, lambda _t: False).held()[0]  # as the run metadata says, before reading every chunk
    problems, _ = check_tables(tables_dir, held, listed=listed)
    if not problems:  # the recording is read through before it is called finished: a copy may be cut or damaged
        whole = FrameStream(info, lambda _t: False)
        for _ in whole:
            pass
        report = whole.report()
        if report is None:
            raise IoError(f"nothing to recover in {folder}: {rec.name} is finished and its tables are whole")
        raise IoError(
            f"nothing to recover in {folder}: the tables of {rec.name} are whole, but the recording is not "
            f"({report}); recover finishes a killed run's .partial and rebuilds tables, it does not mend a damaged "
            "recording: restore it from a whole copy or record the scenario again"
        )
    staged = staging(tables_dir)
    try:
        stream = stage_tables(rec, staged)
        got = sorted(set(stream.yielded))
        if not got:
            raise IoError(
                f"{rec} holds no readable frame to rebuild its tables from ({'; '.join(problems)}); "
                f"{tables_dir} is left as it was"
            )
        span = stream.expected()[0]
        lacking = [k for k in span if k not in set(got)]
        problems, lost = check_tables(tables_dir, span, lacking, listed=listed)
        if lost:
            raise IoError(
                f"{rec} lacks {frames_text(lost)}, whose rows its tables still hold: tables rebuilt from it "
                f"would lose them; {tables_dir} is left as it was ({'; '.join(problems)})"
            )
        if not problems:  # the tables lack only frames the recording lacks too: a rebuild gives them back as they are
            raise IoError(
                f"nothing to recover in {folder}: the tables of {rec.name} hold every frame it holds "
                f"({stream.report()})"
            )
        install_tables(staged, tables_dir)
    finally:
        shutil.rmtree(staged, ignore_errors=True)
    return Recovered(
        recording=rec,
        source=rec,
        frames=got,
        frames_configured=info.frames_configured,
        frames_requested=len(span),
        incomplete=list(stream.incomplete),
        damage=list(stream.damage),
        tables=tables_dir,
        tables_only=problems,
    )


def _finish(src: Path, info: RecordingInfo, final: Path, tmp: Path, staged: Path, tables_dir: Path) -> Recovered:
    """:func:`recover` of the ``.partial`` ``src`` into ``final`` (written as ``tmp``), its tables built in
    ``staged``; the caller removes ``tmp`` and ``staged`` on the way out."""
    from mcap.writer import CompressionType, Writer

    from mmusv.held_signals import HeldSignals

    planned = info.planned[1] if info.planned is not None else info.frames_configured
    folder = src.parent
    # pass 1: which frames are complete (and their tables)
    stream = stage_tables(src, staged)
    keep = set(stream.yielded)
    if not keep:
        # Nothing to finish: a recording of no frame would replace the .partial (and its chance of a better tool).
        raise IoError(
            f"{src} holds no complete frame (the run stopped before its first frame was written, or the file is "
            "damaged there): nothing to recover; it is left as it was"
        )
    times = {round(k / info.frequency_hz * 1e9) for k in keep} if info.frequency_hz > 0 else set()
    # pass 2: copy their messages into a finished MCAP
    scan = Scan(src)
    try:
        with tmp.open("wb") as f:
            # the data section's CRC too (the writer leaves it 0 unless asked): damage outside the chunks is then seen
            w = Writer(f, chunk_size=_CHUNK_BYTES, compression=CompressionType.ZSTD, enable_data_crcs=True)
            w.start(profile="", library="mmusv recover")
            # the scenario, manifest and sensors metadata first, as mmusv run writes them: a copy of the recovered
            # file cut short still reads up to the cut (written after the messages, such a copy held no frame)
            head = Scan(src, chunks=False)
            for _ in head.messages():
                pass
            for name in ("scenario", "manifest", "sensors"):
                if name in head.metadata:
                    w.add_metadata(name, head.metadata[name])
            schemas: dict[int, int] = {}
            channels: dict[int, int] = {}
            for msg, dmg in scan.messages():
                if dmg is not None or msg.log_time not in times:
                    continue
                ch = scan.channels.get(msg.channel_id)
                if ch is None:
                    continue
                if ch.id not in channels:
                    sc = scan.schemas.get(ch.schema_id)
                    if sc is not None and sc.id not in schemas:
                        schemas[sc.id] = w.register_schema(sc.name, sc.encoding, sc.data)
                    channels[ch.id] = w.register_channel(
                        ch.topic, ch.message_encoding, schemas.get(ch.schema_id, 0), dict(ch.metadata)
                    )
                w.add_message(channels[ch.id], msg.log_time, msg.data, msg.publish_time, msg.sequence)
            run = dict(scan.metadata.get("run", {}))
            run.update(
                scenario=info.scenario_name,
                status="interrupted",
                frames_written=str(len(keep)),
                frames_configured=str(info.frames_configured),
                frequency_hz=str(info.frequency_hz),
                agents=",".join(a.id for a in info.agents),
                recovered_from=f"{src.name}: {len(keep)} complete frames"
                + (f", {len(stream.incomplete)} incomplete left out" if stream.incomplete else ""),
            )
            run.pop("frames_requested", None)
            part = _part_of(final)
            if part is not None:  # one part of a split recording: its manifest checks where it starts
                run["first_frame"] = str(part[0])
            elif "first_frame" in run and keep:
                run["frames_requested"] = str(len(keep))
            elif info.planned is not None and (info.planned[0] > 0 or info.planned_range):
                # a frame range recorded alone (acquire.run(frame_range=...)), or a part recovered away from its
                # parts manifest: the manifest metadata, written before the first frame, says where it starts (the
                # recovered run and manifest.json said nothing of it, as for a whole run from frame 0); a range
                # from frame 0 (a split run's part 0) says frame_range there, as a whole run cut short does not
                run["first_frame"] = str(info.planned[0])
            w.add_metadata("run", run)
            w.finish()  # type: ignore[no-untyped-call]
            f.flush()
            os.fsync(f.fileno())
    except OSError as exc:
        raise IoError(f"cannot write {final}: {exc.strerror or exc}; {src} is left as it was") from None
    # the recording, its tables and manifest.json put in place together: a stop waits until they are
    with HeldSignals():
        try:
            os.replace(tmp, final)
        except OSError as exc:
            raise IoError(f"cannot write {final}: {exc.strerror or exc}; {src} is left as it was") from None
        install_tables(staged, tables_dir)
        manifest_path = folder / "manifest.json"
        if (folder / "scenario.yaml").is_file() or manifest_path.is_file() or tables_dir.is_dir():
            from mmusv.jsonio import write_json

            meta = scan.metadata.get("manifest", {})
            manifest: dict[str, Any] = {
                "mmusv_version": meta.get("mmusv_version", info.mmusv_version),
                "scenario": info.scenario_name,
                "seed": info.seed,
                "config_hash": info.config_hash,
                "status": "interrupted",
                "frames_written": len(keep),
                "frames_requested": int(run.get("frames_requested", planned)),
                "frequency_hz": info.frequency_hz,
                "agents": [a.id for a in info.agents],
                "recording": final.name,
                "tables": sorted(p.name for p in tables_dir.iterdir()) if tables_dir.is_dir() else [],
                "recovered_from": src.name,
            }
            if "first_frame" in run:
                manifest["first_frame"] = int(run["first_frame"])
            write_json(manifest_path, manifest)
        src.unlink()
    return Recovered(
        recording=final,
        source=src,
        frames=sorted(keep),
        frames_configured=info.frames_configured,
        frames_requested=planned,
        incomplete=list(stream.incomplete),
        damage=list(stream.damage),
        tables=tables_dir,
    )
