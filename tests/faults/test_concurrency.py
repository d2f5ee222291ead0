"""Concurrent users: a second run or batch into a folder another one is writing refuses at once (an advisory lock
on the folder), and two editor tabs saving the same file never silently lose an edit (ETag / If-Match)."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest
from mmusv.errors import IoError

from .conftest import ROOT, child_env, cli_main, scenario, wait_for, write_yaml

_SLOW_RUN = """
import sys, time
import mmusv
mmusv.run(sys.argv[1], out_dir=sys.argv[2], overwrite=True, progress=lambda done, total: time.sleep(0.05))
"""


def _slow_child(src: Path, out: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-c", _SLOW_RUN, str(src), str(out)],
        cwd=ROOT,
        env=child_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_a_second_run_into_the_same_folder_refuses_at_once(tmp_path: Path) -> None:
    from mmusv.acquire import run

    src = write_yaml(tmp_path / "tiny.yaml", scenario("tiny", frames=40))
    run(src, out_dir=tmp_path / "reference")
    out = tmp_path / "out"
    first = _slow_child(src, out)
    try:
        wait_for(lambda: (out / "tiny.mcap.partial").exists(), timeout=60, what="the first run to start writing")
        t = time.monotonic()
        code, _out, err = cli_main("run", str(src), "-o", str(out), "--overwrite")
        assert time.monotonic() - t < 20  # refused before anything was simulated at length
        assert code == 2 and err.count("\n") == 1, err
        assert f"{out} is being written by another mmusv run (process {first.pid})" in err, err
    finally:
        _stdout, stderr = first.communicate(timeout=120)
    assert first.returncode == 0, stderr
    # the first run's files are intact: the same bytes as a run alone
    assert (out / "tiny.mcap").read_bytes() == (tmp_path / "reference/tiny.mcap").read_bytes()
    assert (out / "manifest.json").read_text() == (tmp_path / "reference/manifest.json").read_text()


def test_a_second_batch_into_the_same_folder_refuses_at_once(tmp_path: Path) -> None:
    from mmusv.batch import run_many

    src = tmp_path / "src"
    for name in ("a", "b"):
        write_yaml(src / f"{name}.yaml", scenario(name, frames=40))
    out = tmp_path / "out"
    first = subprocess.Popen(
        [sys.executable, "-m", "mmusv.cli", "run", str(src), "-o", str(out)],
        cwd=ROOT,
        env=child_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        wait_for(lambda: any(out.rglob("*.mcap*")), timeout=60, what="the first batch to start writing")
        with pytest.raises(IoError, match=r"is being written by another mmusv run \(batch\)"):
            run_many(src, out_dir=out, overwrite=True)
    finally:
        stdout, stderr = first.communicate(timeout=120)
    assert first.returncode == 0 and "2 done, 0 failed" in stdout, stderr


def test_two_editor_tabs_saving_one_file_never_lose_an_edit(tmp_path: Path) -> None:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # starlette's notice about its httpx-based test client
        from fastapi.testclient import TestClient
    from mmusv.editor.app import create_app

    folder = tmp_path / "scenarios"
    folder.mkdir()
    client = TestClient(create_app(folder))
    first = scenario("tabs", frames=5)
    assert client.put("/api/files/tabs.yaml", json={"document": first}).status_code == 200
    tab1 = client.get("/api/files/tabs.yaml").json()
    tab2 = client.get("/api/files/tabs.yaml").json()
    assert tab1["etag"] == tab2["etag"]
    edit1 = {**tab1["document"], "seed": 101}
    edit2 = {**tab2["document"], "seed": 202}
    r1 = client.put(
        "/api/files/tabs.yaml",
        json={"document": edit1, "overwrite": True},
        headers={"If-Match": f'"{tab1["etag"]}"'},
    )
    assert r1.status_code == 200 and r1.json()["etag"] != tab1["etag"]
    assert r1.headers["etag"].strip('"') == r1.json()["etag"]
    r2 = client.put(
        "/api/files/tabs.yaml",
        json={"document": edit2, "overwrite": True},
        headers={"If-Match": f'"{tab2["etag"]}"'},
    )
    assert r2.status_code == 412 and "tabs.yaml was changed since you opened it" in r2.json()["error"]
    assert "seed: 101" in (folder / "tabs.yaml").read_text()  # tab 1's edit is kept
    # tab 2 reloads and saves on top of tab 1's version
    again = client.get("/api/files/tabs.yaml").json()
    assert again["etag"] == r1.json()["etag"]
    r3 = client.put(
        "/api/files/tabs.yaml",
        json={"document": {**again["document"], "seed": 202}, "overwrite": True},
        headers={"If-Match": f'"{again["etag"]}"'},
    )
    assert r3.status_code == 200 and "seed: 202" in (folder / "tabs.yaml").read_text()


def test_a_process_forked_during_a_run_does_not_keep_the_folder_locked(tmp_path: Path) -> None:
    """A process forked while the folder lock was held (a DataLoader's worker started during a run) shares the
    lock through its copy of the descriptor: the lock is released when the run ends, not when that process does
    (closing our descriptor alone left the folder locked)."""
    import os

    from mmusv.recording.guard import FolderLock

    folder = tmp_path / "out"
    folder.mkdir()
    lock = FolderLock(folder, what="test").acquire()
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child sleeps, holding its copy of the descriptor
        os.close(w)
        os.read(r, 1)
        os._exit(0)
    try:
        os.close(r)
        lock.release()
        FolderLock(folder, what="again").acquire().release()  # free at once, the child still alive
    finally:
        os.write(w, b"x")
        os.close(w)
        os.waitpid(pid, 0)
