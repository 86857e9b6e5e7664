//! TCA task trees and temporal constraints: pure bookkeeping, no I/O.
//!
//! The central control process (crate `tca-central`) records every goal, command and
//! query as a node of a task tree (the report, §3.2, Figure 5), asks this crate which nodes
//! may be dispatched, and reports handlers starting and ending. The tree enforces the
//! temporal constraints between nodes, propagates completion and failure, and gives
//! central the tools to handle exceptions. It reads no clock (every call carries the
//! caller's `now`), does no I/O and spawns nothing, so it is deterministic: the same calls
//! give the same events, which is what makes logs replayable.
//!
//! # Layout
//!
//! - `id`: [`NodeId`] and the time base [`Nanos`].
//! - `state`: [`NodeKind`] and [`NodeState`].
//! - `point`: the four time points of a node ([`Point`]) and [`Endpoint`].
//! - `constraint`: [`Constraint`] (`before <= after`), its shorthands, and
//!   [`NewConstraint`] (constraints given with a new node).
//! - `spec`: [`NodeSpec`] (what `add_node` takes) and [`Outcome`] (what `finish` takes).
//! - `event`: [`TreeEvent`], what every call reports.
//! - `error`: [`TreeError`] and the [`Result`] alias.
//! - `tree`: the [`TaskTree`] storage and its read-only queries.
//! - `add`: adding nodes and constraints, plan-first.
//! - `cycle`: the cycle check over time points.
//! - `readiness`: when a node may be dispatched, and why not.
//! - `dispatch`: handlers starting and finishing.
//! - `propagate`: the engine: points occur, constraints are released, nodes complete.
//! - `exception`: failure, kill, suspend, resume, retry.
//! - `retire`: freeing finished subtrees; memory estimate.
//! - `render`: the tree as indented text.
//! - `view`: [`NodeView`], a read-only window on a node.
//! - `op`: [`TreeOp`], mutations as data, and replay.
//! - `snapshot`: the whole tree saved and restored (`Serialize`, `Deserialize`).
//! - `store`: node storage in fixed-size pages indexed by id, freed as nodes retire.
//! - `node`, `hash`: the internal node record and the id hasher.
//!
//! # Nodes and states
//!
//! A node is a goal, a command or a query ([`NodeKind`]). Goals and commands are created by
//! their parent's handler (or patched in under any unfinished node); queries are recorded
//! as leaves and never dispatched, constrained or propagated by the tree. Ids are assigned
//! sequentially from `n1` and never reused.
//!
//! States ([`NodeState`]): `Waiting` (handler not started) → `Handling` (handler running;
//! for a command this is also its achievement) → `Handled` (handler finished, achievement
//! not started) → `Achieving` (achievement started, waiting for descendants or a
//! constraint) → `Achieved`. `Failed` and `Killed` are the other terminal states. A node
//! is *achieved* when its handler has finished, every descendant is achieved (or killed),
//! and the constraints on its two end points hold.
//!
//! # Time points
//!
//! Each node has four points ([`Point`]): handling start and end, achievement start and
//! end. Their meaning:
//!
//! - **Handling start**: the handler is dispatched ([`TaskTree::start`]).
//! - **Handling end**: the handler has reported success ([`TaskTree::finish`]) and no
//!   constraint holds the end back.
//! - **Achievement start**: for a command, its handling start (executing it is achieving
//!   it). For a goal, the first of: a descendant's achievement starts (a command below it
//!   starts), or its own handler finishes; and in either case only once every constraint
//!   on its achievement start, and on that of every ancestor whose achievement has not
//!   started, holds. Starting a node's achievement starts its ancestors' too.
//! - **Achievement end**: the node is achieved.
//!
//! *Why not when the goal is achieved:* starting a command-less goal's achievement when the
//! goal is achieved makes the point depend on the goal's own completion, a hidden ordering
//! the cycle check cannot see: `start(achieve g) <= end(handle g)` is acyclic yet would
//! deadlock. Starting it when the goal's handler finishes (if nothing below started it
//! earlier) keeps every dependency of every point visible to the cycle check, so an
//! accepted plan never deadlocks (the property tests check this).
//!
//! Implicit orderings, enforced and counted by the cycle check: handling start before
//! handling end and (goals) achievement start; both before achievement end; a parent's
//! handling start before its children's; a parent's achievement start before its
//! children's; a child's achievement end before its parent's.
//!
//! # Constraints
//!
//! A [`Constraint`] `before <= after` means the `after` point may not occur until the
//! `before` point has (same instant allowed). Shorthands:
//! [`Constraint::sequential_achievement`] (`end(achieve a) <= start(achieve b)`),
//! [`Constraint::delay_planning`] (`end(achieve a) <= start(handle b)`),
//! [`Constraint::invocation_order`] (`start(handle a) <= start(handle b)`), and
//! [`TaskTree::plan_first`], expressed as `end(handle g) <= start(achieve p)` for every goal
//! `g` of `p`'s subtree, including goals added under `p` later (until `p`'s achievement
//! starts).
//!
//! - **Start points are gates.** A node is *ready* when it is waiting, neither it nor an
//!   ancestor is suspended, its parent's handling has started, every constraint on its
//!   handling start holds, and, for a command, every constraint on its own achievement
//!   start and on that of every ancestor whose achievement has not started. A goal whose
//!   handler has finished waits in `Handled` until its achievement start may occur.
//! - **End points are delayed.** A constraint on a *handling end* lets the handler finish
//!   (the tree cannot stop a handler) but the handling-end point is recorded only when the
//!   constraint holds: until then the node stays `Handling` with
//!   [`NodeView::finish_pending`], and its achievement cannot end. A constraint on an
//!   *achievement end* keeps a node whose handler and descendants are done in `Achieving`
//!   until it holds.
//! - Constraints come with a new node ([`NodeSpec::constraints`], relative to it) or later
//!   ([`TaskTree::add_constraint`]). One whose `before` point has already occurred (or
//!   belongs to a finished or retired node) is satisfied at once and not stored. One whose
//!   `after` point has occurred, or whose `after` node has finished, is refused as
//!   unsatisfiable; one naming an unknown node or a query is refused; one that would close
//!   a cycle, counting the implicit orderings, is refused with the cycle spelled out.
//!
//! # Failure, kill and exceptions
//!
//! - **Dead endpoints.** The points of a killed node, or of a node that failed for good,
//!   count as occurred at the kill or failure time: every constraint waiting for them is
//!   satisfied then, so nothing waits forever on a dead node.
//! - **Failure policy.** When a handler reports failure the node becomes `Failed`, its
//!   unfinished descendants are killed (`Killed { was: Handling }` for running handlers:
//!   central cancels them), and the failure propagates: the parent fails too, and so on
//!   up to the root, each ancestor's unfinished descendants being killed, and
//!   [`TreeEvent::CancelHandler`] reported for an ancestor whose handler is still
//!   running. The failed tree is then retired. A failing query only records its failure
//!   (the asker gets the error as its reply).
//! - **Holding a failure for exception handling.** If the failing node or an ancestor is
//!   suspended ([`TaskTree::suspend`]), the failure is *held*: the node stays `Failed` but
//!   not finished, its parent keeps waiting for it, and the constraints on it stay pending.
//!   Central routes the exception and then either [`TaskTree::retry`]s the node (back to
//!   `Waiting`), [`TaskTree::kill`]s it (the exception is ignored: a killed node counts as
//!   done), adds nodes to patch the plan, or [`TaskTree::resume`]s with the failure still
//!   held, which lets it propagate as above (unhandled). So: suspend first, then report
//!   the failure, then decide.
//! - [`TaskTree::kill`] kills a node and its subtree; the node counts as finished for its
//!   parent. [`TaskTree::ancestors`] gives the routing order (nearest first).
//!
//! # Retirement and memory
//!
//! A node that finishes (achieved, killed, or failed for good) is retired at once, with
//! whatever is left below it, after its events are reported: [`TreeEvent::Retired`] names
//! the top of each retired subtree. A finished node's points have all occurred, so every
//! constraint from it is already satisfied and none to it can ever matter; constraints
//! that name retired nodes later are satisfied (as `before`) or refused (as `after`). The
//! tree thus holds only unfinished nodes, and a long run under one long-lived root holds
//! memory bounded by the live part of the plan ([`TaskTree::len`],
//! [`TaskTree::estimated_bytes`]).
//!
//! # Events and replay
//!
//! Every mutating call returns its [`TreeEvent`]s in a deterministic order. `Ready(id)` is
//! emitted each time a node becomes ready; central should check [`TaskTree::is_ready`]
//! before dispatching, since a constraint or suspension added later can take readiness
//! away (a new `Ready` follows when it comes back). Each mutating call corresponds to a
//! [`TreeOp`]; [`TaskTree::apply`] replays ops into a fresh tree and reproduces the same
//! ids, states and events. A tree also saves and restores whole (it is `Serialize` and
//! `Deserialize`): the restored tree goes on exactly as the saved one would have.
//!
//! # Choices, and why
//!
//! - A goal's achievement starts when its handler finishes if nothing below it started
//!   it earlier (not when the goal is achieved): see *Time points*. Without this, some
//!   acyclic plans deadlocked.
//! - Two more events: [`TreeEvent::HandlingStarted`], so the event stream records every
//!   point, and [`TreeEvent::CancelHandler`], for an ancestor whose handler is still
//!   running when a descendant's failure reaches it. [`TreeEvent`] and [`TreeError`] are
//!   `#[non_exhaustive]`: match them with a `_` arm.
//! - "Unless the caller handles it first" is made precise by holding failures under a
//!   suspension (see *Failure, kill and exceptions*).
//! - Queries cannot be constrained or have children, and their failure does not
//!   propagate: the tree never schedules them.
//! - Finished nodes are retired at once, so [`TaskTree::get`] returns `None` right after
//!   a node's `Achieved`, `Killed` or final `Failed` event: keep what you need from the
//!   events.
//! - When a command starts, its ancestors' `AchievementStarted` events come before its
//!   `HandlingStarted`, so the event order never shows a child's achievement before its
//!   parent's.
//! - [`TaskTree::plan_first`] is a method (and [`NewConstraint::PlanFirst`]), not a
//!   single point constraint, because it must also cover goals added later.
//!
//! # Example
//!
//! ```
//! use tca_task_tree::{NewConstraint, NodeSpec, Outcome, TaskTree, TreeEvent};
//!
//! # fn main() -> tca_task_tree::Result<()> {
//! let mut tree = TaskTree::new();
//! let (walk, events) = tree.add_node(NodeSpec::goal("walk", "gait-planner"), 0)?;
//! assert_eq!(events, vec![TreeEvent::Ready(walk)]);
//! tree.start(walk, 1)?;
//! let (leg, _) = tree.add_node(NodeSpec::command("moveArm", "controller").under(walk), 2)?;
//! let (body, events) = tree.add_node(
//!     NodeSpec::command("moveBase", "controller")
//!         .under(walk)
//!         .with(NewConstraint::sequential_achievement_after(leg)),
//!     2,
//! )?;
//! assert!(events.is_empty()); // moveBase waits for moveArm to be achieved
//! tree.finish(walk, Outcome::Success, 3)?;
//! tree.start(leg, 3)?;
//! let events = tree.finish(leg, Outcome::Success, 9)?;
//! assert!(events.contains(&TreeEvent::Ready(body)));
//! # Ok(())
//! # }
//! ```

mod add;
mod constraint;
mod cycle;
mod dispatch;
mod error;
mod event;
mod exception;
mod hash;
mod id;
mod node;
mod op;
mod point;
mod propagate;
mod readiness;
mod render;
mod retire;
mod snapshot;
mod spec;
mod state;
mod store;
#[cfg(test)]
mod testing;
mod tree;
mod view;

pub use constraint::{Constraint, NewConstraint};
pub use error::{Result, TreeError};
pub use event::TreeEvent;
pub use id::{Nanos, NodeId};
pub use op::TreeOp;
pub use point::{Endpoint, Point};
pub use spec::{NodeSpec, Outcome};
pub use state::{NodeKind, NodeState};
pub use tree::TaskTree;
pub use view::NodeView;
