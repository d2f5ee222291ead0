"""A second round through the editor in a real headless Chromium: a custom wave has a number box of its own, the
preview window keeps the keyboard until Escape gives it back, the unsaved mark follows undo and redo back to the
saved scenario, a page loaded again shows the last run of its file (one that ended too, and after a restart of the
server), the vessel library fits a narrow window, and a waypoint can be added from the keyboard.

Each test checks the browser's console for JavaScript errors (failed requests the page explains are not errors).
"""

from __future__ import annotations

import json
import time
import urllib.request
from typing import Any

import yaml
from editor_server import serve
from mmusv.world.environment import MAX_WAVE_HEIGHT_M
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys
from selenium.webdriver.support.select import Select
from test_browser import LiveServer, _wait, document_of, open_editor, pick_open, settled
from test_browser_round import js_errors, note, type_into


def active_id(driver: Any) -> str:
    return str(driver.execute_script("return document.activeElement.id"))


def save_as(driver: Any, name: str) -> None:
    box = driver.find_element(By.ID, "file-name")
    box.clear()
    box.send_keys(name)
    driver.find_element(By.ID, "save").click()
    _wait(driver, f"return document.body.dataset.saved === {json.dumps(name)} && !window.mmusvEditor.state.dirty", name)


def api(server: LiveServer, path: str, body: dict[str, Any] | None = None) -> Any:
    data = None if body is None else json.dumps(body).encode()
    request = urllib.request.Request(server.url + path, data=data, headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(request) as res:
        return json.load(res)


def run_to_end(server: LiveServer, name: str, frames: int) -> dict[str, Any]:
    """Runs the folder file `name` through the API and waits for the run to end; returns it."""
    job = api(server, "/api/runs", {"name": name, "frames": frames})
    deadline = time.monotonic() + 40
    while job["status"] == "running" and time.monotonic() < deadline:
        time.sleep(0.2)
        job = api(server, f"/api/runs/{job['id']}")
    assert job["status"] != "running", job
    return dict(job)


def test_a_custom_wave_is_changed_in_its_own_box(browser: Any, live_server: LiveServer) -> None:
    """Changing a custom wave took two steps (a preset, then "custom" again: choosing "custom" while the wave was
    custom did nothing)."""
    open_editor(browser, live_server)
    js_errors(browser)
    wave = browser.find_element(By.ID, "e-wave")
    box = browser.find_element(By.ID, "e-wave-height")
    assert not box.is_displayed()  # a preset (W1): no height to type
    Select(wave).select_by_value("custom")
    prompt = browser.switch_to.alert  # from a preset, the height is asked for
    prompt.send_keys("30")
    prompt.accept()
    settled(browser)
    assert document_of(browser)["environment"]["wave"] == "W1" and not box.is_displayed()
    assert "wave: 30 m is out of range" in note(browser, "environment.wave")
    Select(wave).select_by_value("custom")
    prompt = browser.switch_to.alert
    prompt.send_keys("2")
    prompt.accept()
    settled(browser)
    assert document_of(browser)["environment"]["wave"] == 2
    assert box.is_displayed() and box.get_attribute("value") == "2"
    assert not browser.find_elements(By.CSS_SELECTOR, ".field-note") and wave.get_attribute("aria-invalid") is None
    assert float(box.get_attribute("max")) == MAX_WAVE_HEIGHT_M and box.accessible_name.startswith("wave height")
    type_into(browser, box, "3.5")  # one step
    settled(browser)
    assert document_of(browser)["environment"]["wave"] == 3.5 and wave.get_attribute("value") == "custom"

    type_into(browser, box, "1e")
    settled(browser)
    assert document_of(browser)["environment"]["wave"] == 3.5
    assert "wave height: not a number" in note(browser, "environment.wave")
    assert box.get_attribute("aria-invalid") == "true" and box.get_attribute("value") == ""
    type_into(browser, box, "40")
    settled(browser)
    assert document_of(browser)["environment"]["wave"] == 3.5
    text = note(browser, "environment.wave")
    assert "40 m is out of range" in text and f"0 to {MAX_WAVE_HEIGHT_M:g}" in text, text
    assert box.get_attribute("value") == "40"  # kept to fix
    assert len(browser.find_elements(By.CSS_SELECTOR, '.field-note[data-for="environment.wave"]')) == 1
    type_into(browser, box, "0.5")
    settled(browser)
    assert document_of(browser)["environment"]["wave"] == 0.5 and note(browser, "environment.wave") == ""
    assert box.get_attribute("aria-invalid") is None

    Select(wave).select_by_value("W2")
    settled(browser)
    assert document_of(browser)["environment"]["wave"] == "W2" and not box.is_displayed()
    browser.find_element(By.ID, "undo").click()  # back to the custom 0.5 m: the box shows it again
    settled(browser)
    assert box.is_displayed() and box.get_attribute("value") == "0.5"
    assert js_errors(browser) == []


def test_the_preview_window_keeps_the_keyboard_until_escape(browser: Any, live_server: LiveServer) -> None:
    """Escape did not close the preview, and Tab went on to the page behind it."""
    open_editor(browser, live_server)
    js_errors(browser)
    # the window, not the rendering, is tested: the preview request never answers
    browser.execute_script("window.mmusvEditor.api.preview = () => new Promise(() => {})")
    button = browser.find_element(By.ID, "preview")
    button.click()
    modal = browser.find_element(By.ID, "preview-modal")
    assert modal.is_displayed()
    inside = "return document.getElementById('preview-modal').contains(document.activeElement)"
    assert active_id(browser) == "preview-close"
    # Tab goes round the window's Close button and its sheet (which the arrow keys scroll), both ways
    for keys, now in (
        ([Keys.TAB], "preview-body"),
        ([Keys.TAB], "preview-close"),
        ([Keys.SHIFT, Keys.TAB], "preview-body"),
        ([Keys.SHIFT, Keys.TAB], "preview-close"),
    ):
        ActionChains(browser).send_keys(*keys).perform()
        assert active_id(browser) == now, (keys, active_id(browser))
    ActionChains(browser).send_keys(Keys.ESCAPE).perform()
    assert not modal.is_displayed()
    assert active_id(browser) == "preview"  # back where it was opened

    ActionChains(browser).send_keys(Keys.ENTER).perform()  # the Preview button, from the keyboard
    assert modal.is_displayed() and browser.execute_script(inside)
    browser.find_element(By.ID, "preview-close").click()
    assert not modal.is_displayed() and active_id(browser) == "preview"
    ActionChains(browser).send_keys(Keys.ENTER).perform()
    width = modal.rect["width"]
    ActionChains(browser).move_to_element_with_offset(modal, -width / 2 + 10, 0).click().perform()  # beside it
    assert not modal.is_displayed() and active_id(browser) == "preview"
    assert js_errors(browser) == []


def test_the_unsaved_mark_follows_undo_and_redo(browser: Any, live_server: LiveServer) -> None:
    """Undoing back to the scenario opened or saved left the page marked unsaved."""
    open_editor(browser, live_server)
    js_errors(browser)
    clean, dirty = "port_entry.yaml · mmusv editor", "● port_entry.yaml · mmusv editor"
    assert browser.title == clean
    visibility = browser.find_element(By.ID, "e-visibility")
    type_into(browser, visibility, "2000")
    settled(browser)
    assert browser.title == dirty
    undo, redo = browser.find_element(By.ID, "undo"), browser.find_element(By.ID, "redo")
    undo.click()
    settled(browser)
    assert browser.title == clean  # the scenario opened
    redo.click()
    settled(browser)
    assert browser.title == dirty
    type_into(browser, visibility, "1500")
    settled(browser)
    save_as(browser, "marked.yaml")
    assert browser.title == "marked.yaml · mmusv editor"
    undo.click()  # 2000: not what the file holds
    settled(browser)
    assert browser.title == "● marked.yaml · mmusv editor"
    redo.click()  # 1500 again: what the file holds
    settled(browser)
    assert browser.title == "marked.yaml · mmusv editor"
    assert browser.execute_script("return window.mmusvEditor.state.dirty") is False
    assert js_errors(browser) == []


def saved_and_run(driver: Any, server: LiveServer, name: str) -> None:
    """``port_entry`` opened with a LiDAR-only rig (quick to run), saved as ``name`` and run for 2 frames to the
    end."""
    open_editor(driver, server)
    js_errors(driver)
    preset = '#rigs [data-rig="usv_standard"] select[data-key="preset"]'
    Select(driver.find_element(By.CSS_SELECTOR, preset)).select_by_value("lidar_only")
    settled(driver)
    save_as(driver, name)
    done = run_to_end(server, name, 2)
    assert done["status"] == "complete", done


def test_a_page_loaded_again_shows_the_last_run_of_its_file(browser: Any, live_server: LiveServer) -> None:
    """A run that had ended was not shown after a reload (only one still going on was)."""
    saved_and_run(browser, live_server, "ran.yaml")
    # a failing run of another file: its scenario names a vessel the library does not have
    doc = yaml.safe_load((live_server.folder / "ran.yaml").read_text(encoding="utf-8"))
    doc["vessels"][0]["asset"] = "no_such_boat"
    (live_server.folder / "broken.yaml").write_text(yaml.safe_dump(doc), encoding="utf-8")
    failed = run_to_end(live_server, "broken.yaml", 2)
    assert failed["status"] == "failed" and failed["error"], failed

    browser.refresh()  # ran.yaml open again, with its run as it ended
    _wait(browser, "return document.body.dataset.ready === '1' && document.body.dataset.pending === '0'", "the page")
    box = browser.find_element(By.ID, "run-status")
    assert box.is_displayed() and box.get_attribute("data-status") == "complete"
    text = browser.find_element(By.ID, "run-text").text
    assert "done: 2 frames" in text and "out/ran/" in text, text
    assert not browser.find_element(By.ID, "run-stop").is_displayed()
    assert browser.execute_script("return window.mmusvEditor.state.savedName") == "ran.yaml"

    pick_open(browser, "file:broken.yaml")  # another file: its run
    _wait(browser, "return document.getElementById('run-status').dataset.status === 'failed'", "the failed run")
    text = browser.find_element(By.ID, "run-text").text
    assert text.startswith("failed: ") and failed["error"][:40] in text, text
    assert js_errors(browser) == []


def test_a_restarted_server_shows_the_last_run_of_a_file(browser: Any, live_server: LiveServer) -> None:
    """A server started again on the folder (a second server on it here) knew no run: a file reopened there showed
    none, though its recording was in ``out/``. Now the runs there are read from their manifests."""
    saved_and_run(browser, live_server, "before.yaml")
    with serve(live_server.folder) as restarted:
        open_editor(browser, restarted)
        pick_open(browser, "file:before.yaml")
        _wait(browser, "return document.getElementById('run-status').dataset.status === 'complete'", "the last run")
        text = browser.find_element(By.ID, "run-text").text
        assert text == "done: 2 frames → out/before/ (recorded before this editor started)", text
        assert not browser.find_element(By.ID, "run-stop").is_displayed()
        assert js_errors(browser) == []


def test_the_library_fits_a_narrow_window(browser: Any, live_server: LiveServer) -> None:
    """At 800 x 600 a long vessel name pushed its size out of the library, which scrolled sideways."""
    size = browser.get_window_size()
    browser.set_window_size(800, 600)
    try:
        open_editor(browser, live_server)
        js_errors(browser)
        boxes = browser.execute_script(
            "const lib = document.getElementById('library');"
            "return {lib: [lib.scrollWidth, lib.clientWidth], items: [...lib.querySelectorAll('li')].map((li) => {"
            "  const r = li.getBoundingClientRect(), s = li.querySelector('.size').getBoundingClientRect(),"
            "        n = li.firstElementChild.getBoundingClientRect();"
            "  return [li.dataset.asset, li.querySelector('.size').textContent, r.left, r.right, n.left, n.right,"
            "          s.left, s.right, s.width];})}"
        )
        assert boxes["lib"][0] <= boxes["lib"][1], boxes["lib"]
        browser.find_element(By.CSS_SELECTOR, '#fleet li[data-id="tug"]').click()  # the vessel form too
        panel = "const p = document.getElementById('left'); return p.scrollWidth <= p.clientWidth"
        assert browser.execute_script(panel)
        assert len(boxes["items"]) >= 30
        for name, text, left, right, n_left, n_right, s_left, s_right, s_width in boxes["items"]:
            assert left - 0.5 <= n_left and n_right <= right + 0.5, (name, left, right, n_left, n_right)
            assert left - 0.5 <= s_left and s_right <= right + 0.5 and s_width > 20, (name, text, right, s_right)
            assert text.endswith(" m") and " × " in text
    finally:
        browser.set_window_size(size["width"], size["height"])


def test_a_waypoint_is_added_from_the_keyboard(browser: Any, live_server: LiveServer) -> None:
    """Waypoints could be placed with the mouse only; the route's last row takes x and y."""
    open_editor(browser, live_server)
    js_errors(browser)
    browser.find_element(By.CSS_SELECTOR, '#fleet li[data-id="tug"]').click()
    i = [v["id"] for v in document_of(browser)["vessels"]].index("tug")
    route = document_of(browser)["vessels"][i]["route"]
    last = browser.find_element(By.CSS_SELECTOR, f'#v-route button[data-delete="{len(route) - 1}"]')
    browser.execute_script("arguments[0].focus()", last)
    ActionChains(browser).send_keys(Keys.TAB).perform()  # from the last waypoint's row to the row that adds one
    assert active_id(browser) == "v-add-x"
    ActionChains(browser).send_keys("1e", Keys.TAB).perform()
    assert "new waypoint x (east): not a number" in note(browser, f"vessels[{i}].route.(new)[0]")
    ActionChains(browser).send_keys("-520", Keys.ENTER).perform()
    settled(browser)
    assert document_of(browser)["vessels"][i]["route"] == route
    assert "new waypoint x (east): not a number" in note(browser, f"vessels[{i}].route.(new)[0]")
    assert active_id(browser) == "v-add-x"  # to fix
    ActionChains(browser).key_down(Keys.CONTROL).send_keys("a").key_up(Keys.CONTROL).send_keys(
        Keys.DELETE, "300.5", Keys.ENTER
    ).perform()
    settled(browser)
    assert document_of(browser)["vessels"][i]["route"] == [*route, [300.5, -520]]
    assert note(browser, f"vessels[{i}].route.(new)[0]") == ""
    assert active_id(browser) == "v-add-x"  # ready for the next one, the boxes empty
    assert browser.find_element(By.ID, "v-add-y").get_attribute("value") == ""
    row = browser.find_element(By.CSS_SELECTOR, f'#v-route tr[data-index="{len(route)}"]')
    assert [c.get_attribute("value") for c in row.find_elements(By.CSS_SELECTOR, "input")] == ["300.5", "-520"]
    assert browser.find_element(By.CSS_SELECTOR, f'circle.waypoint[data-vessel="tug"][data-index="{len(route)}"]')

    ActionChains(browser).send_keys(Keys.ENTER).perform()  # nothing typed: both boxes say so
    settled(browser)
    assert len(document_of(browser)["vessels"][i]["route"]) == len(route) + 1
    assert "new waypoint x (east): empty" in note(browser, f"vessels[{i}].route.(new)[0]")
    assert "new waypoint y (north): empty" in note(browser, f"vessels[{i}].route.(new)[1]")
    browser.find_element(By.ID, "undo").click()
    settled(browser)
    assert document_of(browser)["vessels"][i]["route"] == route
    assert js_errors(browser) == []
