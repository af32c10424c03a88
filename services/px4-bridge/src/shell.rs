//! `taut svc px4-bridge`: the link to PX4 and the iceoryx2 topics around [`OffboardLink`].
//!
//! Two threads so neither direction waits for the other: the receive thread blocks on the link
//! (20 ms read timeout), frames, decodes and publishes VehicleState / ImuSample / MotorSpeeds;
//! the send thread waits on the ATTITUDE_SETPOINT event (10 ms timeout), sends each setpoint
//! at once, and runs the time-driven output (HEARTBEAT, commands). The core sits behind a mutex
//! held only for its pure calls, never across I/O. iceoryx2 ports are created in the thread
//! that uses them.

use crate::frame::{FrameCounters, FrameScanner, FrameWriter, MAX_FRAME};
use crate::transport::{self, Receiver, Sender};
use crate::{HandshakeStage, LinkStatus, MavMessage, OffboardLink, Telemetry};
use rt_config::periodic::now_ns;
use rt_config::Config;
use shared_types::{names, AttitudeSetpoint, ImuSample, MotorSpeeds, VehicleState};
use std::sync::{Mutex, MutexGuard};
use std::time::Duration;
use taut_ipc::{install_stop_handler, request_stop, stop_requested, Ipc};

/// Longest wait for a setpoint before the time-driven output runs anyway.
const SEND_WAKE: Duration = Duration::from_millis(10);
/// Receive buffer: a whole UDP datagram (PX4 may pack several frames into one).
const RX_BUFFER: usize = 65_536;

#[derive(Debug, Default)]
struct RxCounters {
    frames: FrameCounters,
    io_errors: u64,
    publish_errors: u64,
}

#[derive(Debug, Default)]
struct TxCounters {
    frames: u64,
    errors: u64,
    /// Frames not sent because PX4 has not spoken yet (udpin).
    no_peer: u64,
    ipc_errors: u64,
}

fn lock(link: &Mutex<OffboardLink>) -> MutexGuard<'_, OffboardLink> {
    // The core does not panic; if it ever did, its state is still the best we have.
    link.lock().unwrap_or_else(|e| e.into_inner())
}

pub fn run(cfg: &Config) -> Result<(), String> {
    install_stop_handler();
    let report = rt_config::rt::apply(&cfg.services.px4_bridge)
        .map_err(|e| format!("px4-bridge: real-time: {e}"))?;
    eprintln!("[px4-bridge] real-time: {report}");
    let link = Mutex::new(OffboardLink::new(&cfg.px4, &cfg.vehicle).map_err(|e| e.to_string())?);
    let address = cfg.px4.parse_link()?;
    let (rx, tx) = transport::open(&address)
        .map_err(|e| format!("key `px4.link` = {:?}: cannot open: {e}", cfg.px4.link))?;
    eprintln!("[px4-bridge] link {} open", cfg.px4.link);
    let (rx_result, tx_result) = std::thread::scope(|s| {
        let receiver = std::thread::Builder::new()
            .name("px4-bridge-rx".into())
            .spawn_scoped(s, || {
                let r = receive_loop(cfg, &link, rx);
                request_stop();
                r
            })
            .map_err(|e| format!("cannot start the receive thread: {e}"));
        let tx_result = match &receiver {
            Ok(_) => send_loop(cfg, &link, tx),
            Err(e) => Err(e.clone()),
        };
        request_stop();
        let rx_result = match receiver {
            Ok(h) => h
                .join()
                .unwrap_or_else(|_| Err("the receive thread panicked".into())),
            Err(e) => Err(e),
        };
        (rx_result, tx_result)
    });
    let status = lock(&link).status();
    let (rx, tx) = (rx_result?, tx_result?);
    eprintln!("[px4-bridge] stopped: {}", summary(&status, &rx, &tx));
    Ok(())
}

fn summary(s: &LinkStatus, rx: &RxCounters, tx: &TxCounters) -> String {
    let c = &s.counters;
    let f = &rx.frames;
    format!(
        "stage={:?} link_up={} flags={:#x} setpoints_sent={} setpoints_dropped={} \
         heartbeats_sent={} commands_sent={} command_retries={} ack_timeouts={} \
         acks_accepted={} acks_rejected={} acks_temporarily_rejected={} acks_unexpected={} \
         handshake_restarts={} intervals_accepted={} intervals_failed={} link_losses={} \
         heartbeats_received={} odometry={} imu={} esc={} telemetry_refused={} \
         foreign_messages={} other_messages={} frames_ok={} bad_crc={} unknown_id={} \
         truncated={} bad_header={} decode_errors={} garbage_bytes={} rx_io_errors={} \
         publish_errors={} tx_frames={} tx_errors={} tx_no_peer={} ipc_errors={}",
        s.stage,
        s.link_up,
        s.flags,
        c.setpoints_sent,
        c.setpoints_dropped,
        c.heartbeats_sent,
        c.commands_sent,
        c.command_retries,
        c.ack_timeouts,
        c.acks_accepted,
        c.acks_rejected,
        c.acks_temporarily_rejected,
        c.acks_unexpected,
        c.handshake_restarts,
        c.intervals_accepted,
        c.intervals_failed,
        c.link_losses,
        c.heartbeats_received,
        c.odometry,
        c.imu,
        c.esc,
        c.telemetry_refused,
        c.foreign_messages,
        c.other_messages,
        f.frames_ok,
        f.bad_crc,
        f.unknown_id,
        f.truncated,
        f.bad_header,
        f.decode_errors,
        f.garbage_bytes,
        rx.io_errors,
        rx.publish_errors,
        tx.frames,
        tx.errors,
        tx.no_peer,
        tx.ipc_errors
    )
}

fn receive_loop(
    cfg: &Config,
    link: &Mutex<OffboardLink>,
    mut rx: Receiver,
) -> Result<RxCounters, String> {
    let ipc = Ipc::new(
        &format!("{}-px4-bridge-rx", cfg.uav),
        &cfg.ipc_root,
        &cfg.uav,
    )
    .map_err(|e| e.to_string())?;
    let err = |e: taut_ipc::IpcError| e.to_string();
    let mut states = ipc
        .publisher::<VehicleState>(names::VEHICLE_STATE)
        .map_err(err)?;
    let mut imus = ipc.publisher::<ImuSample>(names::IMU).map_err(err)?;
    let mut motors = ipc
        .publisher::<MotorSpeeds>(names::MOTOR_SPEEDS)
        .map_err(err)?;
    let target = u32::from(cfg.px4.target_system);
    let datagrams = rx.datagrams();
    let mut buf = vec![0u8; RX_BUFFER];
    let mut kept = 0; // stream: bytes of an incomplete frame kept from the previous read
    let mut scanner = FrameScanner::new();
    let mut c = RxCounters::default();
    let mut publish = |t: Telemetry, errors: &mut u64| {
        let r = match t {
            Telemetry::State(s) => states.publish(s).map(drop),
            Telemetry::Imu(s) => imus.publish(s).map(drop),
            Telemetry::Motors(s) => motors.publish(s).map(drop),
        };
        *errors += u64::from(r.is_err());
    };
    while !stop_requested() {
        match rx.recv(&mut buf[kept..]) {
            Ok(Some((n, from))) => {
                let now = now_ns();
                let len = kept + n;
                let mut from_px4 = false;
                let consumed = scanner.scan(&buf[..len], datagrams, |header, msg| {
                    from_px4 |= header.system_id == target;
                    // The guard is dropped before publishing.
                    let sample = lock(link).on_message(now, header, msg);
                    if let Some(t) = sample {
                        publish(t, &mut c.publish_errors);
                    }
                });
                if datagrams {
                    kept = 0;
                    if let (true, Some(from)) = (from_px4, from) {
                        rx.heard_px4(from);
                    }
                } else {
                    buf.copy_within(consumed..len, 0);
                    kept = (len - consumed).min(MAX_FRAME);
                }
            }
            Ok(None) => {}
            Err(e) => {
                if c.io_errors == 0 {
                    eprintln!("[px4-bridge] receive error: {e} (further ones only counted)");
                }
                c.io_errors += 1;
                // A persistent error (serial unplugged) must not spin the core.
                std::thread::sleep(Duration::from_millis(10));
            }
        }
        let update = lock(link).flags_update(now_ns());
        if let Some(s) = update {
            publish(Telemetry::State(s), &mut c.publish_errors);
        }
    }
    c.frames = scanner.counters();
    Ok(c)
}

fn send_frame(tx: &mut Sender, writer: &mut FrameWriter, msg: &MavMessage, c: &mut TxCounters) {
    match tx.send(writer.encode(msg)) {
        Ok(true) => c.frames += 1,
        Ok(false) => c.no_peer += 1,
        Err(e) => {
            if c.errors == 0 {
                eprintln!("[px4-bridge] send error: {e} (further ones only counted)");
            }
            c.errors += 1;
        }
    }
}

fn send_loop(
    cfg: &Config,
    link: &Mutex<OffboardLink>,
    mut tx: Sender,
) -> Result<TxCounters, String> {
    let ipc = Ipc::new(
        &format!("{}-px4-bridge-tx", cfg.uav),
        &cfg.ipc_root,
        &cfg.uav,
    )
    .map_err(|e| e.to_string())?;
    let setpoints = ipc
        .subscriber::<AttitudeSetpoint>(names::ATTITUDE_SETPOINT)
        .map_err(|e| e.to_string())?;
    let mut writer = FrameWriter::new(cfg.px4.system_id, cfg.px4.component_id);
    let mut c = TxCounters::default();
    // Time-driven output collected under the lock, sent after it (capacity kept: no allocation).
    let mut out: Vec<MavMessage> = Vec::with_capacity(16);
    let mut last = (HandshakeStage::Idle, false);
    while !stop_requested() {
        // A stop signal interrupts the wait: that is not an error.
        if setpoints.wait(SEND_WAKE).is_err() && !stop_requested() {
            c.ipc_errors += 1;
        }
        let drained = setpoints.drain(&mut |sp| {
            let msg = lock(link).on_setpoint(now_ns(), &sp);
            if let Some(msg) = msg {
                send_frame(&mut tx, &mut writer, &msg, &mut c);
            }
        });
        c.ipc_errors += u64::from(drained.is_err());
        out.clear();
        let status = {
            let mut l = lock(link);
            l.poll(now_ns(), &mut |m| out.push(m.clone()));
            l.status()
        };
        for msg in &out {
            send_frame(&mut tx, &mut writer, msg, &mut c);
        }
        if (status.stage, status.link_up) != last {
            log_change(&status, last);
            last = (status.stage, status.link_up);
        }
    }
    Ok(c)
}

fn log_change(s: &LinkStatus, (stage, link_up): (HandshakeStage, bool)) {
    if s.link_up != link_up {
        let what = if s.link_up { "PX4 heard" } else { "PX4 lost" };
        eprintln!("[px4-bridge] link: {what}");
    }
    if s.stage != stage {
        match s.failure {
            Some(f) if s.stage == HandshakeStage::Failed => {
                eprintln!("[px4-bridge] handshake FAILED: {f}")
            }
            _ => eprintln!("[px4-bridge] handshake: {:?}", s.stage),
        }
    }
}
