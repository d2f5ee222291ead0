"""The thread counts the environment asks of the libraries mmusv runs on (``RAYON_NUM_THREADS`` for the core,
``POLARS_MAX_THREADS`` for the tables), and the core's code paths (``MMUSV_SIMD``), checked before they are read:
the command line (:mod:`mmusv.cli_console`) and every :class:`~mmusv.simulation.Simulation` check them first."""

from __future__ import annotations

from mmusv.errors import ConfigError

__all__ = ["SIMD_VARIABLE", "THREADS_PER_CPU", "THREAD_VARIABLES", "check_thread_environment"]

THREAD_VARIABLES = {
    "RAYON_NUM_THREADS": (0, "the core's threads; 0: one per CPU"),
    "POLARS_MAX_THREADS": (1, "the Parquet tables' threads"),
}
"""Thread-count variables of the environment read by the libraries ``mmusv`` runs on, each with its least
allowed value and what it sets; :func:`check_thread_environment`."""

SIMD_VARIABLE = "MMUSV_SIMD"
"""The variable that forces the core's portable code paths (``portable``, any case; ``crates/mmusv-core/src/simd.rs``):
any other value was silently ignored (the fastest paths the CPU has ran), so it is refused."""

THREADS_PER_CPU = 4
"""A thread-count variable's value at most: this many threads per CPU of the machine."""


def check_thread_environment(environ: dict[str, str] | None = None) -> None:
    """The thread counts of the environment (``RAYON_NUM_THREADS``, ``POLARS_MAX_THREADS``) checked before a
    thread pool reads them: ``RAYON_NUM_THREADS=99999`` started tens of thousands of core threads (the run did
    not finish in 15 minutes and the machine's load went past 2,000), ``POLARS_MAX_THREADS=0`` was a Rust panic
    with a traceback once the tables were written, and ``abc`` or ``-3`` were quietly taken as the default.
    ``MMUSV_SIMD`` must be ``portable`` (any case), as the core reads it: any other value was silently ignored.
    :class:`~mmusv.errors.ConfigError` naming the variable and what is allowed. Unset or empty: not checked."""
    import os

    env = os.environ if environ is None else environ
    cpus = os.cpu_count() or 1  # the machine's, not this process's affinity: a job may oversubscribe its share
    hi = THREADS_PER_CPU * cpus
    for name, (lo, what) in THREAD_VARIABLES.items():
        raw = env.get(name)
        if raw is None or not raw.strip():
            continue
        text = raw.strip()
        if not (text.isascii() and text.isdigit()) or not lo <= int(text) <= hi:
            raise ConfigError(
                f"{name}={raw!r} in the environment: must be a whole number in {lo}..{hi} ({what}; at most "
                f"{THREADS_PER_CPU} per CPU, this machine has {cpus}); unset it for the "
                "default"
            )
    simd = env.get(SIMD_VARIABLE)
    if simd and simd.lower() != "portable":  # as the core compares it: whole, any case
        raise ConfigError(
            f"{SIMD_VARIABLE}={simd!r} in the environment: must be 'portable' (the core's portable code paths, the "
            "same bytes on any x86-64); unset it for the fastest paths this CPU has"
        )
