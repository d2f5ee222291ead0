//! `cargo bench --bench seacam`: a 640×480 pinhole camera's pixel rays over a W1 wave surface (Hs 1.5 m, Tp 6.1 s,
//! 256 components; one focus at the camera, the demo scene's 48 vessels around), cast two ways that give the
//! same hits: marched through the crest band ray by ray ([`Scene::cast_rays`]), and with the water hits first
//! rasterised for the whole image ([`WaveSurface::first_hits`], [`Raster::resolve`], then
//! [`Scene::cast_rays_over`]). Throughput per pixel.
//!
//! The sampling settings are the group's defaults (`config` below), so criterion's command line
//! (`-- --measurement-time 2 --warm-up-time 1 --sample-size 10`) overrides them; set on the group in code,
//! they silently won over it.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mmusv_core::demo::surround_camera_rays;
use mmusv_core::ocean::{SeaSpec, WaveField};
use mmusv_core::sea::{PinholeView, Raster, SurfaceSpec, WaterHit, WaveSurface};
use std::hint::black_box;
use std::time::Duration;

const RANGE: f32 = 5000.0;

fn bench_seacam(c: &mut Criterion) {
    let mut demo = match mmusv_benches::sea_scene() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("could not build the benchmark scene with its sea: {e}");
            return;
        }
    };
    let sea = SeaSpec { hs: 1.5, tp: 6.1, gamma: 3.3, direction_rad: 0.4, spread_s: 10.0 };
    let Ok(field) = WaveField::new(&sea, 7) else {
        eprintln!("could not build the wave field");
        return;
    };
    let eye = [0.0f32, 0.0, mmusv_benches::CAMERA_HEIGHT];
    let surface = WaveSurface::new(field.components(), 12.0, 0.0, &[[eye[0], eye[1]]], SurfaceSpec::default())
        .unwrap_or_else(|e| unreachable!("{e}"));
    if let Err(e) = demo.scene.set_wave_surface(Some(surface)) {
        eprintln!("could not set the waves: {e}");
        return;
    }
    let scene = &demo.scene;
    let Some(waves) = scene.wave_surface() else { return };
    // One camera level along +x from 2 m, as a small USV's surround camera looks: water to the horizon, vessels
    // ahead; its pixel rays row by row (`surround_camera_rays` with one camera: image right is −y, down −z).
    let (w, h) = (640u32, 480u32);
    let hfov = std::f64::consts::FRAC_PI_2;
    let Ok((o, d)) = surround_camera_rays(eye, 1, w, h, hfov) else {
        eprintln!("could not build the camera rays");
        return;
    };
    let view = PinholeView {
        origin: eye,
        forward: [1.0, 0.0, 0.0],
        right: [0.0, -1.0, 0.0],
        down: [0.0, 0.0, -1.0],
        width: w,
        height: h,
        focal: f64::from(w) / (2.0 * (hfov / 2.0).tan()),
    };
    let rasterised = |waves: &WaveSurface| {
        let raster: Option<Raster<'_>> = waves.first_hits(&view);
        // Each ray's water hit solved from the raster as the cast asks for it.
        let known = |k: usize| raster.as_ref().map_or(WaterHit::Unknown, |r| r.resolve(k, o[k], d[k], RANGE));
        scene.cast_rays_over(&o, &d, RANGE, Some(&known))
    };
    let mut g = c.benchmark_group("sea_camera_w1");
    g.throughput(Throughput::Elements(u64::from(w * h)));
    g.bench_function("marched", |b| b.iter(|| black_box(scene.cast_rays(&o, &d, RANGE))));
    g.bench_function("rasterised", |b| b.iter(|| black_box(rasterised(&waves))));
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .measurement_time(Duration::from_secs(5))
        .warm_up_time(Duration::from_secs(1));
    targets = bench_seacam
}
criterion_main!(benches);
