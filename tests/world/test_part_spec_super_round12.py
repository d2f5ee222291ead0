"""An antennas part whose height is not more than its base mount (4 radii) made a whip of zero length, and
building the asset raised a bare ValueError ('a tube has zero length'): ``mmusv run`` of a scenario naming it printed
a traceback. (A height below the mount built a whip pointing down into it.) Both are refused now, naming the
field and what is allowed."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from mmusv.config import load_scenario
from mmusv.errors import ConfigError
from mmusv.world.asset_spec import AssetSpecError
from mmusv.world.vessels import load_asset_file

HULL = {"length": 12.0, "beam": 4.0, "draft": 0.6, "depth": 1.8}


def _boat(height: float, radius: float) -> dict[str, object]:
    return {
        "name": "ant_boat",
        "hull": HULL,
        "parts": [{"type": "antennas", "at": [[0, 0, 1.2, height]], "radius": radius}],
    }


@pytest.mark.parametrize(("height", "radius"), [(1.2, 0.3), (1.0, 0.3), (0.2, 0.1)])
def test_an_antenna_no_taller_than_its_mount_is_refused(height: float, radius: float) -> None:
    with pytest.raises(AssetSpecError) as info:
        load_asset_file(_boat(height, radius))
    msg = str(info.value)
    assert info.value.field == "ant_boat.parts[0].at[0][3]", msg
    assert f"height {height:g} m must be more than 4 x radius ({4 * radius:g} m" in msg, msg


def test_an_antenna_taller_than_its_mount_is_built() -> None:
    assert load_asset_file(_boat(1.3, 0.3)).height > 1.8


def test_a_scenario_naming_it_is_a_config_error_naming_the_asset_file(tmp_path: Path) -> None:
    (tmp_path / "boat.yaml").write_text(yaml.safe_dump(_boat(1.2, 0.3)), encoding="utf-8")
    scenario = {
        "name": "ant",
        "map": {"type": "open_sea"},
        "assets": ["boat.yaml"],
        "vessels": [{"id": "t", "asset": "ant_boat", "route": [[0, 0], [50, 0]]}],
    }
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(scenario), encoding="utf-8")
    with pytest.raises(ConfigError) as info:
        load_scenario(path)
    msg = str(info.value)
    assert str(path) in msg and "boat.yaml" in msg and "parts[0].at[0][3]" in msg, msg
