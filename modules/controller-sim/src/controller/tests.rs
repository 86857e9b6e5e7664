//! Tests of the Controller's timing: moves playing out in wall-clock time, the simulated
//! clock, and what queries see during a move. Wall-clock instants are given, never waited.

use nalgebra::{Point2, Point3};
use tca_robot::{CarriagePose, ElbowBranch, HeightField, LegKinematics, LegParams};
use tca_single_leg_messages::MoveFailureKind;

use super::*;
use crate::sim::{FaultConfig, StartPose};

fn flat() -> HeightField {
    HeightField::flat(Point2::origin(), Point2::new(6.0, 11.0), 0.02, 0.0).unwrap()
}

/// The leg in the air with the foot at world `foot`, carriage at y = 2 m.
fn in_air(foot: Point3<f64>, speed: SpeedFactor) -> ControllerConfig {
    let params = LegParams::default();
    let joints = LegKinematics::new(&params)
        .inverse_world(&CarriagePose::level(2.0), &foot, ElbowBranch::Positive)
        .unwrap();
    ControllerConfig::new(
        flat(),
        StartPose::Joints {
            carriage_y_m: 2.0,
            joints,
        },
    )
    .with_speed(speed)
}

fn planted(speed: SpeedFactor) -> ControllerConfig {
    ControllerConfig::new(
        flat(),
        StartPose::PlantedAt {
            carriage_y_m: 1.0,
            foot_xy: Point2::new(3.8, 1.2),
            branch: ElbowBranch::Positive,
            force_n: 2224.1,
        },
    )
    .with_speed(speed)
}

fn secs(s: f64) -> Duration {
    Duration::from_secs_f64(s)
}

fn close(a: Duration, b: Duration) -> bool {
    a.abs_diff(b) < Duration::from_micros(10)
}

#[test]
fn as_fast_as_possible_does_not_wait_and_reports_simulated_time() {
    let t0 = Instant::now();
    let mut c = Controller::new(
        &in_air(Point3::new(4.0, 3.0, 0.8), SpeedFactor::AsFastAsPossible),
        t0,
    )
    .unwrap();
    let q = c.snapshot(t0).joints;
    let target = JointPosition {
        vertical_m: q.vertical_m + 0.36,
        ..q
    };
    let run = c.leg_move(&[target], false, t0);
    assert_eq!(run.outcome, Ok(()));
    assert_eq!(run.wall, Duration::ZERO);
    // 10 s at 3.6 cm/s plus the acceleration blends (the simulator core's figure).
    assert!(close(run.simulated, secs(10.72)), "{:?}", run.simulated);
    assert!(!c.moving(t0));
    // Idle wall time does not advance the clock when running as fast as possible.
    let later = c.snapshot(t0 + secs(100.0));
    assert_eq!(later.clock, run.simulated);
    assert_eq!(later.joints, target);
}

#[test]
fn a_move_plays_out_over_duration_over_k() {
    let t0 = Instant::now();
    let mut c = Controller::new(
        &in_air(Point3::new(4.0, 3.0, 0.8), SpeedFactor::Times(2.0)),
        t0,
    )
    .unwrap();
    let q = c.snapshot(t0).joints;
    let target = JointPosition {
        vertical_m: q.vertical_m + 0.36,
        ..q
    };
    let run = c.leg_move(&[target], false, t0);
    assert!(close(run.simulated, secs(10.72)));
    assert!(close(run.wall, secs(5.36)), "{:?}", run.wall);

    // Half-way in wall time: half-way in simulated time, the leg on its trajectory.
    let mid = c.snapshot(t0 + secs(2.68));
    assert!(c.moving(t0 + secs(2.68)));
    assert!(close(mid.clock, secs(5.36)), "{:?}", mid.clock);
    let traj = JointTrajectory::plan(c.simulator().kinematics(), &q, &[target]);
    assert_eq!(mid.joints, traj.position_at(5.36));
    assert!(mid.joints.vertical_m > q.vertical_m + 0.1);
    assert!(mid.joints.vertical_m < target.vertical_m - 0.1);
    // The positions follow the joints.
    assert!((mid.global_leg.z - (0.8 - (mid.joints.vertical_m - q.vertical_m))).abs() < 1e-9);

    // After it: the end state, and idle time at k = 2 runs on the clock.
    let end = c.snapshot(t0 + secs(5.36) + secs(1.0));
    assert!(!c.moving(t0 + secs(6.36)));
    assert_eq!(end.joints, target);
    assert!(close(end.clock, secs(12.72)), "{:?}", end.clock);
    // Settling late does not change the clock.
    c.settle(t0 + secs(6.36));
    assert!(close(c.snapshot(t0 + secs(6.36)).clock, secs(12.72)));
}

#[test]
fn idle_time_counts_at_the_speed_factor() {
    let t0 = Instant::now();
    let c = Controller::new(
        &in_air(Point3::new(4.0, 3.0, 0.8), SpeedFactor::Times(10.0)),
        t0,
    )
    .unwrap();
    assert!(close(c.snapshot(t0 + secs(1.5)).clock, secs(15.0)));
}

#[test]
fn a_refused_command_moves_nothing_and_takes_no_time() {
    let t0 = Instant::now();
    let mut c = Controller::new(
        &in_air(Point3::new(4.0, 3.0, 0.8), SpeedFactor::Times(1.0)),
        t0,
    )
    .unwrap();
    let before = c.snapshot(t0);
    let bad = JointPosition {
        vertical_m: f64::NAN,
        ..before.joints
    };
    for run in [
        c.leg_move(&[bad], false, t0),
        c.leg_move(&[], false, t0),
        c.body_move(99.0, t0),
        c.body_move(1.5, t0), // the foot is in the air
    ] {
        assert_eq!(run.wall, Duration::ZERO);
        let failure = run.outcome.unwrap_err();
        match failure.exception {
            Some(Raised::MoveFailed(m)) => {
                assert_eq!(m.kind, MoveFailureKind::Refused);
                assert!(m.detail.contains("did not move"), "{}", m.detail);
            }
            other => panic!("{other:?}"),
        }
    }
    assert!(!c.moving(t0));
    assert_eq!(c.snapshot(t0), before);
    let refused = c.set_trans_force(-1.0, t0).outcome.unwrap_err();
    assert_eq!(refused.exception, None);
    assert!(refused.reason.starts_with("setTransForce: "));
}

#[test]
fn a_collision_counts_once_it_has_happened() {
    let t0 = Instant::now();
    let mut c = Controller::new(
        &in_air(Point3::new(4.0, 3.0, 0.8), SpeedFactor::Times(1.0)),
        t0,
    )
    .unwrap();
    let q = c.snapshot(t0).joints;
    // Straight down 1 m onto flat ground 0.8 m below, not in transition mode: a strike.
    let run = c.leg_move(
        &[JointPosition {
            vertical_m: q.vertical_m + 1.0,
            ..q
        }],
        false,
        t0,
    );
    let failure = run.outcome.unwrap_err();
    assert!(matches!(
        failure.exception,
        Some(Raised::MoveFailed(ref m)) if m.kind == MoveFailureKind::Collision
    ));
    // It stopped at the ground: 0.8 m takes over 22 s at 3.6 cm/s.
    assert!(run.simulated > secs(22.0) && run.simulated < secs(24.0));
    assert_eq!(c.snapshot(t0 + run.wall / 2).collisions, 0);
    assert_eq!(c.snapshot(t0 + run.wall).collisions, 1);
    assert!(c.snapshot(t0 + run.wall).global_leg.z.abs() < 1e-3);
}

#[test]
fn a_body_move_carries_the_carriage_along() {
    let t0 = Instant::now();
    let mut c = Controller::new(&planted(SpeedFactor::Times(1.0)), t0).unwrap();
    let start = c.snapshot(t0);
    let run = c.body_move(1.5, t0);
    assert_eq!(run.outcome, Ok(()));
    let mid = c.snapshot(t0 + run.wall / 2);
    assert!(mid.carriage.y_m > start.carriage.y_m + 0.1);
    assert!(mid.carriage.y_m < 1.4);
    assert!(mid.foot_planted);
    let end = c.snapshot(t0 + run.wall);
    assert!((end.carriage.y_m - 1.5).abs() <= 0.01);
    assert!(close(end.clock, run.simulated));
}

#[test]
fn hardware_faults_raise_hardware_fault() {
    let t0 = Instant::now();
    let faults = FaultConfig {
        force_drop_probability: 1.0,
        ..FaultConfig::none()
    };
    let mut c = Controller::new(
        &planted(SpeedFactor::AsFastAsPossible).with_faults(faults),
        t0,
    )
    .unwrap();
    let failure = c.body_move(1.5, t0).outcome.unwrap_err();
    match failure.exception {
        Some(Raised::HardwareFault(h)) => {
            assert!(h.detail.contains("force dropped"), "{}", h.detail)
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn bad_configurations_are_refused() {
    let t0 = Instant::now();
    let too_fast = planted(SpeedFactor::Times(f64::INFINITY));
    assert!(matches!(
        Controller::new(&too_fast, t0),
        Err(crate::config::ConfigError::Speed { .. })
    ));
    let bad_faults = planted(SpeedFactor::AsFastAsPossible).with_faults(FaultConfig {
        slip_probability: 2.0,
        ..FaultConfig::none()
    });
    assert!(matches!(
        Controller::new(&bad_faults, t0),
        Err(crate::config::ConfigError::Simulator(_))
    ));
}

mod properties {
    use proptest::prelude::*;

    use super::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Whatever the speed factor and whenever the queries come, the clock never runs
        /// backwards, the leg stays between where it started and where it goes, and the
        /// move ends exactly where the simulator put it.
        #[test]
        fn the_clock_is_monotone_and_the_leg_stays_on_its_path(
            k in 0.5f64..100.0,
            lift_m in 0.01f64..0.19, // the foot starts 0.2 m above the vertical axis's top limit
            mut at in proptest::collection::vec(0.0f64..1.5, 1..12),
        ) {
            let t0 = Instant::now();
            let mut c = Controller::new(
                &in_air(Point3::new(4.0, 3.0, 0.8), SpeedFactor::Times(k)),
                t0,
            )
            .unwrap();
            let q = c.snapshot(t0).joints;
            let target = JointPosition { vertical_m: q.vertical_m - lift_m, ..q };
            let run = c.leg_move(&[target], false, t0);
            prop_assert_eq!(run.outcome.clone(), Ok(()));
            at.sort_by(f64::total_cmp);
            let mut last = Duration::ZERO;
            for f in at {
                let snap = c.snapshot(t0 + run.wall.mul_f64(f));
                prop_assert!(snap.clock >= last);
                last = snap.clock;
                prop_assert!(snap.joints.vertical_m <= q.vertical_m + 1e-12);
                prop_assert!(snap.joints.vertical_m >= target.vertical_m - 1e-12);
                if f >= 1.0 {
                    prop_assert_eq!(snap.joints, c.simulator().joint_leg_position());
                    prop_assert!((snap.joints.vertical_m - target.vertical_m).abs() < 1e-9);
                    prop_assert!(snap.clock >= run.simulated);
                } else {
                    prop_assert!(snap.clock <= run.simulated);
                }
            }
        }
    }
}

#[test]
fn a_compliant_leg_driven_through_the_calibrated_kinematics_lands_within_a_few_cm() {
    // A leg move far out to the side (foot 2.2 m from the column, the vertical axis long):
    // the rails' torsion swings the real foot off. Commanded in rigid joints, it lands about
    // 15 cm off; through the Controller's calibrated kinematics, within 5 cm.
    let t0 = Instant::now();
    let target = Point3::new(0.8, 2.3, 0.3);
    let kin = LegKinematics::new(&LegParams::default());
    let joints = kin
        .inverse_world(&CarriagePose::level(2.0), &target, ElbowBranch::Positive)
        .unwrap();
    let faults = FaultConfig {
        compliance_scale: 1.0,
        ..FaultConfig::none()
    };
    let mut miss = Vec::new();
    for compensate in [false, true] {
        let mut config =
            in_air(Point3::new(3.0, 3.5, 0.8), SpeedFactor::AsFastAsPossible).with_faults(faults);
        config.compensate_deflection = compensate;
        let mut c = Controller::new(&config, t0).unwrap();
        let run = c.leg_move(&[joints], false, t0);
        assert!(run.outcome.is_ok(), "{:?}", run.outcome);
        let real = c.simulator().true_foot_position();
        miss.push((real - target).norm());
        // The readouts are the ideal leg's: the joints commanded.
        if compensate {
            let read = c.snapshot(t0 + Duration::from_secs(3600)).joints;
            assert!(
                (read.shoulder_rad - joints.shoulder_rad).abs() < 1e-3,
                "{read:?}"
            );
            assert!((read.elbow_rad - joints.elbow_rad).abs() < 1e-3, "{read:?}");
        }
    }
    assert!(miss[0] > 0.10, "uncompensated {:.3} m", miss[0]);
    assert!(miss[1] < 0.05, "compensated {:.3} m", miss[1]);
}
