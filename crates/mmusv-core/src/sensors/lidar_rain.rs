//! LiDAR returns from falling rain drops: the hybrid Monte-Carlo model of LISA.
//!
//! Source: Kilic, V., Hegde, D., Sindagi, V., Cooper, A. B., Foster, M. A. & Patel, V. M. (2021), "Lidar Light
//! Scattering Augmentation (LISA): Physics-based Simulation of Adverse Weather Conditions for 3D Object
//! Detection", arXiv:2107.07004, and its code (`velatkilic/LISA`, `lisa.py`, `lisa_mc`, *strongest* mode). Per
//! beam:
//!
//! * the drops in the beam are those of a cone of full angle `δ` (the beam divergence) from the sensor to the
//!   surface the beam meets (to the LiDAR's range where it meets none), beyond the LiDAR's minimum range; the beam's
//!   diameter at range `s` is `D_b(s) = δ s` (LISA's `1e3 tan(bdiv) x` mm; `tan δ = δ` to 3·10⁻⁶ at 3 mrad);
//! * their diameters follow Marshall & Palmer (1948), "The distribution of raindrops with size", J. Meteorol.
//!   5(4): `N(D) = N₀ e^(−Λ D)`, `N₀ = 8000 m⁻³ mm⁻¹`, `Λ = 4.1 R^(−0.21) mm⁻¹` (`R` the rain rate in mm/h),
//!   from `D₀ = 0.05 mm` up (LISA's smallest drop);
//! * a drop at range `s` of diameter `D` returns the power `P = ρ_w τ(s) min((D / D_b(s))², 1) / s²` (arbitrary
//!   units, LISA's): `ρ_w = ((n − 1)/(n + 1))² = 0.0201` the Fresnel reflectance of water (`n = 1.328` at 905 nm,
//!   LISA's) at normal incidence, the share of the beam the drop intercepts, two-way transmission
//!   `τ(s) = exp(−2σs)` with the LiDAR's air extinction `σ` (3 / visibility, the rain's drops included), and the
//!   inverse square of range;
//! * the surface the beam meets returns `P₀ = ρ |cos θ| τ(r) / r²` (the same law: the LiDAR's intensity without its
//!   near-range factor, `I (1 + (r / 100 m)²) / r²`), 0 where the beam meets nothing or its return is lost;
//! * the strongest drop replaces the surface's return where its power exceeds both `P₀` and the smallest power the
//!   receiver detects, `P_min = 0.9 / r_max²` (a 0.9 reflector at the LiDAR's range `r_max`; LISA's). Its
//!   intensity is the LiDAR's law with the drop's reflectivity `ρ_w min((D / D_b)², 1)` at normal incidence.
//!
//! Two departures from LISA's code, both to make its numbers exact rather than sampled differently:
//!
//! * LISA rounds the expected number of drops in the cone to an integer at random; drops falling independently
//!   are a Poisson process, and the count here is a Poisson draw of the same mean.
//! * LISA draws every drop of the cone (hundreds within 30 m at 10 mm/h) and keeps the strongest. Only drops whose
//!   power could exceed `P_min` matter: with `τ ≤ 1`, those with `D ≥ D_min(s) = D_b(s) s √(P_min / ρ_w)` within
//!   `s < s_max = √(ρ_w / P_min)` (0.149 `r_max`). They are themselves a Poisson process, of intensity
//!   `A(s) N₀ e^(−Λ max(D₀, D_min(s))) / Λ` per metre of range (`A(s) = π D_b(s)² / 4` the beam's cross-section)
//!   with diameters `max(D₀, D_min(s))` plus an exponential of mean `1 / Λ`; this model draws those alone (a few
//!   hundredths of a drop per beam at 10 mm/h), then applies `τ` and the thresholds as LISA does. The
//!   distribution of the strongest drop is the same; `tests` check it against a brute-force draw of every drop.
//!
//! The drops' own points have class 0 (nothing: `mmusv.classes`, like the radar's rain clutter) and no instance.
//! The range noise and gates of the LiDAR apply to them as to any return.

use super::noise::{self, stream};

/// Marshall–Palmer intercept `N₀` (drops per m³ per mm of diameter).
pub const MP_N0: f64 = 8000.0;
/// The smallest drop drawn (mm), LISA's `dst`.
pub const MIN_DROP_MM: f64 = 0.05;
/// Refractive index of water at 905 nm (LISA's `m`).
pub const WATER_INDEX: f64 = 1.328;
/// The receiver's threshold as a reflector's reflectivity at the LiDAR's range (`P_min = 0.9 / r_max²`, LISA's).
pub const THRESHOLD_REFLECTIVITY: f64 = 0.9;
/// Cells of the table of the expected drop count along the beam.
const CELLS: usize = 4096;
/// Most drops drawn for one beam (the count's mean is a few hundredths: a cap that never binds in practice).
const MAX_DROPS: u64 = 31;

/// Fresnel reflectance of water at normal incidence, `((n − 1)/(n + 1))²`.
pub fn water_reflectance() -> f64 {
    let n = WATER_INDEX;
    ((n - 1.0) / (n + 1.0)).powi(2)
}

/// Marshall–Palmer slope `Λ = 4.1 R^(−0.21)` (per mm) for the rain rate `R` (mm/h, > 0).
pub fn mp_slope(rain_mm_per_h: f64) -> f64 {
    4.1 * rain_mm_per_h.powf(-0.21)
}

/// The strongest drop of one beam that the receiver detects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DropReturn {
    /// Range of the drop from the sensor (metres).
    pub range: f64,
    /// Its received power, LISA's units (`ρ τ / s²`, the beam-filling share included).
    pub power: f64,
    /// Its reflectivity: `ρ_w min((D / D_b)², 1)`.
    pub reflectivity: f64,
}

/// The rain's drops as a LiDAR's beams meet them, for one rain rate, beam divergence, range window and air: the
/// expected count of detectable drops along a beam, tabulated once.
#[derive(Debug, Clone)]
pub struct RainDrops {
    /// The nearest range drops are seen at (metres): the LiDAR's minimum range.
    s0: f64,
    /// Table step (metres).
    ds: f64,
    /// Expected count of detectable drops from `s0` to `s0 + k ds`, `k = 0..=CELLS`.
    cumulative: Vec<f64>,
    /// Marshall–Palmer slope (per mm).
    slope: f64,
    /// Beam divergence (full angle, radians).
    divergence: f64,
    /// Air extinction σ (1/m).
    sigma: f64,
    /// `P_min`.
    p_min: f64,
    /// `√(P_min / ρ_w)`, per metre.
    k_min: f64,
    /// The probability of no detectable drop along a beam reaching past [`Self::max_range`] (most beams): `e^(−μ)`
    /// of the table's whole count, worked out once.
    none_beyond: f64,
}

impl RainDrops {
    /// The drops of rain falling at `rain_mm_per_h` for a LiDAR of beam divergence `divergence` (full angle,
    /// radians) seeing from `range_min` to `range_max` (metres) in air of extinction `sigma` (1/m). `None` where
    /// no drop can return: no rain, no divergence (a line meets no drop), or every detectable drop nearer than
    /// `range_min`. Non-finite or negative inputs give `None` too (the LiDAR's config and environment are
    /// validated before).
    pub fn new(rain_mm_per_h: f64, divergence: f64, range_min: f64, range_max: f64, sigma: f64) -> Option<Self> {
        let ok = |v: f64| v.is_finite() && v >= 0.0;
        if !(ok(rain_mm_per_h) && ok(divergence) && ok(range_min) && ok(sigma) && range_max.is_finite()) {
            return None;
        }
        if rain_mm_per_h <= 0.0 || divergence <= 0.0 || range_max <= range_min {
            return None;
        }
        let rho = water_reflectance();
        let p_min = THRESHOLD_REFLECTIVITY / (range_max * range_max);
        let s_max = (rho / p_min).sqrt();
        if s_max <= range_min {
            return None;
        }
        let slope = mp_slope(rain_mm_per_h);
        let k_min = (p_min / rho).sqrt();
        let mut this = Self {
            s0: range_min,
            ds: (s_max - range_min) / CELLS as f64,
            cumulative: Vec::with_capacity(CELLS + 1),
            slope,
            divergence,
            sigma,
            p_min,
            k_min,
            none_beyond: 1.0,
        };
        // Trapezoids of the count's density over the cells.
        let mut sum = 0.0;
        let mut prev = this.density(range_min);
        this.cumulative.push(0.0);
        for k in 1..=CELLS {
            let d = this.density(range_min + k as f64 * this.ds);
            sum += 0.5 * (prev + d) * this.ds;
            this.cumulative.push(sum);
            prev = d;
        }
        this.none_beyond = (-sum).exp();
        Some(this)
    }

    /// Beam diameter at range `s` (mm).
    fn beam_mm(&self, s: f64) -> f64 {
        1e3 * self.divergence * s
    }

    /// Smallest drop (mm) at range `s` whose power could exceed `P_min` (with `τ` 1), never below `D₀`.
    fn smallest(&self, s: f64) -> f64 {
        (self.beam_mm(s) * s * self.k_min).max(MIN_DROP_MM)
    }

    /// Expected count of detectable drops per metre of beam at range `s`.
    fn density(&self, s: f64) -> f64 {
        let area = std::f64::consts::PI * (self.divergence * s).powi(2) / 4.0;
        area * MP_N0 * (-self.slope * self.smallest(s)).exp() / self.slope
    }

    /// Farthest range a drop can be detected at (metres).
    pub fn max_range(&self) -> f64 {
        self.s0 + self.ds * CELLS as f64
    }

    /// Expected count of drops within `reach` metres that the receiver could detect (`τ` taken as 1).
    pub fn expected_count(&self, reach: f64) -> f64 {
        let x = (reach.min(self.max_range()) - self.s0) / self.ds;
        if x.is_nan() || x <= 0.0 {
            return 0.0;
        }
        let i = (x as usize).min(CELLS - 1);
        let f = x - i as f64;
        self.cumulative[i] + f * (self.cumulative[i + 1] - self.cumulative[i])
    }

    /// The range where the expected count reaches `m` (`0 ≤ m ≤` the count at the table's end).
    fn range_at(&self, m: f64) -> f64 {
        let i = self.cumulative.partition_point(|&c| c < m).clamp(1, CELLS);
        let (a, b) = (self.cumulative[i - 1], self.cumulative[i]);
        let f = if b > a { ((m - a) / (b - a)).clamp(0.0, 1.0) } else { 0.0 };
        self.s0 + (i as f64 - 1.0 + f) * self.ds
    }

    /// Received power of a drop of `d_mm` at range `s` and its reflectivity.
    pub fn drop_power(&self, s: f64, d_mm: f64) -> (f64, f64) {
        let share = (d_mm / self.beam_mm(s)).powi(2).min(1.0);
        let reflectivity = water_reflectance() * share;
        (reflectivity * (-2.0 * self.sigma * s).exp() / (s * s), reflectivity)
    }

    /// The strongest detectable drop of the beam `index` that reaches `reach` metres, if its power exceeds
    /// `target_power` (`P₀`, 0 for a beam with no return) and `P_min`. Draws from [`stream::RAIN_DROPS`] at
    /// counters `64 · index ..= 64 · index + 63` of `seed`.
    pub fn strongest(&self, reach: f64, target_power: f64, seed: u64, index: u64) -> Option<DropReturn> {
        let mean = self.expected_count(reach);
        if mean <= 0.0 {
            return None;
        }
        let base = index.wrapping_mul(64);
        // The Poisson count by inversion of its distribution.
        let u = noise::uniform(seed, stream::RAIN_DROPS, base);
        let mut p = if reach >= self.max_range() { self.none_beyond } else { (-mean).exp() };
        let mut cdf = p;
        let mut count = 0u64;
        while u >= cdf && count < MAX_DROPS {
            count += 1;
            p *= mean / count as f64;
            cdf += p;
        }
        let mut best: Option<DropReturn> = None;
        for j in 0..count {
            let us = noise::uniform(seed, stream::RAIN_DROPS, base + 1 + 2 * j);
            let ud = noise::uniform(seed, stream::RAIN_DROPS, base + 2 + 2 * j);
            let s = self.range_at(us * mean);
            let d = self.smallest(s) - (1.0 - ud).ln() / self.slope;
            let (power, reflectivity) = self.drop_power(s, d);
            if best.is_none_or(|b| power > b.power) {
                best = Some(DropReturn { range: s, power, reflectivity });
            }
        }
        best.filter(|b| b.power > target_power.max(self.p_min))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A brute-force beam as LISA's `lisa_mc` draws it: every drop of the cone from `D₀` up (a Poisson count of
    /// mean `N(D ≥ D₀) · V`, `V = π/3 · L · (δL/2)²`), ranges from the cone's `s²` law, drops within `s0` left out,
    /// diameters from Marshall–Palmer; the strongest one, if it beats `P₀` and `P_min`.
    fn brute(rain: &RainDrops, reach: f64, p0: f64, seed: u64, index: u64) -> Option<DropReturn> {
        let total = MP_N0 * (-rain.slope * MIN_DROP_MM).exp() / rain.slope;
        let volume = std::f64::consts::PI / 3.0 * reach * (rain.divergence * reach / 2.0).powi(2);
        let mean = total * volume;
        let draw = |k: u64| noise::uniform(seed ^ 0x5eed, 99, index.wrapping_mul(1 << 20) + k);
        // Poisson count by the sum of exponential gaps (the mean is in the tens here).
        let mut count = 0u64;
        let mut t = -(1.0 - draw(0)).ln();
        while t < mean {
            count += 1;
            t -= (1.0 - draw(count)).ln();
        }
        let mut best: Option<DropReturn> = None;
        for j in 0..count {
            let s = reach * draw(100_000 + 2 * j).cbrt();
            if s <= rain.s0 {
                continue;
            }
            let d = MIN_DROP_MM - (1.0 - draw(100_001 + 2 * j)).ln() / rain.slope;
            let (power, reflectivity) = rain.drop_power(s, d);
            if best.is_none_or(|b| power > b.power) {
                best = Some(DropReturn { range: s, power, reflectivity });
            }
        }
        best.filter(|b| b.power > p0.max(rain.p_min))
    }

    /// The thinned draw against LISA's brute force, beam by beam independent draws: the share of beams that
    /// return from a drop, and the mean range and reflectivity of those returns, agree within 4.5 standard errors
    /// — at 10 and 50 mm/h, in clear air and in the rain's own extinction, for beams meeting nothing within 12 m
    /// and beams meeting a weak target at 6 m.
    #[test]
    fn thinned_drops_match_the_brute_force_of_every_drop() {
        let n = 60_000u64;
        for (rate, sigma, reach, p0) in
            [(10.0, 0.0, 12.0, 0.0), (50.0, 3.0 / 700.0, 12.0, 0.0), (10.0, 0.0, 6.0, 0.03 * 0.4 / 36.0)]
        {
            let rain = RainDrops::new(rate, 3e-3, 0.5, 200.0, sigma).unwrap_or_else(|| unreachable!());
            let stats = |f: &dyn Fn(u64) -> Option<DropReturn>| {
                let hits: Vec<DropReturn> = (0..n).filter_map(f).collect();
                let m = hits.len() as f64;
                let mean = |g: fn(&DropReturn) -> f64| hits.iter().map(g).sum::<f64>() / m;
                let sd = |g: fn(&DropReturn) -> f64| {
                    let mu = mean(g);
                    (hits.iter().map(|h| (g(h) - mu).powi(2)).sum::<f64>() / (m - 1.0)).sqrt()
                };
                (m / n as f64, mean(|h| h.range), sd(|h| h.range), mean(|h| h.reflectivity), sd(|h| h.reflectivity), m)
            };
            let a = stats(&|i| rain.strongest(reach, p0, 7, i));
            let b = stats(&|i| brute(&rain, reach, p0, 7, i));
            eprintln!("R {rate} mm/h, σ {sigma:.4}/m, reach {reach} m: thinned {a:?}, brute {b:?}");
            assert!(a.5 > 300.0 && b.5 > 300.0, "too few drop returns to compare: {a:?} {b:?}");
            let se_share = (a.0 * (1.0 - a.0) / n as f64 + b.0 * (1.0 - b.0) / n as f64).sqrt();
            assert!((a.0 - b.0).abs() < 4.5 * se_share, "share of beams: {} vs {}", a.0, b.0);
            let se = |sa: f64, sb: f64| (sa * sa / a.5 + sb * sb / b.5).sqrt();
            assert!((a.1 - b.1).abs() < 4.5 * se(a.2, b.2), "mean range: {} vs {}", a.1, b.1);
            assert!((a.3 - b.3).abs() < 4.5 * se(a.4, b.4), "mean reflectivity: {} vs {}", a.3, b.3);
        }
    }

    /// The tabulated count is the double integral of the drops that could be detected, worked out on a fine
    /// grid in range and diameter by its own quadrature (no closed form in `D` used): within 0.5 %.
    #[test]
    fn expected_count_is_the_integral_of_the_detectable_drops() {
        let rain = RainDrops::new(25.0, 2e-3, 1.0, 120.0, 0.0).unwrap_or_else(|| unreachable!());
        let (reach, ns, nd, dmax) = (9.0, 3000, 6000, 12.0);
        let mut sum = 0.0;
        for i in 0..ns {
            let s = 1.0 + (reach - 1.0) * (i as f64 + 0.5) / ns as f64;
            let area = std::f64::consts::PI * (2e-3 * s).powi(2) / 4.0;
            for j in 0..nd {
                let d = MIN_DROP_MM + (dmax - MIN_DROP_MM) * (j as f64 + 0.5) / nd as f64;
                if rain.drop_power(s, d).0 > rain.p_min {
                    sum += area * MP_N0 * (-rain.slope * d).exp();
                }
            }
        }
        sum *= (reach - 1.0) / ns as f64 * (dmax - MIN_DROP_MM) / nd as f64;
        let table = rain.expected_count(reach);
        assert!((table / sum - 1.0).abs() < 5e-3, "table {table} vs quadrature {sum}");
        // Nothing beyond √(ρ_w / P_min) can be detected: the count stops growing there.
        let s_max = (water_reflectance() / rain.p_min).sqrt();
        assert!((rain.max_range() - s_max).abs() < 1e-9);
        assert_eq!(rain.expected_count(s_max + 50.0), rain.expected_count(s_max));
    }

    /// No rain, no divergence or a window the drops cannot be seen in: no model. A stronger target hides drops:
    /// a target twice as strong as the strongest drop any beam gets keeps every beam.
    #[test]
    fn no_drops_without_rain_or_divergence_and_strong_targets_win() {
        assert!(RainDrops::new(0.0, 3e-3, 0.5, 200.0, 0.0).is_none());
        assert!(RainDrops::new(10.0, 0.0, 0.5, 200.0, 0.0).is_none());
        assert!(RainDrops::new(10.0, 3e-3, 40.0, 200.0, 0.0).is_none());
        assert!(RainDrops::new(f64::NAN, 3e-3, 0.5, 200.0, 0.0).is_none());
        let rain = RainDrops::new(50.0, 3e-3, 0.5, 200.0, 0.0).unwrap_or_else(|| unreachable!());
        let strongest = (0..20_000u64).filter_map(|i| rain.strongest(30.0, 0.0, 3, i)).map(|d| d.power);
        let top = strongest.fold(0.0f64, f64::max);
        assert!(top > 0.0);
        assert!((0..20_000u64).all(|i| rain.strongest(30.0, 2.0 * top, 3, i).is_none()));
        // The same seed and beam give the same drop; another seed others.
        let a: Vec<_> = (0..2000u64).map(|i| rain.strongest(30.0, 0.0, 3, i)).collect();
        let b: Vec<_> = (0..2000u64).map(|i| rain.strongest(30.0, 0.0, 3, i)).collect();
        let c: Vec<_> = (0..2000u64).map(|i| rain.strongest(30.0, 0.0, 4, i)).collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }
}
