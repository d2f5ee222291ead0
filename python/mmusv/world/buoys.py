"""Navigation buoys riding the physical sea: each buoy follows the water surface at its position.

Model: **the long-wavelength limit of a small floating body** (Newman, J. N. (1977), *Marine Hydrodynamics*, MIT
Press, ch. 6, the long-wavelength approximation of wave forces and motions; Faltinsen, O. M. (1990), *Sea Loads on
Ships and Offshore Structures*, Cambridge University Press, ch. 2–3). Where a body is much smaller than the waves
(a map's buoy is 2.4 m across; the shortest waves that carry the energy of the W0–W3 seas, at their peak periods of
3.5–9.3 s, are 19–136 m long) its heave RAO tends to 1 and it stays normal to the surface: the buoy's waterline
point rises and falls with the elevation ``η(x, y, t)`` of the wave field at its position, and its axis is the
surface's normal ``(−∂η/∂x, −∂η/∂y, 1)``. Not modelled: the heave and roll resonances of the float itself (a
1 m draft, ``mmusv.world.port.buoy_mesh``'s, gives a heave period of about 2.5 s with the added mass of its 1.2 m
radius, shorter than the W0 sea's 3.5 s peak period), its mooring's pull and its drift.

Over a still sea, or with ``motion: paper`` (the paper's water is a flat plane), the buoys stand at rest.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from mmusv.frames import pose_matrices

__all__ = ["buoy_matrices", "buoy_poses"]


def buoy_poses(field: Any | None, xy: npt.ArrayLike, t: float) -> npt.NDArray[np.float64]:
    """``(B, 6)`` float64 poses ``[x, y, z, roll, pitch, yaw]`` (world frame, metres, radians; yaw 0, the buoys
    being round) of ``B`` buoys at rest positions ``xy`` ``(B, 2)`` (world metres) riding the wave field ``field``
    (a ``mmusv._core.WaveField``) at time ``t`` (s): ``z`` the elevation at each buoy and the rotation
    ``Ry(pitch)·Rx(roll)`` taking the buoy's axis to the surface normal (the module's model); the body's origin is
    its waterline point, so at rest ``[x, y, 0, 0, 0, 0]``, as where ``field`` is ``None`` (a still sea, or
    ``motion: paper``)."""
    p = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    out = np.zeros((p.shape[0], 6), dtype=np.float64)
    out[:, :2] = p
    if field is None or p.shape[0] == 0:
        return out
    x, y = np.ascontiguousarray(p[:, 0]), np.ascontiguousarray(p[:, 1])
    out[:, 2] = np.asarray(field.elevation(x, y, float(t)), dtype=np.float64)
    s = np.asarray(field.slope(x, y, float(t)), dtype=np.float64).reshape(-1, 2)
    # R·e_z = (sin p cos r, −sin r, cos p cos r) = (−ηx, −ηy, 1) / N (pose_matrices' R = Rz(yaw)·Ry(pitch)·Rx(roll)).
    norm = np.sqrt(1.0 + s[:, 0] ** 2 + s[:, 1] ** 2)
    out[:, 3] = np.arcsin(s[:, 1] / norm)
    out[:, 4] = np.arctan(-s[:, 0])
    return out


def buoy_matrices(field: Any | None, xy: npt.ArrayLike, t: float) -> npt.NDArray[np.float64]:
    """``(B, 4, 4)`` float64 body -> world matrices of :func:`buoy_poses` (at rest where ``field`` is ``None``)."""
    return pose_matrices(buoy_poses(field, xy, t))
