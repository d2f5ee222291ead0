//! Tests of the scene: analytic hits, poses, batches against single rays and brute force, the sea shortcuts and
//! horizons against the full trace, and the SIMD levels against each other; those over a displaced wave surface in
//! [`waves`].

use super::batch::unit_direction;
use super::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A box of half extents `half` centred on the origin, every face of class `class`, outward normals.
pub(crate) fn box_mesh(half: [f32; 3], class: u16) -> Mesh {
    let [a, b, c] = half;
    let v = [[-a, -b, -c], [a, -b, -c], [a, b, -c], [-a, b, -c], [-a, -b, c], [a, -b, c], [a, b, c], [-a, b, c]];
    let f = [
        [0, 2, 1],
        [0, 3, 2],
        [4, 5, 6],
        [4, 6, 7],
        [0, 1, 5],
        [0, 5, 4],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 0, 4],
        [3, 4, 7],
    ];
    Mesh::new("box", &v, &f, &[class]).unwrap_or_else(|e| unreachable!("{e}"))
}

#[test]
fn analytic_box_hit_and_backface() {
    let mut s = Scene::new();
    let m = s.add_mesh(box_mesh([2.0, 1.0, 0.5], 9));
    let pose = RigidPose::from_xyz_rpy([10.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
    let id = s.add_instance(m, pose, None).unwrap_or(99);
    let hits = s.cast_rays(&[[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]], &[[3.0, 0.0, 0.0], [1.0, 0.0, 0.0]], 100.0);
    let hits = hits.unwrap_or_default();
    assert!((hits.distance[0] - 8.0).abs() < 1e-5);
    assert_eq!(hits.instance[0], id as i32);
    assert_eq!(hits.class[0], 9);
    assert!(!hits.backface[0]);
    assert!((hits.normal[0] + 1.0).abs() < 1e-6, "outward normal of the -x face");
    // From inside the box the ray leaves through the +x face's back side.
    assert!((hits.distance[1] - 2.0).abs() < 1e-5);
    assert!(hits.backface[1]);
}

#[test]
fn instance_pose_equals_pretransformed_mesh() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let (v, f) = crate::mesh::tests::random_soup(&mut rng, 200);
    let pose = RigidPose::from_xyz_rpy([5.0, -3.0, 2.0], [0.3, -0.2, 1.1]);
    let moved: Vec<[f32; 3]> = v.iter().map(|p| pose.transform_point(Vec3::from_array(*p)).to_array()).collect();
    let mut a = Scene::new();
    let ma = a.add_mesh(Mesh::new("a", &v, &f, &[1]).unwrap_or_else(|e| unreachable!("{e}")));
    let _ = a.add_instance(ma, RigidPose::IDENTITY, None);
    a.set_poses(&[0], &[pose]).unwrap_or_else(|e| unreachable!("{e}"));
    let mut b = Scene::new();
    let mb = b.add_mesh(Mesh::new("b", &moved, &f, &[1]).unwrap_or_else(|e| unreachable!("{e}")));
    let _ = b.add_instance(mb, RigidPose::IDENTITY, None);
    let n = 4000;
    let origins: Vec<[f32; 3]> =
        (0..n).map(|_| [rng.random_range(-20.0..20.0), rng.random_range(-20.0..20.0), 30.0]).collect();
    let dirs: Vec<[f32; 3]> =
        (0..n).map(|_| [rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5), -1.0]).collect();
    let ha = a.cast_rays(&origins, &dirs, 1e3).unwrap_or_default();
    let hb = b.cast_rays(&origins, &dirs, 1e3).unwrap_or_default();
    let mut hits = 0;
    for i in 0..n {
        assert_eq!(ha.triangle[i], hb.triangle[i], "ray {i}");
        if ha.distance[i].is_finite() {
            hits += 1;
            assert!((ha.distance[i] - hb.distance[i]).abs() <= 1e-4 * hb.distance[i]);
            for k in 0..3 {
                assert!((ha.normal[3 * i + k] - hb.normal[3 * i + k]).abs() < 1e-4);
            }
        }
    }
    assert!(hits > 200, "{hits}");
}

#[test]
fn bad_rays_and_ids_are_errors_not_panics() {
    let mut s = Scene::new();
    let m = s.add_mesh(box_mesh([1.0, 1.0, 1.0], 9));
    assert!(matches!(s.add_instance(m + 1, RigidPose::IDENTITY, None), Err(MmusvError::UnknownId { .. })));
    assert!(s.set_poses(&[3], &[RigidPose::IDENTITY]).is_err());
    assert!(s.cast_rays(&[[0.0; 3]], &[[0.0; 3]], 10.0).is_err());
    assert!(s.cast_rays(&[[f32::NAN, 0.0, 0.0]], &[[1.0, 0.0, 0.0]], 10.0).is_err());
    assert!(s.cast_rays(&[[0.0; 3]], &[[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]], 10.0).is_err());
    assert!(s.cast_rays(&[[0.0; 3]], &[[1.0, 0.0, 0.0]], -1.0).is_err());
    // Empty scene / empty batch: misses, not errors.
    assert!(Scene::new().cast_rays(&[[0.0; 3]], &[[1.0, 0.0, 0.0]], 10.0).is_ok_and(|h| h.instance[0] == NO_HIT));
    assert!(s.cast_rays(&[], &[], 10.0).is_ok_and(|h| h.is_empty()));
    // The ids a scene holds, both ends included ("ids 0..2" read as holding id 2).
    let _ = s.add_instance(m, RigidPose::IDENTITY, None);
    let _ = s.add_instance(m, RigidPose::IDENTITY, None);
    let said = s.set_poses(&[3], &[RigidPose::IDENTITY]).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(said.contains("the scene has 2 instances (ids 0 to 1)"), "{said}");
    let said = s.add_instance(m + 1, RigidPose::IDENTITY, None).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(said.contains("the scene has 1 mesh (id 0)"), "{said}");
    // One id twice: refused, naming the id and where it stands, and nothing moves (the last pose used to win).
    let moved = RigidPose::from_xyz_rpy([5.0, 0.0, 0.0], [0.0; 3]);
    let said = s.set_poses(&[1, 0, 1], &[moved; 3]).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(said.contains("instance id 1 is given 2 times (at 0, 2)"), "{said}");
    assert!(s.instances().iter().all(|i| i.pose().translation.x == 0.0));
}

#[test]
fn batch_matches_single_rays_and_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let (v, f) = crate::mesh::tests::random_soup(&mut rng, 300);
    let mut s = Scene::new();
    let soup = s.add_mesh(Mesh::new("soup", &v, &f, &[2]).unwrap_or_else(|e| unreachable!("{e}")));
    let boxm = s.add_mesh(box_mesh([1.5, 0.7, 0.5], 9));
    let _ = s.add_instance(soup, RigidPose::from_xyz_rpy([0.0, 0.0, -3.0], [0.1, 0.0, 0.4]), None);
    for k in 0..12 {
        let a = k as f64 * 0.5;
        let _ = s.add_instance(boxm, RigidPose::from_xyz_rpy([8.0 * a.cos(), 8.0 * a.sin(), 0.0], [0.0, 0.0, a]), None);
    }
    // A 96x64 pinhole image from above.
    let body = crate::sensors::rays::pinhole_directions(96, 64, 1.6).unwrap_or_default();
    let cam = RigidPose::from_xyz_rpy([0.0, 0.0, 25.0], [0.0, 1.3, 0.2]);
    let dirs: Vec<[f32; 3]> = body.iter().map(|d| cam.transform_vector(Vec3::from_array(*d)).to_array()).collect();
    let origins = vec![cam.translation.to_array(); dirs.len()];
    let batch = s.cast_rays(&origins, &dirs, 100.0).unwrap_or_default();
    let world = s.world_mesh();
    let tris: Vec<crate::geometry::PreparedTriangle> = world
        .faces
        .iter()
        .map(|f| {
            let p = |i: u32| Vec3::from_array(world.vertices[i as usize]);
            crate::geometry::PreparedTriangle::new(p(f[0]), p(f[1]), p(f[2]))
        })
        .collect();
    let mut hits = 0;
    for i in 0..dirs.len() {
        let d = Vec3::from_array(dirs[i]).normalize();
        let single = s.cast_ray(Vec3::from_array(origins[i]), d, 100.0);
        assert_eq!(single.map(|h| h.instance as i32).unwrap_or(NO_HIT), batch.instance[i], "ray {i}");
        let brute = tris
            .iter()
            .enumerate()
            .filter_map(|(k, t)| t.intersect(&RayPrep::new(origins[i], d.to_array()), 100.0).map(|t| (t, k)))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        match brute {
            Some((t, k)) => {
                hits += 1;
                assert!((batch.distance[i] - t).abs() <= 1e-4 * t.max(1.0), "ray {i}: {} vs {t}", batch.distance[i]);
                assert_eq!(world.instances[k] as i32, batch.instance[i]);
                assert_eq!(world.triangles[k] as i32, batch.triangle[i]);
            }
            None => assert_eq!(batch.instance[i], NO_HIT),
        }
    }
    assert!(hits > 400, "{hits}");
}

#[test]
fn max_range_is_honoured() {
    let mut s = Scene::new();
    let m = s.add_mesh(box_mesh([1.0, 1.0, 1.0], 9));
    let _ = s.add_instance(m, RigidPose::from_xyz_rpy([10.0, 0.0, 0.0], [0.0; 3]), None);
    let h = s.cast_rays(&[[0.0; 3]], &[[1.0, 0.0, 0.0]], 8.5).unwrap_or_default();
    assert_eq!(h.instance[0], NO_HIT);
    let h = s.cast_rays(&[[0.0; 3]], &[[1.0, 0.0, 0.0]], 9.5).unwrap_or_default();
    assert_eq!(h.instance[0], 0);
}

/// A small maritime world: the demo heightfield and hulls, a water plane, vessels that move.
fn sea_world() -> (Scene, Vec<u32>) {
    let p = crate::demo::DemoParams { terrain_cells: 96, vessels: 24, extent: 600.0, ..Default::default() };
    let demo = crate::demo::maritime_demo(p).unwrap_or_else(|e| unreachable!("{e}"));
    let ids = demo.vessel_instances.clone();
    (demo.scene, ids)
}

/// Rays of the kinds the sensors cast: camera-like rays from a few metres up in every direction, steep
/// and grazing, and shadow-like rays from the water surface towards a sun.
fn sensor_rays(rng: &mut ChaCha8Rng, n: usize) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let mut o = Vec::with_capacity(n);
    let mut d = Vec::with_capacity(n);
    for k in 0..n {
        let origin = [rng.random_range(-250.0..250.0), rng.random_range(-250.0..250.0), rng.random_range(0.5..40.0)];
        let az: f32 = rng.random_range(0.0..std::f32::consts::TAU);
        let el: f32 = match k % 4 {
            0 => rng.random_range(-1.5..-0.01),
            1 => rng.random_range(-0.05..0.05),
            2 => rng.random_range(0.0..1.5),
            _ => -std::f32::consts::FRAC_PI_2,
        };
        o.push(origin);
        d.push([az.cos() * el.cos(), az.sin() * el.cos(), el.sin()]);
    }
    (o, d)
}

/// Moves the vessels to random places within 200 m of the origin, random headings, at height, roll and pitch
/// `[z, roll, pitch]`.
fn scatter(s: &mut Scene, vessels: &[u32], rng: &mut ChaCha8Rng, [z, roll, pitch]: [f64; 3]) {
    let poses: Vec<RigidPose> = vessels
        .iter()
        .map(|_| {
            let (x, y) = (rng.random_range(-200.0..200.0), rng.random_range(-200.0..200.0));
            RigidPose::from_xyz_rpy([x, y, z], [roll, pitch, rng.random_range(0.0..std::f64::consts::TAU)])
        })
        .collect();
    s.set_poses(vessels, &poses).unwrap_or_else(|e| unreachable!("{e}"));
}

#[test]
fn sea_shortcuts_give_exactly_the_full_trace() {
    let (mut s, vessels) = sea_world();
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    for frame in 0..3 {
        // Move the vessels (the height map follows their boxes), then compare with and without the sea.
        scatter(&mut s, &vessels, &mut rng, [0.3, 0.02, -0.03]);
        let mut with = s.clone();
        with.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
        let (o, d) = sensor_rays(&mut rng, 20_000);
        let full = s.cast_rays(&o, &d, 800.0).unwrap_or_default();
        let fast = with.cast_rays(&o, &d, 800.0).unwrap_or_default();
        assert_eq!(full, fast, "frame {frame}");
        // The same directions from above everything: the rising ones are settled as misses.
        let high: Vec<[f32; 3]> = o.iter().map(|p| [p[0], p[1], 150.0]).collect();
        assert_eq!(s.cast_rays(&high, &d, 800.0).ok(), with.cast_rays(&high, &d, 800.0).ok(), "frame {frame}");
        let sky = |o: &[f32; 3], d: &[f32; 3]| with.sea_sky(&RayPrep::new(*o, unit_direction(d)), 800.0, None);
        let settled = high.iter().zip(&d).filter(|(o, d)| sky(o, d)).count();
        assert!(settled > 5_000, "only {settled} of 20000 rays settled by the sea shortcut");
        // Coherent sets, in 4x4 tiles as the cameras trace them: a pinhole fan from 3 m up looking at the
        // water and the horizon, and a top view's vertical rays.
        let (mut co, mut cd) = (Vec::new(), Vec::new());
        let eye = [rng.random_range(-150.0..150.0), rng.random_range(-150.0..150.0), 3.0f32];
        for top_view in [false, true] {
            for tile in 0..64u32 {
                for k in 0..16u32 {
                    let (u, v) = ((tile % 8) * 4 + k % 4, (tile / 8) * 4 + k / 4);
                    if top_view {
                        co.push([eye[0] + 0.5 * u as f32, eye[1] + 0.5 * v as f32, 120.0]);
                        cd.push([0.0, 0.0, -1.0]);
                    } else {
                        let (az, el) = (0.03 * u as f32 - 0.5, -0.02 * v as f32 + 0.05);
                        co.push(eye);
                        cd.push([az.cos() * el.cos(), az.sin() * el.cos(), el.sin()]);
                    }
                }
            }
        }
        assert_eq!(s.cast_rays(&co, &cd, 800.0).ok(), with.cast_rays(&co, &cd, 800.0).ok(), "frame {frame}");
        // Shadow rays: from just above the water towards the sun, and from above everything.
        let sun = [0.4f32, 0.3, 0.866];
        let so: Vec<[f32; 3]> =
            o.iter().enumerate().map(|(k, p)| [p[0], p[1], if k % 2 == 0 { 0.03 } else { 150.0 }]).collect();
        let sd = vec![sun; so.len()];
        let full_shadow = s.occluded_rays(&so, &sd, 5000.0).unwrap_or_default();
        let fast_shadow = with.occluded_rays(&so, &sd, 5000.0).unwrap_or_default();
        let differ = full_shadow.iter().zip(&fast_shadow).filter(|(a, b)| a != b).count();
        assert!(differ == 0 && fast_shadow.len() == so.len(), "{differ} shadow rays differ (frame {frame})");
        let shaded = full_shadow.iter().step_by(2).filter(|&&b| b).count();
        assert!(shaded > 100, "only {shaded} water points in shade: the comparison proves little");
        let clear = so.iter().filter(|p| with.sea_clear(&RayPrep::new(**p, sun), 5000.0)).count();
        assert!(clear >= 10_000, "only {clear} shadow rays settled");
        // The sun mask (one direction for the whole batch) settles most of the water points by itself.
        let unit = unit_direction(&sun);
        let mask = with.sea.as_ref().and_then(|sea| sea.sun_mask(unit));
        let by_mask = so.iter().filter(|p| with.sun_clear(mask.as_deref(), **p)).count();
        assert!(by_mask >= 6_000, "only {by_mask} shadow rays settled by the sun mask");
    }
    // A moving surface is no longer trusted; a tilted one is refused.
    let mut with = s.clone();
    with.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
    with.set_poses(&[1], &[RigidPose::from_xyz_rpy([0.0, 0.0, 1.0], [0.0; 3])]).unwrap_or_else(|e| unreachable!("{e}"));
    assert_eq!(with.sea_instance(), None);
    let mut tilted = s.clone();
    tilted
        .set_poses(&[1], &[RigidPose::from_xyz_rpy([0.0; 3], [0.1, 0.0, 0.0])])
        .unwrap_or_else(|e| unreachable!("{e}"));
    assert!(tilted.set_sea(1, &vessels).is_err());
}

/// A sea prepared on an earlier state of the scene ([`Scene::prepare_sea`], as the Python binding builds it on a
/// snapshot with the GIL released) and installed after the vessels and the fixed terrain moved answers every ray
/// as the full trace of the scene as it is now.
#[test]
fn a_sea_prepared_before_moves_installs_as_one_built_after_them() {
    let (mut s, vessels) = sea_world();
    let mut rng = ChaCha8Rng::seed_from_u64(22);
    let prepared = s.prepare_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
    scatter(&mut s, &vessels, &mut rng, [0.3, 0.02, -0.03]);
    for moved_terrain in [false, true] {
        if moved_terrain {
            let pose = RigidPose::from_xyz_rpy([40.0, -30.0, 0.0], [0.0, 0.0, 0.3]);
            s.set_poses(&[0], &[pose]).unwrap_or_else(|e| unreachable!("{e}"));
        }
        let mut with = s.clone();
        with.install_sea(prepared.clone()).unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(with.sea_instance(), Some(1));
        let (o, d) = sensor_rays(&mut rng, 20_000);
        let full = s.cast_rays(&o, &d, 800.0).unwrap_or_default();
        assert_eq!(full, with.cast_rays(&o, &d, 800.0).unwrap_or_default(), "terrain moved: {moved_terrain}");
        let high: Vec<[f32; 3]> = o.iter().map(|p| [p[0], p[1], 150.0]).collect();
        assert_eq!(s.cast_rays(&high, &d, 800.0).ok(), with.cast_rays(&high, &d, 800.0).ok());
        // Shadow rays from the water towards a low sun, where the sun mask settles most.
        let so: Vec<[f32; 3]> =
            (0..40_000).map(|k| [(k % 200) as f32 * 3.0 - 300.0, (k / 200) as f32 * 3.0 - 300.0, 0.03]).collect();
        let sd = vec![[0.8f32, 0.3, 0.35]; so.len()];
        let want = s.occluded_rays(&so, &sd, 5000.0).unwrap_or_default();
        let got = with.occluded_rays(&so, &sd, 5000.0).unwrap_or_default();
        let differ = want.iter().zip(&got).filter(|(a, b)| a != b).count();
        assert!(differ == 0 && got.len() == so.len(), "{differ} shadow rays differ (terrain moved: {moved_terrain})");
        assert!(want.iter().filter(|&&b| b).count() > 500, "too few points in shade to tell");
        if moved_terrain {
            // the fixed geometry moved since the grid was built: built again, as a grid built now
            let mut fresh = s.clone();
            fresh.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
            let same = matches!((&with.sea, &fresh.sea), (Some(a), Some(b)) if a.same_grid(b));
            assert!(same, "the grid of the terrain where it was was installed");
        }
    }
}

/// With the sea declared and one sun direction (the sun mask settles rays from their origins alone), a bad
/// origin is still an error naming it, and the settled rays are those of the full trace.
#[test]
fn shadow_batches_with_a_sun_mask_name_bad_origins() {
    let (mut s, vessels) = sea_world();
    let full = s.clone();
    s.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
    let mut o: Vec<[f32; 3]> =
        (0..2000).map(|k| [(k % 50) as f32 * 9.0 - 220.0, (k / 50) as f32 * 9.0 - 180.0, 0.05]).collect();
    let sun = vec![[0.2f32, -0.4, 0.7]; o.len()];
    let want = full.occluded_rays(&o, &sun, 5000.0).unwrap_or_default();
    assert_eq!(s.occluded_rays(&o, &sun, 5000.0).ok(), Some(want));
    for bad in [[f32::NAN, 0.0, 3.0], [10.0, f32::INFINITY, 3.0], [10.0, 0.0, f32::NAN]] {
        o[1234] = bad;
        let err = s.occluded_rays(&o, &sun, 5000.0).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(err.contains("origins[1234]"), "{bad:?}: {err}");
    }
}

#[test]
fn horizons_of_one_origin_batches_give_exactly_the_full_trace() {
    let (mut s, vessels) = sea_world();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    scatter(&mut s, &vessels, &mut rng, [0.2, 0.03, -0.02]);
    let mut with = s.clone();
    with.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
    // Viewpoints: over open water, on (and in) the vessels' boxes as a USV's cameras are, high above all.
    let mut eyes: Vec<[f32; 3]> = (0..6)
        .map(|_| [rng.random_range(-250.0..250.0), rng.random_range(-250.0..250.0), rng.random_range(0.5..6.0)])
        .collect();
    for &v in vessels.iter().take(8) {
        let b = with.world_aabbs[v as usize];
        let (c, h) = (b.center(), b.half_extents());
        eyes.push([c.x + 0.3 * h.x, c.y - 0.2 * h.y, b.maxs.z - 0.3 * h.z]);
        eyes.push([c.x, c.y, b.maxs.z + 0.5]);
        eyes.push([b.maxs.x + 0.05, c.y, c.z]);
    }
    eyes.push([0.0, 0.0, 400.0]);
    // Every direction on a 96 × 64 grid (the pole rows included), most of them rising.
    let mut dirs = Vec::new();
    for i in 0..96 {
        for j in 0..64 {
            let az = i as f32 * std::f32::consts::TAU / 96.0 + 0.001;
            let el = -0.3 + 1.8708 * j as f32 / 63.0;
            dirs.push([az.cos() * el.cos(), az.sin() * el.cos(), el.sin()]);
        }
    }
    // (settled, rising) over the open-water viewpoints and over those on the decks.
    let (mut water, mut decks) = ((0, 0), (0, 0));
    for (k, eye) in eyes.iter().enumerate() {
        let o = vec![*eye; dirs.len()];
        let full = s.cast_rays(&o, &dirs, 900.0).unwrap_or_default();
        let fast = with.cast_rays(&o, &dirs, 900.0).unwrap_or_default();
        assert_eq!(full, fast, "viewpoint {eye:?}");
        let Some(h) = with.horizon(*eye) else { continue };
        let tally = if k < 6 {
            &mut water
        } else if k % 3 == 1 {
            &mut decks
        } else {
            continue;
        };
        for d in &dirs {
            let ray = RayPrep::new(*eye, unit_direction(d));
            tally.1 += usize::from(ray.d[2] >= 0.0);
            tally.0 += usize::from(h.clear(ray.d));
        }
    }
    // Islands of 45-95 m hide some of the sky over the water; a deck's own mast and neighbours more.
    assert!(water.0 * 10 > water.1 * 6, "the horizons settled only {water:?} rising rays over the water");
    assert!(decks.0 * 10 > decks.1 * 4, "the horizons settled only {decks:?} rising rays on the decks");
    assert!(with.horizon([0.0, 0.0, -1.0]).is_none(), "no horizon under the surface");
}

/// The AVX2 and portable versions of the batch casts (and of the mesh kernels they call) give the same
/// bits: LiDAR-like and camera-like ray sets, packets and single rays, with and without the sea shortcuts,
/// closest hits and shadow rays.
#[test]
fn every_simd_level_gives_the_same_bits() {
    let (mut s, vessels) = sea_world();
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let mut origins = Vec::new();
    let mut dirs = Vec::new();
    for k in 0..6000 {
        let o = if k < 4096 { [3.0, -2.0, 2.5] } else { [rng.random_range(-250.0..250.0), 0.0, 30.0] };
        origins.push(o);
        dirs.push([rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-0.6..0.3)]);
    }
    let sun = vec![[0.3, 0.2, 0.9]; origins.len()];
    let mut runs = Vec::new();
    for sea in [false, true] {
        if sea {
            s.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
        }
        for portable in [true, false] {
            crate::simd::set_portable(portable);
            let hits = s.cast_rays(&origins, &dirs, 900.0).unwrap_or_default();
            let shadow = s.occluded_rays(&origins, &sun, 900.0).unwrap_or_default();
            runs.push((sea, portable, hits, shadow));
        }
    }
    crate::simd::set_portable(false);
    for pair in runs.chunks(2) {
        let ((sea, _, a, sa), (_, _, b, sb)) = (&pair[0], &pair[1]);
        assert!(a.instance.iter().filter(|&&i| i >= 0).count() > 2000, "sea {sea}: too few hits");
        assert!(sa.iter().filter(|&&x| x).count() > 100, "sea {sea}: too few shadowed rays");
        let bits = |h: &RayHits| h.distance.iter().chain(&h.normal).map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(a), bits(b), "sea {sea}: distances or normals differ between the levels");
        assert_eq!(
            (&a.instance, &a.triangle, &a.class, &a.backface),
            (&b.instance, &b.triangle, &b.class, &b.backface)
        );
        assert_eq!(sa, sb, "sea {sea}: shadow rays differ between the levels");
    }
    // The mesh kernels called directly with each token.
    if let Some(avx2) = crate::simd::Avx2::detect() {
        let mesh = &s.meshes()[0];
        let mut stack = Stack::default();
        for (o, d) in origins.iter().zip(&dirs) {
            let ray = RayPrep::new(*o, unit_direction(d));
            let a = mesh.closest(Portable, &ray, 900.0, &mut stack);
            let b = mesh.closest(avx2, &ray, 900.0, &mut stack);
            assert_eq!(a.map(|h| (h.t.to_bits(), h.triangle)), b.map(|h| (h.t.to_bits(), h.triangle)));
            assert_eq!(mesh.any(Portable, &ray, 900.0, &mut stack), mesh.any(avx2, &ray, 900.0, &mut stack));
        }
    }
}

mod waves;

#[test]
fn a_moving_instance_swaying_at_the_edge_of_the_scene_keeps_the_horizons() {
    // A map's last buoy, tilting with the waves, took its box past the height grid (built round every instance
    // as they stood): a moving box outside the grid turned every viewpoint's horizon off.
    let ok = |r: Result<()>| r.unwrap_or_else(|e| unreachable!("{e}"));
    let (mut s, vessels) = sea_world();
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    scatter(&mut s, &vessels, &mut rng, [0.3, 0.0, 0.0]);
    let v = vessels[0];
    let others = (0..s.instances.len() as u32).filter(|&i| i != 1 && i != v);
    let lo = others.map(|i| s.world_aabbs[i as usize].mins.x).fold(f32::INFINITY, f32::min);
    let at = [f64::from(lo) - 40.0, 0.0, 0.3];
    let yaw = std::f64::consts::FRAC_PI_2; // beam across x: a roll sweeps the hull's height into -x
    ok(s.set_poses(&[v], &[RigidPose::from_xyz_rpy(at, [0.0, 0.0, yaw])]));
    let mut with = s.clone();
    ok(with.set_sea(1, &vessels));
    let eye = [0.0, 0.0, 3.0];
    assert!(with.horizon(eye).is_some());
    // It tilts 10° where it stands: its box reaches past where it was, and past every other instance.
    let rest = with.world_aabbs[v as usize].mins.x;
    let tilted = RigidPose::from_xyz_rpy(at, [-0.17, 0.0, yaw]);
    ok(s.set_poses(&[v], &[tilted]));
    ok(with.set_poses(&[v], &[tilted]));
    assert!(with.world_aabbs[v as usize].mins.x < rest - 0.1, "{rest} {}", with.world_aabbs[v as usize].mins.x);
    assert!(with.horizon(eye).is_some(), "the tilted instance turned the horizons off");
    let dirs: Vec<[f32; 3]> = (0..720)
        .map(|k| {
            let (az, el) = (k as f32 * 0.0523, (k % 9) as f32 * 0.1 - 0.2);
            [az.cos() * el.cos(), az.sin() * el.cos(), el.sin()]
        })
        .collect();
    let o = vec![eye; dirs.len()];
    assert_eq!(s.cast_rays(&o, &dirs, 900.0).ok(), with.cast_rays(&o, &dirs, 900.0).ok());
}
