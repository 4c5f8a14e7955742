//! The instability guard: what a stable run of a scene cannot do, checked
//! while it runs, so that a diverging run stops as failed with a diagnosis
//! instead of finishing with numbers from an exploded mesh; the start-up
//! checks of a scene's tools; and the energy floor below which a balance
//! error is noise.
//!
//! For any driver: [`Guard::nodes`] and [`Guard::tools`] look at one
//! state (the explicit driver calls them every step, an implicit one would
//! per increment), [`Guard::energy`] at one energy balance (at output
//! frames), and [`Guard::accept`] remembers the last frame, which passed,
//! to which [`Guard::fall_back`] returns a failed run, so that what a
//! failed run reports was never exploded.
//!
//! The bounds are loose on purpose: they catch a run that has lost its
//! physics, not a run that is merely inaccurate, and say which bound and
//! by how much.
//!
//! - **Speed**: a node faster than [`GuardSettings::speed_factor`] (100) ×
//!   the scene's speed, the largest of: the prescribed motions' peak
//!   speeds (tools and boundary conditions), the initial velocities,
//!   gravity's |g|·T, the loads' Σ|F|/M·T on the blank as a rigid body,
//!   the speed a spring's energy at the start gives its node, and the
//!   blank's size over the run time L/T.
//! - **Reach**: a node outside the blank's box grown by the *reach* — the
//!   blank's diagonal + the largest of the tools' travel, the prescribed
//!   displacements, the loads' ½Σ|F|/M·T² and twice a spring's distance to
//!   its anchor + a free fall ½|g|T² + the initial velocities × T (+ what
//!   force-driven tools have travelled so far) — is nowhere a tool, a
//!   boundary condition, a load, a spring or gravity can bring it. A force-driven tool that
//!   travels further than the reach missed the blank or broke through it.
//! - **Energy balance**: |balance error| above
//!   [`GuardSettings::max_energy_error`] (5 %) of the largest energy term,
//!   or of [`energy_floor`] when all terms are below it. A sound run's
//!   error stays bounded, at 1e-9…1e-5 in quasi-static runs but up to a
//!   few per cent early in a violent one (the measured energy of central
//!   differences oscillates with the energy in the highest modes).
//! - **Energy growth**: an instability grows exponentially, and so does
//!   the balance error it causes, faster than the energies, long before it
//!   is large: from a tenth of the run time on, a relative error above
//!   1e-3 that has grown by [`GROWTH_EACH`] at each of the last
//!   [`GROWTH_CHECKS`] checks and [`GROWTH_TOTAL`]-fold over them, from
//!   above round-off ([`GROWTH_BASE`]), stops the run. The bias extension that diverged at 0.85 of its linear limit had
//!   a relative error of 2.5e-5, 2.3e-4, 1.7e-3, 8.6e-3 at 10, 20, 30, 40 %
//!   of its run; a sound run's relative error stays flat or wanders, and an
//!   impact makes it jump once, not grow steadily.
//! - **Quasi-static**: for a scene that declares itself quasi-static, a
//!   kinetic energy above [`GuardSettings::max_kinetic_ratio`] (default 1,
//!   far above the few per cent of a quasi-static run) × the internal
//!   work, from half the run time on ([`QUASI_STATIC_FROM`]) and once the
//!   internal work is above 100 × the floor: the start of any loading from
//!   rest is dynamic (under a smooth step E_kin/E_int grows like 1/t² as
//!   t → 0, the moving clamp's kinetic energy included; the shipped bias
//!   extension has 1.3 at a tenth of its run, 0.12 at 30 %, and a faster
//!   one 1.2 at 30 %).
//!
//! The energy checks run at every output frame and at least
//! [`MIN_ENERGY_CHECKS`] times a run, and on the last state of a run
//! stopped early; the kinematic ones at every step.
//!
//! What it is not: no stability estimate (the drivers), no element checks
//! (an element that folds is an element error).

use drape_contact::{Amplitude, ToolMotion};
use drape_model::{Model, Motion, State};
use nalgebra::Vector3;
use rayon::prelude::*;

use crate::Energies;

/// The strain below which a model's energies are noise: the floor of the
/// balance error is the strain energy of the blank stretched by this much
/// in every direction (see [`energy_floor`]).
pub const NOISE_STRAIN: f64 = 1e-6;

/// Samples of a motion over the run, for its peak speed and travel.
const MOTION_SAMPLES: usize = 1000;

/// What the guard checks, and its bounds.
#[derive(Debug, Clone, PartialEq)]
pub struct GuardSettings {
    /// Off: only non-finite values and failing elements stop a run.
    pub enabled: bool,
    /// A node faster than this many times the scene's speed is unstable.
    pub speed_factor: f64,
    /// Stop when |energy balance error| exceeds this fraction of the
    /// largest energy term (or of the [`energy_floor`]), checked at frames.
    pub max_energy_error: Option<f64>,
    /// For a scene declared quasi-static: stop when E_kin exceeds this many
    /// times the internal work (checked at frames).
    pub max_kinetic_ratio: Option<f64>,
}

impl Default for GuardSettings {
    fn default() -> Self {
        Self {
            enabled: true,
            speed_factor: 100.0,
            max_energy_error: Some(0.05),
            max_kinetic_ratio: None,
        }
    }
}

/// The bound on E_kin/E_int of a scene declared quasi-static, unless it
/// says otherwise: kinetic energy above the internal work is far outside a
/// quasi-static run (whose rule of thumb is a few per cent).
pub const QUASI_STATIC_KINETIC_RATIO: f64 = 1.0;

/// Checks over which the relative balance error must grow steadily (see
/// the module docs).
pub const GROWTH_CHECKS: usize = 3;
/// The growth of the relative balance error at each of those checks…
pub const GROWTH_EACH: f64 = 1.5;
/// …and over all of them.
pub const GROWTH_TOTAL: f64 = 10.0;
/// The smallest relative balance error whose growth stops a run.
pub const GROWTH_FROM_ERROR: f64 = 1e-3;
/// The smallest relative error a growth is measured from. Below it the
/// error is the sums' round-off, and a rise from round-off to a finite
/// error is the start of one (a first impact, measured on the tray's
/// coarse run: 1.9e-15, 3.1e-15, 2.9e-5, 5.5e-3 at the first four checks,
/// then falling), not an instability, which is seen from its second
/// check above round-off on.
pub const GROWTH_BASE: f64 = 1e-12;
/// The fraction of the run time from which the growth check holds: the
/// start of a run grows its error from nothing.
pub const GROWTH_FROM: f64 = 0.1;

/// The fraction of the run time from which the quasi-static bound holds.
pub const QUASI_STATIC_FROM: f64 = 0.5;

/// The energy checks a run gets at least, evenly spaced, however few
/// frames it writes.
pub const MIN_ENERGY_CHECKS: usize = 20;

/// What the guard found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Instability {
    /// A node moves absurdly fast for the scene.
    #[error(
        "node {node} at ({:.2}, {:.2}, {:.2}) mm moves at {speed:.3e} mm/s, more than {factor}× the scene's speed {scale:.3e} mm/s \
         (its fastest prescribed motion, free fall, or blank size per run time){}",
        position[0], position[1], position[2], near_text(near)
    )]
    Speed {
        /// The node.
        node: usize,
        /// Where it is (mm).
        position: [f64; 3],
        /// The nearest tool and the place on it (see [`Instability::near_tools`]).
        near: Option<Box<drape_contact::ToolPlace>>,
        /// Its speed (mm/s).
        speed: f64,
        /// The scene's speed (mm/s).
        scale: f64,
        /// The factor allowed.
        factor: f64,
    },
    /// A node has left everything the scene can reach.
    #[error(
        "node {node} is at ({:.1}, {:.1}, {:.1}) mm, {beyond:.3e} mm outside everything the scene reaches \
         (the blank grown by {reach:.1} mm: its size, the tools' travel, prescribed displacements, free fall){}",
        position[0], position[1], position[2], near_text(near)
    )]
    Outside {
        /// The node.
        node: usize,
        /// The nearest tool and the place on it (see [`Instability::near_tools`]).
        near: Option<Box<drape_contact::ToolPlace>>,
        /// Where it is (mm).
        position: [f64; 3],
        /// How far outside the reachable box (mm).
        beyond: f64,
        /// The reach (mm).
        reach: f64,
    },
    /// A force-driven tool has travelled beyond the blank's reach.
    #[error(
        "force-driven tool `{tool}` has travelled {travel:.3e} mm along its axis, beyond anything the blank \
         reaches ({reach:.1} mm): it missed the blank or went through it"
    )]
    ToolAway {
        /// The tool's name.
        tool: String,
        /// Its displacement (mm).
        travel: f64,
        /// The reach (mm).
        reach: f64,
    },
    /// The energy balance error grows exponentially.
    #[error(
        "the energy balance error grows exponentially: ×{:.3e} over the last {GROWTH_CHECKS} checks \
         (×{:.2e}, ×{:.2e}, ×{:.2e}), now {relative:.3e} of the largest energy",
        growth.iter().product::<f64>(), growth[0], growth[1], growth[2]
    )]
    EnergyGrowth {
        /// |error| over the scale.
        relative: f64,
        /// The growth factors of the relative error at the last checks.
        growth: [f64; GROWTH_CHECKS],
    },
    /// Energy appears from nowhere.
    #[error(
        "energy balance error {relative:.3e} exceeds {bound:.3e} of the largest energy ({scale:.3e} mJ)"
    )]
    EnergyBalance {
        /// |error| over the scale.
        relative: f64,
        /// The bound.
        bound: f64,
        /// The largest energy term, or the floor (mJ).
        scale: f64,
    },
    /// A scene declared quasi-static is dominated by inertia.
    #[error(
        "E_kin/E_int = {ratio:.3e} exceeds {bound} in a scene declared quasi-static: inertia dominates \
         (the run is unstable, or the loading is too fast to be quasi-static)"
    )]
    NotQuasiStatic {
        /// E_kin/E_int.
        ratio: f64,
        /// The bound.
        bound: f64,
    },
}

/// The nearest tool, as a message ends with it.
fn near_text(near: &Option<Box<drape_contact::ToolPlace>>) -> String {
    near.as_ref()
        .map_or_else(String::new, |p| format!("; nearest tool: {p}"))
}

impl Instability {
    /// The same finding with the nearest of `tools` (each at its
    /// displacement) to the node it names, at `x`: a node that runs away
    /// next to a tool, at its open rim above all, says where.
    pub fn near_tools(
        mut self,
        tools: &[drape_contact::Tool],
        displacement: &[f64],
        x: &[Vector3<f64>],
    ) -> Self {
        if let Self::Speed { node, near, .. } | Self::Outside { node, near, .. } = &mut self {
            if let Some(p) = x.get(*node) {
                *near = drape_contact::ToolPlace::nearest(tools, displacement, p).map(Box::new);
            }
        }
        self
    }
}

/// The largest |a(t)| of an amplitude.
fn peak_value(a: &Amplitude) -> f64 {
    match a {
        Amplitude::Table { points } => points.iter().map(|p| p[1].abs()).fold(0.0, f64::max),
        _ => 1.0,
    }
}

/// The largest |da/dt| of an amplitude (1/s); a constant one jumps at the
/// start, which is no speed of a motion.
fn peak_rate(a: &Amplitude) -> f64 {
    match a {
        Amplitude::Constant => 0.0,
        Amplitude::Ramp { duration } => 1.0 / duration,
        // ξ³(10 − 15ξ + 6ξ²) is steepest at ξ = ½: 30ξ²(1 − ξ)² = 15/8.
        Amplitude::SmoothStep { duration } => 1.875 / duration,
        Amplitude::Table { points } => points
            .windows(2)
            .map(|w| ((w[1][1] - w[0][1]) / (w[1][0] - w[0][0])).abs())
            .fold(0.0, f64::max),
    }
}

/// The energy below which a model's balance is noise: the strain energy
/// A·ε²·(E_f·t_f + E_m·h_m/(1 − ν_m)) of its blank (every membrane, area A,
/// both yarn families of thickness t_f each and the resin) stretched by
/// ε = [`NOISE_STRAIN`] in every direction. The balance error is measured
/// against the largest energy term or this floor, whichever is larger, so
/// that a blank on which nothing acts reports no error of noise over noise.
pub fn energy_floor(model: &Model) -> f64 {
    let stiffness_area: f64 = model
        .membranes
        .iter()
        .map(|b| {
            let m = &b.section.material;
            let per_area = m.fibre.modulus * m.family_thickness()
                + m.resin.young * m.resin_thickness() / (1.0 - m.resin.poisson);
            per_area * (0..b.len()).map(|e| b.element_area(e)).sum::<f64>()
        })
        .sum();
    stiffness_area * NOISE_STRAIN * NOISE_STRAIN
}

/// |balance error| over the largest energy term or `floor`, whichever is
/// larger.
pub fn relative_balance_error(energy: &Energies, floor: f64) -> f64 {
    energy.balance_error.abs() / energy_scale(energy).max(floor)
}

/// The implicit driver's Newton residual work
/// ([`Energies::residual_work`]) over the scale of
/// [`relative_balance_error`], with its sign.
pub fn relative_residual_work(energy: &Energies, floor: f64) -> f64 {
    energy.residual_work / energy_scale(energy).max(floor)
}

fn energy_scale(e: &Energies) -> f64 {
    [
        e.kinetic,
        e.internal_work.abs(),
        e.external_work.abs(),
        e.boundary_work.abs(),
        e.contact_work.abs(),
    ]
    .into_iter()
    .fold(0.0, f64::max)
}

/// The instability guard of one run.
#[derive(Debug, Clone)]
pub struct Guard {
    settings: GuardSettings,
    /// The scene's speed without the initial velocities (mm/s).
    prescribed_speed: f64,
    /// The scene's speed (mm/s).
    speed_scale: f64,
    /// (speed_factor · speed_scale)².
    speed_limit_squared: f64,
    /// The blank's reference box.
    low: Vector3<f64>,
    high: Vector3<f64>,
    /// The reach without the force-driven tools' travel and the initial
    /// velocities (mm).
    static_reach: f64,
    end_time: f64,
    /// The reach (mm).
    reach: f64,
    floor: f64,
    /// The relative balance errors at the last energy checks, oldest
    /// first.
    previous_errors: [f64; GROWTH_CHECKS],
    /// The last state that passed, and whether there is one.
    last_good: State,
    has_last_good: bool,
}

impl Guard {
    /// The guard of `model` run to `end_time`.
    pub fn new(model: &Model, settings: GuardSettings, end_time: f64) -> Self {
        let t = end_time.max(0.0);
        let (mut low, mut high) = (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        );
        for p in &model.x0 {
            low = low.inf(p);
            high = high.sup(p);
        }
        let size = if model.x0.is_empty() {
            0.0
        } else {
            (high - low).norm()
        };
        let times = || (0..=MOTION_SAMPLES).map(move |k| t * k as f64 / MOTION_SAMPLES as f64);
        let (mut speed, mut travel) = (0.0f64, 0.0f64);
        for tool in &model.tools {
            if let ToolMotion::Displacement {
                distance,
                amplitude,
                ..
            } = &tool.motion
            {
                speed = speed.max(distance.abs() * peak_rate(amplitude));
                travel = travel.max(distance.abs() * peak_value(amplitude));
            }
        }
        for bc in &model.boundary {
            match &bc.motion {
                Motion::Fixed => {}
                Motion::Velocity { value, amplitude } => {
                    speed = speed.max(value.norm() * peak_value(amplitude));
                    // Travel: at most the peak speed over the run.
                    travel = travel.max(value.norm() * peak_value(amplitude) * t);
                }
                Motion::Displacement { value, amplitude } => {
                    speed = speed.max(value.norm() * peak_rate(amplitude));
                    travel = travel.max(value.norm() * peak_value(amplitude));
                }
                Motion::Trajectory(_) => {
                    // A function of time only known by its values: sampled.
                    for &n in &bc.nodes {
                        let x0 = model.x0[n as usize];
                        let u = |time| bc.displacement(&x0, time).unwrap_or_default();
                        let mut previous = (0.0, u(0.0));
                        for time in times() {
                            let value = u(time);
                            travel = travel.max(value.norm());
                            if time > previous.0 {
                                speed =
                                    speed.max((value - previous.1).norm() / (time - previous.0));
                            }
                            previous = (time, value);
                        }
                    }
                }
            }
        }
        // The loads accelerate the blank as a rigid body at most at
        // Σ|F|/M over the run.
        let total_mass: f64 = model.mass.iter().sum();
        let total_load: f64 = model
            .loads
            .iter()
            .map(|l| l.force.norm() * peak_value(&l.amplitude) * l.nodes.len() as f64)
            .sum::<f64>()
            // A pressure pushes with at most p·(its elements' area): twice
            // the reference area bounds what a forming run stretches them to.
            + model
                .pressure
                .iter()
                .map(|p| p.value.abs() * peak_value(&p.amplitude) * 2.0 * p.area(&model.x0))
                .sum::<f64>();
        let a = total_load / total_mass;
        if a.is_finite() {
            speed = speed.max(a * t);
            travel = travel.max(0.5 * a * t * t);
        }
        // A spring may throw its node to the far side of its anchor, as fast
        // as its energy at the start allows.
        for b in &model.springs {
            for (e, &n) in b.nodes.iter().enumerate() {
                let distance = (b.anchors[e] - model.x0[n as usize]).norm();
                let energy = b.table.energy(distance - b.rest_length[e]).abs();
                travel = travel.max(2.0 * (distance + b.rest_length[e]));
                speed = speed.max((2.0 * energy / model.mass[n as usize]).sqrt());
            }
        }
        let g = model.gravity.norm();
        let prescribed_speed = speed.max(g * t).max(if t > 0.0 { size / t } else { 0.0 });
        let static_reach = size + travel + 0.5 * g * t * t;
        let mut guard = Self {
            speed_limit_squared: 0.0,
            speed_scale: prescribed_speed,
            prescribed_speed,
            low,
            high,
            static_reach,
            end_time: t,
            reach: static_reach,
            floor: energy_floor(model),
            previous_errors: [f64::NAN; GROWTH_CHECKS],
            settings,
            last_good: State {
                time: 0.0,
                step: 0,
                x: Vec::new(),
                v: Vec::new(),
                history: Vec::new(),
            },
            has_last_good: false,
        };
        guard.set_speed_scale(prescribed_speed);
        guard
    }

    fn set_speed_scale(&mut self, scale: f64) {
        self.speed_scale = scale;
        let limit = self.settings.speed_factor * scale;
        self.speed_limit_squared = limit * limit;
    }

    /// The settings.
    pub fn settings(&self) -> &GuardSettings {
        &self.settings
    }

    /// The energy floor of the model ([`energy_floor`]).
    pub fn floor(&self) -> f64 {
        self.floor
    }

    /// The reach (mm): how far outside the blank's reference box a node
    /// may go (see the module docs).
    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// The scene's speed (mm/s) that the speed bound multiplies.
    pub fn speed_scale(&self) -> f64 {
        self.speed_scale
    }

    /// Starts (or resumes) a run at `state`: its velocities join the
    /// scene's speed and reach, and it is the first good state.
    pub fn begin(&mut self, state: &State) {
        let v0 = state.v.iter().map(|v| v.norm()).fold(0.0, f64::max);
        self.set_speed_scale(self.prescribed_speed.max(v0));
        self.static_reach += v0 * (self.end_time - state.time).max(0.0);
        self.reach = self.static_reach;
        self.accept(state);
    }

    /// Checks every node's position and velocity; `movable` tells which
    /// nodes have a free component (the others' motion is the user's: their
    /// speed is not checked). The first offending node, by index.
    pub fn nodes(
        &self,
        x: &[Vector3<f64>],
        v: &[Vector3<f64>],
        movable: &[bool],
    ) -> Result<(), Instability> {
        if !self.settings.enabled {
            return Ok(());
        }
        let (low, high) = (
            self.low.add_scalar(-self.reach),
            self.high.add_scalar(self.reach),
        );
        let limit = self.speed_limit_squared;
        // In pieces of 8 192 nodes: a small model's check stays on one
        // thread, a large model's is no serial part of its step.
        let bad = crate::shared::first_node(x.len(), |i| {
            let p = &x[i];
            let outside = (0..3).any(|k| p[k] < low[k] || p[k] > high[k]);
            outside || (movable[i] && v[i].norm_squared() > limit)
        });
        let Some(i) = bad else {
            return Ok(());
        };
        let p = x[i];
        let beyond = (0..3)
            .map(|k| (low[k] - p[k]).max(p[k] - high[k]))
            .fold(f64::NEG_INFINITY, f64::max);
        if beyond > 0.0 {
            Err(Instability::Outside {
                node: i,
                near: None,
                position: p.into(),
                beyond,
                reach: self.reach,
            })
        } else {
            Err(Instability::Speed {
                node: i,
                position: p.into(),
                near: None,
                speed: v[i].norm(),
                scale: self.speed_scale,
                factor: self.settings.speed_factor,
            })
        }
    }

    /// Checks the force-driven tools' travel (`displacement` per tool of
    /// `model`), and lets the blank's reach grow with it.
    pub fn tools(
        &mut self,
        model: &Model,
        displacement: impl IntoIterator<Item = f64>,
    ) -> Result<(), Instability> {
        let mut travelled = 0.0f64;
        for (tool, u) in model.tools.iter().zip(displacement) {
            if tool.is_force_driven() {
                if self.settings.enabled && u.abs() > self.static_reach {
                    return Err(Instability::ToolAway {
                        tool: tool.name.clone(),
                        travel: u.abs(),
                        reach: self.static_reach,
                    });
                }
                travelled = travelled.max(u.abs());
            }
        }
        self.reach = self.static_reach + travelled;
        Ok(())
    }

    /// Checks the energy balance `energy` at time `time` (and remembers
    /// its error, for the growth check).
    pub fn energy(&mut self, energy: &Energies, time: f64) -> Result<(), Instability> {
        let relative = relative_balance_error(energy, self.floor);
        let error = relative;
        let previous = self.previous_errors;
        self.previous_errors.rotate_left(1);
        self.previous_errors[GROWTH_CHECKS - 1] = error;
        let mut growth = [0.0; GROWTH_CHECKS];
        for k in 0..GROWTH_CHECKS {
            let next = if k + 1 < GROWTH_CHECKS {
                previous[k + 1]
            } else {
                error
            };
            growth[k] = next / previous[k];
        }
        // NaN (fewer checks so far) and 0/0 fail these comparisons.
        let steady = previous[0] >= GROWTH_BASE
            && growth.iter().all(|&g| g >= GROWTH_EACH)
            && growth.iter().product::<f64>() >= GROWTH_TOTAL;
        if self.settings.enabled
            && time >= GROWTH_FROM * self.end_time
            && relative > GROWTH_FROM_ERROR
            && steady
        {
            return Err(Instability::EnergyGrowth { relative, growth });
        }
        if let Some(bound) = self.settings.max_energy_error {
            if relative > bound {
                return Err(Instability::EnergyBalance {
                    relative,
                    bound,
                    scale: energy_scale(energy).max(self.floor),
                });
            }
        }
        if !self.settings.enabled {
            return Ok(());
        }
        if let Some(bound) = self.settings.max_kinetic_ratio {
            let internal = energy.internal_work.abs();
            if time >= QUASI_STATIC_FROM * self.end_time
                && internal > 100.0 * self.floor
                && energy.kinetic > bound * internal
            {
                return Err(Instability::NotQuasiStatic {
                    ratio: energy.kinetic / internal,
                    bound,
                });
            }
        }
        Ok(())
    }

    /// Remembers `state` as the last good one.
    pub fn accept(&mut self, state: &State) {
        self.last_good.clone_from(state);
        self.has_last_good = true;
    }

    /// The last state that passed, if any.
    pub fn last_good(&self) -> Option<&State> {
        self.has_last_good.then_some(&self.last_good)
    }

    /// After a run failed (the guard's finding, a collapsed element, a
    /// non-finite value): puts the last good state back into `state`, so
    /// that what the run reports is a state that passed every check — the
    /// steps before a failure are already on their way to it. Returns
    /// whether there was one.
    pub fn fall_back(&self, state: &mut State) -> bool {
        match self.last_good() {
            Some(good) => {
                state.clone_from(good);
                true
            }
            None => false,
        }
    }
}

/// Nodes listed in a message, at most.
const NODES_NAMED: usize = 5;

fn node_list(nodes: &[usize]) -> String {
    let named: Vec<String> = nodes
        .iter()
        .take(NODES_NAMED)
        .map(usize::to_string)
        .collect();
    if nodes.len() > NODES_NAMED {
        format!("{} nodes ({}, …)", nodes.len(), named.join(", "))
    } else if nodes.len() == 1 {
        format!("node {}", named[0])
    } else {
        format!("{} nodes ({})", nodes.len(), named.join(", "))
    }
}

/// How far from a tool each node's mid-surface must start, node by node:
/// its half thickness for a single ply, and in a stack its own half
/// thickness plus the plies between it and the tool: those below it for a
/// tool under the stack (a mould, a die, a punch from below), those above
/// it for a tool over the stack (a blank holder, a punch from above). A
/// tool is under the stack where its outward normal at the node's closest
/// point leans up the stack ([`Model::stack_up`]).
struct StartClearance {
    /// Per node: (clearance from a tool below, from a tool above), mm.
    clearance: Vec<(f64, f64)>,
    up: Vector3<f64>,
}

impl StartClearance {
    fn of(model: &Model) -> Self {
        let offset = model.contact_offset;
        let mut clearance = vec![(offset, offset); model.node_count()];
        let total: f64 = model.plies.iter().map(|p| p.thickness).sum();
        let mut below = 0.0;
        for ply in &model.plies {
            let half = 0.5 * ply.thickness;
            let above = total - below - ply.thickness;
            for node in ply.nodes.clone() {
                clearance[node as usize] = (below + half, above + half);
            }
            below += ply.thickness;
        }
        Self {
            clearance,
            up: model.stack_up(),
        }
    }

    /// Node `i`'s clearance from a tool whose outward normal there is
    /// `normal`.
    fn from(&self, i: usize, normal: &Vector3<f64>) -> f64 {
        let (below, above) = self.clearance[i];
        if normal.dot(&self.up) < 0.0 {
            above
        } else {
            below
        }
    }
}

/// The nodes a blank at `x` has closer to `tool` (at its start position)
/// than `clearance` says they must start, less a hundredth of the offset
/// of round-off, each with its shortfall (mm) and the tool's outward normal
/// there; those behind a tool's surface are the start-up check's error,
/// not these.
fn too_close(
    model: &Model,
    tool: &drape_contact::Tool,
    x: &[Vector3<f64>],
    clearance: &StartClearance,
) -> Vec<(usize, f64, Vector3<f64>)> {
    let slack = 0.01 * model.contact_offset;
    let u0 = tool.prescribed_displacement(0.0).unwrap_or(0.0);
    (0..x.len())
        .into_par_iter()
        .filter_map(|i| {
            let p = tool.project(&x[i], u0);
            let short = clearance.from(i, &p.normal) - p.gap;
            (p.gap >= -slack && short > slack).then_some((i, short, p.normal))
        })
        .collect()
}

/// Translates a blank at `x` that starts closer to a tool than it must (its
/// half thickness; in a stack, the plies between it and the tool and its
/// own half thickness) away from it, before the first step: by the largest
/// shortfall along that tool's normal there, again (up to four times)
/// while a node is still short, so that every node
/// starts at its distance. A rigid move: the blank keeps its shape and
/// starts stress-free, and a stack keeps its plies apart. Left to the
/// first step, the contact would stop those nodes as a velocity, d/Δt
/// (0.1 mm in a 2e-5 s step: 5 m/s), a kinetic energy from nowhere that
/// the energy guard stopped the run on (a hemisphere whose pole touched
/// the blank stopped at t = 0.01 s). Nothing moves, and None is returned,
/// where a node is held by a boundary condition (`free` false) or the
/// moves would not clear every tool; else the translation (mm).
pub fn settle_on_tools(
    model: &Model,
    x: &mut [Vector3<f64>],
    free: &[bool],
) -> Option<Vector3<f64>> {
    let clearance = StartClearance::of(model);
    let shortfall = |x: &[Vector3<f64>]| {
        let mut worst = (0.0f64, Vector3::zeros());
        for tool in &model.tools {
            for (_, by, normal) in too_close(model, tool, x, &clearance) {
                if by > worst.0 {
                    worst = (by, normal);
                }
            }
        }
        worst
    };
    if shortfall(x).0 == 0.0 || !free.iter().all(|&f| f) {
        return None;
    }
    let start = x.to_vec();
    let mut shift = Vector3::zeros();
    for tries in 0..=SETTLE_TRIES {
        let (by, normal) = shortfall(x);
        if by == 0.0 {
            // Still no node inside a tool either.
            if !starts_inside_a_tool(model, x) {
                return Some(shift);
            }
            break;
        }
        if tries == SETTLE_TRIES {
            break;
        }
        for xi in x.iter_mut() {
            *xi += normal * by;
        }
        shift += normal * by;
    }
    x.copy_from_slice(&start);
    None
}

/// Translations [`settle_on_tools`] tries before it gives up.
const SETTLE_TRIES: usize = 4;

/// Whether a node of `x` starts behind a tool (its mid-surface past the
/// tool's surface by more than round-off).
fn starts_inside_a_tool(model: &Model, x: &[Vector3<f64>]) -> bool {
    let slack = 0.01 * model.contact_offset;
    model.tools.iter().any(|tool| {
        let u0 = tool.prescribed_displacement(0.0).unwrap_or(0.0);
        x.par_iter().any(|p| tool.project(p, u0).gap < -slack)
    })
}

/// The start-up checks of a model's tools against its blank at positions
/// `x`, for a run at step `dt`: an error for a blank that starts inside a
/// tool (its mid-surface behind the tool's surface) and for a force-driven
/// tool that its force alone would carry through the fabric's thickness in
/// one step; the warnings for nodes closer to a tool than the fabric's half
/// thickness (what [`settle_on_tools`] will do about them) and for a
/// force-driven tool with no node ahead of it. Messages name the tool and
/// the nodes.
pub fn check_tools_at_start(
    model: &Model,
    x: &[Vector3<f64>],
    dt: f64,
) -> Result<Vec<String>, String> {
    let offset = model.contact_offset;
    // Round-off of a blank built on a tool's surface is not an overlap.
    let slack = 0.01 * offset;
    let mut warnings = Vec::new();
    let clearance = StartClearance::of(model);
    // What `settle_on_tools` will do, found once for every tool's warning.
    let free = crate::shared::Constraints::new(model).free();
    let settled = std::cell::OnceCell::new();
    for tool in &model.tools {
        let u0 = tool.prescribed_displacement(0.0).unwrap_or(0.0);
        let gaps: Vec<f64> = x.par_iter().map(|p| tool.project(p, u0).gap).collect();
        let inside: Vec<usize> = (0..x.len()).filter(|&i| gaps[i] < -slack).collect();
        if !inside.is_empty() {
            let depth = inside.iter().map(|&i| -gaps[i]).fold(0.0, f64::max);
            return Err(format!(
                "the blank starts inside tool `{}`: {} up to {depth:.4} mm behind its surface; move the tool \
                 or the blank (the fabric's mid-surface must start at least its half thickness, {offset} mm, \
                 away from every tool)",
                tool.name,
                node_list(&inside)
            ));
        }
        let close = too_close(model, tool, x, &clearance);
        if !close.is_empty() {
            let depth = close.iter().map(|c| c.1).fold(0.0, f64::max);
            let close: Vec<usize> = close.iter().map(|c| c.0).collect();
            let shift = *settled.get_or_init(|| settle_on_tools(model, &mut x.to_vec(), &free));
            let what = match shift {
                Some(shift) => format!(
                    "the run moves the blank {:.4} mm along ({:.3}, {:.3}, {:.3}) before its first \
                     step, as a whole (it starts stress-free, off where the scene put it)",
                    shift.norm(),
                    shift.x / shift.norm(),
                    shift.y / shift.norm(),
                    shift.z / shift.norm()
                ),
                None => format!(
                    "the first step pushes {} out, as a velocity that may stop the run on its \
                     energy balance (the blank is not moved {}): start it farther from the tool",
                    if close.len() == 1 { "it" } else { "them" },
                    if free.iter().all(|&f| f) {
                        "because no translation clears every tool"
                    } else {
                        "because boundary conditions hold nodes of it"
                    }
                ),
            };
            warnings.push(format!(
                "{} of the blank start{} closer to tool `{}` than the fabric's half thickness {offset} mm{} \
                 (by up to {depth:.4} mm): {what}",
                node_list(&close),
                if close.len() == 1 { "s" } else { "" },
                tool.name,
                if model.plies.is_empty() {
                    ""
                } else {
                    " (in a stack: than the plies between them and the tool and their own half thickness)"
                },
            ));
        }
        if let ToolMotion::Force {
            direction,
            force,
            amplitude,
            mass,
        } = &tool.motion
        {
            let travel = force.abs() * peak_value(amplitude) / mass * dt * dt;
            // A step that is not a number (mass scaling to an overflowing
            // mass) cannot be judged here: the caller's check of the
            // masses and the step refuses it, naming its setting.
            if dt.is_finite() && travel > 2.0 * offset {
                return Err(format!(
                    "force-driven tool `{}` would travel {travel:.3e} mm in one step under its force alone \
                     ({force:e} N on {mass:e} t, Δt = {dt:.3e} s): more than the fabric's thickness {} mm, so \
                     it would pass through the blank in one step; lower the force or raise the tool's mass",
                    tool.name,
                    2.0 * offset
                ));
            }
            if !ahead_of(tool, u0, direction, x, offset) {
                warnings.push(format!(
                    "force-driven tool `{}` moves along ({}, {}, {}) and no node of the blank lies ahead of \
                     it: it will never touch the blank",
                    tool.name, direction.x, direction.y, direction.z
                ));
            }
        }
    }
    Ok(warnings)
}

/// Whether some node of `x` lies in the path of `tool` (at displacement
/// `u0`) moving along `direction`: within its bounding box seen along the
/// direction, and not behind it.
fn ahead_of(
    tool: &drape_contact::Tool,
    u0: f64,
    direction: &Vector3<f64>,
    x: &[Vector3<f64>],
    margin: f64,
) -> bool {
    let aabb = tool.surface.aabb().translated(&(direction * u0));
    if !(aabb
        .min
        .iter()
        .chain(aabb.max.iter())
        .all(|c| c.is_finite()))
    {
        return true;
    }
    // An orthonormal frame (e₁, e₂, d).
    let d = direction.normalize();
    let helper = if d.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = d.cross(&helper).normalize();
    let e2 = d.cross(&e1);
    let corners = (0..8).map(|k| {
        Vector3::new(
            if k & 1 == 0 { aabb.min.x } else { aabb.max.x },
            if k & 2 == 0 { aabb.min.y } else { aabb.max.y },
            if k & 4 == 0 { aabb.min.z } else { aabb.max.z },
        )
    });
    let mut low = [f64::INFINITY; 3];
    let mut high = [f64::NEG_INFINITY; 3];
    for c in corners {
        for (k, axis) in [e1, e2, d].iter().enumerate() {
            let s = axis.dot(&c);
            low[k] = low[k].min(s);
            high[k] = high[k].max(s);
        }
    }
    x.iter().any(|p| {
        let (s1, s2, s3) = (e1.dot(p), e2.dot(p), d.dot(p));
        s1 >= low[0] - margin
            && s1 <= high[0] + margin
            && s2 >= low[1] - margin
            && s2 <= high[1] + margin
            && s3 >= low[2] - margin
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use drape_contact::{Surface, Tool};

    /// An open 100 × 100 mm plate at z = 0, fabric above.
    fn plate(name: &str, z: f64) -> Tool {
        let v = vec![
            Vector3::new(0.0, 0.0, z),
            Vector3::new(100.0, 0.0, z),
            Vector3::new(100.0, 100.0, z),
            Vector3::new(0.0, 100.0, z),
        ];
        Tool {
            name: name.into(),
            surface: Surface::triangle_mesh(v, vec![[0, 1, 2], [0, 2, 3]]).unwrap(),
            motion: ToolMotion::Fixed,
            friction: 0.0,
        }
    }

    #[test]
    fn a_runaway_node_names_the_nearest_tool_and_its_rim() {
        let tools = [plate("far", 40.0), plate("mould", 0.0)];
        let x = vec![Vector3::zeros(), Vector3::new(97.0, 50.0, 0.5)];
        let speed = Instability::Speed {
            node: 1,
            position: x[1].into(),
            near: None,
            speed: 4e6,
            scale: 100.0,
            factor: 100.0,
        }
        .near_tools(&tools, &[0.0, 0.0], &x);
        let text = speed.to_string();
        for part in [
            "node 1 at (97.00, 50.00, 0.50) mm moves at 4.000e6 mm/s",
            "nearest tool: tool `mould` at (97.00, 50.00, 0.00) mm (gap 5.000e-1 mm), 3.00 mm from its open rim",
        ] {
            assert!(text.contains(part), "{part}: {text}");
        }
        // Without tools, nothing is added.
        let alone = Instability::Outside {
            node: 0,
            near: None,
            position: [0.0; 3],
            beyond: 1.0,
            reach: 2.0,
        }
        .near_tools(&[], &[], &x);
        assert!(!alone.to_string().contains("nearest tool"));
    }
}
