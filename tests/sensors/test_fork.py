"""A process forked after mmusv ran (a PyTorch DataLoader's workers, Linux's default start method) captures and
records like its parent, byte for byte: its parallel work runs on a thread pool of its own
(``mmusv_core::threads``). Before, the parent's pool had no threads in the child and the first capture there
waited forever. Each case runs in a child process with a time limit, so a hang fails the test."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

COMMON = """
import hashlib, os, sys
import numpy as np
import yaml
import mmusv
from mmusv.simulation import Simulation

def scenario():
    sc = yaml.safe_load(open(os.path.join(sys.argv[1], "scenarios/port_entry.yaml")))
    sc["acquisition"]["frames"] = 4
    sc["vessels"] = [v for v in sc["vessels"] if v["id"] != "usv_3"]
    sc["rigs"] = {"usv_standard": {
        "lidar": {"channels": 8, "points_per_second": 8 * 360 * 5},
        "radar": {"range_m": 600, "azimuth_bins": 128, "rays_el": 4, "ppi_size_px": 64},
        "cameras": [{"name": "front", "resolution": [64, 48], "mount": {"point": "camera_front"}}],
        "top_view": {"resolution": [48, 48]},
    }}
    return sc

def digest(cap):
    h = hashlib.sha256()
    for aid in sorted(cap.agents):
        a = cap.agents[aid]
        h.update(np.ascontiguousarray(a.lidar.xyz).tobytes())
        for name in sorted(a.cameras):
            c = a.cameras[name]
            for arr in (c.rgb, c.depth, c.semantic, c.instance):
                h.update(np.ascontiguousarray(arr).tobytes())
        h.update(np.ascontiguousarray(a.top_view.rgb).tobytes())
        h.update(np.ascontiguousarray(a.radar_ppi).tobytes())
    return h.hexdigest()
"""


def _run(body: str, tmp_path: Path, *, timeout: float = 240) -> str:
    """Runs ``body`` after :data:`COMMON` as a script in a session of its own; on a hang the whole session (the
    script and every process it forked) is killed, and the test fails."""
    import signal

    script = tmp_path / "case.py"
    script.write_text(COMMON + textwrap.dedent(body), encoding="utf-8")
    env = {**os.environ, "PYTHONPATH": str(ROOT / "python") + os.pathsep + os.environ.get("PYTHONPATH", "")}
    proc = subprocess.Popen(
        [sys.executable, str(script), str(ROOT), str(tmp_path)],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        raise AssertionError(f"hung (killed after {timeout} s): {out[-2000:]!r} {err[-2000:]!r}") from None
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)  # forked children left behind by a failed case
    assert proc.returncode == 0, (out[-3000:], err[-3000:])
    return out


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork() on this platform")
def test_a_forked_child_captures_what_its_parent_captures(tmp_path: Path) -> None:
    out = _run(
        """
        sim = Simulation(scenario())
        sim.capture(0)                 # the parent's pools exist now
        sim.prefetch_frame(1)          # and a surface is being sampled on a thread of the parent's
        r, w = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(r)
            got = " ".join(digest(sim.capture(k)) for k in (1, 2))
            os.write(w, got.encode())
            os._exit(0)
        os.close(w)
        child = b""
        while chunk := os.read(r, 65536):
            child += chunk
        _, status = os.waitpid(pid, 0)
        assert status == 0, status
        parent = " ".join(digest(sim.capture(k)) for k in (1, 2))
        fresh = Simulation(scenario())
        again = " ".join(digest(fresh.capture(k)) for k in (1, 2))
        print("SAME", child.decode() == parent == again)
        """,
        tmp_path,
    )
    assert "SAME True" in out, out


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork() on this platform")
def test_a_forked_child_records_the_parent_s_bytes_until_polars_has_started(tmp_path: Path) -> None:
    """Recording in a forked child works while the parent has not started Polars' threads (the tables' writer);
    once it has, Polars would hang in the child, and mmusv.run says so at once instead."""
    out = _run(
        """
        from mmusv.errors import ConfigError
        out = sys.argv[2]
        Simulation(scenario()).capture(0)   # the core's pools exist now, Polars' not
        pid = os.fork()
        if pid == 0:
            mmusv.run(scenario(), out_dir=os.path.join(out, "child"), frames=2)
            os._exit(0)
        _, status = os.waitpid(pid, 0)
        mmusv.run(scenario(), out_dir=os.path.join(out, "parent"), frames=2)   # Polars' threads run now
        a = open(os.path.join(out, "parent", "port_entry.mcap"), "rb").read()
        b = open(os.path.join(out, "child", "port_entry.mcap"), "rb").read()
        print("STATUS", status, "SAME", a == b, len(a))
        r, w = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(r)
            try:
                mmusv.run(scenario(), out_dir=os.path.join(out, "late"), frames=2)
                os.write(w, b"recorded")
            except ConfigError as exc:
                os.write(w, str(exc).encode())
            os._exit(0)
        os.close(w)
        said = b""
        while chunk := os.read(r, 65536):
            said += chunk
        os.waitpid(pid, 0)
        print("LATE", said.decode(), "WROTE", os.path.exists(os.path.join(out, "late")))
        """,
        tmp_path,
    )
    assert "STATUS 0 SAME True" in out, out
    assert "LATE mmusv.run cannot run in this process: it was forked" in out and "'spawn'" in out, out
    assert "WROTE False" in out, out


def test_a_simulation_pickles_as_what_rebuilds_it() -> None:
    import pickle

    import yaml
    from mmusv.simulation import Simulation
    from mmusv.world.sea_state import SeaSpec

    sc = yaml.safe_load((ROOT / "scenarios/open_sea_convoy.yaml").read_text())
    sc["acquisition"]["frames"] = 3
    sc["rigs"] = {k: {"preset": "lidar_only", "lidar": {"channels": 8}} for k in sc["rigs"]}
    sim = Simulation(sc)
    sim.set_sea_surface(SeaSpec(hs_m=2.5, tp_s=7.0, gamma=3.3, direction_rad=0.5, spread_s=10.0))  # travels too
    again = pickle.loads(pickle.dumps(sim))
    assert again is not sim and again.sea == sim.sea
    for k in (0, 2):
        a, b = sim.capture(k), again.capture(k)
        for aid in a.agents:
            la, lb = a.agents[aid].lidar, b.agents[aid].lidar
            assert la is not None and lb is not None and la.xyz.size
            assert la.xyz.tobytes() == lb.xyz.tobytes() and la.instance.tobytes() == lb.instance.tobytes()


@pytest.mark.parametrize("context", ["fork", "spawn"])
def test_a_dataloader_s_workers_give_the_captures(context: str, tmp_path: Path) -> None:
    """Forked workers (after the parent captured: the core's pools exist) and spawned ones (the dataset, holding
    a Simulation, is pickled to them) give the captures the dataset gives directly."""
    if context == "fork" and not hasattr(os, "fork"):
        pytest.skip("no fork() on this platform")
    pytest.importorskip("torch")
    out = _run(
        f"""
        from torch.utils.data import DataLoader, Dataset

        class Frames(Dataset):
            def __init__(self):
                self.sim = Simulation(scenario())
            def __len__(self):
                return 3
            def __getitem__(self, k):
                return digest(self.sim.capture(k))

        if __name__ == "__main__":
            ds = Frames()
            direct = [ds[k] for k in range(3)]
            loader = DataLoader(ds, batch_size=None, num_workers=2, multiprocessing_context="{context}")
            print("SAME", list(loader) == direct)
        """,
        tmp_path,
    )
    assert "SAME True" in out, out
