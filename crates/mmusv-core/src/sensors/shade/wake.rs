//! The wakes on the water, for cameras and the LiDAR ([`Wake`], drawn by `foam.rs`'s `Foam`).
//!
//! Behind every vessel under way, turbulent foam along its track (as wide as its beam, widening slowly) and two
//! arms at the Kelvin angle `asin(1/3) = 19.47°` (Lord Kelvin, 1887) from the bow, both fading with their age
//! `distance / speed` (e-folding 30 s); the foam grows with speed (track `min(1, (V / 6 m/s)²)`, arms `min(1, (V
//! / 8 m/s)²)`), so a slow craft leaves a faint trace. A wake is drawn as straight pieces of the path behind its
//! vessel ([`Wake`] rows; `mmusv.Simulation.wakes` works them out from the route, `VesselMotion::wake_pieces`): the
//! vessel's own, straight back along its heading as far as its path ran straight ([`Wake::reach_m`]), then, round
//! each bend, a piece from where the vessel was [`Wake::age_s`] ago, whose foam is as faded and as widened as that
//! age makes it and ends where the next piece goes on (reaching past its end by the track's half-width, to fill
//! the bend's outer corner). A wake row without a piece after it whose path bent (`reach_m` short of the foam's own
//! reach) thins to nothing over the last quarter of that stretch (at most four beams). No foam where the vessel
//! never went. The foam is broken up by the same noise as the whitecaps (`foam.rs`).
//!
//! **The Kelvin arms round a bend** follow the ray theory of ship waves (Lighthill, *Waves in Fluids*, 1978, §3.10,
//! the argument that gives Kelvin's wedge): the waves a vessel at speed `U` sent out `a` seconds ago from a point
//! `P` of its path, heading `ĥ`, are those whose crests kept pace with it (phase speed `U cos θ` at an angle `θ` to
//! `ĥ`); their energy travels at half that speed, so it now lies on a circle of radius `E/4` centred `E/4` ahead of
//! `P` along `ĥ`, `E = Ua` the distance the vessel has gone since. The arms are the envelope of these circles along
//! the path. With `κ` the path's curvature at `P` (to port positive) and `k = Eκ`, the envelope touches the circle of
//! `P` where its normal makes the angle `ψ` with `ĥ` that solves `3 cos ψ + k sin ψ = 1` (the derivative of the
//! family along the path), i.e. `ψ = atan2(k, 3) ± acos(1/√(9 + k²))`, one root per arm. On a straight course (`k =
//! 0`) that is `cos ψ = 1/3`: the wedge of half-angle `asin(1/3)` behind the bow. A vessel's own straight piece draws
//! that wedge as far as the waves it sent out along that piece have gone; round its bends the arms are worked out
//! along the pieces behind it (their headings joined linearly between the pieces' middles, so the curvature is the
//! turn between two pieces over the distance between their middles) and drawn as straight stretches (`E` counted
//! from where the bow was). Their width and fade are those of a straight course's arms the same `E` behind.

/// e-folding age of wake foam, seconds.
const WAKE_FADE_S: f32 = 30.0;
/// The oldest wake foam drawn, seconds (four e-folding ages: 2 % of its fresh density); a wake reaches this
/// long times the speed behind the stern, less where the path bent ([`Wake::reach_m`]).
pub const WAKE_REACH_S: f32 = 4.0 * WAKE_FADE_S;
/// Most straight pieces a wake is drawn in (`mmusv.Simulation.wakes`: the path behind a vessel, piece by piece
/// round its bends; the last one goes on straight).
pub const WAKE_MAX_PIECES: usize = 32;
/// `tan` of the Kelvin half-angle.
const KELVIN_TAN: f32 = 0.353_553_4;

/// A vessel under way, as its wake needs it (world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wake {
    /// Centre of the vessel, metres (x east, y north).
    pub x: f32,
    /// Centre of the vessel, metres.
    pub y: f32,
    /// Heading of the bow, radians counter-clockwise from +x.
    pub heading: f32,
    /// Speed, m/s (`> 0`).
    pub speed: f32,
    /// Length overall, metres.
    pub length: f32,
    /// Beam, metres.
    pub beam: f32,
    /// How far behind the stern the vessel's path ran straight along `heading` (metres, ≥ 0; `f32::INFINITY`:
    /// as far as the foam lasts): the wake is drawn straight behind the vessel, so no farther than its path was
    /// (a turn or a reversal ends it; `mmusv.Simulation.wakes` works it out from the route).
    pub reach_m: f32,
    /// How old the foam at the stern point is, seconds (0 for a vessel's own position; a piece of its path further
    /// back, `mmusv.Simulation.wakes`, passed that long ago): the foam fades and its track widens from that age on,
    /// and a row older than 0 draws no Kelvin arms (the vessel's own piece draws them).
    pub age_s: f32,
    /// Whether the vessel's older foam goes on past `reach_m` in another row (a piece of a wake that follows the
    /// path's bends): the foam then ends there at full strength instead of thinning out before it.
    pub goes_on: bool,
}

/// Which wakes may lay foam in each cell of a square grid: a bit per wake (`words` 64-bit words a cell), set
/// wherever the wake's track or arms may reach into the cell. The test is conservative (a cell's every point within
/// its half-diagonal, plus a centimetre for rounding, of its centre), so a wake whose bit is clear gives no foam
/// there.
#[derive(Debug, Clone, Default)]
struct WakeGrid {
    origin: [f32; 2],
    inv_cell: f32,
    words: usize,
    bits: Vec<u64>,
}

impl WakeGrid {
    /// Cells per side.
    const N: usize = 32;

    /// The wakes that may lay foam at `(x, y)` (a bit per wake); `None` outside the grid (every wake then).
    #[inline(always)]
    fn mask(&self, x: f32, y: f32) -> Option<&[u64]> {
        let (u, v) = ((x - self.origin[0]) * self.inv_cell, (y - self.origin[1]) * self.inv_cell);
        if !(u >= 0.0 && v >= 0.0) {
            return None;
        }
        let (i, j) = (u as usize, v as usize);
        let at = (j * Self::N + i) * self.words;
        (i < Self::N && j < Self::N).then(|| &self.bits[at..at + self.words])
    }
}

/// A wake prepared for lookups: its stern, unit heading, reach and sizes.
#[derive(Debug, Clone, Copy, Default)]
struct WakeShape {
    stern: [f32; 2],
    dir: [f32; 2],
    /// Farthest distance behind the stern with foam on the track.
    reach: f32,
    /// Where the vessel's path bent ([`Wake::reach_m`] short of the foam's own reach): the foam thins linearly to
    /// nothing over this last stretch before `reach` (0: no such end).
    taper: f32,
    /// The fade of the foam at the stern point, for its age there ([`Wake::age_s`]; 1 for a fresh one).
    fade0: f32,
    /// How far along the path the vessel has gone since it passed the stern point (`age_s · speed`, metres): the
    /// track has widened over that much more.
    back: f32,
    /// The track's half-width at its reach (its widest), metres.
    widest: f32,
    /// How far behind the stern the straight Kelvin arms of a vessel's own piece go (0 for a piece further back:
    /// its arms, bent, are [`ArmSegment`]s): as far as its track where its path ran straight as long as the foam
    /// lasts, else as far as the waves it sent out along its straight stretch have gone (module header).
    arm_to: f32,
    speed: f32,
    length: f32,
    beam: f32,
}

impl WakeShape {
    /// The wake of `w` prepared for lookups; `None` for a vessel too slow to leave one.
    fn new(w: &Wake) -> Option<Self> {
        if w.speed <= 0.05 {
            return None;
        }
        let (s, c) = w.heading.sin_cos();
        // The foam's own reach: as far back as it is at most `WAKE_REACH_S` old.
        let age = w.age_s.max(0.0);
        let lasts = w.speed * (WAKE_REACH_S - age).max(0.0);
        let bent = w.reach_m < lasts && !w.goes_on;
        let mut shape = WakeShape {
            stern: [w.x - c * w.length * 0.5, w.y - s * w.length * 0.5],
            dir: [c, s],
            reach: lasts.min(w.reach_m),
            taper: if bent { (0.25 * w.reach_m).min(4.0 * w.beam) } else { 0.0 },
            fade0: (-age / WAKE_FADE_S).exp(),
            back: age * w.speed,
            widest: 0.0,
            arm_to: 0.0,
            speed: w.speed,
            length: w.length,
            beam: w.beam,
        };
        // The waves sent out `reach_m` behind the stern (the bow `length + reach_m` metres ago) lie a third of that
        // ahead of there.
        if shape.back <= 0.0 {
            shape.arm_to = if w.reach_m < lasts { w.reach_m - (w.length + w.reach_m) / 3.0 } else { shape.reach };
        }
        // A piece whose older foam goes on in the next one reaches on past its end by its track's
        // half-width there, to fill the corner on the outer side of the bend between the two.
        if w.goes_on && w.reach_m < lasts {
            shape.reach = lasts.min(w.reach_m + shape.track_half_width(w.reach_m));
        }
        shape.widest = shape.track_half_width(shape.reach);
        Some(shape)
    }

    /// World `(x, y)` in the wake's frame: how far behind the stern along the heading, and how far from the track's
    /// centre line (either side).
    #[inline(always)]
    fn frame(&self, x: f32, y: f32) -> (f32, f32) {
        let [co, s] = self.dir;
        let (dx, dy) = (x - self.stern[0], y - self.stern[1]);
        (-(dx * co + dy * s), (-dx * s + dy * co).abs())
    }

    /// Whether the straight Kelvin arms are drawn: from the vessel itself, not from a piece of its path further
    /// back (one whose foam is older than 0 at its start, [`Wake::age_s`]; its arms are [`ArmSegment`]s).
    #[inline(always)]
    fn arms(&self) -> bool {
        self.back <= 0.0
    }

    /// Half-width of the turbulent track `behind` metres behind the stern (widening slowly).
    #[inline(always)]
    fn track_half_width(&self, behind: f32) -> f32 {
        0.5 * self.beam * (1.0 + ((behind.max(0.0) + self.back) / self.beam.max(1.0)).sqrt() * 0.25)
    }

    /// Farther from the centre line than this, `behind` metres behind the stern, no foam: outside the Kelvin arms
    /// and the track (with arms), or the track at its widest (a piece without them).
    #[inline(always)]
    fn wedge(&self, behind: f32) -> f32 {
        if self.arms() {
            0.6 * self.beam + (behind.max(0.0) + self.length) * (KELVIN_TAN + 0.07) + 0.3
        } else {
            self.widest
        }
    }

    /// Whether any point within `r` of `c` may lie on this wake's track or arms (see [`WakeShape::foam_at`]):
    /// along the wake and across it such a point is at most `r` from `c`'s distances, and the track's half-width
    /// and the arms' width grow with the distance behind.
    fn may_reach(&self, c: [f32; 2], r: f32) -> bool {
        let (behind, lateral) = self.frame(c[0], c[1]);
        if behind + r <= -0.1 * self.length || behind - r > self.reach {
            return false;
        }
        let far = (behind + r).max(0.0);
        if lateral - r < self.track_half_width(far) {
            return true;
        }
        if behind + r <= 0.0 || behind - r > self.arm_to || !self.arms() {
            return false;
        }
        (lateral - (behind + self.length) * KELVIN_TAN).abs() - r * (1.0 + KELVIN_TAN)
            < arm_width(far + self.length, self.beam)
    }

    /// The foam density this wake lays at `(x, y)` (0 where none), `noise_at` the foam noise there.
    #[inline(always)]
    fn foam_at(&self, x: f32, y: f32, noise_at: &mut impl FnMut() -> f32) -> f32 {
        let w = self;
        let (behind, lateral) = w.frame(x, y);
        if behind <= -0.1 * w.length || behind > w.reach {
            return 0.0;
        }
        // Beyond the arms (or, for a piece further back, without them, beyond its track at its widest).
        if lateral > w.wedge(behind) {
            return 0.0;
        }
        // Turbulent track behind the stern, and the Kelvin arms from the bow: whether the point is on either
        // before the fade is worked out (most of the wedge is between them).
        let half = w.track_half_width(behind);
        let on_track = lateral < half;
        let width = arm_width(behind + w.length, w.beam);
        let off = (lateral - (behind + w.length) * KELVIN_TAN).abs();
        let on_arm = w.arms() && behind > 0.0 && behind <= w.arm_to && off < width;
        if !on_track && !on_arm {
            return 0.0;
        }
        let mut fade = (-behind.max(0.0) / (w.speed * WAKE_FADE_S)).exp() * w.fade0;
        if w.taper > 0.0 && behind > w.reach - w.taper {
            fade *= (w.reach - behind) / w.taper;
        }
        let track = (w.speed / 6.0).powi(2).min(1.0);
        let mut f = if on_track { (1.0 - lateral / half).sqrt() * fade * track } else { 0.0 };
        if on_arm {
            f = f.max((1.0 - off / width) * fade * arm_strength(w.speed) * 0.45);
        }
        if f > 0.0 {
            // Broken up by the noise, as real foam is.
            (f * (1.6 * noise_at() - 0.3)).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

/// Width of a Kelvin arm `from_bow` metres behind the bow on a straight course (metres).
#[inline(always)]
fn arm_width(from_bow: f32, beam: f32) -> f32 {
    0.3 + 0.02 * from_bow + 0.1 * beam
}

/// On a straight course, how far behind the bow the arm point of the waves sent out `e` metres back lies.
#[inline(always)]
fn behind_bow(e: f32) -> f32 {
    e * (2.0 / 3.0)
}

/// How strong the Kelvin arms of a vessel at `speed` m/s are (a fresh arm's middle: 0.45 of this foam).
#[inline(always)]
fn arm_strength(speed: f32) -> f32 {
    (speed / 8.0).powi(2).min(1.0)
}

/// A straight stretch of a Kelvin arm bent round the path (module header): from `a` to `b` (world metres), the
/// waves there sent out when the bow was `e[0]`, `e[1]` metres back along the path.
#[derive(Debug, Clone, Copy)]
struct ArmSegment {
    a: [f32; 2],
    /// `b − a` and `1 / |b − a|²`.
    ab: [f32; 2],
    inv_len2: f32,
    e: [f32; 2],
    speed: f32,
    length: f32,
    beam: f32,
}

impl ArmSegment {
    fn new(a: [f32; 2], b: [f32; 2], e: [f32; 2], w: &Wake) -> Self {
        let ab = [b[0] - a[0], b[1] - a[1]];
        let len2 = ab[0] * ab[0] + ab[1] * ab[1];
        let inv_len2 = if len2 > 0.0 { 1.0 / len2 } else { 0.0 };
        Self { a, ab, inv_len2, e, speed: w.speed, length: w.length, beam: w.beam }
    }

    /// The nearest point's share along the segment and its distance from `(x, y)`.
    #[inline(always)]
    fn nearest(&self, x: f32, y: f32) -> (f32, f32) {
        let (dx, dy) = (x - self.a[0], y - self.a[1]);
        let t = ((dx * self.ab[0] + dy * self.ab[1]) * self.inv_len2).clamp(0.0, 1.0);
        (t, (dx - t * self.ab[0]).hypot(dy - t * self.ab[1]))
    }

    /// The widest the arm is along this stretch (it widens with `e`).
    fn widest(&self) -> f32 {
        arm_width(behind_bow(self.e[0].max(self.e[1])), self.beam)
    }

    /// Whether any point within `r` of `c` may lie on this stretch.
    fn may_reach(&self, c: [f32; 2], r: f32) -> bool {
        self.nearest(c[0], c[1]).1 - r < self.widest()
    }

    /// The foam density this stretch lays at `(x, y)` (0 where none), `noise_at` the foam noise there: as wide
    /// and as faded as the arm of a straight course at the same `e`.
    #[inline(always)]
    fn foam_at(&self, x: f32, y: f32, noise_at: &mut impl FnMut() -> f32) -> f32 {
        let (t, d) = self.nearest(x, y);
        let from_bow = behind_bow(self.e[0] + t * (self.e[1] - self.e[0]));
        let width = arm_width(from_bow, self.beam);
        if d >= width {
            return 0.0;
        }
        let fade = (-(from_bow - self.length).max(0.0) / (self.speed * WAKE_FADE_S)).exp();
        let f = (1.0 - d / width) * fade * arm_strength(self.speed) * 0.45;
        (f * (1.6 * noise_at() - 0.3)).clamp(0.0, 1.0)
    }
}

/// The Kelvin arms of the wake whose pieces are `chain` (its vessel's own first, then older pieces round its
/// bends, each starting where the one before ends), from where the own piece's straight arms end as far as the
/// foam lasts: the envelope of the waves' energy circles along the path (module header), worked out at points
/// along it (every 2 % of the distance back, 2–10 m apart) and joined by straight stretches, left arm then right.
fn bent_arms(chain: &[Wake]) -> Vec<ArmSegment> {
    let own = &chain[0];
    let shapes: Vec<WakeShape> = chain.iter().filter_map(WakeShape::new).collect();
    if chain.len() < 2 || shapes.len() != chain.len() {
        return Vec::new();
    }
    let (u, length) = (own.speed, own.length);
    // The path back from the vessel's stern: piece k from `q = back_k` (metres of path) to the next piece's
    // start (the last one as far as it reaches, at most 100 km); the pieces' headings unwrapped.
    let starts: Vec<f32> = shapes.iter().map(|s| s.back).collect();
    let ends: Vec<f32> = (0..chain.len())
        .map(|k| if k + 1 < chain.len() { starts[k + 1] } else { starts[k] + chain[k].reach_m.min(1e5) })
        .collect();
    let mut headings = Vec::with_capacity(chain.len());
    for w in chain {
        let mut h = w.heading;
        if let Some(&prev) = headings.last() {
            let prev: f32 = prev;
            h = prev + (h - prev + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU) - std::f32::consts::PI;
        }
        headings.push(h);
    }
    // The heading turns from one piece's to the next's over the stretch round their joint as long as the shorter of
    // the two (so along a turn cut into equal chords the heading runs linearly between the chords' middles, at the
    // turn's curvature), starting at the joint on the own piece (straight by definition).
    let mut anchors: Vec<(f32, f32)> = Vec::with_capacity(2 * chain.len());
    for k in 0..chain.len() - 1 {
        let joint = starts[k + 1];
        let m = 0.5 * (ends[k] - starts[k]).min(ends[k + 1] - starts[k + 1]).max(0.0);
        anchors.push((if k == 0 { joint } else { joint - m }, headings[k]));
        anchors.push((joint + m, headings[k + 1]));
    }
    // Heading at `q`, and its rate going back along the path (rad per metre) on the stretch between anchors that
    // starts at `q` (`after`) or ends there.
    let heading_at = |q: f32, after: bool| -> (f32, f32) {
        let i = anchors.iter().position(|&(aq, _)| if after { aq > q } else { aq >= q });
        match i {
            Some(0) => (anchors[0].1, 0.0),
            None => (anchors[anchors.len() - 1].1, 0.0),
            Some(i) => {
                let ((q0, h0), (q1, h1)) = (anchors[i - 1], anchors[i]);
                let rate = (h1 - h0) / (q1 - q0).max(1e-3);
                (h0 + rate * (q - q0), rate)
            }
        }
    };
    let point_at = |q: f32| -> [f32; 2] {
        let k = (0..chain.len()).rev().find(|&k| starts[k] <= q).unwrap_or(0);
        let s = &shapes[k];
        let b = q - s.back;
        [s.stern[0] - s.dir[0] * b, s.stern[1] - s.dir[1] * b]
    };
    // From the end of the own piece's straight stretch to the foam's end, every 2 % of the way back (2–10 m), and
    // at every anchor twice, with the curvature before and after it (the envelope there goes round the circle of
    // that point from one to the other; a straight stretch joins them).
    let q_max = (u * WAKE_REACH_S - length).min(ends[chain.len() - 1]);
    let mut samples: Vec<(f32, bool)> = Vec::new();
    let mut q = ends[0];
    let mut next_anchor = 0;
    while q <= q_max {
        while next_anchor < anchors.len() && anchors[next_anchor].0 <= q {
            let aq = anchors[next_anchor].0;
            if aq >= ends[0] && aq <= q_max {
                samples.push((aq, false));
                samples.push((aq, true));
            }
            next_anchor += 1;
        }
        if samples.last().is_none_or(|&(last, _)| last < q) {
            samples.push((q, true));
        }
        q += (0.02 * (q + length)).clamp(2.0, 10.0);
    }
    let mut sides: [Vec<([f32; 2], f32)>; 2] = [Vec::new(), Vec::new()];
    for (q, after) in samples {
        let e = q + length;
        let p = point_at(q);
        let (h, back_rate) = heading_at(q, after);
        // Forward curvature κ = −dθ/dq; with k = E κ the normal to the envelope is at ψ = φ ± acos(1/√(9 + k²))
        // from the heading, φ = atan2(k, 3) (3 cos ψ + k sin ψ = 1).
        let k = -e * back_rate;
        let (phi, spread) = (k.atan2(3.0), (1.0 / (9.0 + k * k).sqrt()).acos());
        let (sh, ch) = h.sin_cos();
        for (side, psi) in [(0, phi + spread), (1, phi - spread)] {
            let (sp, cp) = psi.sin_cos();
            // n = cos ψ ĥ + sin ψ ĥ⊥ (ĥ⊥ to port); the point: P + (E/4)(ĥ + n).
            let n = [cp * ch - sp * sh, cp * sh + sp * ch];
            sides[side].push(([p[0] + 0.25 * e * (ch + n[0]), p[1] + 0.25 * e * (sh + n[1])], e));
        }
    }
    // Runs of points within 5 cm of the straight stretch between their ends are drawn as that one stretch (the
    // straight legs of a path give long runs).
    let mut out = Vec::new();
    for pts in &sides {
        let mut from = 0;
        while from + 1 < pts.len() {
            let mut to = from + 1;
            while to + 1 < pts.len() && (from + 1..=to).all(|m| off_line(pts[m].0, pts[from].0, pts[to + 1].0) <= 0.05)
            {
                to += 1;
            }
            out.push(ArmSegment::new(pts[from].0, pts[to].0, [pts[from].1, pts[to].1], own));
            from = to;
        }
    }
    out
}

/// How far `p` lies from the straight stretch from `a` to `b` (metres).
fn off_line(p: [f32; 2], a: [f32; 2], b: [f32; 2]) -> f32 {
    let (ab, ap) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 { ((ap[0] * ab[0] + ap[1] * ab[1]) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (ap[0] - t * ab[0]).hypot(ap[1] - t * ab[1])
}

/// The wakes of one render, prepared for lookups ([`Wakes::cover`]), optionally indexed around a sensor.
#[derive(Debug, Clone, Default)]
pub(super) struct Wakes {
    shapes: Vec<WakeShape>,
    /// The Kelvin arms bent round the vessels' paths.
    arms: Vec<ArmSegment>,
    /// Which wakes and arms may lay foam where, around a sensor ([`Wakes::around`]); `None`: every one is tried
    /// everywhere.
    grid: Option<WakeGrid>,
}

impl Wakes {
    /// The wakes of the vessels `wakes` (those too slow to leave one left out). The rows of one vessel's wake
    /// round its bends come together, newest first: a row older than 0 ([`Wake::age_s`]) right after a row of
    /// the same speed and size that goes on ([`Wake::goes_on`]) and ends within a beam of the row's start is the
    /// next piece of that wake; the Kelvin arms are bent along each such chain ([`bent_arms`]).
    pub(super) fn new(wakes: &[Wake]) -> Self {
        let shapes = wakes.iter().filter_map(WakeShape::new).collect();
        let mut arms = Vec::new();
        let mut from = 0;
        for k in 1..=wakes.len() {
            let continues = k < wakes.len() && {
                let (prev, w) = (&wakes[k - 1], &wakes[k]);
                let (s, c) = prev.heading.sin_cos();
                let end =
                    [prev.x - c * (0.5 * prev.length + prev.reach_m), prev.y - s * (0.5 * prev.length + prev.reach_m)];
                let (sw, cw) = w.heading.sin_cos();
                let start = [w.x - cw * 0.5 * w.length, w.y - sw * 0.5 * w.length];
                let same = (prev.speed, prev.length, prev.beam) == (w.speed, w.length, w.beam);
                w.age_s > 0.0 && prev.goes_on && same && (end[0] - start[0]).hypot(end[1] - start[1]) <= w.beam
            };
            if !continues {
                if k - from > 1 && wakes[from].age_s <= 0.0 {
                    arms.extend(bent_arms(&wakes[from..k]));
                }
                from = k;
            }
        }
        Self { shapes, arms, grid: None }
    }

    /// Whether there are none.
    pub(super) fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// These wakes indexed on a grid over the square of half-side `radius` metres around `centre` (see
    /// `Foam::around`): the same cover to the bit. Nothing changes with no wakes or a radius that is not a
    /// positive number.
    pub(super) fn around(mut self, centre: [f32; 2], radius: f32) -> Self {
        if self.shapes.is_empty() || !(radius > 0.0 && radius.is_finite()) {
            return self;
        }
        let n = WakeGrid::N;
        let count = self.shapes.len() + self.arms.len();
        let words = count.div_ceil(64);
        let cell = 2.0 * radius / n as f32;
        let origin = [centre[0] - radius, centre[1] - radius];
        let reach = cell * std::f32::consts::FRAC_1_SQRT_2 * 1.001 + 0.01;
        let mut bits = vec![0u64; n * n * words];
        for j in 0..n {
            for i in 0..n {
                let c = [origin[0] + (i as f32 + 0.5) * cell, origin[1] + (j as f32 + 0.5) * cell];
                let cell_bits = &mut bits[(j * n + i) * words..(j * n + i + 1) * words];
                let shapes = self.shapes.iter().map(|w| w.may_reach(c, reach));
                let arms = self.arms.iter().map(|a| a.may_reach(c, reach));
                for (k, hit) in shapes.chain(arms).enumerate() {
                    if hit {
                        cell_bits[k / 64] |= 1u64 << (k % 64);
                    }
                }
            }
        }
        self.grid = Some(WakeGrid { origin, inv_cell: 1.0 / cell, words, bits });
        self
    }

    /// The foam wake `k` lays at `(x, y)` (the shapes, then the bent arms).
    #[inline(always)]
    fn foam_of(&self, k: usize, x: f32, y: f32, noise_at: &mut impl FnMut() -> f32) -> f32 {
        match self.shapes.get(k) {
            Some(w) => w.foam_at(x, y, noise_at),
            None => self.arms[k - self.shapes.len()].foam_at(x, y, noise_at),
        }
    }

    /// The densest wake foam at world `(x, y)` (0 where none), `noise_at` the foam noise there.
    #[inline(always)]
    pub(super) fn cover(&self, x: f32, y: f32, noise_at: &mut impl FnMut() -> f32) -> f32 {
        let mut c = 0.0f32;
        match self.grid.as_ref().and_then(|g| g.mask(x, y)) {
            Some(words) => {
                for (base, &word) in words.iter().enumerate() {
                    let mut m = word;
                    while m != 0 {
                        let k = base * 64 + m.trailing_zeros() as usize;
                        m &= m - 1;
                        c = c.max(self.foam_of(k, x, y, noise_at));
                    }
                }
            }
            None => {
                for k in 0..self.shapes.len() + self.arms.len() {
                    c = c.max(self.foam_of(k, x, y, noise_at));
                }
            }
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::super::foam::{standard_normal, Foam};
    use super::*;
    use crate::sensors::noise;

    /// Wakes indexed around a sensor give every point the cover of every wake tried, to the bit, and most
    /// points there try none.
    #[test]
    fn wakes_indexed_around_a_sensor_give_the_same_cover() {
        let wakes: Vec<Wake> = (0..7)
            .map(|i| {
                let f = i as f32;
                Wake {
                    x: 40.0 * f - 120.0,
                    y: 25.0 * (f * 1.7).sin() * f,
                    heading: 0.9 * f - 2.0,
                    speed: 1.0 + 2.3 * f,
                    length: 4.0 + 30.0 * f,
                    beam: 2.0 + 3.0 * f,
                    reach_m: if i == 3 || i == 5 { 40.0 } else { f32::INFINITY },
                    age_s: if i == 5 { 25.0 } else { 0.0 },
                    goes_on: i == 5,
                }
            })
            .collect();
        let plain = Foam::new(0.02, &wakes, 11).on_crests();
        let indexed = plain.clone().around([10.0, -20.0], 200.0);
        // (The same index, built on its own, to count the points that try no wake.)
        let own = Wakes::new(&wakes).around([10.0, -20.0], 200.0);
        let grid = own.grid.as_ref().unwrap_or_else(|| unreachable!());
        let (mut foamy, mut tried_none) = (0, 0);
        for i in 0..300_000u64 {
            // Inside the grid and a margin beyond it (where every wake is tried).
            let x = noise::uniform(3, 1, 2 * i) as f32 * 520.0 - 250.0;
            let y = noise::uniform(3, 1, 2 * i + 1) as f32 * 520.0 - 280.0;
            let crest = Some(standard_normal(8, i));
            let (a, b) = (plain.cover(x, y, crest), indexed.cover(x, y, crest));
            assert_eq!(a.to_bits(), b.to_bits(), "({x}, {y})");
            foamy += usize::from(a > 0.0);
            tried_none += usize::from(grid.mask(x, y).is_some_and(|m| m.iter().all(|&w| w == 0)));
        }
        assert!(foamy > 10_000, "{foamy}");
        assert!(tried_none > 75_000, "{tried_none}");
        // More wakes than one word holds (the pieces of wakes round their vessels' bends, many vessels).
        let many: Vec<Wake> = (0..150)
            .map(|i| {
                let f = i as f32;
                Wake {
                    x: 7.0 * f - 500.0,
                    y: 30.0 * (f * 0.37).sin(),
                    heading: 0.41 * f,
                    speed: 2.0 + (i % 9) as f32,
                    length: 5.0 + (i % 5) as f32 * 8.0,
                    beam: 2.0 + (i % 4) as f32,
                    reach_m: 20.0 + 3.0 * (i % 11) as f32,
                    age_s: (i % 7) as f32 * 6.0,
                    goes_on: i % 2 == 0,
                }
            })
            .collect();
        let plain = Foam::new(0.0, &many, 5);
        let indexed = plain.clone().around([-100.0, 0.0], 300.0);
        let mut foamy = 0;
        for i in 0..100_000u64 {
            let x = noise::uniform(4, 1, 2 * i) as f32 * 700.0 - 450.0;
            let y = noise::uniform(4, 1, 2 * i + 1) as f32 * 700.0 - 350.0;
            let (a, b) = (plain.cover(x, y, None), indexed.cover(x, y, None));
            assert_eq!(a.to_bits(), b.to_bits(), "({x}, {y})");
            foamy += usize::from(a > 0.0);
        }
        assert!(foamy > 5_000, "{foamy}");
        // No grid without wakes, or with a radius that is not a positive number.
        assert!(Wakes::new(&[]).around([0.0, 0.0], 100.0).grid.is_none());
        assert!(Wakes::new(&wakes).around([0.0, 0.0], f32::NAN).grid.is_none());
    }

    #[test]
    fn wake_lies_behind_and_on_the_kelvin_arms() {
        let w = Wake {
            x: 0.0,
            y: 0.0,
            heading: 0.0,
            speed: 12.0,
            length: 10.0,
            beam: 3.0,
            reach_m: f32::INFINITY,
            age_s: 0.0,
            goes_on: false,
        };
        let foam = Foam::new(0.0, &[w], 3);
        // The mean cover over a patch (the foam is broken up by noise, so single points may be clear).
        let patch = |f: &Foam, x: f32, y: f32| {
            let mut s = 0.0;
            for i in 0..21 {
                for j in 0..21 {
                    s += f.cover(x + (i as f32 - 10.0) * 0.5, y + (j as f32 - 10.0) * 0.05, None);
                }
            }
            s / 441.0
        };
        // Right behind the stern: foam. Ahead of the bow: none.
        assert!(patch(&foam, -12.0, 0.0) > 0.2);
        assert_eq!(patch(&foam, 30.0, 0.0), 0.0);
        // 100 m behind the stern (110 m behind the bow), the arms are at ±38.9 m; between them and the track,
        // none.
        let behind = -5.0 - 100.0;
        assert!(patch(&foam, behind, 38.89) > 0.03);
        assert!(patch(&foam, behind, -38.89) > 0.03);
        assert_eq!(patch(&foam, behind, 18.0), 0.0);
        // A slow craft leaves a faint track.
        let slow = Foam::new(0.0, &[Wake { speed: 1.5, ..w }], 3);
        assert!(patch(&slow, -12.0, 0.0) < 0.1 * patch(&foam, -12.0, 0.0));
        // A path that ran straight only 30 m behind the stern (it turned there): foam no farther, on the track
        // or the arms.
        let turned = Foam::new(0.0, &[Wake { reach_m: 30.0, ..w }], 3);
        assert!(patch(&turned, -12.0, 0.0) > 0.2);
        assert_eq!(patch(&turned, behind, 38.89), 0.0);
        assert_eq!(patch(&turned, -5.0 - 40.0, 0.0), 0.0);
        assert!(patch(&foam, -5.0 - 40.0, 0.0) > 0.1);
        // An older piece of a wake (its vessel passed its start 30 s, 360 m, ago): on its track, the foam of a
        // vessel 360 m further on along the same line, as faded and widened since; without the Kelvin arms.
        let aged = Foam::new(0.0, &[Wake { age_s: 30.0, goes_on: true, ..w }], 3);
        let ahead = Foam::new(0.0, &[Wake { x: 360.0, ..w }], 3);
        for (x, y) in [(-5.0 - 200.0, 0.0), (-5.0 - 100.0, 4.0), (-5.0 - 300.0, -5.5)] {
            let (a, b) = (patch(&aged, x, y), patch(&ahead, x, y));
            assert!(a > 0.02 && (a - b).abs() <= 1e-5 * b, "({x}, {y}): {a} against {b}");
        }
        assert_eq!(patch(&aged, behind, 38.89), 0.0);
        // Its foam lasts only what is left of its life: 120 s − 100 s at 12 m/s, 240 m.
        let old = Foam::new(0.0, &[Wake { age_s: 100.0, goes_on: true, ..w }], 3);
        assert!(patch(&old, -5.0 - 200.0, 0.0) > 0.0);
        assert_eq!(patch(&old, -5.0 - 250.0, 0.0), 0.0);
        // A piece whose older foam goes on in the next one ends at its reach at full strength (past it by its
        // track's half-width, 3.2 m here, to fill the bend's outer corner); a wake whose path bent with nothing after
        // it thins out before.
        let piece = Foam::new(0.0, &[Wake { reach_m: 60.0, goes_on: true, ..w }], 3);
        let ended = Foam::new(0.0, &[Wake { reach_m: 60.0, ..w }], 3);
        let near_end = -5.0 - 52.0;
        assert_eq!(patch(&piece, near_end, 0.0), patch(&foam, near_end, 0.0));
        assert!(patch(&ended, near_end, 0.0) < 0.7 * patch(&piece, near_end, 0.0));
        assert_eq!(patch(&piece, -5.0 - 69.0, 0.0), 0.0);
        assert!(patch(&piece, -5.0 - 63.0, 0.0) > 0.0);
    }

    /// Round a bend the Kelvin arms are the envelope of the waves sent out along the path (module header), worked
    /// out here by brute force: the boundary of the union of the energy circles (centre `P + Eĥ/4`, radius `E/4`)
    /// sent out every 0.25 m along the smooth path itself, a quarter circle of radius 60 m between two straight legs.
    /// Every point of that boundary from 15 m behind the stern on lies on an arm drawn from the wake's pieces (the
    /// own piece and 15° chords of the turn, as `Simulation.wakes` gives them), and farther than 10 m outside it
    /// there is no foam;
    /// indexed around a sensor, the same cover to the bit. (Before, the arms ended at the bend: no foam along the
    /// boundary round and before the turn.)
    #[test]
    fn kelvin_arms_round_a_bend_follow_the_envelope_of_the_waves_sent_out() {
        use std::f64::consts::FRAC_PI_2;
        // Heading east along y = 0, then a quarter turn to port round (0, 60), then north; the stern is now at
        // (60, 120), 60 m past the turn.
        let (u, length, beam, rho) = (10.0f64, 20.0f64, 5.0f64, 60.0f64);
        let arc = |t: f64| [rho * t.sin(), rho * (1.0 - t.cos())];
        let row = |stern: [f64; 2], heading: f64, reach: f64, back: f64| Wake {
            x: (stern[0] + 0.5 * length * heading.cos()) as f32,
            y: (stern[1] + 0.5 * length * heading.sin()) as f32,
            heading: heading as f32,
            speed: u as f32,
            length: length as f32,
            beam: beam as f32,
            reach_m: reach as f32,
            age_s: (back / u) as f32,
            goes_on: true,
        };
        let mut rows = vec![row([60.0, 120.0], FRAC_PI_2, 60.0, 0.0)];
        let step = 15f64.to_radians();
        for j in 0..6 {
            let (t0, t1) = (FRAC_PI_2 - f64::from(j) * step, FRAC_PI_2 - f64::from(j + 1) * step);
            let (a, b) = (arc(t0), arc(t1));
            rows.push(row(a, 0.5 * (t0 + t1), (a[0] - b[0]).hypot(a[1] - b[1]), 60.0 + rho * f64::from(j) * step));
        }
        rows.push(row([0.0, 0.0], 0.0, 2000.0, 60.0 + rho * FRAC_PI_2));
        let wakes = Wakes::new(&rows);
        let density = |x: f64, y: f64| wakes.cover(x as f32, y as f32, &mut || 1.0);
        // The energy circles of the smooth path: (centre, radius) per point sent out; E from the bow.
        let mut circles: Vec<([f64; 2], f64)> = Vec::new();
        let mut add = |p: [f64; 2], h: f64, e: f64| {
            circles.push(([p[0] + 0.25 * e * h.cos(), p[1] + 0.25 * e * h.sin()], 0.25 * e));
        };
        for i in 0..=320 {
            let b = -20.0 + 0.25 * f64::from(i); // behind the stern, from the bow to the turn
            add([60.0, 120.0 - b], FRAC_PI_2, length + b);
        }
        let turn = rho * FRAC_PI_2;
        for i in 0..=(turn / 0.25) as usize {
            let s = 0.25 * i as f64;
            let t = FRAC_PI_2 - s / rho;
            add(arc(t), t, length + 60.0 + s);
        }
        for i in 0..=4000 {
            let b = 0.25 * f64::from(i);
            add([-b, 0.0], 0.0, length + 60.0 + turn + b);
        }
        let inside = |x: [f64; 2]| circles.iter().any(|(c, r)| (x[0] - c[0]).hypot(x[1] - c[1]) < *r);
        // How far a point outside the union is from it.
        let gap =
            |x: [f64; 2]| circles.iter().map(|(c, r)| (x[0] - c[0]).hypot(x[1] - c[1]) - r).fold(f64::MAX, f64::min);
        // The first way out of the union from a point inside along a direction (to 0.02 m).
        let exit = |from: [f64; 2], dir: [f64; 2]| {
            let at = |t: f64| [from[0] + t * dir[0], from[1] + t * dir[1]];
            let mut t = 0.0;
            while inside(at(t + 0.5)) {
                t += 0.5;
            }
            let (mut lo, mut hi) = (t, t + 0.5);
            while hi - lo > 0.02 {
                let mid = 0.5 * (lo + hi);
                if inside(at(mid)) {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            at(lo)
        };
        let mut rays: Vec<([f64; 2], [f64; 2])> = Vec::new();
        for y0 in [70.0, 85.0, 105.0] {
            rays.push(([60.0, y0], [1.0, 0.0]));
            rays.push(([60.0, y0], [-1.0, 0.0]));
        }
        for deg in [10.0f64, 30.0, 45.0, 60.0, 80.0] {
            let t = deg.to_radians();
            rays.push((arc(t), [t.sin(), -t.cos()])); // outside the turn
            rays.push((arc(t), [-t.sin(), t.cos()])); // inside
        }
        for x0 in [-30.0, -100.0, -200.0, -300.0] {
            rays.push(([x0, 0.0], [0.0, -1.0]));
            rays.push(([x0, 0.0], [0.0, 1.0]));
        }
        let mut beyond = 0;
        for (from, dir) in rays {
            let b = exit(from, dir);
            assert!(density(b[0], b[1]) > 0.0, "the envelope at ({:.2}, {:.2}) (from {from:?}) has no arm", b[0], b[1]);
            // Well outside the union (farther from every circle than the widest arm here, 10 m), no foam.
            let out = [b[0] + 25.0 * dir[0], b[1] + 25.0 * dir[1]];
            if gap(out) > 10.0 {
                assert_eq!(density(out[0], out[1]), 0.0, "beyond the envelope at {out:?}");
                beyond += 1;
            }
        }
        assert!(beyond >= 10, "{beyond}");
        assert!(wakes.arms.len() > 20, "{}", wakes.arms.len());
        // Between the outer arm and the track before the turn, inside the envelope: no foam.
        for x0 in [-200.0, -300.0] {
            let arm = exit([x0, 0.0], [0.0, -1.0])[1];
            assert_eq!(density(x0, 0.5 * arm), 0.0);
        }
        // Indexed around a sensor: the same cover to the bit.
        let foam = Foam::new(0.0, &rows, 5);
        let indexed = foam.clone().around([0.0, 50.0], 400.0);
        let mut foamy = 0;
        for i in 0..100_000u64 {
            let x = noise::uniform(6, 1, 2 * i) as f32 * 900.0 - 500.0;
            let y = noise::uniform(6, 1, 2 * i + 1) as f32 * 900.0 - 400.0;
            let (a, b) = (foam.cover(x, y, None), indexed.cover(x, y, None));
            assert_eq!(a.to_bits(), b.to_bits(), "({x}, {y})");
            foamy += usize::from(a > 0.0);
        }
        assert!(foamy > 1_000, "{foamy}");
    }
}
