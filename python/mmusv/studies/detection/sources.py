"""Where the sequences of a detection study come from: recordings given on the command line (files, folders
holding a batch run's ``dataset.json`` (its complete recordings), the ``recordings`` folder of a ``mmusv dataset``
folder (the complete recordings its ``dataset.json`` lists), or other folders searched for ``*.mcap`` and parts
manifests of split recordings, through links to folders too, a folder that cannot be read refused by name:
:func:`~mmusv.recording.folders.find_recordings`), an OPV2V folder, or the bundled detection spec generated and
recorded LiDAR-only.

Sequences are split by sequence before any agent-as-ego expansion: recordings and OPV2V scenario folders without
split folders by :func:`~mmusv.studies.detection.data.split_sequences`; an OPV2V tree that already has
``train``/``validate``/``test`` folders by those folders.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from mmusv.errors import InputError, IoError, NotFoundError
from mmusv.studies.detection import BUNDLED_SPEC
from mmusv.studies.detection.data import (
    SequenceData,
    find_recordings,
    opv2v_scenarios,
    read_opv2v,
    read_recording,
    recording_name,
    recording_summary,
    split_sequences,
)
from mmusv.text import counted, given, named

__all__ = ["BUNDLED_SPEC", "Dataset", "generate_dataset", "lidar_only", "resolve_dataset"]


@dataclass(frozen=True)
class Dataset:
    """The sequences chosen for a study: ``sources`` (recording files or OPV2V scenario folders, by name) and
    the split they came from; :meth:`sequences` loads them one at a time."""

    sources: dict[str, Path]
    kind: str
    split: str

    def sequences(self) -> Iterator[SequenceData]:
        """Each chosen sequence, loaded when reached (sorted by name)."""
        for name in sorted(self.sources):
            yield self.load(name)

    def load(self, name: str) -> SequenceData:
        """The sequence ``name`` (a key of :attr:`sources`)."""
        p = self.sources[name]
        seq = read_recording(p) if self.kind == "recording" else read_opv2v(p)
        return SequenceData(name, seq.frames)

    def frames_by_sequence(self) -> dict[str, int]:
        """Frames of each sequence (cheap for recordings: from their metadata)."""
        if self.kind == "recording":
            return {n: recording_summary(p).frames_configured for n, p in self.sources.items()}
        return {
            n: len({f.stem for c in p.iterdir() if c.is_dir() for f in c.glob("*.pcd")})
            for n, p in self.sources.items()
        }

    def count_frames(self) -> int:
        """Frames over all sequences (:meth:`frames_by_sequence`)."""
        return sum(self.frames_by_sequence().values())


def _indexed_below(folder: Path) -> list[Path] | None:
    """The complete recordings below ``folder`` that the index of the folder above it lists, when that index
    (``mmusv dataset``'s ``DIR/dataset.json``) lists recordings there: ``mmusv study detection DIR/recordings``
    searched the folder instead and also read what the dataset no longer holds (a scenario the spec dropped, whose
    recording stays on disk) and recordings the index marks failed. None when there is no such index."""
    from mmusv.batch.index import INDEX_NAME, dataset_recordings, read_index
    from mmusv.errors import MmusvError

    here = folder.resolve()
    index = here.parent / INDEX_NAME
    if not index.is_file():
        return None
    try:
        doc = read_index(index)
    except MmusvError:
        return None
    prefix = f"{here.name}/"
    paths = [str(r.get("recording") or "") for r in doc["recordings"]]
    if not paths or not all(r.startswith(prefix) for r in paths if r):
        return None
    return [folder / r.relative_to(here) for r in dataset_recordings(index) if r.is_relative_to(here)]


def _recordings(inputs: Sequence[str | Path]) -> list[Path]:
    from mmusv.batch.index import dataset_recordings, find_index

    out: list[Path] = []
    for x in inputs:
        p = Path(x)
        if p.is_dir():
            index = find_index(p)
            indexed = _indexed_below(p) if index is None else None
            if index is not None:
                found = dataset_recordings(index)
            elif indexed is not None:
                found = indexed
            else:
                found = find_recordings(p)
            if not found and indexed is not None:
                raise InputError(
                    f"{p}: {p.resolve().parent / 'dataset.json'} lists no complete recording in this folder"
                )
            if not found:
                raise InputError(f"{p}: folder holds no .mcap recording{_opv2v_hint(p)}")
            out.extend(found)
        elif p.is_file():
            out.append(p)
        else:
            raise IoError(f"{p}: no such recording or folder")
    return out


def _opv2v_hint(folder: Path) -> str:
    """``"; it is an OPV2V folder: give it as opv2v = '...'"`` (``--opv2v ...`` from a command,
    :func:`mmusv.text.given`) when ``folder`` is one (``mmusv convert --to opv2v``'s output), else empty: it was said
    to hold no recording, with no word of the option that reads it."""
    from mmusv.errors import MmusvError
    from mmusv.studies.detection.data import opv2v_scenarios

    try:
        opv2v_scenarios(folder)
    except (MmusvError, OSError):
        return ""
    return f"; it is an OPV2V folder: give it as {given('opv2v', folder)}"


def _sequence_names(recs: Sequence[Path]) -> dict[str, Path]:
    """Sequence name → recording: the recording's name (file name without ``.mcap`` / ``.parts.json``), or, when
    two recordings share a name, the path below the inputs' common folder to it (``island/recordings/x/x``)."""
    import os

    uniq = sorted({r.resolve() for r in recs})
    if len(uniq) != len(recs):
        by: dict[Path, list[Path]] = {}
        for r in recs:
            by.setdefault(r.resolve(), []).append(r)
        twice = next(paths for paths in by.values() if len(paths) > 1)
        raise InputError(
            f"the same recording is given twice: {twice[0]} and {twice[1]}"
            + (f" (both {twice[0].resolve()})" if twice[0] != twice[1] else "")
        )
    _refuse_same_runs(uniq)
    stems = [recording_name(r) for r in uniq]
    if len(set(stems)) == len(stems):
        return dict(zip(stems, uniq, strict=True))
    root = Path(os.path.commonpath([str(r.parent) for r in uniq]))
    return {str(r.parent.relative_to(root) / recording_name(r)): r for r in uniq}


def _refuse_same_runs(recs: Sequence[Path]) -> None:
    """Refuses two recordings of one scenario configuration (a copy of a run folder, or a scenario run twice): the
    same scenario and seed give the same data, which would count as two sequences, and may land in the training and
    the test split both. A file whose metadata cannot be read is left to the reading of its frames to report."""
    from mmusv.errors import MmusvError

    by: dict[str, list[Path]] = {}
    for r in recs:
        try:
            key = recording_summary(r).config_hash
        except (MmusvError, OSError):
            continue
        if key:
            by.setdefault(key, []).append(r)
    same = next((paths for paths in by.values() if len(paths) > 1), None)
    if same is not None:
        raise InputError(
            f"recordings {', '.join(str(r) for r in same)} are runs of the same scenario configuration (the same "
            "scenario and seed give the same data: studied together, each frame would count twice, and could be in "
            "both the training and the test split); give each only once, leaving the others out"
        )


def resolve_dataset(
    inputs: Sequence[str | Path],
    *,
    opv2v: str | Path | None,
    split: str,
    ratios: Sequence[float] = (0.7, 0.15, 0.15),
    seed: int = 0,
) -> Dataset:
    """The sequences of ``split`` from recordings ``inputs`` or the OPV2V folder ``opv2v`` (not both). Raises
    :class:`~mmusv.InputError` when nothing is given or the split is empty. The messages name the arguments as their
    user gave them (:func:`mmusv.text.given`: ``opv2v = '...'``, ``split = 'test'``; ``--opv2v``, ``--split`` and
    ``--generate`` from ``mmusv study`` and ``mmusv train``: :data:`mmusv.studies.detection.cli.DATASET_FLAGS`)."""
    if inputs and opv2v is not None:
        raise InputError(f"give {named('inputs')} or {named('opv2v')}, not both")
    if opv2v is not None:
        folders = opv2v_scenarios(opv2v, name="opv2v")
        kind = "opv2v"
        names = {
            f.name if f.parent.name not in ("train", "validate", "test") else f"{f.parent.name}/{f.name}": f
            for f in folders
        }
        presplit = all(f.parent.name in ("train", "validate", "test") for f in folders)
        if presplit and split != "all":
            chosen = {n: f for n, f in names.items() if f.parent.name == split}
        else:
            chosen = {n: names[n] for n in split_sequences(list(names), split=split, ratios=ratios, seed=seed)}
        chosen = {n.split("/")[-1]: f for n, f in chosen.items()}
    else:
        recs = _recordings(inputs)
        if not recs:
            gen = [named("generate")] if named("generate") != "generate" else []  # a command's --generate
            choices = [f"{named('inputs')} (.mcap files or folders of them)", named("opv2v"), *gen]
            raise InputError(f"empty dataset: give {', '.join(choices[:-1])} or {choices[-1]}")
        kind = "recording"
        by_name = _sequence_names(recs)
        chosen = {n: by_name[n] for n in split_sequences(list(by_name), split=split, ratios=ratios, seed=seed)}
    if not chosen:
        where = opv2v if opv2v is not None else ", ".join(str(x) for x in inputs)
        raise InputError(f"empty dataset: split {split!r} of {where} holds no sequence (try {given('split', 'all')})")
    return Dataset(chosen, kind, split)


def lidar_only(data: dict[str, Any]) -> dict[str, Any]:
    """A scenario dict whose rigs keep only their LiDAR (no cameras, radar or top view)."""
    out = dict(data)
    rigs = out.get("rigs") or {}
    out["rigs"] = {
        name: {**(r or {}), "cameras": [], "radar": None, "top_view": None} if isinstance(r, dict) or r is None else r
        for name, r in rigs.items()
    }
    return out


def generate_dataset(
    out_dir: str | Path,
    *,
    spec: str | Path = BUNDLED_SPEC,
    progress: Callable[[str, int, int], None] | None = None,
    shortfall: Callable[[str], None] | None = None,
) -> list[Path]:
    """Generates ``spec`` into ``out_dir/scenarios``, writes their LiDAR-only versions into ``out_dir/lidar_only``
    and records those with the batch runner (:func:`mmusv.batch.run_many`) into ``out_dir/recordings/<name>/``;
    returns the recordings. A complete recording of the same configuration is kept (delete ``out_dir`` to redo
    it); one of a scenario the spec now makes otherwise is recorded again. ``progress``: ``("recording", frames
    done, frames in all)``. When a quota was not met, ``shortfall`` is called with how many scenarios were
    generated of how many asked for, then with one line per role combination whose quota the generator did not
    meet, with the generator's reason
    (:meth:`mmusv.generate.report.ComboReport.why`). Raises :class:`~mmusv.InputError` when a scenario could not
    be recorded; its messages name ``spec`` as its user gave it (``--generate`` from a command,
    :func:`mmusv.text.given`)."""
    from mmusv.batch import dataset_recordings, run_many
    from mmusv.bundled import resolve_spec
    from mmusv.generate.runner import generate

    try:
        sp = resolve_spec(spec)
    except NotFoundError as exc:  # (it said "spec file ..." without the flag that gave it)
        raise NotFoundError(f"{given('spec', spec)}: {exc}") from None
    out = Path(out_dir)
    scen_dir, lidar_dir = out / "scenarios", out / "lidar_only"
    gen = generate(sp, scen_dir, force=True)
    if shortfall is not None and not gen.all_met:
        shortfall(f"{gen.accepted} of the {counted(sum(c.quota for c in gen.combos), 'scenario')} the spec asks for")
        for c in gen.combos:
            if not c.met:
                shortfall(f"quota not met {c.name}: {c.why()}")
    files = sorted(scen_dir.glob("*.yaml"))
    if not files:
        raise InputError(f"{given('spec', sp)}: produced no scenario (see {scen_dir / 'report.json'})")
    lidar_dir.mkdir(parents=True, exist_ok=True)
    for old in lidar_dir.glob("*.yaml"):
        old.unlink()
    for f in files:
        data = lidar_only(yaml.safe_load(f.read_text(encoding="utf-8")))
        (lidar_dir / f.name).write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    report = run_many(
        lidar_dir,
        out_dir=out / "recordings",
        progress=None if progress is None else (lambda done, total: progress("recording", done, total)),
        # out_dir/recordings is this command's own: a scenario that a changed spec changed is recorded again (it
        # failed as "a complete recording of another configuration", with no --overwrite to pass)
        replace={f.stem for f in files},
    )
    failed = [o for o in report.outcomes if o.status == "failed"]
    if failed:
        raise InputError(
            f"{given('spec', sp)}: {len(failed)} of {counted(len(files), 'scenario')} could not be recorded; "
            f"first: {failed[0].error}"
        )
    return dataset_recordings(out / "recordings")
