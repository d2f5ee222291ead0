//! The first hits of a pinhole camera's pixel rays with the triangulated surface, found by rasterising the
//! surface instead of marching every ray through it ([`WaveSurface::first_hits`]).
//!
//! The surface a ray meets ([`super::march`]) is a set of planar pieces: two triangles per cell of every sampled
//! tile, the vertical walls that close the steps between neighbouring tiles (of different detail, or where two
//! tiles' shared nodes differ by rounding), and the still level over flat tiles and outside the tile rectangle.
//! For rays that all leave one point, the first piece along each ray is the nearest piece in that ray's
//! direction: a depth buffer over the image answers it for every pixel at once.
//!
//! Exact at the pixel centres (homogeneous rasterisation, Olano & Greer, "Triangle scan conversion using 2D
//! homogeneous coordinates", Graphics Hardware 1997): a pixel's centre ray `r = (a, b, 1)` (image right, down,
//! forward) meets triangle `v0 v1 v2` (camera-relative) at a positive distance exactly when `r` lies in the cone
//! of the three vertices, i.e. when the three edge functions `Eᵢ = r · (vⱼ × vₖ)` share the sign of
//! `det = v0 · (v1 × v2)`; the forward depth there is `det / ΣEᵢ`. No near-plane clipping enters the test (the
//! clipping only bounds the pixels visited). Neighbouring pieces share their vertices bit for bit (world `x, y`
//! from one global lattice index, heights from the tile's own nodes, the walls built from both sides' nodes), so
//! a shared edge's edge function is the exact negation in the two pieces and no pixel centre slips between them.
//! The exceptions are where a finer tile meets a coarser one (the wall's coarse-side vertices are the coarse
//! edge's heights interpolated at the fine nodes, on the coarse triangles' edges only to rounding) and where the
//! two sides' heights cross within a wall's segment (the crossing point, likewise): hairline gaps of a few
//! units in the last place, which a pixel centre all but never meets.
//!
//! The raster picks the piece; its distance along the camera's own world ray (and so the hit a march would give,
//! to rounding) is then solved on that piece's plane ([`Raster::resolve`]), and the still level is checked
//! analytically. The depth that picks the nearest piece is `r·N / v0·N` from the triangle's normal `N`; a
//! triangle whose plane passes within `10⁻⁴` rad of the camera (seen edge-on) is left out, as its depth there
//! would be rounding noise (the pieces beside it meet those rays at the same distance). A pixel the plane solve
//! cannot settle (a ray in the piece's plane, or a hit off the piece) is left to the march.

use super::{cell_piece, cell_planes, SurfaceHit, WaveSurface, FLAT_PIECE, SKIN_M, TILE_CELLS};
use rayon::prelude::*;

/// A pinhole view for [`WaveSurface::first_hits`]: the camera's origin and axes in the world, its image and
/// focal length. Pixel `(u, v)`'s centre ray is `forward + a·right + b·down` with `a = (u + ½ − W/2) / f`,
/// `b = (v + ½ − H/2) / f`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PinholeView {
    /// World position of the projection centre, metres.
    pub origin: [f32; 3],
    /// World unit vector of the optical axis.
    pub forward: [f32; 3],
    /// World unit vector of the image's right (`u` growing).
    pub right: [f32; 3],
    /// World unit vector of the image's down (`v` growing).
    pub down: [f32; 3],
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Focal length, pixels (`fx = fy`; the principal point at the image centre).
    pub focal: f64,
}

/// What [`Raster::resolve`] knows of one ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WaterHit {
    /// The ray's first crossing with the surface (below its range).
    Hit(SurfaceHit),
    /// The ray meets the surface nowhere below its range.
    Miss,
    /// Not settled by the raster: march the ray ([`WaveSurface::intersect`]).
    Unknown,
}

/// Where a rasterised piece comes from, for solving a ray against it.
#[derive(Debug, Clone, Copy)]
enum Piece {
    /// A cell's triangle: its plane `[h0, ∂h/∂fu, ∂h/∂fv]` over the cell's local `(fu, fv)` (as
    /// [`cell_planes`]), where `fu = (x − x0) · inv_cs` and `fv = (y − y0) · inv_cs` from the cell's lower
    /// corner `(x0, y0)` (given as the tile's corner and the cell's column and row), and the piece id.
    Cell { corner: [f32; 2], cell: [f32; 2], inv_cs: f32, plane: [f32; 3], id: u32 },
    /// The wall at world coordinate `at` along `axis` (0: x, 1: y) between the tiles on its low and high sides
    /// (`u32::MAX`: outside the rectangle, still water).
    Wall { axis: u8, at: f32, lo: u32, hi: u32 },
}

/// One rasterised triangle: its sign-normalised edge functions, inverse depth and pixel bounds.
#[derive(Debug, Clone, Copy)]
struct Tri {
    /// Edge function coefficients `[ea, eb, ec]`: `E = ea·a + eb·b + ec`, all `>= 0` inside.
    e: [[f32; 3]; 3],
    /// Inverse forward depth `1/s = ia·a + ib·b + ic`.
    inv: [f32; 3],
    /// Pixel bounds, inclusive: `[u0, u1, v0, v1]`.
    bounds: [u32; 4],
    piece: u32,
}

/// The pieces of one tile in view and their triangles (`Tri::piece` indexes `pieces`).
#[derive(Default)]
struct Pieces {
    pieces: Vec<Piece>,
    tris: Vec<Tri>,
}

impl Pieces {
    /// Adds triangle `v` (camera space; `ab` its vertices' projections where known, see [`Frame::setup`]) of
    /// `piece`, unless it covers no pixel centre.
    fn push(&mut self, frame: &Frame<'_>, piece: Piece, v: [[f32; 3]; 3], ab: Option<[[f32; 2]; 3]>) {
        if let Some(tri) = frame.setup(v, ab, self.pieces.len() as u32) {
            self.tris.push(tri);
            self.pieces.push(piece);
        }
    }
}

/// A depth buffer of the surface's pieces over one pinhole image (see the module docs).
pub struct Raster<'a> {
    surface: &'a WaveSurface,
    pieces: Vec<Piece>,
    /// Per pixel (row-major), the nearest piece's index, or `u32::MAX`.
    first: Vec<u32>,
}

/// How far (in cells) outside its piece a resolved hit may fall before the march is asked instead.
const ON_PIECE: f32 = 1e-3;
/// Pixels along a band of rows that one task rasterises.
const BAND_ROWS: usize = 32;
/// Sine of the angle under which a triangle's plane passes the camera below which it counts as seen edge-on.
const EDGE_ON: f32 = 1e-4;
/// Pixels by which a triangle's projected bounds are widened before taking the pixel centres inside them.
const BOUNDS_SLACK: f32 = 0.01;
/// The near plane that bounds the pixels a triangle crossing the camera's plane can cover, metres.
const NEAR_M: f32 = 1e-3;

impl WaveSurface {
    /// Rasterises the surface into `view`'s image (see the module docs): `None` when the view's origin does not
    /// stand clear above the surface (within [`SKIN_M`] of it, rays rising from the water leave it: the march
    /// must decide), or the image is empty.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // a NaN height must answer "not clear"
    pub fn first_hits(&self, view: &PinholeView) -> Option<Raster<'_>> {
        let o = view.origin;
        if !(o[2] > self.height(o[0], o[1]) + SKIN_M) || view.width == 0 || view.height == 0 {
            return None;
        }
        let (w, h) = (view.width as usize, view.height as usize);
        let f = view.focal;
        let a: Vec<f32> = (0..w).map(|u| ((u as f64 + 0.5 - w as f64 / 2.0) / f) as f32).collect();
        let b: Vec<f32> = (0..h).map(|v| ((v as f64 + 0.5 - h as f64 / 2.0) / f) as f32).collect();
        let cam = Frame::new(self, view);
        // Pieces and triangles, tile by tile (in parallel, joined in tile order: the same for any thread count).
        let per_tile: Vec<Pieces> = (0..self.tiles.len()).into_par_iter().map(|k| cam.tile_pieces(k)).collect();
        let mut pieces = Vec::new();
        let mut tris = Vec::new();
        for mut p in per_tile {
            let offset = pieces.len() as u32;
            tris.extend(p.tris.iter().map(|t| Tri { piece: t.piece + offset, ..*t }));
            pieces.append(&mut p.pieces);
        }
        // Pixel u's centre is at a = (u + ½ − W/2) / f: u = a·f + W/2 − ½.
        let (fx, cx) = (f as f32, w as f32 / 2.0 - 0.5);
        let mut first = vec![u32::MAX; w * h];
        first.par_chunks_mut(BAND_ROWS * w).enumerate().for_each(|(band, out)| {
            let v0 = band * BAND_ROWS;
            let rows = out.len() / w;
            let mut depth = vec![0f32; out.len()];
            for t in &tris {
                let [u_lo, u_hi, t_lo, t_hi] = t.bounds.map(|x| x as usize);
                if t_lo >= v0 + rows || t_hi < v0 {
                    continue;
                }
                for v in t_lo.max(v0)..=t_hi.min(v0 + rows - 1) {
                    let bv = b[v];
                    let row = [0, 1, 2].map(|i| t.e[i][1] * bv + t.e[i][2]);
                    // The row's span where every edge function can be >= 0 (a pixel of margin each side; the
                    // exact test below decides).
                    let (mut a_lo, mut a_hi) = (f32::NEG_INFINITY, f32::INFINITY);
                    for i in 0..3 {
                        let ea = t.e[i][0];
                        if ea > 0.0 {
                            a_lo = a_lo.max(-row[i] / ea);
                        } else if ea < 0.0 {
                            a_hi = a_hi.min(-row[i] / ea);
                        } else if row[i] < 0.0 {
                            a_hi = f32::NEG_INFINITY;
                        }
                    }
                    if a_lo.partial_cmp(&a_hi).is_none_or(|o| o.is_gt()) {
                        continue;
                    }
                    let (p_lo, p_hi) = (a_lo * fx + cx - 1.0, a_hi * fx + cx + 1.0);
                    let u_lo = if p_lo > u_lo as f32 { p_lo as usize } else { u_lo };
                    let u_hi = if p_hi < u_hi as f32 { (p_hi as usize).max(u_lo) } else { u_hi };
                    let irow = t.inv[1] * bv + t.inv[2];
                    let base = (v - v0) * w;
                    for u in u_lo..=u_hi {
                        let au = a[u];
                        let e0 = t.e[0][0] * au + row[0];
                        let e1 = t.e[1][0] * au + row[1];
                        let e2 = t.e[2][0] * au + row[2];
                        let inv = t.inv[0] * au + irow;
                        let q = base + u;
                        if e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0 && inv > depth[q] {
                            depth[q] = inv;
                            out[q] = t.piece;
                        }
                    }
                }
            }
        });
        Some(Raster { surface: self, pieces, first })
    }
}

/// A view's camera frame and the tile culling and triangle set-up done in it.
struct Frame<'a> {
    s: &'a WaveSurface,
    view: &'a PinholeView,
    /// Half the image's extent in `a` and `b` (the frustum's slopes), a pixel wider on each side.
    half: [f32; 2],
    /// World `x, y` of the rectangle's lower corner relative to the origin, and the finest cell.
    rel0: [f32; 2],
    fine: f32,
    /// The heights of a flat tile as one cell (the still level).
    still: [f32; 4],
}

impl<'a> Frame<'a> {
    fn new(s: &'a WaveSurface, view: &'a PinholeView) -> Self {
        let f = view.focal;
        let half = [((view.width as f64 / 2.0 + 1.0) / f) as f32, ((view.height as f64 / 2.0 + 1.0) / f) as f32];
        let rel0 = [s.x0 - view.origin[0], s.y0 - view.origin[1]];
        Self { s, view, half, rel0, fine: s.tile_m / TILE_CELLS as f32, still: [s.level; 4] }
    }

    /// Camera coordinates `(right, down, forward)` of the world point at global lattice node `(gx, gy)` (finest
    /// cells from the rectangle's corner) and height `z`.
    #[inline(always)]
    fn node(&self, gx: usize, gy: usize, z: f32) -> [f32; 3] {
        let p = [self.rel0[0] + gx as f32 * self.fine, self.rel0[1] + gy as f32 * self.fine, z - self.view.origin[2]];
        let dot = |a: [f32; 3]| p[0] * a[0] + p[1] * a[1] + p[2] * a[2];
        [dot(self.view.right), dot(self.view.down), dot(self.view.forward)]
    }

    /// Outcode of a camera-space point against the frustum's four sides and the camera plane.
    #[inline(always)]
    fn outcode(&self, c: [f32; 3]) -> u8 {
        let [x, y, z] = c;
        u8::from(x > self.half[0] * z)
            | u8::from(x < -self.half[0] * z) << 1
            | u8::from(y > self.half[1] * z) << 2
            | u8::from(y < -self.half[1] * z) << 3
            | u8::from(z <= 0.0) << 4
    }

    /// Whether the box `[lo, hi]` (world `x, y` in lattice nodes, `z` in metres) lies wholly outside one side.
    fn box_outside(&self, g0: [usize; 2], g1: [usize; 2], z: [f32; 2]) -> bool {
        let mut all = 0x1f;
        for gx in [g0[0], g1[0]] {
            for gy in [g0[1], g1[1]] {
                for &zz in &z {
                    all &= self.outcode(self.node(gx, gy, zz));
                }
            }
        }
        all != 0
    }

    /// The pieces of tile `k` in view: its cells' triangles (sampled tiles) and the walls on its low `x` and low
    /// `y` sides (and on the rectangle's high sides for the last column and row).
    fn tile_pieces(&self, k: usize) -> Pieces {
        let s = self.s;
        let (ix, iy) = (k % s.ntx, k / s.ntx);
        let t = &s.tiles[k];
        let mut out = Pieces::default();
        let g0 = [ix * TILE_CELLS, iy * TILE_CELLS];
        let g1 = [g0[0] + TILE_CELLS, g0[1] + TILE_CELLS];
        if t.n > 0 && !self.box_outside(g0, g1, [t.zmin, t.zmax]) {
            let n = t.n;
            let step = TILE_CELLS / n;
            let w = n + 1;
            let nodes: Vec<[f32; 3]> =
                (0..w * w).map(|q| self.node(g0[0] + (q % w) * step, g0[1] + (q / w) * step, t.h[q])).collect();
            let codes: Vec<u8> = nodes.iter().map(|&c| self.outcode(c)).collect();
            // Each node's projection (shared by its six triangles), NaN before the near plane.
            let ab: Vec<[f32; 2]> =
                nodes.iter().map(|c| if c[2] >= NEAR_M { [c[0] / c[2], c[1] / c[2]] } else { [f32::NAN; 2] }).collect();
            let corner = [s.x0 + ix as f32 * s.tile_m, s.y0 + iy as f32 * s.tile_m];
            let inv_cs = n as f32 * s.inv_tile_m;
            for cj in 0..n {
                for ci in 0..n {
                    let q = [cj * w + ci, cj * w + ci + 1, (cj + 1) * w + ci + 1, (cj + 1) * w + ci];
                    // Triangle 0 (fu >= fv): corners 00, 10, 11; triangle 1: 00, 11, 01 (as `cell_planes`).
                    for (tri, c) in [(0u8, [q[0], q[1], q[2]]), (1, [q[0], q[2], q[3]])] {
                        if codes[c[0]] & codes[c[1]] & codes[c[2]] != 0 {
                            continue;
                        }
                        let plane = cell_planes(t, ci, cj).0[usize::from(tri)];
                        let id = cell_piece(k, n, ci, cj, usize::from(tri));
                        let piece = Piece::Cell { corner, cell: [ci as f32, cj as f32], inv_cs, plane, id };
                        let proj = c.map(|i| ab[i]);
                        let known = proj.iter().all(|p| !p[0].is_nan());
                        out.push(self, piece, c.map(|i| nodes[i]), known.then_some(proj));
                    }
                }
            }
        }
        for axis in 0..2 {
            self.walls(ix, iy, axis, &mut out);
            let last = if axis == 0 { ix + 1 == s.ntx } else { iy + 1 == s.nty };
            if last {
                let (jx, jy) = if axis == 0 { (ix + 1, iy) } else { (ix, iy + 1) };
                self.walls(jx, jy, axis, &mut out);
            }
        }
        out
    }

    /// The tile at `(ix, iy)` as `(index, cells a side, heights, lowest and highest node)`: flat (one cell at
    /// the still level) for a flat tile, and outside the rectangle (index `u32::MAX`).
    fn side(&self, ix: isize, iy: isize) -> (u32, usize, &[f32], [f32; 2]) {
        let s = self.s;
        let flat = [s.level; 2];
        if ix >= 0 && iy >= 0 && (ix as usize) < s.ntx && (iy as usize) < s.nty {
            let k = iy as usize * s.ntx + ix as usize;
            let t = &s.tiles[k];
            if t.n > 0 {
                return (k as u32, t.n, &t.h, [t.zmin, t.zmax]);
            }
            return (k as u32, 1, &self.still, flat);
        }
        (u32::MAX, 1, &self.still, flat)
    }

    /// The walls on the low side along `axis` of the tile slot `(ix, iy)` (which may lie one past the
    /// rectangle), against its neighbour there: per finest segment of the shared edge, the vertical strip between
    /// the two sides' heights (two triangles, or two meeting where the heights cross).
    fn walls(&self, ix: usize, iy: usize, axis: usize, out: &mut Pieces) {
        let (hi_x, hi_y) = (ix as isize, iy as isize);
        let (lo_x, lo_y) = if axis == 0 { (hi_x - 1, hi_y) } else { (hi_x, hi_y - 1) };
        let (klo, nlo, hlo, zl) = self.side(lo_x, lo_y);
        let (khi, nhi, hhi, zh) = self.side(hi_x, hi_y);
        if klo == u32::MAX && khi == u32::MAX || zl == [self.s.level; 2] && zh == zl {
            return; // still water on both sides
        }
        let g = [ix * TILE_CELLS, iy * TILE_CELLS];
        let g_end = if axis == 0 { [g[0], g[1] + TILE_CELLS] } else { [g[0] + TILE_CELLS, g[1]] };
        if self.box_outside(g, g_end, [zl[0].min(zh[0]), zl[1].max(zh[1])]) {
            return;
        }
        let m = nlo.max(nhi);
        // Heights along the edge at its m + 1 nodes: the low side's last column (row), the high side's first.
        let edge = |n: usize, h: &[f32], last: bool, j: usize| -> f32 {
            let w = n + 1;
            let at = |i: usize| {
                let (ci, cj) = if axis == 0 { (if last { n } else { 0 }, i) } else { (i, if last { n } else { 0 }) };
                h[cj * w + ci]
            };
            let r = m / n;
            let (i, fr) = (j / r, j % r);
            if fr == 0 {
                at(i)
            } else {
                let (p, q) = (at(i), at(i + 1));
                p + (q - p) * (fr as f32 / r as f32)
            }
        };
        let lo_h: Vec<f32> = (0..=m).map(|j| edge(nlo, hlo, true, j)).collect();
        let hi_h: Vec<f32> = (0..=m).map(|j| edge(nhi, hhi, false, j)).collect();
        if lo_h == hi_h {
            return;
        }
        let step = TILE_CELLS / m;
        let at = if axis == 0 { self.s.x0 + ix as f32 * self.s.tile_m } else { self.s.y0 + iy as f32 * self.s.tile_m };
        let piece = Piece::Wall { axis: axis as u8, at, lo: klo, hi: khi };
        let node = |j: usize, z: f32| {
            let gj = j * step;
            if axis == 0 {
                self.node(g[0], g[1] + gj, z)
            } else {
                self.node(g[0] + gj, g[1], z)
            }
        };
        for j in 0..m {
            let (a0, a1, b0, b1) = (lo_h[j], lo_h[j + 1], hi_h[j], hi_h[j + 1]);
            let (d0, d1) = (a0 - b0, a1 - b1);
            if d0 == 0.0 && d1 == 0.0 {
                continue;
            }
            let (pa0, pa1, pb0, pb1) = (node(j, a0), node(j + 1, a1), node(j, b0), node(j + 1, b1));
            if (d0 > 0.0 && d1 < 0.0) || (d0 < 0.0 && d1 > 0.0) {
                // The two sides cross inside the segment: two triangles meeting there.
                let f = d0 / (d0 - d1);
                let c = [0, 1, 2].map(|i| pa0[i] + (pa1[i] - pa0[i]) * f);
                out.push(self, piece, [pa0, pb0, c], None);
                out.push(self, piece, [pa1, pb1, c], None);
            } else {
                out.push(self, piece, [pa0, pa1, pb1], None);
                out.push(self, piece, [pa0, pb1, pb0], None);
            }
        }
    }

    /// The rasterised form of triangle `v` (camera space), or `None` when it covers no pixel centre for sure
    /// (behind the camera, outside the image, or seen edge-on). `ab`, when given, holds the vertices'
    /// projections `(x/z, y/z)`, all in front of the near plane.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // a NaN depth must leave the triangle out
    fn setup(&self, v: [[f32; 3]; 3], ab: Option<[[f32; 2]; 3]>, piece: u32) -> Option<Tri> {
        let cross = |p: [f32; 3], q: [f32; 3]| {
            [p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]]
        };
        let mut e = [cross(v[1], v[2]), cross(v[2], v[0]), cross(v[0], v[1])];
        // The depth from the normal `N = (v1 − v0) × (v2 − v0)` (= e0 + e1 + e2, without the cancellation of
        // summing three large cross products): `1/z = r·N / v0·N`.
        let sub = |p: [f32; 3], q: [f32; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
        let n = cross(sub(v[1], v[0]), sub(v[2], v[0]));
        let det = v[0][0] * n[0] + v[0][1] * n[1] + v[0][2] * n[2];
        let scale = (v[0][0] * v[0][0] + v[0][1] * v[0][1] + v[0][2] * v[0][2]).sqrt()
            * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        // Seen (almost) edge-on, its plane through the camera: it covers no pixel centre but by rounding, where
        // its depth would be noise (the pieces beside it are met at the same distance).
        if !(det.abs() > EDGE_ON * scale) {
            return None;
        }
        if det < 0.0 {
            for ei in &mut e {
                *ei = ei.map(|x| -x);
            }
        }
        let inv = n.map(|x| x / det);
        // Pixel bounds from the part of the triangle in front of the near plane.
        let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
        let mut add = |x: [f32; 2]| {
            for i in 0..2 {
                lo[i] = lo[i].min(x[i]);
                hi[i] = hi[i].max(x[i]);
            }
        };
        if let Some(ab) = ab {
            ab.into_iter().for_each(&mut add);
        } else {
            for i in 0..3 {
                let (p, q) = (v[i], v[(i + 1) % 3]);
                if p[2] >= NEAR_M {
                    add([p[0] / p[2], p[1] / p[2]]);
                }
                if (p[2] >= NEAR_M) != (q[2] >= NEAR_M) {
                    let f = (NEAR_M - p[2]) / (q[2] - p[2]);
                    add([(p[0] + (q[0] - p[0]) * f) / NEAR_M, (p[1] + (q[1] - p[1]) * f) / NEAR_M]);
                }
            }
        }
        if lo[0].partial_cmp(&hi[0]).is_none_or(|o| o.is_gt()) {
            return None;
        }
        let f = self.view.focal as f32;
        let (w, h) = (self.view.width as f32, self.view.height as f32);
        // Pixel u's centre is at a = (u + ½ − W/2) / f: u = a·f + W/2 − ½. The pixel centres within the bounds,
        // widened by a hundredth of a pixel (far more than the projection's rounding): a triangle between two
        // pixel centres covers none.
        let px = |a: f32, size: f32| a * f + size / 2.0 - 0.5;
        let (u0, u1) = ((px(lo[0], w) - BOUNDS_SLACK).ceil(), (px(hi[0], w) + BOUNDS_SLACK).floor());
        let (v0, v1) = ((px(lo[1], h) - BOUNDS_SLACK).ceil(), (px(hi[1], h) + BOUNDS_SLACK).floor());
        if u1 < u0 || v1 < v0 || u1 < 0.0 || v1 < 0.0 || u0 > w - 1.0 || v0 > h - 1.0 {
            return None;
        }
        let clamp = |x: f32, size: f32| x.clamp(0.0, size - 1.0) as u32;
        Some(Tri { e, inv, bounds: [clamp(u0, w), clamp(u1, w), clamp(v0, h), clamp(v1, h)], piece })
    }
}

impl Raster<'_> {
    /// The first hit of the ray `o + t·d` (`d` unit, `0 <= t < t_max`) through the centre of pixel `pixel`
    /// (row-major) of the rasterised view, `o` its origin: solved on the piece the raster found there, or on the
    /// still level where the ray meets it over still water first.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // a NaN must send the ray to the march
    pub fn resolve(&self, pixel: usize, o: [f32; 3], d: [f32; 3], t_max: f32) -> WaterHit {
        let s = self.surface;
        let mut best: Option<SurfaceHit> = None;
        if let Some(&p) = self.first.get(pixel).filter(|&&p| p != u32::MAX) {
            let hit = match self.pieces[p as usize] {
                Piece::Cell { corner, cell, inv_cs, plane: q, id } => {
                    // The ray's height above the piece's plane, f0 + f1·t (as the march's `f_at`).
                    let fu0 = (o[0] - corner[0]) * inv_cs - cell[0];
                    let fv0 = (o[1] - corner[1]) * inv_cs - cell[1];
                    let f0 = o[2] - (q[0] + q[1] * fu0 + q[2] * fv0);
                    let (du, dv) = (d[0] * inv_cs, d[1] * inv_cs);
                    let f1 = d[2] - (q[1] * du + q[2] * dv);
                    let t = -f0 / f1;
                    // The hit must lie on the piece (to a thousandth of a cell): else the raster was misled
                    // (rounding at a silhouette) and the march decides.
                    let (fu, fv) = (fu0 + du * t, fv0 + dv * t);
                    let side = if id % 2 == 0 { fu - fv } else { fv - fu };
                    if !(fu > -ON_PIECE
                        && fu < 1.0 + ON_PIECE
                        && fv > -ON_PIECE
                        && fv < 1.0 + ON_PIECE
                        && side > -ON_PIECE)
                    {
                        return WaterHit::Unknown;
                    }
                    (t, id)
                }
                Piece::Wall { axis, at, lo, hi } => {
                    let a = axis as usize;
                    let t = (at - o[a]) / d[a];
                    let entered = if d[a] > 0.0 { hi } else { lo };
                    (t, s.piece_at(entered, o[0] + d[0] * t, o[1] + d[1] * t))
                }
            };
            if !(hit.0.is_finite() && hit.0 >= 0.0) {
                return WaterHit::Unknown;
            }
            best = Some(SurfaceHit { t: hit.0, piece: hit.1 });
        }
        // The still level, where the ray crosses it over a flat tile or outside the rectangle.
        if d[2] != 0.0 {
            let t = (s.level - o[2]) / d[2];
            if t >= 0.0 && best.is_none_or(|b| t < b.t) {
                let (x, y) = (o[0] + d[0] * t, o[1] + d[1] * t);
                let still = s.tile_at(x, y).is_none_or(|(ix, iy)| s.tiles[iy * s.ntx + ix].n == 0);
                if still {
                    best = Some(SurfaceHit { t, piece: FLAT_PIECE });
                }
            }
        }
        match best {
            Some(h) if h.t < t_max => WaterHit::Hit(h),
            _ => WaterHit::Miss,
        }
    }
}

impl WaveSurface {
    /// The piece of tile `k` (`u32::MAX`: outside the rectangle) under world `(x, y)`: its cell's triangle, or
    /// [`FLAT_PIECE`] on a flat tile or outside.
    fn piece_at(&self, k: u32, x: f32, y: f32) -> u32 {
        let Some(t) = self.tiles.get(k as usize).filter(|t| t.n > 0) else { return FLAT_PIECE };
        let k = k as usize;
        let ([ci, cj], [fu, fv]) = self.cell_at(t.n, k % self.ntx, k / self.ntx, x, y);
        (k * 2 * TILE_CELLS * TILE_CELLS) as u32 + 2 * (cj * t.n + ci) as u32 + u32::from(fu < fv)
    }
}

#[cfg(test)]
mod tests;
