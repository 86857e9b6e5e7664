//! Inverse kinematics finds, for any foot position the forward kinematics gives within the
//! joint limits, joint positions within the limits that put the foot there (within 1 mm);
//! and refuses targets out of reach.

use nalgebra::{Point3, Vector3};
use proptest::prelude::*;
use tca_legged_model::{BUILTIN_ROBOTS, IkOptions, KinematicsError, RobotModel};

fn robots() -> Vec<RobotModel> {
    BUILTIN_ROBOTS
        .iter()
        .map(|r| RobotModel::builtin(r.name).expect("shipped robots load"))
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(600))]

    #[test]
    fn ik_of_the_fk_foot_position_lands_within_a_millimetre(
        robot in 0..BUILTIN_ROBOTS.len(),
        leg in 0..6usize,
        fractions in proptest::collection::vec(0.0..=1.0f64, 6),
    ) {
        thread_local! {
            static ROBOTS: Vec<RobotModel> = robots();
        }
        ROBOTS.with(|robots| {
            let leg = &robots[robot].legs()[leg];
            let q: Vec<f64> = leg
                .joints()
                .iter()
                .zip(&fractions)
                .map(|(j, f)| j.limits().lower + f * j.limits().span())
                .collect();
            let target = leg.foot_position(&q).expect("fk");
            let solution = leg
                .inverse_kinematics(&target, &IkOptions::default())
                .map_err(|e| TestCaseError::fail(format!("{e} (from {q:?})")))?;
            prop_assert!(leg.within_limits(&solution.joints), "{:?}", solution.joints);
            let reached = leg.foot_position(&solution.joints).expect("fk");
            prop_assert!((reached - target).norm() < 1e-3, "{reached} vs {target}");
            prop_assert!((solution.error_m - (reached - target).norm()).abs() < 1e-12);
            Ok(())
        })?;
    }

    #[test]
    fn the_jacobian_matches_finite_differences(
        robot in 0..BUILTIN_ROBOTS.len(),
        leg in 0..6usize,
        fractions in proptest::collection::vec(0.0..=1.0f64, 6),
    ) {
        let robot = RobotModel::builtin(BUILTIN_ROBOTS[robot].name).expect("load");
        let leg = &robot.legs()[leg];
        let q: Vec<f64> = leg
            .joints()
            .iter()
            .zip(&fractions)
            .map(|(j, f)| j.limits().lower + f * j.limits().span())
            .collect();
        let jacobian = leg.jacobian(&q).expect("jacobian");
        let h = 1e-6;
        for i in 0..leg.dof() {
            let mut plus = q.clone();
            plus[i] += h;
            let mut minus = q.clone();
            minus[i] -= h;
            let numeric: Vector3<f64> = (leg.foot_position(&plus).expect("fk")
                - leg.foot_position(&minus).expect("fk"))
                / (2.0 * h);
            let analytic = jacobian.column(i);
            prop_assert!((numeric - analytic).norm() < 1e-6, "joint {i}: {numeric} vs {analytic}");
        }
    }
}

#[test]
fn ik_starting_near_an_answer_stays_near_it() {
    let robot = RobotModel::builtin("athlete").expect("load");
    let leg = &robot.legs()[0];
    let q: Vec<f64> = leg
        .joints()
        .iter()
        .map(|j| j.limits().middle() + 0.2)
        .collect();
    let target = leg.foot_position(&q).expect("fk");
    let solution = leg
        .inverse_kinematics(&target, &IkOptions::starting_at(&q))
        .expect("reachable");
    assert_eq!(solution.joints, q, "the start already solves it");
    assert_eq!(solution.iterations, 0);
}

#[test]
fn targets_out_of_reach_are_refused_with_the_distance() {
    for robot in robots() {
        for leg in robot.legs() {
            let far = leg.base_position() + Vector3::new(0.0, 0.0, 100.0);
            match leg.inverse_kinematics(&far, &IkOptions::default()) {
                Err(KinematicsError::Unreachable {
                    leg: name,
                    closest_m,
                    ..
                }) => {
                    assert_eq!(name, leg.name());
                    assert!(closest_m > 90.0, "{closest_m}");
                }
                other => panic!("{}: {other:?}", leg.name()),
            }
        }
    }
    // Within the reach of the links but outside the joint ranges: behind and out from the
    // Ambler's left column, where its stack's rear leg goes but its front leg does not.
    let ambler = RobotModel::builtin("ambler").expect("load");
    let leg = ambler.leg("left_front").expect("leg");
    let behind = Point3::new(-2.0, 2.6, -2.45);
    let e = leg
        .inverse_kinematics(&behind, &IkOptions::default())
        .expect_err("out of range");
    let message = e.to_string();
    assert!(!message.contains('\n'), "{message:?}");
    assert!(
        message.contains("left_front") && message.contains("within its joint limits"),
        "{message}"
    );
    assert!(
        ambler
            .leg("left_rear")
            .expect("leg")
            .inverse_kinematics(&behind, &IkOptions::default())
            .is_ok()
    );
}

#[test]
fn bad_queries_are_errors_not_panics() {
    let robot = RobotModel::builtin("hexapod").expect("load");
    let leg = &robot.legs()[0];
    assert!(matches!(
        leg.forward_kinematics(&[0.0]),
        Err(KinematicsError::JointCount {
            given: 1,
            expected: 3,
            ..
        })
    ));
    assert!(matches!(
        leg.foot_position(&[0.0, f64::NAN, 0.0]),
        Err(KinematicsError::NotFinite { .. })
    ));
    let nan = Point3::new(f64::NAN, 0.0, 0.0);
    assert!(matches!(
        leg.inverse_kinematics(&nan, &IkOptions::default()),
        Err(KinematicsError::NotFinite { .. })
    ));
    assert!(
        leg.inverse_kinematics(&Point3::origin(), &IkOptions::starting_at(&[0.0]))
            .is_err()
    );
    assert!(matches!(
        robot.forward_kinematics(6, &[0.0; 3]),
        Err(KinematicsError::UnknownLeg { .. })
    ));
    let short: Vec<Vec<f64>> = vec![vec![0.0; 3]; 5];
    assert!(matches!(
        robot.centre_of_mass(&short),
        Err(KinematicsError::LegCount {
            given: 5,
            expected: 6
        })
    ));
    let mut wrong = robot.neutral_posture();
    wrong[3].push(0.0);
    let e = robot.collision_shapes(&wrong).expect_err("too many joints");
    assert!(e.to_string().contains("right_front"), "{e}");
}
