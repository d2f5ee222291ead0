"""A round through the editor in a real headless Chromium, as a careful person clicks it: entries the page cannot
use are refused next to their field (the scenario keeps its value, other edits stay), schema errors show next to
the field they concern, a vessel cannot take another's id, stale waypoint handles delete nothing, playing stops
at the frames the scenario has, a small window keeps every control on the page, the lists work from the keyboard,
a cancelled Open and a save leave the page showing what it holds, and a run is followed across a reload and
started by "Overwrite and run".

Each test checks the browser's console for JavaScript errors (responses with an error status, which the page
shows, are not errors of the page).
"""

from __future__ import annotations

import json
import urllib.request
from typing import Any

import yaml
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys
from selenium.webdriver.support.select import Select
from selenium.webdriver.support.ui import WebDriverWait
from test_browser import LiveServer, _wait, act_on, document_of, open_editor, pick_open, settled


def js_errors(driver: Any) -> list[str]:
    """The console's errors since the last call, but failed requests (a 409 or 422 the page explains)."""
    return [
        e["message"]
        for e in driver.get_log("browser")
        if e["level"] == "SEVERE" and "Failed to load resource" not in e["message"]
    ]


def type_into(driver: Any, element: Any, text: str) -> None:
    """Replaces the text of `element` by `text` and leaves the field (its change event)."""
    element.click()
    element.send_keys(Keys.CONTROL, "a")
    element.send_keys(Keys.DELETE)
    if text:
        element.send_keys(text)
    element.send_keys(Keys.TAB)


def note(driver: Any, field: str) -> str:
    """The note shown next to the form field of the scenario path `field` ("" when none)."""
    notes = driver.find_elements(By.CSS_SELECTOR, f'.field-note[data-for="{field}"]')
    return str(notes[0].text) if notes else ""


def test_scenario_form_refuses_what_it_cannot_use_next_to_the_field(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    field = browser.find_element(By.ID, "e-visibility")
    type_into(browser, field, "2500")  # an edit that must survive the refusals below
    settled(browser)
    frames = browser.find_element(By.ID, "a-frames")
    type_into(browser, frames, "1e")  # the browser cannot read it: it reads as empty, which was "the default, 100"
    settled(browser)
    doc = document_of(browser)
    assert doc["acquisition"]["frames"] == 50 and doc["environment"]["visibility_m"] == 2500
    text = note(browser, "acquisition.frames")
    assert "frames: not a number" in text and "1 or more" in text, text
    assert frames.get_attribute("aria-invalid") == "true"

    params = browser.find_element(By.ID, "m-params")
    type_into(browser, params, "{quays")
    seed = browser.find_element(By.ID, "m-seed")
    type_into(browser, seed, "1e400")  # was read as empty: map seed 0, another map
    settled(browser)
    assert document_of(browser)["map"] == {"type": "port", "seed": 3}
    assert "map parameters: not JSON" in note(browser, "map.params")
    assert "map seed: not a number" in note(browser, "map.seed")
    type_into(browser, field, "-4")  # a value the schema refuses: its message is next to the field
    settled(browser)
    assert params.get_attribute("value") == "{quays"  # what was typed is still there to fix
    assert "environment.visibility_m = -4" in note(browser, "environment.visibility_m")
    type_into(browser, field, "2500")
    settled(browser)
    assert note(browser, "environment.visibility_m") == ""

    wave = browser.find_element(By.ID, "e-wave")
    Select(wave).select_by_value("custom")
    prompt = browser.switch_to.alert
    prompt.send_keys("abc")
    prompt.accept()
    settled(browser)
    assert document_of(browser)["environment"]["wave"] == "W1"  # was NaN, sent as null: "wave = None"
    assert wave.get_attribute("value") == "W1"
    assert 'wave: "abc" is not a number' in note(browser, "environment.wave")

    type_into(browser, frames, "10")  # a good entry takes the note away
    settled(browser)
    assert document_of(browser)["acquisition"]["frames"] == 10 and note(browser, "acquisition.frames") == ""
    browser.find_element(By.ID, "undo").click()  # undo shows the scenario's values again, without old refusals
    settled(browser)
    assert not browser.find_elements(By.CSS_SELECTOR, ".field-note")
    assert params.get_attribute("value") == "" and seed.get_attribute("value") == "3"
    assert js_errors(browser) == []


def test_vessel_form_keeps_ids_unique_and_numbers_readable(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    browser.find_element(By.CSS_SELECTOR, '#fleet li[data-id="usv_2"]').click()
    ids = [v["id"] for v in document_of(browser)["vessels"]]
    type_into(browser, browser.find_element(By.ID, "v-id"), "usv_1")
    settled(browser)
    # written, the panel jumped to the other usv_1 and the next edit (the speed below) went to that vessel
    assert [v["id"] for v in document_of(browser)["vessels"]] == ids
    assert browser.execute_script("return window.mmusvEditor.state.selected") == "usv_2"
    assert "is the id of another vessel" in note(browser, "vessels[1].id")
    type_into(browser, browser.find_element(By.ID, "v-speed"), "7")
    settled(browser)
    speeds = {v["id"]: v["speed_mps"] for v in document_of(browser)["vessels"]}
    assert speeds["usv_2"] == 7 and speeds["usv_1"] == 2.5

    route = document_of(browser)["vessels"][1]["route"]
    cell = browser.find_element(By.CSS_SELECTOR, '#v-route tr[data-index="1"] input[data-axis="0"]')
    type_into(browser, cell, "1e")  # was read as 0: the waypoint jumped to x = 0
    type_into(browser, browser.find_element(By.ID, "v-speed"), "")  # was read as 0: the vessel stopped
    settled(browser)
    v = document_of(browser)["vessels"][1]
    assert v["route"] == route and v["speed_mps"] == 7
    assert "waypoint 1 x (east): not a number" in note(browser, "vessels[1].route[1][0]")
    assert "speed: empty" in note(browser, "vessels[1].speed_mps")
    type_into(browser, browser.find_element(By.ID, "v-offset"), "-3")
    settled(browser)
    assert "vessels[1].start_offset_m = -3" in note(browser, "vessels[1].start_offset_m")
    assert js_errors(browser) == []


def test_delete_key_after_the_vessel_is_gone(browser: Any, live_server: LiveServer) -> None:
    """A waypoint handle clicked, then its vessel deleted: Delete on the map threw a TypeError (and left a step in
    the undo history that changed nothing)."""
    open_editor(browser, live_server)
    js_errors(browser)
    browser.find_element(By.CSS_SELECTOR, '#fleet li[data-id="tug"]').click()
    act_on(
        browser,
        'circle.waypoint[data-vessel="tug"][data-index="0"]',
        lambda handle: ActionChains(browser).click(handle).perform(),
    )
    browser.find_element(By.ID, "v-delete").click()
    settled(browser)
    steps = browser.execute_script("return window.mmusvEditor.state.undoStack.length")
    browser.execute_script("document.getElementById('map').focus()")
    ActionChains(browser).send_keys(Keys.DELETE).perform()
    settled(browser)
    assert js_errors(browser) == []
    assert browser.execute_script("return window.mmusvEditor.state.undoStack.length") == steps
    assert "tug" not in [v["id"] for v in document_of(browser)["vessels"]]


def test_play_stops_at_the_frames_the_scenario_has(browser: Any, live_server: LiveServer) -> None:
    """Fewer frames typed while playing: the play went on to the old last frame ("frame 19 / 7")."""
    open_editor(browser, live_server)
    js_errors(browser)
    frames = browser.find_element(By.ID, "a-frames")
    type_into(browser, frames, "20")
    settled(browser)
    browser.find_element(By.ID, "play").click()
    type_into(browser, frames, "8")
    _wait(browser, "return document.getElementById('play').textContent === 'Play'", "the play to stop")
    settled(browser)
    k = browser.execute_script("return window.mmusvEditor.state.frame")
    assert k <= 7
    assert browser.find_element(By.ID, "frame-text").text.startswith(f"frame {k} / 7")
    assert js_errors(browser) == []


def test_small_window_keeps_every_control_on_the_page(browser: Any, live_server: LiveServer) -> None:
    """At 800 x 600 the toolbar did not wrap and pushed the page wider than the window: Preview, Run, the status and
    the whole right panel (checks, scenario form) were off the page, which does not scroll."""
    size = browser.get_window_size()
    browser.set_window_size(800, 600)
    try:
        open_editor(browser, live_server)
        width, height = browser.execute_script("return [window.innerWidth, window.innerHeight]")
        for id_ in ("open", "file-name", "save", "undo", "redo", "preview", "run-frames", "run", "status", "map",
                    "fit", "zoom-out", "problems", "s-name", "play", "frame-text"):  # fmt: skip
            left, top, right, bottom = browser.execute_script(
                "const r = document.getElementById(arguments[0]).getBoundingClientRect();"
                "return [r.left, r.top, r.right, r.bottom]",
                id_,
            )
            assert left >= 0 and top >= 0 and right <= width + 0.5 and bottom <= height + 0.5, (id_, left, right)
        assert browser.execute_script("return document.documentElement.scrollWidth") <= width
        map_width = browser.find_element(By.ID, "map").rect["width"]
        assert map_width >= 250
    finally:
        browser.set_window_size(size["width"], size["height"])


def test_lists_work_from_the_keyboard(browser: Any, live_server: LiveServer) -> None:
    """The vessel list and the library were reachable by mouse only (no tab stop, Enter did nothing)."""
    open_editor(browser, live_server)
    js_errors(browser)
    item = browser.find_element(By.CSS_SELECTOR, '#fleet li[data-id="tug"]')
    assert item.get_attribute("tabindex") == "0"
    browser.execute_script("arguments[0].focus()", item)
    ActionChains(browser).send_keys(Keys.ENTER).perform()
    _wait(browser, "return window.mmusvEditor.state.selected === 'tug'", "tug to be selected")
    ActionChains(browser).send_keys(Keys.TAB, Keys.SPACE).perform()  # the next vessel, with Space
    _wait(browser, "return window.mmusvEditor.state.selected === 'yacht'", "yacht to be selected")
    asset = browser.find_element(By.CSS_SELECTOR, '#library li[data-asset="tug_32m"]')
    browser.execute_script("arguments[0].focus()", asset)
    assert asset.get_attribute("tabindex") == "0"  # the library's one tab stop (test_browser_round7) follows focus
    ActionChains(browser).send_keys(Keys.ENTER).perform()
    assert browser.execute_script("return window.mmusvEditor.map.mode") == "place"
    ActionChains(browser).send_keys(Keys.ESCAPE).perform()
    assert browser.execute_script("return window.mmusvEditor.map.mode") == "select"
    for button in browser.find_elements(By.CSS_SELECTOR, "#zoom-in, #zoom-out, #v-route button"):
        assert len(button.accessible_name) > 2, button.get_attribute("outerHTML")
    assert js_errors(browser) == []


def test_cancelled_open_and_save_leave_the_page_showing_what_it_holds(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    type_into(browser, browser.find_element(By.ID, "e-visibility"), "2000")
    settled(browser)
    assert browser.title.startswith("● port_entry.yaml")
    pick_open(browser, "bundled:island_occlusion")
    browser.switch_to.alert.dismiss()  # keep the edits
    # the Open box went on naming island_occlusion while port_entry stayed open
    assert browser.find_element(By.ID, "open").get_attribute("value") == ""
    assert document_of(browser)["name"] == "port_entry"
    name = browser.find_element(By.ID, "file-name")
    name.clear()
    name.send_keys("kept.yaml")
    browser.find_element(By.ID, "save").click()
    _wait(browser, "return document.body.dataset.saved === 'kept.yaml'", "the save")
    # the title kept the unsaved mark and the old name
    assert browser.title == "kept.yaml · mmusv editor"
    saved = yaml.safe_load((live_server.folder / "kept.yaml").read_text(encoding="utf-8"))
    assert saved["environment"]["visibility_m"] == 2000
    assert js_errors(browser) == []


def test_a_run_is_followed_across_a_reload_and_overwrite_runs(browser: Any, live_server: LiveServer) -> None:
    """A page loaded again showed nothing of the run going on; Run on a file that exists asked to overwrite it, and
    Overwrite saved it without starting the run."""
    open_editor(browser, live_server)
    js_errors(browser)
    preset = '#rigs [data-rig="usv_standard"] select[data-key="preset"]'
    Select(browser.find_element(By.CSS_SELECTOR, preset)).select_by_value("lidar_only")
    type_into(browser, browser.find_element(By.ID, "a-frames"), "5000")  # a run that lasts past the reload
    settled(browser)
    name = browser.find_element(By.ID, "file-name")
    name.clear()
    name.send_keys("again.yaml")
    browser.find_element(By.ID, "save").click()
    _wait(browser, "return document.body.dataset.saved === 'again.yaml'", "the save")
    request = urllib.request.Request(
        live_server.url + "/api/runs",
        data=json.dumps({"name": "again.yaml"}).encode(),
        headers={"Content-Type": "application/json"},
    )
    with urllib.request.urlopen(request) as res:
        job = json.load(res)
    assert job["status"] == "running"
    open_editor(browser, live_server)  # loaded again
    _wait(browser, "return document.getElementById('run-status').dataset.status === 'running'", "the run shown")
    browser.find_element(By.ID, "run-stop").click()
    _wait(browser, "return document.getElementById('run-status').dataset.status === 'interrupted'", "the stop")

    Select(browser.find_element(By.CSS_SELECTOR, preset)).select_by_value("lidar_only")
    settled(browser)
    name = browser.find_element(By.ID, "file-name")
    name.clear()
    name.send_keys("again.yaml")
    type_into(browser, browser.find_element(By.ID, "run-frames"), "2")
    browser.find_element(By.ID, "run").click()
    overwrite = browser.find_element(By.ID, "save-overwrite")
    WebDriverWait(browser, 20).until(lambda d: overwrite.is_displayed(), message="the overwrite question")
    assert overwrite.text == "Overwrite and run"
    overwrite.click()
    WebDriverWait(browser, 30, poll_frequency=0.1).until(
        lambda d: (
            d.execute_script("return document.getElementById('run-status').dataset.status") == "complete"
            and "done: 2 frames" in d.find_element(By.ID, "run-text").text
        ),
        message="the run started by Overwrite and run",
    )
    assert js_errors(browser) == []
