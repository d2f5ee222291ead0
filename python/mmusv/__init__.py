"""mmusv: a headless, deterministic maritime multi-USV simulator and dataset generator.

The main job is ``mmusv.run(cfg, out_dir=...)`` (a scenario YAML path, dict or :class:`mmusv.config.Scenario`)
into an MCAP recording plus Parquet tables; ``mmusv.run_many(folder, out_dir=..., jobs=N | ray=...)`` runs a
folder of them on a local pool or Ray, restartable (:mod:`mmusv.batch`); :class:`mmusv.Simulation` captures
single frames as numpy arrays; :mod:`mmusv.scene` casts rays on your own meshes; :mod:`mmusv.world` has maps,
vessels and environments.

Only the native core and the exception tree load with ``import mmusv``; the names above, and every submodule
as an attribute (``mmusv.config``), load on first use (PEP 562). Importing all of it took about a second, during
which a Ctrl-C of the ``mmusv`` command was a traceback of the import (:mod:`mmusv._launch`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mmusv import errors
from mmusv._lazy import attributes
from mmusv._native import core as _core_module
from mmusv.errors import *  # noqa: F403 (the exception tree, as listed once in mmusv.errors.__all__)

if TYPE_CHECKING:
    from mmusv import config
    from mmusv.acquire import RunResult, run
    from mmusv.batch import BatchReport, run_many
    from mmusv.scene import RayHits, Scene
    from mmusv.simulation import Simulation

__version__: str = _core_module.__version__

_LAZY = {
    "BatchReport": "mmusv.batch",
    "RayHits": "mmusv.scene",
    "RunResult": "mmusv.acquire",
    "Scene": "mmusv.scene",
    "Simulation": "mmusv.simulation",
    "run": "mmusv.acquire",
    "run_many": "mmusv.batch",
}
"""The top-level names loaded on first use, and the module each comes from."""

__all__ = [
    "BatchReport",
    "RayHits",
    "RunResult",
    "Scene",
    "Simulation",
    "__version__",
    "config",
    "run",
    "run_many",
]
__all__ += errors.__all__


__getattr__ = attributes(__name__, _LAZY, submodules=True)
"""``mmusv.run`` and the other names of :data:`__all__` from their modules, and ``mmusv.<submodule>``, imported on
first use and kept."""


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
