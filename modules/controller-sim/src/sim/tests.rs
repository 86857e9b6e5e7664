//! Tests of the simulator core.

use std::time::Duration;

use nalgebra::{Point2, Point3};
use tca_robot::{CarriagePose, ElbowBranch, Grid, HeightField, JointPosition, LegParams};

use super::*;

const RES: f64 = 0.02;

/// The pit at 2 cm with `f(x, y)` as the height.
fn terrain(f: impl Fn(f64, f64) -> f64) -> HeightField {
    HeightField::from_grid(
        Grid::from_fn(Point2::origin(), RES, 301, 551, |_, p| f(p.x, p.y)).unwrap(),
    )
    .unwrap()
}

fn flat() -> HeightField {
    terrain(|_, _| 0.0)
}

/// Joints putting the foot at world `p` with the carriage at `y`.
fn joints_at(y: f64, p: Point3<f64>) -> JointPosition {
    let params = LegParams::default();
    tca_robot::LegKinematics::new(&params)
        .inverse_world(&CarriagePose::level(y), &p, ElbowBranch::Positive)
        .unwrap()
}

fn in_air(t: HeightField, y: f64, foot: Point3<f64>) -> LegSimulator {
    LegSimulator::new(
        LegParams::default(),
        t,
        StartPose::Joints {
            carriage_y_m: y,
            joints: joints_at(y, foot),
        },
    )
    .unwrap()
}

fn planted(t: HeightField, y: f64, foot: Point2<f64>) -> LegSimulator {
    LegSimulator::new(
        LegParams::default(),
        t,
        StartPose::PlantedAt {
            carriage_y_m: y,
            foot_xy: foot,
            branch: ElbowBranch::Positive,
            force_n: 2224.1,
        },
    )
    .unwrap()
}

fn with_vertical(q: JointPosition, vertical_m: f64) -> JointPosition {
    JointPosition { vertical_m, ..q }
}

#[test]
fn pure_vertical_move_takes_ten_seconds_plus_blends() {
    let mut sim = in_air(flat(), 2.0, Point3::new(4.0, 3.0, 0.8));
    let q = sim.joint_leg_position();
    let target = with_vertical(q, q.vertical_m + 0.36);
    let report = sim.leg_move(&[target], false).unwrap();
    assert!(
        (report.duration.as_secs_f64() - 10.72).abs() < 1e-6,
        "{:?}",
        report.duration
    );
    assert_eq!(sim.clock(), report.duration);
    assert_eq!(sim.joint_leg_position(), target);
    assert!((sim.global_leg_position().z - 0.44).abs() < 1e-9);
    // Samples every 0.5 s plus start and end.
    assert_eq!(report.path.len(), 23);
}

#[test]
fn joints_arrive_together() {
    let mut sim = in_air(flat(), 2.0, Point3::new(4.0, 3.0, 0.8));
    let q0 = sim.joint_leg_position();
    let q1 = JointPosition::new(
        q0.shoulder_rad + 0.6,
        q0.elbow_rad - 0.3,
        q0.vertical_m - 0.1,
    );
    let report = sim.leg_move(&[q1], false).unwrap();
    for s in &report.path {
        let f: Vec<f64> = (0..3)
            .map(|j| {
                (s.joints.to_array()[j] - q0.to_array()[j]) / (q1.to_array()[j] - q0.to_array()[j])
            })
            .collect();
        assert!(
            (f[0] - f[1]).abs() < 1e-9 && (f[1] - f[2]).abs() < 1e-9,
            "{f:?} at {:?}",
            s.time
        );
    }
    // The shoulder is the slowest joint: 0.6 rad at 0.1 rad/s plus one blend of 1 s.
    assert!(
        (report.duration.as_secs_f64() - 7.0).abs() < 1e-6,
        "{:?}",
        report.duration
    );
}

#[test]
fn transition_touches_level_ground_at_the_right_height() {
    let mut sim = in_air(flat(), 2.0, Point3::new(4.0, 3.0, 0.5));
    let q = sim.joint_leg_position();
    let report = sim
        .leg_move(&[with_vertical(q, q.vertical_m + 0.8)], true)
        .unwrap();
    let contact = report.contact.unwrap();
    assert!(contact.foot_world.z.abs() < 1e-3, "{contact:?}");
    assert!(sim.foot_planted());
    let force = sim.read_force().force_n.z;
    assert!(
        (force - sim.trans_force_n()).abs() < 0.02 * sim.trans_force_n(),
        "{force}"
    );
    assert!((contact.force_n - force).abs() < 1e-9);
    // About 0.5 m at 3.6 cm/s, well before the 0.8 m way-point.
    let secs = report.duration.as_secs_f64();
    assert!(secs > 13.0 && secs < 15.5, "{secs}");
    // The encoders read the leg pressed a few millimetres into the ground.
    let z = sim.global_leg_position().z;
    assert!(z < 0.0 && z > -0.01, "{z}");
}

#[test]
fn transition_lands_on_a_box_top() {
    let boxed = terrain(|x, y| {
        if (3.6..=4.4).contains(&x) && (2.6..=3.4).contains(&y) {
            0.4
        } else {
            0.0
        }
    });
    let mut sim = in_air(boxed, 2.0, Point3::new(4.0, 3.0, 0.8));
    sim.set_trans_force(1500.0).unwrap();
    let q = sim.joint_leg_position();
    let report = sim
        .leg_move(&[with_vertical(q, q.vertical_m + 1.0)], true)
        .unwrap();
    let contact = report.contact.unwrap();
    assert!((contact.foot_world.z - 0.4).abs() < 1e-3, "{contact:?}");
    assert!((sim.read_force().force_n.z - 1500.0).abs() < 30.0);
}

#[test]
fn transition_without_contact_is_an_error() {
    let mut sim = in_air(flat(), 2.0, Point3::new(4.0, 3.0, 0.8));
    let q = sim.joint_leg_position();
    let target = with_vertical(q, q.vertical_m + 0.3);
    let err = sim.leg_move(&[target], true).unwrap_err();
    assert!(
        matches!(err, SimError::NoContact { force_n, .. } if force_n == 0.0),
        "{err}"
    );
    assert!(err.is_move_failure());
    assert_eq!(sim.joint_leg_position(), target);
    assert!(!sim.foot_planted());
}

#[test]
fn a_move_through_a_box_stops_at_the_box() {
    // Box from x = 3.0 to 3.4 (0.5 m tall) between the foot's start and end.
    let boxed = terrain(|x, y| {
        if (3.0..=3.4).contains(&x) && (2.0..=4.0).contains(&y) {
            0.5
        } else {
            0.0
        }
    });
    let mut sim = in_air(boxed, 2.0, Point3::new(4.2, 3.0, 0.3));
    let target = joints_at(2.0, Point3::new(2.2, 3.0, 0.3));
    let start_clock = sim.clock();
    let err = sim.leg_move(&[target], false).unwrap_err();
    let SimError::Collision {
        foot_world,
        terrain_height_m,
        joints,
        dragged,
    } = err.clone()
    else {
        panic!("expected a collision, got {err}");
    };
    assert!(!dragged);
    assert!(err.is_move_failure());
    // The foot's rim touches the box's face (the bilinear face spans the 2 cm next to x = 3.4).
    let rim_x = foot_world.x - 0.15;
    assert!(rim_x > 3.38 && rim_x < 3.41, "{foot_world}");
    assert!((foot_world.z - 0.3).abs() < 0.01 && terrain_height_m > 0.29);
    assert_eq!(sim.joint_leg_position(), joints);
    assert!(sim.clock() > start_clock);
    assert!((sim.true_foot_position() - foot_world).norm() < 1e-9);
    // Backing away works.
    let back = joints_at(2.0, Point3::new(4.2, 3.0, 0.3));
    sim.leg_move(&[back], false).unwrap();
}

#[test]
fn a_thin_feature_is_not_skipped() {
    // A 2 cm wide, 10 cm tall ridge across the path of a fast sweep.
    let ridge = terrain(|x, _| if (x - 3.0).abs() < 0.011 { 0.1 } else { 0.0 });
    let mut sim = in_air(ridge, 2.0, Point3::new(4.5, 2.0, 0.05));
    let target = joints_at(2.0, Point3::new(1.5, 2.0, 0.05));
    let err = sim.leg_move(&[target], false).unwrap_err();
    assert!(matches!(err, SimError::Collision { .. }), "{err}");
}

#[test]
fn a_loaded_foot_moved_sideways_is_dragged() {
    let mut sim = planted(flat(), 2.0, Point2::new(4.0, 3.0));
    let q = sim.joint_leg_position();
    let sideways = JointPosition {
        shoulder_rad: q.shoulder_rad + 0.2,
        ..q
    };
    let err = sim.leg_move(&[sideways], false).unwrap_err();
    assert!(
        matches!(err, SimError::Collision { dragged: true, .. }),
        "{err}"
    );
    // Lifting first, then moving, is fine.
    let mut sim = planted(flat(), 2.0, Point2::new(4.0, 3.0));
    let q = sim.joint_leg_position();
    let up = with_vertical(q, q.vertical_m - 0.3);
    let over = JointPosition {
        shoulder_rad: q.shoulder_rad + 0.2,
        ..up
    };
    sim.leg_move(&[up, over], false).unwrap();
    assert!(!sim.foot_planted());
    assert_eq!(sim.read_force().force_n.z, 0.0);
}

#[test]
fn bad_commands_are_refused_and_nothing_moves() {
    let mut sim = in_air(flat(), 2.0, Point3::new(4.0, 3.0, 0.5));
    let (q, clock, pose) = (sim.joint_leg_position(), sim.clock(), sim.body_position());
    let mut bad_nan = q;
    bad_nan.elbow_rad = f64::NAN;
    let errors = [
        sim.leg_move(&[], false).unwrap_err(),
        sim.leg_move(&[q, bad_nan], false).unwrap_err(),
        sim.leg_move(&[with_vertical(q, 4.8)], true).unwrap_err(),
        sim.leg_move(
            &[JointPosition {
                shoulder_rad: 3.1,
                ..q
            }],
            false,
        )
        .unwrap_err(),
        sim.body_move(3.0).unwrap_err(),
        sim.set_trans_force(-5.0).unwrap_err(),
        sim.set_trans_force(f64::INFINITY).unwrap_err(),
    ];
    for e in &errors {
        assert!(e.is_rejected(), "{e}");
        assert!(!e.to_string().is_empty());
    }
    assert!(matches!(errors[1], SimError::NotFinite { .. }));
    assert!(matches!(
        errors[2],
        SimError::WaypointOutOfLimits { index: 0, .. }
    ));
    assert!(matches!(errors[4], SimError::FootNotPlanted));
    let mut sim2 = planted(flat(), 2.0, Point2::new(4.0, 3.0));
    let clock2 = sim2.clock();
    for target in [11.0, 0.1, f64::NAN] {
        let e = sim2.body_move(target).unwrap_err();
        assert!(e.is_rejected(), "{e}");
    }
    assert!(matches!(
        sim2.body_move(11.0),
        Err(SimError::BeyondRails { .. })
    ));
    assert_eq!(sim2.clock(), clock2);
    assert_eq!(
        (sim.joint_leg_position(), sim.clock(), sim.body_position()),
        (q, clock, pose)
    );
}

#[test]
fn body_move_reaches_its_target_with_the_foot_still() {
    let mut sim = planted(flat(), 2.0, Point2::new(3.8, 3.5));
    let foot = sim.true_foot_position();
    let report = sim.body_move(3.5).unwrap();
    let y = sim.body_position().y_m;
    assert!((y - 3.5).abs() <= 0.01, "{y}");
    assert!((report.final_y_m - y).abs() < 1e-12);
    // The foot holds (a rigid leg is modelled very stiff, not infinitely).
    let slid = (sim.true_foot_position() - foot).norm();
    assert!(slid < 1e-4, "{slid}");
    assert!(report.foot_slid_m < 1e-4, "{}", report.foot_slid_m);
    // Rigid leg: the encoders agree with the pinned foot.
    assert!(
        (sim.global_leg_position().xy() - foot.xy()).norm() < 1e-3,
        "{}",
        sim.global_leg_position()
    );
    let f = sim.read_force();
    assert!((f.force_n.z - 2224.1).abs() < 1.0, "{f:?}");
    assert_eq!((f.force_n.x, f.force_n.y), (0.0, 0.0));
    // 1.5 m at no more than 5 cm/s, slowing down near the end.
    let secs = report.duration.as_secs_f64();
    assert!(secs > 30.0 && secs < 45.0, "{secs}");
    assert!(report.control_cycles > 1800);
    assert_eq!(sim.clock(), report.duration);
    // And back again.
    sim.body_move(2.5).unwrap();
    assert!((sim.body_position().y_m - 2.5).abs() <= 0.01);
}

#[test]
fn body_move_past_full_extension_fails_and_says_how_far_it_got() {
    let mut sim = planted(flat(), 2.0, Point2::new(4.0, 3.5));
    let err = sim.body_move(7.0).unwrap_err();
    let SimError::ExtensionLimit {
        reached_y_m,
        target_y_m,
        ..
    } = err
    else {
        panic!("{err}")
    };
    assert!(err.is_move_failure());
    assert_eq!(target_y_m, 7.0);
    // The foot is 1 m to the side and 1.5 m ahead; the leg reaches 2.5 m, so the carriage
    // stops about 2.3 m past the foot, at y = 5.8 m.
    assert!(reached_y_m > 5.6 && reached_y_m < 5.85, "{reached_y_m}");
    assert!((sim.body_position().y_m - reached_y_m).abs() < 1e-12);
    assert!(sim.foot_planted());
}

#[test]
fn a_slip_is_a_move_failure() {
    let mut sim = planted(flat(), 2.0, Point2::new(3.8, 3.5));
    sim.set_faults(FaultConfig {
        slip_probability: 1.0,
        slip_distance_m: 0.05,
        ..FaultConfig::none()
    })
    .unwrap();
    let foot = sim.true_foot_position();
    let err = sim.body_move(3.5).unwrap_err();
    assert!(
        matches!(err, SimError::Slip { slid_m, .. } if slid_m >= 0.02),
        "{err}"
    );
    assert!(err.is_move_failure());
    assert!(sim.true_foot_position().y < foot.y - 0.019);
}

#[test]
fn a_force_drop_off_is_a_hardware_fault() {
    let mut sim = planted(flat(), 2.0, Point2::new(3.8, 3.5));
    sim.set_faults(FaultConfig {
        force_drop_probability: 1.0,
        ..FaultConfig::none()
    })
    .unwrap();
    let err = sim.body_move(3.5).unwrap_err();
    assert!(matches!(err, SimError::ForceDropOff { .. }), "{err}");
    assert!(err.is_hardware_fault());
    assert!(sim.read_force().force_n.z < 1.0);
}

#[test]
fn a_limit_switch_trip_is_a_hardware_fault() {
    let mut sim = in_air(flat(), 2.0, Point3::new(4.0, 3.0, 0.5));
    sim.set_faults(FaultConfig {
        limit_switch_probability: 1.0,
        seed: 3,
        ..FaultConfig::none()
    })
    .unwrap();
    let q = sim.joint_leg_position();
    let target = JointPosition {
        shoulder_rad: q.shoulder_rad + 0.5,
        ..q
    };
    let err = sim.leg_move(&[target], false).unwrap_err();
    assert!(matches!(err, SimError::LimitSwitch { .. }), "{err}");
    assert!(err.is_hardware_fault());
    let mut sim = planted(flat(), 2.0, Point2::new(3.8, 3.5));
    sim.set_faults(FaultConfig {
        limit_switch_probability: 1.0,
        ..FaultConfig::none()
    })
    .unwrap();
    assert!(matches!(
        sim.body_move(3.0),
        Err(SimError::LimitSwitch { .. })
    ));
}

#[test]
fn joint_noise_moves_the_leg_and_large_noise_is_a_servo_error() {
    let mut sim = in_air(flat(), 2.0, Point3::new(4.0, 3.0, 0.5));
    let noise = JointNoise {
        shoulder_rad: 0.002,
        elbow_rad: 0.002,
        vertical_m: 0.001,
    };
    sim.set_faults(FaultConfig {
        joint_noise: noise,
        seed: 9,
        ..FaultConfig::none()
    })
    .unwrap();
    let q = sim.joint_leg_position();
    let target = JointPosition {
        shoulder_rad: q.shoulder_rad + 0.2,
        ..q
    };
    let report = sim.leg_move(&[target], false).unwrap();
    let off = report.final_joints.shoulder_rad - target.shoulder_rad;
    assert!(off != 0.0 && off.abs() < 0.02, "{off}");
    let noise = JointNoise {
        shoulder_rad: 0.5,
        elbow_rad: 0.5,
        vertical_m: 0.0,
    };
    sim.set_faults(FaultConfig {
        joint_noise: noise,
        ..FaultConfig::none()
    })
    .unwrap();
    let err = sim.leg_move(&[q], false).unwrap_err();
    assert!(matches!(err, SimError::ServoError { .. }), "{err}");
    assert!(err.is_hardware_fault());
}

#[test]
fn compliance_moves_the_real_foot_off_the_commanded_one() {
    let mut sim = in_air(flat(), 2.0, Point3::new(4.6, 3.2, 0.5));
    sim.set_faults(FaultConfig {
        compliance_scale: 1.0,
        ..FaultConfig::none()
    })
    .unwrap();
    let commanded = sim.global_leg_position();
    let real = sim.true_foot_position();
    let expected = sim
        .kinematics()
        .deflection(&sim.joint_leg_position(), &nalgebra::Vector3::zeros());
    assert!(((real - commanded) - expected).norm() < 1e-12);
    let off = (real - commanded).norm();
    assert!(off > 0.01 && off < 0.25, "{off}");
    // A transition lands where the real foot is, lower than the encoders expect.
    let q = sim.joint_leg_position();
    let report = sim
        .leg_move(&[with_vertical(q, q.vertical_m + 0.8)], true)
        .unwrap();
    assert!(report.contact.unwrap().foot_world.z.abs() < 1e-3);
    // A body move leaves strain that is relieved at the end.
    let report = sim.body_move(3.0).unwrap();
    assert!(
        report.strain_relieved_m > 0.001 && report.strain_relieved_m < 0.05,
        "{}",
        report.strain_relieved_m
    );
    assert!((sim.body_position().y_m - 3.0).abs() <= 0.01);
}

#[test]
fn faults_are_deterministic_for_a_seed() {
    let run = || {
        let mut sim = planted(flat(), 2.0, Point2::new(3.8, 3.5));
        let faults = FaultConfig {
            seed: 42,
            slip_probability: 0.5,
            slip_distance_m: 0.01,
            joint_noise: JointNoise {
                shoulder_rad: 0.001,
                elbow_rad: 0.001,
                vertical_m: 0.001,
            },
            ..FaultConfig::none()
        };
        sim.set_faults(faults).unwrap();
        let body = sim.body_move(3.0);
        let q = sim.joint_leg_position();
        let lift = sim.leg_move(&[with_vertical(q, q.vertical_m - 0.2)], false);
        (body, lift, sim.clock(), sim.true_foot_position())
    };
    assert_eq!(run(), run());
    assert!(
        FaultConfig {
            slip_probability: 2.0,
            ..FaultConfig::none()
        }
        .validate()
        .is_err()
    );
}

#[test]
fn start_poses_are_checked() {
    let params = LegParams::default();
    let q = joints_at(2.0, Point3::new(4.0, 3.0, -0.1));
    let err = LegSimulator::new(
        params.clone(),
        flat(),
        StartPose::Joints {
            carriage_y_m: 2.0,
            joints: q,
        },
    )
    .unwrap_err();
    assert!(err.to_string().contains("into the terrain"), "{err}");
    let q = joints_at(2.0, Point3::new(4.0, 3.0, 0.5));
    assert!(
        LegSimulator::new(
            params.clone(),
            flat(),
            StartPose::Joints {
                carriage_y_m: 12.0,
                joints: q
            }
        )
        .is_err()
    );
    let tall = terrain(|_, _| 3.8);
    assert!(
        LegSimulator::new(
            params,
            tall,
            StartPose::Joints {
                carriage_y_m: 2.0,
                joints: q
            }
        )
        .is_err()
    );
}

#[test]
fn a_step_walks_forward() {
    // Lift, swing forward, lower in transition mode, then move the body over the foot.
    let course = tca_robot::Course::builtin(1).unwrap();
    let mut sim = LegSimulator::new(
        LegParams::default(),
        course.height_field().unwrap(),
        StartPose::PlantedAt {
            carriage_y_m: 1.0,
            foot_xy: Point2::new(3.8, 1.2),
            branch: ElbowBranch::Positive,
            force_n: 2224.1,
        },
    )
    .unwrap();
    let q = sim.joint_leg_position();
    let lifted = with_vertical(q, 3.2);
    let ahead = joints_at(1.0, Point3::new(3.9, 2.6, 0.8));
    let down = with_vertical(ahead, 4.3);
    let report = sim.leg_move(&[lifted, ahead, down], true).unwrap();
    assert!(report.contact.is_some());
    let report = sim.body_move(2.2).unwrap();
    assert!((report.final_y_m - 2.2).abs() <= 0.01);
    assert!(sim.clock() > Duration::from_secs(60));
}

mod invariants {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        /// Whatever the way-points, the real foot never ends inside the terrain: a move either
        /// completes clear of it, stops touching it, or stands on it.
        #[test]
        fn the_foot_never_ends_inside_the_terrain(
            seed in 0u64..1000,
            moves in proptest::collection::vec((-1.2f64..1.2, 0.3f64..2.4, 3.0f64..4.45, any::<bool>()), 1..4),
        ) {
            let course = tca_robot::Course::random(seed);
            let t = course.height_field().unwrap();
            let params = LegParams::default();
            let start = JointPosition::new(0.8, 1.2, 3.0);
            let mut sim = LegSimulator::new(params.clone(), t.clone(), StartPose::Joints { carriage_y_m: 3.0, joints: start }).unwrap();
            for (shoulder, elbow, vertical, transition) in moves {
                let target = JointPosition::new(shoulder + 1.0, elbow, vertical);
                let result = sim.leg_move(&[target], transition);
                let foot = sim.true_foot_position();
                let h = t.max_height_in_disc(foot.xy(), params.leg.foot_radius_m);
                prop_assert!(foot.z - h >= -1e-3, "foot {} under terrain {h} after {result:?}", foot);
                if let Err(SimError::Collision { foot_world, terrain_height_m, dragged: false, .. }) = &result {
                    prop_assert!((foot_world.z - terrain_height_m).abs() < 1e-3, "{foot_world} vs {terrain_height_m}");
                }
                if let Ok(report) = &result {
                    for s in &report.path {
                        let h = t.max_height_in_disc(s.foot_world.xy(), params.leg.foot_radius_m);
                        prop_assert!(s.foot_world.z - h >= -1e-3);
                    }
                }
                // Lift clear before the next move, as a planner would.
                let q = sim.joint_leg_position();
                let _ = sim.leg_move(&[JointPosition { vertical_m: 3.0, ..q }], false);
            }
        }
    }
}
