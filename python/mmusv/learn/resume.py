"""Which ``last.pt`` a training run resumes, and what it must not replace: a ``last.pt`` is resumed only by the
same run (the same preset, mode and seed, and the same data; a cache built from other sequences is refused), the
refusal naming what differs (``preset 'tiny', this run 'cpu'``, ``seed 0, this run 1``); a ``model.pt`` of another
run left without its ``last.pt`` is refused rather than trained over. :func:`mmusv.learn.train.train` and ``mmusv
train`` (for every model before it starts any) ask :func:`resumable_checkpoint`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mmusv.learn._errors import input_error, input_error_types
from mmusv.learn.cache import same_data
from mmusv.learn.checkpoint import load_checkpoint
from mmusv.learn.presets import Preset

__all__ = ["not_a_checkpoint", "resumable_checkpoint"]


def _differs(ck: dict[str, Any], p: Preset, mode: str, seed: int) -> str | None:
    """What of ``preset``, ``mode`` and ``seed`` a ``last.pt`` holds other than this run (``None``: the same run)."""
    out = []
    old = ck.get("preset")
    if old != p.to_dict():
        if isinstance(old, dict) and old.get("name") == p.name:
            changed = sorted(k for k, v in p.to_dict().items() if old.get(k, object()) != v)
            out.append(f"preset {p.name} with other {', '.join(changed) or 'fields'}")
        else:
            name = old.get("name") if isinstance(old, dict) else None
            out.append(f"preset {name!r}, this run {p.name!r}")
    if ck.get("mode") != mode:
        out.append(f"mode {ck.get('mode')!r}, this run {mode!r}")
    if ck.get("seed") != seed:
        out.append(f"seed {ck.get('seed')!r}, this run {seed!r}")
    return "; ".join(out) or None


def not_a_checkpoint(last: Path) -> str:
    """What is said of a ``last.pt`` that cannot be resumed from."""
    return f"{last}: not a checkpoint of mmusv train (remove it to start again, or use another -o)"


def resumable_checkpoint(
    out: str | Path,
    *,
    p: Preset,
    mode: str,
    seed: int,
    identity: dict[str, Any] | None,
    device: Any = "cpu",
) -> dict[str, Any] | None:
    """The ``last.pt`` in model folder ``out`` that this run (preset ``p``, ``mode``, ``seed``, data ``identity``)
    resumes, ``None`` without one; refuses one of another run, naming the file and what differs. ``mmusv train``
    asks it for every model before it starts any: refused only in each model's process, a run of another preset into
    the same ``-o`` printed the refusal once per model and replaced ``train_summary.json`` with one of no model."""
    last = Path(out) / "last.pt"
    if not last.is_file():
        _check_model_alone(Path(out) / "model.pt", p=p, mode=mode, seed=seed, identity=identity)
        return None
    ck = load_checkpoint(last, what=not_a_checkpoint(last), device=device)
    other = _differs(ck, p, mode, seed)
    if other is not None:  # it said "preset/mode/seed differ", not which
        raise input_error(f"{last}: a checkpoint of another run ({other}); use another -o")
    if not same_data(ck.get("data"), identity):
        before = ", ".join(str(x) for x in ck["data"].get("sources", [])) or "?"
        raise input_error(
            f"{last}: a checkpoint of a run on other data (trained on {before}); use another -o, or remove "
            f"{out} to start again"
        )
    return ck


def _check_model_alone(model: Path, *, p: Preset, mode: str, seed: int, identity: dict[str, Any] | None) -> None:
    """Refuses a ``model.pt`` without the ``last.pt`` beside it (removed, or the file alone copied there) when it is
    of another run (another preset, mode, seed or data): training started over and replaced it without a word, the
    run's ``-o`` check passed it by, and a model of another training was lost. One that cannot be read is no
    model to lose (it is replaced)."""
    if not model.is_file():
        return
    try:
        ck = load_checkpoint(model, what=str(model))
    except input_error_types():
        return
    other = _differs(ck, p, mode, seed)
    if other is None and not same_data(ck.get("data"), identity):
        data = ck.get("data")
        before = ", ".join(str(x) for x in data.get("sources", [])) if isinstance(data, dict) else ""
        other = f"trained on other data: {before or '?'}"
    if other is not None:
        raise input_error(
            f"{model}: a model of another run ({other}), without its last.pt; use another -o, or remove {model.parent} "
            "to start again"
        )
