"""Reading the files ``mmusv train`` writes (``model.pt``, ``last.pt``, ``scorer.pt``) safely: one loader for all
of them, with PyTorch's ``weights_only`` unpickler, which rebuilds tensors, containers and plain values only and
never runs code a file carries (a model passed around between machines is input like any other). A file that is
not such a checkpoint (empty, cut short, another program's pickle, one carrying code) is an ``InputError`` naming
it and saying what it is not, never a traceback. What the files hold (dicts of tensors, strings, numbers, lists)
is all the safe unpickler needs.

:func:`weights_digest` names a model's weights (a scorer records the digest of the model it was fitted for, so a
model trained further after its scorer is not rescored by a scorer of other weights).

:func:`save_checkpoint` writes them: through a temporary ``.<name>.<pid>.tmp`` beside the file, renamed into
place (an interruption leaves the previous file whole) and removed when the save fails; a process killed while
saving cannot remove it, so :func:`remove_stale_temporaries` removes those of processes that are gone, at the start
of a training into the folder (files of that exact pattern only, never one the user put there)."""

from __future__ import annotations

import hashlib
import os
import re
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import torch

from mmusv.learn._errors import input_error

__all__ = ["load_checkpoint", "remove_stale_temporaries", "save_checkpoint", "weights_digest"]

SAVED = ("model.pt", "last.pt", "scorer.pt")
"""The files :func:`save_checkpoint` writes."""
_TEMPORARY = re.compile(r"\.(" + "|".join(re.escape(n) for n in (*SAVED, "log.jsonl")) + r")\.([0-9]+)\.tmp")
"""The temporaries of :func:`save_checkpoint` and of the training's ``log.jsonl`` (written the same way)."""


def load_checkpoint(path: str | Path, *, what: str, device: torch.device | str = "cpu") -> dict[str, Any]:
    """The dict saved at ``path``, its tensors on ``device``; ``what`` names the file for the error
    (``"--model runs/model.pt: not an mmusv.learn model.pt"``)."""
    p = Path(path)
    try:
        ck = torch.load(p, map_location=device, weights_only=True)
    except MemoryError:
        raise
    except Exception as exc:  # any bytes: the weights-only unpickler raises whatever its stack machine meets
        # Bytes that are no pickle (a YAML or JSON file, a point cloud) made it fail with an IndexError or KeyError,
        # a traceback, or were said to hold "objects other than tensors".
        text = str(exc).strip()
        no_pickle = "Unsupported operand" in text  # the unpickler's word for a byte that is no pickle opcode
        if ("weights_only" in text or "Unsupported global" in text) and not no_pickle:
            why = f"{type(exc).__name__}: it holds objects other than tensors and plain values, which are not loaded"
        elif no_pickle or not isinstance(exc, (OSError, RuntimeError, zipfile.BadZipFile)):
            why = "empty" if p.is_file() and p.stat().st_size == 0 else "not a PyTorch checkpoint"
        else:  # an unreadable file, a cut-short archive: the first sentence of what was met
            why = f"{type(exc).__name__}: {text.splitlines()[0].split('. ')[0][:200] if text else ''}"
        raise input_error(f"{what} ({why})") from None
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


def save_checkpoint(obj: Mapping[str, Any], path: str | Path) -> Path:
    """``obj`` saved to ``path`` through the temporary ``.<name>.<pid>.tmp`` (module docstring), removed if the
    save fails. Saved through an open file, so the archive inside is named ``archive`` whatever the file is called:
    saved by its path, it was named after the temporary file, whose name holds the process id, and two runs of the
    same seed wrote ``model.pt`` files of different bytes."""
    p = Path(path)
    tmp = p.with_name(f".{p.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "wb") as fh:
            torch.save(obj, fh)
        tmp.replace(p)
    except BaseException:  # a full disk, a Ctrl-C: no temporary file is left behind
        tmp.unlink(missing_ok=True)
        raise
    return p


def _alive(pid: int) -> bool:
    """Whether process ``pid`` runs on this machine (where that cannot be told, it is taken to)."""
    if pid == os.getpid():
        return False  # this process saves nothing into the folder before the removal
    if os.name != "posix":
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process, or no way to tell
        return True
    return True


def remove_stale_temporaries(folder: str | Path) -> list[Path]:
    """Removes from ``folder`` the temporaries of :func:`save_checkpoint` (``.model.pt.<pid>.tmp``,
    ``.last.pt.<pid>.tmp``, ``.scorer.pt.<pid>.tmp``) and of the training's log (``.log.jsonl.<pid>.tmp``) left by
    processes that are gone (killed while saving);
    returns them. A file of any other name, or of a process still running, is left alone."""
    d = Path(folder)
    gone: list[Path] = []
    if not d.is_dir():
        return gone
    for f in sorted(d.glob(".*.tmp")):
        m = _TEMPORARY.fullmatch(f.name)
        if m is None or not f.is_file() or f.is_symlink() or _alive(int(m.group(2))):
            continue
        try:
            f.unlink()
        except FileNotFoundError:
            continue
        gone.append(f)
    return gone
