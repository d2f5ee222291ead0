"""The base of the models of the files a user writes (scenarios and their rigs): unknown keys, NaN and infinity
refused, strings stripped, instances frozen, and no boolean taken for a number.

Pydantic's lax mode reads ``true`` as 1 for an int or float field: ``frames: true`` would record one frame and
``speed_mps: true`` sail at 1 m/s without a word. Here a boolean is refused wherever the field does not take one,
also inside a field's lists, tuples and mappings (a waypoint ``[true, 0]`` sailed to x = 1): :class:`StrictModel`
for the models, :func:`bool_for_a_number` for a model that needs other settings.

Values from numpy (a seed drawn with ``rng.integers``, a route as an array) are taken as the Python values they
stand for first: pydantic reads a numpy integer through a float, so ``np.int64(2**62 + 1)`` became the seed
``2**62`` without a word and ``np.int64(2**63 - 1)`` was refused as too large; and ``np.True_`` is a boolean, not 1.
"""

from __future__ import annotations

import types
import typing
from collections import abc
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, ValidationInfo, field_validator

__all__ = ["StrictModel", "bool_for_a_number", "python_values"]


class StrictModel(BaseModel):
    """A frozen model that forbids unknown keys, NaN and infinity, and booleans for numbers (module docs)."""

    model_config = ConfigDict(extra="forbid", frozen=True, str_strip_whitespace=True, allow_inf_nan=False)

    @field_validator("*", mode="before")
    @classmethod
    def _no_bool_for_a_number(cls, v: Any, info: ValidationInfo) -> Any:
        return bool_for_a_number(cls, v, info)


def bool_for_a_number(model: type[BaseModel], v: Any, info: ValidationInfo) -> Any:
    """``v`` with numpy values as Python's (:func:`python_values`), or ``ValueError`` when it is, or holds where a
    number goes (in a list, tuple or mapping of the field's type), ``true``/``false`` (Python's or numpy's): the
    body of a ``field_validator("*", mode="before")`` of ``model``."""
    v = python_values(v)
    if info.field_name is None:
        return v
    field = model.model_fields.get(info.field_name)
    if field is not None and _bool_for_number(field.annotation, v):
        raise ValueError("a number is expected, not true/false")
    return v


def python_values(v: Any) -> Any:
    """``v`` with numpy scalars and arrays, also inside lists, tuples and mappings, as the Python values they hold
    (``np.int64`` an exact ``int``, ``np.bool_`` a ``bool``, an array its nested lists); anything else unchanged."""
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, np.generic):
        return v.item() if isinstance(v, (np.bool_, np.integer, np.floating)) else v
    if isinstance(v, (list, tuple)) and any(isinstance(x, (np.generic, np.ndarray, list, tuple, dict)) for x in v):
        return type(v)(python_values(x) for x in v) if type(v) in (list, tuple) else v
    if type(v) is dict and any(isinstance(x, (np.generic, np.ndarray, list, tuple, dict)) for x in v.values()):
        return {k: python_values(x) for k, x in v.items()}
    return v


def _bool_for_number(annotation: Any, v: Any) -> bool:
    """Whether ``v`` (or an item of it, at any depth) is a boolean where ``annotation`` takes a number only."""
    if typing.get_origin(annotation) is typing.Annotated:
        return _bool_for_number(typing.get_args(annotation)[0], v)
    if isinstance(v, bool):
        return _numeric(annotation) and not _takes_bool(annotation)
    if not isinstance(v, (list, tuple, dict)):
        return False
    for member in _members(annotation):
        origin, args = typing.get_origin(member), typing.get_args(member)
        if isinstance(v, dict) and origin in (dict, abc.Mapping) and len(args) == 2:
            if any(_bool_for_number(args[1], x) for x in v.values()):
                return True
        elif isinstance(v, (list, tuple)) and origin in (list, tuple, abc.Sequence) and args:
            if origin is tuple and args[-1] is not Ellipsis:
                if any(_bool_for_number(a, x) for a, x in zip(args, v, strict=False)):
                    return True
            elif any(_bool_for_number(args[0], x) for x in v):
                return True
    return False


def _members(annotation: Any) -> tuple[Any, ...]:
    """The members of a union annotation (``int | None``), or the annotation itself; ``Annotated`` unwrapped."""
    if typing.get_origin(annotation) is typing.Annotated:
        return _members(typing.get_args(annotation)[0])
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        return tuple(m for a in typing.get_args(annotation) for m in _members(a))
    return (annotation,)


def _numeric(annotation: Any) -> bool:
    return any(m in (int, float) for m in _members(annotation))


def _takes_bool(annotation: Any) -> bool:
    return any(m is bool or m is Any for m in _members(annotation))
