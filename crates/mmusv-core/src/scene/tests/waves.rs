//! Tests of the scene over a displaced wave surface: every batch against a ray-by-ray reference, the radar's
//! target casts against the full cast, and a camera's rasterised water hits against its rays cast one by one.

use super::*;

/// Appends 4,000 grazing rays from among the crests (1.7–5.7 m up, −0.08 to 0.03 rad), as a low USV's sensors
/// cast them.
fn grazing_rays(rng: &mut ChaCha8Rng, o: &mut Vec<[f32; 3]>, d: &mut Vec<[f32; 3]>) {
    for k in 0..4000 {
        let az: f32 = rng.random_range(0.0..std::f32::consts::TAU);
        let el: f32 = rng.random_range(-0.08..0.03);
        o.push([rng.random_range(-200.0..200.0), rng.random_range(-200.0..200.0), 1.7 + 0.001 * k as f32]);
        d.push([az.cos() * el.cos(), az.sin() * el.cos(), el.sin()]);
    }
}

/// An irregular sea for the wave-surface tests: eight components, 12..80 m long, amplitudes summing to 1.6 m.
fn wave_components() -> Vec<crate::ocean::WaveComponent> {
    (0..8)
        .map(|i| {
            let k = std::f64::consts::TAU / (12.0 + 9.5 * i as f64);
            let dir = 0.4 + 0.37 * i as f64;
            crate::sea::test_component(0.2, k * dir.cos(), k * dir.sin(), (9.81 * k).sqrt(), 1.3 * i as f64)
        })
        .collect()
}

/// With a wave surface, every batch (packets, the sea shortcuts lifted over the crests, horizons, the sun mask)
/// gives exactly the hits of a ray-by-ray reference: the closer of the surface's own intersection and the scene
/// traced without the flat sea mesh.
#[test]
fn wave_surface_batches_give_exactly_the_ray_by_ray_reference() {
    use crate::sea::{SurfaceSpec, WaveSurface};
    let (mut s, vessels) = sea_world();
    let mut rng = ChaCha8Rng::seed_from_u64(33);
    scatter(&mut s, &vessels, &mut rng, [0.3, 0.02, -0.03]);
    // The reference scene: no sea declared, the flat mesh moved out of every ray's reach.
    let mut reference = s.clone();
    reference
        .set_poses(&[1], &[RigidPose::from_xyz_rpy([0.0, 0.0, -5000.0], [0.0; 3])])
        .unwrap_or_else(|e| unreachable!("{e}"));
    s.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
    let foci = [[0.0f32, 0.0], [120.0, -80.0]];
    let spec = SurfaceSpec { radius_m: 400.0, taper_m: 80.0, ..SurfaceSpec::default() };
    let surface = WaveSurface::new(&wave_components(), 7.0, 0.0, &foci, spec).unwrap_or_else(|e| unreachable!("{e}"));
    let w = surface.clone();
    s.set_wave_surface(Some(surface)).unwrap_or_else(|e| unreachable!("{e}"));
    let (mut o, mut d) = sensor_rays(&mut rng, 12_000);
    grazing_rays(&mut rng, &mut o, &mut d);
    let limit = 800.0;
    let fast = s.cast_rays(&o, &d, limit).unwrap_or_default();
    let mut water = 0;
    for i in 0..o.len() {
        let u = unit_direction(&d[i]);
        let wh = if w.leaves(o[i], u) { None } else { w.intersect(o[i], u, limit) };
        let mh = reference.cast_ray(Vec3::from_array(o[i]), Vec3::from_array(u), limit);
        let (dist, inst) = match (wh, mh) {
            (Some(a), Some(b)) if b.distance < a.t => (b.distance, b.instance as i32),
            (Some(a), _) => (a.t, 1),
            (None, Some(b)) => (b.distance, b.instance as i32),
            (None, None) => (f32::INFINITY, NO_HIT),
        };
        assert_eq!((fast.distance[i], fast.instance[i]), (dist, inst), "ray {i}: {:?} {:?}", o[i], d[i]);
        if inst == 1 {
            water += 1;
            let n = w.piece_normal(fast.triangle[i] as u32);
            assert_eq!(&fast.normal[3 * i..3 * i + 3], &n, "ray {i}: the normal of the piece hit");
            assert_eq!(fast.class[i], s.hit_normal_class(&Hit { distance: 0.0, instance: 1, triangle: 0 }).1);
        }
    }
    assert!(water > 5000, "only {water} rays met the waves");
    // A fan of `n` rays from `eye` (azimuth step `az_step`, elevations spread over `el0 .. el0 + span` in the order
    // `k · mul mod n`), cast as one batch and checked ray by ray against the reference; each ray's unit direction,
    // wave distance and distance to the rest of the scene (infinite for none).
    let fan = |eye: [f32; 3], n: u32, az_step: f32, (el0, span, mul): (f32, f32, u32)| {
        let co = vec![eye; n as usize];
        let cd: Vec<[f32; 3]> = (0..n)
            .map(|k| {
                let (az, el) = (az_step * k as f32, el0 + span * ((k * mul) % n) as f32 / n as f32);
                [az.cos() * el.cos(), az.sin() * el.cos(), el.sin()]
            })
            .collect();
        let fast = s.cast_rays(&co, &cd, limit).unwrap_or_default();
        (0..co.len())
            .map(|i| {
                let u = unit_direction(&cd[i]);
                let t_w = if w.leaves(eye, u) { None } else { w.intersect(eye, u, limit) };
                let t_w = t_w.map_or(f32::INFINITY, |h| h.t);
                let t_m = reference
                    .cast_ray(Vec3::from_array(eye), Vec3::from_array(u), limit)
                    .map_or(f32::INFINITY, |h| h.distance);
                assert_eq!(fast.distance[i], t_w.min(t_m), "eye {eye:?}: ray {i} {u:?}");
                (u, t_w, t_m)
            })
            .collect::<Vec<_>>()
    };
    // One viewpoint (a camera above the crests, with its horizon) and one among them.
    for z in [6.0f32, 1.2] {
        fan([30.0f32, -20.0, z], 8192, 0.0008, (-0.3, 0.4, 37));
    }
    // Viewpoints among the crests (over the still level, under the crest bound: a low USV's camera or LiDAR at
    // sea) have horizons too, the crests among their columns; some of these rising rays meet the waves.
    let (mut rising, mut blocked, mut cleared) = (0, 0, 0);
    // Over open water (no vessel's box over them), 0.3-0.9 m above the water under them, under the crest bound.
    let over_vessel = |x: f32, y: f32| {
        vessels.iter().any(|&v| {
            let b = s.world_aabbs[v as usize];
            x >= b.mins.x - 1.0 && x <= b.maxs.x + 1.0 && y >= b.mins.y - 1.0 && y <= b.maxs.y + 1.0
        })
    };
    let eyes: Vec<[f32; 3]> = (0..400)
        .map(|k| {
            let (x, y) = (-150.0 + 7.3 * (k % 40) as f32, -120.0 + 23.9 * (k / 40) as f32);
            [x, y, w.height(x, y) + 0.3 + 0.6 * ((k * 7) % 10) as f32 / 10.0]
        })
        .filter(|e| e[2] > 0.05 && e[2] < w.zmax() - 0.1 && !over_vessel(e[0], e[1]))
        .step_by(9)
        .take(3)
        .collect();
    assert_eq!(eyes.len(), 3, "viewpoints among the crests");
    for eye in eyes {
        let z = eye[2];
        let Some(h) = s.horizon(eye) else { panic!("a viewpoint {z} m up among the crests has no horizon") };
        for (u, t_w, t_m) in fan(eye, 6144, 0.00103, (-0.02, 0.17, 53)) {
            if u[2] > 0.0 {
                rising += 1;
                blocked += usize::from(t_w < t_m);
                // Rising rays the horizon settles (the crests among its columns).
                cleared += usize::from(h.clear(u));
            }
        }
    }
    assert!(blocked > 100 && rising - blocked > 5000, "{blocked} of {rising} rising rays met the waves first");
    assert!(cleared > 1000, "the horizons settled only {cleared} of {rising} rising rays");
    // Shadow rays towards the sun from the wave surface (leaving the water: the waves do not shade them), from
    // just over the skin above it (the sun mask, lifted over the crests that shade them) and from above everything.
    let sun = [0.8f32, 0.3, 0.05];
    let su = unit_direction(&sun);
    let so: Vec<[f32; 3]> = o
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let z = match k % 3 {
                0 => w.height(p[0], p[1]) + 0.02,
                1 => w.height(p[0], p[1]) + crate::sea::SKIN_M + 0.05,
                _ => 150.0,
            };
            [p[0], p[1], z]
        })
        .collect();
    let sd = vec![sun; so.len()];
    let fast = s.occluded_rays(&so, &sd, 5000.0).unwrap_or_default();
    let mut by_waves = 0;
    for i in 0..so.len() {
        let wb = !w.leaves(so[i], su) && w.occludes(so[i], su, 5000.0);
        assert_eq!(w.leaves(so[i], su), i % 3 == 0, "shadow ray {i}");
        let mb =
            reference.occluded_with(Vec3::from_array(so[i]), Vec3::from_array(su), 5000.0, &mut Scratch::default());
        by_waves += usize::from(wb && !mb);
        assert_eq!(fast[i], wb || mb, "shadow ray {i} from {:?}", so[i]);
    }
    assert!(by_waves > 20, "only {by_waves} points shaded by the crests alone");
    // Clearing the sea clears the waves; setting waves without a sea is an error.
    s.clear_sea();
    assert!(s.wave_surface().is_none());
    assert!(s.set_wave_surface(Some(w)).is_err());
}

/// [`Scene::cast_rays_to_targets`] gives [`Scene::cast_rays`]'s hits with those on the sea turned into misses, bit
/// for bit, over the waves (the surface asked only whether it stops a ray first) and over the flat sea: rays of
/// every kind, grazing rays among the crests, and a radar-like fan from one point (with its horizon); some
/// rays must meet a target, and some a target the crests hide.
#[test]
fn target_casts_are_the_closest_hits_with_the_sea_left_out() {
    use crate::sea::{SurfaceSpec, WaveSurface};
    let (mut s, vessels) = sea_world();
    let mut rng = ChaCha8Rng::seed_from_u64(34);
    scatter(&mut s, &vessels, &mut rng, [0.3, 0.02, -0.03]);
    s.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
    let (mut o, mut d) = sensor_rays(&mut rng, 8_000);
    grazing_rays(&mut rng, &mut o, &mut d);
    // A radar's fan: one origin 6 m up, every azimuth, elevations crowded about the horizon.
    for k in 0..8192u32 {
        let az = std::f32::consts::TAU * k as f32 / 8192.0;
        let el = -0.17 + 0.2 * (((k * 37) % 64) as f32 / 64.0).powi(2);
        o.push([10.0, -15.0, 6.0]);
        d.push([az.cos() * el.cos(), az.sin() * el.cos(), el.sin()]);
    }
    let limit = 3000.0;
    let mut components = wave_components();
    components.iter_mut().for_each(|c| c.amplitude_m *= 4.0);
    let spec = SurfaceSpec { radius_m: 400.0, taper_m: 80.0, ..SurfaceSpec::default() };
    let surface = WaveSurface::new(&components, 7.0, 0.0, &[[0.0, 0.0], [120.0, -80.0]], spec)
        .unwrap_or_else(|e| unreachable!("{e}"));
    let mut cast = Vec::new();
    for surface in [Some(surface), None] {
        let waves = surface.is_some();
        s.set_wave_surface(surface).unwrap_or_else(|e| unreachable!("{e}"));
        let all = s.cast_rays(&o, &d, limit).unwrap_or_default();
        let targets = s.cast_rays_to_targets(&o, &d, limit).unwrap_or_default();
        let (mut seen, mut sea) = (0, 0);
        for i in 0..o.len() {
            if all.instance[i] == 1 {
                sea += 1;
                assert_eq!(
                    (targets.instance[i], targets.distance[i]),
                    (NO_HIT, f32::INFINITY),
                    "ray {i} (waves {waves})"
                );
                continue;
            }
            seen += usize::from(all.instance[i] != NO_HIT);
            let at = |h: &RayHits| {
                (
                    h.distance[i],
                    h.instance[i],
                    h.triangle[i],
                    h.class[i],
                    h.backface[i],
                    h.normal[3 * i..3 * i + 3].to_vec(),
                )
            };
            assert_eq!(at(&targets), at(&all), "ray {i} (waves {waves}): {:?} {:?}", o[i], d[i]);
        }
        assert!(seen > 1000 && sea > 5000, "waves {waves}: {seen} rays on targets, {sea} on the sea");
        cast.push(targets);
    }
    // Targets the crests hide: rays whose target the flat sea would leave in view.
    let (wavy, flat) = (&cast[0], &cast[1]);
    let hidden = (0..o.len()).filter(|&i| flat.instance[i] > 1 && wavy.instance[i] == NO_HIT).count();
    assert!(hidden > 50, "only {hidden} targets hidden by the crests");
}

/// A pinhole camera over the waves rasterises its water hits ([`crate::sea::WaveSurface::first_hits`]): its depth
/// and instances are those of the same pixel rays cast ray by ray (marched through the waves), vessels in front
/// of the water included.
#[test]
fn a_camera_over_the_waves_sees_the_marched_hits() {
    use crate::sea::{SurfaceSpec, WaveSurface};
    use crate::sensors::camera::{Camera, CameraConfig, Projection};
    let (mut s, vessels) = sea_world();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    scatter(&mut s, &vessels, &mut rng, [0.3, 0.02, -0.03]);
    s.set_sea(1, &vessels).unwrap_or_else(|e| unreachable!("{e}"));
    let foci = [[0.0f32, 0.0], [120.0, -80.0]];
    let spec = SurfaceSpec { radius_m: 400.0, taper_m: 80.0, ..SurfaceSpec::default() };
    s.set_wave_surface(Some(
        WaveSurface::new(&wave_components(), 7.0, 0.0, &foci, spec).unwrap_or_else(|e| unreachable!("{e}")),
    ))
    .unwrap_or_else(|e| unreachable!("{e}"));
    let cfg = CameraConfig {
        width: 200,
        height: 150,
        projection: Projection::Pinhole { hfov: 1.6 },
        range_max: 900.0,
        image: Default::default(),
    };
    let cam = Camera::new(cfg).unwrap_or_else(|e| unreachable!("{e}"));
    let (mut water, mut differ, mut vessel_px) = (0, 0, 0);
    for (k, pose) in [
        RigidPose::from_xyz_rpy([2.0, 1.0, 3.5], [0.02, 0.05, 0.4]),
        RigidPose::from_xyz_rpy([110.0, -70.0, 8.0], [0.0, 0.3, 2.6]),
        RigidPose::from_xyz_rpy([-60.0, 40.0, 2.5], [-0.04, -0.02, -1.9]),
    ]
    .iter()
    .enumerate()
    {
        let frame = cam.render(&s, pose, &crate::sensors::shade::ShadeEnv::default(), false, 1).unwrap_or_default();
        let (o, d) = cam.world_rays(pose);
        let marched = s.cast_rays(&o, &d, cfg.range_max).unwrap_or_default();
        let axis = pose.transform_vector(Vec3::X);
        for i in 0..o.len() {
            let (mut t, mut instance) = (marched.distance[i], marched.instance[i]);
            if !t.is_finite() {
                // Past the range, a ray going down meets the still water (`Scene::sea_beyond`).
                if let Some((sea, beyond)) = s.sea_beyond().and_then(|b| Some((b.instance, b.meet(o[i], d[i])?))) {
                    (t, instance) = (beyond, sea);
                }
            }
            let depth = if t.is_finite() { t * Vec3::from_array(d[i]).dot(axis) } else { f32::INFINITY };
            let same = frame.instance[i] == instance
                && (depth == frame.depth[i] || (depth - frame.depth[i]).abs() <= 1e-4 * depth);
            if !same {
                differ += 1;
                assert!(
                    instance == 1 && frame.instance[i] == 1,
                    "view {k} pixel {i}: marched {} at {depth}, rasterised {} at {}",
                    instance,
                    frame.instance[i],
                    frame.depth[i]
                );
            }
            water += usize::from(marched.instance[i] == 1);
            vessel_px += usize::from(vessels.contains(&(marched.instance[i] as u32)));
        }
    }
    assert!(water > 30_000 && vessel_px > 500, "{water} water pixels, {vessel_px} vessel pixels");
    assert_eq!(differ, 0, "{differ} of {water} water pixels differ");
}
