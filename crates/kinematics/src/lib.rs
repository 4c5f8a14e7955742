//! # drape-kinematics
//!
//! The kinematics of a woven-fabric membrane in the co-rotational
//! (Green–Naghdi) frame, as used by drape's bi-component elements
//! (SPEC §3): the membrane deformation gradient **F** (3×2, from the
//! element's local reference plane to 3D space), the right Cauchy–Green
//! tensor **C = FᵀF**, the closed-form polar decomposition **F = R·U**, the
//! rotated strain increment **Δε̄** with the midpoint rule, the first
//! Piola stress **P = R·τ̄·U⁻¹** and nodal forces, fibre and truss stretch
//! **λ** with their current direction and log strain, and the shear angle
//! **γ** between the two fibre families.
//!
//! What it is not: no material law (that is `drape-constitutive`), no element
//! loops or history storage (that is `drape-elements`). Everything here is a
//! pure function on fixed-size nalgebra types; nothing allocates.
//!
//! A degenerate configuration (a membrane point without area, a
//! zero-length truss, a collapsed reference element) is a typed
//! [`KinematicsError`], never a NaN; a degenerate membrane point says what
//! it looks like ([`Degeneracy`]: principal stretches, over-stretched,
//! collapsed, and — judged by the element — folded or inverted).
//!
//! ```
//! use drape_kinematics::{polar_decomposition, rotated_strain_increment, Matrix2, Matrix3x2};
//!
//! // A membrane stretched by 10 % along its local x axis, then rotated 30° about z.
//! let (s, c) = 30f64.to_radians().sin_cos();
//! let f = Matrix3x2::new(1.1 * c, -s, 1.1 * s, c, 0.0, 0.0);
//! let polar = polar_decomposition(&f).unwrap();
//! assert!((polar.u - Matrix2::new(1.1, 0.0, 0.0, 1.0)).norm() < 1e-14);
//! assert!((polar.r * polar.u - f).norm() < 1e-14);
//!
//! // The strain increment from the undeformed state: sym((U − I)·((U + I)/2)⁻¹).
//! let d_eps = rotated_strain_increment(&Matrix2::identity(), &polar.u);
//! assert!((d_eps[(0, 0)] - 0.1 / 1.05).abs() < 1e-14);
//! ```
//!
//! Conventions: the reference local frame of a membrane point is an
//! orthonormal pair (e₁, e₂) in its reference tangent plane (see
//! [`reference`](mod@reference)); all 2×2 tensors (C, U, τ̄, Δε̄) are written in it. Shear
//! angles are in radians here; degrees are for input and output files only.

pub mod fibre;
pub mod membrane;
pub mod reference;

pub use fibre::{FibreKinematics, fibre_stretch, shear_angle, truss_stretch};
pub use membrane::{
    DEGENERATE_DET_C, Degeneracy, PolarDecomposition, add_nodal_forces, deformation_gradient,
    first_piola, polar_decomposition, right_cauchy_green, right_stretch, rotated_strain_increment,
};
pub use nalgebra::{Matrix2, Matrix3x2, Vector2, Vector3};
pub use reference::{LocalFrame, ReferencePoint, quad_point, triangle_point};

/// What can go wrong when measuring a deformation.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum KinematicsError {
    /// The membrane point has no area left for its size: det C/(tr C)² ≤
    /// 1e-14, so neither U⁻¹ nor R can be trusted. What it looks like is
    /// in the [`Degeneracy`].
    #[error("degenerate membrane: {0}")]
    DegenerateMembrane(Degeneracy),
    /// A truss or fibre has zero current length, so it has no direction.
    #[error("degenerate fibre: current length {length:e} is not positive")]
    DegenerateFibre {
        /// Current length (truss) or stretch (embedded fibre).
        length: f64,
    },
    /// The reference geometry has no area (collinear nodes) or zero length.
    #[error("degenerate reference element: size {size:e} is not positive")]
    DegenerateReference {
        /// Reference area (membrane) or length (truss).
        size: f64,
    },
    /// A coordinate or a deformation gradient entry is NaN or infinite.
    #[error("non-finite value in the {what}")]
    NonFinite {
        /// Which quantity carried it.
        what: &'static str,
    },
}
