//! `taut svc px4-bridge` on a serial link: a pseudo-terminal stands in for TELEM2. PX4 is played
//! by this test (framing with the bridge's own public FrameWriter / FrameScanner): every write
//! is split in two so frames straddle reads, and a bogus header (0xFD, length 255) sits in the
//! byte stream every 140 ms. Checked: the stream-rate requests, the whole offboard handshake and
//! the VehicleState over serial, the bogus headers counted as rejected candidates.

mod bridge_support;

use bridge_support::{counter, fly, start_bridge, test_setpoint};
use px4_bridge::frame::{FrameScanner, FrameWriter};
use px4_bridge::mavlink::dialects::common::{
    MavCmd, MavFrame, MavModeFlag, MavResult, COMMAND_ACK_DATA, HEARTBEAT_DATA, ODOMETRY_DATA,
};
use px4_bridge::MavMessage;
use shared_types::vehicle_flags as vf;
use std::fs::File;
use std::io::{Read, Write};
use std::os::fd::{AsRawFd, FromRawFd};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(Debug, Default)]
struct Px4Log {
    heartbeats: u64,
    setpoints: u64,
    commands: Vec<u16>,
}

/// A pty pair: (master, slave, slave path).
fn open_pty() -> (File, File, String) {
    let (mut master, mut slave) = (-1, -1);
    // SAFETY: openpty writes two fds; name, termios and winsize are optional (null).
    let r = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    assert_eq!(r, 0, "openpty failed");
    let mut name = [0u8; 128];
    // SAFETY: `name` is a writable buffer of the given length.
    let r = unsafe { libc::ttyname_r(slave, name.as_mut_ptr().cast(), name.len()) };
    assert_eq!(r, 0, "ttyname_r failed");
    let len = name.iter().position(|&b| b == 0).unwrap();
    let path = String::from_utf8_lossy(&name[..len]).into_owned();
    // SAFETY: fresh fds from openpty, owned by these Files from now on.
    unsafe { (File::from_raw_fd(master), File::from_raw_fd(slave), path) }
}

fn play_px4(mut pty: File, stop: Arc<AtomicBool>) -> Px4Log {
    let (mut w, mut scanner) = (FrameWriter::new(1, 1), FrameScanner::new());
    let (mut mode, mut armed) = (3u32 << 16, false);
    let (mut log, mut kept, mut buf) = (Px4Log::default(), Vec::new(), [0u8; 4096]);
    let mut next = Instant::now();
    for k in 0u64.. {
        if stop.load(Ordering::SeqCst) {
            break;
        }
        let mut bytes = Vec::new();
        if k % 5 == 0 {
            let base_mode = if armed {
                MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED
            } else {
                MavModeFlag::empty()
            };
            let hb = HEARTBEAT_DATA {
                custom_mode: mode,
                base_mode: base_mode | MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                ..HEARTBEAT_DATA::default()
            };
            bytes.extend(w.encode(&MavMessage::HEARTBEAT(hb)));
        }
        let odo = ODOMETRY_DATA {
            time_usec: k * 20_000,
            x: 1.5,
            y: -2.0,
            z: -1.25,
            q: [1.0, 0.0, 0.0, 0.0],
            frame_id: MavFrame::MAV_FRAME_LOCAL_NED,
            child_frame_id: MavFrame::MAV_FRAME_LOCAL_NED,
            ..ODOMETRY_DATA::default()
        };
        bytes.extend(w.encode(&MavMessage::ODOMETRY(odo)));
        if k % 7 == 3 {
            bytes.extend([0xFD, 0xFF, 0, 0, 0]);
        }
        let half = bytes.len() / 2;
        pty.write_all(&bytes[..half]).unwrap();
        pty.write_all(&bytes[half..]).unwrap();
        next += Duration::from_millis(20);
        while Instant::now() < next {
            let wait = next.saturating_duration_since(Instant::now()).as_millis() as i32;
            let mut pfd = libc::pollfd {
                fd: pty.as_raw_fd(),
                events: libc::POLLIN,
                revents: 0,
            };
            // SAFETY: one valid pollfd.
            if unsafe { libc::poll(&mut pfd, 1, wait.max(1)) } <= 0 {
                continue;
            }
            let n = pty.read(&mut buf).unwrap_or(0);
            kept.extend_from_slice(&buf[..n]);
            let mut acks = Vec::new();
            let used = scanner.scan(&kept, false, |_, m| match m {
                MavMessage::HEARTBEAT(_) => log.heartbeats += 1,
                MavMessage::SET_ATTITUDE_TARGET(_) => log.setpoints += 1,
                MavMessage::COMMAND_LONG(c) => {
                    log.commands.push(c.command as u16);
                    match c.command {
                        MavCmd::MAV_CMD_DO_SET_MODE => mode = 6 << 16,
                        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => armed = true,
                        _ => {}
                    }
                    acks.push(COMMAND_ACK_DATA {
                        command: c.command,
                        result: MavResult::MAV_RESULT_ACCEPTED,
                        target_system: 1,
                        target_component: 191,
                        ..COMMAND_ACK_DATA::default()
                    });
                }
                _ => {}
            });
            kept.drain(..used);
            for a in acks {
                pty.write_all(w.encode(&MavMessage::COMMAND_ACK(a)))
                    .unwrap();
            }
        }
    }
    log
}

#[test]
fn bridge_flies_the_handshake_over_a_serial_line() {
    let (master, _slave, path) = open_pty();
    let (cfg, mut bridge, _file) = start_bridge("serial", &format!("serial:{path}:921600"));
    let stop = Arc::new(AtomicBool::new(false));
    let px4 = {
        let stop = stop.clone();
        std::thread::spawn(move || play_px4(master, stop))
    };
    let flying = vf::ARMED | vf::OFFBOARD | vf::HANDSHAKE_DONE;
    let o = fly(
        &cfg,
        test_setpoint(),
        |o| !o.states.iter().any(|s| s.flags == flying),
        Duration::from_secs(8),
    );
    stop.store(true, Ordering::SeqCst);
    let log = px4.join().expect("the PX4 thread panicked");
    let (ok, _, err) = bridge.stop();
    println!("bridge: {}\npx4: {log:?}", err.lines().last().unwrap_or(""));
    assert!(ok, "{err}");
    let s = o.states.iter().find(|s| s.flags == flying);
    let s = s.unwrap_or_else(|| panic!("never armed in offboard over serial:\n{err}"));
    assert_eq!(s.position_ned_m, [1.5, -2.0, -1.25]);
    let count = |id: u16| log.commands.iter().filter(|&&c| c == id).count();
    assert_eq!((count(511), count(176), count(400)), (4, 1, 1), "{log:?}");
    assert!(log.heartbeats >= 1 && log.setpoints >= 100, "{log:?}");
    // A bogus header swallows the next bytes as its candidate: rejected as a bad CRC or, when
    // the id bytes it reads are not a known message, as an unknown id.
    let rejected = counter(&err, "bad_crc") + counter(&err, "unknown_id");
    assert!(rejected >= 5, "bogus headers not counted:\n{err}");
    assert_eq!(counter(&err, "rx_io_errors"), 0);
}
