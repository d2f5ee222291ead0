"""The editor in a real headless Chromium (Selenium): open, place vessels by clicking, draw and drag routes onto
land and back, save and run what was drawn, scrub the time slider against ``Simulation.world_state``, preview a
frame, run in the background, and refuse traversal and malformed requests. Screenshots go to
``$MMUSV_EDITOR_SCREENSHOTS`` (``make screenshots``: ``docs/editor/``).

Synchronisation is by explicit waits on the page's own state: ``body[data-ready]`` once booted and
``body[data-pending="0"]`` when no evaluation is in flight or queued after the last edit.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import pytest
from mmusv.bundled import resolve_scenario
from mmusv.config import load_scenario
from mmusv.generate.mapctx import map_context
from mmusv.recording.info import read_info
from selenium.common.exceptions import StaleElementReferenceException
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys
from selenium.webdriver.support.select import Select
from selenium.webdriver.support.ui import WebDriverWait

# Screenshots: into the folder named by MMUSV_EDITOR_SCREENSHOTS (`make screenshots` gives docs/editor/), else a
# temporary folder, so a test run leaves the checkout as it was.
DOCS = Path(os.environ.get("MMUSV_EDITOR_SCREENSHOTS") or tempfile.mkdtemp(prefix="mmusv-editor-shots-"))
WAIT_S = 60
LiveServer = Any  # the live_server fixture of conftest.py: .url, .folder, .app

# Port map seed 3 (port_entry): open water south of the breakwater, and land north of the quays.
USV_ROUTE = [(250.0, -480.0), (450.0, -500.0)]
TARGET_ROUTE = [(300.0, -600.0), (520.0, -610.0)]
LAND = (420.0, 700.0)


def _wait(driver: Any, script: str, what: str) -> Any:
    return WebDriverWait(driver, WAIT_S, poll_frequency=0.05).until(
        lambda d: d.execute_script(script), message=f"timed out waiting for {what}"
    )


def act_on(driver: Any, css: str, act: Any) -> Any:
    """``act(element)`` on the element ``css`` finds, found again while a redraw replaced it in between: a map
    redraw (after an evaluation, on a busy machine) can make a handle or marker stale between finding it and acting
    on it, and Selenium refuses a stale element before any input is sent, so trying again is safe. Returns what
    ``act`` returned (``None`` taken as done)."""

    def attempt(d: Any) -> Any:
        out = act(d.find_element(By.CSS_SELECTOR, css))
        return True if out is None else out

    return WebDriverWait(
        driver, WAIT_S, poll_frequency=0.05, ignored_exceptions=(StaleElementReferenceException,)
    ).until(attempt, message=f"timed out acting on {css}")


def settled(driver: Any) -> None:
    """Waits until the page has evaluated the document as it is now."""
    _wait(driver, "return document.body.dataset.pending === '0'", "the evaluation")


def pick_open(driver: Any, value: str) -> None:
    """Picks ``value`` (``file:NAME`` or ``bundled:NAME``) in the Open box as a person does: reaching the box (its
    focus) reads the folder's files again and replaces the list, so the option is picked once that list is shown
    (``data-listing`` not "reading"), never one of the list it replaces (a stale element, on a busy machine)."""
    driver.find_element(By.ID, "open").click()
    _wait(
        driver,
        "const s = document.getElementById('open'); return s.dataset.listing !== 'reading' && "
        f"[...s.options].some((o) => o.value === {json.dumps(value)})",
        f"{value} in the Open box",
    )
    Select(driver.find_element(By.ID, "open")).select_by_value(value)


def open_editor(driver: Any, server: LiveServer) -> None:
    driver.get(server.url + "/")
    _wait(
        driver,
        "return document.body.dataset.ready === '1' && document.body.dataset.pending === '0' "
        "&& !!document.getElementById('map-image')",
        "the editor to load port_entry and its map",
    )


def set_view(driver: Any, cx: float, cy: float, scale: float) -> None:
    driver.execute_script(
        "const m = window.mmusvEditor.map; m.view = {cx: arguments[0], cy: arguments[1], scale: arguments[2]}; "
        "m.applyView();",
        cx,
        cy,
        scale,
    )


def view(driver: Any) -> dict[str, float]:
    """The view (cx, cy metres at the centre, scale px/m) and the map's box on the page (px)."""
    out: dict[str, float] = driver.execute_script(
        "const m = window.mmusvEditor.map, r = m.svg.getBoundingClientRect();"
        "return {cx: m.view.cx, cy: m.view.cy, scale: m.view.scale, left: r.left, top: r.top, w: r.width, h: r.height};"
    )
    return out


def page_xy(v: dict[str, float], x: float, y: float) -> tuple[float, float]:
    """Where the world point (x, y) metres is on the page: north up, ``scale`` px per metre about the centre."""
    return v["left"] + v["w"] / 2 + (x - v["cx"]) * v["scale"], v["top"] + v["h"] / 2 - (y - v["cy"]) * v["scale"]


def click_world(driver: Any, x: float, y: float) -> tuple[float, float]:
    """Clicks the map at the world point (x, y); returns the world point of the pixel actually clicked."""
    v = view(driver)
    px, py = page_xy(v, x, y)
    svg = driver.find_element(By.ID, "map")
    dx, dy = round(px - (v["left"] + v["w"] / 2)), round(py - (v["top"] + v["h"] / 2))
    ActionChains(driver).move_to_element_with_offset(svg, dx, dy).click().perform()
    return v["cx"] + dx / v["scale"], v["cy"] - dy / v["scale"]


def drag_waypoint(driver: Any, vessel: str, index: int, to: tuple[float, float]) -> None:
    def drag(handle: Any) -> None:
        v = view(driver)
        hx, hy = float(handle.get_attribute("cx")) + v["left"], float(handle.get_attribute("cy")) + v["top"]
        tx, ty = page_xy(v, *to)
        chain = ActionChains(driver).click_and_hold(handle)
        steps = 6
        done_x = done_y = 0
        for k in range(1, steps + 1):
            sx, sy = round((tx - hx) * k / steps) - done_x, round((ty - hy) * k / steps) - done_y
            chain.move_by_offset(sx, sy)
            done_x, done_y = done_x + sx, done_y + sy
        chain.release().perform()

    act_on(driver, f'circle.waypoint[data-vessel="{vessel}"][data-index="{index}"]', drag)


def document_of(driver: Any) -> dict[str, Any]:
    doc: dict[str, Any] = driver.execute_script("return window.mmusvEditor.state.doc")
    return doc


def shot(driver: Any, name: str) -> None:
    DOCS.mkdir(parents=True, exist_ok=True)
    driver.save_screenshot(str(DOCS / name))


def test_opens_a_bundled_scenario(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    shot(browser, "overview.png")
    pick_open(browser, "bundled:island_occlusion")
    _wait(
        browser,
        "const s = window.mmusvEditor.state; return s.doc.name === 'island_occlusion' && "
        "s.mapLayers && s.mapLayers.kind === 'island' && document.body.dataset.pending === '0'",
        "island_occlusion and its map",
    )
    expected = load_scenario(resolve_scenario("island_occlusion"))
    ids = [e.get_attribute("data-id") for e in browser.find_elements(By.CSS_SELECTOR, "#fleet li")]
    assert ids == [v.id for v in expected.vessels]
    markers = browser.find_elements(By.CSS_SELECTOR, "circle.vessel-marker")
    assert sorted(m.get_attribute("data-id") for m in markers) == sorted(ids)
    assert load_scenario(document_of(browser)) == expected


def test_place_draw_drag_onto_land_and_back_save_and_run(browser: Any, live_server: LiveServer, tmp_path: Path) -> None:
    ctx = map_context("port", seed=3, params={})
    for p in [*USV_ROUTE, *TARGET_ROUTE]:
        assert ctx.lookup(ctx.d_nav, np.array(p)) > 60.0, f"{p} should be open water"
    assert ctx.lookup(ctx.d_shore, np.array(LAND)) == 0.0 and ctx.world.heightfield.sample(np.array([LAND]))[0] > 0
    open_editor(browser, live_server)
    set_view(browser, 330.0, 20.0, 0.42)
    n0 = len(document_of(browser)["vessels"])

    clicked: dict[str, list[tuple[float, float]]] = {}
    for asset, route in (("usv_wamv", USV_ROUTE), ("tug_32m", TARGET_ROUTE)):
        search = browser.find_element(By.ID, "library-search")
        search.clear()
        search.send_keys(asset.split("_")[0])
        browser.find_element(By.CSS_SELECTOR, f'#library li[data-asset="{asset}"]').click()
        clicked[asset] = [click_world(browser, *p) for p in route]
        browser.find_element(By.ID, "drawing-done").click()
        settled(browser)

    doc = document_of(browser)
    usv, target = doc["vessels"][n0], doc["vessels"][n0 + 1]
    assert (usv["role"], usv["asset"], usv["rig"]) == ("usv", "usv_wamv", "usv_standard")
    assert (target["role"], target["asset"]) == ("target", "tug_32m")
    px = 1.0 / view(browser)["scale"]
    for vessel, asset in ((usv, "usv_wamv"), (target, "tug_32m")):
        assert len(vessel["route"]) == 2
        for got, want in zip(vessel["route"], clicked[asset], strict=True):
            assert math.dist(got, want) <= 0.1, (got, want)
        for got, want in zip(vessel["route"], USV_ROUTE if asset == "usv_wamv" else TARGET_ROUTE, strict=True):
            assert math.dist(got, want) <= px, (got, want)
    tid, t_index = target["id"], n0 + 1
    field = f"vessels[{t_index}].route"
    in_water = f'li.problem.error[data-check="in_water"][data-field="{field}"]'
    assert not browser.find_elements(By.CSS_SELECTOR, in_water)

    drag_waypoint(browser, tid, 1, LAND)
    settled(browser)
    item = browser.find_element(By.CSS_SELECTOR, in_water)
    assert tid in item.text and field in item.text
    assert browser.find_elements(By.CSS_SELECTOR, f'path.route-bad[data-vessel="{tid}"][data-check="in_water"]')
    assert browser.find_elements(By.CSS_SELECTOR, f'circle.vessel-flag.error[data-id="{tid}"]')
    moved = document_of(browser)["vessels"][t_index]["route"][1]
    assert math.dist(moved, LAND) <= 2 * px
    shot(browser, "route_on_land.png")

    drag_waypoint(browser, tid, 1, TARGET_ROUTE[1])
    settled(browser)
    assert not browser.find_elements(By.CSS_SELECTOR, in_water)
    assert not browser.find_elements(By.CSS_SELECTOR, f'path.route-bad[data-vessel="{tid}"]')
    assert not browser.find_elements(By.CSS_SELECTOR, f'circle.vessel-flag.error[data-id="{tid}"]')
    shot(browser, "vessels_added.png")

    name = browser.find_element(By.ID, "file-name")
    name.clear()
    name.send_keys("drawn.yaml")
    browser.find_element(By.ID, "save").click()
    _wait(browser, "return document.body.dataset.saved === 'drawn.yaml'", "the save")
    saved = live_server.folder / "drawn.yaml"
    scenario = load_scenario(saved)
    assert scenario == load_scenario(document_of(browser))
    assert [v.id for v in scenario.vessels][-2:] == [usv["id"], tid]
    # two frames of what was drawn, with a small LiDAR-only rig to keep the suite quick
    small = scenario.model_dump(mode="json")
    small["rigs"] = {"usv_standard": {"preset": "lidar_only", "lidar": {"channels": 16, "points_per_second": 20000}}}
    res = mmusv.run(small, out_dir=tmp_path / "run", frames=2)
    assert res.status == "complete" and res.frames_written == 2


def test_time_slider_matches_world_state(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    k = 37
    slider = browser.find_element(By.ID, "frame")
    slider.click()
    slider.send_keys(Keys.HOME)
    for _ in range(k):
        slider.send_keys(Keys.ARROW_RIGHT)
    _wait(browser, f"return window.mmusvEditor.state.frame === {k}", f"frame {k}")
    sim = mmusv.Simulation(resolve_scenario("port_entry"))
    state = sim.world_state(k)
    assert "frame 37 / 49" in browser.find_element(By.ID, "frame-text").text
    for scale in (0.5, 4.0):
        set_view(browser, float(state.poses[0, 0]), float(state.poses[0, 1]), scale)
        v = view(browser)
        for i, vessel in enumerate(sim.scenario.vessels):
            marker = browser.find_element(By.CSS_SELECTOR, f'circle.vessel-marker[data-id="{vessel.id}"]')
            r = browser.execute_script(
                "const b = arguments[0].getBoundingClientRect(); return [b.left + b.width / 2, b.top + b.height / 2];",
                marker,
            )
            want = page_xy(v, float(state.poses[i, 0]), float(state.poses[i, 1]))
            assert math.dist(r, want) <= 1.0, (vessel.id, scale, r, want)
    set_view(browser, -40.0, -150.0, 1.1)
    shot(browser, "timeline.png")


def test_preview_frame(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    browser.execute_script("window.mmusvEditor.state.setFrame(10)")
    browser.find_element(By.CSS_SELECTOR, '#fleet li[data-id="usv_1"]').click()
    browser.find_element(By.ID, "preview").click()
    _wait(
        browser,
        "const i = document.getElementById('preview-img'); return !i.hidden && i.complete && i.naturalWidth > 0",
        "the preview image",
    )
    size = browser.execute_script(
        "const i = document.getElementById('preview-img'); return [i.naturalWidth, i.naturalHeight]"
    )
    assert size[0] >= 1000 and size[1] >= 800  # four 320 px camera columns, four panel rows
    assert "usv_1 · frame 10" in browser.find_element(By.ID, "preview-title").text
    shot(browser, "preview.png")
    browser.find_element(By.ID, "preview-close").click()


def test_rig_camera_quality_is_set_and_cleared(browser: Any, live_server: LiveServer) -> None:
    """The rig panel's camera quality writes the rig's ``quality`` (every camera and top view of the rig that sets
    none of its own) and "default" takes it out again."""
    from selenium.webdriver.support.select import Select

    open_editor(browser, live_server)
    css = '#rigs [data-rig="usv_standard"] select[data-key="quality"]'
    Select(browser.find_element(By.CSS_SELECTOR, css)).select_by_value("draft")
    settled(browser)
    assert document_of(browser)["rigs"]["usv_standard"] == {"quality": "draft"}
    Select(browser.find_element(By.CSS_SELECTOR, css)).select_by_value("default")
    settled(browser)
    assert document_of(browser)["rigs"]["usv_standard"] == {}


def test_run_in_the_background(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    preset = browser.find_element(By.CSS_SELECTOR, '#rigs [data-rig="usv_standard"] select[data-key="preset"]')
    from selenium.webdriver.support.select import Select

    Select(preset).select_by_value("lidar_only")
    settled(browser)
    assert document_of(browser)["rigs"]["usv_standard"] == {"preset": "lidar_only"}
    name = browser.find_element(By.ID, "file-name")
    name.clear()
    name.send_keys("run_me.yaml")
    frames = browser.find_element(By.ID, "run-frames")
    frames.clear()
    frames.send_keys("2")
    browser.find_element(By.ID, "run").click()
    _wait(browser, "return document.getElementById('run-status').dataset.status === 'complete'", "the run")
    assert "done: 2 frames" in browser.find_element(By.ID, "run-text").text
    rec = live_server.folder / "out" / "run_me" / "port_entry.mcap"
    assert rec.is_file()
    info = read_info(rec)
    assert [a.id for a in info.agents] == ["usv_1", "usv_2", "usv_3"]


@pytest.mark.parametrize("typed", ["1e", "-", "0", "2.5"])
def test_a_frames_box_it_cannot_read_starts_no_run(browser: Any, live_server: LiveServer, typed: str) -> None:
    """A number box the browser cannot parse ("1e", "-") reads as empty, which means every frame: the page says so
    and starts nothing (it started a full run); 0 and 2.5 are refused the same way before the server is asked."""
    open_editor(browser, live_server)
    frames = browser.find_element(By.ID, "run-frames")
    frames.clear()
    frames.send_keys(typed)
    before = sorted(p.name for p in live_server.folder.rglob("*"))
    browser.find_element(By.ID, "run").click()
    _wait(browser, "return document.getElementById('status').classList.contains('error')", "the error")
    assert "whole number of frames" in browser.find_element(By.ID, "status").text
    assert sorted(p.name for p in live_server.folder.rglob("*")) == before  # nothing saved, nothing run
    assert browser.execute_script("return document.getElementById('run-status').dataset.status") in (None, "")


@pytest.mark.parametrize(
    ("method", "path", "body", "status"),
    [
        ("GET", "/api/files/..%2F..%2F..%2Fetc%2Fpasswd", None, 400),
        ("GET", "/api/files/%2Fetc%2Fhostname.yaml", None, 400),
        ("GET", "/api/files/notes.txt", None, 400),
        ("PUT", "/api/files/..%2Fescape.yaml", '{"document": {}}', 400),
        ("GET", "/static/..%2F..%2Fapp.py", None, 404),
        ("POST", "/api/evaluate", "{not json", 422),
        ("POST", "/api/evaluate", '{"document": [1, 2]}', 422),
        ("POST", "/api/preview", '{"document": {}, "frame": -1}', 422),
    ],
)
def test_refuses_traversal_and_malformed_requests(
    browser: Any, live_server: LiveServer, method: str, path: str, body: str | None, status: int
) -> None:
    if not browser.current_url.startswith(live_server.url):
        browser.get(live_server.url + "/")
    got = browser.execute_async_script(
        "const [method, path, body, done] = arguments;"
        "fetch(path, {method, body, headers: body ? {'Content-Type': 'application/json'} : {}})"
        ".then(async r => done([r.status, await r.text()])).catch(e => done([0, String(e)]));",
        method,
        path,
        body,
    )
    assert got[0] == status, got
    assert "Traceback" not in got[1] and "root:" not in got[1]
    assert '"error"' in got[1]
