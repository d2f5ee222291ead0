"""The learned detector's models and the detection study's fusion modes each of them runs: one table.

``mmusv train`` trains :data:`MODELS` (``single``, ``early``, ``intermediate``); the study's four fusion modes run
them as :data:`STUDY_NEEDS` says (``none`` and ``late`` both run ``single``: late fusion merges single-agent
boxes). Neither PyTorch nor mmusv's native extension is imported here: :mod:`mmusv.learn.replay` and
:mod:`mmusv.learn.infer` run on machines without them, and ``mmusv study`` reads the table before it loads a
model.
"""

from __future__ import annotations

from collections.abc import Iterable

__all__ = ["MODELS", "STUDY_NEEDS", "fusion_modes", "models_for"]

MODELS = ("single", "early", "intermediate")
"""The three models, in the order they are trained, listed and written."""

STUDY_NEEDS = {"none": "single", "late": "single", "early": "early", "intermediate": "intermediate"}
"""The model each of the study's fusion modes (``mmusv study --modes``) runs."""


def fusion_modes(models: Iterable[str]) -> tuple[str, ...]:
    """The study's fusion modes that ``models`` (names of :data:`MODELS`) can run, in the study's order."""
    have = set(models)
    return tuple(mode for mode, need in STUDY_NEEDS.items() if need in have)


def models_for(modes: Iterable[str]) -> tuple[str, ...]:
    """The models the study's fusion ``modes`` run, in :data:`MODELS` order (unknown modes are ignored: the
    study's ``--modes`` check names them)."""
    needed = {STUDY_NEEDS[m] for m in modes if m in STUDY_NEEDS}
    return tuple(m for m in MODELS if m in needed)
