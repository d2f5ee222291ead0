//! The sun mask of a [`Sea`] (see the parent module's docs): per sun direction and height map, the cells from
//! which a shadow ray may meet something; in a cell only moving boxes put in the mask, the ray is tested against
//! those boxes themselves.

use super::{grown, segment_meets, Sea, MARGIN_M};
use crate::bvh::Box3;
use std::sync::{Arc, Mutex};

/// The cells of a [`Sea`] grid from which a ray towards one sun direction may meet something (see the `sea`
/// module's docs): a ray from above the surface starting in any other cell of the grid hits nothing. In a cell only the
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
pub(super) struct SunCache(Mutex<Option<Arc<SunMask>>>);

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
        let g = grown(b);
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sea::tests::tri;
    use parry3d::math::Vec3;

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
}
