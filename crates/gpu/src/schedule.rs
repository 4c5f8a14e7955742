//! The explicit driver's time stepping (`drape_time::Explicit`'s loop: the
//! stable step re-estimated every `time_step_interval` steps, the last
//! steps cut equal so the run ends on its end time, the first step's
//! half-step mean), handing the steps to an [`Engine`] in blocks of equal
//! steps, so that a GPU runs a block without the host.

use std::time::Instant;

use drape_model::State;
use drape_time::{Explicit, ExplicitSettings};
use nalgebra::Vector3;

use crate::GpuError;

/// One step's constants: the update's damping factors c₁ = 1 − αΔt̄/2 and
/// c₂ = 1/(1 + αΔt̄/2), the mean step Δt̄ and the step h; the tool's
/// displacement after and before the step and its velocity, and the time
/// τ = Δt̄/(1 + αΔt̄/2) over which a contact force changes a velocity.
/// The kernels read them as 8 doubles in this order (`DRAPE_PARAMS`).
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
            ..Self::default()
        }
    }

    /// As the kernels read them.
    pub(crate) fn values(&self) -> [f64; 8] {
        [
            self.c1,
            self.c2,
            self.dt_avg,
            self.h,
            self.tool_displacement,
            self.tool_displacement_before,
            self.tool_velocity,
            self.tau,
        ]
    }
}

/// What runs the steps: the GPU ([`crate::CudaStep`]) or the kernels' CPU
/// build ([`crate::HostStep`]).
pub trait Engine {
    /// Takes positions, velocities and histories from `state`.
    fn load(&mut self, state: &State) -> Result<(), GpuError>;
    /// Writes positions, velocities and histories into `state` (its time
    /// and step are the caller's).
    fn store(&mut self, state: &mut State) -> Result<(), GpuError>;
    /// The current positions.
    fn positions(&mut self) -> Result<Vec<Vector3<f64>>, GpuError>;
    /// The internal forces at the current positions and velocities from
    /// the committed histories over a step `dt`, the histories left as they
    /// are (the run's start).
    fn start_forces(&mut self, dt: f64) -> Result<(), GpuError>;
    /// A step of each of `params` (the same h): each the update, the
    /// contact, then the forces at the new positions with the histories
    /// advanced. `step` is the state's step count before them, to name a
    /// failure.
    fn steps(&mut self, params: &[StepParams], step: u64) -> Result<(), GpuError>;
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
    /// Wall time of the steps (s), the stable-step estimates included.
    pub seconds: f64,
}

/// Runs `engine` from `state` to `settings.end_time` (or `max_steps`), as
/// `explicit` (built from the same model and settings) would step it, and
/// leaves the reached state in `state`.
pub fn run_steps(
    engine: &mut dyn Engine,
    explicit: &Explicit<'_>,
    settings: &ExplicitSettings,
    state: &mut State,
    max_steps: Option<u64>,
) -> Result<StepRun, GpuError> {
    let started = Instant::now();
    let end = settings.end_time;
    let interval = settings.time_step_interval.max(1);
    let model = explicit.model();
    if state.step == 0 {
        // As the CPU driver starts (its start-up checks say so).
        let free: Vec<bool> = (0..model.node_count())
            .map(|i| {
                !model
                    .boundary
                    .iter()
                    .any(|b| b.components.iter().any(|&c| c) && b.nodes.contains(&(i as u32)))
            })
            .collect();
        drape_time::guard::settle_on_tools(model, &mut state.x, &free);
    }
    let tool = model.tools.first();
    let mut tool_u = explicit
        .contact()
        .and_then(|c| c.tool_state.first())
        .map_or(0.0, |s| s.displacement);
    let mut block: Vec<StepParams> = Vec::with_capacity(interval.min(4096) as usize);
    engine.load(state)?;
    // Forces at the start, with no time passing so no relaxation.
    engine.start_forces(0.0)?;
    let mut dt = explicit.stable_time_step(&state.x);
    let mut dt_prev = if state.step == 0 { 0.0 } else { dt };
    let (mut steps, mut blocks) = (0u64, 0u64);
    let (mut dt_min, mut dt_max) = (f64::INFINITY, 0.0f64);
    while end - state.time > 1e-6 * dt && max_steps.is_none_or(|m| steps < m) {
        if state.step > 0 && state.step % interval == 0 {
            dt = explicit.stable_time_step(&engine.positions()?);
        }
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(GpuError::Cuda(format!(
                "stable time step {dt:e} at step {} is not positive",
                state.step
            )));
        }
        // The block: to the next re-estimate, while a step is a whole Δt
        // (the time summed step by step, as the CPU driver sums it).
        let left = end - state.time;
        let h = if left < 4.0 * dt {
            left / (left / dt - 1e-6).ceil().max(1.0)
        } else {
            dt
        };
        let mut count = 1u64;
        let mut time = state.time + h;
        let limit =
            (interval - state.step % interval).min(max_steps.map_or(u64::MAX, |m| m - steps));
        while count < limit && h == dt && end - time >= 4.0 * dt {
            time += h;
            count += 1;
        }
        block.clear();
        for k in 0..count {
            let mut p = StepParams::new(settings.damping, if k == 0 { dt_prev } else { h }, h);
            let t_new = state.time + h;
            if let Some(u) = tool.and_then(|t| t.prescribed_displacement(t_new)) {
                p.tool_displacement_before = tool_u;
                p.tool_velocity = (u - tool_u) / h;
                p.tool_displacement = u;
                tool_u = u;
            }
            block.push(p);
            state.time = t_new;
        }
        engine.steps(&block, state.step)?;
        state.step += count;
        steps += count;
        blocks += 1;
        dt_prev = h;
        dt_min = dt_min.min(h);
        dt_max = dt_max.max(h);
    }
    engine.store(state)?;
    Ok(StepRun {
        steps,
        dt_range: (dt_min, dt_max),
        blocks,
        seconds: started.elapsed().as_secs_f64(),
    })
}
