"""A key that is not text in a scenario (``5: 1`` in a vessel, ``2.5: x`` in the environment, ``1: x`` at the top)
was said as pydantic locates it, ending with the key and showing the key as the value: ``vessels[0][5] = 5: Keys
should be strings`` (item 5 of a list, holding 5), ``environment.2.5 = 2.5``. It is now said as the mapping's path,
the key in it and the keys allowed there."""

from __future__ import annotations

from typing import Any

import pytest
from mmusv.config import load_scenario
from mmusv.errors import ConfigError
from tiny_scenario import lidar_scenario


def _refused(change: Any) -> str:
    doc = lidar_scenario("k", frames=1)
    change(doc)
    with pytest.raises(ConfigError) as info:
        load_scenario(doc)
    return str(info.value)


def test_a_number_key_in_a_vessel_names_the_vessel_and_its_keys() -> None:
    msg = _refused(lambda d: d["vessels"][0].update({5: 1}))
    assert "vessels[0] = {5: ...}: the key 5 is not text" in msg, msg
    assert "allowed keys: id, role, asset" in msg and "[5]" not in msg, msg


def test_a_float_key_in_the_environment_names_the_environment() -> None:
    msg = _refused(lambda d: d["environment"].update({2.5: 1}))
    assert "environment = {2.5: ...}: the key 2.5 is not text" in msg and "allowed keys: time_of_day" in msg, msg


def test_a_key_at_the_top_names_the_scenario() -> None:
    msg = _refused(lambda d: d.update({None: "x"}))
    assert "scenario = {None: ...}: the key None is not text" in msg and "allowed keys: name, seed" in msg, msg


def test_the_keys_allowed_are_listed_once_per_mapping() -> None:
    msg = _refused(lambda d: d["vessels"][0].update({5: 1, 6: 2}))
    assert msg.count("allowed keys") == 1 and "the key 6 is not text" in msg, msg
