//! Sampling the surface's tiles: the heights and slopes `∇η` of the linear (Airy) wave components at every node
//! of a tile, by a two-dimensional phasor recurrence.
//!
//! Every component's `a e^{iψ}` at a tile's corner comes from the rectangle's corner by one rotation per tile
//! column and row (tabulated once per frame), then one product with the level's tabulated powers per node column
//! and row inside the tile (independent products, no chain of rotations); the only `sin_cos` calls are a few per
//! component and frame, and the inner loop is a vectorisable multiply-add over a row of nodes (the same values as
//! [`crate::ocean::WaveField::elevation_slope_grid`] to rounding, tested in the parent module). Beyond
//! `radius_m − taper_m` from the nearest focus the waves taper linearly to the still level.

use super::{nearest, SurfaceSpec, Tile, MAX_LEVEL, TILE_CELLS};
use crate::ocean::WaveComponent;

/// Complex number `(re, im)`.
type C64 = (f64, f64);

#[inline(always)]
fn cmul(a: C64, b: C64) -> C64 {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}

#[inline(always)]
fn cis(x: f64) -> C64 {
    let (s, c) = x.sin_cos();
    (c, s)
}

/// The phasor tables of one frame (see the module docs): per component `a e^{iψ}` at each tile column's corner
/// on the rectangle's bottom edge, the rotation to each tile row, and per level the rotation per node step.
pub(super) struct Phasors<'a> {
    comps: &'a [WaveComponent],
    x0: f32,
    y0: f32,
    tile_m: f32,
    /// `[ix · ncomp + c]`: `a e^{iψ}` at `(x0 + ix · tile_m, y0)`.
    col: Vec<C64>,
    /// `[iy · ncomp + c]`: `e^{i ky iy tile_m}`.
    row: Vec<C64>,
    /// Per level, `[c · w + i]`: `(e^{i kx d i}, e^{i ky d i})` for the node step `d` of that level and the
    /// level's `w` nodes a side (the powers tabulated once per frame, so a tile's nodes need no chain of
    /// rotations: every node's phasor is one product, independent of the others).
    powers: Vec<Vec<(C64, C64)>>,
}

impl<'a> Phasors<'a> {
    pub(super) fn new(
        comps: &'a [WaveComponent],
        t: f64,
        x0: f32,
        y0: f32,
        tile_m: f32,
        ntx: usize,
        nty: usize,
    ) -> Self {
        let nc = comps.len();
        let tm = f64::from(tile_m);
        let mut col = vec![(0.0, 0.0); ntx * nc];
        let mut row = vec![(0.0, 0.0); nty * nc];
        let mut powers: Vec<Vec<(C64, C64)>> =
            (0..=MAX_LEVEL).map(|l| vec![((1.0, 0.0), (1.0, 0.0)); nc * ((TILE_CELLS >> l) + 1)]).collect();
        for (c, w) in comps.iter().enumerate() {
            let base = cis(w.phase_at(f64::from(x0), f64::from(y0), t));
            let (ex, ey) = (cis(w.kx * tm), cis(w.ky * tm));
            let mut p = (w.amplitude_m * base.0, w.amplitude_m * base.1);
            for ix in 0..ntx {
                col[ix * nc + c] = p;
                p = cmul(p, ex);
            }
            let mut q = (1.0, 0.0);
            for iy in 0..nty {
                row[iy * nc + c] = q;
                q = cmul(q, ey);
            }
            for (lvl, table) in powers.iter_mut().enumerate() {
                let n = TILE_CELLS >> lvl;
                let d = tm / n as f64;
                let (sx, sy) = (cis(w.kx * d), cis(w.ky * d));
                let (mut px, mut py) = ((1.0, 0.0), (1.0, 0.0));
                for i in 0..=n {
                    table[c * (n + 1) + i] = (px, py);
                    px = cmul(px, sx);
                    py = cmul(py, sy);
                }
            }
        }
        Self { comps, x0, y0, tile_m, col, row, powers }
    }

    /// Samples tile `(ix, iy)`: its level from the distance of its centre to the nearest focus, flat when wholly
    /// beyond the radius.
    pub(super) fn tile(&self, ix: usize, iy: usize, level: f32, foci: &[[f32; 2]], spec: &SurfaceSpec) -> Tile {
        let tile_m = self.tile_m;
        let (tx, ty) = (self.x0 + ix as f32 * tile_m, self.y0 + iy as f32 * tile_m);
        let half = 0.5 * tile_m;
        let dc = nearest(foci, tx + half, ty + half);
        if dc - std::f32::consts::SQRT_2 * half >= spec.radius_m {
            return Tile::default();
        }
        let lvl = if dc <= spec.near_m { 0 } else { ((dc / spec.near_m).log2().ceil() as u32).min(MAX_LEVEL) };
        let n = TILE_CELLS >> lvl;
        let w = n + 1;
        let nc = self.comps.len();
        let mut eta = vec![0f32; w * w];
        let mut sx = vec![0f32; w * w];
        let mut sy = vec![0f32; w * w];
        let (mut pr, mut pi) = (vec![0f32; w], vec![0f32; w]);
        let table = &self.powers[lvl as usize];
        for (c, comp) in self.comps.iter().enumerate() {
            let pw = &table[c * w..(c + 1) * w];
            let p = cmul(self.col[ix * nc + c], self.row[iy * nc + c]);
            for i in 0..w {
                let v = cmul(p, pw[i].0);
                pr[i] = v.0 as f32;
                pi[i] = v.1 as f32;
            }
            let (kx, ky) = (comp.kx as f32, comp.ky as f32);
            for j in 0..w {
                let q = pw[j].1;
                let (fr, fi) = (q.0 as f32, q.1 as f32);
                let rows = j * w..(j + 1) * w;
                let (e, gx, gy) = (&mut eta[rows.clone()], &mut sx[rows.clone()], &mut sy[rows]);
                let (a, b) = (&pr[..w], &pi[..w]);
                for i in 0..w {
                    let re = a[i] * fr - b[i] * fi;
                    let im = a[i] * fi + b[i] * fr;
                    e[i] += re;
                    gx[i] -= kx * im;
                    gy[i] -= ky * im;
                }
            }
        }
        let mut h = vec![0f32; w * w];
        let mut g = vec![[0f32; 2]; w * w];
        let (mut zmin, mut zmax) = (f32::INFINITY, f32::NEG_INFINITY);
        let inner = spec.radius_m - spec.taper_m.max(0.0);
        // Every node within `inner` of a focus is untapered: no distances when the whole tile is.
        let all_inner = dc + std::f32::consts::SQRT_2 * half <= inner;
        for j in 0..w {
            for i in 0..w {
                let k = j * w + i;
                let taper = if all_inner {
                    1.0
                } else {
                    let (x, y) = (tx + i as f32 * tile_m / n as f32, ty + j as f32 * tile_m / n as f32);
                    let dn = nearest(foci, x, y);
                    if dn <= inner {
                        1.0
                    } else if dn >= spec.radius_m {
                        0.0
                    } else {
                        (spec.radius_m - dn) / (spec.radius_m - inner)
                    }
                };
                let z = level + eta[k] * taper;
                h[k] = z;
                g[k] = [sx[k] * taper, sy[k] * taper];
                zmin = zmin.min(z);
                zmax = zmax.max(z);
            }
        }
        Tile { n, zmin, zmax, h, g }
    }
}
