"""A vessel's ``rig`` naming no rig was echoed whole in the error: a 1 MB name made a 1 MB message (the field has
no length limit of its own; a rig's name under ``rigs`` has 64 characters at most). It is shortened as every other
value in a message is (:func:`mmusv.config_errors.short_repr`)."""

from __future__ import annotations

import pytest
from mmusv.config import load_scenario
from mmusv.errors import ConfigError
from tiny_scenario import lidar_scenario


@pytest.mark.parametrize("vessel", [0, 1])  # the USV, and the target (also told that only a USV carries a rig)
def test_a_long_rig_name_a_vessel_gives_is_shortened_in_the_error(vessel: int) -> None:
    doc = lidar_scenario("k", frames=1)
    doc["vessels"][vessel]["rig"] = "x" * 1_000_000
    with pytest.raises(ConfigError) as info:
        load_scenario(doc)
    msg = str(info.value)
    assert "names rig 'xxx" in msg and "...x" in msg and "not defined under rigs" in msg, msg[:300]
    assert len(msg) < 1000, len(msg)
