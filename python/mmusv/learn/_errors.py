"""The error raised for bad input by the training core: mmusv's ``InputError`` where mmusv's native extension
is installed, ``ValueError`` on a machine that trains from a tensor cache without it (``scripts/learn_train.py``,
where the exception tree, defined in the compiled core, does not exist)."""

from __future__ import annotations

__all__ = ["input_error"]


def input_error(message: str) -> Exception:
    """An exception carrying ``message``: :class:`mmusv.errors.InputError` when importable, else ``ValueError``."""
    try:
        from mmusv.errors import InputError
    except ImportError:
        return ValueError(message)
    err: Exception = InputError(message)
    return err
