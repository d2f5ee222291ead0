"""One task of a batch run, as a worker runs it (a process of the local pool, a Ray worker, or the driver itself).

:func:`execute` takes the task's lock file ``OUT/.mmusv/<key>.task`` (so a re-run never writes a folder that a
worker of a killed run is still writing: it waits until that worker is gone), appends one line for this attempt
(the driver's run id: the lines of this run count the attempts, a worker lost and retried included), removes the
old ``manifest.json``, runs :func:`mmusv.acquire.run` and empties the file again once the recording is complete.
It never raises for a failure of the scenario: everything comes back as a :class:`TaskResult`. A stop raises
``KeyboardInterrupt``, also where a library made an error of its own of it (:func:`mmusv.held_signals.stops_unwrapped`).
"""

from __future__ import annotations

import errno
import os
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType

from mmusv.batch.plan import Task
from mmusv.errors import InternalError, IoError, MmusvError
from mmusv.held_signals import stops_unwrapped

__all__ = ["LOCK_TIMEOUT_S", "TaskResult", "execute", "lost"]

LOCK_TIMEOUT_S = 120.0
"""How long a task waits for the lock of its folder before it fails (retryably)."""


@dataclass
class TaskResult:
    """How one attempt of a task ended: ``status`` ``done`` or ``failed`` (``error``; ``retryable`` unless the
    input itself is bad), ``attempts`` (of this run, this one included), frames and bytes written, the worker's
    ``pid`` and ``threads`` (its ``RAYON_NUM_THREADS``, ``None`` when unset), warnings raised while it ran.
    ``lost``: the worker died before it could answer (killed, out of memory); ``disk_full``: see the field."""

    key: str
    status: str
    frames: int = 0
    bytes: int = 0
    seconds: float = 0.0
    error: str | None = None
    retryable: bool = False
    attempts: int = 1
    pid: int = 0
    threads: str | None = None
    warnings: list[str] = field(default_factory=list)
    lost: bool = False
    disk_full: bool = False
    """It failed because the disk is full (``No space left on device``)."""


def lost(task: Task, why: str) -> TaskResult:
    """The result of an attempt whose worker died (``why`` says how)."""
    return TaskResult(key=task.key, status="failed", error=f"worker lost: {why}", retryable=True, lost=True, attempts=0)


class _TaskState:
    """The task's lock and attempt file (see the module docstring)."""

    def __init__(self, path: Path, run_id: str) -> None:
        self.path = path
        self.run_id = run_id
        self.fd = -1
        self.attempts = 0

    def __enter__(self) -> _TaskState:
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise IoError(f"cannot open the task file {self.path}: {exc.strerror or exc}") from None
        self._lock()
        with os.fdopen(os.dup(self.fd), "r+", encoding="utf-8") as f:
            lines = [ln for ln in f.read().splitlines() if ln == self.run_id]
            self.attempts = len(lines) + 1
            f.seek(0)
            f.truncate()
            f.write("\n".join([*lines, self.run_id]) + "\n")
        return self

    def _lock(self) -> None:
        try:
            import fcntl
        except ImportError:  # not POSIX: no cross-process lock, attempts still counted
            return
        deadline = time.monotonic() + LOCK_TIMEOUT_S
        while True:
            try:
                fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                return
            except BlockingIOError:
                if time.monotonic() > deadline:
                    os.close(self.fd)
                    raise IoError(
                        f"{self.path} is locked by another process for {LOCK_TIMEOUT_S:.0f} s: is another mmusv run "
                        "writing the same output folder?"
                    ) from None
                time.sleep(0.1)

    def clear(self) -> None:
        """Empties the file: the task is complete, no attempt is pending."""
        os.ftruncate(self.fd, 0)

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        os.close(self.fd)  # closing releases the lock


def execute(task: Task) -> TaskResult:
    """Runs ``task`` (see the module docstring); returns its result, never raises but ``KeyboardInterrupt`` (a stop,
    or an error a library made of one)."""
    from mmusv.acquire import run
    from mmusv.run_folder import refuse_foreign_files

    t0 = time.perf_counter()
    res = TaskResult(key=task.key, status="failed", pid=os.getpid(), threads=os.environ.get("RAYON_NUM_THREADS"))
    try:
        # an error a library made of a noted stop (the command's, serially; a pool worker's) leaves as the stop
        # (held_signals): the batch ends as stopped, not with the scenario failed by the library's error
        with _TaskState(Path(task.state_file), task.run_id) as state, stops_unwrapped():
            res.attempts = state.attempts
            # a manifest.json (or scenario.yaml) no run wrote is refused before the task's own manifest goes: the
            # plan checked (batch.plan), but a user may have put one there since
            refuse_foreign_files(Path(task.out_dir), task.scenario_file)
            (Path(task.out_dir) / "manifest.json").unlink(missing_ok=True)
            notes: list[str] = []
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                out = run(
                    task.scenario_file,
                    out_dir=task.out_dir,
                    overwrite=True,
                    frames=task.frames,
                    frame_range=task.frame_range,
                    checks=task.checks,
                    notes=notes,
                    check_frames=task.check_frames,
                )
            res.warnings = sorted({str(w.message) for w in caught} | set(notes))
            res.frames, res.bytes = out.frames_written, out.bytes
            if out.frames_written != task.expected_frames:  # cannot happen without an exception; never call it done
                raise InternalError(f"{task.key}: {out.frames_written} of {task.expected_frames} frames written")
            res.status = "done"
            state.clear()
    except MmusvError as exc:
        msg = str(exc)
        res.error = (
            msg if task.scenario_file in msg or Path(task.scenario_file).name in msg else f"{task.scenario_file}: {msg}"
        )
        # bad input fails the same way every time; a file system or internal problem may not
        res.retryable = isinstance(exc, (IoError, InternalError))
        res.disk_full = isinstance(exc, IoError) and os.strerror(errno.ENOSPC) in msg
    except Exception as exc:  # a bug, not bad input: still reported per task, with its type
        res.error = f"{task.scenario_file}: internal error {type(exc).__name__}: {exc}"
        res.retryable = True
    res.seconds = time.perf_counter() - t0
    return res
