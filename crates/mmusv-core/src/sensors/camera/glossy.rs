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
mod tests {
    use super::*;

    /// Every pixel of a `w × h` image a sample of roughness `mss` and grazing sine `sin_g`, radiance from `value`.
    fn samples(w: usize, h: usize, mss: f32, sin_g: f32, value: impl Fn(usize, usize) -> Vec3) -> Vec<Sample> {
        (0..w * h)
            .map(|i| Sample {
                x: (i % w) as u32,
                y: (i / w) as u32,
                value: value(i % w, i / w),
                sky: Vec3::ZERO,
                lobe_sky: Vec3::ZERO,
                mss,
                sin_grazing: sin_g,
            })
            .collect()
    }

    /// The blurred image at every pixel centre.
    fn image(b: &Blurred, w: usize, h: usize) -> Vec<Vec3> {
        (0..w * h).map(|i| b.at((i % w) as f32 + 0.5, (i / w) as f32 + 0.5).unwrap_or(Vec3::ZERO)).collect()
    }

    /// Mean and standard deviation of the image's first channel along x and y, as a distribution.
    fn moments(img: &[Vec3], w: usize) -> ([f64; 2], [f64; 2]) {
        let total: f64 = img.iter().map(|c| f64::from(c.x)).sum();
        let mut m = [0f64; 2];
        for (i, c) in img.iter().enumerate() {
            m[0] += (i % w) as f64 * f64::from(c.x) / total;
            m[1] += (i / w) as f64 * f64::from(c.x) / total;
        }
        let mut v = [0f64; 2];
        for (i, c) in img.iter().enumerate() {
            v[0] += ((i % w) as f64 - m[0]).powi(2) * f64::from(c.x) / total;
            v[1] += ((i / w) as f64 - m[1]).powi(2) * f64::from(c.x) / total;
        }
        (m, [v[0].sqrt(), v[1].sqrt()])
    }

    #[test]
    fn a_point_spreads_into_the_lobe_of_its_slopes() {
        // mss 0.02 at 500 px/rad, sin γ = 0.3: about 2σ₁ f = 100 px down and 2σ₁ f sin γ ≈ 30 px across (the
        // first-order lobe); the lobe's own moments below.
        // (Tall enough that the image's edges, where each pixel's mean is over fewer neighbours, are 6 σ away.)
        let (w, h) = (400, 1200);
        let s =
            samples(w, h, 0.02, 0.3, |x, y| if (x, y) == (200, 600) { Vec3::new(1.0, 2.0, 3.0) } else { Vec3::ZERO });
        let [lx, ly, off] = lobe_px(0.02, 0.3, 500.0);
        // (Down the image the lobe is narrower than the first-order 100 px: at 17° below the horizontal, part of it
        // would leave under the horizon and is masked.)
        assert!((lx - 30.0).abs() < 3.0 && ly > 70.0 && ly < 100.0 && off.abs() < 10.0, "{lx} {ly} {off}");
        let Some(b) = blur(w, h, 500.0, 1, 0.0, &s) else { panic!("no blur") };
        let out = image(&b, w, h);
        let (m, sd) = moments(&out, w);
        // Each pixel is a normalised mean over its share of the lobe around it (SCREEN_SHARE of its spread; the
        // traced directions carry the rest and the lobe's offset, `lobe_ray`): a unit point spreads into that
        // kernel mirrored (every pixel whose kernel reaches it), with its spread (within the discretisation of
        // the boxes and the coarse grid) and no offset.
        let (kx, ky) = (f64::from(SCREEN_SHARE * lx), f64::from(SCREEN_SHARE * ly));
        assert!((m[0] - 200.0).abs() < 2.0 && (m[1] - 600.0).abs() < 3.0, "centre {m:?}");
        assert!((sd[0] - kx).abs() < 1.5, "horizontal σ {} px, want {kx}", sd[0]);
        assert!((sd[1] - ky).abs() < 3.0, "vertical σ {} px, want {ky}", sd[1]);
        // The channels stay in proportion, and what is spread is what was there (a sum over the pixels).
        let total: Vec3 = out.iter().copied().sum();
        assert!((total.y / total.x - 2.0).abs() < 1e-3 && (total.z / total.x - 3.0).abs() < 1e-3);
        assert!((total.x - 1.0).abs() < 0.03, "total {}", total.x);
    }

    #[test]
    fn a_rolled_camera_spreads_along_the_world_vertical_it_shows() {
        // The same point as above, the world's vertical turned by 0.3 rad in the image: the spread's long axis is
        // the image's (−sin 0.3, cos 0.3), and its two spreads are the lobe's.
        let (w, h, roll) = (900usize, 900usize, 0.3f32);
        let s = samples(w, h, 0.02, 0.3, |x, y| if (x, y) == (450, 450) { Vec3::ONE } else { Vec3::ZERO });
        let Some(b) = blur(w, h, 500.0, 1, roll, &s) else { panic!("no blur") };
        let out = image(&b, w, h);
        let total: f64 = out.iter().map(|c| f64::from(c.x)).sum();
        let mean = |f: &dyn Fn(f64, f64) -> f64| {
            out.iter().enumerate().map(|(i, c)| f((i % w) as f64, (i / w) as f64) * f64::from(c.x)).sum::<f64>() / total
        };
        let (mx, my) = (mean(&|x, _| x), mean(&|_, y| y));
        let sxx = mean(&|x, _| (x - mx).powi(2));
        let syy = mean(&|_, y| (y - my).powi(2));
        let sxy = mean(&|x, y| (x - mx) * (y - my));
        // Principal axis of the covariance, and the spreads along and across it.
        let angle = 0.5 * (2.0 * sxy).atan2(syy - sxx);
        let want = f64::from(-roll);
        assert!((angle - want).abs() < 0.03, "long axis at {angle} rad from the columns, want {want}");
        let [lx, ly, _] = lobe_px(0.02, 0.3, 500.0);
        let (c, sn) = (angle.cos(), angle.sin());
        let along = (syy * c * c + sxx * sn * sn + 2.0 * sxy * sn * c).sqrt();
        let across = (sxx * c * c + syy * sn * sn - 2.0 * sxy * sn * c).sqrt();
        let (kx, ky) = (f64::from(SCREEN_SHARE * lx), f64::from(SCREEN_SHARE * ly));
        assert!((along - ky).abs() < 4.0, "along {along}, want {ky}");
        assert!((across - kx).abs() < 2.0, "across {across}, want {kx}");
    }

    #[test]
    fn the_traced_directions_and_the_blur_together_spread_as_the_lobe() {
        // The directions `lobe_ray` draws over the unit square (a fine grid standing for the strata of many
        // seeds): their mean offset is the lobe's, their spreads `√(1 − κ²)` of its; with the blur's `κ` of it,
        // the variances add up to the lobe's.
        let (mss, sin_g) = (0.02f32, 0.3f32);
        let [de, se, sa] = rough_water::lobe(sin_g, mss.sqrt());
        let e0 = sin_g.asin(); // a flat surface: the mirror direction rises as steeply as the view falls
        let mirror = Vec3::new(e0.cos(), 0.0, e0.sin());
        let n = 256;
        let (mut sum, mut sq) = ([0f64; 2], [0f64; 2]);
        for i in 0..n {
            for j in 0..n {
                let u = [(i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32];
                let r = lobe_ray(mirror, mss, sin_g, u);
                let off = [f64::from(r.z.asin() - e0), f64::from(r.y.atan2(r.x))];
                for k in 0..2 {
                    sum[k] += off[k];
                    sq[k] += off[k] * off[k];
                }
            }
        }
        let count = (n * n) as f64;
        let mean = [sum[0] / count, sum[1] / count];
        let sd = [0, 1].map(|k| (sq[k] / count - mean[k] * mean[k]).sqrt());
        let q = f64::from((1.0 - SCREEN_SHARE * SCREEN_SHARE).sqrt());
        assert!((mean[0] - f64::from(de)).abs() < 2e-3 && mean[1].abs() < 1e-4, "mean {mean:?}, want {de}");
        assert!((sd[0] / (q * f64::from(se)) - 1.0).abs() < 0.03, "elevation σ {}, want {}", sd[0], q * f64::from(se));
        assert!((sd[1] / (q * f64::from(sa)) - 1.0).abs() < 0.03, "azimuth σ {}, want {}", sd[1], q * f64::from(sa));
        let total = (sd[0].powi(2) + f64::from(SCREEN_SHARE * se).powi(2)).sqrt();
        assert!((total / f64::from(se) - 1.0).abs() < 0.03, "drawn and blurred {total}, lobe {se}");
    }

    #[test]
    fn each_four_by_four_blocks_draw_the_whole_set_of_strata() {
        for (spacing, seed) in [(1u32, 0u64), (2, 7), (4, 123)] {
            let points: Vec<[f32; 2]> = (0..4u32)
                .flat_map(|by| (0..4u32).map(move |bx| (bx, by)))
                .map(|(bx, by)| stratum(bx * spacing + 8 * spacing, by * spacing, spacing, seed))
                .collect();
            // One point in every sixteenth of each axis (a Latin square of strata, shifted by the seed's rotation).
            for axis in 0..2 {
                let mut cells: Vec<u32> = points.iter().map(|p| (p[axis] * 16.0) as u32).collect();
                cells.sort_unstable();
                cells.dedup();
                assert_eq!(cells.len(), 16, "spacing {spacing}, seed {seed}, axis {axis}: {points:?}");
            }
            // Pixels of one block share their block's point.
            assert_eq!(stratum(spacing - 1, spacing - 1, spacing, seed), stratum(0, 0, spacing, seed));
        }
        assert_ne!(stratum(0, 0, 2, 1), stratum(0, 0, 2, 2));
    }

    #[test]
    fn a_flat_layer_stays_flat_and_other_pixels_neither_give_nor_take() {
        let (w, h) = (64, 48);
        // A hull in the middle: not water, so no samples there (whatever it looks like, it must not leak in).
        let hull = |x: usize, y: usize| (20..40).contains(&x) && (10..20).contains(&y);
        let s: Vec<Sample> = samples(w, h, 0.01, 0.2, |_, _| Vec3::new(5.0, 6.0, 7.0))
            .into_iter()
            .filter(|s| !hull(s.x as usize, s.y as usize))
            .collect();
        let Some(b) = blur(w, h, 200.0, 1, 0.0, &s) else { panic!("no blur") };
        for (i, c) in image(&b, w, h).iter().enumerate() {
            if !hull(i % w, i / w) {
                assert!((*c - Vec3::new(5.0, 6.0, 7.0)).abs().max_element() < 1e-3, "pixel {i}: {c:?}");
            }
        }
        // Traced every other pixel (as at standard quality): the same.
        let sparse: Vec<Sample> = s.iter().filter(|p| p.x % 2 == 0 && p.y % 2 == 0).copied().collect();
        let Some(b) = blur(w, h, 200.0, 2, 0.0, &sparse) else { panic!("no blur") };
        for (i, c) in image(&b, w, h).iter().enumerate() {
            if !hull(i % w, i / w) {
                assert!((*c - Vec3::new(5.0, 6.0, 7.0)).abs().max_element() < 1e-3, "pixel {i}: {c:?}");
            }
        }
        assert!(blur(w, h, 200.0, 1, 0.0, &[]).is_none());
    }

    #[test]
    fn the_sky_is_read_from_its_lobe_means_whatever_the_lobe_reaches() {
        // Reflections that all leave for the sky (value = sky along them) over water whose lobe is far wider than
        // the image (a narrow lens): each place reads the sky's lobe mean given with its samples, not the mirror
        // directions' sky the screen-space spread would average near the edges. A smooth lobe mean (linear down
        // the image) is read back exactly at the cells' centres and within a cell's change between them.
        let (w, h) = (32, 24);
        let lobe_sky = |y: usize| Vec3::new(100.0 + y as f32, 200.0, 300.0 - 2.0 * y as f32);
        let mirror = |x: usize, y: usize| Vec3::new(50.0 + x as f32, 80.0 + 3.0 * y as f32, 900.0);
        let s: Vec<Sample> = samples(w, h, 0.05, 0.5, |_, _| Vec3::ZERO)
            .into_iter()
            .map(|p| {
                let (x, y) = (p.x as usize, p.y as usize);
                Sample { value: mirror(x, y), sky: mirror(x, y), lobe_sky: lobe_sky(y), ..p }
            })
            .collect();
        let Some(b) = blur(w, h, 3000.0, 1, 0.0, &s) else { panic!("no blur") };
        for (i, c) in image(&b, w, h).iter().enumerate() {
            let want = lobe_sky(i / w);
            assert!((*c - want).abs().max_element() < 2.0 * b.dy as f32 + 1e-3, "pixel {i}: {c:?}, want {want:?}");
        }
        // A reflected hull (brighter than an even sky by 1000 in a block) is spread around it.
        let hull = |x: usize, y: usize| (12..20).contains(&x) && (8..14).contains(&y);
        let even = Vec3::new(200.0, 300.0, 400.0);
        let with_hull = |hull_value: Vec3| -> Vec<Sample> {
            s.iter()
                .map(|p| {
                    let (x, y) = (p.x as usize, p.y as usize);
                    let value = if hull(x, y) { hull_value } else { even };
                    Sample { value, sky: even, lobe_sky: even, ..*p }
                })
                .collect()
        };
        let Some(bh) = blur(w, h, 3000.0, 1, 0.0, &with_hull(even + Vec3::splat(1000.0))) else { panic!("no blur") };
        let extra: f32 = image(&bh, w, h).iter().map(|c| c.x - even.x).sum::<f32>() / (w * h) as f32;
        // The spread is a normalised mean over the whole image here and, down it, over the edge rows read again
        // past its top and bottom as far as it is tall (the lobe reaches past it every way): every pixel gets the
        // hull's share, 8 of 32 columns and 6 of 24 + 2 × 24 rows of 1000.
        let want = 1000.0 * (8.0 / 32.0) * (6.0 / 72.0);
        assert!((extra - want).abs() < 0.05 * want, "{extra}, want {want}");
        // A black hull hiding a sky far brighter than the lobe's mean there (dusk: the afterglow low in the mirror,
        // the lobe reaching up into darker sky): the reflection darkens but never goes below zero (the sum of the
        // lobe's mean and the spread difference did, and showed black and pure blue water).
        let dusk: Vec<Sample> = with_hull(Vec3::ZERO)
            .into_iter()
            .map(|p| Sample { sky: Vec3::new(5000.0, 3000.0, 900.0), lobe_sky: Vec3::new(500.0, 400.0, 300.0), ..p })
            .map(|p| if hull(p.x as usize, p.y as usize) { p } else { Sample { value: p.sky, ..p } })
            .collect();
        let Some(bd) = blur(w, h, 3000.0, 1, 0.0, &dusk) else { panic!("no blur") };
        for (i, c) in image(&bd, w, h).iter().enumerate() {
            assert!(c.min_element() >= 0.0 && c.max_element() <= 500.0 + 1e-3, "pixel {i}: {c:?}");
        }
    }

    #[test]
    fn calmer_water_and_a_wider_view_spread_less() {
        assert!(lobe_px(0.003, 0.5, 320.0)[1] < lobe_px(0.046, 0.5, 320.0)[1]);
        assert!(lobe_px(0.01, 0.5, 100.0)[1] < lobe_px(0.01, 0.5, 320.0)[1]);
        // Near the horizon the horizontal spread narrows, and the lobe's centre drops below the pixel.
        assert!(lobe_px(0.01, 0.02, 320.0)[0] < 0.3 * lobe_px(0.01, 0.5, 320.0)[0]);
        assert!(lobe_px(0.01, 0.02, 320.0)[2] > 10.0);
        assert_eq!(decimation(1.0, 1), [1, 1]);
        assert_eq!(decimation(1.0, 2), [2, 2]);
        assert_eq!(decimation(10.0, 1), [1, 2]);
        assert_eq!(decimation(20.0, 1), [2, 4]);
        assert_eq!(decimation(100.0, 2), [4, 8]);
    }
}
