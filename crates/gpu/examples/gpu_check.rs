//! The checks to run on a machine with an NVIDIA GPU (`scripts/gpu-check`
//! builds nothing there: it runs this example's release binary, built
//! where Rust is):
//!
//! 1. agreement with the CPU driver over the first steps of two scenes
//!    (positions, velocities and resin histories, largest differences);
//! 2. the same bits from run to run and whatever the threads per block;
//! 3. a whole run of the shipped hemisphere's blank without its punch on
//!    the GPU and on the CPU, wall times and the largest difference;
//! 4. µs per step of 40 × 40, 200 × 200 and 1000 × 1000 blanks.
//!
//! `gpu_check [--skip-big]`; exit 0 when every agreement check passes,
//! 1 when one fails, 2 when there is no usable GPU.

use std::path::Path;
use std::time::Instant;

use drape_gpu::{CudaStep, Engine, StepParams, probe, run_steps};
use drape_io::scene::Scene;
use drape_model::State;
use drape_time::{Explicit, NoObserver};

#[path = "../tests/common/scenes.rs"]
mod scenes;

/// The shipped `scenes/hemisphere-0-90.toml` without its punch (bending
/// off, as the GPU step has none yet): `CELLS` cells a side.
const BLANK: &str = r#"
gravity = [0, 0, -9810]
[simulation]
end_time = END
mass_scaling_dt = 2e-5
[fabric]
material = "carbon-prepreg-2x2"
fibres = "trusses"
bending = false
blank = { width = 350, height = 350, cells = [CELLS, CELLS] }
[[springs]]
nodes = ["corners", "edge_midpoints"]
stiffness = 1.0
"#;

const SHEET: &str = r#"
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
"#;

/// The shipped `scenes/hemisphere-0-90.toml` (punch, friction, bending)
/// with `cells` cells a side and its other `overrides`.
fn hemisphere(cells: usize, overrides: &[(&str, &str)]) -> Scene {
    let mut all = vec![(
        "fabric.blank.cells".to_owned(),
        format!("[{cells}, {cells}]"),
    )];
    all.extend(
        overrides
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string())),
    );
    Scene::from_file(Path::new("scenes/hemisphere-0-90.toml"), &all).expect("the shipped scene")
}

fn blank(cells: usize, end: f64) -> Scene {
    let text = BLANK
        .replace("CELLS", &cells.to_string())
        .replace("END", &format!("{end:e}"));
    Scene::parse(&text, Path::new("blank.toml"), &[]).expect("the check's scene")
}

/// Largest |a − b| over the largest |a| (0 when both are zero).
fn relative(a: &[f64], b: &[f64]) -> f64 {
    let diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    let scale = a.iter().map(|x| x.abs()).fold(0.0, f64::max);
    if diff == 0.0 { 0.0 } else { diff / scale }
}

fn flat(v: &[nalgebra::Vector3<f64>]) -> Vec<f64> {
    v.iter().flat_map(|p| [p.x, p.y, p.z]).collect()
}

/// (positions, velocities, histories) relative differences.
fn compare(a: &State, b: &State) -> [f64; 3] {
    let h = |s: &State| s.history.concat();
    [
        relative(&flat(&a.x), &flat(&b.x)),
        relative(&flat(&a.v), &flat(&b.v)),
        relative(&h(a), &h(b)),
    ]
}

/// Each node's contact force.
type Forces = Vec<nalgebra::Vector3<f64>>;

fn cpu_run(scene: &Scene, steps: Option<u64>) -> (State, f64) {
    let (state, seconds, _) = cpu_run_with_contact(scene, steps);
    (state, seconds)
}

/// [`cpu_run`], and the last step's contact force on each node (the
/// multipliers' forces; empty without a tool).
fn cpu_run_with_contact(scene: &Scene, steps: Option<u64>) -> (State, f64, Forces) {
    let mut settings = scene.settings.clone();
    settings.max_steps = steps;
    let mut state = scene.model.initial_state();
    let mut explicit = Explicit::new(&scene.model, settings).expect("a driver");
    let started = Instant::now();
    explicit
        .run(&mut state, &mut NoObserver)
        .expect("the CPU run");
    let seconds = started.elapsed().as_secs_f64();
    let forces = explicit
        .contact()
        .map_or_else(Vec::new, |c| c.force.clone());
    (state, seconds, forces)
}

/// `steps` steps on the GPU at `threads` per block: the state, the
/// seconds, the blocks, the threads, and the last step's contact force on
/// each node (empty without a tool).
fn gpu_run(scene: &Scene, steps: Option<u64>, threads: u32) -> (State, f64, u64, u32, Forces) {
    let mut settings = scene.settings.clone();
    settings.max_steps = steps;
    let explicit = Explicit::new(&scene.model, settings.clone()).expect("a driver");
    let mut gpu = CudaStep::new(&explicit).expect("the GPU step");
    let threads = gpu.set_block_threads(threads).expect("threads per block");
    let mut state = scene.model.initial_state();
    let started = Instant::now();
    let run = run_steps(&mut gpu, &explicit, &mut state, steps).expect("the GPU run");
    let seconds = started.elapsed().as_secs_f64();
    let forces = if scene.model.tools.is_empty() {
        Vec::new()
    } else {
        gpu.snapshot(&mut state).expect("a snapshot").contact_force
    };
    (state, seconds, run.blocks, threads, forces)
}

fn gpu_run_full(scene: &Scene) -> (State, f64, drape_gpu::StepRun, u32) {
    let explicit = Explicit::new(&scene.model, scene.settings.clone()).expect("a driver");
    let mut gpu = CudaStep::new(&explicit).expect("the GPU step");
    let mut state = scene.model.initial_state();
    let started = Instant::now();
    let run = run_steps(&mut gpu, &explicit, &mut state, None).expect("the GPU run");
    (state, started.elapsed().as_secs_f64(), run, 256)
}

fn main() {
    let skip_big = std::env::args().any(|a| a == "--skip-big");
    match probe() {
        Ok(count) => println!("GPUs the driver sees: {count}"),
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    }
    println!("CPU threads: {}", rayon_threads());
    let mut failed = false;

    println!("\n## 1. Agreement with the CPU driver (largest difference / largest value)");
    println!(
        "(bounded: positions 1e-9, velocities, histories and contact forces 1e-6, over the first 1000 steps; \
         the 20 000-step rows, through the punch's first contact, are for information)"
    );
    println!("| scene | steps | positions | velocities | resin history | contact forces |");
    println!("|---|---|---|---|---|---|");
    let shipped = |name: &str| {
        Scene::from_file(Path::new(&format!("scenes/{name}.toml")), &[]).expect("a shipped scene")
    };
    let cases = [
        ("hemisphere blank 40 x 40, no punch", blank(40, 1.0), 1000),
        ("hemisphere-0-90", shipped("hemisphere-0-90"), 1000),
        ("hemisphere-45", shipped("hemisphere-45"), 1000),
        ("hemisphere-conform", shipped("hemisphere-conform"), 1000),
        ("picture-frame", shipped("picture-frame"), 1000),
        (
            "picture-frame of twintex-plain (shear locking)",
            Scene::from_file(
                Path::new("scenes/picture-frame.toml"),
                &[("fabric.material".into(), "\"twintex-plain\"".into())],
            )
            .expect("a shipped scene"),
            1000,
        ),
        ("bias-extension", shipped("bias-extension"), 1000),
        ("imported-plate", shipped("imported-plate"), 1000),
        (
            "glass sheet, clamped edge",
            Scene::parse(SHEET, Path::new("sheet.toml"), &[]).expect("scene"),
            600,
        ),
        (
            "glass sheet with nodal loads",
            Scene::parse(scenes::LOADED_SHEET, Path::new("loads.toml"), &[]).expect("scene"),
            600,
        ),
        (
            "ply vacuum-bagged on a dome",
            Scene::parse(scenes::VACUUM_DOME, Path::new("vacuum.toml"), &[]).expect("scene"),
            1000,
        ),
        ("hemisphere-0-90", shipped("hemisphere-0-90"), 20_000),
        ("hemisphere-45", shipped("hemisphere-45"), 20_000),
    ];
    let mut first_gpu = None;
    for (name, scene, steps) in &cases {
        let (cpu, _, cpu_forces) = cpu_run_with_contact(scene, Some(*steps));
        let (gpu, _, _, _, gpu_forces) = gpu_run(scene, Some(*steps), 256);
        let [x, v, h] = compare(&cpu, &gpu);
        // The multipliers' forces (none without a tool).
        let f = relative(&flat(&cpu_forces), &flat(&gpu_forces));
        let forces = if cpu_forces.is_empty() {
            "—".to_owned()
        } else {
            format!("{f:.2e}")
        };
        println!("| {name} | {steps} | {x:.2e} | {v:.2e} | {h:.2e} | {forces} |");
        if *steps <= 1000 {
            failed |= !(x <= 1e-9 && v <= 1e-6 && h <= 1e-6 && f <= 1e-6);
        }
        first_gpu.get_or_insert(gpu);
    }

    println!("\n## 2. Repeatability (hemisphere blank, 1000 steps)");
    let reference = first_gpu.expect("a first run");
    for threads in [256, 64, 1024] {
        let (again, _, _, threads, _) = gpu_run(&cases[0].1, Some(1000), threads);
        let same =
            again.x == reference.x && again.v == reference.v && again.history == reference.history;
        println!(
            "{threads} threads per block: {}",
            if same { "same bits" } else { "DIFFERENT" }
        );
        failed |= !same;
    }

    println!("\n## 3. Whole runs of the steps alone (no frames) on the GPU");
    for (name, scene) in [
        ("hemisphere blank 40 x 40, no punch", blank(40, 1.0)),
        ("shipped hemisphere-0-90", hemisphere(40, &[])),
    ] {
        let (gpu, gpu_s, run, _) = gpu_run_full(&scene);
        println!(
            "{name}: {} steps in {gpu_s:.3} s ({} blocks; {:.3} s of it in the stable step's \
             re-estimates on the host)",
            gpu.step, run.blocks, run.estimate_seconds
        );
    }

    println!(
        "\n## 4. The step alone, µs per step: the shipped hemisphere at N x N cells (punch projected at every node, bending)"
    );
    println!("| blank | nodes | quads | trusses | GPU µs/step | CPU µs/step | set-up s |");
    println!("|---|---|---|---|---|---|---|");
    let mut profiles = Vec::new();
    let sizes: &[usize] = if skip_big {
        &[40, 200]
    } else {
        &[40, 200, 1000]
    };
    for &cells in sizes {
        let started = Instant::now();
        let scene = hemisphere(cells, &[]);
        let explicit = Explicit::new(&scene.model, scene.settings.clone()).expect("a driver");
        let mut gpu = CudaStep::new(&explicit).expect("the GPU step");
        let state = scene.model.initial_state();
        gpu.load(&state).expect("load");
        gpu.start_forces(0.0).expect("forces");
        let setup = started.elapsed().as_secs_f64();
        let dt = explicit.stable_time_step(&state.x);
        let p = StepParams::new(0.0, dt, dt);
        gpu.time_steps(40, p).expect("warm-up");
        let count = match cells {
            c if c <= 40 => 4000,
            c if c <= 200 => 2000,
            _ => 200,
        };
        let gpu_us = gpu.time_steps(count, p).expect("steps") / count as f64 * 1e6;
        let profile = gpu.profile(count.min(400), p).expect("profile");
        profiles.push((cells, profile));
        let cpu_us = if cells <= 200 {
            let steps = if cells <= 40 { 2000 } else { 200 };
            let (_, s) = cpu_run(&scene, Some(steps));
            format!("{:.1}", s / steps as f64 * 1e6)
        } else {
            "—".into()
        };
        let trusses: usize = scene.model.trusses.iter().map(|b| b.len()).sum();
        println!(
            "| {cells} × {cells} | {} | {} | {trusses} | {gpu_us:.2} | {cpu_us} | {setup:.1} |",
            scene.model.node_count(),
            scene.model.membrane_count()
        );
    }
    println!(
        "\n## 4b. Per kernel, µs per step, launched one after another on one stream (no graph: \
         small blanks include the launches' gaps)"
    );
    println!("| blank | gather and node step | trusses | membranes | springs | bending | sum |");
    println!("|---|---|---|---|---|---|---|");
    for (cells, p) in &profiles {
        println!(
            "| {cells} × {cells} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            p[0] + p[5],
            p[1],
            p[2],
            p[3],
            p[4],
            p.iter().sum::<f64>()
        );
    }
    if failed {
        println!("\nA check FAILED");
        std::process::exit(1);
    }
    println!("\nEvery agreement check passed");
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}
