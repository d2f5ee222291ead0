//! Sampling the surface's tiles: the heights and slopes `∇η` of the linear (Airy) wave components at every node
//! of a tile, by a two-dimensional phasor recurrence.
//!
//! Every component's `a e^{iψ}` at a tile's corner comes from the rectangle's corner by one rotation per tile
//! column and row (tabulated once per frame), then one product with the level's tabulated powers per node column
//! and row inside the tile (independent products, no chain of rotations); the only `sin_cos` calls are a few per
//! component and frame, and the inner loop is a vectorisable multiply-add over a row of nodes (the same values as
//! [`crate::ocean::WaveField::elevation_slope_grid`] to rounding, tested in the parent module). Beyond
//! `radius_m − taper_m` from the nearest focus the waves taper linearly to the still level.
//!
//! The heights sum every component; the slopes (which only shading reads) sum only the components the level's
//! cell resolves ([`resolved`]), and the tile keeps the others' mean square slope for the shading to treat
//! statistically (see [`super::WaveSurface::shading`]).

use super::{nearest, resolved, SurfaceSpec, Tile, DETAIL_BANDS, DETAIL_CELLS, MAX_LEVEL, TILE_CELLS};
use crate::ocean::WaveComponent;

/// The mean square slope (both axes) of all the `comps`: `Σ a²k²/2`.
pub(super) fn total_mss(comps: &[WaveComponent]) -> f64 {
    comps.iter().map(WaveComponent::slope_variance).sum()
}

/// Nodes summed together by [`accumulate`] (one AVX2 register of `f32`).
const LANES: usize = 8;

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
    /// Per level (not the detail grid), the rotations to each node row as [`accumulate`] reads them for a tile
    /// summing every component, `([j · nc + c] re, im)` in `f32`: the same for every tile of the level, so made
    /// once per frame.
    rows_f32: Vec<(Vec<f32>, Vec<f32>)>,
    /// Per table of `powers` (levels, then the detail grid), the column rotations `e^{i kx d i}` apart, as
    /// [`spread`] reads them: `([c · s + i] re, im)` with `s` the table's `w` nodes padded to whole groups of
    /// [`LANES`] (zeros in the padding).
    cols_soa: Vec<(Vec<f64>, Vec<f64>)>,
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
        // One table per level, and one for the detail grid ([`DETAIL_CELLS`] cells a side) after them.
        let levels = MAX_LEVEL as usize + 1;
        let cells = |l: usize| if l >= levels { DETAIL_CELLS } else { TILE_CELLS >> l };
        let mut powers: Vec<Vec<(C64, C64)>> =
            (0..=levels).map(|l| vec![((1.0, 0.0), (1.0, 0.0)); nc * (cells(l) + 1)]).collect();
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
                let n = cells(lvl);
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
        let rows_f32 = (0..levels)
            .map(|l| {
                let w = cells(l) + 1;
                let (mut fr, mut fi) = (vec![0f32; w * nc], vec![0f32; w * nc]);
                for c in 0..nc {
                    for i in 0..w {
                        let q = powers[l][c * w + i].1;
                        fr[i * nc + c] = q.0 as f32;
                        fi[i * nc + c] = q.1 as f32;
                    }
                }
                (fr, fi)
            })
            .collect();
        let cols_soa = powers
            .iter()
            .enumerate()
            .map(|(l, table)| {
                let w = cells(l) + 1;
                let stride = w.div_ceil(LANES) * LANES;
                let (mut re, mut im) = (vec![0f64; stride * nc], vec![0f64; stride * nc]);
                for c in 0..nc {
                    for i in 0..w {
                        let q = table[c * w + i].0;
                        re[c * stride + i] = q.0;
                        im[c * stride + i] = q.1;
                    }
                }
                (re, im)
            })
            .collect();
        Self { comps, x0, y0, tile_m, col, row, powers, rows_f32, cols_soa }
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
        // Mean square slope (both axes) of the components this level's cell cannot resolve: their slopes are
        // left out of the sums (a zero wavenumber), their heights kept.
        let cell_m = tile_m / n as f32;
        let mut mss = 0f64;
        let terms: Vec<(usize, [f32; 2])> = self
            .comps
            .iter()
            .enumerate()
            .map(|(c, comp)| {
                if resolved(comp.k_rad_m, cell_m) {
                    (c, [comp.kx as f32, comp.ky as f32])
                } else {
                    mss += comp.slope_variance();
                    (c, [0.0; 2])
                }
            })
            .collect();
        let unresolved_mss = mss;
        let nc = self.comps.len();
        let (eta, sx, sy, stride) = self.node_sums(ix, iy, lvl as usize, w, &terms, spec.slopes);
        let mut h = vec![0f32; w * w];
        let mut g = if spec.slopes { vec![[0f32; 2]; w * w] } else { Vec::new() };
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
                let ks = j * stride + i;
                let z = level + eta[ks] * taper;
                h[k] = z;
                if let Some(g) = g.get_mut(k) {
                    *g = [sx[ks] * taper, sy[ks] * taper];
                }
                zmin = zmin.min(z);
                zmax = zmax.max(z);
            }
        }
        // The detail grid of a finest-level tile wholly inside the untapered sea: the slopes of the waves its
        // cells leave out, in two bands by the cell that resolves them ([`DETAIL_BANDS`]); what even the finest band
        // leaves out stays roughness.
        let mut detail: Vec<[f32; 4]> = Vec::new();
        let mut bands = [false; 2];
        let mut band_mss = [0f32; 2];
        if spec.detail && spec.slopes && lvl == 0 && all_inner {
            let [a_m, b_m] = DETAIL_BANDS.map(|c| tile_m / c as f32);
            let band = |k: f64| {
                if resolved(k, cell_m) {
                    None
                } else if resolved(k, a_m) {
                    Some(0)
                } else if resolved(k, b_m) {
                    Some(1)
                } else {
                    None
                }
            };
            for b in 0..2 {
                let sub: Vec<usize> = (0..nc).filter(|&c| band(self.comps[c].k_rad_m) == Some(b)).collect();
                if sub.is_empty() {
                    continue;
                }
                let slopes = self.detail_slopes(ix, iy, &sub);
                if detail.is_empty() {
                    detail = vec![[0.0; 4]; slopes.len()];
                }
                for (node, g) in detail.iter_mut().zip(&slopes) {
                    node[2 * b] = g[0];
                    node[2 * b + 1] = g[1];
                }
                bands[b] = true;
                let m: f64 = sub.iter().map(|&c| self.comps[c].slope_variance()).sum();
                band_mss[b] = m as f32;
                mss = (mss - m).max(0.0);
            }
        }
        // The finest grid's slopes of the waves this coarser tile leaves out (SurfaceSpec::fine_m), for a top
        // view's uniform footprint.
        let (mut fine, mut fine_mss) = (Vec::new(), 0f32);
        let fine_cell = tile_m / TILE_CELLS as f32;
        if spec.detail && spec.slopes && lvl > 0 && all_inner && dc - std::f32::consts::SQRT_2 * half <= spec.fine_m {
            let terms: Vec<(usize, [f32; 2])> = (0..nc)
                .filter(|&c| resolved(self.comps[c].k_rad_m, fine_cell) && !resolved(self.comps[c].k_rad_m, cell_m))
                .map(|c| (c, [self.comps[c].kx as f32, self.comps[c].ky as f32]))
                .collect();
            if !terms.is_empty() {
                let w = TILE_CELLS + 1;
                let (_, sx, sy, stride) = self.node_sums(ix, iy, 0, w, &terms, true);
                fine = (0..w * w).map(|q| [sx[(q / w) * stride + q % w], sy[(q / w) * stride + q % w]]).collect();
                let m: f64 = terms.iter().map(|&(c, _)| self.comps[c].slope_variance()).sum();
                fine_mss = m as f32;
                mss = (mss - m).max(0.0);
            }
        }
        // Where the waves taper (a level-of-detail device: the sea goes on), the slopes the taper takes from the
        // sampled ones are handed to the roughness, so the total slope variance stays the sea's: the resolved
        // waves' `R` drawn at `s²R` (`s` the taper at the tile's centre) and `(1 − s²) R` as roughness; beyond the
        // taper the still level is shaded with all of it ([`super::WaveSurface::shading`]).
        let centre_taper = ((spec.radius_m - dc) / (spec.radius_m - inner).max(1e-6)).clamp(0.0, 1.0);
        let resolved_mss = (total_mss(self.comps) - unresolved_mss).max(0.0);
        let mss = (mss + (1.0 - f64::from(centre_taper * centre_taper)) * resolved_mss) as f32;
        Tile { n, zmin, zmax, h, g, mss, detail, bands, band_mss, fine, fine_mss }
    }

    /// The slopes `(∂η/∂x, ∂η/∂y)` of components `sub` alone at the `(DETAIL_CELLS + 1)²` nodes of tile
    /// `(ix, iy)`'s detail grid, row-major (the same phasor sums as [`Phasors::tile`], heights discarded).
    fn detail_slopes(&self, ix: usize, iy: usize, sub: &[usize]) -> Vec<[f32; 2]> {
        let w = DETAIL_CELLS + 1;
        let terms: Vec<(usize, [f32; 2])> =
            sub.iter().map(|&c| (c, [self.comps[c].kx as f32, self.comps[c].ky as f32])).collect();
        let (_, sx, sy, stride) = self.node_sums(ix, iy, MAX_LEVEL as usize + 1, w, &terms, true);
        (0..w * w).map(|q| [sx[(q / w) * stride + q % w], sy[(q / w) * stride + q % w]]).collect()
    }

    /// The sums of [`accumulate`] over the `w × w` nodes of tile `(ix, iy)` with power table `table` (a level's,
    /// or the detail grid's after them, for `w` nodes a side): per term, a component's index and the wavenumber its slopes are summed with
    /// (zero: its height only). Returns `eta`, `sx`, `sy` row-major with rows padded to `stride` nodes; without
    /// `slopes`, `sx` and `sy` empty (the heights alone summed, the same bits).
    fn node_sums(
        &self,
        ix: usize,
        iy: usize,
        table: usize,
        w: usize,
        terms: &[(usize, [f32; 2])],
        slopes: bool,
    ) -> (Vec<f32>, Vec<f32>, Vec<f32>, usize) {
        let nc = self.comps.len();
        let level = table;
        let table = &self.powers[level];
        let nt = terms.len();
        // Node rows padded to whole groups of LANES (the padding lanes are summed and never read).
        let groups = w.div_ceil(LANES);
        let stride = groups * LANES;
        // Per term: its phasor along the bottom row, `[(g · nt + t) · LANES + l]` for node column `g · LANES + l`
        // (group-major, so the sum over terms reads memory in order), and the rotation to each node row
        // `[j · nt + t]`.
        let (mut ar, mut ai) = (vec![0f32; groups * nt * LANES], vec![0f32; groups * nt * LANES]);
        // Every component in order (a tile's own sums): the level's row rotations are made once per frame.
        let shared =
            self.rows_f32.get(level).filter(|_| nt == nc && terms.iter().enumerate().all(|(t, &(c, _))| c == t));
        let (mut fr, mut fi) =
            if shared.is_some() { (Vec::new(), Vec::new()) } else { (vec![0f32; w * nt], vec![0f32; w * nt]) };
        let mut k = vec![[0f32; 2]; nt];
        let corner: Vec<(usize, C64)> =
            terms.iter().map(|&(c, _)| (c, cmul(self.col[ix * nc + c], self.row[iy * nc + c]))).collect();
        let (qr, qi) = &self.cols_soa[level];
        spread(&corner, (qr, qi), (&mut ar, &mut ai));
        for (t, &(c, kc)) in terms.iter().enumerate() {
            let pw = &table[c * w..(c + 1) * w];
            if shared.is_none() {
                for (i, q) in pw.iter().enumerate() {
                    fr[i * nt + t] = q.1 .0 as f32;
                    fi[i * nt + t] = q.1 .1 as f32;
                }
            }
            k[t] = kc;
        }
        let (fr, fi) = shared.map_or((&fr[..], &fi[..]), |(r, i)| (&r[..], &i[..]));
        let mut eta = vec![0f32; stride * w];
        let slope_len = if slopes { stride * w } else { 0 };
        let (mut sx, mut sy) = (vec![0f32; slope_len], vec![0f32; slope_len]);
        accumulate((&ar, &ai), (fr, fi), &k, (&mut eta, &mut sx, &mut sy));
        (eta, sx, sy, stride)
    }
}

crate::dispatch! {
    /// Spreads each term's phasor along a tile's bottom row into [`accumulate`]'s `row` layout: for term `t`
    /// (component `c`, phasor `p` at the tile's corner, `corner[t] = (c, p)`), `p · e^{i kx d i}` at node column
    /// `i` (`cols` as [`Phasors`] keeps them, per component a row of whole groups of [`LANES`]) into `out` at
    /// `[(g · nt + t) · LANES + l]` for `i = g · LANES + l`, rounded to `f32` (the padding lanes get `p · 0`,
    /// summed and never read). The same products as one complex multiplication per node (no fused multiply-adds):
    /// the same bits, a whole group at a time; compiled for AVX2 where the CPU has it.
    fn spread(corner: &[(usize, C64)], cols: (&[f64], &[f64]), out: (&mut [f32], &mut [f32])) {
        let nt = corner.len();
        let (ar, ai) = out;
        if nt == 0 {
            return;
        }
        let groups = ar.len() / (nt * LANES);
        let stride = groups * LANES;
        for (t, &(c, p)) in corner.iter().enumerate() {
            let (qr, qi) = (&cols.0[c * stride..(c + 1) * stride], &cols.1[c * stride..(c + 1) * stride]);
            for (g, (gr, gi)) in qr.chunks_exact(LANES).zip(qi.chunks_exact(LANES)).enumerate() {
                let at = (g * nt + t) * LANES;
                let re: [f32; LANES] = std::array::from_fn(|l| (p.0 * gr[l] - p.1 * gi[l]) as f32);
                let im: [f32; LANES] = std::array::from_fn(|l| (p.0 * gi[l] + p.1 * gr[l]) as f32);
                ar[at..at + LANES].copy_from_slice(&re);
                ai[at..at + LANES].copy_from_slice(&im);
            }
        }
    }
}

crate::dispatch! {
    /// Sums the components at every node of a tile: `row` holds each component's phasor `(re, im)` along the
    /// tile's bottom row (group-major, see [`Phasors::tile`]), `rot` its rotation `(re, im)` to each node row
    /// (`[j · nc + c]`), `k` its wavenumber; `eta = Σ re`, `(sx, sy) = −Σ (kx, ky) im`, row-major, rows padded to
    /// whole groups of [`LANES`] (`sx` and `sy` empty: the heights alone, for a surface nothing shades,
    /// [`SurfaceSpec::slopes`] off). Each group of nodes keeps its sums in registers over all components (one store
    /// per node, not one per component), and every node adds the components in order, as a loop per component
    /// would: the same bits, with or without the slopes. Compiled for AVX2 where the CPU has it (no fused
    /// multiply-adds).
    fn accumulate(
        row: (&[f32], &[f32]),
        rot: (&[f32], &[f32]),
        k: &[[f32; 2]],
        out: (&mut [f32], &mut [f32], &mut [f32]),
    ) {
        if out.1.is_empty() {
            sum_nodes::<false>(row, rot, k, out);
        } else {
            sum_nodes::<true>(row, rot, k, out);
        }
    }
}

/// [`accumulate`]'s body, with or without the slopes (inlined into each instruction-set copy).
#[inline(always)]
fn sum_nodes<const SLOPES: bool>(
    row: (&[f32], &[f32]),
    rot: (&[f32], &[f32]),
    k: &[[f32; 2]],
    out: (&mut [f32], &mut [f32], &mut [f32]),
) {
    let nc = k.len();
    let ((ar, ai), (fr, fi), (eta, sx, sy)) = (row, rot, out);
    if nc == 0 {
        return;
    }
    let groups = ar.len() / (nc * LANES);
    let stride = groups * LANES;
    for (j, e_row) in eta.chunks_exact_mut(stride).enumerate() {
        let (fr, fi) = (&fr[j * nc..(j + 1) * nc], &fi[j * nc..(j + 1) * nc]);
        for g in 0..groups {
            let span = g * nc * LANES..(g + 1) * nc * LANES;
            let (mut e, mut gx, mut gy) = ([0f32; LANES], [0f32; LANES], [0f32; LANES]);
            let comps = ar[span.clone()].chunks_exact(LANES).zip(ai[span].chunks_exact(LANES));
            for ((a, b), ((&r, &i), kc)) in comps.zip(fr.iter().zip(fi).zip(k)) {
                for l in 0..LANES {
                    e[l] += a[l] * r - b[l] * i;
                    if SLOPES {
                        let im = a[l] * i + b[l] * r;
                        gx[l] -= kc[0] * im;
                        gy[l] -= kc[1] * im;
                    }
                }
            }
            let at = g * LANES..(g + 1) * LANES;
            e_row[at.clone()].copy_from_slice(&e);
            if SLOPES {
                let at = j * stride + at.start..j * stride + at.end;
                sx[at.clone()].copy_from_slice(&gx);
                sy[at].copy_from_slice(&gy);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ocean::{SeaSpec, WaveField};

    /// The register-blocked sum gives, bit for bit, what adding the components one after the other at every node
    /// gives (the plain loop it replaced), at every level, tapered tiles included.
    #[test]
    fn blocked_sum_is_the_plain_sum_bit_for_bit() {
        let spec = SeaSpec { hs: 2.5, tp: 8.0, gamma: 3.3, direction_rad: 0.3, spread_s: 10.0 };
        let f = WaveField::new(&spec, 5).unwrap_or_else(|e| unreachable!("{e}"));
        let comps = f.components();
        let foci = [[10.0f32, -20.0], [150.0, 60.0]];
        let sspec = SurfaceSpec::default();
        let (tile_m, ntx, nty) = (32.0f32, 24usize, 18usize);
        let (x0, y0) = (-350.0f32, -330.0f32);
        let ph = Phasors::new(comps, 12.5, x0, y0, tile_m, ntx, nty);
        let nc = comps.len();
        let mut seen = [false; (MAX_LEVEL + 1) as usize];
        for iy in 0..nty {
            for ix in 0..ntx {
                let tile = ph.tile(ix, iy, 0.0, &foci, &sspec);
                if tile.n == 0 {
                    continue;
                }
                let lvl = (TILE_CELLS / tile.n).trailing_zeros() as usize;
                seen[lvl] = true;
                let w = tile.n + 1;
                let table = &ph.powers[lvl];
                let (mut eta, mut sx, mut sy) = (vec![0f32; w * w], vec![0f32; w * w], vec![0f32; w * w]);
                for (c, comp) in comps.iter().enumerate() {
                    let pw = &table[c * w..(c + 1) * w];
                    let p = cmul(ph.col[ix * nc + c], ph.row[iy * nc + c]);
                    let keep = resolved(comp.k_rad_m, tile_m / tile.n as f32);
                    let (kx, ky) = if keep { (comp.kx as f32, comp.ky as f32) } else { (0.0, 0.0) };
                    for j in 0..w {
                        let (fr, fi) = (pw[j].1 .0 as f32, pw[j].1 .1 as f32);
                        for i in 0..w {
                            let v = cmul(p, pw[i].0);
                            let (a, b) = (v.0 as f32, v.1 as f32);
                            let k = j * w + i;
                            eta[k] += a * fr - b * fi;
                            let im = a * fi + b * fr;
                            sx[k] -= kx * im;
                            sy[k] -= ky * im;
                        }
                    }
                }
                let half = 0.5 * tile_m;
                let dc = nearest(&foci, x0 + ix as f32 * tile_m + half, y0 + iy as f32 * tile_m + half);
                let untapered = dc + std::f32::consts::SQRT_2 * half <= sspec.radius_m - sspec.taper_m;
                for k in 0..w * w {
                    if untapered {
                        assert_eq!(tile.h[k].to_bits(), eta[k].to_bits(), "tile ({ix}, {iy}) node {k}");
                        assert_eq!(tile.g[k][0].to_bits(), sx[k].to_bits());
                        assert_eq!(tile.g[k][1].to_bits(), sy[k].to_bits());
                    }
                }
            }
        }
        assert!(seen[..4].iter().all(|&s| s), "levels sampled: {seen:?}");
    }
}
