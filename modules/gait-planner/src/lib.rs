//! Gait Planner: weighted constraint cost maps for footfalls and body moves.
