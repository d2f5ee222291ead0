"""The batch runner: every scenario of a folder (or a list of files) through :func:`mmusv.acquire.run`, on the
local pool or Ray, restartable and fault-tolerant. ``mmusv run DIR`` and :func:`mmusv.run_many` both end here.

1. Plan (:mod:`mmusv.batch.plan`): load every file (an invalid one fails alone), hash it, skip the recordings
   that are complete with the same config hash, split long ones into frame ranges when asked.
2. Run the remaining tasks on the executor (:mod:`mmusv.batch.executors`, :mod:`mmusv.batch.ray_backend`). A
   failed task is run again up to ``retries`` times unless its input is bad (it would fail the same way); a
   task whose worker died is run again up to ``lost_worker_retries`` times (by Ray itself on Ray).
3. Keep ``dataset.json`` (:mod:`mmusv.batch.index`) up to date after every task, so a killed driver leaves an
   index of what is done; the finished index holds no times, so it is the same bytes however many runs it took.

Determinism: a task's bytes depend only on its scenario and frames, never on the executor, the worker or the
order of completion.
"""

from __future__ import annotations

import os
import re
import time
import uuid
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mmusv import arguments
from mmusv.batch.executors import (
    Executor,
    PoolExecutor,
    SerialExecutor,
    available_cpus,
    refuse_in_daemon,
    refuse_in_worker_import,
)
from mmusv.batch.index import (
    INDEX_NAME,
    Entry,
    check_extra,
    check_replaceable,
    folder_bytes,
    index_entries,
    read_earlier_index,
    write_index,
)
from mmusv.batch.plan import ScenarioPlan, plan_scenarios, prepare, scenario_files, task_complete
from mmusv.batch.task import TaskResult
from mmusv.errors import ConfigError, IoError, MmusvError
from mmusv.held_signals import raise_noted_stop
from mmusv.recording.guard import FolderLock

__all__ = ["BatchReport", "ScenarioOutcome", "run_many"]


@dataclass
class ScenarioOutcome:
    """How one scenario of a batch ended: ``status`` ``done`` (recorded now), ``skipped`` (already complete) or
    ``failed`` (``error``); frames recorded (all of them, old parts included), ``retried`` attempts of this run,
    ``seconds`` of work summed over its tasks, warnings raised while it ran, ``threads`` (the core threads its
    workers used, ``RAYON_NUM_THREADS``; ``None`` when not set)."""

    name: str
    file: Path
    status: str
    scenario: str | None
    config_hash: str | None
    frames: int
    frames_requested: int
    parts: int
    recording: Path | None
    retried: int = 0
    error: str | None = None
    seconds: float = 0.0
    warnings: list[str] = field(default_factory=list)
    threads: list[str | None] = field(default_factory=list)


@dataclass
class BatchReport:
    """What a batch run did: one :class:`ScenarioOutcome` per file (sorted by name), the executor (``serial``,
    ``pool`` or ``ray``), the index written and the wall time."""

    out_dir: Path
    backend: str
    outcomes: list[ScenarioOutcome]
    index: Path
    seconds: float = 0.0
    index_error: str | None = None
    """Why the index could not be written at the end (a full disk), else None."""
    kept: list[str] = field(default_factory=list)
    """Recordings an earlier run into the folder indexed that this run does not record (names, sorted): its index
    keeps listing them."""

    def count(self, status: str) -> int:
        """How many scenarios ended with ``status``."""
        return sum(1 for o in self.outcomes if o.status == status)

    @property
    def retried(self) -> int:
        """Attempts made again in this run, over all scenarios."""
        return sum(o.retried for o in self.outcomes)

    @property
    def ok(self) -> bool:
        """True when no scenario failed."""
        return self.count("failed") == 0

    def summary(self) -> str:
        """``"3 done, 1 failed, 2 skipped, 1 retried"``."""
        return (
            f"{self.count('done')} done, {self.count('failed')} failed, {self.count('skipped')} skipped, "
            f"{self.retried} retried"
        )


def _executor(jobs: int, ray: bool | str, cpus_per_task: int | None, lost_worker_retries: int) -> Executor:
    if ray is not False and ray is not None:
        from mmusv.batch.ray_backend import RayExecutor

        return RayExecutor(ray, num_cpus=cpus_per_task or 1, max_retries=lost_worker_retries)
    if jobs == 1 and cpus_per_task is None:
        return SerialExecutor()
    threads = cpus_per_task if cpus_per_task is not None else max(1, available_cpus() // jobs)
    return PoolExecutor(jobs, threads)


def join_ray(ray: bool | str, *, cpus_per_task: int | None = None, lost_worker_retries: int = 3) -> Executor:
    """Ray started or joined as :func:`run_many` ``(ray=ray, cpus_per_task=..., lost_worker_retries=...)`` joins it,
    its arguments checked as there: for a caller that must know Ray is there before it changes anything
    (:func:`mmusv.batch.dataset.build_dataset` generates and removes before its batch). A :func:`run_many` called
    meanwhile uses the Ray this joined; :meth:`~mmusv.batch.executors.Executor.close` leaves it.

    Raises:
        ConfigError: bad arguments, Ray asked for but missing, or a cluster without the CPUs of one task.
        IoError: Ray cannot be started or joined."""
    if ray is False or not isinstance(ray, (bool, str)) or (isinstance(ray, str) and not ray.strip()):
        raise ConfigError(f"ray = {arguments.shown(ray)}: must be True, 'local', 'auto' or a Ray address to join")
    if cpus_per_task is not None:
        cpus_per_task = arguments.whole(cpus_per_task, name="cpus_per_task", lo=1)
    lost_worker_retries = arguments.whole(lost_worker_retries, name="lost_worker_retries", lo=0)
    return _executor(1, ray, cpus_per_task, lost_worker_retries)


def _portable_error(error: str | None, plan: ScenarioPlan, root: Path) -> str | None:
    """``error`` as the index keeps it, without the absolute paths the batch's messages name (the scenario file, the
    output folders: the batch makes them absolute), so that the index holds none and is the same bytes wherever the
    scenarios and the output are: the scenario file by its name (as ``scenario_file``), another file of its folder
    by its name, and a path below the index's folder relative to it (that folder itself: ``.``). The console keeps
    the full paths. Before, a failed scenario's ``error`` began with ``/home/me/scenarios/bad.yaml: ...``."""
    if error is None:
        return None
    text = error.replace(str(plan.file), plan.file.name)
    # the longer folder first: the scenarios may sit below the index's folder (mmusv dataset's DIR/scenarios); a
    # folder only where a path starts (not inside /private/tmp/out for /tmp/out) and ends (not /tmp/output)
    seps = re.escape("/" + os.sep)
    for folder in sorted({str(plan.file.parent), str(root)}, key=len, reverse=True):
        folder = folder.rstrip("/" + os.sep)
        if not folder:  # the file system's root: every absolute path's prefix
            continue
        head = r"(?<![\w.~" + seps + r"])" + re.escape(folder)
        text = re.sub(head + "[" + seps + r"]+(?=[^\s:;,'\")\]])", "", text)  # a path below it: relative
        if folder == str(root).rstrip("/" + os.sep):  # the index's folder itself: .
            text = re.sub(head + "[" + seps + r"]*(?![^\s:;,'\")\].])|" + head + r"(?=\.(?:\s|$))", ".", text)
    return text


def _entry(plan: ScenarioPlan, status: str, error: str | None, root: Path) -> Entry:
    from mmusv.jsonio import read_json

    frames = 0
    for t in plan.tasks:
        try:
            m = read_json(Path(t.out_dir) / "manifest.json")
        except MmusvError:  # no (readable) manifest: nothing of this task recorded
            continue
        n = m.get("frames_written")
        # a damaged count ('abc', 1e400, [3]) was a bare ValueError or TypeError before the batch began: such a
        # task is not complete (plan.task_complete), so it runs again and writes its manifest anew; until then
        # the index counts none of its frames
        if (
            m.get("config_hash") == plan.config_hash
            and isinstance(n, int)
            and not isinstance(n, bool)
            and 0 < n <= t.expected_frames
        ):
            frames += n
    rec = None if plan.recording is None else plan.recording.relative_to(root).as_posix()
    return Entry(
        name=plan.name,
        scenario_file=plan.file.name,
        scenario=plan.scenario,
        config_hash=plan.config_hash,
        seed=plan.seed,
        recording=rec,
        status=status,
        frames=frames,
        frames_requested=plan.frames,
        parts=len(plan.tasks) if plan.split else (1 if plan.tasks else 0),
        bytes=folder_bytes(plan.folder) if plan.folder.is_dir() else 0,
        error=_portable_error(error, plan, root),
    )


def run_many(
    source: str | os.PathLike[str] | Sequence[str | os.PathLike[str]],
    *,
    out_dir: str | os.PathLike[str],
    jobs: int = 1,
    ray: bool | str = False,
    cpus_per_task: int | None = None,
    retries: int = 0,
    lost_worker_retries: int = 3,
    split_frames: int | None = None,
    frames: int | None = None,
    overwrite: bool = False,
    checks: bool = True,
    index: str | os.PathLike[str] | None = None,
    index_extra: Mapping[str, Any] | None = None,
    progress: Callable[[int, int], None] | None = None,
    stop_on_full_disk: bool = False,
    replace: Collection[str] = (),
) -> BatchReport:
    """Runs every scenario of ``source`` (a folder of ``*.yaml`` and ``*.yml``, or a list of files) into
    ``out_dir/<stem>/``.

    Args:
        jobs: processes of the local pool (1: in this process); ignored with ``ray``.
        ray: ``False`` (the local pool), ``True`` / ``"local"`` (a local Ray instance), ``"auto"`` or an address
            (join a cluster); see :mod:`mmusv.batch.ray_backend`.
        cpus_per_task: CPUs of one task = its core threads (``RAYON_NUM_THREADS``). Default: 1 on Ray, the CPUs
            shared out between ``jobs`` on the pool, the core's default in this process.
        retries: runs of a failed task after the first (not for bad input, which fails the same way again).
        lost_worker_retries: runs of a task whose worker died (Ray's ``max_retries`` on Ray).
        split_frames: record scenarios longer than this as parts of this many frames, one task each.
        frames: record only the first ``frames`` of every scenario.
        overwrite: run every scenario again, and replace complete recordings of another configuration (without
            it those fail).
        checks: the route checks of :func:`mmusv.acquire.run`.
        index: where ``dataset.json`` goes (default ``out_dir/dataset.json``); ``index_extra``: extra sections
            (a dict of plain JSON values, keyed by names other than the index's own ``format``, ``version``,
            ``recordings`` and ``totals``; checked before anything runs).
        progress: called with (frames done, frames in all) after each task (skipped frames count as done).
        stop_on_full_disk: when a task fails because the disk is full (``No space left on device``), stop: the
            tasks not started are cancelled and reported as failed with that cause (the default goes on, marking
            each recording that cannot be written failed).
        replace: file stems whose complete recording of another configuration (or of other frames) is replaced
            as ``overwrite`` does, while a complete recording of the same one is still skipped (``mmusv dataset``
            passes the recordings its earlier run indexed, so a changed spec records its changed scenarios again).

    The output folder is locked while the batch runs (:class:`~mmusv.recording.guard.FolderLock`): a second batch
    (or ``mmusv run``) into it fails at once.

    Returns:
        the :class:`BatchReport`; ``report.ok`` is False when a scenario failed.

    Raises:
        ConfigError: bad options, an empty folder, Ray asked for but missing. A bad scenario is not raised: it is
        reported as failed while the others run.
        IoError: Ray cannot be started or joined (raised before anything is written: an earlier index stays as it
        was), or another batch writes the output folder.
        KeyboardInterrupt: after the executor stopped and the index says what is done.
    """
    refuse_in_worker_import("mmusv.run_many")
    t0 = time.perf_counter()
    jobs = arguments.whole(jobs, name="jobs", lo=1)
    retries = arguments.whole(retries, name="retries", lo=0)
    lost_worker_retries = arguments.whole(lost_worker_retries, name="lost_worker_retries", lo=0)
    if cpus_per_task is not None:
        cpus_per_task = arguments.whole(cpus_per_task, name="cpus_per_task", lo=1)
    if split_frames is not None:
        split_frames = arguments.whole(split_frames, name="split_frames", lo=1)
    if frames is not None:
        frames = arguments.whole(frames, name="frames", lo=1)
    overwrite = arguments.flag(overwrite, name="overwrite")
    checks = arguments.flag(checks, name="checks")
    stop_on_full_disk = arguments.flag(stop_on_full_disk, name="stop_on_full_disk")
    progress = arguments.callback(progress, name="progress", nargs=2)
    index_extra = arguments.mapping(index_extra, name="index_extra")
    check_extra(index_extra, name="index_extra")
    if isinstance(replace, (str, bytes)) or not isinstance(replace, Iterable):
        raise ConfigError(f"replace = {arguments.shown(replace)}: must be a collection of scenario file stems")
    stems = frozenset(replace)
    if not all(isinstance(n, str) for n in stems):
        raise ConfigError(f"replace = {arguments.shown(replace)}: must be a collection of scenario file stems")
    # an empty address (an unset variable) started a local instance without a word, not the cluster meant
    if not isinstance(ray, (bool, str)) or (isinstance(ray, str) and not ray.strip()):
        raise ConfigError(f"ray = {arguments.shown(ray)}: must be False, True, 'local', 'auto' or a Ray address")
    if ray is False and (jobs > 1 or cpus_per_task is not None):  # the local pool (see _executor)
        refuse_in_daemon(f"mmusv.run_many(jobs={jobs})")
    files = scenario_files(source)
    out = arguments.path(out_dir, name="out_dir").resolve()
    index_path = arguments.path(index, name="index").resolve() if index is not None else out / INDEX_NAME
    root = index_path.parent
    check_replaceable(index_path, writer="the batch")
    earlier = read_earlier_index(index_path)
    spec = earlier.get("spec")
    if index_extra is None and isinstance(spec, dict) and not overwrite:
        raise IoError(
            f"{index_path} is the index of an `mmusv dataset` run (spec {spec.get('name')!r}): a batch run there "
            "would replace it with one of its own, losing its spec and opv2v sections; run into another folder "
            "(-o), or pass --overwrite (overwrite=True in Python) to replace it"
        )
    plans = plan_scenarios(
        files,
        out,
        frames=frames,
        split_frames=split_frames,
        overwrite=overwrite,
        checks=checks,
        run_id=uuid.uuid4().hex,
        replace=stems,
    )
    for p in plans:
        if p.recording is not None and not p.recording.is_relative_to(root):
            raise ConfigError(f"index {index_path} must be in a folder above the output {out}")
    names = {p.name for p in plans}
    kept = [e for e in index_entries(earlier) if e.name not in names and e.recording and (root / e.recording).is_file()]
    # The executor first: Ray that cannot be imported or joined fails the batch here, before anything is written
    # (it wrote an index calling every scenario pending, and readied their folders, as if work had been scheduled).
    executor = _executor(jobs, ray, cpus_per_task, lost_worker_retries) if any(p.to_run for p in plans) else None
    try:
        lock = FolderLock.create(out, what="mmusv run (batch)")
    except BaseException:
        if executor is not None:
            executor.close(cancel=True)
        raise
    try:
        return _run(
            plans,
            out,
            root,
            index_path,
            index_extra,
            executor,
            retries,
            lost_worker_retries,
            progress,
            stop_on_full_disk,
            t0,
            kept,
        )
    finally:
        lock.release()


def _run(
    plans: list[ScenarioPlan],
    out: Path,
    root: Path,
    index_path: Path,
    index_extra: Mapping[str, Any] | None,
    started: Executor | None,
    retries: int,
    lost_worker_retries: int,
    progress: Callable[[int, int], None] | None,
    stop_on_full_disk: bool,
    t0: float,
    kept: list[Entry],
) -> BatchReport:
    """The batch of :func:`run_many` once planned, with the output folder locked, on the executor ``started``
    (``None`` when nothing was to run; closed here)."""
    status: dict[str, str] = {}
    errors: dict[str, str | None] = {}
    retried: dict[str, int] = {}
    results: dict[str, TaskResult] = {}
    try:
        for p in plans:
            _prepare(p)
        for p in plans:
            status[p.name] = "failed" if p.error else "pending" if p.to_run else "complete"
            errors[p.name] = p.error
        # an earlier run's recordings that this one does not record (a folder run before with more scenarios, or
        # another folder run into the same output) stay listed: the index was rewritten with this run's alone,
        # leaving them on disk unlisted, so that conversion and the studies no longer read them
        entries = {e.name: e for e in kept}
        entries.update({p.name: _entry(p, status[p.name], errors[p.name], root) for p in plans})
    except BaseException:
        if started is not None:
            started.close(cancel=True)
        raise

    index_error: list[str] = []

    def write() -> None:  # a full disk must not stop the batch: the index is written again after the next task
        try:
            write_index(index_path, entries.values(), extra=index_extra)
            index_error.clear()
        except IoError as exc:
            index_error[:] = [str(exc)]

    todo = [t for p in plans for t in p.to_run]
    if started is not None and not todo:  # every scenario that was to run failed to ready its folder
        started.close(cancel=False)
    executor: Executor = started if started is not None and todo else SerialExecutor()
    total_frames = sum(p.frames for p in plans if not p.error)
    done_frames = total_frames - sum(t.expected_frames for t in todo)
    by_key = {t.key: t for t in todo}
    plan_of = {t.key: p for p in plans for t in p.to_run}
    left = {p.name: len(p.to_run) for p in plans}
    interrupted = False
    full_disk: str | None = None
    try:
        write()
        if progress is not None:
            progress(done_frames, total_frames)
        for t in todo:
            executor.submit(t)
        tries = dict.fromkeys(by_key, 1)
        lost_tries = dict.fromkeys(by_key, 0)
        while executor.in_flight():
            raise_noted_stop()  # a stop whose KeyboardInterrupt a library swallowed (held_signals)
            task, res = executor.next_done()
            plan = plan_of[task.key]
            if res.status != "done" and res.disk_full and stop_on_full_disk and full_disk is None:
                full_disk = res.error or "No space left on device"
                for t in executor.cancel_pending():  # not started: they would fail the same way
                    results[t.key] = TaskResult(
                        key=t.key, status="failed", error=f"not run: the disk is full ({task.key}: {full_disk})"
                    )
                    left[plan_of[t.key].name] -= 1
                    if errors[plan_of[t.key].name] is None:
                        errors[plan_of[t.key].name] = results[t.key].error
                    if left[plan_of[t.key].name] == 0:
                        name = plan_of[t.key].name
                        status[name] = "failed"
                        entries[name] = _entry(plan_of[t.key], "failed", errors[name], root)
                write()
            if res.status != "done":
                again = False
                if full_disk is not None:
                    pass  # stopping: nothing is run again
                elif res.lost and not executor.retries_lost_workers and lost_tries[task.key] < lost_worker_retries:
                    lost_tries[task.key] += 1
                    again = True
                elif res.retryable and tries[task.key] <= retries:
                    tries[task.key] += 1
                    again = True
                if again:
                    retried[task.key] = retried.get(task.key, 0) + 1
                    executor.submit(task)
                    continue
            results[task.key] = res
            left[plan.name] -= 1
            done_frames += task.expected_frames
            if res.status != "done" and errors[plan.name] is None:
                errors[plan.name] = res.error
            if left[plan.name] == 0:
                status[plan.name] = "failed" if errors[plan.name] else "complete"
                entries[plan.name] = _entry(plan, status[plan.name], errors[plan.name], root)
                write()
            if progress is not None:
                progress(done_frames, total_frames)
    except KeyboardInterrupt:
        interrupted = True
        raise
    finally:
        executor.close(cancel=interrupted)
        if interrupted:
            # a task that ended while the stop came (its worker wrote the recording, the driver never heard of
            # it) is complete on disk: the index says so, not "pending"
            for p in plans:
                if status[p.name] == "pending" and _complete_on_disk(p):
                    status[p.name] = "complete"
                    entries[p.name] = _entry(p, "complete", None, root)
            write()
    outcomes = [_outcome(p, status[p.name], errors[p.name], retried, results) for p in plans]
    if index_error:
        write()
    return BatchReport(
        out_dir=out,
        backend=executor.name,
        outcomes=outcomes,
        index=index_path,
        seconds=time.perf_counter() - t0,
        index_error=index_error[0] if index_error else None,
        kept=sorted(e.name for e in kept),
    )


def _prepare(plan: ScenarioPlan) -> None:
    """:func:`~mmusv.batch.plan.prepare` of one scenario; a folder that cannot be readied (``OUT/<stem>`` is a
    file, ...) fails that scenario alone (the batch ended at once in one line naming a ``.parts.json`` no one
    asked for, running none of the others)."""
    # a part's folder (or OUT/<stem>/parts) that is a file failed each of its tasks as an "internal error
    # NotADirectoryError" of the worker; checked before prepare, which removes the other layout's recording and
    # writes the parts manifest of a scenario that then fails
    for t in plan.to_run:
        folder = Path(t.out_dir)
        for d in (folder, *folder.parents):
            if d == plan.folder:
                break
            if d.exists() and not d.is_dir():
                plan.error = (
                    f"{plan.file}: the folder of its part {d} is a file: move it away (the parts are recorded into "
                    "OUT/<stem>/parts/<first>-<last>/)"
                )
                plan.tasks, plan.to_run = [], []
                return
    try:
        prepare(plan)
    except OSError as exc:
        if plan.folder.exists() and not plan.folder.is_dir():
            why = f"its output folder {plan.folder} is a file: move it away (the recording goes into OUT/<stem>/)"
        else:
            where = f" ({exc.filename})" if exc.filename else ""
            why = f"cannot prepare its output folder {plan.folder}{where}: {exc.strerror or exc}"
        plan.error = f"{plan.file}: {why}"
        plan.tasks, plan.to_run = [], []


def _complete_on_disk(plan: ScenarioPlan) -> bool:
    """Whether every task of ``plan`` is complete in its folder (:func:`~mmusv.batch.plan.task_complete`)."""
    if plan.error is not None or plan.scenario is None or plan.config_hash is None or not plan.tasks:
        return False
    return all(
        task_complete(
            Path(t.out_dir),
            scenario=plan.scenario,
            config_hash=plan.config_hash,
            frames=t.expected_frames,
            first_frame=t.first_frame,
        )
        for t in plan.tasks
    )


def _outcome(
    plan: ScenarioPlan, status: str, error: str | None, retried: dict[str, int], results: dict[str, TaskResult]
) -> ScenarioOutcome:
    ran = [results[t.key] for t in plan.to_run if t.key in results]
    # a task's attempts beyond the first: resubmitted by the runner, or re-run by Ray after a lost worker (seen
    # only in the attempt lines of the task file, which count every attempt that got as far as its lock)
    again = sum(max(retried.get(t.key, 0), results[t.key].attempts - 1 if t.key in results else 0) for t in plan.to_run)
    shown = "failed" if status == "failed" else "done" if plan.to_run else "skipped"
    frames = 0 if plan.error else plan.frames
    if status == "failed":
        frames = sum(r.frames for r in ran if r.status == "done") + sum(
            t.expected_frames for t in plan.tasks if t not in plan.to_run
        )
    return ScenarioOutcome(
        name=plan.name,
        file=plan.file,
        status=shown,
        scenario=plan.scenario,
        config_hash=plan.config_hash,
        frames=frames,
        frames_requested=plan.frames,
        parts=len(plan.tasks) if plan.split else (1 if plan.tasks else 0),
        recording=plan.recording,
        retried=again,
        error=error,
        seconds=sum(r.seconds for r in ran),
        warnings=sorted({w for r in ran for w in r.warnings}),
        threads=[r.threads for r in ran],
    )
