//! Everything that is not the companion computer: emulated plant, autopilot and sensors.

pub mod sensor;
