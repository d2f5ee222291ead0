//! Planar routes: a centripetal Catmull–Rom spline through waypoints, parameterised by arc length
//! (paper eq. 1: `c_v(d)` with `d` the distance travelled).
//!
//! Segment `i` runs from waypoint `P₁ = P_i` to `P₂ = P_{i+1}` with neighbours `P₀`, `P₃`; knot gaps are
//! `Δ_k = |P_{k+1} − P_k|^½` (centripetal, so no cusps or self-intersections inside a segment). In Hermite form,
//! with `m₁ = (P₁−P₀)/Δ₀ − (P₂−P₀)/(Δ₀+Δ₁) + (P₂−P₁)/Δ₁` and `m₂` likewise at `P₂`, and `c = Δ₁·m₁`, `e = Δ₁·m₂`:
//!
//! ```text
//! p(u) = (2P₁ − 2P₂ + c + e)·u³ + (−3P₁ + 3P₂ − 2c − e)·u² + c·u + P₁,   u ∈ [0, 1]
//! ```
//!
//! The tangent at a waypoint depends only on its two neighbours and the knot gaps, so adjacent segments share
//! it: the curve is C1 in the knot parameter and, after re-parameterising by arc length, has a continuous unit
//! tangent. Open routes get phantom end points `P₋₁ = 2P₀ − P₁` and `P_n = 2P_{n−1} − P_{n−2}`, so two
//! waypoints give a straight segment; looped routes wrap the neighbours around.
//!
//! Arc length: every segment is cut into [`SUBDIVISIONS`] equal `u` intervals, each integrated with 5-point
//! Gauss–Legendre; `s → u` is inverted by binary search over that table and a safeguarded Newton iteration.

use crate::error::{MmusvError, Result};
use std::f64::consts::PI;

/// Number of `u` intervals per segment in the arc-length table.
pub const SUBDIVISIONS: usize = 32;

/// Smallest allowed distance between consecutive waypoints, in metres.
pub const MIN_WAYPOINT_SPACING_M: f64 = 1e-6;

/// 5-point Gauss–Legendre nodes and weights on `[-1, 1]`.
const GL_NODES: [f64; 5] =
    [0.0, -0.538_469_310_105_683_1, 0.538_469_310_105_683_1, -0.906_179_845_938_664, 0.906_179_845_938_664];
const GL_WEIGHTS: [f64; 5] = [
    0.568_888_888_888_888_9,
    0.478_628_670_499_366_5,
    0.478_628_670_499_366_5,
    0.236_926_885_056_189_1,
    0.236_926_885_056_189_1,
];

/// What a vessel does once it has travelled the whole route.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EndBehaviour {
    /// Stay at the last waypoint, at rest, keeping the final heading.
    #[default]
    Stop,
    /// The route is closed (last waypoint joins back to the first, C1 at the join) and is travelled round and round.
    Loop,
    /// Go back and forth along the open route; the yaw flips by π when reversing.
    PingPong,
}

impl EndBehaviour {
    /// Parses `"stop"`, `"loop"` or `"ping_pong"` (also `"pingpong"`, `"ping-pong"`; case-insensitive).
    pub fn parse(name: &str) -> Result<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "stop" => Ok(Self::Stop),
            "loop" => Ok(Self::Loop),
            "ping_pong" | "pingpong" | "ping-pong" => Ok(Self::PingPong),
            _ => Err(MmusvError::config(
                "end_behaviour",
                format!("{name:?}"),
                "allowed values are stop, loop, ping_pong",
            )),
        }
    }
}

/// One cubic `p(u) = ((a·u + b)·u + c)·u + d`.
#[derive(Debug, Clone, Copy)]
struct Cubic {
    a: [f64; 2],
    b: [f64; 2],
    c: [f64; 2],
    d: [f64; 2],
}

impl Cubic {
    fn centripetal(p0: [f64; 2], p1: [f64; 2], p2: [f64; 2], p3: [f64; 2]) -> Self {
        let d0 = dist(p0, p1).sqrt();
        let d1 = dist(p1, p2).sqrt();
        let d2 = dist(p2, p3).sqrt();
        let mut a = [0.0; 2];
        let mut b = [0.0; 2];
        let mut c = [0.0; 2];
        for k in 0..2 {
            let m1 = (p1[k] - p0[k]) / d0 - (p2[k] - p0[k]) / (d0 + d1) + (p2[k] - p1[k]) / d1;
            let m2 = (p2[k] - p1[k]) / d1 - (p3[k] - p1[k]) / (d1 + d2) + (p3[k] - p2[k]) / d2;
            let (ck, ek) = (m1 * d1, m2 * d1);
            a[k] = 2.0 * p1[k] - 2.0 * p2[k] + ck + ek;
            b[k] = -3.0 * p1[k] + 3.0 * p2[k] - 2.0 * ck - ek;
            c[k] = ck;
        }
        Self { a, b, c, d: p1 }
    }

    fn pos(&self, u: f64) -> [f64; 2] {
        std::array::from_fn(|k| ((self.a[k] * u + self.b[k]) * u + self.c[k]) * u + self.d[k])
    }

    fn deriv(&self, u: f64) -> [f64; 2] {
        std::array::from_fn(|k| (3.0 * self.a[k] * u + 2.0 * self.b[k]) * u + self.c[k])
    }

    fn speed(&self, u: f64) -> f64 {
        let [x, y] = self.deriv(u);
        x.hypot(y)
    }

    /// `∫ |p'(u)| du` over `[lo, hi]` by 5-point Gauss–Legendre.
    fn arc(&self, lo: f64, hi: f64) -> f64 {
        let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        half * GL_NODES.iter().zip(GL_WEIGHTS).map(|(x, w)| w * self.speed(mid + half * x)).sum::<f64>()
    }
}

fn dist(p: [f64; 2], q: [f64; 2]) -> f64 {
    (q[0] - p[0]).hypot(q[1] - p[1])
}

/// Wraps an angle into `[-π, π)`.
pub fn wrap_angle(a: f64) -> f64 {
    (a + PI).rem_euclid(2.0 * PI) - PI
}

/// A planar route through waypoints, parameterised by arc length `s ∈ [0, length]` (metres).
#[derive(Debug, Clone)]
pub struct Route {
    waypoints: Vec<[f64; 2]>,
    end: EndBehaviour,
    cubics: Vec<Cubic>,
    /// Arc length at the start of each segment, plus the total at the end (`cubics.len() + 1` entries).
    seg_start: Vec<f64>,
    /// Per segment, `SUBDIVISIONS + 1` cumulative arc lengths from the segment start.
    sub: Vec<f64>,
}

impl Route {
    /// Builds the route through `waypoints` (x east, y north, metres).
    ///
    /// Needs at least 2 finite waypoints (3 for [`EndBehaviour::Loop`]) with consecutive ones at least
    /// [`MIN_WAYPOINT_SPACING_M`] apart. For a loop the last waypoint joins back to the first; a last waypoint
    /// repeating the first is dropped. Errors are [`MmusvError::Config`] naming `route` or `route[i]`.
    pub fn new(waypoints: &[[f64; 2]], end: EndBehaviour) -> Result<Self> {
        if let Some(i) = waypoints.iter().position(|p| !(p[0].is_finite() && p[1].is_finite())) {
            return Err(MmusvError::config(
                format!("route[{i}]"),
                format!("{:?}", waypoints[i]),
                "waypoints must be finite [x, y] in metres",
            ));
        }
        let mut pts = waypoints.to_vec();
        if end == EndBehaviour::Loop && pts.len() > 2 {
            if let (Some(first), Some(last)) = (pts.first(), pts.last()) {
                if dist(*first, *last) < MIN_WAYPOINT_SPACING_M {
                    pts.pop();
                }
            }
        }
        let need = if end == EndBehaviour::Loop { 3 } else { 2 };
        if pts.len() < need {
            let what = if end == EndBehaviour::Loop {
                "a looped route needs at least 3 distinct waypoints"
            } else {
                "a route needs at least 2 waypoints"
            };
            return Err(MmusvError::config("route", format!("{} waypoint(s)", waypoints.len()), what));
        }
        let n = pts.len();
        let closing = usize::from(end == EndBehaviour::Loop);
        for i in 1..n + closing {
            let (p, q) = (pts[i - 1], pts[i % n]);
            if dist(p, q) < MIN_WAYPOINT_SPACING_M {
                return Err(MmusvError::config(
                    format!("route[{}]", i % n),
                    format!("{q:?}"),
                    format!(
                        "consecutive waypoints must be at least {MIN_WAYPOINT_SPACING_M} m apart \
                         (it repeats route[{}])",
                        i - 1
                    ),
                ));
            }
        }
        let at = |i: isize| -> [f64; 2] {
            let ni = n as isize;
            if end == EndBehaviour::Loop {
                pts[i.rem_euclid(ni) as usize]
            } else if i < 0 {
                [2.0 * pts[0][0] - pts[1][0], 2.0 * pts[0][1] - pts[1][1]]
            } else if i >= ni {
                let (l, m) = (pts[n - 1], pts[n - 2]);
                [2.0 * l[0] - m[0], 2.0 * l[1] - m[1]]
            } else {
                pts[i as usize]
            }
        };
        let nseg = n - 1 + closing;
        let cubics: Vec<Cubic> =
            (0..nseg as isize).map(|i| Cubic::centripetal(at(i - 1), at(i), at(i + 1), at(i + 2))).collect();
        let mut seg_start = Vec::with_capacity(nseg + 1);
        let mut sub = Vec::with_capacity(nseg * (SUBDIVISIONS + 1));
        let mut total = 0.0;
        for cubic in &cubics {
            seg_start.push(total);
            let mut acc = 0.0;
            sub.push(0.0);
            for j in 0..SUBDIVISIONS {
                acc += cubic.arc(j as f64 / SUBDIVISIONS as f64, (j + 1) as f64 / SUBDIVISIONS as f64);
                sub.push(acc);
            }
            total += acc;
        }
        seg_start.push(total);
        // Finite waypoints can still be too far apart for an arc length (beyond ~1e154 m the squares overflow).
        if !total.is_finite() {
            return Err(MmusvError::config(
                "route",
                format!("{} waypoints", pts.len()),
                "the route's length is not finite: waypoints must lie within reach of one another in metres",
            ));
        }
        Ok(Self { waypoints: pts, end, cubics, seg_start, sub })
    }

    /// The waypoints the route passes through (for a loop, without a repeated closing point).
    pub fn waypoints(&self) -> &[[f64; 2]] {
        &self.waypoints
    }

    /// What happens at the end of the route.
    pub fn end_behaviour(&self) -> EndBehaviour {
        self.end
    }

    /// Total arc length in metres (for a loop, including the closing segment back to the first waypoint).
    pub fn length(&self) -> f64 {
        self.seg_start.last().copied().unwrap_or(0.0)
    }

    /// Arc length at which each waypoint is passed; for a loop a last entry equal to [`Route::length`] marks the
    /// return to the first waypoint.
    pub fn waypoint_arc_lengths(&self) -> &[f64] {
        &self.seg_start
    }

    /// Segment index and spline parameter `u ∈ [0, 1]` at arc length `s` (wrapped for a loop, else clamped).
    fn locate(&self, s: f64) -> (usize, f64) {
        let len = self.length();
        let s = if s.is_nan() {
            0.0
        } else if self.end == EndBehaviour::Loop && len > 0.0 && !(0.0..len).contains(&s) {
            s.rem_euclid(len)
        } else {
            s.clamp(0.0, len)
        };
        let nseg = self.cubics.len();
        let i = self.seg_start.partition_point(|&x| x <= s).saturating_sub(1).min(nseg.saturating_sub(1));
        let local = s - self.seg_start[i];
        let tab = &self.sub[i * (SUBDIVISIONS + 1)..(i + 1) * (SUBDIVISIONS + 1)];
        let j = tab.partition_point(|&x| x <= local).saturating_sub(1).min(SUBDIVISIONS - 1);
        let (mut lo, mut hi) = (j as f64 / SUBDIVISIONS as f64, (j + 1) as f64 / SUBDIVISIONS as f64);
        let u0 = lo;
        let target = local - tab[j];
        let span = tab[j + 1] - tab[j];
        if span <= 0.0 {
            return (i, lo);
        }
        let cubic = &self.cubics[i];
        let mut u = lo + (hi - lo) * (target / span).clamp(0.0, 1.0);
        let tol = 1e-13 * len.max(1.0);
        for _ in 0..50 {
            let f = cubic.arc(u0, u) - target;
            if f.abs() <= tol {
                break;
            }
            if f > 0.0 {
                hi = u;
            } else {
                lo = u;
            }
            let speed = cubic.speed(u);
            let newton = u - f / speed;
            u = if speed > 0.0 && newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
            if hi - lo < 1e-15 {
                break;
            }
        }
        (i, u)
    }

    /// Position `[x, y]` at arc length `s` (wrapped modulo the length for a loop, else clamped to `[0, length]`).
    pub fn position(&self, s: f64) -> [f64; 2] {
        let (i, u) = self.locate(s);
        self.cubics[i].pos(u)
    }

    /// Unit tangent `dc/ds` at arc length `s` (same domain as [`Route::position`]).
    pub fn tangent(&self, s: f64) -> [f64; 2] {
        let (i, u) = self.locate(s);
        let cubic = &self.cubics[i];
        let mut d = cubic.deriv(u);
        let mut n = d[0].hypot(d[1]);
        if n < 1e-9 {
            // A cusp (a waypoint that doubles back, e.g. A → B → A): use the chord around it instead.
            let (lo, hi) = ((u - 1e-4).max(0.0), (u + 1e-4).min(1.0));
            let (p, q) = (cubic.pos(lo), cubic.pos(hi));
            d = [q[0] - p[0], q[1] - p[1]];
            n = d[0].hypot(d[1]);
        }
        if n > 0.0 {
            [d[0] / n, d[1] / n]
        } else {
            [1.0, 0.0]
        }
    }

    /// Heading `atan2(t_y, t_x)` of the tangent at arc length `s`, in radians in `(-π, π]`.
    pub fn yaw(&self, s: f64) -> f64 {
        let [x, y] = self.tangent(s);
        y.atan2(x)
    }

    /// Heading (radians, in `[-π, π]`) of a vessel at arc length `s` travelling in direction `sign` (from
    /// [`Route::distance_to_arc`]): the tangent's, turned by π when travelling backwards (`sign` < 0).
    pub fn heading(&self, s: f64, sign: f64) -> f64 {
        let yaw = self.yaw(s);
        if sign < 0.0 {
            wrap_angle(yaw + std::f64::consts::PI)
        } else {
            yaw
        }
    }

    /// World-frame horizontal velocity (m/s) of a vessel at arc length `s` travelling in direction `sign` at
    /// `speed` m/s: `speed · sign · tangent(s)` (zero at rest).
    pub fn velocity(&self, s: f64, sign: f64, speed: f64) -> [f64; 2] {
        let v = speed * sign;
        let [tx, ty] = if v == 0.0 { [0.0, 0.0] } else { self.tangent(s) };
        [v * tx, v * ty]
    }

    /// Maps a travelled distance `d = offset + u·t` (metres) to `(s, sign)` on the route.
    ///
    /// - [`EndBehaviour::Stop`]: `s = clamp(d, 0, L)`; `sign = +1` while `d < L`, `0` once at rest at the end.
    /// - [`EndBehaviour::Loop`]: `s = d mod L`, `sign = +1`.
    /// - [`EndBehaviour::PingPong`]: with `r = d mod 2L`, `s = r, sign = +1` for `r ≤ L`, else `s = 2L − r,
    ///   sign = −1` (travelling backwards, heading `yaw(s) + π`).
    ///
    /// The horizontal velocity is `u · sign · tangent(s)`. A non-finite `d` gives `(0, 0)` (the kinematics refuses
    /// such times before asking).
    pub fn distance_to_arc(&self, d: f64) -> (f64, f64) {
        let len = self.length();
        if !d.is_finite() || len <= 0.0 {
            return (0.0, 0.0);
        }
        match self.end {
            EndBehaviour::Stop if d >= len => (len, 0.0),
            EndBehaviour::Stop => (d.max(0.0), 1.0),
            EndBehaviour::Loop => (d.rem_euclid(len), 1.0),
            EndBehaviour::PingPong => {
                let r = d.rem_euclid(2.0 * len);
                if r <= len {
                    (r, 1.0)
                } else {
                    (2.0 * len - r, -1.0)
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CURVY: [[f64; 2]; 6] = [[0.0, 0.0], [40.0, 10.0], [60.0, 55.0], [20.0, 80.0], [-30.0, 60.0], [-45.0, 5.0]];

    fn route(pts: &[[f64; 2]], end: EndBehaviour) -> Route {
        Route::new(pts, end).unwrap_or_else(|e| unreachable!("{e}"))
    }

    /// Sum of chord lengths of `n` equally spaced samples in `[a, b]` (arc-length space).
    fn chord_sum(r: &Route, a: f64, b: f64, n: usize) -> f64 {
        let mut prev = r.position(a);
        let mut acc = 0.0;
        for k in 1..=n {
            let p = r.position(a + (b - a) * k as f64 / n as f64);
            acc += dist(prev, p);
            prev = p;
        }
        acc
    }

    #[test]
    fn two_points_give_a_straight_segment() {
        let r = route(&[[1.0, 2.0], [4.0, 6.0]], EndBehaviour::Stop);
        assert!((r.length() - 5.0).abs() < 1e-12);
        let p = r.position(2.5);
        assert!((p[0] - 2.5).abs() < 1e-9 && (p[1] - 4.0).abs() < 1e-9);
        assert!((r.yaw(1.0) - 4.0f64.atan2(3.0)).abs() < 1e-12);
    }

    #[test]
    fn arc_length_is_honoured() {
        for end in [EndBehaviour::Stop, EndBehaviour::Loop] {
            let r = route(&CURVY, end);
            let len = r.length();
            let total = chord_sum(&r, 0.0, len, 200_000);
            assert!(((total - len) / len).abs() < 1e-4, "{end:?}: chords {total} vs length {len}");
            for (a, b) in [(3.0, 17.5), (50.0, 140.0), (0.3 * len, 0.9 * len)] {
                let piece = chord_sum(&r, a, b, 50_000);
                assert!(((piece - (b - a)) / (b - a)).abs() < 1e-4, "{end:?} [{a}, {b}]: {piece}");
            }
        }
    }

    #[test]
    fn yaw_follows_the_finite_difference_direction() {
        for end in [EndBehaviour::Stop, EndBehaviour::Loop] {
            let r = route(&CURVY, end);
            let h = 1e-4;
            for k in 1..400 {
                let s = r.length() * k as f64 / 400.0;
                let (p, q) = (r.position(s - h), r.position(s + h));
                let fd = (q[1] - p[1]).atan2(q[0] - p[0]);
                assert!(wrap_angle(fd - r.yaw(s)).abs() < 1e-4, "s={s}");
                // Unit speed in arc length.
                assert!((dist(p, q) / (2.0 * h) - 1.0).abs() < 1e-4);
            }
        }
    }

    #[test]
    fn c1_at_interior_waypoints() {
        for end in [EndBehaviour::Stop, EndBehaviour::Loop] {
            let r = route(&CURVY, end);
            let n = r.cubics.len();
            let joins = if end == EndBehaviour::Loop { n } else { n - 1 };
            for i in 0..joins {
                let (a, b) = (&r.cubics[i], &r.cubics[(i + 1) % n]);
                let (pa, pb) = (a.pos(1.0), b.pos(0.0));
                let (da, db) = (a.deriv(1.0), b.deriv(0.0));
                assert!(dist(pa, pb) < 1e-9);
                // Derivatives in the knot parameter: u-derivative divided by the knot gap.
                let (ga, gb) = (dist(a.pos(0.0), pa).sqrt(), dist(pb, b.pos(1.0)).sqrt());
                assert!(dist([da[0] / ga, da[1] / ga], [db[0] / gb, db[1] / gb]) < 1e-9, "join {i} {end:?}");
                // And in arc length, from both sides of the waypoint.
                let s = r.waypoint_arc_lengths()[i + 1];
                let eps = 1e-7;
                assert!(dist(r.position(s - eps), r.position(s + eps)) < 1e-6);
                assert!(dist(r.tangent(s - eps), r.tangent(s + eps)) < 1e-5);
                let w = r.waypoints()[(i + 1) % n];
                assert!(dist(r.position(s), w) < 1e-6, "waypoint {} not on the curve", i + 1);
            }
        }
    }

    #[test]
    fn end_behaviours_map_distance() {
        let stop = route(&CURVY, EndBehaviour::Stop);
        let len = stop.length();
        assert_eq!(stop.distance_to_arc(0.5 * len), (0.5 * len, 1.0));
        assert_eq!(stop.distance_to_arc(3.0 * len), (len, 0.0));
        assert!(dist(stop.position(2.0 * len), CURVY[5]) < 1e-9);

        let lp = route(&CURVY, EndBehaviour::Loop);
        let ll = lp.length();
        assert!(ll > len);
        let (s, sign) = lp.distance_to_arc(2.0 * ll + 10.0);
        assert!((s - 10.0).abs() < 1e-9 && sign == 1.0);
        assert!(dist(lp.position(ll - 1e-9), CURVY[0]) < 1e-6);
        assert!(dist(lp.tangent(ll - 1e-7), lp.tangent(1e-7)) < 1e-5);

        let pp = route(&CURVY, EndBehaviour::PingPong);
        let (s, sign) = pp.distance_to_arc(len + 10.0);
        assert!((s - (len - 10.0)).abs() < 1e-9 && sign == -1.0);
        let (s, sign) = pp.distance_to_arc(2.0 * len + 10.0);
        assert!((s - 10.0).abs() < 1e-9 && sign == 1.0);

        // A closing waypoint that repeats the first is dropped for a loop.
        let mut closed = CURVY.to_vec();
        closed.push(CURVY[0]);
        let again = route(&closed, EndBehaviour::Loop);
        assert!((again.length() - ll).abs() < 1e-9);
    }

    #[test]
    fn bad_routes_are_config_errors() {
        let field_of = |pts: &[[f64; 2]], end| match Route::new(pts, end) {
            Err(MmusvError::Config { field, .. }) => field,
            other => unreachable!("expected a config error, got {other:?}"),
        };
        assert_eq!(field_of(&[[0.0, 0.0]], EndBehaviour::Stop), "route");
        assert_eq!(field_of(&[], EndBehaviour::PingPong), "route");
        assert_eq!(field_of(&[[0.0, 0.0], [1.0, 0.0]], EndBehaviour::Loop), "route");
        assert_eq!(field_of(&[[0.0, 0.0], [f64::NAN, 1.0]], EndBehaviour::Stop), "route[1]");
        assert_eq!(field_of(&[[0.0, 0.0], [5.0, 1.0], [5.0, 1.0 + 1e-8]], EndBehaviour::Stop), "route[2]");
        assert!(matches!(EndBehaviour::parse("bounce"), Err(MmusvError::Config { .. })));
        assert_eq!(EndBehaviour::parse("Ping_Pong"), Ok(EndBehaviour::PingPong));
    }

    #[test]
    fn cusp_and_nan_do_not_panic() {
        let r = route(&[[0.0, 0.0], [10.0, 0.0], [0.0, 0.0]], EndBehaviour::Stop);
        let s = r.waypoint_arc_lengths()[1];
        let t = r.tangent(s);
        assert!((t[0].hypot(t[1]) - 1.0).abs() < 1e-9);
        assert!(r.position(f64::NAN).iter().all(|v| v.is_finite()));
        assert_eq!(r.distance_to_arc(f64::NAN), (0.0, 0.0));
    }

    #[test]
    fn a_route_too_long_to_measure_is_refused() {
        let far = Route::new(&[[-1e308, 100.0], [1e308, 100.0]], EndBehaviour::Stop);
        assert!(matches!(far, Err(MmusvError::Config { ref field, .. }) if field == "route"), "{far:?}");
        assert!(Route::new(&[[-1e6, 100.0], [1e6, 100.0]], EndBehaviour::Stop).is_ok());
    }
}
