"""``mmusv train``: the models trained side by side in processes of their own (``--jobs``) are the models trained
in turn in this process, weight for weight, each job fitting its own model's scorer; one that fails does not stop
the others; bad ``--jobs`` values get a clear error."""

from __future__ import annotations

import json
from pathlib import Path

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
    # a checkpoint of another run in early/ makes that model refuse to start; the other two train
    (tmp_path / "early").mkdir(parents=True)
    torch.save({"preset": {}, "mode": "early", "seed": 0}, tmp_path / "early" / "last.pt")
    assert _train(recording, tmp_path, "--jobs", "3", "--threads", "1") != 0
    err = capsys.readouterr().err
    assert "early: failed" in err and "a checkpoint of another run" in err and "Traceback" not in err
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
