//! Times of the contact pass's phases, for the explicit driver's per-pass
//! profile (`drape_time::StepProfile`). Off unless the driver asks
//! ([`crate::ExplicitContact::time_phases`]): a pass without a clock reads
//! none.

use std::time::Duration;

/// A phase of [`crate::ExplicitContact::enforce_step`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactPhase {
    /// Tools moved, last step's outputs cleared, candidate lists checked
    /// and rebuilt when something moved half the margin.
    BroadPhase,
    /// Each candidate node projected on its tool.
    Projection,
    /// The normal multipliers (closed form or the coupled solve) and their
    /// corrections.
    Multipliers,
    /// Coulomb friction.
    Friction,
    /// Contact between the plies of a laminate (normal and the friction
    /// solved with the tools'), in a stack only.
    Plies,
}

impl ContactPhase {
    /// Every phase, in the order of a pass.
    pub const ALL: [ContactPhase; 5] = [
        ContactPhase::BroadPhase,
        ContactPhase::Projection,
        ContactPhase::Multipliers,
        ContactPhase::Friction,
        ContactPhase::Plies,
    ];

    /// A short label.
    pub fn label(self) -> &'static str {
        match self {
            ContactPhase::BroadPhase => "broad phase",
            ContactPhase::Projection => "projection",
            ContactPhase::Multipliers => "multipliers",
            ContactPhase::Friction => "friction",
            ContactPhase::Plies => "ply–ply contact",
        }
    }
}

/// A clock and the phases' summed times.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PhaseTimer {
    pub(crate) clock: fn() -> Duration,
    pub(crate) last: Duration,
    pub(crate) times: [Duration; ContactPhase::ALL.len()],
}

impl PhaseTimer {
    pub(crate) fn start(timer: &mut Option<Self>) {
        if let Some(t) = timer {
            t.last = (t.clock)();
        }
    }

    pub(crate) fn lap(timer: &mut Option<Self>, phase: ContactPhase) {
        if let Some(t) = timer {
            let now = (t.clock)();
            t.times[phase as usize] += now.saturating_sub(t.last);
            t.last = now;
        }
    }
}
