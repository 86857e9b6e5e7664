//! The tree as indented text, for `tca tree` and the log viewer.

use std::fmt::Write;

use crate::id::NodeId;
use crate::tree::TaskTree;

impl TaskTree {
    /// The live trees, oldest root first, one line per node indented two spaces per level:
    /// id, kind, message name, handler module, state and flags, then the pending
    /// constraints that hold the node back. For example:
    ///
    /// ```text
    /// n1 goal walk -> gait-planner: achieving
    ///   n4 command moveBase -> controller: waiting; waits for end(achieve n3) <= start(achieve n4)
    /// ```
    pub fn render_text(&self) -> String {
        let mut out = String::new();
        for root in &self.roots {
            let mut stack = vec![(*root, 0usize)];
            while let Some((id, depth)) = stack.pop() {
                let Some(node) = self.nodes.get(&id) else {
                    continue;
                };
                self.render_line(id, depth, &mut out);
                stack.extend(
                    node.children
                        .iter()
                        .rev()
                        .filter(|c| self.nodes.contains_key(c))
                        .map(|c| (*c, depth + 1)),
                );
            }
        }
        out
    }

    fn render_line(&self, id: NodeId, depth: usize, out: &mut String) {
        let Some(view) = self.get(id) else {
            return;
        };
        for _ in 0..depth {
            out.push_str("  ");
        }
        let _ = write!(
            out,
            "{id} {} {} -> {}: {}",
            view.kind(),
            view.name(),
            view.handler(),
            view.state()
        );
        if view.is_ready() {
            out.push_str(", ready");
        }
        if view.is_suspended() {
            out.push_str(", suspended");
        }
        if view.plan_first() {
            out.push_str(", plan first");
        }
        if view.finish_pending() {
            out.push_str(", finish pending");
        }
        if view.failure_held() {
            let _ = write!(
                out,
                ", failure held ({})",
                view.failure_reason().unwrap_or("no reason given")
            );
        }
        let waits: Vec<String> = view.waiting_on().map(|c| c.to_string()).collect();
        if !waits.is_empty() {
            let _ = write!(out, "; waits for {}", waits.join(", "));
        }
        out.push('\n');
    }
}

#[cfg(test)]
mod tests {
    use crate::NewConstraint;
    use crate::testing::Bench;

    #[test]
    fn renders_one_indented_line_per_node_with_state_and_constraints() {
        let mut b = Bench::new();
        let walk = b.goal(None, "walk");
        b.start(walk);
        let step = b.goal(Some(walk), "planGait");
        let leg = b.command(step, "moveArm", &[]);
        b.command(
            step,
            "moveBase",
            &[NewConstraint::sequential_achievement_after(leg)],
        );
        b.tree.suspend(step, b.now).expect("suspend");
        assert_eq!(
            b.tree.render_text(),
            "n1 goal walk -> planner: handling\n\
             \x20 n2 goal planGait -> planner: waiting, suspended\n\
             \x20   n3 command moveArm -> controller: waiting\n\
             \x20   n4 command moveBase -> controller: waiting; waits for end(achieve n3) <= start(achieve n4)\n"
        );
    }
}
