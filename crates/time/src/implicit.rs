//! The implicit driver (SPEC §7, "Implicit"): Newton–Raphson per increment
//! with inertia kept, a sparse tangent factorised by faer, and the paper's
//! condensed multiplier solve for contact.
//!
//! **Integrator: Bossak–Newmark (WBZ-α).** The equation of an increment is
//! M·((1 − α_m)·a_{n+1} + α_m·aₙ) + f_int(x_{n+1}) + c·M·v_{n+1} =
//! f_ext(t_{n+1}) + f_contact, with Newmark's β = ¼(1 − α_m)², γ = ½ − α_m
//! and α_m = (ρ∞ − 1)/(ρ∞ + 1) from the spectral radius at infinity ρ∞
//! (default 0). Why this one: a flat membrane has no out-of-plane stiffness,
//! so inertia must stay in (statics is singular); forming is quasi-static,
//! so the scheme must kill the high frequencies a large increment cannot
//! follow (ρ∞ = 0 annihilates them in one increment, like backward Euler)
//! yet stay second-order accurate, so that a slow dynamic run does not
//! drift: a blank sliding down an incline moves exactly ½·a·t², which
//! backward Euler misses by a relative h/t. Forces are taken at t_{n+1}
//! only (α_f = 0), so history-dependent elements and contact need no
//! force averaging. The run starts from the consistent acceleration
//! M·a₀ = f₀ + contact (a touching node gets its reaction and friction
//! first), without which the velocity would drift by O(h·Δa₀).
//!
//! **Newton.** Predictor x_{n+1} = xₙ + h·vₙ (see [`predictor`]), prescribed
//! components at their values; then iterations with the tangent K̂ =
//! ((1 − α_m)/(βh²) + c·γ/(βh))·M + sym(∂f_int/∂x) (see
//! [`crate::tangent`]), factorised each iteration with the symbolic
//! analysis reused. Converged when, together: the largest residual
//! component is within `force_tolerance` times the force scale (the largest
//! element nodal force, external, inertial or contact force), the last
//! correction (in Newton's quadratic range the next one, estimated from
//! the residual's contraction: see [`QUADRATIC`]) within
//! `displacement_tolerance` times the increment's largest displacement, no node deeper than `gap_tolerance` in a tool nor a
//! sticking one off its (regularised) stick law by more, no friction
//! state changed, and every force-driven tool balanced; the first two
//! also pass at the round-off floor ([`crate::round_off`]), which a small
//! increment's inertia term would otherwise put above the tolerances. At
//! the end time the blank must be outside every tool
//! ([`crate::completion`]), whatever `gap_tolerance` let through. Stick is a stiff
//! tangential spring by default ([`ELASTIC_SLIP`]), which makes the
//! friction force continuous in the slip, so pairs at the edge of the
//! friction cone settle instead of cycling between stick and slip. With
//! a rigid stick (`elastic_slip = 0`), after a few iterations a slipping
//! pair needs a reversal beyond a small band to stick again (see
//! `SETTLE`). A step that more than doubles the residual
//! (or inverts an element) is halved, up to four times (line search),
//! unless friction states changed with it; from the third iteration on, a
//! step whose residual is not below half the one two iterations back is
//! halved too (contact or friction states cycling, see `CYCLE`). The
//! contact solve is preconditioned with K̂'s nodal blocks at the contact
//! rows' nodes.
//!
//! **Increments.** Grow by 1.5 after an easy increment (≤ 6 iterations
//! besides those that followed a change of friction states), shrink by
//! 0.75 after a hard one (≥ 12); cut to a quarter when Newton fails
//! (too many iterations, an element inverted at every step length, a zero
//! pivot, the contact solve not converging, contact states chattering);
//! below `min_increment` the run stops with the diagnosis. Increments end
//! on output frames and on the end time.
//!
//! **Energy.** Works by the trapezoidal rule over each increment; what the
//! integrator removes, D = Δx·M·ā − ΔE_kin − ½·Δx·(F_{n+1} − Fₙ), is
//! reported as numerical dissipation, so the balance error is the
//! equilibrium residual's work. That work is also summed on its own
//! ([`Energies::residual_work`]): the two agree to round-off where every
//! force's work is in the balance, which is what an implicit balance can
//! check; its size is the Newton tolerance's and the increments'.
//!
//! **Contact solvers** (`contact_solver`, see [`ContactSolver`]): the
//! paper's condensed multiplier solve on the factorised K̂ (the reference),
//! or the active-set saddle-point system ([`crate::saddle`]), one
//! factorisation per Newton iteration; both in `implicit/contact_step.rs`.
//!
//! Not here: the tangent's assembly ([`crate::tangent`]), the contact solve
//! (`drape_contact::ImplicitContact`).

use std::time::Instant;

use drape_contact::{ImplicitContact, ImplicitContactSettings, Increment, SolveError, SystemRow};
use drape_model::{Model, State};
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use crate::energy::{chunked_sum, chunked_sums};
use crate::guard::{self, Guard, GuardSettings};
use crate::round_off::RoundOffFloor;
use crate::saddle::{SaddleError, SaddleSystem};
use crate::shared::{self, Constraints, ForcePass, PressurePass};
use crate::tangent::{MembraneTangentChoice, SparseTangent};
mod contact_step;
mod newton;
mod trace;
pub use contact_step::ContactSolver;

use crate::{
    Control, CutbackReasons, CutbackReport, DriverState, Energies, Frame, ImplicitCarry,
    ImplicitTotals, IncrementReport, Observer, Progress, RunError, RunSummary,
};

/// Newton iterations of an easy increment (the next one grows) and of a
/// hard one (the next one shrinks), not counting those that followed a
/// change of friction states: stick and slip settle pair by pair, which
/// is no reason to shrink.
const EASY: usize = 6;
const HARD: usize = 12;

/// Newton iterations of an increment after which a slipping pair needs a
/// reversal of [`SETTLED_REVERSAL`] times the increment's largest
/// displacement to stick again. Measured on the hemisphere 10×10 (0/90,
/// μ = 0.1, max increment 0.05 s): 628 increments, 7 574 Newton
/// iterations and 1 791 more in 124 cutbacks, instead of 721, 8 675 and
/// 2 479 in 148; maximum shear 19.14° (19.15°), draw-ins unchanged.
/// Sticking again from where the pair is (rather than from tₙ) cut the
/// run further (4 783 iterations, 88 cutbacks) but let slipping nodes
/// stick: the capstan and pinching cases failed with it.
const SETTLE: usize = 4;
const SETTLED_REVERSAL: f64 = 1e-4;

/// A Newton iteration (from the third on) whose residual (over the force
/// scale) is not below this fraction of the one two iterations back is
/// taken as a cycle, and its step is halved. On the hemisphere 40 × 40
/// past half the stroke, where the skirt folds over the dome, attempts
/// failed on period-2 and period-3 cycles: the same residuals (to three
/// digits) recurring with contacts opening and closing, or 100+ pairs
/// switching between stick and slip in turn, until the iteration limit.
/// Halving the step, resumed from t = 0.5 s for 100 s of CPU (1 thread):
/// t = 0.566 s instead of 0.534 s, 184 increments with 21 cutbacks
/// instead of 240 with 48. On 10 × 10 (0/90 and ±45) the increments are
/// the same to one, the condensed-solve products 12–21 % fewer. The
/// residual and the convergence test are unchanged: only the path.
const CYCLE: f64 = 0.5;

/// A step whose direction is within this cosine of the last step's is not
/// halved by the [`CYCLE`] rule: a cycle turns back, and a Newton iteration
/// crawling along a soft direction (a fold forming in the skirt), its
/// steps one after another along one line and its residual falling by
/// 5–10 % an iteration, was held at half steps until the iteration limit
/// cut its increment. Measured with the active-set solver on five shipped
/// scenes, each as shipped and with the punch's μ ± 1e-4 (the scenes'
/// paths scatter with round-off; mean factorisations of the three):
/// hemisphere-0-90 2 198 → 1 878, hemisphere-45 2 515 → 2 309,
/// deep-drawing-0-90 1 057 → 994, deep-drawing-45 1 544 → 1 552,
/// hemisphere-ring 8 659 → 8 689 (6 407–12 527 either way). At 0.9 the
/// ring took 10 474 (8 856–12 075) and the others about as at 0.95. Only
/// with the active-set solver: the condensed solve's path on the 20 × 20
/// ring went wrong with it (see the notes, 2026-11-30).
const ALONG: f64 = 0.95;

/// A full Newton step that cut the residual to at most this fraction of
/// the last one is in Newton's quadratic range: there the next correction
/// is the last one times the residual's contraction (K̂⁻¹ varies little
/// over the step), and the displacement test of convergence is passed on
/// that estimate instead of taking one more step to measure it. Measured
/// (traces of `DRAPE_NEWTON_TRACE`): on the shipped hemisphere-0-90 with
/// the active-set solver 203 of 256 increments took a last iteration whose
/// residual was already within the force tolerance only for the
/// correction test; with the estimate 241 increments, 2 567 + 650 Newton
/// iterations and 3 442 factorisations against 256, 2 764 + 700 and 3 588.
const QUADRATIC: f64 = 0.1;

/// A Newton correction longer than the model's bounding-box diagonal and
/// at least this many times the last one is divergence: the attempt is cut
/// at once instead of at `max_iterations`. Measured with
/// `DRAPE_NEWTON_TRACE` on hemisphere-0-90, deep-drawing-0-90 and
/// deep-drawing-45 (active set): no converged attempt had a correction
/// above 6.7 mm; 14 of their 85 cut attempts grew their corrections three-
/// to tenfold an iteration from ~50 mm to 10⁵–10⁷ mm and were cut at 25
/// iterations with residuals at their force scales. A large first
/// correction that then shrinks (a blank falling far in one increment) is
/// not cut: the growth is asked for too.
const DIVERGED: f64 = 2.0;

/// The predictor of an increment, xₙ + h·vₙ: constant velocity, not
/// constant acceleration (xₙ + h·vₙ + ½h²·aₙ, as it was). The Bossak
/// acceleration at ρ∞ = 0 is a poor guess of the next one (its high
/// frequencies are what the scheme damps, and a pressed node's normal
/// component is reset to the tool's at each commit), and forming is
/// quasi-static: ½h²·aₙ mostly moved the folding skirt away from its
/// answer. Measured 2026-11-28 (one thread, active set, `DRAPE_NEWTON_TRACE`;
/// see docs/notes/implicit-solver.md): the 10 × 10 physical-mass
/// hemisphere 0/90 took 85 increments, 730 + 50 Newton iterations and
/// 814 factorisations instead of 120, 1 058 + 75 and 1 139, ±45 81, 809 +
/// 25 and 866 instead of 117, 965 + 150 and 1 124; the shipped
/// hemisphere-0-90 140 increments, 1 639 + 375 Newton iterations, 2 103
/// factorisations and 68 s of user CPU instead of 241, 2 567 + 650, 3 442
/// and 116 s (run side by side). Tried beside it: the
/// secant xₙ + (h/h_{n−1})·(xₙ − x_{n−1}) did as well on 10 × 10 but needs
/// x_{n−1} in the checkpoint to resume bit for bit; Newmark's a_{n+1} = 0
/// predictor, xₙ + h·vₙ + (½ − β)·h²·aₙ, was dropped earlier (on the
/// hemisphere 40 × 40 as shipped: 2 300 increments and 434 cutbacks
/// against 1 193 and 215). Carrying the friction states to the predictor
/// by the return mapping there, or holding the rows pressed at tₙ at the
/// first iteration whatever their predicted gap, did not help (the note).
/// Force-driven tools keep their constant-acceleration predictor
/// (`drape_contact`'s `begin`).
fn predictor(x_n: Vector3<f64>, v_n: Vector3<f64>, h: f64) -> Vector3<f64> {
    x_n + v_n * h
}

/// The default elastic slip of a sticking pair at the friction limit (mm).
///
/// With a rigid stick, pairs at the edge of the friction cone flip between
/// stick and slip: the stick force jumps from the stick rows' multiplier
/// to μ·λ_N along a direction fixed for the increment, and 3–4
/// neighbouring pairs can cycle until the attempt is cut. A tangential
/// spring (as Abaqus/Standard's penalty friction, whose default elastic
/// slip is 0.5 % of an element length) makes the friction force a
/// continuous function of the slip, f = f_n − k_t·s inside the cone and
/// μ·λ_N along it outside, and Newton converges through the switch.
/// 10 µm is far below what any forming measure resolves (the hemisphere's
/// draw-ins are checked to 0.5 mm) and well inside the contact cases: the
/// capstan still slides everywhere (every touching node slipping, T₂/T₁
/// within its 0.3 % of the discrete wrap), which it no longer does at
/// 40 µm (a sixth to a half of the nodes held on their springs, the
/// tension ratio 2–5 % low). A rigid stick made the hemisphere 10 × 10
/// (0/90, μ = 0.1, physical mass, yarn bending) take 680 increments, 7 975
/// Newton iterations and 136 cutbacks instead of 164, 1 202 and 11 at 1 µm
/// (±45: 1 083, 12 804 and 231 instead of 232, 1 413 and 34), and 0.1 µm
/// 393 increments and 67 cutbacks.
///
/// 10 µm rather than the 1 µm it was: where a blank is drawn in between
/// holder and die, the clamp makes μ·λ_N large, so a 1 µm spring turned
/// each 1e-3 mm of a Newton correction into a swing of the whole cone, and
/// the draw-in front's pairs switched stick ↔ slip by the hundred per
/// iteration. The shipped deep drawings with the active set (implicit, one
/// run each on a loaded 2-core machine; increments, factorisations, user
/// CPU): 0/90 350, 4 811, 116 s → 97, 1 393, 31 s; ±45 279, 4 750 →
/// 192, 2 967; the same answer (0/90: max shear 48.11° → 48.10°, DX
/// 42.26 → 42.23 mm, DD 7.65 → 7.64 mm). The hemispheres, whose Newton
/// iterations go to the folding skirt rather than to friction, are
/// unchanged within their path's scatter (0/90: 140 → 171 increments,
/// 2 103 → 2 376 factorisations).
pub const ELASTIC_SLIP: f64 = 1e-2;

/// Settings of an implicit run.
#[derive(Debug, Clone, PartialEq)]
pub struct ImplicitSettings {
    /// Time to reach (s).
    pub end_time: f64,
    /// Output frames after the initial one, equally spaced in time.
    pub frames: usize,
    /// First increment (s); default a hundredth of the end time.
    pub initial_increment: Option<f64>,
    /// Largest increment (s); default a twentieth of the end time.
    pub max_increment: Option<f64>,
    /// Smallest increment before the run gives up (s); default 1e-9 of the
    /// end time.
    pub min_increment: Option<f64>,
    /// Spectral radius ρ∞ ∈ [0, 1] of the Bossak scheme at infinite
    /// frequency: 0 damps what an increment cannot resolve at once, 1
    /// conserves energy (trapezoidal rule).
    pub spectral_radius: f64,
    /// Newton converges when the residual is within this fraction of the
    /// force scale...
    ///
    /// Why the default stays 1e-6 with the correction tolerance (looser
    /// pairs measured 2026-11-24, 1 thread, release): on the 10 × 10
    /// agreement runs (physical mass, yarn bending) 1e-5 changes nothing
    /// (0/90 178 increments instead of 163, ±45 229 instead of 233, the
    /// answers to 0.001°), and 1e-4 or 1e-3 send 0/90 on a path where
    /// pairs chatter between stick and slip (547–678 increments, 104–131
    /// cutbacks, 4–6× the CPU; max shear and draw-ins within 0.12° and
    /// 0.12 mm). Newton converges quadratically in its last iterations
    /// (the hemisphere 40 × 40: 1e-3 → 2e-5 → 1e-8 of the scale), so a
    /// looser tolerance saves one or two of the ~10 iterations of an
    /// increment at most: to t = 0.6 s, 40 × 40 as shipped, 1e-3 took
    /// 55 s of CPU instead of 65 s, and 1e-4 66 s (both with the contact
    /// pass's force floor kept at 1e-6 of the scale; with it at the
    /// tolerance, as now, 10 × 10 0/90 at 1e-3 took 547 increments, with
    /// it kept 142).
    pub force_tolerance: f64,
    /// ...and the last correction within this fraction of the increment's
    /// largest displacement.
    pub displacement_tolerance: f64,
    /// Largest penetration into a tool, and stick slip, left (mm).
    pub gap_tolerance: f64,
    /// Newton iterations per attempt.
    pub max_iterations: usize,
    /// α of the mass-proportional damping force −α·m·v (1/s).
    pub damping: f64,
    /// Nodes nearer a tool than this take part in the contact solve (mm).
    pub contact_margin: f64,
    /// Elastic slip of a sticking pair at the friction limit (mm): stick
    /// is a tangential spring k_t = μ·λ_N/`elastic_slip` (see
    /// [`ELASTIC_SLIP`]); 0 holds sticking pairs rigidly.
    pub elastic_slip: f64,
    /// The instability guard ([`crate::guard`]), as for the explicit
    /// driver: node speed and reach and the force-driven tools' travel
    /// after every increment, the energy balance (numerical dissipation
    /// counted) at frames and at least `guard::MIN_ENERGY_CHECKS` times a
    /// run.
    pub guard: GuardSettings,
    /// Stop after this many increments.
    pub max_increments: Option<u64>,
    /// Hand the observer a checkpoint every this many increments.
    pub checkpoint_every: Option<u64>,
    /// Target step of the explicit driver's selective mass scaling
    /// ([`crate::ExplicitSettings::mass_scaling`]): the implicit run
    /// integrates with the same nodal masses, so that a scene gives the
    /// same model to both drivers. The weight stays the physical mass's
    /// (mass scaling adds inertia only). None: the physical mass.
    pub mass_scaling: Option<f64>,
    /// The explicit driver's safety factor, which its mass scaling is
    /// computed with (the scene's `safety_factor`); nothing else.
    pub safety_factor: f64,
    /// The resin membranes' tangent in K̂ (see [`MembraneTangentChoice`]):
    /// the residual is exact either way, so this changes Newton's path,
    /// not the converged state.
    ///
    /// Why the default stays exact (one core, user CPU, busy VM, exact →
    /// `TensionFieldWhenIndefinite`): it is not a pure win. The ±45
    /// hemisphere with the physical mass and bending, 20 × 20: 610 → 461
    /// increments, 5 828 + 118 → 5 021 + 175 Newton, 34 → 7 cutbacks,
    /// 122 → 112 s; 10 × 10: 233 → 145 increments, 4.3 → 4.5 s. But the
    /// shipped 0/90 hemisphere (mass-scaled, no bending): 308 → 299
    /// increments, 3 770 + 287 → 3 742 + 538 Newton, cutbacks 24 → 23
    /// (contact indefinite 13 → 2, Newton limit 9 → 19), 109 → 125 s: the
    /// attempts on the scaled tangent converge linearly and more of them
    /// reach the iteration limit. The shipped ±45 one: 433 → 348
    /// increments, 5 198 + 764 → 4 528 + 875 Newton, cutbacks 54 → 35 (no
    /// "contact indefinite" left), 474 → 486 s. The answers are the same
    /// where the model determines them (±45 physical mass and bending:
    /// within 1e-4° at 10 × 10, 3e-4° at 20 × 20); the shipped scenes have
    /// no bending, and their wrinkled skirts differ by an element RMS of
    /// 0.15° (0/90) and 0.9° (±45), as between any two paths there.
    pub membrane_tangent: MembraneTangentChoice,
    /// How each Newton iteration solves the contact (see
    /// [`ContactSolver`]).
    pub contact_solver: ContactSolver,
}

impl Default for ImplicitSettings {
    fn default() -> Self {
        Self {
            end_time: 1.0,
            frames: 10,
            initial_increment: None,
            max_increment: None,
            min_increment: None,
            spectral_radius: 0.0,
            force_tolerance: 1e-6,
            displacement_tolerance: 1e-6,
            gap_tolerance: 1e-9,
            max_iterations: 25,
            damping: 0.0,
            contact_margin: 5.0,
            elastic_slip: ELASTIC_SLIP,
            guard: GuardSettings::default(),
            max_increments: None,
            checkpoint_every: None,
            mass_scaling: None,
            safety_factor: crate::ExplicitSettings::default().safety_factor,
            membrane_tangent: MembraneTangentChoice::Exact,
            contact_solver: ContactSolver::default(),
        }
    }
}

/// Residual norms of one Newton iteration, for tests and diagnosis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonRecord {
    /// Increment (the step count after it).
    pub increment: u64,
    /// Iteration within the attempt (0: the predictor).
    pub iteration: usize,
    /// Largest residual component (N).
    pub residual: f64,
    /// The force scale it is compared with (N).
    pub scale: f64,
    /// Largest component of the correction that led here (mm).
    pub correction: f64,
    /// Normal contact rows that entered or left the active set in the
    /// step that led here.
    pub active_changes: usize,
    /// Pairs whose friction state (stick, slip, released) the return
    /// mapping changed at this iterate.
    pub friction_changes: usize,
    /// Pressed pairs that stick at this iterate.
    pub sticking: usize,
    /// Pressed pairs that slip at this iterate.
    pub slipping: usize,
    /// The largest μ·|Δλ_N| of a slipping pair in the step that led here
    /// (N): friction the step took at the old λ_N.
    pub slip_lag: f64,
    /// Friction state of the node with the largest residual: 0 no
    /// pressed pair, 1 stick, 2 slip.
    pub worst_contact: u8,
    /// Largest penetration (mm).
    pub penetration: f64,
    /// Largest violation of a sticking pair's stick law (mm).
    pub stick_slip: f64,
    /// Force-driven tools' largest imbalance (N).
    pub imbalance: f64,
    /// The increment's size (s).
    pub h: f64,
    /// The cosine of the angle between the Newton step that led here and
    /// the one before it (0 for the first of an attempt): near 1 with
    /// shrinking steps, Newton falls short along one direction.
    pub step_cosine: f64,
    /// The ratio of their lengths (0 for the first).
    pub step_ratio: f64,
    /// The fraction of the Newton step taken (line search, cycle halving).
    pub step_taken: f64,
}

/// Why an attempt failed, for the cutback count and the final diagnosis.
struct Failure {
    reason: Cutback,
    message: String,
}

/// The kinds of [`CutbackReasons`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Cutback {
    FrictionChatter,
    NewtonLimit,
    ElementFailure,
    NotFinite,
    TangentFailure,
    ContactIndefinite,
    ContactNotConverged,
    Diverged,
}

impl Cutback {
    /// The reason's name, as the field of [`CutbackReasons`] that counts it.
    fn name(self) -> &'static str {
        match self {
            Cutback::FrictionChatter => "friction_chatter",
            Cutback::NewtonLimit => "newton_limit",
            Cutback::ElementFailure => "element_failure",
            Cutback::NotFinite => "not_finite",
            Cutback::TangentFailure => "tangent_failure",
            Cutback::ContactIndefinite => "contact_indefinite",
            Cutback::ContactNotConverged => "contact_not_converged",
            Cutback::Diverged => "diverged",
        }
    }

    fn count(self, reasons: &mut CutbackReasons) {
        let n = match self {
            Cutback::FrictionChatter => &mut reasons.friction_chatter,
            Cutback::NewtonLimit => &mut reasons.newton_limit,
            Cutback::ElementFailure => &mut reasons.element_failure,
            Cutback::NotFinite => &mut reasons.not_finite,
            Cutback::TangentFailure => &mut reasons.tangent_failure,
            Cutback::ContactIndefinite => &mut reasons.contact_indefinite,
            Cutback::ContactNotConverged => &mut reasons.contact_not_converged,
            Cutback::Diverged => &mut reasons.diverged,
        };
        *n += 1;
    }
}

/// What a converged attempt reports.
struct Converged {
    newton: usize,
    /// Normal rows that entered or left the active set.
    active_changes: usize,
    /// Factorisations (of K̂ or the saddle-point system).
    factorisations: usize,
    /// Of which followed a change of friction states.
    switched: usize,
    contact_iterations: usize,
}

/// The Bossak–Newmark parameters of ρ∞.
fn bossak(rho: f64) -> (f64, f64, f64) {
    let alpha_m = (rho - 1.0) / (rho + 1.0);
    let beta = 0.25 * (1.0 - alpha_m) * (1.0 - alpha_m);
    let gamma = 0.5 - alpha_m;
    (alpha_m, beta, gamma)
}

/// The implicit driver with its tangent, contact pass and buffers.
pub struct Implicit<'m> {
    model: &'m Model,
    settings: ImplicitSettings,
    constraints: Constraints,
    /// Constrained flag per dof (3·node + component).
    fixed: Vec<bool>,
    forces: ForcePass,
    /// The follower pressures (empty without): part of f_ext, evaluated at
    /// every iterate.
    pressure: PressurePass,
    tangent: SparseTangent,
    contact: Option<ImplicitContact>,
    alpha_m: f64,
    beta: f64,
    gamma: f64,
    /// Committed accelerations aₙ.
    acceleration: Vec<Vector3<f64>>,
    f_ext: Vec<Vector3<f64>>,
    /// Forces at the last committed state, for the trapezoidal works.
    f_int_n: Vec<Vector3<f64>>,
    f_ext_n: Vec<Vector3<f64>>,
    f_c_n: Vec<Vector3<f64>>,
    x: Vec<Vector3<f64>>,
    v: Vec<Vector3<f64>>,
    a: Vec<Vector3<f64>>,
    x_step: Vec<Vector3<f64>>,
    f_slip: Vec<Vector3<f64>>,
    f_con: Vec<Vector3<f64>>,
    r: Vec<f64>,
    dx: Vec<f64>,
    reactions: Vec<Vector3<f64>>,
    resume: Option<DriverState>,
    totals: ImplicitTotals,
    /// Every Newton iteration's norms, when recording.
    record: Option<Vec<NewtonRecord>>,
    /// Where to write the record at the end of the run (see
    /// [`trace::VARIABLE`]).
    trace: Option<std::path::PathBuf>,
    /// The last Newton step, and (cosine, length ratio, halving) of the
    /// last one against the one before (see [`ALONG`]).
    dx_before: Vec<f64>,
    step_angle: (f64, f64, f64),
    /// Kinetic energy at the start of the run.
    kinetic0: f64,
    /// The model's size (bounding-box diagonal, mm).
    size: f64,
    guard: Guard,
    /// Start-up and run warnings.
    warnings: Vec<String>,
    /// Which tools have touched the blank.
    tool_touched: Vec<bool>,
    /// K̂'s 3×3 diagonal block at each node of a contact row (for the
    /// contact solve's preconditioner).
    node_blocks: Vec<Matrix3<f64>>,
    /// The nodes' inertia (t): the model's mass, scaled as the explicit
    /// driver scales it when `mass_scaling` is set.
    mass: Vec<f64>,
    /// The active-set solver's system, its held rows, right-hand side and
    /// solution buffers.
    saddle: SaddleSystem,
    system_rows: Vec<SystemRow>,
    rhs: Vec<f64>,
    multipliers: Vec<f64>,
    tool_steps: Vec<f64>,
}

impl<'m> Implicit<'m> {
    /// Prepares a run of `model`: checks it, builds the constraint list,
    /// the tangent's pattern and symbolic factorisation, the contact pass.
    pub fn new(model: &'m Model, settings: ImplicitSettings) -> Result<Self, RunError> {
        shared::check_model(model, settings.end_time)?;
        if model.plies.len() > 1 {
            return Err(RunError::Setup(format!(
                "a stack of {} plies needs ply–ply contact, which the implicit driver does not                  have (its condensed solve knows rigid tools only): run it with the explicit driver",
                model.plies.len()
            )));
        }
        let positive = |name: &str, v: f64| -> Result<(), RunError> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(RunError::Setup(format!("{name} {v} must be positive")))
            }
        };
        for (name, v) in [
            ("initial increment", settings.initial_increment),
            ("largest increment", settings.max_increment),
            ("smallest increment", settings.min_increment),
        ] {
            if let Some(v) = v {
                positive(name, v)?;
            }
        }
        // As the run resolves them: an increment below the smallest one
        // allowed ends at its first cutback, with a non-finite residual.
        let end = settings.end_time;
        let min_h = settings.min_increment.unwrap_or(1e-9 * end);
        for (name, h) in [
            (
                "initial increment",
                settings.initial_increment.unwrap_or(end / 100.0),
            ),
            (
                "largest increment",
                settings.max_increment.unwrap_or(end / 20.0),
            ),
        ] {
            if h < min_h {
                return Err(RunError::Setup(format!(
                    "the {name} {h:e} s is below the smallest increment {min_h:e} s \
                     (`simulation.min_increment`)"
                )));
            }
        }
        positive("force tolerance", settings.force_tolerance)?;
        positive("displacement tolerance", settings.displacement_tolerance)?;
        positive("gap tolerance", settings.gap_tolerance)?;
        positive("contact margin", settings.contact_margin)?;
        if !(0.0..=1.0).contains(&settings.spectral_radius) {
            return Err(RunError::Setup(format!(
                "spectral radius {} must be in [0, 1]",
                settings.spectral_radius
            )));
        }
        if settings.max_iterations == 0 {
            return Err(RunError::Setup(
                "at least one Newton iteration is needed".into(),
            ));
        }
        if !(settings.damping.is_finite() && settings.damping >= 0.0) {
            return Err(RunError::Setup(format!(
                "damping {} must be ≥ 0",
                settings.damping
            )));
        }
        let n = model.node_count();
        // The explicit driver's own scaling, so that both drivers see the
        // same inertia.
        let mass = match settings.mass_scaling {
            Some(dt) => crate::Explicit::new(
                model,
                crate::ExplicitSettings {
                    end_time: settings.end_time,
                    mass_scaling: Some(dt),
                    safety_factor: settings.safety_factor,
                    ..Default::default()
                },
            )?
            .mass()
            .to_vec(),
            None => model.mass.clone(),
        };
        let constraints = Constraints::new(model);
        let fixed: Vec<bool> = constraints
            .constrained
            .iter()
            .flat_map(|c| c.iter().copied())
            .collect();
        let mut tangent = SparseTangent::new(model, fixed.clone()).map_err(RunError::Setup)?;
        tangent.membrane_tangent = settings.membrane_tangent;
        let contact = (!model.tools.is_empty()).then(|| {
            let mut contact = ImplicitContact::new(
                model.tools.clone(),
                n,
                ImplicitContactSettings {
                    offset: model.contact_offset,
                    margin: settings.contact_margin,
                    // The condensed solve leaves a fraction of what Newton
                    // accepts.
                    tolerance: 1e-3 * settings.gap_tolerance,
                    elastic_slip: settings.elastic_slip,
                    square_friction_leans: settings.contact_solver == ContactSolver::ActiveSet,
                    ..ImplicitContactSettings::default()
                },
            );
            contact.set_mass(&mass);
            // Regularised stick rows as springs in K̂ (see the method):
            // the condensed solve then holds the normal rows only.
            contact.set_springs_in_tangent(true);
            contact
        });
        let (alpha_m, beta, gamma) = bossak(settings.spectral_radius);
        let zeros = vec![Vector3::zeros(); n];
        // No step-size check of force-driven tools: they are unknowns of the
        // contact solve, which cannot let them through the blank.
        let mut warnings =
            guard::check_tools_at_start(model, &model.x0, 0.0).map_err(RunError::Setup)?;
        if let Some(timing) = crate::scaling::LoadTiming::of(model, &mass, settings.end_time) {
            warnings.push(timing.message());
        }
        let guard = Guard::new(model, settings.guard.clone(), settings.end_time);
        let trace = trace::path();
        Ok(Self {
            model,
            settings,
            constraints,
            fixed,
            forces: ForcePass::new(model),
            pressure: PressurePass::new(model),
            tangent,
            contact,
            alpha_m,
            beta,
            gamma,
            acceleration: zeros.clone(),
            f_ext: zeros.clone(),
            f_int_n: zeros.clone(),
            f_ext_n: zeros.clone(),
            f_c_n: zeros.clone(),
            x: zeros.clone(),
            v: zeros.clone(),
            a: zeros.clone(),
            x_step: zeros.clone(),
            f_slip: zeros.clone(),
            f_con: zeros.clone(),
            r: vec![0.0; 3 * n],
            dx: vec![0.0; 3 * n],
            reactions: zeros,
            resume: None,
            totals: ImplicitTotals::default(),
            record: trace.as_ref().map(|_| Vec::new()),
            trace,
            dx_before: Vec::new(),
            step_angle: (0.0, 0.0, 1.0),
            kinetic0: 0.0,
            guard,
            warnings,
            tool_touched: vec![false; model.tools.len()],
            node_blocks: vec![Matrix3::zeros(); n],
            mass,
            saddle: SaddleSystem::new(),
            system_rows: Vec::new(),
            rhs: vec![0.0; 3 * n],
            multipliers: Vec::new(),
            tool_steps: Vec::new(),
            size: {
                let lo = model
                    .x0
                    .iter()
                    .fold(Vector3::repeat(f64::INFINITY), |m, x| m.inf(x));
                let hi = model
                    .x0
                    .iter()
                    .fold(Vector3::repeat(f64::NEG_INFINITY), |m, x| m.sup(x));
                (hi - lo).norm()
            },
        })
    }

    /// Mass added by mass scaling (t), 0 without it.
    pub fn added_mass(&self) -> f64 {
        self.mass.iter().sum::<f64>() - self.model.mass.iter().sum::<f64>()
    }

    /// Records the residual norms of every Newton iteration (see
    /// [`Self::newton_record`]).
    pub fn record_newton(&mut self) {
        self.record = Some(Vec::new());
    }

    /// The recorded Newton iterations.
    pub fn newton_record(&self) -> &[NewtonRecord] {
        self.record.as_deref().unwrap_or(&[])
    }

    /// What the run did so far, in total: also after a failed run, whose
    /// cutbacks by reason say why it failed.
    pub fn totals(&self) -> ImplicitTotals {
        ImplicitTotals {
            factorisations: self.tangent.factorisations + self.saddle.factorisations,
            indefinite: self.tangent.indefinite + self.totals.indefinite,
            compression_scaled: self.tangent.compression_scaled,
            factor_seconds: self.tangent.factor_seconds + self.saddle.factor_seconds,
            contact_solver: match self.settings.contact_solver {
                ContactSolver::Condensed => "condensed",
                ContactSolver::ActiveSet => "active_set",
            },
            ..self.totals
        }
    }

    /// The tangent's size: (degrees of freedom, stored entries).
    pub fn tangent_size(&self) -> (usize, usize) {
        (self.tangent.dofs(), self.tangent.nonzeros())
    }

    /// What the run found doubtful: start-up warnings (a blank closer to a
    /// tool than its half thickness, a force-driven tool with nothing in
    /// its path) and, after [`Self::run`], the run's own.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The contact pass as the last converged increment left it, if the
    /// model has tools (for a frame written after a run stopped between
    /// frames).
    pub fn contact(&self) -> Option<drape_contact::ContactView<'_>> {
        self.contact.as_ref().map(ImplicitContact::view)
    }

    /// Continues a stopped run from a checkpoint's driver state.
    pub fn resume_from(&mut self, driver: DriverState) {
        self.resume = Some(driver);
    }

    fn increment(&self, t: f64, h: f64) -> Increment {
        Increment {
            t_new: t + h,
            h,
            beta: self.beta,
            gamma: self.gamma,
            alpha_m: self.alpha_m,
        }
    }

    /// Accelerations at t = 0 consistent with the forces and the contacts.
    fn initial_acceleration(&mut self, state: &State) -> Result<(), RunError> {
        let model = self.model;
        let damping = self.settings.damping;
        let n = model.node_count();
        for i in 0..n {
            let f = self.f_ext[i] - self.forces.f_int[i] - state.v[i] * (damping * self.mass[i]);
            for k in 0..3 {
                self.acceleration[i][k] = if self.constraints.constrained[i][k] {
                    0.0
                } else {
                    f[k] / self.mass[i]
                };
            }
        }
        // Prescribed components: the motion's second difference.
        let delta = 1e-4 * self.settings.end_time.max(f64::MIN_POSITIVE);
        for c in &self.constraints.list {
            let (i, k) = (c.node as usize, c.component as usize);
            let p = |t: f64| Constraints::position(model, c, 0.0, 0.0, t);
            self.acceleration[i][k] = match Constraints::displacement(model, c, 0.0) {
                Some(_) => (p(2.0 * delta) - 2.0 * p(delta) + p(0.0)) / (delta * delta),
                None => {
                    (Constraints::velocity(model, c, delta) - Constraints::velocity(model, c, 0.0))
                        / delta
                }
            };
        }
        if let Some(contact) = &mut self.contact {
            let touch = 1e3 * self.settings.gap_tolerance;
            let free: Vec<[bool; 3]> = self
                .constraints
                .constrained
                .iter()
                .map(|c| [!c[0], !c[1], !c[2]])
                .collect();
            contact
                .initial_acceleration(
                    &state.x,
                    &state.v,
                    &self.mass,
                    &free,
                    touch,
                    &mut self.acceleration,
                )
                .map_err(|e| RunError::Setup(format!("initial accelerations: {e}")))?;
        }
        Ok(())
    }

    /// Runs from `state` to the end time. On error `state` holds the last
    /// output frame (or the start), which passed every check, as for the
    /// explicit driver.
    pub fn run(
        &mut self,
        state: &mut State,
        observer: &mut dyn Observer,
    ) -> Result<RunSummary, RunError> {
        let result = self.advance(state, observer);
        if let (Some(path), Some(record)) = (&self.trace, &self.record) {
            trace::write(path, record);
        }
        if let Err(e) = &result {
            if !matches!(e, RunError::Setup(_)) {
                self.guard.fall_back(state);
            }
        }
        result
    }

    fn advance(
        &mut self,
        state: &mut State,
        observer: &mut dyn Observer,
    ) -> Result<RunSummary, RunError> {
        let started = Instant::now();
        let model = self.model;
        let n = model.node_count();
        let end = self.settings.end_time;
        shared::check_state(model, state)?;
        if state.step == 0 && self.resume.is_none() {
            // Said in `warnings` by the start-up checks.
            guard::settle_on_tools(model, &mut state.x, &self.constraints.free());
        }
        shared::external_forces(model, state.time, &mut self.f_ext);
        self.pressure
            .add_into(model, &state.x, state.time, &mut self.f_ext);
        self.forces.evaluate(
            model,
            &state.x,
            None,
            &state.history,
            0.0,
            state.step,
            state.time,
            None,
        )?;
        let resume = self.resume.take();
        if resume.as_ref().is_some_and(|r| r.implicit.is_none()) {
            return Err(RunError::Setup(
                "the checkpoint was written by the explicit driver".into(),
            ));
        }
        let mut energy = resume.as_ref().map_or_else(Energies::default, |r| r.energy);
        let kinetic0 = match &resume {
            Some(r) => r.kinetic0,
            None => chunked_sum(n, |i| 0.5 * self.mass[i] * state.v[i].norm_squared()),
        };
        self.kinetic0 = kinetic0;
        match &resume {
            Some(r) => {
                let carry = r.implicit.as_ref().expect("checked above");
                if carry.acceleration.len() != n {
                    return Err(RunError::Setup(
                        "the checkpoint does not belong to this model".into(),
                    ));
                }
                self.acceleration.clone_from(&carry.acceleration);
                self.f_c_n.clone_from(&carry.contact_force);
                if let Some(contact) = &mut self.contact {
                    contact.restore(
                        carry.contacts.clone(),
                        &r.tools,
                        &carry.tool_acceleration,
                        r.friction_dissipation,
                    );
                    contact.force.clone_from(&carry.contact_force);
                }
            }
            None => self.initial_acceleration(state)?,
        }
        self.f_int_n.clone_from(&self.forces.f_int);
        self.f_ext_n.clone_from(&self.f_ext);
        // The stiffness at the start sets the force floor of the
        // convergence test before the first Newton step assembles it.
        self.tangent
            .assemble(model, &state.x, &state.history, 0.0, &self.mass, 0.0)
            .map_err(|(batch, error)| RunError::Element {
                step: state.step,
                time: state.time,
                batch,
                error,
            })?;
        let frame_dt = if self.settings.frames > 0 {
            end / self.settings.frames as f64
        } else {
            f64::INFINITY
        };
        let mut next_frame = (state.time / frame_dt * (1.0 + 1e-12)).floor() as usize + 1;
        // The guard looks at the energy at every frame, and at least
        // `guard::MIN_ENERGY_CHECKS` times a run whatever the frames.
        let check_dt = end / self.settings.frames.max(guard::MIN_ENERGY_CHECKS) as f64;
        let mut next_check = (state.time / check_dt * (1.0 + 1e-12)).floor() + 1.0;
        self.guard.begin(state);
        if state.step == 0 {
            energy.kinetic = kinetic0;
            energy.strain = shared::strain_energy(model, state);
            self.compute_reactions();
            observer.frame(&Frame {
                index: 0,
                model,
                state,
                energy: &energy,
                reactions: &self.reactions,
                contact: self.contact.as_ref().map(ImplicitContact::view),
            });
        }
        let max_h = self.settings.max_increment.unwrap_or(end / 20.0);
        let min_h = self.settings.min_increment.unwrap_or(1e-9 * end);
        let mut h_auto = match &resume {
            Some(r) => r.dt,
            None => self.settings.initial_increment.unwrap_or(end / 100.0),
        }
        .min(max_h);
        let (mut h_min_used, mut h_max_used) = (f64::INFINITY, 0.0f64);
        let mut increments = 0u64;
        let mut stopped = false;
        while end - state.time > 1e-9 * h_auto.min(end) {
            if self
                .settings
                .max_increments
                .is_some_and(|m| increments >= m)
            {
                stopped = true;
                break;
            }
            let to_frame = next_frame as f64 * frame_dt - state.time;
            let mut h = h_auto.min(end - state.time).min(to_frame.max(0.0));
            // A remainder below a millionth of the increment is round-off.
            if h <= 1e-6 * h_auto {
                h = h_auto.min(end - state.time);
            }
            let clamped = h < h_auto;
            let mut cutbacks = 0usize;
            let converged = loop {
                match self.attempt(state, h) {
                    Ok(c) => break c,
                    Err(Failure { reason, message }) => {
                        cutbacks += 1;
                        self.totals.cutbacks += 1;
                        reason.count(&mut self.totals.cutback_reasons);
                        observer.cutback(&CutbackReport {
                            step: state.step + 1,
                            time: state.time,
                            increment: h,
                            reason: reason.name(),
                            message: &message,
                        });
                        h *= 0.25;
                        if h < min_h {
                            return Err(RunError::NoConvergence {
                                step: state.step + 1,
                                time: state.time,
                                increment: h / 0.25,
                                reason: message,
                            });
                        }
                    }
                }
            };
            // Commit.
            let (active, stick, slip) = self.commit(state, h, &mut energy);
            increments += 1;
            let unstable = |what| RunError::Unstable {
                step: state.step,
                time: state.time,
                what,
            };
            self.guard
                .nodes(&state.x, &state.v, &self.constraints.movable)
                .map_err(|what| {
                    unstable(match &self.contact {
                        Some(c) => {
                            let u: Vec<f64> = c.tool_state.iter().map(|t| t.displacement).collect();
                            what.near_tools(&c.tools, &u, &state.x)
                        }
                        None => what,
                    })
                })?;
            if let Some(contact) = &self.contact {
                for (touched, f) in self.tool_touched.iter_mut().zip(&contact.tool_force) {
                    *touched |= *f != 0.0;
                }
                let travel = contact.tool_state.iter().map(|t| t.displacement);
                self.guard.tools(model, travel).map_err(unstable)?;
            }
            let dt_prev = h;
            h_min_used = h_min_used.min(h);
            h_max_used = h_max_used.max(h);
            if cutbacks > 0 {
                h_auto = h;
            } else if converged.newton - converged.switched <= EASY && !clamped {
                h_auto = (1.5 * h_auto).min(max_h);
            } else if converged.newton - converged.switched >= HARD {
                h_auto = (0.75 * h).max(min_h);
            }
            if self
                .settings
                .checkpoint_every
                .is_some_and(|k| state.step % k.max(1) == 0)
            {
                let driver = self.driver_state(h_auto, dt_prev, energy, kinetic0);
                observer.checkpoint(state, &driver);
            }
            let at_end = end - state.time <= 1e-9 * h_auto.min(end);
            let at_frame = state.time >= next_frame as f64 * frame_dt * (1.0 - 1e-12);
            let at_check = state.time >= next_check * check_dt * (1.0 - 1e-12);
            if at_frame || at_end || at_check {
                let mut report = energy;
                report.strain = shared::strain_energy(model, state);
                report.viscous = report.internal_work - report.strain;
                self.guard
                    .energy(&report, state.time)
                    .map_err(|what| RunError::Unstable {
                        step: state.step,
                        time: state.time,
                        what,
                    })?;
                while next_check * check_dt <= state.time * (1.0 + 1e-12) {
                    next_check += 1.0;
                }
                if at_frame || at_end {
                    self.guard.accept(state);
                }
                if at_frame {
                    self.compute_reactions();
                    observer.frame(&Frame {
                        index: next_frame,
                        model,
                        state,
                        energy: &report,
                        reactions: &self.reactions,
                        contact: self.contact.as_ref().map(ImplicitContact::view),
                    });
                    while next_frame as f64 * frame_dt <= state.time * (1.0 + 1e-12) {
                        next_frame += 1;
                    }
                }
            }
            let p = Progress {
                step: state.step,
                time: state.time,
                end_time: end,
                dt: h,
                increment: Some(IncrementReport {
                    newton: converged.newton,
                    contact_iterations: converged.contact_iterations,
                    active_changes: converged.active_changes,
                    factorisations: converged.factorisations,
                    cutbacks,
                    active,
                    stick,
                    slip,
                }),
            };
            if observer.progress(&p) == Control::Stop && !at_end {
                stopped = true;
                break;
            }
        }
        energy.strain = shared::strain_energy(model, state);
        energy.viscous = energy.internal_work - energy.strain;
        if stopped {
            // A run stopped between checks still reports only what passes.
            self.guard
                .energy(&energy, state.time)
                .map_err(|what| RunError::Unstable {
                    step: state.step,
                    time: state.time,
                    what,
                })?;
        }
        if !stopped {
            // Completed only with the blank outside every tool, whatever
            // the gap tolerance let Newton accept.
            let u: Vec<f64> = self.contact.as_ref().map_or_else(Vec::new, |c| {
                c.tool_state.iter().map(|t| t.displacement).collect()
            });
            crate::completion::check_at_end(model, state, &u, Some(self.settings.gap_tolerance))?;
        }
        for (tool, touched) in model.tools.iter().zip(&self.tool_touched) {
            if tool.is_force_driven() && !touched && !stopped {
                self.warnings.push(format!(
                    "force-driven tool `{}` never touched the blank: its force acted on nothing",
                    tool.name
                ));
            }
        }
        Ok(RunSummary {
            steps: increments,
            dt_range: (h_min_used, h_max_used),
            added_mass: self.added_mass(),
            total_mass: self.mass.iter().sum(),
            energy,
            stopped,
            wall_seconds: started.elapsed().as_secs_f64(),
            threads: rayon::current_num_threads(),
            warnings: self.warnings.clone(),
            implicit: Some(self.totals()),
        })
    }

    fn driver_state(&self, h: f64, dt_prev: f64, energy: Energies, kinetic0: f64) -> DriverState {
        DriverState {
            dt: h,
            dt_prev,
            energy,
            kinetic0,
            tools: self
                .contact
                .as_ref()
                .map_or_else(Vec::new, |c| c.tool_state.clone()),
            friction_dissipation: self
                .contact
                .as_ref()
                .map_or(0.0, |c| c.friction_dissipation),
            implicit: Some(ImplicitCarry {
                acceleration: self.acceleration.clone(),
                tool_acceleration: self
                    .contact
                    .as_ref()
                    .map_or_else(Vec::new, |c| c.tool_acceleration.clone()),
                contacts: self
                    .contact
                    .as_ref()
                    .map_or_else(Vec::new, |c| c.carried().to_vec()),
                contact_force: self.f_c_n.clone(),
            }),
            truss_clearance: Vec::new(),
            plies: None,
        }
    }

    /// The residual at the iterate `self.x` (its velocity and acceleration
    /// into `self.v`, `self.a`): `self.r` gets every force but the contact
    /// multipliers' (slip forces included), `self.f_slip` and `self.f_con`
    /// the slip and constraint forces of the last solve. Returns (largest
    /// residual component with the constraint forces, node, force scale).
    fn residual(&mut self, state: &State, inc: &Increment) -> (f64, usize, f64) {
        let damping = self.settings.damping;
        let (x_n, v_n, a_n) = (&state.x, &state.v, &self.acceleration);
        {
            let (x, v, a) = (&self.x, &mut self.v, &mut self.a);
            v.par_iter_mut()
                .zip(a.par_iter_mut())
                .with_min_len(1024)
                .enumerate()
                .for_each(|(i, (vi, ai))| {
                    *ai = inc.acceleration(x[i] - x_n[i], v_n[i], a_n[i]);
                    *vi = inc.velocity(v_n[i], a_n[i], *ai);
                });
        }
        for (s, c) in self.f_slip.iter_mut().zip(self.f_con.iter_mut()) {
            *s = Vector3::zeros();
            *c = Vector3::zeros();
        }
        if let Some(contact) = &self.contact {
            contact.add_slip_forces(&mut self.f_slip);
            contact.add_constraint_forces(&mut self.f_con);
        }
        let fixed = &self.fixed;
        let (f_ext, f_int, f_slip, f_con) =
            (&self.f_ext, &self.forces.f_int, &self.f_slip, &self.f_con);
        let (v, a) = (&self.v, &self.a);
        // r = f_ext − f_int − M·ā − c·M·v + slip forces, zero where
        // prescribed; per node the largest |r + Cᵀλ| and inertia.
        let (largest, node, inertia) = self
            .r
            .par_chunks_mut(3)
            .with_min_len(1024)
            .enumerate()
            .map(|(i, ri)| {
                let m = self.mass[i];
                let inertia = inc.inertia(a_n[i], a[i]) * m;
                let f = f_ext[i] - f_int[i] - inertia - v[i] * (damping * m) + f_slip[i];
                let mut worst = 0.0f64;
                for k in 0..3 {
                    ri[k] = if fixed[3 * i + k] { 0.0 } else { f[k] };
                    if !fixed[3 * i + k] {
                        worst = worst.max((ri[k] + f_con[i][k]).abs());
                    }
                }
                (worst, i, inertia.amax())
            })
            .reduce(
                || (0.0, usize::MAX, 0.0),
                |p, q| {
                    let worst = if q.0 > p.0 || (q.0 == p.0 && q.1 < p.1) {
                        (q.0, q.1)
                    } else {
                        (p.0, p.1)
                    };
                    (worst.0, worst.1, p.2.max(q.2))
                },
            );
        let external = f_ext.iter().map(|f| f.amax()).fold(0.0, f64::max);
        let contact = f_con
            .iter()
            .zip(f_slip)
            .map(|(c, s)| (c + s).amax())
            .fold(0.0, f64::max);
        // With nothing loaded every force is round-off: then the scale is
        // the force that a displacement of a millionth of the model's size
        // costs the stiffest node (the tangent's largest diagonal).
        let scale = self
            .forces
            .element_force_scale()
            .max(external)
            .max(contact)
            .max(inertia)
            .max(1e-6 * self.size * self.tangent.max_stiffness)
            .max(f64::MIN_POSITIVE);
        // A NaN anywhere makes the largest component NaN.
        let largest = if self.r.iter().all(|r| r.is_finite()) {
            largest
        } else {
            f64::NAN
        };
        (largest, node, scale)
    }

    /// Commits the converged attempt: works and numerical dissipation over
    /// the increment, the state, the contact pass. Returns (active
    /// contacts, sticking, slipping).
    fn commit(
        &mut self,
        state: &mut State,
        h: f64,
        energy: &mut Energies,
    ) -> (usize, usize, usize) {
        let model = self.model;
        let inc = self.increment(state.time, h);
        let damping = self.settings.damping;
        let n = model.node_count();
        let (x, v, a) = (&self.x, &self.v, &self.a);
        let (x_n, v_n, a_n) = (&state.x, &state.v, &self.acceleration);
        let (f_int, f_ext, f_int_n, f_ext_n, f_c_n) = (
            &self.forces.f_int,
            &self.f_ext,
            &self.f_int_n,
            &self.f_ext_n,
            &self.f_c_n,
        );
        let (f_slip, f_con) = (&self.f_slip, &self.f_con);
        let fixed = &self.fixed;
        let [w_int, w_ext, w_damp, w_c, w_bc, ke_n, d_num, w_res] = chunked_sums(n, |i| {
            let m = self.mass[i];
            let dx = x[i] - x_n[i];
            let f_c = f_slip[i] + f_con[i];
            let (damp, damp_n) = (v[i] * (damping * m), v_n[i] * (damping * m));
            let force = f_ext[i] - f_int[i] - damp + f_c;
            let force_n = f_ext_n[i] - f_int_n[i] - damp_n + f_c_n[i];
            let inertia = inc.inertia(a_n[i], a[i]) * m;
            let (mut w_bc, mut w_res) = (0.0, 0.0);
            for k in 0..3 {
                let work = (inertia[k] - force[k]) * dx[k];
                if fixed[3 * i + k] {
                    w_bc += work;
                } else {
                    w_res += work;
                }
            }
            [
                0.5 * (f_int_n[i] + f_int[i]).dot(&dx),
                0.5 * (f_ext_n[i] + f_ext[i]).dot(&dx),
                0.5 * (damp_n + damp).dot(&dx),
                0.5 * (f_c_n[i] + f_c).dot(&dx),
                w_bc,
                0.5 * m * v_n[i].norm_squared(),
                inertia.dot(&dx) - 0.5 * (force - force_n).dot(&dx),
                w_res,
            ]
        });
        energy.internal_work += w_int;
        energy.external_work += w_ext;
        energy.damping += w_damp;
        energy.contact_work += w_c;
        energy.boundary_work += w_bc;
        energy.residual_work += w_res;
        let counts = match &mut self.contact {
            Some(contact) => {
                let counts = contact.commit(&self.x, &state.x);
                energy.friction_dissipation = contact.friction_dissipation;
                // A node pressed on a tool moves with it along the normal:
                // Newmark's update would leave it the velocity it hit the
                // tool with (and an acceleration to match), and it would
                // bounce off at the next increment. The impact is
                // inelastic, as for fabric on steel; the kinetic energy it
                // takes is the integrator's, so it lands in the numerical
                // dissipation through ΔE_kin below.
                for &(node, tool, normal) in contact.pressed() {
                    let i = node as usize;
                    let axis = contact.tools[tool as usize].motion.direction();
                    let tool_v = axis * contact.tool_state[tool as usize].velocity;
                    let tool_a = axis * contact.tool_acceleration[tool as usize];
                    let dv = normal.dot(&(self.v[i] - tool_v));
                    let da = normal.dot(&(self.a[i] - tool_a));
                    for k in 0..3 {
                        if !self.fixed[3 * i + k] {
                            self.v[i][k] -= normal[k] * dv;
                            self.a[i][k] -= normal[k] * da;
                        }
                    }
                }
                counts
            }
            None => (0, 0, 0),
        };
        let ke = chunked_sum(n, |i| 0.5 * self.mass[i] * self.v[i].norm_squared());
        energy.numerical_dissipation += d_num - (ke - ke_n);
        energy.kinetic = ke;
        for ((c, s), k) in self.f_c_n.iter_mut().zip(&self.f_slip).zip(&self.f_con) {
            *c = s + k;
        }
        std::mem::swap(&mut state.x, &mut self.x);
        std::mem::swap(&mut state.v, &mut self.v);
        std::mem::swap(&mut self.acceleration, &mut self.a);
        std::mem::swap(&mut state.history, &mut self.forces.history_new);
        self.f_int_n.copy_from_slice(&self.forces.f_int);
        self.f_ext_n.copy_from_slice(&self.f_ext);
        state.time += h;
        state.step += 1;
        energy.balance_error =
            energy.kinetic + energy.internal_work + energy.damping + energy.numerical_dissipation
                - energy.external_work
                - energy.boundary_work
                - energy.contact_work
                - self.kinetic0;
        counts
    }

    /// Reactions at the constrained components, quasi-static part
    /// f_int − f_ext − f_contact: a constrained component takes the tools'
    /// force on its node too, so a clamp inside a pinch carries the
    /// friction there. (The explicit driver reports f_int − f_ext: its
    /// contact pass does not resolve friction along a prescribed
    /// component, see its `compute_reactions`.)
    fn compute_reactions(&mut self) {
        for r in self.reactions.iter_mut() {
            *r = Vector3::zeros();
        }
        for c in &self.constraints.list {
            let (i, k) = (c.node as usize, c.component as usize);
            self.reactions[i][k] = self.f_int_n[i][k] - self.f_ext_n[i][k] - self.f_c_n[i][k];
        }
    }
}
