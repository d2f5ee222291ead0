"""The environment swept as a user writes it: times of day, weathers, visibilities, rain and waves on each bundled map
type (island, open sea, port), recorded end to end and read back with the project's reader, Polars and the ``mcap``
package.

What is checked here, beside the field-level checks of ``tests/world/test_environment.py`` and the physics of
``tests/test_physics_recheck*.py``:

* the labels are geometry (``docs/recording.md``: depth, semantic and instance images, 3D/BEV/2D boxes, the world
  state): the same seed under a clear noon and a foggy night, rainy dusk or overcast southern morning gives the same
  bytes, but for the LiDAR's own ``lidar_points`` count, which the weather thins;
* each sensor reads only what ``mmusv.sensors.env`` says it uses: the LiDAR the visibility (fog, rain's drops) and
  the waves; the radar rain and waves; the sun (time of day, latitude, day of year) reaches the cameras alone;
* the pictures through the whole pipeline (render, exposure, tone curve, PNG): no NaN in the depth, +inf exactly
  on the sky, a day view that is not black, a night view that stays dark, a fog whose contrast falls with distance
  at its Koschmieder rate and is under the WMO's 0.05 beyond the visibility, and an automatic exposure that meters
  an overcast sky's light away where a fixed ``ev100`` follows it;
* the recording's metadata say the environment as given.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mmusv.export.contrast import relative_luminance
from mmusv.recording import decode_image, decode_point_cloud, read_messages
from mmusv.recording.tables import read_table

SKY_INSTANCE = 65535
"""The instance id of the sky (``docs/recording.md``)."""

# Each bundled map type with a USV and a target ahead of it on its water (the island's near ``island_occlusion``'s
# usv_1, the port's near ``port_entry``'s usv_3).
MAPS: dict[str, tuple[dict[str, Any], list[list[float]], list[list[float]]]] = {
    "open_sea": ({"type": "open_sea", "seed": 0}, [[0, 0], [50, 0]], [[40, 15], [90, 15]]),
    "island": ({"type": "island", "seed": 4}, [[470, -320], [560, -320]], [[530, -335], [620, -340]]),
    "port": ({"type": "port", "seed": 3}, [[-190, -340], [-100, -350]], [[-130, -330], [-40, -335]]),
}

CLEAR_NOON = {"time_of_day": "12:00", "weather": "clear", "wave": "W1"}
OTHER_SKIES = {
    "fog_night": {"time_of_day": "00:00", "weather": "fog", "visibility_m": 120, "wave": "W1"},
    "rain_dusk": {"time_of_day": "20:30", "weather": "rain", "rain_mm_per_h": 25, "visibility_m": 1000, "wave": "W1"},
    "overcast_south": {
        "time_of_day": "09:40",
        "weather": "overcast",
        "latitude_deg": -33.9,
        "day_of_year": 200,
        "wave": "W1",
    },
}


def small_rig() -> dict[str, Any]:
    """A rig with every sensor, each small: a 64 x 48 bow camera, a 32 x 32 top view, an 8-channel LiDAR and a
    radar of 512 bearings."""
    return {
        "cameras": [
            {"name": "bow", "resolution": [64, 48], "hfov_deg": 90, "quality": "draft", "mount": {"xyz": [2.6, 0, 1.5]}}
        ],
        "top_view": {"resolution": [32, 32], "quality": "draft"},
        "lidar": {"channels": 8, "points_per_second": 20480},
        "radar": {"azimuth_bins": 512, "ppi_size_px": 64},
    }


def sweep_scenario(map_type: str, env: dict[str, Any], *, frames: int = 2) -> dict[str, Any]:
    map_cfg, usv_route, target_route = MAPS[map_type]
    return {
        "name": "sweep",
        "seed": 7,
        "map": map_cfg,
        "environment": env,
        "acquisition": {"frames": frames},
        "rigs": {"r": small_rig()},
        "vessels": [
            {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": usv_route},
            {"id": "t", "asset": "fishing_boat_12m", "speed_mps": 3, "route": target_route},
        ],
    }


def record(scenario: dict[str, Any], folder: Path) -> Path:
    """Runs ``scenario`` into ``folder``; returns the run folder."""
    mmusv.run(copy.deepcopy(scenario), out_dir=folder)
    return folder


def messages(run: Path) -> dict[str, list[bytes]]:
    """Every topic's messages, serialised, in order."""
    out: dict[str, list[bytes]] = {}
    for topic, _, msg in read_messages(run / "sweep.mcap"):
        out.setdefault(topic, []).append(msg.SerializeToString(deterministic=True))
    return out


def decoded(run: Path, suffix: str) -> list[Any]:
    """The decoded messages of the one topic ending in ``suffix``, in order."""
    out = []
    topics = set()
    for topic, _, msg in read_messages(run / "sweep.mcap"):
        if topic.endswith(suffix):
            topics.add(topic)
            out.append(msg)
    assert len(topics) == 1, (suffix, topics)
    return out


def annotations_without_lidar_points(run: Path) -> list[bytes]:
    out = []
    for msg in decoded(run, "/annotations"):
        for box in msg.boxes_lidar:
            box.lidar_points = 0
        out.append(msg.SerializeToString(deterministic=True))
    return out


def lidar_points_total(run: Path) -> int:
    return sum(box.lidar_points for msg in decoded(run, "/annotations") for box in msg.boxes_lidar)


GEOMETRY_SUFFIXES = ("/depth", "/semantic", "/instance", "/world/state", "/tf", "/boxes", "/calibration")
"""The topics that are geometry whatever the weather: every image of depth, classes and instances (bow camera and
top view), the world state, the transforms and the boxes drawn for Foxglove."""


@pytest.fixture(scope="module")
def sky_runs(tmp_path_factory: pytest.TempPathFactory) -> dict[tuple[str, str], Path]:
    """``(map type, sky) -> run folder``: each map type under the clear noon and each of :data:`OTHER_SKIES`."""
    root = tmp_path_factory.mktemp("env_sweep")
    runs = {}
    for map_type in MAPS:
        for sky, env in {"clear_noon": CLEAR_NOON, **OTHER_SKIES}.items():
            runs[map_type, sky] = record(sweep_scenario(map_type, env), root / f"{map_type}_{sky}")
    return runs


@pytest.mark.parametrize("sky", sorted(OTHER_SKIES))
@pytest.mark.parametrize("map_type", sorted(MAPS))
def test_labels_do_not_depend_on_the_sky(sky_runs: dict[tuple[str, str], Path], map_type: str, sky: str) -> None:
    """The same seed under a clear noon and under ``sky``: every geometric output has the same bytes (depth,
    semantic and instance images of the camera and the top view, world state, transforms, boxes; the 3D, BEV and
    2D boxes with their visible and box pixels, wave occlusion and range), in the MCAP and in the Parquet tables;
    only ``lidar_points`` differs, and the weather did reach the sensors (the RGB differs; the fog and the rain thin
    the LiDAR's returns on the target)."""
    clear, other = sky_runs[map_type, "clear_noon"], sky_runs[map_type, sky]
    a, b = messages(clear), messages(other)
    assert a.keys() == b.keys()
    geometry = [t for t in a if t.endswith(GEOMETRY_SUFFIXES)]
    # 3 camera images, 2 top-view images, state, tf, 3D boxes, the camera's 2D boxes and calibration
    assert len(geometry) == 10, geometry
    for topic in geometry:
        assert a[topic] == b[topic], topic
    assert annotations_without_lidar_points(clear) == annotations_without_lidar_points(other)
    rgb = [t for t in a if t.endswith("/rgb")]
    assert len(rgb) == 2 and all(a[t] != b[t] for t in rgb)
    for table in ("world_state", "boxes_2d", "boxes_3d"):
        ta, tb = (read_table(run / "tables", table).rows for run in (clear, other))
        assert ta.height > 0 and ta.columns == tb.columns, table
        cols = [c for c in ta.columns if c != "lidar_points"]
        assert ta.select(cols).equals(tb.select(cols)), table
        if table == "boxes_3d":
            assert ta["lidar_points"].sum() > 0
    if sky != "overcast_south":  # a 10 km overcast hardly dims 905 nm over tens of metres
        assert lidar_points_total(other) < lidar_points_total(clear), sky


def cloud_bytes(run: Path, suffix: str) -> list[bytes]:
    return [bytes(msg.data) for msg in decoded(run, suffix)]


def test_each_sensor_reads_only_its_documented_environment(
    sky_runs: dict[tuple[str, str], Path], tmp_path: Path
) -> None:
    """``mmusv.sensors.env``: "the LiDAR uses fog, rain and waves; the radar rain and waves"; the sun is the
    cameras'. On the open sea: midnight, a southern winter morning and a rain sky without rain (0 mm/h, the clear
    day's 20 km visibility: the weather's name and its cloud cover alone) leave the LiDAR and the radar byte for
    byte as at noon, while the pictures change; fog (no rain) leaves the radar as it was and cuts the LiDAR's returns
    beyond 30 m (half the visibility) to the two-way transmission's few per cent; rain adds radar returns (its
    clutter)."""
    env_noon = dict(CLEAR_NOON)
    runs = {
        "noon": sky_runs["open_sea", "clear_noon"],
        "midnight": record(sweep_scenario("open_sea", {**env_noon, "time_of_day": "00:00"}), tmp_path / "midnight"),
        "south": record(
            sweep_scenario("open_sea", {**env_noon, "latitude_deg": -60, "day_of_year": 172, "time_of_day": "09:00"}),
            tmp_path / "south",
        ),
        "fog": record(sweep_scenario("open_sea", {**env_noon, "weather": "fog", "visibility_m": 60}), tmp_path / "fog"),
        # the rain's sky without its drops, at the clear day's visibility: the weather's name alone
        "dry_rain": record(
            sweep_scenario("open_sea", {**env_noon, "weather": "rain", "rain_mm_per_h": 0, "visibility_m": 20000}),
            tmp_path / "dry_rain",
        ),
    }
    lidar = {k: cloud_bytes(v, "/lidar") for k, v in runs.items()}
    radar = {k: cloud_bytes(v, "/radar/returns") for k, v in runs.items()}
    rgb = {k: cloud_bytes(v, "/camera/bow/rgb") for k, v in runs.items()}
    for k in ("midnight", "south", "dry_rain"):
        assert lidar[k] == lidar["noon"] and radar[k] == radar["noon"], k
        assert rgb[k] != rgb["noon"], k
    assert radar["fog"] == radar["noon"]
    assert lidar["fog"] != lidar["noon"]
    far = {}
    for k in ("noon", "fog"):
        far[k] = 0
        for msg in decoded(runs[k], "/lidar"):
            cloud = decode_point_cloud(msg)
            r = np.sqrt(cloud["x"].astype(float) ** 2 + cloud["y"] ** 2 + cloud["z"] ** 2)
            far[k] += int(np.sum(r > 30.0))
    # A return is kept with the two-way transmission e^(-2 r 3/V), under 0.05 beyond 30 m in a 60 m fog.
    assert far["noon"] >= 20 and far["fog"] <= 0.15 * far["noon"], far
    rain = sky_runs["open_sea", "rain_dusk"]
    n_rain = sum(len(decode_point_cloud(m)["x"]) for m in decoded(rain, "/radar/returns"))
    n_noon = sum(len(decode_point_cloud(m)["x"]) for m in decoded(runs["noon"], "/radar/returns"))
    assert n_rain > n_noon


@pytest.mark.parametrize("map_type", sorted(MAPS))
def test_pictures_are_sane_by_day_and_night(sky_runs: dict[tuple[str, str], Path], map_type: str) -> None:
    """Every sky on every map: the depth has no NaN and is +inf exactly where the instance image is the sky
    (``docs/recording.md``), finite and positive elsewhere; a day picture (clear noon, overcast morning) is neither
    black nor white; at night (the fog at midnight) the view stays dark (docs/realism: "at night the views stay
    dark") with no more than a few lamp pixels bright."""
    for sky in ("clear_noon", *OTHER_SKIES):
        run = sky_runs[map_type, sky]
        for depth_msg, inst_msg in zip(decoded(run, "/bow/depth"), decoded(run, "/bow/instance"), strict=True):
            depth, inst = decode_image(depth_msg), decode_image(inst_msg)
            assert not np.isnan(depth).any(), sky
            assert np.array_equal(np.isposinf(depth), inst == SKY_INSTANCE), sky
            assert (depth[inst != SKY_INSTANCE] > 0).all() and np.isfinite(depth[inst != SKY_INSTANCE]).all()
        for suffix in ("/bow/rgb", "/top_view/rgb"):
            for msg in decoded(run, suffix):
                rgb = decode_image(msg).astype(float)
                mean, bright = rgb.mean(), float(np.mean(rgb.max(axis=2) >= 250))
                if sky in ("clear_noon", "overcast_south"):
                    assert 40 < mean < 215 and bright < 0.05, (sky, suffix, mean, bright)
                elif sky == "fog_night":
                    assert mean < 5 and bright < 0.01, (sky, suffix, mean, bright)


def fog_view_scenario(env: dict[str, Any]) -> dict[str, Any]:
    """Flat water (the paper's motion, W0) seen by a 160 x 120 bow camera with a 20 deg field of view, pitched 4 deg
    down: water from 7 m to the horizon, each pixel's range in the depth image."""
    cam = {
        "name": "bow",
        "resolution": [160, 120],
        "hfov_deg": 20,
        "quality": "draft",
        "outputs": ["rgb", "depth", "semantic"],
        "mount": {"xyz": [2.6, 0, 1.5], "rpy_deg": [0, 4, 0]},
    }
    return {
        "name": "sweep",
        "seed": 2,
        "map": {"type": "open_sea", "seed": 0},
        "environment": {"motion": "paper", "wave": "W0", "time_of_day": "12:00", **env},
        "acquisition": {"frames": 1},
        "rigs": {"r": {"preset": "lidar_only", "lidar": None, "cameras": [cam]}},
        "vessels": [
            {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": [[0, 0], [50, 0]]},
            {"id": "t", "asset": "fishing_boat_12m", "speed_mps": 3, "route": [[0, 400], [60, 400]]},
        ],
    }


def water_contrast(run: Path) -> tuple[np.ndarray, np.ndarray]:
    """``(range, contrast)`` of each water pixel: its Weber contrast against the mean relative luminance of the
    sky's pixels (the recorded 8-bit sRGB, linearised), and its range from the camera (the depth over the cosine
    of the pixel's angle off the axis)."""
    rgb = decode_image(decoded(run, "/bow/rgb")[0])
    depth = decode_image(decoded(run, "/bow/depth")[0]).astype(float)
    sem = decode_image(decoded(run, "/bow/semantic")[0])
    lum = relative_luminance(rgb)
    h, w = depth.shape
    f = (w / 2) / np.tan(np.radians(10.0))
    v, u = np.mgrid[0:h, 0:w]
    off_axis = np.sqrt(((u + 0.5 - w / 2) / f) ** 2 + ((v + 0.5 - h / 2) / f) ** 2)
    rng = depth * np.sqrt(1 + off_axis**2)
    sky = sem == 0
    water = sem == 1
    assert sky.sum() > 500 and water.sum() > 5000
    l_sky = lum[sky].mean()
    return rng[water], np.abs(lum[water] - l_sky) / l_sky


def test_fog_contrast_falls_with_range_at_the_koschmieder_rate(tmp_path: Path) -> None:
    """The recorded picture of flat water in fog of visibility V, pixel by pixel against its range from the depth
    image: its contrast against the fog's sky falls as ``e^{-sigma r}``, sigma = 3 / V (``docs/exports.md``:
    "in fog a dark vessel fades below 0.05 at about the scenario's visibility_m"), the rate of the clear day's own
    (slow) fall taken out: a least-squares slope of ln(contrast) between 1.0 and 1.35 sigma (the tone curve
    steepens it a little; ``docs/exports.md`` measured 1.07). Beyond V no water pixel stands out by 0.05; in the
    clear the same pixels keep a median of more than 0.3. Two visibilities, so the rate scales with 1/V."""
    clear_r, clear_c = water_contrast(record(fog_view_scenario({"weather": "clear"}), tmp_path / "clear"))
    near = (clear_r > 8) & (clear_r < 60)
    clear_slope = np.polyfit(clear_r[near], np.log(clear_c[near]), 1)[0]
    for vis in (120.0, 240.0):
        r, c = water_contrast(record(fog_view_scenario({"weather": "fog", "visibility_m": vis}), tmp_path / f"{vis}"))
        assert np.array_equal(r, clear_r)  # the same pixels: geometry
        beyond = r > vis
        assert beyond.sum() > 100 and c[beyond].max() < 0.05, vis
        assert np.median(clear_c[beyond]) > 0.3
        sigma = 3.0 / vis
        fit = (r > 8) & (r < 0.6 * vis) & (c > 0.03)
        assert fit.sum() > 500
        slope = np.polyfit(r[fit], np.log(c[fit]), 1)[0]
        rate = -(slope - clear_slope) / sigma
        assert 1.0 <= rate <= 1.35, (vis, rate, slope, clear_slope)


TIMES = ("08:00", "12:00", "16:00")


def test_automatic_exposure_meters_the_overcast_light_away(tmp_path: Path) -> None:
    """README: the exposure is automatic by default (an incident-light meter), or fixed at ``ev100`` "so that
    brightness follows the light". Under a fully overcast sky (the fog: cloud cover 1, no sun beam) every radiance
    scales with the sky's own level, so at 08:00, 12:00 and 16:00 the metered pictures are the same (to one 8-bit
    level) while a fixed EV100 of 12 makes 08:00 darker than noon, and the afternoon, at the morning's sun
    elevation, as dark as the morning."""
    pictures = {}
    for ev in (None, 12.0):
        for t in TIMES:
            scn = fog_view_scenario({"weather": "fog", "visibility_m": 400, "time_of_day": t})
            if ev is not None:
                scn["rigs"]["r"]["cameras"][0]["exposure"] = {"ev100": ev}
            run = record(scn, tmp_path / f"{ev}_{t.replace(':', '')}")
            pictures[ev, t] = decode_image(decoded(run, "/bow/rgb")[0]).astype(float)
    for t in ("08:00", "16:00"):
        metered = np.abs(pictures[None, t] - pictures[None, "12:00"])
        assert metered.max() <= 1 and metered.mean() < 0.01, t  # the same picture but for a rounding
    fixed = {t: float(relative_luminance(pictures[12.0, t].astype(np.uint8)).mean()) for t in TIMES}
    assert fixed["08:00"] < 0.8 * fixed["12:00"], fixed
    assert fixed["16:00"] == pytest.approx(fixed["08:00"], rel=1e-3), fixed
    assert np.abs(pictures[12.0, "12:00"] - pictures[None, "12:00"]).mean() > 3


def test_recording_metadata_say_the_environment_as_given(tmp_path: Path) -> None:
    """The environment as written (``wave`` in lower case, a visibility and rain given as numbers) is what the
    recording's ``scenario`` metadata hold, read with the ``mcap`` package and with :func:`mmusv.recording.read_info`,
    with the defaults the user left out filled in."""
    env = {
        "time_of_day": "05:45",
        "weather": "rain",
        "visibility_m": 900,
        "rain_mm_per_h": 12.5,
        "wave": "w2",
        "latitude_deg": 61.5,
        "day_of_year": 300,
    }
    scn = sweep_scenario("open_sea", env, frames=1)
    scn["rigs"] = {"r": {"preset": "lidar_only", "lidar": {"channels": 8, "points_per_second": 20480}}}
    run = record(scn, tmp_path / "run")
    expected = {**env, "wave": "W2", "visibility_m": 900.0, "sea": None, "motion": "physical"}
    with open(run / "sweep.mcap", "rb") as fh:
        meta = {m.name: m.metadata for m in make_reader(fh).iter_metadata()}
    assert yaml.safe_load(meta["scenario"]["yaml"])["environment"] == expected
    from mmusv.recording import read_info

    assert read_info(run / "sweep.mcap").scenario["environment"] == expected
    assert yaml.safe_load((run / "scenario.yaml").read_text(encoding="utf-8"))["environment"] == expected


@pytest.mark.parametrize(
    ("wave", "hint"),
    [
        (None, "leave `wave` out for W0"),
        (["W1", "W2"], "a list of choices belongs in a generation spec"),
        ({"state": 3}, "environment.sea"),
        (float("inf"), "0..25 metres"),
        ("1.5", "write the height as a number, wave: 1.5"),
    ],
    ids=["null", "list", "mapping", "inf", "quoted-number"],
)
def test_a_wave_of_the_wrong_kind_says_what_is_allowed(tmp_path: Path, wave: object, hint: str) -> None:
    """``wave: null``, a list (a generation spec's choices), a mapping (a sea state meant for ``environment.sea``)
    and ``.inf`` were two lines of the schema's union ("Input should be a valid string; ... Input should be a valid
    number") that did not say what ``wave`` takes; a quoted height ("1.5") was told that heights in metres are
    allowed. Each is now one message naming the file, ``environment.wave``, the presets and the range in metres, with
    the way out."""
    scn = sweep_scenario("open_sea", {"wave": wave}, frames=1)
    path = tmp_path / "waves.yaml"
    path.write_text(yaml.safe_dump(scn, sort_keys=False), encoding="utf-8")
    with pytest.raises(mmusv.ConfigError) as err:
        mmusv.run(str(path), out_dir=tmp_path / "out")
    msg = str(err.value)
    assert msg.startswith(f"{path}: invalid config environment.wave = "), msg
    assert "0..25" in msg and hint in msg, msg
    assert "W0, W1, W2, W3" in msg or wave == float("inf"), msg  # inf: the heights' range, as for 26
    assert "valid string" not in msg and msg.count("environment.wave") == 1, msg
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "environment",
    [
        {"rain_mm_per_h": [2, 10, 30]},
        {"weather": "clear", "rain_mm_per_h": 8},
        {"weather": ["clear"], "rain_mm_per_h": [0, 5]},
    ],
    ids=["no-weather", "clear", "clear-list"],
)
def test_a_spec_whose_skies_never_rain_refuses_its_rain_rates(tmp_path: Path, environment: dict[str, Any]) -> None:
    """A generation spec drops a rain rate drawn beside a clear sky (``mmusv.generate.sampler``); when no weather it
    draws rains (``weather`` left out, i.e. clear, or only ``clear``) every rate was dropped without a word and the
    whole dataset came out dry. Refused, naming the file and the fields, as a scenario refuses rain under a clear
    sky; rates of 0 alone, or a weather that rains among the choices, are taken."""
    from mmusv.generate.spec import load_spec

    path = tmp_path / "spec.yaml"
    base = {"name": "s", "combinations": [{"family": "crossing"}]}
    path.write_text(yaml.safe_dump({**base, "environment": environment}), encoding="utf-8")
    with pytest.raises(mmusv.ConfigError) as err:
        load_spec(path)
    msg = str(err.value)
    assert str(path) in msg and "environment.rain_mm_per_h" in msg and "weather" in msg, msg
    assert "clear sky does not rain" in msg, msg
    for ok in ({**environment, "weather": ["clear", "fog"]}, {"rain_mm_per_h": [0]}, {"weather": "rain"}):
        path.write_text(yaml.safe_dump({**base, "environment": ok}), encoding="utf-8")
        assert load_spec(path).environment == ok


@pytest.mark.parametrize(
    ("weather", "ev_range"), [("clear", (14.5, 15.5)), ("overcast", (11.5, 13.5))], ids=["full-sun", "overcast"]
)
def test_metered_exposure_at_noon_is_the_documented_ev100(
    tmp_path: Path, weather: str, ev_range: tuple[float, float]
) -> None:
    """``ExposureConfig``'s (and the schema's) own guide: a fixed ``ev100`` is "e.g. 15 for full sun, 12 for an
    overcast day" (the photographers' sunny-16 rule: ISO 100, f/16, 1/125 s is EV 15; overcast 12-13). The
    automatic exposure at noon must land there: its picture lies between those of the fixed EV100s that bracket
    the value (a higher EV100 is a darker picture)."""

    def mean_luminance(ev: float | None, name: str) -> float:
        scn = fog_view_scenario({"weather": weather})
        if ev is not None:
            scn["rigs"]["r"]["cameras"][0]["exposure"] = {"ev100": ev}
        run = record(scn, tmp_path / name)
        return float(relative_luminance(decode_image(decoded(run, "/bow/rgb")[0])).mean())

    lo, hi = ev_range
    brighter, metered, darker = mean_luminance(lo, "lo"), mean_luminance(None, "auto"), mean_luminance(hi, "hi")
    assert brighter > metered > darker, (brighter, metered, darker)


def port_entry_contrasts(tmp_path: Path, name: str, environment: dict[str, Any] | None) -> list[float | None]:
    """The COCO ``contrast`` of every visible 2D box of the bundled ``port_entry``, 2 frames, its rig's four
    cameras at 160 x 120 (the rest as bundled), under ``environment`` (``None``: as bundled)."""
    from mmusv.export.conversion import convert

    doc = yaml.safe_load((Path(__file__).resolve().parents[1] / "scenarios/port_entry.yaml").read_text("utf-8"))
    doc["acquisition"]["frames"] = 2
    cams = [
        {"name": n, "resolution": [160, 120], "mount": {"point": f"camera_{n}"}}
        for n in ("front", "left", "rear", "right")
    ]
    doc["rigs"]["usv_standard"] = {"cameras": cams}
    if environment is not None:
        doc["environment"] = environment
    run = record(doc, tmp_path / name)
    convert(run / "port_entry.mcap", to="coco", out_dir=tmp_path / f"{name}_coco", splits=None)
    coco = json.loads((tmp_path / f"{name}_coco/annotations/instances_all.json").read_text("utf-8"))
    return [a["contrast"] for a in coco["annotations"]]


def test_min_contrast_leaves_out_the_fog_s_boxes_as_documented(tmp_path: Path) -> None:
    """``docs/exports.md``: in the bundled ``port_entry`` (2 frames, four cameras at 160 x 120) ``--min-contrast
    0.05`` leaves out most boxes in a 300 m fog at 16:30 and a few on the bundled clear afternoon; the boxes
    themselves are the same 38 in both (geometry). Measured 2026-12-06: 25 and 2 of 38 (23 and 2 of 36 before the
    physical response remembered its course through the bends: the USVs' cameras roll and pitch otherwise)."""
    clear = port_entry_contrasts(tmp_path, "clear", None)
    fog = port_entry_contrasts(
        tmp_path, "fog", {"time_of_day": "16:30", "weather": "fog", "visibility_m": 300, "wave": "W1"}
    )
    assert len(clear) == len(fog) == 38
    low = {k: sum(1 for c in v if c is not None and c < 0.05) for k, v in (("clear", clear), ("fog", fog))}
    assert 22 <= low["fog"] <= 28 and low["clear"] <= 4, low


def test_a_time_of_day_is_one_time_in_the_config_hash() -> None:
    """``time_of_day`` takes one or two digits for the hour (``"6:30"``, as the schema's pattern says); the scenario
    kept the text as written, so ``"6:30"`` and ``"06:30"``, the same sun and the same recording, had two config
    hashes (``dataset.json``, ``RecordingInfo.config_hash``, the converters' folder names) and two spellings in the
    recording's scenario, where ``wave: " w3 "`` is ``W3`` in both. The time is now written ``HH:MM``."""
    from mmusv.config import load_scenario, scenario_hash

    def scenario(time: str) -> dict[str, Any]:
        return sweep_scenario("open_sea", {"time_of_day": time}, frames=1)

    assert load_scenario(scenario("6:30")).environment.time_of_day == "06:30"
    assert load_scenario(scenario(" 7:05 ")).environment.time_of_day == "07:05"
    assert scenario_hash(scenario("6:30")) == scenario_hash(scenario("06:30")) != scenario_hash(scenario("06:31"))


def test_turbidity_of_each_weather_s_default_visibility() -> None:
    """``mmusv.sensors.env``: ``T = 1.9 + 30 / V_km`` clamped to [1.9, 10]; a clear 20 km day 3.4, a 5 km haze 7.9.
    The docstring said "fog and rain ... saturate it": the fog's default 500 m does, and since 2026-12-07 the rain's
    too (2.6 km: its air's 10 km with the drops of 4 mm/h, ``mmusv.world.rain``; it was 5 km, the haze's 7.9, a
    visibility the drops alone do not allow); the saturation is at 30 / 8.1 = 3.7 km."""
    from mmusv.sensors.env import turbidity_from_visibility
    from mmusv.world.environment import Weather

    t = {w: turbidity_from_visibility(Weather.make(w).visibility_m) for w in ("clear", "overcast", "fog", "rain")}
    assert t == pytest.approx({"clear": 3.4, "overcast": 4.9, "fog": 10.0, "rain": 10.0}), t
    assert turbidity_from_visibility(3704.0) < 10.0 == turbidity_from_visibility(3703.0)
    doc = " ".join((mmusv.sensors.env.__doc__ or "").split())
    assert "any visibility under 3.7 km saturates it" in doc and "fog and rain, whose skies are overcast" not in doc
