"""Bad inputs to the generator and to the route checks of ``mmusv run`` get a ConfigError naming the field (and
the file) instead of a hang, a MemoryError or a RecursionError (fuzz findings A-G)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import pytest
import yaml
from mmusv.config import Scenario, load_scenario
from mmusv.errors import ConfigError
from mmusv.generate import generate, load_spec, samples
from mmusv.generate.mapctx import map_context

BASE: dict[str, Any] = {
    "name": "t",
    "map": {"type": "open_sea", "seed": 2},
    "acquisition": {"frequency_hz": 5, "frames": 10},
    "rigs": {"r": {"preset": "lidar_only"}},
    "vessels": [
        {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 3, "route": [[-300, 0], [300, 0]]}
    ],
}
SPEC: dict[str, Any] = {
    "name": "g",
    "seed": 42,
    "map": {"type": "island", "seed": 4},
    "acquisition": {"frequency_hz": 2, "frames": 10},
    "combinations": [{"family": "crossing", "difficulty": "easy", "cooperating": 1, "targets": ["small"], "quota": 1}],
}


def _scenario(**acq: float) -> Scenario:
    return load_scenario({**BASE, "acquisition": acq})


class _NoPoses:
    """A fleet that fails the test when asked to sample: the refusal must come before any sampling."""

    def __init__(self, fleet: Any) -> None:
        self._fleet = fleet

    def route_lengths(self) -> Any:
        return self._fleet.route_lengths()

    def poses_at_times(self, times: Any) -> Any:
        raise AssertionError(f"sampled {len(times):,} times instead of refusing")


@pytest.fixture
def no_sampling(monkeypatch: pytest.MonkeyPatch) -> None:
    real = samples.build_fleet
    monkeypatch.setattr(samples, "build_fleet", lambda sc: _NoPoses(real(sc)))


def _spec_error(tmp_path: Path, extra: dict[str, Any]) -> str:
    path = tmp_path / "spec.yaml"
    path.write_text(yaml.safe_dump({**SPEC, **extra}))
    with pytest.raises(ConfigError) as info:
        load_spec(path)
    msg = str(info.value)
    assert "spec.yaml" in msg
    return msg


# ------------------------------------------------------------------------- A, B: the route checks' sample budget


@pytest.mark.usefixtures("no_sampling")
def test_run_refuses_checks_past_the_sample_budget(tmp_path: Path) -> None:
    # 1000 Hz x 10,000,000 frames is a valid acquisition, but its checks would sample all of it (it hung)
    path = tmp_path / "long.yaml"
    path.write_text(yaml.safe_dump({**BASE, "acquisition": {"frequency_hz": 1000, "frames": 10_000_000}}))
    with pytest.raises(ConfigError) as info:
        mmusv.run(path, out_dir=tmp_path / "out")
    msg = str(info.value)
    assert "long.yaml" in msg and "10,000,000 samples" in msg
    assert "--no-checks" in msg and "acquisition.frames" in msg and "--frames" in msg
    assert not (tmp_path / "out").exists()


def test_run_checks_only_the_frames_it_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # `--frames 1` of that acquisition checks the routes over its one frame (then stops here: nothing recorded).
    import mmusv.acquire

    seen: list[int] = []

    def checked(scenario: Any, world: Any, *, source: str) -> list[str]:
        seen.append(scenario.acquisition.frames)
        raise ConfigError("stop")

    monkeypatch.setattr(mmusv.acquire, "check_routes", checked)
    path = tmp_path / "long.yaml"
    path.write_text(yaml.safe_dump({**BASE, "acquisition": {"frequency_hz": 1000, "frames": 10_000_000}}))
    for kwargs, frames in (({"frames": 1}, 1), ({"frame_range": (3, 7)}, 7)):
        with pytest.raises(ConfigError, match="stop"):
            mmusv.run(path, out_dir=tmp_path / "out", **kwargs)
        assert seen[-1] == frames


@pytest.mark.usefixtures("no_sampling")
def test_take_samples_refuses_instead_of_allocating() -> None:
    from mmusv.scenario_checks import scenario_samples

    sc = _scenario(frequency_hz=1000, frames=10_000_000)
    with pytest.raises(ConfigError, match=r"10,000,000 samples.*acquisition\.frames"):
        scenario_samples(sc, map_context("open_sea", seed=2, params={}))


@pytest.mark.usefixtures("no_sampling")
def test_too_many_samples_advises_what_lowers_them() -> None:
    # The refusal advised "lower acquisition.frames or acquisition.frequency_hz": over the same frames a lower rate
    # is a longer acquisition, whose vessels sail further: never fewer samples, and more once the speed sets them.
    from mmusv.scenario_checks import scenario_samples

    sc = _scenario(frequency_hz=1000, frames=10_000_000)
    with pytest.raises(ConfigError) as info:
        scenario_samples(sc, map_context("open_sea", seed=2, params={}))
    assert samples.FEWER_TIMES in str(info.value) and "or acquisition.frequency_hz" not in str(info.value)
    for frames, hz, speed in ((10_000, 0.5, 10.0), (10_000, 5.0, 0.5), (200, 1.0, 30.0)):
        n = samples.time_samples(frames, frequency_hz=hz, step=2.0, max_speed_mps=speed)
        assert (
            samples.time_samples(frames, frequency_hz=hz / 2, step=2.0, max_speed_mps=speed)
            >= n
            >= samples.time_samples(frames, frequency_hz=hz * 2, step=2.0, max_speed_mps=speed)
        )
    assert samples.time_samples(10_000, frequency_hz=0.25, step=2.0, max_speed_mps=10.0) > samples.time_samples(
        10_000, frequency_hz=0.5, step=2.0, max_speed_mps=10.0
    )
    assert samples.time_samples(5_000, frequency_hz=0.5, step=2.0, max_speed_mps=10.0) < samples.time_samples(
        10_000, frequency_hz=0.5, step=2.0, max_speed_mps=10.0
    )


def test_sample_counts_saturate_instead_of_overflowing() -> None:
    sc = _scenario(frequency_hz=5, frames=10)
    n_t, n_g = samples._counts(sc, np.array([math.inf]), 2.0)  # was an OverflowError
    assert n_t == 10 and n_g > samples.MAX_CHECK_SAMPLES
    problem = samples.budget_problem(sc, n_motion=n_t, n_route=n_g)
    assert problem is not None and "along the longest route" in problem
    n_t, n_g = samples._counts(sc, np.array([600.0]), 2.0)
    assert samples.budget_problem(sc, n_motion=n_t, n_route=n_g) is None


def test_generator_rejects_a_candidate_past_the_budget(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    spec = load_spec({**SPEC, "max_attempts_per_scenario": 2})
    monkeypatch.setattr(samples, "MAX_CHECK_SAMPLES", 10)
    report = generate(spec, tmp_path / "out")
    assert report.accepted == 0
    rep = json.loads((tmp_path / "out" / "report.json").read_text())
    assert "the route checks would take" in json.dumps(rep)


def test_spec_refuses_a_window_past_the_sample_budget(tmp_path: Path) -> None:
    msg = _spec_error(tmp_path, {"acquisition": {"frequency_hz": 0.01, "frames": 10_000_000}})
    assert "invalid spec acquisition" in msg and "samples" in msg


# ------------------------------------------------------------------------------------------- C: speeds


@pytest.mark.parametrize(
    ("extra", "field"),
    [
        ({"usv": {"speed_mps": [1.0e6, 1.0e7]}}, "usv.speed_mps"),
        (
            {"size_classes": {"small": {"length_m": [0, 15], "speed_mps": [1.0e6, 1.0e7]}}},
            "size_classes.small.speed_mps",
        ),
        ({"usv": {"speed_mps": [1, 101]}}, "usv.speed_mps"),
    ],
)
def test_spec_speeds_are_bounded(tmp_path: Path, extra: dict[str, Any], field: str) -> None:
    msg = _spec_error(tmp_path, extra)
    assert f"invalid spec {field}" in msg and "<= 100 m/s" in msg


def test_spec_speed_at_the_bound_is_accepted() -> None:
    assert load_spec({**SPEC, "usv": {"speed_mps": [1, 100]}}).usv.speed_mps == (1, 100)


# --------------------------------------------------------------------------------- D: encounter clearance


def test_spec_encounter_clearance_is_bounded(tmp_path: Path) -> None:
    msg = _spec_error(tmp_path, {"encounter_clearance_m": 1.0e308})
    assert "encounter_clearance_m" in msg and "10000" in msg


def test_eligible_cells_halve_in_a_loop() -> None:
    ctx = map_context("island", seed=4, params={})
    pri = ctx.priors
    ok = pri.water_mask & pri.valid_zones
    cells = ctx._eligible(1.0e308)  # was a RecursionError
    assert cells.size > 0
    need, top = 1.0e308, float(pri.shore_distance[ok].max())
    while need > top:  # the halving sequence, down to the first value some cell reaches
        need /= 2.0
    assert np.array_equal(cells, np.flatnonzero(ok & (pri.shore_distance >= need)))
    assert np.array_equal(ctx._eligible(100.0), np.flatnonzero(ok & (pri.shore_distance >= 100.0)))


# ------------------------------------------------------------------------------ E: difficulty range, constraints


def test_spec_difficulty_range_is_bounded(tmp_path: Path) -> None:
    msg = _spec_error(tmp_path, {"difficulties": {"easy": {"range_m": [1.0e300, 1.0e308]}}})
    assert "difficulties.easy.range_m" in msg and "100,000 m" in msg


@pytest.mark.parametrize(
    ("check", "values"),
    [
        ("cooperation", {"min_m": 1.0e300, "max_m": 1.0e308}),
        ("separation", {"min_m": 1.0e308}),
        ("shore_clearance", {"min_m": 1.0e308}),
        ("sensing_range", {"range_m": 1.0e308}),
    ],
)
def test_spec_constraint_distances_are_bounded(tmp_path: Path, check: str, values: dict[str, float]) -> None:
    msg = _spec_error(tmp_path, {"constraints": {check: values}})
    assert f"constraints.{check}." in msg and "100000" in msg


# ------------------------------------------------------------------------------------------ F: environment


@pytest.mark.parametrize(
    ("key", "value"), [("visibility_m", 1.0e-300), ("visibility_m", 0.5), ("rain_mm_per_h", 1000.0)]
)
def test_spec_environment_ranges_match_the_scenario(tmp_path: Path, key: str, value: float) -> None:
    msg = _spec_error(tmp_path, {"environment": {"weather": ["clear"], key: [value]}})
    assert f"environment.{key}" in msg
    with pytest.raises(ConfigError, match=f"environment.{key}"):  # the scenario refuses the same value
        load_scenario({**BASE, "environment": {key: value}})


# ------------------------------------------------------------------------------------------------- G: name


@pytest.mark.parametrize("name", ["..", ".", "...", ".hidden", "a/b", ""])
def test_spec_name_refuses_dots_and_separators(tmp_path: Path, name: str) -> None:
    msg = _spec_error(tmp_path, {"name": name})
    assert "invalid spec name" in msg


def test_spec_name_with_inner_dots_is_accepted() -> None:
    assert load_spec({**SPEC, "name": "v1.2_run-3"}).name == "v1.2_run-3"


@pytest.mark.parametrize(
    ("environment", "said"),
    [
        ({"wave": ["W1", "W2"], "sea": {"hs_m": 1.0}}, "not both"),
        ({"motion": ["physical", "paper"], "sea": {"state": 4}}, "motion: paper"),
    ],
)
def test_spec_environment_refuses_a_sea_given_twice(tmp_path: Path, environment: dict[str, Any], said: str) -> None:
    # Each key is valid alone, but every candidate drawn with both would be refused by the scenario schema.
    msg = _spec_error(tmp_path, {"environment": environment})
    assert "environment" in msg and said in msg, msg


def test_force_replaces_only_what_a_generate_run_wrote(tmp_path: Path) -> None:
    # `generate spec.yaml -o DIR --force` used to delete every *.yaml in DIR: the spec itself, hand-written files.
    from mmusv.errors import IoError
    from mmusv.generate.runner import _prepare_dir

    out = tmp_path / "gen"
    out.mkdir()
    (out / "a_0000.yaml").write_text("name: a\n")
    (out / "report.json").write_text(json.dumps({"combinations": [{"files": ["a_0000.yaml"]}]}))
    spec = out / "spec.yaml"
    spec.write_text("name: s\n")
    with pytest.raises(IoError, match="spec itself"):
        _prepare_dir(out, True, spec)
    assert spec.is_file() and (out / "a_0000.yaml").is_file()
    spec.unlink()
    (out / "mine.yaml").write_text("name: m\n")
    with pytest.raises(IoError, match=r"mine\.yaml"):
        _prepare_dir(out, True)
    (out / "mine.yaml").unlink()
    _prepare_dir(out, True)  # only the listed scenario and the report: removed
    assert not any(out.iterdir())
    with pytest.raises(IoError, match="--force"):
        (out / "b.yaml").write_text("name: b\n")
        _prepare_dir(out, False)


@pytest.mark.parametrize(
    ("extra", "field", "hint"),
    [
        ({"sed": 3}, "sed = 3", "did you mean 'seed'? allowed keys: name, seed, map,"),
        (
            {"size_classes": {"small": {"lenght_m": [0, 15]}}},
            "size_classes.small.lenght_m",
            "did you mean 'length_m'? allowed keys: length_m, speed_mps, assets",
        ),
        (
            {"combinations": [{**SPEC["combinations"][0], "dificulty": "near"}]},
            "combinations[0].dificulty",
            "did you mean 'difficulty'? allowed keys: name, family, difficulty,",
        ),
    ],
)
def test_an_unknown_spec_key_gets_the_closest_and_the_allowed_keys(
    tmp_path: Path, extra: dict[str, Any], field: str, hint: str
) -> None:
    # A typo said only "Extra inputs are not permitted" (docs review); a scenario's unknown keys said more.
    msg = _spec_error(tmp_path, extra)
    assert f"invalid spec {field}" in msg and hint in msg, msg
