"""Preview frame: the ``mmusv preview`` picture of one acquisition index of the document being edited.

The frame goes through the same path as a run: :class:`~mmusv.simulation.Simulation` captures it with the
scenario's real sensors (only the chosen USV), :func:`mmusv.acquire.annotations_for` annotates it, a
:class:`~mmusv.recording.frames.FrameRecorder` writes it into a one-frame recording in a temporary folder, and
:func:`mmusv.preview.compose_preview` draws the sheet from that recording, so the picture is what ``mmusv run`` then
``mmusv preview --frame K`` would show. Nothing is written into the editor's folder. A scenario of more than
:data:`MAX_PREVIEW_VESSELS` vessels is refused (the picture of one frame of thousands takes minutes).
"""

from __future__ import annotations

import io
import tempfile
from pathlib import Path

from mmusv.acquire import annotations_for
from mmusv.config import Scenario
from mmusv.errors import ConfigError
from mmusv.preview import compose_preview
from mmusv.recording.frames import FrameRecorder
from mmusv.silhouettes import SilhouetteCache
from mmusv.simulation import Simulation
from mmusv.world.maps import MapWorld

__all__ = ["MAX_PREVIEW_VESSELS", "preview_png"]

MAX_PREVIEW_VESSELS = 1000
"""Most vessels a preview draws (a few seconds at the limit)."""


def preview_png(scenario: Scenario, *, frame: int, agent: str | None = None, world: MapWorld | None = None) -> bytes:
    """PNG bytes of the preview sheet of ``frame`` for the USV ``agent`` (default: the first USV); ``world`` is the
    scenario's map when the caller has it already (it is generated otherwise)."""
    if len(scenario.vessels) > MAX_PREVIEW_VESSELS:
        raise ConfigError(
            f"the scenario has {len(scenario.vessels):,} vessels; the editor previews scenarios of at most "
            f"{MAX_PREVIEW_VESSELS:,} (`mmusv run` then `mmusv preview` draws any)"
        )
    usvs = [v.id for v in scenario.usvs]
    if not usvs:
        raise ConfigError("the scenario has no USV (role: usv): there is no sensor to preview")
    agent = usvs[0] if agent is None else agent
    if agent not in usvs:
        raise ConfigError(f"agent {agent!r} is not a USV of the scenario; the USVs are {', '.join(usvs)}")
    if not 0 <= frame < scenario.acquisition.frames:
        raise ConfigError(f"frame {frame} is outside the acquisition (0..{scenario.acquisition.frames - 1})")
    sim = Simulation(scenario, world=world)
    cap = sim.capture(frame, agents=[agent])
    anns = annotations_for(sim, cap, SilhouetteCache())
    with tempfile.TemporaryDirectory(prefix="mmusv-editor-preview-") as tmp:
        path = Path(tmp) / "preview.mcap"
        rec = FrameRecorder(path, sim, frames=(frame, 1), frame_range=True)  # a recording of this one frame, saying so
        try:
            rec.write_frame(cap, {a: ann.columns() for a, ann in anns.items()})
        finally:
            rec.finish(status="complete", frames=1, requested=1, first_frame=frame)
        canvas, _ = compose_preview(path, frame=frame, agent=agent)
    buf = io.BytesIO()
    canvas.save(buf, format="PNG")
    return buf.getvalue()
