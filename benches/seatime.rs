//! `cargo run --release -p mmusv-benches --example seatime -- {top|sky|water|cam} REPS`: casts one ray set over the
//! demo scene with the sea declared, and prints ns per ray.

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map_or("top", String::as_str).to_string();
    let reps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(20);
    let demo = match mmusv_benches::sea_scene() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("could not build the scene with its sea: {e}");
            return;
        }
    };
    let (o, d) = if which == "top" {
        let mut o = Vec::new();
        let mut d = Vec::new();
        for j in 0..512 {
            for i in 0..512 {
                o.push([-40.0 + i as f32 * 0.15, -40.0 + j as f32 * 0.15, 60.0]);
                d.push([0.0, 0.0, -1.0]);
            }
        }
        (o, d)
    } else {
        let Ok((o, d)) = mmusv_benches::cameras() else { return };
        let keep: Vec<usize> = (0..o.len())
            .filter(|&i| match which.as_str() {
                "sky" => d[i][2] >= 0.0,
                "water" => d[i][2] < 0.0,
                _ => true,
            })
            .collect();
        (keep.iter().map(|&i| o[i]).collect(), keep.iter().map(|&i| d[i]).collect())
    };
    let t0 = std::time::Instant::now();
    let mut hits = 0usize;
    for _ in 0..reps {
        if let Ok(h) = demo.scene.cast_rays(&o, &d, 2000.0) {
            hits += h.instance.iter().filter(|&&i| i >= 0).count();
        }
    }
    let dt = t0.elapsed().as_secs_f64();
    println!(
        "{which}: {} rays x {reps}: {:.1} ns per ray (wall), hits {hits}",
        o.len(),
        dt / (o.len() * reps) as f64 * 1e9
    );
}
