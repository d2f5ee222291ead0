"""Checkpoints are read with PyTorch's safe unpickler (mmusv.learn.checkpoint): a model, scorer or resume file that
carries code is refused without running it, and a file that is not a checkpoint is one ``InputError`` naming it."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from mmusv.errors import InputError
from mmusv.learn.detector import load_models
from mmusv.learn.infer import _model
from mmusv.learn.presets import preset
from mmusv.learn.scorer import FEATURES, IoUScorer, load_scorer
from mmusv.learn.train import train

from learn.scenes import SCENES, MemorySource


class _Payload:
    """Unpickled by the full unpickler, it creates the file ``marker`` (what a hostile checkpoint would do)."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self) -> tuple[Any, ...]:
        return (os.mkdir, (str(self.marker),))


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("ck")
    train(MemorySource(SCENES[:1]), p=preset("tiny"), mode="single", out=out, epochs=1, progress=False)
    return out


def _hostile(path: Path, marker: Path, base: dict[str, Any]) -> Path:
    torch.save({**base, "extra": _Payload(marker)}, path)
    return path


def test_a_checkpoint_carrying_code_is_refused_without_running_it(trained: Path, tmp_path: Path) -> None:
    ck = torch.load(trained / "model.pt", weights_only=True)
    marker = tmp_path / "ran"
    bad = _hostile(tmp_path / "model.pt", marker, ck)
    with pytest.raises(InputError, match=r"^path = '.*model\.pt': not an mmusv\.learn model\.pt .*other than tensors"):
        load_models(bad)
    with pytest.raises(InputError, match=r"model\.pt: not an mmusv\.learn model\.pt"):
        _model(bad, torch.device("cpu"))
    scorer = _hostile(tmp_path / "scorer.pt", marker, {"beta": 0.5})
    with pytest.raises(InputError, match=r"scorer\.pt: not an mmusv\.learn scorer"):
        load_scorer(scorer)
    assert not marker.exists()  # the full unpickler would have made it (checked below)
    torch.load(bad, weights_only=False)
    assert marker.exists()


def test_a_resume_file_carrying_code_or_garbage_is_refused(trained: Path, tmp_path: Path) -> None:
    src = MemorySource(SCENES[:1])
    last = torch.load(trained / "last.pt", weights_only=True)
    marker = tmp_path / "ran"
    for name, make in (
        ("hostile", lambda p: _hostile(p, marker, last)),
        ("garbage", lambda p: p.write_bytes(b"\x00" * 100)),
        ("empty", lambda p: p.write_bytes(b"")),
        ("a list", lambda p: torch.save([1, 2], p)),
    ):
        out = tmp_path / name
        out.mkdir()
        make(out / "last.pt")
        with pytest.raises(InputError, match=r"last\.pt: not a checkpoint of mmusv train"):
            train(src, p=preset("tiny"), mode="single", out=out, epochs=2, progress=False)
        assert not (out / "model.pt").exists(), name
    assert not marker.exists()


def test_files_that_are_not_checkpoints_are_named(trained: Path, tmp_path: Path) -> None:
    good = (trained / "model.pt").read_bytes()
    cases = {
        "empty.pt": b"",
        "text.pt": b"not a model\n",
        "cut.pt": good[: len(good) // 2],
    }
    for name, data in cases.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(InputError, match=rf"^path = '.*{name}': not an mmusv\.learn model\.pt"):
            load_models(tmp_path / name)
        with pytest.raises(InputError, match=rf"{name}: not an mmusv\.learn scorer"):
            load_scorer(tmp_path / name)


def test_real_checkpoints_load_with_the_safe_unpickler(trained: Path, tmp_path: Path) -> None:
    det = load_models(trained / "model.pt")
    boxes, scores = det(MemorySource(SCENES[:1]).sample(0)[0])
    assert boxes.shape == (len(scores), 7)
    n = len(FEATURES)
    scorer = IoUScorer(np.arange(n), np.ones(n), beta=0.3)
    path = scorer.save(tmp_path / "scorer.pt", {"note": "test", "ap": 0.5, "steps": [1, 2]})
    again = load_scorer(path)
    assert again.beta == pytest.approx(0.3) and torch.equal(again.mean, scorer.mean)
