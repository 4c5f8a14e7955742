//! The explicit pass's link to the ply–ply contact of a laminate
//! ([`crate::PlyContact`]): the tools' active constraints handed to it as
//! supports (their added multipliers going back to the tools' forces),
//! and the tools' friction solved together with the plies'.

use nalgebra::Vector3;

use super::{Constraint, ContactStatus, ExplicitContact};
use crate::phases::{ContactPhase, PhaseTimer};
use crate::plies::{DrivenTool, Support, ToolFriction};
use crate::tool::ToolMotion;

impl ExplicitContact {
    /// The ply pass of a step without tool constraints.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn ply_pass(
        &mut self,
        x: &mut [Vector3<f64>],
        v: &mut [Vector3<f64>],
        mass: &[f64],
        movable: &[bool],
        dt: f64,
        tau: f64,
        tool_mass_factor: f64,
    ) {
        if self.plies.is_some() {
            self.ply_normal(x, v, mass, movable, dt, tau, tool_mass_factor);
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
    /// multiplier, force and the tool's reaction, and a force-driven tool
    /// moves by what its supports added (`tool_mass_factor` as in
    /// [`ExplicitContact::enforce_step`]).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn ply_normal(
        &mut self,
        x: &mut [Vector3<f64>],
        v: &mut [Vector3<f64>],
        mass: &[f64],
        movable: &[bool],
        dt: f64,
        tau: f64,
        tool_mass_factor: f64,
    ) {
        let Some(plies) = &mut self.plies else {
            return;
        };
        let tools = &self.tools;
        // A near node's gap is ≥ 0; a pressed one's is set to 0 below.
        let support = |c: &Constraint| Support {
            node: c.node,
            normal: c.normal,
            gap: c.gap,
            mu: 0.0,
            driven: match &tools[c.tool as usize].motion {
                ToolMotion::Force {
                    direction,
                    mass: m_tool,
                    ..
                } => Some(DrivenTool {
                    tool: c.tool,
                    along: c.normal.dot(direction),
                    inverse_mass: 1.0 / (m_tool * tool_mass_factor),
                    held: c.mu,
                }),
                _ => None,
            },
        };
        // The pressed nodes (on their tools after the tool pass: gap 0),
        // then the nodes near a tool that no constraint holds.
        self.supports.clear();
        self.supports.extend(
            self.constraints
                .iter()
                .filter(|c| c.mu > 0.0)
                .map(|c| Support {
                    gap: 0.0,
                    ..support(c)
                }),
        );
        // A near node already held by a constraint of the same tool (one
        // the tool pass added and left open) is not listed twice: its
        // entry is marked with μ = −1.
        let held_by = &mut self.scratch.held_by;
        held_by.resize(self.status.len(), 0);
        let bit = |t: u32| if t < 64 { 1u64 << t } else { 0 };
        for c in &self.constraints {
            held_by[c.node as usize] |= bit(c.tool);
        }
        let pressed = self.supports.len();
        for c in &mut self.scratch.near {
            let held = if c.tool < 64 {
                held_by[c.node as usize] & bit(c.tool) != 0
            } else {
                self.constraints
                    .iter()
                    .any(|d| d.node == c.node && d.tool == c.tool)
            };
            if held {
                c.mu = -1.0;
            } else {
                self.supports.push(support(c));
            }
        }
        for c in &self.constraints {
            held_by[c.node as usize] = 0;
        }
        let shift = &mut self.scratch.ply_tool_shift;
        shift.resize(tools.len(), 0.0);
        plies.normal(
            x,
            v,
            mass,
            movable,
            dt,
            tau,
            &mut self.supports,
            shift,
            &mut self.force,
        );
        for (state, &du) in self.tool_state.iter_mut().zip(shift.iter()) {
            state.displacement += du;
            state.velocity += du / dt;
        }
        let lambda_scale = 1.0 / (dt * tau);
        let add = |c: &Constraint, nu: f64, force: &mut [Vector3<f64>], tool_force: &mut [f64]| {
            let lambda = nu * lambda_scale;
            force[c.node as usize] += c.normal * lambda;
            let axis = tools[c.tool as usize].motion.direction();
            tool_force[c.tool as usize] += if axis == Vector3::zeros() {
                lambda
            } else {
                c.normal.dot(&axis) * lambda
            };
        };
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
            add(c, nu, &mut self.force, &mut self.tool_force);
        }
        // A near node the ply pass pressed onto its tool becomes one of
        // the tool's constraints (its friction, its status).
        let mut k = pressed;
        for c in &self.scratch.near {
            if c.mu < 0.0 {
                continue;
            }
            let nu = self.supports[k].mu;
            k += 1;
            if nu <= 0.0 {
                continue;
            }
            let c = Constraint { mu: nu, ..*c };
            add(&c, nu, &mut self.force, &mut self.tool_force);
            let i = c.node as usize;
            self.status[i] = ContactStatus::Stick;
            self.tool_of[i] = c.tool;
            self.touched.push(c.node);
            self.constraints.push(c);
        }
        PhaseTimer::lap(&mut self.phases, ContactPhase::Plies);
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use crate::plies::{NORMAL_COMPLIANCE, NORMAL_TOLERANCE, PlyContact, PlyInterface, fixtures};
    use crate::surface::Surface;
    use crate::tool::{Amplitude, Tool, ToolMotion};
    use crate::{ContactSettings, ExplicitContact};

    /// Two unit squares of thickness h, one on the other (μ_ply = 0), as
    /// `contact`'s ply pass with the rows' `compliance`; their nodes'
    /// positions, the bottom ply's on z = h/2.
    fn two_plies(contact: &mut ExplicitContact, h: f64, compliance: f64) -> Vec<Vector3<f64>> {
        let mut plies = PlyContact::new(
            vec![
                fixtures::square_layer(0, 0.5 * h),
                fixtures::square_layer(4, 0.5 * h),
            ],
            &[PlyInterface {
                lower: 0,
                upper: 1,
                friction: 0.0,
            }],
            vec![0.25; 8],
            1.0,
        );
        plies.compliance = compliance;
        contact.set_plies(plies);
        let square = |z: f64| {
            [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].map(|[x, y]| Vector3::new(x, y, z))
        };
        let mut x = square(0.5 * h).to_vec();
        x.extend(square(1.5 * h));
        x
    }

    /// Two plies (unit squares, thickness h) on a floor under a blank
    /// holder pressed down by F, the holder's face on the top ply: the
    /// holder's force goes through both plies into the floor. The tool
    /// pass alone pushes the top ply into the bottom one by the holder's
    /// predictor; with the holder held where the tool pass left it, the ply
    /// pass cannot put the plies apart (the stack shipped as a deep drawing
    /// threw a node 0.75 mm in one step). With rigid ply rows nothing
    /// moves; with the compliant rows of a run the top ply and the holder
    /// settle by the rows' give, every column alike, and then carry the
    /// force.
    #[test]
    fn a_stack_pressed_by_a_force_driven_holder_carries_its_force_to_the_floor() {
        // The holder weighs the top ply, as the shipped deep drawing's
        // holder weighs about its blank: the sweeps converge in ~24 (a
        // holder much heavier than the nodes it presses converges slowly:
        // at 25 times their mass it ran out of sweeps 1e-5 short).
        let (h, m, f, holder_mass, dt) = (0.1, 1e-6, 3.0, 4e-6, 1e-5);
        // What the holder's force moves it by in a step (mm), the
        // violation the ply pass starts from; its solve stops at its
        // tolerance of it, and so do the positions and the forces.
        let squeeze = f * dt * dt / holder_mass;
        let tolerance = NORMAL_TOLERANCE * squeeze;
        for kappa in [0.0, NORMAL_COMPLIANCE] {
            // A column's row at rest carries F/4, which alone would move
            // its two nodes apart by (F/4)·Δt²·(2/m) in a step: the row
            // holds its gap at κ times that.
            let give = kappa * 0.25 * f * dt * dt * 2.0 / m;
            let floor = Tool {
                name: "floor".into(),
                surface: Surface::plane(Vector3::zeros(), Vector3::z()).unwrap(),
                motion: ToolMotion::Fixed,
                friction: 0.0,
            };
            let holder = Tool {
                name: "holder".into(),
                surface: Surface::plane(Vector3::new(0.0, 0.0, 2.0 * h), -Vector3::z()).unwrap(),
                motion: ToolMotion::Force {
                    direction: -Vector3::z(),
                    force: f,
                    amplitude: Amplitude::Constant,
                    mass: holder_mass,
                },
                friction: 0.0,
            };
            let settings = ContactSettings {
                offset: 0.5 * h,
                ..ContactSettings::default()
            };
            let mut contact = ExplicitContact::new(vec![floor, holder], 8, settings);
            let mut x = two_plies(&mut contact, h, kappa);
            let start = x.clone();
            let mut v = vec![Vector3::zeros(); 8];
            for step in 1..=20 {
                contact
                    .enforce(&mut x, &mut v, &[m; 8], &[true; 8], step as f64 * dt, dt)
                    .unwrap();
                let sink: Vec<f64> = (4..8).map(|i| start[i].z - x[i].z).collect();
                let holder = contact.tool_state[1].displacement;
                for i in 0..4 {
                    let p = x[i];
                    assert!(
                        (p - start[i]).norm() < tolerance,
                        "κ {kappa}, step {step}: node {i} at {p:?}"
                    );
                    let p = x[i + 4];
                    assert!(
                        (p.xy() - start[i + 4].xy()).norm() < tolerance,
                        "κ {kappa}, step {step}: node {} at {p:?}",
                        i + 4
                    );
                    // Every column alike: the rows' share is unique.
                    assert!(
                        (sink[i] - holder).abs() < tolerance,
                        "κ {kappa}, step {step}: node {} sank {} with the holder at {holder}",
                        i + 4,
                        sink[i]
                    );
                }
                // While the holder rings on the rows' give (ten steps) it
                // sinks at most 4 % beyond it; then it rests there and
                // carries its force.
                assert!(
                    holder > -tolerance && holder < 1.04 * give + tolerance,
                    "κ {kappa}, step {step}: holder moved {holder} (give {give})"
                );
                if step < 10 && kappa > 0.0 {
                    continue;
                }
                assert!(
                    (holder - give).abs() < tolerance,
                    "κ {kappa}, step {step}: holder moved {holder} (give {give})"
                );
                for (t, &carried) in contact.tool_force.iter().enumerate() {
                    assert!(
                        (carried - f).abs() < NORMAL_TOLERANCE * f,
                        "κ {kappa}, step {step}: tool {t} carries {carried} N of {f}"
                    );
                }
            }
        }
    }

    /// A top ply near a lid (within the offset of touching it) is pushed up
    /// by a heavy bottom ply rising into it: the lid must hold it, as a
    /// near support, even where the tool pass did not project the node
    /// again this step (it had not moved since it was last projected, far
    /// enough by the tool contact's own reach). The skip missed that band,
    /// and the ply pass pushed the top ply into the lid.
    #[test]
    fn a_node_near_a_tool_is_held_though_its_projection_was_skipped() {
        let (h, dt) = (0.1, 1e-5);
        let offset = 0.5 * h;
        // The lid 1.9 offsets above the top ply's mid-surface: 0.9 offset
        // of room before it touches.
        let lid_z = 1.5 * h + 1.9 * offset;
        let lid = Tool {
            name: "lid".into(),
            surface: Surface::plane(Vector3::new(0.0, 0.0, lid_z), -Vector3::z()).unwrap(),
            motion: ToolMotion::Fixed,
            friction: 0.0,
        };
        let settings = ContactSettings {
            offset,
            ..ContactSettings::default()
        };
        let mut contact = ExplicitContact::new(vec![lid], 8, settings);
        // Rigid rows: the lid's hold is what this measures.
        let mut x = two_plies(&mut contact, h, 0.0);
        let mut v = vec![Vector3::zeros(); 8];
        // The bottom ply ten times heavier: it pushes the top ply up by
        // 10/11 of what it rises into it.
        let mut mass = [1e-5; 8];
        mass[4..].fill(1e-6);
        contact
            .enforce(&mut x, &mut v, &mass, &[true; 8], dt, dt)
            .unwrap();
        // The bottom ply rises by 1.2 offsets in a step: the top one would
        // go 0.19 offset into the lid.
        let rise = 1.2 * offset;
        for i in 0..4 {
            x[i].z += rise;
            v[i].z = rise / dt;
        }
        contact
            .enforce(&mut x, &mut v, &mass, &[true; 8], 2.0 * dt, dt)
            .unwrap();
        for i in 4..8 {
            let into_lid = x[i].z - (lid_z - offset);
            assert!(
                into_lid < NORMAL_TOLERANCE * rise,
                "node {i} {into_lid:e} mm into the lid"
            );
            let apart = x[i].z - x[i - 4].z;
            assert!(
                apart > 2.0 * offset - NORMAL_TOLERANCE * rise,
                "node {i}: plies {apart} apart"
            );
        }
    }
}
