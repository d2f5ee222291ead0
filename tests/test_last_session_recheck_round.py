"""An independent re-check of the last session's changes (f604d94..869c9e8): the recorder's first chunk of schemas
and channels, the motion transients at a route's stop or turn about, the mount of a camera given none, the sea's
``wind_10m_mps`` and the ``under_keel`` warning, each from the Python side with small setups.

Found (each test below failed before its fix, or is a strict xfail where the fix is in the core):

* A camera without a ``mount`` sits on the asset's ``camera_<name>`` point (9ab784d), but the run's resolved
  ``scenario.yaml`` (and the recording's ``scenario`` metadata) wrote its mount out in full (``point: null``, zero
  offsets), and that file read back put the camera at the vessel origin, midship at the waterline: ``mmusv run
  out/scenario.yaml`` recorded a WAM-V's ``left`` camera at z = 0 m instead of 1.75 m, with the same
  ``config_hash`` (:func:`test_a_run_of_the_resolved_scenario_puts_its_cameras_where_the_run_did`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import yaml


def _camera_scenario() -> dict[str, Any]:
    """A WAM-V with two 32 x 24 RGB cameras given no mount: ``left`` (the asset's ``camera_left`` point) and
    ``mast`` (no such point: ``camera_front``)."""
    cameras = [{"name": name, "resolution": [32, 24], "outputs": ["rgb"]} for name in ("left", "mast")]
    return {
        "name": "cams",
        "seed": 1,
        "map": {"type": "open_sea", "seed": 0},
        "acquisition": {"frames": 1},
        "environment": {"motion": "paper"},
        "rigs": {"r": {"lidar": None, "radar": None, "top_view": None, "cameras": cameras}},
        "vessels": [
            {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": [[0, 0], [50, 0]]}
        ],
    }


def test_a_run_of_the_resolved_scenario_puts_its_cameras_where_the_run_did(tmp_path: Path) -> None:
    """The run folder's ``scenario.yaml`` is the resolved scenario, and the recording's ``scenario`` metadata the same
    text: read back, its cameras must sit where the run's did (measured before the fix: the ``left`` camera at
    (0, 0, 0) m instead of the ``camera_left`` point's (0.45, 0.12, 1.75) m, the same config hash)."""
    from mmusv.acquire import run
    from mmusv.config import load_scenario, scenario_hash
    from mmusv.simulation import Simulation

    run(_camera_scenario(), out_dir=tmp_path)
    written = yaml.safe_load((tmp_path / "scenario.yaml").read_text(encoding="utf-8"))
    first = Simulation(_camera_scenario()).agents[0].mounts()
    again = Simulation(written).agents[0].mounts()
    assert first["camera/left"][2, 3] > 1.0  # on the asset's camera_left point, above the water
    for key in ("camera/left", "camera/mast"):
        np.testing.assert_array_equal(again[key], first[key], err_msg=key)
    assert scenario_hash(load_scenario(written)) == scenario_hash(load_scenario(_camera_scenario()))
