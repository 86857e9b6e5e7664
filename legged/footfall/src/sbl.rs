//! SBL, the single-query bi-directional planner with lazy collision checking (after Sánchez
//! and Latombe), over one leg's joints.
//!
//! Two trees grow from the two ends. Each iteration picks a tree at random, picks one of
//! its milestones with a probability inversely proportional to how crowded its
//! neighbourhood is (a random occupied cell of a grid over the joints, then a random
//! milestone in it), and samples a collision-free configuration within a distance `r <= ρ`
//! of it, halving `r` after each sample in collision; only the new milestone is checked,
//! not the segment to it. When the new milestone comes within `ρ` (L-infinity) of the
//! other tree's nearest milestone, the path through both trees and that *bridge* is tested:
//! its segments are checked a bisection level at a time, all segments level 1 first, then
//! level 2, and so on (each tree edge remembers the levels already checked), so that a
//! segment in collision is usually found early. A tree edge in collision is cut with the
//! milestones beyond it; a bridge in collision is dropped. The first path whose segments
//! are all checked down to the resolution is returned.

use std::collections::HashMap;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::collision::{LegChecker, Phase, bisection_levels, linf};

/// SBL's parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SblParams {
    /// Most milestones made over both trees before giving up (the paper's `s`).
    pub max_milestones: usize,
    /// The distance within which a milestone is sampled and two trees are bridged, radians
    /// (L-infinity; the paper's `ρ`).
    pub rho_rad: f64,
    /// How many times the sampling distance is halved before the expansion gives up.
    pub expand_tries: usize,
    /// Seed of the random choices.
    pub seed: u64,
}

impl Default for SblParams {
    fn default() -> Self {
        Self {
            max_milestones: 6000,
            rho_rad: 0.4,
            expand_tries: 4,
            seed: 1,
        }
    }
}

/// What SBL found.
#[derive(Debug, Clone, PartialEq)]
pub struct SblOutcome {
    /// The path from the start to the goal, milestone by milestone.
    pub path: Vec<Vec<f64>>,
    /// Milestones made.
    pub milestones: usize,
    /// Bridges tested.
    pub bridges: usize,
}

#[derive(Debug, Clone)]
struct Node {
    q: Vec<f64>,
    parent: Option<usize>,
    /// Bisection levels of the edge to the parent already checked.
    checked: u32,
    children: Vec<usize>,
    alive: bool,
}

#[derive(Debug)]
struct Tree {
    nodes: Vec<Node>,
    cells: HashMap<Vec<i32>, Vec<usize>>,
    keys: Vec<Vec<i32>>,
}

impl Tree {
    fn new(root: Vec<f64>, cell: f64, active: &[usize]) -> Tree {
        let mut t = Tree {
            nodes: Vec::new(),
            cells: HashMap::new(),
            keys: Vec::new(),
        };
        t.add(root, None, cell, active);
        t
    }

    fn add(&mut self, q: Vec<f64>, parent: Option<usize>, cell: f64, active: &[usize]) -> usize {
        let id = self.nodes.len();
        let key: Vec<i32> = active
            .iter()
            .map(|&i| (q[i] / cell).floor() as i32)
            .collect();
        match self.cells.get_mut(&key) {
            Some(v) => v.push(id),
            None => {
                self.cells.insert(key.clone(), vec![id]);
                self.keys.push(key);
            }
        }
        self.nodes.push(Node {
            q,
            parent,
            checked: 0,
            children: Vec::new(),
            alive: true,
        });
        if let Some(p) = parent {
            self.nodes[p].children.push(id);
        }
        id
    }

    /// A living milestone, picked against the density of its neighbourhood.
    fn pick(&self, rng: &mut ChaCha8Rng) -> Option<usize> {
        for _ in 0..64 {
            let key = &self.keys[rng.random_range(0..self.keys.len())];
            let ids = &self.cells[key];
            let id = ids[rng.random_range(0..ids.len())];
            if self.nodes[id].alive {
                return Some(id);
            }
        }
        self.nodes.iter().rposition(|n| n.alive)
    }

    fn nearest(&self, q: &[f64]) -> Option<(usize, f64)> {
        self.nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| n.alive)
            .map(|(i, n)| (i, linf(&n.q, q)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// The milestones from the root to `id`.
    fn chain(&self, id: usize) -> Vec<usize> {
        let mut out = vec![id];
        let mut at = id;
        while let Some(p) = self.nodes[at].parent {
            out.push(p);
            at = p;
        }
        out.reverse();
        out
    }

    /// Cuts `id` and everything beyond it.
    fn cut(&mut self, id: usize) {
        let mut stack = vec![id];
        while let Some(n) = stack.pop() {
            self.nodes[n].alive = false;
            stack.extend(self.nodes[n].children.iter().copied());
        }
        if let Some(p) = self.nodes[id].parent {
            self.nodes[p].children.retain(|c| *c != id);
        }
    }
}

/// One segment of a candidate path.
struct Segment {
    from: Vec<f64>,
    to: Vec<f64>,
    /// The tree and node whose edge to its parent this is, or `None` for the bridge.
    edge: Option<(usize, usize)>,
    checked: u32,
    needed: u32,
}

/// Plans from `start` to `goal` (both collision-free) with the joints in `active` free to
/// move (the others keep the start's values). `Err` says why not.
pub fn sbl(
    checker: &LegChecker,
    start: &[f64],
    goal: &[f64],
    active: &[usize],
    params: &SblParams,
) -> Result<SblOutcome, String> {
    if !(params.rho_rad.is_finite() && params.rho_rad > 0.0) {
        return Err(format!("ρ is {}; give a positive distance", params.rho_rad));
    }
    let limits: Vec<(f64, f64)> = checker.scene().model.legs()[checker.leg()]
        .joints()
        .iter()
        .map(|j| (j.limits().lower, j.limits().upper))
        .collect();
    let cell = params.rho_rad;
    let mut trees = [
        Tree::new(start.to_vec(), cell, active),
        Tree::new(goal.to_vec(), cell, active),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut milestones = 2;
    let mut bridges = 0;
    // The ends may already be within reach of each other.
    if linf(start, goal) <= params.rho_rad
        && let Some(path) = test_path(checker, &mut trees, 0, 0, 0, &mut bridges)
    {
        return Ok(SblOutcome {
            path,
            milestones,
            bridges,
        });
    }
    while milestones < params.max_milestones {
        let t = usize::from(rng.random_bool(0.5));
        let Some(m) = trees[t].pick(&mut rng) else {
            return Err("a tree lost every milestone".into());
        };
        let base = trees[t].nodes[m].q.clone();
        let mut r = params.rho_rad;
        let mut new = None;
        for _ in 0..params.expand_tries.max(1) {
            let mut q = base.clone();
            for &i in active {
                let (lo, hi) = limits[i];
                q[i] = (base[i] + rng.random_range(-r..=r)).clamp(lo, hi);
            }
            milestones += 1;
            if checker.check(&q, Phase::Free).is_none() {
                new = Some(q);
                break;
            }
            r *= 0.5;
        }
        let Some(q) = new else { continue };
        let id = trees[t].add(q, Some(m), cell, active);
        let other = 1 - t;
        let Some((near, d)) = trees[other].nearest(&trees[t].nodes[id].q) else {
            return Err("a tree lost every milestone".into());
        };
        if d <= params.rho_rad
            && let Some(path) = test_path(checker, &mut trees, t, id, near, &mut bridges)
        {
            return Ok(SblOutcome {
                path,
                milestones,
                bridges,
            });
        }
    }
    Err(format!(
        "SBL made {milestones} milestones ({} and {} still in the two trees) and tested \
         {bridges} bridges without finding a path",
        trees[0].nodes.iter().filter(|n| n.alive).count(),
        trees[1].nodes.iter().filter(|n| n.alive).count()
    ))
}

/// Tests the path through milestone `id` of tree `t`, the bridge to milestone `near` of the
/// other tree, and on to its root; cuts what is in collision. The path from the start on
/// success.
fn test_path(
    checker: &LegChecker,
    trees: &mut [Tree; 2],
    t: usize,
    id: usize,
    near: usize,
    bridges: &mut usize,
) -> Option<Vec<Vec<f64>>> {
    *bridges += 1;
    let res = checker.resolution_rad();
    let mut segments = Vec::new();
    let push_chain = |segments: &mut Vec<Segment>,
                      tree: usize,
                      chain: &[usize],
                      trees: &[Tree; 2],
                      forward: bool| {
        for w in chain.windows(2) {
            // Each edge joins a node and its parent.
            let (parent, child) = if forward { (w[0], w[1]) } else { (w[1], w[0]) };
            let node = &trees[tree].nodes[child];
            let (from, to) = if forward {
                (trees[tree].nodes[parent].q.clone(), node.q.clone())
            } else {
                (node.q.clone(), trees[tree].nodes[parent].q.clone())
            };
            let needed = bisection_levels(&from, &to, res);
            segments.push(Segment {
                from,
                to,
                edge: Some((tree, child)),
                checked: node.checked,
                needed,
            });
        }
    };
    let other = 1 - t;
    let chain_t = trees[t].chain(id);
    let mut chain_o = trees[other].chain(near);
    chain_o.reverse();
    push_chain(&mut segments, t, &chain_t, trees, true);
    let bridge_from = trees[t].nodes[id].q.clone();
    let bridge_to = trees[other].nodes[near].q.clone();
    // Every milestone is collision-free, so the bridge's ends are.
    let needed = bisection_levels(&bridge_from, &bridge_to, res);
    segments.push(Segment {
        from: bridge_from,
        to: bridge_to,
        edge: None,
        checked: 0,
        needed,
    });
    push_chain(&mut segments, other, &chain_o, trees, false);
    let top = segments.iter().map(|s| s.needed).max().unwrap_or(0);
    for level in 1..=top {
        for s in segments.iter_mut() {
            if s.checked >= level || level > s.needed {
                continue;
            }
            if checker
                .segment_level(&s.from, &s.to, level, Phase::Free)
                .is_some()
            {
                if let Some((tree, child)) = s.edge {
                    trees[tree].cut(child);
                }
                return None;
            }
            s.checked = level;
            if let Some((tree, child)) = s.edge {
                trees[tree].nodes[child].checked = level;
            }
        }
    }
    // The path in order from the start: tree 0's chain first.
    let mut path: Vec<Vec<f64>> = chain_t
        .iter()
        .map(|&n| trees[t].nodes[n].q.clone())
        .collect();
    path.extend(chain_o.iter().map(|&n| trees[other].nodes[n].q.clone()));
    if t == 1 {
        path.reverse();
    }
    Some(path)
}
