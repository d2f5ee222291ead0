"""The run report: per combination the quota, attempts, accepted scenarios and rejections per constraint, whether
the quota was met and why not; written as ``report.json`` (deterministic: no times or paths) and shown as a
rich table.

Bookkeeping: every attempt is either accepted or rejected by exactly one name, the first check that failed in
evaluation order, or ``sampling`` when the family template could not place the vessels at all, or ``schema``
when the assembled scenario did not validate. So ``accepted + sum(rejected) == attempts`` per combination and in
total.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from mmusv.text import counted

if TYPE_CHECKING:
    from rich.console import Console

__all__ = ["ComboReport", "RunReport"]


@dataclass
class ComboReport:
    """Bookkeeping of one role combination."""

    name: str
    family: str
    difficulty: str
    quota: int
    max_attempts: int
    attempts: int = 0
    accepted: int = 0
    rejected: dict[str, int] = field(default_factory=dict)
    examples: dict[str, str] = field(default_factory=dict)
    files: list[str] = field(default_factory=list)

    def reject(self, name: str, reason: str) -> None:
        """Counts a rejected attempt against ``name``, keeping the first reason as an example."""
        self.attempts += 1
        self.rejected[name] = self.rejected.get(name, 0) + 1
        self.examples.setdefault(name, reason)

    def accept(self, file: str) -> None:
        """Counts an accepted attempt written to ``file``."""
        self.attempts += 1
        self.accepted += 1
        self.files.append(file)

    @property
    def met(self) -> bool:
        return self.accepted >= self.quota

    def why(self) -> str:
        """One line: "quota met" or why not (attempt cap, the top rejecting constraints with an example)."""
        if self.met:
            return "quota met"
        head = (
            f"{self.accepted}/{self.quota} accepted after {counted(self.attempts, 'attempt')} (cap {self.max_attempts})"
        )
        top = sorted(self.rejected.items(), key=lambda kv: (-kv[1], kv[0]))[:3]
        parts = [f"{name} rejected {n} (e.g. {self.examples[name]})" for name, n in top]
        return head + ("; " + "; ".join(parts) if parts else "")

    def as_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "family": self.family,
            "difficulty": self.difficulty,
            "quota": self.quota,
            "max_attempts": self.max_attempts,
            "attempts": self.attempts,
            "accepted": self.accepted,
            "rejected": dict(sorted(self.rejected.items())),
            "quota_met": self.met,
            "why": self.why(),
            "examples": dict(sorted(self.examples.items())),
            "files": list(self.files),
        }


@dataclass
class RunReport:
    """The report of one ``generate`` run (see module docstring)."""

    spec_name: str
    seed: int
    map: dict[str, Any]
    constraints: list[str]
    combos: list[ComboReport] = field(default_factory=list)
    scenarios: list[dict[str, Any]] = field(default_factory=list)

    @property
    def attempts(self) -> int:
        return sum(c.attempts for c in self.combos)

    @property
    def accepted(self) -> int:
        return sum(c.accepted for c in self.combos)

    @property
    def rejected(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for c in self.combos:
            for k, n in c.rejected.items():
                out[k] = out.get(k, 0) + n
        return dict(sorted(out.items()))

    @property
    def all_met(self) -> bool:
        return all(c.met for c in self.combos)

    def as_dict(self) -> dict[str, Any]:
        return {
            "spec": self.spec_name,
            "seed": self.seed,
            "map": self.map,
            "constraints": self.constraints,
            "attempts": self.attempts,
            "accepted": self.accepted,
            "rejected": self.rejected,
            "all_quotas_met": self.all_met,
            "combinations": [c.as_dict() for c in self.combos],
            "scenarios": self.scenarios,
        }

    def to_json(self) -> str:
        """Deterministic JSON text (fixed key order, two-space indent, trailing newline)."""
        return json.dumps(self.as_dict(), indent=2, ensure_ascii=False) + "\n"

    def print(self, console: Console) -> None:
        """A rich table: one row per combination, then the totals and the unmet quotas' reasons."""
        from rich.table import Table
        from rich.text import Text

        names = [*self.constraints, "sampling", "schema"]
        shown = [n for n in names if any(n in c.rejected for c in self.combos)]
        table = Table(title=f"mmusv generate: {self.spec_name} (seed {self.seed})")
        for col in ("combination", "quota", "accepted", "attempts", *shown, "met"):
            table.add_column(col, justify="left" if col == "combination" else "right")
        for c in self.combos:
            table.add_row(
                c.name,
                str(c.quota),
                str(c.accepted),
                str(c.attempts),
                *(str(c.rejected.get(n, 0)) for n in shown),
                Text("yes", style="green") if c.met else Text("no", style="red"),
            )
        rej = self.rejected
        table.add_row(
            "total",
            str(sum(c.quota for c in self.combos)),
            str(self.accepted),
            str(self.attempts),
            *(str(rej.get(n, 0)) for n in shown),
            "yes" if self.all_met else "no",
            style="bold",
        )
        console.print(table)
        for c in self.combos:
            if not c.met:
                console.print(Text.assemble(("quota not met", "red"), f" {c.name}: {c.why()}"))
