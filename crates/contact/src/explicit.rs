//! Contact for explicit central differences: forward-increment Lagrange
//! multipliers (SPEC §6) and Coulomb friction by return mapping.
//!
//! After the predictor has moved the nodes to x̃ₙ₊₁ without contact, the
//! pass finds the nodes that would sit closer to a tool than the fabric's
//! half thickness and solves C·M⁻¹·Cᵀ·μ = −g with μ = λ·Δt² ≥ 0: per node in
//! closed form when every constraint is alone (one tool per node, tools
//! driven by displacement), by a projected preconditioned conjugate
//! gradient when constraints couple (a node pinched between two tools, a
//! force-driven holder that every node under it pushes back). Friction then
//! corrects the tangential velocity towards sticking to the tool, capped by
//! μ_f·λ.

use nalgebra::Vector3;
use rayon::prelude::*;

use crate::tool::{Tool, ToolMotion, ToolState};

/// A node's contact status.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u8)]
pub enum ContactStatus {
    /// Not touching.
    #[default]
    Open = 0,
    /// Touching and sticking.
    Stick = 1,
    /// Touching and sliding.
    Slip = 2,
}

/// Settings of the contact pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSettings {
    /// Distance of the fabric's mid-surface from a tool at contact: half the
    /// thickness (mm).
    pub offset: f64,
    /// Margin of the broad phase: the candidate lists are rebuilt once a node
    /// or a tool has moved half of it (mm).
    pub margin: f64,
    /// Convergence of the coupled solve: largest gap violation left (mm).
    pub tolerance: f64,
    /// Iterations allowed to the coupled solve.
    pub max_iterations: usize,
}

impl Default for ContactSettings {
    fn default() -> Self {
        Self {
            offset: 0.0,
            margin: 5.0,
            tolerance: 1e-9,
            max_iterations: 500,
        }
    }
}

/// One active constraint of a step.
#[derive(Debug, Clone, Copy)]
struct Constraint {
    node: u32,
    tool: u32,
    normal: Vector3<f64>,
    gap: f64,
    /// μ = λ·Δt².
    mu: f64,
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
}

impl ExplicitContact {
    /// A pass over `node_count` nodes.
    pub fn new(tools: Vec<Tool>, node_count: usize, settings: ContactSettings) -> Self {
        let n_tools = tools.len();
        Self {
            tool_state: vec![ToolState::default(); n_tools],
            tools,
            settings,
            force: vec![Vector3::zeros(); node_count],
            status: vec![ContactStatus::Open; node_count],
            tool_of: vec![u32::MAX; node_count],
            tool_force: vec![0.0; n_tools],
            friction_dissipation: 0.0,
            candidates: vec![Vec::new(); n_tools],
            reference_x: Vec::new(),
            reference_tool: vec![f64::NAN; n_tools],
            constraints: Vec::new(),
            per_node: vec![0; node_count],
            touched: Vec::new(),
            scratch: Scratch {
                node_sum: vec![Vector3::zeros(); node_count],
                ..Scratch::default()
            },
        }
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
                .any(|(a, b)| (a - b).norm_squared() > half * half);
        if !(tools_moved || nodes_moved) {
            return;
        }
        let reach = self.settings.margin + self.settings.offset;
        for (t, tool) in self.tools.iter().enumerate() {
            let shift = tool.motion.direction() * self.tool_state[t].displacement;
            let aabb = tool.surface.aabb().translated(&shift).grown(reach);
            self.candidates[t] = (0..x.len() as u32)
                .into_par_iter()
                .filter(|&i| aabb.contains(&x[i as usize]))
                .collect();
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
    pub fn enforce(
        &mut self,
        x: &mut [Vector3<f64>],
        v: &mut [Vector3<f64>],
        mass: &[f64],
        movable: &[bool],
        t_new: f64,
        dt: f64,
    ) -> ContactStep {
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
                        state.velocity += dt * force * amplitude.value(t_new - dt) / mass;
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
        self.tool_force.iter_mut().for_each(|f| *f = 0.0);
        self.refresh_candidates(x);

        // Narrow phase.
        self.constraints.clear();
        let offset = self.settings.offset;
        for (t, tool) in self.tools.iter().enumerate() {
            let u = self.tool_state[t].displacement;
            for &i in &self.candidates[t] {
                if !movable[i as usize] {
                    continue;
                }
                let p = tool.project(&x[i as usize], u);
                let gap = p.gap - offset;
                if gap < 0.0 {
                    self.constraints.push(Constraint {
                        node: i,
                        tool: t as u32,
                        normal: p.normal,
                        gap,
                        mu: 0.0,
                    });
                }
            }
        }
        if self.constraints.is_empty() {
            return ContactStep::default();
        }
        for c in &self.constraints {
            self.per_node[c.node as usize] += 1;
        }
        let coupled = self.constraints.iter().any(|c| {
            self.per_node[c.node as usize] > 1 || self.tools[c.tool as usize].is_force_driven()
        });
        let mut step = ContactStep {
            active: self.constraints.len(),
            ..ContactStep::default()
        };
        if coupled {
            let (iterations, residual) = self.solve_coupled(mass);
            step.iterations = iterations;
            step.residual = residual;
        } else {
            for c in &mut self.constraints {
                c.mu = -c.gap * mass[c.node as usize];
            }
        }

        // Apply the normal corrections and the force-driven tools' reaction.
        let lambda_scale = 1.0 / (dt * dt);
        for c in &self.constraints {
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
            self.tool_force[c.tool as usize] += if axis == Vector3::zeros() {
                lambda
            } else {
                -c.normal.dot(&axis) * lambda
            };
            if let ToolMotion::Force {
                direction,
                mass: m_tool,
                ..
            } = &tool.motion
            {
                let du = -c.normal.dot(direction) * c.mu / m_tool;
                let state = &mut self.tool_state[c.tool as usize];
                state.displacement += du;
                state.velocity += du / dt;
            }
        }

        if self.has_friction() {
            self.friction(x, v, mass, dt);
        }
        step
    }

    /// Coulomb friction on the active constraints: the tangential force that
    /// would make the node stick to the tool over the step, capped at μ_f·λ.
    fn friction(&mut self, x: &mut [Vector3<f64>], v: &mut [Vector3<f64>], mass: &[f64], dt: f64) {
        for c in &self.constraints {
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
            let lambda = c.mu / (dt * dt);
            let trial = mass[i] * speed / dt;
            let limit = tool.friction * lambda;
            let (magnitude, status) = if trial <= limit {
                (trial, ContactStatus::Stick)
            } else {
                (limit, ContactStatus::Slip)
            };
            let f_t = -v_t / speed * magnitude;
            let dv = f_t * (dt / mass[i]);
            v[i] += dv;
            x[i] += dv * dt;
            self.force[i] += f_t;
            self.status[i] = status;
            if status == ContactStatus::Slip {
                // What the friction force does against the remaining slip.
                let after = speed - magnitude * dt / mass[i];
                self.friction_dissipation += magnitude * after * dt;
            }
        }
    }

    /// Solves min ½μᵀAμ + gᵀμ, μ ≥ 0, with A = C·M⁻¹·Cᵀ (nodes and
    /// force-driven tools), by projected conjugate gradients with a Jacobi
    /// preconditioner (Polyak's active-set variant): CG on the free set,
    /// stopping at the first bound it meets, then a new free set.
    // The solver walks several arrays over the constraints in lockstep;
    // indices read more plainly than zips of five iterators.
    #[allow(clippy::needless_range_loop)]
    fn solve_coupled(&mut self, mass: &[f64]) -> (usize, f64) {
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
        let tool_axis: Vec<(Vector3<f64>, f64)> = tools
            .iter()
            .map(|t| match &t.motion {
                ToolMotion::Force {
                    direction, mass, ..
                } => (*direction, *mass),
                _ => (Vector3::zeros(), f64::INFINITY),
            })
            .collect();
        let mut tool_sum = vec![0.0; tools.len()];
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
        let mut mu: Vec<f64> = vec![0.0; n];
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
        (iterations, residual)
    }
}
