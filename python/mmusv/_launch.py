"""The ``mmusv`` command's entry point (the console script and ``python -m mmusv``): loads :mod:`mmusv.cli` and runs it.

Loading the command (its modules and its argument parser, whose sub-commands load theirs: numpy, rich) takes about half
a second; each command loads the rest (Polars, pydantic, the scenario models) when it starts. A Ctrl-C or SIGTERM
meanwhile is held until the load is done, then ends the command as one at any other moment does (``mmusv: interrupted``,
exit status 130; ``mmusv: terminated (SIGTERM)``, 143) before it starts. It was a ``KeyboardInterrupt`` traceback of
whichever import it cut; and an interrupt in the middle of an import is not safe to catch: a library's ``except`` around
its optional imports swallowed it (the run went on to its end), and one cut inside code a library builds from a string
(a dataclass's methods) made CPython end the process by SIGINT after the message (exit status -2; the command's end
clears that mark: :func:`mmusv.held_signals.forget_handled_interrupt`). Needs ``import mmusv`` to be light
(:mod:`mmusv`'s lazy names): the package's own import runs before this module's code.
"""

from __future__ import annotations

import signal
import sys
from collections.abc import Callable

from mmusv.held_signals import HeldSignals, forget_handled_interrupt

__all__ = ["main"]


def _stopped(signum: int) -> int:
    """Says why the command ends; returns its exit status, 128 + ``signum``."""
    name = "interrupted" if signum == signal.SIGINT else f"terminated ({signal.Signals(signum).name})"
    sys.stderr.write(f"mmusv: {name}\n")
    return 128 + signum


def _load() -> tuple[Callable[[], int], int | None]:
    """:func:`mmusv.cli.main` after the command's modules are loaded, and the first signal held meanwhile."""
    held = HeldSignals().hold()
    try:
        from mmusv.cli import main as cli_main
        from mmusv.cli_parser import parser

        parser()  # the sub-commands' parsers load their modules; cli_main builds it again from them at once
    finally:
        noted = held.release(hand_on=False)
    return cli_main, noted


def main() -> int:
    """Runs the ``mmusv`` command on ``sys.argv``; returns its exit status."""
    try:
        cli_main, held = _load()
        if held is not None:
            return _stopped(held)
        return cli_main()
    except KeyboardInterrupt:  # between the load and the command's own handling, or after it
        forget_handled_interrupt()
        return _stopped(signal.SIGINT)
