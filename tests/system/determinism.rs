//! The same walk, twice, gives the same traffic log: every frame in the same order, with the
//! same data and the same simulated stamps, sequential and concurrent (central releases every
//! message in simulated-time order, one at a time, and each module's computing is modelled
//! under `--compute paper`, so nothing in the log depends on how fast this machine is or how
//! its threads are scheduled).

use std::path::Path;

use crate::common::within;
use tca_logs::{LogFile, RecordKind};
use tca_messages::is_simulated_stamp;
use tca_single_leg_messages::WalkMode;
use tca_walk::{ComputeModel, TerrainChoice, WalkOptions};
use tokio::sync::mpsc;

/// One frame as the comparison sees it: direction, link, peer and the whole envelope, with
/// wall-clock stamps (hellos and registrations, stamped before a module knows any simulated
/// time) set to zero.
fn frames(path: &Path) -> Vec<String> {
    let log = LogFile::open(path).expect("the walk's log reads back");
    assert!(log.truncated.is_none(), "{:?}", log.truncated);
    log.records
        .iter()
        .filter_map(|r| match &r.kind {
            RecordKind::Frame(f) => {
                let mut env = LogFile::envelope(f).expect("every frame decodes");
                if !is_simulated_stamp(env.timestamp_ns) {
                    env.timestamp_ns = 0;
                }
                Some(format!(
                    "{:?} link {} {:?} {:?} t={} ctx={:?} node={:?} re={:?} opts={:?} data={:?}",
                    f.direction,
                    f.link,
                    f.peer,
                    env,
                    env.timestamp_ns,
                    env.context,
                    env.node,
                    env.correlation,
                    env.options,
                    env.data
                ))
            }
            _ => None,
        })
        .collect()
}

async fn walk_to(dir: &Path, mode: WalkMode) {
    let options = WalkOptions {
        terrain: TerrainChoice::Course(3),
        goal_y_m: None,
        backward: false,
        mode,
        seed: 1,
        out: Some(dir.to_owned()),
        step_pictures: false,
        connect: None,
        compute: ComputeModel::Paper,
        fault: None,
        rigid: false,
        body_move_law: Default::default(),
        attach: None,
    };
    let (tx, _rx) = mpsc::unbounded_channel();
    let report = within("walk", tca_walk::walk(&options, tx))
        .await
        .expect("the walk runs");
    assert!(report.reached, "{report:#?}");
}

/// Walks twice in `mode` and compares the logs.
async fn twice(mode: WalkMode) {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    walk_to(&a, mode).await;
    walk_to(&b, mode).await;
    let (fa, fb) = (
        frames(&a.join("traffic.mcap")),
        frames(&b.join("traffic.mcap")),
    );
    assert!(fa.len() > 100, "{} frames", fa.len());
    if let Some(i) = fa.iter().zip(&fb).position(|(x, y)| x != y) {
        panic!(
            "{mode:?}: the logs part at frame {i} of {}:\nfirst:  {}\nsecond: {}",
            fa.len(),
            fa[i],
            fb[i]
        );
    }
    assert_eq!(fa.len(), fb.len(), "{mode:?}: one log is longer");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_same_sequential_walk_twice_gives_the_same_log() {
    twice(WalkMode::Sequential).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_same_concurrent_walk_twice_gives_the_same_log() {
    twice(WalkMode::Concurrent).await;
}
