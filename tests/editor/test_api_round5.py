"""The editor's API after the fifth click-through: a scenario too large to check (too many frames) named only
``vessels``, so the page showed no note at the frames box; a save could write a file larger than the editor opens."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from test_api import bundled_doc, client  # noqa: F401  (the fixture)
from test_api_bad_inputs import error_of

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def test_too_many_frames_to_check_is_an_error_of_the_acquisition(client: Any) -> None:  # noqa: F811
    doc = bundled_doc(client)
    doc["acquisition"] = {**doc["acquisition"], "frames": 5_000_000}
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    assert ev["valid"] is False and len(ev["errors"]) == 1, ev["errors"]
    error = ev["errors"][0]
    assert error["field"] == "acquisition", error  # was: vessels
    # the page shows it next to both boxes: the message names their keys
    assert "acquisition.frames" in error["message"] and "acquisition.frequency_hz" in error["message"], error
    assert "5,000,000 frames" in error["message"]


def test_a_route_too_long_to_check_stays_an_error_of_the_vessels(client: Any) -> None:  # noqa: F811
    doc = bundled_doc(client)
    doc["acquisition"] = {**doc["acquisition"], "frames": 2}
    doc["vessels"][0]["route"] = [[-9e5, -9e5], [9e5, -9e5], [9e5, 9e5], [-9e5, 9e5], [-9e5, -8e5]]
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    assert ev["valid"] is False and ev["errors"][0]["field"] == "vessels", ev["errors"]
    assert "shorten the routes" in ev["errors"][0]["message"]


def test_a_save_larger_than_the_editor_opens_is_refused(
    client: Any,  # noqa: F811
    folder: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import mmusv.editor.files as files

    doc = bundled_doc(client)
    monkeypatch.setattr(files, "MAX_FILE_BYTES", 1000)  # the bundled scenario is larger
    message = error_of(client.put("/api/files/big.yaml", json={"document": doc}), 422)  # was: saved
    assert "big.yaml: not saved" in message and "more than 1,000 bytes" in message, message
    assert "the most the editor opens" in message
    assert list(folder.iterdir()) == []  # nothing written, no temporary file left
