"""The route checks ask the core for their poses in batches (:func:`mmusv.motion.fleet_poses`): a stop ends a
command only between native calls, and the checks of a long scenario asked for all their poses in one call, up to
the 5 M samples of their budget. A pose of the physical motion takes 30–70 µs of CPU on the 2-core EPYC, so Ctrl-C
(or the editor's Stop) during the checks of `mmusv run` did nothing for up to minutes. The batches give the same
samples, bit for bit."""

from __future__ import annotations

import dataclasses
from typing import Any

import mmusv.generate.samples as samples
import mmusv.motion as motion
import numpy as np
import pytest
from mmusv.config import load_scenario
from mmusv.generate.mapctx import map_context
from mmusv.scenario_checks import scenario_samples
from tiny_scenario import lidar_scenario


class _Counted:
    """A ``core.Fleet`` whose ``poses_at_times`` calls are counted (the number of times each call asks for)."""

    def __init__(self, fleet: Any, calls: list[int]) -> None:
        self._fleet, self._calls = fleet, calls

    def __getattr__(self, name: str) -> Any:
        return getattr(self._fleet, name)

    def poses_at_times(self, times: Any) -> Any:
        self._calls.append(len(times))
        return self._fleet.poses_at_times(times)


_BUILD, _FLEET = samples.build_fleet, samples.core.Fleet


def _samples(monkeypatch: pytest.MonkeyPatch, calls: list[int]) -> Any:
    real_build, real_fleet = _BUILD, _FLEET

    class _Core:  # the module's ``core`` with its Fleet counted
        def __getattr__(self, name: str) -> Any:
            if name == "Fleet":
                return lambda **kw: _Counted(real_fleet(**kw), calls)
            return getattr(motion.core, name)

    monkeypatch.setattr(samples, "build_fleet", lambda *a, **kw: _Counted(real_build(*a, **kw), calls))
    monkeypatch.setattr(samples, "core", _Core())
    raw = {**lidar_scenario("batches", frames=400), "environment": {"motion": "physical", "wave": "W3"}}
    return scenario_samples(load_scenario(raw), map_context("open_sea", seed=0, params={}))


def test_the_checks_ask_for_their_poses_in_batches_with_the_same_samples(monkeypatch: pytest.MonkeyPatch) -> None:
    whole_calls: list[int] = []
    whole = _samples(monkeypatch, whole_calls)
    assert max(whole_calls) * 2 <= motion.POSE_BATCH  # one call each: the batch is above these times x 2 vessels
    monkeypatch.setattr(motion, "POSE_BATCH", 64)  # 32 times a call with the 2 vessels
    calls: list[int] = []
    batched = _samples(monkeypatch, calls)
    # was: two calls, of every motion and frame time at once, and of every route sample
    assert len(calls) > len(whole_calls) and max(calls) <= 32, calls
    assert sum(calls) == sum(whole_calls)
    for f in dataclasses.fields(whole):
        a, b = getattr(whole, f.name), getattr(batched, f.name)
        if isinstance(a, np.ndarray):
            assert np.array_equal(a, b), f.name
