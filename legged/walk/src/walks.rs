//! What the walking module remembers of each walk in progress: its goal, the steps alive, the
//! replans so far, and whether the body is still getting nearer the goal.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use tca_messages::NodeId;

/// A walk fails when this many steps in a row have not brought the body nearer the goal.
pub(crate) const MAX_IDLE_STEPS: u32 = 12;
/// Nearer by less than this is not nearer, metres.
pub(crate) const PROGRESS_M: f64 = 0.01;

/// One walk.
#[derive(Debug, Clone)]
pub(crate) struct WalkState {
    pub(crate) goal: [f64; 2],
    pub(crate) tolerance_m: f64,
    pub(crate) concurrent: bool,
    pub(crate) replans: u32,
    /// The highest step number sent so far.
    pub(crate) steps_sent: u32,
    /// Steps numbered below this were abandoned by a replan.
    pub(crate) first_live_step: u32,
    pub(crate) live_steps: Vec<NodeId>,
    /// The least distance to the goal a step has started from.
    best_distance_m: f64,
    idle_steps: u32,
}

impl WalkState {
    pub(crate) fn new(goal: [f64; 2], tolerance_m: f64, concurrent: bool) -> Self {
        WalkState {
            goal,
            tolerance_m,
            concurrent,
            replans: 0,
            steps_sent: 1,
            first_live_step: 1,
            live_steps: Vec::new(),
            best_distance_m: f64::INFINITY,
            idle_steps: 0,
        }
    }
}

/// The walks in progress, by walk node.
#[derive(Debug, Clone, Default)]
pub(crate) struct Walks {
    inner: Arc<Mutex<HashMap<NodeId, WalkState>>>,
}

impl Walks {
    pub(crate) fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<NodeId, WalkState>> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    pub(crate) fn insert(&self, walk: NodeId, state: WalkState) {
        self.lock().insert(walk, state);
    }

    pub(crate) fn step_started(&self, walk: NodeId, step: NodeId) {
        if let Some(w) = self.lock().get_mut(&walk) {
            w.live_steps.push(step);
        }
    }

    pub(crate) fn step_sent(&self, walk: NodeId, step: u32) {
        if let Some(w) = self.lock().get_mut(&walk) {
            w.steps_sent = w.steps_sent.max(step);
        }
    }

    pub(crate) fn is_stale(&self, walk: NodeId, step: u32) -> bool {
        self.lock()
            .get(&walk)
            .is_some_and(|w| step < w.first_live_step)
    }

    /// Notes that a step of `walk` starts with the body `distance_m` from the goal; fails,
    /// saying why, when [`MAX_IDLE_STEPS`] steps in a row have not brought it nearer.
    pub(crate) fn step_starts_at(&self, walk: NodeId, distance_m: f64) -> Result<(), String> {
        let mut all = self.lock();
        let Some(w) = all.get_mut(&walk) else {
            return Ok(());
        };
        if distance_m < w.best_distance_m - PROGRESS_M {
            w.best_distance_m = distance_m;
            w.idle_steps = 0;
        } else {
            w.idle_steps += 1;
        }
        if w.idle_steps >= MAX_IDLE_STEPS {
            return Err(format!(
                "the last {} steps have not brought the body nearer the goal ({distance_m:.2} m away, {:.2} m at best): the free gait finds no way on from here",
                w.idle_steps, w.best_distance_m
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_walk_that_stops_getting_nearer_is_ended_with_the_reason() {
        let walks = Walks::default();
        let w = NodeId(3);
        walks.insert(w, WalkState::new([10.0, 0.0], 0.2, false));
        for d in [10.0, 9.0, 8.0] {
            assert!(walks.step_starts_at(w, d).is_ok());
        }
        for _ in 0..MAX_IDLE_STEPS - 1 {
            assert!(walks.step_starts_at(w, 8.0).is_ok());
        }
        let e = walks.step_starts_at(w, 8.0).unwrap_err();
        assert!(e.contains("8.00 m"), "{e}");
        assert!(walks.step_starts_at(NodeId(4), 1.0).is_ok());
    }
}
