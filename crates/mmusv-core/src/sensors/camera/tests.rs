//! Unit tests of the parent module (`camera.rs`).

use super::*;
use crate::mesh::Mesh;

/// The pixel grid's anchors, in the camera's trace order, are the pixels at even rows and columns around
/// each pixel (by brute force over the whole image, odd sizes included), and its block is the even corner.
#[test]
fn anchors_are_the_even_pixels_around() {
    let cfg = CameraConfig {
        width: 7,
        height: 5,
        projection: Projection::Pinhole { hfov: 1.5 },
        range_max: 100.0,
        image: Default::default(),
    };
    let Ok(cam) = Camera::new(cfg) else { panic!("a valid camera") };
    let grid = cam.pixel_grid();
    for (k, &i) in cam.order.iter().enumerate() {
        let (x, y) = ((i % 7) as i64, (i / 7) as i64);
        let mut want: Vec<(i64, i64)> = Vec::new();
        for yy in [y - 1, y, y + 1] {
            for xx in [x - 1, x, x + 1] {
                if xx % 2 == 0 && yy % 2 == 0 && (xx - x).abs() + (yy - y).abs() == (x % 2) + (y % 2) {
                    want.push((xx, yy));
                }
            }
        }
        let inside = want.iter().all(|&(xx, yy)| (0..7).contains(&xx) && (0..5).contains(&yy));
        if (x % 2, y % 2) == (0, 0) || !inside {
            want.clear();
        }
        let (ids, m) = grid.anchors(k);
        let mut got: Vec<(i64, i64)> =
            ids[..m].iter().map(|&j| cam.order[j as usize]).map(|p| ((p % 7) as i64, (p / 7) as i64)).collect();
        got.sort_unstable();
        want.sort_unstable();
        assert_eq!(got, want, "pixel ({x}, {y})");
        let b = cam.order[grid.block(k)];
        assert_eq!(((b % 7) as i64, (b / 7) as i64), (x & !1, y & !1));
    }
}

fn ground_with_box() -> Scene {
    let mut s = Scene::new();
    let g = [[-500.0, -500.0, 0.0], [500.0, -500.0, 0.0], [500.0, 500.0, 0.0], [-500.0, 500.0, 0.0]];
    let gf = [[0i64, 1, 2], [0, 2, 3]];
    if let Ok(m) = Mesh::new("ground", &g, &gf, &[1, 1]) {
        let id = s.add_mesh(m);
        let _ = s.add_instance(id, RigidPose::IDENTITY, None);
    }
    // A 4 m cube centred at (20, 0, 2).
    let mut v = Vec::new();
    for i in 0..8 {
        v.push([18.0 + 4.0 * (i & 1) as f32, -2.0 + 4.0 * ((i >> 1) & 1) as f32, 4.0 * ((i >> 2) & 1) as f32]);
    }
    let f: Vec<[i64; 3]> = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    if let Ok(m) = Mesh::new("cube", &v, &f, &[10; 12]) {
        let id = s.add_mesh(m);
        let _ = s.add_instance(id, RigidPose::IDENTITY, None);
    }
    s
}

/// Open water and sky shared between anchors (below `high`) look like every pixel shaded: over open water, away
/// from the horizon's anti-aliased edge, standard's shared shading and reflections (traced once per 2 × 2 block,
/// then spread over the glossy lobe as high's are) stay within a few sRGB levels of high's per-pixel shading.
/// (Draft reflects the sky along each pixel's mirror direction without the lobe, so it is not compared.)
#[test]
fn shared_shading_matches_every_pixel_shaded() {
    let mut water = Scene::new();
    let g = [[-5e3, -5e3, 0.0], [5e3, -5e3, 0.0], [5e3, 5e3, 0.0], [-5e3, 5e3, 0.0]];
    if let Ok(m) = Mesh::new("water", &g, &[[0i64, 1, 2], [0, 2, 3]], &[1, 1]) {
        let id = water.add_mesh(m);
        let _ = water.add_instance(id, RigidPose::IDENTITY, None);
    }
    let (w, h) = (96usize, 64usize);
    let render = |quality: Quality| {
        let cfg = CameraConfig {
            width: w as u32,
            height: h as u32,
            projection: Projection::Pinhole { hfov: 1.5 },
            range_max: 1e4,
            image: ImageOptions { quality, ..Default::default() },
        };
        let cam = Camera::new(cfg).ok()?;
        let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 3.0], [0.0, 0.15, 0.3]);
        // A low sun ahead, so the frame holds a glint as well as smooth water and sky.
        let sun = Vec3::new(1.0, 0.25, 0.25).normalize().to_array();
        let env = ShadeEnv { sun_direction: sun, wave_height_m: 0.5, wind_speed_m_s: 4.0, ..ShadeEnv::default() };
        // The incident exposure, fixed: the glint ahead brings the highlight limit in, which reads each quality's
        // own anchors (their reflections traced per block or per pixel) and so would shift the two images' exposure
        // apart by a little; the shading is what is compared here.
        let k = crate::sensors::shade::Shader::new(&env, 3, &[]).exposure();
        let env = ShadeEnv { exposure_ev100: (1.0 / (1.2 * k)).log2(), ..env };
        let opts = RenderOptions { rgb: true, radiance: false, seed: 3, wakes: &[] };
        cam.render_with(&water, &pose, &env, &opts).ok()
    };
    let (Some(shared), Some(high)) = (render(Quality::Standard), render(Quality::High)) else {
        panic!("render failed")
    };
    let (mut compared, mut worst, mut sum) = (0usize, 0u8, 0u64);
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = y * w + x;
            let class = |j: usize| high.semantic[j];
            if [i - 1, i + 1, i - w, i + w].iter().any(|&j| class(j) != class(i)) {
                continue;
            }
            compared += 1;
            for c in 0..3 {
                let d = shared.rgb[3 * i + c].abs_diff(high.rgb[3 * i + c]);
                worst = worst.max(d);
                sum += d as u64;
            }
        }
    }
    assert!(compared > 5000, "{compared} pixels compared");
    let mean = sum as f64 / (3 * compared) as f64;
    assert!(mean < 0.1 && worst <= 10, "mean {mean:.3}, worst {worst} levels");
}

#[test]
fn pinhole_depth_is_along_the_axis() {
    let cam = Camera::new(CameraConfig {
        width: 64,
        height: 48,
        projection: Projection::Pinhole { hfov: 1.5 },
        range_max: 1e4,
        image: Default::default(),
    });
    let Ok(cam) = cam else { return };
    let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 2.0], [0.0, 0.0, 0.0]);
    let f = cam.render(&ground_with_box(), &pose, &ShadeEnv::default(), true, 1).unwrap_or_default();
    assert_eq!(f.rgb.len(), 64 * 48 * 3);
    // Centre pixel looks at the cube's face at x = 18: depth 18 m along the axis.
    let c = 24 * 64 + 32;
    assert!((f.depth[c] - 18.0).abs() < 1e-3, "depth {}", f.depth[c]);
    assert_eq!(f.semantic[c], 10);
    assert_eq!(f.instance[c], 1);
    // Top row sees the sky.
    assert_eq!(f.instance[0], -1);
    assert!(f.depth[0].is_infinite());
}

#[test]
fn orthographic_top_view_sees_the_cube_at_its_place() {
    let m = 0.5;
    let cam = Camera::new(CameraConfig {
        width: 200,
        height: 200,
        projection: Projection::Orthographic { metres_per_pixel: m },
        range_max: 1e4,
        image: Default::default(),
    });
    let Ok(cam) = cam else { return };
    // 100 m up, looking down (pitch +90°), forward = +x at the top of the image.
    let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 100.0], [0.0, std::f64::consts::FRAC_PI_2, 0.0]);
    let f = cam.render(&ground_with_box(), &pose, &ShadeEnv::default(), false, 1).unwrap_or_default();
    // World (20, 0) is 20 m ahead: row 100 - 40 = 60 (centre 59.5..60.5), column 100 (y = 0).
    let px = |u: usize, v: usize| v * 200 + u;
    assert_eq!(f.instance[px(100, 60)], 1);
    assert!((f.depth[px(100, 60)] - 96.0).abs() < 1e-3);
    // 4 m wide: 8 pixels; just outside is ground.
    assert_eq!(f.instance[px(100, 55)], 0);
    assert_eq!(f.instance[px(100, 65)], 0);
    assert_eq!(f.instance[px(105, 60)], 0);
    assert!(f.rgb.is_empty());
}

#[test]
fn pixel_rays_are_the_world_rays_of_those_pixels() {
    // Sizes with partial tiles at the right and bottom edges, both projections.
    for (w, h, projection) in [
        (13u32, 7u32, Projection::Pinhole { hfov: 1.2 }),
        (8, 8, Projection::Pinhole { hfov: 0.7 }),
        (9, 6, Projection::Orthographic { metres_per_pixel: 0.5 }),
    ] {
        let cam =
            Camera::new(CameraConfig { width: w, height: h, projection, range_max: 100.0, image: Default::default() });
        let Ok(cam) = cam else { panic!("camera {w}x{h}") };
        let pose = RigidPose::from_xyz_rpy([3.0, -2.0, 5.0], [0.1, 0.4, -0.7]);
        let (o, d) = cam.world_rays(&pose);
        let all: Vec<i64> = (0..(w * h) as i64).rev().collect();
        let Ok((po, pd)) = cam.pixel_rays(&pose, &all) else { panic!("pixel_rays {w}x{h}") };
        for (j, &p) in all.iter().enumerate() {
            assert_eq!(po[j], o[p as usize], "origin of pixel {p} ({w}x{h})");
            assert_eq!(pd[j], d[p as usize], "direction of pixel {p} ({w}x{h})");
        }
        let err = cam.pixel_rays(&pose, &[0, (w * h) as i64]).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(err.contains("pixels[1]"), "{err}");
        assert!(cam.pixel_rays(&pose, &[-1]).is_err());
    }
}

#[test]
fn bad_configs_name_the_field() {
    let bad = |c: CameraConfig| Camera::new(c).err().map(|e| e.to_string()).unwrap_or_default();
    let ok = CameraConfig {
        width: 8,
        height: 8,
        projection: Projection::Pinhole { hfov: 1.0 },
        range_max: 10.0,
        image: ImageOptions::default(),
    };
    assert!(bad(CameraConfig { projection: Projection::Pinhole { hfov: std::f64::consts::PI }, ..ok })
        .contains("camera.hfov_deg"));
    assert!(bad(CameraConfig { width: 0, ..ok }).contains("camera.resolution"));
    assert!(bad(CameraConfig { range_max: -1.0, ..ok }).contains("camera.range_m"));
    assert!(bad(CameraConfig { projection: Projection::Orthographic { metres_per_pixel: 0.0 }, ..ok })
        .contains("metres_per_pixel"));
    // Both sides allowed, but more pixels than an image may hold: refused before the rays are allocated (some
    // 40 GB at 16384 x 16384, which aborted in the allocator); the most allowed, a strip of a side, still builds.
    assert!(bad(CameraConfig { width: 4097, height: 4096, ..ok }).contains("camera.resolution"));
    let e = bad(CameraConfig { width: MAX_SIDE, height: MAX_SIDE, ..ok });
    assert!(e.contains("camera.resolution") && e.contains(&MAX_PIXELS.to_string()), "{e}");
    assert!(Camera::new(CameraConfig { width: MAX_SIDE, height: 2, ..ok }).is_ok());
}

/// Standard quality traces one water reflection per 2 × 2 block and reconstructs the others from the block
/// corners around each pixel: a cube's mirror image in calm water then stays close to high quality's (every
/// pixel traced), without the 2 × 2 steps that taking the nearest corner's value left along the reflected
/// outline (measured here on calm water's interior pixels against high: mean 0.520 sRGB levels, worst 92 with
/// the nearest corner's value; 0.292 and 55 with the corners' mean; 0.290 and 17 once the reflections were spread
/// over the glossy lobe, read back bilinearly from the corners' cells; 0.462 and 31 since their directions are drawn
/// from the lobe, on a grid of every pixel at high quality and every other one at standard).
#[test]
fn shared_reflections_are_reconstructed_from_the_corners_around() {
    let scene = ground_with_box();
    let (w, h) = (128usize, 96usize);
    let render = |quality: Quality| {
        let cfg = CameraConfig {
            width: w as u32,
            height: h as u32,
            projection: Projection::Pinhole { hfov: 1.0 },
            range_max: 1e4,
            image: ImageOptions { quality, ..Default::default() },
        };
        let cam = Camera::new(cfg).ok()?;
        let pose = RigidPose::from_xyz_rpy([0.0, 0.3, 1.5], [0.0, 0.08, 0.0]);
        let env = ShadeEnv { wave_height_m: 0.0, wind_speed_m_s: 0.0, ..ShadeEnv::default() };
        let opts = RenderOptions { rgb: true, radiance: false, seed: 3, wakes: &[] };
        cam.render_with(&scene, &pose, &env, &opts).ok()
    };
    let (Some(std), Some(high)) = (render(Quality::Standard), render(Quality::High)) else { panic!("render failed") };
    let (mut compared, mut worst, mut sum) = (0usize, 0u8, 0u64);
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = y * w + x;
            if [i, i - 1, i + 1, i - w, i + w].iter().any(|&j| high.semantic[j] != 1) {
                continue; // water away from any silhouette
            }
            compared += 1;
            for c in 0..3 {
                let d = std.rgb[3 * i + c].abs_diff(high.rgb[3 * i + c]);
                worst = worst.max(d);
                sum += d as u64;
            }
        }
    }
    let mean = sum as f64 / (3 * compared) as f64;
    assert!(compared > 3000, "{compared} pixels compared");
    // (The two draw their reflections' directions on different grids, every pixel and every other one: their
    // stratified draws differ by a little noise besides.)
    assert!(mean < 0.6 && worst <= 75, "mean {mean:.3}, worst {worst} levels");
}

#[test]
fn the_image_roll_is_the_cameras_roll_about_its_axis() {
    assert_eq!(super::image_roll(&RigidPose::from_xyz_rpy([1.0, 2.0, 3.0], [0.0, 0.0, 0.7])), 0.0);
    let rolled = super::image_roll(&RigidPose::from_xyz_rpy([0.0; 3], [0.2, 0.0, 0.4]));
    assert!((rolled + 0.2).abs() < 1e-5, "{rolled}");
    // Pitched down, the roll still reads as the roll.
    let pitched = super::image_roll(&RigidPose::from_xyz_rpy([0.0; 3], [0.1, 0.3, 0.0]));
    assert!((pitched + 0.1).abs() < 0.02, "{pitched}");
}

/// A pixel whose ray goes down to the sea but meets nothing within the camera's range is water in the semantic and
/// instance images (the sea's class and instance), at the still water's depth, as the RGB shades it; one that rises
/// is sky. Brute force over every pixel of a level camera 1.5 m up: its ray goes down exactly when the pixel's
/// centre lies below the image's centre row, and meets z = 0 at depth `1.5 fx / (v + ½ − cy)` along the axis.
/// Without a declared sea nothing changes.
#[test]
fn the_sea_beyond_the_range_is_water_not_sky() -> crate::error::Result<()> {
    let (w, h) = (64usize, 48usize);
    let hfov = 1.5f64;
    let cfg = CameraConfig {
        width: w as u32,
        height: h as u32,
        projection: Projection::Pinhole { hfov },
        range_max: 30.0,
        image: Default::default(),
    };
    let cam = Camera::new(cfg)?;
    let pose = RigidPose::from_xyz_rpy([0.0, 0.0, 1.5], [0.0, 0.0, 0.0]);
    let mut scene = ground_with_box();
    let plain = cam.render(&scene, &pose, &ShadeEnv::default(), false, 1)?;
    scene.set_sea(0, &[])?;
    let f = cam.render(&scene, &pose, &ShadeEnv::default(), false, 1)?;
    let fx = w as f64 / (2.0 * (0.5 * hfov).tan());
    let (mut beyond, mut within) = (0, 0);
    for v in 0..h {
        for u in 0..w {
            let i = v * w + u;
            let below = v as f64 + 0.5 - h as f64 / 2.0;
            if plain.depth[i].is_finite() {
                within += usize::from(below > 0.0);
                assert_eq!(f.depth[i].to_bits(), plain.depth[i].to_bits(), "depth of ({u}, {v})");
                assert_eq!((f.semantic[i], f.instance[i]), (plain.semantic[i], plain.instance[i]), "({u}, {v})");
            } else if below < 0.0 {
                assert_eq!((f.semantic[i], f.instance[i]), (0, -1), "sky at ({u}, {v})");
                assert!(f.depth[i] == f32::INFINITY, "sky's depth at ({u}, {v})");
            } else {
                beyond += 1;
                assert_eq!((plain.semantic[i], plain.instance[i]), (0, -1), "no sea declared: ({u}, {v})");
                assert_eq!((f.semantic[i], f.instance[i]), (1, 0), "the sea beyond the range at ({u}, {v})");
                let want = 1.5 * fx / below;
                let got = f64::from(f.depth[i]);
                assert!(want > 30.0 && (got - want).abs() < 1e-4 * want, "depth {got} at ({u}, {v}), want {want}");
            }
        }
    }
    assert!(beyond >= w && within > 10 * w, "{beyond} beyond the range, {within} within");
    Ok(())
}
