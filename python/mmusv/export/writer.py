"""The part every dataset writer shares: which agents and topics a scenario folder needs, and frame checks."""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

from mmusv.export.common import Options, Sink
from mmusv.export.geometry import AgentView, Target, agent_view, targets_of
from mmusv.recording import topics
from mmusv.recording.reader import AgentInfo, Frame, RecordingInfo, WorldFrame

__all__ = ["DatasetWriter"]


class DatasetWriter:
    """Base of the OPV2V and KITTI writers: one instance per recording (scenario folder).

    Subclasses set :attr:`cameras` (our camera name → the dataset's index) and implement :meth:`write_agent`
    and :meth:`finish`. An agent without a LiDAR cannot be an OPV2V/KITTI agent and is left out (with a note).
    """

    cameras: ClassVar[dict[str, int]] = {}

    def __init__(self, info: RecordingInfo, folder: Path, options: Options, sink: Sink) -> None:
        self.info = info
        self.folder = folder
        self.options = options
        self.sink = sink
        self.notes: list[str] = []
        self.agents: list[AgentInfo] = []
        for a in info.agents:
            if a.lidar_mount is None:
                self.notes.append(f"agent {a.id} has no LiDAR and is left out")
            else:
                self.agents.append(a)
        self.extra_counts: dict[str, int] = dict.fromkeys(options.extras, 0)

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
                    out.append(topics.camera(a.id, name, "rgb"))
        return out

    def optional_topics(self) -> list[str]:
        """Topics decoded when present (extras, annotations)."""
        ex = self.options.extras
        out: list[str] = []
        for a in self.agents:
            for name, _ in self.agent_cameras(a):
                out += [topics.camera(a.id, name, kind) for kind in ("depth", "semantic", "instance") if kind in ex]
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

    def finish(self, frames: list[int], skipped: list[dict[str, Any]]) -> None:
        """Called once after the last frame with the converted frame indices and the skipped ranges."""
        for e, n in self.extra_counts.items():
            if n == 0 and frames:
                self.notes.append(f"extra {e!r}: not in the recording, no files written")
