"""Renders the before/after pictures of issue #28 (docs/realism/) with whichever mmusv is on the path.

Usage: ``python3 scripts/realism_pictures.py --out DIR --label before|after [--only VIEW ...]``

Every view is a small scenario dict built here and rendered through APIs that exist both before issue #28
(commit 66e5052) and after it: :class:`mmusv.Simulation`, ``Simulation.capture``, :func:`mmusv.run` and
:func:`mmusv.preview.write_preview`. So the same script, run once with the old package on ``PYTHONPATH`` and once
with the new one, draws the same frames from the same poses. Each view is written as ``DIR/<view>_<label>.png``:

* ``port_entry_preview``: the ``mmusv preview`` sheet of ``port_entry`` frame 10 (an 11-frame run);
* ``container_150m``: a 300 m container ship under way, its centre 150 m from the camera;
* ``tug_30m``: a 32 m tug under way, its centre 30 m from the camera;
* ``ferry_dusk``: a 90 m ro-pax ferry under way at 21:00 (sun 10° below the horizon), 120 m off;
* ``ferry_dusk_zoom``: its mast and bridge enlarged 4× (the lights are a few pixels each);
* ``dusk_series``: the same ferry and view through the hour of dusk (19:45, 20:15, 20:30 above; 20:45, 21:00,
  21:15 below; 480 × 270 each);
* ``night_glitter``: a 90 m ferry under way at midnight, about 130 m off, at ``standard`` and at ``high`` quality
  side by side (its lamps' glitter on the water);
* ``night_hulls``: a 32 m tug and a 16 m pilot boat under way at midnight, 30–35 m off (the lamps' light on
  their hulls);
* ``exposure_settings``: that view at 21:15 through four cameras differing only in their ``exposure`` (the
  default, −1 EV, +1 EV, ISO 25 600; *after* only);
* ``whitecaps_w3``: open water at wave level W3, from 8 m above the sea;
* ``rain``: a 32 m tug 60 m off in rain of 25 mm/h at 12:00, 20:00 and 23:00 (480 × 270 each, side by side): the
  drops near the lens;
* ``wake_chase``: a 35 m patrol boat at 14 m/s, seen from 20 m above a vessel following 100 m behind;
* ``wake_top``: the same boat in its own top view (orthographic, heading up, 0.6 m per pixel);
* ``wake_kelvin``: a 20 m motor yacht at 7 m/s on calm water (W0), from 25 m up, 130 m off its wake;
* ``wake_bend``: a pilot boat at 10 m/s 100 m past a right-angle turn, in a still USV's top view (north up);
* ``lidar_bulk_100m``: the points of the default 64-channel LiDAR and of a dense 128-channel one on a 190 m bulk
  carrier whose centre line is 100 m off, in the ship's frame (side and plan views, coloured by intensity);
* ``lidar_rain``: the default LiDAR's points around a still USV in rain of 10 mm/h (W1, a tug 25 m off), plan
  view 30 m and 6 m about the sensor, the points of class 0 (rain drops, since 2026-12-08) in red.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
from mmusv.bundled import resolve_scenario
from mmusv.preview import write_preview

# The camera vessel: a small USV lying still at the origin, heading east (yaw 0), so a mount's yaw is a world
# bearing (counter-clockwise from east) and its pitch looks down (positive) or up.
_OBSERVER = {"id": "observer", "role": "usv", "asset": "usv_wamv", "rig": "view", "route": [[0.0, 0.0], [10.0, 0.0]]}
_OPEN_SEA = {"type": "open_sea", "seed": 1, "params": {"n_buoys": 0, "islet_probability": 0.0}}


def _camera_rig(
    *, resolution: tuple[int, int], hfov_deg: float, xyz: tuple[float, float, float], yaw_deg: float, pitch_deg: float
) -> dict[str, Any]:
    """A rig with one camera and nothing else; the mount is relative to the vessel origin (body frame)."""
    camera = {
        "name": "view",
        "resolution": list(resolution),
        "hfov_deg": hfov_deg,
        "outputs": ["rgb"],
        "mount": {"xyz": list(xyz), "rpy_deg": [0.0, pitch_deg, yaw_deg]},
    }
    return {"lidar": None, "radar": None, "top_view": None, "cameras": [camera]}


def _scenario(
    name: str, *, rig: dict[str, Any], vessels: list[dict[str, Any]], environment: dict[str, Any], observer: Any = None
) -> dict[str, Any]:
    return {
        "name": name,
        "seed": 28,
        "map": _OPEN_SEA,
        "environment": environment,
        "acquisition": {"frequency_hz": 5, "frames": 1},
        "rigs": {"view": rig},
        "vessels": [observer or _OBSERVER, *vessels],
    }


def _route(x: float, y: float, heading_deg: float, length_m: float = 2000.0) -> list[list[float]]:
    """A straight route starting at ``(x, y)`` (where the vessel is at frame 0) along ``heading_deg``."""
    h = math.radians(heading_deg)
    return [[x, y], [x + length_m * math.cos(h), y + length_m * math.sin(h)]]


def _at(bearing_deg: float, range_m: float) -> tuple[float, float]:
    b = math.radians(bearing_deg)
    return range_m * math.cos(b), range_m * math.sin(b)


def _save_rgb(scenario: dict[str, Any], path: Path) -> None:
    """Captures frame 0 of ``scenario``'s cameras and writes the first USV's camera ``view`` as a PNG."""
    from PIL import Image

    sim = mmusv.Simulation(scenario)
    cap = sim.capture(0, sensors=["cameras"])
    rgb = cap.agents[sim.agents[0].id].cameras["view"].rgb
    assert rgb is not None
    Image.fromarray(np.asarray(rgb)).save(path)


def _times_sheet(
    path: Path,
    name: str,
    *,
    rig: dict[str, Any],
    vessels: list[dict[str, Any]],
    environment: dict[str, Any],
    times: list[str],
) -> None:
    """One scene at several times of day (``environment`` without its ``time_of_day``), 480 × 270 each, three a row
    in the order given, written to ``path``."""
    from PIL import Image

    rows = (len(times) + 2) // 3
    sheet = Image.new("RGB", (min(len(times), 3) * 480, rows * 270))
    with tempfile.TemporaryDirectory(prefix="realism_") as tmp:
        for i, t in enumerate(times):
            one = Path(tmp) / f"{i}.png"
            _save_rgb(_scenario(name, rig=rig, vessels=vessels, environment={"time_of_day": t, **environment}), one)
            with Image.open(one) as im:
                sheet.paste(im, ((i % 3) * 480, (i // 3) * 270))
    sheet.save(path)


# ---------------------------------------------------------------------------------------------------- views


def port_entry_preview(path: Path) -> None:
    """The ``mmusv preview`` sheet of port_entry frame 10."""
    with tempfile.TemporaryDirectory(prefix="realism_") as tmp:
        result = mmusv.run(str(resolve_scenario("port_entry")), out_dir=tmp, frames=11)
        write_preview(result.recording, frame=10, output=path)


def container_150m(path: Path) -> None:
    """A container ship under way (5 m/s), its centre 150 m due east of the camera, 30° off broadside."""
    x, y = _at(0.0, 150.0)
    ship = {"id": "ship", "asset": "container_ship_300m", "speed_mps": 5.0, "route": _route(x, y, 120.0)}
    rig = _camera_rig(resolution=(1024, 512), hfov_deg=100.0, xyz=(0.0, 0.0, 3.0), yaw_deg=15.0, pitch_deg=-8.0)
    env = {"time_of_day": "10:30", "weather": "clear", "wave": "W1"}
    _save_rgb(_scenario("container_150m", rig=rig, vessels=[ship], environment=env), path)


def tug_30m(path: Path) -> None:
    """A tug under way (2 m/s), its centre 30 m from the camera, broadside on."""
    x, y = _at(0.0, 30.0)
    tug = {"id": "tug", "asset": "tug_32m", "speed_mps": 2.0, "route": _route(x, y, 100.0)}
    rig = _camera_rig(resolution=(800, 600), hfov_deg=80.0, xyz=(0.0, 0.0, 3.0), yaw_deg=0.0, pitch_deg=-8.0)
    env = {"time_of_day": "10:30", "weather": "clear", "wave": "W1"}
    _save_rgb(_scenario("tug_30m", rig=rig, vessels=[tug], environment=env), path)


def ferry_dusk(path: Path) -> None:
    """A ro-pax ferry under way at 21:00 on 21 June at 45° N (sun 10° below the horizon, to the north-west:
    nautical twilight), 120 m off towards the afterglow, heading west-south-west so its bow, port side (red
    sidelight) and masthead light face the camera."""
    bearing = 140.0
    x, y = _at(bearing, 120.0)
    ferry = {"id": "ferry", "asset": "ropax_ferry_90m", "speed_mps": 6.0, "route": _route(x, y, 265.0)}
    rig = _camera_rig(resolution=(960, 540), hfov_deg=60.0, xyz=(0.0, 0.0, 3.0), yaw_deg=bearing, pitch_deg=-5.0)
    env = {"time_of_day": "21:00", "weather": "clear", "wave": "W1"}
    _save_rgb(_scenario("ferry_dusk", rig=rig, vessels=[ferry], environment=env), path)


def ferry_dusk_zoom(path: Path) -> None:
    """The mast and bridge of ``ferry_dusk`` (pixels 330..530 × 150..270 of the same render) enlarged 4× without
    smoothing, so the navigation lights (a few pixels each) can be seen."""
    from PIL import Image

    with tempfile.TemporaryDirectory(prefix="realism_") as tmp:
        full = Path(tmp) / "full.png"
        ferry_dusk(full)
        with Image.open(full) as im:
            im.crop((330, 150, 530, 270)).resize((800, 480), Image.Resampling.NEAREST).save(path)


def night_glitter(path: Path) -> None:
    """A ro-pax ferry under way at midnight (21 June, 45° N), about 130 m off with its port side towards a WAM-V's
    bow camera (640 × 480, 90°), at W1: the same view at ``standard`` (left) and ``high`` quality (right). The
    scenario of the sweep that found the glossy reflections' artefact at night (2026-12-04)."""
    from PIL import Image

    halves = []
    for quality in ("standard", "high"):
        camera = {"name": "view", "outputs": ["rgb"], "mount": {"point": "camera_front"}, "quality": quality}
        scenario = {
            "name": "night_glitter",
            "seed": 1,
            "map": {"type": "open_sea", "seed": 2},
            "environment": {"time_of_day": "00:00", "weather": "clear", "wave": "W1"},
            "acquisition": {"frequency_hz": 5, "frames": 1},
            "rigs": {"view": {"lidar": None, "radar": None, "top_view": None, "cameras": [camera]}},
            "vessels": [
                {
                    "id": "usv",
                    "role": "usv",
                    "asset": "usv_wamv",
                    "rig": "view",
                    "speed_mps": 1.5,
                    "route": [[0, 0], [100, 0]],
                },
                {"id": "ferry", "asset": "ropax_ferry_90m", "speed_mps": 6.0, "route": [[120, -60], [120, 200]]},
            ],
        }
        sim = mmusv.Simulation(scenario)
        rgb = sim.capture(0, sensors=["cameras"]).agents["usv"].cameras["view"].rgb
        assert rgb is not None
        halves.append(np.asarray(rgb))
    Image.fromarray(np.concatenate(halves, axis=1)).save(path)


def night_hulls(path: Path) -> None:
    """A tug and a pilot boat under way at midnight (21 June, 45° N), the tug 35 m off on the camera's bow, the
    pilot boat passing close along its port side, seen from 3 m up (960 × 540, 70°), at W1: the hulls lit by the
    lamps (the tug's own and the pilot boat's), not by the night sky alone."""
    x, y = _at(0.0, 35.0)
    tug = {"id": "tug", "asset": "tug_32m", "speed_mps": 2.0, "route": _route(x, y, 150.0)}
    px, py = _at(-12.0, 30.0)
    pilot = {"id": "pilot", "asset": "pilot_boat_16m", "speed_mps": 2.5, "route": _route(px, py, 120.0)}
    rig = _camera_rig(resolution=(960, 540), hfov_deg=70.0, xyz=(0.0, 0.0, 3.0), yaw_deg=-5.0, pitch_deg=-4.0)
    env = {"time_of_day": "00:00", "weather": "clear", "wave": "W1"}
    _save_rgb(_scenario("night_hulls", rig=rig, vessels=[tug, pilot], environment=env), path)


def night_fog(path: Path) -> None:
    """``night_hulls``' tug and pilot boat, and a ferry 300 m off, at midnight in clear air (20 km visibility), in
    haze of 1 km and in fog of 300 m, side by side (640 × 360 each, 70°): the lamps' glow in the air
    (``sensors/shade/lamp_halo.rs``) widening as the visibility falls."""
    from PIL import Image

    x, y = _at(0.0, 35.0)
    tug = {"id": "tug", "asset": "tug_32m", "speed_mps": 2.0, "route": _route(x, y, 150.0)}
    px, py = _at(-12.0, 30.0)
    pilot = {"id": "pilot", "asset": "pilot_boat_16m", "speed_mps": 2.5, "route": _route(px, py, 120.0)}
    fx, fy = _at(20.0, 300.0)
    ferry = {"id": "ferry", "asset": "ropax_ferry_90m", "speed_mps": 6.0, "route": _route(fx, fy, 265.0)}
    rig = _camera_rig(resolution=(640, 360), hfov_deg=70.0, xyz=(0.0, 0.0, 3.0), yaw_deg=-5.0, pitch_deg=-4.0)
    panels = []
    for weather in (
        {"weather": "clear"},
        {"weather": "fog", "visibility_m": 1000.0},
        {"weather": "fog", "visibility_m": 300.0},
    ):
        env = {"time_of_day": "00:00", "wave": "W1", **weather}
        sim = mmusv.Simulation(_scenario("night_fog", rig=rig, vessels=[tug, pilot, ferry], environment=env))
        rgb = sim.capture(0, sensors=["cameras"]).agents[sim.agents[0].id].cameras["view"].rgb
        assert rgb is not None
        panels.append(np.asarray(rgb))
    Image.fromarray(np.concatenate(panels, axis=1)).save(path)


def dusk_series(path: Path) -> None:
    """``ferry_dusk``'s ferry and view at six times through the hour of dusk (19:45, 20:15, 20:30 above; 20:45,
    21:00, 21:15 below), 480 × 270 each, side by side."""

    bearing = 140.0
    x, y = _at(bearing, 120.0)
    ferry = {"id": "ferry", "asset": "ropax_ferry_90m", "speed_mps": 6.0, "route": _route(x, y, 265.0)}
    rig = _camera_rig(resolution=(480, 270), hfov_deg=60.0, xyz=(0.0, 0.0, 3.0), yaw_deg=bearing, pitch_deg=-5.0)
    env = {"weather": "clear", "wave": "W1"}
    times = ["19:45", "20:15", "20:30", "20:45", "21:00", "21:15"]
    _times_sheet(path, "dusk_series", rig=rig, vessels=[ferry], environment=env, times=times)


def exposure_settings(path: Path) -> None:
    """``ferry_dusk``'s ferry and view at 21:15 (below the default camera's floor) through four cameras on the
    same mount that differ only in their ``exposure`` (after issue #28 only: the setting is newer than the *before*
    package): the default automatic exposure (ISO 6 400 at most), −1 EV and +1 EV of compensation, and a camera
    reaching ISO 25 600; 480 × 270 each, in that order left to right, top to bottom."""
    from PIL import Image

    bearing = 140.0
    x, y = _at(bearing, 120.0)
    ferry = {"id": "ferry", "asset": "ropax_ferry_90m", "speed_mps": 6.0, "route": _route(x, y, 265.0)}
    rig = _camera_rig(resolution=(480, 270), hfov_deg=60.0, xyz=(0.0, 0.0, 3.0), yaw_deg=bearing, pitch_deg=-5.0)
    settings = [{}, {"compensation_ev": -1.0}, {"compensation_ev": 1.0}, {"max_iso": 25600.0}]
    rig["cameras"] = [{**rig["cameras"][0], "name": f"view{i}", "exposure": e} for i, e in enumerate(settings)]
    env = {"time_of_day": "21:15", "weather": "clear", "wave": "W1"}
    sim = mmusv.Simulation(_scenario("exposure_settings", rig=rig, vessels=[ferry], environment=env))
    cams = sim.capture(0, sensors=["cameras"]).agents[sim.agents[0].id].cameras
    sheet = Image.new("RGB", (2 * 480, 2 * 270))
    for i in range(len(settings)):
        rgb = cams[f"view{i}"].rgb
        assert rgb is not None
        sheet.paste(Image.fromarray(np.asarray(rgb)), ((i % 2) * 480, (i // 2) * 270))
    sheet.save(path)


def whitecaps_w3(path: Path) -> None:
    """Open water at W3 (clear, 11:00), looking north-west (down-sun) from 8 m above the sea."""
    rig = _camera_rig(resolution=(960, 540), hfov_deg=90.0, xyz=(0.0, 0.0, 8.0), yaw_deg=120.0, pitch_deg=8.0)
    env = {"time_of_day": "11:00", "weather": "clear", "wave": "W3"}
    buoy = {"id": "far", "asset": "fishing_boat_12m", "speed_mps": 0.0, "route": _route(*_at(125.0, 220.0), 0.0)}
    _save_rgb(_scenario("whitecaps_w3", rig=rig, vessels=[buoy], environment=env), path)


def rain(path: Path) -> None:
    """A tug under way (2 m/s), 60 m off, in heavy rain (25 mm/h, the visibility the drops leave) at 12:00, 20:00
    and 23:00 on 21 June at 45° N, from 3 m above the sea: 480 × 270 each, side by side."""

    bearing = 100.0
    tug = {"id": "tug", "asset": "tug_32m", "speed_mps": 2.0, "route": _route(*_at(bearing, 60.0), 180.0)}
    rig = _camera_rig(resolution=(480, 270), hfov_deg=70.0, xyz=(0.0, 0.0, 3.0), yaw_deg=bearing, pitch_deg=-4.0)
    env = {"weather": "rain", "rain_mm_per_h": 25.0, "wave": "W1"}
    _times_sheet(path, "rain", rig=rig, vessels=[tug], environment=env, times=["12:00", "20:00", "23:00"])


_FAST = {"id": "fast", "asset": "patrol_boat_35m", "speed_mps": 14.0, "route": _route(0.0, 0.0, 90.0, 4000.0)}


def wake_chase(path: Path) -> None:
    """A patrol boat at 14 m/s heading north, from 20 m above a vessel 100 m behind it and 15 m to the side,
    going the same speed."""
    chase = {**_OBSERVER, "speed_mps": 14.0, "route": _route(-15.0, -100.0, 90.0, 4000.0)}
    yaw = math.degrees(math.atan2(15.0, 100.0))  # body frame: heading north, the boat 8.5° to the right
    rig = _camera_rig(resolution=(960, 540), hfov_deg=70.0, xyz=(0.0, 0.0, 20.0), yaw_deg=-yaw, pitch_deg=16.0)
    env = {"time_of_day": "12:00", "weather": "clear", "wave": "W1"}
    _save_rgb(_scenario("wake_chase", rig=rig, vessels=[_FAST], environment=env, observer=chase), path)


def wake_top(path: Path) -> None:
    """The patrol boat's own top view: 120 m up, heading up, 0.6 m per pixel, 640 × 640 (384 m square)."""
    from PIL import Image

    rig = {
        "lidar": None,
        "radar": None,
        "cameras": [],
        "top_view": {"resolution": [640, 640], "metres_per_pixel": 0.6, "outputs": ["rgb"]},
    }
    boat = {**_FAST, "role": "usv", "rig": "view"}
    env = {"time_of_day": "12:00", "weather": "clear", "wave": "W1"}
    sc = {**_scenario("wake_top", rig=rig, vessels=[], environment=env, observer=boat)}
    sim = mmusv.Simulation(sc)
    top = sim.capture(0, sensors=["top_view"]).agents["fast"].top_view
    assert top is not None and top.rgb is not None
    Image.fromarray(np.asarray(top.rgb)).save(path)


def wake_kelvin(path: Path) -> None:
    """A 20 m motor yacht at 7 m/s (Froude number 0.5) heading north on calm water (W0), 12:00, clear: the camera
    25 m above a still USV 120 m west of the yacht's track and 150 m south of it, looking at the wake 100 m behind
    the yacht."""
    yacht = {"id": "yacht", "asset": "motor_yacht_20m", "speed_mps": 7.0, "route": _route(0.0, 0.0, 90.0, 2000.0)}
    observer = {**_OBSERVER, "route": [[-120.0, -150.0], [-110.0, -150.0]]}
    target = (0.0, -70.0)
    dx, dy = target[0] + 120.0, target[1] + 150.0
    yaw = math.degrees(math.atan2(dy, dx))
    pitch = math.degrees(math.atan2(25.0, math.hypot(dx, dy)))
    rig = _camera_rig(resolution=(960, 540), hfov_deg=60.0, xyz=(0.0, 0.0, 25.0), yaw_deg=yaw, pitch_deg=pitch)
    env = {"time_of_day": "12:00", "weather": "clear", "wave": "W0"}
    _save_rgb(_scenario("wake_kelvin", rig=rig, vessels=[yacht], environment=env, observer=observer), path)


def wake_bend(path: Path) -> None:
    """A pilot boat at 10 m/s that went east, then turned north (a route with a right-angle corner, which the
    route's spline rounds), 100 m past the corner: the top view (north up, 0.5 m per pixel, 800 × 800, 400 m square)
    of a USV lying still 60 m west and 60 m south of the boat's corner, at 12:00, clear, W1."""
    from PIL import Image

    rig = {
        "lidar": None,
        "radar": None,
        "cameras": [],
        "top_view": {"resolution": [800, 800], "metres_per_pixel": 0.5, "orientation": "north_up", "outputs": ["rgb"]},
    }
    observer = {**_OBSERVER, "speed_mps": 0.1, "route": [[-60.0, -160.0], [-60.0, -150.0]]}
    boat = {"id": "pilot", "role": "target", "asset": "pilot_boat_16m", "speed_mps": 10.0,
            "route": [[-300.0, -100.0], [0.0, -100.0], [0.0, 400.0]]}  # fmt: skip
    env = {"time_of_day": "12:00", "weather": "clear", "wave": "W1"}
    sc = _scenario("wake_bend", rig=rig, vessels=[boat], environment=env, observer=observer)
    sc["acquisition"] = {"frequency_hz": 5, "frames": 201}
    sim = mmusv.Simulation(sc)
    top = sim.capture(200, sensors=["top_view"]).agents["observer"].top_view
    assert top is not None and top.rgb is not None
    Image.fromarray(np.asarray(top.rgb)).save(path)


def top_views(path: Path) -> None:
    """The observer's default top view (512 × 512 at 0.5 m, heading up) over open water at W1 and W3, 11:00, side
    by side."""
    from PIL import Image

    rig = {"lidar": None, "radar": None, "cameras": [], "top_view": {"outputs": ["rgb"]}}
    sheet = Image.new("RGB", (1034, 512), "white")
    for i, wave in enumerate(("W1", "W3")):
        env = {"time_of_day": "11:00", "weather": "clear", "wave": wave}
        sim = mmusv.Simulation(_scenario("top_views", rig=rig, vessels=[], environment=env))
        top = sim.capture(0, sensors=["top_view"]).agents["observer"].top_view
        assert top is not None and top.rgb is not None
        sheet.paste(Image.fromarray(np.asarray(top.rgb)), (i * 522, 0))
    sheet.save(path)


_DENSE_LIDAR = {
    "channels": 128,
    "vertical_fov_deg": [-5.0, 20.0],
    "points_per_second": 128 * 3600 * 5.0,
    "rotation_hz": 5.0,
}
"""A dense scan (128 channels over -5..20°, 0.1° between columns) that resolves the hull's detail at 100 m."""


def _ship_points(lidar: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, Any]:
    """The LiDAR points on a bulk carrier lying still, its centre line 100 m north of the LiDAR, heading east:
    ``(N, 3)`` float64 points in the ship's body frame (metres), their ``(N,)`` intensities and the ship's
    :class:`~mmusv.simulation.VesselInfo`."""
    ship = {"id": "bulk", "asset": "bulk_carrier_190m", "speed_mps": 0.0, "route": _route(0.0, 100.0, 0.0)}
    rig = {"lidar": lidar, "radar": None, "cameras": [], "top_view": None}
    env = {"time_of_day": "12:00", "weather": "clear", "wave": "W0"}
    sim = mmusv.Simulation(_scenario("lidar_bulk_100m", rig=rig, vessels=[ship], environment=env))
    cap = sim.capture(0, sensors=["lidar"])
    ac = cap.agents["observer"]
    assert ac.lidar is not None and ac.lidar_pose is not None
    k = [v.id for v in sim.vessels].index("bulk")
    info = sim.vessels[k]
    on_ship = ac.lidar.instance == info.instance_id
    world = ac.lidar.xyz[on_ship].astype(np.float64) @ ac.lidar_pose[:3, :3].T + ac.lidar_pose[:3, 3]
    ship_mat = cap.world.matrices[k]
    return (world - ship_mat[:3, 3]) @ ship_mat[:3, :3], ac.lidar.intensity[on_ship], info


def lidar_bulk_100m(path: Path, label: str) -> None:
    """Side (x, z) and plan (x, y) views, in the ship's frame and coloured by intensity, of the points of two
    LiDARs on the USV on a bulk carrier whose centre line is 100 m off: the default (64 channels over -25..15°,
    131,072 points/s at 5 Hz: 0.88° between columns) and :data:`_DENSE_LIDAR`."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scans = [("default 64-channel LiDAR", {}), ("dense 128-channel LiDAR, 0.1° columns", _DENSE_LIDAR)]
    data = [(title, *_ship_points(cfg)) for title, cfg in scans]
    info = data[0][3]
    size = info.box_size
    fig, axes = plt.subplots(
        4, 1, figsize=(10, 11), layout="constrained", gridspec_kw={"height_ratios": [size[2], size[1]] * 2}
    )
    half = size / 2 + 4.0
    sc = None
    for row, (title, body, intensity, _) in enumerate(data):
        side, plan = axes[2 * row], axes[2 * row + 1]
        dot = 2.0 if row == 0 else 0.4
        for ax, j, name in ((side, 2, "z (up)"), (plan, 1, "y (port)")):
            sc = ax.scatter(body[:, 0], body[:, j], c=intensity, s=dot, cmap="viridis", vmin=0.0, vmax=0.3, lw=0)
            ax.set_xlim(info.box_center_body[0] - half[0], info.box_center_body[0] + half[0])
            ax.set_ylim(info.box_center_body[j] - half[j], info.box_center_body[j] + half[j])
            ax.set_aspect("equal")
            ax.set_ylabel(f"{name}, m")
            ax.grid(alpha=0.3)
        side.set_title(f"{label}: {title}, {len(body):,} points on the ship (side, then plan)", fontsize=10)
    axes[-1].set_xlabel("x (bow →), m, ship frame")
    assert sc is not None
    fig.colorbar(sc, ax=list(axes), label="intensity", shrink=0.6)
    fig.suptitle("bulk_carrier_190m, centre line 100 m from the LiDAR, starboard side towards it", fontsize=11)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def lidar_rain(path: Path, label: str) -> None:
    """Plan views (LiDAR frame, 30 m and 6 m about the sensor) of the default LiDAR's points on a still USV in rain
    of 10 mm/h (W1, 12:00, a 32 m tug 25 m off), frame 0; class 0 (a drop: nothing else returns with it) red, the
    water blue, the rest grey."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tug = {"id": "tug", "asset": "tug_32m", "speed_mps": 0.0, "route": _route(*_at(60.0, 25.0), 150.0)}
    rig = {"lidar": {}, "radar": None, "cameras": [], "top_view": None}
    env = {"time_of_day": "12:00", "weather": "rain", "rain_mm_per_h": 10.0, "wave": "W1"}
    sim = mmusv.Simulation(_scenario("lidar_rain", rig=rig, vessels=[tug], environment=env))
    points = sim.capture(0, sensors=["lidar"]).agents["observer"].lidar
    assert points is not None
    xyz, cls = np.asarray(points.xyz, dtype=np.float64), np.asarray(points.semantic_class)
    drop = cls == 0
    fig, axes = plt.subplots(1, 2, figsize=(12, 6), layout="constrained")
    for ax, half, dot in ((axes[0], 30.0, 1.5), (axes[1], 6.0, 6.0)):
        for sel, colour, name in ((cls == 1, "tab:blue", "water"), (~drop & (cls != 1), "0.45", "other")):
            ax.scatter(xyz[sel, 0], xyz[sel, 1], s=dot, c=colour, lw=0, label=f"{name} ({int(sel.sum()):,})")
        ax.scatter(xyz[drop, 0], xyz[drop, 1], s=dot, c="red", lw=0, label=f"class 0: rain drops ({int(drop.sum()):,})")
        ax.set_xlim(-half, half)
        ax.set_ylim(-half, half)
        ax.set_aspect("equal")
        ax.set_xlabel("x (bow), m")
        ax.set_ylabel("y (port), m")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper left", fontsize=8, markerscale=4)
    fig.suptitle(
        f"{label}: default 64-channel LiDAR, rain 10 mm/h, W1; {len(points):,} points, "
        f"{int(drop.sum()):,} of class 0 (left 30 m, right 6 m about the sensor)",
        fontsize=10,
    )
    fig.savefig(path, dpi=90)
    plt.close(fig)


VIEWS: dict[str, Callable[[Path], None]] = {
    "port_entry_preview": port_entry_preview,
    "container_150m": container_150m,
    "tug_30m": tug_30m,
    "ferry_dusk": ferry_dusk,
    "ferry_dusk_zoom": ferry_dusk_zoom,
    "dusk_series": dusk_series,
    "night_glitter": night_glitter,
    "night_hulls": night_hulls,
    "night_fog": night_fog,
    "exposure_settings": exposure_settings,
    "whitecaps_w3": whitecaps_w3,
    "rain": rain,
    "wake_chase": wake_chase,
    "wake_top": wake_top,
    "wake_kelvin": wake_kelvin,
    "wake_bend": wake_bend,
    "top_views": top_views,
}


LABELLED: dict[str, Callable[[Path, str], None]] = {"lidar_bulk_100m": lidar_bulk_100m, "lidar_rain": lidar_rain}
"""The views that write their label into the picture."""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, type=Path, help="output folder")
    parser.add_argument("--label", required=True, choices=["before", "after"], help="suffix of the file names")
    parser.add_argument("--only", nargs="*", choices=[*VIEWS, *LABELLED], help="render only these views")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    print(f"mmusv from {Path(mmusv.__file__).parent}", file=sys.stderr)
    for name in [*VIEWS, *LABELLED]:
        if args.only and name not in args.only:
            continue
        path = args.out / f"{name}_{args.label}.png"
        t0 = time.perf_counter()
        if name in LABELLED:
            LABELLED[name](path, args.label)
        else:
            VIEWS[name](path)
        print(f"{path}  {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
