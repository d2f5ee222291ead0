//! Exact shortcuts for rays that can only meet the sea surface or the sky, from a height map of the scene.
//!
//! A maritime scene is mostly empty space over a flat sea. [`Sea`] records which instance is the sea surface
//! (a horizontal plane at `level`) and a grid over the scene's extent holding, per cell, an upper bound of the
//! height of everything else there: static geometry triangle by triangle, moving vessels by their world
//! boxes, every contribution widened by one cell and raised by a margin. The scene uses it for two questions:
//!
//! * a ray going up (a shadow ray, a camera's sky pixel) that stays above every cell it crosses
//!   ([`Sea::path_clear`]) until it is higher than everything in the scene hits nothing.
//!
//! (Rays going down are traced: the scene's walk meets the surface, a large primitive near the top of the tree,
//! about as soon as a walk over the height map could show the way down clear; an earlier route that sent them
//! to the surface mesh alone cost more than it saved.)
//!
//! * a batch of shadow rays all towards one sun direction asks the [`SunMask`] instead: the cells from which a
//!   ray in that direction can pass over some cell at or below that cell's bound, found once per sun direction
//!   and height map by sweeping every occupied cell against the sun. A ray from above the surface whose cell is
//!   not in the mask hits nothing, however far it goes, in one lookup (`sea/sun_mask.rs`). Where only moving boxes put a cell in
//!   the mask, the ray is tested against those boxes (a slab test each): a box is a coarse stand-in for a
//!   vessel, and the water round a USV, which its own cameras see most of, lies in its box's sweep.
//!
//! Both walks and masks keep the static bound and the moving boxes apart in this way: a cell raised by a box
//! alone does not stop a ray that passes over its static bound and misses the box itself.
//!
//! * a batch of rays that all leave one point (a camera's pixels) asks that point's [`Horizon`]: per azimuth,
//!   the slope above which a ray from there passes over everything (`sea/horizon.rs`); from a point among the
//!   waves (under their crest bound), the crests are among its columns (`WaveSurface::add_crests`).
//!
//! So the shortcuts give exactly the full trace's answers; a ray the bound cannot settle is traced fully.

use crate::bvh::Box3;
use horizon::MaxPyramid;
use parry3d::math::Vec3;

mod horizon;
mod sun_mask;
pub(crate) mod surface;

pub use horizon::Horizon;
use sun_mask::SunCache;
pub use sun_mask::SunMask;
#[cfg(test)]
pub(crate) use surface::tests::comp as test_component;
pub use surface::{
    check_time, PinholeView, Raster, SurfaceHit, SurfaceShading, SurfaceSpec, WaterHit, WaveSurface, DETAIL_CELLS,
    FLAT_PIECE, MAX_TILES, MAX_TIME_S, SKIN_M, TILE_CELLS,
};

/// Most cells per side of the height grid.
const MAX_CELLS: usize = 512;
/// Smallest cell side, metres.
const MIN_CELL_M: f32 = 2.0;
/// Heights are raised by this much (metres) so rounding in the walk can never hide a surface.
const MARGIN_M: f32 = 0.05;

/// The sea surface of a scene and the height bound of everything else (see the module docs).
#[derive(Debug, Clone)]
pub struct Sea {
    /// Instance id of the sea surface.
    pub instance: u32,
    /// Height of the surface (world z, metres).
    pub level: f32,
    /// Instances rasterised by their world box after every move.
    moving: Vec<u32>,
    /// Grid: lower corner (world x, y), cell side (m), cells per side.
    x0: f32,
    y0: f32,
    cell: f32,
    nx: usize,
    ny: usize,
    /// Height bound of the static geometry per cell (`-inf` where empty), row-major `y · nx + x`.
    fixed: Vec<f32>,
    /// `fixed` raised by the moving instances' boxes at their current poses.
    heights: Vec<f32>,
    /// Highest bound anywhere.
    top: f32,
    /// Whether every moving box lies inside the grid (else leaving the grid proves nothing).
    contained: bool,
    /// Counts the height maps: bumped by every [`Sea::update`], so a cached [`SunMask`] knows its map.
    generation: u64,
    /// The moving instances' world boxes of the current map.
    boxes: Vec<Box3>,
    /// The last sun mask of the static geometry alone, for its direction (generation 0).
    fixed_sun: SunCache,
    /// The last sun mask built, for its direction and generation.
    sun_cache: SunCache,
    /// Max pyramid of `fixed`, for [`Horizon`]s.
    pyramid: MaxPyramid,
    /// The crest bound of the displaced surface, when waves are set ([`Sea::set_wave_top`]): rays must start
    /// above it (and above `level`) for the shortcuts to apply.
    wave_top: Option<f32>,
}

impl Sea {
    /// Builds the height grid over `bounds` (a world box holding every instance but the surface) with the
    /// static geometry `fixed` (world-space triangles), for surface instance `instance` at height `level`;
    /// `moving` lists the instances rasterised by box on every [`Sea::update`].
    pub fn new(instance: u32, level: f32, bounds: Box3, moving: Vec<u32>, fixed: &[[Vec3; 3]]) -> Self {
        let lo = [bounds.lo[0].min(bounds.hi[0]), bounds.lo[1].min(bounds.hi[1])];
        let (w, h) = ((bounds.hi[0] - lo[0]).max(1.0), (bounds.hi[1] - lo[1]).max(1.0));
        let cell = (w.max(h) / MAX_CELLS as f32).max(MIN_CELL_M);
        let nx = ((w / cell).ceil() as usize + 1).clamp(1, MAX_CELLS + 2);
        let ny = ((h / cell).ceil() as usize + 1).clamp(1, MAX_CELLS + 2);
        let mut sea = Self {
            instance,
            level,
            moving,
            x0: lo[0],
            y0: lo[1],
            cell,
            nx,
            ny,
            fixed: vec![f32::NEG_INFINITY; nx * ny],
            heights: Vec::new(),
            top: f32::NEG_INFINITY,
            contained: true,
            generation: 0,
            boxes: Vec::new(),
            fixed_sun: SunCache::default(),
            sun_cache: SunCache::default(),
            pyramid: MaxPyramid::default(),
            wave_top: None,
        };
        let mut grid = std::mem::take(&mut sea.fixed);
        for tri in fixed {
            let mut b = Box3::EMPTY;
            for p in tri {
                b.grow_point(p.to_array());
            }
            sea.raster(&mut grid, &b);
        }
        sea.pyramid = MaxPyramid::new(nx, ny, &grid);
        sea.fixed = grid;
        sea.heights = sea.fixed.clone();
        sea.top = sea.heights.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        sea
    }

    /// Sets (or clears) the crest bound of the displaced sea surface: no water lies above `top`. The shortcuts
    /// then answer only for rays that start above both the still level and `top`.
    pub fn set_wave_top(&mut self, top: Option<f32>) {
        self.wave_top = top;
    }

    /// The height above which a ray start is over every part of the water (the still level, or the crest bound
    /// of the waves).
    #[inline(always)]
    pub fn surface_top(&self) -> f32 {
        match self.wave_top {
            Some(t) => t.max(self.level),
            None => self.level,
        }
    }

    /// Instances rasterised by box.
    pub fn moving(&self) -> &[u32] {
        &self.moving
    }

    /// Treats instance `id` as moving from now on (its static contribution, if any, stays: still an upper
    /// bound).
    pub fn add_moving(&mut self, id: u32) {
        if !self.moving.contains(&id) {
            self.moving.push(id);
        }
    }

    /// Whether `other` holds the same height grid (extent, cells and heights): built from the same geometry.
    #[cfg(test)]
    pub(crate) fn same_grid(&self, other: &Sea) -> bool {
        (self.x0, self.y0, self.cell, self.nx, self.ny) == (other.x0, other.y0, other.cell, other.nx, other.ny)
            && self.fixed == other.fixed
            && self.heights == other.heights
    }

    /// Recomputes the bound from the static geometry and the moving instances' current world boxes.
    pub fn update(&mut self, moving_boxes: impl Iterator<Item = Box3>) {
        let mut grid = self.fixed.clone();
        self.contained = true;
        self.boxes.clear();
        let [gx1, gy1] = self.grid_far_corner();
        for b in moving_boxes {
            self.boxes.push(b);
            let inside = b.lo[0] >= self.x0 && b.lo[1] >= self.y0 && b.hi[0] <= gx1 && b.hi[1] <= gy1;
            self.contained &= inside;
            self.raster(&mut grid, &b);
        }
        self.top = grid.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        self.heights = grid;
        self.generation += 1;
    }

    /// The [`Horizon`] of viewpoint `origin` over the static geometry and the moving instances' boxes, with the
    /// moving instances whose boxes stand over it (the caller adds their triangles: `Horizon::add_triangle`).
    /// `None` when `origin` is not above the still level or a moving box lies outside the grid. The water is not
    /// part of it: from a viewpoint below the crest bound of the waves ([`Sea::set_wave_top`]), a ray the horizon
    /// clears must also clear the waves.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: a NaN must answer "no"
    pub fn horizon(&self, origin: [f32; 3]) -> Option<(Horizon, Vec<u32>)> {
        if !(self.contained && origin[2] > self.level && origin.iter().all(|v| v.is_finite())) {
            return None;
        }
        let mut h = Horizon::new(origin);
        self.pyramid.add_to(&mut h, self.x0, self.y0, self.cell);
        let mut near = Vec::new();
        for (&id, b) in self.moving.iter().zip(&self.boxes) {
            let (lo, hi) = ([f64::from(b.lo[0]), f64::from(b.lo[1])], [f64::from(b.hi[0]), f64::from(b.hi[1])]);
            if h.over(lo, hi) {
                near.push(id);
            } else {
                h.add_rect(lo, hi, f64::from(b.hi[2] + MARGIN_M));
            }
        }
        Some((h, near))
    }

    /// Raises the cells under `b` (widened by one cell) to `b`'s top plus the margin.
    fn raster(&self, grid: &mut [f32], b: &Box3) {
        let z = b.hi[2] + MARGIN_M;
        let ([x_lo, x_hi], [y_lo, y_hi]) = self.cells_under(b);
        for y in y_lo..=y_hi {
            for c in &mut grid[y * self.nx + x_lo..=y * self.nx + x_hi] {
                if z > *c {
                    *c = z;
                }
            }
        }
    }

    /// The cell ranges `[x_lo, x_hi], [y_lo, y_hi]` (inclusive) that [`Sea::raster`] raises for box `b`.
    fn cells_under(&self, b: &Box3) -> ([usize; 2], [usize; 2]) {
        let cx = |x: f32| ((x - self.x0) / self.cell).floor();
        let cy = |y: f32| ((y - self.y0) / self.cell).floor();
        let clamp = |v: f32, n: usize| (v.max(0.0) as usize).min(n - 1);
        let x = [clamp(cx(b.lo[0]) - 1.0, self.nx), clamp(cx(b.hi[0]) + 1.0, self.nx)];
        let y = [clamp(cy(b.lo[1]) - 1.0, self.ny), clamp(cy(b.hi[1]) + 1.0, self.ny)];
        (x, y)
    }

    /// The upper corner (world x, y) of the grid rectangle; the lower one is `(x0, y0)`.
    #[inline(always)]
    fn grid_far_corner(&self) -> [f32; 2] {
        [self.x0 + self.nx as f32 * self.cell, self.y0 + self.ny as f32 * self.cell]
    }

    /// The part `[t0, t1]` of the segment `o + t·d`, `t ∈ [0, t_end]`, that lies over the grid rectangle
    /// (horizontally), or `None` when none of it does.
    #[inline(always)]
    fn grid_span(&self, o: [f32; 3], d: [f32; 3], t_end: f32) -> Option<(f32, f32)> {
        let [gx1, gy1] = self.grid_far_corner();
        let mut t0 = 0f32;
        let mut t1 = t_end;
        for (oa, da, lo, hi) in [(o[0], d[0], self.x0, gx1), (o[1], d[1], self.y0, gy1)] {
            if da == 0.0 {
                if oa < lo || oa > hi {
                    return None;
                }
            } else {
                let (a, b) = ((lo - oa) / da, (hi - oa) / da);
                let (a, b) = if a < b { (a, b) } else { (b, a) };
                t0 = t0.max(a);
                t1 = t1.min(b);
            }
        }
        (t0 <= t1).then_some((t0, t1))
    }

    /// Highest height bound in the scene (metres).
    pub fn top(&self) -> f32 {
        self.top
    }

    /// Whether the ray `o + t·d`, `t ∈ [0, t_end]`, meets nothing but the sea surface: it stays strictly above
    /// the height bound of every cell it crosses, or where a cell's bound is raised by the moving boxes alone
    /// and the ray is above the static bound there, it misses those boxes. `false` also when the path is longer
    /// than `max_cells` cells (tracing it is then cheaper) or leaves a grid that does not hold everything.
    #[inline(always)]
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a < b)` on purpose: a NaN must answer "not clear"
    pub fn path_clear(&self, o: [f32; 3], d: [f32; 3], t_end: f32, max_cells: usize) -> bool {
        if !(t_end.is_finite() && t_end >= 0.0) {
            return false;
        }
        let run = t_end * (d[0] * d[0] + d[1] * d[1]).sqrt() / self.cell;
        if !(run < max_cells as f32) {
            return false;
        }
        // Clip the segment to the grid rectangle; outside it there is nothing (when `contained`).
        let Some((t0, t1)) = self.grid_span(o, d, t_end) else { return self.contained };
        if (t0 > 0.0 || t1 < t_end) && !self.contained {
            return false;
        }
        // 2D cell walk (Amanatides–Woo) from t0 to t1; in each cell the ray's lowest point is at the end of
        // its stretch there when going down, at the start when going up.
        let px = o[0] + d[0] * t0;
        let py = o[1] + d[1] * t0;
        let clampi = |v: f32, n: usize| (v.floor().max(0.0) as usize).min(n - 1);
        let mut ix = clampi((px - self.x0) / self.cell, self.nx);
        let mut iy = clampi((py - self.y0) / self.cell, self.ny);
        let step = |da: f32| if da > 0.0 { 1isize } else { -1 };
        let next = |i: usize, da: f32, oa: f32, lo: f32| {
            if da == 0.0 {
                f32::INFINITY
            } else {
                let edge = lo + (i as f32 + if da > 0.0 { 1.0 } else { 0.0 }) * self.cell;
                (edge - oa) / da
            }
        };
        let (sx, sy) = (step(d[0]), step(d[1]));
        let (dtx, dty) = (
            if d[0] == 0.0 { f32::INFINITY } else { self.cell / d[0].abs() },
            if d[1] == 0.0 { f32::INFINITY } else { self.cell / d[1].abs() },
        );
        let mut tx = next(ix, d[0], o[0], self.x0);
        let mut ty = next(iy, d[1], o[1], self.y0);
        let mut t = t0;
        // Whether some cell was passed over only above its static bound: the moving boxes decide then.
        let mut boxes = false;
        for _ in 0..=2 * max_cells + 2 {
            let t_exit = tx.min(ty).min(t1);
            let low_t = if d[2] < 0.0 { t_exit } else { t };
            let z_low = o[2] + d[2] * low_t;
            let cell = iy * self.nx + ix;
            if !(z_low > self.heights[cell]) {
                if !(z_low > self.fixed[cell]) {
                    return false;
                }
                boxes = true;
            }
            if t_exit >= t1 {
                return !boxes || self.misses_boxes(o, d, t_end);
            }
            t = t_exit;
            if tx <= ty {
                let n = ix as isize + sx;
                if n < 0 || n >= self.nx as isize {
                    return self.contained && (!boxes || self.misses_boxes(o, d, t_end));
                }
                ix = n as usize;
                tx += dtx;
            } else {
                let n = iy as isize + sy;
                if n < 0 || n >= self.ny as isize {
                    return self.contained && (!boxes || self.misses_boxes(o, d, t_end));
                }
                iy = n as usize;
                ty += dty;
            }
        }
        false
    }

    /// Whether the segment `o + t·d`, `t ∈ [0, t_end]`, misses every moving box grown by [`MARGIN_M`].
    #[inline]
    fn misses_boxes(&self, o: [f32; 3], d: [f32; 3], t_end: f32) -> bool {
        let (ex, ey) = (o[0] + d[0] * t_end, o[1] + d[1] * t_end);
        let (x_lo, x_hi) = (o[0].min(ex) - MARGIN_M, o[0].max(ex) + MARGIN_M);
        let (y_lo, y_hi) = (o[1].min(ey) - MARGIN_M, o[1].max(ey) + MARGIN_M);
        self.boxes.iter().all(|b| {
            // Away from the segment's own footprint, or missed by it.
            b.hi[0] < x_lo || b.lo[0] > x_hi || b.hi[1] < y_lo || b.lo[1] > y_hi || {
                !segment_meets(&grown(b), o, d, t_end)
            }
        })
    }
}

/// Moving box `b` grown by [`MARGIN_M`] every way: what a ray must miss to surely miss the instance.
#[inline(always)]
fn grown(b: &Box3) -> Box3 {
    Box3 { lo: b.lo.map(|v| v - MARGIN_M), hi: b.hi.map(|v| v + MARGIN_M) }
}

/// Whether the segment `o + t·d`, `t ∈ [0, t_end]`, meets the closed box `b` (the slab test; an axis the
/// direction does not move along is met only where `o` lies within the slab). `true` when not sure (a NaN).
#[inline(always)]
#[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a <= b)` on purpose: a NaN must answer "meets"
fn segment_meets(b: &Box3, o: [f32; 3], d: [f32; 3], t_end: f32) -> bool {
    let (mut t0, mut t1) = (0f32, t_end);
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < b.lo[a] || o[a] > b.hi[a] {
                return false;
            }
        } else {
            let (p, q) = ((b.lo[a] - o[a]) / d[a], (b.hi[a] - o[a]) / d[a]);
            let (p, q) = if p < q { (p, q) } else { (q, p) };
            t0 = t0.max(p);
            t1 = t1.min(q);
        }
    }
    !(t0 > t1)
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(super) fn tri(x: f32, y: f32, z: f32) -> [Vec3; 3] {
        [Vec3::new(x, y, z), Vec3::new(x + 1.0, y, z), Vec3::new(x, y + 1.0, z)]
    }

    #[test]
    fn walk_sees_a_tower_and_not_the_empty_sea() {
        let bounds = Box3 { lo: [-100.0, -100.0, -20.0], hi: [100.0, 100.0, 30.0] };
        let sea = Sea::new(0, 0.0, bounds, vec![], &[tri(50.0, 0.0, 30.0), tri(-80.0, -80.0, -20.0)]);
        // Down from 10 m towards (40, 0): clear (the tower is at x = 50..51).
        let o = [0.0, 0.0, 10.0];
        let to = |x: f32, y: f32| {
            let d = [x - o[0], y - o[1], -o[2]];
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            ([d[0] / n, d[1] / n, d[2] / n], n)
        };
        let (d, t) = to(40.0, 0.0);
        assert!(sea.path_clear(o, d, t, 512));
        // Towards (60, 0): the path passes over the tower at z ≈ 1.7 m < 30 m.
        let (d, t) = to(60.0, 0.0);
        assert!(!sea.path_clear(o, d, t, 512));
        // The seabed triangle far below does not block anything above the surface.
        let (d, t) = to(-79.5, -79.5);
        assert!(sea.path_clear(o, d, t, 512));
        // Up past everything: clear once above the top.
        assert!(sea.path_clear(o, [0.0, 0.6, 0.8], 100.0, 512));
        // ... but not when the walk would be longer than allowed.
        assert!(!sea.path_clear(o, [0.0, 0.6, 0.8], 100.0, 2));
        // Up over the tower, below its top: blocked.
        assert!(!sea.path_clear([45.0, 0.5, 1.0], [0.98, 0.0, 0.2], 60.0, 512));
    }

    #[test]
    fn moving_boxes_raise_cells_and_leaving_the_grid_is_unknown_then() {
        let bounds = Box3 { lo: [-50.0, -50.0, 0.0], hi: [50.0, 50.0, 5.0] };
        let mut sea = Sea::new(0, 0.0, bounds, vec![1], &[]);
        let boat = Box3 { lo: [10.0, -2.0, -1.0], hi: [20.0, 2.0, 4.0] };
        sea.update([boat].into_iter());
        assert!(!sea.path_clear([0.0, 0.0, 3.0], [1.0, 0.0, 0.0], 30.0, 512));
        assert!(sea.path_clear([0.0, 0.0, 3.0], [-1.0, 0.0, 0.0], 30.0, 512));
        // Beside the boat (within the cells its box raises) and over it: the box itself is missed, so clear;
        // just inside its margin, or under its top, not.
        assert!(sea.path_clear([0.0, 2.5, 3.0], [1.0, 0.0, 0.0], 30.0, 512));
        assert!(sea.path_clear([0.0, 0.0, 4.1], [1.0, 0.0, 0.0], 30.0, 512));
        assert!(!sea.path_clear([0.0, 2.04, 3.0], [1.0, 0.0, 0.0], 30.0, 512));
        assert!(!sea.path_clear([0.0, 0.0, 4.04], [1.0, 0.0, 0.0], 30.0, 512));
        // Past the boat, the segment's end short of it: clear.
        assert!(sea.path_clear([0.0, 0.0, 3.0], [1.0, 0.0, 0.0], 9.9, 512));
        // The boat sails out of the grid: leaving the grid no longer proves anything.
        let away = Box3 { lo: [60.0, -2.0, -1.0], hi: [70.0, 2.0, 4.0] };
        sea.update([away].into_iter());
        assert!(!sea.path_clear([0.0, 0.0, 3.0], [1.0, 0.0, 0.0], 200.0, 512));
        assert!(sea.path_clear([0.0, 0.0, 3.0], [1.0, 0.0, 0.0], 40.0, 512));
    }
}
