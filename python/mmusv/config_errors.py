"""A pydantic ``ValidationError`` of a scenario, spec or request said as mmusv says errors: one line per problem
naming the field path (``vessels[2].speed_mps``), the value given (shortened, :func:`short_repr`) and what is
allowed; an unknown key is told the keys allowed there and the nearest one (:func:`validation_problems`,
:func:`validation_error`). The models themselves are :mod:`mmusv.config`'s.
"""

from __future__ import annotations

import difflib
import re
import reprlib
import types
import typing
from typing import Any

from pydantic import BaseModel, ValidationError

from mmusv.errors import ConfigError
from mmusv.world.map_params import PARAM_MODELS

__all__ = ["short_repr", "validation_error", "validation_problems"]


def _field_path(loc: tuple[int | str, ...], root: str) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out or root


_VALIDATOR_STEPS = frozenset(
    {"str", "float", "int", "bool", "function-after", "function-before", "function-wrap", "function-plain"}
    | {"constrained-str", "constrained-float", "constrained-int", "literal", "nullable"}
)
"""What pydantic adds to an error's location besides the fields (the union member or validator it tried)."""

_REPR = reprlib.Repr()
_REPR.maxstring, _REPR.maxother, _REPR.maxlong = 80, 80, 40


def short_repr(value: Any) -> str:
    """How a value shows in messages: strings and numbers shortened to 80 characters, containers to a few items,
    so a 3 MB name or a document of aliases is never printed (or walked) whole."""
    return _REPR.repr(value)


def _strip_optional(tp: Any) -> Any:
    """``tp`` without ``Annotated`` and without ``None`` in a union (``LidarConfig | None`` is ``LidarConfig``)."""
    while True:
        if typing.get_origin(tp) is typing.Annotated:
            tp = typing.get_args(tp)[0]
        elif typing.get_origin(tp) in (typing.Union, types.UnionType):
            members = [a for a in typing.get_args(tp) if a is not type(None)]
            if len(members) != 1:
                return tp
            tp = members[0]
        else:
            return tp


def _model_at(model: type[BaseModel], loc: tuple[int | str, ...], data: Any) -> type[BaseModel] | None:
    """The model that reads the mapping at ``loc`` (a field path inside ``model``, as in errors), or ``None`` when
    the path leaves the models; ``data`` (the document, or ``None``) picks the parameters of the map's ``type``."""
    from mmusv.config import MapConfig  # the scenario's models, which call this module's functions in turn

    tp: Any = model
    for part in loc:
        tp = _strip_optional(tp)
        origin, args = typing.get_origin(tp), typing.get_args(tp)
        if isinstance(tp, type) and issubclass(tp, BaseModel) and isinstance(part, str) and part in tp.model_fields:
            if tp is MapConfig and part == "params":  # a union of the kinds' models: the map's type picks one
                kind = data.get("type", "island") if isinstance(data, dict) else None
                tp = PARAM_MODELS.get(kind) if isinstance(kind, str) else None
            else:
                tp = tp.model_fields[part].annotation
        elif origin is dict and isinstance(part, str) and len(args) == 2:
            tp = args[1]
        elif origin is list and isinstance(part, int) and args:
            tp = args[0]
        else:
            return None
        if isinstance(data, dict):
            data = data.get(part)
        elif isinstance(data, list) and isinstance(part, int) and 0 <= part < len(data):
            data = data[part]
        else:
            data = None
    tp = _strip_optional(tp)
    return tp if isinstance(tp, type) and issubclass(tp, BaseModel) else None


def _unknown_key_hint(model: type[BaseModel], loc: tuple[int | str, ...], data: Any, *, keys_said: bool) -> str:
    """For the unknown key at the end of ``loc``: the closest allowed key and every allowed key (but when
    ``keys_said``, already said for another unknown key there), or ``""``."""
    if not loc or not isinstance(loc[-1], str):
        return ""
    where = _model_at(model, loc[:-1], data)
    if where is None:
        return ""
    keys = list(where.model_fields)
    close = difflib.get_close_matches(loc[-1], keys, n=1, cutoff=0.75)
    hint = f"did you mean {close[0]!r}? " if close else ""
    if keys_said:
        return f"; {hint.removesuffix(' ')}" if hint else ""
    return f"; {hint}allowed keys: {', '.join(keys)}"


_PATTERN_WORDS = {
    r"^[A-Za-z0-9_\-]+$": ("use ASCII letters, digits, _ and - only", r"[A-Za-z0-9_\-]"),
    r"^[A-Za-z0-9_\-][A-Za-z0-9_\-.]*$": (
        "use ASCII letters, digits, _, - and . only, not starting with . (it names files and folders)",
        r"[A-Za-z0-9_\-.]",
    ),
}
"""What the schema's name patterns allow, in words, and the characters they take: pydantic's message is the regex
itself ("String should match pattern '^[A-Za-z0-9_\\-]+$'"), which a person typing a name need not read."""


def _pattern_words(pattern: Any, value: Any) -> str | None:
    """The words of a name ``pattern`` of :data:`_PATTERN_WORDS` for ``value``, naming its first character that is
    not allowed (or the leading dot); ``None`` for another pattern."""
    said = _PATTERN_WORDS.get(str(pattern))
    if said is None or not isinstance(value, str):
        return None
    words, chars = said
    allowed = re.compile(chars)
    bad = next((c for c in value if not allowed.fullmatch(c)), None)
    if bad is not None:
        return f"{words}; {bad!r} is not allowed"
    return f"{words}; it starts with {value[:1]!r}" if value else words


def validation_problems(
    err: ValidationError, *, root: str = "scenario", model: type[BaseModel] | None = None, data: Any = None
) -> list[tuple[str, str, str]]:
    """A pydantic ``ValidationError`` as ``(field path, value shown, what is allowed)`` per problem, the field path
    as in messages (``vessels[2].speed_mps``); a check across fields has the empty path and names the fields in its
    message; ``root`` names the whole document when a problem has no field but is not such a check. An unknown key
    of ``model`` (default: :class:`Scenario` for its errors) says the keys allowed there and the closest one;
    ``data``, the document validated, tells which map ``type``'s parameters ``map.params`` holds."""
    from mmusv.config import Scenario

    if model is None and err.title == Scenario.__name__:
        model = Scenario
    out = []
    keys_said: set[tuple[int | str, ...]] = set()  # where the allowed keys were listed: once each (a JSON Schema
    for e in err.errors():  # given as a scenario listed them 8 times)
        # Pydantic adds the union member or validator name to `loc`; drop the non-field parts.
        loc = tuple(p for p in e["loc"] if not (isinstance(p, str) and ("[" in p or p in _VALIDATOR_STEPS)))
        value = e.get("input")
        shown = short_repr(value)
        if isinstance(value, (dict, list)) and len(shown) >= 80:
            shown = f"<{type(value).__name__}>"
        msg = str(e["msg"]).removeprefix("Value error, ")
        if e["type"] == "missing":  # pydantic's input is the mapping the field is missing from, not the field's
            shown, msg = "<missing>", "required"
        if e["type"] == "too_short":  # was pydantic's "List should have at least 1 item after validation, not 0"
            ctx = e.get("ctx", {})
            n, got = ctx.get("min_length", 1), ctx.get("actual_length")
            msg = f"must hold at least {n} {'entry' if n == 1 else 'entries'}, got {got}"
        if e["type"] == "string_pattern_mismatch":
            msg = _pattern_words(e.get("ctx", {}).get("pattern"), value) or msg
        if e["type"] == "invalid_key" and loc:
            # pydantic's location ends with the key and its input is the key ("vessels[0][5] = 5: Keys should be
            # strings" read as item 5 of a list holding 5): the mapping's path, the key in it, and the keys allowed
            loc, shown = loc[:-1], f"{{{short_repr(value)}: ...}}"
            msg = f"the key {short_repr(value)} is not text; keys are names"
            if model is not None:
                msg += _unknown_key_hint(model, (*loc, ""), data, keys_said=loc in keys_said).replace("; ", " (", 1)
                msg += ")" if "(" in msg else ""
                keys_said.add(loc)
        if e["type"] == "extra_forbidden" and model is not None:
            msg += _unknown_key_hint(model, loc, data, keys_said=loc[:-1] in keys_said)
            keys_said.add(loc[:-1])
        if not loc and isinstance(value, dict):  # a check across fields: its message names the fields itself
            out.append(("", shown, msg))
            continue
        out.append((_field_path(loc, root), shown, msg))
    return out


def validation_error(
    err: ValidationError,
    source: str,
    *,
    noun: str = "config",
    root: str = "scenario",
    data: Any = None,
    model: type[BaseModel] | None = None,
) -> ConfigError:
    """A pydantic ``ValidationError`` as one :class:`ConfigError` line per problem: ``invalid <noun> <field
    path> = <value>: <what is allowed>``; ``root`` names the whole document when the problem has no field; ``data``
    is the document validated and ``model`` the model that validated it, for the keys allowed where a key is
    unknown (see :func:`validation_problems`)."""
    lines = [
        f"invalid {noun}: {msg}" if not field else f"invalid {noun} {field} = {shown}: {msg}"
        for field, shown, msg in validation_problems(err, root=root, data=data, model=model)
    ]
    return ConfigError(f"{source}: " + "; ".join(lines))
