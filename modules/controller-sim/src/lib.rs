//! Simulated Controller: leg, carriage and terrain behind the Controller's message interface.
