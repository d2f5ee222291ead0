"""A recording split into frame ranges: several MCAP parts tied together by one parts manifest.

A long scenario can be recorded as parts, each written by its own task (:mod:`mmusv.batch`) with
:func:`mmusv.acquire.run` ``frame_range=(first, stop)``. The parts manifest ``<name>.parts.json`` lists them in
frame order; the readers (:mod:`mmusv.recording.info`, :mod:`mmusv.recording.stream`,
:mod:`mmusv.recording.messages`, :mod:`mmusv.recording.contents`) read a manifest as one sequence (every consumer:
``info``, preview, conversion, the studies), each part through :func:`part_files`. Layout (JSON object)::

    {"format": "mmusv.parts", "version": 1, "scenario": NAME, "config_hash": SHA256, "frames": N,
     "parts": [{"first_frame": 0, "frames": 50, "recording": "parts/000000-000049/NAME.mcap"}, ...]}

``recording`` is relative to the manifest's folder. The parts cover ``0 .. frames - 1`` without gap or overlap.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

from mmusv.errors import ConfigError, IoError

__all__ = [
    "PARTS_FORMAT",
    "PARTS_SUFFIX",
    "Part",
    "PartsManifest",
    "is_parts_manifest",
    "part_files",
    "part_folder",
    "read_parts_manifest",
    "split_ranges",
    "write_parts_manifest",
]

PARTS_SUFFIX = ".parts.json"
PARTS_FORMAT = "mmusv.parts"
_VERSION = 1


@dataclass(frozen=True)
class Part:
    """Frames ``first_frame .. first_frame + frames - 1`` in ``recording`` (POSIX path relative to the
    manifest's folder)."""

    first_frame: int
    frames: int
    recording: str

    @property
    def stop(self) -> int:
        """One past the last frame."""
        return self.first_frame + self.frames


@dataclass(frozen=True)
class PartsManifest:
    """The parts of one recording of scenario ``scenario`` (config hash ``config_hash``), ``frames`` in all."""

    scenario: str
    config_hash: str
    frames: int
    parts: tuple[Part, ...]

    def as_dict(self) -> dict[str, Any]:
        """The JSON document (see the module docstring)."""
        return {
            "format": PARTS_FORMAT,
            "version": _VERSION,
            "scenario": self.scenario,
            "config_hash": self.config_hash,
            "frames": self.frames,
            "parts": [{"first_frame": p.first_frame, "frames": p.frames, "recording": p.recording} for p in self.parts],
        }


def is_parts_manifest(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` names a parts manifest (by its ``.parts.json`` suffix)."""
    return os.fspath(path).endswith(PARTS_SUFFIX)


def split_ranges(frames: int, per_part: int) -> list[tuple[int, int]]:
    """``(first, stop)`` ranges of at most ``per_part`` frames covering ``0 .. frames - 1`` in order."""
    if per_part < 1:
        raise ConfigError(f"frames per part = {per_part}: must be at least 1")
    return [(a, min(a + per_part, frames)) for a in range(0, frames, per_part)]


def part_folder(first: int, stop: int) -> str:
    """The folder name of the part holding frames ``first .. stop - 1`` (``000000-000049``)."""
    return f"{first:06d}-{stop - 1:06d}"


def write_parts_manifest(path: str | os.PathLike[str], manifest: PartsManifest) -> Path:
    """Writes ``manifest`` to ``path`` (must end in ``.parts.json``) atomically."""
    from mmusv.jsonio import write_json

    if not is_parts_manifest(path):
        raise ConfigError(f"{path}: a parts manifest's name ends in {PARTS_SUFFIX}")
    _check(Path(path), manifest)
    return write_json(path, manifest.as_dict())


def _check(p: Path, m: PartsManifest) -> None:
    if m.frames < 1 or not m.parts:
        raise IoError(f"{p}: a parts manifest needs frames >= 1 and at least one part")
    nxt = 0
    for i, part in enumerate(m.parts):
        if part.first_frame != nxt or part.frames < 1:
            raise IoError(
                f"{p}: invalid parts[{i}]: first_frame = {part.first_frame}, frames = {part.frames}; the parts must "
                f"cover the frames in order without gap or overlap (expected first_frame = {nxt}, frames >= 1)"
            )
        rel = PurePosixPath(part.recording)
        if rel.is_absolute() or ".." in rel.parts or not part.recording.endswith(".mcap"):
            raise IoError(
                f"{p}: invalid parts[{i}].recording = {part.recording!r}: must be a relative path to an .mcap "
                "below the manifest's folder"
            )
        nxt = part.stop
    if nxt != m.frames:
        raise IoError(f"{p}: the parts cover frames 0..{nxt - 1}, but frames = {m.frames}")


def _field(p: Path, obj: Any, key: str, kind: type, where: str) -> Any:
    """``obj[key]`` of the manifest ``p`` when it is of ``kind`` (``int``: a whole number, not a float, a text or
    true/false, which were read as 0, 2 or 1; ``str``; ``list``); else an :class:`~mmusv.errors.IoError` naming the
    file and the field ``where + key``."""
    from mmusv import arguments

    name = f"{where}{key}"
    if not isinstance(obj, dict):
        raise IoError(f"{p}: {where.rstrip('.')} = {arguments.shown(obj)}: must be a JSON object")
    if key not in obj:
        raise IoError(f"{p}: field {key!r} is missing" + (f" from {where.rstrip('.')}" if where else ""))
    value = obj[key]
    if kind is int:
        return arguments.whole(value, name=f"{p}: {name}", error=IoError)
    if not isinstance(value, kind):
        what = "a string" if kind is str else "a JSON list"
        raise IoError(f"{p}: {name} = {arguments.shown(value)}: must be {what}, not {type(value).__name__}")
    return value


def read_parts_manifest(path: str | os.PathLike[str]) -> PartsManifest:
    """The manifest at ``path``; :class:`~mmusv.errors.IoError` naming the file and the field when it is not one."""
    from mmusv.jsonio import read_json

    p = Path(path)
    doc = read_json(p)
    if doc.get("format") != PARTS_FORMAT or doc.get("version") != _VERSION:
        raise IoError(
            f"{p}: not a parts manifest (format = {doc.get('format')!r}, version = {doc.get('version')!r}; "
            f"expected {PARTS_FORMAT!r}, {_VERSION})"
        )
    parts_doc = _field(p, doc, "parts", list, "")
    parts = tuple(
        Part(
            first_frame=_field(p, d, "first_frame", int, f"parts[{i}]."),
            frames=_field(p, d, "frames", int, f"parts[{i}]."),
            recording=_field(p, d, "recording", str, f"parts[{i}]."),
        )
        for i, d in enumerate(parts_doc)
    )
    m = PartsManifest(
        scenario=_field(p, doc, "scenario", str, ""),
        config_hash=_field(p, doc, "config_hash", str, ""),
        frames=_field(p, doc, "frames", int, ""),
        parts=parts,
    )
    _check(p, m)
    return m


def part_files(path: Path) -> list[tuple[int, int, Path | None]]:
    """``(first_frame, stop, file or None)`` of every part of the manifest at ``path``: the finished ``.mcap``,
    else its ``.partial`` (an interrupted part), else None (not recorded yet)."""
    m = read_parts_manifest(path)
    out: list[tuple[int, int, Path | None]] = []
    for part in m.parts:
        f = path.parent / part.recording
        partial = f.with_name(f.name + ".partial")
        out.append((part.first_frame, part.stop, f if f.is_file() else partial if partial.is_file() else None))
    return out
