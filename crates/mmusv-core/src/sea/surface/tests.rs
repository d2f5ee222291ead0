//! Unit tests of the parent module (`surface.rs`): sampling, shading bands, the march.

use super::*;
use std::f64::consts::TAU;

/// A wave component `a cos(kx x + ky y − ω t + φ)` (the derived fields filled in).
pub(crate) fn comp(a: f64, kx: f64, ky: f64, omega: f64, phase: f64) -> WaveComponent {
    WaveComponent {
        amplitude_m: a,
        omega_rad_s: omega,
        k_rad_m: kx.hypot(ky),
        direction_rad: ky.atan2(kx),
        phase_rad: phase,
        kx,
        ky,
    }
}

/// A small irregular sea: eight components over directions and wavelengths 12..80 m, amplitudes summing
/// to 1.6 m.
pub(crate) fn test_sea() -> Vec<WaveComponent> {
    (0..8)
        .map(|i| {
            let k = std::f64::consts::TAU / (12.0 + 9.5 * i as f64);
            let dir = 0.4 + 0.37 * i as f64;
            comp(0.2, k * dir.cos(), k * dir.sin(), (9.81 * k).sqrt(), 1.3 * i as f64)
        })
        .collect()
}

/// The elevation summed point by point (the independent reference).
fn eta(c: &[WaveComponent], x: f64, y: f64, t: f64) -> f64 {
    c.iter().map(|w| w.amplitude_m * (w.kx * x + w.ky * y - w.omega_rad_s * t + w.phase_rad).cos()).sum()
}

fn surface(sea: &[WaveComponent], t: f64, foci: &[[f32; 2]], spec: SurfaceSpec) -> WaveSurface {
    WaveSurface::new(sea, t, 0.0, foci, spec).unwrap_or_else(|e| unreachable!("{e}"))
}

#[test]
fn nodes_hold_the_analytic_elevation_and_slope() {
    let c = test_sea();
    let spec = SurfaceSpec { radius_m: 2000.0, ..SurfaceSpec::default() };
    let s = surface(&c, 12.5, &[[130.0, -40.0]], spec);
    let mut checked = 0;
    for (k, tile) in s.tiles.iter().enumerate() {
        if tile.n == 0 || k % 7 != 0 {
            continue;
        }
        let (ix, iy) = (k % s.ntx, k / s.ntx);
        let w = tile.n + 1;
        for j in (0..w).step_by(3) {
            for i in (0..w).step_by(5) {
                let x = f64::from(s.x0 + ix as f32 * s.tile_m) + i as f64 * f64::from(s.tile_m) / tile.n as f64;
                let y = f64::from(s.y0 + iy as f32 * s.tile_m) + j as f64 * f64::from(s.tile_m) / tile.n as f64;
                if nearest(&[[130.0, -40.0]], x as f32, y as f32) > spec.radius_m - spec.taper_m {
                    continue; // tapered
                }
                let e = eta(&c, x, y, 12.5);
                assert!((f64::from(tile.h[j * w + i]) - e).abs() < 2e-4, "tile {k} node {i},{j}");
                // The slopes: those of the waves at least four cells long only.
                let cell = f64::from(s.tile_m) / tile.n as f64;
                let gx: f64 = c
                    .iter()
                    .filter(|w| std::f64::consts::TAU / w.k_rad_m >= 4.0 * cell)
                    .map(|w| -w.amplitude_m * w.kx * w.phase_at(x, y, 12.5).sin())
                    .sum();
                assert!((f64::from(tile.g[j * w + i][0]) - gx).abs() < 2e-4);
                checked += 1;
            }
        }
    }
    assert!(checked > 500);
    assert!(s.zmax() > 0.5 && s.zmax() <= 1.6 && s.zmin() < -0.5);
}

/// A wave shorter than four cells leaves the level's shading slopes and becomes its roughness: its slope
/// variance `a²k²/2` exactly, at every level too coarse for it, so resolved and unresolved slopes together
/// keep the sea's whole mean square slope at every level; the heights keep it at every level.
#[test]
fn short_waves_become_roughness_not_aliased_slopes() {
    // 1.5 m and 12 m waves: the first is resolved nowhere (finest cell 1 m), the second up to 2 m cells.
    let (k1, k2) = (std::f64::consts::TAU / 1.5, std::f64::consts::TAU / 12.0);
    let sea = [comp(0.02, k1 * 0.6, k1 * 0.8, 0.0, 0.3), comp(0.3, k2, 0.0, 0.0, 1.1)];
    let spec = SurfaceSpec { radius_m: 2000.0, ..SurfaceSpec::default() };
    let s = surface(&sea, 0.0, &[[0.0, 0.0]], spec);
    let (m1, m2) = ((0.02 * k1).powi(2) / 2.0, (0.3 * k2).powi(2) / 2.0);
    let mut seen = [false; 4];
    for (k, tile) in s.tiles.iter().enumerate().filter(|(_, t)| t.n > 0) {
        let centre = [s.x0 + ((k % s.ntx) as f32 + 0.5) * s.tile_m, s.y0 + ((k / s.ntx) as f32 + 0.5) * s.tile_m];
        if nearest(&[[0.0, 0.0]], centre[0], centre[1]) > spec.radius_m - spec.taper_m {
            continue; // tapered
        }
        let cell = f64::from(s.tile_m) / tile.n as f64;
        let want = if cell * 4.0 > 12.0 { m1 + m2 } else { m1 };
        assert!((f64::from(tile.mss) - want).abs() < 1e-6 * want.max(1e-3), "cell {cell}: {} vs {want}", tile.mss);
        // The shading slopes are the long wave's alone where it is resolved (no 1.5 m aliasing), none else.
        for (q, g) in tile.g.iter().enumerate().step_by(7) {
            let long = if cell * 4.0 > 12.0 { 0.0 } else { 0.3 * k2 };
            assert!(g[0].abs() <= long as f32 + 1e-5 && g[1].abs() < 1e-5, "cell {cell} node {q}: {g:?}");
        }
        seen[(TILE_CELLS / tile.n).trailing_zeros().min(3) as usize] = true;
    }
    assert!(seen.iter().all(|&v| v), "levels: {seen:?}");
    let sh = s.shading(3.0, 4.0, 0.0).unwrap_or_else(|| unreachable!("inside the sampled tiles"));
    assert!((f64::from(sh.unresolved_mss) - m1).abs() < 1e-9 && sh.normal[2] > 0.9);
}

/// With `detail`, a finest-level tile carries, on a grid of a quarter of its cell, the slopes of the waves
/// too short for its cells in two bands (here a 3 m wave in band 0 and a 1.5 m wave in band 1: their analytic slopes
/// at every detail node); the shading draws each band as normals or roughness by the pixel's footprint;
/// coarser tiles and the geometry do not change.
#[test]
fn detail_bands_hold_the_short_waves_and_follow_the_footprint() {
    let (k1, k2, k3) = (TAU / 3.0, TAU / 12.0, TAU / 1.5);
    let sea = [comp(0.04, k1 * 0.6, k1 * 0.8, 0.0, 0.3), comp(0.3, k2, 0.0, 0.0, 1.1), comp(0.01, 0.0, k3, 0.0, 2.0)];
    let base = SurfaceSpec { radius_m: 2000.0, ..SurfaceSpec::default() };
    let plain = surface(&sea, 0.0, &[[0.0, 0.0]], base);
    let s = surface(&sea, 0.0, &[[0.0, 0.0]], SurfaceSpec { detail: true, ..base });
    let (m1, m3) = ((0.04 * k1).powi(2) / 2.0, (0.01 * k3).powi(2) / 2.0);

    let slope = |c: &WaveComponent, x: f64, y: f64| {
        let sn = c.phase_at(x, y, 0.0).sin();
        [-c.amplitude_m * c.kx * sn, -c.amplitude_m * c.ky * sn]
    };
    let mut checked = 0;
    for (k, (t, p)) in s.tiles.iter().zip(&plain.tiles).enumerate() {
        assert_eq!(t.h, p.h, "tile {k}: the geometry is the same");
        assert_eq!(t.g, p.g);
        if t.n != TILE_CELLS {
            assert!(t.detail.is_empty() && t.bands == [false; 2] && t.mss == p.mss);
            continue;
        }
        assert!(t.mss.abs() < 1e-9, "every short wave is in a band: {}", t.mss);
        assert!((f64::from(t.band_mss[0]) - m1).abs() < 1e-9 && (f64::from(t.band_mss[1]) - m3).abs() < 1e-9);
        let (x0, y0) = (f64::from(s.x0) + (k % s.ntx) as f64 * 32.0, f64::from(s.y0) + (k / s.ntx) as f64 * 32.0);
        for (band, wave, tol) in [(0, &sea[0], 2e-4), (1, &sea[2], 1e-4)] {
            let w = DETAIL_CELLS + 1;
            assert!(t.detail.len() == w * w && t.bands[band], "tile {k} band {band}");
            let step = 32.0 / DETAIL_CELLS as f64;
            for (q, g) in t.detail.iter().enumerate().step_by(37) {
                let (x, y) = (x0 + (q % w) as f64 * step, y0 + (q / w) as f64 * step);
                let want = slope(wave, x, y);
                let got = [f64::from(g[2 * band]), f64::from(g[2 * band + 1])];
                assert!((got[0] - want[0]).abs() < tol && (got[1] - want[1]).abs() < tol, "band {band} node {q}");
                checked += 1;
            }
        }
    }
    assert!(checked > 100);
    // At a detail node near the focus: a fine footprint adds both bands' slopes; 0.5 m (a top view's pixel)
    // only the 3 m wave's, the 1.5 m wave as roughness; 1 m neither, both as roughness.
    let (x, y) = (3.5f64, 7.0f64); // a detail node: the tiles' corners are multiples of 32 m
    let n0 = plain.shading(x as f32, y as f32, 0.0).unwrap_or_else(|| unreachable!("sampled"));
    let gs = |n: [f32; 3], a: usize| -f64::from(n[a] / n[2]);
    let (a, b) = (slope(&sea[0], x, y), slope(&sea[2], x, y));
    for (footprint, wa, wb, mss) in [(0.1f32, 1.0, 1.0, 0.0), (0.5, 1.0, 0.0, m3), (1.0, 0.0, 0.0, m1 + m3)] {
        let sh = s.shading(x as f32, y as f32, footprint).unwrap_or_else(|| unreachable!("sampled"));
        for ax in 0..2 {
            let want = gs(n0.normal, ax) + wa * a[ax] + wb * b[ax];
            assert!((gs(sh.normal, ax) - want).abs() < 2e-3, "footprint {footprint} axis {ax}");
        }
        assert!((f64::from(sh.unresolved_mss) - mss).abs() < 1e-7, "footprint {footprint}: {}", sh.unresolved_mss);
    }
}

/// Brute force: march the ray in tiny steps against [`WaveSurface::height`] (the same triangulated surface,
/// read point by point) and bisect the first sign change.
fn brute(s: &WaveSurface, o: [f32; 3], d: [f32; 3], t_max: f32, step: f32) -> Option<f32> {
    let f = |t: f32| o[2] + d[2] * t - s.height(o[0] + d[0] * t, o[1] + d[1] * t);
    let mut t = 0.0;
    let mut fa = f(0.0);
    while t < t_max {
        let tb = (t + step).min(t_max);
        let fb = f(tb);
        if (fa > 0.0) != (fb > 0.0) {
            let (mut lo, mut hi) = (t, tb);
            for _ in 0..40 {
                let m = 0.5 * (lo + hi);
                if (f(m) > 0.0) == (fa > 0.0) {
                    lo = m
                } else {
                    hi = m
                }
            }
            return Some(0.5 * (lo + hi));
        }
        t = tb;
        fa = fb;
    }
    None
}

/// The tiles of a real wave field against the field's own row-recurrence grid over each tile.
#[test]
fn field_tiles_match_the_fields_own_grids() {
    use crate::ocean::{SeaSpec, WaveField};
    let spec = SeaSpec { hs: 3.5, tp: 9.0, gamma: 3.3, direction_rad: 0.7, spread_s: 8.0 };
    let f = WaveField::new(&spec, 77).unwrap_or_else(|e| unreachable!("{e}"));
    let foci = [[-1234.5f32, 877.25]];
    let spec = SurfaceSpec { radius_m: 500.0, taper_m: 0.0, ..SurfaceSpec::default() };
    let s = WaveSurface::new(f.components(), 41.3, 0.0, &foci, spec).unwrap_or_else(|e| unreachable!("{e}"));
    let mut levels = [0usize; 6];
    for (k, tile) in s.tiles.iter().enumerate() {
        if tile.n == 0 {
            continue;
        }
        levels[(TILE_CELLS / tile.n).trailing_zeros() as usize] += 1;
        let (ix, iy) = (k % s.ntx, k / s.ntx);
        let (x0, y0) = (f64::from(s.x0 + ix as f32 * s.tile_m), f64::from(s.y0 + iy as f32 * s.tile_m));
        let w = tile.n + 1;
        let dx = f64::from(s.tile_m) / tile.n as f64;
        let (h, gx, gy) = f.elevation_slope_grid(x0, y0, dx, w, w, 41.3).unwrap_or_else(|e| unreachable!("{e}"));
        for q in 0..w * w {
            let (xq, yq) = (x0 + (q % w) as f64 * dx, y0 + (q / w) as f64 * dx);
            if nearest(&foci, xq as f32, yq as f32) >= spec.radius_m {
                continue; // still water beyond the radius
            }
            assert!((tile.h[q] - h[q]).abs() < 1e-4, "tile {k} node {q}: {} vs {}", tile.h[q], h[q]);
            // The tile's slopes leave out the waves its cells cannot resolve: add theirs back, point by point.
            let (mut ux, mut uy) = (0.0f64, 0.0f64);
            for w in f.components().iter().filter(|w| !resolved(w.k_rad_m, dx as f32)) {
                let sn = w.phase_at(xq, yq, 41.3).sin();
                ux -= w.amplitude_m * w.kx * sn;
                uy -= w.amplitude_m * w.ky * sn;
            }
            let (ax, ay) = (f64::from(tile.g[q][0]) + ux, f64::from(tile.g[q][1]) + uy);
            assert!((ax - f64::from(gx[q])).abs() < 2e-4 && (ay - f64::from(gy[q])).abs() < 2e-4, "tile {k} {q}");
        }
    }
    assert!(levels[..5].iter().all(|&c| c > 0), "every level sampled: {levels:?}");
}

#[test]
fn intersect_matches_a_dense_march_of_the_surface() {
    let c = test_sea();
    let spec = SurfaceSpec { radius_m: 300.0, taper_m: 60.0, ..SurfaceSpec::default() };
    let s = surface(&c, 3.0, &[[0.0, 0.0], [90.0, 40.0]], spec);
    let mut state = 11u64;
    let mut rand = |lo: f32, hi: f32| {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        lo + (hi - lo) * ((state >> 40) as f32 / (1u64 << 24) as f32)
    };
    let (mut hits, mut grazing, mut agree) = (0, 0, 0);
    let n = 1500;
    for i in 0..n {
        let o = [rand(-60.0, 60.0), rand(-60.0, 60.0), rand(1.0, 6.0)];
        // Mostly grazing rays (crests occlude), some steep, some up.
        let el = if i % 10 == 0 { rand(0.0, 0.3) } else { -rand(0.002, if i % 3 == 0 { 1.2 } else { 0.08 }) };
        let az = rand(0.0, std::f32::consts::TAU);
        let d = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
        let t_max = 400.0;
        let fast = s.intersect(o, d, t_max).map(|h| h.t);
        let slow = brute(&s, o, d, t_max, 0.01);
        match (fast, slow) {
            (Some(a), Some(b)) => {
                assert!((a - b).abs() < 0.02 + 1e-4 * b, "ray {i}: {a} vs brute {b} ({o:?} {d:?})");
                hits += 1;
                grazing += usize::from(d[2] > -0.08);
                agree += 1;
            }
            (None, None) => agree += 1,
            // A crossing thinner than the brute force's step can be missed by it, never by the march.
            (Some(a), None) => {
                let h = s.height(o[0] + d[0] * a, o[1] + d[1] * a);
                assert!((o[2] + d[2] * a - h).abs() < 1e-3, "ray {i}: a hit at {a} off the surface");
            }
            (None, Some(b)) => panic!("ray {i}: brute force hits at {b}, the march misses ({o:?} {d:?})"),
        }
    }
    assert!(agree > n * 99 / 100, "{agree} of {n} agree");
    assert!(hits > 1000 && grazing > 500, "{hits} hits, {grazing} grazing");
}

/// Rays looking straight down (a top view's, whose direction keeps a horizontal drift of `1e-17` from its
/// rotation), solved on the piece under their point: the surface's height there and its piece, and the same hit as
/// a ray tilted just enough (`1e-5`) to take the walk.
#[test]
fn straight_down_rays_meet_the_piece_under_them() {
    let c = test_sea();
    let s = surface(&c, 7.0, &[[0.0, 0.0]], SurfaceSpec::default());
    let mut n = 0;
    for j in 0..40 {
        for i in 0..40 {
            // Over fine, coarse, tapered and still water (the rectangle reaches about ±352 m).
            let (x, y) = (-390.0 + 19.7 * i as f32, -388.0 + 19.3 * j as f32);
            let o = [x, y, 120.0];
            for d in [[0.0, 0.0, -1.0], [-6.6e-19, 6.1e-17, -1.0]] {
                let Some(h) = s.intersect(o, d, 500.0) else { panic!("({x}, {y}): no hit straight down") };
                let z = s.height(x, y);
                assert!((120.0 - h.t - z).abs() < 1e-4, "({x}, {y}): hit at z {} over a surface at {z}", 120.0 - h.t);
                let tilted = [1e-5, 0.0, -1.0f32];
                let w = s.intersect(o, tilted, 500.0).map(|w| w.t);
                assert!(w.is_some_and(|w| (w - h.t).abs() < 5e-4), "({x}, {y}): {} vs the walk's {w:?}", h.t);
                assert_eq!(s.piece_normal(h.piece), s.piece_normal(s.height_piece(x, y).1));
                n += 1;
            }
            // Beyond its range, or from under the surface going down: no hit.
            assert!(s.intersect(o, [0.0, 0.0, -1.0], 100.0).is_none());
            assert!(s.intersect([x, y, s.height(x, y) - 0.5], [0.0, 0.0, -1.0], 500.0).is_none());
        }
    }
    assert_eq!(n, 3200);
}

#[test]
fn crests_hide_what_lies_behind_them() {
    // One long-crested swell along x, 1 m amplitude, 60 m long (crests at x = 0, 60, 120 m): from 1.2 m
    // above the still level looking along x at a point 0.3 m above it 150 m away, the crest at 60 m hides it.
    let k = std::f64::consts::TAU / 60.0;
    let s = surface(&[comp(1.0, k, 0.0, 0.0, 0.0)], 0.0, &[[0.0, 0.0]], SurfaceSpec::default());
    let o = [0.0, 0.0, 1.2];
    let target = [150.0f32, 0.0, 0.3];
    let dv = [target[0] - o[0], target[1] - o[1], target[2] - o[2]];
    let len = (dv[0] * dv[0] + dv[2] * dv[2]).sqrt();
    let d = [dv[0] / len, 0.0, dv[2] / len];
    let Some(h) = s.intersect(o, d, len) else { panic!("the crest at x = 60 m hides the target") };
    let x = o[0] + d[0] * h.t;
    assert!((45.0..=60.0).contains(&x), "hit at x = {x}");
    // A ray above every crest meets nothing, whatever its length.
    assert!(s.intersect([0.0, 0.0, 1.2], [1.0, 0.0, 0.0], 1e6).is_none());
    // The flat beyond the radius: a ray down far away meets the still level.
    let Some(far) = s.intersect([5000.0, 0.0, 10.0], [0.0, 0.0, -1.0], 100.0) else { panic!("still water") };
    assert!((far.t - 10.0).abs() < 1e-4 && far.piece == FLAT_PIECE);
}

#[test]
fn normals_face_up_and_follow_the_slope() {
    let k = std::f64::consts::TAU / 40.0;
    let s = surface(&[comp(0.8, k, 0.0, 0.0, 0.0)], 0.0, &[[0.0, 0.0]], SurfaceSpec::default());
    // At x = 10 m (a quarter wave) the slope is −a k: the normal leans towards +x.
    let n = s.shading_normal(10.0, 3.0).unwrap_or_default();
    let want = (0.8 * k) as f32;
    assert!((n[0] / n[2] - want).abs() < 1e-3, "{n:?}");
    let Some(h) = s.intersect([10.0, 3.0, 5.0], [0.0, 0.0, -1.0], 10.0) else { panic!("a ray straight down") };
    let g = s.piece_normal(h.piece);
    assert!(g[2] > 0.0 && (g[0] / g[2] - want).abs() < 0.01, "{g:?}");
}

/// Sampled without its slopes (nothing renders), the surface is the same geometry bit for bit — the same heights,
/// bounds and hits — and has no shading to give.
#[test]
fn a_surface_without_slopes_has_the_same_geometry_and_no_shading() {
    let c = test_sea();
    let foci = [[0.0f32, 0.0], [150.0, 60.0]];
    let with = surface(&c, 4.0, &foci, SurfaceSpec { detail: true, ..SurfaceSpec::default() });
    let without = surface(&c, 4.0, &foci, SurfaceSpec { detail: true, slopes: false, ..SurfaceSpec::default() });
    assert_eq!((with.zmin(), with.zmax()), (without.zmin(), without.zmax()));
    let (mut shaded, mut hits) = (0, 0);
    for k in 0..4000u32 {
        let (x, y) = (-300.0 + 0.151 * k as f32, -250.0 + 0.137 * ((k * 37) % 4000) as f32);
        assert_eq!(with.height(x, y).to_bits(), without.height(x, y).to_bits(), "height at {x}, {y}");
        shaded += usize::from(with.shading(x, y, 0.1).is_some());
        assert!(without.shading(x, y, 0.1).is_none(), "shading at {x}, {y} without slopes");
        let (o, el) = ([x, y, 2.5], -0.02 - 0.3 * (k % 7) as f32 / 7.0);
        let d = [el.cos() * (0.7 * k as f32).cos(), el.cos() * (0.7 * k as f32).sin(), el.sin()];
        let (a, b) = (with.intersect(o, d, 300.0), without.intersect(o, d, 300.0));
        assert_eq!(a, b, "ray {k}");
        hits += usize::from(a.is_some());
    }
    assert!(shaded > 2000 && hits > 2000, "{shaded} shaded points, {hits} hits");
}

/// The spatial means over the annulus `r0..r1` m around the origin (20,000 points: golden-angle turns, radii
/// uniform in area) of the drawn slopes' square `|∇η|²` and of the roughness, at pixel footprint `footprint` (m).
fn annulus_means(s: &WaveSurface, r0: f32, r1: f32, footprint: f32) -> (f64, f64) {
    let (mut g2, mut rough, n) = (0f64, 0f64, 20_000u32);
    for k in 0..n {
        let f = (k as f32 + 0.5) / n as f32;
        let r = (r0 * r0 + f * (r1 * r1 - r0 * r0)).sqrt();
        let a = k as f32 * 2.399_963;
        let sh = s.shading(r * a.cos(), r * a.sin(), footprint).unwrap_or_else(|| unreachable!("a wavy sea"));
        let [nx, ny, nz] = sh.normal.map(f64::from);
        g2 += (nx * nx + ny * ny) / (nz * nz);
        rough += f64::from(sh.unresolved_mss);
    }
    (g2 / f64::from(n), rough / f64::from(n))
}

/// The sampled sea is a level of detail, not the sea's end: the total slope variance a pixel shades with (the
/// drawn normals' `|∇η|²` plus the roughness) is the waves' `Σ a²k²/2` where every wave is drawn, where the taper
/// takes the drawn slopes away, and beyond, where the still level is shaded with all of it as roughness.
#[test]
fn the_total_slope_variance_is_the_seas_through_the_taper_and_beyond() {
    let c = test_sea();
    let total: f64 = c.iter().map(WaveComponent::slope_variance).sum();
    let spec = SurfaceSpec::default(); // waves taper between 260 and 320 m
    let s = surface(&c, 3.0, &[[0.0, 0.0]], spec);
    for (r0, r1) in [(5.0, 60.0), (270.0, 300.0), (330.0, 600.0)] {
        let (drawn, rough) = annulus_means(&s, r0, r1, 0.0);
        let got = drawn + rough;
        assert!((got - total).abs() < 0.12 * total, "{r0}..{r1} m: {got} against the sea's {total}");
        match r0 {
            // Near the focus (1 and 2 m cells) every wave is drawn: no roughness.
            5.0 => assert!(rough < 1e-9, "{r0}..{r1} m: roughness {rough}"),
            // In the taper (8 m cells, half the slopes tapered away) most of it is roughness.
            270.0 => assert!(rough > 0.5 * total && rough < got, "{r0}..{r1} m: roughness {rough} of {got}"),
            // Beyond, all of it.
            _ => assert!((rough - total).abs() < 1e-6 * total, "{r0}..{r1} m: {rough}"),
        }
    }
    let far = s.shading(5000.0, -7000.0, 1.0).unwrap_or_else(|| unreachable!("the sea goes on"));
    assert_eq!(far.normal, [0.0, 0.0, 1.0]);
    assert!((f64::from(far.unresolved_mss) - total).abs() < 1e-6 * total);
    // Without waves there is nothing to shade with.
    assert!(surface(&[], 3.0, &[[0.0, 0.0]], spec).shading(0.0, 0.0, 0.0).is_none());
}

/// The elevation's standard deviation is the components' `√(Σ a²/2)`: a single wave's `a/√2`, and a W3 field's
/// `H_s / 4` (it realises its 3.5 m); none without waves.
#[test]
fn elevation_std_is_the_seas() {
    let k = TAU / 60.0;
    let s = surface(&[comp(1.2, k, 0.0, (9.81 * k).sqrt(), 0.4)], 2.0, &[[0.0, 0.0]], SurfaceSpec::default());
    assert!((f64::from(s.elevation_std()) - 1.2 / 2f64.sqrt()).abs() < 1e-6);
    use crate::ocean::{paper_sea_states, WaveField};
    let f = WaveField::new(&paper_sea_states()[3].spec(0.8, 10.0), 11).unwrap_or_else(|e| unreachable!("{e}"));
    let w3 = WaveSurface::new(f.components(), 0.0, 0.0, &[[0.0, 0.0]], SurfaceSpec::default())
        .unwrap_or_else(|e| unreachable!("{e}"));
    assert!((f64::from(w3.elevation_std()) * 4.0 - 3.5).abs() < 0.02 * 3.5, "{}", w3.elevation_std());
    assert_eq!(surface(&[], 2.0, &[[0.0, 0.0]], SurfaceSpec::default()).elevation_std(), 0.0);
}

/// With `fine_m`, the coarser tiles near a focus carry the finest grid's waves (here a 6 m wave, which 1 m
/// cells resolve and 2 m cells do not) at their analytic slopes, and a pixel footprint that resolves them draws
/// them: a top view (one footprint everywhere) sees the same waves on every level, no squares at the levels'
/// edges; a wide footprint takes them as roughness; beyond `fine_m` and in the geometry nothing changes.
#[test]
fn fine_slopes_make_every_level_alike_for_a_fine_footprint() {
    let (k6, k40, k15) = (TAU / 6.0, TAU / 40.0, TAU / 1.5);
    let sea = [comp(0.05, k6 * 0.6, k6 * 0.8, 0.0, 0.3), comp(0.5, k40, 0.0, 0.0, 1.1), comp(0.01, 0.0, k15, 0.0, 2.0)];
    let (m6, m40, m15) = ((0.05 * k6).powi(2) / 2.0, (0.5 * k40).powi(2) / 2.0, (0.01 * k15).powi(2) / 2.0);
    let base = SurfaceSpec { radius_m: 2000.0, detail: true, ..SurfaceSpec::default() };
    let plain = surface(&sea, 0.0, &[[0.0, 0.0]], base);
    let s = surface(&sea, 0.0, &[[0.0, 0.0]], SurfaceSpec { fine_m: 150.0, ..base });
    let mut checked = 0;
    for (k, (t, p)) in s.tiles.iter().zip(&plain.tiles).enumerate() {
        assert!(t.h == p.h && t.g == p.g, "tile {k}: the geometry and the level's slopes are the same");
        let (ix, iy) = (k % s.ntx, k / s.ntx);
        let (x0, y0) = (s.x0 + ix as f32 * 32.0, s.y0 + iy as f32 * 32.0);
        let near = nearest(&[[0.0, 0.0]], x0 + 16.0, y0 + 16.0) - std::f32::consts::SQRT_2 * 16.0 <= 150.0;
        if t.n == TILE_CELLS || !near {
            assert!(t.fine.is_empty() && t.mss == p.mss, "tile {k}");
            continue;
        }
        assert!((f64::from(t.fine_mss) - m6).abs() < 1e-9 && (f64::from(t.mss) - m15).abs() < 1e-9, "tile {k}");
        for (q, g) in t.fine.iter().enumerate().step_by(41) {
            let (x, y) = (f64::from(x0) + (q % 33) as f64, f64::from(y0) + (q / 33) as f64);
            let sn = sea[0].phase_at(x, y, 0.0).sin();
            let want = [-0.05 * sea[0].kx * sn, -0.05 * sea[0].ky * sn];
            assert!((f64::from(g[0]) - want[0]).abs() < 2e-4 && (f64::from(g[1]) - want[1]).abs() < 2e-4, "{k} {q}");
            checked += 1;
        }
    }
    assert!(checked > 100);
    // The finest tiles (within 40 m), the 2 m and the 4 m ones: the same waves drawn with `fine_m`, not without.
    let (inner, _) = annulus_means(&s, 5.0, 25.0, 0.5);
    for (r0, r1) in [(60.0, 75.0), (100.0, 140.0)] {
        let (got, rough) = annulus_means(&s, r0, r1, 0.5);
        assert!((got - inner).abs() < 0.1 * inner && (got - (m6 + m40)).abs() < 0.1 * (m6 + m40), "{r0}: {got}");
        assert!((rough - m15).abs() < 1e-6, "{r0}: roughness {rough}");
        let (without, _) = annulus_means(&plain, r0, r1, 0.5);
        assert!(without < inner - 0.5 * m6, "{r0}: {without} drawn without fine slopes against {inner}");
        // A footprint of 2 m or more takes them as roughness.
        let (wide, rough) = annulus_means(&s, r0, r1, 2.5);
        assert!((wide - without).abs() < 1e-3 * without && (rough - m6 - m15).abs() < 1e-6, "{r0}");
    }
}

/// `tiles_for` counts the grid `new` samples (checked on surfaces built here), and `check_extent` refuses foci far
/// apart or a huge radius before anything is allocated, naming `foci`.
#[test]
fn the_tile_count_is_the_grids_and_huge_extents_are_refused() {
    let sea = test_sea();
    for (foci, radius) in [
        (vec![[0.0f32, 0.0]], 320.0f32),
        (vec![[-17.5, 3.0], [250.0, -90.0]], 100.0),
        (vec![[1000.0, 1000.0], [1010.0, 990.0], [960.0, 1100.0]], 64.0),
        (vec![], 320.0),
    ] {
        let spec = SurfaceSpec { radius_m: radius, ..SurfaceSpec::default() };
        let s = surface(&sea, 0.0, &foci, spec);
        assert_eq!(spec.tiles_for(&foci), (s.ntx * s.nty) as u64, "{foci:?}");
        assert!(spec.check_extent(&foci).is_ok());
    }
    let far = [[-2e5f32, -2e5], [2e5, 2e5]];
    let Err(e) = SurfaceSpec::default().check_extent(&far) else { panic!("400 km apart accepted") };
    assert!(e.to_string().contains("foci"), "{e}");
    let huge = SurfaceSpec { radius_m: 1e30, ..SurfaceSpec::default() };
    assert_eq!(huge.tiles_for(&[[0.0, 0.0]]), u64::MAX);
    assert!(huge.check_extent(&[[0.0, 0.0]]).is_err());
}

/// Frame times up to ±`MAX_TIME_S` sample a finite sea; past it (1e308 s made every height NaN, a sea that every
/// ray passed through) or not finite, `new` is an error naming `time_s`.
#[test]
fn frame_times_past_the_bound_are_refused() {
    let sea = test_sea();
    let spec = SurfaceSpec { radius_m: 64.0, ..SurfaceSpec::default() };
    for t in [-MAX_TIME_S, 0.0, 3.7e8, MAX_TIME_S] {
        let s = surface(&sea, t, &[[0.0, 0.0]], spec);
        assert!(s.zmin.is_finite() && s.zmax.is_finite() && s.zmax > s.zmin, "{t}");
    }
    for t in [1.0000001e9, -2e9, 1e308, f64::INFINITY, f64::NAN] {
        let Err(e) = WaveSurface::new(&sea, t, 0.0, &[[0.0, 0.0]], spec) else { panic!("time {t} accepted") };
        assert!(e.to_string().contains("time_s"), "{e}");
    }
}

#[test]
fn a_calm_sea_still_stops_every_ray() {
    // Waves of micrometres (hs_m 1e-6, or no waves at all) make a band of heights thinner than a ray's height
    // rounds to at its range: it must still hold the water, as the still plane does.
    let k = TAU / 40.0;
    for a in [0.0, 5e-7, 1e-6, 1e-4] {
        let c = [comp(a, k, 0.0, 0.0, 0.0)];
        let s = surface(&c, 0.0, &[[0.0, 0.0]], SurfaceSpec::default());
        for (o, d) in [
            ([0.0f32, 0.0, 50.0], [0.0f32, 0.0, -1.0]),
            ([20.0, 5.0, 30.0], [0.0, 0.0, -1.0]),
            ([40.0, -20.0, 3000.0], [0.0, 0.0, -1.0]),
            ([0.0, 0.0, 2.0], [0.6, 0.0, -0.8]),
            ([0.0, 0.0, 2.0], [0.99995, 0.0, -0.01]),
            ([9000.0, 0.0, 40.0], [0.0, 0.6, -0.8]),
        ] {
            let Some(h) = s.intersect(o, d, 1e5) else { panic!("a = {a}: {o:?} + t {d:?} passes through the water") };
            let z = o[2] + d[2] * h.t;
            assert!(z.abs() < 2e-3 * (1.0 + h.t / 1000.0), "a = {a}: {o:?} + t {d:?} meets z = {z}");
        }
    }
}
