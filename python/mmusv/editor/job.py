"""``python -m mmusv.editor.job SCENARIO OUT [--frames N]``: one ``mmusv run`` for the editor, in its own process.

It calls :func:`mmusv.acquire.run` (what ``mmusv run SCENARIO -o OUT --overwrite`` runs) and reports on stdout one
JSON object per line: ``{"done": k, "total": n}`` after every frame, ``{"warning": "..."}`` for each check warning,
and last ``{"status": "complete", "frames": k, "recording": path, "seconds": s}``, ``{"status": "failed",
"error": "..."}`` (exit status 2) or ``{"status": "interrupted", ...}`` after SIGINT (after an empty line, which
ends a line the stop may have cut short; exit status 130; the
recording then holds every completed frame, and the line names it and its frames as for a complete run). A stop
that comes once every frame is written changes nothing: the line says ``complete`` (exit status 0), as the recording
and its manifest do. The stop is handled as ``mmusv run`` handles it (:mod:`mmusv.held_signals`): held while the run's
modules load, and noted, so that a stop a library swallows or makes an error of its own ends the run as a stop.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import warnings
from typing import Any

__all__ = ["main"]


def _say(obj: dict[str, Any]) -> None:
    """One line of ``obj``'s JSON, written whole in one call: ``print`` wrote the text and its newline apart, and a
    stop between the two ran the status line on after a progress line (``{"done": 1, ...}{"status": ...}``), a line
    the editor could not read, so it said "stopped before the first frame" of a run whose recording held frames."""
    sys.stdout.write(json.dumps(obj) + "\n")
    sys.stdout.flush()


def _kept(args: argparse.Namespace) -> dict[str, Any]:
    """``status``, ``frames`` and ``recording`` of a stopped run, as its ``manifest.json`` (written on the way out)
    names them; empty when it has none (stopped before its recording opened). The status line said ``"recording":
    null`` of a recording holding every completed frame."""
    from pathlib import Path

    from mmusv.jsonio import read_json_or_none

    out = Path(args.output)
    manifest = read_json_or_none(out / "manifest.json") or {}
    name, frames, status = manifest.get("recording"), manifest.get("frames_written"), manifest.get("status")
    if not isinstance(name, str) or not (out / name).is_file():
        return {}
    return {
        "recording": str(out / name),
        **({"frames": frames} if isinstance(frames, int) else {}),
        **({"status": status} if isinstance(status, str) else {}),
    }


def main(argv: list[str] | None = None) -> int:
    """Runs the scenario; returns the exit status (see the module docstring)."""
    p = argparse.ArgumentParser(prog="python -m mmusv.editor.job")
    p.add_argument("scenario")
    p.add_argument("output")
    p.add_argument("--frames", type=int, default=None)
    args = p.parse_args(argv)

    def _warn(message: Warning | str, *rest: object, **kw: object) -> None:
        _say({"warning": str(message)})

    warnings.showwarning = _warn
    from mmusv.held_signals import HeldSignals, StopSignals, forget_handled_interrupt

    # A stop while the run's modules load is held to the end of the load, not raised inside it: a library's
    # ``except`` around an optional import swallowed it, and the run went on to its last frame (as mmusv._launch).
    held = HeldSignals().hold()
    try:
        from mmusv.acquire import run
        from mmusv.errors import MmusvError
    finally:
        noted = held.release(hand_on=False)
    if noted is not None:
        _say({"status": "interrupted", "error": "stopped before the first frame"})
        return 128 + noted
    # The stop is noted as ``mmusv run`` notes it (held_signals): raised again at the next frame where a library
    # swallowed its KeyboardInterrupt (the run went on to its last frame and said "complete"), and an error a library
    # made of it is the stop (a traceback, no status line: "the run process ended with status 1").
    with StopSignals() as stops:
        res = None
        try:
            res = run(
                args.scenario,
                out_dir=args.output,
                overwrite=True,
                frames=args.frames,
                progress=lambda done, total: _say({"done": done, "total": total}),
            )
        except KeyboardInterrupt:
            pass
        except MmusvError as exc:
            if stops.received is None:
                _say({"status": "failed", "error": str(exc)})
                return 2
        except Exception:
            if stops.received is None:
                raise
        # From here a stop changes nothing: a second one would cut the status line, and one after a complete run
        # (the editor's button pressed as it ended, or one a library swallowed in the last frame) is too late. It
        # ended the process with a traceback before the status line, and the editor then said "stopped before the
        # first frame" of a complete run.
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        forget_handled_interrupt()
        if res is not None:
            _say(
                {
                    "status": res.status,
                    "frames": res.frames_written,
                    "recording": str(res.recording),
                    "seconds": round(res.seconds, 3),
                }
            )
            return 0
        kept = _kept(args)
        if kept.get("status") == "complete":  # every frame was written before the stop came
            _say({**kept, "seconds": None})
            return 0
        kept.pop("status", None)
        # A newline first ends any line the stop cut short (the editor passes an empty line over).
        sys.stdout.write("\n")
        _say({"status": "interrupted", "error": "stopped; the recording holds every completed frame", **kept})
        return 128 + (stops.received or signal.SIGINT)


if __name__ == "__main__":
    sys.exit(main())
