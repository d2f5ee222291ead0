"""The learned detector as a perception researcher meets it, a second round (``mmusv train``, ``model.pt`` files
passed around, ``scripts/learn_train.py infer``, ``python -m mmusv.learn.replay``), on the tiny preset and 3-frame
recordings.

Each test failed before its fix: a ``model.pt`` without ``epoch`` (or with a preset of another version, or the
model of another mode in a mode's folder) was a ``KeyError`` traceback, a ``TypeError`` of ``Preset.__init__`` or
served the wrong fusion modes; a training whose loss became NaN went on and saved NaN weights as a finished model,
and such a model loaded without a word; a ``last.pt`` of another run was refused without saying what differed; two
runs of the same seed wrote ``model.pt`` and ``scorer.pt`` files of different bytes (the wall-clock time, and the
temporary file's name, with the process id, inside the archive); a recording without LiDAR was "no frame to
cache" (or left out of the cache without a word); a NaN in a cache's ground truth was a ``ValueError`` traceback;
``infer`` without a model wrote an empty peaks file, and ``-o peaks`` wrote ``peaks.npz``; ``replay`` of peaks of
another cache was an ``IndexError`` traceback, and of recordings the cache does not hold an empty predictions file;
the commands' input errors were tracebacks; a NaN point warned at every cloud.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import mmusv
import numpy as np
import polars as pl
import pytest
import torch
import yaml
from mmusv.errors import InputError
from mmusv.learn.cache import Cache, build_cache
from mmusv.learn.detector import load_models
from mmusv.learn.infer import _model, infer_cache, merge_peaks
from mmusv.learn.pillars import pillarize
from mmusv.learn.presets import preset
from mmusv.learn.replay import write_predictions
from mmusv.learn.scorer_fit import fit_scorers
from mmusv.learn.train import train
from mmusv.studies.detection.sources import lidar_only

from learn.scenes import SCENES, MemorySource

ROOT = Path(__file__).resolve().parents[2]
PYTHON = Path(mmusv.__file__).resolve().parents[1]
"""The folder of the mmusv package under test (the commands are run on it)."""


def _record(name: str, out: Path, *, lidar: bool = True) -> Path:
    from mmusv.acquire import run

    data = lidar_only(yaml.safe_load((ROOT / "scenarios" / "island_occlusion.yaml").read_text(encoding="utf-8")))
    if not lidar:
        data["rigs"] = {"usv_standard": {"preset": "lidar_only", "lidar": None}}
    data["vessels"] = [v for v in data["vessels"] if v["role"] != "usv" or v["id"] in ("usv_1", "usv_3")]
    data["name"] = name
    data["acquisition"]["frames"] = 3
    rec: Path = run(data, out_dir=out / name).recording
    return rec


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 3-frame, 2-USV LiDAR-only recording."""
    return _record("lr_island", tmp_path_factory.mktemp("learn_round"))


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A tiny single-agent model.pt trained one epoch on synthetic scenes."""
    out = tmp_path_factory.mktemp("lr_model") / "single"
    train(MemorySource(SCENES), p=preset("tiny"), mode="single", out=out, epochs=1, progress=False)
    return out / "model.pt"


def _variant(model: Path, folder: Path, change: Any) -> Path:
    ck = torch.load(model, weights_only=True)
    ck = {**ck, "preset": dict(ck["preset"])}
    change(ck)
    folder.mkdir(parents=True)
    torch.save(ck, folder / "model.pt")
    return folder / "model.pt"


@pytest.mark.parametrize(
    ("name", "change", "said"),
    [
        ("no_epoch", lambda ck: ck.pop("epoch"), r"\(epoch: None; a count, 0 or more\)"),
        ("epoch_text", lambda ck: ck.update(epoch="x"), r"\(epoch: 'x'; a count"),
        ("no_step", lambda ck: ck.pop("step"), r"\(step: None; a count"),
        (
            "newer_preset",
            lambda ck: ck["preset"].update(anchor_sizes=[1, 2]),
            r"\(preset: unknown field\(s\) anchor_sizes: written by another version of mmusv",
        ),
        ("no_preset_name", lambda ck: ck["preset"].pop("name"), r"\(preset: missing field\(s\) name: written by"),
        ("mode", lambda ck: ck.update(mode="fancy"), r"\(mode: 'fancy'; allowed: single, early, intermediate\)"),
    ],
)
def test_a_model_pt_of_another_version_is_one_error_naming_the_field(
    model: Path, tmp_path: Path, name: str, change: Any, said: str
) -> None:
    # no epoch / step: a KeyError traceback in the study; a preset of a newer version: "TypeError: Preset.__init__()
    # got an unexpected keyword argument"; an unknown mode: an error that did not name the file
    bad = _variant(model, tmp_path / name / "single", change)
    for path in (bad, bad.parent.parent):
        with pytest.raises(InputError, match=rf"^path = '{bad}': not an mmusv\.learn model\.pt {said}"):
            load_models(path)
    with pytest.raises(InputError, match=said):
        _model(bad, torch.device("cpu"))


def test_a_model_in_the_folder_of_another_mode_is_refused(model: Path, tmp_path: Path) -> None:
    # OUT/single/model.pt holding the early model served no and late fusion without a word
    bad = _variant(model, tmp_path / "out" / "single", lambda ck: ck.update(mode="early"))
    with pytest.raises(InputError, match=r"\(mode: it holds the early model, where the single model belongs"):
        load_models(tmp_path / "out")
    with pytest.raises(InputError, match=r"holds the early model"):
        _model(bad, torch.device("cpu"))
    assert set(load_models(bad).models) == {"early"}  # the file alone says which model it is


def test_a_diverged_training_stops_and_nan_weights_are_refused(model: Path, tmp_path: Path) -> None:
    # lr 1e9: the loss became NaN in the second epoch, the run went on and said "finished" with NaN weights
    with pytest.raises(InputError, match=r"single: the training diverged: the loss is nan.* at step \d+ \(epoch 2"):
        train(
            MemorySource(SCENES), p=preset("tiny", lr=1e9), mode="single", out=tmp_path / "d", epochs=3, progress=False
        )
    ck = torch.load(tmp_path / "d" / "model.pt", weights_only=True)
    assert ck["epoch"] == 1  # the last epoch saved before it
    # a model.pt whose weights are NaN (a diverged run of before) found nothing, without a word
    bad = _variant(
        model,
        tmp_path / "nan" / "single",
        lambda ck: ck.update(
            model={k: v * float("nan") if v.is_floating_point() else v for k, v in ck["model"].items()}
        ),
    )
    with pytest.raises(
        InputError, match=r"\(model: weights that are not finite \(NaN or inf\) in encoder\.linear\.weight"
    ):
        load_models(bad)


@pytest.mark.parametrize(
    ("kwargs", "said"),
    [
        ({"p": preset("paper")}, "preset 'tiny', this run 'paper'"),
        ({"p": preset("tiny", lr=1e-3)}, "preset tiny with other lr"),
        ({"seed": 3}, "seed 0, this run 3"),
        ({"mode": "early"}, "mode 'single', this run 'early'"),
    ],
)
def test_a_resume_refusal_names_what_differs(model: Path, tmp_path: Path, kwargs: dict[str, Any], said: str) -> None:
    import shutil

    shutil.copytree(model.parent, tmp_path / "m")
    args: dict[str, Any] = {"p": preset("tiny"), "mode": "single", **kwargs}
    with pytest.raises(InputError, match=rf"last\.pt: a checkpoint of another run \({said}\); use another -o"):
        train(MemorySource(SCENES), out=tmp_path / "m", epochs=2, progress=False, **args)


def test_the_same_seed_writes_the_same_model_bytes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # two runs: the archive inside model.pt was named after the temporary file (its name holds the process id), and
    # model.pt held the run's wall-clock seconds
    files = []
    for run, pid in (("a", 1111), ("b", 2222)):
        monkeypatch.setattr(os, "getpid", lambda pid=pid: pid)
        train(MemorySource(SCENES), p=preset("tiny"), mode="single", out=tmp_path / run, epochs=2, progress=False)
        files.append((tmp_path / run / "model.pt").read_bytes())
    assert files[0] == files[1]


def test_the_same_seed_writes_the_same_scorer_bytes(
    recording: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # scorer.pt held the fit's wall-clock seconds (the summary keeps them)
    import shutil

    cache = build_cache([recording], tmp_path / "cache_all.npz", split="all")
    p = preset("tiny", x_range=(-48.0, 48.0), y_range=(-48.0, 48.0), score_threshold=0.02)
    train(Cache(cache), p=p, mode="single", out=tmp_path / "a" / "single", epochs=1, max_steps=2, progress=False)
    shutil.copytree(tmp_path / "a", tmp_path / "b")
    fits = []
    for run, tick in (("a", 3.0), ("b", 11.0)):  # a clock that runs at another pace in each fit
        clock = iter(np.arange(0.0, 1e6, tick))
        monkeypatch.setattr(time, "perf_counter", lambda clock=clock: float(next(clock)))
        fits.append(fit_scorers(tmp_path / run, cache, ["single"], seed=0)["single"])
        monkeypatch.undo()
    assert "boxes" in fits[0] and fits[0]["seconds"] != fits[1]["seconds"]  # a scorer was fitted, at other times
    assert (tmp_path / "a" / "single" / "scorer.pt").read_bytes() == (
        tmp_path / "b" / "single" / "scorer.pt"
    ).read_bytes()


def test_a_recording_without_lidar_is_named(recording: Path, tmp_path: Path) -> None:
    from mmusv.scenario_checks import MmusvWarning

    with pytest.warns(MmusvWarning, match="rigs.usv_standard switches every sensor off"):
        blind = _record("lr_blind", tmp_path, lidar=False)
    # alone: "split 'all' of [...]: no frame to cache"; beside a recording with LiDAR: left out without a word
    for inputs in ([blind], [blind, recording]):
        with pytest.raises(InputError, match=r"sequence lr_blind: no LiDAR: none of its instrumented USVs carries one"):
            build_cache(inputs, tmp_path / "cache.npz", split="all")
        assert not (tmp_path / "cache.npz").exists()


def test_a_damaged_cache_is_named_by_its_array(recording: Path, tmp_path: Path) -> None:
    good = dict(np.load(build_cache([recording], tmp_path / "good.npz", split="all")))

    def damaged(name: str, **arrays: np.ndarray) -> Path:
        np.savez_compressed(tmp_path / name, **{**good, **arrays})
        return tmp_path / name

    gt = good["gt"].copy()
    gt[1, 0] = np.nan
    # a NaN box: "ValueError: cannot convert float NaN to integer" in training
    said = r"^cache = '.*nan\.npz': gt: 1 row\(s\) with values that are not finite .* first row 1"  # train's cache
    with pytest.raises(InputError, match=said):
        train(damaged("nan.npz", gt=gt), p=preset("tiny"), mode="single", out=tmp_path / "m", epochs=1, progress=False)
    offsets = good["cloud_offsets"].copy()
    offsets[-1] += 10
    with pytest.raises(InputError, match=r"cloud_offsets: not a rising run from 0 to"):
        Cache(damaged("offsets.npz", cloud_offsets=offsets))
    assert not (tmp_path / "m" / "model.pt").exists()


@pytest.fixture(scope="module")
def peaks_setup(recording: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Cache, Path]:
    """The recording's cache and a tiny single-agent model under ``models/single`` (a low score threshold)."""
    root = tmp_path_factory.mktemp("lr_peaks")
    cache = Cache(build_cache([recording], root / "cache_all.npz", split="all"))
    p = preset("tiny", x_range=(-48.0, 48.0), y_range=(-48.0, 48.0), score_threshold=0.02)
    train(cache, p=p, mode="single", out=root / "models" / "single", epochs=1, max_steps=2, progress=False)
    return root, cache, recording


def test_infer_without_a_model_is_refused_and_writes_the_name_given(
    peaks_setup: tuple[Path, Cache, Path], tmp_path: Path
) -> None:
    root, cache, _ = peaks_setup
    # a folder without a model: an empty peaks file, exit status 0
    with pytest.raises(InputError, match=r"^models = '.*nowhere': no single\|early\|intermediate/model\.pt there"):
        infer_cache(cache, models=tmp_path / "nowhere", out=tmp_path / "empty.npz")
    assert not (tmp_path / "empty.npz").exists()
    with pytest.raises(InputError, match=r"^models = '.*': no early/model\.pt there"):
        infer_cache(cache, models=root / "models", out=tmp_path / "early.npz", modes=["early"])
    # -o peaks wrote peaks.npz, and returned the name of a file that was not there
    out = infer_cache(cache, models=root / "models", out=tmp_path / "peaks")
    assert out == tmp_path / "peaks" and out.is_file() and not (tmp_path / "peaks.npz").exists()
    assert sorted(np.load(out).files) == ["single_boxes", "single_model", "single_offsets", "single_scores"]
    # a merge of parts none of which is there: an empty peaks file
    with pytest.raises(InputError, match=r"missing\.npz: none of the peak files is there"):
        merge_peaks([tmp_path / "missing.npz"], tmp_path / "merged.npz")
    assert not (tmp_path / "merged.npz").exists()


def test_replay_refuses_peaks_and_caches_that_do_not_fit(peaks_setup: tuple[Path, Cache, Path], tmp_path: Path) -> None:
    root, cache, recording = peaks_setup
    whole = infer_cache(cache, models=root / "models", out=tmp_path / "whole.npz")
    ok = write_predictions(whole, cache, inputs=[recording], out=tmp_path / "ok.parquet", split="all")
    assert pl.read_parquet(ok).height > 0
    # the peaks of an --limit run (or of another cache): an IndexError traceback
    short = infer_cache(cache, models=root / "models", out=tmp_path / "short.npz", limit=2)
    with pytest.raises(InputError, match=r"short\.npz: single_offsets: peaks of 2 items, where the cache .* 6 clouds"):
        write_predictions(short, cache, inputs=[recording], out=tmp_path / "short.parquet", split="all")
    # recordings the cache does not hold: a predictions file without a row
    other = _record("lr_other", tmp_path)
    said = (  # write_predictions' own arguments, not the replay command's flags
        r"^cache = '.*cache_all\.npz': holds no sequence lr_other of split 'all'.* it was built with split = 'all', "
        r"ratios = \[0\.7, 0\.15, 0\.15\], seed = 0\); give the inputs, split, ratios and seed"
    )
    with pytest.raises(InputError, match=said):
        write_predictions(whole, cache, inputs=[other], out=tmp_path / "other.parquet", split="all")
    assert not (tmp_path / "short.parquet").exists() and not (tmp_path / "other.parquet").exists()


def test_the_commands_say_an_input_error_in_one_line(peaks_setup: tuple[Path, Cache, Path], tmp_path: Path) -> None:
    root, _, recording = peaks_setup
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(PYTHON), os.environ.get("PYTHONPATH", "")])}
    runs = [
        (
            [sys.executable, "-m", "mmusv.learn.replay", "p.npz", str(root / "cache_all.npz"), str(recording)],
            ["--scorers", str(root / "models"), "-o", str(tmp_path / "x.parquet")],
            "mmusv: error: --scorers needs --refine",
        ),
        (
            [
                sys.executable,
                str(PYTHON.parent / "scripts" / "learn_train.py"),
                "infer",
                "--cache",
                str(root / "cache_all.npz"),
            ],
            ["--models", str(tmp_path / "nowhere"), "-o", str(tmp_path / "p.npz")],
            "mmusv: error: --models",
        ),
    ]
    for argv, extra, said in runs:
        r = subprocess.run([*argv, *extra], capture_output=True, text=True, env=env, timeout=120, check=False)
        assert r.returncode == 2, r.stderr
        assert r.stderr.startswith(said) and "Traceback" not in r.stderr and r.stderr.count("\n") == 1, r.stderr


def test_points_that_are_not_finite_are_dropped_without_a_warning() -> None:
    p = preset("tiny")
    pts = np.array(
        [[1, 2, 0, 0.5], [np.nan, 1, 1, 0.5], [1e30, 0, 0, 0.5], [1, 1, np.inf, 0.5], [2, 2, 0, np.nan]],
        dtype=np.float32,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # "invalid value encountered in cast", at every cloud of the study
        pl_ = pillarize(pts, p)
    assert pl_.mask.sum() == 1 and pl_.coords.tolist() == [[34, 33]]
