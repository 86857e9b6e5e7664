//! Helpers for the unit tests.

use crate::{NewConstraint, NodeId, NodeSpec, Outcome, TaskTree, TreeEvent};

/// A tree plus a clock that advances by one on every call.
pub(crate) struct Bench {
    pub(crate) tree: TaskTree,
    pub(crate) now: u64,
    pub(crate) events: Vec<TreeEvent>,
}

impl Bench {
    pub(crate) fn new() -> Self {
        Bench {
            tree: TaskTree::new(),
            now: 0,
            events: Vec::new(),
        }
    }

    fn tick(&mut self) -> u64 {
        self.now = self.now.max(self.tree.last_time()) + 1;
        self.now
    }

    pub(crate) fn add(&mut self, spec: NodeSpec) -> NodeId {
        let now = self.tick();
        let (id, events) = self.tree.add_node(spec, now).expect("add_node");
        self.events.extend(events);
        id
    }

    pub(crate) fn goal(&mut self, parent: Option<NodeId>, name: &str) -> NodeId {
        let spec = NodeSpec::goal(name, "planner");
        self.add(match parent {
            Some(p) => spec.under(p),
            None => spec,
        })
    }

    pub(crate) fn command(&mut self, parent: NodeId, name: &str, with: &[NewConstraint]) -> NodeId {
        let mut spec = NodeSpec::command(name, "controller").under(parent);
        spec.constraints.extend_from_slice(with);
        self.add(spec)
    }

    pub(crate) fn start(&mut self, id: NodeId) -> Vec<TreeEvent> {
        let now = self.tick();
        let events = self.tree.start(id, now).expect("start");
        self.events.extend(events.clone());
        events
    }

    pub(crate) fn succeed(&mut self, id: NodeId) -> Vec<TreeEvent> {
        let now = self.tick();
        let events = self.tree.finish(id, Outcome::Success, now).expect("finish");
        self.events.extend(events.clone());
        events
    }

    pub(crate) fn fail(&mut self, id: NodeId, reason: &str) -> Vec<TreeEvent> {
        let now = self.tick();
        let events = self
            .tree
            .finish(id, Outcome::failure(reason), now)
            .expect("finish");
        self.events.extend(events.clone());
        events
    }

    /// Starts and finishes a node in one go.
    pub(crate) fn run(&mut self, id: NodeId) -> Vec<TreeEvent> {
        let mut events = self.start(id);
        events.extend(self.succeed(id));
        events
    }
}
