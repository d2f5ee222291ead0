"""The page carries a file's comments through an edit and a save (Selenium, headless Chromium): a bundled scenario's
comment above a vessel is written back above it, and one of a vessel deleted in the page is kept at the end of the file
with a word in the status line; a vessel renamed in the page keeps its comments, and undoing the rename takes them
back, also when the rename comes while a save is on its way."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mmusv.bundled import bundled_dir
from mmusv.editor.comments import read_comments
from selenium.webdriver.common.by import By
from test_browser import LiveServer, _wait, open_editor, pick_open, settled
from test_browser_round import js_errors, type_into
from test_browser_round2 import save_as


def open_occlusion(browser: Any, live_server: LiveServer) -> None:
    """The page with the bundled ``island_occlusion`` open (its trawler has two comments above it), settled, the
    JavaScript error log read and emptied."""
    open_editor(browser, live_server)
    js_errors(browser)
    pick_open(browser, "bundled:island_occlusion")
    _wait(browser, "return window.mmusvEditor.state.fileName === 'island_occlusion.yaml'", "the bundled scenario")
    settled(browser)


def test_the_page_saves_a_bundled_scenario_with_its_comments(browser: Any, live_server: LiveServer) -> None:
    open_occlusion(browser, live_server)
    # a waypoint moved: the comments stay at their vessel
    browser.execute_script("window.mmusvEditor.state.edit((d) => { d.vessels[0].route[0][0] += 5; });")
    save_as(browser, "occlusion.yaml")
    saved = (Path(live_server.folder) / "occlusion.yaml").read_text(encoding="utf-8")
    original = (bundled_dir() / "island_occlusion.yaml").read_text(encoding="utf-8")
    assert read_comments(saved) == read_comments(original)
    lines = saved.splitlines()
    trawler = next(i for i, line in enumerate(lines) if line.startswith("- {id: trawler"))
    assert lines[trawler - 2].startswith("# Near traffic on each flank")
    # the trawler deleted: its comments go to the end of the file, and the status line says so
    browser.execute_script(
        "window.mmusvEditor.state.edit((d) => { d.vessels = d.vessels.filter((v) => v.id !== 'trawler'); });"
    )
    settled(browser)
    browser.find_element(By.ID, "save").click()
    _wait(browser, "return !window.mmusvEditor.state.dirty", "the save")
    status = browser.find_element(By.ID, "status").text
    assert "2 comments of the removed vessel trawler were moved to the end of the file" in status, status
    saved = (Path(live_server.folder) / "occlusion.yaml").read_text(encoding="utf-8")
    assert saved.splitlines()[-3] == "# [removed from the scenario: vessel trawler]"
    assert browser.execute_script("return window.mmusvEditor.state.comments.at(-3).text") == saved.splitlines()[-3]
    assert js_errors(browser) == []


def test_a_renamed_vessels_comments_follow_it_and_undo_takes_them_back(browser: Any, live_server: LiveServer) -> None:
    open_occlusion(browser, live_server)
    original = read_comments((bundled_dir() / "island_occlusion.yaml").read_text(encoding="utf-8"))
    trawler = [c for c in original if c.path[:2] == ("vessels", "trawler")]
    assert len(trawler) == 2
    browser.find_element(By.CSS_SELECTOR, '#fleet li[data-id="trawler"]').click()
    type_into(browser, browser.find_element(By.ID, "v-id"), "trawler_2")
    settled(browser)
    save_as(browser, "renamed.yaml")
    # Was: the two comments counted as those of a removed vessel, moved to the end of the file.
    status = browser.find_element(By.ID, "status").text
    assert "moved to the end" not in status, status
    saved = (Path(live_server.folder) / "renamed.yaml").read_text(encoding="utf-8")
    assert "removed from the scenario" not in saved
    lines = saved.splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith("- {id: trawler_2"))
    assert lines[at - 2 : at] == [c.text for c in trawler]
    # undo: the vessel and its comments are the trawler's again
    browser.find_element(By.ID, "undo").click()
    settled(browser)
    assert browser.execute_script("return window.mmusvEditor.state.vessel('trawler') !== null")
    browser.find_element(By.ID, "save").click()
    _wait(browser, "return !window.mmusvEditor.state.dirty", "the save")
    saved = (Path(live_server.folder) / "renamed.yaml").read_text(encoding="utf-8")
    assert read_comments(saved) == original and "removed from the scenario" not in saved
    assert js_errors(browser) == []


def test_a_vessel_renamed_while_a_save_is_on_its_way_keeps_its_comments(browser: Any, live_server: LiveServer) -> None:
    """The save's answer brings the file's comments as the server wrote them: anchored at the id the save sent. A
    rename made while the save was on its way (its field left after Ctrl+S) keeps its comments' new anchors."""
    open_occlusion(browser, live_server)
    save_as(browser, "race.yaml")
    original = read_comments((Path(live_server.folder) / "race.yaml").read_text(encoding="utf-8"))
    browser.execute_script(
        """const fetched = window.fetch;
        window.heldSave = null;
        window.fetch = (url, init) => init?.method === "PUT"
          ? new Promise((done) => { window.heldSave = () => { window.fetch = fetched; done(fetched(url, init)); }; })
          : fetched(url, init);"""
    )
    browser.find_element(By.ID, "save").click()
    _wait(browser, "return window.heldSave !== null", "the save on its way")
    browser.find_element(By.CSS_SELECTOR, '#fleet li[data-id="trawler"]').click()
    type_into(browser, browser.find_element(By.ID, "v-id"), "trawler_2")
    settled(browser)
    browser.execute_script("document.getElementById('status').textContent = ''; window.heldSave();")
    _wait(browser, "return document.getElementById('status').textContent.startsWith('saved race.yaml')", "the answer")
    assert browser.execute_script("return window.mmusvEditor.state.dirty")  # the rename came after what was sent
    # was: the answer's comments (anchored at "trawler") replaced the renamed ones; the next save moved them to the end
    anchors = browser.execute_script("return window.mmusvEditor.state.comments.map((c) => c.path[1] ?? null)")
    assert "trawler_2" in anchors and "trawler" not in anchors, anchors
    browser.find_element(By.ID, "save").click()
    _wait(browser, "return !window.mmusvEditor.state.dirty", "the second save")
    saved = (Path(live_server.folder) / "race.yaml").read_text(encoding="utf-8")
    assert "removed from the scenario" not in saved, saved
    renamed = [c for c in read_comments(saved) if c.path[:2] == ("vessels", "trawler_2")]
    assert [c.text for c in renamed] == [c.text for c in original if c.path[:2] == ("vessels", "trawler")]
    assert js_errors(browser) == []
