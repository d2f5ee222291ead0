"""JSON Schemas of the files a user writes, for editors: :func:`json_schema` (``mmusv schema scenario|spec``).

The YAML language server (VS Code's YAML extension and others) validates and completes a file against the schema
named in its first line::

    # yaml-language-server: $schema=./scenario.schema.json

The schemas come from the pydantic models (:class:`mmusv.config.Scenario`,
:class:`mmusv.generate.spec.GenerationSpec`), widened where the loader reads more than the models' own schema says,
so that every file the loader accepts is valid under its schema (an editor never marks a good file), while unknown
keys and values of the wrong type are still marked:

- numbers may be written as quoted strings (``frames: "100"``), booleans as ``0``/``1`` or ``yes``/``off``/...
  (pydantic's lax mode reads them; a boolean for a number stays an error, as in the loader);
- strings of the scenario's models are stripped before their pattern is checked (``id: " usv_1 "``);
- ``map.params`` may be ``null`` and holds the parameters of the map's ``type`` (``island`` when none is given);
- a difficulty's ``extra_targets`` is ``n`` or ``[lo, hi]``; a combination's ``family`` one of the families;
- a spec's ``environment`` takes each scenario environment key, with one value or a list to draw from, and its
  default rig ``usv_standard`` is checked as a scenario's rig;
- a scenario's rig names (``rigs:`` keys) follow :data:`mmusv.config.RIG_NAME`;
- the bounds the loader's validators check on single fields are added: ``time_of_day`` as ``"HH:MM"``, ``wave`` a
  preset or 0..25 m, waypoints within :data:`mmusv.config.MAX_COORDINATE_M`, image sizes in 1..16384, the
  vertical fans within (-90, 90) degrees, a difficulty's ``range_m``; and a scenario environment's rules among
  its own keys (a ``sea`` with ``wave: W0`` and ``motion: physical`` only, rain under a sky that rains).

The loader stays the authority: checks across fields (a vessel's ``rig`` defined under ``rigs``, unique ids, mount
points of the asset, the sea's steepness, asset names, ...) are not in the schema.
"""

from __future__ import annotations

import copy
import json
import re
import types
import typing
from typing import Any, Literal

from pydantic import BaseModel
from pydantic.types import Strict

__all__ = ["KINDS", "json_schema", "schema_text"]

KINDS = ("scenario", "spec")
"""The kinds of file :func:`json_schema` describes."""

DIALECT = "https://json-schema.org/draft/2020-12/schema"

_INTEGER_TEXT = r"^\s*[+-]?[0-9](_?[0-9])*(\.0*)?\s*$"
"""An integer as pydantic's lax mode reads it from a string: ``"100"``, ``" +3 "``, ``"1_000"``, ``"10.0"``."""
_NUMBER_TEXT = r"^\s*[+-]?([0-9](_?[0-9])*(\.([0-9](_?[0-9])*)?)?|\.[0-9](_?[0-9])*)([eE][+-]?[0-9]+)?\s*$"
"""A finite number as pydantic's lax mode reads it from a string: ``"5"``, ``"2.5"``, ``".5"``, ``"1e3"``."""
_TIME_TEXT = r"^\s*(?:[01]?[0-9]|2[0-3]):[0-5][0-9]\s*$"
"""A time of day as the loader reads it: 24-hour ``"H:MM"`` or ``"HH:MM"``, surrounding spaces stripped."""
_BOOLEAN_TEXT = r"^(?i:true|false|yes|no|on|off|t|f|y|n|1|0)$"
"""A boolean as pydantic's lax mode reads it from a string (any case)."""

_EXTRA_DEFS: dict[str, dict[str, Any]] = {
    "IntegerText": {
        "type": "string",
        "pattern": _INTEGER_TEXT,
        "description": "A whole number written as a string (quoted), which the loader reads as the number.",
    },
    "NumberText": {
        "type": "string",
        "pattern": _NUMBER_TEXT,
        "description": "A number written as a string (quoted), which the loader reads as the number.",
    },
    "BooleanLike": {
        "anyOf": [{"enum": [0, 1]}, {"type": "string", "pattern": _BOOLEAN_TEXT}],
        "description": "A boolean written as 0/1 or as a word (yes/no, on/off, t/f, y/n), which the loader reads.",
    },
}
_META = ("title", "description", "default", "examples")


def json_schema(kind: Literal["scenario", "spec"]) -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a scenario file (``"scenario"``) or a generation spec (``"spec"``); a
    fresh dict on every call. :class:`ValueError` for another ``kind``."""
    if kind == "scenario":
        return copy.deepcopy(_scenario())
    if kind == "spec":
        return copy.deepcopy(_spec())
    raise ValueError(f"unknown schema kind {kind!r}; one of {', '.join(KINDS)}")


def schema_text(kind: Literal["scenario", "spec"]) -> str:
    """:func:`json_schema` as text: indent 2, sorted keys, a final newline (the same bytes on every call)."""
    return json.dumps(json_schema(kind), indent=2, sort_keys=True, ensure_ascii=False) + "\n"


# ------------------------------------------------------------------------------------------------ the two kinds


def _scenario() -> dict[str, Any]:
    from mmusv.config import RIG_NAME, Scenario

    doc = _widened(Scenario)
    doc["properties"]["rigs"]["propertyNames"] = {"pattern": f"^{RIG_NAME.pattern}$"}  # checked before stripping
    _map_params_by_type(doc)
    _field_bounds(doc)
    _environment_rules(doc["$defs"]["EnvironmentConfig"])
    return _finished(
        doc,
        title="mmusv scenario",
        description=(
            "A scenario file of mmusv, the maritime multi-USV simulator: map, environment, acquisition, sensor rigs "
            "and vessels. Generated by `mmusv schema scenario`. The loader (mmusv.config.load_scenario, `mmusv run`) "
            "stays the authority: checks across fields (a vessel's rig defined under rigs, unique vessel ids, mount "
            "points and asset names, the sea's steepness, ...) are not expressed here."
        ),
    )


def _spec() -> dict[str, Any]:
    from mmusv.config import SCENARIO_NAME, EnvironmentConfig
    from mmusv.generate.families import FAMILIES
    from mmusv.generate.spec_models import GenerationSpec
    from mmusv.sensors.config import RigConfig

    raw = GenerationSpec.model_json_schema()
    raw["properties"]["name"]["pattern"] = f"^{SCENARIO_NAME}$"  # GenerationSpec._name checks it in a validator
    doc = _widened(GenerationSpec, raw)
    for model in (EnvironmentConfig, RigConfig):  # what the loader checks the free-form mappings against
        sub = _widened(model)
        defs = sub.pop("$defs", {})
        defs[model.__name__] = sub
        for name, d in defs.items():
            assert doc["$defs"].setdefault(name, d) == d, name  # the same model, the same schema
    _map_params_by_type(doc)
    _field_bounds(doc)
    from mmusv.generate.spec_models import MAX_RANGE_M

    for item in doc["$defs"]["Difficulty"]["properties"]["range_m"]["prefixItems"]:
        _bound(item, minimum=0, maximum=MAX_RANGE_M)

    family = doc["$defs"]["Combination"]["properties"]["family"]
    names = sorted(FAMILIES)
    family["anyOf"] = [{"enum": names}, {"pattern": rf"^\s*(?:{'|'.join(map(re.escape, names))})\s*$"}]

    difficulty = doc["$defs"]["Difficulty"]["properties"]
    pair = difficulty["extra_targets"]
    for item in pair["prefixItems"]:
        item["anyOf"][0].update(minimum=0, maximum=16)
    difficulty["extra_targets"] = {
        "anyOf": [{"type": "integer", "minimum": 0, "maximum": 16}, {k: v for k, v in pair.items() if k not in _META}],
        "description": "Extra (distractor) targets: n, or [low, high] with 0 <= low <= high <= 16.",
        **{k: v for k, v in pair.items() if k in ("title", "default")},
    }

    env = doc["$defs"]["EnvironmentConfig"]
    doc["properties"]["environment"] = {
        "title": "Environment",
        "description": (
            "Scenario environment keys; a list means one value drawn per scenario (a rain_mm_per_h drawn with a "
            "clear sky is left out; a rate above 0 needs a weather that rains among the choices). Give `wave` or "
            "`sea`, not both."
        ),
        "type": "object",
        "additionalProperties": False,
        "properties": {
            key: {
                "anyOf": [_bare(p), {"type": "array", "items": _bare(p), "minItems": 1}],
                **{k: v for k, v in p.items() if k in ("title", "description")},
            }
            for key, p in env["properties"].items()
        },
        "not": {"required": ["sea", "wave"]},
    }
    del doc["$defs"]["EnvironmentConfig"]
    # Only the rig the spec's `rig` names is loaded (as a scenario's rig): the default one is known by name.
    doc["allOf"] = [
        {
            "if": {"properties": {"rig": {"const": "usv_standard"}}},
            "then": {"properties": {"rigs": {"properties": {"usv_standard": {"$ref": "#/$defs/RigConfig"}}}}},
        }
    ]
    doc["properties"]["rigs"]["description"] = (
        "Sensor rigs by name, as in a scenario; the one `rig` names is the rig every USV carries."
    )
    return _finished(
        doc,
        title="mmusv generation spec",
        description=(
            "A generation spec of mmusv, the maritime multi-USV simulator: a batch of scenarios to generate under "
            "constraints (`mmusv generate`). Generated by `mmusv schema spec`. The loader "
            "(mmusv.generate.spec.load_spec) stays the authority: checks across fields (difficulties and size "
            "classes a combination names, a family's map type, contradicting constraints, the rig in use, ...) are "
            "not expressed here."
        ),
    )


def _finished(doc: dict[str, Any], *, title: str, description: str) -> dict[str, Any]:
    """``doc`` with the dialect, ``title`` and ``description``, the extra definitions it uses and no unused one."""
    doc["$defs"] = {**doc.get("$defs", {}), **copy.deepcopy(_EXTRA_DEFS)}
    used: set[str] = set()
    todo: list[Any] = [{k: v for k, v in doc.items() if k != "$defs"}]
    while todo:
        node = todo.pop()
        if isinstance(node, dict):
            ref = node.get("$ref")
            if isinstance(ref, str) and ref.startswith("#/$defs/") and ref[8:] not in used:
                used.add(ref[8:])
                todo.append(doc["$defs"][ref[8:]])
            todo.extend(node.values())
        elif isinstance(node, list):
            todo.extend(node)
    doc["$defs"] = {k: v for k, v in sorted(doc["$defs"].items()) if k in used}
    doc.update({"$schema": DIALECT, "title": title, "description": description})
    return doc


# ------------------------------------------------------------------------------------------------ widening


def _widened(root: type[BaseModel], raw: dict[str, Any] | None = None) -> dict[str, Any]:
    """``root``'s schema (``raw``, else its ``model_json_schema()``), each model's fields widened to what the loader
    reads (module docs): numbers and booleans as text, stripped strings' patterns."""
    doc = raw if raw is not None else root.model_json_schema()
    models = _models(root)
    _widen_model(doc, root)
    for name, d in doc.get("$defs", {}).items():
        if name in models:
            _widen_model(d, models[name])
    return doc


def _widen_model(d: dict[str, Any], model: type[BaseModel]) -> None:
    stripped = bool(model.model_config.get("str_strip_whitespace"))
    lax = not model.model_config.get("strict")
    for name, prop in d.get("properties", {}).items():
        field = model.model_fields.get(name)
        strict = field is not None and any(isinstance(m, Strict) and m.strict for m in field.metadata)
        d["properties"][name] = _widen(prop, lax=lax and not strict, stripped=stripped)


def _widen(node: Any, *, lax: bool, stripped: bool) -> Any:
    """``node`` (a field's schema, not following ``$ref``) widened (see :func:`_widened`)."""
    if isinstance(node, list):
        return [_widen(n, lax=lax, stripped=stripped) for n in node]
    if not isinstance(node, dict) or "$ref" in node:
        return node
    node = {
        k: _widen(v, lax=lax, stripped=stripped)
        if k in ("anyOf", "items", "prefixItems", "additionalProperties")
        else v
        for k, v in node.items()
    }
    kind = node.get("type")
    if kind == "string" and stripped and "pattern" in node:
        inner = node["pattern"].removeprefix("^").removesuffix("$")
        node["pattern"] = rf"^\s*(?:{inner})\s*$"
        node.pop("maxLength", None)  # counted after stripping
    alt = {"integer": "IntegerText", "number": "NumberText", "boolean": "BooleanLike"}.get(kind) if lax else None
    if alt is None:
        return node
    meta = {k: v for k, v in node.items() if k in _META}
    return {"anyOf": [_bare(node), {"$ref": f"#/$defs/{alt}"}], **meta}


def _bare(node: dict[str, Any]) -> dict[str, Any]:
    """``node`` without its annotations (title, description, default)."""
    return {k: v for k, v in node.items() if k not in _META}


def _models(root: type[BaseModel]) -> dict[str, type[BaseModel]]:
    """Every model reachable from ``root``'s fields, by class name (the names of pydantic's ``$defs``)."""
    out: dict[str, type[BaseModel]] = {}
    todo: list[Any] = [root]
    while todo:
        tp = todo.pop()
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            if tp.__name__ in out:
                continue
            out[tp.__name__] = tp
            todo.extend(f.annotation for f in tp.model_fields.values())
        elif typing.get_origin(tp) is not None or isinstance(tp, types.UnionType):
            todo.extend(typing.get_args(tp))
    return out


# ------------------------------------------------------------------------------------------------ field bounds


def _bound(node: dict[str, Any], **limits: float) -> None:
    """``limits`` (``minimum``, ``exclusiveMaximum``, ...) on the number of ``node``: the node itself, or its
    number branch beside the quoted text the loader also reads (a quoted number stays unchecked: never marked)."""
    if node.get("type") in ("number", "integer"):
        node.update(limits)
    for branch in node.get("anyOf", []):
        _bound(branch, **limits)


def _field_bounds(doc: dict[str, Any]) -> None:
    """The bounds of single fields that the loader checks in its validators (the models' own schema leaves them
    out): the time of day and the wave setting, waypoints within ``MAX_COORDINATE_M`` of the origin, image sizes
    in 1..16384 pixels and the LiDAR's and radar's vertical fans strictly within (-90, 90) degrees."""
    from mmusv.config import MAX_COORDINATE_M
    from mmusv.world.environment import MAX_WAVE_HEIGHT_M, WAVE_PRESETS

    defs = doc["$defs"]
    env = defs["EnvironmentConfig"]["properties"]
    env["time_of_day"] = {
        **{k: v for k, v in env["time_of_day"].items() if k in _META},
        "type": "string",
        "pattern": _TIME_TEXT,
        "description": 'Local solar time, 24-hour "HH:MM" in quotes (unquoted, YAML reads 13:00 as a number).',
    }
    presets = "|".join(
        "".join(f"[{c.lower()}{c.upper()}]" if c.isalpha() else re.escape(c) for c in name) for name in WAVE_PRESETS
    )
    env["wave"] = {
        **{k: v for k, v in env["wave"].items() if k in _META},
        "anyOf": [
            {"type": "string", "pattern": rf"^\s*(?:{presets})\s*$"},
            {"type": "number", "minimum": 0, "maximum": MAX_WAVE_HEIGHT_M},
        ],
        "description": (
            f"A wave preset ({', '.join(WAVE_PRESETS)}) or the significant wave height in metres "
            f"(0..{MAX_WAVE_HEIGHT_M:g})."
        ),
    }
    if "VesselConfig" in defs:
        for item in defs["VesselConfig"]["properties"]["route"]["items"]["prefixItems"]:
            _bound(item, minimum=-MAX_COORDINATE_M, maximum=MAX_COORDINATE_M)
    for name in ("CameraConfig", "TopViewConfig"):
        for item in defs[name]["properties"]["resolution"]["prefixItems"]:
            _bound(item, minimum=1, maximum=16384)
    for name, key in (("LidarConfig", "vertical_fov_deg"), ("RadarConfig", "elevation_fan_deg")):
        for item in defs[name]["properties"][key]["prefixItems"]:
            _bound(item, exclusiveMinimum=-90, exclusiveMaximum=90)


def _environment_rules(env: dict[str, Any]) -> None:
    """A scenario environment's rules across its own keys, as :class:`mmusv.config.EnvironmentConfig` checks
    them: a ``sea`` goes with ``wave: W0`` (or none) and ``motion: physical``; rain needs a sky that rains."""
    env["allOf"] = [
        {
            "if": {"properties": {"sea": {"type": "object"}}, "required": ["sea"]},
            "then": {
                "properties": {
                    "wave": {"type": "string", "pattern": r"^\s*[wW]0\s*$"},
                    "motion": {"not": {"const": "paper"}},
                }
            },
        },
        {
            "if": {
                "properties": {"rain_mm_per_h": {"type": "number", "exclusiveMinimum": 0}},
                "required": ["rain_mm_per_h"],
            },
            "then": {"required": ["weather"], "properties": {"weather": {"not": {"const": "clear"}}}},
        },
    ]


# ------------------------------------------------------------------------------------------------ map params


def _map_params_by_type(doc: dict[str, Any]) -> None:
    """``MapConfig.params``: ``null`` or the parameters of the map's ``type`` (island when ``type`` is left out),
    as :meth:`mmusv.config.MapConfig._params_of_type` reads them."""
    from mmusv.world.map_params import PARAM_MODELS

    mc = doc["$defs"]["MapConfig"]
    params = mc["properties"]["params"]
    params["anyOf"] = [*params["anyOf"], {"type": "null"}]
    params["description"] = "The map's parameters: those of its `type` (null: the defaults)."
    mc["allOf"] = [
        {
            "if": {"properties": {"type": {"const": kind}}, **({} if kind == "island" else {"required": ["type"]})},
            "then": {"properties": {"params": {"anyOf": [{"$ref": f"#/$defs/{m.__name__}"}, {"type": "null"}]}}},
        }
        for kind, m in sorted(PARAM_MODELS.items())
    ]
