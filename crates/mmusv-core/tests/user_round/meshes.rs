//! Meshes and scenes: ray hits against triangles, boxes and planes match Möller–Trumbore, slab and plane
//! formulas computed here; meshes, scenes, instances, materials and the seabed refuse bad input.

use super::common::{
    add, box_mesh, close, cross, dot, f32x3, f64x3, guarded, mat_t_vec, mat_vec, norm, ok, ray_box, ray_triangle,
    refuses, rpy_matrix, scale, square_mesh, sub, unit, Lcg,
};
use mmusv_core::geometry::RigidPose;
use mmusv_core::material::Material;
use mmusv_core::mesh::Mesh;
use mmusv_core::scene::{Scene, CLASS_NONE, NO_HIT};
use mmusv_core::seabed::Seabed;
use parry3d::math::{Mat3, Vec3};

#[test]
fn ray_triangle_hits_match_moller_trumbore() {
    let tri = [[0.0f32, 0.0, 0.0], [4.0, 0.5, 0.2], [1.0, 3.0, -0.4]];
    let mesh = ok("triangle mesh", || Mesh::new("tri", &tri, &[[0, 1, 2]], &[9]));
    let mut scene = Scene::new();
    let mid = scene.add_mesh(mesh);
    let rpy = [0.2, -0.3, 0.7];
    let xyz = [10.0, -5.0, 2.0];
    let pose = RigidPose::from_xyz_rpy(xyz, rpy);
    let inst = ok("add_instance", || scene.add_instance(mid, pose, None));
    let r = rpy_matrix(rpy);
    let world: Vec<[f64; 3]> = tri.iter().map(|v| add(mat_vec(&r, f64x3(*v)), xyz)).collect();
    let n_world = unit(cross(sub(world[1], world[0]), sub(world[2], world[0])));
    let mut rng = Lcg(11);
    let (mut origins, mut dirs, mut want) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..4000 {
        let o = [xyz[0] + rng.range(-8.0, 8.0), xyz[1] + rng.range(-8.0, 8.0), xyz[2] + rng.range(-8.0, 8.0)];
        // Aim at a random point of the plane near the triangle, so about half the rays hit.
        let (u, v) = (rng.range(-0.3, 1.0), rng.range(-0.3, 1.0));
        let target = add(world[0], add(scale(sub(world[1], world[0]), u), scale(sub(world[2], world[0]), v)));
        let d = sub(target, o);
        let lenfac = rng.range(0.5, 3.0); // directions need not be unit: they are normalised
        origins.push(f32x3(o));
        dirs.push(f32x3(scale(d, lenfac)));
        want.push(ray_triangle(o, unit(d), world[0], world[1], world[2]));
    }
    let hits = ok("cast_rays", || scene.cast_rays(&origins, &dirs, 1e4));
    assert_eq!(hits.len(), origins.len());
    assert_eq!(hits.normal.len(), 3 * origins.len());
    let mut checked = 0;
    for (i, w) in want.iter().enumerate() {
        // Rays grazing an edge are decided by the watertight test; skip a margin around the edges.
        let near_edge = w.is_some_and(|(_, u, v)| u.min(v).min(1.0 - u - v) < 1e-3);
        let mt_miss_near = {
            let o = f64x3(origins[i]);
            let d = unit(f64x3(dirs[i]));
            let e = 1e-3;
            let grown = [
                add(world[0], scale(sub(world[0], add(world[1], world[2])), e)),
                add(world[1], scale(sub(world[1], add(world[0], world[2])), e)),
                add(world[2], scale(sub(world[2], add(world[0], world[1])), e)),
            ];
            w.is_none() && ray_triangle(o, d, grown[0], grown[1], grown[2]).is_some()
        };
        if near_edge || mt_miss_near {
            continue;
        }
        checked += 1;
        match w {
            Some((t, _, _)) => {
                assert!(close(f64::from(hits.distance[i]), *t, 1e-4), "ray {i}: {} vs {t}", hits.distance[i]);
                assert_eq!(hits.instance[i], inst as i32);
                assert_eq!(hits.triangle[i], 0);
                assert_eq!(hits.class[i], 9);
                let n = [hits.normal[3 * i], hits.normal[3 * i + 1], hits.normal[3 * i + 2]].map(f64::from);
                assert!((norm(n) - 1.0).abs() < 1e-5, "unit normal");
                assert!(dot(n, n_world) > 0.9999, "normal follows the winding, world frame");
                let d = unit(f64x3(dirs[i]));
                assert_eq!(hits.backface[i], dot(n_world, d) > 0.0);
            }
            None => {
                assert!(hits.distance[i].is_infinite() && hits.distance[i] > 0.0, "miss distance is +inf");
                assert_eq!((hits.instance[i], hits.triangle[i], hits.class[i]), (NO_HIT, NO_HIT, CLASS_NONE));
                assert_eq!(&hits.normal[3 * i..3 * i + 3], &[0.0, 0.0, 0.0]);
            }
        }
    }
    assert!(checked > 3000);
    // max_range cuts hits off.
    let near = ok("cast_rays short", || scene.cast_rays(&origins, &dirs, 2.0));
    for i in 0..origins.len() {
        assert!(near.distance[i] < 2.0 || near.distance[i].is_infinite());
    }
    // The single-ray query agrees with the batch.
    for i in (0..origins.len()).step_by(97) {
        let d = Vec3::from_array(f32x3(unit(f64x3(dirs[i]))));
        let one = scene.cast_ray(Vec3::from_array(origins[i]), d, 1e4);
        match one {
            Some(h) => assert!((h.distance - hits.distance[i]).abs() <= 1e-4 * h.distance.max(1.0)),
            None => assert!(hits.distance[i].is_infinite()),
        }
    }
}

#[test]
fn ray_box_and_plane_hits_match_slab_and_plane_formulas() {
    let h = [3.0f32, 1.5, 0.75];
    let mut scene = Scene::new();
    let bm = scene.add_mesh(ok("box", || box_mesh("box", h, 10)));
    let sm = scene.add_mesh(ok("square", || square_mesh("sea", 500.0, 1)));
    let rpy = [0.1, 0.2, -0.9];
    let xyz = [20.0, 10.0, 4.0];
    let bi = ok("box instance", || scene.add_instance(bm, RigidPose::from_xyz_rpy(xyz, rpy), Some(42)));
    let si = ok("sea instance", || scene.add_instance(sm, RigidPose::IDENTITY, None));
    // World box of the rotated box: centre ± |R| h.
    let r = rpy_matrix(rpy);
    let aabb = ok("instance_aabb", || scene.instance_aabb(bi));
    for i in 0..3 {
        let he: f64 = (0..3).map(|j| r[i][j].abs() * f64::from(h[j])).sum();
        assert!((f64::from(aabb.mins.to_array()[i]) - (xyz[i] - he)).abs() < 1e-4);
        assert!((f64::from(aabb.maxs.to_array()[i]) - (xyz[i] + he)).abs() < 1e-4);
    }
    refuses("instance_aabb of an unknown id", "instance", || scene.instance_aabb(99));

    let mut rng = Lcg(5);
    let (mut o, mut d) = (Vec::new(), Vec::new());
    for k in 0..3000 {
        let origin = if k % 10 == 0 {
            // From inside the box: the exit face, seen from behind.
            add(xyz, mat_vec(&r, [rng.range(-2.0, 2.0), rng.range(-1.0, 1.0), rng.range(-0.5, 0.5)]))
        } else {
            [rng.range(-10.0, 50.0), rng.range(-20.0, 40.0), rng.range(1.0, 20.0)]
        };
        let target = [xyz[0] + rng.range(-5.0, 5.0), xyz[1] + rng.range(-5.0, 5.0), rng.range(-3.0, 8.0)];
        o.push(f32x3(origin));
        d.push(f32x3(unit(sub(target, origin))));
    }
    let hits = ok("cast_rays", || scene.cast_rays(&o, &d, 1e4));
    let occluded = ok("occluded_rays", || scene.occluded_rays(&o, &d, 1e4));
    let (mut on_box, mut on_sea) = (0, 0);
    for i in 0..o.len() {
        let (oi, di) = (f64x3(o[i]), unit(f64x3(d[i])));
        let local_o = mat_t_vec(&r, sub(oi, xyz));
        let local_d = mat_t_vec(&r, di);
        let box_hit = ray_box(local_o, local_d, f64x3(h));
        let sea_hit = (di[2] < 0.0 && oi[2] > 0.0).then(|| -oi[2] / di[2]).filter(|t| {
            let p = add(oi, scale(di, *t));
            p[0].abs() < 500.0 && p[1].abs() < 500.0
        });
        let want = match (box_hit, sea_hit) {
            (Some((tb, axis)), Some(ts)) if tb < ts => Some((tb, bi, Some(axis))),
            (Some((tb, axis)), None) => Some((tb, bi, Some(axis))),
            (_, Some(ts)) => Some((ts, si, None)),
            (None, None) => None,
        };
        // Near a tie or an edge the two answers may differ by rounding: skip those.
        if let (Some((tb, _)), Some(ts)) = (box_hit, sea_hit) {
            if (tb - ts).abs() < 1e-3 {
                continue;
            }
        }
        if let Some((t, _)) = box_hit {
            let p = add(local_o, scale(local_d, t));
            let on_edge = (0..3).filter(|&a| (p[a].abs() - f64::from(h[a])).abs() < 1e-3).count() > 1;
            if on_edge {
                continue;
            }
        }
        assert_eq!(occluded[i], want.is_some(), "ray {i}: occluded_rays agrees with the closest hit");
        match want {
            Some((t, inst, axis)) => {
                assert!(close(f64::from(hits.distance[i]), t, 1e-4), "ray {i}: {} vs {t}", hits.distance[i]);
                assert_eq!(hits.instance[i], inst as i32, "ray {i}");
                let n = [hits.normal[3 * i], hits.normal[3 * i + 1], hits.normal[3 * i + 2]].map(f64::from);
                match axis {
                    Some(a) => {
                        on_box += 1;
                        assert_eq!(hits.class[i], 42, "class_override replaces the mesh's class");
                        // The face normal is ± the box axis `a` in the world; outward.
                        let axis_world = [r[0][a], r[1][a], r[2][a]];
                        assert!(dot(n, axis_world).abs() > 0.9999, "ray {i}: normal along the face axis");
                        let p = add(local_o, scale(local_d, t));
                        let outward = if p[a] > 0.0 { 1.0 } else { -1.0 };
                        assert!(dot(n, axis_world) * outward > 0.0, "outward normal");
                        assert_eq!(hits.backface[i], dot(n, di) > 0.0);
                        let inside = (0..3).all(|k| local_o[k].abs() < f64::from(h[k]));
                        assert_eq!(hits.backface[i], inside, "from inside the box the face is seen from behind");
                    }
                    None => {
                        on_sea += 1;
                        assert_eq!(hits.class[i], 1);
                        assert!(n[2] > 0.9999 && !hits.backface[i]);
                    }
                }
            }
            None => assert!(hits.distance[i].is_infinite(), "ray {i} should miss"),
        }
    }
    assert!(on_box > 500 && on_sea > 500, "{on_box} {on_sea}");

    // Moving the box moves its hits; a bad id leaves the scene as it was.
    let moved = RigidPose::from_xyz_rpy([20.0, 10.0, 30.0], [0.0; 3]);
    refuses("set_poses with an unknown id", "instance", || scene.set_poses(&[bi, 7], &[moved, moved]));
    refuses("set_poses with fewer poses", "poses", || scene.set_poses(&[bi], &[]));
    let down = [[20.0f32, 10.0, 50.0]];
    let dir = [[0.0f32, 0.0, -1.0]];
    let before = ok("cast", || scene.cast_rays(&down, &dir, 1e3));
    assert!((before.distance[0] - (50.0 - (4.0 + 0.75 * r[2][2].abs() as f32))).abs() < 0.3);
    ok("set_poses", || scene.set_poses(&[bi], &[moved]));
    let after = ok("cast", || scene.cast_rays(&down, &dir, 1e3));
    assert!((after.distance[0] - (50.0 - 30.75)).abs() < 1e-3, "{}", after.distance[0]);
    // The world mesh export at the current poses.
    let wm = scene.world_mesh();
    assert_eq!(wm.faces.len(), 14);
    assert_eq!(wm.vertices.len(), 12);
    assert_eq!(scene.num_world_triangles(), 14);
    assert!(wm.classes[..12].iter().all(|&c| c == 42) && wm.classes[12..].iter().all(|&c| c == 1));
}

#[test]
fn meshes_refuse_bad_geometry() {
    let v = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    refuses("no vertices", "vertices", || Mesh::new("m", &[], &[[0, 1, 2]], &[1]));
    refuses("no faces", "faces", || Mesh::new("m", &v, &[], &[1]));
    refuses("NaN vertex", "vertices[1]", || Mesh::new("m", &[v[0], [f32::NAN, 0.0, 0.0], v[2]], &[[0, 1, 2]], &[1]));
    refuses("inf vertex", "vertices[2]", || {
        Mesh::new("m", &[v[0], v[1], [0.0, f32::INFINITY, 0.0]], &[[0, 1, 2]], &[1])
    });
    refuses("face past the vertices", "faces[1]", || Mesh::new("m", &v, &[[0, 1, 2], [0, 1, 3]], &[1]));
    refuses("negative face index", "faces[0]", || Mesh::new("m", &v, &[[0, -1, 2]], &[1]));
    refuses("huge face index", "faces[0]", || Mesh::new("m", &v, &[[0, 1, i64::MAX]], &[1]));
    refuses("classes of the wrong length", "classes", || Mesh::new("m", &v, &[[0, 1, 2]], &[1, 2]));
    refuses("no classes", "classes", || Mesh::new("m", &v, &[[0, 1, 2]], &[]));
    let mesh = ok("mesh", || Mesh::new("m", &v, &[[0, 1, 2]], &[1]));
    refuses("materials of the wrong length", "materials", || mesh.clone().with_materials(&[1, 2]));
    // Vertices at the edge of f32 (finite, but their edges and normals overflow): built, and rays are answered
    // without a panic.
    let big = [[-3e38f32, -3e38, 0.0], [3e38, -3e38, 0.0], [0.0, 3e38, 0.0]];
    let built = guarded("mesh of huge vertices", || Mesh::new("big", &big, &[[0, 1, 2]], &[1]));
    if let Ok(m) = built {
        let mut s = Scene::new();
        let id = s.add_mesh(m);
        ok("instance", || s.add_instance(id, RigidPose::IDENTITY, None));
        let _ = guarded("cast into huge triangle", || s.cast_rays(&[[0.0, 0.0, 5.0]], &[[0.0, 0.0, -1.0]], 1e3));
    }
    // Degenerate faces (repeated or collinear vertices) are never hit: no hit at a NaN distance.
    let deg = ok("degenerate mesh", || {
        Mesh::new("deg", &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], &[[0, 1, 2], [0, 0, 1]], &[1])
    });
    let mut s = Scene::new();
    let id = s.add_mesh(deg);
    ok("instance", || s.add_instance(id, RigidPose::IDENTITY, None));
    let h = ok("cast at degenerate", || s.cast_rays(&[[1.0, 0.0, 3.0], [0.5, 0.0, -1.0]], &[[0.0, 0.0, -1.0]; 2], 1e3));
    assert!(h.distance.iter().all(|d| d.is_infinite()), "{:?}", h.distance);
}

#[test]
fn mesh_of_fewer_than_three_vertices_is_refused_as_documented() {
    // `Mesh::new` documents `V ≥ 3`.
    refuses("one vertex", "vertices", || Mesh::new("m", &[[0.0, 0.0, 0.0]], &[[0, 0, 0]], &[1]));
}

#[test]
fn scenes_refuse_bad_calls() {
    let mut scene = Scene::new();
    refuses("instance of an unknown mesh", "mesh", || scene.add_instance(0, RigidPose::IDENTITY, None));
    let m = scene.add_mesh(ok("box", || box_mesh("b", [1.0, 1.0, 1.0], 5)));
    let i = ok("instance", || scene.add_instance(m, RigidPose::IDENTITY, None));
    let o = [[0.0f32, 0.0, 10.0]];
    let d = [[0.0f32, 0.0, -1.0]];
    refuses("max_range 0", "max_range", || scene.cast_rays(&o, &d, 0.0));
    refuses("max_range < 0", "max_range", || scene.cast_rays(&o, &d, -5.0));
    refuses("max_range NaN", "max_range", || scene.cast_rays(&o, &d, f32::NAN));
    refuses("max_range -inf", "max_range", || scene.cast_rays(&o, &d, f32::NEG_INFINITY));
    let inf = ok("infinite range", || scene.cast_rays(&o, &d, f32::INFINITY));
    assert!((inf.distance[0] - 9.0).abs() < 1e-5);
    refuses("lengths differ", "directions", || scene.cast_rays(&o, &[], 10.0));
    refuses("NaN origin", "origins[0]", || scene.cast_rays(&[[f32::NAN, 0.0, 0.0]], &d, 10.0));
    refuses("zero direction", "directions[0]", || scene.cast_rays(&o, &[[0.0, 0.0, 0.0]], 10.0));
    refuses("inf direction", "directions[0]", || scene.cast_rays(&o, &[[f32::INFINITY, 0.0, 0.0]], 10.0));
    // The first bad ray of a big batch is the one named (batches are cast in parallel chunks).
    let mut many_o = vec![[0.0f32, 0.0, 10.0]; 5000];
    let many_d = vec![[0.0f32, 0.0, -1.0]; 5000];
    many_o[4321] = [0.0, f32::NAN, 0.0];
    many_o[4999] = [f32::NAN, 0.0, 0.0];
    refuses("bad ray 4321", "origins[4321]", || scene.cast_rays(&many_o, &many_d, 10.0));
    refuses("shadow rays, bad range", "max_range", || scene.occluded_rays(&o, &d, 0.0));
    refuses("shadow rays, zero direction", "directions[0]", || scene.occluded_rays(&o, &[[0.0; 3]], 10.0));
    refuses("targets, NaN origin", "origins[0]", || scene.cast_rays_to_targets(&[[f32::NAN; 3]], &d, 10.0));
    // Zero rays: an empty answer.
    let none = ok("zero rays", || scene.cast_rays(&[], &[], 10.0));
    assert!(none.is_empty());
    assert!(ok("zero shadow rays", || scene.occluded_rays(&[], &[], 10.0)).is_empty());
    // Tiny and huge (finite) directions are normalised exactly.
    let tiny = ok("tiny direction", || scene.cast_rays(&o, &[[0.0, 0.0, -1e-30]], 100.0));
    let big = ok("huge direction", || scene.cast_rays(&o, &[[0.0, 0.0, -1e30]], 100.0));
    assert!((tiny.distance[0] - 9.0).abs() < 1e-5 && (big.distance[0] - 9.0).abs() < 1e-5);
    // Single-ray queries answer NaN input with "no hit", never a panic.
    let nan_dir = Vec3::new(f32::NAN, 0.0, 0.0);
    assert!(guarded("cast_ray NaN", || scene.cast_ray(Vec3::ZERO, nan_dir, 10.0)).is_none());
    assert!(guarded("cast_ray negative range", || scene.cast_ray(Vec3::new(0.0, 0.0, 10.0), -Vec3::Z, -1.0)).is_none());
    // Sea, lights, materials.
    refuses("set_sea of an unknown instance", "instance", || scene.set_sea(9, &[]));
    refuses("set_sea, unknown moving id", "instance", || scene.set_sea(i, &[9]));
    refuses("set_sea on a box", "surface", || scene.set_sea(i, &[]));
    refuses("wave surface without a sea", "surface", || {
        let empty = ok("empty surface", || mmusv_core::sea::WaveSurface::new(&[], 0.0, 0.0, &[], Default::default()));
        scene.set_wave_surface(Some(empty))
    });
    refuses("lights of an unknown instance", "instance", || scene.set_lights(&[i, 3], true));
    assert_eq!(scene.material_index(-1, -1), 0);
    assert_eq!(scene.material_index(99, 0), 0);
    assert!(scene.material_of(i as i32, 0).is_none());
    let mut s2 = Scene::new();
    let with = ok("materials", || box_mesh("b", [1.0; 3], 5).and_then(|m| m.with_materials(&[3])));
    s2.add_mesh(with);
    refuses("material table too short", "materials", || s2.set_materials(vec![]));
}

#[test]
fn instances_refuse_non_rigid_or_non_finite_poses() {
    // `RigidPose`'s fields are public and `from_xyz_rpy` takes any f64: a scene must not take a NaN pose or a
    // scaled "rotation" (its rays are moved into the mesh frame by the transpose, which is only the inverse of a
    // rotation), or its hits are silently wrong.
    let mut scene = Scene::new();
    let m = scene.add_mesh(ok("box", || box_mesh("b", [1.0, 1.0, 1.0], 5)));
    let nan = RigidPose::from_xyz_rpy([0.0, f64::NAN, 0.0], [0.0; 3]);
    refuses("add_instance with a NaN pose", "pose", || scene.add_instance(m, nan, None));
    let nan_rot = RigidPose::from_xyz_rpy([0.0; 3], [f64::NAN, 0.0, 0.0]);
    refuses("add_instance with a NaN rotation", "pose", || scene.add_instance(m, nan_rot, None));
    let scaled = RigidPose { rotation: Mat3::from_diagonal(Vec3::splat(2.0)), translation: Vec3::ZERO };
    refuses("add_instance with a scaled rotation", "pose", || scene.add_instance(m, scaled, None));
    let i = ok("instance", || scene.add_instance(m, RigidPose::IDENTITY, None));
    refuses("set_poses with a NaN pose", "poses[0]", || scene.set_poses(&[i], &[nan]));
    let far = RigidPose::from_xyz_rpy([1e39, 0.0, 0.0], [0.0; 3]); // 1e39 m is infinite in f32
    refuses("set_poses with an infinite translation", "poses[0]", || scene.set_poses(&[i], &[far]));
    // The scene is unchanged by the refused calls.
    let h = ok("cast", || scene.cast_rays(&[[0.0, 0.0, 10.0]], &[[0.0, 0.0, -1.0]], 100.0));
    assert!((h.distance[0] - 9.0).abs() < 1e-5);
}

#[test]
fn materials_and_seabed_check_their_fields() {
    let good = [0.5, 0.5, 0.5, 0.4, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 180.0];
    let m = ok("material", || Material::from_row(0, &good));
    assert_eq!(m.base_color, [0.5; 3]);
    assert!(m.emits_towards(Vec3::X));
    for (k, v) in [(0, f32::NAN), (1, 1.5), (3, -0.1), (4, f32::INFINITY), (5, -1.0), (8, 0.5), (9, 200.0), (10, 0.0)] {
        let mut row = good;
        row[k] = v;
        refuses(&format!("material column {k} = {v}"), "materials[7]", || Material::from_row(7, &row));
    }
    // Seabed.
    let z = vec![-5.0f32; 6];
    let bed = ok("seabed", || Seabed::new(0.0, 0.0, 10.0, 3, 2, z.clone()));
    assert_eq!(bed.depth(5.0, 5.0, 0.0), Some(5.0));
    assert_eq!(bed.depth(-1.0, 5.0, 0.0), None);
    refuses("seabed NaN origin", "seabed.origin", || Seabed::new(f32::NAN, 0.0, 10.0, 3, 2, z.clone()));
    refuses("seabed zero spacing", "seabed.spacing", || Seabed::new(0.0, 0.0, 0.0, 3, 2, z.clone()));
    refuses("seabed negative spacing", "seabed.spacing", || Seabed::new(0.0, 0.0, -1.0, 3, 2, z.clone()));
    refuses("seabed too few", "seabed.heights", || Seabed::new(0.0, 0.0, 1.0, 1, 6, z.clone()));
    refuses("seabed wrong length", "seabed.heights", || Seabed::new(0.0, 0.0, 1.0, 2, 2, z.clone()));
    let mut zn = z.clone();
    zn[4] = f32::NAN;
    refuses("seabed NaN height", "seabed.heights[4]", || Seabed::new(0.0, 0.0, 1.0, 3, 2, zn));
}

#[test]
fn seabed_refuses_sizes_whose_product_overflows() {
    // nx · ny wraps to 4 in usize: the raster must be refused, not accepted and then read out of bounds.
    let nx = (usize::MAX / 2) + 3; // nx · 2 = usize::MAX + 5 ≡ 4 (mod 2^64)
    let res = guarded("Seabed::new overflowing size", || Seabed::new(0.0, 0.0, 1.0, nx, 2, vec![-1.0; 4]));
    if let Ok(bed) = res {
        let _ = guarded("Seabed::depth on the overflowing raster", || bed.depth(0.5, 0.5, 0.0));
        unreachable!("Seabed::new accepted nx = {nx}, ny = 2 with 4 heights");
    }
    refuses("Seabed::new overflowing size", "seabed.heights", || Seabed::new(0.0, 0.0, 1.0, nx, 2, vec![-1.0; 4]));
}
