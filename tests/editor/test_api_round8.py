"""The editor's API after the eighth click-through: the scenario named on the command line was served to every page
as it was when the server started, so a second tab (or the URL the command line prints, opened again) showed a
version another tab or program had since replaced, as if nothing were unsaved, and its save was refused as changed.
A scenario of the user's own vessels (``assets:``) did not validate in the editor ("unknown asset"), so it could not be
saved or previewed, unless the server's current folder happened to be the scenario's; its asset files are read from
the editor's folder now, and never from outside it. A name or id with a character the schema refuses (a space, a
letter outside ASCII) was told the regular expression itself ("String should match pattern '^[A-Za-z0-9_\\-]+$'")."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import pytest

with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # starlette's notice about its httpx-based test client
    from fastapi.testclient import TestClient

from mmusv.bundled import resolve_scenario
from mmusv.config import load_scenario
from mmusv.editor.app import InitialScenario, comments_json, create_app
from mmusv.editor.document import leading_comment, to_document
from mmusv.world.vessels import asset_names
from user_assets import write_boat

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def _opened(folder: Path) -> TestClient:
    """An editor whose command line named ``folder/a.yaml`` (the bundled port_entry)."""
    p = folder / "a.yaml"
    shutil.copy(resolve_scenario("port_entry"), p)
    text = p.read_text(encoding="utf-8")
    initial = InitialScenario(
        name="a.yaml",
        document=to_document(load_scenario(p)),
        comment=leading_comment(text),
        comments=comments_json(text),
        in_folder=True,
    )
    return TestClient(create_app(folder, initial=initial))


def test_a_page_loaded_later_opens_the_command_line_file_as_it_is_now(folder: Path) -> None:
    client = _opened(folder)
    first = client.get("/api/info").json()["initial"]
    doc = first["document"]
    doc["name"] = "saved_by_the_first_tab"
    body = {"document": doc, "comment": "first tab", "comments": first["comments"], "overwrite": True}
    r = client.put("/api/files/a.yaml", json=body, headers={"If-Match": first["etag"]})
    assert r.status_code == 200, r.text

    second = client.get("/api/info").json()["initial"]  # another tab, opened now
    assert second["document"]["name"] == "saved_by_the_first_tab"  # was: port_entry, the version of the start
    assert second["comment"] == "first tab"
    assert second["etag"] == r.json()["etag"]
    second["document"]["seed"] = 99  # its save goes through: it starts from the file as it is
    body = {"document": second["document"], "comment": "", "comments": second["comments"], "overwrite": True}
    r = client.put("/api/files/a.yaml", json=body, headers={"If-Match": second["etag"]})
    assert r.status_code == 200, r.text
    assert load_scenario(folder / "a.yaml").seed == 99

    (folder / "a.yaml").write_text(  # changed by another program
        (folder / "a.yaml").read_text(encoding="utf-8").replace("saved_by_the_first_tab", "by_hand"), encoding="utf-8"
    )
    assert client.get("/api/info").json()["initial"]["document"]["name"] == "by_hand"


def test_a_command_line_file_deleted_since_opens_as_it_was_at_the_start(folder: Path) -> None:
    client = _opened(folder)
    (folder / "a.yaml").unlink()
    initial = client.get("/api/info").json()["initial"]
    assert initial["name"] == "a.yaml" and initial["document"]["name"] == "port_entry"
    (folder / "a.yaml").write_text("vessels: 3\n", encoding="utf-8")  # no longer a scenario the page can show
    assert client.get("/api/info").json()["initial"]["document"]["name"] == "port_entry"


OWN_BOAT = """\
name: own_boat
map: {type: open_sea, seed: 1}
acquisition: {frequency_hz: 5, frames: 2}
rigs: {r: {preset: lidar_only, lidar: {channels: 16, points_per_second: 20000}}}
assets: [ASSET]
vessels:
  - {id: u, role: usv, asset: usv_wamv, rig: r, speed_mps: 2, route: [[-60, -300], [60, -300]]}
  - {id: s, asset: editor_skiff, speed_mps: 3, route: [[0, -280], [40, -280]]}
"""


@pytest.mark.usefixtures("_library")
def test_a_scenario_of_its_own_vessels_opens_checks_saves_and_previews(
    folder: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    write_boat(folder / "boats" / "skiff.yaml", name="editor_skiff")
    (folder / "own.yaml").write_text(OWN_BOAT.replace("ASSET", "boats/skiff.yaml"), encoding="utf-8")
    monkeypatch.chdir(tmp_path)  # the server runs elsewhere: the asset path is the folder's
    client = TestClient(create_app(folder))
    opened = client.get("/api/files/own.yaml").json()
    assert opened["valid"] is True  # was: False, "unknown asset" under Checks
    doc = opened["document"]
    assert doc["assets"] == ["boats/skiff.yaml"]
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    assert ev["valid"] is True, ev["errors"]
    assert [v["asset"] for v in ev["vessels"]] == ["usv_wamv", "editor_skiff"]
    r = client.put("/api/files/copy.yaml", json={"document": doc})
    assert r.status_code == 200, r.text  # was: 422, the scenario does not validate
    assert load_scenario(folder / "copy.yaml").assets == ["boats/skiff.yaml"]
    r = client.post("/api/preview", json={"document": doc, "frame": 0, "agent": "u"})
    assert r.status_code == 200 and r.headers["content-type"] == "image/png", r.text[:300]


@pytest.mark.usefixtures("_library")
def test_asset_files_outside_the_folder_are_refused_unread(folder: Path, tmp_path: Path) -> None:
    outside = tmp_path / "models" / "skiff.yaml"
    write_boat(outside, name="editor_skiff")
    client = TestClient(create_app(folder))
    for given, field in (
        ("../models/skiff.yaml", "assets[0]"),
        (str(outside), "assets[0]"),
        ("boats/no.yaml", "assets[0]"),
    ):
        (folder / "own.yaml").write_text(OWN_BOAT.replace("ASSET", repr(given)), encoding="utf-8")
        opened = client.get("/api/files/own.yaml").json()
        assert opened["valid"] is False and opened["document"]["assets"] == [given]  # opened to be fixed
        ev = client.post("/api/evaluate", json={"document": opened["document"]}).json()
        assert ev["valid"] is False and [e["field"] for e in ev["errors"]] == [field], ev["errors"]
        message = ev["errors"][0]["message"]
        assert message.startswith(f"{field} = {given!r}: "), message
        assert ("outside the editor's folder" in message) == (given != "boats/no.yaml"), message
        assert "editor_skiff" not in asset_names()  # never read
        r = client.put("/api/files/copy.yaml", json={"document": opened["document"]})
        assert r.status_code == 422 and field in r.json()["error"]

    # the command line's scenario's own files, which it read, may lie outside the folder
    client = TestClient(create_app(folder, asset_files=[outside]))
    (folder / "own.yaml").write_text(OWN_BOAT.replace("ASSET", "../models/skiff.yaml"), encoding="utf-8")
    assert client.get("/api/files/own.yaml").json()["valid"] is True


@pytest.mark.usefixtures("_library")
def test_the_command_line_scenario_keeps_its_asset_files_outside_the_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from mmusv.cli import main
    from mmusv.editor import cli as editor_cli

    write_boat(tmp_path / "models" / "skiff.yaml", name="editor_skiff")
    (tmp_path / "scen").mkdir()
    (tmp_path / "scen" / "own.yaml").write_text(OWN_BOAT.replace("ASSET", "../models/skiff.yaml"), encoding="utf-8")
    apps: list[object] = []
    monkeypatch.setattr(editor_cli, "serve", lambda app, **kw: apps.append(app))
    assert main(["editor", str(tmp_path / "scen" / "own.yaml"), "--port", "0"]) == 0
    (app,) = apps
    client = TestClient(app, base_url="http://127.0.0.1")  # type: ignore[arg-type]
    doc = client.get("/api/info").json()["initial"]["document"]
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    assert ev["valid"] is True, ev["errors"]
    assert client.put("/api/files/own.yaml", json={"document": doc, "overwrite": True}).status_code == 200


def test_a_refused_name_or_id_says_the_characters_allowed_in_words(folder: Path) -> None:
    client = TestClient(create_app(folder))
    doc = client.get("/api/bundled/port_entry").json()["document"]
    doc["name"] = "港口 north"
    doc["vessels"][0]["id"] = "usv 1"
    doc["rigs"]["usv_standard"]["cameras"] = [{"name": "bow cam"}]
    errors = {e["field"]: e["message"] for e in client.post("/api/evaluate", json={"document": doc}).json()["errors"]}
    assert errors["name"] == (
        "name = '港口 north': use ASCII letters, digits, _, - and . only, not starting with . (it names files and "
        "folders); '港' is not allowed"
    ), errors
    assert (
        errors["vessels[0].id"]
        == "vessels[0].id = 'usv 1': use ASCII letters, digits, _ and - only; ' ' is not allowed"
    )
    assert errors["rigs.usv_standard.cameras[0].name"].endswith("_ and - only; ' ' is not allowed"), errors
    assert not any("pattern" in m for m in errors.values()), errors  # was: the regular expression
    doc["name"], doc["vessels"][0]["id"] = ".hidden", "usv_1"
    doc["rigs"]["usv_standard"].pop("cameras")
    errors = {e["field"]: e["message"] for e in client.post("/api/evaluate", json={"document": doc}).json()["errors"]}
    assert errors == {
        "name": "name = '.hidden': use ASCII letters, digits, _, - and . only, not starting with . (it "
        "names files and folders); it starts with '.'"
    }, errors
