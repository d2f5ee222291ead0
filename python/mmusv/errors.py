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
    "MmusvError",
    "InputError",
    "GeometryError",
    "ConfigError",
    "NotFoundError",
    "IoError",
    "InternalError",
]
