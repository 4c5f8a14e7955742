//! The explicit central-difference driver (SPEC §7, "Explicit").

use std::time::Instant;

use drape_contact::{ContactSettings, ExplicitContact, StepTimes};
use drape_model::{Model, State};
use nalgebra::Vector3;
use rayon::prelude::*;

use crate::confinement::Confinement;
use crate::energy::{NodeAtStep, chunked_sum, chunked_sums_into, node_energy_terms};
use crate::guard::{self, Guard, GuardSettings};
use crate::profile::{Pass, ProfileClock, Profiler, StepProfile};
use crate::scaling::LoadTiming;
use crate::shared::{self, Constraints, ForcePass, PressurePass};
use crate::{Control, DriverState, Energies, Frame, Observer, Progress, RunError, RunSummary};

/// Nodes per task of the velocity/position update.
const NODE_PIECE: usize = 4096;

/// Settings of an explicit run.
#[derive(Debug, Clone, PartialEq)]
pub struct ExplicitSettings {
    /// Time to reach (s).
    pub end_time: f64,
    /// Fraction of the stable step used.
    pub safety_factor: f64,
    /// A fixed Δt instead of the stable estimate. [`Explicit::new`] refuses
    /// one above the estimate (at safety factor 1) of the initial mesh; if
    /// the deformed mesh's estimate falls below it later, the run warns
    /// and the guard watches.
    pub time_step: Option<f64>,
    /// Target Δt for selective mass scaling: nodes of elements whose stable
    /// step is smaller get mass until it is reached.
    pub mass_scaling: Option<f64>,
    /// α of the mass-proportional damping force −α·m·v (1/s).
    pub damping: f64,
    /// Number of output frames after the initial one, equally spaced in time.
    pub frames: usize,
    /// Steps between stable-Δt re-estimates.
    pub time_step_interval: u64,
    /// The instability guard ([`crate::guard`]): energy balance bound,
    /// speed and reach checks, the quasi-static bound.
    pub guard: GuardSettings,
    /// Stop after this many steps.
    pub max_steps: Option<u64>,
    /// Broad-phase margin of the contact pass (mm).
    pub contact_margin: f64,
    /// Hand the observer a checkpoint every this many steps.
    pub checkpoint_every: Option<u64>,
    /// Fraction of critical damping of a dashpot along every truss whose
    /// fibre law has a kink (`FibreLaw::has_kink` in drape-constitutive),
    /// for that truss's own two-mass mode: an uncrimped yarn switches
    /// between taut and slack, and without it central differences grow in
    /// resonance bands below the linear stability limit. 0.06 is
    /// Abaqus/Explicit's default linear bulk viscosity. Its work is part of
    /// the internal work, reported as viscous.
    pub fibre_damping: f64,
}

impl Default for ExplicitSettings {
    fn default() -> Self {
        Self {
            end_time: 1.0,
            safety_factor: 0.9,
            time_step: None,
            mass_scaling: None,
            damping: 0.0,
            frames: 10,
            time_step_interval: 20,
            guard: GuardSettings::default(),
            max_steps: None,
            contact_margin: 5.0,
            checkpoint_every: None,
            fibre_damping: 0.06,
        }
    }
}

/// The step to take with `left` seconds to go at a stable step `dt`: `dt`,
/// or near the end the time left cut into equal steps no longer than `dt`,
/// so that the run ends on its end time without a sliver of a last step (a
/// tiny step turns an ordinary contact increment into a huge force). A
/// millionth of a step over a whole number is round-off of the summed
/// steps, not a step more.
pub fn step_length(left: f64, dt: f64) -> f64 {
    if left < 4.0 * dt {
        left / (left / dt - 1e-6).ceil().max(1.0)
    } else {
        dt
    }
}

/// See [`Explicit::step_inputs`].
#[derive(Debug, Clone)]
pub struct StepInputs<'a> {
    /// Per truss batch, per truss, its nodes' mass shares (t).
    pub truss_mass: &'a [Vec<[f64; 2]>],
    /// Per bending batch, per triplet, its nodes' mass shares (t).
    pub bending_mass: &'a [Vec<[f64; 3]>],
    /// Per membrane batch, per element, the factor on its stable step.
    pub membrane_scale: &'a [Vec<f64>],
    /// Per truss batch, the factor its dashpots put on its step.
    pub truss_factor: Vec<f64>,
}

/// The explicit central-difference driver with its scratch buffers.
pub struct Explicit<'m> {
    model: &'m Model,
    settings: ExplicitSettings,
    mass: Vec<f64>,
    /// Each truss's shares of its nodes' masses (a node's mass split evenly
    /// among the trusses of its batch there), for the stable step.
    truss_mass: Vec<Vec<[f64; 2]>>,
    /// Dashpot coefficient of each truss of a batch with a kinked fibre
    /// law (empty for the others), see [`ExplicitSettings::fibre_damping`].
    truss_damping: Vec<Vec<f64>>,
    /// Each bending triplet's shares of its nodes' masses, as the trusses'.
    bending_mass: Vec<Vec<[f64; 3]>>,
    /// √(mass scale) per element of each membrane batch.
    membrane_scale: Vec<Vec<f64>>,
    constraints: Constraints,
    added_mass: f64,
    forces: ForcePass,
    /// The follower pressures (empty without).
    pressure: PressurePass,
    f_ext: Vec<Vector3<f64>>,
    x_new: Vec<Vector3<f64>>,
    v_new: Vec<Vector3<f64>>,
    reactions: Vec<Vector3<f64>>,
    contact: Option<ExplicitContact>,
    /// Prescribed coordinate of each constrained component this step.
    prescribed: Vec<f64>,
    /// Where to pick up, for a resumed run.
    resume: Option<DriverState>,
    /// Partial sums of the step's works, and of the energies at a check.
    work_partials: Vec<[f64; 5]>,
    energy_partials: Vec<[f64; 6]>,
    guard: Guard,
    /// Start-up and run warnings.
    warnings: Vec<String>,
    /// Which tools have touched the blank.
    tool_touched: Vec<bool>,
    /// The per-pass profile, when asked for ([`Self::enable_profile`]).
    profiler: Option<Profiler>,
    /// The confined yarns' scratch, when any yarn is confined
    /// ([`crate::confinement`]).
    confinement: Option<Confinement>,
}

impl<'m> Explicit<'m> {
    /// Prepares a run of `model`: checks it, builds the slot layout and the
    /// constraint list, applies mass scaling.
    pub fn new(model: &'m Model, settings: ExplicitSettings) -> Result<Self, RunError> {
        shared::check_model(model, settings.end_time)?;
        if !(settings.fibre_damping.is_finite() && settings.fibre_damping >= 0.0) {
            return Err(RunError::Setup(format!(
                "fibre damping {} must be a non-negative fraction of critical damping",
                settings.fibre_damping
            )));
        }
        if !(settings.safety_factor > 0.0 && settings.safety_factor <= 1.0) {
            return Err(RunError::Setup(format!(
                "safety factor {} must be in (0, 1]",
                settings.safety_factor
            )));
        }
        let n = model.node_count();
        let constraints = Constraints::new(model);
        let contact = (!model.tools.is_empty()).then(|| {
            ExplicitContact::new(
                model.tools.clone(),
                n,
                ContactSettings {
                    offset: model.contact_offset,
                    margin: settings.contact_margin,
                    // A node and a tool closing in by more than the fabric's
                    // thickness in one step are beyond what a step resolves.
                    max_travel: if model.contact_offset > 0.0 {
                        2.0 * model.contact_offset
                    } else {
                        f64::INFINITY
                    },
                    clearance_reach: Confinement::reach(model),
                    ..ContactSettings::default()
                },
            )
        });
        // A laminate: the plies' contact rides on the tools' pass (which
        // may then have no tool at all).
        let contact = match contact {
            None if model.plies.len() > 1 => Some(ExplicitContact::new(
                Vec::new(),
                n,
                ContactSettings {
                    offset: model.contact_offset,
                    margin: settings.contact_margin,
                    ..ContactSettings::default()
                },
            )),
            other => other,
        }
        .map(|mut c| {
            if model.plies.len() > 1 {
                let (layers, interfaces) = model.ply_layers();
                c.set_plies(drape_contact::PlyContact::new(
                    layers,
                    &interfaces,
                    model.nodal_area(),
                    settings.contact_margin,
                ));
                // Each ply on a tool at its own half thickness.
                c.set_node_offsets(model.ply_half_thickness_per_node());
            }
            c
        });
        let guard = Guard::new(model, settings.guard.clone(), settings.end_time);
        let mut driver = Self {
            model,
            settings,
            contact,
            prescribed: vec![0.0; constraints.list.len()],
            resume: None,
            work_partials: Vec::new(),
            energy_partials: Vec::new(),
            guard,
            warnings: Vec::new(),
            tool_touched: vec![false; model.tools.len()],
            forces: ForcePass::new(model),
            pressure: PressurePass::new(model),
            profiler: None,
            confinement: Confinement::applies(model).then(Confinement::default),
            mass: model.mass.clone(),
            truss_mass: Vec::new(),
            truss_damping: Vec::new(),
            bending_mass: Vec::new(),
            membrane_scale: model.membranes.iter().map(|b| vec![1.0; b.len()]).collect(),
            constraints,
            added_mass: 0.0,
            f_ext: vec![Vector3::zeros(); n],
            x_new: vec![Vector3::zeros(); n],
            v_new: vec![Vector3::zeros(); n],
            reactions: vec![Vector3::zeros(); n],
        };
        if driver.confinement.is_some() {
            driver.forces.truss_clearance = Confinement::free(model);
        }
        driver.share_truss_mass();
        if let Some(target) = driver.settings.mass_scaling {
            driver.scale_mass(target);
            driver.share_truss_mass();
            // Kinds add their stiffnesses (see `stable_time_step`), so the
            // elements' own targets can leave the whole a little short: a
            // last uniform factor closes the gap. It is the material's
            // estimate, never a forced `time_step`: a step forced below the
            // target would otherwise ask for (target/forced)² more mass, and
            // refining the step would change the physics.
            let dt = driver.estimated_time_step(&model.x0);
            if dt < target {
                let f = (target / dt).powi(2);
                let before: f64 = model.mass.iter().sum();
                for m in &mut driver.mass {
                    *m *= f;
                }
                driver.added_mass = driver.mass.iter().sum::<f64>() - before;
                for s in driver.membrane_scale.iter_mut().flatten() {
                    *s *= f.sqrt();
                }
                driver.share_truss_mass();
            }
        }
        let estimate = driver.estimated_time_step(&model.x0);
        if let Some(forced) = driver.settings.time_step {
            let stable = estimate / driver.settings.safety_factor;
            if !(forced > 0.0 && forced.is_finite()) {
                return Err(RunError::Setup(format!(
                    "the time step {forced:e} s must be a positive number"
                )));
            }
            if forced > stable {
                return Err(RunError::Setup(format!(
                    "the time step {forced:.4e} s is {:.3}× the stable time step {stable:.4e} s of this \
                     model (the elements' estimate; drape would use {estimate:.4e} s at safety factor {}): \
                     central differences would diverge. Remove time_step or lower it, or raise the \
                     stable step with mass scaling",
                    forced / stable,
                    driver.settings.safety_factor
                )));
            }
        }
        let dt = driver.settings.time_step.unwrap_or(estimate);
        driver.warnings =
            guard::check_tools_at_start(model, &model.x0, dt).map_err(RunError::Setup)?;
        if let Some(timing) = LoadTiming::of(model, &driver.mass, driver.settings.end_time) {
            driver.warnings.push(timing.message());
        }
        Ok(driver)
    }

    /// Profiles the steps of every later [`Self::run`] by `clock` (see
    /// [`crate::profile`]); the sums start from zero.
    pub fn enable_profile(&mut self, clock: ProfileClock) {
        self.profiler = Some(Profiler::new(clock));
        if let Some(contact) = &mut self.contact {
            contact.time_phases(Some(clock));
        }
    }

    /// The per-pass profile of the steps run since [`Self::enable_profile`],
    /// those of a run that stopped on an error included.
    pub fn profile(&self) -> Option<&StepProfile> {
        self.profiler.as_ref().map(|p| &p.profile)
    }

    #[inline]
    fn lap(&mut self, pass: Pass) {
        if let Some(p) = &mut self.profiler {
            p.lap(pass);
        }
    }

    /// What the run found doubtful: start-up warnings (a blank closer to a
    /// tool than its half thickness, a force-driven tool with nothing in
    /// its path) and, after [`Self::run`], the run's own.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The trusses' mass shares, and the dashpots of kinked yarns that
    /// depend on them.
    fn share_truss_mass(&mut self) {
        let n = self.model.node_count();
        self.truss_mass = self
            .model
            .trusses
            .iter()
            .map(|b| {
                let degree = b.node_degree(n);
                let share = |i: u32| self.mass[i as usize] / f64::from(degree[i as usize]);
                b.nodes.iter().map(|&[i, j]| [share(i), share(j)]).collect()
            })
            .collect();
        self.bending_mass = self
            .model
            .bending
            .iter()
            .map(|b| {
                let degree = b.node_degree(n);
                let share = |i: u32| self.mass[i as usize] / f64::from(degree[i as usize]);
                b.nodes.iter().map(|t| t.map(share)).collect()
            })
            .collect();
        let ratio = self.settings.fibre_damping;
        self.truss_damping = self
            .model
            .trusses
            .iter()
            .zip(&self.truss_mass)
            .map(|(b, shares)| {
                if ratio > 0.0 && b.law.has_kink() {
                    (0..b.len())
                        .map(|e| b.damping_coefficient(e, shares[e], ratio))
                        .collect()
                } else {
                    Vec::new()
                }
            })
            .collect();
    }

    /// The factor √(1 + ξ²) − ξ by which a dashpot at ratio ξ of its mode's
    /// critical damping shortens that mode's stable step (explicit
    /// central differences with the damping force at the mid-step velocity).
    fn damped_step_factor(&self, b: usize) -> f64 {
        if self.truss_damping[b].is_empty() {
            1.0
        } else {
            let xi = self.settings.fibre_damping;
            (1.0 + xi * xi).sqrt() - xi
        }
    }

    /// Selective mass scaling at the reference shape: an element whose step
    /// is below `target` asks for mass factor (target/Δt_e)² on its nodes;
    /// each node takes the largest factor asked. A membrane's step then grows
    /// with the square root of the smallest factor of its nodes; a truss's
    /// and a bending triplet's follow from their nodes' new masses.
    fn scale_mass(&mut self, target: f64) {
        let model = self.model;
        let x = &model.x0;
        let safety = self.settings.safety_factor;
        let mut factor = vec![1.0f64; model.node_count()];
        let mut ask = |nodes: &[u32], dt: f64| {
            let f = (target / (safety * dt)).powi(2);
            if f > 1.0 {
                for &n in nodes {
                    factor[n as usize] = factor[n as usize].max(f);
                }
            }
        };
        for (b, shares) in model.trusses.iter().zip(&self.truss_mass) {
            for (e, share) in shares.iter().enumerate() {
                ask(&b.nodes[e], b.element_stable_time_step(e, x, *share));
            }
        }
        for b in &model.membranes {
            for e in 0..b.len() {
                ask(b.element_nodes(e), b.element_stable_time_step(e, x));
            }
        }
        // A triplet's step goes as h², so on fine meshes bending can ask
        // for more than the membranes; left to the last uniform factor it
        // would weigh down every node.
        for (b, shares) in model.bending.iter().zip(&self.bending_mass) {
            for (e, share) in shares.iter().enumerate() {
                ask(&b.nodes[e], b.element_stable_time_step(e, x, *share));
            }
        }
        let smallest = |nodes: &[u32]| {
            nodes
                .iter()
                .map(|&n| factor[n as usize])
                .fold(f64::INFINITY, f64::min)
                .sqrt()
        };
        for (b, s) in model.membranes.iter().zip(&mut self.membrane_scale) {
            for (e, se) in s.iter_mut().enumerate() {
                *se = smallest(b.element_nodes(e));
            }
        }
        let before: f64 = self.mass.iter().sum();
        for (m, f) in self.mass.iter_mut().zip(&factor) {
            *m *= f;
        }
        self.added_mass = self.mass.iter().sum::<f64>() - before;
    }

    /// The stable step (times the safety factor) at positions `x`.
    ///
    /// Trusses, membranes, springs and yarn bending share the nodes' masses and add their
    /// stiffnesses, so ω_max² ≤ Σ over kinds of each kind's ω_max²: the
    /// kinds' steps combine as 1/Δt² = Σ 1/Δt_kind², each kind's step the
    /// smallest of its elements' (SPEC §7: fibres at the full E_f). A truss
    /// batch with dashpots ([`ExplicitSettings::fibre_damping`]) has its
    /// step shortened by the damping, by √(1 + ξ²) − ξ.
    pub fn stable_time_step(&self, x: &[Vector3<f64>]) -> f64 {
        self.settings
            .time_step
            .unwrap_or_else(|| self.estimated_time_step(x))
    }

    /// The elements' estimate of the stable step times the safety factor,
    /// whether or not a time step is forced.
    fn estimated_time_step(&self, x: &[Vector3<f64>]) -> f64 {
        let model = self.model;
        // Pieces of about 100 k instructions (callgrind, 200 × 200 blank:
        // ≈ 45 per truss): enough to pay for waking a second thread, and
        // the minimum does not depend on how the range is split. The
        // membranes split their own (`min_scaled_stable_time_step`).
        let smallest = |len: usize, piece: usize, dt_e: &(dyn Fn(usize) -> f64 + Sync)| {
            (0..len)
                .into_par_iter()
                .with_min_len(piece)
                .map(dt_e)
                .reduce(|| f64::INFINITY, f64::min)
        };
        let mut inverse_square = 0.0;
        let mut add = |dt: f64| {
            if dt.is_finite() {
                inverse_square += 1.0 / (dt * dt);
            }
        };
        add(model
            .trusses
            .iter()
            .zip(&self.truss_mass)
            .enumerate()
            .map(|(k, (b, m))| {
                smallest(b.len(), 2048, &|e| b.element_stable_time_step(e, x, m[e]))
                    * self.damped_step_factor(k)
            })
            .fold(f64::INFINITY, f64::min));
        // (Resin-only quads on the lanes, with the same bits.)
        add(model
            .membranes
            .iter()
            .zip(&self.membrane_scale)
            .map(|(b, s)| b.min_scaled_stable_time_step(x, s))
            .fold(f64::INFINITY, f64::min));
        add(model
            .springs
            .iter()
            .flat_map(|b| (0..b.len()).map(move |e| (b, e)))
            .map(|(b, e)| b.element_stable_time_step(e, x, self.mass[b.nodes[e] as usize]))
            .fold(f64::INFINITY, f64::min));
        add(model
            .bending
            .iter()
            .zip(&self.bending_mass)
            .map(|(b, m)| smallest(b.len(), 2048, &|e| b.element_stable_time_step(e, x, m[e])))
            .fold(f64::INFINITY, f64::min));
        self.settings.safety_factor / inverse_square.sqrt()
    }

    /// Continues a stopped run: the next [`Self::run`] takes its step size,
    /// energies and tools from `driver` (saved with the state by
    /// [`Observer::checkpoint`]), so it reaches the same result, bit for bit,
    /// as a run that never stopped.
    pub fn resume_from(&mut self, driver: DriverState) {
        self.resume = Some(driver);
    }

    /// What [`Self::resume_from`] was handed, until a run takes it: for a
    /// driver stepped elsewhere (drape-gpu) that continues the same way.
    pub fn resume_state(&self) -> Option<&DriverState> {
        self.resume.as_ref()
    }

    /// The contact pass as the last step left it (forces, statuses,
    /// tools' states), if the model has tools: what a frame written after
    /// [`Self::run`] returns (a run stopped between frames) shows.
    pub fn contact(&self) -> Option<&ExplicitContact> {
        self.contact.as_ref()
    }

    /// What the stable step of each element reads besides the positions:
    /// the trusses' and the bending triplets' shares of their nodes'
    /// masses (per batch, per element), each membrane's mass-scaling
    /// factor on its step, and each truss batch's factor for its dashpots
    /// (1 without), as [`Self::stable_time_step`] takes them.
    pub fn step_inputs(&self) -> StepInputs<'_> {
        StepInputs {
            truss_mass: &self.truss_mass,
            bending_mass: &self.bending_mass,
            membrane_scale: &self.membrane_scale,
            truss_factor: (0..self.truss_damping.len())
                .map(|b| self.damped_step_factor(b))
                .collect(),
        }
    }

    /// The model it runs.
    pub fn model(&self) -> &'m Model {
        self.model
    }

    /// Its settings.
    pub fn settings(&self) -> &ExplicitSettings {
        &self.settings
    }

    /// The dashpot coefficient (N·s/mm) of each truss of each batch along
    /// kinked yarns ([`ExplicitSettings::fibre_damping`]); an empty list for
    /// a batch without. Fixed at set-up from the scaled masses.
    pub fn fibre_dashpots(&self) -> &[Vec<f64>] {
        &self.truss_damping
    }

    /// The nodes' masses the driver integrates with (t): the model's, plus
    /// what mass scaling added.
    pub fn mass(&self) -> &[f64] {
        &self.mass
    }

    /// Mass added by mass scaling (t), 0 without it: known before the run.
    pub fn added_mass(&self) -> f64 {
        self.added_mass
    }

    /// Runs from `state` to the end time. On error `state` holds the last
    /// output frame (or the start), which passed every check: a failed run
    /// reports no state on its way to the failure.
    pub fn run(
        &mut self,
        state: &mut State,
        observer: &mut dyn Observer,
    ) -> Result<RunSummary, RunError> {
        let first = state.step;
        let result = self.advance(state, observer);
        if let Err(e) = &result {
            // The steps taken up to the failure, which `advance` left
            // without closing the profile: a run that stops is one whose
            // profile is wanted (before the fall-back rewinds the step).
            self.end_profile(state.step.saturating_sub(first));
            if !matches!(e, RunError::Setup(_)) {
                self.guard.fall_back(state);
            }
        }
        result
    }

    /// Stops the profile's clock after `steps` steps and adds the contact
    /// phases' times to it; nothing when no profile is running.
    fn end_profile(&mut self, steps: u64) {
        let Some(p) = self.profiler.as_mut().filter(|p| p.is_active()) else {
            return;
        };
        p.end(steps, self.contact.as_ref().and_then(|c| c.phase_times()));
        if let Some(c) = &mut self.contact {
            // The phases were added to the profile: count afresh.
            c.time_phases(Some(p.clock()));
        }
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
        let damping = self.settings.damping;
        shared::check_state(model, state)?;
        if state.step == 0 && self.resume.is_none() {
            // Said in `warnings` by the start-up checks.
            guard::settle_on_tools(model, &mut state.x, &self.constraints.free());
        }
        shared::external_forces(model, state.time, &mut self.f_ext);
        self.pressure
            .add_into(model, &state.x, state.time, &mut self.f_ext);
        // A resumed run's yarns confined as the stopped run's last contact
        // pass left them (the same forces, bit for bit).
        if let Some(r) = &self.resume {
            Confinement::restore(&r.truss_clearance, &mut self.forces.truss_clearance);
        }
        // Forces at the start, with no time passing so no relaxation.
        self.forces.evaluate(
            model,
            &state.x,
            Some((&state.v, &self.truss_damping)),
            &state.history,
            0.0,
            state.step,
            state.time,
            None,
        )?;
        let resume = self.resume.take();
        if resume.as_ref().is_some_and(|r| r.implicit.is_some()) {
            return Err(RunError::Setup(
                "the checkpoint was written by the implicit driver".into(),
            ));
        }
        let mut energy = resume.as_ref().map_or_else(Energies::default, |r| r.energy);
        let kinetic0: f64 = match &resume {
            Some(r) => r.kinetic0,
            None => chunked_sum(n, |i| 0.5 * self.mass[i] * state.v[i].norm_squared()),
        };
        if let (Some(r), Some(contact)) = (&resume, &mut self.contact) {
            contact.tool_state.clone_from(&r.tools);
            contact.friction_dissipation = r.friction_dissipation;
            match (contact.plies_mut(), &r.plies) {
                (Some(plies), Some(carry)) => plies.restore(carry).map_err(RunError::Setup)?,
                // A checkpoint written before the ply pass was carried.
                (Some(_), None) => self.warnings.push(
                    "the checkpoint carries no ply contact state (an older drape wrote it): the \
                     plies' solves start cold and their slip from zero, so the resumed run is \
                     not bit for bit the uninterrupted one"
                        .into(),
                ),
                (None, Some(_)) => {
                    return Err(RunError::Setup(
                        "the checkpoint carries a ply contact, and this model is no stack".into(),
                    ));
                }
                (None, None) => {}
            }
        }
        let frame_dt = if self.settings.frames > 0 {
            end / self.settings.frames as f64
        } else {
            f64::INFINITY
        };
        let mut next_frame = (state.time / frame_dt).floor() as usize + 1;
        // The guard looks at the energy at every frame, and at least
        // `guard::MIN_ENERGY_CHECKS` times a run whatever the frames.
        let check_dt = end / self.settings.frames.max(guard::MIN_ENERGY_CHECKS) as f64;
        let mut next_check = (state.time / check_dt).floor() + 1.0;
        self.guard.begin(state);
        // Plies inside each other at the start (an imported blank stacked
        // too close) are not a state to form from.
        self.check_plies(state)?;
        let mut forced_warned = false;
        if state.step == 0 {
            energy.kinetic = kinetic0;
            energy.strain =
                shared::strain_energy_confined(model, state, &self.forces.truss_clearance);
            observer.frame(&Frame {
                index: 0,
                model,
                state,
                energy: &energy,
                reactions: &self.reactions,
                contact: self.contact.as_ref().map(ExplicitContact::view),
            });
        }
        let (mut dt, mut dt_prev) = match &resume {
            Some(r) => (r.dt, r.dt_prev),
            None => {
                let dt = self.stable_time_step(&state.x);
                (dt, if state.step == 0 { 0.0 } else { dt })
            }
        };
        let (mut dt_min, mut dt_max) = (f64::INFINITY, 0.0f64);
        let mut steps = 0u64;
        let mut stopped = false;
        let mut last_progress = Instant::now();
        if let Some(p) = &mut self.profiler {
            p.begin();
        }
        // A remainder below a millionth of a step is round-off of the sum of
        // steps, not time left to simulate.
        while end - state.time > 1e-6 * dt {
            if self.settings.max_steps.is_some_and(|m| steps >= m) {
                stopped = true;
                break;
            }
            // On the state's step count, so that a resumed run re-estimates
            // at the same steps as an uninterrupted one.
            if state.step > 0 && state.step % self.settings.time_step_interval.max(1) == 0 {
                dt = self.stable_time_step(&state.x);
                if self.settings.time_step.is_some() && !forced_warned {
                    let stable = self.estimated_time_step(&state.x) / self.settings.safety_factor;
                    if dt > stable {
                        forced_warned = true;
                        self.warnings.push(format!(
                            "from step {} (t = {:.6e} s) the time step {dt:.4e} s is above the \
                             deformed mesh's stable estimate {stable:.4e} s",
                            state.step, state.time
                        ));
                    }
                }
            }
            self.lap(Pass::StableStep);
            if !(dt > 0.0 && dt.is_finite()) {
                return Err(RunError::Setup(format!(
                    "stable time step {dt:e} at step {} is not positive",
                    state.step
                )));
            }
            let h = step_length(end - state.time, dt);
            let t_new = state.time + h;
            let dt_avg = 0.5 * (dt_prev + h);
            // Velocities to n+½ and positions to n+1 for free components;
            // mass-proportional damping taken at the mid-step velocity.
            let (c1, c2) = (
                1.0 - 0.5 * damping * dt_avg,
                1.0 / (1.0 + 0.5 * damping * dt_avg),
            );
            {
                let (x, v, m, f_int, f_ext) = (
                    &state.x,
                    &state.v,
                    &self.mass,
                    &self.forces.f_int,
                    &self.f_ext,
                );
                // Pieces of 4 096 nodes pay for a second thread's wake-up
                // (1 024 did not), each a plain loop over zipped slices: a
                // per-node parallel iterator called a closure with five
                // bounds checks at every node (≈ 75 instructions a node
                // and as many again in rayon's loop).
                self.x_new
                    .par_chunks_mut(NODE_PIECE)
                    .zip(self.v_new.par_chunks_mut(NODE_PIECE))
                    .enumerate()
                    .for_each(|(c, (xn, vn))| {
                        let r = c * NODE_PIECE..c * NODE_PIECE + xn.len();
                        let old = x[r.clone()].iter().zip(&v[r.clone()]);
                        let load = f_ext[r.clone()].iter().zip(&f_int[r.clone()]);
                        for ((((xn, vn), (x, v)), (fe, fi)), m) in
                            xn.iter_mut().zip(vn).zip(old).zip(load).zip(&m[r])
                        {
                            let a = (fe - fi) / *m;
                            *vn = (v * c1 + a * dt_avg) * c2;
                            *xn = x + *vn * h;
                        }
                    });
            }
            self.lap(Pass::Update);
            // Prescribed components.
            for (j, c) in self.constraints.list.iter().enumerate() {
                let (i, k) = (c.node as usize, c.component as usize);
                self.prescribed[j] = Constraints::position(model, c, state.x[i][k], state.time, h);
                self.x_new[i][k] = self.prescribed[j];
                self.v_new[i][k] = (self.x_new[i][k] - state.x[i][k]) / h;
            }
            self.lap(Pass::BoundaryConditions);
            if let Some(contact) = &mut self.contact {
                contact
                    .enforce_step(
                        &mut self.x_new,
                        &mut self.v_new,
                        &self.mass,
                        &self.constraints.movable,
                        &StepTimes {
                            t_new,
                            dt: h,
                            dt_mean: dt_avg,
                            damping,
                        },
                    )
                    .map_err(|fault| RunError::ContactFault {
                        step: state.step + 1,
                        time: t_new,
                        fault,
                    })?;
                for (touched, f) in self.tool_touched.iter_mut().zip(&contact.tool_force) {
                    *touched |= *f != 0.0;
                }
                if let Some(p) = &mut self.profiler {
                    p.lap(Pass::Contact);
                }
                // A partly constrained node keeps its prescribed components;
                // its constraint takes the contact force there.
                for (j, c) in self.constraints.list.iter().enumerate() {
                    let (i, k) = (c.node as usize, c.component as usize);
                    if self.constraints.movable[i] {
                        self.x_new[i][k] = self.prescribed[j];
                        self.v_new[i][k] = (self.prescribed[j] - state.x[i][k]) / h;
                    }
                }
                // At the positions the next force pass sees.
                if let Some(confinement) = &mut self.confinement {
                    energy.confinement_work += confinement.update(
                        model,
                        contact,
                        &self.x_new,
                        &mut self.forces.truss_clearance,
                    );
                }
                self.lap(Pass::BoundaryConditions);
            }
            // Work of step n over the centred increment (x_{n+1} − x_{n−1})/2.
            {
                let (x, v, m) = (&state.x, &state.v, &self.mass);
                let (xn, vn, fi, fe) = (&self.x_new, &self.v_new, &self.forces.f_int, &self.f_ext);
                let constrained = &self.constraints.constrained;
                let f_c = self.contact.as_ref().map(|c| &c.force);
                // Mass-proportional damping at the mid-step velocity.
                let damping_force = |i: usize| (v[i] + vn[i]) * 0.5 * (damping * m[i]);
                let terms = |i: usize| -> [f64; 5] {
                    let dx = v[i] * (0.5 * dt_prev) + (xn[i] - x[i]) * 0.5;
                    let v_mid = (v[i] + vn[i]) * 0.5;
                    let damp = damping_force(i);
                    let mut w_bc = 0.0;
                    if constrained[i].iter().any(|&c| c) && dt_avg > 0.0 {
                        // The force the constraint applies: m·a − (f_ext − f_int − damping).
                        let contact = f_c.map_or(Vector3::zeros(), |f| f[i]);
                        let inertia = (vn[i] - v[i]) * (m[i] / dt_avg);
                        let r = inertia - (fe[i] - fi[i] - damp + contact);
                        // At the first step the velocity changes over the
                        // half step from t₀: its inertia works over the mean
                        // velocity there, ½m(v½² − v₀²), not over the step's
                        // first half displacement (twice that from rest).
                        let dx_inertia = if dt_prev > 0.0 { dx } else { v_mid * dt_avg };
                        for k in 0..3 {
                            if constrained[i][k] {
                                w_bc += r[k] * dx[k] + inertia[k] * (dx_inertia[k] - dx[k]);
                            }
                        }
                    }
                    let w_c = f_c.map_or(0.0, |f| f[i].dot(&dx));
                    [fi[i].dot(&dx), fe[i].dot(&dx), damp.dot(&dx), w_bc, w_c]
                };
                let [mut w_int, mut w_ext, mut w_damp, w_bc, mut w_c] =
                    chunked_sums_into(n, terms, &mut self.work_partials);
                // A shift s of the ply pass moved a node with no change of
                // velocity: the centred increment above holds half of it
                // this step and none the next (v excludes it), and the
                // contact force, which acts over the motion, did no work
                // along it. So the node's forces work over all of s, and
                // the contact's work along it is what moving the node
                // against them took, (f_int − f_ext + damping)·s: the
                // balance stays closed. (Counted as f_c·s/2, one shift in
                // the four-ply hemisphere put 6 mJ into the balance error
                // in a step, 2 % of the largest energy, and the guard
                // stopped a sound run.)
                if let Some(contact) = &self.contact {
                    for &(i, s) in contact.position_shifts() {
                        let i = i as usize;
                        let s = Vector3::from_fn(|k, _| if constrained[i][k] { 0.0 } else { s[k] });
                        let damp = damping_force(i);
                        w_int += fi[i].dot(&s) * 0.5;
                        w_ext += fe[i].dot(&s) * 0.5;
                        w_damp += damp.dot(&s) * 0.5;
                        w_c += (fi[i] - fe[i] + damp).dot(&s) - contact.force[i].dot(&s) * 0.5;
                    }
                }
                energy.contact_work += w_c;
                energy.internal_work += w_int;
                energy.external_work += w_ext;
                energy.damping += w_damp;
                energy.boundary_work += w_bc;
            }
            self.lap(Pass::Works);
            if !model.loads.is_empty() || !self.pressure.is_empty() {
                shared::external_forces(model, t_new, &mut self.f_ext);
                // Follower pressures at n+1, on the positions of n+1.
                self.pressure
                    .add_into(model, &self.x_new, t_new, &mut self.f_ext);
                self.lap(Pass::Loads);
            }
            // Forces at n+1, the history advanced to n+1 where it lies (one
            // array streamed, not two): from here to the commit `state`
            // holds x at n with the history at n+1 (partly, if the pass
            // fails), so every failure below returns an error, and `run`
            // puts the guard's last good state back whole.
            self.forces.evaluate_in_place(
                model,
                &self.x_new,
                Some((&self.v_new, &self.truss_damping)),
                &mut state.history,
                h,
                state.step + 1,
                t_new,
                self.profiler.as_mut(),
            )?;
            // The lowest such node whatever the split; in parallel, as a
            // sequential scan was a serial part of a large model's step.
            let (x_new, f_int) = (&self.x_new, &self.forces.f_int);
            if let Some(i) = shared::first_node(n, |i| {
                !(x_new[i].iter().all(|v| v.is_finite()) && f_int[i].iter().all(|v| v.is_finite()))
            }) {
                return Err(RunError::NonFinite {
                    step: state.step + 1,
                    time: t_new,
                    node: i,
                    what: "position or force",
                });
            }
            // Commit.
            std::mem::swap(&mut state.x, &mut self.x_new);
            std::mem::swap(&mut state.v, &mut self.v_new);
            state.time = t_new;
            state.step += 1;
            steps += 1;
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
                let travel = contact.tool_state.iter().map(|t| t.displacement);
                self.guard.tools(model, travel).map_err(unstable)?;
            }
            self.lap(Pass::Checks);
            dt_prev = h;
            dt_min = dt_min.min(h);
            dt_max = dt_max.max(h);
            if self
                .settings
                .checkpoint_every
                .is_some_and(|k| state.step % k.max(1) == 0)
            {
                let driver = DriverState {
                    dt,
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
                    implicit: None,
                    truss_clearance: Confinement::stored(&self.forces.truss_clearance),
                    plies: self
                        .contact
                        .as_ref()
                        .and_then(ExplicitContact::plies)
                        .map(drape_contact::PlyContact::carry),
                };
                observer.checkpoint(state, &driver);
                self.lap(Pass::Output);
            }
            let at_end = end - state.time <= 1e-6 * dt;
            let at_frame = state.time >= next_frame as f64 * frame_dt * (1.0 - 1e-12);
            let at_check = state.time >= next_check * check_dt * (1.0 - 1e-12);
            if at_frame || at_end || at_check {
                let report = self.energies_at(state, &energy, kinetic0, h);
                self.lap(Pass::Energies);
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
                // Before the frame is published or kept as the last good
                // state.
                self.check_plies(state)?;
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
                        contact: self.contact.as_ref().map(ExplicitContact::view),
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
                    dt: h,
                    increment: None,
                };
                if observer.progress(&p) == Control::Stop && !at_end {
                    stopped = true;
                    break;
                }
            }
            self.lap(Pass::Output);
        }
        self.end_profile(steps);
        let energy = self.energies_at(state, &energy, kinetic0, dt_prev);
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
            // Completed only with the blank outside every tool.
            let u: Vec<f64> = self.contact.as_ref().map_or_else(Vec::new, |c| {
                c.tool_state.iter().map(|t| t.displacement).collect()
            });
            crate::completion::check_at_end(model, state, &u, None)?;
        }
        if let Some(w) = self
            .contact
            .as_ref()
            .and_then(|c| c.plies())
            .and_then(|p| crate::ply_check::overlap_warning(model, p))
        {
            self.warnings.push(w);
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
            steps,
            dt_range: (dt_min, dt_max),
            added_mass: self.added_mass,
            total_mass: self.mass.iter().sum(),
            energy,
            stopped,
            wall_seconds: started.elapsed().as_secs_f64(),
            threads: rayon::current_num_threads(),
            warnings: self.warnings.clone(),
            implicit: None,
        })
    }

    /// The plies' overlap check ([`crate::ply_check`]) at `state`, for a
    /// laminate.
    fn check_plies(&mut self, state: &State) -> Result<(), RunError> {
        let model = self.model;
        match self.contact.as_mut().and_then(|c| c.plies_mut()) {
            Some(plies) => crate::ply_check::check_plies(
                model,
                plies,
                state,
                crate::ply_check::ply_overlap_tolerance(model),
            ),
            None => Ok(()),
        }
    }

    /// The energies at step n+1: the works accumulated to n+½ plus the
    /// half increment (x_{n+1} − x_n)/2 at the forces of n+1 (reactions
    /// taken quasi-static there), so that they match the full-step kinetic
    /// energy to O(Δt²).
    fn energies_at(&mut self, state: &State, acc: &Energies, kinetic0: f64, h: f64) -> Energies {
        let n = self.model.node_count();
        let damping = self.settings.damping;
        let mut partials = std::mem::take(&mut self.energy_partials);
        let this = &*self;
        let no_contact = Vector3::zeros();
        let terms = |i: usize| {
            let last_contact = this.contact.as_ref().map_or(&no_contact, |c| &c.force[i]);
            node_energy_terms(
                &NodeAtStep {
                    v: &state.v[i],
                    f_int: &this.forces.f_int[i],
                    f_ext: &this.f_ext[i],
                    last_contact,
                    mass: this.mass[i],
                    constrained: this.constraints.constrained[i],
                },
                damping,
                h,
            )
        };
        let [kinetic, w_int, w_ext, w_damp, w_bc, w_c] = chunked_sums_into(n, terms, &mut partials);
        self.energy_partials = partials;
        let mut e = *acc;
        e.kinetic = kinetic;
        e.internal_work += w_int;
        e.external_work += w_ext;
        e.damping += w_damp;
        e.boundary_work += w_bc;
        e.contact_work += w_c;
        e.friction_dissipation = self
            .contact
            .as_ref()
            .map_or(0.0, |c| c.friction_dissipation);
        e.strain = shared::strain_energy_confined(self.model, state, &self.forces.truss_clearance);
        e.viscous = e.internal_work + e.confinement_work - e.strain;
        e.balance_error = e.kinetic + e.internal_work + e.damping
            - e.external_work
            - e.boundary_work
            - e.contact_work
            - kinetic0;
        e
    }

    /// Reactions at the constrained components, quasi-static part
    /// f_int − f_ext (the inertia of a prescribed node is the user's motion).
    /// Not the tools' force on a constrained node: along a prescribed
    /// component the contact pass's friction is overwritten by the motion
    /// each step, and what it records alternates between stick and slip
    /// (a pinched strip dragged along x by all its nodes: 4.0, 0.16, 0.31,
    /// 3.4 N at successive frames for 2μF = 4 N), so it is left out.
    fn compute_reactions(&mut self) {
        for r in self.reactions.iter_mut() {
            *r = Vector3::zeros();
        }
        for c in &self.constraints.list {
            let (i, k) = (c.node as usize, c.component as usize);
            self.reactions[i][k] = self.forces.f_int[i][k] - self.f_ext[i][k];
        }
    }
}
