//! Criterion benches of the explicit contact pass (SPEC §6) against the
//! element pass of the same blank, per step: a 200 × 200 mm glass blank of
//! 50 × 50 quads with fibre trusses (2601 nodes), and
//!
//! - `elements`: truss and membrane `forces_into` and the slot gather, what
//!   the driver's force pass does each step;
//! - `contact/near`: a hemispherical punch 3 mm under the blank, inside the
//!   broad phase's margin: every node is projected, none touches;
//! - `contact/punch`: the blank lying on the punch's cap (R = 150), every
//!   node predicted 1e-4 mm inside and sliding at 10 mm/s with μ = 0.2:
//!   one constraint per node, closed form, and the friction pass;
//! - `contact/pinched`: the flat blank between a die and a force-driven
//!   holder pushing down, μ = 0.2 on both: two constraints per node, all
//!   coupled through the holder, solved by the projected CG.
//!
//! All run in a one-thread rayon pool (figures per core), with the same
//! throughput unit (nodes), so the group reads as the contact pass's cost
//! relative to the element pass. Each contact iteration starts from a copy
//! of the same predicted state and pass (made outside the timing), so
//! every iteration does the same work.
//!
//! `cargo bench -p drape-benches --bench contact`; a short run with
//! `-- --warm-up-time 1 --measurement-time 3`.

use std::hint::black_box;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use drape_constitutive::Material;
use drape_contact::{ContactSettings, ExplicitContact, StepTimes, Surface, Tool, ToolMotion};
use drape_model::Model;
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use nalgebra::Vector3;

/// An explicit-sized step (s).
const DT: f64 = 1e-6;

fn single_thread_pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread rayon pool")
}

fn glass_blank() -> Model {
    let blank = RectangleBlank {
        width: 200.0,
        height: 200.0,
        center: Vector3::zeros(),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells([50, 50]),
        fibres: FibreRepresentation::Trusses,
    };
    let glass = Material::preset("glass-serge-4x3").expect("preset");
    Model::from_blank(&blank, &glass).expect("blank model")
}

/// The blank draped on a sphere of radius `rho` (its mid-surface) whose top
/// is at z = 0: each node keeps its x, y.
fn draped(x0: &[Vector3<f64>], rho: f64) -> Vec<Vector3<f64>> {
    x0.iter()
        .map(|p| Vector3::new(p.x, p.y, (rho * rho - p.x * p.x - p.y * p.y).sqrt() - rho))
        .collect()
}

fn punch(pole_z: f64, radius: f64, friction: f64) -> Tool {
    Tool {
        name: "punch".into(),
        surface: Surface::hemispherical_punch(Vector3::new(0.0, 0.0, pole_z), radius, 50.0)
            .expect("punch"),
        motion: ToolMotion::Fixed,
        friction,
    }
}

/// One step of the contact pass from a copy of `contact`, `x`, `v`.
fn bench_contact(
    b: &mut criterion::Bencher<'_>,
    contact: &ExplicitContact,
    x: &[Vector3<f64>],
    v: &[Vector3<f64>],
    mass: &[f64],
) {
    let movable = vec![true; x.len()];
    let step = StepTimes {
        t_new: DT,
        dt: DT,
        dt_mean: DT,
        damping: 0.0,
    };
    b.iter_batched(
        || (contact.clone(), x.to_vec(), v.to_vec()),
        |(mut c, mut x, mut v)| {
            c.enforce_step(black_box(&mut x), black_box(&mut v), mass, &movable, &step)
        },
        BatchSize::LargeInput,
    );
}

fn passes(c: &mut Criterion) {
    let pool = single_thread_pool();
    let model = glass_blank();
    let n = model.node_count();
    let offset = model.contact_offset;
    let rho = 150.0 + offset;
    let x = draped(&model.x0, rho);
    let mut group = c.benchmark_group(format!("step_pass/{n}_nodes"));
    group.throughput(Throughput::Elements(n as u64));

    // The element pass at the draped positions (stretched ~0.1 % over the cap).
    let layout = model.slot_layout();
    let mut slots = vec![Vector3::zeros(); layout.len];
    let mut forces = vec![Vector3::zeros(); n];
    let histories: Vec<Vec<f64>> = model
        .membranes
        .iter()
        .map(|b| b.initial_history())
        .collect();
    let mut new_histories = histories.clone();
    group.bench_function("elements", |b| {
        pool.install(|| {
            b.iter(|| {
                for (i, t) in model.trusses.iter().enumerate() {
                    let start = layout.truss_offsets[i];
                    t.forces_into(black_box(&x), &mut slots[start..start + 2 * t.len()])
                        .expect("truss forces");
                }
                for (i, m) in model.membranes.iter().enumerate() {
                    let start = layout.membrane_offsets[i];
                    let end = start + m.shape().nodes() * m.len();
                    m.forces_into(
                        black_box(&x),
                        &histories[i],
                        &mut new_histories[i],
                        DT,
                        &mut slots[start..end],
                    )
                    .expect("membrane forces");
                }
                layout.gather(&slots, black_box(&mut forces));
            })
        })
    });

    let settings = ContactSettings {
        offset,
        ..ContactSettings::default()
    };
    // Each pass is built and run once outside the timing, so that its
    // candidate lists exist: the steady state of a run.
    let prepared = |tools: Vec<Tool>, x: &[Vector3<f64>], v: &[Vector3<f64>]| {
        let mut contact = ExplicitContact::new(tools, n, settings);
        let (mut x, mut v) = (x.to_vec(), v.to_vec());
        contact
            .enforce(&mut x, &mut v, &model.mass, &vec![true; n], DT, DT)
            .expect("no contact fault");
        contact
    };

    // Near: the punch 3 mm below the flat blank.
    let flat: Vec<_> = model.x0.iter().map(|p| p + Vector3::z() * offset).collect();
    let still = vec![Vector3::zeros(); n];
    let near = prepared(vec![punch(-3.0, 150.0, 0.2)], &flat, &still);
    group.bench_function("contact/near", |b| {
        pool.install(|| bench_contact(b, &near, &flat, &still, &model.mass))
    });

    // Punch: every node 1e-4 mm inside the cap, sliding along x.
    let inside = draped(&model.x0, rho - 1e-4);
    let sliding: Vec<_> = x
        .iter()
        .zip(&inside)
        .map(|(on, inn)| Vector3::new(10.0, 0.0, 0.0) + (inn - on) / DT)
        .collect();
    let on_punch = prepared(vec![punch(0.0, 150.0, 0.2)], &inside, &sliding);
    group.bench_function("contact/punch", |b| {
        pool.install(|| bench_contact(b, &on_punch, &inside, &sliding, &model.mass))
    });

    // Pinched: die z = 0, holder z = h pushed down by 500 N, sliding along x.
    let h = 2.0 * offset;
    let tools = vec![
        Tool {
            name: "die".into(),
            surface: Surface::plane(Vector3::zeros(), Vector3::z()).expect("plane"),
            motion: ToolMotion::Fixed,
            friction: 0.2,
        },
        Tool {
            name: "holder".into(),
            surface: Surface::plane(Vector3::new(0.0, 0.0, h), -Vector3::z()).expect("plane"),
            motion: ToolMotion::Force {
                direction: -Vector3::z(),
                force: 500.0,
                amplitude: drape_contact::Amplitude::Constant,
                mass: 1e-3,
            },
            friction: 0.2,
        },
    ];
    let moving = vec![Vector3::new(10.0, 0.0, 0.0); n];
    let pinched = prepared(tools, &flat, &moving);
    group.bench_function("contact/pinched", |b| {
        pool.install(|| bench_contact(b, &pinched, &flat, &moving, &model.mass))
    });
    group.finish();
}

criterion_group!(benches, passes);
criterion_main!(benches);
