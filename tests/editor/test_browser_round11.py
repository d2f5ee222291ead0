"""An eleventh round through the editor in a real headless Chromium: a scenario naming an asset the library lacks (a
typo, an asset file taken away) or a rig it does not define showed a blank asset or rig menu for that vessel, so the
form hid the very value the check refused. The menu now shows it, said to be missing, until another is chosen.

Each browser test checks the browser's console for JavaScript errors (failed requests the page explains are not
errors).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from editor_server import serve
from selenium.webdriver.common.by import By
from selenium.webdriver.support.select import Select
from test_browser import _wait, document_of, open_editor, settled
from test_browser_round import js_errors

SCENARIO = """\
name: typos
map: {type: open_sea, seed: 1}
acquisition: {frequency_hz: 5, frames: 2}
vessels:
  - {id: u, role: usv, asset: usv_wamv, rig: nope, speed_mps: 2, route: [[-60, -300], [60, -300]]}
  - {id: s, asset: tug_23m, speed_mps: 3, route: [[0, -280], [40, -280]]}
"""


def _menu(driver: Any, menu_id: str) -> tuple[str, str, list[str]]:
    """The menu's value, its shown option's text and the values of its options said to be missing."""
    menu = Select(driver.find_element(By.ID, menu_id))
    missing = [o.get_attribute("value") for o in menu.options if o.get_attribute("data-missing")]
    return menu.first_selected_option.get_attribute("value"), menu.first_selected_option.text, missing


def test_a_missing_asset_or_rig_is_shown_in_its_menu(browser: Any, folder: Path) -> None:
    (folder / "typos.yaml").write_text(SCENARIO, encoding="utf-8")
    with serve(folder) as server:
        open_editor(browser, server)
        js_errors(browser)
        browser.execute_script("location.hash = '#file:typos.yaml'")
        _wait(
            browser,
            "return window.mmusvEditor.state.savedName === 'typos.yaml' && document.body.dataset.pending === '0'",
            "typos.yaml to open",
        )
        errors = browser.execute_script("return JSON.stringify(window.mmusvEditor.state.evaluation.errors)")
        assert "tug_23m" in errors, errors  # the check refuses it; the form must show what it refused

        browser.execute_script("window.mmusvEditor.state.select('s')")
        assert _menu(browser, "v-asset") == (
            "tug_23m",
            "tug_23m (not in the library)",
            ["tug_23m"],
        )  # was: a blank menu

        Select(browser.find_element(By.ID, "v-asset")).select_by_value("tug_32m")  # the person picks the right one
        settled(browser)
        assert [v["asset"] for v in document_of(browser)["vessels"]] == ["usv_wamv", "tug_32m"]
        assert _menu(browser, "v-asset")[0::2] == ("tug_32m", [])  # the missing entry is gone with the typo

        browser.execute_script("window.mmusvEditor.state.select('u')")
        assert _menu(browser, "v-asset") == ("usv_wamv", _menu(browser, "v-asset")[1], [])
        assert _menu(browser, "v-rig") == ("nope", "nope (no such rig)", ["nope"])  # was: blank too
        Select(browser.find_element(By.ID, "v-rig")).select_by_value("")  # the default rig
        settled(browser)
        assert "rig" not in document_of(browser)["vessels"][0]
        assert _menu(browser, "v-rig") == ("", "(default rig)", [])
        assert js_errors(browser) == []
