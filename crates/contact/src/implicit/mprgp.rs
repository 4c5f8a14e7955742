//! MPRGP (Dostál) for the condensed multiplier solve, with its round-off
//! floor: the inner solver of `contact_solver = "condensed"`.

use super::*;

/// The MPRGP work vectors.
pub(super) struct Work<'a> {
    /// Where the products are counted by kind.
    pub(super) stats: &'a mut SolveStats,
    pub(super) g: &'a mut [f64],
    pub(super) p: &'a mut [f64],
    pub(super) ap: &'a mut [f64],
    pub(super) phi: &'a mut [f64],
    /// The rows' scaling: the tolerance applies to the gradient times it.
    pub(super) scale: &'a [f64],
    /// What each gradient component's round-off scales with (None: not
    /// known, the tolerance alone decides).
    pub(super) roundoff: Option<&'a mut RoundOff>,
}

/// What the round-off of a computed component of the gradient Aλ + c
/// scales with: the forces that cancel in it. A node pinched between the
/// blank holder and the die carries the clamping force F on two rows ±n,
/// which cancel in Cᵀλ to a rounding error of ε·F; through the node's
/// compliance that is an error of ε·A_kk·F in each row's gap, however
/// small the gap the rows agree on. Likewise a force-driven tool's rows
/// sum to the tool's force, and c holds the step without contact. The
/// buffers live in the pass's scratch: nothing is allocated per solve
/// once they have grown.
#[derive(Debug, Clone, Default)]
pub(super) struct RoundOff {
    /// Each node's number among the rows' nodes (u32::MAX: no row).
    group_of: Vec<u32>,
    /// Each row's node, numbered from 0 over the rows' nodes.
    group: Vec<u32>,
    /// Each row's estimated A_kk (mm/N), the square of its scaling.
    diagonal: Vec<f64>,
    /// Each row's tool and its coefficient on the tool's unknown.
    tool: Vec<u32>,
    coefficient: Vec<f64>,
    /// Each tool's compliance along its axis (mm/N, 0 if not force-driven).
    compliance: Vec<f64>,
    /// Work: Σ|λ| per node and Σ|a·λ| per tool.
    node_sum: Vec<f64>,
    tool_sum: Vec<f64>,
}

/// The round-off floor of the condensed solve's gradient, in units of
/// the estimate ε·(A_kk·Σ|λ| at the row's node + |a_k|·Σ|a·λ| of its
/// tool over the tool's stiffness + |c_k|) (see [`RoundOff`]): a
/// component within this many times its estimate is as converged as the
/// arithmetic allows, whatever the tolerance. The estimate counts one
/// rounding per force; the forward/back solve with the factors adds more
/// (one per factor entry on the way), which the factor 100 leaves room
/// for. It is chosen, not fitted to a run: no case was tuned with it.
pub(super) const ROUNDOFF: f64 = 100.0;

impl RoundOff {
    /// Takes the rows of this solve: their nodes, A_kk = `scale`², tools
    /// and the tools' `stiffness` along their axes.
    pub(super) fn prepare(
        &mut self,
        nodes: usize,
        rows: &[Row],
        pairs: &[Pair],
        scale: &[f64],
        stiffness: &[f64],
    ) {
        self.group_of.clear();
        self.group_of.resize(nodes, u32::MAX);
        self.group.clear();
        let mut groups = 0u32;
        for row in rows {
            let node = pairs[row.pair as usize].node as usize;
            if self.group_of[node] == u32::MAX {
                self.group_of[node] = groups;
                groups += 1;
            }
            self.group.push(self.group_of[node]);
        }
        self.node_sum.clear();
        self.node_sum.resize(groups as usize, 0.0);
        self.diagonal.clear();
        self.diagonal.extend(scale.iter().map(|x| x * x));
        self.tool.clear();
        self.tool
            .extend(rows.iter().map(|r| pairs[r.pair as usize].tool));
        self.coefficient.clear();
        self.coefficient
            .extend(rows.iter().map(|r| r.tool_coefficient));
        self.compliance.clear();
        self.compliance.extend(
            stiffness
                .iter()
                .map(|k| if k.is_finite() { 1.0 / k } else { 0.0 }),
        );
        self.tool_sum.clear();
        self.tool_sum.resize(stiffness.len(), 0.0);
    }

    /// The round-off floor (mm) at the multipliers `mu` (scaled by
    /// `scale`) for the (scaled) linear term `c`: the largest row's, since
    /// the solve with the factors spreads a node's error over the sheet.
    fn floor(&mut self, mu: &[f64], scale: &[f64], c: &[f64]) -> f64 {
        self.node_sum.iter_mut().for_each(|x| *x = 0.0);
        self.tool_sum.iter_mut().for_each(|x| *x = 0.0);
        for k in 0..mu.len() {
            let l = mu[k] / scale[k];
            self.node_sum[self.group[k] as usize] += l.abs();
            self.tool_sum[self.tool[k] as usize] += (self.coefficient[k] * l).abs();
        }
        (0..mu.len())
            .map(|k| {
                let t = self.tool[k] as usize;
                ROUNDOFF
                    * f64::EPSILON
                    * (self.diagonal[k] * self.node_sum[self.group[k] as usize]
                        + self.coefficient[k].abs() * self.compliance[t] * self.tool_sum[t]
                        + (c[k] * scale[k]).abs())
            })
            .fold(0.0, f64::max)
    }
}

/// MPRGP (Dostál 2009, "Optimal quadratic programming algorithms",
/// Alg. 5.8) for min ½λᵀAλ + cᵀλ with λ_k ≥ 0 where `bounded[k]`, from a
/// feasible start `lambda`; A given by its product. Stops when the
/// projected gradient's largest component is within `tolerance`. Returns
/// that residual.
#[allow(clippy::needless_range_loop)]
pub(super) fn mprgp(
    bounded: &[bool],
    c: &[f64],
    lambda: &mut [f64],
    apply: &mut dyn FnMut(&[f64], &mut [f64]),
    work: Work<'_>,
    tolerance: f64,
    max_iterations: usize,
) -> Result<f64, SolveError> {
    let n = c.len();
    let Work {
        stats,
        g,
        p,
        ap,
        phi,
        scale,
        mut roundoff,
    } = work;
    // Γ of the proportioning test.
    const GAMMA: f64 = 1.0;
    for k in 0..n {
        if bounded[k] {
            lambda[k] = lambda[k].max(0.0);
        }
    }
    let at_bound = |l: &[f64], k: usize| bounded[k] && l[k] <= 0.0;
    // g = Aλ + c.
    apply(lambda, g);
    for k in 0..n {
        g[k] += c[k];
    }
    let mut products = 1usize;
    // Step length of the projected gradient step, ᾱ ≤ 2/‖A‖: from ‖A‖
    // estimated by a few power iterations when first needed.
    let mut alpha_bar: Option<f64> = None;
    let mut restart = true;
    let free_gradient = |l: &[f64], g: &[f64], phi: &mut [f64]| {
        for k in 0..n {
            phi[k] = if at_bound(l, k) { 0.0 } else { g[k] };
        }
    };
    loop {
        free_gradient(lambda, g, phi);
        // Projected gradient: φ plus the chopped gradient β = min(g, 0) at
        // the bound.
        let mut residual = 0.0f64;
        let mut beta2 = 0.0;
        for k in 0..n {
            let b = if at_bound(lambda, k) {
                g[k].min(0.0)
            } else {
                0.0
            };
            residual = residual
                .max(phi[k].abs() * scale[k])
                .max(b.abs() * scale[k]);
            beta2 += b * b;
        }
        if residual <= tolerance {
            return Ok(residual);
        }
        // Within the round-off of the arithmetic: converged as far as it
        // can be.
        if let Some(roundoff) = roundoff.as_deref_mut() {
            let floor = roundoff.floor(lambda, scale, c).max(tolerance);
            let within = (0..n).all(|k| {
                let pg = if at_bound(lambda, k) {
                    g[k].min(0.0)
                } else {
                    g[k]
                };
                pg.abs() * scale[k] <= floor
            });
            if within {
                stats.at_roundoff = true;
                return Ok(residual);
            }
        }
        if products >= max_iterations {
            return Err(SolveError::NoConvergence {
                iterations: products,
                residual,
            });
        }
        let phi2: f64 = phi.iter().map(|x| x * x).sum();
        if beta2 <= GAMMA * GAMMA * phi2 {
            // Proportional: a conjugate gradient step on the free set.
            if restart {
                p.copy_from_slice(phi);
                restart = false;
            }
            apply(p, ap);
            products += 1;
            stats.cg_steps += 1;
            let pap: f64 = (0..n).map(|k| p[k] * ap[k]).sum();
            if pap <= 0.0 {
                return Err(SolveError::Indefinite);
            }
            let gp: f64 = (0..n).map(|k| g[k] * p[k]).sum();
            let alpha_cg = gp / pap;
            // The longest feasible step along −p.
            let mut alpha_f = f64::INFINITY;
            for k in 0..n {
                if bounded[k] && p[k] > 0.0 {
                    alpha_f = alpha_f.min(lambda[k] / p[k]);
                }
            }
            if alpha_cg <= alpha_f {
                for k in 0..n {
                    lambda[k] -= alpha_cg * p[k];
                    g[k] -= alpha_cg * ap[k];
                }
                free_gradient(lambda, g, phi);
                let phi_ap: f64 = (0..n).map(|k| phi[k] * ap[k]).sum();
                let gamma = phi_ap / pap;
                for k in 0..n {
                    p[k] = phi[k] - gamma * p[k];
                }
            } else {
                // Expansion: to the bound, then a projected gradient step.
                for k in 0..n {
                    lambda[k] -= alpha_f * p[k];
                    g[k] -= alpha_f * ap[k];
                    if bounded[k] && lambda[k] < 0.0 {
                        lambda[k] = 0.0;
                    }
                }
                let ab = match alpha_bar {
                    Some(a) => a,
                    None => {
                        let (norm, used) = norm_estimate(n, apply, p, ap);
                        products += used;
                        stats.norm_products += used;
                        let a = 1.0 / norm;
                        alpha_bar = Some(a);
                        a
                    }
                };
                free_gradient(lambda, g, phi);
                for k in 0..n {
                    lambda[k] -= ab * phi[k];
                    if bounded[k] && lambda[k] < 0.0 {
                        lambda[k] = 0.0;
                    }
                }
                apply(lambda, g);
                products += 1;
                stats.expansions += 1;
                for k in 0..n {
                    g[k] += c[k];
                }
                restart = true;
            }
        } else {
            // Proportioning: release the bound multipliers along β.
            for k in 0..n {
                p[k] = if at_bound(lambda, k) {
                    g[k].min(0.0)
                } else {
                    0.0
                };
            }
            apply(p, ap);
            products += 1;
            stats.proportionings += 1;
            let pap: f64 = (0..n).map(|k| p[k] * ap[k]).sum();
            if pap <= 0.0 {
                return Err(SolveError::Indefinite);
            }
            let gp: f64 = (0..n).map(|k| g[k] * p[k]).sum();
            let alpha = gp / pap;
            for k in 0..n {
                lambda[k] -= alpha * p[k];
                g[k] -= alpha * ap[k];
            }
            restart = true;
        }
    }
}

/// ‖A‖ from power iterations (an estimate from below, refined until it
/// changes by less than 1 %), and the products used. `v`, `y` are work.
fn norm_estimate(
    n: usize,
    apply: &mut dyn FnMut(&[f64], &mut [f64]),
    v: &mut [f64],
    y: &mut [f64],
) -> (f64, usize) {
    // A start with no symmetry to hide in.
    for (k, x) in v.iter_mut().enumerate() {
        *x = 1.0 + 0.1 * ((k * 7919) % 13) as f64;
    }
    let mut estimate = 0.0;
    let mut used = 0;
    for _ in 0..12 {
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        v.iter_mut().for_each(|x| *x /= norm);
        apply(v, y);
        used += 1;
        let next = y.iter().map(|x| x * x).sum::<f64>().sqrt();
        v[..n].copy_from_slice(&y[..n]);
        let done = (next - estimate).abs() <= 0.01 * next;
        estimate = next;
        if done {
            break;
        }
    }
    (estimate.max(f64::MIN_POSITIVE), used)
}
