"""An eighth round through the editor in a real headless Chromium: Ctrl+S pressed while typing in a box saved the
scenario without what the box showed (its change event comes on leaving the box), said "saved" and showed no unsaved
mark; and leaving the page (a reload, closing the tab) then asked nothing, and lost the text. Undo after an edit of
the description (the leading comment) left the description and took back the edit before it. A reload of a file
that can no longer be opened showed another scenario, its check's verdict replacing at once the status that said why.
The Open list missed the files another tab or program saved since the page loaded. A save of a file deleted since it
was opened asked whether to overwrite a file "changed by another tab or program".

Each browser test checks the browser's console for JavaScript errors (failed requests the page explains are not
errors).
"""

from __future__ import annotations

import re
import shutil
from typing import Any

from mmusv.bundled import resolve_scenario
from mmusv.config import load_scenario
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys
from test_browser import LiveServer, _wait, document_of, open_editor, pick_open, settled
from test_browser_round import js_errors, type_into
from test_browser_round2 import active_id, save_as


def ctrl_s(driver: Any) -> None:
    driver.execute_script("delete document.body.dataset.saved")
    ActionChains(driver).key_down(Keys.CONTROL).send_keys("s").key_up(Keys.CONTROL).perform()
    _wait(driver, "return document.body.dataset.saved === 'typed.yaml'", "the save")


def test_ctrl_s_while_typing_saves_what_the_box_shows(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    save_as(browser, "typed.yaml")
    path = live_server.folder / "typed.yaml"

    box = browser.find_element(By.ID, "s-name")
    box.click()
    box.send_keys(Keys.END, "_typed")  # not left: no change event yet
    ctrl_s(browser)
    assert load_scenario(path).name == "port_entry_typed"  # was: port_entry, while the box showed the new name
    assert not browser.execute_script("return window.mmusvEditor.state.dirty")
    assert not browser.title.startswith("●")
    assert active_id(browser) == "s-name"  # the keyboard stays in the box
    box.send_keys("2")  # typing on goes on in the box, and a second Ctrl+S saves it too
    ctrl_s(browser)
    assert load_scenario(path).name == "port_entry_typed2"

    speed = browser.find_element(By.ID, "a-frequency")  # a number box
    speed.click()
    speed.send_keys(Keys.CONTROL, "a")
    speed.send_keys("2")
    ctrl_s(browser)
    assert load_scenario(path).acquisition.frequency_hz == 2
    assert browser.execute_script("return window.mmusvEditor.state.undoStack.length") == 3  # one edit each
    assert js_errors(browser) == []


def test_undo_takes_back_an_edited_description(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    comment = browser.execute_script("return window.mmusvEditor.state.comment")
    type_into(browser, browser.find_element(By.ID, "s-name"), "renamed")
    settled(browser)
    type_into(browser, browser.find_element(By.ID, "s-comment"), "my description")
    settled(browser)
    browser.find_element(By.ID, "undo").click()
    settled(browser)
    box = browser.find_element(By.ID, "s-comment")
    assert box.get_attribute("value") == comment  # was: "my description" kept, and the rename undone
    assert document_of(browser)["name"] == "renamed"
    browser.find_element(By.ID, "redo").click()
    settled(browser)
    assert box.get_attribute("value") == "my description"
    assert browser.execute_script("return window.mmusvEditor.state.comment") == "my description"
    browser.find_element(By.ID, "undo").click()
    browser.find_element(By.ID, "undo").click()
    settled(browser)
    assert not browser.execute_script("return window.mmusvEditor.state.dirty")  # back to the file as opened
    assert js_errors(browser) == []


LEAVE = "const e = new Event('beforeunload', {cancelable: true}); window.dispatchEvent(e); return e.defaultPrevented"


def test_leaving_the_page_while_typing_asks_first(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    assert browser.execute_script(LEAVE) is False  # nothing to lose
    box = browser.find_element(By.ID, "s-name")
    box.click()
    box.send_keys(Keys.END, "_typed")  # not left: no change event yet
    assert browser.execute_script(LEAVE) is True  # was: False, and a reload lost the text without a question
    assert browser.execute_script("return window.mmusvEditor.state.doc.name") == "port_entry_typed"
    assert active_id(browser) == "s-name"
    assert js_errors(browser) == []


def test_a_reload_of_a_file_that_no_longer_opens_says_why_with_the_scenario_shown_instead(
    browser: Any, live_server: LiveServer
) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    save_as(browser, "broken.yaml")
    path = live_server.folder / "broken.yaml"
    path.write_text(path.read_text(encoding="utf-8").replace("map: {", "map: null\nx: {"), encoding="utf-8")
    browser.refresh()  # the address names #file:broken.yaml
    _wait(
        browser,
        "return document.body.dataset.ready === '1' && document.body.dataset.pending === '0' "
        "&& !!document.getElementById('map-image')",
        "the page to show another scenario",
    )
    said = browser.find_element(By.ID, "status")
    text = said.text
    assert text.startswith("cannot open broken.yaml again: "), text  # was: "8 vessels · 50 frames · ..." only
    assert "map = None" in text and "sections are mappings" in text, text
    # (the map's words come between the two when the map came after the check: either order is right)
    assert re.search(r"showing port_entry\.yaml instead · (port map, seed 3, \d+ m square · )?8 vessels", text), text
    assert "error" in said.get_attribute("class").split()
    type_into(browser, browser.find_element(By.ID, "s-seed"), "5")  # an edit of what is shown: the note has been read
    settled(browser)
    assert not said.text.startswith("cannot open"), said.text
    assert js_errors(browser) == []


def test_a_save_of_a_file_deleted_since_says_it_is_gone(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    save_as(browser, "gone.yaml")
    (live_server.folder / "gone.yaml").unlink()
    type_into(browser, browser.find_element(By.ID, "s-seed"), "5")
    settled(browser)
    browser.find_element(By.ID, "save").click()
    _wait(browser, "return !document.getElementById('save-confirm').hidden", "the question")
    _wait(browser, "return document.getElementById('save-confirm-text').textContent !== ''", "the question's text")
    asked = browser.find_element(By.ID, "save-confirm-text").text
    assert asked.startswith("gone.yaml is no longer in the folder"), asked  # was: "... was changed by another tab"
    browser.find_element(By.ID, "save-overwrite").click()
    _wait(browser, "return document.body.dataset.saved === 'gone.yaml' && !window.mmusvEditor.state.dirty", "the save")
    assert load_scenario(live_server.folder / "gone.yaml").seed == 5
    assert js_errors(browser) == []


def test_the_open_list_shows_files_saved_elsewhere_since(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    shutil.copy(resolve_scenario("open_sea_convoy"), live_server.folder / "from_elsewhere.yaml")
    pick_open(browser, "file:from_elsewhere.yaml")  # reached, the list is read again (was: only at start and after
    # a save of this page), so the file saved elsewhere is in it
    _wait(browser, "return window.mmusvEditor.state.savedName === 'from_elsewhere.yaml'", "the file opened")
    assert js_errors(browser) == []
