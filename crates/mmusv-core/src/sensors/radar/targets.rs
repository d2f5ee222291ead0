//! Rays cast straight at the targets: each object's angular box as the radar sees it, a stratified grid of rays
//! over it, and the weight that combines them with the fan's rays without bias.
//!
//! The fan's rays are spread over a beam some 20° tall; a boat at a kilometre fills a few hundredths of a degree
//! of it, so at the default ray counts it is hit by a ray or by none, and a ray that hits stands for the whole
//! patch of beam it samples (a boat seen at 1 km was ~11 times too bright, and a third of such boats were not
//! seen at all). Here each object in range that does not surround the radar gets `target_rays` rays per beam
//! spacing its box spans in azimuth (at most [`MAX_SPANS`] spacings), spread over its angular box on a stratified
//! grid, and every beam whose window holds such a ray counts its echo.
//!
//! The two sets of rays sample one integral (the echo power of a beam over its azimuth window and elevation fan)
//! with two densities, and are combined by multiple importance sampling with the balance heuristic (Veach, E. &
//! Guibas, L. J. (1995), "Optimally combining sampling techniques for Monte Carlo rendering", SIGGRAPH '95,
//! 419–428; Veach, E. (1997), PhD thesis, Stanford, ch. 9): a ray in direction `(a, e)` that hits stands for the
//! solid angle `cos e / (n_fan p_fan(a, e) + Σ_i n_i p_i(a, e))`, where `n_fan p_fan = 1 / (beamwidth / rays_az ·
//! the fan height of its elevation stratum)` is the fan's density of rays there (what a fan ray stood for alone)
//! and `n_i p_i = n_i / (Δa_i Δe_i)` that of the rays cast at box `i` (zero outside it). Outside every box the
//! fan's rays keep exactly the weight they had alone; the sum stays an unbiased estimate of the beam's power and
//! converges to the radar equation as either count grows.
//!
//! The angular box is bounded from the object's world-aligned box (its current pose) seen in the sensor frame:
//! azimuths from its corners (an object the vertical through the radar does not cross spans less than π, and
//! its extreme azimuths are at corners), elevations from the highest and lowest corner at the nearest and
//! farthest horizontal distance of the box (a bound, not an estimate: the box's top edge may rise highest
//! between two corners), clipped to the fan. The sea is no target and has none; an object the vertical through
//! the radar crosses (its own hull below it, a bridge above it), wider than [`MAX_WIDTH_RAD`] or out of range has
//! none either: the fan samples such objects densely.

use crate::geometry::RigidPose;
use crate::scene::Scene;
use crate::sensors::radar::RadarConfig;
use parry3d::math::Vec3;
use std::f64::consts::{PI, TAU};

/// Most beam spacings of azimuth one object's rays are spread over (wider objects get as many rays).
pub const MAX_SPANS: u32 = 32;
/// Lowest angular box (radians) that gets rays (one touching the fan's edge has none), and lowest fan.
const MIN_HEIGHT_RAD: f64 = 1e-9;
/// Widest object, in azimuth, that gets rays of its own (radians): a nearer one is sampled densely by the fan.
pub const MAX_WIDTH_RAD: f64 = PI / 3.0;

/// One object's angular box in the sensor frame and the density of rays cast at it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct TargetBox {
    /// Azimuth of the box's clockwise edge, radians in `[0, 2π)`; the box spans `[a0, a0 + width]` (mod 2π).
    pub(super) a0: f64,
    /// Azimuth width, radians (`< π`).
    pub(super) width: f64,
    /// Elevations, radians, sensor frame, within the fan: `e0 ≤ e1`.
    pub(super) e0: f64,
    pub(super) e1: f64,
    /// Rays across its azimuth and over its elevation.
    pub(super) n_az: u32,
    pub(super) n_el: u32,
}

impl TargetBox {
    /// The density of rays cast at the box, per unit azimuth × elevation (radians⁻²), at `(a, e)`: 0 outside it.
    pub(super) fn density(&self, a: f64, e: f64) -> f64 {
        // Within the box, to rounding (a ray cast at its edge is its own).
        let da = (a - self.a0 + PI).rem_euclid(TAU) - PI;
        let eps = 1e-12;
        if e < self.e0 - eps || e > self.e1 + eps || da < -eps || da > self.width + eps {
            return 0.0;
        }
        f64::from(self.n_az * self.n_el) / (self.width.max(f64::MIN_POSITIVE) * (self.e1 - self.e0).max(1e-12))
    }
}

/// The rays cast at the targets: their boxes, and each ray's azimuth and elevation (sensor frame, radians) with
/// the summed density of every box at its direction, sorted by azimuth.
#[derive(Debug, Clone, Default)]
pub(super) struct TargetRays {
    pub(super) boxes: Vec<TargetBox>,
    /// `(azimuth in [0, 2π), elevation, Σ_i n_i p_i)` per ray, sorted by azimuth.
    pub(super) rays: Vec<(f64, f64, f64)>,
}

impl TargetRays {
    /// The boxes' summed density of rays at `(a, e)`.
    pub(super) fn density(&self, a: f64, e: f64) -> f64 {
        self.boxes.iter().map(|b| b.density(a, e)).sum()
    }

    /// Indices of the rays whose azimuth lies within `half` of `centre` (both radians), in azimuth order of the
    /// window (wrapping through 0 where it does).
    pub(super) fn within(&self, centre: f64, half: f64) -> impl Iterator<Item = usize> + '_ {
        let lo = (centre - half).rem_euclid(TAU);
        let hi = lo + 2.0 * half;
        let start = self.rays.partition_point(|r| r.0 < lo);
        let end = self.rays.partition_point(|r| r.0 <= hi.min(TAU));
        let wrap_end = if hi > TAU { self.rays.partition_point(|r| r.0 <= hi - TAU) } else { 0 };
        (start..end).chain(0..wrap_end.min(start))
    }
}

/// The angular box of a world-aligned box `[lo, hi]` seen from the sensor at `sensor_to_world`, with its elevations
/// clipped to `fan` (radians); `None` when the vertical through the sensor crosses it, or it lies outside the fan.
pub(super) fn angular_box(sensor_to_world: &RigidPose, lo: [f64; 3], hi: [f64; 3], fan: [f64; 2]) -> Option<[f64; 4]> {
    let corners: Vec<[f64; 3]> = (0..8)
        .map(|c| {
            let w = Vec3::new(
                (if c & 1 == 0 { lo[0] } else { hi[0] }) as f32,
                (if c & 2 == 0 { lo[1] } else { hi[1] }) as f32,
                (if c & 4 == 0 { lo[2] } else { hi[2] }) as f32,
            );
            let s = sensor_to_world.inverse_transform_point(w);
            [f64::from(s.x), f64::from(s.y), f64::from(s.z)]
        })
        .collect();
    // Does the sensor's vertical (its z axis) cross the box? Slab test of the line through the origin along z,
    // in the box's own frame (the world's): the line is origin + t·z_world.
    let origin = sensor_to_world.translation;
    let up = sensor_to_world.rotation * Vec3::Z;
    let (o, d) = ([origin.x, origin.y, origin.z].map(f64::from), [up.x, up.y, up.z].map(f64::from));
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..3 {
        if d[k].abs() < 1e-12 {
            if o[k] < lo[k] || o[k] > hi[k] {
                t0 = f64::INFINITY;
            }
        } else {
            let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
    }
    if t0 <= t1 {
        return None;
    }
    // Azimuths relative to the first corner's (the box spans less than π from the outside).
    let a_ref = corners[0][1].atan2(corners[0][0]);
    let (mut da_lo, mut da_hi) = (0.0f64, 0.0f64);
    for c in &corners {
        let da = (c[1].atan2(c[0]) - a_ref + PI).rem_euclid(TAU) - PI;
        da_lo = da_lo.min(da);
        da_hi = da_hi.max(da);
    }
    // Nearest and farthest horizontal distance: the projected box is a convex polygon whose edges are among the
    // 12 projected edges of the box, and the origin lies outside it.
    const EDGES: [(usize, usize); 12] =
        [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)];
    let rho_min = EDGES
        .iter()
        .map(|&(i, j)| segment_distance([corners[i][0], corners[i][1]], [corners[j][0], corners[j][1]]))
        .fold(f64::INFINITY, f64::min);
    let rho_max = corners.iter().map(|c| c[0].hypot(c[1])).fold(0.0, f64::max);
    let z_max = corners.iter().map(|c| c[2]).fold(f64::NEG_INFINITY, f64::max);
    let z_min = corners.iter().map(|c| c[2]).fold(f64::INFINITY, f64::min);
    let e1 = z_max.atan2(if z_max >= 0.0 { rho_min } else { rho_max }).min(fan[1]);
    let e0 = z_min.atan2(if z_min <= 0.0 { rho_min } else { rho_max }).max(fan[0]);
    (e0 <= e1).then(|| [(a_ref + da_lo).rem_euclid(TAU), da_hi - da_lo, e0, e1])
}

/// Distance from the origin to the segment `p q` in the plane.
fn segment_distance(p: [f64; 2], q: [f64; 2]) -> f64 {
    let d = [q[0] - p[0], q[1] - p[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    let t = if len2 > 0.0 { (-(p[0] * d[0] + p[1] * d[1]) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (p[0] + t * d[0]).hypot(p[1] + t * d[1])
}

/// The rays to cast at the targets of `scene` seen from `sensor_to_world` (see the module documentation): none
/// when `cfg.target_rays` is 0.
pub(super) fn target_rays(scene: &Scene, cfg: &RadarConfig, sensor_to_world: &RigidPose) -> TargetRays {
    // A fan of no height samples one elevation, not an interval: nothing to aim within.
    let [fan_lo, fan_hi] = cfg.elevation_fan_rad;
    if cfg.target_rays == 0 || fan_hi - fan_lo < MIN_HEIGHT_RAD {
        return TargetRays::default();
    }
    let sea = scene.sea_instance();
    let spacing = TAU / f64::from(cfg.azimuth_bins);
    let sensor = sensor_to_world.translation;
    let s = [sensor.x, sensor.y, sensor.z].map(f64::from);
    let mut boxes = Vec::new();
    for id in 0..scene.instances().len() as u32 {
        if Some(id) == sea {
            continue;
        }
        let Ok(aabb) = scene.instance_aabb(id) else { continue };
        let (lo, hi) = (
            [aabb.mins.x, aabb.mins.y, aabb.mins.z].map(f64::from),
            [aabb.maxs.x, aabb.maxs.y, aabb.maxs.z].map(f64::from),
        );
        if !(0..3).all(|k| lo[k].is_finite() && hi[k].is_finite() && lo[k] <= hi[k]) {
            continue;
        }
        // Out of range: nearer than nothing of it lies beyond the blind range, or all of it beyond the range.
        let near = (0..3).map(|k| (lo[k] - s[k]).max(s[k] - hi[k]).max(0.0).powi(2)).sum::<f64>().sqrt();
        let far = (0..3).map(|k| (s[k] - lo[k]).abs().max((hi[k] - s[k]).abs()).powi(2)).sum::<f64>().sqrt();
        if near >= cfg.range_max_m || far < cfg.range_min_m {
            continue;
        }
        let Some([a0, width, e0, e1]) = angular_box(sensor_to_world, lo, hi, cfg.elevation_fan_rad) else { continue };
        if width > MAX_WIDTH_RAD || e1 - e0 < MIN_HEIGHT_RAD {
            continue;
        }
        let spans = ((width / spacing).ceil() as u32).clamp(1, MAX_SPANS);
        boxes.push((TargetBox { a0, width, e0, e1, n_az: 0, n_el: 0 }, cfg.target_rays * spans));
    }
    // Never more aimed rays than the fan has (a scene of very many objects): each object's share scaled down.
    let total: u64 = boxes.iter().map(|b| u64::from(b.1)).sum();
    let cap = cfg.num_rays().max(1);
    let boxes: Vec<TargetBox> = boxes
        .into_iter()
        .map(|(mut b, n)| {
            let n = if total > cap { ((u64::from(n) * cap / total) as u32).max(1) } else { n };
            // A grid about as fine in azimuth as in elevation.
            b.n_az = (((f64::from(n) * b.width / (b.e1 - b.e0).max(1e-9)).sqrt().round()) as u32).clamp(1, n);
            b.n_el = (n / b.n_az).max(1);
            b
        })
        .collect();
    let mut rays = Vec::new();
    for b in &boxes {
        for i in 0..b.n_az {
            for k in 0..b.n_el {
                // Stratified: one ray per cell of the grid, at an offset within it from the R2 sequence (Roberts,
                // M. (2018), "The unreasonable effectiveness of quasirandom sequences").
                let m = f64::from(i * b.n_el + k);
                let (u, v) = ((0.5 + m * 0.754_877_666_246_693).fract(), (0.5 + m * 0.569_840_290_998_053).fract());
                let a = (b.a0 + b.width * (f64::from(i) + u) / f64::from(b.n_az)).rem_euclid(TAU);
                let e = b.e0 + (b.e1 - b.e0) * (f64::from(k) + v) / f64::from(b.n_el);
                rays.push((a, e, 0.0));
            }
        }
    }
    let mut out = TargetRays { boxes, rays };
    for r in 0..out.rays.len() {
        let (a, e, _) = out.rays[r];
        out.rays[r].2 = out.density(a, e);
    }
    out.rays.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.total_cmp(&y.1)));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(z: f64, yaw: f64) -> RigidPose {
        RigidPose::from_xyz_rpy([0.0, 0.0, z], [0.0, 0.0, yaw])
    }

    /// The angular box holds every point of the box (sampled densely) and is tight at the corners.
    #[test]
    fn angular_box_bounds_every_point() {
        let fan = [-1.5, 1.5];
        for (p, lo, hi) in [
            (pose(5.0, 0.3), [100.0, -1.0, -0.5], [105.0, 1.0, 1.0]),
            (pose(5.0, 0.0), [-20.0, 3.0, 0.0], [20.0, 8.0, 30.0]),
            (pose(2.0, 1.0), [-50.0, -60.0, -1.0], [-40.0, -55.0, 3.0]),
            (pose(5.0, 0.0), [-101.0, -0.5, 0.0], [-99.0, 0.5, 9.0]),
        ] {
            let Some([a0, w, e0, e1]) = angular_box(&p, lo, hi, fan) else { panic!("no box for {lo:?}..{hi:?}") };
            let mut worst = 0.0f64;
            for i in 0..=10 {
                for j in 0..=10 {
                    for k in 0..=10 {
                        let t = |n: usize, q: usize| lo[n] + (hi[n] - lo[n]) * q as f64 / 10.0;
                        let s = p.inverse_transform_point(Vec3::new(t(0, i) as f32, t(1, j) as f32, t(2, k) as f32));
                        let (x, y, z) = (f64::from(s.x), f64::from(s.y), f64::from(s.z));
                        let a = y.atan2(x);
                        let e = z.atan2(x.hypot(y));
                        let da = (a - a0 + PI).rem_euclid(TAU) - PI;
                        assert!(da >= -1e-6 && da <= w + 1e-6, "{a} outside [{a0}, +{w}]");
                        assert!(e >= e0 - 1e-6 && e <= e1 + 1e-6, "{e} outside [{e0}, {e1}]");
                        worst = worst.max(da);
                    }
                }
            }
            assert!((worst - w).abs() < 1e-6, "azimuth width {w} not tight ({worst})");
        }
    }

    /// A box the radar's vertical crosses (its own hull below it) has no angular box.
    #[test]
    fn own_hull_has_no_box() {
        assert!(angular_box(&pose(5.0, 0.0), [-6.0, -2.0, -1.0], [6.0, 2.0, 4.0], [-1.0, 1.0]).is_none());
    }

    /// `within` finds the rays of a window that wraps through azimuth 0, and only those.
    #[test]
    fn window_wraps() {
        let rays: Vec<(f64, f64, f64)> = (0..360).map(|d| (f64::from(d).to_radians(), 0.0, 1.0)).collect();
        let t = TargetRays { boxes: vec![], rays };
        let got: Vec<usize> = t.within(0.0, 2.5f64.to_radians()).collect();
        let mut sorted = got.clone();
        sorted.sort();
        assert_eq!(sorted, vec![0, 1, 2, 358, 359]);
        let mid: Vec<usize> = t.within(90f64.to_radians(), 1.5f64.to_radians()).collect();
        assert_eq!(mid, vec![89, 90, 91]);
    }

    fn cubes(n: usize, range: f64, half: f32) -> Scene {
        let mut s = Scene::new();
        let cube = s.add_mesh(crate::scene::tests::box_mesh([half, half, half], 10));
        for k in 0..n {
            let b = std::f64::consts::TAU * k as f64 / n as f64;
            let pose = RigidPose::from_xyz_rpy([range * b.cos(), range * b.sin(), f64::from(half) - 0.5], [0.0; 3]);
            let _ = s.add_instance(cube, pose, None);
        }
        s
    }

    /// So many objects that their rays would outnumber the fan's: each one's share is scaled down.
    #[test]
    fn aimed_rays_never_outnumber_the_fan() {
        let cfg = RadarConfig { azimuth_bins: 64, rays_az: 1, rays_el: 16, ..RadarConfig::tuning() };
        let s = cubes(300, 500.0, 1.0);
        let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 5.0], [0.0; 3]);
        let t = target_rays(&s, &cfg, &pose);
        assert_eq!(t.boxes.len(), 300);
        assert!(t.rays.len() as u64 <= cfg.num_rays(), "{} aimed rays for a fan of {}", t.rays.len(), cfg.num_rays());
        assert!(t.boxes.iter().all(|b| b.n_az * b.n_el >= 1));
        let none = target_rays(&s, &RadarConfig { target_rays: 0, ..cfg }, &pose);
        assert!(none.rays.is_empty() && none.boxes.is_empty());
    }

    /// Unbiased: the echo of 60 cubes of 4 m at 700 m, summed over the sweep, is the same with the aimed rays (the
    /// default fan, 16 aimed rays) as with a fan dense enough to need none (8 × 256 rays a beam), within 3 %
    /// (measured: 6,823 against 6,861; 6,899 with 16 × 1,024; over 6 cubes the fan's fixed azimuths alone scatter
    /// the sum by 15 %, so the test takes many).
    #[test]
    fn aimed_rays_keep_the_echo_unbiased() {
        let s = cubes(60, 700.0, 2.0);
        let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 5.0], [0.0; 3]);
        let env = crate::sensors::radar::RadarEnv { wave_height_m: 0.0, rain_mm_per_h: 0.0 };
        let quiet = RadarConfig { detection_threshold: 1e-9, azimuth_bins: 512, ..RadarConfig::tuning() };
        let off = crate::sensors::radar_model::ClutterModel {
            sea_sigma0_at_1m: 0.0,
            critical_range_per_m: 0.0,
            sea_max_range_m: 0.0,
            rain_eta_at_1mm_h: 0.0,
        };
        let quiet = RadarConfig { clutter: off, ..quiet };
        let total = |cfg: &RadarConfig| -> f64 {
            let r = crate::sensors::radar::radar_sweep(&s, &pose, cfg, &env, 0).unwrap_or_else(|e| unreachable!("{e}"));
            r.intensity.iter().zip(&r.instance).filter(|(_, &i)| i >= 0).map(|(&p, _)| f64::from(p)).sum()
        };
        let dense = total(&RadarConfig { rays_az: 8, rays_el: 256, target_rays: 0, ..quiet });
        let aimed = total(&quiet);
        assert!(dense > 0.0);
        assert!((aimed / dense - 1.0).abs() < 0.03, "aimed {aimed} against dense {dense}");
    }

    /// A fan of no height (every ray at one elevation) gets no aimed rays: its sweep is the fan's alone.
    #[test]
    fn a_flat_fan_aims_nothing() {
        let s = cubes(6, 300.0, 2.0);
        let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 1.0], [0.0; 3]);
        let flat = RadarConfig { elevation_fan_rad: [0.0, 0.0], azimuth_bins: 256, ..RadarConfig::tuning() };
        assert!(target_rays(&s, &flat, &pose).rays.is_empty());
        let env = crate::sensors::radar::RadarEnv { wave_height_m: 0.0, rain_mm_per_h: 0.0 };
        let sweep = |cfg: &RadarConfig| crate::sensors::radar::radar_sweep(&s, &pose, cfg, &env, 0).ok();
        let with = sweep(&flat);
        assert!(with.as_ref().is_some_and(|r| r.instance.iter().any(|&i| i >= 0)));
        assert_eq!(with, sweep(&RadarConfig { target_rays: 0, ..flat }));
    }
}
