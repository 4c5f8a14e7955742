//! One Newton step of the implicit driver with its contact, by either
//! solver of `simulation.contact_solver` (see [`ContactSolver`]): the
//! paper's condensed multiplier solve on the factorised K̂, or the
//! active-set saddle-point system ([`crate::saddle`]). Both assemble K̂
//! with the contact's stick springs and the pressures' load stiffness,
//! climb the same ladder of membrane tangents, and leave Δx in `dx`, the
//! multipliers and the tools' steps in the contact pass.

use super::*;

/// How the implicit driver solves each Newton iteration's contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ContactSolver {
    /// The paper's (eq. 22–27): factorise K̂, then the condensed
    /// multipliers by preconditioned MPRGP, ~30 solves with the factors
    /// per iteration; the complementarity solved exactly every iteration.
    /// The reference.
    Condensed,
    /// Semi-smooth Newton on the complementarity, one active set per
    /// iteration: one factorisation of the saddle-point system
    /// [K̂ Cᵀ; C −εD] with its rows eliminated onto the nodes
    /// ([`crate::saddle`]) and a few solves with it (`drape_contact`'s
    /// `active_set` module).
    ///
    /// The default: the faster on the four shipped contact scenes
    /// (deep-drawing-0-90: 33.6 s against 60.7 s) and on the quick
    /// work–precision bench's 10 × 10 hemisphere (1.4 s against 2.1 s,
    /// as close to the reference), and it passes the validation cases the
    /// condensed solver passes, at the same tolerances (measurements: the
    /// scene reference, *The implicit solver*, and docs/performance.md).
    #[default]
    ActiveSet,
}

/// What a Newton step's contact solve did.
#[derive(Debug, Clone, Copy, Default)]
pub(in crate::implicit) struct StepCounts {
    /// Solves with the factors.
    pub solves: usize,
    /// Normal rows that entered or left the active set (active-set solver).
    pub active_changes: usize,
}

/// Solves again on one linearisation at most this many times when a step
/// would jump a contact (see [`Implicit::active_set_step`]).
const MAX_RESOLVES: usize = 8;

impl Implicit<'_> {
    /// The condensed step: K̂ factorised, the multipliers by MPRGP.
    pub(super) fn condensed_step(
        &mut self,
        state: &State,
        h: f64,
        mass_factor: f64,
    ) -> Result<StepCounts, (Cutback, String)> {
        let model = self.model;
        let t1 = state.time + h;
        // The contact pass's stick springs and the pressures' load
        // stiffness go into every assembly the ladder of membrane
        // tangents makes, before it factorises.
        let contact = &self.contact;
        let x_iterate = &self.x;
        let factorised = self.tangent.assemble_and_factorise(
            model,
            &self.x,
            &state.history,
            Some(&self.forces.history_new),
            h,
            &self.mass,
            mass_factor,
            &mut |tangent: &mut SparseTangent| {
                if let Some(contact) = contact {
                    contact.add_spring_stiffness(|i, b| tangent.add_node_block(i, b));
                }
                tangent.add_pressure_stiffness(model, x_iterate, t1);
            },
        );
        match factorised {
            Ok((_, assembly)) => self.totals.assembly_seconds += assembly,
            Err(e) => return Err((Cutback::TangentFailure, e.to_string())),
        }
        let fixed = &self.fixed;
        let tangent = &mut self.tangent;
        if let Some(contact) = &self.contact {
            for i in contact.row_nodes() {
                let i = i as usize;
                self.node_blocks[i] = tangent.node_block(i);
            }
        }
        let mut solve = |w: &mut [f64]| {
            for (wi, &f) in w.iter_mut().zip(fixed) {
                if f {
                    *wi = 0.0;
                }
            }
            tangent.solve(w);
            for (wi, &f) in w.iter_mut().zip(fixed) {
                if f {
                    *wi = 0.0;
                }
            }
        };
        let mut counts = StepCounts::default();
        match &mut self.contact {
            Some(contact) => {
                let started = Instant::now();
                let blocks = &self.node_blocks;
                let solved = contact.solve_preconditioned(
                    &self.r,
                    &mut solve,
                    Some(&|i: usize| blocks[i]),
                    &mut self.dx,
                );
                self.totals.contact_seconds += started.elapsed().as_secs_f64();
                match solved {
                    Ok(stats) => {
                        counts.solves = stats.iterations;
                        counts.active_changes = stats.active_changes;
                    }
                    Err(e) => {
                        let reason = match e {
                            SolveError::Indefinite => Cutback::ContactIndefinite,
                            SolveError::NoConvergence { .. } => Cutback::ContactNotConverged,
                        };
                        return Err((reason, e.to_string()));
                    }
                }
            }
            None => {
                self.dx.copy_from_slice(&self.r);
                solve(&mut self.dx);
                counts.solves = 1;
            }
        }
        Ok(counts)
    }

    /// The active-set step: the held rows from the last multipliers and the
    /// gaps at the iterate, one factorisation of the saddle-point system,
    /// its solve refined. K̂ alone is not factorised.
    pub(super) fn active_set_step(
        &mut self,
        state: &State,
        h: f64,
        mass_factor: f64,
    ) -> Result<StepCounts, (Cutback, String)> {
        let model = self.model;
        let t1 = state.time + h;
        let contact = self.contact.as_ref().expect("a contact pass");
        let x_iterate = &self.x;
        let (rows, saddle, fixed) = (&mut self.system_rows, &mut self.saddle, &self.fixed);
        let mut failure: Option<SaddleError> = None;
        let factorised = self.tangent.assemble_and_factorise_with(
            model,
            &self.x,
            &state.history,
            Some(&self.forces.history_new),
            h,
            &self.mass,
            mass_factor,
            &mut |tangent: &mut SparseTangent| {
                contact.add_spring_stiffness(|i, b| tangent.add_node_block(i, b));
                tangent.add_pressure_stiffness(model, x_iterate, t1);
            },
            &mut |tangent: &mut SparseTangent| {
                let block = |i: usize| tangent.node_block(i);
                contact.active_set_rows(&block, false, rows);
                match saddle.factorise(tangent, fixed, contact, rows) {
                    Ok(()) => {
                        failure = None;
                        Ok(true)
                    }
                    Err(e @ SaddleError::Indefinite { .. }) => {
                        failure = Some(e);
                        Ok(false)
                    }
                    Err(e) => {
                        failure = Some(e);
                        Ok(true)
                    }
                }
            },
        );
        match factorised {
            Ok((_, assembly)) => self.totals.assembly_seconds += assembly,
            Err(e) => return Err((Cutback::TangentFailure, e.to_string())),
        }
        match failure {
            None => {}
            // Indefinite on the held rows' null space (compressed resin):
            // the step is taken as the condensed solver takes its LDLᵀ of
            // an indefinite K̂, the line search and the convergence test
            // judging it. Cutting the increment instead was measured
            // (hemisphere 10 × 10, 0/90, physical mass, bending, one
            // core): 341 increments, 2 510 + 735 Newton iterations, 48
            // cutbacks, 3.1 s, against 112, 999 + 50, 2 and 1.0 s.
            Some(SaddleError::Indefinite { .. }) => self.totals.indefinite += 1,
            Some(e) => return Err((Cutback::TangentFailure, e.to_string())),
        }
        let started = Instant::now();
        let contact = self.contact.as_mut().expect("a contact pass");
        self.rhs.copy_from_slice(&self.r);
        contact.add_spring_forces(&mut self.rhs);
        let solves_before = self.saddle.solves;
        let mut changes = 0;
        // A step that would carry a row left out deeper than half the
        // margin into its tool is solved again with the set its gaps ask
        // for (see `drape_contact`'s `active_set` module).
        let jump = 0.5 * contact.settings.margin;
        for round in 0..=MAX_RESOLVES {
            if round > 0 {
                let tangent = &self.tangent;
                let block = |i: usize| tangent.node_block(i);
                contact.active_set_rows(&block, true, &mut self.system_rows);
                if let Err(e) =
                    self.saddle
                        .factorise(&self.tangent, &self.fixed, contact, &self.system_rows)
                {
                    match e {
                        SaddleError::Indefinite { .. } => self.totals.indefinite += 1,
                        e => return Err((Cutback::TangentFailure, e.to_string())),
                    }
                }
            }
            self.saddle.solve(
                &self.rhs,
                &self.fixed,
                contact,
                &self.system_rows,
                contact.settings.tolerance,
                &mut self.dx,
                &mut self.multipliers,
                &mut self.tool_steps,
            );
            let stats = contact.finish_active_set(
                &self.system_rows,
                &self.multipliers,
                &self.tool_steps,
                &self.dx,
            );
            changes += stats.active_changes;
            if contact.unheld_penetration() <= jump {
                break;
            }
        }
        self.totals.contact_seconds += started.elapsed().as_secs_f64();
        self.totals.active_set_changes += changes as u64;
        Ok(StepCounts {
            solves: (self.saddle.solves - solves_before) as usize,
            active_changes: changes,
        })
    }
}
