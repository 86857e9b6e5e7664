//! The calibration routine recovers a known scanner mount from a target on the leg.

use std::sync::Arc;

use nalgebra::{Isometry3, Point2, Translation3, UnitQuaternion, Vector3};
use tca_ism::{CalibrationPose, NoiseModel, SensorSpec, VirtualScanner, calibrate};
use tca_robot::{CarriagePose, HeightField, JointPosition, LegKinematics, LegParams};

/// Angle of the rotation between two transforms, radians, and the distance between their
/// translations, metres.
fn difference(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    let d = a.inverse() * b;
    (
        d.rotation.angle(),
        (a.translation.vector - b.translation.vector).norm(),
    )
}

fn leg_poses(params: &LegParams) -> Vec<CalibrationPose> {
    let kin = LegKinematics::new(params);
    let mut poses = Vec::new();
    for (i, shoulder) in [1.35, 1.57, 1.8].into_iter().enumerate() {
        for elbow in [-0.4, 0.3] {
            for vertical in [3.2, 3.8] {
                let foot = kin.forward(&JointPosition {
                    shoulder_rad: shoulder,
                    elbow_rad: elbow,
                    vertical_m: vertical,
                });
                // The target rides on the vertical member, 2 m above the sole.
                poses.push(CalibrationPose {
                    carriage: CarriagePose::level(1.0 + 0.5 * i as f64),
                    target_in_body: foot + Vector3::new(0.0, 0.0, 2.0),
                });
            }
        }
    }
    poses
}

/// The robot parameters with the scanner pitched 35° down: the leg poses below are in the
/// Perceptron's view from that mount.
fn params() -> LegParams {
    let mut p = LegParams::default();
    p.scanner.pitch_down_rad = 35f64.to_radians();
    p
}

#[test]
fn calibration_recovers_a_known_mount() {
    let params = params();
    let terrain = Arc::new(
        HeightField::flat(Point2::new(-5.0, -5.0), Point2::new(12.0, 20.0), 0.1, 0.0).unwrap(),
    );
    let nominal = params.scanner.carriage_from_scanner();
    // The scanner is really mounted 4 cm off and turned by about 2 degrees.
    let truth = Isometry3::from_parts(
        Translation3::new(0.03, -0.02, 0.025),
        UnitQuaternion::from_euler_angles(0.02, -0.025, 0.03),
    ) * nominal;
    let mut scanner = VirtualScanner::new(SensorSpec::perceptron(), terrain, &params)
        .with_true_mount(truth)
        .with_seed(3);
    assert_eq!(
        scanner.noise(),
        NoiseModel::default_for(SensorSpec::perceptron().kind)
    );
    let (angle_before, offset_before) = difference(&scanner.calibration(), &truth.inverse());
    assert!(angle_before > 0.03 && offset_before > 0.03);

    let fit = calibrate(&mut scanner, &leg_poses(&params), 0.08).unwrap();
    let (angle, offset) = difference(&fit.scanner_from_body, &truth.inverse());
    assert!(angle < 0.2_f64.to_radians(), "rotation error {angle} rad");
    assert!(offset < 0.01, "translation error {offset} m");
    assert!(fit.rms_residual_m < 0.01, "rms {}", fit.rms_residual_m);
    assert_eq!(fit.observations, 12);

    scanner.set_calibration(fit.scanner_from_body);
    assert_eq!(scanner.calibration(), fit.scanner_from_body);
}

#[test]
fn a_target_out_of_view_is_reported() {
    let params = params();
    let terrain = Arc::new(
        HeightField::flat(Point2::new(-5.0, -5.0), Point2::new(12.0, 20.0), 0.1, 0.0).unwrap(),
    );
    let mut scanner = VirtualScanner::new(SensorSpec::erim(), terrain, &params);
    let poses = [CalibrationPose {
        carriage: CarriagePose::level(2.0),
        // Behind the scanner.
        target_in_body: nalgebra::Point3::new(0.0, -2.0, -1.0),
    }; 3];
    let e = calibrate(&mut scanner, &poses, 0.1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("target was not found"), "{e}");
}
