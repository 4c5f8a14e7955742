//! Whether a scene's yarns carry their buckling load: `fabric.yarn_buckling`.
//!
//! Unset (or `true`), the material's own compression law is used: every
//! preset's yarn is an imperfect column between interlacings whose load
//! tends to its Euler stress (`FibreLaw::buckling_stress` in
//! drape-constitutive). `false` runs the paper's yarn, which buckles at no
//! cost (c_c = 0, σ_b = 0): the paper's validation runs set it, as they set
//! `bending = false`, to reproduce the paper's element bit for bit.

use drape_constitutive::Material;

use super::{Locator, SceneError};

/// The material with the compression law the scene asks for.
pub(super) fn apply(
    yarn_buckling: Option<bool>,
    mut material: Material,
    at: &Locator<'_>,
) -> Result<Material, SceneError> {
    const FIELD: &str = "fabric.yarn_buckling";
    match yarn_buckling {
        None => Ok(material),
        Some(false) => {
            // The paper's yarn: nothing in compression. A linear
            // compression factor the user gave is a different law, kept.
            material.fibre.buckling_stress = 0.0;
            Ok(material)
        }
        Some(true) if material.fibre.buckling_stress > 0.0 => Ok(material),
        Some(true) => Err(at.error(
            FIELD,
            "yarn buckling needs the material's `fibre.buckling_stress` (MPa, the Euler \
             stress of a yarn segment between interlacings); this material has none",
        )),
    }
}
