//! "The maximum shear away from the holding": the largest shear over the
//! elements that are not beside a held node, shared by the paper cases
//! (`validate/paper.rs`, through `validate/scenes.rs`) and the
//! work–precision bench, so that both leave out the same region.
//!
//! Why it exists: the hemisphere is held by point springs, and the shear at
//! a point spring grows without bound as the mesh is refined (a point load
//! on a membrane is a singularity: 18.7 / 24.2 / 30.9 / 37.2° on 10 / 20 /
//! 40 / 80 cells), so the maximum anywhere measures the mesh at the springs
//! rather than the forming. Away from them the maximum converges.
//!
//! Not for: deciding where a scene's holding is (a node is held when a
//! `[[springs]]` or `[[loads]]` entry names it; contact tools are not
//! holding).

use drape_model::Model;
use nalgebra::Vector3;

/// The neighbourhood of a holding node left out of "the maximum shear away
/// from the holding" (mm, in the flat blank): about three cells of the
/// shipped 40×40 hemisphere mesh (8.75 mm), fixed in millimetres so that it
/// is the same region on every mesh.
pub const AWAY_FROM_HOLDING_MM: f64 = 25.0;

/// The largest |γ| (in the unit of `shear`) over the elements whose
/// reference centroid `centroid0[e]` is more than [`AWAY_FROM_HOLDING_MM`]
/// from every node held by a spring or loaded by a nodal load, measured in
/// the blank's plane (x, y); the largest over every element when nothing
/// is held, and 0 when every element is beside a held node.
///
/// `shear` and `centroid0` are per membrane element, in the model's order.
pub fn max_shear_away(
    model: &Model,
    centroid0: &[Vector3<f64>],
    shear: impl IntoIterator<Item = f64>,
) -> f64 {
    let held: Vec<Vector3<f64>> = (model.springs.iter().map(|s| &s.nodes))
        .chain(model.loads.iter().map(|l| &l.nodes))
        .flatten()
        .map(|&n| model.x0[n as usize])
        .collect();
    shear
        .into_iter()
        .zip(centroid0)
        .filter(|(_, c)| {
            held.iter()
                .all(|x| (x - *c).xy().norm() > AWAY_FROM_HOLDING_MM)
        })
        .fold(0.0, |m: f64, (g, _)| m.max(g.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use drape_io::scene::Scene;
    use std::path::Path;

    /// The shipped hemisphere on a 10 × 10 blank (35 mm cells), held at
    /// its corners and edge midpoints: the elements left out are the
    /// corner cells (centroid 24.7 mm from the corner) and the two cells
    /// beside each edge midpoint (24.7 mm from it), 12 in all; the next
    /// ones are 39.1 mm away.
    #[test]
    fn leaves_out_the_cells_beside_the_springs_only() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
        let scene = root.join("scenes/hemisphere-0-90.toml");
        let cells = [("fabric.blank.cells".to_owned(), "[10, 10]".to_owned())];
        let model = Scene::from_file(&scene, &cells).unwrap().model;
        let centroid0 = model
            .element_fields(&model.initial_state())
            .unwrap()
            .centroid0;
        assert_eq!(centroid0.len(), 100);
        let mut left_out = Vec::new();
        for e in 0..centroid0.len() {
            // One element sheared far more than the rest (signed, so that
            // |γ| is what counts).
            let shear = (0..centroid0.len()).map(|k| if k == e { -50.0 } else { 1.0 });
            match max_shear_away(&model, &centroid0, shear) {
                50.0 => {}
                1.0 => left_out.push(e),
                other => panic!("element {e}: {other}"),
            }
        }
        assert_eq!(left_out.len(), 12, "{left_out:?}");
        for &e in &left_out {
            let c = centroid0[e];
            let (x, y) = (c.x.abs(), c.y.abs());
            // 175 − 17.5: the outermost ring of cells; 17.5: beside an
            // axis (the edge midpoints lie on the axes).
            let corner = (x - 157.5).abs() < 1e-9 && (y - 157.5).abs() < 1e-9;
            let midpoint = ((x - 157.5).abs() < 1e-9 && (y - 17.5).abs() < 1e-9)
                || ((y - 157.5).abs() < 1e-9 && (x - 17.5).abs() < 1e-9);
            assert!(corner || midpoint, "element {e} at {c:?}");
        }
    }

    #[test]
    fn without_holding_it_is_the_maximum_anywhere() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
        let scene = root.join("scenes/hemisphere-0-90.toml");
        let cells = [("fabric.blank.cells".to_owned(), "[4, 4]".to_owned())];
        let mut model = Scene::from_file(&scene, &cells).unwrap().model;
        model.springs.clear();
        model.loads.clear();
        let centroid0 = model
            .element_fields(&model.initial_state())
            .unwrap()
            .centroid0;
        let shear = (0..centroid0.len()).map(|k| if k == 0 { -7.0 } else { 1.0 });
        assert_eq!(max_shear_away(&model, &centroid0, shear), 7.0);
    }
}
