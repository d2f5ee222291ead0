//! The sky horizon of one viewpoint: rays that all leave one point (a camera's pixels, a LiDAR's beams) and rise
//! above everything around it hit nothing.
//!
//! For a point `P` above the sea, a [`Horizon`] holds, per azimuth bin around `P`, an upper bound of the slope
//! (rise over horizontal run) at which a ray from `P` may still meet something. An obstacle is a vertical
//! column with a footprint (a rectangle or a triangle) and a top, holding everything of it: a ray from `P` with
//! slope `s` is at height `P.z + s·r` at horizontal distance `r`, so it passes over a column whose footprint is
//! at least `r_min` away once `s > (top − P.z) / r_min`. The bound of a bin is the largest such slope over the
//! obstacles whose azimuth range (seen from `P`) touches it, widened by one bin on each side for rounding.
//!
//! The obstacles are the cells of the static height map (through a max pyramid, so far blocks count as one), the
//! moving instances by their world boxes, and, triangle by triangle, any moving instance whose box stands over
//! `P` (a USV's own hull). A column standing over `P` and rising above it settles nothing. The triangles of those
//! near instances mark, in a bitmap of azimuth × slope cells, every direction in which a ray from `P` can meet
//! them among the rising directions (a sensor pod's roof hides only the steep slopes; a deck below the viewpoint
//! hides none). Tops carry the height map's margin, distances lose a millimetre and slope bounds a relative
//! 1e-5, so a settled ray passes clear of everything: the answer, a miss, is exactly the full trace's.

/// Azimuth bins around the viewpoint.
const BINS: usize = 2048;
/// A pyramid block counts as one obstacle once its diagonal is below this angle (radians, sixteen bins) as
/// seen from the viewpoint.
const BLOCK_ANGLE: f64 = 16.0 * std::f64::consts::TAU / BINS as f64;
/// Distances to footprints are shortened by this much (metres) against rounding in world coordinates.
const DISTANCE_SLACK_M: f64 = 1e-3;
/// Triangle tops are raised by this much (metres): far more than the rounding of a world-frame vertex.
const TRIANGLE_MARGIN_M: f32 = 0.01;

/// Max pyramid of a height map: level 0 is the map, every next level holds the maximum of 2×2 cells below it.
#[derive(Debug, Clone, Default)]
pub(super) struct MaxPyramid {
    /// `(nx, ny, heights)` per level, row-major `y · nx + x`.
    levels: Vec<(usize, usize, Vec<f32>)>,
}

impl MaxPyramid {
    /// The pyramid of `base` (`nx × ny` cells, row-major).
    pub(super) fn new(nx: usize, ny: usize, base: &[f32]) -> Self {
        let mut levels = vec![(nx, ny, base.to_vec())];
        while let Some((w, h, cells)) = levels.last() {
            if *w == 1 && *h == 1 {
                break;
            }
            let (w2, h2) = (w.div_ceil(2), h.div_ceil(2));
            let mut up = vec![f32::NEG_INFINITY; w2 * h2];
            for y in 0..*h {
                for x in 0..*w {
                    let c = &mut up[(y / 2) * w2 + x / 2];
                    *c = c.max(cells[y * w + x]);
                }
            }
            levels.push((w2, h2, up));
        }
        Self { levels }
    }

    /// Adds every block above the viewpoint to `h`: the cells of level 0 (lower corner `(x0, y0)`, side `cell`)
    /// near it, and whole blocks where they look small from it.
    pub(super) fn add_to(&self, h: &mut Horizon, x0: f32, y0: f32, cell: f32) {
        let Some(top) = self.levels.len().checked_sub(1) else { return };
        let n0 = (self.levels[0].0, self.levels[0].1);
        let (x0, y0, cell) = (f64::from(x0), f64::from(y0), f64::from(cell));
        let pz = f64::from(h.origin[2]);
        let mut stack = vec![(top, 0usize, 0usize)];
        while let Some((k, ix, iy)) = stack.pop() {
            let (w, hgt, cells) = &self.levels[k];
            if ix >= *w || iy >= *hgt {
                continue;
            }
            let height = f64::from(cells[iy * w + ix]);
            if height < pz {
                continue; // everything there is below the viewpoint (or nothing is there)
            }
            let (i0, i1) = (ix << k, ((ix + 1) << k).min(n0.0));
            let (j0, j1) = (iy << k, ((iy + 1) << k).min(n0.1));
            let lo = [x0 + i0 as f64 * cell, y0 + j0 as f64 * cell];
            let hi = [x0 + i1 as f64 * cell, y0 + j1 as f64 * cell];
            let r = h.rect_distance(lo, hi);
            let diag = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
            if k == 0 || (r > 0.0 && diag <= BLOCK_ANGLE * r) {
                h.add_rect(lo, hi, height);
            } else {
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    stack.push((k - 1, 2 * ix + dx, 2 * iy + dy));
                }
            }
        }
    }
}

/// The sky horizon of one viewpoint (see the module docs).
#[derive(Debug, Clone)]
pub struct Horizon {
    /// The viewpoint.
    origin: [f32; 3],
    /// Per azimuth bin, the slope a ray must exceed to pass over every column (`f32::MIN` where none stands).
    slope: Vec<f32>,
    /// Direction cells the triangles of the near instances may lie in: [`SLOPE_WORDS`] words of bits per
    /// azimuth bin, bit `e` for the slopes `s` with `(q + 1) / 2` in `[e, e + 1) / SLOPE_BINS`, where
    /// `q = s / (1 + |s|)` (−1 straight down, 1 straight up). Only the rising half (`e ≥ SLOPE_BINS / 2`) is
    /// marked and read.
    bands: Vec<u64>,
    /// Whether any band bit is set.
    any_bands: bool,
    /// A column stands over the viewpoint and rises above it: no rising ray is settled.
    covered: bool,
}

/// Slope bins of [`Horizon::bands`] per azimuth bin.
const SLOPE_BINS: usize = 512;
/// `u64` words per azimuth bin.
const SLOPE_WORDS: usize = SLOPE_BINS / 64;

impl Horizon {
    /// A horizon of `origin` with nothing around it yet.
    pub(super) fn new(origin: [f32; 3]) -> Self {
        Self {
            origin,
            slope: vec![f32::MIN; BINS],
            bands: vec![0; BINS * SLOPE_WORDS],
            any_bands: false,
            covered: false,
        }
    }

    /// The viewpoint.
    pub fn origin(&self) -> [f32; 3] {
        self.origin
    }

    /// Whether a ray from the viewpoint with unit direction `d` surely hits nothing: it does not go down, rises
    /// more steeply than the columns of its azimuth bin, and its direction cell holds no near triangle.
    /// `false` means "not known".
    #[inline(always)]
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: a NaN must answer "not known"
    pub fn clear(&self, d: [f32; 3]) -> bool {
        if !(d[2] >= 0.0) || self.covered {
            return false;
        }
        let run = (d[0] * d[0] + d[1] * d[1]).sqrt();
        let bin = azimuth_bin(d);
        if !(d[2] > self.slope[bin] * run) {
            return false;
        }
        !self.any_bands || self.band_free(bin, d, run)
    }

    #[inline(always)]
    fn band_free(&self, bin: usize, d: [f32; 3], run: f32) -> bool {
        let q = d[2] / (run + d[2].abs());
        let e = (((q + 1.0) * (SLOPE_BINS / 2) as f32) as usize).min(SLOPE_BINS - 1);
        self.bands[bin * SLOPE_WORDS + e / 64] & (1 << (e % 64)) == 0
    }

    /// Adds a column over the rectangle `lo..hi` (world x, y) holding everything there at or below `top`
    /// (margin included).
    pub(super) fn add_rect(&mut self, lo: [f64; 2], hi: [f64; 2], top: f64) {
        let pz = f64::from(self.origin[2]);
        if top < pz {
            return;
        }
        let r = self.rect_distance(lo, hi) - DISTANCE_SLACK_M;
        if r <= 0.0 {
            self.covered = true;
            return;
        }
        let corners = [[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]];
        let (b0, b1) = self.bins_of(&corners);
        let s = (((top - pz) / r) * (1.0 + 1e-5)) as f32;
        for b in b0..=b1 {
            let v = &mut self.slope[b.rem_euclid(BINS as i64) as usize];
            *v = v.max(s);
        }
    }

    /// Adds a triangle of a near instance (world frame), widened up and down by [`TRIANGLE_MARGIN_M`]: the
    /// direction cells of every slope at which a ray from the viewpoint can meet its height range over its
    /// footprint (`z / r` over heights `z` and horizontal distances `r` of the triangle), in its azimuth range
    /// (all of them when it lies over or under the viewpoint).
    pub(crate) fn add_triangle(&mut self, tri: [[f32; 3]; 3]) {
        let p = self.origin.map(f64::from);
        let (zlo, zhi) = tri.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), v| (a.min(v[2]), b.max(v[2])));
        let (a, b) = (f64::from(zlo - TRIANGLE_MARGIN_M) - p[2], f64::from(zhi + TRIANGLE_MARGIN_M) - p[2]);
        let xy = tri.map(|v| [f64::from(v[0]) - p[0], f64::from(v[1]) - p[1]]);
        let r_max = xy.iter().map(|v| norm(v[0], v[1])).fold(0.0, f64::max) + DISTANCE_SLACK_M;
        // Wholly below the viewpoint, the steepest slope is `b / r_max` whatever the footprint's nearest point:
        // a triangle that marks nothing is known before the footprint's distance and azimuths are worked out.
        if b < 0.0 && marks_nothing(b / r_max) {
            return;
        }
        let r_min = triangle_distance(&xy) - DISTANCE_SLACK_M;
        let (bins, s_lo, s_hi) = if r_min > 0.0 {
            let corners = tri.map(|v| [f64::from(v[0]), f64::from(v[1])]);
            (self.bins_of(&corners), (a / r_min).min(a / r_max), (b / r_min).max(b / r_max))
        } else {
            let lo = if a > 0.0 { a / r_max } else { f64::NEG_INFINITY };
            let hi = if b < 0.0 { b / r_max } else { f64::INFINITY };
            ((0, BINS as i64 - 1), lo, hi)
        };
        // Only the rising half is ever read ([`Horizon::clear`]): a triangle wholly below it marks nothing.
        if marks_nothing(s_hi) {
            return;
        }
        let e1 = slope_bin(s_hi, 1).min(SLOPE_BINS as i64 - 1);
        let e0 = slope_bin(s_lo, -1).clamp((SLOPE_BINS / 2) as i64, e1) as usize;
        let e1 = e1 as usize;
        let mut mask = [0u64; SLOPE_WORDS];
        for (w, m) in mask.iter_mut().enumerate() {
            let (lo, hi) = (e0.max(64 * w), e1.min(64 * w + 63));
            if lo <= hi {
                let span = hi - lo + 1;
                *m = (if span == 64 { u64::MAX } else { (1u64 << span) - 1 }) << (lo - 64 * w);
            }
        }
        for bin in bins.0..=bins.1 {
            let row = bin.rem_euclid(BINS as i64) as usize * SLOPE_WORDS;
            for (word, m) in self.bands[row..row + SLOPE_WORDS].iter_mut().zip(&mask) {
                *word |= m;
            }
        }
        self.any_bands = true;
    }

    /// Adds every face of a near instance's mesh ([`Horizon::add_triangle`] each): `vertices` in the world
    /// frame, `faces` index triples into them. The same horizon as adding the faces one by one; a face wholly
    /// below the viewpoint, under the slope the farthest vertex would give it, is passed over on its heights
    /// alone (most of a hull under a mast-top sensor).
    pub(crate) fn add_mesh(&mut self, vertices: &[[f32; 3]], faces: &[[u32; 3]]) {
        let p = self.origin.map(f64::from);
        // The farthest vertex bounds every face's `r_max` (each is the largest of its own vertices' distances,
        // computed alike).
        let r_far = vertices.iter().map(|v| norm(f64::from(v[0]) - p[0], f64::from(v[1]) - p[1])).fold(0.0, f64::max)
            + DISTANCE_SLACK_M;
        for f in faces {
            let tri = f.map(|k| vertices[k as usize]);
            let zhi = tri[0][2].max(tri[1][2]).max(tri[2][2]);
            let b = f64::from(zhi + TRIANGLE_MARGIN_M) - p[2];
            // `b < 0`: its steepest slope `b / r_max` is at most `b / r_far`; one bin more than
            // [`marks_nothing`] asks keeps the test on the safe side of any rounding between the two slopes.
            if b < 0.0 && slope_bin(b / r_far, 2) < (SLOPE_BINS / 2) as i64 {
                continue;
            }
            self.add_triangle(tri);
        }
    }

    /// Whether the rectangle `lo..hi` (world x, y) stands over the viewpoint, or within the distance slack of it.
    pub(super) fn over(&self, lo: [f64; 2], hi: [f64; 2]) -> bool {
        self.rect_distance(lo, hi) - DISTANCE_SLACK_M <= 0.0
    }

    /// Horizontal distance from the viewpoint to the rectangle `lo..hi` (0 when it stands over it).
    fn rect_distance(&self, lo: [f64; 2], hi: [f64; 2]) -> f64 {
        let (px, py) = (f64::from(self.origin[0]), f64::from(self.origin[1]));
        let dx = (lo[0] - px).max(px - hi[0]).max(0.0);
        let dy = (lo[1] - py).max(py - hi[1]).max(0.0);
        norm(dx, dy)
    }

    /// The azimuth bins `b0..=b1` (to be taken modulo [`BINS`]) of the convex footprint with these corners
    /// (world x, y; the viewpoint outside it), one bin wider on each side.
    fn bins_of(&self, corners: &[[f64; 2]]) -> (i64, i64) {
        let (px, py) = (f64::from(self.origin[0]), f64::from(self.origin[1]));
        let mut a: [f64; 4] = [0.0; 4];
        for (k, c) in corners.iter().enumerate() {
            a[k] = pseudo_angle(c[0] - px, c[1] - py);
        }
        let a = &mut a[..corners.len()];
        let span = |a: &[f64]| {
            let lo = a.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = a.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (lo, hi)
        };
        let (mut lo, mut hi) = span(a);
        // The footprint spans less than half a turn (the viewpoint is outside it): a wider span crosses angle 0.
        // Near half a turn, rounding could mislead that test, so the whole circle is taken.
        if (hi - lo - 2.0).abs() < 0.05 {
            return (0, BINS as i64 - 1);
        }
        if hi - lo > 2.0 {
            for v in a.iter_mut() {
                if *v < 2.0 {
                    *v += 4.0;
                }
            }
            (lo, hi) = span(a);
        }
        let quarter_bins = (BINS / 4) as f64;
        let (b0, b1) = ((lo * quarter_bins).floor() as i64 - 1, (hi * quarter_bins).floor() as i64 + 1);
        if b1 - b0 + 1 >= BINS as i64 {
            (0, BINS as i64 - 1)
        } else {
            (b0, b1)
        }
    }
}

/// The diamond angle of `(x, y)` (not both zero) in either float type: `y / (x + y)` in the first quadrant, one
/// more per quarter turn. One formula for [`pseudo_angle`] (footprints) and [`pseudo_angle_f32`] (rays).
macro_rules! diamond {
    ($x:expr, $y:expr) => {{
        let (x, y) = ($x, $y);
        if y >= 0.0 {
            if x >= 0.0 {
                y / (x + y)
            } else {
                1.0 - x / (y - x)
            }
        } else if x < 0.0 {
            2.0 - y / (-x - y)
        } else {
            3.0 + x / (x - y)
        }
    }};
}

/// A monotone stand-in for the azimuth of `(x, y)` in `[0, 4)` (the "diamond angle": 1 per quarter turn,
/// opposite directions 2 apart), without trigonometry.
fn pseudo_angle(x: f64, y: f64) -> f64 {
    if x == 0.0 && y == 0.0 {
        return 0.0;
    }
    let v: f64 = diamond!(x, y);
    if v >= 4.0 {
        0.0
    } else {
        v
    }
}

/// The azimuth bin of a ray direction.
#[inline(always)]
fn azimuth_bin(d: [f32; 3]) -> usize {
    ((pseudo_angle_f32(d[0], d[1]) * (BINS / 4) as f32) as usize).min(BINS - 1)
}

/// [`pseudo_angle`] in `f32`, for rays (a rounded 4.0 is left as it is: its bin is clamped to the last).
#[inline(always)]
fn pseudo_angle_f32(x: f32, y: f32) -> f32 {
    if x == 0.0 && y == 0.0 {
        return 0.0;
    }
    diamond!(x, y)
}

/// The length of `(x, y)`, metres: `√(x² + y²)` without `hypot`'s guard against overflow and underflow, which no
/// distance in a scene (metres to kilometres, in `f64`) comes near, and which costs several times the square root
/// (the horizon computes six per triangle). Within an ulp of `hypot`; the horizon's distances carry a slack of
/// [`DISTANCE_SLACK_M`] far beyond that.
#[inline(always)]
fn norm(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

/// The slope bin of slope `s` ([`Horizon::bands`]), moved by `widen` bins (`q` is ±1 for infinite slopes).
#[inline(always)]
fn slope_bin(s: f64, widen: i64) -> i64 {
    let q = if s.is_finite() { s / (1.0 + s.abs()) } else { s.signum() };
    ((q + 1.0) * (SLOPE_BINS / 2) as f64).floor() as i64 + widen
}

/// Whether a triangle whose steepest slope from the viewpoint is `s_hi` marks no rising direction cell (its
/// highest cell, widened by one, lies in the falling half, which is never read).
#[inline(always)]
fn marks_nothing(s_hi: f64) -> bool {
    slope_bin(s_hi, 1).min(SLOPE_BINS as i64 - 1) < (SLOPE_BINS / 2) as i64
}

/// Horizontal distance from the origin to a triangle given relative to it (x, y), 0 when it lies over the
/// origin (or the triangle is degenerate through it).
fn triangle_distance(t: &[[f64; 2]; 3]) -> f64 {
    let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
    let c = [cross(t[0], t[1]), cross(t[1], t[2]), cross(t[2], t[0])];
    if c.iter().all(|&v| v >= 0.0) || c.iter().all(|&v| v <= 0.0) {
        return 0.0;
    }
    let seg = |a: [f64; 2], b: [f64; 2]| {
        let ab = [b[0] - a[0], b[1] - a[1]];
        let len2 = ab[0] * ab[0] + ab[1] * ab[1];
        let t = if len2 > 0.0 { (-(a[0] * ab[0] + a[1] * ab[1]) / len2).clamp(0.0, 1.0) } else { 0.0 };
        norm(a[0] + t * ab[0], a[1] + t * ab[1])
    };
    seg(t[0], t[1]).min(seg(t[1], t[2])).min(seg(t[2], t[0]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pseudo_angle_is_monotone_and_opposite_directions_are_two_apart() {
        let mut last = -1.0;
        for k in 0..4000 {
            let a = k as f64 * std::f64::consts::TAU / 4000.0;
            let p = pseudo_angle(a.cos(), a.sin());
            assert!(p > last || k == 0, "not increasing at step {k}: {p} after {last}");
            assert!((0.0..4.0).contains(&p));
            let q = pseudo_angle(-a.cos(), -a.sin());
            assert!(((p - q).abs() - 2.0).abs() < 1e-9, "{p} and its opposite {q}");
            let f = f64::from(pseudo_angle_f32(a.cos() as f32, a.sin() as f32));
            assert!((f - p).abs() < 1e-5 || (f - p).abs() > 3.99, "f32 {f} against f64 {p}");
            last = p;
        }
    }

    #[test]
    fn distances_to_footprints() {
        let t = [[1.0, -1.0], [1.0, 1.0], [3.0, 0.0]];
        assert!((triangle_distance(&t) - 1.0).abs() < 1e-12);
        let t = [[-1.0, -1.0], [2.0, -1.0], [0.0, 2.0]];
        assert_eq!(triangle_distance(&t), 0.0, "over the origin");
        let h = Horizon::new([0.0, 0.0, 2.0]);
        assert!((h.rect_distance([3.0, 4.0], [5.0, 6.0]) - 5.0).abs() < 1e-12);
        assert_eq!(h.rect_distance([-1.0, -1.0], [1.0, 1.0]), 0.0);
    }

    #[test]
    fn a_wall_hides_only_its_own_arc_and_only_below_its_top() {
        // A 10 m wall 20 m east of a viewpoint 2 m up, 8 m wide: its top is 8 m above the eye, 20 m away.
        let mut h = Horizon::new([0.0, 0.0, 2.0]);
        h.add_rect([20.0, -4.0], [21.0, 4.0], 10.0);
        let dir = |az: f64, slope: f64| {
            let d = [az.cos(), az.sin(), slope];
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            d.map(|v| (v / n) as f32)
        };
        assert!(!h.clear(dir(0.0, 0.39)), "just under the top's slope 8/20");
        assert!(h.clear(dir(0.0, 0.41)), "just over it");
        assert!(!h.clear(dir(0.15, 0.1)), "inside the wall's arc (±0.197 rad)");
        assert!(h.clear(dir(0.3, 0.0)), "outside its arc, level");
        assert!(h.clear(dir(std::f64::consts::PI, 0.0)), "behind the viewpoint");
        assert!(!h.clear(dir(std::f64::consts::PI, -0.01)), "going down is never settled here");
        // A roof right over the viewpoint: steep rays may enter its box, shallow ones pass beside it.
        h.add_triangle([[-0.5, -0.5, 2.5], [0.5, -0.5, 2.5], [0.0, 0.6, 2.5]]);
        assert!(!h.clear([0.0, 0.0, 1.0]));
        assert!(h.clear(dir(2.0, 0.2)));
        // A triangle floating above the viewpoint, beside it (a pod's side 4 cm to the north, 0.17-0.26 m up):
        // shallow rays pass under it, steeper ones may meet it, and the other directions are free.
        let mut f = Horizon::new([0.0, 0.0, 2.0]);
        f.add_triangle([[-0.13, 0.04, 2.17], [0.37, 0.04, 2.17], [0.37, 0.04, 2.26]]);
        assert!(f.clear(dir(1.57, 0.2)) && !f.clear(dir(1.57, 1.0)) && f.clear(dir(-1.57, 1.0)));
        // A column standing over the viewpoint and rising above it could hold anything next to it: no ray is
        // settled.
        let mut c = h.clone();
        c.add_rect([-2.0, -2.0], [2.0, 2.0], 2.5);
        assert!(!c.clear(dir(2.0, 0.2)) && !c.clear(dir(0.5, 1.5)));
        // Below the viewpoint: nothing changes.
        let before = h.slope.clone();
        h.add_rect([-50.0, -50.0], [50.0, 50.0], 1.9);
        assert_eq!(before, h.slope);
    }

    #[test]
    fn a_mesh_marks_what_its_faces_mark_one_by_one() {
        // A hull-like cloud of faces around a mast-top viewpoint, most of them below it (and so passed over on
        // their heights by `add_mesh`), some beside and over it, and slivers just under its height: the bands
        // must be the same bits as adding every face with `add_triangle`.
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f32 / (1u64 << 53) as f32
        };
        let mut vertices = Vec::new();
        for _ in 0..1500 {
            let z = if next() < 0.9 { 4.0 * next() } else { 4.7 + 0.6 * next() };
            vertices.push([12.0 * next() - 6.0, 5.0 * next() - 2.5, z]);
        }
        // Slivers within millimetres of the viewpoint's height, where the first rising bin begins.
        for k in 0..200 {
            vertices.push([1.0 + 0.01 * k as f32, 0.3, 4.99 - 0.0001 * k as f32]);
        }
        let n = vertices.len() as u32;
        let faces: Vec<[u32; 3]> = (0..n - 2).map(|k| [k, (k * 7 + 1) % n, (k * 13 + 2) % n]).collect();
        let eye = [0.2f32, -0.1, 5.0];
        let mut marking = 0;
        for f in &faces {
            // Face by face, so that no other face's bits can cover one that a wrong early exit left out.
            let mut one = Horizon::new(eye);
            one.add_triangle(f.map(|k| vertices[k as usize]));
            let mut mesh = Horizon::new(eye);
            mesh.add_mesh(&vertices, std::slice::from_ref(f));
            assert!(one.bands == mesh.bands && one.any_bands == mesh.any_bands, "face {f:?}");
            assert_eq!(one.covered, mesh.covered);
            marking += usize::from(one.any_bands);
        }
        assert!(marking * 10 > faces.len(), "only {marking} of {} faces mark directions", faces.len());
        // And most faces were below: the test exercises the early exit, not only the full path.
        let below = faces.iter().filter(|f| f.iter().all(|&k| vertices[k as usize][2] < 4.9)).count();
        assert!(below * 2 > faces.len(), "only {below} of {} faces below the viewpoint", faces.len());
    }

    #[test]
    fn a_deck_under_the_viewpoint_hides_no_rising_ray() {
        // A 2 m square deck 1 m below the eye marks no direction (only rising ones are ever asked about) ...
        let mut h = Horizon::new([0.0, 0.0, 2.0]);
        h.add_triangle([[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [1.0, 1.0, 1.0]]);
        h.add_triangle([[-1.0, -1.0, 1.0], [1.0, 1.0, 1.0], [-1.0, 1.0, 1.0]]);
        assert!(!h.any_bands);
        let dir = |az: f32, slope: f32| {
            let n = (1.0 + slope * slope).sqrt();
            [az.cos() / n, az.sin() / n, slope / n]
        };
        for az in [0.0f32, 0.8, 2.0, 3.1, 4.0, 5.5] {
            assert!(h.clear(dir(az, 0.1)) && h.clear(dir(az, 0.0)), "rising at {az}: the deck is below");
            assert!(!h.clear(dir(az, -0.1)), "a ray going down is never settled");
        }
        // ... while a rail 1.5 m away reaching 0.2 m above the eye hides the rays rising less than 0.2 / 1.5 there.
        h.add_triangle([[1.5, -0.5, 1.0], [1.5, 0.5, 1.0], [1.5, 0.0, 2.2]]);
        assert!(h.any_bands);
        assert!(!h.clear(dir(0.0, 0.0)) && !h.clear(dir(0.0, 0.1)) && h.clear(dir(0.0, 0.5)));
        assert!(h.clear(dir(3.1, 0.0)), "behind the eye the rail hides nothing");
    }

    #[test]
    fn footprints_across_angle_zero_mark_both_ends() {
        let mut h = Horizon::new([0.0, 0.0, 1.0]);
        h.add_triangle([[10.0, -1.0, 0.0], [10.0, 1.0, 0.0], [12.0, 0.0, 5.0]]);
        let d = |y: f32| {
            let n = (100.0 + y * y + 0.01f32).sqrt();
            [10.0 / n, y / n, 0.1 / n]
        };
        assert!(!h.clear(d(0.5)) && !h.clear(d(-0.5)), "both sides of angle 0 are hidden");
        assert!(h.clear(d(4.0)) && h.clear(d(-4.0)), "beside the triangle is clear");
        // ±0.1 rad is ±0.091 in pseudo-angle, ±47 bins.
        let row = |b: usize| &h.bands[b * SLOPE_WORDS..(b + 1) * SLOPE_WORDS];
        let marked = (0..BINS).filter(|&b| row(b).iter().any(|&w| w != 0)).count();
        assert!((90..=100).contains(&marked), "{marked} bins marked");
        assert!(row(BINS / 2).iter().all(|&w| w == 0), "the opposite direction is free");
    }

    #[test]
    fn pyramid_levels_hold_the_maximum_below() {
        let base: Vec<f32> = (0..35).map(|k| (k * 7 % 11) as f32).collect();
        let p = MaxPyramid::new(7, 5, &base);
        assert_eq!(p.levels.last().map(|l| (l.0, l.1)), Some((1, 1)));
        assert_eq!(p.levels.last().map(|l| l.2[0]), Some(10.0));
        let (w, _, l1) = &p.levels[1];
        for y in 0..5 {
            for x in 0..7 {
                assert!(l1[(y / 2) * w + x / 2] >= base[y * 7 + x]);
            }
        }
    }
}
