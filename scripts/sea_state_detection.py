"""Table III at two sea states side by side (issue #29: the detection study on a W3 spec beside W1): the
markdown table of docs/studies/detection.md (*Sea state*) and its picture, from two ``mmusv study detection``
output folders over the same sequences (``scenarios/specs/coop_detection_w1.yaml`` and ``_w3.yaml``).

Per fusion mode and sea: AP@0.5 and @0.7, AP@0.5 by range bin, recall at IoU 0.5 of the targets the ego sees, of
those only its neighbours see, and of those the waves hide at least half of from the ego (``wave-hidden``), then
each metric's change from the first sea to the second.

Usage: ``python scripts/sea_state_detection.py W1_DIR W3_DIR [--labels W1,W3] [--png PATH] [--title TEXT]``
(each DIR holds a ``detection_table.csv``).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import polars as pl
from mmusv.studies.detection.report import BINS

METRICS: tuple[tuple[str, str], ...] = (
    ("ap50", "AP@0.5"),
    ("ap70", "AP@0.7"),
    *((f"ap50_{b}", f"{b} m") for b in BINS),
    ("recall50_visible", "R visible"),
    ("recall50_hidden", "R hidden"),
    ("recall50_wave_hidden", "R wave-hidden"),
)


def _cell(v: float) -> str:
    return "–" if v is None or math.isnan(v) else f"{v:.3f}"


def _change(a: float, b: float) -> str:
    if a is None or b is None or math.isnan(a) or math.isnan(b) or a == 0:
        return "–"
    return f"{100 * (b / a - 1):+.0f} %"


def markdown(tables: list[pl.DataFrame], labels: list[str]) -> str:
    """The side-by-side table (markdown): each mode's rows at each sea, then the change."""
    head = ["mode", "sea", *(h for _, h in METRICS), "wave-hidden / all gt"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    modes = [m for m in tables[0]["mode"].to_list() if all(m in t["mode"].to_list() for t in tables)]
    for m in modes:
        rows = [t.filter(pl.col("mode") == m).row(0, named=True) for t in tables]
        for lab, r in zip(labels, rows, strict=True):
            gt = f"{int(r['gt_wave_hidden'])} / {int(r['gt'])}"
            lines.append("| " + " | ".join([m, lab, *(_cell(r[c]) for c, _ in METRICS), gt]) + " |")
        change = [_change(rows[0][c], rows[-1][c]) for c, _ in METRICS]
        lines.append("| " + " | ".join([m, f"{labels[0]} → {labels[-1]}", *change, ""]) + " |")
    return "\n".join(lines)


def plot(tables: list[pl.DataFrame], labels: list[str], path: Path, title: str) -> None:
    """AP@0.5 by range bin per mode, one line style per sea (PNG, no timestamp)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    styles = ["-", "--", ":"]
    colours: dict[str, str] = {}
    for t, lab, ls in zip(tables, labels, styles, strict=False):
        for r in t.iter_rows(named=True):
            (line,) = ax.plot(
                range(len(BINS)),
                [r[f"ap50_{b}"] for b in BINS],
                ls=ls,
                marker="o",
                color=colours.get(r["mode"]),
                label=f"{r['mode']} {lab}",
            )
            colours.setdefault(r["mode"], line.get_color())
    ax.set_xticks(range(len(BINS)), BINS)
    ax.set_xlabel("range bin (m)")
    ax.set_ylabel("AP@0.5")
    ax.set_ylim(0, 1)
    ax.grid(alpha=0.3)
    ax.legend(ncol=2, fontsize=8)
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100, metadata={"Software": None})
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("dirs", nargs="+", type=Path, help="study output folders (detection_table.csv), first = reference")
    ap.add_argument("--labels", default=None, help="comma-separated sea labels (default W1,W3)")
    ap.add_argument("--png", type=Path, default=None, help="write the AP-by-range picture here")
    ap.add_argument("--title", default="AP@0.5 by range at two sea states", help="the picture's title")
    args = ap.parse_args()
    labels = args.labels.split(",") if args.labels else ["W1", "W3", "W?"][: len(args.dirs)]
    if len(labels) != len(args.dirs) or len(args.dirs) < 2:
        ap.error("give two or more folders and as many labels")
    tables = [pl.read_csv((d / "detection_table.csv").read_bytes()) for d in args.dirs]
    print(markdown(tables, labels))
    if args.png is not None:
        plot(tables, labels, args.png, args.title)
        print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
