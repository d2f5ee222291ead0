"""``convert``'s refusals name what their user gave: the keyword argument and its value from Python
(``eval_range_m = 100``), the flag as typed from ``mmusv convert`` (``--range 100``). The command line was told of
``eval_range_m = 100``, ``min_contrast = -1.0`` and ``kitti_class = 'Car'``, names it does not have. The options are
checked before any recording is read, so none is needed here."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from mmusv.cli import main
from mmusv.errors import ConfigError
from mmusv.export import convert

CASES = [  # (keyword arguments, their flags, what Python is told, what the command line is told)
    (
        {"to": "coco", "eval_range_m": 100},
        ["--to", "coco", "--range", "100"],
        "eval_range_m = 100: only the OPV2V, KITTI and KITTI tracking exports (to = 'opv2v', 'kitti' or "
        "'kitti_tracking') choose their targets with it, not to = 'coco'",
        "--range 100: only the OPV2V, KITTI and KITTI tracking exports (--to opv2v, kitti or kitti_tracking) choose "
        "their targets with it, not --to coco",
    ),
    (
        {"to": "mastr", "include_usvs": True},
        ["--to", "mastr", "--include-usvs"],
        "include_usvs = True: only the OPV2V",
        "--include-usvs: only the OPV2V",
    ),
    (
        {"to": "opv2v", "min_contrast": 0.05, "box": "projected"},
        ["--to", "opv2v", "--min-contrast", "0.05", "--box", "projected"],
        "min_contrast = 0.05, box = 'projected': only the COCO, YOLO and MOT exports (to = 'coco', 'yolo' or 'mot')",
        "--min-contrast 0.05, --box projected: only the COCO, YOLO and MOT exports (--to coco, yolo or mot)",
    ),
    (
        {"to": "kitti", "min_box_px": 8},
        ["--to", "kitti", "--min-box-px", "8"],
        "min_box_px = 8: only the COCO, YOLO, MOT and ROS 2 exports (to = 'coco', 'yolo', 'mot' or 'ros2')",
        "--min-box-px 8: only the COCO, YOLO, MOT and ROS 2 exports (--to coco, yolo, mot or ros2)",
    ),
    (
        {"to": "coco", "min_contrast": -1.0},
        ["--to", "coco", "--min-contrast", "-1"],
        "min_contrast = -1: must be a Weber contrast >= 0",
        "--min-contrast -1: must be a Weber contrast >= 0",
    ),
    (
        {"to": "coco", "kitti_class": "Car"},
        ["--to", "coco", "--kitti-class", "Car"],
        "kitti_class = 'Car': only to = 'kitti_tracking' writes it, not to = 'coco'",
        "--kitti-class Car: only --to kitti_tracking writes it, not --to coco",
    ),
    (
        {"to": "coco", "extras": "depth"},
        ["--to", "coco", "--extras", "depth"],
        "extras = 'depth': only the OPV2V, KITTI and KITTI tracking exports",
        "--extras depth: only the OPV2V, KITTI and KITTI tracking exports",
    ),
    (
        {"to": "ros2", "splits": "0.5,0.5,0"},
        ["--to", "ros2", "--split", "0.5,0.5,0"],
        "splits = '0.5,0.5,0': to = 'ros2' writes one folder per recording",
        "--split 0.5,0.5,0: --to ros2 writes one folder per recording",
    ),
    (  # said "split 0.7,0.2,0.2" to both (the keyword is splits, the flag --split)
        {"to": "coco", "splits": "0.7,0.2,0.2"},
        ["--to", "coco", "--split", "0.7,0.2,0.2"],
        "splits = '0.7,0.2,0.2': the fractions add up to 1.1",
        "--split 0.7,0.2,0.2: the fractions add up to 1.1",
    ),
]


@pytest.mark.parametrize(("kwargs", "flags", "python", "command"), CASES)
def test_each_entry_point_names_its_own_argument(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    kwargs: dict[str, Any],
    flags: list[str],
    python: str,
    command: str,
) -> None:
    rec = tmp_path / "never_read.mcap"
    with pytest.raises(ConfigError) as err:
        convert(rec, out_dir=tmp_path / "py", **kwargs)
    assert str(err.value).startswith(python), err.value
    assert "--" not in str(err.value), err.value
    capsys.readouterr()
    assert main(["convert", str(rec), "-o", str(tmp_path / "cli"), "--no-progress", *flags]) == 2
    said = capsys.readouterr().err
    assert said.startswith(f"mmusv: error: {command}"), said
    assert " = " not in said and not any(k in said for k in kwargs if "_" in k), said  # eval_range_m, ...
    assert not (tmp_path / "py").exists() and not (tmp_path / "cli").exists()
