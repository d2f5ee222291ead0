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
//! never went. A vessel that has come to rest at its route's end leaves its foam as it lay when it stopped, aging
//! (every row older by the time since; no Kelvin arms: its waves have run off with their group speed). The foam is
//! broken up by the same noise as the whitecaps (`foam.rs`).
//!
//! Only the Kelvin angle is a published law. The foam is the project's own calibration, not a published model: no
//! published law for a wake's foam density against speed, its fade time or its track's widening was found
//! (searched 2026-12-02). The strengths `(V / 6 m/s)²` (track) and `(V / 8 m/s)²` (arms), full from 6 and 8 m/s,
//! the 30 s e-folding fade, the track's half-width `½ B (1 + ¼ √(d / max(B, 1 m)))` (`B` the beam, `d` the
//! metres of path since the stern passed) and an arm's width `0.3 m + 0.02 · (metres from the bow) + 0.1 B` were
//! chosen so that a slow craft leaves a faint trace and a fast one a bright track as wide as its beam with two
//! fainter arms (`docs/realism/README.md`, *A wake behind a fast craft*). The Kelvin angle itself holds for a
//! point source in deep water; from airborne images Rabaud & Moisy (2013), "Ship wakes: Kelvin or Mach angle?",
//! arXiv:1304.2653, find the wake angle falling as `1 / U` above a hull Froude number `U / √(g L)` ≈ 0.5 (0.76
//! for a 35 m boat at 14 m/s), where these arms keep 19.47°. Darmon, Benzaquen & Raphaël (2014), "Kelvin wake
//! pattern at large Froude numbers", J. Fluid Mech. 738, R3 (arXiv:1309.6751), find for a moving pressure
//! disturbance that the angle of the waves' *largest amplitude* falls as `1 / Fr` while the angle *bounding* the
//! wake, outside which the water is flat, stays the Kelvin angle at every Froude number: these arms mark that
//! bound; the narrower crest of the brightest waves at high Froude number is not drawn.
//!
//! The Kelvin arms round a bend are worked out in `kelvin_bend.rs`.

mod kelvin_bend;

use kelvin_bend::{bent_arms, ArmSegment};

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
    /// The vessel's displaced volume, m³: the strength of its Kelvin waves (`kelvin.rs`; 0: none drawn).
    pub displacement_m3: f32,
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

/// How strong the Kelvin arms of a vessel at `speed` m/s are (a fresh arm's middle: 0.45 of this foam).
#[inline(always)]
fn arm_strength(speed: f32) -> f32 {
    (speed / 8.0).powi(2).min(1.0)
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
        let prepared: Vec<Option<WakeShape>> = wakes.iter().map(WakeShape::new).collect();
        let mut arms = Vec::new();
        let mut from = 0;
        for k in 1..=wakes.len() {
            let continues = k < wakes.len() && {
                let (prev, w) = (&wakes[k - 1], &wakes[k]);
                match (&prepared[k - 1], &prepared[k]) {
                    (Some(p), Some(s)) => {
                        let end = [p.stern[0] - p.dir[0] * prev.reach_m, p.stern[1] - p.dir[1] * prev.reach_m];
                        let same = (prev.speed, prev.length, prev.beam) == (w.speed, w.length, w.beam);
                        let gap = (end[0] - s.stern[0]).hypot(end[1] - s.stern[1]);
                        w.age_s > 0.0 && prev.goes_on && same && gap <= w.beam
                    }
                    _ => false,
                }
            };
            if !continues {
                if k - from > 1 && wakes[from].age_s <= 0.0 {
                    let chain: Vec<WakeShape> = prepared[from..k].iter().flatten().copied().collect();
                    arms.extend(bent_arms(&wakes[from..k], &chain));
                }
                from = k;
            }
        }
        Self { shapes: prepared.into_iter().flatten().collect(), arms, grid: None }
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

    /// Asserts that `plain` and `indexed` (the same foam, indexed around a sensor) give the same cover to the bit
    /// at 100,000 points drawn by `seed` over the square of side `side` from `corner`; returns how many have foam.
    pub(super) fn same_cover(plain: &Foam, indexed: &Foam, seed: u64, corner: [f32; 2], side: f32) -> usize {
        let mut foamy = 0;
        for i in 0..100_000u64 {
            let x = noise::uniform(seed, 1, 2 * i) as f32 * side + corner[0];
            let y = noise::uniform(seed, 1, 2 * i + 1) as f32 * side + corner[1];
            let (a, b) = (plain.cover(x, y, None), indexed.cover(x, y, None));
            assert_eq!(a.to_bits(), b.to_bits(), "({x}, {y})");
            foamy += usize::from(a > 0.0);
        }
        foamy
    }

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
                    displacement_m3: 0.0,
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
                    displacement_m3: 0.0,
                }
            })
            .collect();
        let plain = Foam::new(0.0, &many, 5);
        let indexed = plain.clone().around([-100.0, 0.0], 300.0);
        let foamy = same_cover(&plain, &indexed, 4, [-450.0, -350.0], 700.0);
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
            displacement_m3: 0.0,
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
}
