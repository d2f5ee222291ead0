"""The editor's HTTP API (FastAPI TestClient): every endpoint, good and bad input, and the safety of the folder."""

from __future__ import annotations

import io
import json
import os
import re
import time
import warnings
from pathlib import Path
from typing import Any
from urllib.parse import unquote

import numpy as np
import pytest
from PIL import Image

with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # starlette's notice about its httpx-based test client
    from fastapi.testclient import TestClient

import mmusv
from mmusv.bundled import bundled_dir, bundled_scenarios
from mmusv.config import load_scenario
from mmusv.editor.app import MAX_BODY_BYTES, STATIC_DIR, create_app
from mmusv.editor.evaluate import MAX_BULK_FRAMES
from mmusv.preview import compose_preview

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


SMALL_RIG = {"preset": "lidar_only", "lidar": {"channels": 16, "points_per_second": 20000}}


@pytest.fixture
def client(folder: Path) -> TestClient:
    return TestClient(create_app(folder))


def bundled_doc(client: TestClient, name: str = "port_entry") -> dict[str, Any]:
    r = client.get(f"/api/bundled/{name}")
    assert r.status_code == 200, r.text
    doc: dict[str, Any] = r.json()["document"]
    return doc


def small(doc: dict[str, Any]) -> dict[str, Any]:
    """``doc`` with every rig made a small LiDAR-only rig (quick to run)."""
    return {**doc, "rigs": dict.fromkeys(doc["rigs"], SMALL_RIG)}


# ------------------------------------------------------------------------------------------------ pages


def test_page_and_static_files_are_served_with_a_strict_policy(client: TestClient) -> None:
    r = client.get("/")
    assert r.status_code == 200 and "text/html" in r.headers["content-type"]
    assert "default-src 'self'" in r.headers["content-security-policy"]
    for src in re.findall(r'(?:src|href)="([^"]+)"', r.text):
        assert client.get(src).status_code == 200, src
    for js in sorted((STATIC_DIR / "js").glob("*.js")):
        assert client.get(f"/static/js/{js.name}").status_code == 200
        for imp in re.findall(r'from "\./([^"]+)"', js.read_text()):
            assert (STATIC_DIR / "js" / imp).is_file(), (js.name, imp)


def test_the_page_fetches_nothing_from_elsewhere() -> None:
    for f in sorted(STATIC_DIR.rglob("*")):
        if f.is_file():
            urls = set(re.findall(r"https?://[^\s\"')]+", f.read_text(encoding="utf-8")))
            assert urls <= {"http://www.w3.org/2000/svg"}, (f.name, urls)  # the SVG namespace is a name, not a fetch


def test_static_files_do_not_leak_the_package(client: TestClient) -> None:
    for path in ("/static/../app.py", "/static/..%2Fapp.py", "/static/%2e%2e/app.py", "/static/js/../../app.py"):
        r = client.get(path)
        assert r.status_code == 404, path
        assert "create_app" not in r.text


def test_info_gives_the_choices_of_the_schema(client: TestClient) -> None:
    info = client.get("/api/info").json()
    assert info["version"] == mmusv.__version__
    assert info["choices"]["map_type"] == ["island", "open_sea", "port"]
    assert info["choices"]["end"] == ["stop", "loop", "ping_pong"]
    assert info["choices"]["camera_quality"] == ["draft", "standard", "high"]
    assert [w["name"] for w in info["choices"]["wave"]] == ["W0", "W1", "W2", "W3"]
    assert info["initial"] is None and info["limits"]["bulk_frames"] == MAX_BULK_FRAMES


def test_assets_are_the_vessel_library(client: TestClient) -> None:
    from mmusv.world.vessels import get_asset, library

    assets = client.get("/api/assets").json()
    assert [a["name"] for a in assets] == [a.name for a in library()]
    for a in assets:
        ref = get_asset(a["name"])
        assert a["length"] == pytest.approx(ref.length, abs=0.01) and a["beam"] == pytest.approx(ref.beam, abs=0.01)
        assert a["usv"] == ref.is_usv


# ------------------------------------------------------------------------------------------------ files


@pytest.mark.parametrize("name", [b.name for b in bundled_scenarios()])
def test_every_bundled_scenario_saved_unchanged_is_equal(client: TestClient, folder: Path, name: str) -> None:
    r = client.get(f"/api/bundled/{name}")
    assert r.status_code == 200 and r.json()["valid"]
    body = r.json()
    assert (
        client.put(
            f"/api/files/{name}.yaml", json={"document": body["document"], "comment": body["comment"]}
        ).status_code
        == 200
    )
    original = load_scenario(bundled_dir() / f"{name}.yaml")
    assert load_scenario(folder / f"{name}.yaml") == original
    again = client.get(f"/api/files/{name}.yaml").json()
    assert again["document"] == body["document"] and again["comment"] == body["comment"] and again["valid"]
    assert (folder / f"{name}.yaml").read_text().startswith("# ")


def test_bundled_unknown_is_404(client: TestClient) -> None:
    r = client.get("/api/bundled/atlantis")
    assert r.status_code == 404 and "port_entry" in r.json()["error"]


def test_save_refuses_to_replace_without_overwrite(client: TestClient, folder: Path) -> None:
    doc = bundled_doc(client)
    assert client.put("/api/files/a.yaml", json={"document": doc}).status_code == 200
    before = (folder / "a.yaml").read_bytes()
    doc["seed"] = 99
    r = client.put("/api/files/a.yaml", json={"document": doc})
    assert r.status_code == 409 and "overwrite" in r.json()["error"]
    assert (folder / "a.yaml").read_bytes() == before
    assert client.put("/api/files/a.yaml", json={"document": doc, "overwrite": True}).status_code == 200
    assert load_scenario(folder / "a.yaml").seed == 99
    assert [f["name"] for f in client.get("/api/files").json()] == ["a.yaml"]
    assert not [p for p in folder.iterdir() if p.name.startswith(".")]  # no temporary file left behind


def test_save_refuses_an_invalid_scenario_naming_the_field(client: TestClient, folder: Path) -> None:
    doc = bundled_doc(client)
    doc["vessels"][2]["speed_mps"] = -1
    r = client.put("/api/files/bad.yaml", json={"document": doc})
    assert r.status_code == 422 and "vessels[2].speed_mps" in r.json()["error"]
    assert not (folder / "bad.yaml").exists()


@pytest.mark.parametrize(
    "name",
    [
        "..%2Fescape.yaml",
        "..%2F..%2Fetc%2Fpasswd",
        "%2Fetc%2Fpasswd",
        "%2Ftmp%2Fx.yaml",
        "sub%2Fx.yaml",
        "..%5Cx.yaml",
        ".hidden.yaml",
        "x.txt",
        "x.yaml.exe",
        "x%00.yaml",
        "%2E%2E",
        "a" * 200 + ".yaml",
    ],
)
def test_names_outside_the_folder_or_not_yaml_are_refused(client: TestClient, folder: Path, name: str) -> None:
    for r in (
        client.get(f"/api/files/{name}"),
        client.put(f"/api/files/{name}", json={"document": bundled_doc(client)}),
        client.post("/api/runs", json={"name": unquote(name)}),
    ):
        assert r.status_code == 400, (name, r.status_code, r.text)
        assert "not allowed" in r.json()["error"]
    assert sorted(p.name for p in folder.parent.rglob("*") if p.is_file()) == []


def test_a_link_out_of_the_folder_is_not_served(client: TestClient, folder: Path, tmp_path: Path) -> None:
    secret = tmp_path / "secret.yaml"
    secret.write_text("name: secret\nvessels: []\n")
    os.symlink(secret, folder / "link.yaml")
    assert client.get("/api/files").json() == []
    r = client.get("/api/files/link.yaml")
    assert r.status_code == 400 and "secret" not in r.text
    r = client.put("/api/files/link.yaml", json={"document": bundled_doc(client), "overwrite": True})
    assert r.status_code == 400 and secret.read_text().startswith("name: secret")


def test_saving_a_link_in_the_folder_writes_through_it(client: TestClient, folder: Path) -> None:
    """A file that is a link to another file of the folder (``current.yaml -> harbour.yaml``) is saved into the file
    it points to, and stays a link (was: the link was replaced by a file of its own, so ``harbour.yaml`` kept the
    old scenario and the two names parted)."""
    doc = bundled_doc(client)
    assert client.put("/api/files/harbour.yaml", json={"document": doc}).status_code == 200
    os.symlink("harbour.yaml", folder / "current.yaml")
    os.chmod(folder / "harbour.yaml", 0o640)
    opened = client.get("/api/files/current.yaml")
    assert opened.status_code == 200
    doc = {**opened.json()["document"], "name": "renamed_through_the_link"}
    r = client.put("/api/files/current.yaml", json={"document": doc, "overwrite": True})
    assert r.status_code == 200, r.text
    assert (folder / "current.yaml").is_symlink() and os.readlink(folder / "current.yaml") == "harbour.yaml"
    assert "renamed_through_the_link" in (folder / "harbour.yaml").read_text()
    assert (folder / "harbour.yaml").stat().st_mode & 0o777 == 0o640
    assert sorted(p.name for p in folder.iterdir()) == ["current.yaml", "harbour.yaml"]  # no temporary left


def test_reading_files(client: TestClient, folder: Path) -> None:
    assert client.get("/api/files/missing.yaml").status_code == 404
    (folder / "broken.yaml").write_text("vessels: [\n")
    r = client.get("/api/files/broken.yaml")
    assert r.status_code == 422 and "line" in r.json()["error"]
    (folder / "list.yaml").write_text("- 1\n- 2\n")
    assert client.get("/api/files/list.yaml").status_code == 422
    (folder / "invalid.yaml").write_text(
        "name: x\nvessels:\n  - {id: a, asset: usv_wamv, speed_mps: -2, route: [[0, 0], [9, 9]]}\n"
    )
    r = client.get("/api/files/invalid.yaml").json()
    assert r["valid"] is False and r["document"]["vessels"][0]["speed_mps"] == -2  # opened as written, to be fixed
    (folder / "shapeless.yaml").write_text("vessels: {a: 1}\n")
    r = client.get("/api/files/shapeless.yaml")
    assert r.status_code == 422 and "vessels" in r.json()["error"] and "as text" in r.json()["error"]
    (folder / "notes.txt").write_text("not a scenario")
    names = [f["name"] for f in client.get("/api/files").json()]
    assert names == ["broken.yaml", "invalid.yaml", "list.yaml", "shapeless.yaml"]


# ------------------------------------------------------------------------------------------------ map and checks


def test_map_layers(client: TestClient) -> None:
    from mmusv.generate.mapctx import map_context

    m = client.post("/api/map", json={"map": {"type": "port", "seed": 3}}).json()
    ctx = map_context("port", seed=3, params={})
    assert m["kind"] == "port" and m["bounds"] == [-1000.0, -1000.0, 1000.0, 1000.0]
    assert len(m["moored"]) == len(ctx.world.moored) and len(m["structures"]) == len(ctx.priors.structure_boundaries)
    img = Image.open(io.BytesIO(__import__("base64").b64decode(m["image"].split(",", 1)[1])))
    assert img.size[0] == img.size[1] >= 400
    # north up: the port's land (north) is green-brown at the top, the sea blue at the bottom
    top, bottom = np.asarray(img)[5, img.size[0] // 2], np.asarray(img)[-5, img.size[0] // 2]
    assert top[1] > top[2] and bottom[2] > bottom[0]
    r = client.post("/api/map", json={"map": {"type": "lake", "seed": -1}})
    assert r.status_code == 422 and "map.type" in r.json()["error"] and "map.seed" in r.json()["error"]
    r = client.post("/api/map", json={"map": {"type": "port", "params": {"extent_m": -5}}})
    assert r.status_code == 422 and "map.params.extent_m" in r.json()["error"]


def test_evaluate_a_valid_scenario_gives_the_simulated_motion(client: TestClient) -> None:
    doc = bundled_doc(client)
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    assert ev["valid"] and ev["errors"] == [] and ev["problems"] == []
    sim = mmusv.Simulation(load_scenario(doc))
    for k in (0, 17, ev["frames"] - 1):
        st = sim.world_state(k)
        for i, v in enumerate(ev["vessels"]):
            x, y, yaw = v["poses"][k]
            assert (
                abs(x - st.poses[i, 0]) < 1e-3 and abs(y - st.poses[i, 1]) < 1e-3 and abs(yaw - st.poses[i, 5]) < 1e-5
            )
    for v, given in zip(ev["vessels"], doc["vessels"], strict=True):
        # the spline passes through the waypoints: first and last sample are the route's ends
        assert np.allclose(v["path"][0], given["route"][0], atol=1e-3)
        assert np.allclose(v["path"][-1], given["route"][-1], atol=1e-3)
        assert (v["rings"] is not None) == (given["role"] == "usv")
    assert ev["vessels"][0]["rings"] == {"lidar": 200.0, "radar": 3000.0}


def test_evaluate_flags_a_route_over_land_where_it_happens(client: TestClient) -> None:
    from mmusv.generate.mapctx import map_context

    doc = bundled_doc(client)
    doc["vessels"][3]["route"][0] = [-40, 500]  # the ferry starts on land north of the harbour
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    in_water = [p for p in ev["problems"] if p["check"] == "in_water"]
    assert len(in_water) == 1
    p = in_water[0]
    assert p["severity"] == "error" and p["field"] == "vessels[3].route" and p["vessels"] == ["ferry"]
    path = np.array(ev["vessels"][3]["path"])
    bad = np.zeros(len(path), bool)
    for a, b in p["segments"]["ferry"]:
        bad[a : b + 1] = True
    land = map_context("port", seed=3, params={}).world.heightfield.sample(path) > 0.0
    assert land.any() and not (land & ~bad).any()  # every route sample on land is in a red segment
    assert bad[0] and not bad[-1]


def test_evaluate_flags_hulls_that_intersect_as_an_error(client: TestClient) -> None:
    """``mmusv run`` refuses two hulls that run into each other; the editor's map says so, as an error."""
    doc = bundled_doc(client)
    doc["vessels"][1]["route"] = [list(map(float, xy)) for xy in doc["vessels"][0]["route"]]
    doc["vessels"][1]["speed_mps"] = doc["vessels"][0]["speed_mps"]
    doc["vessels"][1].pop("start_offset_m", None)
    doc["vessels"][0].pop("start_offset_m", None)
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    hits = [p for p in ev["problems"] if p["check"] == "hulls_intersect"]
    assert len(hits) == 1, ev["problems"]
    ids = [doc["vessels"][0]["id"], doc["vessels"][1]["id"]]
    assert hits[0]["severity"] == "error" and hits[0]["vessels"] == ids and hits[0]["field"] == "vessels[0]"
    assert "intersect at t=0.0 s" in hits[0]["message"]


def test_evaluate_lists_every_vessel_that_fails(client: TestClient) -> None:
    doc = bundled_doc(client)
    doc["vessels"][0]["route"][2] = [-120, 600]
    doc["vessels"][4]["route"][2] = [-160, 650]
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    assert sorted(p["vessels"][0] for p in ev["problems"] if p["check"] == "in_water") == ["tug", "usv_1"]


def test_evaluate_warns_of_targets_out_of_range_and_sight(client: TestClient) -> None:
    doc = bundled_doc(client)
    doc["vessels"].append(
        {"id": "far", "role": "target", "asset": "tug_32m", "speed_mps": 2, "route": [[700, -800], [800, -800]]}
    )
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    checks = {p["check"] for p in ev["problems"] if p["vessels"] == ["far"]}
    assert checks == {"sensing_range", "line_of_sight"}
    assert all(p["field"] == "vessels[8]" and p["severity"] == "warning" for p in ev["problems"])


def test_evaluate_names_the_field_of_schema_and_route_errors(client: TestClient) -> None:
    doc = bundled_doc(client)
    doc["vessels"][1]["speed_mps"] = -1
    doc["acquisition"]["frames"] = 0
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    assert not ev["valid"] and ev["vessels"] == []
    assert {e["field"] for e in ev["errors"]} == {"vessels[1].speed_mps", "acquisition.frames"}
    assert [e["vessel"] for e in ev["errors"] if e["field"].startswith("vessels")] == ["usv_2"]
    doc = bundled_doc(client)
    doc["vessels"][2]["route"][1] = doc["vessels"][2]["route"][0]
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    assert not ev["valid"] and ev["errors"][0]["field"] == "vessels[2].route[1]"
    doc = bundled_doc(client)
    doc["vessels"][0]["speed_mps"] = 1e9  # beyond any vessel: refused by the schema, naming the field
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    assert not ev["valid"] and ev["errors"][0]["field"] == "vessels[0].speed_mps"
    assert "less than or equal to 100" in ev["errors"][0]["message"]
    doc = bundled_doc(client)
    doc["acquisition"] = {"frequency_hz": 1000, "frames": 10_000_000}  # valid, but too long to sample
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    assert not ev["valid"] and "at most" in ev["errors"][0]["message"]


def test_long_acquisitions_give_poses_one_index_at_a_time(client: TestClient) -> None:
    doc = bundled_doc(client)
    doc["acquisition"] = {"frequency_hz": 50, "frames": MAX_BULK_FRAMES + 1}
    ev = client.post("/api/evaluate", json={"document": doc}).json()
    assert ev["valid"] and all(v["poses"] is None for v in ev["vessels"])
    k = MAX_BULK_FRAMES
    r = client.post("/api/poses", json={"document": doc, "frame": k}).json()
    st = mmusv.Simulation(load_scenario(doc)).world_state(k)
    assert np.allclose(np.array(r["poses"])[:, :2], st.poses[:8, :2], atol=1e-3)
    assert client.post("/api/poses", json={"document": doc, "frame": k + 1}).status_code == 422
    assert client.post("/api/poses", json={"document": doc, "frame": -1}).status_code == 422
    doc["vessels"] = []
    assert client.post("/api/poses", json={"document": doc, "frame": 0}).status_code == 422


# ------------------------------------------------------------------------------------------------ preview and runs


def test_preview_is_the_sheet_mmusv_preview_draws_of_a_run(client: TestClient, tmp_path: Path) -> None:
    doc = bundled_doc(client)
    camera = {"name": "front", "resolution": [160, 120], "mount": {"point": "camera_front"}}
    doc["rigs"] = {"usv_standard": {**SMALL_RIG, "cameras": [camera]}}
    r = client.post("/api/preview", json={"document": doc, "frame": 2, "agent": "usv_2"})
    assert r.status_code == 200 and r.headers["content-type"] == "image/png"
    got = np.asarray(Image.open(io.BytesIO(r.content)))
    res = mmusv.run(doc, out_dir=tmp_path / "run", frames=3)
    want, panels = compose_preview(res.recording, frame=2, agent="usv_2")
    assert got.shape == np.asarray(want).shape and np.array_equal(got, np.asarray(want))
    assert any("front camera" in p.title for p in panels)


def test_preview_refuses_what_it_cannot_draw(client: TestClient) -> None:
    doc = small(bundled_doc(client))
    r = client.post("/api/preview", json={"document": doc, "frame": 0, "agent": "ferry"})
    assert r.status_code == 422 and "usv_1" in r.json()["error"]
    r = client.post("/api/preview", json={"document": doc, "frame": 50})
    assert r.status_code == 422 and "0..49" in r.json()["error"]
    targets = {**doc, "vessels": [v for v in doc["vessels"] if v["role"] != "usv"]}
    r = client.post("/api/preview", json={"document": targets, "frame": 0})
    assert r.status_code == 422 and "no USV" in r.json()["error"]
    r = client.post("/api/preview", json={"document": {"vessels": "none"}, "frame": 0})
    assert r.status_code == 422 and "vessels" in r.json()["error"]


def _wait_run(client: TestClient, job: int) -> dict[str, Any]:
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        j: dict[str, Any] = client.get(f"/api/runs/{job}").json()
        if j["status"] != "running":
            return j
        time.sleep(0.1)  # polling a background process, as the page does
    raise AssertionError("the run did not end")


def test_runs_start_report_progress_and_stop(client: TestClient, folder: Path) -> None:
    doc = small(bundled_doc(client))
    assert client.put("/api/files/quick.yaml", json={"document": doc}).status_code == 200
    job = client.post("/api/runs", json={"name": "quick.yaml", "frames": 2}).json()
    assert job["command"] == "mmusv run quick.yaml -o out/quick --overwrite --frames 2"
    done = _wait_run(client, job["id"])
    assert done["status"] == "complete" and done["done"] == done["total"] == 2, done
    assert (folder / "out" / "quick" / "port_entry.mcap").is_file()
    assert [j["id"] for j in client.get("/api/runs").json()] == [job["id"]]
    long = client.post("/api/runs", json={"name": "quick.yaml"}).json()
    stopped = client.delete(f"/api/runs/{long['id']}").json()
    assert stopped["id"] == long["id"]
    end = _wait_run(client, long["id"])
    assert end["status"] in ("interrupted", "complete"), end
    assert client.post("/api/runs", json={"name": "missing.yaml"}).status_code == 404
    assert client.post("/api/runs", json={"name": "quick.yaml", "frames": 0}).status_code == 422
    assert client.get("/api/runs/999").status_code == 404
    assert client.get("/api/runs/abc").status_code == 422


def test_a_run_of_more_frames_than_the_file_records_is_refused(client: TestClient, folder: Path) -> None:
    """A review's: ``frames`` above the file's ``acquisition.frames`` started a job that then failed (and the page's
    20-digit count was rounded on its way); it is refused before anything starts, naming the file's count."""
    doc = small(bundled_doc(client))
    total = int(doc["acquisition"]["frames"])
    assert client.put("/api/files/few.yaml", json={"document": doc}).status_code == 200
    for frames in (total + 1, 10**20):
        r = client.post("/api/runs", json={"name": "few.yaml", "frames": frames})
        assert r.status_code == 422, r.text
        assert f"few.yaml records {total} (acquisition.frames); give 1..{total}" in r.json()["error"]
    assert client.get("/api/runs").json() == []
    assert not (folder / "out" / "few").exists()


def test_a_failing_run_reports_its_error(client: TestClient, folder: Path) -> None:
    doc = small(bundled_doc(client))
    doc["vessels"][0]["route"][2] = [-120, 600]  # over land: mmusv run refuses it
    assert client.put("/api/files/land.yaml", json={"document": doc}).status_code == 200
    job = client.post("/api/runs", json={"name": "land.yaml", "frames": 1}).json()
    end = _wait_run(client, job["id"])
    assert end["status"] == "failed" and "in_water" in end["error"]


# ------------------------------------------------------------------------------------------------ malformed


@pytest.mark.parametrize(
    ("method", "path", "kwargs", "status", "says"),
    [
        ("POST", "/api/evaluate", {"content": b"{oops", "headers": {"content-type": "application/json"}}, 422, "JSON"),
        ("POST", "/api/evaluate", {"json": {"document": "text"}}, 422, "document"),
        ("POST", "/api/evaluate", {"json": {"document": {}, "extra": 1}}, 422, "extra"),
        ("POST", "/api/evaluate", {"json": []}, 422, "malformed"),
        (
            "POST",
            "/api/evaluate",
            {"content": b"document=1", "headers": {"content-type": "text/plain"}},
            422,
            "malformed",
        ),
        ("POST", "/api/map", {"json": {"map": 5}}, 422, "map"),
        ("POST", "/api/poses", {"json": {"document": {}, "frame": "x"}}, 422, "frame"),
        ("PUT", "/api/files/a.yaml", {"json": {"document": {}, "overwrite": "maybe"}}, 422, "overwrite"),
        ("PUT", "/api/files/a.yaml", {"json": {"document": {}, "comment": "x" * 30000}}, 422, "comment"),
        ("POST", "/api/runs", {"json": {}}, 422, "name"),
        ("GET", "/api/nothing", {}, 404, "no API endpoint"),
        # an endpoint asked with another method: "no API endpoint" (404) or a bare "Method Not Allowed"
        ("DELETE", "/api/files/a.yaml", {}, 405, "/api/files/a.yaml takes GET or PUT, not DELETE"),
        ("POST", "/api/files/a.yaml", {}, 405, "/api/files/a.yaml takes GET or PUT, not POST"),
        ("GET", "/api/evaluate", {}, 405, "/api/evaluate takes POST, not GET"),
        ("POST", "/api/runs/1", {}, 405, "/api/runs/1 takes DELETE or GET, not POST"),
        ("GET", "/api/runs/-1", {}, 422, "path.job_id '-1': a run is named by a whole number"),  # it showed the regex
        ("PATCH", "/api/nothing", {}, 405, "Method Not Allowed"),
        (
            "POST",
            "/api/evaluate",
            {"content": b"x" * (MAX_BODY_BYTES + 1), "headers": {"content-type": "application/json"}},
            413,
            "larger",
        ),
    ],
)
def test_malformed_requests_get_a_4xx_with_a_message(
    client: TestClient, method: str, path: str, kwargs: dict[str, Any], status: int, says: str
) -> None:
    r = client.request(method, path, **kwargs)
    assert r.status_code == status, r.text
    assert says.lower() in r.json()["error"].lower()
    assert "Traceback" not in r.text


def test_evaluate_survives_any_json_document(client: TestClient) -> None:
    for document in ({}, {"vessels": None}, {"vessels": [1, "a", None]}, {"map": {"type": []}, "vessels": [{}]}):
        r = client.post("/api/evaluate", json={"document": document})
        assert r.status_code == 200 and r.json()["valid"] is False and r.json()["errors"], document


def test_other_hosts_are_refused(folder: Path) -> None:
    c = TestClient(create_app(folder, allowed_hosts=["127.0.0.1", "localhost"]), base_url="http://evil.example")
    assert c.get("/api/files").status_code == 400
    c = TestClient(create_app(folder, allowed_hosts=["127.0.0.1", "localhost"]), base_url="http://127.0.0.1:8765")
    assert c.get("/api/files").status_code == 200


def test_a_server_remembers_only_its_newest_finished_runs(
    client: TestClient, folder: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The runs list of a long-lived server does not grow without end: past KEEP_FINISHED finished runs, the
    oldest are forgotten when another starts (asking for one says why it is gone)."""
    import mmusv.editor.jobs as jobs

    monkeypatch.setattr(jobs, "KEEP_FINISHED", 1)
    doc = small(bundled_doc(client))
    doc["vessels"][0]["route"][2] = [-120, 600]  # over land: each run fails at once
    assert client.put("/api/files/land.yaml", json={"document": doc}).status_code == 200
    ids = []
    for _ in range(3):
        job = client.post("/api/runs", json={"name": "land.yaml", "frames": 1}).json()
        _wait_run(client, job["id"])
        ids.append(job["id"])
    listed = [j["id"] for j in client.get("/api/runs").json()]
    assert listed == [ids[2], ids[1]]  # the newest run and the one finished run kept when it started
    gone = client.get(f"/api/runs/{ids[0]}")
    assert gone.status_code == 404 and "newest 1 finished" in gone.text


def test_a_restarted_server_shows_the_runs_already_in_its_folder(client: TestClient, folder: Path) -> None:
    """A server starts knowing the finished runs in ``out/`` (one per manifest of a scenario file in the folder), so a
    file reopened after a restart shows its last run; a folder with no manifest (a run going on or killed), a broken
    manifest or no scenario file is not listed."""
    doc = small(bundled_doc(client))
    assert client.put("/api/files/quick.yaml", json={"document": doc}).status_code == 200
    job = client.post("/api/runs", json={"name": "quick.yaml", "frames": 2}).json()
    done = _wait_run(client, job["id"])
    assert done["status"] == "complete" and done["earlier"] is False
    # a run from the command line into the folder of another file, stopped after its first frame
    assert client.put("/api/files/cli.yml", json={"document": doc}).status_code == 200
    mmusv.run(folder / "cli.yml", out_dir=folder / "out" / "cli", frames=1)
    manifest = folder / "out" / "cli" / "manifest.json"
    meta = json.loads(manifest.read_text())
    manifest.write_text(json.dumps({**meta, "status": "interrupted", "frames_requested": 5}))
    os.utime(manifest, (time.time() + 5, time.time() + 5))  # written after quick's
    for name, text in [("orphan", json.dumps(meta)), ("broken", "{not json"), ("going_on", None)]:
        (folder / "out" / name).mkdir()
        if name != "orphan":
            (folder / f"{name}.yaml").write_text((folder / "quick.yaml").read_text())
        if text is not None:
            (folder / "out" / name / "manifest.json").write_text(text)
    restarted = TestClient(create_app(folder)).get("/api/runs").json()
    assert [(j["scenario"], j["status"], j["done"], j["total"], j["earlier"]) for j in restarted] == [
        ("cli.yml", "interrupted", 1, 5, True),
        ("quick.yaml", "complete", 2, 2, True),
    ], restarted
    cli, quick = restarted
    assert quick["output"] == "out/quick" and quick["command"] == "mmusv run quick.yaml -o out/quick --overwrite"
    assert quick["recording"] == done["recording"] and Path(quick["recording"]).is_file()
    assert quick["error"] is None and cli["error"] == "stopped before the end; the recording holds 1 frame"
    assert cli["id"] > quick["id"]  # newest first, as the page looks for a file's last run
    import mmusv.editor.jobs as jobs

    keep, jobs.KEEP_FINISHED = jobs.KEEP_FINISHED, 1
    try:  # a folder of many runs: the newest KEEP_FINISHED, as a long-lived server keeps
        assert [j["scenario"] for j in TestClient(create_app(folder)).get("/api/runs").json()] == ["cli.yml"]
    finally:
        jobs.KEEP_FINISHED = keep


def test_a_stopped_run_names_its_recording_and_frames(client: TestClient, folder: Path) -> None:
    """A run stopped from the page said ``"recording": null`` though its recording held every completed frame (a
    restarted server named it, from the run's manifest.json). Its 200 frames outlast the stop: with the bundled 50
    the run could end before it on a busy machine (and then, rightly, be complete)."""
    doc = small(bundled_doc(client))
    doc["acquisition"] = {**doc["acquisition"], "frames": 200}
    assert client.put("/api/files/stopme.yaml", json={"document": doc}).status_code == 200
    job = client.post("/api/runs", json={"name": "stopme.yaml"}).json()
    deadline = time.monotonic() + 120
    while client.get(f"/api/runs/{job['id']}").json()["done"] < 1:  # a frame written: the recording is open
        assert time.monotonic() < deadline, "no frame in 120 s"
        time.sleep(0.05)
    client.delete(f"/api/runs/{job['id']}")
    end = _wait_run(client, job["id"])
    manifest = json.loads((folder / "out" / "stopme" / "manifest.json").read_text())
    assert end["status"] == "interrupted" and end["recording"] == str(folder / "out" / "stopme" / "port_entry.mcap"), (
        end  # (its error says which way the recording went unnamed, should it again)
    )
    assert end["done"] == manifest["frames_written"] >= 1, (end, manifest)


def test_a_run_past_the_most_at_a_time_is_a_conflict(
    client: TestClient, folder: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """It was 400, the answer to a bad request; the request is good and the editor busy: 409, as for a second run of
    the same output folder."""
    from mmusv.editor import jobs as editor_jobs

    monkeypatch.setattr(editor_jobs, "MAX_RUNNING", 1)
    doc = small(bundled_doc(client))
    for name in ("one.yaml", "two.yaml"):
        assert client.put(f"/api/files/{name}", json={"document": doc}).status_code == 200
    first = client.post("/api/runs", json={"name": "one.yaml"}).json()
    try:
        r = client.post("/api/runs", json={"name": "two.yaml"})
        assert r.status_code == 409 and "the most the editor runs at a time" in r.json()["error"], r.text
    finally:
        client.delete(f"/api/runs/{first['id']}")
        _wait_run(client, first["id"])
