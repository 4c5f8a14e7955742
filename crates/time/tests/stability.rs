//! The stable time step against the assembled system's highest frequency:
//! Δt·ω_max ≤ 2 on lumped masses, for the meshes the validation runs.

use drape_constitutive::Material;
use drape_model::Model;
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_time::{Explicit, ExplicitSettings};
use nalgebra::{DMatrix, Vector3};

/// ω_max² of M^(−½)·sym(K)·M^(−½) at the reference state (dense).
fn omega_max(model: &Model) -> f64 {
    let n = 3 * model.node_count();
    let mut k: DMatrix<f64> = DMatrix::zeros(n, n);
    let x = &model.x0;
    let mut add = |nodes: &[u32], ke: &DMatrix<f64>| {
        for (a, &na) in nodes.iter().enumerate() {
            for (b, &nb) in nodes.iter().enumerate() {
                for i in 0..3 {
                    for j in 0..3 {
                        k[(3 * na as usize + i, 3 * nb as usize + j)] += ke[(3 * a + i, 3 * b + j)];
                    }
                }
            }
        }
    };
    for b in &model.trusses {
        let mut ke = DMatrix::zeros(6, 6);
        for e in 0..b.len() {
            b.element_tangent(e, x, &mut ke).unwrap();
            add(&b.nodes[e], &ke);
        }
    }
    let state = model.initial_state();
    for (b, h) in model.membranes.iter().zip(&state.history) {
        let m = 3 * b.shape().nodes();
        let mut ke = DMatrix::zeros(m, m);
        let eh = b.element_history_len();
        for e in 0..b.len() {
            b.element_tangent(e, x, &h[e * eh..(e + 1) * eh], 0.0, &mut ke)
                .unwrap();
            add(b.element_nodes(e), &ke);
        }
    }
    let scale: Vec<f64> = (0..n).map(|d| 1.0 / model.mass[d / 3].sqrt()).collect();
    let sym = DMatrix::<f64>::from_fn(n, n, |i, j| {
        0.5 * (k[(i, j)] + k[(j, i)]) * scale[i] * scale[j]
    });
    sym.symmetric_eigenvalues().max()
}

fn check(blank: RectangleBlank, material: Material) {
    let model = Model::from_blank(&blank, &material).unwrap();
    let driver = Explicit::new(
        &model,
        ExplicitSettings {
            safety_factor: 1.0,
            ..Default::default()
        },
    )
    .unwrap();
    let dt = driver.stable_time_step(&model.x0);
    let exact = 2.0 / omega_max(&model).sqrt();
    eprintln!(
        "{:?} θ={} {:?}: estimate {dt:e}, 2/ω_max {exact:e}",
        blank.element, blank.orientation_deg, blank.fibres
    );
    assert!(dt <= exact, "estimate {dt:e} > 2/ω_max {exact:e}");
    assert!(dt >= 0.5 * exact, "estimate {dt:e} ≪ 2/ω_max {exact:e}");
}

/// Fibres linear in tension and compression, so that the reference
/// tangent has the full E_f.
fn linear_glass() -> Material {
    let mut m = Material::preset("glass-serge-4x3").unwrap();
    m.fibre.crimp_strain = 0.0;
    m.fibre.compression_factor = 1.0;
    m
}

#[test]
fn stable_step_bounds_the_highest_frequency() {
    for (theta, element, fibres, cells) in [
        (0.0, ElementKind::Quad, FibreRepresentation::Trusses, [8, 4]),
        (
            45.0,
            ElementKind::Quad,
            FibreRepresentation::Trusses,
            [8, 4],
        ),
        (
            45.0,
            ElementKind::Triangle,
            FibreRepresentation::Trusses,
            [8, 4],
        ),
        (
            30.0,
            ElementKind::Quad,
            FibreRepresentation::Embedded,
            [8, 4],
        ),
        (
            30.0,
            ElementKind::Triangle,
            FibreRepresentation::Embedded,
            [8, 4],
        ),
    ] {
        let blank = RectangleBlank {
            width: 80.0,
            height: 40.0,
            center: Vector3::zeros(),
            orientation_deg: theta,
            element,
            meshing: Meshing::Cells(cells),
            fibres,
        };
        check(blank, linear_glass());
    }
}
