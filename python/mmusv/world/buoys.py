"""Navigation buoys riding the physical sea: each buoy follows the water surface over its waterplane.

Model: **the quasi-static (hydrostatic, Froude–Krylov) response of a small floating disc**, the long-wavelength
limit of a small floating body (Newman, J. N. (1977), *Marine Hydrodynamics*, MIT Press, ch. 6, the
long-wavelength approximation of wave forces and motions; Faltinsen, O. M. (1990), *Sea Loads on Ships and
Offshore Structures*, Cambridge University Press, ch. 2–3, the Froude–Kriloff force). A float whose resonances lie
above the waves that move it (a map's buoy: a 1 m draft and a 1.2 m radius, ``mmusv.world.port.buoy_mesh``, give a
heave period of about 2.5 s with the added mass, shorter than the W0 sea's 3.5 s peak period) is in hydrostatic
balance with the water pressure over its waterplane at each instant: its waterline point rises to the **mean
elevation over its waterplane disc** and its axis takes the normal of the **plane fitted to the surface over that
disc** (least squares; hydrostatic pitch and roll moments of a waterplane whose restoring is its own second moment).
For a plane wave ``a·cos(k·x − ωt + φ)`` over a disc of radius ``R`` these are the wave's elevation weighted by
``2·J₁(kR)/(kR)`` and its slope weighted by ``8·J₂(kR)/(kR)²`` (the disc integrals of ``e^{ik·x}`` and of
``x·e^{ik·x}``); both tend to 1 where ``kR → 0``, the surface-follower of the long-wavelength limit, and both
leave out the waves shorter than the float, which move its waterline but not the float (without them a 2.4 m float
tilted 8° rms, up to 27°, alike at every sea state from W0 to W3). Not modelled: the float's own heave and roll
resonances and their dynamic amplification, the pressure's decay to the draft (``e^{−kd}``), its mooring's pull and
its drift.

Over a still sea, or with ``motion: paper`` (the paper's water is a flat plane), the buoys stand at rest. Where
the sampled sea surface tapers its waves to the still level (a level-of-detail device, 260–320 m from the nearest
USV by default: :func:`mmusv.sea_surface.surface_taper`), a buoy's heave and tilt taper with them, so that it
floats in the water the sensors see; beyond, it stands upright at the still level, as that water lies.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.special import jv

from mmusv import arguments
from mmusv.errors import InputError
from mmusv.frames import pose_matrices
from mmusv.world.port import BUOY_FLOAT_RADIUS_M

__all__ = ["buoy_matrices", "buoy_poses", "waterplane_weights"]


def waterplane_weights(k: npt.ArrayLike, radius_m: float) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """The weights ``(heave, tilt)``, each float64 of ``k``'s shape, of plane waves of wavenumbers ``k`` (rad/m)
    over a disc of radius ``radius_m`` (m): the disc's mean of ``e^{ik·x}``, ``2·J₁(kR)/(kR)``, and its least-squares
    slope over the wave's, ``8·J₂(kR)/(kR)²`` (module docstring); 1 at ``k = 0``. ``k`` must be finite and ≥ 0 and
    ``radius_m`` > 0, else an :class:`~mmusv.errors.InputError` naming it."""
    kk = arguments.reals(k, name="k", what="an array", error=InputError)
    if not (np.isfinite(kk).all() and (kk >= 0.0).all()):
        raise InputError("k: every wavenumber must be a finite number of rad/m >= 0")
    x = kk * arguments.real(radius_m, name="radius_m", unit="metres", above=0.0, error=InputError)
    safe = np.where(x > 1e-6, x, 1.0)
    heave = np.where(x > 1e-6, 2.0 * jv(1, safe) / safe, 1.0 - x**2 / 8.0)
    tilt = np.where(x > 1e-6, 8.0 * jv(2, safe) / safe**2, 1.0 - x**2 / 12.0)
    return heave, tilt


def buoy_poses(
    field: Any | None,
    xy: npt.ArrayLike,
    t: float,
    *,
    radius_m: float = BUOY_FLOAT_RADIUS_M,
    taper: npt.ArrayLike | None = None,
) -> npt.NDArray[np.float64]:
    """``(B, 6)`` float64 poses ``[x, y, z, roll, pitch, yaw]`` (world frame, metres, radians; yaw 0, the buoys
    being round) of ``B`` buoys at rest positions ``xy`` ``(B, 2)`` (world metres) riding the wave field ``field``
    (a ``mmusv._core.WaveField``) at time ``t`` (s) over a waterplane of radius ``radius_m`` (m): ``z`` the mean
    elevation over the waterplane and the rotation ``Ry(pitch)·Rx(roll)`` taking the buoy's axis to the normal of
    the plane fitted to the surface there (the module's model, from the field's components); the body's origin is
    its waterline point, so at rest ``[x, y, 0, 0, 0, 0]``, as where ``field`` is ``None`` (a still sea, or
    ``motion: paper``). ``taper`` ``(B,)`` in [0, 1] scales each buoy's elevation and slopes as the sampled sea
    surface scales the waves where it tapers to the still level (:func:`mmusv.sea_surface.surface_taper`): a buoy
    beyond it stands upright at the still level of the water drawn there, as the sensors see it. A bad argument
    (``xy`` not finite ``(B, 2)``, ``t`` or ``radius_m`` not a finite number, ``radius_m`` ≤ 0, ``taper`` not ``B``
    shares in [0, 1], a ``field`` with no ``components()``) is an :class:`~mmusv.errors.InputError` naming it."""
    p = _rest_positions(xy)
    t = arguments.real(t, name="t", unit="seconds", error=InputError)
    radius_m = arguments.real(radius_m, name="radius_m", unit="metres", above=0.0, error=InputError)
    if field is not None and not callable(getattr(field, "components", None)):
        raise InputError(
            f"field = {arguments.shown(field)}: must be a wave field (mmusv._core.WaveField, e.g. "
            "SeaSpec.field(scenario_seed=...)) or None (a still sea)"
        )
    if taper is not None:
        taper = arguments.reals(taper, name="taper", what=f"an array of shape ({len(p)},)", error=InputError)
        if taper.shape != (len(p),) or not ((taper >= 0.0) & (taper <= 1.0)).all():
            raise InputError(f"taper: must be {len(p)} shares in [0, 1], one per buoy; got shape {taper.shape}")
    out = np.zeros((p.shape[0], 6), dtype=np.float64)
    out[:, :2] = p
    if field is None or p.shape[0] == 0:
        return out
    a, omega, k, direction, phase0 = np.asarray(field.components(), dtype=np.float64).reshape(-1, 5).T
    kx, ky = k * np.cos(direction), k * np.sin(direction)
    heave, tilt = waterplane_weights(k, radius_m)
    share = np.ones(p.shape[0]) if taper is None else taper
    # the field's phase convention (mmusv_core::ocean::WaveComponent::phase_at): k·x − ωt + φ
    phase = p[:, :1] * kx + p[:, 1:] * ky - omega * t + phase0
    out[:, 2] = share * (np.cos(phase) @ (a * heave))
    sin = np.sin(phase)
    sx, sy = -share * (sin @ (a * tilt * kx)), -share * (sin @ (a * tilt * ky))
    # R·e_z = (sin p cos r, −sin r, cos p cos r) = (−sx, −sy, 1) / N (pose_matrices' R = Rz(yaw)·Ry(pitch)·Rx(roll)).
    norm = np.sqrt(1.0 + sx**2 + sy**2)
    out[:, 3] = np.arcsin(sy / norm)
    out[:, 4] = np.arctan(-sx)
    return out


def _rest_positions(xy: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """``xy``, the buoys' rest positions, as ``(B, 2)`` float64 (an empty list: none), each finite, else an
    :class:`~mmusv.errors.InputError` naming ``xy``."""
    p = arguments.rows(xy, name="xy", dtype=np.float64, tail=(2,), empty=True, error=InputError)
    if not np.isfinite(p).all():
        raise InputError(f"xy: every rest position must be a finite world x, y (metres); {len(p)} given")
    return p


def buoy_matrices(
    field: Any | None,
    xy: npt.ArrayLike,
    t: float,
    *,
    radius_m: float = BUOY_FLOAT_RADIUS_M,
    taper: npt.ArrayLike | None = None,
) -> npt.NDArray[np.float64]:
    """``(B, 4, 4)`` float64 body -> world matrices of :func:`buoy_poses` (at rest where ``field`` is ``None``)."""
    return pose_matrices(buoy_poses(field, xy, t, radius_m=radius_m, taper=taper))
