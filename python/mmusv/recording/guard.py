"""Guarding an output folder: one writer at a time (:class:`FolderLock`), naming why a write failed
(:func:`write_cause`), and holding a stop back while a few writes must happen together (:class:`HeldSignals`, from
:mod:`mmusv.held_signals`).

:class:`FolderLock` is an advisory lock (``fcntl.flock``, released by the kernel when its holder exits, however it
exits) on the folder itself. A second ``mmusv run`` (or batch) into the same folder does not wait for it: it refuses
at once and names the process holding it, so two writers never interleave their bytes in one file. On systems
without ``fcntl``, and on file systems that cannot lock a folder, the lock is a no-op.

:func:`write_cause` turns a failed write into its cause as the operating system names it (``No space left on
device``, ``Permission denied``, ``Read-only file system``): from the exception chain when an ``OSError`` (or an
``os error N`` in a message of the core) is there, else by a small probe write into the folder, else from the
folder's free space. The MCAP recorder of the core reports a failed write without its ``io::Error`` after the
first one, so the probe is what names the cause of a full disk there.

:class:`HeldSignals` keeps SIGINT and SIGTERM from interrupting steps that must not be split: a recording is opened
and its metadata written under it, so a stop leaves either no ``.partial`` or one that says what it is (its
``scenario``, ``manifest`` and ``sensors`` metadata), never a file that :func:`mmusv.recording.info.read_info`,
``mmusv info`` and ``mmusv recover`` cannot read.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import tempfile
from pathlib import Path
from types import TracebackType

from mmusv.errors import IoError
from mmusv.held_signals import HeldSignals  # its home; here as before for the recorder's callers

__all__ = ["FolderLock", "HeldSignals", "file_in_the_way", "write_cause"]

_OS_ERROR = re.compile(r"os error (\d+)")
_PROBE_BYTES = 1 << 16


def file_in_the_way(folder: Path) -> Path | None:
    """The nearest of ``folder`` and its parents that exists, when it is not a folder (a file where the folder, or
    one above it, would be made); None when that one is a folder, or none exists."""
    for q in (folder, *folder.parents):
        if q.exists():
            return None if q.is_dir() else q
    return None


class FolderLock:
    """The lock of the folder ``folder`` (it must exist) held by this process; ``what`` says in messages what
    the holder does (``"mmusv run"``). The lock is taken on the folder itself (``flock`` of the directory), so
    it adds no file to the folder."""

    def __init__(self, folder: str | os.PathLike[str], *, what: str) -> None:
        self.folder = Path(folder)
        self.what = what
        self._fd = -1

    @classmethod
    def create(cls, folder: str | os.PathLike[str], *, what: str) -> FolderLock:
        """Creates ``folder`` (with its parents) where it is missing and takes its lock (:meth:`acquire`): how every
        writer of an output folder starts. :class:`~mmusv.errors.IoError` naming the folder and the cause
        (:func:`write_cause`) when it cannot be created."""
        path = Path(folder)
        try:
            path.mkdir(parents=True, exist_ok=True)
        except (FileExistsError, NotADirectoryError):  # the path or a folder above it is a file (said neither)
            above = file_in_the_way(path) or path
            what = "it is a file" if above == path else f"{above} is a file"
            raise IoError(f"cannot create output folder {path}: {what}, not a folder; give another folder") from None
        except OSError as exc:
            raise IoError(f"cannot create output folder {path}: {write_cause(path, exc)}") from None
        return cls(path, what=what).acquire()

    def acquire(self) -> FolderLock:
        """Takes the lock at once; :class:`~mmusv.errors.IoError` naming the holder when another process has it.
        Where the file system cannot lock folders (some network file systems) this is a no-op."""
        try:
            import fcntl
        except ImportError:  # not POSIX: no lock
            return self
        try:
            fd = os.open(self.folder, os.O_RDONLY)
        except OSError as exc:
            raise IoError(f"cannot open the output folder {self.folder}: {write_cause(self.folder, exc)}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            if exc.errno not in (errno.EWOULDBLOCK, errno.EAGAIN):
                os.close(fd)  # the file system cannot lock it: go on unlocked
                return self
            holder = _holder(fd)
            os.close(fd)
            raise IoError(
                f"{self.folder} is being written by another {self.what}"
                + (f" (process {holder})" if holder else "")
                + "; two writers in one folder would corrupt each other's files: wait until it ends, or write "
                "somewhere else"
            ) from None
        self._fd = fd
        return self

    def release(self) -> None:
        """Releases the lock: unlocked first, then closed (a process forked while it was held, a DataLoader's
        worker, shares the lock through its copy of the descriptor; closing ours alone left the folder locked
        until that process ended)."""
        if self._fd >= 0:
            import fcntl  # (a descriptor is only kept where fcntl exists)

            with contextlib.suppress(OSError):
                fcntl.flock(self._fd, fcntl.LOCK_UN)
            os.close(self._fd)
            self._fd = -1

    def __enter__(self) -> FolderLock:
        return self.acquire()

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.release()


def _holder(fd: int) -> int | None:
    """The process holding a ``flock`` on the file of ``fd``, from ``/proc/locks`` (Linux), else None."""
    try:
        st = os.fstat(fd)
        with open("/proc/locks", encoding="ascii", errors="replace") as f:
            lines = f.read().splitlines()
    except OSError:
        return None
    want = f":{st.st_ino}"
    for line in lines:
        parts = line.split()
        if len(parts) >= 6 and parts[1] == "FLOCK" and parts[5].endswith(want):
            dev = parts[5][: -len(want)]
            major, _, minor = dev.partition(":")
            try:
                if (int(major, 16), int(minor, 16)) == (os.major(st.st_dev), os.minor(st.st_dev)):
                    return int(parts[4])
            except ValueError:
                continue
    return None


def _errno_of(exc: BaseException | None) -> int | None:
    seen = 0
    while exc is not None and seen < 10:
        if isinstance(exc, OSError) and exc.errno:
            return int(exc.errno)
        m = _OS_ERROR.search(str(exc))
        if m:
            return int(m.group(1))
        exc = exc.__cause__ or exc.__context__
        seen += 1
    return None


def _probe(folder: Path) -> int | None:
    """The errno of a small write (created, written, synced, removed) into ``folder``, or None when it works."""
    try:
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=".mmusv-probe-")
    except OSError as exc:
        return exc.errno
    try:
        os.write(fd, b"\0" * _PROBE_BYTES)
        os.fsync(fd)
    except OSError as exc:
        return exc.errno
    finally:
        os.close(fd)
        with contextlib.suppress(OSError):
            os.unlink(tmp)
    return None


def write_cause(folder: str | os.PathLike[str], exc: BaseException | None = None) -> str:
    """Why writing into ``folder`` failed, as the operating system names it (see the module docstring); the
    message of ``exc`` when nothing more precise is found."""
    code = _errno_of(exc)
    where = Path(folder)
    while not where.exists() and where != where.parent:
        where = where.parent
    if code is None or code == errno.EIO:
        probed = _probe(where) if where.is_dir() else None
        if probed is not None:
            code = probed
    if code is None:
        try:
            st = os.statvfs(where)
            if st.f_bavail * st.f_frsize < _PROBE_BYTES:
                code = errno.ENOSPC
        except OSError:
            pass
    if code is not None:
        return os.strerror(code)
    return str(exc) if exc is not None else "unknown cause"
