"""The reject-and-resample loop: fill every combination's quota or stop at its attempt cap, write the accepted
scenarios and ``report.json``.

Per combination ``i`` (in spec order) attempts ``0, 1, ...`` are drawn by :func:`sample_candidate` from
``(spec.seed, i, attempt)`` and checked by the enabled constraints; an accepted candidate is written as
``<combination>_<NNN>.yaml`` (``NNN`` = its rank among the combination's accepted scenarios), read back (YAML
safe loader, libyaml's when installed: the same resolver as ``yaml.safe_load``), validated with
:func:`mmusv.config.load_scenario` and compared with the checked scenario before it counts. The loop stops at the
quota or at ``max_attempts``, so it always ends; the same spec gives the same files byte for byte.
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import yaml

from mmusv.config import load_scenario
from mmusv.errors import ConfigError, IoError, MmusvError
from mmusv.generate.checks import Constraint, build_constraints, first_failure
from mmusv.generate.hulls import capsule
from mmusv.generate.layout import SamplingError
from mmusv.generate.mapctx import MapContext, map_context
from mmusv.generate.report import ComboReport, RunReport
from mmusv.generate.sampler import Candidate, sample_candidate
from mmusv.generate.samples import take_samples
from mmusv.generate.spec import GenerationSpec, class_assets, load_spec

__all__ = ["Progress", "dump_scenario", "generate"]

Progress = Callable[[str, int, int], None]
"""Called after every attempt with (combination name, accepted so far in total, attempts so far in total)."""


_RESERVED = {"y", "n", "yes", "no", "true", "false", "on", "off", "null"}
_PLAIN = re.compile(r"^[A-Za-z_][A-Za-z0-9_.\-]*$")
_LOADER: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def _scalar(x: Any) -> str:
    if x is None:
        return "null"
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, int):
        return str(x)
    if isinstance(x, float):
        if math.isnan(x):
            return ".nan"
        if math.isinf(x):
            return ".inf" if x > 0 else "-.inf"
        r = repr(x + 0.0)
        if "e" in r:  # YAML 1.1 floats need a dot in the mantissa: 1e-05 -> 1.0e-05
            mantissa, exp = r.split("e")
            r = f"{mantissa if '.' in mantissa else mantissa + '.0'}e{exp}"
        return r
    if isinstance(x, str):
        return x if _PLAIN.match(x) and x.lower() not in _RESERVED else json.dumps(x)
    raise TypeError(f"cannot write {type(x).__name__} into a scenario file")


def _flow(x: Any) -> str:
    if isinstance(x, dict):
        return "{" + ", ".join(f"{_scalar(k)}: {_flow(v)}" for k, v in x.items()) + "}"
    if isinstance(x, (list, tuple)):
        return "[" + ", ".join(_flow(v) for v in x) + "]"
    return _scalar(x)


def dump_scenario(data: dict[str, Any]) -> str:
    """The YAML text of a scenario dict: top-level keys in insertion order, one flow-style line per value and
    per vessel, floats as ``repr`` (already rounded), strings plain when unambiguous else double-quoted.
    Deterministic and independent of the YAML library; read back by any YAML 1.1/1.2 loader."""
    lines = []
    for key, value in data.items():
        if key == "vessels":
            lines.append("vessels:")
            lines += [f"  - {_flow(v)}" for v in value]
        else:
            lines.append(f"{_scalar(key)}: {_flow(value)}")
    return "\n".join(lines) + "\n"


def _prepare_dir(out: Path, force: bool, spec_path: Path | None = None) -> None:
    """Readies ``out``: with ``force``, removes the scenario files a previous run generated there (those its
    ``report.json`` lists) and that report; any other YAML file there (a hand-written scenario, the spec itself)
    is never deleted: the run refuses instead."""
    if out.exists() and not out.is_dir():
        raise IoError(f"output {str(out)!r} exists and is not a directory")
    if not out.is_dir():
        out.mkdir(parents=True, exist_ok=True)
        return
    yamls = sorted(out.glob("*.yaml"))
    report = out / "report.json"
    if not yamls and not report.is_file():
        return
    if not force:
        raise IoError(f"output directory {str(out)!r} already holds scenario files; pass --force to replace them")
    ours = _generated_here(report)
    foreign = [p for p in yamls if p.name not in ours or (spec_path is not None and _same_file(p, spec_path))]
    if foreign:
        names = ", ".join(p.name for p in foreign[:3]) + (" ..." if len(foreign) > 3 else "")
        raise IoError(
            f"output directory {str(out)!r} holds YAML files that no earlier generate run there wrote ({names}; "
            f"{'the spec itself, ' if spec_path is not None and any(_same_file(p, spec_path) for p in foreign) else ''}"
            "report.json lists what a run wrote); --force replaces only those: choose another folder or move them"
        )
    for p in yamls:
        p.unlink()
    report.unlink(missing_ok=True)


def _generated_here(report: Path) -> set[str]:
    """The scenario file names an earlier run's ``report.json`` lists (empty when there is none or it is not
    readable as one)."""
    try:
        data = json.loads(report.read_text(encoding="utf-8"))
        return {
            f
            for c in data.get("combinations", [])
            for f in c.get("files", [])
            if isinstance(f, str) and Path(f).name == f
        }
    except (OSError, ValueError, AttributeError, TypeError):
        return set()


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve()
    except OSError:
        return False


def _infeasible(spec: GenerationSpec, ctx: MapContext, idx: int) -> str | None:
    """A reason the combination can never pass the clearance checks (the slimmest asset of one of its target
    classes fits nowhere on the map), or None. Attempts still run (and are counted) so the report shows them."""
    combo = spec.combinations[idx]
    cons = spec.constraints
    need = max(
        cons.shore_clearance.min_m if cons.shore_clearance.enabled else 0.0,
        cons.structure_clearance.min_m if cons.structure_clearance.enabled else 0.0,
    )
    best = ctx.max_clearance()
    for cls in combo.targets:
        slimmest = min(class_assets(spec.size_classes[cls]), key=lambda a: capsule(a)[1])
        r = capsule(slimmest)[1]
        if r + need > best:
            return (
                f"infeasible: size class {cls!r} needs {r + need:.0f} m of clearance ({slimmest} hull half-width"
                f" {r:.0f} m + {need:g} m) and the most open water on this map offers {best:.0f} m"
            )
    return None


def _first_failure(
    constraints: list[Constraint], cand: Candidate, ctx: MapContext, spec: GenerationSpec
) -> tuple[str, str] | None:
    """The first failing constraint of a candidate, ``("sampling", why)`` when it has too many samples to check
    (:data:`~mmusv.generate.samples.MAX_CHECK_SAMPLES`), None when it passes."""
    try:
        samples = take_samples(cand.scenario, cand.meta, ctx, spec)
    except ConfigError as exc:
        return "sampling", str(exc)
    return first_failure(constraints, samples)


def generate(
    spec_source: GenerationSpec | str | os.PathLike[str] | dict[str, Any],
    out_dir: str | os.PathLike[str],
    *,
    force: bool = False,
    progress: Progress | None = None,
) -> RunReport:
    """Generates the scenarios of a spec into ``out_dir`` (created; refuses to overwrite earlier scenario files
    unless ``force``) and writes ``report.json`` there; returns the report."""
    spec = load_spec(spec_source)
    out = Path(out_dir)
    contexts = [map_context(m.type, m.seed, m.param_values()) for m in (spec.map_of(c) for c in spec.combinations)]
    constraints = build_constraints(spec)
    spec_path = Path(spec_source) if isinstance(spec_source, (str, os.PathLike)) else None
    _prepare_dir(out, force, spec_path)
    report = RunReport(
        spec_name=spec.name,
        seed=spec.seed,
        map={"type": spec.map.type, "seed": spec.map.seed, "params": spec.map.param_values()},
        constraints=[c.name for c in constraints],
    )
    total_attempts = 0
    for i, combo in enumerate(spec.combinations):
        ctx = contexts[i]
        rep = ComboReport(combo.label(), combo.family, combo.difficulty, combo.quota, spec.max_attempts(combo))
        rep.infeasible = _infeasible(spec, ctx, i)
        report.combos.append(rep)
        width = max(3, int(math.log10(combo.quota)) + 1)
        for attempt in range(rep.max_attempts):
            if rep.met:
                break
            name = f"{rep.name}_{rep.accepted:0{width}d}"
            total_attempts += 1
            try:
                cand = sample_candidate(spec, i, attempt, ctx, name)
            except SamplingError as exc:
                rep.reject("sampling", str(exc))
            except ConfigError as exc:
                rep.reject("schema", str(exc))
            else:
                fail = _first_failure(constraints, cand, ctx, spec)
                if fail is not None:
                    rep.reject(*fail)
                else:
                    path = out / f"{name}.yaml"
                    tmp = path.with_name(f".{path.name}.tmp")  # renamed into place: a stop never leaves half a file
                    tmp.write_text(dump_scenario(cand.data), encoding="utf-8")
                    os.replace(tmp, path)
                    if load_scenario(yaml.load(path.read_text(encoding="utf-8"), Loader=_LOADER)) != cand.scenario:
                        raise MmusvError(f"internal: {path} does not read back as the scenario that was checked")
                    rep.accept(path.name)
                    report.scenarios.append(
                        {
                            "file": path.name,
                            "combination": rep.name,
                            "family": combo.family,
                            "difficulty": combo.difficulty,
                            "attempt": attempt,
                            "seed": cand.data["seed"],
                            "map": cand.data["map"]["type"],
                            "roles": cand.meta.as_dict(),
                        }
                    )
            if progress is not None:
                progress(rep.name, report.accepted, total_attempts)
    tmp = out / ".report.json.tmp"
    tmp.write_text(report.to_json(), encoding="utf-8")
    os.replace(tmp, out / "report.json")
    return report
