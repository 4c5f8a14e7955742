//! # drape-elements
//!
//! The bi-component fabric element of SPEC §2 and §5, as batches of one
//! element type each:
//!
//! - [`TrussBatch`]: two-node trusses carrying one yarn family along a
//!   fibre-aligned mesh edge (the paper's representation), N = A₀·τ/λ.
//! - [`MembraneBatch`] (triangles: 3 nodes, 1 point; quads: 4 nodes, 2×2
//!   Gauss): the resin membrane, updated in the
//!   Green–Naghdi frame with history per integration point, optionally with
//!   both yarn families *embedded* (their stress added at each point).
//! - [`SpringBatch`]: node-to-anchor holding springs with a force–extension
//!   table (the paper's nonlinear springs).
//! - [`BendingBatch`] (optional, beyond the paper): yarn bending as a
//!   discrete elastica along the mesh's yarn lines, three nodes per triplet.
//!
//! Every batch gives the internal force, the tangent stiffness (material +
//! geometric), the stable time step, the strain energy and output fields.
//!
//! What it is not: no assembly, no mass, no time stepping (`drape-model`,
//! `drape-time`). A batch reads the global position array by node index and
//! writes each element's nodal forces into its own *slots* (N per element,
//! in element order); the caller gathers slots per node in a fixed order,
//! which makes a parallel force pass lock-free and independent of the
//! thread count.
//!
//! Hot-loop design: reference data (∂N/∂X, areas, fibre directions, L₀, A₀)
//! are computed once in the constructors; history lives in flat `f64`
//! arrays read from one buffer and written to another, so an evaluation
//! never allocates and a trial state (a Newton iteration, a finite
//! difference) never disturbs the committed one; the explicit step, which
//! never goes back, advances it in place instead
//! ([`MembraneBatch::forces_in_place`], one array streamed instead of two). The explicit force
//! passes of trusses and resin-only quads run four elements at a time on
//! SIMD lanes (`truss_lanes`, `quad_lanes`), with the scalar element as
//! the reference: same operations in the same order, equal bit for bit.
//!
//! ```
//! use drape_constitutive::Material;
//! use drape_elements::{FabricSection, MembraneBatch, Vector3};
//!
//! let glass = Material::preset("glass-serge-4x3").unwrap();
//! let x = vec![
//!     Vector3::new(0.0, 0.0, 0.0),
//!     Vector3::new(10.0, 0.0, 0.0),
//!     Vector3::new(10.0, 10.0, 0.0),
//!     Vector3::new(0.0, 10.0, 0.0),
//! ];
//! // One quad, fibres at 0/90 embedded in the resin.
//! let quads =
//!     MembraneBatch::quads(FabricSection::new(glass, true), &x, vec![[0, 1, 2, 3]], &[Vector3::x()])
//!         .unwrap();
//! let history = quads.initial_history();
//! let mut next = history.clone();
//! let mut slots = vec![Vector3::zeros(); 4];
//! // Stretch the quad by 1 % along x.
//! let moved: Vec<_> = x.iter().map(|p| Vector3::new(1.01 * p.x, p.y, p.z)).collect();
//! quads.forces_into(&moved, &history, &mut next, 1e-4, &mut slots).unwrap();
//! assert!(slots[1].x > 0.0 && slots[0].x < 0.0);
//! ```

mod bending;
mod lanes;
mod membrane;
mod quad_lanes;
mod spring;
mod truss;
mod truss_lanes;

pub use bending::{BendingBatch, YarnTriplet, yarn_triplets};
pub use drape_kinematics::{Degeneracy, KinematicsError, Matrix2, Matrix3x2, Vector2, Vector3};
pub use membrane::{
    ElementHistory, FabricSection, MembraneBatch, MembraneOutput, MembraneShape, MembraneTangent,
};
pub use spring::{ForceTable, ForceTableError, SpringBatch};
pub use truss::{TrussBatch, TrussOutput};

/// An element that could not be evaluated.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("element {element} (integration point {point}): {cause}")]
pub struct ElementError {
    /// Index of the element in its batch.
    pub element: usize,
    /// Integration point (0 for trusses and triangles).
    pub point: usize,
    /// What the kinematics found.
    pub cause: KinematicsError,
}

/// Reduces a parallel pass to the error of the lowest failing element, so
/// that the diagnosis does not depend on the thread count.
pub(crate) fn lowest_error<I>(results: I) -> Result<(), ElementError>
where
    I: rayon::iter::ParallelIterator<Item = Result<(), ElementError>>,
{
    use rayon::iter::ParallelIterator;
    results
        .map(Result::err)
        .reduce(
            || None,
            |a, b| match (a, b) {
                (Some(a), Some(b)) => Some(if a.element <= b.element { a } else { b }),
                (a, b) => a.or(b),
            },
        )
        .map_or(Ok(()), Err)
}

/// Elements per rayon task: below this, splitting costs more than it saves.
pub(crate) const MIN_CHUNK: usize = 256;

/// Trusses per rayon task of the truss pass. A truss costs about a seventh
/// of a quad (≈ 160 instructions on the lanes against ≈ 1 100), so its
/// tasks are four times as long in elements as [`MIN_CHUNK`]; with 256 a
/// task was ≈ 40 k instructions, about what waking a second thread costs,
/// and the small scenes ran no faster on two threads than on one.
pub(crate) const TRUSS_PIECE: usize = 1024;

#[cfg(test)]
pub(crate) mod test_support {
    use nalgebra::{DMatrix, Rotation3, Vector3};

    /// A rotation that depends only on `seed`.
    pub fn random_rotation(seed: u64) -> nalgebra::Matrix3<f64> {
        let s = seed as f64;
        *Rotation3::from_euler_angles(0.7 + 1.3 * s, -0.4 + 0.9 * s, 2.1 * s).matrix()
    }

    /// Asserts that `k` equals the central difference of `force` (the
    /// element's nodal forces, in node order) with respect to the positions
    /// of `nodes`, to 1e-6 relative to the largest entry of `k`.
    pub fn assert_tangent_matches<F>(
        k: &DMatrix<f64>,
        x: &[Vector3<f64>],
        force: F,
        nodes: &[usize],
    ) where
        F: Fn(&[Vector3<f64>]) -> Vec<Vector3<f64>>,
    {
        // A slack element has K = 0; its finite difference must then vanish too.
        let scale = k.amax();
        let size = x.iter().map(|p| p.norm()).fold(1.0, f64::max);
        let h = 1e-6 * size;
        let mut worst = 0.0f64;
        for (b, &node) in nodes.iter().enumerate() {
            for i in 0..3 {
                let mut xp = x.to_vec();
                let mut xm = x.to_vec();
                xp[node][i] += h;
                xm[node][i] -= h;
                let (fp, fm) = (force(&xp), force(&xm));
                for a in 0..nodes.len() {
                    for j in 0..3 {
                        let fd = (fp[a][j] - fm[a][j]) / (2.0 * h);
                        worst = worst.max((fd - k[(3 * a + j, 3 * b + i)]).abs());
                    }
                }
            }
        }
        assert!(
            worst <= 1e-6 * scale,
            "tangent differs from finite differences by {worst:e} (scale {scale:e})"
        );
    }
}
