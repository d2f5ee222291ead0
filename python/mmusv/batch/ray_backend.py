"""Running the tasks of a batch on Ray (``mmusv run DIR --ray [ADDRESS]``, :func:`mmusv.run_many` ``ray=...``).

Ray is an optional dependency (``pip install 'mmusv[ray]'``). ``address``: ``True`` / ``"local"`` starts a local
Ray instance for this run (stopped at the end); ``"auto"`` or ``HOST:PORT`` (``ray://...`` too) joins a running
cluster. A process already connected to Ray (``ray.init`` called before) keeps its connection.

Every task is one Ray task asking for ``num_cpus`` CPUs and running with ``RAYON_NUM_THREADS`` set to the same
number (its own ``runtime_env``), so the core's thread pool uses exactly what Ray reserved and Ray never
oversubscribes a node. A worker that dies (killed, node lost, out of memory) is re-run by Ray itself
(``max_retries``); a task that fails is re-run by the batch runner (``--retries``). The tasks read the scenario
files and write the output folder by absolute path: both must be on storage every node sees at the same path.
"""

from __future__ import annotations

import contextlib
import logging
from typing import Any

from mmusv.batch.plan import Task
from mmusv.batch.task import TaskResult, execute, lost
from mmusv.errors import ConfigError, IoError

__all__ = ["INSTALL_HINT", "RayExecutor", "import_ray"]

INSTALL_HINT = "pip install 'mmusv[ray]' (or pip install ray)"


def import_ray() -> Any:
    """The ``ray`` module; :class:`~mmusv.errors.ConfigError` saying how to install it when it is missing."""
    try:
        import ray
    except ImportError:
        raise ConfigError(f"--ray needs Ray, which is not installed: {INSTALL_HINT}") from None
    return ray


class RayExecutor:
    """Submits tasks as Ray tasks of ``num_cpus`` CPUs each (see the module docstring)."""

    name = "ray"
    retries_lost_workers = True

    def __init__(self, address: str | bool, *, num_cpus: int, max_retries: int) -> None:
        if num_cpus < 1:
            raise ConfigError(f"cpus per task = {num_cpus}: must be at least 1")
        ray = import_ray()
        self._ray = ray
        self.num_cpus = num_cpus
        self.max_retries = max_retries
        self.owned = False
        self._refs: dict[Any, Task] = {}
        if not ray.is_initialized():
            # "local" always starts a new instance (Ray would otherwise join one it finds on this machine)
            where = "local" if address is True or address in ("local", "") else str(address)
            try:
                ray.init(
                    address=where,
                    include_dashboard=False,
                    log_to_driver=False,
                    logging_level=logging.WARNING,
                    configure_logging=True,
                )
            except (ConnectionError, RuntimeError, ValueError) as exc:
                why = str(exc)
                if where == "auto" and "Please specify" in why:
                    # Ray's own advice names its `--address` flag and RAY_ADDRESS, which mmusv does not take
                    why = (
                        why.split("Please specify", 1)[0].strip().rstrip(".")
                        + " (`ray start --head` starts one on this machine); give --ray HOST:PORT for a cluster's "
                        "head, or --ray without an address for a local instance of this run only"
                    )
                raise IoError(f"--ray {where}: cannot start or join Ray: {why}") from None
            self.owned = True
        total = ray.cluster_resources().get("CPU", 0)
        if total < num_cpus:
            self.close(cancel=True)
            raise ConfigError(
                f"cpus per task = {num_cpus}, but the Ray cluster has {total:g} CPUs: no task could ever be scheduled"
            )
        self._remote = ray.remote(execute)

    @property
    def cluster_cpus(self) -> float:
        """CPUs of the Ray cluster."""
        return float(self._ray.cluster_resources().get("CPU", 0))

    def submit(self, task: Task) -> None:
        ref = self._remote.options(
            num_cpus=self.num_cpus,
            max_retries=self.max_retries,
            retry_exceptions=False,
            runtime_env={"env_vars": {"RAYON_NUM_THREADS": str(self.num_cpus)}},
            name=f"mmusv:{task.key}",
        ).remote(task)
        self._refs[ref] = task

    def next_done(self) -> tuple[Task, TaskResult]:
        ray = self._ray
        ready, _ = ray.wait(list(self._refs), num_returns=1)
        ref = ready[0]
        task = self._refs.pop(ref)
        try:
            res: TaskResult = ray.get(ref)
            return task, res
        except ray.exceptions.RayError as exc:  # the worker (or its node) died more often than max_retries
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            return task, lost(task, f"{type(exc).__name__} after {self.max_retries} Ray retries: {first}")

    def in_flight(self) -> int:
        return len(self._refs)

    def cancel_pending(self) -> list[Task]:
        """Ray does not say which tasks have started: none is taken back (those running fail on their own)."""
        return []

    def close(self, *, cancel: bool) -> None:
        if cancel:
            for ref in list(self._refs):
                with contextlib.suppress(Exception):  # already finished or gone: nothing to stop
                    self._ray.cancel(ref, force=True)
        self._refs.clear()
        if self.owned:
            self._ray.shutdown()
            self.owned = False
