//! LiDAR: the default configuration is the documented sensor, a sweep matches its documented pattern, ranges
//! and intensity, and bad configurations, environments and poses are refused naming the field.

use super::common::{close, f64x3, guarded, mat_vec, ok, refuses, room, rpy_matrix};
use mmusv_core::geometry::RigidPose;
use mmusv_core::sensors::lidar::{reflectivity, Lidar, LidarConfig, LidarEnv};
use mmusv_core::sensors::rays;
use std::f64::consts::{FRAC_PI_2, TAU};

#[test]
fn lidar_default_config_is_the_documented_sensor() {
    let c = LidarConfig::default();
    assert_eq!(c.elevations.len(), 64);
    assert!((c.elevations[0] - (-25f64).to_radians()).abs() < 1e-12);
    assert!((c.elevations[63] - 15f64.to_radians()).abs() < 1e-12);
    assert_eq!(c.azimuth_steps, 410);
    assert_eq!((c.range_min, c.range_max), (0.5, 200.0));
    assert!(c.validate().is_ok());
    let el = ok("uniform_elevations", || rays::uniform_elevations(5, -0.2, 0.2));
    assert_eq!(el.len(), 5);
    for (i, e) in el.iter().enumerate() {
        assert!((e - (-0.2 + 0.1 * i as f64)).abs() < 1e-12);
    }
    refuses("no channels", "channels", || rays::uniform_elevations(0, -0.1, 0.1));
    refuses("fov past 90°", "vertical_fov", || rays::uniform_elevations(4, -FRAC_PI_2, 0.1));
    refuses("fov upside down", "vertical_fov", || rays::uniform_elevations(4, 0.2, 0.1));
    refuses("fov NaN", "vertical_fov", || rays::uniform_elevations(4, f64::NAN, 0.1));
}

#[test]
fn lidar_sweep_matches_its_documented_pattern_ranges_and_intensity() {
    let elevations = vec![-0.3, -0.1, 0.05, 0.25];
    let steps = 90u32;
    let cfg = LidarConfig {
        elevations: elevations.clone(),
        azimuth_steps: steps,
        range_noise_std: 0.0,
        dropout: 0.0,
        ..LidarConfig::default()
    };
    let lidar = ok("Lidar::new", || Lidar::new(cfg.clone()));
    // The pattern: column a at azimuth 2πa/N, every channel of a column consecutively.
    let pattern = lidar.pattern();
    assert_eq!(pattern.len(), elevations.len() * steps as usize);
    for (i, d) in pattern.iter().enumerate() {
        let (col, ring) = (i / elevations.len(), i % elevations.len());
        let az = TAU * col as f64 / f64::from(steps);
        let el = elevations[ring];
        let want = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
        assert!((0..3).all(|k| (f64::from(d[k]) - want[k]).abs() < 1e-6), "ray {i}");
    }
    // A sweep inside a room of half-size 20 m around the sensor at a yawed, pitched pose.
    let xyz = [3.0, -2.0, 1.0];
    let rpy = [0.05, -0.1, 0.7];
    let pose = RigidPose::from_xyz_rpy(xyz, rpy);
    let r = rpy_matrix(rpy);
    let scene = room(xyz, 20.0);
    let scan = ok("scan", || lidar.scan(&scene, &pose, &LidarEnv::default(), 3));
    assert_eq!(scan.len(), pattern.len(), "every beam returns from the walls");
    assert_eq!(scan.beam_instance.len(), pattern.len());
    for k in 0..scan.len() {
        let i = scan.ray_index[k] as usize;
        assert_eq!(i, k, "pattern order");
        let (col, ring) = (i / elevations.len(), i % elevations.len());
        assert_eq!(scan.ring[k] as usize, ring);
        assert!((f64::from(scan.azimuth[k]) - TAU * col as f64 / f64::from(steps)).abs() < 1e-6);
        let local = f64x3(pattern[i]);
        let world = mat_vec(&r, local);
        let m = world.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let want_r = 20.0 / m;
        assert!(close(f64::from(scan.range[k]), want_r, 1e-5), "ray {i}: {} vs {want_r}", scan.range[k]);
        // xyz in the LiDAR frame along the pattern direction.
        for a in 0..3 {
            assert!((f64::from(scan.xyz[k][a]) - local[a] * want_r).abs() < 1e-3);
        }
        assert_eq!(scan.class[k], 5);
        assert_eq!(scan.instance[k], 0);
        // Intensity ρ(class)·|cos θ|·τ/(1 + (r/100)²), clear air (τ = 1), θ against the wall's normal.
        let want_i = f64::from(reflectivity(5)) * m / (1.0 + (want_r / 100.0).powi(2));
        assert!((f64::from(scan.intensity[k]) - want_i).abs() < 1e-4, "ray {i}: {} vs {want_i}", scan.intensity[k]);
        assert!((0.0..=1.0).contains(&scan.intensity[k]));
    }
    // Outside [range_min, range_max]: no return.
    let far = LidarConfig { range_min: 45.0, range_max: 60.0, ..cfg.clone() };
    let none = ok("scan far", || Lidar::new(far).and_then(|l| l.scan(&scene, &pose, &LidarEnv::default(), 3)));
    assert!(none.is_empty());
    // Seeded: the same seed gives the same sweep.
    let noisy = ok("noisy lidar", || Lidar::new(LidarConfig { range_noise_std: 0.05, dropout: 0.2, ..cfg.clone() }));
    let a = ok("scan a", || noisy.scan(&scene, &pose, &LidarEnv::default(), 9));
    let b = ok("scan b", || noisy.scan(&scene, &pose, &LidarEnv::default(), 9));
    assert_eq!(a, b);
    assert!(a.len() < pattern.len() && a.len() > pattern.len() / 2, "dropout 0.2: {}", a.len());
}

#[test]
fn lidar_refuses_bad_configs() {
    let base = LidarConfig { elevations: vec![-0.1, 0.1], azimuth_steps: 16, ..LidarConfig::default() };
    let cases: Vec<(&str, LidarConfig, &str)> = vec![
        ("no channels", LidarConfig { elevations: vec![], ..base.clone() }, "lidar.channels"),
        ("2000 channels", LidarConfig { elevations: vec![0.0; 2000], ..base.clone() }, "lidar.channels"),
        ("zero steps", LidarConfig { azimuth_steps: 0, ..base.clone() }, "lidar.azimuth_steps"),
        ("huge steps", LidarConfig { azimuth_steps: u32::MAX, ..base.clone() }, "lidar.azimuth_steps"),
        ("range_min < 0", LidarConfig { range_min: -1.0, ..base.clone() }, "lidar.range_min"),
        ("range_min NaN", LidarConfig { range_min: f32::NAN, ..base.clone() }, "lidar.range_min"),
        ("range_max = range_min", LidarConfig { range_min: 5.0, range_max: 5.0, ..base.clone() }, "lidar.range"),
        ("range_max inf", LidarConfig { range_max: f32::INFINITY, ..base.clone() }, "lidar.range"),
        ("range_max 0", LidarConfig { range_min: 0.0, range_max: 0.0, ..base.clone() }, "lidar.range"),
        ("noise < 0", LidarConfig { range_noise_std: -0.1, ..base.clone() }, "lidar.range_noise_std"),
        ("dropout NaN", LidarConfig { dropout: f32::NAN, ..base.clone() }, "lidar.dropout"),
        ("dropout 1.5", LidarConfig { dropout: 1.5, ..base.clone() }, "lidar.dropout"),
        ("water p < 0", LidarConfig { water_probability: -0.1, ..base.clone() }, "lidar.water_probability"),
        ("water range inf", LidarConfig { water_range_m: f32::INFINITY, ..base.clone() }, "lidar.water_range_m"),
        ("elevation NaN", LidarConfig { elevations: vec![f64::NAN], ..base.clone() }, "elevations[0]"),
        ("elevation 90°", LidarConfig { elevations: vec![0.0, FRAC_PI_2], ..base.clone() }, "elevations[1]"),
    ];
    for (what, cfg, field) in cases {
        refuses(what, field, || Lidar::new(cfg));
    }
}

#[test]
fn lidar_config_validate_checks_every_field_including_elevations() {
    // `LidarConfig::validate` "checks every field; the error names the field (`lidar.<field>`)".
    let cfg = LidarConfig { elevations: vec![0.0, f64::NAN], azimuth_steps: 8, ..LidarConfig::default() };
    refuses("validate NaN elevation", "lidar.elevations[1]", || cfg.validate());
    let cfg = LidarConfig { elevations: vec![-2.0], azimuth_steps: 8, ..LidarConfig::default() };
    refuses("validate elevation below -90°", "lidar.elevations[0]", || cfg.validate());
    refuses("Lidar::new elevation below -90°", "lidar.elevations[0]", || Lidar::new(cfg));
}

#[test]
fn lidar_refuses_bad_environment_and_poses() {
    let lidar =
        ok("lidar", || Lidar::new(LidarConfig { elevations: vec![0.0], azimuth_steps: 8, ..LidarConfig::default() }));
    let scene = room([0.0; 3], 10.0);
    let pose = RigidPose::IDENTITY;
    let cases = [
        ("fog NaN", LidarEnv { fog_extinction_per_m: f32::NAN, ..LidarEnv::default() }, "fog_extinction_per_m"),
        ("fog < 0", LidarEnv { fog_extinction_per_m: -0.5, ..LidarEnv::default() }, "fog_extinction_per_m"),
        ("waves NaN", LidarEnv { wave_height_m: f32::NAN, ..LidarEnv::default() }, "wave_height_m"),
        ("wind < 0", LidarEnv { wind_speed_m_s: -3.0, ..LidarEnv::default() }, "wind_speed_m_s"),
    ];
    for (what, env, field) in cases {
        refuses(what, field, || lidar.scan(&scene, &pose, &env, 1));
    }
}

#[test]
fn sensors_name_the_pose_when_it_is_not_finite() {
    let lidar =
        ok("lidar", || Lidar::new(LidarConfig { elevations: vec![0.0], azimuth_steps: 8, ..LidarConfig::default() }));
    let scene = room([0.0; 3], 10.0);
    let bad = RigidPose::from_xyz_rpy([f64::NAN, 0.0, 0.0], [0.0; 3]);
    // An error, whatever it names, never a panic.
    assert!(guarded("scan from a NaN pose", || lidar.scan(&scene, &bad, &LidarEnv::default(), 1)).is_err());
    refuses("scan from a NaN pose", "pose", || lidar.scan(&scene, &bad, &LidarEnv::default(), 1));
}
