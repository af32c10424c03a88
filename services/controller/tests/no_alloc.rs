//! `ControllerStage::step` must not allocate: a counting global allocator watches every branch
//! (active tension, stale tension, slack, saturation, stale mission, non-finite, idle), for
//! both laws. Allocations are counted per thread: the test harness's own thread allocates
//! while it waits, which made a global count flaky.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use controller::ControllerStage;
use rt_config::{ControllerConfig, ControllerLaw, VehicleConfig};
use shared_types::{
    mission_flags, vehicle_flags, Header, MissionSetpoint, TensionSample, VehicleState,
};

struct Counting;

thread_local! {
    // Const-initialised, no destructor: reading it never allocates.
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn count() {
    ALLOCATIONS.with(|c| c.set(c.get() + 1));
}

fn allocations() -> u64 {
    ALLOCATIONS.with(|c| c.get())
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
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
    for law in [ControllerLaw::Proposed, ControllerLaw::Geometric] {
        no_allocation_with(law);
    }
}

fn no_allocation_with(law: ControllerLaw) {
    let cfg = ControllerConfig {
        law,
        ..Default::default()
    };
    let mut stage = ControllerStage::new(&VehicleConfig::default(), &cfg).unwrap();
    let mut outputs = [0.0f64; 2000];
    // The counter sees allocations (so the check below can fail).
    let probe = allocations();
    drop(std::hint::black_box(Box::new(1u64)));
    assert!(allocations() > probe);
    let before = allocations();
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
    let after = allocations();
    assert_eq!(after - before, 0, "allocations in 2000 steps of {law:?}");
    assert!(outputs.iter().all(|u| u.is_finite()));
    let c = stage.counters();
    // Every branch was visited.
    assert!(c.idle_steps > 0 && c.non_finite_inputs > 0 && c.stale_tension_steps > 0);
    assert!(c.stale_mission_steps > 0 && c.thrust_limited_steps > 0);
    assert!(c.formation_limit_steps > 0 && c.tension_flagged_steps > 0);
}
