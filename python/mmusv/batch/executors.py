"""Where the tasks of a batch run: in the driver itself (one job), a local process pool (``--jobs N``), or Ray
(:mod:`mmusv.batch.ray_backend`). Every executor has the same three calls: :meth:`~Executor.submit` a task,
:meth:`~Executor.next_done` (blocks until one attempt ended, returns the task and its
:class:`~mmusv.batch.task.TaskResult`) and :meth:`~Executor.close`.

The pool spawns its workers (not fork: the driver already runs the core's thread pool, and a forked copy of a
process with threads can deadlock on a lock another thread held). A spawned worker imports the driver's script when
it has one (Python's spawn); a script read from standard input (``python -``, whose ``__file__`` is ``<stdin>``) is
no file to import, and every worker died of it, so the pool starts its workers without it (as from a notebook). A
daemonic process (a ``multiprocessing.Pool`` or DataLoader worker) may not start one: :func:`refuse_in_daemon` says
so before any work. Each worker sets ``RAYON_NUM_THREADS`` to the task's CPU share before the core starts its thread
pool, and exits when the driver is gone (a killed driver leaves no worker writing on). A worker that dies breaks the
pool: every task in flight comes back ``lost``, and the pool is started afresh for the next submission.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Iterator
from typing import Any, Protocol

from mmusv.batch.plan import Task
from mmusv.batch.task import TaskResult, execute, lost
from mmusv.held_signals import note_stop

__all__ = [
    "Executor",
    "PoolExecutor",
    "SerialExecutor",
    "available_cpus",
    "refuse_in_daemon",
    "refuse_in_worker_import",
    "stop_pool",
    "workers_skip_unimportable_main",
]

UNGUARDED = (
    'in a script, put the call under  if __name__ == "__main__":  (the pool\'s worker processes import the script '
    "that starts them, and run what its top level runs)"
)

_REAP_S = 15.0
"""How long a stopped pool worker may take to finish its recording before it is killed."""


def available_cpus() -> int:
    """CPUs this process may run on (its affinity where the OS says, else the CPU count)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def _started_from_a_script() -> bool:
    """Whether this process runs a script file of the user's (which spawned workers import), not ``mmusv``'s own
    command line or an interactive session."""
    import sys

    main = sys.modules.get("__main__")
    spec = getattr(main, "__spec__", None)
    name = getattr(spec, "name", "") or ""
    path = getattr(main, "__file__", None)
    return (
        path is not None
        and not name.startswith("mmusv")
        and os.path.basename(path) not in ("mmusv", "mmusv.exe")
        and _unimportable_main() is None
    )


def _unimportable_main() -> tuple[Any, str] | None:
    """``(module, __file__)`` of ``__main__`` when spawned workers would fail to import it by its path: a script
    that is no file (``python -`` reads it from standard input: ``<stdin>``; a script deleted since), else None.
    A main module run by name (``python -m``) is imported by name, and one without a file (``python -c``, a
    notebook) is not imported at all."""
    import sys
    from multiprocessing import process

    main = sys.modules.get("__main__")
    if main is None or getattr(getattr(main, "__spec__", None), "name", None):
        return None
    path = getattr(main, "__file__", None)
    if not isinstance(path, str):
        return None
    start = getattr(process, "ORIGINAL_DIR", None)  # where spawn looks for a relative script path
    full = path if os.path.isabs(path) or not isinstance(start, str) else os.path.join(start, path)
    return None if os.path.isfile(full) else (main, path)


@contextlib.contextmanager
def workers_skip_unimportable_main() -> Iterator[None]:
    """Around starting spawned workers: hides an ``__main__.__file__`` they could not import
    (:func:`_unimportable_main`), so that they start as from a notebook instead of dying of it."""
    found = _unimportable_main()
    if found is None:
        yield
        return
    main, path = found
    del main.__file__
    try:
        yield
    finally:
        main.__file__ = path


def refuse_in_daemon(what: str) -> None:
    """Raises :class:`~mmusv.errors.ConfigError` when ``what`` (``"mmusv.run_many(jobs=2)"``) would start a
    process pool in a daemonic process (a ``multiprocessing.Pool`` worker, a PyTorch DataLoader worker), which
    Python does not let have child processes (it failed on the first task with a bare ``AssertionError``)."""
    import multiprocessing

    if multiprocessing.current_process().daemon:
        from mmusv.errors import ConfigError

        raise ConfigError(
            f"{what} cannot start its pool of processes here: this process is a daemonic worker (of a "
            "multiprocessing.Pool, a DataLoader), and those may not have child processes; give jobs=1 to record "
            "in this process, or call it from a concurrent.futures.ProcessPoolExecutor worker, which may have them"
        )


def refuse_in_worker_import(what: str) -> None:
    """Raises :class:`~mmusv.errors.ConfigError` when ``what`` (``"mmusv.run_many"``) is called while a pool
    worker imports the script that started the pool (Python's spawn runs the script's top level again, as module
    ``__mp_main__``): the call is not under ``if __name__ == "__main__":`` and would run the batch again inside
    every worker. The worker then dies saying so, and the driver's lost task says it too (:data:`UNGUARDED`)."""
    import sys

    frame = sys._getframe(1)
    while frame is not None:
        if frame.f_code.co_name == "<module>" and frame.f_globals.get("__name__") == "__mp_main__":
            from mmusv.errors import ConfigError

            raise ConfigError(f"{what} was called while a worker process imported the script: {UNGUARDED}")
        frame = frame.f_back  # type: ignore[assignment]


class Executor(Protocol):
    """What the batch runner needs of an executor (see the module docstring)."""

    name: str
    retries_lost_workers: bool
    """True when the executor itself re-runs the task of a lost worker (Ray's ``max_retries``)."""

    def submit(self, task: Task) -> None: ...

    def next_done(self) -> tuple[Task, TaskResult]: ...

    def in_flight(self) -> int: ...

    def cancel_pending(self) -> list[Task]:
        """Takes back the tasks submitted but not started (they will not run) and returns them."""
        ...

    def close(self, *, cancel: bool) -> None: ...


class SerialExecutor:
    """Runs each task in the driver process when :meth:`next_done` asks for it (``--jobs 1``)."""

    name = "serial"
    retries_lost_workers = False

    def __init__(self, run: Callable[[Task], TaskResult] = execute) -> None:
        self._queue: list[Task] = []
        self._run = run

    def submit(self, task: Task) -> None:
        self._queue.append(task)

    def next_done(self) -> tuple[Task, TaskResult]:
        task = self._queue.pop(0)
        return task, self._run(task)

    def in_flight(self) -> int:
        return len(self._queue)

    def cancel_pending(self) -> list[Task]:
        out, self._queue = self._queue, []
        return out

    def close(self, *, cancel: bool) -> None:
        self._queue.clear()


def _init_worker(threads: int | None, driver_pid: int) -> None:
    """Pool worker start: the core's thread pool size, and a watchdog that ends the worker when the driver is
    gone (its parent changes)."""
    import threading
    import time

    if threads is not None:
        os.environ["RAYON_NUM_THREADS"] = str(threads)
    import signal

    signal.signal(signal.SIGTERM, _stop)
    signal.signal(signal.SIGINT, _stop)

    def watch() -> None:
        while True:
            time.sleep(0.5)
            if os.getppid() != driver_pid:
                os._exit(70)

    threading.Thread(target=watch, name="mmusv-driver-watch", daemon=True).start()


_IN_TASK = False
"""True in a pool worker while it runs a task."""
_STOPPING = False
"""True in a pool worker once it was told to stop: it starts no further task (one may already be queued)."""


def _execute(task: Task) -> TaskResult:
    """:func:`~mmusv.batch.task.execute` in a pool worker, marked as running (for :func:`_stop`)."""
    global _IN_TASK
    if _STOPPING:
        raise KeyboardInterrupt
    _IN_TASK = True
    try:
        return execute(task)
    finally:
        _IN_TASK = False


def _stop(signum: int, frame: object) -> None:
    """SIGTERM or SIGINT in a pool worker: a running task finishes its recording as interrupted (raised as
    ``KeyboardInterrupt`` inside it, once) and no further task starts; an idle worker just exits (no traceback).

    A further signal while that task finishes its recording is ignored: a Ctrl-C reaches the driver and every
    worker at once, and the driver's :func:`_reap` sends SIGTERM right after, so a second ``KeyboardInterrupt``
    raised inside the first one's clean-up left the recording a ``.partial`` without its manifest (and, in a
    finaliser, printed a traceback). The stop is noted (:func:`mmusv.held_signals.note_stop`), as the command's
    handler notes its own: where a library swallows that ``KeyboardInterrupt`` the recording's next frame raises it
    again, and where a library wraps it in an error of its own the recording says interrupted, not failed."""
    global _STOPPING
    first = not _STOPPING
    _STOPPING = True
    if _IN_TASK:
        if first:
            # noted as the command's handler notes its stop: one a library swallows in a frame is raised again at
            # the next (it recorded on, ignoring the reaper's SIGTERMs, until killed: a .partial without manifest),
            # and one it wraps in an error of its own is recorded as interrupted, not failed (held_signals)
            note_stop(signum)
            raise KeyboardInterrupt
        return
    os._exit(128 + signum)


def stop_pool(pool: Any, *, signum: int, grace_s: float) -> None:
    """Ends the jobs of ``pool`` (a ``concurrent.futures.ProcessPoolExecutor``) when the work that submitted them
    ends early: the jobs not started are cancelled, each running process gets ``signum`` and is killed if it has not
    ended within ``grace_s`` seconds (one deadline for all). Leaving the pool's ``with`` block alone waits for every
    job submitted. ``mmusv train`` sends SIGINT (a model stops as Ctrl-C stops one trained in turn, its checkpoints
    whole), the detection study's jobs SIGTERM (they write nothing). The batch's own pool is stopped otherwise
    (:func:`_reap`: its workers ignore a second signal while they finish a recording)."""
    import time

    # the pool has no public handle on its processes, and forgets them when shut down
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        if proc.is_alive() and proc.pid is not None:
            with contextlib.suppress(OSError):
                os.kill(proc.pid, signum)
    deadline = time.monotonic() + grace_s
    for proc in processes:
        proc.join(max(0.0, deadline - time.monotonic()))
        if proc.is_alive():
            proc.kill()
            proc.join(1.0)


def _reap(procs: list[Any]) -> None:
    """Stops pool workers: SIGTERM (a running task finishes its recording as interrupted), again every second
    (a worker idle by then exits at once), SIGKILL after :data:`_REAP_S`; every worker is joined (reaped)."""
    import time

    deadline = time.monotonic() + _REAP_S
    while True:
        alive = [p for p in procs if p.is_alive()]
        if not alive:
            return
        if time.monotonic() > deadline:
            for p in alive:
                p.kill()
            for p in alive:
                p.join(timeout=5)
            return
        for p in alive:
            p.terminate()
        for p in alive:
            p.join(timeout=max(0.0, min(1.0, deadline - time.monotonic())))


class PoolExecutor:
    """A local pool of ``jobs`` spawned processes, each with ``threads`` core threads (``None``: the core's
    default, every CPU)."""

    name = "pool"
    retries_lost_workers = False

    def __init__(self, jobs: int, threads: int | None) -> None:
        from concurrent.futures import Future, ProcessPoolExecutor

        self.jobs = jobs
        self.threads = threads
        self._pool: ProcessPoolExecutor | None = None
        self._futures: dict[Future[TaskResult], Task] = {}
        self._finished = 0  # tasks the pool answered (a pool that never answers may be an unguarded script)
        self._dropped: list[Any] = []  # manager threads of the broken pools shut down without waiting

    def _drop(self) -> None:
        """Shuts down a broken pool without waiting (its workers are gone or going), keeping its manager thread
        for :meth:`close` to wait for: still closing the pool's wake-up pipe when the interpreter's exit hook
        wrote to it, it printed "Exception ignored ... OSError: [Errno 9] Bad file descriptor" after a stop."""
        if self._pool is None:
            return
        manager = getattr(self._pool, "_executor_manager_thread", None)
        if manager is not None:
            self._dropped.append(manager)
        self._pool.shutdown(wait=False, cancel_futures=True)
        self._pool = None

    def _ensure(self) -> None:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        if self._pool is None:
            self._pool = ProcessPoolExecutor(
                max_workers=self.jobs,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=_init_worker,
                initargs=(self.threads, os.getpid()),
            )

    def submit(self, task: Task) -> None:
        from concurrent.futures.process import BrokenProcessPool

        self._ensure()
        assert self._pool is not None
        with workers_skip_unimportable_main():  # a submission may start workers
            try:
                fut = self._pool.submit(_execute, task)
            except BrokenProcessPool:  # broken since the last answer: start afresh
                self._drop()
                self._ensure()
                assert self._pool is not None
                fut = self._pool.submit(_execute, task)
        self._futures[fut] = task

    def next_done(self) -> tuple[Task, TaskResult]:
        from concurrent.futures import FIRST_COMPLETED, wait
        from concurrent.futures.process import BrokenProcessPool

        done, _ = wait(list(self._futures), return_when=FIRST_COMPLETED)
        fut = min(done, key=lambda f: self._futures[f].key)
        task = self._futures.pop(fut)
        try:
            result = fut.result()
        except BrokenProcessPool:
            self._drop()
            why = "a process of the local pool died (killed, or out of memory)"
            if self._finished == 0 and _started_from_a_script():
                why = f"{why}; if no task ever finishes: {UNGUARDED}"
            return task, lost(task, why)
        self._finished += 1
        return task, result

    def in_flight(self) -> int:
        return len(self._futures)

    def cancel_pending(self) -> list[Task]:
        out = [task for fut, task in self._futures.items() if fut.cancel()]
        self._futures = {f: t for f, t in self._futures.items() if not f.cancelled()}
        return out

    def close(self, *, cancel: bool) -> None:
        if self._pool is not None:
            if cancel:  # stop now: each worker finishes its recording as interrupted (SIGTERM), then is reaped
                procs = list(getattr(self._pool, "_processes", {}).values())
                self._drop()
                _reap(procs)
            else:
                self._pool.shutdown(wait=True)
            self._pool = None
        for manager in self._dropped:  # see _drop
            manager.join(timeout=_REAP_S)
        self._dropped.clear()
        self._futures.clear()
