//! What both drivers use alike: the constrained components and their
//! prescribed motions, the internal force pass (element batches into slots,
//! gathered per node), gravity and nodal loads, the follower pressures
//! (element slots gathered per node, like the internal forces), the stored
//! strain energy, and the checks a model must pass before it runs.
//!
//! Not here: anything about how a driver advances time (central
//! differences, Newton increments) or treats contact.

use drape_elements::ElementError;
use drape_model::{Model, Motion, SlotLayout, State};
use nalgebra::Vector3;

use crate::RunError;
use crate::profile::{Pass, Profiler};

/// A constrained component: node, component, which boundary condition.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Constraint {
    pub node: u32,
    pub component: u8,
    pub bc: u32,
}

/// Per node, which of its components the model's boundary conditions
/// prescribe (for a driver stepped elsewhere, e.g. drape-gpu).
pub fn constrained_components(model: &Model) -> Vec<[bool; 3]> {
    Constraints::new(model).constrained
}

/// The constrained components that a boundary motion other than `Fixed`
/// moves (a displacement, a velocity, a picture frame's arms), in node and
/// component order, with their coordinates step by step as the explicit
/// driver prescribes them: for a driver stepped elsewhere (drape-gpu),
/// which is handed each step's coordinates.
#[derive(Debug, Clone)]
pub struct PrescribedMotions {
    list: Vec<Constraint>,
}

impl PrescribedMotions {
    /// The moving components of `model`'s boundary conditions (where
    /// conditions overlap, the later one wins, as in the drivers).
    pub fn new(model: &Model) -> Self {
        let list = Constraints::new(model)
            .list
            .into_iter()
            .filter(|c| !matches!(model.boundary[c.bc as usize].motion, Motion::Fixed))
            .collect();
        Self { list }
    }

    /// How many components move.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// Whether none does.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// Each moving component's node and component (0 x, 1 y, 2 z).
    pub fn components(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.list
            .iter()
            .map(|c| (c.node as usize, c.component as usize))
    }

    /// Each component's coordinate at `t + h` into `at`, which holds its
    /// coordinate at `t` (a velocity condition moves from it), as the
    /// explicit driver's step prescribes it.
    pub fn advance(&self, model: &Model, at: &mut [f64], t: f64, h: f64) {
        for (c, x) in self.list.iter().zip(at) {
            *x = Constraints::position(model, c, *x, t, h);
        }
    }
}

/// The constrained components of a model: where conditions overlap, the
/// later one wins for the components it names.
#[derive(Debug, Clone)]
pub(crate) struct Constraints {
    /// Each constrained component once, in node order.
    pub list: Vec<Constraint>,
    /// Per node, which components are constrained.
    pub constrained: Vec<[bool; 3]>,
    /// Per node, whether any component is free (contact may move it).
    pub movable: Vec<bool>,
}

impl Constraints {
    pub fn new(model: &Model) -> Self {
        let n = model.node_count();
        let mut constrained = vec![[false; 3]; n];
        let mut owner = vec![[u32::MAX; 3]; n];
        for (b, bc) in model.boundary.iter().enumerate() {
            for &node in &bc.nodes {
                for c in 0..3 {
                    if bc.components[c] {
                        constrained[node as usize][c] = true;
                        owner[node as usize][c] = b as u32;
                    }
                }
            }
        }
        let mut list = Vec::new();
        for (node, o) in owner.iter().enumerate() {
            for (c, &bc) in o.iter().enumerate() {
                if bc != u32::MAX {
                    list.push(Constraint {
                        node: node as u32,
                        component: c as u8,
                        bc,
                    });
                }
            }
        }
        let movable = constrained.iter().map(|c| !c.iter().all(|&b| b)).collect();
        Self {
            list,
            constrained,
            movable,
        }
    }

    /// Per node, whether no component is constrained.
    pub fn free(&self) -> Vec<bool> {
        self.constrained
            .iter()
            .map(|c| !c.iter().any(|&b| b))
            .collect()
    }

    /// The prescribed displacement of `c` at `t`, None for a velocity
    /// condition.
    pub fn displacement(model: &Model, c: &Constraint, t: f64) -> Option<f64> {
        let bc = &model.boundary[c.bc as usize];
        bc.displacement(&model.x0[c.node as usize], t)
            .map(|u| u[c.component as usize])
    }

    /// The prescribed velocity of `c` at `t` (a velocity condition only).
    pub fn velocity(model: &Model, c: &Constraint, t: f64) -> f64 {
        match &model.boundary[c.bc as usize].motion {
            Motion::Velocity { value, amplitude } => {
                value[c.component as usize] * amplitude.value(t)
            }
            _ => unreachable!("velocity asked of a displacement condition"),
        }
    }

    /// The prescribed coordinate of `c` at `t + h`, from its coordinate
    /// `now` at `t` (a velocity condition moves it by the mid-step
    /// velocity).
    pub fn position(model: &Model, c: &Constraint, now: f64, t: f64, h: f64) -> f64 {
        match Self::displacement(model, c, t + h) {
            Some(u) => model.x0[c.node as usize][c.component as usize] + u,
            None => now + Self::velocity(model, c, t + 0.5 * h) * h,
        }
    }
}

/// The velocities and, per truss batch, the coefficients of the dashpots
/// along kinked yarns (see [`ForcePass::evaluate`]).
pub(crate) type Dashpots<'a> = (&'a [Vector3<f64>], &'a [Vec<f64>]);

/// The internal force pass: every batch writes its elements' nodal forces
/// into its own slots (in parallel), the layout gathers them per node in a
/// fixed order.
#[derive(Debug, Clone)]
pub(crate) struct ForcePass {
    pub layout: SlotLayout,
    slots: Vec<Vector3<f64>>,
    /// The internal forces of the last evaluation, per node.
    pub f_int: Vec<Vector3<f64>>,
    /// The membranes' histories of the last evaluation.
    pub history_new: Vec<Vec<f64>>,
    /// Estimated instructions of the truss and of the membrane pass.
    work: (usize, usize),
    /// Per truss batch, each truss's clearance for a confined yarn (mm,
    /// see crate::confinement); empty for a batch that is not confined.
    pub truss_clearance: Vec<Vec<f64>>,
}

/// Instructions below which a kind's pass is not worth a task of its own
/// (about what waking a second thread costs, with a margin): the pieces of
/// the element passes are sized alike (`drape-elements`).
const SIDE_BY_SIDE_WORK: usize = 100_000;

/// Estimated instructions of the truss and of the membrane pass of `model`
/// (callgrind, 200 × 200 blank: ≈ 125 per truss on the lanes, ≈ 950 per
/// quad on the lanes; a quad with embedded fibres or a Prony table the
/// lanes do not take about twice that; a triangle about a quarter of it).
/// Since the lanes load their history value-major a lane quad costs
/// ≈ 600; the weight is kept, as it only decides whether a pass is worth a
/// task of its own and which kind the calling thread takes, and
/// on a quad grid (about two trusses a quad) the membranes stay the
/// larger kind either way.
fn pass_work(model: &Model) -> (usize, usize) {
    let trusses = model.trusses.iter().map(|b| 125 * b.len()).sum();
    let membranes = model
        .membranes
        .iter()
        .map(|b| match b.shape() {
            drape_elements::MembraneShape::Quad => 1000 * b.len(),
            drape_elements::MembraneShape::Triangle => 250 * b.len(),
        })
        .sum();
    (trusses, membranes)
}

impl ForcePass {
    pub fn new(model: &Model) -> Self {
        let layout = model.slot_layout();
        Self {
            slots: vec![Vector3::zeros(); layout.len],
            layout,
            f_int: vec![Vector3::zeros(); model.node_count()],
            history_new: model
                .membranes
                .iter()
                .map(|b| b.initial_history())
                .collect(),
            work: pass_work(model),
            truss_clearance: Vec::new(),
        }
    }

    /// The internal forces at `x` into `self.f_int`, the new histories (from
    /// the committed `history`, over a step `dt`) into `self.history_new`.
    /// `dashpots`: the velocities and, per truss batch, the coefficients of
    /// the dashpots along kinked yarns (an empty list for a batch without;
    /// the explicit driver's `fibre_damping`). `step` and `time` only name
    /// the failure; `profiler` (the explicit step's, when asked) times the
    /// element kinds. For trial states evaluated from one committed
    /// history (Newton iterations, a run's start); the explicit step uses
    /// [`Self::evaluate_in_place`].
    #[allow(clippy::too_many_arguments)]
    pub fn evaluate(
        &mut self,
        model: &Model,
        x: &[Vector3<f64>],
        dashpots: Option<Dashpots<'_>>,
        history: &[Vec<f64>],
        dt: f64,
        step: u64,
        time: f64,
        profiler: Option<&mut Profiler>,
    ) -> Result<(), RunError> {
        self.evaluate_with(
            model,
            x,
            dashpots,
            Histories::Into(history),
            dt,
            step,
            time,
            profiler,
        )
    }

    /// [`Self::evaluate`] with the membranes' `history` advanced to the new
    /// one where it lies (`self.history_new` untouched): one history array
    /// streamed instead of two, the same bits. On an error `history` is
    /// partly advanced, so the caller must be able to go back to a copy
    /// (the explicit driver returns to the guard's last good state); after
    /// a success it is the new history whatever the caller does next.
    #[allow(clippy::too_many_arguments)]
    pub fn evaluate_in_place(
        &mut self,
        model: &Model,
        x: &[Vector3<f64>],
        dashpots: Option<Dashpots<'_>>,
        history: &mut [Vec<f64>],
        dt: f64,
        step: u64,
        time: f64,
        profiler: Option<&mut Profiler>,
    ) -> Result<(), RunError> {
        self.evaluate_with(
            model,
            x,
            dashpots,
            Histories::InPlace(history),
            dt,
            step,
            time,
            profiler,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn evaluate_with(
        &mut self,
        model: &Model,
        x: &[Vector3<f64>],
        dashpots: Option<Dashpots<'_>>,
        history: Histories<'_>,
        dt: f64,
        step: u64,
        time: f64,
        mut profiler: Option<&mut Profiler>,
    ) -> Result<(), RunError> {
        let profiled = profiler.is_some();
        let fail = |batch: String, error: ElementError| RunError::Element {
            step,
            time,
            batch,
            error,
        };
        let mut lap = |pass: Pass| {
            if let Some(p) = profiler.as_deref_mut() {
                p.lap(pass);
            }
        };
        let truss_slots = self.layout.membrane_offsets.first().copied();
        let (truss_work, membrane_work) = self.work;
        match truss_slots {
            // Unprofiled, trusses and membranes in one parallel region when
            // both are worth a task of their own: on a small model each
            // kind alone is one or two tasks, and two passes one after the
            // other leave the second thread idle (or asleep) for most of
            // the step. The larger kind runs on this thread, the smaller
            // is offered to the other: if waking it takes longer than the
            // larger kind, this thread runs both, as in sequence. Each
            // slot and history entry is written by the same operations
            // either way, so the bits do not depend on this choice; a truss
            // failure is reported before a membrane one, as in sequence.
            Some(split) if !profiled && truss_work.min(membrane_work) >= SIDE_BY_SIDE_WORK => {
                let (truss_part, rest) = self.slots.split_at_mut(split);
                let history_new = &mut self.history_new;
                let layout = &self.layout;
                let clearance = &self.truss_clearance;
                let trusses = || {
                    truss_forces(
                        model,
                        x,
                        dashpots,
                        clearance,
                        truss_part,
                        &fail,
                        &mut |_| {},
                    )
                };
                let membranes = || {
                    membrane_forces(
                        model,
                        x,
                        history,
                        history_new,
                        dt,
                        rest,
                        layout,
                        split,
                        &fail,
                        &mut |_| {},
                    )
                };
                let (trusses, membranes) = if membrane_work >= truss_work {
                    let (m, t) = rayon::join(membranes, trusses);
                    (t, m)
                } else {
                    rayon::join(trusses, membranes)
                };
                trusses?;
                membranes?;
            }
            _ => {
                let split = truss_slots.unwrap_or(self.layout.len);
                let (truss_part, rest) = self.slots.split_at_mut(split);
                truss_forces(
                    model,
                    x,
                    dashpots,
                    &self.truss_clearance,
                    truss_part,
                    &fail,
                    &mut lap,
                )?;
                membrane_forces(
                    model,
                    x,
                    history,
                    &mut self.history_new,
                    dt,
                    rest,
                    &self.layout,
                    split,
                    &fail,
                    &mut lap,
                )?;
            }
        }
        for (i, b) in model.springs.iter().enumerate() {
            let start = self.layout.spring_offsets[i];
            b.forces_into(x, &mut self.slots[start..start + b.len()]);
        }
        lap(Pass::Springs);
        for (i, b) in model.bending.iter().enumerate() {
            let start = self.layout.bending_offsets[i];
            b.forces_into(x, &mut self.slots[start..start + 3 * b.len()])
                .map_err(|e| fail(format!("bending batch {i}"), e))?;
        }
        lap(Pass::Bending);
        self.layout.gather(&self.slots, &mut self.f_int);
        lap(Pass::Gather);
        Ok(())
    }
}

/// The truss batches' forces (and dashpots) into `slots`, the slots of
/// every truss batch (the layout puts them first).
fn truss_forces(
    model: &Model,
    x: &[Vector3<f64>],
    dashpots: Option<Dashpots<'_>>,
    clearance: &[Vec<f64>],
    slots: &mut [Vector3<f64>],
    fail: &(dyn Fn(String, ElementError) -> RunError + Sync),
    lap: &mut dyn FnMut(Pass),
) -> Result<(), RunError> {
    let mut start = 0;
    for (i, b) in model.trusses.iter().enumerate() {
        let end = start + 2 * b.len();
        let dashpots = dashpots
            .filter(|(_, c)| !c[i].is_empty())
            .map(|(v, c)| (v, c[i].as_slice()));
        let clearance = clearance
            .get(i)
            .filter(|c| !c.is_empty())
            .map(Vec::as_slice);
        b.forces_confined_into(x, dashpots, clearance, &mut slots[start..end])
            .map_err(|e| fail(format!("truss batch {i}"), e))?;
        lap(Pass::Trusses);
        start = end;
    }
    Ok(())
}

/// Where the force pass takes the membranes' committed histories from
/// and where the new ones go.
enum Histories<'a> {
    /// From these, the new ones into [`ForcePass::history_new`].
    Into(&'a [Vec<f64>]),
    /// Advanced where they lie.
    InPlace(&'a mut [Vec<f64>]),
}

/// The membrane batches' forces into `slots` (which begin at slot `base`
/// of `layout`) and their new histories (into `history_new`, or in place).
#[allow(clippy::too_many_arguments)]
fn membrane_forces(
    model: &Model,
    x: &[Vector3<f64>],
    mut history: Histories<'_>,
    history_new: &mut [Vec<f64>],
    dt: f64,
    slots: &mut [Vector3<f64>],
    layout: &SlotLayout,
    base: usize,
    fail: &(dyn Fn(String, ElementError) -> RunError + Sync),
    lap: &mut dyn FnMut(Pass),
) -> Result<(), RunError> {
    for (i, b) in model.membranes.iter().enumerate() {
        let start = layout.membrane_offsets[i] - base;
        let n = b.shape().nodes() * b.len();
        let slots = &mut slots[start..start + n];
        match &mut history {
            Histories::Into(h) => b.forces_into(x, &h[i], &mut history_new[i], dt, slots),
            Histories::InPlace(h) => b.forces_in_place(x, &mut h[i], dt, slots),
        }
        .map_err(|e| fail(format!("membrane batch {i} ({:?})", b.shape()), e))?;
        lap(Pass::Membranes);
    }
    Ok(())
}

/// Nodes per task of the per-node checks (≈ 15–35 instructions a node).
const CHECK_PIECE: usize = 8192;

/// The lowest node `i < n` for which `bad(i)` holds: pieces of
/// [`CHECK_PIECE`] nodes searched in parallel, each by a plain loop (rayon's
/// `position_first` checks a shared bound at every node and ran three times
/// the instructions of the loop), the lowest find kept whatever the split.
pub(crate) fn first_node(n: usize, bad: impl Fn(usize) -> bool + Sync) -> Option<usize> {
    use rayon::prelude::*;
    (0..n.div_ceil(CHECK_PIECE))
        .into_par_iter()
        .map(|c| (c * CHECK_PIECE..((c + 1) * CHECK_PIECE).min(n)).find(|&i| bad(i)))
        .reduce(|| None, |a, b| a.or(b))
}

/// Gravity and the nodal loads at time `t` into `f_ext` (the follower
/// pressures apart): the weight, then each load in its order.
pub fn external_forces(model: &Model, t: f64, f_ext: &mut [Vector3<f64>]) {
    // Weight from the physical mass: mass scaling adds inertia only.
    for (f, m) in f_ext.iter_mut().zip(&model.mass) {
        *f = model.gravity * *m;
    }
    for load in &model.loads {
        let f = load.force_at(t);
        for &n in &load.nodes {
            f_ext[n as usize] += f;
        }
    }
}

/// The follower pressures' nodal forces ([`drape_model::pressure`]): each
/// loaded element writes its p·a(t)·A/k into its own slot (in parallel),
/// and each node sums its elements' slots in ascending order, so the forces
/// do not depend on the thread count. Built once; an evaluation allocates
/// nothing. A model without pressure has an empty pass that adds nothing.
/// Public for a driver stepped elsewhere (drape-gpu), which reads its
/// slots and sums them in the same order.
#[derive(Debug, Clone, Default)]
pub struct PressurePass {
    /// Per slot: (load, element of the load).
    elements: Vec<(u32, u32)>,
    /// Each slot's force on each node of its element.
    slots: Vec<Vector3<f64>>,
    /// p·a(t) of each load at the evaluation's time.
    scale: Vec<f64>,
    node_ptr: Vec<usize>,
    node_slots: Vec<u32>,
}

/// Slots (and nodes) per task of the pressure pass: a slot costs a cross
/// product, so pieces this long are worth a task.
const PRESSURE_PIECE: usize = 2048;

impl PressurePass {
    /// The pass of `model`'s pressures.
    pub fn new(model: &Model) -> Self {
        let mut elements = Vec::new();
        let mut owners: Vec<(u32, u32)> = Vec::new();
        for (l, p) in model.pressure.iter().enumerate() {
            for e in 0..p.len() {
                let slot = elements.len() as u32;
                elements.push((l as u32, e as u32));
                owners.extend(p.element(e).iter().map(|&n| (n, slot)));
            }
        }
        if elements.is_empty() {
            return Self::default();
        }
        // Slots are pushed in ascending order, so each node's are too.
        let (node_ptr, node_slots) =
            drape_model::node_slots(model.node_count(), owners.iter().copied());
        Self {
            slots: vec![Vector3::zeros(); elements.len()],
            elements,
            scale: vec![0.0; model.pressure.len()],
            node_ptr,
            node_slots,
        }
    }

    /// Whether the model has no pressure (the pass adds nothing).
    pub fn is_empty(&self) -> bool {
        self.elements.is_empty()
    }

    /// Per slot, its load and the element of the load.
    pub fn slots(&self) -> &[(u32, u32)] {
        &self.elements
    }

    /// Each node's slots in the order it sums them: node i's are
    /// `slots[ptr[i]..ptr[i + 1]]` of (`ptr`, `slots`); empty without
    /// pressure.
    pub fn node_slot_lists(&self) -> (&[usize], &[u32]) {
        (&self.node_ptr, &self.node_slots)
    }

    /// Adds the pressures' nodal forces at positions `x` and time `t` to
    /// `f_ext`.
    pub fn add_into(
        &mut self,
        model: &Model,
        x: &[Vector3<f64>],
        t: f64,
        f_ext: &mut [Vector3<f64>],
    ) {
        use rayon::prelude::*;
        if self.is_empty() {
            return;
        }
        for (s, p) in self.scale.iter_mut().zip(&model.pressure) {
            *s = p.pressure_at(t);
        }
        let (elements, scale) = (&self.elements, &self.scale);
        self.slots
            .par_iter_mut()
            .with_min_len(PRESSURE_PIECE)
            .zip(elements.par_iter())
            .for_each(|(f, &(l, e))| {
                let load = &model.pressure[l as usize];
                let nodes = load.element(e as usize);
                *f = drape_model::pressure::vector_area(nodes, x)
                    * (scale[l as usize] / nodes.len() as f64);
            });
        let (slots, ptr, list) = (&self.slots, &self.node_ptr, &self.node_slots);
        f_ext
            .par_iter_mut()
            .with_min_len(PRESSURE_PIECE)
            .enumerate()
            .for_each(|(i, f)| {
                let mut sum = Vector3::zeros();
                for &s in &list[ptr[i]..ptr[i + 1]] {
                    sum += slots[s as usize];
                }
                *f += sum;
            });
    }
}

/// Stored strain energy at `state`.
pub fn strain_energy(model: &Model, state: &State) -> f64 {
    strain_energy_confined(model, state, &[])
}

/// [`strain_energy`] with the confined yarns' clearances of each truss
/// batch (empty, or a batch's empty: free yarns), held at their values: a
/// clearance that changes under a compressed yarn changes its energy
/// without work, which the balance then shows.
pub(crate) fn strain_energy_confined(model: &Model, state: &State, clearance: &[Vec<f64>]) -> f64 {
    let mut e = 0.0;
    for (k, b) in model.trusses.iter().enumerate() {
        e += match clearance.get(k).filter(|c| !c.is_empty()) {
            Some(c) => (0..b.len())
                .map(|i| {
                    b.element_energy_confined(i, &state.x, c[i])
                        .unwrap_or(f64::NAN)
                })
                .sum::<f64>(),
            None => (0..b.len())
                .map(|i| b.element_energy(i, &state.x).unwrap_or(f64::NAN))
                .sum::<f64>(),
        };
    }
    for (b, h) in model.membranes.iter().zip(&state.history) {
        e += b.energy(&state.x, h).unwrap_or(f64::NAN);
    }
    for b in &model.springs {
        e += (0..b.len())
            .map(|i| b.element_energy(i, &state.x))
            .sum::<f64>();
    }
    for b in &model.bending {
        e += b.energy(&state.x).unwrap_or(f64::NAN);
    }
    e
}

/// What every driver asks of a model before it runs: a consistent model,
/// a mass at every node, a non-negative end time.
pub(crate) fn check_model(model: &Model, end_time: f64) -> Result<(), RunError> {
    model.check().map_err(|e| RunError::Setup(e.to_string()))?;
    if !(end_time.is_finite() && end_time >= 0.0) {
        return Err(RunError::Setup(format!(
            "end time {end_time} must be a non-negative number"
        )));
    }
    if let Some(node) =
        (0..model.node_count()).find(|&i| model.mass[i].is_nan() || model.mass[i] <= 0.0)
    {
        return Err(RunError::Setup(format!(
            "node {node} has no mass (it belongs to no membrane element)"
        )));
    }
    Ok(())
}

/// Checks that `state` belongs to `model`.
pub(crate) fn check_state(model: &Model, state: &State) -> Result<(), RunError> {
    if state.x.len() != model.node_count() || !model.history_fits(&state.history) {
        return Err(RunError::Setup(
            "the state does not belong to this model".into(),
        ));
    }
    Ok(())
}

impl ForcePass {
    /// The largest element nodal force of the last evaluation: the scale
    /// of the forces that balance at a node (N).
    pub fn element_force_scale(&self) -> f64 {
        use rayon::prelude::*;
        self.slots
            .par_iter()
            .with_min_len(4096)
            .map(|f| f.amax())
            .reduce(|| 0.0, f64::max)
    }
}
