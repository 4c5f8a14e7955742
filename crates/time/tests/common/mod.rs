//! What the stack tests share: glass plies of 10 mm quads.

use drape_constitutive::Material;
use drape_model::Model;
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::stack::PlyModel;
use nalgebra::Vector3;

pub fn glass() -> Material {
    Material::preset("glass-serge-4x3").expect("preset")
}

/// A glass ply 40 mm wide and `rows` 10 mm quads high, centred at
/// `center`, with embedded fibres.
pub fn glass_ply(name: &str, center: Vector3<f64>, rows: usize) -> PlyModel {
    let material = glass();
    let blank = RectangleBlank {
        width: 40.0,
        height: 10.0 * rows as f64,
        center,
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells([4, rows]),
        fibres: FibreRepresentation::Embedded,
    };
    PlyModel {
        model: Model::from_mesh(
            &blank.mesh().expect("mesh"),
            &material,
            FibreRepresentation::Embedded,
        )
        .expect("model"),
        name: name.into(),
        thickness: material.thickness,
        orientation_deg: 0.0,
        friction_below: 0.0,
    }
}
