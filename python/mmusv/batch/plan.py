"""Planning a batch run: the scenario files, the tasks of each (a whole recording, or frame-range parts), and
which of them are already complete.

Layout of the output folder ``OUT``: one folder per scenario file, ``OUT/<file stem>/``, holding what
:func:`mmusv.acquire.run` writes (``<name>.mcap``, ``tables/``, ``scenario.yaml``, ``manifest.json``) or, for a
recording split into frame ranges, ``<name>.parts.json`` (:mod:`mmusv.recording.parts`) and one such folder per
part, ``parts/<first>-<last>/``; ``OUT/dataset.json`` (:mod:`mmusv.batch.index`); ``OUT/.mmusv/`` (one small lock
and attempt file per task, :mod:`mmusv.batch.task`).

A task is complete when its folder's ``manifest.json`` (written last by :func:`mmusv.acquire.run`, and removed
before a task starts) says ``status: complete`` with the scenario's config hash
(:func:`mmusv.config.scenario_hash`) and the frames asked for. A re-run skips a scenario whose recording is
complete in either layout; other tasks run again from scratch. A complete recording of another configuration
is replaced only with ``overwrite``, and so is a file of the recording's name that no run wrote; a
``scenario.yaml`` or ``manifest.json`` that no run wrote is never replaced (the scenario fails, naming it).
"""

from __future__ import annotations

import os
import re
import shutil
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mmusv import arguments
from mmusv.errors import ConfigError, MmusvError
from mmusv.recording.parts import (
    PARTS_SUFFIX,
    Part,
    PartsManifest,
    part_folder,
    read_parts_manifest,
    split_ranges,
    write_parts_manifest,
)

__all__ = ["STATE_DIR", "ScenarioPlan", "Task", "plan_scenarios", "prepare", "scenario_files", "task_complete"]

STATE_DIR = ".mmusv"
"""Hidden folder of ``OUT`` with one lock and attempt file per task."""

_PART_DIR = re.compile(r"^\d{6}-\d{6}$")


@dataclass(frozen=True)
class Task:
    """One unit of work for a worker: :func:`mmusv.acquire.run` of ``scenario_file`` into ``out_dir`` (absolute
    paths), all frames, the first ``frames`` or the ``frame_range`` ``(first, stop)``. Picklable."""

    key: str
    name: str
    scenario_file: str
    out_dir: str
    frames: int | None
    frame_range: tuple[int, int] | None
    expected_frames: int
    config_hash: str
    checks: bool
    state_file: str
    run_id: str
    #: The frames the route checks cover (a part of a split run: the whole run's, so each part warns as it would).
    check_frames: int | None = None

    @property
    def first_frame(self) -> int:
        """The first acquisition index this task records."""
        return 0 if self.frame_range is None else self.frame_range[0]


@dataclass
class ScenarioPlan:
    """One scenario file of the batch: what it is, where it goes, its tasks and which of them must run.
    ``error``: it cannot run (invalid file, a conflicting recording); ``parts``: the split layout to write."""

    name: str
    file: Path
    folder: Path
    scenario: str | None = None
    config_hash: str | None = None
    seed: int | None = None
    frames: int = 0
    recording: Path | None = None
    tasks: list[Task] = field(default_factory=list)
    to_run: list[Task] = field(default_factory=list)
    error: str | None = None
    parts: PartsManifest | None = None

    @property
    def split(self) -> bool:
        """Whether the recording is (planned as) parts."""
        return self.recording is not None and self.recording.name.endswith(PARTS_SUFFIX)


def scenario_files(source: str | os.PathLike[str] | Sequence[str | os.PathLike[str]]) -> list[Path]:
    """The scenario files of ``source``: a folder's ``*.yaml`` and ``*.yml`` (not ``report.yaml``), sorted, or the
    files given. Raises :class:`~mmusv.errors.ConfigError` for an empty folder or two files with the same stem
    (their output folders would clash)."""
    if isinstance(source, (str, os.PathLike)):
        src = arguments.path(source, name="source")
        if src.is_dir():
            _check_generated_whole(src)
            files = folder_entries(src)
            if not files:
                below = next((d.name for d in sorted(src.iterdir()) if d.is_dir() and folder_entries(d)), None)
                hint = f" (folders below are not searched: {below}/ holds some; give it)" if below else ""
                raise ConfigError(f"{src} holds no *.yaml or *.yml scenarios{hint}")
            for f in files:  # a broken link or a folder of a scenario's name was skipped without a word
                if not f.is_file():
                    raise ConfigError(f"{f}: {_not_a_file(f)}, not a scenario file; remove it or move it away")
            _check_stems(files)
            return [_absolute(f) for f in files]
        files = [src]
    else:
        if isinstance(source, (bytes, Mapping)) or not isinstance(source, Iterable):
            raise ConfigError(
                f"source = {arguments.shown(source)}: must be a folder of scenarios or a list of scenario files "
                "(str or pathlib.Path)"
            )
        files = [arguments.path(s, name=f"source[{i}]") for i, s in enumerate(source)]
        if not files:
            raise ConfigError("no scenario files given")
    for f in files:
        if not f.is_file():
            raise ConfigError(f"{f}: no such scenario file")
    _check_stems(files)
    return sorted((_absolute(f) for f in files), key=lambda f: f.stem)


def _check_generated_whole(folder: Path) -> None:
    """A folder a ``mmusv generate`` run was stopped in (its journal :data:`mmusv.generate.runner.JOURNAL` left,
    its ``report.json`` not written) holds part of a set: a :class:`~mmusv.errors.ConfigError` saying how to go on.
    Its scenarios were recorded and ``dataset.json`` written as for the whole set, without a word."""
    from mmusv.generate.runner import JOURNAL

    if (folder / JOURNAL).exists():
        raise ConfigError(
            f"{folder} holds part of a generated set: its mmusv generate run was stopped before the end ({JOURNAL} "
            "is there, report.json is not); run mmusv generate again with --force to generate the whole set, or "
            f"remove {folder / JOURNAL} to record the scenarios there as they are"
        )


def folder_entries(folder: Path) -> list[Path]:
    """The entries of ``folder`` a batch takes for scenario files, sorted: every ``*.yaml`` and ``*.yml`` (the run
    of one file takes either, and a folder's ``.yml`` scenarios were skipped without a word) but ``report.yaml``
    and a hidden entry that is not a file, such as the lock link ``.#a.yaml`` Emacs keeps beside a file being
    edited (a broken link, which :func:`scenario_files` refuses). Not all of them need be files."""
    found = [*folder.glob("*.yaml"), *folder.glob("*.yml")]
    return sorted(p for p in found if p.name != "report.yaml" and (p.is_file() or not p.name.startswith(".")))


def _absolute(f: Path) -> Path:
    """``f`` as an absolute path whose name is still the one given: a symbolic link named ``f`` is not followed
    (resolved, ``c.yaml -> a.yaml`` took the stem ``a``: both files recorded into ``OUT/a`` and listed as
    ``a.yaml``), while its folder is resolved as before: ``link/../scen`` is where the system finds it (a lexical
    ``os.path.abspath`` named another folder), and a folder reached through a link is named by its real path, the
    one a Ray cluster's nodes mount."""
    return f.parent.resolve() / f.name


def _not_a_file(f: Path) -> str:
    """What the folder entry ``f``, which is not a regular file, is."""
    if f.is_symlink() and not f.exists():
        return f"a broken symbolic link (to {os.readlink(f)})"
    return "a folder" if f.is_dir() else "not a regular file (a pipe, socket or device)"


def _check_stems(files: Sequence[Path]) -> None:
    """Two scenario files of one stem (``a.yaml`` and ``a.yml``, or the same name in two folders), or of stems that
    differ only in case, would share the output folder ``OUT/<stem>``: a :class:`~mmusv.errors.ConfigError`."""
    stems = [f.stem for f in files]
    dup = sorted({s for s in stems if stems.count(s) > 1})
    if dup:  # named by their files: "files ['a'] share a file stem" named neither a.yaml nor a.yml
        clash = "; ".join(" and ".join(sorted(str(f) for f in files if f.stem == s)) for s in dup)
        raise ConfigError(
            f"scenario files {clash} share a file stem; each gets the output folder OUT/<stem>: rename one"
        )
    folded: dict[str, str] = {}
    for s in stems:  # a.yaml and A.yaml: one output folder on a file system that ignores case (macOS, Windows)
        other = folded.setdefault(s.casefold(), s)
        if other != s:
            raise ConfigError(
                f"scenario files {min(other, s)!r} and {max(other, s)!r} have stems that differ only in case; each "
                "gets the output folder OUT/<stem>, one on a file system that ignores case: rename one"
            )


def _manifest(folder: Path) -> dict[str, Any] | None:
    from mmusv.jsonio import read_json

    try:
        return read_json(folder / "manifest.json")
    except MmusvError:
        return None


def task_complete(out_dir: Path, *, scenario: str, config_hash: str, frames: int, first_frame: int = 0) -> bool:
    """Whether ``out_dir`` holds a complete recording of ``scenario`` with ``config_hash``, frames
    ``first_frame .. first_frame + frames - 1``."""
    m = _manifest(out_dir)
    return (
        m is not None
        and m.get("status") == "complete"
        and m.get("config_hash") == config_hash
        and m.get("frames_written") == frames
        and m.get("frames_requested") == frames
        and m.get("first_frame", 0) == first_frame
        and m.get("recording") == f"{scenario}.mcap"
        and _ends_whole(out_dir / f"{scenario}.mcap")
    )


def _ends_whole(path: Path) -> bool:
    """Whether ``path`` is a file that starts and ends with the MCAP magic: a recording cut short or overwritten
    after its run (a copy that stopped, a file replaced) is recorded again, not skipped as complete because its
    manifest says so (a review's: a re-run skipped both, and the conversion then failed on them)."""
    from mmusv.recording.scan import MAGIC

    try:
        with path.open("rb") as f:
            head = f.read(len(MAGIC))
            size = f.seek(0, 2)
            if size < 2 * len(MAGIC):
                return False
            f.seek(size - len(MAGIC))
            return head == MAGIC and f.read(len(MAGIC)) == MAGIC
    except OSError:
        return False


def _complete_parts(path: Path, *, config_hash: str, frames: int) -> bool:
    try:
        pm = read_parts_manifest(path)
    except MmusvError:
        return False
    return (
        pm.config_hash == config_hash
        and pm.frames == frames
        and all(
            task_complete(
                (path.parent / p.recording).parent,
                scenario=pm.scenario,
                config_hash=config_hash,
                frames=p.frames,
                first_frame=p.first_frame,
            )
            for p in pm.parts
        )
    )


def _conflict(folder: Path, scenario: str, config_hash: str, frames: int, file: str) -> str | None:
    """Why ``folder`` holds a complete recording of ``scenario`` that this run would replace (made from another
    configuration, or of other frames than the ``frames`` asked for: a ``--frames 2`` run replaced complete
    recordings of every frame, which the run of one file refuses), or None."""
    m = _manifest(folder)
    if m is not None and m.get("status") == "complete":
        rec = folder / str(m.get("recording"))
        if m.get("config_hash") != config_hash:
            return f"{rec} is a complete recording of another configuration (config hash differs from {file}'s)"
        n, first = m.get("frames_written"), m.get("first_frame", 0)
        # counts only (true was read as a complete recording of 1 frame, refused as a conflict)
        counts = all(isinstance(x, int) and not isinstance(x, bool) for x in (n, first))
        if (n, first) != (frames, 0) and counts and rec.is_file():
            return (
                f"{rec} is a complete recording of frames {first}..{first + n - 1}, and this run asks for frames "
                f"0..{frames - 1} (frames = {frames})"
            )
    pm_path = folder / f"{scenario}{PARTS_SUFFIX}"
    if pm_path.is_file():
        try:
            pm = read_parts_manifest(pm_path)
        except MmusvError:
            return None
        if pm.config_hash != config_hash:
            return (
                f"{pm_path} lists the parts of a recording of another configuration (config hash differs from {file}'s)"
            )
        if pm.frames != frames and _complete_parts(pm_path, config_hash=config_hash, frames=pm.frames):
            return (
                f"{pm_path} lists the complete parts of a recording of frames 0..{pm.frames - 1}, and this run asks "
                f"for frames 0..{frames - 1} (frames = {frames})"
            )
    return None


def plan_scenarios(
    files: Sequence[Path],
    out: Path,
    *,
    frames: int | None,
    split_frames: int | None,
    overwrite: bool,
    checks: bool,
    run_id: str,
    replace: Collection[str] = (),
) -> list[ScenarioPlan]:
    """The plan of every file (see the module docstring); loading a file validates it (a failure becomes the
    plan's ``error``, never an exception). ``replace``: file stems whose complete recording of another
    configuration (or other frames) is replaced as with ``overwrite``, while one of the same is still skipped."""
    from mmusv.config import load_scenario, scenario_hash

    if split_frames is not None and split_frames < 1:
        raise ConfigError(f"split_frames = {split_frames}: must be at least 1 frame per part")
    plans: list[ScenarioPlan] = []
    for f in files:
        plan = ScenarioPlan(name=f.stem, file=f, folder=out / f.stem)
        plans.append(plan)
        try:
            sc = load_scenario(f)
        except MmusvError as exc:
            msg = str(exc)
            plan.error = msg if str(f) in msg or f.name in msg else f"{f}: {msg}"
            continue
        plan.scenario, plan.config_hash, plan.seed = sc.name, scenario_hash(sc), sc.seed
        acq = sc.acquisition.frames
        total = acq if frames is None else int(frames)
        if not 1 <= total <= acq:
            plan.error = f"{f}: frames = {frames}: must be in 1..{acq} (acquisition.frames)"
            continue
        plan.frames = total
        h, name, folder = plan.config_hash, sc.name, plan.folder
        pm_path = folder / f"{name}{PARTS_SUFFIX}"
        if not overwrite:
            if task_complete(folder, scenario=name, config_hash=h, frames=total):
                plan.recording = folder / f"{name}.mcap"
                plan.tasks = [_task(plan, f, folder, frames, None, total, checks, out, run_id)]
                continue
            if pm_path.is_file() and _complete_parts(pm_path, config_hash=h, frames=total):
                pm = read_parts_manifest(pm_path)
                plan.recording = pm_path
                plan.tasks = [
                    _task(
                        plan,
                        f,
                        (pm_path.parent / p.recording).parent,
                        None,
                        (p.first_frame, p.stop),
                        p.frames,
                        checks,
                        out,
                        run_id,
                    )
                    for p in pm.parts
                ]
                continue
            conflict = _conflict(folder, name, h, total, f.name)
            if conflict is not None and plan.name not in replace:
                plan.error = f"{conflict}; pass --overwrite (overwrite=True in Python) to replace it"
                continue
        if split_frames is not None and total > split_frames:
            ranges = split_ranges(total, split_frames)
            plan.recording = pm_path
            plan.parts = PartsManifest(
                scenario=name,
                config_hash=h,
                frames=total,
                parts=tuple(Part(a, b - a, f"parts/{part_folder(a, b)}/{name}.mcap") for a, b in ranges),
            )
            plan.tasks = [
                _task(plan, f, folder / "parts" / part_folder(a, b), None, (a, b), b - a, checks, out, run_id)
                for a, b in ranges
            ]
        else:
            plan.recording = folder / f"{name}.mcap"
            plan.tasks = [_task(plan, f, folder, frames, None, total, checks, out, run_id)]
        plan.to_run = [
            t
            for t in plan.tasks
            if overwrite
            or not task_complete(
                Path(t.out_dir), scenario=name, config_hash=h, frames=t.expected_frames, first_frame=t.first_frame
            )
        ]
        foreign = next((w for t in plan.to_run if (w := _foreign(Path(t.out_dir), name, f, overwrite))), None)
        if foreign is not None:
            plan.error, plan.tasks, plan.to_run = foreign, [], []
    return plans


def _foreign(folder: Path, scenario: str, file: Path, overwrite: bool) -> str | None:
    """Why the run of ``file`` may not write into ``folder``, a task's run folder, or None: it holds a
    ``scenario.yaml`` or ``manifest.json`` that no run wrote (refused ``--overwrite`` or not, as the run of one file
    refuses them: :func:`mmusv.run_folder.refuse_foreign_files`), or, without ``overwrite``, a ``<scenario>.mcap``
    that is no recording of an mmusv run (its header does not say so and no run's ``manifest.json`` there names
    it). A batch replaced them without a word (its tasks run with ``overwrite``: the folder is the batch's)."""
    from mmusv.errors import IoError
    from mmusv.recording.info import written_by_mmusv
    from mmusv.run_folder import is_run_manifest, refuse_foreign_files

    try:
        refuse_foreign_files(folder, str(file))
    except IoError as exc:
        return f"{file}: {exc}"
    rec = folder / f"{scenario}.mcap"
    if overwrite or not (rec.is_file() or rec.is_symlink()) or written_by_mmusv(rec):
        return None
    m = _manifest(folder)
    if is_run_manifest(m) and m["recording"] == rec.name:  # the run's, damaged since
        return None
    return (
        f"{rec} is not a recording of an mmusv run (its header does not say so, and no run's manifest.json names "
        f"it), and the run of {file.name} would replace it; move it out of {folder}, or pass --overwrite "
        "(overwrite=True in Python) to replace it"
    )


def _task(
    plan: ScenarioPlan,
    file: Path,
    out_dir: Path,
    frames: int | None,
    frame_range: tuple[int, int] | None,
    expected: int,
    checks: bool,
    out: Path,
    run_id: str,
) -> Task:
    key = plan.name if frame_range is None else f"{plan.name}@{part_folder(*frame_range)}"
    assert plan.config_hash is not None
    return Task(
        key=key,
        name=plan.name,
        scenario_file=str(file),
        out_dir=str(out_dir),
        frames=frames,
        frame_range=frame_range,
        expected_frames=expected,
        config_hash=plan.config_hash,
        checks=checks,
        state_file=str(out / STATE_DIR / f"{key}.task"),
        run_id=run_id,
        check_frames=None if frame_range is None else plan.frames,
    )


def prepare(plan: ScenarioPlan) -> None:
    """Before the tasks of ``plan`` run: removes what the other layout left in its folder (a whole recording
    when it is now split, or parts when it is now whole), part folders of another split, and writes the parts
    manifest."""
    if not plan.to_run or plan.scenario is None:
        return
    folder, name = plan.folder, plan.scenario
    remove_task_files(Path(plan.tasks[0].state_file).parent, plan.name, keep={t.key for t in plan.tasks})
    if plan.parts is None:
        (folder / f"{name}{PARTS_SUFFIX}").unlink(missing_ok=True)
        _remove_parts(folder, keep=set())
        return
    for leftover in (f"{name}.mcap", f"{name}.mcap.partial", "manifest.json", "scenario.yaml"):
        (folder / leftover).unlink(missing_ok=True)
    for old in sorted(folder.glob("tables/*/part-*.parquet")):
        old.unlink()
    _remove_parts(folder, keep={Path(t.out_dir).name for t in plan.tasks})
    assert plan.recording is not None
    from mmusv.jsonio import dump_json

    if not (plan.recording.is_file() and plan.recording.read_bytes() == dump_json(plan.parts.as_dict())):
        write_parts_manifest(plan.recording, plan.parts)  # (an unchanged manifest is left as it is)


def remove_task_files(state_dir: Path, name: str, *, keep: set[str]) -> None:
    """Removes the task files (``<name>.task``, ``<name>@<part>.task``) in ``state_dir`` of the scenario ``name``
    whose task key is not in ``keep``: those of a layout no longer used (parts of another split, the whole
    recording when it is now split) or of a scenario no longer recorded. (A worker of a killed run that still holds
    one keeps its open file; nothing takes that key again.)"""
    if not state_dir.is_dir():
        return
    for f in sorted(state_dir.iterdir()):
        if f.suffix != ".task" or f.stem in keep:
            continue
        rest = f.stem[len(name) :] if f.stem.startswith(name) else None  # (a name may hold "@" itself)
        if rest == "" or (rest is not None and rest.startswith("@") and _PART_DIR.match(rest[1:])):
            f.unlink(missing_ok=True)


def _remove_parts(folder: Path, keep: set[str]) -> None:
    parts = folder / "parts"
    if not parts.is_dir():
        return
    for d in sorted(parts.iterdir()):
        if d.is_dir() and _PART_DIR.match(d.name) and d.name not in keep:
            shutil.rmtree(d)
    if not any(parts.iterdir()):
        parts.rmdir()
