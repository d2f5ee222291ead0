"""The one module that imports the compiled extension ``mmusv._core``.

Every other module takes native types from here, so a missing or stale build fails in one place with one
clear message.
"""

from __future__ import annotations

try:
    from mmusv import _core
except ImportError as exc:  # pragma: no cover - only on a broken install
    raise ImportError(
        "mmusv's compiled extension mmusv._core is missing or does not load; "
        "reinstall with `pip install .` (or `maturin develop --release`) from the repository root"
    ) from exc

core = _core

__all__ = ["core"]
