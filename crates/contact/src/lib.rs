//! # drape-contact
//!
//! Rigid tools and frictional contact with the fabric (SPEC §6):
//!
//! - [`Surface`]: plane, sphere, surface of revolution from a profile of
//!   line and arc segments in (r, z) (a punch with its shank, a die with its
//!   opening and fillet, a blank-holder ring). Each answers the closest
//!   point, the outward normal and the signed gap of a point, and a bounding
//!   box for the broad phase. A triangle mesh ([`MeshSurface`], through
//!   parry3d-f64) covers tools from CAD; [`read_stl`] and [`read_obj`] load
//!   its vertices and triangles.
//! - [`Tool`]: a surface, a [`ToolMotion`] (fixed, a prescribed displacement
//!   along an axis with an [`Amplitude`], or a force along an axis on a
//!   rigid body free in that one direction, like a blank holder) and a
//!   Coulomb friction coefficient.
//! - [`ExplicitContact`]: the contact pass of explicit central differences:
//!   a bounding-box broad phase with a margin, forward-increment Lagrange
//!   multipliers for the normal constraints (closed form per node when
//!   uncoupled, projected preconditioned CG when coupled) and Coulomb
//!   friction by return mapping, with per-node force, status and tool; and
//!   a guard that refuses a step whose penetration the step cannot explain
//!   ([`ContactFault`]).
//!
//! What it is not: no elements and no time loop; the explicit driver in
//! `drape-time` calls [`ExplicitContact::enforce`] between its predictor and
//! its force pass.
//!
//! ```
//! use drape_contact::{ContactSettings, ExplicitContact, Surface, Tool, ToolMotion};
//! use nalgebra::Vector3;
//!
//! // A floor at z = 0 and one node of mass 1e-6 t predicted 0.01 mm into it.
//! let floor = Tool {
//!     name: "floor".into(),
//!     surface: Surface::plane(Vector3::zeros(), Vector3::z()).unwrap(),
//!     motion: ToolMotion::Fixed,
//!     friction: 0.0,
//! };
//! let settings = ContactSettings { offset: 0.1, ..ContactSettings::default() };
//! let mut contact = ExplicitContact::new(vec![floor], 1, settings);
//! let mut x = vec![Vector3::new(0.0, 0.0, 0.09)];
//! let mut v = vec![Vector3::new(0.0, 0.0, -10.0)];
//! contact.enforce(&mut x, &mut v, &[1e-6], &[true], 1e-3, 1e-3).unwrap();
//! assert!((x[0].z - 0.1).abs() < 1e-15); // back at half a thickness
//! assert!((contact.force[0].z - 1e-6 * 0.01 / 1e-6).abs() < 1e-9); // λ = m·|g|/Δt²
//! ```

mod explicit;
mod implicit;
mod mesh;
mod mesh_file;
mod mesh_near;
mod mesh_repair;
mod phases;
mod plies;
mod rim;
mod surface;
mod tool;
mod view;

pub use explicit::{
    ContactFault, ContactSettings, ContactStatus, ContactStep, ExplicitContact, FaultKind, Nearest,
    StepTimes, TOUCHING,
};
pub use implicit::{
    CarriedPair, Friction, ImplicitContact, ImplicitContactSettings, Increment, REGULARISATION,
    SLOTS_PER_PAIR, STICK_OVER_INERTIA, SolveError, SolveStats, SystemRow,
};
pub use mesh::{MeshError, MeshSurface};
pub use mesh_file::{MeshBuffers, MeshFileError, read_obj, read_stl};
pub use mesh_repair::{RepairError, RepairOptions, RepairReport, repair};
pub use phases::ContactPhase;
pub use plies::{
    DrivenTool, FaceBend, PlyCarry, PlyContact, PlyInterface, PlyLayer, PlyOverlap, PlyStep,
    PlyTotals, Support, ToolFriction,
};
pub use rim::{RimError, Sides, ToolPlace};
pub use surface::{Aabb, ProfileSegment, Projection, Surface, SurfaceError};
pub use tool::{Amplitude, Tool, ToolMotion, ToolState};
pub use view::ContactView;
