"""The checks of :mod:`mmusv.export.convert_checks` on their own: values that were taken and should not be."""

from __future__ import annotations

import pytest
from mmusv.errors import ConfigError
from mmusv.export.convert_checks import agent_selection


def test_agents_as_a_dict_is_refused_not_read_as_its_keys() -> None:
    """``agents={"usv_1": ...}`` selected usv_1 without a word (the recordings argument refuses a dict)."""
    with pytest.raises(ConfigError, match=r"^agents = \{'usv_1': 1\}: must be agent ids .*, not dict$"):
        agent_selection({"usv_1": 1})  # type: ignore[arg-type]
    assert agent_selection({"usv_2", "usv_1"}) == ("usv_1", "usv_2")
    assert agent_selection("usv_2,usv_1") == ("usv_1", "usv_2")
