//! The simulator's behaviour on the shipped robots: standing up, swings, body moves, what
//! it refuses, collisions, tip-overs and the clock.

use crate::common;

use std::sync::Arc;

use common::{ORIGIN, ROBOTS, flat_for, model, standing, standing_on, swing, through};
use nalgebra::{Isometry3, Point2, Translation3, UnitQuaternion, Vector3};
use tca_legged_messages::MoveFailureKind;
use tca_legged_sim::{LeggedSim, MoveError, MoveException, SimError, SimParams, StartPose};
use tca_robot::HeightField;

/// Everything a refused move must leave as it was.
type Snapshot = (Isometry3<f64>, Vec<Vec<f64>>, Vec<bool>, f64, u32, u32);

fn snapshot(sim: &LeggedSim) -> Snapshot {
    let c = sim.counters();
    (
        sim.body(),
        sim.posture().to_vec(),
        sim.stance(),
        sim.clock_s(),
        c.moves,
        c.collisions,
    )
}

#[test]
fn every_robot_stands_on_flat_ground_with_a_positive_margin() {
    for name in ROBOTS {
        let sim = standing(name);
        let h = sim.model().neutral_height();
        assert!(sim.stance().iter().all(|&s| s), "{name}");
        for (i, p) in sim.contact_points().iter().enumerate() {
            assert!(p.z.abs() < 1e-3 * h, "{name} leg {i} contact at {p:?}");
        }
        assert!(sim.margin() > 0.1 * h, "{name}: margin {}", sim.margin());
        assert!((sim.body().translation.vector.z - h).abs() < 1e-9, "{name}");
        assert_eq!(sim.clock_s(), 0.0);
        assert_eq!(sim.counters(), Default::default());
        assert!(!sim.fallen());
        let s = sim.support_state();
        assert_eq!(s.feet.len(), sim.model().legs().len());
        assert!(s.feet.iter().all(|f| f.stance));
        assert_eq!(s.t_s, 0.0);
        assert!((s.margin_m - sim.margin()).abs() < 1e-12);
    }
}

#[test]
fn a_transition_swing_lands_the_foot_and_makes_it_stand() {
    for name in ROBOTS {
        let mut sim = standing(name);
        let h = sim.model().neutral_height();
        let before = sim.contact_point(0).unwrap();
        let waypoints = swing(&sim, 0, 0.12, 0.1, 0.05);
        let report = sim
            .leg_move("left_front", &waypoints, true)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(sim.stance()[0], "{name}");
        let after = sim.contact_point(0).unwrap();
        assert!(after.z.abs() < 1e-3 * h, "{name}: landed at {after:?}");
        assert!(
            (after.x - before.x - 0.1 * h).abs() < 0.01 * h,
            "{name}: {before:?} -> {after:?}"
        );
        assert_eq!(report.contact, Some(after));
        assert_eq!(report.events.len(), 2, "{name}");
        assert!(!report.events[0].stance && report.events[1].stance);
        assert!(report.events[0].t_s < report.events[1].t_s);
        assert!(!report.events[0].state.feet[0].stance);
        assert!(report.duration_s > 0.0);
        assert_eq!(sim.clock_s(), report.duration_s);
        assert_eq!(sim.counters().moves, 1);
        assert_eq!(sim.counters().collisions, 0);
        assert!(sim.margin() > 0.0);
    }
}

#[test]
fn an_ambler_swing_takes_what_its_slowest_joint_needs() {
    let mut sim = standing("ambler");
    let q = sim.posture()[0].clone();
    // Only the vertical joint moves: 0.36 m at 0.036 m/s is 10 s.
    let up = vec![q[0], q[1], q[2] - 0.36];
    let r = sim
        .leg_move("left_front", std::slice::from_ref(&up), false)
        .unwrap();
    assert!((r.duration_s - 10.0).abs() < 1e-9, "{}", r.duration_s);
    assert!(!sim.stance()[0]);
    // Shoulder 0.2 rad at 0.1 rad/s (2 s) and elbow 0.15 rad at 0.15 rad/s (1 s): 2 s.
    let over = vec![up[0] + 0.2, up[1] + 0.15, up[2]];
    let r = sim.leg_move("left_front", &[over], false).unwrap();
    assert!((r.duration_s - 2.0).abs() < 1e-9);
    assert!((sim.clock_s() - 12.0).abs() < 1e-9);
    assert_eq!(sim.posture()[0][0], up[0] + 0.2);
}

#[test]
fn a_transition_that_never_touches_is_no_contact() {
    let mut sim = standing("hexapod");
    let up = swing(&sim, 0, 0.2, 0.0, 0.0)[0].clone();
    let err = sim.leg_move("left_front", &[up], true).unwrap_err();
    assert!(matches!(err, MoveError::NoContact { .. }), "{err}");
    assert_eq!(err.kind(), MoveFailureKind::NoContact);
    assert!(!sim.stance()[0]);
    // The lift-off happened and is in the last move's report.
    let last = sim.last_move().unwrap();
    assert_eq!(last.events.len(), 1);
    assert!(!last.events[0].stance);
}

#[test]
fn lifting_a_leg_that_leaves_the_centre_of_mass_outside_is_refused() {
    let mut sim = standing("ambler");
    let lift = |sim: &LeggedSim, leg| through(sim, leg, &[Vector3::new(0.0, 0.0, 0.2)]);
    // The left middle leg may lift: five feet hold the body.
    let w = lift(&sim, 1);
    sim.leg_move("left_middle", &w, false).unwrap();
    // The left rear too would leave the centre of mass (x = -0.07 m) behind the line from
    // the left front to the right rear foot.
    let w = lift(&sim, 2);
    let before = snapshot(&sim);
    let err = sim.leg_move("left_rear", &w, false).unwrap_err();
    match &err {
        MoveError::Unstable { margin_m, leg, .. } => {
            assert!(*margin_m < 0.0);
            assert_eq!(leg.as_deref(), Some("left_rear"));
        }
        other => panic!("expected unstable, got {other}"),
    }
    assert_eq!(err.kind(), MoveFailureKind::Unstable);
    assert_eq!(snapshot(&sim), before, "nothing moved");
    assert!(!sim.fallen());
}

#[test]
fn lifting_a_fourth_foot_of_six_is_refused() {
    let mut sim = standing("hexapod");
    // A tripod lifts (left front, right middle, left rear)...
    for (i, name) in [(0, "left_front"), (4, "right_middle"), (2, "left_rear")] {
        let w = through(&sim, i, &[Vector3::new(0.0, 0.0, 0.02)]);
        sim.leg_move(name, &w, false)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    assert_eq!(sim.stance().iter().filter(|&&s| s).count(), 3);
    assert!(sim.margin() > 0.0);
    // ...but not a fourth foot.
    let w = through(&sim, 1, &[Vector3::new(0.0, 0.0, 0.02)]);
    let before = snapshot(&sim);
    let err = sim.leg_move("left_middle", &w, false).unwrap_err();
    assert!(matches!(err, MoveError::Unstable { .. }), "{err}");
    assert!(err.to_string().contains("at least three"), "{err}");
    assert_eq!(snapshot(&sim), before);
    // A body move on three feet is fine when it stays inside their triangle.
    let mut target = sim.body();
    target.translation.vector.z += 0.01;
    sim.body_move(&target).unwrap();
}

#[test]
fn a_body_move_out_of_the_support_polygon_is_refused() {
    let mut sim = standing("ambler");
    // Lift both front feet: the middle feet (x = 0) make the polygon's front edge, 5 cm
    // ahead of the centre of mass.
    for (i, name) in [(0, "left_front"), (3, "right_front")] {
        let w = through(&sim, i, &[Vector3::new(0.0, 0.0, 0.2)]);
        sim.leg_move(name, &w, false).unwrap();
    }
    let margin = sim.margin();
    assert!(margin > 0.03 && margin < 0.1, "{margin}");
    // A few centimetres forward is fine...
    let mut target = sim.body();
    target.translation.vector.x += 0.02;
    let r = sim.body_move(&target).unwrap_or_else(|e| panic!("{e}"));
    assert!(r.min_margin_m >= 0.0 && sim.margin() < margin);
    // ...30 cm puts the centre of mass outside: refused, nothing moves.
    let before = snapshot(&sim);
    target.translation.vector.x += 0.3;
    let err = sim.body_move(&target).unwrap_err();
    assert!(
        matches!(err, MoveError::Unstable { margin_m, .. } if margin_m < 0.0),
        "{err}"
    );
    assert_eq!(snapshot(&sim), before);
    // Backwards, away from the edge, is fine.
    target.translation.vector.x = -0.3;
    sim.body_move(&target).unwrap();
    assert!(sim.margin() > margin);
}

#[test]
fn a_body_move_keeps_standing_feet_where_they_are() {
    for name in ROBOTS {
        let mut sim = standing(name);
        let h = sim.model().neutral_height();
        let feet = sim.contact_points();
        let target = Isometry3::from_parts(
            Translation3::new(0.05 * h, -0.03 * h, 0.95 * h),
            UnitQuaternion::from_euler_angles(0.02, -0.03, 0.05),
        );
        let r = sim
            .body_move(&target)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(r.duration_s > 0.0 && r.samples >= 1);
        assert!((sim.body().translation.vector - target.translation.vector).norm() < 1e-12);
        for (a, b) in feet.iter().zip(sim.contact_points()) {
            assert!((a - b).norm() < 1e-3 * h, "{name}: {a:?} -> {b:?}");
        }
        assert!(sim.stance().iter().all(|&s| s));
        assert_eq!(sim.clock_s(), r.duration_s);
    }
}

#[test]
fn a_body_move_beyond_the_legs_reach_is_a_joint_limit() {
    let mut sim = standing("hexapod");
    let before = snapshot(&sim);
    let mut target = sim.body();
    target.translation.vector.z += 1.0;
    let err = sim.body_move(&target).unwrap_err();
    assert!(matches!(err, MoveError::JointLimit { .. }), "{err}");
    assert_eq!(err.kind(), MoveFailureKind::JointLimit);
    assert_eq!(snapshot(&sim), before);
}

/// Flat ground for the Ambler with a 0.6 m boulder (a box 0.8 m across) centred at `at`.
fn boulder_at(at: Point2<f64>, height: f64) -> HeightField {
    let res = 0.1;
    let (nx, ny) = (121, 121);
    let origin = Point2::new(-6.0, -6.0);
    let mut h = vec![0.0; nx * ny];
    for iy in 0..ny {
        for ix in 0..nx {
            let x = origin.x + ix as f64 * res;
            let y = origin.y + iy as f64 * res;
            if (x - at.x).abs() <= 0.4 && (y - at.y).abs() <= 0.4 {
                h[iy * nx + ix] = height;
            }
        }
    }
    HeightField::new(origin, res, nx, ny, h).unwrap()
}

#[test]
fn a_leg_driven_into_a_boulder_counts_a_collision_and_stops() {
    // A boulder 0.6 m tall whose near face is 0.5 m ahead of the left front foot.
    let mut sim = standing_on("ambler", boulder_at(Point2::new(2.6, 2.75), 0.6), |_| {});
    let foot = sim.contact_point(0).unwrap();
    let lift = through(&sim, 0, &[Vector3::new(0.0, 0.0, 0.3)]);
    sim.leg_move("left_front", &lift, false).unwrap();
    // Sweep the foot 0.3 m above the ground forward through the boulder.
    let sweep = through(&sim, 0, &[Vector3::new(0.6, 0.0, 0.0)]);
    let before = sim.clock_s();
    let err = sim.leg_move("left_front", &sweep, false).unwrap_err();
    match &err {
        MoveError::Collision { leg, at, .. } => {
            assert_eq!(leg.as_deref(), Some("left_front"));
            assert!(at.x > 1.9 && at.x < 2.4, "{at:?}");
        }
        other => panic!("expected a collision, got {other}"),
    }
    assert_eq!(err.kind(), MoveFailureKind::Collision);
    assert!(sim.counters().collisions >= 1);
    assert_eq!(sim.counters().moves, 2);
    // The leg stopped before the boulder, part of the way.
    let p = sim.contact_point(0).unwrap();
    assert!(p.x > foot.x + 0.15 && p.x < 2.2 - 0.1, "stopped at {p:?}");
    assert!(sim.clock_s() > before);
    assert!(!sim.fallen());
    // Back off a little and put the foot down (transition) in front of the boulder.
    let down = through(
        &sim,
        0,
        &[Vector3::new(-0.2, 0.0, 0.0), Vector3::new(-0.2, 0.0, -0.5)],
    );
    sim.leg_move("left_front", &down, true).unwrap();
    assert!(sim.stance()[0]);
    assert!(sim.contact_point(0).unwrap().z.abs() < 1e-3);
}

#[test]
fn a_foot_put_down_on_a_boulder_stands_on_it() {
    let mut sim = standing_on("ambler", boulder_at(Point2::new(2.6, 2.75), 0.6), |_| {});
    let w = through(
        &sim,
        0,
        &[
            Vector3::new(0.0, 0.0, 0.8),
            Vector3::new(0.7, 0.0, 0.8),
            Vector3::new(0.7, 0.0, 0.3),
        ],
    );
    sim.leg_move("left_front", &w, true).unwrap();
    assert!(sim.stance()[0]);
    let p = sim.contact_point(0).unwrap();
    assert!((p.z - 0.6).abs() < 1e-3, "{p:?}");
}

#[test]
fn a_swinging_foot_driven_into_the_ground_is_a_collision() {
    let mut sim = standing("hexapod");
    let w = through(
        &sim,
        0,
        &[Vector3::new(0.0, 0.0, 0.02), Vector3::new(0.0, 0.0, -0.02)],
    );
    let err = sim.leg_move("left_front", &w, false).unwrap_err();
    assert!(
        matches!(&err, MoveError::Collision { link, .. } if link == "left_front_foot"),
        "{err}"
    );
    assert_eq!(sim.counters().collisions, 1);
    assert!(sim.contact_point(0).unwrap().z > -1e-3);
}

#[test]
fn joint_limits_are_refused_before_moving() {
    for name in ROBOTS {
        let mut sim = standing(name);
        let leg = sim.model().legs()[1].clone();
        let mut q = sim.posture()[1].clone();
        q[0] = leg.joints()[0].limits().upper + 0.01;
        let before = snapshot(&sim);
        let err = sim.leg_move(leg.name(), &[q], false).unwrap_err();
        assert!(matches!(err, MoveError::JointLimit { .. }), "{name}: {err}");
        assert!(err.to_string().contains(leg.joints()[0].name()), "{err}");
        assert_eq!(snapshot(&sim), before);
    }
}

#[test]
fn bad_input_is_refused_with_clear_errors() {
    let mut sim = standing("ambler");
    let before = snapshot(&sim);
    let q = sim.posture()[0].clone();
    let err = sim
        .leg_move("left_wing", std::slice::from_ref(&q), false)
        .unwrap_err();
    assert_eq!(err.kind(), MoveFailureKind::Refused);
    assert!(
        err.to_string().contains("no leg `left_wing`") && err.to_string().contains("left_front"),
        "{err}"
    );
    let err = sim
        .leg_move("left_front", &[vec![0.0, 0.0]], false)
        .unwrap_err();
    assert!(
        err.to_string().contains("has 2 values") && err.to_string().contains("3 moving joints"),
        "{err}"
    );
    let err = sim
        .leg_move("left_front", &[vec![0.0, f64::NAN, 0.0]], false)
        .unwrap_err();
    assert!(err.to_string().contains("not a finite number"), "{err}");
    let err = sim.leg_move("left_front", &[], true).unwrap_err();
    assert!(err.to_string().contains("no way-points"), "{err}");
    let mut target = sim.body();
    target.translation.vector.x = f64::INFINITY;
    let err = sim.body_move(&target).unwrap_err();
    assert_eq!(err.kind(), MoveFailureKind::Refused);
    assert!(sim.leg_state("nope").is_err());
    assert_eq!(snapshot(&sim), before);
    // The exception names the command and the leg.
    let err = sim
        .leg_move("left_front", &[vec![0.0, 0.0]], false)
        .unwrap_err();
    match err.to_exception() {
        MoveException::MoveFailed(m) => {
            assert_eq!(m.command, "legged.legMove");
            assert_eq!(m.leg.as_deref(), Some("left_front"));
            assert_eq!(m.kind, MoveFailureKind::Refused);
            assert!(!m.detail.is_empty());
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn told_to_move_anyway_the_robot_tips_over_and_stays_down() {
    let m = model("ambler");
    let mut p = SimParams::for_model(&m);
    p.refuse_unstable_moves = false;
    let mut sim = LeggedSim::new(m.clone(), flat_for(&m), ORIGIN, p).unwrap();
    let w = through(&sim, 1, &[Vector3::new(0.0, 0.0, 0.2)]);
    sim.leg_move("left_middle", &w, false).unwrap();
    let w = through(&sim, 2, &[Vector3::new(0.0, 0.0, 0.2)]);
    let err = sim.leg_move("left_rear", &w, false).unwrap_err();
    assert!(
        matches!(err, MoveError::TipOver { margin_m, .. } if margin_m < 0.0),
        "{err}"
    );
    assert!(sim.fallen());
    assert_eq!(sim.counters().falls, 1);
    match err.to_exception() {
        MoveException::TipOver(t) => assert_eq!(t.standing.len(), 4),
        other => panic!("{other:?}"),
    }
    let err = sim.body_move(&sim.body()).unwrap_err();
    assert!(matches!(err, MoveError::Fallen { .. }));
    let err = sim
        .leg_move("left_front", &[sim.posture()[0].clone()], false)
        .unwrap_err();
    assert_eq!(err.kind(), MoveFailureKind::Refused);
    assert_eq!(sim.counters().falls, 1);
}

#[test]
fn starts_that_cannot_stand_are_refused() {
    let m = model("ambler");
    let p = SimParams::for_model(&m);
    let t = flat_for(&m);
    let far = StartPose {
        x_m: 16.0,
        ..ORIGIN
    };
    let err = LeggedSim::new(m.clone(), t.clone(), far, p.clone()).unwrap_err();
    assert!(matches!(err, SimError::OffMap { .. }), "{err}");
    let edge = StartPose {
        x_m: 14.5,
        ..ORIGIN
    };
    let err = LeggedSim::new(m.clone(), t.clone(), edge, p.clone()).unwrap_err();
    assert!(err.to_string().contains("off the terrain"), "{err}");
    // A 45 degree slope.
    let slope = HeightField::new(
        Point2::new(-8.0, -8.0),
        0.1,
        161,
        161,
        (0..161 * 161).map(|i| (i % 161) as f64 * 0.1).collect(),
    )
    .unwrap();
    let err = LeggedSim::new(m.clone(), Arc::new(slope), ORIGIN, p.clone()).unwrap_err();
    assert!(matches!(err, SimError::TooSteep { .. }), "{err}");
    // A boulder under the body.
    let err = LeggedSim::new(
        m.clone(),
        Arc::new(boulder_at(Point2::new(0.0, 0.0), 2.5)),
        ORIGIN,
        p.clone(),
    );
    let Err(SimError::Collision { link, .. }) = err else {
        panic!("expected a collision, got {err:?}");
    };
    assert!(!link.is_empty());
    let mut bad = p;
    bad.collision_step_m = f64::NAN;
    let err = LeggedSim::new(m, t, ORIGIN, bad).unwrap_err();
    assert!(matches!(err, SimError::Params(_)), "{err}");
}

#[test]
fn a_turned_start_stands_too() {
    let m = model("athlete");
    let p = SimParams::for_model(&m);
    let start = StartPose {
        x_m: 1.0,
        y_m: -0.5,
        yaw_rad: 0.7,
    };
    let sim = LeggedSim::new(m.clone(), flat_for(&m), start, p).unwrap();
    let pose = tca_legged_sim::isometry_to_pose(&sim.body());
    assert!((pose.yaw_rad - 0.7).abs() < 1e-12 && (pose.x_m - 1.0).abs() < 1e-12);
    assert!(sim.margin() > 0.0);
}
