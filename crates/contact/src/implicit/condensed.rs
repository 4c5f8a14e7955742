//! The condensed multiplier solve of `contact_solver = "condensed"` (the
//! paper's eq. 22–27, the reference): with K̂ factorised by the driver, the
//! multipliers of the rows of C solve the bound-constrained problem on
//! A = C·K̂⁻¹·Cᵀ by MPRGP (`mprgp`), λ_N ≥ 0, then Δx follows; and the same
//! solve with M in place of K̂ for the consistent initial acceleration of
//! the nodes touching a tool at the start of a run.
//!
//! Not here: the pairs, their rows and friction (the parent module), the
//! active-set solver's rows (`active_set`).

use super::*;

impl ImplicitContact {
    /// The condensed solve. `r` is the residual over 3·N components with
    /// the slip forces in it; `solve` replaces a vector w by K̂⁻¹·w (and
    /// keeps prescribed components at zero). Writes Δx into `dx` and
    /// keeps each force-driven tool's Δd for [`Self::apply_step`].
    pub fn solve(
        &mut self,
        r: &[f64],
        solve: &mut dyn FnMut(&mut [f64]),
        dx: &mut [f64],
    ) -> Result<SolveStats, SolveError> {
        self.solve_preconditioned(r, solve, None, dx)
    }

    /// [`Self::solve`] with MPRGP preconditioned by the diagonal of
    /// A = C·K̂⁻¹·Cᵀ estimated from `block(i)`, the 3×3 block of K̂ at node
    /// i: A_kk ≈ c_kᵀ·K̂_ii⁻¹·c_k (+ the row's compliance). The problem is
    /// solved in the variables μ = S·λ, S = diag(√A_kk) (a positive
    /// scaling keeps the bounds λ_N ≥ 0), which is MPRGP with a Jacobi
    /// preconditioner in every face; the tolerance stays on the unscaled
    /// gaps.
    pub fn solve_preconditioned(
        &mut self,
        r: &[f64],
        solve: &mut dyn FnMut(&mut [f64]),
        block: Option<&dyn Fn(usize) -> Matrix3<f64>>,
        dx: &mut [f64],
    ) -> Result<SolveStats, SolveError> {
        let n = self.rows.len();
        let n_tools = self.tools.len();
        // Δx₀ = K̂⁻¹·(r + the springs' forces at the iterate), the tools'
        // Δd₀ = r_t/k_t.
        dx.copy_from_slice(r);
        for row in &self.springs {
            let i = 3 * self.pairs[row.pair as usize].node as usize;
            let force = -row.target / row.compliance;
            for c in 0..3 {
                dx[i + c] += row.direction[c] * force;
            }
        }
        solve(dx);
        let mut tool_r = vec![0.0; 0];
        std::mem::swap(&mut tool_r, &mut self.scratch.tool_w);
        tool_r.clear();
        tool_r.extend((0..n_tools).map(|t| {
            if self.tools[t].is_force_driven() {
                self.tool_residual(t) / self.tool_stiffness(t)
            } else {
                0.0
            }
        }));
        let mut stats = SolveStats {
            rows: n,
            ..SolveStats::default()
        };
        if n == 0 {
            self.tool_step.copy_from_slice(&tool_r);
            self.scratch.tool_w = tool_r;
            return Ok(stats);
        }
        let mut stiffness = std::mem::take(&mut self.scratch.tool_stiffness);
        stiffness.clear();
        stiffness.extend((0..n_tools).map(|t| self.tool_stiffness(t)));
        let s = &mut self.scratch;
        for v in [
            &mut s.lambda,
            &mut s.c,
            &mut s.g,
            &mut s.p,
            &mut s.ap,
            &mut s.phi,
        ] {
            v.clear();
            v.resize(n, 0.0);
        }
        s.w.clear();
        s.w.resize(dx.len(), 0.0);
        // c = g + C·K̂⁻¹·r; warm start from the pairs' forces.
        for (k, row) in self.rows.iter().enumerate() {
            let pair = &self.pairs[row.pair as usize];
            let i = pair.node as usize;
            let z = Vector3::new(dx[3 * i], dx[3 * i + 1], dx[3 * i + 2]);
            s.c[k] = row.target
                + row.direction.dot(&z)
                + row.tool_coefficient * tool_r[pair.tool as usize];
            s.lambda[k] = if row.bounded {
                pair.lambda.max(0.0)
            } else {
                row.direction.dot(&pair.stick)
            };
        }
        // The row scaling S (1 without a preconditioner).
        s.scale.clear();
        match block {
            Some(block) => {
                let mut inverse: Option<(u32, Matrix3<f64>)> = None;
                for row in &self.rows {
                    let pair = &self.pairs[row.pair as usize];
                    let b = match inverse {
                        Some((node, b)) if node == pair.node => b,
                        _ => {
                            let b = block(pair.node as usize)
                                .try_inverse()
                                .unwrap_or_else(Matrix3::zeros);
                            inverse = Some((pair.node, b));
                            b
                        }
                    };
                    let t = pair.tool as usize;
                    let tool = if stiffness[t].is_finite() {
                        row.tool_coefficient * row.tool_coefficient / stiffness[t]
                    } else {
                        0.0
                    };
                    let d = row.direction.dot(&(b * row.direction)) + row.compliance + tool;
                    s.scale.push(if d.is_finite() && d > 0.0 {
                        d.sqrt()
                    } else {
                        1.0
                    });
                }
            }
            None => s.scale.resize(n, 1.0),
        }
        for k in 0..n {
            s.c[k] /= s.scale[k];
            s.lambda[k] *= s.scale[k];
        }
        let rows = &self.rows;
        let pairs = &self.pairs;
        let scale = &s.scale;
        let mut w = std::mem::take(&mut s.w);
        let mut tool_w = std::mem::take(&mut s.tool_f);
        tool_w.clear();
        tool_w.resize(n_tools, 0.0);
        let mut bounded = std::mem::take(&mut s.bounded);
        bounded.clear();
        bounded.extend(rows.iter().map(|r| r.bounded));
        let mut products = 0usize;
        // y = A·v = C·K̂⁻¹·Cᵀ·v.
        let mut apply = |v: &[f64], y: &mut [f64]| {
            products += 1;
            w.iter_mut().for_each(|x| *x = 0.0);
            tool_w.iter_mut().for_each(|x| *x = 0.0);
            for ((row, &vk), &sk) in rows.iter().zip(v).zip(scale) {
                let vk = vk / sk;
                let pair = &pairs[row.pair as usize];
                let i = 3 * pair.node as usize;
                for c in 0..3 {
                    w[i + c] += row.direction[c] * vk;
                }
                tool_w[pair.tool as usize] += row.tool_coefficient * vk;
            }
            solve(&mut w);
            for (t, tw) in tool_w.iter_mut().enumerate() {
                *tw = if stiffness[t].is_finite() {
                    *tw / stiffness[t]
                } else {
                    0.0
                };
            }
            for (k, row) in rows.iter().enumerate() {
                let pair = &pairs[row.pair as usize];
                let i = 3 * pair.node as usize;
                y[k] = (row.direction.dot(&Vector3::new(w[i], w[i + 1], w[i + 2]))
                    + row.tool_coefficient * tool_w[pair.tool as usize]
                    + row.compliance * v[k] / scale[k])
                    / scale[k];
            }
        };
        // The round-off estimate's inputs (with the preconditioner only:
        // its scaling is √A_kk).
        let preconditioned = block.is_some();
        let mut roundoff = std::mem::take(&mut s.roundoff);
        if preconditioned {
            roundoff.prepare(self.force.len(), rows, pairs, scale, &stiffness);
        }
        let result = mprgp(
            &bounded,
            &s.c,
            &mut s.lambda,
            &mut apply,
            Work {
                stats: &mut stats,
                g: &mut s.g,
                p: &mut s.p,
                ap: &mut s.ap,
                phi: &mut s.phi,
                scale,
                roundoff: preconditioned.then_some(&mut roundoff),
            },
            self.settings.tolerance,
            self.settings.max_iterations,
        );
        s.w = w;
        s.bounded = bounded;
        s.roundoff = roundoff;
        stats.iterations = products;
        let residual = match result {
            Ok(residual) => residual,
            Err(e) => {
                s.tool_f = tool_w;
                self.scratch.tool_stiffness = stiffness;
                self.scratch.tool_w = tool_r;
                return Err(e);
            }
        };
        for k in 0..n {
            s.lambda[k] /= s.scale[k];
        }
        stats.residual = residual;
        // Δx = K̂⁻¹·(r + Cᵀλ) = Δx₀ + K̂⁻¹·Cᵀλ.
        s.w.iter_mut().for_each(|x| *x = 0.0);
        let mut tool_f = tool_w;
        tool_f.iter_mut().for_each(|x| *x = 0.0);
        for (row, &l) in self.rows.iter().zip(&s.lambda) {
            let pair = &self.pairs[row.pair as usize];
            let i = 3 * pair.node as usize;
            for c in 0..3 {
                s.w[i + c] += row.direction[c] * l;
            }
            tool_f[pair.tool as usize] += row.tool_coefficient * l;
        }
        solve(&mut s.w);
        stats.iterations += 1;
        for (d, w) in dx.iter_mut().zip(&s.w) {
            *d += w;
        }
        for t in 0..n_tools {
            self.tool_step[t] = tool_r[t]
                + if stiffness[t].is_finite() {
                    tool_f[t] / stiffness[t]
                } else {
                    0.0
                };
        }
        stats.active_changes = self
            .rows
            .iter()
            .zip(&s.lambda)
            .filter(|(row, l)| {
                row.bounded && (**l > 0.0) != (self.pairs[row.pair as usize].lambda > 0.0)
            })
            .count();
        // Multipliers back to the pairs.
        for pair in &mut self.pairs {
            pair.lambda_before = pair.lambda;
            pair.lambda = 0.0;
            pair.stick = Vector3::zeros();
        }
        for (row, &l) in self.rows.iter().zip(&s.lambda) {
            let pair = &mut self.pairs[row.pair as usize];
            if row.bounded {
                pair.lambda = l.max(0.0);
            } else {
                pair.stick += row.direction * l;
            }
        }
        self.add_spring_sticks(dx);
        stats.active = self.pairs.iter().filter(|p| p.lambda > 0.0).count();
        self.scratch.tool_w = tool_r;
        self.scratch.tool_f = tool_f;
        self.scratch.tool_stiffness = stiffness;
        self.solve_totals.add(&stats);
        Ok(stats)
    }

    /// The consistent initial acceleration of the nodes touching a tool:
    /// given the free accelerations `a = M⁻¹·f` (prescribed components
    /// zero, for the nodes' `mass` and `free` components), removes what
    /// would push a touching node into its tool and applies Coulomb
    /// friction, by the same condensed solve with M in place of K̂.
    /// Nodes touch when their gap is within `touch` (mm) at `x`; their
    /// velocities `v` decide which slide.
    pub fn initial_acceleration(
        &mut self,
        x: &[Vector3<f64>],
        v: &[Vector3<f64>],
        mass: &[f64],
        free: &[[bool; 3]],
        touch: f64,
        a: &mut [Vector3<f64>],
    ) -> Result<SolveStats, SolveError> {
        let movable: Vec<bool> = free.iter().map(|f| f.iter().any(|&c| c)).collect();
        // A zero-length "increment" whose inertia is the mass: k_t = M_t.
        let inc = Increment {
            t_new: 0.0,
            h: 1.0,
            beta: 1.0,
            gamma: 1.0,
            alpha_m: 0.0,
        };
        self.begin(x, &movable, inc);
        self.initial = true;
        self.trial.copy_from_slice(
            &self
                .tool_state
                .iter()
                .map(|s| s.displacement)
                .collect::<Vec<_>>(),
        );
        let margin = self.settings.margin;
        self.settings.margin = touch;
        // Pairs within `touch`; their rows' targets are the accelerations'.
        self.linearise(x, x);
        self.settings.margin = margin;
        let n = x.len();
        let mut r = vec![0.0; 3 * n];
        let mut dx = vec![0.0; 3 * n];
        let mut stats = SolveStats::default();
        let mut slip_f = vec![Vector3::zeros(); n];
        for _ in 0..20 {
            // Rows act on accelerations: targets zero (relative sliding
            // acceleration of a sticking node, normal acceleration).
            for row in &mut self.rows {
                row.target = 0.0;
            }
            // Slip directions from the relative velocities.
            for pair in &mut self.pairs {
                let tool = &self.tools[pair.tool as usize];
                let rel = v[pair.node as usize]
                    - tool.motion.direction() * self.tool_state[pair.tool as usize].velocity;
                let vt = rel - pair.normal * pair.normal.dot(&rel);
                if tool.friction > 0.0 && vt.norm() > 0.0 {
                    pair.friction = Friction::Slip;
                    pair.slip_direction = -vt.normalize();
                }
            }
            slip_f.iter_mut().for_each(|f| *f = Vector3::zeros());
            self.add_slip_forces(&mut slip_f);
            for i in 0..n {
                for c in 0..3 {
                    r[3 * i + c] = if free[i][c] {
                        a[i][c] * mass[i] + slip_f[i][c]
                    } else {
                        0.0
                    };
                }
            }
            let mut by_mass = |w: &mut [f64]| {
                for i in 0..n {
                    for c in 0..3 {
                        w[3 * i + c] = if free[i][c] {
                            w[3 * i + c] / mass[i]
                        } else {
                            0.0
                        };
                    }
                }
            };
            let s = match self.solve(&r, &mut by_mass, &mut dx) {
                Ok(s) => s,
                Err(e) => {
                    self.increment = None;
                    self.initial = false;
                    self.pairs.clear();
                    return Err(e);
                }
            };
            stats.iterations += s.iterations;
            stats.rows = s.rows;
            stats.active = s.active;
            // Only stick → slip can happen here.
            let mut changed = 0;
            for pair in &mut self.pairs {
                let mu = self.tools[pair.tool as usize].friction;
                if mu > 0.0 && pair.friction == Friction::Stick && pair.lambda > 0.0 {
                    let f = pair.stick.norm();
                    if f > mu * pair.lambda * (1.0 + CONE_SLACK) {
                        pair.friction = Friction::Slip;
                        pair.slip_direction = pair.stick / f;
                        pair.stick = Vector3::zeros();
                        changed += 1;
                    }
                }
            }
            if changed == 0 {
                // The stick rows exist only for pairs that had λ > 0:
                // solve once more if new pairs closed.
                let needs_rows = self.pairs.iter().any(|p| {
                    p.lambda > 0.0
                        && p.friction == Friction::Stick
                        && self.tools[p.tool as usize].friction > 0.0
                        && !p.stick_rows
                });
                if !needs_rows {
                    break;
                }
            }
            self.linearise_rows();
        }
        for i in 0..n {
            for c in 0..3 {
                if free[i][c] {
                    a[i][c] = dx[3 * i + c];
                }
            }
        }
        for t in 0..self.tools.len() {
            if self.tools[t].is_force_driven() {
                self.tool_acceleration[t] = self.tool_step[t];
            }
        }
        // The pairs pressed at t = 0 are in contact since the start of the
        // first increment.
        self.carried = self
            .pairs
            .iter()
            .filter(|p| p.lambda > 0.0)
            .map(|p| CarriedPair {
                tool: p.tool,
                node: p.node,
                lambda: p.lambda,
                stick: p.stick.into(),
                slip_direction: p.slip_direction.into(),
                friction: p.friction,
            })
            .collect();
        self.increment = None;
        self.initial = false;
        self.pairs.clear();
        Ok(stats)
    }
}
