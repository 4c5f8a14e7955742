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
use drape_model::Model;
use nalgebra::Vector3;

use super::{FabricSpec, Locator, SceneError};

/// The rigidities to bend the blank with, or `None` for no bending.
pub(super) fn yarn_bending(
    fabric: &FabricSpec,
    material: &Material,
    model: &Model,
    at: &Locator<'_>,
) -> Result<Option<[f64; 2]>, SceneError> {
    const FIELD: &str = "fabric.bending";
    match fabric.bending {
        Some(false) => Ok(None),
        Some(true) => material.bending_rigidity.map(Some).ok_or_else(|| {
            at.error(
                FIELD,
                "yarn bending needs the material's `bending_rigidity = [warp, weft]` (N·mm); \
                 this material has none",
            )
        }),
        None => {
            let Some(rigidity) = material.bending_rigidity else {
                at.warn(
                    FIELD,
                    "yarn bending is off: the material has no `bending_rigidity = [warp, weft]` \
                     (N·mm), and a membrane without it folds at no cost; give it one, or set \
                     `bending = false` to say that this is meant",
                );
                return Ok(None);
            };
            let theta = fabric.orientation_deg.to_radians();
            let warp = Vector3::new(theta.cos(), theta.sin(), 0.0);
            let coverage = model.yarn_coverage(warp, Vector3::z());
            if coverage.is_complete() {
                return Ok(Some(rigidity));
            }
            at.warn(
                FIELD,
                format!(
                    "yarn bending is off: it acts along mesh lines that follow the yarns, and \
                     {} of the blank's {} interior nodes have a warp and a weft line through \
                     them (a mesh file, or embedded fibres at an angle to the grid); the \
                     membrane can fold at no cost, and the run's fold check says if it did. \
                     Mesh the blank along the yarns (a rectangle blank, θ = 0 or 90 for \
                     embedded fibres) to have it, or set `bending = false` to say that this is \
                     meant",
                    coverage.covered_nodes, coverage.interior_nodes
                ),
            );
            Ok(None)
        }
    }
}
