"""The command line: subcommands work, bad input is one clear line and exit status 2."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "mmusv.cli", *args], capture_output=True, text=True, cwd=ROOT, timeout=120
    )


def test_version_and_assets() -> None:
    assert run("version").stdout.startswith("mmusv ")
    out = run("assets").stdout
    assert "container_ship_300m" in out and "usv_wamv" in out


def test_python_dash_m_mmusv_is_the_command() -> None:
    """``python -m mmusv`` (no console script on the path) was "No module named mmusv.__main__"."""
    r = subprocess.run(
        [sys.executable, "-m", "mmusv", "version"], capture_output=True, text=True, cwd=ROOT, timeout=120
    )
    assert r.returncode == 0 and r.stdout.startswith("mmusv "), r.stderr
    bad = subprocess.run([sys.executable, "-m", "mmusv", "run"], capture_output=True, text=True, cwd=ROOT, timeout=120)
    # a usage error is one line naming the subcommand's help (it was argparse's usage block, then the error)
    said = "mmusv: error: the following arguments are required: scenario (see mmusv run --help)\n"
    assert bad.returncode == 2 and bad.stderr == said, bad.stderr


def test_wave_study_command(tmp_path: Path) -> None:
    r = run("study", "waves", "--frames", "100", "-o", str(tmp_path))
    assert r.returncode == 0, r.stderr
    assert "W3" in r.stdout and (tmp_path / "wave_study.csv").is_file()


def test_bad_scenario_is_one_line_not_a_traceback(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("vessels:\n  - {id: a, asset: nothing, route: [[0, 0], [1, 1]]}\n")
    r = run("study", "waves", "--scenario", str(bad), "-o", str(tmp_path))
    assert r.returncode == 2
    assert "Traceback" not in r.stderr and "vessels[0].asset" in r.stderr


def test_run_checks_its_options_for_one_file_as_for_a_folder(tmp_path: Path) -> None:
    # A single scenario file took --jobs 0 and -o "" (the current folder) without a word.
    scenario = str(ROOT / "scenarios/open_sea_convoy.yaml")
    for args, said in (
        (["--jobs", "0"], "--jobs 0: must be at least 1"),
        (["--frames", "-1"], "--frames -1: must be at least 1"),
        (["-o", ""], "-o/--output is empty"),
    ):
        out = [] if "-o" in args else ["-o", str(tmp_path / "out")]
        r = run("run", scenario, *out, *args)
        assert r.returncode == 2 and said in r.stderr and "Traceback" not in r.stderr, r.stderr
    assert not (tmp_path / "out").exists()


def test_run_counts_one_frame_as_one_frame(tmp_path: Path) -> None:
    # A one-frame run said "1 frames in ...", in mmusv run's line and in a folder run's table.
    import yaml
    from tiny_scenario import lidar_scenario

    for frames, said in ((1, " 1 frame in "), (2, " 2 frames in ")):
        src = tmp_path / f"s{frames}"
        src.mkdir()
        (src / "tiny.yaml").write_text(yaml.safe_dump(lidar_scenario("tiny", frames=frames)))
        one = run("run", str(src / "tiny.yaml"), "-o", str(tmp_path / f"one{frames}"))
        assert one.returncode == 0 and said in one.stdout, one.stdout + one.stderr
        folder = run("run", str(src), "-o", str(tmp_path / f"many{frames}"), "--jobs", "1")
        assert folder.returncode == 0 and said.strip() in " ".join(folder.stdout.split()), folder.stdout
