//! A few pairs of the acceptance campaign (the full hundred is `tca footfall campaign`).

use tca_footfall::campaign::{CampaignParams, run_campaign};

#[test]
fn a_few_pairs_plan_check_and_show_the_sag_lesson() {
    let params = CampaignParams {
        pairs: 4,
        seed: 3,
        ..CampaignParams::default()
    };
    let report = run_campaign(&params, |_, _| {}).unwrap();
    let s = &report.summary;
    println!("{s:#?}");
    assert_eq!(s.pairs, 4);
    assert!(s.feasible >= 3, "{s:?}");
    assert_eq!(s.sbl_successes, s.feasible);
    assert_eq!(s.sbl_checked, s.sbl_plans);
    assert!(s.sbl_max_waypoints <= 5);
    assert_eq!(s.sag_collisions_with, 0);
    assert_eq!(s.sag_runs_with, s.sbl_plans);
    assert!(s.sag_collisions_without > 0);
    assert_eq!(s.rigid_collisions_without, 0);
    for p in &report.pairs {
        if let Some(e) = &p.sag_with_heuristics {
            assert!(e.landed, "{p:?}");
        }
        if let Some(e) = &p.rigid_without_heuristics {
            assert!(e.landed, "{p:?}");
        }
    }
}
