"""Defects of the learned detector's tools an earlier user round reported and left open, each test failing before
its fix: the predictions of a model that found nothing (a replay without a detection) were refused by the study as
"the file holds setting none", though ``--model`` scores such a model as AP 0; ``python -m mmusv.learn.replay``
had no ``--split-ratios``, so a cache built with other ratios could not be replayed; a training killed while it
saved left its ``.model.pt.PID.tmp`` in the output folder for good, and a save that failed left its temporary."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import polars as pl
import pytest
import torch
import yaml
from mmusv.cli import main as mmusv_main
from mmusv.errors import InputError, MmusvError
from mmusv.learn.cache import Cache, build_cache
from mmusv.learn.presets import preset
from mmusv.learn.replay import main as replay_main
from mmusv.learn.replay import write_predictions
from mmusv.learn.scorer import FEATURES, IoUScorer
from mmusv.learn.train import train
from mmusv.studies.detection.sources import lidar_only

from learn.scenes import SCENES, MemorySource

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 3-frame, 2-USV LiDAR-only recording of the island scenario."""
    from mmusv.acquire import run

    data = lidar_only(yaml.safe_load((ROOT / "scenarios" / "island_occlusion.yaml").read_text(encoding="utf-8")))
    data["vessels"] = [v for v in data["vessels"] if v["role"] != "usv" or v["id"] in ("usv_1", "usv_3")]
    data["name"] = "left_learn"
    data["acquisition"]["frames"] = 3
    rec: Path = run(data, out_dir=tmp_path_factory.mktemp("left_learn") / "rec").recording
    return rec


def _no_peaks(cache: Cache, path: Path) -> Path:
    """The peaks file (``mmusv.learn.infer``'s layout) of models of every mode that found nothing in ``cache``."""
    n_clouds = len(cache.arrays["cloud_offsets"]) - 1
    arrays: dict[str, np.ndarray] = {}
    for mode, n in (("single", n_clouds), ("early", len(cache)), ("intermediate", len(cache))):
        arrays[f"{mode}_offsets"] = np.zeros(n + 1, dtype=np.int64)
        arrays[f"{mode}_boxes"] = np.zeros((0, 7), dtype=np.float32)
        arrays[f"{mode}_scores"] = np.zeros(0, dtype=np.float32)
    np.savez(path, **arrays)
    return path


def _study(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    code = mmusv_main([*argv, "--no-progress"])
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err, out + err
    return code, err.replace("\n", " ")


# ------------------------------------------------------------------------------------------------ item 1


def test_the_predictions_of_a_model_that_found_nothing_score_as_ap_0(
    recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A replay without a detection wrote a file without a row, which the study refused with "the file holds
    setting none" (as if a setting named none were held), so such a model could not be scored through
    --predictions. The replay now writes a row of kind frame for every (sequence, frame, ego, mode) it covers: the
    study scores every mode as AP 0, with the ground truth counted, and still refuses a setting the file does not
    cover."""
    cache = Cache(build_cache([recording], tmp_path / "cache.npz", split="all"))
    peaks = _no_peaks(cache, tmp_path / "peaks.npz")
    pred = write_predictions(peaks, cache, inputs=[recording], out=tmp_path / "p.parquet", split="all")
    df = pl.read_parquet(pred)
    assert df.filter(pl.col("kind") == "det").height == 0
    frames = df.filter(pl.col("kind") == "frame")
    assert frames.height == 4 * 3 * 2  # 4 modes x 3 frames x 2 egos, each said once
    modes = ["--modes", "none,late,early,intermediate"]
    code, err = _study(
        ["study", "detection", str(recording), "--split", "all", "--predictions", str(pred), *modes, "-o",
         str(tmp_path / "det")],
        capsys,
    )  # fmt: skip
    assert code == 0, err
    table = pl.read_csv(tmp_path / "det" / "detection_table.csv")
    assert sorted(table["mode"].to_list()) == ["early", "intermediate", "late", "none"]
    assert table["ap50"].to_list() == [0.0] * 4 and table["det"].to_list() == [0] * 4
    assert min(table["gt"].to_list()) > 0 and table["ego_frames"].to_list() == [6] * 4
    # a setting the file does not cover is refused, naming what it covers
    code, err = _study(
        ["study", "robustness", str(recording), "--split", "all", "--settings", "delay:1", "--predictions", str(pred),
         "--modes", "late", "-o", str(tmp_path / "rob")],
        capsys,
    )  # fmt: skip
    assert code == 2, err
    assert "no row of setting delay:1 (modes late)" in err and "covers setting clean (modes " in err, err
    assert "setting none" not in err, err


def test_a_file_that_covers_nothing_is_refused_in_words_that_say_so(
    recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A file without a row (a replay of the old layout, or another tool's) is still refused, since it does not say
    which frames it covers; the message said "the file holds setting none"."""
    empty = tmp_path / "empty.parquet"
    cols = ["sequence", "frame", "ego", "mode", "x", "y", "z", "l", "w", "h", "yaw", "score"]
    schema = {c: pl.Utf8 if c in ("sequence", "ego", "mode") else pl.Float64 for c in cols}
    pl.DataFrame({c: [] for c in cols}, schema=schema).write_parquet(empty)
    code, err = _study(
        ["study", "detection", str(recording), "--split", "all", "--predictions", str(empty), "-o",
         str(tmp_path / "o")],
        capsys,
    )  # fmt: skip
    assert code == 2, err
    assert f"--predictions {empty}: no row of setting clean (modes none, late, early)" in err, err
    assert "holds no detection and covers no frame" in err and "setting none" not in err, err


# ------------------------------------------------------------------------------------------------ item 2


def test_replay_takes_the_split_ratios_the_cache_was_built_with(recording: Path, tmp_path: Path) -> None:
    """``python -m mmusv.learn.replay`` always split with 0.7/0.15/0.15: a cache of the test split made with other
    ratios was refused, and the command had no option to say them. ``--split-ratios`` now means what it means to
    ``mmusv train`` and ``mmusv study`` (same default and checks)."""
    cache = Cache(build_cache([recording], tmp_path / "cache_test.npz", split="test", ratios=(0, 0, 1)))
    peaks = _no_peaks(cache, tmp_path / "peaks.npz")
    args = [str(peaks), str(cache.path), str(recording), "--split", "test"]
    out = tmp_path / "p.parquet"
    assert replay_main([*args, "--split-ratios", "0,0,1", "-o", str(out)]) == 0
    assert pl.read_parquet(out).filter(pl.col("kind") == "frame").height > 0
    # the default ratios put the one recording in train: refused, saying how the cache was built
    with pytest.raises(InputError, match=r"--split-ratios 0,0,1 --seed 0"):
        replay_main([*args, "-o", str(tmp_path / "default.parquet")])
    with pytest.raises(MmusvError, match=r"^--split-ratios 1,2: expected three fractions"):
        replay_main([*args, "--split-ratios", "1,2", "-o", str(tmp_path / "bad.parquet")])
    with pytest.raises(MmusvError, match=r"^--split-ratios 0,0,0: .*not all zero"):
        replay_main([*args, "--split-ratios", "0,0,0", "-o", str(tmp_path / "bad.parquet")])
    assert not (tmp_path / "default.parquet").exists() and not (tmp_path / "bad.parquet").exists()


# ------------------------------------------------------------------------------------------------ item 5


def _dead_pid() -> int:
    """The process id of a process that has ended."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_a_training_removes_the_temporaries_of_a_save_that_was_killed(tmp_path: Path) -> None:
    """A process killed while saving left ``.model.pt.PID.tmp`` (and ``.last.pt.PID.tmp``) in the output folder
    for good. A training into the folder now removes those of processes that are gone, and nothing else: not a
    file of another name, nor the temporary of a process still running."""
    out = tmp_path / "single"
    out.mkdir()
    dead = _dead_pid()
    stale = [out / f".{name}.{dead}.tmp" for name in ("model.pt", "last.pt", "scorer.pt")]
    kept = [
        out / ".model.pt.notes.tmp",
        out / "model.pt.123.tmp",
        out / f".model.pt.{dead}.tmp.bak",
        out / f".other.pt.{dead}.tmp",
        out / ".model.pt.1.tmp",  # process 1 (init) runs
    ]
    for f in stale + kept:
        f.write_bytes(b"half a checkpoint")
    train(MemorySource(SCENES), p=preset("tiny"), mode="single", out=out, epochs=1, max_steps=1, progress=False)
    assert (out / "model.pt").is_file() and (out / "last.pt").is_file()
    assert not any(f.exists() for f in stale), sorted(p.name for p in out.iterdir())
    assert all(f.read_bytes() == b"half a checkpoint" for f in kept)
    left = sorted(p.name for p in out.iterdir() if p.name.endswith(".tmp"))
    assert left == sorted(f.name for f in kept if f.name.endswith(".tmp")), left


def test_a_save_that_fails_leaves_no_temporary(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A save that failed (a full disk, a Ctrl-C) left its temporary file: ``.model.pt.PID.tmp`` of a training,
    ``scorer.pt.part`` of a scorer. Now it is removed, and a previous file is left as it was."""
    out = tmp_path / "single"
    train(MemorySource(SCENES), p=preset("tiny"), mode="single", out=out, epochs=1, max_steps=1, progress=False)
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    def full(obj: object, fh: object, *args: object, **kwargs: object) -> None:
        fh.write(b"PK\x03\x04 half")  # type: ignore[attr-defined]
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(torch, "save", full)
    with pytest.raises(OSError, match="No space left"):
        train(MemorySource(SCENES), p=preset("tiny"), mode="single", out=out, epochs=1, max_steps=2, progress=False)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    n = len(FEATURES)
    with pytest.raises(OSError, match="No space left"):
        IoUScorer(np.zeros(n), np.ones(n), beta=0.5).save(out / "scorer.pt", {"test": True})
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_cut_short_peaks_and_a_missing_model_are_named_as_their_user_gives_them(
    recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The peaks of an inference cut short (``limit``) and a scorer fit without a model named the commands' flags,
    ``--limit`` and ``--scorers-only``, to a Python caller of write_predictions and fit_scorers; now their
    arguments (infer_cache's limit, out = '...') from Python and the flags from the commands."""
    from mmusv.learn.scorer_fit import fit_scorers

    cache = Cache(build_cache([recording], tmp_path / "cache_train.npz", split="all"))
    peaks = _no_peaks(cache, tmp_path / "peaks.npz")
    with np.load(peaks) as z:
        short = {k: (v[:2] if k.endswith("_offsets") else v) for k, v in z.items()}  # as infer --limit 1 writes
    np.savez(peaks, **short)
    with pytest.raises(InputError, match=r"an inference of its first items only \(mmusv\.learn\.infer\.infer_cache's "):
        write_predictions(peaks, cache, inputs=[recording], out=tmp_path / "p.parquet", split="all")
    argv = [str(peaks), str(cache.path), str(recording), "--split", "all", "-o", str(tmp_path / "p.parquet")]
    with pytest.raises(InputError, match=r"first items only \(python -m mmusv\.learn\.infer --limit\)"):
        replay_main(argv)
    out = tmp_path / "run"
    out.mkdir()
    with pytest.raises(InputError, match=rf"^out = '{out}': no {out / 'single' / 'model.pt'}; train the single"):
        fit_scorers(out, cache.path, ["single"], seed=0)
    (out / "cache_all.npz").write_bytes(cache.path.read_bytes())  # --split all
    capsys.readouterr()
    argv = ["train", str(recording), "--split", "all", "--modes", "single", "--scorers-only", "-o", str(out)]
    assert mmusv_main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"mmusv: error: --scorers-only -o {out}: no {out / 'single' / 'model.pt'}; train"), err
    assert not (tmp_path / "p.parquet").exists()
