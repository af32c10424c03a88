//! `ControllerStage::step` must not allocate: a counting global allocator watches every branch
//! (active tension, stale tension, slack, saturation, stale mission, non-finite, idle).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

use controller::ControllerStage;
use rt_config::{ControllerConfig, VehicleConfig};
use shared_types::{
    mission_flags, vehicle_flags, Header, MissionSetpoint, TensionSample, VehicleState,
};

struct Counting;

static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn header(t: u64) -> Header {
    Header {
        sequence: t / 10_000_000,
        t_origin_ns: t,
        t_publish_ns: t,
    }
}

#[test]
fn step_does_not_allocate_on_any_branch() {
    let mut stage =
        ControllerStage::new(&VehicleConfig::default(), &ControllerConfig::default()).unwrap();
    let mut outputs = [0.0f64; 2000];
    // The counter sees allocations (so the check below can fail).
    let probe = ALLOCATIONS.load(Ordering::SeqCst);
    drop(std::hint::black_box(Box::new(1u64)));
    assert!(ALLOCATIONS.load(Ordering::SeqCst) > probe);
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    for k in 0..2000u64 {
        let t = k * 10_000_000;
        let phase = k / 200;
        let mut state = VehicleState {
            header: header(t),
            position_ned_m: [
                -1.25 + 0.01 * (k % 7) as f64,
                -0.5,
                -2.1 + 5.0 * (phase == 3) as u8 as f64,
            ],
            velocity_ned_m_s: [0.1, -0.2, 0.3],
            attitude_wxyz: [0.99, 0.1, -0.05, 0.02],
            flags: vehicle_flags::ARMED,
            ..Default::default()
        };
        if phase == 5 {
            state.flags = 0;
        }
        if phase == 6 && k % 3 == 0 {
            state.velocity_ned_m_s[1] = f64::NAN;
        }
        let tension = TensionSample {
            header: header(if phase == 2 { 0 } else { t }),
            force_body_n: [0.5, 1.3 * (phase != 1) as u8 as f64, 4.9],
            flags: (phase == 4) as u32,
            ..Default::default()
        };
        let mission = MissionSetpoint {
            header: header(if phase == 7 { 0 } else { t }),
            flags: mission_flags::TENSION_ENABLED * (phase != 8) as u32,
            position_ned_m: [-1.25, -0.5, -2.1],
            peer_position_ned_m: [-1.25, 0.5 + 4.0 * (phase == 9) as u8 as f64, -2.1],
            yaw_rad: 0.5,
            ..Default::default()
        };
        let sp = stage.step(t, &state, Some(&tension), Some(&mission));
        outputs[k as usize] = sp.thrust_n;
    }
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    assert_eq!(after - before, 0, "allocations in 2000 steps");
    assert!(outputs.iter().all(|u| u.is_finite()));
    let c = stage.counters();
    // Every branch was visited.
    assert!(c.idle_steps > 0 && c.non_finite_inputs > 0 && c.stale_tension_steps > 0);
    assert!(c.stale_mission_steps > 0 && c.thrust_limited_steps > 0);
    assert!(c.formation_limit_steps > 0 && c.tension_flagged_steps > 0);
}
