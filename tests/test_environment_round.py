"""The machine and the environment ``mmusv`` runs in: locales and console encodings, closed and full standard
streams, thread-count variables, a current folder deleted under the process, file names that are not UTF-8, and
the limits of the machine (open files, one CPU). Every command runs as a child process with a timeout; outputs
made under a changed environment must be the default run's bytes.
"""

from __future__ import annotations

import errno
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import mmusv
import pytest
import yaml
from tiny_scenario import lidar_scenario

PYTHONPATH = str(Path(mmusv.__file__).resolve().parents[1])
TIMEOUT_S = 60


def tiny_scenario(name: str = "tiny") -> dict[str, Any]:
    """The tiny scenario of 3 frames: a run takes a fraction of a second after the imports."""
    return lidar_scenario(name, frames=3)


def write_scenario(path: Path, name: str = "tiny") -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(yaml.safe_dump(tiny_scenario(name), sort_keys=False), encoding="utf-8")
    return path


def child_env(**changes: str | None) -> dict[str, str]:
    """This process's environment for a child ``mmusv``: this checkout's package, Python's own buffering (no
    ``PYTHONUNBUFFERED``: a pipe or file is block-buffered, as for a user), then ``changes`` (``None`` unsets)."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONUNBUFFERED", "RAYON_NUM_THREADS")}
    env.update(PYTHONPATH=PYTHONPATH, PYTHONDONTWRITEBYTECODE="1")
    for k, v in changes.items():
        if v is None:
            env.pop(k, None)
        else:
            env[k] = v
    return env


def mmusv_cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "mmusv.cli", *args]


def run_mmusv(
    *args: str, env: dict[str, str] | None = None, cwd: Path | str | None = None, **kw: Any
) -> subprocess.CompletedProcess[bytes]:
    kw.setdefault("stdout", subprocess.PIPE)
    kw.setdefault("stderr", subprocess.PIPE)
    return subprocess.run(mmusv_cmd(*args), env=env or child_env(), cwd=cwd, timeout=TIMEOUT_S, check=False, **kw)


def no_traceback(err: bytes) -> None:
    text = err.decode("utf-8", "replace")
    assert "Traceback" not in text and "Exception ignored" not in text, text


def files_of(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """``(scenario file, run folder)``: the tiny scenario recorded with this process's environment."""
    root = tmp_path_factory.mktemp("env_reference")
    scn = write_scenario(root / "tiny.yaml")
    out = root / "run"
    res = run_mmusv("run", str(scn), "-o", str(out))
    assert res.returncode == 0, res.stderr.decode()
    return scn, out


# --- consoles that are not UTF-8 -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "changes",
    [
        {"PYTHONIOENCODING": "ascii"},
        {"LC_ALL": "C", "LANG": "C", "PYTHONUTF8": "0", "PYTHONCOERCECLOCALE": "0"},
    ],
    ids=["PYTHONIOENCODING=ascii", "LC_ALL=C-no-utf8-mode"],
)
def test_wave_study_table_prints_on_an_ascii_console(tmp_path: Path, changes: dict[str, str]) -> None:
    """The wave study's table (``4 USVs × 2 frames``, ``roll RMS (°)``, ``R²``) was a UnicodeEncodeError
    traceback on a console whose encoding is ASCII, after the study had run; the characters now print in ASCII
    and the CSV is the same UTF-8 file as on a UTF-8 console."""
    out = tmp_path / "waves"
    res = run_mmusv("study", "waves", "--frames", "2", "-o", str(out), env=child_env(**changes))
    no_traceback(res.stderr)
    assert res.returncode == 0, res.stderr.decode()
    text = res.stdout.decode("ascii")  # only ASCII was written
    assert "4 USVs x 2 frames" in text and "roll RMS (deg)" in text and "R^2 of a linear fit" in text
    ref = tmp_path / "waves_utf8"
    assert run_mmusv("study", "waves", "--frames", "2", "-o", str(ref)).returncode == 0
    assert (out / "wave_study.csv").read_bytes() == (ref / "wave_study.csv").read_bytes()


def test_console_error_handler_keeps_file_name_bytes() -> None:
    """The console streams' handler writes a non-UTF-8 byte of a file name (a surrogate escape) as that byte,
    the known symbols in ASCII and anything else as ``?``; ``main`` in-process gives the streams back as they
    were."""
    from mmusv import cli, cli_console

    text = "x\udce9 \u00d7 \u00b0 \u2026 \u4e2d"
    with cli_console.lenient_output():
        assert text.encode("ascii", cli_console._OUTPUT_ERRORS) == b"x\xe9 x deg ... ?"
        assert "\udce9\u00d7\udce9".encode("ascii", cli_console._OUTPUT_ERRORS) == b"\xe9x\xe9"  # mixed in one span
        assert "\u00b0".encode("latin-1", cli_console._OUTPUT_ERRORS) == b"\xb0"  # what the encoding has is kept
    before = sys.stderr.errors if hasattr(sys.stderr, "errors") else None
    with pytest.raises(SystemExit):
        cli.main(["version", "--no-such-option"])
    assert (sys.stderr.errors if hasattr(sys.stderr, "errors") else None) == before


# --- closed, full and broken standard streams ------------------------------------------------------------------


def test_stdout_into_a_closed_pipe_ends_quietly(reference: tuple[Path, Path]) -> None:
    """``mmusv version | head -0``, ``mmusv info RUN | head -1``: the reader gone, stdout's flush at exit was
    ``Exception ignored ... BrokenPipeError`` with exit status 120; now nothing on stderr and status 1 (as the
    rich tables already did)."""
    _, run = reference
    for args in (("version",), ("--help",), ("info", str(run))):
        r, w = os.pipe()
        os.close(r)
        try:
            res = run_mmusv(*args, stdout=w)
        finally:
            os.close(w)
        assert res.stderr == b"" and res.returncode == 1, (args, res.returncode, res.stderr.decode())


def test_stdout_on_a_full_device_is_one_line(reference: tuple[Path, Path]) -> None:
    """``mmusv version > /dev/full``: one line naming the standard output and status 2, not ``Exception
    ignored`` and status 120 (nor two error lines for a rich table)."""
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full")
    _, run = reference
    for args in (("version",), ("info", str(run))):
        with open("/dev/full", "wb") as full:
            res = run_mmusv(*args, stdout=full)
        no_traceback(res.stderr)
        assert res.returncode == 2
        assert res.stderr.decode().splitlines() == [
            "mmusv: error: cannot write to the standard output: No space left on device"
        ]


def test_closed_stdout_and_stderr(reference: tuple[Path, Path], tmp_path: Path) -> None:
    """A closed stdout (``mmusv info RUN >&-``: ``sys.stdout`` is None) was an AttributeError traceback in
    ``isatty``; the command now runs (a run writes its recording). A closed stderr pipe gives the error's status,
    not 120."""
    scn, run = reference
    close_stdout = "exec 1>&-; exec " + " ".join(f"'{a}'" for a in mmusv_cmd())
    for args in (["info", str(run)], ["run", str(scn), "-o", str(tmp_path / "closed")]):
        res = subprocess.run(
            ["bash", "-c", close_stdout + ' "$@"', "mmusv", *args],
            env=child_env(),
            stderr=subprocess.PIPE,
            timeout=TIMEOUT_S,
            check=False,
        )
        no_traceback(res.stderr)
        assert res.returncode == 0, res.stderr.decode()
    assert (tmp_path / "closed" / "tiny.mcap").is_file()
    r, w = os.pipe()
    os.close(r)
    try:
        res = run_mmusv("run", str(tmp_path / "missing.yaml"), stderr=w)
    finally:
        os.close(w)
    assert res.returncode == 2


# --- thread counts in the environment --------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("RAYON_NUM_THREADS", "99999"),
        ("RAYON_NUM_THREADS", "abc"),
        ("RAYON_NUM_THREADS", "-3"),
        ("POLARS_MAX_THREADS", "0"),
        ("POLARS_MAX_THREADS", "1e3"),
    ],
)
def test_invalid_thread_counts_are_named(name: str, value: str) -> None:
    """``RAYON_NUM_THREADS=99999`` started tens of thousands of core threads (a 2-frame run did not end in 15
    minutes), ``POLARS_MAX_THREADS=0`` was a Rust panic with a traceback at the first table, ``abc`` quietly the
    default: each is refused before any work, naming the variable and the range."""
    res = run_mmusv("version", env=child_env(**{name: value}))
    no_traceback(res.stderr)
    assert res.returncode == 2 and res.stdout == b""
    err = res.stderr.decode().splitlines()[-1]  # Polars warns of some values itself when it is imported
    assert err.startswith(f"mmusv: error: {name}={value!r} in the environment: must be a whole number in ")
    assert err.endswith("unset it for the default")


@pytest.mark.parametrize("value", ["bogus", "avx2", " portable", "portable2"])
def test_an_unknown_simd_level_is_named(value: str) -> None:
    """``MMUSV_SIMD`` takes ``portable`` (the core's portable paths); anything else (a typo, ``avx2``, a blank
    around the word) was silently ignored and the run took the fastest paths the CPU has, as if unset. Refused
    before any work, naming the variable; ``portable`` in any case, and empty, are taken."""
    res = run_mmusv("version", env=child_env(MMUSV_SIMD=value))
    no_traceback(res.stderr)
    assert res.returncode == 2 and res.stdout == b""
    err = res.stderr.decode().splitlines()[-1]
    assert err.startswith(f"mmusv: error: MMUSV_SIMD={value!r} in the environment: must be 'portable'"), err
    for ok in ("portable", "PORTABLE", ""):
        assert run_mmusv("version", env=child_env(MMUSV_SIMD=ok)).returncode == 0, ok


def test_check_thread_environment_bounds() -> None:
    from mmusv.errors import ConfigError
    from mmusv.thread_env import THREADS_PER_CPU, check_thread_environment

    hi = THREADS_PER_CPU * (os.cpu_count() or 1)
    check_thread_environment({"RAYON_NUM_THREADS": "0", "POLARS_MAX_THREADS": "1"})
    check_thread_environment({"RAYON_NUM_THREADS": str(hi), "POLARS_MAX_THREADS": str(hi), "OMP_NUM_THREADS": "x"})
    check_thread_environment({"RAYON_NUM_THREADS": "", "POLARS_MAX_THREADS": " "})  # empty: as unset
    for env in ({"RAYON_NUM_THREADS": str(hi + 1)}, {"POLARS_MAX_THREADS": "0"}, {"RAYON_NUM_THREADS": "٣"}):
        with pytest.raises(ConfigError, match="in the environment"):
            check_thread_environment(env)


@pytest.mark.parametrize(
    ("changes", "prefix"),
    [
        ({"RAYON_NUM_THREADS": "1"}, []),
        ({"POLARS_MAX_THREADS": "1", "OMP_NUM_THREADS": "1"}, []),
        ({"LANG": "C", "LC_ALL": "C", "PYTHONUTF8": "0", "PYTHONCOERCECLOCALE": "0"}, []),
        ({"HOME": None, "TMPDIR": "/nonexistent/tmp", "XDG_CACHE_HOME": "/dev/null"}, []),
        ({}, ["taskset", "-c", "0"]),
        ({}, ["prlimit", "--nofile=64"]),
    ],
    ids=["rayon1", "polars1", "C-locale", "no-home", "one-cpu", "nofile64"],
)
def test_environment_gives_the_same_bytes(
    reference: tuple[Path, Path], tmp_path: Path, changes: dict[str, str | None], prefix: list[str]
) -> None:
    """Under one core thread, one Polars thread, the C locale without UTF-8 mode, no HOME and a missing TMPDIR,
    one CPU, or 64 open files, a run writes the same files with the same bytes as the default run."""
    if prefix and shutil.which(prefix[0]) is None:
        pytest.skip(f"no {prefix[0]}")
    scn, ref = reference
    out = tmp_path / "run"
    res = subprocess.run(
        [*prefix, *mmusv_cmd("run", str(scn), "-o", str(out))],
        env=child_env(**changes),
        capture_output=True,
        timeout=TIMEOUT_S,
        check=False,
    )
    no_traceback(res.stderr)
    assert res.returncode == 0, res.stderr.decode()
    assert files_of(out) == files_of(ref)


# --- locales whose encoding is not UTF-8 -----------------------------------------------------------------------


def test_non_ascii_paths_under_an_ascii_locale_are_refused_with_the_way_out(
    reference: tuple[Path, Path], tmp_path: Path
) -> None:
    """Under a locale that names files in ASCII or Latin-1 (not UTF-8), Python and the core/Polars meet
    different files for a path that is not ASCII: ``info`` called a run's intact tables unreadable (status 0),
    ``run -o "out é"`` was refused as "not UTF-8" although it is. Both now name the locale and the fix; with
    ``PYTHONUTF8=1`` the same commands work."""
    scn, run = reference
    folder = tmp_path / "run \u00e9"
    shutil.copytree(run, folder)
    ascii_env = child_env(LC_ALL="C", LANG="C", PYTHONUTF8="0", PYTHONCOERCECLOCALE="0")
    for args in (["info", str(folder)], ["run", str(scn), "-o", str(tmp_path / "out \u00e9")]):
        res = run_mmusv(*args, env=ascii_env)
        no_traceback(res.stderr)
        err = res.stderr.decode("utf-8", "replace")
        assert res.returncode == 2, err
        assert "a path that is not ASCII needs a UTF-8 locale" in err and "PYTHONUTF8=1" in err, err
    fixed = {**ascii_env, "PYTHONUTF8": "1"}
    res = run_mmusv("info", str(folder), env=fixed)
    assert res.returncode == 0 and b"warning" not in res.stdout + res.stderr, res.stdout.decode()


def test_non_utf8_scenario_file_name_in_a_folder_is_refused_first(tmp_path: Path) -> None:
    """A folder holding ``x\\xe9.yaml`` (a Latin-1 name): the batch recorded it, then ended in a
    UnicodeEncodeError traceback writing ``dataset.json``; now it is named before anything is recorded."""
    folder = tmp_path / "batch"
    folder.mkdir()
    name = os.fsdecode(b"x\xe9.yaml")
    try:
        write_scenario(folder / name)
    except (OSError, UnicodeError):
        pytest.skip("this file system does not take names that are not UTF-8")
    out = tmp_path / "out"
    res = run_mmusv("run", str(folder), "-o", str(out))
    no_traceback(res.stderr)
    err = res.stderr.decode("utf-8", "replace")
    assert res.returncode == 2 and "has a name that is not UTF-8" in err, err
    assert not list(out.rglob("*.mcap"))


# --- the current folder --------------------------------------------------------------------------------------


def test_deleted_current_folder_is_named(reference: tuple[Path, Path], tmp_path: Path) -> None:
    """``cd X; rmdir X; mmusv run FOLDER --jobs 2``: the worker processes start in the current folder, and the
    error was a bare ``No such file or directory``; the message now says the current folder is gone. A run
    with absolute paths still works there."""
    scn, _ = reference
    batch = tmp_path / "batch"
    write_scenario(batch / "a.yaml", "a")
    write_scenario(batch / "b.yaml", "b")
    gone = tmp_path / "gone"
    gone.mkdir()
    script = 'cd "$1" && rmdir "$1" && shift && exec "$@"'
    res = subprocess.run(
        [
            "bash",
            "-c",
            script,
            "sh",
            str(gone),
            *mmusv_cmd("run", str(batch), "-o", str(tmp_path / "b"), "--jobs", "2"),
        ],
        env=child_env(),
        capture_output=True,
        timeout=TIMEOUT_S,
        check=False,
    )
    no_traceback(res.stderr)
    err = res.stderr.decode()
    assert res.returncode == 2 and "the current folder no longer exists" in err, err
    gone.mkdir()
    res = subprocess.run(
        ["bash", "-c", script, "sh", str(gone), *mmusv_cmd("run", str(scn), "-o", str(tmp_path / "abs"))],
        env=child_env(),
        capture_output=True,
        timeout=TIMEOUT_S,
        check=False,
    )
    assert res.returncode == 0, res.stderr.decode()


# --- errors of the machine, in-process -----------------------------------------------------------------------


def test_out_of_memory_and_open_files_are_one_line(monkeypatch: pytest.MonkeyPatch, capsys: Any) -> None:
    """A MemoryError (numpy under ``ulimit -v``) was a traceback; EMFILE (``ulimit -n``) a bare "Too many open
    files". Both are now one line saying which limit to raise."""
    from mmusv import cli

    def raise_(exc: BaseException) -> Any:
        def dispatch(args: Any) -> int:
            raise exc

        return dispatch

    monkeypatch.setattr(cli, "_dispatch", raise_(MemoryError("Unable to allocate 2.75 MiB")))
    assert cli.main(["version"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: out of memory: Unable to allocate 2.75 MiB (") and err.count("\n") == 1
    monkeypatch.setattr(cli, "_dispatch", raise_(OSError(errno.EMFILE, "Too many open files")))
    assert cli.main(["version"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: Too many open files (the limit on open files is ") and "ulimit -n" in err


def test_the_api_checks_the_thread_counts_too(monkeypatch: pytest.MonkeyPatch) -> None:
    """A Simulation (and so mmusv.run) checks RAYON_NUM_THREADS before its first thread pool starts: through the
    API, 99999 started thousands of core threads as the command line did."""
    from mmusv.errors import ConfigError
    from mmusv.simulation import Simulation

    monkeypatch.setenv("RAYON_NUM_THREADS", "99999")
    with pytest.raises(ConfigError, match=r"RAYON_NUM_THREADS='99999' in the environment: must be a whole number"):
        Simulation(Path(__file__).resolve().parents[1] / "scenarios/port_entry.yaml")
