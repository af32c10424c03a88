//! Everything that is not the companion computer: emulated plant, autopilot and sensors.
//!
//! - [`physics`]: two quadrotors, payload, cables, contacts; the integrator.
//! - [`inner_loops`]: PX4's attitude, rate and position controllers and control allocation.
//! - [`commander`]: PX4's modes, arming, offboard proof of life and failsafe.
//! - [`estimator`]: the motion-capture perturbation and the EKF-like position estimator.
//! - [`mavlink_link`]: the MAVLink v2 endpoint of each emulated PX4 (UDP, loopback).
//! - [`scenario`]: scenario files (Test A, Test B) and setpoint paths.
//! - [`plant`]: all of it together, stepped in simulated time; [`pilot`] flies a scenario
//!   through the emulated PX4 without any taut service.
//! - [`sensor`]: the emulated force sensor and its I2C bus.

pub mod commander;
pub mod estimator;
pub mod fast;
pub mod inner_loops;
pub mod mavlink_link;
pub mod physics;
pub mod pilot;
pub mod plant;
pub mod scenario;
pub mod sensor;
