//! The check that a laminate's plies are not inside each other, which the
//! explicit driver makes before the first step and at each of its energy
//! checks (every frame, at least [`crate::guard::MIN_ENERGY_CHECKS`] times a
//! run, and the end), before it publishes the frame: a run whose plies
//! went through each other stops there with the node, its ply, the ply it
//! is in and where, and keeps the frames it had (the guard's last good
//! state), instead of ending "completed" with frames no one should read.
//!
//! The depth is [`drape_contact::PlyContact::record_overlap`]'s, which
//! also keeps each interface's peak for `summary.json`.
//!
//! Not here: the contact that keeps the plies apart (`drape_contact`), the
//! end-of-run check against the tools ([`crate::completion`]).

use drape_contact::PlyContact;
use drape_model::{Model, State};

use crate::RunError;
use crate::completion::{model_size, shortest_edge};

/// The deepest a node of one ply may be inside its neighbour (mm).
///
/// The bound of the tools' end check ([`crate::completion::penetration_tolerance`])
/// on the thinnest ply: a tenth of its thickness (the thickness scatter
/// of a ply, 5–10 %, so a state within it is one the plies could reach,
/// and far above what the ply pass leaves: its rows are solved to 1e-6 of
/// a step's violation, and the hemisphere stacks peak at 1e-4 of the
/// thickness) and a hundredth of the shortest element edge (a node that
/// far off tilts its elements by 0.6°, below what the shear results
/// resolve); never below the round-off of the model's size. The thinnest
/// ply's, because the check is one number for the stack and a thin ply
/// pushed a tenth of a thick one's thickness is through a third of itself.
pub fn ply_overlap_tolerance(model: &Model) -> f64 {
    let thinnest = model
        .plies
        .iter()
        .map(|p| p.thickness)
        .fold(f64::INFINITY, f64::min);
    let physical = (0.1 * thinnest).min(0.01 * shortest_edge(model));
    physical.max(1e-9 * model_size(model))
}

/// Measures the plies at `state` (keeping the peaks) and fails when a
/// node is deeper than `tolerance` inside its neighbour.
pub(crate) fn check_plies(
    model: &Model,
    plies: &mut PlyContact,
    state: &State,
    tolerance: f64,
) -> Result<(), RunError> {
    let Some(o) = plies.record_overlap(&state.x) else {
        return Ok(());
    };
    if o.depth <= tolerance {
        return Ok(());
    }
    let name = |p: usize| {
        model
            .plies
            .get(p)
            .map_or_else(|| format!("#{p}"), |p| p.name.clone())
    };
    Err(RunError::PlyOverlap {
        step: state.step,
        time: state.time,
        overlap: o.depth,
        tolerance,
        ply: name(o.ply),
        into: name(o.into),
        node: o.node as usize,
        at: [o.position.x, o.position.y, o.position.z],
    })
}
