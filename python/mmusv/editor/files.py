"""The editor's folder: the only place the server reads and writes scenario files.

A file is named by a bare file name (``harbour.yaml``): letters, digits, ``_``, ``-`` and ``.``, starting with a
letter or digit, ending in ``.yaml`` or ``.yml``, at most 128 characters. Anything else (a path with ``/`` or
``\\``, ``..``, an absolute path, another suffix) is an :class:`~mmusv.errors.InputError`; a name whose file
resolves outside the folder (a symbolic link pointing out) is refused the same way, so nothing outside the folder
can be read or overwritten through the server. Writes go to a temporary file in the folder first (flushed to disk)
and replace the target in one rename, so a file is never left half-written and a failed write leaves neither the
temporary file nor a changed target behind; a new file gets the permissions of any file the user creates (the
umask applies), a replaced one keeps its own. A name that is a link to another file of the folder is saved into
that file and stays a link. A name that is a folder or another non-file is never replaced.

Reading: a file must be UTF-8 text (a byte-order mark is accepted) of at most :data:`MAX_FILE_BYTES`; anything else
is refused naming the file and the first bad byte, never opened with replacement characters (saving it back would
lose the characters that did not decode).

Lost updates: every read gives the file's ETag (:func:`etag`, a hash of its bytes). A write that names the ETag
it started from (``if_match``) is refused with :class:`ChangedInFolder` when the file has changed since (another
browser tab, or another program, saved it), so an edit is never silently overwritten; the check and the write
happen under one lock of the folder object.

Size: a text larger than :data:`MAX_FILE_BYTES` is never written (the editor could not open the file again).
"""

from __future__ import annotations

import hashlib
import os
import re
import secrets
import stat
import threading
from dataclasses import dataclass
from pathlib import Path

from mmusv.errors import ConfigError, InputError, IoError, NotFoundError
from mmusv.yamlio import decode_text

__all__ = [
    "MAX_FILE_BYTES",
    "ChangedInFolder",
    "FileExistsInFolder",
    "ScenarioFile",
    "ScenarioFolder",
    "ScenarioText",
    "check_name",
    "etag",
    "read_bounded",
]

_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.\-]{0,122}\.ya?ml")
MAX_NAME_CHARS = 128
"""The longest file name the editor saves (what :data:`_NAME` allows: 1 + 122 + ``.yaml``)."""

MAX_FILE_BYTES = 16 * 1024 * 1024
"""Largest scenario file the editor opens (16 MiB, as large as the largest request it takes); larger files are
refused before they are read whole."""


class FileExistsInFolder(IoError):
    """Saving would replace an existing file and the request did not ask to overwrite it."""


class ChangedInFolder(IoError):
    """Saving would replace a file that changed since the client read it (its ETag differs)."""


def read_bounded(path: Path, label: str) -> bytes:
    """The bytes of the scenario file ``path``, read once and at most :data:`MAX_FILE_BYTES` of them: an
    :class:`~mmusv.errors.IoError` when it cannot be read, a :class:`~mmusv.errors.ConfigError` when it is larger,
    each naming ``label``. The editor's one read of a scenario file (its folder's files and the command line's)."""
    try:
        with path.open("rb") as f:
            data = f.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise IoError(f"{label}: cannot be read: {exc.strerror or exc}") from None
    if len(data) > MAX_FILE_BYTES:
        raise ConfigError(f"{label}: larger than {MAX_FILE_BYTES:,} bytes, the most the editor opens; edit it as text")
    return data


def etag(data: bytes) -> str:
    """The ETag of a file's bytes: the first 32 hex digits of their SHA-256."""
    return hashlib.sha256(data).hexdigest()[:32]


def check_name(name: str) -> str:
    """``name`` when it is an allowed scenario file name (see the module docstring), else :class:`InputError`."""
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        shown = repr(name) if len(str(name)) <= 80 else repr(str(name)[:80] + "...")
        raise InputError(
            f"file name {shown} is not allowed: give a bare file name in the editor's folder, ending in .yaml or "
            f".yml (ASCII letters, digits, _ - and ., no folders, no leading dot, at most {MAX_NAME_CHARS} characters)"
        )
    return name


@dataclass(frozen=True)
class ScenarioText:
    """A scenario file as read once: its ``path``, ``text`` and the ``etag`` of exactly those bytes."""

    path: Path
    text: str
    etag: str


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

    def read_text(self, name: str) -> ScenarioText:
        """The file ``name`` read once (its text and the ETag of the same bytes, so a save that names that ETag
        replaces exactly what the client was shown); :class:`NotFoundError` when it does not exist,
        :class:`ConfigError` when it is larger than :data:`MAX_FILE_BYTES` or not UTF-8 text."""
        p = self.path(name)
        if not p.is_file():
            raise NotFoundError(f"no scenario file {name!r} in the editor's folder")
        data = read_bounded(p, name)
        return ScenarioText(p, decode_text(data, name), etag(data))

    def etag_of(self, name: str) -> str | None:
        """The ETag of the file ``name`` now, or ``None`` when it does not exist."""
        p = self.path(name)
        try:
            return etag(p.read_bytes())
        except FileNotFoundError:
            return None
        except OSError as exc:
            raise IoError(f"{name}: cannot be read: {exc.strerror or exc}") from None

    def write_text(self, name: str, text: str, *, overwrite: bool, if_match: list[str] | None = None) -> Path:
        """Writes ``text`` to the file ``name`` (atomically); :class:`FileExistsInFolder` when it exists and
        ``overwrite`` is false, or when the name is a folder or another non-file; :class:`ChangedInFolder` when
        ``if_match`` (the ETags of an ``If-Match`` header, ``"*"`` for any version) is given, the file exists and
        its ETag is none of them, or the file does not exist (whatever the ETags); :class:`ConfigError` when the text
        is larger than :data:`MAX_FILE_BYTES` (the file would not open again): nothing is written."""
        p = self.path(name)
        data = text.encode("utf-8")
        if len(data) > MAX_FILE_BYTES:
            raise ConfigError(
                f"{name}: not saved, its text would take {len(data):,} bytes, more than {MAX_FILE_BYTES:,} bytes, the "
                "most the editor opens, so the file would not open again: use fewer waypoints, vessels or comments"
            )
        with self._write_lock:
            if p.exists() and not p.is_file():
                raise FileExistsInFolder(
                    f"{name} is a folder or another non-file in the editor's folder, not a scenario file; it is "
                    "never replaced: save under another name"
                )
            if p.exists() and not overwrite:
                raise FileExistsInFolder(
                    f"{name} already exists in the editor's folder; save with overwrite to replace it"
                )
            if if_match is not None:
                now = self.etag_of(name)
                if now is None:  # no version of it matches (RFC 9110, 13.1.1): an ETag of it was not refused
                    raise ChangedInFolder(  # and the file came back under its old name, renamed in another tab
                        f"{name} does not exist in the editor's folder (If-Match names a version of an existing "
                        "file; was it deleted or renamed?): save it again without If-Match (Overwrite) to create it"
                    )
                if now is not None and "*" not in if_match and now not in if_match:
                    raise ChangedInFolder(
                        f"{name} was changed since you opened it (another tab or program saved it), so neither "
                        "edit is lost: open it again to see the other version, save under another name, or "
                        "overwrite it"
                    )
            self._replace(p, data, name=name)
        return p

    def _replace(self, p: Path, data: bytes, *, name: str) -> None:
        """Writes ``data`` to a new temporary file in the folder, flushes it to disk and renames it over ``p``;
        on any failure the temporary file is removed and ``p`` is left as it was. A ``p`` that is a link (to a
        file of the folder: :meth:`path`) is written through: the file it points to is replaced, the link stays."""
        if p.is_symlink():
            p = p.resolve()
        tmp = self.root / f".mmusv-editor-{secrets.token_hex(8)}.tmp"
        try:
            # created like any new file (mode 0666 less the umask), refusing to follow or reuse anything there
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o666)
        except OSError as exc:
            raise IoError(f"{name}: cannot be written: {exc.strerror or exc}") from None
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
                f.flush()
                os.fsync(f.fileno())
            if p.is_file():  # a replaced file keeps its permissions
                os.chmod(tmp, stat.S_IMODE(p.stat().st_mode))
            os.replace(tmp, p)
        except BaseException as exc:
            tmp.unlink(missing_ok=True)
            if isinstance(exc, OSError):
                raise IoError(f"{name}: cannot be written: {exc.strerror or exc}") from None
            raise
