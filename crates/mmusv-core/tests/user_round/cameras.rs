//! Cameras: pinhole projection and depth match an independent computation, the orthographic top view is
//! oriented as documented, and bad configurations are refused.

use super::common::{add, box_mesh, guarded, mat_vec, ok, pinhole, refuses, rpy_matrix, square_mesh, unit};
use mmusv_core::geometry::RigidPose;
use mmusv_core::scene::Scene;
use mmusv_core::sensors::camera::{Camera, CameraConfig, Projection};
use mmusv_core::sensors::shade::ShadeEnv;
use std::f64::consts::{FRAC_PI_2, PI};

#[test]
fn pinhole_camera_projects_a_known_point_and_measures_depth_along_the_axis() {
    let (w, h, hfov) = (64u32, 48u32, 1.2f64);
    let cam = ok("camera", || Camera::new(pinhole(w, h, hfov)));
    let f = f64::from(w) / (2.0 * (hfov / 2.0).tan());
    let (cx, cy) = (f64::from(w) / 2.0, f64::from(h) / 2.0);
    assert_eq!(cam.intrinsics(), Some([f, f, cx, cy]));
    let xyz = [5.0, -3.0, 2.0];
    let rpy = [0.0, 0.05, 0.4];
    let pose = RigidPose::from_xyz_rpy(xyz, rpy);
    let r = rpy_matrix(rpy);
    // world_rays: row-major, the ray through pixel centre (u + ½, v + ½): body (1, −x, −y) normalised.
    let (orig, dirs) = cam.world_rays(&pose);
    assert_eq!((orig.len(), dirs.len()), ((w * h) as usize, (w * h) as usize));
    for (i, d) in dirs.iter().enumerate() {
        let (u, v) = ((i as u32 % w) as f64 + 0.5, (i as u32 / w) as f64 + 0.5);
        let body = unit([1.0, -(u - cx) / f, -(v - cy) / f]);
        let want = mat_vec(&r, body);
        assert!((0..3).all(|k| (f64::from(d[k]) - want[k]).abs() < 1e-5), "pixel {i}");
        assert!((0..3).all(|k| (f64::from(orig[i][k]) - xyz[k]).abs() < 1e-5));
    }
    let some = ok("pixel_rays", || cam.pixel_rays(&pose, &[0, 77, (w * h - 1) as i64]));
    assert_eq!(some.1, vec![dirs[0], dirs[77], dirs[(w * h - 1) as usize]]);
    refuses("pixel past the image", "pixels[1]", || cam.pixel_rays(&pose, &[0, (w * h) as i64]));
    refuses("negative pixel", "pixels[0]", || cam.pixel_rays(&pose, &[-1]));

    // A small square facing the camera, centred on the ray of pixel (u0, v0) at D metres along the axis.
    let (u0, v0, depth) = (41u32, 13u32, 25.0f64);
    let body = [depth, -(f64::from(u0) + 0.5 - cx) / f * depth, -(f64::from(v0) + 0.5 - cy) / f * depth];
    let centre = add(mat_vec(&r, body), xyz);
    let mut scene = Scene::new();
    let sq = scene.add_mesh(ok("target", || square_mesh("target", 0.08, 10)));
    // The square's normal (+z local) along the camera's −x (facing it): rotate local z to body −x, then by R.
    let face_pose = {
        // Columns: local x → body y, local y → body z, local z → body −x (right-handed: y × z = x ⇒ ... ok).
        let cols = [mat_vec(&r, [0.0, 1.0, 0.0]), mat_vec(&r, [0.0, 0.0, 1.0]), mat_vec(&r, [1.0, 0.0, 0.0])];
        let mut m = [0.0; 16];
        for (j, c) in cols.iter().enumerate() {
            for i in 0..3 {
                m[i * 4 + j] = c[i];
            }
        }
        m[3] = centre[0];
        m[7] = centre[1];
        m[11] = centre[2];
        m[15] = 1.0;
        ok("face pose", || RigidPose::from_matrix_row_major(&m, "face"))
    };
    let target = ok("target instance", || scene.add_instance(sq, face_pose, None));
    let frame = ok("render", || cam.render(&scene, &pose, &ShadeEnv::default(), false, 1));
    assert_eq!((frame.width, frame.height), (w, h));
    assert_eq!(frame.depth.len(), (w * h) as usize);
    assert!(frame.rgb.is_empty() && frame.radiance.is_empty());
    let at = (v0 * w + u0) as usize;
    assert_eq!(frame.instance[at], target as i32, "the target is seen at its projected pixel");
    assert_eq!(frame.semantic[at], 10);
    assert!((f64::from(frame.depth[at]) - depth).abs() < 1e-3, "depth along the axis: {}", frame.depth[at]);
    let seen: Vec<usize> = (0..frame.instance.len()).filter(|&i| frame.instance[i] == target as i32).collect();
    assert_eq!(seen, vec![at], "the 16 cm square covers only its own pixel centre");
    for i in 0..frame.instance.len() {
        if i != at {
            assert_eq!((frame.instance[i], frame.semantic[i]), (-1, 0));
            assert!(frame.depth[i].is_infinite() && frame.depth[i] > 0.0);
        }
    }
    // A wall perpendicular to the axis: depth (not distance) is the same at every pixel.
    let mut wall_scene = Scene::new();
    let wm = wall_scene.add_mesh(ok("wall", || square_mesh("wall", 500.0, 8)));
    let wall_pose = RigidPose::from_xyz_rpy([30.0, 0.0, 0.0], [0.0, -FRAC_PI_2, 0.0]);
    ok("wall instance", || wall_scene.add_instance(wm, wall_pose, None));
    let level = RigidPose::from_xyz_rpy([0.0, 0.0, 1.0], [0.0; 3]);
    let wall = ok("render wall", || cam.render(&wall_scene, &level, &ShadeEnv::default(), false, 1));
    assert!(wall.depth.iter().all(|d| (d - 30.0).abs() < 1e-3), "{:?}", &wall.depth[..4]);
    assert!(wall.semantic.iter().all(|&c| c == 8));
}

#[test]
fn orthographic_top_view_puts_forward_at_the_top() {
    let cfg = CameraConfig {
        width: 32,
        height: 32,
        projection: Projection::Orthographic { metres_per_pixel: 1.0 },
        range_max: 500.0,
        image: Default::default(),
    };
    let cam = ok("top view", || Camera::new(cfg));
    assert_eq!(cam.intrinsics(), None);
    let mut scene = Scene::new();
    let b = scene.add_mesh(ok("box", || box_mesh("b", [0.4, 0.4, 0.5], 10)));
    // A target 5.5 m ahead (+x) of a vessel facing +x, 3.5 m to its left (+y).
    ok("target", || scene.add_instance(b, RigidPose::from_xyz_rpy([5.5, 3.5, 0.5], [0.0; 3]), None));
    let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 100.0], [0.0, FRAC_PI_2, 0.0]);
    let frame = ok("render top", || cam.render(&scene, &pose, &ShadeEnv::default(), false, 1));
    let hit: Vec<usize> = (0..frame.instance.len()).filter(|&i| frame.instance[i] == 0).collect();
    assert_eq!(hit.len(), 1, "a 0.8 m box at 1 m/px covers one pixel centre: {hit:?}");
    let (u, v) = (hit[0] % 32, hit[0] / 32);
    // Row v sees body z = (H/2 − (v + ½))·m = world x; column u sees body y = (W/2 − (u + ½))·m = world y.
    assert_eq!((u, v), (12, 10));
    assert!((frame.depth[hit[0]] - 99.0).abs() < 1e-3, "depth along the axis: {}", frame.depth[hit[0]]);
}

#[test]
fn cameras_refuse_bad_configs() {
    let base = pinhole(16, 8, 1.0);
    let cases: Vec<(&str, CameraConfig, &str)> = vec![
        ("zero width", CameraConfig { width: 0, ..base }, "camera.resolution"),
        ("zero height", CameraConfig { height: 0, ..base }, "camera.resolution"),
        ("huge width", CameraConfig { width: u32::MAX, ..base }, "camera.resolution"),
        ("hfov 0", CameraConfig { projection: Projection::Pinhole { hfov: 0.0 }, ..base }, "camera.hfov_deg"),
        ("hfov π", CameraConfig { projection: Projection::Pinhole { hfov: PI }, ..base }, "camera.hfov_deg"),
        ("hfov NaN", CameraConfig { projection: Projection::Pinhole { hfov: f64::NAN }, ..base }, "camera.hfov_deg"),
        ("hfov < 0", CameraConfig { projection: Projection::Pinhole { hfov: -1.0 }, ..base }, "camera.hfov_deg"),
        ("range 0", CameraConfig { range_max: 0.0, ..base }, "camera.range_m"),
        ("range < 0", CameraConfig { range_max: -3.0, ..base }, "camera.range_m"),
        ("range NaN", CameraConfig { range_max: f32::NAN, ..base }, "camera.range_m"),
        (
            "ortho 0 m/px",
            CameraConfig { projection: Projection::Orthographic { metres_per_pixel: 0.0 }, ..base },
            "camera.metres_per_pixel",
        ),
        (
            "ortho NaN m/px",
            CameraConfig { projection: Projection::Orthographic { metres_per_pixel: f64::NAN }, ..base },
            "camera.metres_per_pixel",
        ),
        (
            "ortho inf m/px",
            CameraConfig { projection: Projection::Orthographic { metres_per_pixel: f64::INFINITY }, ..base },
            "camera.metres_per_pixel",
        ),
    ];
    for (what, cfg, field) in cases {
        refuses(what, field, || Camera::new(cfg));
    }
    // Infinite range is documented as allowed.
    assert!(guarded("infinite range", || Camera::new(CameraConfig { range_max: f32::INFINITY, ..base })).is_ok());
}

#[test]
fn orthographic_scale_beyond_f32_is_refused_at_construction() {
    // 1e39 m/px is finite in f64 but its pixel offsets are infinite in the f32 scene: refused up front, naming
    // the scale, rather than failing every render on `origins[...]`.
    let cfg = CameraConfig {
        width: 4,
        height: 4,
        projection: Projection::Orthographic { metres_per_pixel: 1e39 },
        range_max: 10.0,
        image: Default::default(),
    };
    refuses("ortho 1e39 m/px", "camera.metres_per_pixel", || Camera::new(cfg));
}
