//! Perception Display Manager: map pictures as PNG.
