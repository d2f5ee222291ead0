//! Surface materials: the parameters of the camera's physically based shading, one table per scene.
//!
//! A [`Material`] is the metallic-roughness set of glTF 2.0 and of B. Burley's "Physically Based Shading at
//! Disney" (2012): a linear base colour, a perceptual roughness (GGX `α = roughness²`), a metallic weight, and
//! an emitted radiance (cd/m², linear RGB) for parts that glow. `nav_light` marks COLREG navigation lights, which
//! emit only on instances whose lights are on (vessels under way). Every face of a mesh names a material by
//! index into the scene's table; index 0 means "no material": the camera falls back to its per-class colour.

use crate::error::{MmusvError, Result};

/// Columns of one row of a material table as Python passes it: r, g, b, roughness, metallic, er, eg, eb, nav.
pub const COLUMNS: usize = 9;

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
    /// A navigation light: emits only when its instance's lights are on.
    pub nav_light: bool,
}

impl Material {
    /// A material from one table row `[r, g, b, roughness, metallic, er, eg, eb, nav]`; `row` names it in errors
    /// (`materials[row]`).
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
        Ok(Self {
            base_color: [v[0], v[1], v[2]],
            roughness: v[3],
            metallic: v[4],
            emissive: [v[5], v[6], v[7]],
            nav_light: v[8] == 1.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_checked() {
        let ok = [0.5, 0.5, 0.5, 0.4, 0.0, 0.0, 0.0, 0.0, 0.0];
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
    }
}
