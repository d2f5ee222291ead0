//! The sign march of [`WaveSurface::intersect`]: a ray against the triangulated surface, exactly.
//!
//! Only the part of the ray inside the band `[zmin, zmax]` of the sampled heights is walked (above the band
//! nothing can be hit: the crest bound), tile by tile, cell by cell (one 2D DDA type for both levels),
//! triangle by triangle; on every piece the height of the ray above the surface is linear in `t`, so its sign
//! change gives the hit. The sign is carried from piece to piece, so no ray slips through a shared edge, and a
//! step between two tiles of different detail is closed by a vertical wall (hit where the sign flips at the tile
//! boundary). Tiles and cells whose sampled maximum lies below the ray are skipped whole; a ray that crosses the
//! band within one tile goes straight to it.

use super::{cell_piece, cell_planes, fmax, fmin, SurfaceHit, WaveSurface, FLAT_PIECE};

impl WaveSurface {
    /// [`WaveSurface::intersect`]'s body, inlined into each instruction-set copy of [`intersect_with`].
    #[inline(always)]
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN must answer "no hit"
    fn intersect_in(&self, o: [f32; 3], d: [f32; 3], t_max: f32) -> Option<SurfaceHit> {
        // The band [zmin, zmax] of the ray.
        let (oz, dz) = (o[2], d[2]);
        let (mut t0, mut t1) = (0.0f32, t_max);
        if dz > 0.0 {
            t1 = fmin(t1, (self.zmax - oz) / dz);
            t0 = fmax(t0, (self.zmin - oz) / dz);
        } else if dz < 0.0 {
            t0 = fmax(t0, (self.zmax - oz) / dz);
            t1 = fmin(t1, (self.zmin - oz) / dz);
        } else if !(oz >= self.zmin && oz <= self.zmax) {
            return None;
        }
        if !(t0 <= t1) {
            return None;
        }
        // A ray that stays over one point while in the band (a top view's, looking straight down: its horizontal
        // drift there rounds away) meets only the piece under that point, solved on its plane without a walk.
        let (xa, ya) = (o[0] + d[0] * t0, o[1] + d[1] * t0);
        if xa == o[0] + d[0] * t1 && ya == o[1] + d[1] * t1 {
            let (h, piece) = self.height_piece(xa, ya);
            let (fa, fb) = (oz + dz * t0 - h, oz + dz * t1 - h);
            if (fa > 0.0) == (fb > 0.0) {
                return None;
            }
            let f = fa / (fa - fb);
            let t = if f.is_finite() { t0 + (t1 - t0) * f.clamp(0.0, 1.0) } else { t0 };
            return Some(SurfaceHit { t, piece });
        }
        let inv = [0, 1, 2].map(|a| if d[a] == 0.0 { f32::INFINITY } else { 1.0 / d[a] });
        let mut m = March { s: self, o, d, inv, above: None };
        // A steep ray crosses the band within one tile: straight to it.
        let at = |t: f32| self.tile_at(o[0] + d[0] * t, o[1] + d[1] * t);
        if let (Some(a), Some(b)) = (at(t0), at(t1)) {
            if a == b {
                return m.tile(a.0, a.1, t0, t1);
            }
        }
        // Split [t0, t1] into the parts before, inside and after the tile rectangle.
        let span = self.rect_span(o, d, t0, t1);
        match span {
            None => m.flat(t0, t1),
            Some((a, b)) => {
                if a > t0 {
                    if let Some(h) = m.flat(t0, a) {
                        return Some(h);
                    }
                }
                if let Some(h) = m.tiles(a, b) {
                    return Some(h);
                }
                if b < t1 {
                    return m.flat(b, t1);
                }
                None
            }
        }
    }

    /// The part of `[t0, t1]` of the ray over the tile rectangle, or `None`.
    #[inline(always)]
    fn rect_span(&self, o: [f32; 3], d: [f32; 3], t0: f32, t1: f32) -> Option<(f32, f32)> {
        if self.ntx == 0 {
            return None;
        }
        let hi = [self.x0 + self.ntx as f32 * self.tile_m, self.y0 + self.nty as f32 * self.tile_m];
        let lo = [self.x0, self.y0];
        let (mut a, mut b) = (t0, t1);
        for ax in 0..2 {
            if d[ax] == 0.0 {
                if o[ax] < lo[ax] || o[ax] >= hi[ax] {
                    return None;
                }
            } else {
                let (p, q) = ((lo[ax] - o[ax]) / d[ax], (hi[ax] - o[ax]) / d[ax]);
                a = fmax(a, fmin(p, q));
                b = fmin(b, fmax(p, q));
            }
        }
        (a < b).then_some((a, b))
    }
}

crate::dispatch! {
    /// [`WaveSurface::intersect`], compiled for AVX2/FMA where the CPU has them (the march's floors and
    /// divisions are single instructions there; the results are the same bits).
    pub(super) fn intersect_with(s: &WaveSurface, o: [f32; 3], d: [f32; 3], t_max: f32) -> Option<SurfaceHit> {
        s.intersect_in(o, d, t_max)
    }
}

/// The state of one sign march: the ray and whether it was last above the surface (`None` before the first
/// piece).
struct March<'a> {
    s: &'a WaveSurface,
    o: [f32; 3],
    d: [f32; 3],
    /// `1 / d.x`, `1 / d.y`, `1 / d.z` (infinite along an axis the ray does not move on): the march multiplies
    /// by these instead of dividing.
    inv: [f32; 3],
    above: Option<bool>,
}

/// A 2D DDA over a square grid: the current cell, the ray distances to the next column and row boundaries, and
/// the distance between boundaries (infinite along an axis the ray does not cross).
struct Dda {
    cell: [usize; 2],
    next: [f32; 2],
    step: [f32; 2],
    /// The cell step along each axis: +1, -1, or 0 where the ray does not move along it.
    dir: [isize; 2],
}

impl Dda {
    /// Starts at ray distance `t` on the grid with lower corner `g` and cells of side `c` (`inv_c = 1 / c`),
    /// cells `lo..=hi` per axis (the start cell clamped into them).
    #[inline(always)]
    fn new(m: &March<'_>, t: f32, g: [f32; 2], c: f32, inv_c: f32, lo: [usize; 2], hi: [usize; 2]) -> Self {
        let mut cell = [0usize; 2];
        let mut next = [f32::INFINITY; 2];
        let mut step = [f32::INFINITY; 2];
        let mut dir = [0isize; 2];
        for a in 0..2 {
            let u = (m.o[a] + m.d[a] * t - g[a]) * inv_c;
            cell[a] = (u.floor().max(lo[a] as f32) as usize).min(hi[a]);
            if m.d[a] != 0.0 {
                let side = if m.d[a] > 0.0 { 1.0 } else { 0.0 };
                next[a] = (g[a] + (cell[a] as f32 + side) * c - m.o[a]) * m.inv[a];
                step[a] = c * m.inv[a].abs();
                dir[a] = if m.d[a] > 0.0 { 1 } else { -1 };
            }
        }
        Self { cell, next, step, dir }
    }

    /// The ray distance where the current cell is left.
    #[inline(always)]
    fn exit(&self) -> f32 {
        fmin(self.next[0], self.next[1])
    }

    /// Moves to the next cell along the ray; `false` when that leaves `lo..=hi`. The axis is picked by index,
    /// not by a branch (along a diagonal ray the two alternate unpredictably).
    #[inline(always)]
    fn advance(&mut self, lo: [usize; 2], hi: [usize; 2]) -> bool {
        let a = usize::from(self.next[0] > self.next[1]);
        let c = self.cell[a].wrapping_add(self.dir[a] as usize);
        if c < lo[a] || c > hi[a] {
            return false;
        }
        self.cell[a] = c;
        self.next[a] += self.step[a];
        true
    }
}

impl March<'_> {
    #[inline(always)]
    fn z(&self, t: f32) -> f32 {
        self.o[2] + self.d[2] * t
    }

    /// A piece on which the ray's height above the surface goes linearly from `fa` (at `ta`) to `fb` (at `tb`):
    /// the hit, if the sign changes (at `ta` against the carried sign, or inside).
    #[inline(always)]
    fn piece(&mut self, ta: f32, tb: f32, fa: f32, fb: f32, piece: u32) -> Option<SurfaceHit> {
        let a_above = fa > 0.0;
        if let Some(prev) = self.above {
            if prev != a_above {
                return Some(SurfaceHit { t: ta, piece });
            }
        }
        let b_above = fb > 0.0;
        self.above = Some(b_above);
        if a_above != b_above {
            let f = fa / (fa - fb);
            let t = if f.is_finite() { ta + (tb - ta) * f.clamp(0.0, 1.0) } else { ta };
            return Some(SurfaceHit { t, piece });
        }
        None
    }

    /// A stretch over still water.
    #[inline(always)]
    fn flat(&mut self, ta: f32, tb: f32) -> Option<SurfaceHit> {
        let l = self.s.level;
        self.piece(ta, tb, self.z(ta) - l, self.z(tb) - l, FLAT_PIECE)
    }

    /// The stretch `[ta, tb]` inside the tile rectangle: tile by tile (2D DDA).
    #[inline(always)]
    fn tiles(&mut self, ta: f32, tb: f32) -> Option<SurfaceHit> {
        let s = self.s;
        let (lo, hi) = ([0, 0], [s.ntx - 1, s.nty - 1]);
        let mut g = Dda::new(self, ta, [s.x0, s.y0], s.tile_m, s.inv_tile_m, lo, hi);
        let mut t = ta;
        loop {
            let t_exit = fmin(g.exit(), tb);
            if t_exit > t {
                if let Some(h) = self.tile(g.cell[0], g.cell[1], t, t_exit) {
                    return Some(h);
                }
            }
            if t_exit >= tb || !g.advance(lo, hi) {
                return None;
            }
            t = t_exit;
        }
    }

    /// The stretch `[ta, tb]` over tile `(ix, iy)`.
    #[inline(always)]
    fn tile(&mut self, ix: usize, iy: usize, ta: f32, tb: f32) -> Option<SurfaceHit> {
        let s = self.s;
        let k = iy * s.ntx + ix;
        let tile = &s.tiles[k];
        if tile.n == 0 {
            return self.flat(ta, tb);
        }
        let (za, zb) = (self.z(ta), self.z(tb));
        if fmin(za, zb) > tile.zmax && self.above != Some(false) {
            self.above = Some(true);
            return None; // wholly above every crest of the tile
        }
        if fmax(za, zb) <= tile.zmin && self.above == Some(false) {
            return None; // wholly under the tile's troughs, and already under water
        }
        // Only the part of the stretch below the tile's crest bound can meet it: a falling ray is walked from
        // where it comes down to the bound, a rising one until it rises above it (strictly above every node of the
        // tile before and after, so the carried sign there is "above").
        let (mut ta, mut tb) = (ta, tb);
        let mut rises_clear = false;
        if self.above != Some(false) {
            let t_top = (tile.zmax - self.o[2]) * self.inv[2];
            if self.d[2] > 0.0 && t_top < tb {
                tb = fmax(t_top, ta);
                rises_clear = true;
            } else if self.d[2] < 0.0 && t_top > ta {
                ta = fmin(t_top, tb);
                self.above = Some(true);
            }
        }
        let n = tile.n;
        let corner = [s.x0 + ix as f32 * s.tile_m, s.y0 + iy as f32 * s.tile_m];
        let hit = self.cells(k, corner, ta, tb, [0, 0], [n - 1, n - 1]);
        if hit.is_none() && rises_clear {
            self.above = Some(true);
        }
        hit
    }

    /// The stretch `[ta, tb]` over the cells `lo..=hi` (column, row) of tile `k` (lower corner `corner`): cell by
    /// cell (2D DDA), triangle by triangle.
    #[inline(always)]
    fn cells(
        &mut self,
        k: usize,
        corner: [f32; 2],
        ta: f32,
        tb: f32,
        lo: [usize; 2],
        hi: [usize; 2],
    ) -> Option<SurfaceHit> {
        let s = self.s;
        let tile = &s.tiles[k];
        let n = tile.n;
        let inv_cs = n as f32 * s.inv_tile_m;
        let cs = s.tile_m / n as f32;
        let (o, d) = (self.o, self.d);
        // Cell coordinates (u, v) along the ray: u(t) = (o.x + d.x t - corner.x) / cs.
        let (u0, v0) = ((o[0] - corner[0]) * inv_cs, (o[1] - corner[1]) * inv_cs);
        let (du, dv) = (d[0] * inv_cs, d[1] * inv_cs);
        let mut g = Dda::new(self, ta, corner, cs, inv_cs, lo, hi);
        let mut t = ta;
        loop {
            let t_exit = fmin(g.exit(), tb);
            if t_exit >= t {
                let [ci, cj] = g.cell;
                let (plane, cmax) = cell_planes(tile, ci, cj);
                let (zt, ze) = (self.z(t), self.z(t_exit));
                if fmin(zt, ze) > cmax && self.above != Some(false) {
                    self.above = Some(true);
                } else {
                    let id = cell_piece(k, n, ci, cj, 0);
                    // Local (fu, fv) at t: u(t) - ci.
                    let fu = |t: f32| u0 + du * t - ci as f32;
                    let fv = |t: f32| v0 + dv * t - cj as f32;
                    let (oz, dz) = (o[2], d[2]);
                    let f_at = |t: f32, tri: usize| {
                        let p = plane[tri];
                        oz + dz * t - (p[0] + p[1] * fu(t) + p[2] * fv(t))
                    };
                    let tri_of = |t: f32| usize::from(fu(t) < fv(t));
                    // Diagonal crossing: fu(t) = fv(t).
                    let dd = du - dv;
                    let td = if dd != 0.0 { (v0 - cj as f32 - (u0 - ci as f32)) / dd } else { f32::NAN };
                    if td > t && td < t_exit {
                        let tri_a = tri_of(0.5 * (t + td));
                        if let Some(hh) = self.piece(t, td, f_at(t, tri_a), f_at(td, tri_a), id + tri_a as u32) {
                            return Some(hh);
                        }
                        let tri_b = 1 - tri_a;
                        if let Some(hh) =
                            self.piece(td, t_exit, f_at(td, tri_b), f_at(t_exit, tri_b), id + tri_b as u32)
                        {
                            return Some(hh);
                        }
                    } else {
                        let tri = tri_of(0.5 * (t + t_exit));
                        if let Some(hh) = self.piece(t, t_exit, f_at(t, tri), f_at(t_exit, tri), id + tri as u32) {
                            return Some(hh);
                        }
                    }
                }
            }
            if t_exit >= tb || !g.advance(lo, hi) {
                return None;
            }
            t = t_exit;
        }
    }
}
