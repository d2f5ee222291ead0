//! The displaced sea surface of one frame: a heightfield sampled from a sum of wave components, which every ray
//! of every sensor meets (crests occlude what lies behind them).
//!
//! Model: the elevation `η(x, y, t) = Σ a cos(kx x + ky y − ω t + φ)` of the linear (Airy) wave components of
//! [`crate::ocean::WaveField`] (a random-phase realisation of a directional spectrum), triangulated. The
//! surface is sampled once per frame time on a world-aligned lattice of square tiles ([`TILE_CELLS`] cells a side, [`SurfaceSpec::
//! tile_m`] metres): fine near the *foci* (the USVs, every sensor's platform), coarser with distance (each level
//! doubles the cell), and tapered to the still level beyond [`SurfaceSpec::radius_m`] (flat there). The level of
//! detail depends only on the frame's foci, so every sensor and every agent sees the same surface at one frame.
//!
//! Each cell is two triangles (split along the `(0,0)–(1,1)` diagonal). A ray meets that piecewise-planar surface
//! exactly ([`WaveSurface::intersect`], the sign march of [`march`]); tiles and cells whose sampled maximum lies
//! below the ray are skipped whole. Heights and slopes `∇η` (for smooth shading normals,
//! [`WaveSurface::shading`], whose filtering of the waves a level cannot resolve lives in [`shading`]) are summed
//! per tile by the phasor recurrence of [`sample`].

mod march;
mod raster;
mod sample;
mod shading;

use crate::ocean::WaveComponent;
use march::intersect_with;
pub use raster::{PinholeView, Raster, WaterHit};
use rayon::prelude::*;
use sample::Phasors;
use shading::resolved;
pub use shading::{SurfaceShading, DETAIL_BANDS, DETAIL_CELLS};

/// Cells along a side of a finest-level tile (a tile at level `L` has `TILE_CELLS >> L`).
pub const TILE_CELLS: usize = 32;
/// Coarsest level (one cell per tile).
const MAX_LEVEL: u32 = 5;
/// Rays that rise from within this height (metres) above the surface under their origin leave the water: the
/// surface does not occlude them ([`WaveSurface::leaves`]).
pub const SKIN_M: f32 = 0.25;
/// Piece id of the still, flat water (outside the sampled tiles or in a flat tile).
pub const FLAT_PIECE: u32 = u32::MAX - 1;

/// How finely the surface is sampled around its foci.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceSpec {
    /// Side of a tile, metres (the finest cell is `tile_m / 32`).
    pub tile_m: f32,
    /// Tiles whose centre lies within this distance of a focus are sampled at the finest level; each doubling of
    /// the distance halves the detail.
    pub near_m: f32,
    /// The waves taper to the still level between `radius_m - taper_m` and `radius_m` from the nearest focus.
    pub radius_m: f32,
    /// Width of that taper, metres.
    pub taper_m: f32,
    /// Whether the finest-level tiles also carry the slopes of the waves shorter than four of their cells on a
    /// grid of a quarter of their cell, in two bands ([`DETAIL_BANDS`]), for shading only: cameras near the foci
    /// see waves down to one cell long as normals rather than roughness. The geometry, and so every hit, is the same either way; the
    /// sampling costs more (the scene sets it only when cameras render).
    pub detail: bool,
}

impl Default for SurfaceSpec {
    /// 1 m cells within ~40 m, 2 m to ~80 m, 4 m to ~160 m, 8 m to ~320 m, waves out to 320 m around every
    /// focus (tapered over the last 60 m).
    fn default() -> Self {
        Self { tile_m: 32.0, near_m: 40.0, radius_m: 320.0, taper_m: 60.0, detail: false }
    }
}

/// One sampled tile: `n` cells a side (0: flat at the still level), node heights and slopes row-major.
#[derive(Debug, Clone, Default)]
struct Tile {
    n: usize,
    zmin: f32,
    zmax: f32,
    /// `(n+1)²` heights, world z (every component).
    h: Vec<f32>,
    /// `(n+1)²` slopes `(∂η/∂x, ∂η/∂y)` of the components the cell resolves ([`resolved`]).
    g: Vec<[f32; 2]>,
    /// Mean square slope `Σ a²k²/2` (both axes) of the components its slopes leave out (the detail bands'
    /// apart), tapered as the waves are.
    mss: f32,
    /// With [`SurfaceSpec::detail`], on a finest-level tile: per detail band ([`DETAIL_BANDS`]), the slopes
    /// `(∂η/∂x, ∂η/∂y)` of its waves at the `(DETAIL_CELLS + 1)²` nodes of the detail grid; empty otherwise.
    detail: [Vec<[f32; 2]>; 2],
    /// The mean square slopes of the two detail bands' waves.
    band_mss: [f32; 2],
}

/// The displaced sea surface of one frame (see the module docs).
#[derive(Debug, Clone)]
pub struct WaveSurface {
    level: f32,
    time_s: f64,
    /// Lower corner of the tile rectangle (world x, y).
    x0: f32,
    y0: f32,
    tile_m: f32,
    /// `1 / tile_m`.
    inv_tile_m: f32,
    ntx: usize,
    nty: usize,
    tiles: Vec<Tile>,
    zmin: f32,
    zmax: f32,
}

/// A hit of a ray with the surface: distance and the piece (tile, cell, triangle) hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceHit {
    /// Distance along the ray's direction.
    pub t: f32,
    /// The piece: see [`WaveSurface::piece_normal`].
    pub piece: u32,
}

impl WaveSurface {
    /// Samples `components` at time `time_s` around the `foci` (world x, y), with still level `level`.
    /// Deterministic: the same inputs give the same surface, whatever the thread count.
    pub fn new(components: &[WaveComponent], time_s: f64, level: f32, foci: &[[f32; 2]], spec: SurfaceSpec) -> Self {
        let tile_m = spec.tile_m.max(1e-3);
        let reach = spec.radius_m.max(0.0);
        let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
        for f in foci {
            for a in 0..2 {
                lo[a] = lo[a].min(f[a] - reach);
                hi[a] = hi[a].max(f[a] + reach);
            }
        }
        let empty = foci.is_empty() || reach == 0.0 || components.is_empty();
        let (x0, y0, ntx, nty) = if empty {
            (0.0, 0.0, 0, 0)
        } else {
            let x0 = (lo[0] / tile_m).floor() * tile_m;
            let y0 = (lo[1] / tile_m).floor() * tile_m;
            (x0, y0, ((hi[0] - x0) / tile_m).ceil() as usize, ((hi[1] - y0) / tile_m).ceil() as usize)
        };
        let phasors = Phasors::new(components, time_s, x0, y0, tile_m, ntx, nty);
        let tiles: Vec<Tile> = (0..ntx * nty)
            .into_par_iter()
            .map(|k| {
                let (ix, iy) = (k % ntx, k / ntx);
                phasors.tile(ix, iy, level, foci, &spec)
            })
            .collect();
        let mut zmin = level;
        let mut zmax = level;
        for t in &tiles {
            if t.n > 0 {
                zmin = zmin.min(t.zmin);
                zmax = zmax.max(t.zmax);
            }
        }
        Self { level, time_s, x0, y0, tile_m, inv_tile_m: 1.0 / tile_m, ntx, nty, tiles, zmin, zmax }
    }

    /// The still water level (world z).
    pub fn level(&self) -> f32 {
        self.level
    }
    /// The frame time the surface was sampled at, seconds.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }
    /// Highest point of the surface (world z): no ray above it can meet the water.
    pub fn zmax(&self) -> f32 {
        self.zmax
    }
    /// Lowest point of the surface (world z).
    pub fn zmin(&self) -> f32 {
        self.zmin
    }
    /// Number of sampled (non-flat) tiles.
    pub fn sampled_tiles(&self) -> usize {
        self.tiles.iter().filter(|t| t.n > 0).count()
    }

    /// The tile holding world `(x, y)`, if inside the rectangle.
    #[inline(always)]
    fn tile_at(&self, x: f32, y: f32) -> Option<(usize, usize)> {
        let (u, v) = ((x - self.x0) * self.inv_tile_m, (y - self.y0) * self.inv_tile_m);
        // Truncation is the floor here: negative and NaN coordinates are out (`!(u >= 0)`).
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(u >= 0.0 && v >= 0.0 && u < self.ntx as f32 && v < self.nty as f32) {
            return None;
        }
        Some(((u as usize).min(self.ntx - 1), (v as usize).min(self.nty - 1)))
    }

    /// The cell holding world `(x, y)` of tile `(ix, iy)` cut into `n` cells a side, and the local `(fu, fv)` in
    /// it (clamped into the tile).
    #[inline(always)]
    fn cell_at(&self, n: usize, ix: usize, iy: usize, x: f32, y: f32) -> ([usize; 2], [f32; 2]) {
        let inv = n as f32 * self.inv_tile_m;
        let u = ((x - (self.x0 + ix as f32 * self.tile_m)) * inv).clamp(0.0, n as f32);
        let v = ((y - (self.y0 + iy as f32 * self.tile_m)) * inv).clamp(0.0, n as f32);
        let (ci, cj) = ((u as usize).min(n - 1), (v as usize).min(n - 1));
        ([ci, cj], [u - ci as f32, v - cj as f32])
    }

    /// Height of the surface at world `(x, y)` (the triangulated surface; the still level outside).
    #[inline]
    pub fn height(&self, x: f32, y: f32) -> f32 {
        let Some((ix, iy)) = self.tile_at(x, y) else { return self.level };
        let k = iy * self.ntx + ix;
        let t = &self.tiles[k];
        if t.n == 0 {
            return self.level;
        }
        let ([ci, cj], [fu, fv]) = self.cell_at(t.n, ix, iy, x, y);
        let (plane, _) = cell_planes(t, ci, cj);
        let p = if fu >= fv { plane[0] } else { plane[1] };
        p[0] + p[1] * fu + p[2] * fv
    }

    /// Unit geometric normal (up-facing) of piece `piece` (a [`SurfaceHit::piece`]).
    #[inline]
    pub fn piece_normal(&self, piece: u32) -> [f32; 3] {
        if piece == FLAT_PIECE {
            return [0.0, 0.0, 1.0];
        }
        let per_tile = (2 * TILE_CELLS * TILE_CELLS) as u32;
        let (k, rest) = ((piece / per_tile) as usize, piece % per_tile);
        let Some(t) = self.tiles.get(k).filter(|t| t.n > 0) else { return [0.0, 0.0, 1.0] };
        let (cell, tri) = ((rest / 2) as usize, (rest % 2) as usize);
        // n is a power of two: the column and row by mask and shift.
        let (ci, cj) = (cell & (t.n - 1), cell >> t.n.trailing_zeros());
        if cj >= t.n {
            return [0.0, 0.0, 1.0];
        }
        let s = self.tile_m / t.n as f32;
        let (plane, _) = cell_planes(t, ci, cj);
        let p = plane[tri];
        unit([-p[1] / s, -p[2] / s, 1.0])
    }

    /// The first crossing of the ray `o + t·d` (`d` unit, `0 <= t < t_max`) with the surface, from either side,
    /// or `None`.
    pub fn intersect(&self, o: [f32; 3], d: [f32; 3], t_max: f32) -> Option<SurfaceHit> {
        intersect_with(self, o, d, t_max)
    }

    /// Whether the ray `o + t·d` rises from the water itself: its origin lies no more than [`SKIN_M`] above (and
    /// not below) the surface under it. Such rays — a camera's reflected rays and shadow rays from the water it
    /// sees — are not occluded by the waves (no wave self-shadowing; the capillary slopes' shading stands in for
    /// it), which the scene applies to every such ray alike, so its shortcuts stay exact.
    #[inline]
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: a NaN must answer "no"
    pub fn leaves(&self, o: [f32; 3], d: [f32; 3]) -> bool {
        if !(d[2] > 0.0) || o[2] > self.zmax + SKIN_M || o[2] < self.zmin {
            return false;
        }
        let h = self.height(o[0], o[1]);
        o[2] >= h && o[2] <= h + SKIN_M
    }

    /// Whether the ray `o + t·d` crosses the surface with `0 <= t < t_max`.
    #[inline]
    pub fn occludes(&self, o: [f32; 3], d: [f32; 3], t_max: f32) -> bool {
        self.intersect(o, d, t_max).is_some()
    }
}

/// The two triangle planes of cell `(ci, cj)` as `[h0, ∂h/∂fu, ∂h/∂fv]` over the cell's local `(fu, fv) ∈ [0,1]²`:
/// `[0]` for `fu >= fv` (corners 00, 10, 11), `[1]` for `fu < fv` (00, 11, 01); and the cell's highest corner.
#[inline(always)]
fn cell_planes(t: &Tile, ci: usize, cj: usize) -> ([[f32; 3]; 2], f32) {
    let w = t.n + 1;
    let (h00, h10) = (t.h[cj * w + ci], t.h[cj * w + ci + 1]);
    let (h01, h11) = (t.h[(cj + 1) * w + ci], t.h[(cj + 1) * w + ci + 1]);
    ([[h00, h10 - h00, h11 - h10], [h00, h11 - h01, h01 - h00]], fmax(fmax(h00, h10), fmax(h01, h11)))
}

/// The smaller of `a` and `b`, for a march's distances and heights (never NaN where it is used: one
/// instruction, where `f32::min`'s care for NaN costs two more); `a` when they are equal or `b` is NaN.
#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if b < a {
        b
    } else {
        a
    }
}

/// The larger of `a` and `b` (see [`fmin`]).
#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if b > a {
        b
    } else {
        a
    }
}

#[inline]
fn unit(v: [f32; 3]) -> [f32; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] / n, v[1] / n, v[2] / n]
}

/// Distance from `(x, y)` to the nearest focus.
#[inline]
fn nearest(foci: &[[f32; 2]], x: f32, y: f32) -> f32 {
    foci.iter().map(|f| (f[0] - x).hypot(f[1] - y)).fold(f32::INFINITY, f32::min)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::f64::consts::TAU;

    /// A wave component `a cos(kx x + ky y − ω t + φ)` (the derived fields filled in).
    pub(crate) fn comp(a: f64, kx: f64, ky: f64, omega: f64, phase: f64) -> WaveComponent {
        WaveComponent {
            amplitude_m: a,
            omega_rad_s: omega,
            k_rad_m: kx.hypot(ky),
            direction_rad: ky.atan2(kx),
            phase_rad: phase,
            kx,
            ky,
        }
    }

    /// A small irregular sea: eight components over directions and wavelengths 12..80 m, amplitudes summing
    /// to 1.6 m.
    pub(crate) fn test_sea() -> Vec<WaveComponent> {
        (0..8)
            .map(|i| {
                let k = std::f64::consts::TAU / (12.0 + 9.5 * i as f64);
                let dir = 0.4 + 0.37 * i as f64;
                comp(0.2, k * dir.cos(), k * dir.sin(), (9.81 * k).sqrt(), 1.3 * i as f64)
            })
            .collect()
    }

    /// The elevation summed point by point (the independent reference).
    fn eta(c: &[WaveComponent], x: f64, y: f64, t: f64) -> f64 {
        c.iter().map(|w| w.amplitude_m * (w.kx * x + w.ky * y - w.omega_rad_s * t + w.phase_rad).cos()).sum()
    }

    fn surface(sea: &[WaveComponent], t: f64, foci: &[[f32; 2]], spec: SurfaceSpec) -> WaveSurface {
        WaveSurface::new(sea, t, 0.0, foci, spec)
    }

    #[test]
    fn nodes_hold_the_analytic_elevation_and_slope() {
        let c = test_sea();
        let spec = SurfaceSpec { radius_m: 2000.0, ..SurfaceSpec::default() };
        let s = surface(&c, 12.5, &[[130.0, -40.0]], spec);
        let mut checked = 0;
        for (k, tile) in s.tiles.iter().enumerate() {
            if tile.n == 0 || k % 7 != 0 {
                continue;
            }
            let (ix, iy) = (k % s.ntx, k / s.ntx);
            let w = tile.n + 1;
            for j in (0..w).step_by(3) {
                for i in (0..w).step_by(5) {
                    let x = f64::from(s.x0 + ix as f32 * s.tile_m) + i as f64 * f64::from(s.tile_m) / tile.n as f64;
                    let y = f64::from(s.y0 + iy as f32 * s.tile_m) + j as f64 * f64::from(s.tile_m) / tile.n as f64;
                    if nearest(&[[130.0, -40.0]], x as f32, y as f32) > spec.radius_m - spec.taper_m {
                        continue; // tapered
                    }
                    let e = eta(&c, x, y, 12.5);
                    assert!((f64::from(tile.h[j * w + i]) - e).abs() < 2e-4, "tile {k} node {i},{j}");
                    // The slopes: those of the waves at least four cells long only.
                    let cell = f64::from(s.tile_m) / tile.n as f64;
                    let gx: f64 = c
                        .iter()
                        .filter(|w| std::f64::consts::TAU / w.k_rad_m >= 4.0 * cell)
                        .map(|w| -w.amplitude_m * w.kx * w.phase_at(x, y, 12.5).sin())
                        .sum();
                    assert!((f64::from(tile.g[j * w + i][0]) - gx).abs() < 2e-4);
                    checked += 1;
                }
            }
        }
        assert!(checked > 500);
        assert!(s.zmax() > 0.5 && s.zmax() <= 1.6 && s.zmin() < -0.5);
    }

    /// A wave shorter than four cells leaves the level's shading slopes and becomes its roughness: its slope
    /// variance `a²k²/2` exactly, at every level too coarse for it, so resolved and unresolved slopes together
    /// keep the sea's whole mean square slope at every level; the heights keep it at every level.
    #[test]
    fn short_waves_become_roughness_not_aliased_slopes() {
        // 1.5 m and 12 m waves: the first is resolved nowhere (finest cell 1 m), the second up to 2 m cells.
        let (k1, k2) = (std::f64::consts::TAU / 1.5, std::f64::consts::TAU / 12.0);
        let sea = [comp(0.02, k1 * 0.6, k1 * 0.8, 0.0, 0.3), comp(0.3, k2, 0.0, 0.0, 1.1)];
        let spec = SurfaceSpec { radius_m: 2000.0, ..SurfaceSpec::default() };
        let s = surface(&sea, 0.0, &[[0.0, 0.0]], spec);
        let (m1, m2) = ((0.02 * k1).powi(2) / 2.0, (0.3 * k2).powi(2) / 2.0);
        let mut seen = [false; 4];
        for (k, tile) in s.tiles.iter().enumerate().filter(|(_, t)| t.n > 0) {
            let centre = [s.x0 + ((k % s.ntx) as f32 + 0.5) * s.tile_m, s.y0 + ((k / s.ntx) as f32 + 0.5) * s.tile_m];
            if nearest(&[[0.0, 0.0]], centre[0], centre[1]) > spec.radius_m - spec.taper_m {
                continue; // tapered
            }
            let cell = f64::from(s.tile_m) / tile.n as f64;
            let want = if cell * 4.0 > 12.0 { m1 + m2 } else { m1 };
            assert!((f64::from(tile.mss) - want).abs() < 1e-6 * want.max(1e-3), "cell {cell}: {} vs {want}", tile.mss);
            // The shading slopes are the long wave's alone where it is resolved (no 1.5 m aliasing), none else.
            for (q, g) in tile.g.iter().enumerate().step_by(7) {
                let long = if cell * 4.0 > 12.0 { 0.0 } else { 0.3 * k2 };
                assert!(g[0].abs() <= long as f32 + 1e-5 && g[1].abs() < 1e-5, "cell {cell} node {q}: {g:?}");
            }
            seen[(TILE_CELLS / tile.n).trailing_zeros().min(3) as usize] = true;
        }
        assert!(seen.iter().all(|&v| v), "levels: {seen:?}");
        let sh = s.shading(3.0, 4.0, 0.0).unwrap_or_else(|| unreachable!("inside the sampled tiles"));
        assert!((f64::from(sh.unresolved_mss) - m1).abs() < 1e-9 && sh.normal[2] > 0.9);
    }

    /// With `detail`, a finest-level tile carries, on a grid of a quarter of its cell, the slopes of the waves
    /// too short for its cells in two bands (here a 3 m wave in band 0 and a 1.5 m wave in band 1: their analytic slopes
    /// at every detail node); the shading draws each band as normals or roughness by the pixel's footprint;
    /// coarser tiles and the geometry do not change.
    #[test]
    fn detail_bands_hold_the_short_waves_and_follow_the_footprint() {
        let (k1, k2, k3) = (TAU / 3.0, TAU / 12.0, TAU / 1.5);
        let sea =
            [comp(0.04, k1 * 0.6, k1 * 0.8, 0.0, 0.3), comp(0.3, k2, 0.0, 0.0, 1.1), comp(0.01, 0.0, k3, 0.0, 2.0)];
        let base = SurfaceSpec { radius_m: 2000.0, ..SurfaceSpec::default() };
        let plain = surface(&sea, 0.0, &[[0.0, 0.0]], base);
        let s = surface(&sea, 0.0, &[[0.0, 0.0]], SurfaceSpec { detail: true, ..base });
        let (m1, m3) = ((0.04 * k1).powi(2) / 2.0, (0.01 * k3).powi(2) / 2.0);

        let slope = |c: &WaveComponent, x: f64, y: f64| {
            let sn = c.phase_at(x, y, 0.0).sin();
            [-c.amplitude_m * c.kx * sn, -c.amplitude_m * c.ky * sn]
        };
        let mut checked = 0;
        for (k, (t, p)) in s.tiles.iter().zip(&plain.tiles).enumerate() {
            assert_eq!(t.h, p.h, "tile {k}: the geometry is the same");
            assert_eq!(t.g, p.g);
            if t.n != TILE_CELLS {
                assert!(t.detail.iter().all(Vec::is_empty) && t.mss == p.mss);
                continue;
            }
            assert!(t.mss.abs() < 1e-9, "every short wave is in a band: {}", t.mss);
            assert!((f64::from(t.band_mss[0]) - m1).abs() < 1e-9 && (f64::from(t.band_mss[1]) - m3).abs() < 1e-9);
            let (x0, y0) = (f64::from(s.x0) + (k % s.ntx) as f64 * 32.0, f64::from(s.y0) + (k / s.ntx) as f64 * 32.0);
            for (band, wave, tol) in [(0, &sea[0], 2e-4), (1, &sea[2], 1e-4)] {
                let w = DETAIL_CELLS + 1;
                assert_eq!(t.detail[band].len(), w * w, "tile {k} band {band}");
                let step = 32.0 / DETAIL_CELLS as f64;
                for (q, g) in t.detail[band].iter().enumerate().step_by(37) {
                    let (x, y) = (x0 + (q % w) as f64 * step, y0 + (q / w) as f64 * step);
                    let want = slope(wave, x, y);
                    let got = g.map(f64::from);
                    assert!((got[0] - want[0]).abs() < tol && (got[1] - want[1]).abs() < tol, "band {band} node {q}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 100);
        // At a detail node near the focus: a fine footprint adds both bands' slopes; 0.5 m (a top view's pixel)
        // only the 3 m wave's, the 1.5 m wave as roughness; 1 m neither, both as roughness.
        let (x, y) = (3.5f64, 7.0f64); // a detail node: the tiles' corners are multiples of 32 m
        let n0 = plain.shading(x as f32, y as f32, 0.0).unwrap_or_else(|| unreachable!("sampled"));
        let gs = |n: [f32; 3], a: usize| -f64::from(n[a] / n[2]);
        let (a, b) = (slope(&sea[0], x, y), slope(&sea[2], x, y));
        for (footprint, wa, wb, mss) in [(0.1f32, 1.0, 1.0, 0.0), (0.5, 1.0, 0.0, m3), (1.0, 0.0, 0.0, m1 + m3)] {
            let sh = s.shading(x as f32, y as f32, footprint).unwrap_or_else(|| unreachable!("sampled"));
            for ax in 0..2 {
                let want = gs(n0.normal, ax) + wa * a[ax] + wb * b[ax];
                assert!((gs(sh.normal, ax) - want).abs() < 2e-3, "footprint {footprint} axis {ax}");
            }
            assert!((f64::from(sh.unresolved_mss) - mss).abs() < 1e-7, "footprint {footprint}: {}", sh.unresolved_mss);
        }
    }

    /// Brute force: march the ray in tiny steps against [`WaveSurface::height`] (the same triangulated surface,
    /// read point by point) and bisect the first sign change.
    fn brute(s: &WaveSurface, o: [f32; 3], d: [f32; 3], t_max: f32, step: f32) -> Option<f32> {
        let f = |t: f32| o[2] + d[2] * t - s.height(o[0] + d[0] * t, o[1] + d[1] * t);
        let mut t = 0.0;
        let mut fa = f(0.0);
        while t < t_max {
            let tb = (t + step).min(t_max);
            let fb = f(tb);
            if (fa > 0.0) != (fb > 0.0) {
                let (mut lo, mut hi) = (t, tb);
                for _ in 0..40 {
                    let m = 0.5 * (lo + hi);
                    if (f(m) > 0.0) == (fa > 0.0) {
                        lo = m
                    } else {
                        hi = m
                    }
                }
                return Some(0.5 * (lo + hi));
            }
            t = tb;
            fa = fb;
        }
        None
    }

    /// The tiles of a real wave field against the field's own row-recurrence grid over each tile.
    #[test]
    fn field_tiles_match_the_fields_own_grids() {
        use crate::ocean::{SeaSpec, WaveField};
        let spec = SeaSpec { hs: 3.5, tp: 9.0, gamma: 3.3, direction_rad: 0.7, spread_s: 8.0 };
        let f = WaveField::new(&spec, 77).unwrap_or_else(|e| unreachable!("{e}"));
        let foci = [[-1234.5f32, 877.25]];
        let spec = SurfaceSpec { radius_m: 500.0, taper_m: 0.0, ..SurfaceSpec::default() };
        let s = WaveSurface::new(f.components(), 41.3, 0.0, &foci, spec);
        let mut levels = [0usize; 6];
        for (k, tile) in s.tiles.iter().enumerate() {
            if tile.n == 0 {
                continue;
            }
            levels[(TILE_CELLS / tile.n).trailing_zeros() as usize] += 1;
            let (ix, iy) = (k % s.ntx, k / s.ntx);
            let (x0, y0) = (f64::from(s.x0 + ix as f32 * s.tile_m), f64::from(s.y0 + iy as f32 * s.tile_m));
            let w = tile.n + 1;
            let dx = f64::from(s.tile_m) / tile.n as f64;
            let (h, gx, gy) = f.elevation_slope_grid(x0, y0, dx, w, w, 41.3).unwrap_or_else(|e| unreachable!("{e}"));
            for q in 0..w * w {
                let (xq, yq) = (x0 + (q % w) as f64 * dx, y0 + (q / w) as f64 * dx);
                if nearest(&foci, xq as f32, yq as f32) >= spec.radius_m {
                    continue; // still water beyond the radius
                }
                assert!((tile.h[q] - h[q]).abs() < 1e-4, "tile {k} node {q}: {} vs {}", tile.h[q], h[q]);
                // The tile's slopes leave out the waves its cells cannot resolve: add theirs back, point by point.
                let (mut ux, mut uy) = (0.0f64, 0.0f64);
                for w in f.components().iter().filter(|w| !resolved(w.k_rad_m, dx as f32)) {
                    let sn = w.phase_at(xq, yq, 41.3).sin();
                    ux -= w.amplitude_m * w.kx * sn;
                    uy -= w.amplitude_m * w.ky * sn;
                }
                let (ax, ay) = (f64::from(tile.g[q][0]) + ux, f64::from(tile.g[q][1]) + uy);
                assert!((ax - f64::from(gx[q])).abs() < 2e-4 && (ay - f64::from(gy[q])).abs() < 2e-4, "tile {k} {q}");
            }
        }
        assert!(levels[..5].iter().all(|&c| c > 0), "every level sampled: {levels:?}");
    }

    #[test]
    fn intersect_matches_a_dense_march_of_the_surface() {
        let c = test_sea();
        let spec = SurfaceSpec { radius_m: 300.0, taper_m: 60.0, ..SurfaceSpec::default() };
        let s = surface(&c, 3.0, &[[0.0, 0.0], [90.0, 40.0]], spec);
        let mut state = 11u64;
        let mut rand = |lo: f32, hi: f32| {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            lo + (hi - lo) * ((state >> 40) as f32 / (1u64 << 24) as f32)
        };
        let (mut hits, mut grazing, mut agree) = (0, 0, 0);
        let n = 1500;
        for i in 0..n {
            let o = [rand(-60.0, 60.0), rand(-60.0, 60.0), rand(1.0, 6.0)];
            // Mostly grazing rays (crests occlude), some steep, some up.
            let el = if i % 10 == 0 { rand(0.0, 0.3) } else { -rand(0.002, if i % 3 == 0 { 1.2 } else { 0.08 }) };
            let az = rand(0.0, std::f32::consts::TAU);
            let d = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
            let t_max = 400.0;
            let fast = s.intersect(o, d, t_max).map(|h| h.t);
            let slow = brute(&s, o, d, t_max, 0.01);
            match (fast, slow) {
                (Some(a), Some(b)) => {
                    assert!((a - b).abs() < 0.02 + 1e-4 * b, "ray {i}: {a} vs brute {b} ({o:?} {d:?})");
                    hits += 1;
                    grazing += usize::from(d[2] > -0.08);
                    agree += 1;
                }
                (None, None) => agree += 1,
                // A crossing thinner than the brute force's step can be missed by it, never by the march.
                (Some(a), None) => {
                    let h = s.height(o[0] + d[0] * a, o[1] + d[1] * a);
                    assert!((o[2] + d[2] * a - h).abs() < 1e-3, "ray {i}: a hit at {a} off the surface");
                }
                (None, Some(b)) => panic!("ray {i}: brute force hits at {b}, the march misses ({o:?} {d:?})"),
            }
        }
        assert!(agree > n * 99 / 100, "{agree} of {n} agree");
        assert!(hits > 1000 && grazing > 500, "{hits} hits, {grazing} grazing");
    }

    #[test]
    fn crests_hide_what_lies_behind_them() {
        // One long-crested swell along x, 1 m amplitude, 60 m long (crests at x = 0, 60, 120 m): from 1.2 m
        // above the still level looking along x at a point 0.3 m above it 150 m away, the crest at 60 m hides it.
        let k = std::f64::consts::TAU / 60.0;
        let s = surface(&[comp(1.0, k, 0.0, 0.0, 0.0)], 0.0, &[[0.0, 0.0]], SurfaceSpec::default());
        let o = [0.0, 0.0, 1.2];
        let target = [150.0f32, 0.0, 0.3];
        let dv = [target[0] - o[0], target[1] - o[1], target[2] - o[2]];
        let len = (dv[0] * dv[0] + dv[2] * dv[2]).sqrt();
        let d = [dv[0] / len, 0.0, dv[2] / len];
        let Some(h) = s.intersect(o, d, len) else { panic!("the crest at x = 60 m hides the target") };
        let x = o[0] + d[0] * h.t;
        assert!((45.0..=60.0).contains(&x), "hit at x = {x}");
        // A ray above every crest meets nothing, whatever its length.
        assert!(s.intersect([0.0, 0.0, 1.2], [1.0, 0.0, 0.0], 1e6).is_none());
        // The flat beyond the radius: a ray down far away meets the still level.
        let Some(far) = s.intersect([5000.0, 0.0, 10.0], [0.0, 0.0, -1.0], 100.0) else { panic!("still water") };
        assert!((far.t - 10.0).abs() < 1e-4 && far.piece == FLAT_PIECE);
    }

    #[test]
    fn normals_face_up_and_follow_the_slope() {
        let k = std::f64::consts::TAU / 40.0;
        let s = surface(&[comp(0.8, k, 0.0, 0.0, 0.0)], 0.0, &[[0.0, 0.0]], SurfaceSpec::default());
        // At x = 10 m (a quarter wave) the slope is −a k: the normal leans towards +x.
        let n = s.shading_normal(10.0, 3.0).unwrap_or_default();
        let want = (0.8 * k) as f32;
        assert!((n[0] / n[2] - want).abs() < 1e-3, "{n:?}");
        let Some(h) = s.intersect([10.0, 3.0, 5.0], [0.0, 0.0, -1.0], 10.0) else { panic!("a ray straight down") };
        let g = s.piece_normal(h.piece);
        assert!(g[2] > 0.0 && (g[0] / g[2] - want).abs() < 0.01, "{g:?}");
    }
}
