"""Fixtures of the editor tests: a live editor server on a free port (uvicorn in a thread) and a headless Chromium
driven by Selenium (Debian's ``chromium`` and ``chromium-driver``, which ``scripts/test.sh`` installs)."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from editor_server import LiveServer, serve
from user_assets import library_restored

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMEDRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
WAIT_S = 60


@pytest.fixture(scope="module")
def live_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveServer]:
    with serve(tmp_path_factory.mktemp("editor")) as server:
        yield server


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    if not (Path(CHROMIUM).exists() and Path(CHROMEDRIVER).exists()):
        pytest.fail("the browser tests need Debian's chromium and chromium-driver (scripts/test.sh installs them)")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--window-size=1500,950", "--disable-gpu"):
        opts.add_argument(arg)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
    driver.set_script_timeout(WAIT_S)
    try:
        yield driver
    finally:
        driver.quit()


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    """The editor's scenario folder (empty)."""
    d = tmp_path / "scenarios"
    d.mkdir()
    return d


@pytest.fixture
def _library() -> Iterator[None]:
    """The vessel library put back as it was after the test (the user assets it registered taken out)."""
    with library_restored():
        yield
