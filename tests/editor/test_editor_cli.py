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
        (["editor", "no_such_scenario.yaml"], "does not exist and is not a bundled scenario"),
        (["editor", "--port", "70000"], "--port 70000"),
    ],
)
def test_bad_arguments_end_with_one_line(args: list[str], says: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(args) == 2
    err = capsys.readouterr().err
    assert says in err and err.count("\n") == 1 and err.startswith("mmusv: error:")
