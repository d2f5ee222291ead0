"""The paths the command line is given, checked by their flag before any work: an empty path is never the current
folder (``mmusv info ""`` read ``.``, ``-o ""`` wrote there), an output path must be UTF-8, and an output folder
must not lie under a file. One :class:`~mmusv.errors.ConfigError` naming the flag; used by ``mmusv`` and every
subcommand's module (``batch``, ``editor``, ``generate``, ``learn``, ``studies.detection``)."""

from __future__ import annotations

from pathlib import Path

from mmusv import arguments
from mmusv.errors import ConfigError

__all__ = ["check_output_folder", "output_arg", "path_arg"]


def path_arg(value: str, *, flag: str, empty: str = "give a path") -> str:
    """``value``, the path given to ``flag``, as it is; :class:`~mmusv.errors.ConfigError` naming ``flag`` (and
    ending in ``empty``) when it is empty: an empty path quietly meant the current folder (``mmusv info ""`` read
    ``.``, ``-o ""`` wrote there)."""
    if value == "":
        raise ConfigError(f"{flag} is empty: {empty}")
    arguments.path(value, name=flag)  # a NUL character, from a caller in Python
    return value


def output_arg(value: str, *, flag: str = "-o/--output") -> str:
    """``value``, the output path given to ``flag``, as it is: not empty (:func:`path_arg`) and valid UTF-8. A
    name with bytes that are not UTF-8 was written halfway (the recording, the table) before the Parquet or CSV
    writer failed with a traceback."""
    path_arg(value, flag=flag, empty='give a path ("." for the current folder)')
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
    out = Path(output_arg(value, flag=flag))
    for q in (out, *out.parents):
        if q.exists():
            if not q.is_dir():
                raise ConfigError(f"{flag} {value}: {q} is a file, not a folder")
            break
    return out
