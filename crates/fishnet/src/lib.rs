//! # drape-fishnet
//!
//! Kinematic draping: where a woven ply goes on a mould and how much it
//! shears, from geometry alone, in milliseconds. This is the pin-jointed
//! net (fishnet) model of Mack and Taylor (1956) that kinematic draping
//! tools use: the yarns are inextensible, free to turn at their crossings
//! (no shear stiffness), and lie on the mould.
//!
//! - [`NetSpec`]: the flat blank (a rectangle), the seed point on it, the
//!   warp angle, the yarn spacing, the direction in which the blank meets
//!   the mould, and optionally the two generator curves.
//! - [`Net::drape`]: the net on a [`drape_contact::Surface`] (plane,
//!   sphere, surface of revolution, triangle mesh), through the same
//!   closest-point query [`Surface::project`](drape_contact::Surface::project)
//!   that contact uses, so a mould behaves here as it does in a forming run.
//! - [`NetCell`]: per cell, the shear angle, the fibre directions and the
//!   area; [`Net::shear_at`] and [`Net::position_at`] read the net at any
//!   flat point of the blank (to compare it with a mechanical result).
//! - [`NetResults`] ([`Net::results`]): the draped net as drape's model
//!   types (a [`drape_model::Model`] of quads on the flat net, a
//!   [`drape_model::State`] on the mould, [`drape_model::ElementFields`]
//!   and [`drape_model::Measures`]), so that drape-io writes the same
//!   results folder as for a forming run.
//!
//! What it is not: no forces, no friction, no time. The net knows nothing
//! of the fabric's shear stiffness or of how the blank is held, so its
//! answer is the one a forming process reaches only where the fabric is
//! pressed onto the mould with negligible resistance to shear; a
//! mechanical run (`drape run`) says how far a real process is from it.
//!
//! ## The construction
//!
//! Crossing (i, j) of the lattice sits, before draping, at
//! `seed + i·s_w·w + j·s_f·f` in the blank's plane (w, f the flat warp and
//! weft, s_w, s_f the cell sides along them).
//!
//! 1. **Seed.** The crossing (0, 0) is the first point of the mould on the
//!    line through the flat seed along the draping direction (sphere
//!    tracing with the signed gap, which is a distance).
//! 2. **Generators.** From the seed the warp leaves along the flat warp
//!    projected on the tangent plane, the weft at right angles to it
//!    (unsheared at the seed). Each further crossing of a generator lies on
//!    the mould one segment (s_w or s_f) from the last, in the plane of the
//!    previous segment and the surface normal: a discrete geodesic, exact
//!    great circles on a sphere. A generator curve given by the user
//!    replaces "straight on" by "towards the curve".
//! 3. **Cells.** Outward from the generators, quadrant by quadrant, the
//!    crossing X of a cell with known corners A (along the warp from X),
//!    B (along the weft) and C (opposite) lies where the spheres
//!    |X − A| = s_w and |X − B| = s_f meet the mould. The spheres meet on a
//!    circle; on it, the signed gap g(φ) of the point at angle φ (φ = 0 the
//!    flat parallelogram's corner A + B − C) has the derivative n·X′(φ)
//!    with n the projection's normal, and a safeguarded Newton iteration
//!    (bisection once bracketed) finds the root nearest the flat guess,
//!    to 1e-10 of the spacing, in three to five queries. This is the
//!    Newton–Raphson form of the sphere-intersection construction.
//! 4. **Stops.** Only the crossings the outline's cells need are built
//!    (cells whose flat centre lies in the blank). Where the circle does
//!    not meet the mould (its edge) or the cell would close with its
//!    yarns on one line (sheared to 90°: the net folds), the crossing has
//!    no place and neither have those built from it; their cells are left
//!    undraped and counted.
//! 5. **Shear.** A cell's warp direction is the mean of its two warp
//!    segments, its weft likewise; the shear angle is 90° less the angle
//!    between them (positive closing), the convention of drape's elements.
//!
//! ## The analytic net on a sphere
//!
//! A continuous net with unit yarn speeds has the first fundamental form
//! du² + 2 cos ω du dv + dv² (u, v the arc lengths along warp and weft, ω
//! the angle between them: a Chebyshev net). Its Christoffel symbols give
//! the geodesic curvature of a warp line (v = const) as −∂ω/∂u and of a
//! weft line as −∂ω/∂v, and its Gauss curvature as K = −ω_uv / sin ω.
//! With geodesic generators through the seed, ω does not change along
//! them, so ω(u, 0) = ω(0, v) = π/2 when they cross at right angles. On a
//! sphere of radius R, ω_uv = −sin ω / R² with these data has a solution
//! depending on z = uv/R² only: ω_u = f′·v/R², ω_uv = (f′ + z f″)/R², so
//! the shear γ = π/2 − ω solves
//!
//! (z γ′)′ = cos γ,  γ(0) = 0,  i.e. γ = z − z³/18 + …,
//!
//! an odd function: the shear depends on the product of the arc lengths
//! along the two generators, γ ≈ uv/R² when small, positive in the
//! quadrants where u and v have the same sign. The discrete net converges
//! to it at second order in the cell size (`tests/sphere.rs`; the
//! validation case `fishnet/chebyshev-sphere` of `cargo xtask validate`
//! measures the order).
//!
//! ```
//! use drape_contact::Surface;
//! use drape_fishnet::{Net, NetSpec};
//! use drape_model::blank::BlankFrame;
//! use nalgebra::Vector3;
//!
//! // A 200 × 200 mm 0/90 ply on a sphere of radius 100 whose top is under
//! // the blank's centre, 5 mm cells.
//! let sphere = Surface::sphere(Vector3::new(0.0, 0.0, -100.0), 100.0).unwrap();
//! let spec = NetSpec {
//!     outline: BlankFrame { center: Vector3::new(0.0, 0.0, 10.0), width: 200.0, height: 200.0 },
//!     seed: [0.0, 0.0],
//!     orientation_deg: 0.0,
//!     spacing: [5.0, 5.0],
//!     direction: -Vector3::z(),
//!     warp_curve: None,
//!     weft_curve: None,
//! };
//! let net = Net::drape(&sphere, &spec).unwrap();
//! assert_eq!(net.stats().draped_cells, 40 * 40);
//! // Next to a generator the net hardly shears (γ ≈ uv/R² = 0.013); it
//! // shears most on the diagonals, with the sign of i·j.
//! assert!(net.cell(0, 10).unwrap().shear.abs() < 0.02);
//! assert!(net.cell(15, 15).unwrap().shear > 0.3);
//! assert!(net.cell(-16, 15).unwrap().shear < -0.3);
//! ```

mod mould;
mod net;
mod results;

pub use net::{Net, NetCell, NetSpec, NetStats, NodeStatus};
pub use results::NetResults;

/// Why a net cannot be draped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FishnetError {
    /// A value of the specification is not allowed.
    #[error("{field}: {what}")]
    Invalid {
        /// The field of [`NetSpec`].
        field: &'static str,
        /// What is wrong.
        what: String,
    },
    /// The seed's line does not meet the mould.
    #[error(
        "the line through the seed ({:.6}, {:.6}, {:.6}) along the draping direction ({:.6}, {:.6}, {:.6}) does not meet the mould",
        point[0], point[1], point[2], direction[0], direction[1], direction[2]
    )]
    SeedMissesMould {
        /// The flat seed.
        point: [f64; 3],
        /// The draping direction.
        direction: [f64; 3],
    },
    /// The seed's line starts on the mould's back side.
    #[error(
        "the line through the seed ({:.6}, {:.6}, {:.6}) comes to the mould from its back (the side the fabric may not be on): check the draping direction",
        point[0], point[1], point[2]
    )]
    SeedBehindMould {
        /// The flat seed.
        point: [f64; 3],
    },
    /// The warp has no direction on the mould at the seed.
    #[error(
        "the warp (or a generator curve) is normal to the mould at the seed: it has no direction on the surface there"
    )]
    WarpNormalToMould,
    /// A generator curve misses the seed.
    #[error(
        "the {family} generator curve passes {distance:.6} mm from the seed crossing ({:.6}, {:.6}, {:.6}): it must pass through it (within half a cell)",
        seed[0], seed[1], seed[2]
    )]
    CurveOffSeed {
        /// `warp` or `weft`.
        family: &'static str,
        /// Closest distance (mm).
        distance: f64,
        /// The seed crossing on the mould.
        seed: [f64; 3],
    },
}
