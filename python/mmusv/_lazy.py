"""Names of a package loaded on first use (PEP 562): the ``__getattr__`` of :mod:`mmusv` and :mod:`mmusv.generate`.
Every ``mmusv`` command builds the whole argument parser, whose sub-commands import these packages; loading what
each package's names need only when a name is used keeps a command's start (and ``import mmusv``) short. A lazy
name must not also be a submodule's name: importing the submodule would bind the name to the module (hence
:mod:`mmusv.export.conversion`, whose function is ``mmusv.export.convert``)."""

from __future__ import annotations

import importlib
import importlib.util
import sys
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["attributes"]


def attributes(package: str, names: Mapping[str, str], *, submodules: bool = False) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``package``: each name of ``names`` is imported from the module it maps to,
    and with ``submodules`` any other name that is a submodule of ``package`` is that submodule; the value is kept
    on the package, so it is looked up once. Else ``AttributeError``, as for any missing attribute."""

    def __getattr__(name: str) -> Any:
        if name in names:
            value = getattr(importlib.import_module(names[name]), name)
        elif submodules and not name.startswith("__") and importlib.util.find_spec(f"{package}.{name}") is not None:
            value = importlib.import_module(f"{package}.{name}")
        else:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        setattr(sys.modules[package], name, value)
        return value

    return __getattr__
