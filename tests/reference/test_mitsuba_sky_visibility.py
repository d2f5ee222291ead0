"""The sky's visibility over a mesh's own surfaces (``crates/mmusv-core/src/sky_visibility.rs``) against Mitsuba 3:
a wall standing on a floor, one mesh, under the overcast sky. Mitsuba's layer of that mesh under the sky (path depth
2, ``mitsuba_scenes.layers``) hides from each point the sky and the ground that the mesh itself hides, which is what
mmusv's baked visibility stands for; the ``draft`` quality, which lights every surface with the whole sky, is the
same render without it.

The overcast (CIE) sky is the same in every azimuth, as the visibility's shading assumes within each half of the
sky it splits (above and below the horizon). Under a clear sky the wall hides the brighter sky around the sun from
the floor beside it, which a share of the sky cannot tell from the rest (the module's docstring)."""

from __future__ import annotations

import math
from pathlib import Path

import mitsuba_scenes as ms
import numpy as np
import pytest

#: Resolution and Mitsuba samples per pixel.
WIDTH, HEIGHT, SPP = 96, 64, 256


def wall_on_floor() -> ms.RefScene:
    """A 120 m floor and a 12 × 1.5 × 5 m wall standing on it, as one mesh, seen from 12 m off and 3 m up."""
    fv, ff = ms.square(60.0)
    wv, wf = ms.box((0.0, -6.0, 0.0), (1.5, 6.0, 5.0))
    vertices = np.concatenate([fv, wv]).astype(np.float32)
    faces = np.concatenate([ff, wf + len(fv)]).astype(np.int32)
    obj = ms.Object("floor and wall", vertices, faces, ms.Material((0.5, 0.45, 0.4), 0.8))
    return ms.RefScene(
        name="wall_on_floor",
        title="a wall on a floor, one mesh, overcast sky",
        objects=(obj,),
        env=ms.Env(sun=ms.unit((0.6, 0.3, 0.5)), ground_albedo=0.3, cloud=1.0),
        pose=ms.look_pose((-12.0, -4.0, 3.0), math.radians(15.0), math.radians(14.0)),
        hfov=math.radians(60.0),
    )


@pytest.fixture(scope="module")
def errors(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per quality, mmusv's per-pixel relative error against Mitsuba's render and the pixels kept."""
    scene = wall_on_floor()
    workdir: Path = tmp_path_factory.mktemp("mitsuba_sky")
    out = {}
    reference = None
    for quality in ("standard", "draft"):
        img = ms.render_mmusv(scene, WIDTH, HEIGHT, quality=quality)
        if reference is None:
            reference = ms.render_mitsuba(scene, img.instance, WIDTH, HEIGHT, spp=SPP, seed=3, workdir=workdir)
        out[quality] = (ms.relative_error(img.radiance, reference.radiance), ~ms.excluded(img))
    return out


def test_the_mesh_hiding_its_own_sky_matches_mitsuba(errors: dict[str, tuple[np.ndarray, np.ndarray]]) -> None:
    # Measured: 3.0 % at 512 spp (Mitsuba's own noise included), against 22.5 % with the whole sky on every surface.
    err, keep = errors["standard"]
    assert keep.mean() > 0.9
    assert err[keep].mean() <= 0.05, f"mean relative error {err[keep].mean():.4f}"


def test_without_it_the_recess_is_too_bright(errors: dict[str, tuple[np.ndarray, np.ndarray]]) -> None:
    # The same render lighting every surface with the whole sky (draft) is far off Mitsuba by the wall: the
    # comparison above would notice the visibility missing.
    with_it, keep = errors["standard"]
    without, _ = errors["draft"]
    assert without[keep].mean() > 3.0 * with_it[keep].mean()
    assert without[keep].mean() > 0.15
