//! The walking task tree of Figure 5 (the report, §3.2–§3.3), sequential and concurrent,
//! its replay, and its memory over long runs.

use crate::common;

use common::walking::{Durations, Mode, Role, WalkSim};
use tca_task_tree::{TaskTree, TreeEvent, TreeOp};

fn starts(mode: Mode, steps: u32) -> (Vec<(u64, Role)>, u64, WalkSim) {
    let mut sim = WalkSim::new(mode, steps, Durations::HAND);
    sim.record = true;
    let end = sim.run();
    assert!(sim.tree.is_empty(), "{}", sim.tree.render_text());
    (sim.starts.clone(), end, sim)
}

#[test]
fn sequential_walking_plans_each_step_after_the_previous_base_move() {
    use Role::*;
    let (starts, end, _) = starts(Mode::Sequential, 3);
    assert_eq!(
        starts,
        vec![
            (0, Walk),
            (1, PlanGait(1)),
            (3, MoveArmGoal(1)),
            (4, MoveArm(1)),
            (9, MoveBase(1)),
            (13, PlanGait(2)),
            (15, MoveArmGoal(2)),
            (16, MoveArm(2)),
            (21, MoveBase(2)),
            (25, PlanGait(3)),
            (27, MoveArmGoal(3)),
            (28, MoveArm(3)),
            (33, MoveBase(3)),
        ]
    );
    assert_eq!(end, 37);
}

#[test]
fn concurrent_walking_plans_the_next_step_while_the_current_one_executes() {
    use Role::*;
    let (starts, end, _) = starts(Mode::Concurrent, 3);
    // Starts at the same instant are listed in the driver's module order.
    assert_eq!(
        starts,
        vec![
            (0, Walk),
            (1, PlanGait(1)),
            (3, PlanGait(2)),
            (3, MoveArmGoal(1)),
            (4, MoveArm(1)),
            (5, MoveArmGoal(2)),
            (9, MoveBase(1)),
            (13, PlanGait(3)),
            (13, MoveArm(2)),
            (15, MoveArmGoal(3)),
            (18, MoveBase(2)),
            (22, MoveArm(3)),
            (27, MoveBase(3)),
        ]
    );
    assert_eq!(
        end, 31,
        "concurrent mode saves the planning time of steps 2 and 3"
    );
}

#[test]
fn commands_never_overlap_and_each_leg_move_precedes_its_base_move() {
    for mode in [Mode::Sequential, Mode::Concurrent] {
        let (starts, _, _) = starts(mode, 20);
        let commands: Vec<Role> = starts
            .iter()
            .map(|(_, r)| *r)
            .filter(|r| matches!(r, Role::MoveArm(_) | Role::MoveBase(_)))
            .collect();
        let expected: Vec<Role> = (1..=20)
            .flat_map(|k| [Role::MoveArm(k), Role::MoveBase(k)])
            .collect();
        assert_eq!(commands, expected, "{mode:?}");
    }
}

#[test]
fn replaying_the_walk_reproduces_ids_events_and_trees() {
    let (_, _, sim) = starts(Mode::Concurrent, 5);
    let json = serde_json::to_string(&sim.ops).expect("ops serialize");
    let ops: Vec<TreeOp> = serde_json::from_str(&json).expect("ops deserialize");
    let (tree, events) = TaskTree::replay(&ops).expect("replay");
    assert_eq!(events, sim.events);
    assert!(tree.is_empty());

    // Rebuild as it stood at time 13, when steps 1 and 2 overlap.
    let upto: Vec<TreeOp> = ops.iter().filter(|op| op.now() <= 13).cloned().collect();
    let (tree, _) = TaskTree::replay(&upto).expect("replay prefix");
    let text = tree.render_text();
    assert!(
        text.contains("planGait -> gait-planner: handling"),
        "{text}"
    );
    assert!(
        text.contains("command moveArm -> controller: handling"),
        "{text}"
    );
    assert!(!events.is_empty() && events.iter().any(|e| matches!(e, TreeEvent::Retired(_))));
}

#[test]
fn memory_stays_bounded_over_ten_thousand_steps() {
    let mut short = WalkSim::new(Mode::Concurrent, 1_000, Durations::HAND);
    short.run();
    let mut long = WalkSim::new(Mode::Concurrent, 10_000, Durations::HAND);
    long.run();
    assert!(short.tree.is_empty() && long.tree.is_empty());
    assert_eq!(long.nodes_added, 1 + 4 * 10_000);
    assert!(
        long.peak_live <= 16,
        "live nodes peaked at {}",
        long.peak_live
    );
    assert_eq!(long.peak_live, short.peak_live);
    assert!(
        long.peak_bytes <= short.peak_bytes + short.peak_bytes / 10,
        "bytes at 1,000 steps: {}, at 10,000: {}",
        short.peak_bytes,
        long.peak_bytes
    );
}
