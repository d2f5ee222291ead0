"""From a generation spec to a dataset in one call: ``mmusv dataset SPEC.yaml -o DIR`` / :func:`build_dataset`.

Steps, each skipped on a re-run when its result is already there:

1. generate the spec (:func:`mmusv.generate.generate`) into ``DIR/scenarios`` (skipped when ``DIR/dataset.json``
   names the same spec hash and ``DIR/scenarios/report.json`` exists with every file it lists; a generation stopped
   before its report is done again, replacing what it wrote); the quotas it did not meet are reported on every run;
2. record every scenario into ``DIR/recordings/<stem>/`` with the batch runner (:func:`mmusv.batch.run_many`: the
   local pool or Ray, complete recordings skipped). The recordings an earlier run indexed are this dataset's own:
   when the spec changed, one of a scenario that changed is recorded again (it used to fail, telling to pass an
   ``--overwrite`` that ``mmusv dataset`` did not take) and one of a scenario the spec no longer makes is removed,
   so ``DIR/recordings`` holds what ``dataset.json`` lists. With ``ray``, Ray is joined before step 1 changes
   anything (when scenarios are to be generated or a stale recording removed): a cluster that cannot be joined
   fails the command with nothing on disk changed (it generated the scenarios and removed recordings first);
3. convert the complete recordings to OPV2V (:func:`mmusv.export.convert`) into ``DIR/opv2v`` (skipped when the
   last conversion was of the same recordings and configurations);
4. ``DIR/dataset.json`` (:mod:`mmusv.batch.index`) lists every recording, with sections ``spec`` (file name,
   name, hash) and ``opv2v`` (folder, status, frames converted, the recordings converted with their hashes; status
   ``converting`` while step 3 runs, so an index left by a stop then never calls a half-written folder complete).
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mmusv.batch.index import (
    INDEX_NAME,
    check_replaceable,
    index_entries,
    read_earlier_index,
    read_index,
    write_index,
)
from mmusv.batch.plan import STATE_DIR, remove_task_files
from mmusv.batch.runner import BatchReport, join_ray, run_many
from mmusv.errors import IoError, MmusvError

__all__ = ["DatasetReport", "build_dataset"]

Progress = Callable[[str, int, int], None]
"""``(stage, done, total)`` with stage ``generate`` (scenarios), ``record`` or ``convert`` (frames)."""


@dataclass
class DatasetReport:
    """What :func:`build_dataset` did: whether it generated (``False``: reused), the batch report, frames
    converted (``None``: conversion skipped, up to date) and quota shortfalls of the generation."""

    out_dir: Path
    generated: bool
    shortfall: list[str]
    batch: BatchReport
    converted: int | None
    opv2v: Path
    removed: list[str] = field(default_factory=list)
    """The scenarios whose recordings were removed, since the spec no longer makes them (an edited spec)."""

    @property
    def ok(self) -> bool:
        """True when every scenario was recorded."""
        return self.batch.ok


def _conversion_complete(opv2v: Path) -> bool:
    """Whether ``opv2v`` holds a finished conversion of today's format: its report says ``status: complete`` and
    ``format_version`` the OPV2V writer's (:attr:`~mmusv.export.writer.DatasetWriter.format_version`: a folder
    converted before a file's meaning changed is converted again), and every recording it converted frames of still
    has its folder (``<split>/<folder>``). A conversion into a folder that was not there (removed by hand) writes
    into it directly and starts its report as ``in_progress``: stopped there (Ctrl-C), a re-run took the
    half-written folder for up to date, as the index still named the same recordings."""
    from mmusv.export.conversion import writer_class
    from mmusv.export.convert_report import REPORT_NAME
    from mmusv.yamlio import read_yaml

    try:
        doc = read_yaml(opv2v / REPORT_NAME)
    except (OSError, MmusvError, ValueError):
        return False
    if not isinstance(doc, dict) or doc.get("status") != "complete":
        return False
    # Converted by an earlier version whose files mean something else today (OPV2V 2: the depth PNGs' encoding).
    if doc.get("format_version", 1) != writer_class("opv2v").format_version:
        return False
    # Every recording that was converted still has its folder: one removed by hand (to make room, or to convert it
    # again) was taken for up to date, "opv2v: ... is up to date" with its sequence gone.
    recordings = doc.get("recordings")
    if not isinstance(recordings, list):
        return False
    for r in recordings:
        if (
            not isinstance(r, dict)
            or not isinstance(r.get("folder"), str)
            or not isinstance(r.get("split"), str | None)
        ):
            return False
        if r.get("frames_converted") and not (opv2v / (r["split"] or "") / r["folder"]).is_dir():
            return False
    return True


def _spec_hash(spec: Any) -> str:
    text = json.dumps(spec.model_dump(mode="json"), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def _generated_set(scen_dir: Path) -> list[str] | None:
    """The quota shortfalls of the scenario set an earlier run generated into ``scen_dir`` (``[]`` when every quota
    was met), or None when that set is not whole (no readable ``report.json``, or a file it lists is gone) and must
    be generated again. A re-run used to say only "kept (same spec)", forgetting the shortfall the first run
    printed, and kept a set whose files had been deleted, recording fewer scenarios than the spec makes."""
    try:
        data = json.loads((scen_dir / "report.json").read_text(encoding="utf-8"))
        combos = data["combinations"]
        files = [f for c in combos for f in c["files"]]
        shortfall = [f"{c['name']}: {c['accepted']} of {c['quota']}" for c in combos if not c["quota_met"]]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if not all(isinstance(f, str) and (scen_dir / f).is_file() for f in files):
        return None
    return shortfall


def _refuse_foreign(scen_dir: Path) -> None:
    """Refuses (:class:`~mmusv.errors.IoError`) scenario files in ``scen_dir`` that no generation there wrote (not
    listed in its ``report.json``, nor in the journal of one stopped before its report): the batch records every
    ``*.yaml`` and ``*.yml`` there, so a file put there by hand (or a ``.yml``, which generate does not check) was
    recorded, converted and indexed as part of the spec's dataset without a word. Checked before the generation
    (a ``.yml`` was refused only once the whole spec had been generated)."""
    from mmusv.batch.plan import folder_entries
    from mmusv.generate.runner import JOURNAL, _generated_here, _journal_names

    listed = _generated_here(scen_dir / "report.json") | _journal_names(scen_dir / JOURNAL)
    foreign = [p.name for p in folder_entries(scen_dir) if p.name not in listed]
    if foreign:
        names = ", ".join(foreign[:3]) + (" ..." if len(foreign) > 3 else "")
        raise IoError(
            f"{scen_dir} holds scenario files the spec's generation did not write ({names}; its report.json lists "
            "what it wrote): mmusv dataset records the spec's scenarios only; move them away"
        )


def _own_recordings(old: dict[str, Any]) -> set[str]:
    """The scenarios whose recording folder ``DIR/recordings/<name>/`` an earlier ``mmusv dataset`` run into this
    folder indexed (its ``dataset.json``, with the ``spec`` section only that command writes)."""
    if not isinstance(old.get("spec"), dict):
        return set()
    out = set()
    for r in old.get("recordings", []):
        name, rec = r.get("name"), r.get("recording")
        if (
            isinstance(name, str)
            and isinstance(rec, str)
            and name == Path(name).name
            and not name.startswith(".")
            and rec.startswith(f"recordings/{name}/")
        ):
            out.add(name)
    return out


def _opv2v_section(old: dict[str, Any]) -> dict[str, Any] | None:
    """The ``opv2v`` section of an earlier run's index when it is one this command wrote (a JSON object of plain
    JSON values), else None: the conversion is then not known to be up to date and is done again. A damaged one
    (a text, a list) was an AttributeError traceback after every scenario had been recorded, one holding NaN a
    refusal naming ``index_extra['opv2v']``, an argument no user gave."""
    section = old.get("opv2v")
    if not isinstance(section, dict):
        return None
    try:
        json.dumps(section, allow_nan=False)
    except (TypeError, ValueError):
        return None
    return section


def _remove_stale(rec_dir: Path, own: set[str], stems: set[str]) -> list[str]:
    """Removes the recording folders of this dataset's own scenarios that the spec no longer makes, and their
    task files; the names of the scenarios whose recording folder it removed."""
    removed: list[str] = []
    for name in sorted(own - stems):
        remove_task_files(rec_dir / STATE_DIR, name, keep=set())
        folder = rec_dir / name
        if folder.is_dir() and not folder.is_symlink():
            try:
                shutil.rmtree(folder)
            except OSError as exc:
                raise IoError(
                    f"{folder}: cannot remove the recording of {name}, which the spec no longer makes: "
                    f"{exc.strerror or exc}"
                ) from None
            removed.append(name)
    return removed


def build_dataset(
    spec: str | os.PathLike[str],
    *,
    out_dir: str | os.PathLike[str],
    jobs: int = 1,
    ray: bool | str = False,
    cpus_per_task: int | None = None,
    retries: int = 0,
    split_frames: int | None = None,
    checks: bool = True,
    progress: Progress | None = None,
    stop_on_full_disk: bool = False,
    overwrite: bool = False,
) -> DatasetReport:
    """Generates, records, converts and indexes the dataset of ``spec`` into ``out_dir`` (see the module
    docstring); the batch options are those of :func:`mmusv.batch.run_many` (``overwrite``: record every scenario
    again, replacing whatever ``DIR/recordings`` holds for it)."""
    from mmusv.bundled import resolve_spec
    from mmusv.export.conversion import convert
    from mmusv.generate.runner import generate
    from mmusv.generate.spec import load_spec

    sp = resolve_spec(Path(spec))
    loaded = load_spec(sp)
    out = Path(out_dir)
    scen_dir, rec_dir, opv2v = out / "scenarios", out / "recordings", out / "opv2v"
    index_path = out / INDEX_NAME
    check_replaceable(index_path, writer="mmusv dataset")  # the batch refuses it too, but after the generation
    old = read_earlier_index(index_path)
    listed = old.get("recordings")
    if isinstance(listed, list) and listed and not isinstance(old.get("spec"), dict):
        raise IoError(
            f"{index_path} is the index of a batch run (mmusv run DIR), not of mmusv dataset: it lists "
            f"{len(listed)} recording(s) that a dataset there would leave unlisted (its index replaces this one); "
            "give the dataset a folder of its own (-o)"
        )
    old_opv2v = _opv2v_section(old)
    spec_section = {"file": Path(sp).name, "name": loaded.name, "hash": _spec_hash(loaded)}
    kept = _generated_set(scen_dir) if old.get("spec") == spec_section else None
    generated = kept is None
    shortfall: list[str] = [] if kept is None else kept
    quota = sum(c.quota for c in loaded.combinations)
    own = _own_recordings(old)
    _refuse_foreign(scen_dir)  # before the generation, which replaces only what a generation wrote
    # Ray before anything changes on disk: a cluster that could not be joined failed the batch after the scenarios
    # were generated and stale recordings removed. (With nothing to generate or remove, the batch joins it if it has
    # something to record, before it writes anything, as `mmusv run DIR --ray` does.)
    joined = None
    if ray is not False and (generated or own - {p.stem for p in scen_dir.glob("*.yaml")}):
        joined = join_ray(ray, cpus_per_task=cpus_per_task)
    try:
        if generated:

            def tick(_name: str, accepted: int, _attempts: int) -> None:
                if progress is not None:
                    progress("generate", accepted, quota)

            report = generate(loaded, scen_dir, force=True, progress=tick, source=str(sp))
            shortfall = [f"{c.name}: {c.accepted} of {c.quota}" for c in report.combos if not c.met]
        if progress is not None:
            progress("generate", quota, quota)
        removed = _remove_stale(rec_dir, own, {p.stem for p in scen_dir.glob("*.yaml")})
        if not any(scen_dir.glob("*.yaml")):  # no candidate met the spec: nothing to record (the shortfall says so)
            nothing = {"folder": opv2v.name, "status": "nothing to convert", "frames": 0, "sources": {}}
            write_index(index_path, [], extra={"spec": spec_section, "opv2v": nothing})
            empty = BatchReport(out_dir=rec_dir, backend="serial", outcomes=[], index=index_path)
            return DatasetReport(
                out_dir=out,
                generated=generated,
                shortfall=shortfall,
                batch=empty,
                converted=0,
                opv2v=opv2v,
                removed=removed,
            )
        batch = run_many(
            scen_dir,
            out_dir=rec_dir,
            jobs=jobs,
            ray=ray,
            cpus_per_task=cpus_per_task,
            retries=retries,
            split_frames=split_frames,
            checks=checks,
            index=index_path,
            index_extra={"spec": spec_section, "opv2v": old_opv2v},
            progress=None if progress is None else (lambda d, t: progress("record", d, t)),
            stop_on_full_disk=stop_on_full_disk,
            overwrite=overwrite,
            replace=own,
        )
        if joined is not None:  # the batch ran on the Ray joined here: left now (shut down if started here)
            joined.close(cancel=False)
            joined = None
        doc = read_index(index_path)
        sources = {r["name"]: r["config_hash"] for r in doc["recordings"] if r["status"] == "complete"}
        section = old_opv2v or {}
        converted: int | None = None
        up_to_date = (
            section.get("sources") == sources and section.get("status") == "complete" and _conversion_complete(opv2v)
        )
        entries = index_entries(doc)
        if sources and not up_to_date:
            recs = [out / r["recording"] for r in doc["recordings"] if r["name"] in sources]
            # the index says the conversion is under way until it is done: it kept the earlier conversion's
            # "complete" while DIR/opv2v was being replaced, so a stop meanwhile left it saying complete over a
            # folder holding a part of the files (conversion.yaml said interrupted)
            converting = {"folder": opv2v.name, "status": "converting", "frames": 0, "sources": {}}
            write_index(index_path, entries, extra={"spec": spec_section, "opv2v": converting})
            try:
                conv = convert(
                    recs,
                    to="opv2v",
                    out_dir=opv2v,
                    overwrite=True,
                    progress=None if progress is None else (lambda d, t: progress("convert", d, t)),
                )
            except OSError as exc:  # a full disk: "No space left on device" alone, naming no folder and no way on
                where = f"{exc.filename}: " if exc.filename else ""
                raise IoError(
                    f"{opv2v}: converting the recordings to OPV2V failed: {where}{exc.strerror or exc}; the "
                    f"{len(recs)} complete recording(s) are kept and indexed in {index_path}: free space and run the "
                    "same command again to convert them"
                ) from None
            converted = conv.frames
            section = {"folder": opv2v.name, "status": "complete", "frames": conv.frames, "sources": sources}
        elif not sources:
            section = {"folder": opv2v.name, "status": "nothing to convert", "frames": 0, "sources": {}}
            converted = 0  # not "up to date": no recording is complete
        write_index(index_path, entries, extra={"spec": spec_section, "opv2v": section})
        return DatasetReport(
            out_dir=out,
            generated=generated,
            shortfall=shortfall,
            batch=batch,
            converted=converted,
            opv2v=opv2v,
            removed=removed,
        )
    finally:
        if joined is not None:
            joined.close(cancel=True)
