"""The learned detector's messages name what their user gave: the keyword argument (``path = '...'``,
``rescore = True``, ``items[0] = '...'``, ``cache = '...'``) when called from Python, the flag (``--model``,
``--rescore on``, ``--set``, ``--cache``) from the command line. They named the flags from Python too."""

from __future__ import annotations

from pathlib import Path

import pytest
from mmusv.cli import main
from mmusv.errors import InputError
from mmusv.learn.cache import Cache
from mmusv.learn.cli import load_for_study
from mmusv.learn.detector import load_models
from mmusv.learn.presets import parse_overrides, preset
from mmusv.learn.train import main as train_main
from mmusv.learn.train import train

from learn.scenes import SCENES, MemorySource


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("names_model") / "single"
    train(MemorySource(SCENES[:1]), p=preset("tiny"), mode="single", out=out, epochs=1, max_steps=1, progress=False)
    return out / "model.pt"


def _cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    capsys.readouterr()
    assert main(argv) == 2
    return capsys.readouterr().err


def test_a_cache_is_named_by_the_argument_that_gave_it(tmp_path: Path) -> None:
    bad = tmp_path / "c.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(InputError, match=rf"^path = '{bad}': not a readable \.npz cache") as err:
        Cache(bad)
    assert "--cache" not in str(err.value)
    with pytest.raises(InputError, match=rf"^cache = '{bad}': not a readable \.npz cache"):
        train(bad, p=preset("tiny"), mode="single", out=tmp_path / "m", progress=False)
    with pytest.raises(InputError, match=rf"^--cache {bad}: not a readable \.npz cache"):  # scripts/learn_train.py
        train_main(["--cache", str(bad), "-o", str(tmp_path / "m")])


def test_a_bad_mode_is_named_by_the_argument(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"^mode = 'fancy': allowed: single, early, intermediate"):
        train(MemorySource(SCENES[:1]), p=preset("tiny"), mode="fancy", out=tmp_path, progress=False)


def test_a_preset_override_is_named_by_its_item_or_by_set() -> None:
    with pytest.raises(InputError, match=r"^items\[1\] = 'foo=1': expected KEY=VALUE") as err:
        parse_overrides(["min_points=1", "foo=1"])
    assert "--set" not in str(err.value)
    with pytest.raises(InputError, match=r"^--set 'foo=1': expected KEY=VALUE"):
        train_main(["--cache", "unread.npz", "-o", "unwritten", "--set", "foo=1"])
    with pytest.raises(InputError, match=r"^items = 'min_points=1': must be a list of KEY=VALUE strings"):
        parse_overrides("min_points=1")  # type: ignore[arg-type]


def test_load_models_names_path_and_the_study_names_model(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    nowhere = tmp_path / "nowhere"
    with pytest.raises(InputError, match=rf"^path = '{nowhere}': no model\.pt there") as err:
        load_models(nowhere)
    assert "--model" not in str(err.value)
    with pytest.raises(InputError, match=rf"^--model {nowhere}: no model\.pt there"):  # the study's own loader
        load_for_study(str(nowhere))
    err_line = _cli(["study", "detection", "x.mcap", "--model", str(nowhere), "-o", str(tmp_path / "o")], capsys)
    assert err_line.startswith(f"mmusv: error: --model {nowhere}: no model.pt there"), err_line


def test_rescore_is_named_as_given(model: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(InputError, match=r"^rescore = True needs the refined boxes \(refine = True;") as err:
        load_models(model, refine=False, rescore=True)
    assert "--" not in str(err.value)
    with pytest.raises(InputError, match=r"^rescore = True: single has no .*scorer\.pt"):
        load_models(model, refine=True, rescore=True)
    argv = ["study", "detection", "x.mcap", "--model", str(model), "-o", str(tmp_path / "o")]
    said = _cli([*argv, "--refine", "off", "--rescore", "on"], capsys)
    assert said.startswith("mmusv: error: --rescore on needs the refined boxes (--refine on;"), said
    said = _cli([*argv, "--refine", "on", "--rescore", "on"], capsys)
    assert said.startswith("mmusv: error: --rescore on: single has no "), said


def test_split_ratios_are_named_as_given(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The split's fractions were called "split" by every entry point ("split '1,2'", "split[1] = nan"), and
    "--split-ratios: split '1,2'" by the commands: now the keyword argument (``ratios`` of assign_splits and the
    detection study's split_sequences) from Python, ``--split-ratios`` as typed from mmusv train and mmusv study."""
    from mmusv.errors import ConfigError
    from mmusv.export.splits import assign_splits
    from mmusv.studies.detection.data import split_sequences

    with pytest.raises(ConfigError, match=r"^ratios = '1,2': expected three fractions") as err:
        assign_splits(["a", "b"], ratios="1,2", seed=0)  # type: ignore[arg-type]
    assert "split" not in str(err.value)
    with pytest.raises(ConfigError, match=r"^ratios\[1\] = nan: must be a number"):
        split_sequences(["a", "b"], split="train", ratios=(0.5, float("nan"), 0.5), seed=0)
    for command in (["train", "x.mcap"], ["study", "detection", "x.mcap"]):
        said = _cli([*command, "-o", str(tmp_path / "o"), "--split-ratios", "1,2"], capsys)
        assert said.startswith("mmusv: error: --split-ratios 1,2: expected three fractions"), said
        assert "ratios =" not in said and "split '" not in said, said
    assert not (tmp_path / "o").exists()
