//! The radiance of a set of camera rays whose primary hits are known: sun visibility by shadow rays (`sunlit.rs`),
//! water reflections by traced rays (with their own shadow rays), then the [`Shader`] per ray.
//!
//! Every stage is one batch over the scene (parallel, coherent packets in the order given), so a camera's
//! pixels, its anti-aliasing samples and any other ray set go through the same code. Hits are turned into
//! [`SurfaceHit`]s on the fly in each pass rather than stored (a stored hit per pixel costs more in memory
//! traffic than recomputing it), except those of the water rays whose reflections are traced: their shading
//! normals sample the wave surface, which costs more than keeping them (−3 % of `port_entry`'s camera CPU).

use super::glossy;
use super::sunlit::{sunlit, sunlit_of};
use crate::error::Result;
use crate::scene::{RayHits, Scene};
use crate::sensors::shade::tonemap;
use crate::sensors::shade::{Shader, SurfaceHit};
use parry3d::math::Vec3;
use rayon::prelude::*;

/// Farthest a reflected ray looks for a surface, metres.
const REFLECTION_RANGE: f32 = 20_000.0;

/// The hit of ray `k` as shading needs it (normal turned towards the ray, the face's material, the swell's
/// normal on water), `None` for a miss.
#[inline(always)]
pub(crate) fn surface_at(
    shader: &Shader,
    scene: &Scene,
    hits: &RayHits,
    origins: &[[f32; 3]],
    dirs: &[[f32; 3]],
    k: usize,
) -> Option<SurfaceHit> {
    let t = hits.distance[k];
    if !t.is_finite() {
        return None;
    }
    let d = Vec3::from_array(dirs[k]);
    let mut normal = Vec3::new(hits.normal[3 * k], hits.normal[3 * k + 1], hits.normal[3 * k + 2]);
    if normal.dot(d) > 0.0 {
        normal = -normal;
    }
    let point = Vec3::from_array(origins[k]) + d * t;
    let (instance, triangle) = (hits.instance[k], hits.triangle[k]);
    let material = scene.material_index(instance, triangle);
    let hit = SurfaceHit {
        t,
        point,
        normal,
        class: hits.class[k],
        instance,
        material,
        lights_on: lamp_lit(scene, shader, instance, material, d),
        shading_normal: normal,
        unresolved_mss: 0.0,
        sky_visibility: if hits.class[k] == 1 || hits.backface[k] {
            [1.0; 2]
        } else {
            shader.sky_visibility(scene, instance, triangle, point)
        },
    };
    Some(shader.with_swell(d, hit))
}

/// Whether a navigation lamp of face material `material` hit along `d` shines towards the viewer: its instance's
/// lights are on and the direction back to the viewer lies in the lamp's arc
/// ([`crate::material::Material::emits_towards`], COLREG Rule 21). Other materials emit whenever the instance's
/// lights are on.
#[inline]
fn lamp_lit(scene: &Scene, shader: &Shader, instance: i32, material: u16, d: Vec3) -> bool {
    let Some(inst) = usize::try_from(instance).ok().and_then(|i| scene.instances().get(i)) else {
        return false;
    };
    inst.lights_on() && shader.lamp_shines(material, || inst.pose().inverse_transform_vector(-d))
}

/// Where water reflections are traced.
#[derive(Clone, Copy)]
pub enum Reflections<'a> {
    /// Not at all: water reflects the sky.
    Sky,
    /// For every water ray.
    Every,
    /// None traced: water ray `k` reflects `given(k)` (`None`: the sky along its mirror direction), e.g. the
    /// blurred reflection of the pixel an anti-aliasing sample lies in.
    Given(&'a (dyn Fn(usize) -> Option<Vec3> + Sync)),
    /// Once per 2 × 2 block of a camera's pixels (at its even corner, [`PixelGrid::block`], when that one is
    /// water; else at the ray itself): every other water ray takes the mean of those traced at its anchors
    /// ([`PixelGrid::anchors`], the block corners around it), else its block's. With the glossy blur, once per
    /// 4 × 4 block where even the calmest water's lobe spans many of them, and every water ray reads the blur.
    Shared(PixelGrid<'a>),
}

/// A camera's rays as a pixel grid, for shading shared between neighbouring pixels: ray `k` is pixel
/// `pos[k]` (`[x, y]`), and row-major pixel `i` is ray `rank[i]`.
#[derive(Clone, Copy)]
pub struct PixelGrid<'a> {
    /// Pixels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// `[x, y]` of each ray's pixel.
    pub pos: &'a [[u16; 2]],
    /// The ray of each row-major pixel.
    pub rank: &'a [u32],
}

impl PixelGrid<'_> {
    /// The ray at the even corner of ray `k`'s 2 × 2 block of pixels.
    #[inline(always)]
    pub fn block(&self, k: usize) -> usize {
        self.block_of(k, 2)
    }

    /// The ray at the corner of ray `k`'s `side × side` block of pixels (`side` a power of two).
    #[inline(always)]
    pub fn block_of(&self, k: usize, side: u32) -> usize {
        let [x, y] = self.pos[k].map(u32::from);
        let m = !(side.max(1) - 1);
        self.rank[((y & m) * self.width + (x & m)) as usize] as usize
    }

    /// The anchors of ray `k` (up to four rays, and how many) whose mean it may take instead of being shaded:
    /// the pixels at even rows and columns around it (the two beside it on an odd column or row, the four
    /// corners on both). An anchor itself, or a pixel whose anchors leave the image, has none.
    #[inline(always)]
    pub fn anchors(&self, k: usize) -> ([u32; 4], usize) {
        let [x, y] = self.pos[k].map(u32::from);
        let (ox, oy) = (x & 1, y & 1);
        if ox | oy == 0 || x + ox >= self.width || y + oy >= self.height {
            return ([0; 4], 0);
        }
        let at = |xx: u32, yy: u32| self.rank[(yy * self.width + xx) as usize];
        match (ox, oy) {
            (1, 0) => ([at(x - 1, y), at(x + 1, y), 0, 0], 2),
            (0, 1) => ([at(x, y - 1), at(x, y + 1), 0, 0], 2),
            _ => ([at(x - 1, y - 1), at(x + 1, y - 1), at(x - 1, y + 1), at(x + 1, y + 1)], 4),
        }
    }
}

/// Largest difference (sRGB levels of 255, any channel, after exposure `k` and the tone curve) between two
/// colours that count as alike: where the anchors of a ray agree this well, their mean stands for it, and an
/// edge between alike pixels needs no anti-aliasing (a mixture of the two differs from either by no more).
pub const ALIKE_LEVELS: u8 = 2;

/// Whether radiances `a` and `b` look alike under exposure `k` ([`ALIKE_LEVELS`]).
#[inline]
pub fn alike(a: Vec3, b: Vec3, k: f32) -> bool {
    alike_shown(tonemap::to_srgb8(a, k), tonemap::to_srgb8(b, k))
}

/// Whether two tone-mapped colours are alike ([`ALIKE_LEVELS`]).
#[inline]
fn alike_shown(a: [u8; 3], b: [u8; 3]) -> bool {
    (0..3).all(|c| a[c].abs_diff(b[c]) <= ALIKE_LEVELS)
}

/// What a ray sees, for sharing shading: 0 a surface other than water (never shared), 1 the sky, 2 water.
#[inline]
fn kind(hits: &RayHits, k: usize) -> u8 {
    if !hits.distance[k].is_finite() {
        1
    } else if hits.class[k] == 1 {
        2
    } else {
        0
    }
}

/// What [`radiance`] returns: per ray, the radiance and, with a glossy blur, the blurred reflections the water
/// rays' shading read.
pub struct Shaded {
    /// Radiance per ray (linear RGB, cd/m²).
    pub radiance: Vec<Vec3>,
    /// The blurred reflections (`glossy.rs`), read at a pixel's centre; `None` without the blur.
    pub reflected: Option<glossy::Blurred>,
    /// The view's exposure ([`Shader::metered_exposure`] of the rays' radiance), where the shared shading
    /// needed it (it compares the pixels as shown); `None` otherwise.
    pub exposure: Option<f32>,
}

/// Radiance (linear RGB, cd/m², aerial perspective included) along every ray `origins[k] + t dirs[k]` whose
/// closest hits are `hits`, with water `reflections` traced as asked; `shadows` casts shadow rays (else every
/// surface facing the sun is lit). With `glossy` (the rays are a pinhole camera's pixels, its focal length in
/// pixels per radian, its roll: how far the world's vertical shows turned in the image, radians, and the seed of
/// the reflections' directions), each traced reflection leaves in a direction drawn from the water's roughness
/// lobe at its point and the traced reflections are spread over the rest of the lobe (`glossy.rs`) before the
/// water is shaded.
///
/// With `shared` (the rays are a camera's pixels), a ray that sees the open water or the sky, as all its anchors
/// ([`PixelGrid::anchors`]) do, takes their mean when their colours are alike ([`alike`] under the shader's
/// exposure) and is shaded itself otherwise: smooth water and sky cost one shading per anchor, while glints,
/// foam and the sun's disc, whose anchors differ, keep every pixel. Such a ray takes its anchors' sun visibility
/// where they agree on it and casts its own shadow ray where they do not (a shadow narrower than the two pixels
/// between anchors is lost; on `port_entry` frame 10 this changed 91 of 4.5 million pixels).
pub fn radiance(
    scene: &Scene,
    shader: &Shader,
    shadows: bool,
    reflections: Reflections<'_>,
    shared: Option<PixelGrid<'_>>,
    glossy: Option<(PixelGrid<'_>, f32, f32, u64)>,
    (origins, dirs, hits): (&[[f32; 3]], &[[f32; 3]], &RayHits),
) -> Result<Shaded> {
    let n = origins.len();
    let surface = |k: usize| surface_at(shader, scene, hits, origins, dirs, k);
    let is_water = |k: usize| hits.distance[k].is_finite() && hits.class[k] == 1;
    // Candidates for a shared shading: the ray and its anchors all see water, or all the sky (each ray's kind
    // read where it is needed: a pass of its own cost more than reading the anchors' twice).
    let candidate: Vec<bool> = match shared {
        None => Vec::new(),
        Some(grid) => (0..n)
            .into_par_iter()
            .with_min_len(PASS_CHUNK)
            .map(|k| {
                let kk = kind(hits, k);
                if kk == 0 {
                    return false;
                }
                let (ids, m) = grid.anchors(k);
                m > 0 && ids[..m].iter().all(|&j| kind(hits, j as usize) == kk)
            })
            .collect(),
    };
    let is_candidate = |k: usize| candidate.get(k).copied().unwrap_or(false);
    let lit = sunlit(scene, shader, shadows, (hits, origins, dirs), |k| !is_candidate(k))?;
    // At night the lamps' glitter is estimated at every water ray (`shade/lamp_glitter.rs`), and the traced
    // reflections leave the lamps out; not at draft quality, which traces no reflections.
    let lamps = Some(shader.lamps()).filter(|set| !set.is_empty() && !matches!(reflections, Reflections::Sky));
    // Reflected rays of the water hits (their representatives'), traced, and the radiance they bring back:
    // `index[k]` is ray k's own traced reflection in `values`, `u32::MAX` where it has none.
    let mut values: Vec<Vec3> = Vec::new();
    let mut index: Vec<u32> = Vec::new();
    // The surfaces of the rays whose reflections are traced, kept in `values`' order for their own shading (a
    // water hit's shading normal samples the waves: worked out once, not again in the final pass).
    let mut traced_hits: Vec<SurfaceHit> = Vec::new();
    // With the glossy blur, per traced reflection: the sky along it (what it brings back meeting nothing) and the
    // sky's mean over the water's lobe around it (`shade/sky_lobe.rs`), in `values`' order.
    let mut skies: Vec<(Vec3, Vec3)> = Vec::new();
    // Traced reflections per block side: standard quality traces one per 2 × 2 block, or per 4 × 4 where the
    // glossy lobe of the calmest water here spans many such blocks (the blur then reads them on cells at least
    // that coarse, `glossy::decimation`).
    let spacing = match (reflections, glossy) {
        (Reflections::Shared(_), Some((_, f_px, _, _))) => {
            // (By the whole lobe: 4 × 4 blocks where even the screen-space share of it spans four of them, so the
            // blur still averages the strata of 4 × 4 blocks of drawn directions; by that share alone, blocks of
            // 2 × 2 were chosen four times as often, for 11 % more CPU on `port_entry`, the Mitsuba scenes' errors
            // the same.)
            glossy::decimation(glossy::narrowest_lobe_px(shader.water_mss(0.0), f_px), 2)[0] as u32
        }
        (Reflections::Shared(_), None) => 2,
        _ => 1,
    };
    // The ray whose reflection stands for ray k's: its block's corner where that is water too, else itself.
    let owner = |k: usize| match reflections {
        Reflections::Shared(grid) => {
            let r = grid.block_of(k, spacing);
            if r < n && is_water(r) {
                r
            } else {
                k
            }
        }
        _ => k,
    };
    if !matches!(reflections, Reflections::Sky | Reflections::Given(_)) {
        // A candidate's own reflection is traced only if it is its own representative (its shading may fall
        // back to its own); with a shared one, the representative's serves.
        let traced: Vec<u32> = (0..n)
            .into_par_iter()
            .filter(|&k| {
                is_water(k) && owner(k) == k && !(is_candidate(k) && matches!(reflections, Reflections::Shared(_)))
            })
            .map(|k| k as u32)
            .collect();
        traced_hits = traced
            .par_iter()
            .map(|&k| surface(k as usize).unwrap_or_else(|| unreachable!("ray {k} was a water hit")))
            .collect();
        // The mirror rays; with the glossy blur each leaves instead in a direction drawn from the part of the lobe
        // the blur does not spread (`glossy::lobe_ray`): at its own point, so that a hull close behind the water
        // darkens the reflection over the whole lobe it fills (the screen-space spread alone read the mirror rays
        // of the water farther below, which pass over it). The mirror directions stay for the sky's lobe mean.
        let mirrors: Vec<(Vec3, Vec3)> = traced
            .par_iter()
            .zip(&traced_hits)
            .map(|(&k, h)| shader.reflection_ray(Vec3::from_array(dirs[k as usize]), h))
            .collect();
        let (ro, rd): (Vec<[f32; 3]>, Vec<[f32; 3]>) = traced
            .par_iter()
            .zip(&traced_hits)
            .zip(&mirrors)
            .map(|((&k, h), &(o, r))| {
                let r = match glossy {
                    Some((grid, _, _, seed)) => {
                        let [x, y] = grid.pos[k as usize];
                        let u = glossy::stratum(u32::from(x), u32::from(y), spacing, seed);
                        glossy::lobe_ray(r, shader.water_mss(h.unresolved_mss), (-dirs[k as usize][2]).max(0.0), u)
                    }
                    None => r,
                };
                (o.to_array(), r.to_array())
            })
            .unzip();
        let rhits = scene.cast_rays(&ro, &rd, REFLECTION_RANGE)?;
        let rsurface = |j: usize| {
            let mut h = surface_at(shader, scene, &rhits, &ro, &rd, j).filter(|h| !h.is_water())?;
            // The lamps' light on the water is their glitter's, below.
            h.lights_on &= lamps.is_none();
            Some(h)
        };
        let rlit = sunlit(scene, shader, shadows, (&rhits, &ro, &rd), |j| rhits.class[j] != 1)?;
        values = (0..ro.len())
            .into_par_iter()
            .map(|j| {
                // A reflection meeting the water again (a wave face) reads the sky along it.
                let h = rsurface(j);
                shader.reflected(Vec3::from_array(rd[j]), h.as_ref(), rlit[j])
            })
            .collect();
        if let Some(set) = lamps {
            // The lamps' light on what the reflections meet (a lamp-lit hull mirrors lit), through the fog of
            // the reflected ray's own length as the rest of its shading.
            let solid: Vec<u32> = (0..ro.len()).filter(|&j| kind(&rhits, j) == 0).map(|j| j as u32).collect();
            let light = super::lamp_light::lamp_light(scene, shader, set, (&ro, &rd, &rhits), &solid);
            for (&j, c) in solid.iter().zip(light) {
                values[j as usize] += c;
            }
        }
        if glossy.is_some() {
            skies = (0..ro.len())
                .into_par_iter()
                .map(|j| {
                    let alpha = shader.water_mss(traced_hits[j].unresolved_mss).sqrt();
                    // The sky along the drawn direction (what it brings back meeting nothing), the lobe's mean
                    // around the mirror direction.
                    (shader.reflected(Vec3::from_array(rd[j]), None, false), shader.sky_lobe(mirrors[j].1, alpha))
                })
                .collect();
        }
        index = vec![u32::MAX; n];
        for (j, &k) in traced.iter().enumerate() {
            index[k as usize] = j as u32;
        }
    }
    // The reflected radiance ray k reads: its own traced one; sharing its block's (standard quality), the mean of
    // those traced at the block corners around it, its anchors (a bilinear reconstruction of the half-resolution
    // reflections rather than the nearest corner's, so a reflected outline has no 2 × 2 steps); `None`: the sky.
    let traced_of = |k: usize| -> Option<Vec3> {
        if let Reflections::Given(given) = reflections {
            return given(k);
        }
        let own = index.get(k).copied().filter(|&i| i != u32::MAX);
        if let Some(i) = own {
            return values.get(i as usize).copied();
        }
        if let Reflections::Shared(grid) = reflections {
            let (ids, m) = grid.anchors(k);
            let (mut sum, mut count) = (Vec3::ZERO, 0u32);
            for &a in &ids[..m] {
                if let Some(&i) = index.get(a as usize).filter(|&&i| i != u32::MAX) {
                    sum += values[i as usize];
                    count += 1;
                }
            }
            if count > 0 {
                return Some(sum / count as f32);
            }
        }
        index.get(owner(k)).and_then(|&i| values.get(i as usize)).copied()
    };
    // The traced reflections spread over the water's roughness lobe, read back at each water pixel.
    let blurred = match glossy {
        Some((grid, f_px, roll, _)) if !matches!(reflections, Reflections::Sky | Reflections::Given(_)) => {
            // (A camera's ray directions are unit vectors: `−d.z` is the grazing sine.)
            let samples: Vec<glossy::Sample> = index
                .par_iter()
                .with_min_len(PASS_CHUNK)
                .enumerate()
                .filter(|(_, &i)| i != u32::MAX)
                .map(|(k, &i)| {
                    let [x, y] = grid.pos[k];
                    let sin_grazing = (-dirs[k][2]).max(0.0);
                    let mss = shader.water_mss(traced_hits[i as usize].unresolved_mss);
                    let (sky, lobe_sky) = skies[i as usize];
                    let (x, y) = (u32::from(x), u32::from(y));
                    glossy::Sample { x, y, value: values[i as usize], sky, lobe_sky, mss, sin_grazing }
                })
                .collect();
            let (w, h) = (grid.width as usize, grid.height as usize);
            glossy::blur(w, h, f_px, spacing as usize, roll, &samples).map(|b| (b, grid))
        }
        _ => None,
    };
    let reflected_of = |k: usize| -> Option<Vec3> {
        match &blurred {
            Some((b, grid)) => {
                let [x, y] = grid.pos[k];
                b.at(f32::from(x) + 0.5, f32::from(y) + 0.5).or_else(|| traced_of(k))
            }
            None => traced_of(k),
        }
    };
    // Ray k's surface: the one kept when its reflection was traced, else worked out.
    let hit_of = |k: usize| match index.get(k).filter(|&&i| i != u32::MAX) {
        Some(&i) => Some(traced_hits[i as usize]),
        None => surface(k),
    };
    let mut exposure = None;
    let mut out = vec![Vec3::ZERO; n];
    out.par_chunks_mut(SHADE_CHUNK).enumerate().for_each(|(c, chunk)| {
        shade_chunk(shader, dirs, (&lit, &reflected_of), (c * SHADE_CHUNK, &|k| !is_candidate(k), &hit_of), chunk);
    });
    // The lamps' glitter on the water rays shaded themselves (a shared one takes its anchors' mean, glitter and
    // all; one whose anchors differ gets its own below).
    let add_glitter = |out: &mut [Vec3], water: &[u32]| {
        if let Some(set) = lamps {
            for (&k, g) in
                water.iter().zip(super::lamp_glow::lamp_glow(scene, shader, set, (origins, dirs, hits), water))
            {
                out[k as usize] += g;
            }
        }
    };
    if lamps.is_some() {
        let water: Vec<u32> =
            (0..n).into_par_iter().filter(|&k| is_water(k) && !is_candidate(k)).map(|k| k as u32).collect();
        add_glitter(&mut out, &water);
    }
    // The lamps' light on everything but the water (`shade/lamp_light.rs`), at every quality: such a ray is never
    // a candidate for a shared shading, so each is shaded above.
    if !shader.lamps().is_empty() {
        let solid: Vec<u32> =
            (0..n).into_par_iter().with_min_len(PASS_CHUNK).filter(|&k| kind(hits, k) == 0).map(|k| k as u32).collect();
        let light = super::lamp_light::lamp_light(scene, shader, shader.lamps(), (origins, dirs, hits), &solid);
        for (&k, c) in solid.iter().zip(light) {
            out[k as usize] += c;
        }
    }
    if let Some(grid) = shared {
        // The candidates: the anchors' mean where they look alike; the others (`redo`) need their own shading.
        // The exposure the view is shown with (the metered pixels are anchors: shaded themselves, above).
        let k_exp = shader.metered_exposure(grid.width as usize, grid.height as usize, |p| out[grid.rank[p] as usize]);
        exposure = Some(k_exp);
        // The anchors' colours as shown (each tone-mapped once; only water and sky can be anchors).
        let shown: Vec<[u8; 3]> = (0..n)
            .into_par_iter()
            .with_min_len(PASS_CHUNK)
            .map(|k| if is_candidate(k) || kind(hits, k) == 0 { [0; 3] } else { tonemap::to_srgb8(out[k], k_exp) })
            .collect();
        // Each candidate with its anchors' mean, or, where they differ (or the mean is not a number), on the list
        // to shade: per task of `PASS_CHUNK` rays, the means (ray, value) and the rays to shade, in order, then
        // applied (a slot per ray and a pass over all of them to apply it took 10 ms more a frame of
        // `port_entry`, one thread; one filtered list of pairs for the whole camera, more still).
        let parts: Vec<MeansAndRedo> = (0..n.div_ceil(PASS_CHUNK))
            .into_par_iter()
            .map(|c| {
                let (mut means, mut redo) = (Vec::new(), Vec::new());
                for k in c * PASS_CHUNK..((c + 1) * PASS_CHUNK).min(n) {
                    if !is_candidate(k) {
                        continue;
                    }
                    let (ids, m) = grid.anchors(k);
                    let first = shown[ids[0] as usize];
                    let alike = ids[1..m].iter().all(|&j| alike_shown(first, shown[j as usize]));
                    let mean = alike.then(|| ids[..m].iter().map(|&j| out[j as usize]).sum::<Vec3>() / m as f32);
                    match mean.filter(|c| !c.x.is_nan()) {
                        Some(v) => means.push((k as u32, v)),
                        None => redo.push(k as u32),
                    }
                }
                (means, redo)
            })
            .collect();
        let mut redo: Vec<u32> = Vec::new();
        for (means, r) in parts {
            for (k, v) in means {
                out[k as usize] = v;
            }
            redo.extend(r);
        }
        // The rays whose anchors differ: shaded themselves. Their sun visibility is their anchors' where those
        // agree (as a shadow map at half the resolution gives it), a shadow ray of their own where they do not.
        let agreed: Vec<Option<bool>> = redo
            .par_iter()
            .map(|&k| {
                let (ids, m) = grid.anchors(k as usize);
                let first = lit[ids[0] as usize];
                ids[1..m].iter().all(|&j| lit[j as usize] == first).then_some(first)
            })
            .collect();
        let own: Vec<u32> = redo.iter().zip(&agreed).filter(|(_, a)| a.is_none()).map(|(&k, _)| k).collect();
        let own_lit = sunlit_of(scene, shader, shadows, (hits, origins, dirs), &own)?;
        let mut own_lit = own_lit.into_iter();
        let redo_lit: Vec<bool> = agreed.iter().map(|a| a.unwrap_or_else(|| own_lit.next().unwrap_or(false))).collect();
        let shaded: Vec<Vec3> = redo
            .par_iter()
            .zip(redo_lit.par_iter())
            .map(|(&k, &lit)| {
                let k = k as usize;
                let refl = if is_water(k) { reflected_of(k) } else { None };
                shader.shade(Vec3::from_array(dirs[k]), hit_of(k).as_ref(), lit, refl)
            })
            .collect();
        for (&k, c) in redo.iter().zip(shaded) {
            out[k as usize] = c;
        }
        if lamps.is_some() {
            let water: Vec<u32> = redo.iter().copied().filter(|&k| is_water(k as usize)).collect();
            add_glitter(&mut out, &water);
        }
    }
    Ok(Shaded { radiance: out, reflected: blurred.map(|(b, _)| b), exposure })
}

/// The surface a ray of the batch hit (`None`: a miss).
type SurfaceOf<'a> = dyn Fn(usize) -> Option<SurfaceHit> + Sync + 'a;

/// One task's shared shadings: (ray, its anchors' mean) pairs, and the rays whose anchors differ.
type MeansAndRedo = (Vec<(u32, Vec3)>, Vec<u32>);

/// Rays shaded together per task of the final pass.
const SHADE_CHUNK: usize = 4096;
/// Least rays per task of the cheap per-ray passes (kinds, candidates, means).
pub(super) const PASS_CHUNK: usize = 4096;

crate::dispatch! {
    /// Shades the rays `start..start + out.len()` that `which` accepts into `out` (the others are left as they
    /// are), with their surfaces `hit_of(k)`, sun visibility `lit` and, for water, the reflected radiance
    /// `reflected_of(k)` (none: the sky's).
    fn shade_chunk(
        shader: &Shader,
        dirs: &[[f32; 3]],
        reflected: (&[bool], &(dyn Fn(usize) -> Option<Vec3> + Sync)),
        range: (usize, &(dyn Fn(usize) -> bool + Sync), &SurfaceOf<'_>),
        out: &mut [Vec3],
    ) {
        let (lit, reflected_of) = reflected;
        let (start, which, hit_of) = range;
        for (j, c) in out.iter_mut().enumerate() {
            let k = start + j;
            if !which(k) {
                continue;
            }
            let h = hit_of(k);
            let refl = match &h {
                Some(h) if h.is_water() => reflected_of(k),
                _ => None,
            };
            *c = shader.shade(Vec3::from_array(dirs[k]), h.as_ref(), lit[k], refl);
        }
    }
}
