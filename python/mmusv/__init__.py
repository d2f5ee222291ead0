"""mmusv: a headless, deterministic maritime multi-USV simulator and dataset generator.

The main job is ``mmusv.run(cfg, out_dir=...)`` (a scenario YAML path, dict or :class:`mmusv.config.Scenario`)
into an MCAP recording plus Parquet tables; ``mmusv.run_many(folder, out_dir=..., jobs=N | ray=...)`` runs a
folder of them on a local pool or Ray, restartable (:mod:`mmusv.batch`); :class:`mmusv.Simulation` captures
single frames as numpy arrays; :mod:`mmusv.scene` casts rays on your own meshes; :mod:`mmusv.world` has maps,
vessels and environments.
"""

from __future__ import annotations

from mmusv import config, errors
from mmusv._native import core as _core_module
from mmusv.acquire import RunResult, run
from mmusv.batch import BatchReport, run_many
from mmusv.errors import *  # noqa: F403 (the exception tree, as listed once in mmusv.errors.__all__)
from mmusv.scene import RayHits, Scene
from mmusv.simulation import Simulation

__version__: str = _core_module.__version__

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
