//! The GPU kernels' arithmetic, compiled for the CPU (`HostStep`), against
//! the CPU driver: the same steps from the same state give the same
//! positions, velocities and resin histories bit for bit.

use std::path::Path;

use drape_gpu::{GpuError, HostStep, run_steps, unsupported};
use drape_io::scene::Scene;
use drape_model::State;
use drape_time::{Explicit, NoObserver};

#[path = "common/scenes.rs"]
mod scenes;

fn scene(text: &str) -> Scene {
    Scene::parse(text, Path::new("gpu-test.toml"), &[]).expect("a valid scene")
}

/// `steps` steps of `scene` by the CPU driver and by the kernels' CPU
/// build, from the model's initial state; and how many nodes the CPU
/// driver's last step pressed on a tool.
fn both_counting_contacts(scene: &Scene, steps: u64) -> (State, State, usize) {
    let model = &scene.model;
    let mut settings = scene.settings.clone();
    settings.max_steps = Some(steps);
    let mut cpu = model.initial_state();
    let mut explicit = Explicit::new(model, settings.clone()).expect("a driver");
    explicit
        .run(&mut cpu, &mut NoObserver)
        .expect("the CPU run");
    let touching = explicit.contact().map_or(0, |c| {
        c.force
            .iter()
            .filter(|f| **f != nalgebra::Vector3::zeros())
            .count()
    });
    let explicit = Explicit::new(model, settings.clone()).expect("a driver");
    let mut host = HostStep::new(&explicit).expect("a model the GPU steps");
    let mut gpu = model.initial_state();
    let run = run_steps(&mut host, &explicit, &mut gpu, Some(steps)).expect("steps");
    assert_eq!(run.steps, cpu.step);
    (cpu, gpu, touching)
}

fn both(scene: &Scene, steps: u64) -> (State, State) {
    let (cpu, gpu, _) = both_counting_contacts(scene, steps);
    (cpu, gpu)
}

fn assert_same(cpu: &State, gpu: &State) {
    assert_eq!(cpu.step, gpu.step);
    assert_eq!(cpu.time.to_bits(), gpu.time.to_bits(), "time");
    for (i, (a, b)) in cpu.x.iter().zip(&gpu.x).enumerate() {
        assert_eq!(a, b, "position of node {i}");
    }
    for (i, (a, b)) in cpu.v.iter().zip(&gpu.v).enumerate() {
        assert_eq!(a, b, "velocity of node {i}");
    }
    for (a, b) in cpu.history.iter().zip(&gpu.history) {
        assert_eq!(a, b, "resin history");
    }
}

/// The shipped hemisphere's blank without its punch: prepreg trusses with
/// the crimp law, the buckled column and dashpots, the six-term Prony
/// resin, corner and mid-edge springs, gravity and mass scaling.
const SAGGING_PREPREG: &str = r#"
gravity = [0, 0, -9810]
[simulation]
end_time = 1.0
mass_scaling_dt = 2e-5
[fabric]
material = "carbon-prepreg-2x2"
fibres = "trusses"
bending = false
blank = { width = 350, height = 350, cells = [16, 16] }
[[springs]]
nodes = ["corners", "edge_midpoints"]
stiffness = 1.0
"#;

#[test]
fn a_sagging_prepreg_blank_steps_as_on_the_cpu_bit_for_bit() {
    let s = scene(SAGGING_PREPREG);
    let (cpu, gpu) = both(&s, 3000);
    // It moved: the test compares a deforming state, not the reference.
    let sag = s.model.x0[144].z - cpu.x[144].z;
    assert!(sag > 0.3, "the middle sagged {sag} mm");
    assert_same(&cpu, &gpu);
}

#[test]
fn an_elastic_resin_sheet_with_a_clamped_edge_and_damping_steps_as_on_the_cpu() {
    let mut s = scene(
        r#"
gravity = [0, 0, -9810]
[simulation]
end_time = 0.05
[fabric]
material = "glass-serge-4x3"
fibres = "trusses"
bending = false
blank = { width = 100, height = 60, cells = [10, 6] }
[[boundary]]
nodes = "left"
motion = { kind = "fixed" }
"#,
    );
    s.settings.damping = 40.0;
    let resin = &s.model.membranes[0].section.material.resin;
    assert!(resin.prony.is_empty() || resin.prony.len() <= 8);
    let (cpu, gpu) = both(&s, 600);
    assert_same(&cpu, &gpu);
}

#[test]
fn a_run_ends_on_its_end_time_as_on_the_cpu() {
    // 2.5e-3 s is not a whole number of steps: the last ones are cut equal.
    let text = SAGGING_PREPREG.replace("end_time = 1.0", "end_time = 2.5e-3");
    let s = scene(&text);
    let (cpu, gpu) = both(&s, u64::MAX / 2);
    assert!(cpu.step > 20);
    assert_same(&cpu, &gpu);
}

#[test]
fn the_shipped_hemisphere_steps_as_on_the_cpu_through_contact_friction_and_bending() {
    let overrides = [
        ("fabric.blank.cells", "[16, 16]"),
        ("tools.0.friction", "0.3"),
    ]
    .map(|(k, v)| (k.to_owned(), v.to_owned()));
    let s = Scene::from_file(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/hemisphere-0-90.toml"),
        &overrides,
    )
    .expect("the shipped scene");
    assert!(s.model.features().bending);
    let (cpu, gpu, touching) = both_counting_contacts(&s, 20_000);
    // The punch has come up about 40 mm and carries the middle of the blank.
    assert_same(&cpu, &gpu);
    assert!(touching > 10, "{touching} nodes on the punch");
}

#[test]
fn the_shipped_45_degree_hemisphere_with_its_triangles_steps_as_on_the_cpu() {
    let overrides = [("fabric.blank.cells", "[12, 12]")].map(|(k, v)| (k.to_owned(), v.to_owned()));
    let s = Scene::from_file(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/hemisphere-45.toml"),
        &overrides,
    )
    .expect("the shipped scene");
    assert!(
        s.model
            .membranes
            .iter()
            .any(|b| b.shape() == drape_elements::MembraneShape::Triangle && !b.is_empty())
    );
    let (cpu, gpu, touching) = both_counting_contacts(&s, 20_000);
    assert_same(&cpu, &gpu);
    assert!(touching > 10, "{touching} nodes on the punch");
}

#[test]
fn what_the_gpu_does_not_do_is_named() {
    let s = scene(
        r#"
[simulation]
end_time = 0.1
[fabric]
material = "carbon-prepreg-2x2"
fibres = "trusses"
blank = { width = 100, height = 100, cells = [4, 4] }
[[tools]]
name = "punch"
geometry = { kind = "hemispherical_punch", pole = [0, 0, -1], radius = 40, shank = 50 }
motion = { kind = "displacement", direction = [0, 0, 1], distance = 20, amplitude = { kind = "smooth_step", duration = 0.1 } }
[[tools]]
name = "ring"
geometry = { kind = "plane", point = [0, 0, 5], normal = [0, 0, -1] }
"#,
    );
    let missing = unsupported(&s.model);
    assert!(
        missing.iter().any(|m| m.contains("more than one tool")),
        "{missing:?}"
    );
    let explicit = Explicit::new(&s.model, s.settings.clone()).expect("a driver");
    let refused = HostStep::new(&explicit);
    assert!(matches!(refused, Err(GpuError::Unsupported(m)) if m == missing));
}

/// Frames and the last progress a run hands its observer.
#[derive(Default)]
struct Frames {
    energies: Vec<drape_time::Energies>,
    times: Vec<f64>,
    contact_force: Vec<f64>,
    /// Σ|r_x| of the reactions (twice a bias extension's force).
    reaction_x: Vec<f64>,
}

impl drape_time::Observer for Frames {
    fn frame(&mut self, f: &drape_time::Frame<'_>) {
        self.energies.push(*f.energy);
        self.times.push(f.state.time);
        self.contact_force
            .push(f.contact.map_or(0.0, |c| c.tool_force.iter().sum()));
        self.reaction_x
            .push(f.reactions.iter().map(|r| r.x.abs()).sum());
    }
}

/// The frames at the same times with the same energies: the same states;
/// the works summed node by node over the steps instead of over the nodes
/// at each step, so round-off apart.
fn assert_same_energies(cpu: &Frames, gpu: &Frames) {
    assert_eq!(cpu.times, gpu.times);
    for (c, g) in cpu.energies.iter().zip(&gpu.energies) {
        let scale = c
            .external_work
            .abs()
            .max(c.boundary_work.abs())
            .max(c.kinetic)
            .max(1e-12);
        assert_close_energies(c, g, scale);
    }
}

/// Each of the CPU's energies `c` and the GPU's `g` within 1e-9 of `scale`.
fn assert_close_energies(c: &drape_time::Energies, g: &drape_time::Energies, scale: f64) {
    for (what, a, b) in [
        ("kinetic", c.kinetic, g.kinetic),
        ("strain", c.strain, g.strain),
        ("internal work", c.internal_work, g.internal_work),
        ("external work", c.external_work, g.external_work),
        ("boundary work", c.boundary_work, g.boundary_work),
        ("contact work", c.contact_work, g.contact_work),
        ("friction", c.friction_dissipation, g.friction_dissipation),
        ("balance", c.balance_error, g.balance_error),
    ] {
        assert!(
            (a - b).abs() <= 1e-9 * scale,
            "{what}: CPU {a:e}, GPU {b:e}"
        );
    }
}

#[test]
fn a_whole_run_through_the_gpu_driver_gives_the_cpu_drivers_frames_and_energies() {
    let overrides = [
        ("fabric.blank.cells", "[16, 16]"),
        ("simulation.end_time", "0.4"),
        ("simulation.frames", "4"),
    ]
    .map(|(k, v)| (k.to_owned(), v.to_owned()));
    let s = Scene::from_file(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/hemisphere-0-90.toml"),
        &overrides,
    )
    .expect("the shipped scene");
    let model = &s.model;
    let (mut cpu, mut gpu) = (model.initial_state(), model.initial_state());
    let (mut cpu_frames, mut gpu_frames) = (Frames::default(), Frames::default());
    let mut cpu_explicit = Explicit::new(model, s.settings.clone()).expect("a driver");
    let cpu_run = cpu_explicit
        .run(&mut cpu, &mut cpu_frames)
        .expect("the CPU run");
    let explicit = Explicit::new(model, s.settings.clone()).expect("a driver");
    let mut host = HostStep::new(&explicit).expect("a model the GPU steps");
    let (gpu_run, gpu_contact) =
        drape_gpu::run(&explicit, &mut host, &mut gpu, &mut gpu_frames).expect("run");
    assert_eq!(cpu_run.steps, gpu_run.steps);
    assert_same(&cpu, &gpu);
    // The contact at the end, as the run's last frame and picture take it:
    // the tool where the CPU driver's is, the nodes' forces and statuses.
    let (c, g) = (
        cpu_explicit.contact().expect("a tool").view(),
        gpu_contact.view(&model.tools).expect("a tool"),
    );
    assert_eq!(c.tool_state[0].displacement, g.tool_state[0].displacement);
    assert!(g.tool_state[0].displacement > 10.0);
    assert_eq!(c.force, g.force);
    assert_eq!(c.status, g.status);
    assert_same_energies(&cpu_frames, &gpu_frames);
    // The punch carries the blank at the end, and the frame says with
    // what force (summed node by node in both drivers' order).
    let (c, g) = (
        cpu_frames.contact_force.last(),
        gpu_frames.contact_force.last(),
    );
    assert!(c.is_some_and(|f| *f > 0.0), "{c:?}");
    assert_eq!(c, g);
}

#[test]
fn the_shipped_conforming_ply_steps_as_on_the_cpu_with_its_pinned_nodes() {
    let s = Scene::from_file(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/hemisphere-conform.toml"),
        &[],
    )
    .expect("the shipped scene");
    let (cpu, gpu, touching) = both_counting_contacts(&s, 1500);
    assert_same(&cpu, &gpu);
    assert!(touching > 10, "{touching} nodes on the mould");
}

/// A shipped scene by its file name, with `overrides`.
fn shipped(name: &str, overrides: &[(&str, &str)]) -> Scene {
    let overrides: Vec<(String, String)> = overrides
        .iter()
        .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
        .collect();
    Scene::from_file(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenes")
            .join(name),
        &overrides,
    )
    .expect("the shipped scene")
}

#[test]
fn the_shipped_picture_frame_runs_to_its_end_as_on_the_cpu() {
    // The frame's arms: a trajectory of every edge node, from a closure.
    let s = shipped("picture-frame.toml", &[]);
    assert!(unsupported(&s.model).is_empty());
    let (cpu, gpu) = both(&s, u64::MAX / 2);
    assert!(cpu.time >= s.settings.end_time * (1.0 - 1e-9), "to its end");
    // Sheared: the frame's far corner has swung round its pin.
    let moved = cpu
        .x
        .iter()
        .zip(&s.model.x0)
        .map(|(x, x0)| (x - x0).norm())
        .fold(0.0, f64::max);
    assert!(moved > 10.0, "the nodes moved up to {moved} mm");
    assert_same(&cpu, &gpu);
}

#[test]
fn the_shipped_bias_extension_runs_to_its_end_as_on_the_cpu() {
    // One end fixed, the other pulled by a smooth-step displacement.
    let s = shipped("bias-extension.toml", &[]);
    let (cpu, gpu) = both(&s, u64::MAX / 2);
    assert!(cpu.time >= s.settings.end_time * (1.0 - 1e-9), "to its end");
    let right = s.model.node_set("right").expect("the pulled end")[0] as usize;
    let pulled = cpu.x[right].x - s.model.x0[right].x;
    assert!((pulled - 25.0).abs() < 1e-9, "pulled {pulled} mm");
    assert_same(&cpu, &gpu);
}

#[test]
fn velocity_conditions_and_part_held_nodes_on_a_tool_step_as_on_the_cpu() {
    // An edge over the punch driven by a velocity in x only (free in y
    // and z, so the punch's contact moves it there), the opposite edge by
    // a table in z only: each constrained component where the CPU
    // driver's step puts it, through contact.
    let s = scene(
        r#"
gravity = [0, 0, -9810]
[simulation]
end_time = 0.04
mass_scaling_dt = 2e-5
[fabric]
material = "carbon-prepreg-2x2"
fibres = "trusses"
blank = { width = 40, height = 120, cells = [4, 12] }
[[tools]]
name = "punch"
geometry = { kind = "hemispherical_punch", pole = [-15, 0, -1], radius = 40, shank = 50 }
motion = { kind = "displacement", direction = [0, 0, 1], distance = 20, amplitude = { kind = "smooth_step", duration = 0.04 } }
friction = 0.2
[[boundary]]
nodes = "left"
components = "x"
motion = { kind = "velocity", value = [-50, 0, 0], amplitude = { kind = "ramp", duration = 0.02 } }
[[boundary]]
nodes = "right"
components = "z"
motion = { kind = "displacement", value = [0, 0, 5], amplitude = { kind = "table", points = [[0, 0], [0.02, 1], [0.04, 0.5]] } }
"#,
    );
    // To t = 0.02 s (1 000 steps of 2e-5 s): the punch halfway up.
    let (cpu, gpu, touching) = both_counting_contacts(&s, 1000);
    assert!(touching >= 3, "{touching} nodes on the punch");
    let lifted = s.model.node_set("left").expect("an edge").iter();
    assert!(
        lifted.filter(|&&i| cpu.x[i as usize].z > 5.0).count() >= 3,
        "the edge on the punch"
    );
    let left = s.model.node_set("left").expect("an edge")[3] as usize;
    let right = s.model.node_set("right").expect("an edge")[3] as usize;
    // x moved by ∫v dt = −50·t²/(2·0.02) mm (midpoint sums of a ramp are
    // exact); z by the table, 5·t/0.02 mm.
    let t = cpu.time;
    assert!(t > 0.019, "at {t} s");
    let pulled = cpu.x[left].x - s.model.x0[left].x;
    assert!(
        (pulled + 50.0 * t * t / 0.04).abs() < 1e-9,
        "pulled {pulled} mm"
    );
    assert!((cpu.x[right].z - s.model.x0[right].z - 5.0 * t / 0.02).abs() < 1e-9);
    assert_same(&cpu, &gpu);
}

/// Whole runs of `scene` by the CPU driver and by the GPU driver on the
/// kernels' CPU build, the same states at the end (checked): the CPU's
/// state, and each run's frames.
fn whole_runs(scene: &Scene) -> (State, Frames, Frames) {
    let model = &scene.model;
    let (mut cpu, mut gpu) = (model.initial_state(), model.initial_state());
    let (mut cpu_frames, mut gpu_frames) = (Frames::default(), Frames::default());
    Explicit::new(model, scene.settings.clone())
        .expect("a driver")
        .run(&mut cpu, &mut cpu_frames)
        .expect("the CPU run");
    let explicit = Explicit::new(model, scene.settings.clone()).expect("a driver");
    let mut host = HostStep::new(&explicit).expect("a model the GPU steps");
    drape_gpu::run(&explicit, &mut host, &mut gpu, &mut gpu_frames).expect("the GPU run");
    assert_same(&cpu, &gpu);
    (cpu, cpu_frames, gpu_frames)
}

#[test]
fn a_whole_bias_extension_through_the_gpu_driver_gives_the_cpu_drivers_energies() {
    // The pulled end's work is the boundary work: the energies of a run
    // that only a prescribed motion drives.
    let s = shipped("bias-extension.toml", &[("simulation.frames", "3")]);
    let (_, cpu_frames, gpu_frames) = whole_runs(&s);
    let last = cpu_frames.energies.last().expect("frames");
    assert!(last.boundary_work > 0.0 && last.strain > 0.0, "{last:?}");
    assert_same_energies(&cpu_frames, &gpu_frames);
    // The force the machine measures, from the same forces in the same
    // order: the same bits.
    assert!(cpu_frames.reaction_x.last().is_some_and(|f| f.abs() > 1.0));
    assert_eq!(cpu_frames.reaction_x, gpu_frames.reaction_x);
}

#[test]
fn the_shipped_imported_plate_with_embedded_fibres_runs_to_its_end_as_on_the_cpu() {
    // A gmsh blank, the fibres at 30° embedded in its membranes, a rising
    // sphere with friction, corner springs.
    let s = shipped("imported-plate.toml", &[]);
    assert!(s.model.features().embedded_fibres);
    assert!(
        unsupported(&s.model).is_empty(),
        "{:?}",
        unsupported(&s.model)
    );
    let (cpu, gpu) = both(&s, u64::MAX / 2);
    assert!(cpu.time >= s.settings.end_time * (1.0 - 1e-9), "to its end");
    // The sphere's top rose from z = -0.5 to 34.5 mm, carrying the plate.
    let top = cpu.x.iter().map(|x| x.z).fold(f64::MIN, f64::max);
    assert!(top > 30.0, "the plate's top at z = {top} mm");
    assert_same(&cpu, &gpu);
}

#[test]
fn the_benchmark_fabrics_shear_locking_law_runs_as_on_the_cpu() {
    // `twintex-plain` (Cao et al. 2008's plain weave) carries the law: the
    // picture frame takes it to 60°, past locking, where the law's
    // stiffening also sets the stable step.
    let twintex = ("fabric.material", "\"twintex-plain\"");
    let s = shipped("picture-frame.toml", &[twintex]);
    let law = &s.model.membranes[0].section.material.resin.shear_locking;
    assert!(law.as_ref().is_some_and(|l| l.coefficients.len() >= 2));
    assert!(unsupported(&s.model).is_empty());
    let (cpu, gpu) = both(&s, u64::MAX / 2);
    assert!(cpu.time >= s.settings.end_time * (1.0 - 1e-9), "to its end");
    assert_same(&cpu, &gpu);
    // With embedded fibres, which are the law's fibres too, and a friction
    // term (a dry fabric's, as `drape fit` gives it).
    let mut s = shipped(
        "bias-extension.toml",
        &[twintex, ("fabric.fibres", "\"embedded\"")],
    );
    for b in &mut s.model.membranes {
        if let Some(law) = &mut b.section.material.resin.shear_locking {
            law.friction = Some([0.003, 0.02]);
        }
    }
    let (cpu, gpu) = both(&s, u64::MAX / 2);
    assert_same(&cpu, &gpu);
}

#[test]
fn nodal_loads_with_their_amplitudes_run_as_on_the_cpu() {
    // A sheet clamped on its left edge, its right edge pulled by a load
    // per length on a ramp, its corners (also on that edge) pushed down by
    // a second load on a table: a node with two loads sums them in the
    // loads' order; the frames' reactions and energies use the loads at
    // the frame's time.
    let s = scene(scenes::LOADED_SHEET);
    assert!(unsupported(&s.model).is_empty());
    let model = &s.model;
    let (cpu, cpu_frames, gpu_frames) = whole_runs(&s);
    // The loads matter: without them the edge hangs elsewhere.
    let mut unloaded = model.clone();
    unloaded.loads.clear();
    let mut hanging = unloaded.initial_state();
    Explicit::new(&unloaded, s.settings.clone())
        .expect("a driver")
        .run(&mut hanging, &mut drape_time::NoObserver)
        .expect("the CPU run");
    let right = model.node_set("right").expect("an edge")[2] as usize;
    let moved = (cpu.x[right] - hanging.x[right]).norm();
    assert!(moved > 0.1, "the loads moved the edge by {moved} mm");
    let last = cpu_frames.energies.last().expect("frames");
    assert!(last.external_work > 0.0, "{last:?}");
    assert_same_energies(&cpu_frames, &gpu_frames);
    assert_eq!(cpu_frames.reaction_x, gpu_frames.reaction_x);
}

#[test]
fn a_vacuum_pressure_drapes_a_ply_on_a_dome_as_on_the_cpu() {
    // The shipped conforming ply's mould (a dome), the ply pressed onto it
    // by a follower pressure (a vacuum bag) on a smooth step: each node's
    // share of its elements' current vector areas, in the pressure pass's
    // order; the frames' energies take the pressure at their positions.
    let s = scene(scenes::VACUUM_DOME);
    assert!(
        unsupported(&s.model).is_empty(),
        "{:?}",
        unsupported(&s.model)
    );
    let model = &s.model;
    let (cpu, cpu_frames, gpu_frames) = whole_runs(&s);
    // Pressed down over the dome: a corner, beyond it, went down.
    let drop = model.x0[0].z - cpu.x[0].z;
    assert!(drop > 1.0, "the corner went down {drop} mm");
    let last = cpu_frames.energies.last().expect("frames");
    assert!(last.external_work > 0.0, "{last:?}");
    assert_same_energies(&cpu_frames, &gpu_frames);
}

/// The checkpoints a run hands its observer.
#[derive(Default)]
struct Checkpoints(Vec<(State, drape_time::DriverState)>);

impl drape_time::Observer for Checkpoints {
    fn checkpoint(&mut self, state: &State, driver: &drape_time::DriverState) {
        self.0.push((state.clone(), driver.clone()));
    }
}

#[test]
fn a_gpu_run_checkpoints_and_resumes_as_the_cpu_driver_does() {
    // The punch through contact and friction; checkpoints every 2 999
    // steps, of both drivers; each resumed on the other driver.
    let mut s = shipped(
        "hemisphere-0-90.toml",
        &[
            ("fabric.blank.cells", "[16, 16]"),
            ("simulation.end_time", "0.3"),
        ],
    );
    // Not a multiple of the stable step's re-estimates (every 20).
    s.settings.checkpoint_every = Some(2999);
    let model = &s.model;
    let run_cpu = |state: &mut State, from: Option<drape_time::DriverState>| {
        let mut explicit = Explicit::new(model, s.settings.clone()).expect("a driver");
        if let Some(d) = from {
            explicit.resume_from(d);
        }
        let mut seen = Checkpoints::default();
        explicit.run(state, &mut seen).expect("the CPU run");
        seen
    };
    let run_gpu = |state: &mut State, from: Option<drape_time::DriverState>| {
        let mut explicit = Explicit::new(model, s.settings.clone()).expect("a driver");
        if let Some(d) = from {
            explicit.resume_from(d);
        }
        let mut host = HostStep::new(&explicit).expect("a model the GPU steps");
        let mut seen = Checkpoints::default();
        drape_gpu::run(&explicit, &mut host, state, &mut seen).expect("the GPU run");
        seen
    };
    let (mut cpu, mut gpu) = (model.initial_state(), model.initial_state());
    let cpu_points = run_cpu(&mut cpu, None).0;
    let gpu_points = run_gpu(&mut gpu, None).0;
    assert_same(&cpu, &gpu);
    assert!(cpu_points.len() >= 2, "{} checkpoints", cpu_points.len());
    assert_eq!(cpu_points.len(), gpu_points.len());
    for ((cs, cd), (gs, gd)) in cpu_points.iter().zip(&gpu_points) {
        assert_same(cs, gs);
        assert_eq!((cd.dt, cd.dt_prev), (gd.dt, gd.dt_prev));
        assert_eq!(cd.tools[0].displacement, gd.tools[0].displacement);
        assert_eq!(cd.tools[0].velocity, gd.tools[0].velocity);
        let scale = cd.energy.internal_work.abs().max(1e-12);
        for (a, b) in [
            (cd.energy.internal_work, gd.energy.internal_work),
            (cd.energy.external_work, gd.energy.external_work),
            (cd.energy.contact_work, gd.energy.contact_work),
            (cd.friction_dissipation, gd.friction_dissipation),
            (cd.tools[0].impulse, gd.tools[0].impulse),
        ] {
            assert!((a - b).abs() <= 1e-9 * scale.max(a.abs()), "{a:e} {b:e}");
        }
    }
    // Each driver's checkpoint, resumed on the other, ends where both
    // uninterrupted runs end.
    let (state, driver) = gpu_points[1].clone();
    let mut resumed = state;
    run_cpu(&mut resumed, Some(driver));
    assert_same(&cpu, &resumed);
    let (state, driver) = cpu_points[1].clone();
    let mut resumed = state;
    let later = run_gpu(&mut resumed, Some(driver)).0;
    assert_same(&gpu, &resumed);
    // And the resumed GPU run checkpoints at the same steps.
    assert_eq!(later.len(), gpu_points.len() - 2);
    assert_same(&later[0].0, &gpu_points[2].0);
}

#[test]
fn a_gpu_run_stopped_between_checks_reports_its_energies_where_it_stopped() {
    // 777 steps: before the first energy check (at 2 500 steps), as a
    // Ctrl-C or a step budget stops a run anywhere.
    let mut s = shipped(
        "hemisphere-0-90.toml",
        &[("fabric.blank.cells", "[16, 16]")],
    );
    s.settings.max_steps = Some(777);
    let model = &s.model;
    let mut cpu = model.initial_state();
    let c = Explicit::new(model, s.settings.clone())
        .expect("a driver")
        .run(&mut cpu, &mut NoObserver)
        .expect("the CPU run");
    let explicit = Explicit::new(model, s.settings.clone()).expect("a driver");
    let mut host = HostStep::new(&explicit).expect("a model the GPU steps");
    let mut gpu = model.initial_state();
    let (g, _) = drape_gpu::run(&explicit, &mut host, &mut gpu, &mut NoObserver).expect("run");
    assert!(c.stopped && g.stopped);
    assert_same(&cpu, &gpu);
    let (c, g) = (c.energy, g.energy);
    let scale = c
        .internal_work
        .abs()
        .max(c.kinetic)
        .max(c.external_work.abs());
    assert!(c.external_work > 0.0, "{c:?}");
    assert_close_energies(&c, &g, scale);
}

#[test]
fn motions_loads_and_pressure_together_run_as_on_the_cpu() {
    // Each step's values hold all three (prescribed coordinates, then the
    // loads' forces, then the pressures' p·a(t)): each read at its place.
    let s = scene(
        r#"
[simulation]
end_time = 0.01
frames = 2
mass_scaling_dt = 2e-5
[fabric]
material = "carbon-prepreg-2x2"
fibres = "trusses"
blank = { width = 120, height = 120, cells = [12, 12] }
[[tools]]
name = "dome"
geometry = { kind = "sphere", center = [0, 0, -80.5], radius = 80 }
[[pressure]]
value = 0.02
towards = "dome"
amplitude = { kind = "ramp", duration = 0.01 }
[[loads]]
nodes = "corners"
force = [0.0, 0.0, 0.5]
[[boundary]]
nodes = "left"
components = "x"
motion = { kind = "displacement", value = [-2, 0, 0], amplitude = { kind = "smooth_step", duration = 0.01 } }
"#,
    );
    let f = s.model.features();
    assert!(f.prescribed_motion && f.loads && f.pressure);
    let (cpu, cpu_frames, gpu_frames) = whole_runs(&s);
    let left = s.model.node_set("left").expect("an edge")[4] as usize;
    assert!((cpu.x[left].x - s.model.x0[left].x + 2.0).abs() < 1e-9);
    assert_same_energies(&cpu_frames, &gpu_frames);
}
