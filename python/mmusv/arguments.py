"""Checks of the plain arguments the Python API takes from a programmer: whole numbers (frame indices, counts,
seeds), real numbers and arrays of them, flags, file and folder paths, callbacks and collections of names.

Each check returns the value in its one accepted form (``int``, ``float``, ``bool``, :class:`~pathlib.Path`, ...)
or raises ``error`` (:class:`~mmusv.errors.ConfigError` unless the caller names another class of
:mod:`mmusv.errors`) whose message names the argument, the value given and what is allowed, e.g.
``frames = 1.5: must be a whole number (int or numpy integer) in 1..50``. Nothing is coerced that could change its
meaning: a float is not a frame index (``1.7`` is not frame 1), a string is not a number, ``True`` is neither a
count nor a number, and a flag is a ``bool`` (the string ``"no"`` would be true). numpy integers, floats and
booleans count as their Python kinds.
"""

from __future__ import annotations

import inspect
import math
import numbers
import operator
import os
import reprlib
from collections.abc import Collection, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from typing_extensions import TypeIs

from mmusv.errors import ConfigError

__all__ = [
    "callback",
    "flag",
    "holds_true_false",
    "is_number",
    "mapping",
    "names",
    "path",
    "real",
    "reals",
    "rows",
    "shown",
    "whole",
]

_REPR = reprlib.Repr()
_REPR.maxstring, _REPR.maxother = 60, 60


def shown(value: Any) -> str:
    """``value`` as a message shows it: its repr, shortened to about 60 characters."""
    return _REPR.repr(value)


def _is_bool(value: Any) -> bool:
    return isinstance(value, (bool, np.bool_))


def is_number(value: object) -> TypeIs[numbers.Real]:
    """Whether ``value`` is a real number: a Python or numpy integer or float, not true/false (which
    :class:`numbers.Real` holds) and not a string. Its range is the caller's to check; where it is true, type
    checkers know ``value`` is a :class:`numbers.Real` (``float(value)`` is allowed). (``TypeIs``, not ``TypeGuard``:
    it keeps a ``float`` argument a ``float`` where true; where false it would claim the value is no
    :class:`numbers.Real`, which a bool is, but mypy does not narrow builtin numbers that way.)"""
    return isinstance(value, numbers.Real) and not _is_bool(value)


def whole(
    value: Any,
    *,
    name: str,
    lo: int | None = None,
    hi: int | None = None,
    error: type[Exception] = ConfigError,
) -> int:
    """``value`` as an ``int``: a Python or numpy integer (or a 0-d integer array) in ``lo..hi`` (either bound
    may be ``None``: unbounded). Floats, strings and booleans are refused, whatever their value."""
    where = _range(lo, hi)
    if _is_bool(value):
        raise error(f"{name} = {value!r}: must be a whole number{where}, not true/false")
    try:
        i = operator.index(value)
    except TypeError:
        raise error(
            f"{name} = {shown(value)}: must be a whole number (int or numpy integer){where}, not {type(value).__name__}"
        ) from None
    if (lo is not None and i < lo) or (hi is not None and i > hi):
        raise error(f"{name} = {shown(i)}: must be a whole number{where}")
    return i


def _range(lo: int | None, hi: int | None) -> str:
    if lo is not None and hi is not None:
        return f" in {lo}..{hi}"
    if lo is not None:
        return f" >= {lo}"
    if hi is not None:
        return f" <= {hi}"
    return ""


def real(
    value: Any,
    *,
    name: str,
    unit: str = "",
    lo: float | None = None,
    hi: float | None = None,
    above: float | None = None,
    finite: bool = True,
    error: type[Exception] = ConfigError,
) -> float:
    """``value`` as a ``float``: a Python or numpy real number (not a string, not a boolean), finite unless
    ``finite`` is false, with ``lo <= value <= hi`` and ``value > above`` where those are given. ``unit`` (e.g.
    ``"metres"``) is named in the message."""
    what = "a finite number" if finite else "a number"
    if unit:
        what += f" of {unit}"
    bounds = [f">= {lo:g}" if lo is not None else "", f"> {above:g}" if above is not None else ""]
    bounds += [f"<= {hi:g}" if hi is not None else ""]
    allowed = what + "".join(f" {b}" for b in bounds if b)
    if not is_number(value):
        kind = "true/false" if _is_bool(value) else type(value).__name__
        raise error(f"{name} = {shown(value)}: must be {allowed}, not {kind}")
    x = float(value)
    if (finite and not math.isfinite(x)) or math.isnan(x):
        raise error(f"{name} = {x}: must be {allowed}")
    if (lo is not None and x < lo) or (hi is not None and x > hi) or (above is not None and not x > above):
        raise error(f"{name} = {shown(value)}: must be {allowed}")
    return x


def flag(value: Any, *, name: str, error: type[Exception] = ConfigError) -> bool:
    """``value`` as a ``bool``: ``True``/``False`` (or numpy's). Anything else is refused: the string ``"no"``
    or the number 2 are not flags."""
    if not _is_bool(value):
        raise error(f"{name} = {shown(value)}: must be True or False, not {type(value).__name__}")
    return bool(value)


def path(value: Any, *, name: str, error: type[Exception] = ConfigError) -> Path:
    """``value`` as a :class:`~pathlib.Path`: a ``str`` or an ``os.PathLike`` of ``str``, not empty (an empty
    path would quietly mean the current folder: give ``"."`` for that)."""
    if isinstance(value, bytes) or not isinstance(value, (str, os.PathLike)):
        raise error(f"{name} = {shown(value)}: must be a path (str or pathlib.Path), not {type(value).__name__}")
    try:
        text = os.fspath(value)
    except TypeError as exc:
        raise error(f"{name} = {shown(value)}: must be a path (str or pathlib.Path): {exc}") from None
    if not isinstance(text, str):
        raise error(f"{name} = {shown(value)}: must be a path of str, not of {type(text).__name__}")
    if not text:
        raise error(f'{name} is empty: give a path ("." for the current folder)')
    if "\x00" in text:
        raise error(f"{name} = {shown(text)}: a path cannot hold a NUL character")
    return Path(text)


def callback(value: Any, *, name: str, nargs: int, error: type[Exception] = ConfigError) -> Any:
    """``value`` when it is ``None`` or a callable that takes ``nargs`` positional arguments (checked on its
    signature where Python can read one), so that a wrong callback fails before any work, not after the first
    frame."""
    if value is None:
        return None
    if not callable(value):
        raise error(f"{name} = {shown(value)}: must be a function taking {nargs} arguments, or None")
    try:
        sig = inspect.signature(value)
    except (TypeError, ValueError):  # a builtin without a signature: called as it is
        return value
    try:
        sig.bind(*range(nargs))
    except TypeError as exc:  # Python's words are the call's ("too many positional arguments"), not the function's
        why = "it takes fewer" if "too many" in str(exc) else "it needs others" if "missing" in str(exc) else exc
        raise error(f"{name} = {shown(value)}: must take {nargs} positional arguments; {why}") from None
    return value


def names(value: Any, *, name: str, example: str, error: type[Exception] = ConfigError) -> frozenset[str] | None:
    """``value`` as a set of names: ``None`` (all), or a collection (list, tuple, set) of strings. A bare string
    is refused rather than read as its characters; ``example`` shows the expected form (``['usv_1']``)."""
    if value is None:
        return None
    if isinstance(value, (str, bytes)):
        raise error(f"{name} = {shown(value)}: must be a list of names, e.g. {example}, not a single string")
    if not isinstance(value, Collection) or isinstance(value, Mapping):
        raise error(f"{name} = {shown(value)}: must be a list of names, e.g. {example}, not {type(value).__name__}")
    bad = [v for v in value if not isinstance(v, str)]
    if bad:
        raise error(f"{name} = {shown(value)}: must hold names (strings), e.g. {example}; got {shown(bad[0])}")
    return frozenset(value)


def mapping(value: Any, *, name: str, error: type[Exception] = ConfigError) -> Mapping[str, Any] | None:
    """``value`` when it is ``None`` or a mapping with string keys."""
    if value is None:
        return None
    if not isinstance(value, Mapping) or not all(isinstance(k, str) for k in value):
        raise error(f"{name} = {shown(value)}: must be a dict with string keys, or None")
    return value


_KINDS = {"b": "true/false", "U": "text", "S": "bytes", "c": "complex numbers"}
"""What a numpy array of each dtype kind holds, said where real numbers go."""


def reals(
    value: Any, *, name: str, what: str, tail: tuple[int, ...] = (), error: type[Exception] = ConfigError
) -> np.ndarray:
    """``value`` as a float64 array of real numbers (not true/false, also inside a list, nor text, ``None`` or
    complex numbers) whose last axes are ``tail``, else ``error`` naming ``name`` and the shape ``what`` it must
    have."""
    try:
        raw = np.asarray(value)
        # Only real numbers: a None (NaN as float64), a bool, text ("1.5" converts) or a complex number (its
        # imaginary part dropped) would be read as a number without a word.
        kind = raw.dtype.kind
        if holds_true_false(value, raw):
            raise TypeError("it holds true/false")
        if kind == "O":
            bad = [x for x in raw.flat if not is_number(x)][:1]
            if bad:
                raise TypeError(f"it holds {shown(bad[0])}")
        elif kind not in "iuf":
            raise TypeError(f"it holds {_KINDS.get(kind, f'{raw.dtype} values')}")
        a = np.asarray(raw, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise error(f"{name} must be {what} of real numbers: {exc}") from None
    if a.ndim < len(tail) or a.shape[a.ndim - len(tail) :] != tail:
        raise error(f"{name} must be {what}, got shape {a.shape}")
    return a


def rows(
    value: Any,
    *,
    name: str,
    dtype: Any,
    tail: tuple[int, ...],
    empty: bool = False,
    error: type[Exception] = ConfigError,
) -> np.ndarray:
    """``value``, numbers of shape ``(N, *tail)``, as a C-contiguous array of ``dtype`` (values past a float32's range
    become inf, for the caller's finiteness check to name), else ``error`` naming ``name``: not numbers (true/false,
    text, objects), complex numbers, another shape, or real numbers where ``dtype`` is an integer type. With
    ``empty``, an empty list or tuple, or an array of shape ``(0,)``, is no rows (numpy reads ``[]`` as ``(0,)``)."""
    if empty and (
        (isinstance(value, (list, tuple)) and not value) or (isinstance(value, np.ndarray) and value.shape == (0,))
    ):
        return np.zeros((0, *tail), dtype=dtype)
    try:
        arr = np.asarray(value)
    except Exception as exc:
        raise error(f"{name} could not be converted to an array: {exc}") from None
    if arr.dtype == object or not np.issubdtype(arr.dtype, np.number):
        raise error(f"{name} must be numeric, got dtype {arr.dtype}")
    if np.iscomplexobj(arr):
        raise error(f"{name} must be real, got complex dtype {arr.dtype}")
    if arr.ndim != 1 + len(tail) or tuple(arr.shape[1:]) != tail:
        raise error(f"{name} must have shape (N, {', '.join(str(s) for s in tail)}), got {arr.shape}")
    if np.issubdtype(dtype, np.integer) and not np.issubdtype(arr.dtype, np.integer):
        raise error(f"{name} must be an integer array, got dtype {arr.dtype}")
    with np.errstate(over="ignore", invalid="ignore"):
        return np.ascontiguousarray(arr, dtype=dtype)


def holds_true_false(value: Any, raw: np.ndarray) -> bool:
    """Whether ``value``, which numpy read as ``raw``, holds true/false among numbers: a list such as ``[True,
    2.0]`` is numbers to numpy (``[1.0, 2.0]``), so where ``raw`` is numbers and ``value`` no array, its entries
    are looked at (a bool, numpy's, or a bool array)."""
    if raw.dtype.kind not in "iuf" or raw.ndim == 0 or isinstance(value, np.ndarray):
        return False
    return any(map(_true_false, np.asarray(value, dtype=object).flat))


def _true_false(x: object) -> bool:
    """Whether ``x`` (an entry of a list numpy read as numbers) is true/false: a bool or a bool array."""
    return isinstance(x, (bool, np.bool_)) or (isinstance(x, np.ndarray) and x.dtype.kind == "b")
