//! `cargo bench --bench sensors`: per-sensor throughput on the synthetic maritime scene (≈0.78 M triangles,
//! 48 vessels) from an ego USV at the origin — the paper's LiDAR sweep (64 × 410 columns, 131,072 points/s at
//! 5 Hz; also in rain of 10 mm/h, its drops' returns drawn), one 640×480 camera with depth + semantic + instance, the same with RGB shading (shadow rays
//! included), and a 512×512 top view. Throughput is reported per ray (= per pixel for cameras), criterion's
//! `elem/s`.
//!
//! The sampling settings are the group's defaults (`config` below), so criterion's command line
//! (`-- --measurement-time 2 --warm-up-time 1 --sample-size 10`) overrides them; set on the group in code,
//! they silently won over it.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mmusv_core::sensors::camera::{Camera, CameraConfig, ImageOptions, Projection, Quality};
use mmusv_core::sensors::lidar::{Lidar, LidarConfig, LidarEnv};
use mmusv_core::sensors::shade::ShadeEnv;
use mmusv_core::RigidPose;
use std::hint::black_box;
use std::time::Duration;

fn bench_sensors(c: &mut Criterion) {
    let demo = match mmusv_benches::sea_scene() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("could not build the benchmark scene with its sea: {e}");
            return;
        }
    };
    let scene = &demo.scene;
    let lidar_pose = RigidPose::from_xyz_rpy([0.0, 0.0, f64::from(mmusv_benches::LIDAR_HEIGHT)], [0.0, 0.0, 0.0]);
    let cam_pose = RigidPose::from_xyz_rpy([0.0, 0.0, f64::from(mmusv_benches::CAMERA_HEIGHT)], [0.0, 0.0, 0.0]);
    let top_pose = RigidPose::from_xyz_rpy([0.0, 0.0, 120.0], [0.0, std::f64::consts::FRAC_PI_2, 0.0]);
    let (Ok(lidar), Ok(cam), Ok(top)) = (
        Lidar::new(LidarConfig::default()),
        Camera::new(CameraConfig {
            width: 640,
            height: 480,
            projection: Projection::Pinhole { hfov: std::f64::consts::FRAC_PI_2 },
            range_max: 5000.0,
            image: ImageOptions::default(),
        }),
        Camera::new(CameraConfig {
            width: 512,
            height: 512,
            projection: Projection::Orthographic { metres_per_pixel: 0.5 },
            range_max: 1000.0,
            image: ImageOptions::default(),
        }),
    ) else {
        eprintln!("could not build the sensors");
        return;
    };
    let env = ShadeEnv::default();
    let lenv = LidarEnv { wave_height_m: 1.5, ..LidarEnv::default() };
    let mut g = c.benchmark_group("sensors");
    g.throughput(Throughput::Elements(lidar.pattern().len() as u64));
    g.bench_function("lidar_sweep_64x410", |b| b.iter(|| black_box(lidar.scan(scene, &lidar_pose, &lenv, 1))));
    // The same sweep in rain of 10 mm/h with its visibility (Marshall–Palmer, 1.9 km): the drops in the beams
    // (`sensors/lidar_rain.rs`) besides the air's extinction.
    let wet = LidarEnv { rain_mm_per_h: 10.0, fog_extinction_per_m: 3.0 / 1900.0, ..lenv };
    g.bench_function("lidar_sweep_64x410_rain_10mm_h", |b| {
        b.iter(|| black_box(lidar.scan(scene, &lidar_pose, &wet, 1)))
    });
    g.throughput(Throughput::Elements(640 * 480));
    g.bench_function("camera_640x480_depth_semantic", |b| {
        b.iter(|| black_box(cam.render(scene, &cam_pose, &env, false, 1)))
    });
    // The RGB at each quality level (draft: no reflections or anti-aliasing).
    for quality in [Quality::Draft, Quality::Standard, Quality::High] {
        let cfg = CameraConfig { image: ImageOptions { quality, ..ImageOptions::default() }, ..*cam.config() };
        let Ok(q) = Camera::new(cfg) else { continue };
        g.bench_function(format!("camera_640x480_rgb_{quality:?}").to_lowercase(), |b| {
            b.iter(|| black_box(q.render(scene, &cam_pose, &env, true, 1)))
        });
    }
    g.throughput(Throughput::Elements(512 * 512));
    g.bench_function("top_view_512x512_rgb", |b| b.iter(|| black_box(top.render(scene, &top_pose, &env, true, 1))));
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .measurement_time(Duration::from_secs(5))
        .warm_up_time(Duration::from_secs(1));
    targets = bench_sensors
}
criterion_main!(benches);
