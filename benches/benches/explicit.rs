//! Criterion benches of the explicit driver's step throughput on a
//! 100 × 100 quad blank (200 × 200 mm, carbon-prepreg-2x2 at 0/90): the left
//! edge clamped, the right edge pulled 0.5 mm with a smooth step over the
//! run. One iteration is a run of [`STEPS`] steps at the stable Δt from a
//! fresh copy of the initial state, with no output frames, on 1 and on 2
//! rayon threads; fibres as trusses (the paper's representation) or
//! embedded in the quads.
//!
//! The throughput is in node·steps per second (`Throughput::Elements` of
//! nodes × steps); the element updates per second are that times
//! elements/nodes, printed with the model sizes at the start. A run also
//! does one force pass and two strain-energy sums outside its steps; the
//! `run_overhead` bench times a one-step run to show that share.
//!
//! Before benching, the heap allocations per step are counted (a counting
//! global allocator, runs of 2 and [`STEPS`] steps): the hot loop should not
//! allocate.
//!
//! `cargo bench -p drape-benches --bench explicit`; a short run with
//! `-- --warm-up-time 1 --measurement-time 3`. With
//! `DRAPE_BENCH_CLOCK=thread-cpu` the one-thread runs are timed by the pool
//! thread's CPU time (see the crate docs); the two-thread runs always by
//! the wall clock.

use std::alloc::{GlobalAlloc, Layout, System};
use std::hint::black_box;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use drape_benches::{Clock, Stopwatch};
use drape_constitutive::Material;
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{Amplitude, BoundaryCondition, Model, Motion, State};
use drape_time::{Explicit, ExplicitSettings, NoObserver, RunSummary};
use nalgebra::Vector3;

/// Steps per iteration.
const STEPS: u32 = 100;

/// The system allocator, counting allocations (and reallocations).
struct Counting;

static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

// SAFETY: forwards every call to `System` unchanged.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller's contract is `System`'s.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: as above.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: as above.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The pulled blank, its stable Δt and the elements updated per step.
struct Case {
    name: &'static str,
    model: Model,
    dt: f64,
    elements: usize,
}

impl Case {
    fn new(name: &'static str, fibres: FibreRepresentation) -> Self {
        let blank = RectangleBlank {
            width: 200.0,
            height: 200.0,
            center: Vector3::zeros(),
            orientation_deg: 0.0,
            element: ElementKind::Quad,
            meshing: Meshing::Cells([100, 100]),
            fibres,
        };
        let material = Material::preset("carbon-prepreg-2x2").expect("preset");
        let mut model = Model::from_blank(&blank, &material).expect("blank model");
        let left = model.node_set("left").expect("left edge").to_vec();
        model.boundary.push(BoundaryCondition::fixed(left));
        let dt = Explicit::new(&model, ExplicitSettings::default())
            .expect("driver")
            .stable_time_step(&model.x0);
        let right = model.node_set("right").expect("right edge").to_vec();
        model.boundary.push(BoundaryCondition {
            nodes: right,
            components: [true; 3],
            motion: Motion::Displacement {
                value: Vector3::new(0.5, 0.0, 0.0),
                amplitude: Amplitude::SmoothStep {
                    duration: f64::from(STEPS) * dt,
                },
            },
        });
        let elements =
            model.trusses.iter().map(|b| b.len()).sum::<usize>() + model.membrane_count();
        Self {
            name,
            model,
            dt,
            elements,
        }
    }

    fn settings(&self, steps: u32) -> ExplicitSettings {
        ExplicitSettings {
            end_time: f64::from(steps) * self.dt,
            time_step: Some(self.dt),
            frames: 0,
            ..ExplicitSettings::default()
        }
    }

    fn run(&self, driver: &mut Explicit<'_>, state: &mut State) -> RunSummary {
        driver.run(state, &mut NoObserver).expect("explicit run")
    }

    /// Times `iters` runs of `driver` in `pool`, each from a fresh copy of
    /// the initial state (the copy not timed).
    fn time_runs(
        &self,
        pool: &rayon::ThreadPool,
        clock: Clock,
        driver: &mut Explicit<'_>,
        iters: u64,
    ) -> Duration {
        pool.install(|| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let mut state = self.model.initial_state();
                let watch = Stopwatch::start(clock);
                black_box(self.run(driver, &mut state));
                total += watch.elapsed();
            }
            total
        })
    }

    /// Heap allocations per step, from runs of 2 and `STEPS` steps (the
    /// difference removes the per-run ones).
    fn allocations_per_step(&self, pool: &rayon::ThreadPool) -> (f64, u64) {
        let count = |steps: u32| {
            let mut driver = Explicit::new(&self.model, self.settings(steps)).expect("driver");
            let mut state = self.model.initial_state();
            pool.install(|| {
                let before = ALLOCATIONS.load(Ordering::Relaxed);
                let summary = self.run(&mut driver, &mut state);
                assert_eq!(summary.steps, u64::from(steps));
                ALLOCATIONS.load(Ordering::Relaxed) - before
            })
        };
        // A first run pays for one-off allocations (rayon's and the
        // allocator's own set-up): not counted.
        count(2);
        let (short, long) = (count(2), count(STEPS));
        ((long as f64 - short as f64) / f64::from(STEPS - 2), short)
    }
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a rayon pool")
}

fn explicit(c: &mut Criterion) {
    let cases = [
        Case::new("trusses", FibreRepresentation::Trusses),
        Case::new("embedded", FibreRepresentation::Embedded),
    ];
    let pools = [(1, pool(1)), (2, pool(2))];
    for case in &cases {
        let nodes = case.model.node_count();
        eprintln!(
            "explicit/{}: {nodes} nodes, {} elements ({} trusses + {} quads), dt = {:.3e} s, \
             element updates = node·steps × {:.4}",
            case.name,
            case.elements,
            case.elements - case.model.membrane_count(),
            case.model.membrane_count(),
            case.dt,
            case.elements as f64 / nodes as f64,
        );
        for (threads, pool) in &pools {
            let (per_step, per_run) = case.allocations_per_step(pool);
            eprintln!(
                "explicit/{}/{threads} thread(s): {per_step:.2} heap allocations per step, \
                 {per_run} in a 2-step run",
                case.name
            );
        }
    }

    let clock = Clock::from_env();
    let mut group = c.benchmark_group("explicit_100x100");
    group.sample_size(10);
    for case in &cases {
        let nodes = case.model.node_count() as u64;
        group.throughput(Throughput::Elements(nodes * u64::from(STEPS)));
        for (threads, pool) in &pools {
            let mut driver = Explicit::new(&case.model, case.settings(STEPS)).expect("driver");
            // Thread CPU time only measures a one-thread pool.
            let clock = if *threads == 1 { clock } else { Clock::Wall };
            group.bench_function(format!("{}/{threads}thread/{STEPS}steps", case.name), |b| {
                b.iter_custom(|iters| case.time_runs(pool, clock, &mut driver, iters))
            });
        }
    }
    group.finish();

    // What a run costs besides its steps: a one-step run is one step plus
    // the start's force pass and the two strain-energy sums.
    let mut group = c.benchmark_group("explicit_100x100_run_overhead");
    group.sample_size(20);
    for case in &cases {
        let (threads, pool) = &pools[0];
        let mut driver = Explicit::new(&case.model, case.settings(1)).expect("driver");
        group.bench_function(format!("{}/{threads}thread/1step", case.name), |b| {
            b.iter_custom(|iters| case.time_runs(pool, clock, &mut driver, iters))
        });
    }
    group.finish();
}

criterion_group!(benches, explicit);
criterion_main!(benches);
