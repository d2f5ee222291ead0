"""Value equality for the dataclasses that hold numpy arrays (captures, sweeps, images, annotations).

A dataclass's generated ``__eq__`` compares its fields as a tuple, which asks an array for its truth value and
raises numpy's ``ValueError``: ``capture_a == capture_b`` could not answer. :func:`same` compares field by field
instead: arrays by dtype, shape and value (NaN equal to NaN, so two captures of the same frame are equal), dicts
by keys and values, lists and tuples item by item, fields marked ``compare=False`` left out.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

__all__ = ["same"]


def same(a: Any, b: Any) -> bool:
    """Whether ``a`` and ``b`` hold the same values (see the module docstring)."""
    if a is b:
        return True
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        if not (isinstance(a, np.ndarray) and isinstance(b, np.ndarray)):
            return False
        if a.dtype != b.dtype or a.shape != b.shape:
            return False
        return bool(np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"))
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        return type(a) is type(b) and all(
            same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a) if f.compare
        )
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(same(v, b[k]) for k, v in a.items())
    if isinstance(a, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    return bool(a == b)
