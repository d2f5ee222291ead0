//! `cargo bench`: ray-casting throughput (rays/s, criterion's `elem/s`) on the synthetic maritime scene in its two
//! layouts, and the cost of moving vessel instances (top-level rebuild only).
//!
//! * `instanced`: terrain, water plane and vessels as separate instances (how `mmusv` builds its worlds);
//! * `single_mesh`: the same triangles concatenated into one mesh at the identity pose, no instancing (how a
//!   user's own meshes often look). `benches/compare_open3d.py` times Open3D (Embree) on both layouts.
//!
//! The sampling settings are each group's defaults (`config` below), so criterion's command line
//! (`-- --measurement-time 2 --warm-up-time 1 --sample-size 10`) overrides them; set on the group in code,
//! they silently won over it.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mmusv_core::RigidPose;
use std::hint::black_box;
use std::time::Duration;

fn bench_raycast(c: &mut Criterion) {
    let (demo, lidar, cams) = match (mmusv_benches::scene(), mmusv_benches::lidar(), mmusv_benches::cameras()) {
        (Ok(s), Ok(l), Ok(c)) => (s, l, c),
        _ => {
            eprintln!("could not build the benchmark scene");
            return;
        }
    };
    eprintln!(
        "scene: {} world triangles, {} instances; lidar rays {}, camera rays {}",
        demo.scene.num_world_triangles(),
        demo.scene.instances().len(),
        lidar.0.len(),
        cams.0.len()
    );
    let single = match mmusv_benches::single_mesh(&demo.scene) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("could not build the single-mesh scene: {e}");
            return;
        }
    };
    let mut g = c.benchmark_group("raycast");
    for (layout, scene) in [("instanced", &demo.scene), ("single_mesh", &single)] {
        g.throughput(Throughput::Elements(lidar.0.len() as u64));
        g.bench_function(format!("{layout}/lidar_64x2048"), |b| {
            b.iter(|| black_box(scene.cast_rays(&lidar.0, &lidar.1, 2000.0)))
        });
        g.throughput(Throughput::Elements(cams.0.len() as u64));
        g.bench_function(format!("{layout}/cameras_4x640x480"), |b| {
            b.iter(|| black_box(scene.cast_rays(&cams.0, &cams.1, 2000.0)))
        });
    }
    g.finish();
}

fn bench_pose_update(c: &mut Criterion) {
    let demo = match mmusv_benches::scene() {
        Ok(s) => s,
        Err(e) => {
            eprintln!("could not build the benchmark scene: {e}");
            return;
        }
    };
    let mut scene = demo.scene.clone();
    let ids: Vec<u32> = demo.vessel_instances.iter().copied().take(50).collect();
    let mut g = c.benchmark_group("pose_update");
    let mut k = 0.0f64;
    g.bench_function(format!("move_{}_instances", ids.len()), |b| {
        b.iter(|| {
            k += 1.0;
            let poses: Vec<RigidPose> = ids
                .iter()
                .map(|&i| RigidPose::from_xyz_rpy([i as f64 * 10.0 + k * 0.01, 0.0, 0.0], [0.0, 0.0, k * 0.001]))
                .collect();
            black_box(scene.set_poses(&ids, &poses))
        })
    });
    g.finish();
}

criterion_group! {
    name = raycast;
    config = Criterion::default()
        .sample_size(10)
        .measurement_time(Duration::from_secs(6))
        .warm_up_time(Duration::from_secs(1));
    targets = bench_raycast
}
criterion_group! {
    name = pose_update;
    config = Criterion::default().sample_size(50).measurement_time(Duration::from_secs(2));
    targets = bench_pose_update
}
criterion_main!(raycast, pose_update);
