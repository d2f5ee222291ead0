"""The reject-and-resample loop: fill every combination's quota or stop at its attempt cap, write the accepted
scenarios and ``report.json``.

Per combination (in spec order) attempts ``0, 1, ...`` are drawn by :func:`sample_candidate` from
``(spec.seed, the combination's name, attempt)`` (the distractor count from the place in the quota being filled;
the name, not the place in the list: the others' scenarios stay when one is added, removed or moved) and checked
by the enabled constraints; an accepted candidate is written as
``<combination>_<NNN>.yaml`` (``NNN`` = its rank among the combination's accepted scenarios; its name goes into
the hidden ``.generate.partial`` first, so a run stopped before its report is known by ``--force``), read back (YAML
safe loader, libyaml's when installed: the same resolver as ``yaml.safe_load``), validated with
:func:`mmusv.config.load_scenario` and compared with the checked scenario before it counts. The loop stops at the
quota or at ``max_attempts``, so it always ends; the same spec gives the same files byte for byte. Beside the
spec's constraints, a candidate whose vessel's keel reaches the seabed is rejected (``under_keel``, always on). A
combination whose vessels fit nowhere on its map at the clearances asked, or whose distances (closest approach,
cooperation) exceed what its water spans (:func:`infeasible_error`), is refused before the first attempt, and nothing
is written.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
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
from mmusv.generate.spec import load_spec
from mmusv.generate.spec_models import GenerationSpec, class_assets
from mmusv.held_signals import raise_noted_stop

__all__ = ["JOURNAL", "Progress", "check_output", "dump_scenario", "generate", "infeasible_error"]

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


JOURNAL = ".generate.partial"
"""The file in the output folder that names every scenario file a run is about to write, one per line, before the
file appears; removed once ``report.json`` is in place. A run stopped before its report (Ctrl-C, a kill, a full
disk) leaves it, so ``--force`` (and ``mmusv dataset`` run again) knows those files are a generate run's own."""


def check_output(out: str | os.PathLike[str], *, force: bool, spec_path: str | os.PathLike[str] | None = None) -> None:
    """Raises the :class:`~mmusv.errors.IoError` that generating into ``out`` would end in (a file there, YAML
    files no generate run wrote, or, without ``force``, an earlier run's files), changing nothing: ``mmusv generate``
    calls it before building the maps, which took seconds before such a refusal."""
    _existing(Path(out), force, Path(spec_path) if spec_path is not None else None)


def _existing(out: Path, force: bool, spec_path: Path | None) -> tuple[list[Path], set[str]] | None:
    """The YAML files in ``out`` and the names an earlier run there wrote (its ``report.json`` or, for a run
    stopped before its report, its :data:`JOURNAL`), or None when ``out`` holds nothing of a run; raises when the
    run must refuse (see :func:`_prepare_dir`)."""
    if out.exists() and not out.is_dir():
        raise IoError(f"output {str(out)!r} exists and is not a directory")
    if not out.is_dir():
        return None
    report, journal = out / "report.json", out / JOURNAL
    for path, what in ((report, "report"), (journal, "journal")):  # found only when written: the report at the end
        if path.exists() and not path.is_file():
            raise IoError(
                f"output directory {str(out)!r}: {path.name} is a folder (or another non-file) where generate writes "
                f"its {what}: move it away"
            )
    yamls = sorted(out.glob("*.yaml"))
    # generate writes .yaml only, but ``mmusv run`` of the folder records its .yml files too: each is foreign (a
    # user's .yml there was accepted and recorded with the set)
    ymls = sorted(out.glob("*.yml"))
    if not yamls and not ymls and not report.is_file():  # a journal alone: a run stopped before its first file
        return None
    ours = _generated_here(report) | _journal_names(journal)
    is_spec = [p for p in [*yamls, *ymls] if spec_path is not None and _same_file(p, spec_path)]
    foreign = sorted([p for p in yamls if p.name not in ours or p in is_spec] + ymls)
    if foreign:  # --force would not replace them either: say so at once, not after a first refusal
        names = ", ".join(p.name for p in foreign[:3]) + (" ..." if len(foreign) > 3 else "")
        raise IoError(
            f"output directory {str(out)!r} holds YAML files that no earlier generate run there wrote ({names}; "
            f"{'the spec itself, ' if is_spec else ''}"
            "report.json lists what a run wrote); --force replaces only those: choose another folder or move them"
        )
    if not force:
        what = (
            f"the {len(yamls)} scenario files of a generate run stopped before its report.json"
            if not report.is_file()
            else f"{len(yamls)} scenario files and the report.json of an earlier generate run"
        )
        raise IoError(f"output directory {str(out)!r} already holds {what}; pass --force to replace them")
    return yamls, ours


def _prepare_dir(out: Path, force: bool, spec_path: Path | None = None) -> None:
    """Readies ``out``: with ``force``, removes the scenario files a previous run generated there (those its
    ``report.json`` lists, or, for a run stopped before its report, its :data:`JOURNAL`) and that report; any other
    YAML file there (a hand-written scenario, the spec itself) is never deleted: the run refuses instead, with or
    without ``force``."""
    found = _existing(out, force, spec_path)
    if found is None:
        out.mkdir(parents=True, exist_ok=True)
        for name in _journal_names(out / JOURNAL):  # a temporary a stopped run left (the journal is rewritten)
            (out / f".{name}.tmp").unlink(missing_ok=True)
        return
    yamls, ours = found
    journal = out / JOURNAL
    # The journal names every file about to go, so a run stopped while removing them still knows them as its own.
    try:
        _write_journal(journal, sorted(ours | {p.name for p in yamls}))
        (out / "report.json").unlink(missing_ok=True)
        for p in yamls:
            p.unlink()
        for name in ours:
            (out / f".{name}.tmp").unlink(missing_ok=True)
        (out / ".report.json.tmp").unlink(missing_ok=True)
        journal.unlink()
    except OSError as exc:
        raise IoError(
            f"output directory {str(out)!r}: cannot replace the earlier run's files: {exc.strerror or exc}"
        ) from None


def _write_journal(journal: Path, names: list[str]) -> None:
    tmp = journal.with_name(journal.name + ".tmp")
    tmp.write_text("".join(f"{n}\n" for n in names), encoding="utf-8")
    os.replace(tmp, journal)


def _journal_names(journal: Path) -> set[str]:
    """The scenario file names a run's :data:`JOURNAL` lists (empty when there is none or it is unreadable)."""
    try:
        lines = journal.read_text(encoding="utf-8").splitlines()
    except (OSError, ValueError):
        return set()
    return {n for n in lines if n.endswith(".yaml") and Path(n).name == n}


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


def _write_failed(path: Path, exc: OSError, written: int) -> IoError:
    """The one-line error of a write that failed (a full disk, a read-only folder): the file, the cause, what is
    kept and how to go on. The OSError of a write to an open file names no file, so the CLI said only "No space
    left on device"."""
    cause = f"{path}: cannot write it: {exc.strerror or exc}"
    if not written:
        return IoError(f"{cause}; free space or choose a folder that can be written")
    return IoError(
        f"{cause}; the {written} scenario file(s) written before it are kept: free space and run again (generate "
        "--force, or the same mmusv dataset command), which replaces what this run wrote"
    )


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve()
    except OSError:
        return False


def _infeasible(spec: GenerationSpec, ctx: MapContext, idx: int) -> tuple[str, float, str] | None:
    """Why combination ``idx`` can never pass the clearance checks on its map ``ctx``, as ``(constraint field, its
    value, why)`` (:func:`infeasible_error` words it), or None. Exact: the clearance checks ask every point of a
    hull capsule's axis for ``raster - cell slack - radius - (more slack) >= min_m``, so a vessel (the slimmest
    asset its role may take: a target's size class, the ego, a cooperating USV) fits only where one cell of the
    map leaves that much room from the shore and from the structures at once; where none does, every attempt
    would be spent on rejections (``shore_clearance: {min_m: 100000}`` ran 100,000 attempts for 12 minutes)."""
    combo = spec.combinations[idx]
    cons = spec.constraints
    shore = cons.shore_clearance.min_m if cons.shore_clearance.enabled else None
    struct = cons.structure_clearance.min_m if cons.structure_clearance.enabled else None
    if shore is None and struct is None:
        return None
    roles = [(f"size class {cls!r}", class_assets(spec.size_classes[cls])) for cls in dict.fromkeys(combo.targets)]
    roles.append((f"the ego ({combo.ego or spec.usv.assets[0]})", [combo.ego or spec.usv.assets[0]]))
    if combo.cooperating:
        roles.append(("a cooperating USV", list(spec.usv.assets)))
    room_shore = ctx.d_shore - ctx.cell_slack  # the clearance every point of a cell has, conservatively
    room_struct = ctx.d_struct - ctx.cell_slack
    best_shore, best_struct = float(room_shore.max(initial=0.0)), float(room_struct.max(initial=0.0))
    m = spec.map_of(combo)
    where = f"on this map ({m.type}, seed {m.seed})"
    for role, assets in roles:
        slimmest = min(assets, key=lambda a: (capsule(a)[1], a))
        r = capsule(slimmest)[1]
        fits = np.ones(room_shore.shape, dtype=bool)
        if shore is not None:
            fits &= room_shore - r >= shore - _EPS
        if struct is not None:
            fits &= room_struct - r >= struct - _EPS
        if fits.any():
            continue
        hull = f"{slimmest} hull radius {r:.1f} m"
        if shore is not None and best_shore - r < shore - _EPS:
            return (
                "constraints.shore_clearance.min_m",
                shore,
                f"{role} needs {r + shore:.0f} m of clearance from the shore ({hull} + {shore:g} m) and the most "
                f"open water {where} offers {best_shore:.0f} m: lower shore_clearance.min_m",
            )
        if struct is not None and best_struct - r < struct - _EPS:
            return (
                "constraints.structure_clearance.min_m",
                struct,
                f"{role} needs {r + struct:.0f} m of clearance from port structures, buoys and moored ships ({hull} "
                f"+ {struct:g} m) and no water {where} lies farther than {best_struct:.0f} m from them: lower "
                "structure_clearance.min_m",
            )
        return (
            "constraints.shore_clearance.min_m",
            float(shore or 0.0),
            f"{role} needs {r + (shore or 0.0):.0f} m of clearance from the shore and {r + (struct or 0.0):.0f} m "
            f"from port structures, buoys and moored ships ({hull}), and no water {where} offers both: lower "
            "shore_clearance.min_m or structure_clearance.min_m",
        )
    return None


_EPS = 1e-9
"""Metres of rounding :func:`_infeasible` forgives, so it never refuses what the checks could accept."""


def _out_of_reach(spec: GenerationSpec, ctx: MapContext, idx: int) -> tuple[str, float, str] | None:
    """Why combination ``idx`` can never pass a distance it asks for on its map ``ctx``, as :func:`_infeasible`
    says it, or None: its difficulty's closest-approach range, or (with more than one USV) the cooperation
    distance, farther than any two points of the map's navigable water lie apart (the diagonal of the box round
    them). A cooperation of 3,000 m on a 2,000 m island map spent every attempt on rejections."""
    combo = spec.combinations[idx]
    water = ctx.d_shore > 0.0
    if not water.any():
        return None
    rows, cols = np.nonzero(water)
    span = math.hypot(
        (int(cols.max()) - int(cols.min()) + 1) * ctx.resolution,
        (int(rows.max()) - int(rows.min()) + 1) * ctx.resolution,
    )
    m = spec.map_of(combo)
    where = f"the navigable water of this map ({m.type}, seed {m.seed}) spans at most {span:.0f} m"
    lo = spec.difficulties[combo.difficulty].range_m[0]
    if spec.constraints.target_range.enabled and lo > span + _EPS:
        return (
            f"difficulties.{combo.difficulty}.range_m",
            lo,
            f"its targets must come no nearer than {lo:g} m to the ego and {where}: lower range_m",
        )
    coop = spec.constraints.cooperation
    if combo.cooperating and coop.enabled and coop.min_share > 0.0 and coop.min_m > span + _EPS:
        return (
            "constraints.cooperation.min_m",
            coop.min_m,
            f"its USVs must keep {coop.min_m:g} m from each other and {where}: lower cooperation.min_m",
        )
    return None


def infeasible_error(spec: GenerationSpec, contexts: list[MapContext], *, source: str = "spec") -> ConfigError | None:
    """The :class:`~mmusv.errors.ConfigError` that refuses ``spec`` when one of its combinations can never pass the
    clearance checks on its map (``contexts[i]`` is combination ``i``'s; :func:`_infeasible`), or a distance it asks
    for (:func:`_out_of_reach`), worded as the spec's other impossible constraints are
    (:func:`mmusv.generate.spec.load_spec`); None when none is found."""
    for i, ctx in enumerate(contexts):
        bad = _out_of_reach(spec, ctx, i) or _infeasible(spec, ctx, i)
        if bad is not None:
            field, value, why = bad
            return ConfigError(
                f"{source}: invalid spec {field} = {value!r}: combinations[{i}] "
                f"({spec.combinations[i].label()}) could never pass: {why}"
            )
    return None


def _first_failure(
    constraints: list[Constraint], cand: Candidate, ctx: MapContext, spec: GenerationSpec
) -> tuple[str, str] | None:
    """The first failing constraint of a candidate, ``("sampling", why)`` when it has too many samples to check
    (:data:`~mmusv.generate.samples.MAX_CHECK_SAMPLES`), then ``("under_keel", why)`` when a vessel's draft reaches
    the seabed at some frame (:func:`mmusv.scenario_checks.keel_findings`, what ``mmusv run`` warns about: a
    330 m tanker among islands, a bulk carrier in a 14 m port basin), None when it passes."""
    from mmusv.scenario_checks import keel_findings

    try:
        samples = take_samples(cand.scenario, cand.meta, ctx, spec)
    except ConfigError as exc:
        return "sampling", str(exc)
    fail = first_failure(constraints, samples)
    if fail is None:
        keel = keel_findings(cand.scenario, ctx.world, samples)
        if keel:
            return "under_keel", keel[0].message
    return fail


def generate(
    spec_source: GenerationSpec | str | os.PathLike[str] | dict[str, Any],
    out_dir: str | os.PathLike[str],
    *,
    force: bool = False,
    progress: Progress | None = None,
    source: str | None = None,
) -> RunReport:
    """Generates the scenarios of a spec into ``out_dir`` (created; refuses to overwrite earlier scenario files
    unless ``force``) and writes ``report.json`` there; returns the report. A combination that can never pass the
    clearance checks on its map is refused with a :class:`~mmusv.errors.ConfigError` before anything is written, as
    :func:`~mmusv.generate.spec.load_spec` refuses other impossible constraints; ``source`` names the spec in it
    (default: the path given, else ``spec``)."""
    spec = load_spec(spec_source)
    out = Path(out_dir)
    spec_path = Path(spec_source) if isinstance(spec_source, (str, os.PathLike)) else None
    check_output(out, force=force, spec_path=spec_path)  # before the maps are built: a refusal took their seconds first
    contexts = [
        map_context(m.type, seed=m.seed, params=m.param_values()) for m in (spec.map_of(c) for c in spec.combinations)
    ]
    where = source if source is not None else str(spec_path) if spec_path is not None else "spec"
    refused = infeasible_error(spec, contexts, source=where)
    if refused is not None:  # every attempt would be rejected: said at once, nothing written
        raise refused
    constraints = build_constraints(spec)
    _prepare_dir(out, force, spec_path)
    journal = out / JOURNAL
    try:  # also the first write into the folder: a read-only one is named before any sampling
        journal.write_text("", encoding="utf-8")
    except OSError as exc:
        raise _write_failed(journal, exc, 0) from None
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
        report.combos.append(rep)
        width = max(3, int(math.log10(combo.quota)) + 1)
        for attempt in range(rep.max_attempts):
            if rep.met:
                break
            raise_noted_stop()  # a stop whose KeyboardInterrupt a library swallowed (held_signals)
            name = f"{rep.name}_{rep.accepted:0{width}d}"
            total_attempts += 1
            try:
                cand = sample_candidate(spec, combo_index=i, attempt=attempt, ctx=ctx, name=name, slot=rep.accepted)
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
                    _write_scenario(path, dump_scenario(cand.data), journal, report.accepted)
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
    _write_atomic(out / "report.json", report.to_json(), report.accepted)
    journal.unlink(missing_ok=True)  # the report lists every file now
    return report


def _write_atomic(path: Path, text: str, written: int) -> None:
    """``text`` into ``path`` through a hidden temporary renamed into place (a stop never leaves half a file); on
    an OSError the temporary is removed and the error names ``path`` (:func:`_write_failed`). The temporary's
    name is fixed (not :func:`mmusv.jsonio.write_bytes_atomic`'s per process): :func:`_prepare_dir` finds a
    stopped run's temporaries by the names its journal lists."""
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    except OSError as exc:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
        raise _write_failed(path, exc, written) from None


def _write_scenario(path: Path, text: str, journal: Path, written: int) -> None:
    """Writes one accepted scenario: its name into the journal first (flushed), then the file itself."""
    try:
        with journal.open("a", encoding="utf-8") as f:
            f.write(f"{path.name}\n")
    except OSError as exc:
        raise _write_failed(journal, exc, written) from None
    _write_atomic(path, text, written)
