"""``dataset.json``: the index of a folder of recordings written by a batch run (``mmusv run DIR``,
:func:`mmusv.run_many`, ``mmusv dataset``).

One entry per scenario, sorted by name::

    {"format": "mmusv.dataset", "version": 1,
     "recordings": [{"name": "a", "scenario_file": "a.yaml", "scenario": "a", "config_hash": SHA256, "seed": 1,
                     "recording": "a/a.mcap", "status": "complete", "frames": 20, "frames_requested": 20,
                     "parts": 1, "bytes": 123456, "error": null}, ...],
     "totals": {"recordings": 3, "complete": 3, "failed": 0, "pending": 0, "frames": 60, "frames_incomplete": 0,
                "bytes": ...},
     ...}

``status`` is ``complete``, ``failed`` (``error`` says why) or ``pending`` (not run yet, or interrupted);
``recording`` (relative to the index's folder) is an ``.mcap`` or a parts manifest (:mod:`mmusv.recording.parts`);
``bytes`` is the size of every file of the recording's folder. ``totals.frames`` counts the frames of the complete
recordings only, the dataset's; the frames a failed or pending recording wrote (its entry's ``frames``) are in
``totals.frames_incomplete``, and ``totals.failed`` says how many recordings failed. The file holds no times or
absolute paths, so a finished dataset's index is the same bytes however many runs it took. ``mmusv dataset`` adds
``spec`` and ``opv2v`` sections. Conversion (:func:`mmusv.export.convert`) and the studies take a folder holding a
``dataset.json`` and read its complete recordings (:func:`dataset_recordings`).
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

from mmusv import arguments
from mmusv.errors import IoError

__all__ = [
    "INDEX_FORMAT",
    "INDEX_NAME",
    "OWN_SECTIONS",
    "STATUSES",
    "Entry",
    "check_extra",
    "check_replaceable",
    "dataset_recordings",
    "find_index",
    "index_entries",
    "read_earlier_index",
    "read_index",
    "write_index",
]

INDEX_NAME = "dataset.json"
INDEX_FORMAT = "mmusv.dataset"
STATUSES = ("complete", "failed", "pending")
_VERSION = 1


@dataclass(frozen=True)
class Entry:
    """One scenario of the index (see the module docstring); ``recording`` relative to the index's folder
    (POSIX), ``None`` when the scenario could not even be loaded."""

    name: str
    scenario_file: str
    scenario: str | None
    config_hash: str | None
    seed: int | None
    recording: str | None
    status: str
    frames: int
    frames_requested: int
    parts: int
    bytes: int
    error: str | None = None

    def as_dict(self) -> dict[str, Any]:
        """The entry's JSON object."""
        return {
            "name": self.name,
            "scenario_file": self.scenario_file,
            "scenario": self.scenario,
            "config_hash": self.config_hash,
            "seed": self.seed,
            "recording": self.recording,
            "status": self.status,
            "frames": self.frames,
            "frames_requested": self.frames_requested,
            "parts": self.parts,
            "bytes": self.bytes,
            "error": self.error,
        }


def folder_bytes(folder: Path) -> int:
    """Bytes of every file below ``folder`` (0 when it does not exist)."""
    total = 0
    for root, _dirs, files in os.walk(folder):
        for f in files:
            try:
                total += (Path(root) / f).stat().st_size
            except OSError:
                continue
    return total


def write_index(
    path: str | os.PathLike[str], entries: Iterable[Entry], *, extra: Mapping[str, Any] | None = None
) -> Path:
    """Writes the index (entries sorted by name, totals, then the ``extra`` sections) atomically to ``path``."""
    from mmusv.jsonio import write_json

    rows = sorted(entries, key=lambda e: e.name)
    bad = [e.name for e in rows if e.status not in STATUSES]
    if bad:
        raise IoError(f"{path}: entries {bad} have a status outside {STATUSES}")
    doc: dict[str, Any] = {
        "format": INDEX_FORMAT,
        "version": _VERSION,
        "recordings": [e.as_dict() for e in rows],
        "totals": {
            "recordings": len(rows),
            **{s: sum(1 for e in rows if e.status == s) for s in STATUSES},
            # the dataset's frames: a failed or pending recording's are not part of it (they were counted in)
            "frames": sum(e.frames for e in rows if e.status == "complete"),
            "frames_incomplete": sum(e.frames for e in rows if e.status != "complete"),
            "bytes": sum(e.bytes for e in rows),
        },
    }
    for key, value in (extra or {}).items():
        if key in doc:
            raise IoError(f"{path}: section {key!r} is the index's own")
        doc[key] = value
    return write_json(path, doc)


OWN_SECTIONS = ("format", "version", "recordings", "totals")
"""The sections :func:`write_index` writes itself: an ``extra`` section may not take their names."""


def check_extra(extra: Mapping[str, Any] | None, *, name: str) -> None:
    """Refuses (:class:`~mmusv.errors.ConfigError` naming ``name``) ``extra`` sections :func:`write_index` could not
    write: one named like the index's own (:data:`OWN_SECTIONS`), or a value that is not plain JSON (dicts with
    string keys, lists, strings, finite numbers, booleans, ``None``). Checked before a batch starts, not when its
    index is written after the first recording."""
    import json

    from mmusv.arguments import shown
    from mmusv.errors import ConfigError

    for key, value in (extra or {}).items():
        if key in OWN_SECTIONS:
            raise ConfigError(
                f"{name}: section {key!r} is the index's own ({', '.join(OWN_SECTIONS)}); give it another name"
            )
        try:
            json.dumps(value, allow_nan=False)
        except (TypeError, ValueError) as exc:
            raise ConfigError(
                f"{name}[{key!r}] = {shown(value)}: must be plain JSON (dicts with string keys, lists, strings, finite "
                f"numbers, booleans, None): {exc}"
            ) from None


def check_replaceable(path: Path, *, writer: str) -> None:
    """Raises :class:`~mmusv.errors.IoError` when ``path`` holds what writing an index there would lose or fail on:
    a folder (found only after every recording, as a warning), or a file that is not an mmusv dataset index (a
    ``dataset.json`` of another tool was replaced without a word). An index of mmusv's, even a damaged one, is
    recognised by its ``format`` at the top (:func:`write_index` writes it first) and may be replaced, as may a
    file holding nothing else (empty, blanks or NUL bytes, or cut short before its ``format``: what a crash of the
    machine can leave of an index being written, since an index is renamed into place unsynced; a re-run after
    it, which the batch promises finishes the work, was refused as "not an mmusv dataset index"). ``writer`` says
    who writes the index, for the message."""
    import re

    if not path.exists():
        return
    if not path.is_file():
        what = "a folder" if path.is_dir() else "not a regular file"
        raise IoError(f"index {path} is {what}: move it away ({writer} writes its index there)")
    try:
        with path.open("rb") as f:
            head = f.read(4096).decode("utf-8", errors="replace")
    except OSError as exc:
        raise IoError(f"cannot read {path}: {exc.strerror or exc}") from None
    start, squeezed = f'{{"format":"{INDEX_FORMAT}"', re.sub(r"[\s\x00]", "", head)
    if not (squeezed.startswith(start) or start.startswith(squeezed)):
        raise IoError(
            f"{path} is not an mmusv dataset index, and {writer} would replace it with its own: move it away or "
            "choose another output folder"
        )


def find_index(folder: str | os.PathLike[str]) -> Path | None:
    """``folder/dataset.json`` when it exists."""
    p = Path(folder) / INDEX_NAME
    return p if p.is_file() else None


def read_index(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The index at ``path`` (a ``dataset.json`` or a folder holding one); :class:`~mmusv.errors.IoError` naming the
    file when it is not one."""
    from mmusv.jsonio import read_json

    p = Path(path)
    if p.is_dir():
        p = p / INDEX_NAME
    doc = read_json(p)
    if doc.get("format") != INDEX_FORMAT or doc.get("version") != _VERSION:
        raise IoError(
            f"{p}: not an mmusv dataset index (format = {doc.get('format')!r}, version = {doc.get('version')!r}; "
            f"expected {INDEX_FORMAT!r}, {_VERSION})"
        )
    recs = doc.get("recordings")
    if not isinstance(recs, list) or not all(isinstance(r, dict) and "name" in r and "status" in r for r in recs):
        raise IoError(f"{p}: field 'recordings' must be a list of entries with a name and a status")
    for i, r in enumerate(recs):  # a status ['complete'] was a bare TypeError (unhashable) in dataset_recordings
        for key in ("name", "status"):
            if not isinstance(r[key], str):
                raise IoError(
                    f"{p}: recordings[{i}].{key} = {arguments.shown(r[key])}: must be a string, not "
                    f"{type(r[key]).__name__}"
                )
        # a status "bogus", or a complete entry without its recording, was passed over without a word
        if r["status"] not in STATUSES:
            raise IoError(
                f"{p}: recordings[{i}] ({r['name']}).status = {arguments.shown(r['status'])}: must be one of "
                f"{', '.join(STATUSES)}"
            )
        if r["status"] == "complete" and not r.get("recording"):
            raise IoError(
                f"{p}: recordings[{i}] ({r['name']}) is complete but names no recording (field 'recording': the path "
                "of its .mcap or .parts.json below the index's folder)"
            )
    return doc


def read_earlier_index(path: Path) -> dict[str, Any]:
    """The index an earlier run wrote at ``path`` (:func:`read_index`); ``{}`` when there is none or it cannot be
    read (a writer then replaces it: :func:`check_replaceable` says whether it may)."""
    from mmusv.errors import MmusvError

    if not path.is_file():
        return {}
    try:
        return read_index(path)
    except MmusvError:
        return {}


def index_entries(doc: Mapping[str, Any]) -> list[Entry]:
    """The entries of an index :func:`read_index` read (``{}``: none), as :class:`Entry`."""
    return [Entry(**{k: r[k] for k in Entry.__dataclass_fields__}) for r in doc.get("recordings", [])]


def dataset_recordings(path: str | os.PathLike[str], *, statuses: Iterable[str] = ("complete",)) -> list[Path]:
    """The recordings (``.mcap`` or parts manifests) of the index at ``path`` whose status is in ``statuses``,
    in the index's order, as paths below the index's folder. Raises :class:`~mmusv.errors.IoError` when a listed
    recording is missing."""
    p = Path(path)
    doc = read_index(p)
    root = p if p.is_dir() else p.parent
    want = set(statuses)
    out: list[Path] = []
    for i, r in enumerate(doc["recordings"]):
        if r["status"] not in want or not r.get("recording"):
            continue
        rel = r["recording"]
        if not isinstance(rel, str) or PurePosixPath(rel).is_absolute() or ".." in PurePosixPath(rel).parts:
            # an absolute path or ../ was followed out of the dataset's folder
            raise IoError(
                f"{root / INDEX_NAME}: recordings[{i}].recording = {arguments.shown(rel)}: must be a relative path "
                "below the index's folder (an .mcap or a .parts.json)"
            )
        rec = root / rel
        if not rec.is_file():
            raise IoError(f"{root / INDEX_NAME}: recordings[{i}] ({r['name']}) lists {rec}, which does not exist")
        out.append(rec)
    return out
