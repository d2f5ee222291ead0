"""``mmusv editor`` on the command line: prints its URL, serves the page and the named scenario, binds 127.0.0.1,
stops on Ctrl-C; bad arguments end with one line and exit status 2."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import urllib.request
from pathlib import Path

import pytest
from mmusv.cli import main

ENV = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2] / "python")}


def test_serves_the_named_scenario_on_loopback_and_stops_on_ctrl_c(tmp_path: Path) -> None:
    proc = subprocess.Popen(
        [sys.executable, "-m", "mmusv.cli", "editor", "port_entry", "--port", "0", "--dir", str(tmp_path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=ENV,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()  # blocks until the server has bound its port and says where
        m = re.match(r"mmusv editor: (http://127\.0\.0\.1:(\d+)/) ", line)
        assert m, line
        with urllib.request.urlopen(m.group(1), timeout=30) as r:
            assert r.status == 200 and b'<svg id="map"' in r.read()
        with urllib.request.urlopen(m.group(1) + "api/info", timeout=30) as r:
            info = json.loads(r.read())
        assert info["initial"]["name"] == "port_entry.yaml" and info["initial"]["in_folder"] is False
        assert info["folder"] == str(tmp_path.resolve())
        assert info["initial"]["comment"].startswith("Port map")
    finally:
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    # stopped by a signal: 128 + SIGINT, as every long-running command (issue #30)
    assert proc.returncode == 128 + signal.SIGINT and "stopped" in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["editor", "--dir", "/nonexistent/folder"], "does not exist"),
        (["editor", "no_such_scenario"], "does not exist and is not a bundled scenario"),
        (["editor", "--port", "70000"], "--port 70000"),
    ],
)
def test_bad_arguments_end_with_one_line(args: list[str], says: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(args) == 2
    err = capsys.readouterr().err
    assert says in err and err.count("\n") == 1 and err.startswith("mmusv: error:")


def test_a_folder_given_as_the_scenario_is_named_as_such(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A folder for SCENARIO was read as a file: "DIR: Is a directory", naming neither the argument nor the way to
    edit a folder's scenarios."""
    assert main(["editor", str(tmp_path)]) == 2
    assert capsys.readouterr().err == (
        f"mmusv: error: scenario {str(tmp_path)!r} is a folder, not a scenario file: give a YAML file, or --dir "
        f"{tmp_path} to edit the scenarios in that folder\n"
    )


def _opened(argv: list[str], monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> tuple[dict, str]:
    """``mmusv editor ARGV`` up to serving: the page's ``initial`` scenario (``/api/info``) and what was printed."""
    import warnings

    from mmusv.editor import cli as editor_cli

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # starlette's notice about its httpx-based test client
        from fastapi.testclient import TestClient

    apps: list[object] = []
    monkeypatch.setattr(editor_cli, "serve", lambda app, **kw: apps.append(app))
    assert main(argv) == 0
    (app,) = apps
    info = TestClient(app, base_url="http://127.0.0.1").get("/api/info").json()  # type: ignore[arg-type]
    return info["initial"], capsys.readouterr().err


def test_a_scenario_that_does_not_validate_opens_to_be_fixed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """It was refused (exit 2), though the page opens the same file from its Open box and lists what is wrong."""
    path = tmp_path / "broken.yaml"
    path.write_text("# my harbour\nname: broken\nvessels: []\n")
    initial, err = _opened(["editor", str(path), "--port", "0"], monkeypatch, capsys)
    assert initial["name"] == "broken.yaml" and initial["in_folder"] is True and initial["etag"], initial
    assert initial["document"]["vessels"] == [] and initial["comment"] == "my harbour", initial
    assert "the page lists what is wrong under Checks" in err, err


def test_a_file_not_named_yaml_is_said_to_be_saved_under_another_name(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The page was told it was the folder's ``scen.txt.yaml`` (a file that does not exist, saved beside it)."""
    src = Path(__file__).resolve().parents[2] / "scenarios" / "port_entry.yaml"
    path = tmp_path / "scen.txt"
    path.write_bytes(src.read_bytes())
    initial, err = _opened(["editor", str(path), "--port", "0"], monkeypatch, capsys)
    assert initial["name"] == "scen.txt.yaml" and initial["in_folder"] is False and initial["etag"] is None
    assert "scen.txt is saved as scen.txt.yaml" in err, err
