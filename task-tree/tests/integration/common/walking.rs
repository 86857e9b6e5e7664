//! A discrete-event driver for the single-leg walking task tree of Figure 5 (the report,
//! §3.2), shared by the tests and the benchmark.
//!
//! Per step `k`: the Gait Planner handles the goal `planGait k`, which issues the goal
//! `moveArm k` (handled by the Leg Recovery Planner, which issues the command `moveArm
//! k`) and the command `moveBase k`, and issues `planGait k+1` under the walk goal. Each
//! module handles one message at a time (TCA's resource management), and each handler
//! takes a fixed time. Constraints:
//!
//! - always: the moveArm goal of step k is achieved before moveBase k starts, and the
//!   moveArm goal of step k+1 is not achieved before moveBase k is (its planning may run
//!   ahead, its command may not);
//! - sequential: `planGait k+1` is not planned until `moveBase k` is achieved;
//! - concurrent: `planGait k+1` waits only for `moveBase k-1`, so step k+1 is planned
//!   while step k executes.
#![allow(dead_code)]

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap, VecDeque};

use tca_task_tree::{Nanos, NewConstraint, NodeId, NodeSpec, Outcome, TaskTree, TreeEvent, TreeOp};

/// How steps overlap.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mode {
    Sequential,
    Concurrent,
}

/// What a node stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Role {
    Walk,
    PlanGait(u32),
    MoveArmGoal(u32),
    MoveArm(u32),
    MoveBase(u32),
}

impl Role {
    /// The module that handles it: 0 user interface, 1 gait planner, 2 leg recovery
    /// planner, 3 controller.
    fn module(self) -> usize {
        match self {
            Role::Walk => 0,
            Role::PlanGait(_) => 1,
            Role::MoveArmGoal(_) => 2,
            Role::MoveArm(_) | Role::MoveBase(_) => 3,
        }
    }

    fn handler(self) -> &'static str {
        ["user-interface", "gait-planner", "lrp", "controller"][self.module()]
    }
}

/// How long each handler runs.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Durations {
    pub(crate) walk: Nanos,
    pub(crate) plan_gait: Nanos,
    pub(crate) lrp: Nanos,
    pub(crate) leg_move: Nanos,
    pub(crate) base_move: Nanos,
}

impl Durations {
    /// Small integers, easy to follow by hand.
    pub(crate) const HAND: Durations = Durations {
        walk: 1,
        plan_gait: 2,
        lrp: 1,
        leg_move: 5,
        base_move: 4,
    };

    fn of(&self, role: Role) -> Nanos {
        match role {
            Role::Walk => self.walk,
            Role::PlanGait(_) => self.plan_gait,
            Role::MoveArmGoal(_) => self.lrp,
            Role::MoveArm(_) => self.leg_move,
            Role::MoveBase(_) => self.base_move,
        }
    }
}

/// The walking system driven over a task tree.
pub(crate) struct WalkSim {
    pub(crate) tree: TaskTree,
    pub(crate) now: Nanos,
    mode: Mode,
    steps: u32,
    durations: Durations,
    /// Role of each live node (dropped when the node retires, so the driver's memory stays
    /// bounded like the tree's).
    roles: HashMap<NodeId, Role>,
    walk: NodeId,
    /// moveBase of the last steps, by step (older ones are dropped).
    base_moves: HashMap<u32, NodeId>,
    queues: [VecDeque<NodeId>; 4],
    busy: [bool; 4],
    running: BinaryHeap<Reverse<(Nanos, u64, NodeId)>>,
    sequence: u64,
    /// Handling starts, in order (kept only when `record` is set).
    pub(crate) starts: Vec<(Nanos, Role)>,
    /// When true, every op and event is kept.
    pub(crate) record: bool,
    pub(crate) ops: Vec<TreeOp>,
    pub(crate) events: Vec<TreeEvent>,
    /// Largest number of live nodes and estimated bytes seen (sampled per step).
    pub(crate) peak_live: usize,
    pub(crate) peak_bytes: usize,
    pub(crate) nodes_added: u64,
}

impl WalkSim {
    pub(crate) fn new(mode: Mode, steps: u32, durations: Durations) -> Self {
        WalkSim {
            tree: TaskTree::new(),
            now: 0,
            mode,
            steps,
            durations,
            roles: HashMap::new(),
            walk: NodeId(0),
            base_moves: HashMap::new(),
            queues: Default::default(),
            busy: [false; 4],
            running: BinaryHeap::new(),
            sequence: 0,
            starts: Vec::new(),
            record: false,
            ops: Vec::new(),
            events: Vec::new(),
            peak_live: 0,
            peak_bytes: 0,
            nodes_added: 0,
        }
    }

    fn role(&self, id: NodeId) -> Option<Role> {
        self.roles.get(&id).copied()
    }

    fn take(&mut self, events: Vec<TreeEvent>) {
        for e in &events {
            match e {
                TreeEvent::Ready(id) => {
                    if let Some(role) = self.role(*id) {
                        self.queues[role.module()].push_back(*id);
                    }
                }
                // Every node of the walk is achieved and retired on its own.
                TreeEvent::Retired(id) => {
                    self.roles.remove(id);
                }
                _ => {}
            }
        }
        if self.record {
            self.events.extend(events);
        }
    }

    fn add(&mut self, role: Role, parent: Option<NodeId>, with: Vec<NewConstraint>) -> NodeId {
        let name = match role {
            Role::Walk => "walk",
            Role::PlanGait(_) => "planGait",
            Role::MoveArmGoal(_) | Role::MoveArm(_) => "moveArm",
            Role::MoveBase(_) => "moveBase",
        };
        let mut spec = match role {
            Role::MoveArm(_) | Role::MoveBase(_) => NodeSpec::command(name, role.handler()),
            _ => NodeSpec::goal(name, role.handler()),
        };
        spec.parent = parent;
        spec.constraints = with;
        let op_spec = self.record.then(|| spec.clone());
        let (id, events) = self
            .tree
            .add_node(spec, self.now)
            .expect("walking plan is valid");
        if let Some(spec) = op_spec {
            self.ops.push(TreeOp::AddNode {
                id,
                spec,
                now: self.now,
            });
        }
        self.nodes_added += 1;
        self.roles.insert(id, role);
        self.take(events);
        id
    }

    /// What a handler issues just before it finishes.
    fn issue(&mut self, id: NodeId, role: Role) {
        match role {
            Role::Walk => {
                self.add(Role::PlanGait(1), Some(id), Vec::new());
            }
            Role::PlanGait(k) => {
                let previous_body = self.base_moves.get(&(k - 1)).copied();
                let leg_with = previous_body
                    .map(NewConstraint::sequential_achievement_after)
                    .into_iter()
                    .collect();
                let leg = self.add(Role::MoveArmGoal(k), Some(id), leg_with);
                let body = self.add(
                    Role::MoveBase(k),
                    Some(id),
                    vec![NewConstraint::sequential_achievement_after(leg)],
                );
                self.base_moves.insert(k, body);
                self.base_moves.remove(&k.saturating_sub(2));
                if k < self.steps {
                    let wait_for = match self.mode {
                        Mode::Sequential => Some(body),
                        Mode::Concurrent => previous_body,
                    };
                    let with = wait_for
                        .map(NewConstraint::delay_planning_until)
                        .into_iter()
                        .collect();
                    self.add(Role::PlanGait(k + 1), Some(self.walk), with);
                }
                self.sample(k);
            }
            Role::MoveArmGoal(k) => {
                self.add(Role::MoveArm(k), Some(id), Vec::new());
            }
            Role::MoveArm(_) | Role::MoveBase(_) => {}
        }
    }

    /// Records the peaks: live nodes exactly (the tree tracks them), bytes every 16 steps
    /// (the estimate walks the node pages, and the walk repeats with a short period).
    fn sample(&mut self, step: u32) {
        self.peak_live = self.tree.peak_len();
        if step % 16 == 1 {
            self.peak_bytes = self.peak_bytes.max(self.tree.estimated_bytes());
        }
    }

    fn dispatch(&mut self) {
        for module in 0..4 {
            while !self.busy[module] {
                let Some(id) = self.queues[module].pop_front() else {
                    break;
                };
                if !self.tree.is_ready(id) {
                    continue;
                }
                let events = self.tree.start(id, self.now).expect("ready node starts");
                if self.record {
                    self.ops.push(TreeOp::Start {
                        node: id,
                        now: self.now,
                    });
                }
                self.take(events);
                let Some(role) = self.role(id) else {
                    continue;
                };
                if self.record {
                    self.starts.push((self.now, role));
                }
                self.busy[module] = true;
                self.sequence += 1;
                self.running.push(Reverse((
                    self.now + self.durations.of(role),
                    self.sequence,
                    id,
                )));
            }
        }
    }

    /// Walks every step; returns the time the walk goal was achieved.
    pub(crate) fn run(&mut self) -> Nanos {
        self.walk = self.add(Role::Walk, None, Vec::new());
        self.dispatch();
        while let Some(Reverse((at, _, id))) = self.running.pop() {
            self.now = at;
            let Some(role) = self.role(id) else {
                continue;
            };
            self.issue(id, role);
            let events = self
                .tree
                .finish(id, Outcome::Success, self.now)
                .expect("running node finishes");
            if self.record {
                self.ops.push(TreeOp::Finish {
                    node: id,
                    outcome: Outcome::Success,
                    now: self.now,
                });
            }
            self.take(events);
            self.busy[role.module()] = false;
            self.dispatch();
        }
        self.now
    }
}
