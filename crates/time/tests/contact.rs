//! Contact through the explicit driver: a blank on an incline.

use drape_constitutive::Material;
use drape_contact::{Surface, Tool, ToolMotion};
use drape_model::Model;
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_time::{Explicit, ExplicitSettings, NoObserver};
use nalgebra::Vector3;

const G: f64 = 9810.0;

/// A 20 mm glass square resting on a floor with gravity tilted by α
/// (the same as a floor tilted by α), μ on the floor; returns the mean
/// x displacement after `time` and the largest penetration.
fn incline(alpha_deg: f64, mu: f64, time: f64) -> (f64, f64) {
    let glass = Material::preset("glass-serge-4x3").unwrap();
    let blank = RectangleBlank {
        width: 20.0,
        height: 20.0,
        center: Vector3::new(0.0, 0.0, 0.5 * glass.thickness),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells([2, 2]),
        fibres: FibreRepresentation::Trusses,
    };
    let mut model = Model::from_blank(&blank, &glass).unwrap();
    let a = alpha_deg.to_radians();
    model.gravity = Vector3::new(a.sin(), 0.0, -a.cos()) * G;
    model.tools.push(Tool {
        name: "floor".into(),
        surface: Surface::plane(Vector3::zeros(), Vector3::z()).unwrap(),
        motion: ToolMotion::Fixed,
        friction: mu,
    });
    let mut state = model.initial_state();
    let settings = ExplicitSettings {
        end_time: time,
        frames: 1,
        ..ExplicitSettings::default()
    };
    Explicit::new(&model, settings)
        .unwrap()
        .run(&mut state, &mut NoObserver)
        .unwrap();
    let n = model.node_count() as f64;
    let mean_dx = state
        .x
        .iter()
        .zip(&model.x0)
        .map(|(x, x0)| x.x - x0.x)
        .sum::<f64>()
        / n;
    let penetration = state
        .x
        .iter()
        .map(|x| (0.5 * glass.thickness - x.z).max(0.0))
        .fold(0.0, f64::max);
    (mean_dx, penetration)
}

#[test]
fn a_blank_sticks_below_the_friction_angle_and_slides_above_it() {
    let time = 0.05;
    // tan 20° = 0.364 < 0.4: sticks.
    let (dx, pen) = incline(20.0, 0.4, time);
    assert!(dx.abs() < 1e-9, "moved {dx}");
    assert!(pen < 1e-9);
    // tan 30° = 0.577 > 0.2: slides with a = g(sin α − μ cos α).
    let (dx, pen) = incline(30.0, 0.2, time);
    let a = G * (30f64.to_radians().sin() - 0.2 * 30f64.to_radians().cos());
    let expected = 0.5 * a * time * time;
    assert!(
        (dx - expected).abs() < 1e-3 * expected,
        "{dx} vs {expected}"
    );
    assert!(pen < 1e-9);
    // Frictionless: a = g sin α.
    let (dx, _) = incline(10.0, 0.0, time);
    let expected = 0.5 * G * 10f64.to_radians().sin() * time * time;
    assert!(
        (dx - expected).abs() < 1e-3 * expected,
        "{dx} vs {expected}"
    );
}
