//! Single-leg walker models: leg kinematics, terrain height fields, grids, obstacle courses.
