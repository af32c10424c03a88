//! `taut sim test-a | test-b`: the main job. The plant in real time and two complete drone
//! service sets as separate processes (`--fast`: the same code in one process, in simulated
//! time), then a summary of the flight.

pub mod metrics;
