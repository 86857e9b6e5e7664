//! The depth camera sees the terrain with stereo-like noise; odometry drifts as set.

use nalgebra::Point2;
use tca_nav_sensing::{Attitude, CameraMount, CameraParams, DepthCamera, DriftingOdometry, Pose2};
use tca_robot::HeightField;

fn flat() -> HeightField {
    HeightField::flat(Point2::new(-1.0, -3.0), Point2::new(6.0, 3.0), 0.02, 0.0).unwrap()
}

const MOUNT: CameraMount = CameraMount {
    forward_m: 0.1,
    height_m: 0.4,
    pitch_down_rad: 0.5,
};

#[test]
fn depth_points_lie_on_the_ground_with_noise_growing_with_distance() {
    let terrain = flat();
    let mut params = CameraParams::stereo_default();
    params.untextured_fraction = 0.0;
    let mut cam = DepthCamera::new(params.clone(), 1).unwrap();
    let pose = MOUNT.camera_pose(&Pose2::new(0.0, 0.0, 0.0), &Attitude::level(0.0));
    let img = cam.capture(&terrain, &pose);
    assert!(
        img.valid() > img.depth.len() / 2,
        "most pixels see the ground"
    );
    let pts = img.points(&params, &pose, 10.0);
    let spread = |lo: f64, hi: f64| {
        let zs: Vec<f64> = pts
            .iter()
            .filter(|p| (lo..hi).contains(&p.x))
            .map(|p| p.z)
            .collect();
        assert!(zs.len() > 100, "points between {lo} and {hi} m");
        let m = zs.iter().sum::<f64>() / zs.len() as f64;
        (zs.iter().map(|z| (z - m).powi(2)).sum::<f64>() / zs.len() as f64).sqrt()
    };
    let near = spread(0.6, 0.9);
    let far = spread(1.8, 2.6);
    assert!(near < 0.01, "near points within 1 cm of the ground: {near}");
    assert!(far > 2.0 * near, "far noise {far} grows over near {near}");
    // Untextured pixels are invalid.
    let mut params = CameraParams::stereo_default();
    params.untextured_fraction = 0.5;
    let mut cam = DepthCamera::new(params, 1).unwrap();
    let half = cam.capture(&terrain, &pose).valid();
    assert!((half as f64) < 0.6 * img.valid() as f64);
}

#[test]
fn odometry_drifts_by_its_fraction_of_the_distance() {
    for seed in 0..8 {
        let mut odo = DriftingOdometry::new(Pose2::default(), 0.0125, seed);
        let mut truth = Pose2::default();
        for _ in 0..400 {
            let next = truth.moved(0.01, 0.0, 0.0);
            odo.update(&truth, &next);
            truth = next;
        }
        let err = odo.estimate().distance(&truth) / odo.travelled_m();
        assert!(
            (0.008..0.017).contains(&err),
            "seed {seed}: error {err} of the distance"
        );
    }
    let mut odo = DriftingOdometry::new(Pose2::default(), 0.0, 3);
    let next = Pose2::new(1.0, 0.5, 0.3);
    assert!(odo.update(&Pose2::default(), &next).distance(&next) < 1e-12);
}

#[test]
fn bad_camera_parameters_are_refused() {
    let mut p = CameraParams::stereo_default();
    p.hfov_rad = 4.0;
    assert!(
        DepthCamera::new(p, 0)
            .unwrap_err()
            .to_string()
            .contains("hfov_rad")
    );
}

#[test]
fn a_camera_on_a_tilted_body_tilts_with_it() {
    let mount = CameraMount {
        forward_m: 0.15,
        height_m: 0.1,
        pitch_down_rad: 0.5,
    };
    let planar = Pose2::new(1.0, 2.0, 0.0);
    let level = mount.camera_pose(&planar, &Attitude::level(0.3));
    // Level: 0.15 m ahead, 0.1 m above the reference point, looking 0.5 rad down.
    let t = level.translation.vector;
    assert!((t.x - 1.15).abs() < 1e-12 && (t.y - 2.0).abs() < 1e-12 && (t.z - 0.4).abs() < 1e-12);
    let axis = level.rotation * nalgebra::Vector3::x();
    assert!((axis.z + 0.5f64.sin()).abs() < 1e-12, "{axis:?}");
    // Nose 0.1 rad further down: the camera lower at the front and looking 0.6 rad down.
    let tilted = mount.camera_pose(
        &planar,
        &Attitude {
            z_m: 0.3,
            roll_rad: 0.0,
            pitch_rad: 0.1,
        },
    );
    let axis = tilted.rotation * nalgebra::Vector3::x();
    assert!((axis.z + 0.6f64.sin()).abs() < 1e-12, "{axis:?}");
    assert!(tilted.translation.z < level.translation.z);
    // Rolled left side up: the body's down leans left, and so does the downward-looking
    // optical axis.
    let rolled = mount.camera_pose(
        &planar,
        &Attitude {
            z_m: 0.3,
            roll_rad: 0.2,
            pitch_rad: 0.0,
        },
    );
    let axis = rolled.rotation * nalgebra::Vector3::x();
    assert!(axis.y > 0.05, "{axis:?}");
}
