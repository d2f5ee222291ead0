"""A sixth round through the editor in a real headless Chromium, by keyboard and at small windows: the question
"overwrite?" of a save did not close with Escape and, once answered, left the keyboard on the page's body; a refused
file name or run length was told in the status only, without marking the box to fix; a vessel's id emptied was
written (a blank row in the list, and Extend route then did nothing); the map could not be panned or zoomed from the
keyboard; the status of a scenario that does not validate was read out as how many errors, not which field or what
it allows.

Each browser test checks the browser's console for JavaScript errors (failed requests the page explains are not
errors).
"""

from __future__ import annotations

from typing import Any

from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys
from test_browser import LiveServer, _wait, act_on, document_of, drag_waypoint, open_editor, settled, view
from test_browser_round import js_errors, note, type_into
from test_browser_round2 import active_id, save_as
from test_browser_round4 import status, window

CONFIRM_SHOWN = "return !document.getElementById('save-confirm').hidden"


def ask_to_overwrite(driver: Any, name: str) -> None:
    """Saves under `name`, a file of the folder other than the one open: the page asks whether to overwrite it."""
    box = driver.find_element(By.ID, "file-name")
    box.clear()
    box.send_keys(name)
    driver.find_element(By.ID, "save").send_keys(Keys.ENTER)
    _wait(driver, CONFIRM_SHOWN, "the question")


def test_the_overwrite_question_closes_by_escape_and_keeps_the_keyboard(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    save_as(browser, "kept.yaml")
    save_as(browser, "other.yaml")

    ask_to_overwrite(browser, "kept.yaml")
    ActionChains(browser).send_keys(Keys.TAB, Keys.TAB).perform()  # Save -> Overwrite -> Cancel
    assert active_id(browser) == "save-cancel"
    ActionChains(browser).send_keys(Keys.ENTER).perform()
    assert not browser.execute_script(CONFIRM_SHOWN)
    assert active_id(browser) == "file-name"  # was: the body (the button gone), the next Tab from the top
    assert "Overwrite replaces it" not in status(browser), status(browser)  # no longer offered

    ask_to_overwrite(browser, "kept.yaml")
    ActionChains(browser).send_keys(Keys.ESCAPE).perform()  # was: nothing
    assert not browser.execute_script(CONFIRM_SHOWN)
    assert active_id(browser) == "file-name"

    ask_to_overwrite(browser, "kept.yaml")
    ActionChains(browser).send_keys(Keys.TAB, Keys.ENTER).perform()  # Overwrite
    _wait(browser, "return document.body.dataset.saved === 'kept.yaml'", "the save")
    assert active_id(browser) == "save"
    assert js_errors(browser) == []


def test_a_refused_file_name_or_frames_marks_its_box(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    name = browser.find_element(By.ID, "file-name")
    for typed in ("bad name", ""):
        type_into(browser, name, typed)
        browser.find_element(By.ID, "save").click()
        _wait(browser, "return document.getElementById('file-name').getAttribute('aria-invalid') === 'true'", typed)
        assert name.get_attribute("aria-describedby") == "status"  # the status says why and what is allowed
        assert ".yaml" in status(browser), status(browser)
        assert active_id(browser) == "file-name"  # ready to be fixed
        name.send_keys("x")
        assert name.get_attribute("aria-invalid") is None  # an edit takes the mark away
    save_as(browser, "marked.yaml")
    assert name.get_attribute("aria-invalid") is None

    frames = browser.find_element(By.ID, "run-frames")
    type_into(browser, frames, "-3")
    browser.find_element(By.ID, "run").click()
    assert "whole number of frames" in status(browser), status(browser)
    assert frames.get_attribute("aria-invalid") == "true" and frames.get_attribute("aria-describedby") == "status"
    assert active_id(browser) == "run-frames"
    frames.send_keys(Keys.BACKSPACE)
    assert frames.get_attribute("aria-invalid") is None
    assert js_errors(browser) == []


def test_an_empty_vessel_id_is_refused_and_the_vessel_buttons_work(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    browser.find_element(By.CSS_SELECTOR, '#fleet li[data-id="tug"]').click()
    box = browser.find_element(By.ID, "v-id")
    type_into(browser, box, "   ")
    settled(browser)
    assert [v["id"] for v in document_of(browser)["vessels"]].count("tug") == 1  # was: an id ""
    assert browser.execute_script("return window.mmusvEditor.state.selected") == "tug"
    text = note(browser, box.get_attribute("data-field"))
    assert "id: empty" in text and "tug" in text, text
    assert box.get_attribute("aria-invalid") == "true"
    assert all(li.text.strip() for li in browser.find_elements(By.CSS_SELECTOR, "#fleet li"))  # no blank row
    browser.find_element(By.ID, "v-extend").click()  # was: nothing (no vessel selected by the id "")
    assert browser.execute_script("return window.mmusvEditor.map.mode") == "draw"
    ActionChains(browser).send_keys(Keys.ESCAPE).perform()
    type_into(browser, box, "tug_2")
    settled(browser)
    assert browser.execute_script("return window.mmusvEditor.state.selected") == "tug_2"
    assert note(browser, box.get_attribute("data-field")) == ""
    assert js_errors(browser) == []


def test_the_map_pans_and_zooms_from_the_keyboard_in_a_small_window(browser: Any, live_server: LiveServer) -> None:
    with window(browser, 900, 650):
        open_editor(browser, live_server)
        js_errors(browser)
        svg = browser.find_element(By.ID, "map")
        browser.execute_script("arguments[0].focus()", svg)
        v0 = view(browser)
        svg.send_keys(Keys.ARROW_RIGHT)
        v1 = view(browser)
        assert abs((v1["cx"] - v0["cx"]) * v0["scale"] - v0["w"] / 8) < 1, (v0, v1)  # an eighth of the view east
        svg.send_keys(Keys.ARROW_UP)
        assert view(browser)["cy"] > v1["cy"]  # north
        svg.send_keys("+")
        assert abs(view(browser)["scale"] / v0["scale"] - 1.5) < 1e-6
        svg.send_keys("-")
        assert abs(view(browser)["scale"] / v0["scale"] - 1) < 1e-6
        assert browser.execute_script("return document.getElementById('map-wrap').scrollTop") == 0  # no page scroll
        assert "arrow keys" in (svg.accessible_name or ""), svg.accessible_name

        # and the mouse still works there: a vessel picked on the map, a waypoint of it dragged
        browser.execute_script("window.mmusvEditor.map.zoomTo('tug')")
        act_on(
            browser,
            '#map .vessel-marker[data-id="tug"]',
            lambda marker: ActionChains(browser).move_to_element(marker).click().perform(),
        )
        assert browser.execute_script("return window.mmusvEditor.state.selected") == "tug"
        x, y = browser.execute_script("return window.mmusvEditor.state.vessel('tug').route[1]")
        drag_waypoint(browser, "tug", 1, (x + 20, y + 10))
        settled(browser)
        moved = browser.execute_script("return window.mmusvEditor.state.vessel('tug').route[1]")
        assert abs(moved[0] - (x + 20)) <= 2 and abs(moved[1] - (y + 10)) <= 2, moved
    assert js_errors(browser) == []


def test_the_status_names_the_first_schema_error(browser: Any, live_server: LiveServer) -> None:
    """The status, which a screen reader reads out (role=status), said "1 error(s): the scenario does not
    validate" only."""
    open_editor(browser, live_server)
    js_errors(browser)
    assert browser.find_element(By.ID, "status").get_attribute("role") == "status"
    browser.find_element(By.CSS_SELECTOR, '#fleet li[data-id="tug"]').click()
    type_into(browser, browser.find_element(By.ID, "v-speed"), "-2")
    settled(browser)
    said = browser.find_element(By.ID, "status").get_attribute("textContent")  # what is read out
    assert "does not validate" in said and "speed_mps = -2" in said and "greater than or equal to 0" in said, said
    assert browser.execute_script(  # but not shown: a longer status would wrap and move the map
        "const r = document.querySelector('#status .sr-only').getBoundingClientRect(); return r.width <= 1"
    )
    type_into(browser, browser.find_element(By.ID, "e-day"), "400")
    settled(browser)
    said = browser.find_element(By.ID, "status").get_attribute("textContent")
    assert "2 error(s)" in said and "1 more under Checks" in said, said
    type_into(browser, browser.find_element(By.ID, "e-day"), "")
    type_into(browser, browser.find_element(By.ID, "v-speed"), "2")
    settled(browser)
    assert "does not validate" not in status(browser)
    assert js_errors(browser) == []


def test_escape_elsewhere_keeps_the_overwrite_question(browser: Any, live_server: LiveServer) -> None:
    """Escape is the question's where the keyboard is on it or on what asked it (tested above); pressed on a vessel's
    button to end drawing a route, or in a vessel's field, it did not end the drawing and threw the question (and the
    run it held) away instead."""
    open_editor(browser, live_server)
    js_errors(browser)
    save_as(browser, "held.yaml")  # names of their own: the folder is the module's
    save_as(browser, "elsewhere.yaml")
    ask_to_overwrite(browser, "held.yaml")

    browser.find_element(By.CSS_SELECTOR, '#fleet li[data-id="tug"]').click()
    browser.find_element(By.ID, "v-extend").click()
    assert browser.execute_script("return window.mmusvEditor.map.mode") == "draw"
    assert active_id(browser) == "v-extend"
    ActionChains(browser).send_keys(Keys.ESCAPE).perform()
    assert browser.execute_script("return window.mmusvEditor.map.mode") == "select"  # was: still drawing
    assert browser.execute_script(CONFIRM_SHOWN)  # was: closed, "not saved: the file was kept as it is"

    browser.find_element(By.ID, "v-speed").click()
    ActionChains(browser).send_keys(Keys.ESCAPE).perform()
    assert browser.execute_script(CONFIRM_SHOWN)

    browser.find_element(By.ID, "save-overwrite").send_keys(Keys.ESCAPE)  # on the question: it closes
    assert not browser.execute_script(CONFIRM_SHOWN)
    assert active_id(browser) == "file-name"
    assert js_errors(browser) == []
