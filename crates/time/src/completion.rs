//! The end-of-run contact check, the same for both drivers: a run is
//! "completed" only if no node of the blank ends deeper inside a rigid
//! tool than [`penetration_tolerance`]. The drivers enforce contact to
//! their own settings (the implicit one to `gap_tolerance`, which a user
//! can set to anything); this check holds every run to a physical bound
//! taken from the model alone, so no setting can make a blank that went
//! through a tool read as formed.
//!
//! Not here: contact enforcement itself (`drape_contact`), the start-up
//! checks of tools against the blank ([`crate::guard::check_tools_at_start`]).

use drape_contact::Tool;
use drape_model::Model;
use nalgebra::Vector3;
use rayon::prelude::*;

/// The deepest a node may end inside a tool (mm), from the model alone.
///
/// The gap's zero is the ply's surface (the mid-surface half a thickness
/// t from the tool), so a node δ inside has the ply squashed by δ, which
/// rigid contact does not represent. Bound it by
/// - a tenth of the thickness: within the thickness scatter of a ply
///   (prepregs and dry fabrics vary by 5–10 %), so a formed state with it
///   is one the model could have reached, and far above what the solvers
///   leave (the explicit pass solves the contact rows to round-off, the
///   implicit one to `gap_tolerance`, 1e-9 mm by default);
/// - a hundredth of the shortest element edge l: a node that far off the
///   surface tilts its elements by at most δ/l = 0.6°, below what the
///   forming measures (shear angles to a degree) resolve, which matters
///   for a thick ply on a fine mesh;
///
/// and never below the round-off of the model's coordinates (1e-9 of its
/// size), for a model built without a thickness.
///
/// Not the user's `gap_tolerance`: that is a solver setting, and the check
/// exists to catch the run that setting let through.
pub fn penetration_tolerance(model: &Model) -> f64 {
    let thickness = 2.0 * model.contact_offset;
    let edge = shortest_edge(model);
    let physical = (0.1 * thickness).min(0.01 * edge);
    physical.max(1e-9 * model_size(model))
}

/// The shortest edge of the blank's elements in the reference
/// configuration (mm): membranes' element edges and trusses; infinite for
/// a model without either.
pub(crate) fn shortest_edge(model: &Model) -> f64 {
    let x = &model.x0;
    let mut shortest = f64::INFINITY;
    for batch in &model.membranes {
        for e in 0..batch.len() {
            let nodes = batch.element_nodes(e);
            for (k, &a) in nodes.iter().enumerate() {
                let b = nodes[(k + 1) % nodes.len()];
                shortest = shortest.min((x[a as usize] - x[b as usize]).norm());
            }
        }
    }
    for batch in &model.trusses {
        for [a, b] in &batch.nodes {
            shortest = shortest.min((x[*a as usize] - x[*b as usize]).norm());
        }
    }
    shortest
}

/// The bounding-box diagonal of the reference positions (mm).
pub(crate) fn model_size(model: &Model) -> f64 {
    let lo = model
        .x0
        .iter()
        .fold(Vector3::repeat(f64::INFINITY), |m, x| m.inf(x));
    let hi = model
        .x0
        .iter()
        .fold(Vector3::repeat(f64::NEG_INFINITY), |m, x| m.sup(x));
    let d = (hi - lo).norm();
    if d.is_finite() { d } else { 0.0 }
}

/// A node found deeper inside a tool than the tolerance.
#[derive(Debug, Clone, PartialEq)]
pub struct Penetration {
    /// The node.
    pub node: usize,
    /// The tool's name.
    pub tool: String,
    /// How far the ply's surface at the node is inside the tool (mm).
    pub depth: f64,
    /// The tolerance it exceeds (mm, [`penetration_tolerance`]).
    pub tolerance: f64,
    /// Nodes beyond the tolerance, in all tools.
    pub count: usize,
}

/// The deepest node of `x` inside a tool beyond `tolerance`, with the tools
/// at `displacements` along their axes (one per tool), or `None`.
///
/// The depth is `offset(i) − gap` for node i, `offset` its half thickness
/// (the ply's surface behind the tool's). On
/// an open tool (a profile or a mesh) the gap's sign flips behind the rim
/// without the node going through anything, so a depth counts only where
/// the node is nearer the surface than the rim
/// ([`Tool::rim_clearance`]; infinite on a closed tool), where the sign is
/// the surface's. Ties go to the lowest node, so the answer does not
/// depend on the thread count.
pub fn deepest_penetration(
    tools: &[Tool],
    displacements: &[f64],
    offset: impl Fn(usize) -> f64 + Sync,
    x: &[Vector3<f64>],
    tolerance: f64,
) -> Option<Penetration> {
    let mut deepest: Option<Penetration> = None;
    let mut count = 0;
    for (tool, &u) in tools.iter().zip(displacements) {
        let (depth, node, n) = x
            .par_iter()
            .enumerate()
            .with_min_len(512)
            .map(|(i, p)| {
                let gap = tool.project(p, u).gap;
                let depth = offset(i) - gap;
                // A NaN position is the non-finite checks' business.
                let counted = depth > tolerance && gap.abs() < tool.rim_clearance(p, u);
                if counted {
                    (depth, i, 1usize)
                } else {
                    (f64::NEG_INFINITY, usize::MAX, 0)
                }
            })
            .reduce(
                || (f64::NEG_INFINITY, usize::MAX, 0),
                |a, b| {
                    let pick = if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) {
                        b
                    } else {
                        a
                    };
                    (pick.0, pick.1, a.2 + b.2)
                },
            );
        count += n;
        if n > 0 && deepest.as_ref().is_none_or(|d| depth > d.depth) {
            deepest = Some(Penetration {
                node,
                tool: tool.name.clone(),
                depth,
                tolerance,
                count: 0,
            });
        }
    }
    deepest.map(|d| Penetration { count, ..d })
}

/// The check at the end of a run that reached its end time, `state` at
/// the end and the tools at `displacements`: a [`RunError::Penetration`](crate::RunError::Penetration)
/// naming the deepest node, its tool and the setting to change. For an
/// implicit run, `gap_tolerance` is its setting (the advice depends on it).
pub fn check_at_end(
    model: &Model,
    state: &drape_model::State,
    displacements: &[f64],
    gap_tolerance: Option<f64>,
) -> Result<(), crate::RunError> {
    if model.tools.is_empty() {
        return Ok(());
    }
    let tolerance = penetration_tolerance(model);
    // A laminate's plies each sit at their own half thickness.
    let half = model.ply_half_thickness_per_node();
    match deepest_penetration(
        &model.tools,
        displacements,
        |i| half[i],
        &state.x,
        tolerance,
    ) {
        None => Ok(()),
        Some(found) => Err(crate::RunError::Penetration {
            step: state.step,
            time: state.time,
            advice: advice(&found, gap_tolerance),
            node: found.node,
            tool: found.tool,
            depth: found.depth,
            tolerance: found.tolerance,
            count: found.count,
        }),
    }
}

/// What a user changes when a run ends with `found` (`implicit_gap_tolerance`
/// the implicit run's setting, None for an explicit run): the settings
/// that let nodes through a tool.
fn advice(found: &Penetration, implicit_gap_tolerance: Option<f64>) -> String {
    match implicit_gap_tolerance {
        Some(g) if g > found.tolerance => format!(
            "lower `simulation.gap_tolerance` (now {g:e} mm) below {:.3e} mm",
            found.tolerance
        ),
        Some(_) => "lower `simulation.max_increment` or raise `simulation.contact_margin` \
                    (a node that crosses the margin within one increment is not in the contact \
                    solve)"
            .to_owned(),
        None => "lower `simulation.safety_factor` or `simulation.time_step` (a node that \
                 crosses a tool's surface within one step is past what the contact pass \
                 resolves)"
            .to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drape_contact::{Surface, ToolMotion};

    fn plane_tool() -> Tool {
        Tool {
            name: "table".into(),
            surface: Surface::plane(Vector3::zeros(), Vector3::z()).unwrap(),
            motion: ToolMotion::Fixed,
            friction: 0.0,
        }
    }

    #[test]
    fn finds_the_deepest_node_beyond_the_tolerance_and_counts_them() {
        let tools = [plane_tool()];
        let offset = 0.1;
        // Heights of the mid-surface: depth = offset − z.
        let x: Vec<Vector3<f64>> = [0.2, 0.05, -0.3, -0.3, 0.09]
            .iter()
            .map(|&z| Vector3::new(0.0, 0.0, z))
            .collect();
        let found = deepest_penetration(&tools, &[0.0], |_| offset, &x, 0.02).unwrap();
        // Nodes 1 (depth 0.05), 2 and 3 (0.4) are beyond; node 4 (0.01) is not.
        assert_eq!(found.count, 3);
        // Ties go to the lowest node.
        assert_eq!(found.node, 2);
        assert!((found.depth - 0.4).abs() < 1e-15);
        assert_eq!(found.tool, "table");
        assert!(deepest_penetration(&tools, &[0.0], |_| offset, &x, 0.5).is_none());
    }

    #[test]
    fn a_moved_tool_is_checked_where_it_is() {
        let mut tool = plane_tool();
        tool.motion = ToolMotion::Displacement {
            direction: Vector3::z(),
            distance: 1.0,
            amplitude: drape_contact::Amplitude::Constant,
        };
        let x = vec![Vector3::new(0.0, 0.0, 0.5)];
        // At u = 0 the node is 0.4 mm clear; the table moved up 1 mm has
        // it 0.6 mm inside.
        assert!(
            deepest_penetration(std::slice::from_ref(&tool), &[0.0], |_| 0.1, &x, 1e-3).is_none()
        );
        let found = deepest_penetration(&[tool], &[1.0], |_| 0.1, &x, 1e-3).unwrap();
        assert!((found.depth - 0.6).abs() < 1e-12);
    }
}
