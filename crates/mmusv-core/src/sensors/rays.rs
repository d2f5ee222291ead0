//! Ray patterns of the sensors, as unit direction vectors in the sensor's body frame (x forward, y left,
//! z up) or, for cameras, rows of pixels.
//!
//! * Spinning LiDAR: `channels × azimuth_steps` rays, ordered azimuth-major (all channels of one column
//!   are consecutive, as a spinning head fires them), azimuth from 0 (forward) counter-clockwise.
//! * Pinhole camera: one ray per pixel centre, row-major from the top-left pixel, for the optical frame
//!   (x right, y down, z forward) mapped to the body frame (optical z = body x, optical x = −body y,
//!   optical y = −body z).

use crate::error::{MmusvError, Result};

/// Most LiDAR channels a sweep may have.
pub const MAX_CHANNELS: u32 = 1024;
/// Most azimuth steps a sweep may have.
pub const MAX_AZIMUTH_STEPS: u32 = 1 << 16;

/// Pinhole intrinsics from an image size and horizontal field of view: `fx = fy = W / (2 tan(hfov/2))`,
/// principal point at the image centre `(W/2, H/2)`. Returns `[fx, fy, cx, cy]` in pixels. `hfov` is in radians,
/// in `(0, π)`; a zero side or an `hfov` outside that range is an error naming `resolution` or `hfov`.
pub fn pinhole_intrinsics(width: u32, height: u32, hfov: f64) -> Result<[f64; 4]> {
    if width == 0 || height == 0 {
        return Err(MmusvError::config("resolution", format!("[{width}, {height}]"), "width and height must be >= 1"));
    }
    if !(hfov > 0.0 && hfov < std::f64::consts::PI) {
        return Err(MmusvError::config("hfov", hfov, "horizontal field of view must be in (0, π) radians"));
    }
    let f = width as f64 / (2.0 * (hfov / 2.0).tan());
    Ok([f, f, width as f64 / 2.0, height as f64 / 2.0])
}

/// Unit ray directions through every pixel centre of a pinhole camera, in the camera BODY frame
/// (x forward, y left, z up). Row-major, `width × height` rows of `[x, y, z]`; `hfov` in radians, as in
/// [`pinhole_intrinsics`].
/// Sides above [`MAX_SIDE`](crate::sensors::camera::MAX_SIDE) are refused (a camera's own bound), before anything
/// is allocated.
pub fn pinhole_directions(width: u32, height: u32, hfov: f64) -> Result<Vec<[f32; 3]>> {
    let max = crate::sensors::camera::MAX_SIDE;
    if width > max || height > max {
        return Err(MmusvError::config(
            "resolution",
            format!("[{width}, {height}]"),
            format!("width and height must be in 1..={max}"),
        ));
    }
    let [fx, fy, cx, cy] = pinhole_intrinsics(width, height, hfov)?;
    let mut out = Vec::with_capacity(width as usize * height as usize);
    for v in 0..height {
        for u in 0..width {
            // Optical frame: x right, y down, z forward.
            let ox = (u as f64 + 0.5 - cx) / fx;
            let oy = (v as f64 + 0.5 - cy) / fy;
            let n = (ox * ox + oy * oy + 1.0).sqrt();
            out.push([(1.0 / n) as f32, (-ox / n) as f32, (-oy / n) as f32]);
        }
    }
    Ok(out)
}

/// Elevation angles (radians) of `channels` beams spread uniformly over `[lower, upper]` radians,
/// lowest first; `channels` in `1..=MAX_CHANNELS`.
pub fn uniform_elevations(channels: u32, lower: f64, upper: f64) -> Result<Vec<f64>> {
    if channels == 0 {
        return Err(MmusvError::config("channels", channels, "a LiDAR needs at least one channel"));
    }
    if channels > MAX_CHANNELS {
        return Err(MmusvError::config("channels", channels, format!("must be in 1..={MAX_CHANNELS}")));
    }
    if !(lower.is_finite()
        && upper.is_finite()
        && lower <= upper
        && lower > -std::f64::consts::FRAC_PI_2
        && upper < std::f64::consts::FRAC_PI_2)
    {
        return Err(MmusvError::config(
            "vertical_fov",
            format!("[{lower}, {upper}] rad"),
            "need lower <= upper, both strictly between -90 and 90 degrees",
        ));
    }
    if channels == 1 {
        return Ok(vec![(lower + upper) / 2.0]);
    }
    let step = (upper - lower) / (channels - 1) as f64;
    Ok((0..channels).map(|i| lower + step * i as f64).collect())
}

/// Unit directions of one full LiDAR sweep in the LiDAR frame: `azimuth_steps` columns starting at azimuth 0
/// (forward, +x) and turning counter-clockwise (towards +y), each column holding every elevation in order.
pub fn lidar_directions(elevations: &[f64], azimuth_steps: u32) -> Result<Vec<[f32; 3]>> {
    if azimuth_steps == 0 || azimuth_steps > MAX_AZIMUTH_STEPS {
        return Err(MmusvError::config("azimuth_steps", azimuth_steps, format!("must be in 1..={MAX_AZIMUTH_STEPS}")));
    }
    if elevations.len() > MAX_CHANNELS as usize {
        return Err(MmusvError::config("channels", elevations.len(), format!("at most {MAX_CHANNELS} channels")));
    }
    if let Some(i) = elevations.iter().position(|e| !(e.is_finite() && e.abs() < std::f64::consts::FRAC_PI_2)) {
        return Err(MmusvError::config(
            format!("elevations[{i}]"),
            elevations[i],
            "must be finite, strictly between -90 and 90 degrees",
        ));
    }
    let mut out = Vec::with_capacity(elevations.len() * azimuth_steps as usize);
    for a in 0..azimuth_steps {
        let az = std::f64::consts::TAU * a as f64 / azimuth_steps as f64;
        let (sa, ca) = az.sin_cos();
        for &el in elevations {
            let (se, ce) = el.sin_cos();
            out.push([(ce * ca) as f32, (ce * sa) as f32, se as f32]);
        }
    }
    Ok(out)
}

/// Neighbouring columns traced one after the other by the LiDAR and radar ([`lidar_trace_order`]): consecutive
/// rays are then nearly parallel and walk nearly the same BVH nodes, which keeps them in cache.
pub const TRACE_BLOCK: u32 = 8;

/// The order in which a sweep is best traced: blocks of `block` neighbouring columns, and within a block each
/// channel's `block` rays consecutively, so consecutive rays are nearly parallel and visit nearly the same nodes.
/// Entry `i` is the index, in [`lidar_directions`]'s azimuth-major order, of the `i`-th ray to trace.
pub fn lidar_trace_order(channels: u32, azimuth_steps: u32, block: u32) -> Result<Vec<u32>> {
    if channels == 0 || channels > MAX_CHANNELS {
        return Err(MmusvError::config("channels", channels, format!("must be in 1..={MAX_CHANNELS}")));
    }
    if azimuth_steps == 0 || azimuth_steps > MAX_AZIMUTH_STEPS {
        return Err(MmusvError::config("azimuth_steps", azimuth_steps, format!("must be in 1..={MAX_AZIMUTH_STEPS}")));
    }
    let block = block.max(1);
    let mut order = Vec::with_capacity(channels as usize * azimuth_steps as usize);
    let mut first = 0;
    while first < azimuth_steps {
        let last = (first + block).min(azimuth_steps);
        for ch in 0..channels {
            for col in first..last {
                order.push(col * channels + ch);
            }
        }
        first = last;
    }
    Ok(order)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_out_of_range_hfov_is_refused_in_its_unit() {
        // `hfov` is in radians: the message said "(0, 180) degrees", which 4.0 lies within.
        for hfov in [0.0, -1.0, 4.0, std::f64::consts::PI, f64::NAN] {
            let e = pinhole_intrinsics(8, 8, hfov).err().map(|e| e.to_string()).unwrap_or_default();
            assert!(e.contains("hfov") && e.contains("radians") && !e.contains("degrees"), "{hfov}: {e}");
        }
        assert!(pinhole_intrinsics(8, 8, 3.1).is_ok());
    }

    #[test]
    fn huge_sizes_are_refused_before_allocating() {
        // Each used to try to allocate gigabytes (and abort the process when that failed).
        let side = crate::sensors::camera::MAX_SIDE;
        assert!(pinhole_directions(side + 1, 6, 1.0).is_err());
        assert!(pinhole_directions(8, u32::MAX, 1.0).is_err());
        assert!(uniform_elevations(MAX_CHANNELS + 1, -0.1, 0.1).is_err());
        assert!(uniform_elevations(u32::MAX, -0.1, 0.1).is_err());
        assert_eq!(uniform_elevations(MAX_CHANNELS, -0.1, 0.1).map(|e| e.len()).ok(), Some(MAX_CHANNELS as usize));
        assert_eq!(pinhole_directions(side, 1, 1.0).map(|d| d.len()).ok(), Some(side as usize));
    }

    #[test]
    fn pinhole_centre_ray_is_forward_and_corners_match_fov() {
        let d = pinhole_directions(4, 2, std::f64::consts::FRAC_PI_2).unwrap_or_default();
        assert_eq!(d.len(), 8);
        // Pixel (0, 0) is top-left: looks left (+y) and up (+z).
        assert!(d[0][1] > 0.0 && d[0][2] > 0.0);
        // Horizontal angle of the left edge of the image is hfov/2 = 45°.
        let [fx, _, cx, _] = pinhole_intrinsics(4, 2, std::f64::consts::FRAC_PI_2).unwrap_or([0.0; 4]);
        assert!(((cx / fx).atan() - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
        for r in &d {
            let n = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
            assert!((n - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn lidar_pattern_order_and_angles() {
        let el = uniform_elevations(64, (-25f64).to_radians(), 15f64.to_radians()).unwrap_or_default();
        assert_eq!(el.len(), 64);
        assert!((el[63] - 15f64.to_radians()).abs() < 1e-12);
        let d = lidar_directions(&el, 2048).unwrap_or_default();
        assert_eq!(d.len(), 64 * 2048);
        // Column 512 is azimuth 90°: +y.
        let r = d[512 * 64 + 20];
        assert!(r[0].abs() < 1e-6 && r[1] > 0.0);
        assert!((r[2] as f64 - el[20].sin()).abs() < 1e-6);
        let order = lidar_trace_order(64, 2048, 8).unwrap_or_default();
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..64 * 2048).collect::<Vec<u32>>(), "a permutation");
        assert_eq!(&order[..3], &[0, 64, 128]);
        assert!(uniform_elevations(0, 0.0, 0.1).is_err());
        assert!(lidar_trace_order(u32::MAX, u32::MAX, 8).is_err());
        assert!(lidar_directions(&[f64::NAN], 16).is_err());
        assert!(lidar_directions(&el, 0).is_err());
        assert!(pinhole_intrinsics(0, 10, 1.0).is_err());
    }
}
