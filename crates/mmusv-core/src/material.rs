//! Surface materials: the parameters of the camera's physically based shading, one table per scene.
//!
//! A [`Material`] is the metallic-roughness set of glTF 2.0 and of B. Burley's "Physically Based Shading at
//! Disney" (2012): a linear base colour, a perceptual roughness (GGX `α = roughness²`), a metallic weight, and
//! an emitted radiance (cd/m², linear RGB) for parts that glow. `nav_light` marks COLREG navigation lights, which
//! emit only on instances whose lights are on (vessels under way), and only across their horizontal arc: the
//! International Regulations for Preventing Collisions at Sea (COLREG 1972), Rule 21, give the masthead light
//! 225° (right ahead to 22.5° abaft the beam on either side), each sidelight 112.5° (right ahead to 22.5° abaft
//! the beam on its own side) and the sternlight 135° (67.5° either side of right astern); Annex I §9 asks the
//! cut-off to fall within a few degrees of the sector's edge, which a lantern's screens and lens make sharp. The
//! arc is a bearing in the vessel's body frame (x forward, y to port) and a half-width; 180° is all round. Every
//! face of a mesh names a material by index into the scene's table; index 0 means "no material": the camera falls
//! back to its per-class colour.

use crate::error::{MmusvError, Result};
use parry3d::math::Vec3;

/// Columns of one row of a material table as Python passes it: r, g, b, roughness, metallic, er, eg, eb, nav,
/// arc centre (degrees, body frame: 0 right ahead, +90 to port), arc half-width (degrees, 180: all round).
pub const COLUMNS: usize = 11;

/// One material (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Linear RGB base colour (albedo for dielectrics, `F0` for metals), each in `[0, 1]`.
    pub base_color: [f32; 3],
    /// Perceptual roughness in `[0, 1]`.
    pub roughness: f32,
    /// Metallic weight in `[0, 1]`.
    pub metallic: f32,
    /// Emitted radiance, linear RGB, cd/m² (`>= 0`).
    pub emissive: [f32; 3],
    /// A navigation light: emits only when its instance's lights are on, across [`Material::arc_deg`].
    pub nav_light: bool,
    /// The light's horizontal arc: its centre bearing and half-width, degrees, in the body frame of the
    /// instance (0 right ahead, +90 to port); a half-width of 180 is all round.
    pub arc_deg: [f32; 2],
}

impl Material {
    /// A material from one table row `[r, g, b, roughness, metallic, er, eg, eb, nav, arc centre, arc half-width]`;
    /// `row` names it in errors (`materials[row]`).
    pub fn from_row(row: usize, v: &[f32; COLUMNS]) -> Result<Self> {
        let bad = |what: &str, allowed: &str| {
            Err(MmusvError::input(format!("materials[{row}]"), format!("{what} {allowed}; got {v:?}")))
        };
        if v.iter().any(|x| !x.is_finite()) {
            return bad("every value", "must be finite");
        }
        if v[..5].iter().any(|&x| !(0.0..=1.0).contains(&x)) {
            return bad("base colour, roughness and metallic", "must be in [0, 1]");
        }
        if v[5..8].iter().any(|&x| x < 0.0) {
            return bad("emissive radiance", "must be >= 0");
        }
        if v[8] != 0.0 && v[8] != 1.0 {
            return bad("nav_light", "must be 0 or 1");
        }
        if !(-180.0..=180.0).contains(&v[9]) {
            return bad("arc centre", "must be a bearing in [-180, 180] degrees");
        }
        if !(v[10] > 0.0 && v[10] <= 180.0) {
            return bad("arc half-width", "must be in (0, 180] degrees");
        }
        Ok(Self {
            base_color: [v[0], v[1], v[2]],
            roughness: v[3],
            metallic: v[4],
            emissive: [v[5], v[6], v[7]],
            nav_light: v[8] == 1.0,
            arc_deg: [v[9], v[10]],
        })
    }

    /// Whether the light emits towards `dir` (from the light outward, in the instance's body frame): its bearing
    /// in the horizontal plane of the body lies within [`Material::arc_deg`]. Straight up or down (no bearing) it
    /// does.
    #[inline]
    pub fn emits_towards(&self, dir: Vec3) -> bool {
        self.arc().is_none_or(|arc| arc.contains(dir))
    }

    /// [`Material::arc_deg`] made ready for many tests ([`LightArc::contains`]); `None` all round (a half-width of 180°).
    #[inline]
    pub fn arc(&self) -> Option<LightArc> {
        let [centre, half] = self.arc_deg;
        (half < 180.0).then(|| {
            let (sin_centre, cos_centre) = centre.to_radians().sin_cos();
            LightArc { cos_centre, sin_centre, cos_half: half.to_radians().cos() }
        })
    }
}

/// A light's horizontal arc (not all round), as the cosine and sine of its centre bearing and the cosine of its
/// half-width (body frame; [`Material::arc_deg`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightArc {
    /// Cosine of the centre bearing.
    pub cos_centre: f32,
    /// Sine of the centre bearing.
    pub sin_centre: f32,
    /// Cosine of the half-width.
    pub cos_half: f32,
}

impl LightArc {
    /// Whether `dir` (body frame, any length) lies inside the arc: its level bearing is within the half-width of
    /// the centre's; straight up or down (no bearing) it does.
    #[inline]
    pub fn contains(&self, dir: Vec3) -> bool {
        let h = (dir.x * dir.x + dir.y * dir.y).sqrt();
        h <= 1e-6 * dir.length() || dir.x * self.cos_centre + dir.y * self.sin_centre >= self.cos_half * h
    }
}

#[cfg(test)]
impl Material {
    /// A navigation lamp's material for the lamp tests: white, roughness 0.5, not metallic, radiance `emissive`
    /// (cd/m², linear RGB) across `arc` (centre bearing and half-width, degrees).
    pub(crate) fn test_lamp(emissive: [f32; 3], arc: [f32; 2]) -> Self {
        Self { base_color: [1.0; 3], roughness: 0.5, metallic: 0.0, emissive, nav_light: true, arc_deg: arc }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_checked() {
        let ok = [0.5, 0.5, 0.5, 0.4, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 180.0];
        assert!(Material::from_row(0, &ok).is_ok());
        let mut bad = ok;
        bad[3] = 1.5;
        let e = Material::from_row(3, &bad).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("materials[3]") && e.contains("[0, 1]"), "{e}");
        bad = ok;
        bad[6] = -1.0;
        assert!(Material::from_row(0, &bad).is_err());
        bad = ok;
        bad[8] = 0.5;
        assert!(Material::from_row(0, &bad).is_err());
        bad = ok;
        bad[0] = f32::NAN;
        assert!(Material::from_row(0, &bad).is_err());
        bad = ok;
        bad[9] = 200.0;
        assert!(Material::from_row(0, &bad).is_err());
        bad = ok;
        bad[10] = 0.0;
        assert!(Material::from_row(0, &bad).is_err());
    }

    /// Rule 21's arcs at whole degrees: the bearings each lamp emits towards, counted independently with atan2.
    #[test]
    fn colreg_arcs() {
        let lamp = |centre: f32, half: f32| Material {
            base_color: [1.0; 3],
            roughness: 0.1,
            metallic: 0.0,
            emissive: [1.0; 3],
            nav_light: true,
            arc_deg: [centre, half],
        };
        let bearings = |m: &Material| -> Vec<i32> {
            (-179..=180)
                .filter(|&b: &i32| {
                    let a = (b as f32).to_radians();
                    // a little above the horizon, as a camera on another deck sees it
                    m.emits_towards(Vec3::new(a.cos(), a.sin(), 0.1))
                })
                .collect()
        };
        let masthead = bearings(&lamp(0.0, 112.5));
        assert_eq!(masthead, (-112..=112).collect::<Vec<_>>());
        let port = bearings(&lamp(56.25, 56.25));
        assert_eq!(port, (0..=112).collect::<Vec<_>>());
        let starboard = bearings(&lamp(-56.25, 56.25));
        assert_eq!(starboard, (-112..=0).collect::<Vec<_>>());
        let stern = bearings(&lamp(180.0, 67.5));
        let expect: Vec<i32> = (-179..=-113).chain(113..=180).collect();
        assert_eq!(stern, expect);
        assert!(lamp(0.0, 180.0).emits_towards(-Vec3::X) && lamp(0.0, 112.5).emits_towards(Vec3::Z));
    }
}
