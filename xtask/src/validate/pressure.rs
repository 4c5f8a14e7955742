//! Validation of the follower pressure (`[[pressure]]`): a membrane strip
//! clamped over a gap and inflated by a uniform pressure p.
//!
//! With no load along the strip, its tension T is the same everywhere, and
//! a membrane under a normal pressure is in equilibrium where its curvature
//! is p/T: the strip takes a circular arc of radius R = T/p (the
//! cylinder's hoop formula, T = p·R), whatever its stress–strain law. So
//! the check needs no material law: T from the force the clamps hold, R
//! from the deformed shape. A load fixed in direction (a dead load) would
//! give a different curve with a tension that grows towards the clamps.
//!
//! The discrete strip is a polygon; its nodes' lumped loads p·w·h (element
//! length h) balance the tension turned by the element angle θ = h/R, so
//! T = p·R·cos(θ/2): 1.5e-5 off here, far inside the tolerance.

use drape_constitutive::Material;
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{Amplitude, BoundaryCondition, Model, Motion, PressureLoad};
use drape_time::{ExplicitSettings, Frame};
use nalgebra::Vector3;

use super::contact::{self, Driver};
use super::explicit::Frames;
use super::{Case, Check};

/// The cases of this module.
pub const CASES: &[Case] = &[
    Case {
        name: "pressure/strip-over-gap",
        quick: true,
        run: strip_explicit,
    },
    Case {
        name: "pressure/strip-over-gap-implicit",
        quick: true,
        run: strip_implicit,
    },
];

/// Span (mm), width (mm), pressure (MPa), elements along the span.
const SPAN: f64 = 100.0;
const WIDTH: f64 = 10.0;
const PRESSURE: f64 = 0.1;
const CELLS: usize = 40;

fn strip_explicit() -> Vec<Check> {
    strip(Driver::Explicit)
}

fn strip_implicit() -> Vec<Check> {
    strip(Driver::Implicit)
}

/// The glass strip, 0/90 trusses, clamped at both ends, y held everywhere
/// (plane strain: a slice of a wide membrane), the pressure ramped up
/// along +z over 0.01 s and held, with mass-proportional damping that
/// settles it by 0.02 s.
fn strip_model() -> Model {
    let blank = RectangleBlank {
        width: SPAN,
        height: WIDTH,
        center: Vector3::zeros(),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells([CELLS, 2]),
        fibres: FibreRepresentation::Trusses,
    };
    let material = Material::paper_preset("glass-serge-4x3").expect("preset");
    let mut model = Model::from_blank(&blank, &material).expect("model");
    let all: Vec<u32> = (0..model.node_count() as u32).collect();
    model.boundary.push(BoundaryCondition {
        nodes: all,
        components: [false, true, false],
        motion: Motion::Fixed,
    });
    for side in ["left", "right"] {
        let nodes = model.node_set(side).expect("set").to_vec();
        model.boundary.push(BoundaryCondition::fixed(nodes));
    }
    let load = PressureLoad::on_membranes(
        &model,
        None,
        false,
        PRESSURE,
        Amplitude::SmoothStep { duration: 0.01 },
    );
    model.pressure.push(load);
    model
}

fn strip(driver: Driver) -> Vec<Check> {
    let model = strip_model();
    let left = model.node_set("left").expect("set").to_vec();
    let settings = ExplicitSettings {
        end_time: 0.02,
        frames: 4,
        damping: 5000.0,
        ..ExplicitSettings::default()
    };
    let mut clamp = Vector3::zeros();
    let mut observer = Frames(|f: &Frame<'_>| {
        clamp = left
            .iter()
            .map(|&n| f.reactions[n as usize])
            .sum::<Vector3<f64>>();
    });
    let state = contact::run(driver, &model, settings, &mut observer);
    // The clamp holds the first element's tension T·w and the pressure on
    // its half, p·w·h/2, at right angles to it: T from the x and z parts.
    let h = SPAN / CELLS as f64;
    let lumped = PRESSURE * WIDTH * 0.5 * h;
    let held = (clamp.x * clamp.x + clamp.z * clamp.z - lumped * lumped).sqrt();
    let tension = held / WIDTH;
    // The arc through the clamps and the crown (the edge y = −w/2).
    let mut line: Vec<(f64, Vector3<f64>)> = (0..model.node_count())
        .filter(|&i| (model.x0[i].y + 0.5 * WIDTH).abs() < 1e-9)
        .map(|i| (model.x0[i].x, state.x[i]))
        .collect();
    line.sort_by(|a, b| a.0.total_cmp(&b.0));
    let crown = line[line.len() / 2].1;
    let sag = crown.z;
    let radius = (0.25 * SPAN * SPAN + sag * sag) / (2.0 * sag);
    let centre = Vector3::new(crown.x, crown.y, sag - radius);
    let off_circle = line
        .iter()
        .map(|(_, x)| ((x - centre).norm() - radius).abs() / radius)
        .fold(0.0, f64::max);
    // The polygon's element angle θ from its chords, for the discrete
    // equilibrium T = p·R·cos(θ/2).
    let chord = (line[1].1 - line[0].1).norm();
    let half_angle = (0.5 * chord / radius).asin();
    let name = match driver {
        Driver::Explicit => "explicit",
        Driver::Implicit => "implicit",
        Driver::ImplicitActiveSet => "implicit (active set)",
    };
    vec![
        Check::rel(
            format!(
                "{name}: tension T at the clamp (N/mm) against p·R, R from the sag {sag:.3} mm"
            ),
            PRESSURE * radius,
            tension,
            0.01,
        ),
        Check::rel(
            format!("{name}: T against the discrete polygon's p·R·cos(θ/2)"),
            PRESSURE * radius * half_angle.cos(),
            tension,
            1e-4,
        ),
        Check::abs(
            format!("{name}: largest distance of a node from the arc, over R"),
            0.0,
            off_circle,
            // A regular polygon up to the run's settling and Newton's
            // tolerance (measured 1e-16 and 1e-9); a dead load's curve
            // would be ~3e-4 off.
            1e-6,
        ),
        // The pressure pushed along +z, the blank's normal: the strip
        // bulges up, by more than a tenth of a thickness.
        Check::abs(
            format!("{name}: the strip bulges along the pushed side (sag > 0.1 mm)"),
            1.0,
            f64::from(sag > 0.1),
            0.0,
        ),
    ]
}
