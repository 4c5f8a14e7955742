//! # drape-constitutive
//!
//! The material laws of a woven prepreg (SPEC §4), written for the
//! co-rotational frame of `drape-kinematics`:
//!
//! - [`FibreLaw`]: the crimped yarn of the paper (eq. 8–9), hyperelastic in
//!   the log strain ε = ln λ: a soft start while the undulation straightens
//!   (crimp strain ε_sh), then the full modulus E_f; optional compression
//!   stiffness (default none: yarns buckle).
//! - [`ResinLaw`]: isotropic plane-stress hypo-elasticity updated in the
//!   Green–Naghdi frame, with an optional Prony relaxation of the in-plane
//!   shear (exact recursive update for piecewise-linear strain histories).
//! - [`ShearLocking`] (optional, beyond the paper): a non-linear in-plane
//!   shear law τ_s(γ) that stiffens past the locking angle, and its fit
//!   from a picture-frame curve.
//! - [`Material`]: a fabric (fibres + resin + thickness, fibre volume
//!   fraction, density), its validation with errors that name the field,
//!   serde (de)serialisation for scene files, and the paper's presets
//!   ([`Material::preset`]).
//!
//! What it is not: no kinematics (stretch, rotations: `drape-kinematics`),
//! no element integration or history storage (`drape-elements`). Laws are
//! plain data with pure methods; nothing allocates in an update.
//!
//! Units are the consistent set mm, N, MPa, t/mm³, s.
//!
//! ```
//! use drape_constitutive::Material;
//! use nalgebra::Matrix2;
//!
//! let carbon = Material::preset("carbon-prepreg-2x2").unwrap();
//! // A yarn at 1 % strain has straightened: its tangent is close to E_f.
//! let (tau, e_t) = carbon.fibre.stress_and_tangent(0.01);
//! assert!(e_t > 0.86 * carbon.fibre.modulus && tau > 0.0);
//!
//! // The resin takes an in-plane shear increment Δε̄₁₂ = 0.001 in 1 ms.
//! let mut tau_bar = Matrix2::zeros();
//! let mut history = vec![0.0; carbon.resin.history_len()];
//! let d_eps = Matrix2::new(0.0, 0.001, 0.001, 0.0);
//! carbon.resin.update_stress(&mut tau_bar, &mut history, &d_eps, 1e-3);
//! let g0 = carbon.resin.shear_modulus();
//! assert!(tau_bar[(0, 1)] > 0.0 && tau_bar[(0, 1)] < g0 * 0.002);
//! ```

mod fibre;
mod locking;
mod material;
mod resin;

pub use fibre::{CONFINED_SHORTENING, FibreLaw};
pub use locking::{FitError, ShearLocking};
pub use material::{Material, MaterialError, PRESET_NAMES};
pub use resin::{PronyTerm, ResinLaw};
