//! `cargo run --release -p mmusv-benches --example raybands -- [instanced|single_mesh] [REPS]`: the LiDAR sweep
//! of the benchmark scene split by elevation band (steeply down, shallow down, grazing, shallow up, up), each
//! band cast on one thread, best of REPS: nanoseconds per ray and hits per band, to see which rays cost what.

use mmusv_core::Scene;

/// Bands of the direction's z component.
const BANDS: [(f32, f32); 5] = [(-1.0, -0.2), (-0.2, -0.05), (-0.05, 0.0), (0.0, 0.05), (0.05, 1.0)];

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let layout = args.get(1).map_or("instanced", String::as_str);
    let reps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(20);
    if let Err(e) = run(layout, reps) {
        eprintln!("raybands: {e}");
        std::process::exit(1);
    }
}

fn run(layout: &str, reps: usize) -> Result<(), String> {
    let demo = mmusv_benches::scene().map_err(|e| e.to_string())?;
    let scene: Scene = match layout {
        "instanced" => demo.scene,
        "single_mesh" => mmusv_benches::single_mesh(&demo.scene).map_err(|e| e.to_string())?,
        other => return Err(format!("layout {other:?}: use instanced or single_mesh")),
    };
    let (o, d) = mmusv_benches::lidar().map_err(|e| e.to_string())?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().map_err(|e| e.to_string())?;
    let mut total = 0.0;
    for (lo, hi) in BANDS {
        let idx: Vec<usize> = (0..d.len()).filter(|&i| d[i][2] >= lo && d[i][2] < hi).collect();
        let oo: Vec<[f32; 3]> = idx.iter().map(|&i| o[i]).collect();
        let dd: Vec<[f32; 3]> = idx.iter().map(|&i| d[i]).collect();
        let (mut best, mut hits) = (f64::MAX, 0);
        for _ in 0..reps.max(1) {
            let t0 = std::time::Instant::now();
            let h = pool.install(|| scene.cast_rays(&oo, &dd, 2000.0)).map_err(|e| e.to_string())?;
            best = best.min(t0.elapsed().as_secs_f64());
            hits = h.instance.iter().filter(|&&i| i >= 0).count();
        }
        total += best;
        println!(
            "dz in [{lo:5.2},{hi:5.2}): {:6} rays, {:6.1} ns/ray, hits {hits}, {:.2} ms",
            idx.len(),
            best * 1e9 / idx.len().max(1) as f64,
            best * 1e3
        );
    }
    println!("{layout}: total {:.2} ms = {:.2} Mrays/s on one thread", total * 1e3, d.len() as f64 / total / 1e6);
    Ok(())
}
