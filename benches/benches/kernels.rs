//! Criterion benches of drape's per-integration-point kernels, the inner
//! loop of every element pass: the polar decomposition, the fibre law and
//! the resin update. One call per iteration, so criterion's time per
//! iteration is the cost per call.
//!
//! `cargo xtask bench` (or `cargo bench -p drape-benches`); short runs with
//! `cargo xtask bench -- --warm-up-time 1 --measurement-time 2`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use drape_constitutive::Material;
use drape_kinematics::{Matrix2, Matrix3x2, polar_decomposition};

fn kinematics(c: &mut Criterion) {
    // A stretched, sheared and tilted membrane point: no shortcut applies.
    let f = Matrix3x2::new(1.08, 0.21, -0.13, 0.94, 0.31, -0.27);
    c.bench_function("polar_decomposition", |b| {
        b.iter(|| polar_decomposition(black_box(&f)))
    });
}

fn fibre(c: &mut Criterion) {
    let law = Material::preset("carbon-prepreg-2x2")
        .expect("preset")
        .fibre;
    let mut group = c.benchmark_group("fibre_stress_tangent_energy");
    // Mid-crimp (the exponential matters) and a straightened yarn.
    for (name, eps) in [
        ("crimp", 0.5 * law.crimp_strain),
        ("straight", 20.0 * law.crimp_strain),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| {
                let eps = black_box(eps);
                let (tau, tangent) = law.stress_and_tangent(eps);
                (tau, tangent, law.energy(eps))
            })
        });
    }
    group.finish();
}

fn resin(c: &mut Criterion) {
    let mut group = c.benchmark_group("resin_update_stress");
    // A small general increment at an explicit-sized step; the stress keeps
    // accumulating across iterations, which stays finite for any run length.
    let d_eps = Matrix2::new(1e-9, 4e-10, 4e-10, -3e-10);
    let dt = 1e-6;
    for (name, preset) in [
        ("elastic_glass", "glass-serge-4x3"),
        ("prony6_carbon", "carbon-prepreg-2x2"),
    ] {
        let law = Material::preset(preset).expect("preset").resin;
        let mut tau = Matrix2::zeros();
        let mut history = vec![0.0; law.history_len()];
        group.bench_function(name, |b| {
            b.iter(|| {
                law.update_stress(
                    black_box(&mut tau),
                    black_box(&mut history),
                    black_box(&d_eps),
                    black_box(dt),
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, kinematics, fibre, resin);
criterion_main!(benches);
