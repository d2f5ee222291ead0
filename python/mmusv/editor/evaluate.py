"""Live validation and motion of the document the editor holds: what the page draws and lists after every edit.

:func:`evaluate` validates the document with the scenario schema (:mod:`mmusv.config`), builds the fleet with the
Rust kinematics (:func:`mmusv.motion.build_fleet`; route geometry errors such as repeated waypoints surface here)
and runs the named checks on the map (:func:`mmusv.scenario_checks.map_findings`, the generator's checks, and
:func:`mmusv.scenario_checks.top_view_land`: a top view lower than the land within its view, the error ``top_view``
that ``mmusv run`` refuses). It returns, JSON-ready:

* ``errors``: schema and route problems, each ``{field, message, vessel}``: ``field`` is the path in the scenario
  (``vessels[2].speed_mps``), ``vessel`` the id of the vessel it belongs to (or None);
* ``problems``: check failures, each ``{check, severity, message, field, vessels, point, segments}``:
  ``segments`` maps a vessel id to ``[first, last]`` index ranges of its ``path`` samples that fail (clearance
  checks: the red part of a route), ``point`` the world ``[x, y]`` where it happens;
* ``vessels``: per scenario vessel ``{id, role, asset, length, beam, path, poses, rings}``: ``path`` the spline
  sampled along its whole length as the simulator sails it (the route samples the checks test), ``poses`` ``[x,
  y, yaw]`` at every acquisition index (None above :data:`MAX_BULK_FRAMES` frames: ask :func:`poses_at`),
  ``rings`` the LiDAR and radar ranges of a USV's rig (metres);
* ``valid`` (the schema and the routes are fine; problems may remain), ``frames``, ``frequency_hz``, ``map``.

Bounds (:func:`mmusv.generate.samples.budget_problem`, the ones ``mmusv run`` checks): the checks take at most
``MAX_CHECK_SAMPLES`` samples x vessels and ``MAX_CHECK_PAIR_SAMPLES`` time samples x pairs of vessels (the
separation check compares every pair at every time: without this bound a fleet of a few thousand vessels, a body
of a few hundred kB, would take minutes); above either the document is not valid and ``errors`` says why, at the
field ``acquisition`` when the samples in time set the count (frames and frequency), else ``vessels``. At most
:data:`MAX_PROBLEMS` problems are listed; one more entry (check ``more``) then says how many were left out.

World frame, metres, radians (yaw from +x, counter-clockwise); coordinates rounded to millimetres.
"""

from __future__ import annotations

import contextlib
import re
import threading
import warnings
from collections.abc import Collection, Iterator
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import ValidationError

from mmusv.config import Scenario, validation_problems
from mmusv.errors import ConfigError, MmusvError
from mmusv.generate.mapctx import map_context
from mmusv.generate.samples import FEWER_TIMES, MAX_CHECK_SAMPLES, budget_problem, sample_counts
from mmusv.motion import build_fleet
from mmusv.scenario_checks import (
    check_mounts,
    check_rain_visibility,
    check_sensors,
    map_check_spec,
    map_findings,
    top_view_land,
)
from mmusv.sensors.config import RigConfig
from mmusv.text import counted
from mmusv.world.vessels import get_asset

__all__ = [
    "MAX_BULK_FRAMES",
    "MAX_PROBLEMS",
    "AssetScope",
    "evaluate",
    "poses_at",
    "register_assets",
    "validate",
]

MAX_BULK_FRAMES = 3000
"""Above this many frames the evaluation leaves the per-frame poses out; the page asks for one index at a time."""
MAX_PROBLEMS = 1000
"""Most problems listed; the rest are counted in one last entry."""

_FIELD = re.compile(r"invalid config (\S+) = ")
_VESSEL_FIELD = re.compile(r"^vessels\[(\d+)\]")


def _vessel_of(field: str, document: dict[str, Any]) -> str | None:
    m = _VESSEL_FIELD.match(field)
    vessels = document.get("vessels")
    if m is None or not isinstance(vessels, list) or int(m.group(1)) >= len(vessels):
        return None
    v = vessels[int(m.group(1))]
    vid = v.get("id") if isinstance(v, dict) else None
    return vid if isinstance(vid, str) else None


def _error(field: str, message: str, document: dict[str, Any]) -> dict[str, Any]:
    return {"field": field, "message": message, "vessel": _vessel_of(field, document)}


class AssetScope:
    """The user assets one editor server's requests see: those of the asset files the scenario of the request lists
    (``assets:``), none of another scenario's. The vessel library is one per process, so two scenario files that
    each name an asset ``skiff`` in their own asset file clashed ("already in the library") when the second was
    opened, and a scenario that listed no asset file validated with another scenario's assets; now
    :meth:`use` takes the assets of other files out of the library first
    (:func:`mmusv.scenario_assets.keep_scenario_assets`, as :func:`mmusv.config.load_scenario` does for each
    scenario it reads; what a scope adds is the waiting of threads). Requests of scenarios listing the same asset
    files run together; one that lists others waits until they have ended (they hold the assets while they build,
    check or render the scenario)."""

    def __init__(self, folder: str | Path) -> None:
        self._root = Path(folder).resolve()
        self._cond = threading.Condition()
        self._key: frozenset[Path] | None = None
        self._users = 0

    def key(self, data: Any) -> frozenset[Path]:
        """The resolved asset files a scenario mapping ``data`` lists (its ``assets:`` entries that are paths)."""
        from mmusv.scenario_assets import asset_files

        return asset_files(data.get("assets") if isinstance(data, dict) else None, self._root)

    @contextlib.contextmanager
    def use(self, data: Any) -> Iterator[None]:
        """Holds the library for the scenario mapping ``data`` (its asset files' assets, and no others'), while the
        block reads, checks or renders it."""
        from mmusv.scenario_assets import keep_scenario_assets

        key = self.key(data)
        with self._cond:
            while self._users and self._key != key:
                self._cond.wait()
            if self._key != key:
                keep_scenario_assets(key)
                self._key = key
            self._users += 1
        try:
            yield
        finally:
            with self._cond:
                self._users -= 1
                self._cond.notify_all()


def register_assets(
    document: dict[str, Any], folder: str | Path, *, also: Collection[Path] = ()
) -> list[dict[str, Any]]:
    """Registers the asset files of ``document``'s ``assets:`` (the user's own vessels) from ``folder``, the editor's
    folder where its file lies, as ``mmusv run`` of that file does; the errors (``[]`` when none): a file outside
    the folder (never read: the editor reads nothing outside it; ``also``: resolved files outside it that may be read,
    those of the scenario named on the command line), or one that does not exist or holds no asset.
    Before, the editor never read them: a scenario of its own vessels did not validate ("unknown asset"), and could
    not be saved, unless the server's current folder happened to be the scenario's when the file was opened."""
    from mmusv.scenario_assets import asset_file_path, register_scenario_assets

    entries = document.get("assets")
    if not isinstance(entries, list) or not entries:
        return []
    root = Path(folder).resolve()
    for i, entry in enumerate(entries):
        if not isinstance(entry, str) or not entry.strip():
            continue  # said by register_scenario_assets below
        field = f"assets[{i}]"
        try:
            path = asset_file_path(root, entry)
        except ValueError as exc:  # was an internal error
            return [_error(field, f"{field} = {entry!r:.80}: {exc}; give the path of an asset YAML file", document)]
        if root not in path.parents and path not in also:
            field = f"assets[{i}]"
            return [
                _error(
                    field,
                    f"{field} = {entry!r}: {path} is outside the editor's folder {root}; the editor reads asset files "
                    "in its folder only: give a path under it, relative to the folder, or start the editor on a "
                    "--dir that holds both",
                    document,
                )
            ]
    try:
        register_scenario_assets(entries, base_dir=root, where="scenario")
    except ConfigError as exc:
        message = str(exc).removeprefix("scenario: invalid scenario ")
        m = re.match(r"assets\[\d+\]", message)
        return [_error(m.group(0) if m else "assets", message, document)]
    return []


def validate(
    document: dict[str, Any], *, folder: str | Path | None = None, also: Collection[Path] = ()
) -> tuple[Scenario | None, list[dict[str, Any]]]:
    """The scenario of ``document`` (None when invalid) and its schema and route errors (see module docstring);
    with ``folder``, the asset files of its ``assets:`` are read from there first (:func:`register_assets`)."""
    if folder is not None:
        asset_errors = register_assets(document, folder, also=also)
        if asset_errors:
            return None, asset_errors
    try:
        scenario = Scenario.model_validate(document)
    except ValidationError as exc:
        return None, [
            _error(f, f"{f or 'scenario'} = {shown}: {msg}" if f else msg, document)
            for f, shown, msg in validation_problems(exc)
        ]
    except MmusvError as exc:
        m = _FIELD.search(str(exc))
        return None, [_error(m.group(1) if m else "", str(exc), document)]
    try:
        build_fleet(scenario)
    except MmusvError as exc:
        m = _FIELD.search(str(exc))
        return None, [_error(m.group(1) if m else "vessels", str(exc).removeprefix("invalid config "), document)]
    return scenario, []


def _runs(mask: np.ndarray) -> list[list[int]]:
    """``[first, last]`` index ranges of the True runs of a bool ``mask``."""
    idx = np.flatnonzero(mask)
    if idx.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(idx) > 1)
    starts = np.concatenate([[idx[0]], idx[breaks + 1]])
    ends = np.concatenate([idx[breaks], [idx[-1]]])
    return [[int(a), int(b)] for a, b in zip(starts, ends, strict=True)]


def _rings(scenario: Scenario, rig: str | None) -> dict[str, float | None]:
    r = scenario.rigs[rig] if rig is not None else RigConfig()
    return {
        "lidar": r.lidar.range_m if r.lidar is not None else None,
        "radar": r.radar.range_m if r.radar is not None else None,
    }


def _frame_poses(fleet: Any, scenario: Scenario, frames: np.ndarray) -> np.ndarray:
    """``(F, V, 3)`` ``[x, y, yaw]`` at acquisition indices ``frames`` (t = k / f), rounded."""
    eta = np.asarray(fleet.poses_at_times(frames.astype(np.float64) / scenario.acquisition.frequency_hz))
    out = eta[:, :, [0, 1, 5]]
    out[:, :, :2] = np.round(out[:, :, :2], 3)
    out[:, :, 2] = np.round(out[:, :, 2], 6)
    return out


def poses_at(scenario: Scenario, frame: int) -> list[list[float]]:
    """``[x, y, yaw]`` of every scenario vessel at acquisition index ``frame``."""
    if not 0 <= frame < scenario.acquisition.frames:
        raise ConfigError(f"frame {frame} is outside the acquisition (0..{scenario.acquisition.frames - 1})")
    return _frame_poses(build_fleet(scenario), scenario, np.array([frame]))[0].tolist()  # type: ignore[no-any-return]


def _budget_error(problem: str, n_motion: int, n_route: int, n_vessels: int) -> tuple[str, str]:
    """The field and message of a scenario too large to check (``problem``, from :func:`budget_problem`).

    When the samples in time set the count (the acquisition's frames and rate do, and every pair of vessels is
    compared at every time), the field is ``acquisition`` and the message names ``acquisition.frames`` and
    ``acquisition.frequency_hz``: the page shows it next to those two boxes, where the change that caused it was
    made. Otherwise the longest route sets the count: ``vessels``."""
    if n_motion >= n_route or max(n_motion, n_route) * n_vessels <= MAX_CHECK_SAMPLES:
        advice = f"{FEWER_TIMES}, lower the speeds or use fewer vessels"
        return "acquisition", f"{problem}: {advice}"
    return "vessels", f"{problem}: shorten the routes or use fewer vessels"


def evaluate(
    document: dict[str, Any], *, folder: str | Path | None = None, also: Collection[Path] = ()
) -> dict[str, Any]:
    """Validates ``document`` (its asset files read from ``folder``: :func:`validate`) and, when valid, samples its
    motion and runs the named checks (module docstring)."""
    out: dict[str, Any] = {"valid": False, "errors": [], "problems": [], "vessels": [], "frames": None}
    scenario, errors = validate(document, folder=folder, also=also)
    if scenario is None:
        out["errors"] = errors
        return out
    acq = scenario.acquisition
    out.update(frames=acq.frames, frequency_hz=acq.frequency_hz, valid=True)
    out["map"] = {"type": scenario.map.type, "seed": scenario.map.seed, "params": scenario.map.param_values()}
    spec = map_check_spec(scenario)
    n_motion, n_route = sample_counts(scenario, spec)
    problem = budget_problem(scenario, n_motion=n_motion, n_route=n_route)  # the bounds `mmusv run` checks
    if problem is not None:
        out["valid"] = False
        out["errors"] = [_error(*_budget_error(problem, n_motion, n_route, len(scenario.vessels)), document)]
        return out
    ctx = map_context(scenario.map.type, seed=scenario.map.seed, params=scenario.map.param_values())
    samples, findings = map_findings(scenario, ctx, spec)
    index = {v.id: i for i, v in enumerate(scenario.vessels)}
    for mf in findings:
        f = mf.finding
        first = index[f.vessels[0]] if f.vessels else None
        field = f"vessels[{first}]" if first is not None else ""
        if mf.check in ("in_water", "shore_clearance", "structure_clearance", "under_keel"):
            field += ".route"
        out["problems"].append(
            {
                "check": mf.check,
                "severity": mf.severity,
                "message": f.message,
                "field": field,
                "vessels": list(f.vessels),
                "point": None if f.point is None else [round(f.point[0], 2), round(f.point[1], 2)],
                "segments": {vid: _runs(mask) for vid, mask in sorted(f.route.items())},
            }
        )
    # A top view lower than the land within its view (mmusv run refuses it): from the frames' and the motion's samples.
    usv_rows = {index[vid]: j for j, vid in enumerate(samples.ids) if scenario.vessels[index[vid]].role == "usv"}
    seen_from = {i: np.concatenate([samples.frames[:, j], samples.motion[:, j]]) for i, j in usv_rows.items()}
    for tl in top_view_land(scenario, ctx.world, seen_from):
        out["problems"].append(
            {
                "check": "top_view",
                "severity": "error",
                "message": tl.message,
                "field": tl.field if tl.field.startswith("rigs.") else f"vessels[{tl.index}].rig",
                "vessels": [scenario.vessels[tl.index].id],
                "point": [round(tl.point[0], 2), round(tl.point[1], 2)],
                "segments": {},
            }
        )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mounts = check_mounts(scenario, source="scenario")
        sensors = check_sensors(scenario, source="scenario")
        rain = check_rain_visibility(scenario, source="scenario")
    said = [("mounts", m) for m in mounts] + [("sensors", m) for m in sensors] + [("rain", m) for m in rain]
    for check, msg in said:
        text = msg.removeprefix("scenario: ")
        field = text.split(" ", 1)[0].rstrip(",")
        out["problems"].append(
            {
                "check": check,
                "severity": "warning",
                "message": text,
                "field": field if field.startswith(("rigs.", "environment.")) else "vessels",
                "vessels": [],
                "point": None,
                "segments": {},
            }
        )
    if len(out["problems"]) > MAX_PROBLEMS:
        left = out["problems"][MAX_PROBLEMS:]
        n_err = sum(1 for p in left if p["severity"] == "error")
        out["problems"] = out["problems"][:MAX_PROBLEMS]
        out["problems"].append(
            {
                "check": "more",
                "severity": "error" if n_err else "warning",
                "message": f"{counted(len(left), 'more problem', fmt=',')} "
                f"({counted(n_err, 'error', fmt=',')}, "
                f"{counted(len(left) - n_err, 'warning', fmt=',')}) {'is' if len(left) == 1 else 'are'} "
                f"not listed; the editor lists at most {MAX_PROBLEMS:,}",
                "field": "",
                "vessels": [],
                "point": None,
                "segments": {},
            }
        )
    fleet = build_fleet(scenario)
    poses = _frame_poses(fleet, scenario, np.arange(acq.frames)) if acq.frames <= MAX_BULK_FRAMES else None
    geo = np.round(samples.geo, 3)
    for i, v in enumerate(scenario.vessels):
        a = get_asset(v.asset)
        out["vessels"].append(
            {
                "id": v.id,
                "role": v.role,
                "asset": v.asset,
                "length": a.length,
                "beam": a.beam,
                "path": geo[:, i].tolist(),
                "poses": None if poses is None else poses[:, i].tolist(),
                "rings": _rings(scenario, v.rig) if v.role == "usv" else None,
            }
        )
    return out
