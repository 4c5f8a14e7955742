//! A tool mesh that is an open surface, as moulds come from CAD: the side
//! the fabric is on, detected from where the blank starts (`flip_normals`
//! overrides it), and the tangential extension of its open rims
//! (`rim_extension`). Closed meshes keep the convention of
//! [`drape_contact::MeshSurface`] (normals out of the solid).
//!
//! Not for reading or repairing the file (see `placement`).

use drape_constitutive::Material;
use drape_contact::{MeshSurface, Surface};
use drape_model::Model;

use super::SceneError;
use super::locate::Locator;

/// The default rim extension, in the blank's elements (the square root of
/// its mean element area), beyond the blank's overhang: a node that reaches
/// a rim has its neighbours within an element behind it, so three elements
/// keep the gap continuous for the node and the rows that follow it. A
/// blank cut larger than the mould's trimmed surface (as plies are: the
/// mould's flange goes on beyond the part's trim line) overhangs the rim
/// from the start; the extension then reaches that far and three elements
/// more, standing in for the flange, so the overhang neither hangs round
/// the rim to the surface's back nor meets the rim as the blank draws in.
pub const RIM_EXTENSION_ELEMENTS: f64 = 3.0;

/// Halvings of the default extension tried before giving up on it, when it
/// would pass through the blank.
const SHORTER_TRIES: usize = 4;

/// The keys of a mesh geometry about open surfaces.
pub(super) struct OpenMesh {
    /// `flip_normals`.
    pub flip_normals: Option<bool>,
    /// `rim_extension` (mm).
    pub rim_extension: Option<f64>,
}

/// The blank's element size: the square root of its mean element area (mm).
fn element_size(model: &Model) -> Option<f64> {
    let (mut area, mut count) = (0.0, 0usize);
    for b in &model.membranes {
        for e in 0..b.len() {
            area += b.element_area(e);
        }
        count += b.len();
    }
    (count > 0 && area > 0.0).then(|| (area / count as f64).sqrt())
}

fn at_node(model: &Model, i: Option<usize>) -> String {
    match i.and_then(|i| model.x0.get(i).map(|x| (i, x))) {
        Some((i, x)) => format!("node {i} at ({:.2}, {:.2}, {:.2})", x.x, x.y, x.z),
        None => "no node".into(),
    }
}

/// The surface of tool `name` (geometry at `g`) with the fabric on the
/// blank's side and its rims extended, as `open` asks; `model` holds the
/// blank at its start.
pub(super) fn place(
    at: &Locator<'_>,
    g: &str,
    name: &str,
    surface: Surface,
    open: &OpenMesh,
    model: &Model,
    material: &Material,
) -> Result<Surface, SceneError> {
    let Surface::Mesh(mesh) = surface else {
        return Ok(surface);
    };
    if mesh.is_closed() {
        if let Some(l) = open.rim_extension.filter(|&l| l != 0.0) {
            at.warn(
                &format!("{g}.rim_extension"),
                format!("`{name}` is a closed mesh: it has no open rim, so rim_extension = {l} does nothing"),
            );
        }
        // A closed mesh's side is its inside: flipped only on request.
        return Ok(Surface::Mesh(if open.flip_normals == Some(true) {
            mesh.flipped()
        } else {
            mesh
        }));
    }
    // Nodes closer than half the thickness say nothing: a blank laid on
    // the surface (a flange at the blank's height) is on neither side.
    let tolerance = 0.5 * material.thickness;
    let flip = match open.flip_normals {
        Some(f) => f,
        None => {
            let sides = mesh.sides(&model.x0, tolerance);
            match (sides.front, sides.back) {
                (0, 0) => {
                    return Err(at.error(
                        g,
                        format!(
                            "`{name}` is an open mesh ({:.4} mm across) and no node of the blank lies over it \
                             (every node's closest point is on its rim, or within half the fabric's thickness of \
                             it), so the side the fabric comes from cannot be found: check the mesh's `units` and \
                             where it lies, or give `flip_normals = false` (the fabric on the side the file's \
                             normals point to) or `true` (the other side)",
                            { let b = mesh.aabb(); (b.max - b.min).norm() }
                        ),
                    ));
                }
                (_, 0) => false,
                (0, back) => {
                    at.warn(
                        &format!("{g}.flip_normals"),
                        format!(
                            "`{name}` is an open mesh whose normals point away from the blank ({back} node{} \
                             of the blank behind them, none in front): reversed, so the fabric's side is the \
                             blank's (give `flip_normals = false` to keep them as in the file)",
                            if back == 1 { "" } else { "s" }
                        ),
                    );
                    true
                }
                (front, back) => {
                    return Err(at.error(
                        g,
                        format!(
                            "the blank starts on both sides of the open mesh `{name}`: {front} node{} in front of \
                             its normals (first: {}), {back} behind (first: {}); place the blank on one side of \
                             the tool, or give `flip_normals = true|false` to say which side the fabric is on",
                            if front == 1 { "" } else { "s" },
                            at_node(model, sides.first_front),
                            at_node(model, sides.first_back),
                        ),
                    ));
                }
            }
        }
    };
    let mesh = if flip { mesh.flipped() } else { mesh };
    let key = format!("{g}.rim_extension");
    let extend = |mesh: &MeshSurface, length: f64| {
        mesh.with_rim_extension(length).map_err(|e| {
            at.error(
                &key,
                format!("`{name}`: {e} (give `rim_extension = 0` to keep the rim as it is)"),
            )
        })
    };
    // Whether an extension puts the blank on both of its sides where the
    // surface alone had it on one (a wall's rim extended through the
    // blank), or lays itself under the blank within the contact band where
    // the surface alone had no node that close (a mould in the blank's own
    // plane beside it): every such node would be pushed out by the band in
    // the first step, and the run blows up. What it is, with the node.
    let pierced = |extended: &MeshSurface| -> Option<String> {
        let before = mesh.sides(&model.x0, tolerance);
        let after = extended.sides(&model.x0, tolerance);
        let straddles = |s: &drape_contact::Sides| s.front > 0 && s.back > 0;
        if straddles(&after) && !straddles(&before) {
            let node = if before.back > 0 {
                after.first_front
            } else {
                after.first_back
            };
            return Some(format!(
                "passes through the blank ({} is on its other side)",
                at_node(model, node)
            ));
        }
        let (touching, first) = extended.touching(&model.x0, tolerance);
        (touching > 0 && mesh.touching(&model.x0, tolerance).0 == 0).then(|| {
            format!(
                "lies under the blank within half its thickness ({touching} node{} on it, first {}), \
                 where the mesh itself has none: the first step would throw them off it",
                if touching == 1 { "" } else { "s" },
                at_node(model, first)
            )
        })
    };
    let extended = match open.rim_extension {
        Some(0.0) => mesh,
        Some(l) => {
            if !(l.is_finite() && l > 0.0) {
                return Err(at.error(
                    &key,
                    format!(
                        "{l} is not allowed: expected a length ≥ 0 (mm; 0 turns the extension off)"
                    ),
                ));
            }
            let extended = extend(&mesh, l)?;
            if let Some(why) = pierced(&extended) {
                return Err(at.error(
                    &key,
                    format!(
                        "`{name}`: the rim extended by {l} mm {why}: give a shorter rim_extension, or 0"
                    ),
                ));
            }
            extended
        }
        None => {
            let Some(cell) = element_size(model) else {
                return Ok(Surface::Mesh(mesh));
            };
            let full = RIM_EXTENSION_ELEMENTS * cell + mesh.overhang(&model.x0);
            let mut length = full;
            let mut found = None;
            for k in 0..=SHORTER_TRIES {
                if k > 0 {
                    length *= 0.5;
                }
                let extended = extend(&mesh, length)?;
                if pierced(&extended).is_none() {
                    found = Some(extended);
                    break;
                }
            }
            match found {
                Some(e) => {
                    if length < full {
                        at.warn(
                            &key,
                            format!(
                                "`{name}`: its open rim is extended by {length:.3} mm only: the default {full:.3} mm \
                                 (the blank's overhang and three of its elements) passes through the blank, or lies \
                                 under it within half its thickness, at its start; a node that goes past the shorter extension meets the open rim again (give \
                                 `rim_extension` to choose, and place the blank clear of it)",
                            ),
                        );
                    }
                    e
                }
                None => {
                    at.warn(
                        &key,
                        format!(
                            "`{name}`: its open rim is not extended: any extension from {full:.3} mm down to \
                             {length:.3} mm passes through the blank or lies under it (give `rim_extension` to choose, 0 to silence \
                             this)",
                        ),
                    );
                    mesh
                }
            }
        }
    };
    Ok(Surface::Mesh(extended))
}
