//! The raster's first hits against the march ([`WaveSurface::intersect`]), pixel by pixel.

use super::super::tests::{comp, test_sea};
use super::*;
use crate::sea::SurfaceSpec;

/// A view from `origin` looking at azimuth `az` (radians from +x) and pitch `pitch` (radians, negative down),
/// with a horizontal field of view `hfov`.
fn view(origin: [f32; 3], az: f64, pitch: f64, hfov: f64, width: u32, height: u32) -> PinholeView {
    let (ca, sa, cp, sp) = (az.cos(), az.sin(), pitch.cos(), pitch.sin());
    let forward = [ca * cp, sa * cp, sp];
    let right = [sa, -ca, 0.0];
    // down = right × forward (x right, y down, z forward is right-handed).
    let down = [
        right[1] * forward[2] - right[2] * forward[1],
        right[2] * forward[0] - right[0] * forward[2],
        right[0] * forward[1] - right[1] * forward[0],
    ];
    PinholeView {
        origin,
        forward: forward.map(|x| x as f32),
        right: right.map(|x| x as f32),
        down: down.map(|x| x as f32),
        width,
        height,
        focal: f64::from(width) / (2.0 * (hfov / 2.0).tan()),
    }
}

/// The world unit direction of pixel `(u, v)`'s centre ray (as a camera computes it, in f64 then rounded).
fn pixel_dir(v: &PinholeView, u: u32, w: u32) -> [f32; 3] {
    let a = (f64::from(u) + 0.5 - f64::from(v.width) / 2.0) / v.focal;
    let b = (f64::from(w) + 0.5 - f64::from(v.height) / 2.0) / v.focal;
    let d: Vec<f64> =
        (0..3).map(|i| f64::from(v.forward[i]) + a * f64::from(v.right[i]) + b * f64::from(v.down[i])).collect();
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    [(d[0] / n) as f32, (d[1] / n) as f32, (d[2] / n) as f32]
}

/// Pixels where raster and march agree (hit or miss, distance to 1e-4 relative), the hits, the pixels whose
/// piece differs, and the pixels whose nearest piece is a wall.
fn compare(s: &WaveSurface, v: &PinholeView, t_max: f32) -> (usize, usize, usize, usize) {
    let r = s.first_hits(v).unwrap_or_else(|| panic!("a view above the water: {:?}", v.origin));
    let (mut agree, mut hits, mut other_piece, mut walls) = (0, 0, 0, 0);
    for px in 0..v.width * v.height {
        let (u, w) = (px % v.width, px / v.width);
        let d = pixel_dir(v, u, w);
        let march = s.intersect(v.origin, d, t_max);
        let raster = r.resolve(px as usize, v.origin, d, t_max);
        if let Some(&p) = r.first.get(px as usize).filter(|&&p| p != u32::MAX) {
            walls += usize::from(matches!(r.pieces[p as usize], Piece::Wall { .. }));
        }
        match (march, raster) {
            (None, WaterHit::Miss) => agree += 1,
            (Some(m), WaterHit::Hit(h)) => {
                hits += 1;
                if (m.t - h.t).abs() <= 1e-4 * m.t + 1e-4 {
                    agree += 1;
                } else {
                    eprintln!("pixel ({u}, {w}): march {m:?}, raster {h:?}, dir {d:?}");
                }
                other_piece += usize::from(m.piece != h.piece);
            }
            (m, h) => eprintln!("pixel ({u}, {w}): march {m:?}, raster {h:?}, dir {d:?}"),
        }
    }
    (agree, hits, other_piece, walls)
}

#[test]
fn raster_hits_are_the_march_hits_at_every_pixel() {
    // Two foci 90 m apart: every level of detail, steps between them, the taper and the flat beyond.
    let c = test_sea();
    let spec = SurfaceSpec { radius_m: 300.0, taper_m: 60.0, ..SurfaceSpec::default() };
    let s = WaveSurface::new(&c, 3.0, 0.0, &[[0.0, 0.0], [90.0, 40.0]], spec).unwrap_or_else(|e| unreachable!("{e}"));
    let mut walls_seen = 0;
    let views = [
        view([0.5, 0.3, 3.0], 0.3, -0.05, 1.6, 160, 120),
        view([0.5, 0.3, 3.0], 2.2, -0.25, 1.2, 160, 120),
        view([-20.0, 15.0, 2.2], -1.0, 0.0, 1.6, 160, 120),
        view([90.0, 40.0, 12.0], 3.5, -0.6, 1.0, 120, 90),
        view([31.99, 64.0, 2.5], 4.7, -0.02, 1.6, 160, 120),
        // From high above the taper, the flat still water beyond and rays rising into the sky.
        view([250.0, -200.0, 40.0], 2.4, -0.08, 1.4, 160, 120),
    ];
    for v in &views {
        let (agree, hits, other_piece, walls) = compare(&s, v, 2000.0);
        let n = (v.width * v.height) as usize;
        assert_eq!(agree, n, "{:?}: {agree} of {n} pixels agree", v.origin);
        assert!(hits > n / 4, "{:?}: {hits} hits", v.origin);
        assert!(other_piece * 1000 <= hits, "{:?}: {other_piece} of {hits} hits on another piece", v.origin);
        walls_seen += walls;
    }
    assert!(walls_seen > 0, "no view sees a step between levels");
}

#[test]
fn a_view_within_the_skin_is_left_to_the_march() {
    let s = WaveSurface::new(&[comp(0.5, 0.1, 0.0, 0.0, 0.0)], 0.0, 0.0, &[[0.0, 0.0]], SurfaceSpec::default())
        .unwrap_or_else(|e| unreachable!("{e}"));
    let h = s.height(2.0, 3.0);
    assert!(s.first_hits(&view([2.0, 3.0, h + 0.1], 0.0, 0.0, 1.0, 8, 8)).is_none());
    assert!(s.first_hits(&view([2.0, 3.0, h - 1.0], 0.0, 0.0, 1.0, 8, 8)).is_none());
    assert!(s.first_hits(&view([2.0, 3.0, h + 1.0], 0.0, 0.0, 1.0, 8, 8)).is_some());
}
