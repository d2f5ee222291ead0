"""The main job: run a scenario and stream every frame into one MCAP recording plus Parquet tables.

``run(cfg, out_dir=...)`` (also ``mmusv.run`` and ``mmusv run FILE -o DIR``) validates the scenario before
anything is written, builds the :class:`~mmusv.simulation.Simulation`, then for every acquisition index k
captures every sensor of every USV on the frozen state of t_k = k / f, derives the annotations and writes them
(Algorithm 1 of the paper). Frames are written as they are produced, so memory stays flat however long the
run; tables are flushed to Parquet parts every ``TABLE_PART_FRAMES`` frames.

No core waits: all sensors of a frame run in one native call (:meth:`~mmusv.simulation.Simulation.capture`),
and frame k is written (images encoded in parallel, MCAP, tables) on a writer thread while frame k+1 is
captured (:mod:`mmusv.recording.background`; at most one frame waits between the two, so memory stays flat); a run
without cameras annotates it there too (the annotations of a capture read the scene only for what a run never
changes: its sea instance and whether waves are set; everything else comes from the capture itself). One thread
writes every frame in order, so the files are byte-identical to doing it all one frame after another.

Output in ``out_dir``: ``<name>.mcap`` (see ``docs/recording.md``), ``tables/{world_state,boxes_3d,boxes_2d}/
part-NNNNN.parquet`` (polars), ``scenario.yaml`` (the resolved scenario) and ``manifest.json``. A run stopped by
Ctrl-C or an error still finishes the MCAP (every completed frame is in it, its ``run`` metadata says
``status: interrupted`` or ``failed``) and the tables of the completed frames.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from threadpoolctl import threadpool_limits

from mmusv import arguments
from mmusv.agent_annotations import Annotations
from mmusv.annotate import annotate_agent
from mmusv.config import Scenario, load_scenario, scenario_hash
from mmusv.errors import ConfigError, IoError, MmusvError, located
from mmusv.forking import check_polars
from mmusv.held_signals import HeldSignals, raise_noted_stop, stops_unwrapped
from mmusv.jsonio import dump_json, write_bytes_atomic
from mmusv.profiling import RunProfile, clocks
from mmusv.recording.background import BackgroundWriter
from mmusv.recording.guard import FolderLock, write_cause
from mmusv.recording.tables import TableWriter
from mmusv.run_folder import (
    refuse_earlier_run,
    refuse_foreign_files,
    refuse_wrong_kinds,
    replace_outputs,
    write_failure,
    writes_into,
)
from mmusv.scenario_checks import (
    check_lidar_water,
    check_mounts,
    check_rain_visibility,
    check_routes,
    check_sensors,
    check_top_view_land,
)
from mmusv.silhouettes import SilhouetteCache
from mmusv.simulation import FrameCapture, Simulation

__all__ = ["TABLE_PART_FRAMES", "RunResult", "recording_path", "run"]

TABLE_PART_FRAMES = 200


@dataclass
class RunResult:
    """What a run wrote and how it ended.

    Attributes:
        recording: the MCAP file written, ``out_dir/<scenario name>.mcap``.
        tables: the folder of the Parquet tables, ``out_dir/tables`` (``world_state``, ``boxes_3d``, ``boxes_2d``).
        frames_written: acquisition indices recorded whole (every sensor, annotation and table row of each).
        status: ``complete``, ``interrupted`` or ``failed`` (what the recording's ``run`` metadata says;
            :func:`run` returns only complete runs and raises otherwise, after finishing the recording).
        seconds: wall-clock seconds of the whole run (checks, world building, every frame, finishing).
        messages: MCAP messages in the recording, every topic.
        bytes: size of the MCAP file in bytes.
        error: ``"<ExceptionType>: <message>"`` of what failed the run, else ``None``.
        frame_seconds: wall-clock seconds of each frame, in acquisition order (capture, annotation and handing
            it to the writer; the first includes the first capture made before anything was written).
        profile: per-stage times with ``run(..., profile=True)`` (:class:`~mmusv.profiling.RunProfile`), else
            ``None``.
    """

    recording: Path
    tables: Path
    frames_written: int
    status: str
    seconds: float
    messages: int = 0
    bytes: int = 0
    error: str | None = None
    frame_seconds: list[float] = field(default_factory=list)
    profile: RunProfile | None = None


def recording_path(out_dir: Path, scenario: Scenario) -> Path:
    """Where the MCAP of ``scenario`` goes in ``out_dir``."""
    return out_dir / f"{scenario.name}.mcap"


@dataclass(frozen=True, eq=False)
class _Frame:
    """One captured and annotated frame on its way to the writer: the capture and, per agent, its
    :class:`~mmusv.agent_annotations.Annotations` with their ``columns()``."""

    capture: FrameCapture
    annotations: dict[str, tuple[Annotations, dict[str, Any]]]


def annotations_for(sim: Simulation, cap: FrameCapture, silhouettes: SilhouetteCache) -> dict[str, Annotations]:
    """Every agent's annotations of one captured frame. Safe on another thread while ``sim`` captures the next
    frame (a recording annotates on its writer thread): everything of the frame comes from ``cap``, and the scene
    is read only for what a run never changes (its sea instance, whether waves are set), since a capture gives
    each box's first hits itself (the cameras' instance images, the LiDAR's beams)."""
    out: dict[str, Annotations] = {}
    silhouettes.assets = sim.assets  # the vessels as sim was built with them, not as the library holds them now
    for agent in sim.agents:
        ac = cap.agents.get(agent.id)
        if ac is None:
            continue
        cams = {
            name: (agent.cameras[name][0], ac.camera_poses[name], img.instance, agent.cameras[name][1].range_m)
            for name, img in ac.cameras.items()
        }
        rng = agent.rig.lidar.range_m if agent.rig.lidar is not None else 200.0
        out[agent.id] = annotate_agent(
            agent_id=agent.id,
            agent_index=agent.index,
            frame=cap.frame,
            time_s=cap.time_s,
            vessels=sim.vessels,
            state=cap.world,
            lidar_pose=ac.lidar_pose,
            lidar_instances=ac.lidar.instance if ac.lidar is not None else None,
            cameras=cams,
            silhouettes=silhouettes,
            max_range_m=rng,
            scene=sim.ws.scene,
            lidar_pattern=agent.lidar_pattern,
            lidar_beams=ac.lidar_beams,
        )
    return out


def run(
    cfg: Any,
    *,
    out_dir: str | Path = "out",
    overwrite: bool = False,
    frames: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    checks: bool = True,
    frame_range: tuple[int, int] | None = None,
    profile: bool = False,
    notes: list[str] | None = None,
    check_frames: int | None = None,
) -> RunResult:
    """Runs a scenario (a YAML path, a dict or a :class:`~mmusv.config.Scenario`) into ``out_dir``.

    Args:
        out_dir: output folder (a ``str`` or ``os.PathLike``, not empty; created).
        overwrite: replace an existing recording of the same scenario name; otherwise that is an error.
        frames: run only the first ``frames`` indices, a whole number (``int`` or numpy integer) in
            ``1..acquisition.frames`` (default: the scenario's ``acquisition.frames``).
        progress: called (on the calling thread) with (frames done, frames total) after every frame has been
            captured, annotated and handed to the writer; a callable taking two arguments, checked before the run.
        frame_range: ``(first, stop)``, two whole numbers: run only acquisition indices ``first .. stop - 1`` (one
            part of a recording split into frame ranges, :mod:`mmusv.batch`); every frame is the same as in a whole
            run (each frame is captured from its own frozen state and seeds). Not together with ``frames``.
        checks: run the generator's route checks on the map (:mod:`mmusv.scenario_checks`): a route over land
            is an error, clearance and separation problems and far-away mounts are warnings.
        profile: time every stage (each sensor, annotation, encoding, writing, the rest) into
            ``RunResult.profile`` (:class:`~mmusv.profiling.RunProfile`); the output bytes are the same.
        notes: lines for the user are appended here (an interrupted run found and recorded again).
        check_frames: the route checks cover acquisition indices ``0 .. check_frames - 1``, a whole number from the
            last index this run records + 1 to ``acquisition.frames`` (default: up to the last index it records). The
            parts of a split batch (:mod:`mmusv.batch`) pass the whole run's, so that every part finds and says what
            the whole run would (the batch reports a scenario's warnings once).

    The folder is locked while the run writes it (:class:`~mmusv.recording.guard.FolderLock`): a second run into
    the same folder fails at once. A ``.partial`` recording left by a killed run is recorded again from scratch
    (a clean redo; ``notes`` says so). An earlier run's ``manifest.json``, table parts and ``scenario.yaml`` are
    replaced only once the new recording is open (a stop before it starts to open, or a recording that cannot be
    opened, leaves that run whole; a stop while it opens ends the run as one during a frame does, ``interrupted``),
    and its recording only when the new one is finished.

    The first frame is captured before anything is written: a failure there (a setting a sensor refuses only when
    it captures, a capture that cannot be made) leaves the folder as it was, an earlier run in it included.

    Raises:
        ConfigError: the scenario or an argument is invalid, or the first frame cannot be captured (nothing is
            written); flags (``overwrite``, ``checks``, ``profile``) must be ``bool``.
        IoError: the output exists and ``overwrite`` is false, another run writes the folder, a name the run
            writes there is taken by the wrong kind (a file named ``tables``, a folder named ``manifest.json``:
            refused before anything is written), or it cannot be written (the message names the cause, e.g.
            ``No space left on device``, and the frames that are safe).
        KeyboardInterrupt: re-raised after the recording was finished with every completed frame (``status:
            interrupted``); under the ``mmusv`` command also for an error a library made of the stop during a frame
            (raised from that error: :func:`mmusv.held_signals.stops_unwrapped`).
    """

    from mmusv.batch.executors import refuse_in_worker_import

    refuse_in_worker_import("mmusv.run")  # the top level of a script a batch's worker imports: said at once
    check_polars("mmusv.run")  # a process forked after Polars started (it writes the tables): said at once
    # The arguments' types first (cheap, and before anything is built or written), their ranges once the scenario
    # says how many frames it has.
    out = arguments.path(out_dir, name="out_dir")
    overwrite = arguments.flag(overwrite, name="overwrite")
    checks = arguments.flag(checks, name="checks")
    profile = arguments.flag(profile, name="profile")
    progress = arguments.callback(progress, name="progress", nargs=2)
    if notes is not None and not isinstance(notes, list):
        raise ConfigError(f"notes = {arguments.shown(notes)}: must be a list (lines are appended to it), or None")
    count = None if frames is None else arguments.whole(frames, name="frames")
    span = None if frame_range is None else _frame_range(frame_range)
    if isinstance(cfg, (str, os.PathLike)) and os.path.isdir(cfg):  # False, not OSError, for text given as cfg
        raise ConfigError(
            f"{cfg} is a directory; mmusv.run takes one scenario file (run a folder with `mmusv run {cfg} -o OUT`)"
        )
    source = str(cfg) if isinstance(cfg, (str, os.PathLike)) else "scenario"
    scenario = load_scenario(cfg)
    total = scenario.acquisition.frames if count is None else count
    if not 1 <= total <= scenario.acquisition.frames:
        raise ConfigError(
            f"frames = {frames} (mmusv run --frames): must be in 1..{scenario.acquisition.frames}, the "
            f"acquisition.frames of {source}"
        )
    first = 0
    if span is not None:
        if frames is not None:
            raise ConfigError("give frames or frame_range, not both")
        first, total = span
        if not 0 <= first < total <= scenario.acquisition.frames:
            raise ConfigError(
                f"frame_range = {span}: must be (first, stop) with 0 <= first < stop <= "
                f"{scenario.acquisition.frames}, the acquisition.frames of {source}"
            )
        frame_range = span
    checked = total
    if check_frames is not None:
        checked = arguments.whole(check_frames, name="check_frames")
        if not total <= checked <= scenario.acquisition.frames:
            raise ConfigError(
                f"check_frames = {check_frames}: must be in {total}..{scenario.acquisition.frames} (from the frames "
                f"this run records to the acquisition.frames of {source})"
            )
    rec_path = recording_path(out, scenario)
    refuse_wrong_kinds(out, rec_path)
    refuse_earlier_run(out, rec_path, overwrite=overwrite)
    refuse_foreign_files(out, cfg)
    try:  # builds the world: any remaining config problem surfaces here, before writing
        sim = Simulation(scenario)
    except MmusvError as exc:
        raise located(exc, source) from None
    check_sensors(scenario, source=source)  # not checks of the map: said with or without checks
    check_rain_visibility(scenario, source=source)
    if checks:
        check_mounts(scenario, source=source)
        check_lidar_water(scenario, source=source)
        # The routes as far as this run sails them, frames 0 .. total - 1 (the stop of a frame range), or as far as
        # the whole run a part belongs to (check_frames).
        upto = scenario.acquisition.model_copy(update={"frames": checked})
        check_routes(scenario.model_copy(update={"acquisition": upto}), sim.world, source=source)
        check_top_view_land(sim, range(first, total), source=source)
    # The first frame is captured before anything is written or replaced: whatever a sensor refuses only when it
    # captures (or any other failure of a capture) fails the run here, with the folder as it was.
    started = clocks()  # the run's clocks start with its first frame
    try:
        first_capture = sim.capture(first)
    except MmusvError as exc:
        raise located(exc, source) from None
    captured = [(first_capture, time.perf_counter() - started[0])]
    del first_capture
    lock = FolderLock.create(out, what="mmusv run")  # a second run into `out` refuses at once
    try:
        # numpy's BLAS on one thread while recording (restored after): the loop's products are skinny, (N, 3) by
        # (3, 3), which OpenBLAS spreads over its threads for five times the CPU, its idle workers then spinning on
        # the cores the sensors use.
        with threadpool_limits(limits=1, user_api="blas"):
            return _record(
                scenario,
                sim,
                out,
                rec_path,
                overwrite,
                first,
                total,
                frame_range,
                progress,
                profile,
                notes=notes,
                captured=captured,
                started=started,
            )
    finally:
        lock.release()


def _frame_range(value: Any) -> tuple[int, int]:
    """``run``'s ``frame_range`` as ``(first, stop)``: a tuple or list of exactly two whole numbers."""
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        raise ConfigError(
            f"frame_range = {arguments.shown(value)}: must be (first, stop), two whole numbers (acquisition indices "
            "first .. stop - 1)"
        )
    return (
        arguments.whole(value[0], name="frame_range[0] (first)"),
        arguments.whole(value[1], name="frame_range[1] (stop)"),
    )


def _record(
    scenario: Scenario,
    sim: Simulation,
    out: Path,
    rec_path: Path,
    overwrite: bool,
    first: int,
    total: int,
    frame_range: tuple[int, int] | None,
    progress: Callable[[int, int], None] | None,
    profile: bool,
    *,
    notes: list[str] | None,
    captured: list[tuple[FrameCapture, float]],
    started: tuple[float, float],
) -> RunResult:
    """The recording part of :func:`run`, with the folder locked; ``captured`` holds frame ``first``, captured
    before anything was written, and the seconds it took (taken from the list, so it is freed once written);
    ``started``: the clocks (:func:`~mmusv.profiling.clocks`) read when that capture began, from which the run's
    seconds and its profile count."""
    from mmusv.recording.frames import FrameRecorder  # the MCAP side, kept apart from the loop

    refuse_earlier_run(out, rec_path, overwrite=overwrite)  # again, now that no other run can be writing it

    partial = rec_path.with_name(rec_path.name + ".partial")
    tables_dir = out / "tables"
    stale = sorted(tables_dir.glob("*/part-*.parquet")) if tables_dir.exists() else []
    if partial.exists():  # a run killed before it could finish: recorded again from its first frame
        line = (
            f"{partial} was left by an interrupted run; recording {scenario.name} again from frame {first} "
            f"(a clean redo: the interrupted run is not resumed"
            + ("; its table parts are removed" if stale else "")
            + f"; `mmusv recover {out}` would have kept its frames instead)"
        )
        if notes is not None:
            notes.append(line)
    tables = TableWriter(tables_dir)
    silhouettes = SilhouetteCache()
    result = RunResult(recording=rec_path, tables=tables_dir, frames_written=0, status="complete", seconds=0.0)
    t0 = started[0]  # the first frame's capture, before the recording was opened
    prof = RunProfile() if profile else None
    result.profile = prof

    def annotate(cap: FrameCapture) -> _Frame:
        anns = annotations_for(sim, cap, silhouettes)
        return _Frame(cap, {agent: (a, a.columns()) for agent, a in anns.items()})

    def write(item: _Frame | FrameCapture) -> None:  # on the writer thread, in frame order
        ta = time.perf_counter()
        frame = annotate(item) if isinstance(item, FrameCapture) else item
        t = time.perf_counter()
        encoded = recorder.encode_seconds
        recorder.write_frame(frame.capture, {agent: cols for agent, (_, cols) in frame.annotations.items()})
        tw = time.perf_counter()
        tables.add_frame(sim.vessels, frame.capture, frame.annotations)
        if (frame.capture.frame + 1) % TABLE_PART_FRAMES == 0:  # parts end at the same indices in every run
            tables.flush()
        if prof is not None:
            if frame is not item:
                prof.add("writer:annotate", t - ta)
            prof.add("writer:write", tw - t)
            prof.add("writer:write/encode", recorder.encode_seconds - encoded)
            prof.add("writer:tables", time.perf_counter() - tw)

    # A stop (SIGINT, SIGTERM) from the opening of the recording to the frame loop is held and raised in the loop
    # (below): the run then ends as one stopped during a frame does, its recording finished as interrupted and its
    # manifest.json written. Unheld, a stop there left the recording's .partial without a manifest. An earlier
    # run's manifest.json, table parts and scenario.yaml are replaced only once the new recording is open, within
    # the hold: a stop before the hold leaves that run whole (--overwrite removed them before the recording opened,
    # and a stop in between left the earlier recording without its manifest and tables, and nothing new), and so
    # does a recording that cannot be opened (a full disk).
    held = HeldSignals().hold()
    try:
        try:
            recorder = FrameRecorder(
                rec_path, sim, overwrite=overwrite, frames=(first, total - first), frame_range=frame_range is not None
            )
        except MmusvError as exc:  # the metadata could not be written (a full disk): say why
            if not writes_into(exc, out):
                raise
            kept = f"; {rec_path.name} and the rest of the run there are left as they were" if rec_path.exists() else ""
            raise IoError(f"cannot write into {out}: {write_cause(out, exc)}{kept}") from None
        try:
            replace_outputs(out, scenario, stale)
        except OSError as exc:
            recorder.discard()
            raise IoError(f"cannot write into {out}: {write_cause(out, exc)}") from None
        writer: BackgroundWriter[_Frame | FrameCapture] = BackgroundWriter(write, depth=1)
        renders = sim.renders()
        # Without cameras a frame is annotated on the writer thread while the next is captured. With them the
        # annotations' native calls (each box's pixel rays and silhouette) would queue on the thread pool behind
        # the cameras' work, stalling the writer (port_entry: 50 -> 930 ms a frame), so they run between captures.
        annotate_behind = not renders
        if prof is not None:
            prof.start(since=started)
    except BaseException:
        held.release()
        raise
    failure: BaseException | None = None
    try:
        # an error a library made of the stop's KeyboardInterrupt leaves as the stop (held_signals): recorded as
        # interrupted, as a plain Ctrl-C, not as failed with the library's error
        with stops_unwrapped():
            held.release()  # a stop held since the recording opened: KeyboardInterrupt here, in the loop's handling
            for k in range(first, total):
                raise_noted_stop()  # a stop whose KeyboardInterrupt a library swallowed (held_signals)
                tf = time.perf_counter()
                if captured:  # frame `first`, captured before the recording was opened
                    cap, earlier = captured.pop()
                else:
                    cap, earlier = sim.capture(k), 0.0
                # The next frame's sea surface is sampled on its own thread while this one is annotated and written.
                if k + 1 < total:
                    sim.prefetch_frame(k + 1, shading_detail=renders)
                t1 = time.perf_counter()
                item: _Frame | FrameCapture = cap if annotate_behind else annotate(cap)
                t2 = time.perf_counter()
                waited = writer.wait_seconds
                writer.submit(item)  # (annotated and) written while the next frame is captured
                if prof is not None:
                    prof.add("main:capture", t1 - tf + earlier)
                    for key, sec in cap.sensor_seconds.items():  # keyed <agent>/<sensor>: summed over the agents
                        prof.add("main:capture/" + key.split("/", 1)[1], sec)
                    if not annotate_behind:
                        prof.add("main:annotate", t2 - t1)
                    prof.add("main:wait", writer.wait_seconds - waited)
                del cap, item
                result.frame_seconds.append(time.perf_counter() - tf + earlier)
                if progress is not None:
                    progress(k + 1 - first, total - first)
            writer.close()
            writer.raise_pending()
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM through the command line's handler
        result.status = "interrupted"
        failure = exc
    except Exception as exc:
        result.status = "failed"
        result.error = f"{type(exc).__name__}: {exc}"
        failure = exc
    # A stop (SIGINT, SIGTERM) while the run is finished is held until its manifest.json is written, then raised:
    # unheld, a Ctrl-C as the last frame was written (or a second one while the first was handled) left the
    # recording's .partial unfinished and no manifest.json, and the editor's stop button a run naming no recording.
    finishing = HeldSignals().hold()
    try:
        writer.close()  # every frame handed over is written, also after an error or a Ctrl-C
        if writer.interrupted and failure is None:
            result.status, failure = "interrupted", KeyboardInterrupt()
        result.frames_written = writer.done
        # finish what can be finished; a write that fails here (a full disk) is named below, not raised half-way
        problems: list[tuple[str, BaseException]] = []
        # The last table part is written before the recording is finished, so that a recording never says
        # `complete` of a run whose tables could not be written (it says `failed`, and why).
        try:
            tables.flush()  # the writer thread has ended: the tables are the main thread's again
        except OSError as exc:
            problems.append(("writing the tables", exc))
            if result.status == "complete":
                result.status = "failed"
                result.error = f"writing the tables: {write_cause(out, exc)}"
        try:
            summary = recorder.finish(
                status=result.status,
                frames=result.frames_written,
                error=result.error,
                requested=total - first,
                first_frame=None if frame_range is None else first,
            )
            result.messages, result.bytes = summary.get("messages", 0), summary.get("bytes", 0)
        except (MmusvError, OSError) as exc:
            problems.append((f"finishing {rec_path.name}", exc))
        result.seconds = time.perf_counter() - t0
        if prof is not None:
            prof.stop(result.frames_written)
        message = None
        if failure is not None and writes_into(failure, out):
            problems.insert(0, ("writing a frame", failure))
        if problems:  # the disk is full, or the folder went read-only: say why and what is safe
            result.status = "failed"
            message, safe = write_failure(out, rec_path, problems)
            result.frames_written = safe
        manifest = {
            "mmusv_version": _version(),
            "scenario": scenario.name,
            "seed": scenario.seed,
            "config_hash": scenario_hash(scenario),
            "status": result.status,
            "frames_written": result.frames_written,
            "frames_requested": total - first,
            "frequency_hz": scenario.acquisition.frequency_hz,
            "agents": [a.id for a in sim.agents],
            "recording": rec_path.name,
            "tables": sorted(p.name for p in tables_dir.iterdir()) if tables_dir.is_dir() else [],
        }
        if frame_range is not None:
            manifest["first_frame"] = first
        try:  # renamed into place: never half-written
            write_bytes_atomic(out / "manifest.json", dump_json(manifest))
        except OSError as exc:
            if message is None:
                message, _safe = write_failure(out, rec_path, [("writing manifest.json", exc)])
    except BaseException:
        finishing.release(hand_on=False)  # an unexpected error ends the run anyway
        raise
    try:
        finishing.release()  # a stop held meanwhile: KeyboardInterrupt (the run's own error, if any, goes first)
    except KeyboardInterrupt:
        if message is None and failure is None:
            raise  # the run was finished whole: the stop ends it now, as a stop in the loop would have
        # else the run's own error (below) says more than the stop
    if message is not None:
        raise IoError(message) from None
    if failure is not None:
        raise failure
    return result


def _version() -> str:
    from mmusv import __version__

    return __version__
