"""A trained model as the detection study's detector (:mod:`mmusv.studies.detection.detector`'s interface).

:func:`load_models` reads ``model.pt`` files written by :mod:`mmusv.learn.train`: one file, a model's own folder
(``OUT/single``), or a folder holding ``single/``, ``early/`` and ``intermediate/`` sub-folders (what ``mmusv
train`` writes). The
:class:`LearnedDetector` it returns is called like any detector (``points (N, 4)`` float32 ego LiDAR frame →
``boxes (M, 7)``, ``scores (M,)``) with the single-agent model, which serves no and late fusion; the study's
fusion code (:func:`mmusv.studies.detection.fusion.fuse`) calls :meth:`LearnedDetector.early` on the aggregated
cloud and :meth:`LearnedDetector.intermediate` with the ego and its neighbours (as delayed or noisy as the
robustness setting makes them). :attr:`LearnedDetector.shared_bytes` records, per intermediate-fusion call, the
bytes the neighbours sent (:func:`mmusv.learn.example.message_bytes`). By default the boxes of ``cpu``-preset
models are tightened on the points by the geometric second stage of :mod:`mmusv.learn.refine` (``refine``), and
rescored by a model's IoU scorer (:mod:`mmusv.learn.scorer`, ``scorer.pt`` beside its ``model.pt``) where it has one
and it was fitted for these weights (a scorer of a model trained on after it is left out, and said so).
:meth:`LearnedDetector.describe` says how far each model trained (``3 of 12 epochs`` for a run that stopped
short); :meth:`LearnedDetector.trained_on` which sequences it learnt from.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import torch

from mmusv.learn._errors import input_error
from mmusv.learn.checkpoint import load_checkpoint, weights_digest
from mmusv.learn.decode import decode
from mmusv.learn.example import collate, make_example, message_bytes
from mmusv.learn.model import PillarNet, from_checkpoint
from mmusv.learn.modes import MODELS, fusion_modes
from mmusv.learn.refine import RefineParams
from mmusv.learn.scorer import SCORER_FILE, IoUScorer, load_scorer, second_stage
from mmusv.text import counted, given

__all__ = ["LearnedDetector", "load_models"]


def _load(path: Path, device: torch.device, mode: str | None = None) -> tuple[PillarNet, dict[str, Any]]:
    what = f"{given('path', path)}: not an mmusv.learn model.pt"
    ck = load_checkpoint(path, what=what, device=device)
    model = from_checkpoint(ck, what, mode=mode)
    model.to(device).eval()
    if device.type == "cuda":
        model.channels_last()
    return model, ck


def load_models(
    path: str | Path,
    *,
    device: str = "cpu",
    refine: bool | None = None,
    rescore: bool | None = None,
    models: Sequence[str] | None = None,
) -> LearnedDetector:
    """The models at ``path`` (module docstring) as one detector; raises ``InputError`` naming the path when
    there is none or one is unreadable. ``refine``: apply the geometric second stage
    (:mod:`mmusv.learn.refine`) to every model's boxes; ``None`` (default): only when every model is of the
    ``cpu`` preset, the one it was measured on. ``rescore``: rank the refined boxes by each model's IoU scorer
    (:mod:`mmusv.learn.scorer`); ``None`` (default): where a model has one and the boxes are refined; ``True``:
    every model must have one (an ``InputError`` names the one without). The messages name ``path``, ``refine``
    and ``rescore`` (the flags of a command that calls it in :func:`mmusv.text.command_line`). ``models``: of a
    folder holding ``single/``, ``early/``, ``intermediate/``, load only these (``None``: every one there); the
    others are not read, so one that is damaged or of another training does not stop a study that does not run it."""
    p = Path(path)
    dev = torch.device(device)
    files: dict[str, Path] = {}
    if p.is_dir() and (p / "model.pt").is_file():  # a model's own folder (OUT/single): it was "no model.pt there"
        p = p / "model.pt"
    if p.is_file():
        _, ck = _load(p, dev)
        files[str(ck["mode"])] = p
    elif p.is_dir():
        wanted = MODELS if models is None else tuple(m for m in MODELS if m in models)
        files = {m: p / m / "model.pt" for m in wanted if (p / m / "model.pt").is_file()}
    if not files:
        raise input_error(
            f"{given('path', p)}: no model.pt there (a model.pt, a folder holding one, or a folder with "
            f"{'/'.join(MODELS)}/model.pt)"
        )
    nets: dict[str, PillarNet] = {}
    info: dict[str, dict[str, Any]] = {}
    for mode, f in files.items():
        nets[mode], ck = _load(f, dev, mode if p.is_dir() else None)
        info[mode] = {
            "file": str(f),
            "epoch": int(ck["epoch"]),
            "step": int(ck["step"]),
            "preset": ck["preset"]["name"],
            "epochs": ck.get("epochs"),  # asked for (checkpoints from before it was recorded lack it)
            "stopped": ck.get("stopped"),
            "seed": ck.get("seed"),
            "data": ck.get("data") if isinstance(ck.get("data"), dict) else None,
        }
    if refine is None:
        refine = all(v["preset"] == "cpu" for v in info.values())
    scorers: dict[str, IoUScorer] = {}
    if rescore is not False:
        if not refine and rescore:
            raise input_error(
                f"{given('rescore', True)} needs the refined boxes ({given('refine', True)}; without it, only models "
                "of the cpu preset are refined): the scorer reads the refinement"
            )
        for mode, f in files.items():
            sf = f.parent / SCORER_FILE
            if refine and sf.is_file():
                scorer = load_scorer(sf)
                fitted_for = scorer.info.get("model")
                if fitted_for is not None and fitted_for != weights_digest(nets[mode].state_dict()):
                    # the model trained on after its scorer was fitted (mmusv train --no-scorers, or a resumed run):
                    # the scorer ranks boxes it never saw, so it is left out, and the line of describe() says so
                    why = f"{sf} was fitted for other weights of this model; refit it: mmusv train --scorers-only"
                    if rescore:
                        raise input_error(f"{given('rescore', True)}: {why}")
                    info[mode]["stale_scorer"] = str(sf)
                    continue
                scorers[mode] = scorer
                info[mode]["scorer"] = str(sf)
            elif rescore:
                raise input_error(
                    f"{given('rescore', True)}: {mode} has no {sf} (fit it with mmusv train --scorers-only)"
                )
    return LearnedDetector(nets, info, refine=RefineParams() if refine else None, scorers=scorers)


def _progress(v: dict[str, Any]) -> str:
    """``12 epochs, 5340 steps``; ``3 of 12 epochs, unfinished, 1335 steps`` for a run that stopped short (``stopped
    at its time limit`` when that is why)."""
    planned = v.get("epochs")
    if not isinstance(planned, int) or v["epoch"] >= planned:
        return f"{counted(v['epoch'], 'epoch')}, {counted(v['step'], 'step')}"
    why = "stopped at its time limit" if v.get("stopped") == "time limit" else "unfinished"
    return f"{v['epoch']} of {counted(planned, 'epoch')}, {why}, {counted(v['step'], 'step')}"


class LearnedDetector:
    """Trained models by training mode (``single``, ``early``, ``intermediate``; module docstring). With
    ``refine``, every model's decoded boxes go through :func:`mmusv.learn.refine.refine_boxes` on the points the
    model was given (the aggregate for early fusion; the ego's own cloud for intermediate fusion, whose
    neighbours send features, not points), then, for a model with a scorer in ``scorers``, the IoU-aware
    rescoring, and the preset's rotated NMS again (two proposals on one hull can grow into the same box):
    :func:`mmusv.learn.scorer.second_stage`."""

    def __init__(
        self,
        models: dict[str, PillarNet],
        info: dict[str, dict[str, Any]],
        *,
        refine: RefineParams | None = None,
        scorers: dict[str, IoUScorer] | None = None,
    ) -> None:
        self.models, self.info, self.refine = models, info, refine
        self.scorers: dict[str, IoUScorer] = dict(scorers or {})
        self.shared_bytes: list[int] = []

    @property
    def fusion_modes(self) -> tuple[str, ...]:
        """The study's fusion modes these models can run (:data:`mmusv.learn.modes.STUDY_NEEDS`)."""
        return fusion_modes(self.models)

    def describe(self) -> str:
        """One line: each model's file, preset and the epochs it was trained for (``3 of 12 epochs, unfinished``
        for a model whose run stopped short: a ``model.pt`` is written after every epoch), and the second stage."""
        models = "; ".join(f"{m}: {v['file']} (preset {v['preset']}, {_progress(v)})" for m, v in self.info.items())
        second = self.refine.describe() if self.refine is not None else "no box refinement (network boxes as decoded)"
        if self.scorers:
            second += (
                "; IoU-aware rescoring ("
                + ", ".join(f"{m} β={s.beta:g}" for m, s in sorted(self.scorers.items()))
                + ")"
            )
        stale = [v["stale_scorer"] for v in self.info.values() if "stale_scorer" in v]
        if stale:
            second += (
                f"; not used, fitted for other weights of the model (refit: mmusv train --scorers-only): "
                f"{', '.join(stale)}"
            )
        return f"{models}; {second}"

    def trained_on(self, fingerprints: dict[str, str]) -> dict[str, list[str]]:
        """``{model: sequences}``: which of the sequences ``fingerprints`` (``{name: fingerprint}``,
        :func:`mmusv.learn.cache.dataset_fingerprints`) each model was trained on (the same name and fingerprint
        in its checkpoint's data; none for a checkpoint that does not record it)."""
        out: dict[str, list[str]] = {}
        for mode, v in self.info.items():
            seen = (v.get("data") or {}).get("fingerprints") or {}
            both = sorted(n for n, fp in fingerprints.items() if isinstance(seen, dict) and seen.get(n) == fp)
            if both:
                out[mode] = both
        return out

    def _run(
        self, mode: str, ego: np.ndarray, neighbours: Sequence[tuple[np.ndarray, np.ndarray]]
    ) -> tuple[np.ndarray, np.ndarray]:
        boxes, scores = self._infer(mode, ego, neighbours)
        return second_stage(
            ego,
            boxes=boxes,
            scores=scores,
            refine=self.refine,
            scorer=self.scorers.get(mode),
            nms_iou=self.models[mode].preset.nms_iou,
        )

    def _infer(
        self, mode: str, ego: np.ndarray, neighbours: Sequence[tuple[np.ndarray, np.ndarray]]
    ) -> tuple[np.ndarray, np.ndarray]:
        if mode not in self.models:
            raise input_error(
                f"no {mode} model among those loaded (have {', '.join(self.models)}); train it with mmusv train"
            )
        model = self.models[mode]
        p = model.preset
        ex = make_example(np.asarray(ego, dtype=np.float32), neighbours=list(neighbours), boxes=None, mode=mode, p=p)
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
