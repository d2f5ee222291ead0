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
//!   not in the mask hits nothing, however far it goes, in one lookup. Where only moving boxes put a cell in
//!   the mask, the ray is tested against those boxes (a slab test each): a box is a coarse stand-in for a
//!   vessel, and the water round a USV, which its own cameras see most of, lies in its box's sweep.
//!
//! Both walks and masks keep the static bound and the moving boxes apart in this way: a cell raised by a box
//! alone does not stop a ray that passes over its static bound and misses the box itself.
//!
//! * a batch of rays that all leave one point (a camera's pixels) asks that point's [`Horizon`]: per azimuth,
//!   the slope above which a ray from there passes over everything (`sea/horizon.rs`).
//!
//! So the shortcuts give exactly the full trace's answers; a ray the bound cannot settle is traced fully.

use crate::bvh::Box3;
use horizon::MaxPyramid;
use parry3d::math::Vec3;
use std::sync::{Arc, Mutex};

mod horizon;
pub(crate) mod surface;

pub use horizon::Horizon;
#[cfg(test)]
pub(crate) use surface::tests::comp as test_component;
pub use surface::{
    PinholeView, Raster, SurfaceHit, SurfaceShading, SurfaceSpec, WaterHit, WaveSurface, DETAIL_CELLS, FLAT_PIECE,
    SKIN_M, TILE_CELLS,
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

/// The cells of a [`Sea`] grid from which a ray towards one sun direction may meet something (see the module
/// docs): a ray from above the surface starting in any other cell of the grid hits nothing. In a cell only the
/// moving instances' boxes may shade, the ray is tested against those boxes themselves.
#[derive(Debug, Clone, PartialEq)]
pub struct SunMask {
    /// The unit direction the mask was built for.
    dir: [f32; 3],
    /// The height map's generation it was built from.
    generation: u64,
    /// Per cell, row-major like the height map: [`OPEN`], [`BOXES`] or [`FIXED`].
    cells: Vec<u8>,
    /// The moving instances' boxes, grown by [`MARGIN_M`], each with the horizontal rectangle
    /// `[x_lo, y_lo, x_hi, y_hi]` holding every start above the surface from which a ray in `dir` may meet it.
    boxes: Vec<(Box3, [f32; 4])>,
}

/// A [`SunMask`] cell from which a ray towards the sun meets nothing.
const OPEN: u8 = 0;
/// A [`SunMask`] cell over which only moving boxes may stand in the sun's way: the ray is tested against them.
const BOXES: u8 = 1;
/// A [`SunMask`] cell from which a ray towards the sun may meet the static geometry: it is traced.
const FIXED: u8 = 2;

/// The last [`SunMask`] built; a copy of a [`Sea`] starts with an empty cache.
#[derive(Debug, Default)]
struct SunCache(Mutex<Option<Arc<SunMask>>>);

impl Clone for SunCache {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl SunMask {
    /// The unit direction the mask was built for.
    pub fn dir(&self) -> [f32; 3] {
        self.dir
    }
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
    /// `None` when `origin` is not above the surface or a moving box lies outside the grid.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: a NaN must answer "no"
    pub fn horizon(&self, origin: [f32; 3]) -> Option<(Horizon, Vec<u32>)> {
        if !(self.contained && origin[2] > self.surface_top() && origin.iter().all(|v| v.is_finite())) {
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

    /// The [`SunMask`] of unit direction `dir` for the current height map, built on first use and kept until
    /// the map or the direction changes. `None` when `dir` does not rise (`dir.z <= 0`, or not finite) or a
    /// moving box lies outside the grid (the map then does not hold everything).
    ///
    /// The static geometry's part is built once per direction and kept across maps; each map adds the moving
    /// boxes' sweeps to a copy. Callers on several threads may ask at once: one builds, the others wait (the
    /// build is sequential).
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: a NaN must answer "no"
    pub fn sun_mask(&self, dir: [f32; 3]) -> Option<Arc<SunMask>> {
        if !(dir[2] > 0.0 && dir.iter().all(|v| v.is_finite()) && self.contained) {
            return None;
        }
        let mut cache = self.sun_cache.0.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some(m) = cache.as_ref() {
            if m.dir == dir && m.generation == self.generation {
                return Some(Arc::clone(m));
            }
        }
        let fixed = {
            let mut fixed = self.fixed_sun.0.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
            match fixed.as_ref() {
                Some(m) if m.dir == dir => Arc::clone(m),
                _ => {
                    let m = Arc::new(self.fixed_sun_mask(dir));
                    *fixed = Some(Arc::clone(&m));
                    m
                }
            }
        };
        let mut cells = fixed.cells.clone();
        let (nx, ny) = (self.nx, self.ny);
        for b in &self.boxes {
            let h = b.hi[2] + MARGIN_M;
            let ([x_lo, x_hi], [y_lo, y_hi]) = self.cells_under(b);
            for iy in y_lo..=y_hi {
                for ix in x_lo..=x_hi {
                    self.sweep(ix, iy, h, dir, |gx, gy| {
                        for y in gy.saturating_sub(1)..=(gy + 1).min(ny - 1) {
                            for c in &mut cells[y * nx + gx.saturating_sub(1)..=y * nx + (gx + 1).min(nx - 1)] {
                                *c = (*c).max(BOXES);
                            }
                        }
                    });
                }
            }
        }
        let boxes = self.boxes.iter().map(|b| self.sun_shadow(b, dir)).collect();
        let mask = Arc::new(SunMask { dir, generation: self.generation, cells, boxes });
        *cache = Some(Arc::clone(&mask));
        Some(mask)
    }

    /// The sun mask of the static geometry alone (the moving boxes left out).
    fn fixed_sun_mask(&self, dir: [f32; 3]) -> SunMask {
        let (nx, ny) = (self.nx, self.ny);
        let mut centre = vec![false; nx * ny];
        for iy in 0..ny {
            for ix in 0..nx {
                self.sweep(ix, iy, self.fixed[iy * nx + ix], dir, |gx, gy| centre[gy * nx + gx] = true);
            }
        }
        // Widen by one cell (a 3×3 maximum, done separably).
        let mut rows = vec![false; nx * ny];
        for iy in 0..ny {
            for ix in 0..nx {
                let r = &centre[iy * nx..(iy + 1) * nx];
                rows[iy * nx + ix] = r[ix.saturating_sub(1)..=(ix + 1).min(nx - 1)].iter().any(|&b| b);
            }
        }
        let mut cells = vec![OPEN; nx * ny];
        for iy in 0..ny {
            for ix in 0..nx {
                if (iy.saturating_sub(1)..=(iy + 1).min(ny - 1)).any(|y| rows[y * nx + ix]) {
                    cells[iy * nx + ix] = FIXED;
                }
            }
        }
        SunMask { dir, generation: 0, cells, boxes: Vec::new() }
    }

    /// Moving box `b` grown by [`MARGIN_M`], and the horizontal rectangle of the starts above the surface from
    /// which a ray in unit direction `dir` (rising) may meet it: the box's own, swept back against the sun as far
    /// as a ray rising from the surface to the box's top runs, padded by the margin.
    fn sun_shadow(&self, b: &Box3, dir: [f32; 3]) -> (Box3, [f32; 4]) {
        let g = Box3 { lo: b.lo.map(|v| v - MARGIN_M), hi: b.hi.map(|v| v + MARGIN_M) };
        let run = ((g.hi[2] - self.level).max(0.0) / dir[2]) * 1.001 + MARGIN_M;
        let (bx, by) = (-dir[0] * run, -dir[1] * run);
        let rect = [
            g.lo[0] + bx.min(0.0) - MARGIN_M,
            g.lo[1] + by.min(0.0) - MARGIN_M,
            g.hi[0] + bx.max(0.0) + MARGIN_M,
            g.hi[1] + by.max(0.0) + MARGIN_M,
        ];
        (g, rect)
    }

    /// Sweeps cell `(ix, iy)` with height bound `h` against the sun `dir`, calling `mark(gx, gy)` for the cell
    /// of every sample (clamped into the grid); the caller widens each mark by one cell.
    ///
    /// A ray from height `z >= level` passes over the cell at height at most `h` only if its start lies in the
    /// cell moved back along the horizontal sun direction by up to `(h - level) · |d_xy| / d_z`. The sweep is
    /// sampled every half cell, so the widened marks cover every point within 0.75 cells of a sample: the whole
    /// swept square. A cell bounded at or below the surface is skipped: a ray from above it never gets there.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: a NaN must answer "no"
    #[inline]
    fn sweep(&self, ix: usize, iy: usize, h: f32, dir: [f32; 3], mut mark: impl FnMut(usize, usize)) {
        if !(h > self.level) {
            return;
        }
        let (nx, ny) = (self.nx, self.ny);
        let hlen = (dir[0] * dir[0] + dir[1] * dir[1]).sqrt();
        let (ux, uy) = if hlen > 0.0 { (dir[0] / hlen, dir[1] / hlen) } else { (0.0, 0.0) };
        let step = 0.5 * self.cell;
        // Horizontal run while rising from the surface to `h`, padded against rounding.
        let run = (h - self.level) / dir[2] * hlen * 1.001 + step;
        let samples = if hlen > 0.0 { (run / step).ceil() as usize } else { 0 };
        let cx = self.x0 + (ix as f32 + 0.5) * self.cell;
        let cy = self.y0 + (iy as f32 + 0.5) * self.cell;
        for k in 0..=samples {
            let back = k as f32 * step;
            let gx = ((cx - back * ux - self.x0) / self.cell).floor();
            let gy = ((cy - back * uy - self.y0) / self.cell).floor();
            // Outside the grid by more than the widening: moving on only goes further out.
            if gx < -1.0 || gy < -1.0 || gx > nx as f32 || gy > ny as f32 {
                break;
            }
            mark(gx.clamp(0.0, (nx - 1) as f32) as usize, gy.clamp(0.0, (ny - 1) as f32) as usize);
        }
    }

    /// Whether a ray from `o` in the direction of `mask` surely hits nothing: `o` is above the surface, and the
    /// ray starts in a cell outside the mask or, from outside the grid (where there is nothing but the surface),
    /// never passes over the grid or enters it in a cell outside the mask (the rest of the ray is the ray from
    /// there). `false` means "not known" (trace it).
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: a NaN must answer "no"
    #[inline(always)]
    pub fn sun_clear(&self, mask: &SunMask, o: [f32; 3]) -> bool {
        if !(o[2] > self.level) {
            return false;
        }
        let d = mask.dir;
        let [gx1, gy1] = self.grid_far_corner();
        let (px, py) = if o[0] >= self.x0 && o[0] <= gx1 && o[1] >= self.y0 && o[1] <= gy1 {
            (o[0], o[1]) // over the grid (what grid_span's entry at t = 0 gives, without its divisions)
        } else {
            // From outside the grid, the rest of the ray is the ray from where it enters.
            let Some((t0, _)) = self.grid_span(o, d, f32::INFINITY) else { return true }; // never over the grid
            (o[0] + d[0] * t0, o[1] + d[1] * t0)
        };
        let gx = ((px - self.x0) / self.cell).floor().clamp(0.0, (self.nx - 1) as f32);
        let gy = ((py - self.y0) / self.cell).floor().clamp(0.0, (self.ny - 1) as f32);
        match mask.cells[gy as usize * self.nx + gx as usize] {
            OPEN => true,
            BOXES => mask.boxes.iter().all(|(b, r)| {
                o[0] < r[0] || o[1] < r[1] || o[0] > r[2] || o[1] > r[3] || !segment_meets(b, o, d, f32::INFINITY)
            }),
            _ => false,
        }
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
                let g = Box3 { lo: b.lo.map(|v| v - MARGIN_M), hi: b.hi.map(|v| v + MARGIN_M) };
                !segment_meets(&g, o, d, t_end)
            }
        })
    }
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

    fn tri(x: f32, y: f32, z: f32) -> [Vec3; 3] {
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

    /// Whether the rising ray `o + t·d` meets one of the horizontal triangles `tris` or the inside of box `b`:
    /// by brute force (each triangle's plane crossing, and the ray sampled every centimetre up to `b`'s top).
    fn meets_by_brute_force(tris: &[[Vec3; 3]], b: &Box3, o: [f32; 3], d: [f32; 3]) -> bool {
        let (o64, d64) = (o.map(f64::from), d.map(f64::from));
        let on_tri = tris.iter().any(|t| {
            let t_hit = (f64::from(t[0].z) - o64[2]) / d64[2];
            let (x, y) = (o64[0] + d64[0] * t_hit, o64[1] + d64[1] * t_hit);
            let (u, v) = (x - f64::from(t[0].x), y - f64::from(t[0].y));
            t_hit > 0.0 && u >= 0.0 && v >= 0.0 && u + v <= 1.0
        });
        let t_top = (f64::from(b.hi[2]) - o64[2]) / d64[2];
        let in_box = (0..=(t_top.max(0.0) * 100.0) as usize).any(|k| {
            let p = [0, 1, 2].map(|a| o64[a] + d64[a] * k as f64 * 0.01);
            (0..3).all(|a| p[a] >= f64::from(b.lo[a]) && p[a] <= f64::from(b.hi[a]))
        });
        on_tri || in_box
    }

    #[test]
    fn sun_mask_clears_only_rays_that_meet_nothing() {
        // A tower and a low quay on a 200 m grid, a moving boat; suns from steep to low, one straight up.
        let bounds = Box3 { lo: [-100.0, -100.0, -20.0], hi: [100.0, 100.0, 30.0] };
        let mut fixed = vec![tri(50.0, 0.0, 30.0), tri(-80.0, -80.0, -20.0)];
        fixed.extend((0..40).map(|i| tri(-60.0 + i as f32, 40.0, 2.0)));
        let mut sea = Sea::new(0, 0.0, bounds, vec![1], &fixed);
        let boat = Box3 { lo: [0.0, -30.0, -1.0], hi: [12.0, -26.0, 6.0] };
        sea.update([boat].into_iter());
        let mut state = 7u64;
        let mut rand = |lo: f32, hi: f32| {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            lo + (hi - lo) * ((state >> 40) as f32 / (1u64 << 24) as f32)
        };
        for sun in [[0.4f32, 0.3, 0.866], [-0.9, 0.1, 0.42], [0.0, -0.97, 0.24], [0.0, 0.0, 1.0]] {
            let n = (sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2]).sqrt();
            let d = [sun[0] / n, sun[1] / n, sun[2] / n];
            let Some(mask) = sea.sun_mask(d) else { panic!("no mask for {d:?}") };
            let (mut cleared, mut shaded, mut outside) = (0, 0, 0);
            let cell_of = |o: [f32; 3]| {
                let g = |v: f32, v0: f32, n: usize| (((v - v0) / sea.cell).floor().max(0.0) as usize).min(n - 1);
                mask.cells[g(o[1], sea.y0, sea.ny) * sea.nx + g(o[0], sea.x0, sea.nx)]
            };
            let (mut by_box, mut shaded_by_box) = (0, 0);
            for k in 0..24_000 {
                // Every sixth start lies in the water round the boat, where the boxes decide.
                let o = if k % 6 == 0 {
                    [rand(-20.0, 32.0), rand(-50.0, -6.0), rand(0.001, 3.0)]
                } else {
                    [rand(-170.0, 170.0), rand(-170.0, 170.0), rand(0.001, 3.0)]
                };
                let meets = meets_by_brute_force(&fixed, &boat, o, d);
                if sea.sun_clear(&mask, o) {
                    assert!(!meets, "mask clears {o:?} towards {d:?}, yet the ray meets something");
                    outside += usize::from(o[0].abs() > 105.0 || o[1].abs() > 105.0);
                    cleared += 1;
                    by_box += usize::from(cell_of(o) == BOXES);
                }
                shaded += usize::from(meets);
                shaded_by_box += usize::from(meets && cell_of(o) == BOXES);
            }
            // The mask settles most of the open water, and the shade is real.
            assert!(cleared > 15_000, "only {cleared} cleared towards {d:?}");
            assert!(shaded > 50, "only {shaded} shaded towards {d:?}");
            assert!(outside > 5_000, "only {outside} cleared from outside the grid towards {d:?}");
            // Round the boat, the box itself decides: most starts there are cleared, some are in its shade.
            assert!(by_box > 300, "only {by_box} cleared where the boat's box is tested towards {d:?}");
            assert!(shaded_by_box > 20, "only {shaded_by_box} in the boat's shade towards {d:?}");
            // Cached: the same mask again, until the map changes.
            assert!(sea.sun_mask(d).is_some_and(|m| Arc::ptr_eq(&m, &mask)));
        }
        assert!(sea.sun_mask([0.6, 0.0, -0.8]).is_none(), "a sun below the horizon has no mask");
        let before = sea.sun_mask([0.0, 0.0, 1.0]);
        sea.update([Box3 { lo: [-50.0, 60.0, -1.0], hi: [-40.0, 64.0, 6.0] }].into_iter());
        let after = sea.sun_mask([0.0, 0.0, 1.0]);
        assert!(before.is_some() && after.is_some() && before != after, "a new map gives a new mask");
        // A boat outside the grid: no mask.
        sea.update([Box3 { lo: [160.0, 0.0, 0.0], hi: [170.0, 4.0, 4.0] }].into_iter());
        assert!(sea.sun_mask([0.0, 0.0, 1.0]).is_none());
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
