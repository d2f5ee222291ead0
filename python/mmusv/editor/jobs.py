"""Background runs started from the editor: one process per run (:mod:`mmusv.editor.job`), its progress read from
the JSON lines it prints.

A run of ``NAME.yaml`` in the editor's folder writes into ``<folder>/out/<NAME>/`` (replacing an earlier run of
the same file), like ``mmusv run NAME.yaml -o out/NAME --overwrite``. :meth:`Jobs.cancel` sends SIGINT, so the
recording is finished with every completed frame, exactly as Ctrl-C on the command line.

At most :data:`MAX_RUNNING` runs go on at a time, and one output folder has one run at a time (``a.yaml`` and
``a.yml`` share ``out/a``): a second is refused with :class:`RunGoingOn` instead of starting and failing on the
folder's lock. A run never writes outside the folder: ``out/NAME`` reached through a link pointing elsewhere is
refused.

A server starts knowing the runs already in its folder: each ``out/NAME/manifest.json`` (written last by every run
that ended, ``mmusv run`` on the command line included) of a scenario file ``NAME.yaml`` (or ``.yml``) is one finished
run, marked ``earlier``, so a file reopened after a restart shows its last run as before.
"""

from __future__ import annotations

import itertools
import json
import os
import signal
import subprocess
import sys
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mmusv.errors import InputError, NotFoundError
from mmusv.text import counted

__all__ = ["KEEP_FINISHED", "MAX_RUNNING", "Job", "Jobs", "RunGoingOn"]

MAX_RUNNING = 2
"""Runs at a time; a further start is refused until one ends."""
KEEP_FINISHED = 100
"""Finished runs a server remembers (the newest); older ones are forgotten when another starts."""


class RunGoingOn(InputError):
    """A run of the same output folder, or :data:`MAX_RUNNING` runs, are going on already (HTTP 409)."""


@dataclass
class Job:
    """One run: ``status`` is ``running``, ``complete``, ``failed`` or ``interrupted``; ``done``/``total``
    frames; ``command`` the equivalent ``mmusv run`` command line (relative to the folder)."""

    id: int
    scenario: str
    output: str
    command: str
    status: str = "running"
    done: int = 0
    total: int | None = None
    error: str | None = None
    recording: str | None = None
    seconds: float | None = None
    warnings: list[str] = field(default_factory=list)
    earlier: bool = False
    """Run before this server started (read from the output folder's manifest; no timing, no warnings)."""
    process: subprocess.Popen[str] | None = field(default=None, repr=False)
    stop_requested: bool = field(default=False, repr=False)

    def as_dict(self) -> dict[str, Any]:
        """The job as JSON (without the process)."""
        keys = (
            "id",
            "scenario",
            "output",
            "command",
            "status",
            "done",
            "total",
            "error",
            "recording",
            "seconds",
            "earlier",
        )
        return {**{k: getattr(self, k) for k in keys}, "warnings": list(self.warnings)}


class Jobs:
    """The runs of one editor server, for scenario files in ``root``."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self._jobs: dict[int, Job] = {}
        self._ids = itertools.count(1)
        self._lock = threading.Lock()
        self._followers: list[threading.Thread] = []
        for job in _earlier_runs(root)[-KEEP_FINISHED:]:  # the newest, as a long-lived server keeps them
            job.id = next(self._ids)
            self._jobs[job.id] = job

    def start(self, path: Path, *, frames: int | None = None) -> Job:
        """Starts ``mmusv run`` of the scenario file ``path`` (in the folder) into ``out/<stem>``."""
        out = self.root / "out" / path.stem
        rel_out = out.relative_to(self.root)
        if not out.resolve().is_relative_to(self.root.resolve()):
            raise InputError(
                f"{rel_out} is a link (or inside one) that points outside the editor's folder; a run writes only "
                "inside the folder: remove the link"
            )
        with self._lock:
            running = [j for j in self._jobs.values() if j.status == "running"]
            same = [j for j in running if j.output == str(rel_out)]
            if same:
                raise RunGoingOn(
                    f"run {same[0].id} ({same[0].scenario}) is writing {rel_out} already; wait for it to end or stop it"
                )
            if len(running) >= MAX_RUNNING:  # 409, as for a run of the same folder: a good request, a busy editor
                raise RunGoingOn(
                    f"{len(running)} runs are going on already, the most the editor runs at a time; wait for one to "
                    "end or stop it"
                )
            cmd = [sys.executable, "-m", "mmusv.editor.job", str(path), str(out)]
            shown = f"mmusv run {path.name} -o {rel_out} --overwrite"
            if frames is not None:
                cmd += ["--frames", str(frames)]
                shown += f" --frames {frames}"
            job = Job(id=next(self._ids), scenario=path.name, output=str(rel_out), command=shown)
            job.process = subprocess.Popen(
                cmd,
                cwd=self.root,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
                env={**os.environ, "PYTHONUNBUFFERED": "1"},
            )
            self._jobs[job.id] = job
            # A long-lived server keeps the newest KEEP_FINISHED finished runs (their records, and the threads that
            # followed them), not every run it ever started.
            finished = sorted((j.id for j in self._jobs.values() if j.status != "running"), reverse=True)
            for old in finished[KEEP_FINISHED:]:
                del self._jobs[old]
            self._followers = [t for t in self._followers if t.is_alive()]
        follower = threading.Thread(target=self._follow, args=(job,), daemon=True)
        self._followers.append(follower)
        follower.start()
        return job

    def _follow(self, job: Job) -> None:
        proc = job.process
        assert proc is not None and proc.stdout is not None and proc.stderr is not None
        final: dict[str, Any] | None = None
        for line in proc.stdout:
            try:
                msg = json.loads(line)
            except json.JSONDecodeError:
                continue
            if not isinstance(msg, dict):
                continue
            with self._lock:
                if "done" in msg:
                    job.done, job.total = int(msg["done"]), int(msg["total"])
                elif "warning" in msg:
                    job.warnings.append(str(msg["warning"]))
                elif "status" in msg:
                    final = msg
        err = proc.stderr.read()
        code = proc.wait()
        proc.stdout.close()  # read to the end: the pipes are done with (a forgotten run leaves none open)
        proc.stderr.close()
        with self._lock:
            if final is None and job.stop_requested:  # stopped while Python was still starting
                job.status = "interrupted"
                job.error = "stopped before the first frame"
            elif final is None:
                job.status = "failed"
                tail = err.strip().splitlines()[-1:] if err.strip() else []
                job.error = f"the run process ended with status {code}" + (f": {tail[0]}" if tail else "")
            else:
                job.status = str(final["status"])
                job.error = final.get("error")
                job.recording = final.get("recording")
                job.seconds = final.get("seconds")
                if "frames" in final:
                    job.done = int(final["frames"])

    def get(self, job_id: int) -> Job:
        """The run ``job_id``; :class:`NotFoundError` when there is none."""
        with self._lock:
            if job_id not in self._jobs:
                raise NotFoundError(f"no run {job_id} (the editor keeps its newest {KEEP_FINISHED} finished runs)")
            return self._jobs[job_id]

    def all(self) -> list[Job]:
        """Every run of this server, newest first."""
        with self._lock:
            return sorted(self._jobs.values(), key=lambda j: -j.id)

    def cancel(self, job_id: int) -> Job:
        """Stops a running run with SIGINT (its recording keeps every completed frame)."""
        job = self.get(job_id)
        if job.status == "running" and job.process is not None and job.process.poll() is None:
            job.stop_requested = True
            job.process.send_signal(signal.SIGINT)
        return job

    def shutdown(self, *, timeout: float = 10.0) -> None:
        """Stops every running run (SIGINT: each finishes its recording with every completed frame), waits for
        them all (``timeout`` seconds in all), kills any still running, and reaps every process and the threads
        that follow them, so the server leaves no child behind."""
        import time

        running = [j for j in self.all() if j.process is not None and j.process.poll() is None]
        for job in running:
            assert job.process is not None
            job.stop_requested = True
            job.process.send_signal(signal.SIGINT)
        deadline = time.monotonic() + timeout
        for job in running:
            assert job.process is not None
            try:
                job.process.wait(timeout=max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                job.process.kill()
                job.process.wait()
        for follower in self._followers:
            follower.join(timeout=max(0.1, deadline - time.monotonic()))


_MANIFEST_STATUSES = ("complete", "interrupted", "failed")


def _earlier_runs(root: Path) -> list[Job]:
    """The finished runs in ``root/out`` (see the module docstring), oldest first (by their manifest's time, then
    name); ids are given by the caller. A folder without a readable manifest of a known status (a run going on or
    killed, or not a run) or without its scenario file in ``root`` is not a run the editor shows."""
    found: list[tuple[float, str, Job]] = []
    out = root / "out"
    try:
        folders = sorted(p for p in out.iterdir() if p.is_dir() and not p.is_symlink())
    except OSError:
        return []
    for folder in folders:
        files = [root / f"{folder.name}{ext}" for ext in (".yaml", ".yml")]
        scenario = next((f for f in files if f.is_file()), None)
        manifest = folder / "manifest.json"
        try:
            meta = json.loads(manifest.read_text(encoding="utf-8"))
            when = manifest.stat().st_mtime
        except (OSError, UnicodeDecodeError, json.JSONDecodeError):
            continue
        if scenario is None or not isinstance(meta, dict) or meta.get("status") not in _MANIFEST_STATUSES:
            continue
        written, requested, recording = meta.get("frames_written"), meta.get("frames_requested"), meta.get("recording")
        if not isinstance(written, int) or not isinstance(recording, str):
            continue
        rel = f"out/{folder.name}"
        status = str(meta["status"])
        error, frames = None, counted(written, "frame")
        if status == "interrupted":
            error = f"stopped before the end; the recording holds {frames}"
        elif status == "failed":
            error = f"the run failed; the recording holds its first {frames} (mmusv info {rel})"
        job = Job(
            id=0,
            scenario=scenario.name,
            output=rel,
            command=f"mmusv run {scenario.name} -o {rel} --overwrite",
            status=status,
            done=written,
            total=requested if isinstance(requested, int) else None,
            error=error,
            recording=str(folder / recording),
            earlier=True,
        )
        found.append((when, folder.name, job))
    return [job for _, _, job in sorted(found, key=lambda t: (t[0], t[1]))]
