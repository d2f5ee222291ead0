"""The Python API as a researcher in a notebook meets it (round 3): what a wrong argument, a foreign file or a
documented promise met, each test failing before its fix."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import pytest
import yaml
from mmusv import recording
from mmusv.acquire import RunResult
from mmusv.config import load_scenario, scenario_hash
from mmusv.errors import ConfigError, InputError, IoError
from mmusv.export import convert
from mmusv.recording.decode import WorldFrame
from mmusv.sea_surface import surface_tiles
from tiny_scenario import lidar_scenario


def _scenario(name: str = "round3") -> dict[str, Any]:
    """The tests' tiny LiDAR scenario with a small camera (flat water: quick)."""
    sc = lidar_scenario(name, frames=1)
    sc["rigs"]["r"]["cameras"] = [{"name": "front", "resolution": [24, 16], "mount": {"point": "camera_front"}}]
    return sc


@pytest.fixture(scope="module")
def rec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    res = mmusv.run(_scenario(), out_dir=tmp_path_factory.mktemp("round3"))
    assert res.status == "complete" and res.frames_written == 1
    return res.recording


# ---------------------------------------------------------------------------------------------- run_many


@pytest.mark.parametrize(
    ("extra", "said"),
    [
        ({"totals": {"mine": 1}}, "section 'totals' is the index's own"),
        ({"note": float("nan")}, "index_extra['note'] = nan: must be plain JSON"),
        ({"note": {"when": object()}}, "index_extra['note'] = {'when': <object object"),
    ],
)
def test_run_many_refuses_index_sections_it_cannot_write_before_it_runs(
    tmp_path: Path, extra: dict[str, Any], said: str
) -> None:
    """Before: a section named like the index's own ran the whole batch and then never wrote ``dataset.json``
    (``report.ok`` true, the cause only in ``report.index_error``); a NaN or an object ended in a bare
    ``ValueError`` / ``TypeError`` from the JSON encoder after the first recording."""
    src = tmp_path / "src"
    src.mkdir()
    (src / "a.yaml").write_text(yaml.safe_dump(lidar_scenario("a", frames=1)))
    out = tmp_path / "out"
    with pytest.raises(ConfigError, match=re.escape(said)):
        mmusv.run_many(src, out_dir=out, index_extra=extra)
    assert not (out / "a").exists() and not (out / "dataset.json").exists()


# ---------------------------------------------------------------------------------------------- convert


@pytest.mark.parametrize(
    ("to", "options", "said"),
    [
        ("opv2v", {"min_box_px": 8}, "min_box_px = 8"),
        ("kitti", {"max_occlusion": 0.5}, "max_occlusion = 0.5"),
        ("kitti_tracking", {"min_contrast": 0.05}, "min_contrast = 0.05"),
        ("mastr", {"box": "projected"}, "box = 'projected'"),
        ("ros2", {"box": "projected"}, "box = 'projected'"),
        ("ros2", {"min_contrast": 0.05}, "min_contrast = 0.05"),
    ],
)
def test_convert_refuses_2d_box_options_a_format_would_ignore(
    rec: Path, tmp_path: Path, to: str, options: dict[str, Any], said: str
) -> None:
    """Before: ``convert(rec, to="opv2v", min_box_px=8)`` converted as if the option had not been given (only COCO,
    YOLO and MOT choose 2D boxes), while ``kitti_class`` with another format was refused."""
    with pytest.raises(ConfigError, match=re.escape(said) + r".*only the COCO, YOLO(,| and) MOT( and ROS 2)? exports"):
        convert(rec, to=to, out_dir=tmp_path / "x", splits=None, **options)
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize(
    ("to", "options", "said"),
    [
        ("coco", {"eval_range_m": 100}, "eval_range_m = 100"),
        ("yolo", {"include_usvs": True}, "include_usvs = True"),
        ("mot", {"eval_range_m": 50, "include_usvs": True}, "eval_range_m = 50, include_usvs = True"),
        ("semantickitti", {"eval_range_m": 80}, "eval_range_m = 80"),
        ("mastr", {"include_usvs": True}, "include_usvs = True"),
        ("ros2", {"eval_range_m": 80}, "eval_range_m = 80"),
    ],
)
def test_convert_refuses_target_options_a_format_would_ignore(
    rec: Path, tmp_path: Path, to: str, options: dict[str, Any], said: str
) -> None:
    """Before: ``mmusv convert --to coco --range 100 --include-usvs`` converted as if neither had been given (only
    OPV2V, KITTI and KITTI tracking choose their targets by range and role; a helper's cross-export round)."""
    with pytest.raises(ConfigError, match=re.escape(said) + r".*only the OPV2V, KITTI and KITTI tracking exports"):
        convert(rec, to=to, out_dir=tmp_path / "x", splits=None, **options)
    assert not (tmp_path / "x").exists()


def test_convert_box_options_at_their_defaults_pass_for_every_format(rec: Path, tmp_path: Path) -> None:
    report = convert(rec, to="kitti", out_dir=tmp_path / "k", min_box_px=0, max_occlusion=1, box="visible")
    assert report.frames == 1
    report = convert(rec, to="coco", out_dir=tmp_path / "c", eval_range_m=200, include_usvs=False)
    assert report.frames == 1
    report = convert(rec, to="kitti", out_dir=tmp_path / "r", eval_range_m=80, include_usvs=True)
    assert report.frames == 1


# ---------------------------------------------------------------------------------------------- scene


@pytest.mark.parametrize(
    ("foci", "radius", "err"),
    [
        (None, 320.0, "foci must be numeric"),
        ([0.0, 0.0], 320.0, r"foci must have shape \(N, 2\), got \(2,\)"),
        ([[math.nan, 0.0]], 320.0, "foci: every focus must be a finite"),
        ([[0.0, 0.0]], -1.0, "radius_m = -1"),
        ([[0.0, 0.0]], 0.0, "radius_m = 0"),
        ([[0.0, 0.0]], math.nan, "radius_m = nan"),
        ([[0.0, 0.0]], math.inf, "radius_m = inf"),
        ([[0.0, 0.0]], "320", "radius_m = '320'"),
        ([[0.0, 0.0]], None, "radius_m = None"),
    ],
)
def test_surface_tiles_checks_its_arguments(foci: Any, radius: Any, err: str) -> None:
    """Before: ``ValueError: cannot reshape`` / ``TypeError: float()`` from deep inside, and a NaN focus or an
    infinite radius counted 18446744073709551615 tiles, a negative radius 0."""
    with pytest.raises(InputError, match=err):
        surface_tiles(foci, radius_m=radius)


def test_surface_tiles_still_counts() -> None:
    assert surface_tiles(np.zeros((0, 2)), radius_m=320.0) == 0
    assert surface_tiles([[0, 0]], radius_m=1) == 4  # the four tiles around the origin
    assert surface_tiles(np.zeros((1, 2)), radius_m=np.float32(320.0)) == 400


# ---------------------------------------------------------------------------------------------- config


def test_scenario_hash_takes_what_load_scenario_takes_and_is_the_recordings_hash(rec: Path, tmp_path: Path) -> None:
    """Before: ``scenario_hash(dict)`` / ``scenario_hash("x.yaml")`` was ``AttributeError: ... has no attribute
    'model_dump'``; a researcher comparing a scenario with a recording's ``config_hash`` had to know to validate
    first."""
    sc = _scenario()
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(sc))
    want = recording.read_info(rec).config_hash
    assert re.fullmatch(r"[0-9a-f]{64}", want)
    assert scenario_hash(sc) == scenario_hash(path) == scenario_hash(str(path)) == want
    assert scenario_hash(load_scenario(sc)) == want
    for bad in (None, 3, [sc]):
        with pytest.raises(ConfigError, match="a scenario is a YAML path, a dict or a validated model"):
            scenario_hash(bad)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="does not exist"):
        scenario_hash(tmp_path / "missing.yaml")


# ---------------------------------------------------------------------------------------------- recordings


def _foreign_mcap(path: Path) -> Path:
    from mcap.writer import Writer

    with path.open("wb") as f:
        w = Writer(f)
        w.start()
        schema = w.register_schema("pose", "jsonschema", b"{}")
        channel = w.register_channel("/pose", "json", schema)
        w.add_message(channel, log_time=0, data=b'{"x": 1}', publish_time=0)
        w.finish()
    return path


def test_read_messages_refuses_an_mcap_whose_messages_are_not_protobuf(tmp_path: Path) -> None:
    """Before: ``list(read_messages(foreign))`` was ``[]``, as if the file were an empty recording."""
    p = _foreign_mcap(tmp_path / "foreign.mcap")
    with pytest.raises(IoError, match=r"channel /pose holds 'json' messages, not protobuf: not a recording of mmusv"):
        list(recording.read_messages(p))
    with pytest.raises(IoError, match="was it written by mmusv run"):  # as read_info already said
        recording.read_info(p)


def test_decoded_arrays_are_what_the_docstrings_say(rec: Path) -> None:
    """The dtypes and shapes ``decode_image``, ``decode_point_cloud`` and ``WorldFrame`` document (they said none)."""
    m = recording.frame_messages(rec, 0)
    want = {"rgb": (np.uint8, 3), "semantic": (np.uint16, 2), "instance": (np.uint16, 2), "depth": (np.float32, 2)}
    for kind, (dtype, ndim) in want.items():
        img = recording.decode_image(m[f"/u/camera/front/{kind}"])
        assert img.dtype == dtype and img.ndim == ndim and img.shape[:2] == (16, 24), kind
        assert img.flags.writeable, kind
    assert kind in (recording.decode_image.__doc__ or "")
    pc = recording.decode_point_cloud(m["/u/lidar"])
    assert list(pc) == ["x", "y", "z", "intensity", "ring", "azimuth", "class", "instance"]
    types = {k: v.dtype for k, v in pc.items()}
    floats = dict.fromkeys(["x", "y", "z", "intensity", "azimuth"], np.dtype(np.float32))
    assert types == {**floats, "ring": np.uint16, "class": np.uint16, "instance": np.int32}
    w = WorldFrame.from_message(m["/world/state"])
    assert w.poses.dtype == np.float64 and w.poses.shape == (2, 6) and w.velocities.shape == (2, 3)
    assert w.classes.dtype == np.int64 and w.instance_ids.dtype == np.int64


@pytest.mark.parametrize("cls", [RunResult, WorldFrame])
def test_result_types_document_every_field(cls: type) -> None:
    """Before: ``help(mmusv.RunResult)`` named only ``status``: not what ``seconds``, ``bytes``, ``messages`` or
    ``frame_seconds`` count, nor their units; ``WorldFrame`` gave no dtypes and no unit of its velocities."""
    doc = cls.__doc__ or ""
    missing = [f.name for f in dataclasses.fields(cls) if not re.search(rf"\b{f.name}\b", doc)]
    assert not missing, f"{cls.__name__} does not document {missing}"


# ---------------------------------------------------------------------------------------------- simulation


@pytest.mark.parametrize("bad", [None, 0, ["u"]])
def test_simulation_agent_names_its_argument(bad: Any) -> None:
    """Before: ``sim.agent(None)`` said ``no USV named None``, as if a USV could be called that."""
    sim = mmusv.Simulation(lidar_scenario("a", frames=1))
    with pytest.raises(ConfigError, match=r"agent_id = .*: must be a USV's id \(a str\).*the USVs are \['u'\]"):
        sim.agent(bad)
    assert sim.agent("u").id == "u"
