"""The ``mmusv`` command line (placeholder entry point; subcommands are added in :mod:`mmusv.cli`)."""

from __future__ import annotations

import sys


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``mmusv`` command."""
    from mmusv import __version__

    args = sys.argv[1:] if argv is None else argv
    if args and args[0] in {"--version", "version"}:
        print(f"mmusv {__version__}")
        return 0
    print("usage: mmusv --version")
    return 2
