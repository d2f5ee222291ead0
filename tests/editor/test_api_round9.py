"""The editor's API after the ninth click-through: the vessel library is one per process, so two scenario files of
one editor server that each name an asset ``skiff`` in their own asset file clashed ("already in the library") when
the second was opened, and a scenario that listed no asset file validated with the assets another scenario had
registered (which ``mmusv run`` of it refuses); each scenario sees its own asset files' assets now."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import pytest

with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # starlette's notice about its httpx-based test client
    from fastapi.testclient import TestClient

from mmusv.config import load_scenario
from mmusv.editor.app import create_app
from test_api_round8 import OWN_BOAT
from user_assets import write_boat

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def _lengths(client: TestClient, name: str) -> dict[str, float]:
    """The vessels' lengths of the folder's file ``name`` as the editor checks it (its errors when it does not)."""
    opened = client.get(f"/api/files/{name}").json()
    ev = client.post("/api/evaluate", json={"document": opened["document"]}).json()
    assert opened["valid"] is ev["valid"], (opened, ev["errors"])
    if not ev["valid"]:
        return {e["field"]: e["message"] for e in ev["errors"]}
    return {v["id"]: v["length"] for v in ev["vessels"]}


@pytest.mark.usefixtures("_library")
def test_one_asset_name_in_two_scenarios_asset_files_is_each_scenarios_own(folder: Path) -> None:
    write_boat(folder / "harbour" / "boat.yaml", name="skiff", length=6.0)
    write_boat(folder / "lake" / "boat.yaml", name="skiff", length=12.0)
    for stem, asset_file in (("harbour", "harbour/boat.yaml"), ("lake", "lake/boat.yaml")):
        text = OWN_BOAT.replace("ASSET", asset_file).replace("editor_skiff", "skiff")
        (folder / f"{stem}.yaml").write_text(text, encoding="utf-8")
    (folder / "unlisted.yaml").write_text(  # names the asset without listing an asset file
        OWN_BOAT.replace("assets: [ASSET]\n", "").replace("editor_skiff", "skiff"), encoding="utf-8"
    )
    client = TestClient(create_app(folder))
    for _ in range(2):  # back and forth, as two tabs do
        assert _lengths(client, "harbour.yaml")["s"] == 6.0
        # was: assets[0]: asset 'skiff' is already in the library, from .../harbour/boat.yaml
        assert _lengths(client, "lake.yaml")["s"] == 12.0
    # was: valid, with the 12 m skiff of lake's file, while `mmusv run unlisted.yaml` says "unknown asset"
    errors = _lengths(client, "unlisted.yaml")
    assert list(errors) == ["vessels[1].asset"] and "unknown asset" in errors["vessels[1].asset"], errors

    doc = client.get("/api/files/lake.yaml").json()["document"]
    client.get("/api/files/harbour.yaml")
    r = client.put("/api/files/lake_copy.yaml", json={"document": doc})  # saved with its own assets
    assert r.status_code == 200, r.text
    r = client.post("/api/poses", json={"document": doc, "frame": 1})
    assert r.status_code == 200, r.text
    assert load_scenario(folder / "lake_copy.yaml").assets == ["lake/boat.yaml"]


@pytest.mark.usefixtures("_library")
@pytest.mark.parametrize(
    ("entry", "says"),
    [
        ("boats/a\x00b.yaml", "it holds a NUL character, which no file name can"),
        ("~no_such_user_here/boat.yaml", "'~no_such_user_here' names no user of this machine"),
        ("x" * 300 + ".yaml", "not a file this system can open (File name too long)"),
    ],
    ids=["nul", "no-user", "too-long"],
)
def test_an_asset_path_that_names_no_file_is_said_to_be_so(folder: Path, entry: str, says: str) -> None:
    """Such an ``assets:`` entry in a file opened, checked or saved was an internal error (500, a traceback on the
    server's console); ``mmusv run`` of the file ended in a traceback."""
    from mmusv.errors import ConfigError

    (folder / "own.yaml").write_text(OWN_BOAT.replace("[ASSET]", json.dumps([entry])), encoding="utf-8")
    client = TestClient(create_app(folder), raise_server_exceptions=False)
    opened = client.get("/api/files/own.yaml")
    assert opened.status_code == 200 and opened.json()["valid"] is False, opened.text  # opened to be fixed
    doc = opened.json()["document"]
    ev = client.post("/api/evaluate", json={"document": doc})
    assert ev.status_code == 200, ev.text
    (error,) = ev.json()["errors"]
    assert error["field"] == "assets[0]" and says in error["message"], error
    r = client.put("/api/files/copy.yaml", json={"document": doc})
    assert r.status_code == 422 and says in r.json()["error"], r.text
    with pytest.raises(ConfigError, match=r"assets\[0\]") as got:
        load_scenario(folder / "own.yaml")
    assert says in str(got.value)
