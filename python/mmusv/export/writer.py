"""The part every dataset writer shares: which agents and topics a recording needs, frame checks, and the hooks
through which :func:`mmusv.export.convert` drives every format (one folder per recording, or one layout shared by
every recording of the conversion)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

from mmusv.errors import ConfigError
from mmusv.export.common import Options, Sink
from mmusv.export.geometry import AgentView, Target, agent_view, targets_of
from mmusv.recording import topics
from mmusv.recording.decode import WorldFrame
from mmusv.recording.info import AgentInfo, RecordingInfo
from mmusv.recording.stream import Frame

__all__ = ["DatasetWriter"]


class DatasetWriter:
    """Base of every format's writer: one instance per recording.

    :func:`mmusv.export.convert` reads, validates, splits and selects the frames of every recording, reports
    progress, and calls, in this order: :meth:`for_options` (the class to use), :meth:`check` (every recording,
    before anything is written), :meth:`start` (once: state shared by the recordings of one conversion), the
    constructor, :meth:`write_frame` per complete frame, :meth:`finish` per recording (:meth:`stop` instead when
    it ends early) and :meth:`finish_all` (once). Subclasses set :attr:`cameras` (our camera
    name → the dataset's index) and implement :meth:`write_agent` (or :meth:`write_frame`) and :meth:`finish`.

    By default an agent without a LiDAR is left out (with a note), as OPV2V and KITTI need one; a format that
    needs cameras instead overrides :meth:`uses_agent`. ``owns_folder``: convert creates the recording's folder
    ``<split>/<scenario>`` and deletes it when no frame was converted; a format with one layout for every
    recording (COCO, YOLO, SemanticKITTI) writes under the output root instead. ``splits``: whether the
    train/validate/test split applies to the format. ``needs_agent``: a recording without an agent the format uses
    is an error (:meth:`check`) rather than a recording whose frames are all skipped.
    """

    cameras: ClassVar[dict[str, int]] = {}
    owns_folder: ClassVar[bool] = True
    splits: ClassVar[bool] = True
    no_agent_reason: ClassVar[str] = "no agent with a LiDAR"
    needs_agent: ClassVar[bool] = False
    format_version: ClassVar[int] = 1
    """The version of what the format's files mean, written in ``conversion.yaml`` (``format_version``): raised
    when a file of an earlier conversion would be read otherwise today (its name, encoding, a field's meaning), so
    that a folder converted before is not taken for a current one (``mmusv dataset`` converts it again). A report
    without the key predates the versions: 1."""

    def __init__(
        self,
        info: RecordingInfo,
        folder: Path,
        options: Options,
        sink: Sink,
        *,
        split: str | None = None,
        shared: Any = None,
    ) -> None:
        self.info = info
        self.folder = folder
        self.options = options
        self.sink = sink
        self.split = split
        self.shared = shared
        self.notes: list[str] = []
        self.agents: list[AgentInfo] = []
        for a in info.agents:
            if options.agents is not None and a.id not in options.agents:
                continue  # not selected (convert checked that the recording holds a selected agent)
            why = self.uses_agent(a)
            if why is None:
                self.agents.append(a)
            else:
                self.notes.append(f"agent {a.id} {why} and is left out")
        self.extra_counts: dict[str, int] = dict.fromkeys(options.extras, 0)

    # ------------------------------------------------------------------------------------------ the conversion

    @classmethod
    def check(cls, info: RecordingInfo) -> None:
        """Raises :class:`~mmusv.errors.ConfigError` naming the file when ``info``'s recording cannot be converted
        to this format at all (called for every recording before anything is written). With :attr:`needs_agent`,
        a recording without an agent this format uses is such an error (otherwise its frames are skipped, with
        :attr:`no_agent_reason`)."""
        if cls.needs_agent and not any(cls.uses_agent(a) is None for a in info.agents):
            raise ConfigError(f"{info.path}: cannot convert to {cls.format_name()}: {cls.no_agent_reason}")

    @classmethod
    def for_options(cls, options: Options) -> type[DatasetWriter]:
        """The writer class that converts with ``options`` (called by :func:`mmusv.export.convert` before
        :meth:`check`): this class, unless the options change what the format needs from a recording (YOLO's
        ``box="visible"`` needs instance images)."""
        return cls

    @classmethod
    def format_name(cls) -> str:
        """The format's ``--to`` name (the class name without ``Writer``, lower case)."""
        return cls.__name__.removesuffix("Writer").lower()

    @classmethod
    def uses_agent(cls, agent: AgentInfo) -> str | None:
        """``None`` when this format converts ``agent``, else why not (``"has no LiDAR"``)."""
        return None if agent.lidar_mount is not None else "has no LiDAR"

    @classmethod
    def start(cls, out: Path, options: Options, sink: Sink) -> Any:
        """State shared by every recording of one conversion into ``out`` (passed to each writer as
        ``shared``); ``None`` by default."""
        return None

    @classmethod
    def finish_all(cls, shared: Any, out: Path, sink: Sink) -> None:
        """Called once after the last recording (files that describe the whole conversion)."""

    # ------------------------------------------------------------------------------------------ topics

    def agent_cameras(self, agent: AgentInfo) -> list[tuple[str, int]]:
        """``(our name, dataset index)`` of the agent's cameras the dataset holds, by index."""
        return sorted(((n, i) for n, i in self.cameras.items() if n in agent.cameras), key=lambda t: t[1])

    def required_topics(self) -> list[str]:
        """Topics a frame must hold to be converted."""
        out = [topics.WORLD_STATE]
        for a in self.agents:
            out.append(topics.lidar(a.id))
            for name, _ in self.agent_cameras(a):
                if "rgb" in a.cameras[name].outputs:
                    out.append(topics.camera(a.id, name, kind="rgb"))
        return out

    def optional_topics(self) -> list[str]:
        """Topics decoded when present (extras, annotations)."""
        ex = self.options.extras
        out: list[str] = []
        for a in self.agents:
            for name, _ in self.agent_cameras(a):
                out += [
                    topics.camera(a.id, name, kind=kind) for kind in ("depth", "semantic", "instance") if kind in ex
                ]
            if "radar" in ex:
                out.append(topics.radar_ppi(a.id))
            if "top_view" in ex:
                out += [topics.top_view(a.id, "rgb"), topics.top_view(a.id, "semantic")]
        return out

    def topic_filter(self) -> set[str]:
        """Every topic to decode."""
        return set(self.required_topics()) | set(self.optional_topics())

    def missing(self, frame: Frame) -> list[str]:
        """Required topics ``frame`` lacks."""
        return [t for t in self.required_topics() if t not in frame.messages]

    # ------------------------------------------------------------------------------------------ writing

    def write_frame(self, frame: Frame) -> None:
        """Writes every agent's files of a complete frame."""
        world = frame.world
        assert world is not None
        for a in self.agents:
            view = agent_view(a, world)
            tg = targets_of(view, world, eval_range_m=self.options.eval_range_m, include_usvs=self.options.include_usvs)
            self.write_agent(frame, world, view, tg)

    def put(self, path: Path, data: bytes, extra: str | None = None) -> None:
        """Writes one file (counting an extra's files under its name)."""
        self.sink.write(path, data)
        if extra is not None:
            self.extra_counts[extra] = self.extra_counts.get(extra, 0) + 1

    def write_agent(self, frame: Frame, world: WorldFrame, view: AgentView, targets: list[Target]) -> None:
        raise NotImplementedError

    def stop(self, *, interrupted: bool) -> None:
        """Called instead of :meth:`finish` when the conversion of this recording ends early: ``interrupted`` for a
        stop (Ctrl-C, SIGTERM), else an error. A writer holding a file open closes it here (the files already
        written stay, and ``conversion.yaml`` says the conversion was interrupted or failed); by default nothing."""

    def finish(self, frames: list[int], skipped: list[dict[str, Any]]) -> None:
        """Called once after the last frame with the converted frame indices and the skipped ranges."""
        for e, n in self.extra_counts.items():
            if n == 0 and frames:
                self.notes.append(f"extra {e!r}: not in the recording, no files written")
