//! A CG-space walk whose route joins run on worker modules: the walk reaches its goal as
//! without them, the joins are the walking handler's own queries in the log (so central's
//! simulated clock counts the handler as waiting for them), and the log passes the audit and
//! the time check.

use crate::walk::Progress;
use crate::{LeggedPlanner, LeggedTerrain, LeggedWalkOptions, WalkWorkers, walk};
use tca_cg_space::PlanParams;
use tca_logs::{Direction, LogFile, RecordKind};
use tca_messages::Class;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_ambler_walks_the_cliff_with_its_route_joins_on_two_workers() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let mut plan = PlanParams::default();
    // A flood too short to settle the route, so that the roadmap (and so the workers) finds
    // it.
    plan.route.flood_budget = 50;
    let options = LeggedWalkOptions {
        terrain: Some(LeggedTerrain::Course {
            name: "cliff".into(),
            seed: 1,
        }),
        planner: LeggedPlanner::CgSpace,
        out: Some(dir.path().to_path_buf()),
        cg_workers: Some(WalkWorkers {
            count: 2,
            region_cap: None,
            program: None,
        }),
        cg_plan: Some(plan),
        ..LeggedWalkOptions::new("ambler")
    };
    let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel::<Progress>();
    let drain = tokio::spawn(async move { while rx.recv().await.is_some() {} });
    let report = walk(&options, tx).await.expect("the walk runs");
    drain.abort();
    assert!(report.reached, "{:?}", report.reason);
    assert_eq!((report.falls, report.collisions), (0, 0));
    assert!(
        report.state_problems.is_empty(),
        "{:?}",
        report.state_problems
    );

    let log = LogFile::open(&dir.path().join("traffic.mcap")).expect("the walk's log");
    let joins: Vec<_> = log
        .records
        .iter()
        .filter_map(|r| match &r.kind {
            RecordKind::Frame(f) if f.direction == Direction::In => LogFile::envelope(f).ok(),
            _ => None,
        })
        .filter(|e| e.class == Class::Query && e.name.as_str().starts_with("cgspace.join."))
        .collect();
    assert!(!joins.is_empty(), "no join was asked of the workers");
    // Both workers had a share, and every join was asked by the walking module itself.
    for k in 0..2 {
        let name = format!("cgspace.join.{k}");
        assert!(
            joins.iter().any(|e| e.name.as_str() == name),
            "worker {k} was never asked"
        );
    }
    assert!(
        joins.iter().all(|e| e.sender.as_str() == "gait"),
        "joins asked by {:?}",
        joins.iter().map(|e| e.sender.as_str()).collect::<Vec<_>>()
    );
    let audit = tca_logs::audit(&log);
    assert!(audit.lost.is_empty(), "{}", audit.text());
    let time = tca_logs::time_check(&log);
    assert!(time.holds(), "{}", time.text());
}
