"""A maritime domain expert's round on the world mmusv builds, checked against independent references.

Findings, each with its test:

* ``island_port_waves`` (the wave study's scenario) sailed its 300 m container ship (draft 14.5 m) over 7.8 m of
  water on the island's shelf, and its 32 m tug (draft 5.0 m) with 0.4 m under the keel; over the study's 20
  minutes the container ship, stopped at its route's end, lay across the speedboat's loop, whose hull sailed
  through it. The two routes now keep to water at least 1.1 x their draft deep and no two hulls ever meet
  (:func:`test_bundled_vessels_float_with_ten_per_cent_under_the_keel`,
  :func:`test_wave_study_hulls_never_overlap_over_its_twenty_minutes`).
* COLREG lights: eight power-driven vessels of 50 m and more (superyacht, research vessel, OSV, ro-pax ferry,
  dredger, ro-ro, car carrier, cruise ship) carried one masthead light, not the two of Rule 23(a)(ii); the
  sailing yacht and catamaran (sails hoisted), the kayak (under oars) and the deck barge (towed) carried a
  masthead light, which marks a power-driven vessel (Rules 24(e), 25(a), 25(d))
  (:func:`test_masthead_lights_follow_colreg_rules_23_to_25`).
* ``mmusv generate`` gave a sea kayak up to 8.7 m/s (17 kn), a 12 m cruising sloop 8.5 m/s (16 kn) and a towed
  deck barge 6.6 m/s (13 kn): the size class's range alone, whatever the vessel type
  (:func:`test_generated_targets_stay_below_their_type_s_top_speed`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest
import yaml
from mmusv.config import load_scenario
from mmusv.motion import build_fleet, scenario_poses
from mmusv.world.maps import generate_map_from
from mmusv.world.materials import lamp_ids
from mmusv.world.vessels import asset_names, get_asset

ROOT = Path(__file__).resolve().parents[1]
BUNDLED = sorted((ROOT / "scenarios").glob("*.yaml"))

UKC_FRACTION = 0.10
"""Least gross under-keel clearance, a fraction of the draft: PIANC (2014), Report 121 "Harbour Approach Channels
Design Guidelines", §3.3 (10 % of the draft in sheltered water with waves under 1 m; more in open water)."""


def _footprint(pose: npt.NDArray[np.float64], length: float, beam: float) -> npt.NDArray[np.float64]:
    """Points covering the hull's waterplane box at ``pose`` (``x, y, ..., yaw``): 9 along x 5 across, world xy."""
    u, v = np.meshgrid(np.linspace(-length / 2, length / 2, 9), np.linspace(-beam / 2, beam / 2, 5))
    c, s = math.cos(pose[5]), math.sin(pose[5])
    return np.stack([pose[0] + c * u.ravel() - s * v.ravel(), pose[1] + s * u.ravel() + c * v.ravel()], axis=1)


@pytest.mark.parametrize("path", BUNDLED, ids=[p.stem for p in BUNDLED])
def test_bundled_vessels_float_with_ten_per_cent_under_the_keel(path: Path) -> None:
    """Every vessel of every bundled scenario, at every 5th recorded frame, and every moored ship has water at
    least (1 + 10 %) x its draft deep under its whole hull box (PIANC 2014; the seabed is the map's terrain)."""
    scenario = load_scenario(path)
    world = generate_map_from(scenario.map.params, seed=scenario.map.seed)
    poses = scenario_poses(scenario)[::5]
    hulls = [(v.id, get_asset(v.asset), poses[:, i]) for i, v in enumerate(scenario.vessels)]
    hulls += [
        (f"moored_{k:02d}", get_asset(name), np.array([[x, y, 0.0, 0.0, 0.0, yaw]]))
        for k, (name, (x, y, yaw)) in enumerate(world.moored)
    ]
    for vid, asset, track in hulls:
        points = np.concatenate([_footprint(p, asset.length, asset.beam) for p in track])
        depth = -float(np.nanmax(world.heightfield.sample(points)))
        assert depth >= (1.0 + UKC_FRACTION) * asset.draft, (vid, asset.name, asset.draft, round(depth, 1))


def _corners(x: np.ndarray, y: np.ndarray, yaw: np.ndarray, length: float, beam: float) -> np.ndarray:
    """``(T, 4, 2)`` corners of a hull box along a track."""
    u = np.array([1, 1, -1, -1]) * length / 2
    v = np.array([1, -1, -1, 1]) * beam / 2
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    return np.stack([x[:, None] + c * u - s * v, y[:, None] + s * u + c * v], axis=-1)


def _overlap(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``(T,)`` whether two rectangles (``(T, 4, 2)`` corners each) overlap: no separating axis among their edges."""
    apart = np.zeros(a.shape[0], dtype=bool)
    for box in (a, b):
        for k in range(2):
            edge = box[:, k + 1] - box[:, k]
            axis = np.stack([-edge[:, 1], edge[:, 0]], axis=1)
            pa = np.einsum("tkd,td->tk", a, axis)
            pb = np.einsum("tkd,td->tk", b, axis)
            apart |= (pa.max(axis=1) < pb.min(axis=1)) | (pb.max(axis=1) < pa.min(axis=1))
    return ~apart


def test_wave_study_hulls_never_overlap_over_its_twenty_minutes() -> None:
    """``mmusv study waves --motion physical`` sails ``island_port_waves`` for 1200 s
    (``mmusv.studies.waves.PHYSICAL_RECORD_S``): no two hull boxes meet at any second of it (the container ship
    used to stop across the speedboat's loop)."""
    from mmusv.studies.waves import PHYSICAL_RECORD_S

    scenario = load_scenario(ROOT / "scenarios" / "island_port_waves.yaml")
    poses = np.asarray(build_fleet(scenario).poses_at_times(np.arange(0.0, PHYSICAL_RECORD_S, 0.5)))
    assets = [get_asset(v.asset) for v in scenario.vessels]
    boxes = [_corners(poses[:, i, 0], poses[:, i, 1], poses[:, i, 5], a.length, a.beam) for i, a in enumerate(assets)]
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            hit = _overlap(boxes[i], boxes[j])
            assert not hit.any(), (scenario.vessels[i].id, scenario.vessels[j].id, float(np.argmax(hit)) * 0.5)


NO_MASTHEAD = {"sailing_yacht", "sailing_catamaran", "kayak", "barge"}
"""Categories that show sidelights and a sternlight but no masthead light: a sailing vessel under sail (COLREG Rule
25(a); these assets have their sails hoisted), a vessel under oars (Rule 25(d)(ii)) and a towed barge (Rule 24(e))."""


def _lamps(name: str, lamp: str) -> list[np.ndarray]:
    """Centres of the lanterns of material ``lamp`` on asset ``name`` (faces within 1 m grouped), body frame."""
    m = get_asset(name).mesh
    centres = m.vertices[m.faces[np.isin(m.materials, lamp_ids(lamp))]].mean(axis=1)
    out = []
    while len(centres):
        near = np.linalg.norm(centres - centres[0], axis=1) < 1.0
        out.append(centres[near].mean(axis=0))
        centres = centres[~near]
    return out


@pytest.mark.parametrize("name", asset_names())
def test_masthead_lights_follow_colreg_rules_23_to_25(name: str) -> None:
    """COLREG 1972: every vessel shows sidelights and a sternlight; a power-driven vessel a masthead light, and from
    50 m a second one abaft of and higher than the forward one (Rule 23(a)(ii)) by at least 4.5 m (Annex I
    2(a)(ii)); sailing, rowed and towed vessels none. A warship (``naval_frigate``) may place its lights otherwise
    (Rule 1(e)), so only its count is checked."""
    asset = get_asset(name)
    assert len(_lamps(name, "nav_port_red")) == len(_lamps(name, "nav_starboard_green")) == 1
    assert len(_lamps(name, "nav_stern_white")) == 1
    heads = sorted(_lamps(name, "nav_masthead_white"), key=lambda p: -p[0])  # forward first
    if asset.category in NO_MASTHEAD:
        assert heads == []
    elif asset.length >= 50.0:
        assert len(heads) == 2, [h.round(1).tolist() for h in heads]
        if asset.category != "naval_frigate":
            assert heads[1][2] - heads[0][2] >= 4.5, [h.round(1).tolist() for h in heads]
    else:
        assert len(heads) >= 1


KNOT = 1852.0 / 3600.0
"""m/s per knot."""
TOP_SPEEDS_MPS = {
    "kayak_4m": 3.0,
    "sailing_yacht_12m": 1.1 * 1.34 * KNOT * math.sqrt(10.7 / 0.3048),
    "deck_barge_60m": 8.0 * KNOT,
}
"""Independent top speeds: a sea kayak is toured at 3-4 kn (1.5-2 m/s) and sprints near 3 m/s; a displacement
yacht's hull speed is 1.34 kn x √(waterline length in feet) (Froude number 0.40; a 12.2 m sloop's waterline about
10.7 m: 4.1 m/s), here with 10 % to spare; a deck barge is towed at 5-8 kn."""


def test_generated_targets_stay_below_their_type_s_top_speed(tmp_path: Path) -> None:
    """``mmusv generate`` with the default small/medium speed ranges (3-10 and 3-8 m/s) over kayaks, sloops and
    barges, in crossing and overtaking encounters (an overtaking target is given the ego's speed plus 1-3 m/s):
    every target stays at or below its type's top speed."""
    from mmusv.generate.runner import generate

    spec = {
        "name": "top_speeds",
        "seed": 5,
        "map": {"type": "open_sea", "seed": 1},
        "acquisition": {"frequency_hz": 1, "frames": 20},
        "size_classes": {
            "small": {"assets": ["kayak_4m", "sailing_yacht_12m"], "speed_mps": [3, 10]},
            "medium": {"assets": ["deck_barge_60m"], "speed_mps": [3, 8]},
        },
        "combinations": [
            {"family": "overtaking", "difficulty": "easy", "targets": ["small"], "quota": 4},
            {"family": "crossing", "difficulty": "easy", "targets": ["medium", "small"], "quota": 3},
        ],
    }
    generate(spec, tmp_path / "out")
    speeds = [
        (v["asset"], float(v["speed_mps"]))
        for f in sorted((tmp_path / "out").glob("*.yaml"))
        for v in yaml.safe_load(f.read_text(encoding="utf-8"))["vessels"]
        if v["role"] != "usv"
    ]
    assert {a for a, _ in speeds} == set(TOP_SPEEDS_MPS)
    for asset, speed in speeds:
        assert 0.0 < speed <= TOP_SPEEDS_MPS[asset] + 1e-9, (asset, speed)
