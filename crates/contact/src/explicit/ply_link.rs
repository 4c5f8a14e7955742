//! The explicit pass's link to the ply–ply contact of a laminate
//! ([`crate::PlyContact`]): the tools' active constraints handed to it as
//! supports (their added multipliers going back to the tools' forces),
//! and the tools' friction solved together with the plies'.

use nalgebra::Vector3;

use super::{ContactStatus, ExplicitContact};
use crate::phases::{ContactPhase, PhaseTimer};
use crate::plies::{Support, ToolFriction};

impl ExplicitContact {
    /// The ply pass of a step without tool constraints.
    pub(super) fn ply_pass(
        &mut self,
        x: &mut [Vector3<f64>],
        v: &mut [Vector3<f64>],
        mass: &[f64],
        movable: &[bool],
        dt: f64,
        tau: f64,
    ) {
        if self.plies.is_some() {
            self.ply_normal(x, v, mass, movable, dt, tau);
            self.ply_friction(x, v, mass, movable, dt, tau);
        }
    }

    /// The plies' friction solved with the tools' on the nodes that touch
    /// both (see [`crate::PlyContact::friction`]); the tools' forces and statuses
    /// updated by what the joint solve changed.
    pub(super) fn ply_friction(
        &mut self,
        x: &mut [Vector3<f64>],
        v: &mut [Vector3<f64>],
        mass: &[f64],
        movable: &[bool],
        dt: f64,
        tau: f64,
    ) {
        let Some(plies) = &mut self.plies else {
            return;
        };
        let lambda_scale = 1.0 / (dt * tau);
        self.tool_friction.clear();
        let mut applied = self.scratch.applied.iter().peekable();
        for (k, c) in self.constraints.iter().enumerate() {
            let tool = &self.tools[c.tool as usize];
            let f = match applied.peek() {
                Some(&&(a, f)) if a as usize == k => {
                    applied.next();
                    f
                }
                _ => Vector3::zeros(),
            };
            if tool.friction == 0.0 || c.mu <= 0.0 {
                continue;
            }
            self.tool_friction.push(ToolFriction {
                node: c.node,
                normal: c.normal,
                tool_velocity: tool.motion.direction() * self.tool_state[c.tool as usize].velocity,
                cap: tool.friction * c.mu * lambda_scale,
                force: f,
            });
        }
        // The tool pass's own friction was timed already.
        PhaseTimer::lap(&mut self.phases, ContactPhase::Friction);
        let before = self.tool_friction.len();
        self.tool_old.clear();
        self.tool_old
            .extend(self.tool_friction.iter().map(|t| t.force));
        plies.friction(
            x,
            v,
            mass,
            movable,
            dt,
            tau,
            &mut self.tool_friction,
            &mut self.force,
        );
        debug_assert_eq!(before, self.tool_friction.len());
        for (t, old) in self.tool_friction.iter().zip(&self.tool_old) {
            let d = t.force - old;
            if d == Vector3::zeros() {
                continue;
            }
            let i = t.node as usize;
            self.force[i] += d;
            self.status[i] = if t.force.norm() >= t.cap * (1.0 - 1e-12) {
                ContactStatus::Slip
            } else {
                ContactStatus::Stick
            };
        }
        PhaseTimer::lap(&mut self.phases, ContactPhase::Plies);
    }

    /// The plies' normal constraints with the active tool constraints as
    /// supports; what a support needs is added to its tool constraint's
    /// multiplier, force and the tool's reaction.
    pub(super) fn ply_normal(
        &mut self,
        x: &mut [Vector3<f64>],
        v: &mut [Vector3<f64>],
        mass: &[f64],
        movable: &[bool],
        dt: f64,
        tau: f64,
    ) {
        let Some(plies) = &mut self.plies else {
            return;
        };
        self.supports.clear();
        self.supports.extend(
            self.constraints
                .iter()
                .filter(|c| c.mu > 0.0)
                .map(|c| Support {
                    node: c.node,
                    normal: c.normal,
                    mu: 0.0,
                }),
        );
        plies.normal(
            x,
            v,
            mass,
            movable,
            dt,
            tau,
            &mut self.supports,
            &mut self.force,
        );
        let lambda_scale = 1.0 / (dt * tau);
        for (k, c) in self
            .constraints
            .iter_mut()
            .filter(|c| c.mu > 0.0)
            .enumerate()
        {
            let nu = self.supports[k].mu;
            if nu == 0.0 {
                continue;
            }
            c.mu += nu;
            let lambda = nu * lambda_scale;
            self.force[c.node as usize] += c.normal * lambda;
            let axis = self.tools[c.tool as usize].motion.direction();
            self.tool_force[c.tool as usize] += if axis == Vector3::zeros() {
                lambda
            } else {
                c.normal.dot(&axis) * lambda
            };
        }
        PhaseTimer::lap(&mut self.phases, ContactPhase::Plies);
    }
}
