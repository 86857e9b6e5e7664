//! Properties of the grid, A* and the flood on random terrains.

use crate::common;

use std::sync::{Arc, OnceLock};

use proptest::prelude::*;
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
                // Both are shortest in unit moves.
                prop_assert_eq!(route.len(), other.len());
            }
            (None, Flood::Enclosed { .. }) => {}
            (r, f) => prop_assert!(false, "A* {:?} but flood {:?}", r.as_ref().map(Vec::len), f),
        }
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
