"""The detection study's messages name what their user gave: the keyword argument (``path = '...'``, ``spec =
'...'``, ``opv2v = '...'``) when its API is called from Python, the flag as typed (``--predictions ...``,
``--detector ...``, ``--opv2v ...``) from ``mmusv study`` and ``mmusv train``, also in the worker processes of
``--jobs``. They named the flags to a Python caller (``--predictions x: no such file``, ``--detector 'x'``, ``give
recordings or --opv2v DIR``, ``(try --split all)``)."""

from __future__ import annotations

from pathlib import Path

import polars as pl
import pytest
import yaml
from mmusv.cli import main
from mmusv.errors import ConfigError, InputError, IoError, MmusvError
from mmusv.studies.detection.detector import load_detector
from mmusv.studies.detection.parallel import DetectorSpec, run_study_jobs
from mmusv.studies.detection.predictions import check_prediction_coverage, load_predictions
from mmusv.studies.detection.robustness import Setting
from mmusv.studies.detection.sources import resolve_dataset
from mmusv.studies.detection.study import StudyOptions, StudyResult, check_predictions_used

ROOT = Path(__file__).resolve().parents[2]


def _cli(argv: list[str], out: Path, capsys: pytest.CaptureFixture[str]) -> str:
    capsys.readouterr()
    assert main([*argv, "-o", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: ") and "Traceback" not in err, err
    assert not out.exists()
    return err.removeprefix("mmusv: error: ")


def _python(call: object, error: type[MmusvError] = InputError) -> str:
    with pytest.raises(error) as err:
        call()  # type: ignore[operator]
    said = str(err.value)
    assert "--" not in said, said
    return said


@pytest.fixture(scope="module")
def rec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One frame of two USVs with a LiDAR (as tests/studies/test_study_bad_args.py records it)."""
    from mmusv.acquire import run
    from mmusv.studies.detection.sources import lidar_only

    data = lidar_only(yaml.safe_load((ROOT / "scenarios/island_occlusion.yaml").read_text(encoding="utf-8")))
    data["vessels"] = [v for v in data["vessels"] if v["role"] != "usv" or v["id"] in ("usv_1", "usv_3")]
    data["name"] = "tiny_argument_names"
    data["acquisition"]["frames"] = 1
    return Path(run(data, out_dir=tmp_path_factory.mktemp("names_rec")).recording)


def test_a_predictions_file_is_named_by_the_argument_that_gave_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = tmp_path / "missing.parquet"
    assert _python(lambda: load_predictions(missing)) == f"path = '{missing}': no such file"
    said = _cli(["study", "detection", "x.mcap", "--predictions", str(missing)], tmp_path / "o", capsys)
    assert said == f"--predictions {missing}: no such file\n", said
    columns = tmp_path / "columns.parquet"
    pl.DataFrame({"sequence": ["a"], "frame": [0]}).write_parquet(columns)
    assert _python(lambda: load_predictions(columns)).startswith(f"path = '{columns}': missing column(s) ['ego',")
    said = _cli(["study", "detection", "x.mcap", "--predictions", str(columns)], tmp_path / "o", capsys)
    assert said.startswith(f"--predictions {columns}: missing column(s) ['ego',"), said


@pytest.mark.parametrize("typed", [True, False], ids=["typed", "untyped"])
def test_a_predictions_file_that_covers_nothing_names_settings_and_modes_as_given(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], typed: bool
) -> None:
    # an empty table written without a schema (pl.DataFrame({c: [] ...})) has Null columns: it was refused as
    # "column frame must hold integer acquisition indices, not Null", where the same table typed says it covers
    # nothing
    empty = tmp_path / "empty.parquet"
    schema = {"sequence": pl.Utf8, "frame": pl.Int64, "ego": pl.Utf8, "mode": pl.Utf8, "score": pl.Float64}
    schema.update(dict.fromkeys(["x", "y", "z", "l", "w", "h", "yaw"], pl.Float64))
    (pl.DataFrame(schema=schema) if typed else pl.DataFrame({c: [] for c in schema})).write_parquet(empty)
    predictions = load_predictions(empty)
    assert predictions == {}
    said = _python(lambda: check_prediction_coverage(empty, predictions, modes=("late",), settings=(Setting(),)))
    assert said.startswith(f"path = '{empty}': no row of setting clean (modes late);"), said
    assert "every setting (settings) and mode (modes) scored" in said, said
    argv = ["study", "detection", "x.mcap", "--modes", "late", "--predictions", str(empty)]
    said = _cli(argv, tmp_path / "o", capsys)
    assert said.startswith(f"--predictions {empty}: no row of setting clean (modes late);"), said
    assert "every setting (--settings) and mode (--modes) scored" in said and " = " not in said, said


def test_predictions_that_match_nothing_are_named_as_given(
    rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    res = StudyResult(options=StudyOptions(predictions={}), ego_frames=1, sequences=["a"])
    assert _python(lambda: check_predictions_used(res)).startswith("predictions: no row matches any (sequence,")
    other = tmp_path / "other.parquet"
    row = {"sequence": ["elsewhere"], "frame": [0], "ego": ["usv_1"], "mode": ["none"], "score": [0.5]}
    row.update({c: [1.0] for c in ("x", "y", "z", "l", "w", "h", "yaw")})
    pl.DataFrame(row).write_parquet(other)
    argv = ["study", "detection", str(rec), "--modes", "none", "--predictions", str(other)]
    said = _cli(argv, tmp_path / "o", capsys)
    assert said.startswith("--predictions: no row matches any (sequence,"), said


def test_a_detector_is_named_by_its_spec_or_by_detector(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    said = _python(lambda: load_detector("no_such_module:fn"), ConfigError)
    assert said.startswith("spec = 'no_such_module:fn': cannot import module 'no_such_module'"), said
    said = _cli(["study", "detection", "x.mcap", "--detector", "no_such_module:fn"], tmp_path / "o", capsys)
    assert said.startswith("--detector no_such_module:fn: cannot import module 'no_such_module'"), said


def test_a_failing_detector_is_named_as_given_in_the_jobs_processes_too(
    rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A ``--jobs`` worker process does not inherit the command's :func:`mmusv.text.command_line` block: the flags
    are passed to it, so a user's detector failing there is named as the command's user typed it, and as the
    Python caller of run_study_jobs gave it."""
    dataset = resolve_dataset([rec], opv2v=None, split="all")
    options = StudyOptions(modes=("none",))
    spec = DetectorSpec(detector="builtins:len")
    said = _python(lambda: run_study_jobs(dataset, options=options, spec=spec, jobs=2))
    assert said.startswith("spec = 'builtins:len': calling it returned int"), said
    for jobs in ("1", "2"):
        argv = ["study", "detection", str(rec), "--modes", "none", "--detector", "builtins:len", "--jobs", jobs]
        said = _cli(argv, tmp_path / "o", capsys)
        assert said.startswith("--detector builtins:len: calling it returned int"), (jobs, said)


def test_the_dataset_is_named_as_given(rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    nowhere = tmp_path / "nowhere"
    said = _python(lambda: resolve_dataset([], opv2v=nowhere, split="all"), IoError)
    assert said == f"opv2v = '{nowhere}': not a folder", said
    for command in (["study", "detection"], ["train"]):
        said = _cli([*command, "--opv2v", str(nowhere)], tmp_path / "o", capsys)
        assert said == f"--opv2v {nowhere}: not a folder\n", (command, said)
    said = _python(lambda: resolve_dataset([rec], opv2v=tmp_path, split="all"))
    assert said == "give inputs or opv2v, not both", said
    said = _cli(["study", "detection", str(rec), "--opv2v", str(tmp_path)], tmp_path / "o", capsys)
    assert said == "give recordings or --opv2v, not both\n", said
    said = _python(lambda: resolve_dataset([], opv2v=None, split="all"))
    assert said == "empty dataset: give inputs (.mcap files or folders of them) or opv2v", said
    said = _cli(["study", "detection"], tmp_path / "o", capsys)
    assert said == "empty dataset: give recordings (.mcap files or folders of them), --opv2v or --generate\n", said
    said = _python(lambda: resolve_dataset([rec], opv2v=None, split="test"))  # one recording: in train
    assert said.endswith("holds no sequence (try split = 'all')"), said
    said = _cli(["study", "detection", str(rec), "--split", "test"], tmp_path / "o", capsys)
    assert said.endswith("holds no sequence (try --split all)\n"), said


def test_intermediate_fusion_without_a_learned_model_says_how_to_give_one(
    rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.studies.detection.detector import baseline_detect
    from mmusv.studies.detection.study import run_study

    dataset = resolve_dataset([rec], opv2v=None, split="all")
    options = StudyOptions(modes=("intermediate",), detector=baseline_detect)
    said = _python(lambda: run_study(dataset.sequences(), options=options))
    assert (
        said == "intermediate fusion needs a learned model (mmusv.learn.detector.load_models), not a points -> "
        "boxes detector"
    ), said
    said = _cli(["study", "detection", str(rec), "--modes", "intermediate"], tmp_path / "o", capsys)
    assert said == "intermediate fusion needs a learned model (--model), not a points -> boxes detector\n", said
