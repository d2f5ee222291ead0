//! Poses: `RigidPose` matches the documented roll–pitch–yaw rotation and refuses non-rigid or non-finite matrices.

use super::common::{add, mat_vec, ok, refuses, rpy_matrix};
use mmusv_core::geometry::RigidPose;
use parry3d::math::Vec3;

#[test]
fn poses_match_the_documented_rotation_and_reject_bad_matrices() {
    let rpy = [0.3, -0.4, 1.1];
    let xyz = [4.0, -2.0, 7.5];
    let p = RigidPose::from_xyz_rpy(xyz, rpy);
    let m = rpy_matrix(rpy);
    let row = p.to_matrix_row_major();
    for i in 0..3 {
        for j in 0..3 {
            assert!((row[i * 4 + j] - m[i][j]).abs() < 1e-6, "R[{i}][{j}]");
        }
        assert!((row[i * 4 + 3] - xyz[i]).abs() < 1e-6);
    }
    assert_eq!(&row[12..], &[0.0, 0.0, 0.0, 1.0]);
    // Round trip through the validated constructor.
    let q = ok("from_matrix_row_major", || RigidPose::from_matrix_row_major(&row, "pose"));
    let local = Vec3::new(1.0, 2.0, 3.0);
    let w = q.transform_point(local);
    let want = add(mat_vec(&m, [1.0, 2.0, 3.0]), xyz);
    assert!((0..3).all(|i| (f64::from(w.to_array()[i]) - want[i]).abs() < 1e-4));
    let back = q.inverse_transform_point(w);
    assert!((back - local).length() < 1e-4);

    let good = RigidPose::IDENTITY.to_matrix_row_major();
    let mut nan = good;
    nan[5] = f64::NAN;
    refuses("pose with NaN", "my_pose", || RigidPose::from_matrix_row_major(&nan, "my_pose"));
    let mut inf = good;
    inf[3] = f64::INFINITY;
    refuses("pose with inf translation", "my_pose", || RigidPose::from_matrix_row_major(&inf, "my_pose"));
    let mut scaled = good;
    scaled[0] = 2.0;
    refuses("scaled pose", "my_pose", || RigidPose::from_matrix_row_major(&scaled, "my_pose"));
    let mut mirror = good;
    mirror[0] = -1.0;
    refuses("reflection", "my_pose", || RigidPose::from_matrix_row_major(&mirror, "my_pose"));
    let mut last = good;
    last[12] = 1.0;
    refuses("bad last row", "my_pose", || RigidPose::from_matrix_row_major(&last, "my_pose"));
    let zero = [0.0; 16];
    refuses("zero matrix", "my_pose", || RigidPose::from_matrix_row_major(&zero, "my_pose"));
    let mut huge = good;
    huge[3] = 1e300; // finite in f64, infinite once stored as f32
    refuses("translation beyond f32", "my_pose", || RigidPose::from_matrix_row_major(&huge, "my_pose"));
}
