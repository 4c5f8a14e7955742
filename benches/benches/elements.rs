//! Criterion benches of the element batch passes, the bulk of an explicit
//! step: `forces_into` of a truss batch and of triangle and quad membrane
//! batches (resin only, or with both yarn families embedded) over about
//! 10 000 elements of a deformed blank.
//!
//! Each pass runs inside a one-thread rayon pool, so the figures are per
//! core; the throughput is in elements per second (`Throughput::Elements`).
//! The pass starts from the initial history each time and writes the new
//! history into a scratch buffer, so every iteration does the same work.
//!
//! `cargo bench -p drape-benches --bench elements`; a short run with
//! `-- --warm-up-time 1 --measurement-time 3`.
//! With `DRAPE_BENCH_CLOCK=thread-cpu` the passes are timed by the pool
//! thread's CPU time (see the crate docs): per-core figures on a busy
//! machine.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use drape_benches::{Clock, time_iters};
use drape_constitutive::Material;
use drape_elements::{FabricSection, MembraneBatch, Vector3};
use drape_model::Model;
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};

/// A 200 × 200 mm blank at θ = 0 of `cells` cells.
fn blank(element: ElementKind, cells: [usize; 2], fibres: FibreRepresentation) -> RectangleBlank {
    RectangleBlank {
        width: 200.0,
        height: 200.0,
        center: Vector3::zeros(),
        orientation_deg: 0.0,
        element,
        meshing: Meshing::Cells(cells),
        fibres,
    }
}

/// A homogeneous deformation of the reference positions: 1 % along the
/// warp (x), 0.5 % along the weft (y), a shear of 0.02 and a small
/// out-of-plane tilt, so that both families are in tension (no slack
/// shortcut) and no kinematic shortcut applies.
fn deform(x0: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    x0.iter()
        .map(|p| {
            Vector3::new(
                1.01 * p.x + 0.02 * p.y,
                1.005 * p.y,
                p.z + 1e-3 * p.x - 2e-3 * p.y,
            )
        })
        .collect()
}

fn single_thread_pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread rayon pool")
}

fn trusses(c: &mut Criterion) {
    let (pool, clock) = (single_thread_pool(), Clock::from_env());
    let mut group = c.benchmark_group("truss_forces");
    for preset in ["carbon-prepreg-2x2", "glass-serge-4x3"] {
        let material = Material::preset(preset).expect("preset");
        // 100 × 99 cells: the warp family (x edges) has 100 × 100 trusses.
        let model = Model::from_blank(
            &blank(ElementKind::Quad, [100, 99], FibreRepresentation::Trusses),
            &material,
        )
        .expect("blank model");
        let batch = &model.trusses[0];
        // The warp trusses lie along x: stretched by exactly 1 %.
        let x: Vec<_> = model
            .x0
            .iter()
            .map(|p| Vector3::new(1.01 * p.x, p.y, p.z))
            .collect();
        let mut slots = vec![Vector3::zeros(); 2 * batch.len()];
        group.throughput(Throughput::Elements(batch.len() as u64));
        group.bench_function(format!("{preset}/{}", batch.len()), |b| {
            b.iter_custom(|iters| {
                pool.install(|| {
                    time_iters(clock, iters, || {
                        batch
                            .forces_into(black_box(&x), black_box(&mut slots))
                            .expect("truss forces")
                    })
                })
            })
        });
    }
    group.finish();
}

fn membranes(c: &mut Criterion) {
    let (pool, clock) = (single_thread_pool(), Clock::from_env());
    let mut group = c.benchmark_group("membrane_forces");
    // An explicit-sized step for the resin's relaxation.
    let dt = 1e-7;
    for (shape, element, cells) in [
        ("tri", ElementKind::Triangle, [100, 50]),
        ("quad", ElementKind::Quad, [100, 100]),
    ] {
        for preset in ["carbon-prepreg-2x2", "glass-serge-4x3"] {
            let material = Material::preset(preset).expect("preset");
            let model = Model::from_blank(
                &blank(element, cells, FibreRepresentation::Embedded),
                &material,
            )
            .expect("blank model");
            let x = deform(&model.x0);
            for embedded in [false, true] {
                let mut batch: MembraneBatch = model.membranes[0].clone();
                batch.section = FabricSection::new(material.clone(), embedded);
                let h_in = batch.initial_history();
                let mut h_out = h_in.clone();
                let mut slots = vec![Vector3::zeros(); batch.shape().nodes() * batch.len()];
                let fibres = if embedded { "embedded" } else { "resin" };
                group.throughput(Throughput::Elements(batch.len() as u64));
                group.bench_function(format!("{shape}/{preset}/{fibres}/{}", batch.len()), |b| {
                    b.iter_custom(|iters| {
                        pool.install(|| {
                            time_iters(clock, iters, || {
                                batch
                                    .forces_into(
                                        black_box(&x),
                                        black_box(&h_in),
                                        black_box(&mut h_out),
                                        dt,
                                        black_box(&mut slots),
                                    )
                                    .expect("membrane forces")
                            })
                        })
                    })
                });
            }
        }
    }
    group.finish();
}

criterion_group!(benches, trusses, membranes);
criterion_main!(benches);
