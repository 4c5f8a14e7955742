//! Tools: a surface, how it moves, its friction.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::surface::{Projection, Surface};

/// A time function a(t) scaling a prescribed motion or load.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", deny_unknown_fields)]
pub enum Amplitude {
    /// a = 1.
    Constant,
    /// a = t/T, then 1.
    Ramp {
        /// T (s).
        duration: f64,
    },
    /// a = ξ³(10 − 15ξ + 6ξ²), ξ = t/T, then 1: zero velocity and
    /// acceleration at both ends (SPEC §7).
    SmoothStep {
        /// T (s).
        duration: f64,
    },
    /// Piecewise linear through (t, a) points, constant beyond the ends.
    Table {
        /// (t, a) points with increasing t.
        points: Vec<[f64; 2]>,
    },
}

impl Amplitude {
    /// a(t).
    pub fn value(&self, t: f64) -> f64 {
        match self {
            Self::Constant => 1.0,
            Self::Ramp { duration } => (t / duration).clamp(0.0, 1.0),
            Self::SmoothStep { duration } => {
                let xi = (t / duration).clamp(0.0, 1.0);
                xi * xi * xi * (10.0 - 15.0 * xi + 6.0 * xi * xi)
            }
            Self::Table { points } => {
                let (first, last) = (points[0], points[points.len() - 1]);
                if t <= first[0] {
                    return first[1];
                }
                if t >= last[0] {
                    return last[1];
                }
                let i = points.partition_point(|p| p[0] <= t);
                let (p0, p1) = (points[i - 1], points[i]);
                p0[1] + (p1[1] - p0[1]) * (t - p0[0]) / (p1[0] - p0[0])
            }
        }
    }

    /// Checks the parameters; `field` names it in the message.
    pub fn validate(&self) -> Result<(), String> {
        match self {
            Self::Constant => Ok(()),
            Self::Ramp { duration } | Self::SmoothStep { duration } => {
                if duration.is_finite() && *duration > 0.0 {
                    Ok(())
                } else {
                    Err(format!("duration {duration} must be positive"))
                }
            }
            Self::Table { points } => {
                if points.is_empty() {
                    return Err("a table needs at least one point".into());
                }
                for (i, p) in points.iter().enumerate() {
                    if !(p[0].is_finite() && p[1].is_finite()) {
                        return Err(format!("point {i} is not finite"));
                    }
                    if i > 0 && p[0] <= points[i - 1][0] {
                        return Err(format!("times must increase: point {i} does not"));
                    }
                }
                Ok(())
            }
        }
    }
}

/// How a tool moves: rigidly, translating along one axis.
#[derive(Debug, Clone, PartialEq)]
pub enum ToolMotion {
    /// Never moves.
    Fixed,
    /// Displacement `distance·a(t)` along the unit `direction`.
    Displacement {
        /// Unit axis.
        direction: Vector3<f64>,
        /// Travel at a = 1 (mm).
        distance: f64,
        /// a(t).
        amplitude: Amplitude,
    },
    /// A rigid body free along the unit `direction` only, with `mass`,
    /// pushed by `force·a(t)` along it (a blank holder).
    Force {
        /// Unit axis.
        direction: Vector3<f64>,
        /// Force at a = 1 (N).
        force: f64,
        /// a(t).
        amplitude: Amplitude,
        /// Mass of the moving tool (t).
        mass: f64,
    },
}

impl ToolMotion {
    /// The axis of motion (zero for a fixed tool).
    pub fn direction(&self) -> Vector3<f64> {
        match self {
            Self::Fixed => Vector3::zeros(),
            Self::Displacement { direction, .. } | Self::Force { direction, .. } => *direction,
        }
    }
}

/// A rigid tool.
#[derive(Debug, Clone, PartialEq)]
pub struct Tool {
    /// A name for reports.
    pub name: String,
    /// Its surface at zero displacement.
    pub surface: Surface,
    /// How it moves.
    pub motion: ToolMotion,
    /// Coulomb friction coefficient μ with the fabric.
    pub friction: f64,
}

/// Where a tool is: its displacement and velocity along its axis, and
/// the impulse its contact has given the fabric so far.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ToolState {
    /// Displacement along the axis (mm).
    pub displacement: f64,
    /// Velocity along the axis (mm/s); mid-step for a force-driven tool.
    pub velocity: f64,
    /// The tool's contact force on the fabric (the passes' `tool_force`)
    /// integrated over the steps since the start (N·s). Between two frames
    /// its difference over their time apart is the mean force, which a
    /// sampled `tool_force` is not where a force-driven tool rings on a
    /// compliant stack (a 10 kg holder on two plies: up to 7.5e-4 of its
    /// force at a frame, at nanometres of motion). Checkpoints from
    /// before it start it at zero.
    #[serde(default)]
    pub impulse: f64,
}

impl Tool {
    /// Checks the tool's parameters.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return Err(format!(
                "tool `{}`: friction {} must be ≥ 0",
                self.name, self.friction
            ));
        }
        let axis = |d: &Vector3<f64>| -> Result<(), String> {
            if ((d.norm() - 1.0).abs()) < 1e-9 {
                Ok(())
            } else {
                Err(format!(
                    "tool `{}`: the motion direction must be a unit vector",
                    self.name
                ))
            }
        };
        match &self.motion {
            ToolMotion::Fixed => Ok(()),
            ToolMotion::Displacement {
                direction,
                distance,
                amplitude,
            } => {
                axis(direction)?;
                if !distance.is_finite() {
                    return Err(format!("tool `{}`: distance must be finite", self.name));
                }
                amplitude
                    .validate()
                    .map_err(|e| format!("tool `{}`: amplitude: {e}", self.name))
            }
            ToolMotion::Force {
                direction,
                force,
                amplitude,
                mass,
            } => {
                axis(direction)?;
                if !force.is_finite() {
                    return Err(format!("tool `{}`: force must be finite", self.name));
                }
                if !(mass.is_finite() && *mass > 0.0) {
                    return Err(format!(
                        "tool `{}`: a force-driven tool needs a positive mass",
                        self.name
                    ));
                }
                amplitude
                    .validate()
                    .map_err(|e| format!("tool `{}`: amplitude: {e}", self.name))
            }
        }
    }

    /// The prescribed displacement at `t` (None for a force-driven tool).
    pub fn prescribed_displacement(&self, t: f64) -> Option<f64> {
        match &self.motion {
            ToolMotion::Fixed => Some(0.0),
            ToolMotion::Displacement {
                distance,
                amplitude,
                ..
            } => Some(distance * amplitude.value(t)),
            ToolMotion::Force { .. } => None,
        }
    }

    /// Whether the tool is a rigid body driven by a force.
    pub fn is_force_driven(&self) -> bool {
        matches!(self.motion, ToolMotion::Force { .. })
    }

    /// The projection of the world point `x` with the tool displaced by
    /// `displacement` along its axis.
    pub fn project(&self, x: &Vector3<f64>, displacement: f64) -> Projection {
        let shift = self.motion.direction() * displacement;
        let mut p = self.surface.project(&(x - shift));
        p.point += shift;
        p
    }

    /// [`Self::project`] with the hint of [`Surface::project_from`].
    pub fn project_from(&self, x: &Vector3<f64>, displacement: f64, hint: &mut u32) -> Projection {
        let shift = self.motion.direction() * displacement;
        let mut p = self.surface.project_from(&(x - shift), hint);
        p.point += shift;
        p
    }

    /// [`Surface::rim_clearance`] of the world point `x` with the tool
    /// displaced by `displacement`.
    pub fn rim_clearance(&self, x: &Vector3<f64>, displacement: f64) -> f64 {
        self.surface
            .rim_clearance(&(x - self.motion.direction() * displacement))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amplitudes() {
        assert_eq!(Amplitude::Constant.value(3.0), 1.0);
        assert_eq!(Amplitude::Ramp { duration: 2.0 }.value(1.0), 0.5);
        assert_eq!(Amplitude::Ramp { duration: 2.0 }.value(5.0), 1.0);
        let s = Amplitude::SmoothStep { duration: 2.0 };
        assert_eq!(s.value(0.0), 0.0);
        assert_eq!(s.value(1.0), 0.5);
        assert_eq!(s.value(2.0), 1.0);
        // Zero slope at both ends.
        assert!(s.value(1e-4) < 1e-10 && 1.0 - s.value(2.0 - 1e-4) < 1e-10);
        let t = Amplitude::Table {
            points: vec![[0.0, 0.0], [1.0, 2.0], [3.0, 1.0]],
        };
        assert_eq!(t.value(-1.0), 0.0);
        assert_eq!(t.value(0.5), 1.0);
        assert_eq!(t.value(2.0), 1.5);
        assert_eq!(t.value(9.0), 1.0);
        assert!(t.validate().is_ok());
        assert!(Amplitude::Ramp { duration: 0.0 }.validate().is_err());
        assert!(
            Amplitude::Table {
                points: vec![[1.0, 0.0], [1.0, 1.0]]
            }
            .validate()
            .is_err()
        );
    }
}
