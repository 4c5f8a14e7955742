//! The contact pass allocates nothing in a time step once warmed up, also
//! in the steps that rebuild the broad phase's candidate lists.
//!
//! A global allocator that counts every allocation of the process: this
//! file is its own test binary and holds a single test, so nothing else
//! allocates while it counts. The pass runs in a one-thread rayon pool:
//! with more threads rayon's own work-stealing queues grow now and then
//! (a few allocations per hundred steps, none of them drape's buffers).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use drape_contact::Amplitude;
use drape_contact::{ContactSettings, ExplicitContact, Surface, Tool, ToolMotion};
use nalgebra::Vector3;

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller's contract, passed on.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract, passed on.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller's contract, passed on.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn steps_that_rebuild_the_candidates_allocate_nothing() {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a rayon pool")
        .install(sheet_on_a_rising_ball);
}

fn sheet_on_a_rising_ball() {
    // A 30 × 30 sheet sinking onto a rising sphere with friction, from
    // above the sphere's box: a 0.5 mm margin makes the lists be rebuilt
    // every few steps, and the sheet enters the box after the warm-up.
    let ball = Tool {
        name: "ball".into(),
        surface: Surface::sphere(Vector3::zeros(), 20.0).unwrap(),
        motion: ToolMotion::Displacement {
            direction: Vector3::z(),
            distance: 10.0,
            amplitude: Amplitude::Ramp { duration: 1.0 },
        },
        friction: 0.2,
    };
    let settings = ContactSettings {
        offset: 0.1,
        margin: 0.5,
        ..ContactSettings::default()
    };
    let side = 30;
    let n = side * side;
    let mut x: Vec<Vector3<f64>> = (0..n)
        .map(|i| {
            let (a, b) = ((i % side) as f64, (i / side) as f64);
            Vector3::new(2.0 * a - 29.0, 2.0 * b - 29.0, 22.5)
        })
        .collect();
    let mass = vec![1e-6; n];
    let movable = vec![true; n];
    let mut contact = ExplicitContact::new(vec![ball], n, settings);
    let dt = 0.002;
    let step = |k: usize, x: &mut Vec<Vector3<f64>>, contact: &mut ExplicitContact| {
        let mut v = vec![Vector3::new(0.0, 0.0, -20.0); n];
        let mut x_pred: Vec<Vector3<f64>> = x.iter().zip(&v).map(|(p, w)| p + w * dt).collect();
        let start = ALLOCATIONS.load(Ordering::Relaxed);
        contact
            .enforce(&mut x_pred, &mut v, &mass, &movable, k as f64 * dt, dt)
            .unwrap();
        let allocated = ALLOCATIONS.load(Ordering::Relaxed) - start;
        *x = x_pred;
        allocated
    };
    // Warm-up: the first build and the scratch buffers' growth.
    for k in 1..=20 {
        step(k, &mut x, &mut contact);
    }
    let before = contact.candidate_counts();
    let allocated: usize = (21..=120).map(|k| step(k, &mut x, &mut contact)).sum();
    let after = contact.candidate_counts();
    assert_eq!(allocated, 0, "allocations in 100 steps");
    // The lists were rebuilt (they grew) and the sheet is on the ball.
    assert!(after[0] > before[0], "{before:?} → {after:?}");
    assert!(
        contact
            .status
            .iter()
            .any(|s| *s != drape_contact::ContactStatus::Open)
    );
}
