"""mmusv.jsonio: atomic JSON writes leave nothing behind, even after a killed writer."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from mmusv.jsonio import read_json, write_bytes_atomic, write_json


def test_a_killed_writers_temporary_file_is_removed_by_the_next_write(tmp_path: Path) -> None:
    target = tmp_path / "dataset.json"
    # A writer that died between writing its temporary file and renaming it: a process that has exited.
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    stale = tmp_path / f".dataset.json.{int(dead.stdout)}.tmp"
    stale.write_bytes(b"")
    # A writer still running (this process's parent, say) keeps its file.
    live = tmp_path / f".dataset.json.{os.getppid()}.tmp"
    live.write_bytes(b"{}")
    other = tmp_path / ".other.json.1.tmp"
    other.write_bytes(b"")
    write_json(target, {"a": 1})
    assert read_json(target) == {"a": 1}
    assert not stale.exists()
    assert live.exists() and other.exists()
    assert not (tmp_path / f".dataset.json.{os.getpid()}.tmp").exists()


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path: Path, monkeypatch) -> None:
    """A full disk during the write: the file keeps its old bytes, no temporary stays, the OSError reaches the
    caller (who names the file in its own words)."""
    import errno
    import pathlib

    from mmusv.jsonio import write_bytes_atomic

    target = tmp_path / "manifest.json"
    target.write_bytes(b"old\n")
    real = pathlib.Path.write_bytes

    def full(self: Path, data: bytes) -> int:
        real(self, data[:3])  # what a full disk leaves: the start of the file
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(pathlib.Path, "write_bytes", full)
    try:
        write_bytes_atomic(target, b"new contents\n")
    except OSError as exc:
        assert exc.errno == errno.ENOSPC
    else:
        raise AssertionError("the OSError was swallowed")
    monkeypatch.undo()
    assert target.read_bytes() == b"old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["manifest.json"]
    assert write_bytes_atomic(target, b"new\n") == target and target.read_bytes() == b"new\n"


def test_a_name_with_brackets_is_no_glob_pattern(tmp_path: Path) -> None:
    """A file ``a[1].json`` (a run named so): its name went into a glob pattern, where ``[1]`` matches "1", so its
    own stale temporary was kept and ``a1.json``'s removed, its process id read at the wrong place."""
    from mmusv.jsonio import remove_stale_temps

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    own = tmp_path / f".a[1].json.{int(dead.stdout)}.tmp"
    other = tmp_path / f".a1.json.{int(dead.stdout)}.tmp"
    own.write_bytes(b"")
    other.write_bytes(b"")
    remove_stale_temps(tmp_path / "a[1].json")
    assert not own.exists() and other.exists()


def test_read_json_or_none_is_the_object_or_none(tmp_path: Path) -> None:
    from mmusv.jsonio import read_json_or_none

    good, listed, broken, binary = (tmp_path / n for n in ("good.json", "list.json", "broken.json", "bin.json"))
    good.write_text('{"a": [1, 2]}', encoding="utf-8")
    listed.write_text("[1, 2]", encoding="utf-8")
    broken.write_text('{"a": ', encoding="utf-8")
    binary.write_bytes(b"\xff\xfe{")
    assert read_json_or_none(good) == {"a": [1, 2]}
    for path in (listed, broken, binary, tmp_path / "missing.json", tmp_path):
        assert read_json_or_none(path) is None


def test_a_link_is_written_through_and_a_fifo_or_device_into(tmp_path: Path) -> None:
    """``mmusv schema -o`` onto a FIFO, a device or a link to ``/proc/self/fd/1`` replaced it with a regular file
    (``/dev/full`` itself, as root) and said ``wrote``: the temporary was renamed onto it."""
    import stat
    import threading

    target = tmp_path / "real.json"
    target.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    write_bytes_atomic(link, b"new")
    assert link.is_symlink() and target.read_bytes() == b"new"

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got: list[bytes] = []

    def read() -> None:
        with open(fifo, "rb") as f:
            got.append(f.read())

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    write_bytes_atomic(fifo, b"through the pipe")
    reader.join(timeout=10)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode) and got == [b"through the pipe"]

    to_null = tmp_path / "null"  # a link to a device: written into, the device and the link stay
    to_null.symlink_to("/dev/null")
    write_bytes_atomic(to_null, b"gone")
    assert to_null.is_symlink() and stat.S_ISCHR(os.stat("/dev/null").st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.json", "null", "pipe", "real.json"]  # no temporary
