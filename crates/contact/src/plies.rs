//! Contact between the deformable plies of a laminate, for the explicit
//! pass: node-to-face constraints between neighbouring plies, enforced
//! by forward-increment Lagrange multipliers like the tools' (SPEC §6),
//! with Coulomb friction by return mapping.
//!
//! Each interface (a ply and the one below it) is searched both ways: the
//! upper ply's nodes against the lower ply's triangles and the lower
//! ply's nodes against the upper's, so neither ply's nodes pass through
//! the other's faces when the meshes differ. A constraint keeps a node
//! half a thickness of each ply (the sum of the two half thicknesses) from
//! the face's mid-surface: g = (xₛ − Σ wⱼxⱼ)·n − (hₐ + h_b)/2 ≥ 0, with wⱼ
//! the barycentric weights of the closest point.
//!
//! Which side of a neighbour a node belongs on is the stacking side,
//! which each face's normal (wound up the stack) carries through the
//! ply's folds. A node found inside a ply beyond its mid-surface, which
//! no step's motion does (a fold came over it), is put back out on its
//! own side, not the nearer one (which is through the ply), by a shift of
//! position alone: the shift is up to the plies' thickness, and as a
//! velocity it would throw the node. (Near the ply's free end it goes out
//! through the end instead, where that is shorter: below.)
//! A side memory that turned a node's side when it was seen clear on the
//! far side of a ply (shell contact codes keep one) stopped the full
//! four-ply hemisphere at t = 0.95 s with a `p90` node held at the offset
//! on the far side of `p45`, its side turned near a fold.
//!
//! A ply ends square at its free outline, and a node may hang beside the
//! end on either side of the ply, but never come round it to the far side
//! of the face. Nothing else stops that: beside the end a node is free,
//! and past the end plane behind the ply, deeper than the offset, the
//! faces take it for another part of the ply (a fold), so a free edge
//! went round its neighbour's (in the four-ply hemisphere, whose
//! four plies share one outline, a `p45` node came round `p90`'s edge
//! 0.5 mm beside it and crossed the end plane 2 mm behind it). So a node
//! behind a face whose way out through the end is shorter than the way
//! back to its own side is held by the end: a row whose normal lies in
//! the ply, out of the end ([`narrow`]). It stops a node going in, and an
//! end that comes over a node behind it pushes the node along. Such a row
//! can begin violated by more than a step's motion (the end plane comes
//! to a node as a face switches, and a node that comes up beside the end
//! into the face's hold from the far side starts up to the offset inside
//! it: at the four-ply hemisphere's 2e-5 s step, a velocity of 15 m/s):
//! what the two plies' motion over the step brought is stopped as a
//! velocity, an inelastic impact, and the rest moved as a position.
//!
//! The normal rows give a little: each holds its gap at κ times what its
//! own push moves it in the step ([`NORMAL_COMPLIANCE`], about 0.2 % of
//! the thickness under the shipped holder), which makes the multipliers
//! unique where rigid rows leave them undetermined (a stack clamped
//! between a holder and a die).
//!
//! Stick is exact, not regularised: the friction multiplier makes the
//! relative tangential velocity zero unless that needs more than μλ (as
//! for the tools): a penalty would need a stiffness that either limits the
//! stable step or lets a sticking ply creep, and the sled and incline
//! validations would then test the penalty, not Coulomb's law.
//!
//! A row is in a step's solve where its gap at the predicted positions is
//! violated, or clear by less than the step's deepest violation, since the
//! solve's corrections may close it (a ply resting on one that its own
//! rows push up). Before, only violated rows were: three plies on a plate
//! under a bag's ramped pressure on the upper two, the top ply was left
//! inside the middle one by each push and thrown back out by the next
//! step's row, ringing, its kinetic energy growing with the load until the
//! energy guard stopped the run. A node clear by more, within the offset,
//! joins once the corrections close it ([`wake`]).
//!
//! The constraints of a step couple (a node pressed by the ply above into
//! the ply below, a ply between two tools), so the multipliers are found
//! by projected Gauss–Seidel sweeps over the constraints in a fixed order
//! (results independent of the thread count), with the nodes that a tool
//! pressed this step, or that lie within the offset of one, held on the
//! tool by a support constraint whose multiplier goes to that tool's
//! contact ([`Support`]). A force-driven tool (a blank holder) is not held
//! where the tool pass left it: its supports move it ([`DrivenTool`]),
//! since between a holder and a die the holder's step presses the top ply
//! into the one below, and only the holder can give way. Three things keep
//! the sweeps few: where a node of each ply is nearest a node of the
//! other, the two searches' rows (nearly the same row, which Gauss–Seidel
//! shares out between them without end) are one row with the deeper gap;
//! the sweeps are over-relaxed ([`NORMAL_OMEGA`], [`FRICTION_OMEGA`]);
//! and each solve starts from the forces of the step before. And a sweep
//! passes over a row whose update is bound to be negligible, its nodes
//! having barely moved since its last one ([`SKIP`]): most rows of a late
//! sweep are settled while a few still move. A solve that
//! has reached a plateau far below the overlap the plies may have stops
//! there ([`STALL_SWEEPS`]). A holder much heavier than the nodes it
//! presses converges slowly (its share of a correction is their mass
//! over its own); the shipped holder weighs about the blank.
//!
//! Broad phase: per search direction, a uniform grid of the master ply's
//! faces grown by the reach; each slave node lists the faces whose grown
//! box holds it. The lists are rebuilt when a node of either ply has moved
//! half the margin, so a stack pays only near where plies meet.
//! Narrow phase ([`narrow`]): each slave node's closest candidate face,
//! found without projecting the node on the faces a bound rules out.
//!
//! What it is not: tool contact ([`crate::ExplicitContact`] holds both and
//! calls this pass), nor an implicit ply contact.

use nalgebra::Vector3;
use rayon::prelude::*;

mod carry;
mod narrow;
mod overlap;
pub use carry::PlyCarry;
use narrow::{FaceBound, Master, closest_on_triangle, face_bounds};
pub use overlap::{FaceBend, PlyOverlap};

/// The ply rows' compliance, as a share of each row's own step: a row
/// holds g + κ·μ/m ≥ 0 instead of g ≥ 0 (μ its multiplier, m its
/// effective mass, so μ/m is how far its own push moves it in the step).
/// What graphics codes call constraint force mixing: with it the rows'
/// system is strictly monotone, so its multipliers are unique and the
/// sweeps converge at a rate bounded away from 1.
///
/// Rigid rows (κ = 0) left two things undetermined. Between a blank
/// holder and a die, how the holder's force is shared among the columns
/// of nodes under it (rigid tools, plies rigid through their thickness):
/// the sweeps settled on a share that depends on the rows' order, and the
/// two-ply deep drawing (24 × 24 cells, symmetric about both axes) slid
/// toward −y from t = 0.2 s (−10.9 mm by 0.35 s), drew in 40 mm on one
/// edge and 5 mm on the other, and stopped at t = 0.356 s on a node thrown
/// into the die. With κ = 0.025 it stays centred (mean displacement
/// within 0.001 mm at every frame) and draws the whole stroke. And on
/// a dome, a lower ply's nodes under the upper ply's chord faces make rows
/// nearly dependent on the upper ply's own (docs/notes/stack-cost.md):
/// the four-ply hemisphere's last 10 641 steps took 102 normal sweeps a
/// step rigid and 49 at κ = 0.025 (and 97 / 109 friction sweeps).
///
/// What it costs is a give: a row resting under a steady force F sits
/// κ·μ/m = κ·F·Δt²/m inside the offset. Under the shipped deep drawing's
/// holder (3.25 MPa on two 69-fold mass-scaled glass plies at Δt = 2e-5 s,
/// 1/m = 2/m_node) that is about 1.3 µm, 0.2 % of the ply's thickness; on
/// the hemisphere stacks far less. A row that begins a step violated by d
/// (an impact) ends it κ/(1+κ)·d inside, and each step after takes that
/// by the same factor. It vanishes with the step, as Δt². A step shorter
/// than the run's longest (its last, landing on the end time) keeps the
/// give as a force, like a spring of stiffness m/(κ·Δt²) at the longest Δt
/// (`a_shortened_step_keeps_the_rows_give`).
pub(crate) const NORMAL_COMPLIANCE: f64 = 0.025;

/// Sweeps allowed to the friction solve: a stack sticking on a tool
/// needs its friction to [`FRICTION_TOLERANCE`] (no creep beyond it);
/// the four-ply hemisphere's steps took at most 100 over the first 0.3 s
/// (12 × 12 and 24 × 24 cells).
const FRICTION_SWEEPS: usize = 500;

/// The normal solve stops when what is left of every row's violation is
/// this fraction of the largest violation at the start of the step (the
/// step's penetration; an absolute tolerance would be most of a slow
/// step's, Δt²·a). What is left is the next step's gap, so the overlap it
/// leaves is 1e-5 of one step's penetration, far below the 1 % of the
/// thickness the plies may overlap. The multipliers' error scales with it
/// and sets the friction caps: the sled's sliding friction μN comes out
/// within 3e-9 of μN (at 1e-4 within 6e-7 to 6e-6, which its
/// validation's 1e-6 does not always pass) against the 1 %.
/// Late in the four-ply hemisphere's stroke (24 × 24 and 17 × 17 cells,
/// t = 0.79–1 s) the sweeps gain a decade only every ~35 sweeps: 1e-6
/// took 140 sweeps a step there, 1e-5 104 and 1e-4 71.
pub(crate) const NORMAL_TOLERANCE: f64 = 1e-5;

/// The friction solve stops when no tangential force changes by more than
/// this fraction of the largest cap (μλ) in a sweep. A sticking node then
/// slides, per step, at most this fraction of what its cap would move it
/// in a step (a_cap·Δt², a_cap = μλ/m): over a time t, ε·a_cap·Δt·t. On
/// the incline (a_cap ≈ 4·10³ mm/s², t = 0.02 s) a sticking ply moves
/// 6e-11 and 3.8e-10 mm against the check's 1e-9 mm, which 1e-4 exceeds
/// (1.3e-9 mm).
/// Late in the four-ply hemisphere's stroke 1e-6 took 141 sweeps a step,
/// 1e-5 100 and 1e-4 64.
const FRICTION_TOLERANCE: f64 = 1e-5;

/// The normal solve also stops when [`STALL_SWEEPS`] sweeps have not
/// taken a tenth off the largest violation left and that is below
/// [`STALL_GAP`] of the smallest offset (the plies' half thicknesses):
/// more sweeps would move it little, and it is far below the overlap the
/// plies may have. A stack pressed between a blank holder and a die was
/// such a plateau with rigid rows: the holder's clamp could be shared
/// among the columns of nodes under it in any way, and the sweeps
/// wandered among the shares. The two-ply deep drawing (24 × 24 cells)
/// left 7e-7 mm after 20 sweeps, 1.5e-4 of the step's 2e-3 mm, and then
/// ran to the 200 sweeps' cap in about 4 800 of its first 4 971 steps
/// without taking it below that. With [`NORMAL_COMPLIANCE`] the share is
/// unique, but the same drawing still stops here in 16 642 of its first
/// 18 164 steps (which rows plateau was not traced).
const STALL_SWEEPS: usize = 8;

/// See [`STALL_SWEEPS`]: the sweeps must have taken the step's largest
/// violation down a hundredfold before a plateau counts. A slow solve is
/// no plateau: a heavy holder on a few light nodes gains a little every
/// sweep, and stopped as stalled it left the whole step's violation.
const STALL_SHARE: f64 = 1e-2;

/// See [`STALL_SWEEPS`]: a thousandth of the offset, 0.3–0.6 µm for the
/// presets' plies (the overlap check allows 1 %, ten times more).
const STALL_GAP: f64 = 1e-3;

/// The friction solve stops, like the normal one ([`STALL_SWEEPS`]), when
/// the sweeps have not taken a tenth off the largest change of a force in
/// a sweep and that is below this fraction of the largest cap. Nodes
/// pinched between two tools through a stack, sticking, can share their
/// friction among the tools and the interfaces in any way: the two-ply
/// deep drawing's sweeps wandered among the shares at changes of 2e-6 to
/// 3e-5 of the largest cap per sweep, and ran out of their 500 in 134 of
/// its first 2 471 steps (87 % of the friction solve's time).
const FRICTION_STALL: f64 = 1e-4;

/// The weight of a face's vertex above which a node's closest point is
/// taken to be at that vertex, for pairing a node with a node of the other
/// ply ([`mutual`]): rows of such a pair differ by less than a fifth of a
/// node's share, so one row keeps both gaps to that fraction of one step's
/// correction, which the next step's gap takes up.
const PAIR_WEIGHT: f64 = 0.9;

/// Over-relaxation of the projected Gauss–Seidel sweeps of the normal
/// solve: any factor in (0, 2) converges to the same multipliers on this
/// convex problem. On the four-ply hemisphere (12 × 12 cells, at the
/// earlier tolerance of 1e-6) 1.5 takes 53 sweeps per step over the whole
/// stroke against 79 at 1.3, and over the first 0.3 s 28 against 34 at
/// 1.3, 52 at 1.1 and 42 at 1.7.
const NORMAL_OMEGA: f64 = 1.5;

/// Over-relaxation of the friction solve's sweeps (then plain ones, see
/// [`PlyContact::friction`]): on the same runs 1.3 takes 19 sweeps per
/// step over the first 0.3 s against 21 at 1.5 and 38 at 1.7.
const FRICTION_OMEGA: f64 = 1.3;

/// A sweep passes over a row whose update is bound to change it by less
/// than this fraction of the solve's tolerance. Between two of its
/// updates a row's next one is at most (ω − 1) times its last (its own
/// over-relaxation: its trial value moves by that) plus ω times what the
/// other rows' updates have moved its nodes since, taken as the sum of
/// their magnitudes (a projection on λ ≥ 0 or on the friction disc is
/// non-expansive), so a skipped update is below this bound, and the
/// solve stops at the same tolerance. (ω must be the same for both
/// updates: the friction solve updates every row at the sweep after it
/// turns ω to 1.)
///
/// Over the first 0.3 s of the four-ply hemisphere 4 % of the friction
/// sweeps' updates and 9 % of the normal sweeps' were above the
/// tolerance. Over its whole stroke (one thread) the rows updated fell
/// from 1.85·10⁹ to 0.68·10⁹ (friction) and from 1.36·10⁹ to 0.74·10⁹
/// (normal) at the same sweeps a step, the ply contact from 2 125 to
/// 1 906 µs a step, the step from 2 806 to 2 642 µs; on two threads
/// 117.0 → 109.5 s. The sweeps' count is what is left: late in the stroke
/// about half of every sweep's rows still move.
const SKIP: f64 = 0.1;

/// Slave nodes projected per rayon task.
const NODES_PER_TASK: usize = 256;

/// A ply as the contact sees it: its nodes (a contiguous range), its
/// triangles (quads split in two), wound so that their normal points up
/// the stack, and half its thickness.
#[derive(Debug, Clone)]
pub struct PlyLayer {
    /// First node.
    pub first_node: u32,
    /// Number of nodes.
    pub node_count: u32,
    /// Triangles, normal up the stack.
    pub faces: Vec<[u32; 3]>,
    /// Half the ply's thickness (mm).
    pub half_thickness: f64,
}

/// Two neighbouring plies and the friction coefficient between them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlyInterface {
    /// The lower ply (index into the layers).
    pub lower: usize,
    /// The upper ply.
    pub upper: usize,
    /// Coulomb coefficient.
    pub friction: f64,
}

/// A node held on a tool this step: the ply pass may not push it into the
/// tool along `normal`; the multiplier it needs is the tool's.
#[derive(Debug, Clone, Copy)]
pub struct Support {
    /// The node.
    pub node: u32,
    /// The tool's normal at the node (towards the fabric).
    pub normal: Vector3<f64>,
    /// The node's gap to the tool at the start of the pass (mm): 0 for a
    /// node the tool pass pressed onto it, else what is left before the
    /// node touches.
    pub gap: f64,
    /// The support's multiplier found by the last solve (μ = λ·Δt·τ).
    pub mu: f64,
    /// The tool when it is force-driven, which the pass moves with the
    /// multipliers it adds (None: it moves as prescribed).
    pub driven: Option<DrivenTool>,
}

/// A force-driven tool (a blank holder under its force) behind a
/// [`Support`]. The ply pass must move it: between a holder and a die a
/// stack's two plies are pressed together by the holder, and with the
/// holder held where the tool pass left it the plies cannot be put apart
/// without going into a tool; the sweeps then diverge and throw nodes
/// (a two-ply deep drawing stopped at t = 0.021 s, a node moved 0.75 mm in
/// one step).
#[derive(Debug, Clone, Copy)]
pub struct DrivenTool {
    /// The tool's index into the shifts [`PlyContact::normal`] returns.
    pub tool: u32,
    /// n·d, the tool's axis d on the support's normal: the node's gap
    /// closes by `along` per unit of the tool's travel along d.
    pub along: f64,
    /// The tool's inverse mass in the nodes' units (1/(M·τ/Δt_mean), as in
    /// [`crate::ExplicitContact::enforce_step`]).
    pub inverse_mass: f64,
    /// The tool pass's multiplier on this node: the support may take it
    /// back (down to no push at all) when the pass moves the tool away.
    pub held: f64,
}

/// A node's friction on a tool, for the joint friction solve: what the
/// tool pass applied and may apply (its cap, μ_tool·λ).
#[derive(Debug, Clone, Copy)]
pub struct ToolFriction {
    /// The node.
    pub node: u32,
    /// The tool's normal.
    pub normal: Vector3<f64>,
    /// The tool's velocity.
    pub tool_velocity: Vector3<f64>,
    /// μ·λ of the contact (N).
    pub cap: f64,
    /// The tangential force on the node (N).
    pub force: Vector3<f64>,
}

/// A slave node's closest face.
#[derive(Debug, Clone, Copy)]
struct Hit {
    gap: f64,
    normal: Vector3<f64>,
    nodes: [u32; 3],
    w: [f64; 3],
    /// The face (index into the master's faces; `u32::MAX`: none).
    face: u32,
    found: bool,
    /// The node is inside the face's ply on the far side of its
    /// mid-surface from its own (the stacking side, [`Search::side`]):
    /// it came round a free edge or a fold, and goes back by a shift of
    /// its position, not a velocity ([`PlyContact::normal`]).
    recover: bool,
    /// The node is inside the face's ply through its free end (or on
    /// the far side past it), the way out through that end the shorter:
    /// `normal` is in the ply's plane, out of the end, and `w` the
    /// weights of the nearest point of the end.
    end: bool,
}

impl Hit {
    const NONE: Self = Self {
        gap: f64::INFINITY,
        normal: Vector3::new(0.0, 0.0, 0.0),
        nodes: [0; 3],
        w: [0.0; 3],
        face: u32::MAX,
        found: false,
        recover: false,
        end: false,
    };
}

/// One search direction of an interface.
#[derive(Debug, Clone, Default)]
struct Search {
    slave: usize,
    master: usize,
    /// +1 when the slave ply is above the master, −1 below.
    side: f64,
    friction: f64,
    /// Sum of the two half thicknesses (mm).
    offset: f64,
    /// Candidate faces of each slave node (CSR over the slave's nodes).
    cand_ptr: Vec<u32>,
    cand: Vec<u32>,
    hits: Vec<Hit>,
    /// The master faces' grown boxes, and the grid of them.
    boxes: Vec<[f64; 6]>,
    cell_ptr: Vec<u32>,
    cell_faces: Vec<u32>,
    fill: Vec<u32>,
    /// Each slave node's multiplier (as a force, N) and tangential force
    /// at the last pass it was constrained, and that pass's number: the
    /// next pass's solves start from them.
    warm: Vec<Warm>,
}

impl Default for Hit {
    fn default() -> Self {
        Self::NONE
    }
}

#[derive(Debug, Clone, Copy)]
struct Constraint {
    slave: u32,
    masters: [u32; 3],
    w: [f64; 3],
    normal: Vector3<f64>,
    gap: f64,
    mu: f64,
    /// 1/(1/mₛ + Σ wⱼ²/mⱼ) with the fixed nodes' inverse mass 0.
    mass: f64,
    /// The inverse masses of the slave and the masters (0 for a fixed
    /// node), read by every sweep.
    inv: [f64; 4],
    /// The upper ply's node whose slip on the ply below the row measures
    /// (`u32::MAX`: none, a row of a lower node alone).
    slip_node: u32,
    search: u32,
    /// How much of the violation goes as a shift of position before the
    /// solve (mm): all of it for a node back to its side
    /// ([`Hit::recover`]), what is beyond the step's motion for a node
    /// put back out through the end ([`Hit::end`]) or deep in the ply at
    /// the step's start, else none.
    shift: f64,
    /// The row's give per unit of its own step (μ/m): κ
    /// ([`NORMAL_COMPLIANCE`]) at the longest step so far, more at a
    /// shorter one; 0 for a row that holds a node out of a free end
    /// ([`Hit::end`]): that one is a rule of where a node may go, not a
    /// ply pressed through its thickness.
    compliance: f64,
}

impl Constraint {
    /// The slave's correction `dx` relative to its face's point.
    fn relative(&self, dx: &[Vector3<f64>]) -> Vector3<f64> {
        dx[self.slave as usize]
            - self
                .masters
                .iter()
                .zip(&self.w)
                .map(|(&j, w)| dx[j as usize] * *w)
                .sum::<Vector3<f64>>()
    }
}

/// A constraint's forces at a pass, for the next pass to start from.
#[derive(Debug, Clone, Copy, Default)]
struct Warm {
    normal: f64,
    tangential: Vector3<f64>,
    pass: u64,
}

/// What the last step of the ply pass did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PlyStep {
    /// Active node-to-face constraints.
    pub active: usize,
    /// Gauss–Seidel sweeps.
    pub sweeps: usize,
    /// Largest linearised gap violation left (mm): at most 1e-5
    /// (`NORMAL_TOLERANCE`) of the largest at the start unless the sweeps
    /// ran out or stalled.
    pub residual: f64,
    /// The sweeps stopped on a plateau below a thousandth of the offset
    /// (`STALL_SWEEPS`).
    pub stalled: bool,
}

/// Sums over the steps of the ply pass since it was made: what its
/// solves cost, for a profile or a validation note.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct PlyTotals {
    /// Steps with at least one active constraint.
    pub steps: u64,
    /// Active constraints, summed over those steps.
    pub constraints: u64,
    /// Gauss–Seidel sweeps of the normal solve, summed.
    pub normal_sweeps: u64,
    /// Sweeps of the friction solve, summed.
    pub friction_sweeps: u64,
    /// The most sweeps one step's normal solve took.
    pub max_normal_sweeps: usize,
    /// The most sweeps one step's friction solve took.
    pub max_friction_sweeps: usize,
    /// Steps whose normal solve ran out of sweeps.
    pub normal_capped: u64,
    /// Steps whose normal solve stopped on a plateau (`STALL_SWEEPS`): what
    /// they left is below a thousandth of the plies' offset.
    pub normal_stalled: u64,
    /// Steps whose friction solve ran out of sweeps.
    pub friction_capped: u64,
    /// Steps whose friction solve stopped on a plateau (`FRICTION_STALL`).
    pub friction_stalled: u64,
    /// Nodes moved by a shift of position (put back out on their side of
    /// a ply), summed over the steps ([`PlyContact::shifts`]).
    #[serde(default)]
    pub shifted_nodes: u64,
}

/// The ply–ply contact pass.
#[derive(Debug, Clone)]
pub struct PlyContact {
    layers: Vec<PlyLayer>,
    searches: Vec<Search>,
    /// Per layer and face, which of its features lie on the ply's free
    /// outline: bits 0–2 the edges ab, bc, ca, bits 3–5 the vertices.
    outline: Vec<Vec<u8>>,
    /// Per layer and face, its bound at this step's positions (for the
    /// narrow phase, [`narrow`]).
    face_bound: Vec<Vec<FaceBound>>,
    margin: f64,
    tolerance: f64,
    max_sweeps: usize,
    /// [`NORMAL_COMPLIANCE`]; 0 in the tests of the rigid rows' limit.
    pub(crate) compliance: f64,
    /// The longest Δt·τ of the passes so far: the step the rows' give is
    /// set at ([`NORMAL_COMPLIANCE`]).
    spring_step: f64,
    reference_x: Vec<Vector3<f64>>,
    constraints: Vec<Constraint>,
    /// This step's rows of nodes resting on the neighbour, clear of it at
    /// the predicted positions by at least the step's deepest violation
    /// and less than the offset: not in the solve unless its corrections
    /// close them ([`wake`]).
    dormant: Vec<Constraint>,
    dx: Vec<Vector3<f64>>,
    /// The part of each node's `dx` that moves it back to its side of a
    /// ply it came round ([`Hit::recover`]): a position correction only.
    shift: Vec<Vector3<f64>>,
    /// The shifts of the last normal pass, by node (in the order the
    /// constraints visit them): what the driver's energy balance counts
    /// as the contact's work, not as motion ([`Self::shifts`]).
    shifted: Vec<(u32, Vector3<f64>)>,
    /// Each constraint's tangential force in the friction solve.
    f_t: Vec<Vector3<f64>>,
    /// The velocities before the friction sweeps.
    v_before: Vec<Vector3<f64>>,
    /// Per node, the sum of the magnitudes of the changes the current
    /// solve's updates made to its velocity (friction) or its correction
    /// (normal); per row, that sum over its nodes after its own last
    /// update, and the size of that update: what lets a sweep pass over a
    /// row whose update would be negligible ([`SKIP`]).
    drift: Vec<f64>,
    row_seen: Vec<f64>,
    row_last: Vec<f64>,
    /// Each node's reference area (for the pressure).
    area: Vec<f64>,
    /// Accumulated tangential slip of each node on the ply below (mm).
    pub slip: Vec<f64>,
    /// Contact pressure of the ply below on each node at the last step
    /// (MPa): the normal force on the node over its area, from the rows of
    /// its own and, by their weights, those of the lower ply's nodes under
    /// its faces (0 on the bottom ply; a middle node's pressure from the
    /// ply above is that ply's).
    pub pressure: Vec<f64>,
    /// Nodes whose pressure was set at the last step.
    touched: Vec<u32>,
    /// Friction dissipated between plies so far (mJ).
    pub friction_dissipation: f64,
    /// The last step.
    pub last: PlyStep,
    /// Sums over the steps so far.
    pub totals: PlyTotals,
    /// Passes so far (the normal pass counts them).
    pass: u64,
    /// Each interface's largest overlap over the checks so far (mm)
    /// ([`Self::record_overlap`]).
    overlap_peak: Vec<f64>,
    /// The deepest overlap at the checks so far ([`Self::worst_overlap`]).
    worst_overlap: Option<PlyOverlap>,
}

impl PlyContact {
    /// A pass over `node_count` nodes of the `layers` with their
    /// `interfaces`; `area` is each node's reference area (mm²), `margin`
    /// the broad phase's (mm).
    pub fn new(
        layers: Vec<PlyLayer>,
        interfaces: &[PlyInterface],
        area: Vec<f64>,
        margin: f64,
    ) -> Self {
        let n = area.len();
        let mut searches = Vec::new();
        for i in interfaces {
            let offset = layers[i.lower].half_thickness + layers[i.upper].half_thickness;
            for (slave, master, side) in [(i.upper, i.lower, 1.0), (i.lower, i.upper, -1.0)] {
                let count = layers[slave].node_count as usize;
                searches.push(Search {
                    slave,
                    master,
                    side,
                    friction: i.friction,
                    offset,
                    cand_ptr: vec![0; count + 1],
                    hits: vec![Hit::NONE; count],
                    warm: vec![Warm::default(); count],
                    boxes: vec![[0.0; 6]; layers[master].faces.len()],
                    ..Search::default()
                });
            }
        }
        let outline = layers.iter().map(|l| outline_of(&l.faces)).collect();
        let face_bound = layers
            .iter()
            .map(|l| vec![FaceBound::default(); l.faces.len()])
            .collect();
        Self {
            outline,
            face_bound,
            layers,
            searches,
            margin,
            tolerance: NORMAL_TOLERANCE,
            // The four-ply hemisphere's steps took at most 119 over the
            // whole 12 × 12 stroke (at 1e-8 and 1.3, 21 843 of the 24 × 24
            // stroke's 50 454 ran out); a step that runs out is counted
            // ([`PlyTotals::normal_capped`]) and what it leaves is the
            // next step's gap.
            max_sweeps: 200,
            compliance: NORMAL_COMPLIANCE,
            spring_step: 0.0,
            reference_x: Vec::new(),
            constraints: Vec::with_capacity(2 * n),
            dormant: Vec::with_capacity(2 * n),
            dx: vec![Vector3::zeros(); n],
            shift: vec![Vector3::zeros(); n],
            shifted: Vec::new(),
            f_t: Vec::with_capacity(2 * n),
            v_before: Vec::with_capacity(n),
            drift: vec![0.0; n],
            row_seen: Vec::with_capacity(2 * n),
            row_last: Vec::with_capacity(2 * n),
            area,
            slip: vec![0.0; n],
            pressure: vec![0.0; n],
            touched: Vec::with_capacity(n),
            friction_dissipation: 0.0,
            last: PlyStep::default(),
            totals: PlyTotals::default(),
            pass: 0,
            overlap_peak: vec![0.0; interfaces.len()],
            worst_overlap: None,
        }
    }

    /// The layers.
    pub fn layers(&self) -> &[PlyLayer] {
        &self.layers
    }

    /// The nodes the last normal pass moved by a shift of position (a
    /// node put back out on its side of a ply, see the module doc), and
    /// each one's shift (mm). A shift changes no velocity, so the
    /// driver's energy balance, which integrates work over the motion,
    /// counts the work it takes against the node's forces as the
    /// contact's.
    pub fn shifts(&self) -> &[(u32, Vector3<f64>)] {
        &self.shifted
    }

    /// Number of candidate (node, face) pairs of the broad phase.
    pub fn candidate_pairs(&self) -> usize {
        self.searches.iter().map(|s| s.cand.len()).sum()
    }

    /// Starts a solve's record of what its updates move ([`SKIP`]): the
    /// drift of the rows' nodes and of the `other` nodes the solve moves
    /// (the tools' supports or friction) at zero, each row's at zero.
    fn begin_sweeps(&mut self, other: impl Iterator<Item = u32>) {
        let rows = self.constraints.len();
        for record in [&mut self.row_seen, &mut self.row_last] {
            record.clear();
            record.resize(rows, 0.0);
        }
        let drift = &mut self.drift;
        for c in self.constraints.iter().chain(&self.dormant) {
            for i in std::iter::once(c.slave).chain(c.masters) {
                drift[i as usize] = 0.0;
            }
        }
        for i in other {
            drift[i as usize] = 0.0;
        }
    }

    /// Rebuilds the candidate lists once a node has moved half the margin.
    fn refresh(&mut self, x: &[Vector3<f64>]) {
        let half = 0.5 * self.margin;
        let moved = self.reference_x.len() != x.len()
            || x.par_iter()
                .zip(&self.reference_x)
                .with_min_len(4096)
                .any(|(a, b)| (a - b).norm_squared() > half * half);
        if !moved {
            return;
        }
        for s in &mut self.searches {
            let reach = s.offset + self.margin;
            build_candidates(s, &self.layers, x, reach);
        }
        self.reference_x.clear();
        self.reference_x.extend_from_slice(x);
    }

    /// The ply constraints' normal pass on the predicted `x`, `v`: finds
    /// the constraints, solves their multipliers together with the tools'
    /// `supports`, and corrects `x` and `v`; adds each ply's normal force to
    /// `force`. `tau` as in [`crate::ExplicitContact::enforce_step`].
    /// `tool_shift[t]` gets the travel along its axis that the pass gives
    /// force-driven tool t ([`Support::driven`]; zero for the others).
    #[allow(clippy::too_many_arguments)]
    pub fn normal(
        &mut self,
        x: &mut [Vector3<f64>],
        v: &mut [Vector3<f64>],
        mass: &[f64],
        movable: &[bool],
        dt: f64,
        tau: f64,
        supports: &mut [Support],
        tool_shift: &mut [f64],
        force: &mut [Vector3<f64>],
    ) -> PlyStep {
        tool_shift.fill(0.0);
        self.shifted.clear();
        for &i in &self.touched {
            self.pressure[i as usize] = 0.0;
        }
        self.touched.clear();
        self.constraints.clear();
        self.dormant.clear();
        self.pass += 1;
        // A row's give in a step is κ·μ/m at the longest step so far, as
        // a force (μ/(Δt·τ)): a run's last step, shortened to land on the
        // end time, would otherwise take its give back at once and throw
        // the plies apart (1.3 µm in a step of a few ns, the quick
        // stacked deep drawing's energy balance off by a third).
        self.spring_step = self.spring_step.max(dt * tau);
        let give = self.compliance * self.spring_step / (dt * tau);
        self.refresh(x);
        let inv = |i: u32| inverse_mass(mass, movable, i);
        let layers = &self.layers;
        // The bounds of the faces of every ply (each is some search's
        // master).
        self.face_bound
            .par_iter_mut()
            .zip(layers)
            .for_each(|(bounds, l)| face_bounds(&l.faces, x, bounds));
        // The searches side by side, each split into tasks: one search's
        // slave ply is a few hundred nodes on a small mesh, under two
        // tasks' worth, and searched one after the other the four-ply
        // hemisphere at 12 × 12 cells ran its whole narrow phase on one
        // thread. Each hit is its node's alone, so the split changes no
        // bit.
        let (x_now, outline, face_bound, margin) =
            (&*x, &self.outline, &self.face_bound, self.margin);
        self.searches.par_iter_mut().for_each(|s| {
            let slave = &layers[s.slave];
            let master = Master {
                faces: &layers[s.master].faces,
                outline: &outline[s.master],
                bounds: &face_bound[s.master],
                side: s.side,
                offset: s.offset,
                reach: s.offset + margin,
            };
            let (ptr, cand) = (&s.cand_ptr, &s.cand);
            s.hits
                .par_iter_mut()
                .enumerate()
                .with_min_len(NODES_PER_TASK)
                .for_each(|(local, hit)| {
                    let range = ptr[local] as usize..ptr[local + 1] as usize;
                    *hit = if range.is_empty() {
                        Hit::NONE
                    } else {
                        let p = x_now[slave.first_node as usize + local];
                        master.closest(&p, x_now, &cand[range], hit.face)
                    };
                });
        });
        for (k, s) in self.searches.iter().enumerate() {
            let slave = &layers[s.slave];
            // The search the other way of the same interface ([`Self::new`]
            // pushes them in pairs, the upper ply's nodes first).
            let other = &self.searches[if s.side > 0.0 { k + 1 } else { k - 1 }];
            let other_slave = &layers[s.master];
            for (local, hit) in s.hits.iter().enumerate() {
                if !hit.found {
                    continue;
                }
                let node = slave.first_node + local as u32;
                // Two nodes each nearest the other, one in each ply: the
                // two searches' rows are nearly one row, which
                // Gauss–Seidel shares out between them without end (and
                // never settles where their gaps differ by round-off).
                // The deeper of the two is kept, as it is; the other gap
                // moves with it to first order, and is the deeper one at
                // a later step if it falls behind.
                let pair = mutual(hit, node, other, other_slave);
                let deeper = |o: &Hit| {
                    if s.side > 0.0 {
                        o.gap < hit.gap
                    } else {
                        o.gap <= hit.gap
                    }
                };
                if pair.is_some_and(deeper) {
                    continue;
                }
                let gap = hit.gap;
                // The upper ply's node whose slip on the ply below this
                // row measures: its slave, or for a row kept for a pair
                // from below, the pair's upper node.
                let slip_node = match (s.side > 0.0, pair) {
                    (true, _) => node,
                    (false, Some(_)) => nearest(hit).unwrap_or(u32::MAX),
                    (false, None) => u32::MAX,
                };
                // A node clear of the face by up to the offset may be
                // pushed onto it by the solve (the ply below it pushed up
                // by its own rows or a tool): its row waits, dormant.
                if gap >= s.offset {
                    continue;
                }
                let m_inv = inv(node)
                    + hit
                        .nodes
                        .iter()
                        .zip(&hit.w)
                        .map(|(&j, w)| w * w * inv(j))
                        .sum::<f64>();
                if m_inv == 0.0 {
                    continue;
                }
                let shift = if hit.recover {
                    -gap
                } else {
                    // What the plies' motion over this step brought of the
                    // violation is stopped as a velocity (an inelastic
                    // impact). The rest was there before the step and goes
                    // as a shift of position, for a node put back out
                    // through the end and for one within half the offset
                    // of the mid-surface at the step's start (come in from
                    // the far side, sideways through the end, or level
                    // with the mid-plane, where the side is round-off). A
                    // node resting on the ply, about the offset from it
                    // (also on the edge of an equal blank), keeps its row
                    // as it was. As velocities these threw two top-ply
                    // nodes of a stacked deep drawing, one on the die level
                    // with the bottom ply's edge, one come in through that
                    // edge to 0.02 mm over its mid-surface, at 34 and
                    // 12 m/s.
                    let rel = v[node as usize]
                        - hit
                            .nodes
                            .iter()
                            .zip(&hit.w)
                            .map(|(&j, w)| v[j as usize] * *w)
                            .sum::<Vector3<f64>>();
                    let approach = -rel.dot(&hit.normal) * dt;
                    if hit.end || gap + s.offset + approach < 0.5 * s.offset {
                        (-gap - approach.max(0.0)).max(0.0)
                    } else {
                        0.0
                    }
                };
                // The last step's force, as this step's multiplier: in a
                // forming run the plies press on each other much as they
                // did a step ago.
                let warm = s.warm[local];
                let mu = if warm.pass + 1 == self.pass && !hit.recover && gap < 0.0 {
                    warm.normal * dt * tau
                } else {
                    0.0
                };
                let rows = if gap < 0.0 {
                    &mut self.constraints
                } else {
                    &mut self.dormant
                };
                rows.push(Constraint {
                    slave: node,
                    masters: hit.nodes,
                    w: hit.w,
                    normal: hit.normal,
                    gap,
                    mu,
                    mass: 1.0 / m_inv,
                    inv: [
                        inv(node),
                        inv(hit.nodes[0]),
                        inv(hit.nodes[1]),
                        inv(hit.nodes[2]),
                    ],
                    slip_node,
                    search: k as u32,
                    shift,
                    compliance: if hit.end { 0.0 } else { give },
                });
            }
        }
        let mut step = PlyStep {
            active: self.constraints.len(),
            ..PlyStep::default()
        };
        if self.constraints.is_empty() {
            self.last = step;
            return step;
        }
        // Projected Gauss–Seidel on the linearised gaps, the increments
        // summed per node in `dx`.
        for c in &self.constraints {
            self.dx[c.slave as usize] = Vector3::zeros();
            for &j in &c.masters {
                self.dx[j as usize] = Vector3::zeros();
            }
        }
        for s in supports.iter_mut() {
            self.dx[s.node as usize] = Vector3::zeros();
            s.mu = 0.0;
        }
        for c in &self.constraints {
            if c.mu > 0.0 {
                self.dx[c.slave as usize] += c.normal * (c.mu * c.inv[0]);
                for k in 0..3 {
                    self.dx[c.masters[k] as usize] -= c.normal * (c.mu * c.w[k] * c.inv[k + 1]);
                }
            }
        }
        // A node that came round to the wrong side of a ply is moved back
        // out on its side before the solve, by the row's own projection
        // (its masses' shares), as a shift of position only: its depth is
        // up to the plies' thickness, which as a velocity (dx/dt) would
        // throw it at metres a second. So is the part of a row's
        // violation that the step's motion did not bring, where the node
        // was deep in the ply at the step's start or goes out through its
        // end. The row stays in the solve with the shift in its gap, so
        // the others cannot push it back in.
        //
        // A node resting on a tool is shifted along the tool, not into
        // it: what the tool's support took back of a shift would leave the
        // solve as a velocity (a bottom-ply node on the die, put back out
        // of a steep fold of the ply above, went up at 14.6 m/s). Shifted
        // rows are few (none in most steps), so each scans the supports.
        for c in &self.constraints {
            if c.shift <= 0.0 {
                continue;
            }
            let off_tools = |node: u32, mut d: Vector3<f64>| {
                for s in supports.iter().filter(|s| s.node == node) {
                    let into = d.dot(&s.normal);
                    if into < 0.0 {
                        d -= s.normal * into;
                    }
                }
                d
            };
            let slave = off_tools(c.slave, c.normal);
            let masters: [Vector3<f64>; 3] =
                std::array::from_fn(|k| off_tools(c.masters[k], -c.normal));
            // The gap one unit of the row's impulse opens along these.
            let opens = c.inv[0] * c.normal.dot(&slave)
                - (0..3)
                    .map(|k| c.w[k] * c.w[k] * c.inv[k + 1] * c.normal.dot(&masters[k]))
                    .sum::<f64>();
            // Every node held that way by a tool: the solve takes the
            // row as it is, as a velocity.
            if opens <= 0.0 {
                continue;
            }
            let impulse = c.shift / opens;
            let s = slave * (impulse * c.inv[0]);
            self.dx[c.slave as usize] += s;
            self.shift[c.slave as usize] += s;
            for (k, along) in masters.iter().enumerate() {
                let m = along * (impulse * c.w[k] * c.inv[k + 1]);
                self.dx[c.masters[k] as usize] += m;
                self.shift[c.masters[k] as usize] += m;
            }
        }
        // Converged when what is left of every violation is
        // [`NORMAL_TOLERANCE`] of the largest one at the start.
        let start = self.constraints.iter().map(|c| -c.gap).fold(0.0, f64::max);
        // A resting row clear by less than the step's deepest violation is
        // in the solve from its start: corrections of about that size may
        // close it, and woken once the others have converged
        // ([`wake`]) it made them converge again (the four-ply hemisphere
        // at 12 × 12 cells, first 0.3 s: 41.7 normal sweeps a step, 23.4
        // from the start, 20.5 before either).
        let (rows, dormant) = (&mut self.constraints, &mut self.dormant);
        dormant.retain(|c| {
            let near = c.gap < start;
            if near {
                rows.push(*c);
            }
            !near
        });
        let tolerance = self.tolerance * start;
        let plateau = STALL_GAP
            * self
                .searches
                .iter()
                .map(|s| s.offset)
                .fold(f64::INFINITY, f64::min);
        let mut window = f64::INFINITY;
        self.begin_sweeps(supports.iter().map(|s| s.node));
        let dx = &mut self.dx;
        let (drift, seen, last) = (&mut self.drift, &mut self.row_seen, &mut self.row_last);
        let skip = SKIP * tolerance;
        for sweep in 1..=self.max_sweeps {
            let mut worst: f64 = 0.0;
            for (k, c) in self.constraints.iter_mut().enumerate() {
                let [a, b, e] = c.masters.map(|j| drift[j as usize]);
                let moved = drift[c.slave as usize] + a + b + e;
                // The gap this row's next update would move, at most.
                if sweep > 1
                    && (moved - seen[k]) / (1.0 + c.compliance)
                        + (NORMAL_OMEGA - 1.0) / NORMAL_OMEGA * last[k] / c.mass
                        <= skip
                {
                    continue;
                }
                let g = c.gap + c.normal.dot(&c.relative(dx)) + c.compliance * c.mu / c.mass;
                let mu = (c.mu - NORMAL_OMEGA * g * c.mass / (1.0 + c.compliance)).max(0.0);
                let d = mu - c.mu;
                last[k] = d.abs();
                if d != 0.0 {
                    // The gap this update moves (|g| for a row that stays
                    // pressed): a row let go by a sweep that pressed it too
                    // hard (a warm start from a step that pressed harder)
                    // opens its gap by its whole multiplier, and a
                    // measure of the violation alone would call it done
                    // while the next rows are still to take it up.
                    worst = worst.max(d.abs() / (NORMAL_OMEGA * c.mass));
                    c.mu = mu;
                    dx[c.slave as usize] += c.normal * (d * c.inv[0]);
                    drift[c.slave as usize] += d.abs() * c.inv[0];
                    for k in 0..3 {
                        let j = c.masters[k] as usize;
                        dx[j] -= c.normal * (d * c.w[k] * c.inv[k + 1]);
                        drift[j] += d.abs() * c.w[k] * c.inv[k + 1];
                    }
                    let [a, b, e] = c.masters.map(|j| drift[j as usize]);
                    seen[k] = drift[c.slave as usize] + a + b + e;
                } else {
                    seen[k] = moved;
                }
            }
            for s in supports.iter_mut().filter(|s| s.driven.is_none()) {
                let m_inv = inv(s.node);
                if m_inv == 0.0 {
                    continue;
                }
                let g = s.gap + s.normal.dot(&dx[s.node as usize]);
                let mu = (s.mu - NORMAL_OMEGA * g / m_inv).max(0.0);
                let d = mu - s.mu;
                if d != 0.0 {
                    worst = worst.max(d.abs() * m_inv / NORMAL_OMEGA);
                    s.mu = mu;
                    dx[s.node as usize] += s.normal * (d * m_inv);
                    drift[s.node as usize] += d.abs() * m_inv;
                }
            }
            for s in supports.iter_mut() {
                let Some(t) = s.driven else { continue };
                let m_inv = inv(s.node);
                let shift = &mut tool_shift[t.tool as usize];
                let w = m_inv + t.along * t.along * t.inverse_mass;
                if w == 0.0 {
                    continue;
                }
                let g = s.gap + s.normal.dot(&dx[s.node as usize]) - t.along * *shift;
                let mu = (s.mu - NORMAL_OMEGA * g / w).max(-t.held);
                let d = mu - s.mu;
                if d != 0.0 {
                    worst = worst.max(d.abs() * w / NORMAL_OMEGA);
                    *shift -= t.along * d * t.inverse_mass;
                    s.mu = mu;
                    dx[s.node as usize] += s.normal * (d * m_inv);
                    drift[s.node as usize] += d.abs() * m_inv;
                }
            }
            step.sweeps = sweep;
            step.residual = worst;
            let (rows, dormant) = (&mut self.constraints, &mut self.dormant);
            if worst <= tolerance {
                if wake(dormant, rows, dx, tolerance, seen, last) {
                    continue;
                }
                break;
            }
            if sweep % STALL_SWEEPS == 0 {
                if worst > 0.9 * window && worst <= plateau && worst <= STALL_SHARE * start {
                    if wake(dormant, rows, dx, tolerance, seen, last) {
                        window = f64::INFINITY;
                        continue;
                    }
                    step.stalled = true;
                    break;
                }
                window = worst;
            }
        }
        step.active = self.constraints.len();
        let lambda_scale = 1.0 / (dt * tau);
        let shift = &mut self.shift;
        for c in &self.constraints {
            for i in std::iter::once(c.slave).chain(c.masters) {
                let i = i as usize;
                if dx[i] != Vector3::zeros() {
                    x[i] += dx[i];
                    v[i] += (dx[i] - shift[i]) / dt;
                    dx[i] = Vector3::zeros();
                }
                if shift[i] != Vector3::zeros() {
                    self.shifted.push((i as u32, shift[i]));
                    shift[i] = Vector3::zeros();
                }
            }
            if c.mu > 0.0 {
                let f = c.normal * (c.mu * lambda_scale);
                force[c.slave as usize] += f;
                for (&j, w) in c.masters.iter().zip(&c.w) {
                    force[j as usize] -= f * *w;
                }
                // On the upper ply's nodes: a row from below presses the
                // upper face's nodes by their weights.
                let p = c.mu * lambda_scale;
                let (pressure, touched, area) = (&mut self.pressure, &mut self.touched, &self.area);
                let mut press = |i: u32, p: f64| {
                    let i_ = i as usize;
                    if pressure[i_] == 0.0 {
                        touched.push(i);
                    }
                    pressure[i_] += p / area[i_].max(f64::MIN_POSITIVE);
                };
                if self.searches[c.search as usize].side > 0.0 {
                    press(c.slave, p);
                } else {
                    for (&j, w) in c.masters.iter().zip(&c.w) {
                        if *w > 0.0 {
                            press(j, p * w);
                        }
                    }
                }
            }
        }
        for s in supports.iter() {
            let i = s.node as usize;
            if dx[i] != Vector3::zeros() {
                x[i] += dx[i];
                v[i] += dx[i] / dt;
                dx[i] = Vector3::zeros();
            }
        }
        self.last = step;
        let totals = &mut self.totals;
        totals.steps += 1;
        totals.constraints += step.active as u64;
        totals.normal_sweeps += step.sweeps as u64;
        totals.max_normal_sweeps = totals.max_normal_sweeps.max(step.sweeps);
        totals.shifted_nodes += self.shifted.len() as u64;
        if step.stalled {
            totals.normal_stalled += 1;
        } else if step.residual > tolerance {
            totals.normal_capped += 1;
        }
        step
    }

    /// Coulomb friction on the constraints of the last normal pass and on
    /// the nodes' tool contacts `tools` (with the friction the tool pass
    /// applied already), solved together: projected Gauss–Seidel on each
    /// constraint's tangential force, the force that stops the relative
    /// sliding over the step projected on the disc of radius μλ, until no
    /// force changes by more than 1e-5 (`FRICTION_TOLERANCE`) of the largest
    /// cap. Together,
    /// because a ply that sticks to the one below drags it on the tool:
    /// friction solved one contact after the other would let a sticking
    /// stack creep. Adds the plies' forces to `force` (the tools' are
    /// returned in `tools`) and the slip they leave to [`Self::slip`].
    #[allow(clippy::too_many_arguments)]
    pub fn friction(
        &mut self,
        x: &mut [Vector3<f64>],
        v: &mut [Vector3<f64>],
        mass: &[f64],
        movable: &[bool],
        dt: f64,
        tau: f64,
        tools: &mut [ToolFriction],
        force: &mut [Vector3<f64>],
    ) {
        let inv = |i: u32| inverse_mass(mass, movable, i);
        let relative = |v: &[Vector3<f64>], c: &Constraint| {
            let rel = v[c.slave as usize]
                - c.masters
                    .iter()
                    .zip(&c.w)
                    .map(|(&j, w)| v[j as usize] * *w)
                    .sum::<Vector3<f64>>();
            rel - c.normal * c.normal.dot(&rel)
        };
        let lambda_scale = 1.0 / (dt * tau);
        self.f_t.clear();
        self.f_t.resize(self.constraints.len(), Vector3::zeros());
        // From the last step's tangential forces, in the new tangent
        // planes and within the new caps.
        for (k, c) in self.constraints.iter().enumerate() {
            let s = &self.searches[c.search as usize];
            let cap = s.friction * c.mu * lambda_scale;
            let local = (c.slave - self.layers[s.slave].first_node) as usize;
            let warm = s.warm[local];
            if cap == 0.0 || warm.pass + 1 != self.pass {
                continue;
            }
            let f = warm.tangential - c.normal * c.normal.dot(&warm.tangential);
            let n = f.norm();
            if n == 0.0 {
                continue;
            }
            let f = if n > cap { f * (cap / n) } else { f };
            self.f_t[k] = f;
            let dv = f * (tau * c.inv[0]);
            v[c.slave as usize] += dv;
            x[c.slave as usize] += dv * dt;
            for k in 0..3 {
                let dv = f * (-c.w[k] * tau * c.inv[k + 1]);
                v[c.masters[k] as usize] += dv;
                x[c.masters[k] as usize] += dv * dt;
            }
        }
        let mut largest: f64 = tools.iter().map(|t| t.cap).fold(0.0, f64::max);
        for c in &self.constraints {
            largest = largest.max(self.searches[c.search as usize].friction * c.mu * lambda_scale);
        }
        if largest == 0.0 {
            self.remember(lambda_scale);
            return;
        }
        let project = |trial: Vector3<f64>, cap: f64| {
            let n = trial.norm();
            if n > cap { trial * (cap / n) } else { trial }
        };
        let mut sweeps = 0;
        let (mut converged, mut stalled, mut window) = (false, false, f64::INFINITY);
        // Over-relaxed until converged, then plain sweeps until one changes
        // nothing beyond the tolerance: a plain update leaves its
        // constraint's relative tangential velocity exactly zero where it
        // sticks (given the others), which an over-relaxed one overshoots.
        let mut omega = FRICTION_OMEGA;
        // The sweeps read and write the velocities only; the positions
        // follow once, from what the sweeps changed (half the stores of
        // an update).
        self.v_before.clear();
        self.v_before.extend_from_slice(v);
        self.begin_sweeps(tools.iter().map(|t| t.node));
        let (drift, seen, last) = (&mut self.drift, &mut self.row_seen, &mut self.row_last);
        let skip = SKIP * FRICTION_TOLERANCE * largest;
        // Every row is updated at the first sweep and at the first after ω
        // changes (the bound below holds for two updates at one ω).
        let mut every = true;
        for _ in 0..FRICTION_SWEEPS {
            sweeps += 1;
            let mut change: f64 = 0.0;
            for (k, c) in self.constraints.iter().enumerate() {
                let mu_f = self.searches[c.search as usize].friction;
                if mu_f == 0.0 || c.mu <= 0.0 {
                    continue;
                }
                let [a, b, e] = c.masters.map(|j| drift[j as usize]);
                let moved = drift[c.slave as usize] + a + b + e;
                if !every
                    && omega * (moved - seen[k]) * c.mass / tau + (omega - 1.0) * last[k] <= skip
                {
                    continue;
                }
                let v_t = relative(v, c);
                let new = project(
                    self.f_t[k] - v_t * (omega * c.mass / tau),
                    mu_f * c.mu * lambda_scale,
                );
                let d = new - self.f_t[k];
                let size = d.norm();
                last[k] = size;
                if size == 0.0 {
                    seen[k] = moved;
                    continue;
                }
                change = change.max(size);
                self.f_t[k] = new;
                v[c.slave as usize] += d * (tau * c.inv[0]);
                drift[c.slave as usize] += size * tau * c.inv[0];
                let mut moved = drift[c.slave as usize];
                for k in 0..3 {
                    let j = c.masters[k] as usize;
                    v[j] += d * (-c.w[k] * tau * c.inv[k + 1]);
                    drift[j] += size * c.w[k] * tau * c.inv[k + 1];
                    moved += drift[j];
                }
                seen[k] = moved;
            }
            for t in tools.iter_mut() {
                let m_inv = inv(t.node);
                if m_inv == 0.0 {
                    continue;
                }
                let i = t.node as usize;
                let rel = v[i] - t.tool_velocity;
                let v_t = rel - t.normal * t.normal.dot(&rel);
                let new = project(t.force - v_t * (omega / (m_inv * tau)), t.cap);
                let d = new - t.force;
                if d == Vector3::zeros() {
                    continue;
                }
                change = change.max(d.norm());
                t.force = new;
                v[i] += d * (tau * m_inv);
                drift[i] += d.norm() * tau * m_inv;
            }
            every = false;
            if change <= FRICTION_TOLERANCE * largest {
                if omega == 1.0 {
                    converged = true;
                    break;
                }
                omega = 1.0;
                every = true;
            }
            if sweeps % STALL_SWEEPS == 0 {
                if change > 0.9 * window && change <= FRICTION_STALL * largest {
                    stalled = true;
                    break;
                }
                window = change;
            }
        }
        for ((x, v), v0) in x.iter_mut().zip(v.iter()).zip(&self.v_before) {
            if v != v0 {
                *x += (v - v0) * dt;
            }
        }
        let totals = &mut self.totals;
        totals.friction_sweeps += sweeps as u64;
        totals.max_friction_sweeps = totals.max_friction_sweeps.max(sweeps);
        if stalled {
            totals.friction_stalled += 1;
        } else if !converged {
            totals.friction_capped += 1;
        }
        for (c, f_t) in self.constraints.iter().zip(&self.f_t) {
            if *f_t == Vector3::zeros() {
                continue;
            }
            force[c.slave as usize] += f_t;
            for (&j, w) in c.masters.iter().zip(&c.w) {
                force[j as usize] -= f_t * *w;
            }
            self.friction_dissipation -= f_t.dot(&relative(v, c)) * dt;
        }
        // The slip of each node on the ply below: the upper ply's node of
        // each row (its slave, or its pair's), at the velocities all
        // forces left.
        for c in &self.constraints {
            if c.slip_node != u32::MAX && c.mu > 0.0 {
                self.slip[c.slip_node as usize] += relative(v, c).norm() * dt;
            }
        }
        self.remember(lambda_scale);
    }

    /// Keeps each constraint's multiplier (as a force) and tangential
    /// force for the next step's solves to start from.
    fn remember(&mut self, lambda_scale: f64) {
        for (k, c) in self.constraints.iter().enumerate() {
            let s = &mut self.searches[c.search as usize];
            let local = (c.slave - self.layers[s.slave].first_node) as usize;
            s.warm[local] = Warm {
                normal: c.mu * lambda_scale,
                tangential: self.f_t.get(k).copied().unwrap_or_else(Vector3::zeros),
                pass: self.pass,
            };
        }
    }
}

/// Moves into `rows` each `dormant` row that the solve's corrections so
/// far (`dx`) have closed by more than `tolerance`, in their order, with
/// records (`seen`, `last`) that make the next sweep update it; whether
/// any moved. The rows clear by less than the step's deepest violation
/// are in the solve from its start; this catches the rest (a few in the
/// first 0.5 s of the shipped four-ply hemisphere).
fn wake(
    dormant: &mut Vec<Constraint>,
    rows: &mut Vec<Constraint>,
    dx: &[Vector3<f64>],
    tolerance: f64,
    seen: &mut Vec<f64>,
    last: &mut Vec<f64>,
) -> bool {
    let before = rows.len();
    dormant.retain(|c| {
        let closed = c.gap + c.normal.dot(&c.relative(dx)) < -tolerance;
        if closed {
            rows.push(*c);
        }
        !closed
    });
    for _ in before..rows.len() {
        // Never passed over before its first update ([`SKIP`]).
        seen.push(f64::NEG_INFINITY);
        last.push(0.0);
    }
    rows.len() > before
}

/// A hit's face vertex that carries at least [`PAIR_WEIGHT`] of the
/// closest point.
fn nearest(hit: &Hit) -> Option<u32> {
    if hit.end {
        // A row through the ply's end is not the face's row of a node
        // on a node: its normal lies in the ply.
        return None;
    }
    (0..3)
        .find(|&k| hit.w[k] >= PAIR_WEIGHT)
        .map(|k| hit.nodes[k])
}

/// The other search's hit of the node nearest `hit` (of `node`), if that
/// node's nearest is `node` in turn: a pair of nodes, one per ply, each
/// all but on the other.
fn mutual<'a>(hit: &Hit, node: u32, other: &'a Search, other_slave: &PlyLayer) -> Option<&'a Hit> {
    let m = nearest(hit)?;
    let o = other
        .hits
        .get(m.checked_sub(other_slave.first_node)? as usize)?;
    (o.found && nearest(o) == Some(node)).then_some(o)
}

/// Which features of each face are on the outline of the layer: an edge
/// that no other face shares, and its two vertices.
fn outline_of(faces: &[[u32; 3]]) -> Vec<u8> {
    let mut count = std::collections::HashMap::new();
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    for f in faces {
        for k in 0..3 {
            *count.entry(key(f[k], f[(k + 1) % 3])).or_insert(0u32) += 1;
        }
    }
    let mut vertex = std::collections::HashSet::new();
    for (&(a, b), &n) in &count {
        if n == 1 {
            vertex.insert(a);
            vertex.insert(b);
        }
    }
    faces
        .iter()
        .map(|f| {
            let mut bits = 0u8;
            for k in 0..3 {
                if count[&key(f[k], f[(k + 1) % 3])] == 1 {
                    bits |= 1 << k;
                }
                if vertex.contains(&f[k]) {
                    bits |= 1 << (3 + k);
                }
            }
            bits
        })
        .collect()
}

/// Whether the closest point of barycentric weights `w` lies on a face's
/// outline feature (`bits` as [`outline_of`] gives them).
fn on_outline(bits: u8, w: &[f64; 3]) -> bool {
    if bits == 0 {
        return false;
    }
    let zero = w.map(|w| w == 0.0);
    match zero {
        // A vertex: the one whose weight is 1.
        [true, true, false] => bits & (1 << 5) != 0,
        [true, false, true] => bits & (1 << 4) != 0,
        [false, true, true] => bits & (1 << 3) != 0,
        // An edge: the one opposite the zero weight (ab is bit 0).
        [false, false, true] => bits & 1 != 0,
        [true, false, false] => bits & 2 != 0,
        [false, true, false] => bits & 4 != 0,
        _ => false,
    }
}

/// The candidate faces of every slave node of `s`: a uniform grid of the
/// master's face boxes grown by `reach`, each node looking in its cell.
fn build_candidates(s: &mut Search, layers: &[PlyLayer], x: &[Vector3<f64>], reach: f64) {
    let faces = &layers[s.master].faces;
    let slave = &layers[s.slave];
    let mut low = [f64::INFINITY; 3];
    let mut high = [f64::NEG_INFINITY; 3];
    let mut size: f64 = 0.0;
    for (b, f) in s.boxes.iter_mut().zip(faces) {
        let p = f.map(|n| x[n as usize]);
        for k in 0..3 {
            let lo = p[0][k].min(p[1][k]).min(p[2][k]) - reach;
            let hi = p[0][k].max(p[1][k]).max(p[2][k]) + reach;
            b[k] = lo;
            b[k + 3] = hi;
            low[k] = low[k].min(lo);
            high[k] = high[k].max(hi);
            size = size.max(hi - lo);
        }
    }
    s.cand.clear();
    s.cand_ptr.iter_mut().for_each(|p| *p = 0);
    if faces.is_empty() {
        return;
    }
    // Cells at least as large as a grown face, so a face lies in at most
    // two cells along each axis; fewer cells than 8 per face.
    let extent = [high[0] - low[0], high[1] - low[1], high[2] - low[2]];
    let mut cell = size.max(f64::MIN_POSITIVE);
    let dims = |cell: f64| extent.map(|e| ((e / cell).floor() as usize + 1).max(1));
    while dims(cell).iter().product::<usize>() > 8 * faces.len() + 8 {
        cell *= 1.5;
    }
    let d = dims(cell);
    let index = |p: [f64; 3]| -> [usize; 3] {
        [0, 1, 2].map(|k| (((p[k] - low[k]) / cell).floor().max(0.0) as usize).min(d[k] - 1))
    };
    let cells = d[0] * d[1] * d[2];
    s.cell_ptr.clear();
    s.cell_ptr.resize(cells + 1, 0);
    let each_cell = |b: &[f64; 6], f: &mut dyn FnMut(usize)| {
        let lo = index([b[0], b[1], b[2]]);
        let hi = index([b[3], b[4], b[5]]);
        for i in lo[0]..=hi[0] {
            for j in lo[1]..=hi[1] {
                for k in lo[2]..=hi[2] {
                    f((k * d[1] + j) * d[0] + i);
                }
            }
        }
    };
    for b in &s.boxes {
        each_cell(b, &mut |c| s.cell_ptr[c + 1] += 1);
    }
    for c in 0..cells {
        s.cell_ptr[c + 1] += s.cell_ptr[c];
    }
    s.fill.clear();
    s.fill.extend_from_slice(&s.cell_ptr[..cells]);
    s.cell_faces.clear();
    s.cell_faces.resize(s.cell_ptr[cells] as usize, 0);
    for (f, b) in s.boxes.iter().enumerate() {
        let (fill, out) = (&mut s.fill, &mut s.cell_faces);
        each_cell(b, &mut |c| {
            out[fill[c] as usize] = f as u32;
            fill[c] += 1;
        });
    }
    for local in 0..slave.node_count as usize {
        let p = x[slave.first_node as usize + local];
        let inside = (0..3).all(|k| p[k] >= low[k] && p[k] <= high[k]);
        if inside {
            let [i, j, k] = index([p.x, p.y, p.z]);
            let c = (k * d[1] + j) * d[0] + i;
            for &f in &s.cell_faces[s.cell_ptr[c] as usize..s.cell_ptr[c + 1] as usize] {
                let b = &s.boxes[f as usize];
                if (0..3).all(|k| p[k] >= b[k] && p[k] <= b[k + 3]) {
                    s.cand.push(f);
                }
            }
        }
        s.cand_ptr[local + 1] = s.cand.len() as u32;
    }
}

/// A node's inverse mass, 0 where its motion is prescribed (it takes no
/// share of a correction).
fn inverse_mass(mass: &[f64], movable: &[bool], i: u32) -> f64 {
    if movable[i as usize] {
        1.0 / mass[i as usize]
    } else {
        0.0
    }
}

#[cfg(test)]
mod end_tests;
#[cfg(test)]
mod side_tests;

#[cfg(test)]
mod thread_tests;

/// Fixtures of the ply-contact tests.
#[cfg(test)]
pub(crate) mod fixtures {
    use super::{PlyContact, PlyInterface, PlyLayer, Support};
    use nalgebra::Vector3;

    /// The lower ply a 10 mm square in z = 0 (normal +z, its free end
    /// x = 10), the upper one the quad `upper` (nodes 4..8): the two plies
    /// 0.15 mm half thick (offset 0.3 mm), frictionless.
    pub fn on_square(upper: [Vector3<f64>; 4]) -> (Vec<Vector3<f64>>, PlyContact) {
        let mut x: Vec<Vector3<f64>> = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]
            .map(|[a, b]| Vector3::new(a, b, 0.0))
            .to_vec();
        x.extend(upper);
        let layer = |first| square_layer(first, 0.15);
        let interface = PlyInterface {
            lower: 0,
            upper: 1,
            friction: 0.0,
        };
        let c = PlyContact::new(vec![layer(0), layer(4)], &[interface], vec![1.0; 8], 1.0);
        (x, c)
    }

    /// [`on_square`] with a 4 mm wide quad from x = 6 (z = 0.3, resting
    /// on the square), its nodes 5 and 6 at `far` (x, z).
    pub fn quad_over_square(far: [f64; 2]) -> (Vec<Vector3<f64>>, PlyContact) {
        on_square([
            Vector3::new(6.0, 3.0, 0.3),
            Vector3::new(far[0], 3.0, far[1]),
            Vector3::new(far[0], 7.0, far[1]),
            Vector3::new(6.0, 7.0, 0.3),
        ])
    }

    /// A ply of the two triangles of the quad `first`..`first + 3`.
    pub fn square_layer(first: u32, half_thickness: f64) -> PlyLayer {
        PlyLayer {
            first_node: first,
            node_count: 4,
            faces: vec![[first, first + 1, first + 2], [first, first + 2, first + 3]],
            half_thickness,
        }
    }

    /// One normal pass of `contact` with Δt = τ = 1 ms and no
    /// force-driven tool behind the `supports`: what the tests run.
    pub fn normal_pass(
        contact: &mut PlyContact,
        x: &mut [Vector3<f64>],
        v: &mut [Vector3<f64>],
        mass: &[f64],
        movable: &[bool],
        supports: &mut [Support],
        force: &mut [Vector3<f64>],
    ) -> super::PlyStep {
        contact.normal(x, v, mass, movable, 1e-3, 1e-3, supports, &mut [], force)
    }

    /// Nodes 0..4 held on a tool below them (normal +z).
    pub fn bottom_supports() -> Vec<Support> {
        (0..4)
            .map(|n| Support {
                node: n,
                normal: Vector3::z(),
                gap: 0.0,
                mu: 0.0,
                driven: None,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests;
