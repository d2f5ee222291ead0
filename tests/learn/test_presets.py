"""Presets: ``--set KEY=VALUE`` overrides parsed into typed fields, and rejected with the item and what is allowed."""

from __future__ import annotations

import pytest
from mmusv.errors import InputError
from mmusv.learn.presets import PRESETS, parse_overrides, preset


def test_overrides_typed_as_the_fields() -> None:
    got = parse_overrides(
        [
            "min_points=1",
            "code_weights=[1,1,0.1,1,1,1,1,1]",
            "lr=1",
            "flip=false",
            "z_range=[-5,10]",
            "blocks=[[8,1,2]]",
        ]
    )
    assert got == {
        "min_points": 1,
        "code_weights": (1.0, 1.0, 0.1, 1.0, 1.0, 1.0, 1.0, 1.0),
        "lr": 1.0,
        "flip": False,
        "z_range": (-5.0, 10.0),
        "blocks": ((8, 1, 2),),
    }
    assert type(got["lr"]) is float and all(type(v) is float for v in got["code_weights"])
    p = preset("paper", **parse_overrides(["min_points=1", "code_weights=[1,1,0.1,1,1,1,1,1]"]))
    # the cpu preset's two loss choices on the paper grid; everything else the paper's
    assert (p.min_points, p.code_weights) == (PRESETS["cpu"].min_points, PRESETS["cpu"].code_weights)
    assert (p.pillar_m, p.lr, p.batch, p.epochs, p.name) == (0.4, 2e-3, 4, 30, "paper")
    assert parse_overrides([]) == {}


@pytest.mark.parametrize(
    ("item", "says"),
    [
        ("foo=1", "KEY one of"),
        ("name=x", "KEY one of"),
        ("min_points", "KEY=VALUE"),
        ("min_points=1.5", "min_points must be an integer"),
        ("min_points=true", "min_points must be an integer"),
        ("code_weights=[1,2]", "code_weights must be a list of 8 numbers"),
        ("z_range=[1]", "z_range must be a list of 2 numbers"),
        ("flip=1", "flip must be true or false"),
        ("lr=abc", "not JSON"),
        ("lr=[1]", "lr must be a number"),
        ("blocks=[[1,2]]", "blocks must be a list of [channels, layers, stride]"),
    ],
)
def test_bad_overrides_name_the_item(item: str, says: str) -> None:
    # called from Python: the list's item by its index (mmusv train --set names the flag: test_replay)
    with pytest.raises(InputError, match=r"^items\[0\] = '.*'") as err:
        parse_overrides([item])
    assert item in str(err.value) and says in str(err.value)
