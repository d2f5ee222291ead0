"""Scenarios at the mission's scale: 30+ vessels from 3 m to 330 m with moored ships on the port map.

* ``map.params.n_moored`` beyond the berths a port has is refused naming the field and the most that fit (it was
  built with fewer ships, silently, while ``MapWorld.params`` and the reserved ids said the number asked for);
* a 35-vessel scenario (every size class, 300 m+ ships, static and moored vessels) labels every vessel: unique,
  stable ids; every vessel whose box centre is within the LiDAR's range has a 3D box of its catalogue size.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
import shapely
import yaml
from mmusv.cli import main
from mmusv.world.map_params import MapConfigError
from mmusv.world.maps import generate_map
from mmusv.world.vessels import get_asset

# Port map 3 has free berths for seven ships of the default moored_assets (found by hand: the terminal quay holds
# three, the two piers four; an eighth overlaps a pier or another ship).
_FIT = 7


def _footprint(asset: str, pose: tuple[float, float, float]) -> shapely.Polygon:
    """The hull rectangle of a moored ship from the catalogue's length and beam (independent of the map's own)."""
    a = get_asset(asset)
    length, beam = a.length, a.beam
    x, y, yaw = pose
    c, s = np.cos(yaw), np.sin(yaw)
    local = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=np.float64) * [length / 2.0, beam / 2.0]
    return shapely.Polygon(local @ np.array([[c, s], [-s, c]]) + [x, y])


def test_n_moored_that_fits_builds_that_many_ships_apart() -> None:
    w = generate_map("port", seed=3, n_moored=_FIT)
    assert len(w.moored) == _FIT == w.params.n_moored
    feet = [_footprint(a, pose) for a, pose in w.moored]
    for p, q in itertools.combinations(feet, 2):
        assert not p.intersects(q)
    # Every moored ship lies on the water side of the quay line (y = 250 on this map, coast to the north).
    assert all(f.bounds[3] < 250.0 for f in feet)


@pytest.mark.parametrize("asked", [_FIT + 1, 12, 50])
def test_n_moored_beyond_the_berths_is_refused(asked: int) -> None:
    with pytest.raises(MapConfigError) as info:
        generate_map("port", seed=3, n_moored=asked)
    assert info.value.field == "n_moored"
    msg = str(info.value)
    assert f"n_moored={asked}" in msg and f"at most {_FIT}" in msg and "n_piers" in msg


def _scenario(n_moored: int) -> dict[str, object]:
    targets = [
        ("vlcc", "vlcc_tanker_330m", [[-150, -400], [200, -400]], 0.0),
        ("boxship", "container_ship_300m", [[200, -620], [-300, -620]], 6.0),
        ("bulk", "bulk_carrier_290m", [[320, -900], [320, -700]], 5.0),
        ("pctc", "car_carrier_200m", [[-450, -900], [-450, -700]], 5.0),
        ("roro", "roro_180m", [[-700, -450], [-900, -450]], 5.0),
        ("feeder", "feeder_container_140m", [[-130, -700], [-130, -500]], 3.0),
        ("frigate", "frigate_135m", [[500, -300], [800, -300]], 8.0),
        ("cargo", "general_cargo_120m", [[650, -600], [900, -600]], 4.0),
        ("ropax", "ropax_ferry_90m", [[-300, 100], [-130, -50]], 4.0),
        ("osv", "offshore_supply_85m", [[600, -800], [300, -800]], 4.0),
        ("superyacht", "superyacht_60m", [[100, -250], [400, -260]], 3.0),
        ("barge", "deck_barge_60m", [[-400, 0], [-380, 0]], 0.0),
        ("catferry", "catamaran_ferry_40m", [[-450, -100], [0, -120]], 6.0),
        ("patrol", "patrol_boat_35m", [[-300, -250], [-300, -300]], 6.0),
        ("tug", "tug_32m", [[100, 0], [300, -50]], 2.0),
        ("fireboat", "fireboat_25m", [[350, 0], [450, -100]], 2.0),
        ("hover", "hovercraft_22m", [[-700, -650], [-500, -650]], 10.0),
        ("myacht", "motor_yacht_20m", [[-350, 150], [-50, 150]], 3.0),
        ("pilot", "pilot_boat_16m", [[-100, -250], [-100, -300]], 7.0),
        ("syacht", "sailing_yacht_12m", [[150, -350], [250, -300]], 3.0),
        ("fisher", "fishing_boat_12m", [[-600, -200], [-700, -250]], 2.0),
        ("speedboat", "speedboat_5m", [[-200, -320], [200, -330]], 10.0),
        ("rib", "rib_4_5m", [[0, 50], [100, 80]], 5.0),
        ("kayak", "kayak_4m", [[-60, -300], [-40, -310]], 1.0),
        ("jetski", "jet_ski_3m", [[-250, 0], [-150, 30]], 8.0),
        ("crew", "crew_transfer_27m", [[700, -350], [900, -450]], 8.0),
        ("trawler", "trawler_35m", [[800, -800], [800, -950]], 3.0),
    ]
    rig = {"preset": "lidar_only", "lidar": {"channels": 16, "points_per_second": 40_000}}
    usvs = [
        {
            "id": "usv_1",
            "role": "usv",
            "asset": "usv_wamv",
            "rig": "r",
            "speed_mps": 2.5,
            "route": [[-300, -50], [-100, 50]],
        },
        {
            "id": "usv_2",
            "role": "usv",
            "asset": "usv_patrol_12m",
            "rig": "r",
            "speed_mps": 3,
            "route": [[0, 100], [150, 120]],
        },
        {
            "id": "usv_3",
            "role": "usv",
            "asset": "usv_wamv",
            "rig": "r",
            "speed_mps": 2,
            "route": [[-200, -450], [100, -450]],
        },
    ]
    vessels = usvs + [{"id": i, "asset": a, "speed_mps": s, "route": r} for i, a, r, s in targets]
    return {
        "name": "scale35",
        "seed": 4,
        "map": {"type": "port", "seed": 3, "params": {"n_moored": n_moored}},
        "environment": {"wave": "W1"},
        "acquisition": {"frequency_hz": 2, "frames": 2},
        "rigs": {"r": rig},
        "vessels": vessels,
    }


def test_cli_refuses_n_moored_beyond_the_berths(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "many_moored.yaml"
    src.write_text(yaml.safe_dump(_scenario(12)))
    assert main(["run", str(src), "-o", str(tmp_path / "out"), "--no-checks"]) != 0
    err = capsys.readouterr().err
    assert "many_moored.yaml" in err and "n_moored=12" in err and f"at most {_FIT}" in err
    assert not (tmp_path / "out" / "scale35.mcap").exists()


def test_35_vessels_every_vessel_labelled(tmp_path: Path) -> None:
    from mmusv.recording import read_messages

    doc = _scenario(5)
    src = tmp_path / "scale35.yaml"
    src.write_text(yaml.safe_dump(doc))
    assert main(["run", str(src), "-o", str(tmp_path / "out"), "--no-checks"]) == 0
    world: dict[int, object] = {}
    ann: dict[tuple[int, str], object] = {}
    for topic, _, msg in read_messages(tmp_path / "out" / "scale35.mcap"):
        if topic == "/world/state":
            world[msg.frame] = msg
        elif topic.endswith("/annotations"):
            ann[(msg.frame, msg.agent_id)] = msg
    assert sorted(world) == [0, 1]
    names = [v["id"] for v in doc["vessels"]] + [f"moored_{k:02d}" for k in range(5)]  # type: ignore[attr-defined]
    ids_per_frame = []
    for f, w in world.items():
        ids = [v.id for v in w.vessels]  # type: ignore[attr-defined]
        inst = {v.id: v.instance_id for v in w.vessels}  # type: ignore[attr-defined]
        assert sorted(ids) == sorted(names) and len(set(inst.values())) == len(names)
        ids_per_frame.append(inst)
        for v in w.vessels:  # type: ignore[attr-defined]
            a = get_asset(v.asset)
            assert np.allclose(v.box_size, [a.length, a.beam, a.height]), (
                v.id
            )  # 300 m+ hulls at their catalogue length, not cut
        by_id = {v.id: v for v in w.vessels}  # type: ignore[attr-defined]
        for agent in ("usv_1", "usv_2", "usv_3"):
            a = ann[(f, agent)]
            me = np.array(by_id[agent].pose[:2])
            boxed = {b.target_id: b for b in a.boxes_lidar}  # type: ignore[attr-defined]
            assert len(boxed) == len(a.boxes_lidar) == len(a.boxes_bev)  # type: ignore[attr-defined]
            for vid, v in by_id.items():
                if vid == agent:
                    continue
                # The recording's rule: the box's BEV footprint within the LiDAR's 200 m (a margin for the sensor's
                # offset), its distance from the USV by shapely (a 330 m ship centred beyond 200 m may reach in).
                yaw = float(v.pose[5])
                ax = np.array([np.cos(yaw), np.sin(yaw)])
                ay = np.array([-ax[1], ax[0]])
                c = np.array(v.box_center[:2])
                half = np.array(v.box_size[:2]) / 2.0
                rect = [c + sx * half[0] * ax + sy * half[1] * ay for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
                d = float(shapely.Polygon(rect).distance(shapely.Point(*me)))
                if d < 195.0:
                    assert vid in boxed, (f, agent, vid, d)
                    assert np.allclose(boxed[vid].size, v.box_size)
                elif d > 205.0:
                    assert vid not in boxed, (f, agent, vid, d)
    assert ids_per_frame[0] == ids_per_frame[1]  # instance ids stable across frames
