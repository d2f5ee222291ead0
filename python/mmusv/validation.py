"""Building blocks of mmusv's pydantic schemas, and pydantic errors as a dotted field path plus what is allowed.

:class:`Spec` is a frozen model that refuses unknown keys and reads ``key: null`` as "not given"; the value types
(:data:`Number`, :data:`Positive`, :data:`Vec3`, ...) refuse bools and strings where a number is meant. Checks in
validators raise :func:`invalid` (the value at hand) or :func:`invalid_field` (a named field of the model, for
checks across fields). :func:`describe` turns one error of ``ValidationError.errors()`` into
``("tug.parts[3].top", "must be > 0.0, got -1")``: union tags left out of the path, unknown keys answered with the
keys that are known there.
"""

from __future__ import annotations

import reprlib
import types
import typing
from collections.abc import Mapping
from typing import Annotated, Any, Literal, Union

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, model_validator
from pydantic_core import ErrorDetails, PydanticCustomError

__all__ = [
    "Fraction",
    "NonNegative",
    "Number",
    "Positive",
    "Spec",
    "Text",
    "Vec2",
    "Vec3",
    "Whole",
    "describe",
    "invalid",
    "invalid_field",
    "join",
    "keys",
    "sequence",
    "whole",
]


def invalid(reason: str) -> PydanticCustomError:
    """A problem with the value at hand (its message is ``reason`` as is)."""
    return PydanticCustomError("mmusv_value", "{reason}", {"reason": reason})


def invalid_field(field: str, reason: str) -> PydanticCustomError:
    """A problem a model check finds in its field ``field`` (the error path gets ``.field`` appended)."""
    return PydanticCustomError("mmusv_field", "{reason}", {"field": field, "reason": reason})


def sequence(n_min: int, n_max: int | None, what: str) -> BeforeValidator:
    """Accepts a list (or tuple) of ``n_min`` to ``n_max`` items (no upper bound for ``None``); ``what`` names it."""

    def check(value: object) -> object:
        if not isinstance(value, (list, tuple)):
            raise invalid(f"must be {what}, got {reprlib.repr(value)}")
        if not n_min <= len(value) <= (n_max or len(value)):
            raise invalid(f"must be {what}, got {len(value):,} items: {reprlib.repr(value)}")
        return value

    return BeforeValidator(check)


def whole(value: object) -> object:
    """A whole number given as an int or an integral float (``3`` or ``3.0``); not a bool, not a string."""
    if isinstance(value, float) and value.is_integer():
        return int(value)
    if isinstance(value, bool) or not isinstance(value, int):
        raise invalid(f"must be a whole number, got {value!r}")
    return value


Number = Annotated[float, Field(strict=True, allow_inf_nan=False)]
"""A finite number (an int or a float; not a bool, not a string)."""
Positive = Annotated[Number, Field(gt=0.0)]
"""A finite number > 0."""
NonNegative = Annotated[Number, Field(ge=0.0)]
"""A finite number >= 0."""
Fraction = Annotated[Number, Field(ge=0.0, le=1.0)]
"""A finite number in [0, 1]."""
Whole = Annotated[int, BeforeValidator(whole)]
"""A whole number (``3`` or ``3.0``; not ``3.5``, a bool or a string)."""
Text = Annotated[str, Field(strict=True, min_length=1)]
"""A non-empty string."""
Vec2 = Annotated[tuple[Number, ...], sequence(2, 2, "a list of 2 numbers")]
"""Two numbers (a YAML list)."""
Vec3 = Annotated[tuple[Number, ...], sequence(3, 3, "a list of 3 numbers")]
"""Three numbers (a YAML list)."""


class Spec(BaseModel):
    """Frozen, unknown keys refused; ``key: null`` is the same as leaving the key out (so the default applies)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @model_validator(mode="before")
    @classmethod
    def _null_is_absent(cls, data: Any) -> Any:
        if not isinstance(data, Mapping):
            return data
        known = keys(cls)
        return {str(k): v for k, v in data.items() if v is not None or str(k) not in known}


def keys(model: type[BaseModel]) -> list[str]:
    """The keys a model accepts (field aliases where given), sorted."""
    return sorted(f.alias or name for name, f in model.model_fields.items())


# ------------------------------------------------------------------------------------------------ error paths


def join(path: str, key: str) -> str:
    """``path.key``, or ``key`` alone below an empty path."""
    return f"{path}.{key}" if path else key


def describe(e: ErrorDetails, model: type[BaseModel], root: str) -> tuple[str, str]:
    """The dotted path (below ``root``) and the message (what is allowed) of one error of validating ``model``."""
    path, owner, at = _walk(model, tuple(e["loc"]), root)
    value, ctx = e.get("input"), e.get("ctx") or {}
    match e["type"]:
        case "mmusv_field":
            return join(path, ctx["field"]), str(ctx["reason"])
        case "union_tag_invalid":
            return join(path, "type"), f"must be one of {', '.join(sorted(_tags(at)))}; got {ctx['tag']!r}"
        case "union_tag_not_found":
            return join(path, "type"), f"is required (one of {', '.join(sorted(_tags(at)))})"
        case "missing":
            return path, "is required"
        case "extra_forbidden":
            return path, f"unknown key (known here: {', '.join(keys(owner) if owner else [])})"
        case "greater_than" | "greater_than_equal" | "less_than" | "less_than_equal":
            (bound, limit), *_ = ctx.items()
            op = {"gt": ">", "ge": ">=", "lt": "<", "le": "<="}[bound]
            return path, f"must be {op} {limit}, got {value!r}"
        case "float_type":
            return path, f"must be a number, got {value!r}"
        case "finite_number":
            return path, f"must be finite, got {value!r}"
        case "string_type" | "string_too_short":
            return path, f"must be a non-empty string, got {value!r}"
        case "literal_error":
            return path, f"must be one of {', '.join(map(str, _literals(at)))}; got {value!r}"
        case "dict_type" | "model_type" | "model_attributes_type":
            return path, f"must be a mapping, got {type(value).__name__}"
        case "list_type" | "tuple_type":
            return path, f"must be a list, got {type(value).__name__}"
        case _:
            return path, str(e["msg"]).removeprefix("Value error, ")


def _walk(model: type[BaseModel], loc: tuple[int | str, ...], root: str) -> tuple[str, type[BaseModel] | None, Any]:
    """Follows ``loc`` through ``model``'s annotations: the dotted path (union tags left out), the model that
    holds the last key, and the type found at the end of ``loc``."""
    path, owner, tp = root, None, _bare(model)
    for part in loc:
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            owner = tp
            path = join(path, str(part))
            fields = {f.alias or n: f for n, f in tp.model_fields.items()}
            tp = _bare(fields[str(part)].annotation) if str(part) in fields else None
        elif _is_union(tp) and isinstance(part, str):  # a discriminated union puts the member's tag in `loc`
            tp = next((m for m in _members(tp) if part in _tags(m)), None)
        elif isinstance(part, int):
            path += f"[{part}]"
            args = typing.get_args(tp)
            tp = _bare(args[0]) if args else None
        else:  # a mapping's key
            path = join(path, str(part))
            args = typing.get_args(tp)
            tp = _bare(args[1]) if len(args) == 2 else None
    return path, owner, tp


def _bare(tp: Any) -> Any:
    """``tp`` without ``Annotated`` and without ``| None``."""
    while True:
        if typing.get_origin(tp) is Annotated:
            tp = typing.get_args(tp)[0]
        elif _is_union(tp) and len(rest := [a for a in typing.get_args(tp) if a is not type(None)]) == 1:
            tp = rest[0]
        else:
            return tp


def _is_union(tp: Any) -> bool:
    return typing.get_origin(tp) in (Union, types.UnionType)


def _members(tp: Any) -> list[Any]:
    return [_bare(m) for m in typing.get_args(tp)] if _is_union(tp) else [tp]


def _tags(tp: Any) -> list[str]:
    """The ``type`` tags of the models in ``tp`` (a model or a union of models)."""
    out = []
    for m in _members(tp):
        if isinstance(m, type) and issubclass(m, BaseModel) and "type" in m.model_fields:
            out += [str(a) for a in _literals(m.model_fields["type"].annotation)]
    return out


def _literals(tp: Any) -> tuple[object, ...]:
    tp = _bare(tp)
    return typing.get_args(tp) if typing.get_origin(tp) is Literal else ()
