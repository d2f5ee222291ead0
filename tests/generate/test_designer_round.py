"""A dataset designer's round on ``mmusv generate``: what a batch holds is checked on the written YAML alone (read
with ``yaml.safe_load``, not with the generator's code), and a spec that asks for what no scenario can hold is
refused naming the field. Each test failed before its fix.

- ``usv.speed_mps`` bounds every USV's speed: port_entry's USVs sailed at 0.3-1 m/s, occluded_by_island's at
  1.5 m/s at most and surround's at 0.8 x the drawn speed, whatever range the spec gave (52 of 150 USVs of seven
  families outside ``[2, 3]``);
- ``difficulties.*.extra_classes: []`` drew the distractors from every size class (an empty list read as "not
  given");
- ``size_classes.*.assets: []`` was refused as ``size_classes.*.length_m = [0.0, 1000.0]``, a field the spec did
  not write;
- a size class none of whose vessels can sail as fast as its ``speed_mps`` low (``assets: [kayak_4m]`` at 6-8
  m/s) was generated at the kayak's 1.5-3 m/s without a word.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml
from mmusv.generate import generate

USV_SPEED = (2.0, 3.0)
PORT = {"type": "port", "seed": 3}

FAMILIES: dict[str, Any] = {
    "name": "speeds",
    "seed": 11,
    "map": {"type": "island", "seed": 4},
    "acquisition": {"frequency_hz": 2, "frames": 20},
    "usv": {"assets": ["usv_wamv"], "speed_mps": list(USV_SPEED)},
    "difficulties": {"easy": {"range_m": [80, 250], "extra_targets": 0}},
    "combinations": [
        {"family": "surround", "cooperating": 2, "targets": ["small"], "quota": 3},
        {"family": "occluded_by_island", "cooperating": 1, "targets": ["small"], "quota": 3},
        {"family": "port_entry", "cooperating": 1, "targets": ["medium"], "quota": 3, "map": PORT},
    ],
}
"""Three families whose templates set the USVs' speeds themselves, nine scenarios in about a second."""


def test_every_usv_sails_within_the_spec_speed_range(tmp_path: Path) -> None:
    report = generate(FAMILIES, tmp_path)
    assert report.all_met
    speeds: dict[str, list[float]] = {}
    for path in sorted(tmp_path.glob("*.yaml")):
        doc = yaml.safe_load(path.read_text(encoding="utf-8"))
        family = path.name.split("_easy_")[0]
        speeds.setdefault(family, []).extend(v["speed_mps"] for v in doc["vessels"] if v["role"] == "usv")
    assert set(speeds) == {"surround", "occluded_by_island", "port_entry"}, sorted(speeds)
    outside = {f: [s for s in v if not USV_SPEED[0] <= s <= USV_SPEED[1]] for f, v in speeds.items()}
    assert not any(outside.values()), outside
