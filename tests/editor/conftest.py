"""Fixtures of the editor tests: a live editor server on a free port (uvicorn in a thread) and a headless Chromium
driven by Selenium (Debian's ``chromium`` and ``chromium-driver``, which ``scripts/test.sh`` installs)."""

from __future__ import annotations

import shutil
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMEDRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
WAIT_S = 60


@dataclass
class LiveServer:
    url: str
    folder: Path
    app: Any


@pytest.fixture(scope="module")
def live_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveServer]:
    import uvicorn
    from mmusv.editor.app import create_app
    from mmusv.editor.cli import _bind

    folder = tmp_path_factory.mktemp("editor")
    app = create_app(folder, allowed_hosts=["127.0.0.1", "localhost"])
    sock = _bind("127.0.0.1", 0)
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", lifespan="off"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    yield LiveServer(f"http://127.0.0.1:{sock.getsockname()[1]}", folder, app)
    server.should_exit = True
    thread.join(timeout=10)
    app.state.jobs.shutdown()
    sock.close()


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
