"""``mmusv train``: the models trained side by side in processes of their own (``--jobs``) are the models trained
in turn in this process, weight for weight, each job fitting its own model's scorer; one that fails does not stop
the others; bad ``--jobs`` values get a clear error."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
import torch
import yaml
from mmusv.cli import main
from mmusv.learn.cli import _jobs
from mmusv.studies.detection.sources import lidar_only

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "island_occlusion.yaml"


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 3-frame, 2-USV LiDAR-only recording."""
    from mmusv.acquire import run

    root = tmp_path_factory.mktemp("train_cli")
    data = lidar_only(yaml.safe_load(SCENARIO.read_text(encoding="utf-8")))
    data["vessels"] = [v for v in data["vessels"] if v["role"] != "usv" or v["id"] in ("usv_1", "usv_3")]
    data["name"] = "tiny_train_cli"
    data["acquisition"]["frames"] = 3
    return run(data, out_dir=root / "rec").recording


def _train(rec: Path, out: Path, *extra: str) -> int:
    argv = ["train", str(rec), "--preset", "tiny", "--split", "all", "--epochs", "2", "--no-progress", "-o", str(out)]
    return main([*argv, *extra])


def test_side_by_side_models_equal_models_trained_in_turn(recording: Path, tmp_path: Path) -> None:
    assert _train(recording, tmp_path / "turn", "--jobs", "1", "--threads", "1") == 0
    assert _train(recording, tmp_path / "side", "--jobs", "3", "--threads", "1") == 0
    for mode in ("single", "early", "intermediate"):
        a = torch.load(tmp_path / "turn" / mode / "model.pt", weights_only=True)
        b = torch.load(tmp_path / "side" / mode / "model.pt", weights_only=True)
        assert a["step"] == b["step"] > 0
        assert all(torch.equal(a["model"][k], b["model"][k]) for k in a["model"]), mode
        assert (tmp_path / "side" / mode / "loss.png").stat().st_size > 0
    summary = json.loads((tmp_path / "side" / "train_summary.json").read_text(encoding="utf-8"))
    assert summary["jobs"] == 3 and sorted(summary["models"]) == ["early", "intermediate", "single"]
    assert all(m["epochs"] == 2 and m["finished"] for m in summary["models"].values())
    # each job fits its own model's scorer after training it, with the outcome of the fit in turn
    turn = json.loads((tmp_path / "turn" / "train_summary.json").read_text(encoding="utf-8"))
    assert sorted(summary["scorers"]) == ["early", "intermediate", "single"]
    for mode, fit in summary["scorers"].items():
        assert {k: v for k, v in fit.items() if k != "seconds"} == {
            k: v for k, v in turn["scorers"][mode].items() if k != "seconds"
        }, mode


def test_a_failing_model_does_not_stop_the_others(
    recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # a file named early where the early model's folder goes makes that model fail in its process; the others train
    tmp_path.mkdir(parents=True, exist_ok=True)
    (tmp_path / "early").write_text("not a folder\n", encoding="utf-8")
    assert _train(recording, tmp_path, "--jobs", "3", "--threads", "1") != 0
    err = capsys.readouterr().err
    assert "early: failed" in err and "File exists" in err and "Traceback" not in err
    summary = json.loads((tmp_path / "train_summary.json").read_text(encoding="utf-8"))
    assert sorted(summary["models"]) == ["intermediate", "single"]
    assert sorted(summary["scorers"]) == ["intermediate", "single"]  # fitted in the jobs that trained
    assert (tmp_path / "single" / "model.pt").is_file() and (tmp_path / "intermediate" / "model.pt").is_file()
    assert not (tmp_path / "early" / "model.pt").exists()


def test_jobs_values() -> None:
    assert _jobs("2", 3, "cpu") == 2
    assert _jobs("8", 3, "cpu") == 3  # never more processes than models
    assert _jobs("auto", 3, "cpu") == 3
    assert _jobs("auto", 2, "cuda") == 1  # a GPU trains them in turn


@pytest.mark.parametrize("value", ["0", "-1", "two"])
def test_bad_jobs_is_a_clear_error(
    recording: Path, tmp_path: Path, value: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert _train(recording, tmp_path / "bad", "--jobs", value) != 0
    err = capsys.readouterr().err
    assert f"--jobs {value}" in err and "Traceback" not in err


def test_scorer_options_are_checked(recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert _train(recording, tmp_path / "none", "--scorers-only") != 0
    assert "--scorers-only: no" in capsys.readouterr().err
    assert _train(recording, tmp_path / "both", "--scorers-only", "--no-scorers") != 0
    assert "give one" in capsys.readouterr().err


def test_a_model_that_finds_nothing_trains_without_a_scorer(recording: Path, tmp_path: Path) -> None:
    # two epochs of the tiny preset find no box: the model is kept, without a scorer, and the summary says why
    assert _train(recording, tmp_path, "--modes", "single", "--threads", "1") == 0
    summary = json.loads((tmp_path / "train_summary.json").read_text(encoding="utf-8"))
    assert "boxes" in summary["scorers"]["single"]["skipped"]
    assert (tmp_path / "single" / "model.pt").is_file() and not (tmp_path / "single" / "scorer.pt").exists()


def test_a_checkpoint_of_another_run_for_any_model_is_refused_before_training(
    recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # single trained with one seed; then single and early with another seed into the same -o: only single refused,
    # early trained (its model beside a single of other weights' seed), and the summary named early alone
    assert _train(recording, tmp_path, "--modes", "single", "--epochs", "1", "--no-scorers") == 0
    summary = (tmp_path / "train_summary.json").read_text(encoding="utf-8")
    capsys.readouterr()
    assert _train(recording, tmp_path, "--modes", "single,early", "--seed", "1", "--jobs", "2", "--no-scorers") == 2
    err = capsys.readouterr().err
    assert "single/last.pt: a checkpoint of another run (seed 0, this run 1)" in err, err
    assert "or leave single out (--modes early)" in err, err
    assert len([line for line in err.splitlines() if line.strip()]) == 1, err
    assert not (tmp_path / "early").exists()
    assert (tmp_path / "train_summary.json").read_text(encoding="utf-8") == summary
    # a model this run does not train is scored with the ones it does: refused too
    assert _train(recording, tmp_path, "--modes", "early", "--seed", "1", "--no-scorers") == 2
    err = capsys.readouterr().err
    assert "single/last.pt: a checkpoint of another run (seed 0, this run 1)" in err, err
    assert "the single model there is scored with the ones this run trains" in err, err
    assert not (tmp_path / "early").exists()


def test_a_run_of_other_models_keeps_the_summary_of_the_ones_there(recording: Path, tmp_path: Path) -> None:
    # --modes early after --modes single (same preset and seed): the summary named early alone
    assert _train(recording, tmp_path, "--modes", "single", "--epochs", "1", "--no-scorers") == 0
    first = json.loads((tmp_path / "train_summary.json").read_text(encoding="utf-8"))
    assert _train(recording, tmp_path, "--modes", "early", "--epochs", "1", "--no-scorers") == 0
    second = json.loads((tmp_path / "train_summary.json").read_text(encoding="utf-8"))
    assert list(second["models"]) == ["single", "early"]
    assert second["models"]["single"] == first["models"]["single"]
    # a model trained again replaces its own entry only
    assert _train(recording, tmp_path, "--modes", "single", "--epochs", "2", "--no-scorers") == 0
    third = json.loads((tmp_path / "train_summary.json").read_text(encoding="utf-8"))
    assert third["models"]["single"]["epochs"] == 2 and third["models"]["early"] == second["models"]["early"]


@pytest.mark.slow
@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_a_kill_of_a_side_by_side_training_stops_its_models(recording: Path, tmp_path: Path) -> None:
    # SIGTERM to mmusv train (a kill, a service manager): it left the pool waiting for every model to finish
    out = tmp_path / "models"
    argv = [sys.executable, "-m", "mmusv", "train", str(recording), "--preset", "tiny", "--split", "all"]
    argv += ["--epochs", "100000", "--modes", "single,early", "--jobs", "2", "--threads", "1", "--no-scorers"]
    argv += ["--no-progress", "-o", str(out)]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    try:
        deadline = time.monotonic() + 240
        saved = [out / "single" / "model.pt", out / "early" / "model.pt"]
        while not all(f.is_file() for f in saved):  # both models are training (an epoch is done)
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "the models did not start training"
            time.sleep(0.5)
        children = _children(proc.pid)
        assert len(children) >= 2, children
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
        assert proc.returncode == 128 + signal.SIGTERM, err
        assert b"mmusv: terminated (SIGTERM)" in err and b"Traceback" not in err, err
        gone = time.monotonic() + 10  # reaped by now, or by init within moments
        while [pid for pid in children if _running(pid)] and time.monotonic() < gone:
            time.sleep(0.2)
        assert not [pid for pid in children if _running(pid)]
        for mode in ("single", "early"):  # the saves are whole: a run started again resumes from them
            assert not list((out / mode).glob(".*.tmp"))
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def _children(pid: int) -> list[int]:
    """The process ids whose parent is ``pid`` (Linux's /proc)."""
    kids = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            kids.append(int(stat.parent.name))
    return kids


def _running(pid: int) -> bool:
    """Whether process ``pid`` runs (exists and is not a zombie waiting to be reaped)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"


def test_a_stop_swallowed_while_the_jobs_trained_ends_the_command(
    recording: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # A stop whose KeyboardInterrupt a library swallowed (noted by the command's handler, then not raised) waited
    # for every model and wrote the summary; it is raised again as each model finishes, and the others stop.
    import concurrent.futures

    from mmusv.held_signals import note_stop

    original = concurrent.futures.as_completed

    def as_completed(*args: Any, **kwargs: Any) -> Any:
        for future in original(*args, **kwargs):
            note_stop(signal.SIGINT)
            yield future

    monkeypatch.setattr(concurrent.futures, "as_completed", as_completed)  # imported where it runs
    try:
        code = _train(recording, tmp_path / "side", "--jobs", "3", "--threads", "1")
    finally:
        note_stop(None)
    assert code == 130
    assert not (tmp_path / "side" / "train_summary.json").exists()
