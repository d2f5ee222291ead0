"""The helpers that took the place of logic written twice: each answers as both copies did.

* :func:`mmusv.sensors.env.check_config` / :func:`~mmusv.sensors.env.check_sensor`: the argument checks of every
  ``*_from_config`` builder and sensor call (LiDAR, radar, cameras), one message format for all.
* ``_up_to_extent`` of :mod:`mmusv.world.map_params`: the knobs bounded by ``extent_m / k``, a number or a pair.
* ``_per_face`` of :mod:`mmusv.world.primitives`: a mesh's classes and materials broadcast to its faces.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from mmusv._native import core
from mmusv.errors import ConfigError, InputError
from mmusv.sensors.config import CameraConfig, LidarConfig, RadarConfig, TopViewConfig
from mmusv.sensors.env import check_config, check_sensor
from mmusv.sensors.radar import radar_from_config
from mmusv.world.map_params import MapConfigError, make_params
from mmusv.world.primitives import TriMesh


@pytest.mark.parametrize("cls", [LidarConfig, RadarConfig, CameraConfig, TopViewConfig])
def test_check_config_names_the_model(cls: type) -> None:
    with pytest.raises(ConfigError) as err:
        check_config({"channels": 4}, cls)
    name = cls.__name__
    assert str(err.value) == (
        f"cfg = {{'channels': 4}}: must be a {name} (mmusv.sensors.config.{name}(**fields)), not dict"
    )
    check_config(cls(name="c") if cls is CameraConfig else cls(), cls)  # a config of the class passes


def test_check_sensor_names_the_argument_and_the_makers() -> None:
    with pytest.raises(InputError) as err:
        check_sensor(LidarConfig(), core.Lidar, name="lidar", made_by="lidar_from_config(LidarConfig(...))")
    assert re.fullmatch(
        r"lidar = LidarConfig\(.*\): must be a native lidar \(lidar_from_config\(LidarConfig\(\.\.\.\)\)\), "
        r"not LidarConfig",
        str(err.value),
    )
    radar = radar_from_config(RadarConfig())
    check_sensor(radar, core.Radar, name="radar", made_by="")  # a native sensor of the kind passes


@pytest.mark.parametrize(
    ("kind", "params", "allowed"),
    [
        ("island", {"clearance_m": 600}, "a number in [0, 500] (the upper bound is extent_m / 4"),
        ("island", {"min_gap_m": 1500}, "a number in [0, 1000] (the upper bound is extent_m / 2"),
        ("island", {"island_radius_m": [10, 20]}, "two numbers [a, b] with 15 <= a <= b <= 1000 (the upper bound is "),
        ("open_sea", {"islet_radius_m": [20, 1001]}, "two numbers [a, b] with 10 <= a <= b <= 1000 (the upper bound "),
    ],
)
def test_knobs_bounded_by_the_extent(kind: str, params: dict[str, object], allowed: str) -> None:
    with pytest.raises(MapConfigError) as err:
        make_params(kind, **params)
    assert err.value.allowed.startswith(allowed)
    assert err.value.allowed.endswith("set this knob too, or raise extent_m)")


def test_knobs_at_the_extent_bound_pass() -> None:
    p = make_params("open_sea", clearance_m=1000, islet_radius_m=[20, 1000])
    assert (p.clearance_m, p.islet_radius_m) == (1000.0, (20.0, 1000.0))


def test_classes_and_materials_broadcast_to_the_faces() -> None:
    v, faces = np.zeros((3, 3)), np.array([[0, 1, 2], [0, 2, 1]])
    m = TriMesh(v, faces, np.array(5), np.array([], dtype=np.uint16))
    assert m.classes.tolist() == [5, 5] and m.materials.tolist() == [0, 0]
    assert m.classes.dtype == m.materials.dtype == np.uint16
    with pytest.raises(ValueError, match=r"^classes has 0 entries for 2 faces$"):
        TriMesh(v, faces, np.array([], dtype=np.uint16))
    with pytest.raises(ValueError, match=r"^materials has 3 entries for 2 faces$"):
        TriMesh(v, faces, np.array(1), np.array([1, 2, 3]))


@pytest.mark.parametrize(
    ("call", "expected"),
    [
        (
            "scan",
            "lidar = 'x': must be a native lidar (lidar_from_config(LidarConfig(...)), or Simulation.agent(id).lidar), "
            "not str",
        ),
        (
            "radar_sweep",
            "radar = 'x': must be a native radar (radar_from_config(RadarConfig(...)), or Simulation.agent(id).radar), "
            "not str",
        ),
        (
            "render",
            "camera = 'x': must be a native camera (camera_from_config(CameraConfig(...)), "
            "top_view_from_config(TopViewConfig(...)), or Simulation.agent(id).cameras[name][0]), not str",
        ),
    ],
)
def test_each_sensor_call_names_its_own_sensor_and_makers(call: str, expected: str) -> None:
    """The whole message of each sensor call given something that is not its native sensor: the argument's name and
    the ways to make one are the call's own (a wrong ``name=`` or ``made_by=`` at a call site would show here)."""
    from mmusv.scene import Scene
    from mmusv.sensors.camera import render
    from mmusv.sensors.lidar import scan
    from mmusv.sensors.radar import radar_sweep

    fn = {"scan": scan, "radar_sweep": radar_sweep, "render": render}[call]
    with pytest.raises(InputError) as err:
        fn("x", Scene(), pose=np.eye(4), env=None, seed=0)  # the sensor is checked first
    assert str(err.value) == expected
