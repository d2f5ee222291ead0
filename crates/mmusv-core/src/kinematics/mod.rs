//! Vessel motion (paper eq. 1–3): spline routes travelled at a nominal speed, with wave-driven heave, roll
//! and pitch superimposed.
//!
//! Model: the perception-centric vessel motion model of the MMUSV-Sim paper (Li, Z., Ye, J., Tang, B., Zhang,
//! L., Zuo, K., Huang, S. & Gao, C., "MMUSV-Sim: A Perception-Oriented Simulation and Data-Generation Platform
//! for Multi-USV Cooperative Perception", submitted to the IEEE), §"Perception-Centric Vessel Motion Model",
//! eqs. 1–3; "the paper" below and in [`waves`] is that paper. With a [`WaveField`] ([`Fleet::with_sea`]) heave,
//! roll and pitch come instead from the hull's RAOs ([`crate::ocean::response`](mod@crate::ocean::response)).
//!
//! For vessel `v` at time `t ≥ 0` (seconds), with travelled distance `d = offset + u·t` mapped to an arc
//! length `s` and direction `σ ∈ {+1, −1, 0}` by [`Route::distance_to_arc`]:
//!
//! ```text
//! η_v(t) = [x, y, z_base + Δz, Δφ, Δθ, θ]
//! [x, y] = c(s),   θ = atan2(c'(s)) (+ π when σ = −1),   [Δz, Δφ, Δθ] from the wave model (see waves)
//! ```
//!
//! Angles are roll about x, pitch about y, yaw about z (R = Rz·Ry·Rx), radians; positions are metres in the
//! world frame (x east, y north, z up). The state is a pure function of the configuration, the seed and `t`.
//!
//! - [`spline`]: [`Route`] and [`EndBehaviour`].
//! - [`waves`]: [`WaveSetting`], size factor, base amplitudes and the seeded periodic functions `g(t)`.
//! - [`knots`]: a route's knots, points between which its heading turns by at most half a degree, nearly linearly.
//! - [`path_behind`]: how far back a vessel's path ran straight, and its straight pieces round the bends
//!   ([`WakePiece`]).
//! - [`transient`]: the physical response remembers the recent course: through a route's bends, stops and turns
//!   about the hull passes from one steady state to the next at the rate its roll's free oscillation decays.

pub mod knots;
pub mod path_behind;
pub mod spline;
pub mod transient;
pub mod waves;

pub use path_behind::WakePiece;

pub use spline::{wrap_angle, EndBehaviour, Route};
pub use waves::{mix_seed, BaseAmplitudes, PeriodicSignal, VesselDims, WaveSetting, WaveSignals};

use crate::error::{MmusvError, Result};
use crate::ocean::{Hull, WaveField};
use rayon::prelude::*;
use std::sync::Arc;

/// Checks that a simulation time is finite and ≥ 0; `field` names it in the [`MmusvError::InvalidInput`].
pub fn check_time(t: f64, field: &str) -> Result<()> {
    if t.is_finite() && t >= 0.0 {
        Ok(())
    } else {
        Err(MmusvError::input(field, format!("time must be finite and >= 0 s, got {t}")))
    }
}

/// Per-vessel motion settings other than the route and the wave signals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VesselParams {
    /// Nominal speed `u` along the route in m/s (finite, ≥ 0).
    pub speed_mps: f64,
    /// Distance along the route at `t = 0` in metres (finite, ≥ 0; at most the route length for `Stop`).
    pub start_offset_m: f64,
    /// Height of the vessel origin above the water surface at rest, `z_base`, in metres.
    pub z_base_m: f64,
    /// Bounding box used for the size factor `α_v`.
    pub dims: VesselDims,
    /// Base amplitudes `r_z`, `r_φ`, `r_θ`.
    pub amplitudes: BaseAmplitudes,
    /// Hull particulars for the physical response (used only when the fleet sails in a [`WaveField`]).
    pub hull: Hull,
}

/// Most poses (times × vessels) one [`Fleet::poses_at_times`] call returns: 2²⁶, 3 GiB of float64.
pub const MAX_POSES: usize = 1 << 26;

/// The reference USV hull: 5 m × 2.5 m, draft 0.45 m, Cb 0.45, GM 0.6 m, default roll gyradius and damping.
pub const REFERENCE_HULL: Hull = Hull {
    length_m: 5.0,
    beam_m: 2.5,
    draft_m: 0.45,
    block_coefficient: 0.45,
    gm_m: 0.6,
    roll_gyradius_m: crate::ocean::response::ROLL_GYRADIUS_RATIO * 2.5,
    roll_damping_ratio: crate::ocean::response::ROLL_DAMPING_RATIO,
};

impl Default for VesselParams {
    /// At rest at the route start, `z_base = 0`, reference USV size and amplitudes.
    fn default() -> Self {
        Self {
            speed_mps: 0.0,
            start_offset_m: 0.0,
            z_base_m: 0.0,
            dims: VesselDims::REFERENCE,
            amplitudes: BaseAmplitudes::default(),
            hull: REFERENCE_HULL,
        }
    }
}

/// The motion of one vessel: its route, speed, start offset, base height, size and wave signals.
#[derive(Debug, Clone)]
pub struct VesselMotion {
    route: Route,
    params: VesselParams,
    signals: WaveSignals,
    alpha: f64,
}

impl VesselMotion {
    /// Builds a vessel motion; errors are [`MmusvError::Config`] naming `speed_mps`, `start_offset_m`,
    /// `z_base_m`, `dims.*` or `amplitudes.*`.
    pub fn new(route: Route, params: VesselParams, signals: WaveSignals) -> Result<Self> {
        let p = &params;
        if !p.speed_mps.is_finite() || p.speed_mps < 0.0 {
            return Err(MmusvError::config("speed_mps", p.speed_mps, "must be a finite speed >= 0 m/s"));
        }
        if !p.start_offset_m.is_finite() || p.start_offset_m < 0.0 {
            return Err(MmusvError::config("start_offset_m", p.start_offset_m, "must be a finite distance >= 0 m"));
        }
        if route.end_behaviour() == EndBehaviour::Stop && p.start_offset_m > route.length() {
            return Err(MmusvError::config(
                "start_offset_m",
                p.start_offset_m,
                format!("must not exceed the route length {:.3} m when the vessel stops at the end", route.length()),
            ));
        }
        if !p.z_base_m.is_finite() {
            return Err(MmusvError::config("z_base_m", p.z_base_m, "must be a finite height in metres"));
        }
        p.dims.validate()?;
        p.amplitudes.validate()?;
        p.hull.validate()?;
        let alpha = p.dims.alpha();
        Ok(Self { route, params, signals, alpha })
    }

    /// The route.
    pub fn route(&self) -> &Route {
        &self.route
    }

    /// The motion settings.
    pub fn params(&self) -> &VesselParams {
        &self.params
    }

    /// The seeded periodic functions `g_z`, `g_φ`, `g_θ`.
    pub fn signals(&self) -> &WaveSignals {
        &self.signals
    }

    /// The size factor `α_v` of this vessel.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// Travelled distance `d = offset + u·t` in metres (before end handling).
    pub fn travelled_m(&self, t: f64) -> f64 {
        self.params.start_offset_m + self.params.speed_mps * t
    }

    /// Checks `t` ([`check_time`]) and that the distance travelled by then is finite (`offset + u·t` overflows
    /// for a huge speed and time, and the route has no place for an infinite distance); `field` names `t`.
    fn check_travel(&self, t: f64, field: &str) -> Result<()> {
        check_time(t, field)?;
        if self.travelled_m(t).is_finite() {
            Ok(())
        } else {
            Err(MmusvError::input(
                field,
                format!(
                    "at {t} s the distance travelled, start_offset_m + speed_mps · t = {} + {} · {t} m, overflows",
                    self.params.start_offset_m, self.params.speed_mps
                ),
            ))
        }
    }

    /// `[Δz (m), Δφ (rad), Δθ (rad)] = S_wave · α_v · [r_z g_z(t), r_φ g_φ(t), r_θ g_θ(t)]` (eq. 2).
    pub fn perturbation_at(&self, t: f64, wave: &WaveSetting) -> [f64; 3] {
        let k = wave.scale() * self.alpha;
        let (a, g) = (&self.params.amplitudes, &self.signals);
        [k * a.heave_m * g.heave.value(t), k * a.roll_rad * g.roll.value(t), k * a.pitch_rad * g.pitch.value(t)]
    }

    /// The pose `η = [x, y, z_base + Δz, Δφ, Δθ, θ]` at time `t` (eq. 3); `t` must be finite and ≥ 0, and the
    /// distance travelled by then, `offset + u·t`, finite (errors name `t`).
    /// Yaw `θ` is in `[-π, π]`; travelling backwards on a ping-pong route it is the route heading + π.
    pub fn pose_at(&self, t: f64, wave: &WaveSetting) -> Result<[f64; 6]> {
        self.check_travel(t, "t")?;
        Ok(self.pose_unchecked(t, wave, None))
    }

    /// The pose with the physical response to `sea` (heave, roll, pitch through the hull's RAOs at the vessel's
    /// position, heading and velocity, remembering its recent course: [`transient`]) instead of the paper's
    /// perturbation. A [`Fleet`] in a sea keeps each route's steady states from call to call; this works them out
    /// afresh each time.
    pub fn pose_in_sea(&self, t: f64, sea: &WaveField) -> Result<[f64; 6]> {
        self.check_travel(t, "t")?;
        Ok(self.pose_unchecked(t, &WaveSetting::W0, Some((sea, None))))
    }

    /// World-frame linear velocity `[vx, vy, vz]` in m/s at time `t`: `u·σ·tangent(s)` horizontally (zero at
    /// rest at the end of a `Stop` route) and `dΔz/dt` vertically (in a sea: the derivative of the heave the pose
    /// gives, bends and route events included, by central differences of 0.1 ms).
    pub fn velocity_at(&self, t: f64, wave: &WaveSetting) -> Result<[f64; 3]> {
        self.check_travel(t, "t")?;
        Ok(self.velocity_unchecked(t, wave, None))
    }

    fn pose_unchecked(&self, t: f64, wave: &WaveSetting, sea: Option<Sea<'_>>) -> [f64; 6] {
        let (s, sign) = self.route.distance_to_arc(self.travelled_m(t));
        let [x, y] = self.route.position(s);
        let yaw = self.route.heading(s, sign);
        let [dz, roll, pitch] = match sea {
            None => self.perturbation_at(t, wave),
            Some((field, memo)) => transient::remembered_response(field, &self.route, &self.params, [x, y], t, memo),
        };
        [x, y, self.params.z_base_m + dz, roll, pitch, yaw]
    }

    /// World-frame horizontal velocity at arc length `s` travelled in direction `sign`.
    fn horizontal_velocity(&self, s: f64, sign: f64) -> [f64; 2] {
        self.route.velocity(s, sign, self.params.speed_mps)
    }

    fn velocity_unchecked(&self, t: f64, wave: &WaveSetting, sea: Option<Sea<'_>>) -> [f64; 3] {
        let (s, sign) = self.route.distance_to_arc(self.travelled_m(t));
        let [vx, vy] = self.horizontal_velocity(s, sign);
        let vz = match sea {
            None => wave.scale() * self.alpha * self.params.amplitudes.heave_m * self.signals.heave.derivative(t),
            Some(_) => {
                // The heave's own derivative along the path: the response changes with the heading in a bend and
                // through a route event's transient, besides its waves' phases (Re(a H (−iω_e) e^{iψ}) alone was
                // up to 1.4 m/s off in a 16 m bend at 9 m/s). Central differences, one-sided (second order) in the
                // first step; the truncation error is of order δ² ω³ a, under 1e-6 m/s.
                let z = |t: f64| self.pose_unchecked(t, wave, sea)[2];
                if t >= HEAVE_RATE_STEP_S {
                    (z(t + HEAVE_RATE_STEP_S) - z(t - HEAVE_RATE_STEP_S)) / (2.0 * HEAVE_RATE_STEP_S)
                } else {
                    (-3.0 * z(t) + 4.0 * z(t + HEAVE_RATE_STEP_S) - z(t + 2.0 * HEAVE_RATE_STEP_S))
                        / (2.0 * HEAVE_RATE_STEP_S)
                }
            }
        };
        [vx, vy, vz]
    }
}

/// A wave field and, where a fleet keeps them, the vessel's route knots' steady states in it.
type Sea<'a> = (&'a WaveField, Option<&'a transient::KnotGains>);

/// The time step (s) of the heave rate's differences in a sea ([`VesselMotion::velocity_at`]).
const HEAVE_RATE_STEP_S: f64 = 1e-4;

/// All vessels of a scenario under one wave setting: the paper's perturbation, or, with a sea
/// ([`Fleet::with_sea`]), each hull's physical response to that wave field.
#[derive(Debug, Clone)]
pub struct Fleet {
    vessels: Vec<VesselMotion>,
    wave: WaveSetting,
    sea: Option<Arc<WaveField>>,
    /// Per vessel, its route knots' steady states in `sea` (filled as the poses ask for them).
    memos: Vec<Arc<transient::KnotGains>>,
}

impl Fleet {
    /// A fleet of `vessels` (index order is kept in every output) under `wave`, moved by the paper's formula.
    pub fn new(vessels: Vec<VesselMotion>, wave: WaveSetting) -> Self {
        Self { vessels, wave, sea: None, memos: Vec::new() }
    }

    /// The same fleet moved physically by `sea`: heave, roll and pitch from each hull's RAOs
    /// ([`crate::ocean::response`](mod@crate::ocean::response)) instead of the paper's perturbation.
    pub fn with_sea(mut self, sea: Arc<WaveField>) -> Self {
        self.sea = Some(sea);
        self.memos = self.vessels.iter().map(|_| Arc::new(transient::KnotGains::new())).collect();
        self
    }

    /// The wave field the fleet sails in, when physical.
    pub fn sea(&self) -> Option<&WaveField> {
        self.sea.as_deref()
    }

    /// Vessel `v`'s sea: the field and its memo of the route's steady states.
    fn sea_of(&self, v: usize) -> Option<Sea<'_>> {
        self.sea.as_deref().map(|f| (f, self.memos.get(v).map(Arc::as_ref)))
    }

    /// The vessels, in order.
    pub fn vessels(&self) -> &[VesselMotion] {
        &self.vessels
    }

    /// Number of vessels.
    pub fn len(&self) -> usize {
        self.vessels.len()
    }

    /// Whether the fleet has no vessel.
    pub fn is_empty(&self) -> bool {
        self.vessels.is_empty()
    }

    /// `VesselMotion::check_travel` of every vessel at `t`.
    fn check_travel(&self, t: f64, field: &str) -> Result<()> {
        check_time(t, field)?;
        self.vessels.iter().try_for_each(|v| v.check_travel(t, field))
    }

    /// The scene wave setting.
    pub fn wave(&self) -> WaveSetting {
        self.wave
    }

    /// Changes the scene wave setting.
    pub fn set_wave(&mut self, wave: WaveSetting) {
        self.wave = wave;
    }

    /// Poses `η = [x, y, z, roll, pitch, yaw]` of every vessel at time `t` (finite, ≥ 0), in vessel order.
    pub fn poses_at(&self, t: f64) -> Result<Vec<[f64; 6]>> {
        self.check_travel(t, "t")?;
        Ok(self.vessels.iter().enumerate().map(|(i, v)| v.pose_unchecked(t, &self.wave, self.sea_of(i))).collect())
    }

    /// World-frame linear velocities `[vx, vy, vz]` (m/s) of every vessel at time `t`, in vessel order.
    pub fn velocities_at(&self, t: f64) -> Result<Vec<[f64; 3]>> {
        self.check_travel(t, "t")?;
        Ok(self.vessels.iter().enumerate().map(|(i, v)| v.velocity_unchecked(t, &self.wave, self.sea_of(i))).collect())
    }

    /// Poses at many times, flattened time-major: entry `k · len() + v` is vessel `v` at `times[k]`
    /// (a T×V×6 array). Every time must be finite and ≥ 0 (errors name `times[k]`); at most [`MAX_POSES`] poses
    /// (T·V) a call, checked before anything is allocated. Runs over rayon.
    pub fn poses_at_times(&self, times: &[f64]) -> Result<Vec<[f64; 6]>> {
        let nv = self.vessels.len();
        if times.len().saturating_mul(nv) > MAX_POSES {
            return Err(MmusvError::input(
                "times",
                format!(
                    "{} times × {nv} vessels would be {} poses; at most {MAX_POSES} a call: ask for fewer times at \
                     once",
                    times.len(),
                    times.len().saturating_mul(nv)
                ),
            ));
        }
        for (k, &t) in times.iter().enumerate() {
            self.check_travel(t, &format!("times[{k}]"))?;
        }
        let mut out = vec![[0.0; 6]; times.len() * nv];
        if nv == 0 {
            return Ok(out);
        }
        out.par_chunks_mut(nv).zip(times.par_iter()).for_each(|(row, &t)| {
            for (i, (slot, v)) in row.iter_mut().zip(&self.vessels).enumerate() {
                *slot = v.pose_unchecked(t, &self.wave, self.sea_of(i));
            }
        });
        Ok(out)
    }
}

#[cfg(test)]
mod tests;
