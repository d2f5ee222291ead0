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

/// The knots of one leg whose travelled distance `dist_of(knots[k])` is at most `top`: the first of them on a leg
/// travelled forwards (distances rising with the knot), the last on one travelled backwards. `dist_of` is a constant
/// plus or minus the sorted arc lengths, rounded, so monotone in the knot: a binary search finds them.
fn leg_within(knots: &[f64], dist_of: impl Fn(f64) -> f64, forwards: bool, top: f64) -> std::ops::Range<usize> {
    if forwards {
        0..knots.partition_point(|&x| dist_of(x) <= top)
    } else {
        knots.partition_point(|&x| dist_of(x) > top)..knots.len()
    }
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
        // The knots within `top`, youngest first.
        let within = leg_within(knots, dist_of, forwards, top);
        let order: Box<dyn Iterator<Item = usize>> = if forwards { Box::new(within.rev()) } else { Box::new(within) };
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
#[path = "transient_tests.rs"]
mod tests;
