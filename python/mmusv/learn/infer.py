"""Batch inference over a tensor cache with torch and numpy alone (a GPU machine without mmusv installed): the
heatmap peaks (:func:`mmusv.learn.decode.peaks`, before rotated NMS) of the single-agent model on every cloud,
and of the early- and intermediate-fusion models on every sample (the ego with its current neighbours).

Output ``.npz``: for each of ``single`` (per cloud), ``early`` and ``intermediate`` (per sample): ``<m>_boxes``
``(M, 7)`` float32 ego-frame ``x, y, z, l, w, h, yaw``, ``<m>_scores`` ``(M,)``, ``<m>_offsets`` (rows of item
``i`` are ``offsets[i]:offsets[i+1]``), ``<m>_model`` ``()`` str the weights' digest
(:func:`mmusv.learn.checkpoint.weights_digest`: replay checks the IoU scorers were fitted for them); and
``intermediate_bytes`` ``(K,)`` the bytes the neighbours sent.
:mod:`mmusv.learn.replay` turns it into the detection study's predictions Parquet (rotated NMS and late fusion
done there by the study's own code). A ``--models`` folder without a model of the ``--modes`` asked for is refused
(an empty peaks file was written). The file is written under the very name given (``-o peaks`` wrote
``peaks.npz``).

Run as a command (``scripts/learn_train.py infer|merge``), a bad input is one line, ``mmusv: error: ...``, and exit
status 2.
"""

from __future__ import annotations

import argparse
import time
import zipfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import torch

from mmusv.learn._errors import input_error
from mmusv.learn.cache import Cache
from mmusv.learn.checkpoint import load_checkpoint, weights_digest
from mmusv.learn.decode import peaks
from mmusv.learn.example import MODES, collate, make_example, message_bytes
from mmusv.learn.model import PillarNet, checked_device, from_checkpoint
from mmusv.text import command_line, counted, given

__all__ = ["infer_cache", "main", "merge_main", "merge_peaks"]


def _model(path: Path, dev: torch.device) -> PillarNet:
    what = f"{path}: not an mmusv.learn model.pt"
    ck = load_checkpoint(path, what=what, device=dev)
    m = from_checkpoint(ck, what, mode=path.parent.name if path.parent.name in MODES else None).to(dev)
    return (m.channels_last() if dev.type == "cuda" else m).eval()


def infer_cache(
    cache: Cache,
    *,
    models: str | Path,
    out: str | Path,
    device: str | None = None,
    limit: int | None = None,
    modes: Sequence[str] = MODES,
) -> Path:
    """Writes the peaks of every model of ``modes`` found under ``models`` (``<mode>/model.pt``) on ``cache`` to
    ``out`` (the first ``limit`` items per model only, when given: smoke tests). One process per mode, each
    with its own ``out``, runs the models side by side; :func:`merge_peaks` joins their files."""
    unknown = sorted(set(modes) - set(MODES))
    if unknown or not modes:  # none: "no /model.pt there"
        what = f"unknown {', '.join(unknown)}" if unknown else "no model named"
        raise input_error(f"{given('modes', list(modes) or '')}: {what}; allowed: {', '.join(MODES)}")
    # -1 ran every item but the last (a slice), 0 none
    if limit is not None and not (isinstance(limit, int) and not isinstance(limit, bool) and limit >= 1):
        raise input_error(f"{given('limit', limit)}: must be a whole number >= 1 (or left out for every item)")
    check_out_file(out)
    dev = checked_device(device)  # "tpu" was a torch traceback
    root = Path(models)
    arrays: dict[str, np.ndarray] = {}
    n_clouds = len(cache.arrays["cloud_offsets"]) - 1
    for mode in MODES:
        f = root / mode / "model.pt"
        if mode not in modes or not f.is_file():
            continue
        model = _model(f, dev)
        p = model.preset
        items = range(n_clouds) if mode == "single" else range(len(cache))
        if limit is not None:
            items = items[:limit]
        boxes, scores, counts, sent = [], [], [], []
        t0 = time.perf_counter()
        for i in items:
            if mode == "single":
                ex = make_example(cache.cloud(i), neighbours=[], boxes=None, mode=mode, p=p)
            else:
                ego, nbs, _ = cache.sample(i)
                ex = make_example(ego, neighbours=nbs, boxes=None, mode=mode, p=p)
                if ex.nb is not None:
                    sent.append(message_bytes(ex.nb, p.pfn_channels))
            with torch.no_grad():
                b, s = peaks(model(collate([ex]).to(dev)), p)
            boxes.append(b.astype(np.float32))
            scores.append(s.astype(np.float32))
            counts.append(len(s))
        arrays[f"{mode}_boxes"] = np.concatenate(boxes) if boxes else np.zeros((0, 7), np.float32)
        arrays[f"{mode}_scores"] = np.concatenate(scores) if scores else np.zeros(0, np.float32)
        arrays[f"{mode}_offsets"] = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        arrays[f"{mode}_model"] = np.array(weights_digest(model.state_dict()))
        if mode == "intermediate":
            arrays["intermediate_bytes"] = np.array(sent, dtype=np.int64)
        print(f"{mode}: {counted(len(counts), 'inference')}, {time.perf_counter() - t0:.1f} s", flush=True)
    if not arrays:  # an empty peaks file was written, and replayed into predictions without a box
        raise input_error(
            f"{given('models', root)}: no {'|'.join(m for m in MODES if m in modes)}/model.pt there (mmusv train's "
            "output folder holds one per model)"
        )
    return _write(arrays, out)


def check_out_file(out: str | Path) -> Path:
    """``out``, the file a command writes (``-o``), refused when it is a folder, before any work: the peaks were
    computed (minutes on a GPU), then their file failed to take the folder's place, in a message naming the
    temporary file (``.OUT.partial: Is a directory``), which was left behind."""
    out_p = Path(out)
    if out_p.is_dir():
        raise input_error(f"{given('out', out)}: a folder; give the name of the file to write")
    return out_p


def _write(arrays: dict[str, np.ndarray], out: str | Path) -> Path:
    """``arrays`` into the ``.npz`` file ``out``, by that very name (numpy's own writer appended ``.npz`` to a name
    without it, and the path returned was not the file written), through a temporary file: an interrupted run leaves
    no file that looks complete, and a failed one no temporary file."""
    out_p = check_out_file(out)
    tmp = out_p.with_name(f".{out_p.name}.partial")
    try:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, **arrays)  # type: ignore[arg-type]
        tmp.replace(out_p)
    except BaseException:  # a full disk, a Ctrl-C
        tmp.unlink(missing_ok=True)
        raise
    return out_p


def merge_peaks(parts: Sequence[str | Path], out: str | Path) -> Path:
    """Joins the peak files ``parts`` of :func:`infer_cache` (one mode or more each, no mode twice) into
    ``out``; a missing part is skipped (a model that was not trained)."""
    check_out_file(out)
    arrays: dict[str, np.ndarray] = {}
    for part in parts:
        if not Path(part).is_file():
            continue
        try:
            with open(part, "rb") as fh, np.load(fh, allow_pickle=False) as f:
                held = {k: f[k] for k in f.files}
        except (ValueError, EOFError, TypeError, zipfile.BadZipFile) as exc:  # a numpy traceback
            raise input_error(f"{part}: not a peaks .npz of mmusv.learn.infer ({type(exc).__name__})") from None
        for k, v in held.items():
            if k in arrays:
                raise input_error(f"{part}: {k} is in two of the peak files")
            arrays[k] = v
    if not arrays:
        raise input_error(f"{', '.join(str(x) for x in parts)}: none of the peak files is there")
    return _write(arrays, out)


def main(argv: Sequence[str] | None = None) -> int:
    """``scripts/learn_train.py infer --cache C --models DIR -o OUT.npz``."""
    ap = argparse.ArgumentParser(description="Heatmap peaks of trained models on a tensor cache (torch + numpy only).")
    ap.add_argument("--cache", required=True)
    ap.add_argument("--models", required=True, help="folder with <mode>/model.pt")
    ap.add_argument("-o", "--out", required=True, help="output .npz")
    ap.add_argument("--device", default=None)
    ap.add_argument("--limit", type=int, default=None, help="first N items per model (smoke tests)")
    ap.add_argument("--modes", default=",".join(MODES), help="the models to run (default: every one found)")
    a = ap.parse_args(argv)
    modes = [m.strip() for m in a.modes.split(",") if m.strip()]
    flags = {"cache": "--cache", "models": "--models", "modes": "--modes", "out": "-o", "limit": "--limit"}
    flags["device"] = "--device"
    with command_line(flags):  # the messages name these flags
        cache = Cache(a.cache, name="cache")
        infer_cache(cache, models=a.models, out=a.out, device=a.device, limit=a.limit, modes=modes)
    return 0


def merge_main(argv: Sequence[str] | None = None) -> int:
    """``scripts/learn_train.py merge -o OUT.npz PART.npz...``: :func:`merge_peaks`."""
    ap = argparse.ArgumentParser(description="Join per-mode peak files of scripts/learn_train.py infer.")
    ap.add_argument("parts", nargs="+")
    ap.add_argument("-o", "--out", required=True, help="output .npz")
    a = ap.parse_args(argv)
    with command_line({"out": "-o"}):
        print(merge_peaks(a.parts, a.out))
    return 0
