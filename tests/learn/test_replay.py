"""Training's ``--set`` on the command line, inference per mode and its merge, and the replay of the peaks
(:mod:`mmusv.learn.replay`) against the study's learned detector: the peaks of ``scripts/learn_train.py infer``
run one mode at a time and merged equal one run of every mode, and the predictions replayed from them, with and
without the second stage, equal what :class:`mmusv.learn.detector.LearnedDetector` gives on the same clouds (the
model's input: the cache's points)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import polars as pl
import pytest
import torch
import yaml
from mmusv.errors import InputError
from mmusv.learn.cache import Cache, build_cache
from mmusv.learn.detector import load_models
from mmusv.learn.example import MODES, early_cloud
from mmusv.learn.infer import infer_cache, merge_peaks
from mmusv.learn.presets import preset
from mmusv.learn.refine import RefineParams
from mmusv.learn.replay import write_predictions
from mmusv.learn.train import main as train_main
from mmusv.learn.train import train
from mmusv.studies.detection.sources import lidar_only

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "island_occlusion.yaml"


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Cache, Path]:
    """A 3-frame, 2-USV recording, its cache, and tiny models of every mode trained for a few steps (a low
    score threshold, so that every cloud has peaks to refine)."""
    from mmusv.acquire import run

    root = tmp_path_factory.mktemp("replay")
    data = lidar_only(yaml.safe_load(SCENARIO.read_text(encoding="utf-8")))
    data["vessels"] = [v for v in data["vessels"] if v["role"] != "usv" or v["id"] in ("usv_1", "usv_3")]
    data["name"] = "tiny_replay"
    data["acquisition"]["frames"] = 3
    rec = run(data, out_dir=root / "rec").recording
    cache = Cache(build_cache([rec], root / "cache.npz", split="all"))
    p = preset("tiny", x_range=(-48.0, 48.0), y_range=(-48.0, 48.0), score_threshold=0.02)
    for mode in MODES:
        train(cache, p=p, mode=mode, out=root / "models" / mode, epochs=1, max_steps=4, progress=False)
    return rec, cache, root


def test_per_mode_inference_merges_to_one_run(trained: tuple[Path, Cache, Path], tmp_path: Path) -> None:
    _, cache, root = trained
    models = root / "models"
    whole = np.load(infer_cache(cache, models=models, out=tmp_path / "all.npz"))
    parts = [infer_cache(cache, models=models, out=tmp_path / f"{m}.npz", modes=[m]) for m in MODES]
    assert set(np.load(parts[0]).files) == {"single_boxes", "single_scores", "single_offsets", "single_model"}
    merged = np.load(merge_peaks([*parts, tmp_path / "missing.npz"], tmp_path / "merged.npz"))
    assert sorted(merged.files) == sorted(whole.files)
    assert all(np.array_equal(merged[k], whole[k]) for k in whole.files)
    assert len(whole["single_scores"]) > 0
    with pytest.raises(InputError, match="in two of the peak files"):
        merge_peaks([parts[0], parts[0]], tmp_path / "twice.npz")
    with pytest.raises(InputError, match="allowed: single, early, intermediate"):
        infer_cache(cache, models=models, out=tmp_path / "bad.npz", modes=["late"])


def _rows(df: pl.DataFrame, key: tuple[str, int, str], mode: str) -> tuple[np.ndarray, np.ndarray]:
    sel = df.filter(
        (pl.col("sequence") == key[0])
        & (pl.col("frame") == key[1])
        & (pl.col("ego") == key[2])
        & (pl.col("mode") == mode)
        & (pl.col("kind") == "det")  # a row of kind frame says the frame is covered
    )
    return sel.select(["x", "y", "z", "l", "w", "h", "yaw"]).to_numpy(), sel["score"].to_numpy()


def _assert_replay_is_the_detector(df: pl.DataFrame, cache: Cache, det: Any, k: int) -> dict[str, Any]:
    """Sample ``k``'s rows of every mode in the replayed ``df`` equal ``det`` on the same clouds; returns what
    ``det`` gave, by mode."""
    key = cache.key(int(cache.arrays["sample_cloud"][k]))
    ego, nbs, _ = cache.sample(k)
    expect = {
        "none": det(ego),
        "early": det.early(early_cloud(ego, nbs)),
        "intermediate": det.intermediate(ego, nbs),
    }
    for mode, (b, s) in expect.items():
        got_b, got_s = _rows(df, key, mode)
        assert got_b.shape == b.shape, (key, mode)
        np.testing.assert_allclose(got_s, s, rtol=1e-6)
        np.testing.assert_allclose(got_b, _tied_order(got_b, b, s), atol=1e-3)
    return expect


def _tied_order(got: np.ndarray, boxes: np.ndarray, scores: np.ndarray) -> np.ndarray:
    """``boxes`` ``(M, 7)`` (in descending ``scores``) reordered to ``got``'s order within runs of tied scores.

    The replay decodes the peaks file's float32 boxes where the detector keeps float64, so two boxes whose scores
    tie to 10⁻⁶ (two mirror-image boxes a random scorer rates alike) may rank either way round: only within such a
    run may the order differ; every box elsewhere stays in its place."""
    out = np.array(boxes, dtype=np.float64, copy=True)
    i = 0
    while i < len(scores):
        j = i + 1
        while j < len(scores) and np.isclose(scores[j], scores[i], rtol=1e-6, atol=0.0):
            j += 1
        if j - i > 1:
            d = np.abs(got[i:j, None, :] - boxes[None, i:j, :]).max(axis=2)
            pick = d.argmin(axis=1)
            if len(set(pick.tolist())) == j - i:  # a one-to-one match; otherwise left as is (and the check fails)
                out[i:j] = boxes[i:j][pick]
        i = j
    return out


@pytest.mark.parametrize("refine", [False, True])
def test_replay_equals_the_detector_on_the_same_clouds(
    trained: tuple[Path, Cache, Path], tmp_path: Path, refine: bool
) -> None:
    rec, cache, root = trained
    peaks = infer_cache(cache, models=root / "models", out=tmp_path / "peaks.npz")
    out = write_predictions(
        peaks,
        cache,
        inputs=[rec],
        out=tmp_path / "pred.parquet",
        split="all",
        refine=RefineParams() if refine else None,
    )
    df = pl.read_parquet(out)
    assert set(df["mode"].unique().to_list()) == {"none", "late", "early", "intermediate"}
    det = load_models(root / "models", refine=refine)
    moved = 0
    for k in range(len(cache)):
        expect = _assert_replay_is_the_detector(df, cache, det, k)
        if refine:  # the second stage changed boxes: the network's own differ
            ego, _, _ = cache.sample(k)
            net_b, _ = load_models(root / "models", refine=False)(ego)
            moved += int(net_b.shape != expect["none"][0].shape or not np.allclose(net_b, expect["none"][0]))
    assert len(cache) > 0
    if refine:
        assert moved > 0


def test_replay_rejects_an_unknown_late_merge(trained: tuple[Path, Cache, Path], tmp_path: Path) -> None:
    rec, cache, root = trained
    peaks = infer_cache(cache, models=root / "models", out=tmp_path / "peaks.npz", modes=["single"])
    with pytest.raises(InputError, match=r"^late_merge = 'mean': allowed: nms, wbf"):
        write_predictions(peaks, cache, inputs=[rec], out=tmp_path / "p.parquet", split="all", late_merge="mean")
    out = write_predictions(peaks, cache, inputs=[rec], out=tmp_path / "p.parquet", split="all", late_merge="wbf")
    assert set(pl.read_parquet(out)["mode"].unique().to_list()) == {"none", "late"}


def test_train_command_line_applies_set(trained: tuple[Path, Cache, Path], tmp_path: Path) -> None:
    _, _, root = trained
    args = ["--cache", str(root / "cache.npz"), "--preset", "tiny", "--modes", "single", "-o", str(tmp_path)]
    args += ["--max-steps", "1", "--no-progress", "--threads", "1"]
    assert train_main([*args, "--set", "min_points=1", "--set", "code_weights=[1,1,0.1,1,1,1,1,1]"]) == 0
    ck = torch.load(tmp_path / "single" / "model.pt", weights_only=True)
    assert ck["preset"]["min_points"] == 1 and ck["preset"]["code_weights"][2] == 0.1
    assert ck["preset"]["pillar_m"] == preset("tiny").pillar_m
    with pytest.raises(InputError, match="--set 'min_point=1'"):
        train_main([*args, "--set", "min_point=1"])


def test_replay_with_scorers_equals_the_rescoring_detector(trained: tuple[Path, Cache, Path], tmp_path: Path) -> None:
    """The IoU scorers (here seeded random ones, β = ½, beside a copy of each model) rescore the replay as they
    rescore the detector: the same boxes and scores, and scores other than the network's."""
    import shutil

    from mmusv.learn.scorer import FEATURES, SCORER_FILE, IoUScorer, load_scorer

    rec, cache, root = trained
    models = tmp_path / "models"
    shutil.copytree(root / "models", models)
    torch.manual_seed(7)
    for mode in MODES:
        n = len(FEATURES)
        IoUScorer(np.zeros(n), np.ones(n), beta=0.5).save(models / mode / SCORER_FILE, {"test": True})
    peaks = infer_cache(cache, models=models, out=tmp_path / "peaks.npz")
    scorers = {m: load_scorer(models / m / SCORER_FILE) for m in MODES}
    out = write_predictions(
        peaks, cache, inputs=[rec], out=tmp_path / "pred.parquet", split="all", refine=RefineParams(), scorers=scorers
    )
    df = pl.read_parquet(out)
    det = load_models(models, refine=True)  # rescored: the scorers are found beside the models
    plain = load_models(models, refine=True, rescore=False)
    assert sorted(det.scorers) == sorted(MODES) and not plain.scorers
    changed = 0
    for k in range(len(cache)):
        expect = _assert_replay_is_the_detector(df, cache, det, k)
        ego, _, _ = cache.sample(k)
        _, s0 = plain(ego)
        changed += int(s0.shape != expect["none"][1].shape or not np.allclose(np.sort(s0), np.sort(expect["none"][1])))
    assert changed > 0
    with pytest.raises(InputError, match=r"^rescore = True: single has no"):
        load_models(root / "models", refine=True, rescore=True)


def test_mmusv_train_scorers_only_fits_every_model(trained: tuple[Path, Cache, Path], tmp_path: Path) -> None:
    """``mmusv train --scorers-only``'s fit (the model's own input per mode: the ego cloud, the aggregate, the ego
    and its neighbours) writes a scorer beside each model that the detector then loads."""
    import shutil

    from mmusv.learn.scorer import SCORER_FILE
    from mmusv.learn.scorer_fit import fit_scorers

    _, cache, root = trained
    out = tmp_path / "out"
    shutil.copytree(root / "models", out)
    done = fit_scorers(out, cache.path, list(MODES), seed=0, threads=1)
    fitted = [m for m in MODES if "beta" in done[m]]
    assert fitted, done  # the tiny models find boxes at their low threshold
    for m in MODES:
        assert (out / m / SCORER_FILE).is_file() == (m in fitted)
        if m in fitted:
            assert done[m]["boxes"] >= 20 and done[m]["frames"] == len(cache)
    det = load_models(out, refine=True)
    assert sorted(det.scorers) == sorted(fitted)


def test_the_study_scores_the_models_on_the_threads_asked(
    trained: tuple[Path, Cache, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``mmusv study detection --model DIR --threads 1``: the four modes scored beside the baseline, with torch on
    one thread; ``--threads`` below 1 is refused by name."""
    from mmusv.cli import main

    rec, _, root = trained
    before = torch.get_num_threads()
    try:
        argv = ["study", "detection", str(rec), "--split", "all", "--model", str(root / "models"), "--no-progress"]
        assert main([*argv, "--threads", "1", "-o", str(tmp_path / "t3")]) == 0
        assert torch.get_num_threads() == 1
        out = capsys.readouterr().out
        assert "learned models:" in out and "intermediate" in out
        table = pl.read_csv(tmp_path / "t3" / "detection_table.csv")
        assert sorted(table["mode"].to_list()) == ["early", "intermediate", "late", "none"]
        assert (tmp_path / "t3" / "baseline" / "detection_table.csv").is_file()
        # The same study in a worker process (--jobs): its own models, one torch thread, the same bytes.
        assert main([*argv, "--threads", "1", "--jobs", "2", "-o", str(tmp_path / "j2")]) == 0
        shared = [line for line in out.splitlines() if "shared per ego-frame" in line]
        assert shared and shared == [ln for ln in capsys.readouterr().out.splitlines() if "shared per ego-frame" in ln]
        for sub in ("", "baseline/"):
            for name in ("detection_table.csv", "detection_boxes.parquet"):
                assert (tmp_path / "t3" / sub / name).read_bytes() == (tmp_path / "j2" / sub / name).read_bytes()
        assert main([*argv, "--threads", "0", "-o", str(tmp_path / "bad")]) == 2
        assert "--threads 0: must be >= 1" in capsys.readouterr().err
    finally:
        torch.set_num_threads(before)


def test_replay_refuses_the_scorers_of_other_weights(trained: tuple[Path, Cache, Path], tmp_path: Path) -> None:
    """A scorer fitted for other weights than the model whose peaks are replayed is refused, naming the model and
    ``--scorers``: the predictions were written rescored by it without a word (the peaks recorded no model). The
    scorer of the peaks' own weights is taken; peaks written before the digest are refused with scorers only."""
    import shutil

    from mmusv.learn.checkpoint import weights_digest
    from mmusv.learn.replay import main as replay_main
    from mmusv.learn.scorer import FEATURES, SCORER_FILE, IoUScorer, load_scorer

    rec, cache, root = trained
    models = tmp_path / "models"
    shutil.copytree(root / "models", models)
    peaks = infer_cache(cache, models=models, out=tmp_path / "peaks.npz", modes=["single"])
    with np.load(peaks) as f:
        held = {k: f[k] for k in f.files}
    net = load_models(models).models["single"]
    assert str(held["single_model"]) == weights_digest(net.state_dict())
    other = {k: v + 1.0 if v.is_floating_point() else v for k, v in net.state_dict().items()}
    n = len(FEATURES)
    torch.manual_seed(3)
    IoUScorer(np.zeros(n), np.ones(n)).save(models / "single" / SCORER_FILE, {"model": weights_digest(other)})
    stale = {"single": load_scorer(models / "single" / SCORER_FILE)}
    kw: dict[str, Any] = {"inputs": [rec], "split": "all", "refine": RefineParams()}
    with pytest.raises(InputError, match=r"^scorers: the single scorer was fitted for other weights than the single"):
        write_predictions(peaks, cache, out=tmp_path / "a.parquet", scorers=stale, **kw)
    assert not (tmp_path / "a.parquet").exists()
    argv = [str(peaks), str(cache.path), str(rec), "--split", "all", "--refine", "--scorers", str(models)]
    with pytest.raises(InputError, match=r"^--scorers: the single scorer was fitted for other weights"):
        replay_main([*argv, "-o", str(tmp_path / "b.parquet")])
    IoUScorer(np.zeros(n), np.ones(n)).save(models / "single" / SCORER_FILE, {"model": str(held["single_model"])})
    own = {"single": load_scorer(models / "single" / SCORER_FILE)}
    assert write_predictions(peaks, cache, out=tmp_path / "c.parquet", scorers=own, **kw).is_file()
    old = tmp_path / "old.npz"
    np.savez(old, **{k: v for k, v in held.items() if k != "single_model"})
    with pytest.raises(InputError, match=r"records no digest of its single model"):
        write_predictions(old, cache, out=tmp_path / "d.parquet", scorers=own, **kw)
    assert write_predictions(old, cache, out=tmp_path / "e.parquet", **kw).is_file()  # no scorers: nothing to match
