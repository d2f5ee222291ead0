"""``mmusv editor`` on the command line after the ninth click-through: a scenario file that does not exist yet was
refused ("does not exist and is not a bundled scenario"), so a new scenario could not be started from the command
line; it opens a new scenario now, which Save writes to that file. A binary or UTF-16 file was read with
replacement characters and refused as "not valid YAML"; it is said not to be UTF-8 text, naming the file."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest
from mmusv.cli import main
from test_editor_cli import _opened

with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # starlette's notice about its httpx-based test client
    from fastapi.testclient import TestClient

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")

VESSEL = {"id": "usv_1", "role": "usv", "asset": "usv_wamv", "speed_mps": 2, "route": [[-60, -300], [60, -300]]}


def test_a_file_that_does_not_exist_yet_opens_a_new_scenario_saved_to_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.config import load_scenario
    from mmusv.editor import cli as editor_cli

    path = tmp_path / "harbour_new.yaml"
    monkeypatch.chdir(tmp_path.parent)  # the folder is the file's, not the current one
    initial, err = _opened(["editor", str(path), "--port", "0"], monkeypatch, capsys)  # was: exit 2
    assert initial["name"] == "harbour_new.yaml" and initial["new"] is True and initial["in_folder"] is False
    doc = initial["document"]
    assert doc["name"] == "harbour_new" and doc["vessels"] == [] and doc["map"]["type"], doc
    assert f"Save writes to {path}" in err and "Traceback" not in err, err
    assert not path.exists()  # nothing written before Save

    apps: list[object] = []
    monkeypatch.setattr(editor_cli, "serve", lambda app, **kw: apps.append(app))
    assert main(["editor", str(path), "--port", "0"]) == 0
    client = TestClient(apps[0], base_url="http://127.0.0.1")  # type: ignore[arg-type]
    assert client.get("/api/info").json()["folder"] == str(tmp_path.resolve())
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    # the one thing to fix, said in words (was pydantic's "List should have at least 1 item after validation, not 0")
    assert [(e["field"], e["message"]) for e in ev["errors"]] == [
        ("vessels", "vessels = []: must hold at least 1 entry, got 0")
    ]
    doc["vessels"] = [VESSEL]
    r = client.put("/api/files/harbour_new.yaml", json={"document": doc, "comment": "", "overwrite": False})
    assert r.status_code == 200, r.text
    assert [v.id for v in load_scenario(path).vessels] == ["usv_1"]
    now = client.get("/api/info").json()["initial"]  # a page opened after the save: the file saved, not a new one
    assert now["new"] is False and now["in_folder"] is True and now["etag"] == r.json()["etag"], now
    assert now["document"]["vessels"][0]["id"] == "usv_1"


@pytest.mark.parametrize(
    ("given", "says"),
    [
        ("no_folder/new.yaml", "the folder 'no_folder' does not exist; create it first"),
        ("no_such_scenario", "is not a bundled scenario; bundled: "),  # a mistyped bundled name, most likely
        ("new file.yaml", "file name 'new file.yaml' is not allowed"),
    ],
)
def test_a_new_file_that_cannot_be_saved_there_is_refused_in_one_line(
    given: str, says: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.editor import cli as editor_cli

    monkeypatch.setattr(editor_cli, "serve", lambda app, **kw: None)  # (a server started is a failure here)
    monkeypatch.chdir(tmp_path)
    assert main(["editor", given, "--port", "0"]) == 2
    err = capsys.readouterr().err
    assert says in err and err.count("\n") == 1 and err.startswith("mmusv: error:"), err
    if given == "no_such_scenario":
        assert err.endswith("; to start a new scenario, give a file name ending in .yaml\n"), err
    assert list(tmp_path.iterdir()) == []


def test_a_link_that_leads_nowhere_is_said_to_be_one(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    link = tmp_path / "gone.yaml"
    link.symlink_to(tmp_path / "moved.yaml")
    assert main(["editor", str(link), "--port", "0"]) == 2
    err = capsys.readouterr().err
    assert "is a link that leads nowhere: it points to" in err and "start a new scenario" not in err, err


@pytest.mark.parametrize(
    ("data", "says"),
    [
        (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256)), "not a text file (a NUL byte at offset 8)"),
        ("name: café\nvessels: []\n".encode("latin-1"), "not UTF-8 text (byte 0xe9 at offset 9)"),
        ("name: a\nvessels: []\n".encode("utf-16"), "the file is encoded as UTF-16"),
    ],
    ids=["binary", "latin-1", "utf-16"],
)
def test_a_file_that_is_not_utf8_text_is_said_to_be_so_naming_it(
    data: bytes, says: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.editor import cli as editor_cli

    monkeypatch.setattr(editor_cli, "serve", lambda app, **kw: None)  # (a server started is a failure here)
    path = tmp_path / "photo.yaml"
    path.write_bytes(data)
    assert main(["editor", str(path), "--port", "0"]) == 2
    err = capsys.readouterr().err
    # was: "photo.yaml: not valid YAML: unacceptable character #x0000", or for text in Latin-1 opened with "caf\ufffd"
    assert err == f"mmusv: error: {path}: {says}" + err.split(says, 1)[1], err
    assert "YAML:" not in err and err.count("\n") == 1, err
