//! What a contact pass shows the outside world at an output frame, the
//! same for the explicit and the implicit pass: per-node forces and
//! statuses, the tools' states and forces, the friction dissipated.

use nalgebra::Vector3;

use crate::explicit::ContactStatus;
use crate::tool::{Tool, ToolState};

/// A borrowed view of a contact pass's outputs.
#[derive(Debug, Clone, Copy)]
pub struct ContactView<'a> {
    /// The tools.
    pub tools: &'a [Tool],
    /// Their displacement and velocity along their axes.
    pub tool_state: &'a [ToolState],
    /// Contact force on each node (N): normal + friction.
    pub force: &'a [Vector3<f64>],
    /// Each node's status.
    pub status: &'a [ContactStatus],
    /// Which tool each node touches (u32::MAX for none).
    pub tool_of: &'a [u32],
    /// Normal force of each tool on the fabric (N, along the tool's axis of
    /// motion for a moving tool, magnitude otherwise).
    pub tool_force: &'a [f64],
    /// Friction dissipated so far (mJ).
    pub friction_dissipation: f64,
    /// The contact between the plies of a laminate (slip, pressure), if
    /// the model is one and the pass has it.
    pub plies: Option<&'a crate::PlyContact>,
}
