"""A twelfth round through the editor in a real headless Chromium: reaching the Open box reads the folder's files
again and replaces its list when they come. A pick made in between chose an option of the list being replaced (CI
saw a stale element in ``test_the_library_is_the_open_scenarios``). The box now says while its list is being read
(``data-listing="reading"``, "done" once shown), so a pick waits for the list it will be made in.

Each browser test checks the browser's console for JavaScript errors (failed requests the page explains are not
errors).
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

from editor_server import serve
from mmusv.bundled import resolve_scenario
from selenium.webdriver.common.by import By
from test_browser import _wait, open_editor, pick_open
from test_browser_round import js_errors

SLOW_LISTING = """const real = window.fetch;
window.fetch = async (url, opts) => {
  if (String(url).endsWith('/api/files')) await new Promise((r) => setTimeout(r, 1200));
  return real(url, opts);
};"""


def _listing(driver: Any) -> Any:
    return driver.execute_script("return document.getElementById('open').dataset.listing")


def test_the_open_box_says_while_its_list_is_read(browser: Any, folder: Path) -> None:
    shutil.copy(resolve_scenario("port_entry"), folder / "first.yaml")
    with serve(folder) as server:
        open_editor(browser, server)
        js_errors(browser)
        assert _listing(browser) == "done"  # the list read at the start is shown
        shutil.copy(resolve_scenario("open_sea_convoy"), folder / "later.yaml")
        browser.execute_script(SLOW_LISTING)

        browser.find_element(By.ID, "open").click()  # reached: the folder is read again, slowly here
        assert _listing(browser) == "reading"  # was: no word, the old list shown and pickable
        listed = "return [...document.querySelectorAll('#open option')].map((o) => o.value)"
        assert "file:later.yaml" not in browser.execute_script(listed)
        _wait(browser, "return document.getElementById('open').dataset.listing === 'done'", "the new list")
        assert "file:later.yaml" in browser.execute_script(listed)

        browser.execute_script("document.activeElement.blur()")
        pick_open(browser, "file:later.yaml")  # reached again, read again: picked in the list shown after
        _wait(browser, "return window.mmusvEditor.state.savedName === 'later.yaml'", "later.yaml opened")
        assert browser.execute_script("return window.mmusvEditor.state.doc.name") == "open_sea_convoy"
        assert js_errors(browser) == []
