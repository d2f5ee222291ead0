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

/// The least half-height of the band `[zmin, zmax]` the march walks, metres: a flat or micrometre sea's band is
/// widened to it, so that a ray's height above the water, rounded at its range, still changes sign inside it.
pub const MIN_BAND_HALF_M: f32 = 0.01;
/// Crest columns given to a [`crate::sea::Horizon`] ([`WaveSurface::add_crests`]) stand this much (metres) above
/// the highest node under them: far more than the rounding of the surface's planes.
const CREST_MARGIN_M: f64 = 1e-3;
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
    /// grid of a quarter of their cell, in two bands (`DETAIL_BANDS`), for shading only: cameras near the foci
    /// see waves down to one cell long as normals rather than roughness. The geometry, and so every hit, is the same either way; the
    /// sampling costs more (the scene sets it only when cameras render).
    pub detail: bool,
    /// Whether the tiles carry the slopes the cameras shade with ([`WaveSurface::shading`], which answers `None`
    /// without them; `detail` needs them too). The geometry, and so every hit, is the same either way; the
    /// sampling costs less without (the scene leaves them out when nothing renders).
    pub slopes: bool,
    /// With [`SurfaceSpec::detail`]: tiles coarser than the finest level whose nearest point lies within this
    /// distance of a focus also carry, on a grid of the finest cell, the slopes of the waves that cell resolves
    /// and theirs does not, drawn where a pixel's footprint resolves them (0: none). An orthographic top view sees
    /// the water with one footprint everywhere: without them its shading would change texture at every level's
    /// edge (the finest tiles drawing 4–8 m waves as normals, the next as roughness), concentric squares around
    /// its USV. The geometry is the same either way (the scene sets it to its top views' reach).
    pub fine_m: f32,
}

impl Default for SurfaceSpec {
    /// 1 m cells within ~40 m, 2 m to ~80 m, 4 m to ~160 m, 8 m to ~320 m, waves out to 320 m around every
    /// focus (tapered over the last 60 m).
    fn default() -> Self {
        Self { tile_m: 32.0, near_m: 40.0, radius_m: 320.0, taper_m: 60.0, detail: false, slopes: true, fine_m: 0.0 }
    }
}

/// Most tiles one surface may hold: 2²² (a square of about 65 km a side at the default 32 m tiles, beyond any
/// map). [`WaveSurface::new`] samples the rectangle around every focus as one grid, so foci far apart or a huge
/// radius would ask for more memory than a machine has; [`SurfaceSpec::check_extent`] refuses them first.
pub const MAX_TILES: u64 = 1 << 22;

/// The largest frame time a wave surface is sampled at, seconds either side of 0 (about 32 years): the waves'
/// phases `ω t` keep a precision of microradians up to it, and at 1e308 s they were NaN, a sea every ray passed
/// through.
pub const MAX_TIME_S: f64 = 1e9;

/// `time_s` checked for [`WaveSurface::new`]: finite and within ±[`MAX_TIME_S`], else an error naming `time_s`.
pub fn check_time(time_s: f64) -> crate::Result<()> {
    if time_s.abs() <= MAX_TIME_S {
        return Ok(());
    }
    Err(crate::MmusvError::input(
        "time_s",
        format!("{time_s} s is not allowed; give a frame time within ±{MAX_TIME_S:e} s (about 32 years)"),
    ))
}

impl SurfaceSpec {
    /// How many tiles [`WaveSurface::new`] samples for `foci` (world x, y, metres): the foci's bounding rectangle
    /// grown by `radius_m`, in tiles of `tile_m` (0 without foci). Counted in `f64` and saturated, never
    /// overflowing.
    pub fn tiles_for(&self, foci: &[[f32; 2]]) -> u64 {
        let tile_m = f64::from(self.tile_m.max(1e-3));
        let reach = f64::from(self.radius_m.max(0.0));
        if foci.is_empty() || reach == 0.0 {
            return 0;
        }
        let side = |a: usize| {
            let lo = foci.iter().map(|f| f64::from(f[a])).fold(f64::INFINITY, f64::min) - reach;
            let hi = foci.iter().map(|f| f64::from(f[a])).fold(f64::NEG_INFINITY, f64::max) + reach;
            let x0 = (lo / tile_m).floor() * tile_m;
            ((hi - x0) / tile_m).ceil()
        };
        let n = side(0) * side(1);
        if n.is_finite() && n < 1.8e19 {
            n as u64
        } else {
            u64::MAX
        }
    }

    /// Refuses foci and a radius whose surface would hold more than [`MAX_TILES`] tiles (an input error naming
    /// `foci`, the count and the limit).
    pub fn check_extent(&self, foci: &[[f32; 2]]) -> crate::Result<()> {
        let n = self.tiles_for(foci);
        if n > MAX_TILES {
            return Err(crate::MmusvError::input(
                "foci",
                format!(
                    "the wave surface around these foci out to radius_m = {} m would hold {n} tiles of {} m, more \
                     than the {MAX_TILES} one surface may (a square of about 65 km); bring the foci closer together \
                     or lower radius_m",
                    self.radius_m, self.tile_m
                ),
            ));
        }
        Ok(())
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
    /// `(n+1)²` slopes `(∂η/∂x, ∂η/∂y)` of the components the cell resolves ([`resolved`]); empty without
    /// [`SurfaceSpec::slopes`].
    g: Vec<[f32; 2]>,
    /// Mean square slope `Σ a²k²/2` (both axes) of the components its slopes leave out (the detail bands'
    /// apart), tapered as the waves are.
    mss: f32,
    /// With [`SurfaceSpec::detail`], on a finest-level tile: at each of the `(DETAIL_CELLS + 1)²` nodes of the
    /// detail grid, the slopes `(∂η/∂x, ∂η/∂y)` of band 0's waves then band 1's ([`DETAIL_BANDS`]; a band
    /// without waves holds zeros and is not read), together so one lookup serves both; empty otherwise.
    detail: Vec<[f32; 4]>,
    /// Which detail bands hold waves.
    bands: [bool; 2],
    /// The mean square slopes of the two detail bands' waves.
    band_mss: [f32; 2],
    /// With [`SurfaceSpec::fine_m`], on a coarser tile near a focus: the slopes `(∂η/∂x, ∂η/∂y)` of the waves the
    /// finest cell resolves and this tile's does not, at the `(TILE_CELLS + 1)²` nodes of the finest grid; empty
    /// otherwise.
    fine: Vec<[f32; 2]>,
    /// The mean square slope of those waves.
    fine_mss: f32,
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
    /// The mean square slope of every wave, the roughness the still water beyond the sampled sea is shaded with
    /// (`None` without waves, or without slopes: [`SurfaceSpec::slopes`]).
    far_mss: Option<f32>,
    /// The elevation's standard deviation `√(Σ a²/2)` of the components sampled, metres.
    elevation_std: f32,
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
    /// Deterministic: the same inputs give the same surface, whatever the thread count. A time past ±[`MAX_TIME_S`]
    /// is an error naming `time_s` ([`check_time`]). Foci and a radius whose
    /// surface would hold more than [`MAX_TILES`] tiles are an error naming `foci` ([`SurfaceSpec::check_extent`]:
    /// far-apart foci asked for more memory than a machine has, or overflowed the tile count).
    pub fn new(
        components: &[WaveComponent],
        time_s: f64,
        level: f32,
        foci: &[[f32; 2]],
        spec: SurfaceSpec,
    ) -> crate::Result<Self> {
        check_time(time_s)?;
        spec.check_extent(foci)?;
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
        // The band is at least ±MIN_BAND_HALF_M about the still level: a calmer sea's (hs_m of micrometres, or
        // no waves) is thinner than a ray's height rounds to at its range, and the march's sign test over it let
        // every ray through. A wider band is still a bound, so no hit of a real sea changes.
        let mut zmin = level - MIN_BAND_HALF_M;
        let mut zmax = level + MIN_BAND_HALF_M;
        for t in &tiles {
            if t.n > 0 {
                zmin = zmin.min(t.zmin);
                zmax = zmax.max(t.zmax);
            }
        }
        let far_mss = (spec.slopes && !components.is_empty()).then(|| sample::total_mss(components) as f32);
        Ok(Self {
            level,
            time_s,
            x0,
            y0,
            tile_m,
            inv_tile_m: 1.0 / tile_m,
            ntx,
            nty,
            tiles,
            zmin,
            zmax,
            far_mss,
            elevation_std: components.iter().map(WaveComponent::elevation_variance).sum::<f64>().sqrt() as f32,
        })
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
    /// The standard deviation of the elevation of the waves sampled, metres: `√(Σ a²/2)`, `H_s / 4` of the sea
    /// they realise (0 without waves).
    #[inline]
    pub fn elevation_std(&self) -> f32 {
        self.elevation_std
    }
    /// Side of the finest cells, metres (`tile_m / TILE_CELLS`).
    pub fn finest_cell_m(&self) -> f32 {
        self.tile_m / TILE_CELLS as f32
    }
    /// Whether every number that places the surface is finite: its level, time, lattice origin, height bounds and
    /// elevation spread. A NaN time, level, focus or component samples a surface no ray meets (the sea would
    /// vanish), which [`crate::Scene::set_wave_surface`] refuses.
    pub(crate) fn is_finite(&self) -> bool {
        self.level.is_finite()
            && self.time_s.is_finite()
            && self.x0.is_finite()
            && self.y0.is_finite()
            && self.zmin.is_finite()
            && self.zmax.is_finite()
            && self.elevation_std.is_finite()
    }

    /// Number of sampled (non-flat) tiles.
    pub fn sampled_tiles(&self) -> usize {
        self.tiles.iter().filter(|t| t.n > 0).count()
    }

    /// Whether world `(x, y)` lies on the sampled part of the surface (a sampled tile; else the still level, where
    /// the sea goes on unsampled).
    #[inline]
    pub fn sampled_at(&self, x: f32, y: f32) -> bool {
        self.tile_at(x, y).is_some_and(|(ix, iy)| self.tiles[iy * self.ntx + ix].n > 0)
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
        self.height_piece(x, y).0
    }

    /// [`WaveSurface::height`] at world `(x, y)` and the piece there ([`FLAT_PIECE`] over still water), as a
    /// [`SurfaceHit::piece`].
    #[inline(always)]
    fn height_piece(&self, x: f32, y: f32) -> (f32, u32) {
        let Some((ix, iy)) = self.tile_at(x, y) else { return (self.level, FLAT_PIECE) };
        let k = iy * self.ntx + ix;
        let t = &self.tiles[k];
        if t.n == 0 {
            return (self.level, FLAT_PIECE);
        }
        let ([ci, cj], [fu, fv]) = self.cell_at(t.n, ix, iy, x, y);
        let (plane, _) = cell_planes(t, ci, cj);
        let tri = usize::from(fu < fv);
        let p = plane[tri];
        (p[0] + p[1] * fu + p[2] * fv, cell_piece(k, t.n, ci, cj, tri))
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
        self.leaves_over(o, d, |x, y| self.height(x, y))
    }

    /// [`WaveSurface::leaves`] with the surface's height under the origin from `height(x, y)` (called only
    /// when needed; a caller with many rays from one point keeps it).
    #[inline(always)]
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(a > b)` on purpose: a NaN must answer "no"
    pub fn leaves_over(&self, o: [f32; 3], d: [f32; 3], mut height: impl FnMut(f32, f32) -> f32) -> bool {
        if !(d[2] > 0.0) || o[2] > self.zmax + SKIN_M || o[2] < self.zmin {
            return false;
        }
        let h = height(o[0], o[1]);
        o[2] >= h && o[2] <= h + SKIN_M
    }

    /// Adds the crests to `horizon` as columns (see [`crate::sea::Horizon`]): every sampled tile rising to its
    /// viewpoint's height or above, as one column up to its highest node, and, for the tiles within a tile of the
    /// viewpoint, each such cell as its own column up to its highest corner (so the water just round a sensor
    /// among the waves hides only the directions its crests stand in; a cell under the viewpoint rising above it
    /// covers the horizon). A ray the horizon then clears crosses no wave.
    pub(crate) fn add_crests(&self, horizon: &mut crate::sea::Horizon) {
        let o = horizon.origin();
        let pz = f64::from(o[2]);
        let (ox, oy) = (f64::from(o[0]), f64::from(o[1]));
        let tm = f64::from(self.tile_m);
        for (k, t) in self.tiles.iter().enumerate() {
            if t.n == 0 || f64::from(t.zmax) + CREST_MARGIN_M < pz {
                continue;
            }
            let lo = [f64::from(self.x0) + (k % self.ntx) as f64 * tm, f64::from(self.y0) + (k / self.ntx) as f64 * tm];
            let hi = [lo[0] + tm, lo[1] + tm];
            let near = (lo[0] - ox).max(ox - hi[0]) < tm && (lo[1] - oy).max(oy - hi[1]) < tm;
            if !near {
                horizon.add_rect(lo, hi, f64::from(t.zmax) + CREST_MARGIN_M);
                continue;
            }
            let cs = tm / t.n as f64;
            for cj in 0..t.n {
                for ci in 0..t.n {
                    let (_, cmax) = cell_planes(t, ci, cj);
                    let top = f64::from(cmax) + CREST_MARGIN_M;
                    if top >= pz {
                        let c = [lo[0] + ci as f64 * cs, lo[1] + cj as f64 * cs];
                        horizon.add_rect(c, [c[0] + cs, c[1] + cs], top);
                    }
                }
            }
        }
    }

    /// Whether the ray `o + t·d` crosses the surface with `0 <= t < t_max`.
    #[inline]
    pub fn occludes(&self, o: [f32; 3], d: [f32; 3], t_max: f32) -> bool {
        self.intersect(o, d, t_max).is_some()
    }
}

/// The piece id ([`SurfaceHit::piece`]) of triangle `tri` (as [`cell_planes`] numbers them) of cell `(ci, cj)` of
/// tile `k` cut into `n` cells a side: what [`WaveSurface::piece_normal`] takes apart.
#[inline(always)]
fn cell_piece(k: usize, n: usize, ci: usize, cj: usize, tri: usize) -> u32 {
    (k * 2 * TILE_CELLS * TILE_CELLS + 2 * (cj * n + ci) + tri) as u32
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
pub(crate) mod tests;
