//! The courses are what the paper's tests had: the ramps course is reachable only over its
//! ramps; the hill is too steep to climb and can be walked round.

use nalgebra::Point2;
use tca_nav_dstar_lite::{Cell, CostGrid, DStarLite, PlanError};
use tca_nav_navigator::{hill_course, ramps_course, true_danger_map, wheeled_params};

/// D* Lite from the course's start to its goal on the true danger map with the cells
/// `blocked` says made untraversable: the path's cells, or `None` when there is none.
fn plan(
    course: &tca_nav_navigator::Course,
    blocked: impl Fn(Point2<f64>) -> bool,
) -> Option<Vec<Point2<f64>>> {
    let params = wheeled_params();
    let truth = true_danger_map(&course.terrain, &params).unwrap();
    let cells = truth.cells();
    let dangers = cells
        .iter()
        .map(|(c, d)| {
            if blocked(cells.cell_center(c)) {
                f64::INFINITY
            } else {
                d.danger
            }
        })
        .collect();
    let grid = CostGrid::from_dangers(cells.nx(), cells.ny(), params.beta, dangers).unwrap();
    let start = Point2::new(course.start.x, course.start.y);
    let goal = start + nalgebra::Vector2::new(course.goal_offset[0], course.goal_offset[1]);
    let (s, g) = (cells.nearest_cell(start), cells.nearest_cell(goal));
    let mut planner = DStarLite::new(grid, Cell::new(s.ix, s.iy), Cell::new(g.ix, g.iy)).unwrap();
    match planner.plan() {
        Ok(p) => Some(
            p.cells
                .iter()
                .map(|c| cells.cell_center(tca_robot::CellIndex::new(c.ix, c.iy)))
                .collect(),
        ),
        Err(PlanError::NoPath { .. }) => None,
        Err(e) => panic!("{e}"),
    }
}

#[test]
fn the_ramps_course_is_crossed_only_over_its_ramps() {
    let course = ramps_course().unwrap();
    // The goal is 0.8 m to the left and 2.8 m ahead, as in the paper.
    assert_eq!(course.goal_offset, [2.8, 0.8]);
    let path = plan(&course, |_| false).expect("the ramps lead to the goal");
    // Where the path crosses the platform (x 1.8 to 2.2 m) it is on the ramps' band.
    let on_platform: Vec<_> = path.iter().filter(|p| (1.8..=2.2).contains(&p.x)).collect();
    assert!(!on_platform.is_empty());
    assert!(
        on_platform.iter().all(|p| (0.2..=1.2).contains(&p.y)),
        "{on_platform:?}"
    );
    // With the ramps' band closed there is no way at all.
    let no_ramps = |p: Point2<f64>| (1.0..=3.0).contains(&p.x) && (0.2..=1.2).contains(&p.y);
    assert_eq!(plan(&course, no_ramps), None);
}

#[test]
fn the_hill_cannot_be_climbed_and_can_be_walked_round() {
    let course = hill_course().unwrap();
    assert_eq!(course.goal_offset, [1.4, 0.0]);
    let params = wheeled_params();
    let truth = true_danger_map(&course.terrain, &params).unwrap();
    let top = truth.cells().nearest_cell(Point2::new(1.25, 1.1));
    assert!(
        !truth.cell(top).is_traversable(),
        "the hill's top is untraversable"
    );
    let path = plan(&course, |_| false).expect("a way round the hill");
    assert!(
        path.iter()
            .all(|p| (p - Point2::new(1.25, 1.1)).norm() > 0.3)
    );
}
