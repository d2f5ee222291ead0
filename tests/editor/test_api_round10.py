"""The editor's API after the tenth click-through: the vessel library (``GET /api/assets``) was the assets the server
held when asked, so a page that loaded it at its start listed no asset of a scenario opened later, and could list
another scenario's (refused as "unknown asset" once placed); it answers for a scenario now (``?assets=`` its
``assets:`` entries), and with no query the built-in assets only, none of another scenario's."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # starlette's notice about its httpx-based test client
    from fastapi.testclient import TestClient

from mmusv.editor.app import create_app
from mmusv.world.vessels import library
from user_assets import write_boat

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def _own(client: TestClient, *entries: str) -> dict[str, float]:
    """The user assets (name: length) of the library the editor gives a scenario whose ``assets:`` is ``entries``;
    the rest of it is the built-in library."""
    r = client.get("/api/assets", params={"assets": list(entries)} if entries else None)
    assert r.status_code == 200, r.text
    builtin = {a.name for a in library() if a.source == "builtin"}
    got = r.json()
    assert builtin <= {a["name"] for a in got}
    assert [a["name"] for a in got] == sorted(a["name"] for a in got)
    return {a["name"]: a["length"] for a in got if a["name"] not in builtin}


@pytest.mark.usefixtures("_library")
def test_the_library_is_the_scenarios_own(folder: Path) -> None:
    write_boat(folder / "harbour" / "boat.yaml", name="skiff", length=6.0)
    write_boat(folder / "lake" / "boat.yaml", name="skiff", length=12.0)
    write_boat(folder / "lake" / "punt.yaml", name="punt", length=3.0)
    client = TestClient(create_app(folder))
    for _ in range(2):  # back and forth, as the page opening one scenario then another
        # was: {} (the query unread: nothing registered yet), then harbour's 6 m skiff for lake
        assert _own(client, "harbour/boat.yaml") == {"skiff": 6.0}
        assert _own(client, "lake/boat.yaml", "lake/punt.yaml") == {"skiff": 12.0, "punt": 3.0}
    assert _own(client) == {}  # was: lake's skiff and punt, which a scenario listing no asset file cannot use
    # a file that cannot be read (it is said under the scenario's checks) hides none of the others
    assert _own(client, "lake/none.yaml", "../outside.yaml", "lake/punt.yaml") == {"punt": 3.0}
    # the scenario's checks agree with its library: harbour's skiff is there again for harbour
    doc = {
        "name": "h",
        "assets": ["harbour/boat.yaml"],
        "vessels": [{"id": "s", "asset": "skiff", "speed_mps": 2, "route": [[0, -280], [40, -280]]}],
    }
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    assert ev["valid"] and ev["vessels"][0]["length"] == pytest.approx(6.0), ev["errors"]
