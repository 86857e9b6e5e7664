//! Planning on built terrains: validity, routes, footfalls and the feedback.

use crate::common;

use std::time::{Duration, Instant};

use nalgebra::Point2;
use tca_cg_space::{
    CgCell, CgError, CgParams, CgSpace, FootStep, MoveCheck, Plan, PlanParams, SearchParams,
    Stance, Verdict, apply_step, plan, plan_checked,
};
use tca_legged_model::RobotModel;

fn ambler_space(terrain: &tca_robot::HeightField) -> CgSpace {
    let model = RobotModel::builtin("ambler").expect("the Ambler");
    CgSpace::for_model(&model, terrain, CgParams::default()).expect("a CG-space")
}

/// The cliff course (seed 1).
fn cliff_course() -> tca_robot::HeightField {
    tca_legged_courses::Course::builtin("cliff", 1)
        .expect("the cliff course")
        .terrain
}

/// The Ambler's CG-space with one heading bin, as walks plan: the robot keeps facing +X.
fn ambler_one_heading(terrain: &tca_robot::HeightField) -> CgSpace {
    let model = RobotModel::builtin("ambler").expect("the Ambler");
    let cg = CgParams {
        theta_bins: Some(1),
        ..CgParams::default()
    };
    CgSpace::for_model(&model, terrain, cg).expect("a CG-space")
}

#[test]
fn flat_ground_is_valid_and_a_plan_keeps_every_stance_standing() {
    let t = common::terrain(0.0, 20.0, -6.0, 6.0, 0.1, |_, _| 0.0);
    let mut space = ambler_space(&t);
    let p = plan(
        &mut space,
        (Point2::new(5.0, 0.0), 0.0),
        (Point2::new(10.0, 0.0), 0.0),
        None,
        &PlanParams::default(),
    )
    .expect("a plan on flat ground");
    let route = &p.feet.route;
    let grid = *space.grid();
    assert!(
        route
            .windows(2)
            .all(|w| grid.steps_between(w[0], w[1]) == 1)
    );
    assert_eq!(p.feet.steps.len() - p.feet.foot_moves(), route.len() - 1);
    assert!(
        p.feet
            .steps
            .iter()
            .any(|s| matches!(s, FootStep::Place { .. })),
        "the feet must move to go 5 m"
    );
    assert_every_stance_stands(&space, &p, true);
}

/// Checks each stance of a plan independently: at least three feet down, each foot within
/// its leg's range (the body-frame map) at a common body height, and with `neutral_com` the
/// CG of the neutral posture inside the feet (the search holds the CG of the legs as posed,
/// which the neutral one matches only while the legs stay near neutral, as on flat ground).
fn assert_every_stance_stands(space: &CgSpace, p: &Plan, neutral_com: bool) {
    let route = &p.feet.route;
    let grid = *space.grid();
    let robot = space.robot().clone();
    for s in p.feet.stances() {
        let c = route[s.k];
        let centre = grid.centre(c.ix, c.iy);
        let theta = grid.theta(c.it);
        let down: Vec<Point2<f64>> = s
            .feet
            .iter()
            .flatten()
            .map(|f| grid.centre(f.0, f.1))
            .collect();
        assert!(down.len() >= 3);
        let poly = tca_stability::support_polygon(&down);
        let (s_, c_) = theta.sin_cos();
        // The centre of mass, body frame to world.
        let com = robot.com;
        let com = centre + nalgebra::Vector2::new(c_ * com.x - s_ * com.y, s_ * com.x + c_ * com.y);
        assert!(
            !neutral_com || poly.signed_distance(com) > 0.0,
            "CG outside the feet at {c:?}: {:.3} m",
            poly.signed_distance(com)
        );
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for (leg, f) in s.feet.iter().enumerate() {
            let Some(f) = f else { continue };
            let d = grid.centre(f.0, f.1) - centre;
            let body = Point2::new(c_ * d.x + s_ * d.y, -s_ * d.x + c_ * d.y);
            let (z_lo, z_hi) = robot
                .reach_at(leg, body)
                .expect("foot within its leg's range");
            let r = robot.foot_radius[leg];
            lo = lo.max(r - z_hi);
            hi = hi.min(r - z_lo);
        }
        assert!(lo <= hi, "no body height suits every foot at {c:?}");
    }
}

#[test]
fn straddled_patch_leaves_cg_cells_valid_and_a_large_region_grows_a_border() {
    // A 3 m patch of spikes too steep to stand on at (10, 0), and a 12 x 12 m steep field
    // about (26, 0).
    let t = common::terrain(0.0, 40.0, -12.0, 12.0, 0.1, |x, y| {
        let small = (x - 10.0).abs() < 1.5 && y.abs() < 1.5;
        let big = (x - 26.0).abs() < 6.0 && y.abs() < 6.0;
        if small || big {
            if ((x * 10.0).round() as i64 + (y * 10.0).round() as i64) % 2 == 0 {
                0.4
            } else {
                0.0
            }
        } else {
            0.0
        }
    });
    let mut space = ambler_space(&t);
    let grid = *space.grid();
    let foot = space.foot().clone();
    let (px, py) = grid.xy_of(Point2::new(10.0, 0.0));
    assert!(!foot.valid(px, py), "the patch is no foothold");
    // The Ambler straddles the small patch: every heading valid over it.
    for it in 0..grid.theta_bins {
        for dx in -1..=1 {
            for dy in -1..=1 {
                let c = tca_cg_space::CgCell::new(px + dx, py + dy, it);
                assert!(
                    space.is_valid(c),
                    "{c:?} over the small patch: {:?}",
                    space.verdict(c)
                );
            }
        }
    }
    // Over the middle of the big field no stance exists...
    let (bx, by) = grid.xy_of(Point2::new(26.0, 0.0));
    assert!(!space.is_valid(tca_cg_space::CgCell::new(bx, by, 0)));
    // ...and going west from it, the first valid CG cell lies beyond the last invalid foot
    // cell: a border of invalid CG cells over good footing, where one side has no support.
    let mut last_bad_foot = bx;
    while !foot.valid(last_bad_foot - 1, by) {
        last_bad_foot -= 1;
    }
    let mut first_valid = bx;
    while !space.is_valid(tca_cg_space::CgCell::new(first_valid, by, 0)) {
        first_valid -= 1;
    }
    assert!(
        first_valid < last_bad_foot - 1,
        "valid CG cell at column {first_valid}, field ends at {last_bad_foot}"
    );
    // Far from everything, valid.
    let (fx, fy) = grid.xy_of(Point2::new(4.0, 0.0));
    assert!(space.is_valid(tca_cg_space::CgCell::new(fx, fy, 0)));

    // The spider, whose feet reach at most 1.3 m from its centre, cannot straddle the
    // same patch: over its middle it has invalid CG cells; well away from it, none.
    let spider = RobotModel::builtin("spider").expect("the spider");
    let mut space = CgSpace::for_model(&spider, &t, CgParams::default()).expect("a CG-space");
    let grid = *space.grid();
    assert_eq!(
        grid.theta_bins, 1,
        "the spider is the same turned by an eighth"
    );
    let (px, py) = grid.xy_of(Point2::new(10.0, 0.0));
    let over_patch = (-3..=3)
        .flat_map(|dx| (-3..=3).map(move |dy| (dx, dy)))
        .filter(|&(dx, dy)| !space.is_valid(tca_cg_space::CgCell::new(px + dx, py + dy, 0)))
        .count();
    assert!(
        over_patch > 0,
        "the spider stands everywhere over the patch"
    );
    let (fx, fy) = grid.xy_of(Point2::new(4.0, 0.0));
    assert!(space.is_valid(tca_cg_space::CgCell::new(fx, fy, 0)));
}

#[test]
fn cliff_is_invalid_and_the_route_takes_the_ramp() {
    // The walking course's cliff: its ramp is wide enough for the Ambler to stand on with
    // every leg clear of the others (the search checks the legs' links against each other).
    let t = cliff_course();
    let mut space = ambler_space(&t);
    let grid = *space.grid();
    // Standing across the cliff face is impossible: feet at the base and on top.
    let (cx, cy) = grid.xy_of(Point2::new(14.0, 0.0));
    let v = space.verdict(tca_cg_space::CgCell::new(cx, cy, 0));
    assert!(
        matches!(v, Verdict::NoHeight | Verdict::EmptyQuadrant(_)),
        "{v:?}"
    );
    let p = plan(
        &mut space,
        (Point2::new(4.0, 0.0), 0.0),
        (Point2::new(24.0, 0.0), 0.0),
        None,
        &PlanParams::default(),
    )
    .expect("a plan by the ramp");
    let route = &p.feet.route;
    // Where the route crosses x = 14 m, it is on the ramp's side.
    for c in route {
        let at = grid.centre(c.ix, c.iy);
        if (at.x - 14.0).abs() < 1.0 {
            assert!(at.y > 2.0, "the route crosses the cliff at {at:?}");
        }
    }
    let foot = space.foot();
    for s in p.feet.stances() {
        for f in s.feet.iter().flatten() {
            assert!(foot.valid(f.0, f.1), "a foot on the cliff face at {f:?}");
        }
    }
}

#[test]
fn after_backing_off_from_where_the_search_stuck_the_plan_still_holds_together() {
    // The cliff course with the feedback backing off four cells from where a search got
    // stuck: the steps kept before the back-off and those searched after it make one plan
    // whose every stance stands, along one unbroken route that takes the ramp.
    let t = cliff_course();
    // One heading bin, as walks plan: the robot keeps facing +X.
    let mut space = ambler_one_heading(&t);
    let grid = *space.grid();
    let params = PlanParams {
        backoff_cells: 4,
        ..PlanParams::default()
    };
    let p = plan(
        &mut space,
        (Point2::new(4.0, 0.0), 0.0),
        (Point2::new(24.0, 0.0), 0.0),
        None,
        &params,
    )
    .expect("a plan by the ramp");
    assert!(p.routes > 1, "the feedback never ran: {} route", p.routes);
    let route = &p.feet.route;
    assert!(
        route
            .windows(2)
            .all(|w| grid.steps_between(w[0], w[1]) == 1),
        "the route is broken"
    );
    assert_eq!(
        route.first(),
        grid.cell_of(Point2::new(4.0, 0.0), 0.0).as_ref()
    );
    assert_eq!(
        route.last(),
        grid.cell_of(Point2::new(24.0, 0.0), 0.0).as_ref()
    );
    let stances = p.feet.stances();
    assert_eq!(stances.last().map(|s| s.k), Some(route.len() - 1));
    // Where the route crosses the cliff's line (x = 14 m), it is beside the ramp.
    for w in route.windows(2) {
        let (a, b) = (grid.centre(w[0].ix, w[0].iy), grid.centre(w[1].ix, w[1].iy));
        if (a.x < 14.0) != (b.x < 14.0) {
            assert!(
                a.y > 2.0 && b.y > 2.0,
                "the route crosses the cliff from {a:?} to {b:?}"
            );
        }
    }
    assert_every_stance_stands(&space, &p, false);
}

#[test]
fn walled_goal_is_reported_unreachable_quickly() {
    let t = common::walled_yard();
    let mut space = ambler_space(&t);
    let began = Instant::now();
    let r = plan(
        &mut space,
        (Point2::new(5.0, 0.0), 0.0),
        (Point2::new(20.0, 0.0), 0.0),
        None,
        &PlanParams::default(),
    );
    assert!(
        matches!(
            r,
            Err(CgError::Unreachable {
                enclosed: "goal",
                ..
            })
        ),
        "{r:?}"
    );
    assert!(began.elapsed() < Duration::from_secs(60));
}

#[test]
fn a_search_stuck_within_the_goals_tolerance_has_arrived() {
    // The cliff course with no replans allowed: the first foot search sticks before the
    // goal. Asking for the goal's own cell, that is the end of planning; with a tolerance
    // that takes in every cell the search reached, the plan ends on the furthest of them,
    // and it holds together as any plan does.
    let t = cliff_course();
    let mut space = ambler_one_heading(&t);
    let grid = *space.grid();
    let (start, goal) = (Point2::new(4.0, 0.0), Point2::new(24.0, 0.0));
    let exact = PlanParams {
        max_replans: 0,
        ..PlanParams::default()
    };
    let r = plan(&mut space, (start, 0.0), (goal, 0.0), None, &exact);
    assert!(
        matches!(r, Err(CgError::NoFootfalls { replans: 0, .. })),
        "the first search should stick on this course: {r:?}"
    );
    let tolerant = PlanParams {
        goal_tolerance_m: 100.0,
        ..exact
    };
    let p = plan(&mut space, (start, 0.0), (goal, 0.0), None, &tolerant)
        .expect("a plan that ends where the search stuck");
    assert_eq!(p.routes, 1, "no replan");
    assert!(p.marked.is_empty(), "no cell marked: {:?}", p.marked);
    let route = &p.feet.route;
    assert!(
        route.len() < p.first_route.cells.len(),
        "the plan ends before the route does"
    );
    assert_eq!(route[..], p.first_route.cells[..route.len()]);
    let stances = p.feet.stances();
    assert_eq!(stances.last().map(|s| s.k), Some(route.len() - 1));
    let end = route.last().expect("a route");
    let at = grid.centre(end.ix, end.iy);
    assert!(at.x > start.x + 1.0, "the walk got somewhere: {at:?}");
    assert_every_stance_stands(&space, &p, false);
}

#[test]
fn searches_that_stick_nearer_the_goal_do_not_use_up_the_replans() {
    // On the cliff course, with a search budget of 1,000 nodes, the plan marks three cells;
    // one of those searches got no nearer the goal than the one before it. A budget of two
    // such searches is enough (the others made progress), a budget of one is not.
    let t = cliff_course();
    let attempt = |max_replans: usize| {
        let mut space = ambler_one_heading(&t);
        let params = PlanParams {
            backoff_cells: 4,
            max_replans,
            search: SearchParams {
                stall_nodes: 1_000,
                ..SearchParams::default()
            },
            route: tca_cg_space::RouteParams {
                shortcut_cells: 0,
                ..Default::default()
            },
            ..PlanParams::default()
        };
        plan(
            &mut space,
            (Point2::new(4.0, 0.0), 0.0),
            (Point2::new(24.0, 0.0), 0.0),
            None,
            &params,
        )
    };
    let p = attempt(2).expect("a plan with two searches that got no nearer allowed");
    assert!(p.marked.len() > 2, "only {} cells marked", p.marked.len());
    match attempt(1) {
        Err(CgError::NoFootfalls { replans, .. }) => assert!(replans < p.marked.len()),
        other => panic!("one search that got no nearer allowed: {other:?}"),
    }
}

/// A check that lets every move through and remembers each it was asked about.
#[derive(Default)]
struct Recorder {
    asked: std::cell::RefCell<std::collections::HashSet<(Stance, Stance)>>,
}

impl MoveCheck for Recorder {
    fn check(&self, from: &Stance, _: CgCell, _: &FootStep, to: &Stance, _: CgCell) -> bool {
        self.asked.borrow_mut().insert((from.clone(), to.clone()));
        true
    }
}

#[test]
fn every_move_of_a_replanned_plan_was_put_to_the_check() {
    // With the feedback backing off after a stuck search, the steps kept from that search
    // are part of the plan: the outside check must have seen each of them, as it has seen
    // the moves of the searches that succeeded.
    let t = cliff_course();
    let mut space = ambler_one_heading(&t);
    let params = PlanParams {
        backoff_cells: 4,
        ..PlanParams::default()
    };
    let check = Recorder::default();
    let p = plan_checked(
        &mut space,
        (Point2::new(4.0, 0.0), 0.0),
        (Point2::new(24.0, 0.0), 0.0),
        None,
        &params,
        Some(&check),
    )
    .expect("a plan by the ramp");
    assert!(!p.marked.is_empty(), "the feedback never ran");
    let asked = check.asked.borrow();
    let mut at = p.feet.start.clone();
    for (i, step) in p.feet.steps.iter().enumerate() {
        let mut next = at.clone();
        apply_step(&mut next, step);
        assert!(
            asked.contains(&(at.clone(), next.clone())),
            "move {i} of {} ({step:?}) was never checked",
            p.feet.steps.len()
        );
        at = next;
    }
}

#[test]
fn a_goal_too_near_the_maps_edge_is_approached_within_the_tolerance() {
    // Flat ground ending at x = 20 m: with the goal 1 m from that edge the Ambler's
    // underside would reach past it, so the goal's own cell is invalid. Asked for that cell,
    // the planner says so; allowed 2 m, it plans to the nearest valid cell within them.
    let t = common::terrain(0.0, 20.0, -8.0, 8.0, 0.1, |_, _| 0.0);
    let mut space = ambler_space(&t);
    let grid = *space.grid();
    let (start, goal) = (Point2::new(10.0, 0.0), Point2::new(19.0, 0.0));
    let g = grid.cell_of(goal, 0.0).expect("on the map");
    assert_eq!(space.verdict(g), Verdict::OffMap);
    let exact = PlanParams::default();
    match plan(&mut space, (start, 0.0), (goal, 0.0), None, &exact) {
        Err(CgError::InvalidEndpoint { what, reason, .. }) => {
            assert_eq!(what, "goal");
            assert!(reason.contains("map's edge"), "{reason}");
        }
        other => panic!("the goal's own cell is invalid: {other:?}"),
    }
    let tolerant = PlanParams {
        goal_tolerance_m: 2.0,
        ..PlanParams::default()
    };
    let p = plan(&mut space, (start, 0.0), (goal, 0.0), None, &tolerant)
        .expect("a plan to a cell near the goal");
    let end = *p.feet.route.last().expect("a route");
    let at = grid.centre(end.ix, end.iy);
    assert!((at - goal).norm() <= 2.0, "ends at {at:?}");
    assert!(space.verdict(end).is_valid());
}
