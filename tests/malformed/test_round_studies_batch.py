"""Bad input to the batch runner, ``mmusv dataset``, the studies and ``mmusv train`` that got past the earlier
rounds (a helper's malformed-input round): a damaged count in a task's manifest was a bare ValueError before a
re-run began; a folder's broken link (or a folder named like a scenario) was skipped without a word, and a link
to a scenario was recorded under the linked file's name (two files into one folder); a damaged ``opv2v`` section
of a dataset's index was an AttributeError traceback after every recording; the agreement study counted a
scenario given twice twice; ``train --cache-only --scorers-only`` fitted the scorers. Each test fails on the code
before."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.batch import run_many
from mmusv.batch.plan import scenario_files
from mmusv.errors import ConfigError
from tiny_scenario import lidar_scenario


def _write(path: Path, data: dict[str, Any]) -> Path:
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def _scenario_folder(tmp_path: Path, *, frames: int = 1) -> Path:
    """``tmp_path/src`` holding one tiny LiDAR scenario, ``a.yaml`` of ``frames`` frames: a batch's input."""
    src = tmp_path / "src"
    src.mkdir()
    _write(src / "a.yaml", lidar_scenario("a", frames=frames))
    return src


# -------------------------------------------------------------------------------------------- batch: manifests


@pytest.mark.parametrize("count", ['"abc"', "[3]", "1e400", "true"])
def test_a_damaged_frame_count_in_a_tasks_manifest_is_recorded_again(tmp_path: Path, count: str) -> None:
    """``frames_written`` of a recording's ``manifest.json`` damaged ('abc', a list, 1e400): the re-run ended in a
    bare ValueError / TypeError / OverflowError traceback before anything ran. The task is not complete, so it is
    recorded again and the index counts its frames once it is."""
    src = _scenario_folder(tmp_path, frames=2)
    out = tmp_path / "out"
    assert run_many(src, out_dir=out).ok
    manifest = out / "a" / "manifest.json"
    text = manifest.read_text(encoding="utf-8")
    assert '"frames_written": 2' in text
    manifest.write_text(text.replace('"frames_written": 2', f'"frames_written": {count}'), encoding="utf-8")
    rep = run_many(src, out_dir=out)
    assert rep.summary() == "1 done, 0 failed, 0 skipped, 0 retried"
    assert json.loads(manifest.read_text(encoding="utf-8"))["frames_written"] == 2
    index = json.loads((out / "dataset.json").read_text(encoding="utf-8"))
    assert index["recordings"][0]["frames"] == 2 and index["recordings"][0]["status"] == "complete"


# ------------------------------------------------------------------------------------ batch: a folder's contents


def test_a_broken_link_in_a_scenario_folder_is_refused_by_name(tmp_path: Path) -> None:
    """A ``*.yaml`` link to a file that is gone was skipped without a word (the batch said '1 done')."""
    src = _scenario_folder(tmp_path)
    (src / "b.yaml").symlink_to(tmp_path / "gone.yaml")
    with pytest.raises(ConfigError, match=r"b\.yaml: a broken symbolic link \(to .*gone\.yaml\), not a scenario"):
        scenario_files(src)
    with pytest.raises(ConfigError, match=r"b\.yaml: a broken symbolic link"):
        run_many(src, out_dir=tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_a_folder_named_like_a_scenario_is_refused_by_name(tmp_path: Path) -> None:
    src = _scenario_folder(tmp_path)
    (src / "b.yaml").mkdir()
    with pytest.raises(ConfigError, match=r"b\.yaml: a folder, not a scenario file"):
        scenario_files(src)


def test_a_link_to_a_scenario_is_recorded_under_its_own_name(tmp_path: Path) -> None:
    """``c.yaml -> a.yaml`` in the folder was resolved to ``a.yaml``: both recorded into ``OUT/a``, the table listing
    a.yaml twice and the index one entry; a link to another folder's ``a.yaml`` beside this folder's own ``a.yaml``
    (another scenario) wrote both into ``OUT/a``. A link now runs under its own name, into ``OUT/<its stem>``."""
    other = tmp_path / "other"
    other.mkdir()
    _write(other / "a.yaml", lidar_scenario("other", frames=1, seed=2))
    src = _scenario_folder(tmp_path)
    (src / "c.yaml").symlink_to("a.yaml")
    (src / "d.yaml").symlink_to(other / "a.yaml")
    assert [f.name for f in scenario_files(src)] == ["a.yaml", "c.yaml", "d.yaml"]
    assert [f.name for f in scenario_files([src / "d.yaml", src / "a.yaml"])] == ["a.yaml", "d.yaml"]
    out = tmp_path / "out"
    rep = run_many(src, out_dir=out)
    assert rep.summary() == "3 done, 0 failed, 0 skipped, 0 retried"
    assert [(o.file.name, o.recording) for o in rep.outcomes] == [
        ("a.yaml", out / "a" / "a.mcap"),
        ("c.yaml", out / "c" / "a.mcap"),
        ("d.yaml", out / "d" / "other.mcap"),
    ]
    index = json.loads((out / "dataset.json").read_text(encoding="utf-8"))
    assert [(r["scenario_file"], r["recording"]) for r in index["recordings"]] == [
        ("a.yaml", "a/a.mcap"),
        ("c.yaml", "c/a.mcap"),
        ("d.yaml", "d/other.mcap"),
    ]


@pytest.mark.parametrize("blocked", ["parts/000001-000001", "parts"])
def test_a_file_where_a_part_is_recorded_fails_that_scenario_by_name(tmp_path: Path, blocked: str) -> None:
    """A file where a part's folder (or ``OUT/<stem>/parts``) goes: each of its tasks failed as an 'internal error
    NotADirectoryError' of the worker."""
    src = _scenario_folder(tmp_path, frames=2)
    _write(src / "b.yaml", lidar_scenario("b", frames=1))
    out = tmp_path / "out"
    (out / "a" / blocked).parent.mkdir(parents=True)
    (out / "a" / blocked).write_text("not a folder\n", encoding="utf-8")
    rep = run_many(src, out_dir=out, split_frames=1)
    assert rep.summary() == "1 done, 1 failed, 0 skipped, 0 retried"
    error = rep.outcomes[0].error or ""
    assert f"the folder of its part {out.resolve() / 'a' / blocked} is a file: move it away" in error, error
    assert "internal error" not in error


def test_an_empty_ray_address_is_refused(tmp_path: Path, capsys: Any) -> None:
    """``--ray "$ADDRESS"`` with the variable unset (``--ray ''``) started a local Ray instance without a word
    instead of joining the cluster meant; ``run_many(ray='')`` did the same."""
    from mmusv.cli import main

    src = _scenario_folder(tmp_path)
    out = tmp_path / "out"
    assert main(["run", str(src), "-o", str(out), "--ray", ""]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("mmusv: error: --ray '': an empty address; give HOST:PORT or 'auto'"), err
    with pytest.raises(ConfigError, match=r"ray = '': must be False, True, 'local', 'auto' or a Ray address"):
        run_many(src, out_dir=out, ray="")
    assert not out.exists()


def test_an_index_path_that_is_a_folder_is_refused_before_anything_runs(tmp_path: Path) -> None:
    """``OUT/dataset.json`` a folder: every scenario was recorded, then the index was a warning and the exit
    status 0, the summary line naming the index as written."""
    from mmusv.errors import IoError

    src = _scenario_folder(tmp_path)
    out = tmp_path / "out"
    (out / "dataset.json").mkdir(parents=True)
    with pytest.raises(IoError, match=r"index .*dataset\.json is a folder: move it away"):
        run_many(src, out_dir=out)
    assert not (out / "a").exists()


@pytest.mark.parametrize("text", ['{"my": "notes"}\n', "[1, 2]\n", "not JSON\n"])
def test_a_dataset_json_of_another_tool_is_not_replaced(tmp_path: Path, text: str) -> None:
    """``OUT/dataset.json`` that mmusv did not write (another tool's metadata) was replaced by the batch's index
    without a word; an index of mmusv's, even one cut short, is still replaced."""
    from mmusv.errors import IoError

    src = _scenario_folder(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / "dataset.json").write_text(text, encoding="utf-8")
    with pytest.raises(IoError, match=r"dataset\.json is not an mmusv dataset index, and the batch would replace it"):
        run_many(src, out_dir=out)
    assert (out / "dataset.json").read_text(encoding="utf-8") == text and not (out / "a").exists()
    (out / "dataset.json").write_text('{\n  "format": "mmusv.dataset",\n  "version": 1,\n  "recor', encoding="utf-8")
    assert run_many(src, out_dir=out).ok
    assert json.loads((out / "dataset.json").read_text(encoding="utf-8"))["totals"]["complete"] == 1


def test_mmusv_run_of_a_folder_whose_index_cannot_be_written_exits_1(
    tmp_path: Path, capsys: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An index that cannot be written at the end (a full disk) was a warning, exit status 0 and a summary naming
    it as the index."""
    import mmusv.batch.runner as runner
    from mmusv.cli import main
    from mmusv.errors import IoError

    def full(path: Any, *_args: Any, **_kw: Any) -> Path:
        raise IoError(f"cannot write {path}: No space left on device")

    monkeypatch.setattr(runner, "write_index", full)
    src = _scenario_folder(tmp_path)
    out = tmp_path / "out"
    assert main(["run", str(src), "-o", str(out)]) == 1
    said = " ".join(capsys.readouterr().out.split())  # the console wraps long lines
    assert "mmusv: warning: cannot write" in said and f"no index written to {out.resolve() / 'dataset.json'}" in said


# ------------------------------------------------------------------------------------------------ mmusv dataset

TINY_SPEC: dict[str, Any] = {
    "name": "tiny",
    "seed": 1,
    "map": {"type": "open_sea", "seed": 0},
    "acquisition": {"frequency_hz": 2, "frames": 2},
    "environment": {"motion": "paper"},
    "rig": "r",
    "rigs": {"r": {"preset": "lidar_only", "lidar": {"channels": 8, "points_per_second": 20480}}},
    "combinations": [{"family": "crossing", "difficulty": "easy", "cooperating": 1, "targets": ["small"]}],
}


@pytest.mark.parametrize("section", ['"x"', "[1]", '{"frames": NaN}'])
def test_a_damaged_opv2v_section_of_the_index_converts_again(tmp_path: Path, section: str) -> None:
    """``dataset.json``'s ``opv2v`` section not an object: the re-run recorded (or skipped) every scenario and then
    ended in an AttributeError traceback; one holding NaN was refused naming ``index_extra['opv2v']``, an argument
    the user never gave. The conversion is not known to be up to date then: it is done again."""
    from mmusv.batch.dataset import build_dataset

    spec = _write(tmp_path / "tiny.yaml", TINY_SPEC)
    out = tmp_path / "ds"
    first = build_dataset(spec, out_dir=out)
    assert first.ok and first.converted == 2
    index = out / "dataset.json"
    doc = json.loads(index.read_text(encoding="utf-8"))
    doc["opv2v"] = "@SECTION@"
    index.write_text(json.dumps(doc).replace('"@SECTION@"', section), encoding="utf-8")
    again = build_dataset(spec, out_dir=out)
    assert again.ok and again.converted == 2
    opv2v = json.loads(index.read_text(encoding="utf-8"))["opv2v"]
    assert opv2v["status"] == "complete" and opv2v["frames"] == 2


def test_mmusv_dataset_refuses_an_index_path_that_is_a_folder_before_generating(tmp_path: Path) -> None:
    """``DIR/dataset.json`` a folder: the spec was generated into DIR/scenarios first, every recording made, and
    the index only a warning."""
    from mmusv.batch.dataset import build_dataset
    from mmusv.errors import IoError

    spec = _write(tmp_path / "tiny.yaml", TINY_SPEC)
    out = tmp_path / "ds"
    (out / "dataset.json").mkdir(parents=True)
    with pytest.raises(IoError, match=r"index .*dataset\.json is a folder: move it away"):
        build_dataset(spec, out_dir=out)
    assert sorted(p.name for p in out.iterdir()) == ["dataset.json"]


def test_mmusv_dataset_refuses_a_dataset_json_of_another_tool_before_generating(tmp_path: Path) -> None:
    from mmusv.batch.dataset import build_dataset
    from mmusv.errors import IoError

    spec = _write(tmp_path / "tiny.yaml", TINY_SPEC)
    out = tmp_path / "ds"
    out.mkdir()
    (out / "dataset.json").write_text('{"my": "notes"}', encoding="utf-8")
    with pytest.raises(IoError, match=r"not an mmusv dataset index, and mmusv dataset would replace it"):
        build_dataset(spec, out_dir=out)
    assert sorted(p.name for p in out.iterdir()) == ["dataset.json"]
    assert (out / "dataset.json").read_text(encoding="utf-8") == '{"my": "notes"}'


@pytest.mark.parametrize("name", ["extra.yaml", "extra.yml"])
def test_mmusv_dataset_refuses_a_scenario_its_spec_did_not_generate(tmp_path: Path, name: str) -> None:
    """A scenario put into ``DIR/scenarios`` by hand (or any ``.yml``, which generate does not check) was recorded,
    converted and indexed as part of the spec's dataset on the next run, without a word."""
    from mmusv.batch.dataset import build_dataset
    from mmusv.errors import IoError

    spec = _write(tmp_path / "tiny.yaml", TINY_SPEC)
    out = tmp_path / "ds"
    assert build_dataset(spec, out_dir=out).ok
    before = (out / "dataset.json").read_bytes()
    _write(out / "scenarios" / name, lidar_scenario("extra", frames=1))
    with pytest.raises(IoError, match=rf"holds scenario files the spec's generation did not write \({name};"):
        build_dataset(spec, out_dir=out)
    assert not (out / "recordings" / "extra").exists() and (out / "dataset.json").read_bytes() == before


@pytest.mark.parametrize(("name", "what"), [("report.json", "report"), (".generate.partial", "journal")])
def test_generate_refuses_a_folder_where_its_report_goes_before_generating(
    tmp_path: Path, capsys: Any, name: str, what: str
) -> None:
    """``-o DIR`` holding a folder named ``report.json``: every scenario was generated and written, then the run
    ended saying the disk was full ('free space and run again'), the scenario files and the journal left behind."""
    from mmusv.cli import main

    spec = _write(tmp_path / "tiny.yaml", TINY_SPEC)
    out = tmp_path / "gen"
    (out / name).mkdir(parents=True)
    assert main(["generate", str(spec), "-o", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (
        f"mmusv: error: output directory {str(out)!r}: {name} is a folder (or another non-file) where generate "
        f"writes its {what}: move it away"
    ), err
    assert sorted(p.name for p in out.iterdir()) == [name]


# ------------------------------------------------------------------------------------------ study agreement


def _top_view_scenario(name: str) -> dict[str, Any]:
    sc = lidar_scenario(name, frames=2)
    sc["rigs"]["r"]["top_view"] = {"resolution": [64, 64], "metres_per_pixel": 2.0, "outputs": ["semantic", "instance"]}
    return sc


def test_the_agreement_study_refuses_a_scenario_given_twice(tmp_path: Path) -> None:
    """``mmusv study agreement tv.yaml tv.yaml`` counted every sample twice (valid samples 4 of 2); two files of
    one scenario name could not be told apart in the samples' file."""
    from mmusv.studies.agreement import load_scenarios, run_agreement_study

    tv = _write(tmp_path / "tv.yaml", _top_view_scenario("tv"))
    copy = _write(tmp_path / "copy.yaml", _top_view_scenario("tv"))
    with pytest.raises(ConfigError, match=r"tv\.yaml: the scenario name 'tv' is taken by an earlier scenario"):
        load_scenarios([str(tv), str(tv)])
    with pytest.raises(ConfigError, match=r"copy\.yaml: the scenario name 'tv' is taken .*\(.*tv\.yaml\)"):
        run_agreement_study([str(tv), str(copy)], frames=1)
    assert len(load_scenarios([str(tv), str(_write(tmp_path / "b.yaml", _top_view_scenario("b")))])) == 2


def test_study_agreement_given_one_scenario_twice_writes_nothing(tmp_path: Path, capsys: Any) -> None:
    from mmusv.cli import main

    tv = _write(tmp_path / "tv.yaml", _top_view_scenario("tv"))
    out = tmp_path / "study"
    assert main(["study", "agreement", str(tv), str(tv), "--frames", "1", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("mmusv: ") and "'tv' is taken by an earlier scenario" in err and "\n" not in err
    assert not out.exists()


# ------------------------------------------------------------------------------------- study detection


@pytest.fixture(scope="module")
def one_usv_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    import mmusv

    folder = tmp_path_factory.mktemp("rec")
    sc = _write(folder / "a.yaml", lidar_scenario("a", frames=2))
    return Path(mmusv.run(str(sc), out_dir=str(folder / "out")).recording)


def test_study_detection_refuses_predictions_of_a_negative_size(
    one_usv_recording: Path, tmp_path: Path, capsys: Any
) -> None:
    """A --predictions box with l = -1 was scored without a word (AP 0 written as a result)."""
    import polars as pl
    from mmusv.cli import main

    argv = ["study", "detection", str(one_usv_recording), "--modes", "none", "--no-progress"]
    assert main([*argv, "-o", str(tmp_path / "first")]) == 0
    boxes = pl.read_parquet(tmp_path / "first" / "detection_boxes.parquet").filter(pl.col("kind") == "gt")
    assert boxes.height > 0
    pred = tmp_path / "pred.parquet"
    boxes.with_columns(pl.lit("det").alias("kind"), pl.lit(0.9).alias("score"), pl.lit(-1.0).alias("w")).write_parquet(
        pred
    )
    capsys.readouterr()
    out = tmp_path / "study"
    assert main([*argv, "--predictions", str(pred), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.endswith("column w must hold box sizes in metres, not negative; row 0 has -1.0"), err
    assert not out.exists()


def test_study_detection_refuses_a_detector_box_of_negative_size(
    one_usv_recording: Path, tmp_path: Path, capsys: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A --detector callable returning a box of negative length was scored without a word."""
    from mmusv.cli import main

    (tmp_path / "negative_detector.py").write_text(
        "import numpy as np\n\n\ndef detect(points):\n"
        "    return np.array([[10.0, 0.0, 0.0, -4.0, 2.0, 1.0, 0.0]]), np.array([0.9])\n",
        encoding="utf-8",
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    out = tmp_path / "study"
    argv = ["study", "detection", str(one_usv_recording), "--modes", "none", "--no-progress", "-o", str(out)]
    assert main([*argv, "--detector", "negative_detector:detect"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--detector negative_detector:detect returned a box of negative size (l, w or h)" in err and "\n" not in err
    assert not out.exists()


@pytest.fixture(scope="module")
def opv2v_sequence(one_usv_recording: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One OPV2V scenario folder (``<cav>/<frame>.pcd`` + ``.yaml``) of the one-USV recording."""
    from mmusv.export.conversion import convert
    from mmusv.studies.detection.data import opv2v_scenarios

    out = tmp_path_factory.mktemp("opv2v") / "opv2v"
    convert(one_usv_recording, to="opv2v", out_dir=out, splits=None)
    return opv2v_scenarios(out)[0]


def _frame_yaml(folder: Path) -> Path:
    return sorted(folder.glob("*/000000.yaml"))[0]


def _vehicle(doc: dict[str, Any]) -> dict[str, Any]:
    return next(iter(doc["vehicles"].values()))  # type: ignore[no-any-return]


@pytest.mark.parametrize(
    ("change", "said"),
    [
        (
            lambda d: _vehicle(d).update(extent=[float("nan"), 1.0, 1.0]),
            r"\.extent = \[nan, 1\.0, 1\.0\]: must be finite",
        ),
        (lambda d: _vehicle(d).update(extent=[-3.0, 1.0, 1.0]), r"\.extent = \[-3\.0, 1\.0, 1\.0\]: must be finite"),
        (lambda d: _vehicle(d).update(location=[float("inf"), 0.0, 0.0]), r"location, center and angle must be finite"),
        (lambda d: _vehicle(d).update(angle=[1.0, 2.0]), r"angle and extent must be 3 numbers each"),
        (lambda d: _vehicle(d).pop("location"), r"KeyError: 'location'"),
        (lambda d: d.update(vehicles=[1]), r"AttributeError"),
    ],
    ids=["nan-extent", "negative-extent", "inf-location", "two-angles", "no-location", "vehicles-list"],
)
def test_an_opv2v_frames_damaged_vehicle_is_refused_by_name(
    opv2v_sequence: Path, tmp_path: Path, change: Any, said: str
) -> None:
    """A NaN or negative extent was read as a ground-truth box and scored without a word; a vehicle without a
    location, with two angles or a list of vehicles was a bare KeyError / ValueError / AttributeError traceback
    (the vehicles were read outside the frame's checks)."""
    import shutil

    from mmusv.errors import IoError
    from mmusv.studies.detection.data import read_opv2v

    folder = Path(shutil.copytree(opv2v_sequence, tmp_path / opv2v_sequence.name))
    frame = _frame_yaml(folder)
    doc = yaml.safe_load(frame.read_text(encoding="utf-8"))
    assert doc["vehicles"], "the fixture's frame lists no vehicle"
    change(doc)
    frame.write_text(yaml.safe_dump(doc), encoding="utf-8")
    with pytest.raises(IoError, match=r"000000\.yaml: not a readable OPV2V frame \(.*" + said):
        read_opv2v(folder)


def test_an_opv2v_frame_of_bad_yaml_is_one_line(opv2v_sequence: Path, tmp_path: Path) -> None:
    import shutil

    from mmusv.errors import IoError
    from mmusv.studies.detection.data import read_opv2v

    folder = Path(shutil.copytree(opv2v_sequence, tmp_path / opv2v_sequence.name))
    _frame_yaml(folder).write_text("{\n", encoding="utf-8")
    with pytest.raises(IoError, match="not a readable OPV2V frame") as caught:
        read_opv2v(folder)
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize("gone", [".yaml", ".pcd"])
def test_an_opv2v_frame_missing_half_of_its_pair_is_refused(opv2v_sequence: Path, tmp_path: Path, gone: str) -> None:
    """A CAV's frame with its .pcd (or .yaml) gone was left out of the frame without a word (the study then said
    the sequence had one USV too few)."""
    import shutil

    from mmusv.errors import IoError
    from mmusv.studies.detection.data import read_opv2v

    folder = Path(shutil.copytree(opv2v_sequence, tmp_path / opv2v_sequence.name))
    frame = _frame_yaml(folder).with_suffix(gone)
    frame.unlink()
    with pytest.raises(IoError, match=rf"000000\{gone}: missing beside 000000\.(pcd|yaml)"):
        read_opv2v(folder)


def test_an_opv2v_cloud_not_named_by_its_frame_is_refused(opv2v_sequence: Path, tmp_path: Path) -> None:
    """A ``notes.pcd`` in a CAV's folder was a bare ValueError (int('notes'))."""
    import shutil

    from mmusv.errors import IoError
    from mmusv.studies.detection.data import read_opv2v

    folder = Path(shutil.copytree(opv2v_sequence, tmp_path / opv2v_sequence.name))
    frame = _frame_yaml(folder).with_suffix(".pcd")
    shutil.copy(frame, frame.with_name("notes.pcd"))
    with pytest.raises(IoError, match=r"notes\.pcd: not an OPV2V frame"):
        read_opv2v(folder)


# ------------------------------------------------------------------------------------------------- mmusv train


def test_train_refuses_cache_only_with_scorers_only(tmp_path: Path, capsys: Any) -> None:
    """``--cache-only --scorers-only`` fitted the scorers (minutes) where a cache was, --cache-only ignored; without
    one it said 'train first'. The two contradict each other: one line saying so."""
    pytest.importorskip("torch")
    from mmusv.cli import main

    out = tmp_path / "train"
    assert main(["train", "-o", str(out), "--cache-only", "--scorers-only", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "mmusv: error: --scorers-only and --cache-only: give one", err
    assert not out.exists()
