"""Rig knobs a researcher sets by mistake are refused by name: a top view asked for ``depth`` (it has no depth
topic; it used to be recorded under an undocumented ``/{agent}/top_view/depth``), a camera or top view with
no ``outputs`` at all (it used to be rendered every frame and recorded nowhere) or with one listed twice."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from mmusv.cli import main
from mmusv.config import load_scenario
from mmusv.sensors.config import CameraConfig, TopViewConfig

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "open_sea_convoy.yaml"


def _scenario(tmp_path: Path, rig: dict[str, object]) -> Path:
    data = yaml.safe_load(SCENARIO.read_text())
    data["acquisition"]["frames"] = 1
    small = {"preset": "lidar_only", "lidar": {"channels": 2, "points_per_second": 720, "rotation_hz": 10}}
    data["rigs"] = {"usv_standard": {**small, **rig}}  # small: the old code ran the scenario
    path = tmp_path / "knobs.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def test_top_view_outputs_are_rgb_semantic_instance() -> None:
    assert TopViewConfig(outputs=["rgb", "semantic", "instance"]).outputs == ["rgb", "semantic", "instance"]
    with pytest.raises(ValueError, match=r"outputs\.1\n.*'rgb', 'semantic' or 'instance'"):
        TopViewConfig(outputs=["rgb", "depth"])


@pytest.mark.parametrize("model", [CameraConfig, TopViewConfig])
def test_no_outputs_is_refused(model: type[CameraConfig] | type[TopViewConfig]) -> None:
    kw = {"name": "c"} if model is CameraConfig else {}
    with pytest.raises(ValueError, match=r"outputs\n.*must list at least one of rgb, "):
        model(outputs=[], **kw)


@pytest.mark.parametrize(
    ("rig", "message"),
    [
        (
            {"top_view": {"outputs": ["rgb", "depth"]}},
            "rigs.usv_standard.top_view.outputs[1] = 'depth': Input should be 'rgb', 'semantic' or 'instance'",
        ),
        (
            {"top_view": {"outputs": []}},
            "rigs.usv_standard.top_view.outputs = []: must list at least one of rgb, semantic, instance; "
            "to drop the top view, set top_view: null",
        ),
        (
            {"cameras": [{"name": "a", "mount": {"point": "camera_front"}, "outputs": []}]},
            "rigs.usv_standard.cameras[0].outputs = []: must list at least one of rgb, depth, semantic, instance; "
            "to drop the camera, leave it out of cameras (cameras: [] for none)",
        ),
        (  # was accepted, and the sensors metadata listed the image twice
            {"cameras": [{"name": "a", "mount": {"point": "camera_front"}, "outputs": ["depth", "semantic", "depth"]}]},
            "rigs.usv_standard.cameras[0].outputs = ['depth', 'semantic', 'depth']: lists depth more than once; list "
            "each output once (of rgb, depth, semantic, instance)",
        ),
        (
            {"top_view": {"outputs": ["semantic", "semantic"]}},
            "rigs.usv_standard.top_view.outputs = ['semantic', 'semantic']: lists semantic more than once; list each "
            "output once (of rgb, semantic, instance)",
        ),
    ],
)
def test_cli_refuses_the_outputs_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], rig: dict[str, object], message: str
) -> None:
    path = _scenario(tmp_path, rig)
    with pytest.raises(Exception, match="outputs"):  # the loader itself refuses it, before any sensor is built
        load_scenario(path)
    assert main(["run", str(path), "-o", str(tmp_path / "out"), "--frames", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"mmusv: error: {path}: invalid config {message}", err
    assert "Traceback" not in err and not (tmp_path / "out").exists()
