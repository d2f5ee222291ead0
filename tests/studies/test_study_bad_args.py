"""Bad arguments of the studies: ``study agreement --frames`` below 1 (was an empty table and exit status 0), and a
``--detector`` callable that fails when called (was the callable's own traceback)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mmusv.cli import main
from mmusv.errors import ConfigError, InputError
from mmusv.studies.agreement import run_agreement_study
from mmusv.studies.detection.detector import load_detector

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("frames", [0, -1])
def test_agreement_refuses_frames_below_one(frames: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(ConfigError, match="--frames"):
        run_agreement_study([str(ROOT / "scenarios/open_sea_convoy.yaml")], frames=frames)
    out = tmp_path / "agree"
    scenario = str(ROOT / "scenarios/open_sea_convoy.yaml")
    assert main(["study", "agreement", scenario, "-o", str(out), "--frames", str(frames)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: ") and f"--frames) = {frames}" in err and ">= 1" in err, err
    assert not out.exists()


def test_agreement_refuses_a_stride_below_one() -> None:
    with pytest.raises(ConfigError, match="stride"):
        run_agreement_study([str(ROOT / "scenarios/open_sea_convoy.yaml")], frames=1, stride=0)


POINTS = np.zeros((5, 4), dtype=np.float32)


def test_a_detector_of_another_signature_names_the_detector() -> None:
    det = load_detector("os:getcwd")
    with pytest.raises(ConfigError, match=r"^spec = 'os:getcwd'.*TypeError.*expected detect\(points \(N, 4\)"):
        det(POINTS)


def test_a_detector_returning_no_pair_names_the_detector() -> None:
    with pytest.raises(ConfigError, match=r"^spec = 'builtins:len'.*returned int"):
        load_detector("builtins:len")(POINTS)


def test_a_working_user_detector_and_its_early_entry_run_as_they_are(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "my_bad_args_detector.py").write_text(
        "import numpy as np\n"
        "def detect(points):\n"
        "    return np.ones((1, 7)), np.ones(1)\n"
        "def _early(points):\n"
        "    raise ValueError('broken early')\n"
        "detect.early = _early\n"
        "detect.tag = 'mine'\n",
        encoding="utf-8",
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "my_bad_args_detector", raising=False)
    det: Any = load_detector("my_bad_args_detector:detect")
    boxes, scores = det(POINTS)
    assert boxes.shape == (1, 7) and scores.shape == (1,)
    assert det.tag == "mine"
    with pytest.raises(ConfigError, match=r"^spec = 'my_bad_args_detector:detect': its 'early'.*broken early"):
        det.early(POINTS)


def test_study_detection_with_a_failing_detector_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.acquire import run
    from mmusv.studies.detection.sources import lidar_only

    data = lidar_only(yaml.safe_load((ROOT / "scenarios/island_occlusion.yaml").read_text(encoding="utf-8")))
    data["vessels"] = [v for v in data["vessels"] if v["role"] != "usv" or v["id"] in ("usv_1", "usv_3")]
    data["name"] = "tiny_bad_detector"
    data["acquisition"]["frames"] = 1
    rec = run(data, out_dir=tmp_path / "rec").recording
    code = main(["study", "detection", str(rec), "--detector", "os:getcwd", "-o", str(tmp_path / "o"), "--no-progress"])
    assert code == 2
    err = capsys.readouterr().err
    assert err.startswith("mmusv: error: --detector os:getcwd: calling it"), err
    assert "TypeError" in err and "Traceback" not in err


def test_waves_names_the_scenario_flag(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`study waves --scenario /some/folder` said "scenario '...' is a directory, not a file", naming no flag."""
    from mmusv.cli import main

    rc = main(["study", "waves", "--scenario", str(tmp_path), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 2 and "--scenario: " in err and "is a directory" in err, err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("command", "names"),
    [
        (["waves", "--frames", "2"], ["wave_study.png"]),
        (["waves", "--frames", "2", "--motion", "physical"], ["wave_study_physical.csv", "wave_study_vessels.csv"]),
        (["agreement", str(ROOT / "scenarios/open_sea_convoy.yaml"), "--frames", "1"], ["agreement_summary.csv"]),
        (["detection", "no_such_recordings"], ["detection_note.txt"]),
        (["robustness", "no_such_recordings"], ["robustness_table.csv", "robustness_ap.png"]),
    ],
    ids=["waves", "waves-physical", "agreement", "detection", "robustness"],
)
def test_a_study_keeps_files_of_its_names_already_in_the_folder(
    command: list[str], names: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``mmusv study ... -o DIR`` replaced a user's files of the names it writes (``wave_study.png``,
    ``agreement_summary.csv``, ...) without a word, after the whole study: now refused before any work, naming
    the folder, the files and ``--overwrite``; the files and the rest of the folder are left as they were."""
    out = tmp_path / "mine"
    out.mkdir()
    for n in [*names, "notes.txt"]:
        (out / n).write_text(f"my {n}")
    assert main(["study", *command, "-o", str(out)]) == 2
    captured = capsys.readouterr()
    shown = ", ".join(names)
    said = "is" if len(names) == 1 else "are"
    assert captured.err.strip() == (
        f"mmusv: error: -o/--output {out}: {shown} {said} already there (from an earlier run, or files of yours); "
        f"pass --overwrite to replace {'it' if len(names) == 1 else 'them'}, or give another folder"
    )
    assert captured.out == ""  # refused before the study ran
    assert sorted(p.name for p in out.iterdir()) == sorted([*names, "notes.txt"])
    assert all((out / n).read_text() == f"my {n}" for n in [*names, "notes.txt"])


def test_a_study_with_overwrite_replaces_its_files_and_nothing_else(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "waves"
    out.mkdir()
    (out / "wave_study.csv").write_text("mine")
    (out / "notes.txt").write_text("mine")
    assert main(["study", "waves", "--frames", "2", "-o", str(out), "--overwrite"]) == 0
    assert (out / "wave_study.csv").read_text().startswith("wave,") and (out / "notes.txt").read_text() == "mine"
    # with --overwrite the detection study goes on to its input (here missing), past its files
    det = tmp_path / "det"
    det.mkdir()
    (det / "detection_table.csv").write_text("mine")
    capsys.readouterr()
    assert main(["study", "detection", str(tmp_path / "none"), "-o", str(det), "--overwrite"]) == 2
    err = capsys.readouterr().err
    assert "already there" not in err and "none" in err


@pytest.mark.parametrize(
    ("study", "flag", "value", "python", "command"),
    [
        ("detection", "--modes", "none,bogus", "text = 'none,bogus': unknown mode(s)", "--modes none,bogus: unknown"),
        ("detection", "--modes", "", "text = '': no mode", "--modes '': no mode"),
        ("robustness", "--settings", "delay:0", "text = 'delay:0': item 'delay:0'", "--settings delay:0: item"),
        ("robustness", "--settings", "", "text = '': empty", "--settings '': empty"),
    ],
)
def test_modes_and_settings_are_named_by_the_entry_point(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], study: str, flag: str, value: str, python: str, command: str
) -> None:
    """parse_modes and parse_settings named --modes and --settings to a Python caller; the command line names them
    as typed, Python by the argument ``text``."""
    from mmusv.studies.detection.fusion import parse_modes
    from mmusv.studies.detection.robustness import parse_settings

    with pytest.raises(InputError) as err:
        (parse_modes if flag == "--modes" else parse_settings)(value)
    assert str(err.value).startswith(python) and "--" not in str(err.value), err.value
    capsys.readouterr()
    assert main(["study", study, str(tmp_path / "x.mcap"), f"{flag}={value}", "-o", str(tmp_path / "o")]) == 2
    said = capsys.readouterr().err
    assert said.startswith(f"mmusv: error: {command}") and "text" not in said, said
