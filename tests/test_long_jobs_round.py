"""The long jobs as a new user meets them (``mmusv dataset``, ``mmusv train``), shrunk to tiny specs and presets.

Each test failed before its fix: a dataset whose OPV2V conversion was stopped (Ctrl-C) after its folder had been
removed was taken for up to date by the next run, which left the half-written conversion as the dataset's; a
``mmusv train`` of another preset into a folder of trained models (every model refusing its checkpoint) printed its
refusal once per model, told to use
another ``--out`` (the option is ``-o/--output``) and replaced ``train_summary.json`` with a summary of no model;
``mmusv study detection|robustness --generate`` and ``mmusv train --generate`` refused a ``--split`` they do not know
or a negative ``--seed`` (named ``seed = -1``, not the option) only after generating and recording the whole dataset.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.cli import main

ROOT = Path(__file__).resolve().parents[1]

SPEC: dict[str, Any] = {
    "name": "longjobs",
    "seed": 7,
    "map": {"type": "open_sea", "seed": 2},
    "acquisition": {"frequency_hz": 5, "frames": 3},
    "rig": "usv_lidar",
    "rigs": {"usv_lidar": {"preset": "lidar_only", "lidar": {"channels": 8, "points_per_second": 20480}}},
    "usv": {"assets": ["usv_wamv"], "speed_mps": [2, 3]},
    "difficulties": {"near": {"range_m": [40, 120]}},
    "combinations": [
        {"family": "crossing", "difficulty": "near", "cooperating": 1, "targets": ["small"], "quota": 2},
    ],
}


def test_a_dataset_whose_conversion_was_stopped_is_converted_again(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = tmp_path / "longjobs.yaml"
    spec.write_text(yaml.safe_dump(SPEC, sort_keys=False), encoding="utf-8")
    out = tmp_path / "ds"
    assert main(["dataset", str(spec), "-o", str(out)]) == 0
    assert "frames converted into" in capsys.readouterr().out
    opv2v = out / "opv2v"
    whole = sorted(str(p.relative_to(opv2v)) for p in opv2v.rglob("*"))
    # What a Ctrl-C leaves of a conversion into a folder that was not there (the user removed it): the conversion
    # writes into it directly, its report first, as in_progress, then the first frames of the first recording.
    shutil.rmtree(opv2v)
    (opv2v / "train").mkdir(parents=True)
    (opv2v / "conversion.yaml").write_text("format: opv2v\nstatus: in_progress\n", encoding="utf-8")
    assert main(["dataset", str(spec), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "is up to date" not in printed and "frames converted into" in printed
    assert yaml.safe_load((opv2v / "conversion.yaml").read_text(encoding="utf-8"))["status"] == "complete"
    assert sorted(str(p.relative_to(opv2v)) for p in opv2v.rglob("*")) == whole
    # and a finished conversion is still left alone
    assert main(["dataset", str(spec), "-o", str(out)]) == 0
    assert "is up to date" in capsys.readouterr().out


def _record(out: Path) -> Path:
    from mmusv.acquire import run
    from mmusv.studies.detection.sources import lidar_only

    data = lidar_only(yaml.safe_load((ROOT / "scenarios" / "open_sea_convoy.yaml").read_text(encoding="utf-8")))
    usvs = [v["id"] for v in data["vessels"] if v["role"] == "usv"][:2]
    data["vessels"] = [v for v in data["vessels"] if v["role"] != "usv" or v["id"] in usvs]
    data["name"] = "lj_sea"
    data["acquisition"]["frames"] = 3
    rec: Path = run(data, out_dir=out / "lj_sea").recording
    return rec


@pytest.mark.slow
def test_a_train_of_another_preset_is_refused_once_and_keeps_the_summary(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("torch")
    rec = _record(tmp_path)
    out = tmp_path / "models"
    argv = ["train", str(rec), "--split", "all", "--modes", "single,early", "--epochs", "1", "--threads", "1"]
    tail = ["--no-scorers", "--no-progress", "-o", str(out)]
    assert main([*argv, "--preset", "tiny", "--jobs", "1", *tail]) == 0
    summary = (out / "train_summary.json").read_text(encoding="utf-8")
    assert sorted(json.loads(summary)["models"]) == ["early", "single"]
    capsys.readouterr()
    # side by side (the CPU default for several models): each process refused alone, the summary was rewritten
    assert main([*argv, "--preset", "cpu", "--jobs", "2", *tail]) == 2
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert "last.pt: a checkpoint of another run (preset 'tiny', this run 'cpu'); use another -o" in lines[0]
    assert "--out" not in err
    assert (out / "train_summary.json").read_text(encoding="utf-8") == summary


@pytest.mark.parametrize("command", [["study", "detection"], ["study", "robustness"], ["train"]])
@pytest.mark.parametrize(
    ("option", "said"),
    [
        (["--seed", "-1"], "--seed -1: the split's seed must be a whole number >= 0"),
        (["--split", "bogus"], "--split bogus: expected one of train, validate, test, all"),
    ],
)
def test_a_bad_split_or_seed_is_refused_before_generating(
    command: list[str],
    option: list[str],
    said: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    import mmusv.studies.detection.sources as sources

    def generate_dataset(*args: Any, **kwargs: Any) -> Any:
        raise AssertionError("generated before the options were checked")

    monkeypatch.setattr(sources, "generate_dataset", generate_dataset)
    if command == ["train"] and option[0] == "--seed":  # train's seeds the weights too: refused as such (4569346)
        said = "--seed -1: the seed of the split, the weights and the augmentation must be a whole number in 0.."
        said += str(2**63 - 1)
    assert main([*command, "--generate", "coop_detection", *option, "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.splitlines() == [f"mmusv: error: {said}"], err
    assert not (tmp_path / "out" / "dataset").exists()
