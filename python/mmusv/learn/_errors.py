"""The error raised for bad input by the training core: mmusv's ``InputError`` where mmusv's native extension
is installed, :class:`LearnInputError` (a ``ValueError``) on a machine that trains from a tensor cache without it
(``scripts/learn_train.py``, where the exception tree, defined in the compiled core, does not exist).

:func:`command` runs the ``main`` of a module run as a command (``python -m mmusv.learn.replay``,
``scripts/learn_train.py``): such an error is one line on stderr and exit status 2, as ``mmusv`` itself says it
(they were tracebacks)."""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence

__all__ = ["LearnInputError", "command", "input_error", "input_error_types"]


class LearnInputError(ValueError):
    """Bad input to the training core where mmusv's ``InputError`` cannot be imported."""


def input_error(message: str) -> Exception:
    """An exception carrying ``message``: :class:`mmusv.errors.InputError` when importable, else
    :class:`LearnInputError`."""
    try:
        from mmusv.errors import InputError
    except ImportError:
        return LearnInputError(message)
    err: Exception = InputError(message)
    return err


def input_error_types() -> tuple[type[Exception], ...]:
    """The classes :func:`input_error` (and mmusv's own checks) raise here: to catch them and say them."""
    try:
        from mmusv.errors import MmusvError
    except ImportError:
        return (LearnInputError,)
    return (LearnInputError, MmusvError)


def command(main: Callable[[Sequence[str] | None], int], argv: Sequence[str] | None = None) -> int:
    """``main(argv)``, with an input error said as ``mmusv: error: MESSAGE`` on stderr and exit status 2."""
    try:
        return main(argv)
    except input_error_types() as exc:
        print(f"mmusv: error: {exc}", file=sys.stderr, flush=True)
        return 2
    except OSError as exc:  # a file named that is not there, a folder that cannot be written
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"mmusv: error: {where}{exc.strerror or exc}", file=sys.stderr, flush=True)
        return 2
