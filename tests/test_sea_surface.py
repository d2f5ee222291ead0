"""``mmusv.sea_surface``: the displaced sea surface's arguments — the taper band's and the tile grid's closed forms,
the check of a sea state and the native arguments of ``Scene.set_wave_surface``."""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from mmusv.errors import ConfigError, InputError
from mmusv.sea_surface import (
    MAX_SURFACE_TILES,
    SURFACE_TAPER_M,
    SURFACE_TILE_M,
    check_sea,
    surface_args,
    surface_taper,
    surface_tiles,
)
from mmusv.world.sea_state import sea_spec_for_preset


def test_surface_taper_is_the_cores_linear_taper_to_the_nearest_focus() -> None:
    """1 within radius - 60 m of the nearest focus, linear to 0 at the radius, 0 beyond; a radius under 60 m
    tapers over the whole of it; no focus keeps no wave (the core's sea::surface::sample)."""
    assert SURFACE_TAPER_M == 60.0
    foci = np.array([[0.0, 0.0], [1000.0, 0.0]])
    xy = np.array([[100.0, 0.0], [0.0, 260.0], [290.0, 0.0], [0.0, -305.0], [320.0, 0.0], [500.0, 0.0], [710.0, 0.0]])
    np.testing.assert_allclose(surface_taper(xy, foci=foci, radius_m=320.0), [1.0, 1.0, 0.5, 0.25, 0.0, 0.0, 0.5])
    small = surface_taper([[10.0, 0.0], [0.0, 30.0]], foci=[[0.0, 0.0]], radius_m=40.0)
    np.testing.assert_allclose(small, [0.75, 0.25])
    np.testing.assert_array_equal(surface_taper(xy, foci=np.zeros((0, 2)), radius_m=320.0), np.zeros(len(xy)))
    assert surface_taper([], foci=[], radius_m=320.0).shape == (0,)


@pytest.mark.parametrize(
    ("kw", "err"),
    [
        ({"xy": [[0.0, 0.0, 0.0]]}, r"xy must have shape \(N, 2\), got \(1, 3\)"),
        ({"xy": [["a", "b"]]}, r"xy must be numeric"),
        ({"foci": [[True, False]]}, r"foci must be numeric"),
        ({"radius_m": 0.0}, r"radius_m"),
        ({"radius_m": "320"}, r"radius_m"),
    ],
)
def test_surface_taper_names_a_bad_argument(kw: dict[str, Any], err: str) -> None:
    args: dict[str, Any] = {"xy": [[0.0, 0.0]], "foci": [[0.0, 0.0]], "radius_m": 320.0, **kw}
    with pytest.raises(InputError, match=err):
        surface_taper(args.pop("xy"), **args)


def test_surface_tiles_is_the_aligned_grid_round_the_foci() -> None:
    """The tiles of the SURFACE_TILE_M grid (aligned on its multiples) covering the foci's rectangle grown by the
    radius, counted apart from the core."""
    rng = np.random.default_rng(3)
    for _ in range(20):
        foci = rng.uniform(-500.0, 500.0, size=(int(rng.integers(1, 4)), 2)).astype(np.float32)
        radius = float(rng.uniform(10.0, 400.0))
        lo, hi = foci.min(axis=0) - radius, foci.max(axis=0) + radius
        want = int(np.prod(np.ceil(hi / SURFACE_TILE_M) - np.floor(lo / SURFACE_TILE_M)))
        assert surface_tiles(foci, radius_m=radius) == want
    assert surface_tiles([], radius_m=100.0) == 0


def test_check_sea_takes_a_sea_state_or_none_and_names_what_is_missing() -> None:
    check_sea(None, name="sea")
    check_sea(sea_spec_for_preset("W2"), name="sea")
    half = SimpleNamespace(hs_m=1.0, tp_s=6.0)
    with pytest.raises(InputError, match=r"sea = .*: must be a sea state .* has no gamma, direction_rad, spread_s$"):
        check_sea(half, name="sea")
    bad = SimpleNamespace(hs_m=1.0, tp_s=True, gamma=3.3, direction_rad=0.0, spread_s=10.0)
    with pytest.raises(ConfigError, match=r"environment\.sea\.tp_s"):
        check_sea(bad, name="environment.sea", error=ConfigError)


def test_surface_args_are_the_native_keywords() -> None:
    sea = sea_spec_for_preset("W3")
    assert surface_args(
        None, scenario_seed=1, time_s=0.0, foci=[[0, 0]], radius_m=320.0, detail=True, slopes=True, fine_m=0.0
    ) == (None, {})
    hs, kw = surface_args(
        sea, scenario_seed=7, time_s=2.5, foci=[[1, 2]], radius_m=40.0, detail=False, slopes=True, fine_m=3.0
    )
    assert hs == sea.hs_m
    assert kw["foci"].dtype == np.float32 and kw["foci"].shape == (1, 2) and kw["foci"].flags.c_contiguous
    assert (kw["scenario_seed"], kw["time_s"], kw["radius_m"], kw["fine_m"]) == (7, 2.5, 40.0, 3.0)
    assert kw["taper_m"] == 40.0  # a radius under SURFACE_TAPER_M tapers over all of it
    assert (kw["detail"], kw["slopes"]) == (False, True)
    assert (
        surface_args(
            sea, scenario_seed=7, time_s=2.5, foci=[[1, 2]], radius_m=320.0, detail=True, slopes=True, fine_m=0.0
        )[1]["taper_m"]
        == SURFACE_TAPER_M
    )
    with pytest.raises(TypeError):
        surface_args(sea, 7, 2.5, [[1, 2]], 320.0, True, True, 0.0)  # type: ignore[misc]


def test_surface_args_refuse_foci_too_far_apart_before_the_core_allocates() -> None:
    side = (math.sqrt(MAX_SURFACE_TILES) + 2.0) * SURFACE_TILE_M
    common = {"scenario_seed": 1, "time_s": 0.0, "radius_m": 10.0, "detail": False, "slopes": False, "fine_m": 0.0}
    with pytest.raises(InputError, match=r"would hold .* tiles of 32 m; at most \d+ .*bring the foci closer"):
        surface_args(sea_spec_for_preset("W1"), foci=[[0.0, 0.0], [side, side]], **common)
    with pytest.raises(InputError, match=r"scenario_seed"):
        surface_args(sea_spec_for_preset("W1"), foci=[[0.0, 0.0]], **{**common, "scenario_seed": -1})


def test_the_former_home_still_imports_them() -> None:
    """They lived in ``mmusv.scene`` until 2026-12-07; a user's ``from mmusv.scene import surface_tiles`` works on."""
    import mmusv.scene
    import mmusv.sea_surface

    for name in ("MAX_SURFACE_TILES", "SURFACE_TAPER_M", "SURFACE_TILE_M", "surface_taper", "surface_tiles"):
        assert getattr(mmusv.scene, name) is getattr(mmusv.sea_surface, name), name
