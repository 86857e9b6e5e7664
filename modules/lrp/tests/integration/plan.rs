//! The Leg Recovery Planner's behaviour: trajectories over and around obstacles, the shape
//! of the vertical profile, the turn penalty, and clear failures on bad input.

use crate::common;

use common::*;
use nalgebra::{Point2, Point3};
use tca_lrp::trajectory::check_clearance;
use tca_lrp::{CostModel, LegRecoveryPlanner, LrpParams, MapValue, PlanError, TerrainGrid};
use tca_robot::{Course, ElbowBranch, LegKinematics, LegParams};

const V: f64 = 0.036;

fn foot_xy(kin: &LegKinematics, body_y: f64, p: &[f64; 3]) -> Point2<f64> {
    let h = kin.forward_horizontal(p[0], p[1]);
    Point2::new(3.0 + h.x, body_y + h.y)
}

#[test]
fn on_flat_ground_the_foot_lifts_moves_and_lowers_in_transition() {
    let terrain = boxes(0.0, &[]);
    let map = map_around(&terrain, 4.0);
    let start = planted(&terrain, 4.0, Point2::new(2.0, 3.0), ElbowBranch::Positive);
    let goal = Point3::new(4.0, 5.5, 0.0);
    let plan = planner().plan(&map, 4.0, &start, &goal).unwrap();
    let cs = planner().cspace(&map, 4.0).unwrap();
    check_clearance(&cs, &plan.points).unwrap();
    let mv = plan.to_leg_move();
    assert!(mv.transition);
    // The first way-point is a pure lift; the last one a pure lowering below the ground.
    let first = plan.waypoints[0];
    assert_eq!(
        (first.shoulder_rad, first.elbow_rad),
        (start.shoulder_rad, start.elbow_rad)
    );
    assert!(first.vertical_m < start.vertical_m);
    let n = plan.waypoints.len();
    let (before, last) = (plan.waypoints[n - 2], plan.waypoints[n - 1]);
    assert_eq!(
        (before.shoulder_rad, before.elbow_rad),
        (last.shoulder_rad, last.elbow_rad)
    );
    assert!(
        last.vertical_m > 4.0 + 0.1,
        "aims below the sand: {}",
        last.vertical_m
    );
    // The foot never goes higher than the clearance or the initial lift needs on flat ground.
    let top = plan.points.iter().map(|p| p[2]).fold(f64::MIN, f64::max);
    let needed = 0.05f64.max(LrpParams::default().start_lift_m);
    assert!(top <= needed + 1e-9, "{top}");
    // It ends above the footfall.
    let kin = kin();
    let end = foot_xy(&kin, 4.0, plan.points.last().unwrap());
    assert!((end - Point2::new(4.0, 5.5)).norm() < 1e-6);
}

#[test]
fn the_foot_keeps_rising_while_it_moves_and_lowers_only_at_the_end() {
    // A 0.6 m wall across the way: the foot must lift over it.
    let terrain = boxes(0.0, &[(3.0, 5.6, 3.0, 0.3, 0.6)]);
    let map = map_around(&terrain, 4.0);
    let start = planted(&terrain, 4.0, Point2::new(3.0, 4.9), ElbowBranch::Positive);
    let goal = footfall(&terrain, Point2::new(3.0, 6.3));
    let plan = planner().plan(&map, 4.0, &start, &goal).unwrap();
    let z: Vec<f64> = plan.points.iter().map(|p| p[2]).collect();
    let peak = z.iter().copied().fold(f64::MIN, f64::max);
    assert!(peak >= 0.65 - 1e-9, "over the wall: {peak}");
    // Heights rise then fall: never down then up again.
    let top = z.iter().position(|&v| v == peak).unwrap();
    assert!(z[..=top].windows(2).all(|w| w[1] >= w[0] - 1e-12), "{z:?}");
    assert!(z[top..].windows(2).all(|w| w[1] <= w[0] + 1e-12), "{z:?}");
    // Along horizontal moves the vertical axis never has to go faster than its limit.
    let speeds = planner().cspace(&map, 4.0).unwrap().speeds().to_owned();
    for w in plan.points.windows(2) {
        let (ds, de, dz) = (w[1][0] - w[0][0], w[1][1] - w[0][1], w[1][2] - w[0][2]);
        let th = speeds.horizontal_time_s(ds, de);
        if th > 0.0 {
            assert!(dz.abs() <= V * th + 1e-9, "segment {w:?}");
        }
    }
}

#[test]
fn it_goes_around_the_sun_box_which_is_too_tall_to_lift_over() {
    let terrain = Course::builtin(3).unwrap().height_field().unwrap();
    let body_y = 2.0;
    let map = map_around(&terrain, body_y);
    let start = planted(
        &terrain,
        body_y,
        Point2::new(3.3, 1.0),
        ElbowBranch::Positive,
    );
    let goal = footfall(&terrain, Point2::new(3.3, 3.4));
    let plan = planner().plan(&map, body_y, &start, &goal).unwrap();
    let kin = kin();
    // Sample the joint-space path finely: the foot disc never overlaps the box.
    for w in plan.points.windows(2) {
        for k in 0..=50 {
            let t = f64::from(k) / 50.0;
            let p = [
                w[0][0] + (w[1][0] - w[0][0]) * t,
                w[0][1] + (w[1][1] - w[0][1]) * t,
                w[0][2] + (w[1][2] - w[0][2]) * t,
            ];
            let xy = foot_xy(&kin, body_y, &p);
            let dx = ((xy.x - 3.3).abs() - 0.45).max(0.0);
            let dy = ((xy.y - 2.1).abs() - 0.30).max(0.0);
            assert!(dx.hypot(dy) > 0.15, "foot at {xy} touches the sun box");
        }
    }
    assert!(plan.points.iter().all(|p| p[2] < 1.0 + 1e-9));
}

#[test]
fn a_low_box_is_lifted_over_rather_than_walked_around() {
    // A 0.15 m box between start and goal, long enough that going around costs more.
    let terrain = boxes(0.0, &[(3.0, 5.6, 4.0, 0.4, 0.15)]);
    let map = map_around(&terrain, 4.0);
    let start = planted(&terrain, 4.0, Point2::new(3.0, 4.8), ElbowBranch::Positive);
    let goal = footfall(&terrain, Point2::new(3.0, 6.4));
    let plan = planner().plan(&map, 4.0, &start, &goal).unwrap();
    let peak = plan.points.iter().map(|p| p[2]).fold(f64::MIN, f64::max);
    assert!((0.2 - 1e-9..0.4).contains(&peak), "{peak}");
    assert!(plan.turns <= 2, "a direct path: {} turns", plan.turns);
}

#[test]
fn the_turn_penalty_reduces_turns() {
    let (mut with, mut without) = (0, 0);
    for seed in 0..12 {
        let (terrain, a, b) = random_scene(seed);
        let map = map_around(&terrain, 4.0);
        let start = planted(&terrain, 4.0, a, ElbowBranch::Positive);
        let goal = footfall(&terrain, b);
        let plan = |penalty: f64| {
            let params = LrpParams {
                cost: CostModel {
                    turn_penalty_s: penalty,
                    ..CostModel::default()
                },
                ..LrpParams::default()
            };
            LegRecoveryPlanner::new(LegParams::default(), params)
                .unwrap()
                .plan(&map, 4.0, &start, &goal)
        };
        if let (Ok(p0), Ok(p1)) = (plan(0.0), plan(0.5)) {
            assert!(
                p1.turns <= p0.turns + 1,
                "seed {seed}: {} vs {}",
                p1.turns,
                p0.turns
            );
            // The penalty trades little real cost for the straighter path.
            assert!(
                p1.cost <= p0.cost * 1.10,
                "seed {seed}: {} vs {}",
                p1.cost,
                p0.cost
            );
            with += p1.turns;
            without += p0.turns;
        }
    }
    assert!(
        with < without,
        "turns with the penalty {with}, without {without}"
    );
}

#[test]
fn bad_input_is_a_clear_error() {
    let terrain = Course::builtin(3).unwrap().height_field().unwrap();
    let body_y = 2.0;
    let map = map_around(&terrain, body_y);
    let p = planner();
    let start = planted(
        &terrain,
        body_y,
        Point2::new(3.3, 1.0),
        ElbowBranch::Positive,
    );

    // An empty map.
    let mut empty = map.clone();
    for v in empty.grid_mut().cells_mut() {
        *v = MapValue::Unknown;
    }
    assert_eq!(
        p.plan(&empty, body_y, &start, &Point3::new(3.3, 3.4, 0.0))
            .unwrap_err(),
        PlanError::EmptyMap
    );
    // A footfall on unknown terrain.
    let mut hidden = map.clone();
    let g = hidden.grid_mut();
    if let Some(c) = g.cell_at(Point2::new(4.5, 3.0)) {
        *g.get_mut(c).unwrap() = MapValue::Unknown;
    }
    let err = p
        .plan(&hidden, body_y, &start, &Point3::new(4.5, 3.0, 0.0))
        .unwrap_err();
    assert!(matches!(err, PlanError::UnknownGoal { .. }), "{err}");
    // Out of reach (4 m from the column).
    let err = p
        .plan(&map, body_y, &start, &Point3::new(5.8, 4.5, 0.0))
        .unwrap_err();
    assert!(matches!(err, PlanError::GoalOutOfReach { .. }), "{err}");
    // On top of the sun box: above what the foot can reach.
    let err = p
        .plan(&map, body_y, &start, &Point3::new(3.3, 2.1, 1.2))
        .unwrap_err();
    assert!(
        matches!(err, PlanError::GoalHeightOutOfReach { .. }),
        "{err}"
    );
    // Right next to the sun box: blocked.
    let err = p
        .plan(&map, body_y, &start, &Point3::new(3.3, 2.75, 0.0))
        .unwrap_err();
    assert!(matches!(err, PlanError::GoalBlocked { .. }), "{err}");
    // A start inside the box (the map says the terrain is far above the foot).
    let sunk = kin()
        .inverse_world(
            &tca_robot::CarriagePose::level(body_y),
            &Point3::new(3.6, 2.3, 0.0),
            ElbowBranch::Positive,
        )
        .unwrap();
    let err = p
        .plan(&map, body_y, &sunk, &Point3::new(3.3, 3.4, 0.0))
        .unwrap_err();
    assert!(matches!(err, PlanError::StartInCollision { .. }), "{err}");
    // On the sand right beside the box the foot cannot move: the box is too tall.
    let beside = planted(
        &terrain,
        body_y,
        Point2::new(4.0, 2.1),
        ElbowBranch::Positive,
    );
    let err = p
        .plan(&map, body_y, &beside, &Point3::new(3.3, 3.4, 0.0))
        .unwrap_err();
    assert!(matches!(err, PlanError::StartBlocked { .. }), "{err}");
    // Not finite.
    let err = p
        .plan(&map, body_y, &start, &Point3::new(f64::NAN, 3.4, 0.0))
        .unwrap_err();
    assert!(matches!(err, PlanError::NotFinite { .. }), "{err}");
    let err = p
        .plan(&map, f64::INFINITY, &start, &Point3::new(3.3, 3.4, 0.0))
        .unwrap_err();
    assert!(matches!(err, PlanError::NotFinite { .. }), "{err}");
    // Every message says what to do.
    assert!(err.to_string().contains("give finite"));
}

#[test]
fn a_footfall_walled_in_by_tall_boxes_is_unreachable() {
    let wall = 1.3;
    let terrain = boxes(
        0.0,
        &[
            (4.2, 5.0, 1.6, 0.2, wall),
            (4.2, 6.4, 1.6, 0.2, wall),
            (3.5, 5.7, 0.2, 1.6, wall),
            (4.9, 5.7, 0.2, 1.6, wall),
        ],
    );
    let map = map_around(&terrain, 4.0);
    let start = planted(&terrain, 4.0, Point2::new(2.0, 3.5), ElbowBranch::Positive);
    let err = planner()
        .plan(&map, 4.0, &start, &Point3::new(4.2, 5.7, 0.0))
        .unwrap_err();
    assert!(matches!(err, PlanError::Unreachable { .. }), "{err}");
    assert!(err.to_string().contains("choose another footfall"));
    // The reachability map agrees.
    let p = planner();
    let cs = p.cspace(&map, 4.0).unwrap();
    let reach = p.reachability(&cs, &start).unwrap();
    assert!(!reach.reaches(Point2::new(4.2, 5.7)));
    assert!(reach.reaches(Point2::new(2.0, 5.5)));
}

#[test]
fn unknown_terrain_counts_as_an_obstacle_of_the_configured_height() {
    // The whole map unknown except around the start and the goal: the foot must rise to
    // the unknown height plus clearance on the way.
    let terrain = boxes(0.0, &[]);
    let mut map = map_around(&terrain, 4.0);
    let keep = |p: Point2<f64>| {
        (p - Point2::new(2.0, 3.0)).norm() < 0.7 || (p - Point2::new(4.0, 5.5)).norm() < 0.7
    };
    let grid = map.grid_mut();
    let cells: Vec<_> = grid.iter().map(|(c, _)| c).collect();
    for c in cells {
        let centre = grid.cell_center(c);
        if !keep(centre) {
            *grid.get_mut(c).unwrap() = MapValue::Unknown;
        }
    }
    let start = planted(&terrain, 4.0, Point2::new(2.0, 3.0), ElbowBranch::Positive);
    let plan = planner()
        .plan(&map, 4.0, &start, &Point3::new(4.0, 5.5, 0.0))
        .unwrap();
    let peak = plan.points.iter().map(|p| p[2]).fold(f64::MIN, f64::max);
    let params = LrpParams::default();
    let want = params.unknown_height_m + params.clearance_m;
    assert!((peak - want).abs() < 1e-9, "{peak} against {want}");
    let _: &TerrainGrid = &map;
}

mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(40))]

        /// On random scenes and footfalls, a plan is either a clear error or a trajectory
        /// that clears every cell it passes, keeps the vertical axis within its speed along
        /// horizontal moves, and ends with a pure lowering onto the footfall.
        #[test]
        fn plans_clear_the_terrain_or_fail_clearly(
            seed in 0u64..10_000,
            gx in 1.0f64..5.0,
            gy in 2.0f64..6.0,
        ) {
            let (terrain, a, _) = random_scene(seed);
            let map = map_around(&terrain, 4.0);
            let p = planner();
            let cs = p.cspace(&map, 4.0).unwrap();
            let start = planted(&terrain, 4.0, a, ElbowBranch::Positive);
            let goal = footfall(&terrain, Point2::new(gx, gy));
            match p.plan_in(&cs, &start, &goal) {
                Ok(plan) => {
                    prop_assert!(check_clearance(&cs, &plan.points).is_ok());
                    let speeds = *cs.speeds();
                    for w in plan.points.windows(2) {
                        let th = speeds.horizontal_time_s(w[1][0] - w[0][0], w[1][1] - w[0][1]);
                        if th > 0.0 {
                            prop_assert!((w[1][2] - w[0][2]).abs() <= V * th + 1e-9);
                        }
                    }
                    let n = plan.waypoints.len();
                    prop_assert!(n >= 2);
                    let (before, last) = (plan.waypoints[n - 2], plan.waypoints[n - 1]);
                    prop_assert_eq!(before.shoulder_rad, last.shoulder_rad);
                    prop_assert_eq!(before.elbow_rad, last.elbow_rad);
                    prop_assert!(last.vertical_m > before.vertical_m);
                }
                Err(e) => {
                    let msg = e.to_string();
                    prop_assert!(!matches!(e, PlanError::Internal(_)), "{}", msg);
                    prop_assert!(msg.contains("choose") || msg.contains("give"), "{}", msg);
                }
            }
        }
    }
}
