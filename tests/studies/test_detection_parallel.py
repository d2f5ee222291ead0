"""``--jobs``: the detection and robustness studies over several processes give the same files, byte for byte,
as one process; a worker's bad input is the same one-line error."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest
import yaml
from mmusv.cli import main
from test_detection_study import record


@pytest.fixture(scope="module")
def two_sequences(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder of two recordings (2 and 3 USVs; 4 and 3 frames)."""
    root = tmp_path_factory.mktemp("seqs")
    folder = root / "recordings"
    folder.mkdir()
    for usvs, frames in ((("usv_1", "usv_3"), 4), (("usv_1", "usv_2", "usv_3"), 3)):
        rec = record(root / f"r{len(usvs)}", usvs, frames=frames)
        shutil.copy(rec, folder / rec.name)
    return folder


def _blind(out: Path) -> Path:
    """A recording (2 USVs, 2 frames) whose rig carries no LiDAR."""
    from mmusv.acquire import run
    from mmusv.scenario_checks import MmusvWarning
    from mmusv.studies.detection.sources import lidar_only
    from test_detection_study import SCENARIO

    data = lidar_only(yaml.safe_load(SCENARIO.read_text(encoding="utf-8")))
    data["vessels"] = [v for v in data["vessels"] if v["role"] != "usv" or v["id"] in ("usv_1", "usv_3")]
    data["name"] = "tiny_blind"
    data["acquisition"]["frames"] = 2
    data["rigs"] = {name: {**rig, "lidar": None} for name, rig in data["rigs"].items()}
    with pytest.warns(MmusvWarning, match="switches every sensor off"):
        rec: Path = run(data, out_dir=out).recording
    return rec


def study(args: list[str], out: Path) -> Path:
    assert main([*args, "-o", str(out), "--no-progress"]) == 0
    return out


def test_detection_jobs_give_the_same_bytes(two_sequences: Path, tmp_path: Path) -> None:
    args = ["study", "detection", str(two_sequences)]
    one = study(args, tmp_path / "one")
    two = study([*args, "--jobs", "2"], tmp_path / "two")
    for name in ("detection_table.csv", "detection_boxes.parquet"):
        assert (one / name).read_bytes() == (two / name).read_bytes(), name
    # A predictions file scored over two processes: the same table again.
    again = study([*args, "--predictions", str(one / "detection_boxes.parquet"), "--jobs", "2"], tmp_path / "pred")
    assert (again / "detection_table.csv").read_bytes() == (one / "detection_table.csv").read_bytes()


def test_robustness_jobs_give_the_same_bytes(two_sequences: Path, tmp_path: Path) -> None:
    args = ["study", "robustness", str(two_sequences), "--settings", "delay:1,noise:1/1"]
    one = study(args, tmp_path / "one")
    three = study([*args, "--jobs", "3"], tmp_path / "three")  # more jobs than sequences
    for name in ("robustness_table.csv", "robustness_boxes.parquet"):
        assert (one / name).read_bytes() == (three / name).read_bytes(), name


def test_a_workers_bad_input_is_one_line(
    two_sequences: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mixed = tmp_path / "mixed"
    shutil.copytree(two_sequences, mixed)
    blind = _blind(tmp_path / "blind")  # refused in its worker (a sequence of one USV is scored, in mode none)
    shutil.copy(blind, mixed / blind.name)
    assert main(["study", "detection", str(mixed), "--jobs", "2", "-o", str(tmp_path / "o"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "sequence tiny_blind: no LiDAR" in err and "Traceback" not in err
    assert main(["study", "detection", str(two_sequences), "--jobs", "0", "-o", str(tmp_path / "o")]) == 2
    assert "--jobs 0: must be >= 1" in capsys.readouterr().err


def test_the_python_api_names_its_own_arguments() -> None:
    """split_sequences(split=..., seed=...) and run_study_jobs(jobs=...) called from Python were refused as
    "--split 'x'", "--seed -1", "--jobs 0", naming flags the caller never gave (and jobs="2" was a TypeError)."""
    from mmusv.errors import InputError
    from mmusv.studies.detection.data import split_sequences
    from mmusv.studies.detection.parallel import run_study_jobs

    ratios = (0.7, 0.15, 0.15)
    with pytest.raises(InputError, match=r"^split = 'x': expected one of train, validate, test, all$"):
        split_sequences(["a", "b"], split="x", ratios=ratios, seed=0)
    with pytest.raises(InputError, match=r"^seed = -1: the split's seed must be a whole number >= 0$"):
        split_sequences(["a", "b"], split="train", ratios=ratios, seed=-1)
    for bad, said in ((0, "jobs = 0: must be a whole number"), ("2", "not str")):
        with pytest.raises(InputError, match=re.escape(said)):
            run_study_jobs(None, options=None, spec=None, jobs=bad)  # type: ignore[arg-type]


def test_a_stop_swallowed_while_the_jobs_ran_ends_the_study(
    two_sequences: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # A stop whose KeyboardInterrupt a library swallowed (noted by the command's handler, then not raised) ended
    # nothing: the study merged the workers' results and wrote its tables. It is raised again after the wait.
    import signal

    import mmusv.studies.detection.parallel as parallel
    from mmusv.held_signals import note_stop

    original = parallel.wait

    def wait(*args: object, **kwargs: object) -> object:
        done = original(*args, **kwargs)  # type: ignore[arg-type]
        note_stop(signal.SIGINT)
        return done

    monkeypatch.setattr(parallel, "wait", wait)
    out = tmp_path / "det"
    try:
        code = main(["study", "detection", str(two_sequences), "--jobs", "2", "-o", str(out), "--no-progress"])
    finally:
        note_stop(None)
    assert code == 130
    assert not (out / "detection_table.csv").exists()
