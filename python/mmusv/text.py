"""Words of the messages the commands print, with no dependency (the training scripts import it with torch and
numpy alone, :mod:`mmusv.learn.train`).

:func:`given` and :func:`named` say an argument as its user gave it. The Python API's checks name their keyword
arguments (``eval_range_m = 100``, as :mod:`mmusv.arguments` does); a command that calls the API wraps the call in
:func:`command_line` with its flags (``{"eval_range_m": "--range"}``), and the same checks then name the flag as
typed (``--range 100``). A message never names a flag a Python caller did not give, nor a keyword argument the
command line does not have."""

from __future__ import annotations

import contextlib
import os
import reprlib
from collections.abc import Iterator, Mapping
from contextvars import ContextVar
from types import MappingProxyType

__all__ = ["command_line", "counted", "flags", "given", "named"]


def counted(n: int, noun: str, *, plural: str | None = None, fmt: str = "") -> str:
    """``n`` and ``noun``, plural unless ``n`` is 1, for what the commands print: ``counted(1, "epoch")`` is ``1
    epoch``, ``counted(3, "epoch")`` ``3 epochs`` (``plural`` when adding an s is wrong; ``fmt`` formats ``n``, e.g.
    ``","``). The summaries said "1 sequences", "1 epochs". Machine-readable outputs keep their own fields."""
    return f"{n:{fmt}} {noun if n == 1 else plural or noun + 's'}"


_FLAGS: ContextVar[Mapping[str, str]] = ContextVar("mmusv_text_flags", default=MappingProxyType({}))
_REPR = reprlib.Repr()
_REPR.maxstring, _REPR.maxother = 60, 60


@contextlib.contextmanager
def command_line(flags: Mapping[str, str]) -> Iterator[None]:
    """Within it, :func:`given` and :func:`named` say the keyword arguments ``flags`` maps (``{"eval_range_m":
    "--range"}``) as those flags: a command wraps its calls of the Python API in it, so that the API's messages
    name what its user typed. Nested blocks add to the outer one's flags."""
    token = _FLAGS.set(MappingProxyType({**_FLAGS.get(), **flags}))
    try:
        yield
    finally:
        _FLAGS.reset(token)


def flags() -> dict[str, str]:
    """The flags of the :func:`command_line` block around the caller (``{}`` outside one): for a worker process
    to say its messages as the command that started it does."""
    return dict(_FLAGS.get())


def named(name: str) -> str:
    """The keyword argument ``name`` as its user gave it: its flag within :func:`command_line` (``--range``), else
    ``name`` itself."""
    return _FLAGS.get().get(name, name)


def given(name: str, value: object) -> str:
    """The keyword argument ``name`` and its ``value`` as its user gave them: ``eval_range_m = 100`` or ``cache =
    'run/c.npz'`` (Python: the value's repr, shortened unless a string; a path as its string; a float as ``%g``),
    or, within :func:`command_line`, the flag as typed: ``--range 100``, ``--cache run/c.npz``, a list
    comma-separated (its floats as ``%g``: ``--split-ratios 0,0,1``, not ``0.0,0.0,1.0``), an empty string as
    ``''``, and a switch given alone (``--include-usvs`` for ``True``)."""
    flag = _FLAGS.get().get(name)
    if isinstance(value, os.PathLike):
        value = os.fspath(value)
    if flag is None:
        if isinstance(value, float):
            return f"{name} = {value:g}"
        return f"{name} = {value!r}" if isinstance(value, str) else f"{name} = {_REPR.repr(value)}"
    if value is True:
        return flag
    if value == "":  # --modes "" as the shell took it
        return f"{flag} ''"
    if isinstance(value, float):
        return f"{flag} {value:g}"
    if isinstance(value, (list, tuple, set, frozenset)):
        return f"{flag} {','.join(f'{v:g}' if isinstance(v, float) else str(v) for v in value)}"
    return f"{flag} {value}"
