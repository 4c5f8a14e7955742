//! A forced `time_step` and mass scaling together: the added mass is the
//! material's (the elements' stable steps against the target), whatever
//! step the run is forced to take (issue 29, fault 7: a step forced below
//! the target made the driver scale the mass to the forced step, 14.5×
//! became 246× the blank's mass).

use drape_constitutive::Material;
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{Amplitude, BoundaryCondition, Model, Motion};
use drape_time::{Explicit, ExplicitSettings};
use nalgebra::Vector3;

/// A 6 × 4 blank of 10 mm cells with trusses and membranes, clamped on
/// the left and pulled on the right.
fn pulled() -> Model {
    let blank = RectangleBlank {
        width: 60.0,
        height: 40.0,
        center: Vector3::zeros(),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells([6, 4]),
        fibres: FibreRepresentation::Trusses,
    };
    let mut model =
        Model::from_blank(&blank, &Material::preset("glass-serge-4x3").unwrap()).unwrap();
    model.boundary.push(BoundaryCondition::fixed(
        model.node_set("left").unwrap().to_vec(),
    ));
    model.boundary.push(BoundaryCondition {
        nodes: model.node_set("right").unwrap().to_vec(),
        components: [true, true, true],
        motion: Motion::Displacement {
            value: Vector3::new(0.5, 0.0, 2.0),
            amplitude: Amplitude::SmoothStep { duration: 1e-3 },
        },
    });
    model
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|m| m.to_bits()).collect()
}

#[test]
fn a_forced_step_below_the_target_adds_the_same_mass_bit_for_bit() {
    let model = pulled();
    let physical = Explicit::new(&model, ExplicitSettings::default())
        .unwrap()
        .stable_time_step(&model.x0);
    let target = 8.0 * physical;
    let settings = ExplicitSettings {
        mass_scaling: Some(target),
        end_time: 1e-3,
        ..ExplicitSettings::default()
    };
    let free = Explicit::new(&model, settings.clone()).unwrap();
    let added = free.added_mass();
    let mass: f64 = model.mass.iter().sum();
    // The elements all ask for about 64× (uniform cells, edge nodes aside).
    assert!(added > 10.0 * mass, "added {} of the mass", added / mass);
    // Steps forced below the target (the scaled stable step), down to a
    // hundredth of it, and one just under it.
    for forced in [0.01 * target, 0.25 * target, 0.5 * target, 0.999 * target] {
        let driver = Explicit::new(
            &model,
            ExplicitSettings {
                time_step: Some(forced),
                ..settings.clone()
            },
        )
        .unwrap();
        assert_eq!(
            bits(driver.mass()),
            bits(free.mass()),
            "the masses with time_step {forced:e} (target {target:e})"
        );
        assert_eq!(driver.added_mass().to_bits(), added.to_bits());
        // The step is the forced one (the driver integrates with `mass()`).
        assert_eq!(driver.stable_time_step(&model.x0), forced);
    }
}
