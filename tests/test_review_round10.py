"""Review of d2da72c..d888fe0: the stops a library swallows or wraps (``held_signals``), the name-keyed draws of
``mmusv generate``, the buoys on their waterplane, the moored ships that float.

Three loops still went on past a swallowed stop:

* ``mmusv study agreement`` (:func:`mmusv.studies.agreement.run_agreement_study`) captures every frame of every
  scenario, minutes of work, with no ``raise_noted_stop``: a stop whose ``KeyboardInterrupt`` a library swallowed
  ran the study to its end (45e86dd's "every long loop" left it out).
* ``mmusv train``'s cache (:func:`mmusv.learn.cache.build_cache`) loads every sequence of the dataset before the
  first training step, with no ``raise_noted_stop``: a stop swallowed while one loaded loaded all the others.
* a pool worker's handler (:func:`mmusv.batch.executors._stop`, SIGTERM/SIGINT in a ``--jobs N`` worker) raised
  ``KeyboardInterrupt`` without noting the stop: one a library swallowed in a frame was never raised again (the
  worker recorded on, ignoring the driver's further SIGTERMs, until it was killed after ``_REAP_S``, leaving a
  ``.partial`` with no manifest), and one a library wrapped in an error of its own was recorded ``failed`` with that
  error, as 298477f fixed for the serial batch only.

And a stop of ``mmusv study detection --jobs N`` (45e86dd raises a swallowed one after each wait; a plain SIGTERM
lands there too) left the loop inside ``with ProcessPoolExecutor``, whose exit waits for every sequence submitted:
the study ran all of them before it ended as stopped (:func:`mmusv.batch.executors.stop_pool`).

The rest was checked apart from the code under test and found as described (see the report of this round): the
waterplane weights against a plane fitted over the disc to a single plane wave in any direction, the phase against
``WaveField.elevation``; the replacement ship inside its berth's footprint and touching the same face, quay and pier.
"""

from __future__ import annotations

import json
import signal
from collections.abc import Iterator
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
import yaml
from mmusv.held_signals import note_stop
from test_review_round9 import _TINY  # a 4-frame LiDAR-only scenario that records in a second


@pytest.fixture(autouse=True)
def _forget_the_stop() -> Iterator[None]:
    note_stop(None)
    yield
    note_stop(None)


def test_the_agreement_study_captures_no_frame_after_a_swallowed_stop(monkeypatch: Any) -> None:
    # Two scenarios of 50 frames, no agent (nothing to sample): only the captures are counted. The command's
    # handler noted the stop during the first capture and a library swallowed its KeyboardInterrupt there.
    import mmusv.studies.agreement as agreement

    captures: list[tuple[str, int]] = []

    class Sim:
        def __init__(self, sc: Any) -> None:
            self.sc = sc
            self.agents: list[Any] = []
            self.vessels: list[Any] = []

        def capture(self, k: int, **kwargs: Any) -> Any:
            captures.append((self.sc.name, k))
            if len(captures) == 1:
                note_stop(signal.SIGINT)  # ... and the KeyboardInterrupt raised after it was swallowed
            return SimpleNamespace(world=None, agents={})

    scenarios = [
        SimpleNamespace(name=n, acquisition=SimpleNamespace(frames=50), map=SimpleNamespace(type="open_sea"))
        for n in ("a", "b")
    ]
    monkeypatch.setattr(agreement, "load_scenarios", lambda given: list(given))
    monkeypatch.setattr(agreement, "Simulation", Sim)
    with pytest.raises(KeyboardInterrupt):
        agreement.run_agreement_study(scenarios)  # type: ignore[arg-type]
    assert captures == [("a", 0)]  # before: all 100 frames of both scenarios, then the tables


def _record_with_a_worker_stop(tmp_path: Path, monkeypatch: Any, *, how: str) -> dict[str, Any]:
    """The tiny scenario recorded as in a pool worker running a task (``executors._IN_TASK``) whose stop handler,
    called during frame 1's capture as the driver's SIGTERM would call it, raises ``KeyboardInterrupt`` where a
    "library" swallows it (``how="swallow"``) or wraps it in an error of its own (``"wrap"``); the manifest."""
    import mmusv.batch.executors as executors
    import mmusv.simulation as simulation
    from mmusv.acquire import run

    monkeypatch.setattr(executors, "_IN_TASK", True)
    monkeypatch.setattr(executors, "_STOPPING", False)
    original = simulation.Simulation.capture

    def capture(self: Any, frame: int, **kwargs: Any) -> Any:
        if frame == 1:
            try:
                executors._stop(signal.SIGTERM, None)
            except KeyboardInterrupt as exc:
                if how == "wrap":
                    raise RuntimeError("Error calling __set_name__ on 'Field' instance") from exc
        return original(self, frame, **kwargs)

    monkeypatch.setattr(simulation.Simulation, "capture", capture)
    scenario = tmp_path / "tiny.yaml"
    scenario.write_text(yaml.safe_dump(_TINY), encoding="utf-8")
    with pytest.raises(KeyboardInterrupt):
        run(scenario, out_dir=tmp_path / "out")
    manifest: dict[str, Any] = json.loads((tmp_path / "out" / "manifest.json").read_text(encoding="utf-8"))
    return manifest


def test_a_stop_swallowed_in_a_pool_worker_s_frame_ends_its_recording_at_the_next_frame(
    tmp_path: Path, monkeypatch: Any
) -> None:
    # Before: the worker recorded all 4 frames ("complete", no KeyboardInterrupt), in a real batch on until the
    # driver's reaper killed it 15 s later, the recording a .partial without its manifest.
    manifest = _record_with_a_worker_stop(tmp_path, monkeypatch, how="swallow")
    assert manifest["status"] == "interrupted", manifest
    assert manifest["frames_written"] == 2, manifest  # frames 0 and 1; frame 2 not started


def test_a_stop_wrapped_by_a_library_in_a_pool_worker_s_frame_is_recorded_as_interrupted(
    tmp_path: Path, monkeypatch: Any
) -> None:
    # Before: the RuntimeError left the recording "failed" with that error (the batch's task: "internal error").
    manifest = _record_with_a_worker_stop(tmp_path, monkeypatch, how="wrap")
    assert manifest["status"] == "interrupted", manifest
    assert "RuntimeError" not in json.dumps(manifest), manifest


class _SlowSequences:
    """A stand-in for :class:`mmusv.studies.detection.sources.Dataset` (pickled to the study's worker processes):
    each sequence's load leaves a file named after it in ``folder``, waits ``seconds`` and fails as bad input."""

    def __init__(self, folder: str, names: list[str], seconds: float) -> None:
        self.folder, self.seconds = folder, seconds
        self.sources = {n: Path(folder) / n for n in names}

    def frames_by_sequence(self) -> dict[str, int]:
        return dict.fromkeys(self.sources, 1)

    def load(self, name: str) -> Any:
        import time

        from mmusv.errors import InputError

        (Path(self.folder) / name).touch()
        time.sleep(self.seconds)
        raise InputError(f"{name}: not a sequence (a stand-in)")


def test_a_stop_of_the_detection_study_s_jobs_runs_no_further_sequence(tmp_path: Path, monkeypatch: Any) -> None:
    # `mmusv study detection --jobs N` over more sequences than processes: a stop (here a swallowed one, noted and
    # raised again after the first sequence's result, as 45e86dd does; a plain SIGTERM raises at the same place)
    # left the loop inside `with ProcessPoolExecutor`, whose exit waits for every sequence submitted: the study
    # ran all of them (hours on a large dataset) before it ended as stopped.
    import signal

    import mmusv.studies.detection.parallel as parallel
    from mmusv.studies.detection.study import StudyOptions

    names = [f"s{k}" for k in range(6)]
    original = parallel.wait

    def wait(*args: Any, **kwargs: Any) -> Any:
        done = original(*args, **kwargs)
        note_stop(signal.SIGINT)  # the stop's KeyboardInterrupt was swallowed meanwhile
        return done

    monkeypatch.setattr(parallel, "wait", wait)
    dataset = _SlowSequences(str(tmp_path), names, seconds=0.5)
    with pytest.raises(KeyboardInterrupt):
        parallel.run_study_jobs(dataset, options=StudyOptions(), spec=parallel.DetectorSpec(), jobs=1)  # type: ignore[arg-type]
    loaded = sorted(p.name for p in tmp_path.iterdir())
    # the first, and at most the one the pool had already handed its process: not the other four
    assert len(loaded) <= 2, loaded


def test_the_training_cache_loads_no_sequence_after_a_swallowed_stop(tmp_path: Path, monkeypatch: Any) -> None:
    # `mmusv train` packs its dataset into a cache first, loading each sequence when reached (minutes for a large
    # dataset): a stop swallowed while the first loaded went on to load every other one before the training's
    # steps raised it.
    import mmusv.learn.cache as cache
    import mmusv.studies.detection.sources as sources

    loaded: list[str] = []

    class Sequences:
        def sequences(self) -> Iterator[Any]:
            for name in ("a", "b", "c", "d"):
                loaded.append(name)
                if name == "a":
                    note_stop(signal.SIGINT)  # ... and the KeyboardInterrupt raised after it was swallowed
                yield SimpleNamespace(name=name, frames=[], agent_ids=[])

    monkeypatch.setattr(sources, "resolve_dataset", lambda *args, **kwargs: Sequences())
    monkeypatch.setattr(cache, "dataset_fingerprints", lambda ds: {})
    with pytest.raises(KeyboardInterrupt):  # before: all four loaded, then "no frame to cache" (an InputError)
        cache.build_cache([], tmp_path / "cache.npz")
    assert loaded == ["a"]
