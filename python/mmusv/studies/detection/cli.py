"""``mmusv study detection`` (Table III) and ``mmusv study robustness`` (Table IV): the command-line faces of
:func:`mmusv.studies.detection.study.run_study`.

:func:`add_parsers` adds both to the ``study`` sub-parsers and :func:`run` executes one (rich progress bar, the
table, the files written). Bad input raises :class:`mmusv.errors.MmusvError`, printed by the ``mmusv`` entry
point as one line (exit status 2).
"""

from __future__ import annotations

import argparse
import contextlib
import time
from pathlib import Path
from typing import Any

from mmusv.learn.modes import MODELS, STUDY_NEEDS, fusion_modes, models_for
from mmusv.text import command_line, counted

__all__ = ["DATASET_FLAGS", "FLAGS", "add_dataset_arguments", "add_parsers", "run"]

DATASET_FLAGS = {
    "inputs": "recordings",
    "opv2v": "--opv2v",
    "generate": "--generate",
    "split": "--split",
    "ratios": "--split-ratios",
    "seed": "--seed",
}
"""The flags of the dataset a detection command reads (:func:`add_dataset_arguments`, ``--split``, ``--split-ratios``,
``--seed``) by the keyword arguments of :func:`~mmusv.studies.detection.sources.resolve_dataset` they give: ``mmusv
study`` and ``mmusv train`` call it within :func:`mmusv.text.command_line` of these, so its messages name the flags
(``--opv2v x: not a folder``) where a Python caller reads ``opv2v = 'x'``. ``generate_dataset``'s ``spec`` is
``--generate`` (a block of its own: the study's ``spec`` is ``--detector``)."""

FLAGS = {
    **DATASET_FLAGS,
    "spec": "--detector",
    "path": "--predictions",
    "predictions": "--predictions",
    "modes": "--modes",
    "settings": "--settings",
    "model": "--model",
    "jobs": "--jobs",
}
"""How ``mmusv study detection|robustness`` names the keyword arguments of the API it calls (:data:`DATASET_FLAGS`;
``load_detector``'s ``spec``, ``load_predictions``' ``path``, the :class:`~mmusv.studies.detection.study.StudyOptions`'
``predictions``, ``modes`` and ``settings``, ...): the study runs in :func:`mmusv.text.command_line` of these, and
its ``--jobs`` processes too (:mod:`mmusv.studies.detection.parallel`)."""

_BOXES_HELP = (
    "Parquet columns: sequence, frame, ego, [setting], mode, kind (det|gt), x, y, z, l, w, h, yaw "
    "(ego LiDAR frame, m, rad), score, range_bin, matched (at IoU 0.5), ego_points, neighbour_points (gt: "
    "LiDAR points inside from the ego / the other USVs), wave_occlusion (gt: the share of it the waves hide "
    "from the ego's LiDAR, from the recording's annotations; NaN where unknown)"
)


def add_dataset_arguments(p: argparse.ArgumentParser, *, into: str, then: str) -> None:
    """The dataset a detection command reads: ``inputs`` (recordings or folders), ``--opv2v`` or ``--generate
    [SPEC]`` (the bundled spec recorded LiDAR-only into the folder ``into``, then ``then``)."""
    from mmusv.studies.detection import BUNDLED_SPEC

    p.add_argument("inputs", nargs="*", help="recordings (.mcap) or folders of them")
    p.add_argument("--opv2v", default=None, help="an OPV2V folder written by mmusv convert --to opv2v")
    p.add_argument(
        "--generate",
        nargs="?",
        const=BUNDLED_SPEC,
        default=None,
        metavar="SPEC",
        help=f"generate SPEC (default {BUNDLED_SPEC}) and record it LiDAR-only into {into}, then {then}",
    )


def _common(p: argparse.ArgumentParser, default_out: str) -> None:
    add_dataset_arguments(p, into="OUT", then="evaluate")
    p.add_argument(
        "--split",
        default=None,
        help="train, validate, test or all (default: test with --generate, else all); the split is made by sequence",
    )
    p.add_argument(
        "--split-ratios", default="0.7,0.15,0.15", help="train,validate,test fractions (default 0.7,0.15,0.15)"
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the split and of the pose noise (default 0)")
    p.add_argument(
        "--modes",
        default=None,
        help="fusion modes, from none,late,early,intermediate (default none,late,early; with --model every mode "
        "its models serve; intermediate needs --model)",
    )
    p.add_argument(
        "--detector",
        default=None,  # None, not "baseline": --detector baseline given with --model or --predictions is refused
        help="'baseline' (training-free, not the paper's learned model; the default) or package.module:function, a "
        "callable (points (N,4) float32 ego LiDAR frame) -> (boxes (M,7) x,y,z,l,w,h,yaw, scores (M,))",
    )
    p.add_argument(
        "--model",
        default=None,
        metavar="CKPT",
        help="a learned model (mmusv train's output folder, or one model.pt; needs the learn extra): single "
        "serves none/late, early and intermediate their own",
    )
    p.add_argument(
        "--refine",
        choices=("auto", "on", "off"),
        default="auto",
        help="with --model: tighten the network's boxes on the LiDAR points (mmusv.learn.refine, geometric); "
        "auto (default) = on for cpu-preset models, where it was measured",
    )
    p.add_argument(
        "--rescore",
        choices=("auto", "on", "off"),
        default="auto",
        help="with --model: rank the refined boxes by each model's IoU scorer (mmusv.learn.scorer, scorer.pt "
        "beside model.pt, fitted by mmusv train); auto (default) = where a model has one and boxes are refined",
    )
    p.add_argument(
        "--threads",
        type=int,
        default=None,
        help="with --model: torch's CPU threads for the learned models, in this process and in each --jobs process "
        "(default 1: the same bytes with any --jobs and on any machine; the outputs of a network depend on its "
        "thread count, the order of its float sums). More threads run faster where no other work shares the cores: "
        "torch's waiting threads spin, and two studies side by side with torch's own default (one per core) had "
        "not finished Table III after 28 minutes, which one thread each did in 3",
    )
    p.add_argument(
        "--late-merge",
        choices=("nms", "wbf"),
        default="nms",
        help="how late fusion merges the USVs' boxes: nms (rotated NMS at BEV IoU 0.1, default) or wbf "
        "(score-weighted box fusion at IoU 0.3, noisy-OR score of the agreeing USVs)",
    )
    p.add_argument(
        "--predictions",
        default=None,
        help="a Parquet of detections instead of a detector (layout of "
        "the boxes Parquet this command writes, kind=det rows)",
    )
    p.add_argument(
        "--range", dest="range_m", type=float, default=200.0, help="evaluation range in metres (default 200)"
    )
    p.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="processes, one sequence each (default 1); the tables and boxes are the same with any number "
        "(mmusv.studies.detection.parallel). With --model each runs torch on --threads threads (default 1), as "
        "--jobs 1 does",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("-o", "--output", default=default_out, help=f"output folder (default {default_out})")
    p.add_argument(
        "--overwrite", action="store_true", help="replace the files of its names already in -o (and -o/baseline)"
    )


def add_parsers(studies: Any) -> None:
    """Adds ``detection`` and ``robustness`` to ``studies`` (the ``study`` command's sub-parsers)."""
    det = studies.add_parser(
        "detection",
        help="Table III: no / late / early fusion AP by IoU and range",
        description="Cooperative 3D detection benchmark (Table III). " + _BOXES_HELP,
    )
    _common(det, "out/detection_study")
    rob = studies.add_parser(
        "robustness",
        help="Table IV: AP@0.5 under fixed delay and pose noise",
        description="Robustness of late and early fusion (Table IV). " + _BOXES_HELP,
    )
    _common(rob, "out/robustness_study")
    rob.add_argument(
        "--settings",
        default="delay:1,delay:2,delay:3,noise:0.5/0.5,noise:1/1,noise:2/2",
        help="delay:K (frames) and noise:SIGMA_XYZ_M/SIGMA_RPY_DEG items (noise:S = noise:S/S; clean is always "
        "included). A frame k is scored where the frame k-K of every delay was recorded",
    )


def run(args: argparse.Namespace) -> int:
    """Runs ``mmusv study detection|robustness``; returns the exit status. Its messages, and those of the API it
    calls, name its flags (:data:`FLAGS`)."""
    with command_line(FLAGS), contextlib.ExitStack() as stack:
        return _run(args, stack)


def _run(args: argparse.Namespace, stack: contextlib.ExitStack) -> int:
    from rich.text import Text

    from mmusv import arguments
    from mmusv.cli_console import rich_console
    from mmusv.cli_paths import check_output_folder, made_output_folder, path_arg
    from mmusv.errors import InputError
    from mmusv.learn.cli import check_threads, split_ratios
    from mmusv.studies.detection.data import check_split
    from mmusv.studies.detection.detector import BASELINE_NOTE, load_detector
    from mmusv.studies.detection.fusion import parse_modes
    from mmusv.studies.detection.predictions import check_prediction_coverage, load_predictions
    from mmusv.studies.detection.robustness import Setting, parse_settings
    from mmusv.studies.detection.sources import generate_dataset, resolve_dataset
    from mmusv.studies.detection.study import StudyOptions, run_study

    robust = args.study == "robustness"
    console = rich_console()  # text as it is: a path holding brackets is no markup
    learned = None
    tri = {"auto": None, "on": True, "off": False}
    if args.jobs < 1:
        raise InputError(f"--jobs {args.jobs}: must be >= 1")
    # Paths before anything is read: an empty one meant the current folder (-o "" wrote the tables there), and an
    # -o that is a file was named only after the evaluation.
    for item in args.inputs:
        path_arg(item, flag="recording")
    for flag, value in (("--opv2v", args.opv2v), ("--predictions", args.predictions), ("--model", args.model)):
        if value is not None:
            path_arg(value, flag=flag)
    out = check_output_folder(args.output)
    ratios = split_ratios(args.split_ratios)
    # before --generate, which refused a bad --split or --seed only after generating and recording the whole dataset
    # (a pre-split OPV2V folder's --split takes no seed)
    check_split(args.split or ("test" if args.generate is not None else "all"), args.seed if args.opv2v is None else 0)
    # --range: a finite distance (inf was taken, and cropped the clouds at inf metres)
    range_m = arguments.real(args.range_m, name="--range", unit="metres", above=0.0, error=InputError)
    if args.model is not None:
        check_threads(args.threads)  # before the models load: 10**11 was a torch traceback
        if args.predictions is not None or args.detector is not None:
            raise InputError("give one of --model, --detector or --predictions")
        from mmusv.learn.cli import load_for_study

        # only the models the asked --modes run (one damaged or of another training stopped a study not running it)
        with command_line({"text": "--modes"}):
            asked = parse_modes(args.modes) if args.modes is not None else None
        if asked is not None:
            _check_folder_modes(args.model, asked)
        learned = load_for_study(args.model, refine=tri[args.refine], rescore=tri[args.rescore], modes=asked)
    if args.model is None and (args.refine != "auto" or args.rescore != "auto"):
        flag = f"--refine {args.refine}" if args.refine != "auto" else f"--rescore {args.rescore}"
        raise InputError(f"{flag}: only with --model (the learned detector's second stage)")
    if args.threads is not None and args.model is None:
        raise InputError(f"--threads {args.threads}: only with --model (torch's threads of the learned models)")
    if args.model is not None:
        import torch

        # 1 when left out, as in every --jobs process: a network's outputs depend on torch's thread count (the order
        # of its float sums), and torch's default (one per core) here gave other scores with --jobs 1 than --jobs N
        torch.set_num_threads(args.threads or 1)
    default_modes = ",".join(learned.fusion_modes) if learned is not None else "none,late,early"
    with command_line({"text": "--modes"}):
        modes = parse_modes(default_modes if args.modes is None else args.modes)  # "" was taken as the default
    if learned is not None:
        _check_model_modes(args.model, tuple(learned.models), modes)
    mixed = _mixed_training(args.model, learned, modes) if learned is not None else None
    if mixed is not None:
        import warnings

        from mmusv.scenario_checks import MmusvWarning

        warnings.warn(mixed, MmusvWarning, stacklevel=2)
    with command_line({"text": "--settings"}):
        settings = parse_settings(args.settings) if robust else (Setting(),)
    if robust and not any(m != "none" for m in modes):
        raise InputError("--modes: the robustness study needs late and/or early fusion")
    if args.predictions is not None and args.detector is not None:
        raise InputError("give --detector or --predictions, not both")
    chosen = args.detector if args.detector is not None else "baseline"
    detector = learned if learned is not None else None if args.predictions is not None else load_detector(chosen)
    detector_name = f"learned model {args.model}" if learned is not None else chosen
    runs: list[tuple[Any, str, tuple[str, ...], Path]] = [(detector, detector_name, modes, out)]
    if learned is not None:  # the learned model beside the baseline, on the same frames
        base_modes = tuple(m for m in modes if m != "intermediate")
        if base_modes and (not robust or any(m != "none" for m in base_modes)):
            runs.append((load_detector("baseline"), "baseline", base_modes, out / "baseline"))
    # the files of its names already there (a user's detection_table.csv) were replaced without a word, after the
    # whole study (and --generate's recording)
    from mmusv.cli_paths import refuse_replacing
    from mmusv.studies.detection.report import DETECTION_FILES, ROBUSTNESS_FILES

    names = ROBUSTNESS_FILES if robust else DETECTION_FILES
    refuse_replacing(
        out, [str(run_out.relative_to(out) / n) for *_, run_out in runs for n in names], overwrite=args.overwrite
    )
    predictions = load_predictions(args.predictions) if args.predictions is not None else None
    if predictions is not None:
        check_prediction_coverage(args.predictions, predictions, modes=modes, settings=settings)
    # made (or named when it cannot be) before the work, which failed writing the tables after the whole study;
    # removed again if still empty when the study fails or is interrupted
    stack.enter_context(made_output_folder(args.output))
    t0 = time.perf_counter()
    inputs: list[Any] = list(args.inputs)
    if args.generate is not None:
        if inputs or args.opv2v:
            raise InputError("--generate makes its own recordings: give no recordings and no --opv2v with it")
        from rich.markup import escape

        shortfalls: list[str] = []
        with (
            _bar(console, "generate + record (LiDAR-only)", args.no_progress) as (bar, task),
            command_line({"spec": "--generate"}),
        ):
            inputs = generate_dataset(
                out / "dataset",
                spec=args.generate,
                progress=lambda name, done, total: (
                    bar.update(task, completed=done, total=total) if bar is not None else None
                ),
                shortfall=shortfalls.append,
            )
        for line in shortfalls[1:]:
            console.print(f"[yellow]generate: {escape(line)}[/]", markup=True, highlight=False)
        short = f" (quotas not met: {shortfalls[0]})" if shortfalls else ""
        console.print(
            f"dataset: {counted(len(inputs), 'recording')} "
            f"in {out / 'dataset'}{short} ({time.perf_counter() - t0:.1f} s)",
            highlight=False,
        )
    split = args.split or ("test" if args.generate is not None else "all")
    dataset = resolve_dataset(inputs, opv2v=args.opv2v, split=split, ratios=ratios, seed=args.seed)
    learned_notes: list[str] = []
    if learned is not None:
        from rich.markup import escape

        learned_notes.append(f"learned models: {learned.describe()}")
        if mixed is not None:
            learned_notes.append(f"warning: {mixed}")
        leak = _training_overlap(learned, dataset)
        if leak:
            console.print(f"[yellow]{escape(leak)}[/]", markup=True, highlight=False)
            learned_notes.append(leak)
    from mmusv.studies.detection import report

    files: report.Files = {}  # every run's report, written once all are computed (module docstring of report)
    for det, name, run_modes, run_out in runs:
        options = StudyOptions(
            modes=run_modes,
            settings=settings,
            detector=det,
            predictions=predictions,
            range_m=range_m,
            seed=args.seed,
            late_merge=args.late_merge,
        )
        total = dataset.count_frames()
        t1 = time.perf_counter()
        with _bar(console, f"{args.study} study ({name})", args.no_progress) as (bar, task):
            show = (lambda done, tot: bar.update(task, completed=done, total=tot)) if bar is not None else None
            if args.jobs > 1:
                from mmusv.studies.detection.parallel import DetectorSpec, run_study_jobs

                if learned is not None and det is learned:
                    spec = DetectorSpec(
                        model=args.model,
                        refine=tri[args.refine],
                        rescore=tri[args.rescore],
                        threads=args.threads or 1,
                        modes=modes,
                    )
                elif det is None:
                    spec = DetectorSpec(predictions=args.predictions)
                else:
                    spec = DetectorSpec(detector=name)  # the run's detector name: --detector, or the baseline beside
                res, nbytes = run_study_jobs(dataset, options=options, spec=spec, jobs=args.jobs, progress=show)
                if learned is not None and det is learned:
                    learned.shared_bytes.extend(nbytes)
            else:
                res = run_study(dataset.sequences(), options=options, total_frames=total, progress=show)
        if res.ego_frames == 0:
            delay = max(s.delay_frames for s in settings)
            why = (
                f" (the robustness study leaves out the first {counted(delay, 'frame')} of every "
                f"sequence: --settings holds "
                f"delay:{delay})"
                if delay > 0
                else f" ({counted(len(res.none_only), 'sequence')} of one USV with a LiDAR, nothing to fuse: "
                f"{', '.join(res.none_only)}; add none to --modes to score them without fusion)"
                if res.none_only
                else ""
            )
            raise InputError(
                f"empty dataset: the {len(dataset.sources)} sequence(s) of split {split!r} hold no frame to "
                f"evaluate{why}"
            )
        eval_s = time.perf_counter() - t1
        if len(runs) > 1:
            console.print(Text(name, style="bold"), highlight=False)
        notes = learned_notes if det is learned and learned is not None else []
        if robust:
            made = report.robustness_files(res, run_out, detector=name, notes=notes)
            _print_robustness(console, res)
        else:
            made = report.detection_files(res, run_out, detector=name, notes=notes)
            _print_detection(console, res)
        files.update({f"{name}:{k}": v for k, v in made.items()})
        lone = report.none_only_line(res)
        if lone is not None:
            from rich.markup import escape

            console.print(f"[yellow]{escape(lone)}[/]", markup=True, highlight=False)
        if det is learned and learned is not None:
            console.print(f"learned models: {learned.describe()}", highlight=False)
            if learned.shared_bytes:
                kb = sum(learned.shared_bytes) / len(learned.shared_bytes) / 1024
                console.print(
                    f"intermediate fusion: {kb:.1f} KiB shared per ego-frame on average (the neighbours' pillar "
                    f"features, float32, and cells; {counted(len(learned.shared_bytes), 'ego-frame')})",
                    highlight=False,
                )
        elif det is not None and name == "baseline":
            console.print(Text(BASELINE_NOTE, style="yellow"))
        if any(m == "late" for m in run_modes):
            console.print(f"late fusion merge: {args.late_merge}", highlight=False)
        console.print(
            f"split {split}: {counted(len(res.sequences), 'sequence')}, {counted(res.frames, 'frame')}, "
            f"{counted(res.ego_frames, 'ego-frame')}, "
            f"{res.gt_boxes / max(res.ego_frames, 1):.2f} ground-truth boxes per ego-frame; evaluation "
            f"{eval_s:.1f} s, total {time.perf_counter() - t0:.1f} s",
            highlight=False,
        )
    paths = report.write_files(files)
    console.print("wrote " + ", ".join(str(p) for p in paths.values()), highlight=False)
    return 0


def _check_model_modes(model: str, held: tuple[str, ...], modes: tuple[str, ...]) -> None:
    """Refuses fusion ``modes`` the models ``held`` at ``--model`` (``single``, ``early``, ``intermediate``) cannot
    run, before any frame is read (the error came from the first frame, naming the missing model but not the mode
    asked for)."""
    from mmusv.errors import InputError

    missing = [m for m in modes if STUDY_NEEDS[m] not in held]
    if missing:
        needs = models_for(missing)
        raise InputError(
            f"--modes {','.join(missing)}: needs the {' and '.join(needs)} model{'s' if len(needs) > 1 else ''}, "
            f"which --model {model} does not "
            f"hold (it has {', '.join(held)}: modes {','.join(fusion_modes(held))}; train it with "
            "mmusv train --modes)"
        )


def _check_folder_modes(model: str, modes: tuple[str, ...]) -> None:
    """Refuses fusion ``modes`` of which a ``--model`` folder of models (``OUT/single``, ``OUT/early``, ...) holds no
    model, by :func:`_check_model_modes`, before any is loaded: only the models the modes run are loaded, and
    ``--modes early`` with ``OUT`` holding ``single`` alone said "--model OUT: no model.pt there"."""
    p = Path(model)
    if not p.is_dir() or (p / "model.pt").is_file():  # a model.pt or a model's own folder: its file says its mode
        return
    held = tuple(m for m in MODELS if (p / m / "model.pt").is_file())
    if held and not set(models_for(modes)) & set(held):
        _check_model_modes(model, held, modes)


def _mixed_training(model: str, learned: Any, modes: tuple[str, ...]) -> str | None:
    """A warning line when the models the fusion ``modes`` run (``--model``'s ``single``, ``early``,
    ``intermediate``) were trained with other presets or seeds (a folder put together from several runs): the modes
    compared models of different training, not fusion alone, without a word."""
    used = [m for m in learned.models if m in models_for(modes)]

    def seed(v: Any) -> str:
        return f"seed {v}" if v is not None else "seed not recorded"

    how = {m: (learned.info[m].get("preset"), learned.info[m].get("seed")) for m in used}
    if len(set(how.values())) < 2:
        return None
    each = "; ".join(f"{m}: preset {p}, {seed(s)}" for m, (p, s) in how.items())
    return (
        f"--model {model}: its models were trained with other presets or seeds ({each}), so the modes they serve "
        "differ by training as well as by fusion; train them in one mmusv train run (one --preset and --seed, "
        f"--modes {','.join(used)})"
    )


def _training_overlap(learned: Any, dataset: Any) -> str | None:
    """A warning line when sequences evaluated were in a model's training data (the same name and fingerprint:
    :meth:`mmusv.learn.detector.LearnedDetector.trained_on`): a model trained with another ``--seed`` or
    ``--split-ratios`` than the study's, or on ``--split all``, was scored on what it learnt from without a word."""
    from mmusv.learn.cache import dataset_fingerprints

    seen = learned.trained_on(dataset_fingerprints(dataset))
    if not seen:
        return None
    names = sorted({n for v in seen.values() for n in v})
    shown = ", ".join(names[:6]) + (f" and {len(names) - 6} more" if len(names) > 6 else "")
    how: dict[str, list[str]] = {}
    for mode in seen:
        data = learned.info[mode].get("data") or {}
        seed = data.get("seed", learned.info[mode].get("seed"))
        ratios = ",".join(f"{r:g}" for r in data.get("ratios", []))
        how.setdefault(f"split {data.get('split', '?')!r} made with --seed {seed} --split-ratios {ratios}", []).append(
            mode
        )
    trained = "; ".join(f"{' and '.join(m)}: {h}" for h, m in how.items())
    return (
        f"warning: {len(names)} of the {counted(len(dataset.sources), 'sequence')} evaluated "
        f"({shown}) {'is' if len(names) == 1 else 'are'} in the training data "
        f"of the learned models ({trained}): their scores are not held-out; evaluate a split made with the same "
        "--seed and --split-ratios"
    )


class _bar:
    """A rich progress bar (or none) as a context manager yielding ``(progress or None, task id)``."""

    def __init__(self, console: Any, title: str, off: bool) -> None:
        self.console, self.title, self.off = console, title, off
        self.progress: Any = None

    def __enter__(self) -> tuple[Any, Any]:
        if self.off:
            return None, None
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self.progress = Progress(
            TextColumn(f"[bold]{self.title}"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeElapsedColumn(),
            TimeRemainingColumn(),
            console=self.console,
            transient=True,
        )
        self.progress.__enter__()
        return self.progress, self.progress.add_task(self.title, total=None)

    def __exit__(self, *exc: object) -> None:
        if self.progress is not None:
            self.progress.__exit__(*exc)


def _print_detection(console: Any, res: Any) -> None:
    from rich.table import Table

    from mmusv.studies.detection.report import DETECTION_METRICS, detection_table, fmt

    t = detection_table(res)
    table = Table(title="Cooperative detection (Table III)")
    shown = [(column, heading) for column, heading in DETECTION_METRICS if heading]
    for h in ["mode", *(heading for _, heading in shown)]:
        table.add_column(h, justify="right")
    for r in t.iter_rows(named=True):
        table.add_row(r["mode"], *[fmt(r[column]) for column, _ in shown])
    console.print(table)
    r0 = t.row(0, named=True)
    console.print(
        f"ground truth: {int(r0['gt'])} boxes: {int(r0['gt_visible'])} visible to the ego, "
        f"{int(r0['gt_hidden'])} hidden from it but seen by neighbours, {int(r0['gt_unseen'])} seen by "
        "neither (seen = at least 5 LiDAR points inside); " + _wave_line(res, int(r0["gt_wave_hidden"])),
        highlight=False,
    )


def _wave_line(res: Any, hidden: int) -> str:
    """How many ground truths the waves hide at least half of from the ego, or that the source does not say (an
    OPV2V folder, a recording made before the shares were recorded)."""
    import math

    shares = [w for w, k in zip(res.rows["wave_occlusion"], res.rows["kind"], strict=True) if k == "gt"]
    if shares and all(w is None or math.isnan(w) for w in shares):
        return "the source gives no wave-occlusion shares"
    return f"{hidden} at least half hidden from the ego by the waves"


def _print_robustness(console: Any, res: Any) -> None:
    from rich.table import Table

    from mmusv.studies.detection.report import fmt, robustness_table

    w = robustness_table(res)
    table = Table(title="Robustness: AP@0.5 (Table IV)")
    modes = [m for m in ("none", "late", "early", "intermediate") if m in w.columns]
    table.add_column("setting")
    for m in modes:
        table.add_column(m, justify="right")
    for r in w.iter_rows(named=True):
        table.add_row(r["setting"], *[fmt(r[m]) for m in modes])
    console.print(table)
