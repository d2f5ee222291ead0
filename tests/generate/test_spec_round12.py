"""A generation spec's cross-field errors echoed the value whole: a 1 MB ``rig`` or ``difficulty`` name made a
1 MB message. The value is shortened as in every other message (:func:`mmusv.config_errors.short_repr`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.errors import ConfigError
from mmusv.generate.spec import load_spec

SPEC = Path(__file__).resolve().parents[2] / "scenarios" / "specs" / "island_demo.yaml"


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda d: d.update(rig="y" * 1_000_000), "invalid spec rig = 'yyy"),
        (lambda d: d["combinations"][0].update(difficulty="y" * 1_000_000), "combinations[0].difficulty = 'yyy"),
    ],
)
def test_a_long_name_is_shortened_in_the_error(change: Any, field: str) -> None:
    doc = yaml.safe_load(SPEC.read_text(encoding="utf-8"))
    change(doc)
    with pytest.raises(ConfigError) as info:
        load_spec(doc)
    msg = str(info.value)
    assert field in msg and "...y" in msg and "not defined under" in msg, msg[:300]
    assert len(msg) < 1000, len(msg)
