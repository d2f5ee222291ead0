"""mmusv.jsonio: atomic JSON writes leave nothing behind, even after a killed writer."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from mmusv.jsonio import read_json, write_json


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
