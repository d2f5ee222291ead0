//! Cameras: pinhole (surround views) and orthographic (the top-view camera for BEV renderings).
//!
//! Body frame of a camera: x forward (the optical axis), y left, z up. Image `u` grows to the right (−y),
//! `v` downwards (−z); pixel `(u, v)` covers `[u, u+1) × [v, v+1)` and its ray goes through the pixel centre.
//! * Pinhole: intrinsics `fx = fy = W / (2 tan(hfov/2))`, `c = (W/2, H/2)` ([`rays::pinhole_intrinsics`]); depth
//!   is the distance along the optical axis (`t · d_x`).
//! * Orthographic: parallel rays along +x from an image plane of `W · m × H · m` metres (`m` metres per pixel)
//!   centred on the camera; depth is the distance along the axis. Mounted with pitch +90° it looks straight
//!   down with the vessel's forward direction at the top of the image.
//!
//! * Lens distortion (optional, pinhole only): Brown–Conrady in OpenCV's convention ([`Distortion`]): a pixel at
//!   distorted normalised coordinates `(x_d, y_d)` sees the ray of the undistorted `(x, y)`.
//!
//! One render casts every pixel's primary ray at once on the frozen scene; RGB adds shadow rays, reflected rays
//! on water and sub-pixel rays on edges ([`radiance`], [`Quality`]). Outputs per pixel: depth (float32 metres,
//! +inf for sky), semantic class (uint16, 0 for sky), instance id (int32, −1 for sky), all from the pixel centre,
//! and optionally sRGB (uint8 × 3) and linear radiance (float32 × 3, cd/m²).
//!
//! A pixel's ray that goes down towards the sea and meets nothing within the range (`range_max`), or past the
//! water's mesh, meets the still water beyond it ([`Scene::sea_beyond`]): the pixel is water in the semantic and
//! instance images (the sea's class and instance) with the still water's depth, as the RGB shades it (the sea
//! below the horizon). So depth is +inf exactly where the instance is −1, the sky. Before, such pixels were
//! labelled sky: with `range_m: 150`, the band of sea from 150 m out to the horizon.

use super::rays;
use super::shade::rain::{self, RainView};
use super::shade::tonemap::{self, SensorNoise};
use super::shade::wake::Wake;
use super::shade::{ShadeEnv, Shader};
use crate::error::{MmusvError, Result};
use crate::geometry::RigidPose;
use crate::scene::{KnownWater, Scene};
use crate::sea::{PinholeView, Raster, WaveSurface};
use parry3d::math::Vec3;
use rayon::prelude::*;

mod antialias;
mod distortion;
mod glossy;
mod lamp_glow;
mod lamp_halo;
mod lamp_light;
mod lamp_points;
mod lamp_shadows;
pub mod radiance;
mod sunlit;

use antialias::surface_key;
use distortion::check_distortion;
pub use distortion::Distortion;
use radiance::Reflections;

/// Largest image side, pixels.
pub const MAX_SIDE: u32 = 16_384;
/// Most pixels of one image (4096 × 4096, about 16.8 M): a camera's rays and a frame's buffers take about 150 bytes
/// a pixel, so a 16384 × 16384 image (both sides allowed) would want some 40 GB and abort in the allocator.
pub const MAX_PIXELS: u64 = 4096 * 4096;

/// How pixels map to rays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    /// Pinhole with horizontal field of view (radians, in (0, π)).
    Pinhole {
        /// Horizontal field of view, radians.
        hfov: f64,
    },
    /// Parallel rays, `metres_per_pixel` apart.
    Orthographic {
        /// Ground sampling distance, metres per pixel (> 0).
        metres_per_pixel: f64,
    },
}

/// How much work the RGB image gets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Quality {
    /// One sample per pixel; water reflects the sky only; wakes are foam without their Kelvin waves.
    Draft,
    /// Traced water reflections, one per 2 × 2 block of water pixels (4 × 4 where the water's glossy lobe spans
    /// many such blocks), each in a direction drawn from that lobe and spread over the rest of it; 4 stratified
    /// samples on edge pixels; the sky's light hidden from a mesh's recesses by the mesh itself (also at `high`).
    #[default]
    Standard,
    /// Traced water reflections for every pixel; 16 stratified samples on edge pixels.
    High,
}

impl Quality {
    /// Samples averaged on an edge pixel (1: no anti-aliasing).
    pub fn edge_samples(self) -> u32 {
        match self {
            Quality::Draft => 1,
            Quality::Standard => 4,
            Quality::High => 16,
        }
    }
    /// Whether water reflections are traced.
    pub fn reflections(self) -> bool {
        !matches!(self, Quality::Draft)
    }
    /// Whether the water shows the vessels' Kelvin waves (`shade/kelvin.rs`; `draft` draws their foam only).
    pub fn kelvin_waves(self) -> bool {
        !matches!(self, Quality::Draft)
    }
    /// Whether a mesh's own surfaces hide the sky's light from its recesses ([`crate::sky_visibility`]; `draft`
    /// lights every surface with the whole sky).
    pub fn sky_visibility(self) -> bool {
        !matches!(self, Quality::Draft)
    }
}

/// How the RGB image is formed: quality, lens distortion, sensor noise.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImageOptions {
    /// Anti-aliasing and reflections.
    pub quality: Quality,
    /// Lens distortion (pinhole cameras only).
    pub distortion: Option<Distortion>,
    /// Shot and read noise added before the tone curve.
    pub noise: Option<SensorNoise>,
    /// Automatic (compensated, up to a highest ISO) or fixed exposure ([`tonemap::Exposure`]).
    pub exposure: tonemap::Exposure,
}

/// Configuration of a camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraConfig {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Projection.
    pub projection: Projection,
    /// Farthest surface traced (metres, > 0; may be infinite); the still water beyond it is still water.
    pub range_max: f32,
    /// Image formation of the RGB.
    pub image: ImageOptions,
}

/// What one render produces beyond depth, class and instance.
#[derive(Debug, Clone, Copy)]
pub struct RenderOptions<'a> {
    /// The tone-mapped sRGB image.
    pub rgb: bool,
    /// The linear radiance (cd/m²; rain included, before sensor noise and exposure).
    pub radiance: bool,
    /// Swell, rain, jitter, glossy reflection directions and noise seed.
    pub seed: u64,
    /// Vessels under way, for their wakes.
    pub wakes: &'a [Wake],
}

/// One rendered image set. Arrays are row-major, `width · height` long (`× 3` for RGB).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CameraFrame {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Depth along the optical axis, metres; `+inf` where nothing was hit.
    pub depth: Vec<f32>,
    /// Semantic class per pixel, 0 where nothing was hit.
    pub semantic: Vec<u16>,
    /// Scene instance id per pixel, −1 where nothing was hit.
    pub instance: Vec<i32>,
    /// sRGB, 3 bytes per pixel; empty unless RGB was requested.
    pub rgb: Vec<u8>,
    /// Linear radiance (cd/m², linear sRGB primaries), 3 floats per pixel; empty unless requested.
    pub radiance: Vec<f32>,
}

/// Side of the square pixel tiles rays are traced in: a tile's 16 rays form one packet (see
/// [`crate::bvh::packet`]), much tighter than 16 pixels of a row.
const TILE: u32 = 4;
/// Half-side of the square around a camera over which its wakes are indexed (metres): most of its water pixels
/// lie within it; farther ones try every wake.
const FOAM_INDEX_M: f32 = 1_000.0;

/// World-frame ray origins and unit directions, one row per ray.
pub type WorldRays = (Vec<[f32; 3]>, Vec<[f32; 3]>);

/// A camera with its ray pattern computed once.
#[derive(Debug, Clone)]
pub struct Camera {
    cfg: CameraConfig,
    /// Body-frame ray direction of each pixel (pinhole) or the common direction (orthographic), in trace order.
    dirs: Vec<[f32; 3]>,
    /// Body-frame ray origin of each pixel (orthographic only), in trace order.
    origins: Vec<[f32; 3]>,
    /// Trace order: entry `k` is the row-major index of the `k`-th pixel traced ([`TILE`]² tiles, row by row).
    order: Vec<u32>,
    /// The inverse of `order`: entry `i` is the trace position of row-major pixel `i`.
    rank: Vec<u32>,
    /// Column and row of the pixel at each trace position.
    pos: Vec<[u16; 2]>,
}

/// Row-major pixel indices of a `w × h` image in [`TILE`]×[`TILE`] tiles, tiles row by row, pixels within a tile
/// row by row (partial tiles at the right and bottom edges).
fn tile_order(w: u32, h: u32) -> Vec<u32> {
    let mut order = Vec::with_capacity(w as usize * h as usize);
    for ty in (0..h).step_by(TILE as usize) {
        for tx in (0..w).step_by(TILE as usize) {
            for y in ty..(ty + TILE).min(h) {
                for x in tx..(tx + TILE).min(w) {
                    order.push(y * w + x);
                }
            }
        }
    }
    order
}

impl Camera {
    /// Validates `cfg` and precomputes the rays. Errors name the field (`camera.resolution`, `camera.hfov_deg`,
    /// `camera.metres_per_pixel`, `camera.range_m`, `camera.exposure.<field>`).
    pub fn new(cfg: CameraConfig) -> Result<Self> {
        if cfg.width == 0 || cfg.height == 0 || cfg.width > MAX_SIDE || cfg.height > MAX_SIDE {
            return Err(MmusvError::config(
                "camera.resolution",
                format!("[{}, {}]", cfg.width, cfg.height),
                format!("width and height must be in 1..={MAX_SIDE}"),
            ));
        }
        if u64::from(cfg.width) * u64::from(cfg.height) > MAX_PIXELS {
            return Err(MmusvError::config(
                "camera.resolution",
                format!("[{}, {}]", cfg.width, cfg.height),
                format!(
                    "{} pixels, more than the {MAX_PIXELS} allowed (4096 x 4096)",
                    u64::from(cfg.width) * u64::from(cfg.height)
                ),
            ));
        }
        if !(cfg.range_max > 0.0) {
            return Err(MmusvError::config("camera.range_m", cfg.range_max, "must be > 0 metres"));
        }
        cfg.image.exposure.validate()?;
        let (w, h) = (cfg.width, cfg.height);
        let (dirs, origins) = match cfg.projection {
            Projection::Pinhole { hfov } => {
                if !(hfov > 0.0 && hfov < std::f64::consts::PI) {
                    return Err(MmusvError::config(
                        "camera.hfov_deg",
                        hfov.to_degrees(),
                        "a pinhole camera needs a horizontal field of view strictly between 0 and 180 degrees; \
                         use several cameras for a wider view",
                    ));
                }
                let mut dirs = rays::pinhole_directions(w, h, hfov)?;
                if let Some(dist) = &cfg.image.distortion {
                    check_distortion(dist)?;
                    let f = w as f64 / (2.0 * (hfov / 2.0).tan());
                    for (i, d) in dirs.iter_mut().enumerate() {
                        let (u, v) = ((i as u32 % w) as f64 + 0.5, (i as u32 / w) as f64 + 0.5);
                        let (xd, yd) = ((u - w as f64 / 2.0) / f, (v - h as f64 / 2.0) / f);
                        let (x, y) = dist.undistort(xd, yd);
                        let (rx, ry) = dist.distort(x, y);
                        if !((rx - xd).abs() < 1e-6 && (ry - yd).abs() < 1e-6) {
                            return Err(MmusvError::config(
                                "camera.distortion",
                                format!("{:?}", dist.coefficients),
                                format!(
                                    "no ray maps to pixel ({}, {}): the distortion folds over within the image; \
                                     use smaller coefficients",
                                    u - 0.5,
                                    v - 0.5
                                ),
                            ));
                        }
                        let nrm = (x * x + y * y + 1.0).sqrt();
                        *d = [(1.0 / nrm) as f32, (-x / nrm) as f32, (-y / nrm) as f32];
                    }
                }
                (tile_order(w, h).iter().map(|&i| dirs[i as usize]).collect(), Vec::new())
            }
            Projection::Orthographic { metres_per_pixel: m } => {
                if cfg.image.distortion.is_some() {
                    return Err(MmusvError::config(
                        "camera.distortion",
                        "given",
                        "lens distortion applies to pinhole cameras only",
                    ));
                }
                // The pixels' offsets from the centre, up to half the larger side, must be finite in the f32 scene.
                let reach = m * f64::from(w.max(h)) / 2.0;
                if !(m.is_finite() && m > 0.0 && reach <= f64::from(f32::MAX)) {
                    return Err(MmusvError::config(
                        "camera.metres_per_pixel",
                        m,
                        "must be a finite distance > 0 (the image's half-width in metres within the f32 range)",
                    ));
                }
                let origins = tile_order(w, h)
                    .iter()
                    .map(|&i| {
                        let (u, v) = (i % w, i / w);
                        let y = (w as f64 / 2.0 - (u as f64 + 0.5)) * m;
                        let z = (h as f64 / 2.0 - (v as f64 + 0.5)) * m;
                        [0.0, y as f32, z as f32]
                    })
                    .collect();
                (vec![[1.0, 0.0, 0.0]], origins)
            }
        };
        let order = tile_order(w, h);
        let mut rank = vec![0u32; order.len()];
        for (k, &i) in order.iter().enumerate() {
            rank[i as usize] = k as u32;
        }
        let pos = order.iter().map(|&i| [(i % w) as u16, (i / w) as u16]).collect();
        Ok(Self { cfg, dirs, origins, order, rank, pos })
    }

    /// The configuration.
    pub fn config(&self) -> &CameraConfig {
        &self.cfg
    }

    /// Pinhole intrinsics `[fx, fy, cx, cy]` (pixels); `None` for an orthographic camera.
    pub fn intrinsics(&self) -> Option<[f64; 4]> {
        match self.cfg.projection {
            Projection::Pinhole { hfov } => rays::pinhole_intrinsics(self.cfg.width, self.cfg.height, hfov).ok(),
            Projection::Orthographic { .. } => None,
        }
    }

    /// World-frame ray origins and unit directions of every pixel, row-major.
    pub fn world_rays(&self, pose: &RigidPose) -> WorldRays {
        let (o, d) = self.traced_rays(pose);
        let mut origins = vec![[0f32; 3]; o.len()];
        let mut dirs = vec![[0f32; 3]; d.len()];
        for (k, &i) in self.order.iter().enumerate() {
            origins[i as usize] = o[k];
            dirs[i as usize] = d[k];
        }
        (origins, dirs)
    }

    /// World-frame ray origins and unit directions of the pixels `pixels` (row-major indices `v · W + u`), in
    /// the order given: the same values as the rows of [`Camera::world_rays`], without computing the others.
    /// An index outside the image is an error naming it (`pixels[i]`).
    pub fn pixel_rays(&self, pose: &RigidPose, pixels: &[i64]) -> Result<WorldRays> {
        let n = self.cfg.width as i64 * self.cfg.height as i64;
        if let Some((i, &p)) = pixels.iter().enumerate().find(|(_, &p)| !(0..n).contains(&p)) {
            return Err(MmusvError::input(
                format!("pixels[{i}]"),
                format!("{p} is outside the {}×{} image (0..{n})", self.cfg.width, self.cfg.height),
            ));
        }
        Ok(self.rays_at(pose, pixels.iter().map(|&p| self.rank[p as usize] as usize)))
    }

    /// World-frame ray origins and unit directions of every pixel in trace order (see [`Camera`]).
    fn traced_rays(&self, pose: &RigidPose) -> WorldRays {
        self.rays_at(pose, 0..self.cfg.width as usize * self.cfg.height as usize)
    }

    /// World-frame ray origins and unit directions of the rays at trace positions `ks`, in that order.
    fn rays_at(&self, pose: &RigidPose, ks: impl ExactSizeIterator<Item = usize>) -> WorldRays {
        let n = ks.len();
        if self.origins.is_empty() {
            let o = pose.translation.to_array();
            let d = ks.map(|k| pose.transform_vector(Vec3::from_array(self.dirs[k])).to_array()).collect();
            (vec![o; n], d)
        } else {
            let d = pose.transform_vector(Vec3::from_array(self.dirs[0])).to_array();
            let o = ks.map(|k| pose.transform_point(Vec3::from_array(self.origins[k])).to_array()).collect();
            (o, vec![d; n])
        }
    }

    /// Renders the frozen `scene` from `pose` (camera body → world). `rgb` asks for the shaded image; `seed`
    /// drives the swell, rain streaks, anti-aliasing jitter, the directions of the traced glossy reflections and
    /// sensor noise. No vessel wakes: see [`Camera::render_with`].
    pub fn render(&self, scene: &Scene, pose: &RigidPose, env: &ShadeEnv, rgb: bool, seed: u64) -> Result<CameraFrame> {
        self.render_with(scene, pose, env, &RenderOptions { rgb, radiance: false, seed, wakes: &[] })
    }

    /// Renders the frozen `scene` from `pose` (camera body → world) with `options`. A pose that is not finite or
    /// not rigid is an error naming `pose`.
    ///
    /// Depth, semantic class and instance come from each pixel's centre ray. The RGB image (and the linear
    /// radiance, when asked) is shaded by [`radiance::radiance`]: shadow rays towards the sun, traced water
    /// reflections above `draft` quality, and, on pixels at an edge (a change of instance, class or material, or
    /// of depth by more than 5 %), the mean of [`Quality::edge_samples`] stratified sub-pixel rays. Then rain (the
    /// drops near the lens, `shade/rain.rs`), sensor noise, exposure and the tone curve.
    pub fn render_with(
        &self,
        scene: &Scene,
        pose: &RigidPose,
        env: &ShadeEnv,
        options: &RenderOptions<'_>,
    ) -> Result<CameraFrame> {
        pose.validate("pose")?;
        let (origins, dirs) = self.traced_rays(pose);
        let waves = scene.wave_surface();
        let raster = waves.as_deref().and_then(|w| self.water_raster(w, pose));
        let range = self.cfg.range_max;
        let (o, d) = (&origins, &dirs);
        let water = raster.as_ref().map(|r| move |k: usize| r.resolve(self.order[k] as usize, o[k], d[k], range));
        let hits = scene.cast_rays_over(&origins, &dirs, range, water.as_ref().map(|w| w as &KnownWater<'_>))?;
        let n = origins.len();
        let axis = pose.transform_vector(Vec3::X);
        let sea_beyond = scene.sea_beyond();
        let mut frame = CameraFrame {
            width: self.cfg.width,
            height: self.cfg.height,
            depth: vec![f32::INFINITY; n],
            semantic: vec![0; n],
            instance: vec![0; n],
            rgb: Vec::new(),
            radiance: Vec::new(),
        };
        // Instance, class and material per pixel in one word, for the anti-aliasing's edge test only.
        let edges_wanted = (options.rgb || options.radiance) && self.cfg.image.quality.edge_samples() > 1;
        let mut surface = if edges_wanted { vec![0u64; n] } else { Vec::new() };
        for (k, &i) in self.order.iter().enumerate() {
            let i = i as usize;
            let t = hits.distance[k];
            if t.is_finite() {
                frame.depth[i] = t * Vec3::from_array(dirs[k]).dot(axis);
            }
            frame.semantic[i] = hits.class[k];
            frame.instance[i] = hits.instance[k];
            if !t.is_finite() {
                if let Some((sea, t)) = sea_beyond.and_then(|s| s.meet(origins[k], dirs[k]).map(|t| (s, t))) {
                    frame.depth[i] = t * Vec3::from_array(dirs[k]).dot(axis);
                    frame.semantic[i] = sea.class;
                    frame.instance[i] = sea.instance;
                }
            }
            if !surface.is_empty() {
                let material = scene.material_index(hits.instance[k], hits.triangle[k]);
                surface[i] = surface_key(hits.instance[k], hits.class[k], material);
            }
        }
        if !(options.rgb || options.radiance) {
            return Ok(frame);
        }
        let q = self.cfg.image.quality;
        // A pixel's footprint for the sea's detail bands: its angle (at the image centre) or its width.
        let (pixel_rad, pixel_m) = match self.cfg.projection {
            Projection::Pinhole { hfov } => ((2.0 * (0.5 * hfov).tan() / f64::from(self.cfg.width)) as f32, 0.0),
            Projection::Orthographic { metres_per_pixel } => (0.0, metres_per_pixel as f32),
        };
        let shader = Shader::new(env, options.seed, options.wakes)
            .with_kelvin_waves(q.kelvin_waves())
            .with_materials(scene.material_table())
            .with_sky_visibility_if(q.sky_visibility(), scene)
            .with_lamps(scene)
            .with_seabed(scene.seabed())
            .with_waves(scene.wave_surface())
            .with_footprint(pixel_rad, pixel_m)
            .with_exposure(&self.cfg.image.exposure)
            .with_foam_around([pose.translation.x, pose.translation.y], self.cfg.range_max.min(FOAM_INDEX_M));
        // Standard quality shares one traced reflection per 2 × 2 (or 4 × 4) block of water pixels; high traces
        // each; both spread them over the water's glossy lobe. Below
        // `high`, open water and sky share their shading over the pixels between even rows and columns wherever
        // the even pixels around agree (radiance::radiance).
        let grid = self.pixel_grid();
        let refl = match q {
            Quality::Draft => Reflections::Sky,
            Quality::Standard => Reflections::Shared(grid),
            Quality::High => Reflections::Every,
        };
        let shared = if q == Quality::High { None } else { Some(grid) };
        // Reflections spread over the water's roughness (pinhole cameras; the top view looks straight down).
        let glossy = match self.cfg.projection {
            Projection::Pinhole { .. } if pixel_rad > 0.0 => {
                Some((grid, 1.0 / pixel_rad, image_roll(pose), options.seed))
            }
            _ => None,
        };
        let shaded = radiance::radiance(scene, &shader, env.shadows, refl, shared, glossy, (&origins, &dirs, &hits))?;
        let mut linear = vec![Vec3::ZERO; n];
        for (k, &i) in self.order.iter().enumerate() {
            linear[i as usize] = shaded.radiance[k];
        }
        // The exposure: metered on the centre rays (before anti-aliasing), as the shared shading showed them.
        let (w, h) = (self.cfg.width as usize, self.cfg.height as usize);
        let k = shaded.exposure.unwrap_or_else(|| shader.metered_exposure(w, h, |p| linear[p]));
        if q.edge_samples() > 1 {
            let reflected = shaded.reflected.as_ref();
            let centres = antialias::Centres { frame: &frame, surface: &surface, hits: &hits, reflected };
            self.antialias(scene, pose, (&shader, env.shadows, options.seed, k), centres, &mut linear)?;
        }
        if !shader.lamps().is_empty() {
            // The lamps' glow in the air along each pixel's centre ray (`camera/lamp_halo.rs`).
            let grid = (q != Quality::High).then_some(grid);
            lamp_halo::add_lamp_halos(scene, &shader, (&origins, &dirs, &hits), grid, &self.order, &mut linear);
            // Lamps smaller than a pixel, from the lamps themselves (`camera/lamp_points.rs`).
            self.add_lamp_points(scene, pose, &shader, (&frame, &mut linear))?;
        }
        if let (Some([f, ..]), true) = (self.intrinsics(), env.rain_mm_per_h > 0.0) {
            // The drops near the lens (`shade/rain.rs`), in the exposure the camera metered.
            let view = RainView {
                size: (self.cfg.width, self.cfg.height),
                f: f as f32,
                rotation: pose.rotation,
                exposure_s: tonemap::exposure_time_s(k),
                rain_mm_per_h: env.rain_mm_per_h,
            };
            let drops = view.drops(options.seed);
            let (cover, light) = rain::coverage(view.size, &drops, &frame.depth, |d| shader.drop_radiance(d.dir));
            linear.par_iter_mut().zip(cover.par_iter().zip(light.par_iter())).for_each(|(c, (&a, &l))| {
                *c = rain::apply(*c, a, l);
            });
        }
        if options.radiance {
            frame.radiance = linear.iter().flat_map(|c| c.to_array()).collect();
        }
        if options.rgb {
            let noise = self.cfg.image.noise;
            let mut out = vec![0u8; 3 * n];
            out.par_chunks_mut(3 * w).zip(linear.par_chunks(w)).enumerate().for_each(|(row, (px, cs))| {
                let Some(nz) = noise else {
                    tonemap::to_srgb8_all(cs, k, px);
                    return;
                };
                for (j, c) in cs.iter().enumerate() {
                    let x = *c * k;
                    let p = (row * w + j) as u64;
                    let x = Vec3::new(
                        nz.apply(x.x, options.seed, p, 0),
                        nz.apply(x.y, options.seed, p, 1),
                        nz.apply(x.z, options.seed, p, 2),
                    );
                    px[3 * j..3 * j + 3].copy_from_slice(&tonemap::to_srgb8(x, 1.0));
                }
            });
            frame.rgb = out;
        }
        Ok(frame)
    }

    /// The scene's wave surface `waves` rasterised for this camera at `pose` ([`crate::sea::WaveSurface::first_hits`]),
    /// so that its traced rays' first water hits are solved from it ([`crate::sea::Raster::resolve`]) instead of
    /// marched ray by ray: for an undistorted pinhole camera whose origin stands clear above the water; `None`
    /// otherwise (the rays march).
    fn water_raster<'w>(&self, waves: &'w WaveSurface, pose: &RigidPose) -> Option<Raster<'w>> {
        let Projection::Pinhole { hfov } = self.cfg.projection else { return None };
        if self.cfg.image.distortion.is_some() {
            return None;
        }
        let axis = |v: Vec3| pose.transform_vector(v).to_array();
        let view = PinholeView {
            origin: pose.translation.to_array(),
            forward: axis(Vec3::X),
            right: axis(-Vec3::Y),
            down: axis(-Vec3::Z),
            width: self.cfg.width,
            height: self.cfg.height,
            focal: f64::from(self.cfg.width) / (2.0 * (hfov / 2.0).tan()),
        };
        waves.first_hits(&view)
    }

    /// The traced rays as a pixel grid (what the shading shared between neighbouring pixels reads).
    fn pixel_grid(&self) -> radiance::PixelGrid<'_> {
        radiance::PixelGrid { width: self.cfg.width, height: self.cfg.height, pos: &self.pos, rank: &self.rank }
    }

    /// Body-frame origin and unit direction of the ray through image point `(u, v)` (pixels, `(0, 0)` the
    /// top-left corner of the image).
    fn body_ray(&self, u: f64, v: f64) -> ([f32; 3], [f32; 3]) {
        let (w, h) = (self.cfg.width as f64, self.cfg.height as f64);
        match self.cfg.projection {
            Projection::Pinhole { hfov } => {
                let f = w / (2.0 * (hfov / 2.0).tan());
                let (xd, yd) = ((u - w / 2.0) / f, (v - h / 2.0) / f);
                let (x, y) = match &self.cfg.image.distortion {
                    Some(dist) => dist.undistort(xd, yd),
                    None => (xd, yd),
                };
                let nrm = (x * x + y * y + 1.0).sqrt();
                ([0.0; 3], [(1.0 / nrm) as f32, (-x / nrm) as f32, (-y / nrm) as f32])
            }
            Projection::Orthographic { metres_per_pixel: m } => {
                ([0.0, ((w / 2.0 - u) * m) as f32, ((h / 2.0 - v) * m) as f32], [1.0, 0.0, 0.0])
            }
        }
    }
}

/// How far the world's vertical shows turned in a pinhole image taken from `pose` (radians; 0 for a level camera,
/// `−θ` for one rolled by `θ` about its axis): the image's "down" (`−z` of the camera body, as `+v`) against the
/// world's down there. 0 when the camera looks straight up or down.
fn image_roll(pose: &RigidPose) -> f32 {
    let r = pose.rotation;
    // The world's up in the camera body: the third row of the rotation.
    let (up_y, up_z) = (r.y_axis.z, r.z_axis.z);
    if up_y == 0.0 && up_z == 0.0 {
        return 0.0;
    }
    (-up_y).atan2(up_z)
}

#[cfg(test)]
mod tests;
