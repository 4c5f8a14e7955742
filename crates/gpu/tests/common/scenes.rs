//! Scenes that both the kernels' CPU-build tests (`host_kernels.rs`) and
//! the device check (`examples/gpu_check.rs`, which includes this file by
//! path) run: what the CPU build checks bit for bit, the GPU is checked on.

/// A sheet clamped on its left edge, its right edge pulled by a load per
/// length on a ramp, its corners (also on that edge) pushed down by a
/// second load on a table.
pub const LOADED_SHEET: &str = r#"
gravity = [0, 0, -9810]
[simulation]
end_time = 0.02
frames = 4
mass_scaling_dt = 2e-5
[fabric]
material = "glass-serge-4x3"
fibres = "trusses"
blank = { width = 100, height = 60, cells = [10, 6] }
[[boundary]]
nodes = "left"
motion = { kind = "fixed" }
[[loads]]
nodes = "right"
force = [2.0, 0.0, 0.5]
per_length = true
amplitude = { kind = "ramp", duration = 0.01 }
[[loads]]
nodes = "corners"
force = [0.0, 0.3, -1.0]
amplitude = { kind = "table", points = [[0, 0], [0.005, 1], [0.02, 0.2]] }
"#;

/// A ply pressed onto a dome (the shipped conforming ply's mould) by a
/// follower pressure (a vacuum bag) on a smooth step.
pub const VACUUM_DOME: &str = r#"
[simulation]
end_time = 0.02
frames = 4
mass_scaling_dt = 2e-5
[fabric]
material = "carbon-prepreg-2x2"
fibres = "trusses"
blank = { width = 120, height = 120, cells = [12, 12] }
[[tools]]
name = "dome"
geometry = { kind = "sphere", center = [0, 0, -80.5], radius = 80 }
friction = 0.2
[[pressure]]
value = 0.02
towards = "dome"
amplitude = { kind = "smooth_step", duration = 0.02 }
[[springs]]
nodes = "corners"
stiffness = 1.0
"#;
