"""The editor's folder: the only place the server reads and writes scenario files.

A file is named by a bare file name (``harbour.yaml``): letters, digits, ``_``, ``-`` and ``.``, starting with a
letter or digit, ending in ``.yaml`` or ``.yml``, at most 128 characters. Anything else (a path with ``/`` or
``\\``, ``..``, an absolute path, another suffix) is an :class:`~mmusv.errors.InputError`; a name whose file
resolves outside the folder (a symbolic link pointing out) is refused the same way, so nothing outside the folder
can be read or overwritten through the server. Writes go to a temporary file in the folder first and replace the
target in one rename, so a file is never left half-written.

Lost updates: every read gives the file's ETag (:func:`etag`, a hash of its bytes). A write that names the ETag
it started from (``if_match``) is refused with :class:`ChangedInFolder` when the file has changed since (another
browser tab, or another program, saved it), so an edit is never silently overwritten; the check and the write
happen under one lock of the folder object.
"""

from __future__ import annotations

import hashlib
import os
import re
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path

from mmusv.errors import InputError, IoError, NotFoundError

__all__ = ["ChangedInFolder", "FileExistsInFolder", "ScenarioFile", "ScenarioFolder", "check_name", "etag"]

_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.\-]{0,122}\.ya?ml")


class FileExistsInFolder(IoError):
    """Saving would replace an existing file and the request did not ask to overwrite it."""


class ChangedInFolder(IoError):
    """Saving would replace a file that changed since the client read it (its ETag differs)."""


def etag(data: bytes) -> str:
    """The ETag of a file's bytes: the first 32 hex digits of their SHA-256."""
    return hashlib.sha256(data).hexdigest()[:32]


def check_name(name: str) -> str:
    """``name`` when it is an allowed scenario file name (see the module docstring), else :class:`InputError`."""
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        shown = repr(name) if len(str(name)) <= 80 else repr(str(name)[:80] + "...")
        raise InputError(
            f"file name {shown} is not allowed: give a bare file name in the editor's folder, ending in .yaml or "
            ".yml (letters, digits, _ - and ., no folders, no leading dot)"
        )
    return name


@dataclass(frozen=True)
class ScenarioFile:
    """A scenario file of the folder: ``name``, ``size`` in bytes."""

    name: str
    size: int


class ScenarioFolder:
    """The folder ``root`` (must exist) and the scenario files directly in it."""

    def __init__(self, root: str | os.PathLike[str]) -> None:
        p = Path(root)
        if not p.is_dir():
            raise NotFoundError(f"editor folder {str(p)!r} does not exist or is not a folder")
        self.root = p.resolve()
        self._write_lock = threading.Lock()

    def path(self, name: str) -> Path:
        """The path of the file ``name`` in the folder (it need not exist); refused when outside the folder."""
        p = self.root / check_name(name)
        if p.resolve().parent != self.root:
            raise InputError(f"file {name!r} is a link that points outside the editor's folder; it is not served")
        return p

    def files(self) -> list[ScenarioFile]:
        """The scenario files (``*.yaml``, ``*.yml``) directly in the folder, sorted by name; links pointing
        outside the folder and names the editor would refuse are left out."""
        out = []
        for p in sorted(self.root.iterdir()):
            if not _NAME.fullmatch(p.name) or not p.is_file() or p.resolve().parent != self.root:
                continue
            out.append(ScenarioFile(p.name, p.stat().st_size))
        return out

    def read_text(self, name: str) -> tuple[Path, str]:
        """``(path, text)`` of the file ``name``; :class:`NotFoundError` when it does not exist."""
        p = self.path(name)
        if not p.is_file():
            raise NotFoundError(f"no scenario file {name!r} in the editor's folder")
        try:
            return p, p.read_text(encoding="utf-8", errors="replace")
        except OSError as exc:
            raise IoError(f"{name}: cannot be read: {exc.strerror or exc}") from None

    def etag_of(self, name: str) -> str | None:
        """The ETag of the file ``name`` now, or ``None`` when it does not exist."""
        p = self.path(name)
        try:
            return etag(p.read_bytes())
        except FileNotFoundError:
            return None
        except OSError as exc:
            raise IoError(f"{name}: cannot be read: {exc.strerror or exc}") from None

    def write_text(self, name: str, text: str, *, overwrite: bool, if_match: str | None = None) -> Path:
        """Writes ``text`` to the file ``name`` (atomically); :class:`FileExistsInFolder` when it exists and
        ``overwrite`` is false; :class:`ChangedInFolder` when ``if_match`` is given, the file exists and its ETag
        is another (it changed since the client read it)."""
        p = self.path(name)
        with self._write_lock:
            if p.exists() and not overwrite:
                raise FileExistsInFolder(
                    f"{name} already exists in the editor's folder; save with overwrite to replace it"
                )
            if if_match is not None:
                now = self.etag_of(name)
                if now is not None and now != if_match:
                    raise ChangedInFolder(
                        f"{name} was changed since you opened it (another tab or program saved it), so neither "
                        "edit is lost: open it again to see the other version, save under another name, or "
                        "overwrite it"
                    )
            fd, tmp = tempfile.mkstemp(dir=self.root, prefix=".mmusv-editor-", suffix=".tmp")
            try:
                with os.fdopen(fd, "w", encoding="utf-8") as f:
                    f.write(text)
                os.replace(tmp, p)
            except OSError as exc:
                Path(tmp).unlink(missing_ok=True)
                raise IoError(f"{name}: cannot be written: {exc.strerror or exc}") from None
        return p
