"""The seeds of the sensors' noise: one 64-bit seed per (scenario seed, frame, agent, sensor, camera), as
:meth:`mmusv.simulation.Simulation.capture` seeds every sensor it runs, so that a capture is a pure function of
the scenario, its seed and the frame."""

from __future__ import annotations

import hashlib

from mmusv import arguments
from mmusv.errors import ConfigError

__all__ = ["sensor_seed"]

_SENSOR_CODES = {"lidar": 1, "radar": 2, "camera": 3, "top_view": 4}


def sensor_seed(scenario_seed: int, *, frame: int, agent: int, sensor: str, index: int = 0) -> int:
    """The 64-bit seed (a whole number in ``0..2**64 - 1``) of one sensor capture: a hash of (scenario seed, frame,
    agent index, sensor, index), as :meth:`mmusv.simulation.Simulation.capture` seeds its sensors.

    Args:
        scenario_seed: the scenario's ``seed``, a whole number in ``0..2**63 - 1`` (as the scenario allows).
        frame: the acquisition index, a whole number >= 0.
        agent: the agent's index (:attr:`mmusv.agents.Agent.index`, its position in the scenario's vessels), a
            whole number >= 0.
        sensor: one of ``lidar``, ``radar``, ``camera``, ``top_view`` (one camera of the rig: ``camera``, with
            ``index`` its position in the rig's cameras).
        index: the camera's position in the rig's cameras (0 for the other sensors), a whole number >= 0.

    Whole numbers are ``int`` or numpy integers (floats and booleans are refused); anything else is a
    ``ConfigError`` naming the argument.
    """
    scenario_seed = arguments.whole(scenario_seed, name="scenario_seed", lo=0, hi=2**63 - 1)
    frame = arguments.whole(frame, name="frame", lo=0)
    agent = arguments.whole(agent, name="agent", lo=0)
    index = arguments.whole(index, name="index", lo=0)
    code = _SENSOR_CODES.get(sensor) if isinstance(sensor, str) else None
    if code is None:
        cameras = isinstance(sensor, str) and sensor == "cameras"  # capture's kind, not one sensor
        hint = " (one camera is 'camera', with index its position in the rig's cameras)" if cameras else ""
        raise ConfigError(
            f"sensor = {arguments.shown(sensor)}: must be one of {', '.join(map(repr, _SENSOR_CODES))}{hint}"
        )
    key = f"{scenario_seed}/{frame}/{agent}/{code}/{index}".encode()
    return int.from_bytes(hashlib.blake2b(key, digest_size=8).digest(), "little")
