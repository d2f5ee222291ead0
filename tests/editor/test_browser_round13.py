"""A thirteenth round through the editor in a real headless Chromium: the replies about a run can come back out of
order. The stop's reply is the run as it was when the stop was sent (still running), and a slow poll's reply can be
older than the next poll's. Either one, coming after the poll that saw the run end, put the run back to "running"
with its Stop button, and nothing polled it again: the page showed a stopped run as running for good. CI saw
``test_an_interrupted_run_is_told_as_an_error`` wait 60 s for the stop. A run that has ended now stays ended, and
its progress never goes back. The preview had the same fault: a preview closed and asked again for another frame
showed the first one's picture if it came in last (or as its picture finished loading); and so had opening a file:
the Open box's arrow keys open each file they pass, and a file read coming in after the next one's showed the file
passed. A reply is now shown only if it is the last asked for.

Each browser test checks the browser's console for JavaScript errors (failed requests the page explains are not
errors).
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import pytest
from editor_server import serve
from mmusv.bundled import resolve_scenario
from selenium.webdriver.common.by import By
from selenium.webdriver.support.select import Select
from test_browser import LiveServer, _wait, open_editor, pick_open, settled
from test_browser_round import js_errors, type_into
from test_browser_round2 import save_as

ENDED = "return document.getElementById('run-status').dataset.status === 'interrupted'"

HOLD = """const [method, pattern, until, every, tiny, settleMs] = arguments;
const real = window.fetch, re = new RegExp(pattern), ready = new Function(`return (${until});`);
let asked = 0;
window.heldDelivered = false;
window.fetch = async (url, opts) => {
  const held = ((opts && opts.method) || 'GET') === method && re.test(String(url)) && (every || asked++ === 0);
  const res = await real(url, opts);
  if (!held) return res;
  while (!ready()) await new Promise((r) => setTimeout(r, 50));
  setTimeout(() => { window.heldDelivered = true; }, settleMs);
  if (!tiny) return res;
  const c = document.createElement('canvas');
  c.width = c.height = 1;
  const png = await new Promise((r) => c.toBlob(r, 'image/png'));
  return new Response(png, { status: 200, headers: { 'Content-Type': 'image/png' } });
};"""


def hold_replies(
    driver: Any, method: str, pattern: str, until: str, *, every: bool = False, tiny: bool = False, settle_ms: int = 300
) -> None:
    """Holds the reply to the page's first request of ``method`` whose address matches the regular expression
    ``pattern`` (``every``: each such request's) until the JavaScript expression ``until`` is true, then hands it to
    the page; ``window.heldDelivered`` turns true ``settle_ms`` later (the page has handled it). A request is counted
    as it is asked, not as it is answered (the server may answer a later one first). ``tiny``: the held reply is
    replaced by a 1 x 1 PNG, so that the page's picture tells whose reply it shows."""
    driver.execute_script(HOLD, method, pattern, until, every, tiny, settle_ms)


@pytest.mark.parametrize("late", ["DELETE", "GET"], ids=["the stop's reply", "a poll's reply"])
def test_a_reply_older_than_the_run_s_end_does_not_start_it_again(
    browser: Any, live_server: LiveServer, late: str
) -> None:
    open_editor(browser, live_server)
    js_errors(browser)
    preset = '#rigs [data-rig="usv_standard"] select[data-key="preset"]'
    Select(browser.find_element(By.CSS_SELECTOR, preset)).select_by_value("lidar_only")
    type_into(browser, browser.find_element(By.ID, "a-frames"), "200")  # a run long enough to stop (40 s sailed)
    settled(browser)
    save_as(browser, f"late_{late.lower()}.yaml")  # a file of its own: the folder is the module's
    type_into(browser, browser.find_element(By.ID, "run-frames"), "")
    # the stop's reply, or the first poll's, held until the page shows the run ended
    hold_replies(browser, late, r"/api/runs/\d+$", ENDED.removeprefix("return "))
    browser.find_element(By.ID, "run").click()
    _wait(browser, "return document.getElementById('run-status').dataset.status === 'running'", "the run")
    if late == "GET":  # the first poll's reply is the one held: it must be asked for before the stop
        _wait(browser, "return document.getElementById('run-text').textContent.startsWith('running')", "a poll")
        browser.execute_script("return new Promise((r) => setTimeout(r, 500))")
    browser.find_element(By.ID, "run-stop").click()
    _wait(browser, ENDED, "the stop")
    _wait(browser, "return window.heldDelivered", "the late reply")
    # was: "running · frame 0", the Stop button shown, and no poll left to correct it
    assert browser.execute_script(ENDED)
    assert browser.find_element(By.ID, "run-text").text.startswith("interrupted: ")
    assert not browser.find_element(By.ID, "run-stop").is_displayed()
    assert js_errors(browser) == []


def test_a_preview_asked_before_another_does_not_replace_it(browser: Any, live_server: LiveServer) -> None:
    # A preview renders for seconds; closed and asked again for another frame, the first one's picture came in
    # after the second's and took its place under the second's title (frame 12 said, frame 2 shown).
    open_editor(browser, live_server)
    js_errors(browser)
    # the first preview's reply held until a picture is shown (the second's), then handed on as a 1 x 1 picture
    img = "document.getElementById('preview-img')"
    picture = f"!{img}.hidden && {img}.complete && {img}.naturalWidth > 1"
    hold_replies(browser, "POST", "/api/preview$", picture, tiny=True, settle_ms=500)
    browser.execute_script("window.mmusvEditor.state.setFrame(2)")
    browser.find_element(By.ID, "preview").click()
    browser.find_element(By.ID, "preview-close").click()
    browser.execute_script("window.mmusvEditor.state.setFrame(12)")
    browser.find_element(By.ID, "preview").click()
    _wait(browser, "return window.heldDelivered", "the first preview's reply")
    shown = browser.execute_script(
        "const i = document.getElementById('preview-img'); return [i.hidden, i.naturalWidth, "
        "document.getElementById('preview-wait').hidden]"
    )
    assert shown == [False, shown[1], True] and shown[1] > 1, shown  # was: the 1 x 1 picture of the first
    assert "frame 12" in browser.find_element(By.ID, "preview-title").text
    assert js_errors(browser) == []


def test_a_file_opened_before_another_does_not_replace_it(browser: Any, folder: Path) -> None:
    # The Open box opened first.yaml, then later.yaml before the first had come (arrow keys on the box open each
    # file they pass): the first's reply coming in last showed first.yaml, the file not picked last.
    shutil.copy(resolve_scenario("port_entry"), folder / "first.yaml")
    shutil.copy(resolve_scenario("open_sea_convoy"), folder / "later.yaml")
    with serve(folder) as server:
        open_editor(browser, server)
        js_errors(browser)
        # the first file's read held until later.yaml is shown
        later = "window.mmusvEditor.state.savedName === 'later.yaml'"
        hold_replies(browser, "GET", r"/api/files/first\.yaml$", later, settle_ms=800)
        pick_open(browser, "file:first.yaml")
        browser.execute_script("document.activeElement.blur()")
        pick_open(browser, "file:later.yaml")
        _wait(browser, "return window.heldDelivered", "the first file's reply")
        # was: first.yaml (port_entry) shown, named in the address and the status
        assert browser.execute_script("return window.mmusvEditor.state.savedName") == "later.yaml"
        assert browser.execute_script("return window.mmusvEditor.state.doc.name") == "open_sea_convoy"
        assert browser.execute_script("return location.hash") == "#file:later.yaml"
        assert js_errors(browser) == []


SHOWN = "const d = (id) => document.getElementById(id); return [d('preview-img').hidden, d('preview-wait').hidden]"


def test_a_picture_loaded_after_another_preview_was_asked_for_does_not_show(
    browser: Any, live_server: LiveServer
) -> None:
    # The picture of a preview whose load ends once another preview was asked for (its image's onload, still the
    # first one's until the second's reply comes) showed it, and hid the wait, under the second's title.
    open_editor(browser, live_server)
    js_errors(browser)
    browser.execute_script("window.mmusvEditor.state.setFrame(2)")
    browser.find_element(By.ID, "preview").click()
    _wait(browser, "const i = document.getElementById('preview-img'); return !i.hidden && i.naturalWidth > 1", "it")
    browser.find_element(By.ID, "preview-close").click()
    hold_replies(browser, "POST", "/api/preview$", "window.releasePreviews", every=True)  # each, until released
    browser.execute_script("window.mmusvEditor.state.setFrame(12)")
    browser.find_element(By.ID, "preview").click()
    assert browser.execute_script(SHOWN) == [True, False]
    browser.execute_script("document.getElementById('preview-img').onload()")  # the first picture's load ends
    assert browser.execute_script(SHOWN) == [True, False]  # was: [False, True], frame 2's picture shown
    browser.execute_script("window.releasePreviews = true")
    _wait(browser, f"return JSON.stringify((() => {{ {SHOWN} }})()) === '[false,true]'", "the second preview")
    assert "frame 12" in browser.find_element(By.ID, "preview-title").text
    assert js_errors(browser) == []
