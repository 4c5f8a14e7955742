//! What a driver tells the outside world while it runs: frames, progress,
//! checkpoints; and how the outside world asks it to stop.

use drape_contact::ContactView;
use drape_model::{Model, State};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::Energies;

/// One output frame.
pub struct Frame<'a> {
    /// 0 for the initial state.
    pub index: usize,
    /// The model.
    pub model: &'a Model,
    /// The state at the frame.
    pub state: &'a State,
    /// The energies there.
    pub energy: &'a Energies,
    /// Reaction forces at the constrained nodes (zero elsewhere), N.
    pub reactions: &'a [Vector3<f64>],
    /// The contact pass (forces, statuses, tools' states), if there are tools.
    pub contact: Option<ContactView<'a>>,
}

/// Progress of a run, for an observer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Completed steps.
    pub step: u64,
    /// Simulated time.
    pub time: f64,
    /// Time to reach.
    pub end_time: f64,
    /// Current Δt (the explicit step, or the implicit increment).
    pub dt: f64,
    /// What the last implicit increment did (None for explicit steps).
    pub increment: Option<IncrementReport>,
}

/// One implicit increment, as the progress line shows it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct IncrementReport {
    /// Newton iterations of the converged attempt.
    pub newton: usize,
    /// Iterations of its condensed contact solves (each one solve with the
    /// factors).
    pub contact_iterations: usize,
    /// Attempts cut back before it converged.
    pub cutbacks: usize,
    /// Normal contact rows that entered or left the active set over its
    /// Newton iterations (both solvers).
    pub active_changes: usize,
    /// Factorisations of the converged attempt.
    pub factorisations: usize,
    /// Contacts pressing at its end.
    pub active: usize,
    /// Of which sticking.
    pub stick: usize,
    /// Of which slipping.
    pub slip: usize,
}

/// An implicit attempt that failed and was cut back: where, how large,
/// and why (the reason's name as in [`crate::CutbackReasons`], the
/// message as a failed run would report it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CutbackReport<'a> {
    /// The increment being attempted (completed increments + 1).
    pub step: u64,
    /// Time at the start of the increment (s).
    pub time: f64,
    /// The increment that failed (s); the next attempt takes a quarter.
    pub increment: f64,
    /// `friction_chatter`, `newton_limit`, `element_failure`,
    /// `not_finite`, `tangent_failure`, `contact_indefinite`,
    /// `contact_not_converged` or `diverged`.
    pub reason: &'static str,
    /// What failed: residual, node, correction, penetration, friction
    /// states changed…
    pub message: &'a str,
}

/// What an observer asks of the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    /// Go on.
    Continue,
    /// Stop after this step (the state stays consistent).
    Stop,
}

/// Receives frames and progress from a run.
pub trait Observer {
    /// An output frame.
    fn frame(&mut self, _frame: &Frame<'_>) {}
    /// Called every few steps; return [`Control::Stop`] to stop.
    fn progress(&mut self, _progress: &Progress) -> Control {
        Control::Continue
    }
    /// Called every `checkpoint_every` steps (or increments) with what a
    /// restart needs ([`crate::Explicit::resume_from`],
    /// [`crate::Implicit::resume_from`]).
    fn checkpoint(&mut self, _state: &State, _driver: &DriverState) {}
    /// An implicit attempt failed and its increment is cut back.
    fn cutback(&mut self, _cutback: &CutbackReport<'_>) {}
}

/// What the driver carries from step to step beside the [`State`]: with
/// both, a run continues exactly as if it had never stopped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DriverState {
    /// The current stable step.
    pub dt: f64,
    /// The last step taken.
    pub dt_prev: f64,
    /// The works accumulated so far (to the last half step).
    pub energy: Energies,
    /// Kinetic energy at the start of the run.
    pub kinetic0: f64,
    /// The tools' displacements and velocities.
    pub tools: Vec<drape_contact::ToolState>,
    /// Friction dissipated so far.
    pub friction_dissipation: f64,
    /// What the implicit driver carries besides (None for explicit runs).
    #[serde(default)]
    pub implicit: Option<ImplicitCarry>,
    /// The explicit driver's confined yarns' clearances (mm) per truss
    /// batch, as the last contact pass left them (f64::MAX: no wall);
    /// empty where no yarn is confined.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub truss_clearance: Vec<Vec<f64>>,
    /// The explicit driver's ply contact between steps (warm starts, broad
    /// phase, slip and peaks); None without a stack.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plies: Option<drape_contact::PlyCarry>,
}

/// The implicit driver's carried state: accelerations (the Bossak scheme
/// needs aₙ), the tools' accelerations, the contacts and their forces.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImplicitCarry {
    /// Nodal accelerations aₙ (mm/s²).
    pub acceleration: Vec<Vector3<f64>>,
    /// Each tool's acceleration along its axis (mm/s²).
    pub tool_acceleration: Vec<f64>,
    /// The contacts of the last increment, with multipliers and friction
    /// states.
    pub contacts: Vec<drape_contact::CarriedPair>,
    /// Contact force per node at the last increment (N).
    pub contact_force: Vec<Vector3<f64>>,
}

/// An observer that does nothing.
pub struct NoObserver;
impl Observer for NoObserver {}
