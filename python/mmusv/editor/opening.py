"""A scenario file's text opened in the editor: the page's document of a valid scenario (:func:`load_document`),
else the raw mapping, so that the page can list what is wrong, as long as the page can draw it (vessels and routes
as lists) and JSON can carry it.
"""

from __future__ import annotations

import contextlib
import json
from collections.abc import Collection
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mmusv.config import load_scenario
from mmusv.editor.carry import unjsonable
from mmusv.editor.document import to_document
from mmusv.errors import ConfigError, MmusvError
from mmusv.yamlio import parse_yaml

if TYPE_CHECKING:
    from mmusv.editor.evaluate import AssetScope

__all__ = ["load_document", "new_document"]


def load_document(
    text: str,
    where: str,
    *,
    folder: str | Path | None = None,
    also: Collection[Path] = (),
    scope: AssetScope | None = None,
) -> tuple[dict[str, Any], bool]:
    """``(document, valid)`` of a scenario file's text: the editor's document of a valid scenario, else the raw
    mapping (the page then lists what is wrong); :class:`ConfigError` when it is not a YAML mapping. ``folder``: the
    file's folder, where the asset files of its ``assets:`` are read (:func:`mmusv.editor.evaluate.register_assets`;
    without it, relative to the current folder, as :func:`mmusv.config.load_scenario` reads a mapping's). ``scope``:
    the editor server's user assets, held for this scenario while it is read (:class:`~.evaluate.AssetScope`)."""
    data = parse_yaml(text, where)
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: a scenario must be a YAML mapping with at least `vessels:`")
    with scope.use(data) if scope is not None else contextlib.nullcontext():
        if folder is not None and data.get("assets"):
            from mmusv.editor.evaluate import validate

            scenario, errors = validate(data, folder=folder, also=also)
            if scenario is not None:
                return to_document(scenario), True
            return _raw(data, where, f"{where}: " + "; ".join(e["message"] for e in errors)), False
        try:
            return to_document(load_scenario(data)), True
        except MmusvError as exc:
            return _raw(data, where, str(exc)), False


def new_document(name: str) -> dict[str, Any]:
    """The document of a new scenario called ``name``: the schema's defaults (map, environment, acquisition) and no
    vessels yet, which the page lists as the one thing to fix (``vessels``: at least 1 entry)."""
    placeholder = {"id": "v", "role": "usv", "asset": "usv_wamv", "route": [[0, 0], [10, 0]]}
    document = to_document(load_scenario({"name": name, "vessels": [placeholder]}))
    document["vessels"] = []
    return document


def _raw(data: dict[str, Any], where: str, problem: str) -> dict[str, Any]:
    """The mapping of a file that does not validate (``problem`` says why), as the page gets it to be fixed;
    :class:`ConfigError` when the page could not show it."""
    if not _editable(data):  # the page could not show it: say what is wrong instead
        raise ConfigError(
            f"{problem}; the editor opens files whose sections are mappings, each rig too, and whose vessels and "
            "routes are lists (fix it as text)"
        )
    raw: dict[str, Any] = json.loads(json.dumps(data, default=str))
    unjson = unjsonable(raw, "")
    if unjson is not None:  # JSON cannot carry it to the page
        raise ConfigError(f"{where}: {unjson}; the editor cannot show this value (fix it as text)")
    return raw


def _editable(data: dict[str, Any]) -> bool:
    """Whether an invalid scenario mapping still has the shape the page draws: sections are mappings, each rig too
    (``usv_standard:`` with nothing after it, a rig of ``null``, opened and broke the page's rig panel: "Cannot read
    properties of null"), ``vessels`` a list of mappings whose ``route`` is a list of ``[x, y]`` numbers."""
    if any(k in data and not isinstance(data[k], dict) for k in ("map", "environment", "acquisition", "rigs")):
        return False
    if not all(isinstance(rig, dict) for rig in (data.get("rigs") or {}).values()):
        return False
    vessels = data.get("vessels", [])
    if not isinstance(vessels, list) or not all(isinstance(v, dict) for v in vessels):
        return False
    for v in vessels:
        route = v.get("route", [])
        if not isinstance(route, list):
            return False
        for p in route:
            if not (isinstance(p, list) and len(p) == 2 and all(isinstance(c, (int, float)) for c in p)):
                return False
    return True
