//! The explicit run with the steps on an [`Engine`]: `drape_time::Explicit`'s
//! loop at the times the host looks (energy checks, frames, progress), the
//! steps between them on the GPU. The energies, the instability guard, the
//! frames and the end-of-run contact check are the CPU driver's own
//! functions, fed from what the engine hands back at those times.
//!
//! Not done here (refused at the start): resuming from a checkpoint and
//! writing checkpoints.

use std::time::Instant;

use drape_contact::{ContactStatus, ContactView, ToolState};
use drape_elements::{ElementError, KinematicsError};
use drape_model::{Model, State};
use drape_time::guard::{Guard, MIN_ENERGY_CHECKS};
use drape_time::{
    Control, DriverState, Energies, Explicit, Frame, NodeAtStep, Observer, Progress, RunError,
    RunSummary, node_energy_terms, strain_energy,
};
use nalgebra::Vector3;

use crate::schedule::{Snapshot, Stepper};
use crate::{Engine, GpuError};

/// The contact at the last state the host read (the tools' state, each
/// node's force and status), as a frame shows it: what a caller writes a
/// run's last frame and picture with.
#[derive(Debug, Clone)]
pub struct RunContact {
    tool_state: Vec<ToolState>,
    force: Vec<Vector3<f64>>,
    status: Vec<ContactStatus>,
    tool_of: Vec<u32>,
    tool_force: Vec<f64>,
    friction_dissipation: f64,
}

impl RunContact {
    /// The contact as a frame takes it (None for a model without tools).
    pub fn view<'a>(&'a self, tools: &'a [drape_contact::Tool]) -> Option<ContactView<'a>> {
        (!tools.is_empty()).then_some(ContactView {
            tools,
            tool_state: &self.tool_state,
            force: &self.force,
            status: &self.status,
            tool_of: &self.tool_of,
            tool_force: &self.tool_force,
            friction_dissipation: self.friction_dissipation,
            plies: None,
        })
    }
}

/// A GPU failure as the run reports it.
fn run_error(e: GpuError, state: &State) -> RunError {
    match e {
        GpuError::Element { kind, index, step } => RunError::Element {
            step,
            time: state.time,
            batch: format!("{kind} (on the GPU)"),
            error: ElementError {
                element: index,
                point: 0,
                cause: KinematicsError::NonFinite {
                    what: "element: collapsed, degenerate or not finite (the CPU driver names \
                           the cause)",
                },
            },
        },
        other => RunError::Setup(format!(
            "the GPU run stopped near t = {:.6e} s: {other}",
            state.time
        )),
    }
}

/// Σ of each running sum over the nodes (in node order), after what a
/// resumed run carries of the first seven (`carried`).
fn totals(s: &Snapshot, n: usize, carried: &[f64; 7]) -> [f64; 8] {
    let mut out = [0.0; 8];
    for (k, o) in out.iter_mut().enumerate() {
        let start = carried.get(k).copied().unwrap_or(0.0);
        *o = s.sums[k * n..(k + 1) * n]
            .iter()
            .fold(start, |sum, x| sum + x);
    }
    out
}

/// Runs `explicit`'s model from `state` to its end time with the steps on
/// `engine`, handing `observer` the frames, progress and checkpoints the
/// CPU driver would; returns the summary and the contact at the end. A
/// run resumed from a checkpoint (`Explicit::resume_from`, the CPU
/// driver's or this one's) continues with the same states, bit for bit,
/// as one that never stopped; its works go on from the checkpoint's
/// totals. On an error `state` holds the last frame that passed every
/// check (or the start).
pub fn run(
    explicit: &Explicit<'_>,
    engine: &mut dyn Engine,
    state: &mut State,
    observer: &mut dyn Observer,
) -> Result<(RunSummary, RunContact), RunError> {
    let started = Instant::now();
    let model = explicit.model();
    let settings = explicit.settings();
    let resume = explicit.resume_state().cloned();
    if let Some(r) = &resume {
        if r.implicit.is_some() {
            return Err(RunError::Setup(
                "the checkpoint was written by the implicit driver".into(),
            ));
        }
        if r.plies.is_some() || !r.truss_clearance.is_empty() {
            return Err(RunError::Setup(
                "the checkpoint carries a ply contact or confined yarns, which the GPU run does \
                 not do: resume it on the CPU"
                    .into(),
            ));
        }
    }
    // The works, friction and tool impulse the stopped run had summed.
    let carried = resume.as_ref().map_or([0.0; 7], |r| {
        let e = &r.energy;
        [
            e.internal_work,
            e.external_work,
            e.damping,
            e.boundary_work,
            e.contact_work,
            r.friction_dissipation,
            r.tools.first().map_or(0.0, |t| t.impulse),
        ]
    });
    let n = model.node_count();
    let end = settings.end_time;
    let mass = explicit.mass();
    let constrained = drape_time::constrained_components(model);
    let movable: Vec<bool> = constrained.iter().map(|c| !c.iter().all(|&b| b)).collect();
    let mut externals = Externals {
        f_ext: vec![Vector3::zeros(); n],
        pressure: drape_time::PressurePass::new(model),
    };
    let mut guard = Guard::new(model, settings.guard.clone(), end);
    let mut stepper = Stepper::start(engine, explicit, state).map_err(|e| run_error(e, state))?;
    let kinetic0: f64 = match &resume {
        Some(r) => r.kinetic0,
        None => (0..n)
            .map(|i| 0.5 * mass[i] * state.v[i].norm_squared())
            .sum(),
    };
    guard.begin(state);
    let mut record = RunContact {
        tool_state: match &resume {
            Some(r) => r.tools.clone(),
            None => explicit
                .contact()
                .map_or_else(Vec::new, |c| c.tool_state.clone()),
        },
        force: vec![Vector3::zeros(); n],
        status: vec![ContactStatus::Open; n],
        tool_of: vec![u32::MAX; n],
        tool_force: vec![0.0; model.tools.len()],
        friction_dissipation: 0.0,
    };
    let mut reactions = vec![Vector3::zeros(); n];
    let inputs = EnergyInputs {
        model,
        mass,
        constrained: &constrained,
        damping: settings.damping,
        kinetic0,
    };
    let mut energy = match &resume {
        Some(r) => r.energy,
        None => Energies {
            kinetic: kinetic0,
            strain: strain_energy(model, state),
            ..Energies::default()
        },
    };
    if state.step == 0 {
        observer.frame(&Frame {
            index: 0,
            model,
            state,
            energy: &energy,
            reactions: &reactions,
            contact: record.view(&model.tools),
        });
    }
    let frame_dt = if settings.frames > 0 {
        end / settings.frames as f64
    } else {
        f64::INFINITY
    };
    let check_dt = end / settings.frames.max(MIN_ENERGY_CHECKS) as f64;
    // As the CPU driver counts them, from a resumed run's time too.
    let mut next_frame = (state.time / frame_dt).floor() as usize + 1;
    let mut next_check = (state.time / check_dt).floor() + 1.0;
    let mut stopped = false;
    let mut last_progress = Instant::now();
    let mut checkpointed = state.step;
    // The step `energy` was measured at.
    let mut measured = state.step;
    while !stepper.at_end(state) {
        if settings.max_steps.is_some_and(|m| stepper.steps >= m) {
            stopped = true;
            break;
        }
        // To the first step at or past the next frame or check, as the CPU
        // driver's tests take them.
        let until = (next_frame as f64 * frame_dt).min(next_check * check_dt) * (1.0 - 1e-12);
        stepper
            .advance(engine, explicit, state, until, settings.max_steps)
            .map_err(|e| {
                let e = run_error(e, state);
                guard.fall_back(state);
                e
            })?;
        let at_end = stepper.at_end(state);
        let at_frame = state.time >= next_frame as f64 * frame_dt * (1.0 - 1e-12);
        let at_check = state.time >= next_check * check_dt * (1.0 - 1e-12);
        let snapshot = engine.snapshot(state).map_err(|e| {
            let e = run_error(e, state);
            guard.fall_back(state);
            e
        })?;
        let unstable = |what| RunError::Unstable {
            step: state.step,
            time: state.time,
            what,
        };
        if let Err(what) = guard.nodes(&state.x, &state.v, &movable) {
            // Where the node is against the tool, as the CPU driver says.
            let u = [stepper.tool_displacement];
            let e = unstable(what.near_tools(&model.tools, &u[..model.tools.len()], &state.x));
            guard.fall_back(state);
            return Err(e);
        }
        // The contact as the frame shows it.
        let sums = totals(&snapshot, n, &carried);
        record.force.clone_from(&snapshot.contact_force);
        for (i, s) in snapshot.status.iter().enumerate() {
            record.status[i] = match s {
                1 => ContactStatus::Stick,
                2 => ContactStatus::Slip,
                _ => ContactStatus::Open,
            };
            record.tool_of[i] = if *s == 0 { u32::MAX } else { 0 };
        }
        record.friction_dissipation = sums[5];
        if let Some(ts) = record.tool_state.first_mut() {
            ts.displacement = stepper.tool_displacement;
            ts.velocity = stepper.tool_velocity;
            ts.impulse = sums[6];
            record.tool_force[0] = sums[7];
        }
        // Before the checks, as the CPU driver hands it: what a restart
        // needs, the works summed to the last half step.
        if stepper.at_checkpoint(state) && state.step > checkpointed {
            checkpointed = state.step;
            observer.checkpoint(
                state,
                &DriverState {
                    dt: stepper.dt,
                    dt_prev: stepper.dt_prev,
                    energy: Energies {
                        internal_work: sums[0],
                        external_work: sums[1],
                        damping: sums[2],
                        boundary_work: sums[3],
                        contact_work: sums[4],
                        ..Energies::default()
                    },
                    kinetic0,
                    tools: record.tool_state.clone(),
                    friction_dissipation: sums[5],
                    implicit: None,
                    truss_clearance: Vec::new(),
                    plies: None,
                },
            );
        }
        if at_frame || at_end || at_check {
            let f_ext = externals.at(model, state);
            energy = energies_at(&inputs, f_ext, state, &snapshot, sums, stepper.dt_prev);
            measured = state.step;
            if let Err(what) = guard.energy(&energy, state.time) {
                let e = unstable(what);
                guard.fall_back(state);
                return Err(e);
            }
            while next_check * check_dt <= state.time * (1.0 + 1e-12) {
                next_check += 1.0;
            }
            if at_frame || at_end {
                guard.accept(state);
            }
            if at_frame {
                for (i, (r, c)) in reactions.iter_mut().zip(&constrained).enumerate() {
                    let quasi_static = snapshot.f_int[i] - externals.f_ext[i];
                    *r = Vector3::from_fn(|k, _| if c[k] { quasi_static[k] } else { 0.0 });
                }
                observer.frame(&Frame {
                    index: next_frame,
                    model,
                    state,
                    energy: &energy,
                    reactions: &reactions,
                    contact: record.view(&model.tools),
                });
                while next_frame as f64 * frame_dt <= state.time * (1.0 + 1e-12) {
                    next_frame += 1;
                }
            }
        }
        if last_progress.elapsed().as_millis() >= 100 || at_end {
            last_progress = Instant::now();
            let p = Progress {
                step: state.step,
                time: state.time,
                end_time: end,
                dt: stepper.dt_prev,
                increment: None,
            };
            if observer.progress(&p) == Control::Stop && !at_end {
                stopped = true;
                break;
            }
        }
    }
    if state.step != measured {
        // Stopped between checks: the energies where it stopped, and only
        // if they pass, as the CPU driver reports them.
        let snapshot = engine.snapshot(state).map_err(|e| run_error(e, state))?;
        let sums = totals(&snapshot, n, &carried);
        let f_ext = externals.at(model, state);
        energy = energies_at(&inputs, f_ext, state, &snapshot, sums, stepper.dt_prev);
        guard
            .energy(&energy, state.time)
            .map_err(|what| RunError::Unstable {
                step: state.step,
                time: state.time,
                what,
            })?;
    }
    if !stopped {
        let u: Vec<f64> = record.tool_state.iter().map(|t| t.displacement).collect();
        drape_time::completion::check_at_end(model, state, &u, None)?;
    }
    let summary = RunSummary {
        steps: stepper.steps,
        dt_range: (stepper.dt_min, stepper.dt_max),
        added_mass: explicit.added_mass(),
        total_mass: mass.iter().sum(),
        energy,
        stopped,
        wall_seconds: started.elapsed().as_secs_f64(),
        threads: 1,
        warnings: explicit.warnings().to_vec(),
        implicit: None,
    };
    Ok((summary, record))
}

/// The external forces at a state's time (the weight, the loads and the
/// follower pressures), as the CPU driver holds them after a step.
struct Externals {
    f_ext: Vec<Vector3<f64>>,
    pressure: drape_time::PressurePass,
}

impl Externals {
    fn at(&mut self, model: &Model, state: &State) -> &[Vector3<f64>] {
        drape_time::external_forces(model, state.time, &mut self.f_ext);
        self.pressure
            .add_into(model, &state.x, state.time, &mut self.f_ext);
        &self.f_ext
    }
}

/// What [`energies_at`] reads besides the snapshot.
struct EnergyInputs<'a> {
    model: &'a Model,
    mass: &'a [f64],
    constrained: &'a [[bool; 3]],
    damping: f64,
    kinetic0: f64,
}

/// `Explicit::energies_at`: the works summed to n+½ plus each node's half
/// increment at the forces of n+1 ([`node_energy_terms`], the CPU
/// driver's own), summed node by node; `f_ext` at the state's time, `h`
/// the last step.
fn energies_at(
    inp: &EnergyInputs<'_>,
    f_ext: &[Vector3<f64>],
    state: &State,
    s: &Snapshot,
    sums: [f64; 8],
    h: f64,
) -> Energies {
    let mut sum = [0.0; 6];
    for (i, f_ext) in f_ext.iter().enumerate() {
        let terms = node_energy_terms(
            &NodeAtStep {
                v: &state.v[i],
                f_int: &s.f_int[i],
                f_ext,
                last_contact: &s.contact_force[i],
                mass: inp.mass[i],
                constrained: inp.constrained[i],
            },
            inp.damping,
            h,
        );
        for (total, t) in sum.iter_mut().zip(terms) {
            *total += t;
        }
    }
    let [kinetic, w_int, w_ext, w_damp, w_bc, w_c] = sum;
    let mut e = Energies {
        kinetic,
        strain: strain_energy(inp.model, state),
        internal_work: sums[0] + w_int,
        external_work: sums[1] + w_ext,
        damping: sums[2] + w_damp,
        boundary_work: sums[3] + w_bc,
        contact_work: sums[4] + w_c,
        friction_dissipation: sums[5],
        ..Energies::default()
    };
    e.viscous = e.internal_work + e.confinement_work - e.strain;
    e.balance_error = e.kinetic + e.internal_work + e.damping
        - e.external_work
        - e.boundary_work
        - e.contact_work
        - inp.kinetic0;
    e
}
