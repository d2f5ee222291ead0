//! Unit tests of the parent module (`shade.rs`).

use super::brdf::{fresnel_dielectric, specular_cos};
use super::*;

fn hit(class: u16, material: u16) -> SurfaceHit {
    SurfaceHit {
        t: 10.0,
        point: Vec3::ZERO,
        normal: Vec3::Z,
        class,
        instance: 0,
        material,
        lights_on: false,
        shading_normal: Vec3::Z,
        unresolved_mss: 0.0,
        sky_visibility: [1.0; 2],
    }
}

/// A rough grey dielectric: base colour 0.5, roughness 1 (nearly Lambertian), no emission.
fn rough_grey() -> Material {
    Material {
        base_color: [0.5; 3],
        roughness: 1.0,
        metallic: 0.0,
        emissive: [0.0; 3],
        nav_light: false,
        arc_deg: [0.0, 180.0],
    }
}

/// A table whose material 1 is `m`.
fn table(m: Material) -> Arc<Vec<Material>> {
    Arc::new(vec![m, m])
}

#[test]
fn lambert_plane_under_the_sun_is_albedo_times_irradiance_over_pi() {
    let env = ShadeEnv { fog_extinction_per_m: 0.0, ..ShadeEnv::default() };
    let sh = Shader::new(&env, 1, &[]).with_materials(table(rough_grey()));
    // The specular part of a rough dielectric is small; compare the diffuse share in closed form.
    let lit = sh.surface(-Vec3::Z, &hit(2, 1), true);
    let dark = sh.surface(-Vec3::Z, &hit(2, 1), false);
    let sun = sh.sun();
    let want = sh.sun_e * (0.5 / std::f32::consts::PI * sun.z);
    let got = lit - dark;
    let spec = specular_cos(Vec3::Z, Vec3::Z, sun, 1.0, Vec3::splat(0.04)) * sh.sun_e;
    assert!(((got - spec) - want).length() < 1e-3 * want.length(), "{got} {want}");
    // Shadowed: only the environment, which for the up normal is the sky's irradiance.
    let e = sh.lighting().irradiance(Vec3::Z);
    assert!((dark.y - 0.5 / std::f32::consts::PI * e.y).abs() < 0.05 * dark.y, "{dark} {e}");
}

#[test]
fn nav_lights_glow_only_when_on_and_fog_veils() {
    let env = ShadeEnv { sun_direction: [0.0, 0.9, -0.436], ..ShadeEnv::default() };
    let lamp = Material {
        base_color: [0.8, 0.1, 0.1],
        roughness: 0.3,
        metallic: 0.0,
        emissive: [2e4, 0.0, 0.0],
        nav_light: true,
        arc_deg: [56.25, 56.25],
    };
    let sh = Shader::new(&env, 1, &[]).with_materials(table(lamp));
    let off = sh.surface(-Vec3::X, &SurfaceHit { normal: Vec3::X, ..hit(10, 1) }, false);
    let on = sh.surface(-Vec3::X, &SurfaceHit { normal: Vec3::X, lights_on: true, ..hit(10, 1) }, false);
    assert!(on.x > 1e4 && off.x < 10.0, "{on} {off}");
    let foggy = Shader::new(&ShadeEnv { fog_extinction_per_m: 0.01, ..ShadeEnv::default() }, 1, &[]);
    let far = foggy.shade(-Vec3::X, Some(&SurfaceHit { t: 5000.0, normal: Vec3::X, ..hit(2, 0) }), true, None);
    let air = foggy.air_light(-Vec3::X);
    assert!((far - air).length() < 1e-3 * air.length());
}

#[test]
fn water_reflects_by_fresnel() {
    let env = ShadeEnv { wave_height_m: 0.0, wind_speed_m_s: 0.0, ..ShadeEnv::default() };
    let sh = Shader::new(&env, 1, &[]);
    let w = sh.with_swell(-Vec3::Z, hit(1, 0));
    // Looking straight down (no glint: the sun is not behind the camera) the reflected radiance is weighted
    // by F(0) = 0.02; at grazing incidence by much more.
    let bright = Vec3::splat(1000.0);
    let down = sh.water(-Vec3::Z, &w, false, Some(bright)) - sh.water(-Vec3::Z, &w, false, Some(Vec3::ZERO));
    let n = w.shading_normal;
    let f = fresnel_dielectric(n.dot(Vec3::Z), WATER_IOR);
    assert!((down.x - 1000.0 * f).abs() < 0.01, "{down} {f}");
    let g = Vec3::new(1.0, 0.0, -0.05).normalize();
    let wg = sh.with_swell(g, hit(1, 0));
    let graze = sh.water(g, &wg, false, Some(bright)) - sh.water(g, &wg, false, Some(Vec3::ZERO));
    assert!(graze.x > 5.0 * down.x);
}

#[test]
fn the_sky_and_the_ground_a_mesh_hides_scale_their_own_light() {
    // A rough grey wall and floor in the shade (no sun, no emission): the environment's light alone. Each part of
    // the hemisphere scales its own irradiance: the floor (normal up) sees no ground, so V_ground does nothing to
    // it; a face looking straight down sees no sky, so V_sky does nothing to its diffuse light; with both parts
    // hidden nothing is left (the specular too: its occlusion is 0 when V is); with neither, the shading of before.
    let env = ShadeEnv { fog_extinction_per_m: 0.0, ground_albedo: 0.3, ..ShadeEnv::default() };
    let sh = Shader::new(&env, 1, &[]).with_materials(table(rough_grey()));
    let shade = |n: Vec3, v: [f32; 2]| {
        let h = SurfaceHit { normal: n, shading_normal: n, sky_visibility: v, ..hit(2, 1) };
        sh.surface(-n, &h, false)
    };
    let up = Vec3::Z;
    assert_eq!(shade(up, [0.4, 0.0]), shade(up, [0.4, 1.0]));
    assert!(shade(up, [0.4, 1.0]).y < 0.5 * shade(up, [1.0, 1.0]).y);
    let side = Vec3::X;
    let both = shade(side, [1.0, 1.0]);
    assert_eq!(shade(side, [0.0, 0.0]), Vec3::ZERO);
    // The wall's diffuse light splits into the sky's and the ground's parts, each scaled by its own share; its
    // specular light (seen along its normal, the lobe leans into neither part: the sky's share counts) goes with
    // the sky's.
    let e = sh.lighting().irradiance(side);
    let g = sh.lighting().ground_irradiance(side);
    assert!(g.y > 0.0 && g.y < e.y, "{g} {e}");
    let diffuse = Vec3::splat(0.5 / std::f32::consts::PI);
    let specular = both - diffuse * e;
    assert!(specular.y > 0.0 && specular.y < 0.1 * both.y, "{specular}");
    let no_ground = shade(side, [1.0, 0.0]);
    let no_sky = shade(side, [0.0, 1.0]);
    assert!((no_ground - (diffuse * (e - g) + specular)).length() < 1e-3 * both.length(), "{no_ground}");
    assert!((no_sky - diffuse * g).length() < 1e-3 * both.length(), "{no_sky}");
    let down = -Vec3::Z;
    let d_sky = shade(down, [0.0, 1.0]) - shade(down, [1.0, 1.0]);
    assert!(d_sky.length() < 1e-3 * shade(down, [1.0, 1.0]).length(), "{d_sky}");
}
