"""A trained model as the detection study's detector (:mod:`mmusv.studies.detection.detector`'s interface).

:func:`load_models` reads ``model.pt`` files written by :mod:`mmusv.learn.train`: one file, or a folder
holding ``single/``, ``early/`` and ``intermediate/`` sub-folders (what ``mmusv train`` writes). The
:class:`LearnedDetector` it returns is called like any detector (``points (N, 4)`` float32 ego LiDAR frame →
``boxes (M, 7)``, ``scores (M,)``) with the single-agent model, which serves no and late fusion; the study's
fusion code (:func:`mmusv.studies.detection.fusion.fuse`) calls :meth:`LearnedDetector.early` on the aggregated
cloud and :meth:`LearnedDetector.intermediate` with the ego and its neighbours (as delayed or noisy as the
robustness setting makes them). :attr:`LearnedDetector.shared_bytes` records, per intermediate-fusion call, the
bytes the neighbours sent (:func:`mmusv.learn.example.message_bytes`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import torch

from mmusv.learn._errors import input_error
from mmusv.learn.decode import decode
from mmusv.learn.example import MODES, collate, make_example, message_bytes
from mmusv.learn.model import PillarNet
from mmusv.learn.presets import Preset

__all__ = ["LearnedDetector", "load_models"]


def _load(path: Path, device: torch.device) -> tuple[PillarNet, dict[str, Any]]:
    try:
        ck = torch.load(path, map_location=device, weights_only=False)
        p = Preset.from_dict(ck["preset"])
        model = PillarNet(p, ck["mode"])
        model.load_state_dict(ck["model"])
    except (OSError, KeyError, TypeError, RuntimeError, ValueError) as exc:
        raise input_error(f"--model {path}: not an mmusv.learn model.pt ({type(exc).__name__}: {exc})") from None
    model.to(device).eval()
    return model, ck


def load_models(path: str | Path, *, device: str = "cpu") -> LearnedDetector:
    """The models at ``path`` (module docstring) as one detector; raises ``InputError`` naming the path when
    there is none or one is unreadable."""
    p = Path(path)
    dev = torch.device(device)
    files: dict[str, Path] = {}
    if p.is_file():
        _, ck = _load(p, dev)
        files[str(ck["mode"])] = p
    elif p.is_dir():
        files = {m: p / m / "model.pt" for m in MODES if (p / m / "model.pt").is_file()}
    if not files:
        raise input_error(f"--model {p}: no model.pt there (a file, or a folder with {'/'.join(MODES)}/model.pt)")
    models: dict[str, PillarNet] = {}
    info: dict[str, dict[str, Any]] = {}
    for mode, f in files.items():
        models[mode], ck = _load(f, dev)
        info[mode] = {
            "file": str(f),
            "epoch": int(ck["epoch"]),
            "step": int(ck["step"]),
            "preset": ck["preset"]["name"],
        }
    return LearnedDetector(models, info)


class LearnedDetector:
    """Trained models by training mode (``single``, ``early``, ``intermediate``; module docstring)."""

    def __init__(self, models: dict[str, PillarNet], info: dict[str, dict[str, Any]]) -> None:
        self.models, self.info = models, info
        self.shared_bytes: list[int] = []

    @property
    def fusion_modes(self) -> tuple[str, ...]:
        """The study's fusion modes these models can run: none and late need ``single``."""
        out = [m for m, need in (("none", "single"), ("late", "single"), ("early", "early")) if need in self.models]
        if "intermediate" in self.models:
            out.append("intermediate")
        return tuple(out)

    def describe(self) -> str:
        """One line: each model's file, preset and the epochs it was trained for."""
        return "; ".join(
            f"{m}: {v['file']} (preset {v['preset']}, {v['epoch']} epochs, {v['step']} steps)"
            for m, v in self.info.items()
        )

    def _run(
        self, mode: str, ego: np.ndarray, neighbours: Sequence[tuple[np.ndarray, np.ndarray]]
    ) -> tuple[np.ndarray, np.ndarray]:
        if mode not in self.models:
            raise input_error(f"--model: no {mode} model (have {', '.join(self.models)}); train it with mmusv train")
        model = self.models[mode]
        p = model.preset
        ex = make_example(np.asarray(ego, dtype=np.float32), list(neighbours), None, mode=mode, p=p)
        if mode == "intermediate" and ex.nb is not None:
            self.shared_bytes.append(message_bytes(ex.nb, p.pfn_channels))
        dev = next(model.parameters()).device
        with torch.no_grad():
            out = model(collate([ex]).to(dev))
        return decode(out, p)

    def __call__(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The single-agent model on one cloud (no and late fusion)."""
        return self._run("single", points, [])

    def early(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The early-fusion model on the aggregated cloud (ego LiDAR frame)."""
        return self._run("early", points, [])

    def intermediate(
        self, ego: np.ndarray, neighbours: Sequence[tuple[np.ndarray, np.ndarray]]
    ) -> tuple[np.ndarray, np.ndarray]:
        """The intermediate-fusion model: the ego's cloud and each neighbour's ``(points in its own LiDAR frame,
        (4, 4) neighbour LiDAR → ego LiDAR)``."""
        return self._run("intermediate", ego, neighbours)
