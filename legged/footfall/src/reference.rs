//! The dense reference planner that decides whether a step is feasible at all: RRT-Connect
//! over the leg's joints in which every edge is checked at the full resolution before it
//! joins a tree (nothing lazy), with a large budget and several seeds. A path it finds is
//! a proof that the step can be made; it is slow, which is why it is only a yardstick.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::collision::{LegChecker, Phase, lerp, linf};

/// The reference planner's budget.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ReferenceParams {
    /// Longest edge, radians (L-infinity).
    pub step_rad: f64,
    /// Nodes over both trees per seed.
    pub max_nodes: usize,
    /// Seeds tried one after the other.
    pub seeds: u64,
}

impl Default for ReferenceParams {
    fn default() -> Self {
        Self {
            step_rad: 0.1,
            max_nodes: 20_000,
            seeds: 3,
        }
    }
}

struct Tree {
    q: Vec<Vec<f64>>,
    parent: Vec<Option<usize>>,
}

impl Tree {
    fn nearest(&self, q: &[f64]) -> usize {
        let mut best = (0, f64::INFINITY);
        for (i, n) in self.q.iter().enumerate() {
            let d = linf(n, q);
            if d < best.1 {
                best = (i, d);
            }
        }
        best.0
    }

    fn chain(&self, mut id: usize) -> Vec<Vec<f64>> {
        let mut out = vec![self.q[id].clone()];
        while let Some(p) = self.parent[id] {
            out.push(self.q[p].clone());
            id = p;
        }
        out.reverse();
        out
    }
}

enum Extend {
    Reached(usize),
    Advanced(usize),
    Trapped,
}

fn extend(checker: &LegChecker, tree: &mut Tree, target: &[f64], step: f64) -> Extend {
    let near = tree.nearest(target);
    let from = tree.q[near].clone();
    let d = linf(&from, target);
    let (to, reached) = if d <= step {
        (target.to_vec(), true)
    } else {
        (lerp(&from, target, step / d), false)
    };
    if checker.check(&to, Phase::Free).is_some()
        || checker.segment(&from, &to, Phase::Free).is_err()
    {
        return Extend::Trapped;
    }
    tree.q.push(to);
    tree.parent.push(Some(near));
    let id = tree.q.len() - 1;
    if reached {
        Extend::Reached(id)
    } else {
        Extend::Advanced(id)
    }
}

/// A collision-free path from `start` to `goal` moving the joints in `active`, or `None`
/// when the budget ran out.
pub fn reference_path(
    checker: &LegChecker,
    start: &[f64],
    goal: &[f64],
    active: &[usize],
    params: &ReferenceParams,
) -> Option<Vec<Vec<f64>>> {
    let limits: Vec<(f64, f64)> = checker.scene().model.legs()[checker.leg()]
        .joints()
        .iter()
        .map(|j| (j.limits().lower, j.limits().upper))
        .collect();
    if checker.segment(start, goal, Phase::Free).is_ok() {
        return Some(vec![start.to_vec(), goal.to_vec()]);
    }
    for seed in 0..params.seeds {
        let mut rng = ChaCha8Rng::seed_from_u64(0x5245_4600 + seed);
        let mut trees = [
            Tree {
                q: vec![start.to_vec()],
                parent: vec![None],
            },
            Tree {
                q: vec![goal.to_vec()],
                parent: vec![None],
            },
        ];
        let mut a = 0;
        while trees[0].q.len() + trees[1].q.len() < params.max_nodes {
            let mut sample = start.to_vec();
            if rng.random_bool(0.1) {
                sample = trees[1 - a].q[0].clone();
            } else {
                for &i in active {
                    let (lo, hi) = limits[i];
                    sample[i] = rng.random_range(lo..=hi);
                }
            }
            let new = match extend(checker, &mut trees[a], &sample, params.step_rad) {
                Extend::Trapped => None,
                Extend::Reached(id) | Extend::Advanced(id) => Some(id),
            };
            if let Some(id) = new {
                let target = trees[a].q[id].clone();
                // Connect: the other tree steps toward the new node until it gets there or
                // is blocked.
                loop {
                    match extend(checker, &mut trees[1 - a], &target, params.step_rad) {
                        Extend::Reached(other) => {
                            let mut first = trees[a].chain(id);
                            let mut second = trees[1 - a].chain(other);
                            second.reverse();
                            second.remove(0);
                            first.extend(second);
                            if a == 1 {
                                first.reverse();
                            }
                            return Some(first);
                        }
                        Extend::Advanced(_) => continue,
                        Extend::Trapped => break,
                    }
                }
            }
            a = 1 - a;
        }
    }
    None
}
