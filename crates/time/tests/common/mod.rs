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
    glass_ply_mapped(name, center, rows, |x| x)
}

/// [`glass_ply`] with its mesh's nodes moved by `map` before the model is
/// built (the elements' rest shape is the mapped one).
pub fn glass_ply_mapped(
    name: &str,
    center: Vector3<f64>,
    rows: usize,
    map: impl Fn(Vector3<f64>) -> Vector3<f64>,
) -> PlyModel {
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
    let mut mesh = blank.mesh().expect("mesh");
    for x in &mut mesh.x0 {
        *x = map(*x);
    }
    PlyModel {
        model: Model::from_mesh(&mesh, &material, FibreRepresentation::Embedded).expect("model"),
        name: name.into(),
        thickness: material.thickness,
        orientation_deg: 0.0,
        friction_below: 0.0,
    }
}
