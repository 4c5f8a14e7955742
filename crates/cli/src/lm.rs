//! Levenberg–Marquardt for small, expensive least-squares problems: each
//! residual vector is a simulation, so the Jacobian is taken by forward
//! differences with its columns evaluated as one batch (the caller runs
//! them in parallel, in a fixed order), and a trial point where the model
//! cannot be evaluated (a shear law that softens, a run that fails) is a
//! rejected step, not the end of the fit.
//!
//! Why not the `levenberg-marquardt` crate: its 0.15 is built on
//! nalgebra 0.34 (the workspace is on 0.35), and it ends the minimisation
//! when a residual cannot be computed, where this fit must step back
//! from a law outside the valid set and go on. Damping as Nielsen
//! (1999): μ·diag(JᵀJ), shrunk by max(1/3, 1 − (2ρ − 1)³) after a good
//! step, doubled and redoubled after a bad one.

use nalgebra::{DMatrix, DVector};

/// Stopping rules.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmOptions {
    /// Most Jacobians (outer iterations).
    pub max_iterations: usize,
    /// Stop when a step changes no parameter by more than this fraction
    /// of its scale.
    pub x_tolerance: f64,
    /// Stop when an accepted step lowers the cost by less than this
    /// fraction.
    pub f_tolerance: f64,
    /// Forward-difference step, a fraction of each parameter's scale.
    pub fd_step: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        Self {
            max_iterations: 30,
            x_tolerance: 1e-6,
            f_tolerance: 1e-8,
            fd_step: 1e-4,
        }
    }
}

/// The result of a minimisation.
#[derive(Debug, Clone, PartialEq)]
pub struct LmResult {
    /// The parameters.
    pub x: DVector<f64>,
    /// Their residuals.
    pub residuals: DVector<f64>,
    /// The Jacobian at `x` (from the last iteration's differences).
    pub jacobian: DMatrix<f64>,
    /// Outer iterations.
    pub iterations: usize,
    /// Residual evaluations (model runs).
    pub evaluations: usize,
    /// Why it stopped.
    pub stop: &'static str,
}

impl LmResult {
    /// ½·|r|².
    pub fn cost(&self) -> f64 {
        0.5 * self.residuals.norm_squared()
    }

    /// Standard errors of the parameters, s·√diag((JᵀJ)⁻¹) with
    /// s² = |r|²/(m − n): the spread the data allow (None when the
    /// Jacobian is singular or m ≤ n).
    pub fn standard_errors(&self) -> Option<DVector<f64>> {
        let (m, n) = self.jacobian.shape();
        if m <= n {
            return None;
        }
        let s2 = self.residuals.norm_squared() / (m - n) as f64;
        let inv = (self.jacobian.transpose() * &self.jacobian).try_inverse()?;
        Some(DVector::from_iterator(
            n,
            (0..n).map(|k| (s2 * inv[(k, k)]).max(0.0).sqrt()),
        ))
    }
}

/// A batch of points in, each one's residuals (or None) out.
pub type BatchEval<'a> = dyn FnMut(&[DVector<f64>]) -> Vec<Option<DVector<f64>>> + 'a;

/// Minimises ½·|r(x)|² from `x0`; `scale` gives each parameter's size
/// (the difference step and the convergence test are relative to it).
/// `eval` takes a batch of points and returns each one's residuals, or
/// None where the model cannot be evaluated.
pub fn minimise(
    x0: DVector<f64>,
    scale: &DVector<f64>,
    options: LmOptions,
    eval: &mut BatchEval<'_>,
) -> Result<LmResult, String> {
    let n = x0.len();
    let mut evaluations = 1;
    let mut r = eval(std::slice::from_ref(&x0))
        .pop()
        .flatten()
        .ok_or("the starting point cannot be evaluated")?;
    let mut x = x0;
    let mut cost = 0.5 * r.norm_squared();
    let mut mu = 1e-3;
    let mut nu = 2.0;
    let mut jacobian = DMatrix::zeros(r.len(), n);
    for iteration in 1..=options.max_iterations {
        // Forward differences; a column whose forward point fails is
        // taken backwards.
        let steps: Vec<f64> = (0..n).map(|k| options.fd_step * scale[k]).collect();
        let forward: Vec<DVector<f64>> = (0..n)
            .map(|k| {
                let mut p = x.clone();
                p[k] += steps[k];
                p
            })
            .collect();
        let mut columns = eval(&forward);
        evaluations += n;
        for k in 0..n {
            let (rk, h) = match columns[k].take() {
                Some(rk) => (rk, steps[k]),
                None => {
                    let mut p = x.clone();
                    p[k] -= steps[k];
                    evaluations += 1;
                    let rk = eval(&[p])
                        .pop()
                        .flatten()
                        .ok_or("the model fails on both sides of a parameter")?;
                    (rk, -steps[k])
                }
            };
            jacobian.set_column(k, &((rk - &r) / h));
        }
        let g = jacobian.transpose() * &r;
        let a = jacobian.transpose() * &jacobian;
        loop {
            let mut damped = a.clone();
            for k in 0..n {
                damped[(k, k)] += mu * a[(k, k)].max(1e-300);
            }
            let Some(delta) = damped.cholesky().map(|c| c.solve(&(-&g))) else {
                mu *= nu;
                nu *= 2.0;
                if mu > 1e20 {
                    return Ok(LmResult {
                        x,
                        residuals: r,
                        jacobian,
                        iterations: iteration,
                        evaluations,
                        stop: "the damped system stayed singular",
                    });
                }
                continue;
            };
            let small = (0..n).all(|k| delta[k].abs() <= options.x_tolerance * scale[k]);
            let trial = &x + &delta;
            evaluations += 1;
            let accepted = match eval(std::slice::from_ref(&trial)).pop().flatten() {
                Some(rt) => {
                    let cost_t = 0.5 * rt.norm_squared();
                    // Predicted decrease of the damped model.
                    let mut d = delta.clone();
                    for k in 0..n {
                        d[k] *= mu * a[(k, k)];
                    }
                    let predicted = 0.5 * delta.dot(&(d - &g));
                    let rho = (cost - cost_t) / predicted.max(1e-300);
                    (rho > 0.0).then_some((rt, cost_t, rho))
                }
                None => None,
            };
            match accepted {
                Some((rt, cost_t, rho)) => {
                    let gain = (cost - cost_t) / cost.max(1e-300);
                    x = trial;
                    r = rt;
                    cost = cost_t;
                    mu *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
                    nu = 2.0;
                    if small || gain < options.f_tolerance {
                        return Ok(LmResult {
                            x,
                            residuals: r,
                            jacobian,
                            iterations: iteration,
                            evaluations,
                            stop: if small {
                                "the step fell below the parameter tolerance"
                            } else {
                                "the cost stopped falling"
                            },
                        });
                    }
                    break;
                }
                None => {
                    if small {
                        return Ok(LmResult {
                            x,
                            residuals: r,
                            jacobian,
                            iterations: iteration,
                            evaluations,
                            stop: "no smaller step lowers the cost",
                        });
                    }
                    mu *= nu;
                    nu *= 2.0;
                }
            }
        }
    }
    Ok(LmResult {
        x,
        residuals: r,
        jacobian,
        iterations: options.max_iterations,
        evaluations,
        stop: "the iteration limit",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y = a·exp(−b·t) + c from exact samples: found from a poor start,
    /// and a region the model refuses (b < 0.5) is stepped around, not
    /// fatal; the standard errors vanish with the residuals.
    #[test]
    fn an_exponential_is_fitted_around_a_forbidden_region() {
        let truth = [2.0, 0.7, 0.3];
        let t: Vec<f64> = (0..30).map(|k| 0.2 * k as f64).collect();
        let model = |p: &DVector<f64>| {
            (p[1] >= 0.5).then(|| {
                DVector::from_iterator(
                    t.len(),
                    t.iter().map(|&t| {
                        p[0] * (-p[1] * t).exp() + p[2]
                            - (truth[0] * (-truth[1] * t).exp() + truth[2])
                    }),
                )
            })
        };
        let mut calls = 0;
        let result = minimise(
            DVector::from_vec(vec![1.0, 2.0, 0.0]),
            &DVector::from_vec(vec![1.0, 1.0, 1.0]),
            LmOptions::default(),
            &mut |ps| {
                calls += ps.len();
                ps.iter().map(model).collect()
            },
        )
        .unwrap();
        for (x, t) in result.x.iter().zip(truth) {
            assert!((x - t).abs() < 1e-6, "{:?}", result.x);
        }
        assert_eq!(result.evaluations, calls);
        assert!(result.standard_errors().unwrap().max() < 1e-6);
    }

    /// Noisy samples: the standard error of a straight line's slope is
    /// the textbook s/√Σ(t − t̄)².
    #[test]
    fn standard_errors_are_the_linear_regression_ones() {
        let t: Vec<f64> = (0..10).map(|k| k as f64).collect();
        let noise = [0.1, -0.2, 0.05, 0.0, 0.15, -0.1, -0.05, 0.2, -0.15, 0.0];
        let y: Vec<f64> = t
            .iter()
            .zip(noise)
            .map(|(t, e)| 1.0 + 0.5 * t + e)
            .collect();
        let result = minimise(
            DVector::from_vec(vec![0.0, 0.0]),
            &DVector::from_vec(vec![1.0, 1.0]),
            LmOptions::default(),
            &mut |ps| {
                ps.iter()
                    .map(|p| {
                        Some(DVector::from_iterator(
                            10,
                            t.iter().zip(&y).map(|(t, y)| p[0] + p[1] * t - y),
                        ))
                    })
                    .collect()
            },
        )
        .unwrap();
        let s = (result.residuals.norm_squared() / 8.0).sqrt();
        let sxx: f64 = t.iter().map(|t| (t - 4.5).powi(2)).sum();
        let se = result.standard_errors().unwrap();
        assert!((se[1] - s / sxx.sqrt()).abs() < 1e-6 * se[1], "{se}");
    }
}
