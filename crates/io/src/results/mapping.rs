//! Per-element values carried from one mesh to another by closest point:
//! the draped orientations onto a structural mesh of the user's
//! ([`map_onto`]), one run's shear onto another run's mesh (`drape
//! compare RUN_A RUN_B`).
//!
//! A [`SurfaceField`] holds a surface mesh and values per element. It
//! first turns them into values per node, each node taking the
//! area-weighted mean of its elements' (NaN values left out), so that the
//! field is continuous; a query point then takes the closest point of the
//! surface (parry3d's BVH over the mesh's triangles, quads split along
//! their 0–2 diagonal) and the values there, interpolated linearly between
//! the triangle's nodes. A query point at the centroid of the element found
//! (to 1e-6 of the element's size: the same mesh, or a mesh sharing that
//! element) takes the element's value as it is, at distance zero (a
//! warped quad's centroid is off its two triangles), so that a mesh compared
//! with itself or mapped onto itself loses nothing. For a smooth field this is second-order accurate
//! in the element size away from the mesh's boundary (first order within
//! an element of it, where a node's mean is one-sided); the tests measure
//! it.
//!
//! What it is not: no conservative (integral-preserving) transfer, and no
//! check that the two meshes describe the same part: the distance of each
//! query point to the surface is reported for that.

use drape_model::Model;
use nalgebra::Vector3;
use parry3d_f64::math::Vector as DVec3;
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::TriMesh;

use super::export::Orientations;
use crate::mesh_import::ImportedMesh;

/// A surface mesh with values per node, for sampling by closest point.
pub struct SurfaceField {
    mesh: TriMesh,
    /// Per channel, per node.
    nodal: Vec<Vec<f64>>,
    /// The element each triangle of `mesh` comes from.
    element_of: Vec<u32>,
    /// Per element: centroid and size (square root of its area).
    centroid: Vec<(Vector3<f64>, f64)>,
    /// Per channel, per element, as given.
    elemental: Vec<Vec<f64>>,
}

/// A sample of a [`SurfaceField`].
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// The values, one per channel.
    pub values: Vec<f64>,
    /// The closest point of the surface.
    pub point: Vector3<f64>,
    /// Distance from the query point to it (mm).
    pub distance: f64,
}

impl SurfaceField {
    /// The field of `channels` (each one value per element of `elements`,
    /// node indices into `nodes`, 3 or 4 each).
    pub fn new(
        nodes: &[Vector3<f64>],
        elements: &[Vec<u32>],
        channels: &[Vec<f64>],
    ) -> Result<Self, String> {
        if let Some(c) = channels.iter().find(|c| c.len() != elements.len()) {
            return Err(format!(
                "a channel has {} values for {} elements",
                c.len(),
                elements.len()
            ));
        }
        let mut triangles = Vec::with_capacity(2 * elements.len());
        let mut element_of = Vec::with_capacity(2 * elements.len());
        let mut centroid = Vec::with_capacity(elements.len());
        let mut weight = vec![0.0; nodes.len()];
        let mut nodal = vec![vec![0.0; nodes.len()]; channels.len()];
        let mut weights = vec![vec![0.0; nodes.len()]; channels.len()];
        for (e, element) in elements.iter().enumerate() {
            if element.iter().any(|&n| n as usize >= nodes.len()) {
                return Err(format!("element {e} names a node that does not exist"));
            }
            let p = |k: usize| nodes[element[k] as usize];
            let area = match element.len() {
                3 => {
                    triangles.push([element[0], element[1], element[2]]);
                    element_of.push(e as u32);
                    0.5 * (p(1) - p(0)).cross(&(p(2) - p(0))).norm()
                }
                4 => {
                    triangles.push([element[0], element[1], element[2]]);
                    triangles.push([element[0], element[2], element[3]]);
                    element_of.extend([e as u32, e as u32]);
                    0.5 * (p(2) - p(0)).cross(&(p(3) - p(1))).norm()
                }
                n => return Err(format!("element {e} has {n} nodes, expected 3 or 4")),
            };
            let mid = element
                .iter()
                .map(|&n| nodes[n as usize])
                .sum::<Vector3<f64>>()
                / element.len() as f64;
            centroid.push((mid, area.sqrt()));
            for &n in element {
                weight[n as usize] += area;
                for (c, values) in channels.iter().enumerate() {
                    if values[e].is_finite() {
                        nodal[c][n as usize] += area * values[e];
                        weights[c][n as usize] += area;
                    }
                }
            }
        }
        for (values, w) in nodal.iter_mut().zip(&weights) {
            for (v, &w) in values.iter_mut().zip(w) {
                *v = if w > 0.0 { *v / w } else { f64::NAN };
            }
        }
        let vertices = nodes.iter().map(|p| DVec3::new(p.x, p.y, p.z)).collect();
        let mesh = TriMesh::new(vertices, triangles)
            .map_err(|e| format!("the surface cannot be searched: {e:?}"))?;
        Ok(Self {
            mesh,
            nodal,
            element_of,
            centroid,
            elemental: channels.to_vec(),
        })
    }

    /// The values at the surface's closest point to `x`.
    pub fn sample(&self, x: &Vector3<f64>) -> Sample {
        let q = DVec3::new(x.x, x.y, x.z);
        let (projection, (triangle, location)) =
            self.mesh.project_local_point_and_get_location(q, false);
        let corners = self.mesh.indices()[triangle as usize];
        let p = projection.point;
        let point = Vector3::new(p.x, p.y, p.z);
        let element = self.element_of[triangle as usize] as usize;
        let (mid, size) = self.centroid[element];
        // The centroid of a warped quad is off its two triangles: the query
        // is compared with the centroid, not with its projection.
        if (x - mid).norm() <= 1e-6 * size {
            return Sample {
                values: self.elemental.iter().map(|v| v[element]).collect(),
                point: mid,
                distance: (x - mid).norm(),
            };
        }
        let weights = location
            .barycentric_coordinates()
            .filter(|w| w.iter().all(|v| v.is_finite()))
            .unwrap_or([1.0, 0.0, 0.0]);
        let values = self
            .nodal
            .iter()
            .map(|nodal| {
                corners
                    .iter()
                    .zip(weights)
                    .map(|(&n, w)| w * nodal[n as usize])
                    .sum()
            })
            .collect();
        Sample {
            values,
            point,
            distance: (x - point).norm(),
        }
    }
}

/// The membrane elements of `model` as node lists, in its element order.
pub fn model_elements(model: &Model) -> Vec<Vec<u32>> {
    let mut cells = Vec::with_capacity(model.membrane_count());
    for batch in &model.membranes {
        for e in 0..batch.len() {
            cells.push(batch.element_nodes(e).to_vec());
        }
    }
    cells
}

/// `source`'s orientations carried onto the elements of `target` (a
/// structural mesh, in the same coordinates as the formed part): at each
/// target element's centroid, the values of `source`'s closest point
/// ([`SurfaceField`]); the directions are then projected on the target
/// element's plane and normalised. The result names the target's elements
/// by their labels (sorted) and has no mesh; its `distance` holds each
/// centroid's distance to the formed surface.
///
/// The shear angle and the thickness are interpolated as values, not
/// recomputed from the directions, as in the source (see the conventions
/// of [`super::export`]).
///
/// A laminate's plies are mapped one by one, each from its own formed
/// surface onto all of `target`'s elements: the result is a layup with
/// every ply over the same labels.
pub fn map_onto(source: &Orientations, target: &ImportedMesh) -> Result<Orientations, String> {
    if source.plies.is_empty() {
        return map_one(source, target);
    }
    let plies = source
        .plies
        .iter()
        .map(|p| {
            map_one(&source.ply(p), target)
                .map(|o| (p.name.clone(), o))
                .map_err(|e| format!("ply {}: {e}", p.name))
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(Orientations::layup(plies))
}

/// [`map_onto`] for one ply.
fn map_one(source: &Orientations, target: &ImportedMesh) -> Result<Orientations, String> {
    if source.nodes.is_empty() {
        return Err("the orientations carry no mesh to map from".into());
    }
    let component = |d: &[Vector3<f64>], k: usize| d.iter().map(|v| v[k]).collect::<Vec<_>>();
    let channels = vec![
        component(&source.warp, 0),
        component(&source.warp, 1),
        component(&source.warp, 2),
        component(&source.weft, 0),
        component(&source.weft, 1),
        component(&source.weft, 2),
        source.shear_deg.clone(),
        source.thickness.clone(),
    ];
    let field = SurfaceField::new(&source.nodes, &source.elements, &channels)?;
    let mut rows: Vec<(i64, Vec<u32>)> = target
        .quad_labels
        .iter()
        .zip(&target.quads)
        .map(|(&l, q)| (l, q.to_vec()))
        .chain(
            target
                .triangle_labels
                .iter()
                .zip(&target.triangles)
                .map(|(&l, t)| (l, t.to_vec())),
        )
        .collect();
    rows.sort_by_key(|(label, _)| *label);
    let mut out = Orientations {
        title: format!("{} (mapped by closest point)", source.title),
        nominal_thickness: source.nominal_thickness,
        distance: Some(Vec::with_capacity(rows.len())),
        ..Orientations::default()
    };
    for (label, nodes) in rows {
        let p = |k: usize| target.x0[nodes[k] as usize];
        let centroid = nodes
            .iter()
            .map(|&n| target.x0[n as usize])
            .sum::<Vector3<f64>>()
            / nodes.len() as f64;
        let normal = if nodes.len() == 4 {
            (p(2) - p(0)).cross(&(p(3) - p(1)))
        } else {
            (p(1) - p(0)).cross(&(p(2) - p(0)))
        }
        .try_normalize(0.0)
        .unwrap_or_else(Vector3::z);
        let s = field.sample(&centroid);
        let v = &s.values;
        // A yarn along the element's normal has no direction in its plane:
        // missing, with the reason, not a NaN direction.
        let in_plane = |d: Vector3<f64>| (d - normal * d.dot(&normal)).try_normalize(1e-9);
        let (warp, weft) = (
            in_plane(Vector3::new(v[0], v[1], v[2])),
            in_plane(Vector3::new(v[3], v[4], v[5])),
        );
        let edge_on: Vec<&str> = [(warp.is_none(), "warp"), (weft.is_none(), "weft")]
            .iter()
            .filter(|(none, _)| *none)
            .map(|(_, name)| *name)
            .collect();
        if !edge_on.is_empty() {
            out.missing.push((
                out.labels.len(),
                format!(
                    "the formed part's {} runs along this element's normal (the element is \
                     edge-on to the fibres): no direction in its plane",
                    edge_on.join(" and ")
                ),
            ));
        }
        let none = Vector3::repeat(f64::NAN);
        out.labels.push(label);
        out.centroid.push(centroid);
        out.warp.push(warp.unwrap_or(none));
        out.weft.push(weft.unwrap_or(none));
        out.shear_deg.push(v[6]);
        out.thickness.push(v[7]);
        if let Some(d) = &mut out.distance {
            d.push(s.distance);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear field on a flat mesh is reproduced exactly inside it (the
    /// nodal means of a linear field are not its nodal values in general,
    /// but on a uniform grid of equal elements they are, away from the
    /// boundary), and a point above the mesh reports its height.
    #[test]
    fn a_uniform_grid_reproduces_a_linear_field_inside() {
        let n = 6;
        let nodes: Vec<Vector3<f64>> = (0..=n)
            .flat_map(|j| (0..=n).map(move |i| Vector3::new(i as f64, j as f64, 0.0)))
            .collect();
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut elements = Vec::new();
        let mut values = Vec::new();
        for j in 0..n {
            for i in 0..n {
                elements.push(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                values.push(2.0 * (i as f64 + 0.5) - 3.0 * (j as f64 + 0.5));
            }
        }
        let field = SurfaceField::new(&nodes, &elements, &[values]).unwrap();
        let s = field.sample(&Vector3::new(2.3, 3.6, 0.7));
        assert!(
            (s.values[0] - (2.0 * 2.3 - 3.0 * 3.6)).abs() < 1e-12,
            "{s:?}"
        );
        assert!((s.distance - 0.7).abs() < 1e-12);
        assert!((s.point - Vector3::new(2.3, 3.6, 0.0)).norm() < 1e-12);
    }

    /// At an element's own centroid the element's value, not the smoothed
    /// nodal interpolation (a field that is not linear: nodal means would
    /// change it).
    #[test]
    fn an_element_centroid_takes_the_element_value() {
        let nodes = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(2.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
            Vector3::new(2.0, 1.0, 0.0),
        ];
        let elements = vec![vec![0, 1, 4, 3], vec![1, 2, 5], vec![1, 5, 4]];
        let values = vec![1.0, 5.0, -2.0];
        let field = SurfaceField::new(&nodes, &elements, std::slice::from_ref(&values)).unwrap();
        for (e, element) in elements.iter().enumerate() {
            let c = element
                .iter()
                .map(|&n| nodes[n as usize])
                .sum::<Vector3<f64>>()
                / element.len() as f64;
            assert_eq!(field.sample(&c).values[0], values[e], "element {e}");
        }
        // Off the centroid, interpolated between nodal means.
        let s = field.sample(&Vector3::new(0.3, 0.5, 0.0));
        assert!(s.values[0] != values[0], "{s:?}");
    }
}
