"""The Python API called wrongly by a programmer (an audit of 2026-11-30): arguments of the wrong type, floats and
booleans for counts and frame indices, strings for flags, single strings for lists of names, paths that are not
paths, values that made the core abort the process. Each is refused with an ``mmusv.errors`` class naming the
argument and what is allowed, before anything is written; never a bare TypeError/ValueError/AttributeError from deep
inside, a silent fallback (``frames=1.7`` recorded 1 frame, ``agents="usv_1"`` looked for USVs named after its
letters, ``overwrite="no"`` overwrote) or a crash. numpy integers work wherever Python ints do."""

from __future__ import annotations

import copy
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import pytest
import yaml
from mmusv.errors import ConfigError, GeometryError, InputError, MmusvError, NotFoundError
from mmusv.export import convert
from mmusv.recording import decode_image, decode_point_cloud, frame_messages, read_info, read_messages, summary, to_ns
from mmusv.recording.decode import WorldFrame
from mmusv.recording.stream import FrameStream
from mmusv.scene import Scene, demo_scene
from mmusv.world import environment, maps, sea_state, vessels
from mmusv.world.map_params import MapConfigError, OpenSeaParams

ROOT = Path(__file__).resolve().parents[2]

TINY: dict[str, Any] = {
    "name": "tiny",
    "seed": 1,
    "map": {"type": "open_sea", "seed": 1, "params": {"extent_m": 1000}},
    "acquisition": {"frequency_hz": 5, "frames": 3},
    "rigs": {"r": {"preset": "lidar_only"}},
    "vessels": [
        {"id": "usv_1", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2.0, "route": [[0, 0], [100, 0]]},
        {"id": "t1", "asset": "fishing_boat_12m", "speed_mps": 2.0, "route": [[50, 50], [100, 50]]},
    ],
}


def tiny() -> dict[str, Any]:
    return copy.deepcopy(TINY)


@pytest.fixture(scope="module")
def sim() -> mmusv.Simulation:
    return mmusv.Simulation(tiny())


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("rec")
    return mmusv.run(tiny(), out_dir=out, frames=2).recording


def _refused(call: Any, cls: type[Exception], *words: str) -> str:
    with pytest.raises(cls) as err:
        call()
    msg = str(err.value)
    assert all(w in msg for w in words), msg
    return msg


# ------------------------------------------------------------------------------------------------ mmusv.run

BAD_RUN_ARGS: list[tuple[dict[str, Any], str]] = [
    ({"frames": 1.7}, "frames = 1.7"),  # recorded 1 frame
    ({"frames": 1.0}, "frames = 1.0"),
    ({"frames": "2"}, "frames = '2'"),  # recorded 2 frames
    ({"frames": True}, "frames = True"),  # recorded 1 frame
    ({"frames": float("nan")}, "frames = nan"),  # ValueError
    ({"frames": float("inf")}, "frames = inf"),  # OverflowError
    ({"frames": [1]}, "frames = [1]"),  # TypeError
    ({"frame_range": (0,)}, "frame_range = (0,)"),  # IndexError
    ({"frame_range": (0, 1, 2)}, "frame_range = (0, 1, 2)"),  # the third item was dropped
    ({"frame_range": (0.5, 2)}, "frame_range[0]"),  # truncated to 0
    ({"frame_range": (None, 2)}, "frame_range[0]"),  # TypeError
    ({"frame_range": "02"}, "frame_range = '02'"),  # read as frames 0..1
    ({"frame_range": 5}, "frame_range = 5"),  # TypeError
    ({"frame_range": {"a": 1}}, "frame_range"),  # KeyError
    ({"frame_range": (True, 2)}, "frame_range[0]"),
    ({"out_dir": 5}, "out_dir = 5"),  # TypeError
    ({"out_dir": b"somewhere"}, "out_dir = b'somewhere'"),  # TypeError
    ({"out_dir": None}, "out_dir = None"),  # TypeError
    ({"out_dir": ""}, "out_dir is empty"),  # wrote into the current folder
    ({"overwrite": "no"}, "overwrite = 'no'"),  # "no" is true: replaced the recording
    ({"checks": "no"}, "checks = 'no'"),
    ({"profile": "no"}, "profile = 'no'"),
    ({"progress": 5}, "progress = 5"),  # TypeError after the first frame, a failed recording left
    ({"progress": lambda: None}, "progress"),  # the same
    ({"notes": ()}, "notes = ()"),
]


@pytest.mark.parametrize(("kwargs", "said"), BAD_RUN_ARGS, ids=[repr(k) for k, _ in BAD_RUN_ARGS])
def test_run_refuses_bad_arguments_before_writing(
    kwargs: dict[str, Any], said: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # an empty out_dir once meant the current folder
    out = tmp_path / "out"
    args = {"out_dir": out, **kwargs}
    _refused(lambda: mmusv.run(tiny(), **args), ConfigError, said)
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_run_takes_numpy_integers(tmp_path: Path) -> None:
    r = mmusv.run(tiny(), out_dir=tmp_path / "a", frames=np.int64(2))
    assert (r.status, r.frames_written) == ("complete", 2)
    r = mmusv.run(tiny(), out_dir=tmp_path / "b", frame_range=(np.int32(1), np.uint8(3)))
    assert (r.status, r.frames_written) == ("complete", 2)
    r = mmusv.run(tiny(), out_dir=tmp_path / "b", frame_range=[0, 1], overwrite=np.bool_(True))
    assert r.frames_written == 1


# ------------------------------------------------------------------------------------------------ Simulation


@pytest.mark.parametrize("frame", [1.5, 1.0, "1", None, True, np.float32(1.0), [0], np.array([1])])
def test_a_frame_index_is_a_whole_number(sim: mmusv.Simulation, frame: Any) -> None:
    # 1.5 captured a state between frames (FrameCapture.frame == 1.5), True frame 1; the rest were TypeErrors
    for call in (sim.capture, sim.world_state, sim.set_frame, sim.time_of, sim.prefetch_frame):
        _refused(lambda call=call: call(frame), ConfigError, "frame = ", "whole number")


def test_frames_outside_the_acquisition_are_refused(sim: mmusv.Simulation) -> None:
    for k in (-1, sim.frames, 10**30):
        for call in (sim.world_state, sim.time_of, sim.capture):  # world_state(-1) named `times[0]`, (3) worked
            _refused(lambda call=call, k=k: call(k), ConfigError, f"frame {k} is outside the acquisition")
    sim.prefetch_frame(sim.frames)  # documented: nothing to do outside the acquisition


def test_numpy_frame_indices_work(sim: mmusv.Simulation) -> None:
    cap = sim.capture(np.int64(1))
    assert cap.frame == 1 and type(cap.frame) is int
    assert sim.world_state(np.uint64(2)).frame == 2 and sim.time_of(np.int32(1)) == pytest.approx(0.2)


def test_capture_selections_are_lists_of_names(sim: mmusv.Simulation) -> None:
    # a single string was read as its letters: "no USV named '1', '_', 's', ..."
    _refused(lambda: sim.capture(0, agents="usv_1"), ConfigError, "agents = 'usv_1'", "single string", "['usv_1']")
    _refused(lambda: sim.capture(0, sensors="lidar"), ConfigError, "sensors = 'lidar'", "single string")
    _refused(lambda: sim.capture(0, agents=5), ConfigError, "agents = 5")  # TypeError
    _refused(lambda: sim.capture(0, agents=[["usv_1"]]), ConfigError, "agents")  # unhashable: TypeError
    _refused(lambda: sim.capture(0, sensors=3), ConfigError, "sensors = 3")
    _refused(lambda: sim.capture(0, radar="no"), ConfigError, "radar = 'no'")  # "no" is true
    assert sim.renders(sensors=["lidar"]) is False
    _refused(lambda: sim.renders(sensors="cameras"), ConfigError, "sensors = 'cameras'")  # answered False
    _refused(lambda: sim.renders(sensors=["camera"]), ConfigError, "unknown sensor kind")
    assert list(sim.capture(0, agents=("usv_1",), sensors={"lidar"}).agents) == ["usv_1"]


def test_simulation_arguments_of_the_wrong_kind(sim: mmusv.Simulation) -> None:
    _refused(lambda: mmusv.Simulation(tiny(), world="island"), ConfigError, "world = 'island'", "MapWorld")
    _refused(lambda: sim.set_frame(0, sea_radius_m="x"), ConfigError, "sea_radius_m = 'x'")  # ValueError
    _refused(lambda: sim.set_frame(0, shading_detail="no"), ConfigError, "shading_detail")
    _refused(lambda: sim.set_sea_surface("W2"), ConfigError, "sea = 'W2'", "SeaSpec")  # AttributeError
    _refused(lambda: sim.wakes(None), ConfigError, "WorldState")  # type: ignore[arg-type]
    state = sim.world_state(0)
    _refused(lambda: sim.sensor_poses("usv_1", state), ConfigError, "Agent")  # type: ignore[arg-type]


def test_a_huge_sea_radius_is_refused(sim: mmusv.Simulation) -> None:
    # a Rust panic (capacity overflow) surfacing as InternalError
    _refused(lambda: sim.set_frame(0, sea_radius_m=1e30), ConfigError, "sea_radius_m", "give at most")


def test_a_refused_frame_leaves_the_scene_as_it_was() -> None:
    """``set_frame`` moved the vessels and the buoys to the new frame, then refused the sea surface (too large for
    one grid): the scene was left half in the new frame. Now the surface is checked before anything moves."""
    doc = tiny()
    doc["acquisition"]["frames"] = 20
    doc["vessels"][1]["speed_mps"] = 10.0
    sim = mmusv.Simulation(doc)
    sim.set_frame(0)
    ids = [*np.asarray(sim.ws.vessel_instances).tolist(), *sim.ws.buoy_instances]
    assert len(sim.ws.buoy_instances) > 0 and sim._buoy_field is not None  # the map's buoys ride the W0 sea

    def poses() -> np.ndarray:
        return np.array([sim.ws.scene.instance_pose(i) for i in ids])

    before = poses()
    _refused(lambda: sim.set_frame(19, sea_radius_m=1e5), ConfigError, "sea_radius_m = 100000", "give at most")
    np.testing.assert_array_equal(poses(), before)
    sim.set_frame(19)
    moved = np.abs(poses() - before).max(axis=(1, 2))
    assert moved[1] > 30.0 and moved[2:].max() > 0.1  # the target sailed 38 m, the buoys near the USV rode the waves


_ABORTS = """
import numpy as np
import mmusv
from mmusv.errors import MmusvError
from mmusv.scene import Scene, demo_scene
from mmusv.world.sea_state import sea_spec_for_preset
doc = {doc!r}
try:
    mmusv.Simulation(doc).capture(0)
except MmusvError as exc:
    print("simulation:", type(exc).__name__, exc)
s = Scene()
s.set_sea(s.add_instance(s.add_mesh(np.array([[-9.0, -9, 0], [9, -9, 0], [0, 9, 0]]), [[0, 1, 2]])))
try:
    s.set_wave_surface(sea_spec_for_preset("4"), scenario_seed=0, time_s=0.0, foci=[[-2e5, -2e5], [2e5, 2e5]])
except MmusvError as exc:
    print("scene:", type(exc).__name__, exc)
try:
    demo_scene(terrain_cells=10**6)
except MmusvError as exc:
    print("demo:", type(exc).__name__, exc)
# The native calls themselves, past the Python checks: the core refuses them too.
from mmusv._native import core
far = np.array([[-2e5, -2e5], [2e5, 2e5]], np.float32)
for foci, radius in ((far, 320.0), (np.zeros((1, 2), np.float32), 1e30)):
    try:
        s.native.set_wave_surface(2.0, tp_s=7.0, gamma=1.0, foci=foci, radius_m=radius)
    except MmusvError as exc:
        print("native scene:", type(exc).__name__, exc)
for cells, vessels in ((10**6, 1), (64, 10**9)):
    try:
        core.demo_scene(seed=1, extent=2000.0, terrain_cells=cells, vessels=vessels)
    except MmusvError as exc:
        print("native demo:", type(exc).__name__, exc)
"""


def test_requests_that_aborted_the_process_are_refused() -> None:
    """Two USVs 2,000 km apart over a physical sea (a valid scenario; `mmusv.run` only catches it with its route
    checks), wave-surface foci 400 km apart and a 10⁶-cell demo scene each asked the core for hundreds of GB and
    the process aborted (``memory allocation of ... bytes failed``). Run in a child with 4 GiB of address space."""
    doc = tiny()
    doc["environment"] = {"wave": "W2"}
    doc["vessels"] = [
        {"id": "u1", "role": "usv", "asset": "usv_wamv", "rig": "r", "route": [[-1e6, -1e6], [-999900, -1e6]]},
        {"id": "u2", "role": "usv", "asset": "usv_wamv", "rig": "r", "route": [[1e6, 1e6], [1e6, 999900]]},
    ]
    code = textwrap.dedent(_ABORTS).format(doc=doc)
    limit = "import resource; resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))\n"
    r = subprocess.run(
        [sys.executable, "-c", limit + code], capture_output=True, text=True, timeout=600, cwd=ROOT, check=False
    )
    assert r.returncode == 0, r.stderr[-2000:]
    lines = r.stdout.splitlines()
    assert any(ln.startswith("simulation: ConfigError") and "keep the USVs within" in ln for ln in lines), r.stdout
    assert any(ln.startswith("scene: InputError") and "bring the foci closer" in ln for ln in lines), r.stdout
    assert any(ln.startswith("demo: InputError") and "terrain_cells" in ln for ln in lines), r.stdout
    native = [ln for ln in lines if ln.startswith("native scene: InputError") and "foci" in ln]
    assert len(native) == 2, r.stdout  # foci 400 km apart; a radius of 1e30 m (a capacity-overflow panic)
    assert any(ln.startswith("native demo: InputError") and "terrain_cells" in ln for ln in lines), r.stdout
    assert any(ln.startswith("native demo: InputError") and "vessels" in ln for ln in lines), r.stdout


# ------------------------------------------------------------------------------------------------ Scene

TRI_V = np.array([[-10.0, -10, 0], [10, -10, 0], [0, 10, 0]])
TRI_F = np.array([[0, 1, 2]])


@pytest.fixture
def scene() -> Scene:
    s = Scene()
    s.add_instance(s.add_mesh(TRI_V, TRI_F))
    return s


def test_scene_arguments_of_the_wrong_kind(scene: Scene) -> None:
    s = scene
    _refused(lambda: s.add_mesh(TRI_V, TRI_F, name=5), InputError, "name = 5")  # type: ignore[arg-type]
    _refused(lambda: s.add_mesh(TRI_V.astype(bool), TRI_F), InputError, "vertices", "bool")  # read as 0/1 metres
    big = np.array([[0, 1, 2**64 - 1]], dtype=np.uint64)
    _refused(lambda: s.add_mesh(TRI_V, big), GeometryError, "18446744073709551615")  # the message said -1
    o, d = [[0.0, 0.0, 1.0]], [[0.0, 0.0, -1.0]]
    _refused(lambda: s.cast_rays(o, d, max_range="5"), InputError, "max_range = '5'")  # type: ignore[arg-type]
    _refused(lambda: s.cast_rays(o, d, max_range=True), InputError, "max_range = True")  # a 1 m range
    _refused(lambda: s.set_lights([0], on="off"), InputError, "on = 'off'")  # type: ignore[arg-type]  # lit them
    # an id the scene cannot hold is one it does not hold, as set_poses and the core say (InputError for -1 only)
    for bad in ([-1], [2**32], [999]):
        _refused(lambda b=bad: s.set_lights(b, on=True), NotFoundError, f"unknown instance id {bad[0]}")
        _refused(lambda b=bad: s.set_poses(b, np.eye(4)), NotFoundError, f"unknown instance id {bad[0]}")
    _refused(lambda: s.set_lights([[0]], on=True), InputError, "instance_ids must be a 1-D integer array")
    _refused(lambda: s.set_lights([0.5], on=True), InputError, "instance_ids must be a 1-D integer array")
    _refused(lambda: s.set_sea(0, moving=[0.5]), InputError, "moving")  # truncated to instance 0
    _refused(lambda: s.set_materials("red"), InputError, "materials")  # ValueError
    _refused(lambda: s.set_seabed("flat"), InputError, "seabed heights")  # ValueError
    _refused(lambda: s.set_seabed(np.zeros((2, 2)), x0="a"), InputError, "x0 = 'a'")  # type: ignore[arg-type]
    _refused(lambda: s.export(5), InputError, "path = 5")  # type: ignore[arg-type]  # TypeError
    _refused(lambda: s.export(b"/tmp/x.ply"), InputError, "path = b")  # type: ignore[arg-type]
    _refused(lambda: s.wave_heights([[np.nan, 0.0]]), InputError, "xy[0]")  # answered 0 m
    hits = s.cast_rays(o, d)
    _refused(lambda: hits.points(np.zeros((2, 3)), np.ones((2, 3))), InputError, "points")  # IndexError
    _refused(lambda: hits.points(o, [[0.0, 0.0, 0.0]]), InputError, "non-zero")  # nan rows and a RuntimeWarning


def test_vertices_beyond_float32_are_a_geometry_error(scene: Scene) -> None:
    # a RuntimeWarning (an error under -W error) from the cast before the finiteness check
    v = TRI_V.copy()
    v[1, 0] = 1e39
    _refused(lambda: scene.add_mesh(v, TRI_F), GeometryError, "vertices[1]")
    _refused(lambda: scene.cast_rays([[1e39, 0.0, 0.0]], [[0.0, 0.0, -1.0]]), InputError, "origins[0]")


def test_wave_surface_arguments(scene: Scene) -> None:
    s = scene
    s.set_sea(0)
    sea = sea_state.sea_spec_for_preset("4")
    good: dict[str, Any] = {"scenario_seed": 0, "time_s": 0.0, "foci": np.zeros((1, 2))}
    s.set_wave_surface(sea, **good)
    for kw, said in (
        ({"radius_m": "x"}, "radius_m = 'x'"),  # ValueError
        ({"radius_m": 1e30}, "radius_m = 1e+30"),  # a Rust panic: capacity overflow
        ({"time_s": "now"}, "time_s = 'now'"),  # ValueError
        ({"time_s": 1e308}, "time_s"),  # every height NaN: a sea every ray passed through
        ({"time_s": -2e9}, "time_s"),  # phases of no precision
        ({"scenario_seed": -1}, "scenario_seed = -1"),  # OverflowError
        ({"scenario_seed": 2**64}, "scenario_seed"),  # OverflowError
        ({"scenario_seed": 1.5}, "scenario_seed = 1.5"),  # truncated to 1
        ({"detail": "no"}, "detail = 'no'"),  # "no" is true
    ):
        _refused(lambda kw=kw: s.set_wave_surface(sea, **{**good, **kw}), InputError, said)
    _refused(lambda: s.set_wave_surface("W2", **good), InputError, "sea = 'W2'")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "said"),
    [
        ({"terrain_cells": -1}, "terrain_cells = -1"),  # OverflowError
        ({"vessels": 1.5}, "vessels = 1.5"),  # TypeError
        ({"vessels": 10**9}, "vessels = 1000000000"),  # hours of work, then out of memory
        ({"seed": -1}, "seed = -1"),
        ({"extent": "big"}, "extent = 'big'"),
    ],
)
def test_demo_scene_arguments(kwargs: dict[str, Any], said: str) -> None:
    _refused(lambda: demo_scene(**kwargs), InputError, said)


# ------------------------------------------------------------------------------------------------ recordings


@pytest.mark.parametrize("path", [5, None, b"/tmp/x.mcap", ["/tmp/x.mcap"]])
def test_a_recording_path_must_be_a_path(path: Any) -> None:
    for call in (read_info, summary, lambda p: list(read_messages(p)), lambda p: frame_messages(p, 0)):
        _refused(lambda call=call: call(path), ConfigError, "recording path")  # TypeErrors


def test_reader_arguments(recording: Path) -> None:
    # a single string was read as a set of letters: no message, no word
    _refused(lambda: list(read_messages(recording, "/world/state")), ConfigError, "topics = '/world/state'")
    _refused(lambda: list(read_messages(recording, ["/nope"])), ConfigError, "no topic '/nope'", "/world/state")
    _refused(lambda: list(read_messages(recording, 5)), ConfigError, "topics = 5")  # type: ignore[arg-type]
    _refused(lambda: list(read_messages(recording, damage=())), ConfigError, "damage = ()")  # type: ignore[arg-type]
    assert len(list(read_messages(recording, ["/world/state"]))) == 2
    for frame in (1.0, "1", None, True):  # 1.0 and True read frame 1, the others were TypeErrors
        _refused(lambda frame=frame: frame_messages(recording, frame), ConfigError, "frame = ")
    assert "/world/state" in frame_messages(recording, np.int64(1))
    info = read_info(recording)
    _refused(lambda: FrameStream(str(recording), want=bool), ConfigError, "RecordingInfo")  # type: ignore[arg-type]
    _refused(lambda: FrameStream(info, want=None), ConfigError, "want = None")  # type: ignore[arg-type]


def test_decoders_name_the_message_they_take(recording: Path) -> None:
    msgs = frame_messages(recording, 0)
    cloud = msgs["/usv_1/lidar"]
    _refused(lambda: decode_image(cloud), InputError, "decode_image", "foxglove.PointCloud")  # AttributeError
    _refused(lambda: decode_point_cloud(None), InputError, "decode_point_cloud")
    _refused(lambda: WorldFrame.from_message(cloud), InputError, "mmusv.WorldState")
    assert WorldFrame.from_message(msgs["/world/state"]).frame == 0


def test_to_ns_arguments() -> None:
    _refused(lambda: to_ns("1"), InputError, "time_s")  # type: ignore[arg-type]  # TypeError
    _refused(lambda: to_ns(1e30), InputError, "2**64 ns")  # an int no MCAP log time can hold
    assert to_ns(np.float32(0.5)) == 500_000_000


# ------------------------------------------------------------------------------------------------ mmusv.world


def test_map_generators_take_their_own_parameters() -> None:
    # AttributeErrors, and generate_map_from(None) made a port map
    _refused(lambda: maps.generate_map_from({"extent_m": 500}, seed=0), MapConfigError, "params")  # type: ignore[arg-type]
    _refused(lambda: maps.generate_map_from(None, seed=0), MapConfigError, "params")  # type: ignore[arg-type]
    _refused(lambda: maps.generate_island(seed=0, params={"extent_m": 500}), MapConfigError, "IslandParams")  # type: ignore[arg-type]
    _refused(lambda: maps.generate_port(seed=0, params=OpenSeaParams()), MapConfigError, "PortParams")  # type: ignore[arg-type]


def test_asset_helpers_name_the_valid_names() -> None:
    _refused(lambda: vessels.get_asset(5), ConfigError, "asset name = 5", "asset_names()")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="string"):  # still a ValueError for schema validators
        vessels.known_asset(5)  # type: ignore[arg-type]  # a TypeError inside difflib
    with pytest.raises(ConfigError, match="did you mean usv_wamv"):
        vessels.known_asset("usv_wam")
    _refused(lambda: vessels.library(category="nope"), ConfigError, "category = 'nope'", "fishing_boat")  # []
    _refused(lambda: vessels.library(semantic_class=999), ConfigError, "semantic_class = 999", "10 (vessel)")
    _refused(lambda: vessels.library(semantic_class="boat"), ConfigError, "semantic_class")  # type: ignore[arg-type]
    _refused(lambda: vessels.register_asset("usv_wamv"), ConfigError, "VesselAsset")  # type: ignore[arg-type]
    _refused(lambda: vessels.load_asset_catalog(5), ConfigError, "path")  # type: ignore[arg-type]
    _refused(lambda: vessels.unregister_asset(["x"]), ConfigError, "asset name")  # type: ignore[arg-type]


def test_environment_helpers_check_their_types() -> None:
    _refused(lambda: environment.Environment.make(time_of_day=1300), ConfigError, "time_of_day = 1300")  # type: ignore[arg-type]
    _refused(lambda: environment.sun_at(None), ConfigError, "time_of_day = None")  # type: ignore[arg-type]
    _refused(lambda: environment.sun_at("12:00", latitude_deg="x"), ConfigError, "latitude_deg")  # type: ignore[arg-type]
    _refused(lambda: environment.sun_at("12:00", day_of_year=1.5), ConfigError, "day_of_year")  # type: ignore[arg-type]
    _refused(lambda: environment.Environment.make(visibility_m="far"), ConfigError, "visibility_m = 'far'")  # type: ignore[arg-type]
    for wave in (True, None, [1]):  # True was a 1 m sea; the others TypeErrors
        _refused(lambda wave=wave: environment.wave_height_m(wave), ConfigError, "environment.wave")


def test_sea_state_helpers_check_their_values() -> None:
    for name in ("10", 3, None, "4 "):  # KeyErrors
        with pytest.raises(ConfigError, match="the presets are 0, 1") as err:
            sea_state.sea_spec_for_preset(name)  # type: ignore[arg-type]
        assert isinstance(err.value, KeyError)  # as documented before
    for kw, said in (
        ({"hs_m": "2"}, "hs_m = '2'"),  # TypeError
        ({"hs_m": 2.0, "tp_s": float("nan")}, "tp_s = nan"),  # a sea of NaN, refused first when used
        ({"hs_m": 2.0, "tp_s": 0.0}, "tp_s = 0"),
        ({"hs_m": 2.0, "gamma": 0.0}, "gamma = 0"),
        ({"hs_m": 2.0, "spread_s": -1.0}, "spread_s = -1"),
        ({"hs_m": 2.0, "direction_deg": float("nan")}, "direction_deg = nan"),
    ):
        _refused(lambda kw=kw: sea_state.sea_spec_for_height(**kw), ConfigError, said)
    assert sea_state.sea_spec_for_height(np.float64(2.0)).hs_m == 2.0


# ------------------------------------------------------------------------------------------------ exports

BAD_CONVERT_ARGS: list[tuple[dict[str, Any], str]] = [
    ({"recordings": 5}, "recordings = 5"),  # TypeError
    ({"recordings": None}, "recordings = None"),
    ({"recordings": b"/tmp/x.mcap"}, "recordings = b"),  # iterated as integers
    ({"recordings": [5]}, "recordings[0] = 5"),
    ({"splits": 5}, "splits = 5"),  # TypeError
    ({"splits": ["a", 1, 1]}, "splits[0] = 'a'"),  # ValueError
    ({"splits": (True, 0, 0)}, "splits[0] = True"),
    ({"seed": None}, "seed = None"),  # a random split: a different dataset every run
    ({"seed": "x"}, "seed = 'x'"),
    ({"seed": 1.5}, "seed = 1.5"),
    ({"seed": -1}, "seed = -1"),
    ({"eval_range_m": True}, "eval_range_m = True"),  # a 1 m range
    ({"eval_range_m": "200"}, "eval_range_m = '200'"),
    ({"extras": 5}, "extras = 5"),  # TypeError
    ({"min_box_px": True}, "min_box_px = True"),
    ({"max_occlusion": True}, "max_occlusion = True"),
    ({"min_contrast": True}, "min_contrast = True"),
    ({"min_contrast": -1}, "min_contrast = -1"),
    ({"include_usvs": "no"}, "include_usvs = 'no'"),
    ({"overwrite": "no"}, "overwrite = 'no'"),  # "no" is true: a previous conversion was deleted
    ({"progress": 5}, "progress = 5"),  # TypeError after the first frame, conversion.yaml left in_progress
    ({"out_dir": 5}, "out_dir = 5"),
    ({"out_dir": b"x"}, "out_dir = b'x'"),
    ({"out_dir": None}, "out_dir = None"),
    ({"out_dir": ""}, "out_dir is empty"),  # the current folder
]


@pytest.mark.parametrize(("kwargs", "said"), BAD_CONVERT_ARGS, ids=[repr(k) for k, _ in BAD_CONVERT_ARGS])
def test_convert_refuses_bad_arguments_before_writing(
    recording: Path, kwargs: dict[str, Any], said: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    args: dict[str, Any] = {"recordings": recording, "to": "coco", "out_dir": tmp_path / "out", **kwargs}
    _refused(lambda: convert(**args), ConfigError, said)
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------------------------ run_many

BAD_BATCH_ARGS: list[tuple[dict[str, Any], str]] = [
    ({"jobs": "x"}, "jobs = 'x'"),  # ValueError
    ({"jobs": None}, "jobs = None"),  # TypeError
    ({"jobs": 1.5}, "jobs = 1.5"),  # truncated to 1
    ({"jobs": True}, "jobs = True"),
    ({"retries": 1.5}, "retries = 1.5"),
    ({"cpus_per_task": "x"}, "cpus_per_task = 'x'"),
    ({"split_frames": "x"}, "split_frames = 'x'"),  # TypeError
    ({"split_frames": 1.5}, "split_frames = 1.5"),
    ({"frames": 0}, "frames = 0"),  # every scenario failed instead
    ({"frames": 1.5}, "frames = 1.5"),
    ({"frames": True}, "frames = True"),
    ({"overwrite": "no"}, "overwrite = 'no'"),
    ({"checks": "no"}, "checks = 'no'"),
    ({"stop_on_full_disk": "no"}, "stop_on_full_disk = 'no'"),
    ({"ray": 5}, "ray = 5"),
    ({"progress": 5}, "progress = 5"),  # TypeError after the first task
    ({"index": 5}, "index = 5"),
    ({"index_extra": 5}, "index_extra = 5"),  # AttributeError after every task ran
    ({"out_dir": 5}, "out_dir = 5"),
    ({"out_dir": ""}, "out_dir is empty"),  # the current folder
    ({"source": 5}, "source = 5"),  # TypeError
    ({"source": b"scenarios"}, "source = b"),
    ({"source": [5]}, "source[0] = 5"),
]


@pytest.mark.parametrize(("kwargs", "said"), BAD_BATCH_ARGS, ids=[repr(k) for k, _ in BAD_BATCH_ARGS])
def test_run_many_refuses_bad_arguments_before_writing(
    kwargs: dict[str, Any], said: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    src = tmp_path / "src"
    src.mkdir()
    (src / "tiny.yaml").write_text(yaml.safe_dump(tiny()), encoding="utf-8")
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    args: dict[str, Any] = {"source": src, "out_dir": tmp_path / "out", "frames": 1, **kwargs}
    source = args.pop("source")
    _refused(lambda: mmusv.run_many(source, **args), ConfigError, said)
    assert not (tmp_path / "out").exists() and list(work.iterdir()) == []


def test_every_refusal_here_is_an_mmusv_error() -> None:
    """The classes the tests above expect are all in the tree a caller catches."""
    for cls in (ConfigError, InputError, GeometryError, MapConfigError, vessels.AssetNameError):
        assert issubclass(cls, MmusvError)
