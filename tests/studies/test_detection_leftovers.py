"""``mmusv study detection|robustness``: a sequence with one USV is scored in mode ``none`` only (it refused the whole
dataset), the report is written after every run is computed and atomically (an interruption left half a report),
and a ``--model`` folder of models of other presets or seeds is named (the modes compared models of different
training without a word). Tiny data: 3 frames, LiDAR only."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import polars as pl
import pytest
from mmusv.cli import main
from test_detection_study import record

REPORT = ("detection_table.csv", "detection_boxes.parquet", "detection_ap.png", "detection_note.txt")


@pytest.fixture(scope="module")
def mixed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder of two recordings of 3 frames: ``tiny_2usv`` (2 USVs) and ``tiny_1usv`` (1 USV)."""
    root = tmp_path_factory.mktemp("mixed")
    folder = root / "recordings"
    folder.mkdir()
    for usvs in (("usv_1", "usv_3"), ("usv_1",)):
        rec = record(root / f"r{len(usvs)}", usvs, frames=3)
        shutil.copy(rec, folder / rec.name)
    return folder


def _study(args: list[str], out: Path) -> int:
    return main([*args, "-o", str(out), "--no-progress"])


def test_a_one_usv_sequence_is_scored_in_none_only(
    mixed: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "det"
    assert _study(["study", "detection", str(mixed)], out) == 0
    text = capsys.readouterr().out
    said = "scored in mode none only (one USV with a LiDAR: nothing to fuse): tiny_1usv"
    assert said in " ".join(text.split()), text
    assert said in (out / "detection_note.txt").read_text(encoding="utf-8")
    table = pl.read_csv(out / "detection_table.csv")
    assert table["mode"].to_list() == ["none", "late", "early"]
    frames = dict(zip(table["mode"], table["frames"], strict=True))
    ego_frames = dict(zip(table["mode"], table["ego_frames"], strict=True))
    assert frames == {"none": 6, "late": 3, "early": 3}  # the lone sequence's 3 frames count for none only
    assert ego_frames == {"none": 9, "late": 6, "early": 6}
    boxes = pl.read_parquet(out / "detection_boxes.parquet")
    assert set(boxes.filter(pl.col("sequence") == "tiny_1usv")["mode"].to_list()) == {"none"}
    assert set(boxes.filter(pl.col("sequence") == "tiny_2usv")["mode"].to_list()) == {"none", "late", "early"}
    # the sequence with two USVs scores as it does alone
    alone = tmp_path / "alone"
    shutil.copytree(mixed, alone, ignore=shutil.ignore_patterns("tiny_1usv*"))
    assert _study(["study", "detection", str(alone)], tmp_path / "a") == 0
    capsys.readouterr()
    two = pl.read_csv(tmp_path / "a" / "detection_table.csv")
    assert two.filter(pl.col("mode") != "none").equals(table.filter(pl.col("mode") != "none"))
    # without mode none the lone sequence is not scored, said in words for both entry points (not as a flag)
    assert _study(["study", "detection", str(mixed), "--modes", "late"], tmp_path / "late") == 0
    unscored = "not scored (one USV with a LiDAR: nothing to fuse, and mode none was not asked for): tiny_1usv"
    assert unscored in " ".join(capsys.readouterr().out.split())
    assert unscored in (tmp_path / "late" / "detection_note.txt").read_text(encoding="utf-8")
    # over two processes: the same bytes
    assert _study(["study", "detection", str(mixed), "--jobs", "2"], tmp_path / "j") == 0
    assert said in " ".join(capsys.readouterr().out.split())
    for name in REPORT:
        assert (out / name).read_bytes() == (tmp_path / "j" / name).read_bytes(), name


def test_a_one_usv_sequence_in_the_robustness_study(
    mixed: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "rob"
    assert _study(["study", "robustness", str(mixed), "--settings", "delay:1,noise:1/1"], out) == 0
    assert "tiny_1usv" in " ".join(capsys.readouterr().out.split())
    boxes = pl.read_parquet(out / "robustness_boxes.parquet")
    lone = boxes.filter(pl.col("sequence") == "tiny_1usv")
    assert set(zip(lone["setting"], lone["mode"], strict=True)) == {("clean", "none")}
    assert "tiny_1usv" in (out / "robustness_note.txt").read_text(encoding="utf-8")
    # only sequences of one USV and no mode none: nothing to score, said
    lone_only = tmp_path / "lone"
    shutil.copytree(mixed, lone_only, ignore=shutil.ignore_patterns("tiny_2usv*"))
    assert _study(["study", "detection", str(lone_only), "--modes", "late"], tmp_path / "o") == 2
    err = " ".join(capsys.readouterr().err.split())
    assert "empty dataset" in err and "tiny_1usv" in err and "one USV with a LiDAR" in err and "--modes" in err, err
    # with mode none they are scored there
    assert _study(["study", "detection", str(lone_only)], tmp_path / "n") == 0
    capsys.readouterr()
    assert pl.read_csv(tmp_path / "n" / "detection_table.csv")["mode"].to_list() == ["none"]


def test_an_interrupted_report_leaves_no_half_of_it(
    pair: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from mmusv.studies.detection import report

    out = tmp_path / "det"
    assert _study(["study", "detection", str(pair), "--modes", "none"], out) == 0
    before = {name: (out / name).read_bytes() for name in REPORT}

    def interrupted(*args: Any, **kwargs: Any) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(report, "_plot_detection", interrupted)  # Ctrl-C while the plot is drawn
    assert _study(["study", "detection", str(pair), "--overwrite"], out) == 130
    assert "interrupted" in capsys.readouterr().err
    # the earlier report whole, not a new table beside the old plot
    assert {name: (out / name).read_bytes() for name in REPORT} == before
    assert sorted(p.name for p in out.iterdir()) == sorted(REPORT)  # no temporary file either
    fresh = tmp_path / "fresh"
    assert _study(["study", "detection", str(pair)], fresh) == 130
    assert not fresh.exists() or not any(fresh.iterdir())


def _models(folder: Path, made: dict[str, tuple[str, int]]) -> Path:
    """A ``--model`` folder of untrained models: ``{mode: (preset, seed)}``, each written as mmusv train writes it."""
    import torch
    from mmusv.learn.checkpoint import save_checkpoint
    from mmusv.learn.model import PillarNet
    from mmusv.learn.presets import preset

    for mode, (name, seed) in made.items():
        torch.manual_seed(seed)
        p = preset(name)
        (folder / mode).mkdir(parents=True, exist_ok=True)
        state = {"preset": p.to_dict(), "mode": mode, "seed": seed, "epoch": 1, "epochs": 1, "stopped": None}
        state |= {"step": 1, "log": [], "data": None, "model": PillarNet(p, mode).state_dict()}
        save_checkpoint(state, folder / mode / "model.pt")
    return folder


@pytest.fixture(scope="module")
def pair(mixed: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The recording of 2 USVs alone (3 frames)."""
    folder = tmp_path_factory.mktemp("pair")
    shutil.copy(mixed / "tiny_2usv.mcap", folder / "tiny_2usv.mcap")
    return folder


@pytest.mark.filterwarnings("always::mmusv.scenario_checks.MmusvWarning")  # said on stderr by mmusv's main
def test_models_of_other_presets_or_seeds_are_named(
    pair: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("torch")
    base = ["study", "detection", str(pair), "--refine", "off"]
    presets = _models(tmp_path / "presets", {"single": ("tiny", 0), "early": ("cpu", 0)})
    assert _study([*base, "--model", str(presets), "--modes", "none,early"], tmp_path / "p") == 0
    err = " ".join(capsys.readouterr().err.split())
    assert f"mmusv: warning: --model {presets}: its models were trained with other presets or seeds" in err, err
    assert "(single: preset tiny, seed 0; early: preset cpu, seed 0)" in err and "mmusv train" in err, err
    note = (tmp_path / "p" / "detection_note.txt").read_text(encoding="utf-8")
    assert "single: preset tiny, seed 0; early: preset cpu, seed 0" in note
    assert "seed 0" not in (tmp_path / "p" / "baseline" / "detection_note.txt").read_text(encoding="utf-8")
    seeds = _models(tmp_path / "seeds", {"single": ("tiny", 0), "early": ("tiny", 1)})
    assert _study([*base, "--model", str(seeds), "--modes", "late,early"], tmp_path / "s") == 0
    assert "(single: preset tiny, seed 0; early: preset tiny, seed 1)" in " ".join(capsys.readouterr().err.split())
    # one model scored (none and late run the single model), or models of one training: nothing said
    assert _study([*base, "--model", str(presets), "--modes", "none,late"], tmp_path / "n") == 0
    same = _models(tmp_path / "same", {"single": ("tiny", 3), "early": ("tiny", 3)})
    assert _study([*base, "--model", str(same), "--modes", "none,early"], tmp_path / "t") == 0
    assert "warning" not in capsys.readouterr().err


def test_a_second_run_interrupted_leaves_no_report_of_the_first(
    pair: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """With --model the learned model's run and the baseline's beside it: the first's report was written before the
    second ran, so a Ctrl-C in the second left a report that looked complete."""
    pytest.importorskip("torch")
    from mmusv.studies.detection import study

    models = _models(tmp_path / "m", {"single": ("tiny", 0)})
    calls: list[int] = []
    real = study.run_study

    def second_interrupted(*args: Any, **kwargs: Any) -> Any:
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(study, "run_study", second_interrupted)
    out = tmp_path / "o"
    assert _study(["study", "detection", str(pair), "--model", str(models), "--refine", "off"], out) == 130
    assert len(calls) == 2
    assert "interrupted" in capsys.readouterr().err
    assert not out.exists() or not any(out.rglob("*.*")), sorted(out.rglob("*"))
    monkeypatch.setattr(study, "run_study", real)
    assert _study(["study", "detection", str(pair), "--model", str(models), "--refine", "off"], out) == 0
    assert all((out / name).is_file() and (out / "baseline" / name).is_file() for name in REPORT)


def test_only_the_models_of_the_asked_modes_are_read(
    pair: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # a damaged early/model.pt stopped --modes none,late, which runs the single model alone (read before the modes)
    pytest.importorskip("torch")
    models = _models(tmp_path / "models", {"single": ("tiny", 0), "early": ("tiny", 0)})
    (models / "early" / "model.pt").write_bytes(b"PK\x03\x04 cut short")
    base = ["study", "detection", str(pair), "--refine", "off", "--model", str(models)]
    for jobs in ("1", "2"):
        assert _study([*base, "--modes", "none,late", "--jobs", jobs], tmp_path / f"nl{jobs}") == 0, jobs
        note = (tmp_path / f"nl{jobs}" / "detection_note.txt").read_text(encoding="utf-8")
        assert "early" not in note.split("learned models:")[1].split("\n")[0], note
    capsys.readouterr()
    for jobs in ("1", "2"):
        assert (tmp_path / "nl1" / "detection_table.csv").read_bytes() == (
            tmp_path / f"nl{jobs}" / "detection_table.csv"
        ).read_bytes()
    # a mode that runs it still names the file
    assert _study([*base, "--modes", "none,early"], tmp_path / "ne") == 2
    assert f"--model {models / 'early' / 'model.pt'}: not an mmusv.learn model.pt" in capsys.readouterr().err
