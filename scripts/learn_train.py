"""Train mmusv.learn models from a tensor cache on a machine with torch and numpy but without mmusv installed
(no native extension, no polars): ``PYTHONPATH=python python3 scripts/learn_train.py --cache C.npz --preset
paper -o OUT``. Arguments: those of :func:`mmusv.learn.train.main`; with ``infer`` first, those of
:func:`mmusv.learn.infer.main` (heatmap peaks of trained models on a cache); with ``merge`` first, those of
:func:`mmusv.learn.infer.merge_main` (join per-mode peak files).

``import mmusv.learn`` would run ``mmusv/__init__.py``, which loads the native extension; this entry registers
``mmusv`` as a bare package over its source folder first, so only the training core (torch + numpy) loads.
"""

from __future__ import annotations

import sys
import types
from pathlib import Path

if __name__ == "__main__":
    pkg = Path(__file__).resolve().parents[1] / "python" / "mmusv"
    if "mmusv" not in sys.modules:
        bare = types.ModuleType("mmusv")
        bare.__path__ = [str(pkg)]
        sys.modules["mmusv"] = bare
    from mmusv.learn._errors import command  # a bad input is one line and exit status 2, not a traceback

    if sys.argv[1:2] == ["infer"]:
        from mmusv.learn.infer import main

        raise SystemExit(command(main, sys.argv[2:]))
    if sys.argv[1:2] == ["merge"]:
        from mmusv.learn.infer import merge_main

        raise SystemExit(command(merge_main, sys.argv[2:]))
    from mmusv.learn.train import main

    raise SystemExit(command(main, sys.argv[1:]))
