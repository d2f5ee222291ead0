//! The Kelvin ship waves behind every vessel under way, as the slopes the cameras shade the water with
//! ([`KelvinWaves`]): the divergent waves of a fast craft's wake stand out in the reflections, the transverse waves
//! of a slow ship barely do.
//!
//! Model: the steady, linear, deep-water wave pattern of a pressure distribution moving at speed `U` over the free
//! surface (Havelock, T. H. (1908), "The propagation of groups of waves in dispersive media, with application to
//! waves on water produced by a travelling disturbance", Proc. R. Soc. Lond. A 81, 398–430), the hull standing in as
//! a Gaussian pressure patch as in Darmon, A., Benzaquen, M. & Raphaël, E. (2014), "Kelvin wake pattern at large
//! Froude numbers", J. Fluid Mech. 738, R3: `ζ̂(k) = −k p̂(k) / (ρ (g k − (k·U)²))`, with
//! `p(x, y) = p₀ exp(−x²/2σx² − y²/2σy²)`, `σx = L/4`, `σy = B/4`, and `p₀` such that the patch's static depression
//! `p/ρg` holds the vessel's displaced volume `V` (`p̂(k) = ρ g V exp(−(kx²σx² + ky²σy²)/2)`). Its free waves are
//! those moving with the vessel: direction `θ` from the track, wavenumber `k(θ) = k₀ sec²θ`, `k₀ = g/U²`. Far behind
//! (`k₀ r ≫ 1`) the method of stationary phase (Lighthill, J. (1978), *Waves in Fluids*, Cambridge University
//! Press, §3.10) gives, at distance `r` behind the vessel's centre and angle `α` off its track,
//!
//! `ζ = −Σₛ (V k₀² sec⁴θₛ / π) · exp(−k(θₛ)² (σx² cos²θₛ + σy² sin²θₛ) / 2) · √(2π / |ψ''ₛ|) · sin(ψₛ ± π/4)`,
//!
//! with `ψ(θ) = k₀ r cos(θ − α) sec²θ` and the sum over its stationary angles `θₛ` (`tan θ` the roots of
//! `2 tan α · t² + t + tan α = 0`: the transverse and the divergent waves), which exist within Kelvin's half-angle
//! `asin(1/3) = 19.47°` (Thomson, W. (1887), "On ship waves", Proc. Inst. Mech. Eng. 38, 409–434). Towards that
//! cusp line the two coalesce and `ψ''` vanishes, so the pair is summed with the uniform approximation of
//! Chester, C., Friedman, B. & Ursell, F. (1957), "An extension of the method of steepest descents", Proc.
//! Camb. Phil. Soc. 53, 599–611: `∫ g e^{iψ} dθ ≈ 2π e^{iA} (p₀ Ai(−ζ) − i p₁ Ai'(−ζ))`, `A` the mean of the two
//! phases, `(4/3) ζ^{3/2}` their difference, `p₀ ± p₁√ζ = g √(2√ζ / |ψ''|)` at the two points (`airy.rs`): finite on
//! the caustic (amplitude `∝ r^{-1/3}` along the cusps, `r^{-1/2}` elsewhere), the two stationary-phase waves far
//! from it. Beyond the cusp line the pattern is the Airy tail `2π g (2/|ψ'''|)^{1/3} Ai(z)` at the cusp angle,
//! `z = |ψ'| (|ψ'''|/2)^{-1/3}`.
//!
//! The slope is the elevation's gradient (within the cusps from the phases' gradients `k(θ)(cos θ, sin θ)`, the
//! amplitudes' slow variation left out; in the tail, where the Airy factor falls off across a wavelength, by
//! differences), capped at Michell's limiting steepness `a k = π · 0.142` (Michell, J. H. (1893), "The highest
//! waves in water", Phil. Mag. 36, 430–437): the linear pattern overshoots it only next to the hull. A wave whose
//! length a pixel's footprint cannot resolve (four footprints or fewer, the sea's own rule,
//! `sea/surface/shading.rs`) is left out of the elevation and becomes roughness: its mean square slope `(a k)²/2`,
//! `a` its stationary-phase amplitude. Within a length of the vessel's centre the far field does not hold (the hull
//! covers most of it): the waves grow in as `1 − exp(−(r/L)²)`. They are drawn only where the vessel's path ran
//! straight behind it (the wake row's `reach_m`, thinning over its last quarter), no farther than
//! [`super::wake::WAKE_REACH_S`] of its travel nor than where their steepest slope falls below `4·10⁻³`; a wake row
//! of an older piece of a bent path draws none (its foam does). The waves are slopes, not geometry: the sea's
//! surface, and so every ray's hit point, does not move with them (their heights, centimetres to decimetres, stay
//! out of the wave surface). The cameras shade with them ([`tilted`]); the LiDAR's water model and the radar's
//! sea clutter do not see them (tilting the LiDAR's facets by them was tried and cost 15 % of a LiDAR-only W3
//! recording's speed: `docs/sea/README.md`, *LiDAR returns from wakes*).

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > 0.0)` on purpose: a NaN must answer "no waves"

use super::wake::{Wake, WAKE_REACH_S};

/// Standard gravity, m/s².
const G: f64 = 9.80665;
/// Michell's limiting steepness `a k = π H/λ` with `H/λ = 0.142`.
const MAX_STEEPNESS: f64 = std::f64::consts::PI * 0.142;
/// `tan` of Kelvin's half-angle `asin(1/3)`: `1/√8`.
const TAN_KELVIN: f64 = 0.353_553_390_593_273_8;
/// Where a component's Gaussian factor's exponent passes this, it is left out (`e^{-30}`).
const MAX_EXPONENT: f64 = 30.0;
/// Beyond `tan α` of this (25°) the Airy tail is left out (below 1 % of the cusp's amplitude at `k₀ r ≥ 20`).
const WEDGE_TAN: f64 = 0.466_307_658_154_998_6;
/// Where the Airy tail is left out: `Ai(4) = 9.5·10⁻⁴`.
const TAIL_Z_MAX: f64 = 4.0;
/// The step of the tail's differences, metres.
const TAIL_DIFF_M: f64 = 0.01;
/// Slopes below this are not drawn: a wake's waves end where their steepest falls below it (0.23°, a twentieth of
/// the capillary slopes' r.m.s. per axis under a 2 m/s breeze, Cox–Munk).
const MIN_SLOPE: f64 = 4e-3;
/// Below this speed a vessel draws no wake waves, m/s (its waves are shorter than the capillaries' roughness).
const MIN_SPEED: f64 = 0.5;

/// One vessel's wave source, in its own frame (f64: phases reach thousands of radians).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Source {
    centre: [f64; 2],
    /// Unit heading (the bow's direction).
    h: [f64; 2],
    k0: f64,
    length: f64,
    sx2: f64,
    sy2: f64,
    /// `V k₀² / π`.
    scale: f64,
    /// How far behind the centre the waves are drawn, metres.
    reach: f64,
    /// Where they start to thin out, metres (`reach` when they do not).
    thin_from: f64,
    /// World bounding box of the wedge, `[xmin, ymin, xmax, ymax]`.
    bbox: [f64; 4],
}

/// The slopes of one stationary wave at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KelvinWave {
    /// Amplitude, metres (≥ 0).
    pub amplitude: f64,
    /// Wavenumber, rad/m.
    pub k: f64,
    /// Phase `Φ` (the elevation is `−A sin Φ`).
    pub phase: f64,
    /// Unit direction of `∇Φ` in the vessel's frame: `(behind, port)` components `(cos θ, sin θ)`.
    pub dir: [f64; 2],
}

/// The Kelvin waves of the vessels under way ([`Wake`] rows of age 0), for the cameras' water normals.
#[derive(Debug, Clone, Default)]
pub struct KelvinWaves {
    sources: Vec<Source>,
}

/// The waves' slopes and the roughness of those too short for the pixel, at one point.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct KelvinSlope {
    /// `(∂ζ/∂x, ∂ζ/∂y)`, world.
    pub slope: [f32; 2],
    /// Mean square slope (both axes) of the waves the footprint does not resolve.
    pub unresolved_mss: f32,
}

/// The unit normal `n` of a water facet tilted by the surface slopes `slope` (`∂ζ/∂x, ∂ζ/∂y`) laid over it: the
/// facet's own slopes `(−n_x/n_z, −n_y/n_z)` plus `slope`. `n` itself where `slope` is zero or `n` does not face up.
#[inline]
pub fn tilted(n: parry3d::math::Vec3, slope: [f32; 2]) -> parry3d::math::Vec3 {
    if slope == [0.0, 0.0] || n.z <= 0.0 {
        n
    } else {
        parry3d::math::Vec3::new(n.x / n.z - slope[0], n.y / n.z - slope[1], 1.0).normalize_or(n)
    }
}

impl KelvinWaves {
    /// The wave sources of `wakes` (each vessel's own row, `age_s == 0`, at `MIN_SPEED` or more).
    pub fn new(wakes: &[Wake]) -> Self {
        let sources =
            wakes.iter().filter(|w| w.age_s == 0.0 && f64::from(w.speed) >= MIN_SPEED).filter_map(source).collect();
        Self { sources }
    }

    /// Whether no vessel draws waves.
    pub fn is_empty(&self) -> bool {
        self.sources.is_empty()
    }

    /// The waves' slopes at world `(x, y)` seen with a pixel footprint of `footprint_m` metres (0: every wave
    /// resolved), summed over the vessels.
    #[inline]
    pub fn slope(&self, x: f32, y: f32, footprint_m: f32) -> KelvinSlope {
        let (px, py) = (f64::from(x), f64::from(y));
        let mut out = [0.0f64; 2];
        let mut mss = 0.0f64;
        let k_max = std::f64::consts::FRAC_PI_2 / f64::from(footprint_m.max(0.0));
        for s in &self.sources {
            let b = &s.bbox;
            if px < b[0] || py < b[1] || px > b[2] || py > b[3] {
                continue;
            }
            let (behind, port) = s.frame(px, py);
            let f = fade(s, behind);
            if f == 0.0 || !s.in_wedge(behind, port) {
                continue;
            }
            let here = local(s, behind, port);
            let short = match &here {
                Local::None => false,
                Local::Inside(a, b, _) => a.k > k_max || b.as_ref().is_some_and(|b| b.k > k_max),
                Local::Tail(c, _) => c.k > k_max,
            };
            if short {
                let (ws, n) = here.waves(s);
                for w in ws[..n].iter().filter(|w| w.k > k_max) {
                    let ak = (w.amplitude * f * w.k).min(MAX_STEEPNESS);
                    mss += 0.5 * ak * ak;
                }
            }
            let (_, g) = match here {
                // Beyond the cusp line the Airy factor falls off across a wavelength: its gradient by differences.
                Local::Tail(..) => {
                    let at = |b: f64, p: f64| local(s, b, p).elevation(s, k_max).0;
                    let (h, z) = (TAIL_DIFF_M, here.elevation(s, k_max).0);
                    (z, [(at(behind + h, port) - z) / h, (at(behind, port + h) - z) / h])
                }
                _ => here.elevation(s, k_max),
            };
            let [gx, gy] = s.world_gradient(g).map(|v| f * v);
            let g = gx.hypot(gy);
            let cap = if g > MAX_STEEPNESS { MAX_STEEPNESS / g } else { 1.0 };
            out[0] += gx * cap;
            out[1] += gy * cap;
        }
        KelvinSlope { slope: [out[0] as f32, out[1] as f32], unresolved_mss: mss as f32 }
    }

    /// The elevation `ζ` (metres) at world `(x, y)`, summed over the vessels (for checks and pictures).
    pub fn elevation(&self, x: f64, y: f64) -> f64 {
        self.sources.iter().map(|s| source_elevation(s, x, y, f64::INFINITY).0).sum()
    }

    /// The elevation of the first vessel's waves at `behind`, `port` metres in its frame, without the fades (for
    /// checks).
    pub fn local_elevation(&self, behind: f64, port: f64) -> f64 {
        self.sources.first().map_or(0.0, |s| local(s, behind, port).elevation(s, f64::INFINITY).0)
    }

    /// The stationary-phase waves (at most two) of the first vessel at `behind`, `port` metres in its frame,
    /// without the fades (for checks).
    pub fn waves_at(&self, behind: f64, port: f64) -> Vec<KelvinWave> {
        self.sources.first().map_or_else(Vec::new, |s| {
            let (w, n) = local(s, behind, port).waves(s);
            w[..n].to_vec()
        })
    }
}

/// The wave source of one wake row, or `None` when it draws nothing.
fn source(w: &Wake) -> Option<Source> {
    let u = f64::from(w.speed);
    let (length, beam) = (f64::from(w.length), f64::from(w.beam));
    let volume = f64::from(w.displacement_m3);
    if !(volume > 0.0 && length > 0.0 && beam > 0.0) {
        return None;
    }
    let k0 = G / (u * u);
    let reach = f64::from(w.reach_m).min(u * f64::from(WAKE_REACH_S));
    let thin_from = if f64::from(w.reach_m) < u * f64::from(WAKE_REACH_S) { 0.75 * reach } else { reach };
    let scale = volume * k0 * k0 / std::f64::consts::PI;
    let (sx2, sy2) = ((length / 4.0).powi(2), (beam / 4.0).powi(2));
    // The Gaussian factor is largest for the transverse wave on the track, exp(−k₀²σx²/2) = exp(−1/(32 Fr⁴)): a
    // hull below a Froude number of 0.18 makes no wave above e^{-30} of its scale.
    if !(reach > 0.0) || k0 * k0 * sx2 / 2.0 > MAX_EXPONENT {
        return None;
    }
    let h = [f64::from(w.heading).cos(), f64::from(w.heading).sin()];
    let c = [f64::from(w.x), f64::from(w.y)];
    let mut s = Source { centre: c, h, k0, length, sx2, sy2, scale, reach, thin_from, bbox: [0.0; 4] };
    // Where the waves' slopes fall below MIN_SLOPE: no farther than r₀ (S₀ / MIN_SLOPE)³, S₀ the steepest wave met
    // across the wedge at r₀ (they decay as r^{-1/2}, along the cusps as r^{-1/3}).
    let r0 = (2.0 * length).max(20.0 / k0);
    let steepest = (0..=40)
        .map(|i| {
            let a = TAN_KELVIN.atan() * 1.05 * f64::from(i) / 40.0;
            let (ws, n) = local(&s, r0 * a.cos(), r0 * a.sin()).waves(&s);
            ws[..n].iter().map(|w| (w.amplitude * w.k).min(MAX_STEEPNESS)).fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    let far = r0 * (steepest / MIN_SLOPE).powi(3);
    if far < s.reach {
        s.reach = far.max(r0);
        s.thin_from = s.thin_from.min(0.75 * s.reach);
    }
    let reach = s.reach;
    // The wedge behind the centre, as wide as the tail drawn, and the hull.
    let half = reach * WEDGE_TAN + length;
    let back = [c[0] - h[0] * reach, c[1] - h[1] * reach];
    let perp = [-h[1], h[0]];
    let pts = [
        [c[0] + h[0] * length + perp[0] * length, c[1] + h[1] * length + perp[1] * length],
        [c[0] + h[0] * length - perp[0] * length, c[1] + h[1] * length - perp[1] * length],
        [back[0] + perp[0] * half, back[1] + perp[1] * half],
        [back[0] - perp[0] * half, back[1] - perp[1] * half],
    ];
    let bbox = pts.iter().fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |b, p| {
        [b[0].min(p[0]), b[1].min(p[1]), b[2].max(p[0]), b[3].max(p[1])]
    });
    s.bbox = bbox;
    Some(s)
}

/// The near-field growth and the reach's thinning at `behind` metres behind the centre (0 outside).
#[inline(always)]
fn fade(s: &Source, behind: f64) -> f64 {
    if !(behind > 0.0) || behind >= s.reach {
        return 0.0;
    }
    let near = 1.0 - (-(behind / s.length).powi(2)).exp();
    let thin = if behind > s.thin_from { (s.reach - behind) / (s.reach - s.thin_from) } else { 1.0 };
    near * thin
}

/// `f(θ) = cos(θ − α) sec²θ` and its derivatives `f'`, `f''`, `f'''` at `tan θ = t`, given `cos α`, `sin α`.
#[inline(always)]
fn phase_derivatives(t: f64, ca: f64, sa: f64) -> [f64; 4] {
    let sec2 = 1.0 + t * t;
    let c = 1.0 / sec2.sqrt();
    let s = t * c;
    let cd = c * ca + s * sa; // cos(θ − α)
    let sd = s * ca - c * sa; // sin(θ − α)
    let g = 2.0 * t * cd - sd;
    let g1 = 2.0 * sec2 * cd - 2.0 * t * sd - cd;
    let g2 = 4.0 * sec2 * t * cd - 4.0 * sec2 * sd - 2.0 * t * cd + sd;
    // f' = sec²θ g; f'' = sec²θ (2 t g + g'); f''' = sec²θ (2 (sec²θ + 2t²) g + 4 t g' + g'').
    let f1 = sec2 * g;
    let f2 = sec2 * (2.0 * t * g + g1);
    let f3 = sec2 * (2.0 * (sec2 + 2.0 * t * t) * g + 4.0 * t * g1 + g2);
    [cd * sec2, f1, f2, f3]
}

/// One stationary wave direction of the pattern at a point: the phase `ψ`, `ψ''`, the integrand's
/// `sec⁴θ · G(θ)` (0 where the hull makes no such wave), the wavenumber and `(cos θ, sin θ)`.
#[derive(Debug, Clone, Copy)]
struct Stat {
    phase: f64,
    p2: f64,
    g: f64,
    k: f64,
    dir: [f64; 2],
}

/// The pattern at one point of the vessel's frame.
enum Local {
    /// Ahead of the centre: none.
    None,
    /// Within the cusps: the transverse wave's and, when its direction exists (`tan α ≠ 0`), the divergent one's,
    /// with `ψ'''` at the cusp angle (the caustic's limit).
    Inside(Stat, Option<Stat>, f64),
    /// Beyond the cusp line: the cusp angle's wave and its Airy factor `2π (2/|ψ'''|)^{1/3} Ai(z)`.
    Tail(Stat, f64),
}

/// The stationary wave of source `s` at `tan θ = t` (point at `kr = k₀ r`, `cos α`, `sin α`) and `f`'s derivatives.
#[inline(always)]
fn stat(s: &Source, t: f64, kr: f64, ca: f64, sa: f64) -> (Stat, [f64; 4]) {
    let d = phase_derivatives(t, ca, sa);
    let sec2 = 1.0 + t * t;
    let c = 1.0 / sec2.sqrt();
    let sn = t * c;
    let k = s.k0 * sec2;
    let e = k * k * (s.sx2 * c * c + s.sy2 * sn * sn) / 2.0;
    let g = if e > MAX_EXPONENT { 0.0 } else { sec2 * sec2 * (-e).exp() };
    (Stat { phase: kr * d[0], p2: kr * d[2], g, k, dir: [c, sn] }, d)
}

/// The pattern of source `s` at `behind`, `port` metres (vessel frame).
#[inline(always)]
fn local(s: &Source, behind: f64, port: f64) -> Local {
    let r = behind.hypot(port);
    if !(behind > 0.0) || r == 0.0 {
        return Local::None;
    }
    let (ca, sa) = (behind / r, port / r);
    let tau = port / behind; // tan α
    let kr = s.k0 * r;
    let disc = 1.0 - 8.0 * tau * tau;
    if disc >= 0.0 {
        let q = disc.sqrt();
        // Both roots of 2τ t² + t + τ = 0, in forms that stay accurate as τ → 0: the transverse wave's t, and the
        // divergent wave's (infinite at τ = 0: a wave along the beam, which a hull does not make).
        let (a, _) = stat(s, -2.0 * tau / (1.0 + q), kr, ca, sa);
        if tau == 0.0 {
            return Local::Inside(a, None, 0.0);
        }
        let (b, _) = stat(s, -(1.0 + q) / (4.0 * tau), kr, ca, sa);
        let p3 = kr * phase_derivatives(-1.0 / (4.0 * tau), ca, sa)[3];
        Local::Inside(a, Some(b), p3)
    } else {
        // Beyond the cusp line: the pair's Airy tail at the cusp angle (tan θ = −1/(4 tan α)).
        let (c, d) = stat(s, -1.0 / (4.0 * tau), kr, ca, sa);
        let half_p3 = (kr * d[3]).abs().max(1e-300) / 2.0;
        let p1 = (kr * d[1]).abs();
        // Past z = 4 the tail is below 0.3 % of the caustic's Ai(0) (tested without the cube root: z³ = |ψ'|³/(|ψ'''|/2)).
        if p1 * p1 * p1 > TAIL_Z_MAX.powi(3) * half_p3 {
            return Local::None;
        }
        let c3 = half_p3.cbrt(); // (|ψ'''|/2)^{1/3}
        let z = p1 / c3;
        let m = 2.0 * std::f64::consts::PI / c3 * airy::airy(z).0;
        Local::Tail(c, m)
    }
}

impl Local {
    /// The stationary-phase waves here (amplitudes before the fades; for the roughness and the checks): the first
    /// `n` of the array.
    fn waves(&self, s: &Source) -> ([KelvinWave; 2], usize) {
        let wave = |w: &Stat, amplitude: f64| KelvinWave { amplitude, k: w.k, phase: w.phase, dir: w.dir };
        let none = KelvinWave { amplitude: 0.0, k: 0.0, phase: 0.0, dir: [1.0, 0.0] };
        let mut out = [none; 2];
        let mut n = 0;
        match self {
            Local::None => {}
            Local::Inside(a, b, p3) => {
                // Each no larger than the caustic's largest, 2π (2/|ψ'''|)^{1/3} max Ai (the stationary phase's
                // amplitude grows without bound on the cusp line).
                let tau = 2.0 * std::f64::consts::PI;
                let q = (p3.abs() / 2.0).powi(2) / (tau * airy::AI_MAX * airy::AI_MAX).powi(3);
                for w in std::iter::once(a).chain(b.as_ref()).filter(|w| w.g > 0.0) {
                    // (The cap binds where |ψ''|³ < (|ψ'''|/2)² / (2π max Ai²)³: no cube root elsewhere.)
                    let capped = b.is_some() && w.p2.abs().powi(3) < q;
                    let m = if capped {
                        tau * (2.0 / p3.abs().max(1e-300)).cbrt() * airy::AI_MAX
                    } else {
                        (tau / w.p2.abs()).sqrt()
                    };
                    out[n] = wave(w, s.scale * w.g * m);
                    n += 1;
                }
            }
            Local::Tail(c, m) => {
                if c.g > 0.0 {
                    out[0] = wave(c, s.scale * c.g * m.abs());
                    n = 1;
                }
            }
        }
        (out, n)
    }

    /// The elevation (before the fades) of the waves no longer than `k_max` allows, metres, and its gradient in the
    /// vessel's frame (`∂/∂behind`, `∂/∂port`), the amplitudes' slow variation left out.
    fn elevation(&self, s: &Source, k_max: f64) -> (f64, [f64; 2]) {
        let keep = |w: &Stat| if w.k <= k_max { w.g } else { 0.0 };
        let grad = |w: &Stat| [w.k * w.dir[0], w.k * w.dir[1]];
        let (im, d) = match self {
            Local::None => return (0.0, [0.0; 2]),
            Local::Tail(c, m) => {
                let (sn, cs) = c.phase.sin_cos();
                let a = keep(c) * m;
                let g = grad(c);
                (a * sn, [a * cs * g[0], a * cs * g[1]])
            }
            Local::Inside(a, None, _) => {
                // The transverse wave alone (on the track): stationary phase, ψ'' > 0.
                let amp = keep(a) * (2.0 * std::f64::consts::PI / a.p2.abs()).sqrt();
                let (sn, cs) = (a.phase + std::f64::consts::FRAC_PI_4).sin_cos();
                let g = grad(a);
                (amp * sn, [amp * cs * g[0], amp * cs * g[1]])
            }
            Local::Inside(a, Some(b), _) if keep(a) == 0.0 && keep(b) == 0.0 => return (0.0, [0.0; 2]),
            Local::Inside(a, Some(b), p3) => {
                // Chester–Friedman–Ursell: the point with ψ'' > 0 at u = +√ζ, the other at −√ζ.
                let (lo, hi) = if a.p2 >= b.p2 { (a, b) } else { (b, a) };
                let mean = 0.5 * (lo.phase + hi.phase);
                let zeta = (0.75 * (hi.phase - lo.phase).max(0.0)).powf(2.0 / 3.0);
                let root = zeta.sqrt();
                let jac = |w: &Stat| {
                    let j = (2.0 * root / w.p2.abs()).sqrt();
                    if j.is_finite() && root > 1e-6 {
                        j
                    } else {
                        (2.0 / p3.abs().max(1e-300)).cbrt() // on the caustic
                    }
                };
                let (ga, gb) = (keep(lo) * jac(lo), keep(hi) * jac(hi));
                let p0 = 0.5 * (ga + gb);
                let p1 = if root > 1e-6 { (ga - gb) / (2.0 * root) } else { 0.0 };
                let (ai, dai) = airy::airy(-zeta);
                let (sn, cs) = mean.sin_cos();
                let (p, q) = (p0 * ai, p1 * dai);
                // I = 2π e^{iA} (P − iQ); ∇I = 2π e^{iA} (i ∇A (P − iQ) + ∇ζ (−p₀ Ai'(−ζ) − i p₁ ζ Ai(−ζ))), with
                // ∇A the mean of the two phases' gradients, ∇ζ their difference over 2√ζ (Ai'' = x Ai).
                let (gl, gh) = (grad(lo), grad(hi));
                let mut d = [0.0; 2];
                for j in 0..2 {
                    let da = 0.5 * (gl[j] + gh[j]);
                    let dz = if root > 1e-6 { (gh[j] - gl[j]) / (2.0 * root) } else { 0.0 };
                    let (xr, xi) = (da * q - dz * p0 * dai, da * p - dz * p1 * zeta * ai);
                    d[j] = 2.0 * std::f64::consts::PI * (sn * xr + cs * xi);
                }
                (2.0 * std::f64::consts::PI * (sn * p - cs * q), d)
            }
        };
        // Re[i · scale · I] = −scale · Im I.
        (-s.scale * im, [-s.scale * d[0], -s.scale * d[1]])
    }
}

/// The elevation of source `s` at world `(x, y)` of the waves up to wavenumber `k_max`, with the fades, and its
/// world gradient.
#[inline(always)]
fn source_elevation(s: &Source, x: f64, y: f64, k_max: f64) -> (f64, [f64; 2]) {
    let (behind, port) = s.frame(x, y);
    let f = fade(s, behind);
    if f == 0.0 || !s.in_wedge(behind, port) {
        return (0.0, [0.0; 2]);
    }
    let (z, g) = local(s, behind, port).elevation(s, k_max);
    (f * z, s.world_gradient(g).map(|v| f * v))
}

impl Source {
    /// World `(x, y)` in the vessel's frame: metres `behind` its centre and to `port`.
    #[inline(always)]
    fn frame(&self, x: f64, y: f64) -> (f64, f64) {
        let (dx, dy) = (x - self.centre[0], y - self.centre[1]);
        (-(dx * self.h[0] + dy * self.h[1]), -dx * self.h[1] + dy * self.h[0])
    }

    /// Whether a point of the vessel's frame lies within the wedge drawn (the Airy tail's and the hull's margin).
    #[inline(always)]
    fn in_wedge(&self, behind: f64, port: f64) -> bool {
        port.abs() <= behind * WEDGE_TAN + self.length
    }

    /// A gradient `(∂/∂behind, ∂/∂port)` in world axes: behind = −(d·h), port = d·h⊥, so
    /// `∂/∂x = −h.x ∂/∂behind − h.y ∂/∂port` and `∂/∂y = −h.y ∂/∂behind + h.x ∂/∂port`.
    #[inline(always)]
    fn world_gradient(&self, [gb, gp]: [f64; 2]) -> [f64; 2] {
        [-self.h[0] * gb - self.h[1] * gp, -self.h[1] * gb + self.h[0] * gp]
    }
}

mod airy;

#[cfg(test)]
mod tests;
