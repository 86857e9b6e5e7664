//! Property tests on random trees and random constraint sets, driven by a random
//! scheduler that starts ready nodes and finishes running ones in random order.
//!
//! Checked on every run:
//! - a constraint is refused as a cycle exactly when a reference checker (plain depth-first
//!   search over the documented orderings) finds one;
//! - no accepted constraint, and no implicit ordering of the tree, is ever violated: its
//!   `before` point (or the death of its node) is reported before its `after` point;
//! - `Ready` is reported exactly for the nodes that have just become ready;
//! - the run always completes: the tree ends empty (no deadlock);
//! - replaying the op log (through JSON) reproduces every event and the tree after every op.

use std::collections::{BTreeSet, HashMap};

use proptest::prelude::*;
use tca_task_tree::{
    Constraint, Endpoint, NewConstraint, NodeId, NodeKind, NodeSpec, Outcome, Point, TaskTree,
    TreeError, TreeEvent, TreeOp,
};

/// SplitMix64: small, fast, deterministic.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    fn chance(&mut self, percent: u32) -> bool {
        self.next() % 100 < u64::from(percent)
    }

    fn pick<T: Copy>(&mut self, items: &[T]) -> Option<T> {
        (!items.is_empty()).then(|| items[self.below(items.len())])
    }

    fn point(&mut self) -> Point {
        Point::ALL[self.below(4)]
    }
}

/// Reference cycle check: the documented orderings, searched naively.
#[derive(Default)]
struct Reference {
    kind: HashMap<NodeId, NodeKind>,
    parent: HashMap<NodeId, NodeId>,
    children: HashMap<NodeId, Vec<NodeId>>,
    edges: Vec<(Endpoint, Endpoint)>,
}

impl Reference {
    fn canonical(&self, e: Endpoint) -> Endpoint {
        if e.point == Point::AchievementStart && self.kind.get(&e.node) == Some(&NodeKind::Command)
        {
            e.node.handling_start()
        } else {
            e
        }
    }

    fn successors(&self, e: Endpoint) -> Vec<Endpoint> {
        let n = e.node;
        let command = self.kind.get(&n) == Some(&NodeKind::Command);
        let kids: Vec<NodeId> = self
            .children
            .get(&n)
            .into_iter()
            .flatten()
            .copied()
            .filter(|c| self.kind.get(c) != Some(&NodeKind::Query))
            .collect();
        let mut out = Vec::new();
        let mut points = vec![e.point];
        if command && e.point == Point::HandlingStart {
            points.push(Point::AchievementStart);
        }
        for p in points {
            match p {
                Point::HandlingStart => {
                    out.push(n.handling_end());
                    out.push(n.achievement_start());
                    out.extend(kids.iter().map(|c| c.handling_start()));
                }
                Point::HandlingEnd => out.push(n.achievement_end()),
                Point::AchievementStart => {
                    out.push(n.achievement_end());
                    out.extend(kids.iter().map(|c| c.achievement_start()));
                }
                Point::AchievementEnd => {
                    out.extend(self.parent.get(&n).map(|p| p.achievement_end()))
                }
            }
            for (b, a) in &self.edges {
                if *b == Endpoint::new(n, p) {
                    out.push(*a);
                }
            }
        }
        out.into_iter()
            .map(|x| self.canonical(x))
            .filter(|x| *x != e)
            .collect()
    }

    fn reaches(&self, from: Endpoint, to: Endpoint) -> bool {
        let (from, to) = (self.canonical(from), self.canonical(to));
        let mut seen = BTreeSet::new();
        let mut stack = vec![from];
        while let Some(e) = stack.pop() {
            if e == to {
                return true;
            }
            if seen.insert(e) {
                stack.extend(self.successors(e));
            }
        }
        false
    }
}

/// One random run, with everything needed to check it.
struct Run {
    tree: TaskTree,
    rng: Rng,
    now: u64,
    ops: Vec<TreeOp>,
    events: Vec<TreeEvent>,
    /// The tree's text after each op.
    renders: Vec<String>,
    /// Positions (indices into `events`) where each point occurred.
    occurred: HashMap<Endpoint, Vec<usize>>,
    died: HashMap<NodeId, usize>,
    /// Accepted constraints with the event position at acceptance.
    accepted: Vec<(Constraint, usize)>,
    kind: HashMap<NodeId, NodeKind>,
    parent: HashMap<NodeId, NodeId>,
    ready: BTreeSet<NodeId>,
    running: BTreeSet<NodeId>,
    waiting_queries: BTreeSet<NodeId>,
    suspended: Vec<NodeId>,
}

impl Run {
    fn new(seed: u64) -> Self {
        Run {
            tree: TaskTree::new(),
            rng: Rng(seed),
            now: 0,
            ops: Vec::new(),
            events: Vec::new(),
            renders: Vec::new(),
            occurred: HashMap::new(),
            died: HashMap::new(),
            accepted: Vec::new(),
            kind: HashMap::new(),
            parent: HashMap::new(),
            ready: BTreeSet::new(),
            running: BTreeSet::new(),
            waiting_queries: BTreeSet::new(),
            suspended: Vec::new(),
        }
    }

    fn live(&self) -> Vec<NodeId> {
        self.tree
            .roots()
            .flat_map(|r| self.tree.subtree(r))
            .collect()
    }

    fn live_schedulable(&self) -> Vec<NodeId> {
        self.live()
            .into_iter()
            .filter(|n| self.kind.get(n) != Some(&NodeKind::Query))
            .collect()
    }

    /// Applies an op; on success records it and checks the readiness events.
    fn apply(&mut self, op: TreeOp) -> Result<Vec<TreeEvent>, TreeError> {
        let events = self.tree.apply(&op)?;
        match &op {
            TreeOp::AddNode { id, spec, .. } => {
                self.kind.insert(*id, spec.kind);
                if let Some(p) = spec.parent {
                    self.parent.insert(*id, p);
                }
                if spec.kind == NodeKind::Query {
                    self.waiting_queries.insert(*id);
                }
            }
            TreeOp::Finish { node, .. } => {
                self.running.remove(node);
            }
            TreeOp::Start { node, .. } => {
                self.waiting_queries.remove(node);
            }
            _ => {}
        }
        for e in &events {
            let position = self.events.len();
            let point = match e {
                TreeEvent::HandlingStarted(n) => {
                    self.running.insert(*n);
                    Some(n.handling_start())
                }
                TreeEvent::HandlingEnded(n) => Some(n.handling_end()),
                TreeEvent::AchievementStarted(n) => Some(n.achievement_start()),
                TreeEvent::Achieved(n) => Some(n.achievement_end()),
                TreeEvent::Killed { node, .. } | TreeEvent::Failed { node, .. } => {
                    self.died.entry(*node).or_insert(position);
                    self.running.remove(node);
                    self.waiting_queries.remove(node);
                    None
                }
                _ => None,
            };
            if let Some(p) = point {
                self.occurred.entry(p).or_default().push(position);
            }
            self.events.push(e.clone());
        }
        let ready_now: BTreeSet<NodeId> = self
            .live()
            .into_iter()
            .filter(|n| self.tree.is_ready(*n))
            .collect();
        let announced: BTreeSet<NodeId> = events
            .iter()
            .filter_map(|e| match e {
                TreeEvent::Ready(n) => Some(*n),
                _ => None,
            })
            .collect();
        let became: BTreeSet<NodeId> = ready_now.difference(&self.ready).copied().collect();
        assert_eq!(announced, became, "Ready events after {op:?}: {events:?}");
        self.ready = ready_now;
        self.ops.push(op);
        self.renders.push(self.tree.render_text());
        Ok(events)
    }

    fn random_constraint(&mut self) -> Option<Constraint> {
        let nodes = self.live_schedulable();
        let a = self.rng.pick(&nodes)?;
        let b = self.rng.pick(&nodes)?;
        let (pa, pb) = (self.rng.point(), self.rng.point());
        Some(Constraint::new(a.at(pa), b.at(pb)))
    }

    fn add_constraint(&mut self, c: Constraint) -> Result<(), TreeError> {
        let mark = self.events.len();
        self.apply(TreeOp::AddConstraint {
            constraint: c,
            now: self.now,
        })?;
        self.accepted.push((c, mark));
        Ok(())
    }

    fn random_spec(&mut self, parent: Option<NodeId>, with_constraints: bool) -> NodeSpec {
        let roll = self.rng.below(10);
        let mut spec = match roll {
            0 if parent.is_some() => NodeSpec::query("q", "oracle"),
            1..=5 => NodeSpec::goal("g", "planner"),
            _ => NodeSpec::command("c", "controller"),
        };
        spec.parent = parent;
        if with_constraints && spec.kind != NodeKind::Query {
            let others = self.live_schedulable();
            for _ in 0..self.rng.below(3) {
                let Some(o) = self.rng.pick(&others) else {
                    break;
                };
                let (p1, p2) = (self.rng.point(), self.rng.point());
                spec.constraints.push(match self.rng.below(9) {
                    0 => NewConstraint::PlanFirst,
                    1..=4 => NewConstraint::After {
                        before: o.at(p1),
                        point: p2,
                    },
                    _ => NewConstraint::Before {
                        point: p1,
                        after: o.at(p2),
                    },
                });
            }
        }
        spec
    }

    fn add_node(&mut self, spec: NodeSpec) -> Result<NodeId, TreeError> {
        let id = self.tree.next_id();
        let mark = self.events.len();
        let constraints = spec.constraints.clone();
        self.apply(TreeOp::AddNode {
            id,
            spec,
            now: self.now,
        })?;
        for c in constraints.iter().filter_map(|c| c.resolve(id)) {
            self.accepted.push((c, mark));
        }
        Ok(id)
    }
}

/// True if `before` (or its node's death) was reported before position `at`.
fn came_before(run: &Run, before: Endpoint, at: usize) -> bool {
    let occurred = run
        .occurred
        .get(&before)
        .is_some_and(|v| v.iter().any(|&p| p < at));
    occurred || run.died.get(&before.node).is_some_and(|&p| p < at)
}

/// A command's achievement start is its handling start.
fn canonical(run: &Run, e: Endpoint) -> Endpoint {
    if e.point == Point::AchievementStart && run.kind.get(&e.node) == Some(&NodeKind::Command) {
        e.node.handling_start()
    } else {
        e
    }
}

/// Every occurrence of `after` reported after position `since` came after `before`.
fn check_order(run: &Run, before: Endpoint, after: Endpoint, since: usize, what: &str) {
    if canonical(run, before) == canonical(run, after) {
        return; // `x <= x` always holds
    }
    let (before, after) = (canonical(run, before), canonical(run, after));
    for &at in run.occurred.get(&after).into_iter().flatten() {
        if at >= since {
            assert!(
                came_before(run, before, at),
                "{what}: {after} occurred (event {at}) before {before}\nevents: {:?}\nops: {:?}",
                run.events,
                run.ops
            );
        }
    }
}

#[derive(Debug, Clone)]
struct Params {
    seed: u64,
    nodes: usize,
    constraints: usize,
    dynamic: usize,
    kill_percent: u32,
    fail_percent: u32,
    suspend_percent: u32,
}

fn params() -> impl Strategy<Value = Params> {
    (
        any::<u64>(),
        1usize..30,
        0usize..50,
        0usize..15,
        prop_oneof![Just(0u32), 1u32..4],
        prop_oneof![Just(0u32), 1u32..10],
        prop_oneof![Just(0u32), 1u32..5],
    )
        .prop_map(
            |(seed, nodes, constraints, dynamic, kill_percent, fail_percent, suspend_percent)| {
                Params {
                    seed,
                    nodes,
                    constraints,
                    dynamic,
                    kill_percent,
                    fail_percent,
                    suspend_percent,
                }
            },
        )
}

fn simulate(p: &Params) -> Run {
    let mut run = Run::new(p.seed);
    let mut reference = Reference::default();

    // Phase 1: a random forest and random constraints, before anything runs.
    for i in 0..p.nodes {
        let parents: Vec<NodeId> = run
            .live()
            .into_iter()
            .filter(|n| run.kind.get(n) != Some(&NodeKind::Query))
            .collect();
        let parent = if i == 0 || run.rng.chance(10) {
            None
        } else {
            run.rng.pick(&parents)
        };
        let spec = run.random_spec(parent, false);
        let kind = spec.kind;
        let id = run.add_node(spec).expect("a plain node is always accepted");
        reference.kind.insert(id, kind);
        if let Some(par) = parent {
            reference.parent.insert(id, par);
            reference.children.entry(par).or_default().push(id);
        }
    }
    for _ in 0..p.constraints {
        let Some(c) = run.random_constraint() else {
            break;
        };
        let cyclic = reference.reaches(c.after, c.before)
            && reference.canonical(c.after) != reference.canonical(c.before);
        match run.add_constraint(c) {
            Ok(()) => {
                assert!(!cyclic, "{c} closes a cycle but was accepted");
                reference.edges.push((c.before, c.after));
            }
            Err(TreeError::Cycle { .. }) => assert!(cyclic, "{c} was refused as a cycle"),
            Err(e) => panic!("{c} refused: {e}"),
        }
    }

    // Phase 2: a random scheduler, with plan patches, kills, failures and suspensions.
    let mut dynamic = p.dynamic;
    for _ in 0..20_000 {
        run.now += run.rng.below(3) as u64;
        let mut startable: Vec<NodeId> = run.ready.iter().copied().collect();
        startable.extend(run.waiting_queries.iter().copied());
        let running: Vec<NodeId> = run.running.iter().copied().collect();
        if startable.is_empty() && running.is_empty() {
            if run.suspended.is_empty() {
                break;
            }
            let i = run.rng.below(run.suspended.len());
            let node = run.suspended.swap_remove(i);
            let _ = run.apply(TreeOp::Resume { node, now: run.now });
            continue;
        }
        let roll = run.rng.below(100) as u32;
        if roll < p.kill_percent {
            let live = run.live();
            if let Some(node) = run.rng.pick(&live) {
                run.apply(TreeOp::Kill { node, now: run.now })
                    .expect("a live node can be killed");
            }
        } else if roll < p.kill_percent + p.suspend_percent {
            let live = run.live_schedulable();
            if let Some(node) = run.rng.pick(&live)
                && run.apply(TreeOp::Suspend { node, now: run.now }).is_ok()
            {
                run.suspended.push(node);
            }
        } else if roll < 20 && dynamic > 0 {
            dynamic -= 1;
            let parents: Vec<NodeId> = run
                .live_schedulable()
                .into_iter()
                .filter(|n| {
                    run.tree
                        .get(*n)
                        .is_some_and(|v| v.state() != tca_task_tree::NodeState::Failed)
                })
                .collect();
            if let Some(parent) = run.rng.pick(&parents) {
                let spec = run.random_spec(Some(parent), true);
                if let Err(e) = run.add_node(spec) {
                    assert!(
                        matches!(e, TreeError::Cycle { .. } | TreeError::Unsatisfiable { .. }),
                        "{e}"
                    );
                }
            }
        } else if roll < 25 {
            if let Some(c) = run.random_constraint()
                && let Err(e) = run.add_constraint(c)
            {
                assert!(
                    matches!(e, TreeError::Cycle { .. } | TreeError::Unsatisfiable { .. }),
                    "{e}"
                );
            }
        } else if roll < 28 {
            let held: Vec<NodeId> = run
                .live()
                .into_iter()
                .filter(|n| run.tree.get(*n).is_some_and(|v| v.failure_held()))
                .collect();
            if let Some(node) = run.rng.pick(&held) {
                run.apply(TreeOp::Retry { node, now: run.now })
                    .expect("a held failure can be retried");
            }
        } else if !startable.is_empty() && (running.is_empty() || run.rng.chance(50)) {
            let node = startable[run.rng.below(startable.len())];
            run.apply(TreeOp::Start { node, now: run.now })
                .expect("a ready node starts");
        } else if let Some(node) = run.rng.pick(&running) {
            let fails = run.rng.chance(p.fail_percent);
            let query = run.kind.get(&node) == Some(&NodeKind::Query);
            if fails && !query && run.rng.chance(60) {
                exception(&mut run, node);
                continue;
            }
            let outcome = if fails {
                Outcome::failure("random failure")
            } else {
                Outcome::Success
            };
            run.apply(TreeOp::Finish {
                node,
                outcome,
                now: run.now,
            })
            .expect("a running node finishes");
        }
    }
    run
}

/// Central's exception protocol: suspend the node, report the failure (now held), then
/// retry it, kill it (ignore the failure), or resume with the failure held (unhandled: it
/// propagates).
fn exception(run: &mut Run, node: NodeId) {
    let now = run.now;
    run.apply(TreeOp::Suspend { node, now })
        .expect("a running node can be suspended");
    run.apply(TreeOp::Finish {
        node,
        outcome: Outcome::failure("exception"),
        now,
    })
    .expect("a running node finishes");
    assert!(
        run.tree.get(node).is_some_and(|v| v.failure_held()),
        "failure under a suspension is held"
    );
    match run.rng.below(4) {
        0 | 1 => {
            run.apply(TreeOp::Retry { node, now })
                .expect("a held failure can be retried");
            run.apply(TreeOp::Resume { node, now })
                .expect("the retried node is still suspended");
        }
        2 => {
            run.apply(TreeOp::Kill { node, now })
                .expect("a held failure can be killed");
        }
        _ => {
            run.apply(TreeOp::Resume { node, now })
                .expect("the failed node is still suspended");
            let still_suspended = std::iter::once(node)
                .chain(run.tree.ancestors(node))
                .any(|a| run.tree.get(a).is_some_and(|v| v.is_suspended()));
            if still_suspended {
                assert!(
                    run.tree.get(node).is_some_and(|v| v.failure_held()),
                    "the failure stays held while it or an ancestor is suspended"
                );
            } else {
                assert!(!run.tree.contains(node), "an unhandled failure propagates");
            }
        }
    }
}

fn check(run: &Run) {
    // No deadlock: everything completed and was retired.
    assert!(
        run.tree.is_empty(),
        "stalled with live nodes:\n{}\nops: {:?}",
        run.tree.render_text(),
        run.ops
    );
    // No accepted constraint violated.
    for (c, since) in &run.accepted {
        check_order(run, c.before, c.after, *since, &format!("constraint {c}"));
    }
    // No implicit ordering violated.
    for (&n, &kind) in &run.kind {
        if kind == NodeKind::Query {
            continue;
        }
        let implicit = [
            (n.handling_start(), n.handling_end()),
            (n.handling_start(), n.achievement_start()),
            (n.handling_end(), n.achievement_end()),
            (n.achievement_start(), n.achievement_end()),
        ];
        for (b, a) in implicit {
            check_order(run, b, a, 0, "node ordering");
        }
        if let Some(&p) = run.parent.get(&n) {
            check_order(
                run,
                p.handling_start(),
                n.handling_start(),
                0,
                "parent start",
            );
            check_order(
                run,
                p.achievement_start(),
                n.achievement_start(),
                0,
                "parent achievement start",
            );
            check_order(
                run,
                n.achievement_end(),
                p.achievement_end(),
                0,
                "child achievement end",
            );
        }
        if run.occurred.contains_key(&n.achievement_end()) {
            for point in Point::ALL {
                assert!(
                    run.occurred.contains_key(&n.at(point)),
                    "{n} achieved without {point:?}"
                );
            }
        }
    }
    // Replay through JSON reproduces every event and every intermediate tree.
    let json = serde_json::to_string(&run.ops).expect("ops serialize");
    let ops: Vec<TreeOp> = serde_json::from_str(&json).expect("ops deserialize");
    let mut tree = TaskTree::new();
    let mut events = Vec::new();
    for (op, render) in ops.iter().zip(&run.renders) {
        events.extend(tree.apply(op).expect("replayed op applies"));
        assert_eq!(
            &tree.render_text(),
            render,
            "tree differs after replaying {op:?}"
        );
    }
    assert_eq!(events, run.events);
    // A tree saved part-way and restored goes on exactly as the original did.
    for cut in [ops.len() / 3, ops.len() * 2 / 3] {
        let (mut tree, mut events) = TaskTree::replay(&ops[..cut]).expect("prefix replays");
        let saved = serde_json::to_string(&tree).expect("tree saves");
        tree = serde_json::from_str(&saved).expect("tree restores");
        for (i, (op, render)) in ops[cut..].iter().zip(&run.renders[cut..]).enumerate() {
            events.extend(tree.apply(op).expect("op applies to the restored tree"));
            if i % 8 == 0 {
                assert_eq!(
                    &tree.render_text(),
                    render,
                    "restored tree differs after {op:?}"
                );
            }
        }
        assert_eq!(events, run.events, "restored at op {cut}");
    }
}

proptest! {
    // 400 cases by default; PROPTEST_CASES=N runs a longer sweep.
    #![proptest_config(ProptestConfig::with_cases(
        std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(400)
    ))]

    #[test]
    fn random_plans_respect_constraints_complete_and_replay(p in params()) {
        let run = simulate(&p);
        check(&run);
    }
}

#[test]
fn a_large_random_plan_without_faults_completes() {
    for seed in 0..20 {
        let p = Params {
            seed,
            nodes: 200,
            constraints: 300,
            dynamic: 50,
            kill_percent: 0,
            fail_percent: 0,
            suspend_percent: 0,
        };
        let run = simulate(&p);
        check(&run);
        assert!(
            run.accepted.len() > 50,
            "seed {seed}: only {} accepted",
            run.accepted.len()
        );
    }
}
