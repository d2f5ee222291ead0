"""Reading the files ``mmusv train`` writes (``model.pt``, ``last.pt``, ``scorer.pt``) safely: one loader for all
of them, with PyTorch's ``weights_only`` unpickler, which rebuilds tensors, containers and plain values only and
never runs code a file carries (a model passed around between machines is input like any other). A file that is
not such a checkpoint (empty, cut short, another program's pickle, one carrying code) is an ``InputError`` naming
it and saying what it is not, never a traceback. What the files hold (dicts of tensors, strings, numbers, lists)
is all the safe unpickler needs.

:func:`weights_digest` names a model's weights (a scorer records the digest of the model it was fitted for, so a
model trained further after its scorer is not rescored by a scorer of other weights)."""

from __future__ import annotations

import hashlib
import pickle
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import torch

from mmusv.learn._errors import input_error

__all__ = ["load_checkpoint", "weights_digest"]


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


def weights_digest(state: Mapping[str, Any]) -> str:
    """A SHA-256 hex digest of a model's ``state_dict`` (names, dtypes, shapes and values, in name order): the same
    weights give the same digest on any machine and in any layout (channels-last tensors are read in logical
    order)."""
    h = hashlib.sha256()
    for name in sorted(state):
        t = state[name]
        if not isinstance(t, torch.Tensor):
            continue
        c = t.detach().cpu().contiguous()
        h.update(f"{name}:{c.dtype}:{tuple(c.shape)};".encode())
        h.update(c.reshape(-1).view(torch.uint8).numpy().tobytes() if c.numel() else b"")
    return h.hexdigest()
