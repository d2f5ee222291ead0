//! One frame of every sensor of every USV in one call: the sensors run as tasks over rayon on one frozen
//! [`Scene`] state, each with its own pose and seed, so no core waits while another sensor finishes.
//!
//! Every task calls exactly the function a single-sensor call uses ([`Lidar::scan`], [`Camera::render`],
//! [`radar_sweep`] then [`ppi_image`]) with the same arguments, and every sensor draws its randomness from
//! counter-based streams ([`super::noise`]), so a batch gives bit-identical outputs to the calls one by one,
//! whatever the thread scheduling. Outputs come back in task order.
//!
//! Each result also carries the wall time its task took (start to end of that sensor's work while it shares the
//! cores with the other tasks), for profiling only: nothing that is recorded depends on it.

use super::camera::{Camera, CameraFrame, RenderOptions};
use super::lidar::{Lidar, LidarEnv, LidarScan};
use super::ppi::{ppi_image, PpiConfig};
use super::radar::{radar_sweep, RadarConfig, RadarEnv, RadarReturns};
use super::shade::wake::Wake;
use super::shade::ShadeEnv;
use crate::error::Result;
use crate::geometry::RigidPose;
use crate::scene::Scene;
use crate::sky_visibility::SkyVisibility;
use rayon::prelude::*;
use std::time::Instant;

/// What the LiDAR takes of the environment: the air's extinction (fog and rain, from the visibility), waves,
/// wind and the rain rate (the drops that return).
pub fn lidar_env(env: &ShadeEnv) -> LidarEnv {
    LidarEnv {
        fog_extinction_per_m: env.fog_extinction_per_m,
        wave_height_m: env.wave_height_m,
        wind_speed_m_s: env.wind_speed_m_s,
        rain_mm_per_h: env.rain_mm_per_h,
    }
}

/// What the radar takes of the environment: waves and rain.
pub fn radar_env(env: &ShadeEnv) -> RadarEnv {
    RadarEnv { wave_height_m: env.wave_height_m, rain_mm_per_h: env.rain_mm_per_h }
}

/// A PPI to draw from a sweep's returns: size, scale and orientation, and the sensor's world yaw (radians,
/// used by north-up).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PpiRequest {
    /// The image's size, scale and orientation.
    pub config: PpiConfig,
    /// World yaw of the sensor's forward axis, radians.
    pub sensor_yaw: f32,
}

/// One sensor of one USV at one frame: the configured sensor, its pose (sensor → world) and its seed.
#[derive(Debug, Clone, Copy)]
pub enum SensorTask<'a> {
    /// A LiDAR sweep ([`Lidar::scan_with_wakes`], with the frame's wakes).
    Lidar {
        /// The LiDAR.
        lidar: &'a Lidar,
        /// LiDAR → world.
        pose: RigidPose,
        /// Noise, dropout and water-return seed.
        seed: u64,
    },
    /// A camera image set ([`Camera::render_with`], with the frame's wakes, no linear radiance), shaded RGB when
    /// `rgb`.
    Camera {
        /// The camera (pinhole or orthographic).
        camera: &'a Camera,
        /// Whether to shade RGB.
        rgb: bool,
        /// Camera body → world.
        pose: RigidPose,
        /// Seed of the swell, rain streaks, anti-aliasing jitter, glossy reflection directions and sensor noise
        /// ([`Camera::render_with`]).
        seed: u64,
    },
    /// A radar revolution ([`radar_sweep`]) and, when asked, its PPI ([`ppi_image`]).
    Radar {
        /// The radar's configuration.
        radar: &'a RadarConfig,
        /// Sensor → world.
        pose: RigidPose,
        /// Clutter and range-noise seed.
        seed: u64,
        /// The PPI to draw from the returns, if any.
        ppi: Option<PpiRequest>,
    },
}

/// The output of one [`SensorTask`].
#[derive(Debug, Clone, PartialEq)]
pub enum SensorOutput {
    /// A LiDAR sweep.
    Lidar(LidarScan),
    /// A camera image set.
    Camera(CameraFrame),
    /// A radar sweep and its PPI (`size_px²` float32, row-major) when one was asked for.
    Radar {
        /// The returns.
        returns: RadarReturns,
        /// The PPI image.
        ppi: Option<Vec<f32>>,
    },
}

/// One task's output and the wall seconds it took (the PPI timed apart from the radar sweep).
#[derive(Debug, Clone, PartialEq)]
pub struct TaskResult {
    /// What the sensor produced.
    pub output: SensorOutput,
    /// Wall seconds of the sensor's work (for a radar: the sweep), for profiling only.
    pub seconds: f64,
    /// Wall seconds of the PPI (0 when none), for profiling only.
    pub ppi_seconds: f64,
}

/// Runs one task on the frozen `scene`, with `wakes` behind the vessels under way (cameras and LiDARs).
pub fn run_task(scene: &Scene, env: &ShadeEnv, wakes: &[Wake], task: &SensorTask<'_>) -> Result<TaskResult> {
    let start = Instant::now();
    let (output, ppi_seconds) = match *task {
        SensorTask::Lidar { lidar, ref pose, seed } => {
            (SensorOutput::Lidar(lidar.scan_with_wakes(scene, pose, &lidar_env(env), seed, wakes)?), 0.0)
        }
        SensorTask::Camera { camera, rgb, ref pose, seed } => {
            let options = RenderOptions { rgb, radiance: false, seed, wakes };
            (SensorOutput::Camera(camera.render_with(scene, pose, env, &options)?), 0.0)
        }
        SensorTask::Radar { radar, ref pose, seed, ppi } => {
            let returns = radar_sweep(scene, pose, radar, &radar_env(env), seed)?;
            let swept = Instant::now();
            let image = match ppi {
                Some(req) => Some(ppi_image(&returns, &req.config, req.sensor_yaw, radar)?),
                None => None,
            };
            let ppi_seconds = if image.is_some() { swept.elapsed().as_secs_f64() } else { 0.0 };
            (SensorOutput::Radar { returns, ppi: image }, ppi_seconds)
        }
    };
    let seconds = start.elapsed().as_secs_f64() - ppi_seconds;
    Ok(TaskResult { output, seconds, ppi_seconds })
}

/// Runs every task of a frame concurrently on the current rayon pool (each sensor's own rays in parallel
/// inside its task) and returns the results in task order. The first error (in task order) is returned.
/// `wakes` are the vessels under way at this frame (their wakes in the cameras and the LiDARs' water returns).
pub fn capture_frame(
    scene: &Scene,
    env: &ShadeEnv,
    wakes: &[Wake],
    tasks: &[SensorTask<'_>],
) -> Result<Vec<TaskResult>> {
    // The meshes' sky visibility, baked here once (each mesh's samples in parallel) rather than by the first
    // cameras at once, each baking it.
    let shaded = |t: &SensorTask<'_>| match *t {
        SensorTask::Camera { camera, rgb, .. } => rgb && camera.config().image.quality.sky_visibility(),
        _ => false,
    };
    if tasks.iter().any(shaded) {
        SkyVisibility::prepare(scene);
    }
    tasks.par_iter().with_max_len(1).map(|task| run_task(scene, env, wakes, task)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo;
    use crate::sensors::camera::{CameraConfig, Projection};
    use crate::sensors::lidar::LidarConfig;
    use crate::sensors::ppi::PpiOrientation;
    use crate::sensors::rays::uniform_elevations;

    fn pose(x: f64, y: f64, z: f64, yaw: f64) -> Result<RigidPose> {
        let (s, c) = yaw.sin_cos();
        let m = [c, -s, 0.0, x, s, c, 0.0, y, 0.0, 0.0, 1.0, z, 0.0, 0.0, 0.0, 1.0];
        RigidPose::from_matrix_row_major(&m, "pose")
    }

    #[test]
    fn a_batch_equals_the_sensors_one_by_one() -> Result<()> {
        let scene =
            demo::maritime_demo(demo::DemoParams { terrain_cells: 64, vessels: 24, ..demo::DemoParams::default() })?
                .scene;
        let env = ShadeEnv { rain_mm_per_h: 4.0, wave_height_m: 1.25, ..ShadeEnv::default() };
        let lidar = Lidar::new(LidarConfig {
            elevations: uniform_elevations(16, -0.26, 0.26)?,
            azimuth_steps: 360,
            ..LidarConfig::default()
        })?;
        let pin = Camera::new(CameraConfig {
            width: 64,
            height: 48,
            projection: Projection::Pinhole { hfov: 1.5 },
            range_max: 2000.0,
            image: Default::default(),
        })?;
        let ortho = Camera::new(CameraConfig {
            width: 32,
            height: 32,
            projection: Projection::Orthographic { metres_per_pixel: 2.0 },
            range_max: 600.0,
            image: Default::default(),
        })?;
        let radar = RadarConfig { azimuth_bins: 128, rays_el: 4, range_max_m: 800.0, ..RadarConfig::tuning() };
        let ppi = PpiRequest {
            config: PpiConfig { size_px: 64, metres_per_pixel: 25.0, orientation: PpiOrientation::NorthUp },
            sensor_yaw: 0.4,
        };
        let (a, b) = (pose(-40.0, 10.0, 3.0, 0.4)?, pose(60.0, -30.0, 2.5, 2.0)?);
        let tasks = [
            SensorTask::Lidar { lidar: &lidar, pose: a, seed: 11 },
            SensorTask::Camera { camera: &pin, rgb: true, pose: a, seed: 12 },
            SensorTask::Camera { camera: &pin, rgb: false, pose: b, seed: 13 },
            SensorTask::Camera { camera: &ortho, rgb: true, pose: pose(0.0, 0.0, 300.0, 0.0)?, seed: 14 },
            SensorTask::Radar { radar: &radar, pose: b, seed: 15, ppi: Some(ppi) },
            SensorTask::Radar { radar: &radar, pose: a, seed: 16, ppi: None },
            SensorTask::Lidar { lidar: &lidar, pose: b, seed: 17 },
        ];
        let wakes = [Wake {
            x: 0.0,
            y: 0.0,
            heading: 0.3,
            speed: 9.0,
            length: 20.0,
            beam: 5.0,
            reach_m: f32::INFINITY,
            age_s: 0.0,
            goes_on: false,
            displacement_m3: 0.0,
        }];
        let batch = capture_frame(&scene, &env, &wakes, &tasks)?;
        assert_eq!(batch.len(), tasks.len());
        let one = |t: &SensorTask<'_>| -> Result<SensorOutput> {
            Ok(match *t {
                SensorTask::Lidar { lidar, ref pose, seed } => {
                    SensorOutput::Lidar(lidar.scan_with_wakes(&scene, pose, &lidar_env(&env), seed, &wakes)?)
                }
                SensorTask::Camera { camera, rgb, ref pose, seed } => {
                    let options = RenderOptions { rgb, radiance: false, seed, wakes: &wakes };
                    SensorOutput::Camera(camera.render_with(&scene, pose, &env, &options)?)
                }
                SensorTask::Radar { radar, ref pose, seed, ppi } => {
                    let returns = radar_sweep(&scene, pose, radar, &radar_env(&env), seed)?;
                    let ppi = ppi.map(|r| ppi_image(&returns, &r.config, r.sensor_yaw, radar)).transpose()?;
                    SensorOutput::Radar { returns, ppi }
                }
            })
        };
        for (t, got) in tasks.iter().zip(&batch) {
            let want = one(t)?;
            assert!(same_bits(&got.output, &want), "task {t:?} differs from its single call");
            assert!(got.seconds >= 0.0 && got.ppi_seconds >= 0.0);
        }
        // the scene is not empty: the LiDAR saw something and the radar's PPI has echoes
        let SensorOutput::Lidar(scan) = &batch[0].output else { unreachable!("task 0 is a LiDAR") };
        assert!(!scan.is_empty());
        let SensorOutput::Radar { ppi: Some(img), .. } = &batch[4].output else { unreachable!("task 4 has a PPI") };
        assert!(img.iter().any(|&v| v > 0.0));
        assert!(batch[5].ppi_seconds == 0.0);
        Ok(())
    }

    #[test]
    fn the_first_failing_task_is_reported() -> Result<()> {
        let scene =
            demo::maritime_demo(demo::DemoParams { terrain_cells: 64, vessels: 24, ..demo::DemoParams::default() })?
                .scene;
        let bad = RadarConfig { azimuth_bins: 0, ..RadarConfig::tuning() };
        let tasks = [SensorTask::Radar { radar: &bad, pose: pose(0.0, 0.0, 3.0, 0.0)?, seed: 1, ppi: None }];
        let err = capture_frame(&scene, &ShadeEnv::default(), &[], &tasks).err().map(|e| e.to_string());
        assert!(err.is_some_and(|e| e.contains("azimuth_bins")), "a bad radar config must fail with its field");
        Ok(())
    }

    /// Equality of the bit patterns (so `+inf` depths and `-0.0` compare as they are).
    fn same_bits(a: &SensorOutput, b: &SensorOutput) -> bool {
        fn f(x: &[f32]) -> Vec<u32> {
            x.iter().map(|v| v.to_bits()).collect()
        }
        match (a, b) {
            (SensorOutput::Lidar(x), SensorOutput::Lidar(y)) => {
                let flat = |s: &LidarScan| s.xyz.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
                flat(x) == flat(y)
                    && f(&x.range) == f(&y.range)
                    && f(&x.intensity) == f(&y.intensity)
                    && f(&x.azimuth) == f(&y.azimuth)
                    && (&x.ring, &x.class, &x.instance, &x.ray_index) == (&y.ring, &y.class, &y.instance, &y.ray_index)
            }
            (SensorOutput::Camera(x), SensorOutput::Camera(y)) => {
                f(&x.depth) == f(&y.depth)
                    && (x.width, x.height, &x.semantic, &x.instance, &x.rgb)
                        == (y.width, y.height, &y.semantic, &y.instance, &y.rgb)
            }
            (SensorOutput::Radar { returns: x, ppi: p }, SensorOutput::Radar { returns: y, ppi: q }) => {
                f(&x.range) == f(&y.range)
                    && f(&x.azimuth) == f(&y.azimuth)
                    && f(&x.elevation) == f(&y.elevation)
                    && f(&x.intensity) == f(&y.intensity)
                    && (&x.instance, &x.class) == (&y.instance, &y.class)
                    && p.as_deref().map(f) == q.as_deref().map(f)
            }
            _ => false,
        }
    }
}
