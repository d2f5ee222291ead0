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
//! - [`path_behind`]: how far back a vessel's path ran straight, and its straight pieces round the bends
//!   ([`WakePiece`]).
//! - [`transient`]: the physical response across a route's stop or turn about, from the steady state before to the
//!   one after.

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
    /// position, heading and velocity) instead of the paper's perturbation.
    pub fn pose_in_sea(&self, t: f64, sea: &WaveField) -> Result<[f64; 6]> {
        self.check_travel(t, "t")?;
        Ok(self.pose_unchecked(t, &WaveSetting::W0, Some(sea)))
    }

    /// World-frame linear velocity `[vx, vy, vz]` in m/s at time `t`: `u·σ·tangent(s)` horizontally (zero at
    /// rest at the end of a `Stop` route) and `dΔz/dt` vertically (in a sea: the derivative of the heave the pose
    /// gives, bends and route events included, by central differences of 0.1 ms).
    pub fn velocity_at(&self, t: f64, wave: &WaveSetting) -> Result<[f64; 3]> {
        self.check_travel(t, "t")?;
        Ok(self.velocity_unchecked(t, wave, None))
    }

    fn pose_unchecked(&self, t: f64, wave: &WaveSetting, sea: Option<&WaveField>) -> [f64; 6] {
        let (s, sign) = self.route.distance_to_arc(self.travelled_m(t));
        let [x, y] = self.route.position(s);
        let yaw = self.route.heading(s, sign);
        let [dz, roll, pitch] = match sea {
            None => self.perturbation_at(t, wave),
            Some(field) => {
                let v = self.horizontal_velocity(s, sign);
                transient::response_through_events(field, &self.route, &self.params, [x, y], yaw, v, t)
            }
        };
        [x, y, self.params.z_base_m + dz, roll, pitch, yaw]
    }

    /// World-frame horizontal velocity at arc length `s` travelled in direction `sign`.
    fn horizontal_velocity(&self, s: f64, sign: f64) -> [f64; 2] {
        self.route.velocity(s, sign, self.params.speed_mps)
    }

    fn velocity_unchecked(&self, t: f64, wave: &WaveSetting, sea: Option<&WaveField>) -> [f64; 3] {
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

/// The time step (s) of the heave rate's differences in a sea ([`VesselMotion::velocity_at`]).
const HEAVE_RATE_STEP_S: f64 = 1e-4;

/// All vessels of a scenario under one wave setting: the paper's perturbation, or, with a sea
/// ([`Fleet::with_sea`]), each hull's physical response to that wave field.
#[derive(Debug, Clone)]
pub struct Fleet {
    vessels: Vec<VesselMotion>,
    wave: WaveSetting,
    sea: Option<Arc<WaveField>>,
}

impl Fleet {
    /// A fleet of `vessels` (index order is kept in every output) under `wave`, moved by the paper's formula.
    pub fn new(vessels: Vec<VesselMotion>, wave: WaveSetting) -> Self {
        Self { vessels, wave, sea: None }
    }

    /// The same fleet moved physically by `sea`: heave, roll and pitch from each hull's RAOs
    /// ([`crate::ocean::response`](mod@crate::ocean::response)) instead of the paper's perturbation.
    pub fn with_sea(mut self, sea: Arc<WaveField>) -> Self {
        self.sea = Some(sea);
        self
    }

    /// The wave field the fleet sails in, when physical.
    pub fn sea(&self) -> Option<&WaveField> {
        self.sea.as_deref()
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
        Ok(self.vessels.iter().map(|v| v.pose_unchecked(t, &self.wave, self.sea())).collect())
    }

    /// World-frame linear velocities `[vx, vy, vz]` (m/s) of every vessel at time `t`, in vessel order.
    pub fn velocities_at(&self, t: f64) -> Result<Vec<[f64; 3]>> {
        self.check_travel(t, "t")?;
        Ok(self.vessels.iter().map(|v| v.velocity_unchecked(t, &self.wave, self.sea())).collect())
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
            for (slot, v) in row.iter_mut().zip(&self.vessels) {
                *slot = v.pose_unchecked(t, &self.wave, self.sea());
            }
        });
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    pub(super) fn straight_test_vessel(waypoints: &[[f64; 2]], end: EndBehaviour, speed: f64) -> VesselMotion {
        let route = Route::new(waypoints, end).unwrap_or_else(|e| unreachable!("{e}"));
        let params = VesselParams {
            speed_mps: speed,
            start_offset_m: 0.0,
            z_base_m: 0.0,
            dims: VesselDims { length_m: 10.0, beam_m: 4.0, height_m: 3.0 },
            amplitudes: BaseAmplitudes::default(),
            hull: REFERENCE_HULL,
        };
        VesselMotion::new(route, params, WaveSignals::from_seed(1, 0)).unwrap_or_else(|e| unreachable!("{e}"))
    }

    const CURVY: [[f64; 2]; 5] = [[0.0, 0.0], [60.0, 20.0], [80.0, 90.0], [10.0, 120.0], [-50.0, 60.0]];

    fn ok<T>(r: Result<T>) -> T {
        r.unwrap_or_else(|e| unreachable!("{e}"))
    }

    fn vessel(end: EndBehaviour, speed: f64, dims: VesselDims, seed: u64, idx: u64) -> VesselMotion {
        let route = ok(Route::new(&CURVY, end));
        let params = VesselParams { speed_mps: speed, dims, z_base_m: 0.4, ..VesselParams::default() };
        ok(VesselMotion::new(route, params, WaveSignals::from_seed(seed, idx)))
    }

    fn hyp(a: [f64; 6], b: [f64; 6]) -> f64 {
        (b[0] - a[0]).hypot(b[1] - a[1])
    }

    #[test]
    fn travelled_distance_is_speed_times_time() {
        for end in [EndBehaviour::Stop, EndBehaviour::Loop, EndBehaviour::PingPong] {
            let v = vessel(end, 4.0, VesselDims::REFERENCE, 1, 0);
            let len = v.route().length();
            let t_end = if end == EndBehaviour::Stop { 0.9 * len / 4.0 } else { 2.6 * len / 4.0 };
            let n = 100_000;
            let mut prev = ok(v.pose_at(0.0, &WaveSetting::W2));
            let mut acc = 0.0;
            for k in 1..=n {
                let p = ok(v.pose_at(t_end * k as f64 / n as f64, &WaveSetting::W2));
                acc += hyp(prev, p);
                prev = p;
            }
            let want = 4.0 * t_end;
            assert!(((acc - want) / want).abs() < 0.005, "{end:?}: {acc} vs {want}");
        }
    }

    #[test]
    fn yaw_and_velocity_follow_the_motion() {
        for end in [EndBehaviour::Loop, EndBehaviour::PingPong] {
            let v = vessel(end, 3.0, VesselDims::REFERENCE, 2, 1);
            let w = WaveSetting::W1;
            let h = 1e-4;
            for k in 0..300 {
                let t = 0.7 + k as f64 * 0.77;
                let (a, b) = (ok(v.pose_at(t - h, &w)), ok(v.pose_at(t + h, &w)));
                if hyp(a, b) < 2.0 * h * 3.0 * 0.99 {
                    continue; // straddles a ping-pong reversal
                }
                let yaw = ok(v.pose_at(t, &w))[5];
                let fd = (b[1] - a[1]).atan2(b[0] - a[0]);
                assert!(wrap_angle(fd - yaw).abs() < 1e-4, "{end:?} t={t}");
                let vel = ok(v.velocity_at(t, &w));
                for (i, want) in [(b[0] - a[0]) / (2.0 * h), (b[1] - a[1]) / (2.0 * h), (b[2] - a[2]) / (2.0 * h)]
                    .into_iter()
                    .enumerate()
                {
                    assert!((vel[i] - want).abs() < 1e-4, "{end:?} t={t} axis {i}");
                }
            }
        }
    }

    #[test]
    fn stop_rests_at_the_end_and_ping_pong_turns_round() {
        let w = WaveSetting::W0;
        let stop = vessel(EndBehaviour::Stop, 5.0, VesselDims::REFERENCE, 3, 0);
        let len = stop.route().length();
        let t_after = len / 5.0 + 10.0;
        let (p, q) = (ok(stop.pose_at(t_after, &w)), ok(stop.pose_at(t_after + 50.0, &w)));
        assert!(hyp(p, CURVY.map(|c| [c[0], c[1], 0.0, 0.0, 0.0, 0.0])[4]) < 1e-9);
        assert_eq!((p[0], p[1], p[5]), (q[0], q[1], q[5]));
        let vel = ok(stop.velocity_at(t_after, &w));
        assert_eq!((vel[0], vel[1]), (0.0, 0.0));

        let pp = vessel(EndBehaviour::PingPong, 5.0, VesselDims::REFERENCE, 3, 0);
        let s = 30.0;
        let (fwd, back) = (ok(pp.pose_at(s / 5.0, &w)), ok(pp.pose_at((2.0 * len - s) / 5.0, &w)));
        assert!(hyp(fwd, back) < 1e-6);
        assert!((wrap_angle(back[5] - fwd[5]).abs() - PI).abs() < 1e-9);
        let lp = vessel(EndBehaviour::Loop, 5.0, VesselDims::REFERENCE, 3, 0);
        let period = lp.route().length() / 5.0;
        let (a, b) = (ok(lp.pose_at(7.0, &w)), ok(lp.pose_at(7.0 + period, &w)));
        assert!(hyp(a, b) < 1e-6 && wrap_angle(a[5] - b[5]).abs() < 1e-9);
    }

    /// RMS of heave (mean removed per vessel), roll and pitch (degrees) over all vessels and frames.
    fn rms(fleet: &Fleet, frames: usize, dt: f64) -> [f64; 3] {
        let times: Vec<f64> = (0..frames).map(|k| k as f64 * dt).collect();
        let poses = ok(fleet.poses_at_times(&times));
        let nv = fleet.len();
        let mut sums = [0.0; 3];
        for v in 0..nv {
            let mean_z = (0..frames).map(|k| poses[k * nv + v][2]).sum::<f64>() / frames as f64;
            for k in 0..frames {
                let p = poses[k * nv + v];
                sums[0] += (p[2] - mean_z).powi(2);
                sums[1] += p[3].to_degrees().powi(2);
                sums[2] += p[4].to_degrees().powi(2);
            }
        }
        sums.map(|s| (s / (frames * nv) as f64).sqrt())
    }

    fn fleet(dims: VesselDims, wave: WaveSetting, seed: u64) -> Fleet {
        Fleet::new((0..4).map(|i| vessel(EndBehaviour::Loop, 3.0, dims, seed, i)).collect(), wave)
    }

    #[test]
    fn wave_rms_is_monotonic_linear_and_matches_table_one() {
        let table =
            [[0.0274, 0.2054, 0.0684], [0.0818, 0.6134, 0.2062], [0.1379, 1.0345, 0.3395], [0.1923, 1.4421, 0.4774]];
        let mut got = Vec::new();
        for (w, want) in WaveSetting::PRESETS.iter().zip(table) {
            let r = rms(&fleet(VesselDims::REFERENCE, *w, 7), 36_000, 0.1);
            eprintln!("{w}: heave {:.4} m, roll {:.4} deg, pitch {:.4} deg", r[0], r[1], r[2]);
            for axis in 0..3 {
                assert!((r[axis] / want[axis] - 1.0).abs() < 0.05, "{w} axis {axis}: {} vs {}", r[axis], want[axis]);
            }
            got.push(r);
        }
        let heights: Vec<f64> = WaveSetting::PRESETS.iter().map(WaveSetting::height_m).collect();
        for axis in 0..3 {
            let y: Vec<f64> = got.iter().map(|r| r[axis]).collect();
            assert!(y.windows(2).all(|p| p[1] > p[0]), "axis {axis} not monotonic: {y:?}");
            let n = y.len() as f64;
            let (mx, my) = (heights.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
            let sxy: f64 = heights.iter().zip(&y).map(|(x, y)| (x - mx) * (y - my)).sum();
            let sxx: f64 = heights.iter().map(|x| (x - mx).powi(2)).sum();
            let slope = sxy / sxx;
            let ss_res: f64 = heights.iter().zip(&y).map(|(x, y)| (y - my - slope * (x - mx)).powi(2)).sum();
            let ss_tot: f64 = y.iter().map(|y| (y - my).powi(2)).sum();
            assert!(1.0 - ss_res / ss_tot >= 0.99, "axis {axis}: R² too low");
        }
        // A free height in between behaves like the presets.
        let free = rms(&fleet(VesselDims::REFERENCE, ok(WaveSetting::from_height(2.0)), 7), 36_000, 0.1);
        assert!(free[0] > got[1][0] && free[0] < got[2][0]);
        let flat = rms(&fleet(VesselDims::REFERENCE, ok(WaveSetting::from_height(0.0)), 7), 100, 0.1);
        assert!(flat.iter().all(|r| *r < 1e-12), "{flat:?}");
    }

    #[test]
    fn small_vessels_move_more_than_large_ships() {
        let small = VesselDims { length_m: 3.0, beam_m: 1.2, height_m: 1.0 };
        let ship = VesselDims { length_m: 300.0, beam_m: 48.0, height_m: 60.0 };
        let a = rms(&fleet(small, WaveSetting::W2, 5), 12_000, 0.1);
        let b = rms(&fleet(ship, WaveSetting::W2, 5), 12_000, 0.1);
        for axis in 0..3 {
            assert!(a[axis] > 10.0 * b[axis], "axis {axis}: {} vs {}", a[axis], b[axis]);
        }
    }

    #[test]
    fn same_seed_same_poses_other_seed_other_phases() {
        let times: Vec<f64> = (0..500).map(|k| k as f64 * 0.2).collect();
        let a = ok(fleet(VesselDims::REFERENCE, WaveSetting::W3, 42).poses_at_times(&times));
        let b = ok(fleet(VesselDims::REFERENCE, WaveSetting::W3, 42).poses_at_times(&times));
        let bits = |p: &[[f64; 6]]| p.iter().flatten().map(|x| x.to_bits()).collect::<Vec<u64>>();
        assert_eq!(bits(&a), bits(&b));
        let c = ok(fleet(VesselDims::REFERENCE, WaveSetting::W3, 43).poses_at_times(&times));
        assert_ne!(bits(&a), bits(&c));
        // Same layout as calling poses_at at each time; vessels of one fleet differ from each other.
        let f = fleet(VesselDims::REFERENCE, WaveSetting::W3, 42);
        assert_eq!(ok(f.poses_at(times[17])), a[17 * 4..18 * 4].to_vec());
        assert_ne!(f.vessels()[0].signals(), f.vessels()[1].signals());
    }

    #[test]
    fn bad_inputs_are_errors_not_panics() {
        let route = || ok(Route::new(&CURVY, EndBehaviour::Stop));
        let sig = WaveSignals::from_seed(0, 0);
        let field_of = |p: VesselParams| match VesselMotion::new(route(), p, sig) {
            Err(MmusvError::Config { field, .. }) => field,
            other => unreachable!("expected a config error, got {other:?}"),
        };
        assert_eq!(field_of(VesselParams { speed_mps: -1.0, ..VesselParams::default() }), "speed_mps");
        assert_eq!(field_of(VesselParams { speed_mps: f64::NAN, ..VesselParams::default() }), "speed_mps");
        assert_eq!(field_of(VesselParams { start_offset_m: 1e6, ..VesselParams::default() }), "start_offset_m");
        assert_eq!(field_of(VesselParams { z_base_m: f64::INFINITY, ..VesselParams::default() }), "z_base_m");
        assert!(matches!(Route::new(&[[0.0, 0.0]], EndBehaviour::Stop), Err(MmusvError::Config { .. })));
        assert!(matches!(
            Route::new(&[[0.0, 0.0], [f64::NAN, 0.0]], EndBehaviour::Stop),
            Err(MmusvError::Config { .. })
        ));
        assert!(matches!("W9".parse::<WaveSetting>(), Err(MmusvError::Config { .. })));
        assert!(matches!(WaveSetting::from_height(-1.0), Err(MmusvError::Config { .. })));
        let f = fleet(VesselDims::REFERENCE, WaveSetting::W1, 1);
        for t in [-1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(f.poses_at(t), Err(MmusvError::InvalidInput { ref field, .. }) if field == "t"));
            assert!(matches!(f.velocities_at(t), Err(MmusvError::InvalidInput { .. })));
        }
        let err = f.poses_at_times(&[0.0, 1.0, -2.0]);
        assert!(matches!(err, Err(MmusvError::InvalidInput { ref field, .. }) if field == "times[2]"));
        assert_eq!(Fleet::new(Vec::new(), WaveSetting::W0).poses_at_times(&[1.0]).map(|v| v.len()), Ok(0));
    }

    #[test]
    fn poses_at_times_refuses_more_than_max_poses_before_allocating() {
        // 4 vessels at MAX_POSES / 4 + 1 times: one pose too many (used to allocate T·V·48 bytes, unbounded).
        let f = fleet(VesselDims::REFERENCE, WaveSetting::W1, 1);
        let times = vec![0.0; MAX_POSES / 4 + 1];
        let err = f.poses_at_times(&times);
        assert!(matches!(err, Err(MmusvError::InvalidInput { ref field, .. }) if field == "times"), "{err:?}");
        assert_eq!(f.poses_at_times(&times[..2]).map(|v| v.len()), Ok(8));
    }

    #[test]
    fn a_fleet_in_a_sea_moves_by_its_hulls_response() {
        use crate::ocean::{response::response, SeaSpec, WaveField};
        let sea = SeaSpec { hs: 2.5, tp: 8.0, gamma: 3.3, direction_rad: 0.5, spread_s: 10.0 };
        let field = Arc::new(ok(WaveField::new(&sea, 9)));
        let paper = fleet(VesselDims::REFERENCE, WaveSetting::W2, 4);
        let physical = paper.clone().with_sea(Arc::clone(&field));
        let t = 37.5;
        let (pp, pq) = (ok(paper.poses_at(t)), ok(physical.poses_at(t)));
        for (v, (a, b)) in paper.vessels().iter().zip(pp.iter().zip(&pq)) {
            // Same route position and heading; heave, roll, pitch from the RAOs at that place and velocity.
            assert_eq!((a[0], a[1], a[5]), (b[0], b[1], b[5]));
            let vel = ok(v.velocity_at(t, &WaveSetting::W2));
            let r = response(&field, &v.params().hull, b[0], b[1], b[5], vel[0], vel[1], t)[0];
            assert_eq!([b[2] - v.params().z_base_m, b[3], b[4]], r);
            assert_eq!(ok(v.pose_in_sea(t, &field)), *b);
        }
        // Vertical velocity is the time derivative of the heave, the turning's change of the response included
        // (on this curve it is a few per cent of the rate at a fixed heading and velocity).
        let h = 1e-5;
        let (a, b) = (ok(physical.poses_at(t - h)), ok(physical.poses_at(t + h)));
        let vz = ok(physical.velocities_at(t));
        for (i, v) in physical.vessels().iter().enumerate() {
            let fd = (b[i][2] - a[i][2]) / (2.0 * h);
            assert!((fd - vz[i][2]).abs() < 1e-5, "{fd} {}", vz[i][2]);
            let b = pq[i];
            let vel = ok(v.velocity_at(t, &WaveSetting::W2));
            let fixed = response(&field, &v.params().hull, b[0], b[1], b[5], vel[0], vel[1], t)[1][0];
            assert!((fd - fixed).abs() < 0.05 * (fixed.abs() + 0.01));
        }
        // The paper fleet is untouched by the existence of a sea.
        assert!(paper.sea().is_none() && physical.sea().is_some());
    }

    #[test]
    fn the_physical_response_passes_smoothly_through_a_stop_and_a_turn_about() {
        use crate::ocean::{response::response, SeaSpec, WaveField};
        use transient::FADED;
        let sea = SeaSpec { hs: 3.5, tp: 8.0, gamma: 3.3, direction_rad: 0.3, spread_s: 10.0 };
        let field = ok(WaveField::new(&sea, 5));
        let field = Arc::new(field);
        for end in [EndBehaviour::Stop, EndBehaviour::PingPong] {
            let v = straight_test_vessel(&[[0.0, 0.0], [50.0, 0.0]], end, 5.0);
            let fleet = Fleet::new(vec![v.clone()], WaveSetting::W0).with_sea(Arc::clone(&field));
            let te = v.route().length() / 5.0; // 50 m at 5 m/s
            let pose = |t: f64| ok(v.pose_in_sea(t, &field));
            let (a, b) = (pose(te - 1e-7), pose(te + 1e-7));
            assert!(
                (a[2] - b[2]).abs() < 1e-6 && (a[3] - b[3]).abs() < 1e-6 && (a[4] - b[4]).abs() < 1e-6,
                "{a:?} {b:?}"
            );
            // The steady state just after the event differs (the stop or the turn), so the step was real.
            let vel = ok(v.velocity_at(te + 1e-7, &WaveSetting::W0));
            let steady = response(&field, &v.params().hull, b[0], b[1], b[5], vel[0], vel[1], te + 1e-7)[0];
            assert!((steady[1] - b[3]).abs() > 1e-3 || (steady[0] - b[2]).abs() > 1e-3, "{end:?}");
            // Long after, the steady state of the new course (before the next turn of the ping-pong route).
            let hull = &v.params().hull;
            let faded = -FADED.ln() / (hull.roll_damping_ratio * hull.roll_natural_frequency());
            if end == EndBehaviour::Stop {
                let t = te + faded + 1.0;
                let p = pose(t);
                assert_eq!(
                    [p[2] - v.params().z_base_m, p[3], p[4]],
                    response(&field, hull, 50.0, 0.0, p[5], 0.0, 0.0, t)[0]
                );
            }
            // The heave rate is the heave's derivative across the event too.
            let vz = ok(fleet.velocities_at(te + 0.5))[0][2];
            let fd = (pose(te + 0.5 + 1e-5)[2] - pose(te + 0.5 - 1e-5)[2]) / 2e-5;
            assert!((vz - fd).abs() < 1e-5, "{vz} {fd}");
        }
    }
}
