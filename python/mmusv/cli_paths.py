"""The paths the command line is given, checked by their flag before any work: an empty path is never the current
folder (``mmusv info ""`` read ``.``, ``-o ""`` wrote there), an output path must be UTF-8, and an output folder
must not lie under a file. One :class:`~mmusv.errors.ConfigError` naming the flag; used by ``mmusv`` and every
subcommand's module (``batch``, ``editor``, ``generate``, ``learn``, ``studies.detection``)."""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path

from mmusv import arguments
from mmusv.errors import ConfigError, IoError

__all__ = [
    "check_output_folder",
    "made_output_folder",
    "output_arg",
    "path_arg",
    "ready_output_folder",
    "refuse_replacing",
]


def path_arg(value: str, *, flag: str, empty: str = "give a path") -> str:
    """``value``, the path given to ``flag``, as it is; :class:`~mmusv.errors.ConfigError` naming ``flag`` (and
    ending in ``empty``) when it is empty: an empty path quietly meant the current folder (``mmusv info ""`` read
    ``.``, ``-o ""`` wrote there)."""
    if value == "":
        raise ConfigError(f"{flag} is empty: {empty}")
    arguments.path(value, name=flag)  # a NUL character, from a caller in Python
    _check_locale(value, flag=flag)
    return value


def _check_locale(value: str, *, flag: str) -> None:
    """A path that is not ASCII under a locale whose encoding is not UTF-8 (``LC_ALL=en_US.ISO-8859-1``, or
    ``LC_ALL=C`` with ``PYTHONUTF8=0``): Python names the file with the locale's bytes, the core and Polars with
    UTF-8's, so they meet different files. ``mmusv run X -o "out é"`` wrote the recording, then failed writing
    its tables (``No such file or directory``); ``mmusv info`` called intact tables unreadable, ``recover``
    failed. :class:`~mmusv.errors.ConfigError` naming ``flag``, the locale and the two ways out."""
    encoding = sys.getfilesystemencoding()
    if value.isascii() or encoding.lower().replace("-", "").replace("_", "") in ("utf8", "utf8mb4"):
        return
    raise ConfigError(
        f"{flag} {arguments.shown(value)}: a path that is not ASCII needs a UTF-8 locale, and this one names files "
        f"in {encoding} (LC_ALL/LC_CTYPE/LANG = {_locale_name()!r}); run with PYTHONUTF8=1 or LC_ALL=C.UTF-8"
    )


def _locale_name() -> str:
    for name in ("LC_ALL", "LC_CTYPE", "LANG"):
        if os.environ.get(name):
            return os.environ[name]
    return ""


def output_arg(value: str, *, flag: str = "-o/--output") -> str:
    """``value``, the output path given to ``flag``, as it is: not empty (:func:`path_arg`) and valid UTF-8. A
    name with bytes that are not UTF-8 was written halfway (the recording, the table) before the Parquet or CSV
    writer failed with a traceback."""
    path_arg(value, flag=flag, empty='give a path ("." for the current folder)')  # and the locale's encoding
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        raise ConfigError(
            f"{flag} {arguments.shown(value)}: the path holds bytes that are not UTF-8; give a UTF-8 path"
        ) from None
    return value


def check_output_folder(value: str, *, flag: str = "-o/--output") -> Path:
    """``value`` (:func:`output_arg`) as the output folder of ``flag``, checked without creating anything: it, or
    the nearest of its parents that exists, is a folder. A file there was named only after the computing."""
    from mmusv.recording.guard import file_in_the_way

    out = Path(output_arg(value, flag=flag))
    blocking = file_in_the_way(out)
    if blocking is not None:
        raise ConfigError(f"{flag} {value}: {blocking} is a file, not a folder")
    return out


def ready_output_folder(output: str, *, flag: str = "-o/--output") -> None:
    """Creates a command's output folder before its work, so that a folder that cannot be written is named (as
    ``flag``) at once, not after the computing."""
    check_output_folder(output, flag=flag)  # a file there (or above) is named as such, not as "File exists"
    try:
        Path(output).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise IoError(f"{flag} {output}: cannot create the folder: {exc.strerror or exc}") from None


def refuse_replacing(
    folder: str | os.PathLike[str],
    names: Iterable[str],
    *,
    overwrite: bool,
    flag: str = "-o/--output",
    how: str = "pass --overwrite",
) -> None:
    """Raises :class:`~mmusv.errors.IoError` unless ``overwrite`` when a file (or anything else) of one of
    ``names`` (paths relative to ``folder``) is already there, before any work: a command that writes files of
    fixed names into an existing folder (``mmusv assets --render``, ``mmusv study ... -o``) replaced a user's
    files of those names without a word. The message names the folder by ``flag``, the files and ``how`` to
    replace them (``pass --overwrite``; ``overwrite=True`` for a Python caller). A folder (or another non-file) of
    one of ``names`` is refused even with ``overwrite``, which replaces files only: it was named only when the
    files were written, after the work (a whole study), and said to need ``--overwrite`` without it."""
    base = Path(folder)
    names = list(names)
    blocked = [n for n in names if (base / n).exists() and not (base / n).is_file()]
    if blocked:
        shown = ", ".join(blocked[:4]) + (f" and {len(blocked) - 4} more" if len(blocked) > 4 else "")
        one = len(blocked) == 1
        what = "is a folder (or another non-file)" if one else "are folders (or other non-files)"
        raise IoError(
            f"{flag} {os.fspath(folder)}: {shown} {what}, "
            f"where {'a file' if one else 'files'} of {'that name is' if one else 'those names are'} written; "
            f"remove {'it' if one else 'them'}, or give another folder"
        )
    if overwrite:
        return
    taken = [n for n in names if os.path.lexists(base / n)]
    if not taken:
        return
    shown = ", ".join(taken[:4]) + (f" and {len(taken) - 4} more" if len(taken) > 4 else "")
    raise IoError(
        f"{flag} {os.fspath(folder)}: {shown} {'is' if len(taken) == 1 else 'are'} already there (from an earlier "
        f"run, or files of yours); {how} to replace {'it' if len(taken) == 1 else 'them'}, or give another folder"
    )


@contextlib.contextmanager
def made_output_folder(output: str, *, flag: str = "-o/--output") -> Iterator[Path]:
    """:func:`ready_output_folder` for the work of the ``with`` block: when the block fails or is interrupted
    (Ctrl-C, SIGTERM), the folders it created are removed again if they are still empty (``mmusv study agreement``
    stopped in its first scenario left an empty ``-o`` folder behind). A folder that existed before, or one the
    work wrote into, is left as it is."""
    out = Path(output)
    made = []  # the folders that do not exist yet, deepest first: those that ready_output_folder creates
    for q in (out, *out.parents):
        if os.path.lexists(q):
            break
        made.append(q)
    ready_output_folder(output, flag=flag)
    try:
        yield out
    except BaseException:
        for q in made:
            try:
                q.rmdir()  # only an empty folder
            except OSError:
                break
        raise
