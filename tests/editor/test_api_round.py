"""What the editor's API adds for the page's second click-through round: the heights a custom wave may have (the
page's wave box checks what is typed against them)."""

from __future__ import annotations

import warnings

import pytest
from mmusv.world.environment import MAX_WAVE_HEIGHT_M
from test_api import bundled_doc, client

with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # starlette's notice about its httpx-based test client
    from fastapi.testclient import TestClient

__all__ = ["client"]  # the fixture, shared with test_api.py

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def test_info_gives_the_heights_a_custom_wave_may_have(client: TestClient) -> None:
    lo, hi = client.get("/api/info").json()["choices"]["wave_height_m"]
    assert (lo, hi) == (0, MAX_WAVE_HEIGHT_M)
    doc = bundled_doc(client)
    for wave, valid in ((lo, True), (hi, True), (hi + 0.01, False), (lo - 0.01, False)):
        doc["environment"]["wave"] = wave
        ev = client.post("/api/evaluate", json={"document": doc}).json()
        assert ev["valid"] is valid, (wave, ev["errors"])
        if not valid:
            assert [e["field"] for e in ev["errors"]] == ["environment.wave"], ev["errors"]
