"""Batch scenario generation under constraints (issue #7): ``mmusv generate SPEC.yaml -o DIR``.

A generation spec (:mod:`.spec`) names a map, scenario families (:mod:`.families`), roles and difficulty levels,
role combinations with quotas, and constraint thresholds. The sampler (:mod:`.sampler`) draws candidates from
the spec's seed; the named constraints (:mod:`.checks`) accept or reject them, vectorised over dense route and
time samples evaluated in the Rust core; the loop (:mod:`.runner`) resamples up to a cap and writes one scenario
YAML per accepted candidate plus ``report.json`` (:mod:`.report`). Python API::

    from mmusv.generate import generate
    report = generate("scenarios/specs/island_demo.yaml", "scenarios/generated/island_demo")
    report.accepted, report.attempts, report.rejected
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mmusv._lazy import attributes

if TYPE_CHECKING:
    from mmusv.generate.families import FAMILIES
    from mmusv.generate.report import ComboReport, RunReport
    from mmusv.generate.runner import generate
    from mmusv.generate.spec import GenerationSpec, load_spec

__all__ = ["FAMILIES", "ComboReport", "GenerationSpec", "RunReport", "generate", "load_spec"]

_LAZY = {
    "FAMILIES": "mmusv.generate.families",
    "ComboReport": "mmusv.generate.report",
    "GenerationSpec": "mmusv.generate.spec",
    "RunReport": "mmusv.generate.report",
    "generate": "mmusv.generate.runner",
    "load_spec": "mmusv.generate.spec",
}
"""The names above, loaded on first use (PEP 562): ``mmusv generate``'s parser is built by every ``mmusv`` command
(``mmusv --help`` loaded the sampler, the map builder and the vessel library, a quarter of a second)."""


__getattr__ = attributes(__name__, _LAZY)
