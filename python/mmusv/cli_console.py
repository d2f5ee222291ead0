"""The console and the machine the ``mmusv`` command runs on: standard streams that never fail on a character their
encoding lacks (ASCII consoles, Latin-1 locales), a stdout whose reader went away (``| head``), a full or closed
stream, a deleted current folder, out-of-memory and open-file limits, and the thread counts the environment asks for
(``RAYON_NUM_THREADS``, ``POLARS_MAX_THREADS``) checked before any thread pool exists. :func:`mmusv.cli.main` wraps
every command in these; each turns what was a traceback or a hang into one line (``tests/test_environment_round.py``).
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rich.console import Console

from mmusv.thread_env import check_thread_environment

__all__ = [
    "check_thread_environment",
    "cwd_hint",
    "drop",
    "flush_stdout",
    "lenient_output",
    "memory_hint",
    "open_missing_streams",
    "os_hint",
    "rich_console",
    "say",
    "stdout_broken",
    "stdout_fails",
]

_ASCII_FORMS = {
    "\u00d7": "x",  # ×
    "\u00b0": "deg",  # °
    "\u00b2": "^2",
    "\u00b3": "^3",
    "\u00b1": "+/-",
    "\u00b5": "u",
    "\u00b7": ".",
    "\u2013": "-",  # –
    "\u2014": "-",  # —
    "\u2212": "-",  # −
    "\u2026": "...",  # …
    "\u2192": "->",  # →
    "\u2190": "<-",
    "\u2264": "<=",
    "\u2265": ">=",
    "\u2248": "~",
    "\u2018": "'",
    "\u2019": "'",
    "\u201c": '"',
    "\u201d": '"',
}
_OUTPUT_ERRORS = "mmusv.output"
"""The error handler of stdout and stderr while ``mmusv`` runs (:func:`lenient_output`)."""


def _output_replacement(err: UnicodeError) -> tuple[str | bytes, int]:
    """Encoding error handler of the console streams: a character the stream's encoding (ASCII under ``LANG=C``
    without UTF-8 mode, ``PYTHONIOENCODING=ascii``, Latin-1) cannot write becomes its ASCII form (``×`` -> ``x``,
    ``°`` -> ``deg``, ``–`` -> ``-``) or ``?``; a byte of a file name that is not UTF-8 (a surrogate escape)
    is written as the byte it was, as ``surrogateescape`` does."""
    if not isinstance(err, UnicodeEncodeError):
        raise err
    text = err.object[err.start : err.end]
    escaped = [0xDC80 <= ord(c) <= 0xDCFF for c in text]
    run = next((i for i, e in enumerate(escaped) if e != escaped[0]), len(text))  # the leading run of one kind
    if escaped[0]:
        return bytes(ord(c) - 0xDC00 for c in text[:run]), err.start + run
    out = []
    for c in text[:run]:
        form = _ASCII_FORMS.get(c, "?")
        try:
            form.encode(err.encoding)
        except (UnicodeError, LookupError):
            form = "?"
        out.append(form)
    return "".join(out), err.start + run


@contextlib.contextmanager
def lenient_output() -> Iterator[None]:
    """While ``mmusv`` runs, stdout and stderr never fail on a character their encoding lacks: ``mmusv study
    waves`` under ``PYTHONIOENCODING=ascii`` (or ``LANG=C`` without UTF-8 mode) ended in a UnicodeEncodeError
    traceback at the table's ``×``. The streams' own error handlers come back afterwards (``main`` may be called
    in-process)."""
    import codecs

    try:
        codecs.lookup_error(_OUTPUT_ERRORS)
    except LookupError:
        codecs.register_error(_OUTPUT_ERRORS, _output_replacement)
    old: list[tuple[Any, str]] = []
    for stream in (sys.stdout, sys.stderr):
        errors = getattr(stream, "errors", None)
        if errors is None or not hasattr(stream, "reconfigure") or errors == _OUTPUT_ERRORS:
            continue
        try:
            stream.reconfigure(errors=_OUTPUT_ERRORS)
        except (OSError, ValueError):  # a stream already failing: left as it is
            continue
        old.append((stream, errors))
    try:
        yield
    finally:
        for stream, errors in old:
            with contextlib.suppress(OSError, ValueError):
                stream.reconfigure(errors=errors)


def open_missing_streams() -> None:
    """A closed stdout or stderr (``mmusv run X >&-``, a daemon without one) is ``None`` in Python: both are
    made to write nowhere, so the command runs and says what it can."""
    import os

    for name in ("stdout", "stderr"):
        if getattr(sys, name) is None:
            setattr(sys, name, open(os.devnull, "w", encoding="utf-8"))  # noqa: SIM115 - for the process's life


def say(line: str) -> None:
    """``line`` on stderr; nothing when stderr itself cannot be written (a closed pipe, a full disk)."""
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):
        drop(sys.stderr)  # else Python's flush at exit fails again: status 120


def stdout_broken() -> bool:
    """Whether stdout is a pipe whose reader has gone (``| head -1``): the pipe reports an error on poll."""
    import select

    try:
        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
        return any(ev & select.POLLERR for _fd, ev in poller.poll(0))
    except (OSError, ValueError, AttributeError):
        return False


def drop(stream: Any) -> None:
    """Points ``stream``'s file descriptor at ``/dev/null``, so that what Python still holds for it is written
    nowhere at exit instead of ending in ``Exception ignored ... BrokenPipeError`` and exit status 120."""
    import os

    try:
        fd = stream.fileno()
        null = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(null, fd)
        finally:
            os.close(null)
    except (OSError, ValueError, AttributeError):
        pass


def stdout_fails() -> bool:
    """Whether stdout cannot take what it holds (a full device, an I/O error): the cause of an ``OSError``
    without a file name, which then names the standard output."""
    try:
        sys.stdout.flush()
    except (OSError, ValueError):
        return True
    except AttributeError:
        return False
    return False


def flush_stdout(code: int) -> int:
    """Flushes stdout before the exit status is final: a stdout that is a closed pipe ends the command quietly
    (status 1, as rich does), one that cannot be written (``> /dev/full``) is named on stderr (status 2); both
    used to end in ``Exception ignored in: <_io.TextIOWrapper name='<stdout>'>`` and status 120."""
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        drop(sys.stdout)
        return code or 1
    except OSError as exc:
        if code == 0:  # else the command's own error was said already
            say(f"mmusv: error: cannot write to the standard output: {exc.strerror or exc}")
        drop(sys.stdout)
        return code or 2
    except (ValueError, AttributeError):  # closed or replaced by the caller
        pass
    return code


def cwd_hint() -> str:
    """A note for an error message when the current folder has been deleted under the process (``cd X; rmdir
    X``): relative paths and worker processes (which start in it) cannot work there; empty otherwise."""
    import os

    try:
        os.getcwd()
    except OSError:
        return (
            " (the current folder no longer exists: relative paths and --jobs workers need one; cd to an "
            "existing folder or give absolute paths)"
        )
    return ""


def os_hint(exc: OSError) -> str:
    """What a system limit behind ``exc`` is, for its message: the open-files limit for EMFILE/ENFILE."""
    import errno

    if exc.errno in (errno.EMFILE, errno.ENFILE):
        try:
            import resource

            soft = resource.getrlimit(resource.RLIMIT_NOFILE)[0]
        except (ImportError, OSError, ValueError):
            return " (the limit on open files; raise it with ulimit -n)"
        return f" (the limit on open files is {soft}; raise it with ulimit -n)"
    return ""


def memory_hint() -> str:
    """The address-space limit (``ulimit -v``) for an out-of-memory message, when one is set."""
    try:
        import resource

        soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    except (ImportError, OSError, ValueError):
        return ""
    if soft == resource.RLIM_INFINITY:
        return " (use fewer frames, sensors or --jobs, or a machine with more memory)"
    return f" (the address-space limit, ulimit -v, is {soft // 1024} kB: raise it, or use fewer frames or --jobs)"


def rich_console() -> Console:
    """A rich console for a command's tables; wide when not writing to a terminal, so piped tables are not
    wrapped. What it prints is taken as it is, not as rich markup: a path or name holding brackets was read as
    markup, so ``-o "out [old]"`` was said as ``out /...`` and ``-o "[/x]"`` ended the command with rich's
    MarkupError traceback after its files were written. A styled line passes ``markup=True`` and escapes what it
    embeds (:func:`rich.markup.escape`), or is a :class:`rich.text.Text`."""
    from rich.console import Console

    return Console(width=None if sys.stdout.isatty() else 160, markup=False)
