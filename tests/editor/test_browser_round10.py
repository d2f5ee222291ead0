"""A tenth round through the editor in a real headless Chromium: the page loaded the vessel library once, at its
start, with the assets the server held then, so a scenario opened later (Open, an address, Back) listed none of its
own asset files' vessels in the library and the asset menu, and could list another scenario's, refused as "unknown
asset" once placed. The library and the menu are the open scenario's now, changed with it, never the scenario before.

Each browser test checks the browser's console for JavaScript errors (failed requests the page explains are not
errors).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from editor_server import serve
from selenium.webdriver.common.by import By
from selenium.webdriver.support.select import Select
from test_browser import _wait, click_world, open_editor, pick_open, settled, view
from test_browser_round import js_errors
from user_assets import write_boat

SCENARIO = """\
name: NAME
map: {type: open_sea, seed: 1}
acquisition: {frequency_hz: 5, frames: 2}
assets: ASSETS
vessels:
  - {id: u, role: usv, asset: usv_wamv, speed_mps: 2, route: [[-60, -300], [60, -300]]}
  - {id: s, asset: skiff, speed_mps: 3, route: [[0, -280], [40, -280]]}
"""

# What the page shows, each time the library changes or a scenario is shown: the scenario's name, the library's
# entries (name and size) and the asset menu's (names)
RECORD = """
const state = window.mmusvEditor.state;
window.shownLibraries = [];
const record = () => window.shownLibraries.push([
  state.doc?.name ?? null,
  [...document.querySelectorAll('#library li')].map((li) => `${li.dataset.asset} ${li.lastChild.textContent}`),
  [...document.querySelectorAll('#v-asset option')].map((o) => o.value),
]);
new MutationObserver(record).observe(document.getElementById('library'), {childList: true});
new MutationObserver(record).observe(document.getElementById('v-asset'), {childList: true});
state.on('loaded', record);
"""

OWN = {  # a scenario's own vessels as its library lists them; those it must not list
    "port_entry": ([], ["skiff", "punt"]),
    "harbour": (["skiff 6 × 2.4 m"], ["punt"]),
    "lake": (["skiff 12 × 2.4 m", "punt 3 × 2.4 m"], []),
}


def _opened(driver: Any, name: str) -> None:
    _wait(
        driver,
        f"return window.mmusvEditor.state.savedName === {name!r} && document.body.dataset.pending === '0'",
        f"{name} to open",
    )


def _check_shown(driver: Any) -> list[Any]:
    """Every library the page showed since the last call was the scenario's shown with it."""
    shown: list[Any] = driver.execute_script("const s = window.shownLibraries; window.shownLibraries = []; return s")
    for scenario, entries, menu in shown:
        own, others = OWN[scenario]
        names = {e.split(" ", 1)[0] for e in entries}
        assert set(own) <= set(entries) and names.isdisjoint(others), (scenario, entries)
        assert {e.split(" ", 1)[0] for e in own} <= set(menu) and set(menu).isdisjoint(others), (scenario, menu)
        assert "usv_wamv" in names and "usv_wamv" in menu
    return shown


@pytest.mark.usefixtures("_library")
def test_the_library_is_the_open_scenarios(browser: Any, folder: Path) -> None:
    write_boat(folder / "harbour" / "boat.yaml", name="skiff", length=6.0)
    write_boat(folder / "lake" / "boat.yaml", name="skiff", length=12.0)
    write_boat(folder / "lake" / "punt.yaml", name="punt", length=3.0)
    for name, assets in (("harbour", "[harbour/boat.yaml]"), ("lake", "[lake/boat.yaml, lake/punt.yaml]")):
        text = SCENARIO.replace("NAME", name).replace("ASSETS", assets)
        (folder / f"{name}.yaml").write_text(text, encoding="utf-8")
    with serve(folder) as server:
        open_editor(browser, server)  # port_entry, bundled: the built-in library
        js_errors(browser)
        browser.execute_script(RECORD)

        pick_open(browser, "file:lake.yaml")  # (the list is read again when reached)
        _opened(browser, "lake.yaml")
        assert {s[0] for s in _check_shown(browser)} == {"lake"}  # was: the start's library, no punt
        browser.execute_script("window.mmusvEditor.state.select('s')")
        menu = Select(browser.find_element(By.ID, "v-asset"))
        assert menu.first_selected_option.text == "skiff (12 × 2.4 m)"

        browser.execute_script("location.hash = '#file:harbour.yaml'")  # an address edited by hand
        _opened(browser, "harbour.yaml")
        assert {s[0] for s in _check_shown(browser)} == {"harbour"}  # was: no skiff (or lake's), and lake's punt
        browser.execute_script("window.mmusvEditor.state.select('s')")
        assert menu.first_selected_option.text == "skiff (6 × 2.4 m)"

        browser.back()  # to lake again
        _opened(browser, "lake.yaml")
        assert {s[0] for s in _check_shown(browser)} == {"lake"}

        browser.find_element(By.CSS_SELECTOR, '#library li[data-asset="punt"]').click()  # the scenario's own vessel
        v = view(browser)
        for dx in (0.0, 60.0):
            click_world(browser, v["cx"] + dx / v["scale"], v["cy"])
        browser.find_element(By.ID, "drawing-done").click()
        settled(browser)
        ev = browser.execute_script("return window.mmusvEditor.state.evaluation")
        assert ev["valid"], ev["errors"]  # was: "unknown asset 'punt'" had it been listed
        assert [x["asset"] for x in ev["vessels"]] == ["usv_wamv", "skiff", "punt"]
        assert ev["vessels"][2]["length"] == pytest.approx(3.0)
        browser.execute_script("const s = window.mmusvEditor.state; while (s.undoStack.length) s.undo();")
        settled(browser)
        _check_shown(browser)
        assert js_errors(browser) == []
