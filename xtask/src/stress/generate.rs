//! The stress suite's generators: random valid-looking scenes and damaged
//! mesh files, from a seeded generator so that a failing case is
//! reproduced by its seed (`cargo xtask stress --seed N`).
//!
//! Why not proptest: its strength is shrinking a failing input, which here
//! would mean re-running whole simulations; a seed and the scene written to
//! the case's directory reproduce a failure as well, and xtask stays on std
//! and the workspace's own crates.

use std::fmt::Write as _;
use std::time::Duration;

use super::{Context, Expect, Outcome, Row, Run, execute};
use crate::validate::Rng;

/// Steps a generated run may take before it is stopped (as "stopped"): it
/// is robustness that is tested, not a result.
const STEP_BUDGET: u64 = 1500;
/// The same for a run on a damaged mesh: loading is what is tested.
const MESH_STEP_BUDGET: u64 = 200;
/// Wall clock after which a generated run counts as hung.
const LIMIT: Duration = Duration::from_secs(120);

impl Rng {
    fn chance(&mut self, p: f64) -> bool {
        self.uniform(0.0, 1.0) < p
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[(self.next_u64() % items.len() as u64) as usize]
    }

    /// 10^U(lo, hi).
    fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        10f64.powf(self.uniform(lo, hi))
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

fn amplitude(rng: &mut Rng, end_time: f64) -> String {
    let duration = end_time * rng.uniform(0.1, 1.0);
    match rng.below(3) {
        0 => format!("{{ kind = \"smooth_step\", duration = {duration:e} }}"),
        1 => format!("{{ kind = \"ramp\", duration = {duration:e} }}"),
        _ => format!(
            "{{ kind = \"table\", points = [[0, 0], [{duration:e}, 1], [{:e}, 0.5]] }}",
            2.0 * duration
        ),
    }
}

/// A random scene that looks valid: every value of a plausible kind, in
/// ranges from far too soft to far too stiff, tools placed clear of the
/// blank. Some are bad input all the same (a holder that would cross the
/// blank in one step): they must be refused with a reason.
pub fn random_scene(rng: &mut Rng) -> String {
    let mut s = String::new();
    if rng.chance(0.5) {
        s.push_str("gravity = [0, 0, -9810]\n");
    }
    let end_time = rng.log_uniform(-4.0, -2.0);
    let _ = writeln!(
        s,
        "\n[simulation]\nend_time = {end_time:e}\nframes = {}",
        1 + rng.below(10)
    );
    if rng.chance(0.3) {
        let _ = writeln!(s, "mass_scaling_dt = {:e}", rng.log_uniform(-7.0, -5.0));
    }
    if rng.chance(0.3) {
        let _ = writeln!(s, "damping = {:?}", rng.uniform(0.0, 500.0));
    }
    if rng.chance(0.3) {
        let _ = writeln!(s, "safety_factor = {:?}", rng.uniform(0.2, 1.0));
    }
    if rng.chance(0.2) {
        s.push_str("quasi_static = true\n");
    }

    s.push_str("\n[fabric]\n");
    let any = rng.uniform(-90.0, 90.0);
    let orientation = *rng.pick(&[0.0, 45.0, 90.0, any]);
    let aligned = [0.0, 45.0, 90.0].contains(&orientation);
    let trusses = aligned && rng.chance(0.6);
    let _ = writeln!(
        s,
        "orientation_deg = {orientation:?}\nfibres = \"{}\"",
        if trusses { "trusses" } else { "embedded" }
    );
    // Square cells, so that a ±45 lattice fits.
    let (nx, ny) = (1 + rng.below(12), 1 + rng.below(12));
    let cell = rng.uniform(2.0, 40.0);
    let (width, height) = (nx as f64 * cell, ny as f64 * cell);
    let _ = writeln!(
        s,
        "blank = {{ width = {width:?}, height = {height:?}, cells = [{nx}, {ny}], element = \"{}\" }}",
        rng.pick(&["quad", "triangle"])
    );
    let thickness = rng.uniform(0.1, 2.0);
    if rng.chance(0.5) {
        let _ = writeln!(
            s,
            "material = \"{}\"",
            rng.pick(&["carbon-prepreg-2x2", "glass-serge-4x3"])
        );
    } else {
        let crimp = if rng.chance(0.3) {
            0.0
        } else {
            rng.uniform(0.0, 0.05)
        };
        let compression = if rng.chance(0.5) {
            0.0
        } else {
            rng.uniform(0.0, 1.0)
        };
        let _ = write!(
            s,
            "\n[fabric.material]\nname = \"random\"\nthickness = {thickness:?}\nfibre_volume_fraction = {:?}\n\
             density = {:e}\nfibre = {{ modulus = {:e}, crimp_strain = {crimp:?}, compression_factor = {compression:?} }}\n\
             resin = {{ young = {:e}, poisson = {:?}",
            rng.uniform(0.2, 0.7),
            rng.log_uniform(-9.5, -8.5),
            rng.log_uniform(2.0, 6.5),
            rng.log_uniform(-1.0, 3.5),
            rng.uniform(0.0, 0.49),
        );
        if rng.chance(0.3) {
            let _ = write!(
                s,
                ", prony = [{{ g = {:?}, tau = {:e} }}]",
                rng.uniform(0.0, 0.9),
                rng.log_uniform(-4.0, 1.0)
            );
        }
        s.push_str(" }\n");
    }

    // Tools, clear of the blank (its half thickness is at most 1 mm).
    for k in 0..rng.below(3) {
        let clear = rng.uniform(1.5, 10.0);
        let _ = write!(
            s,
            "\n[[tools]]\nname = \"tool{k}\"\nfriction = {:?}\n",
            if rng.chance(0.3) {
                0.0
            } else {
                rng.uniform(0.0, 1.5)
            }
        );
        match rng.below(4) {
            0 => {
                let _ = writeln!(
                    s,
                    "geometry = {{ kind = \"plane\", point = [0, 0, {:?}], normal = [0, 0, 1] }}",
                    -clear
                );
            }
            1 => {
                let r = rng.uniform(5.0, 100.0);
                let _ = writeln!(
                    s,
                    "geometry = {{ kind = \"sphere\", center = [0, 0, {:?}], radius = {r:?} }}",
                    -(r + clear)
                );
            }
            2 => {
                let r = rng.uniform(5.0, 100.0);
                let _ = writeln!(
                    s,
                    "geometry = {{ kind = \"hemispherical_punch\", pole = [0, 0, {:?}], radius = {r:?}, shank = {:?} }}",
                    -clear,
                    rng.uniform(0.0, 200.0)
                );
            }
            _ => {
                let inner = rng.uniform(1.0, 50.0);
                let _ = writeln!(
                    s,
                    "geometry = {{ kind = \"ring\", center = [0, 0, {clear:?}], inner_radius = {inner:?}, outer_radius = {:?} }}",
                    inner + rng.uniform(1.0, 200.0)
                );
                let _ = writeln!(
                    s,
                    "motion = {{ kind = \"force\", direction = [0, 0, -1], force = {:e}, mass = {:e}, amplitude = {} }}",
                    rng.log_uniform(-1.0, 5.0),
                    rng.log_uniform(-5.0, -1.0),
                    amplitude(rng, end_time)
                );
                continue;
            }
        }
        if rng.chance(0.6) {
            let _ = writeln!(
                s,
                "motion = {{ kind = \"displacement\", direction = [0, 0, 1], distance = {:?}, amplitude = {} }}",
                rng.uniform(0.0, 60.0),
                amplitude(rng, end_time)
            );
        }
    }
    if rng.chance(0.5) {
        s.push_str("\n[[boundary]]\nnodes = \"left\"\nmotion = { kind = \"fixed\" }\n");
    }
    if rng.chance(0.4) {
        let reach = 0.3 * width;
        let _ = write!(
            s,
            "\n[[boundary]]\nnodes = \"right\"\ncomponents = \"{}\"\nmotion = {{ kind = \"{}\", value = [{:?}, {:?}, {:?}], amplitude = {} }}\n",
            rng.pick(&["xyz", "x", "xz"]),
            rng.pick(&["displacement", "velocity"]),
            rng.uniform(-reach, reach),
            rng.uniform(-reach, reach),
            rng.uniform(-reach, reach),
            amplitude(rng, end_time)
        );
    }
    if rng.chance(0.2) {
        let _ = write!(
            s,
            "\n[[loads]]\nnodes = \"corners\"\nforce = [{:e}, 0, {:e}]\n",
            rng.log_uniform(-3.0, 2.0),
            -rng.log_uniform(-3.0, 2.0)
        );
    }
    if rng.chance(0.2) {
        let _ = write!(
            s,
            "\n[[springs]]\nnodes = [\"corners\", \"edge_midpoints\"]\nstiffness = {:e}\n",
            rng.log_uniform(-1.0, 2.0),
        );
        // A preload needs an anchor away from the node, or it is refused
        // (now and then it is not given one, to see it refused).
        if rng.chance(0.5) {
            let _ = writeln!(s, "preload = {:?}", rng.uniform(0.0, 5.0));
            if rng.chance(0.8) {
                let _ = writeln!(s, "anchor_offset = [0, 0, {:?}]", -rng.uniform(1.0, 50.0));
            }
        }
    }
    s.push_str("\n[output]\nvtu = false\npictures = false\n");
    s
}

/// Tallies a generator's outcomes into one row: it passes if every run is
/// robust (see [`Expect::Robust`]); the row names the first failures'
/// cases and where their scenes are.
fn tally(ctx: &Context, budget: u64, outcomes: Vec<(String, Outcome)>, seconds: f64) -> Row {
    let runs = outcomes.len();
    let (mut completed, mut stopped, mut failed, mut refused) = (0, 0, 0, 0);
    let mut bad = Vec::new();
    for (label, outcome) in &outcomes {
        match outcome {
            Outcome::Refused(_) => refused += 1,
            Outcome::Ran { summary, .. } => match summary.status.as_str() {
                "completed" => completed += 1,
                "stopped" => stopped += 1,
                _ => failed += 1,
            },
            _ => {}
        }
        if !outcome.passes(Expect::Robust) {
            bad.push(format!("{label}: {}", outcome.describe()));
        }
    }
    let mut happened = format!(
        "{runs} runs (seed {}): {completed} completed, {stopped} stopped at the {budget}-step budget, \
         {failed} failed with a diagnosis, {refused} refused",
        ctx.seed
    );
    if !bad.is_empty() {
        let _ = write!(
            happened,
            "; {} NOT ROBUST: {}",
            bad.len(),
            bad[..bad.len().min(3)].join("; ")
        );
    }
    Row {
        case: ctx.name.to_owned(),
        expect: Expect::Robust,
        happened,
        pass: bad.is_empty(),
        seconds,
    }
}

/// `count` random scenes, each run for at most [`STEP_BUDGET`] steps.
pub fn random_scenes(ctx: &Context, count: usize) -> Row {
    let started = std::time::Instant::now();
    let mut outcomes = Vec::new();
    for k in 0..count {
        let mut rng = Rng::new(ctx.seed.wrapping_mul(1_000_003).wrapping_add(k as u64));
        let text = random_scene(&mut rng);
        let dir = ctx.dir.join(format!("scene-{k:03}"));
        let outcome = execute(
            &dir,
            Run {
                step_budget: Some(STEP_BUDGET),
                limit: LIMIT,
                ..Run::scene(text)
            },
        );
        outcomes.push((format!("{}", dir.display()), outcome));
    }
    tally(ctx, STEP_BUDGET, outcomes, started.elapsed().as_secs_f64())
}

/// A flat 100 × 100 mm plate 1 mm below z = 0 as an ASCII STL, with a
/// zero-area triangle (three points on a line), a triangle that repeats a
/// vertex and a duplicate of a good triangle among its two good ones.
pub fn degenerate_plate_stl() -> String {
    let tri = |n: [f64; 3], v: [[f64; 3]; 3]| {
        let mut t = format!(
            "  facet normal {} {} {}\n    outer loop\n",
            n[0], n[1], n[2]
        );
        for p in v {
            let _ = writeln!(t, "      vertex {} {} {}", p[0], p[1], p[2]);
        }
        t.push_str("    endloop\n  endfacet\n");
        t
    };
    let z = -1.0;
    let (a, b, c, d) = (
        [-50.0, -50.0, z],
        [50.0, -50.0, z],
        [50.0, 50.0, z],
        [-50.0, 50.0, z],
    );
    let up = [0.0, 0.0, 1.0];
    let mut s = String::from("solid plate\n");
    s.push_str(&tri(up, [a, b, c]));
    s.push_str(&tri(up, [a, c, d]));
    s.push_str(&tri(up, [a, [0.0, 0.0, z], c])); // on the diagonal: no area
    s.push_str(&tri(up, [b, b, c])); // a vertex twice
    s.push_str(&tri(up, [a, b, c])); // the first again
    s.push_str("endsolid plate\n");
    s
}

/// A closed box as an OBJ: the tool of the damaged-OBJ cases.
fn box_obj() -> String {
    let mut s = String::from("# a 40 × 40 × 20 mm box under the blank\n");
    for (x, y, z) in [
        (-20, -20, -22),
        (20, -20, -22),
        (20, 20, -22),
        (-20, 20, -22),
        (-20, -20, -2),
        (20, -20, -2),
        (20, 20, -2),
        (-20, 20, -2),
    ] {
        let _ = writeln!(s, "v {x} {y} {z}");
    }
    for f in [
        [1, 3, 2],
        [1, 4, 3],
        [5, 6, 7],
        [5, 7, 8],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 4, 8],
        [3, 8, 7],
        [4, 1, 5],
        [4, 5, 8],
    ] {
        let _ = writeln!(s, "f {} {} {}", f[0], f[1], f[2]);
    }
    s
}

/// A closed box as an ASCII STL (normals left to drape to compute).
fn box_stl() -> String {
    let obj = box_obj();
    let v: Vec<[f64; 3]> = obj
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let c: Vec<f64> = l.split_whitespace().map(|t| t.parse().unwrap()).collect();
            [c[0], c[1], c[2]]
        })
        .collect();
    let mut s = String::from("solid box\n");
    for f in obj.lines().filter_map(|l| l.strip_prefix("f ")) {
        s.push_str("  facet normal 0 0 0\n    outer loop\n");
        for i in f.split_whitespace() {
            let p = v[i.parse::<usize>().unwrap() - 1];
            let _ = writeln!(s, "      vertex {} {} {}", p[0], p[1], p[2]);
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    s.push_str("endsolid box\n");
    s
}

/// Values a damaged file may hold where a number should be.
const HOSTILE: [&str; 12] = [
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "0",
    "-0",
    "abc",
    "",
    "99999999999999999999",
    "1e-320",
    "3.5.2",
];

/// One damage: truncation, a line deleted, doubled or swapped, a number
/// replaced by a hostile value, a byte overwritten, a garbage line.
fn damage(rng: &mut Rng, bytes: &[u8]) -> (Vec<u8>, String) {
    let text = String::from_utf8_lossy(bytes).into_owned();
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let n = lines.len().max(1);
    let what;
    match rng.below(7) {
        0 => {
            let at = rng.below(bytes.len().max(1));
            return (bytes[..at].to_vec(), format!("truncated at byte {at}"));
        }
        1 => {
            let at = rng.below(n);
            lines.remove(at.min(lines.len().saturating_sub(1)));
            what = format!("line {} deleted", at + 1);
        }
        2 => {
            let at = rng.below(n).min(lines.len().saturating_sub(1));
            let line = lines.get(at).cloned().unwrap_or_default();
            lines.insert(at, line);
            what = format!("line {} doubled", at + 1);
        }
        3 => {
            let (i, j) = (rng.below(n), rng.below(n));
            if i < lines.len() && j < lines.len() {
                lines.swap(i, j);
            }
            what = format!("lines {} and {} swapped", i + 1, j + 1);
        }
        4 => {
            // A number token somewhere.
            let at = rng.below(n).min(lines.len().saturating_sub(1));
            let value = *rng.pick(&HOSTILE);
            if let Some(line) = lines.get_mut(at) {
                let tokens: Vec<&str> = line
                    .split(|c: char| c == ',' || c.is_whitespace())
                    .collect();
                let numeric: Vec<&str> = tokens
                    .iter()
                    .copied()
                    .filter(|t| t.parse::<f64>().is_ok())
                    .collect();
                if !numeric.is_empty() {
                    let target = numeric[rng.below(numeric.len())].to_owned();
                    *line = line.replacen(&target, value, 1);
                }
            }
            what = format!("a number on line {} set to `{value}`", at + 1);
        }
        5 => {
            let mut out = bytes.to_vec();
            if !out.is_empty() {
                let at = rng.below(out.len());
                out[at] = (rng.next_u64() & 0xff) as u8;
                return (out, format!("byte {at} overwritten"));
            }
            return (out, "empty".into());
        }
        _ => {
            let at = rng.below(n);
            lines.insert(at.min(lines.len()), "1 2 3 4 5 6 7 8 9 $End garbage".into());
            what = format!("garbage inserted at line {}", at + 1);
        }
    }
    let mut out = lines.join("\n");
    out.push('\n');
    (out.into_bytes(), what)
}

/// `count` damaged mesh files, a quarter each of the Gmsh and Abaqus
/// blanks shipped in `scenes/meshes` and of STL and OBJ tools: each loaded
/// by a scene and, if it loads, run for a short while.
pub fn damaged_meshes(ctx: &Context, count: usize) -> Row {
    let started = std::time::Instant::now();
    let read = |name: &str| std::fs::read(ctx.root.join("scenes/meshes").join(name));
    let (msh, inp) = match (read("plate.msh"), read("plate.inp")) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(e), _) | (_, Err(e)) => {
            return Row {
                case: ctx.name.to_owned(),
                expect: Expect::Robust,
                happened: format!("could not read scenes/meshes: {e}"),
                pass: false,
                seconds: 0.0,
            };
        }
    };
    let blank_scene = |file: &str| {
        format!(
            "gravity = [0, 0, -9810]\n\n[simulation]\nend_time = 0.01\nframes = 2\nmass_scaling_dt = 2e-5\n\n\
             [fabric]\nmaterial = \"glass-serge-4x3\"\norientation_deg = 30\nfibres = \"embedded\"\n\
             blank = {{ mesh = \"{file}\" }}\n\n[[tools]]\nname = \"floor\"\n\
             geometry = {{ kind = \"plane\", point = [0, 0, -2], normal = [0, 0, 1] }}\n\n\
             [output]\nvtu = false\npictures = false\n"
        )
    };
    let tool_scene = |file: &str| {
        format!(
            "gravity = [0, 0, -9810]\n\n[simulation]\nend_time = 0.01\nframes = 2\nmass_scaling_dt = 2e-5\n\n\
             [fabric]\nmaterial = \"glass-serge-4x3\"\nfibres = \"trusses\"\n\
             blank = {{ width = 60, height = 60, cells = [6, 6] }}\n\n[[tools]]\nname = \"box\"\nfriction = 0.2\n\
             geometry = {{ kind = \"mesh\", file = \"{file}\" }}\n\n[output]\nvtu = false\npictures = false\n"
        )
    };
    let sources: [(&str, Vec<u8>); 4] = [
        ("plate.msh", msh),
        ("plate.inp", inp),
        ("box.stl", box_stl().into_bytes()),
        ("box.obj", box_obj().into_bytes()),
    ];
    let mut outcomes = Vec::new();
    for k in 0..count {
        let (name, bytes) = &sources[k % sources.len()];
        let mut rng = Rng::new(ctx.seed.wrapping_mul(7_919).wrapping_add(k as u64));
        let (mut damaged, mut what) = damage(&mut rng, bytes);
        // Sometimes two or three damages at once.
        for _ in 0..rng.below(3) {
            let (again, more) = damage(&mut rng, &damaged);
            damaged = again;
            what = format!("{what}, {more}");
        }
        let scene = if name.starts_with("plate") {
            blank_scene(name)
        } else {
            tool_scene(name)
        };
        let dir = ctx.dir.join(format!("mesh-{k:03}"));
        let outcome = execute(
            &dir,
            Run {
                files: vec![((*name).to_owned(), damaged)],
                step_budget: Some(MESH_STEP_BUDGET),
                limit: LIMIT,
                ..Run::scene(scene)
            },
        );
        outcomes.push((format!("{} ({name}: {what})", dir.display()), outcome));
    }
    tally(
        ctx,
        MESH_STEP_BUDGET,
        outcomes,
        started.elapsed().as_secs_f64(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_scenes_are_toml_and_depend_on_the_seed_only() {
        let a = random_scene(&mut Rng::new(3));
        assert_eq!(a, random_scene(&mut Rng::new(3)));
        assert_ne!(a, random_scene(&mut Rng::new(4)));
        for seed in 0..50 {
            let text = random_scene(&mut Rng::new(seed));
            assert!(text.parse::<toml::Table>().is_ok(), "seed {seed}:\n{text}");
        }
    }

    #[test]
    fn the_test_meshes_are_well_formed() {
        let stl = box_stl();
        assert_eq!(stl.matches("facet normal").count(), 12);
        assert_eq!(degenerate_plate_stl().matches("facet normal").count(), 5);
        let mut rng = Rng::new(1);
        for _ in 0..100 {
            let (bytes, what) = damage(&mut rng, stl.as_bytes());
            assert!(!what.is_empty());
            assert!(bytes.len() <= stl.len() + 64);
        }
    }
}
