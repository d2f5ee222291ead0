"""``mmusv editor SCENARIO --dir FOLDER`` with a scenario outside the folder that lists its own asset files relative
to its own folder (as ``mmusv run`` reads them): the page resolved them from the editor's folder instead, so the
scenario that runs did not validate there ("does not exist"), and a copy saved into the folder would have named
files that are not there. The page's document names them by their full paths now, the files ``mmusv run`` reads."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest
from mmusv.cli import main
from user_assets import write_boat

with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # starlette's notice about its httpx-based test client
    from fastapi.testclient import TestClient

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")

SCENARIO = """\
name: elsewhere
map: {type: open_sea, seed: 1}
acquisition: {frequency_hz: 5, frames: 2}
assets: [boats/skiff.yaml]
vessels:
  - {id: u, role: usv, asset: usv_wamv, speed_mps: 2, route: [[-60, -300], [60, -300]]}
  - {id: s, asset: skiff, speed_mps: 3, route: [[0, -280], [40, -280]]}
"""


@pytest.mark.usefixtures("_library")
def test_a_scenario_outside_the_folder_keeps_its_own_asset_files(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from mmusv.config import load_scenario
    from mmusv.editor import cli as editor_cli

    elsewhere, folder = tmp_path / "elsewhere", tmp_path / "work"
    folder.mkdir()
    write_boat(elsewhere / "boats" / "skiff.yaml", name="skiff", length=7.0)
    path = elsewhere / "harbour.yaml"
    path.write_text(SCENARIO, encoding="utf-8")
    assert load_scenario(path).vessels[1].asset == "skiff"  # it runs

    apps: list[object] = []
    monkeypatch.setattr(editor_cli, "serve", lambda app, **kw: apps.append(app))
    assert main(["editor", str(path), "--dir", str(folder), "--port", "0"]) == 0
    err = capsys.readouterr().err
    client = TestClient(apps[0], base_url="http://127.0.0.1")  # type: ignore[arg-type]
    initial = client.get("/api/info").json()["initial"]
    assert initial["in_folder"] is False
    doc = initial["document"]
    skiff = (elsewhere / "boats" / "skiff.yaml").resolve()
    assert doc["assets"] == [str(skiff)], doc["assets"]  # was: boats/skiff.yaml, looked for under the folder
    assert "boats/skiff.yaml" in err and str(skiff) in err, err  # said where the page names them from

    ev = client.post("/api/evaluate", json={"document": doc}).json()
    assert ev["valid"] and ev["errors"] == [], ev["errors"]  # was: assets[0] ... does not exist
    assert ev["vessels"][1]["length"] == pytest.approx(7.0)

    r = client.put("/api/files/harbour.yaml", json={"document": doc, "comment": "", "overwrite": False})
    assert r.status_code == 200, r.text
    saved = load_scenario(folder / "harbour.yaml")  # the copy in the folder runs too, with the same skiff
    assert saved.vessels[1].asset == "skiff" and saved.assets == [str(skiff)]
