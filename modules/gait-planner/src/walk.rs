//! The `walk` goal (Figure 5): the user's one message. Its handler attaches the Gait Planner
//! as the handler of the Controller's exceptions on the walk node and sends the first
//! `planStep`; each step sends the next as its sibling until the goal is reached
//! ([`next_step`]). Sequential and concurrent walking differ only in constraints (§3.3):
//!
//! - **sequential**: step k+1 is planned only after step k's body move is achieved
//!   (`delay_planning(bodyMove k, planStep k+1)`);
//! - **concurrent**: step k+1 is planned while step k executes, from where step k will leave
//!   the carriage and the foot; its planning waits for step k-1's body move (what the scanner
//!   sees from where the carriage stands), and its leg move for step k's body move.
//!
//! In both, each leg move is achieved before its body move starts.
//!
//! Exceptions (§6.3): a failed leg or body move (`moveFailed`) ends the step: the handler adds
//! a new step planned from where the leg is, then kills the steps in progress (patch, then
//! kill). After `max_replans` failures in one walk it gives up: the exception passes up and
//! the walk fails with the reason. A hardware fault (`hardwareFault`) halts the walk: the
//! handler passes it up, so the whole task tree is killed and the user told why.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use tca_messages::{MessageId, NodeId};
use tca_module::{ConstraintSpec, Context, HandlerError, ModuleBuilder, Task, TaskRef};
use tca_robot::RailParams;
use tca_single_leg_messages::{
    HardwareFault, MoveFailed, PlanStep, StepStart, Walk, WalkMode, WorldPoint,
};

/// What the module remembers of each walk in progress.
#[derive(Debug, Clone)]
struct WalkState {
    goal_y_m: f64,
    mode: WalkMode,
    replans: u32,
    /// The highest step number sent so far.
    steps_sent: u32,
    /// Steps numbered below this belong to a chain a replan abandoned: if one still reaches
    /// the Gait Planner (it was waiting on a constraint when the others were killed), it
    /// ends at once without planning.
    first_live_step: u32,
    live_steps: Vec<NodeId>,
    /// Where the carriage stood when the last step was planned from the Controller's reading.
    last_start_y_m: Option<f64>,
    /// Steps in a row that found the carriage where the one before had.
    stalled: u32,
}

/// A step that finds the carriage within this of where the step before found it has not
/// advanced it, metres.
pub const STALL_M: f64 = 0.005;
/// A walk ends, failed, when this many steps in a row have not advanced the carriage.
pub const MAX_STALLED_STEPS: u32 = 2;

/// The walks in progress, by walk node.
#[derive(Debug, Clone, Default)]
pub struct Walks {
    inner: Arc<Mutex<HashMap<NodeId, WalkState>>>,
}

impl Walks {
    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<NodeId, WalkState>> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Records that a step started under `walk`.
    pub fn step_started(&self, walk: NodeId, step: NodeId) {
        if let Some(w) = self.lock().get_mut(&walk) {
            w.live_steps.push(step);
        }
    }

    /// Notes that step number `step` was sent in walk `walk`.
    pub fn step_sent(&self, walk: NodeId, step: u32) {
        if let Some(w) = self.lock().get_mut(&walk) {
            w.steps_sent = w.steps_sent.max(step);
        }
    }

    /// Notes that a step of walk `walk` found the carriage at `body_y_m`; fails, saying why,
    /// when [`MAX_STALLED_STEPS`] steps in a row have not moved it (the body moves are not
    /// advancing the carriage, so stepping on would never end).
    pub fn step_starts_at(&self, walk: NodeId, body_y_m: f64) -> Result<(), String> {
        let mut all = self.lock();
        let Some(w) = all.get_mut(&walk) else {
            return Ok(());
        };
        let still = w
            .last_start_y_m
            .is_some_and(|before| (body_y_m - before).abs() < STALL_M);
        w.stalled = if still { w.stalled + 1 } else { 0 };
        w.last_start_y_m = Some(body_y_m);
        if w.stalled >= MAX_STALLED_STEPS {
            return Err(format!(
                "the carriage has stayed at y = {body_y_m:.3} m for the last {} steps, short of \
                 the goal {:.3} m: its body moves are not advancing it",
                w.stalled, w.goal_y_m
            ));
        }
        Ok(())
    }

    /// Whether step number `step` of walk `walk` was abandoned by a replan.
    pub fn is_stale(&self, walk: NodeId, step: u32) -> bool {
        self.lock()
            .get(&walk)
            .is_some_and(|w| step < w.first_live_step)
    }
}

/// Registers the `walk` goal and the exception handlers on a Gait Planner module builder.
pub fn register(
    builder: ModuleBuilder,
    walks: Walks,
    max_replans: u32,
    rails: RailParams,
) -> ModuleBuilder {
    let (w1, w2) = (walks.clone(), walks);
    builder
        .handle(move |ctx: Context, walk: Walk| {
            let walks = w1.clone();
            async move { start_walk(&ctx, walk, &walks, &rails).await }
        })
        .handle(move |ctx: Context, failure: MoveFailed| {
            let walks = w2.clone();
            async move { replan(&ctx, failure, &walks, max_replans).await }
        })
        .handle(|_ctx: Context, fault: HardwareFault| async move {
            tracing::info!(detail = %fault.detail, "hardware fault: halting the walk");
            // Passed up: nobody above handles it, so central kills the whole tree and tells
            // the user why.
            Err::<(), _>(HandlerError::new(format!(
                "hardware fault: {}; the walk was halted",
                fault.detail
            )))
        })
}

async fn start_walk(
    ctx: &Context,
    walk: Walk,
    walks: &Walks,
    rails: &RailParams,
) -> Result<(), HandlerError> {
    check_goal(walk.goal_y_m, rails).map_err(HandlerError::new)?;
    let node = ctx
        .node()
        .ok_or_else(|| HandlerError::new("a walk must be a task (sent as a goal)"))?;
    ctx.on_exception::<MoveFailed>(node).await?;
    ctx.on_exception::<HardwareFault>(node).await?;
    walks.lock().insert(
        node,
        WalkState {
            goal_y_m: walk.goal_y_m,
            mode: walk.mode,
            replans: 0,
            steps_sent: 1,
            first_live_step: 1,
            live_steps: Vec::new(),
            last_start_y_m: None,
            stalled: 0,
        },
    );
    tracing::info!(goal_y_m = walk.goal_y_m, mode = ?walk.mode, "walk started");
    ctx.goal(&PlanStep {
        step: 1,
        goal_y_m: walk.goal_y_m,
        mode: walk.mode,
        start: None,
        after_body_move: None,
    })?;
    Ok(())
}

/// Whether the carriage can stand at `goal_y_m` on `rails`; if not, says why and what goal to
/// give instead.
pub fn check_goal(goal_y_m: f64, rails: &RailParams) -> Result<(), String> {
    if !goal_y_m.is_finite() {
        return Err(format!(
            "the walk's goal {goal_y_m} is not a number of metres; give a carriage position \
             between {:.2} and {:.2} m",
            rails.y_min_m, rails.y_max_m
        ));
    }
    if goal_y_m < rails.y_min_m || goal_y_m > rails.y_max_m {
        return Err(format!(
            "the goal y = {goal_y_m:.3} m is off the rails, which run from {:.2} to {:.2} m; \
             give a goal between them",
            rails.y_min_m, rails.y_max_m
        ));
    }
    Ok(())
}

/// The step after `step`, which plans to leave the carriage at `body_target_y_m` and the foot
/// at `footfall` with its body move `body_move`.
pub fn next_step(
    step: &PlanStep,
    body_target_y_m: f64,
    footfall: WorldPoint,
    body_move: MessageId,
) -> PlanStep {
    let concurrent = step.mode == WalkMode::Concurrent;
    PlanStep {
        step: step.step + 1,
        goal_y_m: step.goal_y_m,
        mode: step.mode,
        start: concurrent.then_some(StepStart {
            body_y_m: body_target_y_m,
            foot: footfall,
        }),
        after_body_move: concurrent.then_some(body_move),
    }
}

/// The constraints the next step is sent with: sequentially, it is not planned before this
/// step's body move is achieved; concurrently (§3.3), it is planned while this step executes,
/// but not before the previous step's body move is achieved (one step of look-ahead: what
/// the scanner sees from where the carriage stands).
pub fn next_step_constraints(step: &PlanStep, body_move: &Task) -> Option<ConstraintSpec> {
    match step.mode {
        WalkMode::Sequential => Some(ConstraintSpec::delay_planning(
            body_move.task_ref(),
            TaskRef::This,
        )),
        WalkMode::Concurrent => step.after_body_move.map(|previous| {
            ConstraintSpec::delay_planning(TaskRef::Message(previous), TaskRef::This)
        }),
    }
}

/// `moveFailed` at the walk node: plan again from where the leg is.
async fn replan(
    ctx: &Context,
    failure: MoveFailed,
    walks: &Walks,
    max_replans: u32,
) -> Result<(), HandlerError> {
    let walk = ctx
        .node()
        .ok_or_else(|| HandlerError::new("moveFailed delivered outside a walk"))?;
    let (state, old_steps) = {
        let mut all = walks.lock();
        let Some(state) = all.get_mut(&walk) else {
            return Err(HandlerError::new(format!(
                "moveFailed for a walk this module does not know ({walk}): {}",
                failure.detail
            )));
        };
        state.replans += 1;
        state.steps_sent += 1;
        state.first_live_step = state.steps_sent;
        (state.clone(), std::mem::take(&mut state.live_steps))
    };
    tracing::info!(
        command = %failure.command,
        kind = ?failure.kind,
        detail = %failure.detail,
        replans = state.replans,
        "a move failed; planning the step again from where the leg is"
    );
    if state.replans > max_replans {
        return Err(HandlerError::new(format!(
            "{} moves failed in this walk (limit {max_replans}); the last: {} {:?}: {}",
            state.replans, failure.command, failure.kind, failure.detail
        )));
    }
    // Patch first (a new step under the walk), then kill the steps in progress, newest
    // first: killing a step releases what waits on its body move, so a step planned ahead
    // from where the failed one would have left the leg must be gone before that.
    ctx.goal(&PlanStep {
        step: state.steps_sent,
        goal_y_m: state.goal_y_m,
        mode: state.mode,
        start: None,
        after_body_move: None,
    })?;
    for step in old_steps.into_iter().rev() {
        if let Err(e) = ctx.kill(step).await {
            tracing::debug!(%step, %e, "step already finished");
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_walk_whose_steps_do_not_move_the_carriage_is_stopped_with_the_reason() {
        let walks = Walks::default();
        let walk = NodeId(7);
        walks.lock().insert(
            walk,
            WalkState {
                goal_y_m: 9.5,
                mode: WalkMode::Sequential,
                replans: 0,
                steps_sent: 1,
                first_live_step: 1,
                live_steps: Vec::new(),
                last_start_y_m: None,
                stalled: 0,
            },
        );
        // Advancing steps, then one that found the carriage where it was: still walking.
        for y in [1.0, 2.4, 3.9, 3.902, 5.0, 5.001] {
            assert!(walks.step_starts_at(walk, y).is_ok(), "{y}");
        }
        // A second step in a row that did not move it ends the walk.
        let e = walks.step_starts_at(walk, 5.003).unwrap_err();
        assert!(
            e.contains("5.003") && e.contains("9.500") && e.contains("2 steps"),
            "{e}"
        );
        // A walk this module does not know is not judged.
        assert!(walks.step_starts_at(NodeId(8), 1.0).is_ok());
    }

    #[test]
    fn goals_off_the_rails_or_not_numbers_are_refused_with_the_range() {
        let rails = tca_robot::LegParams::default().rails;
        for ok in [rails.y_min_m, 5.0, rails.y_max_m] {
            assert!(check_goal(ok, &rails).is_ok(), "{ok}");
        }
        for bad in [100.0, 0.2, -1.0, f64::NAN, f64::INFINITY] {
            let e = check_goal(bad, &rails).unwrap_err();
            assert!(e.contains("0.50") && e.contains("10.50"), "{bad}: {e}");
        }
    }
}
