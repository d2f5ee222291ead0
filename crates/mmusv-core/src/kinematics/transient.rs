//! The hull's response across a route event: where a `Stop` route ends (the hull comes to rest) or a `PingPong`
//! route turns about (its heading flips by π), the steady-state response of [`crate::ocean::response()`] changes in
//! an instant, and heave, roll and pitch would step with it (0.76 m of heave between two frames, 15° of roll).
//!
//! Model: after a change of forcing at `t_e`, a linear damped oscillator goes from its old steady state to its new
//! one through a free transient whose envelope decays as `e^{−ζ ω_n (t − t_e)}` (e.g. Newland, D. E. (1989),
//! *Mechanical Vibration Analysis and Computation*, ch. 2; for ship roll, Lloyd, A. R. J. M. (1989),
//! *Seakeeping: Ship Behaviour in Rough Weather*, §9). Here the response after the event is
//!
//! ```text
//! r(t) = κ(w) · (w r_before(t) + (1 − w) r_after(t)),   w = e^{−ζ ω_φ (t − t_e)}
//! κ(w)² = (w σ_b² + (1 − w) σ_a²) / (w² σ_b² + (1 − w)² σ_a² + 2 w (1 − w) c_ab)
//! ```
//!
//! with `r_before` the steady state the hull had (its heading and velocity just before the event, frozen, at its
//! position now) and `r_after` the one it has; `ζ ω_φ` is the roll's (the least damped of the three modes, so its
//! envelope bounds the heave's and the pitch's). `σ_b²`, `σ_a²` and `c_ab` are the two steady states' variances and
//! covariance over the field's random phases, `Σ a²/2 |H_b|²`, `Σ a²/2 |H_a|²` and `Σ a²/2 Re(H_b H_a*)` per mode:
//! `κ` keeps the blend's variance between the two (a plain linear blend of two partly independent responses would
//! take energy out of the motion while it lasts: 1–2 % of the roll over 20 minutes of turns about in
//! `island_port_waves`). The pose is continuous at the event (`w = 1`, `κ = 1`), and the old steady state fades
//! over `1/(ζ ω_φ)` (2.5 s for a WAM-V; an approximation: the free oscillation itself, at the natural frequency, is
//! not drawn). Several events in a row chain: `r_before` of an event is the previous segment's response, itself
//! blended with the event before it (each segment is a gain per wave component and mode, so the chain's variances
//! follow). Events older than [`FADED`] of weight, or more than [`MAX_EVENTS`] back, are left out.

use super::spline::{EndBehaviour, Route};
use super::VesselParams;
use crate::ocean::response::{encounter_frequency, response};
use crate::ocean::{Hull, WaveField};

/// The weight below which an event's earlier steady state is left out: its share of the difference between two
/// steady states (at most a few metres or radians) is then under a nanometre or a nanoradian.
pub const FADED: f64 = 1e-9;

/// The most events chained (a short `PingPong` route sailed fast turns about every few seconds).
pub const MAX_EVENTS: usize = 64;

/// A route event: its time and the hull's heading (rad) and world velocity (m/s) just before it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Event {
    t: f64,
    yaw: f64,
    vx: f64,
    vy: f64,
}

/// The heading and velocity of a hull at arc length `s`, travelling in direction `sign` at `speed` along `route`.
fn state(route: &Route, speed: f64, s: f64, sign: f64) -> (f64, f64, f64) {
    let [vx, vy] = route.velocity(s, sign, speed);
    (route.heading(s, sign), vx, vy)
}

/// The events of `route` sailed with `params` up to time `t` whose weight at `t` is at least [`FADED`] (at most
/// [`MAX_EVENTS`], the latest), oldest first; `decay` is `ζ ω_φ` (1/s).
fn events(route: &Route, params: &VesselParams, t: f64, decay: f64) -> Vec<Event> {
    let (u, offset, len) = (params.speed_mps, params.start_offset_m, route.length());
    if !(u > 0.0 && len > 0.0) {
        return Vec::new();
    }
    let window = -FADED.ln() / decay; // seconds after which an event has faded
    let d_now = offset + u * t;
    let event_at = |d: f64| (d - offset) / u;
    match route.end_behaviour() {
        EndBehaviour::Loop => Vec::new(),
        EndBehaviour::Stop => {
            // At rest from d = L on (Route::distance_to_arc); a hull that starts there never sailed.
            let te = event_at(len);
            if offset < len && d_now >= len && t - te <= window {
                let (yaw, vx, vy) = state(route, u, len, 1.0);
                vec![Event { t: te, yaw, vx, vy }]
            } else {
                Vec::new()
            }
        }
        EndBehaviour::PingPong => {
            // Turns at d = n L (n ≥ 1): at the far end (n odd) from travelling forwards, passed once d > n L; at the
            // start (n even) from travelling backwards, passed at d = n L already (as Route::distance_to_arc has
            // it). A turn at the start offset itself is one only at the far end (the hull starts there forwards).
            let mut n = (d_now / len).floor();
            if n * len >= d_now && n % 2.0 == 1.0 {
                n -= 1.0;
            }
            let mut out = Vec::new();
            while n >= 1.0 && out.len() < MAX_EVENTS {
                let dn = n * len;
                let te = event_at(dn);
                if dn < offset || (dn == offset && n % 2.0 == 0.0) || t - te > window {
                    break;
                }
                let forwards = n % 2.0 == 1.0;
                let (yaw, vx, vy) = if forwards { state(route, u, len, 1.0) } else { state(route, u, 0.0, -1.0) };
                out.push(Event { t: te, yaw, vx, vy });
                n -= 1.0;
            }
            out.reverse();
            out
        }
    }
}

/// A segment's response: the complex gain of each wave component (field order) for heave, roll and pitch.
type Gains = Vec<[[f64; 2]; 3]>;

/// The steady-state gains (the RAOs at the encounter frequencies) of `hull` at heading `yaw` and velocity `(vx, vy)`.
fn steady(field: &WaveField, hull: &Hull, yaw: f64, vx: f64, vy: f64) -> Gains {
    field
        .components()
        .iter()
        .map(|c| {
            let we = encounter_frequency(c.omega_rad_s, c.kx, c.ky, vx, vy);
            let h = hull.rao(c.omega_rad_s, c.direction_rad - yaw, we);
            [h.heave, h.roll, h.pitch]
        })
        .collect()
}

/// `κ(w) (w before + (1 − w) after)`, gain by gain (the module's header).
fn blend(field: &WaveField, after: &Gains, before: &Gains, w: f64) -> Gains {
    let mut sums = [[0.0f64; 3]; 3]; // per mode: σ_b², σ_a², c_ab
    for ((c, a), b) in field.components().iter().zip(after).zip(before) {
        let v = c.elevation_variance();
        for m in 0..3 {
            let ([ar, ai], [br, bi]) = (a[m], b[m]);
            sums[m][0] += v * (br * br + bi * bi);
            sums[m][1] += v * (ar * ar + ai * ai);
            sums[m][2] += v * (br * ar + bi * ai);
        }
    }
    let kappa = sums.map(|[vb, va, cab]| {
        let linear = w * w * vb + (1.0 - w) * (1.0 - w) * va + 2.0 * w * (1.0 - w) * cab;
        let target = w * vb + (1.0 - w) * va;
        if linear > 0.0 && target > 0.0 {
            (target / linear).sqrt()
        } else {
            1.0
        }
    });
    after
        .iter()
        .zip(before)
        .map(|(a, b)| {
            [0, 1, 2].map(|m| {
                let k = kappa[m];
                [k * (w * b[m][0] + (1.0 - w) * a[m][0]), k * (w * b[m][1] + (1.0 - w) * a[m][1])]
            })
        })
        .collect()
}

/// `Σ Re(G e^{iψ}) a` at `(x, y, t)`, per mode.
fn evaluate(field: &WaveField, gains: &Gains, x: f64, y: f64, t: f64) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (c, g) in field.components().iter().zip(gains) {
        let (s, co) = c.phase_at(x, y, t).sin_cos();
        let (er, ei) = (c.amplitude_m * co, c.amplitude_m * s);
        for m in 0..3 {
            out[m] += g[m][0] * er - g[m][1] * ei;
        }
    }
    out
}

/// `[heave (m), roll (rad), pitch (rad)]` of the hull of `params` on `route` in `field` at time `t`, at world
/// position `(x, y)` with heading `yaw` and world velocity `(vx, vy)` (its state at `t`): the steady-state response
/// ([`response`]), passed through the transients of the route's recent events (the module's header).
#[allow(clippy::too_many_arguments)]
pub fn response_through_events(
    field: &WaveField,
    route: &Route,
    params: &VesselParams,
    [x, y]: [f64; 2],
    yaw: f64,
    [vx, vy]: [f64; 2],
    t: f64,
) -> [f64; 3] {
    let hull = &params.hull;
    let decay = hull.roll_damping_ratio * hull.roll_natural_frequency();
    let evs = events(route, params, t, decay);
    if evs.is_empty() {
        return response(field, hull, x, y, yaw, vx, vy, t)[0];
    }
    let weight = |te: f64| (-decay * (t - te).max(0.0)).exp();
    // The chain: the steady state before the oldest event, blended at each later event with the one before it.
    let mut before: Option<(Gains, f64)> = None;
    for ev in &evs {
        let held = steady(field, hull, ev.yaw, ev.vx, ev.vy);
        let segment = match before {
            None => held,
            Some((earlier, te)) => blend(field, &held, &earlier, weight(te)),
        };
        before = Some((segment, ev.t));
    }
    let now = steady(field, hull, yaw, vx, vy);
    let gains = match before {
        Some((earlier, te)) => blend(field, &now, &earlier, weight(te)),
        None => now,
    };
    evaluate(field, &gains, x, y, t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn route(end: EndBehaviour) -> Route {
        Route::new(&[[0.0, 0.0], [50.0, 0.0]], end).unwrap_or_else(|e| unreachable!("{e}"))
    }

    fn params(speed: f64, offset: f64) -> VesselParams {
        VesselParams { speed_mps: speed, start_offset_m: offset, ..VesselParams::default() }
    }

    #[test]
    fn a_stop_route_has_one_event_at_its_end() {
        let r = route(EndBehaviour::Stop);
        let te = r.length() / 5.0; // 10 s, to the spline's arc length
        assert!(events(&r, &params(5.0, 0.0), 9.9, 0.1).is_empty());
        assert_eq!(events(&r, &params(5.0, 0.0), te, 0.1).len(), 1); // at rest from d = L on
        let e = events(&r, &params(5.0, 0.0), 12.0, 0.1);
        assert_eq!(e.len(), 1);
        assert!((e[0].t - 10.0).abs() < 1e-12 && e[0].yaw.abs() < 1e-12 && (e[0].vx - 5.0).abs() < 1e-12);
        // Faded after −ln(1e-9)/0.1 = 207 s; at rest from the start (offset at the end, or no speed): none.
        assert!(events(&r, &params(5.0, 0.0), 10.0 + 210.0, 0.1).is_empty());
        assert!(events(&r, &params(5.0, r.length()), 12.0, 0.1).is_empty());
        assert!(events(&r, &params(0.0, 0.0), 12.0, 0.1).is_empty());
        let ring = Route::new(&[[0.0, 0.0], [50.0, 0.0], [25.0, 40.0]], EndBehaviour::Loop);
        let ring = ring.unwrap_or_else(|e| unreachable!("{e}"));
        assert!(events(&ring, &params(5.0, 0.0), 300.0, 0.1).is_empty());
    }

    #[test]
    fn a_ping_pong_route_turns_at_each_end_from_the_heading_it_had() {
        let r = route(EndBehaviour::PingPong);
        // 10 s a leg: turns at 10 s (at the far end, heading east before) and 20 s (at the start, heading west).
        let e = events(&r, &params(5.0, 0.0), 25.0, 0.1);
        assert_eq!(e.len(), 2);
        assert!((e[0].t - 10.0).abs() < 1e-12 && (e[1].t - 20.0).abs() < 1e-12);
        assert!(e[0].yaw.abs() < 1e-12 && (e[0].vx - 5.0).abs() < 1e-12);
        assert!((e[1].yaw.abs() - PI).abs() < 1e-12 && (e[1].vx + 5.0).abs() < 1e-12);
        // Starting 60 m along (back from the far end): the first turn is at d = 100 m, 8 s later.
        let e = events(&r, &params(5.0, 60.0), 9.0, 0.1);
        assert_eq!(e.len(), 1);
        assert!((e[0].t - 8.0).abs() < 1e-12 && (e[0].vx + 5.0).abs() < 1e-12);
        // No turn yet, and exactly at the far end (still before the turn).
        let (len, leg) = (r.length(), r.length() / 5.0);
        assert!(events(&r, &params(5.0, 0.0), 9.0, 0.1).is_empty());
        assert!(events(&r, &params(5.0, 0.0), leg, 0.1).is_empty());
        // Starting at the far end: a turn at once; at the start (d = 2 L): none until the far end.
        assert_eq!(events(&r, &params(5.0, len), 1.0, 0.1).first().map(|e| e.t), Some(0.0));
        assert!(events(&r, &params(5.0, 2.0 * len), 9.0, 0.1).is_empty());
        // The chain's cap.
        assert_eq!(events(&r, &params(5.0, 0.0), 1000.0, 1e-3).len(), MAX_EVENTS);
    }

    #[test]
    fn the_blend_keeps_the_variance_between_the_two_steady_states() {
        use crate::ocean::SeaSpec;
        let sea = SeaSpec { hs: 2.0, tp: 7.0, gamma: 3.3, direction_rad: 0.4, spread_s: 8.0 };
        let field = WaveField::new(&sea, 3).unwrap_or_else(|e| unreachable!("{e}"));
        let hull = super::super::REFERENCE_HULL;
        let var = |g: &Gains, m: usize| -> f64 {
            field
                .components()
                .iter()
                .zip(g)
                .map(|(c, g)| c.elevation_variance() * (g[m][0].powi(2) + g[m][1].powi(2)))
                .sum()
        };
        let (a, b) = (steady(&field, &hull, 0.0, 5.0, 0.0), steady(&field, &hull, PI, -5.0, 0.0));
        // The evaluation of a steady state is the steady-state response.
        let r = response(&field, &hull, 3.0, -2.0, 0.0, 5.0, 0.0, 11.0)[0];
        let e = evaluate(&field, &a, 3.0, -2.0, 11.0);
        assert!((0..3).all(|m| (r[m] - e[m]).abs() < 1e-12), "{r:?} {e:?}");
        for w in [0.0, 0.2, 0.5, 0.9, 1.0] {
            let g = blend(&field, &a, &b, w);
            for m in 0..3 {
                let target = w * var(&b, m) + (1.0 - w) * var(&a, m);
                assert!((var(&g, m) - target).abs() <= 1e-9 * target, "{w} {m}");
            }
            // A blend of a segment with itself is that segment.
            let same = blend(&field, &a, &a, w);
            assert!(same.iter().zip(&a).all(|(x, y)| (0..3).all(|m| (x[m][0] - y[m][0]).abs() < 1e-12)));
        }
        // The ends are the two segments themselves.
        assert_eq!(blend(&field, &a, &b, 1.0), b);
        assert_eq!(blend(&field, &a, &b, 0.0), a);
    }
}
