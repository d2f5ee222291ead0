//! Spinning multi-channel LiDAR.
//!
//! A sweep is `channels × azimuth_steps` rays from the LiDAR origin ([`rays::lidar_directions`]: column `a` at
//! azimuth `2π a / azimuth_steps`, counter-clockwise from +x, every channel of a column consecutively). The
//! whole sweep samples one frozen scene state. Rays are traced in [`rays::lidar_trace_order`] (coherent
//! packets) and put back in pattern order.
//!
//! Per ray, in this order (each random draw is a pure function of `(seed, ray index)`, see [`noise`]):
//! 1. the exact hit (distance `r`, normal `n`, class, instance) or a miss; the cast reaches `range_max + 6σ`
//!    (`σ = range_noise_std`), so that step 7 meets the ranges that noise brings inside `range_max` too;
//! 2. no hit: no return;
//! 3. open water (class 1): on a scene with a displaced wave surface ([`crate::Scene::wave_surface`]), a return
//!    with the probability of the physical model in [`super::lidar_water`] (quasi-specular glints off the wave
//!    facet met, at its incidence angle, whitecaps, and the foam of the wakes where the beam meets it — the
//!    cameras' wake foam at that point — detected through speckle), its intensity the speckle draw that passed
//!    the detection threshold ([`super::lidar_water::speckle_intensity`]: never below the threshold; until
//!    2026-12-01 a detected return carried the model's mean, below the threshold for one in seven water returns
//!    at W1) (the vessels' Kelvin waves, the cameras' slopes, do not tilt the facet: `docs/sea/README.md`,
//!    *LiDAR returns from wakes*, says what that cost);
//!    `water_probability` and `water_probability_per_wave_m` both 0 switch these off (no water return at all; until
//!    2026-12-06 the physical model ignored them, and no setting gave a LiDAR dataset without water returns);
//!    on a flat sea, the empirical rule: a return only with probability
//!    `p_w = water_probability + water_probability_per_wave_m · H` (clamped to 1) and only within
//!    `water_range_m + water_range_per_wave_m · H` — calm water is a mirror at 905 nm, waves give the beam facets
//!    to return from;
//! 4. weather: two-way transmission `τ = exp(−2 σ r)` with `σ` the air's extinction from its visibility
//!    (Koschmieder, 3 / V). The visibility `V` is the meteorological optical range in the scenario's air, rain
//!    included (`mmusv.world.rain`), and the drops, far larger than the wavelength, extinguish 905 nm as they do
//!    visible light (geometric optics, extinction efficiency 2: with Marshall & Palmer's 1948 drop sizes
//!    `≈ 0.365 · R^0.63` per km, 1.6 km⁻¹ at 10 mm/h), so `3 / V` carries the rain's extinction and the rain rate
//!    itself adds nothing here. Until 2026-12-07 a second rain term `1e-5 · R^0.6` per metre, without a source,
//!    was added to `σ` (2.4–2.7 % of the drops' own extinction over 1–50 mm/h, counted twice); the same numbers,
//!    `0.01 · R^0.6`, are the rain extinction that the LISA code (Kilic et al. 2021, arXiv:2107.07004,
//!    `velatkilic/LISA`) attributes to Goodin et al. (2019), Electronics 8(1), 89, applied per metre. The
//!    return is lost with probability `1 − τ` — but for the physical water returns of step 3,
//!    whose speckle threshold already met the attenuated mean `τ ⟨I⟩` (until 2026-12-01 they were lost with
//!    probability `1 − τ` as well, the fog counted twice: at 600 m visibility a fifth fewer water returns 20 m out
//!    than the model gives, a third 40 m out);
//! 5. rain drops (`LidarEnv::rain_mm_per_h` > 0 and a `beam_divergence` > 0): the strongest drop in the beam's
//!    cone, nearer than what the beam met (anywhere within range where it met nothing), replaces the return
//!    where its power exceeds the return's and the receiver's threshold (LISA's hybrid Monte-Carlo model,
//!    [`super::lidar_rain`]): a point of class 0 and no instance, its intensity the same law below with the
//!    drop's reflectivity at normal incidence. Without rain the scan is the same to the bit as before the drops
//!    were modelled (2026-12-08; until then the drops only dimmed the air);
//! 6. random dropout with probability `dropout`;
//! 7. range noise: `r' = r + N(0, range_noise_std)` (not below 0); a measured range `r' < range_min` or
//!    `r' > range_max` gives no return (the sensor gates on what it measures: no point's range lies outside
//!    `[range_min, range_max]`; until 2026-12-01 the gate took the exact `r` and noise put points beyond both
//!    limits); the point is `origin + r' · d` in the LiDAR frame.
//!
//! Intensity in `[0, 1]`: `ρ(class) · |cos θ| · τ / (1 + (r / 100 m)²)`, θ the incidence angle, ρ a per-class
//! reflectivity ([`reflectivity`]). This is the project's own calibration, not a published law; it lies between
//! two published conventions:
//! * the received power of the LiDAR range equation for an extended Lambertian target, `P_r ∝ ρ cos α · η_atm / R²`
//!   (Höfle & Pfeifer 2007, "Correction of laser scanning intensity data: Data and model-driven approaches", ISPRS
//!   Journal of Photogrammetry and Remote Sensing, their model-driven correction for spherical loss, incidence angle
//!   and atmospheric transmission). Ours has that `ρ cos θ τ`, but its range factor is inverse-square only far out:
//!   `1 / (1 + (r / 100 m)²)` is `x² / (1 + x²)` of `(100 m / r)²`, 0.8 of it at the default 200 m range, 0.5 at
//!   100 m, 0.04 at 20 m (Pfeifer et al. 2007, Optical 3-D Measurement Techniques VIII, 328–337, found the
//!   inverse-square law too simple for a Riegl LMS-Z420i over 1.2–48 m anyway);
//! * the range-compensated reflectivity that spinning LiDARs report: Velodyne's VLP-16 User Manual, §6.1
//!   *Calibrated Reflectivity* (reflectivity "independent of laser power and distances", 0–100 for 0–100 %
//!   diffuse reflectors, 101–255 for retro-reflectors), Ouster's firmware manual, *Calibrated Reflectivity*
//!   (signal photons scaled by range and sensor sensitivity), Hesai's PandarXT-16 manual (the reflectivity field
//!   linear in target reflectivity). Against a range-independent `ρ |cos θ| τ` ours is 4 % low at 20 m, 20 % at
//!   50 m, 50 % at 100 m and 80 % at 200 m: the intensity is neither a raw power nor a calibrated reflectivity.

use super::lidar_rain::RainDrops;
use super::lidar_water;
use super::noise::{self, stream};
use super::rays;
use super::shade::foam::{Foam, FOAM_SEED};
use super::shade::wake::Wake;
use crate::error::{MmusvError, Result};
use crate::geometry::RigidPose;
use crate::scene::{Scene, CLASS_NONE, NO_HIT};
use parry3d::math::Vec3;

/// Semantic class of open water (see `mmusv.classes`).
pub const CLASS_WATER: u16 = 1;

/// Configuration of a spinning LiDAR. Angles in radians, distances in metres.
#[derive(Debug, Clone, PartialEq)]
pub struct LidarConfig {
    /// Elevation of each channel (ring `i` = `elevations[i]`), radians, strictly inside ±90°.
    pub elevations: Vec<f64>,
    /// Columns per revolution (points per second / (rotation rate · channels)).
    pub azimuth_steps: u32,
    /// Returns whose measured range (noise included) is closer than this are discarded (metres, ≥ 0).
    pub range_min: f32,
    /// Returns whose measured range (noise included) is farther than this are discarded (metres, > range_min).
    pub range_max: f32,
    /// Standard deviation of the Gaussian range noise (metres, ≥ 0).
    pub range_noise_std: f32,
    /// Probability that a valid return is dropped at random, in `[0, 1]`.
    pub dropout: f32,
    /// Probability of a return from open water in calm conditions, in `[0, 1]`.
    pub water_probability: f32,
    /// Increase of that probability per metre of wave height (≥ 0).
    pub water_probability_per_wave_m: f32,
    /// Farthest water return in calm conditions (metres, ≥ 0).
    pub water_range_m: f32,
    /// Increase of that distance per metre of wave height (metres per metre, ≥ 0).
    pub water_range_per_wave_m: f32,
    /// Full angle of the beam's divergence (radians, in `[0, 0.1]`): the cone in which rain drops return
    /// ([`super::lidar_rain`]); 0 meets no drop.
    pub beam_divergence: f32,
}

/// The beam divergence of [`LidarConfig::default`]: 3 mrad, LISA's (Kilic et al. 2021, [`super::lidar_rain`]).
pub const DEFAULT_BEAM_DIVERGENCE: f32 = 3e-3;

impl Default for LidarConfig {
    /// The paper's LiDAR (64 channels, 131,072 points/s at 5 Hz, 200 m) over mmusv's vertical field of
    /// [−25°, 15°] (the paper gives none): 26,214.4 points per sweep, fired as 410 whole columns of 64, 0.5–200 m.
    fn default() -> Self {
        let elevations = rays::uniform_elevations(64, (-25f64).to_radians(), 15f64.to_radians()).unwrap_or_default();
        Self {
            elevations,
            azimuth_steps: 410,
            range_min: 0.5,
            range_max: 200.0,
            range_noise_std: 0.02,
            dropout: 0.0,
            water_probability: 0.05,
            water_probability_per_wave_m: 0.1,
            water_range_m: 20.0,
            water_range_per_wave_m: 10.0,
            beam_divergence: DEFAULT_BEAM_DIVERGENCE,
        }
    }
}

impl LidarConfig {
    /// Checks every field; the error names the field (`lidar.<field>`) and what is allowed.
    pub fn validate(&self) -> Result<()> {
        let c = self.elevations.len();
        if c == 0 || c > rays::MAX_CHANNELS as usize {
            return Err(MmusvError::config("lidar.channels", c, format!("must be in 1..={}", rays::MAX_CHANNELS)));
        }
        if let Some(i) = self.elevations.iter().position(|e| !(e.is_finite() && e.abs() < std::f64::consts::FRAC_PI_2))
        {
            return Err(MmusvError::config(
                format!("lidar.elevations[{i}]"),
                self.elevations[i],
                "must be a finite angle strictly between -π/2 and π/2 radians",
            ));
        }
        if self.azimuth_steps == 0 || self.azimuth_steps > rays::MAX_AZIMUTH_STEPS {
            return Err(MmusvError::config(
                "lidar.azimuth_steps",
                self.azimuth_steps,
                format!("must be in 1..={} (raise points_per_second or lower rotation_hz)", rays::MAX_AZIMUTH_STEPS),
            ));
        }
        if !(self.range_min.is_finite() && self.range_min >= 0.0) {
            return Err(MmusvError::config("lidar.range_min_m", self.range_min, "must be a finite distance >= 0"));
        }
        if !(self.range_max.is_finite() && self.range_max > self.range_min) {
            return Err(MmusvError::config(
                "lidar.range_m",
                self.range_max,
                "must be finite and greater than range_min_m",
            ));
        }
        let non_negative = [
            ("lidar.range_noise_std_m", self.range_noise_std),
            ("lidar.water_probability_per_wave_m", self.water_probability_per_wave_m),
            ("lidar.water_range_m", self.water_range_m),
            ("lidar.water_range_per_wave_m", self.water_range_per_wave_m),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(MmusvError::config(name, v, "must be finite and >= 0"));
            }
        }
        if !(self.beam_divergence.is_finite() && (0.0..=0.1).contains(&self.beam_divergence)) {
            return Err(MmusvError::config(
                "lidar.beam_divergence",
                self.beam_divergence,
                "must be a finite full angle in [0, 0.1] radians (0 meets no rain drop)",
            ));
        }
        for (name, v) in [("lidar.dropout", self.dropout), ("lidar.water_probability", self.water_probability)] {
            if !(0.0..=1.0).contains(&v) {
                return Err(MmusvError::config(name, v, "a probability must be in [0, 1]"));
            }
        }
        Ok(())
    }
}

/// Conditions that change what a LiDAR sees. Every field finite and `>= 0` ([`LidarEnv::validate`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LidarEnv {
    /// Atmospheric extinction coefficient (1/m), 3 / visibility: fog and rain's drops alike (the visibility is the
    /// one in the rain).
    pub fog_extinction_per_m: f32,
    /// Significant wave height H (m).
    pub wave_height_m: f32,
    /// Wind speed at 10 m (m/s): capillary roughness and whitecaps of the physical water returns.
    pub wind_speed_m_s: f32,
    /// Rain rate (mm/h): the drops that return from within the beam ([`super::lidar_rain`]); their extinction is
    /// in `fog_extinction_per_m`.
    pub rain_mm_per_h: f32,
}

impl LidarEnv {
    /// Checks that every field is finite and `>= 0`; errors name `lidar.<field>`.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("lidar.fog_extinction_per_m", self.fog_extinction_per_m),
            ("lidar.wave_height_m", self.wave_height_m),
            ("lidar.wind_speed_m_s", self.wind_speed_m_s),
            ("lidar.rain_mm_per_h", self.rain_mm_per_h),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(MmusvError::config(name, v, "must be finite and >= 0"));
            }
        }
        Ok(())
    }
}

/// The points of one sweep, in pattern order (azimuth column, then ring) with the rays that gave no return
/// left out. Columns are parallel arrays of one length.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LidarScan {
    /// Point positions in the LiDAR frame (metres).
    pub xyz: Vec<[f32; 3]>,
    /// Measured range (metres, noise included).
    pub range: Vec<f32>,
    /// Intensity in `[0, 1]`.
    pub intensity: Vec<f32>,
    /// Channel index (0 = lowest elevation of a uniform pattern).
    pub ring: Vec<u16>,
    /// Azimuth of the column (radians, `[0, 2π)`, counter-clockwise from +x).
    pub azimuth: Vec<f32>,
    /// Semantic class of the surface hit.
    pub class: Vec<u16>,
    /// Scene instance id of the surface hit.
    pub instance: Vec<i32>,
    /// Index of the ray in the full pattern (`column · channels + ring`).
    pub ray_index: Vec<u32>,
    /// Per ray of the full pattern (pattern order, every ray, returned or not): the scene instance its cast met
    /// first within `range_max`, or [`crate::scene::NO_HIT`]. What the annotations read to know which beams the
    /// water stopped (a box's wave-occlusion share) without casting them again.
    pub beam_instance: Vec<i32>,
}

impl LidarScan {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.xyz.len()
    }

    /// Whether the sweep has no points.
    pub fn is_empty(&self) -> bool {
        self.xyz.is_empty()
    }
}

/// Reflectivity of each semantic class at the LiDAR wavelength (dimensionless, `[0, 1]`).
///
/// The project's own values, not measured ones: no published 905 nm table for these classes (hull paint, quay
/// concrete, rock and sand, vegetation, containers, cranes) was found (searched 2026-12-02), so they are chosen to
/// order the classes plausibly (water darkest, retro-reflective buoys brightest), not to match a sensor. Water's
/// 0.05 serves only the flat sea's empirical rule (module header, step 3); over the displaced sea the returns'
/// intensity is [`super::lidar_water`]'s. Retro-reflective tape, which Velodyne's calibrated reflectivity puts
/// above every diffuse surface (101–255 against 0–100), is 0.80 here, inside the `[0, 1]` of diffuse ones.
pub fn reflectivity(class: u16) -> f32 {
    match class {
        1 => 0.05,       // water
        2 => 0.35,       // terrain (rock, sand)
        3 => 0.45,       // vegetation
        4 | 8 => 0.30,   // concrete structures, buildings
        5 => 0.55,       // painted containers
        6 => 0.60,       // cranes
        7 => 0.80,       // buoys (retro-reflective tape)
        10 | 11 => 0.50, // painted hulls
        _ => 0.20,
    }
}

/// A LiDAR with its ray pattern computed once.
#[derive(Debug, Clone)]
pub struct Lidar {
    cfg: LidarConfig,
    /// Unit directions in the LiDAR frame, pattern order.
    pattern: Vec<[f32; 3]>,
    /// Trace order (indices into `pattern`).
    order: Vec<u32>,
}

impl Lidar {
    /// Validates `cfg` and precomputes the pattern.
    pub fn new(cfg: LidarConfig) -> Result<Self> {
        cfg.validate()?;
        let pattern = rays::lidar_directions(&cfg.elevations, cfg.azimuth_steps)?;
        let order = rays::lidar_trace_order(cfg.elevations.len() as u32, cfg.azimuth_steps, rays::TRACE_BLOCK)?;
        Ok(Self { cfg, pattern, order })
    }

    /// The configuration.
    pub fn config(&self) -> &LidarConfig {
        &self.cfg
    }

    /// Unit ray directions of the full pattern in the LiDAR frame (`channels · azimuth_steps` rows).
    pub fn pattern(&self) -> &[[f32; 3]] {
        &self.pattern
    }

    /// One sweep from the LiDAR at `sensor_to_world` on the frozen `scene`, no vessel under way leaving a wake.
    pub fn scan(&self, scene: &Scene, sensor_to_world: &RigidPose, env: &LidarEnv, seed: u64) -> Result<LidarScan> {
        self.scan_with_wakes(scene, sensor_to_world, env, seed, &[])
    }

    /// One sweep from the LiDAR at `sensor_to_world` on the frozen `scene`, with `wakes` behind the vessels under
    /// way: over a displaced wave surface, beams that meet their foam return from it ([`super::lidar_water`];
    /// the same foam the cameras draw). On a flat sea the empirical water rule stands and wakes change nothing.
    /// Errors name `pose` (not finite or not rigid, [`RigidPose::validate`]) or the `lidar.<field>` of `env`.
    pub fn scan_with_wakes(
        &self,
        scene: &Scene,
        sensor_to_world: &RigidPose,
        env: &LidarEnv,
        seed: u64,
        wakes: &[Wake],
    ) -> Result<LidarScan> {
        sensor_to_world.validate("pose")?;
        env.validate()?;
        let cfg = &self.cfg;
        let channels = cfg.elevations.len();
        let origin = sensor_to_world.translation.to_array();
        let origins = vec![origin; self.order.len()];
        let dirs: Vec<[f32; 3]> = self
            .order
            .iter()
            .map(|&i| sensor_to_world.transform_vector(Vec3::from_array(self.pattern[i as usize])).to_array())
            .collect();
        // Hits a little beyond `range_max` may be measured within it (step 6); `range_max` itself without noise.
        let reach = cfg.range_max + 6.0 * cfg.range_noise_std;
        let hits = scene.cast_rays(&origins, &dirs, reach)?;
        // Back to pattern order.
        let mut slot = vec![u32::MAX; self.pattern.len()];
        for (k, &i) in self.order.iter().enumerate() {
            slot[i as usize] = k as u32;
        }
        let h = env.wave_height_m.max(0.0);
        let p_water = (cfg.water_probability + cfg.water_probability_per_wave_m * h).clamp(0.0, 1.0) as f64;
        let water_range = cfg.water_range_m + cfg.water_range_per_wave_m * h;
        let sigma = env.fog_extinction_per_m.max(0.0);
        let waves = scene.wave_surface().is_some();
        // Both water probabilities 0: no water returns, on the physical sea too (whose model otherwise ignores them).
        let water_off = cfg.water_probability == 0.0 && cfg.water_probability_per_wave_m == 0.0;
        // The wakes' foam (no whitecaps: those are the model's area mean), only over a wave surface.
        let wake_foam = Some(Foam::new(0.0, wakes, FOAM_SEED))
            .filter(|f| waves && !f.is_empty())
            .map(|f| f.around([origin[0], origin[1]], reach));
        let within = |k: usize| if hits.distance[k] <= cfg.range_max { hits.instance[k] } else { NO_HIT };
        let mut out =
            LidarScan { beam_instance: slot.iter().map(|&k| within(k as usize)).collect(), ..LidarScan::default() };
        // The return of the surface a beam met (its intensity), if any survives steps 2–4.
        let surface = |k: usize, idx: u64| -> Option<f32> {
            let r = hits.distance[k];
            let class = hits.class[k];
            if !r.is_finite() || hits.instance[k] == NO_HIT {
                return None;
            }
            // Clear air (no fog, no rain: `σ` 0) transmits all: `exp(-0)` is 1 to the bit, without the call per beam.
            let tau = if sigma > 0.0 { (-2.0 * sigma * r).exp() } else { 1.0 };
            let n = Vec3::new(hits.normal[3 * k], hits.normal[3 * k + 1], hits.normal[3 * k + 2]);
            let cos = n.dot(Vec3::from_array(dirs[k])).abs().min(1.0);
            let mut water_intensity = None;
            if class == CLASS_WATER {
                if water_off {
                    return None;
                } else if waves {
                    let foam = wake_foam.as_ref().map_or(0.0, |f| {
                        let p = Vec3::from_array(origin) + Vec3::from_array(dirs[k]) * r;
                        f.cover(p.x, p.y, None)
                    });
                    let mean = lidar_water::mean_intensity_with_foam(cos, env.wind_speed_m_s, r, tau, foam);
                    let u = noise::uniform(seed, stream::WATER, idx);
                    if u >= f64::from(lidar_water::detection_probability(mean)) {
                        return None;
                    }
                    water_intensity = Some(lidar_water::speckle_intensity(mean, u).clamp(0.0, 1.0));
                } else if r > water_range || noise::uniform(seed, stream::WATER, idx) >= p_water {
                    return None;
                }
            }
            // The physical water returns' detection already took the attenuated mean (step 3).
            if sigma > 0.0 && water_intensity.is_none() && noise::uniform(seed, stream::WEATHER, idx) >= tau as f64 {
                return None;
            }
            Some(water_intensity.unwrap_or_else(|| {
                (reflectivity(class) * cos * tau / (1.0 + (r / 100.0) * (r / 100.0))).clamp(0.0, 1.0)
            }))
        };
        let rain = RainDrops::new(
            f64::from(env.rain_mm_per_h),
            f64::from(cfg.beam_divergence),
            f64::from(cfg.range_min),
            f64::from(cfg.range_max),
            f64::from(sigma),
        );
        for (i, &k) in slot.iter().enumerate() {
            let k = k as usize;
            let idx = i as u64;
            // (range, intensity, class, instance) of the return.
            let mut point =
                surface(k, idx).map(|intensity| (hits.distance[k], intensity, hits.class[k], hits.instance[k]));
            if let Some(rain) = &rain {
                let met = hits.distance[k].is_finite() && hits.instance[k] != NO_HIT;
                let reach = if met { f64::from(hits.distance[k]) } else { f64::INFINITY };
                // The return's power in the drops' units: its intensity without the near-range factor, over r².
                let p0 = point.map_or(0.0, |(r, intensity, _, _)| {
                    let r = f64::from(r).max(1e-6);
                    f64::from(intensity) * (1.0 + (r / 100.0) * (r / 100.0)) / (r * r)
                });
                if let Some(drop) = rain.strongest(reach, p0, seed, idx) {
                    let s = drop.range;
                    let tau = (-2.0 * f64::from(sigma) * s).exp();
                    let intensity = (drop.reflectivity * tau / (1.0 + (s / 100.0) * (s / 100.0))).clamp(0.0, 1.0);
                    point = Some((s as f32, intensity as f32, CLASS_NONE, NO_HIT));
                }
            }
            let Some((r, intensity, class, instance)) = point else {
                continue;
            };
            if cfg.dropout > 0.0 && noise::uniform(seed, stream::DROPOUT, idx) < cfg.dropout as f64 {
                continue;
            }
            let measured = if cfg.range_noise_std > 0.0 {
                (r + cfg.range_noise_std * noise::normal(seed, stream::RANGE, idx) as f32).max(0.0)
            } else {
                r
            };
            if measured < cfg.range_min || measured > cfg.range_max {
                continue;
            }
            let d = self.pattern[i];
            let column = i / channels;
            out.xyz.push([d[0] * measured, d[1] * measured, d[2] * measured]);
            out.range.push(measured);
            out.intensity.push(intensity);
            out.ring.push((i % channels) as u16);
            out.azimuth.push((std::f64::consts::TAU * column as f64 / cfg.azimuth_steps as f64) as f32);
            out.class.push(class);
            out.instance.push(instance);
            out.ray_index.push(i as u32);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;

    fn wall_scene(x: f32) -> Scene {
        // A 100 m × 100 m wall facing −x at distance x, class 10.
        let v = [[x, -50.0, -50.0], [x, 50.0, -50.0], [x, 50.0, 50.0], [x, -50.0, 50.0]];
        let f = [[0i64, 1, 2], [0, 2, 3]];
        let mut s = Scene::new();
        let m = Mesh::new("wall", &v, &f, &[10, 10]).map(|m| s.add_mesh(m));
        if let Ok(m) = m {
            let _ = s.add_instance(m, RigidPose::IDENTITY, None);
        }
        s
    }

    fn cfg(ch: u32, steps: u32) -> LidarConfig {
        LidarConfig {
            elevations: rays::uniform_elevations(ch, -0.2, 0.2).unwrap_or_default(),
            azimuth_steps: steps,
            range_noise_std: 0.0,
            ..LidarConfig::default()
        }
    }

    #[test]
    fn wall_ranges_are_exact_and_rings_match() {
        let lidar = Lidar::new(cfg(8, 360));
        assert!(lidar.is_ok());
        let Ok(lidar) = lidar else { return };
        let scan = lidar.scan(&wall_scene(10.0), &RigidPose::IDENTITY, &LidarEnv::default(), 1).unwrap_or_default();
        assert!(!scan.is_empty());
        for i in 0..scan.len() {
            let [x, _, _] = scan.xyz[i];
            assert!((x - 10.0).abs() < 1e-3, "point on the wall plane, got x = {x}");
            let ring = scan.ring[i] as usize;
            let el = lidar.config().elevations[ring] as f32;
            let p = scan.xyz[i];
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            assert!((p[2] / r - el.sin()).abs() < 1e-4);
            assert!((p[1].atan2(p[0]).rem_euclid(std::f32::consts::TAU) - scan.azimuth[i]).abs() < 1e-3);
            assert_eq!(scan.class[i], 10);
        }
        // Only the forward half (|azimuth| < ~84°) can hit a wall 10 m away, 50 m wide.
        assert!(scan.azimuth.iter().all(|a| a.cos() > 0.0));
    }

    /// In rain, a beam that meets nothing returns from a drop with the probability `1 − e^(−μ)` of at least one
    /// detectable drop along it (`μ` the drops' expected count, clear air so `τ` is 1 and every drop the count
    /// holds is detected), as a point of class 0 with no instance within the drops' reach; beams that meet a wall
    /// 2 m off return from drops only nearer than the wall; a line for a beam (divergence 0), or no rain, gives
    /// the scan of clear air to the bit.
    #[test]
    fn rain_drops_return_as_often_as_the_model_says() {
        let c = cfg(16, 3600);
        let lidar = Lidar::new(c.clone()).unwrap_or_else(|e| unreachable!("{e}"));
        let rain = LidarEnv { rain_mm_per_h: 20.0, ..LidarEnv::default() };
        let s = wall_scene(150.0);
        let wet = lidar.scan(&s, &RigidPose::IDENTITY, &rain, 8).unwrap_or_else(|e| unreachable!("{e}"));
        let dry = lidar.scan(&s, &RigidPose::IDENTITY, &LidarEnv::default(), 8).unwrap_or_else(|e| unreachable!("{e}"));
        let drops = RainDrops::new(20.0, 3e-3, 0.5, 200.0, 0.0).unwrap_or_else(|| unreachable!());
        let misses: Vec<usize> = (0..wet.beam_instance.len()).filter(|&i| wet.beam_instance[i] == NO_HIT).collect();
        let from_drops = (0..wet.len()).filter(|&p| wet.class[p] == CLASS_NONE).collect::<Vec<_>>();
        for &p in &from_drops {
            assert_eq!(wet.instance[p], NO_HIT);
            assert!(wet.range[p] >= 0.5 && f64::from(wet.range[p]) <= drops.max_range() + 1e-3, "{}", wet.range[p]);
        }
        let on_misses = from_drops.iter().filter(|&&p| wet.beam_instance[wet.ray_index[p] as usize] == NO_HIT).count();
        let expected = 1.0 - (-drops.expected_count(f64::INFINITY)).exp();
        let n = misses.len() as f64;
        let sd = (n * expected * (1.0 - expected)).sqrt();
        eprintln!("{on_misses} drop returns on {n} beams meeting nothing; expected {:.1} ± {sd:.1}", n * expected);
        assert!(n > 40_000.0 && expected > 0.002, "{n} beams, p = {expected}");
        assert!((on_misses as f64 - n * expected).abs() < 4.5 * sd);
        // The wall's own returns: as in dry air, but where a drop outshone them.
        let walls = |scan: &LidarScan| scan.class.iter().filter(|&&k| k == 10).count();
        assert_eq!(walls(&dry) - walls(&wet), from_drops.len() - on_misses);
        // A wall 2 m off: drop points only in front of it.
        let near = wall_scene(2.0);
        let wet = lidar.scan(&near, &RigidPose::IDENTITY, &rain, 8).unwrap_or_else(|e| unreachable!("{e}"));
        let pattern = lidar.pattern();
        for p in (0..wet.len()).filter(|&p| wet.class[p] == CLASS_NONE) {
            let i = wet.ray_index[p] as usize;
            if wet.beam_instance[i] != NO_HIT {
                assert!(wet.range[p] < 2.0 / pattern[i][0], "a drop behind the wall: {}", wet.range[p]);
            }
        }
        // No drops with a line for a beam, or without rain.
        let line = Lidar::new(LidarConfig { beam_divergence: 0.0, ..c }).unwrap_or_else(|e| unreachable!("{e}"));
        let a = line.scan(&s, &RigidPose::IDENTITY, &rain, 8).unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(a, dry);
        let bad = LidarConfig { beam_divergence: f32::NAN, ..cfg(4, 8) };
        assert!(Lidar::new(bad).is_err_and(|e| e.to_string().contains("lidar.beam_divergence")));
    }

    #[test]
    fn noise_is_seeded_and_weather_drops_points() {
        let mut c = cfg(16, 720);
        c.range_noise_std = 0.05;
        let lidar = Lidar::new(c).ok();
        let Some(lidar) = lidar else { return };
        let s = wall_scene(30.0);
        let a = lidar.scan(&s, &RigidPose::IDENTITY, &LidarEnv::default(), 5).unwrap_or_default();
        let b = lidar.scan(&s, &RigidPose::IDENTITY, &LidarEnv::default(), 5).unwrap_or_default();
        let c2 = lidar.scan(&s, &RigidPose::IDENTITY, &LidarEnv::default(), 6).unwrap_or_default();
        assert_eq!(a, b);
        assert_ne!(a.range, c2.range);
        let fog = LidarEnv { fog_extinction_per_m: 3.0 / 100.0, ..LidarEnv::default() };
        let f = lidar.scan(&s, &RigidPose::IDENTITY, &fog, 5).unwrap_or_default();
        assert!(
            f.len() * 3 < a.len(),
            "fog with 100 m visibility loses most returns at 30 m: {} vs {}",
            f.len(),
            a.len()
        );
    }

    /// The range gates take the measured range: with 5 cm of noise and a wall 29.5 m off, no point lies beyond a
    /// 30 m `range_max` or before a 30 m `range_min`, and the beams that meet the wall just beyond 30 m return
    /// where their noise brings them inside, as often as those just inside fall out (the gate unbiased; near the
    /// axis as many beams meet the wall per centimetre of range on either side of the gate). Until
    /// 2026-12-01 the gates took the exact range, and noise put points beyond both.
    #[test]
    fn range_gates_take_the_measured_range() {
        let c = LidarConfig { range_noise_std: 0.05, ..cfg(16, 3600) };
        let s = wall_scene(29.5);
        let scan = |c: LidarConfig| {
            Lidar::new(c).and_then(|l| l.scan(&s, &RigidPose::IDENTITY, &LidarEnv::default(), 3)).unwrap_or_default()
        };
        let pattern = rays::lidar_directions(&c.elevations, c.azimuth_steps).unwrap_or_default();
        let truth = |i: u32| 29.5 / pattern[i as usize][0];
        let far = scan(LidarConfig { range_max: 30.0, ..c.clone() });
        assert!(far.range.iter().all(|&r| r <= 30.0), "a point beyond range_max");
        let near_gate = |lo: f32, hi: f32| (0..pattern.len() as u32).filter(|&i| (lo..hi).contains(&truth(i))).count();
        // Beams whose wall lies within 5 cm beyond the gate: about a fifth (P(N > 1σ) ≈ 0.16 over 0..1σ) return.
        let beyond = far.ray_index.iter().filter(|&&i| truth(i) > 30.0).count();
        let kept = far.ray_index.iter().filter(|&&i| (29.95..30.0).contains(&truth(i))).count();
        let inside_lost = near_gate(29.95, 30.0) - kept;
        assert!(beyond > 20 && near_gate(30.0, 30.05) > 100, "{beyond} of {}", near_gate(30.0, 30.05));
        eprintln!("gate at 30 m: {beyond} beams beyond it return, {inside_lost} inside it are lost");
        let n = (beyond + inside_lost) as f64;
        assert!((beyond as f64 - inside_lost as f64).abs() < 4.0 * n.sqrt(), "{beyond} in, {inside_lost} out");
        let near = scan(LidarConfig { range_min: 30.0, ..c });
        assert!(!near.is_empty() && near.range.iter().all(|&r| r >= 30.0), "a point before range_min");
        // The annotations' beams stop at range_max as before.
        let l = Lidar::new(LidarConfig { range_max: 30.0, ..cfg(16, 3600) });
        let exact = l.and_then(|l| l.scan(&s, &RigidPose::IDENTITY, &LidarEnv::default(), 3)).unwrap_or_default();
        assert_eq!(far.beam_instance, exact.beam_instance);
    }

    /// Over a displaced sea in fog, each beam meeting the water returns with the physical model's probability
    /// `exp(−I_d / ⟨I⟩)` of the attenuated mean `⟨I⟩ ∝ τ`, worked out here beam by beam from the cast's own facet
    /// normals: the counts per band of range agree within 4.5 standard deviations. Until 2026-12-01 the weather's
    /// random loss `1 − τ` came on top, a second time.
    #[test]
    fn water_returns_in_fog_count_the_attenuation_once() {
        use crate::ocean::{sea_seed, SeaSpec, WaveField};
        use crate::sea::{SurfaceSpec, WaveSurface};
        let mut s = Scene::new();
        let h = 5000.0f32;
        let sea =
            Mesh::new("sea", &[[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]], &[[0, 1, 2], [0, 2, 3]], &[1])
                .unwrap_or_else(|e| unreachable!("{e}"));
        let sea = s.add_mesh(sea);
        let id = s.add_instance(sea, RigidPose::IDENTITY, None).unwrap_or_else(|e| unreachable!("{e}"));
        s.set_sea(id, &[]).unwrap_or_else(|e| unreachable!("{e}"));
        let spec = SeaSpec { hs: 1.5, tp: 6.1, gamma: 1.0, direction_rad: 0.4, spread_s: 10.0 };
        let field = WaveField::new(&spec, sea_seed(2)).unwrap_or_else(|e| unreachable!("{e}"));
        let w = WaveSurface::new(field.components(), 0.0, 0.0, &[[0.0, 0.0]], SurfaceSpec::default())
            .unwrap_or_else(|e| unreachable!("{e}"));
        s.set_wave_surface(Some(w)).unwrap_or_else(|e| unreachable!("{e}"));
        let c = LidarConfig {
            elevations: rays::uniform_elevations(32, (-25f64).to_radians(), (-2f64).to_radians()).unwrap_or_default(),
            azimuth_steps: 1024,
            range_noise_std: 0.0,
            ..LidarConfig::default()
        };
        let lidar = Lidar::new(c.clone()).unwrap_or_else(|e| unreachable!("{e}"));
        let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 3.0], [0.0; 3]);
        let env =
            LidarEnv { fog_extinction_per_m: 3.0 / 600.0, wave_height_m: 1.5, wind_speed_m_s: 9.0, rain_mm_per_h: 0.0 };
        let scan = lidar.scan(&s, &pose, &env, 4).unwrap_or_else(|e| unreachable!("{e}"));
        let dirs: Vec<[f32; 3]> =
            lidar.pattern().iter().map(|d| pose.transform_vector(Vec3::from_array(*d)).to_array()).collect();
        let hits = s
            .cast_rays(&vec![pose.translation.to_array(); dirs.len()], &dirs, c.range_max)
            .unwrap_or_else(|e| unreachable!("{e}"));
        for (lo, hi) in [(5.0f32, 12.0f32), (12.0, 25.0), (25.0, 60.0)] {
            let (mut want, mut var) = (0.0f64, 0.0f64);
            for (k, d) in dirs.iter().enumerate() {
                let r = hits.distance[k];
                if hits.class[k] != CLASS_WATER || !(lo..hi).contains(&r) {
                    continue;
                }
                let n = Vec3::new(hits.normal[3 * k], hits.normal[3 * k + 1], hits.normal[3 * k + 2]);
                let cos = n.dot(Vec3::from_array(*d)).abs().min(1.0);
                let tau = (-2.0 * env.fog_extinction_per_m * r).exp();
                let p = f64::from(lidar_water::detection_probability(lidar_water::mean_intensity(cos, 9.0, r, tau)));
                want += p;
                var += p * (1.0 - p);
            }
            let got =
                (0..scan.len()).filter(|&i| scan.class[i] == CLASS_WATER && (lo..hi).contains(&scan.range[i])).count();
            eprintln!("fog, water {lo}-{hi} m: {got} returns, the model {want:.0} ± {:.0}", var.sqrt());
            assert!(want > 200.0, "{want}");
            assert!((got as f64 - want).abs() < 4.5 * var.sqrt() + 2.0, "{lo}-{hi} m: {got} returns, model {want:.0}");
        }
    }

    #[test]
    fn bad_configs_name_the_field() {
        let mut c = cfg(8, 16);
        c.elevations.clear();
        assert!(Lidar::new(c).err().map(|e| e.to_string()).unwrap_or_default().contains("lidar.channels"));
        let mut c = cfg(8, 16);
        c.range_max = -1.0;
        assert!(Lidar::new(c).err().map(|e| e.to_string()).unwrap_or_default().contains("lidar.range_m"));
        let mut c = cfg(8, 16);
        c.dropout = 2.0;
        assert!(Lidar::new(c).err().map(|e| e.to_string()).unwrap_or_default().contains("lidar.dropout"));
    }
}
