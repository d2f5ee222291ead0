//! The hull's response remembers its recent course. The steady-state response of [`crate::ocean::response()`] (the
//! RAOs at the heading and encounter frequencies of the moment) changes with the course: at once where a `Stop` route
//! ends (the hull comes to rest) or a `PingPong` route turns about (its heading flips by π), and quickly in a tight
//! bend. A damped hull cannot follow such a change faster than its own free oscillation decays. Without memory the
//! heave, roll and pitch stepped at a stop or a turn about (0.76 m of heave between two frames, 15° of roll), and in a
//! bend a small craft's roll swept through its resonance with the heading: a 5 m speedboat at 9 m/s round a 16 m
//! bend rolled at 158°/s, against 29°/s on its legs (`island_port_waves`' `target_1` at W1).
//!
//! Model: a linear damped oscillator whose forcing changes responds, wave component by wave component, with a
//! complex amplitude that relaxes towards the steady state of the moment with the envelope of its free transient,
//! `e^{−ζ ω_n τ}` (e.g. Newland, D. E. (1989), *Mechanical Vibration Analysis and Computation*, ch. 2; for ship
//! roll, Lloyd, A. R. J. M. (1989), *Seakeeping: Ship Behaviour in Rough Weather*, §9). With `G(s)` the steady-state
//! gains (the complex RAO of each wave component and mode) of the hull's course (heading and velocity) at time `s`:
//!
//! ```text
//! A(t) = κ · ( ∫₀^W λ e^{−λτ} G(t − τ) dτ + e^{−λW} G(t − W) ),   λ = ζ ω_φ
//! κ²   = ( ∫₀^W λ e^{−λτ} σ²(t − τ) dτ + e^{−λW} σ²(t − W) ) / Σ_c a_c²/2 |A_c / κ|²      (per mode)
//! ```
//!
//! and the response `Σ_c Re(A_c a_c e^{iψ_c})` at the hull's position now. `λ` is the roll's (the least damped of
//! the three modes, so its envelope bounds the heave's and the pitch's); `σ²(s) = Σ_c a_c²/2 |G_c(s)|²` is the
//! steady state's variance over the field's random phases, and `κ` keeps the response's variance the kernel's mean of
//! the steady variances it remembers (averaging gains whose phases differ would otherwise take energy out of the
//! motion: 1–2 % of the roll over 20 minutes of turns about in `island_port_waves`). Before `t = 0` the hull is
//! taken in the steady state of its course at `t = 0`, and beyond the memory `W = −ln(`[`MEMORY`]`)/λ` (13.8/λ:
//! 35 s for a WAM-V, 6 minutes for the 190 m bulk carrier, 10 for the 300 m container ship) in that of its course
//! at `t − W`, so the pose is continuous in time. Where the course has not changed over the window (a straight
//! leg, or at rest), `A = G(t)` exactly.
//!
//! Quadrature: `G` is taken linear in time between the route's knots ([`route_knots`]: points between which the
//! heading turns by less than [`super::knots::KNOT_TURN_RAD`], nearly linearly, so a turn's start and end are knots)
//! and the two courses of each route event (a stop, a turn about: both at the same time), with the kernel's weights
//! exact for that; the course now is worked out afresh, the window's start is taken linear between its two knots,
//! and each knot's gains are worked out once per vessel for the whole run ([`KnotGains`], which a [`super::Fleet`]
//! in a sea keeps). At a single event on a straight route this is the
//! blend `κ (w G_before + (1 − w) G_after)`, `w = e^{−λ (t − t_e)}`, of the two steady states.
//!
//! Approximations: the free oscillation at the natural frequency itself is not drawn, and every component relaxes at
//! the roll's rate, where in the oscillator one far from resonance follows the change faster.

use super::knots::route_knots;
use super::spline::{wrap_angle, EndBehaviour, Route};
use super::VesselParams;
use crate::ocean::response::{encounter_frequency, response};
use crate::ocean::{Hull, WaveField};
use std::collections::HashMap;
use std::fmt;
use std::sync::{Arc, Mutex, MutexGuard, OnceLock, PoisonError};

/// The weight of the kernel at the memory's end: a course older than that counts as the one the hull had then (its
/// share of the difference between two steady states, at most a few metres or radians, is then under a few
/// micrometres or microradians).
pub const MEMORY: f64 = 1e-6;

/// The most knots one response remembers, on average: the memory is at most as long as the hull takes to pass that
/// many at its route's mean knot spacing (a route short and tight enough to pass more within the kernel's memory,
/// such as a 3 m circle at 20 m/s, is remembered that far back, its tail then weighing several per cent: the pose stays
/// continuous, its rate kinks at each knot). A window holds at most twice this many points and the route's own knots
/// besides (a `ping_pong` route's ends count on both sides of each turn about).
pub const MAX_POINTS: usize = 8192;

/// A course: heading (rad) and world velocity (m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Course {
    yaw: f64,
    vx: f64,
    vy: f64,
}

impl Course {
    /// The course at arc length `s` travelling in direction `sign` (0 at rest) at `speed`.
    fn on(route: &Route, s: f64, sign: f64, speed: f64) -> Self {
        let [vx, vy] = route.velocity(s, sign, speed);
        Self { yaw: route.heading(s, sign), vx, vy }
    }

    /// The course at knot `k` of `knots` (arc lengths) travelled forwards or backwards at `speed`.
    fn at_knot(route: &Route, knots: &[f64], k: usize, forwards: bool, speed: f64) -> Self {
        Self::on(route, knots[k], if forwards { 1.0 } else { -1.0 }, speed)
    }

    /// Whether `other` is this course to within 1e-12 (rad, m/s): a straight leg's headings differ in the last bits.
    fn same(&self, other: &Self) -> bool {
        wrap_angle(self.yaw - other.yaw).abs() <= 1e-12
            && (self.vx - other.vx).abs() <= 1e-12
            && (self.vy - other.vy).abs() <= 1e-12
    }
}

/// A point of the remembered course.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Point {
    /// Knot `k` of the route, travelled forwards (`true`) or backwards.
    Knot(usize, bool),
    /// The fraction `f` of the way from knot `k` to knot `k + 1`, travelled forwards or backwards: the steady state
    /// taken linear between them, as the quadrature takes it (the window's start).
    Between(usize, f64, bool),
    /// Any other course (the one now, and at rest).
    Fresh(Course),
}

/// Where a term of the sum comes from: a knot's steady state or a block's share (memoised), or a course's own.
#[derive(Debug, Clone, Copy)]
enum Source {
    Knot(usize, bool),
    Block(usize, bool),
    Fresh(Course),
}

/// A steady state: the complex gain of each wave component (field order) for heave, roll and pitch, and its
/// variance per mode over the field's random phases.
#[derive(Debug, Clone)]
pub struct Steady {
    gains: Vec<[[f64; 2]; 3]>,
    variance: [f64; 3],
}

impl Steady {
    /// Zero gains for `n` components, zero variances.
    fn zero(n: usize) -> Self {
        Self { gains: vec![[[0.0; 2]; 3]; n], variance: [0.0; 3] }
    }

    /// `self += w · other`, gain by gain and variance by variance.
    fn add(&mut self, w: f64, other: &Steady) {
        for (acc, g) in self.gains.iter_mut().zip(&other.gains) {
            for m in 0..3 {
                acc[m][0] += w * g[m][0];
                acc[m][1] += w * g[m][1];
            }
        }
        for m in 0..3 {
            self.variance[m] += w * other.variance[m];
        }
    }

    /// The steady state of `hull` on `course` in `field` (the RAOs at the encounter frequencies).
    fn of(field: &WaveField, hull: &Hull, course: Course) -> Self {
        let gains: Vec<_> = field
            .components()
            .iter()
            .map(|c| {
                let we = encounter_frequency(c.omega_rad_s, c.kx, c.ky, course.vx, course.vy);
                let h = hull.rao(c.omega_rad_s, c.direction_rad - course.yaw, we);
                [h.heave, h.roll, h.pitch]
            })
            .collect();
        let variance = variance_of(field, &gains);
        Self { gains, variance }
    }
}

/// `Σ_c a_c²/2 |g_c|²` per mode: the variance over the field's random phases of the response with gains `gains`
/// (field order).
fn variance_of(field: &WaveField, gains: &[[[f64; 2]; 3]]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (c, g) in field.components().iter().zip(gains) {
        let v = c.elevation_variance();
        for m in 0..3 {
            out[m] += v * (g[m][0] * g[m][0] + g[m][1] * g[m][1]);
        }
    }
    out
}

/// The steady states at one vessel's route knots, both directions, and the blocks' shares, each worked out on first
/// use and kept, at most [`MEMO_ENTRIES`] of each (past that the kept ones are let go and worked out again when
/// asked: the same values, so the poses do not depend on what is kept). Its route's knots ([`route_knots`]) are kept
/// for good. Shared between threads; a child forked from the process that made it keeps a memo of its own (the
/// parent's lock may have been held, at the fork, by a thread the child does not have: `crate::threads`).
pub struct KnotGains {
    knots: OnceLock<Vec<f64>>,
    kept: Mutex<Kept>,
    /// The process that made this memo.
    pid: u32,
    /// In a forked child: its own memo, and its process (never locked in the process that made this one).
    child: Mutex<Option<(u32, Arc<KnotGains>)>>,
}

impl Default for KnotGains {
    fn default() -> Self {
        Self { knots: OnceLock::new(), kept: Mutex::default(), pid: std::process::id(), child: Mutex::new(None) }
    }
}

/// The kept steady states: per knot and direction, and per block of [`BLOCK`] intervals between knots
/// (`b·BLOCK ..= (b+1)·BLOCK`) and direction, the kernel-weighted sum of its intervals' steady states relative to its
/// youngest knot ([`KnotGains::block`]).
#[derive(Default)]
struct Kept {
    knots: Shelf,
    blocks: Shelf,
}

/// Steady states kept by (knot or block index, travelled forwards).
type Shelf = HashMap<(usize, bool), Arc<Steady>>;

/// The most knots' steady states, and blocks' shares, one vessel's memo keeps (12 KiB each in a field of 256
/// components: at most 12 MiB a vessel). A pose needs a few dozen knots (at the memory's two ends) and a block per 32
/// knots between; a route with tens of thousands of knots (a jittery track of 40 km) does not keep them all.
pub const MEMO_ENTRIES: usize = 512;

/// Knot intervals summed as one in the kernel's sum where the whole block lies inside the memory: the kernel is an
/// exponential, so a block's share at any time is its share relative to its youngest knot times that knot's weight.
pub const BLOCK: usize = 32;

impl fmt::Debug for KnotGains {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let kept = self.lock();
        f.debug_struct("KnotGains")
            .field("knots", &self.knots.get().map_or(0, Vec::len))
            .field("kept_knots", &kept.knots.len())
            .field("kept_blocks", &kept.blocks.len())
            .finish()
    }
}

impl KnotGains {
    /// An empty memo.
    pub fn new() -> Self {
        Self::default()
    }

    fn knots(&self, route: &Route) -> &[f64] {
        self.knots.get_or_init(|| route_knots(route))
    }

    /// The memo of this process: `None` in the one that made it (use it), else the forked child's own.
    fn in_child(&self) -> Option<Arc<KnotGains>> {
        let pid = std::process::id();
        if pid == self.pid {
            return None;
        }
        let mut child = self.child.lock().unwrap_or_else(PoisonError::into_inner);
        match &*child {
            Some((p, memo)) if *p == pid => Some(Arc::clone(memo)),
            _ => {
                let memo = Arc::new(KnotGains::new());
                *child = Some((pid, Arc::clone(&memo)));
                Some(memo)
            }
        }
    }

    /// The kept states (a poisoned lock still holds whole entries: each is inserted complete).
    fn lock(&self) -> MutexGuard<'_, Kept> {
        self.kept.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// `map[key]`, or `make()` kept there (the map let go first when full).
    fn kept(&self, key: (usize, bool), map: fn(&mut Kept) -> &mut Shelf, make: impl FnOnce() -> Steady) -> Arc<Steady> {
        if let Some(s) = map(&mut self.lock()).get(&key) {
            return Arc::clone(s);
        }
        let made = Arc::new(make());
        let mut kept = self.lock();
        let m = map(&mut kept);
        if m.len() >= MEMO_ENTRIES {
            m.clear();
        }
        Arc::clone(m.entry(key).or_insert(made))
    }

    /// The steady state at knot `k` (forwards or not) of `route` sailed at `speed` by `hull` in `field`.
    fn get(&self, field: &WaveField, hull: &Hull, route: &Route, speed: f64, k: usize, forwards: bool) -> Arc<Steady> {
        let knots = self.knots(route);
        self.kept(
            (k, forwards),
            |kept| &mut kept.knots,
            || Steady::of(field, hull, Course::at_knot(route, knots, k, forwards, speed)),
        )
    }

    /// Block `b`'s share of the kernel's sum relative to its youngest knot (the block's end in its direction of
    /// travel), for `hull` at `speed` with the kernel's rate `lambda`: `Σ e^{−λ τ_a} ((1 − e^{−x} − q) G_a + q G_b)`
    /// over its intervals `a → b` (from younger to older), `τ_a` the age of `a` from the youngest knot, `x = λ h` and
    /// `q = (1 − e^{−x})/x − e^{−x}` (the weights of G linear between the two), and the same sum of the variances.
    #[allow(clippy::too_many_arguments)]
    fn block(
        &self,
        field: &WaveField,
        hull: &Hull,
        route: &Route,
        speed: f64,
        lambda: f64,
        b: usize,
        forwards: bool,
    ) -> Arc<Steady> {
        let knots = self.knots(route);
        self.kept(
            (b, forwards),
            |kept| &mut kept.blocks,
            || {
                let mut sum = Steady::zero(field.components().len());
                let order: Vec<usize> = if forwards {
                    (b * BLOCK..=(b + 1) * BLOCK).rev().collect()
                } else {
                    (b * BLOCK..=(b + 1) * BLOCK).collect()
                };
                let young = knots[order[0]];
                for pair in order.windows(2) {
                    let (a, o) = (pair[0], pair[1]);
                    let ea = (-lambda * (knots[a] - young).abs() / speed).exp();
                    let (wa, wb) = interval_weights(ea, lambda * (knots[a] - knots[o]).abs() / speed);
                    for (k, w) in [(a, wa), (o, wb)] {
                        sum.add(w, &self.get(field, hull, route, speed, k, forwards));
                    }
                }
                sum
            },
        )
    }
}

/// The kernel's weights `(w_a, w_b)` of the two ends of an interval of the course, G taken linear between them:
/// `ea = e^{−λ τ_a}` the kernel at its younger end, `x = λ h` its length in decay times (> 0).
fn interval_weights(ea: f64, x: f64) -> (f64, f64) {
    let part = -(-x).exp_m1(); // 1 − e^{−x}
    let wb = ea * (part / x - (-x).exp());
    (ea * part - wb, wb)
}

/// The course of `route` at travelled distance `d` at `speed` (at rest past a `Stop` route's end).
fn course_at(route: &Route, speed: f64, d: f64) -> Course {
    let (s, sign) = route.distance_to_arc(d);
    Course::on(route, s, sign, speed)
}

/// The remembered points from now (age 0) back to the window's age `window` (ages ascending; two at one age at a
/// route event): `(age s, point)`. `knots` are the route's; `d1` the distance travelled now and `d0` at the window's
/// start. Knots strictly between the window's ends count (its ends are the
/// courses now and then), and a route event just passed, at `d1` itself.
fn history(route: &Route, knots: &[f64], speed: f64, d1: f64, d0: f64, window: f64) -> Vec<(f64, Point)> {
    let len = route.length();
    let age = |d: f64| ((d1 - d) / speed).clamp(0.0, window);
    let now = course_at(route, speed, d1);
    let mut out = vec![(0.0, Point::Fresh(now))];
    let end = route.end_behaviour();
    let mut top = d1;
    if end == EndBehaviour::Stop {
        if d1 > len {
            out.push((age(len), Point::Fresh(Course::on(route, len, 0.0, speed))));
        }
        top = d1.min(len);
    }
    // Legs of the route in distance, [nL, (n+1)L], travelled forwards or (the odd legs of a ping-pong) backwards;
    // a stop route has leg 0 only.
    let mut n = if end == EndBehaviour::Stop { 0.0 } else { (top / len).floor() };
    while n >= 0.0 && (n + 1.0) * len > d0 {
        let forwards = end != EndBehaviour::PingPong || n % 2.0 == 0.0;
        let dist_of = |x: f64| if forwards { n * len + x } else { (n + 1.0) * len - x };
        // The knots within `top`, youngest first: `dist_of` is monotone in the knot (a constant plus or minus sorted
        // distances, rounded), so a binary search finds the first one where a walk from the leg's end would.
        let order: Box<dyn Iterator<Item = usize>> = if forwards {
            Box::new((0..knots.partition_point(|&x| dist_of(x) <= top)).rev())
        } else {
            Box::new(knots.partition_point(|&x| dist_of(x) > top)..knots.len())
        };
        for k in order {
            let d = dist_of(knots[k]);
            if d <= d0 {
                break;
            }
            // At d1 itself: a leg's start is the course now or one still to come; a leg's end is the course before
            // an event just passed (Route::distance_to_arc has the hull on the later leg from there).
            let leg_start = if forwards { k == 0 } else { k + 1 == knots.len() };
            if d == d1 && (leg_start || Course::at_knot(route, knots, k, forwards, speed).same(&now)) {
                continue;
            }
            out.push((age(d), Point::Knot(k, forwards)));
        }
        n -= 1.0;
    }
    let (s0, sign) = route.distance_to_arc(d0);
    let start = if sign == 0.0 || knots.len() < 2 {
        Point::Fresh(Course::on(route, s0, sign, speed))
    } else {
        let k = knots.partition_point(|&x| x <= s0).saturating_sub(1).min(knots.len() - 2);
        let f = ((s0 - knots[k]) / (knots[k + 1] - knots[k])).clamp(0.0, 1.0);
        Point::Between(k, f, sign > 0.0)
    };
    out.push((window, start));
    out
}

/// `[heave (m), roll (rad), pitch (rad)]` of the hull of `params` on `route` in `field` at time `t`, at world
/// position `(x, y)` (its position at `t`): the steady-state response of its course now ([`response`]), through the
/// memory of its recent course (the module's header). `memo` holds the route's knots' steady states for `field`
/// (worked out afresh, and slower, without one).
pub fn remembered_response(
    field: &WaveField,
    route: &Route,
    params: &VesselParams,
    [x, y]: [f64; 2],
    t: f64,
    memo: Option<&KnotGains>,
) -> [f64; 3] {
    let (hull, speed) = (&params.hull, params.speed_mps);
    let d1 = params.start_offset_m + speed * t;
    let now = course_at(route, speed, d1);
    let steady_now = || response(field, hull, x, y, now.yaw, now.vx, now.vy, t)[0];
    let lambda = hull.roll_damping_ratio * hull.roll_natural_frequency();
    if !(speed > 0.0 && route.length() > 0.0 && t > 0.0) {
        return steady_now();
    }
    let own;
    let child;
    let memo = match memo {
        Some(m) => match m.in_child() {
            None => m,
            Some(c) => {
                child = c;
                &*child
            }
        },
        None => {
            own = KnotGains::new();
            &own
        }
    };
    // The memory: −ln(MEMORY)/λ, at most as long as the hull takes to pass MAX_POINTS knots at the route's mean
    // knot spacing (a constant of the route, so the window is continuous in time), and back to t = 0 at most, where
    // it starts at the offset itself (`offset + u t − u t` rounds to either side of a route event there).
    let knots = memo.knots(route);
    let spacing = route.length() / (knots.len().max(2) - 1) as f64;
    let window = t.min(-MEMORY.ln() / lambda).min(MAX_POINTS as f64 * spacing / speed);
    let d0 = if window == t { params.start_offset_m } else { d1 - speed * window };
    let points = history(route, knots, speed, d1, d0, window);
    // Where the course now is the one all along the window (no knot or event in it): the steady state itself.
    let constant = points.iter().all(|p| match p.1 {
        Point::Fresh(c) => c.same(&now),
        Point::Between(..) => course_at(route, speed, d0).same(&now),
        Point::Knot(k, fw) => Course::at_knot(route, knots, k, fw, speed).same(&now),
    });
    if constant {
        return steady_now();
    }
    // The kernel's weight of each point: exact for G linear in time between consecutive points, and the tail;
    // where BLOCK intervals between knots follow each other, their share comes whole from the memo.
    let block_at = |i: usize| -> Option<(usize, bool)> {
        let Point::Knot(k, fw) = points[i].1 else { return None };
        let (b, other) = match fw {
            true if k % BLOCK == 0 && k >= BLOCK => (k / BLOCK - 1, k - BLOCK),
            false if k % BLOCK == 0 && k + BLOCK < knots.len() => (k / BLOCK, k + BLOCK),
            _ => return None,
        };
        (points.get(i + BLOCK).map(|p| p.1) == Some(Point::Knot(other, fw))).then_some((b, fw))
    };
    let mut weights = vec![0.0; points.len()];
    let mut blocks = Vec::new();
    let mut i = 0;
    while i + 1 < points.len() {
        if let Some((b, fw)) = block_at(i) {
            blocks.push(((-lambda * points[i].0).exp(), b, fw));
            i += BLOCK;
            continue;
        }
        let (ta, tb) = (points[i].0, points[i + 1].0);
        let h = tb - ta;
        if h > 0.0 {
            let (wa, wb) = interval_weights((-lambda * ta).exp(), lambda * h);
            weights[i] += wa;
            weights[i + 1] += wb;
        }
        i += 1;
    }
    weights[points.len() - 1] += (-lambda * window).exp();
    let mut sum = Steady::zero(field.components().len());
    // Each point's weight on the steady states it stands for, and the blocks'.
    let mut terms: Vec<(f64, Source)> = Vec::with_capacity(points.len() + blocks.len() + 1);
    for (p, &w) in points.iter().zip(&weights) {
        match p.1 {
            Point::Knot(k, fw) => terms.push((w, Source::Knot(k, fw))),
            Point::Between(k, f, fw) => {
                terms.push((w * (1.0 - f), Source::Knot(k, fw)));
                terms.push((w * f, Source::Knot(k + 1, fw)));
            }
            Point::Fresh(c) => terms.push((w, Source::Fresh(c))),
        }
    }
    terms.extend(blocks.into_iter().map(|(w, b, fw)| (w, Source::Block(b, fw))));
    for (w, source) in terms {
        if w == 0.0 {
            continue;
        }
        let steady = match source {
            Source::Knot(k, fw) => memo.get(field, hull, route, speed, k, fw),
            Source::Block(b, fw) => memo.block(field, hull, route, speed, lambda, b, fw),
            Source::Fresh(c) => Arc::new(Steady::of(field, hull, c)),
        };
        sum.add(w, &steady);
    }
    let (gains, target) = (sum.gains, sum.variance);
    let linear = variance_of(field, &gains);
    let kappa: [f64; 3] =
        std::array::from_fn(|m| if linear[m] > 0.0 && target[m] > 0.0 { (target[m] / linear[m]).sqrt() } else { 1.0 });
    let mut out = [0.0; 3];
    for (c, g) in field.components().iter().zip(&gains) {
        let (s, co) = c.phase_at(x, y, t).sin_cos();
        let (er, ei) = (c.amplitude_m * co, c.amplitude_m * s);
        for m in 0..3 {
            out[m] += kappa[m] * (g[m][0] * er - g[m][1] * ei);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::knots::tests::square;
    use crate::ocean::SeaSpec;
    use std::f64::consts::PI;

    fn ok<T, E: std::fmt::Display>(r: std::result::Result<T, E>) -> T {
        r.unwrap_or_else(|e| unreachable!("{e}"))
    }

    fn field(hs: f64, direction: f64, seed: u64) -> WaveField {
        ok(WaveField::new(&SeaSpec { hs, tp: 7.0, gamma: 3.3, direction_rad: direction, spread_s: 8.0 }, seed))
    }

    fn params(speed: f64, offset: f64) -> VesselParams {
        VesselParams { speed_mps: speed, start_offset_m: offset, ..VesselParams::default() }
    }

    /// A 5 m speedboat (beam 2 m, draft 0.35 m, Cb 0.4, GM 0.6 m): a roll period of 2 s.
    fn speedboat() -> Hull {
        ok(Hull::new(5.0, 2.0, 0.35, 0.4, 0.6))
    }

    /// `Σ_c Re(G_c a_c e^{iψ_c})` per mode at `(x, y, t)`.
    fn evaluate(field: &WaveField, gains: &[[[f64; 2]; 3]], x: f64, y: f64, t: f64) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (c, g) in field.components().iter().zip(gains) {
            let (s, co) = c.phase_at(x, y, t).sin_cos();
            for m in 0..3 {
                out[m] += c.amplitude_m * (g[m][0] * co - g[m][1] * s);
            }
        }
        out
    }

    #[test]
    fn on_a_straight_leg_the_response_is_the_steady_state_to_the_bit() {
        let (f, r) = (field(2.0, 0.4, 3), ok(Route::new(&[[0.0, 0.0], [400.0, 0.0]], EndBehaviour::PingPong)));
        let p = params(6.0, 0.0);
        for t in [0.5, 20.0, 55.0] {
            let x = 6.0 * t;
            let got = remembered_response(&f, &r, &p, [x, 0.0], t, None);
            assert_eq!(got, response(&f, &p.hull, x, 0.0, 0.0, 6.0, 0.0, t)[0]);
        }
    }

    #[test]
    fn one_event_blends_the_two_steady_states_and_keeps_the_variance() {
        // A stop and a turn about on a straight route of 50 m at 5 m/s (the event at 10 s), against the closed
        // form κ (w G_before + (1 − w) G_after), w = e^{−λ (t − 10)}, worked out here from the RAOs.
        let f = field(3.0, 0.3, 5);
        let hull = crate::kinematics::REFERENCE_HULL;
        let lambda = hull.roll_damping_ratio * hull.roll_natural_frequency();
        for (end, after) in [(EndBehaviour::Stop, (0.0, 0.0, 0.0)), (EndBehaviour::PingPong, (PI, -5.0, 0.0))] {
            let r = ok(Route::new(&[[0.0, 0.0], [50.0, 0.0]], end));
            let gains = |(yaw, vx, vy): (f64, f64, f64)| Steady::of(&f, &hull, Course { yaw, vx, vy });
            let (b, a) = (gains((0.0, 5.0, 0.0)), gains(after));
            for t in [10.3, 12.0, 19.5] {
                let x = if end == EndBehaviour::Stop { 50.0 } else { 50.0 - 5.0 * (t - 10.0) };
                let w = (-lambda * (t - 10.0)).exp();
                let mixed: Vec<_> = a
                    .gains
                    .iter()
                    .zip(&b.gains)
                    .map(|(ga, gb)| [0, 1, 2].map(|m| [0, 1].map(|i| w * gb[m][i] + (1.0 - w) * ga[m][i])))
                    .collect();
                let mixed = Steady { variance: [0.0; 3], gains: mixed };
                let var = |s: &Steady, m: usize| -> f64 {
                    f.components()
                        .iter()
                        .zip(&s.gains)
                        .map(|(c, g)| c.elevation_variance() * (g[m][0].powi(2) + g[m][1].powi(2)))
                        .sum()
                };
                let kappa: [f64; 3] =
                    std::array::from_fn(|m| ((w * b.variance[m] + (1.0 - w) * a.variance[m]) / var(&mixed, m)).sqrt());
                let plain = evaluate(&f, &mixed.gains, x, 0.0, t);
                let got = remembered_response(&f, &r, &params(5.0, 0.0), [x, 0.0], t, None);
                for m in 0..3 {
                    let want = kappa[m] * plain[m];
                    assert!((got[m] - want).abs() <= 1e-9 * (1.0 + want.abs()), "{end:?} {t} {m} {got:?} {want}");
                }
            }
        }
    }

    #[test]
    fn a_bend_remembers_its_course_as_a_fine_quadrature_of_the_kernel_does() {
        // Brute force: the kernel's integral by the trapezoid rule on 20,000 ages, each course from the route
        // itself, against the knots' quadrature (knots every half degree, exact weights).
        // A loop (knots travelled forwards, whole blocks of them in the sum) and a ping-pong route after its turn
        // about (backwards).
        let f = field(1.5, 2.0, 11);
        let p = VesselParams { hull: speedboat(), ..params(9.0, 10.0) };
        let lambda = p.hull.roll_damping_ratio * p.hull.roll_natural_frequency();
        let mut worst = [0.0f64; 3];
        let mut scale = [0.0f64; 3];
        let cases = [(EndBehaviour::Loop, [4.0, 7.5, 9.0, 30.0]), (EndBehaviour::PingPong, [50.0, 62.0, 75.0, 90.0])];
        for (end, t) in cases.iter().flat_map(|(e, ts)| ts.iter().map(move |t| (*e, *t))) {
            let r = square(end);
            let memo = KnotGains::new();
            let d1 = p.start_offset_m + 9.0 * t;
            let [x, y] = r.position(r.distance_to_arc(d1).0);
            let got = remembered_response(&f, &r, &p, [x, y], t, Some(&memo));
            assert_eq!(got, remembered_response(&f, &r, &p, [x, y], t, None)); // the memo changes nothing
            let window = t.min(-MEMORY.ln() / lambda);
            let n = 20_000;
            let h = window / n as f64;
            let mut acc = Steady::zero(f.components().len());
            for i in 0..=n {
                let tau = i as f64 * h;
                let mut w = lambda * (-lambda * tau).exp() * h * if i == 0 || i == n { 0.5 } else { 1.0 };
                if i == n {
                    w += (-lambda * window).exp();
                }
                acc.add(w, &Steady::of(&f, &p.hull, course_at(&r, 9.0, d1 - 9.0 * tau)));
            }
            let (acc, target) = (acc.gains, acc.variance);
            let lin = Steady::of(&f, &p.hull, course_at(&r, 9.0, d1)); // for its shape only
            let mut linear = [0.0; 3];
            for (c, g) in f.components().iter().zip(&acc) {
                for m in 0..3 {
                    linear[m] += c.elevation_variance() * (g[m][0].powi(2) + g[m][1].powi(2));
                }
            }
            let plain = evaluate(&f, &acc, x, y, t);
            for m in 0..3 {
                let want = (target[m] / linear[m]).sqrt() * plain[m];
                worst[m] = worst[m].max((got[m] - want).abs());
                scale[m] = scale[m].max(lin.variance[m].sqrt());
            }
        }
        // Whole blocks were summed in both directions.
        let used = |memo: &KnotGains, fw: bool| memo.lock().blocks.keys().any(|k| k.1 == fw);
        for (end, t, fw) in [(EndBehaviour::Loop, 30.0, true), (EndBehaviour::PingPong, 75.0, false)] {
            let (r, memo) = (square(end), KnotGains::new());
            let [x, y] = r.position(r.distance_to_arc(p.start_offset_m + 9.0 * t).0);
            remembered_response(&f, &r, &p, [x, y], t, Some(&memo));
            assert!(used(&memo, fw), "{end:?}");
        }
        // Within 1 % of the response's RMS scale in each mode (measured: 0.42 % for the roll, 0.10 % for the heave,
        // 0.08 % for the pitch; 3.1 % for the roll with knots a degree apart and no rule on the heading's
        // linearity between them: the steady state is taken linear between knots).
        for m in 0..3 {
            assert!(worst[m] <= 0.01 * scale[m], "{m}: {} of {}", worst[m], scale[m]);
        }
    }

    #[test]
    fn a_speedboat_rolls_through_a_tight_bend_at_the_rate_of_its_legs() {
        // The defect this memory mends: a 5 m speedboat at 9 m/s round the 60 m square's corners (about 16 m of
        // radius) at W1, its roll sampled every 10 ms over two laps: the steady state of the moment rolled several
        // times faster in the corners than on the legs.
        let f = field(1.5, 0.7, 2);
        let r = square(EndBehaviour::Loop);
        let p = VesselParams { hull: speedboat(), ..params(9.0, 0.0) };
        let memo = KnotGains::new();
        let (mut bend, mut legs, mut bend_steady, mut legs_steady) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let roll = |t: f64| {
            let d = 9.0 * t;
            let (s, sign) = r.distance_to_arc(d);
            let [x, y] = r.position(s);
            let c = Course::on(&r, s, sign, 9.0);
            let steady = response(&f, &p.hull, x, y, c.yaw, c.vx, c.vy, t)[0][1];
            (remembered_response(&f, &r, &p, [x, y], t, Some(&memo))[1], steady, c.yaw)
        };
        let mut prev = roll(30.0);
        for i in 1..(2.0 * r.length() / 9.0 / 0.01) as usize {
            let now = roll(30.0 + 0.01 * i as f64);
            let (rate, rate_steady) = ((now.0 - prev.0).abs() / 0.01, (now.1 - prev.1).abs() / 0.01);
            if wrap_angle(now.2 - prev.2).abs() / 0.01 > 0.05 {
                (bend, bend_steady) = (bend.max(rate), bend_steady.max(rate_steady));
            } else {
                (legs, legs_steady) = (legs.max(rate), legs_steady.max(rate_steady));
            }
            prev = now;
        }
        assert!(
            bend_steady > 2.5 * legs_steady,
            "the steady state did not show the defect: {bend_steady} {legs_steady}"
        );
        // Measured: 197°/s in the corners against 36°/s on the legs without memory; 57°/s against 35°/s with it.
        assert!(bend < 2.0 * legs && bend < 0.4 * bend_steady, "{} deg/s in the bends, {} on the legs", bend, legs);
    }

    /// The knots of `history`'s legs found by a walk over every knot from the leg's end (its first form).
    fn history_by_walk(route: &Route, knots: &[f64], speed: f64, d1: f64, d0: f64, window: f64) -> Vec<(f64, Point)> {
        let (len, end) = (route.length(), route.end_behaviour());
        let age = |d: f64| ((d1 - d) / speed).clamp(0.0, window);
        let now = course_at(route, speed, d1);
        let mut out = vec![(0.0, Point::Fresh(now))];
        let mut top = d1;
        if end == EndBehaviour::Stop {
            if d1 > len {
                out.push((age(len), Point::Fresh(Course::on(route, len, 0.0, speed))));
            }
            top = d1.min(len);
        }
        let mut n = if end == EndBehaviour::Stop { 0.0 } else { (top / len).floor() };
        while n >= 0.0 && (n + 1.0) * len > d0 {
            let forwards = end != EndBehaviour::PingPong || n % 2.0 == 0.0;
            let order: Vec<usize> =
                if forwards { (0..knots.len()).rev().collect() } else { (0..knots.len()).collect() };
            for k in order {
                let d = if forwards { n * len + knots[k] } else { (n + 1.0) * len - knots[k] };
                if d > top {
                    continue;
                }
                if d <= d0 {
                    break;
                }
                let leg_start = if forwards { k == 0 } else { k + 1 == knots.len() };
                if d == d1 && (leg_start || Course::at_knot(route, knots, k, forwards, speed).same(&now)) {
                    continue;
                }
                out.push((age(d), Point::Knot(k, forwards)));
            }
            n -= 1.0;
        }
        let (s0, sign) = route.distance_to_arc(d0);
        let start = if sign == 0.0 || knots.len() < 2 {
            Point::Fresh(Course::on(route, s0, sign, speed))
        } else {
            let k = knots.partition_point(|&x| x <= s0).saturating_sub(1).min(knots.len() - 2);
            Point::Between(k, ((s0 - knots[k]) / (knots[k + 1] - knots[k])).clamp(0.0, 1.0), sign > 0.0)
        };
        out.push((window, start));
        out
    }

    #[test]
    fn history_finds_the_knots_a_walk_over_every_knot_finds() {
        // Every end behaviour, a rounded square and a jittery track; windows ending on knots, on leg ends, between.
        let pts: Vec<[f64; 2]> =
            (0..60).map(|i| [20.0 * f64::from(i), ((f64::from(i) * 12.9898).sin() * 43_758.547).fract()]).collect();
        let mut checked = 0;
        for end in [EndBehaviour::Stop, EndBehaviour::Loop, EndBehaviour::PingPong] {
            for r in [square(end), ok(Route::new(&pts, end))] {
                let (knots, len, speed) = (route_knots(&r), r.length(), 7.0);
                let mut ends: Vec<f64> = (0..=300).map(|i| f64::from(i) * 3.1 * len / 300.0).collect();
                ends.extend(knots.iter().flat_map(|&k| [k, len + k, 2.0 * len - k, 2.0 * len + k]));
                for d1 in ends {
                    for window in [0.0, 0.3, 4.0, 25.0, 400.0] {
                        for d0 in [d1 - speed * window, d1 - speed * window - 1e-9, 0.0] {
                            let (d0, window) = if d0 == 0.0 { (0.0, d1 / speed) } else { (d0, window) };
                            let fast = history(&r, &knots, speed, d1, d0, window);
                            assert_eq!(fast, history_by_walk(&r, &knots, speed, d1, d0, window), "{d1} {d0}");
                            checked += fast.len();
                        }
                    }
                }
            }
        }
        assert!(checked > 100_000, "{checked}");
    }

    #[test]
    fn a_long_jittery_track_keeps_a_bounded_memo_with_the_same_poses() {
        // 8 km of waypoints every 20 m, each up to a metre off the line (a track's noise): thousands of knots. The
        // memo keeps at most MEMO_ENTRIES of them, and the poses are those worked out with no memo at all.
        let pts: Vec<[f64; 2]> =
            (0..400).map(|i| [20.0 * f64::from(i), ((f64::from(i) * 12.9898).sin() * 43_758.547).fract()]).collect();
        let r = ok(Route::new(&pts, EndBehaviour::Stop));
        assert!(route_knots(&r).len() > 2 * MEMO_ENTRIES, "{}", route_knots(&r).len());
        let (f, p, memo) =
            (field(1.5, 0.7, 4), VesselParams { hull: speedboat(), ..params(10.0, 0.0) }, KnotGains::new());
        // Along the whole track (every knot's state worked out, so the memo lets go more than once), then back.
        for t in (1..=40).map(|i| 19.75 * f64::from(i)).chain([120.0, 30.0]) {
            let [x, y] = r.position(r.distance_to_arc(10.0 * t).0);
            let kept = remembered_response(&f, &r, &p, [x, y], t, Some(&memo));
            assert_eq!(kept, remembered_response(&f, &r, &p, [x, y], t, None), "{t}");
            let held = memo.lock();
            assert!(held.knots.len() <= MEMO_ENTRIES && held.blocks.len() <= MEMO_ENTRIES);
        }
    }

    #[test]
    fn a_forked_child_does_not_wait_on_its_parents_memo() {
        // A memo made by another process (as the parent's is in a forked child) whose lock a thread of that
        // process held at the fork: the child keeps a memo of its own and gives the same poses.
        let (f, r) = (field(1.5, 0.7, 2), square(EndBehaviour::Loop));
        let p = VesselParams { hull: speedboat(), ..params(9.0, 0.0) };
        let parent = KnotGains { pid: std::process::id().wrapping_add(1), ..KnotGains::new() };
        let held = parent.lock();
        let [x, y] = r.position(r.distance_to_arc(9.0 * 40.0).0);
        let got = remembered_response(&f, &r, &p, [x, y], 40.0, Some(&parent));
        assert_eq!(got, remembered_response(&f, &r, &p, [x, y], 40.0, None));
        assert!(held.knots.is_empty());
        drop(held);
        assert!(parent.child.lock().is_ok_and(|c| c.as_ref().is_some_and(|(pid, _)| *pid == std::process::id())));
    }

    #[test]
    fn the_memory_is_capped_by_the_routes_knot_spacing_and_stays_continuous() {
        // A ping-pong route of 2 m sailed at 20 m/s by a slowly damped hull turns about ten times a second: its
        // memory is as long as 8,192 knots take at the route's 2 m spacing (819 s), and the pose has no step.
        let f = field(1.0, 0.0, 1);
        let r = ok(Route::new(&[[0.0, 0.0], [2.0, 0.0]], EndBehaviour::PingPong));
        let hull = Hull { roll_damping_ratio: 0.01, ..ok(Hull::new(100.0, 16.0, 6.0, 0.7, 1.0)) };
        let knots = route_knots(&r);
        assert_eq!(knots.len(), 2);
        let window = MAX_POINTS as f64 * 2.0 / 20.0;
        let d1 = 20.0 * 900.0;
        let points = history(&r, &knots, 20.0, d1, d1 - 20.0 * window, window);
        assert!(points.len() <= 2 * (MAX_POINTS + knots.len()) + 4 && points.len() > MAX_POINTS, "{}", points.len());
        let p = VesselParams { hull, ..params(20.0, 0.0) };
        let memo = KnotGains::new();
        let z: Vec<[f64; 3]> = (0..400)
            .map(|i| remembered_response(&f, &r, &p, [0.0, 0.0], 900.0 + 1e-4 * i as f64, Some(&memo)))
            .collect();
        let steps: Vec<f64> = z.windows(2).map(|w| (w[1][1] - w[0][1]).abs()).collect();
        let typical = steps.iter().sum::<f64>() / steps.len() as f64;
        assert!(
            steps.iter().all(|&d| d <= 5.0 * typical + 1e-9),
            "{typical} {:?}",
            steps.iter().fold(0.0f64, |a, &b| a.max(b))
        );
    }
}
