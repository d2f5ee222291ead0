//! Batch ray casting over a [`Scene`]: closest hits ([`Scene::cast_rays`]) and shadow rays
//! ([`Scene::occluded_rays`]) in parallel chunks over rayon.
//!
//! Each chunk prepares its rays (normalising directions, noting the first invalid one so the batch fails with an
//! error naming it), lets the sea shortcuts settle what they can ([`crate::sea`]: rays rising clear of
//! everything, shadow rays from open water), and traces the rest as packets of [`PACKET`] coherent rays or one by
//! one; both give each ray the same hit.

use super::{Hit, RayHits, Scene, Scratch, NO_HIT};
use crate::bvh::{Packet, PACKET};
use crate::error::{MmusvError, Result};
use crate::ray::{prepare_lanes, RayPrep};
use crate::sea::{Horizon, SunMask, WaterHit};
use crate::simd::Level;
use parry3d::math::Vec3;
use rayon::prelude::*;

impl Scene {
    /// Casts a batch of rays in parallel.
    ///
    /// * `origins`, `dirs`: the same length; finite; directions non-zero (normalised here).
    /// * `max_range`: metres, `> 0` (may be infinite).
    ///
    /// Errors name the first offending ray.
    pub fn cast_rays(&self, origins: &[[f32; 3]], dirs: &[[f32; 3]], max_range: f32) -> Result<RayHits> {
        self.cast_rays_over(origins, dirs, max_range, None)
    }

    /// [`Scene::cast_rays`] for sensors to which the water is no target (a radar, whose sea echo is clutter drawn
    /// per cell): each ray's closest hit on anything but the sea, where the sea does not stop the ray first; a ray
    /// that meets the sea first, or nothing, is a miss. The same as [`Scene::cast_rays`] with its hits on the sea
    /// turned into misses (to a tie between the two distances), but over a wave surface the surface is only asked
    /// whether it stops a ray before the thing it hit, not where it meets every ray: a ray that hits nothing else
    /// (most of a radar's, over open water) is never marched through the waves, and a descending ray from above
    /// the crests is walked through the tree only down to the lowest trough.
    pub fn cast_rays_to_targets(&self, origins: &[[f32; 3]], dirs: &[[f32; 3]], max_range: f32) -> Result<RayHits> {
        self.cast(origins, dirs, max_range, None, true)
    }

    /// [`Scene::cast_rays`] with each ray's wave-surface hit already known where `water(k)` says so for ray `k`
    /// (from [`crate::sea::Raster::resolve`] with the same `max_range`, asked as each ray is traced, so the
    /// answers need no pass and no array of their own; [`WaterHit::Unknown`] marches): the same hits, without
    /// marching the known rays through the waves. Ignored without a wave surface.
    pub fn cast_rays_over(
        &self,
        origins: &[[f32; 3]],
        dirs: &[[f32; 3]],
        max_range: f32,
        water: Option<&KnownWater<'_>>,
    ) -> Result<RayHits> {
        self.cast(origins, dirs, max_range, water, false)
    }

    /// [`Scene::cast_rays_over`], or with `targets` [`Scene::cast_rays_to_targets`].
    fn cast(
        &self,
        origins: &[[f32; 3]],
        dirs: &[[f32; 3]],
        max_range: f32,
        water: Option<&KnownWater<'_>>,
        targets: bool,
    ) -> Result<RayHits> {
        check_batch(origins, dirs, max_range)?;
        let water = water.filter(|_| self.waves.is_some());
        let mut out = RayHits::zeroed(origins.len());
        let limit = if max_range.is_finite() { max_range } else { f32::MAX };
        // Rays that all leave one point (a camera's pixels): its horizon settles those rising over everything.
        let horizon = self.batch_horizon(origins);
        let horizon = horizon.as_ref();
        let bad = (
            out.distance.par_chunks_mut(CHUNK),
            out.instance.par_chunks_mut(CHUNK),
            out.triangle.par_chunks_mut(CHUNK),
            out.normal.par_chunks_mut(3 * CHUNK),
            out.class.par_chunks_mut(CHUNK),
            out.backface.par_chunks_mut(CHUNK),
            origins.par_chunks(CHUNK),
            dirs.par_chunks(CHUNK),
        )
            .into_par_iter()
            .enumerate()
            .map(|(k, (dist, inst, tri, nrm, cls, back, o, d))| {
                let out = ChunkOut { dist, inst, tri, nrm, cls, back };
                let water = water.map(|w| (w, k * CHUNK));
                BadRays::offset(trace_chunk(self, o, d, (limit, targets), horizon, water, out), k * CHUNK)
            })
            .reduce(BadRays::default, BadRays::min);
        bad.check(origins, dirs)?;
        Ok(out)
    }

    /// The [`Horizon`] of the batch's one origin, when every ray leaves the same point and there are enough of
    /// them to pay for building it.
    fn batch_horizon(&self, origins: &[[f32; 3]]) -> Option<Horizon> {
        let o0 = *origins.first()?;
        if origins.len() < HORIZON_MIN_RAYS || origins.iter().any(|o| *o != o0) {
            return None;
        }
        self.horizon(o0)
    }

    /// Shadow-ray batch: for each ray, whether anything is hit with `0 < t < max_range` (see
    /// [`Scene::occluded_with`]). Same argument rules and errors as [`Scene::cast_rays`].
    pub fn occluded_rays(&self, origins: &[[f32; 3]], dirs: &[[f32; 3]], max_range: f32) -> Result<Vec<bool>> {
        check_batch(origins, dirs, max_range)?;
        let mut out = vec![false; origins.len()];
        let limit = if max_range.is_finite() { max_range } else { f32::MAX };
        // Shadow rays all towards one sun: the sea's sun mask settles those that start over open water.
        let mask = match (&self.sea, dirs.first()) {
            (Some(sea), Some(d0)) if dirs.iter().all(|d| d == d0) => sea.sun_mask(unit_direction(d0)),
            _ => None,
        };
        let mask = mask.as_deref();
        let bad = out
            .par_chunks_mut(CHUNK)
            .zip(origins.par_chunks(CHUNK))
            .zip(dirs.par_chunks(CHUNK))
            .enumerate()
            .map(|(k, ((out, o), d))| BadRays::offset(occlusion_chunk(self, o, d, limit, mask, out), k * CHUNK))
            .reduce(BadRays::default, BadRays::min);
        bad.check(origins, dirs)?;
        Ok(out)
    }
}

/// The wave-surface hit of batch ray `k` where it is known ([`Scene::cast_rays_over`]).
pub type KnownWater<'a> = dyn Fn(usize) -> WaterHit + Sync + 'a;

/// Fewest rays from one point for which [`Scene::cast_rays`] builds that point's [`Horizon`] (about a millisecond).
const HORIZON_MIN_RAYS: usize = 4096;

/// Rays per rayon task: large enough to amortise scheduling, small enough to balance.
const CHUNK: usize = 512;

/// Rays traced as one packet must start within this many metres of the packet's first ray (camera pixels share
/// an origin; neighbouring shadow-ray or top-view origins lie close together).
const COHERENT_RADIUS: f32 = 4.0;
/// ... and point within ≈ 11° of its direction.
const COHERENT_COS: f32 = 0.98;

/// Output slices of one chunk of [`Scene::cast_rays`].
struct ChunkOut<'a> {
    dist: &'a mut [f32],
    inst: &'a mut [i32],
    tri: &'a mut [i32],
    nrm: &'a mut [f32],
    cls: &'a mut [u16],
    back: &'a mut [bool],
}

impl ChunkOut<'_> {
    /// Ray `i` hit nothing.
    #[inline(always)]
    fn miss(&mut self, i: usize) {
        self.dist[i] = f32::INFINITY;
        self.inst[i] = NO_HIT;
        self.tri[i] = NO_HIT;
    }

    /// Ray `i` (unit direction `dir`) hit `hit`; with `targets`, a hit on the sea is left a miss.
    #[inline(always)]
    fn hit(&mut self, scene: &Scene, i: usize, dir: Vec3, hit: &Hit, targets: bool) {
        if targets && scene.sea.as_ref().is_some_and(|s| s.instance == hit.instance) {
            return;
        }
        let (n, c) = scene.hit_normal_class(hit);
        self.dist[i] = hit.distance;
        self.inst[i] = hit.instance as i32;
        self.tri[i] = hit.triangle as i32;
        self.nrm[3 * i..3 * i + 3].copy_from_slice(&n.to_array());
        self.cls[i] = c;
        self.back[i] = n.dot(dir) > 0.0;
    }
}

/// Whether the prepared rays are worth tracing as one packet (see [`COHERENT_RADIUS`], [`COHERENT_COS`]).
#[inline(always)]
fn coherent(rays: &[RayPrep]) -> bool {
    let Some(r0) = rays.first() else { return false };
    rays.len() > 1
        && rays.iter().all(|r| {
            let dc = r.d[0] * r0.d[0] + r.d[1] * r0.d[1] + r.d[2] * r0.d[2];
            let o2 = (r.o[0] - r0.o[0]).powi(2) + (r.o[1] - r0.o[1]).powi(2) + (r.o[2] - r0.o[2]).powi(2);
            dc >= COHERENT_COS && o2 <= COHERENT_RADIUS * COHERENT_RADIUS
        })
}

crate::dispatch! {
    /// Traces one chunk of rays (normalising each direction) and stores the hits: coherent groups of
    /// [`PACKET`] consecutive rays as packets, the others one by one; both give each ray the same hit. With
    /// `targets`, the hits of [`Scene::cast_rays_to_targets`].
    fn trace_chunk[lv](
        scene: &Scene,
        o: &[[f32; 3]],
        d: &[[f32; 3]],
        limit_targets: (f32, bool),
        horizon: Option<&Horizon>,
        water: Option<(&KnownWater<'_>, usize)>,
        out: ChunkOut<'_>,
    ) -> BadRays {
        let (limit, targets) = limit_targets;
        let mut scratch = Scratch::default();
        let mut packet = Packet::default();
        let mut bad = BadRays::default();
        let mut out = out;
        for start in (0..o.len()).step_by(PACKET) {
            let end = (start + PACKET).min(o.len());
            for i in start..end {
                out.miss(i);
            }
            let Some(mut rays) = prepare(o, d, start..end, &mut bad) else { continue };
            let rays = &mut rays[..end - start];
            // Whether each ray leaves the water, worked out once for the sea shortcut and the wave test alike.
            scene.mark_leaves(rays);
            let rays = &*rays;
            let mut sky = [false; PACKET];
            let mut any_sky = false;
            for (r, ray) in rays.iter().enumerate() {
                sky[r] = scene.sea_sky(ray, limit, horizon);
                any_sky |= sky[r];
            }
            if !any_sky {
                // Nothing for the sea shortcut: trace the rays in place.
                trace_rest(lv, scene, rays, |j| start + j, (limit, water, targets), &mut scratch, &mut packet, &mut out);
                continue;
            }
            // Rays the sea shortcut settles are misses; the others are traced (as a packet when coherent).
            let mut rest = [rays[0]; PACKET];
            let mut lane = [0usize; PACKET];
            let mut n = 0;
            for (r, ray) in rays.iter().enumerate() {
                if !sky[r] {
                    rest[n] = *ray;
                    lane[n] = r;
                    n += 1;
                }
            }
            let at = |j: usize| start + lane[j];
            trace_rest(lv, scene, &rest[..n], at, (limit, water, targets), &mut scratch, &mut packet, &mut out);
        }
        bad
    }
}

/// Traces `rays` fully (as one packet when coherent, else one by one) and stores each hit at chunk index
/// `at(j)` for ray `j`; with `targets`, the hits of [`Scene::cast_rays_to_targets`].
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn trace_rest<L: Level>(
    lv: L,
    scene: &Scene,
    rays: &[RayPrep],
    at: impl Fn(usize) -> usize,
    (limit, water, targets): (f32, Option<(&KnownWater<'_>, usize)>, bool),
    scratch: &mut Scratch,
    p: &mut Packet,
    out: &mut ChunkOut<'_>,
) {
    if targets && scene.waves.is_some() {
        return trace_targets(lv, scene, rays, at, limit, scratch, p, out);
    }
    // The rays' wave-surface hits where the raster knows them, else marched.
    let known = |j: usize| water.map_or(WaterHit::Unknown, |(w, base)| w(base + at(j)));
    if coherent(rays) && p.fill(rays, limit) {
        let water = scene.known_wave_hits_packet(p, known);
        let (inst, tri) = scene.cast_packet_over(lv, p, water, scratch);
        for (j, ray) in rays.iter().enumerate() {
            if inst[j] != u32::MAX {
                let hit = Hit { distance: p.best[j], instance: inst[j], triangle: tri[j] };
                out.hit(scene, at(j), Vec3::from_array(ray.d), &hit, targets);
            }
        }
    } else {
        for (j, ray) in rays.iter().enumerate() {
            let water = scene.known_wave_hit(ray, known(j), limit);
            let hit = scene.cast_prepared_over(lv, ray, water, limit, scratch);
            if let Some(hit) = hit {
                out.hit(scene, at(j), Vec3::from_array(ray.d), &hit, targets);
            }
        }
    }
}

/// [`trace_rest`] of [`Scene::cast_rays_to_targets`] over a wave surface: each ray's closest hit among the
/// instances (the sea's stands aside for the surface), kept unless the surface stops the ray before it. A ray that
/// descends from above the crests crosses the surface before it sinks below the lowest trough, so its walk ends
/// there (with a margin against rounding: what lies beyond is behind the water either way, and anything found
/// short of it is checked against the surface).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn trace_targets<L: Level>(
    lv: L,
    scene: &Scene,
    rays: &[RayPrep],
    at: impl Fn(usize) -> usize,
    limit: f32,
    scratch: &mut Scratch,
    p: &mut Packet,
    out: &mut ChunkOut<'_>,
) {
    let Some(w) = scene.waves.as_deref() else { return };
    let (zmin, zmax) = (w.zmin(), w.zmax());
    let reach = |ray: &RayPrep| {
        if ray.d[2] < 0.0 && ray.o[2] > zmax {
            let t = (zmin - ray.o[2]) / ray.d[2];
            limit.min(t + 1e-3 * (1.0 + t))
        } else {
            limit
        }
    };
    // The water stops ray `j` before `t`: then it has no target.
    let water_first = |ray: &RayPrep, t: f32| scene.wave_hit(ray, t).is_some();
    if coherent(rays) && p.fill(rays, limit) {
        for (j, ray) in rays.iter().enumerate() {
            p.best[j] = reach(ray);
        }
        let (inst, tri) = scene.cast_packet_over(lv, p, None, scratch);
        for (j, ray) in rays.iter().enumerate() {
            if inst[j] != u32::MAX && !water_first(ray, p.best[j]) {
                let hit = Hit { distance: p.best[j], instance: inst[j], triangle: tri[j] };
                out.hit(scene, at(j), Vec3::from_array(ray.d), &hit, true);
            }
        }
    } else {
        for (j, ray) in rays.iter().enumerate() {
            let hit = scene.cast_prepared_over(lv, ray, None, reach(ray), scratch);
            if let Some(hit) = hit.filter(|h| !water_first(ray, h.distance)) {
                out.hit(scene, at(j), Vec3::from_array(ray.d), &hit, true);
            }
        }
    }
}

crate::dispatch! {
    /// Shadow-ray queries of one chunk (directions normalised here), packets where the rays are coherent.
    /// `mask`, when given, is the sea's sun mask for the direction every ray of the chunk has.
    fn occlusion_chunk[lv](
        scene: &Scene,
        o: &[[f32; 3]],
        d: &[[f32; 3]],
        limit: f32,
        mask: Option<&SunMask>,
        out: &mut [bool],
    ) -> BadRays {
        let mut scratch = Scratch::default();
        let mut packet = Packet::default();
        let mut bad = BadRays::default();
        for start in (0..o.len()).step_by(PACKET) {
            let end = (start + PACKET).min(o.len());
            // Rays the sun mask settles need no preparation: it reads their origins alone (the direction is
            // the batch's one, valid since it has a mask).
            let mut todo = [0usize; PACKET];
            let mut m = 0;
            for i in start..end {
                if scene.sun_clear(mask, o[i]) {
                    out[i] = false;
                } else {
                    todo[m] = i;
                    m += 1;
                }
            }
            if m == 0 {
                continue;
            }
            let Some(mut rays) = prepare(o, d, todo[..m].iter().copied(), &mut bad) else { continue };
            scene.mark_leaves(&mut rays[..m]);
            let mut rest = [rays[0]; PACKET];
            let mut lane = [0usize; PACKET];
            let mut n = 0;
            for (j, ray) in rays[..m].iter().enumerate() {
                if scene.sea_clear(ray, limit) {
                    out[todo[j]] = false;
                } else {
                    rest[n] = *ray;
                    lane[n] = todo[j];
                    n += 1;
                }
            }
            let rest = &rest[..n];
            if coherent(rest) && packet.fill(rest, limit) {
                scene.occluded_packet_with(lv, &mut packet, &mut scratch);
                for j in 0..n {
                    out[lane[j]] = packet.best[j] < 0.0;
                }
            } else {
                for (j, ray) in rest.iter().enumerate() {
                    out[lane[j]] = scene.occluded_prepared(lv, ray, limit, &mut scratch);
                }
            }
        }
        bad
    }
}

/// Prepares the rays `idx` of a chunk (at most [`PACKET`]; directions normalised) as lanes `0..idx.len()`, or
/// records the first invalid origin and direction in `bad` and returns `None` (the batch then fails with an
/// error naming the ray).
///
/// The arithmetic runs across the rays (lanes), so it vectorises; each ray gets exactly
/// `RayPrep::new(o, unit_direction(d))` (the same correctly rounded operations in the same order).
#[inline(always)]
fn prepare(
    o: &[[f32; 3]],
    d: &[[f32; 3]],
    idx: impl Iterator<Item = usize>,
    bad: &mut BadRays,
) -> Option<[RayPrep; PACKET]> {
    let mut ok = true;
    let mut dir = [[1f64; PACKET], [0f64; PACKET], [0f64; PACKET]];
    let mut origin = [[0f32; 3]; PACKET];
    for (j, i) in idx.enumerate() {
        let (oi, di) = (&o[i], &d[i]);
        let bad_o = !(oi[0].is_finite() && oi[1].is_finite() && oi[2].is_finite());
        let bad_d = !(di[0].is_finite() && di[1].is_finite() && di[2].is_finite())
            || (di[0] == 0.0 && di[1] == 0.0 && di[2] == 0.0);
        if bad_o || bad_d {
            bad.note(i, bad_o, bad_d);
            ok = false;
            continue;
        }
        origin[j] = *oi;
        for a in 0..3 {
            dir[a][j] = di[a] as f64;
        }
    }
    if !ok {
        return None;
    }
    // unit_direction, across the rays.
    let mut u = [[0f32; PACKET]; 3];
    for j in 0..PACKET {
        let (x, y, z) = (dir[0][j], dir[1][j], dir[2][j]);
        let n = (x * x + y * y + z * z).sqrt();
        u[0][j] = (x / n) as f32;
        u[1][j] = (y / n) as f32;
        u[2][j] = (z / n) as f32;
    }
    Some(prepare_lanes(&origin, &u))
}

/// The first invalid origin and direction of a batch (indices within the chunk, then the batch).
#[derive(Debug, Default, Clone, Copy)]
struct BadRays {
    origin: Option<usize>,
    direction: Option<usize>,
}

impl BadRays {
    fn note(&mut self, i: usize, origin: bool, direction: bool) {
        if origin && self.origin.is_none() {
            self.origin = Some(i);
        }
        if direction && self.direction.is_none() {
            self.direction = Some(i);
        }
    }

    fn offset(self, by: usize) -> Self {
        Self { origin: self.origin.map(|i| i + by), direction: self.direction.map(|i| i + by) }
    }

    fn min(a: Self, b: Self) -> Self {
        let m = |x: Option<usize>, y: Option<usize>| match (x, y) {
            (Some(x), Some(y)) => Some(x.min(y)),
            (x, None) => x,
            (None, y) => y,
        };
        Self { origin: m(a.origin, b.origin), direction: m(a.direction, b.direction) }
    }

    /// The error for the first bad origin, else the first bad direction (checked in that order, as the rays are
    /// given).
    fn check(self, origins: &[[f32; 3]], dirs: &[[f32; 3]]) -> Result<()> {
        if let Some(i) = self.origin {
            return Err(MmusvError::input(format!("origins[{i}]"), format!("{:?} is not finite", origins[i])));
        }
        if let Some(i) = self.direction {
            return Err(MmusvError::input(
                format!("directions[{i}]"),
                format!("{:?} is zero-length or not finite; directions must be finite and non-zero", dirs[i]),
            ));
        }
        Ok(())
    }
}

/// `d / |d|` computed in `f64`, so any finite non-zero `f32` direction (even 1e-30 or 1e30 long) normalises
/// exactly instead of under- or overflowing in `f32`.
#[inline]
pub(super) fn unit_direction(d: &[f32; 3]) -> [f32; 3] {
    let (x, y, z) = (d[0] as f64, d[1] as f64, d[2] as f64);
    let n = (x * x + y * y + z * z).sqrt();
    [(x / n) as f32, (y / n) as f32, (z / n) as f32]
}

/// The checks of a batch that need no pass over the rays (each ray is checked as it is traced).
fn check_batch(origins: &[[f32; 3]], dirs: &[[f32; 3]], max_range: f32) -> Result<()> {
    if origins.len() != dirs.len() {
        return Err(MmusvError::input(
            "directions",
            format!("{} directions for {} origins; give one direction per origin", dirs.len(), origins.len()),
        ));
    }
    if max_range.is_nan() || max_range <= 0.0 {
        return Err(MmusvError::input("max_range", format!("{max_range} is not allowed; give a range > 0 metres")));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The lane-wise preparation gives every ray exactly what `RayPrep::new(o, unit_direction(d))` gives it:
    /// random directions, axis-aligned ones, tiny and signed-zero components, ties between axes, short packets.
    #[test]
    fn prepare_matches_ray_by_ray_preparation() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let special = crate::ray::tests::SPECIAL_DIRECTIONS;
        let mut o = Vec::new();
        let mut d = Vec::new();
        for i in 0..20_000 {
            o.push([rng.random_range(-500.0..500.0), rng.random_range(-500.0..500.0), rng.random_range(-5.0..50.0)]);
            let dir = if i % 3 == 0 {
                special[(i / 3) % special.len()]
            } else {
                [rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)]
            };
            d.push(dir);
        }
        for start in (0..o.len()).step_by(PACKET) {
            // Short packets too: every length from 1 to PACKET.
            let end = (start + 1 + (start / PACKET) % PACKET).min(o.len());
            let mut bad = BadRays::default();
            let Some(rays) = prepare(&o, &d, start..end, &mut bad) else { unreachable!("valid rays") };
            for (j, i) in (start..end).enumerate() {
                assert_eq!(rays[j], RayPrep::new(o[i], unit_direction(&d[i])), "ray {i}: {:?} {:?}", o[i], d[i]);
            }
        }
    }

    #[test]
    fn prepare_names_the_first_bad_ray() {
        let o = vec![[0.0; 3], [f32::NAN, 0.0, 0.0], [0.0; 3], [0.0; 3]];
        let d = vec![[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0; 3], [f32::INFINITY, 0.0, 0.0]];
        let mut bad = BadRays::default();
        assert!(prepare(&o, &d, 0..4, &mut bad).is_none());
        assert_eq!((bad.origin, bad.direction), (Some(1), Some(2)));
    }
}
