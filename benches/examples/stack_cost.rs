//! What a step of the four-ply hemisphere (`scenes/hemisphere-stack-4.toml`)
//! costs against its bottom ply alone, pass by pass: a measuring tool for
//! issue 31's "four plies ≤ 5× one ply", not a bench (nothing is checked).
//!
//! `cargo run --release -p drape-benches --example stack_cost -- PLIES
//! [--threads N] [--scene FILE] [--set key=value]...` runs the scene's
//! (the four-ply hemisphere's unless `--scene` names another) first PLIES plies
//! with the overrides on a pool of N threads (1 by default), profiled
//! by the driver thread's CPU time on one thread (the wall clock on more),
//! and prints: nodes and elements, steps, the process's CPU time, the
//! per-pass profile, the ply pass's totals and a hash of the final state's
//! bits (positions and velocities), so two builds can be compared for
//! identical results.

use std::path::Path;

use drape_time::{Explicit, NoObserver, profile};

fn process_cpu() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |k: usize| fields.get(k).and_then(|f| f.parse::<f64>().ok());
    match (ticks(11), ticks(12)) {
        (Some(u), Some(s)) => (u + s) / 100.0,
        _ => f64::NAN,
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let plies: usize = args
        .first()
        .and_then(|a| a.parse().ok())
        .expect("PLIES first");
    let mut threads = 1;
    let mut overrides = Vec::new();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut path = root.join("scenes/hemisphere-stack-4.toml");
    let mut k = 1;
    while k < args.len() {
        match args[k].as_str() {
            "--threads" => threads = args[k + 1].parse().expect("--threads N"),
            "--scene" => path = args[k + 1].clone().into(),
            "--set" => {
                let (key, value) = args[k + 1].split_once('=').expect("--set key=value");
                overrides.push((key.to_string(), value.to_string()));
            }
            other => panic!("unknown argument {other}"),
        }
        k += 2;
    }
    let text = std::fs::read_to_string(&path).expect("scene");
    let starts: Vec<usize> = text
        .match_indices("[[stack.ply]]")
        .map(|(i, _)| i)
        .collect();
    let text = if plies < starts.len() {
        let tools = text.find("[[tools]]").expect("tools");
        format!("{}{}", &text[..starts[plies]], &text[tools..])
    } else {
        text
    };
    let scene = drape_io::scene::Scene::parse(&text, &path, &overrides).expect("scene");
    let model = &scene.model;
    let trusses: usize = model.trusses.iter().map(|b| b.len()).sum();
    let springs: usize = model.springs.iter().map(|b| b.len()).sum();
    println!(
        "plies {} nodes {} membranes {} trusses {} springs {} threads {threads}",
        model.plies.len().max(1),
        model.node_count(),
        model.membrane_count(),
        trusses,
        springs,
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    let clock: drape_time::ProfileClock = if threads == 1 {
        drape_benches::thread_cpu_time
    } else {
        profile::wall_clock
    };
    pool.install(|| {
        let mut state = model.initial_state();
        let mut driver = Explicit::new(model, scene.settings.clone()).expect("driver");
        driver.enable_profile(clock);
        let cpu = process_cpu();
        let result = driver.run(&mut state, &mut NoObserver);
        let cpu = process_cpu() - cpu;
        match &result {
            Ok(s) => println!("completed: {} steps, t = {:.4} s", s.steps, state.time),
            Err(e) => println!("stopped: {e}"),
        }
        println!("process CPU {cpu:.2} s");
        let p = driver.profile().expect("profiled");
        println!(
            "profile ({}), {} steps, {:.1} µs/step:\n{}",
            if threads == 1 { "thread CPU" } else { "wall" },
            p.steps,
            p.step_time().as_secs_f64() * 1e6,
            p.table()
        );
        if let Some(c) = driver.contact() {
            println!("tool candidates {:?}", c.candidate_counts());
            if let Some(pl) = c.plies() {
                let t = &pl.totals;
                let per = |n: u64| n as f64 / t.steps.max(1) as f64;
                println!(
                    "ply pass: {} steps, {:.0} constraints, {:.2} normal sweeps (max {}, capped {}, stalled {}), \
                     {:.2} friction sweeps (max {}, capped {}, stalled {}), {} candidate pairs now, \
                     {} nodes shifted",
                    t.steps,
                    per(t.constraints),
                    per(t.normal_sweeps),
                    t.max_normal_sweeps,
                    t.normal_capped,
                    t.normal_stalled,
                    per(t.friction_sweeps),
                    t.max_friction_sweeps,
                    t.friction_capped,
                    t.friction_stalled,
                    pl.candidate_pairs(),
                    t.shifted_nodes,
                );
            }
        }
        // FNV-1a over the bits of x and v.
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for p in state.x.iter().chain(&state.v) {
            for c in p.iter() {
                for b in c.to_bits().to_le_bytes() {
                    h ^= u64::from(b);
                    h = h.wrapping_mul(0x0000_0100_0000_01b3);
                }
            }
        }
        println!("state hash {h:016x} (step {})", state.step);
    });
}
