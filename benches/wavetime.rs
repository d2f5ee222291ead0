//! `cargo run --release -p mmusv-benches --example wavetime -- REPS`: times `WaveSurface::intersect` alone on the
//! paper's W1 sea around one focus: a radar's grazing beams, straight-down rays (one point; a top view) and rays from
//! a camera 3 m up (its lower half, and by bands of rows), plus the surface's build time; and on the paper's W3 sea,
//! a 64-channel LiDAR (−25° to 15°, 410 columns) 2 m above the water under it, as a USV carries it among the waves.

use mmusv_core::ocean::{paper_sea_states, WaveField};
use mmusv_core::sea::{SurfaceSpec, WaveSurface};

fn main() {
    let reps: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(5);
    let preset = paper_sea_states()[1];
    let Ok(field) = WaveField::new(&preset.spec(0.3, 10.0), 7) else { return };
    let mut best = f64::INFINITY;
    for k in 0..8 {
        let t0 = std::time::Instant::now();
        let s = WaveSurface::new(field.components(), 12.0 + k as f64, 0.0, &[[0.0, 0.0]], SurfaceSpec::default())
            .unwrap_or_else(|e| unreachable!("{e}"));
        best = best.min(t0.elapsed().as_secs_f64());
        std::hint::black_box(s);
    }
    let s = WaveSurface::new(field.components(), 12.0, 0.0, &[[0.0, 0.0]], SurfaceSpec::default())
        .unwrap_or_else(|e| unreachable!("{e}"));
    println!("build (one focus, least of 8): {:.2} ms, {} sampled tiles", best * 1e3, s.sampled_tiles());
    let ks: Vec<f64> = field.components().iter().map(|c| c.kx.hypot(c.ky)).collect();
    let kmax = ks.iter().copied().fold(0.0, f64::max);
    let mut sorted = ks.clone();
    sorted.sort_by(f64::total_cmp);
    println!(
        "zmin {:.2} zmax {:.2}; shortest wavelength {:.2} m, 99th pct {:.2} m, 90th {:.2} m, median {:.2} m",
        s.zmin(),
        s.zmax(),
        std::f64::consts::TAU / kmax,
        std::f64::consts::TAU / sorted[sorted.len() * 99 / 100],
        std::f64::consts::TAU / sorted[sorted.len() * 9 / 10],
        std::f64::consts::TAU / sorted[sorted.len() / 2]
    );
    let same = vec![([3.3f32, 4.4, 120.0], [0.0f32, 0.0, -1.0]); 262144];
    let mut top = Vec::new();
    for j in 0..512 {
        for i in 0..512 {
            top.push(([-128.0 + i as f32 * 0.5, -128.0 + j as f32 * 0.5, 120.0], [0.0, 0.0, -1.0]));
        }
    }
    let mut cam = Vec::new();
    for j in 240..480 {
        for i in 0..640 {
            let x = (i as f32 - 320.0) / 320.0;
            let z = -(j as f32 - 240.0 + 0.5) / 320.0;
            let n = (1.0 + x * x + z * z).sqrt();
            cam.push(([0.0, 0.0, 3.0], [1.0 / n, x / n, z / n]));
        }
    }
    // A marine radar's beams: 4 m up, 0.25°-4° down, all round.
    let mut radar = Vec::new();
    for e in 0..16 {
        let el = -(0.25 + e as f32 * 0.25f32).to_radians();
        for a in 0..2048 {
            let az = a as f32 / 2048.0 * std::f32::consts::TAU;
            radar.push(([0.0, 0.0, 4.0], [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()]));
        }
    }
    let band = |lo: usize, hi: usize| -> Vec<([f32; 3], [f32; 3])> { cam[(lo - 240) * 640..(hi - 240) * 640].to_vec() };
    let (b1, b2, b3, b4) = (band(240, 250), band(250, 270), band(270, 330), band(330, 480));
    for (name, rays) in [
        ("radar", &radar),
        ("same", &same),
        ("top", &top),
        ("camera-lower-half", &cam),
        ("rows 240-250", &b1),
        ("rows 250-270", &b2),
        ("rows 270-330", &b3),
        ("rows 330-480", &b4),
    ] {
        if std::env::var("ONLY").is_ok_and(|o| o != name) {
            continue;
        }
        time(name, &s, rays, 5000.0, reps);
    }
    let w3 = paper_sea_states()[3];
    let Ok(field3) = WaveField::new(&w3.spec(0.3, 10.0), 7) else { return };
    let s3 = WaveSurface::new(field3.components(), 12.0, 0.0, &[[0.0, 0.0]], SurfaceSpec::default())
        .unwrap_or_else(|e| unreachable!("{e}"));
    let oz = s3.height(0.0, 0.0) + 2.0;
    let mut lidar = Vec::new();
    for c in 0..64 {
        let el = (-25.0 + 40.0 * c as f32 / 63.0).to_radians();
        for a in 0..410 {
            let az = a as f32 / 410.0 * std::f32::consts::TAU;
            lidar.push(([0.0, 0.0, oz], [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()]));
        }
    }
    if std::env::var("ONLY").is_ok_and(|o| o != "lidar-w3") {
        return;
    }
    time("lidar-w3", &s3, &lidar, 200.0, reps);
    // By elevation band (channels of 410 rays each).
    for (name, lo, hi) in [("below -10°", 0, 24), ("-10° to -2°", 24, 37), ("-2° to 2°", 37, 43), ("above 2°", 43, 64)]
    {
        time(&format!("  {name}"), &s3, &lidar[lo * 410..hi * 410], 200.0, reps);
    }
}

/// Prints the mean time of `surface.intersect` over `rays` (`reps` passes) and the hits per pass.
fn time(name: &str, surface: &WaveSurface, rays: &[([f32; 3], [f32; 3])], t_max: f32, reps: usize) {
    let t0 = std::time::Instant::now();
    let mut hits = 0usize;
    for _ in 0..reps {
        hits += rays.iter().filter(|(o, d)| surface.intersect(*o, *d, t_max).is_some()).count();
    }
    let dt = t0.elapsed().as_secs_f64();
    println!("{name}: {:.1} ns per ray, hits {}", dt / (rays.len() * reps) as f64 * 1e9, hits / reps);
}
