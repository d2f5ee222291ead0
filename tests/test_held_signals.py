"""A stop the ``mmusv`` command noted (:func:`mmusv.held_signals.note_stop`) whose ``KeyboardInterrupt`` a library
swallowed still ends every long loop at its next step (:func:`mmusv.held_signals.raise_noted_stop`): the
generator's attempts, the batch's scenarios, the wave studies' settings, the detection study's frames, the
training's steps (tests/learn/test_stops.py). The recording's and the converter's loops are checked end to end in
tests/test_launch.py. Each test here swallows a stop in the middle of the loop (noted as the command's handler
notes it, then not raised) and checks that no step ran after it; each fails where its loop does not look. An error
a library made of the stop leaves a :func:`~mmusv.held_signals.stops_unwrapped` block as the stop (the recording,
the conversion, a batch's task: end to end in tests/test_review_round9.py)."""

from __future__ import annotations

import signal
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.held_signals import is_stop, note_stop, raise_noted_stop, stops_unwrapped

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(autouse=True)
def _forget_the_stop() -> Iterator[None]:
    note_stop(None)
    yield
    note_stop(None)


def _swallowing(original: Callable[..., Any], calls: list[int], *, at: int) -> Callable[..., Any]:
    """``original``, noting a stop (as the command's handler does before it raises) in its call number ``at``
    whose KeyboardInterrupt a library then swallowed; counts the calls in ``calls``."""

    def wrapped(*args: Any, **kwargs: Any) -> Any:
        calls.append(len(calls))
        if len(calls) == at:
            note_stop(signal.SIGINT)  # ... and the KeyboardInterrupt raised after it was swallowed
        return original(*args, **kwargs)

    return wrapped


def test_no_stop_noted_raises_nothing_and_a_noted_one_raises_until_forgotten() -> None:
    raise_noted_stop()
    note_stop(signal.SIGTERM)
    with pytest.raises(KeyboardInterrupt):
        raise_noted_stop()
    with pytest.raises(KeyboardInterrupt):  # still noted: every loop on the way out stops too
        raise_noted_stop()
    note_stop(None)
    raise_noted_stop()


def test_an_error_after_a_noted_stop_leaves_a_stops_unwrapped_block_as_the_stop() -> None:
    # A library that met the stop's KeyboardInterrupt made an error of its own of it (Python 3.11's RuntimeError
    # from __set_name__): the block's caller records the stop (interrupted), not a failure with that error.
    wrapped = RuntimeError("Error calling __set_name__ on 'Field' instance")
    with pytest.raises(RuntimeError), stops_unwrapped():  # no stop noted: errors leave as they are
        raise wrapped
    assert not is_stop(wrapped) and is_stop(KeyboardInterrupt())
    note_stop(signal.SIGTERM)
    assert is_stop(wrapped) and is_stop(KeyboardInterrupt()) and not is_stop(SystemExit(2))
    with pytest.raises(KeyboardInterrupt) as stop, stops_unwrapped():
        raise wrapped
    assert stop.value.__cause__ is wrapped  # the library's error stays in the traceback
    with pytest.raises(KeyboardInterrupt) as plain, stops_unwrapped():  # a plain stop leaves unchanged
        raise KeyboardInterrupt
    assert plain.value.__cause__ is None
    with pytest.raises(SystemExit), stops_unwrapped():
        raise SystemExit(2)
    with stops_unwrapped():  # nothing raised: nothing raised (the loops' raise_noted_stop does that)
        pass


def test_the_generator_makes_no_attempt_after_a_swallowed_stop(tmp_path: Path, monkeypatch: Any) -> None:
    import mmusv.generate.runner as runner

    spec = {
        "name": "stops",
        "seed": 3,
        "map": {"type": "open_sea", "seed": 2},
        "acquisition": {"frequency_hz": 2, "frames": 4},
        "difficulties": {"near": {"range_m": [40, 120]}},
        "combinations": [{"family": "crossing", "difficulty": "near", "targets": ["small"], "quota": 6}],
    }
    calls: list[int] = []
    monkeypatch.setattr(runner, "sample_candidate", _swallowing(runner.sample_candidate, calls, at=2))
    with pytest.raises(KeyboardInterrupt):
        runner.generate(spec, tmp_path / "gen")
    assert calls == [0, 1]  # it went on to its quota of 6 (and more attempts where some were rejected)
    assert not (tmp_path / "gen" / "report.json").exists()  # a stopped generation writes no report


def test_the_batch_starts_no_scenario_after_a_swallowed_stop(tmp_path: Path, monkeypatch: Any) -> None:
    from mmusv.batch import run_many
    from mmusv.batch.executors import SerialExecutor

    folder = tmp_path / "scenarios"
    folder.mkdir()
    for name in ("a", "b", "c"):
        data = {
            "name": name,
            "seed": 1,
            "map": {"type": "open_sea", "seed": 0, "params": {"extent_m": 800, "islet_probability": 0.0}},
            "acquisition": {"frames": 2},
            "rigs": {"r": {"preset": "lidar_only", "lidar": {"channels": 8, "points_per_second": 20480}}},
            "vessels": [
                {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": [[0, 0], [50, 0]]}
            ],
        }
        (folder / f"{name}.yaml").write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    calls: list[int] = []
    original = SerialExecutor.next_done

    def next_done(self: SerialExecutor) -> Any:  # the stop swallowed after the first scenario's last frame
        done = original(self)
        calls.append(len(calls))
        if len(calls) == 1:
            note_stop(signal.SIGINT)
        return done

    monkeypatch.setattr(SerialExecutor, "next_done", next_done)
    with pytest.raises(KeyboardInterrupt):
        run_many(folder, out_dir=tmp_path / "out", jobs=1)
    assert calls == [0]  # it recorded b and c too
    assert sorted(p.parent.name for p in (tmp_path / "out").glob("*/*.mcap")) == ["a"]


def _tiny_usv_scenario() -> Any:
    from mmusv.config import load_scenario

    data = yaml.safe_load((ROOT / "scenarios" / "open_sea_convoy.yaml").read_text(encoding="utf-8"))
    data["acquisition"]["frames"] = 4
    return load_scenario(data)


@pytest.mark.parametrize("study", ["paper", "physical"])
def test_the_wave_studies_compute_no_setting_after_a_swallowed_stop(monkeypatch: Any, study: str) -> None:
    import mmusv.studies.waves as waves

    calls: list[int] = []
    monkeypatch.setattr(waves, "scenario_poses", _swallowing(waves.scenario_poses, calls, at=1))
    with pytest.raises(KeyboardInterrupt):
        if study == "paper":
            waves.run_wave_study(_tiny_usv_scenario(), waves=("W0", "W1", "W2"))
        else:
            waves.run_physical_wave_study(_tiny_usv_scenario(), waves=("W0", "W1", "W2"))
    assert len(calls) == (1 if study == "paper" else 2)  # the physical study reads two poses a setting


def test_the_detection_study_scores_no_frame_after_a_swallowed_stop(tmp_path: Path, monkeypatch: Any) -> None:
    import mmusv.studies.detection.study as study
    from mmusv.acquire import run
    from mmusv.cli import main
    from mmusv.studies.detection.sources import lidar_only

    data = lidar_only(yaml.safe_load((ROOT / "scenarios" / "island_occlusion.yaml").read_text(encoding="utf-8")))
    data["acquisition"]["frames"] = 4
    rec = run(data, out_dir=tmp_path / "rec").recording
    calls: list[int] = []
    frames: list[int] = []

    def score(res: Any, seq: Any, t: int, *args: Any, **kwargs: Any) -> None:
        frames.append(t)
        return original(res, seq, t, *args, **kwargs)

    original = study._score_ego
    monkeypatch.setattr(study, "_score_ego", _swallowing(score, calls, at=1))
    # the CLI: its handler forgets the stop when the command ends, and a stop is status 130
    assert main(["study", "detection", str(rec), "-o", str(tmp_path / "det"), "--no-progress"]) == 130
    assert sorted(set(frames)) == [0]  # every ego of frame 0 (the frame the stop came in), then nothing
    assert not (tmp_path / "det" / "detection_table.csv").exists()
