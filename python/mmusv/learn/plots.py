"""Loss curves of a training's ``log.jsonl`` (:mod:`mmusv.learn.train`): one run's losses, or several runs' total
loss side by side; drawn with matplotlib's Agg backend into a PNG."""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["plot_losses", "plot_runs"]


def plot_losses(log_path: str | Path, png: str | Path) -> Path:
    """Draws the total, heatmap and regression losses of ``log.jsonl`` (or several: one per line style) over
    the optimiser steps into ``png``; returns ``png``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [json.loads(line) for line in Path(log_path).read_text(encoding="utf-8").splitlines() if line.strip()]
    steps = [r for r in rows if "loss" in r]
    fig, ax = plt.subplots(figsize=(7, 4))
    for key, style in (("loss", "-"), ("heatmap", "--"), ("regression", ":")):
        ax.plot([r["step"] for r in steps], [r[key] for r in steps], style, label=key)
    for r in rows:
        if r.get("epoch_end"):
            ax.axvline(r["step"], color="0.85", lw=0.8)
    ax.set_yscale("log")
    ax.set_xlabel("optimiser step (grey: epoch ends)")
    ax.set_ylabel("loss per object")
    ax.legend()
    ax.set_title(f"training loss: {Path(log_path).parent.name}")
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return Path(png)


def plot_runs(logs: dict[str, str | Path], png: str | Path, *, title: str) -> Path:
    """The total loss of several runs' ``log.jsonl`` (by label) over the optimiser steps in one plot."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    for label, path in logs.items():
        rows = [json.loads(x) for x in Path(path).read_text(encoding="utf-8").splitlines() if x.strip()]
        steps = [r for r in rows if "loss" in r]
        ax.plot([r["step"] for r in steps], [r["loss"] for r in steps], label=label, lw=0.9)
    ax.set_yscale("log")
    ax.set_xlabel("optimiser step")
    ax.set_ylabel("loss per object")
    ax.legend()
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return Path(png)
