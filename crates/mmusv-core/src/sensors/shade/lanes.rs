//! [`Shader::shade`] for [`LANES`] pixels at once, as structure-of-arrays loops the compiler vectorises (under
//! the caller's AVX2 dispatch): the same IEEE operations in the same order as the per-pixel formulas, so every
//! lane gets exactly the colour [`Shader::shade`] gives it. Only the libm calls (`cos`, `exp`, `powf`) stay one
//! lane at a time, and only for the lanes that need them.

use super::{albedo, Shader, SurfaceHit, GLINT_ZERO, SUN_DISC_ZERO};
use parry3d::math::Vec3;

/// Pixels shaded together by [`Shader::shade_lanes`].
pub const LANES: usize = 8;

/// Up to [`LANES`] camera rays as shading needs them, one array entry per lane (world frame, metres).
#[derive(Debug, Clone, Copy, Default)]
pub struct Lanes {
    /// Unit ray directions, `[x, y, z][lane]`.
    pub d: [[f32; LANES]; 3],
    /// Whether the ray hit a surface (else it sees the sky, and the fields below are ignored).
    pub hit: [bool; LANES],
    /// Hit distances.
    pub t: [f32; LANES],
    /// Hit points, `[x, y, z][lane]`.
    pub p: [[f32; LANES]; 3],
    /// Unit hit normals facing the camera, `[x, y, z][lane]`.
    pub n: [[f32; LANES]; 3],
    /// Semantic classes of the hits.
    pub class: [u16; LANES],
    /// Scene instance ids of the hits.
    pub instance: [i32; LANES],
    /// Whether each hit point sees the sun.
    pub lit: [bool; LANES],
}

impl Lanes {
    /// Sets lane `j` to ray direction `d` with hit `hit` (`None`: the sky) and sun visibility `lit`.
    #[inline(always)]
    pub fn set(&mut self, j: usize, d: Vec3, hit: Option<&SurfaceHit>, lit: bool) {
        let [dx, dy, dz] = d.to_array();
        (self.d[0][j], self.d[1][j], self.d[2][j]) = (dx, dy, dz);
        self.lit[j] = lit;
        match hit {
            Some(h) => {
                self.hit[j] = true;
                self.t[j] = h.t;
                (self.p[0][j], self.p[1][j], self.p[2][j]) = (h.point.x, h.point.y, h.point.z);
                (self.n[0][j], self.n[1][j], self.n[2][j]) = (h.normal.x, h.normal.y, h.normal.z);
                self.class[j] = h.class;
                self.instance[j] = h.instance;
            }
            None => {
                self.hit[j] = false;
                self.t[j] = 0.0;
                (self.p[0][j], self.p[1][j], self.p[2][j]) = (0.0, 0.0, 0.0);
                (self.n[0][j], self.n[1][j], self.n[2][j]) = (0.0, 0.0, 1.0);
                self.class[j] = 0;
                self.instance[j] = 0;
            }
        }
    }

    /// The hit of lane `j` (`None` for the sky).
    #[inline(always)]
    fn surface(&self, j: usize) -> Option<SurfaceHit> {
        self.hit[j].then(|| SurfaceHit {
            t: self.t[j],
            point: Vec3::new(self.p[0][j], self.p[1][j], self.p[2][j]),
            normal: Vec3::new(self.n[0][j], self.n[1][j], self.n[2][j]),
            class: self.class[j],
            instance: self.instance[j],
        })
    }
}

/// `x⁵` as LLVM expands `powi(x, 5)`: `x · (x²)²`.
#[inline(always)]
fn pow5(x: f32) -> f32 {
    let x2 = x * x;
    x * (x2 * x2)
}

/// `x⁸` as LLVM expands `powi(x, 8)`: `((x²)²)²`.
#[inline(always)]
fn pow8(x: f32) -> f32 {
    let x2 = x * x;
    let x4 = x2 * x2;
    x4 * x4
}

/// Linear RGB, `[r, g, b][lane]`.
pub type LaneColors = [[f32; LANES]; 3];

impl Shader {
    /// [`Shader::sky`] of the directions `v` (`[x, y, z][lane]`).
    #[inline(always)]
    fn sky_lanes(&self, v: &[[f32; LANES]; 3]) -> LaneColors {
        let env = &self.env;
        let (hor, zen) = (env.sky_horizon, env.sky_zenith);
        let mut c = [[0f32; LANES]; 3];
        for j in 0..LANES {
            let up = v[2][j].max(0.0).sqrt();
            for a in 0..3 {
                c[a][j] = (hor[a] * (1.0 - up) + zen[a] * up) * self.sky_brightness;
                if v[2][j] < 0.0 {
                    c[a][j] *= 0.8;
                }
            }
        }
        if env.sun_intensity > 0.0 {
            let s = self.sun;
            let mut cs = [0f32; LANES];
            let mut disc = [0f32; LANES];
            for j in 0..LANES {
                cs[j] = (v[0][j] * s.x + v[1][j] * s.y + v[2][j] * s.z).max(0.0);
            }
            for j in 0..LANES {
                // cs^2000 is exactly 0 below SUN_DISC_ZERO (see Shader::sky).
                if cs[j] > SUN_DISC_ZERO {
                    disc[j] = cs[j].powf(2000.0);
                }
            }
            for j in 0..LANES {
                let k = pow8(cs[j]) * 0.25 + disc[j] * 20.0;
                for a in 0..3 {
                    let add = c[a][j] + env.sun_color[a] * env.sun_intensity * k;
                    c[a][j] = if cs[j] > 0.0 { add } else { c[a][j] };
                }
            }
        }
        let sky_fog = self.sky_fog.to_array();
        for j in 0..LANES {
            for a in 0..3 {
                c[a][j] = c[a][j] * self.sky_keep + sky_fog[a];
            }
        }
        c
    }

    /// [`Shader::shade`] of every lane of `l`: bit for bit the per-pixel result.
    #[inline(always)]
    pub fn shade_lanes(&self, l: &Lanes) -> LaneColors {
        let water: [bool; LANES] = std::array::from_fn(|j| l.hit[j] && l.class[j] == 1);
        let (sun, sun_lit, amb) = (self.sun.to_array(), self.sun_lit.to_array(), self.ambient_light.to_array());
        let d = &l.d;
        // Swell slopes of the water lanes (Shader::water_normal), libm's cos lane by lane.
        let (mut gx, mut gy) = ([0f32; LANES], [0f32; LANES]);
        for w in &self.swell {
            let mut cos = [0f32; LANES];
            for j in 0..LANES {
                if water[j] {
                    cos[j] = (w.k * (w.c * l.p[0][j] + w.s * l.p[1][j]) + w.phase).cos();
                }
            }
            for j in 0..LANES {
                let slope = w.amp_k * cos[j];
                gx[j] += slope * w.c;
                gy[j] += slope * w.s;
            }
        }
        // Water: the perturbed normal (the geometric one where it faces away), Fresnel, reflection, glint.
        let mut r = [[0f32; LANES]; 3];
        let mut body = [[0f32; LANES]; 3];
        let mut fresnel = [0f32; LANES];
        let mut rs = [0f32; LANES];
        for j in 0..LANES {
            let v = [-gx[j], -gy[j], 1.0f32];
            let rcp = 1.0 / (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            let ok = rcp.is_finite() && rcp > 0.0;
            let mut n = if ok { [v[0] * rcp, v[1] * rcp, v[2] * rcp] } else { [0.0; 3] };
            if n[0] * d[0][j] + n[1] * d[1][j] + n[2] * d[2][j] > 0.0 {
                n = [l.n[0][j], l.n[1][j], l.n[2][j]];
            }
            let dn = d[0][j] * n[0] + d[1][j] * n[1] + d[2][j] * n[2];
            let cos = (-dn).clamp(0.0, 1.0);
            fresnel[j] = 0.02 + 0.98 * pow5(1.0 - cos);
            for a in 0..3 {
                r[a][j] = d[a][j] - n[a] * (2.0 * dn);
            }
            r[2][j] = r[2][j].abs();
            let lit = if l.lit[j] { 1.0 } else { 0.0 };
            let ns = (n[0] * sun[0] + n[1] * sun[1] + n[2] * sun[2]).max(0.0);
            for (a, c) in [0.01f32, 0.045, 0.06].into_iter().enumerate() {
                body[a][j] = c * (amb[a] + sun_lit[a] * lit * ns);
            }
            rs[j] = (r[0][j] * sun[0] + r[1][j] * sun[1] + r[2][j] * sun[2]).max(0.0);
        }
        let mut glint = [0f32; LANES];
        for j in 0..LANES {
            // rs^300 is exactly 0 below GLINT_ZERO (see Shader::shade).
            if water[j] && rs[j] > GLINT_ZERO {
                glint[j] = rs[j].powf(300.0);
            }
        }
        // The sky along each lane's reflection (water) or its own direction (sky).
        let mut v = *d;
        for j in 0..LANES {
            if water[j] {
                for a in 0..3 {
                    v[a][j] = r[a][j];
                }
            }
        }
        let sky = self.sky_lanes(&v);
        // Other surfaces: albedo lit by the sky and the sun, one lane at a time (the albedo hashes).
        let mut alb = [[0f32; LANES]; 3];
        for j in 0..LANES {
            if l.hit[j] && !water[j] {
                if let Some(h) = l.surface(j) {
                    let a = albedo(&h).to_array();
                    (alb[0][j], alb[1][j], alb[2][j]) = (a[0], a[1], a[2]);
                }
            }
        }
        let mut fog = [0f32; LANES];
        for j in 0..LANES {
            if l.hit[j] {
                fog[j] = (-self.env.fog_extinction_per_m * l.t[j]).exp();
            }
        }
        let fog_color = self.fog_color.to_array();
        let mut out = [[0f32; LANES]; 3];
        for j in 0..LANES {
            let lit = if l.lit[j] { 1.0 } else { 0.0 };
            let ns = (l.n[0][j] * sun[0] + l.n[1][j] * sun[1] + l.n[2][j] * sun[2]).max(0.0);
            let f = fog[j];
            for a in 0..3 {
                let sl = sun_lit[a] * lit;
                let wet = body[a][j] * (1.0 - fresnel[j]) + sky[a][j] * fresnel[j] + sl * glint[j] * 4.0;
                let dry = alb[a][j] * (amb[a] + sl * ns);
                let c = if water[j] { wet } else { dry };
                let fogged = c * f + fog_color[a] * (1.0 - f);
                out[a][j] = if l.hit[j] { fogged } else { sky[a][j] };
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn unit(rng: &mut ChaCha8Rng) -> Vec3 {
        loop {
            let v = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            if v.length() > 0.1 {
                return v.normalize();
            }
        }
    }

    /// Every lane's colour is bit for bit [`Shader::shade`]'s: sky, water and other classes mixed in one call,
    /// lit and shadowed, directions near the sun (disc) and reflections near it (glint), far and near hits,
    /// in clear noon, low sun with fog and swell, and night.
    #[test]
    fn lanes_equal_the_per_pixel_shading() {
        let envs = super::super::tests::test_envs();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut glints = 0;
        let mut discs = 0;
        for env in &envs {
            let sh = Shader::new(env, 42);
            let sun = Vec3::from_array(env.sun_direction).normalize();
            // The mirror image of the sun in a level sea: rays along it glint.
            let glint_dir = Vec3::new(sun.x, sun.y, -sun.z);
            for _ in 0..6_000 {
                let mut l = Lanes::default();
                let mut want = Vec::new();
                for j in 0..LANES {
                    let d = match rng.random_range(0..6) {
                        0 => (sun + unit(&mut rng) * 0.05).normalize(),
                        1 => (glint_dir + unit(&mut rng) * 0.05).normalize(),
                        _ => unit(&mut rng),
                    };
                    let kind = rng.random_range(0..4);
                    let hit = (kind > 0).then(|| {
                        let t = rng.random_range(0.5f32..8_000.0);
                        let mut normal = if kind == 1 { Vec3::Z } else { unit(&mut rng) };
                        if normal.dot(d) > 0.0 {
                            normal = -normal;
                        }
                        SurfaceHit {
                            t,
                            point: Vec3::new(rng.random_range(-3e3..3e3), rng.random_range(-3e3..3e3), 0.0),
                            normal,
                            class: if kind == 1 { 1 } else { rng.random_range(0..13) },
                            instance: rng.random_range(-1..40),
                        }
                    });
                    let lit = rng.random_bool(0.7);
                    l.set(j, d, hit.as_ref(), lit);
                    want.push(sh.shade(d, hit.as_ref(), lit));
                    if env.sun_intensity > 0.0 && hit.is_none() && d.dot(sun) > SUN_DISC_ZERO {
                        discs += 1;
                    }
                    if hit.is_some_and(|h| h.class == 1) && d.dot(glint_dir) > 0.99 {
                        glints += 1;
                    }
                }
                let got = sh.shade_lanes(&l);
                for (j, w) in want.iter().enumerate() {
                    let g = [got[0][j], got[1][j], got[2][j]];
                    assert_eq!(g.map(f32::to_bits), w.to_array().map(f32::to_bits), "lane {j}: {g:?} != {w:?}");
                }
            }
        }
        assert!(glints > 100 && discs > 100, "the cases near the sun were drawn: {glints} glints, {discs} discs");
    }
}
