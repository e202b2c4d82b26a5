//! criterion benches over the subdiv pipeline; the benches themselves live in `benches/`.
//!
//! `cargo bench -p subdiv-benches` runs them all; `cargo xtask bench` runs them and prints one
//! `key=value` line per measurement.
