"""The studies' pictures drawn with matplotlib's own defaults, whatever the user's configuration says: a
``matplotlibrc`` in the current folder, in ``$MPLCONFIGDIR`` or ``~/.config/matplotlib``, ``$MATPLOTLIBRC``, or a
style or ``rcParams`` a script or notebook set before calling a study. Each of them changed the bytes of
``wave_study.png``, ``detection_ap.png`` and ``robustness_ap.png`` (line widths, fonts, colours, the saved dpi),
which are the same for the same inputs wherever they are made."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["default_style"]


@contextmanager
def default_style() -> Iterator[None]:
    """Within it, pyplot on the Agg backend with matplotlib's default ``rcParams`` (``style.context("default")``:
    every parameter but the backend's); the caller's are back afterwards."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with plt.style.context("default"):
        yield
