//! Task-tree throughput and memory.
//!
//! - `add_dispatch_complete/walk_250k_steps`: the walking tree of Figure 5 (4 nodes a
//!   step under one walk goal, with the concurrent-mode constraints), 250,000 steps =
//!   1,000,001 nodes added, dispatched and completed through the discrete-event driver of
//!   the tests (module queues and capacities included in the time).
//! - `add_dispatch_complete/plan_1m_nodes`: a plan built up front (1 root, 1,000 goals in
//!   sequential achievement, 999 commands each in sequential achievement) = 1,000,001
//!   nodes live at once, then dispatched and completed.
//! - memory: live nodes and the tree's own byte estimate at their peak over 1,000 and
//!   10,000 walking steps, printed before the timings (with the process's peak resident
//!   set, which only grows).
//!
//! Run: `CARGO_TARGET_DIR=/work/target-task-tree cargo bench -p tca-task-tree --bench tree`.

#[path = "../tests/integration/common/walking.rs"]
mod walking;

use std::collections::VecDeque;
use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use tca_task_tree::{NewConstraint, NodeId, NodeSpec, Outcome, TaskTree, TreeEvent};
use walking::{Durations, Mode, WalkSim};

const INSTANT: Durations = Durations {
    walk: 0,
    plan_gait: 0,
    lrp: 0,
    leg_move: 0,
    base_move: 0,
};

/// Walks `steps` steps; returns nodes added.
fn walk(steps: u32) -> u64 {
    let mut sim = WalkSim::new(Mode::Concurrent, steps, INSTANT);
    sim.run();
    assert!(sim.tree.is_empty());
    sim.nodes_added
}

fn ready_in(events: &[TreeEvent], queue: &mut VecDeque<NodeId>) {
    queue.extend(events.iter().filter_map(|e| match e {
        TreeEvent::Ready(id) => Some(*id),
        _ => None,
    }));
}

/// Builds the whole plan, then runs every ready node to completion; returns nodes added
/// and the tree's byte estimate with the whole plan live.
fn plan(goals: u32, commands_per_goal: u32) -> (u64, usize) {
    let mut tree = TaskTree::new();
    let mut queue = VecDeque::new();
    let mut now = 0;
    let (root, events) = tree
        .add_node(NodeSpec::goal("plan", "planner"), now)
        .expect("root");
    ready_in(&events, &mut queue);
    let mut added = 1;
    let mut previous_goal = None;
    for _ in 0..goals {
        let mut spec = NodeSpec::goal("step", "planner").under(root);
        if let Some(p) = previous_goal {
            spec = spec.with(NewConstraint::sequential_achievement_after(p));
        }
        let (goal, events) = tree.add_node(spec, now).expect("goal");
        ready_in(&events, &mut queue);
        added += 1;
        previous_goal = Some(goal);
        let mut previous = None;
        for _ in 0..commands_per_goal {
            let mut spec = NodeSpec::command("move", "controller").under(goal);
            if let Some(p) = previous {
                spec = spec.with(NewConstraint::sequential_achievement_after(p));
            }
            let (cmd, events) = tree.add_node(spec, now).expect("command");
            ready_in(&events, &mut queue);
            added += 1;
            previous = Some(cmd);
        }
    }
    let bytes = tree.estimated_bytes();
    while let Some(id) = queue.pop_front() {
        if !tree.is_ready(id) {
            continue;
        }
        now += 1;
        let events = tree.start(id, now).expect("start");
        ready_in(&events, &mut queue);
        let events = tree.finish(id, Outcome::Success, now).expect("finish");
        ready_in(&events, &mut queue);
    }
    assert!(tree.is_empty(), "plan did not complete");
    (added, bytes)
}

/// The process's peak resident set in KiB, from /proc (Linux only).
fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn memory_report() {
    for steps in [1_000u32, 10_000] {
        let mut sim = WalkSim::new(Mode::Concurrent, steps, Durations::HAND);
        sim.run();
        println!(
            "memory: {steps:>6} walking steps: {} nodes added, peak live nodes {}, peak estimated bytes {}, process peak RSS {} KiB",
            sim.nodes_added,
            sim.peak_live,
            sim.peak_bytes,
            peak_rss_kib().map_or("?".to_string(), |k| k.to_string()),
        );
    }
    let (nodes, bytes) = plan(1_000, 999);
    println!(
        "memory: plan of {nodes} live nodes: estimated {bytes} bytes ({} bytes a node)",
        bytes / nodes as usize
    );
}

fn benches(c: &mut Criterion) {
    memory_report();
    let mut group = c.benchmark_group("add_dispatch_complete");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(30));
    group.throughput(Throughput::Elements(1_000_001));
    group.bench_function("walk_250k_steps", |b| b.iter(|| black_box(walk(250_000))));
    group.bench_function("plan_1m_nodes", |b| b.iter(|| black_box(plan(1_000, 999))));
    group.finish();
}

criterion_group!(tree_benches, benches);
criterion_main!(tree_benches);
