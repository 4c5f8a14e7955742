//! How a run ends: its summary, or why it stopped early.

use drape_contact::ContactFault;
use drape_elements::ElementError;

use crate::Energies;
use crate::guard::Instability;

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
    /// The instability guard found the run diverging ([`crate::guard`]).
    #[error("step {step}, t = {time:.6e} s: stopped by the instability guard: {what}")]
    Unstable {
        /// The step.
        step: u64,
        /// Its time.
        time: f64,
        /// What the guard found.
        what: Instability,
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

impl RunError {
    /// The step and time at which the run failed (none for a run that
    /// could not start).
    pub fn step_and_time(&self) -> Option<(u64, f64)> {
        match self {
            Self::Element { step, time, .. }
            | Self::NonFinite { step, time, .. }
            | Self::Unstable { step, time, .. }
            | Self::ContactFault { step, time, .. } => Some((*step, *time)),
            Self::Setup(_) => None,
        }
    }
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
    /// What the run found doubtful but not wrong enough to stop (a tool
    /// that never touched the blank, a forced step above the deformed
    /// mesh's estimate…); also [`crate::Explicit::warnings`].
    pub warnings: Vec<String>,
}
