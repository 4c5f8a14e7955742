//! A uniform follower pressure on the blank's surface (a vacuum bag, a
//! diaphragm): on each loaded membrane element a force p·A along its current
//! normal, lumped equally to its nodes.
//!
//! A = ∫ n dA is the element's current vector area: ½(x₂ − x₀) × (x₃ − x₁)
//! for a bilinear quad (exact for a warped one, the integral of
//! ∂x/∂ξ × ∂x/∂η), ½(x₁ − x₀) × (x₂ − x₀) for a triangle. Each of the k
//! nodes gets p·A/k: the total force is the exact ∫ p·n dA of the element,
//! and for a triangle the lumped load is the consistent one.
//!
//! The load follows the surface, so it depends on the positions: its
//! derivative ∂fₐ/∂x_b = (p/k)·∂A/∂x_b, with ∂A/∂x_b = ½[x_{b−1} − x_{b+1}]×
//! (neighbours in the element's cyclic node order; the same formula for
//! both shapes), is not symmetric.
//!
//! Not here: where the forces are summed per node and when (`drape-time`),
//! which side a scene asks for (`drape-io`).

use nalgebra::{Matrix3, Vector3};

use crate::{Amplitude, Model};

/// A uniform pressure on a set of membrane elements, along each element's
/// right-hand normal (node order): the elements are stored oriented so
/// that a positive `value` pushes the way the scene asked.
#[derive(Debug, Clone, PartialEq)]
pub struct PressureLoad {
    /// Pressure at a = 1 (MPa = N/mm²).
    pub value: f64,
    /// a(t).
    pub amplitude: Amplitude,
    /// Loaded quads, oriented.
    pub quads: Vec<[u32; 4]>,
    /// Loaded triangles, oriented.
    pub triangles: Vec<[u32; 3]>,
}

impl PressureLoad {
    /// A pressure `value`·a(t) on the membrane elements of `model` whose
    /// nodes all belong to `selected` (every element when None), along
    /// their normals by node order, or against them when `flip`.
    pub fn on_membranes(
        model: &Model,
        selected: Option<&[u32]>,
        flip: bool,
        value: f64,
        amplitude: Amplitude,
    ) -> Self {
        let mut chosen = vec![selected.is_none(); model.node_count()];
        for &n in selected.unwrap_or(&[]) {
            if let Some(c) = chosen.get_mut(n as usize) {
                *c = true;
            }
        }
        let mut load = Self {
            value,
            amplitude,
            quads: Vec::new(),
            triangles: Vec::new(),
        };
        for b in &model.membranes {
            for e in 0..b.len() {
                let nodes = b.element_nodes(e);
                if !nodes.iter().all(|&n| chosen[n as usize]) {
                    continue;
                }
                match *nodes {
                    [a, b, c, d] => load
                        .quads
                        .push(if flip { [a, d, c, b] } else { [a, b, c, d] }),
                    [a, b, c] => load
                        .triangles
                        .push(if flip { [a, c, b] } else { [a, b, c] }),
                    _ => unreachable!("membranes are quads or triangles"),
                }
            }
        }
        load
    }

    /// Number of loaded elements.
    pub fn len(&self) -> usize {
        self.quads.len() + self.triangles.len()
    }

    /// Whether no element is loaded.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The nodes of loaded element `e` (quads first, then triangles).
    pub fn element(&self, e: usize) -> &[u32] {
        match self.quads.get(e) {
            Some(q) => q,
            None => &self.triangles[e - self.quads.len()],
        }
    }

    /// Total area of the loaded elements at positions `x` (mm²).
    pub fn area(&self, x: &[Vector3<f64>]) -> f64 {
        (0..self.len())
            .map(|e| vector_area(self.element(e), x).norm())
            .sum()
    }

    /// The pressure p·a(t) at time `t` (MPa).
    pub fn pressure_at(&self, t: f64) -> f64 {
        self.value * self.amplitude.value(t)
    }

    /// The force on each node of element `e` at positions `x` and
    /// amplitude value `a`: p·a·A/k (N).
    pub fn nodal_force(&self, e: usize, x: &[Vector3<f64>], a: f64) -> Vector3<f64> {
        let nodes = self.element(e);
        vector_area(nodes, x) * (self.value * a / nodes.len() as f64)
    }
}

/// The current vector area ∫ n dA of an element (a quad's or a
/// triangle's nodes, in order) at positions `x` (mm²).
pub fn vector_area(nodes: &[u32], x: &[Vector3<f64>]) -> Vector3<f64> {
    let p = |i: usize| x[nodes[i] as usize];
    match nodes.len() {
        4 => 0.5 * (p(2) - p(0)).cross(&(p(3) - p(1))),
        3 => 0.5 * (p(1) - p(0)).cross(&(p(2) - p(0))),
        k => unreachable!("an element of {k} nodes"),
    }
}

/// ∂A/∂x_b of [`vector_area`] for the element's node `b` (local index):
/// ½[x_{b−1} − x_{b+1}]×, the cross-product matrix of the difference of
/// its neighours in the cyclic node order.
pub fn vector_area_derivative(nodes: &[u32], x: &[Vector3<f64>], b: usize) -> Matrix3<f64> {
    let k = nodes.len();
    let d = x[nodes[(b + k - 1) % k] as usize] - x[nodes[(b + 1) % k] as usize];
    0.5 * d.cross_matrix()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
    use drape_constitutive::Material;
    use nalgebra::Rotation3;

    fn model(element: ElementKind) -> Model {
        let blank = RectangleBlank {
            width: 40.0,
            height: 30.0,
            center: Vector3::zeros(),
            orientation_deg: 0.0,
            element,
            meshing: Meshing::Cells([4, 3]),
            fibres: FibreRepresentation::Embedded,
        };
        Model::from_blank(&blank, &Material::preset("glass-serge-4x3").unwrap()).unwrap()
    }

    /// Σ of every node's force over the loaded elements.
    fn total(load: &PressureLoad, x: &[Vector3<f64>], a: f64) -> Vector3<f64> {
        (0..load.len())
            .map(|e| load.nodal_force(e, x, a) * load.element(e).len() as f64)
            .sum()
    }

    #[test]
    fn a_tilted_flat_blank_gets_p_times_its_area_along_its_normal() {
        // Turned by 35° about an oblique axis and stretched 3 % and 1 %:
        // area 40·30·1.03·1.01 along the turned z axis.
        let turn = Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(Vector3::new(1.0, 2.0, 0.5)),
            0.61,
        );
        for element in [ElementKind::Quad, ElementKind::Triangle] {
            let m = model(element);
            let x: Vec<_> = m
                .x0
                .iter()
                .map(|p| {
                    turn * Vector3::new(1.03 * p.x, 1.01 * p.y, p.z) + Vector3::new(5.0, -2.0, 7.0)
                })
                .collect();
            let area = 40.0 * 30.0 * 1.03 * 1.01;
            let normal = turn * Vector3::z();
            for (flip, sign) in [(false, 1.0), (true, -1.0)] {
                let load = PressureLoad::on_membranes(&m, None, flip, 0.1, Amplitude::Constant);
                assert_eq!(load.len(), m.membrane_count());
                let f = total(&load, &x, 0.5);
                let expected = normal * (sign * 0.1 * 0.5 * area);
                assert!(
                    (f - expected).norm() <= 1e-12 * expected.norm(),
                    "{element:?} flip {flip}: {f:?} instead of {expected:?}"
                );
                assert!((load.area(&x) - area).abs() <= 1e-11 * area);
                // Every node of an element gets the same share, along n.
                for e in 0..load.len() {
                    let fe = load.nodal_force(e, &x, 1.0);
                    assert!(fe.normalize().dot(&(normal * sign)) > 1.0 - 1e-12);
                }
            }
        }
    }

    /// A warped quad (its four nodes not in one plane): the vector area is
    /// the integral of the bilinear surface's normal, by Gauss.
    #[test]
    fn a_warped_quad_gets_the_integral_of_p_n_over_its_bilinear_surface() {
        let x = vec![
            Vector3::new(-3.0, 0.0, 0.4),
            Vector3::new(4.0, 0.3, -0.2),
            Vector3::new(3.5, 5.0, 0.9),
            Vector3::new(-2.8, 4.6, -0.5),
        ];
        let nodes = [0u32, 1, 2, 3];
        // ∫∫ x_ξ × x_η dξ dη by 4 × 4 Gauss (the integrand is bilinear).
        let (g, w) = (
            [
                -0.861_136_311_594_052_6,
                -0.339_981_043_584_856_3,
                0.339_981_043_584_856_3,
                0.861_136_311_594_052_6,
            ],
            [
                0.347_854_845_137_453_9,
                0.652_145_154_862_546_1,
                0.652_145_154_862_546_1,
                0.347_854_845_137_453_9,
            ],
        );
        let (sx, sy) = ([-1.0, 1.0, 1.0, -1.0], [-1.0, -1.0, 1.0, 1.0]);
        let mut integral = Vector3::zeros();
        for (xi, wi) in g.iter().zip(w) {
            for (eta, wj) in g.iter().zip(w) {
                let mut dxi = Vector3::zeros();
                let mut deta = Vector3::zeros();
                for a in 0..4 {
                    dxi += x[a] * (0.25 * sx[a] * (1.0 + sy[a] * eta));
                    deta += x[a] * (0.25 * sy[a] * (1.0 + sx[a] * xi));
                }
                integral += dxi.cross(&deta) * (wi * wj);
            }
        }
        let area = vector_area(&nodes, &x);
        assert!(
            (area - integral).norm() <= 1e-13 * integral.norm(),
            "{area:?} {integral:?}"
        );
    }

    #[test]
    fn the_area_derivative_matches_central_differences() {
        let x = vec![
            Vector3::new(-3.0, 0.0, 0.4),
            Vector3::new(4.0, 0.3, -0.2),
            Vector3::new(3.5, 5.0, 0.9),
            Vector3::new(-2.8, 4.6, -0.5),
        ];
        for nodes in [&[0u32, 1, 2, 3][..], &[0, 1, 2][..], &[3, 1, 0][..]] {
            for b in 0..nodes.len() {
                let k = vector_area_derivative(nodes, &x, b);
                for c in 0..3 {
                    let h = 1e-6;
                    let mut xp = x.clone();
                    xp[nodes[b] as usize][c] += h;
                    let mut xm = x.clone();
                    xm[nodes[b] as usize][c] -= h;
                    let fd = (vector_area(nodes, &xp) - vector_area(nodes, &xm)) / (2.0 * h);
                    assert!(
                        (k.column(c) - fd).norm() <= 1e-8,
                        "{nodes:?} node {b} component {c}: {:?} vs {fd:?}",
                        k.column(c)
                    );
                }
            }
        }
    }

    #[test]
    fn a_node_set_selects_the_elements_wholly_inside_it() {
        let m = model(ElementKind::Quad);
        let left = m.node_set("left").unwrap().to_vec();
        // The left column of elements has two nodes on the edge: none is
        // wholly inside the edge's set.
        let edge = PressureLoad::on_membranes(&m, Some(&left), false, 1.0, Amplitude::Constant);
        assert!(edge.is_empty());
        let near: Vec<u32> = (0..m.node_count() as u32)
            .filter(|&n| m.x0[n as usize].x < -5.0)
            .collect();
        // Nodes at x = −20 and −10: the first column of the 4 × 3 grid.
        let load = PressureLoad::on_membranes(&m, Some(&near), false, 1.0, Amplitude::Constant);
        assert_eq!(load.len(), 3);
    }
}
