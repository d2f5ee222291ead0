"""``mmusv convert REC.mcap [REC ...] --to opv2v|kitti|ros2|coco|yolo|mastr|semantickitti|mot|kitti_tracking -o
DIR``: the command-line face of :func:`mmusv.export.convert`.

:func:`add_parser` adds the subcommand to the ``mmusv`` argparse sub-parsers and :func:`run` executes it (a rich
progress bar, then one line per recording and the totals). Bad input raises :class:`mmusv.errors.MmusvError`,
which the ``mmusv`` entry point prints as one line (exit status 2).
"""

from __future__ import annotations

import argparse
from typing import Any

from mmusv.errors import ConfigError
from mmusv.text import command_line

__all__ = ["FLAGS", "add_parser", "run"]

FLAGS = {
    "to": "--to",
    "out_dir": "-o/--output",
    "splits": "--split",
    "seed": "--seed",
    "eval_range_m": "--range",
    "include_usvs": "--include-usvs",
    "extras": "--extras",
    "min_box_px": "--min-box-px",
    "max_occlusion": "--max-occlusion",
    "min_contrast": "--min-contrast",
    "box": "--box",
    "overwrite": "--overwrite",
    "agents": "--agents",
    "frames": "--frames",
    "kitti_class": "--kitti-class",
    "oxts_origin": "--oxts-origin",
}
"""The flag of each argument of :func:`mmusv.export.convert`: its messages name these under ``mmusv convert``
(:func:`mmusv.text.command_line`), ``--range 100`` where a Python caller reads ``eval_range_m = 100``."""


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Adds ``convert`` to ``subparsers`` (the object ``ArgumentParser.add_subparsers`` returned)."""
    from mmusv.export.common import DEFAULT_EXTRAS, EXTRAS

    p: argparse.ArgumentParser = subparsers.add_parser(
        "convert",
        help="convert recordings into a dataset: OPV2V, KITTI, ROS 2 bags, COCO, YOLO, MaSTr, SemanticKITTI, "
        "MOTChallenge or KITTI tracking",
        description="Converts mmusv recordings into the OPV2V layout (CARLA frame, per-agent folders), KITTI-style "
        "per-agent folders, rosbag2 folders (one per recording), COCO or YOLO 2D detection sets, MaSTr1325-style "
        "obstacle/water/sky masks, SemanticKITTI LiDAR scans and labels, MOTChallenge tracking sequences (one per "
        "camera, gt.txt with a track id per vessel) or KITTI tracking sequences (one per agent: LiDAR scans, front "
        "images, label_02 with a track id per vessel), split into train/validate/test by recording with a fixed seed "
        "(docs/exports.md).",
    )
    p.add_argument(
        "recordings",
        nargs="+",
        help=".mcap files written by mmusv run (.mcap.partial accepted), .parts.json of split recordings, or "
        "batch output folders (their dataset.json)",
    )
    p.add_argument(
        "--to",
        default="opv2v",
        help="target layout: opv2v (default), kitti, ros2 (rosbag2 folders, never split), coco, yolo, mastr, "
        "semantickitti or mot (MOTChallenge: MOT17/MOT20 sequences for multi-object tracking) or kitti_tracking "
        "(the KITTI tracking benchmark's layout for 3D multi-object tracking)",
    )
    p.add_argument("-o", "--output", required=True, help="output folder")
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--split",
        default="0.7,0.15,0.15",
        help="train,validate,test fractions that add up to 1, or whole-number weights such as 7,2,1; by recording "
        "(default 0.7,0.15,0.15)",
    )
    g.add_argument(
        "--no-split", action="store_true", help="no train/validate/test folders: scenarios directly in the output"
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the split (default 0)")
    p.add_argument(
        "--range",
        type=float,
        default=200.0,
        dest="range_m",
        help="opv2v, kitti, kitti_tracking: evaluation range in metres, targets within R in BEV (default 200)",
    )
    p.add_argument(
        "--include-usvs",
        action="store_true",
        help="opv2v, kitti, kitti_tracking: list the other USVs as targets too (default: not, as in the paper)",
    )
    p.add_argument(
        "--extras",
        default=",".join(DEFAULT_EXTRAS),
        help=f"extra files of the OPV2V, KITTI and KITTI tracking exports (the others write none), comma-separated "
        f"from {','.join(EXTRAS)}; empty for none (default {','.join(DEFAULT_EXTRAS)})",
    )
    p.add_argument(
        "--min-box-px",
        type=float,
        default=0.0,
        help="coco, yolo, mot, ros2: leave out 2D boxes whose shorter side is under this many pixels (default 0)",
    )
    p.add_argument(
        "--max-occlusion",
        type=float,
        default=1.0,
        help="coco, yolo, mot, ros2: leave out 2D boxes hidden by more than this fraction, 0..1 (default 1: keep all; "
        "ros2's Detection2DArray then holds wholly hidden vessels too, with no field to say so)",
    )
    p.add_argument(
        "--min-contrast",
        type=float,
        default=None,
        metavar="C",
        help="coco, yolo, mot: leave out 2D boxes whose apparent (Weber) contrast in the recorded RGB image is under "
        "C, e.g. 0.05, the WMO's visibility threshold: vessels lost in fog, haze or the dark (default: keep all; needs "
        "instance images, also with --box projected)",
    )
    p.add_argument(
        "--box",
        default="visible",
        help="coco, yolo, mot: the 2D box written: visible (default: the tight box of the vessel's pixels in the "
        "instance image, COCO's bbox convention; yolo and mot then need instance images) or projected (the recording's "
        "box: the projected 3D box's part in the image, reaching down to the keel); kitti and ros2 keep the recorded "
        "box",
    )
    p.add_argument(
        "--agents",
        default=None,
        help="convert only these agents (USV ids, comma-separated, e.g. usv_1,usv_2); every recording must hold one",
    )
    p.add_argument(
        "--frames",
        default=None,
        metavar="START:STOP",
        help="convert only the acquisition indices START..STOP-1 (STOP may be left out: to the end)",
    )
    p.add_argument(
        "--kitti-class",
        default=None,
        metavar="NAME",
        help="kitti_tracking: the type written for every vessel, e.g. Car, the class stock TrackEval and the KITTI "
        "devkit score (default: each vessel's class name, Vessel or Usv)",
    )
    p.add_argument(
        "--oxts-origin",
        default=None,
        metavar="LAT,LON",
        help="kitti_tracking: the geodetic point (degrees) of the world origin in the oxts files' latitudes and "
        "longitudes, LAT in [-85, 85], LON in [-180, 180], e.g. --oxts-origin=-33.9,151.3 (with = before a minus) "
        "(default 45,-2: at sea in the Bay of Biscay)",
    )
    p.add_argument("--overwrite", action="store_true", help="replace a previous conversion in the output folder")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p


def run(args: argparse.Namespace) -> int:
    """Runs ``mmusv convert``; returns the exit status (0 when at least one frame was converted, 1 otherwise)."""

    from mmusv.cli_console import rich_console
    from mmusv.cli_paths import output_arg
    from mmusv.export.common import BOXES, TARGETS
    from mmusv.export.kitti_oxts import parse_origin

    if args.to not in TARGETS:
        raise ConfigError(f"unknown --to {args.to!r}; allowed: {', '.join(TARGETS)}")
    if args.box not in BOXES:
        raise ConfigError(
            f"unknown --box {args.box!r}; allowed: visible (the tight box of the vessel's visible pixels, the default) "
            "or projected (the recording's box: the projected 3D box's part in the image)"
        )
    output_arg(args.output)  # named as the flag, not as the API's out_dir
    origin = None
    if args.oxts_origin is not None:  # checked here, so that the message names the option as typed
        if args.to != "kitti_tracking":  # (before its value, as the API checks it)
            raise ConfigError(
                f"--oxts-origin {args.oxts_origin!r}: only --to kitti_tracking writes it, not --to {args.to}"
            )
        origin = parse_origin(args.oxts_origin)
    console = rich_console()
    kwargs: dict[str, Any] = {
        "to": args.to,
        "out_dir": args.output,
        "splits": None if args.no_split else args.split,
        "seed": args.seed,
        "eval_range_m": args.range_m,
        "include_usvs": args.include_usvs,
        "extras": args.extras,
        "min_box_px": args.min_box_px,
        "max_occlusion": args.max_occlusion,
        "min_contrast": args.min_contrast,
        "box": args.box,
        "overwrite": args.overwrite,
        "agents": args.agents,
        "frames": args.frames,
        "kitti_class": args.kitti_class,
        "oxts_origin": origin,
    }
    with command_line(FLAGS):  # convert's messages name these flags, not its keyword arguments
        report = _convert(args, console, kwargs)
    for line in report.lines():
        console.print(line, highlight=False, markup=False)
    return 0 if report.frames > 0 else 1


def _convert(args: argparse.Namespace, console: Any, kwargs: dict[str, Any]) -> Any:
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    from mmusv.export.conversion import convert

    if args.no_progress or not console.is_terminal:  # a bar only on a terminal (piped, it left an empty line)
        report = convert(args.recordings, **kwargs)
    else:
        with Progress(
            TextColumn(f"[bold]convert → {args.to}"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeRemainingColumn(),
            console=console,
            transient=True,
        ) as bar:
            task = bar.add_task("frames", total=None)
            report = convert(
                args.recordings, progress=lambda done, total: bar.update(task, completed=done, total=total), **kwargs
            )
    return report
