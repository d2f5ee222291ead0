"""mmusv.studies.detection.predictions: a predictions Parquet read into per-(sequence, frame, ego, mode, setting)
detections, written here by hand and read back, and its refusals (each naming the file, the column and the row)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import polars as pl
import pytest
from mmusv.errors import InputError
from mmusv.studies.detection.predictions import COVERAGE_KINDS, check_prediction_coverage, load_predictions
from mmusv.studies.detection.robustness import Setting

BOX = {"x": 10.0, "y": -2.0, "z": 0.5, "l": 8.0, "w": 3.0, "h": 2.0, "yaw": 0.25}


def _row(**over: object) -> dict[str, object]:
    row: dict[str, object] = {"sequence": "s0", "frame": 3, "ego": "usv_1", "mode": "late", **BOX, "score": 0.9}
    row.update(over)
    return row


def _write(tmp_path: Path, rows: list[dict[str, object]], name: str = "pred.parquet") -> Path:
    path = tmp_path / name
    pl.DataFrame(rows).write_parquet(path)
    return path


def test_detections_are_grouped_by_key_in_file_order(tmp_path: Path) -> None:
    rows = [
        _row(score=0.9),
        _row(frame=4, x=1.0, score=0.2),
        _row(score=0.5, x=-7.0),
        _row(mode="early", setting="delay:2", score=0.1),
    ]
    rows[:3] = [{**r, "setting": "clean"} for r in rows[:3]]
    got = load_predictions(_write(tmp_path, rows))
    assert sorted(got) == [
        ("s0", 3, "usv_1", "early", "delay:2"),
        ("s0", 3, "usv_1", "late", "clean"),
        ("s0", 4, "usv_1", "late", "clean"),
    ]
    boxes, scores = got[("s0", 3, "usv_1", "late", "clean")]
    assert boxes.shape == (2, 7) and boxes.dtype == np.float64
    np.testing.assert_array_equal(scores, [0.9, 0.5])
    np.testing.assert_array_equal(boxes[:, 0], [10.0, -7.0])
    np.testing.assert_array_equal(boxes[0], [BOX[c] for c in ("x", "y", "z", "l", "w", "h", "yaw")])


def test_without_a_setting_column_every_row_is_clean(tmp_path: Path) -> None:
    got = load_predictions(_write(tmp_path, [_row()]))
    assert list(got) == [("s0", 3, "usv_1", "late", "clean")]


def test_coverage_rows_cover_a_frame_without_a_detection(tmp_path: Path) -> None:
    null_box = dict.fromkeys((*BOX, "score"))
    rows = [
        {**_row(), "kind": "det"},
        {**_row(frame=5), **null_box, "kind": "frame"},
        {**_row(frame=6), **null_box, "kind": "gt"},
        {**_row(frame=7), "kind": "something else"},  # neither a detection nor coverage: skipped
    ]
    assert set(COVERAGE_KINDS) == {"frame", "gt"}
    got = load_predictions(_write(tmp_path, rows))
    assert sorted(k[1] for k in got) == [3, 5, 6]
    assert got[("s0", 5, "usv_1", "late", "clean")][0].shape == (0, 7)
    assert got[("s0", 6, "usv_1", "late", "clean")][1].shape == (0,)


def test_a_file_without_a_row_covers_nothing(tmp_path: Path) -> None:
    path = tmp_path / "empty.parquet"
    pl.DataFrame(schema=dict.fromkeys(("sequence", "frame", "ego", "mode", *BOX, "score"), pl.Float64)).write_parquet(
        path
    )
    assert load_predictions(path) == {}


@pytest.mark.parametrize(
    ("over", "said"),
    [
        ({"frame": 1.5}, "column frame must hold integer acquisition indices; row 1 has 1.5"),
        ({"frame": None}, "column frame has 1 null value(s) (first: row 1)"),
        ({"mode": "fused"}, "column mode has unknown value(s) ['fused']"),
        ({"x": float("nan")}, "column x must hold finite numbers; row 1 has nan"),
        ({"score": None}, "column score has 1 null value(s) (first: row 1); every det row needs one"),
        ({"w": -1.0}, "column w must hold box sizes in metres, not negative; row 1 has -1.0"),
    ],
)
def test_a_bad_value_names_the_file_column_and_row(tmp_path: Path, over: dict[str, object], said: str) -> None:
    path = _write(tmp_path, [_row(frame=2.0), _row(**over)] if "frame" in over else [_row(), _row(**over)])
    with pytest.raises(InputError) as exc:
        load_predictions(path)
    assert str(exc.value).startswith(f"path = '{path}': ")
    assert said in str(exc.value)


def test_a_missing_file_a_folder_and_a_missing_column_are_refused(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such file"):
        load_predictions(tmp_path / "nope.parquet")
    with pytest.raises(InputError, match="a folder; give the predictions Parquet file"):
        load_predictions(tmp_path)
    path = _write(tmp_path, [{k: v for k, v in _row().items() if k != "yaw"}])
    with pytest.raises(InputError, match=r"missing column\(s\) \['yaw'\]"):
        load_predictions(path)
    not_parquet = tmp_path / "a.parquet"
    not_parquet.write_text("x,y\n1,2\n")
    with pytest.raises(InputError, match="not a readable Parquet file"):
        load_predictions(not_parquet)


def test_coverage_names_each_setting_and_mode_missing(tmp_path: Path) -> None:
    path = _write(tmp_path, [_row()])
    preds = load_predictions(path)
    check_prediction_coverage(path, preds, modes=("late",), settings=(Setting(),))
    # "none" is scored in the clean setting only: a delay setting does not ask for it.
    with pytest.raises(InputError) as exc:
        check_prediction_coverage(path, preds, modes=("none", "late"), settings=(Setting(), Setting(delay_frames=2)))
    said = str(exc.value)
    assert "no row of setting clean (modes none); setting delay:2 (modes late)" in said
    assert "the file covers setting clean (modes late)" in said
    with pytest.raises(InputError, match="the file holds no detection and covers no frame"):
        check_prediction_coverage(path, {}, modes=("late",), settings=(Setting(),))
