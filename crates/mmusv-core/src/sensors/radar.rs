//! A rotating ray-cast marine radar: one full revolution ("sweep") as sparse returns.
//!
//! The antenna turns through `azimuth_bins` beams per revolution; beam `b` points at azimuth
//! `2π b / azimuth_bins` in the sensor frame (0 = forward +x, counter-clockwise towards +y). Each beam is
//! sampled by `rays_az × rays_el` rays: `rays_az` azimuths at the centres of equal slices of the beamwidth,
//! and for each of them `rays_el` elevations spread uniformly (stratified) over the elevation fan. Surface
//! targets a kilometre away span a fraction of a degree of a fan some 20° tall, so (with `horizon_fraction` 0.75,
//! the scenario default) three quarters
//! of the elevation rays are spread uniformly over the band `±horizon_band_rad` around the sea horizon (where the
//! world's horizontal plane cuts the fan at that azimuth, from the sensor pose: it follows roll and pitch)
//! and the rest uniformly over the remainder of the fan; every ray carries the fan height it stands for as
//! its weight, so intensities stay unbiased (`horizon_fraction = 0` gives the plain uniform fan). Within its
//! stratum each ray sits at an offset that changes from azimuth sample to azimuth sample along the
//! golden-ratio sequence, so neighbouring samples fill the gaps between rows (no seed involved). All rays of
//! the sweep are cast in one [`Scene::cast_rays_to_targets`] call. Besides the fan, `target_rays` rays per beam
//! spacing are cast straight at each object in range over its angular box (`targets`), and the two sets of rays
//! are combined by multiple importance sampling: a ray's echo stands for the solid angle the two sets' summed
//! density of rays gives it, which outside every object's box is what a fan ray stood for alone (until
//! 2026-12-06 there were only the fan's rays, which missed a 2 m boat as often as not beyond 600 m and credited a
//! hit with the whole patch of beam it sampled: 11 times too bright at 1 km).
//!
//! Range bin `k` covers `[k Δr, (k+1) Δr)` and is reported at its centre `(k + ½) Δr`; bins whose centre lies
//! outside `[range_min_m, range_max_m)` are blind, and so are echoes from nearer than `range_min_m` in any bin
//! (the receiver is blanked while it transmits: until 2026-12-04 a bin straddling `range_min_m` took them, and a
//! coarse bin reported the own hull). Hits are aggregated per cell (azimuth bin, range bin):
//! intensity is the sum of [`radar_model::ray_power`] over the rays hitting something other than water (each
//! weighted by the fan's two-way elevation gain, [`RadarConfig::two_way_gain`]; the fan's rays and the aimed
//! rays whose azimuth lies within the beam's window), plus the cell's clutter draw
//! ([`radar_model::clutter_mean`]); a cell is reported when its intensity is positive and at least
//! `detection_threshold`. Its instance and class are those of the object with the largest summed
//! echo in the cell, or instance −1 and class WATER (sea clutter) / NONE (rain clutter) when clutter
//! dominates. Rays that hit water end there and are not targets: the sea is seen only as clutter. Sea clutter
//! comes only from the water the beam sees: a cell's sea clutter mean is scaled by the share of the beam's azimuth
//! samples whose rays show the water at that range in view, not under land or in the shadow of an island, a quay
//! or a ship (`shadow`; until 2026-12-01 sea clutter was drawn at every range of every beam, over islands too).
//!
//! Determinism: clutter and range noise of cell `(b, k)` come from a ChaCha8 generator seeded with `seed`,
//! stream `b`, at word offset `4k`, so they depend on nothing else (not on threads, other cells, or the
//! range limits), and for a fixed seed clutter grows monotonically with the wave height and rain rate.
//!
//! One module a step: `config` (what the radar is and what it sees through, checked), `pattern` (where its
//! rays go), `targets` (the rays aimed at the objects and their weights), this file (cast the sweep, collect each beam's echoes, assemble the returns), `shadow` (where the
//! beam sees the sea), `cells` (echoes grouped per cell and merged with clutter into returns) and `clutter`
//! (clutter means and the seeded per-cell draws).

mod cells;
mod clutter;
mod config;
mod pattern;
pub mod sea_clutter;
mod shadow;
mod targets;

use crate::error::Result;
use crate::geometry::RigidPose;
use crate::scene::{Scene, NO_HIT};
use crate::sensors::radar_model::{self, CLASS_WATER};
use cells::{group_cells, BeamContext, Echo, Return};
use clutter::clutter_table;
use parry3d::math::Vec3;
use pattern::trace_index;
use rayon::prelude::*;
use shadow::Blockers;

pub(crate) use config::{validate_azimuth_bins, validate_resolution};
pub use config::{RadarConfig, RadarEnv, MAX_AZIMUTH_BINS, MAX_RANGE_BINS, MAX_RANGE_M, MAX_RAYS, MAX_TARGET_RAYS};
pub use pattern::horizon_elevation;

// The unit tests (radar_tests.rs) reach these through `use super::*`.
#[cfg(test)]
use crate::error::MmusvError;
#[cfg(test)]
use crate::sensors::radar_model::ClutterModel;

/// The returns of one sweep, parallel arrays sorted by (azimuth bin, range bin), at most one per cell.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RadarReturns {
    /// Range, metres: the bin centre plus the optional range noise (never negative).
    pub range: Vec<f32>,
    /// Beam azimuth in the sensor frame, radians in `[0, 2π)`, 0 = forward, counter-clockwise.
    pub azimuth: Vec<f32>,
    /// Elevation in the sensor frame, radians: echo-weighted mean of the rays hitting the cell, or for
    /// clutter where the still sea level (world z = 0) lies at that range and azimuth seen from the sensor's
    /// height: the sea horizon's elevation in the (tilted) sensor frame less `atan(height / range)`, without
    /// the waves.
    pub elevation: Vec<f32>,
    /// Intensity, linear, relative to a 1 m² target at 1 km (see [`radar_model`]).
    pub intensity: Vec<f32>,
    /// Scene instance of the strongest echo, or −1 for clutter.
    pub instance: Vec<i32>,
    /// Semantic class of the strongest echo; WATER (1) for sea clutter, NONE (0) for rain clutter.
    pub class: Vec<u16>,
}

impl RadarReturns {
    /// Number of returns.
    pub fn len(&self) -> usize {
        self.range.len()
    }
    /// Whether there are no returns.
    pub fn is_empty(&self) -> bool {
        self.range.is_empty()
    }
}

/// One full revolution of the radar at `sensor_to_world` (sensor frame: x forward, y left, z up).
///
/// Casts `cfg.num_rays()` rays in one batch, aggregates them per (azimuth bin, range bin) cell, adds seeded
/// sea / rain clutter and returns the detections sorted by (azimuth bin, range bin). See the module
/// documentation for the ray pattern and [`radar_model`] for the intensity model. Deterministic for a given
/// scene, pose, configuration and seed. A pose that is not finite or not rigid is an error naming `pose`.
pub fn radar_sweep(
    scene: &Scene,
    sensor_to_world: &RigidPose,
    cfg: &RadarConfig,
    env: &RadarEnv,
    seed: u64,
) -> Result<RadarReturns> {
    cfg.validate()?;
    env.validate()?;
    sensor_to_world.validate("pose")?;
    let samples = (cfg.azimuth_bins * cfg.rays_az) as usize;
    let rows = cfg.rays_el as usize;
    // Ray directions (world) and per-ray (elevation, fan-height weight), both in trace order.
    let (dirs, meta) = pattern::sweep_rays(cfg, sensor_to_world);
    let origins = vec![sensor_to_world.translation.to_array(); dirs.len()];
    // Water is no target (its echo is the clutter drawn per cell): the surface is only asked whether it stops a ray.
    let hits = scene.cast_rays_to_targets(&origins, &dirs, cfg.range_max_m as f32)?;
    drop(origins);
    // The rays cast straight at the targets (`targets`), and what they hit.
    let aimed = targets::target_rays(scene, cfg, sensor_to_world);
    let aimed_dirs: Vec<[f32; 3]> = aimed
        .rays
        .iter()
        .map(|&(a, e, _)| {
            let ((sa, ca), (se, ce)) = (a.sin_cos(), e.sin_cos());
            sensor_to_world.transform_vector(Vec3::new((ce * ca) as f32, (ce * sa) as f32, se as f32)).to_array()
        })
        .collect();
    let aimed_hits = scene.cast_rays_to_targets(
        &vec![sensor_to_world.translation.to_array(); aimed_dirs.len()],
        &aimed_dirs,
        cfg.range_max_m as f32,
    )?;

    let (first, end) = cfg.range_bins();
    // Over the physical sea (a displaced wave surface), sea clutter follows sea state and grazing angle.
    let physical = scene.wave_surface().map(|w| {
        sea_clutter::PhysicalSea::new(env.wave_height_m as f64, f64::from(sensor_to_world.translation.z - w.level()))
            .with_band(cfg.frequency_ghz, cfg.polarisation)
    });
    let sensor_height = sensor_to_world.translation.z.max(0.0) as f64;
    let table = clutter_table(cfg, env, physical.as_ref(), sensor_height, first, end);
    // Solid angle of a fan ray alone = (beamwidth / rays_az) · its fan-height weight · cos(its elevation); with
    // the aimed rays, cos(elevation) over the two sets' summed density of rays in its direction (`targets`).
    let az_width = cfg.beamwidth_az_rad / cfg.rays_az as f64;
    let rain = radar_model::RainLoss::new(&cfg.band(), env.rain_mm_per_h as f64);
    // The clutter bins' ranges and the still water's depression there (`shadow`).
    let clutter_ranges: Vec<f64> = (first..).take(table.len()).map(|k| cfg.bin_centre(k)).collect();
    let depression: Vec<f64> = clutter_ranges.iter().map(|&r| sensor_height.atan2(r)).collect();
    let ctx = BeamContext { cfg, env, seed, first, end, table: &table, sensor_height, physical, pose: sensor_to_world };
    let per_beam: Vec<Vec<Return>> = (0..cfg.azimuth_bins)
        .into_par_iter()
        .map(|b| {
            let mut echoes = Vec::new();
            // Per clutter bin, the beam's azimuth samples that do not see the sea there (`shadow`; empty: none).
            let mut shadowed = Vec::new();
            let mut blockers = Blockers::default();
            for j in 0..cfg.rays_az {
                let g = b * cfg.rays_az + j;
                let horizon = horizon_elevation(sensor_to_world, cfg.sample_azimuth(g)).unwrap_or(0.0);
                blockers.clear();
                for k in 0..cfg.rays_el {
                    let i = trace_index(g as usize, k as usize, samples, rows);
                    let (instance, class, d) = (hits.instance[i], hits.class[i], hits.distance[i] as f64);
                    if instance == NO_HIT || class == CLASS_WATER || !d.is_finite() {
                        continue;
                    }
                    let [elevation, weight] = meta[i];
                    if d >= cfg.range_min_m && f64::from(elevation) <= horizon {
                        blockers.push(f64::from(elevation), d);
                    }
                    let bin = (d / cfg.range_resolution_m).floor() as u32;
                    // An echo from inside the blind range is not received, whatever bin it falls in.
                    if bin < first || bin >= end || d < cfg.range_min_m {
                        continue;
                    }
                    let n = &hits.normal[3 * i..3 * i + 3];
                    let dir = dirs[i];
                    let cos = (n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2]) as f64;
                    let e = f64::from(elevation);
                    let aimed_density = aimed.density(cfg.sample_azimuth(g), e);
                    let omega = e.cos() * cfg.two_way_gain(e) / (1.0 / (az_width * weight as f64) + aimed_density);
                    let power = radar_model::ray_power(class, cos, omega, d, &rain);
                    echoes.push(Echo { bin, instance, class, power, elevation: e });
                }
                blockers.count_shadowed(horizon, &clutter_ranges, &depression, &mut shadowed);
            }
            // The aimed rays within the beam's window, weighed against the fan's density of rays where they go.
            let centre = cfg.beam_azimuth(b);
            for r in aimed.within(centre, 0.5 * cfg.beamwidth_az_rad) {
                let (instance, class, d) = (aimed_hits.instance[r], aimed_hits.class[r], aimed_hits.distance[r] as f64);
                if instance == NO_HIT || class == CLASS_WATER || !d.is_finite() || d < cfg.range_min_m {
                    continue;
                }
                let bin = (d / cfg.range_resolution_m).floor() as u32;
                if bin < first || bin >= end {
                    continue;
                }
                let (a, e, aimed_density) = aimed.rays[r];
                // The fan's azimuth sample whose slice of the beam holds `a`, and its elevation stratum at `e`.
                let offset = (a - centre + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                    - std::f64::consts::PI
                    + 0.5 * cfg.beamwidth_az_rad;
                let j = ((offset / az_width).floor().max(0.0) as u32).min(cfg.rays_az - 1);
                let g = b * cfg.rays_az + j;
                let stratum = cfg.stratum_height(horizon_elevation(sensor_to_world, cfg.sample_azimuth(g)), e);
                let n = &aimed_hits.normal[3 * r..3 * r + 3];
                let dir = aimed_dirs[r];
                let cos = (n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2]) as f64;
                let omega = e.cos() * cfg.two_way_gain(e) / (1.0 / (az_width * stratum) + aimed_density);
                let power = radar_model::ray_power(class, cos, omega, d, &rain);
                echoes.push(Echo { bin, instance, class, power, elevation: e });
            }
            ctx.returns(b, &group_cells(echoes), &shadowed)
        })
        .collect();

    let n: usize = per_beam.iter().map(Vec::len).sum();
    let mut out = RadarReturns {
        range: Vec::with_capacity(n),
        azimuth: Vec::with_capacity(n),
        elevation: Vec::with_capacity(n),
        intensity: Vec::with_capacity(n),
        instance: Vec::with_capacity(n),
        class: Vec::with_capacity(n),
    };
    for r in per_beam.into_iter().flatten() {
        out.range.push(r.range);
        out.azimuth.push(r.azimuth);
        out.elevation.push(r.elevation);
        out.intensity.push(r.intensity);
        out.instance.push(r.instance);
        out.class.push(r.class);
    }
    Ok(out)
}

#[cfg(test)]
#[path = "radar_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "radar_clutter_tests.rs"]
mod clutter_tests;
