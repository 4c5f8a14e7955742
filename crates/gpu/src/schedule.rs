//! The explicit driver's time stepping (`drape_time::Explicit`'s loop: the
//! stable step re-estimated every `time_step_interval` steps, the last
//! steps cut equal so the run ends on its end time, the first step's
//! half-step mean), handing the steps to an [`Engine`] in blocks of equal
//! steps, so that a GPU runs a block without the host.

use std::time::Instant;

use drape_model::State;
use drape_time::{Explicit, PrescribedMotions};
use nalgebra::Vector3;

use crate::GpuError;

/// One step's constants: the update's damping factors c₁ = 1 − αΔt̄/2 and
/// c₂ = 1/(1 + αΔt̄/2), the mean step Δt̄ and the step h; the tool's
/// displacement after and before the step and its velocity, and the time
/// τ = Δt̄/(1 + αΔt̄/2) over which a contact force changes a velocity.
/// The kernels read them as 10 doubles in this order (`DRAPE_PARAMS`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[repr(C)]
pub struct StepParams {
    /// 1 − α·Δt̄/2.
    pub c1: f64,
    /// 1/(1 + α·Δt̄/2).
    pub c2: f64,
    /// Δt̄ = (h_prev + h)/2.
    pub dt_avg: f64,
    /// The step.
    pub h: f64,
    /// The tool's displacement at the end of the step.
    pub tool_displacement: f64,
    /// ... and at its start.
    pub tool_displacement_before: f64,
    /// The tool's velocity over the step.
    pub tool_velocity: f64,
    /// Δt̄/(1 + α·Δt̄/2).
    pub tau: f64,
    /// The step before (0 at a run's first).
    pub dt_prev: f64,
    /// The mass-proportional damping α (1/s).
    pub damping: f64,
}

impl StepParams {
    /// The step's constants without a tool (one that does not move).
    pub fn new(damping: f64, dt_prev: f64, h: f64) -> Self {
        let dt_avg = 0.5 * (dt_prev + h);
        Self {
            c1: 1.0 - 0.5 * damping * dt_avg,
            c2: 1.0 / (1.0 + 0.5 * damping * dt_avg),
            dt_avg,
            h,
            tau: dt_avg / (1.0 + 0.5 * damping * dt_avg),
            dt_prev,
            damping,
            ..Self::default()
        }
    }

    /// As the kernels read them.
    pub(crate) fn values(&self) -> [f64; 10] {
        [
            self.c1,
            self.c2,
            self.dt_avg,
            self.h,
            self.tool_displacement,
            self.tool_displacement_before,
            self.tool_velocity,
            self.tau,
            self.dt_prev,
            self.damping,
        ]
    }
}

/// What the host reads at an energy check or a frame, besides the state.
#[derive(Debug, Clone, Default)]
pub struct Snapshot {
    /// The internal forces at the state.
    pub f_int: Vec<Vector3<f64>>,
    /// The last step's contact force on each node (N).
    pub contact_force: Vec<Vector3<f64>>,
    /// Each node's contact status (0 open, 1 stick, 2 slip).
    pub status: Vec<u8>,
    /// Each node's running sums (`DRAPE_SUMS`): works of the internal,
    /// external, damping, boundary and contact forces, friction
    /// dissipated, the normal contact impulse along the tool's axis;
    /// `[k·n + i]`.
    pub sums: Vec<f64>,
}

/// The smallest stable step of each batch at the current positions, in
/// the model's batch order (+∞ for an empty batch).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BatchSteps {
    /// Per truss batch, before its dashpots' factor.
    pub trusses: Vec<f64>,
    /// Per membrane batch, with each element's mass-scaling factor.
    pub membranes: Vec<f64>,
    /// Per spring batch.
    pub springs: Vec<f64>,
    /// Per bending batch.
    pub bending: Vec<f64>,
}

impl BatchSteps {
    /// Replaces the values (no allocation once the lists have their
    /// lengths).
    pub fn set(&mut self, trusses: &[f64], membranes: &[f64], springs: &[f64], bending: &[f64]) {
        for (to, from) in [
            (&mut self.trusses, trusses),
            (&mut self.membranes, membranes),
            (&mut self.springs, springs),
            (&mut self.bending, bending),
        ] {
            to.clear();
            to.extend_from_slice(from);
        }
    }
}

/// `Explicit::stable_time_step` from the batches' smallest steps: the kinds
/// combined as 1/Δt² = Σ 1/Δt_kind², times the safety factor (a fixed
/// step where the settings give one).
fn stable_step(steps: &BatchSteps, factors: &[f64], explicit: &Explicit<'_>) -> f64 {
    let settings = explicit.settings();
    if let Some(dt) = settings.time_step {
        return dt;
    }
    let mut inverse_square = 0.0;
    let mut add = |dt: f64| {
        if dt.is_finite() {
            inverse_square += 1.0 / (dt * dt);
        }
    };
    let smallest = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    add(steps
        .trusses
        .iter()
        .zip(factors)
        .map(|(dt, f)| dt * f)
        .fold(f64::INFINITY, f64::min));
    add(smallest(&steps.membranes));
    add(smallest(&steps.springs));
    add(smallest(&steps.bending));
    settings.safety_factor / inverse_square.sqrt()
}

/// What runs the steps: the GPU ([`crate::CudaStep`]) or the kernels' CPU
/// build ([`crate::HostStep`]).
pub trait Engine {
    /// Takes positions, velocities and histories from `state`.
    fn load(&mut self, state: &State) -> Result<(), GpuError>;
    /// Writes positions, velocities and histories into `state` (its time
    /// and step are the caller's).
    fn store(&mut self, state: &mut State) -> Result<(), GpuError>;
    /// The smallest stable step of each batch at the current positions,
    /// into `out`.
    fn batch_steps(&mut self, out: &mut BatchSteps) -> Result<(), GpuError>;
    /// The state into `state` (as [`Self::store`]) and the rest of what an
    /// energy check and a frame read.
    fn snapshot(&mut self, state: &mut State) -> Result<Snapshot, GpuError>;
    /// The internal forces at the current positions and velocities from
    /// the committed histories over a step `dt`, the histories left as they
    /// are (the run's start).
    fn start_forces(&mut self, dt: f64) -> Result<(), GpuError>;
    /// A step of each of `params` (the same h): each the update, the
    /// contact, then the forces at the new positions with the histories
    /// advanced. `values`: step k's at `[k·w, (k + 1)·w)`, w = m + 3·L +
    /// P: the coordinates of the m components a boundary motion moves at
    /// the step's end (`drape_time::PrescribedMotions`' order), the force
    /// of each of the model's L nodal loads and the p·a(t) of each of its P
    /// pressures at the step's start. `step` is the state's step count
    /// before them, to name a failure.
    fn steps(&mut self, params: &[StepParams], values: &[f64], step: u64) -> Result<(), GpuError>;
}

/// What [`run_steps`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepRun {
    /// Steps taken.
    pub steps: u64,
    /// Smallest and largest step.
    pub dt_range: (f64, f64),
    /// Blocks handed to the engine.
    pub blocks: u64,
    /// Of `seconds`, the stable step's re-estimates (on the engine, the
    /// batches' steps combined on the host).
    pub estimate_seconds: f64,
    /// Wall time of the steps (s), the stable-step estimates included.
    pub seconds: f64,
}

/// The driver's stepping between the times the host looks: the stable
/// step and its re-estimates, the tool's motion, the counts.
pub(crate) struct Stepper {
    end: f64,
    interval: u64,
    /// Blocks end at the steps a checkpoint is taken at (`checkpoint_every`).
    checkpoint: Option<u64>,
    damping: f64,
    /// The current stable step.
    pub dt: f64,
    /// The last step taken (0 before the first).
    pub dt_prev: f64,
    /// The tool's displacement and velocity after the last step.
    pub tool_displacement: f64,
    pub tool_velocity: f64,
    pub steps: u64,
    pub blocks: u64,
    pub dt_min: f64,
    pub dt_max: f64,
    /// Seconds spent re-estimating the stable step.
    pub estimate_seconds: f64,
    /// Each truss batch's dashpot factor on its step.
    truss_factor: Vec<f64>,
    /// The batches' steps at the last re-estimate.
    batch: BatchSteps,
    block: Vec<StepParams>,
    /// The components a boundary motion moves, their coordinates after
    /// the last step, and the block's values (`Engine::steps`' `values`).
    prescribed: PrescribedMotions,
    held_now: Vec<f64>,
    values: Vec<f64>,
}

impl Stepper {
    /// Starts `engine` at `state` as the CPU driver starts: the blank
    /// settled on the tools (its start-up checks said so), the forces at
    /// the start with no time passing, the first stable step; or, resumed
    /// (`explicit.resume_state()`), its steps and tool where the stopped run
    /// left them.
    pub fn start(
        engine: &mut dyn Engine,
        explicit: &Explicit<'_>,
        state: &mut State,
    ) -> Result<Self, GpuError> {
        let settings = explicit.settings();
        let model = explicit.model();
        let resume = explicit.resume_state();
        if state.step == 0 && resume.is_none() {
            let free: Vec<bool> = drape_time::constrained_components(model)
                .iter()
                .map(|c| !c.iter().any(|&b| b))
                .collect();
            drape_time::guard::settle_on_tools(model, &mut state.x, &free);
        }
        engine.load(state)?;
        engine.start_forces(0.0)?;
        let (dt, dt_prev) = match resume {
            Some(r) => (r.dt, r.dt_prev),
            None => {
                let dt = explicit.stable_time_step(&state.x);
                (dt, if state.step == 0 { 0.0 } else { dt })
            }
        };
        let interval = settings.time_step_interval.max(1);
        let tool = match resume {
            Some(r) => r.tools.first(),
            None => explicit.contact().and_then(|c| c.tool_state.first()),
        };
        let prescribed = PrescribedMotions::new(model);
        let held_now: Vec<f64> = prescribed
            .components()
            .map(|(i, k)| state.x[i][k])
            .collect();
        let block = interval.min(4096) as usize;
        Ok(Self {
            end: settings.end_time,
            interval,
            checkpoint: settings.checkpoint_every.map(|k| k.max(1)),
            damping: settings.damping,
            dt,
            dt_prev,
            tool_displacement: tool.map_or(0.0, |t| t.displacement),
            tool_velocity: tool.map_or(0.0, |t| t.velocity),
            steps: 0,
            blocks: 0,
            dt_min: f64::INFINITY,
            dt_max: 0.0,
            estimate_seconds: 0.0,
            truss_factor: explicit.step_inputs().truss_factor,
            batch: BatchSteps::default(),
            block: Vec::with_capacity(block),
            values: Vec::with_capacity(
                block * (held_now.len() + 3 * model.loads.len() + model.pressure.len()),
            ),
            prescribed,
            held_now,
        })
    }

    /// Whether `state` is at the end time (a remainder below a millionth
    /// of a step is round-off).
    pub fn at_end(&self, state: &State) -> bool {
        self.end - state.time <= 1e-6 * self.dt
    }

    /// Whether `state` is at a step a checkpoint is taken at.
    pub fn at_checkpoint(&self, state: &State) -> bool {
        self.checkpoint.is_some_and(|k| state.step % k == 0)
    }

    /// Steps until the first step whose time is at or past `until`, the
    /// end time, `max_steps` steps in all or a checkpoint's step, in blocks
    /// of equal steps that end at the stable step's re-estimates.
    pub fn advance(
        &mut self,
        engine: &mut dyn Engine,
        explicit: &Explicit<'_>,
        state: &mut State,
        until: f64,
        max_steps: Option<u64>,
    ) -> Result<(), GpuError> {
        let tool = explicit.model().tools.first();
        let end = self.end;
        let first = state.step;
        while !self.at_end(state)
            && state.time < until
            && max_steps.is_none_or(|m| self.steps < m)
            && !(state.step > first && self.at_checkpoint(state))
        {
            if state.step > 0 && state.step % self.interval == 0 {
                let started = Instant::now();
                engine.batch_steps(&mut self.batch)?;
                self.dt = stable_step(&self.batch, &self.truss_factor, explicit);
                self.estimate_seconds += started.elapsed().as_secs_f64();
            }
            let dt = self.dt;
            if !(dt > 0.0 && dt.is_finite()) {
                return Err(GpuError::Cuda(format!(
                    "stable time step {dt:e} at step {} is not positive",
                    state.step
                )));
            }
            // The block: to the next re-estimate, while a step is a whole
            // Δt (the time summed step by step, as the CPU driver sums it).
            let h = drape_time::step_length(end - state.time, dt);
            let limit = (self.interval - state.step % self.interval)
                .min(max_steps.map_or(u64::MAX, |m| m - self.steps))
                .min(self.checkpoint.map_or(u64::MAX, |k| k - state.step % k));
            let (mut count, mut time) = (1u64, state.time + h);
            while count < limit && h == dt && end - time >= 4.0 * dt && time < until {
                time += h;
                count += 1;
            }
            self.block.clear();
            self.values.clear();
            for k in 0..count {
                let before = if k == 0 { self.dt_prev } else { h };
                let mut p = StepParams::new(self.damping, before, h);
                let t_new = state.time + h;
                if let Some(u) = tool.and_then(|t| t.prescribed_displacement(t_new)) {
                    p.tool_displacement_before = self.tool_displacement;
                    p.tool_velocity = (u - self.tool_displacement) / h;
                    p.tool_displacement = u;
                    self.tool_displacement = u;
                    self.tool_velocity = p.tool_velocity;
                }
                self.block.push(p);
                // As the CPU driver's step: from the coordinate before it;
                // the loads as they were at its start.
                let model = explicit.model();
                self.prescribed
                    .advance(model, &mut self.held_now, state.time, h);
                self.values.extend_from_slice(&self.held_now);
                for load in &model.loads {
                    self.values
                        .extend_from_slice(load.force_at(state.time).as_slice());
                }
                for p in &model.pressure {
                    self.values.push(p.pressure_at(state.time));
                }
                state.time = t_new;
            }
            engine.steps(&self.block, &self.values, state.step)?;
            state.step += count;
            self.steps += count;
            self.blocks += 1;
            self.dt_prev = h;
            self.dt_min = self.dt_min.min(h);
            self.dt_max = self.dt_max.max(h);
        }
        Ok(())
    }
}

/// Runs `engine` from `state` to its end time (or `max_steps`), as
/// `explicit` would step it, and leaves the reached state in `state`:
/// the steps alone, with no energies, guard or frames (see
/// [`crate::run`] for the whole run).
pub fn run_steps(
    engine: &mut dyn Engine,
    explicit: &Explicit<'_>,
    state: &mut State,
    max_steps: Option<u64>,
) -> Result<StepRun, GpuError> {
    let started = Instant::now();
    let mut stepper = Stepper::start(engine, explicit, state)?;
    stepper.advance(engine, explicit, state, f64::INFINITY, max_steps)?;
    engine.store(state)?;
    Ok(StepRun {
        steps: stepper.steps,
        dt_range: (stepper.dt_min, stepper.dt_max),
        blocks: stepper.blocks,
        estimate_seconds: stepper.estimate_seconds,
        seconds: started.elapsed().as_secs_f64(),
    })
}
