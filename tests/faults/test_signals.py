"""SIGTERM ends every long-running command cleanly: the recording in progress is finished with its completed
frames (status ``interrupted``), files are closed, background runs and pool workers are stopped and reaped, the
exit status is 128 + 15, and no traceback is printed."""

from __future__ import annotations

import json
import os
import signal
import time
import urllib.request
from pathlib import Path
from typing import Any

import yaml

from .conftest import mmusv, scenario, wait_for, write_yaml

SPEC: dict[str, Any] = {
    "name": "sigspec",
    "seed": 7,
    "map": {"type": "open_sea", "seed": 2},
    "acquisition": {"frequency_hz": 5, "frames": 400},
    "rig": "usv_lidar",
    "rigs": {"usv_lidar": {"preset": "lidar_only", "lidar": {"channels": 32, "points_per_second": 327680}}},
    "usv": {"assets": ["usv_wamv"], "speed_mps": [2, 3]},
    "difficulties": {"near": {"range_m": [40, 120]}},
    "combinations": [
        {"family": "crossing", "difficulty": "near", "cooperating": 1, "targets": ["small"], "quota": 2},
        {"family": "head_on", "difficulty": "near", "cooperating": 1, "targets": ["medium"], "quota": 1},
    ],
}


def _group(pgid: int) -> list[int]:
    """Processes of the process group ``pgid`` still alive (zombies count: they were not reaped)."""
    out = []
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                if os.getpgid(int(d)) == pgid:
                    out.append(int(d))
            except OSError:
                continue
    return out


def _term(proc: Any, ready: Any, *, timeout: float = 120) -> tuple[str, str]:
    wait_for(lambda: ready() or proc.poll() is not None, timeout=timeout, what="the command to be busy")
    assert proc.poll() is None, "the command ended before it could be stopped"
    os.kill(proc.pid, signal.SIGTERM)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signal.SIGTERM, (proc.returncode, stderr)
    assert "Traceback" not in stderr, stderr
    wait_for(lambda: not _group(proc.pid), timeout=30, what="every child of the command to be gone")
    return stdout, stderr


def test_sigterm_ends_a_run_with_its_frames_kept(tmp_path: Path) -> None:
    from mmusv.recording.contents import summary

    src = write_yaml(tmp_path / "long.yaml", scenario("long", frames=400, dense=True))
    out = tmp_path / "out"
    proc = mmusv("run", str(src), "-o", str(out))
    partial = out / "long.mcap.partial"
    _stdout, stderr = _term(proc, lambda: partial.exists() and partial.stat().st_size > 4 << 20)  # a chunk written
    assert "mmusv: terminated (SIGTERM)" in stderr
    s = summary(out / "long.mcap")
    run = s["metadata"]["run"]
    assert run["status"] == "interrupted" and 0 < int(run["frames_written"]) < 400
    assert s["frames"]["read"] == int(run["frames_written"]) and not s["damage"]
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["status"] == "interrupted" and manifest["frames_written"] == int(run["frames_written"])


def test_sigterm_ends_generate_without_half_written_files(tmp_path: Path) -> None:
    from mmusv.config import load_scenario

    spec = dict(SPEC, combinations=[dict(SPEC["combinations"][0], quota=400)])
    spec_file = write_yaml(tmp_path / "spec.yaml", spec)
    out = tmp_path / "gen"
    proc = mmusv("generate", str(spec_file), "-o", str(out), "--no-progress")
    _term(proc, lambda: len(list(out.glob("*.yaml"))) >= 2)
    assert not list(out.glob(".*.tmp")) and not (out / "report.json").exists()
    for f in out.glob("*.yaml"):
        load_scenario(f)  # every file written is whole


def test_sigterm_ends_dataset_and_reaps_its_pool_workers(tmp_path: Path) -> None:
    spec_file = write_yaml(tmp_path / "spec.yaml", SPEC)
    out = tmp_path / "ds"
    proc = mmusv("dataset", str(spec_file), "-o", str(out), "--jobs", "2")
    started: list[float] = []

    def recording() -> bool:  # a second after the first worker started writing
        if not started and any((out / "recordings").rglob("*.mcap.partial")):
            started.append(time.monotonic())
        return bool(started) and time.monotonic() - started[0] > 1.0

    _term(proc, recording, timeout=240)
    from mmusv.recording.contents import summary

    finished = 0
    for manifest in (out / "recordings").glob("*/manifest.json"):
        doc = json.loads(manifest.read_text())
        assert doc["status"] in ("complete", "interrupted")
        s = summary(manifest.parent / doc["recording"])  # each worker finished its file
        assert s["complete"] and s["frames"]["read"] == doc["frames_written"] > 0
        finished += 1
    assert finished >= 1
    for partial in (out / "recordings").rglob("*.mcap.partial"):  # only a recording stopped before its first frame
        assert summary(partial)["frames"]["read"] == 0


def test_sigterm_ends_the_editor_and_its_background_run(tmp_path: Path) -> None:
    folder = tmp_path / "scen"
    write_yaml(folder / "long.yaml", scenario("long", frames=400, dense=True))
    proc = mmusv("editor", "--dir", str(folder), "--port", "0")
    assert proc.stdout is not None
    line = proc.stdout.readline()
    url = line.split()[2]
    req = urllib.request.Request(
        url + "api/runs",
        data=json.dumps({"name": "long.yaml"}).encode(),
        headers={"Content-Type": "application/json"},
        method="POST",
    )
    job = json.loads(urllib.request.urlopen(req, timeout=30).read())

    def progressing() -> bool:
        now = json.loads(urllib.request.urlopen(f"{url}api/runs/{job['id']}", timeout=30).read())
        return bool(now["done"] >= 2)

    t = time.monotonic()
    _stdout, stderr = _term(proc, progressing)
    assert "mmusv editor: stopped" in stderr and time.monotonic() - t < 120
    manifest = json.loads((folder / "out/long/manifest.json").read_text())
    assert manifest["status"] == "interrupted"
    assert yaml.safe_load((folder / "out/long/scenario.yaml").read_text())["name"] == "long"
