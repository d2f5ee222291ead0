"""A determinism re-check round (a helper's round): outputs whose bytes must not depend on what a run should not
depend on. Each test here failed before its fix.

* ``mmusv study agreement A B`` and ``... B A`` (or :func:`~mmusv.studies.agreement.run_agreement_study` given the
  scenarios in another order) wrote ``agreement_samples.parquet`` with its rows in the order the scenarios were
  given, and ``agreement_summary.csv``'s per-map means summed the samples in that order, so their last digits moved
  with it (a shell glob, a list built from a folder's listing, or a hand-typed list gave other bytes for one set of
  scenarios). The samples are now in scenario-name order, as the detection study sorts its sequences and ``mmusv
  convert`` its recordings.
* ``mmusv study detection|robustness --model M`` promised "the tables and boxes are the same with any number" of
  ``--jobs``, but left ``--threads`` out it ran the models on torch's default threads (one per core) with
  ``--jobs 1`` and on one thread in each ``--jobs N`` process: a network's outputs depend on torch's thread count
  (the order of its float sums), so every score in ``detection_boxes.parquet`` differed between ``--jobs 1`` and
  ``--jobs 2`` (and between machines of other core counts). Left out, ``--threads`` is now 1 in every process.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from tiny_scenario import lidar_scenario

PYTHONPATH = str(Path(__file__).resolve().parents[1] / "python")


def _top_view_scenario(name: str, seed: int) -> dict[str, Any]:
    """The tests' tiny open-sea scenario with a small top view on its USV (what the agreement study evaluates)."""
    sc = lidar_scenario(name, frames=1, seed=seed)
    sc["rigs"]["r"] = {"top_view": {"resolution": [64, 64], "metres_per_pixel": 2.5, "quality": "draft"}}
    return sc


def test_the_agreement_study_writes_the_same_bytes_in_any_scenario_order(tmp_path: Path) -> None:
    from mmusv.config import load_scenario
    from mmusv.studies.agreement import run_agreement_study

    scenarios = [load_scenario(_top_view_scenario(n, s)) for n, s in (("zulu", 3), ("alpha", 4), ("mike", 5))]
    written, studies = [], []
    for i, order in enumerate((scenarios, [scenarios[1], scenarios[2], scenarios[0]])):
        study = run_agreement_study(order, frames=1)
        paths = study.write(tmp_path / str(i))
        written.append({k: p.read_bytes() for k, p in paths.items()})
        studies.append(study)
    # every scenario has samples, so the order is seen in the table: the scenarios' names in order
    assert studies[0].samples["scenario"].unique(maintain_order=True).to_list() == ["alpha", "mike", "zulu"]
    assert written[0] == written[1]


def _boosted_model(folder: Path) -> Path:
    """A ``single`` model of the ``tiny`` preset with seeded weights and its heatmap's bias raised, so that it finds
    boxes (many) on any cloud: the learned detector's scores are then in the study's boxes."""
    torch = pytest.importorskip("torch")
    from mmusv.learn.model import PillarNet
    from mmusv.learn.presets import preset

    torch.manual_seed(0)
    p = preset("tiny")
    net = PillarNet(p, "single")
    state = net.state_dict()
    state["head.branches.heatmap.3.bias"] += 4.0
    ck = {"preset": p.to_dict(), "mode": "single", "seed": 0, "epoch": 1, "epochs": 1, "stopped": None, "step": 1}
    (folder / "single").mkdir(parents=True)
    torch.save({**ck, "log": [], "data": None, "model": state}, folder / "single" / "model.pt")
    return folder


@pytest.mark.slow  # about 25 s on a loaded 2-core machine: a recording, two studies, spawned workers
def test_a_learned_model_s_study_is_the_same_bytes_with_any_jobs(tmp_path: Path) -> None:
    from mmusv.acquire import run

    models = _boosted_model(tmp_path / "models")
    sc = lidar_scenario("learned_jobs", frames=2)
    sc["vessels"][1]["route"] = [[0, 28], [60, 28]]  # within the tiny preset's 32 m grid
    rec = run(sc, out_dir=tmp_path / "rec").recording
    # torch's default threads: 2 however many cores this machine has, as on any machine of 2 cores or more
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONUNBUFFERED", "MKL_NUM_THREADS")}
    env.update(PYTHONPATH=PYTHONPATH, OMP_NUM_THREADS="2")
    boxes = []
    for jobs in ("1", "2"):
        out = tmp_path / f"jobs{jobs}"
        args = [str(rec), "--model", str(models), "--modes", "none", "--refine", "off", "--jobs", jobs]
        done = subprocess.run(
            [sys.executable, "-m", "mmusv.cli", "study", "detection", *args, "--no-progress", "-o", str(out)],
            env=env,
            capture_output=True,
            text=True,
            timeout=300,
            check=False,
        )
        assert done.returncode == 0, done.stderr
        boxes.append((out / "detection_boxes.parquet").read_bytes())
    import polars as pl

    assert pl.read_parquet(tmp_path / "jobs1" / "detection_boxes.parquet").filter(kind="det").height > 0
    assert boxes[0] == boxes[1]
