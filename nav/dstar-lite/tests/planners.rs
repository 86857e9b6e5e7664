//! D* Lite against A*: equal minimum costs after random map changes and start moves,
//! untraversable cells never entered, blocked goals reported.

use proptest::prelude::*;
use tca_nav_dstar_lite::{Cell, CostGrid, DStarLite, PlanError, astar};

fn grid_from(nx: usize, ny: usize, cells: &[(f64, bool)]) -> CostGrid {
    let dangers = cells
        .iter()
        .map(|&(d, blocked)| if blocked { f64::INFINITY } else { d })
        .collect();
    CostGrid::from_dangers(nx, ny, 2.0, dangers).unwrap()
}

fn assert_same(
    d: Result<tca_nav_dstar_lite::Path, PlanError>,
    a: Result<tca_nav_dstar_lite::Path, PlanError>,
    grid: &CostGrid,
) {
    match (d, a) {
        (Ok(d), Ok(a)) => {
            assert!(
                (d.cost - a.cost).abs() <= 1e-9 * a.cost.max(1.0),
                "D* Lite cost {} differs from A* cost {}",
                d.cost,
                a.cost
            );
            for c in &d.cells[1..] {
                assert!(
                    grid.danger(*c).is_finite(),
                    "path enters untraversable cell {c:?}"
                );
            }
            for w in d.cells.windows(2) {
                assert!(w[0].ix.abs_diff(w[1].ix) <= 1 && w[0].iy.abs_diff(w[1].iy) <= 1);
            }
        }
        (Err(PlanError::NoPath { .. }), Err(PlanError::NoPath { .. })) => {}
        (d, a) => panic!("D* Lite gave {d:?} but A* gave {a:?}"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn dstar_lite_cost_equals_astar_after_random_changes(
        nx in 3usize..24,
        ny in 3usize..24,
        seed_cells in prop::collection::vec((0.0f64..1.0, prop::bool::weighted(0.2)), 24 * 24),
        start in (0usize..24, 0usize..24),
        goal in (0usize..24, 0usize..24),
        rounds in prop::collection::vec(
            (prop::collection::vec(((0usize..24, 0usize..24), 0.0f64..1.0, prop::bool::weighted(0.3)), 1..30), 0usize..4),
            1..5,
        ),
    ) {
        let cells = &seed_cells[..nx * ny];
        let start = Cell::new(start.0 % nx, start.1 % ny);
        let goal = Cell::new(goal.0 % nx, goal.1 % ny);
        let grid = grid_from(nx, ny, cells);
        let mut dstar = DStarLite::new(grid.clone(), start, goal).unwrap();
        assert_same(dstar.plan(), astar(&grid, start, goal), &grid);
        for (changes, steps) in rounds {
            // The robot walks a few cells along its path before the map changes.
            if let Ok(path) = dstar.plan() {
                let next = path.cells[steps.min(path.cells.len() - 1)];
                dstar.move_start(next).unwrap();
            }
            for ((x, y), d, blocked) in changes {
                let c = Cell::new(x % nx, y % ny);
                dstar.set_danger(c, if blocked { f64::INFINITY } else { d }).unwrap();
            }
            let grid = dstar.grid().clone();
            let s = dstar.start();
            assert_same(dstar.plan(), astar(&grid, s, goal), &grid);
        }
    }
}

#[test]
fn a_wall_is_gone_around_and_a_closed_wall_means_no_path() {
    let mut grid = CostGrid::filled(20, 20, 2.0, 0.0).unwrap();
    for iy in 0..19 {
        grid.set_danger(Cell::new(10, iy), f64::INFINITY).unwrap();
    }
    let (start, goal) = (Cell::new(2, 2), Cell::new(17, 2));
    let mut dstar = DStarLite::new(grid.clone(), start, goal).unwrap();
    let path = dstar.plan().unwrap();
    assert!(
        path.cells.iter().any(|c| c.iy == 19),
        "the path goes through the gap"
    );
    assert!(path.cells.iter().all(|c| grid.danger(*c).is_finite()));
    dstar.set_danger(Cell::new(10, 19), f64::INFINITY).unwrap();
    assert!(matches!(dstar.plan(), Err(PlanError::NoPath { .. })));
    assert!(matches!(
        astar(dstar.grid(), start, goal),
        Err(PlanError::NoPath { .. })
    ));
    // Opening the wall again gives the straight way back.
    dstar.set_danger(Cell::new(10, 2), 0.5).unwrap();
    let path = dstar.plan().unwrap();
    assert_eq!(path.cells.len(), 16);
    assert!((path.cost - (15.0 + 2.0 * 0.5)).abs() < 1e-12);
}

#[test]
fn danger_is_weighed_against_length() {
    // A block of danger 1, three cells deep, across the straight way: with beta = 2 its
    // crossing costs 6 more than open ground, a detour of 2.5 more is taken.
    let mut dangers = vec![0.0; 121];
    for iy in 3..8 {
        for ix in 4..7 {
            dangers[iy * 11 + ix] = 1.0;
        }
    }
    let grid = CostGrid::from_dangers(11, 11, 2.0, dangers.clone()).unwrap();
    let path = astar(&grid, Cell::new(0, 5), Cell::new(10, 5)).unwrap();
    assert!(
        path.cells.iter().all(|c| grid.danger(*c) == 0.0),
        "{:?}",
        path.cells
    );
    // With beta = 0 danger costs nothing and the straight way is taken.
    let free = CostGrid::from_dangers(11, 11, 0.0, dangers).unwrap();
    let straight = astar(&free, Cell::new(0, 5), Cell::new(10, 5)).unwrap();
    assert_eq!(straight.cells.len(), 11);
    assert!((straight.cost - 10.0).abs() < 1e-12);
}

#[test]
fn bad_input_is_refused_with_reasons() {
    assert!(matches!(
        CostGrid::filled(0, 3, 2.0, 0.0),
        Err(PlanError::EmptyGrid { .. })
    ));
    assert!(matches!(
        CostGrid::filled(3, 3, -1.0, 0.0),
        Err(PlanError::BadBeta(_))
    ));
    let e = CostGrid::from_dangers(2, 1, 2.0, vec![0.0, f64::NAN]).unwrap_err();
    assert!(e.to_string().contains("cell (1, 0)"), "{e}");
    let grid = CostGrid::filled(3, 3, 2.0, 0.0).unwrap();
    let e = DStarLite::new(grid, Cell::new(3, 0), Cell::new(0, 0)).unwrap_err();
    assert!(e.to_string().contains("outside the 3 x 3 grid"), "{e}");
}
