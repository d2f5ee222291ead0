"""A second determinism round (a helper's round): outputs whose bytes must not depend on what a run should not
depend on (the folders the inputs and outputs sit in, the way the paths were given). Each test here failed before
its fix.

* ``dataset.json`` promises "no times or absolute paths, so a finished dataset's index is the same bytes however
  many runs it took" (``docs/recording.md``, :mod:`mmusv.batch.index`), but the ``error`` of a failed scenario named
  its scenario file (and the output folders) by their absolute paths: ``"/home/me/batch/bad.yaml: invalid config
  ..."``, so the index of one batch moved or copied elsewhere, or run from another checkout, was other bytes. The
  index now names the scenario file by its name (as ``scenario_file`` does) and a path below the index's folder
  relative to it; the console still prints the full path.
* A frame range recorded alone (``mmusv.acquire.run(frame_range=(40, 300))``), or a part recovered away from its
  parts manifest, killed and then finished by ``mmusv recover``, lost its ``first_frame``: the recovered ``run``
  metadata and ``manifest.json`` said nothing of where it starts (as for a whole run from frame 0), though the
  ``.partial``'s ``manifest`` metadata says it, and the same range run to its end says it in both; so the recovered
  file was refused as "a whole recording, not a part" wherever a parts manifest then named it. Recovery
  now takes it from the ``manifest`` metadata.
* The studies' pictures (``wave_study.png``, ``detection_ap.png``, ``robustness_ap.png``) were drawn with whatever
  matplotlib configuration was about: a ``matplotlibrc`` in the current folder (matplotlib reads ``./matplotlibrc``
  first), in ``$MPLCONFIGDIR`` or ``~/.config/matplotlib``, ``$MATPLOTLIBRC``, or a style a script or notebook had
  set; their bytes (line widths, colours, fonts, dpi) changed with the folder a study was run from. They are now
  drawn with matplotlib's defaults (:func:`mmusv.studies.plotting.default_style`); the pictures without such a
  configuration are the same bytes as before.
* A SemanticKITTI sequence's ``calib.txt`` ``Tr`` (and KITTI's per-frame ``calib``) was composed from the frame's
  world poses, so its rounding (entries of 1e-19..1e-14 where the mounts give exact zeros) depended on the first
  converted frame, and ``--frames 1:`` wrote other bytes than the whole conversion for a transform rigid on the
  hull; it is composed from the mounts now.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from tiny_scenario import lidar_scenario


def _failing_batch(folder: Path) -> Path:
    """A batch folder of three scenarios that fail without recording a frame: a schema error and a file that is not
    YAML (refused when the batch is planned), and a route on land (refused by the task's route checks)."""
    folder.mkdir(parents=True)
    bad = lidar_scenario("bad_schema", frames=2)
    bad["vessels"][0]["speed_mps"] = -5
    (folder / "bad_schema.yaml").write_text(yaml.safe_dump(bad), encoding="utf-8")
    (folder / "broken.yaml").write_text("name: [unclosed\n", encoding="utf-8")
    land = lidar_scenario("on_land", frames=2)
    land["map"] = {"type": "island", "seed": 4}
    land["vessels"][0]["route"] = [[500, 500], [510, 500]]
    (folder / "on_land.yaml").write_text(yaml.safe_dump(land), encoding="utf-8")
    return folder


def test_a_batch_index_names_no_absolute_path_in_its_errors(tmp_path: Path) -> None:
    from mmusv.batch import run_many

    indexes = []
    for src, out in (
        (tmp_path / "one" / "scen", tmp_path / "one" / "out"),
        (tmp_path / "two" / "deeper" / "scenarios", tmp_path / "elsewhere" / "batch_out"),
    ):
        report = run_many(_failing_batch(src), out_dir=out)
        assert not report.ok
        indexes.append((out / "dataset.json").read_bytes())
    doc = json.loads(indexes[0])
    errors = {r["name"]: r["error"] for r in doc["recordings"]}
    assert all(r["status"] == "failed" for r in doc["recordings"]) and all(errors.values()), errors
    assert errors["bad_schema"].startswith("bad_schema.yaml: ") and "speed_mps" in errors["bad_schema"]
    assert errors["on_land"].startswith("on_land.yaml: in_water: ") and errors["broken"].startswith("broken.yaml: ")
    assert str(tmp_path) not in indexes[0].decode()
    assert indexes[0] == indexes[1]


def _front_camera_recording(folder: Path) -> Path:
    """The export tests' two-USV ``coop`` scene for 2 frames with a rig of an 8-channel LiDAR and one tiny front
    camera (about a second)."""
    import mmusv

    spec = importlib.util.spec_from_file_location(
        "export_scenes", Path(__file__).resolve().parent / "export/conftest.py"
    )
    assert spec is not None and spec.loader is not None
    scenes = importlib.util.module_from_spec(spec)  # the export tests' scenes, without their fixtures' registration
    spec.loader.exec_module(scenes)
    sc = scenes.coop(name="calib")
    sc["acquisition"]["frames"] = 2
    sc["rigs"]["r"] = {
        "lidar": {"channels": 8, "points_per_second": 20480, "rotation_hz": 5},
        "cameras": [{"name": "front", "resolution": [32, 24], "hfov_deg": 90, "mount": {"point": "camera_front"}}],
    }
    mmusv.run(sc, out_dir=folder)
    return folder / "calib.mcap"


def test_a_semantickitti_calibration_is_the_same_whatever_the_first_frame(tmp_path: Path) -> None:
    """``mmusv.export.kitti.front_calib`` composed the LiDAR → front camera transform from the frame's world poses,
    whose rounding (1e-19..1e-14 where 0 is exact) changed from frame to frame, so a SemanticKITTI sequence's
    calib.txt (its first converted frame's) was other bytes with ``--frames 1:`` than with all frames, and KITTI's
    per-frame calib files differed, though both sensors are rigid on the hull; it is the mounts' now."""
    from mmusv.export.conversion import convert

    rec = _front_camera_recording(tmp_path / "rec")
    convert(rec, to="semantickitti", out_dir=tmp_path / "all", splits=None)
    convert(rec, to="semantickitti", out_dir=tmp_path / "from1", splits=None, frames=(1, None))
    for seq in ("00", "01"):
        whole = (tmp_path / "all" / "sequences" / seq / "calib.txt").read_bytes()
        assert (tmp_path / "from1" / "sequences" / seq / "calib.txt").read_bytes() == whole, seq


_KILL_AT = """
import os, signal, sys
from mmusv.acquire import run
def progress(done, total):
    if done == int(sys.argv[3]):
        os.kill(os.getpid(), signal.SIGKILL)
span = None if sys.argv[4] == "whole" else (int(sys.argv[4]), 300)
run(sys.argv[1], out_dir=sys.argv[2], frame_range=span, frames=300 if span is None else None, progress=progress)
"""


@pytest.mark.parametrize("first", [40, 0, None], ids=["range-from-40", "range-from-0", "whole-run"])
def test_a_recovered_frame_range_says_where_it_starts(tmp_path: Path, first: int | None) -> None:
    """A range from frame 0 (a split run's part 0, recovered away from its parts manifest) kept no ``first_frame``
    either: it and a whole run said the same (first frame 0) until the ``manifest`` metadata said
    ``frame_range``. A whole run recovered still says nothing of a first frame."""
    from mcap.reader import make_reader
    from mmusv.recording.recover import recover

    src = tmp_path / "dense.yaml"
    src.write_text(yaml.safe_dump(lidar_scenario("dense", frames=300, dense=True)), encoding="utf-8")
    out = tmp_path / "run"
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1] / "python")}
    proc = subprocess.run(  # 110 frames of ~60 kB: the first 4 MiB chunk is on disk when it is killed
        [sys.executable, "-c", _KILL_AT, str(src), str(out), "110", "whole" if first is None else str(first)],
        env=env,
        capture_output=True,
        timeout=120,
    )
    assert proc.returncode == -9, proc.stderr.decode()
    rec = recover(out)
    assert rec.frames and rec.frames[0] == (first or 0), rec.frames[:3]
    manifest = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
    with (out / "dense.mcap").open("rb") as f:
        run = {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}["run"]
    assert manifest["status"] == "interrupted" and manifest["frames_written"] == len(rec.frames)
    if first is None:
        assert "first_frame" not in manifest and "first_frame" not in run, (manifest, run)
    else:
        assert manifest.get("first_frame") == first and run.get("first_frame") == str(first), (manifest, run)


def test_the_wave_study_picture_is_the_same_from_a_folder_with_a_matplotlibrc(tmp_path: Path) -> None:
    pngs = []
    for name, rc in (("plain", None), ("styled", "lines.linewidth: 4\nsavefig.facecolor: red\nfont.size: 20\n")):
        cwd = tmp_path / name
        cwd.mkdir()
        if rc is not None:
            (cwd / "matplotlibrc").write_text(rc, encoding="utf-8")
        env = {
            **os.environ,
            "PYTHONPATH": str(Path(__file__).resolve().parents[1] / "python"),
            "MPLCONFIGDIR": str(tmp_path / "mplconfig"),  # not this machine's own configuration
        }
        env.pop("MATPLOTLIBRC", None)
        proc = subprocess.run(
            [sys.executable, "-m", "mmusv", "study", "waves", "--frames", "5", "-o", "out"],
            cwd=cwd,
            env=env,
            capture_output=True,
            timeout=120,
        )
        assert proc.returncode == 0, proc.stderr.decode()
        pngs.append((cwd / "out" / "wave_study.png").read_bytes())
        assert (cwd / "out" / "wave_study.csv").read_bytes() == (tmp_path / "plain/out/wave_study.csv").read_bytes()
    assert pngs[0] == pngs[1]


def test_the_detection_picture_is_the_same_under_a_caller_s_style(tmp_path: Path) -> None:
    import matplotlib
    import polars as pl
    from mmusv.studies.detection.report import BINS, _plot_detection

    row = {"ap30": 0.6, "ap50": 0.5, "ap70": 0.2, **{f"ap50_{b}": 0.1 * (i + 1) for i, b in enumerate(BINS)}}
    table = pl.DataFrame([{"mode": m, **row} for m in ("none", "late", "early")])
    _plot_detection(table, tmp_path / "plain.png")
    with matplotlib.rc_context({"lines.linewidth": 4.0, "axes.facecolor": "black", "savefig.dpi": 50}):
        _plot_detection(table, tmp_path / "styled.png")
    assert (tmp_path / "styled.png").read_bytes() == (tmp_path / "plain.png").read_bytes()


@pytest.mark.parametrize(
    ("error", "said"),
    [
        ("cannot write /private/tmp/out/bad/bad.mcap", "cannot write /private/tmp/out/bad/bad.mcap"),  # not inside
        ("cannot write /tmp/out/", "cannot write ."),  # the path vanished
        ("/tmp/out/a/b.mcap: x; see /tmp/output/c", "a/b.mcap: x; see /tmp/output/c"),  # a prefix of another
        ("/tmp/out/scenarios/other.yaml: y", "other.yaml: y"),
        ("in /tmp/out, stop", "in ., stop"),
    ],
)
def test_an_index_error_loses_only_the_folders_where_a_path_starts(error: str, said: str) -> None:
    """The review's: the folders were replaced anywhere in the message (``/private/tmp/out/...`` became
    ``/privatebad/...``; ``/tmp/out/`` vanished)."""
    from types import SimpleNamespace

    from mmusv.batch.runner import _portable_error

    plan = SimpleNamespace(file=Path("/tmp/out/scenarios/bad.yaml"))
    assert _portable_error(error, plan, Path("/tmp/out")) == said  # type: ignore[arg-type]


def test_task_files_of_a_name_holding_an_at_sign_are_its_own(tmp_path: Path) -> None:
    """The review's: a name was cut at its first ``@``, so ``b@x``'s stale part ``b@x@000000-000001.task`` stayed and
    ``b@x``'s clean-up could take another scenario's files; now a task file is the name's own when the name is
    followed by nothing or by ``@`` and a part folder's name. (``a@000000-000001`` is ``a``'s first part's key, and
    the key of a scenario file of that name: the batch's keys cannot tell those two apart.)"""
    from mmusv.batch.plan import remove_task_files

    for key in ("a", "a@000000-000001", "ab", "b@x", "b@x@000000-000001", "b@x@y"):
        (tmp_path / f"{key}.task").write_text("")
    remove_task_files(tmp_path, "b@x", keep={"b@x"})
    assert sorted(p.stem for p in tmp_path.iterdir()) == ["a", "a@000000-000001", "ab", "b@x", "b@x@y"]
    remove_task_files(tmp_path, "a", keep=set())
    assert sorted(p.stem for p in tmp_path.iterdir()) == ["ab", "b@x", "b@x@y"]
