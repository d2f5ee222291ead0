"""The learned detector's user paths met again (``mmusv train``, ``mmusv study detection --model``), on the tiny
preset and in-memory scenes.

Each test failed before its fix: ``--modes early`` with a ``--model`` folder holding the ``single`` model alone
said "--model OUT: no model.pt there", where one is; a ``log.jsonl`` cut short (it was written in place) stayed so,
and the same command run again failed plotting it; ``--detector baseline`` with ``--model`` or ``--predictions`` was
ignored (it is the default); a ``model.pt`` of another seed without its ``last.pt`` was replaced by training;
``scripts/learn_train.py infer`` / ``merge`` and ``python -m mmusv.learn.replay`` with ``-o`` a folder failed after
the work, naming and leaving a temporary file; an ``-o`` that cannot be made was found by the study after its
evaluation, and by ``mmusv train`` in a message without ``-o``; ``python -m mmusv.learn.replay`` could not take the
OPV2V folder a cache was built from, and told to give it "as opv2v = '...'"; a ``--model`` file of bytes that are
no pickle (YAML, text) was a traceback of the unpickler, and JSON said to hold "objects other than tensors";
``scripts/learn_train.py`` (:func:`mmusv.learn.train.train`) took ``--epochs 0``, a NaN or negative ``--time-limit``
and ``--max-steps 0`` (training nothing, or without a limit), and ``--seed -1``, ``--workers -1`` and
``--device tpu`` were tracebacks; ``scripts/learn_train.py infer --limit -1`` inferred every item but the last,
``--device tpu`` was a traceback, ``--modes ''`` said "no /model.pt there", and ``merge`` of a file that is no
``.npz`` was a traceback; ``mmusv train --scorers-only`` left ``train_summary.json``'s ``scorers`` as the training
wrote them; a folder where ``mmusv train`` writes a file (``train_summary.json``, the cache, ``model.pt``) failed
when written, naming a temporary file, the summary after the training.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from mmusv.cli import main
from mmusv.learn.presets import preset
from mmusv.learn.train import train

from learn.scenes import SCENES, MemorySource


@pytest.fixture(scope="module")
def single(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``mmusv train``'s output folder holding the single model alone (tiny preset, one epoch)."""
    out = tmp_path_factory.mktemp("round15") / "models"
    train(MemorySource(SCENES), p=preset("tiny"), mode="single", out=out / "single", epochs=1, progress=False)
    return out


def _study(tmp_path: Path, *extra: str) -> int:
    rec = tmp_path / "x.mcap"  # refused before any recording is read
    rec.touch()
    return main(["study", "detection", str(rec), "--no-progress", "-o", str(tmp_path / "study"), *extra])


def test_modes_of_a_model_the_folder_lacks_name_the_mode(
    single: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert _study(tmp_path, "--model", str(single), "--modes", "early") == 2
    err = capsys.readouterr().err
    assert "no model.pt there" not in err, err
    assert f"--modes early: needs the early model, which --model {single} does not hold (it has single" in err, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert not (tmp_path / "study").exists()
    assert _study(tmp_path, "--model", str(single), "--modes", "early,intermediate") == 2
    err = capsys.readouterr().err
    assert "--modes early,intermediate: needs the early and intermediate models, which" in err, err  # was: model


def test_a_log_cut_short_is_whole_again_when_the_run_is_started_again(tmp_path: Path) -> None:
    from mmusv.learn.plots import plot_losses

    src, p = MemorySource(SCENES), preset("tiny")
    train(src, p=p, mode="single", out=tmp_path, epochs=1, progress=False)
    log = tmp_path / "log.jsonl"
    whole = log.read_bytes()
    log.write_bytes(whole[: len(whole) // 2])  # a run interrupted while it wrote the log (it was written in place)
    # the same command again: nothing left to train, and plotting the log was a JSONDecodeError traceback
    again = train(src, p=p, mode="single", out=tmp_path, epochs=1, progress=False)
    assert again.epochs == 1
    assert log.read_bytes() == whole
    assert plot_losses(log, tmp_path / "loss.png").is_file()
    assert not list(tmp_path.glob(".*.tmp"))


def test_detector_baseline_given_with_model_or_predictions_is_refused(
    single: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # --detector baseline was the default itself, so given with --model the model was scored without a word
    assert _study(tmp_path, "--model", str(single), "--detector", "baseline") == 2
    err = capsys.readouterr().err
    assert "give one of --model, --detector or --predictions" in err and "Traceback" not in err, err
    boxes = tmp_path / "boxes.parquet"  # refused before it is read
    boxes.touch()
    assert _study(tmp_path, "--predictions", str(boxes), "--detector", "baseline") == 2
    err = capsys.readouterr().err
    assert "give --detector or --predictions, not both" in err and "Traceback" not in err, err
    assert not (tmp_path / "study").exists()


def test_a_model_of_another_run_without_its_last_checkpoint_is_not_replaced(
    single: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import shutil

    from mmusv.errors import InputError

    out = tmp_path / "m"
    shutil.copytree(single / "single", out)
    (out / "last.pt").unlink()  # removed (it holds the optimiser too), or the model.pt alone copied there
    model = (out / "model.pt").read_bytes()
    # another seed into the folder: it trained from the start and replaced the model without a word
    with pytest.raises(InputError, match=r"model\.pt: a model of another run \(seed 0, this run 5\), without its last"):
        train(MemorySource(SCENES), p=preset("tiny"), mode="single", out=out, seed=5, epochs=1, progress=False)
    assert (out / "model.pt").read_bytes() == model
    # the same run trains again as before (the same seed, the same weights)
    train(MemorySource(SCENES), p=preset("tiny"), mode="single", out=out, epochs=1, progress=False)
    assert (out / "model.pt").read_bytes() == model


def test_an_output_file_that_is_a_folder_is_refused_before_the_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import numpy as np
    from mmusv.errors import InputError
    from mmusv.learn._errors import command
    from mmusv.learn.infer import infer_cache, merge_main

    folder = tmp_path / "peaks"
    folder.mkdir()
    part = tmp_path / "single.npz"
    np.savez(part, single_boxes=np.zeros((0, 7), np.float32))
    # it failed when written, naming its temporary file (".peaks.partial: Is a directory"), and left that file
    assert command(merge_main, ["-o", str(folder), str(part)]) == 2
    err = capsys.readouterr().err
    assert err == f"mmusv: error: -o {folder}: a folder; give the name of the file to write\n", err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["peaks", "single.npz"]
    # infer: before any model runs (the peaks were computed first, minutes on a GPU)
    with pytest.raises(InputError, match=r"out = '.*peaks': a folder; give the name"):
        infer_cache(MemorySource(SCENES), models=tmp_path, out=folder)  # type: ignore[arg-type]


def test_an_output_folder_that_cannot_be_made_is_named_before_the_work(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    locked = tmp_path / "locked"
    made = Path.mkdir

    def mkdir(self: Path, *args: object, **kwargs: object) -> None:  # a folder this user may not write (root may)
        if self == locked:
            raise PermissionError(13, "Permission denied", str(self))
        made(self, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(Path, "mkdir", mkdir)
    rec = tmp_path / "x.mcap"  # the -o refusal comes before any recording is read
    rec.touch()
    said = f"mmusv: error: -o/--output {locked}: cannot create the folder: Permission denied\n"
    # the study evaluated every frame, then failed writing its tables ("cannot write .../detection_table.csv")
    assert main(["study", "detection", str(rec), "--no-progress", "-o", str(locked)]) == 2
    assert capsys.readouterr().err == said
    # mmusv train named the folder without its -o ("mmusv: error: ...: Permission denied") when building the cache
    argv = ["train", str(rec), "--preset", "tiny", "--modes", "single", "--epochs", "1", "--threads", "1"]
    assert main([*argv, "--no-scorers", "--no-progress", "-o", str(locked)]) == 2
    assert capsys.readouterr().err == said


@pytest.fixture(scope="module")
def opv2v_cache(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """An OPV2V folder converted from a 3-frame, 2-USV LiDAR-only recording, and the tensor cache of all of it."""
    import yaml
    from mmusv.acquire import run
    from mmusv.learn.cache import build_cache
    from mmusv.studies.detection.sources import lidar_only

    tmp = tmp_path_factory.mktemp("round15_opv2v")
    root = Path(__file__).resolve().parents[2]
    data = lidar_only(yaml.safe_load((root / "scenarios" / "island_occlusion.yaml").read_text(encoding="utf-8")))
    usvs = [v["id"] for v in data["vessels"] if v["role"] == "usv"][:2]
    data["vessels"] = [v for v in data["vessels"] if v["role"] != "usv" or v["id"] in usvs]
    data["name"], data["acquisition"]["frames"] = "r15", 3
    rec = run(data, out_dir=tmp / "rec").recording
    opv = tmp / "opv"
    assert main(["convert", str(rec), "--to", "opv2v", "-o", str(opv), "--no-progress"]) == 0
    return opv, build_cache([], tmp / "cache.npz", opv2v=str(opv), split="all")


def test_replay_takes_the_opv2v_folder_a_cache_was_built_from(
    opv2v_cache: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.learn import replay
    from mmusv.learn._errors import command
    from mmusv.learn.cache import Cache
    from mmusv.learn.infer import infer_cache

    opv, cache = opv2v_cache
    capsys.readouterr()
    train(Cache(cache), p=preset("tiny"), mode="single", out=tmp_path / "models" / "single", epochs=1, progress=False)
    peaks = infer_cache(Cache(cache), models=tmp_path / "models", out=tmp_path / "peaks.npz")
    argv = [str(peaks), str(cache), "--split", "all", "-o", str(tmp_path / "p.parquet")]
    # given as a recording, it was told to be given "as opv2v = '...'", which the command had no way to take
    assert command(replay.main, [*argv, str(opv)]) == 2
    err = capsys.readouterr().err
    assert f"it is an OPV2V folder: give it as --opv2v {opv};" in err, err
    assert command(replay.main, [*argv, "--opv2v", str(opv)]) == 0
    assert (tmp_path / "p.parquet").is_file()


@pytest.mark.parametrize(
    ("content", "said"),
    [
        (b"a: 1\nb: [2, 3]\n", "not a PyTorch checkpoint"),  # a YAML file: an IndexError traceback
        (b"hello world\n", "not a PyTorch checkpoint"),  # a KeyError traceback
        (b'{"model": "x"}\n', "not a PyTorch checkpoint"),  # said to hold "objects other than tensors"
        (b"", "empty"),
    ],
)
def test_a_model_file_of_other_bytes_is_named_without_a_traceback(
    content: bytes, said: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    model = tmp_path / "model.pt"
    model.write_bytes(content)
    assert _study(tmp_path, "--model", str(model)) == 2
    err = capsys.readouterr().err
    assert err == f"mmusv: error: --model {model}: not an mmusv.learn model.pt ({said})\n", err


@pytest.mark.parametrize(
    ("flag", "value", "said"),
    [
        ("--epochs", "0", "--epochs 0: must be a whole number >= 1"),  # trained nothing, "finished=True"
        ("--epochs", "-3", "--epochs -3: must be a whole number >= 1"),
        ("--time-limit", "nan", "--time-limit nan: seconds, a finite number > 0"),  # ignored: trained without one
        ("--time-limit", "-1", "--time-limit -1"),  # no step, no model
        ("--max-steps", "0", "--max-steps 0: must be a whole number >= 1"),
        ("--seed", "-1", "--seed -1: must be a whole number in 0.."),  # a numpy traceback
        ("--workers", "-1", "--workers -1: must be a whole number >= 0"),  # a torch traceback
        ("--device", "tpu", "--device tpu: not a device; allowed: cpu, cuda, cuda:N or mps"),  # a torch traceback
        ("--threads", "0", "--threads 0: must be a whole number >= 1"),  # taken as 1 without a word
        ("--threads", "-2", "--threads -2: must be a whole number >= 1"),
    ],
)
def test_learn_train_script_refuses_bad_numbers_before_training(
    flag: str, value: str, said: str, opv2v_cache: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.learn._errors import command
    from mmusv.learn.train import main as train_main

    cache = opv2v_cache[1]
    capsys.readouterr()
    out = tmp_path / "out"
    argv = ["--cache", str(cache), "--preset", "tiny", "--no-progress", "--threads", "1", "-o", str(out)]
    assert command(train_main, [*argv, flag, value]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"mmusv: error: {said}") and err.count("\n") == 1, err
    assert not out.exists()


@pytest.mark.parametrize(
    ("extra", "said"),
    [
        (
            ["--limit", "-1"],
            "--limit -1: must be a whole number >= 1 (or left out for every item)",
        ),  # every item but the last, without a word
        (["--limit", "0"], "--limit 0: must be a whole number >= 1 (or left out for every item)"),  # no item
        (["--device", "tpu"], "--device tpu: not a device; allowed: cpu, cuda, cuda:N or mps"),  # a torch traceback
        (["--modes", ""], "--modes '': no model named; allowed: single, early, intermediate"),  # "no /model.pt there"
    ],
)
def test_learn_train_infer_refuses_bad_options(
    extra: list[str],
    said: str,
    single: Path,
    opv2v_cache: tuple[Path, Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    from mmusv.learn._errors import command
    from mmusv.learn.infer import main as infer_main

    capsys.readouterr()
    out = tmp_path / "peaks.npz"
    argv = ["--cache", str(opv2v_cache[1]), "--models", str(single), "-o", str(out), *extra]
    assert command(infer_main, argv) == 2
    err = capsys.readouterr().err
    assert err == f"mmusv: error: {said}\n", err
    assert not out.exists()


def test_learn_train_merge_names_a_part_that_is_not_a_peaks_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.learn._errors import command
    from mmusv.learn.infer import merge_main

    part = tmp_path / "notes.npz"
    part.write_text("a: 1\n", encoding="utf-8")  # a numpy ValueError traceback
    assert command(merge_main, ["-o", str(tmp_path / "peaks.npz"), str(part)]) == 2
    err = capsys.readouterr().err
    assert err == f"mmusv: error: {part}: not a peaks .npz of mmusv.learn.infer (ValueError)\n", err


def test_scorers_only_records_its_fits_in_the_summary(
    opv2v_cache: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import json
    import shutil

    out = tmp_path / "m"
    out.mkdir()
    shutil.copy(opv2v_cache[1], out / "cache_all.npz")
    argv = ["train", "--opv2v", str(opv2v_cache[0]), "--split", "all", "--preset", "tiny", "--modes", "single"]
    argv += ["--epochs", "1", "--threads", "1", "--no-progress", "-o", str(out)]
    assert main([*argv, "--no-scorers"]) == 0
    assert "scorers" not in json.loads((out / "train_summary.json").read_text(encoding="utf-8"))
    assert main([*argv, "--scorers-only"]) == 0
    said = capsys.readouterr().out
    summary = json.loads((out / "train_summary.json").read_text(encoding="utf-8"))
    # it was left as the training wrote it: no word of the fit (here: too few boxes, which the line says)
    assert set(summary["scorers"]) == {"single"}, summary
    fit = summary["scorers"]["single"]
    assert ("skipped" in fit and fit["skipped"] in said) or (out / "single" / "scorer.pt").is_file(), (fit, said)
    assert list(summary["models"]) == ["single"]


@pytest.mark.parametrize(
    ("folder", "said"),
    [
        ("train_summary.json", "train_summary.json is a folder (or another non-file), where a file"),
        ("cache_all.npz", "cache_all.npz is a folder (or another non-file), where a file"),
        ("single/model.pt", "single/model.pt is a folder (or another non-file), where a file"),
    ],
)
def test_train_refuses_what_is_in_the_way_of_its_files_before_the_work(
    folder: str, said: str, opv2v_cache: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "m"
    (out / folder).mkdir(parents=True)
    argv = ["train", "--opv2v", str(opv2v_cache[0]), "--split", "all", "--preset", "tiny", "--modes", "single"]
    # each failed when written, naming a temporary file ("Is a directory"), the summary after the training
    assert main([*argv, "--epochs", "1", "--threads", "1", "--no-scorers", "--no-progress", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"mmusv: error: -o/--output {out}: {said}") and err.count("\n") == 1, err
    assert not (out / "single" / "last.pt").exists()


@pytest.mark.parametrize("command", [["train"], ["study", "detection"]])
def test_a_missing_generate_spec_is_named_by_its_flag(
    command: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    assert main([*command, "--generate", "nosuch.yaml", "--no-progress", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    # was: "spec file 'nosuch.yaml' does not exist ..." without the flag
    assert err.startswith("mmusv: error: --generate nosuch.yaml: spec file 'nosuch.yaml' does not exist"), err
    assert "bundled: coop_detection" in err and err.count("\n") == 1, err
    assert not out.exists()


def test_a_predictions_folder_is_said_to_be_a_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "predictions"
    folder.mkdir()
    assert _study(tmp_path, "--predictions", str(folder)) == 2
    err = capsys.readouterr().err
    assert err == f"mmusv: error: --predictions {folder}: a folder; give the predictions Parquet file\n", err  # was:
    # "no such file"
