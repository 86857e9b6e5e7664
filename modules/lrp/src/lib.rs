//! Leg Recovery Planner: the Envelope Trajectory Finding Algorithm.
