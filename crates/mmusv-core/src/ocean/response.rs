//! Vessel heave, roll and pitch in the wave field, through closed-form response amplitude operators (RAOs).
//!
//! Models and sources:
//! - **Heave and pitch**: Jensen, J. J., Mansour, A. E. & Olsen, A. S. (2004), "Estimation of ship motions using
//!   closed-form expressions", Ocean Engineering 31, 61–85: a homogeneously loaded box of length `L`, draft `T`
//!   and breadth `B = Cb·B₀` (block coefficient times beam; in the damping terms at most `2π T`,
//!   [`MAX_DAMPING_BREADTH_PER_DRAFT`]), at speed `U` and heading `β` to the waves
//!   (β = 0 following, π head seas). With `k = ω²/g`, `α = ω_e/ω = 1 − Fn·√(kL)·cos β`, `k_e = |k cos β|`,
//!   `κ = exp(−k_e T)`:
//!
//!   ```text
//!   A = 2 sin(k B α²/2) exp(−k T α²),          f = √((1 − kT)² + (A²/(k B α³))²)
//!   F = κ f sin(k_e L/2)/(k_e L/2),             G = κ f 24/((k_e L)² L) [sin(k_e L/2) − (k_e L/2) cos(k_e L/2)]
//!   η = 1/√((1 − 2kTα²)² + (A²/(k B α²))²)      heave = η F (m per m of wave amplitude), pitch = η G (rad per m)
//!   ```
//!
//!   Phases: the single-degree-of-freedom form `1/((1 − 2kTα²) − i·sgn(ω_e)·A²/(kBα²))` (natural frequency
//!   `√(g/2T)`, as in the paper) carries the lag; pitch follows the along-ship wave slope (bow up on a rising
//!   face ahead).
//! - **Encounter frequency**: `ω_e = ω − k·(U_x cos θ + U_y sin θ)` for a wave travelling towards `θ` and a hull
//!   moving with world velocity `U` (e.g. Lewis, E. V. (ed.) (1989), "Principles of Naval Architecture" vol. III,
//!   SNAME, ch. 8).
//! - **Roll**: a linear one-degree-of-freedom oscillator driven by the effective transverse wave slope (e.g.
//!   Lloyd, A. R. J. M. (1989), "Seakeeping: Ship Behaviour in Rough Weather", ch. 10; the same model underlies
//!   the IMO 2008 Intact Stability Code weather criterion):
//!
//!   ```text
//!   roll = i k sin β · e^{−kT} · R(k|sin β| B₀/2) / (1 − Λ² − i·sgn(ω_e)·2ζΛ),   Λ = |ω_e|/ω_φ
//!   R(σ) = 3(sin σ − σ cos σ)/σ³   (Froude–Krylov slope of a box of beam B₀, the transverse twin of JMO's G)
//!   ω_φ = √(g GM)/k_xx,  k_xx = 0.39 B₀ (roll radius of gyration incl. added inertia, 0.35–0.40 B₀ typical;
//!   IMO IS Code 2008 §2.3: T_φ = 2 C B/√GM, i.e. k_xx ≈ C B (2π/√g ≈ 2), with
//!   C = 0.373 + 0.023 B/d − 0.043 L/100: 0.37–0.40 for ships of usual proportions, 0.35 for the catalogue's
//!   190 m bulk carrier and 0.41 for its 32 m tug; for a 5 m USV (B/d ≈ 7, outside the ships the empirical
//!   formula was made for) it gives 0.53, a roll period 36 % longer than 0.39 B₀'s), ζ = 0.10 (equivalent
//!   linear roll damping ratio, 0.05–0.2 typical: ITTC Recommended Procedure 7.5-02-07-04.5, "Numerical
//!   estimation of roll damping").
//!   ```
//!
//! Every RAO is a complex number `H` per metre of wave amplitude: a component `ζ = a cos ψ` at the hull's
//! origin gives the response `Re(a H e^{iψ})`. Conventions: heave m (z up); roll rad about the body x axis
//! (positive lifts the port side); pitch rad about body y (positive puts the bow down), as in the kinematics.
//! In the long-wave limit the hull follows the surface: heave → ζ, roll → ∂ζ/∂y_body, pitch → −∂ζ/∂x_body.

use super::field::{SeaSpec, WaveField};
use super::spectrum::{simpson, CosTwoS, Jonswap, GRAVITY};
use crate::error::{MmusvError, Result};
use std::f64::consts::{PI, TAU};

/// Default roll radius of gyration as a fraction of the beam.
pub const ROLL_GYRADIUS_RATIO: f64 = 0.39;
/// Default equivalent linear roll damping ratio ζ.
pub const ROLL_DAMPING_RATIO: f64 = 0.10;

/// The most breadth per draft JMO's heave and pitch damping takes, `2π`: at heave resonance (`2kTα² = 1`) the
/// damping term `A²/(kBα²)` has `sin(kBα²/2) = sin(B/4T)`, which rises with `B/T` up to `2π` and then falls, to 0 at
/// `4π`: an artefact of the box section's sine far outside the ships the closed form was built and checked for
/// (Jensen et al.'s hulls have `B/T` of 2–4; the widest of the library's, the 60 m deck barge, 6.2). A hull wider
/// for its draft (the 22 m hovercraft's 26: its heave resonance 92 times the wave, where every other asset's is at most
/// 4.5) takes `B = 2π T` in the damping terms (its peak then 2.1). The RAOs of hulls within it are unchanged.
pub const MAX_DAMPING_BREADTH_PER_DRAFT: f64 = TAU;

/// Main particulars of a hull: what the closed-form RAOs need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hull {
    /// Length `L` (m).
    pub length_m: f64,
    /// Beam `B₀` (m).
    pub beam_m: f64,
    /// Draft `T` (m).
    pub draft_m: f64,
    /// Block coefficient `Cb` in [0.2, 1].
    pub block_coefficient: f64,
    /// Transverse metacentric height `GM` (m), > 0.
    pub gm_m: f64,
    /// Roll radius of gyration `k_xx` (m), including added inertia.
    pub roll_gyradius_m: f64,
    /// Equivalent linear roll damping ratio ζ in [0.005, 1].
    pub roll_damping_ratio: f64,
}

/// Complex RAOs `(re, im)` of one wave component, per metre of wave amplitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rao {
    /// Heave (m/m).
    pub heave: [f64; 2],
    /// Roll (rad/m).
    pub roll: [f64; 2],
    /// Pitch (rad/m).
    pub pitch: [f64; 2],
}

fn cmul(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0]]
}

fn cinv(a: [f64; 2]) -> [f64; 2] {
    let d = a[0] * a[0] + a[1] * a[1];
    [a[0] / d, -a[1] / d]
}

/// `3(sin σ − σ cos σ)/σ³` (→ 1 as σ → 0, by its series below 1e-3).
fn box_slope_factor(s: f64) -> f64 {
    if s < 1e-3 {
        1.0 - s * s / 10.0
    } else {
        3.0 * (s.sin() - s * s.cos()) / (s * s * s)
    }
}

/// `sin σ / σ` (→ 1 as σ → 0).
fn sinc(s: f64) -> f64 {
    if s < 1e-4 {
        1.0 - s * s / 6.0
    } else {
        s.sin() / s
    }
}

impl Hull {
    /// A hull with the default roll gyradius (0.39 B) and damping (0.10). Errors as [`Hull::validate`].
    pub fn new(length_m: f64, beam_m: f64, draft_m: f64, block_coefficient: f64, gm_m: f64) -> Result<Self> {
        let h = Self {
            length_m,
            beam_m,
            draft_m,
            block_coefficient,
            gm_m,
            roll_gyradius_m: ROLL_GYRADIUS_RATIO * beam_m,
            roll_damping_ratio: ROLL_DAMPING_RATIO,
        };
        h.validate()?;
        Ok(h)
    }

    /// Checks every field; errors are [`MmusvError::Config`] naming `hull.<field>` and the allowed range.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("hull.length_m", self.length_m),
            ("hull.beam_m", self.beam_m),
            ("hull.draft_m", self.draft_m),
            ("hull.gm_m", self.gm_m),
            ("hull.roll_gyradius_m", self.roll_gyradius_m),
        ] {
            if !v.is_finite() || v <= 0.0 {
                return Err(MmusvError::config(name, v, "must be a finite length > 0 m"));
            }
        }
        if !self.block_coefficient.is_finite() || !(0.2..=1.0).contains(&self.block_coefficient) {
            return Err(MmusvError::config("hull.block_coefficient", self.block_coefficient, "must be in [0.2, 1]"));
        }
        if !self.roll_damping_ratio.is_finite() || !(0.005..=1.0).contains(&self.roll_damping_ratio) {
            return Err(MmusvError::config(
                "hull.roll_damping_ratio",
                self.roll_damping_ratio,
                "must be a damping ratio in [0.005, 1]",
            ));
        }
        Ok(())
    }

    /// Natural roll frequency `ω_φ = √(g GM)/k_xx` (rad/s).
    pub fn roll_natural_frequency(&self) -> f64 {
        (GRAVITY * self.gm_m).sqrt() / self.roll_gyradius_m
    }

    /// Natural roll period `T_φ = 2π k_xx/√(g GM)` (s).
    pub fn roll_natural_period(&self) -> f64 {
        TAU / self.roll_natural_frequency()
    }

    /// Natural heave and pitch frequency of the JMO box, `√(g/(2T))` (rad/s).
    pub fn heave_natural_frequency(&self) -> f64 {
        (GRAVITY / (2.0 * self.draft_m)).sqrt()
    }

    /// The RAOs for a wave of absolute frequency `omega` (rad/s, > 0) met at heading `beta` (rad, wave travel
    /// direction minus hull heading: 0 following, π head seas) with encounter frequency `omega_e` (rad/s, may be
    /// ≤ 0 when the hull overtakes the waves).
    pub fn rao(&self, omega: f64, beta: f64, omega_e: f64) -> Rao {
        let k = omega * omega / GRAVITY;
        let (sb, cb) = beta.sin_cos();
        let (l, t) = (self.length_m, self.draft_m);
        let b = (self.block_coefficient * self.beam_m).min(MAX_DAMPING_BREADTH_PER_DRAFT * t);
        let alpha = (omega_e / omega).abs();
        let a2 = alpha * alpha;
        let ke = (k * cb).abs();
        let kappa = (-ke * t).exp();
        let damp = 2.0 * (0.5 * k * b * a2).sin() * (-k * t * a2).exp();
        // A²/(kBα²) and A²/(kBα³); both → 0 with α (A ≈ kBα²).
        let (d2, d3) = if alpha > 1e-9 {
            let q = damp * damp / (k * b * a2);
            (q, q / alpha)
        } else {
            (0.0, 0.0)
        };
        let f = ((1.0 - k * t).powi(2) + d3 * d3).sqrt();
        let sigma = 0.5 * ke * l;
        let big_f = kappa * f * sinc(sigma);
        let big_g = kappa * f * ke * box_slope_factor(sigma);
        let sgn = if omega_e < 0.0 { -1.0 } else { 1.0 };
        let eta = cinv([1.0 - 2.0 * k * t * a2, -sgn * d2]);
        let heave = [big_f * eta[0], big_f * eta[1]];
        let pitch = cmul([0.0, -cb.signum() * big_g], eta);
        // Roll: 1-DOF oscillator on the effective transverse slope.
        let lam = omega_e.abs() / self.roll_natural_frequency();
        let osc = cinv([1.0 - lam * lam, -sgn * 2.0 * self.roll_damping_ratio * lam]);
        let slope = k * sb * (-k * t).exp() * box_slope_factor(0.5 * (k * sb).abs() * self.beam_m);
        let roll = cmul([0.0, slope], osc);
        Rao { heave, roll, pitch }
    }
}

/// Encounter frequency `ω_e = ω − (kx·vx + ky·vy)` (rad/s) of a wave with wave vector `(kx, ky)` for a hull moving
/// with world velocity `(vx, vy)` (m/s).
pub fn encounter_frequency(omega: f64, kx: f64, ky: f64, vx: f64, vy: f64) -> f64 {
    omega - (kx * vx + ky * vy)
}

/// `[heave (m), roll (rad), pitch (rad)]` and their rates `[m/s, rad/s, rad/s]` of a hull at world position
/// `(x, y)`, heading `yaw` (rad) and world velocity `(vx, vy)` at time `t`: the sum over the field's
/// components of `Re(a H e^{iψ})` with `H` at each component's encounter frequency; rates are
/// `Re(a H (−iω_e) e^{iψ})` (the hull's own position change is the Doppler term).
#[allow(clippy::too_many_arguments)]
pub fn response(field: &WaveField, hull: &Hull, x: f64, y: f64, yaw: f64, vx: f64, vy: f64, t: f64) -> [[f64; 3]; 2] {
    let mut out = [[0.0; 3]; 2];
    for c in field.components() {
        let we = encounter_frequency(c.omega_rad_s, c.kx, c.ky, vx, vy);
        let h = hull.rao(c.omega_rad_s, c.direction_rad - yaw, we);
        let (s, co) = c.phase_at(x, y, t).sin_cos();
        let e = [c.amplitude_m * co, c.amplitude_m * s];
        for (i, hv) in [h.heave, h.roll, h.pitch].into_iter().enumerate() {
            let z = cmul(hv, e);
            out[0][i] += z[0];
            // (−iω_e)·z = (ω_e z_im, −ω_e z_re)
            out[1][i] += we * z[1];
        }
    }
    out
}

/// The fastest speed (m/s) [`response_variance`] takes: far past any vessel, short of where its sums overflow.
pub const MAX_SPEED_MPS: f64 = 1e6;

/// The spectral prediction of the response variances `[heave m², roll rad², pitch rad²]` of a hull at heading
/// `yaw` and speed `speed_mps` (along the heading) in the sea `spec`:
/// `∫∫ |H(ω, θ − yaw, ω_e)|² S(ω) D(θ − θ̄) dω dθ`, by Simpson in ln ω over `[0.1, 40]·ωp` (4000 intervals)
/// and the trapezoid rule in θ (720 steps, exact for periodic integrands to high order).
pub fn response_variance(hull: &Hull, spec: &SeaSpec, yaw: f64, speed_mps: f64) -> Result<[f64; 3]> {
    spec.validate()?;
    hull.validate()?;
    // Past 1e6 m/s the encounter frequencies overflow (1e200 m/s gave NaN variances); a heading that is not finite
    // gave NaN too.
    if !(0.0..=MAX_SPEED_MPS).contains(&speed_mps) {
        return Err(MmusvError::config("speed_mps", speed_mps, "must be a speed within [0, 1e6] m/s"));
    }
    if !yaw.is_finite() {
        return Err(MmusvError::config("yaw", yaw, "must be a finite heading in radians"));
    }
    if spec.hs == 0.0 {
        return Ok([0.0; 3]);
    }
    let s = Jonswap::new(spec.hs, spec.tp, spec.gamma)?;
    let d = CosTwoS::new(spec.spread_s)?;
    let nth = 720;
    let dth = TAU / nth as f64;
    let (vx, vy) = (speed_mps * yaw.cos(), speed_mps * yaw.sin());
    let wp = s.omega_p();
    let mut out = [0.0; 3];
    for (axis, slot) in out.iter_mut().enumerate() {
        *slot = simpson(
            |lw| {
                let w = lw.exp();
                let k = w * w / GRAVITY;
                let mut acc = 0.0;
                for j in 0..nth {
                    let delta = -PI + dth * j as f64;
                    let theta = spec.direction_rad + delta;
                    let we = encounter_frequency(w, k * theta.cos(), k * theta.sin(), vx, vy);
                    let h = hull.rao(w, theta - yaw, we);
                    let hv = [h.heave, h.roll, h.pitch][axis];
                    acc += (hv[0] * hv[0] + hv[1] * hv[1]) * d.density(delta) * dth;
                }
                acc * s.density(w) * w
            },
            (0.1 * wp).ln(),
            (40.0 * wp).ln(),
            4000,
        );
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    fn ok<T>(r: Result<T>) -> T {
        r.unwrap_or_else(|e| unreachable!("{e}"))
    }

    /// The three hulls of issue #29: a 5 m USV, a 32 m tug and a 190 m bulk carrier.
    fn hulls() -> [(&'static str, Hull, f64); 3] {
        [
            ("usv_5m", ok(Hull::new(5.0, 2.5, 0.45, 0.45, 0.6)), 3.0),
            ("tug_32m", ok(Hull::new(32.0, 11.0, 4.5, 0.52, 1.1)), 5.0),
            ("bulk_190m", ok(Hull::new(190.0, 32.0, 12.0, 0.83, 2.6)), 6.0),
        ]
    }

    fn abs(z: [f64; 2]) -> f64 {
        z[0].hypot(z[1])
    }

    /// The amplitudes written out as in Jensen et al. (2004), eq. for η, F, G (and the roll oscillator), term by
    /// term from the paper's variables (Fn, α from Froude number, k_e), independently of `Hull::rao`.
    fn closed_form(h: &Hull, omega: f64, beta: f64, u: f64) -> [f64; 3] {
        let g = GRAVITY;
        let k = omega * omega / g;
        let fn_ = u / (g * h.length_m).sqrt();
        let alpha = 1.0 - fn_ * (k * h.length_m).sqrt() * beta.cos();
        let ke = (k * beta.cos()).abs();
        let (l, b, t) = (h.length_m, h.block_coefficient * h.beam_m, h.draft_m);
        let kappa = (-ke * t).exp();
        let a = 2.0 * (k * b * alpha * alpha / 2.0).sin() * (-k * t * alpha * alpha).exp();
        let f = ((1.0 - k * t).powi(2) + (a * a / (k * b * alpha.abs().powi(3))).powi(2)).sqrt();
        let ff = kappa * f * 2.0 / (ke * l) * (ke * l / 2.0).sin();
        let gg =
            kappa * f * 24.0 / ((ke * l).powi(2) * l) * ((ke * l / 2.0).sin() - ke * l / 2.0 * (ke * l / 2.0).cos());
        let eta =
            1.0 / ((1.0 - 2.0 * k * t * alpha * alpha).powi(2) + (a * a / (k * b * alpha * alpha)).powi(2)).sqrt();
        let we = alpha * omega;
        let wn = (g * h.gm_m).sqrt() / (0.39 * h.beam_m);
        let lam = we.abs() / wn;
        let sy = k * beta.sin().abs() * h.beam_m / 2.0;
        let r = 3.0 * (sy.sin() - sy * sy.cos()) / sy.powi(3);
        let roll =
            k * beta.sin().abs() * (-k * t).exp() * r.abs() / ((1.0 - lam * lam).powi(2) + (0.2 * lam).powi(2)).sqrt();
        [eta * ff.abs(), roll, eta * gg.abs()]
    }

    #[test]
    fn raos_match_the_closed_form_values() {
        for (name, h, u) in hulls() {
            for beta_deg in [20.0, 60.0, 100.0, 135.0, 170.0] {
                let beta = f64::to_radians(beta_deg);
                for omega in [0.3, 0.5, 0.8, 1.2, 1.8, 2.6] {
                    let k = omega * omega / GRAVITY;
                    let we = omega - k * u * beta.cos();
                    let r = h.rao(omega, beta, we);
                    let want = closed_form(&h, omega, beta, u);
                    for (axis, got) in [abs(r.heave), abs(r.roll), abs(r.pitch)].into_iter().enumerate() {
                        let tol = 1e-9 * want[axis].max(1e-6);
                        assert!(
                            (got - want[axis]).abs() <= tol,
                            "{name} β={beta_deg} ω={omega} axis {axis}: {got} vs {}",
                            want[axis]
                        );
                    }
                }
            }
        }
    }

    /// The heave resonance's damping term never falls as a hull widens for its draft: up to `B = 2π T` the RAOs are
    /// the closed form's, past it those of a hull `2π T` wide. In beam seas at rest at heave resonance (`κ = 1`,
    /// `sinc = 1`, `α = 1`, `2kT = 1`) the heave is `√(¼ + d²)/d` per metre of wave, `d = A²/(kB)`: 46 for the
    /// hovercraft's `B/T` of 26 as the closed form has it, 1.5 with the breadth capped.
    #[test]
    fn heave_damping_takes_at_most_two_pi_drafts_of_breadth() {
        let (draft, cb) = (0.25, 0.6);
        let hull = |beam: f64| ok(Hull::new(22.0, beam, draft, cb, 1.0));
        // The beam whose breadth Cb·B₀ is 2π T.
        let cap = TAU * draft / cb;
        // Within: the closed form itself, written out independently (`closed_form`).
        let within = hull(0.9 * cap);
        for (omega, beta) in [(1.0, 0.3), (3.0, 2.0), (4.4, PI), (6.0, 1.0)] {
            let k: f64 = omega * omega / GRAVITY;
            let r = within.rao(omega, beta, omega - k * 5.0 * beta.cos());
            let want = closed_form(&within, omega, beta, 5.0);
            assert!((abs(r.heave) - want[0]).abs() <= 1e-9 * want[0].max(1e-6), "{omega} {beta}");
        }
        // Past it: the hull 2π T wide, to the bit, however wide (the roll keeps its own beam).
        let omega = (GRAVITY / (2.0 * draft)).sqrt();
        let at = hull(cap).rao(omega, PI / 2.0, omega);
        for beam in [12.0, 11.0, 30.0] {
            let r = hull(beam).rao(omega, PI / 2.0, omega);
            assert_eq!((r.heave, r.pitch), (at.heave, at.pitch), "{beam}");
        }
        // kB = k · 2π T = π there, so A = 2 sin(π/2) e^{−kT} = 2 e^{−1/2} and d = A²/π.
        let d = (2.0 * (-0.5_f64).exp()).powi(2) / PI;
        let want = (0.25 + d * d).sqrt() / d;
        assert!((abs(at.heave) - want).abs() < 1e-9 * want, "{:?} against {want}", at.heave);
        assert!(abs(hull(11.0).rao(omega, PI / 2.0, omega).heave) < 1.6);
    }

    #[test]
    fn long_waves_are_followed_and_roll_resonates() {
        let h = hulls()[1].1;
        // Long waves at rest: heave → 1, roll → k sin β, pitch → k cos β (wave slopes).
        let (omega, beta) = (0.02, 0.7);
        let k = omega * omega / GRAVITY;
        let r = h.rao(omega, beta, omega);
        assert!((abs(r.heave) - 1.0).abs() < 1e-3);
        assert!((abs(r.roll) / (k * beta.sin()) - 1.0).abs() < 1e-3);
        assert!((abs(r.pitch) / (k * beta.cos()) - 1.0).abs() < 1e-3);
        // Beam seas at the roll natural frequency: amplitude = slope·e^{−kT}·R / (2ζ).
        let wn = h.roll_natural_frequency();
        let r = h.rao(wn, PI / 2.0, wn);
        let k = wn * wn / GRAVITY;
        let slope = k * (-k * h.draft_m).exp() * box_slope_factor(0.5 * k * h.beam_m);
        assert!((abs(r.roll) - slope / (2.0 * ROLL_DAMPING_RATIO)).abs() < 1e-12);
        assert!((h.roll_natural_period() - TAU * 0.39 * 11.0 / (GRAVITY * 1.1).sqrt()).abs() < 1e-12);
        // Sign conventions: a long wave whose face rises ahead (towards the bow) puts the bow up (pitch < 0).
        let hd = ok(Hull::new(50.0, 10.0, 3.0, 0.6, 1.0));
        let field_like = |psi: f64, r: Rao| cmul(r.pitch, [psi.cos(), psi.sin()])[0];
        // ζ = cos ψ with ψ = k x − ωt: at ψ = −π/2 the surface rises with x (slope k > 0).
        let r = hd.rao(0.1, 0.0, 0.1);
        assert!(field_like(-PI / 2.0, r) < 0.0);
    }

    #[test]
    fn simulated_rms_matches_the_spectral_prediction() {
        let seas = [
            ("usv_5m", SeaSpec { hs: 1.5, tp: 6.0, gamma: 3.3, direction_rad: 0.3, spread_s: 10.0 }),
            ("tug_32m", SeaSpec { hs: 2.5, tp: 8.0, gamma: 3.3, direction_rad: 0.3, spread_s: 10.0 }),
            ("bulk_190m", SeaSpec { hs: 3.5, tp: 10.0, gamma: 3.3, direction_rad: 0.3, spread_s: 10.0 }),
        ];
        for ((name, hull, u), (_, sea)) in hulls().into_iter().zip(seas) {
            for (yaw, speed) in [(0.3 + 2.4, u), (0.3 + 1.2, 0.0)] {
                let field = ok(WaveField::new(&sea, 1));
                let want = ok(response_variance(&hull, &sea, yaw, speed));
                let (vx, vy) = (speed * f64::cos(yaw), speed * f64::sin(yaw));
                let (dt, n) = (0.5, 12_000);
                let acc = (0..n)
                    .into_par_iter()
                    .map(|i| {
                        let t = i as f64 * dt;
                        let r = response(&field, &hull, vx * t, vy * t, yaw, vx, vy, t)[0];
                        [r[0] * r[0], r[1] * r[1], r[2] * r[2]]
                    })
                    .reduce(|| [0.0; 3], |a, b| [a[0] + b[0], a[1] + b[1], a[2] + b[2]]);
                for a in 0..3 {
                    let (sim, pred) = ((acc[a] / n as f64).sqrt(), want[a].sqrt());
                    eprintln!(
                        "{name} yaw {yaw:.2} U {speed}: axis {a} simulated RMS {sim:.5}, spectral {pred:.5} ({:+.1} %)",
                        100.0 * (sim / pred - 1.0)
                    );
                    assert!((sim / pred - 1.0).abs() < 0.10, "{name} axis {a}: {sim} vs {pred}");
                }
            }
        }
    }

    #[test]
    fn rates_are_time_derivatives() {
        let sea = SeaSpec { hs: 2.0, tp: 7.0, gamma: 3.3, direction_rad: 1.0, spread_s: 5.0 };
        let field = ok(WaveField::new(&sea, 3));
        let hull = hulls()[0].1;
        let (vx, vy, h) = (2.0, -1.0, 1e-5);
        for i in 0..20 {
            let t = 3.7 * i as f64;
            let at = |t: f64| response(&field, &hull, 10.0 + vx * t, -4.0 + vy * t, 0.4, vx, vy, t)[0];
            let (a, b) = (at(t - h), at(t + h));
            let r = response(&field, &hull, 10.0 + vx * t, -4.0 + vy * t, 0.4, vx, vy, t)[1];
            for k in 0..3 {
                assert!(((b[k] - a[k]) / (2.0 * h) - r[k]).abs() < 1e-5 * (1.0 + r[k].abs()));
            }
        }
    }

    /// The module docs' sign conventions, against the pose the kinematics builds (`RigidPose::from_xyz_rpy`): a
    /// long beam wave whose surface rises towards port gives roll ≈ ∂ζ/∂y_body > 0, and a positive roll lifts the
    /// port side (+y); a positive pitch puts the bow (+x) down.
    #[test]
    fn roll_and_pitch_signs_match_the_pose() {
        use crate::geometry::RigidPose;
        use parry3d::math::Vec3;
        let hd = ok(Hull::new(50.0, 10.0, 3.0, 0.6, 1.0));
        let omega = 0.05;
        let k = omega * omega / GRAVITY;
        // Waves travelling towards body +y (β = π/2); at ψ = −π/2 the surface `cos ψ` rises with y_body.
        let r = hd.rao(omega, PI / 2.0, omega);
        let psi: f64 = -PI / 2.0;
        let roll = cmul(r.roll, [psi.cos(), psi.sin()])[0];
        // Within 1 %: the roll oscillator still adds 1/(1 − Λ²) ≈ 1.004 at Λ = ω/ω_φ ≈ 0.06.
        assert!((roll / k - 1.0).abs() < 1e-2, "roll {roll} vs the slope {k}");
        let port = RigidPose::from_xyz_rpy([0.0; 3], [roll, 0.0, 0.0]).transform_vector(Vec3::Y);
        assert!(port.z > 0.0);
        let bow = RigidPose::from_xyz_rpy([0.0; 3], [0.0, 0.1, 0.0]).transform_vector(Vec3::X);
        assert!(bow.z < 0.0);
    }

    #[test]
    fn bad_hulls_name_their_field() {
        assert!(
            matches!(Hull::new(0.0, 1.0, 1.0, 0.5, 1.0), Err(MmusvError::Config { field, .. }) if field == "hull.length_m")
        );
        assert!(
            matches!(Hull::new(5.0, 1.0, 1.0, 1.5, 1.0), Err(MmusvError::Config { field, .. }) if field == "hull.block_coefficient")
        );
        assert!(
            matches!(Hull::new(5.0, 1.0, 1.0, 0.5, -1.0), Err(MmusvError::Config { field, .. }) if field == "hull.gm_m")
        );
    }

    /// A heading that is not finite, or a speed past [`MAX_SPEED_MPS`], is refused by name: both gave NaN
    /// variances (a yaw of NaN or ∞; a speed of 1e200 m/s). The fastest speed allowed still gives finite ones.
    #[test]
    fn response_variance_refuses_what_it_cannot_sum() {
        let sea = SeaSpec { hs: 2.0, tp: 8.0, gamma: 3.3, direction_rad: 0.0, spread_s: 10.0 };
        let hull = ok(Hull::new(5.0, 2.5, 0.5, 0.5, 1.0));
        for (yaw, speed, field) in [
            (f64::NAN, 3.0, "yaw"),
            (f64::INFINITY, 3.0, "yaw"),
            (0.3, 1e200, "speed_mps"),
            (0.3, f64::NAN, "speed_mps"),
            (0.3, -1.0, "speed_mps"),
        ] {
            let got = response_variance(&hull, &sea, yaw, speed);
            assert!(
                matches!(&got, Err(MmusvError::Config { field: f, .. }) if f == field),
                "yaw {yaw}, speed {speed}: {got:?}"
            );
        }
        let fastest = ok(response_variance(&hull, &sea, 0.3, MAX_SPEED_MPS));
        assert!(fastest.iter().all(|v| v.is_finite() && *v >= 0.0), "{fastest:?}");
    }
}
