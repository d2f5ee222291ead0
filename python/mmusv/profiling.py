"""Where a run's time goes: seconds per stage, summed over frames, for ``mmusv run --profile``.

A :class:`RunProfile` is filled while :func:`mmusv.acquire.run` runs (``run(..., profile=True)``) and printed
with :meth:`RunProfile.render`. It only reads clocks (``time.perf_counter``, process CPU time, peak RSS): it
never touches what is captured or written, so a profiled run writes the same bytes as any other.

Stages are named ``<thread>:<stage>``; ``thread`` is ``main`` (capture, annotation, handing frames over) or
``writer`` (encoding and writing, overlapped with the next frame's capture). Within ``capture`` every sensor is
a row of its own (``capture/lidar``, ``capture/camera/<name>``, ``capture/top_view``, ``capture/radar``,
``capture/ppi``), summed over the USVs; sensors of one frame run concurrently on the cores, so their rows are
task times (start to end of that sensor's work while sharing the cores) and add up to more than the capture's
wall time (``capture`` itself). ``main:python`` is the rest of the main thread: wall time minus its stages.
Units: seconds in :attr:`RunProfile.seconds`, milliseconds per frame in the table.
"""

from __future__ import annotations

import os
import resource
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

from mmusv.text import counted

__all__ = ["RunProfile", "StageRow"]

MAIN = "main"
WRITER = "writer"


@dataclass(frozen=True)
class StageRow:
    """One line of the table: ``stage`` (``thread:name``), total ``seconds`` over the run, ``ms_per_frame`` and
    ``share`` of the wall time (0..1; rows of concurrent work can add up to more than 1)."""

    stage: str
    seconds: float
    ms_per_frame: float
    share: float
    overlapping: bool


@dataclass
class RunProfile:
    """Seconds per stage of one run (thread-safe: the writer thread adds its own stages)."""

    seconds: dict[str, float] = field(default_factory=dict)
    frames: int = 0
    wall_s: float = 0.0
    cpu_s: float = 0.0
    peak_rss_mb: float = 0.0
    load_average: tuple[float, float, float] = (0.0, 0.0, 0.0)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)
    _t0: float = field(default=0.0, repr=False)
    _cpu0: float = field(default=0.0, repr=False)

    def add(self, stage: str, seconds: float) -> None:
        """Adds ``seconds`` to ``stage`` (``thread:name``, e.g. ``main:annotate``)."""
        with self._lock:
            self.seconds[stage] = self.seconds.get(stage, 0.0) + seconds

    @contextmanager
    def time(self, stage: str) -> Iterator[None]:
        """Times the block into ``stage``."""
        t = time.perf_counter()
        try:
            yield
        finally:
            self.add(stage, time.perf_counter() - t)

    def start(self, *, since: tuple[float, float] | None = None) -> None:
        """Starts the wall and CPU clocks (at the first frame); ``since``: clocks read earlier (:func:`clocks`),
        when the first frame was captured before the rest was set up."""
        self._t0, self._cpu0 = since if since is not None else clocks()

    def stop(self, frames: int) -> None:
        """Stops the clocks after ``frames`` frames and reads the peak RSS and the load average."""
        self.wall_s = time.perf_counter() - self._t0
        self.cpu_s = _cpu_seconds() - self._cpu0
        self.frames = frames
        self.peak_rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
        self.load_average = os.getloadavg()

    @property
    def frames_per_s(self) -> float:
        """Frames per second of wall time."""
        return self.frames / self.wall_s if self.wall_s > 0 else 0.0

    @property
    def cpu_percent(self) -> float:
        """Process CPU time over wall time, percent (200 = two cores busy)."""
        return 100.0 * self.cpu_s / self.wall_s if self.wall_s > 0 else 0.0

    def rows(self) -> list[StageRow]:
        """The table, main-thread stages first (with ``main:python``, the rest of its wall time), then the writer's
        (with ``writer:idle``); within each, the order stages first appeared in."""
        n = max(self.frames, 1)
        wall = self.wall_s if self.wall_s > 0 else 1.0
        with self._lock:
            secs = dict(self.seconds)
        out: list[StageRow] = []
        for thread, rest in ((MAIN, "python"), (WRITER, "idle")):
            mine = {k: v for k, v in secs.items() if k.startswith(thread + ":")}
            if not mine:
                continue
            # sensor rows (capture/...) run concurrently inside `capture`; they are not part of the thread's sum
            flat = sum(v for k, v in mine.items() if "/" not in k)
            mine[f"{thread}:{rest}"] = max(self.wall_s - flat, 0.0)
            for k in [k for k in mine if "/" not in k]:
                for kk in [k, *(c for c in mine if c.startswith(k + "/"))]:
                    v = mine[kk]
                    out.append(StageRow(kk, v, 1000.0 * v / n, v / wall, overlapping=kk != k))
        return out

    def render(self) -> str:
        """A plain-text table: stage, ms/frame, share of wall; then wall time, frames/s, CPU, peak RSS, load."""
        lines = [f"{'stage':<32} {'ms/frame':>10} {'% wall':>8}"]
        for r in self.rows():
            name = ("  " + r.stage) if r.overlapping else r.stage
            lines.append(f"{name:<32} {r.ms_per_frame:>10.1f} {100 * r.share:>7.1f}%")
        la = " ".join(f"{x:.2f}" for x in self.load_average)
        lines.append(
            f"wall {self.wall_s:.1f} s for {counted(self.frames, 'frame')}: {self.frames_per_s:.2f} frames/s, "
            f"CPU {self.cpu_percent:.0f} % ({counted(os.cpu_count() or 1, 'core')}, "
            f"{self.cpu_s / max(self.frames, 1):.2f} CPU s per "
            f"frame), peak RSS {self.peak_rss_mb:.0f} MB, "
            f"load average {la}"
        )
        lines.append("indented rows: task times inside the stage above them (sensors of one frame run concurrently,")
        lines.append("so they can add up to more than that stage)")
        return "\n".join(lines)


def clocks() -> tuple[float, float]:
    """``(time.perf_counter(), process CPU seconds)`` now: what :meth:`RunProfile.start` reads."""
    return time.perf_counter(), _cpu_seconds()


def _cpu_seconds() -> float:
    """User + system CPU seconds of this process (all threads)."""
    t = os.times()
    return t.user + t.system
