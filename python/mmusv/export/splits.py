"""Splitting recordings (sequences) into ``train`` / ``validate`` / ``test`` with a fixed seed.

The split is made per recording, before any agent-as-ego expansion a loader may do, so no scene ends up in two
splits. Recordings are ordered by a stable key (not by the order they were given), shuffled with
``random.Random(seed)``, and cut by largest-remainder counts; every split with a non-zero ratio gets at least one
recording when there are enough recordings for that.
"""

from __future__ import annotations

import math
import random
from collections.abc import Sequence

import numpy as np

from mmusv import arguments
from mmusv.errors import ConfigError
from mmusv.text import given, named

__all__ = ["DEFAULT_RATIOS", "SPLIT_NAMES", "assign_splits", "parse_ratios", "split_counts"]

SPLIT_NAMES = ("train", "validate", "test")
DEFAULT_RATIOS = (0.7, 0.15, 0.15)
"""The default ``(train, validate, test)`` fractions."""


def parse_ratios(ratios: Sequence[float] | str, *, name: str = "ratios") -> tuple[float, float, float]:
    """Validated ``(train, validate, test)`` fractions from a sequence or a ``"0.7,0.15,0.15"`` string: three
    fractions that add up to 1 (within 1e-6), or three whole-number weights (``7,2,1``, ``1,1,1``), normalised to
    sum to 1. Fractions that add up to something else (``0.7,0.2,0.2``) are refused: they were rescaled without
    a word, so a typo changed the proportions asked for. ``name``: the keyword argument that gave them (``ratios``
    of :func:`assign_splits`, ``splits`` of :func:`mmusv.export.convert`), which the messages name as their user
    gave it (:func:`mmusv.text.given`: ``splits = (0.7, 0.2, 0.2)`` from Python, ``--split 0.7,0.2,0.2`` or
    ``--split-ratios 1,2`` from a command); they said ``split`` whatever the caller gave."""
    shown = given(name, ratios)
    if isinstance(ratios, str):
        try:
            vals = [float(x) for x in ratios.split(",")]
        except ValueError:
            raise ConfigError(f"{shown}: expected three comma-separated fractions, e.g. 0.7,0.15,0.15") from None
    else:
        if isinstance(ratios, np.ndarray) and ratios.ndim == 1:  # three fractions as numpy holds them
            ratios = ratios.tolist()
        if not isinstance(ratios, (list, tuple)):
            raise ConfigError(
                f"{shown}: expected three fractions (train, validate, test), e.g. (0.7, 0.15, 0.15) or '0.7,0.15,0.15'"
            )
        vals = [arguments.real(x, name=f"{named(name)}[{i}]", finite=False) for i, x in enumerate(ratios)]
    if len(vals) != 3:
        raise ConfigError(f"{shown}: expected three fractions (train, validate, test)")
    if not all(math.isfinite(v) and v >= 0 for v in vals) or sum(vals) <= 0:
        raise ConfigError(f"{shown}: fractions must be finite, non-negative and not all zero")
    total = sum(vals)
    if abs(total - 1.0) > 1e-6 and not all(float(v).is_integer() for v in vals):
        raise ConfigError(
            f"{shown}: the fractions add up to {total:.6g}; they must add up to 1 "
            "(e.g. 0.7,0.15,0.15), or be whole-number weights (e.g. 7,2,1)"
        )
    return (vals[0] / total, vals[1] / total, vals[2] / total)


def split_counts(n: int, ratios: Sequence[float]) -> list[int]:
    """How many of ``n`` recordings go to each split (largest remainder; ties to the earlier split)."""
    raw = [r * n for r in ratios]
    counts = [math.floor(x) for x in raw]
    order = sorted(range(len(raw)), key=lambda i: (-(raw[i] - counts[i]), i))
    for i in order[: n - sum(counts)]:
        counts[i] += 1
    wanted = [i for i, r in enumerate(ratios) if r > 0]
    if n >= len(wanted):
        for i in wanted:
            if counts[i] == 0:
                donor = max(range(len(counts)), key=lambda j: (counts[j], -j))
                counts[donor] -= 1
                counts[i] += 1
    return counts


def assign_splits(keys: Sequence[str], *, ratios: Sequence[float], seed: int) -> dict[str, str]:
    """Split name of every key (unique strings, e.g. recording paths): deterministic in (set of keys, ratios,
    seed), independent of the order of ``keys``. ``ratios`` as :func:`parse_ratios` takes them (three fractions
    adding up to 1, or three whole-number weights); :class:`~mmusv.errors.ConfigError` for others."""
    if len(set(keys)) != len(keys):
        twice = next(k for i, k in enumerate(keys) if k in keys[:i])
        raise ConfigError(f"the same recording is given twice: {twice}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        # random.Random takes |seed|: -1 would split as 1 does
        raise ConfigError(f"seed = {seed!r}: the split's seed must be a whole number >= 0")
    # checked as parse_ratios checks them (a caller in Python gave them unchecked: two fractions were zip()'s
    # ValueError, a string a TypeError, (0.7, 0.7, 0.7) or a negative one a split of other proportions, silently);
    # fractions that add up to 1 are used as given, so that the splits they made stay the same
    checked = parse_ratios(ratios, name="ratios")
    asked = [float(r) for r in ratios] if not isinstance(ratios, str) else list(checked)
    fractions = asked if abs(sum(asked) - 1.0) <= 1e-6 else list(checked)
    ordered = sorted(keys)
    random.Random(seed).shuffle(ordered)
    counts = split_counts(len(ordered), fractions)
    out: dict[str, str] = {}
    start = 0
    for name, c in zip(SPLIT_NAMES, counts, strict=True):
        for k in ordered[start : start + c]:
            out[k] = name
        start += c
    return out
