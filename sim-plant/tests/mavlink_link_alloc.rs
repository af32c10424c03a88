//! The endpoint's steady state does not allocate: `send_due` and `poll` (with commands,
//! setpoints, bad frames and interval changes arriving) are counted by a global allocator that
//! only counts on the thread and during the calls under test.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::net::UdpSocket;
use std::sync::atomic::{AtomicU64, Ordering};

use mavlink::dialects::common::{
    AttitudeTargetTypemask, MavCmd, MavMessage, COMMAND_LONG_DATA, SET_ATTITUDE_TARGET_DATA,
};
use sim_plant::mavlink_link::codec::FrameWriter;
use sim_plant::mavlink_link::{Inbound, LinkConfig, MavResult, MavlinkEndpoint, Telemetry};

struct CountingAlloc;

static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);
thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
}

unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.try_with(|c| c.get()).unwrap_or(false) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.try_with(|c| c.get()).unwrap_or(false) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAlloc = CountingAlloc;

fn counted<R>(f: impl FnOnce() -> R) -> R {
    COUNTING.with(|c| c.set(true));
    let r = f();
    COUNTING.with(|c| c.set(false));
    r
}

#[test]
fn mavlink_endpoint_send_due_and_poll_do_not_allocate() {
    let peer = UdpSocket::bind("127.0.0.1:0").unwrap();
    peer.set_nonblocking(true).unwrap();
    let config = LinkConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        remote: peer.local_addr().unwrap(),
        ..LinkConfig::px4_sitl(0)
    };
    let mut ep = MavlinkEndpoint::open(config).unwrap();
    let to = ep.local_addr();

    // Pre-encoded traffic from the companion (allocated before counting starts).
    let mut w = FrameWriter::new(42, 191);
    let setpoint = w
        .encode(&MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
            q: [1.0, 0.0, 0.0, 0.0],
            thrust: 0.5,
            target_system: 1,
            target_component: 1,
            type_mask: AttitudeTargetTypemask::from_bits_retain(7),
            ..SET_ATTITUDE_TARGET_DATA::default()
        }))
        .to_vec();
    let cmd = |command, p1, p2| {
        MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            command,
            param1: p1,
            param2: p2,
            target_system: 1,
            target_component: 1,
            ..COMMAND_LONG_DATA::default()
        })
    };
    let arm = w
        .encode(&cmd(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1.0, 0.0))
        .to_vec();
    let interval = w
        .encode(&cmd(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL, 331.0, 5000.0))
        .to_vec();
    let request = w
        .encode(&cmd(MavCmd::MAV_CMD_REQUEST_MESSAGE, 148.0, 0.0))
        .to_vec();
    let mut bad = setpoint.clone();
    let n = bad.len();
    bad[n - 1] ^= 0xFF;
    let garbage = vec![0x55u8; 64];

    let telemetry = Telemetry::default();
    let mut delivered = 0u32;
    let mut handler = |i: Inbound| {
        delivered += 1;
        matches!(i, Inbound::Command { .. }).then_some(MavResult::MAV_RESULT_ACCEPTED)
    };
    let mut sink = [0u8; 2048];
    let mut step = |k: u64, count: bool| {
        let t_ns = k * 1_000_000;
        if k.is_multiple_of(10) {
            for d in [&setpoint, &arm, &interval, &request, &bad, &garbage] {
                peer.send_to(d, to).unwrap();
            }
        }
        let sent = if count {
            counted(|| {
                ep.poll(t_ns, &mut handler);
                ep.send_due(t_ns, &telemetry)
            })
        } else {
            ep.poll(t_ns, &mut handler);
            ep.send_due(t_ns, &telemetry)
        };
        while peer.recv_from(&mut sink).is_ok() {}
        sent
    };
    for k in 0..200 {
        step(k, false);
    }
    let probe = ALLOCATIONS.load(Ordering::Relaxed);
    counted(|| drop(std::hint::black_box(vec![0u8; 16])));
    assert_eq!(
        ALLOCATIONS.load(Ordering::Relaxed),
        probe + 1,
        "the counter sees allocations"
    );

    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let mut frames = 0;
    for k in 200..2200 {
        frames += step(k, true);
    }
    let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
    assert!(frames > 500, "the loop did send ({frames} frames)");
    assert_eq!(allocations, 0, "allocations in 2000 steady-state steps");
    let c = ep.counters();
    assert!(
        c.rx_bad_crc >= 200 && c.rx_frames_ok >= 800,
        "traffic arrived: {c:?}"
    );
    assert!(delivered >= 400);
}
