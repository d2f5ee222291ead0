"""A review of the day's changes (the split of ``simulation.py``, ``Agent`` pickling, the maritime round, the
editor, the KITTI fix, the apparent contrast and ``--min-contrast``), each test failing before its fix:

- ``mmusv generate``'s top speeds by vessel type (``TOP_SPEED_MPS``) capped a target's drawn speed and the faster
  overtaking branch, but two families still gave a target a speed of their own: an overtaking target drawn slower
  than the ego (the ego's speed less 0.8-1.5 m/s) and every convoy member (the convoy sails at the USV's drawn
  speed). With USVs at 5-6 m/s a kayak (top 3 m/s) was overtaken at 4-5 m/s and paddled in a convoy at 5-6 m/s.
  Both are now capped at the type's top speed (the convoy at its slowest member's; one draw as before).
- ``min_contrast`` refused a value with a message naming the bound it broke as allowed: ``min_contrast = 3295:
  must be a Weber contrast >= 0 and <= 3295`` (the bound is 255 x 12.92 = 3294.6, shown rounded to 3295), and
  ``docs/exports.md`` said "a number from 0 to 3295". The bound is shown as 3294.6.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.errors import ConfigError
from mmusv.export.contrast import MAX_CONTRAST
from mmusv.export.conversion import _contrast_filter

KAYAK_TOP_MPS = 3.0


def _target_speeds(spec: dict[str, Any], out: Path) -> list[tuple[str, float]]:
    from mmusv.generate.runner import generate

    generate(spec, out)
    return [
        (v["asset"], float(v["speed_mps"]))
        for f in sorted(out.glob("*.yaml"))
        for v in yaml.safe_load(f.read_text(encoding="utf-8"))["vessels"]
        if v["role"] != "usv"
    ]


@pytest.mark.parametrize(("family", "targets"), [("overtaking", 1), ("convoy", 2)])
def test_fast_usvs_do_not_speed_up_a_kayak_past_its_top_speed(tmp_path: Path, family: str, targets: int) -> None:
    """USVs at 5-6 m/s with kayaks (top 3 m/s): an overtaking kayak drawn slower than the ego was given the ego's
    speed less 0.8-1.5 m/s (4.05 and 4.84 m/s with this seed) and a convoy of kayaks sailed at the USV's speed
    (5.0-5.4 m/s); now every kayak stays at or below 3 m/s."""
    spec = {
        "name": f"fast_usvs_{family}",
        "seed": 5,
        "map": {"type": "open_sea", "seed": 1},
        "acquisition": {"frequency_hz": 1, "frames": 20},
        "usv": {"assets": ["usv_wamv"], "speed_mps": [5, 6]},
        "size_classes": {"small": {"assets": ["kayak_4m"], "speed_mps": [3, 10]}},
        "combinations": [{"family": family, "difficulty": "easy", "targets": ["small"] * targets, "quota": 3}],
    }
    speeds = _target_speeds(spec, tmp_path / "out")
    assert len(speeds) == 3 * targets
    for asset, speed in speeds:
        assert asset == "kayak_4m" and 0.0 < speed <= KAYAK_TOP_MPS + 1e-9, (asset, speed)


def test_min_contrast_refusal_names_a_bound_the_value_breaks() -> None:
    """3295 was refused as "<= 3295"; the message now gives the bound as 3294.6, and the bound itself is taken."""
    assert _contrast_filter(MAX_CONTRAST) == MAX_CONTRAST
    with pytest.raises(ConfigError) as err:
        _contrast_filter(3295)
    msg = str(err.value)
    assert msg.startswith("min_contrast = 3295: must be a Weber contrast >= 0 and <= 3294.6 "), msg
