//! The path behind a vessel: how far back it ran straight, and the straight pieces it runs in round its bends
//! (what a wake is drawn along: `sensors/shade/wake.rs`, `mmusv.Simulation.wakes`).
//!
//! Worked out from the route spline itself, sampled back along the distance travelled (before the scenario's
//! start the vessel is taken to have come straight along its heading there): a piece runs straight while every
//! sampled point of the path behind lies within the tolerance of the line back from its start, ever farther
//! behind; the next one starts where the path left it.

use super::{check_time, VesselMotion};
use crate::error::{MmusvError, Result};

/// One straight piece of a vessel's path behind it ([`VesselMotion::wake_pieces`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WakePiece {
    /// Where the piece starts (the vessel's centre when it passed there), metres.
    pub x: f64,
    /// Where the piece starts, metres.
    pub y: f64,
    /// The direction of travel there, radians counter-clockwise from +x.
    pub heading: f64,
    /// How far back from there the path ran straight (metres; infinite: as far as asked).
    pub reach_m: f64,
    /// How long ago the vessel passed the piece's start, seconds.
    pub age_s: f64,
}

/// Refuses distances that are not finite and positive, naming them.
fn check_distances(max_m: f64, step_m: f64, tolerance_m: f64) -> Result<()> {
    for (name, v) in [("max_m", max_m), ("step_m", step_m), ("tolerance_m", tolerance_m)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(MmusvError::input(name, format!("must be a finite distance > 0 m, got {v}")));
        }
    }
    Ok(())
}

impl VesselMotion {
    /// The vessel's path behind it at time `t` (finite, ≥ 0) as straight pieces, newest first, for a wake that
    /// follows the bends. The first is the vessel's own, back along its heading from its position: as far as
    /// every point of the route behind (checked every `step_m`) lies within `tolerance_m` of that line, ever
    /// farther behind (a reversal or a turn ends it); before `t = 0` the vessel is taken to have come straight
    /// along its heading at the start (a scenario starts with its vessels under way). Each next one starts where the path stopped running straight within `tolerance_m` of the one
    /// before (the vessel's centre there, and how long ago it passed there, `age_s`) and runs along the chord to
    /// the next one's start (`heading` the direction of travel, `reach_m` the chord's length), until `max_m` of
    /// path or `max_pieces` pieces; the last reaches on straight along the vessel's heading there (`reach_m`
    /// infinite). A vessel at rest at the end of a `stop` route keeps the pieces it had when it arrived there, each
    /// as much older as it has lain at rest (`age_s` counts from then: the foam it left outlasts its stop and fades
    /// with its age), out to `max_m` of path at its speed (none once that is all older than `max_m / speed`); none
    /// for a vessel of zero speed or one at rest from the start (a `start_offset_m` at or past its route's end).
    pub fn wake_pieces(
        &self,
        t: f64,
        max_m: f64,
        step_m: f64,
        tolerance_m: f64,
        max_pieces: usize,
    ) -> Result<Vec<WakePiece>> {
        check_time(t, "t")?;
        check_distances(max_m, step_m, tolerance_m)?;
        let speed = self.params.speed_mps;
        let mut d = self.travelled_m(t);
        if speed == 0.0 {
            return Ok(Vec::new());
        }
        // At rest at a `stop` route's end: the path as it was on arrival, the time since then added to every age.
        let mut rest_s = 0.0;
        if self.route.distance_to_arc(d).1 == 0.0 {
            let end = self.route.length();
            if self.params.start_offset_m >= end {
                // At rest from the start (parked at its route's end): no wake of its own.
                return Ok(Vec::new());
            }
            rest_s = (d - end) / speed;
            d = end;
        }
        let mut pieces = Vec::new();
        let mut back = rest_s * speed;
        while back < max_m && pieces.len() < max_pieces {
            let (p, u, _) = self.route_heading(d);
            let (mut reach, path) = self.straight_run(d, max_m - back, step_m, tolerance_m);
            if pieces.len() + 1 == max_pieces {
                reach = f64::INFINITY;
            }
            if reach > 0.0 {
                let heading = u[1].atan2(u[0]);
                pieces.push(WakePiece { x: p[0], y: p[1], heading, reach_m: reach, age_s: back / speed });
            }
            if reach.is_infinite() {
                break;
            }
            // On from where the path left the line (at least a step back, so that a sharp turn moves on).
            let step = path.max(step_m);
            d -= step;
            back += step;
        }
        // Each older piece along its chord, from its start to the next one's (where the path left it), so that
        // the pieces meet on the path; the vessel's own keeps its heading, and the last one, reaching on, its own.
        for k in 1..pieces.len().saturating_sub(1) {
            let (a, b) = (pieces[k], pieces[k + 1]);
            let (dx, dy) = (a.x - b.x, a.y - b.y);
            pieces[k].heading = dy.atan2(dx);
            pieces[k].reach_m = dx.hypot(dy);
        }
        Ok(pieces)
    }

    /// Position, unit heading (the direction of travel; at rest at a `stop` route's end, the one it arrived
    /// with) and direction sign (0 at rest) at travelled distance `d`; before the start (`d` below the start
    /// offset) on the straight line the vessel is taken to have come along.
    fn route_heading(&self, d: f64) -> ([f64; 2], [f64; 2], f64) {
        let at = |d: f64| {
            let (s, sign) = self.route.distance_to_arc(d);
            let [tx, ty] = self.route.tangent(s);
            let u = if sign == 0.0 { 1.0 } else { sign };
            (self.route.position(s), [tx * u, ty * u], sign)
        };
        let d_start = self.params.start_offset_m;
        if d >= d_start {
            return at(d);
        }
        let (p, u, sign) = at(d_start);
        ([p[0] - (d_start - d) * u[0], p[1] - (d_start - d) * u[1]], u, sign)
    }

    /// How far back from travelled distance `d` (under way) the path runs straight within `tolerance_m` of the
    /// line back along the heading there, checked every `step_m` out to `max_m`: the reach along that line
    /// (`f64::INFINITY` when straight to `max_m`), and the distance along the path to the last point checked on it.
    fn straight_run(&self, d: f64, max_m: f64, step_m: f64, tolerance_m: f64) -> (f64, f64) {
        let (p0, u, _) = self.route_heading(d);
        let mut reach = 0.0;
        let mut path = 0.0;
        let steps = (max_m / step_m).ceil() as usize;
        for k in 1..=steps {
            let back = (k as f64 * step_m).min(max_m);
            let p = self.route_heading(d - back).0;
            let (rx, ry) = (p0[0] - p[0], p0[1] - p[1]);
            let along = rx * u[0] + ry * u[1];
            let across = (rx * u[1] - ry * u[0]).abs();
            if across > tolerance_m || along <= reach {
                return (reach, path);
            }
            reach = along;
            path = back;
            if back + 1e-6 >= max_m {
                // (Within a micrometre of `max_m`: a quotient rounded up may ask for a last step of next to nothing.)
                break;
            }
        }
        (f64::INFINITY, path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::tests::straight_test_vessel;
    use crate::kinematics::{EndBehaviour, WaveSetting};
    use std::f64::consts::PI;

    /// A ring of radius `r` metres round the origin (a 64-gon through the spline).
    fn ring(r: f64) -> Vec<[f64; 2]> {
        (0..=64)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 64.0;
                [r * a.cos(), r * a.sin()]
            })
            .collect()
    }

    /// The vessel's own piece: on a straight route, straight behind as far as asked (also back before the start);
    /// on a ping-pong route only back to where it turned; on a circle only as far as its arc stays within the
    /// tolerance of the tangent, `√(2 R tol)` for a radius R. None at rest.
    #[test]
    fn the_vessels_own_piece_runs_as_far_as_the_path_ran_straight() {
        let own = |v: &VesselMotion, t: f64, step: f64, tol: f64| {
            let pieces = v.wake_pieces(t, 600.0, step, tol, 32).unwrap_or_else(|e| unreachable!("{e}"));
            pieces.first().map(|p| p.reach_m)
        };
        let line = straight_test_vessel(&[[0.0, 0.0], [1000.0, 0.0]], EndBehaviour::Stop, 5.0);
        assert_eq!(own(&line, 10.0, 2.0, 1.0), Some(f64::INFINITY));
        assert_eq!(own(&line, 0.0, 2.0, 1.0), Some(f64::INFINITY));
        assert_eq!(own(&line, 210.0, 2.0, 1.0), Some(f64::INFINITY), "at rest for 10 s: its wake as it arrived");
        assert_eq!(own(&line, 330.0, 2.0, 1.0), None, "at rest for 130 s: the 600 m asked for all older");
        // Ping-pong on a 100 m leg at 5 m/s: at t = 24 s it turned 20 m ago (d = 120 m).
        let pp = straight_test_vessel(&[[0.0, 0.0], [100.0, 0.0]], EndBehaviour::PingPong, 5.0);
        let b = own(&pp, 24.0, 1.0, 1.0).unwrap_or(f64::NAN);
        assert!((b - 20.0).abs() <= 1.0 + 1e-9, "{b}");
        // A loop on a circle of radius 100 m.
        let (r, tol) = (100.0, 2.0);
        let circle = straight_test_vessel(&ring(r), EndBehaviour::Loop, 5.0);
        let b = own(&circle, 30.0, 0.5, tol).unwrap_or(f64::NAN);
        let want = (2.0 * r * tol).sqrt();
        assert!((b - want).abs() < 0.1 * want, "{b} against {want}");
        assert!(line.wake_pieces(1.0, 0.0, 2.0, 1.0, 32).is_err());
        assert!(line.wake_pieces(f64::NAN, 10.0, 2.0, 1.0, 32).is_err());
    }

    /// The pieces of the path behind a vessel follow it round its bends: on a route with a right-angle corner
    /// (which the route's spline rounds), every point the vessel passed lies within the tolerance of a piece, and
    /// every point of a piece within it of the path (both sampled from the poses themselves); each piece starts
    /// where the vessel was `age_s` ago, where the one before left its line. A ping-pong route's reversal starts a
    /// piece heading the other way; on a circle, pieces of `√(2 R tol)` each, whose starts lie on the circle.
    #[test]
    fn wake_pieces_follow_the_path_round_its_bends() {
        let ok = |r: Result<Vec<WakePiece>>| r.unwrap_or_else(|e| unreachable!("{e}"));
        let pose = |v: &VesselMotion, t: f64| v.pose_at(t, &WaveSetting::W0).unwrap_or_else(|e| unreachable!("{e}"));
        // East 200 m, then north: at t = 70 s (5 m/s) the vessel is 150 m past the corner.
        let (t, tol, speed) = (70.0, 2.0, 5.0);
        let el = straight_test_vessel(&[[0.0, 0.0], [200.0, 0.0], [200.0, 300.0]], EndBehaviour::Stop, speed);
        let pieces = ok(el.wake_pieces(t, 600.0, 1.0, tol, 32));
        assert!(pieces.len() >= 3, "{pieces:?}");
        assert!((pieces[0].heading - PI / 2.0).abs() < 0.2 && pieces[0].age_s == 0.0, "{:?}", pieces[0]);
        let last = pieces[pieces.len() - 1];
        assert!(last.reach_m.is_infinite() && last.heading.abs() < 0.1, "{last:?}");
        for (k, w) in pieces.windows(2).enumerate() {
            assert!(w[1].age_s > w[0].age_s);
            assert!((w[0].x - w[1].x).hypot(w[0].y - w[1].y) < w[0].reach_m + 1.0 + 1e-9, "{w:?}");
            if k > 0 {
                // An older piece runs along its chord: it ends where the next one starts.
                let end = [w[0].x - w[0].reach_m * w[0].heading.cos(), w[0].y - w[0].reach_m * w[0].heading.sin()];
                assert!((end[0] - w[1].x).hypot(end[1] - w[1].y) < 1e-9, "{w:?}");
            }
        }
        // A piece's stretch while the scenario ran: from its start back along its heading, as long as its reach or
        // what was left of the scenario's time.
        let stretch = |p: &WakePiece| p.reach_m.min((t - p.age_s) * speed).max(0.0);
        let on_piece = |p: &WakePiece, q: [f64; 2]| {
            let (c, s) = (p.heading.cos(), p.heading.sin());
            let (dx, dy) = (p.x - q[0], p.y - q[1]);
            let along = (dx * c + dy * s).clamp(0.0, stretch(p));
            (dx - along * c).hypot(dy - along * s)
        };
        let path: Vec<[f64; 2]> =
            (0..=(t * 20.0) as usize).map(|k| pose(&el, k as f64 / 20.0)).map(|q| [q[0], q[1]]).collect();
        for q in &path {
            let d = pieces.iter().map(|p| on_piece(p, *q)).fold(f64::INFINITY, f64::min);
            assert!(d <= tol + 0.3, "the path at {q:?} is {d} m from every piece");
        }
        for p in pieces.iter().filter(|p| p.age_s <= t) {
            let then = pose(&el, t - p.age_s);
            assert!((then[0] - p.x).hypot(then[1] - p.y) < 1e-6, "{p:?} against {then:?}");
            let n = stretch(p).ceil() as usize;
            for k in 0..=n {
                let b = (k as f64).min(stretch(p));
                let q = [p.x - b * p.heading.cos(), p.y - b * p.heading.sin()];
                let d = path.iter().map(|r| (r[0] - q[0]).hypot(r[1] - q[1])).fold(f64::INFINITY, f64::min);
                assert!(d <= tol + 0.3, "{p:?} at {b} m is {d} m off the path");
            }
        }
        // A ping-pong leg 100 m long at 5 m/s, 24 s in: back to the turn 20 m away, then the outbound leg.
        let pp = straight_test_vessel(&[[0.0, 0.0], [100.0, 0.0]], EndBehaviour::PingPong, 5.0);
        let pieces = ok(pp.wake_pieces(24.0, 600.0, 1.0, 1.0, 32));
        assert_eq!(pieces.len(), 2, "{pieces:?}");
        assert!((pieces[0].reach_m - 20.0).abs() <= 1.0 && (pieces[0].heading.abs() - PI).abs() < 1e-6);
        assert!(pieces[1].heading.abs() < 1e-6 && pieces[1].reach_m.is_infinite());
        assert!((pieces[1].age_s - 4.0).abs() <= 0.2 && (pieces[1].x - 100.0).abs() <= 1.0, "{:?}", pieces[1]);
        // A circle of radius 100 m: pieces of about √(2 R tol), all on the circle, the last going on straight.
        let r = 100.0;
        let circle = straight_test_vessel(&ring(r), EndBehaviour::Loop, 5.0);
        let pieces = ok(circle.wake_pieces(60.0, 300.0, 0.5, 2.0, 32));
        let want = (2.0 * r * 2.0_f64).sqrt();
        for p in &pieces[..pieces.len() - 1] {
            assert!((p.reach_m - want).abs() < 0.15 * want, "{p:?} against {want}");
            assert!((p.x.hypot(p.y) - r).abs() < 0.5, "{p:?}");
        }
        // The pieces cover the 300 m asked for (the last reaching on): their starts are that far back in time.
        let covered = pieces[pieces.len() - 1].age_s * 5.0;
        assert!(covered > 300.0 - 1.1 * want && covered < 300.0, "{covered}");
        // Capped: the last of `max_pieces` goes on straight.
        let few = ok(circle.wake_pieces(60.0, 300.0, 0.5, 2.0, 3));
        assert_eq!(few.len(), 3);
        assert!(few[2].reach_m.is_infinite() && few[1].reach_m.is_finite());
        // At rest at the end (there at `t_end`, its route's length at 5 m/s): the pieces it had on arriving, each as
        // much older as it has lain there, until the oldest is older than the reach asked.
        let t_end = (el.route.length() - el.params.start_offset_m) / speed;
        let arrived = ok(el.wake_pieces(t_end, 600.0, 1.0, tol, 32));
        for later in [t_end + 0.5, t_end + 30.0] {
            let rest = ok(el.wake_pieces(later, 600.0, 1.0, tol, 32));
            assert!(!rest.is_empty() && rest.len() <= arrived.len(), "{rest:?}");
            // (The last one reaches on straight, from wherever the reach asked ends.)
            for (a, b) in arrived.iter().zip(&rest[..rest.len() - 1]) {
                assert!((b.age_s - a.age_s - (later - t_end)).abs() < 1e-9, "{a:?} {b:?}");
                assert!((a.x - b.x).hypot(a.y - b.y) < 1e-9 && (a.heading - b.heading).abs() < 1e-9, "{a:?} {b:?}");
            }
            // Covered back to where the path was `max_m` at arrival, less what has aged out.
            let back = rest[rest.len() - 1].age_s * speed;
            assert!(back <= 600.0 && (rest[0].age_s - (later - t_end)).abs() < 1e-9, "{rest:?}");
        }
        let at_end = el.route.position(el.route.length());
        assert!((arrived[0].x - at_end[0]).hypot(arrived[0].y - at_end[1]) < 1e-9, "{arrived:?}");
        assert!((arrived[0].heading - PI / 2.0).abs() < 0.05 && arrived[0].age_s == 0.0, "{arrived:?}");
        assert!(ok(el.wake_pieces(1000.0, 600.0, 1.0, 2.0, 32)).is_empty(), "at rest for 900 s: 4,500 m of path ago");
        // Parked at its route's end from the start: no wake at any time.
        let mut parked = straight_test_vessel(&[[0.0, 0.0], [100.0, 0.0]], EndBehaviour::Stop, 5.0);
        for offset in [parked.route.length(), 150.0] {
            parked.params.start_offset_m = offset;
            for t in [0.0, 1.0, 30.0] {
                assert!(ok(parked.wake_pieces(t, 600.0, 1.0, 2.0, 32)).is_empty(), "{offset} {t}");
            }
        }
        assert!(el.wake_pieces(1.0, 600.0, 0.0, 2.0, 32).is_err());
    }
}
