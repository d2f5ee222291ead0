//! `cargo bench --bench seacam`: a 640×480 pinhole camera's pixel rays over a W1 wave surface (Hs 1.5 m, Tp 6.1 s,
//! 256 components; one focus at the camera, the demo scene's 48 vessels around), cast two ways that give the
//! same hits: marched through the crest band ray by ray ([`Scene::cast_rays`]), and with the water hits first
//! rasterised for the whole image ([`WaveSurface::first_hits`], [`Raster::resolve`], then
//! [`Scene::cast_rays_over`]). Throughput per pixel.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mmusv_core::ocean::{SeaSpec, WaveField};
use mmusv_core::sea::{PinholeView, Raster, SurfaceSpec, WaterHit, WaveSurface};
use mmusv_core::RigidPose;
use parry3d::math::Vec3;
use rayon::prelude::*;
use std::hint::black_box;
use std::time::Duration;

const RANGE: f32 = 5000.0;

fn bench_seacam(c: &mut Criterion) {
    let Ok(mut demo) = mmusv_benches::scene() else {
        eprintln!("could not build the benchmark scene");
        return;
    };
    if let Err(e) = demo.scene.set_sea(1, &demo.vessel_instances) {
        eprintln!("could not declare the sea: {e}");
        return;
    }
    let sea = SeaSpec { hs: 1.5, tp: 6.1, gamma: 3.3, direction_rad: 0.4, spread_s: 10.0 };
    let Ok(field) = WaveField::new(&sea, 7) else {
        eprintln!("could not build the wave field");
        return;
    };
    let eye = [0.0f32, 0.0, mmusv_benches::CAMERA_HEIGHT];
    let surface = WaveSurface::new(field.components(), 12.0, 0.0, &[[eye[0], eye[1]]], SurfaceSpec::default());
    if let Err(e) = demo.scene.set_wave_surface(Some(surface)) {
        eprintln!("could not set the waves: {e}");
        return;
    }
    let scene = &demo.scene;
    let Some(waves) = scene.wave_surface() else { return };
    // Level along +x from 2 m, as a small USV's surround camera looks: water to the horizon, vessels ahead.
    let pose = RigidPose::from_xyz_rpy([0.0, 0.0, f64::from(eye[2])], [0.0, 0.0, 0.0]);
    let (w, h) = (640u32, 480u32);
    let focal = f64::from(w) / 2.0; // 90° horizontal field of view
    let axis = |v: Vec3| pose.transform_vector(v).to_array();
    let view = PinholeView {
        origin: eye,
        forward: axis(Vec3::X),
        right: axis(-Vec3::Y),
        down: axis(-Vec3::Z),
        width: w,
        height: h,
        focal,
    };
    let (mut o, mut d) = (Vec::new(), Vec::new());
    for v in 0..h {
        for u in 0..w {
            let (a, b) =
                ((f64::from(u) + 0.5 - f64::from(w) / 2.0) / focal, (f64::from(v) + 0.5 - f64::from(h) / 2.0) / focal);
            let dir: Vec<f64> = (0..3)
                .map(|i| f64::from(view.forward[i]) + a * f64::from(view.right[i]) + b * f64::from(view.down[i]))
                .collect();
            let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
            o.push(eye);
            d.push([(dir[0] / n) as f32, (dir[1] / n) as f32, (dir[2] / n) as f32]);
        }
    }
    let rasterised = |waves: &WaveSurface| {
        let raster: Option<Raster<'_>> = waves.first_hits(&view);
        let known: Option<Vec<WaterHit>> =
            raster.map(|r| (0..o.len()).into_par_iter().map(|k| r.resolve(k, o[k], d[k], RANGE)).collect());
        scene.cast_rays_over(&o, &d, RANGE, known.as_deref())
    };
    let mut g = c.benchmark_group("sea_camera_w1");
    g.sample_size(10).measurement_time(Duration::from_secs(5)).warm_up_time(Duration::from_secs(1));
    g.throughput(Throughput::Elements(u64::from(w * h)));
    g.bench_function("marched", |b| b.iter(|| black_box(scene.cast_rays(&o, &d, RANGE))));
    g.bench_function("rasterised", |b| b.iter(|| black_box(rasterised(&waves))));
    g.finish();
}

criterion_group!(benches, bench_seacam);
criterion_main!(benches);
