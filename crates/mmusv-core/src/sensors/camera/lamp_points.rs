//! Navigation lamps smaller than a pixel, seen directly: each delivers its light to the pixel it projects into.
//!
//! A pixel's value is the mean radiance over its area. A lantern's lens at a distance is far smaller than a pixel
//! (a 0.04 m² lens 200 m off covers a tenth of a 640 × 480, 90° camera's pixel), so the pixel-centre ray misses it
//! in most frames and the lamp vanishes, or hits it and paints the whole pixel with the lens's radiance, tens of
//! times too bright. Here, as the glitter on the water (`shade/lamp_glitter.rs`), the lamp is sampled itself: its
//! illuminance at the camera, `E = I(−l) e^{−σ r} / r²` (its intensity towards the camera inside its COLREG arc,
//! `scene/lamps.rs`, through the fog), spread over the pixel's solid angle `Ω`, over the background it hides:
//! `L = L_bg (1 − c) + E / Ω`, `c = A_proj / (r² Ω)` its share of the pixel (the pixel-area mean of a lens of
//! radiance `L_e`: `L_bg (1 − c) + L_e c`, with `L_e A_proj = I`). The background is the pixel's own shading where
//! its centre ray missed the lantern, else the mean of its 4-neighbours. A shadow ray from the camera to the lamp
//! lets hulls, crests and the lamp's own vessel hide it. Lamps that cover a pixel or more are left to the pixel
//! rays and the anti-aliasing. Pinhole cameras, while the lamps' glitter is on (the sun below
//! `shade::lamp_glitter::LAMP_GLITTER_SUN_DEG`).

use super::{Camera, CameraFrame, Projection};
use crate::error::Result;
use crate::geometry::RigidPose;
use crate::scene::{Scene, Scratch};
use crate::sensors::shade::Shader;
use parry3d::math::Vec3;

impl Camera {
    /// Adds the lamps smaller than a pixel to `linear` (row-major, linear RGB) of the frame rendered from `pose`
    /// (see the module docs); the lamps are the shader's ([`Shader::lamps`]).
    pub(super) fn add_lamp_points(
        &self,
        scene: &Scene,
        pose: &RigidPose,
        shader: &Shader,
        (frame, linear): (&CameraFrame, &mut [Vec3]),
    ) -> Result<()> {
        let Projection::Pinhole { .. } = self.cfg.projection else { return Ok(()) };
        let (w, h) = (self.cfg.width as i64, self.cfg.height as i64);
        let eye = pose.translation;
        let axis = pose.transform_vector(Vec3::X);
        let mut scratch = Scratch::default();
        for lamp in shader.lamps().lamps() {
            let to = lamp.centre - eye;
            let r = to.length();
            if r.is_nan() || r <= 0.0 {
                continue;
            }
            let l = to / r;
            let Some((u, v)) = self.project(pose.inverse_transform_vector(to)) else { continue };
            let (px, py) = (u.floor() as i64, v.floor() as i64);
            if px < 0 || py < 0 || px >= w || py >= h {
                continue;
            }
            let omega = self.pixel_solid_angle(px as f64, py as f64);
            let cover = lamp.projected_area(l) / (r * r * omega);
            // A lamp of a pixel or more: the pixel rays see it.
            if cover.is_nan() || cover >= 1.0 {
                continue;
            }
            let i = lamp.intensity(-l);
            if i == Vec3::ZERO || scene.occluded_with(eye, l, r - 1.5 * lamp.radius, &mut scratch) {
                continue;
            }
            let p = (py * w + px) as usize;
            // Whether the pixel's centre ray met this lamp's lantern (its instance, at the lamp's depth).
            let depth = to.dot(axis);
            let on_lantern =
                frame.instance[p] == lamp.instance as i32 && (frame.depth[p] - depth).abs() <= 2.0 * lamp.radius + 0.5;
            let background = if on_lantern {
                let mut sum = Vec3::ZERO;
                let mut count = 0.0f32;
                for (dx, dy) in [(-1, 0), (1, 0), (0, -1), (0, 1)] {
                    let (x, y) = (px + dx, py + dy);
                    if x >= 0 && y >= 0 && x < w && y < h {
                        sum += linear[(y * w + x) as usize];
                        count += 1.0;
                    }
                }
                sum / count.max(1.0)
            } else {
                linear[p]
            };
            linear[p] = background * (1.0 - cover) + shader.transmitted(i, r) / (r * r * omega);
        }
        Ok(())
    }

    /// Image point `(u, v)` (pixels, `(0, 0)` the top-left corner) of body-frame point `b` (x forward, y left, z
    /// up) seen by this pinhole camera; `None` behind it.
    fn project(&self, b: Vec3) -> Option<(f64, f64)> {
        let Projection::Pinhole { hfov } = self.cfg.projection else { return None };
        if b.x <= 0.0 {
            return None;
        }
        let (w, h) = (f64::from(self.cfg.width), f64::from(self.cfg.height));
        let f = w / (2.0 * (hfov / 2.0).tan());
        let (x, y) = (-f64::from(b.y) / f64::from(b.x), -f64::from(b.z) / f64::from(b.x));
        let (xd, yd) = match &self.cfg.image.distortion {
            Some(dist) => dist.distort(x, y),
            None => (x, y),
        };
        Some((xd * f + w / 2.0, yd * f + h / 2.0))
    }

    /// Solid angle (sr) of pixel `(x, y)` (its top-left corner): the spherical quadrilateral of its corner rays,
    /// as two triangles (Van Oosterom & Strackee 1983), distortion included.
    fn pixel_solid_angle(&self, x: f64, y: f64) -> f32 {
        let ray = |u: f64, v: f64| Vec3::from_array(self.body_ray(u, v).1);
        let [a, b, c, d] = [ray(x, y), ray(x + 1.0, y), ray(x + 1.0, y + 1.0), ray(x, y + 1.0)];
        let tri = |p: Vec3, q: Vec3, s: Vec3| {
            let num = p.dot(q.cross(s)).abs();
            let den = 1.0 + p.dot(q) + q.dot(s) + s.dot(p);
            2.0 * num.atan2(den)
        };
        tri(a, b, c) + tri(a, c, d)
    }
}
