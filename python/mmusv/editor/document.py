"""A scenario as the editor holds it: a compact JSON document, and its YAML file.

:func:`to_document` turns a validated :class:`~mmusv.config.Scenario` into the JSON object the page edits: the
keys a person writes by hand (name, seed, map, environment, acquisition, rigs, vessels with id, role, asset, rig,
speed and route) always, everything else only where it differs from its default, and each rig with the keys its
file gave and those that differ from its ``preset`` (a camera's quality where its file set it or where it is not the
rig's). Validating the document again gives a scenario equal to the original, which is why
"load, save unchanged" gives an equal scenario. :func:`scenario_yaml` writes it the way the bundled scenarios are
written (top-level blocks, one flow line per vessel), with the file's leading comment kept and its other comments
written back at their anchors (a key, a rig, a vessel by its id: :mod:`mmusv.editor.comments`). A text holding a line
break, a tab or a character outside printable Unicode (a rig named ``"a\\x85b"``) is written double-quoted with
escapes, so it reads back as written (PyYAML's default style would fold such a break into a space).
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from typing import Any

import yaml

from mmusv.config import Scenario, VesselConfig
from mmusv.editor.comments import Comment, place_comments
from mmusv.sensors.config import CameraConfig, RigConfig, TopViewConfig

__all__ = ["leading_comment", "scenario_file", "scenario_yaml", "to_document"]

_ALWAYS_VESSEL = ("id", "role", "asset", "speed_mps", "route")


def _rig_document(rig: RigConfig) -> dict[str, Any]:
    """The keys of ``rig`` its file gave or that differ from what its preset and its quality give (``{}`` for the
    paper's full suite); nested models (a LiDAR, each camera) only with their non-default keys. A key the file gave
    equal to its preset's (``radar: null`` under ``lidar_only``), or a camera's quality equal to the rig's, is kept: a
    later change of the preset or of the rig's quality in the page leaves it as the file set it."""
    base = RigConfig.model_validate({"preset": rig.preset, "quality": rig.quality}).model_dump(mode="json")
    given = rig.model_dump(mode="json", exclude_defaults=True)
    full = rig.model_dump(mode="json")
    out: dict[str, Any] = {"preset": rig.preset} if rig.preset != "full" or "preset" in rig.model_fields_set else {}
    if rig.quality is not None:
        out["quality"] = rig.quality
    for key, value in full.items():
        if key in ("preset", "quality"):
            continue
        if value != base[key] or key in rig.model_fields_set:  # e.g. a radar added back to a LiDAR-only rig
            out[key] = given.get(key, {} if isinstance(value, dict) else value)
    if rig.quality is not None:
        # Under a rig's quality a camera (or the top view) states its own where it differs from the rig's or where
        # its file set it: a camera's `standard`, the model's default, left out would read back as the rig's quality.
        cameras = out.get("cameras")
        if isinstance(cameras, list):
            for cam, doc in zip(rig.cameras, cameras, strict=True):
                _own_quality(doc, cam, rig.quality)
        if rig.top_view is not None and isinstance(out.get("top_view"), dict):
            _own_quality(out["top_view"], rig.top_view, rig.quality)
    return out


def _own_quality(doc: dict[str, Any], sensor: CameraConfig | TopViewConfig, rig_quality: str) -> None:
    """Writes a camera's or top view's quality into its ``doc`` when it is not the rig's or its file set it (else
    leaves it out: the rig's, passed down)."""
    if sensor.quality == rig_quality and "quality" not in sensor.model_fields_set:
        doc.pop("quality", None)
    else:
        doc["quality"] = sensor.quality


def _vessel_document(v: VesselConfig) -> dict[str, Any]:
    full = v.model_dump(mode="json")
    given = v.model_dump(mode="json", exclude_defaults=True)
    return {k: val for k, val in full.items() if k in _ALWAYS_VESSEL or k in given}


def to_document(scenario: Scenario) -> dict[str, Any]:
    """The editor's JSON document of ``scenario`` (see the module docstring); key order as in a hand-written file."""
    full = scenario.model_dump(mode="json")
    env_given = scenario.environment.model_dump(mode="json", exclude_defaults=True)
    env = {k: full["environment"][k] for k in ("time_of_day", "weather", "wave")}
    env.update({k: v for k, v in env_given.items() if k not in env})
    map_doc: dict[str, Any] = {"type": scenario.map.type, "seed": scenario.map.seed}
    params = scenario.map.param_values()
    if params:
        map_doc["params"] = params
    doc = {
        "name": scenario.name,
        "seed": scenario.seed,
        "map": map_doc,
        "environment": env,
        "acquisition": full["acquisition"],
        "rigs": {name: _rig_document(rig) for name, rig in scenario.rigs.items()},
    }
    if scenario.assets:  # the user's own vessels' files: saved as written (they were dropped on save)
        doc["assets"] = list(scenario.assets)
    doc["vessels"] = [_vessel_document(v) for v in scenario.vessels]
    return doc


class _Dumper(yaml.SafeDumper):
    """Block style for the top level and the ``rigs``/``vessels`` lists, flow style below."""


def _flow(dumper: yaml.SafeDumper, data: Any) -> yaml.Node:
    if isinstance(data, dict):
        return dumper.represent_mapping("tag:yaml.org,2002:map", data, flow_style=True)
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=True)


class _FlowMap(dict[str, Any]):
    pass


class _FlowList(list[Any]):
    pass


def _float(dumper: yaml.SafeDumper, data: float) -> yaml.Node:
    """Whole numbers without ``.0`` (waypoints read like hand-written ones); others as Python's shortest repr."""
    if data.is_integer() and abs(data) < 1e15:
        return dumper.represent_int(int(data))
    return dumper.represent_float(data)


_ESCAPE = re.compile("[^\x20-\x7e\xa0-\u2027\u202a-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")
"""A character that only a double-quoted YAML scalar keeps as it is: controls, line breaks (``\\x85``,
``\\u2028``, ``\\u2029`` included), tab, surrogates."""


def _str(dumper: yaml.SafeDumper, data: str) -> yaml.Node:
    """Texts as PyYAML writes them, but double-quoted (escaped) when they hold a character of :data:`_ESCAPE`."""
    style = '"' if _ESCAPE.search(data) else None
    return dumper.represent_scalar("tag:yaml.org,2002:str", data, style=style)


_Dumper.add_representer(str, _str)
_Dumper.add_representer(_FlowMap, _flow)
_Dumper.add_representer(_FlowList, _flow)
_Dumper.add_representer(float, _float)


def _flowed(value: Any) -> Any:
    if isinstance(value, dict):
        return _FlowMap({k: _flowed(v) for k, v in value.items()})
    if isinstance(value, list):
        return _FlowList([_flowed(v) for v in value])
    return value


def leading_comment(text: str) -> str:
    """The file's leading ``#`` comment block without the ``#`` marks (lines joined by newlines; empty if none)."""
    lines = []
    for line in text.removeprefix("\ufeff").splitlines():  # a byte-order mark is not the first line's text
        if not line.startswith("#"):
            break
        body = line[1:]
        lines.append(body[1:] if body.startswith(" ") else body)
    return "\n".join(lines)


def scenario_yaml(scenario: Scenario, *, comment: str = "", comments: Iterable[Comment] = ()) -> str:
    """The YAML text of ``scenario`` (its :func:`to_document`), ``comment`` as a leading ``#`` block and
    ``comments`` (:func:`mmusv.editor.comments.read_comments` of the file it came from) at their anchors."""
    return scenario_file(scenario, comment=comment, comments=comments)[0]


def scenario_file(
    scenario: Scenario, *, comment: str = "", comments: Iterable[Comment] = ()
) -> tuple[str, list[Comment]]:
    """:func:`scenario_yaml`'s text and the comments whose anchor is gone, which it wrote at the end of the file
    (:func:`mmusv.editor.comments.place_comments`)."""
    doc = to_document(scenario)
    top: dict[str, Any] = {}
    for key, value in doc.items():
        if key == "rigs":
            top[key] = {name: _flowed(rig) for name, rig in value.items()}
        elif key == "vessels":
            top[key] = [_flowed(v) for v in value]
        else:
            top[key] = _flowed(value)
    body = yaml.dump(top, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=120, indent=2)
    body, moved = place_comments(body, comments)
    head = "".join(f"# {line}".rstrip() + "\n" for line in comment.splitlines()) if comment.strip() else ""
    if body.startswith("#"):  # comments of the first key: a blank line keeps them out of the leading block
        head += "\n"
    return head + body, moved
