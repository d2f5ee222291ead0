"""The base of the models of the files a user writes (scenarios and their rigs): unknown keys, NaN and infinity
refused, strings stripped, instances frozen, and no boolean taken for a number.

Pydantic's lax mode reads ``true`` as 1 for an int or float field: ``frames: true`` would record one frame and
``speed_mps: true`` sail at 1 m/s without a word. Here a boolean is refused wherever the field does not take one.
"""

from __future__ import annotations

import types
import typing
from typing import Any

from pydantic import BaseModel, ConfigDict, ValidationInfo, field_validator

__all__ = ["StrictModel"]


class StrictModel(BaseModel):
    """A frozen model that forbids unknown keys, NaN and infinity, and booleans for numbers (module docs)."""

    model_config = ConfigDict(extra="forbid", frozen=True, str_strip_whitespace=True, allow_inf_nan=False)

    @field_validator("*", mode="before")
    @classmethod
    def _no_bool_for_a_number(cls, v: Any, info: ValidationInfo) -> Any:
        if isinstance(v, bool) and info.field_name is not None:
            field = cls.model_fields.get(info.field_name)
            if field is not None and _numeric(field.annotation) and not _takes_bool(field.annotation):
                raise ValueError("a number is expected, not true/false")
        return v


def _members(annotation: Any) -> tuple[Any, ...]:
    """The members of a union annotation (``int | None``), or the annotation itself."""
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        return typing.get_args(annotation)
    return (annotation,)


def _numeric(annotation: Any) -> bool:
    return any(m in (int, float) for m in _members(annotation))


def _takes_bool(annotation: Any) -> bool:
    return any(m is bool or m is Any for m in _members(annotation))
