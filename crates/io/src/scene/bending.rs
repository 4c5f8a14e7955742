//! Whether a scene's fabric gets yarn bending: `fabric.bending` and its
//! default.
//!
//! Unset, bending is on wherever it can hold the blank: the material has a
//! `bending_rigidity` and the mesh's lines follow the yarns through every
//! interior node ([`drape_model::YarnCoverage::is_complete`]). Where it
//! cannot, the scene runs without it and says so in one warning, never an
//! error: a membrane without bending folds at no cost, and the run's fold
//! check will say if it did. `true` insists (an error where it cannot
//! apply at all, as before the default changed); `false` turns it off
//! without a word.

use drape_constitutive::Material;
use drape_model::{Model, YarnCoverage};
use nalgebra::Vector3;

use super::{FabricSpec, Locator, SceneError};

/// The rigidities to bend the blank with, or `None` for no bending.
pub(super) fn yarn_bending(
    fabric: &FabricSpec,
    material: &Material,
    model: &Model,
    at: &Locator<'_>,
) -> Result<Option<[f64; 2]>, SceneError> {
    let theta = fabric.orientation_deg.to_radians();
    let warp = Vector3::new(theta.cos(), theta.sin(), 0.0);
    decide(
        at,
        &Whose {
            field: "fabric.bending",
            ply: None,
        },
        fabric.bending,
        material,
        || model.yarn_coverage(warp, Vector3::z()),
    )
}

/// Whose bending setting it is, for the messages: its field, and the ply
/// of a stack it is for (`None` for `[fabric]`'s one blank).
pub(super) struct Whose<'a> {
    pub(super) field: &'a str,
    pub(super) ply: Option<&'a str>,
}

/// The rigidities to bend one blank (a `[fabric]`, or one ply of a stack)
/// with, from its `bending` setting, its material and how far its mesh
/// lines follow its yarns; `None` for no bending.
pub(super) fn decide(
    at: &Locator<'_>,
    whose: &Whose<'_>,
    setting: Option<bool>,
    material: &Material,
    coverage: impl FnOnce() -> YarnCoverage,
) -> Result<Option<[f64; 2]>, SceneError> {
    let field = whose.field;
    let (blank, in_ply) = match whose.ply {
        None => ("the blank".to_owned(), String::new()),
        Some(name) => (format!("ply `{name}`"), format!(" in ply `{name}`")),
    };
    match setting {
        Some(false) => Ok(None),
        Some(true) => material.bending_rigidity.map(Some).ok_or_else(|| {
            at.error(
                field,
                "yarn bending needs the material's `bending_rigidity = [warp, weft]` (N·mm); \
                 this material has none",
            )
        }),
        None => {
            let Some(rigidity) = material.bending_rigidity else {
                at.warn(
                    field,
                    format!(
                        "yarn bending is off{}: the material has no `bending_rigidity = [warp, \
                         weft]` (N·mm), and a membrane without it folds at no cost; give it one, \
                         or set `bending = false` to say that this is meant",
                        in_ply
                    ),
                );
                return Ok(None);
            };
            let coverage = coverage();
            if coverage.is_complete() {
                return Ok(Some(rigidity));
            }
            at.warn(
                field,
                format!(
                    "yarn bending is off{}: it acts along mesh lines that follow the yarns, and \
                     {} of {blank}'s {} interior nodes have a warp and a weft line through \
                     them (a mesh file, or embedded fibres at an angle to the grid); the \
                     membrane can fold at no cost, and the run's fold check says if it did. \
                     Mesh the blank along the yarns (a rectangle blank, θ = 0 or 90 for \
                     embedded fibres) to have it, or set `bending = false` to say that this is \
                     meant",
                    in_ply, coverage.covered_nodes, coverage.interior_nodes
                ),
            );
            Ok(None)
        }
    }
}
