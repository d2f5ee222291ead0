"""A rig's keys as its file gave them, through the editor (the leftover of the 2026-12-06 note): the page's document
left out a camera's ``quality`` equal to its rig's and a rig key equal to its preset's, so a later change of the
rig's quality or preset in the page moved what the file had set explicitly. Both tests failed before the fix."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.config import load_scenario
from test_api import TestClient, bundled_doc, client

__all__ = ["client"]  # the fixture, shared with test_api.py

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def _open(client: TestClient, folder: Path, rig: dict[str, Any]) -> dict[str, Any]:
    """Writes the bundled ``port_entry`` with every USV on ``rig`` as the folder's ``own.yaml`` and opens it."""
    doc = bundled_doc(client)
    doc["rigs"] = {"own": rig}
    for v in doc["vessels"]:
        if "rig" in v:
            v["rig"] = "own"
    (folder / "own.yaml").write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    r = client.get("/api/files/own.yaml")
    assert r.status_code == 200, r.text
    opened: dict[str, Any] = r.json()["document"]
    return opened


def _save(client: TestClient, folder: Path, doc: dict[str, Any]) -> Any:
    r = client.put("/api/files/own.yaml", json={"document": doc, "overwrite": True})
    assert r.status_code == 200, r.text
    return load_scenario(folder / "own.yaml").rigs["own"]


def test_a_camera_quality_the_file_set_stays_when_the_rigs_quality_changes(client: TestClient, folder: Path) -> None:
    rig = {
        "quality": "draft",
        "cameras": [
            {"name": "front", "quality": "draft", "mount": {"point": "camera_front"}},
            {"name": "left", "mount": {"point": "camera_left"}},
        ],
        "top_view": {"quality": "draft"},
    }
    doc = _open(client, folder, rig)
    doc["rigs"]["own"]["quality"] = "high"  # what the rig panel's quality menu does
    saved = _save(client, folder, doc)
    assert [c.quality for c in saved.cameras] == ["draft", "high"]  # front set draft itself; left took the rig's
    assert saved.top_view is not None and saved.top_view.quality == "draft"


def test_a_key_the_file_gave_equal_to_its_presets_stays_when_the_preset_changes(
    client: TestClient, folder: Path
) -> None:
    doc = _open(client, folder, {"preset": "lidar_only", "radar": None})
    assert doc["rigs"]["own"] == {"preset": "lidar_only", "radar": None}
    doc["rigs"]["own"]["preset"] = "full"  # what the rig panel's preset menu does
    saved = _save(client, folder, doc)
    assert saved.radar is None  # the file's radar: null, not the full suite's radar
    assert saved.lidar is not None and len(saved.cameras) == 4 and saved.top_view is not None


def test_a_rig_without_explicit_keys_still_opens_as_its_preset(client: TestClient, folder: Path) -> None:
    doc = _open(client, folder, {"preset": "lidar_only"})
    assert doc["rigs"]["own"] == {"preset": "lidar_only"}
    doc = _open(client, folder, {"quality": "draft"})
    assert doc["rigs"]["own"] == {"quality": "draft"}
