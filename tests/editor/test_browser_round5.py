"""A fifth round through the editor in a real headless Chromium: a vessel selected on the map or in the list left
the Selected vessel panel below the fold of the scrolled left panel at 1280 x 800; a run that ended interrupted was
told in the status like any message; a scenario with too many frames to check showed no note at the frames box.

Each browser test checks the browser's console for JavaScript errors (failed requests the page explains are not
errors).
"""

from __future__ import annotations

from typing import Any

from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.support.select import Select
from test_browser import LiveServer, _wait, act_on, open_editor, settled
from test_browser_round import js_errors, type_into
from test_browser_round2 import save_as
from test_browser_round4 import status, window

PANEL_SEEN = (
    "const p = document.getElementById('vessel-panel').getBoundingClientRect(),"
    " s = document.getElementById('left').getBoundingClientRect();"
    "return !document.getElementById('vessel-panel').hidden && p.top >= s.top && p.top + 60 <= s.bottom"
)


def test_a_selected_vessel_brings_its_panel_into_view(browser: Any, live_server: LiveServer) -> None:
    """At 1280 x 800 the Selected vessel panel lies below the vessel list: a vessel picked there or on the map left
    it out of sight."""
    with window(browser, 1280, 800):
        open_editor(browser, live_server)
        js_errors(browser)
        browser.execute_script("document.getElementById('left').scrollTop = 0")
        browser.find_element(By.CSS_SELECTOR, '#fleet li[data-id="tug"]').click()
        assert browser.execute_script(PANEL_SEEN), "the panel, after a pick in the list"

        browser.execute_script("window.mmusvEditor.state.select(null); document.getElementById('left').scrollTop = 0")
        act_on(
            browser,
            '#map .vessel-marker[data-id="yacht"]',
            lambda marker: ActionChains(browser).move_to_element(marker).click().perform(),
        )
        assert browser.execute_script("return window.mmusvEditor.state.selected") == "yacht"
        assert browser.execute_script(PANEL_SEEN), "the panel, after a pick on the map"
        assert browser.execute_script("return document.activeElement.id") == "map"  # the keyboard stays there
    assert js_errors(browser) == []


def test_an_interrupted_run_is_told_as_an_error(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    preset = '#rigs [data-rig="usv_standard"] select[data-key="preset"]'
    Select(browser.find_element(By.CSS_SELECTOR, preset)).select_by_value("lidar_only")
    # a run long enough to stop (was 5000 frames: a run that failed its route checks 5 s on, hulls_intersect at 43 s)
    type_into(browser, browser.find_element(By.ID, "a-frames"), "200")
    settled(browser)
    save_as(browser, "stopped.yaml")
    type_into(browser, browser.find_element(By.ID, "run-frames"), "")
    browser.find_element(By.ID, "run").click()
    _wait(browser, "return document.getElementById('run-status').dataset.status === 'running'", "the run")
    browser.find_element(By.ID, "run-stop").click()
    _wait(browser, "return document.getElementById('run-status').dataset.status === 'interrupted'", "the stop")
    _wait(browser, "return document.getElementById('status').textContent.startsWith('run of stopped')", "its word")
    assert "interrupted: " in status(browser), status(browser)
    assert "error" in (browser.find_element(By.ID, "status").get_attribute("class") or "")  # was: a plain word
    assert browser.execute_script(  # the run's own line too, like a failed run's
        "const c = (id) => getComputedStyle(document.getElementById(id)).color; return c('run-text') === c('status')"
    )
    assert js_errors(browser) == []


def test_too_many_frames_to_check_is_noted_at_the_frames_box(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    type_into(browser, browser.find_element(By.ID, "a-frames"), "5000000")
    settled(browser)
    for id_ in ("a-frames", "a-frequency"):
        box = browser.find_element(By.ID, id_)
        assert box.get_attribute("aria-invalid") == "true", id_
        note = browser.find_element(By.ID, box.get_attribute("aria-describedby"))
        assert "route checks would take" in note.text and "acquisition.frames" in note.text, note.text
    assert js_errors(browser) == []
