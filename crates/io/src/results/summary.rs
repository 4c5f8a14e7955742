//! Parts of `summary.json` beyond the end state: the peaks over a run and
//! the set-up a run started with.

use drape_model::{ElementFields, Model, State};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// The largest values over a run's frames, with when and where they
/// occurred: a formed part can pass through a state more sheared or more
/// loaded than its end state (the paper's hemisphere reaches its largest
/// shear before the end of the stroke).
///
/// Sampled at the output frames (the initial one included), so a peak
/// between two frames is seen at the nearer frames only; more frames
/// resolve it better.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Peaks {
    /// Largest |shear angle| over the frames (degrees).
    pub max_shear_deg: f64,
    /// Time of the frame where it occurred (s).
    pub max_shear_time_s: f64,
    /// Current centroid of the element there, at that frame (mm).
    pub max_shear_at: [f64; 3],
    /// Largest yarn tension per unit width over the frames (N/mm), by
    /// [`max_yarn_tension`].
    pub max_fibre_tension_n_per_mm: f64,
    /// Time of the frame where it occurred (s).
    pub max_fibre_tension_time_s: f64,
    /// Current centroid of the element there, at that frame (mm).
    pub max_fibre_tension_at: [f64; 3],
}

impl Default for Peaks {
    /// No frame seen: zero peaks at t = 0.
    fn default() -> Self {
        Self {
            max_shear_deg: 0.0,
            max_shear_time_s: 0.0,
            max_shear_at: [0.0; 3],
            max_fibre_tension_n_per_mm: 0.0,
            max_fibre_tension_time_s: 0.0,
            max_fibre_tension_at: [0.0; 3],
        }
    }
}

/// The largest yarn tension per unit width (N/mm) of `model` at
/// positions `x` and where it is: over the trusses (N·t_f/A₀, the
/// `tension_per_width` of `trusses.pvd`, at the truss's midpoint) when
/// the model has trusses, over the elements' `fibre_tension` (at their
/// centroids) otherwise. None without a finite value.
///
/// With trusses the trusses carry the yarns: an element's
/// `fibre_tension` is the law's value at its mean stretch, which under the
/// crimped law's stiffening is below the tension of its most stretched
/// edge.
pub fn max_yarn_tension(
    model: &Model,
    x: &[Vector3<f64>],
    fields: &ElementFields,
) -> Option<(f64, [f64; 3])> {
    let mut best: Option<(f64, [f64; 3])> = None;
    let mut offer = |t: f64, at: Vector3<f64>| {
        if t.is_finite() && best.is_none_or(|(b, _)| t > b) {
            best = Some((t, at.into()));
        }
    };
    if model.features().trusses {
        let family_thickness = model
            .membranes
            .first()
            .map_or(f64::NAN, |b| b.section.material.family_thickness());
        for batch in &model.trusses {
            for (e, &[i, j]) in batch.nodes.iter().enumerate() {
                if let Ok(out) = batch.element_output(e, x) {
                    let middle = 0.5 * (x[i as usize] + x[j as usize]);
                    offer(out.tension * family_thickness / batch.section[e], middle);
                }
            }
        }
    } else {
        for (t, c) in fields.fibre_tension.iter().zip(&fields.centroid) {
            offer(t[0].max(t[1]), *c);
        }
    }
    best
}

impl Peaks {
    /// Takes the frame of `model` at `state` with element `fields` into
    /// account: a value larger than the peak so far replaces it (an equal
    /// one does not, so a plateau is dated by its start). Non-finite
    /// values are skipped. The yarn tension is [`max_yarn_tension`]'s.
    pub fn observe(&mut self, model: &Model, state: &State, fields: &ElementFields) {
        let time = state.time;
        let largest = fields
            .shear
            .iter()
            .map(|g| g.abs().to_degrees())
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .fold(None, |best: Option<(usize, f64)>, (i, v)| match best {
                Some((_, b)) if b >= v => best,
                _ => Some((i, v)),
            });
        if let Some((i, g)) = largest
            && g > self.max_shear_deg
        {
            self.max_shear_deg = g;
            self.max_shear_time_s = time;
            self.max_shear_at = fields
                .centroid
                .get(i)
                .map_or([f64::NAN; 3], |c| (*c).into());
        }
        if let Some((t, at)) = max_yarn_tension(model, &state.x, fields)
            && t > self.max_fibre_tension_n_per_mm
        {
            self.max_fibre_tension_n_per_mm = t;
            self.max_fibre_tension_time_s = time;
            self.max_fibre_tension_at = at;
        }
    }
}

/// What a run started with: the model's size, the fibres and the time
/// step. Printed before the run and kept in the summary.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RunSetup {
    /// Nodes.
    pub nodes: usize,
    /// Membrane elements (triangles and quads).
    pub membrane_elements: usize,
    /// Fibre trusses (0 with embedded fibres).
    pub trusses: usize,
    /// `trusses` or `embedded`.
    pub fibres: String,
    /// The stable time step with the physical mass, at the reference
    /// shape, times the safety factor (s).
    pub stable_time_step_s: f64,
    /// The step the run starts with (s): the stable one, the mass-scaled
    /// one, or the scene's fixed `time_step`.
    pub time_step_s: f64,
    /// The target step of mass scaling (s), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass_scaling_dt_s: Option<f64>,
    /// Mass added by mass scaling (t).
    pub added_mass_t: f64,
    /// The added mass over the physical mass.
    pub added_mass_fraction: f64,
    /// The end time over the starting step: the steps to expect (the step
    /// is re-estimated as the part deforms).
    pub expected_steps: u64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use drape_constitutive::Material;
    use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};

    fn model(fibres: FibreRepresentation) -> Model {
        let blank = RectangleBlank {
            width: 20.0,
            height: 10.0,
            center: Vector3::zeros(),
            orientation_deg: 0.0,
            element: ElementKind::Quad,
            meshing: Meshing::Cells([2, 1]),
            fibres,
        };
        Model::from_blank(&blank, &Material::preset("glass-serge-4x3").unwrap()).unwrap()
    }

    /// A state of `model` at `time` stretched by `stretch` along x.
    fn stretched(model: &Model, stretch: f64, time: f64) -> State {
        let mut state = model.initial_state();
        state.time = time;
        for p in &mut state.x {
            p.x *= stretch;
        }
        state
    }

    #[test]
    fn peaks_keep_the_largest_value_with_its_time_and_place() {
        let m = model(FibreRepresentation::Embedded);
        let mut p = Peaks::default();
        for (stretch, time) in [(1.01, 0.1), (1.03, 0.8), (1.02, 1.0)] {
            let state = stretched(&m, stretch, time);
            let mut fields = m.element_fields(&state).unwrap();
            // Shear put in by hand: 31.3° on element 1 at 0.8 s.
            fields.shear = vec![
                0.0,
                if time == 0.8 { -31.3f64 } else { 30.9f64 }.to_radians(),
            ];
            p.observe(&m, &state, &fields);
        }
        assert!((p.max_shear_deg - 31.3).abs() < 1e-12);
        assert_eq!(p.max_shear_time_s, 0.8);
        // The stretch peaks at 0.8 s too; both elements carry the same
        // tension, so the first one is named.
        assert_eq!(p.max_fibre_tension_time_s, 0.8);
        let glass = Material::preset("glass-serge-4x3").unwrap();
        let expected = glass.family_thickness() * glass.fibre.stress(1.03f64.ln()) / 1.03;
        assert!((p.max_fibre_tension_n_per_mm - expected).abs() < 1e-9 * expected);
        assert!((p.max_fibre_tension_at[0] - (-5.0 * 1.03)).abs() < 1e-9);
    }

    #[test]
    fn the_yarn_tension_of_trusses_is_their_force_over_their_strip_width() {
        // Uniform stretch: every warp truss carries t_f·τ/λ per unit width,
        // the edge trusses half the force on half the width.
        let m = model(FibreRepresentation::Trusses);
        let state = stretched(&m, 1.02, 0.0);
        let fields = m.element_fields(&state).unwrap();
        let (t, _) = max_yarn_tension(&m, &state.x, &fields).unwrap();
        let glass = Material::preset("glass-serge-4x3").unwrap();
        let expected = glass.family_thickness() * glass.fibre.stress(1.02f64.ln()) / 1.02;
        assert!((t - expected).abs() < 1e-12 * expected, "{t} vs {expected}");
        // And the elements' own measure agrees under a uniform stretch.
        assert!((fields.fibre_tension[0][0] - expected).abs() < 1e-12 * expected);
    }
}
