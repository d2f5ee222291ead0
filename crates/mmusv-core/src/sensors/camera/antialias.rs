//! Anti-aliasing of a camera's shaded image where it matters: a pixel at a visible edge (a 4-neighbour on another
//! surface, instance, class or material, or, off the water, at a depth differing by more than 5 %, whose shading
//! differs from that neighbour's by more than [`radiance::alike`] allows) gets [`super::Quality::edge_samples`]
//! stratified sub-pixel rays (a `√s × √s` grid, jittered by the frame's seed). Where all of them see the pixel
//! centre's surface (the edge runs through the neighbour) the pixel keeps its centre's shading; elsewhere it
//! takes the mean of its samples' radiance, each shaded like a pixel at `high` quality (traced reflections above
//! `draft`). Depth, class and instance stay those of the centre.

use super::glossy::Blurred;
use super::radiance::{self, Reflections};
use super::{Camera, CameraFrame, WorldRays};
use crate::error::Result;
use crate::geometry::RigidPose;
use crate::scene::{RayHits, Scene};
use crate::sensors::shade::Shader;
use parry3d::math::Vec3;
use rayon::prelude::*;

/// What the pixel centres saw: the frame (row-major depth, class, instance), each pixel's [`surface_key`], the
/// centre rays' hits (in trace order) and, with glossy reflections, the blurred reflections.
pub(super) struct Centres<'a> {
    pub frame: &'a CameraFrame,
    pub surface: &'a [u64],
    pub hits: &'a RayHits,
    pub reflected: Option<&'a Blurred>,
}

impl Camera {
    /// Replaces the radiance of the edge pixels of `linear` (row-major, linear RGB) by the mean of their
    /// sub-pixel samples (see the module docs); `shading` is the shader, whether shadows are cast, the seed and the
    /// view's exposure (the edge test compares pixels as shown).
    pub(super) fn antialias(
        &self,
        scene: &Scene,
        pose: &RigidPose,
        shading: (&Shader, bool, u64, f32),
        centres: Centres<'_>,
        linear: &mut [Vec3],
    ) -> Result<()> {
        let (shader, shadows, seed, exposure) = shading;
        let Centres { frame, surface, hits, reflected } = centres;
        let q = self.cfg.image.quality;
        let s = q.edge_samples();
        let edges = edge_pixels(frame, surface, |a, b| !radiance::alike(linear[a], linear[b], exposure));
        if edges.is_empty() {
            return Ok(());
        }
        let (so, sd) = self.sample_rays(pose, &edges, s, seed);
        let shits = scene.cast_rays(&so, &sd, self.cfg.range_max)?;
        let per = s as usize;
        // A pixel whose samples all see its centre's surface (the edge runs through its neighbour) keeps its
        // centre's shading; the others are shaded sample by sample.
        let key = |j: usize| {
            let m = scene.material_index(shits.instance[j], shits.triangle[j]);
            surface_key(shits.instance[j], shits.class[j], m)
        };
        let mixed: Vec<u32> = (0..edges.len())
            .into_par_iter()
            .filter(|&e| {
                let i = edges[e] as usize;
                let t = hits.distance[self.rank[i] as usize];
                (e * per..(e + 1) * per).any(|j| {
                    let tj = shits.distance[j];
                    key(j) != surface[i] || frame.semantic[i] != 1 && t.is_finite() && (tj - t).abs() > 0.05 * tj.min(t)
                })
            })
            .map(|e| e as u32)
            .collect();
        let rays: Vec<u32> =
            mixed.iter().flat_map(|&e| (e as usize * per..(e as usize + 1) * per).map(|j| j as u32)).collect();
        let (mo, md): (Vec<[f32; 3]>, Vec<[f32; 3]>) = rays.iter().map(|&j| (so[j as usize], sd[j as usize])).unzip();
        let mhits = shits.select(&rays);
        // A water sample reflects the blurred reflections at its own position in the image (the lobe is far wider
        // than a pixel; no water within reach: the sky along its mirror direction); without the blur, its own
        // traced reflection.
        let given = |j: usize| {
            let (i, sub) = (edges[mixed[j / per] as usize], (j % per) as u32);
            let [u, v] = self.sample_point(i, sub, s, seed);
            reflected.and_then(|b| b.at(u as f32, v as f32))
        };
        let refl = match (q.reflections(), reflected) {
            (false, _) => Reflections::Sky,
            (true, None) => Reflections::Every,
            (true, Some(_)) => Reflections::Given(&given),
        };
        let samples = radiance::radiance(scene, shader, shadows, refl, None, None, (&mo, &md, &mhits))?.radiance;
        for (m, &e) in mixed.iter().enumerate() {
            let sum: Vec3 = samples[m * per..(m + 1) * per].iter().copied().sum();
            linear[edges[e as usize] as usize] = sum / s as f32;
        }
        Ok(())
    }

    /// World rays of `samples` stratified sub-pixel positions (a `√s × √s` grid, jittered by `seed`) in every
    /// pixel of `pixels` (row-major indices), pixel by pixel.
    fn sample_rays(&self, pose: &RigidPose, pixels: &[u32], samples: u32, seed: u64) -> WorldRays {
        let g = (samples as f64).sqrt().round().max(1.0) as u32;
        let cap = pixels.len() * (g * g) as usize;
        let (mut o, mut d) = (Vec::with_capacity(cap), Vec::with_capacity(cap));
        for &i in pixels {
            for k in 0..g * g {
                let [su, sv] = self.sample_point(i, k, samples, seed);
                let (bo, bd) = self.body_ray(su, sv);
                o.push(pose.transform_point(Vec3::from_array(bo)).to_array());
                d.push(pose.transform_vector(Vec3::from_array(bd)).normalize().to_array());
            }
        }
        (o, d)
    }

    /// Image point (pixels) of sub-pixel sample `k` (row `k / √s`, column `k % √s` of the `√s × √s` grid,
    /// jittered by `seed`) of row-major pixel `i`.
    fn sample_point(&self, i: u32, k: u32, samples: u32, seed: u64) -> [f64; 2] {
        let g = (samples as f64).sqrt().round().max(1.0) as u32;
        let w = self.cfg.width;
        let (u, v) = ((i % w) as f64, (i / w) as f64);
        let (a, b) = (k / g, k % g);
        let key = (i as u64) << 8 | (a * g + b) as u64;
        let ju = crate::sensors::noise::uniform(seed, 0xAA, 2 * key);
        let jv = crate::sensors::noise::uniform(seed, 0xAA, 2 * key + 1);
        [u + (b as f64 + ju) / g as f64, v + (a as f64 + jv) / g as f64]
    }
}

/// Instance, class and material of a hit in one word (what the anti-aliasing compares).
#[inline]
pub(super) fn surface_key(instance: i32, class: u16, material: u16) -> u64 {
    (instance as u32 as u64) << 32 | (class as u64) << 16 | material as u64
}

/// Row-major indices of the pixels at a visible edge: a 4-neighbour on another surface (`surface`: instance,
/// class and material in one word) or, off the water, at a depth differing by more than 5 %, and whose centre
/// colour differs from that neighbour's (`contrast(a, b)`, so an edge between two surfaces that look alike,
/// [`radiance::alike`], keeps its one sample).
fn edge_pixels(frame: &CameraFrame, surface: &[u64], contrast: impl Fn(usize, usize) -> bool + Sync) -> Vec<u32> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    // Each pair of 4-neighbours once: bit 0 (1) of pixel `a` when `a` sees an edge towards `b`, bit 1 (2) when
    // `b` sees one towards `a` (the depth step counts from a pixel off the water only), for its right neighbour
    // in the low two bits and the one below in the next two. The geometric test runs over whole rows without
    // branches (so it runs in vector lanes); the colours are compared only where it finds an edge.
    let mut flags = vec![0u8; w * h];
    flags.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let i = y * w;
        let (s0, d0, c0) = (&surface[i..i + w], &frame.depth[i..i + w], &frame.semantic[i..i + w]);
        let right = s0.iter().zip(&s0[1..]).zip(d0.iter().zip(&d0[1..])).zip(c0.iter().zip(&c0[1..]));
        for (f, ((s, d), c)) in row.iter_mut().zip(right) {
            *f = geometric_pair((*s.0, *s.1), (*d.0, *d.1), (*c.0, *c.1));
        }
        if y + 1 < h {
            let j = i + w;
            let (s1, d1, c1) = (&surface[j..j + w], &frame.depth[j..j + w], &frame.semantic[j..j + w]);
            let down = s0.iter().zip(s1).zip(d0.iter().zip(d1)).zip(c0.iter().zip(c1));
            for (f, ((s, d), c)) in row.iter_mut().zip(down) {
                *f |= geometric_pair((*s.0, *s.1), (*d.0, *d.1), (*c.0, *c.1)) << 2;
            }
        }
        for (x, f) in row.iter_mut().enumerate() {
            if *f & 3 != 0 && !contrast(i + x, i + x + 1) {
                *f &= !3;
            }
            if *f & 12 != 0 && !contrast(i + x, i + x + w) {
                *f &= !12;
            }
        }
    });
    let flags = &flags;
    (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..w).filter_map(move |x| {
                let i = y * w + x;
                let edge =
                    flags[i] & (1 | 4) != 0 || (x > 0 && flags[i - 1] & 2 != 0) || (y > 0 && flags[i - w] & 8 != 0);
                edge.then_some(i as u32)
            })
        })
        .collect()
}

/// The geometric half of [`edge_pixels`]' test for neighbours `a` and `b` (their surface keys, depths and
/// classes): bit 0 when `a` sees an edge towards `b` (another surface, or a depth step of more than 5 % from `a`
/// off the water), bit 1 when `b` sees one towards `a`. Branch-free.
#[inline(always)]
fn geometric_pair((sa, sb): (u64, u64), (da, db): (f32, f32), (ca, cb): (u16, u16)) -> u8 {
    let other = sa != sb;
    let step = da.is_finite() & db.is_finite() & ((da - db).abs() > 0.05 * da.min(db));
    let from_a = other | (step & (ca != 1));
    let from_b = other | (step & (cb != 1));
    u8::from(from_a) | u8::from(from_b) << 1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The edge test written pixel by pixel, as the module docs state it.
    fn edges_by_definition(frame: &CameraFrame, surface: &[u64], contrast: impl Fn(usize, usize) -> bool) -> Vec<u32> {
        let (w, h) = (frame.width as usize, frame.height as usize);
        let sees_edge = |a: usize, b: usize| {
            let (da, db) = (frame.depth[a], frame.depth[b]);
            let step = da.is_finite() && db.is_finite() && (da - db).abs() > 0.05 * da.min(db);
            // (the contrast of a pair is asked with its left or upper pixel first)
            (surface[a] != surface[b] || step && frame.semantic[a] != 1) && contrast(a.min(b), a.max(b))
        };
        let mut out = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let mut nb = Vec::new();
                if x > 0 {
                    nb.push(i - 1);
                }
                if x + 1 < w {
                    nb.push(i + 1);
                }
                if y > 0 {
                    nb.push(i - w);
                }
                if y + 1 < h {
                    nb.push(i + w);
                }
                if nb.iter().any(|&j| sees_edge(i, j)) {
                    out.push(i as u32);
                }
            }
        }
        out
    }

    #[test]
    fn edge_pixels_follow_their_definition() {
        // Random frames with few surfaces, water (class 1), sky (infinite depth) and depth steps around 5 %, and
        // a contrast that refuses some pairs: every pixel as the definition says.
        for (seed, (w, h)) in [(1u64, (37usize, 23usize)), (2, (1, 9)), (3, (9, 1)), (4, (64, 48))] {
            let n = w * h;
            let u = |k: u64| crate::sensors::noise::uniform(seed, 7, k);
            let surface: Vec<u64> = (0..n).map(|i| (u(4 * i as u64) * 3.0) as u64).collect();
            let semantic: Vec<u16> = (0..n).map(|i| if u(4 * i as u64 + 1) < 0.4 { 1 } else { 3 }).collect();
            let depth: Vec<f32> = (0..n)
                .map(|i| {
                    if u(4 * i as u64 + 2) < 0.1 {
                        f32::INFINITY
                    } else {
                        100.0 * (1.0 + 0.1 * u(4 * i as u64 + 3) as f32)
                    }
                })
                .collect();
            let frame = CameraFrame {
                width: w as u32,
                height: h as u32,
                depth,
                semantic,
                instance: vec![0; n],
                rgb: Vec::new(),
                radiance: Vec::new(),
            };
            let contrast = |a: usize, b: usize| !(a * 31 + b * 17).is_multiple_of(5);
            let fast = edge_pixels(&frame, &surface, contrast);
            let slow = edges_by_definition(&frame, &surface, contrast);
            assert!(slow.len() > n / 10 || n < 20, "a frame with edges ({} of {n})", slow.len());
            assert_eq!(fast, slow, "{w} x {h}");
        }
    }
}
