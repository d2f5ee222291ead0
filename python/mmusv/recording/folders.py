"""The recordings in a folder and below it: those there (:func:`find_recordings`: every ``.mcap`` and parts
manifest, a killed run's ``.partial`` on request, through links to folders too), those a batch's ``dataset.json``
or a run's ``manifest.json`` names but that are gone (:func:`missing_recordings`), and those files when they no
longer read (:func:`unreadable_listings`): what ``mmusv info`` on a batch's folder lists, and what the exports and
studies read from a folder. One recording's own metadata: :mod:`mmusv.recording.info`.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mmusv import arguments
from mmusv.errors import IoError
from mmusv.recording.parts import read_parts_manifest

__all__ = ["MissingRecording", "find_recordings", "folder_hint", "missing_recordings", "unreadable_listings"]


def find_recordings(folder: str | os.PathLike[str], *, unfinished: bool = False) -> list[Path]:
    """The recordings below ``folder``, sorted: every parts manifest and every ``.mcap`` that is not one of a
    manifest's parts. Folders reached through a link are searched too (a batch's run folders may be links), each
    once. ``folder`` must be an existing folder (:class:`~mmusv.errors.IoError` otherwise).

    ``unfinished=True`` (``mmusv info`` on a batch's folder, which reports what is wrong with each) also lists
    every ``.mcap.partial`` of a killed run beside no ``.mcap``, keeps an unreadable parts manifest and lists a
    folder below that cannot be read (without it, each is an :class:`~mmusv.errors.IoError`: its recordings would
    be left out without a word); a readable manifest's parts stay out, ``.partial`` or not."""
    root = arguments.path(folder, name="folder")
    if not root.is_dir():
        what = "does not exist" if not root.exists() else "is not a folder"
        raise IoError(f"folder = {root} {what}: give a folder holding recordings (.mcap or .parts.json)")
    try:
        os.scandir(root).close()
    except OSError as exc:
        raise IoError(f"folder = {root} cannot be read ({exc.strerror or type(exc).__name__})") from None
    files, closed = _files_below(root)
    if closed and not unfinished:
        where, why = closed[0]
        more = f" (and {len(closed) - 1} more)" if len(closed) > 1 else ""
        raise IoError(
            f"{root}: cannot read the folder {where} below it ({why}){more}: the recordings in it would be left out"
        )
    manifests = sorted(f for f in files if f.name.endswith(".parts.json"))
    parts: set[Path] = set()
    for m in manifests:
        try:
            named = read_parts_manifest(m).parts
        except IoError:
            if not unfinished:
                raise
            continue  # listed: what reads it says what is wrong with it
        for part in named:
            rec = (m.parent / part.recording).resolve()
            parts |= {rec, rec.with_name(rec.name + ".partial")}
    mcaps = [f for f in files if f.suffix == ".mcap" and f.resolve() not in parts]
    partial = (
        [f for f in files if f.name.endswith(".mcap.partial") and not f.with_suffix("").exists()] if unfinished else []
    )
    return sorted([*manifests, *mcaps, *(f for f in partial if f.resolve() not in parts), *(c for c, _ in closed)])


def folder_hint(folder: Path) -> str:
    """For an error about a folder given where a recording file was wanted (``mmusv preview out/run``): the
    recordings right in it (a run folder's ``NAME.mcap``, a split run's ``NAME.parts.json``, a killed run's
    ``NAME.mcap.partial``), as ``"; it holds out/run/NAME.mcap: give that"`` (``"; it holds 2 recordings (a.mcap,
    b.mcap): give one of them"``); ``""`` when it holds none or cannot be read. Only the folder itself is looked
    at, not the folders below it."""
    try:
        names = sorted(e.name for e in os.scandir(folder) if e.is_file())
    except OSError:
        return ""
    manifests = [n for n in names if n.endswith(".parts.json")]
    mcaps = [n for n in names if n.endswith(".mcap")]
    partial = [n for n in names if n.endswith(".mcap.partial") and n.removesuffix(".partial") not in names]
    found = [*manifests, *mcaps, *partial]  # a split run's parts are in folders below it, not listed
    if not found:
        return ""
    if len(found) == 1:
        return f"; it holds {folder / found[0]}: give that"
    shown = ", ".join(found[:3]) + (", ..." if len(found) > 3 else "")
    return f"; it holds {len(found)} recordings ({shown}): give one of them"


@dataclass(frozen=True)
class MissingRecording:
    """A recording that a file below a folder names but that is not there (:func:`missing_recordings`): ``path``
    where it should be; ``named_by``, each file naming it with what it says (``(dataset.json, "c: status
    complete")``); the scenario, agents and frames that file gives, when it does."""

    path: Path
    named_by: tuple[tuple[Path, str], ...]
    scenario: str | None = None
    agents: tuple[str, ...] = ()
    frames_requested: int | None = None


def missing_recordings(folder: str | os.PathLike[str]) -> list[MissingRecording]:
    """The recordings that are named below ``folder`` but gone (``mmusv info`` on a batch's folder lists them: left
    out, a batch looked whole where a run had lost its recording): those a batch's ``dataset.json`` lists as
    ``complete`` (what ``mmusv convert`` reads, and refuses when one is gone) and those a run folder's
    ``manifest.json`` names (written once the run has its recording), each neither there nor as its ``.partial``
    (a broken link is there: its reader says what is wrong). Sorted by path; a file naming it that is not an index
    or a manifest of mmusv, or names nothing below its folder, is passed over. ``folder`` as for
    :func:`find_recordings` (folders below that cannot be read are skipped: that lists them)."""
    root = arguments.path(folder, name="folder")
    if not root.is_dir():
        return []
    files, _closed = _files_below(root)
    found: dict[Path, MissingRecording] = {}

    def note(path: Path, by: Path, what: str, doc: dict[str, Any]) -> None:
        if os.path.lexists(path) or (path.suffix == ".mcap" and os.path.lexists(f"{path}.partial")):
            return
        key = Path(os.path.realpath(path.parent)) / path.name  # (named by the index and, through a link, its run)
        agents, frames = doc.get("agents"), doc.get("frames_requested")
        this = MissingRecording(
            path=path,
            named_by=((by, what),),
            scenario=_text(doc.get("scenario")),
            agents=tuple(map(str, agents)) if isinstance(agents, list) else (),
            frames_requested=frames if isinstance(frames, int) and not isinstance(frames, bool) else None,
        )
        had = found.get(key)
        found[key] = (
            this
            if had is None
            else MissingRecording(
                path=had.path,
                named_by=had.named_by + this.named_by,
                scenario=had.scenario or this.scenario,
                agents=had.agents or this.agents,
                frames_requested=this.frames_requested if had.frames_requested is None else had.frames_requested,
            )
        )

    for f in files:
        if f.name not in ("dataset.json", "manifest.json"):
            continue
        try:
            doc = json.loads(f.read_bytes())
        except (OSError, ValueError):
            continue
        if not isinstance(doc, dict):
            continue
        if f.name == "manifest.json":
            rec = doc.get("recording")
            if _plain_name(rec) and isinstance(doc.get("status"), str):
                note(f.parent / str(rec), f, f"status {doc['status']}", doc)
            continue
        entries = doc.get("recordings") if doc.get("format") == "mmusv.dataset" else None
        for r in entries if isinstance(entries, list) else []:
            rel = r.get("recording") if isinstance(r, dict) else None
            if not isinstance(r, dict) or r.get("status") != "complete" or not isinstance(rel, str):
                continue
            parts = Path(rel).parts
            if not parts or Path(rel).is_absolute() or ".." in parts or "\\" in rel:
                continue
            note(f.parent / rel, f, f"{r.get('name')}: status complete", r)
    return sorted(found.values(), key=lambda m: str(m.path))


def unreadable_listings(folder: str | os.PathLike[str]) -> list[tuple[Path, str]]:
    """The files below ``folder`` that would say which recordings belong there but cannot be read, each with why:
    a batch's ``dataset.json`` or a run's ``manifest.json`` written by mmusv (its bytes name ``mmusv``) that is no
    longer JSON (cut short, damaged), and a ``dataset.json`` of mmusv's format that :func:`mmusv.batch.index.
    read_index` refuses. :func:`missing_recordings` passes over what they name, as it passes over files of those
    names that other tools wrote (which do not name ``mmusv``). Sorted by path; ``folder`` as for
    :func:`find_recordings`."""
    from mmusv.batch.index import INDEX_FORMAT, read_index
    from mmusv.errors import MmusvError

    root = arguments.path(folder, name="folder")
    if not root.is_dir():
        return []
    out: list[tuple[Path, str]] = []
    for f in _files_below(root)[0]:
        if f.name not in ("dataset.json", "manifest.json"):
            continue
        try:
            raw = f.read_bytes()
        except OSError as exc:
            out.append((f, f"cannot be read: {exc.strerror or type(exc).__name__}"))
            continue
        if b'"mmusv' not in raw:
            continue  # another tool's file of that name
        try:
            doc = json.loads(raw)
        except ValueError as exc:
            out.append((f, f"not JSON: {exc}"))
            continue
        if not isinstance(doc, dict):
            out.append((f, f"holds a JSON {type(doc).__name__}, not an object"))
        elif f.name == "dataset.json" and doc.get("format") == INDEX_FORMAT:
            try:
                read_index(f)
            except MmusvError as exc:
                out.append((f, str(exc).removeprefix(f"{f}: ")))
    return sorted(out, key=lambda x: str(x[0]))


def _plain_name(name: object) -> bool:
    """Whether ``name`` is a file name (no folder, not ``.`` or ``..``)."""
    return isinstance(name, str) and name not in ("", ".", "..") and "/" not in name and "\\" not in name


def _text(value: object) -> str | None:
    return value if isinstance(value, str) and value else None


def _files_below(root: Path) -> tuple[list[Path], list[tuple[Path, str]]]:
    """Every entry below ``root`` that is not a folder (a file, or a broken link, listed so that what reads it says
    what is wrong), through links to folders too: the real folders first, so that a recording is named by its own
    path where it has one below ``root``, then each folder reached only through a link; each real folder once (a
    link back up the tree is no loop). Beside them, the folders that could not be read, each with the reason."""
    out: list[Path] = []
    seen: set[Path] = set()
    links: list[Path] = []
    closed: list[tuple[Path, str]] = []
    closed_real: set[Path] = set()

    def walk(top: Path, follow: bool) -> None:
        def unreadable(exc: OSError) -> None:
            if isinstance(exc, FileNotFoundError) or exc.filename is None:
                return  # gone since it was listed (a batch still writing removes its staging folders)
            where = Path(os.fsdecode(exc.filename))
            if where.resolve() not in closed_real:  # (also reached through a link: one row)
                closed_real.add(where.resolve())
                closed.append((where, exc.strerror or type(exc).__name__))

        for here, dirs, names in os.walk(top, onerror=unreadable, followlinks=follow):
            real = Path(here).resolve()
            if real in seen:
                dirs[:] = []
                continue
            seen.add(real)
            dirs.sort()
            if not follow:  # os.walk lists a link to a folder among the folders, and does not enter it
                links.extend(Path(here) / d for d in dirs if (Path(here) / d).is_symlink())
            out.extend(Path(here) / n for n in sorted(names))

    walk(root, False)
    for link in links:
        walk(link, True)
    return out, closed
