"""A ninth round through the editor in a real headless Chromium: the command line's file that does not exist yet
opens as a new scenario, said so until it is edited; an address edited by hand (``#file:NAME``) changed the address
only, while the page went on showing and saving the scenario it had; deleting the vessel whose route was being drawn
left its hint ("Click to add waypoints to usv_1") and the drawing on.

Each browser test checks the browser's console for JavaScript errors (failed requests the page explains are not
errors).
"""

from __future__ import annotations

import shutil
from typing import Any

from editor_server import serve
from mmusv.bundled import resolve_scenario
from mmusv.config import load_scenario
from mmusv.editor.app import InitialScenario
from mmusv.editor.opening import new_document
from selenium.webdriver.common.by import By
from selenium.webdriver.support import expected_conditions
from selenium.webdriver.support.ui import WebDriverWait
from test_browser import LiveServer, _wait, click_world, document_of, open_editor, set_view, settled, view
from test_browser_round import js_errors, type_into


def status_text(driver: Any) -> str:
    return str(driver.find_element(By.ID, "status").text)


def test_a_new_file_of_the_command_line_opens_a_new_scenario(browser: Any, tmp_path: Any) -> None:
    initial = InitialScenario(name="harbour_new.yaml", document=new_document("harbour_new"), comment="", new=True)
    with serve(tmp_path, initial=initial) as server:
        browser.get(server.url + "/")
        _wait(browser, "return document.body.dataset.ready === '1' && document.body.dataset.pending === '0'", "boot")
        js_errors(browser)
        _wait(browser, "return !!document.getElementById('map-image')", "the map")
        said = "new scenario: harbour_new.yaml does not exist yet; place vessels from the library, then Save creates it"
        _wait(browser, f"return document.getElementById('status').textContent.startsWith({said!r})", "the note")
        assert browser.find_element(By.ID, "file-name").get_attribute("value") == "harbour_new.yaml"
        assert document_of(browser)["vessels"] == []
        assert browser.current_url.endswith("/")  # no file of the folder named yet
        type_into(browser, browser.find_element(By.ID, "s-name"), "renamed")  # an edit: the note has done its work
        settled(browser)
        assert "does not exist yet" not in status_text(browser)

        browser.find_element(By.ID, "save").click()  # no vessel yet: refused, saying what to fix, once
        # (the live check's own "1 error(s)" line is an error too: wait for the save's, not for the class alone,
        # which the live check may have set before the save's answer came, on a loaded machine)
        _wait(
            browser,
            "const s = document.getElementById('status');"
            "return s.classList.contains('error') && s.textContent.startsWith('not saved:')",
            "the refusal",
        )
        assert status_text(browser) == (
            "not saved: harbour_new.yaml: the scenario does not validate: vessels = []: must hold at least 1 entry, "
            "got 0"
        )  # was: "not saved: harbour_new.yaml: not saved, the scenario ..."
        assert not (tmp_path / "harbour_new.yaml").exists()

        browser.find_element(By.CSS_SELECTOR, '#library li[data-asset="usv_wamv"]').click()
        v = view(browser)
        for dx in (0.0, 80.0):  # a vessel and its route: Save creates the file
            click_world(browser, v["cx"] + dx / v["scale"], v["cy"])
        browser.find_element(By.ID, "drawing-done").click()
        settled(browser)
        browser.find_element(By.ID, "save").click()
        _wait(browser, "return document.body.dataset.saved === 'harbour_new.yaml'", "the save")
        scenario = load_scenario(tmp_path / "harbour_new.yaml")
        assert scenario.name == "renamed" and [v.asset for v in scenario.vessels] == ["usv_wamv"]
        assert browser.execute_script("return location.hash") == "#file:harbour_new.yaml"
        assert js_errors(browser) == []


def question(driver: Any) -> Any:
    """The page's question (``window.confirm``), once it is asked."""
    return WebDriverWait(driver, 60).until(expected_conditions.alert_is_present(), message="no question asked")


def _file(server: LiveServer, name: str, scenario_name: str) -> None:
    path = server.folder / name
    shutil.copy(resolve_scenario("port_entry"), path)
    path.write_text(path.read_text(encoding="utf-8").replace("name: port_entry", f"name: {scenario_name}"))


def _shown(driver: Any, name: str) -> None:
    _wait(
        driver,
        f"return window.mmusvEditor.state.savedName === {name!r} && document.body.dataset.pending === '0'",
        f"{name} to open",
    )


def test_an_address_edited_by_hand_opens_the_file_it_names(browser: Any, live_server: LiveServer) -> None:
    _file(live_server, "first.yaml", "first")
    _file(live_server, "second.yaml", "second")
    browser.get(live_server.url + "/#file:first.yaml")
    _shown(browser, "first.yaml")
    js_errors(browser)

    browser.execute_script("location.hash = '#file:second.yaml'")  # as typed into the address bar
    _shown(browser, "second.yaml")  # was: the address changed, first.yaml stayed shown (and Save saved it)
    assert document_of(browser)["name"] == "second"
    assert browser.find_element(By.ID, "file-name").get_attribute("value") == "second.yaml"

    type_into(browser, browser.find_element(By.ID, "s-name"), "edited")
    settled(browser)
    browser.execute_script("location.hash = '#bundled:island_occlusion'")
    question(browser).dismiss()  # keep the edits
    _wait(browser, "return location.hash === '#file:second.yaml'", "the address of the scenario shown")
    assert document_of(browser)["name"] == "edited"

    browser.execute_script("location.hash = '#file:no_such.yaml'")
    question(browser).accept()  # discard the edits: but it cannot be opened
    _wait(browser, "return location.hash === '#file:second.yaml'", "the address put back")
    _wait(browser, "return document.getElementById('status').classList.contains('error')", "the refusal")
    assert "no scenario file 'no_such.yaml'" in status_text(browser)
    browser.execute_script("location.hash = '#nonsense'")
    _wait(browser, "return location.hash === '#file:second.yaml'", "the address put back")
    assert "names no scenario" in status_text(browser)

    browser.execute_script("location.hash = '#bundled:island_occlusion'")
    question(browser).accept()
    _wait(browser, "return window.mmusvEditor.state.doc.name === 'island_occlusion'", "the bundled scenario")
    assert browser.execute_script("return location.hash") == "#bundled:island_occlusion"
    assert js_errors(browser) == []


def _place_tug(driver: Any) -> str:
    """Places a tug on the map (drawing its route then); its id."""
    driver.find_element(By.CSS_SELECTOR, '#library li[data-asset="tug_32m"]').click()
    click_world(driver, 300.0, -600.0)
    _wait(driver, "return window.mmusvEditor.map.mode === 'draw'", "drawing")
    return str(driver.execute_script("return window.mmusvEditor.state.selected"))


def test_deleting_the_vessel_being_drawn_ends_the_drawing_and_its_hint(browser: Any, live_server: LiveServer) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    set_view(browser, 330.0, 20.0, 0.42)
    hint = browser.find_element(By.ID, "mode-hint")
    idle = hint.text
    vid = _place_tug(browser)
    assert hint.text.startswith(f"Click to add waypoints to {vid} ")
    browser.find_element(By.ID, "v-delete").click()
    # was: "Click to add waypoints to tug_..." stayed, with the drawing box and the map's drawing cursor
    _wait(browser, "return window.mmusvEditor.map.mode === 'select'", "the drawing to end")
    assert hint.text == idle
    assert not browser.find_element(By.ID, "drawing").is_displayed()
    assert "drawing" not in (browser.find_element(By.ID, "map").get_attribute("class") or "")

    _place_tug(browser)
    type_into(browser, browser.find_element(By.ID, "v-id"), "tug_new")  # a rename: the hint follows it
    _wait(browser, "return document.getElementById('mode-hint').textContent.includes('waypoints to tug_new ')", "hint")
    assert browser.execute_script("return window.mmusvEditor.map.mode") == "draw"
    browser.find_element(By.ID, "undo").click()  # the rename
    browser.find_element(By.ID, "undo").click()  # the placing: the vessel is gone
    _wait(browser, "return window.mmusvEditor.map.mode === 'select'", "the drawing to end")
    assert hint.text == idle
    assert js_errors(browser) == []
