"""Malformed procedural asset entries: each is refused with an AssetSpecError naming the field, quickly.

Before these checks the entries below raised bare numpy/ValueError/OverflowError/MemoryError, emitted RuntimeWarnings,
hung, or built degenerate meshes (zero-area or inside-out pieces, parts far outside the hull).
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import pytest
from mmusv.world.vessels import AssetSpecError, load_asset_file, unregister_asset

HULL: dict[str, Any] = {"length": 30.0, "beam": 8.0, "draft": 2.0, "depth": 4.0}
TWIN: dict[str, Any] = {"type": "twin", "length": 20.0, "beam": 8.0, "demi_beam": 2.0, "draft": 1.0, "depth": 2.5}
BOX: dict[str, Any] = {"type": "box", "x": 0.0, "size": [6.0, 4.0], "height": 3.0}


def _entry(*, hull: dict[str, Any] | None = None, parts: list[dict[str, Any]] | None = None) -> dict[str, Any]:
    """A procedural entry named ``bad`` with ``hull`` (default :data:`HULL`) and ``parts``."""
    return {"name": "bad", "hull": copy.deepcopy(hull or HULL), "parts": copy.deepcopy(parts or [])}


def _part(**kw: Any) -> list[dict[str, Any]]:
    """One part given by ``kw``."""
    return [kw]


CASES: list[tuple[str, dict[str, Any], str]] = [
    # hull: degenerate or overflowing dimensions
    ("draft tiny", _entry(hull=dict(HULL, draft=1e-300)), "bad.hull.draft"),
    ("freeboard tiny", _entry(hull=dict(HULL, draft=3.99999999)), "bad.hull.depth"),
    ("sheer huge", _entry(hull=dict(HULL, sheer=1e300)), "bad.hull.sheer"),
    ("twin depth huge", _entry(hull=dict(TWIN, depth=1e300)), "bad.hull.depth"),
    ("bow taper tiny", _entry(hull=dict(HULL, bow=1e-6)), "bad.hull.bow"),
    ("demi_beam tiny", _entry(hull=dict(TWIN, demi_beam=1e-300)), "bad.hull.demi_beam"),
    ("hull too tall", _entry(hull=dict(HULL, sheer=500.0)), "bad.hull"),
    # parts: sizes that are negative, zero or tiny (inside-out / zero-area pieces)
    ("box size negative", _entry(parts=_part(type="box", x=0.0, size=[-1.0, 2.0], height=1.0)), "bad.parts[0].size"),
    ("box size zero", _entry(parts=_part(type="box", x=0.0, size=[0.0, 2.0], height=1.0)), "bad.parts[0].size"),
    ("box taper tiny", _entry(parts=[dict(BOX, taper=1e-300)]), "bad.parts[0].taper"),
    ("house tier h zero", _entry(parts=_part(type="house", x=0.0, tiers=[[6.0, 4.0, 0.0]])), "bad.parts[0].tiers"),
    ("house taper huge", _entry(parts=_part(type="house", x=0.0, tiers=[[6, 4, 3]], taper=1e9)), "bad.parts[0].taper"),
    ("windows width tiny", _entry(parts=_part(type="windows", x0=-5, x1=5, z=3, width=1e-300, height=1, pitch=2)), "w"),
    ("mast yard tiny", _entry(parts=_part(type="mast", x=0.0, top=8.0, yard=1e-300)), "bad.parts[0].yard"),
    (
        "containers width too small for rows",
        _entry(parts=_part(type="containers", x0=-10, x1=10, bays=1, rows=5, tiers=[1], width=0.5, base=4.0)),
        "bad.parts[0].width",
    ),
    (
        "hatches narrower than the coaming",
        _entry(parts=_part(type="hatches", x0=-10, x1=10, count=2, width=0.2, height=1.0)),
        "bad.parts[0].width",
    ),
    # parts: huge values (overflow, precision loss, bare exceptions)
    ("dome radius huge", _entry(parts=_part(type="dome", x=0.0, radius=1e300, top=8.0)), "bad.parts[0].radius"),
    ("strut from huge", _entry(parts=_part(type="strut", **{"from": [1e300, 0, 5], "to": [1, 0, 5]}, width=0.1)), "f"),
    ("crane jib huge", _entry(parts=_part(type="crane", x=0.0, pedestal=[0.5, 2.0], jib=[1e300, 30, 0])), "j"),
    ("antenna height huge", _entry(parts=_part(type="antennas", at=[[0, 0, 4, 1e300]])), "bad.parts[0].at[0][3]"),
    (
        "containers seed huge",
        _entry(parts=_part(type="containers", x0=-10, x1=10, bays=1, rows=2, tiers=[1], width=5, seed=1e300)),
        "bad.parts[0].seed",
    ),
    ("part far below the keel", _entry(parts=[dict(BOX, base=-499.0, height=1.0)]), "bad.parts[0]"),
    # counts and list lengths: bounded
    ("row count 1e9", _entry(parts=_part(type="row", x0=-10, x1=10, count=1e9, width=2, heights=[1])), "c"),
    ("antennas 100000", _entry(parts=_part(type="antennas", at=[[0, 0, 4, 1]] * 100000)), "bad.parts[0].at"),
    ("masthead 100000", _entry(parts=_part(type="nav_lights", masthead=[[0, 0, 5]] * 100000)), "m"),
    ("1001 parts", _entry(parts=[BOX] * 1001), "bad.parts"),
]
_SHORT = {
    "w": "bad.parts[0].width",
    "f": "bad.parts[0].from",
    "j": "bad.parts[0].jib",
    "c": "bad.parts[0].count",
    "m": "bad.parts[0].masthead",
}


@pytest.mark.parametrize(("entry", "field"), [pytest.param(e, f, id=i) for i, e, f in CASES])
def test_bad_procedural_entry_names_the_field(entry: dict[str, Any], field: str) -> None:
    field = _SHORT.get(field, field)
    with pytest.raises(AssetSpecError) as info:
        load_asset_file(entry)
    assert info.value.field.startswith(field), str(info.value)
    assert str(info.value).startswith(field)


def _min_area(entry: dict[str, Any]) -> float:
    mesh = load_asset_file(entry).mesh
    tri = mesh.vertices[mesh.faces]
    return float((0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)).min())


def test_smallest_accepted_sizes_build_faces_of_real_area() -> None:
    parts = [
        {"type": "tube", "from": [0, 0, 5], "to": [1, 0, 5], "radius": 0.001},
        {"type": "mast", "x": 2.0, "top": 8.0, "width": 0.001, "yard": 0.001},
        {"type": "box", "x": -2.0, "size": [0.001, 0.001], "height": 0.001, "taper": 0.05},
    ]
    assert _min_area(_entry(hull=dict(HULL, bow=0.01, stern=0.01, draft=0.01, depth=0.02), parts=parts)) > 1e-10


def test_accepted_odd_asset_runs_in_a_scenario(tmp_path: Path) -> None:
    odd = _entry(
        hull={"length": 6.0, "beam": 8.0, "draft": 0.3, "depth": 1.0, "bow": 0.0, "stern": 0.0},  # beam > length
        parts=[
            {"type": "box", "x": 0.0, "size": [2, 2], "base": 40.0, "height": 1.0},  # far above the deck
            {"type": "box", "x": 0.0, "size": [2, 2], "height": 1.0},
            {"type": "box", "x": 0.0, "size": [2, 2], "height": 1.0},  # overlapping
            {"type": "tube", "from": [0, 0, 1], "to": [1, 0, 1.001], "radius": 0.001},
        ],
    )
    odd.update(name="test_fz4_odd", semantic_class="usv", mounts={"lidar": {"xyz": [0.0, 0.0, 3.5]}})
    load_asset_file(odd, register=True)
    try:
        doc = {
            "name": "fz4",
            "seed": 1,
            "map": {"type": "open_sea"},
            "acquisition": {"frequency_hz": 5, "frames": 1},
            "rigs": {"r": {"preset": "lidar_only"}},
            "vessels": [
                {
                    "id": "ego",
                    "role": "usv",
                    "asset": "test_fz4_odd",
                    "rig": "r",
                    "speed_mps": 1.0,
                    "route": [[0, 0], [20, 0]],
                },
                {"id": "t", "role": "target", "asset": "test_fz4_odd", "speed_mps": 1.0, "route": [[30, 5], [40, 5]]},
            ],
        }
        res = mmusv.run(doc, out_dir=tmp_path / "run", frames=1)
        assert res.status == "complete" and res.frames_written == 1
    finally:
        unregister_asset("test_fz4_odd")
