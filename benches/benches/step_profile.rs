//! Where the explicit step's time goes, and what a second thread buys.
//!
//! Two tables, printed by `cargo xtask bench` before the criterion benches
//! (`cargo bench -p drape-benches --bench step_profile [-- --quick]`):
//!
//! 1. The per-pass profile of the explicit step ([`drape_time::profile`]):
//!    element forces by kind, gather, the contact pass by phase, boundary
//!    conditions, the works, checks, energies at outputs, output; µs per
//!    step and share, on 1 and 2 threads, for the hemisphere scene
//!    (scenes/hemisphere-0-90.toml, 40 × 40 cells) and the same scene with
//!    a 200 × 200-cell blank. Each starts from a state advanced into the
//!    stroke (so the punch is in contact), then profiles a window of steps.
//! 2. ms per step on 1 and on 2 threads for every shipped scene
//!    (scenes/*.toml), and their ratio, from a state a few hundred steps
//!    into the run.
//! 3. A triangle-mesh mould against the same mould as an analytic surface
//!    (`tray.rs`: a round, open-rimmed tray of ≈ 7 000 triangles and the
//!    surface of revolution of its profile, a 40 × 40 blank pressed in by a
//!    punch): the per-pass profile of each near the end of the stroke, then
//!    ms per step of each on one thread, alternating, best of three, and the
//!    mesh/analytic ratio.
//!
//! Wall-clock figures mean something only on a quiet machine: the load
//! average is printed next to them. With `DRAPE_BENCH_CLOCK=thread-cpu` the
//! one-thread figures are the driver thread's CPU time instead (a
//! per-core figure that survives a busy machine); two-thread figures are
//! always wall time. `--quick` profiles shorter windows from earlier in
//! the stroke. `--filter TEXT` keeps the cases and scenes whose name
//! contains TEXT; `--profile-scenes` prints the per-pass profile of each
//! shipped scene too (where a small model's step goes on 2 threads);
//! `--threads N` profiles on N threads only and `--steps N` profiles
//! windows of N steps (for a run under callgrind,
//! `--toggle-collect='*profile_steps*'`: the instructions of a step are
//! the difference of two windows' divided by the difference of their
//! steps, which leaves out the driver's set-up, first force pass and last
//! energies; windows of multiples of 20 steps hold the stable-Δt
//! estimates at their share).

use std::path::{Path, PathBuf};
use std::time::Duration;

mod tray;

use drape_benches::{Clock, Stopwatch};
use drape_io::scene::Scene;
use drape_model::State;
use drape_time::{
    DriverState, Explicit, ExplicitSettings, NoObserver, Observer, ProfileClock, StepProfile,
    profile,
};

/// `--set key.path=value` pairs.
type Overrides = Vec<(String, String)>;

/// How far into a run a measurement starts and how many steps it takes.
#[derive(Debug, Clone, Copy)]
struct Window {
    warm_steps: u64,
    steps: u64,
}

fn main() {
    // cargo bench passes `--bench`; criterion-style filters are ignored.
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    let profile_scenes = args.iter().any(|a| a == "--profile-scenes");
    let filter = args
        .iter()
        .position(|a| a == "--filter")
        .and_then(|k| args.get(k + 1))
        .cloned()
        .unwrap_or_default();
    let threads: Vec<usize> = args
        .iter()
        .position(|a| a == "--threads")
        .and_then(|k| args.get(k + 1))
        .map_or_else(|| vec![1, 2], |n| vec![n.parse().expect("--threads N")]);
    let steps: Option<u64> = args
        .iter()
        .position(|a| a == "--steps")
        .and_then(|k| args.get(k + 1))
        .map(|n| n.parse().expect("--steps N"));
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("benches/ sits in the workspace")
        .to_path_buf();
    let clock = Clock::from_env();
    println!(
        "drape step profile ({} mode); load average {}; one-thread figures by {}",
        if quick { "quick" } else { "full" },
        load_average(),
        match clock {
            Clock::Wall => "wall clock",
            Clock::ThreadCpu => "thread CPU time",
        }
    );
    let hemisphere = root.join("scenes/hemisphere-0-90.toml");
    let cases: [(&str, Overrides, Window); 2] = [
        (
            "hemisphere 40×40",
            Vec::new(),
            if quick {
                Window {
                    warm_steps: 1_000,
                    steps: 300,
                }
            } else {
                Window {
                    warm_steps: 15_000,
                    steps: 3_000,
                }
            },
        ),
        (
            "hemisphere scene, 200×200 blank",
            vec![("fabric.blank.cells".to_owned(), "[200, 200]".to_owned())],
            if quick {
                Window {
                    warm_steps: 100,
                    steps: 30,
                }
            } else {
                Window {
                    warm_steps: 1_500,
                    steps: 200,
                }
            },
        ),
    ];
    for (name, overrides, window) in cases.iter().filter(|c| c.0.contains(&filter)) {
        let scene = load(&hemisphere, overrides);
        let window = Window {
            steps: steps.unwrap_or(window.steps),
            ..*window
        };
        print_profiles(name, &scene, window, clock, &threads);
    }

    if "tray mould".contains(&filter) {
        tray_ratio(&root, quick, clock, &threads);
    }

    println!(
        "\n== ms per step, 1 vs 2 threads (wall clock), shipped scenes (load {})",
        load_average()
    );
    let cpu = clock == Clock::ThreadCpu;
    println!(
        "  {:<28} {:>7} {:>9} {:>9} {:>7}{}",
        "scene",
        "nodes",
        "1 thread",
        "2 threads",
        "2t/1t",
        if cpu { "   1 thread (CPU)" } else { "" }
    );
    let window = if quick {
        Window {
            warm_steps: 200,
            steps: 200,
        }
    } else {
        Window {
            warm_steps: 500,
            steps: 2_000,
        }
    };
    for path in shipped_scenes(&root) {
        let file = path.file_name().unwrap_or_default().to_string_lossy();
        if !file.contains(&filter) {
            continue;
        }
        let scene = load(&path, &[]);
        if profile_scenes {
            print_profiles(&file, &scene, window, clock, &threads);
        }
        let warm = advance(&scene, window.warm_steps);
        // Alternating 1 and 2 threads, best of three: a burst of other work
        // on the machine hits one repeat, not the figure.
        let mut best = [f64::INFINITY; 3];
        let runs = [(1, Clock::Wall), (2, Clock::Wall), (1, clock)];
        for _ in 0..3 {
            for (k, &(threads, c)) in runs.iter().enumerate().take(if cpu { 3 } else { 2 }) {
                let t = in_pool(threads, || time_steps(&scene, &warm, window.steps, c));
                best[k] = best[k].min(t.as_secs_f64() * 1e3 / window.steps as f64);
            }
        }
        let cpu_column = if cpu {
            format!(" {:>17.3}", best[2])
        } else {
            String::new()
        };
        println!(
            "  {:<28} {:>7} {:>9.3} {:>9.3} {:>7.2}{cpu_column}",
            path.file_name().unwrap_or_default().to_string_lossy(),
            scene.model.node_count(),
            best[0],
            best[1],
            best[1] / best[0],
        );
    }
}

/// The tray mould as a triangle mesh and as a surface of revolution: their
/// per-pass profiles and the ratio of their steps on one thread.
fn tray_ratio(root: &Path, quick: bool, clock: Clock, threads: &[usize]) {
    // Runs of 5 000 (quick: 2 500) steps, measured from 90 % of the stroke:
    // the blank is in the cavity, most nodes touch the mould or the punch.
    let end_time = if quick { 0.05 } else { 0.1 };
    let steps = (end_time / 2e-5_f64).round() as u64;
    let window = Window {
        warm_steps: steps * 9 / 10,
        steps: if quick { 100 } else { 400 },
    };
    let (meshed, analytic, triangles) =
        tray::write_scenes(&root.join("target/bench/tray"), end_time);
    let mesh_scene = load(&meshed, &[]);
    let revolution_scene = load(&analytic, &[]);
    println!(
        "\n== tray mould: a {triangles}-triangle open mesh against its surface of revolution (load {})",
        load_average()
    );
    let warm = [
        advance(&mesh_scene, window.warm_steps),
        advance(&revolution_scene, window.warm_steps),
    ];
    let names = ["tray mould, mesh", "tray mould, revolution"];
    let scenes = [&mesh_scene, &revolution_scene];
    for k in 0..2 {
        print_profiles_from(names[k], scenes[k], &warm[k], window, clock, threads);
    }
    let mut best = [f64::INFINITY; 2];
    for _ in 0..3 {
        for k in 0..2 {
            let t = in_pool(1, || time_steps(scenes[k], &warm[k], window.steps, clock));
            best[k] = best[k].min(t.as_secs_f64() * 1e3 / window.steps as f64);
        }
    }
    println!(
        "  ms per step on 1 thread (best of 3, steps {}..{}): mesh {:.3}, revolution {:.3}; \
         mesh/analytic ratio {:.2} (load {})",
        window.warm_steps,
        window.warm_steps + window.steps,
        best[0],
        best[1],
        best[0] / best[1],
        load_average()
    );
}

/// The per-pass profile of `window` on 1 and on 2 threads.
fn print_profiles(name: &str, scene: &Scene, window: Window, clock: Clock, threads: &[usize]) {
    let warm = advance(scene, window.warm_steps);
    print_profiles_from(name, scene, &warm, window, clock, threads);
}

/// [`print_profiles`] from a state already advanced.
fn print_profiles_from(
    name: &str,
    scene: &Scene,
    warm: &Warm,
    window: Window,
    clock: Clock,
    threads: &[usize],
) {
    let m = &scene.model;
    println!(
        "\n== {name}: {} nodes, {} membranes, {} trusses, {} springs, {} tools; \
         profile of steps {}..{} (load {})",
        m.node_count(),
        m.membrane_count(),
        m.trusses.iter().map(|b| b.len()).sum::<usize>(),
        m.springs.iter().map(|b| b.len()).sum::<usize>(),
        m.tools.len(),
        warm.state.step,
        warm.state.step + window.steps,
        load_average(),
    );
    for &threads in threads {
        let profile_clock: ProfileClock = match (clock, threads) {
            (Clock::ThreadCpu, 1) => thread_cpu,
            _ => profile::wall_clock,
        };
        let p = in_pool(threads, || {
            profile_steps(scene, warm, window.steps, profile_clock)
        });
        println!(
            "-- {threads} thread(s): {:.3} ms/step",
            p.step_time().as_secs_f64() * 1e3
        );
        print!("{}", p.table());
    }
}

fn load(path: &Path, overrides: &[(String, String)]) -> Scene {
    Scene::from_file(path, overrides).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn settings(scene: &Scene, steps: u64) -> ExplicitSettings {
    ExplicitSettings {
        max_steps: Some(steps),
        ..scene.settings.clone()
    }
}

/// A run stopped part way: its state and what its driver carries (the
/// tools' positions and velocities, the step size), so that a new driver
/// continues it instead of restarting the tools at their start.
struct Warm {
    state: State,
    driver: DriverState,
}

/// Keeps the last checkpoint a run hands out.
struct LastCheckpoint(Option<DriverState>);
impl Observer for LastCheckpoint {
    fn checkpoint(&mut self, _state: &State, driver: &DriverState) {
        self.0 = Some(driver.clone());
    }
}

/// The scene's run after `steps` steps on all threads.
fn advance(scene: &Scene, steps: u64) -> Warm {
    let mut state = scene.model.initial_state();
    let settings = ExplicitSettings {
        checkpoint_every: Some(steps.max(1)),
        ..settings(scene, steps)
    };
    let mut driver = Explicit::new(&scene.model, settings).expect("driver");
    let mut last = LastCheckpoint(None);
    driver.run(&mut state, &mut last).expect("warm-up run");
    Warm {
        state,
        driver: last.0.expect("a checkpoint at the end of the warm-up"),
    }
}

/// A driver for `steps` more steps that continues `warm`.
fn continuing<'m>(scene: &'m Scene, warm: &Warm, steps: u64) -> Explicit<'m> {
    let mut driver = Explicit::new(&scene.model, settings(scene, steps)).expect("driver");
    driver.resume_from(warm.driver.clone());
    driver
}

#[inline(never)]
fn profile_steps(scene: &Scene, start: &Warm, steps: u64, clock: ProfileClock) -> StepProfile {
    let mut driver = continuing(scene, start, steps);
    driver.enable_profile(clock);
    let mut state = start.state.clone();
    driver
        .run(&mut state, &mut NoObserver)
        .expect("profiled run");
    *driver.profile().expect("profiled")
}

/// Time of `steps` steps from `start` (the driver's set-up and its first
/// force pass not counted: they are a second run of one step, subtracted).
fn time_steps(scene: &Scene, start: &Warm, steps: u64, clock: Clock) -> Duration {
    let run = |n: u64| {
        let mut driver = continuing(scene, start, n);
        let mut state = start.state.clone();
        let watch = Stopwatch::start(clock);
        driver.run(&mut state, &mut NoObserver).expect("timed run");
        watch.elapsed()
    };
    let (one, many) = (run(1), run(steps + 1));
    many.saturating_sub(one)
}

fn in_pool<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a rayon pool")
        .install(f)
}

fn shipped_scenes(root: &Path) -> Vec<PathBuf> {
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(root.join("scenes"))
        .expect("scenes/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    scenes.sort();
    scenes
}

fn thread_cpu() -> Duration {
    drape_benches::thread_cpu_time()
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".to_owned())
}
