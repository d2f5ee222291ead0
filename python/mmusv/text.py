"""Words of the messages the commands print, with no dependency (the training scripts import it with torch and
numpy alone, :mod:`mmusv.learn.train`)."""

from __future__ import annotations

__all__ = ["counted"]


def counted(n: int, noun: str, *, plural: str | None = None, fmt: str = "") -> str:
    """``n`` and ``noun``, plural unless ``n`` is 1, for what the commands print: ``counted(1, "epoch")`` is ``1
    epoch``, ``counted(3, "epoch")`` ``3 epochs`` (``plural`` when adding an s is wrong; ``fmt`` formats ``n``, e.g.
    ``","``). The summaries said "1 sequences", "1 epochs". Machine-readable outputs keep their own fields."""
    return f"{n:{fmt}} {noun if n == 1 else plural or noun + 's'}"
