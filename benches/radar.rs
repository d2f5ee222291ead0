//! `cargo bench --bench radar`: marine radar sweep throughput (rays/s, returns per sweep) on the synthetic
//! maritime scene, calm and with 3.5 m waves (W3 sea clutter), and PPI rasterisation (returns/s).
//!
//! The sampling settings are the group's defaults (`config` below), so criterion's command line
//! (`-- --measurement-time 2 --warm-up-time 1 --sample-size 10`) overrides them; set on the group in code,
//! they silently won over it.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mmusv_core::sensors::ppi::{ppi_image, PpiConfig};
use mmusv_core::sensors::radar::{radar_sweep, RadarConfig, RadarEnv};
use mmusv_core::RigidPose;
use std::hint::black_box;
use std::time::Duration;

fn bench_radar(c: &mut Criterion) {
    let Ok(demo) = mmusv_benches::scene() else {
        eprintln!("could not build the benchmark scene");
        return;
    };
    let pose = RigidPose::from_xyz_rpy([0.0, 0.0, mmusv_benches::RADAR_HEIGHT as f64], [0.0, 0.0, 0.3]);
    // The configuration of the core's tests (as before; the user defaults live in the scenario schema).
    let cfg = RadarConfig::tuning();
    let mut g = c.benchmark_group("radar");
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

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .measurement_time(Duration::from_secs(6))
        .warm_up_time(Duration::from_secs(1));
    targets = bench_radar
}
criterion_main!(benches);
