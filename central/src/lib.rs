//! TCA central control: a sans-I/O routing core and its transport adapters.
