"""A new user's round on ``mmusv generate`` and ``mmusv dataset``: a run stopped before its report (Ctrl-C, a kill,
a full disk) is replaced by ``--force`` and finished by ``mmusv dataset`` run again; a folder that cannot be written
is named before any sampling, a full disk names the file and leaves no temporary; a spec refuses booleans for
numbers and constraints that contradict each other (naming both); an earlier run's folder is refused before the
maps are built; a dataset run again reports its quota shortfall again, brings back a deleted scenario file and
says what to do when converting fails on a full disk. Each test failed before its fix."""

from __future__ import annotations

import argparse
import copy
import errno
import filecmp
import importlib
import json
import pathlib
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
import yaml
from mmusv.errors import ConfigError, IoError
from mmusv.generate import generate, load_spec
from mmusv.generate import runner as gen_runner

TINY: dict[str, Any] = {
    "name": "tiny",
    "seed": 5,
    "map": {"type": "open_sea", "seed": 2},
    "acquisition": {"frequency_hz": 5, "frames": 2},
    "rig": "usv_lidar",
    "rigs": {"usv_lidar": {"preset": "lidar_only", "lidar": {"channels": 16}}},
    "combinations": [
        {"family": "crossing", "difficulty": "easy", "cooperating": 1, "targets": ["small"], "quota": 2},
        {"family": "head_on", "difficulty": "easy", "cooperating": 1, "targets": ["medium"], "quota": 1},
    ],
}
"""Three scenarios on the open sea, generated in a second or two, recorded LiDAR-only in a second each."""

JOURNAL = ".generate.partial"
"""Where a run names each scenario file before writing it (mmusv.generate.runner.JOURNAL)."""

FILES = ["crossing_easy_2usv_small_000.yaml", "crossing_easy_2usv_small_001.yaml", "head_on_easy_2usv_medium_000.yaml"]


class Stop(KeyboardInterrupt):
    """The Ctrl-C of a test, raised from a progress callback."""


def _stop_after_first(name: str, accepted: int, attempts: int) -> None:
    if accepted >= 1:
        raise Stop


@pytest.fixture(scope="module")
def clean(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """TINY generated once, undisturbed: the bytes every restarted run must end with."""
    out = tmp_path_factory.mktemp("clean")
    report = generate(TINY, out)
    assert report.all_met and sorted(p.name for p in out.glob("*.yaml")) == FILES
    return out


def _same_files(a: Path, b: Path) -> None:
    names = sorted(p.name for p in a.iterdir())
    assert names == sorted(p.name for p in b.iterdir())
    _match, mismatch, errors = filecmp.cmpfiles(a, b, names, shallow=False)
    assert not mismatch and not errors


# ------------------------------------------------------------------------------------------- stopped runs


def test_a_generate_run_stopped_before_its_report_is_replaced_by_force(tmp_path: Path, clean: Path) -> None:
    """Ctrl-C after the first accepted scenario left a scenario file and no report.json; the same command with
    --force then refused it forever as "YAML files that no earlier generate run there wrote"."""
    out = tmp_path / "gen"
    with pytest.raises(Stop):
        generate(TINY, out, progress=_stop_after_first)
    assert [p.name for p in out.glob("*.yaml")] == [FILES[0]] and not (out / "report.json").exists()
    assert (out / JOURNAL).read_text(encoding="utf-8").split() == [FILES[0]]
    with pytest.raises(IoError, match=r"stopped before its report\.json; pass --force"):
        generate(TINY, out)
    report = generate(TINY, out, force=True)
    assert report.all_met
    _same_files(out, clean)  # the journal is gone once the report lists every file


def test_a_folder_that_cannot_be_written_is_named_before_any_sampling(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A read-only output folder (simulated: root writes anywhere) was found at the first accepted scenario, after
    its sampling (minutes for a demanding spec), and named a hidden temporary file."""
    out = tmp_path / "ro"
    out.mkdir()
    real = pathlib.Path.write_text

    def read_only(self: Path, *a: Any, **k: Any) -> int:
        if self.parent == out:
            raise OSError(errno.EROFS, "Read-only file system", str(self))
        return real(self, *a, **k)

    drawn: list[int] = []
    real_sample = gen_runner.sample_candidate
    monkeypatch.setattr(pathlib.Path, "write_text", read_only)
    monkeypatch.setattr(gen_runner, "sample_candidate", lambda *a, **k: drawn.append(1) or real_sample(*a, **k))
    with pytest.raises(IoError, match=r"cannot write it: Read-only file system; free space or choose a folder"):
        generate(TINY, out)
    assert drawn == []


def test_a_full_disk_names_the_file_keeps_what_was_written_and_leaves_no_temporary(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, clean: Path
) -> None:
    """The disk filled up while the second scenario was written: the CLI said only "No space left on device" (the
    OSError of a write names no file), the half-written temporary stayed, and the folder was refused thereafter."""
    out = tmp_path / "full"
    real = pathlib.Path.write_text

    def full(self: Path, data: str, *a: Any, **k: Any) -> int:
        if self.name == f".{FILES[1]}.tmp":
            real(self, data[:20], *a, **k)  # what a full disk leaves: the start of the file
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, data, *a, **k)

    monkeypatch.setattr(pathlib.Path, "write_text", full)
    with pytest.raises(IoError, match=rf"{FILES[1]}: cannot write it: No space left on device; the 1 scenario file"):
        generate(TINY, out)
    assert sorted(p.name for p in out.iterdir()) == sorted([FILES[0], JOURNAL])
    monkeypatch.setattr(pathlib.Path, "write_text", real)
    generate(TINY, out, force=True)  # space freed: the same command with --force finishes it
    _same_files(out, clean)


def test_an_earlier_run_is_refused_before_the_maps_are_built(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Generating into a folder of an earlier run without --force built every map of the spec (seconds for the
    bundled coop_detection) before saying so; the CLI too."""
    from mmusv.generate import mapctx
    from mmusv.generate.cli import add_parser, run

    out = tmp_path / "gen"
    generate(TINY, out)
    built: list[tuple[Any, ...]] = []

    def counted(*a: Any) -> Any:
        built.append(a)
        return SimpleNamespace(scene=None)

    monkeypatch.setattr(gen_runner, "map_context", counted)
    monkeypatch.setattr(mapctx, "map_context", counted)
    with pytest.raises(IoError, match="--force"):
        generate(TINY, out)
    spec = tmp_path / "tiny.yaml"
    spec.write_text(yaml.safe_dump(TINY), encoding="utf-8")
    sub = argparse.ArgumentParser().add_subparsers()
    args = add_parser(sub).parse_args([str(spec), "-o", str(out), "--no-progress"])
    with pytest.raises(IoError, match="--force"):
        run(args)
    assert built == []


def test_the_spec_in_its_output_folder_is_named_at_once(tmp_path: Path) -> None:
    """``mmusv generate DIR/spec.yaml -o DIR`` said "already holds scenario files; pass --force", and with --force
    that the folder holds a file no run wrote: two commands to learn that the spec itself is in the way."""
    from mmusv.generate.cli import add_parser, run

    spec = tmp_path / "tiny.yaml"
    spec.write_text(yaml.safe_dump(TINY), encoding="utf-8")
    sub = argparse.ArgumentParser().add_subparsers()
    args = add_parser(sub).parse_args([str(spec), "-o", str(tmp_path), "--no-progress"])
    with pytest.raises(IoError, match=r"tiny\.yaml; the spec itself"):
        run(args)
    assert spec.is_file()


def test_ctrl_c_says_how_to_start_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Ctrl-C printed "mmusv: interrupted" alone; the files left and the way on (--force) were not said."""
    from mmusv.generate.cli import add_parser, run

    def stopped(*a: Any, **k: Any) -> None:
        raise Stop

    monkeypatch.setattr(gen_runner, "generate", stopped)
    spec = tmp_path / "tiny.yaml"
    spec.write_text(yaml.safe_dump(TINY), encoding="utf-8")
    sub = argparse.ArgumentParser().add_subparsers()
    args = add_parser(sub).parse_args([str(spec), "-o", str(tmp_path / "out"), "--no-progress"])
    with pytest.raises(Stop):
        run(args)
    assert "run the same command with --force" in capsys.readouterr().err


# ------------------------------------------------------------------------------------------- the spec


def _with(path: str, value: Any) -> dict[str, Any]:
    spec = copy.deepcopy(TINY)
    *keys, last = path.split(".")
    cur: Any = spec
    for k in keys:
        cur = cur[int(k)] if k.isdigit() else cur.setdefault(k, {})
    cur[last] = value
    return spec


@pytest.mark.parametrize(
    ("path", "value", "field"),
    [
        ("seed", True, "seed"),
        ("combinations.0.quota", True, r"combinations\[0\]\.quota"),
        ("combinations.0.cooperating", True, r"combinations\[0\]\.cooperating"),
        ("combinations.0.max_attempts", True, r"combinations\[0\]\.max_attempts"),
        ("max_attempts_per_scenario", True, "max_attempts_per_scenario"),
        ("check_step_m", True, "check_step_m"),
        ("proposals", True, "proposals"),
        ("constraints.separation.min_m", True, r"constraints\.separation\.min_m"),
        ("constraints.target_density.min_targets", True, r"constraints\.target_density\.min_targets"),
        ("constraints.sensing_range.min_share", False, r"constraints\.sensing_range\.min_share"),
        ("size_classes.small", {"speed_mps": [True, 5]}, r"size_classes\.small\.speed_mps"),
        ("usv", {"speed_mps": [True, 3]}, r"usv\.speed_mps"),
        ("difficulties.easy", {"range_m": [False, 300]}, r"difficulties\.easy\.range_m"),
        ("difficulties.easy", {"extra_targets": [True, 2]}, r"difficulties\.easy\.extra_targets"),
        ("difficulties.easy", {"occluded_share": True}, r"difficulties\.easy\.occluded_share"),
    ],
)
def test_a_spec_takes_no_boolean_for_a_number(path: str, value: Any, field: str) -> None:
    """``quota: true`` generated one scenario, ``speed_mps: [true, 5]`` drew speeds from 1 m/s: Pydantic's lax
    mode, which the scenario files refuse (mmusv.strict), read them as numbers in a spec."""
    with pytest.raises(ConfigError, match=rf"invalid spec {field} = .*(true/false)"):
        load_spec(_with(path, value))


CONTRADICTIONS: list[tuple[dict[str, Any], str]] = [
    (
        {"target_density": {"enabled": True, "min_targets": 3}},
        r"constraints\.target_density\.min_targets = 3: combinations\[0\] \(crossing_easy_2usv_small\) could never "
        r"pass: the combination has at most 1 target",
    ),
    (
        {"separation": {"min_m": 500}},
        r"constraints\.separation\.min_m = 500\.0: .*come within 250 m \(range_m\) and target_range checks it",
    ),
    (
        {"separation": {"min_m": 100}, "cooperation": {"max_m": 80}},
        r"constraints\.separation\.min_m = 100\.0: .*nearest USV to be within 80 m \(max_m\)",
    ),
    (
        {"route_separation": {"min_m": 300, "pairs": ["usv-usv"]}, "cooperation": {"max_m": 200}},
        r"constraints\.route_separation\.min_m = 300\.0: .*nearest USV to be within 200 m \(max_m\)",
    ),
    (
        {"route_separation": {"min_m": 300, "pairs": ["usv-target"]}},
        r"constraints\.route_separation\.min_m = 300\.0: .*come within 250 m \(range_m\)",
    ),
    (
        {"sensing_range": {"range_m": 10}},
        r"constraints\.sensing_range\.range_m = 10\.0: .*none is ever within 10 m",
    ),
    (
        {"target_density": {"enabled": True, "range_m": 12}},
        r"constraints\.target_density\.range_m = 12\.0: .*none is ever within 12 m",
    ),
]


@pytest.mark.parametrize(("constraints", "message"), CONTRADICTIONS)
def test_constraints_that_contradict_are_refused_naming_the_constraint(
    constraints: dict[str, Any], message: str
) -> None:
    """Each of these could never produce a scenario; the run spent quota x max_attempts_per_scenario attempts (4M
    for a quota of 100,000) and its report named only the check that rejected most, as if more attempts might do."""
    spec = dict(TINY, constraints=constraints)
    with pytest.raises(ConfigError, match=message):
        load_spec(spec)


def test_a_lone_ego_must_sense_its_target() -> None:
    """With no cooperating USV, a target kept farther from the ego than the sensing range is never sensed."""
    spec = dict(
        TINY,
        combinations=[{"family": "crossing", "difficulty": "far", "targets": ["small"]}],
        difficulties={"far": {"range_m": [1500, 2000]}},
        constraints={"sensing_range": {"range_m": 1000}},
    )
    with pytest.raises(ConfigError, match=r"constraints\.sensing_range\.range_m = 1000\.0: .*at least 1500 m away"):
        load_spec(spec)
    spec["combinations"] = [dict(spec["combinations"][0], cooperating=1)]  # a cooperating USV may sense it
    assert load_spec(spec).combinations[0].cooperating == 1


def test_bounds_that_just_meet_are_accepted() -> None:
    """The contradiction checks are exact: thresholds equal to each other stay possible."""
    spec = dict(
        TINY,
        constraints={
            "separation": {"min_m": 250},
            "cooperation": {"max_m": 250},
            "sensing_range": {"range_m": 250},
            "target_density": {"enabled": True, "min_targets": 1, "range_m": 250},
        },
    )
    assert load_spec(spec).constraints.separation.min_m == 250


# ------------------------------------------------------------------------------------------- mmusv dataset


def _spec_file(folder: Path, spec: dict[str, Any]) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "spec.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False), encoding="utf-8")
    return path


def _index(out: Path) -> dict[str, Any]:
    return json.loads((out / "dataset.json").read_text(encoding="utf-8"))


def test_a_dataset_run_again_reports_its_shortfall_and_brings_back_a_deleted_scenario(tmp_path: Path) -> None:
    """Run again, ``mmusv dataset`` said "kept (same spec)" and forgot the quota it had not met; a scenario file
    deleted from DIR/scenarios was not generated again, and the dataset silently held one recording fewer."""
    from mmusv.batch.dataset import build_dataset

    short = copy.deepcopy(TINY)
    short["combinations"][1].update(quota=2, max_attempts=1)  # one attempt: at most one of two
    spec = _spec_file(tmp_path, short)
    out = tmp_path / "ds"
    first = build_dataset(spec, out_dir=out)
    assert first.ok and first.shortfall == ["head_on_easy_2usv_medium: 1 of 2"]
    again = build_dataset(spec, out_dir=out)
    assert not again.generated and again.shortfall == first.shortfall
    (out / "scenarios" / FILES[0]).unlink()
    third = build_dataset(spec, out_dir=out)
    assert third.generated and third.shortfall == first.shortfall
    assert (out / "scenarios" / FILES[0]).is_file()
    assert [r["scenario_file"] for r in _index(out)["recordings"]] == FILES
    assert all(o.status == "skipped" for o in third.batch.outcomes)  # the same bytes: nothing recorded twice


def test_a_dataset_stopped_while_generating_is_finished_by_the_same_command(tmp_path: Path, clean: Path) -> None:
    """Ctrl-C while ``mmusv dataset`` generated printed "run the same command again to record the rest", and the
    same command then refused DIR/scenarios for holding files no generate run wrote."""
    from mmusv.batch.dataset import build_dataset

    spec = _spec_file(tmp_path, TINY)
    out = tmp_path / "ds"

    def stop(stage: str, done: int, total: int) -> None:
        if stage == "generate" and done >= 1:
            raise Stop

    with pytest.raises(Stop):
        build_dataset(spec, out_dir=out, progress=stop)
    assert [p.name for p in (out / "scenarios").glob("*.yaml")] == [FILES[0]]
    rep = build_dataset(spec, out_dir=out)
    assert rep.ok and rep.generated
    doc = _index(out)
    assert [r["scenario_file"] for r in doc["recordings"]] == FILES
    assert {r["status"] for r in doc["recordings"]} == {"complete"} and doc["opv2v"]["status"] == "complete"
    for f in FILES:
        assert filecmp.cmp(out / "scenarios" / f, clean / f, shallow=False)


def test_a_full_disk_while_converting_names_the_folder_and_the_way_on(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A full disk during the OPV2V conversion ended ``mmusv dataset`` with "No space left on device" alone."""
    from mmusv.batch.dataset import build_dataset

    export_convert = importlib.import_module("mmusv.export.conversion")
    spec = _spec_file(tmp_path, dict(TINY, combinations=TINY["combinations"][1:]))
    out = tmp_path / "ds"
    real = export_convert.convert

    def full(*a: Any, **k: Any) -> Any:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(export_convert, "convert", full)
    with pytest.raises(IoError, match=r"opv2v: converting the recordings to OPV2V failed: No space left on device; "):
        build_dataset(spec, out_dir=out)
    assert [r["status"] for r in _index(out)["recordings"]] == ["complete"]
    monkeypatch.setattr(export_convert, "convert", real)
    rep = build_dataset(spec, out_dir=out)
    assert rep.converted == 2 and _index(out)["opv2v"]["status"] == "complete"


def test_a_run_stopped_before_its_first_file_is_no_earlier_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A guard of the journal: stopped before any scenario was accepted, a run leaves only its empty journal, and
    the next run needs no --force."""
    out = tmp_path / "gen"

    def stop(*a: Any, **k: Any) -> None:
        raise Stop

    with monkeypatch.context() as m:
        m.setattr(gen_runner, "sample_candidate", stop)
        with pytest.raises(Stop):
            generate(TINY, out)
    assert [p.name for p in out.iterdir()] == [JOURNAL]
    assert generate(TINY, out).all_met
