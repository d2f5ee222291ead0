"""Holding SIGINT and SIGTERM back while steps run that a stop must not split (:class:`HeldSignals`): a
recording opened and its metadata written (:mod:`mmusv.recording.guard`), the ``mmusv`` command's modules loaded
(:mod:`mmusv._launch`), the editor's run process's (:mod:`mmusv.editor.job`). And the stop the ``mmusv`` command's
handler (:class:`StopSignals`, also the editor's run process's; or its batch's pool worker's) noted
(:func:`note_stop`), for the work to end as a stop where a library met its ``KeyboardInterrupt``: raised again
where the library swallowed it (:func:`raise_noted_stop`), and where the library made an error of its own of it,
that error taken for the stop (:func:`is_stop`, :func:`stops_unwrapped`). A module of its own, light to import:
the command holds the signals before it loads the rest of mmusv.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from types import TracebackType
from typing import Any

__all__ = [
    "HeldSignals",
    "StopSignals",
    "forget_handled_interrupt",
    "is_stop",
    "note_stop",
    "raise_noted_stop",
    "stops_unwrapped",
]

_stop: list[int] = []
"""The stop the ``mmusv`` command's handler noted (at most one signal number; :func:`note_stop`)."""


class HeldSignals:
    """SIGINT and SIGTERM held back while steps run that a stop must not split (see the module docstring).

    :meth:`hold` (or entering ``with``) replaces the handlers of both signals with one that only notes the first
    signal; :meth:`release` (or leaving ``with``) puts the handlers back, then hands a noted signal to the handler
    that was in place: Python's default SIGINT handler and the command line's (``mmusv.cli``) raise
    ``KeyboardInterrupt`` there, a pool worker's finishes its task as interrupted, ``SIG_DFL`` gets the signal's
    default action, ``SIG_IGN`` nothing. A stop is never lost, only moved to the end of the steps. Holds nest (an
    inner release hands the signal to the outer hold). Python runs signal handlers in the main thread only: in
    another thread this holds nothing."""

    SIGNALS = ("SIGINT", "SIGTERM")

    def __init__(self) -> None:
        self._old: dict[int, Any] = {}
        self._noted: int | None = None

    def hold(self) -> HeldSignals:
        """Starts holding the signals back; returns ``self``."""
        import signal
        import threading

        if threading.current_thread() is not threading.main_thread():
            return self
        for name in self.SIGNALS:
            num = getattr(signal, name, None)
            if num is None or num in self._old:
                continue
            old = signal.getsignal(num)
            if old is None:  # a handler installed outside Python: it could not be put back, so it is left alone
                continue
            signal.signal(num, self._note)
            self._old[num] = old
        return self

    def _note(self, signum: int, frame: object) -> None:
        if self._noted is None:
            self._noted = signum

    @property
    def noted(self) -> int | None:
        """The signal that came while held (not yet handed on), else None."""
        return self._noted

    def release(self, *, hand_on: bool = True) -> int | None:
        """Puts the handlers back, then hands a signal that came meanwhile to its handler (which may raise
        ``KeyboardInterrupt``); returns that signal, else None. ``hand_on=False``: the caller ends the work itself
        (the ``mmusv`` command's start, :mod:`mmusv._launch`), and the signal is only returned. Releasing again does
        nothing."""
        import signal

        old, self._old = self._old, {}
        for num, handler in old.items():
            signal.signal(num, handler)
        noted, self._noted = self._noted, None
        if noted is None or not hand_on:
            return noted
        handler = old.get(noted)
        if callable(handler):
            handler(noted, None)
        elif handler == signal.SIG_DFL:
            signal.raise_signal(noted)
        return noted

    def __enter__(self) -> HeldSignals:
        return self.hold()

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.release()


def forget_handled_interrupt() -> None:
    """Tells CPython that the ``KeyboardInterrupt`` a command caught was handled, so that its exit status stands.

    CPython marks a ``KeyboardInterrupt`` that leaves code run from a string (``exec(str)``, ``eval(str)``: every
    dataclass method is made that way while a module loads) as unhandled, even when a caller catches it later;
    under ``python -m`` the interpreter then ends the process by SIGINT at exit instead of with the status the
    command returned (``mmusv: interrupted``, then status -2 for ``subprocess``, not 130: 4 of 38 Ctrl-Cs in the
    first second of ``python -m mmusv run``). Each string evaluation clears the mark when it starts, so an empty
    one does (CPython's ``run_eval_code_obj``); where there is no mark it does nothing."""
    exec("pass", {})


def note_stop(signum: int | None) -> None:
    """Notes (or, with ``None``, forgets) the stop the ``mmusv`` command's signal handler received, before it
    raises ``KeyboardInterrupt``: :func:`raise_noted_stop` raises it again where a library swallowed it, and
    :func:`stops_unwrapped` where a library wrapped it in an error of its own. Only the command notes stops (its
    handler, :class:`StopSignals`, which the editor's run process uses too, and that of its batch's pool workers,
    ``mmusv.batch.executors``): called from Python, mmusv's functions see no noted stop and are unchanged."""
    _stop[:] = [] if signum is None else [signum]


def raise_noted_stop() -> None:
    """Raises ``KeyboardInterrupt`` if a stop was noted (:func:`note_stop`) and the work is still going: the one
    the handler raised was swallowed where it landed. A Ctrl-C that came while a frame's lazy import ran raised
    inside importlib's module-lock callback, which Python reports as "Exception ignored" and goes on: the run went
    on to its last frame (1 of 200 starts of ``mmusv run`` under load). Every long loop calls this once a step: the
    recording's and the converter's frames, the generator's attempts, the batch's finished scenarios, the wave
    studies' settings, the agreement study's frames, the detection study's frames (and its jobs' results), the
    training cache's sequences, the training's steps (and its jobs' models). A stop swallowed in a loop's last
    step, after its last call, is said by the command once it returns (``mmusv: interrupted``, status 128 + the
    signal: ``mmusv.cli``); the work itself was done whole."""
    if _stop:
        raise KeyboardInterrupt


def is_stop(exc: BaseException) -> bool:
    """Whether ``exc`` ends the work as a stop: a ``KeyboardInterrupt``, or an error raised after a stop was noted
    (:func:`note_stop`), which a library made of the stop's ``KeyboardInterrupt`` (:func:`stops_unwrapped`)."""
    return isinstance(exc, KeyboardInterrupt) or (bool(_stop) and isinstance(exc, Exception))


class _StopsUnwrapped:
    """The context manager of :func:`stops_unwrapped`."""

    def __enter__(self) -> None:
        return None

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        if exc is not None and not isinstance(exc, KeyboardInterrupt) and is_stop(exc):
            raise KeyboardInterrupt from exc


def stops_unwrapped() -> _StopsUnwrapped:
    """A ``with`` block in which an error raised after a stop was noted (:func:`note_stop`) leaves as that stop, a
    ``KeyboardInterrupt`` raised from the error (:func:`is_stop`); without a noted stop errors leave unchanged, and
    nothing is raised where the block raised nothing (:func:`raise_noted_stop` does that, once a step). A library
    that meets the stop's ``KeyboardInterrupt`` may wrap it in an error of its own (Python 3.11's ``RuntimeError``
    from ``__set_name__`` while a lazy import defines a dataclass, pydantic-core's ``SchemaError``), which was
    recorded as ``failed`` with that error under a command that said ``mmusv: interrupted``. The recording's frames
    (``mmusv.acquire``), a conversion (``mmusv.export.conversion``; its writer stops as for a Ctrl-C: ``is_stop``)
    and a batch's task (``mmusv.batch.task``, in the command's process or a pool worker) run in one: the error is
    recorded as the stop it is (``status: interrupted``, as for a plain Ctrl-C). The command itself ends any error
    after a stop as the stop (``mmusv.cli``)."""
    return _StopsUnwrapped()


class StopSignals:
    """While a command runs (``mmusv``, :mod:`mmusv.cli`; a run the editor started, :mod:`mmusv.editor.job`): SIGTERM
    (a ``kill``, a service manager) and SIGINT (Ctrl-C, the editor's Stop) both end it the way Ctrl-C always did —
    raised as ``KeyboardInterrupt`` in the main thread, so the current frame is finished or abandoned, files are
    closed and background jobs are stopped — and the stop is noted (:func:`note_stop`) for the work to end as a stop
    also where a library swallowed the ``KeyboardInterrupt`` or made an error of its own of it. ``received`` is the
    first signal; the caller ends with one word of the stop (``said``) and the exit status 128 + the signal's number
    (:meth:`status`). The previous handlers come back afterwards (the caller may run in a process that goes on)."""

    SIGNALS = ("SIGINT", "SIGTERM")

    def __init__(self) -> None:
        self.received: int | None = None
        self.said = False  # the caller said the stop (the command's ``mmusv: interrupted``)
        self._old: dict[int, object] = {}
        self._hook: Callable[[Any], object] = sys.unraisablehook

    def _handle(self, signum: int, frame: object) -> None:
        if self.received is None:
            self.received = signum
        note_stop(signum)  # raised again by long loops where a library swallows this KeyboardInterrupt
        raise KeyboardInterrupt

    def _unraisable(self, unraisable: Any) -> None:
        # The KeyboardInterrupt this handler raised where Python cannot propagate it (importlib's module-lock
        # callback, a finalizer) was reported as "Exception ignored in ..." with a traceback; the stop is noted and
        # raised again by the long loops (held_signals.raise_noted_stop), so it is not reported.
        if self.received is not None and isinstance(unraisable.exc_value, KeyboardInterrupt):
            return
        self._hook(unraisable)

    def __enter__(self) -> StopSignals:
        import signal
        import threading

        if threading.current_thread() is threading.main_thread():
            for name in self.SIGNALS:
                num = getattr(signal, name, None)
                if num is not None:
                    self._old[num] = signal.signal(num, self._handle)
            self._hook, sys.unraisablehook = sys.unraisablehook, self._unraisable
        return self

    def __exit__(self, *exc: object) -> None:
        import signal

        for num, old in self._old.items():
            signal.signal(num, old)  # type: ignore[arg-type]
        if self._old:
            sys.unraisablehook = self._hook
        note_stop(None)

    def status(self, default: int) -> int:
        """128 + the signal received, else ``default``."""
        return default if self.received is None else 128 + self.received
