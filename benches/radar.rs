//! `cargo bench --bench radar`: marine radar sweep throughput (rays/s, returns per sweep) on the synthetic
//! maritime scene, calm and with 3.5 m waves (W3 sea clutter), and PPI rasterisation (returns/s).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mmusv_core::sensors::ppi::{ppi_image, PpiConfig};
use mmusv_core::sensors::radar::{radar_sweep, RadarConfig, RadarEnv};
use mmusv_core::sensors::radar_model::ClutterModel;
use mmusv_core::RigidPose;
use std::hint::black_box;
use std::time::Duration;

fn bench_radar(c: &mut Criterion) {
    let Ok(demo) = mmusv_benches::scene() else {
        eprintln!("could not build the benchmark scene");
        return;
    };
    let pose = RigidPose::from_xyz_rpy([0.0, 0.0, mmusv_benches::RADAR_HEIGHT as f64], [0.0, 0.0, 0.3]);
    // The paper rig with the scenario defaults of `mmusv.sensors.config.RadarConfig` (the core has no Default).
    let cfg = RadarConfig {
        range_min_m: 10.0,
        range_max_m: 3000.0,
        range_resolution_m: 3.0,
        azimuth_bins: 2048,
        beamwidth_az_rad: 1.2f64.to_radians(),
        elevation_fan_rad: [(-10f64).to_radians(), 10f64.to_radians()],
        rays_az: 3,
        rays_el: 16,
        horizon_fraction: 0.75,
        horizon_band_rad: 1.0f64.to_radians(),
        detection_threshold: 0.3,
        range_noise_std_m: 0.0,
        clutter: ClutterModel {
            sea_sigma0_at_1m: 4.0e-7,
            critical_range_per_m: 300.0,
            sea_max_range_m: 2500.0,
            rain_eta_at_1mm_h: 5.0e-9,
        },
    };
    let mut g = c.benchmark_group("radar");
    g.sample_size(10).measurement_time(Duration::from_secs(6)).warm_up_time(Duration::from_secs(1));
    for (name, waves) in [("sweep_calm", 0.0f32), ("sweep_w3", 3.5)] {
        let env = RadarEnv { wave_height_m: waves, rain_mm_per_h: 0.0 };
        let n = radar_sweep(&demo.scene, &pose, &cfg, &env, 1).map(|r| r.len()).unwrap_or(0);
        eprintln!("radar {name}: {} rays per sweep, {n} returns", cfg.num_rays());
        g.throughput(Throughput::Elements(cfg.num_rays()));
        g.bench_function(name, |b| b.iter(|| black_box(radar_sweep(&demo.scene, &pose, &cfg, &env, 1))));
    }
    let env = RadarEnv { wave_height_m: 3.5, rain_mm_per_h: 0.0 };
    if let Ok(ret) = radar_sweep(&demo.scene, &pose, &cfg, &env, 1) {
        let ppi = PpiConfig { size_px: 1024, metres_per_pixel: 3.0, ..PpiConfig::default() };
        g.throughput(Throughput::Elements(ret.len() as u64));
        g.bench_function("ppi_1024px_w3", |b| b.iter(|| black_box(ppi_image(&ret, &ppi, 0.3, &cfg))));
    }
    g.finish();
}

criterion_group!(benches, bench_radar);
criterion_main!(benches);
