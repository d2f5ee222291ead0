"""Test helpers for user vessel assets (``assets:`` in a scenario, :mod:`mmusv.scenario_assets`): an asset file
with its mesh, and the asset library put back as it was (it is per process)."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

import trimesh
import yaml
from mmusv import scenario_assets
from mmusv.world.vessels import asset_names, unregister_asset


def write_boat(entry_file: Path, *, name: str, length: float = 6.0) -> None:
    """``entry_file`` (an asset YAML) naming ``name``, and its mesh beside it (same stem, ``.ply``): a box
    ``length`` × 2.4 × 1.6 m, draft 0.4 m, semantic class ``vessel``."""
    entry_file.parent.mkdir(parents=True, exist_ok=True)
    mesh = entry_file.with_suffix(".ply")
    trimesh.creation.box(extents=[length, 2.4, 1.6]).export(mesh)
    entry = {"name": name, "mesh": mesh.name, "draft": 0.4, "semantic_class": "vessel"}
    entry_file.write_text(yaml.safe_dump(entry), encoding="utf-8")


@contextlib.contextmanager
def library_restored() -> Iterator[None]:
    """The assets registered meanwhile are removed afterwards, and the scenario-asset cache cleared."""
    before = set(asset_names())
    try:
        yield
    finally:
        for name in set(asset_names()) - before:
            unregister_asset(name)
        scenario_assets._loaded.clear()
        scenario_assets._parked.clear()
