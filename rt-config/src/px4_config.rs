//! Config of the PX4 bridge: the MAVLink link and the offboard handshake.

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Px4Config {
    /// `serial:/dev/ttyAMA0:921600` (TELEM2 on the Pi), or `udpin:ADDR:PORT` (listen where PX4
    /// SITL or the plant streams to), or `udpout:ADDR:PORT`.
    pub link: String,
    /// Our MAVLink system and component ids (a companion computer: 1 / 191 is PX4's onboard
    /// computer default).
    pub system_id: u8,
    pub component_id: u8,
    /// PX4's system id (MAV_SYS_ID) and autopilot component.
    pub target_system: u8,
    pub target_component: u8,
    /// HEARTBEAT rate, Hz.
    pub heartbeat_hz: f64,
    /// No HEARTBEAT from PX4 for this long means the link is lost, s.
    pub link_timeout_s: f64,
    /// Stream setpoints this long before asking for offboard (PX4 wants > 1 s above 2 Hz), s.
    pub stream_before_offboard_s: f64,
    /// Wait this long for a COMMAND_ACK before resending, s.
    pub ack_timeout_s: f64,
    /// Sends of one command before the handshake gives up.
    pub command_attempts: u32,
    /// Telemetry rates asked with SET_MESSAGE_INTERVAL, Hz.
    pub odometry_hz: f64,
    pub attitude_hz: f64,
    pub imu_hz: f64,
    pub esc_hz: f64,
}

impl Default for Px4Config {
    fn default() -> Self {
        Self {
            link: "udpin:127.0.0.1:14540".to_string(),
            system_id: 1,
            component_id: 191,
            target_system: 1,
            target_component: 1,
            heartbeat_hz: 1.0,
            link_timeout_s: 1.5,
            stream_before_offboard_s: 1.2,
            ack_timeout_s: 0.3,
            command_attempts: 5,
            odometry_hz: 100.0,
            attitude_hz: 100.0,
            imu_hz: 250.0,
            esc_hz: 50.0,
        }
    }
}

/// Where the bridge talks to PX4, parsed from [`Px4Config::link`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Px4Link {
    /// `udpin:ADDR:PORT`: bind there, answer whoever sends PX4's frames.
    UdpIn(std::net::SocketAddr),
    /// `udpout:ADDR:PORT`: send there from an ephemeral port.
    UdpOut(std::net::SocketAddr),
    /// `serial:DEVICE:BAUD`.
    Serial { device: String, baud: u32 },
}

impl Px4Config {
    /// Parses `link` (`udpin:ADDR:PORT`, `udpout:ADDR:PORT`, `serial:DEVICE:BAUD`).
    pub fn parse_link(&self) -> Result<Px4Link, String> {
        let bad = |why: &str| format!("key `px4.link` = {:?}: {why}", self.link);
        let (kind, rest) = self.link.split_once(':').ok_or_else(|| {
            bad("expected udpin:ADDR:PORT, udpout:ADDR:PORT or serial:DEVICE:BAUD")
        })?;
        match kind {
            "udpin" | "udpout" => {
                let addr: std::net::SocketAddr = rest
                    .parse()
                    .map_err(|_| bad("expected an IP address and port, e.g. 127.0.0.1:14540"))?;
                if addr.port() == 0 {
                    return Err(bad("port 0 is not a fixed port"));
                }
                Ok(if kind == "udpin" {
                    Px4Link::UdpIn(addr)
                } else {
                    Px4Link::UdpOut(addr)
                })
            }
            "serial" => {
                let (device, baud) = rest
                    .rsplit_once(':')
                    .ok_or_else(|| bad("expected serial:DEVICE:BAUD"))?;
                let baud: u32 = baud
                    .parse()
                    .ok()
                    .filter(|b| *b > 0)
                    .ok_or_else(|| bad("the baud rate must be a positive integer"))?;
                if device.is_empty() {
                    return Err(bad("the serial device is empty"));
                }
                Ok(Px4Link::Serial {
                    device: device.to_string(),
                    baud,
                })
            }
            _ => Err(bad(
                "unknown link kind (udpin, udpout or serial; tcp is not supported)",
            )),
        }
    }

    /// Semantic checks; each problem names its key.
    pub fn validate(&self) -> Result<(), String> {
        self.parse_link()?;
        for (key, v) in [
            ("px4.system_id", self.system_id),
            ("px4.target_system", self.target_system),
        ] {
            if v == 0 {
                return Err(format!("key `{key}` = 0: system id 0 is the broadcast id"));
            }
        }
        if self.system_id == self.target_system && self.component_id == self.target_component {
            return Err(format!(
                "key `px4.component_id` = {}: same system and component as the target PX4",
                self.component_id
            ));
        }
        let positive = [
            ("px4.heartbeat_hz", self.heartbeat_hz),
            ("px4.link_timeout_s", self.link_timeout_s),
            ("px4.ack_timeout_s", self.ack_timeout_s),
            ("px4.odometry_hz", self.odometry_hz),
            ("px4.attitude_hz", self.attitude_hz),
            ("px4.imu_hz", self.imu_hz),
            ("px4.esc_hz", self.esc_hz),
        ];
        for (key, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("key `{key}` = {v}: must be a positive number"));
            }
        }
        for (key, v) in [
            ("px4.odometry_hz", self.odometry_hz),
            ("px4.attitude_hz", self.attitude_hz),
            ("px4.imu_hz", self.imu_hz),
            ("px4.esc_hz", self.esc_hz),
        ] {
            if v > 1000.0 {
                return Err(format!("key `{key}` = {v}: above 1000 Hz"));
            }
        }
        let s = self.stream_before_offboard_s;
        if !(s.is_finite() && s > 1.0) {
            return Err(format!(
                "key `px4.stream_before_offboard_s` = {s}: PX4 wants the setpoint stream for more \
                 than 1 s before offboard"
            ));
        }
        if self.command_attempts == 0 {
            return Err("key `px4.command_attempts` = 0: at least one send is needed".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_parse_and_bad_values_name_their_key() {
        let mut c = Px4Config::default();
        assert!(c.validate().is_ok());
        assert_eq!(
            c.parse_link().unwrap(),
            Px4Link::UdpIn("127.0.0.1:14540".parse().unwrap())
        );
        c.link = "serial:/dev/ttyAMA0:921600".into();
        assert_eq!(
            c.parse_link().unwrap(),
            Px4Link::Serial {
                device: "/dev/ttyAMA0".into(),
                baud: 921600
            }
        );
        c.link = "tcpout:1.2.3.4:5".into();
        assert!(c.validate().unwrap_err().contains("px4.link"));
        c = Px4Config {
            stream_before_offboard_s: 0.8,
            ..Px4Config::default()
        };
        assert!(c
            .validate()
            .unwrap_err()
            .contains("px4.stream_before_offboard_s"));
        c = Px4Config {
            ack_timeout_s: f64::NAN,
            ..Px4Config::default()
        };
        assert!(c.validate().unwrap_err().contains("px4.ack_timeout_s"));
    }
}
