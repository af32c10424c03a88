//! [`OffboardLink`]: the bridge's pure core. No I/O, no clock: every call takes `now_ns`
//! (CLOCK_MONOTONIC in the shell); no allocation after `new`.

use crate::command::{CommandTiming, PendingCommand};
use crate::telemetry::{imu_sample, motor_speeds, vehicle_state};
use crate::{normalized_thrust, BridgeConfigError, Telemetry, PX4_CUSTOM_MODE_OFFBOARD};
use crate::{STREAM_GAP_S, TYPE_MASK_ATTITUDE_THRUST};
use mavlink::dialects::common::{
    AttitudeTargetTypemask, MavAutopilot, MavCmd, MavMessage, MavModeFlag, MavState, MavType,
    HEARTBEAT_DATA, SET_ATTITUDE_TARGET_DATA,
};
use mavlink::MavHeader;
use shared_types::{setpoint_flags, vehicle_flags, AttitudeSetpoint, VehicleState};

mod handshake;

pub use crate::status::{HandshakeFailure, HandshakeStage, LinkCounters, LinkStatus};

/// Streams asked for with SET_MESSAGE_INTERVAL, one at a time (acks carry only the command
/// id): ODOMETRY, ATTITUDE_QUATERNION, HIGHRES_IMU, ESC_STATUS at px4.{odometry, attitude,
/// imu, esc}_hz.
const STREAMS: [u32; 4] = [331, 31, 105, 291];

/// The offboard link to one PX4: setpoints out, telemetry in, the handshake in between.
pub struct OffboardLink {
    timing: CommandTiming,
    own: (u8, u8),
    heartbeat_period_ns: u64,
    link_timeout_ns: u64,
    stream_before_ns: u64,
    stream_gap_ns: u64,
    mass_kg: f64,
    hover_throttle: f64,
    gravity_m_s2: f64,
    interval_us: [f32; 4],
    last_heartbeat_ns: Option<u64>,
    base_mode: u8,
    custom_mode: u32,
    link_up: bool,
    /// When the link last came up: setpoints sent before it may not have reached PX4.
    link_up_since_ns: u64,
    stream_start_ns: Option<u64>,
    last_setpoint_ns: Option<u64>,
    arm_request: bool,
    stage: HandshakeStage,
    failure: Option<HandshakeFailure>,
    set_mode: PendingCommand,
    arm: PendingCommand,
    confirm_deadline_ns: u64,
    interval: PendingCommand,
    /// Index into [`STREAMS`] of the request under way; 4 when all are settled.
    interval_next: usize,
    next_heartbeat_ns: u64,
    last_state: Option<VehicleState>,
    published_flags: u32,
    counters: LinkCounters,
}

fn seconds_ns(s: f64) -> u64 {
    (s * 1e9).round() as u64
}

impl OffboardLink {
    pub fn new(
        px4: &rt_config::Px4Config,
        vehicle: &rt_config::VehicleConfig,
    ) -> Result<Self, BridgeConfigError> {
        px4.validate().map_err(BridgeConfigError::Px4)?;
        let v = vehicle;
        let checks = [
            (
                "vehicle.mass_kg",
                v.mass_kg,
                v.mass_kg > 0.0,
                "must be positive",
            ),
            (
                "vehicle.hover_throttle",
                v.hover_throttle,
                v.hover_throttle > 0.0 && v.hover_throttle <= 1.0,
                "must be in (0, 1]",
            ),
            (
                "vehicle.gravity_m_s2",
                v.gravity_m_s2,
                v.gravity_m_s2 > 0.0,
                "must be positive",
            ),
        ];
        for (key, value, ok, why) in checks {
            if !(ok && value.is_finite()) {
                return Err(BridgeConfigError::Vehicle { key, value, why });
            }
        }
        let hz = [px4.odometry_hz, px4.attitude_hz, px4.imu_hz, px4.esc_hz];
        Ok(Self {
            timing: CommandTiming {
                ack_timeout_ns: seconds_ns(px4.ack_timeout_s),
                attempts: px4.command_attempts,
                target_system: px4.target_system,
                target_component: px4.target_component,
            },
            own: (px4.system_id, px4.component_id),
            heartbeat_period_ns: seconds_ns(1.0 / px4.heartbeat_hz),
            link_timeout_ns: seconds_ns(px4.link_timeout_s),
            stream_before_ns: seconds_ns(px4.stream_before_offboard_s),
            stream_gap_ns: seconds_ns(STREAM_GAP_S),
            mass_kg: v.mass_kg,
            hover_throttle: v.hover_throttle,
            gravity_m_s2: v.gravity_m_s2,
            interval_us: hz.map(|f| (1e6 / f) as f32),
            last_heartbeat_ns: None,
            base_mode: 0,
            custom_mode: 0,
            link_up: false,
            link_up_since_ns: 0,
            stream_start_ns: None,
            last_setpoint_ns: None,
            arm_request: false,
            stage: HandshakeStage::Idle,
            failure: None,
            set_mode: PendingCommand::new(MavCmd::MAV_CMD_DO_SET_MODE),
            arm: PendingCommand::new(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM),
            confirm_deadline_ns: 0,
            interval: PendingCommand::new(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL),
            interval_next: 0,
            next_heartbeat_ns: 0,
            last_state: None,
            published_flags: 0,
            counters: LinkCounters::default(),
        })
    }

    /// A parsed message from PX4. Returns the sample to publish, if any.
    pub fn on_message(
        &mut self,
        now_ns: u64,
        header: &MavHeader,
        msg: &MavMessage,
    ) -> Option<Telemetry> {
        let t = &self.timing;
        if header.system_id != u32::from(t.target_system)
            || header.component_id != t.target_component
        {
            self.counters.foreign_messages += 1;
            return None;
        }
        let sample = match msg {
            MavMessage::HEARTBEAT(h) => {
                self.on_heartbeat(now_ns, h);
                return None;
            }
            MavMessage::COMMAND_ACK(a) => {
                self.refresh_link(now_ns);
                self.on_ack(now_ns, a);
                return None;
            }
            MavMessage::ODOMETRY(o) => vehicle_state(now_ns, o).map(|mut s| {
                self.counters.odometry += 1;
                self.refresh_link(now_ns);
                s.custom_mode = self.custom_mode;
                s.flags = self.flags();
                self.published_flags = s.flags;
                self.last_state = Some(s);
                Telemetry::State(s)
            }),
            MavMessage::HIGHRES_IMU(m) => imu_sample(now_ns, m).map(|s| {
                self.counters.imu += 1;
                Telemetry::Imu(s)
            }),
            MavMessage::ESC_STATUS(m) => motor_speeds(now_ns, m).map(|s| {
                self.counters.esc += 1;
                Telemetry::Motors(s)
            }),
            _ => {
                self.counters.other_messages += 1;
                return None;
            }
        };
        if sample.is_err() {
            self.counters.telemetry_refused += 1;
        }
        sample.ok()
    }

    /// The controller's setpoint -> the SET_ATTITUDE_TARGET to send now (None, counted, if it
    /// is not finite or not a rotation).
    pub fn on_setpoint(&mut self, now_ns: u64, sp: &AttitudeSetpoint) -> Option<MavMessage> {
        let q = sp.attitude_wxyz;
        let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
        if !(sp.thrust_n.is_finite() && norm.is_finite() && (0.5..=2.0).contains(&norm)) {
            self.counters.setpoints_dropped += 1;
            return None;
        }
        if self
            .last_setpoint_ns
            .is_none_or(|t| now_ns.saturating_sub(t) > self.stream_gap_ns)
        {
            self.stream_stopped();
            self.stream_start_ns = Some(now_ns);
        }
        self.last_setpoint_ns = Some(now_ns);
        let request = sp.flags & setpoint_flags::ARM_REQUEST != 0;
        if !request && self.stage != HandshakeStage::Idle {
            self.reset_handshake();
        }
        self.arm_request = request;
        self.counters.setpoints_sent += 1;
        Some(MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
            time_boot_ms: (now_ns / 1_000_000) as u32,
            q: q.map(|c| (c / norm) as f32),
            body_roll_rate: 0.0,
            body_pitch_rate: 0.0,
            body_yaw_rate: 0.0,
            thrust: normalized_thrust(
                sp.thrust_n,
                self.mass_kg,
                self.hover_throttle,
                self.gravity_m_s2,
            ),
            target_system: self.timing.target_system,
            target_component: self.timing.target_component,
            type_mask: AttitudeTargetTypemask::from_bits_retain(TYPE_MASK_ATTITUDE_THRUST),
            thrust_body: [0.0; 3],
        }))
    }

    /// Time-driven output: HEARTBEAT, the handshake's commands and their retries, the
    /// SET_MESSAGE_INTERVAL requests.
    pub fn poll(&mut self, now_ns: u64, send: &mut impl FnMut(&MavMessage)) {
        self.refresh_link(now_ns);
        if now_ns >= self.next_heartbeat_ns {
            send(&self.heartbeat());
            self.counters.heartbeats_sent += 1;
            // Keep the grid; after a stall (or at the start) restart it from now.
            let next = self.next_heartbeat_ns + self.heartbeat_period_ns;
            self.next_heartbeat_ns = if next <= now_ns {
                now_ns + self.heartbeat_period_ns
            } else {
                next
            };
        }
        if self
            .last_setpoint_ns
            .is_some_and(|t| now_ns.saturating_sub(t) > self.stream_gap_ns)
        {
            self.stream_stopped();
        }
        self.advance_handshake(now_ns, send);
        self.advance_intervals(now_ns, send);
    }

    /// The last VehicleState with its flags refreshed, when they changed since the last one
    /// returned (e.g. LINK_LOST while no telemetry arrives). None before the first ODOMETRY.
    /// Its header keeps the ODOMETRY's receipt time.
    pub fn flags_update(&mut self, now_ns: u64) -> Option<VehicleState> {
        self.refresh_link(now_ns);
        let flags = self.flags();
        let state = self.last_state.as_mut()?;
        if flags == self.published_flags {
            return None;
        }
        self.published_flags = flags;
        state.flags = flags;
        state.custom_mode = self.custom_mode;
        Some(*state)
    }

    pub fn status(&self) -> LinkStatus {
        LinkStatus {
            stage: self.stage,
            failure: self.failure,
            link_up: self.link_up,
            flags: self.flags(),
            custom_mode: self.custom_mode,
            counters: self.counters,
        }
    }

    fn flags(&self) -> u32 {
        let mut f = 0;
        if self.base_mode & MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED.bits() != 0 {
            f |= vehicle_flags::ARMED;
        }
        if self.offboard() {
            f |= vehicle_flags::OFFBOARD;
        }
        if !self.link_up {
            f |= vehicle_flags::LINK_LOST;
        }
        f | match self.stage {
            HandshakeStage::Done => vehicle_flags::HANDSHAKE_DONE,
            HandshakeStage::Failed => vehicle_flags::HANDSHAKE_FAILED,
            HandshakeStage::LeftOffboard => vehicle_flags::LEFT_OFFBOARD,
            _ => 0,
        }
    }

    fn offboard(&self) -> bool {
        self.custom_mode & 0x00FF_0000 == PX4_CUSTOM_MODE_OFFBOARD
    }

    fn armed_in_offboard(&self) -> bool {
        self.flags() & (vehicle_flags::ARMED | vehicle_flags::OFFBOARD)
            == vehicle_flags::ARMED | vehicle_flags::OFFBOARD
    }

    fn heartbeat(&self) -> MavMessage {
        MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 0,
            mavtype: MavType::MAV_TYPE_ONBOARD_CONTROLLER,
            autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
            base_mode: MavModeFlag::empty(),
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        })
    }

    fn refresh_link(&mut self, now_ns: u64) {
        let up = self
            .last_heartbeat_ns
            .is_some_and(|t| now_ns.saturating_sub(t) <= self.link_timeout_ns);
        if up != self.link_up {
            if up {
                self.link_up_since_ns = now_ns;
                // (Re)connected: PX4 may have rebooted and forgotten the stream rates.
                self.interval_next = 0;
                self.interval.cancel();
            } else {
                self.counters.link_losses += 1;
            }
            self.link_up = up;
        }
    }
}
