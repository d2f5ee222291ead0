"""What mmusv can do in a process made by ``os.fork()`` (Linux's default start method of ``multiprocessing`` and
of a PyTorch ``DataLoader``'s workers).

The core's own parallel work survives a fork: a child runs it on a thread pool of its own
(``mmusv_core::threads``), so capturing frames in forked workers gives the parent's bytes. Polars, which writes
and reads the Parquet tables, does not: once its thread pool has started in the parent, a Polars computation in
the child waits forever for threads that are not there (the Polars guide: use ``spawn``). So that such a child
stops with a message instead of hanging, mmusv notes at each fork whether Polars' threads were running
(``/proc/self/task``, Linux), and :func:`check_polars` refuses the table work in a child forked after they were.
"""

from __future__ import annotations

import os
from pathlib import Path

from mmusv.errors import ConfigError

__all__ = ["check_polars", "polars_threads_running"]

_running_at_fork = False
"""Whether Polars' threads were running when this process was forked from its parent (False in a process not
made by fork)."""
_seen_before_fork = False


def polars_threads_running() -> bool:
    """Whether this process runs Polars' thread pool (threads named ``polars-N``; False where ``/proc`` is not
    there to say)."""
    try:
        tasks = list(Path("/proc/self/task").iterdir())
    except OSError:
        return False
    for task in tasks:
        try:
            name = (task / "comm").read_text(encoding="utf-8", errors="replace").strip()
        except OSError:
            continue
        if name.startswith("polars-") and name[7:].isdigit():
            return True
    return False


def _before_fork() -> None:
    global _seen_before_fork
    _seen_before_fork = polars_threads_running()


def _after_fork_in_child() -> None:
    global _running_at_fork
    _running_at_fork = _running_at_fork or _seen_before_fork


if hasattr(os, "register_at_fork"):
    os.register_at_fork(before=_before_fork, after_in_child=_after_fork_in_child)


def check_polars(what: str) -> None:
    """Raises :class:`~mmusv.errors.ConfigError` when ``what`` (``"mmusv.run"``), which writes or reads Parquet
    tables with Polars, runs in a process forked after Polars' threads had started (see the module docstring)."""
    if _running_at_fork:
        raise ConfigError(
            f"{what} cannot run in this process: it was forked (os.fork, multiprocessing's 'fork' start method, a "
            "DataLoader's workers) from one whose Polars threads were running, and Polars, which writes and reads "
            "the Parquet tables, would wait forever for them; start the process with the 'spawn' or "
            "'forkserver' method (multiprocessing.get_context('spawn'), DataLoader(multiprocessing_context="
            "'spawn')), or use mmusv.run_many. Capturing frames (Simulation.capture) works in forked processes"
        )
