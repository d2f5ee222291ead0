//! Plausible (not photoreal) RGB shading of camera hits from the environment.
//!
//! Linear-light model, encoded to sRGB at the end:
//! * sky (no hit): a gradient from the horizon colour to the zenith colour by ray elevation, plus the sun disc
//!   and a glow around it;
//! * surfaces: per-class albedo (containers and vessels varied per object) lit by ambient sky light and the sun
//!   (Lambert), the sun term switched off in shadow (a shadow ray towards the sun, cast by the camera);
//! * water: the geometric normal perturbed by a few deterministic swell components whose slope grows with the
//!   wave height, a Fresnel mix (Schlick, F0 = 0.02) of the dark water body and the reflected sky, and a sun
//!   glint;
//! * fog: Koschmieder blending towards the fog colour, `c · e^{−σ t} + fog · (1 − e^{−σ t})`;
//! * rain: overall darkening and thin bright streaks, positions drawn from the seed.

use super::noise::{self, stream};
use parry3d::math::Vec3;

mod lanes;
pub use lanes::{LaneColors, Lanes, LANES};

/// Lighting and weather for shading. Colours are linear RGB in `[0, 1]`; directions are world-frame unit vectors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadeEnv {
    /// Unit vector towards the sun (world frame).
    pub sun_direction: [f32; 3],
    /// Sun colour.
    pub sun_color: [f32; 3],
    /// Sun strength, 0 at night, 1 at zenith in clear sky.
    pub sun_intensity: f32,
    /// Ambient (sky) light level in `[0, 1]`.
    pub ambient: f32,
    /// Sky colour straight up.
    pub sky_zenith: [f32; 3],
    /// Sky colour at the horizon.
    pub sky_horizon: [f32; 3],
    /// Atmospheric extinction (1/m), 3 / visibility.
    pub fog_extinction_per_m: f32,
    /// Colour surfaces fade to with distance.
    pub fog_color: [f32; 3],
    /// Rain rate (mm/h).
    pub rain_mm_per_h: f32,
    /// Significant wave height (m).
    pub wave_height_m: f32,
    /// Whether to cast shadow rays.
    pub shadows: bool,
}

impl Default for ShadeEnv {
    /// Clear noon.
    fn default() -> Self {
        Self {
            sun_direction: [0.3, 0.2, 0.93],
            sun_color: [1.0, 0.98, 0.95],
            sun_intensity: 1.0,
            ambient: 0.55,
            sky_zenith: [0.12, 0.3, 0.7],
            sky_horizon: [0.6, 0.72, 0.88],
            fog_extinction_per_m: 3.0 / 20_000.0,
            fog_color: [0.7, 0.75, 0.8],
            rain_mm_per_h: 0.0,
            wave_height_m: 0.5,
            shadows: true,
        }
    }
}

/// What a camera ray hit, as shading needs it.
#[derive(Debug, Clone, Copy)]
pub struct SurfaceHit {
    /// Distance along the ray (m).
    pub t: f32,
    /// World hit point.
    pub point: Vec3,
    /// Unit world normal, facing the camera.
    pub normal: Vec3,
    /// Semantic class.
    pub class: u16,
    /// Scene instance id.
    pub instance: i32,
}

fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

#[inline]
fn hash_tint(id: u64, seed: u64) -> Vec3 {
    let h = noise::hash3(seed, 0xC0105, id);
    let f = |s: u32| 0.55 + 0.45 * ((h >> s) & 0xFF) as f32 / 255.0;
    Vec3::new(f(0), f(8), f(16))
}

/// Linear albedo of a surface.
#[inline]
fn albedo(hit: &SurfaceHit) -> Vec3 {
    match hit.class {
        2 => Vec3::new(0.33, 0.27, 0.18),
        3 => Vec3::new(0.07, 0.18, 0.05),
        4 => Vec3::new(0.38, 0.38, 0.37),
        5 => {
            // One colour per container-sized cell of space.
            let p = hit.point;
            let cell = ((p.x / 6.1).floor() as i64 as u64).wrapping_mul(73_856_093)
                ^ ((p.y / 2.5).floor() as i64 as u64).wrapping_mul(19_349_663)
                ^ ((p.z / 2.6).floor() as i64 as u64).wrapping_mul(83_492_791);
            const PALETTE: [[f32; 3]; 6] = [
                [0.5, 0.08, 0.05],
                [0.05, 0.2, 0.45],
                [0.1, 0.35, 0.12],
                [0.6, 0.45, 0.05],
                [0.45, 0.45, 0.45],
                [0.5, 0.22, 0.05],
            ];
            v3(PALETTE[(noise::hash3(5, 5, cell) % 6) as usize])
        }
        6 => Vec3::new(0.6, 0.42, 0.04),
        7 => Vec3::new(0.75, 0.15, 0.08),
        8 => Vec3::new(0.42, 0.4, 0.38),
        10 => Vec3::new(0.62, 0.62, 0.62) * hash_tint(hit.instance.max(0) as u64, 10),
        11 => Vec3::new(0.15, 0.45, 0.45),
        _ => Vec3::splat(0.3),
    }
}

/// Sky colour seen along unit direction `d`.
pub fn sky(env: &ShadeEnv, d: Vec3) -> Vec3 {
    Shader::new(env, 0).sky(d)
}

/// Linear RGB of one camera ray `d` (world, unit) given its hit (or `None` for the sky) and whether the hit
/// point sees the sun.
pub fn shade(env: &ShadeEnv, d: Vec3, hit: Option<&SurfaceHit>, sunlit: bool, seed: u64) -> Vec3 {
    Shader::new(env, seed).shade(d, hit, sunlit)
}

/// `x^300` rounds to exactly 0 for every `x ≤ GLINT_ZERO` (`0.7^300 ≈ 3e-47`, below half the smallest subnormal).
const GLINT_ZERO: f32 = 0.7;
/// `x^2000` rounds to exactly 0 for every `x ≤ SUN_DISC_ZERO` (`0.949^2000 ≈ 3.5e-46`).
const SUN_DISC_ZERO: f32 = 0.949;

/// One swell component of the water surface: direction `(cos, sin)`, wave number, phase and slope amplitude.
#[derive(Debug, Clone, Copy)]
struct Swell {
    c: f32,
    s: f32,
    k: f32,
    phase: f32,
    amp_k: f32,
}

/// Shading of one render: everything that depends only on the environment and the seed, computed once
/// (swell components, light colours, the sky's fog veil), then [`Shader::shade`] per pixel. Gives bit for bit
/// what the formulas give evaluated per pixel.
#[derive(Debug, Clone, Copy)]
pub struct Shader {
    env: ShadeEnv,
    swell: [Swell; 4],
    sun: Vec3,
    sun_lit: Vec3,
    ambient_light: Vec3,
    sky_keep: f32,
    sky_fog: Vec3,
    sky_brightness: f32,
    fog_color: Vec3,
}

impl Shader {
    /// Precomputes the shading of a render with environment `env` and seed `seed` (ripples, rain streaks).
    pub fn new(env: &ShadeEnv, seed: u64) -> Self {
        let h = env.wave_height_m.max(0.05);
        let swell = std::array::from_fn(|i| {
            let i = i as u64;
            let dir = std::f32::consts::TAU * noise::uniform(seed, stream::RIPPLE, 2 * i) as f32;
            let phase = std::f32::consts::TAU * noise::uniform(seed, stream::RIPPLE, 2 * i + 1) as f32;
            let wavelength = [41.0f32, 23.0, 11.0, 3.7][i as usize];
            let k = std::f32::consts::TAU / wavelength;
            // Steepness limited so slopes stay below ~0.35.
            let amp = (0.5 * h).min(0.05 * wavelength) * [0.5f32, 0.3, 0.15, 0.05][i as usize];
            let (s, c) = dir.sin_cos();
            Swell { c, s, k, phase, amp_k: amp * k }
        });
        let veil = 1.0 - (-env.fog_extinction_per_m * 3000.0).exp();
        Self {
            env: *env,
            swell,
            sun: v3(env.sun_direction),
            sun_lit: v3(env.sun_color) * env.sun_intensity,
            ambient_light: (v3(env.sky_zenith) * 0.5 + v3(env.sky_horizon) * 0.5) * (0.4 + 1.2 * env.ambient),
            sky_keep: 1.0 - veil,
            sky_fog: v3(env.fog_color) * env.ambient.max(0.1) * 1.3 * veil,
            sky_brightness: 0.25 + 1.3 * env.ambient,
            fog_color: v3(env.fog_color) * env.ambient.max(0.1) * 1.3,
        }
    }

    /// Sky colour seen along unit direction `d`.
    #[inline]
    pub fn sky(&self, d: Vec3) -> Vec3 {
        let env = &self.env;
        let up = d.z.max(0.0).sqrt();
        let mut c = (v3(env.sky_horizon) * (1.0 - up) + v3(env.sky_zenith) * up) * self.sky_brightness;
        if d.z < 0.0 {
            c *= 0.8;
        }
        if env.sun_intensity > 0.0 {
            let cs = d.dot(self.sun).max(0.0);
            if cs > 0.0 {
                // cs^2000 is exactly 0 below SUN_DISC_ZERO (it rounds to zero): skip powf's slow underflow path.
                let disc = if cs > SUN_DISC_ZERO { cs.powf(2000.0) } else { 0.0 };
                c += v3(env.sun_color) * env.sun_intensity * (cs.powi(8) * 0.25 + disc * 20.0);
            }
        }
        // Fog thickens the whole sky towards the fog colour.
        c * self.sky_keep + self.sky_fog
    }

    /// Slope of the water surface at `p` (x, y): sum of three swell components and a ripple.
    #[inline]
    fn water_normal(&self, p: Vec3) -> Vec3 {
        let mut gx = 0.0;
        let mut gy = 0.0;
        for w in &self.swell {
            let arg = w.k * (w.c * p.x + w.s * p.y) + w.phase;
            let slope = w.amp_k * arg.cos();
            gx += slope * w.c;
            gy += slope * w.s;
        }
        Vec3::new(-gx, -gy, 1.0).normalize_or_zero()
    }

    #[inline]
    fn fog(&self, c: Vec3, t: f32) -> Vec3 {
        let f = (-self.env.fog_extinction_per_m * t).exp();
        c * f + self.fog_color * (1.0 - f)
    }

    /// Linear RGB of one camera ray `d` (world, unit) given its hit (or `None` for the sky) and whether the hit
    /// point sees the sun. Cameras shade with [`Shader::shade_lanes`], the same bits for [`LANES`] pixels at once.
    #[inline]
    pub fn shade(&self, d: Vec3, hit: Option<&SurfaceHit>, sunlit: bool) -> Vec3 {
        let Some(hit) = hit else {
            return self.sky(d);
        };
        let sun = self.sun;
        let sun_light = self.sun_lit * if sunlit { 1.0 } else { 0.0 };
        let ambient_light = self.ambient_light;
        let c = if hit.class == 1 {
            let mut n = self.water_normal(hit.point);
            if n.dot(d) > 0.0 {
                n = hit.normal;
            }
            let cos = (-d.dot(n)).clamp(0.0, 1.0);
            let fresnel = 0.02 + 0.98 * (1.0 - cos).powi(5);
            let mut r = d - n * (2.0 * d.dot(n));
            r.z = r.z.abs();
            let body = Vec3::new(0.01, 0.045, 0.06) * (ambient_light + sun_light * n.dot(sun).max(0.0));
            let rs = r.dot(sun).max(0.0);
            // rs^300 is exactly 0 below GLINT_ZERO: skip powf's slow underflow path.
            let glint = sun_light * if rs > GLINT_ZERO { rs.powf(300.0) } else { 0.0 } * 4.0;
            body * (1.0 - fresnel) + self.sky(r) * fresnel + glint
        } else {
            let a = albedo(hit);
            a * (ambient_light + sun_light * hit.normal.dot(sun).max(0.0))
        };
        self.fog(c, hit.t)
    }

    /// [`rain`] with this render's environment.
    #[inline(always)]
    pub fn rain(&self, c: Vec3, u: u32, v: u32, seed: u64) -> Vec3 {
        rain(&self.env, c, u, v, seed)
    }
}

/// Rain: darkening and streaks on a linear colour at pixel `(u, v)`.
#[inline(always)]
pub fn rain(env: &ShadeEnv, c: Vec3, u: u32, v: u32, seed: u64) -> Vec3 {
    if env.rain_mm_per_h <= 0.0 {
        return c;
    }
    let strength = (env.rain_mm_per_h / 16.0).min(1.0);
    let mut out = c * (1.0 - 0.3 * strength);
    let len = 12u32;
    let offset = (noise::hash3(seed, stream::RAIN, u as u64) % len as u64) as u32;
    let segment = (v + offset) / len;
    let key = ((u as u64) << 32) | segment as u64;
    if noise::uniform(seed, stream::RAIN, key) < 0.03 * strength as f64 {
        out += Vec3::splat(0.12);
    }
    out
}

/// Linear `[0, 1]` to 8-bit sRGB by the formula (the reference [`to_srgb8`] reproduces exactly).
fn srgb8_formula(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let s = if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// Buckets of the direct table in front of the step search (`x · BUCKETS` picks one).
const BUCKETS: usize = 4096;

/// The encoding as tables: `steps[b]` is the smallest linear value the formula encodes as `b` or more (found
/// once by bisection over the float bit patterns of `[0, 1]`, so the tables reproduce the formula exactly;
/// `steps[256] = steps[257] = +inf`, the last one so that no lookup needs a bounds check), and `start[i]` the
/// encoding of `i / BUCKETS`. No bucket holds more than two steps (checked when the tables are built), so a
/// lookup is one table read and two comparisons.
struct SrgbTables {
    steps: [f32; 258],
    start: Box<[u8; BUCKETS + 1]>,
}

fn srgb_tables() -> &'static SrgbTables {
    static TABLES: std::sync::OnceLock<SrgbTables> = std::sync::OnceLock::new();
    TABLES.get_or_init(|| {
        let mut steps = [f32::INFINITY; 258];
        steps[0] = 0.0;
        let one = 1.0f32.to_bits();
        for (b, slot) in steps.iter_mut().enumerate().take(256).skip(1) {
            // Smallest bit pattern in [0, one] whose encoding is >= b (encodings only grow with the value).
            let (mut lo, mut hi) = (0u32, one);
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if srgb8_formula(f32::from_bits(mid)) as usize >= b {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            *slot = f32::from_bits(lo);
        }
        let mut start = Box::new([0u8; BUCKETS + 1]);
        for (i, slot) in start.iter_mut().enumerate() {
            *slot = srgb8_formula(i as f32 / BUCKETS as f32);
        }
        for i in 0..BUCKETS {
            assert!(start[i + 1] - start[i] <= 2, "more than two sRGB steps in bucket {i}");
        }
        SrgbTables { steps, start }
    })
}

/// Linear `[0, ∞)` to 8-bit sRGB (`round(255 · srgb(clamp(x, 0, 1)))`), by table: the same bytes as the
/// formula, without a `powf` per channel.
#[inline(always)]
pub fn to_srgb8(c: Vec3) -> [u8; 3] {
    let t = srgb_tables();
    let enc = |x: f32| {
        // Above 1 encodes as 1 (and +inf must not pass `steps[256] = +inf`); NaN stays NaN and compares false.
        let x = if x > 1.0 { 1.0 } else { x };
        // `max` sends negative values and NaN to bucket 0 (NaN then compares false below); `x ≤ 1` keeps the
        // index within the table, and a 32-bit conversion is shorter code than a saturating `usize` one.
        let i = ((x.max(0.0) * BUCKETS as f32) as u32 as usize).min(BUCKETS);
        let mut b = t.start[i] as usize;
        b += usize::from(t.steps[b + 1] <= x);
        b += usize::from(t.steps[b + 1] <= x);
        b as u8
    };
    [enc(c.x), enc(c.y), enc(c.z)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Environments the shading tests run in: clear noon; low sun with fog and 3.5 m waves; night.
    pub(super) fn test_envs() -> [ShadeEnv; 3] {
        [
            ShadeEnv::default(),
            ShadeEnv {
                sun_direction: [0.9, 0.0, 0.436],
                wave_height_m: 3.5,
                fog_extinction_per_m: 0.01,
                ..ShadeEnv::default()
            },
            ShadeEnv { sun_intensity: 0.0, ambient: 0.05, ..ShadeEnv::default() },
        ]
    }

    #[test]
    fn sky_brighter_towards_sun_and_fog_veils() {
        let env = ShadeEnv::default();
        let s = v3(env.sun_direction);
        assert!(sky(&env, s).x > sky(&env, -s + Vec3::new(0.0, 0.0, 1.5)).x);
        let hit = SurfaceHit { t: 5000.0, point: Vec3::ZERO, normal: Vec3::Z, class: 2, instance: 0 };
        let near = SurfaceHit { t: 10.0, ..hit };
        let foggy = ShadeEnv { fog_extinction_per_m: 3.0 / 300.0, ..env };
        let far_c = shade(&foggy, -Vec3::Z, Some(&hit), true, 1);
        let fog_c = v3(foggy.fog_color) * foggy.ambient * 1.3;
        assert!((far_c - fog_c).length() < 1e-3, "far surface disappears in fog");
        assert!((shade(&foggy, -Vec3::Z, Some(&near), true, 1) - fog_c).length() > 0.05);
        assert_eq!(to_srgb8(Vec3::ZERO), [0, 0, 0]);
        assert_eq!(to_srgb8(Vec3::ONE), [255, 255, 255]);
    }

    #[test]
    fn skipped_powers_are_exactly_zero() {
        for i in 0..=100_000 {
            let x = GLINT_ZERO * i as f32 / 100_000.0;
            assert_eq!(x.powf(300.0), 0.0, "{x}");
            let y = SUN_DISC_ZERO * i as f32 / 100_000.0;
            assert_eq!(y.powf(2000.0), 0.0, "{y}");
        }
    }

    #[test]
    fn srgb_table_equals_the_formula() {
        // Every step boundary and its neighbours, a dense sweep, and values outside [0, 1].
        let steps = &srgb_tables().steps;
        let mut xs: Vec<f32> = vec![-1.0, -0.0, 0.0, 1.0, 1.5, f32::INFINITY, f32::NAN, 1e-30, 0.003_130_8];
        for &t in steps.iter().take(256) {
            let b = t.to_bits();
            xs.extend((b.saturating_sub(3)..b + 3).map(f32::from_bits));
        }
        xs.extend((0..200_000).map(|i| i as f32 / 200_000.0));
        // ... and every bucket edge with its neighbours.
        for i in 0..=BUCKETS {
            let b = (i as f32 / BUCKETS as f32).to_bits();
            xs.extend((b.saturating_sub(2)..b + 2).map(f32::from_bits));
        }
        for x in xs {
            let want = srgb8_formula(x);
            assert_eq!(to_srgb8(Vec3::splat(x)), [want; 3], "x = {x:e}");
        }
    }

    #[test]
    fn precomputed_shader_equals_the_per_pixel_formulas() {
        // The shading as it was written per pixel (before the constants were hoisted), as a reference.
        fn reference(env: &ShadeEnv, d: Vec3, hit: Option<&SurfaceHit>, sunlit: bool, seed: u64) -> Vec3 {
            let sky = |d: Vec3| {
                let up = d.z.max(0.0).sqrt();
                let brightness = 0.25 + 1.3 * env.ambient;
                let mut c = (v3(env.sky_horizon) * (1.0 - up) + v3(env.sky_zenith) * up) * brightness;
                if d.z < 0.0 {
                    c *= 0.8;
                }
                if env.sun_intensity > 0.0 {
                    let cs = d.dot(v3(env.sun_direction)).max(0.0);
                    c += v3(env.sun_color) * env.sun_intensity * (cs.powi(8) * 0.25 + cs.powf(2000.0) * 20.0);
                }
                let veil = 1.0 - (-env.fog_extinction_per_m * 3000.0).exp();
                c * (1.0 - veil) + v3(env.fog_color) * env.ambient.max(0.1) * 1.3 * veil
            };
            let Some(hit) = hit else { return sky(d) };
            let sun = v3(env.sun_direction);
            let sun_light = v3(env.sun_color) * env.sun_intensity * if sunlit { 1.0 } else { 0.0 };
            let ambient_light = (v3(env.sky_zenith) * 0.5 + v3(env.sky_horizon) * 0.5) * (0.4 + 1.2 * env.ambient);
            let c = if hit.class == 1 {
                let h = env.wave_height_m.max(0.05);
                let (mut gx, mut gy) = (0.0f32, 0.0f32);
                for i in 0..4u64 {
                    let dir = std::f32::consts::TAU * noise::uniform(seed, stream::RIPPLE, 2 * i) as f32;
                    let phase = std::f32::consts::TAU * noise::uniform(seed, stream::RIPPLE, 2 * i + 1) as f32;
                    let wavelength = [41.0f32, 23.0, 11.0, 3.7][i as usize];
                    let k = std::f32::consts::TAU / wavelength;
                    let amp = (0.5 * h).min(0.05 * wavelength) * [0.5f32, 0.3, 0.15, 0.05][i as usize];
                    let (s, c) = dir.sin_cos();
                    let slope = amp * k * (k * (c * hit.point.x + s * hit.point.y) + phase).cos();
                    gx += slope * c;
                    gy += slope * s;
                }
                let mut n = Vec3::new(-gx, -gy, 1.0).normalize_or_zero();
                if n.dot(d) > 0.0 {
                    n = hit.normal;
                }
                let cos = (-d.dot(n)).clamp(0.0, 1.0);
                let fresnel = 0.02 + 0.98 * (1.0 - cos).powi(5);
                let mut r = d - n * (2.0 * d.dot(n));
                r.z = r.z.abs();
                let body = Vec3::new(0.01, 0.045, 0.06) * (ambient_light + sun_light * n.dot(sun).max(0.0));
                let glint = sun_light * r.dot(sun).max(0.0).powf(300.0) * 4.0;
                body * (1.0 - fresnel) + sky(r) * fresnel + glint
            } else {
                albedo(hit) * (ambient_light + sun_light * hit.normal.dot(sun).max(0.0))
            };
            let f = (-env.fog_extinction_per_m * hit.t).exp();
            c * f + v3(env.fog_color) * env.ambient.max(0.1) * 1.3 * (1.0 - f)
        }
        let envs = test_envs();
        let mut k = 0u64;
        for env in &envs {
            let sh = Shader::new(env, 42);
            for i in 0..4000 {
                k += 1;
                let a = i as f32 * 0.37;
                let d = Vec3::new(a.cos() * 0.8, a.sin() * 0.8, (i as f32 * 0.011).sin()).normalize();
                let class = [1u16, 2, 5, 10][i % 4];
                let hit = SurfaceHit {
                    t: 3.0 + i as f32 * 0.7,
                    point: Vec3::new(i as f32 * 1.3 - 900.0, (k % 97) as f32 * 5.1, 0.0),
                    normal: Vec3::Z,
                    class,
                    instance: (i % 7) as i32,
                };
                for sunlit in [true, false] {
                    assert_eq!(sh.shade(d, Some(&hit), sunlit), reference(env, d, Some(&hit), sunlit, 42));
                }
                assert_eq!(sh.shade(d, None, true), reference(env, d, None, true, 42));
            }
        }
    }

    #[test]
    fn shadow_darkens_and_rain_darkens() {
        let env = ShadeEnv::default();
        let hit = SurfaceHit { t: 10.0, point: Vec3::ZERO, normal: Vec3::Z, class: 2, instance: 0 };
        let lit = shade(&env, -Vec3::Z, Some(&hit), true, 1);
        let dark = shade(&env, -Vec3::Z, Some(&hit), false, 1);
        assert!(lit.x > dark.x * 1.5);
        let wet = ShadeEnv { rain_mm_per_h: 16.0, ..env };
        let sum: f32 = (0..64).map(|v| rain(&wet, lit, 3, v, 1).x).sum();
        assert!(sum < lit.x * 64.0);
    }
}
