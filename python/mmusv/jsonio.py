"""JSON files the project writes for itself (``dataset.json``, parts manifests): one layout and atomic writes.

:func:`dump_json` gives the bytes (2-space indent, keys in the order given, a final newline, no NaN), so two
writes of the same document are byte-identical; :func:`write_json` replaces a file atomically (a reader or a
killed writer never leaves half a file behind) through :func:`write_bytes_atomic`, which other small files the
project writes whole (a run's ``manifest.json``, a JSON Schema, a study's tables and plots:
:func:`write_files_atomic`) use too; :func:`read_json` reads one object and
names the file in every error (:class:`~mmusv.errors.IoError`); :func:`read_json_or_none` reads one that may be
missing or damaged.
"""

from __future__ import annotations

import contextlib
import glob
import json
import os
import stat
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from mmusv.errors import IoError

__all__ = [
    "dump_json",
    "read_json",
    "read_json_or_none",
    "remove_stale_temps",
    "write_bytes_atomic",
    "write_files_atomic",
    "write_json",
]


def dump_json(doc: Any) -> bytes:
    """The UTF-8 bytes of ``doc``: indented, insertion order kept, ending in a newline; NaN/inf are refused."""
    return (json.dumps(doc, indent=2, ensure_ascii=False, allow_nan=False) + "\n").encode("utf-8")


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists (a process we may not signal exists too)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_temps(path: Path) -> None:
    """Removes the temporary files of earlier writes of ``path`` (``.NAME.PID.tmp`` beside it) whose writer no
    longer runs: what a writer killed between writing and renaming leaves behind."""
    for tmp in path.parent.glob(f".{glob.escape(path.name)}.*.tmp"):  # a name a[1].json is no pattern
        pid = tmp.name[len(path.name) + 2 : -len(".tmp")]
        if pid.isdigit() and int(pid) != os.getpid() and not _alive(int(pid)):
            tmp.unlink(missing_ok=True)


def write_bytes_atomic(path: str | os.PathLike[str], data: bytes) -> Path:
    """Writes ``data`` to ``path`` through a temporary file beside it (``.NAME.PID.tmp``) and an atomic rename, so
    a reader or a writer killed on the way never leaves half a file; temporary files of earlier writers that no
    longer run are removed first. The folder must exist. An :class:`OSError` is raised as it came, after the
    temporary is removed: the caller words it (it names no file).

    A ``path`` that is a link is written through: the file it points to is replaced, the link stays. One that is
    no file (a device, a FIFO, ``/dev/stdout``) is written into directly: renaming a temporary onto it replaced
    ``/dev/full`` itself with a file (as root), a FIFO and a link to ``/proc/self/fd/1`` likewise."""
    p = Path(path)
    try:
        mode = os.stat(p).st_mode  # through links
    except (FileNotFoundError, NotADirectoryError):
        mode = None
    if mode is not None and not stat.S_ISREG(mode) and not stat.S_ISDIR(mode):
        with open(p, "wb") as f:
            f.write(data)
        return p
    if p.is_symlink():
        write_bytes_atomic(os.path.realpath(p), data)
        return p
    tmp = p.with_name(f".{p.name}.{os.getpid()}.tmp")
    try:
        remove_stale_temps(p)
        tmp.write_bytes(data)
        os.replace(tmp, p)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
        raise
    return p


def write_files_atomic(files: Mapping[Path, bytes]) -> None:
    """Writes several files made in memory (a study's table and plot), creating their folders, each with
    :func:`write_bytes_atomic`, after checking that no name is taken by a folder: a failure half-way never leaves
    a new table beside the old plot of an earlier run, nor half a file. :class:`~mmusv.errors.IoError` naming
    the file."""
    for path in files:
        if path.exists() and not path.is_file():
            raise IoError(f"cannot write {path}: a folder (or another non-file) has that name; remove it")
    for path, data in files.items():
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            write_bytes_atomic(path, data)
        except OSError as exc:
            raise IoError(f"cannot write {path}: {exc.strerror or exc}") from None


def write_json(path: str | os.PathLike[str], doc: Any) -> Path:
    """Writes ``doc`` (:func:`dump_json`) to ``path`` with :func:`write_bytes_atomic`, creating its folder;
    :class:`~mmusv.errors.IoError` naming the file when it cannot be written."""
    p = Path(path)
    data = dump_json(doc)
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        return write_bytes_atomic(p, data)
    except OSError as exc:
        raise IoError(f"cannot write {p}: {exc.strerror or exc}") from None


def read_json(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The JSON object in ``path``; :class:`~mmusv.errors.IoError` naming the file when it is missing, not
    UTF-8 JSON, or not an object."""
    p = Path(path)
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise IoError(f"{p} does not exist") from None
    except OSError as exc:
        raise IoError(f"cannot read {p}: {exc.strerror or exc}") from None
    except (UnicodeDecodeError, ValueError) as exc:
        raise IoError(f"{p} is not a JSON file: {exc}") from None
    if not isinstance(doc, dict):
        raise IoError(f"{p}: expected a JSON object at the top, got {type(doc).__name__}")
    return doc


def read_json_or_none(path: str | os.PathLike[str]) -> dict[str, Any] | None:
    """The JSON object in ``path``; ``None`` where there is none (missing, unreadable, not JSON, not an object):
    for a file the project writes beside its outputs to remember a past run, which a rerun may do without."""
    try:
        return read_json(path)
    except IoError:
        return None
