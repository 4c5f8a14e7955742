//! Contact for explicit central differences: forward-increment Lagrange
//! multipliers (SPEC §6) and Coulomb friction by return mapping.
//!
//! After the predictor has moved the nodes to x̃ₙ₊₁ without contact, the
//! pass finds the nodes that would sit closer to a tool than the fabric's
//! half thickness and solves C·M⁻¹·Cᵀ·μ = −g with μ = λ·Δt·τ ≥ 0 (τ = Δt
//! for equal undamped steps, see [`StepTimes`]): per node in
//! closed form when every constraint is alone (one tool per node, tools
//! driven by displacement), by a projected preconditioned conjugate
//! gradient when constraints couple (a node pinched between two tools, a
//! force-driven holder that every node under it pushes back). Friction then
//! corrects the tangential velocity towards sticking to the tool, capped by
//! μ_f·λ.

use std::time::Duration;

use nalgebra::Vector3;
use rayon::prelude::*;

use crate::phases::{ContactPhase, PhaseTimer};
use crate::plies::{PlyContact, Support, ToolFriction};

mod clearance;
mod ply_link;
use crate::tool::{Tool, ToolMotion, ToolState};
pub use clearance::Nearest;

/// The gap, as a fraction of the contact offset (the fabric's half
/// thickness), within which a node is touching a tool though nothing
/// presses it in: a node resting on a tool at zero gap sits there to
/// round-off (1e-12 mm), one lifting off or approaching is microns away.
pub const TOUCHING: f64 = 1e-6;

/// Candidates projected (or nodes checked) per rayon task: a projection
/// costs ≈ 0.1 µs, so a task of 512 is ≈ 50 µs, well above the cost of
/// handing it to another thread; the 1681-node hemisphere blank splits its
/// ≈ 1000 punch candidates in two.
const PROJECTIONS_PER_TASK: usize = 512;

/// A candidate's last projection on its tool: the gap (less nothing: the
/// surface's own), the normal, and where the node and the tool were. The
/// gap's magnitude is 1-Lipschitz in the node's position and in the tool's
/// displacement, and its sign can change only through the surface or, on
/// an open tool, across the cut behind its rim, which a node nearer the
/// surface than the rim cannot reach (`Surface::rim_clearance`, infinite on
/// a closed tool). So with s = |x − at| + |u − u_at|·|axis|, while
/// gap − s stays beyond the contact reach and gap + s below the rim's
/// distance the node cannot touch the tool and is not projected again: a
/// far node costs a distance, not a closest-point query, and the
/// constraints found are the same.
#[derive(Debug, Clone, Copy)]
struct Projected {
    gap: f64,
    normal: Vector3<f64>,
    at: Vector3<f64>,
    u: f64,
    /// A lower bound of the distance to the tool's rim at the projection
    /// (0 when not taken: the node was within reach).
    rim: f64,
    /// The triangle a mesh tool's projection found (the next one starts
    /// there, see `Surface::project_from`); `u32::MAX` for none.
    hint: u32,
    /// Whether the gap and normal are this step's.
    fresh: bool,
}

impl Projected {
    /// Never projected: the next step projects it.
    const STALE: Self = Self {
        gap: f64::NEG_INFINITY,
        normal: Vector3::new(0.0, 0.0, 0.0),
        at: Vector3::new(0.0, 0.0, 0.0),
        u: 0.0,
        rim: 0.0,
        hint: u32::MAX,
        fresh: false,
    };
}

/// Nodes checked for broad-phase motion per rayon task (≈ 2 ns each).
const NODES_PER_TASK: usize = 16_384;

/// A node's contact status.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u8)]
pub enum ContactStatus {
    /// Not touching: further from every tool than [`TOUCHING`] of the
    /// offset.
    #[default]
    Open = 0,
    /// Touching and sticking (or resting on the tool at zero gap, with no
    /// force).
    Stick = 1,
    /// Touching and sliding.
    Slip = 2,
}

/// Node `i`'s offset from the tools: its own where the nodes have theirs
/// (see [`ExplicitContact::set_node_offsets`]), else the uniform one.
#[inline]
fn offset_at(node_offset: &[f64], uniform: f64, i: usize) -> f64 {
    node_offset.get(i).copied().unwrap_or(uniform)
}

/// Settings of the contact pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSettings {
    /// Distance of the fabric's mid-surface from a tool at contact: half the
    /// thickness (mm); in a laminate of plies of different thicknesses the
    /// largest, each node's own given by [`ExplicitContact::set_node_offsets`].
    pub offset: f64,
    /// Margin of the broad phase: the candidate lists are rebuilt once a node
    /// or a tool has moved half of it (mm).
    pub margin: f64,
    /// Convergence of the coupled solve: largest gap violation left (mm).
    pub tolerance: f64,
    /// Iterations allowed to the coupled solve.
    pub max_iterations: usize,
    /// The contact guard's slack (mm): how much more a node's gap may drop
    /// in a step than the node and the tool travelled before the step is a
    /// [`ContactFault`]. Round-off of the gap is far below it.
    pub fault_tolerance: f64,
    /// The largest travel of a node relative to a tool in one step that the
    /// pass resolves (mm): a node found inside a tool after the node and
    /// the tool together moved more than this is a [`ContactFault`]. The
    /// explicit driver sets it to the fabric's thickness; the default does
    /// not limit.
    pub max_travel: f64,
    /// The largest clearance between two tools that a confined yarn can
    /// meet (mm; 0: no yarn is confined): a node whose gap to a tool is
    /// within the offset and this is projected on it at every step, and a
    /// tool farther away is no wall ([`ExplicitContact::clearance_into`]),
    /// so that a yarn's clearance depends on the positions alone, not on
    /// when the node was last projected (a resumed run's projections are
    /// all new).
    pub clearance_reach: f64,
}

impl Default for ContactSettings {
    fn default() -> Self {
        Self {
            offset: 0.0,
            margin: 5.0,
            tolerance: 1e-9,
            max_iterations: 500,
            fault_tolerance: 1e-3,
            max_travel: f64::INFINITY,
            clearance_reach: 0.0,
        }
    }
}

/// What the contact guard found wrong.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FaultKind {
    /// The gap dropped by more than the node's and the tool's travel in the
    /// step (plus [`ContactSettings::fault_tolerance`]): a gap that is
    /// 1-Lipschitz in the point and in the tool's position cannot, so the
    /// node crossed a discontinuity (the cut behind an open tool's rim, see
    /// [`Surface::revolution`](crate::Surface::revolution)) and the closest
    /// point is on the wrong side.
    GapJump {
        /// The gap at the start of the step (mm, less the offset).
        previous_gap: f64,
    },
    /// The node and the tool moved farther towards each other in one step
    /// than [`ContactSettings::max_travel`]: the tool may have been forced
    /// through the fabric, and the closest point need not be on the side
    /// the node came from.
    Overrun {
        /// The limit (mm).
        limit: f64,
    },
}

/// A step the contact pass refuses: a node inside a tool by more than one
/// step can explain. Pushing it out would inject energy (a jump of the
/// fabric by the penetration in one step), so the step is not taken.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactFault {
    /// The node.
    pub node: usize,
    /// The tool's index.
    pub tool: usize,
    /// The tool's name.
    pub tool_name: String,
    /// The node's gap to the tool at the end of the step, less the offset
    /// (mm, negative: inside).
    pub gap: f64,
    /// How far the node moved in the step (mm).
    pub node_travel: f64,
    /// How far the tool moved in the step (mm).
    pub tool_travel: f64,
    /// What was wrong.
    pub kind: FaultKind,
    /// Where the node is at the end of the step (`place.from`) and where
    /// on the tool: its closest point, and how far from an open rim (boxed:
    /// a step's result stays small).
    pub place: Box<crate::ToolPlace>,
}

impl std::fmt::Display for ContactFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.place.from;
        write!(
            f,
            "node {} at ({:.2}, {:.2}, {:.2}) mm is {:.4e} mm inside tool `{}` (gap {:.4e} mm) after a step in which the node moved {:.3e} mm and the tool {:.3e} mm",
            self.node,
            x.x,
            x.y,
            x.z,
            -self.gap,
            self.tool_name,
            self.gap,
            self.node_travel,
            self.tool_travel
        )?;
        match self.kind {
            FaultKind::GapJump { previous_gap } => write!(
                f,
                "; its gap was {previous_gap:.4e} mm a step earlier and cannot drop by more than that travel: \
                 the node has crossed behind an open edge of the tool (or the tool's gap is not continuous), \
                 so it is not pushed out"
            ),
            FaultKind::Overrun { limit } => {
                write!(
                    f,
                    ", more than the {limit:.3e} mm the contact resolves in one step (the fabric's thickness): "
                )?;
                // A node that moved ten times as far as its tool was thrown
                // by the fabric itself. In the stacked deep drawing of two
                // frictionless plies under a fixed holder (2026-11-30) a
                // corner of the bottom ply reached 40 m/s as the stack
                // snapped through a fold in the die's opening (strain
                // energy going to kinetic, the energy balance closed); a
                // step 2.9 times shorter stopped the same way 4 ms later,
                // at another node.
                if self.tool_travel < 0.1 * self.node_travel {
                    write!(
                        f,
                        "the tool hardly moved, so the fabric threw the node (a fold snapping through, a free edge \
                         or corner whipping; see the run's fold warning and the waviness in the last frames), and \
                         it is not pushed out; a shorter step may not help, holding the blank (holder, springs, \
                         friction) or a finer mesh where it folds may"
                    )
                } else {
                    write!(
                        f,
                        "the tool or the node moves too fast for the step (was the tool forced through the blank?), \
                         so it is not pushed out; a shorter step (less mass scaling) or a slower tool keeps each \
                         step's travel within it"
                    )
                }
            }
        }?;
        write!(f, "; closest point on {}", self.place)
    }
}

impl std::error::Error for ContactFault {}

/// One active constraint of a step.
#[derive(Debug, Clone, Copy)]
struct Constraint {
    node: u32,
    tool: u32,
    normal: Vector3<f64>,
    gap: f64,
    /// μ = λ·Δt·τ.
    mu: f64,
}

/// The times of one step of central differences, xₙ₊₁ = xₙ + Δt·vₙ₊½,
/// vₙ₊½ = (vₙ₋½·(1 − ½αΔt_mean) + Δt_mean·aₙ)/(1 + ½αΔt_mean).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepTimes {
    /// tₙ₊₁ (s).
    pub t_new: f64,
    /// Δt = tₙ₊₁ − tₙ (s).
    pub dt: f64,
    /// Δt_mean = ½(tₙ₊₁ − tₙ₋₁), the step of the velocity update (s): half
    /// of Δt at the first step, different from it whenever Δt changes.
    pub dt_mean: f64,
    /// α of the mass-proportional damping of the nodes (1/s).
    pub damping: f64,
}

/// What a step of the contact pass did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactStep {
    /// Active constraints.
    pub active: usize,
    /// Iterations of the coupled solve (0 when solved in closed form).
    pub iterations: usize,
    /// Largest gap violation left after the solve (mm, ≥ 0).
    pub residual: f64,
}

/// The explicit contact pass with its tools, broad phase and outputs.
#[derive(Debug, Clone)]
pub struct ExplicitContact {
    /// The tools.
    pub tools: Vec<Tool>,
    /// Each node's offset where they differ (a laminate of plies of
    /// different thicknesses: each ply's half thickness); empty: every
    /// node at `settings.offset` ([`Self::set_node_offsets`]).
    node_offset: Vec<f64>,
    /// Their displacement and velocity.
    pub tool_state: Vec<ToolState>,
    /// The settings.
    pub settings: ContactSettings,
    /// Contact force on each node at the last step (N): normal + friction.
    pub force: Vec<Vector3<f64>>,
    /// Each node's status at the last step.
    pub status: Vec<ContactStatus>,
    /// Which tool each node touched last (u32::MAX for none).
    pub tool_of: Vec<u32>,
    /// Normal force of each tool on the fabric at the last step (N, along
    /// the tool's axis of motion for a moving tool, magnitude otherwise).
    pub tool_force: Vec<f64>,
    /// Friction dissipated so far (mJ).
    pub friction_dissipation: f64,
    candidates: Vec<Vec<u32>>,
    reference_x: Vec<Vector3<f64>>,
    reference_tool: Vec<f64>,
    constraints: Vec<Constraint>,
    per_node: Vec<u32>,
    touched: Vec<u32>,
    scratch: Scratch,
    phases: Option<PhaseTimer>,
    /// Contact between the plies of a laminate (none for one ply).
    plies: Option<PlyContact>,
    /// The tool contacts handed to the ply pass as supports.
    supports: Vec<Support>,
    /// The tool contacts' friction handed to the ply pass, and what it was.
    tool_friction: Vec<ToolFriction>,
    tool_old: Vec<Vector3<f64>>,
}

#[derive(Debug, Clone, Default)]
struct Scratch {
    node_sum: Vec<Vector3<f64>>,
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
    diag: Vec<f64>,
    free: Vec<bool>,
    /// First constraint of each node (u32::MAX for none) and the next one
    /// of the same node, while looking for violated pairs.
    head: Vec<u32>,
    next: Vec<u32>,
    /// Friction forces of the step, by constraint.
    applied: Vec<(u32, Vector3<f64>)>,
    /// The coupled solve's multipliers, and per tool: axis and mass,
    /// correction sums, shifts; constraints found violated after a solve.
    mu: Vec<f64>,
    tool_axis: Vec<(Vector3<f64>, f64)>,
    tool_sum: Vec<f64>,
    tool_shift: Vec<f64>,
    /// Per tool, the travel the ply pass gives a force-driven one.
    ply_tool_shift: Vec<f64>,
    /// In a stack, the nodes within the offset of a tool that no
    /// constraint presses (gap ≥ 0): the ply pass may not push them in
    /// either ([`crate::plies::Support`]).
    near: Vec<Constraint>,
    /// Per node, the tools (bits, the first 64) whose constraint on it
    /// the ply pass holds already, while its supports are listed.
    held_by: Vec<u64>,
    added: Vec<Constraint>,
    /// Per tool, per candidate: its last projection (see [`Projected`]).
    projected: Vec<Vec<Projected>>,
    /// Each tool's displacement at the start of the step (for the guard).
    tool_before: Vec<f64>,
    /// Per node, whether it is inside the tool's grown box (broad phase).
    inside: Vec<bool>,
}

impl ExplicitContact {
    /// A pass over `node_count` nodes.
    ///
    /// The lists that grow with the number of contact pairs take room for
    /// one pair per node from the start, so that a step in which more nodes
    /// come into contact does not allocate (a node held by two tools at
    /// once can still grow them, once).
    pub fn new(tools: Vec<Tool>, node_count: usize, settings: ContactSettings) -> Self {
        let n_tools = tools.len();
        Self {
            tool_state: vec![ToolState::default(); n_tools],
            tools,
            node_offset: Vec::new(),
            settings,
            force: vec![Vector3::zeros(); node_count],
            status: vec![ContactStatus::Open; node_count],
            tool_of: vec![u32::MAX; node_count],
            tool_force: vec![0.0; n_tools],
            friction_dissipation: 0.0,
            candidates: vec![Vec::new(); n_tools],
            reference_x: Vec::new(),
            reference_tool: vec![f64::NAN; n_tools],
            constraints: Vec::with_capacity(node_count),
            per_node: vec![0; node_count],
            touched: Vec::with_capacity(node_count),
            scratch: Scratch {
                node_sum: vec![Vector3::zeros(); node_count],
                r: Vec::with_capacity(node_count),
                z: Vec::with_capacity(node_count),
                p: Vec::with_capacity(node_count),
                q: Vec::with_capacity(node_count),
                diag: Vec::with_capacity(node_count),
                free: Vec::with_capacity(node_count),
                next: Vec::with_capacity(node_count),
                applied: Vec::with_capacity(node_count),
                mu: Vec::with_capacity(node_count),
                added: Vec::with_capacity(node_count),
                head: vec![u32::MAX; node_count],
                tool_axis: Vec::with_capacity(n_tools),
                tool_sum: Vec::with_capacity(n_tools),
                tool_shift: Vec::with_capacity(n_tools),
                tool_before: Vec::with_capacity(n_tools),
                ..Scratch::default()
            },
            phases: None,
            plies: None,
            supports: Vec::new(),
            tool_friction: Vec::new(),
            tool_old: Vec::new(),
        }
    }

    /// Each node's own offset from the tools (its ply's half thickness),
    /// for a laminate whose plies differ in thickness; `settings.offset`
    /// must be the largest (the broad phase's reach). Without, every node
    /// keeps `settings.offset`: with one offset for all, a thin ply under
    /// a thick one was held the thick ply's half thickness off the tool.
    pub fn set_node_offsets(&mut self, offsets: Vec<f64>) {
        assert!(
            offsets.len() == self.force.len()
                && offsets
                    .iter()
                    .all(|&o| o > 0.0 && o <= self.settings.offset),
            "a positive offset per node, none above settings.offset"
        );
        self.node_offset = offsets;
    }

    /// The shifts of position the ply pass made at the last step (see
    /// [`PlyContact::shifts`]); none without plies.
    pub fn position_shifts(&self) -> &[(u32, Vector3<f64>)] {
        self.plies.as_ref().map_or(&[], PlyContact::shifts)
    }

    /// Adds contact between the plies of a laminate (see [`PlyContact`]):
    /// solved after the tools' normal constraints, with the nodes on a tool
    /// held there, before the tools' friction and its own.
    pub fn set_plies(&mut self, plies: PlyContact) {
        self.supports = Vec::with_capacity(self.force.len());
        self.tool_friction = Vec::with_capacity(self.force.len());
        self.tool_old = Vec::with_capacity(self.force.len());
        self.plies = Some(plies);
    }

    /// The ply–ply contact, when the model is a laminate.
    pub fn plies(&self) -> Option<&PlyContact> {
        self.plies.as_ref()
    }

    /// The ply–ply contact, for the driver's overlap checks
    /// ([`PlyContact::record_overlap`]).
    pub fn plies_mut(&mut self) -> Option<&mut PlyContact> {
        self.plies.as_mut()
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
            plies: self.plies.as_ref(),
        }
    }

    /// Times the phases of every later pass by `clock` (a monotonic time
    /// since a fixed origin), or stops timing with `None`; the sums start
    /// from zero.
    pub fn time_phases(&mut self, clock: Option<fn() -> Duration>) {
        self.phases = clock.map(|clock| PhaseTimer {
            clock,
            last: Duration::ZERO,
            times: [Duration::ZERO; ContactPhase::ALL.len()],
        });
    }

    /// The phases' summed times since [`Self::time_phases`], in the order of
    /// [`ContactPhase::ALL`] (none when not timing).
    pub fn phase_times(&self) -> Option<[Duration; ContactPhase::ALL.len()]> {
        self.phases.map(|t| t.times)
    }

    /// Whether any tool has friction (the friction pass runs only then).
    pub fn has_friction(&self) -> bool {
        self.tools.iter().any(|t| t.friction > 0.0)
    }

    /// Rebuilds the candidate lists when a node or a tool has moved more
    /// than half the margin since the last build.
    fn refresh_candidates(&mut self, x: &[Vector3<f64>]) {
        let half = 0.5 * self.settings.margin;
        let tools_moved = self
            .tool_state
            .iter()
            .zip(&self.reference_tool)
            .any(|(s, r)| r.is_nan() || (s.displacement - r).abs() >= half);
        let nodes_moved = self.reference_x.len() != x.len()
            || x.par_iter()
                .zip(&self.reference_x)
                .with_min_len(NODES_PER_TASK)
                .any(|(a, b)| (a - b).norm_squared() > half * half);
        if !(tools_moved || nodes_moved) {
            return;
        }
        let reach = self.settings.margin + self.settings.offset;
        for (t, tool) in self.tools.iter().enumerate() {
            let shift = tool.motion.direction() * self.tool_state[t].displacement;
            let aabb = tool.surface.aabb().translated(&shift).grown(reach);
            if let Some(p) = self.scratch.projected.get_mut(t) {
                // New candidates: all projected at the next narrow phase.
                p.clear();
            }
            // The box test in parallel into a mask, the list compacted from
            // it in node order into the tool's own list: a rebuild (every
            // few hundred steps) allocates nothing after the first, whose
            // list takes room for every node.
            let inside = &mut self.scratch.inside;
            inside.resize(x.len(), false);
            inside
                .par_iter_mut()
                .zip(x.par_iter())
                .with_min_len(NODES_PER_TASK)
                .for_each(|(m, p)| *m = aabb.contains(p));
            let list = &mut self.candidates[t];
            list.clear();
            list.reserve(x.len());
            if self.scratch.projected.len() < self.tools.len() {
                self.scratch.projected.resize(self.tools.len(), Vec::new());
            }
            let projected = &mut self.scratch.projected[t];
            projected.reserve(x.len().saturating_sub(projected.len()));
            list.extend((0..x.len() as u32).filter(|&i| inside[i as usize]));
        }
        self.reference_x.clear();
        self.reference_x.extend_from_slice(x);
        for (r, s) in self.reference_tool.iter_mut().zip(&self.tool_state) {
            *r = s.displacement;
        }
    }

    /// Number of candidate nodes of each tool (the broad phase's result).
    pub fn candidate_counts(&self) -> Vec<usize> {
        self.candidates.iter().map(Vec::len).collect()
    }

    /// Enforces contact on the predicted step: moves the tools to `t_new`
    /// (a force-driven one by its force), corrects the predicted positions
    /// `x` and mid-step velocities `v` of the nodes whose `movable` flag is
    /// set, and records forces and statuses. `mass` are the nodal masses.
    ///
    /// For a run of equal steps `dt` without damping; [`Self::enforce_step`]
    /// takes the general step.
    pub fn enforce(
        &mut self,
        x: &mut [Vector3<f64>],
        v: &mut [Vector3<f64>],
        mass: &[f64],
        movable: &[bool],
        t_new: f64,
        dt: f64,
    ) -> Result<ContactStep, ContactFault> {
        let step = StepTimes {
            t_new,
            dt,
            dt_mean: dt,
            damping: 0.0,
        };
        self.enforce_step(x, v, mass, movable, &step)
    }

    /// [`Self::enforce`] for a step of central differences with varying
    /// steps and mass-proportional damping (see [`StepTimes`]): the forces
    /// reported are the ones that, applied at tₙ in the velocity update,
    /// produce the corrections made to x̃ₙ₊₁.
    ///
    /// `x` and `v` are the predicted positions and mid-step velocities, so
    /// that each node started the step at `x − v·Δt`.
    ///
    /// # Contact guard
    ///
    /// A node inside a tool by more than the step can explain is a
    /// [`ContactFault`], and nothing is corrected: since the gap is
    /// 1-Lipschitz in the point and the tool moves rigidly, a node's gap
    /// drops in one step by at most the node's travel plus the tool's. A
    /// larger drop means a discontinuity of the gap (a node behind an open
    /// rim); a relative travel beyond [`ContactSettings::max_travel`] means a
    /// step too coarse to resolve the contact. Both would push the node out
    /// by the closest point, possibly on the wrong side and in any case by
    /// far more than the tool moved. The first fault in tool order, then in
    /// node order, is returned (independent of the thread count).
    pub fn enforce_step(
        &mut self,
        x: &mut [Vector3<f64>],
        v: &mut [Vector3<f64>],
        mass: &[f64],
        movable: &[bool],
        step_times: &StepTimes,
    ) -> Result<ContactStep, ContactFault> {
        let StepTimes {
            t_new,
            dt,
            dt_mean,
            damping,
        } = *step_times;
        PhaseTimer::start(&mut self.phases);
        // A force f on a node at tₙ changes vₙ₊½ by f·τ/m and xₙ₊₁ by
        // f·τ·Δt/m, τ = Δt_mean/(1 + ½·α·Δt_mean) with the damping taken at
        // mid-step; an undamped force-driven tool responds with Δt_mean, so
        // in the nodes' units it weighs M·τ/Δt_mean.
        let tau = dt_mean / (1.0 + 0.5 * damping * dt_mean);
        let tool_mass_factor = tau / dt_mean;
        self.scratch.tool_before.clear();
        self.scratch
            .tool_before
            .extend(self.tool_state.iter().map(|s| s.displacement));
        // Tools: prescribed, or the force-driven predictor (reaction to come).
        for (tool, state) in self.tools.iter().zip(self.tool_state.iter_mut()) {
            match tool.prescribed_displacement(t_new) {
                Some(u) => {
                    state.velocity = (u - state.displacement) / dt;
                    state.displacement = u;
                }
                None => {
                    if let ToolMotion::Force {
                        force,
                        amplitude,
                        mass,
                        ..
                    } = &tool.motion
                    {
                        state.velocity += dt_mean * force * amplitude.value(t_new - dt) / mass;
                        state.displacement += dt * state.velocity;
                    }
                }
            }
        }
        // Clear last step's outputs where they were set.
        for &i in &self.touched {
            self.force[i as usize] = Vector3::zeros();
            self.status[i as usize] = ContactStatus::Open;
            self.tool_of[i as usize] = u32::MAX;
            self.per_node[i as usize] = 0;
        }
        self.touched.clear();
        if self.plies.is_some() {
            // The ply pass puts forces on nodes of its own.
            self.force.iter_mut().for_each(|f| *f = Vector3::zeros());
        }
        self.tool_force.iter_mut().for_each(|f| *f = 0.0);
        self.refresh_candidates(x);
        PhaseTimer::lap(&mut self.phases, ContactPhase::BroadPhase);

        // Narrow phase. A node within `touch` of a tool rests on it: in
        // contact with no force this step (nothing pushes it in).
        self.constraints.clear();
        self.scratch.near.clear();
        let offset = self.settings.offset;
        let (slack, max_travel) = (self.settings.fault_tolerance, self.settings.max_travel);
        let touch = TOUCHING * offset;
        for (t, tool) in self.tools.iter().enumerate() {
            let u = self.tool_state[t].displacement;
            let u_before = self.scratch.tool_before[t];
            let tool_travel = (u - u_before).abs() * tool.motion.direction().norm();
            // The projections are independent: in parallel, into a buffer
            // read in candidate order below (the same constraints in the
            // same order for any thread count).
            // A node whose last gap, less the travel of the node and of the
            // tool since, is beyond the reach, and whose last gap plus that
            // travel is below its last distance to the tool's rim, is not
            // projected ([`Projected`]); a margin of 2·touch covers the
            // round-off of the bound.
            let candidates = &self.candidates[t];
            if self.scratch.projected.len() < self.tools.len() {
                self.scratch.projected.resize(self.tools.len(), Vec::new());
            }
            let projected = &mut self.scratch.projected[t];
            projected.resize(candidates.len(), Projected::STALE);
            let axis = tool.motion.direction().norm();
            // A stack's ply pass also reads the nodes within the offset of
            // a tool (`near`), and the confined yarns every gap within the
            // clearance reach, so none of those may be skipped either.
            let near = if self.plies.is_some() { offset } else { 0.0 };
            let reach = offset + near.max(self.settings.clearance_reach) + 2.0 * touch;
            candidates
                .par_iter()
                .zip(projected.par_iter_mut())
                .with_min_len(PROJECTIONS_PER_TASK)
                .for_each(|(&i, out)| {
                    let xi = x[i as usize];
                    out.fresh = false;
                    if !movable[i as usize] {
                        return;
                    }
                    let travel = (xi - out.at).norm() + (u - out.u).abs() * axis;
                    if out.gap - travel > reach && out.gap + travel + 2.0 * touch < out.rim {
                        return;
                    }
                    let mut hint = out.hint;
                    let p = tool.project_from(&xi, u, &mut hint);
                    // The rim's distance matters only to a node that may be
                    // skipped next step; it costs a query of its own.
                    let rim = if p.gap > reach {
                        tool.rim_clearance(&xi, u)
                    } else {
                        0.0
                    };
                    *out = Projected {
                        gap: p.gap,
                        normal: p.normal,
                        at: xi,
                        u,
                        rim,
                        hint,
                        fresh: true,
                    };
                });
            for (&i, out) in candidates.iter().zip(projected.iter()) {
                if !out.fresh {
                    // Not movable, or too far to touch.
                    continue;
                }
                let (gap, normal) = (out.gap, out.normal);
                let offset = offset_at(&self.node_offset, self.settings.offset, i as usize);
                let gap = gap - offset;
                if gap < 0.0 {
                    let node_travel = v[i as usize].norm() * dt;
                    let travel = node_travel + tool_travel;
                    let fault = |kind| ContactFault {
                        node: i as usize,
                        tool: t,
                        tool_name: tool.name.clone(),
                        gap,
                        node_travel,
                        tool_travel,
                        kind,
                        place: Box::new(crate::ToolPlace::of(tool, &x[i as usize], u)),
                    };
                    if travel > max_travel {
                        return Err(fault(FaultKind::Overrun { limit: max_travel }));
                    }
                    if -gap > travel + slack {
                        let before = x[i as usize] - v[i as usize] * dt;
                        let previous_gap = tool.project(&before, u_before).gap - offset;
                        if previous_gap - gap > travel + slack {
                            return Err(fault(FaultKind::GapJump { previous_gap }));
                        }
                    }
                    self.constraints.push(Constraint {
                        node: i,
                        tool: t as u32,
                        normal,
                        gap,
                        mu: 0.0,
                    });
                } else {
                    if gap <= TOUCHING * offset {
                        self.status[i as usize] = ContactStatus::Stick;
                        self.tool_of[i as usize] = t as u32;
                        self.touched.push(i);
                    }
                    if self.plies.is_some() && gap <= offset {
                        self.scratch.near.push(Constraint {
                            node: i,
                            tool: t as u32,
                            normal,
                            gap,
                            mu: 0.0,
                        });
                    }
                }
            }
        }
        PhaseTimer::lap(&mut self.phases, ContactPhase::Projection);
        if self.constraints.is_empty() {
            // A stack's ply pass may still press nodes onto a tool (its
            // supports): their force is the tool's too.
            self.ply_pass(x, v, mass, movable, dt, tau, tool_mass_factor);
            self.add_impulse(dt);
            return Ok(ContactStep::default());
        }
        let mut step = ContactStep::default();
        // Solve; then, as long as the corrections would push a node into a
        // tool whose constraint is not in the set (a node pressed by the
        // holder into the die under it, by one tool into another), add that
        // constraint and solve again: the set of the predictor alone misses
        // the contacts the solve itself closes.
        loop {
            for c in &self.constraints {
                self.per_node[c.node as usize] = 0;
            }
            for c in &self.constraints {
                self.per_node[c.node as usize] += 1;
            }
            let coupled = self.constraints.iter().any(|c| {
                self.per_node[c.node as usize] > 1 || self.tools[c.tool as usize].is_force_driven()
            });
            if coupled {
                let (iterations, residual) = self.solve_coupled(mass, tool_mass_factor);
                step.iterations += iterations;
                step.residual = residual;
            } else {
                for c in &mut self.constraints {
                    c.mu = (-c.gap * mass[c.node as usize]).max(0.0);
                }
            }
            if !self.add_violated(x, mass, movable, tool_mass_factor) {
                break;
            }
        }
        step.active = self.constraints.len();

        // Apply the normal corrections and the force-driven tools' reaction.
        let lambda_scale = 1.0 / (dt * tau);
        for c in &self.constraints {
            if c.mu == 0.0 && c.gap >= 0.0 {
                // Added for safety and left open by the solve: not touching.
                continue;
            }
            let i = c.node as usize;
            let dx = c.normal * (c.mu / mass[i]);
            x[i] += dx;
            v[i] += dx / dt;
            let lambda = c.mu * lambda_scale;
            self.force[i] += c.normal * lambda;
            self.status[i] = ContactStatus::Stick;
            self.tool_of[i] = c.tool;
            self.touched.push(c.node);
            let tool = &self.tools[c.tool as usize];
            let axis = tool.motion.direction();
            // On the fabric: the normal force n·λ, along the axis n·a·λ
            // (positive when the tool pushes the fabric the way it moves).
            self.tool_force[c.tool as usize] += if axis == Vector3::zeros() {
                lambda
            } else {
                c.normal.dot(&axis) * lambda
            };
            if let ToolMotion::Force {
                direction,
                mass: m_tool,
                ..
            } = &tool.motion
            {
                let du = -c.normal.dot(direction) * c.mu / (m_tool * tool_mass_factor);
                let state = &mut self.tool_state[c.tool as usize];
                state.displacement += du;
                state.velocity += du / dt;
            }
        }

        PhaseTimer::lap(&mut self.phases, ContactPhase::Multipliers);
        if self.plies.is_some() {
            // The ply pass leaves the tool friction for the friction pass
            // below, which reads the supports' added multipliers.
            self.ply_normal(x, v, mass, movable, dt, tau, tool_mass_factor);
        }
        if self.has_friction() {
            self.friction(x, v, mass, dt, tau);
            PhaseTimer::lap(&mut self.phases, ContactPhase::Friction);
        }
        if self.plies.is_some() {
            self.ply_friction(x, v, mass, movable, dt, tau);
        }
        self.add_impulse(dt);
        Ok(step)
    }

    /// Adds each tool's force over the step to its impulse: over the step
    /// to t_new, so that the impulse between two frames over their time
    /// apart is the mean force, exact for a constant one. (The tool's
    /// momentum moves by f·Δt_mean: the two sums differ by half the change
    /// of the step between the frames, times f.)
    fn add_impulse(&mut self, dt: f64) {
        for (state, f) in self.tool_state.iter_mut().zip(&self.tool_force) {
            state.impulse += f * dt;
        }
    }

    /// Adds to the constraint set every (node, tool) pair of the candidates
    /// that the solved corrections would leave penetrating by more than the
    /// tolerance: a corrected node against another tool, any node against a
    /// force-driven tool the corrections moved. Each added constraint is
    /// linearised, like the others, at the predicted positions. Returns
    /// whether any was added.
    fn add_violated(
        &mut self,
        x: &[Vector3<f64>],
        mass: &[f64],
        movable: &[bool],
        tool_mass_factor: f64,
    ) -> bool {
        const NONE: u32 = u32::MAX;
        let s = &mut self.scratch;
        let nodes = x.len();
        if s.head.len() != nodes {
            s.head = vec![NONE; nodes];
        }
        s.next.clear();
        let mut tool_shift = std::mem::take(&mut s.tool_shift);
        tool_shift.clear();
        tool_shift.resize(self.tools.len(), 0.0);
        for c in &self.constraints {
            s.node_sum[c.node as usize] = Vector3::zeros();
        }
        // Each node's correction, its constraints as a linked list, and each
        // force-driven tool's correction.
        for (k, c) in self.constraints.iter().enumerate() {
            let i = c.node as usize;
            s.node_sum[i] += c.normal * (c.mu / mass[i]);
            s.next.push(s.head[i]);
            s.head[i] = k as u32;
            if let ToolMotion::Force {
                direction,
                mass: m_tool,
                ..
            } = &self.tools[c.tool as usize].motion
            {
                tool_shift[c.tool as usize] +=
                    -c.normal.dot(direction) * c.mu / (m_tool * tool_mass_factor);
            }
        }
        let tol = self.settings.tolerance;
        let mut added = std::mem::take(&mut s.added);
        added.clear();
        for (t, tool) in self.tools.iter().enumerate() {
            let u = self.tool_state[t].displacement;
            let moved = tool_shift[t] != 0.0;
            for (slot, &i) in self.candidates[t].iter().enumerate() {
                let iu = i as usize;
                if !movable[iu] || !(moved || s.head[iu] != NONE) {
                    continue;
                }
                // A mesh tool's search starts from the node's last triangle
                // (the same answer, see `Surface::project_from`).
                let mut hint = s
                    .projected
                    .get(t)
                    .and_then(|p| p.get(slot))
                    .map_or(u32::MAX, |p| p.hint);
                let mut k = s.head[iu];
                let mut present = false;
                while k != NONE {
                    present |= self.constraints[k as usize].tool == t as u32;
                    k = s.next[k as usize];
                }
                if present {
                    continue;
                }
                let corrected = if s.head[iu] != NONE {
                    x[iu] + s.node_sum[iu]
                } else {
                    x[iu]
                };
                let offset = offset_at(&self.node_offset, self.settings.offset, iu);
                if tool
                    .project_from(&corrected, u + tool_shift[t], &mut hint)
                    .gap
                    - offset
                    < -tol
                {
                    let p = tool.project_from(&x[iu], u, &mut hint);
                    added.push(Constraint {
                        node: i,
                        tool: t as u32,
                        normal: p.normal,
                        gap: p.gap - offset,
                        mu: 0.0,
                    });
                }
            }
        }
        for c in &self.constraints {
            s.head[c.node as usize] = NONE;
        }
        let any = !added.is_empty();
        self.constraints.extend_from_slice(&added);
        self.scratch.added = added;
        self.scratch.tool_shift = tool_shift;
        any
    }

    /// Coulomb friction on the active constraints: the tangential force that
    /// would make the node stick to the tool over the step, capped at μ_f·λ.
    /// `tau` is the time over which a force changes a node's velocity (see
    /// [`Self::enforce_step`]).
    fn friction(
        &mut self,
        x: &mut [Vector3<f64>],
        v: &mut [Vector3<f64>],
        mass: &[f64],
        dt: f64,
        tau: f64,
    ) {
        self.scratch.applied.clear();
        for (k, c) in self.constraints.iter().enumerate() {
            let tool = &self.tools[c.tool as usize];
            if tool.friction == 0.0 || c.mu <= 0.0 {
                continue;
            }
            let i = c.node as usize;
            let v_tool = tool.motion.direction() * self.tool_state[c.tool as usize].velocity;
            let rel = v[i] - v_tool;
            let v_t = rel - c.normal * c.normal.dot(&rel);
            let speed = v_t.norm();
            if speed == 0.0 {
                continue;
            }
            let lambda = c.mu / (dt * tau);
            let trial = mass[i] * speed / tau;
            let limit = tool.friction * lambda;
            let (magnitude, status) = if trial <= limit {
                (trial, ContactStatus::Stick)
            } else {
                (limit, ContactStatus::Slip)
            };
            let f_t = -v_t / speed * magnitude;
            let dv = f_t * (tau / mass[i]);
            v[i] += dv;
            x[i] += dv * dt;
            self.force[i] += f_t;
            self.status[i] = status;
            self.scratch.applied.push((k as u32, f_t));
        }
        // What each friction force does against the slip left once all are
        // applied: a node pinched between two tools slides on both at its
        // final velocity, not at the one it had before the second.
        for &(k, f_t) in &self.scratch.applied {
            let c = &self.constraints[k as usize];
            let v_tool = self.tools[c.tool as usize].motion.direction()
                * self.tool_state[c.tool as usize].velocity;
            let rel = v[c.node as usize] - v_tool;
            let slip = rel - c.normal * c.normal.dot(&rel);
            self.friction_dissipation -= f_t.dot(&slip) * dt;
        }
    }

    /// Solves min ½μᵀAμ + gᵀμ, μ ≥ 0, with A = C·M⁻¹·Cᵀ (nodes and
    /// force-driven tools), by projected conjugate gradients with a Jacobi
    /// preconditioner (Polyak's active-set variant): CG on the free set,
    /// stopping at the first bound it meets, then a new free set.
    // The solver walks several arrays over the constraints in lockstep;
    // indices read more plainly than zips of five iterators.
    #[allow(clippy::needless_range_loop)]
    fn solve_coupled(&mut self, mass: &[f64], tool_mass_factor: f64) -> (usize, f64) {
        let n = self.constraints.len();
        let s = &mut self.scratch;
        for v in [&mut s.r, &mut s.z, &mut s.p, &mut s.q, &mut s.diag] {
            v.clear();
            v.resize(n, 0.0);
        }
        s.free.clear();
        s.free.resize(n, false);
        let tools = &self.tools;
        let cons = &mut self.constraints;
        let mut tool_axis = std::mem::take(&mut s.tool_axis);
        tool_axis.clear();
        tool_axis.extend(tools.iter().map(|t| match &t.motion {
            ToolMotion::Force {
                direction, mass, ..
            } => (*direction, *mass * tool_mass_factor),
            _ => (Vector3::zeros(), f64::INFINITY),
        }));
        let mut tool_sum = std::mem::take(&mut s.tool_sum);
        tool_sum.clear();
        tool_sum.resize(tools.len(), 0.0);
        // y = A·w for a vector w over the constraints.
        let apply = |w: &[f64],
                     y: &mut [f64],
                     node_sum: &mut [Vector3<f64>],
                     tool_sum: &mut [f64],
                     cons: &[Constraint]| {
            for c in cons {
                node_sum[c.node as usize] = Vector3::zeros();
            }
            tool_sum.iter_mut().for_each(|t| *t = 0.0);
            for (c, wk) in cons.iter().zip(w) {
                node_sum[c.node as usize] += c.normal * *wk;
                let (a, _) = tool_axis[c.tool as usize];
                tool_sum[c.tool as usize] += c.normal.dot(&a) * wk;
            }
            for (k, c) in cons.iter().enumerate() {
                let (a, m_t) = tool_axis[c.tool as usize];
                y[k] = c.normal.dot(&node_sum[c.node as usize]) / mass[c.node as usize]
                    + c.normal.dot(&a) * tool_sum[c.tool as usize] / m_t;
            }
        };
        for (k, c) in cons.iter().enumerate() {
            let (a, m_t) = tool_axis[c.tool as usize];
            s.diag[k] = 1.0 / mass[c.node as usize] + c.normal.dot(&a).powi(2) / m_t;
        }
        let tol = self.settings.tolerance;
        // Start from the last round's multipliers (see `add_violated`), a
        // new constraint from its own closed form as if alone. When the
        // constraints are dependent (a node pinched between two tools, a
        // holder resting on many nodes) the multipliers are not unique;
        // starting from zero, which of them round-off lets in first decides
        // the share, and a holder's load would pile on a few nodes that then
        // stick while the rest slide free. The closed-form start shares it
        // by nodal mass, like a pressure, and the same way every step.
        let mut mu = std::mem::take(&mut s.mu);
        mu.clear();
        mu.extend(cons.iter().zip(&s.diag).map(|(c, d)| {
            if c.mu > 0.0 {
                c.mu
            } else {
                (-c.gap).max(0.0) / d
            }
        }));
        let mut iterations = 0;
        let mut residual = f64::INFINITY;
        'outer: while iterations < self.settings.max_iterations {
            // r = −(Aμ + g): the gap still violated (> 0) or open (< 0).
            apply(&mu, &mut s.q, &mut s.node_sum, &mut tool_sum, cons);
            for k in 0..n {
                s.r[k] = -(s.q[k] + cons[k].gap);
                s.free[k] = mu[k] > 0.0 || s.r[k] > 0.0;
            }
            residual = (0..n)
                .filter(|&k| s.free[k])
                .map(|k| s.r[k].abs())
                .fold(0.0, f64::max);
            if residual <= tol {
                break;
            }
            let mut rz = 0.0;
            for k in 0..n {
                s.z[k] = if s.free[k] { s.r[k] / s.diag[k] } else { 0.0 };
                s.p[k] = s.z[k];
                rz += s.r[k] * s.z[k];
            }
            loop {
                iterations += 1;
                apply(&s.p, &mut s.q, &mut s.node_sum, &mut tool_sum, cons);
                let pq: f64 = (0..n).filter(|&k| s.free[k]).map(|k| s.p[k] * s.q[k]).sum();
                if pq <= 0.0 {
                    break;
                }
                let alpha = rz / pq;
                // The longest step that keeps μ ≥ 0.
                let mut alpha_max = f64::INFINITY;
                for k in 0..n {
                    if s.free[k] && s.p[k] < 0.0 {
                        alpha_max = alpha_max.min(-mu[k] / s.p[k]);
                    }
                }
                if alpha >= alpha_max {
                    for k in 0..n {
                        if s.free[k] {
                            mu[k] = (mu[k] + alpha_max * s.p[k]).max(0.0);
                            if s.p[k] < 0.0 && -mu[k] / s.p[k] <= 1e-14 * alpha_max {
                                mu[k] = 0.0;
                            }
                        }
                    }
                    continue 'outer;
                }
                let mut worst = 0.0f64;
                for k in 0..n {
                    if s.free[k] {
                        mu[k] += alpha * s.p[k];
                        s.r[k] -= alpha * s.q[k];
                        worst = worst.max(s.r[k].abs());
                    }
                }
                if worst <= tol || iterations >= self.settings.max_iterations {
                    continue 'outer;
                }
                let mut rz_new = 0.0;
                for k in 0..n {
                    if s.free[k] {
                        s.z[k] = s.r[k] / s.diag[k];
                        rz_new += s.r[k] * s.z[k];
                    }
                }
                let beta = rz_new / rz;
                rz = rz_new;
                for k in 0..n {
                    if s.free[k] {
                        s.p[k] = s.z[k] + beta * s.p[k];
                    }
                }
            }
        }
        for (c, m) in cons.iter_mut().zip(&mu) {
            c.mu = *m;
        }
        s.mu = mu;
        s.tool_axis = tool_axis;
        s.tool_sum = tool_sum;
        (iterations, residual)
    }
}

#[cfg(test)]
mod tests;
