//! Where an explicit step spends its time: a per-pass profile.
//!
//! [`crate::Explicit::enable_profile`] makes the driver read a clock
//! between its passes (element forces by kind, gather, the contact pass
//! and its phases, boundary conditions, the works, the checks, the energy
//! at outputs, the output itself) and add each interval to that pass.
//! Off by default: a run without a profile reads no clock in its steps.
//!
//! What it is for: finding what to make faster (`cargo xtask bench`
//! prints it for the hemisphere scene and a 200 × 200 blank). What it is
//! not: a benchmark. The clock is read about twenty times a step (≈ 20 ns
//! each for the wall clock, more for thread CPU time), which is noise on
//! a step of the hemisphere scene but not on a step of a ten-element
//! model; and with more than one thread each pass is timed on the driver's
//! thread, i.e. as wall time until the pass's last task ends. A profiled
//! step runs the truss and membrane passes one after the other, so each
//! has its own time; an unprofiled step runs them side by side (see
//! `shared::ForcePass::evaluate`), so on two threads it can be shorter
//! than the profile's sum says.
//!
//! The clock is a plain function, the wall clock unless the caller passes
//! another ([`ProfileClock`]): the benches pass the calling thread's CPU
//! time on a machine shared with other work.

use std::fmt::Write as _;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use drape_contact::ContactPhase;

/// A clock for the profile: a monotonic time since some fixed origin.
pub type ProfileClock = fn() -> Duration;

/// The wall clock, as time since its first reading in this process.
pub fn wall_clock() -> Duration {
    static ORIGIN: OnceLock<Instant> = OnceLock::new();
    ORIGIN.get_or_init(Instant::now).elapsed()
}

/// The passes of an explicit step, in the order a step runs them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pass {
    /// The stable Δt re-estimate (every `time_step_interval` steps).
    StableStep,
    /// Velocities to n+½ and positions to n+1 of the free components.
    Update,
    /// Prescribed components (before and after the contact pass).
    BoundaryConditions,
    /// The contact pass, all phases ([`ContactPhase`] splits it).
    Contact,
    /// The step's works (internal, external, damping, boundary, contact).
    Works,
    /// Gravity and nodal loads.
    Loads,
    /// Truss forces, with the dashpots of kinked yarns (one pass).
    Trusses,
    /// Membrane forces (resin, embedded fibres) and their new history.
    Membranes,
    /// Holding springs.
    Springs,
    /// Yarn bending (when the scene switches it on).
    Bending,
    /// Element slots summed per node.
    Gather,
    /// Finite values and the guard's kinematic checks.
    Checks,
    /// Kinetic and strain energy, the balance, at frames and guard checks.
    Energies,
    /// Checkpoints, frames and progress handed to the observer.
    Output,
}

impl Pass {
    /// Every pass, in step order.
    pub const ALL: [Pass; 14] = [
        Pass::StableStep,
        Pass::Update,
        Pass::BoundaryConditions,
        Pass::Contact,
        Pass::Works,
        Pass::Loads,
        Pass::Trusses,
        Pass::Membranes,
        Pass::Springs,
        Pass::Bending,
        Pass::Gather,
        Pass::Checks,
        Pass::Energies,
        Pass::Output,
    ];

    /// A short label.
    pub fn label(self) -> &'static str {
        match self {
            Pass::StableStep => "stable Δt estimate",
            Pass::Update => "velocity/position update",
            Pass::BoundaryConditions => "boundary conditions",
            Pass::Contact => "contact",
            Pass::Works => "works (energy sums)",
            Pass::Loads => "gravity and loads",
            Pass::Trusses => "element forces: trusses, dashpots",
            Pass::Membranes => "element forces: membranes",
            Pass::Springs => "element forces: springs",
            Pass::Bending => "element forces: yarn bending",
            Pass::Gather => "gather",
            Pass::Checks => "finite and guard checks",
            Pass::Energies => "energies at outputs",
            Pass::Output => "observer/output",
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

/// Accumulated pass times of the steps of one or more runs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepProfile {
    /// Steps profiled.
    pub steps: u64,
    /// Time of those steps, passes and what lies between them.
    pub total: Duration,
    passes: [Duration; Pass::ALL.len()],
    contact: [Duration; ContactPhase::ALL.len()],
}

impl StepProfile {
    /// Time spent in `pass`.
    pub fn time(&self, pass: Pass) -> Duration {
        self.passes[pass.index()]
    }

    /// Time spent in a phase of the contact pass (part of [`Pass::Contact`]).
    pub fn contact_time(&self, phase: ContactPhase) -> Duration {
        self.contact[phase as usize]
    }

    /// Time of the steps not in any pass (loop bookkeeping, the clock's own
    /// readings).
    pub fn unattributed(&self) -> Duration {
        self.total
            .saturating_sub(self.passes.iter().sum::<Duration>())
    }

    /// Mean time per step of `pass`.
    pub fn per_step(&self, pass: Pass) -> Duration {
        per_step(self.time(pass), self.steps)
    }

    /// Mean time per step.
    pub fn step_time(&self) -> Duration {
        per_step(self.total, self.steps)
    }

    /// `pass`'s share of the steps' time (0 with no steps).
    pub fn share(&self, pass: Pass) -> f64 {
        share(self.time(pass), self.total)
    }

    /// Adds another profile's times (e.g. of a resumed run).
    pub fn add(&mut self, other: &StepProfile) {
        self.steps += other.steps;
        self.total += other.total;
        for (a, b) in self.passes.iter_mut().zip(&other.passes) {
            *a += *b;
        }
        for (a, b) in self.contact.iter_mut().zip(&other.contact) {
            *a += *b;
        }
    }

    /// A table of the passes: µs per step and share of the step, with the
    /// contact phases indented under the contact pass; passes that took no
    /// time are left out.
    pub fn table(&self) -> String {
        let mut out = String::new();
        let us = |d: Duration| d.as_secs_f64() * 1e6 / self.steps.max(1) as f64;
        let _ = writeln!(out, "  {:<34} {:>10} {:>7}", "pass", "µs/step", "share");
        let mut row = |label: &str, d: Duration| {
            let _ = writeln!(
                out,
                "  {label:<34} {:>10.2} {:>6.1}%",
                us(d),
                100.0 * share(d, self.total)
            );
        };
        for pass in Pass::ALL {
            let d = self.time(pass);
            if d.is_zero() {
                continue;
            }
            row(pass.label(), d);
            if pass == Pass::Contact {
                let mut phases = Duration::ZERO;
                for phase in ContactPhase::ALL {
                    let p = self.contact_time(phase);
                    phases += p;
                    row(&format!("  {}", phase.label()), p);
                }
                row("  (rest of the contact pass)", d.saturating_sub(phases));
            }
        }
        row("unattributed", self.unattributed());
        row("step", self.total);
        out
    }
}

fn per_step(d: Duration, steps: u64) -> Duration {
    if steps == 0 {
        Duration::ZERO
    } else {
        d.div_f64(steps as f64)
    }
}

fn share(d: Duration, total: Duration) -> f64 {
    if total.is_zero() {
        0.0
    } else {
        d.as_secs_f64() / total.as_secs_f64()
    }
}

/// The driver's side: the clock, the last reading and the sums.
#[derive(Debug, Clone)]
pub(crate) struct Profiler {
    clock: ProfileClock,
    last: Duration,
    started: Duration,
    active: bool,
    pub(crate) profile: StepProfile,
}

impl Profiler {
    pub(crate) fn new(clock: ProfileClock) -> Self {
        Self {
            clock,
            last: Duration::ZERO,
            started: Duration::ZERO,
            active: false,
            profile: StepProfile::default(),
        }
    }

    pub(crate) fn clock(&self) -> ProfileClock {
        self.clock
    }

    /// Whether steps are being timed (between [`Self::begin`] and
    /// [`Self::end`]).
    pub(crate) fn is_active(&self) -> bool {
        self.active
    }

    /// Starts timing steps: laps count from now.
    pub(crate) fn begin(&mut self) {
        self.last = (self.clock)();
        self.started = self.last;
        self.active = true;
    }

    /// Charges the time since the last lap to `pass`.
    #[inline]
    pub(crate) fn lap(&mut self, pass: Pass) {
        if self.active {
            let now = (self.clock)();
            self.profile.passes[pass.index()] += now.saturating_sub(self.last);
            self.last = now;
        }
    }

    /// Stops timing after `steps` steps, adding the contact phases' times.
    pub(crate) fn end(&mut self, steps: u64, contact: Option<[Duration; ContactPhase::ALL.len()]>) {
        if self.active {
            self.active = false;
            self.profile.steps += steps;
            self.profile.total += (self.clock)().saturating_sub(self.started);
            if let Some(phases) = contact {
                for (a, b) in self.profile.contact.iter_mut().zip(phases) {
                    *a += b;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_add_up_and_inactive_laps_are_not_counted() {
        let mut p = Profiler::new(wall_clock);
        p.lap(Pass::Membranes);
        assert_eq!(p.profile.time(Pass::Membranes), Duration::ZERO);
        p.begin();
        let mut x = 1.0f64;
        for _ in 0..100_000 {
            x = std::hint::black_box(x.sqrt() + 1.0);
        }
        p.lap(Pass::Membranes);
        p.lap(Pass::Gather);
        p.end(1, None);
        let prof = p.profile;
        assert_eq!(prof.steps, 1);
        assert!(prof.time(Pass::Membranes) > Duration::ZERO);
        let sum: Duration = Pass::ALL.iter().map(|&q| prof.time(q)).sum();
        assert!(sum <= prof.total);
        let shares: f64 = Pass::ALL.iter().map(|&q| prof.share(q)).sum();
        assert!(shares <= 1.0 + 1e-12 && shares > 0.0);
        assert!(prof.table().contains("element forces: membranes"));
    }
}
