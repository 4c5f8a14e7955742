//! drape's explicit step on an NVIDIA GPU.
//!
//! What it is for: running the explicit driver's central-difference step of
//! a [`drape_model::Model`] on a GPU, the whole step on the device between
//! the times the host looks at the state: one thread per truss, quad and
//! spring writing its own force slots, one thread per node gathering its
//! slots in the CPU driver's fixed order and advancing the node. No
//! floating-point atomics, so the results do not depend on the launch
//! geometry and repeat bit for bit from run to run.
//!
//! How: [`cudarc`] with dynamic loading (the build needs neither a GPU nor
//! the CUDA toolkit; `libcuda` and `libnvrtc` are opened at run time, after
//! [`probe`] has checked that they can be), and the kernels
//! (`kernels/step.h`, `kernels/cuda.cu`) compiled at run time by NVRTC
//! without fused multiply-adds. The same `step.h` is compiled for the CPU
//! by `build.rs` ([`HostStep`]): the tests check its arithmetic against the
//! CPU driver step by step, and [`compile_kernels`] checks that the CUDA
//! source compiles, both without a GPU.
//!
//! What it covers: the paper's element (fibre trusses with the crimp law,
//! the buckled column and their dashpots, resin quads and triangles with
//! Prony relaxation, or membranes with the fibres embedded; the
//! shear-locking law), yarn bending, holding springs, gravity, nodal
//! loads and follower pressures (each step handed their values at its
//! start), boundary
//! conditions (fixed, or moved by a displacement, a velocity or a picture
//! frame: the host works out each step's prescribed coordinates as the CPU
//! driver does, [`drape_time::PrescribedMotions`], and hands them over
//! with the step's constants), mass-proportional damping, and contact with
//! one rigid tool (plane, sphere or surface of revolution, moved by a
//! prescribed displacement) with Coulomb friction: the shipped hemisphere,
//! picture-frame, bias-extension and imported-plate scenes. A model with
//! anything else is refused by [`unsupported`], naming what (a second
//! tool, a force-driven or a mesh tool, plies).
//!
//! ```
//! use drape_gpu::unsupported;
//! let scene = drape_io::scene::Scene::parse(
//!     "[simulation]\nend_time = 0.01\n[fabric]\nmaterial = \"carbon-prepreg-2x2\"\n\
//!      fibres = \"trusses\"\nbending = false\nblank = { width = 100, height = 100, cells = [4, 4] }\n",
//!     std::path::Path::new("blank.toml"),
//!     &[],
//! )
//! .unwrap();
//! assert!(unsupported(&scene.model).is_empty());
//! ```

mod cuda;
mod driver;
mod host;
mod layout;
mod schedule;

impl GpuError {
    /// The contact kernel's fault word `4·node + kind` at `step`.
    pub(crate) fn contact_fault(word: u64, step: u64) -> Self {
        Self::Contact {
            node: (word / 4) as usize,
            what: if word % 4 == 1 {
                "travelled more than the contact guard's largest travel in one step"
            } else {
                "is inside the tool by more than its step explains (its gap jumped)"
            },
            step,
        }
    }
}

pub use cuda::{CudaStep, compile_kernels, kernel_source, probe};
pub use driver::{RunContact, run};
pub use host::HostStep;
pub use layout::unsupported;
pub use schedule::{BatchSteps, Engine, Snapshot, StepParams, StepRun, run_steps};

/// Why a model cannot be stepped on the GPU, or the GPU failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GpuError {
    /// The model uses what the GPU step does not do yet.
    #[error("the GPU step does not do {}", .0.join(", "))]
    Unsupported(Vec<String>),
    /// No usable GPU or CUDA library on this machine.
    #[error("no usable GPU: {0}")]
    NoDevice(String),
    /// A CUDA call or the kernels' compilation failed.
    #[error("CUDA: {0}")]
    Cuda(String),
    /// The contact guard's fault (`drape_contact::ContactFault`): a node
    /// inside the tool by more than its step explains, nothing corrected.
    #[error("contact fault at step {step}: node {node} {what}")]
    Contact {
        /// The node.
        node: usize,
        /// What the guard saw.
        what: &'static str,
        /// The step.
        step: u64,
    },
    /// An element's kinematics failed (collapsed truss, degenerate quad
    /// point, non-finite position): the CPU driver names the element.
    #[error("{kind} {index} is collapsed, degenerate or not finite at step {step}")]
    Element {
        /// "truss" or "quad" (of the batch order, counted from 0 per batch).
        kind: &'static str,
        /// The element in its batch.
        index: usize,
        /// The step at which it failed.
        step: u64,
    },
}
