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

use drape_contact::{PlyContact, PlyOverlap};
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
    let thinnest = thinnest(model);
    let physical = (0.1 * thinnest).min(0.01 * shortest_edge(model));
    physical.max(1e-9 * model_size(model))
}

/// The thinnest ply's thickness (mm).
fn thinnest(model: &Model) -> f64 {
    model
        .plies
        .iter()
        .map(|p| p.thickness)
        .fold(f64::INFINITY, f64::min)
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
            .into_boxed_str()
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
        advice: advice(model, &o)
            .unwrap_or_else(|| {
                "it puts a node that came round a ply's free edge or a fold into the ply back on \
             its side, but not one whose motion is prescribed, nor one that crossed the whole \
             ply within one step, nor one that came round the free edge farther behind the ply \
             than the contact's reach: hold the stack more (springs, a holder) so its flanges \
             do not fold over, or lower `simulation.safety_factor`"
                    .into()
            })
            .into_boxed_str(),
    })
}

/// What the overlap `o` comes from, where the faces of the ply it is in
/// are too coarse for their bend ([`drape_contact::FaceBend`]): their
/// middles sag more than half the plies' distance apart (mid-surface to
/// mid-surface), so the neighbour's nodes, held off the flat faces, still
/// reach through them. None where they do not.
///
/// Measured (2026-11-29, two glass plies of 0.57 mm deep drawn over the
/// die's 10 mm fillet): at 24 × 24 cells, faces of 12.5 mm (sag ≈ 2 mm),
/// the plies went into each other there by 3.1 % of the thickness under
/// the force-driven holder (`plies/pressed-stack`); at 48 × 48, faces of
/// 6.25 mm (sag ≈ 0.5 mm), under a fixed holder, by at most 4.8e-4 mm
/// (0.08 %) over 0.4 s. On the hemisphere's 120 mm punch, faces of
/// 14.6 mm sag 0.22 mm, 0.73 of the 0.3 mm the plies lie apart, and the
/// plies go into each other by at most 0.6 % of the thickness: the rows of
/// the other ply's nodes push the faces out.
fn advice(model: &Model, o: &PlyOverlap) -> Option<String> {
    let bend = o.bend?;
    let thickness = |p: usize| model.plies.get(p).map(|p| p.thickness);
    let apart = 0.5 * (thickness(o.ply)? + thickness(o.into)?);
    if bend.sag.is_nan() || bend.sag <= 0.5 * apart {
        return None;
    }
    let into = &model.plies[o.into].name;
    Some(format!(
        "ply `{into}`'s faces there are too coarse for its bend: its nodes' normals turn \
         {:.0}° over an edge of {:.1} mm (a bend of radius {:.1} mm), so a face's middle lies \
         {:.2} mm inside the curved ply its nodes describe, more than half the {apart:.3} mm \
         between the plies' mid-surfaces, and the contact, which holds each node off the \
         neighbour's flat faces, lets the plies through each other between the nodes: refine \
         the blank where it wraps that bend (faces of at most {:.1} mm sag half that \
         distance), or round the tool more",
        bend.turn_deg,
        bend.edge,
        bend.radius,
        bend.sag,
        bend.edge_for_sag(0.5 * apart),
    ))
}

/// The warning a run ends with where its plies were inside each other by
/// more than 1 % of the thinnest ply's thickness at a check (the bound of
/// a formed laminate that the validation holds the stacks to), but within
/// the tolerance that stops it: where, how deep, and from what, if the
/// faces' bend tells ([`advice`]).
pub(crate) fn overlap_warning(model: &Model, plies: &PlyContact) -> Option<String> {
    let o = plies.worst_overlap()?;
    let thinnest = thinnest(model);
    if o.depth.is_nan() || o.depth <= 0.01 * thinnest {
        return None;
    }
    let name = |p: usize| model.plies.get(p).map_or("?", |p| p.name.as_str());
    let mut text = format!(
        "the plies were inside each other by up to {:.3e} mm ({:.1} % of the thinnest ply's \
         {thinnest} mm): node {} of ply `{}` at ({:.1}, {:.1}, {:.1}) mm in ply `{}`",
        o.depth,
        100.0 * o.depth / thinnest,
        o.node,
        name(o.ply),
        o.position.x,
        o.position.y,
        o.position.z,
        name(o.into),
    );
    if let Some(a) = advice(model, o) {
        text.push_str("; ");
        text.push_str(&a);
    }
    Some(text)
}
