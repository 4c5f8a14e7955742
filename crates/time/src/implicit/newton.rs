//! One Newton attempt at an increment of the implicit driver: the
//! iterations from the predictor to convergence or to a reason to cut the
//! increment (the driver's `advance` decides what to do with either).

use super::*;

impl Implicit<'_> {
    /// One attempt at the increment of size `h` from `state`; the iterate
    /// is left in `self.x`, `self.v`, `self.a`, the forces in the force
    /// pass and the contact pass.
    pub(super) fn attempt(&mut self, state: &State, h: f64) -> Result<Converged, Failure> {
        let model = self.model;
        let inc = self.increment(state.time, h);
        let t1 = inc.t_new;
        let settings = self.settings.clone();
        // Predictor: constant velocity (see `predictor`); prescribed
        // components at their values.
        {
            let (x_n, v_n) = (&state.x, &state.v);
            self.x
                .par_iter_mut()
                .with_min_len(1024)
                .enumerate()
                .for_each(|(i, x)| *x = predictor(x_n[i], v_n[i], h));
        }
        for c in &self.constraints.list {
            let (i, k) = (c.node as usize, c.component as usize);
            self.x[i][k] = Constraints::position(model, c, state.x[i][k], state.time, h);
        }
        shared::external_forces(model, t1, &mut self.f_ext);
        if let Some(contact) = &mut self.contact {
            contact.begin(&self.x, &self.constraints.movable, inc);
        }
        let mass_factor = inc.mass_factor() + settings.damping * self.gamma / (self.beta * h);
        let heaviest = self.mass.iter().copied().fold(0.0, f64::max);
        let floor = 1e-6 * self.size;
        let mut step_taken = false;
        let mut alpha = 1.0;
        let mut merit_prev = f64::INFINITY;
        let mut correction = 0.0f64;
        let mut newton = 0usize;
        self.tangent.begin_attempt();
        let mut contact_iterations = 0usize;
        let mut active_changes = 0usize;
        let mut step_changes = 0usize;
        let factorisations_before = self.tangent.factorisations + self.saddle.factorisations;
        let mut switched = 0usize;
        // The residuals over their force scale of the last two iterations,
        // oldest first.
        let mut residuals = [f64::INFINITY; 2];
        // Whether the last step was the whole Newton step (not halved for
        // a cycle).
        let mut full_step = true;
        let fail =
            |newton: usize, totals: &mut ImplicitTotals, reason: Cutback, message: String| {
                totals.wasted_iterations += newton as u64;
                Err(Failure { reason, message })
            };
        loop {
            let evaluated = self.forces.evaluate(
                model,
                &self.x,
                None,
                &state.history,
                h,
                state.step + 1,
                t1,
                None,
            );
            let mut friction_changes = 0;
            if !self.pressure.is_empty() {
                // The pressures follow the iterate: f_ext of x_{n+1}.
                shared::external_forces(model, t1, &mut self.f_ext);
                self.pressure.add_into(model, &self.x, t1, &mut self.f_ext);
            }
            let (res, node, scale) = match evaluated {
                Ok(()) => {
                    if let Some(contact) = &mut self.contact {
                        if step_taken {
                            // Stick and slip settle pair by pair, but pairs
                            // at the edge of the friction cone that slip
                            // together can cycle stick → slip → stick until
                            // the attempt is cut. After `SETTLE` iterations
                            // a slip must run along its friction force by a
                            // `SETTLED_REVERSAL` fraction of the
                            // increment's motion before the pair sticks
                            // again.
                            let reversal = if newton >= SETTLE {
                                SETTLED_REVERSAL
                                    * self
                                        .x
                                        .iter()
                                        .zip(&state.x)
                                        .map(|(a, b)| (a - b).amax())
                                        .fold(0.0, f64::max)
                            } else {
                                0.0
                            };
                            friction_changes = contact.update_friction(&self.x, reversal);
                        }
                        contact.linearise(&self.x, &state.x);
                    }
                    self.residual(state, &inc)
                }
                Err(e) => (f64::NAN, usize::MAX, {
                    if !(step_taken && alpha > 1.0 / 16.0) {
                        return fail(
                            newton,
                            &mut self.totals,
                            Cutback::ElementFailure,
                            e.to_string(),
                        );
                    }
                    f64::NAN
                }),
            };
            // More than doubled, or not finite. A residual that rises
            // because contact or friction states changed is the next
            // iteration's business, not the step length's.
            let worse = (res > 2.0 * merit_prev || res.is_nan())
                && (friction_changes == 0 || !res.is_finite());
            if step_taken
                && worse
                && alpha > 1.0 / 16.0
                && (res > settings.force_tolerance * scale || res.is_nan())
            {
                // Line search: halve the step.
                alpha *= 0.5;
                for (i, x) in self.x.iter_mut().enumerate() {
                    for k in 0..3 {
                        x[k] = self.x_step[i][k] + alpha * self.dx[3 * i + k];
                    }
                }
                if let Some(contact) = &mut self.contact {
                    contact.apply_step(-alpha);
                }
                correction *= 0.5;
                continue;
            }
            if !res.is_finite() {
                return fail(
                    newton,
                    &mut self.totals,
                    Cutback::NotFinite,
                    format!("the residual is not finite after {newton} iterations"),
                );
            }
            if let Some(contact) = &mut self.contact {
                contact.set_force_floor(settings.force_tolerance * scale);
            }
            let increment = self
                .x
                .iter()
                .zip(&state.x)
                .map(|(a, b)| (a - b).amax())
                .fold(0.0, f64::max);
            let (pen, stick_slip, imbalance) = self.contact.as_ref().map_or((0.0, 0.0, 0.0), |c| {
                let (p, s) = c.violation();
                (p, s, c.tool_imbalance())
            });
            if let Some(record) = &mut self.record {
                let contact = self.contact.as_ref();
                let (sticking, slipping) = contact.map_or((0, 0), |c| c.friction_census());
                let worst_contact = match contact.and_then(|c| c.friction_at(node as u32)) {
                    None => 0,
                    Some(drape_contact::Friction::Stick) => 1,
                    Some(drape_contact::Friction::Slip) => 2,
                };
                record.push(NewtonRecord {
                    increment: state.step + 1,
                    iteration: newton,
                    residual: res,
                    scale,
                    correction,
                    active_changes: step_changes,
                    friction_changes,
                    sticking,
                    slipping,
                    slip_lag: if newton > 0 {
                        contact.map_or(0.0, |c| c.slip_lag())
                    } else {
                        0.0
                    },
                    worst_contact,
                    penetration: pen,
                    stick_slip,
                    imbalance,
                    h,
                    step_cosine: self.step_angle.0,
                    step_ratio: self.step_angle.1,
                    step_taken: alpha * self.step_angle.2,
                });
            }
            if friction_changes > 0 {
                switched += 1;
            }
            // Where the last full step cut the residual at least tenfold,
            // the next correction is estimated as the last one times that
            // contraction (see `QUADRATIC`), and need not be taken to be
            // shown small.
            let contraction = res / merit_prev;
            let next_correction = if alpha == 1.0 && full_step && contraction <= QUADRATIC {
                correction * contraction
            } else {
                correction
            };
            let forces_pass = (res <= settings.force_tolerance * scale
                && (newton == 0
                    || next_correction <= settings.displacement_tolerance * increment.max(floor)))
                || (newton > 0 && {
                    // Below the tolerance f64 cannot go: a small enough
                    // increment puts the inertia term's round-off above it
                    // (see `crate::round_off`).
                    let coordinate = self.x.iter().map(|x| x.amax()).fold(0.0, f64::max);
                    RoundOffFloor::new(
                        heaviest * mass_factor + self.tangent.max_stiffness,
                        coordinate,
                        scale,
                    )
                    .reached(res, correction)
                });
            let converged = forces_pass
                && pen <= settings.gap_tolerance
                && stick_slip <= settings.gap_tolerance
                && friction_changes == 0
                && imbalance <= settings.force_tolerance * scale;
            if converged {
                self.totals.newton_iterations += newton as u64;
                self.totals.contact_iterations += contact_iterations as u64;
                return Ok(Converged {
                    newton,
                    active_changes,
                    factorisations: (self.tangent.factorisations + self.saddle.factorisations
                        - factorisations_before) as usize,
                    switched,
                    contact_iterations,
                });
            }
            if newton >= settings.max_iterations {
                let reason = if friction_changes > 0 {
                    Cutback::FrictionChatter
                } else {
                    Cutback::NewtonLimit
                };
                return fail(
                    newton,
                    &mut self.totals,
                    reason,
                    format!(
                        "{newton} Newton iterations: residual {res:.3e} N at node {node} (force scale {scale:.3e} N), \
                         last correction {correction:.3e} mm, penetration {pen:.3e} mm, \
                         stick slip {stick_slip:.3e} mm, {friction_changes} friction states changed"
                    ),
                );
            }
            // The Newton step.
            let step = match (&self.contact, settings.contact_solver) {
                (Some(_), ContactSolver::ActiveSet) => self.active_set_step(state, h, mass_factor),
                _ => self.condensed_step(state, h, mass_factor),
            };
            match step {
                Ok(counts) => {
                    contact_iterations += counts.solves;
                    active_changes += counts.active_changes;
                    step_changes = counts.active_changes;
                }
                Err((reason, message)) => {
                    return fail(newton, &mut self.totals, reason, message);
                }
            }
            // A residual not below `CYCLE` times the one two iterations
            // back: Newton is cycling between contact or friction states
            // (see `CYCLE`); half the step breaks the cycle.
            let relative = res / scale;
            // The step against the last one (see `ALONG`, `NewtonRecord`).
            self.step_angle = if newton > 0 {
                let (cosine, ratio) = step_angle(&self.dx, &self.dx_before);
                (cosine, ratio, 1.0)
            } else {
                (0.0, 0.0, 1.0)
            };
            self.dx_before.clone_from(&self.dx);
            // Measured with the active-set solver only (see `ALONG`); the
            // condensed solve, the reference, keeps its path.
            let along = match (&self.contact, settings.contact_solver) {
                (Some(_), ContactSolver::ActiveSet) => self.step_angle.0,
                _ => 0.0,
            };
            let halved = halves(newton, relative, residuals[0], along);
            if halved {
                self.step_angle.2 = 0.5;
                self.dx.iter_mut().for_each(|d| *d *= 0.5);
                if let Some(contact) = &mut self.contact {
                    contact.scale_step(0.5);
                }
            }
            full_step = !halved;
            residuals = [residuals[1], relative];
            newton += 1;
            self.x_step.copy_from_slice(&self.x);
            for (i, x) in self.x.iter_mut().enumerate() {
                for k in 0..3 {
                    x[k] += self.dx[3 * i + k];
                }
            }
            if let Some(contact) = &mut self.contact {
                contact.apply_step(1.0);
            }
            alpha = 1.0;
            merit_prev = res;
            step_taken = true;
            let last = correction;
            correction = self.dx.iter().fold(0.0f64, |m, d| m.max(d.abs()));
            // A correction longer than the whole model, and at least twice
            // the last one, is divergence (see `DIVERGED`).
            if diverging(newton, correction, last, self.size) {
                return fail(
                    newton,
                    &mut self.totals,
                    Cutback::Diverged,
                    format!(
                        "Newton diverged: correction {correction:.3e} mm after {newton} iterations \
                         ({last:.3e} mm the one before), longer than the model ({:.3e} mm); \
                         residual {res:.3e} N at node {node} (force scale {scale:.3e} N)",
                        self.size
                    ),
                );
            }
        }
    }
}

/// The cosine of the angle between a Newton step and the last one, and
/// their length ratio; zeros where either step is zero.
fn step_angle(dx: &[f64], before: &[f64]) -> (f64, f64) {
    let dot: f64 = dx.iter().zip(before).map(|(a, b)| a * b).sum();
    let a = dx.iter().map(|a| a * a).sum::<f64>().sqrt();
    let b = before.iter().map(|b| b * b).sum::<f64>().sqrt();
    if a > 0.0 && b > 0.0 && dx.len() == before.len() {
        (dot / (a * b), a / b)
    } else {
        (0.0, 0.0)
    }
}

/// Whether the `newton`th step is halved as a cycle (see `CYCLE`): its
/// residual over the force scale, `relative`, not below `CYCLE` times
/// `two_back`'s, and the step not along the last one (`cosine` above
/// `ALONG`).
fn halves(newton: usize, relative: f64, two_back: f64, cosine: f64) -> bool {
    newton >= 3 && relative >= CYCLE * two_back && cosine <= ALONG
}

/// Whether the `newton`th correction (mm), after `last`, shows Newton
/// diverging on a model of `size` (its bounding-box diagonal, mm): see
/// `DIVERGED`.
fn diverging(newton: usize, correction: f64, last: f64, size: f64) -> bool {
    newton >= 2 && correction > size && correction > DIVERGED * last
}

#[cfg(test)]
mod tests {
    use super::{diverging, halves, step_angle};

    /// From `DRAPE_NEWTON_TRACE` of hemisphere-0-90 (increment 74's cut
    /// attempt): the residual over its scale falling 7.5e-2, 7.8e-2, 7.6e-2
    /// along steps at cosines of 0.999 to each other, which the cycle rule
    /// halved to the iteration limit; a step that turns back with the same
    /// residuals (a stick/slip cycle, cosine −0.9) is still halved, and so
    /// is one at a right angle.
    #[test]
    fn a_slow_step_along_the_last_is_not_halved_a_turning_one_is() {
        let (along, _) = step_angle(&[0.2, -0.1, 1e-3], &[0.19, -0.1, 1e-3]);
        assert!(along > 0.999, "{along}");
        assert!(!halves(15, 7.6e-2, 7.5e-2, along));
        assert!(halves(15, 7.6e-2, 7.5e-2, -0.9));
        assert!(halves(15, 7.6e-2, 7.5e-2, 0.0));
        // Not before the third iteration, nor where the residual halved.
        assert!(!halves(2, 7.6e-2, 7.5e-2, -0.9));
        assert!(!halves(15, 3e-2, 7.5e-2, -0.9));
        assert_eq!(step_angle(&[1.0, 0.0], &[0.0, 0.0]), (0.0, 0.0));
        let (back, ratio) = step_angle(&[1.0, 0.0], &[-2.0, 0.0]);
        assert_eq!((back, ratio), (-1.0, 0.5));
    }

    /// The corrections of a cut attempt of hemisphere-0-90 (mm, from
    /// `DRAPE_NEWTON_TRACE`) are cut where they pass the model's 495 mm;
    /// a blank falling far in one increment (a first correction longer
    /// than the model that then shrinks) and a converging attempt's
    /// largest corrections are not.
    #[test]
    fn only_a_growing_correction_longer_than_the_model_is_divergence() {
        let size = 495.0;
        let first_cut = |corrections: &[f64]| {
            (2..corrections.len()).find(|&k| diverging(k, corrections[k], corrections[k - 1], size))
        };
        let diverged = [0.0, 18.0, 69.0, 300.0, 2.1e3, 1.5e4, 1.3e5];
        assert_eq!(first_cut(&diverged), Some(4));
        let falling = [0.0, 2.0e3, 40.0, 0.3, 1e-3];
        assert_eq!(first_cut(&falling), None);
        let falling_again = [0.0, 600.0, 900.0, 20.0];
        assert_eq!(first_cut(&falling_again), None);
        let converging = [0.0, 2.0, 6.6, 1.2, 0.01];
        assert_eq!(first_cut(&converging), None);
    }
}
