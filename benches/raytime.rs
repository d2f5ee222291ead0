//! `cargo run --release -p mmusv-benches --example raytime -- {lidar|cameras} REPS [instanced|single_mesh]`: casts
//! a ray set REPS times over one layout of the benchmark scene and prints the throughput; for quick A/B checks
//! under `time` (CPU seconds) or a profiler.

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map_or("lidar", String::as_str);
    let reps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(3);
    let layout = args.get(3).map_or("instanced", String::as_str);
    let (Ok(demo), Ok(rays)) =
        (mmusv_benches::scene(), if which == "lidar" { mmusv_benches::lidar() } else { mmusv_benches::cameras() })
    else {
        eprintln!("could not build the scene");
        return;
    };
    let scene = match layout {
        "instanced" => demo.scene,
        "single_mesh" => match mmusv_benches::single_mesh(&demo.scene) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("could not build the single mesh: {e}");
                return;
            }
        },
        other => {
            eprintln!("layout {other:?}: use instanced or single_mesh");
            return;
        }
    };
    let t0 = std::time::Instant::now();
    let mut hits = 0usize;
    for _ in 0..reps {
        if let Ok(h) = scene.cast_rays(&rays.0, &rays.1, 2000.0) {
            hits += h.instance.iter().filter(|&&i| i >= 0).count();
        }
    }
    let dt = t0.elapsed().as_secs_f64();
    println!(
        "{which} ({layout}): {} rays x {reps} in {dt:.3} s = {:.2} Mrays/s (hits {hits})",
        rays.0.len(),
        (rays.0.len() * reps) as f64 / dt / 1e6
    );
}
