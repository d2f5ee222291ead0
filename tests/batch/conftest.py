"""Shared pieces of the batch tests: tiny scenario folders, a reference run, file-tree fingerprints, and finding
(and killing) the process that writes a recording."""

from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.batch import run_many

ROOT = Path(__file__).resolve().parents[2]
GOOD = ("a_sea", "b_sea", "c_sea")
FRAMES = 60
SPEC: dict[str, Any] = {
    "name": "tinyset",
    "seed": 7,
    "map": {"type": "open_sea", "seed": 2},
    "acquisition": {"frequency_hz": 5, "frames": 6},
    "rig": "usv_lidar",
    "rigs": {"usv_lidar": {"preset": "lidar_only", "lidar": {"channels": 8, "points_per_second": 20480}}},
    "usv": {"assets": ["usv_wamv"], "speed_mps": [2, 3]},
    "difficulties": {"near": {"range_m": [40, 120]}},
    "combinations": [
        {"family": "crossing", "difficulty": "near", "cooperating": 1, "targets": ["small"], "quota": 2},
        {"family": "head_on", "difficulty": "near", "cooperating": 1, "targets": ["medium"], "quota": 1},
    ],
}
"""A generation spec of three tiny LiDAR-only scenarios (6 frames) on the open sea."""


def scenario(name: str, *, frames: int = FRAMES, seed: int = 1) -> dict[str, Any]:
    """An open-sea, LiDAR-only scenario of ``frames`` frames: 65k points a frame, under a second of recording on
    one core, long enough to be caught mid-recording."""
    return {
        "name": name,
        "seed": seed,
        "map": {"type": "open_sea", "seed": 0},
        "acquisition": {"frames": frames},
        "rigs": {"r": {"preset": "lidar_only", "lidar": {"channels": 32, "points_per_second": 32 * 2048 * 5}}},
        "vessels": [
            {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": [[0, 0], [50, 0]]},
            {"id": "t", "asset": "fishing_boat_12m", "speed_mps": 3, "route": [[0, 60], [60, 60]]},
        ],
    }


def write(path: Path, data: dict[str, Any]) -> Path:
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def good_folder(path: Path) -> Path:
    """A folder with the three good scenarios."""
    path.mkdir(parents=True, exist_ok=True)
    for n in GOOD:
        write(path / f"{n}.yaml", scenario(n))
    return path


def tree(root: Path) -> dict[str, str]:
    """``{relative path: sha256}`` of every file below ``root`` but the runner's own ``.mmusv`` folder."""
    out = {}
    for p in sorted(root.rglob("*")):
        rel = p.relative_to(root)
        if p.is_file() and ".mmusv" not in rel.parts:
            out[rel.as_posix()] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def stamps(root: Path, names: Iterable[str]) -> dict[str, tuple[int, int]]:
    """``(inode, mtime_ns)`` of every file of the scenario folders ``names``: unchanged when a re-run skips them."""
    out = {}
    for n in names:
        for p in sorted((root / n).rglob("*")):
            if p.is_file():
                st = p.stat()
                out[p.relative_to(root).as_posix()] = (st.st_ino, st.st_mtime_ns)
    return out


def complete(root: Path) -> set[str]:
    """Scenario folders of ``root`` whose manifest.json says complete."""
    import json

    done = set()
    for m in root.glob("*/manifest.json"):
        try:
            if json.loads(m.read_text())["status"] == "complete":
                done.add(m.parent.name)
        except (ValueError, KeyError):
            continue
    return done


def _pids() -> list[int]:
    return [int(d) for d in os.listdir("/proc") if d.isdigit()]


def _stat(pid: int) -> tuple[int, int] | None:
    """``(ppid, pgid)`` of ``pid``."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return int(fields[1]), int(fields[2])


def descendants(pid: int) -> set[int]:
    """Every process below ``pid`` (children, their children, ...)."""
    children: dict[int, list[int]] = {}
    for p in _pids():
        st = _stat(p)
        if st is not None:
            children.setdefault(st[0], []).append(p)
    out: set[int] = set()
    todo = [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            if c not in out:
                out.add(c)
                todo.append(c)
    return out


def group(pgid: int) -> set[int]:
    """Live processes of process group ``pgid``."""
    return {p for p in _pids() if (st := _stat(p)) is not None and st[1] == pgid}


def holders(root: Path, pids: Iterable[int], suffix: str = "") -> set[int]:
    """Which of ``pids`` hold a file below ``root`` open (ending in ``suffix``)."""
    prefix = str(root.resolve()) + os.sep
    out = set()
    for pid in pids:
        try:
            fds = os.listdir(f"/proc/{pid}/fd")
        except OSError:
            continue
        for fd in fds:
            try:
                target = os.readlink(f"/proc/{pid}/fd/{fd}")
            except OSError:
                continue
            if target.startswith(prefix) and target.endswith(suffix):
                out.add(pid)
                break
    return out


def wait_for(cond: Callable[[], bool], *, timeout: float, what: str, every: float = 0.005) -> None:
    end = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(every)


class WorkerKiller(threading.Thread):
    """Kills (SIGKILL) the first process among ``candidates()`` seen writing a ``.partial`` recording below
    ``root``, once; ``killed`` is its pid."""

    def __init__(self, root: Path, candidates: Callable[[], set[int]]) -> None:
        super().__init__(daemon=True)
        self.root, self.candidates = root, candidates
        self.killed: int | None = None
        self.stop = threading.Event()

    def run(self) -> None:
        while not self.stop.is_set() and self.killed is None:
            if any(self.root.rglob("*.mcap.partial")):
                pids = holders(self.root, self.candidates(), ".mcap.partial")
                if pids:
                    self.killed = min(pids)
                    os.kill(self.killed, signal.SIGKILL)
                    return
            time.sleep(0.003)


def cli(*args: str, extra_env: dict[str, str] | None = None, **kw: Any) -> subprocess.Popen[str]:
    """``python -m mmusv.cli ARGS`` as a child in its own session (its process group is its pid)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "python") + os.pathsep + os.environ.get("PYTHONPATH", "")}
    env.update(extra_env or {})
    return subprocess.Popen(
        [sys.executable, "-m", "mmusv.cli", *args],
        cwd=ROOT,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        **kw,
    )


def kill_driver_partway(proc: subprocess.Popen[str], out: Path) -> None:
    """SIGKILLs the driver ``proc`` once a recording of ``out`` is complete and another is being written."""
    try:
        wait_for(
            lambda: (bool(complete(out)) and any(out.rglob("*.mcap.partial"))) or proc.poll() is not None,
            timeout=240,
            what="a complete recording and one in progress",
        )
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
    stdout, stderr = proc.communicate(timeout=30)  # also closes the pipes
    assert proc.returncode == -signal.SIGKILL, f"the run ended before it could be killed:\n{stdout}\n{stderr}"


@pytest.fixture(scope="session")
def reference(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, str]]:
    """The three good scenarios run one after the other in this process: the bytes every runner must give."""
    base = tmp_path_factory.mktemp("reference")
    src = good_folder(base / "src")
    out = base / "out"
    report = run_many(src, out_dir=out)
    assert report.ok and report.backend == "serial" and report.count("done") == 3
    return src, tree(out)
