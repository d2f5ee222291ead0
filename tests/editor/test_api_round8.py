"""The editor's API after the eighth click-through: the scenario named on the command line was served to every page
as it was when the server started, so a second tab (or the URL the command line prints, opened again) showed a
version another tab or program had since replaced, as if nothing were unsaved, and its save was refused as changed."""

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
