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
    /// An implicit increment did not converge down to the smallest
    /// increment allowed.
    #[error(
        "increment {step}, t = {time:.6e} s: no convergence with an increment of {increment:.3e} s: {reason}"
    )]
    NoConvergence {
        /// The increment that failed (the state holds the one before).
        step: u64,
        /// Its start time.
        time: f64,
        /// The last size tried (s).
        increment: f64,
        /// What went wrong in the last attempt.
        reason: String,
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
    /// The run reached its end time with a node inside a tool deeper than
    /// the physical tolerance ([`crate::completion`]): not a formed state.
    #[error(
        "step {step}, t = {time:.6e} s: at the end node {node} is {depth:.4e} mm inside tool `{tool}` \
         ({count} node(s) deeper than the tolerance {tolerance:.3e} mm, the lesser of a tenth of the fabric's \
         thickness and a hundredth of the shortest element edge): the contact was not enforced; {advice}"
    )]
    Penetration {
        /// The last step.
        step: u64,
        /// Its time.
        time: f64,
        /// The deepest node.
        node: usize,
        /// The tool it is inside.
        tool: String,
        /// How deep (mm).
        depth: f64,
        /// The tolerance (mm).
        tolerance: f64,
        /// Nodes beyond the tolerance.
        count: usize,
        /// Which setting to change.
        advice: String,
    },
    /// A node of one ply of a laminate is inside its neighbour deeper than
    /// the physical tolerance ([`crate::ply_overlap_tolerance`]), found at
    /// an energy check or at the end: not a formed stack.
    #[error(
        "step {step}, t = {time:.6e} s: node {node} of ply `{ply}` at ({:.3}, {:.3}, {:.3}) mm \
         is {overlap:.4e} mm inside ply `{into}` (tolerance {tolerance:.3e} mm, the lesser of a \
         tenth of the thinnest ply's thickness and a hundredth of the shortest element edge): \
         the ply–ply contact did not keep the plies apart; {advice}",
        .at[0], .at[1], .at[2]
    )]
    PlyOverlap {
        /// The step of the check.
        step: u64,
        /// Its time.
        time: f64,
        /// How deep the node is (mm).
        overlap: f64,
        /// The tolerance (mm).
        tolerance: f64,
        /// The node's ply (boxed, as the names below, to keep the error
        /// small).
        ply: Box<str>,
        /// The ply it is inside.
        into: Box<str>,
        /// The node.
        node: usize,
        /// Where it is (mm).
        at: [f64; 3],
        /// What likely put it there and what to change
        /// (the faces' bend, where it explains the overlap).
        advice: Box<str>,
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
            | Self::NoConvergence { step, time, .. }
            | Self::ContactFault { step, time, .. }
            | Self::Penetration { step, time, .. }
            | Self::PlyOverlap { step, time, .. } => Some((*step, *time)),
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
    /// The implicit driver's totals (None for explicit runs).
    pub implicit: Option<ImplicitTotals>,
}

/// What an implicit run did, in total.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImplicitTotals {
    /// Newton iterations of converged increments.
    pub newton_iterations: u64,
    /// Newton iterations of attempts that were cut back.
    pub wasted_iterations: u64,
    /// Iterations of the condensed contact solves (one solve with the
    /// factors each).
    pub contact_iterations: u64,
    /// Numeric factorisations.
    pub factorisations: u64,
    /// Of which fell back to LDLᵀ (indefinite tangent).
    pub indefinite: u64,
    /// Of which had the resin's compressive stress terms scaled down
    /// because the exact tangent was indefinite (see
    /// [`crate::tangent::MembraneTangentChoice`]).
    pub compression_scaled: u64,
    /// Increments cut back.
    pub cutbacks: u64,
    /// The cutbacks by why the attempt failed.
    pub cutback_reasons: CutbackReasons,
    /// Seconds in numeric factorisations.
    pub factor_seconds: f64,
    /// Seconds in tangent assembly.
    pub assembly_seconds: f64,
    /// Seconds in the condensed contact solves (their solves with the
    /// factors included), or the active-set solves.
    pub contact_seconds: f64,
    /// Normal contact rows that entered or left the active set, over the
    /// converged and the cut attempts (active-set solver).
    pub active_set_changes: u64,
    /// The contact solver's name as the scene gives it (`condensed`,
    /// `active_set`).
    pub contact_solver: &'static str,
}

/// Why the implicit driver's attempts failed (each one cut the increment
/// to a quarter), counted by reason.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CutbackReasons {
    /// The Newton iteration limit was reached with friction states still
    /// changing in the last iteration: stick/slip chatter.
    pub friction_chatter: u64,
    /// The Newton iteration limit was reached with the friction states
    /// settled: slow convergence of the residual or the correction.
    pub newton_limit: u64,
    /// An element's law failed (an inverted element) at the predictor or at
    /// every step length of the line search.
    pub element_failure: u64,
    /// The residual was not finite.
    pub not_finite: u64,
    /// The tangent could not be assembled or had a zero pivot.
    pub tangent_failure: u64,
    /// The condensed contact solve met a direction of non-positive
    /// curvature (an indefinite tangent seen through the contact rows).
    pub contact_indefinite: u64,
    /// The condensed contact solve ran out of iterations.
    pub contact_not_converged: u64,
    /// Newton diverged: a correction longer than the model, and at least
    /// twice the last one.
    pub diverged: u64,
}

impl CutbackReasons {
    /// Their sum: every cutback has one reason.
    pub fn total(&self) -> u64 {
        self.friction_chatter
            + self.newton_limit
            + self.element_failure
            + self.not_finite
            + self.tangent_failure
            + self.contact_indefinite
            + self.contact_not_converged
            + self.diverged
    }
}
