"""The tests' tiny scenario: one LiDAR-only USV and one target on the open sea (shared by the fault, environment,
concurrency and reader tests, which each had a copy)."""

from __future__ import annotations

from typing import Any


def lidar_scenario(name: str, *, frames: int, dense: bool = False, seed: int = 1) -> dict[str, Any]:
    """An open-sea scenario with one LiDAR-only USV and one target. ``dense``: a 32-channel LiDAR (about 60 kB a
    frame, so a run of ~100 frames fills the recorder's 4 MiB chunks); else 8 channels (about 7 kB a frame). The
    paper's motion over flat water keeps these frame sizes (the physical sea's water returns would change them),
    which the chunk counts and kill timings of the fault tests rely on."""
    lidar = {"channels": 32, "points_per_second": 327680} if dense else {"channels": 8, "points_per_second": 20480}
    return {
        "name": name,
        "seed": seed,
        "map": {"type": "open_sea", "seed": 0},
        "acquisition": {"frames": frames},
        "environment": {"motion": "paper"},
        "rigs": {"r": {"preset": "lidar_only", "lidar": lidar}},
        "vessels": [
            {"id": "u", "role": "usv", "asset": "usv_wamv", "rig": "r", "speed_mps": 2, "route": [[0, 0], [50, 0]]},
            {"id": "t", "asset": "fishing_boat_12m", "speed_mps": 3, "route": [[0, 60], [60, 60]]},
        ],
    }
