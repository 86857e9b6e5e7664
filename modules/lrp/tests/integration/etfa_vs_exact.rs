//! The ETFA against an exact search over (shoulder, elbow, foot height) at four times its
//! resolution, on small random terrains (§6.3): its trajectories never collide, it finds a
//! trajectory exactly when one exists, and its cost is within the 8% grid-bias bound of the
//! optimum.

use crate::common;

use common::*;
use tca_lrp::PlanError;
use tca_lrp::exact::{ExactOptions, exact_search};
use tca_lrp::trajectory::check_clearance;
use tca_robot::ElbowBranch;

#[test]
fn etfa_cost_is_within_eight_percent_of_the_exact_optimum() {
    // Without the minimum initial lift: the exact search knows nothing of it.
    let p = tca_lrp::LegRecoveryPlanner::new(
        tca_robot::LegParams::default(),
        tca_lrp::LrpParams {
            start_lift_m: 0.0,
            ..tca_lrp::LrpParams::default()
        },
    )
    .unwrap();
    let model = p.params().cost;
    let mut compared = 0;
    let mut worst: f64 = 0.0;
    for seed in 0..20 {
        let (terrain, a, b) = random_scene(seed);
        let map = map_around(&terrain, 4.0);
        let cs = p.cspace(&map, 4.0).unwrap();
        let start = planted(&terrain, 4.0, a, ElbowBranch::Positive);
        let goal = footfall(&terrain, b);
        let plan = p.plan_in(&cs, &start, &goal);
        let plan = match plan {
            Ok(plan) => plan,
            Err(PlanError::Unreachable { .. }) => {
                // The exact search must agree that there is no way.
                let goal_q = kin()
                    .inverse_world(
                        &tca_robot::CarriagePose::level(4.0),
                        &goal,
                        ElbowBranch::Positive,
                    )
                    .unwrap();
                let none = exact_search(
                    &cs,
                    &model,
                    [start.shoulder_rad, start.elbow_rad, cs.foot_z_m(&start)],
                    [goal_q.shoulder_rad, goal_q.elbow_rad, goal.z],
                    &ExactOptions::default(),
                );
                assert!(
                    none.is_none(),
                    "seed {seed}: exact found a way the ETFA did not"
                );
                continue;
            }
            Err(e) => panic!("seed {seed}: {e}"),
        };
        check_clearance(&cs, &plan.points).unwrap();
        let end = plan.points.last().copied().unwrap();
        let exact = exact_search(&cs, &model, plan.points[0], end, &ExactOptions::default())
            .unwrap_or_else(|| panic!("seed {seed}: the exact search found nothing"));
        check_clearance(&cs, &exact.points).unwrap();
        let ratio = plan.cost / exact.cost;
        eprintln!(
            "seed {seed}: ETFA {:.2} (time {:.1} s, {:.0} J, {} turns) exact {:.2} (time {:.1} s, {:.0} J)",
            plan.cost,
            plan.motion.time_s,
            plan.motion.energy_j,
            plan.turns,
            exact.cost,
            exact.motion.time_s,
            exact.motion.energy_j,
        );
        worst = worst.max(ratio);
        assert!(
            ratio <= 1.08,
            "seed {seed}: ETFA {:.2} vs exact {:.2} ({:.1}% worse)",
            plan.cost,
            exact.cost,
            100.0 * (ratio - 1.0)
        );
        // The reference is optimal up to its lattice (steps of 0.2 s of any joint): the ETFA
        // can beat it only by that resolution.
        assert!(
            ratio >= 0.97,
            "seed {seed}: ETFA {:.2} beats exact {:.2}",
            plan.cost,
            exact.cost
        );
        compared += 1;
    }
    assert!(compared >= 12, "only {compared} scenes compared");
    eprintln!("worst ETFA / exact cost ratio: {worst:.4}");
}
