//! How a run ends: its summary, or why it stopped early.

use drape_contact::ContactFault;
use drape_elements::ElementError;

use crate::Energies;

/// Why a run stopped early.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunError {
    /// An element collapsed or inverted.
    #[error("step {step}, t = {time:.6e} s: {batch} {error}")]
    Element {
        /// The step that failed.
        step: u64,
        /// Its time.
        time: f64,
        /// Which batch kind and index.
        batch: String,
        /// The element and what happened.
        error: ElementError,
    },
    /// A NaN or infinite value appeared.
    #[error("step {step}, t = {time:.6e} s: non-finite {what} at node {node}")]
    NonFinite {
        /// The step that failed.
        step: u64,
        /// Its time.
        time: f64,
        /// The node.
        node: usize,
        /// What was not finite.
        what: &'static str,
    },
    /// The energy balance drifted beyond the allowed bound.
    #[error(
        "step {step}, t = {time:.6e} s: energy balance error {relative:.3e} exceeds {bound:.3e} of the largest energy"
    )]
    EnergyBalance {
        /// The step.
        step: u64,
        /// Its time.
        time: f64,
        /// |error|/largest energy.
        relative: f64,
        /// The bound.
        bound: f64,
    },
    /// The contact guard refused a step: a node inside a tool by more than
    /// the step can explain (see [`ContactFault`]).
    #[error("step {step}, t = {time:.6e} s: contact fault: {fault}")]
    ContactFault {
        /// The step that failed.
        step: u64,
        /// Its time.
        time: f64,
        /// The node, the tool, the gap and why.
        fault: ContactFault,
    },
    /// The settings or the model cannot run.
    #[error("cannot run: {0}")]
    Setup(String),
}

/// What a finished run reports.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSummary {
    /// Steps taken in this run.
    pub steps: u64,
    /// Smallest and largest Δt used.
    pub dt_range: (f64, f64),
    /// Mass added by mass scaling (t).
    pub added_mass: f64,
    /// Total mass after scaling (t).
    pub total_mass: f64,
    /// Final energies.
    pub energy: Energies,
    /// Whether an observer asked to stop before the end.
    pub stopped: bool,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
    /// Threads in rayon's pool.
    pub threads: usize,
}
