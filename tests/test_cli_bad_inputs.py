"""The command line misused as a new user would: empty paths, outputs that are files or not UTF-8, counts past
what the machine has, unreachable addresses. Each is one ``mmusv: error:`` line naming the option (exit status 2)
before anything is computed or written, never a traceback, a hang, or a silent fallback to the current folder or a
default. The options are checked first, so most cases name a recording or spec that does not exist: the code before
these checks failed on that instead, without naming the option."""

from __future__ import annotations

import os
import socket
from collections.abc import Sequence
from pathlib import Path

import pytest
import yaml
from mmusv.cli import main

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = str(ROOT / "scenarios/open_sea_convoy.yaml")
SPEC = str(ROOT / "scenarios/specs/island_demo.yaml")


def _refused(argv: Sequence[str], capsys: pytest.CaptureFixture[str]) -> tuple[str, str]:
    """Runs ``mmusv argv`` in this process; asserts exit status 2 and one error line; returns (stdout, stderr)."""
    assert main(list(argv)) == 2
    out, err = capsys.readouterr()
    assert err.startswith("mmusv: error: ") and "Traceback" not in err, err
    return out, err


def _usage_error(argv: Sequence[str], capsys: pytest.CaptureFixture[str]) -> str:
    """Runs ``mmusv argv``, which argparse refuses: asserts exit status 2 and one error line; returns it."""
    with pytest.raises(SystemExit) as e:
        main(list(argv))
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.fixture
def cwd(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty current folder, to see that nothing lands there."""
    here = tmp_path / "cwd"
    here.mkdir()
    monkeypatch.chdir(here)
    return here


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["assets", "--render", ""], "--render is empty"),
        (["study", "waves", "--frames", "2", "-o", ""], "-o/--output is empty"),
        (["study", "waves", "--scenario", ""], "--scenario is empty"),
        (["study", "agreement", "", "--frames", "1", "-o", "agree"], "scenario is empty"),
        (["study", "agreement", "missing.yaml", "--frames", "1", "-o", ""], "-o/--output is empty"),
        (["run", "", "-o", "out"], "scenario is empty"),
        (["info", ""], "recording is empty"),
        (["recover", ""], "target is empty"),
        (["preview", ""], "recording is empty"),
        (["preview", "missing.mcap", "-o", ""], "-o/--output is empty"),
        (["generate", ""], "spec is empty"),
        (["generate", "missing.yaml", "-o", ""], "-o/--output is empty"),
        (["dataset", "", "-o", "ds"], "spec is empty"),
        (["dataset", "missing.yaml", "-o", ""], "-o/--output is empty"),
        (["study", "detection", "", "-o", "det"], "recording is empty"),
        (["study", "detection", "missing.mcap", "-o", ""], "-o/--output is empty"),
        (["study", "detection", "--opv2v", "", "-o", "det"], "--opv2v is empty"),
        (["train", "", "-o", "tr"], "recording is empty"),
        (["train", "missing.mcap", "-o", ""], "-o/--output is empty"),
        (["editor", "", "--port", "-1"], "scenario is empty"),
        (["editor", "--dir", "", "--port", "-1"], "--dir is empty"),
    ],
)
def test_an_empty_path_is_refused_by_name_not_taken_as_the_current_folder(
    argv: list[str], said: str, cwd: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _, err = _refused(argv, capsys)
    assert said in err, err
    assert list(cwd.iterdir()) == []


@pytest.mark.parametrize(
    "argv",
    [
        ["run", SCENARIO, "--frames", "1", "-o"],
        ["study", "waves", "--frames", "2", "-o"],
    ],
)
def test_an_output_path_that_is_not_utf8_is_refused_before_anything_is_written(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = os.fsdecode(os.fsencode(tmp_path) + b"/out\xff")  # as Python hands such an argument over
    _, err = _refused([*argv, bad], capsys)
    assert "-o/--output" in err and "not UTF-8" in err, err
    assert list(tmp_path.iterdir()) == []


def test_output_folders_under_a_file_are_named_as_the_option_before_any_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    afile = tmp_path / "afile"
    afile.write_text("not a folder\n", encoding="utf-8")
    out, err = _refused(["assets", "--render", str(afile / "sheet")], capsys)
    assert err.startswith(f"mmusv: error: --render {afile / 'sheet'}: {afile} is a file, not a folder"), err
    assert out == ""  # the table was printed before the folder was refused
    for argv in (
        ["generate", SPEC, "-o", str(afile)],
        ["dataset", SPEC, "-o", str(afile / "ds")],
        ["study", "detection", str(tmp_path / "missing.mcap"), "-o", str(afile)],
        ["train", str(tmp_path / "missing.mcap"), "-o", str(afile)],
        # "cannot create output folder ...: File exists" (or "Not a directory" below it)
        ["run", SCENARIO, "-o", str(afile)],
        ["run", str(Path(SCENARIO).parent), "-o", str(afile / "batch")],
    ):
        _, err = _refused(argv, capsys)
        assert f"-o/--output {argv[-1]}: {afile} is a file, not a folder" in err, (argv, err)
    assert afile.read_text(encoding="utf-8") == "not a folder\n"


@pytest.mark.parametrize(("frames", "said"), [("0", "--frames = 0"), (str(10**30), f"--frames = {10**30}")])
def test_wave_study_frames_are_bounded_and_checked_before_the_output_folder(
    frames: str, said: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "waves"
    _, err = _refused(["study", "waves", "--frames", frames, "-o", str(out)], capsys)
    assert said in err and "2..10000000" in err, err
    assert not out.exists()


def _empty_folder(tmp_path: Path) -> str:
    folder = tmp_path / "no_scenarios"
    folder.mkdir()
    return str(folder)


@pytest.mark.parametrize(
    ("option", "said"),
    [
        (["--jobs", str(10**11)], f"--jobs {10**11}: must be in 1.."),
        (["--cpus-per-task", str(10**11)], f"--cpus-per-task {10**11}: must be in 1.."),
    ],
)
def test_a_local_pool_is_bounded_by_the_cpus_of_the_machine(
    option: list[str], said: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--jobs 10**11`` was a multiprocessing traceback, ``--cpus-per-task 10**11`` as many core threads (a hang);
    an empty folder of scenarios made the code before the check fail at once, on something else."""
    out = tmp_path / "out"
    _, err = _refused(["run", _empty_folder(tmp_path), "-o", str(out), *option], capsys)
    assert said in err and "this machine" in err, err
    _, err = _refused(["dataset", str(tmp_path / "missing.yaml"), "-o", str(tmp_path / "ds"), *option], capsys)
    assert said in err, err
    assert not out.exists() and not (tmp_path / "ds").exists()


def _closed_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
    return port


def test_a_ray_address_where_nothing_listens_is_named_not_retried_for_minutes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    address = f"127.0.0.1:{_closed_port()}"
    _, err = _refused(["run", _empty_folder(tmp_path), "-o", str(tmp_path / "out"), "--ray", address], capsys)
    assert f"--ray {address}: nothing answers" in err, err


@pytest.mark.parametrize(
    ("option", "said"),
    [
        (["--workers", str(10**11)], f"--workers {10**11}: must be in 0.."),
        (["--threads", str(10**11)], f"--threads {10**11}: must be at most"),
    ],
)
def test_train_threads_and_workers_are_bounded_by_the_cpus(
    option: list[str], said: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["train", str(tmp_path / "missing.mcap"), "--no-progress", "-o", str(tmp_path / "tr"), *option]
    _, err = _refused(argv, capsys)
    assert said in err and "CPUs of this machine" in err, err
    assert not (tmp_path / "tr").exists()


@pytest.mark.parametrize(
    ("option", "said"),
    [
        (["--range", "inf"], "--range = inf: must be a finite number of metres > 0"),
        (["--modes", ""], "--modes '': no mode; allowed: none, late, early, intermediate"),
        (["--split-ratios", "1,2"], "--split-ratios 1,2: expected three fractions"),
        (["--model", "missing", "--threads", str(10**11)], f"--threads {10**11}: must be at most"),
    ],
)
def test_detection_study_options_are_refused_by_name_before_the_data_is_read(
    option: list[str], said: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--range inf`` and ``--modes ""`` (the default modes) were taken without a word, ``--threads 10**11`` was
    a torch traceback, and a bad ``--split-ratios`` was called "split"."""
    argv = ["study", "detection", str(tmp_path / "missing.mcap"), "--no-progress", "-o", str(tmp_path / "det")]
    _, err = _refused([*argv, *option], capsys)
    assert said in err, err


def test_robustness_says_why_a_dataset_shorter_than_the_delay_is_empty(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.acquire import run
    from mmusv.studies.detection.sources import lidar_only

    data = lidar_only(yaml.safe_load(Path(SCENARIO).read_text(encoding="utf-8")))
    data["name"] = "one_frame"
    data["acquisition"]["frames"] = 1
    rec = run(data, out_dir=tmp_path / "rec").recording
    argv = ["study", "robustness", str(rec), "--settings", "delay:1", "--no-progress", "-o", str(tmp_path / "rob")]
    _, err = _refused(argv, capsys)
    assert "empty dataset" in err and "leaves out the first 1 frame of every" in err, err  # was "1 frames"
    assert "--settings holds delay:1" in err, err


def test_a_fifo_given_as_a_scenario_is_not_said_to_be_missing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fifo = tmp_path / "scenario.yaml"
    os.mkfifo(fifo)
    _, err = _refused(["run", str(fifo), "-o", str(tmp_path / "out")], capsys)
    assert f"scenario {str(fifo)!r} is not a regular file" in err, err


def test_preview_refuses_a_negative_frame_by_name(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _, err = _refused(["preview", str(tmp_path / "missing.mcap"), "--frame", "-1"], capsys)
    assert "--frame = -1: must be a whole number >= 0" in err, err


def test_editor_host_that_is_not_utf8_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Was a UnicodeError traceback from the name lookup."""
    host = os.fsdecode(b"\xff")
    _, err = _refused(["editor", "--dir", str(tmp_path), "--host", host, "--port", "0"], capsys)
    assert err.startswith(f"mmusv: error: --host {host!r}: not a host name or address"), err


def test_retries_are_bounded(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``--retries 10**20`` was taken: a task that always fails would have been run again practically forever."""
    _, err = _refused(["run", _empty_folder(tmp_path), "-o", str(tmp_path / "out"), "--retries", str(10**20)], capsys)
    assert "--retries" in err and "0..100" in err, err
    assert not (tmp_path / "out").exists()


def test_generate_takes_a_bundled_spec_by_name(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``mmusv dataset coop_detection`` found the bundled spec, ``mmusv generate island_demo`` said it did not exist.
    With an output under a file, the run goes past the spec (resolved, loaded) and stops at ``-o`` before any map."""
    blocker = tmp_path / "file"
    blocker.write_text("x")
    _, err = _refused(["generate", "island_demo", "-o", str(blocker / "out")], capsys)
    assert "-o/--output" in err and "is a file" in err, err
    _, err = _refused(["generate", "no_such_spec"], capsys)
    assert "not a bundled spec" in err and "island_demo" in err, err


def test_recover_names_a_path_that_does_not_exist(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _, err = _refused(["recover", str(tmp_path / "missing")], capsys)
    assert "does not exist" in err, err


def test_robustness_settings_may_not_be_empty(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``--settings ""`` ran the clean setting alone: a robustness study of nothing."""
    argv = ["study", "robustness", str(tmp_path / "missing.mcap"), "--settings", "", "-o", str(tmp_path / "rob")]
    _, err = _refused(argv, capsys)
    assert "--settings '': empty; give clean" in err, err


def test_jobs_for_one_scenario_is_said_to_do_nothing(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``--jobs 3`` with one scenario file was ignored without a word (it runs the files of a folder side by side)."""
    scenario = yaml.safe_load(Path(SCENARIO).read_text())
    scenario["rigs"] = {"r": {"preset": "lidar_only", "lidar": {"channels": 4, "points_per_second": 2000}}}
    scenario["vessels"] = [{**v, "rig": "r"} if v.get("role") == "usv" else v for v in scenario["vessels"]]
    path = tmp_path / "one.yaml"
    path.write_text(yaml.safe_dump(scenario))
    argv = ["run", str(path), "-o", str(tmp_path / "out"), "--frames", "1", "--jobs", "3", "--no-checks"]
    assert main([*argv, "--stop-on-full-disk"]) == 0
    _, err = capsys.readouterr()
    assert "mmusv: note: --jobs 3 runs the scenarios of a folder side by side" in err, err
    # --stop-on-full-disk was dropped without a word too
    assert "mmusv: note: --stop-on-full-disk stops a batch's other recordings" in err, err
    assert (tmp_path / "out" / f"{scenario['name']}.mcap").is_file()  # one file's layout: not a batch of one


@pytest.mark.parametrize(
    ("argv", "hint"),
    [
        (["run", "port_entry", "--frame", "3"], "--frame: did you mean --frames?"),  # was taken as --frames 3
        (["run", "port_entry", "--frmes", "3"], "--frmes: did you mean --frames?"),
        (["convert", "rec", "-o", "out", "--max-occ", "1"], "--max-occ: did you mean --max-occlusion?"),
    ],
)
def test_a_shortened_or_misspelt_flag_is_refused_with_the_flag_it_may_mean(
    argv: list[str], hint: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # argparse took any unambiguous prefix: ``--frame 3`` ran 3 frames, and a script using it would change
    # meaning the day a second flag shared the prefix. Now it is an unrecognised argument, nothing is written.
    argv = [str(tmp_path / a) if a in ("rec", "out") else a for a in argv]
    err = _usage_error(argv, capsys)
    assert "unrecognized arguments" in err and hint in err, err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        # argparse said "unknown command '1'", naming the option's value as the command
        (["--frames", "1", "run", "rec"], "option --frames is given before the command 'run'"),
        # argparse said "unrecognized arguments: --frames=1 (see mmusv run --help)", though run takes --frames
        (["--frames=1", "run", "rec"], "option --frames=1 is given before the command 'run'"),
        (["-o", "out", "convert", "rec"], "option -o is given before the command 'convert'"),
        (["--frames", "1"], "option --frames is given before any command"),
    ],
)
def test_an_option_before_the_command_is_said_to_belong_after_it(
    argv: list[str], said: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    err = _usage_error(argv, capsys)
    assert said in err, err
    if "any command" not in said:
        command = argv[argv.index(said.split("'")[1])]
        assert f"as in: mmusv {command} " in err, err


def test_a_misspelt_command_is_still_named_as_unknown(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["runn", "x"])
    assert "unknown command 'runn'" in capsys.readouterr().err


@pytest.mark.parametrize("seed", ["-1", str(2**63)])
def test_train_seed_is_refused_by_name_before_anything_is_written(
    seed: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # -1 built the tensor cache, then failed each model with numpy's "expected non-negative integer" and a traceback
    argv = ["train", str(tmp_path / "missing.mcap"), "--no-progress", "-o", str(tmp_path / "tr"), "--seed", seed]
    _, err = _refused(argv, capsys)
    assert f"--seed {seed}: the seed of the split, the weights and the augmentation must be a whole number" in err, err
    assert not (tmp_path / "tr").exists()


@pytest.mark.parametrize(
    ("argv", "hint"),
    [
        (["convert", "rec", "--split", "-1,1,1", "-o", "out"], "given as --split=-1,1,1"),
        (["convert", "rec", "--oxts-origin", "-10,5,0", "-o", "out"], "given as --oxts-origin=-10,5,0"),
        (["convert", "rec", "-o", "--frames", "1"], None),  # a value forgotten: no such hint
    ],
)
def test_a_value_that_begins_with_a_dash_is_shown_how_to_give_it(
    argv: list[str], hint: str | None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # argparse takes "-1,1,1" for an option and said only "argument --split: expected one argument"
    argv = [str(tmp_path / a) if a in ("rec", "out") else a for a in argv]
    err = _usage_error(argv, capsys)
    assert "expected one argument" in err, err
    if hint is None:
        assert "begins with '-'" not in err, err
    else:
        assert f"; a value that begins with '-' is {hint} (see mmusv convert --help)" in err, err
