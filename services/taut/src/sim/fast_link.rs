//! The plant side of the in-process MAVLink link: what the plant's endpoint does with a
//! message from the bridge (attitude targets, heartbeats, commands; SET_MESSAGE_INTERVAL is
//! answered by the link layer, as on the wire).

use super::{FastDrone, FastRecording, MAV_CMD_SET_MESSAGE_INTERVAL};
use px4_bridge::mavlink::dialects::common::{MavMessage, MavResult, COMMAND_ACK_DATA};
use sim_plant::mavlink_link::inbound::{attitude_target, CommandLong};
use sim_plant::mavlink_link::{IntervalRequest, Stream};
use sim_plant::plant::Plant;

impl FastDrone {
    /// A message from the bridge to the emulated PX4 (what the plant's endpoint would do with it).
    pub(super) fn deliver_to_plant(
        &mut self,
        plant: &mut Plant,
        k: usize,
        t_ns: u64,
        msg: &MavMessage,
        out: &mut FastRecording,
    ) {
        let (sys, comp) = (self.plant_link.system_id, self.plant_link.component_id);
        match msg {
            MavMessage::SET_ATTITUDE_TARGET(d) => {
                if let Some(inbound) = attitude_target(d, sys, comp) {
                    plant.handle(k, inbound);
                }
            }
            MavMessage::HEARTBEAT(_) => {
                plant.handle(
                    k,
                    sim_plant::mavlink_link::Inbound::Heartbeat {
                        sysid: self.cfg.px4.system_id,
                        compid: self.cfg.px4.component_id,
                    },
                );
            }
            MavMessage::COMMAND_LONG(d) => {
                let cmd = CommandLong::from_parsed(d);
                if !cmd.is_for(sys, comp) {
                    return;
                }
                let result = if cmd.command == MAV_CMD_SET_MESSAGE_INTERVAL {
                    let stream = (cmd.params[0] >= 0.0)
                        .then(|| Stream::from_message_id(cmd.params[0] as u32))
                        .flatten();
                    match (stream, IntervalRequest::from_param_us(cmd.params[1])) {
                        (Some(stream), Some(req)) => {
                            self.streams.set(stream, req, t_ns);
                            MavResult::MAV_RESULT_ACCEPTED
                        }
                        _ => MavResult::MAV_RESULT_DENIED,
                    }
                } else {
                    plant
                        .handle(
                            k,
                            sim_plant::mavlink_link::Inbound::Command {
                                command: cmd.command,
                                params: cmd.params,
                                from: (self.cfg.px4.system_id, self.cfg.px4.component_id),
                            },
                        )
                        .unwrap_or(MavResult::MAV_RESULT_UNSUPPORTED)
                };
                let ack = MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                    command: d.command,
                    result,
                    progress: 0,
                    result_param2: 0,
                    target_system: self.cfg.px4.system_id,
                    target_component: self.cfg.px4.component_id,
                });
                self.deliver_to_bridge(k, t_ns, &ack, out);
            }
            _ => {}
        }
    }
}
