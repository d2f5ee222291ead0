"""Defects an earlier user round reported and left open, each test failing before its fix: a stop while `mmusv run`
opened its recording left a `.partial` without its manifest (and sensors) metadata, which `info` called "not written
by mmusv run" and `recover` refused; `dataset.json` counted the frames of a failed recording as the dataset's; a
batch on a Ray cluster it could not join wrote an index of pending scenarios; `mmusv generate` had no `--seed`;
`mmusv info` said 0 frames of a killed `--split-frames` run whose parts held them all; an island map whose islands
do not fit was found only when the run built its world."""

from __future__ import annotations

import copy
import json
import signal
from pathlib import Path
from typing import Any

import pytest
from mcap_rechunk import killed_copy, no_ray_cluster
from mmusv.batch import build_dataset, read_index, run_many
from mmusv.cli import main
from mmusv.config import load_scenario
from mmusv.errors import ConfigError, IoError, MmusvError
from mmusv.generate import load_spec
from mmusv.recording.info import read_info
from mmusv.world.map_params import IslandParams
from tiny_scenario import lidar_scenario

from .conftest import SPEC as BATCH_SPEC
from .conftest import tree, write

SPEC: dict[str, Any] = {**BATCH_SPEC, "name": "leftset", "acquisition": {"frequency_hz": 5, "frames": 2}}
"""Three tiny LiDAR-only scenarios of two frames on the open sea."""


def _cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """``mmusv argv`` in this process: ``(exit status, stdout, stderr)``, rich's line breaks joined."""
    code = main(argv)
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err, out + err
    return code, out.replace("\n", " "), err


# ------------------------------------------------------------------------------------------------ a stop


@pytest.mark.parametrize(
    ("record", "signum"),
    [("scenario", signal.SIGINT), ("manifest", signal.SIGINT), ("sensors", signal.SIGTERM)],
)
def test_a_stop_while_the_recording_opens_leaves_a_run_that_says_what_it_is(
    record: str,
    signum: signal.Signals,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A SIGINT or SIGTERM that came as the recording's metadata record ``record`` was being written left a
    `.partial` without it (or without what followed it), which `mmusv info` called an MCAP not written by mmusv
    run and `mmusv recover` refused, and no manifest.json. Now the stop is held until the recording is open and
    ends the run as a stop during a frame does: the recording finished as interrupted, its manifest.json written."""
    from mmusv.recording import writer

    src = write(tmp_path / "s.yaml", lidar_scenario("stopme", frames=2))
    out = tmp_path / "out"
    real = writer.Recording.metadata

    def metadata(self: Any, name: str, mapping: Any) -> None:
        if name == record:
            signal.raise_signal(signum)  # a Ctrl-C or a kill while the recording opens
        real(self, name, mapping)

    monkeypatch.setattr(writer.Recording, "metadata", metadata)
    code, _out, err = _cli(["run", str(src), "-o", str(out)], capsys)
    monkeypatch.undo()
    assert code == 128 + signum, err
    for partial in out.glob("*.partial"):  # none is left now; one that is must say what it is
        read_info(partial)
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["status"] == "interrupted" and manifest["frames_written"] == 0, manifest
    info = read_info(out / "stopme.mcap")
    assert info.run["status"] == "interrupted" and info.config_hash == manifest["config_hash"]
    code, text, err = _cli(["info", str(out)], capsys)
    assert code == 1 and "not written by mmusv run" not in text and "status interrupted" in text, (
        text,
        err,
    )  # no frame


def test_held_signals_hand_a_stop_on_once_released() -> None:
    """The hold itself: signals while held reach no handler; released, the handler in place gets the first, once,
    and is the handler again."""
    from mmusv.recording.guard import HeldSignals

    calls: list[int] = []

    def handler(signum: int, _frame: object) -> None:
        calls.append(signum)

    old = signal.signal(signal.SIGINT, handler)
    try:
        with HeldSignals() as held:
            signal.raise_signal(signal.SIGINT)
            signal.raise_signal(signal.SIGINT)
            assert calls == [] and held.noted == signal.SIGINT
        assert calls == [signal.SIGINT] and signal.getsignal(signal.SIGINT) is handler
    finally:
        signal.signal(signal.SIGINT, old)


# ------------------------------------------------------------------------------------------------ dataset.json


def test_dataset_json_counts_the_frames_of_complete_recordings_only(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A recording that failed after writing frame 0 added that frame to `totals.frames` (5 frames for a dataset of
    4, the 4 converted to OPV2V); now the totals count the complete recordings' frames, and say the failed one and
    the frames it wrote apart."""
    from mmusv.simulation import Simulation

    real = Simulation.capture

    def capture(self: Simulation, k: int, *args: Any, **kwargs: Any) -> Any:
        if k == 1 and self.scenario.name.startswith("head_on"):
            raise MmusvError("the capture of frame 1 fails")
        return real(self, k, *args, **kwargs)

    monkeypatch.setattr(Simulation, "capture", capture)
    rep = build_dataset(write(tmp_path / "s.yaml", SPEC), out_dir=tmp_path / "d")
    assert rep.batch.summary().startswith("2 done, 1 failed")
    doc = read_index(tmp_path / "d")
    failed = [r for r in doc["recordings"] if r["status"] == "failed"]
    assert [r["frames"] for r in failed] == [1]  # the entry still says what that recording wrote
    totals = doc["totals"]
    assert totals["complete"] == 2 and totals["failed"] == 1
    assert totals["frames"] == 4 == doc["opv2v"]["frames"] and totals["frames_incomplete"] == 1, totals


# ------------------------------------------------------------------------------------------------ Ray


def test_a_ray_batch_that_cannot_join_its_cluster_writes_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """`--ray ADDRESS` with no cluster there wrote dataset.json calling every scenario pending (and readied their
    folders) before it failed; now it fails first, leaving a new output folder unmade and an earlier index as it
    was."""
    src = tmp_path / "src"
    src.mkdir()
    write(src / "a.yaml", lidar_scenario("a", frames=1))
    out = tmp_path / "out"
    assert run_many(src, out_dir=out).ok
    before = tree(out)
    write(src / "b.yaml", lidar_scenario("b", frames=1))  # something to run
    no_ray_cluster(monkeypatch)
    with pytest.raises(IoError, match=r"--ray auto: cannot start or join Ray: Could not find any running Ray"):
        run_many(src, out_dir=out, ray="auto")
    assert tree(out) == before and not (out / "b").exists()
    fresh = tmp_path / "fresh"
    code, _out, err = _cli(["run", str(src), "-o", str(fresh), "--ray", "auto"], capsys)
    assert code == 2 and err.startswith("mmusv: error: --ray auto: cannot start or join Ray"), err
    assert not fresh.exists()


# ------------------------------------------------------------------------------------------------ generate --seed


def test_generate_seed_replaces_the_spec_seed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`mmusv generate --seed N` generates, byte for byte, what the spec with `seed: N` does (report.json says N),
    and refuses a seed outside the spec's range before writing anything."""
    spec = write(tmp_path / "s.yaml", SPEC)
    seeded = write(tmp_path / "s5.yaml", {**copy.deepcopy(SPEC), "seed": 5})
    code, _out, err = _cli(["generate", str(spec), "-o", str(tmp_path / "a"), "--seed", "5", "--no-progress"], capsys)
    assert code == 0, err
    code, _out, err = _cli(["generate", str(seeded), "-o", str(tmp_path / "b"), "--no-progress"], capsys)
    assert code == 0, err
    assert tree(tmp_path / "a") == tree(tmp_path / "b") and len(tree(tmp_path / "a")) == 4
    assert json.loads((tmp_path / "a/report.json").read_text())["seed"] == 5 != SPEC["seed"]
    for bad in ("-1", "9223372036854775808", "abc", "1.5", ""):
        code, _out, err = _cli(["generate", str(spec), "-o", str(tmp_path / "c"), f"--seed={bad}"], capsys)
        assert code == 2 and f"--seed {bad!r}: must be a whole number in 0..9223372036854775807" in err, err
        assert not (tmp_path / "c").exists()
    with pytest.raises(SystemExit):
        main(["generate", "--help"])
    assert "--seed N" in capsys.readouterr().out


# ------------------------------------------------------------------------------------------------ info of parts


def _killed(recording: Path) -> None:
    """``recording`` (a finished part) as a run killed after its last frame leaves it: ``NAME.mcap.partial`` with
    the header, the scenario, manifest and sensors metadata and every message, no ``run`` metadata, no summary;
    the part's manifest.json gone."""
    killed_copy(recording, recording.with_name(recording.name + ".partial"))
    recording.unlink()
    (recording.parent / "manifest.json").unlink()


def test_info_of_a_killed_split_run_counts_the_frames_its_parts_hold(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Both parts of a `--split-frames 2` run of 4 frames killed after their last frame: `mmusv info` said "0
    frames" (a part without `run` metadata counted 0), and a killed whole run's `.partial` "? frames"."""
    src = write(tmp_path / "tiny.yaml", lidar_scenario("tiny", frames=4))
    out = tmp_path / "out"
    assert main(["run", str(src), "-o", str(out), "--split-frames", "2"]) == 0
    capsys.readouterr()
    parts = sorted((out / "tiny/parts").glob("*/tiny.mcap"))
    assert len(parts) == 2
    for part in parts:
        _killed(part)
    info = read_info(out / "tiny/tiny.parts.json")
    assert info.run["status"] == "incomplete (0 of 2 parts complete)" and info.run["frames_written"] == "4"
    code, text, err = _cli(["info", str(out / "tiny")], capsys)
    assert code == 0 and "status incomplete (0 of 2 parts complete), 4 frames" in text, (text, err)
    code, text, err = _cli(["info", str(parts[0].parent)], capsys)
    assert code == 0 and "is still going), 2 frames" in text and "? frames" not in text, (text, err)


# ------------------------------------------------------------------------------------------------ island maps


def test_an_island_map_whose_islands_do_not_fit_is_refused_when_it_loads(tmp_path: Path) -> None:
    """Twelve islands of 150..200 m in a 1000 m map loaded and validated; only the run's world build said they do
    not fit. Now the scenario and a spec with that map are refused when they load, naming the file, the field and
    what to change."""
    params: dict[str, Any] = {"extent_m": 1000, "n_islands": 12, "island_radius_m": [150, 200]}
    crowded = {"type": "island", "seed": 3, "params": params}
    sc = lidar_scenario("crowded", frames=1)
    sc["map"] = crowded
    path = write(tmp_path / "crowded.yaml", sc)
    with pytest.raises(ConfigError) as exc:
        load_scenario(path)
    msg = str(exc.value)
    assert msg.startswith(f"{path}: invalid config map.params.n_islands = 12: fewer or smaller islands"), msg
    assert "island_radius_m [150, 200]" in msg and "extent_m = 1000" in msg and "min_gap_m = 120" in msg, msg
    with pytest.raises(ConfigError, match=r"invalid spec map\.params\.n_islands = 12: fewer or smaller islands"):
        load_spec({**copy.deepcopy(SPEC), "map": crowded})
    roomy = {**crowded, "params": {**params, "n_islands": 2}}
    loaded = load_scenario({**sc, "map": roomy}).map.params  # islands that fit still load
    assert isinstance(loaded, IslandParams) and loaded.n_islands == 2
