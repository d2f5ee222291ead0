"""The output folder of a conversion (:func:`mmusv.export.convert`): checked, locked against a second conversion
into it, and, when ``overwrite`` replaces a previous conversion, written as a staging folder beside it that is
swapped in only once the new conversion is complete (the previous one stays when it fails); its report says what
became of a conversion that stopped halfway in a folder of its own."""

from __future__ import annotations

import contextlib
import glob
import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from mmusv.errors import IoError, MmusvError
from mmusv.export.common import dump_yaml, naming
from mmusv.export.convert_report import REPORT_NAME
from mmusv.recording.guard import FolderLock
from mmusv.recording.info import written_by_mmusv
from mmusv.text import counted

__all__ = ["contents", "prepare_out", "reported", "staged"]


def prepare_out(out: Path, overwrite: bool, inputs: list[Path]) -> tuple[Path, FolderLock]:
    """Checks ``out``, locks it (:class:`~mmusv.recording.guard.FolderLock`: a second conversion into it, from
    another process or thread, is refused instead of mixing its files with this one's) and returns the folder to
    write into, with the lock to release when done: ``out`` itself (created), or, when ``overwrite`` replaces a
    previous conversion there, a staging folder beside it that :func:`staged` swaps in once the new conversion is
    complete, so that one failing halfway (a full disk) leaves the previous one as it was. Where ``out`` cannot be
    swapped (it is, or holds, the working folder, e.g. ``-o .``; it is a link; its parent takes no new folder) the
    previous conversion is emptied in place instead."""
    if out.exists() and not out.is_dir():
        raise IoError(f"output {out} exists and is not a folder")
    # The output folder is replaced on --overwrite: it may not hold a recording being converted.
    home = out.resolve()
    for p in inputs:
        where = p.resolve()
        if where == home or home in where.parents:
            raise IoError(
                f"output folder {out} holds {p}, which is being converted; write the conversion to another folder"
            )
    lock = FolderLock.create(out, what="mmusv convert")
    try:
        return _prepare_locked(out, home, overwrite), lock
    except BaseException:
        lock.release()
        raise


def _prepare_locked(out: Path, home: Path, overwrite: bool) -> Path:
    """:func:`prepare_out` once ``out`` exists and is locked."""
    if any(out.iterdir()):
        if not overwrite and not (out / REPORT_NAME).is_file():  # --overwrite would refuse it too: not a hint
            raise IoError(
                f"output folder {out} already exists, is not empty and holds no {REPORT_NAME} of a previous "
                "conversion; choose another folder (-o)"
            )
        if not overwrite:
            raise IoError(
                f"output folder {out} already exists and holds a conversion; pass --overwrite (overwrite=True in "
                "Python) to replace it"
            )
        if not (out / REPORT_NAME).is_file():
            raise IoError(
                f"output folder {out} is not empty and holds no {REPORT_NAME} from a previous conversion; "
                "refusing to delete it, choose another folder"
            )
        _check_only_a_conversion(out)
        here = Path.cwd().resolve()
        if not out.is_symlink() and home != here and home not in here.parents:
            _remove_stale_stages(out)
            stage = out.parent / f".{out.name}.converting-{os.getpid()}"
            try:
                if stage.exists():
                    shutil.rmtree(stage)
                stage.mkdir()
                return stage
            except OSError:
                pass  # the parent takes no new folder: replaced in place
        for child in sorted(out.iterdir()):
            if child.is_dir() and not child.is_symlink():
                shutil.rmtree(child)
            else:
                child.unlink()
    return out


RUN_FILES = ("manifest.json", "dataset.json")
"""Files of a recording's run folder or a batch that no conversion writes."""
RUN_SUFFIXES = (".mcap.partial", ".parts.json", ".parquet")
"""Endings of a recording's files (a killed run's, a split recording's manifest, its tables) no conversion writes."""


def contents(folder: Path) -> dict[str, Any]:
    """What a conversion wrote into ``folder`` besides its report, kept in the report so that ``--overwrite`` can
    tell it from what was added since: its top-level ``entries`` (sorted names) and the number of ``files`` below
    it (links not followed)."""
    entries = sorted(p.name for p in folder.iterdir() if p.name != REPORT_NAME)
    files = sum(len(names) for _root, _dirs, names in os.walk(folder)) - int((folder / REPORT_NAME).exists())
    return {"entries": entries, "files": files}


def _check_only_a_conversion(out: Path) -> None:
    """Refuses (:class:`~mmusv.errors.IoError`) to replace ``out`` when it holds what its previous conversion did
    not write: a recording or a batch anywhere below (``--overwrite`` deleted a folder that had a
    ``conversion.yaml`` at its top, recordings and all), or, where its report says what the conversion wrote
    (:func:`contents`), another top-level entry or more files than that."""
    found: list[str] = []
    for root, _dirs, names in os.walk(out):
        for name in sorted(names):
            path = Path(root) / name
            if name in RUN_FILES or name.endswith(RUN_SUFFIXES) or (name.endswith(".mcap") and written_by_mmusv(path)):
                found.append(str(path))
    if found:
        raise IoError(
            f"output folder {out} holds {_listed(found)}, which no conversion writes (a recording, its tables or a "
            "batch); refusing to delete it: convert into another folder, or move them out first"
        )
    try:
        import yaml

        said = yaml.safe_load((out / REPORT_NAME).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return  # a report cut short (a conversion killed while writing it): the recordings check above stands
    wrote = said.get("contents") if isinstance(said, dict) else None
    if not isinstance(wrote, dict):
        return  # a conversion that did not finish, or from before the record
    entries, files = wrote.get("entries"), wrote.get("files")
    if isinstance(entries, list):
        extra = sorted(p.name for p in out.iterdir() if p.name != REPORT_NAME and p.name not in entries)
        if extra:
            raise IoError(
                f"output folder {out} holds {_listed([str(out / e) for e in extra])} besides the conversion its "
                f"{REPORT_NAME} describes; refusing to delete what no conversion wrote: convert into another folder, "
                "or move them out first"
            )
    if isinstance(files, int) and not isinstance(files, bool):
        now = contents(out)["files"]
        if now > files:
            raise IoError(
                f"output folder {out} holds {counted(now - files, 'file')} more than the conversion its {REPORT_NAME} "
                f"describes wrote ({files}); refusing to delete what no conversion wrote: convert into another "
                "folder, or move them out first"
            )


def _listed(paths: list[str]) -> str:
    """Up to three paths, and how many more."""
    more = len(paths) - 3
    return ", ".join(paths[:3]) + (f" and {more} more" if more > 0 else "")


def _remove_stale_stages(out: Path) -> None:
    """Removes the staging and replaced folders beside ``out`` left by conversions that were killed (their process
    no longer runs): ``.<name>.converting-<pid>`` and ``.<name>.replaced-<pid>``."""
    for kind in ("converting", "replaced"):
        for left in out.parent.glob(f".{glob.escape(out.name)}.{kind}-*"):  # a folder a[1] is no pattern
            pid = left.name.rpartition("-")[2]
            if not pid.isdigit() or not left.is_dir() or left.is_symlink():
                continue
            try:
                os.kill(int(pid), 0)
            except ProcessLookupError:
                shutil.rmtree(left, ignore_errors=True)
            except (PermissionError, OverflowError, ValueError):
                continue


@contextlib.contextmanager
def staged(work: Path, out: Path) -> Iterator[None]:
    """Around a conversion written into ``work`` (:func:`prepare_out`): when that is a staging folder, swaps it in
    for ``out`` on success (the previous conversion is removed only then) and removes it on failure (the previous
    conversion stays)."""
    if work == out:
        yield
        return
    try:
        yield
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        raise
    old = out.parent / f".{out.name}.replaced-{os.getpid()}"
    try:
        os.replace(out, old)
        try:
            os.replace(work, out)
        except OSError:
            os.replace(old, out)
            raise
    except OSError as exc:
        shutil.rmtree(work, ignore_errors=True)
        raise IoError(f"cannot replace {out} with the new conversion: {exc.strerror or exc}") from None
    shutil.rmtree(old, ignore_errors=True)


@contextlib.contextmanager
def reported(report: Path, header: dict[str, Any]) -> Iterator[None]:
    """Around a conversion whose report is ``report``: writes it first with ``status: in_progress`` and, when the
    conversion stops with an exception, rewrites it with ``status: failed`` and the ``error``, or ``status:
    interrupted`` for a stop (Ctrl-C, or SIGTERM through the command line's handler: a ``KeyboardInterrupt``, as a
    recording's run metadata say it), so that a folder left with part of a conversion says so and why; the files
    already written stay. (Inside a staging folder, :func:`staged` then removes it all.) The conversion writes the
    complete report itself."""
    try:
        report.write_bytes(dump_yaml({**header, "status": "in_progress"}))
    except OSError as exc:  # a full disk: no report at all rather than an empty one, which read as a conversion
        with contextlib.suppress(OSError):
            report.unlink(missing_ok=True)
        raise naming(exc, report) from exc
    try:
        yield
    except BaseException as exc:
        if isinstance(exc, KeyboardInterrupt):
            ended: dict[str, Any] = {"status": "interrupted"}
        else:
            error = str(exc) if isinstance(exc, MmusvError) else f"{type(exc).__name__}: {exc}".rstrip(": ")
            ended = {"status": "failed", "error": error}
        # where even this cannot be written (a full disk), the report is left empty or cut: not complete either
        with contextlib.suppress(OSError):
            report.write_bytes(dump_yaml({**header, **ended}))
        raise
