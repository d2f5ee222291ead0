"""Write faults: a full disk and a read-only output folder. The cause is named as the system names it, the frames
that are safe are named and readable, the exit status is non-zero, never a traceback; a batch marks the recording
failed and goes on, or stops at once with ``--stop-on-full-disk``.

A full disk is a small tmpfs (mounted here when the tests run as root); without the right to mount, the writes are
cut off by the file-size limit instead (``RLIMIT_FSIZE``: the kernel fails them with "File too large"), the same
failure of a real ``write(2)`` under the recorder."""

from __future__ import annotations

import errno
import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from .conftest import ROOT, child_env, cli_main, frames_of, scenario, write_yaml


@contextmanager
def tmpfs(where: Path, size: str, *, read_only: bool = False) -> Iterator[Path]:
    where.mkdir(parents=True, exist_ok=True)
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)], capture_output=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({r.stderr.decode().strip()})")
    try:
        if read_only:
            subprocess.run(["mount", "-o", "remount,ro", str(where)], check=True, capture_output=True)
        yield where
    finally:
        subprocess.run(["umount", "-l", str(where)], capture_output=True)


def test_full_disk_names_the_cause_and_the_last_safe_frame(tmp_path: Path) -> None:
    src = write_yaml(tmp_path / "dense.yaml", scenario("dense", frames=110, dense=True))
    if os.geteuid() == 0:
        with tmpfs(tmp_path / "disk", "5m") as disk:
            code, _out, err = cli_main("run", str(src), "-o", str(disk / "out"))
            cause = os.strerror(errno.ENOSPC)
            partial = disk / "out" / "dense.mcap.partial"
            _check_full(code, err, cause, partial)
            # converting onto the full disk: one line, no traceback
            code, _out, err = cli_main("convert", str(partial), "-o", str(disk / "conv"), "--no-progress", "--no-split")
            assert code == 2 and err.startswith("mmusv: error: ") and cause in err and "Traceback" not in err, err
    else:  # the same failure of write(2), from the file-size limit
        script = (
            "import resource, signal, sys\n"
            "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
            "resource.setrlimit(resource.RLIMIT_FSIZE, (5 << 20, 5 << 20))\n"
            "from mmusv.cli import main\n"
            "sys.exit(main(sys.argv[1:]))\n"
        )
        out_dir = tmp_path / "out"
        p = subprocess.run(
            [sys.executable, "-c", script, "run", str(src), "-o", str(out_dir)],
            cwd=ROOT,
            env=child_env(),
            capture_output=True,
            text=True,
            timeout=300,
        )
        _check_full(p.returncode, p.stderr, os.strerror(errno.EFBIG), out_dir / "dense.mcap.partial")


def _check_full(code: int, err: str, cause: str, partial: Path) -> None:
    assert code == 2 and "Traceback" not in err, err
    assert err.startswith("mmusv: error: cannot write into ") and cause in err, err
    frames, _stream = frames_of(partial)  # the .partial is readable up to the last frame written
    assert frames and sorted(frames) == list(range(len(frames)))
    assert f"the last completely written frame is {max(frames)}" in err, err
    assert f"{partial}" in err and "mmusv recover" in err


def test_a_batch_marks_the_full_disk_failure_and_goes_on_or_stops(tmp_path: Path) -> None:
    from mmusv.batch import run_many

    if os.geteuid() != 0:
        pytest.skip("needs a small tmpfs (root)")
    src = tmp_path / "src"
    for name in ("a", "b", "c"):
        write_yaml(src / f"{name}.yaml", scenario(name, frames=12))
    with tmpfs(tmp_path / "disk", "400k") as disk:
        (disk / "filler").write_bytes(b"\0" * ((400 - 56) << 10))  # room for the index, not for a recording
        rep = run_many(src, out_dir=disk / "out")
        assert [o.status for o in rep.outcomes] == ["failed"] * 3
        assert all(os.strerror(errno.ENOSPC) in str(o.error) for o in rep.outcomes), [o.error for o in rep.outcomes]
        shutil.rmtree(disk / "out")
        rep = run_many(src, out_dir=disk / "out2", stop_on_full_disk=True)
        errors = [str(o.error) for o in rep.outcomes]
        assert [o.status for o in rep.outcomes] == ["failed"] * 3
        assert "No space left on device" in errors[0] and all("not run: the disk is full" in e for e in errors[1:])
        shutil.rmtree(disk / "out2")
        code, out, err = cli_main("run", str(src), "-o", str(disk / "out3"), "--stop-on-full-disk")
        assert code == 1 and "Traceback" not in err and "not run: the disk is full" in out


def test_a_read_only_output_folder_is_one_line(tmp_path: Path) -> None:
    src = write_yaml(tmp_path / "tiny.yaml", scenario("tiny", frames=3))
    if os.geteuid() == 0:
        with tmpfs(tmp_path / "ro", "1m", read_only=True) as ro:
            code, _out, err = cli_main("run", str(src), "-o", str(ro))
            assert code == 2 and err == f"mmusv: error: cannot write into {ro}: {os.strerror(errno.EROFS)}\n", err
            code, _out, err = cli_main("run", str(src), "-o", str(ro / "sub"))
            assert code == 2 and os.strerror(errno.EROFS) in err and err.count("\n") == 1, err
    else:
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o555)
        code, _out, err = cli_main("run", str(src), "-o", str(ro))
        assert code == 2 and os.strerror(errno.EACCES) in err and err.count("\n") == 1, err


def test_an_output_folder_that_cannot_be_made_names_it_and_the_cause(tmp_path: Path) -> None:
    """``run``, a batch and ``convert`` start the same way (:meth:`FolderLock.create`): an output folder under a file
    is one line naming the folder and the file in the way (the system's "Not a directory" named neither), and
    nothing is written; ``run`` says so of its option before it reads the scenario."""
    src = write_yaml(tmp_path / "in" / "tiny.yaml", scenario("tiny", frames=2))
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    code, _out, err = cli_main("run", str(src), "-o", str(blocker / "out"))
    assert code == 2 and err == f"mmusv: error: -o/--output {blocker / 'out'}: {blocker} is a file, not a folder\n"
    code, _out, err = cli_main("run", str(src.parent), "-o", str(blocker / "batch"))
    assert code == 2 and f"-o/--output {blocker / 'batch'}: {blocker} is a file, not a folder" in err, err
    assert "Traceback" not in err and err.count("\n") == 1, err
    rec = tmp_path / "rec"
    code, _out, err = cli_main("run", str(src), "-o", str(rec))
    assert code == 0, err
    code, _out, err = cli_main(
        "convert", str(rec / "tiny.mcap"), "-o", str(blocker / "conv"), "--no-progress", "--no-split"
    )
    said = f"cannot create output folder {blocker / 'conv'}: {blocker} is a file, not a folder; give another folder"
    assert code == 2 and err == f"mmusv: error: {said}\n", err
    assert blocker.read_text() == "not a folder"
