//! Properties of the grid, A* and the flood on random terrains.

use crate::common;

use std::sync::{Arc, OnceLock};

use proptest::prelude::*;
use tca_cg_space::astar::route_cost;
use tca_cg_space::route::{RouteParams, roadmap, shortcut};
use tca_cg_space::{Block, CgCell, CgParams, CgRobot, CgSpace, Flood, astar, flood};
use tca_legged_model::RobotModel;

fn ambler() -> Arc<CgRobot> {
    static ROBOT: OnceLock<Arc<CgRobot>> = OnceLock::new();
    ROBOT
        .get_or_init(|| {
            let model = RobotModel::builtin("ambler").expect("the Ambler");
            Arc::new(CgRobot::new(&model, 0.1, CgParams::default()).expect("tables"))
        })
        .clone()
}

/// A 14 x 14 m map with tall blocks at the given places.
fn blocks(at: &[(f64, f64)]) -> tca_robot::HeightField {
    let at = at.to_vec();
    common::terrain(0.0, 14.0, 0.0, 14.0, 0.1, move |x, y| {
        if at
            .iter()
            .any(|(bx, by)| (x - bx).abs() < 1.0 && (y - by).abs() < 1.0)
        {
            4.0
        } else {
            0.0
        }
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    #[test]
    fn a_cell_centre_falls_in_its_cell(ix in 0i32..40, iy in 0i32..40, it in 0u16..8) {
        let t = blocks(&[]);
        let space = CgSpace::new(ambler(), &t).unwrap();
        let g = *space.grid();
        let c = CgCell::new(ix.min(g.nx - 1), iy.min(g.ny - 1), it);
        prop_assert_eq!(g.cell_of(g.centre(c.ix, c.iy), g.theta(c.it)), Some(c));
    }

    #[test]
    fn astar_and_the_flood_agree(
        obstacles in proptest::collection::vec((3.0f64..11.0, 3.0f64..11.0), 0..6),
        a in (0i32..8, 0i32..8), b in (0i32..8, 0i32..8), ta in 0u16..8, tb in 0u16..8,
    ) {
        let t = blocks(&obstacles);
        let mut space = CgSpace::new(ambler(), &t).unwrap();
        let g = *space.grid();
        // Ends in the corners' quarters, where the Ambler fits.
        let from = CgCell::new(14 + a.0, 14 + a.1, ta);
        let to = CgCell::new(g.nx - 15 - b.0, g.ny - 15 - b.1, tb);
        prop_assume!(space.is_valid(from) && space.is_valid(to));
        let whole = Block::whole(&space);
        let found = astar(&mut space, from, to, whole);
        let flooded = flood(&mut space, from, to, usize::MAX);
        match (&found.route, &flooded) {
            (Some(route), Flood::Met(other)) => {
                prop_assert_eq!(route.first(), Some(&from));
                prop_assert_eq!(route.last(), Some(&to));
                for w in route.windows(2) {
                    prop_assert_eq!(g.steps_between(w[0], w[1]), 1);
                }
                for c in route {
                    prop_assert!(space.is_valid(*c));
                }
                // The flood's route is shortest in moves; A*'s is the cheapest, turns costing
                // more than moves in x and y.
                prop_assert!(route.len() >= other.len());
                prop_assert!(route_cost(route) <= route_cost(other));
            }
            (None, Flood::Enclosed { .. }) => {}
            (r, f) => prop_assert!(false, "A* {:?} but flood {:?}", r.as_ref().map(Vec::len), f),
        }
    }

    #[test]
    fn a_cut_route_holds_together_and_costs_no_more(
        obstacles in proptest::collection::vec((3.0f64..11.0, 3.0f64..11.0), 0..4),
        seed in 0u64..1000, ta in 0u16..8, tb in 0u16..8, span in 4usize..80,
    ) {
        let t = blocks(&obstacles);
        let mut space = CgSpace::new(ambler(), &t).unwrap();
        let g = *space.grid();
        let from = CgCell::new(15, 15, ta);
        let to = CgCell::new(g.nx - 16, g.ny - 16, tb);
        prop_assume!(space.is_valid(from) && space.is_valid(to));
        let params = RouteParams { seed, shortcut_cells: span, ..RouteParams::default() };
        let Some(found) = roadmap(&mut space, from, to, &params) else {
            return Ok(());
        };
        let cut = shortcut(&mut space, &found.cells, &params);
        prop_assert_eq!(cut.first(), Some(&from));
        prop_assert_eq!(cut.last(), Some(&to));
        for w in cut.windows(2) {
            prop_assert_eq!(g.steps_between(w[0], w[1]), 1);
        }
        for c in &cut {
            prop_assert!(space.is_valid(*c));
        }
        prop_assert!(route_cost(&cut) <= route_cost(&found.cells));
    }

    #[test]
    fn a_marked_cell_is_avoided(k in 2usize..10) {
        let t = blocks(&[]);
        let mut space = CgSpace::new(ambler(), &t).unwrap();
        let from = CgCell::new(15, 20, 0);
        let to = CgCell::new(28, 20, 0);
        let first = astar(&mut space, from, to, Block::about(from, to, 3)).route.unwrap();
        let bad = first[k];
        space.mark_invalid(bad);
        let second = astar(&mut space, from, to, Block::about(from, to, 3)).route.unwrap();
        prop_assert!(!second.contains(&bad));
        prop_assert!(second.len() >= first.len());
    }
}

#[test]
fn a_region_cap_bounds_the_memory_and_keeps_the_answers() {
    let t = blocks(&[(7.0, 7.0)]);
    let mut free = CgSpace::new(ambler(), &t).unwrap();
    let mut capped = CgSpace::new(ambler(), &t).unwrap().with_region_cap(Some(1));
    let g = *free.grid();
    for iy in (0..g.ny).step_by(3) {
        for ix in (0..g.nx).step_by(3) {
            let c = CgCell::new(ix, iy, (ix % 8) as u16);
            assert_eq!(free.is_valid(c), capped.is_valid(c));
            assert!(capped.regions_held() <= 1);
        }
    }
    assert!(free.regions_held() > 1);
    assert!(capped.regions_materialised() > free.regions_materialised());
}

#[test]
fn a_detour_and_its_turns_are_cut() {
    let t = blocks(&[]);
    let mut space = CgSpace::new(ambler(), &t).unwrap();
    // Up 10 cells, a turn there and back, 15 across, down 10: 35 moves and two turns.
    let mut detour = Vec::new();
    detour.extend((15..=25).map(|iy| CgCell::new(15, iy, 0)));
    detour.push(CgCell::new(15, 25, 1));
    detour.extend((15..=30).map(|ix| CgCell::new(ix, 25, 0)));
    detour.extend((15..25).rev().map(|iy| CgCell::new(30, iy, 0)));
    assert!(detour.iter().all(|c| space.is_valid(*c)));
    assert_eq!(route_cost(&detour), 35 + 2 * tca_cg_space::astar::TURN_COST);
    let cut = shortcut(&mut space, &detour, &RouteParams::default());
    assert_eq!(cut.first(), Some(&CgCell::new(15, 15, 0)));
    assert_eq!(cut.last(), Some(&CgCell::new(30, 15, 0)));
    assert_eq!(route_cost(&cut), 15, "straight across: {cut:?}");
    assert!(cut.iter().all(|c| c.it == 0));
    // With cutting off, the route is kept as it was.
    let off = RouteParams {
        shortcut_cells: 0,
        ..RouteParams::default()
    };
    assert_eq!(shortcut(&mut space, &detour, &off), detour);
}
