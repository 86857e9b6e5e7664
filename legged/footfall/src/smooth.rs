//! Path smoothing by shortcuts: the shortest path through the path's own nodes whose
//! straight segments are collision-free (a shortest-path search over every pair of nodes),
//! then every segment of it bisected to give new nodes, again and again until a round
//! shortens the path (its Euclidean length in joint space) by less than a set fraction.
//!
//! The search is lazy: it takes the shortest path assuming every shortcut is free, checks
//! that path's shortcuts, forbids those in collision and searches again, so that the pairs
//! it never needs are never checked. It finds the same path as a search over the checked
//! graph.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::collision::{LegChecker, Phase, euclid, lerp};

/// How hard smoothing works.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SmoothParams {
    /// Stop when a round shortens the path by less than this fraction of its length.
    pub stop_change: f64,
    /// Most rounds.
    pub max_rounds: usize,
}

impl Default for SmoothParams {
    /// 25 % and ten rounds.
    fn default() -> Self {
        Self {
            stop_change: 0.25,
            max_rounds: 10,
        }
    }
}

/// The length of a path in joint space (Euclidean), radians.
pub fn path_length(path: &[Vec<f64>]) -> f64 {
    path.windows(2).map(|w| euclid(&w[0], &w[1])).sum()
}

/// What smoothing did.
#[derive(Debug, Clone, PartialEq)]
pub struct Smoothed {
    /// The smoothed path.
    pub path: Vec<Vec<f64>>,
    /// Rounds of search and bisection.
    pub rounds: usize,
    /// The length before, radians.
    pub length_before: f64,
    /// The length after, radians.
    pub length_after: f64,
}

/// Smooths a collision-free path (its segments checked, in `phase`).
pub fn smooth(
    checker: &LegChecker,
    path: &[Vec<f64>],
    phase: Phase,
    params: &SmoothParams,
) -> Smoothed {
    let length_before = path_length(path);
    let mut current = path.to_vec();
    let mut length = length_before;
    let mut rounds = 0;
    while rounds < params.max_rounds && current.len() > 2 {
        rounds += 1;
        let shortest = shortcut(checker, &current, phase);
        let new_length = path_length(&shortest);
        let gain = (length - new_length) / length.max(1e-12);
        current = shortest;
        length = new_length;
        if gain < params.stop_change || current.len() <= 2 {
            break;
        }
        current = bisect(&current);
    }
    Smoothed {
        path: current,
        rounds,
        length_before,
        length_after: length,
    }
}

/// Each segment split at its middle.
fn bisect(path: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut out = Vec::with_capacity(2 * path.len());
    for w in path.windows(2) {
        out.push(w[0].clone());
        out.push(lerp(&w[0], &w[1], 0.5));
    }
    if let Some(last) = path.last() {
        out.push(last.clone());
    }
    out
}

/// The shortest path from the first node to the last through the nodes, over segments
/// that are collision-free (consecutive nodes are known to be).
fn shortcut(checker: &LegChecker, nodes: &[Vec<f64>], phase: Phase) -> Vec<Vec<f64>> {
    let n = nodes.len();
    // Known segments: true free, false in collision.
    let mut known: HashMap<(usize, usize), bool> = HashMap::new();
    for i in 0..n - 1 {
        known.insert((i, i + 1), true);
    }
    loop {
        // Shortest path in a DAG (i < j), every pair not known blocked allowed.
        let mut dist = vec![f64::INFINITY; n];
        let mut prev = vec![usize::MAX; n];
        dist[0] = 0.0;
        for j in 1..n {
            for i in 0..j {
                if known.get(&(i, j)) == Some(&false) || !dist[i].is_finite() {
                    continue;
                }
                let d = dist[i] + euclid(&nodes[i], &nodes[j]);
                if d < dist[j] {
                    dist[j] = d;
                    prev[j] = i;
                }
            }
        }
        let mut order = vec![n - 1];
        while let Some(&at) = order.last() {
            if at == 0 || prev[at] == usize::MAX {
                break;
            }
            order.push(prev[at]);
        }
        order.reverse();
        let mut all_free = true;
        for w in order.windows(2) {
            let key = (w[0], w[1]);
            let free = *known
                .entry(key)
                .or_insert_with(|| checker.segment(&nodes[key.0], &nodes[key.1], phase).is_ok());
            if !free {
                all_free = false;
                break;
            }
        }
        if all_free {
            return order.into_iter().map(|i| nodes[i].clone()).collect();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bisection_adds_midpoints() {
        let p = vec![vec![0.0, 0.0], vec![2.0, 0.0], vec![2.0, 2.0]];
        let b = bisect(&p);
        assert_eq!(b.len(), 5);
        assert_eq!(b[1], vec![1.0, 0.0]);
        assert_eq!(b[3], vec![2.0, 1.0]);
        assert!((path_length(&b) - 4.0).abs() < 1e-12);
    }
}
