"""Reading the files ``mmusv train`` writes (``model.pt``, ``last.pt``, ``scorer.pt``) safely: one loader for all
of them, with PyTorch's ``weights_only`` unpickler, which rebuilds tensors, containers and plain values only and
never runs code a file carries (a model passed around between machines is input like any other). A file that is
not such a checkpoint (empty, cut short, another program's pickle, one carrying code) is an ``InputError`` naming
it and saying what it is not, never a traceback. What the files hold (dicts of tensors, strings, numbers, lists)
is all the safe unpickler needs."""

from __future__ import annotations

import pickle
import zipfile
from pathlib import Path
from typing import Any

import torch

from mmusv.learn._errors import input_error

__all__ = ["load_checkpoint"]


def load_checkpoint(path: str | Path, *, what: str, device: torch.device | str = "cpu") -> dict[str, Any]:
    """The dict saved at ``path``, its tensors on ``device``; ``what`` names the file for the error
    (``"--model runs/model.pt: not an mmusv.learn model.pt"``)."""
    p = Path(path)
    try:
        ck = torch.load(p, map_location=device, weights_only=True)
    except (OSError, EOFError, pickle.UnpicklingError, RuntimeError, ValueError, zipfile.BadZipFile) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        if "weights_only" in str(exc) or "Unsupported global" in str(exc):
            first = "it holds objects other than tensors and plain values, which are not loaded"
        raise input_error(f"{what} ({type(exc).__name__}: {first[:200]})") from None
    if not isinstance(ck, dict):
        raise input_error(f"{what} (it holds a {type(ck).__name__}, not a dict)")
    return ck
