//! Reference geometry of a membrane integration point: its local orthonormal
//! frame (e₁, e₂) in the reference tangent plane and the shape-function
//! gradients ∂Nₐ/∂X in that frame, for 3-node triangles and 4-node quads.
//!
//! The reference mesh may be curved (an imported preform): each integration
//! point gets the tangent plane of its own reference position, e₁ along
//! ∂X/∂ξ. With these gradients the reference configuration has F = [e₁ e₂]
//! and C = I exactly.

use nalgebra::{Matrix2, Vector2, Vector3};

use crate::KinematicsError;

/// An orthonormal frame in a membrane's reference tangent plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFrame {
    /// First local axis (along ∂X/∂ξ).
    pub e1: Vector3<f64>,
    /// Second local axis, n × e₁.
    pub e2: Vector3<f64>,
    /// Unit normal.
    pub normal: Vector3<f64>,
}

impl LocalFrame {
    /// The frame with e₁ along `g1` in the plane of `g1` and `g2`.
    pub fn from_tangents(g1: &Vector3<f64>, g2: &Vector3<f64>) -> Result<Self, KinematicsError> {
        let n = g1.cross(g2);
        let size = n.norm();
        if !size.is_finite() {
            return Err(KinematicsError::NonFinite {
                what: "reference coordinates",
            });
        }
        if size <= 1e-12 * g1.norm() * g2.norm() {
            return Err(KinematicsError::DegenerateReference { size });
        }
        let normal = n / size;
        let e1 = g1.normalize();
        Ok(Self {
            e1,
            e2: normal.cross(&e1),
            normal,
        })
    }

    /// Components of a 3D vector in the frame (its in-plane part).
    #[inline]
    pub fn local(&self, v: &Vector3<f64>) -> Vector2<f64> {
        Vector2::new(self.e1.dot(v), self.e2.dot(v))
    }

    /// The 3D vector of local components `v`.
    #[inline]
    pub fn global(&self, v: &Vector2<f64>) -> Vector3<f64> {
        self.e1 * v.x + self.e2 * v.y
    }
}

/// Reference data of one membrane integration point with `N` nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferencePoint<const N: usize> {
    /// ∂Nₐ/∂X in the local frame.
    pub grad_n: [Vector2<f64>; N],
    /// Shape-function values Nₐ at the point.
    pub shape: [f64; N],
    /// The local frame of the reference tangent plane.
    pub frame: LocalFrame,
    /// Reference area this point integrates (det J × quadrature weight).
    pub area: f64,
}

fn reference_point<const N: usize>(
    x: &[Vector3<f64>; N],
    shape: [f64; N],
    d_xi: [f64; N],
    d_eta: [f64; N],
    weight: f64,
) -> Result<ReferencePoint<N>, KinematicsError> {
    let mut g1 = Vector3::zeros();
    let mut g2 = Vector3::zeros();
    for a in 0..N {
        g1 += x[a] * d_xi[a];
        g2 += x[a] * d_eta[a];
    }
    let frame = LocalFrame::from_tangents(&g1, &g2)?;
    // J = ∂X/∂ξ in the local frame; upper triangular since e₁ ∥ g₁.
    let j = Matrix2::from_columns(&[frame.local(&g1), frame.local(&g2)]);
    let det_j = j.determinant();
    let j_inv_t = Matrix2::new(j[(1, 1)], -j[(1, 0)], -j[(0, 1)], j[(0, 0)]) / det_j;
    let mut grad_n = [Vector2::zeros(); N];
    for a in 0..N {
        grad_n[a] = j_inv_t * Vector2::new(d_xi[a], d_eta[a]);
    }
    Ok(ReferencePoint {
        grad_n,
        shape,
        frame,
        area: det_j * weight,
    })
}

/// The single integration point (centroid) of a linear triangle with
/// reference nodes `x`; `area` is the triangle's area.
pub fn triangle_point(x: &[Vector3<f64>; 3]) -> Result<ReferencePoint<3>, KinematicsError> {
    let third = 1.0 / 3.0;
    reference_point(x, [third; 3], [-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0], 0.5)
}

/// The bilinear quad's integration point at natural coordinates (ξ, η) with
/// quadrature weight `weight` (1 for each point of the 2×2 Gauss rule).
/// Nodes are numbered counter-clockwise from (−1, −1).
pub fn quad_point(
    x: &[Vector3<f64>; 4],
    xi: f64,
    eta: f64,
    weight: f64,
) -> Result<ReferencePoint<4>, KinematicsError> {
    let (xm, xp, em, ep) = (1.0 - xi, 1.0 + xi, 1.0 - eta, 1.0 + eta);
    reference_point(
        x,
        [
            0.25 * xm * em,
            0.25 * xp * em,
            0.25 * xp * ep,
            0.25 * xm * ep,
        ],
        [-0.25 * em, 0.25 * em, 0.25 * ep, -0.25 * ep],
        [-0.25 * xm, -0.25 * xp, 0.25 * xp, 0.25 * xm],
        weight,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{deformation_gradient, polar_decomposition};
    use nalgebra::{Matrix3x2, Rotation3};

    const GAUSS: f64 = 0.577_350_269_189_625_8; // 1/√3

    fn distorted_quad() -> [Vector3<f64>; 4] {
        let q = Rotation3::from_euler_angles(0.4, 0.2, -0.7);
        [
            q * Vector3::new(0.0, 0.0, 0.0),
            q * Vector3::new(2.0, 0.3, 0.0),
            q * Vector3::new(2.4, 1.9, 0.0),
            q * Vector3::new(-0.2, 1.5, 0.0),
        ]
    }

    #[test]
    fn gradients_reproduce_linear_fields_and_areas() {
        let x = distorted_quad();
        let mut area = 0.0;
        for (xi, eta) in [(-1., -1.), (1., -1.), (1., 1.), (-1., 1.)] {
            let p = quad_point(&x, xi * GAUSS, eta * GAUSS, 1.0).unwrap();
            area += p.area;
            let sum: Vector2<f64> = p.grad_n.iter().sum();
            assert!(sum.norm() < 1e-14);
            assert!((p.shape.iter().sum::<f64>() - 1.0).abs() < 1e-15);
            // The reference configuration is unstretched: F = [e₁ e₂], U = I.
            let f = deformation_gradient(&x, &p.grad_n);
            let expected = Matrix3x2::from_columns(&[p.frame.e1, p.frame.e2]);
            assert!((f - expected).norm() < 1e-14);
            let polar = polar_decomposition(&f).unwrap();
            assert!((polar.u - Matrix2::identity()).norm() < 1e-14);
        }
        // Shoelace area of the planar quad in its plane.
        let pts = [(0.0, 0.0), (2.0, 0.3), (2.4, 1.9), (-0.2, 1.5)];
        let shoelace: f64 = (0..4)
            .map(|i| {
                let (a, b) = (pts[i], pts[(i + 1) % 4]);
                a.0 * b.1 - b.0 * a.1
            })
            .sum::<f64>()
            / 2.0;
        assert!((area - shoelace).abs() < 1e-13);

        let tri = [x[0], x[1], x[2]];
        let p = triangle_point(&tri).unwrap();
        let f = deformation_gradient(&tri, &p.grad_n);
        assert!((f - Matrix3x2::from_columns(&[p.frame.e1, p.frame.e2])).norm() < 1e-14);
        assert!((p.area - 0.5 * (x[1] - x[0]).cross(&(x[2] - x[0])).norm()).abs() < 1e-14);
    }

    #[test]
    fn collinear_reference_nodes_are_a_typed_error() {
        let x = [Vector3::zeros(), Vector3::x(), Vector3::x() * 2.0];
        assert!(matches!(
            triangle_point(&x),
            Err(KinematicsError::DegenerateReference { .. })
        ));
    }
}
