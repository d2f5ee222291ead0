//! Glossy water reflections: a camera's reflections traced in directions drawn from the reflection lobe of the
//! water's unresolved roughness, then spread over the rest of it in screen space.
//!
//! **Model.** The water's roughness below the surface's sampling is a Gaussian slope distribution of mean square
//! slope `σ² = α²` (both axes; C. Cox & W. Munk, "Measurement of the Roughness of the Sea Surface from
//! Photographs of the Sun's Glitter", JOSA 44(11), 1954: `α² = 0.003 + 5.12·10⁻³ U`, plus the slopes of the waves
//! too short for the sampled surface there), the same `α` that shapes the sun's glitter (`sensors/shade.rs`). A
//! facet tilted by slopes `(s_u, s_c)` (along and across the line of sight) turns the mirror direction of a view
//! ray that meets the water at grazing angle `γ` by `2 s_u` in elevation and `2 s_c tan γ` in azimuth (first
//! order; Cox & Munk's glitter geometry, their section 3), so the reflected radiance is the mirror image
//! convolved with a Gaussian of standard deviations `2 σ_1` vertically and `2 σ_1 sin γ` horizontally
//! (`σ_1 = α/√2` per axis; radians of view, the azimuth's at the mirror direction's elevation `γ`). That is why
//! reflections on a breezy sea stretch into vertical streaks and lose their outlines.
//!
//! **Traced, then spread in screen space.** Each traced reflection leaves in a direction drawn from the lobe at
//! its own point ([`lobe_ray`]: the mirror direction turned by the lobe's mean offset and a Gaussian draw of
//! `√(1 − κ²)` of its spreads, `κ` = [`SCREEN_SHARE`]; the draws stratified over each 4 × 4 block of traced
//! reflections, [`stratum`]), and a pinhole camera then spreads the traced reflections over the remaining `κ` of
//! the lobe in screen space (`f` pixels per radian at the image centre): each water pixel's reflected radiance
//! becomes the mean of the traced reflections around it under that share of the lobe — the variances add up to
//! the lobe's. This is the stochastic screen-space filtering of glossy reflections of real-time renderers (T.
//! Stachowiak, "Stochastic Screen-Space Reflections", SIGGRAPH 2015 Advances in Real-Time Rendering: rays drawn
//! from the BRDF, resolved by a spatial filter), with stratified rather than random draws. Drawing the directions
//! at each point matters where what is reflected stands close behind the water: the mirror rays of the water
//! farther below a hull pass over it, so a spread of mirror rays alone lost most of the hull's reflection seen
//! near the horizon (Mitsuba's comparison scene `grazing`, 2.1 times the reference's radiance there). Only
//! water takes part. The screen-space share is a tent of two box filters per axis (P. S. Heckbert, "Filtering by
//! repeated integration", SIGGRAPH 1986), each box read from prefix sums, so any width costs the same; the boxes'
//! widths follow each place's own lobe. The sums run on a grid of cells of several pixels, as coarse as the
//! narrowest screen-space share allows (four cells to its standard deviation, [`decimation`]), and each pixel
//! reads them back bilinearly. The grid is laid along the world's vertical as the image shows it (turned by the
//! camera's roll), so a rolling USV's streaks stay vertical in the world. Approximations: the lobe is a Gaussian
//! of the microfacet lobe's moments; its screen-space share is taken at the image's focal length everywhere; and
//! where the water ends in the image, down the image the missing reflections are the nearest traced ones in the
//! same column (a hull standing on the water: the reflections just below it, which show the hull) and past the
//! image's top and bottom its edge rows, while across the image the mean is over the water that remains.
//!
//! **The sky's part.** The screen space cannot look past the image's edge: a lens narrower than the lobe, or a
//! view steeply down, would read the sky of the mirror directions around the pixel instead of the lobe's mean (a
//! 4° lens over 8 m/s wind: 0.80 of it in red). So the sky is spread too, alongside: each traced reflection also
//! carries the sky along its ray (`sky`, what it brings back when it meets nothing), and each place reads the
//! spread reflections scaled by the sky's own mean over the lobe (`lobe_sky`, from a table of the same microfacet
//! model, `shade/sky_lobe.rs`) over the spread sky: `L = blur(value) · lobe_sky / blur(sky)`, per channel. Where
//! the lobe meets only sky this is the table's mean exactly, whatever the lens; where it meets a ship it is the
//! screen-space spread, scaled by how much the sky's part is off there; and it is never negative (a sum
//! `lobe_sky + blur(value − sky)` went below zero where a dark hull hid a much brighter sky, at dusk).

use crate::sensors::noise;
use crate::sensors::shade::rough_water;
use parry3d::math::Vec3;

/// The share `κ` of the lobe's spread (its standard deviations) left to the screen-space blur: each traced
/// reflection leaves in a direction drawn from the lobe narrowed to `√(1 − κ²)` of its spread around its mean
/// ([`lobe_ray`]), so that the two together spread as the lobe does (variances add).
pub const SCREEN_SHARE: f32 = 0.5;

/// The point in `[0, 1)²` that draws the direction of the reflection traced at pixel `(x, y)`, traced every
/// `spacing` pixels: the 16 points of a Hammersley set laid over each 4 × 4 block of traced reflections in the
/// order of a Bayer matrix (neighbours draw far-apart points, so that the blur averages the whole set over a few
/// blocks), the set shifted by a draw of `seed` (Cranley–Patterson rotation: every seed its own, unbiased set).
pub fn stratum(x: u32, y: u32, spacing: u32, seed: u64) -> [f32; 2] {
    const BAYER: [[u32; 4]; 4] = [[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]];
    let s = spacing.max(1);
    let i = BAYER[((y / s) % 4) as usize][((x / s) % 4) as usize];
    let reversed = ((i & 1) << 3) | ((i & 2) << 1) | ((i & 4) >> 1) | ((i & 8) >> 3);
    let shift =
        [noise::uniform(seed, noise::stream::GLOSSY, 0) as f32, noise::uniform(seed, noise::stream::GLOSSY, 1) as f32];
    let point = [(i as f32 + 0.5) / 16.0, (reversed as f32 + 0.5) / 16.0];
    [(point[0] + shift[0]).fract(), (point[1] + shift[1]).fract()]
}

/// A direction drawn from the reflection lobe around the `mirror` direction (unit; the mirror image of the view
/// ray about the shading normal) of water of mean square slope `mss` seen at grazing sine `sin_grazing`, by the
/// point `u` of `[0, 1)²`: the mirror direction turned by the lobe's mean offset in elevation plus a Gaussian
/// draw (Box–Muller) of `√(1 − κ²)` of its standard deviations in elevation and azimuth ([`rough_water::lobe`],
/// [`SCREEN_SHARE`]), kept above the horizon as the mirror direction is (a draw below it is mirrored back up).
pub fn lobe_ray(mirror: Vec3, mss: f32, sin_grazing: f32, u: [f32; 2]) -> Vec3 {
    let [de, se, sa] = rough_water::lobe(sin_grazing.clamp(0.0, 1.0), mss.max(0.0).sqrt());
    let q = (1.0 - SCREEN_SHARE * SCREEN_SHARE).sqrt();
    let radius = (-2.0 * (1.0 - u[0]).max(1e-7).ln()).sqrt();
    let (s, c) = (std::f32::consts::TAU * u[1]).sin_cos();
    let e = mirror.z.clamp(-1.0, 1.0).asin() + de + q * se * radius * c;
    let a = mirror.y.atan2(mirror.x) + q * sa * radius * s;
    let (se_, ce) = e.sin_cos();
    let (sa_, ca) = a.sin_cos();
    Vec3::new(ce * ca, ce * sa_, se_.abs().max(1e-4)).normalize()
}

/// One traced water reflection: its pixel (`x`, `y`, the pixel's index), the reflected radiance (linear RGB),
/// the sky's radiance along the same reflected ray (what it brings back when it meets nothing) and the sky's mean
/// over the water's lobe around it, the roughness's mean square slope `α²` (both axes) there, and `sin γ`, the
/// sine of its view ray's angle below the horizontal.
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    /// Pixel column.
    pub x: u32,
    /// Pixel row.
    pub y: u32,
    /// Reflected radiance, linear RGB.
    pub value: Vec3,
    /// The sky's radiance along the reflected ray, linear RGB.
    pub sky: Vec3,
    /// The sky's mean over the lobe around the reflected ray, linear RGB (`shade/sky_lobe.rs`).
    pub lobe_sky: Vec3,
    /// Mean square slope `α²`.
    pub mss: f32,
    /// Sine of the view ray's angle below the horizontal.
    pub sin_grazing: f32,
}

/// The lobe in pixels, `[σ_x, σ_y, Δy]` (standard deviations across and down the image, and how far below the
/// pixel its centre lies), for mean square slope `mss`, grazing sine `sin_grazing` and focal length `f_px`: the
/// microfacet lobe's moments ([`rough_water::lobe`]) at `f_px` pixels per radian (an azimuth's at the view's
/// elevation).
#[inline]
pub fn lobe_px(mss: f32, sin_grazing: f32, f_px: f32) -> [f32; 3] {
    let sin_g = sin_grazing.clamp(0.0, 1.0);
    let [de, se, sa] = rough_water::lobe(sin_g, mss.max(0.0).sqrt());
    let cos_g = (1.0 - sin_g * sin_g).sqrt();
    [sa * f_px * cos_g, se * f_px, de * f_px]
}

/// The narrowest lobe down the image (pixels) of water whose mean square slope is at least `mss_min`: at the
/// grazing views where it is narrowest, about 0.6 of the first-order spread `2σ₁ f` (`rough_water.rs`).
/// That is the lobe's; the screen-space blur spreads [`SCREEN_SHARE`] of it.
#[inline]
pub fn narrowest_lobe_px(mss_min: f32, f_px: f32) -> f32 {
    0.6 * 2.0 * (0.5 * mss_min.max(0.0)).sqrt() * f_px
}

/// Pixels per coarse-grid cell `[x, y]`: the largest power of two up to 8 down the image such that the narrowest
/// lobe (`sigma_min_vertical`, pixels) still spans four cells, and half that across (the lobe of water near the
/// horizon is narrow across the image, so fewer pixels are merged that way); at least `spacing` both ways (the
/// traced reflections' spacing, so that every cell holds one).
pub fn decimation(sigma_min_vertical: f32, spacing: usize) -> [usize; 2] {
    let mut d = 1;
    while d < 8 && sigma_min_vertical / (2 * d) as f32 >= 4.0 {
        d *= 2;
    }
    [(d / 2).max(spacing.max(1)), d.max(spacing.max(1))]
}

/// The blurred reflections of one image: the lobe-weighted means of the reflections and of the sky along them,
/// and the sky's lobe means, on a coarse grid of `dx × dy`-pixel cells, read back bilinearly ([`Blurred::at`]).
#[derive(Debug, Clone)]
pub struct Blurred {
    /// The frame the grid is laid in: image points turned by the camera's roll about `centre`, so that the grid's
    /// columns run along the world's vertical as the image shows it, then moved by `origin`.
    frame: Frame,
    dx: usize,
    dy: usize,
    /// Where a cell's samples lie on average, in pixels from its centre (the traced reflections sit at the
    /// corner of each `spacing × spacing` block: `0.5 − spacing / 2`).
    shift: f32,
    cw: usize,
    ch: usize,
    /// Per cell, the reflected radiance over its lobe, scaled by the sky's lobe mean over the spread sky there;
    /// `None` where no water lies within reach or the cell holds no sample of its own.
    mean: Vec<Option<Vec3>>,
}

impl Blurred {
    /// The blurred reflected radiance at image point `(u, v)` (pixels; a pixel's centre is `x + 0.5, y + 0.5`):
    /// the spread reflections scaled by the sky's lobe mean over the spread sky (see the module docs), bilinear
    /// between the four nearest cells that hold it, else the point's own cell's; `None` when neither does.
    #[inline]
    pub fn at(&self, u: f32, v: f32) -> Option<Vec3> {
        let [u, v] = self.frame.grid_point(u, v);
        let fx = ((u - self.shift) / self.dx as f32 - 0.5).clamp(0.0, (self.cw - 1) as f32);
        let fy = ((v - self.shift) / self.dy as f32 - 0.5).clamp(0.0, (self.ch - 1) as f32);
        let (x0, y0) = (fx as usize, fy as usize);
        let (x1, y1) = ((x0 + 1).min(self.cw - 1), (y0 + 1).min(self.ch - 1));
        let (tx, ty) = (fx - x0 as f32, fy - y0 as f32);
        let mut acc = Vec3::ZERO;
        let mut wsum = 0.0;
        for (cx, cy, wt) in
            [(x0, y0, (1.0 - tx) * (1.0 - ty)), (x1, y0, tx * (1.0 - ty)), (x0, y1, (1.0 - tx) * ty), (x1, y1, tx * ty)]
        {
            if let Some(m) = self.mean[cy * self.cw + cx] {
                acc += m * wt;
                wsum += wt;
            }
        }
        if wsum > 0.0 {
            return Some(acc / wsum);
        }
        let (cx, cy) =
            (((u.max(0.0) as usize) / self.dx).min(self.cw - 1), ((v.max(0.0) as usize) / self.dy).min(self.ch - 1));
        // (u, v) are in the grid's frame here.
        self.mean[cy * self.cw + cx]
    }
}

/// Image points (pixels) to the grid's frame: turned by `-roll` about `centre`, then moved by `-origin`. Without
/// roll it is the identity (exactly: the centre and origin are zero then).
#[derive(Debug, Clone, Copy)]
struct Frame {
    cos: f32,
    sin: f32,
    centre: [f32; 2],
    origin: [f32; 2],
}

impl Frame {
    /// The frame of a `width × height` image whose world vertical shows turned by `roll` radians (clockwise
    /// positive: the image's "down" lies at `roll` from its columns), holding the whole image.
    fn new(width: usize, height: usize, roll: f32) -> Self {
        if roll == 0.0 || !roll.is_finite() {
            return Self { cos: 1.0, sin: 0.0, centre: [0.0; 2], origin: [0.0; 2] };
        }
        let (sin, cos) = roll.sin_cos();
        let centre = [0.5 * width as f32, 0.5 * height as f32];
        let turned = Self { cos, sin, centre, origin: [0.0; 2] };
        Self { origin: turned.bounds(width, height)[0], ..turned }
    }

    /// The lowest and highest grid-frame coordinates `[[x, y], [x, y]]` of a `width × height` image's corners.
    fn bounds(&self, width: usize, height: usize) -> [[f32; 2]; 2] {
        let (w, h) = (width as f32, height as f32);
        let g = [[0.0, 0.0], [w, 0.0], [0.0, h], [w, h]].map(|[u, v]| self.grid_point(u, v));
        let fold = |a: usize, init: f32, f: fn(f32, f32) -> f32| g.iter().map(|p| p[a]).fold(init, f);
        [
            [fold(0, f32::INFINITY, f32::min), fold(1, f32::INFINITY, f32::min)],
            [fold(0, 0.0, f32::max), fold(1, 0.0, f32::max)],
        ]
    }

    #[inline(always)]
    fn grid_point(&self, u: f32, v: f32) -> [f32; 2] {
        let (x, y) = (u - self.centre[0], v - self.centre[1]);
        [
            self.cos * x + self.sin * y + self.centre[0] - self.origin[0],
            -self.sin * x + self.cos * y + self.centre[1] - self.origin[1],
        ]
    }
}

/// Sums per cell: radiance (3), the sky along the same rays (3), samples (1).
const SUMS: usize = 7;
/// Where the sample count is among the [`SUMS`].
const COUNT: usize = 6;

/// Spreads the traced reflections `samples` of a `width × height` image (focal length `f_px` pixels per radian;
/// traced every `spacing` pixels, or closer; the world's vertical turned by `roll` radians in the image, the
/// camera's roll) over their lobes (see the module docs); `None` without samples.
pub fn blur(width: usize, height: usize, f_px: f32, spacing: usize, roll: f32, samples: &[Sample]) -> Option<Blurred> {
    if samples.is_empty() || width == 0 || height == 0 {
        return None;
    }
    // The narrowest lobe: the calmest water's, at grazing views.
    let mss_min = samples.iter().map(|s| s.mss).fold(f32::INFINITY, f32::min);
    let [dx, dy] = decimation(SCREEN_SHARE * narrowest_lobe_px(mss_min, f_px), spacing);
    let frame = Frame::new(width, height, roll);
    let [ew, eh] = frame.bounds(width, height)[1];
    let (cw, ch) = ((ew.ceil() as usize).div_ceil(dx).max(1), (eh.ceil() as usize).div_ceil(dy).max(1));
    // The coarse grid: sums of radiance, of the sky along the same rays and of samples; of the grazing sine and the
    // roughness; of the sky's lobe means.
    let mut sum = vec![[0f32; SUMS]; cw * ch];
    let mut geo = vec![[0f32; 2]; cw * ch];
    let mut lobe_sky = vec![Vec3::ZERO; cw * ch];
    for s in samples {
        let [gx, gy] = frame.grid_point(s.x as f32 + 0.5, s.y as f32 + 0.5);
        let (x, y) = ((gx.max(0.0) as usize).min(cw * dx - 1), (gy.max(0.0) as usize).min(ch * dy - 1));
        let c = (y / dy) * cw + x / dx;
        let acc = &mut sum[c];
        for (k, v) in [s.value.x, s.value.y, s.value.z, s.sky.x, s.sky.y, s.sky.z, 1.0].into_iter().enumerate() {
            acc[k] += v;
        }
        geo[c][0] += s.sin_grazing;
        geo[c][1] += s.mss;
        lobe_sky[c] += s.lobe_sky;
    }
    // Per cell, its share of the lobe (in cells): the half-widths of each box of the tent (a box of width 2r has
    // variance r²/3; two of σ/√2 make σ). Centred: the traced directions carry the lobe's mean offset.
    let radius: Vec<[f32; 2]> = sum
        .iter()
        .zip(&geo)
        .map(|(s, g)| {
            if s[COUNT] <= 0.0 {
                return [0.0; 2];
            }
            let [lx, ly, _] = lobe_px(g[1] / s[COUNT], g[0] / s[COUNT], f_px);
            let k = 1.5f32.sqrt() * SCREEN_SHARE;
            [lx / dx as f32 * k, ly / dy as f32 * k]
        })
        .collect();
    // The sky's lobe mean of each cell's own samples (not spread: it is the lobe's already).
    let own: Vec<Option<Vec3>> =
        sum.iter().zip(lobe_sky).map(|(s, l)| (s[COUNT] > 0.0).then(|| l / s[COUNT])).collect();
    // Down the image the lobe is cut by what is not water (a hull standing on it, the horizon, the image's top and
    // bottom edges): there the missing reflections are taken as the nearest traced ones in the same column (and
    // beyond the edges as the edge's), clamped rather than left out, so that a water pixel just below a hull still
    // reads the hull's reflection over the part of its lobe the hull hides (left out, the mean leant to the water
    // farther below, which reflects what is higher: the sky over a low hull). Across the image, where the lobe
    // runs along the water and past a hull's sides, the mean stays over the water that remains.
    let mut cur = fill_columns(&sum, cw, ch);
    for axis in [1usize, 1] {
        cur = box_pass(&cur, &radius, cw, ch, axis);
    }
    for (c, own) in cur.iter_mut().zip(&own) {
        if own.is_none() {
            *c = [0.0; SUMS]; // (a cell without samples of its own, filled down its column: not water)
        }
    }
    for axis in [0usize, 0] {
        cur = box_pass(&cur, &radius, cw, ch, axis);
    }
    let mean = cur
        .iter()
        .zip(&own)
        .map(|(s, own)| {
            let lobe = (*own)?;
            (s[COUNT] > 1e-6).then(|| {
                let value = Vec3::new(s[0], s[1], s[2]) / s[COUNT];
                let sky = Vec3::new(s[3], s[4], s[5]) / s[COUNT];
                // Per channel: the spread reflections times the sky's lobe mean over the spread sky (1 where there
                // is no sky to speak of: a black night sky).
                let scale = |v: f32, l: f32, k: f32| if k > 1e-12 { v * (l / k) } else { v };
                Vec3::new(scale(value.x, lobe.x, sky.x), scale(value.y, lobe.y, sky.y), scale(value.z, lobe.z, sky.z))
            })
        })
        .collect();
    // (Turned, the traced corners no longer sit at a fixed place in their cells.)
    let shift = if frame.sin == 0.0 { 0.5 - 0.5 * spacing.max(1) as f32 } else { 0.0 };
    Some(Blurred { frame, dx, dy, shift, cw, ch, mean })
}

/// The `cw × ch` grid of sums with each empty cell (no sample) given the sums of the nearest cell with samples in
/// its column (the one below on a tie); a column without samples stays empty.
fn fill_columns(src: &[[f32; SUMS]], cw: usize, ch: usize) -> Vec<[f32; SUMS]> {
    let mut out = src.to_vec();
    for x in 0..cw {
        let full: Vec<usize> = (0..ch).filter(|&y| src[y * cw + x][COUNT] > 0.0).collect();
        if full.is_empty() {
            continue;
        }
        let mut next = 0; // index into `full` of the first full row at or below y
        for y in 0..ch {
            while next < full.len() && full[next] < y {
                next += 1;
            }
            if src[y * cw + x][COUNT] > 0.0 {
                continue;
            }
            let below = full.get(next).copied();
            let above = next.checked_sub(1).map(|i| full[i]);
            let from = match (above, below) {
                (Some(a), Some(b)) => {
                    if y - a < b - y {
                        a
                    } else {
                        b
                    }
                }
                (Some(a), None) => a,
                (None, Some(b)) => b,
                (None, None) => continue,
            };
            out[y * cw + x] = src[from * cw + x];
        }
    }
    out
}

/// One box pass along `axis` (0: along rows, 1: along columns) over the `cw × ch` grid of sums: each cell takes
/// the sum over the box of half-width `radius[c][axis]` cells centred on it, fractional ends read linearly from
/// prefix sums; at least a cell's width. Down the columns the grid is taken as continued past its ends by its end
/// cells, as far again as it is tall (the image's top and bottom rows clamped); along the rows it ends there.
fn box_pass(src: &[[f32; SUMS]], radius: &[[f32; 2]], cw: usize, ch: usize, axis: usize) -> Vec<[f32; SUMS]> {
    let (lines, len) = if axis == 0 { (ch, cw) } else { (cw, ch) };
    let at = move |line: usize, k: usize| if axis == 0 { line * cw + k } else { k * cw + line };
    let mut out = vec![[0f32; SUMS]; cw * ch];
    let mut prefix = vec![[0f64; SUMS]; len + 1];
    for line in 0..lines {
        for k in 0..len {
            let s = src[at(line, k)];
            prefix[k + 1] = std::array::from_fn(|c| prefix[k][c] + f64::from(s[c]));
        }
        let (first, last) = (src[at(line, 0)], src[at(line, len - 1)]);
        // The sums of the cells over the continuous interval [0, x) (x ≥ 0: truncation is the floor); down the
        // columns, past the ends, the end cells repeated (as far as the grid is tall: a lobe far taller than the
        // image would otherwise read little but its edge rows).
        let cum = |x: f32| -> [f64; SUMS] {
            if axis == 1 && x < 0.0 {
                return std::array::from_fn(|c| f64::from(x.max(-(len as f32))) * f64::from(first[c]));
            }
            if axis == 1 && x > len as f32 {
                let past = f64::from((x - len as f32).min(len as f32));
                return std::array::from_fn(|c| prefix[len][c] + past * f64::from(last[c]));
            }
            let x = x.clamp(0.0, len as f32);
            let i = (x as usize).min(len);
            if i == len {
                return prefix[len];
            }
            let f = f64::from(x - i as f32);
            let (a, b) = (prefix[i], prefix[i + 1]);
            std::array::from_fn(|c| a[c] + f * (b[c] - a[c]))
        };
        for k in 0..len {
            let r = radius[at(line, k)][axis].max(0.5);
            let centre = k as f32 + 0.5;
            let (hi, lo) = (cum(centre + r), cum(centre - r));
            out[at(line, k)] = std::array::from_fn(|c| (hi[c] - lo[c]) as f32);
        }
    }
    out
}

#[cfg(test)]
#[path = "glossy_tests.rs"]
mod tests;
