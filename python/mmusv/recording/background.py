"""Recording in the background: frame k is written on a writer thread while the main thread captures frame k+1.

:class:`BackgroundWriter` runs ``write(item)`` for every submitted item, in submission order, on one thread of
its own. At most ``depth`` items wait between the two threads, so memory stays flat however long the run: a
:meth:`~BackgroundWriter.submit` blocks while the writer is behind. The writer's native calls (image encoding,
MCAP writing) release the GIL, so they run on the cores the capture leaves free.

Order and bytes: one thread writes every item in order, so the file is the one writing them in a loop gives.

Failures: the first exception of ``write`` stops the writing (later items are dropped, never written out of
order); :meth:`~BackgroundWriter.submit` and :meth:`~BackgroundWriter.raise_pending` raise it in the caller's
thread. :meth:`~BackgroundWriter.close` always waits until every submitted item is written: a Ctrl-C while it
waits is remembered (:attr:`~BackgroundWriter.interrupted`), not raised, so the caller can still finish its
files before re-raising it. Waits poll every 0.1 s, so a Ctrl-C is seen promptly.
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable
from typing import Generic, TypeVar

__all__ = ["BackgroundWriter"]

T = TypeVar("T")

_POLL_S = 0.1


class _Stop:
    """The end-of-work marker."""


class BackgroundWriter(Generic[T]):
    """Runs ``write(item)`` for each submitted item on one background thread, in order (see the module docstring).

    Args:
        write: called once per item on the writer thread.
        depth: items that may wait while one is being written (>= 1).
        name: the thread's name.
    """

    def __init__(self, write: Callable[[T], None], *, depth: int = 1, name: str = "mmusv-writer") -> None:
        if depth < 1:
            raise ValueError(f"depth must be >= 1, got {depth}")
        self._write = write
        self._queue: queue.Queue[T | _Stop] = queue.Queue(maxsize=depth)
        self._error: BaseException | None = None
        self._closed = False
        self._stop_sent = False
        self.done = 0
        """Items written so far."""
        self.wait_seconds = 0.0
        """Wall seconds :meth:`submit` spent blocked because the writer was behind."""
        self.interrupted = False
        """True if a Ctrl-C came while :meth:`close` waited."""
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    @property
    def error(self) -> BaseException | None:
        """The exception that stopped the writer, if any."""
        return self._error

    def submit(self, item: T) -> None:
        """Hands ``item`` to the writer; blocks while ``depth`` items wait. Raises the writer's error if it failed."""
        if self._closed:
            raise RuntimeError("the background writer is closed")
        self.raise_pending()
        t = time.perf_counter()
        while True:
            try:
                self._queue.put(item, timeout=_POLL_S)
                break
            except queue.Full:
                self.raise_pending()
        self.wait_seconds += time.perf_counter() - t

    def raise_pending(self) -> None:
        """Raises the writer's error, or ``KeyboardInterrupt`` when a Ctrl-C came during :meth:`close`."""
        if self._error is not None:
            raise self._error
        if self.interrupted:
            raise KeyboardInterrupt

    def close(self) -> None:
        """Waits until every submitted item is written (or the writer failed), then ends the thread. Never raises
        (see :meth:`raise_pending`); calling it again does nothing."""
        # `_closed` refuses new items; the end marker is sent until it is in (`_stop_sent`): a stop that came between
        # setting the one and sending the other left a second `close` joining a writer that nothing would end (a
        # SIGTERM'd run hung so once in CI: the writer in `queue.get`, the main thread in `_joined`).
        self._closed = True
        if not self._stop_sent:
            self._wait(self._put_stop)
        self._wait(self._joined)

    def _joined(self) -> bool:
        self._thread.join(timeout=_POLL_S)
        return not self._thread.is_alive()

    def _put_stop(self) -> bool:
        try:
            self._queue.put(_Stop(), timeout=_POLL_S)
        except queue.Full:
            return False
        self._stop_sent = True
        return True

    def _wait(self, step: Callable[[], bool]) -> None:
        """Repeats ``step`` until it returns True; a Ctrl-C in between is remembered, not raised."""
        while True:
            try:
                if step():
                    return
            except KeyboardInterrupt:
                self.interrupted = True

    def _run(self) -> None:
        while True:
            try:
                # A poll, not a wait without end: a stop raised in the main thread inside `Queue.put`, after the
                # item went in but before the waiting writer was woken, left the writer asleep beside a full queue
                # and `close` waiting for it for ever (a SIGTERM'd run hung so once); a poll finds the item.
                item = self._queue.get(timeout=_POLL_S)
            except queue.Empty:
                continue
            if isinstance(item, _Stop):
                return
            if self._error is not None:
                continue  # drain without writing: nothing is written after a failure
            try:
                self._write(item)
                self.done += 1
            except BaseException as exc:  # any failure stops the writing and goes to the caller
                self._error = exc
