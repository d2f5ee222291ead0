"""Leftovers of the earlier notes, each as a user met it; every test failed before its fix.

- A LiDAR given both ``elevations_deg`` and a ``vertical_fov_deg`` of its own fired the elevations' rings and
  ignored the field of view without a word; now the two must agree (the field of view the rings' span, or left at
  its default), else the scenario is refused naming both.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import yaml
from mmusv.cli import main
from mmusv.config import Scenario
from tiny_scenario import lidar_scenario


def _with_lidar(**lidar: object) -> dict[str, object]:
    doc = lidar_scenario("elevations", frames=1)
    doc["rigs"]["r"]["lidar"] = {"channels": 3, "points_per_second": 3 * 5 * 360, **lidar}  # type: ignore[index]
    return doc


def test_elevations_with_another_vertical_fov_is_refused_naming_the_file_and_both_fields(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "both.yaml"
    path.write_text(yaml.safe_dump(_with_lidar(elevations_deg=[-15, -5, 2], vertical_fov_deg=[-25, 10])))
    out = tmp_path / "out"
    assert main(["run", str(path), "-o", str(out)]) != 0
    err = capsys.readouterr().err
    assert "both.yaml" in err
    assert "rigs.r.lidar" in err
    assert "vertical_fov_deg [-25.0, 10.0]" in err
    assert "elevations_deg" in err
    assert "[-15, 2]" in err  # the rings' span, which the user may give instead
    assert "Traceback" not in err
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.parametrize("fov", [None, [-25, 15], [-15, 2]])
def test_elevations_with_the_default_or_their_own_span_still_load(fov: list[float] | None) -> None:
    lidar: dict[str, object] = {"elevations_deg": [2, -15, -5]}
    if fov is not None:
        lidar["vertical_fov_deg"] = fov
    rig = Scenario.model_validate(_with_lidar(**lidar)).rigs["r"]
    assert rig.lidar is not None
    assert sorted(rig.lidar.elevations_rad()) == pytest.approx([math.radians(e) for e in (-15, -5, 2)])
