"""mmusv under the ways researchers run Python code concurrently (a helper's round; each test failed before its
fix): a FrameRecorder shared by threads keeps each frame's messages together, a process forked while another
thread captures on a simulation can capture (its turn is free again), ``run_many(jobs=2)`` in a daemonic pool
worker is refused with a message instead of a bare ``AssertionError``, and ``run_many(jobs=2)`` from a script read
on standard input (``python -``) records instead of losing every worker. Cases that could hang run in a child
process with a time limit."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import threading
from pathlib import Path
from typing import Any

import pytest
import yaml
from tiny_scenario import lidar_scenario

ROOT = Path(__file__).resolve().parents[1]


def _lidar(name: str, frames: int = 2) -> dict[str, Any]:
    """The tiny scenario (:func:`tiny_scenario.lidar_scenario`) of ``frames`` frames."""
    return lidar_scenario(name, frames=frames)


def _camera(name: str, frames: int) -> dict[str, Any]:
    """The tiny scenario with a 64×48 camera and a small top view beside the LiDAR (more messages a frame)."""
    sc = _lidar(name, frames)
    sc["rigs"]["r"] = {
        "lidar": {"channels": 8, "points_per_second": 8 * 360 * 5},
        "cameras": [{"name": "front", "resolution": [64, 48]}],
        "top_view": {"resolution": [48, 48]},
    }
    return sc


def _folder(path: Path, names: tuple[str, ...] = ("a", "b")) -> Path:
    path.mkdir(parents=True, exist_ok=True)
    for n in names:
        (path / f"{n}.yaml").write_text(yaml.safe_dump(_lidar(n)), encoding="utf-8")
    return path


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT / "python") + os.pathsep + os.environ.get("PYTHONPATH", "")}


def _python(args: list[str], *, cwd: Path, timeout: float, stdin: str | None = None) -> str:
    """``python ARGS`` in ``cwd``: its stdout; a hang (killed after ``timeout`` s) or a failure fails the test."""
    try:
        proc = subprocess.run(
            [sys.executable, *args],
            cwd=cwd,
            env=_env(),
            input=stdin,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
    except subprocess.TimeoutExpired as exc:
        raise AssertionError(f"hung (killed after {timeout} s): {exc.stdout!r:.2000} {exc.stderr!r:.2000}") from None
    assert proc.returncode == 0, (proc.stdout[-3000:], proc.stderr[-3000:])
    return proc.stdout


def test_a_frame_recorder_shared_by_threads_keeps_each_frame_whole(tmp_path: Path) -> None:
    """Threads writing frames into one FrameRecorder interleaved the frames' messages, and the reader then gave
    each frame with a few of its topics (silently); now each frame is written together and reads back whole."""
    from mmusv.acquire import annotations_for
    from mmusv.recording.frames import FrameRecorder
    from mmusv.recording.info import read_info
    from mmusv.recording.stream import FrameStream
    from mmusv.silhouettes import SilhouetteCache
    from mmusv.simulation import Simulation

    sim = Simulation(_camera("shared", 6))
    caps = [sim.capture(k) for k in range(6)]
    silhouettes = SilhouetteCache()
    anns = [{a: x.columns() for a, x in annotations_for(sim, c, silhouettes).items()} for c in caps]

    def frames(path: Path) -> dict[int, dict[str, bytes]]:
        stream = FrameStream(read_info(path), want=lambda _t: True)
        return {fr.index: {t: m.SerializeToString() for t, m in fr.messages.items()} for fr in stream}

    one = FrameRecorder(tmp_path / "one.mcap", sim)
    for cap, ann in zip(caps, anns, strict=True):
        one.write_frame(cap, ann)
    one.finish(status="complete", frames=6)
    expected = frames(tmp_path / "one.mcap")
    assert len(expected) == 6 and all(len(m) > 5 for m in expected.values())

    shared = FrameRecorder(tmp_path / "shared.mcap", sim)
    start = threading.Barrier(3)

    def write(first: int) -> None:
        start.wait()
        for k in range(first, 6, 3):
            shared.write_frame(caps[k], anns[k])

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # threads take turns between (nearly) every two bytecodes
    try:
        threads = [threading.Thread(target=write, args=(i,)) for i in range(3)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        sys.setswitchinterval(interval)
    shared.finish(status="complete", frames=6)
    got = frames(tmp_path / "shared.mcap")
    assert {k: sorted(m) for k, m in got.items()} == {k: sorted(m) for k, m in expected.items()}
    assert got == expected


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork() on this platform")
def test_a_child_forked_while_a_thread_captures_captures_too(tmp_path: Path) -> None:
    """A process forked while another thread held a simulation's turn (a DataLoader's workers started while a
    thread captures) waited forever on its first capture: the thread that would give the turn back is not in the
    child. Now the child captures the parent's bytes."""
    script = tmp_path / "case.py"
    script.write_text(
        textwrap.dedent(
            f"""
            import hashlib, os, threading, time
            import numpy as np
            from mmusv.simulation import Simulation

            def digest(cap):
                a = cap.agents["u"]
                return hashlib.sha256(np.ascontiguousarray(a.lidar.xyz).tobytes()).hexdigest()

            sim = Simulation({_lidar("forked", 3)!r})
            expected = digest(sim.capture(1))
            held, done = threading.Event(), threading.Event()

            def capturing():  # a thread in the middle of a capture: it holds the simulation's turn
                with sim._lock:
                    held.set()
                    done.wait()

            t = threading.Thread(target=capturing)
            t.start()
            held.wait()
            r, w = os.pipe()
            pid = os.fork()
            if pid == 0:
                os.close(r)
                os.write(w, digest(sim.capture(1)).encode())
                os._exit(0)
            os.close(w)
            deadline = time.monotonic() + 60
            while not os.waitpid(pid, os.WNOHANG)[0]:
                if time.monotonic() > deadline:
                    os.kill(pid, 9)
                    os.waitpid(pid, 0)
                    print("HUNG")
                    break
                time.sleep(0.05)
            else:
                print("SAME", os.read(r, 200).decode() == expected)
            done.set()
            t.join()
            """
        ),
        encoding="utf-8",
    )
    out = _python([str(script)], cwd=tmp_path, timeout=150)
    assert "SAME True" in out, out


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork() on this platform")
def test_run_many_with_a_pool_in_a_daemonic_worker_is_refused_with_a_message(tmp_path: Path) -> None:
    """A multiprocessing.Pool (or DataLoader) worker may not have child processes: ``run_many(jobs=2)`` there
    failed on its first task with a bare ``AssertionError: daemonic processes are not allowed to have children``
    after writing its index. Now it is refused before anything is written, naming ``jobs=1``, which records the
    batch in the worker itself."""
    folder = _folder(tmp_path / "scenarios")
    script = tmp_path / "case.py"
    script.write_text(
        textwrap.dedent(
            f"""
            import multiprocessing, os
            import mmusv

            def batch(args):
                out, jobs = args
                try:
                    report = mmusv.run_many({str(folder)!r}, out_dir=out, jobs=jobs)
                except Exception as exc:
                    return f"{{type(exc).__name__}}: {{exc}}"
                return str(report.ok)

            if __name__ == "__main__":
                with multiprocessing.get_context("fork").Pool(1) as pool:
                    two = pool.apply(batch, (({str(tmp_path / "two")!r}, 2),))
                    one = pool.apply(batch, (({str(tmp_path / "one")!r}, 1),))
                print("TWO", two)
                print("ONE", one)
            """
        ),
        encoding="utf-8",
    )
    out = _python([str(script)], cwd=tmp_path, timeout=120)
    two = out.split("TWO ", 1)[1].split("\n", 1)[0]
    assert two.startswith("ConfigError: mmusv.run_many(jobs=2) cannot start its pool"), out
    assert "daemonic" in two and "jobs=1" in two, two
    assert not (tmp_path / "two").exists()  # refused before anything was written
    assert "ONE True" in out, out
    assert (tmp_path / "one" / "a" / "a.mcap").is_file() and (tmp_path / "one" / "b" / "b.mcap").is_file()


def test_run_many_with_a_pool_from_a_script_on_standard_input(tmp_path: Path) -> None:
    """``python -`` (the script piped in, ``__main__.__file__`` = ``<stdin>``): every spawned worker died trying
    to import ``<stdin>`` and each recording failed as a lost worker, blaming a missing ``__main__`` guard. Now
    the workers start without the script (as from a notebook) and record."""
    _folder(tmp_path / "scenarios")
    script = textwrap.dedent(
        """
        import mmusv
        if __name__ == "__main__":
            report = mmusv.run_many("scenarios", out_dir="out", jobs=2)
            print("OK", report.ok, report.backend, [o.error for o in report.outcomes])
        """
    )
    out = _python(["-"], cwd=tmp_path, timeout=150, stdin=script)
    assert "OK True pool" in out, out
    assert (tmp_path / "out" / "a" / "a.mcap").is_file() and (tmp_path / "out" / "b" / "b.mcap").is_file()


def test_the_detection_study_s_pool_in_a_daemonic_worker_is_refused() -> None:
    """The detection study's own pool of spawned workers follows the batch's rule: a daemonic process (a
    multiprocessing.Pool worker) may not start one, said up front instead of a bare AssertionError."""
    import multiprocessing

    with multiprocessing.get_context("spawn").Pool(1) as pool:
        said = pool.apply(_study_pool_in_worker)
    assert "cannot start its pool of processes here: this process is a daemonic worker" in said, said


def _study_pool_in_worker() -> str:
    from mmusv.errors import ConfigError
    from mmusv.studies.detection.parallel import run_study_jobs

    try:
        run_study_jobs(None, options=None, spec=None, jobs=2)  # type: ignore[arg-type]
    except ConfigError as exc:
        return str(exc)
    except Exception as exc:  # what it raised instead, for the assertion message
        return f"{type(exc).__name__}: {exc}"
    return "no error"
