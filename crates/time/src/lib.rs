//! # drape-time
//!
//! Time integration of a [`drape_model::Model`]. Today: the explicit
//! central-difference driver [`Explicit`] with lumped mass (what the paper
//! ran in Abaqus/Explicit): stable Δt from the elements with a safety
//! factor, optional selective mass scaling to a target Δt, optional
//! mass-proportional damping, prescribed motions with amplitudes, gravity,
//! an energy balance, and an [`Observer`] that receives frames and progress
//! and may ask the run to stop. No file formats live here.
//!
//! Element passes run in parallel with rayon; every node sums its element
//! slots in a fixed order, so positions are bit-identical for any number
//! of threads.
//!
//! A diverging run stops with a [`RunError`] that says the step, the time,
//! the element or node and what went wrong. Besides non-finite values and
//! failing elements, the [`guard`] stops a run whose nodes fly off, whose
//! energy balance breaks or that leaves the quasi-static range it declared;
//! the state passed in then holds the last output frame, which passed every
//! check.
//!
//! ```
//! use drape_constitutive::Material;
//! use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
//! use drape_model::{Amplitude, BoundaryCondition, Model, Motion};
//! use drape_time::{Explicit, ExplicitSettings, NoObserver};
//! use nalgebra::Vector3;
//!
//! // A 40 × 10 mm glass strip, clamped on the left, pulled 0.1 mm on the right.
//! let blank = RectangleBlank {
//!     width: 40.0, height: 10.0, center: Vector3::zeros(), orientation_deg: 0.0,
//!     element: ElementKind::Quad, meshing: Meshing::Cells([8, 2]),
//!     fibres: FibreRepresentation::Trusses,
//! };
//! let mut model = Model::from_blank(&blank, &Material::preset("glass-serge-4x3").unwrap()).unwrap();
//! model.boundary.push(BoundaryCondition::fixed(model.node_set("left").unwrap().to_vec()));
//! model.boundary.push(BoundaryCondition {
//!     nodes: model.node_set("right").unwrap().to_vec(),
//!     components: [true, true, true],
//!     motion: Motion::Displacement {
//!         value: Vector3::new(0.1, 0.0, 0.0),
//!         amplitude: Amplitude::SmoothStep { duration: 1e-3 },
//!     },
//! });
//! let mut state = model.initial_state();
//! let settings = ExplicitSettings { end_time: 1e-3, ..ExplicitSettings::default() };
//! let summary = Explicit::new(&model, settings).unwrap().run(&mut state, &mut NoObserver).unwrap();
//! assert!(summary.steps > 10);
//! assert!((state.x[model.node_set("right").unwrap()[0] as usize].x - 20.1).abs() < 1e-9);
//! ```

pub mod completion;
mod confinement;
mod energy;
mod error;
mod explicit;
pub mod guard;
mod implicit;
mod observer;
mod ordering;
mod ply_check;
pub mod profile;
pub mod round_off;
pub mod saddle;
pub mod scaling;
mod shared;
mod split;
pub mod tangent;

pub use energy::{Energies, NodeAtStep, next_contact_force, node_energy_terms};
pub use error::{CutbackReasons, ImplicitTotals, RunError, RunSummary};
pub use explicit::{Explicit, ExplicitSettings, StepInputs, step_length};
pub use guard::{Guard, GuardSettings, Instability};
pub use implicit::{ContactSolver, ELASTIC_SLIP, Implicit, ImplicitSettings, NewtonRecord};
pub use observer::{
    Control, CutbackReport, DriverState, Frame, ImplicitCarry, IncrementReport, NoObserver,
    Observer, Progress,
};
pub use ply_check::ply_overlap_tolerance;
pub use profile::{Pass, ProfileClock, StepProfile};
pub use shared::{
    PrescribedMotions, PressurePass, constrained_components, external_forces, strain_energy,
};
