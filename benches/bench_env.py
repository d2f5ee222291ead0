"""What every script in ``benches/`` shares: the packages it needs, named with the command that installs them
(a missing one ends the script with that line and exit status 2, not a traceback), the machine it ran on, the
command-line checks of counts (``--frames 0`` is refused by argparse, not met as a division by zero) and the
one-line report of mmusv's own errors (:func:`run`).

Imported first by every script (``import bench_env``): it checks at import that ``mmusv`` itself is there.
"""

from __future__ import annotations

import argparse
import importlib
import os
import platform
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

INSTALL_MMUSV = "pip install .  (or `make install`; `make dev` for an editable install)"
"""How to install mmusv from this checkout."""


def require(module: str, install: str, why: str = "") -> ModuleType:
    """``module`` imported, or exit status 2 with one line naming it and the command that installs it (an
    ``OSError`` at import, a missing system library such as Open3D's libgomp, is reported the same way)."""
    try:
        return importlib.import_module(module)
    except (ImportError, OSError) as exc:
        for_what = f" ({why})" if why else ""
        sys.stderr.write(f"{Path(sys.argv[0]).name}: needs {module}{for_what}: {exc}\n  install it: {install}\n")
        raise SystemExit(2) from None


def available_cpus() -> int:
    """CPUs this process may run on (its affinity where the OS says, else the machine's count)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo`` on Linux, else what :mod:`platform` says), with its widest x86
    vector extension (the core's SIMD paths are chosen from them at run time)."""
    name, flags = "", set[str]()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            if key.strip() == "model name" and not name:
                name = value.strip()
            elif key.strip() == "flags" and not flags:
                flags = set(value.split())
    except OSError:
        pass
    name = name or platform.processor() or platform.machine() or "unknown CPU"
    simd = next((f for f in ("avx512f", "avx2", "sse4_2") if f in flags), "")
    return f"{name}{f' ({simd})' if simd else ''}"


def machine() -> str:
    """One line: CPU model, the CPUs this process may use of the machine's, OS, Python, the load average (the
    machine may be shared: compare figures taken at the same load), the core's code paths
    (:func:`mmusv._core.simd_level`) and the variables the environment sets for them and the threads."""
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    env = [f"{k}={os.environ[k]}" for k in ("RAYON_NUM_THREADS", "MMUSV_SIMD") if os.environ.get(k)]
    try:  # the code paths the core runs in this process (AVX2 + FMA or portable), as it chose them
        from mmusv._native import core

        paths = f"; core paths {core.simd_level()}"
    except ImportError:
        paths = ""
    return (
        f"machine: {cpu_model()}, {available_cpus()} of {os.cpu_count()} CPUs available, {platform.system()} "
        f"{platform.machine()}, Python {platform.python_version()}; load average {load}{paths}"
        + (f"; {', '.join(env)}" if env else "")
    )


def positive_int(text: str) -> int:
    """An argparse type: a whole number of at least 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value}: give 1 or more")
    return value


def description(doc: str | None) -> str:
    """The first paragraph of a script's docstring as one line (argparse's description: the first line alone
    stopped mid-sentence)."""
    first = (doc or "").strip().split("\n\n")[0]
    return " ".join(first.split())


def run(main: Callable[[], int | None]) -> None:
    """Runs a script's ``main``: mmusv's own errors (a scenario file that is not there, an unknown sea preset)
    end it with their one-line message and exit status 2, as ``mmusv`` itself does, not a traceback."""
    mmusv = sys.modules["mmusv"]
    try:
        code = main()
    except mmusv.MmusvError as exc:
        message = exc.args[0] if len(exc.args) == 1 and isinstance(exc.args[0], str) else str(exc)
        sys.stderr.write(f"{Path(sys.argv[0]).name}: {message}\n")
        raise SystemExit(2) from None
    raise SystemExit(code or 0)


require("mmusv", INSTALL_MMUSV)
