//! The wave surface in a scene: it follows the field it samples, and non-finite inputs or foci too far apart
//! are refused.

use super::common::{ok, refuses, spec, square_mesh};
use mmusv_core::geometry::RigidPose;
use mmusv_core::ocean::{SeaSpec, WaveField};
use mmusv_core::scene::Scene;

#[test]
fn a_wave_surface_follows_the_field_it_samples() {
    let field = ok("field", || WaveField::with_components(&SeaSpec { hs: 1.0, tp: 6.0, ..spec() }, 3, 64));
    let spec_s = mmusv_core::sea::SurfaceSpec::default();
    let surface =
        ok("surface", || mmusv_core::sea::WaveSurface::new(field.components(), 10.0, 0.0, &[[0.0, 0.0]], spec_s));
    assert!(surface.zmax() >= surface.zmin());
    assert!(f64::from(surface.zmax()) <= field.max_elevation() + 1e-3);
    // Heights at lattice nodes near the focus (1 m cells): the field's elevation there.
    for (x, y) in [(0.0f32, 0.0f32), (3.0, -7.0), (12.0, 5.0)] {
        let h = f64::from(surface.height(x, y));
        let want = field.elevation(f64::from(x), f64::from(y), 10.0);
        assert!((h - want).abs() < 1e-3, "({x}, {y}): {h} vs {want}");
    }
    let mut scene = Scene::new();
    let sea = scene.add_mesh(ok("sea", || square_mesh("sea", 2000.0, 1)));
    let si = ok("sea instance", || scene.add_instance(sea, RigidPose::IDENTITY, None));
    ok("set_sea", || scene.set_sea(si, &[]));
    ok("set_wave_surface", || scene.set_wave_surface(Some(surface.clone())));
    // A ray straight down at a node meets the surface at the node's height.
    let hits = ok("cast down", || scene.cast_rays(&[[3.0, -7.0, 20.0]], &[[0.0, 0.0, -1.0]], 100.0));
    let want = 20.0 - f64::from(surface.height(3.0, -7.0));
    assert!((f64::from(hits.distance[0]) - want).abs() < 1e-3);
    assert_eq!(hits.instance[0], si as i32);
    assert_eq!(hits.class[0], 1);
    // Too many tiles are refused by the documented check.
    let far = [[-1e7f32, 0.0], [1e7, 0.0]];
    refuses("check_extent", "foci", || spec_s.check_extent(&far));
}

#[test]
fn a_wave_surface_of_non_finite_inputs_is_refused_not_a_vanished_sea() {
    // A NaN time, level or focus gives a surface no ray meets: before the check, a ray straight down at the
    // water missed (+inf) silently.
    let field = ok("field", || WaveField::with_components(&SeaSpec { hs: 1.0, tp: 6.0, ..spec() }, 3, 16));
    let mut scene = Scene::new();
    let sea = scene.add_mesh(ok("sea", || square_mesh("sea", 2000.0, 1)));
    let si = ok("sea instance", || scene.add_instance(sea, RigidPose::IDENTITY, None));
    ok("set_sea", || scene.set_sea(si, &[]));
    let spec_s = mmusv_core::sea::SurfaceSpec::default();
    let comps = field.components();
    // A NaN level gives a surface the scene refuses; a time that is not finite (or past ±MAX_TIME_S) is refused
    // by WaveSurface::new itself, naming time_s.
    let w = ok("NaN level", || mmusv_core::sea::WaveSurface::new(comps, 0.0, f32::NAN, &[[0.0, 0.0]], spec_s));
    refuses("NaN level", "surface", || scene.set_wave_surface(Some(w)));
    for (what, t) in [("NaN time", f64::NAN), ("infinite time", f64::INFINITY), ("time past the bound", 1e12)] {
        refuses(what, "time_s", || mmusv_core::sea::WaveSurface::new(comps, t, 0.0, &[[0.0, 0.0]], spec_s));
    }
    // A NaN focus has no extent: WaveSurface::new itself refuses it.
    refuses("NaN focus", "foci", || mmusv_core::sea::WaveSurface::new(comps, 0.0, 0.0, &[[f32::NAN, 0.0]], spec_s));
    // A valid surface is met by a ray straight down.
    let w = ok("valid", || mmusv_core::sea::WaveSurface::new(comps, 0.0, 0.0, &[[0.0, 0.0]], spec_s));
    ok("valid surface", || scene.set_wave_surface(Some(w)));
    let h = ok("cast", || scene.cast_rays(&[[3.0, 2.0, 10.0]], &[[0.0, 0.0, -1.0]], 100.0));
    assert!(h.distance[0].is_finite());
}

/// `WaveSurface::new` was infallible: foci 2e30 m apart panicked (capacity overflow), foci ~1e7 m apart tried to
/// allocate ~1e7 tiles. It now refuses what `SurfaceSpec::check_extent` refuses.
#[test]
fn wave_surface_new_refuses_foci_too_far_apart() {
    let field = ok("field", || WaveField::with_components(&spec(), 3, 16));
    let comps = field.components();
    for far in [[[-1e30f32, 0.0], [1e30, 0.0]], [[-1e7, 0.0], [1e7, 0.0]]] {
        refuses("far foci", "foci", || mmusv_core::sea::WaveSurface::new(comps, 0.0, 0.0, &far, Default::default()));
    }
}
