"""A vessel's apparent contrast in a recorded camera image: how much it stands out from what surrounds it, as the
picture shows it (fog, haze, rain and night included), for the image datasets' ``contrast`` and ``min_contrast``
(:mod:`mmusv.export.camera`; ``docs/exports.md``).

The 2D boxes come from the instance image, which is geometry: a vessel far beyond the meteorological visibility
still has all its pixels there while the RGB image shows nothing. The Weber contrast of the vessel against a ring of
background beside it, measured on the RGB image, tells the two apart. Row by row of the image (the background
beside a vessel changes from sky to sea across the horizon, and a hull, its superstructure and its windows are
bands of their own), over the rows ``r`` holding ``n_r`` of the vessel's pixels:

``C = Σ_r n_r · |L_v(r) − L_b(r)| / max(L_b(r), L_min)  /  Σ_r n_r``

* ``L_v(r)``: the mean relative luminance of the vessel's pixels (those whose instance is the vessel's) in row
  ``r``;
* ``L_b(r)``: the mean relative luminance of the *background ring*'s pixels in row ``r`` (the whole ring's mean
  where that row has none, e.g. a vessel cut by the image's edge): the ring is the pixels of the vessel's tight
  box (the box of its pixels, :func:`mmusv.export.common.mask_box`) grown by :func:`ring_margin` on each side
  and clipped to the image, less the vessel's own pixels, the pixels of the other vessels (``other_ids``) and the
  pixels next to the vessel's (its 8-neighbours: with anti-aliasing, ``quality`` ``standard`` or ``high``, they
  blend the vessel into its background). Where that leaves no pixel, the neighbours are taken back, then the
  other vessels' pixels; where still none is left (the vessel covers its whole grown box, i.e. fills the image)
  the contrast is undefined (``None``);
* relative luminance ``L = 0.2126 R + 0.7152 G + 0.0722 B`` (ITU-R BT.709 / sRGB primaries) of the *linear*
  values, the 8-bit sRGB values decoded by the IEC 61966-2-1 transfer function (:func:`srgb_to_linear`), so
  ``L`` is in ``[0, 1]`` (1 = white), relative to the image's white, not cd/m²: the image as recorded, after the
  camera's exposure and tone curve;
* ``L_min`` (:data:`MIN_BACKGROUND_LUMINANCE`): the luminance of the first sRGB level above black, the night
  guard. Against a black background (night, no moon) a vessel just as black has contrast 0 and a lit one
  (navigation lights) a large finite contrast, at most :data:`MAX_CONTRAST`; above the floor Weber contrast does
  not depend on the exposure, so a dim scene whose vessel still differs from its background keeps its contrast
  (quantised: one 8-bit level is a large step of a dark background's luminance).

Sources. Weber contrast ``(L − L_b) / L_b`` (E. H. Weber, 1834; the definition used for a small object on a uniform
background, e.g. E. Peli, "Contrast in complex images", JOSA A 7(10), 1990). Koschmieder's law (H. Koschmieder,
"Theorie der horizontalen Sichtweite", Beitr. Phys. freien Atmos. 12, 1924): through air of extinction
coefficient ``σ`` an object at distance ``d`` against the horizon sky has apparent contrast ``C(d) = C0 · e^{−σ d}``.
The WMO's meteorological optical range is the distance at which a black object's contrast falls to 0.05
(:data:`WMO_CONTRAST_THRESHOLD`; WMO-No. 8, *Guide to Instruments and Methods of Observation*, vol. I, ch. 9), so
``σ = −ln(0.05) / MOR ≈ 3.0 / MOR``, the extinction mmusv renders from a scenario's ``visibility_m``
(``mmusv.world.environment.Weather.extinction_per_m``; the cameras' aerial perspective ``L T + L_air (1 − T)``,
``T = e^{−σ t}``, ``crates/mmusv-core/src/sensors/shade.rs``); Koschmieder's own ``3.912 / V`` is the same law
with a 0.02 threshold. So a vessel at the scenario's visibility has ``C ≤ 0.05 · C0 ≤ 0.05`` for a dark hull
(``C0 ≤ 1``): ``min_contrast = 0.05`` keeps what an observer would report as seen.

Why row by row: one mean against one mean let a vessel whose bright and dark parts average out against a ring of
bright sky and dark sea measure low although plainly visible (on a clear afternoon in ``port_entry``, a white yacht
with dark windows 0.011, a blue-and-white ferry 0.048); per row, the sky beside a superstructure and the sea beside
a hull are each compared with what stands in front of them, while each row's means still average the pixels'
noise. Over a uniform background each row's contrast falls as ``e^{−σ d}``, and so does their average.

It lives here, with the exports, not in :mod:`mmusv.annotate`: the recording's annotations are geometry taken at
capture from the instance image (part of the recording's format), while this needs the rendered picture and is
measured from the recording when converting, so existing recordings get it without being run again.
"""

from __future__ import annotations

from collections.abc import Collection

import numpy as np

from mmusv.errors import InputError
from mmusv.export.common import mask_box

__all__ = [
    "LUMA_709",
    "MAX_CONTRAST",
    "MIN_BACKGROUND_LUMINANCE",
    "WMO_CONTRAST_THRESHOLD",
    "apparent_contrast",
    "relative_luminance",
    "ring_margin",
    "srgb_to_linear",
]

LUMA_709 = (0.2126, 0.7152, 0.0722)
"""Relative luminance of linear R, G, B (ITU-R BT.709, the sRGB primaries and D65 white)."""

WMO_CONTRAST_THRESHOLD = 0.05
"""The contrast threshold of the WMO's meteorological optical range (WMO-No. 8): the suggested ``min_contrast``."""


def srgb_to_linear(values: np.ndarray) -> np.ndarray:
    """The IEC 61966-2-1 sRGB transfer function (EOTF): encoded values in ``[0, 1]`` (any shape, float) → linear
    values in ``[0, 1]`` (float64, same shape): ``c / 12.92`` up to ``c = 0.04045``, ``((c + 0.055) / 1.055)^2.4``
    above."""
    c = np.asarray(values, dtype=np.float64)
    out: np.ndarray = np.where(c <= 0.04045, c / 12.92, ((np.maximum(c, 0.04045) + 0.055) / 1.055) ** 2.4)
    return out


MIN_BACKGROUND_LUMINANCE = float(srgb_to_linear(np.array(1.0 / 255.0)))
"""The night guard: the relative luminance of sRGB grey level 1 of 255 (``1 / 255 / 12.92`` ≈ 3.04e-4), below which
the background luminance is floored in the denominator of the contrast."""

MAX_CONTRAST = 1.0 / MIN_BACKGROUND_LUMINANCE
"""The largest contrast :func:`apparent_contrast` gives (a white vessel on black: ``255 · 12.92`` ≈ 3295): a
``min_contrast`` above it would leave out every box."""

_LUT = srgb_to_linear(np.arange(256, dtype=np.float64) / 255.0)


def relative_luminance(rgb: np.ndarray) -> np.ndarray:
    """Relative luminance of an 8-bit sRGB image: ``rgb`` ``(H, W, 3)`` uint8 (R, G, B as recorded) → ``(H, W)``
    float64 in ``[0, 1]``, :data:`LUMA_709` over the linearised values (:func:`srgb_to_linear`). Other shapes or
    dtypes raise :class:`~mmusv.errors.InputError`."""
    a = np.asarray(rgb)
    if a.ndim != 3 or a.shape[2] != 3 or a.dtype != np.uint8:
        raise InputError(f"rgb must be an (H, W, 3) uint8 sRGB image, got shape {a.shape} and dtype {a.dtype}")
    lin = _LUT[a]
    out: np.ndarray = lin[..., 0] * LUMA_709[0] + lin[..., 1] * LUMA_709[1] + lin[..., 2] * LUMA_709[2]
    return out


def ring_margin(width: int, height: int) -> tuple[int, int]:
    """How far the background ring reaches beyond a tight box of ``width`` × ``height`` pixels: ``(mx, my)`` =
    ``max(2, ceil(0.25 · width))`` columns left and right, ``max(2, ceil(0.25 · height))`` rows above and below
    (about as many background pixels as the box holds: ``1.5² − 1``; at least two pixels of each side for a tiny
    box)."""
    return max(2, -(-int(width) // 4)), max(2, -(-int(height) // 4))


def apparent_contrast(
    *,
    rgb: np.ndarray,
    instance: np.ndarray,
    instance_id: int,
    other_ids: Collection[int] = (),
    box: tuple[int, int, int, int] | None = None,
) -> float | None:
    """The Weber contrast of the vessel ``instance_id`` in a recorded image (see the module docstring for the
    definition, the ring and the night guard).

    Args:
        rgb: ``(H, W, 3)`` uint8, the camera's RGB image as recorded (8-bit sRGB).
        instance: ``(H, W)`` integer, the camera's instance image of the same frame (pixel → instance id).
        instance_id: the vessel's instance id.
        other_ids: the instance ids of the other vessels, whose pixels are kept out of the ring (the vessel's own
            id among them is ignored).
        box: the vessel's tight box ``(x_min, y_min, x_max, y_max)`` in pixel-edge coordinates, as
            :func:`~mmusv.export.common.mask_box` gives it, when the caller has it already; ``None``: worked out.

    Returns:
        The contrast (the module docstring's row-weighted Weber contrast, each row's background floored at
        ``MIN_BACKGROUND_LUMINANCE``), a float ``>= 0`` (dimensionless, 0.05 the WMO's visibility threshold);
        ``None`` when the vessel has no pixel in ``instance`` or no background pixel is left around it.

    Raises:
        InputError: ``rgb`` not ``(H, W, 3)`` uint8, or ``instance`` not ``(H, W)`` of the same size.
    """
    inst = np.asarray(instance)
    img = np.asarray(rgb)
    if img.ndim != 3 or img.shape[2] != 3 or img.dtype != np.uint8:
        raise InputError(f"rgb must be an (H, W, 3) uint8 sRGB image, got shape {img.shape} and dtype {img.dtype}")
    if inst.shape != img.shape[:2]:
        raise InputError(f"instance must be (H, W) = {img.shape[:2]} like rgb, got {inst.shape}")
    tight = mask_box(inst, instance_id) if box is None else box
    if tight is None:
        return None
    h, w = inst.shape
    x0, y0, x1, y1 = tight
    mx, my = ring_margin(x1 - x0, y1 - y0)
    gx0, gx1, gy0, gy1 = max(0, x0 - mx), min(w, x1 + mx), max(0, y0 - my), min(h, y1 + my)
    vessel = inst[gy0:gy1, gx0:gx1] == instance_id  # every pixel of the vessel lies in its tight box
    lum = relative_luminance(img[gy0:gy1, gx0:gx1])  # the window only: the whole image per box is slow
    others = np.isin(inst[gy0:gy1, gx0:gx1], np.array([i for i in other_ids if i != instance_id], dtype=np.int64))
    # The vessel's 8-neighbours and itself (its mask dilated by one pixel; the window reaches >= 2 beyond it).
    padded = np.pad(vessel, 1)
    near = np.zeros_like(vessel)
    for dy in (0, 1, 2):
        for dx in (0, 1, 2):
            near |= padded[dy : dy + vessel.shape[0], dx : dx + vessel.shape[1]]
    for ring in (~near & ~others, ~vessel & ~others, ~vessel):
        if ring.any():
            return _row_contrast(lum, vessel, ring)
    return None


def _row_contrast(lum: np.ndarray, vessel: np.ndarray, ring: np.ndarray) -> float:
    """The contrast of the module docstring over a window: ``lum`` ``(h, w)`` float64 luminance, ``vessel`` and
    ``ring`` ``(h, w)`` bool masks (``ring`` not empty): per row holding vessel pixels, the Weber contrast of their
    mean against the ring's mean in that row (the whole ring's where the row has none), averaged with the rows'
    vessel pixel counts as weights."""
    n_vessel = vessel.sum(axis=1)
    n_ring = ring.sum(axis=1)
    rows = n_vessel > 0
    vessel_rows = np.where(vessel, lum, 0.0).sum(axis=1)[rows] / n_vessel[rows]
    ring_all = float(lum[ring].mean())
    ring_sum = np.where(ring, lum, 0.0).sum(axis=1)[rows]
    ring_rows = np.where(n_ring[rows] > 0, ring_sum / np.maximum(n_ring[rows], 1), ring_all)
    per_row = np.abs(vessel_rows - ring_rows) / np.maximum(ring_rows, MIN_BACKGROUND_LUMINANCE)
    return float(np.average(per_row, weights=n_vessel[rows]))
