//! The water's shading from the sampled surface: each level's slopes of the waves it resolves, the rest as
//! roughness, and near the foci two detail bands chosen by the pixel's footprint ([`WaveSurface::shading`]).
//!
//! Model: a wave shorter than four cells of a level ([`resolved`]: twice the Nyquist limit) cannot be drawn from
//! its nodes (sampled there, it aliases into a false pattern of longer slopes, or, between two and four cells,
//! bilinear interpolation draws the cells' lattice), so its slopes are treated
//! statistically, as filtered normal maps treat detail finer than a texel: M. Olano & D. Baker, "LEAN Mapping",
//! I3D 2010; M. Toksvig, "Mipmapping Normal Maps", J. Graphics Tools 10(3), 2005. The detail bands are chosen as a
//! mipmap's level is, by the footprint of the pixel that sees the water. Past the sampled sea (where the waves
//! taper, and the still level beyond) the slopes not drawn are roughness too, so the total slope variance is the
//! sea's everywhere. Checked in the parent's tests against the waves' analytic slopes and variances.

use super::{unit, WaveSurface, TILE_CELLS};

/// The detail bands ([`SurfaceSpec::detail`](super::SurfaceSpec::detail)) by the cells per tile side that resolve them: band 0 holds the
/// waves the finest cells (a 32nd of a tile) cannot resolve but a 64th can (2–4 m long with 32 m tiles), band 1
/// those that need a 128th (1–2 m).
pub const DETAIL_BANDS: [usize; 2] = [2 * TILE_CELLS, 4 * TILE_CELLS];
/// Cells along a side of the grid both detail bands are sampled on: the finer band's, so each band has four
/// nodes or more to its shortest wave (bilinear interpolation keeps its amplitude).
pub const DETAIL_CELLS: usize = 4 * TILE_CELLS;

/// Whether a wave of wavenumber `k_rad_m` is resolved by samples `cell_m` apart: at least four cells to its
/// wavelength (`k ≤ π / (2 cell_m)`, twice the Nyquist limit). Shorter waves sampled at the nodes either alias
/// into spurious longer slope patterns (under two cells) or, interpolated bilinearly between nodes two to four
/// cells apart along the wave, draw the grid itself: a lattice of highlights aligned with the cells, its amplitude
/// set by where the nodes fall on the wave (at W3 the shortest waves, 2.1 m, have just over two of the finest 1 m
/// cells). So the shading slopes leave them out and take their slope variance as roughness instead
/// ([`WaveSurface::shading`]).
#[inline]
pub(crate) fn resolved(k_rad_m: f64, cell_m: f32) -> bool {
    k_rad_m * f64::from(cell_m) <= std::f64::consts::FRAC_PI_2
}

/// The water's shading at a point: the resolved waves' normal and the unresolved ones' slope variance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceShading {
    /// Unit normal (up-facing) of the sampled slopes `∇η` of the resolved waves, interpolated bilinearly.
    pub normal: [f32; 3],
    /// Mean square slope (both axes, `σx² + σy²`) of the waves too short for the level's cells: a roughness
    /// to add to the capillaries' (the filtered-normal-map rule, LEAN/Toksvig), so every level shows the same
    /// total slope variance.
    pub unresolved_mss: f32,
}

impl WaveSurface {
    /// Smooth unit normal at world `(x, y)`: the sampled slopes `∇η` of the resolved waves interpolated
    /// bilinearly (up-facing); straight up over the still water beyond the sampled sea (see
    /// [`WaveSurface::shading`]); `None` without waves or slopes.
    #[inline]
    pub fn shading_normal(&self, x: f32, y: f32) -> Option<[f32; 3]> {
        self.shading(x, y, 0.0).map(|s| s.normal)
    }

    /// The water's shading at world `(x, y)` seen with a pixel footprint of `footprint_m` metres on the water
    /// ([`SurfaceShading`]); `None` on a surface without waves or sampled without its slopes
    /// ([`SurfaceSpec::slopes`](super::SurfaceSpec::slopes) off).
    ///
    /// Model: a wave shorter than four cells of the tile's level (`resolved`) cannot be drawn from its nodes
    /// (sampled there, it aliases into a false pattern of longer slopes, and the level's edge shows as a change
    /// of texture), so its slopes are treated statistically, as filtered normal maps treat detail finer than a
    /// texel: M. Olano & D. Baker, "LEAN Mapping", I3D 2010; M. Toksvig, "Mipmapping Normal Maps", J. Graphics
    /// Tools 10(3), 2005. Each level's normals carry the waves it resolves and its roughness the variance of
    /// the rest, `Σ a²k²/2` over those components. With [`SurfaceSpec::detail`](super::SurfaceSpec::detail) the finest level's short waves
    /// come in two bands of their own, each drawn as normals where the footprint resolves it (a footprint no
    /// wider than the band's cell) and as roughness where it is twice as wide or more, with a linear crossfade
    /// of the slopes in between (`w`, the roughness taking `(1 − w²)` of the band's variance): the texture
    /// filtering rule of a mipmap's level selection, so a top view's 0.5 m pixels never alias waves of 0.5 m.
    ///
    /// The same rule carries the sea past its sampled part, which is a level of detail and not the sea's end:
    /// where the waves taper to the still level, the slopes the taper takes away are handed to the roughness,
    /// and the still water beyond (outside the tiles, or a flat tile) is the coarsest level of all, every wave
    /// too short for it: a level normal with the whole `Σ a²k²/2` as roughness. So the total slope variance
    /// (drawn plus rough) is the sea's everywhere, and the far sea reads as the near one does from afar instead
    /// of changing texture where the sampling ends.
    #[inline]
    pub fn shading(&self, x: f32, y: f32, footprint_m: f32) -> Option<SurfaceShading> {
        let far = |mss: f32| SurfaceShading { normal: [0.0, 0.0, 1.0], unresolved_mss: mss };
        let Some((ix, iy)) = self.tile_at(x, y) else { return self.far_mss.map(far) };
        let t = &self.tiles[iy * self.ntx + ix];
        if t.n == 0 {
            return self.far_mss.map(far);
        }
        if t.g.is_empty() {
            return None;
        }
        let [mut gx, mut gy] = self.slope_at(&t.g, t.n, ix, iy, x, y);
        let mut mss = t.mss;
        // The detail grid's cell and its four nodes, read once for both bands.
        let mut nodes: Option<([f32; 2], [[f32; 4]; 4])> = None;
        for b in 0..2 {
            if !t.bands[b] {
                continue;
            }
            let cell = self.tile_m / DETAIL_BANDS[b] as f32;
            let w = (2.0 - footprint_m / cell).clamp(0.0, 1.0);
            if w > 0.0 {
                let (f, g) = *nodes.get_or_insert_with(|| {
                    let ([ci, cj], f) = self.cell_at(DETAIL_CELLS, ix, iy, x, y);
                    let at = |i: usize, j: usize| t.detail[j * (DETAIL_CELLS + 1) + i];
                    (f, [at(ci, cj), at(ci + 1, cj), at(ci, cj + 1), at(ci + 1, cj + 1)])
                });
                let dx = bilinear([g[0][2 * b], g[1][2 * b], g[2][2 * b], g[3][2 * b]], f);
                let dy = bilinear([g[0][2 * b + 1], g[1][2 * b + 1], g[2][2 * b + 1], g[3][2 * b + 1]], f);
                gx += w * dx;
                gy += w * dy;
            }
            mss += (1.0 - w * w) * t.band_mss[b];
        }
        if !t.fine.is_empty() {
            // The finest grid's waves on a coarser tile (SurfaceSpec::fine_m), by the same footprint rule.
            let w = (2.0 - footprint_m * TILE_CELLS as f32 * self.inv_tile_m).clamp(0.0, 1.0);
            if w > 0.0 {
                let [dx, dy] = self.slope_at(&t.fine, TILE_CELLS, ix, iy, x, y);
                gx += w * dx;
                gy += w * dy;
            }
            mss += (1.0 - w * w) * t.fine_mss;
        }
        Some(SurfaceShading { normal: unit([-gx, -gy, 1.0]), unresolved_mss: mss })
    }

    /// The slopes `grid` (`(n + 1)²` nodes of tile `(ix, iy)` cut into `n` cells a side, row-major) at world
    /// `(x, y)`, bilinearly.
    #[inline]
    fn slope_at(&self, grid: &[[f32; 2]], n: usize, ix: usize, iy: usize, x: f32, y: f32) -> [f32; 2] {
        let ([ci, cj], f) = self.cell_at(n, ix, iy, x, y);
        let w = n + 1;
        let g = |i: usize, j: usize| grid[j * w + i];
        let (g00, g10, g01, g11) = (g(ci, cj), g(ci + 1, cj), g(ci, cj + 1), g(ci + 1, cj + 1));
        [0, 1].map(|a| bilinear([g00[a], g10[a], g01[a], g11[a]], f))
    }
}

/// The bilinear mix of a cell's corner values `[v00, v10, v01, v11]` at local `(fu, fv)`.
#[inline(always)]
fn bilinear([v00, v10, v01, v11]: [f32; 4], [fu, fv]: [f32; 2]) -> f32 {
    (v00 * (1.0 - fu) + v10 * fu) * (1.0 - fv) + (v01 * (1.0 - fu) + v11 * fu) * fv
}
