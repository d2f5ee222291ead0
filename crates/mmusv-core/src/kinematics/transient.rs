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
//! r(t) = r_after(t) + w(t − t_e) · (r_before(t) − r_after(t)),   w(τ) = e^{−ζ ω_φ τ}
//! ```
//!
//! with `r_before` the steady state the hull had (its heading and velocity just before the event, frozen, at its
//! position now) and `r_after` the one it has; `ζ ω_φ` is the roll's (the least damped of the three modes, so its
//! envelope bounds the heave's and the pitch's). The pose is continuous at the event (`w(0) = 1`), and the old
//! steady state fades over `1/(ζ ω_φ)` (13 s for a 5 m USV; an approximation: the free oscillation itself, at the
//! natural frequency, is not drawn). Several events in a row chain: `r_before` of an event is the previous
//! segment's response, itself blended with the event before it. Events older than [`FADED`] of weight, or more
//! than [`MAX_EVENTS`] back, are left out.

use super::spline::{EndBehaviour, Route};
use super::VesselParams;
use crate::ocean::{response::response, WaveField};
use std::f64::consts::PI;

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
    let mut yaw = route.yaw(s);
    if sign < 0.0 {
        yaw = super::spline::wrap_angle(yaw + PI);
    }
    let [tx, ty] = route.tangent(s);
    (yaw, speed * sign * tx, speed * sign * ty)
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

/// `[heave (m), roll (rad), pitch (rad)]` of the hull of `params` on `route` in `field` at time `t`, at world
/// position `(x, y)` with heading `yaw` and world velocity `(vx, vy)` (its state at `t`): the steady-state response,
/// passed through the transients of the route's recent events (the module's header).
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
    let now = response(field, hull, x, y, yaw, vx, vy, t)[0];
    let evs = events(route, params, t, decay);
    if evs.is_empty() {
        return now;
    }
    let blend = |after: [f64; 3], before: [f64; 3], te: f64| {
        let w = (-decay * (t - te).max(0.0)).exp();
        [0, 1, 2].map(|i| after[i] + w * (before[i] - after[i]))
    };
    // The chain: the steady state before the oldest event, blended at each later event with the one before it.
    let mut before: Option<([f64; 3], f64)> = None;
    for ev in &evs {
        let steady = response(field, hull, x, y, ev.yaw, ev.vx, ev.vy, t)[0];
        let segment = match before {
            None => steady,
            Some((earlier, te)) => blend(steady, earlier, te),
        };
        before = Some((segment, ev.t));
    }
    match before {
        Some((earlier, te)) => blend(now, earlier, te),
        None => now,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
