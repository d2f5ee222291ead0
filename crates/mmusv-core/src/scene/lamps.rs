//! The scene's lit navigation lamps as small light sources, for the camera's next-event estimation of their
//! glitter on the water (`sensors/shade/lamp_glitter.rs`) and their light on other surfaces (`lamp_light.rs`),
//! their glow in the air (`lamp_halo.rs`) and the lamps smaller than a pixel (`camera/lamp_points.rs`).
//!
//! A lamp is the faces of one instance that share a navigation-light material
//! ([`crate::material::Material::nav_light`]) and lie within [`LAMP_GROUP_M`] of the first face of their group
//! (a lantern's lens: a ring of faces round a vertical axis). Its intensity towards a direction `ω` is its
//! radiance times its projected area, `L_e · ½ Σ A_i |n_i · ω|` (the half: a closed lens shows each direction one
//! side of every pair of opposite faces), inside the lamp's COLREG arc and nothing outside it. A [`Lamp`] is made
//! ready once per render for the many queries of those passes: the arc's trigonometry and the body axes worked
//! out, and the area vectors of faces facing the same way summed (a lens quad's two triangles), which gives the
//! same `½ Σ |A_i · ω|` every way.

use super::Scene;
use crate::geometry::RigidPose;
use crate::material::{LightArc, Material};
use parry3d::math::Vec3;

/// Faces of one navigation-light material within this distance (metres, body frame) of a group's first face
/// belong to that lamp; farther ones start another (two masthead lanterns of one ship lie metres apart).
pub const LAMP_GROUP_M: f32 = 1.0;

/// One lit lamp, in the world frame, made ready for the many intensity queries of a render ([`Lamp::new`]).
#[derive(Debug, Clone)]
pub struct Lamp {
    /// Centre of its faces (area-weighted), world frame, metres.
    pub centre: Vec3,
    /// Largest distance of a face's corner from the centre, metres.
    pub radius: f32,
    /// Area vectors of its faces (unit normal times area, m²), world frame, those facing the same way summed.
    faces: Vec<Vec3>,
    /// Its material (radiance, arc).
    pub material: Material,
    /// Its instance's pose (the arc is a bearing in the body frame).
    pub pose: RigidPose,
    /// Its instance.
    pub instance: u32,
    /// The material's arc, made ready; `None` all round.
    arc: Option<LightArc>,
    /// The body axes in the world frame: the rows of the world-to-body rotation.
    body_axes: [Vec3; 3],
    /// [`Lamp::max_intensity`].
    max_intensity: f32,
}

/// `faces` with the area vectors of faces that face the same way summed (the two triangles of a lens quad): the
/// same `½ Σ |A_i · w|` every way, as `|a · w| + |b · w| = |(a + b) · w|` for `a`, `b` of one direction; faces
/// without area left out.
fn merged_faces(faces: &[Vec3]) -> Vec<Vec3> {
    let mut out: Vec<Vec3> = Vec::new();
    for &a in faces {
        let len = a.length();
        if len.is_nan() || len <= 0.0 {
            continue;
        }
        match out.iter_mut().find(|b| b.dot(a) >= (1.0 - 1e-6) * b.length() * len) {
            Some(b) => *b += a,
            None => out.push(a),
        }
    }
    out
}

impl Lamp {
    /// The lamp of `material` whose lens has the area vectors `faces` (m², world frame) round `centre` within
    /// `radius` (world frame, m), on instance `instance` at `pose`: its arc's trigonometry done once and the faces
    /// that face the same way merged, so that [`Lamp::intensity`] is a few dot products.
    pub fn new(centre: Vec3, radius: f32, faces: &[Vec3], material: Material, pose: RigidPose, instance: u32) -> Self {
        let axis = |v: Vec3| pose.transform_vector(v);
        let max_intensity = material.emissive.iter().fold(0.0f32, |a, &e| a.max(e))
            * 0.5
            * faces.iter().map(|a| a.length()).sum::<f32>();
        Self {
            centre,
            radius,
            faces: merged_faces(faces),
            material,
            pose,
            instance,
            arc: material.arc(),
            body_axes: [axis(Vec3::X), axis(Vec3::Y), axis(Vec3::Z)],
            max_intensity,
        }
    }

    /// Area vectors of its lens (m², world frame), those of faces that face the same way summed.
    pub fn faces(&self) -> &[Vec3] {
        &self.faces
    }

    /// The material's arc ([`Material::arc`]); `None` all round.
    #[inline]
    pub fn arc(&self) -> Option<LightArc> {
        self.arc
    }

    /// World vector `v` in the instance's body frame.
    #[inline]
    pub fn to_body(&self, v: Vec3) -> Vec3 {
        Vec3::new(self.body_axes[0].dot(v), self.body_axes[1].dot(v), self.body_axes[2].dot(v))
    }

    /// Intensity (cd, linear RGB) towards unit world direction `out` (from the lamp outwards): the projected area
    /// of the lens times its radiance inside the lamp's arc ([`Material::emits_towards`]), zero outside it.
    #[inline]
    pub fn intensity(&self, out: Vec3) -> Vec3 {
        if self.arc.is_some_and(|arc| !arc.contains(self.to_body(out))) {
            return Vec3::ZERO;
        }
        Vec3::from_array(self.material.emissive) * self.projected_area(out)
    }

    /// The most intensity (cd) the lamp gives in any direction and any colour: its brightest channel's radiance
    /// times `½ Σ A_i`, a bound on its projected area (every face seen face on).
    #[inline]
    pub fn max_intensity(&self) -> f32 {
        self.max_intensity
    }

    /// Area (m²) of the lens seen along unit direction `dir` (either way): `½ Σ A_i |n_i · dir|`.
    #[inline]
    pub fn projected_area(&self, dir: Vec3) -> f32 {
        0.5 * self.faces.iter().map(|a| a.dot(dir).abs()).sum::<f32>()
    }
}

impl Scene {
    /// The navigation lamps of the instances whose lights are on ([`Scene::set_lights`]), instance by instance in
    /// id order, each instance's in the order of their first face.
    pub fn nav_lamps(&self) -> Vec<Lamp> {
        let mut out = Vec::new();
        for (id, inst) in self.instances.iter().enumerate().filter(|(_, i)| i.lights_on()) {
            let mesh = &self.meshes[inst.mesh() as usize];
            let (verts, faces) = (mesh.vertices(), mesh.faces());
            // Per lamp (body frame): its material, its first face's centroid, and its faces' corners and area
            // vectors.
            let mut groups: Vec<(u16, Vec3, Vec<Vec3>, Vec<Vec3>)> = Vec::new();
            for (t, f) in faces.iter().enumerate() {
                let mat = mesh.material(t as u32);
                let Some(m) = self.materials.get(mat as usize).filter(|m| mat != 0 && m.nav_light) else {
                    continue;
                };
                if m.emissive.iter().all(|&e| e <= 0.0) {
                    continue;
                }
                let [a, b, c] = f.map(|v| verts[v as usize]);
                let centroid = (a + b + c) / 3.0;
                let area = 0.5 * (b - a).cross(c - a);
                let at = groups.iter().position(|g| g.0 == mat && (g.1 - centroid).length() <= LAMP_GROUP_M);
                let g = match at {
                    Some(i) => &mut groups[i],
                    None => {
                        groups.push((mat, centroid, Vec::new(), Vec::new()));
                        groups.last_mut().unwrap_or_else(|| unreachable!("a group was pushed"))
                    }
                };
                g.2.extend([a, b, c]);
                g.3.push(area);
            }
            let pose = *inst.pose();
            for (mat, _, corners, areas) in groups {
                // The area-weighted centre of the faces (their corners' mean where every face is degenerate).
                let total: f32 = areas.iter().map(|a| a.length()).sum();
                let centre = if total > 0.0 {
                    corners.chunks(3).zip(&areas).map(|(c, a)| (c[0] + c[1] + c[2]) / 3.0 * a.length()).sum::<Vec3>()
                        / total
                } else {
                    corners.iter().copied().sum::<Vec3>() / corners.len() as f32
                };
                let radius = corners.iter().map(|c| (*c - centre).length()).fold(0.0, f32::max);
                let faces: Vec<Vec3> = areas.iter().map(|a| pose.transform_vector(*a)).collect();
                let material = self.materials[mat as usize];
                out.push(Lamp::new(pose.transform_point(centre), radius, &faces, material, pose, id as u32));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;

    /// A closed square prism (side `s`, height `h`) round `at`, its 4 sides of material 1 and its caps of 2.
    fn lantern(at: Vec3, s: f32, h: f32) -> (Vec<[f32; 3]>, Vec<[i64; 3]>, Vec<u16>) {
        let r = s / 2.0;
        let mut v = Vec::new();
        for z in [0.0, h] {
            for (x, y) in [(-r, -r), (r, -r), (r, r), (-r, r)] {
                v.push([at.x + x, at.y + y, at.z + z]);
            }
        }
        let mut f = Vec::new();
        let mut m = Vec::new();
        for i in 0..4i64 {
            let j = (i + 1) % 4;
            f.extend([[i, j, j + 4], [i, j + 4, i + 4]]);
            m.extend([1u16, 1]);
        }
        f.extend([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7]]);
        m.extend([2u16; 4]);
        (v, f, m)
    }

    fn scene_with(arc: [f32; 2], lights: bool) -> crate::error::Result<Scene> {
        scene_posed(arc, lights, RigidPose::from_xyz_rpy([100.0, 50.0, 0.0], [0.0, 0.0, std::f64::consts::FRAC_PI_2]))
    }

    /// Two lanterns of arc `arc` 5 m apart on one instance at `pose`, lit or not.
    fn scene_posed(arc: [f32; 2], lights: bool, pose: RigidPose) -> crate::error::Result<Scene> {
        let (mut v, mut f, mut m) = lantern(Vec3::new(0.0, 0.0, 10.0), 0.2, 0.3);
        // A second lantern of the same material 5 m aft: a lamp of its own.
        let (v2, f2, m2) = lantern(Vec3::new(-5.0, 0.0, 10.0), 0.2, 0.3);
        let off = v.len() as i64;
        v.extend(v2);
        f.extend(f2.iter().map(|t| t.map(|i| i + off)));
        m.extend(m2);
        let classes = vec![3u16; f.len()];
        let mesh = Mesh::new("lanterns", &v, &f, &classes)?.with_materials(&m)?;
        let mut scene = Scene::new();
        let id = scene.add_mesh(mesh);
        let housing = Material { nav_light: false, emissive: [0.0; 3], ..Material::test_lamp([0.0; 3], [0.0, 180.0]) };
        scene.set_materials(vec![housing, Material::test_lamp([2e4; 3], arc), housing])?;
        let inst = scene.add_instance(id, pose, None)?;
        scene.set_lights(&[inst], lights)?;
        Ok(scene)
    }

    #[test]
    fn lamps_are_grouped_placed_and_measured() -> crate::error::Result<()> {
        assert!(scene_with([0.0, 180.0], false)?.nav_lamps().is_empty(), "lights off: no lamps");
        let lamps = scene_with([0.0, 180.0], true)?.nav_lamps();
        assert_eq!(lamps.len(), 2, "two lanterns 5 m apart are two lamps");
        // Body (0, 0, 10.15) turned 90° about z and moved to (100, 50): world (100, 50, 10.15); the aft one at
        // body x = −5 lies at world y = 45.
        assert!((lamps[0].centre - Vec3::new(100.0, 50.0, 10.15)).length() < 1e-4, "{:?}", lamps[0].centre);
        assert!((lamps[1].centre - Vec3::new(100.0, 45.0, 10.15)).length() < 1e-4, "{:?}", lamps[1].centre);
        assert!(lamps.iter().all(|l| l.instance == 0));
        // Seen horizontally square-on, the prism shows one 0.2 × 0.3 side: 0.06 m²; along a diagonal, √2 of it.
        let l = &lamps[0];
        assert!((l.intensity(Vec3::X).x - 2e4 * 0.06).abs() < 0.5, "{:?}", l.intensity(Vec3::X));
        let diag = Vec3::new(1.0, 1.0, 0.0).normalize();
        assert!((l.intensity(diag).x - 2e4 * 0.06 * 2f32.sqrt()).abs() < 1.0);
        // Straight down the sides show nothing (the caps are not lamp faces).
        assert!(l.intensity(-Vec3::Z).x.abs() < 1e-3);
        // The corners lie √(0.1² + 0.1² + 0.15²) from the centre.
        assert!((l.radius - (0.02f32 + 0.0225).sqrt()).abs() < 1e-4);
        Ok(())
    }

    #[test]
    fn a_lamp_shines_only_inside_its_arc() -> crate::error::Result<()> {
        // A sidelight to port (+y in the body): the body is turned 90°, so port is world −x.
        let lamps = scene_with([90.0, 56.25], true)?.nav_lamps();
        let l = &lamps[0];
        assert!(l.intensity(-Vec3::X).x > 0.0, "towards port");
        assert_eq!(l.intensity(Vec3::X), Vec3::ZERO, "towards starboard");
        assert_eq!(l.intensity(Vec3::new(0.0, -1.0, 0.0)), Vec3::ZERO, "right astern");
        Ok(())
    }

    #[test]
    fn a_lamp_made_ready_has_its_faces_intensity_every_way() -> crate::error::Result<()> {
        // A port sidelight's lantern on a vessel turned 70° and rolled 0.2 rad: `Lamp::intensity` (the arc's
        // trigonometry done once, the two triangles of each lens side merged) equals the intensity worked out from
        // the mesh's own faces over a sphere of directions: `Material::emits_towards` of the direction taken into
        // the body frame by the pose, times the radiance and `½ Σ |A_i · w|` of every triangle.
        let pose = RigidPose::from_xyz_rpy([3.0, -2.0, 0.0], [0.2, 0.0, 70f64.to_radians()]);
        let lamps = scene_posed([56.25, 56.25], true, pose)?.nav_lamps();
        let l = &lamps[0];
        assert_eq!(l.faces().len(), 4, "the two triangles of each of the lantern's 4 sides are merged");
        // The first lantern's 8 side triangles, their area vectors in the world frame.
        let (verts, tris, _) = lantern(Vec3::new(0.0, 0.0, 10.0), 0.2, 0.3);
        let areas: Vec<Vec3> = tris[..8]
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| pose.transform_point(Vec3::from_array(verts[i as usize])));
                0.5 * (b - a).cross(c - a)
            })
            .collect();
        let (mut zero, mut lit) = (0, 0);
        for i in 0..40 {
            for j in 0..80 {
                let (el, az) = (-1.5 + 3.0 * i as f32 / 39.0, std::f32::consts::TAU * j as f32 / 80.0);
                let w = Vec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
                let inside = l.material.emits_towards(pose.inverse_transform_vector(w));
                let area = 0.5 * areas.iter().map(|a| a.dot(w).abs()).sum::<f32>();
                let want = if inside { Vec3::splat(2e4 * area) } else { Vec3::ZERO };
                let got = l.intensity(w);
                assert!((got - want).length() <= 1e-4 * want.length().max(1.0), "{w:?}: {got:?} against {want:?}");
                if want == Vec3::ZERO {
                    zero += 1;
                } else {
                    lit += 1;
                }
            }
        }
        assert!(zero > 1000 && lit > 500, "{zero} {lit}");
        // The bound: the radiance times half the sum of the triangles' areas (4 sides of 0.2 × 0.3).
        assert!((l.max_intensity() - 2e4 * 0.5 * 4.0 * 0.06).abs() < 1.0, "{}", l.max_intensity());
        Ok(())
    }
}
