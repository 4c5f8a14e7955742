//! Contact for the implicit driver: the paper's condensed multiplier solve
//! (SPEC §6 "Normal, implicit"; El Hami et al. eq. 22–27) with Coulomb
//! friction by return mapping.
//!
//! Per Newton iteration the driver has factorised its tangent K̂ and holds
//! the residual r (every force but the contact multipliers'). The
//! constraints are linearised at the current iterate: a normal row per
//! (node, tool) pair nearer than the broad-phase margin, g + n·Δx ≥ 0 (minus
//! (n·a)·Δd for a force-driven tool free along a); and, for a pair that
//! sticks, two tangential rows t·(s + Δx) = 0 that hold the node's slip s
//! relative to the tool over the increment at zero. With C those rows,
//!
//!   K̂·Δx = r + Cᵀλ,   C·Δx + g ≥ 0,   λ_N ≥ 0,   λ_N·(C·Δx + g)_N = 0,
//!
//! and Δx eliminated, λ solves the bound-constrained quadratic programme
//! min ½λᵀAλ + cᵀλ, λ_N ≥ 0, A = C·K̂⁻¹·Cᵀ, c = g + C·K̂⁻¹·r, whose gradient
//! Aλ + c is the linearised gap after the step. It is solved by MPRGP
//! (Dostál's modified proportioning with reduced gradient projections):
//! conjugate gradients on the free set, each iteration one product with A,
//! that is one forward/back solve with the factors, A never formed; a step
//! that would cross a bound is cut there and followed by a projected
//! gradient step, which adds or releases many constraints at once; a
//! proportioning step releases bound multipliers whose gradient asks for
//! it. It is chosen over the explicit pass's projected CG (Polyak's
//! active-set variant, which adds one constraint per restart) because a
//! forming increment opens and closes hundreds of contacts at once, and
//! MPRGP's rate is bounded by A's spectral condition alone, whatever the
//! active set does. The driver preconditions it
//! ([`ImplicitContact::solve_preconditioned`]): the rows are scaled by
//! √A_kk estimated from K̂'s nodal 3×3 blocks, A_kk ≈ c_kᵀ·K̂_ii⁻¹·c_k,
//! which is MPRGP with a Jacobi preconditioner in every face (the scaling
//! is positive, so the bounds stay λ_N ≥ 0). Rows of different kinds
//! (normal, regularised stick and slip-turn rows with their compliance,
//! rows coupled to a force-driven tool) differ in A_kk by orders of
//! magnitude; the scaling halved the products on the hemisphere 40 × 40
//! (107 340 → 55 767 to half the stroke). Then Δx = K̂⁻¹(r + Cᵀλ).
//!
//! The driver takes the regularised stick rows (and slip-turn rows) of a
//! node out of C and into K̂ as the springs they are
//! ([`ImplicitContact::set_springs_in_tangent`]): the same Newton step,
//! but A then holds the normal rows only (and rows coupled to a
//! force-driven tool's unknown). With the stick rows in A, where most of
//! the blank sticks (deep drawing: under the holder, on the die) A's stick
//! block was K̂⁻¹ of the sheet's membrane, as ill-conditioned as the sheet,
//! and the solves took hundreds to thousands of products. Deep drawing
//! ±45, 20 × 20, implicit, one core (user CPU): to t = 0.1 s the same
//! path and answer with 768 products instead of 4 739; the whole stroke
//! completes in 336 increments, 2 376 + 639 Newton iterations, 99 144
//! products and 41.5 s, where before it stopped at t = 0.34 s after
//! 900 s wall (179 s user CPU on a loaded machine; 535 increments,
//! 402 164 products, 49 of its 114 cutbacks "contact not converged").
//! The holder's unknown was not the cause: its compliance is negligible
//! next to the nodes' (10 kg). What stays: a node pinched between the
//! holder and the die has two normal rows ±n, and how much of the clamping
//! force each pinched node carries is indeterminate (A has one zero
//! eigenvalue per pinched node, 547 in that solve); the gradient's
//! component there was round-off (2e-11 and 4e-11 in the two solves
//! analysed), so conjugate gradients do not see it.
//!
//! The round-off floor (`RoundOff` in the source): at 40 × 40 (±45, shipped scene)
//! the solves stalled because they asked for less than the arithmetic
//! gives. A pinched node carries the clamping force (80–250 N a node
//! under 190 kN) on its rows ±n, which cancel in Cᵀλ to ε·F, an error of
//! ε·A_kk·F in the gaps, spread over the sheet by the solve with the
//! factors. Traced (the first stalled solve, t ≈ 0.05 s, 4 948 rows):
//! conjugate gradients reached 3.0e-12 mm in 39 products against the
//! tolerance of 1e-12 (1e-3 × the driver's gap tolerance), then the
//! residual grew again to 2e-9 (the null space's round-off in the
//! directions), a step hit a bound, and the rest of the 2 000 products
//! went in 52 such cycles, each releasing one row, ending at 1.3e-7.
//! The solve now also stops when every projected-gradient component is
//! within `ROUNDOFF` (100) × ε × the largest A_kk·Σ|λ| at a node (plus the
//! tool's and c's share). Deep drawing ±45, 40 × 40, implicit, one core:
//! before, t = 0.27 s after 1 500 s wall (54 cutbacks, 47 "contact not
//! converged"); now it completes: 369 increments, 2 461 + 162 Newton
//! iterations, 161 655 products, 77 cutbacks (50 contact indefinite,
//! 22 contact not converged, 3 friction chatter, 2 Newton limit),
//! 341 s user CPU. What is left: the 22 solves that still ran out are
//! not round-off (ε × the estimate 1e-15 … 5e-12 mm, residuals 5e-7 …
//! 1.4 mm): steps cut at a bound every few products (56–480 expansions
//! per solve, each releasing about one row), pinched nodes on the
//! holder's rounded edge (normals ±n tilted by a few degrees, so nearly
//! null directions) among the largest components; and the "contact
//! indefinite" cuts come in a regular rhythm (every fourth increment
//! from t = 0.275 s, as the increment grows), with 51 indefinite
//! factorisations in the same run: the tangent's, by the look of it
//! (compressed resin), not analysed further. Measured and not kept: the
//! expansion's projected step as a Jacobi step (ᾱ = 1 in the scaled
//! variables) cut by an exact line search on the segment, against
//! ᾱ = 1/‖A‖: deep drawing ±45
//! 20 × 20, 193 increments, 68 947 products, 39 cutbacks against 180,
//! 65 855 and 35.
//!
//! Measured and not kept (shipped hemisphere 40 × 40, 0/90, implicit, one
//! core; to t = 0.4 s the scaling above takes 25 124 CG steps, 28 609
//! products, 21.4 s of user CPU):
//! - FETI's lumped preconditioner, C·K̂·Cᵀ applied in the face: 59 265
//!   CG steps. It ignores that a contact node's in-plane freedom relieves
//!   the stiff fibres a normal push stretches on a curved tool.
//! - The diagonal from one level of K̂'s Schur complement,
//!   K̂_ii − Σ_j K̂_ij·K̂_jj⁻¹·K̂_ji, instead of K̂_ii: 24 128 (−4 %).
//! - A per-node 3 × 3 block of the estimate (normal and stick rows
//!   together, a triangular change of variables keeping λ_N ≥ 0): not
//!   built, since in that estimate a pair's rows are nearly uncoupled
//!   (|A_kl|/√(A_kk·A_ll) 0.014 on average, above 0.1 for 3 % of the row
//!   pairs): it would be this scaling.
//! - An inexact-Newton forcing term, the solve's tolerance times the
//!   Newton residual over the force tolerance (at least 1, at most 1e6,
//!   so exact where Newton converges): to t = 0.4 s the same path and
//!   answer with 13 796 CG steps (−45 %) and 17.2 s; but over the whole
//!   stroke the folding skirt took another path: 6 793 increments,
//!   1 374 cutbacks (776 friction chatter, 593 Newton limit), 1 054 s
//!   against 1 193, 215 and 322 s exact, the answer moved (max shear
//!   +0.38°, DD −0.47 mm, element shear RMS 0.51°), and
//!   the 10 × 10 agreement case (validate, quick) took 725 increments,
//!   4 668 + 1 908 Newton iterations and 137 176 products instead of 163,
//!   1 132 + 95 and 17 654: the friction return mapping reads the
//!   multipliers of the inexact solves. A cap of 1e3 saved 25 % to
//!   t = 0.4 s, not run further.
//!
//! Friction (SPEC §6): a sticking pair carries its tangential rows in the
//! same condensed system; after the solve, a stick force beyond μ·λ_N
//! turns the pair to slip, in the stick force's direction. A slipping pair
//! has no stick rows: the driver applies μ·λ_N as a force, with λ_N from
//! the last solve. A new contact starts sticking.
//!
//! The stick is regularised when `elastic_slip` δ > 0 (the driver's
//! default): a tangential spring k_t = μ·λ_N/δ from where the pair was at
//! tₙ carrying the friction force it had there, f_n, so that a stick row
//! holds t·(s + Δx) + (λ − t·f_n)/k_t = 0 (its compliance 1/k_t on A's
//! diagonal). The return mapping then uses the spring's trial force
//! f = f_n − k_t·s: inside the cone the pair sticks, outside it slides
//! with μ·λ_N along f — also at once when a pair becomes pressed (a new
//! contact's spring starts where it closed, so it sticks; a pair pressed
//! since tₙ that lifted off in the iterations is anchored at tₙ) — and a
//! slipping pair gets one row across its slip direction with the
//! stiffness of that direction's turn (see `linearise_rows`). The friction force is a continuous function of the
//! slip, so pairs at the edge of the cone do not cycle. With δ = 0 the
//! stick is rigid: a slipping pair slides along a direction fixed for the
//! increment and sticks again when its slip runs along its friction force
//! (reversal).
//!
//! A force-driven tool (a blank holder) is an extra unknown, its
//! displacement along its axis, with the same Newmark update as the nodes
//! and its mass as inertia; its rows couple it to every node it touches.
//!
//! The active-set alternative (`contact_solver = "active_set"`) shares the
//! pairs, rows, friction and tools, and replaces the condensed solve by
//! the held rows of a saddle-point system: see `implicit/active_set.rs`.
//!
//! What it is not: no assembly, no factorisation, no time loop; the driver
//! owns those and hands the pass a solve with its factors.
//!
//! Here: the pairs, their linearisation and friction. The condensed solve
//! and the start's acceleration are in `condensed`, MPRGP in `mprgp`, the
//! active-set solver's rows in `active_set`.

use nalgebra::{Matrix3, Vector3};

use crate::explicit::ContactStatus;
use crate::tool::{Tool, ToolMotion, ToolState};

/// Times and Newmark parameters of one increment (the Bossak–Newmark
/// scheme of the implicit driver): a_{n+1} = (Δu − h·vₙ)/(β·h²) −
/// (1/(2β) − 1)·aₙ, v_{n+1} = vₙ + h·((1 − γ)·aₙ + γ·a_{n+1}), and the
/// inertia of the equation M·((1 − α_m)·a_{n+1} + α_m·aₙ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Increment {
    /// t_{n+1} (s).
    pub t_new: f64,
    /// h = t_{n+1} − tₙ (s).
    pub h: f64,
    /// Newmark β.
    pub beta: f64,
    /// Newmark γ.
    pub gamma: f64,
    /// Bossak α_m (≤ 0).
    pub alpha_m: f64,
}

impl Increment {
    /// ∂(inertia)/∂u per unit mass: (1 − α_m)/(β·h²).
    pub fn mass_factor(&self) -> f64 {
        (1.0 - self.alpha_m) / (self.beta * self.h * self.h)
    }

    /// a_{n+1} from the increment's displacement `du` and vₙ, aₙ.
    pub fn acceleration<T>(&self, du: T, v: T, a: T) -> T
    where
        T: Copy + std::ops::Sub<Output = T> + std::ops::Mul<f64, Output = T>,
    {
        let h = self.h;
        (du - v * h) * (1.0 / (self.beta * h * h)) - a * (0.5 / self.beta - 1.0)
    }

    /// v_{n+1} from vₙ, aₙ and a_{n+1}.
    pub fn velocity<T>(&self, v: T, a: T, a_new: T) -> T
    where
        T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
    {
        v + (a * (1.0 - self.gamma) + a_new * self.gamma) * self.h
    }

    /// The Bossak inertia weight: (1 − α_m)·a_{n+1} + α_m·aₙ.
    pub fn inertia<T>(&self, a: T, a_new: T) -> T
    where
        T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
    {
        a_new * (1.0 - self.alpha_m) + a * self.alpha_m
    }
}

/// A stick force may exceed μ·λ_N by this fraction before the pair slips:
/// the multipliers come from an iterative solve, and a node held exactly at
/// the friction angle must not chatter between stick and slip on
/// round-off.
const CONE_SLACK: f64 = 1e-6;

/// A slip shorter than this many times the solve's tolerance is noise: it
/// neither reverses a slipping pair nor sets its direction.
const SLIP_NOISE: f64 = 1e3;

/// Settings of the implicit contact pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImplicitContactSettings {
    /// Distance of the fabric's mid-surface from a tool at contact: half
    /// the thickness (mm).
    pub offset: f64,
    /// Pairs nearer a tool than this take part in the solve (mm).
    pub margin: f64,
    /// Largest linearised gap violation (and stick slip) the condensed
    /// solve leaves (mm).
    pub tolerance: f64,
    /// Products with A (solves with the factors) allowed per solve.
    pub max_iterations: usize,
    /// Elastic slip at the friction limit (mm): a sticking pair is held by
    /// a tangential spring of stiffness k_t = μ·λ_N/`elastic_slip` rather
    /// than rigidly (0: rigid stick), stiffer if the node's inertia asks for
    /// it ([`STICK_OVER_INERTIA`]), so the elastic slip is at most this.
    /// See [`ImplicitContact::update_friction`].
    pub elastic_slip: f64,
    /// Whether a node pinched between two tools whose normals lean inside
    /// their friction (sin θ < μ₁ + μ₂) has them made opposite (see
    /// `ImplicitContact::square_pinches`): the active-set solver's
    /// Newton iteration, whose slip forces lag behind λ_N, needs it; the
    /// condensed solve (the reference) converges on the lean.
    pub square_friction_leans: bool,
}

impl Default for ImplicitContactSettings {
    fn default() -> Self {
        Self {
            offset: 0.0,
            margin: 5.0,
            tolerance: 1e-10,
            max_iterations: 2000,
            elastic_slip: 0.0,
            square_friction_leans: false,
        }
    }
}

/// Friction state of a pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Friction {
    /// Held by tangential constraints.
    Stick,
    /// Sliding against μ·λ_N.
    Slip,
}

/// A (node, tool) pair near contact, with its multipliers and friction
/// state.
#[derive(Debug, Clone, Copy)]
struct Pair {
    tool: u32,
    node: u32,
    /// Normal force λ_N (N) of the last solve.
    lambda: f64,
    /// Tangential force of the stick rows on the node (N).
    stick: Vector3<f64>,
    /// Unit direction of the friction force on the node when slipping.
    slip_direction: Vector3<f64>,
    friction: Friction,
    /// Linearisation: outward normal, gap beyond the offset, tangential
    /// slip over the increment relative to the tool.
    normal: Vector3<f64>,
    gap: f64,
    slip: Vector3<f64>,
    /// Whether the rows include this pair's stick rows.
    stick_rows: bool,
    /// Where the node and the tool were at tₙ if the pair was pressed then,
    /// or where it closed in this increment: the stick rows hold the slip
    /// from there at zero.
    anchor: Vector3<f64>,
    anchor_tool: f64,
    /// Pressed at tₙ (carried from the last increment).
    since_start: bool,
    /// Tangential friction force on the node at tₙ (N): where the
    /// tangential spring of a regularised stick starts the increment.
    force_n: Vector3<f64>,
    /// k_t of a regularised stick (N/mm), fixed from the first λ_N the
    /// pair needs it with in the increment (0: not yet), so that the
    /// spring is linear over the increment and Newton converges on it.
    stick_stiffness: f64,
    /// |f_n − k_t·s| at the last return mapping of a regularised slip
    /// (N; 0: not yet mapped in this increment).
    trial: f64,
    /// The active-set solver's normal multiplier, with its sign (λ_N is
    /// this clamped at zero): what decides the next active set.
    multiplier: f64,
    /// Whether the active-set solver's last system held the normal row as
    /// an equality.
    active: bool,
    /// The normal row's linearised gap after the last active-set system
    /// (the gap at the linearisation before one).
    predicted: f64,
    /// λ_N before the last solve (for [`ImplicitContact::slip_lag`]).
    lambda_before: f64,
    /// Its normal was turned to be exactly opposite another tool's (see
    /// [`ImplicitContact::square_pinches`]): not a flat face's.
    squared: bool,
}

impl Pair {
    /// The node's slip from its anchor at position `x` with its tool at
    /// `tool` along `axis`, tangential to the pair's normal (mm).
    fn tangential_slip(&self, x: Vector3<f64>, tool: f64, axis: Vector3<f64>) -> Vector3<f64> {
        let s = x - self.anchor - axis * (tool - self.anchor_tool);
        s - self.normal * self.normal.dot(&s)
    }

    /// k_t of the pair's regularised stick: fixed at its first use in the
    /// increment, from the friction limit μ·λ_N it has then (see
    /// [`stick_stiffness`]), so the spring is linear over the increment.
    fn stick_spring(
        &mut self,
        mu: f64,
        elastic_slip: f64,
        mass: &[f64],
        inc: Option<Increment>,
    ) -> f64 {
        if self.stick_stiffness == 0.0 {
            self.stick_stiffness = stick_stiffness(
                mu * self.lambda,
                elastic_slip,
                mass.get(self.node as usize).copied(),
                inc,
            );
        }
        self.stick_stiffness
    }

    /// The regularised stick's trial force f = f_n − k_t·s at the node's
    /// position `x` with its tool at `tool` along `axis` (s: the slip from
    /// the anchor, tangential to the pair's normal).
    #[allow(clippy::too_many_arguments)]
    fn trial_force(
        &mut self,
        x: Vector3<f64>,
        tool: f64,
        axis: Vector3<f64>,
        mu: f64,
        elastic_slip: f64,
        mass: &[f64],
        inc: Option<Increment>,
    ) -> Vector3<f64> {
        let slip = self.tangential_slip(x, tool, axis);
        let f_n = self.force_n - self.normal * self.normal.dot(&self.force_n);
        f_n - slip * self.stick_spring(mu, elastic_slip, mass, inc)
    }
}

/// A pair's state carried from one increment to the next (and through a
/// checkpoint).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CarriedPair {
    /// Tool index.
    pub tool: u32,
    /// Node index.
    pub node: u32,
    /// Normal force (N).
    pub lambda: f64,
    /// Tangential stick force on the node (N).
    pub stick: [f64; 3],
    /// Friction direction when slipping.
    pub slip_direction: [f64; 3],
    /// Friction state.
    pub friction: Friction,
}

/// One row of C.
#[derive(Debug, Clone, Copy)]
struct Row {
    pair: u32,
    /// The row on the node's three components.
    direction: Vector3<f64>,
    /// On the tool's displacement (force-driven tools only).
    tool_coefficient: f64,
    /// The row's value now: a gap, or a stick slip component (mm).
    target: f64,
    /// λ ≥ 0 (normal) or free (tangential).
    bounded: bool,
    /// 1/k_t of a regularised stick row (0 otherwise): the row holds
    /// t·(s + Δx) + (λ − t·f_n)/k_t = 0.
    compliance: f64,
}

impl Row {
    /// A compliant row on its node alone (no tool unknown in it): a
    /// spring the driver can put into K̂. A tangent of a force-driven
    /// tool's flat face is across its axis up to round-off of the face's
    /// normal (20 × 20 deep drawing: 142 holder pairs kept their rows with
    /// an exact test); a coupling of at most [`SPRING_COUPLING`] is
    /// dropped, a change of that relative order in the step.
    fn is_spring(&self) -> bool {
        !self.bounded && self.compliance > 0.0 && self.tool_coefficient.abs() <= SPRING_COUPLING
    }
}

/// The largest coupling |t·a| of a compliant row to a force-driven tool's
/// axis a that still makes it a spring in K̂ (see [`Row::is_spring`]).
const SPRING_COUPLING: f64 = 1e-12;

/// What a condensed solve did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SolveStats {
    /// Products with A (one solve with the factors each), power iterations
    /// for the projection step included.
    pub iterations: usize,
    /// Rows of C.
    pub rows: usize,
    /// Normal rows with λ > 0.
    pub active: usize,
    /// Largest projected-gradient component left (mm).
    pub residual: f64,
    /// Of the products: conjugate gradient steps on the free set.
    pub cg_steps: usize,
    /// Expansion steps (a step cut at a bound, then a projected gradient
    /// step): two products each.
    pub expansions: usize,
    /// Proportioning steps (bound multipliers released).
    pub proportionings: usize,
    /// Products spent estimating ‖A‖ for the projected gradient step.
    pub norm_products: usize,
    /// Normal rows whose multiplier changed from zero to positive or back
    /// against the warm start.
    pub active_changes: usize,
    /// The solve stopped at the round-off floor of its gradient (above the
    /// tolerance; see `RoundOff` in the source).
    pub at_roundoff: bool,
    /// Of the solves summed: how many stopped at the round-off floor.
    pub roundoff_stops: usize,
}

impl SolveStats {
    /// Adds `other`'s counts to these; rows, active and residual become
    /// `other`'s.
    fn add(&mut self, other: &Self) {
        self.iterations += other.iterations;
        self.cg_steps += other.cg_steps;
        self.expansions += other.expansions;
        self.proportionings += other.proportionings;
        self.norm_products += other.norm_products;
        self.active_changes += other.active_changes;
        self.roundoff_stops += usize::from(other.at_roundoff);
        self.rows = other.rows;
        self.active = other.active;
        self.residual = other.residual;
    }
}

/// The condensed solve did not converge, or met a direction of
/// non-positive curvature (an indefinite tangent).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// Iterations ran out.
    #[error(
        "condensed contact solve did not converge in {iterations} iterations (residual {residual:.3e} mm)"
    )]
    NoConvergence {
        /// Iterations used.
        iterations: usize,
        /// Residual left (mm).
        residual: f64,
    },
    /// pᵀ·A·p ≤ 0.
    #[error("condensed contact operator not positive definite (indefinite tangent)")]
    Indefinite,
}

/// The implicit contact pass: tools, their states, the pairs of the
/// current increment and the outputs of the last committed one.
#[derive(Debug, Clone)]
pub struct ImplicitContact {
    /// The tools.
    pub tools: Vec<Tool>,
    /// Committed displacement and velocity of each tool along its axis.
    pub tool_state: Vec<ToolState>,
    /// Committed acceleration of each tool along its axis.
    pub tool_acceleration: Vec<f64>,
    /// The settings.
    pub settings: ImplicitContactSettings,
    /// Contact force on each node at the last committed increment (N).
    pub force: Vec<Vector3<f64>>,
    /// Each node's status there.
    pub status: Vec<ContactStatus>,
    /// Which tool each node touched (u32::MAX for none).
    pub tool_of: Vec<u32>,
    /// Normal force of each tool on the fabric (N, along the axis of a
    /// moving tool, magnitude otherwise).
    pub tool_force: Vec<f64>,
    /// Friction dissipated so far (mJ).
    pub friction_dissipation: f64,
    increment: Option<Increment>,
    /// Solving for the initial accelerations: a tool's residual is its
    /// applied force, its stiffness its mass.
    initial: bool,
    trial: Vec<f64>,
    tool_step: Vec<f64>,
    candidates: Vec<Vec<u32>>,
    pairs: Vec<Pair>,
    next_pairs: Vec<Pair>,
    carried: Vec<CarriedPair>,
    /// (node, tool, normal) of the pairs pressing at the last commit.
    pressed: Vec<(u32, u32, Vector3<f64>)>,
    /// A normal force below this carries no friction (N): see
    /// [`Self::set_force_floor`].
    force_floor: f64,
    rows: Vec<Row>,
    /// Compliant rows (regularised stick and slip-turn rows on a node
    /// alone) that the driver puts into K̂ as springs instead: see
    /// [`Self::set_springs_in_tangent`].
    springs: Vec<Row>,
    springs_in_tangent: bool,
    scratch: Scratch,
    /// Nodal masses for the regularised stick's inertia floor (empty: none).
    mass: Vec<f64>,
    /// Sums of the condensed solves' counts so far (rows, active and
    /// residual: of the last solve).
    solve_totals: SolveStats,
    /// Bumped when an increment's candidates differ from the last one's:
    /// the active-set system's pattern follows them.
    candidate_generation: u64,
    /// The candidates of one tool being gathered.
    candidate_scratch: Vec<u32>,
}

#[derive(Debug, Clone, Default)]
struct Scratch {
    lambda: Vec<f64>,
    c: Vec<f64>,
    g: Vec<f64>,
    p: Vec<f64>,
    ap: Vec<f64>,
    phi: Vec<f64>,
    w: Vec<f64>,
    tool_w: Vec<f64>,
    /// Row scaling of the preconditioned solve.
    scale: Vec<f64>,
    /// Per tool: its stiffness along its axis, and work for its forces.
    tool_stiffness: Vec<f64>,
    tool_f: Vec<f64>,
    /// Whether each row is bounded (λ ≥ 0).
    bounded: Vec<bool>,
    /// The round-off estimate's inputs and work.
    roundoff: RoundOff,
}

/// A regularised stick's spring is at least this many times the node's
/// inertia stiffness m·(1 − α_m)/(β·h²): its tangential vibration
/// (ω² = k_t/m) is then beyond what the increment resolves (ω·h ≥ 14 with
/// ρ∞ = 0), where the Bossak scheme removes it, and a node that lands and
/// sticks does not ring on the spring. Measured: without it a blank
/// dropped on a plane (μ = 0.5, 1e-3 N per node) still rang with 0.9 % of
/// the applied force at the end of the no-penetration case.
pub const STICK_OVER_INERTIA: f64 = 100.0;

/// Two tools' normals at a node within this of opposite (1 + cos θ; θ ≤
/// 1.4e-3 rad, 7 µm onto a 5 mm round) are made exactly opposite (see
/// `ImplicitContact::square_pinches`), and so are those whose lean is
/// inside the two tools' friction (sin θ < μ₁ + μ₂).
pub const PINCH: f64 = 1e-6;

/// A normal within this of a tool's axis (1 − cos θ; θ ≤ 4.5e-5 rad), or
/// two tools' normals within this of opposite, are a flat face's, or two
/// flat faces' pinching a node.
pub const FLAT: f64 = 1e-9;

/// The inertia floor never stiffens a regularised stick beyond
/// μ·λ_N over this slip (mm): a slipping pair's direction turns by
/// k_t·Δs/|f|, and with k_t unbounded (the floor grows as 1/h² when
/// increments are cut) the Δs that carries the turn fell below the
/// positions' round-off and Newton stalled (the capstan and
/// no-penetration cases at h ≈ 1e-11 s).
///
/// 1e-4 mm, not 1e-6 mm as it was: at μ·λ_N/1e-6 mm a slipping pair's
/// trial force f_n − k_t·s swung by more than μ·λ_N with each Newton
/// correction. Traced on the hemisphere-ring scene (10 × 10), node 82 at
/// t = 0.664 s, h = 1.06e-5 s (k_t ≈ 6e6 N/mm for μ·λ_N = 5.9 N): its slip
/// direction alternated between (0.37, 0.78, −0.51) and (0.05, −0.83,
/// 0.55) for 20 iterations with corrections of 2e-5 mm, the residual stuck
/// at 6 N of 185, and the cut attempt stiffened the spring further (720 of
/// that run's 875 cutbacks hit the iteration limit). Measured (one core,
/// user CPU, elastic slip 1 µm): that scene 5 094 increments and 52.7 s at
/// 1e-6 mm, 721 and 23.3 s at 1e-4 mm, 488 and 14.1 s without the floor;
/// but without it a blank dropped on a plane rings (no-penetration
/// balance at rest 8.9e-3 of the load against a tolerance of 1e-3; 3.8e-4
/// at 1e-4 mm, 3.9e-7 at 1e-6 mm).
///
/// It is a slip, not a multiple of the elastic slip (it was 1/10 of it at
/// 1 µm), so a softer stick keeps the floor that stops a landing node
/// ringing: at an elastic slip of 10 µm a floor of 1/10 of it rang (the
/// plane's balance at rest 8.9e-3) and slowed the shipped hemisphere-0-90
/// by a quarter (185 increments against 140).
const STIFFEST_FLOOR_SLIP: f64 = 1e-4;

/// k_t of a regularised stick: μ·λ_N/δ for a pair at the friction limit
/// `cone` = μ·λ_N and elastic slip δ, and at least
/// [`STICK_OVER_INERTIA`] times the node's inertia stiffness when its
/// `mass` is known, up to μ·λ_N/[`STIFFEST_FLOOR_SLIP`].
fn stick_stiffness(cone: f64, elastic_slip: f64, mass: Option<f64>, inc: Option<Increment>) -> f64 {
    let inertia = match (mass, inc) {
        (Some(m), Some(inc)) => STICK_OVER_INERTIA * m * inc.mass_factor(),
        _ => 0.0,
    };
    let k = cone / elastic_slip;
    k.max(inertia.min(cone / STIFFEST_FLOOR_SLIP))
}

/// Two unit tangents of the plane normal to `n`.
fn tangents(n: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let e = if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let t1 = (e - n * n.dot(&e)).normalize();
    [t1, n.cross(&t1)]
}

impl ImplicitContact {
    /// The regularised stick rows' forces on their pairs, from the step
    /// `dx` (both solvers: the condensed one and the active set).
    fn add_spring_sticks(&mut self, dx: &[f64]) {
        for row in &self.springs {
            let pair = &mut self.pairs[row.pair as usize];
            let i = 3 * pair.node as usize;
            let t = row.direction;
            let along = t.x * dx[i] + t.y * dx[i + 1] + t.z * dx[i + 2];
            pair.stick -= t * ((row.target + along) / row.compliance);
        }
    }

    /// A pass over `node_count` nodes.
    pub fn new(tools: Vec<Tool>, node_count: usize, settings: ImplicitContactSettings) -> Self {
        let t = tools.len();
        Self {
            tool_state: vec![ToolState::default(); t],
            tool_acceleration: vec![0.0; t],
            tools,
            settings,
            force: vec![Vector3::zeros(); node_count],
            status: vec![ContactStatus::Open; node_count],
            tool_of: vec![u32::MAX; node_count],
            tool_force: vec![0.0; t],
            friction_dissipation: 0.0,
            increment: None,
            initial: false,
            trial: vec![0.0; t],
            tool_step: vec![0.0; t],
            candidates: vec![Vec::new(); t],
            pairs: Vec::new(),
            next_pairs: Vec::new(),
            carried: Vec::new(),
            pressed: Vec::new(),
            force_floor: 0.0,
            rows: Vec::new(),
            springs: Vec::new(),
            springs_in_tangent: false,
            scratch: Scratch::default(),
            mass: Vec::new(),
            solve_totals: SolveStats::default(),
            candidate_generation: 0,
            candidate_scratch: Vec::new(),
        }
    }

    /// The nodal masses: a regularised stick's spring is then at least
    /// [`STICK_OVER_INERTIA`] times the node's inertia stiffness in the
    /// increment (see [`ImplicitContactSettings::elastic_slip`]).
    pub fn set_mass(&mut self, mass: &[f64]) {
        self.mass = mass.to_vec();
    }

    /// The pass's outputs, as a frame shows them.
    pub fn view(&self) -> crate::ContactView<'_> {
        crate::ContactView {
            tools: &self.tools,
            tool_state: &self.tool_state,
            force: &self.force,
            status: &self.status,
            tool_of: &self.tool_of,
            tool_force: &self.tool_force,
            friction_dissipation: self.friction_dissipation,
            plies: None,
        }
    }

    /// The pairs in contact at the last committed increment, for a
    /// checkpoint.
    pub fn carried(&self) -> &[CarriedPair] {
        &self.carried
    }

    /// (node, tool, outward normal) of every pair pressing at the last
    /// committed increment.
    pub fn pressed(&self) -> &[(u32, u32, Vector3<f64>)] {
        &self.pressed
    }

    /// Restores the carried pairs, tools and outputs of a checkpoint.
    pub fn restore(
        &mut self,
        carried: Vec<CarriedPair>,
        tools: &[ToolState],
        tool_acceleration: &[f64],
        friction_dissipation: f64,
    ) {
        self.carried = carried;
        self.tool_state.copy_from_slice(tools);
        self.tool_acceleration.copy_from_slice(tool_acceleration);
        self.friction_dissipation = friction_dissipation;
        self.write_outputs_from_carried();
    }

    fn write_outputs_from_carried(&mut self) {
        self.force.iter_mut().for_each(|f| *f = Vector3::zeros());
        self.status
            .iter_mut()
            .for_each(|s| *s = ContactStatus::Open);
        self.tool_of.iter_mut().for_each(|t| *t = u32::MAX);
        self.tool_force.iter_mut().for_each(|f| *f = 0.0);
        for c in &self.carried {
            let i = c.node as usize;
            self.tool_of[i] = c.tool;
            self.status[i] = match c.friction {
                Friction::Slip => ContactStatus::Slip,
                Friction::Stick => ContactStatus::Stick,
            };
        }
    }

    /// Normal forces up to `floor` (N) are round-off of the driver's
    /// equilibrium: such a pair gets neither stick rows nor a slip force
    /// (its friction would be at most μ·floor, below what the driver's
    /// convergence test resolves), so that a node touching with nothing to
    /// press it does not flip between stick and slip.
    pub fn set_force_floor(&mut self, floor: f64) {
        self.force_floor = floor;
    }

    /// With `on`, a compliant row that couples a node to nothing else (a
    /// regularised stick row or a slip-turn row, of a fixed or prescribed
    /// tool or across a force-driven tool's axis) leaves the condensed
    /// system: it is a spring k = 1/compliance along its direction, which
    /// the caller adds to K̂ before factorising
    /// ([`Self::add_spring_stiffness`]); the solve puts its force at the
    /// iterate into the right-hand side and returns its multiplier
    /// λ = −k·(target + t·Δx). The Newton step is the same (the two are
    /// the dual and primal forms of one quadratic programme), but A then
    /// holds only the normal rows and the rows coupled to a tool's
    /// unknown.
    ///
    /// Why: a node that sticks carries two tangential rows, and where most
    /// of the blank sticks (under a blank holder, on the die) those rows
    /// cover nearly every in-plane freedom, so A's stick block is K̂⁻¹ of
    /// the sheet's membrane, as ill-conditioned as the sheet (stiff yarns,
    /// nearly free shear), and a node pinched between the holder and the
    /// die has two such pairs of rows acting on the same freedoms. Deep
    /// drawing ±45 at 20 × 20, a solve at t ≈ 0.2 s (2 851 rows, dumped and
    /// analysed densely): A's free face, scaled by the estimated diagonal,
    /// spans 5e-4 … 7.2e3 (and 547 zero eigenvalues: the clamping force
    /// of a pinched node between the two tools is indeterminate), the
    /// stick rows' true A_kk up to 78 × the estimate; that solve used its
    /// 2 000 products without converging. With the stick rows as springs
    /// the normal rows' operator spans 0.1 … 105 (the 547 zero ones
    /// stay) and conjugate gradients from the same start reach 1e-11 mm
    /// in 89 steps, against 537–1 598 with the rows and a diagonal,
    /// block-diagonal (per node) or exact-diagonal scaling.
    pub fn set_springs_in_tangent(&mut self, on: bool) {
        self.springs_in_tangent = on;
    }

    /// Adds the springs of the last linearisation (see
    /// [`Self::set_springs_in_tangent`]) to K̂ through `add(node, block)`:
    /// k·t·tᵀ on the node's 3 × 3 diagonal block, k = 1/compliance.
    pub fn add_spring_stiffness(&self, mut add: impl FnMut(usize, &Matrix3<f64>)) {
        for row in &self.springs {
            let node = self.pairs[row.pair as usize].node as usize;
            let t = row.direction;
            add(node, &(t * t.transpose() / row.compliance));
        }
    }

    /// Whether any tool is a force-driven rigid body.
    fn has_free_tools(&self) -> bool {
        self.tools.iter().any(Tool::is_force_driven)
    }

    /// The tools' trial displacements of the current increment.
    pub fn trial_displacements(&self) -> &[f64] {
        &self.trial
    }

    /// Starts an increment: prescribed tools move to t_{n+1}, a
    /// force-driven one to its constant-acceleration predictor; the
    /// candidates are the nodes inside each tool's box grown by the margin
    /// at the predicted positions `x`.
    pub fn begin(&mut self, x: &[Vector3<f64>], movable: &[bool], increment: Increment) {
        self.increment = Some(increment);
        let h = increment.h;
        for (t, tool) in self.tools.iter().enumerate() {
            let s = self.tool_state[t];
            self.trial[t] = match tool.prescribed_displacement(increment.t_new) {
                Some(d) => d,
                None => s.displacement + h * s.velocity + 0.5 * h * h * self.tool_acceleration[t],
            };
        }
        let reach = self.settings.margin + self.settings.offset;
        for (t, tool) in self.tools.iter().enumerate() {
            let shift = tool.motion.direction() * self.trial[t];
            let aabb = tool.surface.aabb().translated(&shift).grown(reach);
            let mut next = std::mem::take(&mut self.candidate_scratch);
            next.clear();
            next.extend(
                (0..x.len() as u32)
                    .filter(|&i| movable[i as usize] && aabb.contains(&x[i as usize])),
            );
            if next != self.candidates[t] {
                std::mem::swap(&mut next, &mut self.candidates[t]);
                self.candidate_generation += 1;
            }
            self.candidate_scratch = next;
        }
        self.pairs.clear();
    }

    /// The residual of each force-driven tool's equation at its trial
    /// displacement, without contact: F·a(t) − M·inertia.
    fn tool_residual(&self, t: usize) -> f64 {
        let inc = self.increment.expect("an increment has begun");
        match &self.tools[t].motion {
            ToolMotion::Force {
                force,
                amplitude,
                mass,
                ..
            } => {
                if self.initial {
                    return force * amplitude.value(inc.t_new);
                }
                let s = self.tool_state[t];
                let a0 = self.tool_acceleration[t];
                let a = inc.acceleration(self.trial[t] - s.displacement, s.velocity, a0);
                force * amplitude.value(inc.t_new) - mass * inc.inertia(a0, a)
            }
            _ => 0.0,
        }
    }

    /// The effective stiffness of a force-driven tool's unknown.
    fn tool_stiffness(&self, t: usize) -> f64 {
        let inc = self.increment.expect("an increment has begun");
        match &self.tools[t].motion {
            ToolMotion::Force { mass, .. } => mass * inc.mass_factor(),
            _ => f64::INFINITY,
        }
    }

    /// Linearises the contact at the iterate `x` (committed positions
    /// `x_n`): pairs nearer than the margin, their gaps, normals and slips,
    /// the rows of C. Friction states and multipliers carry over from the
    /// last linearisation, or from the last increment.
    pub fn linearise(&mut self, x: &[Vector3<f64>], x_n: &[Vector3<f64>]) {
        let offset = self.settings.offset;
        let margin = self.settings.margin;
        let mut next = std::mem::take(&mut self.next_pairs);
        next.clear();
        let (mut old, mut carried) = (0usize, 0usize);
        for (t, tool) in self.tools.iter().enumerate() {
            let axis = tool.motion.direction();
            let d = self.trial[t];
            for &i in &self.candidates[t] {
                let iu = i as usize;
                let p = tool.project(&x[iu], d);
                let gap = p.gap - offset;
                if gap >= margin {
                    continue;
                }
                let key = (t as u32, i);
                while old < self.pairs.len() && (self.pairs[old].tool, self.pairs[old].node) < key {
                    old += 1;
                }
                while carried < self.carried.len()
                    && (self.carried[carried].tool, self.carried[carried].node) < key
                {
                    carried += 1;
                }
                let mut pair = Pair {
                    tool: t as u32,
                    node: i,
                    lambda: 0.0,
                    stick: Vector3::zeros(),
                    slip_direction: Vector3::zeros(),
                    friction: Friction::Stick,
                    normal: p.normal,
                    gap,
                    slip: Vector3::zeros(),
                    stick_rows: false,
                    anchor: x[iu],
                    anchor_tool: d,
                    since_start: false,
                    force_n: Vector3::zeros(),
                    stick_stiffness: 0.0,
                    trial: 0.0,
                    multiplier: 0.0,
                    active: false,
                    predicted: gap,
                    lambda_before: 0.0,
                    squared: false,
                };
                if old < self.pairs.len() && (self.pairs[old].tool, self.pairs[old].node) == key {
                    let o = &self.pairs[old];
                    pair.lambda = o.lambda;
                    pair.stick = o.stick;
                    pair.slip_direction = o.slip_direction;
                    pair.friction = o.friction;
                    pair.anchor = o.anchor;
                    pair.anchor_tool = o.anchor_tool;
                    pair.since_start = o.since_start;
                    pair.force_n = o.force_n;
                    pair.stick_stiffness = o.stick_stiffness;
                    pair.trial = o.trial;
                    pair.multiplier = o.multiplier;
                    pair.active = o.active;
                    pair.lambda_before = o.lambda_before;
                } else if carried < self.carried.len()
                    && (self.carried[carried].tool, self.carried[carried].node) == key
                {
                    // In contact since tₙ: its slip counts from there.
                    let c = &self.carried[carried];
                    pair.lambda = c.lambda;
                    pair.stick = Vector3::from(c.stick);
                    pair.slip_direction = Vector3::from(c.slip_direction);
                    pair.friction = c.friction;
                    pair.anchor = x_n[iu];
                    pair.anchor_tool = self.tool_state[t].displacement;
                    pair.since_start = true;
                    pair.multiplier = c.lambda;
                    pair.active = c.lambda > 0.0;
                    let mu = tool.friction;
                    pair.force_n = match c.friction {
                        Friction::Stick => pair.stick,
                        Friction::Slip => pair.slip_direction * (mu * c.lambda),
                    };
                }
                pair.slip = pair.tangential_slip(x[iu], d, axis);
                next.push(pair);
            }
        }
        self.next_pairs = std::mem::replace(&mut self.pairs, next);
        self.square_pinches(x);
        self.linearise_rows();
    }

    /// Makes the normals of a node pinched between two tools exactly
    /// opposite, ±(n₁ − n₂)/|n₁ − n₂|, where they are within [`PINCH`] of
    /// it, and marks the pairs `squared` where they were not within
    /// [`FLAT`] (two flat faces' normals, which differ by round-off, are
    /// made exactly opposite too, so that the clamp sharing moves no
    /// force).
    ///
    /// Why: where a holder's flat face meets its rounded edge and a die's
    /// flat face its fillet, the two normals at a node just onto the
    /// rounds lean the same way by θ (measured: 5e-6 to 4e-5 rad on the
    /// shipped hemisphere-ring). The two rows then resist a tangential
    /// force f through their leaning, λ₁ + λ₂ = f/θ, and the system's
    /// multipliers came out at −5·10⁴ N on a 45 N clamp: both rows left
    /// the set, came back, and the active-set solve cycled until the
    /// increment was cut to 2e-9 s. A fabric is not a rigid wedge (it
    /// compresses through its thickness long before it carries f/θ);
    /// turning each normal by at most θ changes its row's force direction
    /// by that angle, and the gaps are still the distances to the tools.
    ///
    /// With friction, for the active-set solver
    /// ([`ImplicitContactSettings::square_friction_leans`]), the lean is
    /// squared further, while sin θ < μ₁ + μ₂ (the two tools'
    /// coefficients): there its Newton iteration does not converge on the
    /// lean. The slip forces lag one iteration behind λ_N
    /// (see the `active_set` module), so the rows' lean must carry what
    /// the lagged friction misses, λ·sin θ = f − (μ₁ + μ₂)·λ_before: a
    /// fixed-point iteration of gain (μ₁ + μ₂)/sin θ. Measured on the
    /// shipped deep-drawing-0-90 (active set): nodes under the holder's
    /// rounded inner edge, pinched on the flat die at leans of 0.01–0.09
    /// rad, took up to 4.5·10⁴ N of the holder's 1.9·10⁵ N in one
    /// iteration; its ~1 000 other rows came out negative to keep its
    /// total, left the set together, and the attempt cycled until it was
    /// cut (22 of the run's 26 cutbacks). Squared there: 10 cutbacks and
    /// 1 017 factorisations against 1 712, the same answer (48.10°, draw-in
    /// DX 42.23 mm, DD 7.64 mm). Inside the friction cone the lean's
    /// tangential share is no more than what friction can carry. The
    /// condensed solve settles the multipliers exactly at every iteration
    /// (λ ≥ 0 held inside it), so it does not cycle on the lean; squared
    /// there, its rows are dependent and their share open, and it lost
    /// (the 20 × 20 hemisphere-ring: 3 666 → 7 815 factorisations).
    ///
    /// A squared pair is not a flat face's: the tools part there, so the
    /// node may have more room than the clamp on the flat faces, and the
    /// active-set solve's clamp sharing leaves it to the system.
    fn square_pinches(&mut self, x: &[Vector3<f64>]) {
        let pairs = &mut self.pairs;
        let mut start = 0;
        for t in 0..self.tools.len() {
            let end = pairs.partition_point(|p| (p.tool as usize) <= t);
            let mut other = end;
            for u in t + 1..self.tools.len() {
                let other_end = pairs.partition_point(|p| (p.tool as usize) <= u);
                for k in start..end {
                    let Ok(j) =
                        pairs[other..other_end].binary_search_by_key(&pairs[k].node, |q| q.node)
                    else {
                        continue;
                    };
                    let j = other + j;
                    let cosine = pairs[k].normal.dot(&pairs[j].normal);
                    // sin θ of the lean (the normals within 90° of opposite).
                    let lean = pairs[k].normal.cross(&pairs[j].normal).norm();
                    let friction = self.tools[t].friction + self.tools[u].friction;
                    let pinched = cosine < -1.0 + PINCH
                        || (self.settings.square_friction_leans && cosine < 0.0 && lean < friction);
                    if !pinched || pairs[k].normal == -pairs[j].normal {
                        continue;
                    }
                    let squared = cosine > -1.0 + FLAT;
                    let Some(n) = (pairs[k].normal - pairs[j].normal).try_normalize(0.0) else {
                        continue;
                    };
                    for (m, normal) in [(k, n), (j, -n)] {
                        let pair = &mut pairs[m];
                        let axis = self.tools[pair.tool as usize].motion.direction();
                        pair.normal = normal;
                        pair.slip = pair.tangential_slip(
                            x[pair.node as usize],
                            self.trial[pair.tool as usize],
                            axis,
                        );
                        pair.squared = squared;
                    }
                }
                other = other_end;
            }
            start = end;
        }
    }

    /// Adds the slipping pairs' friction forces μ·λ_N (the forces the
    /// driver applies, not solved for) to the nodal forces `f`.
    pub fn add_slip_forces(&self, f: &mut [Vector3<f64>]) {
        for pair in &self.pairs {
            if let Some(force) = self.slip_force(pair) {
                f[pair.node as usize] += force;
            }
        }
    }

    fn slip_force(&self, pair: &Pair) -> Option<Vector3<f64>> {
        let mu = self.tools[pair.tool as usize].friction;
        (mu > 0.0 && pair.friction == Friction::Slip && pair.lambda > self.force_floor)
            .then(|| pair.slip_direction * (mu * pair.lambda))
    }

    /// Adds the constraint forces Cᵀλ of the last solve (normal and stick)
    /// to the nodal forces `f`.
    pub fn add_constraint_forces(&self, f: &mut [Vector3<f64>]) {
        for pair in &self.pairs {
            f[pair.node as usize] += pair.normal * pair.lambda + pair.stick;
        }
    }

    /// Largest penetration (mm, ≥ 0) over the pairs at their linearisation
    /// and largest stick slip: what must vanish at convergence.
    pub fn violation(&self) -> (f64, f64) {
        let mut pen = 0.0f64;
        let mut slip = 0.0f64;
        for pair in &self.pairs {
            pen = pen.max(-pair.gap);
            let sticking = pair.friction == Friction::Stick
                && pair.lambda > self.force_floor
                && self.tools[pair.tool as usize].friction > 0.0;
            if sticking {
                // A regularised stick's spring takes (f_n − f)/k_t.
                let elastic = match self.stick_compliance(pair) {
                    Some(c) => (pair.force_n - pair.stick) * c,
                    None => Vector3::zeros(),
                };
                let elastic = elastic - pair.normal * pair.normal.dot(&elastic);
                slip = slip.max((pair.slip - elastic).norm());
            }
        }
        (pen, slip)
    }

    /// The largest |residual| of the force-driven tools' equations with
    /// the last solve's reactions (N).
    pub fn tool_imbalance(&self) -> f64 {
        let mut worst = 0.0f64;
        for t in 0..self.tools.len() {
            if !self.tools[t].is_force_driven() {
                continue;
            }
            let axis = self.tools[t].motion.direction();
            let reaction: f64 = self
                .pairs
                .iter()
                .filter(|p| p.tool as usize == t)
                .map(|p| -(p.normal * p.lambda + p.stick).dot(&axis))
                .sum();
            worst = worst.max((self.tool_residual(t) + reaction).abs());
        }
        worst
    }

    /// Scales the last solve's steps of the force-driven tools, as the
    /// driver scales Δx (a damped Newton step).
    pub fn scale_step(&mut self, alpha: f64) {
        for d in &mut self.tool_step {
            *d *= alpha;
        }
    }

    /// Moves the force-driven tools by `alpha` times the last solve's Δd
    /// (the driver's line search moves the nodes by α·Δx).
    pub fn apply_step(&mut self, alpha: f64) {
        for (d, step) in self.trial.iter_mut().zip(&self.tool_step) {
            *d += alpha * step;
        }
    }

    /// The return mapping after a solve, at the new iterate `x`: a stick
    /// force beyond μ·λ_N turns the pair to slip in its direction; a slip
    /// that runs along its friction force turns back to stick; a pair that
    /// left contact forgets its friction. A slip counts as reversed when
    /// it runs along the friction force by more than `reversal` (mm), or
    /// by more than noise of the solve if that is larger (the driver
    /// widens the band after the first iterations of an increment, see
    /// its `SETTLE`). Returns how many pairs changed.
    pub fn update_friction(&mut self, x: &[Vector3<f64>], reversal: f64) -> usize {
        let reversal = reversal.max(SLIP_NOISE * self.settings.tolerance);
        let elastic_slip = self.settings.elastic_slip;
        let mut changes = 0;
        for pair in &mut self.pairs {
            let tool = &self.tools[pair.tool as usize];
            let mu = tool.friction;
            if mu == 0.0 {
                continue;
            }
            let i = pair.node as usize;
            let here = (x[i], self.trial[pair.tool as usize]);
            let (mass, increment) = (&self.mass, self.increment);
            let trial_force = |pair: &mut Pair| {
                let axis = tool.motion.direction();
                pair.trial_force(here.0, here.1, axis, mu, elastic_slip, mass, increment)
            };
            if pair.lambda <= self.force_floor {
                // Not pressed: when it is again, it sticks from there.
                if !pair.since_start {
                    (pair.anchor, pair.anchor_tool) = here;
                }
                // Stick rows that held it with no normal force must go.
                if pair.friction == Friction::Slip
                    || (pair.stick_rows && pair.stick != Vector3::zeros())
                {
                    changes += 1;
                }
                pair.friction = Friction::Stick;
                pair.stick = Vector3::zeros();
                continue;
            }
            match pair.friction {
                Friction::Stick if !pair.stick_rows => {
                    // A contact that closed in this increment sticks from
                    // where it closed; one pressed since tₙ from there.
                    if !pair.since_start {
                        (pair.anchor, pair.anchor_tool) = here;
                    }
                    // Newly pressed: it was free along the tool in this
                    // solve; the next one holds it...
                    changes += 1;
                    // ...unless its regularised stick's trial force is
                    // beyond the cone: then it slides along it at once,
                    // the return mapping of a pressed pair. A pair pressed
                    // since tₙ that lifted off and landed again in the
                    // iterations is anchored at tₙ, and its spring can pull
                    // it back with many times μ·λ_N: stick rows with that
                    // force lift it off again, and on the hemisphere
                    // 40 × 40 ±45 such pairs cycled pressed ↔ released
                    // until the attempt was cut (most of its cutbacks).
                    if elastic_slip > 0.0 {
                        let trial = trial_force(pair);
                        let size = trial.norm();
                        if size > mu * pair.lambda * (1.0 + CONE_SLACK) {
                            pair.friction = Friction::Slip;
                            pair.slip_direction = trial / size;
                            pair.trial = size;
                        }
                    }
                }
                Friction::Stick => {
                    let f = pair.stick.norm();
                    if f > mu * pair.lambda * (1.0 + CONE_SLACK) {
                        pair.friction = Friction::Slip;
                        pair.slip_direction = pair.stick / f;
                        pair.trial = f;
                        pair.stick = Vector3::zeros();
                        changes += 1;
                    }
                }
                Friction::Slip if elastic_slip > 0.0 => {
                    // Regularised: the spring's trial force from tₙ decides,
                    // f = f_n − k_t·s; inside the cone the pair sticks (with
                    // that force, continuous across the switch), outside it
                    // slides along it.
                    let trial = trial_force(pair);
                    let size = trial.norm();
                    // The force of the row across the slip (see
                    // `linearise_rows`) is now in the direction.
                    pair.stick = Vector3::zeros();
                    if size <= mu * pair.lambda {
                        pair.friction = Friction::Stick;
                        changes += 1;
                    } else {
                        pair.slip_direction = trial / size;
                        pair.trial = size;
                    }
                }
                Friction::Slip => {
                    let axis = tool.motion.direction();
                    let slip = pair.tangential_slip(x[i], here.1, axis);
                    // Along its friction force by more than the solve's
                    // accuracy: the slip has reversed, the node sticks
                    // (unless it has switched MAX_FLIPS times already in
                    // this increment). Otherwise the direction stays as
                    // the increment found it (from the stick force, or the
                    // last increment's slip): recomputed from a slip that
                    // may still be round-off, it would turn at random and
                    // Newton would not converge.
                    if slip.dot(&pair.slip_direction) > reversal {
                        // Sticking from where it was at tₙ (or where it
                        // closed): from where it stopped it would keep
                        // the slip it made against a force it did not
                        // need, and creep.
                        pair.friction = Friction::Stick;
                        changes += 1;
                    }
                }
            }
        }
        changes
    }

    /// Commits the increment at the converged `x` (committed positions
    /// `x_n`): tools' states by the Newmark update, per-node outputs,
    /// friction dissipation, the pairs in contact carried to the next
    /// increment. Returns (active contacts, sticking, slipping).
    pub fn commit(&mut self, x: &[Vector3<f64>], x_n: &[Vector3<f64>]) -> (usize, usize, usize) {
        let inc = self.increment.take().expect("an increment has begun");
        // Friction dissipation over the increment: −f·slip for the slip
        // forces (stick pairs have no slip at convergence).
        for pair in &self.pairs {
            if let Some(f) = self.slip_force(pair) {
                let tool = &self.tools[pair.tool as usize];
                let i = pair.node as usize;
                let dd = self.trial[pair.tool as usize]
                    - self.tool_state[pair.tool as usize].displacement;
                let s = x[i] - x_n[i] - tool.motion.direction() * dd;
                let slip = s - pair.normal * pair.normal.dot(&s);
                self.friction_dissipation -= f.dot(&slip);
            }
        }
        self.carried.clear();
        self.pressed.clear();
        let (mut active, mut stick, mut slip) = (0, 0, 0);
        for pair in &self.pairs {
            if pair.lambda <= 0.0 {
                continue;
            }
            active += 1;
            self.pressed.push((pair.node, pair.tool, pair.normal));
            let sliding =
                pair.friction == Friction::Slip && self.tools[pair.tool as usize].friction > 0.0;
            if sliding {
                slip += 1;
            } else {
                stick += 1;
            }
            // The next increment starts sliding against this one's slip,
            // when it is more than noise.
            let mut direction = pair.slip_direction;
            if sliding && self.settings.elastic_slip == 0.0 {
                let tool = &self.tools[pair.tool as usize];
                let i = pair.node as usize;
                let dd = self.trial[pair.tool as usize]
                    - self.tool_state[pair.tool as usize].displacement;
                let s = x[i] - x_n[i] - tool.motion.direction() * dd;
                let slip_t = s - pair.normal * pair.normal.dot(&s);
                if slip_t.norm() > SLIP_NOISE * self.settings.tolerance {
                    direction = -slip_t.normalize();
                }
            }
            self.carried.push(CarriedPair {
                tool: pair.tool,
                node: pair.node,
                lambda: pair.lambda,
                stick: pair.stick.into(),
                slip_direction: direction.into(),
                friction: if sliding {
                    Friction::Slip
                } else {
                    Friction::Stick
                },
            });
        }
        // The tools move on once the pairs have measured their slips
        // against the tools' positions at tₙ.
        for t in 0..self.tools.len() {
            let s = self.tool_state[t];
            let a0 = self.tool_acceleration[t];
            let a = inc.acceleration(self.trial[t] - s.displacement, s.velocity, a0);
            self.tool_state[t] = ToolState {
                displacement: self.trial[t],
                velocity: inc.velocity(s.velocity, a0, a),
                impulse: s.impulse,
            };
            self.tool_acceleration[t] = a;
        }
        self.write_outputs_from_carried();
        // A node resting on a tool at zero gap with nothing pressing it
        // reads in contact, as in the explicit pass (`TOUCHING`).
        let touch = crate::TOUCHING * self.settings.offset;
        for pair in &self.pairs {
            let i = pair.node as usize;
            if pair.lambda <= 0.0 && pair.gap <= touch && self.status[i] == ContactStatus::Open {
                self.status[i] = ContactStatus::Stick;
                self.tool_of[i] = pair.tool;
            }
        }
        for pair in &self.pairs {
            if pair.lambda <= 0.0 {
                continue;
            }
            let i = pair.node as usize;
            let slip = self.slip_force(pair).unwrap_or_else(Vector3::zeros);
            self.force[i] += pair.normal * pair.lambda + pair.stick + slip;
            let axis = self.tools[pair.tool as usize].motion.direction();
            self.tool_force[pair.tool as usize] += if axis == Vector3::zeros() {
                pair.lambda
            } else {
                pair.normal.dot(&axis) * pair.lambda
            };
        }
        // The force at the increment's end over the increment: first order
        // in h, as the end-point equilibrium the increment solves.
        for (state, f) in self.tool_state.iter_mut().zip(&self.tool_force) {
            state.impulse += f * inc.h;
        }
        (active, stick, slip)
    }

    /// Builds the rows of C from the current pairs: a normal row each, two
    /// tangential rows for a pair that sticks and pressed at the last solve.
    fn linearise_rows(&mut self) {
        self.rows.clear();
        self.springs.clear();
        for (k, pair) in self.pairs.iter_mut().enumerate() {
            let tool = &self.tools[pair.tool as usize];
            let axis = tool.motion.direction();
            let free = tool.is_force_driven();
            self.rows.push(Row {
                pair: k as u32,
                direction: pair.normal,
                tool_coefficient: if free { -pair.normal.dot(&axis) } else { 0.0 },
                target: pair.gap,
                bounded: true,
                compliance: 0.0,
            });
            pair.stick_rows = tool.friction > 0.0
                && pair.friction == Friction::Stick
                && pair.lambda > self.force_floor;
            if pair.stick_rows {
                let compliance = if self.initial || self.settings.elastic_slip == 0.0 {
                    0.0
                } else {
                    let elastic_slip = self.settings.elastic_slip;
                    1.0 / pair.stick_spring(tool.friction, elastic_slip, &self.mass, self.increment)
                };
                for t in tangents(&pair.normal) {
                    let row = Row {
                        pair: k as u32,
                        direction: t,
                        tool_coefficient: if free { -t.dot(&axis) } else { 0.0 },
                        target: t.dot(&pair.slip) - compliance * t.dot(&pair.force_n),
                        bounded: false,
                        compliance,
                    };
                    if self.springs_in_tangent && row.is_spring() {
                        self.springs.push(row);
                    } else {
                        self.rows.push(row);
                    }
                }
            } else if !self.initial
                && self.settings.elastic_slip > 0.0
                && tool.friction > 0.0
                && pair.friction == Friction::Slip
                && pair.lambda > self.force_floor
            {
                // A regularised slip's force μ·λ_N·(f_n − k_t·s)/|f_n − k_t·s|
                // turns with the slip: across its direction d it changes
                // by −k⊥·Δs, k⊥ = μ·λ_N·k_t/|f_n − k_t·s|. That stiffness
                // as a row t⊥·Δx + λ/k⊥ = 0 (t⊥ = n × d) puts the turn in
                // the Newton step: without it the direction lags one
                // iteration behind and Newton does not converge when k_t
                // is stiff.
                let elastic_slip = self.settings.elastic_slip;
                let k_t =
                    pair.stick_spring(tool.friction, elastic_slip, &self.mass, self.increment);
                let cone = tool.friction * pair.lambda;
                let trial = if pair.trial > 0.0 { pair.trial } else { cone };
                let across = pair.normal.cross(&pair.slip_direction);
                if let Some(t) = across.try_normalize(1e-12) {
                    let row = Row {
                        pair: k as u32,
                        direction: t,
                        tool_coefficient: if free { -t.dot(&axis) } else { 0.0 },
                        target: 0.0,
                        bounded: false,
                        compliance: trial / (cone * k_t),
                    };
                    if self.springs_in_tangent && row.is_spring() {
                        self.springs.push(row);
                    } else {
                        self.rows.push(row);
                    }
                }
            }
        }
    }

    /// 1/k_t of a sticking pair's regularised stick, if regularised.
    fn stick_compliance(&self, pair: &Pair) -> Option<f64> {
        (self.settings.elastic_slip > 0.0 && !self.initial && pair.stick_stiffness > 0.0)
            .then(|| 1.0 / pair.stick_stiffness)
    }

    /// The nodes of the rows of C at the last linearisation (in row
    /// order, repeated per row).
    pub fn row_nodes(&self) -> impl Iterator<Item = u32> + '_ {
        self.rows.iter().map(|r| self.pairs[r.pair as usize].node)
    }

    /// The condensed solves' counts summed over the run so far (products
    /// by kind; rows, active and residual of the last solve); solves that
    /// failed are not counted.
    pub fn solve_totals(&self) -> SolveStats {
        self.solve_totals
    }

    /// Whether a force-driven tool is among the tools.
    pub fn couples_tools(&self) -> bool {
        self.has_free_tools()
    }

    /// The largest change μ·|Δλ_N| of a slipping pair's friction force in
    /// the last solve (N): the force the Newton step took as a fixed load
    /// at the old λ_N, so what the next residual finds at that node when
    /// the slip force lags behind the multipliers (a diagnosis).
    pub fn slip_lag(&self) -> f64 {
        self.pairs
            .iter()
            .filter(|p| p.friction == Friction::Slip && p.lambda > self.force_floor)
            .map(|p| self.tools[p.tool as usize].friction * (p.lambda - p.lambda_before).abs())
            .fold(0.0, f64::max)
    }

    /// Pressed pairs (λ_N above the force floor) that stick and that slip.
    pub fn friction_census(&self) -> (usize, usize) {
        let pressed = self.pairs.iter().filter(|p| p.lambda > self.force_floor);
        pressed.fold((0, 0), |(stick, slip), p| match p.friction {
            Friction::Stick => (stick + 1, slip),
            Friction::Slip => (stick, slip + 1),
        })
    }

    /// The friction state of node `node`'s pressed pair, if any (the
    /// first such pair's, tool by tool).
    pub fn friction_at(&self, node: u32) -> Option<Friction> {
        self.pairs
            .iter()
            .find(|p| p.node == node && p.lambda > self.force_floor)
            .map(|p| p.friction)
    }
}

mod active_set;
pub use active_set::{REGULARISATION, SLOTS_PER_PAIR, SystemRow};
mod condensed;
mod mprgp;
#[cfg(test)]
use mprgp::ROUNDOFF;
use mprgp::{RoundOff, Work, mprgp};

#[cfg(test)]
mod tests;
