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
//! One render casts every pixel's primary ray at once on the frozen scene and, for RGB, one shadow ray per lit
//! surface pixel towards the sun. Outputs per pixel: depth (float32 metres, +inf for sky), semantic class
//! (uint16, 0 for sky), instance id (int32, −1 for sky) and optionally sRGB (uint8 × 3).

use super::rays;
use super::shade::{self, Lanes, ShadeEnv, Shader, SurfaceHit, LANES};
use crate::error::{MmusvError, Result};
use crate::geometry::RigidPose;
use crate::scene::{RayHits, Scene};
use parry3d::math::Vec3;
use rayon::prelude::*;

/// Largest image side, pixels.
pub const MAX_SIDE: u32 = 16_384;

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

/// Configuration of a camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraConfig {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Projection.
    pub projection: Projection,
    /// Farthest surface rendered (metres, > 0; may be infinite).
    pub range_max: f32,
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
}

/// Side of the square pixel tiles rays are traced in: a tile's 16 rays form one packet (see
/// [`crate::bvh::packet`]), much tighter than 16 pixels of a row.
const TILE: u32 = 4;

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
    /// `camera.metres_per_pixel`, `camera.range_m`).
    pub fn new(cfg: CameraConfig) -> Result<Self> {
        if cfg.width == 0 || cfg.height == 0 || cfg.width > MAX_SIDE || cfg.height > MAX_SIDE {
            return Err(MmusvError::config(
                "camera.resolution",
                format!("[{}, {}]", cfg.width, cfg.height),
                format!("width and height must be in 1..={MAX_SIDE}"),
            ));
        }
        if !(cfg.range_max > 0.0) {
            return Err(MmusvError::config("camera.range_m", cfg.range_max, "must be > 0 metres"));
        }
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
                let dirs = rays::pinhole_directions(w, h, hfov)?;
                (tile_order(w, h).iter().map(|&i| dirs[i as usize]).collect(), Vec::new())
            }
            Projection::Orthographic { metres_per_pixel: m } => {
                if !(m.is_finite() && m > 0.0) {
                    return Err(MmusvError::config("camera.metres_per_pixel", m, "must be a finite distance > 0"));
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
        Ok(Self { cfg, dirs, origins, order: tile_order(w, h) })
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
        Ok(self.rays_at(pose, pixels.iter().map(|&p| self.trace_index(p as u32))))
    }

    /// Position in trace order of row-major pixel `i` (the inverse of [`tile_order`]).
    fn trace_index(&self, i: u32) -> usize {
        let (w, h) = (self.cfg.width as usize, self.cfg.height as usize);
        let (x, y) = (i as usize % w, i as usize / w);
        let t = TILE as usize;
        let (tx, ty) = (x / t, y / t);
        // Tile rows above, tiles to the left in this tile row (all full width), then the pixel in its tile.
        let th = t.min(h - ty * t);
        let tw = t.min(w - tx * t);
        ty * t * w + tx * t * th + (y - ty * t) * tw + (x - tx * t)
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

    /// Renders the frozen `scene` from `pose` (camera body → world). `rgb` asks for the shaded image (one more
    /// ray per sunlit surface pixel); `seed` drives the water ripples and rain streaks.
    ///
    /// Rays are traced in [`TILE`]×[`TILE`] tiles (coherent packets), shadow rays as occlusion queries that stop
    /// at the first occluder, and the results scattered back to row-major order: the same image as tracing and
    /// shading pixel by pixel.
    pub fn render(&self, scene: &Scene, pose: &RigidPose, env: &ShadeEnv, rgb: bool, seed: u64) -> Result<CameraFrame> {
        let (origins, dirs) = self.traced_rays(pose);
        let hits = scene.cast_rays(&origins, &dirs, self.cfg.range_max)?;
        let n = origins.len();
        let axis = pose.transform_vector(Vec3::X);
        let mut frame = CameraFrame {
            width: self.cfg.width,
            height: self.cfg.height,
            depth: vec![f32::INFINITY; n],
            semantic: vec![0; n],
            instance: vec![0; n],
            rgb: Vec::new(),
        };
        for (k, &i) in self.order.iter().enumerate() {
            let i = i as usize;
            let t = hits.distance[k];
            if t.is_finite() {
                frame.depth[i] = t * Vec3::from_array(dirs[k]).dot(axis);
            }
            frame.semantic[i] = hits.class[k];
            frame.instance[i] = hits.instance[k];
        }
        if !rgb {
            return Ok(frame);
        }
        let surface = |k: usize| surface_at(&hits, &origins, &dirs, k);
        // Shadow rays from every surface point facing the sun, in trace order (neighbouring points, one packet),
        // gathered block by block.
        let sun = Vec3::from_array(env.sun_direction).normalize_or_zero();
        let mut lit = vec![false; n];
        if env.sun_intensity > 0.0 && sun.z > 0.0 {
            const BLOCK: usize = 4096;
            let blocks: Vec<(Vec<u32>, Vec<[f32; 3]>)> = (0..n.div_ceil(BLOCK))
                .into_par_iter()
                .map(|b| {
                    let (mut ks, mut os) = (Vec::new(), Vec::new());
                    for k in b * BLOCK..((b + 1) * BLOCK).min(n) {
                        if let Some(h) = surface(k).filter(|h| h.normal.dot(sun) > 0.0 || h.class == 1) {
                            let eps = 0.02 + 1e-4 * h.t;
                            ks.push(k as u32);
                            os.push((h.point + h.normal * eps).to_array());
                        }
                    }
                    (ks, os)
                })
                .collect();
            let facing: Vec<u32> = blocks.iter().flat_map(|(ks, _)| ks.iter().copied()).collect();
            if env.shadows {
                let so: Vec<[f32; 3]> = blocks.into_iter().flat_map(|(_, os)| os).collect();
                let sd = vec![sun.to_array(); so.len()];
                let blocked = scene.occluded_rays(&so, &sd, 5_000.0)?;
                for (&k, b) in facing.iter().zip(blocked) {
                    lit[k as usize] = !b;
                }
            } else {
                for &k in &facing {
                    lit[k as usize] = true;
                }
            }
        }
        // Shade tile row by tile row: the trace positions of a tile row are exactly the row-major pixels of its
        // image rows, so each row block is written in place.
        let w = self.cfg.width as usize;
        let rows = TILE as usize * w;
        let shader = Shader::new(env, seed);
        let mut out = vec![0u8; 3 * n];
        let traced = Traced { order: &self.order, origins: &origins, dirs: &dirs, hits: &hits, lit: &lit };
        out.par_chunks_mut(3 * rows).enumerate().for_each(|(r, px)| {
            shade_rows(px, r * rows, w, &traced, &shader, seed);
        });
        frame.rgb = out;
        Ok(frame)
    }
}

/// The hit of trace position `k` as shading needs it (normal turned towards the camera), `None` for a miss.
#[inline(always)]
fn surface_at(hits: &RayHits, origins: &[[f32; 3]], dirs: &[[f32; 3]], k: usize) -> Option<SurfaceHit> {
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
    Some(SurfaceHit { t, point, normal, class: hits.class[k], instance: hits.instance[k] })
}

/// One render's traced rays, in trace order, with their hits and whether each hit sees the sun.
struct Traced<'a> {
    order: &'a [u32],
    origins: &'a [[f32; 3]],
    dirs: &'a [[f32; 3]],
    hits: &'a RayHits,
    lit: &'a [bool],
}

crate::dispatch! {
    /// Shades the trace positions `base..` that fill `px` (row-major RGB8 of the image rows starting at pixel
    /// `base`; `w` pixels a row). Under the AVX2 dispatch: the shading maths ([`Shader::shade_lanes`], [`LANES`]
    /// pixels at a time) inlines into it and vectorises; the bytes are the portable build's and
    /// [`Shader::shade`]'s (Rust never contracts a multiply and an add into an FMA).
    fn shade_rows(px: &mut [u8], base: usize, w: usize, traced: &Traced<'_>, shader: &Shader, seed: u64) {
        let end = base + px.len() / 3;
        let mut k0 = base;
        while k0 < end {
            // LANES pixels at a time (the last group padded with copies of its last pixel).
            let m = LANES.min(end - k0);
            let mut lanes = Lanes::default();
            for j in 0..LANES {
                let k = k0 + j.min(m - 1);
                let h = surface_at(traced.hits, traced.origins, traced.dirs, k);
                lanes.set(j, Vec3::from_array(traced.dirs[k]), h.as_ref(), traced.lit[k]);
            }
            let c = shader.shade_lanes(&lanes);
            for j in 0..m {
                let i = traced.order[k0 + j] as usize;
                let c = shader.rain(Vec3::new(c[0][j], c[1][j], c[2][j]), (i % w) as u32, (i / w) as u32, seed);
                let at = 3 * (i - base);
                px[at..at + 3].copy_from_slice(&shade::to_srgb8(c));
            }
            k0 += m;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;

    fn ground_with_box() -> Scene {
        let mut s = Scene::new();
        let g = [[-500.0, -500.0, 0.0], [500.0, -500.0, 0.0], [500.0, 500.0, 0.0], [-500.0, 500.0, 0.0]];
        let gf = [[0i64, 1, 2], [0, 2, 3]];
        if let Ok(m) = Mesh::new("ground", &g, &gf, &[1, 1]) {
            let id = s.add_mesh(m);
            let _ = s.add_instance(id, RigidPose::IDENTITY, None);
        }
        // A 4 m cube centred at (20, 0, 2).
        let mut v = Vec::new();
        for i in 0..8 {
            v.push([18.0 + 4.0 * (i & 1) as f32, -2.0 + 4.0 * ((i >> 1) & 1) as f32, 4.0 * ((i >> 2) & 1) as f32]);
        }
        let f: Vec<[i64; 3]> = vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        if let Ok(m) = Mesh::new("cube", &v, &f, &[10; 12]) {
            let id = s.add_mesh(m);
            let _ = s.add_instance(id, RigidPose::IDENTITY, None);
        }
        s
    }

    #[test]
    fn pinhole_depth_is_along_the_axis() {
        let cam = Camera::new(CameraConfig {
            width: 64,
            height: 48,
            projection: Projection::Pinhole { hfov: 1.5 },
            range_max: 1e4,
        });
        let Ok(cam) = cam else { return };
        let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 2.0], [0.0, 0.0, 0.0]);
        let f = cam.render(&ground_with_box(), &pose, &ShadeEnv::default(), true, 1).unwrap_or_default();
        assert_eq!(f.rgb.len(), 64 * 48 * 3);
        // Centre pixel looks at the cube's face at x = 18: depth 18 m along the axis.
        let c = 24 * 64 + 32;
        assert!((f.depth[c] - 18.0).abs() < 1e-3, "depth {}", f.depth[c]);
        assert_eq!(f.semantic[c], 10);
        assert_eq!(f.instance[c], 1);
        // Top row sees the sky.
        assert_eq!(f.instance[0], -1);
        assert!(f.depth[0].is_infinite());
    }

    #[test]
    fn orthographic_top_view_sees_the_cube_at_its_place() {
        let m = 0.5;
        let cam = Camera::new(CameraConfig {
            width: 200,
            height: 200,
            projection: Projection::Orthographic { metres_per_pixel: m },
            range_max: 1e4,
        });
        let Ok(cam) = cam else { return };
        // 100 m up, looking down (pitch +90°), forward = +x at the top of the image.
        let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 100.0], [0.0, std::f64::consts::FRAC_PI_2, 0.0]);
        let f = cam.render(&ground_with_box(), &pose, &ShadeEnv::default(), false, 1).unwrap_or_default();
        // World (20, 0) is 20 m ahead: row 100 - 40 = 60 (centre 59.5..60.5), column 100 (y = 0).
        let px = |u: usize, v: usize| v * 200 + u;
        assert_eq!(f.instance[px(100, 60)], 1);
        assert!((f.depth[px(100, 60)] - 96.0).abs() < 1e-3);
        // 4 m wide: 8 pixels; just outside is ground.
        assert_eq!(f.instance[px(100, 55)], 0);
        assert_eq!(f.instance[px(100, 65)], 0);
        assert_eq!(f.instance[px(105, 60)], 0);
        assert!(f.rgb.is_empty());
    }

    #[test]
    fn pixel_rays_are_the_world_rays_of_those_pixels() {
        // Sizes with partial tiles at the right and bottom edges, both projections.
        for (w, h, projection) in [
            (13u32, 7u32, Projection::Pinhole { hfov: 1.2 }),
            (8, 8, Projection::Pinhole { hfov: 0.7 }),
            (9, 6, Projection::Orthographic { metres_per_pixel: 0.5 }),
        ] {
            let cam = Camera::new(CameraConfig { width: w, height: h, projection, range_max: 100.0 });
            let Ok(cam) = cam else { panic!("camera {w}x{h}") };
            let pose = RigidPose::from_xyz_rpy([3.0, -2.0, 5.0], [0.1, 0.4, -0.7]);
            let (o, d) = cam.world_rays(&pose);
            let all: Vec<i64> = (0..(w * h) as i64).rev().collect();
            let Ok((po, pd)) = cam.pixel_rays(&pose, &all) else { panic!("pixel_rays {w}x{h}") };
            for (j, &p) in all.iter().enumerate() {
                assert_eq!(po[j], o[p as usize], "origin of pixel {p} ({w}x{h})");
                assert_eq!(pd[j], d[p as usize], "direction of pixel {p} ({w}x{h})");
            }
            let err = cam.pixel_rays(&pose, &[0, (w * h) as i64]).err().map(|e| e.to_string()).unwrap_or_default();
            assert!(err.contains("pixels[1]"), "{err}");
            assert!(cam.pixel_rays(&pose, &[-1]).is_err());
        }
    }

    #[test]
    fn bad_configs_name_the_field() {
        let bad = |c: CameraConfig| Camera::new(c).err().map(|e| e.to_string()).unwrap_or_default();
        let ok = CameraConfig { width: 8, height: 8, projection: Projection::Pinhole { hfov: 1.0 }, range_max: 10.0 };
        assert!(bad(CameraConfig { projection: Projection::Pinhole { hfov: std::f64::consts::PI }, ..ok })
            .contains("camera.hfov_deg"));
        assert!(bad(CameraConfig { width: 0, ..ok }).contains("camera.resolution"));
        assert!(bad(CameraConfig { range_max: -1.0, ..ok }).contains("camera.range_m"));
        assert!(bad(CameraConfig { projection: Projection::Orthographic { metres_per_pixel: 0.0 }, ..ok })
            .contains("metres_per_pixel"));
    }
}
