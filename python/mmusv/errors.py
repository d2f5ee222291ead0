"""mmusv's exception tree (defined in the compiled core, re-exported here).

``MmusvError`` is the base of every error mmusv raises on purpose; the subclasses say what kind of input was
wrong. Messages name the field or argument at fault and what is allowed.
"""

from __future__ import annotations

from mmusv._native import core

MmusvError = core.MmusvError
InputError = core.InputError
GeometryError = core.GeometryError
ConfigError = core.ConfigError
NotFoundError = core.NotFoundError
IoError = core.IoError
InternalError = core.InternalError

__all__ = [
    "ConfigError",
    "GeometryError",
    "InputError",
    "InternalError",
    "IoError",
    "MmusvError",
    "NotFoundError",
]


def located(exc: MmusvError, source: str) -> MmusvError:
    """``exc`` with ``source`` (a file name) in front of its message, as the nearest class of the core tree
    (``ConfigError``, ``InputError``, ...), so subclasses whose constructors take other arguments work too.
    Returned unchanged when the message already names ``source``."""
    msg = str(exc)
    if source in msg:
        return exc
    base = next(c for c in type(exc).__mro__ if c.__module__ == core.__name__)
    return base(f"{source}: {msg}")  # type: ignore[no-any-return]
