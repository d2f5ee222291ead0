//! The lamps' glow in the air (`shade/lamp_halo.rs`) added to a camera's pixels: along each pixel's centre ray, up
//! to what it meets (the far sea beyond the sampled surface included), from every lamp whose glow reaches the ray.
//! `camera.rs` adds it after the anti-aliasing (the glow is smooth: the centre ray's serves the pixel) and before
//! the lamps smaller than a pixel.
//!
//! **Shared over blocks** (below `high` quality, which works out every pixel's own). The glow is smooth wherever
//! nothing stands in the air in front of it and no lamp is near, so it is worked out at the corners of blocks of
//! [`BLOCK`] × [`BLOCK`] pixels, and a block whose corners agree takes their bilinear mean at each of its pixels
//! whose ray meets what the corners' meet (the same instance, or nothing, as they do); a pixel whose ray does not
//! works out its own. The corners agree when their rays and the block's middle one meet the same, their glows are
//! within [`ALIKE_GLOW`] of each other and their bilinear mean at the middle pixel within [`MIDDLE_ERROR`] of that
//! pixel's own (or all of them are under a tenth of the glow's least), and no lamp that glows there
//! passes nearer the block's middle ray than twice the block's own width at the lamp's distance (a lamp inside the
//! block, whose peak its corners would miss). A block whose corners do not agree is split in four, down to 2 × 2,
//! whose pixels all work out their own.

use super::radiance::PixelGrid;
use crate::scene::{RayHits, Scene};
use crate::sensors::shade::lamp_halo::LAMP_HALO_LEAST;
use crate::sensors::shade::Shader;
use parry3d::math::Vec3;
use rayon::prelude::*;

/// Rays per task.
const CHUNK: usize = 1024;

/// The largest block side (pixels) the glow is shared over.
pub const BLOCK: usize = 16;

/// Relative spread (largest less least over largest, of the channels' sum) of a block's corners' glows within which
/// they may agree.
pub const ALIKE_GLOW: f32 = 0.5;

/// Relative difference between a block's middle pixel's own glow and its corners' bilinear mean there within which
/// the corners agree.
pub const MIDDLE_ERROR: f32 = 0.005;

/// A block: its corners' columns and rows (inclusive).
type Block = (usize, usize, usize, usize);

/// A block judged: the pixels (row-major) that take its corners' bilinear mean and that mean, the pixels `(x, y)`
/// that work out their own, and the four blocks it splits into.
type Decision = (Vec<(usize, Vec3)>, Vec<(usize, usize)>, Vec<Block>);

/// Adds the lamps' glow to `linear` (per pixel, `order[k]` the pixel of ray `k`) for the rays `origins`, `dirs`
/// and their `hits`, shared over the blocks of `grid` when given (module docstring); nothing without lit lamps or
/// without air to scatter.
pub(super) fn add_lamp_halos(
    scene: &Scene,
    shader: &Shader,
    (origins, dirs, hits): (&[[f32; 3]], &[[f32; 3]], &RayHits),
    grid: Option<PixelGrid<'_>>,
    order: &[u32],
    linear: &mut [Vec3],
) {
    let Some((_, exposure)) = shader.halo_air() else { return };
    let lamps = shader.lamps().lamps();
    if lamps.is_empty() {
        return;
    }
    let sea_beyond = scene.sea_beyond();
    let n = origins.len();
    let length: Vec<f32> = (0..n)
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|k| {
            let t = hits.distance[k];
            if t.is_finite() {
                return t;
            }
            sea_beyond.and_then(|s| s.meet(origins[k], dirs[k])).unwrap_or(f32::INFINITY)
        })
        .collect();
    // What each ray meets, for the blocks' test: its instance, the far sea, or nothing.
    let met: Vec<u32> = (0..n)
        .map(|k| match (hits.distance[k].is_finite(), length[k].is_finite()) {
            (true, _) => hits.instance[k] as u32,
            (false, true) => u32::MAX - 1, // the far sea beyond the sampled surface
            (false, false) => u32::MAX,
        })
        .collect();
    let ray = |k: usize| (Vec3::from_array(origins[k]), Vec3::from_array(dirs[k]));
    // The farthest a ray may pass each lamp and still be reached by its glow (its most, `J(0)` and no extinction).
    let far2: Vec<f32> = lamps.iter().map(|l| shader.halo_reach(l).powi(2)).collect();
    let glow_of = |k: usize| {
        let (o, d) = ray(k);
        let mut sum = Vec3::ZERO;
        for (lamp, &far2) in lamps.iter().zip(&far2) {
            let to = lamp.centre - o;
            let t0 = to.dot(d);
            if (to - d * t0).length_squared() < far2 {
                sum += shader.lamp_halo(o, d, length[k], lamp);
            }
        }
        sum
    };
    let Some(g) = grid else {
        let glow: Vec<Vec3> = (0..n).into_par_iter().with_min_len(CHUNK).map(glow_of).collect();
        for (k, v) in glow.into_iter().enumerate() {
            linear[order[k] as usize] += v;
        }
        return;
    };
    let (w, h) = (g.width as usize, g.height as usize);
    let ray_at = |x: usize, y: usize| g.rank[y * w + x] as usize;
    // The glow of each pixel (row-major) worked out or shared so far.
    let mut glow: Vec<Option<Vec3>> = vec![None; w * h];
    let work = |pixels: Vec<(usize, usize)>, glow: &mut Vec<Option<Vec3>>| {
        let todo: Vec<(usize, usize)> = pixels.into_iter().filter(|&(x, y)| glow[y * w + x].is_none()).collect();
        let values: Vec<Vec3> = todo.par_iter().with_min_len(CHUNK / 8).map(|&(x, y)| glow_of(ray_at(x, y))).collect();
        for ((x, y), v) in todo.into_iter().zip(values) {
            glow[y * w + x] = Some(v);
        }
    };
    // The blocks of the first level, [`BLOCK`] pixels a side (fewer at the last row and column).
    let mut blocks: Vec<Block> = Vec::new();
    for y0 in (0..h.saturating_sub(1).max(1)).step_by(BLOCK) {
        for x0 in (0..w.saturating_sub(1).max(1)).step_by(BLOCK) {
            blocks.push((x0, (x0 + BLOCK).min(w - 1), y0, (y0 + BLOCK).min(h - 1)));
        }
    }
    let middle = |x0: usize, x1: usize, y0: usize, y1: usize| ((x0 + x1).div_ceil(2), (y0 + y1).div_ceil(2));
    // The blocks' corners and middles, worked out before a block is judged.
    let corners = |b: &[Block]| -> Vec<(usize, usize)> {
        let mut c: Vec<(usize, usize)> = b
            .iter()
            .flat_map(|&(x0, x1, y0, y1)| [(x0, y0), (x1, y0), (x0, y1), (x1, y1), middle(x0, x1, y0, y1)])
            .collect();
        c.sort_unstable();
        c.dedup();
        c
    };
    let least = LAMP_HALO_LEAST / exposure;
    while !blocks.is_empty() {
        work(corners(&blocks), &mut glow);
        let known = &glow;
        let value = |x: usize, y: usize| known[y * w + x].unwrap_or(Vec3::ZERO);
        // Per block: the pixels it shares its corners' glow with, or the four blocks it splits into, or (2 × 2 and
        // smaller) the pixels that work out their own.
        let decided: Vec<Decision> = blocks
            .par_iter()
            .map(|&(x0, x1, y0, y1)| {
                let cs = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)];
                let ks = cs.map(|(x, y)| ray_at(x, y));
                let vs = cs.map(|(x, y)| value(x, y));
                let alike_rays = ks.iter().all(|&k| met[k] == met[ks[0]]);
                let sums = vs.map(|v| v.element_sum());
                let (lo, hi) = sums.iter().fold((f32::INFINITY, 0.0f32), |(lo, hi), &s| (lo.min(s), hi.max(s)));
                let bilinear = |x: usize, y: usize| {
                    let (fx, fy) =
                        ((x - x0) as f32 / (x1 - x0).max(1) as f32, (y - y0) as f32 / (y1 - y0).max(1) as f32);
                    (vs[0] * (1.0 - fx) + vs[1] * fx) * (1.0 - fy) + (vs[2] * (1.0 - fx) + vs[3] * fx) * fy
                };
                // The middle pixel's own glow against the corners' bilinear mean there: the curvature the corners
                // alone cannot tell (between two lamps the glow dips where the corners agree).
                let (xm, ym) = middle(x0, x1, y0, y1);
                let (own_mid, mean_mid) = (value(xm, ym).element_sum(), bilinear(xm, ym).element_sum());
                let alike_glow = (hi - lo <= ALIKE_GLOW * hi
                    && met[ray_at(xm, ym)] == met[ks[0]]
                    && (own_mid - mean_mid).abs() <= MIDDLE_ERROR * own_mid)
                    || hi <= 0.1 * least;
                let lamp_inside = alike_rays && alike_glow && {
                    // The block's middle ray, and the farthest its corner rays stray from it at a lamp's distance.
                    let (om, dm) = ray(ray_at(xm, ym));
                    lamps.iter().any(|lamp| {
                        let t0 = (lamp.centre - om).dot(dm);
                        if !(t0 > 0.0) {
                            return false;
                        }
                        let across = (lamp.centre - om - dm * t0).length();
                        let spread = ks
                            .iter()
                            .map(|&k| {
                                let (o, d) = ray(k);
                                ((o + d * t0) - (om + dm * t0)).length()
                            })
                            .fold(0.0f32, f32::max);
                        across <= 2.0 * spread
                    })
                };
                if alike_rays && alike_glow && !lamp_inside {
                    let mut shared = Vec::new();
                    let mut own = Vec::new();
                    for y in y0..=y1 {
                        for x in x0..=x1 {
                            let i = y * w + x;
                            if known[i].is_some() {
                                continue;
                            }
                            if met[ray_at(x, y)] != met[ks[0]] {
                                own.push((x, y));
                                continue;
                            }
                            shared.push((i, bilinear(x, y)));
                        }
                    }
                    return (shared, own, Vec::new());
                }
                let side = (x1 - x0).max(y1 - y0);
                if side <= 2 || x1 == x0 || y1 == y0 {
                    let own = (y0..=y1).flat_map(|y| (x0..=x1).map(move |x| (x, y))).collect();
                    return (Vec::new(), own, Vec::new());
                }
                let mut split = Vec::new();
                for (a0, a1) in [(x0, xm), (xm, x1)] {
                    for (b0, b1) in [(y0, ym), (ym, y1)] {
                        if a1 > a0 && b1 > b0 {
                            split.push((a0, a1, b0, b1));
                        }
                    }
                }
                (Vec::new(), Vec::new(), split)
            })
            .collect();
        let mut own = Vec::new();
        let mut next = Vec::new();
        for (shared, o, split) in decided {
            for (i, v) in shared {
                glow[i].get_or_insert(v);
            }
            own.extend(o);
            next.extend(split);
        }
        work(own, &mut glow);
        blocks = next;
    }
    // (Every pixel is a block's: none is left, but none is lost if one were.)
    let left: Vec<(usize, usize)> = (0..w * h).filter(|&i| glow[i].is_none()).map(|i| (i % w, i / w)).collect();
    work(left, &mut glow);
    for (i, v) in glow.into_iter().enumerate() {
        linear[i] += v.unwrap_or(Vec3::ZERO);
    }
}
