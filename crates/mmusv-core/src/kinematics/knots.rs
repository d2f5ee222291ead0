//! A route's knots: the points along it between which its heading turns by at most half a degree, nearly linearly
//! in arc length, so that a quantity of the course (the hull's steady-state response, [`super::transient`]) can be
//! taken linear between them. A turn's start and end are knots; a straight route has only its ends.

use super::spline::{wrap_angle, Route};
use std::f64::consts::PI;

/// The most the heading turns between two knots of a route (half a degree): a steady state near roll resonance
/// changes over a few degrees of heading at the speeds of small craft, and is taken linear between knots.
pub const KNOT_TURN_RAD: f64 = PI / 360.0;

/// The most samples between two knots (a long straight track gets a knot every 64 samples, 8 waypoint segments,
/// which keeps the search linear in the route's length).
const MAX_KNOT_RUN: usize = 64;

/// The shortest step (m) the knots' search bisects down to (a waypoint that doubles back turns the heading by π at
/// once).
const MIN_KNOT_STEP_M: f64 = 1e-3;

/// The arc lengths (m, ascending, from 0 to the route's length) of the route's knots: its two ends and, along it,
/// points such that between two knots the heading turns by at most [`KNOT_TURN_RAD`] and stays within a quarter of
/// it of the heading taken linear in arc length between them (so a turn's start and end are knots: a bend followed
/// by a straight leg is not taken as turning all along the leg). A straight route has only its ends. Found by
/// sampling each segment 8 times, bisected where a step turns by more than a fifth of [`KNOT_TURN_RAD`], and
/// placing each knot at the last sample that keeps both rules from the previous one.
pub fn route_knots(route: &Route) -> Vec<f64> {
    let len = route.length();
    let mut knots = vec![0.0];
    if len.is_nan() || len <= 0.0 {
        return knots;
    }
    // Samples (arc length, heading unwrapped along the route).
    let mut samples = vec![(0.0, route.yaw(0.0))];
    for seg in route.waypoint_arc_lengths().windows(2) {
        let (a, b) = (seg[0], seg[1]);
        for j in 1..=8 {
            let s = if j == 8 { b } else { a + (b - a) * f64::from(j) / 8.0 };
            let mut stack = vec![(s, route.yaw(s))];
            // Bisect (last sample, top] until each step turns by at most a fifth of a knot's turn.
            while let Some(&(sb, yb)) = stack.last() {
                let (sa, ya) = samples[samples.len() - 1];
                let turn = wrap_angle(yb - ya);
                if turn.abs() > 0.2 * KNOT_TURN_RAD && sb - sa > MIN_KNOT_STEP_M {
                    let m = 0.5 * (sa + sb);
                    stack.push((m, route.yaw(m)));
                } else {
                    stack.pop();
                    if sb > sa {
                        samples.push((sb, ya + turn));
                    }
                }
            }
        }
    }
    // Greedy: the knot's run grows while every sample in it keeps both rules; else its previous sample is a knot.
    let fits = |run: &[(f64, f64)]| -> bool {
        let ((s0, y0), (s1, y1)) = (run[0], run[run.len() - 1]);
        (y1 - y0).abs() <= KNOT_TURN_RAD
            && run.iter().all(|&(s, y)| (y - (y0 + (y1 - y0) * (s - s0) / (s1 - s0))).abs() <= 0.25 * KNOT_TURN_RAD)
    };
    let mut start = 0;
    for i in 1..samples.len() {
        if i - start >= 2 && (i - start > MAX_KNOT_RUN || !fits(&samples[start..=i])) {
            knots.push(samples[i - 1].0);
            start = i - 1;
        }
    }
    if len > knots[knots.len() - 1] {
        knots.push(len);
    }
    knots
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::kinematics::EndBehaviour;

    fn ok<T, E: std::fmt::Display>(r: std::result::Result<T, E>) -> T {
        r.unwrap_or_else(|e| unreachable!("{e}"))
    }

    /// A square of 120 m sides, straight along its sides (collinear waypoints) and with its corners rounded by the
    /// spline (about 15 m of radius); the transient tests sail it too.
    pub(crate) fn square(end: EndBehaviour) -> Route {
        let side = [0.0, 40.0, 80.0];
        let mut pts: Vec<[f64; 2]> = side.iter().map(|&x| [x, 0.0]).collect();
        pts.extend(side.iter().map(|&y| [120.0, y]));
        pts.extend(side.iter().map(|&x| [120.0 - x, 120.0]));
        pts.extend(side.iter().map(|&y| [0.0, 120.0 - y]));
        ok(Route::new(&pts, end))
    }

    #[test]
    fn knots_split_the_route_where_the_heading_turns_by_half_a_degree() {
        let line = ok(Route::new(&[[0.0, 0.0], [80.0, 30.0]], EndBehaviour::Stop));
        assert_eq!(route_knots(&line), vec![0.0, line.length()]);
        for end in [EndBehaviour::Stop, EndBehaviour::Loop] {
            let r = square(end);
            let knots = route_knots(&r);
            assert!(knots.windows(2).all(|w| w[1] > w[0]) && knots[0] == 0.0);
            assert_eq!(knots.last().copied(), Some(r.length()));
            // Densely sampled (1 cm): between two knots the heading stays within a knot's turn of the first.
            let (mut turned, mut k) = (0.0f64, 0);
            let n = (r.length() / 0.01) as usize;
            let mut prev = r.yaw(0.0);
            for i in 0..=n {
                let s = r.length() * i as f64 / n as f64;
                while k + 1 < knots.len() && knots[k + 1] <= s {
                    k += 1;
                }
                let y = r.yaw(s);
                assert!(wrap_angle(y - r.yaw(knots[k])).abs() <= KNOT_TURN_RAD + 1e-6, "{s} {k}");
                if k + 1 < knots.len() {
                    // Within a quarter of a knot's turn of the heading taken linear between the two knots.
                    let (ya, yb) = (r.yaw(knots[k]), r.yaw(knots[k + 1]));
                    let f = (s - knots[k]) / (knots[k + 1] - knots[k]);
                    let lin = ya + wrap_angle(yb - ya) * f;
                    assert!(wrap_angle(y - lin).abs() <= 0.3 * KNOT_TURN_RAD, "{s} {k} {y} {lin}");
                }
                turned += wrap_angle(y - prev).abs();
                prev = y;
            }
            // No more knots than one per 0.8 knot's turn of the total turn, with the legs' own few.
            let degrees = turned / KNOT_TURN_RAD;
            let count = knots.len() as f64;
            assert!(count < 1.25 * degrees + 24.0 && count > 0.9 * degrees, "{degrees} {count}");
        }
        // A bend and then a straight leg of 2 km: the turn's end is a knot (within a metre of where the heading
        // settles), not the leg's far end.
        let r = ok(Route::new(&[[0.0, 0.0], [60.0, 0.0], [60.0, 40.0], [60.0, 2000.0]], EndBehaviour::Stop));
        let knots = route_knots(&r);
        let settled = (0..20_000)
            .map(|i| r.length() * f64::from(i) / 20_000.0)
            .find(|&s| s > 100.0 && wrap_angle(r.yaw(s) - r.yaw(r.length())).abs() < 1e-9)
            .unwrap_or(r.length());
        let last_bend_knot = knots.iter().rev().nth(1).copied().unwrap_or(0.0);
        assert!(last_bend_knot < settled + 40.0, "{last_bend_knot} {settled}");
    }
}
