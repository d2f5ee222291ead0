"""mmusv: a headless, deterministic maritime multi-USV simulator and dataset generator.

Start with :mod:`mmusv.scene` for ray casting on your own meshes, :mod:`mmusv.world` for maps, vessels and
environments.
"""

from __future__ import annotations

from mmusv._native import core as _core_module
from mmusv.errors import (
    ConfigError,
    GeometryError,
    InputError,
    InternalError,
    IoError,
    MmusvError,
    NotFoundError,
)
from mmusv.scene import RayHits, Scene

__version__: str = _core_module.__version__

__all__ = [
    "__version__",
    "Scene",
    "RayHits",
    "MmusvError",
    "InputError",
    "GeometryError",
    "ConfigError",
    "NotFoundError",
    "IoError",
    "InternalError",
]
