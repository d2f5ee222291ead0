"""Leftovers of the earlier reviews, each as a user met it; every test failed before its fix.

- A bad option value (``--jobs abc``), an unknown subcommand, a missing argument: argparse printed its usage block
  (a dozen lines for ``run``) and then the error; now one ``mmusv: error:`` line naming the option and the
  subcommand's ``--help``, exit status 2, as the command's other errors.
- Counts of one in the summaries: "1 sequences", "1 epochs", "1 steps", "first 1 frames".
- ``mmusv study agreement`` interrupted (or failing) in its first scenario left an empty ``-o`` folder behind.
- A generation spec given where a scenario goes (``mmusv run``, ``study agreement``, ``study waves``) was a dozen
  "invalid config" problems on one very long line; a scenario given to ``mmusv generate`` the reverse.
- ``mmusv train`` run again over a model whose IoU-scorer fit had failed (too few boxes) ran the model over the whole
  cache again to fail the same way (minutes); now the failure is recorded for those weights, data and seed, and
  ``--scorers-only`` tries again.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.cli import main

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = str(ROOT / "scenarios/port_entry.yaml")
SPEC = str(ROOT / "scenarios/specs/island_demo.yaml")


def _exit_status(argv: list[str]) -> int:
    """``mmusv argv`` in this process: its exit status, whether returned or raised (argparse exits)."""
    try:
        return main(argv)
    except SystemExit as exc:
        return 0 if exc.code is None else int(exc.code)


# ------------------------------------------------------------------------------------------ usage errors, one line


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["run", SCENARIO, "--jobs", "abc"], "argument --jobs: invalid int value: 'abc' (see mmusv run --help)"),
        (
            ["convert", "x.mcap", "--to", "kitti", "--range", "abc", "-o", "out"],
            "argument --range: invalid float value: 'abc' (see mmusv convert --help)",
        ),
        (["frobnicate"], "unknown command 'frobnicate' (choose from 'version', 'assets', "),
        (["study", "tables"], "unknown study 'tables' (choose from 'waves', 'agreement', "),
        (["run"], "the following arguments are required: scenario (see mmusv run --help)"),
        (["convert", "x.mcap"], "the following arguments are required: -o/--output (see mmusv convert --help)"),
        (
            ["study", "agreement", "--frames", "x"],
            "--frames: invalid int value: 'x' (see mmusv study agreement",
        ),
        (
            ["study", "detection", "x.mcap", "--bogus"],
            "arguments: --bogus (see mmusv study detection --help)",
        ),
        (
            ["train", "x.mcap", "--epochs", "1.5"],
            "--epochs: invalid int value: '1.5' (see mmusv train --help)",
        ),
        (["schema", "yaml"], "unknown kind 'yaml' (choose from 'scenario', 'spec') (see mmusv schema --help)"),
        (["preview", "x.mcap", "--frame"], "argument --frame: expected one argument (see mmusv preview --help)"),
    ],
)
def test_a_usage_error_is_one_line_naming_the_option_and_the_help(
    argv: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert _exit_status(argv) == 2
    out, err = capsys.readouterr()
    assert err.startswith("mmusv: error: ") and err.count("\n") == 1 and said in err, err
    assert "usage:" not in err and out == ""


def test_help_is_as_it_was(capsys: pytest.CaptureFixture[str]) -> None:
    assert _exit_status(["run", "--help"]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("usage: mmusv run [-h]") and "--jobs JOBS" in out and err == ""


# ------------------------------------------------------------------------------------------------------ plurals


def test_counts_of_one_are_singular() -> None:
    from mmusv.learn.detector import _progress
    from mmusv.text import counted

    assert [counted(1, "epoch"), counted(2, "epoch"), counted(0, "box", plural="boxes")] == [
        "1 epoch",
        "2 epochs",
        "0 boxes",
    ]
    assert counted(1234, "frame", fmt=",") == "1,234 frames"
    # mmusv study detection's "learned models:" line (and the notes): "1 epochs, 1 steps"
    assert _progress({"epoch": 1, "step": 1, "epochs": 1}) == "1 epoch, 1 step"
    assert _progress({"epoch": 0, "step": 1, "epochs": 1}) == "0 of 1 epoch, unfinished, 1 step"


def test_the_detection_study_summary_of_one_sequence(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``mmusv study detection`` on a one-frame recording said "1 sequences, 1 frames"."""
    from mmusv.acquire import run
    from mmusv.studies.detection.sources import lidar_only

    data = lidar_only(yaml.safe_load((ROOT / "scenarios/open_sea_convoy.yaml").read_text(encoding="utf-8")))
    usv = next(v["id"] for v in data["vessels"] if v["role"] == "usv")
    data["vessels"] = [v for v in data["vessels"] if v["role"] != "usv" or v["id"] == usv]
    data["name"], data["acquisition"]["frames"] = "one_frame", 1
    rec = run(data, out_dir=tmp_path / "rec").recording
    argv = ["study", "detection", str(rec), "--modes", "none", "--no-progress", "-o", str(tmp_path / "det")]
    assert main(argv) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "split all: 1 sequence, 1 frame, 1 ego-frame," in out, out


# ----------------------------------------------------------------------------- study agreement's output folder


def _interrupted(*args: Any, **kwargs: Any) -> Any:
    raise KeyboardInterrupt


def test_an_interrupted_agreement_study_leaves_no_empty_output_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import mmusv.studies.agreement as agreement

    monkeypatch.setattr(agreement, "run_agreement_study", _interrupted)
    new = tmp_path / "new" / "agreement"  # both folders made by the command
    assert main(["study", "agreement", "--frames", "1", "-o", str(new)]) == 130
    assert "mmusv: interrupted" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []
    # a folder that was there, and one holding earlier results, are left as they are
    (tmp_path / "old").mkdir()
    assert main(["study", "agreement", "--frames", "1", "-o", str(tmp_path / "old")]) == 130
    assert (tmp_path / "old").is_dir()
    earlier = tmp_path / "results"
    (earlier / "sub").mkdir(parents=True)
    (earlier / "sub" / "agreement_summary.csv").write_text("map\n", encoding="utf-8")
    assert main(["study", "agreement", "--frames", "1", "-o", str(earlier / "sub"), "--overwrite"]) == 130
    assert (earlier / "sub" / "agreement_summary.csv").read_text(encoding="utf-8") == "map\n"


def test_a_failing_wave_study_leaves_no_empty_output_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import mmusv.studies.waves as waves
    from mmusv.errors import MmusvError

    def fails(*args: Any, **kwargs: Any) -> Any:
        raise MmusvError("the study failed")

    monkeypatch.setattr(waves, "run_wave_study", fails)
    assert main(["study", "waves", "--frames", "2", "-o", str(tmp_path / "waves")]) == 2
    assert "the study failed" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------ a spec where a scenario goes


@pytest.mark.parametrize(
    "argv",
    [
        ["study", "agreement", SPEC, "--frames", "1"],
        ["run", SPEC],
        ["study", "waves", "--scenario", SPEC],
    ],
)
def test_a_generation_spec_given_as_a_scenario_is_said_in_one_short_line(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([*argv, "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and len(err) < 400, err
    assert f"{SPEC} is a generation spec" in err and f"mmusv generate {SPEC}" in err, err
    assert "invalid config" not in err and not (tmp_path / "out").exists()


def test_a_scenario_given_as_a_spec_and_bundled_names_of_the_other_kind(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["generate", SCENARIO, "-o", str(tmp_path / "gen")]) == 2
    err = capsys.readouterr().err
    assert f"{SCENARIO} is a scenario" in err and f"mmusv run {SCENARIO}" in err and "invalid spec" not in err, err
    assert main(["run", "island_demo", "-o", str(tmp_path / "run")]) == 2
    assert "(island_demo is a bundled generation spec: mmusv generate island_demo)" in capsys.readouterr().err
    assert main(["generate", "port_entry", "-o", str(tmp_path / "gen")]) == 2
    assert "(port_entry is a bundled scenario: mmusv run port_entry)" in capsys.readouterr().err


def test_a_valid_scenario_and_spec_still_load() -> None:
    from mmusv.config import load_scenario
    from mmusv.generate.spec import load_spec

    assert load_scenario(SCENARIO).name and load_spec(SPEC).name


# ------------------------------------------------------------------------------------- train's failed scorer fit


def test_a_failed_scorer_fit_is_not_redone_by_a_rerun(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("torch")
    import mmusv.learn.scorer as scorer_module
    from mmusv.acquire import run
    from mmusv.learn._errors import input_error
    from mmusv.studies.detection.sources import lidar_only

    data = lidar_only(yaml.safe_load((ROOT / "scenarios/island_occlusion.yaml").read_text(encoding="utf-8")))
    data["vessels"] = [v for v in data["vessels"] if v["role"] != "usv" or v["id"] in ("usv_1", "usv_3")]
    data["name"], data["acquisition"]["frames"] = "scorer_rerun", 2
    rec = run(data, out_dir=tmp_path / "rec").recording
    fits: list[int] = []

    def too_few_boxes(*args: Any, **kwargs: Any) -> Any:  # as a model that finds (almost) nothing
        fits.append(1)
        raise input_error("fitting the IoU scorer: the model found 0 boxes on the training part of the samples")

    monkeypatch.setattr(scorer_module, "fit_scorer", too_few_boxes)
    out = tmp_path / "out"
    argv = ["train", str(rec), "--preset", "tiny", "--split", "all", "--modes", "single", "--epochs", "1"]
    argv += ["--threads", "1", "--no-progress", "-o", str(out)]
    assert main(argv) == 0 and len(fits) == 1
    record = json.loads((out / "single" / "scorer_skipped.json").read_text(encoding="utf-8"))
    assert "0 boxes" in record["reason"] and record["seed"] == 0
    capsys.readouterr()
    assert main(argv) == 0 and len(fits) == 1  # the same weights, cache and seed: not fitted again
    said = capsys.readouterr().out
    assert "single: no IoU scorer (its fit failed before for these weights and data" in said, said
    assert f"mmusv train --scorers-only -o {out}" in said, said
    summary = json.loads((out / "train_summary.json").read_text(encoding="utf-8"))
    assert "0 boxes" in summary["scorers"]["single"]["skipped"]
    # --scorers-only tries again; another seed (other data for the fit) does too
    assert main([*argv, "--scorers-only"]) == 0 and len(fits) == 2
    assert main([*argv, "--seed", "1", "-o", str(tmp_path / "seed1")]) == 0 and len(fits) == 3
