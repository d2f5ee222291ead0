//! The seabed under the water as a raster of heights, for the optics of shallow water (the cameras' water body
//! shows the bottom through less water: [`crate::sensors::shade::water::shallow_albedo`]).
//!
//! Heights are world `z` (metres, negative below the sea surface) at grid vertices `(x0 + j·spacing,
//! y0 + i·spacing)`, row `i` northwards, read bilinearly; outside the grid the water is taken as deep.

use crate::error::{MmusvError, Result};

/// A seabed height raster (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Seabed {
    x0: f32,
    y0: f32,
    spacing: f32,
    /// `1 / spacing`.
    inv_spacing: f32,
    nx: usize,
    ny: usize,
    z: Vec<f32>,
}

impl Seabed {
    /// A raster of `ny × nx` heights `z` (row-major) with its first vertex at `(x0, y0)` and `spacing` metres
    /// between vertices. Errors name the field: a non-finite origin or height, a spacing not `> 0`, fewer than
    /// 2 × 2 vertices, or a length that is not `nx · ny`.
    pub fn new(x0: f32, y0: f32, spacing: f32, nx: usize, ny: usize, z: Vec<f32>) -> Result<Self> {
        if !(x0.is_finite() && y0.is_finite()) {
            return Err(MmusvError::input("seabed.origin", format!("({x0}, {y0}) must be finite")));
        }
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(MmusvError::input("seabed.spacing", format!("{spacing} must be a finite distance > 0")));
        }
        if nx < 2 || ny < 2 || nx.checked_mul(ny) != Some(z.len()) {
            return Err(MmusvError::input(
                "seabed.heights",
                format!("need at least 2 x 2 heights, nx·ny of them; got {} for {ny} x {nx}", z.len()),
            ));
        }
        if let Some(i) = z.iter().position(|v| !v.is_finite()) {
            return Err(MmusvError::input(format!("seabed.heights[{i}]"), "must be finite"));
        }
        Ok(Self { x0, y0, spacing, inv_spacing: 1.0 / spacing, nx, ny, z })
    }

    /// Water depth (metres, `>= 0`) over the seabed at world `(x, y)` below a surface at `level`; `None` outside
    /// the raster.
    #[inline(always)]
    pub fn depth(&self, x: f32, y: f32, level: f32) -> Option<f32> {
        let u = (x - self.x0) * self.inv_spacing;
        let v = (y - self.y0) * self.inv_spacing;
        if !(u >= 0.0 && v >= 0.0 && u <= (self.nx - 1) as f32 && v <= (self.ny - 1) as f32) {
            return None;
        }
        let (j, i) = ((u as usize).min(self.nx - 2), (v as usize).min(self.ny - 2));
        let (fu, fv) = (u - j as f32, v - i as f32);
        let at = |i: usize, j: usize| self.z[i * self.nx + j];
        let a = at(i, j) * (1.0 - fu) + at(i, j + 1) * fu;
        let b = at(i + 1, j) * (1.0 - fu) + at(i + 1, j + 1) * fu;
        Some((level - (a * (1.0 - fv) + b * fv)).max(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_is_bilinear_and_unknown_outside() -> Result<()> {
        // A slope from -2 m at x = 0 to -22 m at x = 100 (two columns), any y.
        let s = Seabed::new(0.0, 0.0, 100.0, 2, 2, vec![-2.0, -22.0, -2.0, -22.0])?;
        assert_eq!(s.depth(0.0, 50.0, 0.0), Some(2.0));
        assert!((s.depth(25.0, 10.0, 0.0).unwrap_or(0.0) - 7.0).abs() < 1e-5);
        assert_eq!(s.depth(-1.0, 0.0, 0.0), None);
        assert!(Seabed::new(0.0, 0.0, 0.0, 2, 2, vec![0.0; 4]).is_err());
        assert!(Seabed::new(0.0, 0.0, 1.0, 2, 2, vec![0.0; 3]).is_err());
        assert!(Seabed::new(0.0, 0.0, 1.0, 2, 2, vec![0.0, f32::NAN, 0.0, 0.0]).is_err());
        Ok(())
    }
}
