"""The IoU scorers of trained models (``mmusv train``'s second step, ``--scorers-only``): each model of ``OUT/<mode>/``
is run over the training cache and its scorer (:func:`mmusv.learn.scorer.fit_scorer`) fitted into
``OUT/<mode>/scorer.pt``; a fit that fails for too few boxes is recorded beside the model (:data:`SCORER_SKIPPED`)
so a rerun does not run the model over the cache again to fail the same way.
"""

from __future__ import annotations

import contextlib
import json
import time
from pathlib import Path
from typing import Any

from mmusv.errors import InputError, MmusvError
from mmusv.jsonio import read_json_or_none
from mmusv.text import counted, given, named

__all__ = ["SCORER_SKIPPED", "fit_scorers"]

SCORER_SKIPPED = "scorer_skipped.json"
"""Beside a model whose IoU-scorer fit failed (too few boxes): for which weights, cache and seed, and why
(:func:`fit_scorers`)."""


def fit_scorers(
    out: Path,
    cache_path: Path,
    modes: list[str],
    *,
    seed: int,
    threads: int | None = None,
    keep_current: bool = False,
) -> dict[str, dict[str, Any]]:
    """Fits the IoU scorer (:func:`mmusv.learn.scorer.fit_scorer`) of each trained model in ``modes`` on the
    training cache, each into ``OUT/<mode>/scorer.pt``; returns what each fit measured. ``threads``: torch's
    threads (``None``: as they are). ``keep_current``: a ``scorer.pt`` already fitted for the model's weights as they
    are is kept, not fitted again (a rerun of a finished training: minutes of work for the same scorer), and so is
    a fit that failed for these weights, this cache and seed (``OUT/<mode>/scorer_skipped.json``, written when the
    model finds too few boxes: the fit is deterministic, and a rerun ran the model over the whole cache again, for
    minutes, to fail the same way). ``--scorers-only`` (``keep_current`` false) always fits: the way to try again.
    Any other failure (Ctrl-C, out of memory) is not recorded and the next run fits again. A mode without a model
    is refused naming ``out`` as its user gave it (:func:`mmusv.text.given`: ``out = 'run'``, ``--scorers-only -o run``
    from ``mmusv train``; it said ``--scorers-only`` to a Python caller)."""
    import torch

    from mmusv.learn.cache import Cache, cache_identity
    from mmusv.learn.checkpoint import remove_stale_temporaries, weights_digest
    from mmusv.learn.detector import load_models
    from mmusv.learn.example import early_cloud
    from mmusv.learn.refine import RefineParams
    from mmusv.learn.scorer import SCORER_FILE, fit_scorer, load_scorer

    if threads is not None:
        torch.set_num_threads(threads)
    cache = Cache(cache_path)
    done: dict[str, dict[str, Any]] = {}
    for mode in modes:
        if not (out / mode / "model.pt").is_file():
            raise InputError(f"{given('out', out)}: no {out / mode / 'model.pt'}; train the {mode} model first")
        remove_stale_temporaries(out / mode)  # of a fit killed while it saved its scorer.pt
        det = load_models(out / mode / "model.pt", refine=True, rescore=False)
        model = det.models[mode]
        current = out / mode / SCORER_FILE
        digest = weights_digest(model.state_dict())
        if keep_current and current.is_file():
            try:
                kept = load_scorer(current).info
            except MmusvError:
                kept = {}
            if kept.get("model") == digest:
                done[mode] = kept
                print(f"{mode}: {current} was fitted for these weights; kept", flush=True)
                continue
        skipped_file = out / mode / SCORER_SKIPPED
        # as read back from its file (JSON: tuples are lists)
        failed_fit = json.loads(json.dumps({"model": digest, "cache": cache_identity(cache_path), "seed": seed}))
        if keep_current:  # a scorer.pt for these weights was kept above; a stale one does not count
            before = read_json_or_none(skipped_file)
            if before is not None and {k: before.get(k) for k in failed_fit} == failed_fit:
                done[mode] = {"skipped": before.get("reason", "")}
                again = f"mmusv train --scorers-only -o {out}" if named("out") != "out" else "keep_current = False"
                print(
                    f"{mode}: no IoU scorer (its fit failed before for these weights and data: {before.get('reason')};"
                    f" {skipped_file}); the model's boxes keep the network's scores (try again: {again})",
                    flush=True,
                )
                continue

        def sample(k: int, mode: str = mode, det: Any = det) -> tuple[Any, Any, Any, Any]:
            ego, nbs, gt = cache.sample(k)
            points = early_cloud(ego, nbs) if mode == "early" else ego
            boxes, scores = det._infer(mode, points, nbs if mode == "intermediate" else [])
            return points, boxes, scores, gt

        ks = list(range(len(cache)))
        groups = [cache.key(int(cache.arrays["sample_cloud"][k]))[0] for k in ks]
        t0 = time.perf_counter()
        try:
            scorer, fit = fit_scorer(
                sample, samples=ks, groups=groups, refine=RefineParams(), nms_iou=model.preset.nms_iou, seed=seed
            )
        except InputError as e:  # a model that finds (almost) nothing: it is used as it is, and this is said
            done[mode] = {"skipped": str(e)}
            # recorded: the same weights, cache and seed fail the same way (a rerun took minutes to say it again)
            with contextlib.suppress(OSError):  # not recorded: the next run fits again
                skipped_file.write_text(json.dumps({**failed_fit, "reason": str(e)}, indent=2) + "\n", encoding="utf-8")
            print(f"{mode}: no IoU scorer ({e}); the model's boxes keep the network's scores", flush=True)
            continue
        with contextlib.suppress(OSError):
            skipped_file.unlink(missing_ok=True)
        info = {
            "model": digest,  # the weights it was fitted for (load_models checks)
            "boxes": fit.boxes,
            "frames": fit.frames,
            "beta": fit.beta,
            "held_out": [{"beta": b, "ap50": round(a5, 4), "ap70": round(a7, 4)} for b, a5, a7 in fit.held_out],
            "seconds": round(time.perf_counter() - t0, 1),
        }
        # the file without the fit's wall-clock time (the summary has it): the same seed, the same bytes
        path = scorer.save(out / mode / SCORER_FILE, {k: v for k, v in info.items() if k != "seconds"})
        done[mode] = info
        base = next(x for x in fit.held_out if x[0] == 0.0)
        chosen = next(x for x in fit.held_out if x[0] == fit.beta)
        print(
            f"{mode}: IoU scorer on {counted(fit.boxes, 'box', plural='boxes')} "
            f"of {counted(fit.frames, 'ego-frame')}, β = {fit.beta:g} (held-out "
            f"AP@0.5 {base[1]:.3f} -> {chosen[1]:.3f}, AP@0.7 {base[2]:.3f} -> {chosen[2]:.3f}), "
            f"{info['seconds']:.0f} s -> {path}",
            flush=True,
        )
    return done
