"""A sweep of the editor as a person clicking through the newest scenario knobs: the sea (wave, sea state, motion), the
time of day (night included), the weather and the cameras' settings.

Each browser test checks the browser's console for JavaScript errors (failed requests the page explains are not
errors).
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import pytest
import yaml
from mmusv.bundled import bundled_dir
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys
from selenium.webdriver.support.select import Select
from test_api import client
from test_browser import LiveServer, _wait, document_of, settled
from test_browser_round import js_errors, note
from test_browser_round3 import open_file, value, value_of, write_scenario

with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # starlette's notice about its httpx-based test client
    from fastapi.testclient import TestClient

__all__ = ["client"]  # the fixture, shared with test_api.py


def hours(driver: Any, box: Any) -> None:
    """Clicks the hours of the time box ``box`` (its left end)."""
    ActionChains(driver).move_to_element_with_offset(box, -box.rect["width"] / 2 + 8, 0).click().perform()


def test_a_time_box_left_without_a_time_keeps_the_scenarios_time(browser: Any, live_server: LiveServer) -> None:
    """Clearing the time box, or one part of it (Backspace on the hours, as when typing a new hour), left the box
    empty (``--:--``) while the scenario silently became noon, the schema's default: a night scenario saved so was
    a midday one, with no word next to the box."""
    env = {"time_of_day": "23:30", "weather": "fog", "visibility_m": 300}
    write_scenario(live_server.folder, "night.yaml", environment=env)
    open_file(browser, live_server, "night.yaml")
    js_errors(browser)
    box = browser.find_element(By.ID, "e-time")
    assert value(browser, "e-time") == "23:30"
    hours(browser, box)
    box.send_keys(Keys.BACKSPACE)
    box.send_keys(Keys.TAB)
    settled(browser)
    assert document_of(browser)["environment"]["time_of_day"] == "23:30"
    assert not browser.execute_script("return window.mmusvEditor.state.dirty")
    text = note(browser, "environment.time_of_day")
    assert "time of day" in text and "00:00 to 23:59" in text and "keeps its time" in text, text
    # a whole time typed again is taken (04:15, in the morning or afternoon as the browser's locale shows hours),
    # and the note goes
    hours(browser, box)
    box.send_keys("0415")
    box.send_keys(Keys.TAB)
    settled(browser)
    assert document_of(browser)["environment"]["time_of_day"] == value(browser, "e-time")
    assert value(browser, "e-time") in ("04:15", "16:15")
    assert note(browser, "environment.time_of_day") == ""
    assert js_errors(browser) == []


def test_a_wave_preset_written_in_lower_case_shows_as_that_preset(browser: Any, live_server: LiveServer) -> None:
    """The schema reads ``wave: " w2"`` as W2, but a file that does not validate (here a vessel's speed) comes to the
    page as written: its wave showed as "custom height…" beside an empty height box and no note, the W2 nowhere; with
    a ``sea``, ``" w0"`` showed a custom wave instead of the sea."""
    data = write_scenario(live_server.folder, "low.yaml", environment={"time_of_day": "21:00", "wave": " w2"})
    data["vessels"][0]["speed_mps"] = -1
    (live_server.folder / "low.yaml").write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    open_file(browser, live_server, "low.yaml")
    js_errors(browser)
    assert value(browser, "e-wave") == "W2"
    assert not browser.find_element(By.ID, "e-wave-height").is_displayed()
    assert document_of(browser)["environment"]["wave"] == " w2"  # shown, not changed
    data["environment"] = {"wave": "w0", "sea": {"state": 4}}
    (live_server.folder / "low.yaml").write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    open_file(browser, live_server, "low.yaml")
    assert value(browser, "e-wave") == "sea"
    assert value(browser, "e-sea") == '{"state":4}'
    assert js_errors(browser) == []


def test_the_rig_panel_follows_a_preset_or_quality_picked_in_it(browser: Any, live_server: LiveServer) -> None:
    """The rig panel was not drawn again while the focus was in it, and a select keeps the focus once picked: a
    LiDAR-only preset picked there kept saying "radar: on" and "4 surround cameras" (the rig had neither), a camera
    quality picked kept the summary of the one before ("own quality: rear draft" under a rig at draft), and a rig
    removed with its button (which then held the focus) stayed on the page, until an edit after the focus left."""
    rig = {
        "quality": "high",
        "cameras": [
            {"name": "front", "resolution": [320, 240], "mount": {"point": "camera_front"}},
            {"name": "rear", "resolution": [320, 240], "mount": {"point": "camera_rear"}, "quality": "draft"},
        ],
    }
    write_scenario(live_server.folder, "rigs.yaml", rigs={"usv_standard": rig, "spare": {}})
    open_file(browser, live_server, "rigs.yaml")
    js_errors(browser)
    css = '#rigs [data-rig="usv_standard"]'

    def summary(css: str = css) -> str:
        return str(browser.find_element(By.CSS_SELECTOR, f"{css} .summary").text)

    assert summary().startswith("2 cameras (own quality: rear draft); carried by usv_1")
    Select(browser.find_element(By.CSS_SELECTOR, f'{css} select[data-key="quality"]')).select_by_value("draft")
    settled(browser)
    assert document_of(browser)["rigs"]["usv_standard"]["quality"] == "draft"
    assert summary().startswith("2 cameras; carried by usv_1"), summary()
    spare = '#rigs [data-rig="spare"]'
    assert summary(spare).startswith("4 surround cameras; carried by no vessel")
    Select(browser.find_element(By.CSS_SELECTOR, f'{spare} select[data-key="preset"]')).select_by_value("lidar_only")
    settled(browser)
    assert document_of(browser)["rigs"]["spare"] == {"preset": "lidar_only"}
    assert value_of(browser, f'{spare} select[data-key="radar"]') == "off"
    assert summary(spare).startswith("no cameras; carried by no vessel"), summary(spare)
    assert browser.execute_script("return document.activeElement.dataset.key") == "preset"  # the focus stays
    browser.find_element(By.CSS_SELECTOR, f'{spare} button[data-action="remove"]').click()
    settled(browser)
    assert "spare" not in document_of(browser)["rigs"]
    assert browser.find_elements(By.CSS_SELECTOR, spare) == []
    assert js_errors(browser) == []


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
@pytest.mark.parametrize("rig", ["", "5", "[draft]"])
def test_a_rig_that_is_not_a_mapping_is_named_when_the_file_opens(client: TestClient, folder: Path, rig: str) -> None:
    """``usv_standard:`` with nothing after it (a rig of ``null``), or a rig of ``5``, came to the page as the raw
    mapping to be fixed there, which its rig panel could not draw: the page said "cannot open ... Cannot read
    properties of null (reading 'lidar')". Now the file's answer names the rig and says to fix it as text."""
    text = (bundled_dir() / "port_entry.yaml").read_text(encoding="utf-8")
    assert "  usv_standard: {}\n" in text
    (folder / "r.yaml").write_text(text.replace("  usv_standard: {}\n", f"  usv_standard: {rig}\n"), encoding="utf-8")
    r = client.get("/api/files/r.yaml")
    assert r.status_code == 422, r.text[:300]
    message = r.json()["error"]
    assert "rigs.usv_standard = " in message and "fix it as text" in message, message


def test_a_rig_that_is_not_a_mapping_does_not_break_the_page(browser: Any, live_server: LiveServer) -> None:
    """The page said why the file did not open, not a JavaScript error's words."""
    text = (bundled_dir() / "port_entry.yaml").read_text(encoding="utf-8")
    (live_server.folder / "nullrig.yaml").write_text(text.replace("  usv_standard: {}\n", "  usv_standard:\n"))
    browser.get("about:blank")
    browser.get(f"{live_server.url}/#file:nullrig.yaml")
    _wait(browser, "return document.body.dataset.ready === '1' && document.body.dataset.pending === '0'", "the page")
    said = browser.find_element(By.ID, "status").text
    assert "rigs.usv_standard = None" in said and "Cannot read properties" not in said, said
    assert js_errors(browser) == []


def shown_choice(driver: Any, css: str) -> str:
    """The text of the option the select ``css`` shows ("" when it shows none)."""
    return str(driver.execute_script("return document.querySelector(arguments[0]).selectedOptions[0]?.text ?? ''", css))


def test_a_choice_the_schema_refuses_is_shown_in_its_menu(browser: Any, live_server: LiveServer) -> None:
    """A file opened to be fixed whose weather, motion, rig preset or camera quality is none of the menu's choices
    showed a blank menu beside the schema's note (the vessel panel's asset and rig menus say "(not in the library)"):
    now the menu shows the value, saying it is not one of its choices, until another is picked."""
    env = {"time_of_day": "22:00", "weather": "snow", "motion": "phys"}
    write_scenario(
        live_server.folder, "odd.yaml", environment=env, rigs={"usv_standard": {"preset": "lidar", "quality": "ultra"}}
    )
    open_file(browser, live_server, "odd.yaml")
    js_errors(browser)
    rig = '#rigs [data-rig="usv_standard"]'
    assert shown_choice(browser, "#e-weather") == "snow (not a weather)"
    assert shown_choice(browser, "#e-motion") == "phys (not a motion)"
    assert shown_choice(browser, f'{rig} select[data-key="preset"]') == "lidar (not a rig preset)"
    assert shown_choice(browser, f'{rig} select[data-key="quality"]') == "ultra (not a camera quality)"
    assert "environment.weather = 'snow'" in note(browser, "environment.weather")
    Select(browser.find_element(By.ID, "e-weather")).select_by_value("fog")
    settled(browser)  # the change's live check may draw the rig panel again: find its menu after it (CI: stale)
    Select(browser.find_element(By.CSS_SELECTOR, f'{rig} select[data-key="quality"]')).select_by_value("draft")
    settled(browser)
    assert document_of(browser)["environment"]["weather"] == "fog"
    assert document_of(browser)["rigs"]["usv_standard"]["quality"] == "draft"
    browser.find_element(By.ID, "s-name").click()  # the focus out of the menus: they are drawn again
    Select(browser.find_element(By.ID, "e-motion")).select_by_value("paper")
    settled(browser)
    assert browser.find_elements(By.CSS_SELECTOR, "#e-weather option[data-missing]") == []
    assert browser.find_elements(By.CSS_SELECTOR, f'{rig} select[data-key="quality"] option[data-missing]') == []
    assert shown_choice(browser, f'{rig} select[data-key="preset"]') == "lidar (not a rig preset)"
    assert js_errors(browser) == []
