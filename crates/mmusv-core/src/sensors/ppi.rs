//! The plan-position indicator (PPI): radar returns rasterised into an ego-centred square image at a fixed
//! scale.
//!
//! Pixel `(row, col)` has its centre at `(row, col)` in pixel units; the sensor sits at the centre of pixel
//! `(S/2, S/2)` (integer division) of an `S × S` image, row 0 at the top. A point at range `r` (metres) and
//! screen angle `θ` (counter-clockwise from screen right) is at `col = S/2 + (r/m) cos θ`,
//! `row = S/2 − (r/m) sin θ` with `m` metres per pixel: **a target at range `R` is `R / m` pixels from the
//! centre in every frame**, whatever else is in view (the scale never adapts to the content).
//!
//! * North-up: up is world north (+y), right is east (+x): `θ = azimuth + sensor_yaw`.
//! * Head-up: up is the sensor's forward (+x), left its +y: `θ = azimuth + π/2`.
//!
//! Each return is painted as its polar cell, range `[r − Δr/2, r + Δr/2)` × azimuth `[a − π/N, a + π/N)`
//! (`N` azimuth bins): every pixel whose centre lies in the cell takes the return's intensity, with max
//! compositing, so neighbouring cells tile the image without gaps and far cells are arcs. The pixel nearest
//! the cell centre is always painted too, so a cell thinner than a pixel never vanishes.
//!
//! Roll and pitch: a marine radar's antenna is not stabilised. It turns in the deck plane of the hull it is bolted
//! to (the sweep's rays follow the full sensor pose, `radar/pattern.rs`), and the radar knows only the slant range
//! of an echo and the antenna's shaft angle against the bow; it draws them as if the deck were level. So the PPI
//! plots each return at its slant range and its azimuth in the (tilted) sensor frame, head-up as it is and
//! north-up turned by the gyro heading alone (the yaw of the sensor's forward axis projected on the horizontal,
//! `sensor_yaw`), and does not correct roll or pitch: a target at bearing β off the bow seen with the hull rolled
//! φ is drawn at `atan(tan β cos φ)` (1.8° short at β = 45°, φ = 20°), the tilt error of a real set (IMO's radar
//! performance standards, MSC.192(79), ask only that detection not be substantially impaired in roll or pitch up
//! to ±10°). Checked by `tests::a_rolled_radar_draws_its_targets_in_the_deck_plane`; the heading-only rotation is
//! what `mmusv.sensors.radar` passes as `sensor_yaw`.

use crate::error::{MmusvError, Result};
use crate::sensors::radar::{validate_azimuth_bins, validate_resolution, RadarConfig, RadarReturns};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Largest PPI side, pixels.
pub const MAX_PPI_SIZE: u32 = 8192;

/// Which way is up in the PPI.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum PpiOrientation {
    /// Up is world north (+y).
    #[default]
    NorthUp,
    /// Up is the sensor's forward axis (+x).
    HeadUp,
}

impl PpiOrientation {
    /// Parses `"north_up"` or `"head_up"`; the error names `ppi.orientation`.
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "north_up" => Ok(Self::NorthUp),
            "head_up" => Ok(Self::HeadUp),
            other => Err(MmusvError::config("ppi.orientation", other, "must be \"north_up\" or \"head_up\"")),
        }
    }
}

/// Size, scale and orientation of a PPI image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PpiConfig {
    /// Image side, pixels (`1..=8192`); the image is `size_px × size_px`.
    pub size_px: u32,
    /// Scale, metres per pixel (`> 0`).
    pub metres_per_pixel: f32,
    /// North-up or head-up.
    pub orientation: PpiOrientation,
}

impl Default for PpiConfig {
    /// 512 px at 12 m/px: a 3 km radar fills the image.
    fn default() -> Self {
        Self { size_px: 512, metres_per_pixel: 12.0, orientation: PpiOrientation::NorthUp }
    }
}

impl PpiConfig {
    /// Checks the size and scale; errors name `ppi.size_px` / `ppi.metres_per_pixel`.
    pub fn validate(&self) -> Result<()> {
        if !(1..=MAX_PPI_SIZE).contains(&self.size_px) {
            return Err(MmusvError::config("ppi.size_px", self.size_px, format!("must be in 1..={MAX_PPI_SIZE}")));
        }
        let m = self.metres_per_pixel;
        if !(m.is_finite() && m > 0.0) {
            return Err(MmusvError::config("ppi.metres_per_pixel", m, "must be a finite number of metres > 0"));
        }
        Ok(())
    }

    /// Screen angle (radians, counter-clockwise from screen right) of sensor azimuth `azimuth`.
    pub fn screen_angle(&self, azimuth: f64, sensor_yaw: f64) -> f64 {
        match self.orientation {
            PpiOrientation::NorthUp => azimuth + sensor_yaw,
            PpiOrientation::HeadUp => azimuth + FRAC_PI_2,
        }
    }

    /// Continuous `(row, col)` pixel coordinates of the point at `range` metres and sensor `azimuth`.
    pub fn pixel(&self, range: f64, azimuth: f64, sensor_yaw: f64) -> (f64, f64) {
        let c = (self.size_px / 2) as f64;
        let rho = range / self.metres_per_pixel as f64;
        let (s, co) = self.screen_angle(azimuth, sensor_yaw).sin_cos();
        (c - rho * s, c + rho * co)
    }
}

/// Wraps an angle into `[−π, π)`.
fn wrap(a: f64) -> f64 {
    (a + PI).rem_euclid(TAU) - PI
}

/// The trigonometry of one screen angle `θ` of a return: `(sin, cos)` of its cell's two edges `θ ∓ π/N` and of
/// `θ` itself, and of each screen axis the cell spans (`None` for the others).
#[derive(Debug, Clone, Copy)]
struct Direction {
    edges: [(f64, f64); 2],
    axes: [Option<(f64, f64)>; 4],
    centre: (f64, f64),
}

impl Direction {
    fn new(theta: f64, half_az: f64) -> Self {
        let edges = [(theta - half_az).sin_cos(), (theta + half_az).sin_cos()];
        let axes = [0.0, FRAC_PI_2, PI, -FRAC_PI_2].map(|a| (wrap(a - theta).abs() <= half_az).then(|| a.sin_cos()));
        Self { edges, axes, centre: theta.sin_cos() }
    }
}

/// The `size × size` float32 PPI (row-major, row 0 at the top) of `returns` from a sensor with world yaw
/// `sensor_yaw` (radians; used by north-up only). `cfg_radar` gives the cell size (`range_resolution_m`,
/// `azimuth_bins`); only `range`, `azimuth` and `intensity` of the returns are read. Pixels without a return
/// are 0.
pub fn ppi_image(
    returns: &RadarReturns,
    cfg: &PpiConfig,
    sensor_yaw: f32,
    cfg_radar: &RadarConfig,
) -> Result<Vec<f32>> {
    cfg.validate()?;
    validate_resolution(cfg_radar.range_resolution_m)?;
    validate_azimuth_bins(cfg_radar.azimuth_bins)?;
    let n = returns.range.len();
    if returns.azimuth.len() != n || returns.intensity.len() != n {
        return Err(MmusvError::input(
            "returns",
            format!(
                "range, azimuth and intensity must have the same length, got {}, {} and {}",
                n,
                returns.azimuth.len(),
                returns.intensity.len()
            ),
        ));
    }
    if !sensor_yaw.is_finite() {
        return Err(MmusvError::input("sensor_yaw", format!("{sensor_yaw} is not a finite angle in radians")));
    }
    let bad = |v: &[f32], ok: fn(f32) -> bool| v.iter().position(|&x| !ok(x));
    if let Some(i) = bad(&returns.range, |r| r.is_finite() && r >= 0.0) {
        return Err(MmusvError::input(
            format!("range[{i}]"),
            format!("{} must be finite metres >= 0", returns.range[i]),
        ));
    }
    if let Some(i) = bad(&returns.azimuth, f32::is_finite) {
        return Err(MmusvError::input(format!("azimuth[{i}]"), "must be a finite angle in radians"));
    }
    if let Some(i) = bad(&returns.intensity, f32::is_finite) {
        return Err(MmusvError::input(format!("intensity[{i}]"), "must be finite"));
    }
    let size = cfg.size_px as usize;
    let mut img = vec![0.0f32; size * size];
    let mpp = cfg.metres_per_pixel as f64;
    let half_range = cfg_radar.range_resolution_m / 2.0;
    let half_az = PI / cfg_radar.azimuth_bins as f64;
    let c = (cfg.size_px / 2) as f64;
    let yaw = sensor_yaw as f64;
    // The trigonometry of a return depends on its azimuth alone, and a sweep's returns come azimuth by azimuth:
    // worked out once per run of equal azimuths (the same values, so the same image).
    let mut dir: Option<(f64, Direction)> = None;
    for i in 0..n {
        let (r, v) = (returns.range[i] as f64, returns.intensity[i]);
        let theta = cfg.screen_angle(returns.azimuth[i] as f64, yaw);
        let g = match dir {
            Some((t, g)) if t.to_bits() == theta.to_bits() => g,
            _ => {
                let g = Direction::new(theta, half_az);
                dir = Some((theta, g));
                g
            }
        };
        let (rho0, rho1) = (((r - half_range) / mpp).max(0.0), (r + half_range) / mpp);
        // Bounding box of the annular sector: its corners plus the axis directions it spans.
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        let mut add = |rho: f64, (s, co): (f64, f64)| {
            x0 = x0.min(rho * co);
            x1 = x1.max(rho * co);
            y0 = y0.min(rho * s);
            y1 = y1.max(rho * s);
        };
        for sc in g.edges {
            add(rho0, sc);
            add(rho1, sc);
        }
        for sc in g.axes.iter().flatten() {
            add(rho1, *sc);
        }
        let (col0, col1) = ((c + x0).floor() as i64, (c + x1).ceil() as i64);
        let (row0, row1) = ((c - y1).floor() as i64, (c - y0).ceil() as i64);
        let (rows, cols) = (row0.max(0)..=row1.min(size as i64 - 1), col0.max(0)..=col1.min(size as i64 - 1));
        let rho = r / mpp;
        let nearest = ((c - rho * g.centre.0).round() as i64, (c + rho * g.centre.1).round() as i64);
        // With max compositing a return no brighter than every pixel it may paint (its cell's bounding box and its
        // nearest pixel) changes nothing: skipped before the per-pixel trigonometry. Over the waves most returns
        // are the sea's clutter, dozens to a pixel near the ship, and most of them are such.
        let dim = |row: i64, col: i64| {
            !((0..size as i64).contains(&row) && (0..size as i64).contains(&col))
                || img[row as usize * size + col as usize] >= v
        };
        if dim(nearest.0, nearest.1) && rows.clone().all(|row| cols.clone().all(|col| dim(row, col))) {
            continue;
        }
        let mut paint = |row: i64, col: i64| {
            if (0..size as i64).contains(&row) && (0..size as i64).contains(&col) {
                let p = &mut img[row as usize * size + col as usize];
                *p = p.max(v);
            }
        };
        for row in rows {
            let dy = c - row as f64;
            for col in cols.clone() {
                let dx = col as f64 - c;
                let rho = (dx * dx + dy * dy).sqrt();
                if rho < rho0 || rho >= rho1 {
                    continue;
                }
                let d = wrap(dy.atan2(dx) - theta);
                if d >= -half_az && d < half_az {
                    paint(row, col);
                }
            }
        }
        paint(nearest.0, nearest.1);
    }
    Ok(img)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(range: f32, azimuth: f32, intensity: f32) -> RadarReturns {
        RadarReturns {
            range: vec![range],
            azimuth: vec![azimuth],
            elevation: vec![0.0],
            intensity: vec![intensity],
            instance: vec![1],
            class: vec![10],
        }
    }

    fn painted(img: &[f32], size: usize) -> Vec<(usize, usize)> {
        (0..img.len()).filter(|&i| img[i] > 0.0).map(|i| (i / size, i % size)).collect()
    }

    #[test]
    fn target_at_range_r_is_r_over_mpp_pixels_from_centre() {
        let radar = RadarConfig::tuning();
        for orientation in [PpiOrientation::NorthUp, PpiOrientation::HeadUp] {
            let cfg = PpiConfig { size_px: 401, metres_per_pixel: 7.5, orientation };
            let c = 200i64;
            // Exact: R / mpp an integer, on the four screen axes.
            for (k, r_px) in [(0u32, 10i64), (1, 57), (2, 133), (3, 199)] {
                let want_theta = k as f64 * FRAC_PI_2;
                let yaw = 0.3f32;
                let az = match orientation {
                    PpiOrientation::NorthUp => want_theta - yaw as f64,
                    PpiOrientation::HeadUp => want_theta - FRAC_PI_2,
                };
                let az = az.rem_euclid(TAU) as f32;
                let img = ppi_image(&one(r_px as f32 * 7.5, az, 2.0), &cfg, yaw, &radar).unwrap_or_default();
                let (dr, dc) = [(0, 1), (-1, 0), (0, -1), (1, 0)][k as usize];
                let (row, col) = (c + dr * r_px, c + dc * r_px);
                assert_eq!(img[(row * 401 + col) as usize], 2.0, "{orientation:?} k={k} r={r_px}");
                for (pr, pc) in painted(&img, 401) {
                    let d = (((pr as i64 - c).pow(2) + (pc as i64 - c).pow(2)) as f64).sqrt();
                    assert!((d - r_px as f64).abs() <= 1.5 / 7.5 + 0.5, "pixel at {d} for {r_px}");
                }
            }
            // Anywhere: every painted pixel lies within the cell's range ± half a pixel diagonal.
            for i in 0..200 {
                let r = 20.0 + 7.31 * i as f64;
                let az = (i as f64 * 0.731).rem_euclid(TAU);
                let img = ppi_image(&one(r as f32, az as f32, 1.0), &cfg, 1.1, &radar).unwrap_or_default();
                let px = painted(&img, 401);
                assert!(!px.is_empty());
                for (pr, pc) in px {
                    let d = (((pr as i64 - c).pow(2) + (pc as i64 - c).pow(2)) as f64).sqrt();
                    assert!((d - r / 7.5).abs() <= 1.5 / 7.5 + 0.75, "pixel at {d} px for {} px", r / 7.5);
                }
            }
        }
    }

    #[test]
    fn orientation_and_arcs() {
        let radar = RadarConfig { azimuth_bins: 64, range_resolution_m: 10.0, ..RadarConfig::tuning() };
        // Forward (azimuth 0) with the sensor facing east (yaw 0): right in north-up, up in head-up.
        let ret = one(500.0, 0.0, 1.0);
        let north = PpiConfig { size_px: 256, metres_per_pixel: 5.0, orientation: PpiOrientation::NorthUp };
        let img = ppi_image(&ret, &north, 0.0, &radar).unwrap_or_default();
        assert_eq!(img[128 * 256 + 228], 1.0);
        let head = PpiConfig { orientation: PpiOrientation::HeadUp, ..north };
        let img = ppi_image(&ret, &head, 0.0, &radar).unwrap_or_default();
        assert_eq!(img[28 * 256 + 128], 1.0);
        // A 64-bin beam at 100 px spans 2π/64 · 100 ≈ 9.8 px of arc: an arc, not a dot.
        assert!(painted(&img, 256).len() >= 15, "{}", painted(&img, 256).len());
        // Sensor yawed 90° (facing north): forward is up in north-up too.
        let img = ppi_image(&ret, &north, std::f32::consts::FRAC_PI_2, &radar).unwrap_or_default();
        assert_eq!(img[28 * 256 + 128], 1.0);
        // Max compositing; cells of a full ring tile without gaps.
        let ring = RadarReturns {
            range: vec![300.0; 64],
            azimuth: (0..64).map(|b| (TAU * b as f64 / 64.0) as f32).collect(),
            intensity: (0..64).map(|b| b as f32 + 1.0).collect(),
            ..RadarReturns::default()
        };
        let img = ppi_image(&ring, &north, 0.0, &radar).unwrap_or_default();
        for k in 0..720 {
            let a = TAU * k as f64 / 720.0;
            let (row, col) = north.pixel(300.0, a, 0.0);
            assert!(img[row.round() as usize * 256 + col.round() as usize] > 0.0, "gap at {a}");
        }
    }

    /// The image pixel by pixel, apart from the bounding boxes and the skipping of dim returns: each pixel
    /// takes the brightest return whose cell holds its centre (the same polar test per pixel), then each return
    /// its nearest pixel, in the returns' order (max compositing is order-free).
    fn brute_force(returns: &RadarReturns, cfg: &PpiConfig, yaw: f64, radar: &RadarConfig) -> Vec<f32> {
        let size = cfg.size_px as usize;
        let (c, mpp) = ((cfg.size_px / 2) as f64, cfg.metres_per_pixel as f64);
        let (half_range, half_az) = (radar.range_resolution_m / 2.0, PI / radar.azimuth_bins as f64);
        let mut img = vec![0.0f32; size * size];
        for i in 0..returns.range.len() {
            let (r, v) = (returns.range[i] as f64, returns.intensity[i]);
            let theta = cfg.screen_angle(returns.azimuth[i] as f64, yaw);
            let (rho0, rho1) = (((r - half_range) / mpp).max(0.0), (r + half_range) / mpp);
            for row in 0..size {
                let dy = c - row as f64;
                for col in 0..size {
                    let dx = col as f64 - c;
                    let rho = (dx * dx + dy * dy).sqrt();
                    let d = wrap(dy.atan2(dx) - theta);
                    if rho >= rho0 && rho < rho1 && d >= -half_az && d < half_az {
                        img[row * size + col] = img[row * size + col].max(v);
                    }
                }
            }
            let (s, co) = theta.sin_cos();
            let (row, col) = ((c - r / mpp * s).round() as i64, (c + r / mpp * co).round() as i64);
            if (0..size as i64).contains(&row) && (0..size as i64).contains(&col) {
                let p = &mut img[row as usize * size + col as usize];
                *p = p.max(v);
            }
        }
        img
    }

    /// Random sweeps, many returns to a pixel (as the sea's clutter near the ship) and cells wider than many
    /// (far arcs), dim and bright in any order, some of them not above 0, some outside the image: the image is
    /// the pixel-by-pixel one, bit for bit, in both orientations.
    #[test]
    fn the_image_is_the_pixel_by_pixel_one() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for (k, (size, mpp, bins, res)) in
            [(65u32, 3.0f32, 360u32, 1.5f64), (48, 12.0, 1024, 7.5), (31, 0.7, 90, 0.5)].into_iter().enumerate()
        {
            let radar = RadarConfig { azimuth_bins: bins, range_resolution_m: res, ..RadarConfig::tuning() };
            let n = 3000;
            let bin = |rng: &mut rand_chacha::ChaCha8Rng| (rng.random_range(0..bins) as f64 + 0.5) * TAU / bins as f64;
            let far = size as f64 * mpp as f64 * 0.8;
            let returns = RadarReturns {
                range: (0..n).map(|_| rng.random_range(0.0..far) as f32).collect(),
                azimuth: (0..n).map(|_| bin(&mut rng) as f32).collect(),
                elevation: vec![0.0; n],
                intensity: (0..n)
                    .map(|_| {
                        if rng.random_bool(0.05) {
                            -rng.random_range(0.0..1.0f32)
                        } else {
                            rng.random_range(0.0..1.0f32)
                        }
                    })
                    .collect(),
                instance: vec![1; n],
                class: vec![10; n],
            };
            for orientation in [PpiOrientation::NorthUp, PpiOrientation::HeadUp] {
                let cfg = PpiConfig { size_px: size, metres_per_pixel: mpp, orientation };
                let yaw = 0.3 * k as f32;
                let got = ppi_image(&returns, &cfg, yaw, &radar).unwrap_or_default();
                let want = brute_force(&returns, &cfg, yaw as f64, &radar);
                let painted = want.iter().filter(|&&x| x > 0.0).count();
                assert!(painted > size as usize * size as usize / 4, "{painted} pixels painted: too few to test");
                assert_eq!(got.len(), want.len(), "a valid sweep");
                assert!(got.iter().zip(&want).all(|(a, b)| a.to_bits() == b.to_bits()), "size {size}, {orientation:?}");
            }
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        let r = RadarConfig::tuning();
        let ok = one(100.0, 0.0, 1.0);
        let field = |res: Result<Vec<f32>>| match res {
            Err(MmusvError::Config { field, .. } | MmusvError::InvalidInput { field, .. }) => field,
            other => format!("{:?}", other.map(|v| v.len())),
        };
        let p = PpiConfig::default();
        assert_eq!(field(ppi_image(&ok, &PpiConfig { size_px: 0, ..p }, 0.0, &r)), "ppi.size_px");
        assert_eq!(field(ppi_image(&ok, &PpiConfig { metres_per_pixel: -1.0, ..p }, 0.0, &r)), "ppi.metres_per_pixel");
        let bins = RadarConfig { azimuth_bins: 0, ..r };
        assert_eq!(field(ppi_image(&ok, &p, 0.0, &bins)), "radar.azimuth_bins");
        let short = RadarReturns { intensity: vec![], ..ok.clone() };
        assert_eq!(field(ppi_image(&short, &p, 0.0, &r)), "returns");
        let neg = one(-3.0, 0.0, 1.0);
        assert_eq!(field(ppi_image(&neg, &p, 0.0, &r)), "range[0]");
        assert_eq!(field(ppi_image(&ok, &p, f32::NAN, &r)), "sensor_yaw");
        assert_eq!(PpiOrientation::parse("head_up"), Ok(PpiOrientation::HeadUp));
        assert!(
            matches!(PpiOrientation::parse("up"), Err(MmusvError::Config { field, .. }) if field == "ppi.orientation")
        );
        // Returns outside the image are clipped, not errors.
        assert!(ppi_image(&one(1e5, 1.0, 1.0), &p, 0.0, &r).is_ok_and(|v| v.iter().all(|&x| x == 0.0)));
    }

    /// The antenna is not stabilised: with the hull rolled 20° a buoy 45° off the bow (in the horizontal) is
    /// swept at its azimuth in the deck plane, `atan(tan 45° cos 20°)` = 43.22°, written out here, not at 45°,
    /// and the north-up PPI draws it there turned by the heading alone (the module documentation's choice).
    #[test]
    fn a_rolled_radar_draws_its_targets_in_the_deck_plane() {
        use crate::geometry::RigidPose;
        use crate::scene::Scene;
        use crate::sensors::radar::{radar_sweep, RadarEnv};
        use crate::sensors::radar_model::ClutterModel;
        let (heading, roll, beta, dist) = (0.4f64, 20f64.to_radians(), 45f64.to_radians(), 300.0);
        let mut s = Scene::new();
        // A 2 m buoy level with the antenna (on the sea horizon: its bearing in the horizontal is β).
        let buoy = s.add_mesh(crate::scene::tests::box_mesh([1.0, 1.0, 1.0], 10));
        let bearing = heading + beta;
        let _ = s.add_instance(
            buoy,
            RigidPose::from_xyz_rpy([dist * bearing.cos(), dist * bearing.sin(), 5.0], [0.0; 3]),
            None,
        );
        let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 5.0], [roll, 0.0, heading]);
        let radar = RadarConfig {
            azimuth_bins: 2048,
            rays_az: 8,
            elevation_fan_rad: [(-25f64).to_radians(), 25f64.to_radians()],
            detection_threshold: 1e-6,
            clutter: ClutterModel { sea_sigma0_at_1m: 0.0, rain_eta_at_1mm_h: 0.0, ..ClutterModel::tuning() },
            ..RadarConfig::tuning()
        };
        let ret = radar_sweep(&s, &pose, &radar, &RadarEnv::default(), 1).unwrap_or_else(|e| unreachable!("{e}"));
        assert!(!ret.is_empty());
        // The echo-weighted azimuth of the buoy's returns.
        let w: f64 = ret.intensity.iter().map(|&x| f64::from(x)).sum();
        let az = ret.azimuth.iter().zip(&ret.intensity).map(|(&a, &x)| f64::from(a) * f64::from(x)).sum::<f64>() / w;
        let deck = (beta.tan() * roll.cos()).atan();
        let bin = TAU / 2048.0;
        assert!(
            (az - deck).abs() < 1.5 * bin,
            "azimuth {:.3}° vs deck-plane {:.3}°",
            az.to_degrees(),
            deck.to_degrees()
        );
        assert!((az - beta).abs() > 4.0 * bin, "drawn at the levelled bearing {:.3}°", az.to_degrees());
        // North-up: the strongest return's pixel is at screen angle azimuth + heading (east = right, north = up).
        let i = (0..ret.len()).max_by(|&a, &b| ret.intensity[a].total_cmp(&ret.intensity[b])).unwrap_or(0);
        let p = PpiConfig { size_px: 801, metres_per_pixel: 1.0, orientation: PpiOrientation::NorthUp };
        let img = ppi_image(&ret, &p, heading as f32, &radar).unwrap_or_default();
        let (r, a) = (f64::from(ret.range[i]), f64::from(ret.azimuth[i]));
        let (row, col) = (400.0 - r * (a + heading).sin(), 400.0 + r * (a + heading).cos());
        assert!(img[row.round() as usize * 801 + col.round() as usize] > 0.0, "pixel ({row:.1}, {col:.1})");
    }
}
