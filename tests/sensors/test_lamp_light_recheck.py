"""An independent re-check of the navigation lamps' light on surfaces at night (``sensors/shade/lamp_light.rs``,
``sensors/camera/lamp_light.rs``) against closed forms computed here, not by the code under test.

The scene: a grey Lambertian wall (the face ``x = 0`` of a box, normal ``+x``, roughness 1) and a small lit
lantern (a closed cube of side ``S`` and lens radiance ``L_e`` in every channel) in front of it, at night (the sun
below the horizon), no water. A lantern's intensity towards a unit direction ``ω`` is ``L_e`` times its projected
area, for a cube ``½ Σ |A_i n_i·ω| = S² (|ω_x| + |ω_y| + |ω_z|)``, and a Lambertian surface of albedo ``ρ`` under it
has radiance ``ρ/π · I cos θ / r²`` (the photometric inverse-square and cosine laws). Each pixel's closed form is
taken at the wall point its centre ray (``Camera.world_rays``) meets.

The lamp's part of a pixel's radiance is isolated by a double difference that needs no model of the rest:
``[on(ρ) − off(ρ)] − [on(0) − off(0)]`` (lights on and off, a grey and a black wall): the night sky's light
cancels in ``on − off`` and the GGX specular lobe (2–3 % of the diffuse at roughness 1, the same for both albedos
since ``F0 = 0.04`` does not depend on the base colour of a dielectric) in the second difference, leaving
``ρ/π (n·l) E`` alone. ``radiance`` (linear, before exposure) is compared, never the exposed ``rgb``.

Measured on this build: the wall's lamp light is 0.17–0.19 % under the closed form 2 m from the lantern and
0.05 % under 4 m from it, face on; 0.12–0.32 % and 0.04–0.06 % under at 60° (the wall points 1.4–2.6 m and
3.4–4.6 m off) — all of it what ``E = I/(r² + ρ_lens²)`` takes off, the lens radius ``ρ_lens = S√3/2`` bounding
the light at the lantern (``ρ_lens²/r²`` = 0.19 % at 2 m, 0.05 % at 4 m). Inside an arc as much, outside and in
a screen's shadow exactly nothing; the fog's ``exp(−σ (r + t))`` within 3·10⁻⁷; the orthographic top view
0.10–0.24 % under; the water's reflection of the lit wall 0.5 % under over the sum. The bound is 1 % (3 % for
the water's sum); a lamp 10 % brighter, a law without the cosine or with ``1/r`` instead of ``1/r²``, or a fog
that dims only the camera ray fail it.
"""

from __future__ import annotations

import math
from typing import Any

import mmusv
import numpy as np
import numpy.typing as npt
import pytest
from mmusv import _core
from mmusv.sensors.camera import render as render_camera
from reference import mitsuba_scenes as ms

#: The lantern's lens radiance (cd/m², every channel), its side (m), the wall's albedo.
LE = 2.0e4
S = 0.1
RHO = 0.5
#: The wall: the face ``x = 0`` of this box, normal +x.
WALL = ((-0.2, -10.0, -5.0), (0.0, 10.0, 5.0))
WALL_POINT, WALL_NORMAL = np.zeros(3), np.array([1.0, 0.0, 0.0])
#: Night (the sun 38° below the horizon) and day (30° up).
NIGHT_SUN = ms.unit((0.3, 0.5, -0.4))
DAY_SUN = (math.cos(math.radians(30.0)) * 0.6, math.cos(math.radians(30.0)) * 0.8, math.sin(math.radians(30.0)))
#: A camera 5 m from the wall's point (0, 0, 0), looking at it from 37° off its normal, 10° across, 32 × 24.
POSE = ms.look_pose((4.0, 3.0, 0.0), math.atan2(-3.0, -4.0), 0.0)
W, H = 32, 24
#: The bound on the relative error of the lamp's light against the closed form.
TOL = 0.01


def _env(sun: tuple[float, float, float], fog: float = 0.0) -> Any:
    """A ``SensorEnv``: clear, calm, shadows on, the sun towards ``sun``, fog extinction ``fog`` (1/m)."""
    return ms.Env(sun=sun).sensor_env(fog_extinction_per_m=fog)


def _camera(ortho: bool = False) -> Any:
    if ortho:
        return _core.Camera(width=W, height=H, rgb=True, metres_per_pixel=0.05, quality="standard")
    return _core.Camera(width=W, height=H, rgb=True, hfov=math.radians(10.0), quality="standard")


def _box_at(c: tuple[float, float, float], side: float) -> tuple[Any, Any]:
    h = side / 2.0
    v, f = ms.box((c[0] - h, c[1] - h, c[2] - h), (c[0] + h, c[1] + h, c[2] + h))
    return v, f


def _render(
    lamp: tuple[float, float, float],
    *,
    rho: float = RHO,
    on: bool = True,
    emission: float = LE,
    arc: tuple[float, float] = (0.0, 180.0),
    nav: bool = True,
    screen: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None,
    wall: tuple[tuple[float, float, float], tuple[float, float, float]] = WALL,
    env: Any = None,
    pose: npt.NDArray[np.float64] = POSE,
    ortho: bool = False,
    water: bool = False,
    lantern_yaw_deg: float = 0.0,
) -> Any:
    """The camera's images (radiance too) of the wall and the lantern centred on ``lamp`` (and calm water at
    ``z = 0``, the last instance, with ``water``)."""
    s = mmusv.Scene()
    e = emission
    lens = [0, 0, 0, 0.5, 0, e, e, e, 1, *arc] if nav else [0, 0, 0, 0.5, 0, 0, 0, 0, 0, 0, 180]
    s.set_materials(
        np.array(
            [
                [0.0] * 10 + [180.0],
                lens,
                [rho, rho, rho, 1.0, 0, 0, 0, 0, 0, 0, 180],
                [0, 0, 0, 1.0, 0, 0, 0, 0, 0, 0, 180],
            ],
            np.float32,
        )
    )
    s.add_instance(s.add_mesh(*ms.box(*wall), classes=4, name="wall", materials=2))
    # The lantern's mesh round its own origin, placed at ``lamp`` turned by ``lantern_yaw_deg`` (its body frame, in
    # which the arc's bearings are, turned with it).
    yaw = math.radians(lantern_yaw_deg)
    placed = np.eye(4)
    placed[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
    placed[:3, 3] = lamp
    lantern_mesh = s.add_mesh(*_box_at((0.0, 0.0, 0.0), S), classes=4, name="lantern", materials=1)
    lantern = s.add_instance(lantern_mesh, pose=placed)
    if screen is not None:
        s.add_instance(s.add_mesh(*ms.box(*screen), classes=4, name="screen", materials=3))
    if water:
        s.add_instance(s.add_mesh(*ms.square(2000.0), classes=1, name="water"))
    s.set_lights([lantern], on=on)
    out = render_camera(
        _camera(ortho), s, pose=pose, env=_env(NIGHT_SUN) if env is None else env, seed=0, radiance=True
    )
    assert out.radiance is not None
    return out


def _rad(out: Any) -> npt.NDArray[np.float64]:
    return np.asarray(out.radiance, dtype=np.float64)


def _lamp_part(lamp: tuple[float, float, float], **kw: Any) -> npt.NDArray[np.float64]:
    """The lamp's diffuse light ``(H, W, 3)``: ``[on(ρ) − off(ρ)] − [on(0) − off(0)]``."""
    grey = _rad(_render(lamp, **kw)) - _rad(_render(lamp, on=False, **kw))
    black = _rad(_render(lamp, rho=0.0, **kw)) - _rad(_render(lamp, rho=0.0, on=False, **kw))
    return grey - black


def _closed_form(
    lamp: tuple[float, float, float],
    *,
    emission: float = LE,
    point: npt.NDArray[np.float64] = WALL_POINT,
    normal: npt.NDArray[np.float64] = WALL_NORMAL,
    pose: npt.NDArray[np.float64] = POSE,
    ortho: bool = False,
) -> dict[str, npt.NDArray[np.float64]]:
    """Per pixel ``(H, W)``: ``L = ρ/π · I cos θ / r²`` at the plane point the pixel's centre ray meets, with
    ``r`` (lamp to point), ``t`` (camera to point), the point ``p`` ``(H, W, 3)`` and the direction ``out`` from
    the lamp to the point ``(H, W, 3)``."""
    o, d = _camera(ortho).world_rays(pose)
    o, d = o.astype(np.float64), d.astype(np.float64)
    t = ((point - o) @ normal) / (d @ normal)
    p = o + t[:, None] * d
    v = np.asarray(lamp, dtype=np.float64) - p
    r = np.linalg.norm(v, axis=1)
    w = v / r[:, None]
    intensity = emission * S * S * np.abs(w).sum(axis=1)
    cos = np.clip(w @ normal, 0.0, None)
    lum = RHO / math.pi * intensity * cos / r**2
    return {
        "L": lum.reshape(H, W),
        "r": r.reshape(H, W),
        "t": t.reshape(H, W),
        "p": p.reshape(H, W, 3),
        "out": (-w).reshape(H, W, 3),
        "cos": cos.reshape(H, W),
    }


def _lamp_at(r: float, theta_deg: float) -> tuple[float, float, float]:
    """The lantern ``r`` m from the wall's point (0, 0, 0), ``theta_deg`` off its normal towards −y (out of the
    camera's view and away from its line of sight)."""
    th = math.radians(theta_deg)
    return (r * math.cos(th), -r * math.sin(th), 0.0)


@pytest.mark.parametrize(("r", "theta"), [(2.0, 0.0), (4.0, 0.0), (2.0, 60.0), (4.0, 60.0)])
def test_a_lambertian_wall_under_a_lantern_follows_the_inverse_square_and_cosine_laws(r: float, theta: float) -> None:
    lamp = _lamp_at(r, theta)
    got = _lamp_part(lamp)
    want = _closed_form(lamp)["L"]
    # Grey light on a grey wall: the three channels alike.
    assert np.allclose(got[..., 0], got[..., 1], rtol=1e-5) and np.allclose(got[..., 0], got[..., 2], rtol=1e-5)
    err = np.abs(got[..., 1] / want - 1.0)
    assert err.max() <= TOL, (r, theta, err.max())


def test_the_laws_are_sharp_a_brighter_lamp_or_a_wrong_law_fails() -> None:
    near, far, slant = _lamp_at(2.0, 0.0), _lamp_at(4.0, 0.0), _lamp_at(2.0, 60.0)
    # 10 % more radiance in the lens fails the bound.
    brighter = _lamp_part(near, emission=1.1 * LE)[..., 1] / _closed_form(near)["L"]
    assert np.abs(brighter - 1.0).min() > TOL, brighter.min()
    # Twice as far, the same wall points: a quarter of the light (1/r² with I's own change), not a half (1/r).
    cf_near, cf_far = _closed_form(near), _closed_form(far)
    got = _lamp_part(far)[..., 1] / _lamp_part(near)[..., 1]
    assert np.abs(got / (cf_far["L"] / cf_near["L"]) - 1.0).max() <= TOL
    inverse_linear = (cf_far["L"] / cf_near["L"]) * (cf_far["r"] / cf_near["r"])
    assert np.abs(got / inverse_linear - 1.0).min() > 0.4
    # 60° off the normal (cos θ 0.4..0.65 over the view): a law without the cosine is 35 % off or more.
    cf = _closed_form(slant)
    assert cf["cos"].max() < 0.7
    no_cosine = cf["L"] / cf["cos"]
    got = _lamp_part(slant)[..., 1]
    assert np.abs(got / no_cosine - 1.0).min() > 0.3


def test_a_lamp_lights_only_inside_its_arc() -> None:
    lamp = _lamp_at(2.0, 0.0)
    cf = _closed_form(lamp)
    # The wall lies towards −x of the lamp (bearing 180°, 0 ahead along +x, +90 to port along +y).
    out = cf["out"]
    bearing = np.degrees(np.arctan2(out[..., 1], out[..., 0])) % 360.0
    assert bearing.min() > 160.0 and bearing.max() < 200.0
    whole = _lamp_part(lamp, arc=(180.0, 20.0))[..., 1]
    assert np.abs(whole / cf["L"] - 1.0).max() <= TOL
    # An arc round the bow (centre 0, half-width 20°) leaves the wall dark; so does one to port.
    for arc in ((0.0, 20.0), (90.0, 20.0)):
        on, off = _rad(_render(lamp, arc=arc)), _rad(_render(lamp, arc=arc, on=False))
        assert np.array_equal(on, off), arc
    # An arc 140°..180° splits the wall: the points at bearings below 180° lit as the closed form, those beyond
    # dark (a pixel's footprint, about 1.3° from the lamp, kept off the edge).
    split = _lamp_part(lamp, arc=(160.0, 20.0))[..., 1]
    inside, outside = bearing < 178.5, bearing > 181.5
    assert inside.sum() >= 100 and outside.sum() >= 100, (inside.sum(), outside.sum())
    assert np.abs(split[inside] / cf["L"][inside] - 1.0).max() <= TOL
    assert np.abs(split[outside]).max() <= 1e-6 * cf["L"].max()


def test_the_arc_turns_with_the_lamps_vessel() -> None:
    # The lantern's instance turned 90° to port: the wall, at world bearing 180° from the lamp, lies at 90° (to
    # port) in its body frame. An arc to port lights it as the closed form; one astern (180°, where the wall lies in
    # the world frame) leaves it dark.
    lamp = _lamp_at(2.0, 0.0)
    cf = _closed_form(lamp)
    port = _lamp_part(lamp, arc=(90.0, 20.0), lantern_yaw_deg=90.0)[..., 1]
    assert np.abs(port / cf["L"] - 1.0).max() <= TOL
    on = _rad(_render(lamp, arc=(180.0, 20.0), lantern_yaw_deg=90.0))
    off = _rad(_render(lamp, arc=(180.0, 20.0), lantern_yaw_deg=90.0, on=False))
    assert np.array_equal(on, off)


def test_an_opaque_screen_shadows_the_wall() -> None:
    lamp = _lamp_at(2.0, 0.0)
    # A black screen halfway between, over y < 0: the shadow edge on the wall is the line y = 0.
    screen = ((0.9, -5.0, -5.0), (1.0, 0.0, 5.0))
    out = _render(lamp, screen=screen)
    cf = _closed_form(lamp)
    y = cf["p"][..., 1]
    wall = out.instance == 0
    # The 10 cm lantern's penumbra on the wall is about 10 cm wide: kept out.
    lit, dark = wall & (y > 0.08), wall & (y < -0.08)
    assert lit.sum() >= 100 and dark.sum() >= 100, (lit.sum(), dark.sum())
    got = _lamp_part(lamp, screen=screen)[..., 1]
    assert np.abs(got[lit] / cf["L"][lit] - 1.0).max() <= TOL
    assert np.abs(got[dark]).max() <= 1e-6 * cf["L"].max()
    # Without the screen those points are lit.
    assert (_lamp_part(lamp)[..., 1][dark] >= 0.99 * cf["L"][dark]).all()


def test_lights_off_give_no_lamp_light() -> None:
    lamp = _lamp_at(2.0, 0.0)
    off = _render(lamp, on=False)
    plain = _render(lamp, nav=False)
    # Lights off: the wall as under a plain black box; lights on: far brighter (the lamp's light dominates).
    assert np.array_equal(_rad(off), _rad(plain))
    on = _rad(_render(lamp))
    assert (on[..., 1] > 10.0 * _rad(off)[..., 1]).all()


def test_by_day_the_lamps_light_nothing() -> None:
    lamp = _lamp_at(2.0, 0.0)
    day = _env(DAY_SUN)
    on, off = _render(lamp, env=day), _render(lamp, env=day, on=False)
    assert np.array_equal(on.rgb, off.rgb)
    assert np.array_equal(_rad(on), _rad(off))
    # (At night the same pair differs.)
    assert not np.array_equal(_rad(_render(lamp)), _rad(_render(lamp, on=False)))


def test_fog_dims_the_lamp_light_along_both_paths() -> None:
    lamp = _lamp_at(2.0, 0.0)
    sigma = 0.05
    cf = _closed_form(lamp)
    ratio = _lamp_part(lamp, env=_env(NIGHT_SUN, sigma))[..., 1] / _lamp_part(lamp)[..., 1]
    # Lamp to wall (about 2 m) and wall to camera (about 5 m): exp(-0.35) ≈ 0.70.
    both = np.exp(-sigma * (cf["r"] + cf["t"]))
    assert np.abs(ratio / both - 1.0).max() <= TOL
    # The camera ray's fog alone (exp(-0.25)) is 10 % off.
    camera_only = np.exp(-sigma * cf["t"])
    assert np.abs(ratio / camera_only - 1.0).min() > 5 * TOL


def test_the_same_render_twice_gives_the_same_bytes() -> None:
    lamp = _lamp_at(2.0, 60.0)
    a, b = _render(lamp), _render(lamp)
    assert a.rgb is not None and a.rgb.tobytes() == b.rgb.tobytes()
    assert a.radiance.tobytes() == b.radiance.tobytes()


def test_an_orthographic_top_view_sees_the_lamp_light() -> None:
    # A deck (the top face z = 0 of a box) seen straight down from 10 m, 1.6 × 1.2 m at 5 cm a pixel; the lantern
    # 1.5 m up and 1.5 m off the view's centre (out of it).
    deck = ((-5.0, -5.0, -0.2), (5.0, 5.0, 0.0))
    pose = ms.look_pose((0.0, 0.0, 10.0), 0.0, math.radians(90.0))
    lamp = (1.5, 0.0, 1.5)
    kw: dict[str, Any] = {"wall": deck, "pose": pose, "ortho": True}
    out = _render(lamp, **kw)
    assert (out.instance == 0).all()
    got = _lamp_part(lamp, **kw)[..., 1]
    cf = _closed_form(lamp, point=np.zeros(3), normal=np.array([0.0, 0.0, 1.0]), pose=pose, ortho=True)
    assert np.abs(got / cf["L"] - 1.0).max() <= TOL


def test_the_water_mirrors_the_lamp_lit_wall_lit() -> None:
    # The wall stands in calm water (no wind, no waves); the camera, 3 m up and 5.4 m off, looks down at the water
    # in front of it (incidence 57°..65°), whose traced reflections meet the wall 0.2..1 m up. The lantern is out
    # of the view and of its mirror image, so that the double difference leaves only the wall's lamp light
    # reflected: the water's Fresnel reflectance (unpolarised, n = 1.33) times the closed form at the point the
    # mirrored centre ray meets.
    wall = ((-0.2, -10.0, -2.0), (0.0, 10.0, 5.0))
    lamp = (2.0, -1.5, 1.5)
    pose = ms.look_pose((6.0, 2.0, 3.0), math.atan2(-2.0, -5.0), math.atan2(3.0, math.hypot(5.0, 2.0)))
    kw: dict[str, Any] = {"wall": wall, "pose": pose, "water": True}
    water = _render(lamp, **kw).instance == 2
    got = _lamp_part(lamp, **kw)[..., 1]
    o, d = _camera().world_rays(pose)
    o, d = o.astype(np.float64), d.astype(np.float64)
    p = o + (-o[:, 2] / d[:, 2])[:, None] * d
    mirrored = d * np.array([1.0, 1.0, -1.0])
    q = p + (-p[:, 0] / mirrored[:, 0])[:, None] * mirrored
    v = np.asarray(lamp) - q
    r = np.linalg.norm(v, axis=1)
    w = v / r[:, None]
    lum = RHO / math.pi * LE * S * S * np.abs(w).sum(axis=1) * np.clip(w[:, 0], 0.0, None) / r**2
    ci = -d[:, 2]
    ct = np.sqrt(1.0 - (1.0 - ci**2) / 1.33**2)
    fresnel = 0.5 * (((ci - 1.33 * ct) / (ci + 1.33 * ct)) ** 2 + ((1.33 * ci - ct) / (1.33 * ci + ct)) ** 2)
    want = (fresnel * lum).reshape(H, W)
    keep = water & (q[:, 2] > 0.05).reshape(H, W)
    assert keep.sum() >= 600, keep.sum()
    # Measured on this build: the sum over the water 0.5 % under the closed form (seeds 1 and 2: 0.8 % and 0.3 %
    # over); pixel by pixel −7 %..+12 %, the sampled roughness lobe and the reflections shared between
    # neighbouring pixels (standard quality). Unlit reflections would be 100 % under, a lamp 10 % brighter 10 %
    # over.
    total = got[keep].sum() / want[keep].sum() - 1.0
    assert abs(total) <= 0.03, total
    assert np.abs(got[keep] / want[keep] - 1.0).max() <= 0.25
