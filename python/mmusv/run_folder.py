"""The run folder of ``mmusv run`` (:func:`mmusv.acquire.run`): what must hold before a run writes into it, and
what it replaces there.

A run writes its recording, ``manifest.json``, ``scenario.yaml`` and ``tables/`` into one folder. Before anything is
written it refuses a folder whose names are taken by the wrong kind of entry (:func:`refuse_wrong_kinds`), one
holding an earlier run of this recording or the finished run of another, unless told to overwrite
(:func:`refuse_earlier_run`), and a ``scenario.yaml`` or ``manifest.json`` that no run wrote
(:func:`refuse_foreign_files`). Once its recording is open it replaces an earlier run's outputs
(:func:`replace_outputs`); a write that fails says why and which frames are safe (:func:`writes_into`,
:func:`write_failure`).
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path
from typing import Any, TypeGuard

import yaml

from mmusv.config import Scenario
from mmusv.errors import IoError, MmusvError
from mmusv.recording.guard import write_cause
from mmusv.recording.tables import SCHEMAS

__all__ = [
    "is_run_manifest",
    "refuse_earlier_run",
    "refuse_foreign_files",
    "refuse_wrong_kinds",
    "replace_outputs",
    "write_failure",
    "writes_into",
]


def refuse_earlier_run(out: Path, rec_path: Path, *, overwrite: bool) -> None:
    """Raises :class:`~mmusv.errors.IoError` unless ``overwrite`` when ``rec_path`` exists (saying whether its run
    finished) or ``out`` holds the finished run of another recording."""
    if overwrite:
        return
    if rec_path.exists():
        raise IoError(
            f"{rec_path} already exists{_earlier_run(out, rec_path)}; pass --overwrite (overwrite=True in Python) "
            "to replace it"
        )
    _refuse_another_run(out, rec_path)


def _earlier_run(out: Path, rec_path: Path) -> str:
    """What the run folder ``out`` says of the run that wrote ``rec_path`` when it did not finish, as
    ``" (its run was interrupted: 61 of 300 frames written)"`` (``""`` otherwise): refused without a word on it, a
    stopped run looked like a finished one that a second run would only repeat."""
    from mmusv.jsonio import read_json_or_none

    manifest = read_json_or_none(out / "manifest.json")
    if manifest is None or manifest.get("recording") != rec_path.name:
        return ""
    status, written, asked = manifest.get("status"), manifest.get("frames_written"), manifest.get("frames_requested")
    if status in (None, "complete") or not isinstance(status, str):
        return ""
    counts = f": {written} of {asked} frames written" if isinstance(written, int) and isinstance(asked, int) else ""
    return f" (its run was {status}{counts})"


def _refuse_another_run(out: Path, rec_path: Path) -> None:
    """Raises :class:`~mmusv.errors.IoError` when ``out`` holds the finished run of another recording
    (:func:`~mmusv.recording.info.another_run`): this run would replace that run's ``manifest.json``,
    ``scenario.yaml`` and tables, which a second scenario run into the same folder did without a word, leaving the
    first recording without its tables."""
    from mmusv.recording.info import another_run

    other = another_run(out, rec_path.name)
    if other is not None:
        raise IoError(
            f"{out} holds the run of another recording, {other} (its manifest.json, scenario.yaml and tables/), "
            f"which a run of {rec_path.name} there would replace; give each scenario a folder of its own (-o), or "
            f"pass --overwrite (overwrite=True in Python) to replace them ({other} itself is kept)"
        )


def refuse_wrong_kinds(out: Path, rec_path: Path) -> None:
    """Raises :class:`~mmusv.errors.IoError` when one of the names a run writes in ``out`` is taken by the wrong
    kind of entry: ``tables`` and its three table folders must be folders, ``manifest.json``, ``scenario.yaml`` and
    the recording ``rec_path`` (and its ``.partial``) files. Checked before anything is written; before, a file
    named ``tables`` failed the run only after its last frame, with the recording finished as ``complete``, no
    tables and no manifest."""
    wanted = {"manifest.json": False, "scenario.yaml": False, "tables": True}
    # the recording and a killed run's .partial: a folder of that name was "left by an interrupted run", then
    # "cannot write into out: Is a directory"
    wanted.update({rec_path.name: False, rec_path.name + ".partial": False})
    wanted.update({f"tables/{name}": True for name in SCHEMAS})
    for name, folder in wanted.items():
        path = out / name
        if not (path.exists() or path.is_symlink()) or path.is_dir() == folder:
            continue
        kind, must = ("a folder", "a file") if path.is_dir() else ("not a folder", "a folder")
        raise IoError(
            f"{path} is {kind}, but a run writes its {name} there as {must}; move it out of {out} or give the run "
            "another folder (-o)"
        )


def refuse_foreign_files(out: Path, cfg: object) -> None:
    """Raises :class:`~mmusv.errors.IoError` when ``out`` holds a ``scenario.yaml`` or ``manifest.json`` that no
    run wrote: a run replaces both, and replaced a user's own notes, a hand-written scenario (the scenario it ran
    included: ``mmusv run scenario.yaml -o .``) or manifest without a word, ``--overwrite`` or not. A run's
    ``scenario.yaml`` lies beside its recording (``.mcap``, or ``.mcap.partial`` of a killed run), or is the
    resolved scenario as :func:`replace_outputs` dumps it (read back and dumped again, it is the same text); its
    ``manifest.json`` is a JSON object naming its ``recording`` and ``mmusv_version``."""
    import warnings

    from mmusv.config import load_scenario
    from mmusv.jsonio import read_json_or_none

    scenario_file, manifest = out / "scenario.yaml", out / "manifest.json"
    foreign: Path | None = None
    ran = any(out.glob("*.mcap")) or any(out.glob("*.mcap.partial"))  # a run's, its scenario.yaml beside it
    if scenario_file.is_file() and not ran:
        try:
            text = scenario_file.read_text(encoding="utf-8")
            with warnings.catch_warnings():  # its own warnings are not this run's
                warnings.simplefilter("ignore")
                dumped = yaml.safe_dump(load_scenario(scenario_file).model_dump(mode="json"), sort_keys=False)
        except (MmusvError, OSError, ValueError, yaml.YAMLError):
            text, dumped = "", None
        if text != dumped:
            foreign = scenario_file
    if foreign is None and manifest.is_file() and not is_run_manifest(read_json_or_none(manifest)):
        foreign = manifest
    if foreign is None:
        return
    if isinstance(cfg, (str, os.PathLike)) and Path(cfg).resolve() == foreign.resolve():
        raise IoError(
            f"the scenario file {cfg} is where a run into {out} writes its resolved scenario: it would be replaced "
            "(--overwrite or not); run into another folder (-o), or copy the scenario out of it first"
        )
    raise IoError(
        f"{foreign} was not written by an mmusv run, and a run into {out} replaces its {foreign.name} (--overwrite "
        f"or not); run into another folder (-o), or move it out of {out}"
    )


def is_run_manifest(doc: dict[str, Any] | None) -> TypeGuard[dict[str, Any]]:
    """Whether ``doc``, a ``manifest.json`` read (``None``: none that reads), is one a run wrote: a JSON object naming
    its ``recording`` and ``mmusv_version``."""
    return doc is not None and isinstance(doc.get("recording"), str) and "mmusv_version" in doc


def replace_outputs(out: Path, scenario: Scenario, stale: list[Path]) -> None:
    """Removes an earlier run's ``manifest.json`` (written last: a run in progress never has one) and table parts
    ``stale`` (tables of another run, replaced or killed before it finished, never mix with these) and writes this
    run's ``scenario.yaml``; the new recording is open by then (see :func:`mmusv.acquire.run`)."""
    (out / "manifest.json").unlink(missing_ok=True)
    for old in stale:
        old.unlink(missing_ok=True)
    for folder in sorted({old.parent for old in stale}):  # a table this run writes no row of is not listed
        with contextlib.suppress(OSError):
            folder.rmdir()  # only when empty
    (out / "scenario.yaml").write_text(
        yaml.safe_dump(scenario.model_dump(mode="json"), sort_keys=False), encoding="utf-8"
    )


def writes_into(exc: BaseException, out: Path) -> bool:
    """Whether ``exc`` is a failed write into the folder ``out`` (the recorder's or the tables')."""
    if isinstance(exc, OSError):
        return exc.filename is None or str(out) in str(exc.filename) or str(out) in str(exc)
    return isinstance(exc, IoError) and str(out) in str(exc)


def write_failure(out: Path, rec_path: Path, problems: list[tuple[str, BaseException]]) -> tuple[str, int]:
    """The message of a run stopped by a failed write (the cause as the system names it, what failed, the frames
    that are safe and where) and how many frames are safe."""
    cause = write_cause(out, problems[0][1])
    what = ", ".join(dict.fromkeys(w for w, _ in problems))
    partial = rec_path.with_name(rec_path.name + ".partial")
    target = partial if partial.exists() else rec_path
    safe, kept = "no frame is safe", 0
    if target.exists():
        try:
            from mmusv.recording.info import read_info
            from mmusv.recording.stream import FrameStream, frame_ranges

            stream = FrameStream(read_info(target), want=lambda _t: False)
            frames = [fr.index for fr in stream]
            kept = len(frames)
            if frames:
                safe = (
                    f"frames {frame_ranges(frames)} are safe in {target} (the last completely written frame is "
                    f"{max(frames)})"
                )
                if target == partial:
                    safe += f"; `mmusv recover {out}` finishes it once there is room"
        except MmusvError:
            pass
    return f"cannot write into {out}: {cause} (while {what}); {safe}", kept
