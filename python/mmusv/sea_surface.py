"""The displaced sea surface's arguments as the ray-casting scene takes them: the sea state it is sampled from, the
grid of tiles it is sampled on and the band where its waves taper to the still level.

The core (``sea::surface``) samples the waves of a directional JONSWAP sea (:class:`SeaState`, e.g.
:class:`~mmusv.world.sea_state.SeaSpec`) on one grid of :data:`SURFACE_TILE_M` tiles round the foci (the USVs) out
to a radius, and tapers the waves linearly to the still level over the last :data:`SURFACE_TAPER_M` metres (a level
of detail: farther water is drawn flat). This module holds those constants, their closed forms
(:func:`surface_tiles`, :func:`surface_taper`), the check of a sea state (:func:`check_sea`) and the native
arguments of :meth:`mmusv.scene.Scene.set_wave_surface` (:func:`surface_args`). Frames and units: world frame
(x east, y north, z up), metres, seconds.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from mmusv import arguments
from mmusv._native import core
from mmusv.errors import InputError

__all__ = [
    "MAX_SURFACE_TILES",
    "SURFACE_TAPER_M",
    "SURFACE_TILE_M",
    "SeaState",
    "check_sea",
    "surface_args",
    "surface_taper",
    "surface_tiles",
]

SURFACE_TILE_M = 32.0
"""Side of a tile of the displaced sea surface, metres (the core's ``SurfaceSpec::tile_m``, which
:meth:`~mmusv.scene.Scene.set_wave_surface` leaves at its default)."""
SURFACE_TAPER_M = 60.0
"""Width of the band over which the displaced sea surface's waves taper to the still level, metres: from
``radius_m − SURFACE_TAPER_M`` to ``radius_m`` from the nearest focus (the whole radius where it is shorter), as
:meth:`~mmusv.scene.Scene.set_wave_surface` asks the core (:func:`surface_taper`)."""
MAX_SURFACE_TILES: int = core.MAX_SURFACE_TILES
"""Most tiles one displaced sea surface may hold (the core's ``sea::MAX_TILES``, which it refuses past itself).
The core samples the rectangle around every focus (out to ``radius_m``) as one grid of :data:`SURFACE_TILE_M`
tiles, so foci far apart (or a huge radius) would ask for more memory than any machine has: 2²² tiles is a square
of about 65 km a side, beyond any map."""


class SeaState(Protocol):
    """A directional JONSWAP sea as the wave surface takes it (the ocean's sea specification has these)."""

    @property
    def hs_m(self) -> float:
        """Significant wave height, metres."""

    @property
    def tp_s(self) -> float:
        """Peak period, seconds."""

    @property
    def gamma(self) -> float:
        """JONSWAP peak enhancement."""

    @property
    def direction_rad(self) -> float:
        """Mean travel direction, radians, counter-clockwise from world +x."""

    @property
    def spread_s(self) -> float:
        """cos-2s spreading exponent."""


def surface_tiles(foci: npt.ArrayLike, *, radius_m: float) -> int:
    """How many tiles the displaced sea surface around ``foci`` ``(F, 2)`` (world x, y, metres) out to
    ``radius_m`` (metres) holds: the core samples their bounding rectangle, grown by ``radius_m``, as one grid of
    :data:`SURFACE_TILE_M` tiles aligned on multiples of :data:`SURFACE_TILE_M` (so a side may take one tile more
    than its length over the tile's); 0 without foci. ``foci`` must be finite (cast to float32) and ``radius_m`` a
    finite number > 0, else an :class:`~mmusv.errors.InputError` naming the argument."""
    f = arguments.rows(foci, name="foci", dtype=np.float32, tail=(2,), empty=True, error=InputError)
    if not np.isfinite(f).all():
        bad = int(np.count_nonzero(~np.isfinite(f).all(axis=1)))
        raise InputError(
            f"foci: every focus must be a finite world x, y (metres, within float32); {bad} of {len(f)} are not"
        )
    radius = arguments.real(radius_m, name="radius_m", unit="metres", above=0.0, error=InputError)
    return int(core.surface_tiles(f, radius_m=radius, tile_m=SURFACE_TILE_M))  # the core's own count


def surface_taper(xy: npt.ArrayLike, *, foci: npt.ArrayLike, radius_m: float) -> npt.NDArray[np.float64]:
    """``(N,)`` float64 share of the waves the displaced sea surface around ``foci`` ``(F, 2)`` keeps at the points
    ``xy`` ``(N, 2)`` (world x, y, metres) with radius ``radius_m`` (metres, > 0), as the core tapers each node
    (``sea::surface::sample``): 1 within ``radius_m − taper`` of the nearest focus, falling linearly to 0 at
    ``radius_m`` and 0 beyond (the still level), ``taper`` = min(:data:`SURFACE_TAPER_M`, ``radius_m``); the
    surface's elevation and slopes there are the waves' times this share. 0 everywhere without foci."""
    p = arguments.rows(xy, name="xy", dtype=np.float64, tail=(2,), empty=True, error=InputError)
    f = arguments.rows(foci, name="foci", dtype=np.float64, tail=(2,), empty=True, error=InputError)
    radius = arguments.real(radius_m, name="radius_m", unit="metres", above=0.0, error=InputError)
    if len(f) == 0 or len(p) == 0:
        return np.zeros(len(p))
    d = np.sqrt(((p[:, None, :] - f[None, :, :]) ** 2).sum(axis=2)).min(axis=1)
    width = min(SURFACE_TAPER_M, radius)
    return np.asarray(np.clip((radius - d) / max(width, 1e-6), 0.0, 1.0))


_SEA_FIELDS = ("hs_m", "tp_s", "gamma", "direction_rad", "spread_s")


def check_sea(sea: Any, *, name: str, error: type[Exception] = InputError) -> None:
    """``sea`` must be ``None`` or a :class:`SeaState` (e.g. :class:`~mmusv.world.sea_state.SeaSpec`): an object
    with the real numbers ``hs_m``, ``tp_s``, ``gamma``, ``direction_rad`` and ``spread_s``."""
    if sea is None:
        return
    missing = [k for k in _SEA_FIELDS if not hasattr(sea, k)]
    if missing:
        raise error(
            f"{name} = {arguments.shown(sea)}: must be a sea state such as mmusv.world.sea_state.SeaSpec "
            f"(sea_spec_for_preset('4'), sea_spec_for_height(2.0)) with {', '.join(_SEA_FIELDS)}, or None; "
            f"{type(sea).__name__} has no {', '.join(missing)}"
        )
    for k in _SEA_FIELDS:
        arguments.real(getattr(sea, k), name=f"{name}.{k}", error=error)


def surface_args(
    sea: SeaState | None,
    *,
    scenario_seed: int,
    time_s: float,
    foci: npt.ArrayLike,
    radius_m: float,
    detail: bool,
    slopes: bool,
    fine_m: float,
) -> tuple[float | None, dict[str, Any]]:
    """The native ``set_wave_surface`` / ``prefetch_wave_surface`` arguments for
    :meth:`~mmusv.scene.Scene.set_wave_surface`'s (whose docstring says what each is): ``hs_m`` (``None`` without a
    sea) and the keywords, each checked, or an :class:`~mmusv.errors.InputError` naming the argument; foci so far
    apart that the surface would hold more than :data:`MAX_SURFACE_TILES` tiles are refused here, before the core
    would allocate them."""
    check_sea(sea, name="sea")
    if sea is None:
        return None, {}
    f = arguments.rows(foci, name="foci", dtype=np.float32, tail=(2,), error=InputError)
    seed = arguments.whole(scenario_seed, name="scenario_seed", lo=0, hi=2**64 - 1, error=InputError)
    t = arguments.real(time_s, name="time_s", unit="seconds", error=InputError)
    radius = arguments.real(radius_m, name="radius_m", unit="metres", above=0.0, error=InputError)
    fine = arguments.real(fine_m, name="fine_m", unit="metres", lo=0.0, error=InputError)
    flags = {k: arguments.flag(v, name=k, error=InputError) for k, v in (("detail", detail), ("slopes", slopes))}
    if np.isfinite(f).all():  # (non-finite foci: the core names them)
        tiles = surface_tiles(f, radius_m=radius)
        if tiles > MAX_SURFACE_TILES:
            span = f.max(axis=0) - f.min(axis=0)
            raise InputError(
                f"the sea surface around foci spanning {span[0]:.0f} m x {span[1]:.0f} m out to radius_m = {radius:g} "
                f"would hold {float(tiles):.3g} tiles of {SURFACE_TILE_M:g} m; at most {MAX_SURFACE_TILES} (a square "
                f"of about {math.sqrt(MAX_SURFACE_TILES) * SURFACE_TILE_M / 1000.0:.0f} km): bring the foci closer "
                "together or lower radius_m"
            )
    return float(sea.hs_m), {
        "tp_s": float(sea.tp_s),
        "gamma": float(sea.gamma),
        "direction_rad": float(sea.direction_rad),
        "spread_s": float(sea.spread_s),
        "scenario_seed": seed,
        "time_s": t,
        "foci": f,
        "radius_m": radius,
        "taper_m": min(SURFACE_TAPER_M, radius),
        "fine_m": fine,
        **flags,
    }
