"""Calls that move one simulation's scene take turns, also across ``os.fork()``.

A :class:`~mmusv.simulation.Simulation` moves one native scene: ``capture``, ``set_frame``, ``prefetch_frame`` and
``set_sea_surface`` each set it to a frame or a sea. Two threads capturing frames 1 and 2 at once got each other's
state, so these methods hold the simulation's lock (:func:`one_at_a_time`; the core already runs each capture on
every CPU). A process forked while another thread held that lock (a DataLoader's workers started while a thread
captures) would wait forever for a thread that is not there: in a forked child every object registered with
:func:`take_turns` gets a fresh lock, and its ``_after_fork_in_child()`` forgets the frame it was set to (the next
capture sets the whole frame anew).
"""

from __future__ import annotations

import functools
import os
import threading
import weakref
from collections.abc import Callable
from typing import Any, Protocol, TypeVar

__all__ = ["TakesTurns", "one_at_a_time", "take_turns"]


class TakesTurns(Protocol):
    """An object whose scene-moving methods take turns: its lock, and what it forgets in a forked child."""

    _lock: threading.RLock

    def _after_fork_in_child(self) -> None: ...


_F = TypeVar("_F", bound=Callable[..., Any])

_LIVE: weakref.WeakSet[Any] = weakref.WeakSet()
"""Every object of this process registered with :func:`take_turns` (weakly: registering keeps nothing alive)."""


def take_turns(obj: TakesTurns) -> threading.RLock:
    """Registers ``obj`` (for a fresh lock after a fork) and returns the lock to keep as ``obj._lock``."""
    _LIVE.add(obj)
    return threading.RLock()


def one_at_a_time(method: _F) -> _F:
    """``method`` holding its object's ``_lock`` (see the module docstring)."""

    @functools.wraps(method)
    def locked(self: TakesTurns, *args: Any, **kwargs: Any) -> Any:
        with self._lock:
            return method(self, *args, **kwargs)

    return locked  # type: ignore[return-value]


def _free_turns_after_fork() -> None:
    """In a forked child: a fresh lock for every registered object, which then forgets its frame (see the module
    docstring)."""
    for obj in list(_LIVE):
        obj._lock = threading.RLock()
        obj._after_fork_in_child()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_free_turns_after_fork)
