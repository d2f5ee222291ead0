"""The benchmarks as a performance-minded user meets them (a helper's round): every script in ``benches/`` names
what it lacks with the command that installs it, refuses counts below one on its command line, describes itself
and every option in ``--help``; ``compare_open3d.py`` runs both sides on the same threads, prints the machine and
refuses to time results that differ from Open3D's; ``generate_rate.py`` builds its maps before the timing;
criterion's command line reaches the Rust benches. Each script runs with its smallest settings."""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import mmusv
import pytest
from help_pages import check_help_page

ROOT = Path(__file__).resolve().parents[1]
BENCHES = ROOT / "benches"
SCRIPTS = sorted(p for p in BENCHES.glob("*.py") if p.name != "bench_env.py")
HAS_OPEN3D = importlib.util.find_spec("open3d") is not None


def _env(shadow: Path | None = None, **extra: str) -> dict[str, str]:
    """This process's environment with the installed mmusv importable (its folder first on ``PYTHONPATH``),
    ``shadow`` (fake packages) before it."""
    env = dict(os.environ)
    paths = [str(Path(mmusv.__file__).resolve().parents[1])]
    if shadow is not None:
        paths.insert(0, str(shadow))
    env["PYTHONPATH"] = os.pathsep.join([*paths, env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env.update(extra)
    return env


def _start(args: list[str], env: dict[str, str]) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, *args], cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )


def _finish(proc: subprocess.Popen[str], timeout: float = 120) -> tuple[int, str, str]:
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        pytest.fail(f"{proc.args} did not finish in {timeout} s: {out[-2000:]} {err[-2000:]}")
    return proc.returncode, out, err


def test_help_describes_each_script_and_every_option() -> None:
    """``--help`` of every script: its description a whole paragraph (it stopped mid-sentence, 'a 1,000-frame
    full-suite run of', where the docstring's first line ended) and a line of help for every option."""
    runner = textwrap.dedent(
        """
        import contextlib, io, runpy, sys
        sys.path.insert(0, sys.argv[1])
        for path in sys.argv[2:]:
            sys.argv = [path, "--help"]
            buf = io.StringIO()
            with contextlib.redirect_stdout(buf), contextlib.suppress(SystemExit):
                runpy.run_path(path, run_name="__main__")
            print("=====", path)
            print(buf.getvalue())
        """
    )
    code, out, err = _finish(_start(["-c", runner, str(BENCHES), *map(str, SCRIPTS)], _env(COLUMNS="100")), timeout=120)
    assert code == 0, err
    pages = dict(re.findall(r"===== (\S+)\n(.*?)(?=\n===== |\Z)", out, re.S))
    assert len(pages) == len(SCRIPTS), out
    for path, page in pages.items():
        check_help_page(Path(path).name, page)


ZERO_COUNTS = [
    ("record_throughput.py", ["--frames", "0"]),
    ("sea_surface_speed.py", ["--rounds", "0"]),
    ("quality_speed.py", ["--rounds", "0", "--quality", "draft", "--sea", "flat"]),
    ("memory_long_run.py", ["--frames", "2", "--every", "0"]),
    ("generate_rate.py", ["--repeat", "0"]),
    ("batch_speedup.py", ["--scenarios", "1", "--frames", "1", "--repeat", "0", "--skip-ray"]),
    ("compare_open3d.py", ["--repeat", "0"]),
]


def test_counts_below_one_are_refused_on_the_command_line() -> None:
    """``--frames 0``, ``--rounds 0``, ``--repeat 0``, ``--every 0`` were a ZeroDivisionError, an empty median, a
    KeyError or an empty table after the run's work; argparse refuses them now, naming the option."""
    procs = [(name, _start([str(BENCHES / name), *args], _env())) for name, args in ZERO_COUNTS]
    results = [(name, *_finish(proc)) for name, proc in procs]  # every one waited for before any assertion
    for name, code, _, err in results:
        assert code == 2 and "Traceback" not in err, f"{name}: {code} {err[-1500:]}"
        assert "give 1 or more" in err, f"{name}: {err[-500:]}"


def test_mmusv_errors_end_in_one_line() -> None:
    """A scenario file that is not there or an unknown sea preset ended in mmusv's message under a traceback; now
    the message alone, exit status 2, as ``mmusv`` itself reports it."""
    cases = [
        ("profile_run.py", ["no_such_scenario.yaml"], "does not exist"),
        ("sea_surface_speed.py", ["--preset", "W9", "--frames", "1", "--rounds", "1"], "is unknown"),
    ]
    procs = [(name, want, _start([str(BENCHES / name), *args], _env())) for name, args, want in cases]
    results = [(name, want, *_finish(proc)) for name, want, proc in procs]
    for name, want, code, _, err in results:
        assert code == 2 and "Traceback" not in err, f"{name}: {code} {err[-1500:]}"
        assert err.startswith(f"{name}: ") and want in err and len(err.strip().splitlines()) == 1, err


def _shadow(tmp_path: Path, *packages: str) -> Path:
    """A folder of packages whose import fails as a missing one does."""
    for name in packages:
        (tmp_path / name).mkdir()
        (tmp_path / name / "__init__.py").write_text(f"raise ImportError({f'No module named {name!r}'!r})\n")
    return tmp_path


@pytest.mark.parametrize(
    ("script", "args", "missing", "install"),
    [
        ("compare_open3d.py", ["--repeat", "1"], "open3d", "pip install open3d-cpu"),
        ("batch_speedup.py", ["--scenarios", "1", "--frames", "1", "--repeat", "1"], "ray", "pip install '.[ray]'"),
        ("profile_run.py", ["--frames", "1"], "mmusv", "pip install ."),
    ],
)
def test_a_missing_package_is_named_with_its_install_command(
    tmp_path: Path, script: str, args: list[str], missing: str, install: str
) -> None:
    """``make bench-peers`` without Open3D, ``batch_speedup.py`` without Ray (after writing and recording its
    warm-up scenario) and any script without mmusv ended in a traceback."""
    code, out, err = _finish(_start([str(BENCHES / script), *args], _env(_shadow(tmp_path, missing))))
    assert code == 2 and "Traceback" not in err, f"{code} {err[-1500:]}"
    assert f"needs {missing}" in err and install in err, err
    assert "Mr/s" not in out and "round 1" not in out, out


@pytest.mark.skipif(not HAS_OPEN3D, reason="needs open3d (pip install open3d-cpu)")
def test_compare_open3d_same_threads_machine_and_checked_results() -> None:
    """With ``RAYON_NUM_THREADS=1`` in the environment mmusv ran on one thread and Open3D on every CPU, and the
    output said neither; it said '2 cores' and nothing of the CPU; a ``--max-range`` shorter than the hits let
    mmusv stop where Open3D went on, unsaid."""
    threads = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    code, out, err = _finish(
        _start(
            [str(BENCHES / "compare_open3d.py"), "--repeat", "1", "--max-range", "300"],
            _env(RAYON_NUM_THREADS="1"),
        )
    )
    assert code == 0, err[-2000:]
    machine = next(line for line in out.splitlines() if line.startswith("machine: "))
    assert "CPUs available" in machine and "load average" in machine, machine
    assert f"threads: {threads} each (mmusv: RAYON_NUM_THREADS={threads}; open3d: nthreads={threads})" in out, out
    assert "RAYON_NUM_THREADS=1 in the environment replaced" in out, out
    assert "beyond --max-range 300 m" in out, out
    assert "Mr/s = millions of rays per second" in out, out
    rows = [line.split() for line in out.splitlines() if line.startswith(("instanced ", "single_mesh "))]
    assert len(rows) == 4, out
    for row in rows:
        rays, disagree = int(row[2]), int(row[-1])
        assert disagree <= 1e-4 * rays, row


@pytest.mark.skipif(not HAS_OPEN3D, reason="needs open3d (pip install open3d-cpu)")
def test_compare_open3d_refuses_to_time_results_that_differ() -> None:
    """A layout whose hits differ from Open3D's (here: its vessels moved 30 m) was timed and its ratio printed
    beside an 'agree' column nobody had to read; the check now runs before the timing and ends the run."""
    runner = textwrap.dedent(
        """
        import sys
        sys.path.insert(0, sys.argv[1])
        import numpy as np
        import compare_open3d as c

        def scenes(mod):
            native, vessels = mod.demo_scene(seed=1, extent=2000.0, terrain_cells=64, vessels=12)
            v, f, classes = native.world_mesh()[:3]
            single = mod.Scene()
            mesh = single.add_mesh(np.ascontiguousarray(v, np.float32), np.ascontiguousarray(f, np.int64),
                                   np.ascontiguousarray(classes), "world")
            single.add_instance(mesh, np.eye(4))
            poses = np.stack([np.asarray(native.instance_pose(i)) for i in vessels])
            poses[:, 0, 3] += 30.0
            native.set_poses(np.asarray(vessels, np.uint32), poses)
            return {"instanced": native, "single_mesh": single}

        c.scenes = scenes
        sys.argv = ["compare_open3d.py", "--repeat", "1"]
        c.main()
        """
    )
    code, out, err = _finish(_start(["-c", runner, str(BENCHES)], _env()))
    assert code == 1, f"{code} {out[-2000:]} {err[-2000:]}"
    assert "instanced" in err and "differ from Open3D's" in err, err
    assert not any(line.startswith(("instanced ", "single_mesh ")) for line in out.splitlines()), out


def test_generate_rate_builds_its_maps_before_the_timing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``generate_rate.py`` built the map under its whole parameter set while ``generate`` looks it up by the set
    parameters alone: the first timed run built it again (a two-scenario spec: 0.64 s timed, 0.10 s of it
    generation)."""
    import yaml
    from mmusv.generate import mapctx

    spec = yaml.safe_load((ROOT / "scenarios/specs/rate_100.yaml").read_text())
    spec["combinations"] = spec["combinations"][:1]
    spec["combinations"][0]["quota"] = 1
    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(spec))
    built: list[tuple[object, ...]] = []
    real = mapctx.generate_map

    def counting(*args: object, **kwargs: object) -> object:
        built.append(args)
        return real(*args, **kwargs)

    monkeypatch.setattr(mapctx, "generate_map", counting)
    monkeypatch.syspath_prepend(str(BENCHES))
    monkeypatch.setattr(sys, "argv", ["generate_rate.py", str(path), "--repeat", "1"])
    mapctx._cached.cache_clear()
    try:
        import generate_rate

        generate_rate.main()
    finally:
        mapctx._cached.cache_clear()
    assert len(built) == 1, built


def test_criterion_command_line_reaches_the_rust_benches() -> None:
    """Sampling settings set on a benchmark group in code win over criterion's command line: ``cargo bench --bench
    radar -- --measurement-time 1`` still measured 6 s per benchmark. They belong in ``criterion_group!``'s
    ``config``, which the command line overrides. (Read from the sources: running criterion takes minutes.)"""
    for path in sorted(BENCHES.glob("*.rs")):
        text = path.read_text()
        if "criterion_group!" not in text:
            continue
        groups = re.findall(r"let\s+mut\s+(\w+)\s*=\s*\w+\.benchmark_group\(", text)
        for g in groups:
            found = re.findall(rf"\b{g}\s*\.\s*(sample_size|measurement_time|warm_up_time)\s*\(", text)
            assert not found, f"{path.name}: group {g} sets {found} in code, over the command line"


def test_benchmark_names_in_the_docs_exist() -> None:
    """Every ``benches/*.py`` path and every ``cargo bench --bench NAME`` / ``--example NAME`` that the README, the
    Makefile and docs/ name is there."""
    cargo = (BENCHES / "Cargo.toml").read_text()
    benches = set(re.findall(r'\[\[bench\]\]\s*name = "(\w+)"', cargo))
    examples = set(re.findall(r'\[\[example\]\]\s*name = "(\w+)"', cargo))
    texts = [ROOT / "README.md", ROOT / "Makefile", ROOT / "ARCHITECTURE.md", *sorted((ROOT / "docs").rglob("*.md"))]
    for doc in texts:
        text = doc.read_text()
        for script in re.findall(r"benches/(\w+\.(?:py|rs))", text):
            assert (BENCHES / script).exists(), f"{doc.name}: benches/{script} is not there"
        for name in re.findall(r"cargo bench[^`\n]*--bench (\w+)", text):
            assert name in benches, f"{doc.name}: cargo bench --bench {name}: no such bench ({sorted(benches)})"
        for name in re.findall(r"--example (\w+)", text):
            assert name in examples, f"{doc.name}: --example {name}: no such example ({sorted(examples)})"
