//! Loads a scene and runs it without writing results, printing the energy
//! and the measures at each frame: a quick look while building scenes.
//!
//! `cargo run --release -p drape-io --example try_scene -- scenes/hemisphere-0-90.toml [key=value …]`

use drape_io::scene::Scene;
use drape_time::{Explicit, Frame, Observer};

struct Print;
impl Observer for Print {
    fn frame(&mut self, f: &Frame<'_>) {
        let m = f.model.measures(f.state, 50.0).unwrap();
        let e = f.energy;
        let d = m.draw_in.unwrap_or_default();
        eprintln!(
            "frame {:>3} t={:.4} step={} max shear {:.2}° draw-in dx {:.1} dd {:.1} Ekin/Eint {:.2e} balance {:.2e} contact {:?}",
            f.index,
            f.state.time,
            f.state.step,
            m.max_shear_deg,
            d.dx,
            d.dd,
            e.kinetic_to_internal(),
            e.relative_error(),
            f.contact.map(|c| c.tool_force.to_vec())
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let overrides: Vec<(String, String)> = args[1..]
        .iter()
        .map(|s| {
            let (k, v) = s.split_once('=').expect("key=value");
            (k.to_owned(), v.to_owned())
        })
        .collect();
    let scene = Scene::from_file(args[0].as_ref(), &overrides).unwrap_or_else(|e| panic!("{e}"));
    let mut state = scene.model.initial_state();
    let t = std::time::Instant::now();
    let summary = Explicit::new(&scene.model, scene.settings.clone())
        .unwrap()
        .run(&mut state, &mut Print);
    eprintln!(
        "{:?}\nwall {:.1} s",
        summary.map(|s| (s.steps, s.added_mass, s.total_mass)),
        t.elapsed().as_secs_f64()
    );
}
