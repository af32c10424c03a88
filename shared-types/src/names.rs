//! Service names, all in one place: `taut/<uav>/<topic>`, under a configurable root so that
//! several service sets (two drones, parallel tests) share one machine without seeing each other.

/// Topic of [`crate::RawAdcFrame`]s from the ADC sampler.
pub const RAW_ADC: &str = "raw_adc";
/// Topic of [`crate::TensionSample`]s from the tension stage.
pub const TENSION: &str = "tension";

/// Topic of [`crate::TensionSample`]s from the model-based external-force estimator (the
/// baseline: accelerometer and motor speeds; `force_body_n` is its estimate of the cable pull).
pub const TENSION_ESTIMATE: &str = "tension_estimate";
/// Topic of [`crate::TensionSample`]s holding the plant's true anchor force (simulation only,
/// for the `truth` tension source).
pub const TENSION_TRUTH: &str = "tension_truth";
/// Topic of [`crate::VehicleState`]s from the PX4 bridge.
pub const VEHICLE_STATE: &str = "vehicle_state";
/// Topic of [`crate::ImuSample`]s from the PX4 bridge.
pub const IMU: &str = "imu";
/// Topic of [`crate::MotorSpeeds`] from the PX4 bridge.
pub const MOTOR_SPEEDS: &str = "motor_speeds";
/// Topic of [`crate::MissionSetpoint`]s from the mission.
pub const MISSION_SETPOINT: &str = "mission_setpoint";
/// Topic of [`crate::AttitudeSetpoint`]s from the controller.
pub const ATTITUDE_SETPOINT: &str = "attitude_setpoint";

/// Topic of [`crate::PlantTruth`] under the uav id [`PLANT`]; evaluation only.
pub const TRUTH: &str = "truth";
/// The "uav" id the plant publishes under.
pub const PLANT: &str = "plant";

/// Longest service name we build (iceoryx2 allows 255 bytes).
pub const MAX_NAME_LEN: usize = 255;

/// `"<root>/taut/<uav>/<topic>"` (`root` may be empty, then `"taut/<uav>/<topic>"`).
///
/// `root` separates test runs; `uav` is the drone id from the config; `topic` one of the
/// constants above. The event service that wakes a topic's subscribers uses the same name: in
/// iceoryx2 a name is unique per messaging pattern.
pub fn service_name(root: &str, uav: &str, topic: &str) -> String {
    if root.is_empty() {
        format!("taut/{uav}/{topic}")
    } else {
        format!("{}/taut/{uav}/{topic}", root.trim_end_matches('/'))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_rooted_per_drone() {
        assert_eq!(service_name("", "uav1", TENSION), "taut/uav1/tension");
        assert_eq!(
            service_name("test-42/", "uav2", RAW_ADC),
            "test-42/taut/uav2/raw_adc"
        );
    }
}
