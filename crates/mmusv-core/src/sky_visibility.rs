//! The sky's visibility over a mesh's own surfaces (ambient occlusion), baked once per mesh, so that the cameras'
//! image-based sky light (`sensors/shade/envlight.rs`) does not reach into a hull's recesses as onto its open decks.
//!
//! Model: **ambient occlusion** (Zhukov, Iones & Kronin 1998, "An ambient light illumination model", *Rendering
//! Techniques '98*, Springer, pp. 45–55; Landis 2002, "Production-ready global illumination", SIGGRAPH 2002
//! course 16 notes), split at the horizon. At a surface point `x` of normal `n`, for each part `P` of its
//! hemisphere, the directions above the mesh's local horizon (the sky's) and those below it (the ground's: the
//! environment's uniform light from below the horizon, `envlight.rs`),
//! `V_P(x) = ∫_P v(x, ω) (n·ω) dω / ∫_P (n·ω) dω`, with `v = 1` where the ray `x + tω` meets no triangle of the
//! mesh: the cosine-weighted share of that part through which `x` sees past the mesh. The shader
//! (`sensors/shade.rs`) scales the environment's irradiance from the sky by `V_sky` and that from the ground by
//! `V_ground`, taking each part's mean radiance over its open directions for its whole mean (exact under a uniform
//! sky and ground: `E = V_P · E_P(n)`), and its prefiltered specular light by [`specular_occlusion`] (Lagarde & de
//! Rousiers 2014, "Moving Frostbite to Physically Based Rendering 3.0", SIGGRAPH course notes, section 4.10.2) of
//! the part its reflection lobe leans into. One share for the whole hemisphere would take half the sky's light
//! from a wall standing on a deck, whose lower half sees the deck where it would see the darker sea.
//! The local horizon is the mesh's `z = 0` plane's: a vessel's roll and pitch of a few degrees tilt it.
//!
//! Estimator: [`RAYS`] directions cosine-distributed about the normal (Malley's method: stratified points of the
//! unit disc lifted onto the hemisphere; Pharr, Jakob & Humphreys, *Physically Based Rendering*, 3rd ed., section
//! 13.6.3), so that `V_P ≈` the share of those falling in `P` that leave the mesh (1 where none falls in it). A ray
//! whose first hit is a back face counts neither way: a vessel is built of overlapping closed parts, and a sample of
//! one part's face that lies inside another sees only that part's inside.
//!
//! Samples: per triangle a barycentric lattice of `r` subdivisions (`(r + 1)(r + 2)/2` nodes, corners and edges
//! included), `r` the triangle's longest edge over the mesh's sample spacing (at most [`MAX_DIVISIONS`]); a triangle
//! shorter than a spacing gets one sample ([`DETAIL_RAYS`] rays). The spacing is a fixed share of the mesh's size,
//! widened until the lattices hold at most [`MAX_SAMPLES`] beyond one a triangle. Each sample's rays leave from
//! points spread over its share of the triangle (its lattice cell, ±½ a step, or the whole of a one-sample
//! triangle), so that it holds the mean of `V` over that area, which the linear interpolation then spreads (a node
//! at the very foot of a wall, `V = ½` however low the wall, would darken a whole step around it). Every sample
//! draws the same stratified pattern (turn, jitter, origins), so that neighbouring samples on like geometry err
//! alike rather than as noise. A hit reads `V` interpolated linearly over the lattice's sub-triangle around it
//! ([`SkyVisibility::at`]). Deterministic: the values depend on the mesh alone, whatever the thread count.
//!
//! Checked against: a convex mesh (`V = 1` everywhere), the view factor of a floor element at distance `d` from the
//! foot of a perpendicular wall of height `h` and infinite length, `F = ½ (1 − d/√(d² + h²))`, `V_sky = 1 − F`
//! (Howell, *A Catalog of Radiation Heat Transfer Configuration Factors*; the tests below), and Mitsuba 3's path
//! tracing of a wall on a floor under the sky (`tests/reference/test_mitsuba_sky_visibility.py`).
//!
//! Not modelled: occlusion by other instances (a ship alongside a quay, one vessel under another's flare), the
//! light that the occluding surfaces send back (interreflection: the shading is direct light only), and the back
//! faces of open, one-sided parts, which read `V = 1`; an occluder wound inside out hides nothing.

use crate::mesh::Mesh;
use crate::ray::RayPrep;
use crate::scene::Scene;
use crate::sensors::radar_model::CLASS_WATER;
use parry3d::math::Vec3;
use rayon::prelude::*;
use std::sync::{Arc, Mutex};

/// Rays per sample of a lattice (a triangle at least a spacing long).
pub const RAYS: usize = 32;
/// Rays of the one sample of a triangle shorter than a spacing (a detail a few pixels across in any view that
/// shows the mesh whole).
pub const DETAIL_RAYS: usize = 16;
/// Most lattice subdivisions of one triangle's edge.
pub const MAX_DIVISIONS: u32 = 64;
/// Most lattice samples of one mesh beyond its one per triangle: the spacing widens until the lattices fit.
pub const MAX_SAMPLES: usize = 40_000;
/// Sample spacing as a share of the mesh's bounding-box diagonal (before any widening).
const SPACING_SHARE: f32 = 1.0 / 96.0;
/// Least sample spacing, metres.
const MIN_SPACING_M: f32 = 0.1;
/// The seed of the samples' strata (fixed: a mesh bakes to the same values in every run).
const SEED: u64 = 0x5eed_5c1e;
/// The index every sample draws its strata's turn, jitter and origins at (one pattern for all: [`bake_chunk`]).
const PATTERN: u64 = 0;
/// The first of the noise streams of the rays' origins (two per ray, after the directions' streams).
const ORIGIN_STREAM: u64 = 1 << 16;

/// The baked sky visibility of one mesh: per triangle a lattice of values ([`SkyVisibility::at`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SkyVisibility {
    /// Per triangle: the offset of its values in `values` and its subdivisions (0: one value, at the centroid).
    lattices: Vec<(u32, u8)>,
    /// `[V_sky, V_ground]` per sample, each in `[0, 1]` (module docstring).
    values: Vec<[f32; 2]>,
}

/// Samples of a lattice of `r` subdivisions (one at the centroid for `r = 0`).
#[inline]
fn lattice_len(r: u32) -> usize {
    if r == 0 {
        1
    } else {
        ((r + 1) * (r + 2) / 2) as usize
    }
}

impl SkyVisibility {
    /// Bakes the sky visibility of `mesh` (its own triangles occlude; nothing else).
    pub fn bake(mesh: &Mesh) -> Self {
        let faces = mesh.num_triangles();
        let size = (mesh.aabb().maxs - mesh.aabb().mins).length();
        let longest: Vec<f32> = (0..faces as u32)
            .map(|k| {
                let [a, b, c] = mesh.triangle(k).v;
                (b - a).length().max((c - b).length()).max((a - c).length())
            })
            .collect();
        let mut spacing = (size * SPACING_SHARE).max(MIN_SPACING_M);
        let divisions = |spacing: f32| -> Vec<u32> {
            longest
                .iter()
                .map(|&l| if l < spacing { 0 } else { ((l / spacing).ceil() as u32).min(MAX_DIVISIONS) })
                .collect()
        };
        let mut r = divisions(spacing);
        while r.iter().map(|&r| lattice_len(r)).sum::<usize>() > MAX_SAMPLES + faces {
            spacing *= 1.5;
            r = divisions(spacing);
        }
        let mut lattices = Vec::with_capacity(faces);
        let mut total = 0usize;
        for &rk in &r {
            lattices.push((total as u32, rk as u8));
            total += lattice_len(rk);
        }
        let mut values = vec![[1.0f32; 2]; total];
        values.par_chunks_mut(64).enumerate().for_each(|(chunk, out)| {
            bake_chunk(mesh, &lattices, size, chunk * 64, out);
        });
        Self { lattices, values }
    }

    /// `[V_sky, V_ground]` at the local point `p` on triangle `triangle` of `mesh` (the mesh this was baked
    /// from), interpolated over the lattice; `[1, 1]` for a triangle it does not know.
    #[inline]
    pub fn at(&self, mesh: &Mesh, triangle: u32, p: Vec3) -> [f32; 2] {
        let Some(&(o, r)) = self.lattices.get(triangle as usize) else {
            return [1.0; 2];
        };
        let o = o as usize;
        if r == 0 {
            return self.values[o];
        }
        let tri = mesh.triangle(triangle);
        let [a, b, c] = tri.v;
        let (e1, e2, q) = (b - a, c - a, p - a);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (q1, q2) = (q.dot(e1), q.dot(e2));
        let det = d11 * d22 - d12 * d12;
        if det <= 0.0 || !det.is_finite() {
            return self.values[o];
        }
        let rf = f32::from(r);
        let u = ((d22 * q1 - d12 * q2) / det).max(0.0) * rf;
        let w = ((d11 * q2 - d12 * q1) / det).max(0.0) * rf;
        // A point a rounding outside the triangle reads its nearest edge's values.
        let (u, w) = if u + w > rf { (u * rf / (u + w), w * rf / (u + w)) } else { (u, w) };
        let r = u32::from(r);
        let i0 = (u.floor() as u32).min(r - 1);
        let j0 = (w.floor() as u32).min(r - 1 - i0);
        let (fu, fw) = (u - i0 as f32, w - j0 as f32);
        let val = |i: u32, j: u32, part: usize| self.values[o + node_index(r, i, j)][part];
        let lower = fu + fw <= 1.0 || i0 + j0 + 2 > r;
        [0, 1].map(|part| {
            let v = if lower {
                let v00 = val(i0, j0, part);
                v00 + fu * (val(i0 + 1, j0, part) - v00) + fw * (val(i0, j0 + 1, part) - v00)
            } else {
                let v11 = val(i0 + 1, j0 + 1, part);
                v11 + (1.0 - fu) * (val(i0, j0 + 1, part) - v11) + (1.0 - fw) * (val(i0 + 1, j0, part) - v11)
            };
            v.clamp(0.0, 1.0)
        })
    }

    /// Bakes ([`SkyVisibility::shared`]) every mesh of `scene` whose sky visibility the cameras read (all but the
    /// water's), one mesh after the other.
    pub fn prepare(scene: &Scene) {
        for m in scene.meshes() {
            if wants_sky_visibility(m) {
                SkyVisibility::shared(m);
            }
        }
    }

    /// Number of samples baked.
    pub fn num_samples(&self) -> usize {
        self.values.len()
    }

    /// The baked `[V_sky, V_ground]`, triangle by triangle (each triangle's lattice rows of constant `j`).
    pub fn values(&self) -> &[[f32; 2]] {
        &self.values
    }

    /// The sky visibility of `mesh`, baked once per process and shared (meshes of the same vertices and faces share
    /// one; a cache of the last [`CACHE_MESHES`] meshes).
    pub fn shared(mesh: &Mesh) -> Arc<SkyVisibility> {
        static CACHE: Mutex<Vec<(u64, Arc<SkyVisibility>)>> = Mutex::new(Vec::new());
        let key = mesh.content_key();
        if let Ok(cache) = CACHE.lock() {
            if let Some((_, v)) = cache.iter().find(|(k, _)| *k == key) {
                return Arc::clone(v);
            }
        }
        // Baked outside the lock: two threads asking for the same new mesh at once each bake it (the same values).
        let v = Arc::new(SkyVisibility::bake(mesh));
        if let Ok(mut cache) = CACHE.lock() {
            if !cache.iter().any(|(k, _)| *k == key) {
                if cache.len() >= CACHE_MESHES {
                    cache.remove(0);
                }
                cache.push((key, Arc::clone(&v)));
            }
        }
        v
    }
}

/// Whether the cameras read `mesh`'s sky visibility: every mesh but the water's (all its faces of class 1).
#[inline]
pub fn wants_sky_visibility(mesh: &Mesh) -> bool {
    !mesh.classes().iter().all(|&c| c == CLASS_WATER)
}

/// Meshes whose sky visibility the process keeps ([`SkyVisibility::shared`]).
pub const CACHE_MESHES: usize = 96;

/// Node `(i, j)` of the `s`-th sample of a lattice of `r` subdivisions (rows of constant `j`, `r + 1 − j` long).
#[inline]
fn lattice_node(r: u32, s: u32) -> (u32, u32) {
    let mut j = 0;
    let mut s = s;
    while s > r - j {
        s -= r - j + 1;
        j += 1;
    }
    (s, j)
}

/// The index of node `(i, j)` in a lattice of `r` subdivisions: `Σ_{j' < j} (r + 1 − j') + i`.
#[inline(always)]
fn node_index(r: u32, i: u32, j: u32) -> usize {
    (j * (r + 1) - j * (j.saturating_sub(1)) / 2 + i) as usize
}

crate::dispatch! {
    /// The samples `first..first + out.len()` of `mesh` (of its `lattices`, a mesh `size` metres across) into `out`.
    fn bake_chunk[lv](mesh: &Mesh, lattices: &[(u32, u8)], size: f32, first: usize, out: &mut [[f32; 2]]) {
        let offset = 2e-5 * size + 1e-4;
        let mut stack = crate::bvh::Stack::default();
        for (s, v) in out.iter_mut().enumerate() {
            let sample = first + s;
            // The triangle owning this sample: the last whose offset is at most `sample`.
            let k = lattices.partition_point(|&(o, _)| o as usize <= sample) - 1;
            let (o, rk) = lattices[k];
            let tri = mesh.triangle(k as u32);
            let n = tri.n.normalize_or_zero();
            if n == Vec3::ZERO {
                continue;
            }
            let [a, b, c] = tri.v;
            let centroid = (a + b + c) / 3.0;
            let sample = sample as u64;
            // Every sample draws the same pattern (index 0 of each stream): neighbouring samples on like geometry
            // then err alike, so that their errors do not show as noise between them (a fan of thin triangles,
            // one sample each, would read as pie slices).
            let draw = |stream: u64| crate::sensors::noise::uniform(SEED, stream, PATTERN) as f32;
            let rf = f32::from(rk);
            let node = lattice_node(u32::from(rk.max(1)), (sample - o as u64) as u32);
            // Ray `k`'s origin: a point drawn over the sample's share of the triangle (the whole of it for a
            // one-sample triangle; else the node's cell, ±½ a step), a hair towards the centroid (a point on a
            // concave edge sees the neighbouring face rise beside it rather than start at its own origin), and
            // lifted off the face.
            let origin = |k: u64| {
                let (s1, s2) = (draw(ORIGIN_STREAM + 2 * k), draw(ORIGIN_STREAM + 2 * k + 1));
                let p = if rk == 0 {
                    let su = s1.sqrt();
                    a * (1.0 - su) + b * (su * (1.0 - s2)) + c * (su * s2)
                } else {
                    let mut u = (node.0 as f32 + s1 - 0.5).clamp(0.0, rf);
                    let mut w = (node.1 as f32 + s2 - 0.5).clamp(0.0, rf);
                    if u + w > rf {
                        let scale = rf / (u + w);
                        (u, w) = (u * scale, w * scale);
                    }
                    a + (b - a) * (u / rf) + (c - a) * (w / rf)
                };
                p + (centroid - p) * 1e-3 + n * offset
            };
            let rays = if rk == 0 { DETAIL_RAYS } else { RAYS };
            *v = visibility_at(lv, mesh, (origin, n), rays, 2.0 * size + 1.0, PATTERN, &mut stack);
        }
    }
}

/// The share of `rays` cosine-distributed rays about the unit normal `n`, ray `k` from `origin(k)`, that meet no
/// triangle of `mesh` closer than `t_max` (`sample` seeds the strata's turn and jitter): 4 equal-area rings of the unit disc, `rays / 4`
/// sectors each, lifted onto the hemisphere (Malley's method); `[V_sky, V_ground]`, each part's share among the
/// rays that fall in it. Rays whose first hit is a back face are left out (the sample is inside a part it overlaps);
/// a part with no ray left reads 1.
#[inline(always)]
fn visibility_at<L: crate::simd::Level>(
    lv: L,
    mesh: &Mesh,
    (origin, n): (impl Fn(u64) -> Vec3, Vec3),
    rays: usize,
    t_max: f32,
    sample: u64,
    stack: &mut crate::bvh::Stack,
) -> [f32; 2] {
    let (t1, t2) = basis(n);
    let turn = crate::sensors::noise::uniform(SEED, 0, sample) as f32;
    let (rings, sectors) = (4usize, (rays / 4).max(1));
    // Per part (0: directions above the local horizon, the sky's; 1: below it, the ground's): open and blocked.
    let (mut open, mut blocked) = ([0usize; 2], [0usize; 2]);
    for ring in 0..rings {
        for sector in 0..sectors {
            let k = (ring * sectors + sector) as u64;
            let jitter = crate::sensors::noise::uniform(SEED, 1 + k, sample) as f32;
            // Equal-area rings of the unit disc (u = r² stratified), sectors turned by the sample's angle.
            let u = (ring as f32 + jitter) / rings as f32;
            let phi = std::f32::consts::TAU * ((sector as f32 + turn) / sectors as f32);
            let rad = u.sqrt();
            let d = t1 * (rad * phi.cos()) + t2 * (rad * phi.sin()) + n * (1.0 - u).max(0.0).sqrt();
            let ray = RayPrep::new(origin(k).to_array(), d.to_array());
            let part = usize::from(d.z <= 0.0);
            if !mesh.any(lv, &ray, t_max, stack) {
                open[part] += 1;
            } else if mesh.closest(lv, &ray, t_max, stack).is_some_and(|h| mesh.triangle(h.triangle).n.dot(d) < 0.0) {
                blocked[part] += 1;
            }
            // A ray whose first hit is a back face left from inside a solid part: the sample lies in another part
            // it passes through (parts of a vessel overlap), a direction that tells nothing of the sky.
        }
    }
    [0, 1].map(|part| {
        let seen = open[part] + blocked[part];
        if seen == 0 {
            1.0
        } else {
            open[part] as f32 / seen as f32
        }
    })
}

/// Two unit tangents completing the unit `n` to a right-handed basis (Duff et al. 2017's branchless construction).
#[inline]
fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), Vec3::new(b, sign + n.y * n.y * a, -n.y))
}

/// The share of the environment's specular light a surface of sky visibility `v` still receives, seen at
/// `n·v = nv` with GGX roughness `alpha`: `clamp((nv + v)^(2^(−16α − 1)) − 1 + v, 0, 1)` (Lagarde & de Rousiers
/// 2014, section 4.10.2, with `α` as Filament reads it). 1 where `v = 1`.
#[inline]
pub fn specular_occlusion(nv: f32, v: f32, alpha: f32) -> f32 {
    if v >= 1.0 {
        return 1.0;
    }
    ((nv + v).powf((-16.0 * alpha - 1.0).exp2()) - 1.0 + v).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(v: &[[f32; 3]], f: &[[i64; 3]]) -> Mesh {
        Mesh::new("m", v, f, &[2]).unwrap_or_else(|e| unreachable!("{e}"))
    }

    /// A floor `[0, 60] × [−30, 30]` at z = 0 facing up and a wall of height `h` in the plane x = 0 along
    /// y ∈ [−half, half] (long enough to stand for an infinite one seen from the floor).
    fn floor_and_wall(h: f32, half: f32) -> Mesh {
        let v = [
            [0.0, -30.0, 0.0],
            [60.0, -30.0, 0.0],
            [60.0, 30.0, 0.0],
            [0.0, 30.0, 0.0],
            [0.0, -half, 0.0],
            [0.0, half, 0.0],
            [0.0, half, h],
            [0.0, -half, h],
        ];
        mesh(&v, &[[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    }

    #[test]
    fn a_convex_mesh_sees_the_whole_sky_everywhere() {
        let sky = SkyVisibility::bake(&crate::scene::tests::box_mesh([10.0, 3.0, 2.5], 2));
        assert!(sky.num_samples() > 12);
        assert!(sky.values().iter().all(|&x| x == [1.0; 2]), "{:?}", sky.values());
    }

    #[test]
    fn a_floor_by_a_wall_sees_the_view_factor_closed_form() {
        // F = ½ (1 − d/√(d² + h²)) of a floor element at distance d from the foot of a perpendicular wall of
        // height h and infinite length; V = 1 − F. The mean over 400 samples along the wall (each its own strata
        // turn and jitter) leaves the estimator's noise well under the tolerance.
        let h = 10.0f32;
        let m = floor_and_wall(h, 5000.0);
        let mut stack = crate::bvh::Stack::default();
        for d in [1.0f32, 5.0, 10.0, 30.0] {
            let want = 1.0 - 0.5 * (1.0 - d / (d * d + h * h).sqrt());
            let n = 400;
            let got = (0..n)
                .map(|k| {
                    let p = Vec3::new(d, -20.0 + 40.0 * k as f32 / n as f32, 1e-3);
                    // An upward floor: every ray is above the horizon, the ground's part reads 1.
                    let [sky, ground] =
                        visibility_at(crate::simd::Portable, &m, (|_| p, Vec3::Z), RAYS, 1e5, k as u64, &mut stack);
                    assert_eq!(ground, 1.0);
                    sky
                })
                .sum::<f32>()
                / n as f32;
            assert!((got - want).abs() < 0.01, "d = {d}: V = {got}, closed form {want}");
        }
    }

    #[test]
    fn a_wall_on_a_floor_keeps_its_sky_and_loses_its_ground() {
        // The wall's face (x = 0, facing +x) at height z above the floor: nothing hides the sky above its
        // horizon (V_sky = 1), while the floor hides most of what lies below it. V_ground against the share of the
        // lower quarter-sphere's cosine-weighted directions that miss the 60 × 60 m floor, summed on a fine grid
        // of directions with the ray–plane intersection in closed form (not the BVH).
        let m = floor_and_wall(10.0, 5000.0);
        let mut stack = crate::bvh::Stack::default();
        for z in [0.5f32, 2.0, 5.0] {
            let (mut open, mut total) = (0.0f64, 0.0f64);
            let steps = 600;
            for i in 0..steps {
                for j in 0..steps {
                    // Directions d = (cos e cos a, cos e sin a, sin e), e ∈ (−π/2, 0), a ∈ (−π/2, π/2); measure
                    // cos e de da, weight n·d = d.x.
                    let e = -std::f64::consts::FRAC_PI_2 * (i as f64 + 0.5) / steps as f64;
                    let a = std::f64::consts::PI * ((j as f64 + 0.5) / steps as f64 - 0.5);
                    let d = [e.cos() * a.cos(), e.cos() * a.sin(), e.sin()];
                    let w = d[0] * e.cos();
                    let t = f64::from(z) / -d[2];
                    let (x, y) = (t * d[0], t * d[1]);
                    total += w;
                    if !((0.0..=60.0).contains(&x) && (-30.0..=30.0).contains(&y)) {
                        open += w;
                    }
                }
            }
            let want = (open / total) as f32;
            let n = 400;
            let (mut sky, mut ground) = (0.0f32, 0.0f32);
            for k in 0..n {
                let p = Vec3::new(1e-3, -5.0 + 10.0 * k as f32 / n as f32, z);
                let [s, g] =
                    visibility_at(crate::simd::Portable, &m, (|_| p, Vec3::X), RAYS, 1e5, k as u64, &mut stack);
                (sky, ground) = (sky + s / n as f32, ground + g / n as f32);
            }
            assert!((sky - 1.0).abs() < 1e-5, "z = {z}: V_sky = {sky}");
            assert!((ground - want).abs() < 0.02, "z = {z}: V_ground = {ground}, summed {want}");
            assert!(want < 0.2, "z = {z}: {want}");
        }
    }

    #[test]
    fn the_baked_floor_darkens_towards_the_wall_as_the_closed_form() {
        // The bake itself: the floor's lattice nodes at each distance from the wall, averaged along it (a wall of
        // ±300 m, whose ends change V by under 0.001 at these distances, keeps the mesh small enough for a fine
        // lattice).
        let h = 10.0f32;
        let m = floor_and_wall(h, 300.0);
        let sky = SkyVisibility::bake(&m);
        let mut by_d: std::collections::BTreeMap<i64, (f32, usize)> = Default::default();
        for t in 0..2u32 {
            let tri = m.triangle(t);
            let (o, r) = sky.lattices[t as usize];
            assert!(r > 1, "the floor's triangles are subdivided: r = {r}");
            for s in 0..lattice_len(u32::from(r)) as u32 {
                let (i, j) = lattice_node(u32::from(r), s);
                let [a, b, c] = tri.v;
                let p = a + (b - a) * (i as f32 / f32::from(r)) + (c - a) * (j as f32 / f32::from(r));
                // The lookup returns each node's own value there.
                let at = sky.at(&m, t, p + ((a + b + c) / 3.0 - p) * 1e-3);
                let own = sky.values[o as usize + s as usize];
                assert!((at[0] - own[0]).abs() < 0.02 && at[1] == 1.0, "node {i}, {j}: {at:?} against {own:?}");
                let e = by_d.entry((p.x * 100.0).round() as i64).or_default();
                e.0 += own[0];
                e.1 += 1;
            }
        }
        let mut checked = 0;
        for (d100, (sum, count)) in by_d {
            let d = d100 as f32 / 100.0;
            if count < 4 || !(0.5..=40.0).contains(&d) {
                continue;
            }
            let want = 1.0 - 0.5 * (1.0 - d / (d * d + h * h).sqrt());
            let got = sum / count as f32;
            assert!((got - want).abs() < 0.05, "d = {d}: V = {got} over {count} nodes, closed form {want}");
            checked += 1;
        }
        assert!(checked >= 3, "distances checked: {checked}");
    }

    #[test]
    fn the_lookup_is_linear_over_each_sub_triangle() {
        // Values set to a linear function of position: the lookup gives that function anywhere on the triangle.
        let v = [[0.0, 0.0, 0.0], [8.0, 1.0, 0.0], [2.0, 6.0, 0.5]];
        let m = mesh(&v, &[[0, 1, 2]]);
        let f = |p: Vec3| 0.1 + 0.05 * p.x + 0.07 * p.y;
        for r in [1u32, 2, 5, 24] {
            let [a, b, c] = m.triangle(0).v;
            let values = (0..lattice_len(r) as u32)
                .map(|s| {
                    let (i, j) = lattice_node(r, s);
                    let x = f(a + (b - a) * (i as f32 / r as f32) + (c - a) * (j as f32 / r as f32));
                    [x, 1.0 - x]
                })
                .collect();
            let sky = SkyVisibility { lattices: vec![(0, r as u8)], values };
            for k in 0..200u64 {
                let (mut u, mut w) =
                    (crate::sensors::noise::uniform(3, 0, k) as f32, crate::sensors::noise::uniform(3, 1, k) as f32);
                if u + w > 1.0 {
                    (u, w) = (1.0 - u, 1.0 - w);
                }
                let p = a + (b - a) * u + (c - a) * w;
                let [x, y] = sky.at(&m, 0, p);
                assert!((x - f(p)).abs() < 1e-4 && (y - (1.0 - f(p))).abs() < 1e-4, "r = {r}, ({u}, {w})");
            }
        }
    }

    #[test]
    fn lattice_nodes_and_indices_agree() {
        for r in [1u32, 2, 3, 7, 24] {
            let mut seen = 0;
            for j in 0..=r {
                for i in 0..=r - j {
                    let s = node_index(r, i, j);
                    assert_eq!(s, seen);
                    assert_eq!(lattice_node(r, s as u32), (i, j));
                    seen += 1;
                }
            }
            assert_eq!(seen, lattice_len(r));
        }
    }

    #[test]
    fn specular_occlusion_follows_its_formula() {
        assert_eq!(specular_occlusion(0.5, 1.0, 0.3), 1.0);
        let (nv, v, a) = (0.6f32, 0.4f32, 0.25f32);
        let want = ((nv + v).powf(2f32.powf(-16.0 * a - 1.0)) - 1.0 + v).clamp(0.0, 1.0);
        assert!((specular_occlusion(nv, v, a) - want).abs() < 1e-6);
        assert!(specular_occlusion(1.0, 0.0, 0.5) < 0.05 && specular_occlusion(0.2, 0.9, 0.0) <= 1.0);
    }

    #[test]
    fn large_meshes_keep_to_the_sample_cap() {
        // 100,000 triangles of a heightfield: at least one sample each, and no more than the cap allows.
        let n = 224usize;
        let v: Vec<[f32; 3]> =
            (0..n * n).map(|k| [(k % n) as f32 * 5.0, (k / n) as f32 * 5.0, ((k * 7919) % 13) as f32 * 0.3]).collect();
        let mut f = Vec::new();
        for y in 0..n - 1 {
            for x in 0..n - 1 {
                let k = (y * n + x) as i64;
                f.push([k, k + 1, k + n as i64 + 1]);
                f.push([k, k + n as i64 + 1, k + n as i64]);
            }
        }
        let m = mesh(&v, &f);
        let sky = SkyVisibility::bake(&m);
        assert!(sky.num_samples() >= m.num_triangles() && sky.num_samples() <= MAX_SAMPLES + m.num_triangles());
        assert!(sky.values().iter().flatten().all(|x| (0.0..=1.0).contains(x)));
    }
}
