//! Lens distortion of a pinhole camera: Brown–Conrady in OpenCV's convention (D. C. Brown, "Decentering
//! Distortion of Lenses", Photogrammetric Engineering 32(3), 1966; OpenCV's `calib3d` coefficient order
//! `[k1, k2, p1, p2, k3]`).
//!
//! Normalised image coordinates: `x = (u − c_x) / f` to the right, `y = (v − c_y) / f` downwards (pixels over the
//! focal length, unitless). A pixel at distorted `(x_d, y_d)` sees the ray of the undistorted `(x, y)` with
//! `x_d = x (1 + k1 r² + k2 r⁴ + k3 r⁶) + 2 p1 x y + p2 (r² + 2 x²)`, `y_d = y (…) + p1 (r² + 2 y²) + 2 p2 x y`,
//! `r² = x² + y²`; [`Distortion::undistort`] inverts it numerically. The camera casts each pixel's ray through the
//! undistorted point (see [`super::Camera`]).

use crate::error::{MmusvError, Result};

/// Brown–Conrady distortion coefficients, OpenCV's order and convention (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Distortion {
    /// `[k1, k2, p1, p2, k3]`.
    pub coefficients: [f64; 5],
}

impl Distortion {
    /// Distorted normalised coordinates of undistorted `(x, y)`.
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        let [k1, k2, p1, p2, k3] = self.coefficients;
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        (
            x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
        )
    }

    /// Undistorted normalised coordinates of distorted `(xd, yd)`: Newton's method on [`Distortion::distort`]
    /// (numerical Jacobian), from `(xd, yd)`.
    pub fn undistort(&self, xd: f64, yd: f64) -> (f64, f64) {
        let (mut x, mut y) = (xd, yd);
        for _ in 0..30 {
            let (fx, fy) = self.distort(x, y);
            let (ex, ey) = (fx - xd, fy - yd);
            if ex.abs() < 1e-12 && ey.abs() < 1e-12 {
                break;
            }
            let h = 1e-7;
            let (ax, ay) = self.distort(x + h, y);
            let (bx, by) = self.distort(x, y + h);
            let (j11, j21, j12, j22) = ((ax - fx) / h, (ay - fy) / h, (bx - fx) / h, (by - fy) / h);
            let det = j11 * j22 - j12 * j21;
            if det.abs() < 1e-12 {
                break;
            }
            x -= (j22 * ex - j12 * ey) / det;
            y -= (-j21 * ex + j11 * ey) / det;
        }
        (x, y)
    }
}

/// Checks distortion coefficients are finite.
pub(super) fn check_distortion(d: &Distortion) -> Result<()> {
    if d.coefficients.iter().any(|c| !c.is_finite()) {
        return Err(MmusvError::config("camera.distortion", format!("{:?}", d.coefficients), "must be finite"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn only(i: usize, value: f64) -> Distortion {
        let mut coefficients = [0.0; 5];
        coefficients[i] = value;
        Distortion { coefficients }
    }

    /// Each coefficient alone against its closed form on an axis: `k1` on the x axis `x + k1 x³`, `k2` `x + k2 x⁵`,
    /// `k3` `x + k3 x⁷`, `p2` at `(x, 0)` `x + 3 p2 x²` (and `y` stays 0), `p1` at `(0, y)` `y + 3 p1 y²`.
    #[test]
    fn each_coefficient_matches_its_closed_form_on_an_axis() {
        let x: f64 = 0.37;
        let close = |a: f64, b: f64| (a - b).abs() < 1e-15;
        let (xd, yd) = only(0, -0.21).distort(x, 0.0);
        assert!(close(xd, x - 0.21 * x.powi(3)) && yd == 0.0, "{xd} {yd}");
        let (xd, _) = only(1, 0.05).distort(x, 0.0);
        assert!(close(xd, x + 0.05 * x.powi(5)), "{xd}");
        let (xd, _) = only(4, 0.02).distort(x, 0.0);
        assert!(close(xd, x + 0.02 * x.powi(7)), "{xd}");
        let (xd, yd) = only(3, 0.003).distort(x, 0.0);
        assert!(close(xd, x + 3.0 * 0.003 * x * x) && yd == 0.0, "{xd} {yd}");
        let (xd, yd) = only(2, -0.004).distort(0.0, x);
        assert!(close(yd, x - 3.0 * 0.004 * x * x) && xd == 0.0, "{xd} {yd}");
    }

    /// `undistort` of a barrel (`k1` only) point on the x axis is the root of `x + k1 x³ = x_d` found by
    /// bisection; with all five coefficients, distorting the undistorted point gives the distorted one back.
    #[test]
    fn undistort_inverts_distort() {
        let d = only(0, -0.25);
        let xd = 0.41;
        let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid - 0.25 * mid.powi(3) < xd {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (x, y) = d.undistort(xd, 0.0);
        assert!((x - lo).abs() < 1e-10 && y.abs() < 1e-12, "{x} {y} vs {lo}");
        let d = Distortion { coefficients: [-0.25, 0.06, 0.001, -0.002, 0.01] };
        for &(xd, yd) in &[(0.0, 0.0), (0.3, -0.2), (-0.45, 0.33), (0.1, 0.5)] {
            let (x, y) = d.undistort(xd, yd);
            let (rx, ry) = d.distort(x, y);
            assert!((rx - xd).abs() < 1e-10 && (ry - yd).abs() < 1e-10, "({xd}, {yd}) -> ({x}, {y}) -> ({rx}, {ry})");
        }
    }

    /// A coefficient that is not finite is refused, naming the field.
    #[test]
    fn non_finite_coefficients_name_the_field() {
        assert!(check_distortion(&only(0, 0.1)).is_ok());
        let Err(e) = check_distortion(&only(3, f64::NAN)) else { panic!("NaN accepted") };
        assert!(e.to_string().contains("camera.distortion"), "{e}");
    }
}
