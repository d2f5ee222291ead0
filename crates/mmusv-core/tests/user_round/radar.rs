//! Radar and PPI: a box is seen at its range and bearing, bad radar and PPI configurations are refused, and
//! `capture_frame` equals running the sensors one by one.

use super::common::{box_mesh, ok, pinhole, refuses, room};
use mmusv_core::geometry::RigidPose;
use mmusv_core::scene::Scene;
use mmusv_core::sensors::camera::Camera;
use mmusv_core::sensors::capture::{capture_frame, SensorOutput, SensorTask};
use mmusv_core::sensors::lidar::{Lidar, LidarConfig};
use mmusv_core::sensors::ppi::{ppi_image, PpiConfig, PpiOrientation};
use mmusv_core::sensors::radar::sea_clutter::Polarisation;
use mmusv_core::sensors::radar::{radar_sweep, RadarConfig, RadarEnv};
use mmusv_core::sensors::radar_model::ClutterModel;
use mmusv_core::sensors::shade::ShadeEnv;
use std::f64::consts::{FRAC_PI_2, TAU};

fn quiet_radar() -> RadarConfig {
    RadarConfig {
        range_min_m: 10.0,
        range_max_m: 1000.0,
        range_resolution_m: 5.0,
        azimuth_bins: 360,
        beamwidth_az_rad: 1f64.to_radians(),
        elevation_fan_rad: [(-10f64).to_radians(), 10f64.to_radians()],
        rays_az: 2,
        rays_el: 16,
        target_rays: 16,
        horizon_fraction: 0.0,
        horizon_band_rad: 0.0,
        detection_threshold: 1e-9,
        range_noise_std_m: 0.0,
        clutter: ClutterModel {
            sea_sigma0_at_1m: 0.0,
            critical_range_per_m: 0.0,
            sea_max_range_m: 0.0,
            rain_eta_at_1mm_h: 0.0,
        },
        frequency_ghz: 9.41,
        polarisation: Polarisation::Horizontal,
    }
}

#[test]
fn radar_sees_a_box_at_its_range_and_bearing() {
    let cfg = quiet_radar();
    let mut scene = Scene::new();
    let b = scene.add_mesh(ok("box", || box_mesh("b", [5.0, 5.0, 5.0], 10)));
    // Sensor yawed 30°; the box at 300 m on bearing 40° in the world, so 10° to port in the sensor frame.
    let yaw = 30f64.to_radians();
    let bearing = 40f64.to_radians();
    let c = [300.0 * bearing.cos(), 300.0 * bearing.sin(), 0.0];
    ok("target", || scene.add_instance(b, RigidPose::from_xyz_rpy(c, [0.0, 0.0, bearing]), None));
    let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 2.0], [0.0, 0.0, yaw]);
    let ret = ok("sweep", || radar_sweep(&scene, &pose, &cfg, &RadarEnv::default(), 7));
    assert!(!ret.is_empty());
    for k in 0..ret.len() {
        assert_eq!(ret.instance[k], 0);
        assert_eq!(ret.class[k], 10);
        let az = f64::from(ret.azimuth[k]);
        // Azimuth of a beam bin is 2πb/N.
        let b = az / (TAU / 360.0);
        assert!((b - b.round()).abs() < 1e-3, "azimuth on a bin: {az}");
        // The box subtends ±~1° around 10°, plus half a beamwidth.
        assert!((az - 10f64.to_radians()).abs() < 2.5f64.to_radians(), "azimuth {}", az.to_degrees());
        // Bin centres (k + ½)Δr between the near face (295 m) and the far corner.
        let r = f64::from(ret.range[k]);
        assert!(((r / 5.0) - 0.5 - ((r / 5.0) - 0.5).round()).abs() < 1e-3, "range at a bin centre: {r}");
        assert!((292.5..=312.5).contains(&r), "range {r}");
        assert!(ret.intensity[k] > 0.0);
    }
    let nearest = ret.range.iter().fold(f32::INFINITY, |a, &b| a.min(b));
    assert_eq!(nearest, 297.5, "the near face at 295 m falls in the bin [295, 300)");
    // Same seed, same sweep.
    assert_eq!(ret, ok("sweep again", || radar_sweep(&scene, &pose, &cfg, &RadarEnv::default(), 7)));

    // The PPI: a target at range R is R/m pixels from the centre.
    let ppi = PpiConfig { size_px: 401, metres_per_pixel: 2.0, orientation: PpiOrientation::NorthUp };
    let img = ok("ppi", || ppi_image(&ret, &ppi, yaw as f32, &cfg));
    assert_eq!(img.len(), 401 * 401);
    // North-up: screen angle azimuth + yaw, right = east, up = north.
    let (row, col) = ppi.pixel(297.5, 10f64.to_radians(), yaw);
    assert!((col - (200.0 + 148.75 * bearing.cos())).abs() < 1e-9);
    assert!((row - (200.0 - 148.75 * bearing.sin())).abs() < 1e-9);
    for k in 0..ret.len() {
        let (row, col) = ppi.pixel(f64::from(ret.range[k]), f64::from(ret.azimuth[k]), yaw);
        let px = img[row.round() as usize * 401 + col.round() as usize];
        assert!(
            px >= ret.intensity[k],
            "return {k} painted at its cell centre (max compositing): {px} < {} at ({row}, {col}), r {} az {}",
            ret.intensity[k],
            ret.range[k],
            ret.azimuth[k]
        );
        let rho = (row - 200.0).hypot(col - 200.0);
        assert!((rho - f64::from(ret.range[k]) / 2.0).abs() < 1e-9, "R / m pixels from the centre");
    }
}

#[test]
fn radar_and_ppi_refuse_bad_configs() {
    let scene = Scene::new();
    let pose = RigidPose::IDENTITY;
    let env = RadarEnv::default();
    let base = quiet_radar();
    let cases: Vec<(&str, RadarConfig, &str)> = vec![
        ("range_max 0", RadarConfig { range_max_m: 0.0, ..base }, "radar.range_max_m"),
        ("range_max NaN", RadarConfig { range_max_m: f64::NAN, ..base }, "radar.range_max_m"),
        ("range_max 1e6", RadarConfig { range_max_m: 1e6, ..base }, "radar.range_max_m"),
        ("range_min < 0", RadarConfig { range_min_m: -1.0, ..base }, "radar.range_min_m"),
        ("range_min ≥ max", RadarConfig { range_min_m: 1000.0, ..base }, "radar.range_min_m"),
        ("resolution 0", RadarConfig { range_resolution_m: 0.0, ..base }, "radar.range_resolution_m"),
        ("resolution tiny", RadarConfig { range_resolution_m: 1e-6, ..base }, "radar.range_resolution_m"),
        ("no azimuth bins", RadarConfig { azimuth_bins: 0, ..base }, "radar.azimuth_bins"),
        ("beamwidth 0", RadarConfig { beamwidth_az_rad: 0.0, ..base }, "radar.beamwidth_az_rad"),
        ("beamwidth NaN", RadarConfig { beamwidth_az_rad: f64::NAN, ..base }, "radar.beamwidth_az_rad"),
        ("fan upside down", RadarConfig { elevation_fan_rad: [0.2, 0.1], ..base }, "radar.elevation_fan_rad"),
        ("fan to 90°", RadarConfig { elevation_fan_rad: [-0.1, FRAC_PI_2], ..base }, "radar.elevation_fan_rad"),
        ("rays_az 0", RadarConfig { rays_az: 0, ..base }, "radar.rays_az"),
        ("rays_el 0", RadarConfig { rays_el: 0, ..base }, "radar.rays_el"),
        ("too many rays", RadarConfig { rays_az: u32::MAX, rays_el: u32::MAX, ..base }, "radar.rays_el"),
        ("horizon fraction 2", RadarConfig { horizon_fraction: 2.0, ..base }, "radar.horizon_fraction"),
        ("threshold NaN", RadarConfig { detection_threshold: f64::NAN, ..base }, "radar.detection_threshold"),
        ("noise < 0", RadarConfig { range_noise_std_m: -1.0, ..base }, "radar.range_noise_std_m"),
        (
            "sea σ0 < 0",
            RadarConfig { clutter: ClutterModel { sea_sigma0_at_1m: -1.0, ..base.clutter }, ..base },
            "radar.clutter.sea_sigma0_at_1m",
        ),
    ];
    for (what, cfg, field) in cases {
        refuses(what, field, || radar_sweep(&scene, &pose, &cfg, &env, 1));
    }
    for (what, env, field) in [
        ("waves NaN", RadarEnv { wave_height_m: f32::NAN, rain_mm_per_h: 0.0 }, "radar.wave_height_m"),
        ("waves 40 m", RadarEnv { wave_height_m: 40.0, rain_mm_per_h: 0.0 }, "radar.wave_height_m"),
        ("rain < 0", RadarEnv { wave_height_m: 0.0, rain_mm_per_h: -1.0 }, "radar.rain_mm_per_h"),
    ] {
        refuses(what, field, || radar_sweep(&scene, &pose, &base, &env, 1));
    }
    let ret = mmusv_core::sensors::radar::RadarReturns::default();
    let p = PpiConfig::default();
    refuses("ppi size 0", "ppi.size_px", || ppi_image(&ret, &PpiConfig { size_px: 0, ..p }, 0.0, &base));
    refuses("ppi size huge", "ppi.size_px", || ppi_image(&ret, &PpiConfig { size_px: u32::MAX, ..p }, 0.0, &base));
    refuses("ppi m/px NaN", "ppi.metres_per_pixel", || {
        ppi_image(&ret, &PpiConfig { metres_per_pixel: f32::NAN, ..p }, 0.0, &base)
    });
    refuses("ppi yaw inf", "sensor_yaw", || ppi_image(&ret, &p, f32::INFINITY, &base));
    refuses("ppi orientation", "ppi.orientation", || PpiOrientation::parse("south_up"));
    assert!(ok("empty ppi", || ppi_image(&ret, &p, 0.0, &base)).iter().all(|&v| v == 0.0));
}

#[test]
fn capture_frame_equals_the_sensors_one_by_one() {
    let mut scene = room([0.0, 0.0, 0.0], 30.0);
    let b = scene.add_mesh(ok("box", || box_mesh("b", [1.0, 1.0, 1.0], 10)));
    ok("box", || scene.add_instance(b, RigidPose::from_xyz_rpy([10.0, 2.0, 0.0], [0.0; 3]), None));
    let env = ShadeEnv { fog_extinction_per_m: 0.0, rain_mm_per_h: 0.0, wave_height_m: 0.0, ..ShadeEnv::default() };
    let lidar = ok("lidar", || {
        Lidar::new(LidarConfig { elevations: vec![-0.1, 0.0, 0.1], azimuth_steps: 64, ..LidarConfig::default() })
    });
    let cam = ok("camera", || Camera::new(pinhole(24, 16, 1.2)));
    let radar = RadarConfig { range_max_m: 200.0, azimuth_bins: 64, ..quiet_radar() };
    let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 1.0], [0.0, 0.0, 0.2]);
    let tasks = [
        SensorTask::Lidar { lidar: &lidar, pose, seed: 3 },
        SensorTask::Camera { camera: &cam, rgb: false, pose, seed: 4 },
        SensorTask::Radar { radar: &radar, pose, seed: 5, ppi: None },
    ];
    let out = ok("capture_frame", || capture_frame(&scene, &env, &[], &tasks));
    assert_eq!(out.len(), 3);
    let lone = ok("lidar alone", || lidar.scan(&scene, &pose, &mmusv_core::sensors::capture::lidar_env(&env), 3));
    assert_eq!(out[0].output, SensorOutput::Lidar(lone));
    let frame = ok("camera alone", || cam.render(&scene, &pose, &env, false, 4));
    assert_eq!(out[1].output, SensorOutput::Camera(frame));
    let ret =
        ok("radar alone", || radar_sweep(&scene, &pose, &radar, &mmusv_core::sensors::capture::radar_env(&env), 5));
    assert_eq!(out[2].output, SensorOutput::Radar { returns: ret, ppi: None });
    assert!(ok("no tasks", || capture_frame(&scene, &env, &[], &[])).is_empty());
    // A bad task is an error (the radar sees the environment's NaN wave height).
    let bad_env = ShadeEnv { wave_height_m: f32::NAN, ..env };
    refuses("capture with NaN waves", "wave_height_m", || capture_frame(&scene, &bad_env, &[], &tasks));
}
