//! TCA traffic log: MCAP writer, reader, display and statistics.
