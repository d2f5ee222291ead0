//! The vessel motion's tests: routes travelled at speed, route ends, the paper's perturbation (Table I), the
//! physical response in a sea and its transients at a route's events, bad inputs.

use super::*;
use std::f64::consts::PI;

pub(super) fn straight_test_vessel(waypoints: &[[f64; 2]], end: EndBehaviour, speed: f64) -> VesselMotion {
    let route = Route::new(waypoints, end).unwrap_or_else(|e| unreachable!("{e}"));
    let params = VesselParams {
        speed_mps: speed,
        start_offset_m: 0.0,
        z_base_m: 0.0,
        dims: VesselDims { length_m: 10.0, beam_m: 4.0, height_m: 3.0 },
        amplitudes: BaseAmplitudes::default(),
        hull: REFERENCE_HULL,
    };
    VesselMotion::new(route, params, WaveSignals::from_seed(1, 0)).unwrap_or_else(|e| unreachable!("{e}"))
}

const CURVY: [[f64; 2]; 5] = [[0.0, 0.0], [60.0, 20.0], [80.0, 90.0], [10.0, 120.0], [-50.0, 60.0]];

fn ok<T>(r: Result<T>) -> T {
    r.unwrap_or_else(|e| unreachable!("{e}"))
}

fn vessel(end: EndBehaviour, speed: f64, dims: VesselDims, seed: u64, idx: u64) -> VesselMotion {
    let route = ok(Route::new(&CURVY, end));
    let params = VesselParams { speed_mps: speed, dims, z_base_m: 0.4, ..VesselParams::default() };
    ok(VesselMotion::new(route, params, WaveSignals::from_seed(seed, idx)))
}

fn hyp(a: [f64; 6], b: [f64; 6]) -> f64 {
    (b[0] - a[0]).hypot(b[1] - a[1])
}

#[test]
fn travelled_distance_is_speed_times_time() {
    for end in [EndBehaviour::Stop, EndBehaviour::Loop, EndBehaviour::PingPong] {
        let v = vessel(end, 4.0, VesselDims::REFERENCE, 1, 0);
        let len = v.route().length();
        let t_end = if end == EndBehaviour::Stop { 0.9 * len / 4.0 } else { 2.6 * len / 4.0 };
        let n = 100_000;
        let mut prev = ok(v.pose_at(0.0, &WaveSetting::W2));
        let mut acc = 0.0;
        for k in 1..=n {
            let p = ok(v.pose_at(t_end * k as f64 / n as f64, &WaveSetting::W2));
            acc += hyp(prev, p);
            prev = p;
        }
        let want = 4.0 * t_end;
        assert!(((acc - want) / want).abs() < 0.005, "{end:?}: {acc} vs {want}");
    }
}

#[test]
fn yaw_and_velocity_follow_the_motion() {
    for end in [EndBehaviour::Loop, EndBehaviour::PingPong] {
        let v = vessel(end, 3.0, VesselDims::REFERENCE, 2, 1);
        let w = WaveSetting::W1;
        let h = 1e-4;
        for k in 0..300 {
            let t = 0.7 + k as f64 * 0.77;
            let (a, b) = (ok(v.pose_at(t - h, &w)), ok(v.pose_at(t + h, &w)));
            if hyp(a, b) < 2.0 * h * 3.0 * 0.99 {
                continue; // straddles a ping-pong reversal
            }
            let yaw = ok(v.pose_at(t, &w))[5];
            let fd = (b[1] - a[1]).atan2(b[0] - a[0]);
            assert!(wrap_angle(fd - yaw).abs() < 1e-4, "{end:?} t={t}");
            let vel = ok(v.velocity_at(t, &w));
            for (i, want) in [(b[0] - a[0]) / (2.0 * h), (b[1] - a[1]) / (2.0 * h), (b[2] - a[2]) / (2.0 * h)]
                .into_iter()
                .enumerate()
            {
                assert!((vel[i] - want).abs() < 1e-4, "{end:?} t={t} axis {i}");
            }
        }
    }
}

#[test]
fn stop_rests_at_the_end_and_ping_pong_turns_round() {
    let w = WaveSetting::W0;
    let stop = vessel(EndBehaviour::Stop, 5.0, VesselDims::REFERENCE, 3, 0);
    let len = stop.route().length();
    let t_after = len / 5.0 + 10.0;
    let (p, q) = (ok(stop.pose_at(t_after, &w)), ok(stop.pose_at(t_after + 50.0, &w)));
    assert!(hyp(p, CURVY.map(|c| [c[0], c[1], 0.0, 0.0, 0.0, 0.0])[4]) < 1e-9);
    assert_eq!((p[0], p[1], p[5]), (q[0], q[1], q[5]));
    let vel = ok(stop.velocity_at(t_after, &w));
    assert_eq!((vel[0], vel[1]), (0.0, 0.0));

    let pp = vessel(EndBehaviour::PingPong, 5.0, VesselDims::REFERENCE, 3, 0);
    let s = 30.0;
    let (fwd, back) = (ok(pp.pose_at(s / 5.0, &w)), ok(pp.pose_at((2.0 * len - s) / 5.0, &w)));
    assert!(hyp(fwd, back) < 1e-6);
    assert!((wrap_angle(back[5] - fwd[5]).abs() - PI).abs() < 1e-9);
    let lp = vessel(EndBehaviour::Loop, 5.0, VesselDims::REFERENCE, 3, 0);
    let period = lp.route().length() / 5.0;
    let (a, b) = (ok(lp.pose_at(7.0, &w)), ok(lp.pose_at(7.0 + period, &w)));
    assert!(hyp(a, b) < 1e-6 && wrap_angle(a[5] - b[5]).abs() < 1e-9);
}

/// RMS of heave (mean removed per vessel), roll and pitch (degrees) over all vessels and frames.
fn rms(fleet: &Fleet, frames: usize, dt: f64) -> [f64; 3] {
    let times: Vec<f64> = (0..frames).map(|k| k as f64 * dt).collect();
    let poses = ok(fleet.poses_at_times(&times));
    let nv = fleet.len();
    let mut sums = [0.0; 3];
    for v in 0..nv {
        let mean_z = (0..frames).map(|k| poses[k * nv + v][2]).sum::<f64>() / frames as f64;
        for k in 0..frames {
            let p = poses[k * nv + v];
            sums[0] += (p[2] - mean_z).powi(2);
            sums[1] += p[3].to_degrees().powi(2);
            sums[2] += p[4].to_degrees().powi(2);
        }
    }
    sums.map(|s| (s / (frames * nv) as f64).sqrt())
}

fn fleet(dims: VesselDims, wave: WaveSetting, seed: u64) -> Fleet {
    Fleet::new((0..4).map(|i| vessel(EndBehaviour::Loop, 3.0, dims, seed, i)).collect(), wave)
}

#[test]
fn wave_rms_is_monotonic_linear_and_matches_table_one() {
    let table =
        [[0.0274, 0.2054, 0.0684], [0.0818, 0.6134, 0.2062], [0.1379, 1.0345, 0.3395], [0.1923, 1.4421, 0.4774]];
    let mut got = Vec::new();
    for (w, want) in WaveSetting::PRESETS.iter().zip(table) {
        let r = rms(&fleet(VesselDims::REFERENCE, *w, 7), 36_000, 0.1);
        eprintln!("{w}: heave {:.4} m, roll {:.4} deg, pitch {:.4} deg", r[0], r[1], r[2]);
        for axis in 0..3 {
            assert!((r[axis] / want[axis] - 1.0).abs() < 0.05, "{w} axis {axis}: {} vs {}", r[axis], want[axis]);
        }
        got.push(r);
    }
    let heights: Vec<f64> = WaveSetting::PRESETS.iter().map(WaveSetting::height_m).collect();
    for axis in 0..3 {
        let y: Vec<f64> = got.iter().map(|r| r[axis]).collect();
        assert!(y.windows(2).all(|p| p[1] > p[0]), "axis {axis} not monotonic: {y:?}");
        let n = y.len() as f64;
        let (mx, my) = (heights.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
        let sxy: f64 = heights.iter().zip(&y).map(|(x, y)| (x - mx) * (y - my)).sum();
        let sxx: f64 = heights.iter().map(|x| (x - mx).powi(2)).sum();
        let slope = sxy / sxx;
        let ss_res: f64 = heights.iter().zip(&y).map(|(x, y)| (y - my - slope * (x - mx)).powi(2)).sum();
        let ss_tot: f64 = y.iter().map(|y| (y - my).powi(2)).sum();
        assert!(1.0 - ss_res / ss_tot >= 0.99, "axis {axis}: R² too low");
    }
    // A free height in between behaves like the presets.
    let free = rms(&fleet(VesselDims::REFERENCE, ok(WaveSetting::from_height(2.0)), 7), 36_000, 0.1);
    assert!(free[0] > got[1][0] && free[0] < got[2][0]);
    let flat = rms(&fleet(VesselDims::REFERENCE, ok(WaveSetting::from_height(0.0)), 7), 100, 0.1);
    assert!(flat.iter().all(|r| *r < 1e-12), "{flat:?}");
}

#[test]
fn small_vessels_move_more_than_large_ships() {
    let small = VesselDims { length_m: 3.0, beam_m: 1.2, height_m: 1.0 };
    let ship = VesselDims { length_m: 300.0, beam_m: 48.0, height_m: 60.0 };
    let a = rms(&fleet(small, WaveSetting::W2, 5), 12_000, 0.1);
    let b = rms(&fleet(ship, WaveSetting::W2, 5), 12_000, 0.1);
    for axis in 0..3 {
        assert!(a[axis] > 10.0 * b[axis], "axis {axis}: {} vs {}", a[axis], b[axis]);
    }
}

#[test]
fn same_seed_same_poses_other_seed_other_phases() {
    let times: Vec<f64> = (0..500).map(|k| k as f64 * 0.2).collect();
    let a = ok(fleet(VesselDims::REFERENCE, WaveSetting::W3, 42).poses_at_times(&times));
    let b = ok(fleet(VesselDims::REFERENCE, WaveSetting::W3, 42).poses_at_times(&times));
    let bits = |p: &[[f64; 6]]| p.iter().flatten().map(|x| x.to_bits()).collect::<Vec<u64>>();
    assert_eq!(bits(&a), bits(&b));
    let c = ok(fleet(VesselDims::REFERENCE, WaveSetting::W3, 43).poses_at_times(&times));
    assert_ne!(bits(&a), bits(&c));
    // Same layout as calling poses_at at each time; vessels of one fleet differ from each other.
    let f = fleet(VesselDims::REFERENCE, WaveSetting::W3, 42);
    assert_eq!(ok(f.poses_at(times[17])), a[17 * 4..18 * 4].to_vec());
    assert_ne!(f.vessels()[0].signals(), f.vessels()[1].signals());
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let route = || ok(Route::new(&CURVY, EndBehaviour::Stop));
    let sig = WaveSignals::from_seed(0, 0);
    let field_of = |p: VesselParams| match VesselMotion::new(route(), p, sig) {
        Err(MmusvError::Config { field, .. }) => field,
        other => unreachable!("expected a config error, got {other:?}"),
    };
    assert_eq!(field_of(VesselParams { speed_mps: -1.0, ..VesselParams::default() }), "speed_mps");
    assert_eq!(field_of(VesselParams { speed_mps: f64::NAN, ..VesselParams::default() }), "speed_mps");
    assert_eq!(field_of(VesselParams { start_offset_m: 1e6, ..VesselParams::default() }), "start_offset_m");
    assert_eq!(field_of(VesselParams { z_base_m: f64::INFINITY, ..VesselParams::default() }), "z_base_m");
    assert!(matches!(Route::new(&[[0.0, 0.0]], EndBehaviour::Stop), Err(MmusvError::Config { .. })));
    assert!(matches!(Route::new(&[[0.0, 0.0], [f64::NAN, 0.0]], EndBehaviour::Stop), Err(MmusvError::Config { .. })));
    assert!(matches!("W9".parse::<WaveSetting>(), Err(MmusvError::Config { .. })));
    assert!(matches!(WaveSetting::from_height(-1.0), Err(MmusvError::Config { .. })));
    let f = fleet(VesselDims::REFERENCE, WaveSetting::W1, 1);
    for t in [-1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(f.poses_at(t), Err(MmusvError::InvalidInput { ref field, .. }) if field == "t"));
        assert!(matches!(f.velocities_at(t), Err(MmusvError::InvalidInput { .. })));
    }
    let err = f.poses_at_times(&[0.0, 1.0, -2.0]);
    assert!(matches!(err, Err(MmusvError::InvalidInput { ref field, .. }) if field == "times[2]"));
    assert_eq!(Fleet::new(Vec::new(), WaveSetting::W0).poses_at_times(&[1.0]).map(|v| v.len()), Ok(0));
}

#[test]
fn poses_at_times_refuses_more_than_max_poses_before_allocating() {
    // 4 vessels at MAX_POSES / 4 + 1 times: one pose too many (used to allocate T·V·48 bytes, unbounded).
    let f = fleet(VesselDims::REFERENCE, WaveSetting::W1, 1);
    let times = vec![0.0; MAX_POSES / 4 + 1];
    let err = f.poses_at_times(&times);
    assert!(matches!(err, Err(MmusvError::InvalidInput { ref field, .. }) if field == "times"), "{err:?}");
    assert_eq!(f.poses_at_times(&times[..2]).map(|v| v.len()), Ok(8));
}

#[test]
fn a_fleet_in_a_sea_moves_by_its_hulls_response() {
    use crate::ocean::{response::response, SeaSpec, WaveField};
    let sea = SeaSpec { hs: 2.5, tp: 8.0, gamma: 3.3, direction_rad: 0.5, spread_s: 10.0 };
    let field = Arc::new(ok(WaveField::new(&sea, 9)));
    let paper = fleet(VesselDims::REFERENCE, WaveSetting::W2, 4);
    let physical = paper.clone().with_sea(Arc::clone(&field));
    let t = 37.5;
    let (pp, pq) = (ok(paper.poses_at(t)), ok(physical.poses_at(t)));
    for (v, (a, b)) in paper.vessels().iter().zip(pp.iter().zip(&pq)) {
        // Same route position and heading; heave, roll, pitch from the RAOs at that place, through the memory of
        // the course (on this curving loop within a few per cent of the steady state of the moment's RMS scale).
        assert_eq!((a[0], a[1], a[5]), (b[0], b[1], b[5]));
        assert_eq!(ok(v.pose_in_sea(t, &field)), *b);
        let vel = ok(v.velocity_at(t, &WaveSetting::W2));
        let r = response(&field, &v.params().hull, b[0], b[1], b[5], vel[0], vel[1], t)[0];
        let scale = ok(crate::ocean::response_variance(&v.params().hull, &sea, b[5], 3.0)).map(f64::sqrt);
        for m in 0..3 {
            let got = [b[2] - v.params().z_base_m, b[3], b[4]][m];
            assert!((got - r[m]).abs() < 0.1 * scale[m], "{m} {got} {} {}", r[m], scale[m]);
        }
    }
    // Vertical velocity is the time derivative of the heave, the turning's change of the response included.
    let h = 1e-5;
    let (a, b) = (ok(physical.poses_at(t - h)), ok(physical.poses_at(t + h)));
    let vz = ok(physical.velocities_at(t));
    for i in 0..physical.len() {
        let fd = (b[i][2] - a[i][2]) / (2.0 * h);
        assert!((fd - vz[i][2]).abs() < 1e-5, "{fd} {}", vz[i][2]);
    }
    // The paper fleet is untouched by the existence of a sea.
    assert!(paper.sea().is_none() && physical.sea().is_some());
}

#[test]
fn the_physical_response_passes_smoothly_through_a_stop_and_a_turn_about() {
    use crate::ocean::{response::response, SeaSpec, WaveField};
    use transient::MEMORY;
    let sea = SeaSpec { hs: 3.5, tp: 8.0, gamma: 3.3, direction_rad: 0.3, spread_s: 10.0 };
    let field = ok(WaveField::new(&sea, 5));
    let field = Arc::new(field);
    for end in [EndBehaviour::Stop, EndBehaviour::PingPong] {
        let v = straight_test_vessel(&[[0.0, 0.0], [50.0, 0.0]], end, 5.0);
        let fleet = Fleet::new(vec![v.clone()], WaveSetting::W0).with_sea(Arc::clone(&field));
        let te = v.route().length() / 5.0; // 50 m at 5 m/s
        let pose = |t: f64| ok(v.pose_in_sea(t, &field));
        let (a, b) = (pose(te - 1e-7), pose(te + 1e-7));
        assert!((a[2] - b[2]).abs() < 1e-6 && (a[3] - b[3]).abs() < 1e-6 && (a[4] - b[4]).abs() < 1e-6, "{a:?} {b:?}");
        // The steady state just after the event differs (the stop or the turn), so the step was real.
        let vel = ok(v.velocity_at(te + 1e-7, &WaveSetting::W0));
        let steady = response(&field, &v.params().hull, b[0], b[1], b[5], vel[0], vel[1], te + 1e-7)[0];
        assert!((steady[1] - b[3]).abs() > 1e-3 || (steady[0] - b[2]).abs() > 1e-3, "{end:?}");
        // Long after, the steady state of the new course (before the next turn of the ping-pong route).
        let hull = &v.params().hull;
        let faded = -MEMORY.ln() / (hull.roll_damping_ratio * hull.roll_natural_frequency());
        if end == EndBehaviour::Stop {
            let t = te + faded + 1.0;
            let p = pose(t);
            assert_eq!(
                [p[2] - v.params().z_base_m, p[3], p[4]],
                response(&field, hull, 50.0, 0.0, p[5], 0.0, 0.0, t)[0]
            );
        }
        // The heave rate is the heave's derivative across the event too.
        let vz = ok(fleet.velocities_at(te + 0.5))[0][2];
        let fd = (pose(te + 0.5 + 1e-5)[2] - pose(te + 0.5 - 1e-5)[2]) / 2e-5;
        assert!((vz - fd).abs() < 1e-5, "{vz} {fd}");
    }
}
