"""Packs the models of ``scripts/learn_train.py``'s output folder for transfer: ``SRC/<mode>/model.pt`` →
``DST/<mode>.pt`` with float16 weights (half the size; :func:`mmusv.learn.detector.load_models` loads them back
into float32) and ``SRC/<mode>/log.jsonl`` → ``DST/<mode>.jsonl``. Needs torch only.
Usage: ``python3 scripts/learn_pack.py SRC DST``."""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("src", type=Path, help="scripts/learn_train.py's output folder (SRC/<mode>/model.pt)")
    ap.add_argument("dst", type=Path, help="the folder to write <mode>.pt and <mode>.jsonl into")
    args = ap.parse_args()
    import torch

    src, dst = args.src, args.dst
    dst.mkdir(parents=True, exist_ok=True)
    for d in sorted(x for x in src.iterdir() if (x / "model.pt").is_file()):
        ck = torch.load(d / "model.pt", map_location="cpu", weights_only=True)
        ck["model"] = {k: (v.half() if v.is_floating_point() else v) for k, v in ck["model"].items()}
        torch.save(ck, dst / f"{d.name}.pt")
        shutil.copy(d / "log.jsonl", dst / f"{d.name}.jsonl")
        print(
            f"{d.name}: epoch {ck['epoch']}, step {ck['step']}, {(dst / f'{d.name}.pt').stat().st_size / 2**20:.1f} MiB"
        )
