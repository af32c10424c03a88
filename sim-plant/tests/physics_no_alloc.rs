//! `World::step` and the readings do not allocate: a counting global allocator watches them
//! through contacts, taut and slack cables, sub-stepping and rejected inputs.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use nalgebra::Vector3;
use sim_plant::physics::{hanging_formation, BodyId, BoxObstacle, World, WorldParams};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn stepping_does_not_allocate() {
    let params = WorldParams {
        boxes: vec![BoxObstacle {
            center_ned: [0.0, 0.0, -0.1],
            half_extents: [0.5, 0.5, 0.1],
        }],
        ..WorldParams::default()
    };
    // Quads start 2 m up with the payload hanging; with too little thrust everything falls,
    // the payload onto the box, the quads to the ground.
    let f = hanging_formation(&params, Vector3::new(0.0, 0.0, -2.0), 1.6);
    let mut w = World::new(params, f.state).unwrap();
    let cmd = [[700.0; 4], [f64::NAN, 0.0, 900.0, 800.0]];
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    let mut sink = 0.0;
    for k in 0..4000 {
        w.step(if k % 2 == 0 { 0.0005 } else { 0.0013 }, &cmd);
        w.step(f64::NAN, &cmd);
        if k == 100 {
            w.pin_quad(1, true);
            w.set_external_force(BodyId::Payload, Vector3::new(1.0, 0.0, 0.0));
        }
        sink += w.cable(0).tension_n + w.anchor_force_frd(1).x + w.specific_force_frd(0).z;
        sink += w.payload_contact().normal_force_n + w.energy().total_j;
        sink += f64::from(u8::from(w.quad_on_ground(0)));
    }
    let allocated = ALLOCATIONS.load(Ordering::SeqCst) - before;
    assert!(w.quad_on_ground(0));
    assert_eq!(w.non_finite_step_count(), 0);
    assert!(sink.is_finite());
    assert_eq!(
        allocated, 0,
        "step or a reading allocated {allocated} times"
    );
    assert_eq!(w.rejected_input_count(), 4000);
}
