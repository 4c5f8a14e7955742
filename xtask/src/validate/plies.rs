//! Validation of laminates: contact and Coulomb friction between the
//! plies of a stack through the explicit driver: a ply pulled over another
//! under a normal load (the sled), a two-ply stack on an incline (which
//! interface slides first), no interpenetration of two plies formed
//! together over the hemisphere, and two plies without friction between
//! them against each ply formed alone (on the free hemisphere, and drawn
//! through a die under a holder in [`held`]).
//!
//! References come from closed formulas evaluated here (μN, the rigid
//! slide of a constant or ramped force, the friction angle atan μ) and,
//! for the overlap, from a distance computed here from the positions
//! alone, never from the contact crate.

use drape_constitutive::Material;
use drape_contact::Surface;
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::stack::PlyModel;
use drape_model::{Amplitude, BoundaryCondition, Model, NodalLoad, Tool, ToolMotion};
use drape_time::{Explicit, ExplicitSettings, Frame, Observer};
use nalgebra::{Matrix3, Vector3};

use super::{Case, Check, note};

mod four;
mod held;
mod pressed;

/// The cases of this module.
pub const CASES: &[Case] = &[
    Case {
        name: "plies/sled",
        quick: true,
        run: sled,
    },
    Case {
        name: "plies/incline",
        quick: true,
        run: incline,
    },
    Case {
        name: "plies/hemisphere-overlap",
        quick: true,
        run: hemisphere_overlap,
    },
    Case {
        name: "plies/hemisphere-friction",
        quick: false,
        run: hemisphere_friction,
    },
    Case {
        name: "plies/hemisphere-frictionless",
        quick: false,
        run: hemisphere_frictionless,
    },
    Case {
        name: "plies/held-frictionless",
        quick: false,
        run: held::held_frictionless,
    },
    Case {
        name: "plies/pressed-stack",
        quick: true,
        run: pressed::pressed_stack,
    },
    Case {
        name: "plies/hemisphere-four",
        quick: true,
        run: four::hemisphere_four,
    },
];

/// Gravity (mm/s²).
const G: f64 = 9810.0;

struct Frames<F: FnMut(&Frame<'_>)>(F);
impl<F: FnMut(&Frame<'_>)> Observer for Frames<F> {
    fn frame(&mut self, frame: &Frame<'_>) {
        (self.0)(frame)
    }
}

/// Two square glass plies `sides` mm across (bottom, top) of 10 mm quads
/// (embedded fibres) stacked on a plane through the origin whose normal
/// is `rot`·z, the bottom ply's mid-surface half a thickness above it.
fn two_plies(rot: Matrix3<f64>, friction: f64, sides: [f64; 2]) -> Model {
    let material = Material::preset("glass-serge-4x3").expect("preset");
    let h = material.thickness;
    let ply = |name: &str, side: f64| {
        let cells = (side / 10.0).round() as usize;
        let blank = RectangleBlank {
            width: side,
            height: side,
            center: Vector3::new(0.0, 0.0, 0.5 * h),
            orientation_deg: 0.0,
            element: ElementKind::Quad,
            meshing: Meshing::Cells([cells, cells]),
            fibres: FibreRepresentation::Embedded,
        };
        let mut mesh = blank.mesh().expect("mesh");
        for x in &mut mesh.x0 {
            *x = rot * *x;
        }
        mesh.warp = rot * mesh.warp;
        PlyModel {
            model: Model::from_mesh(&mesh, &material, FibreRepresentation::Embedded)
                .expect("model"),
            name: name.into(),
            thickness: h,
            orientation_deg: 0.0,
            friction_below: friction,
        }
    };
    Model::stack(vec![ply("bottom", sides[0]), ply("top", sides[1])]).expect("stack")
}

/// Mean displacement of a ply's nodes along `along`.
fn mean_along(model: &Model, x: &[Vector3<f64>], ply: usize, along: Vector3<f64>) -> f64 {
    let nodes = model.plies[ply].nodes.clone();
    let n = nodes.len() as f64;
    nodes
        .map(|i| (x[i as usize] - model.x0[i as usize]).dot(&along))
        .sum::<f64>()
        / n
}

/// The sled: the bottom ply held, the top ply pressed on it by N = 1 N
/// and pulled along x by F(t) = 2μN·t/T, both spread over its nodes by
/// their areas (so every node carries the same F/N and the ply moves as a
/// rigid body, with no stress to blur the onset). It sticks while F < μN;
/// once F passes μN it slides with the friction at μN, and its slide is
/// the pull beyond the stick phase, x(t) = (2μN/(T·M))·(t − t_s)³/6 with
/// t_s = T/2 (M the ply's mass).
///
/// Tolerances: while sticking the slide is 0 to 1e-9 mm and the friction
/// equals F to 1e-6 and the sliding friction μN to 1e-6 (the issue asks
/// 1 %; the multipliers come out within 3e-9 with rigid ply rows at the
/// normal solve's tolerance, 1e-5 of a step's violation, within 9.4e-8
/// and 3.5e-8 with the compliant rows of `NORMAL_COMPLIANCE`, and within
/// 6e-7 to 6e-6 at a tolerance of 1e-4); the slide to 1e-5
/// (central differences integrate the cubic exactly but for the onset
/// falling inside a step, an error of order (Δt/T)², Δt/T ≈ 2e-4).
fn sled() -> Vec<Check> {
    let mut checks = Vec::new();
    for mu in [0.1, 0.3] {
        // The bottom ply twice as wide, so the top one slides on it.
        let mut model = two_plies(Matrix3::identity(), mu, [40.0, 20.0]);
        let bottom: Vec<u32> = model.plies[0].nodes.clone().collect();
        model.boundary.push(BoundaryCondition::fixed(bottom));
        let area = model.nodal_area();
        let top = model.plies[1].nodes.clone();
        let total: f64 = top.clone().map(|i| area[i as usize]).sum();
        let (normal, period) = (1.0, 0.01);
        for i in top.clone() {
            let share = area[i as usize] / total;
            model.loads.push(NodalLoad {
                nodes: vec![i],
                force: Vector3::new(0.0, 0.0, -normal * share),
                amplitude: Amplitude::Constant,
            });
            model.loads.push(NodalLoad {
                nodes: vec![i],
                force: Vector3::new(2.0 * mu * normal * share, 0.0, 0.0),
                amplitude: Amplitude::Ramp { duration: period },
            });
        }
        let mass: f64 = top.clone().map(|i| model.mass[i as usize]).sum();
        let frames = 100;
        // (time, slide, friction along x) at each frame.
        let mut rows = Vec::new();
        let mut observer = Frames(|f: &Frame<'_>| {
            let force = f.contact.expect("ply contact").force;
            let friction: f64 = top.clone().map(|i| force[i as usize].x).sum();
            rows.push((
                f.state.time,
                mean_along(f.model, &f.state.x, 1, Vector3::x()),
                -friction,
            ));
        });
        let settings = ExplicitSettings {
            end_time: period,
            frames,
            ..ExplicitSettings::default()
        };
        let mut state = model.initial_state();
        let mut driver = Explicit::new(&model, settings).expect("driver");
        // The ply moves rigidly, so the step stays the first one.
        let dt = driver.stable_time_step(&model.x0);
        driver.run(&mut state, &mut observer).expect("run");
        let label = format!("μ = {mu}");
        // The last frame before the onset: F = 0.98·μN. Its friction
        // balanced the load of the step's start, t − Δt.
        let (t, slide, friction) = rows[49];
        let pull = 2.0 * mu * normal * (t - dt) / period;
        checks.push(Check::abs(
            format!(
                "{label}, F = {:.3}·μN: slide while sticking (mm)",
                pull / (mu * normal)
            ),
            0.0,
            slide,
            1e-9,
        ));
        checks.push(Check::rel(
            format!("{label}, sticking: friction = F (N)"),
            pull,
            friction,
            1e-6,
        ));
        let (t, slide, friction) = rows[frames];
        checks.push(Check::rel(
            format!("{label}, F = 2μN: sliding friction = μN (N)"),
            mu * normal,
            friction,
            1e-6,
        ));
        let onset = 0.5 * period;
        let reference = 2.0 * mu * normal / (period * mass) * (t - onset).powi(3) / 6.0;
        checks.push(Check::rel(
            format!("{label}: slide = pull beyond the stick phase (mm)"),
            reference,
            slide,
            1e-5,
        ));
    }
    checks
}

/// A stack of two plies on a plane tilted by α about y, gravity straight
/// down, friction μ_tool between the plane and the bottom ply, μ_ply
/// between the plies; mean slides (bottom, top) down the slope after
/// `time`.
fn incline_run(alpha: f64, mu_tool: f64, mu_ply: f64, time: f64) -> (f64, f64) {
    let (s, c) = alpha.sin_cos();
    let rot = Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c);
    let mut model = two_plies(rot, mu_ply, [20.0, 20.0]);
    model.gravity = Vector3::new(0.0, 0.0, -G);
    model.tools.push(Tool {
        name: "slope".into(),
        surface: Surface::plane(Vector3::zeros(), rot * Vector3::z()).expect("plane"),
        motion: ToolMotion::Fixed,
        friction: mu_tool,
    });
    let settings = ExplicitSettings {
        end_time: time,
        frames: 4,
        ..ExplicitSettings::default()
    };
    let mut state = model.initial_state();
    Explicit::new(&model, settings)
        .expect("driver")
        .run(&mut state, &mut Frames(|_: &Frame<'_>| {}))
        .expect("run");
    let downhill = rot * Vector3::x();
    (
        mean_along(&model, &state.x, 0, downhill),
        mean_along(&model, &state.x, 1, downhill),
    )
}

/// The stack on an incline at 1 % of tan α below and above the critical
/// slope. With μ_tool < μ_ply the critical slope is tan α = μ_tool, and
/// beyond it the stack slides as one, ½·g(sin α − μ_tool cos α)·t²; with
/// μ_ply < μ_tool it is tan α = μ_ply, and beyond it the top ply slides
/// off the bottom one, ½·g(sin α − μ_ply cos α)·t², the bottom ply held
/// by the tool (μ_tool·2W cos α > W sin α + μ_ply·W cos α).
///
/// Tolerances: a sticking ply's slide 0 to 1e-9 mm (the joint friction
/// solve stops at 1e-5 of the largest cap per sweep, which lets a sticking
/// node creep 1e-5 of what its cap would move it: 6e-11 and 3.8e-10 mm
/// here, while 1e-4 would not pass); a sliding one's to 1e-6 relative (every node
/// has the same acceleration, which central differences integrate
/// exactly; a sliding node's friction is on its cap, which the solve's
/// tolerance does not touch).
fn incline() -> Vec<Check> {
    let time = 0.02;
    let mut checks = Vec::new();
    for (mu_tool, mu_ply) in [(0.2, 0.4), (0.4, 0.2)] {
        let critical = f64::min(mu_tool, mu_ply);
        for factor in [0.99, 1.01] {
            let alpha = (factor * critical).atan();
            let (bottom, top) = incline_run(alpha, mu_tool, mu_ply, time);
            let label =
                format!("μ_tool = {mu_tool}, μ_ply = {mu_ply}, tan α = {factor}·{critical}");
            let slide = |mu: f64| 0.5 * G * (alpha.sin() - mu * alpha.cos()) * time * time;
            if factor < 1.0 {
                checks.push(Check::abs(
                    format!("{label}: bottom slide (mm)"),
                    0.0,
                    bottom,
                    1e-9,
                ));
                checks.push(Check::abs(
                    format!("{label}: top slide (mm)"),
                    0.0,
                    top,
                    1e-9,
                ));
            } else if mu_tool < mu_ply {
                let reference = slide(mu_tool);
                checks.push(Check::rel(
                    format!("{label}: bottom slides ½g(sin α − μ_tool cos α)t² (mm)"),
                    reference,
                    bottom,
                    1e-6,
                ));
                checks.push(Check::rel(
                    format!("{label}: top slides with it (mm)"),
                    reference,
                    top,
                    1e-6,
                ));
            } else {
                checks.push(Check::abs(
                    format!("{label}: bottom held by the tool (mm)"),
                    0.0,
                    bottom,
                    1e-9,
                ));
                checks.push(Check::rel(
                    format!("{label}: top slides off, ½g(sin α − μ_ply cos α)t² (mm)"),
                    slide(mu_ply),
                    top,
                    1e-6,
                ));
            }
        }
    }
    checks
}

/// Signed distance of `p` from the triangles `faces` of `x` along their
/// normal (wound up the stack, `up` = +1 for the ply above them), over the
/// triangles whose plane projection of `p` falls inside them, and that
/// projection; None when it falls inside none (past the ply's edge).
fn distance_over(
    p: &Vector3<f64>,
    x: &[Vector3<f64>],
    faces: &[[u32; 3]],
    up: f64,
) -> Option<(f64, Vector3<f64>)> {
    let mut best: Option<(f64, Vector3<f64>)> = None;
    for f in faces {
        let [a, b, c] = f.map(|i| x[i as usize]);
        let n = (b - a).cross(&(c - a));
        let area2 = n.norm_squared();
        if area2 == 0.0 {
            continue;
        }
        // Barycentric coordinates of the projection.
        let w_a = (b - p).cross(&(c - p)).dot(&n) / area2;
        let w_b = (c - p).cross(&(a - p)).dot(&n) / area2;
        let w_c = 1.0 - w_a - w_b;
        if w_a < -1e-9 || w_b < -1e-9 || w_c < -1e-9 {
            continue;
        }
        let d = (p - a).dot(&n) / area2.sqrt() * up;
        if best.is_none_or(|(q, _)| d.abs() < q.abs()) {
            best = Some((d, a * w_a + b * w_b + c * w_c));
        }
    }
    best
}

/// The free outline of the triangles `faces`: the edges no other face
/// shares.
fn outline(faces: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut count = std::collections::BTreeMap::new();
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            *count.entry([a.min(b), a.max(b)]).or_insert(0u32) += 1;
        }
    }
    count
        .into_iter()
        .filter_map(|(e, n)| (n == 1).then_some(e))
        .collect()
}

/// The distance from `q` to the nearest of the segments `edges` of `x`.
fn from_outline(q: &Vector3<f64>, x: &[Vector3<f64>], edges: &[[u32; 2]]) -> f64 {
    edges
        .iter()
        .map(|&[a, b]| {
            let (a, b) = (x[a as usize], x[b as usize]);
            let e = b - a;
            let t = ((q - a).dot(&e) / e.norm_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            (q - (a + e * t)).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

/// The largest overlap of either ply into the other: thickness − the
/// distance of each node from the other ply's mid-surface.
fn overlap(model: &Model, x: &[Vector3<f64>]) -> f64 {
    overlap_between(model, x, 0, 1)
}

/// The largest overlap of ply `lower` into its neighbour `upper` or back:
/// half of each thickness − the distance of each node from the other
/// ply's mid-surface, for a node behind that mid-surface the lesser of
/// that and its distance in from the ply's free outline (the shorter way
/// out of the ply that does not cross it: a node held beside a ply's end
/// on its far side is at the end, not through the ply).
fn overlap_between(model: &Model, x: &[Vector3<f64>], lower: usize, upper: usize) -> f64 {
    let faces = |p: usize| -> Vec<[u32; 3]> {
        let mut out = Vec::new();
        for b in &model.membranes[model.plies[p].membranes.clone()] {
            for e in 0..b.len() {
                let n = b.element_nodes(e);
                for k in 1..n.len() - 1 {
                    out.push([n[0], n[k], n[k + 1]]);
                }
            }
        }
        out
    };
    let offset = 0.5 * (model.plies[lower].thickness + model.plies[upper].thickness);
    let mut worst: f64 = 0.0;
    for (slave, master, up) in [(upper, lower, 1.0), (lower, upper, -1.0)] {
        let f = faces(master);
        let edges = outline(&f);
        for i in model.plies[slave].nodes.clone() {
            if let Some((d, q)) = distance_over(&x[i as usize], x, &f, up) {
                // A node more than both plies' thickness away is over
                // another part of the blank, not on it.
                if d.abs() < 4.0 * offset {
                    let depth = offset - d;
                    let depth = if d < 0.0 {
                        depth.min(from_outline(&q, x, &edges))
                    } else {
                        depth
                    };
                    worst = worst.max(depth);
                }
            }
        }
    }
    worst
}

/// The shipped hemisphere scene (`scenes/hemisphere-0-90.toml`) as two
/// plies, 0/90 under ±45 (μ_ply = 0.2), at 16 × 16 cells: the largest
/// overlap of one ply into the other over every frame, at most 1 % of
/// the ply thickness (the bound).
fn hemisphere_overlap() -> Vec<Check> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let path = root.join("scenes/hemisphere-0-90.toml");
    let text = std::fs::read_to_string(&path)
        .expect("scene")
        .replace("cells = [40, 40]", "cells = [16, 16]");
    let text = format!(
        "{text}\n[stack]\nfriction = 0.2\n[[stack.ply]]\nname = \"p0\"\n[[stack.ply]]\nname = \"p45\"\norientation_deg = 45\n"
    );
    let scene = drape_io::scene::Scene::parse(&text, &path, &[]).expect("scene");
    let model = &scene.model;
    let mut worst: f64 = 0.0;
    let mut frames = 0;
    // The driver's own peak over its checks (the frames here), which
    // summary.json reports per ply.
    let mut driver_peak = f64::NAN;
    let mut observer = Frames(|f: &Frame<'_>| {
        worst = worst.max(overlap(f.model, &f.state.x));
        frames += 1;
        if let Some(p) = f.contact.and_then(|c| c.plies) {
            driver_peak = p.overlap_peaks()[0];
        }
    });
    let mut state = model.initial_state();
    Explicit::new(model, scene.settings.clone())
        .expect("driver")
        .run(&mut state, &mut observer)
        .expect("run");
    let h = model.plies[0].thickness;
    note(format!(
        "Two-ply hemisphere (16 × 16 cells, 0/90 under ±45, μ_ply = 0.2): largest overlap {:.3e} mm = {:.3e} of the ply thickness over {frames} frames; the driver's own measure's peak over the run {:.3e} mm.",
        worst,
        worst / h,
        driver_peak,
    ));
    vec![
        Check::abs(
            "largest overlap / ply thickness over the frames (≤ 1 %)",
            0.0,
            worst / h,
            1e-2,
        ),
        // The two measures differ only over a kink between faces (the
        // driver's rounds it, this one skips it): on this run they agree
        // to four digits at every frame.
        Check::rel(
            "the driver's peak overlap over the run = the largest here (mm)",
            worst,
            driver_peak,
            1e-3,
        ),
    ]
}

/// The shipped `scenes/hemisphere-stack.toml` with its plies replaced by
/// `plies` (name, orientation) and the friction between them `mu`; the
/// end state's per-ply summary and the wall time of the run (s).
fn stack_run(plies: &[(&str, f64)], mu: f64) -> (Vec<drape_io::results::PlySummary>, f64) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let path = root.join("scenes/hemisphere-stack.toml");
    let text = std::fs::read_to_string(&path).expect("scene");
    let head = &text[..text.find("[[stack.ply]]").expect("plies")];
    let tail = &text[text.find("[[tools]]").expect("tools")..];
    let mut body = String::new();
    for (name, theta) in plies {
        body.push_str(&format!(
            "[[stack.ply]]\nname = \"{name}\"\norientation_deg = {theta}\n"
        ));
    }
    let head = head.replace(
        "friction = 0.2                            # Coulomb μ between neighbouring plies",
        &format!("friction = {mu}"),
    );
    let text = format!("{head}{body}\n{tail}");
    let scene = drape_io::scene::Scene::parse(&text, &path, &[]).expect("scene");
    let model = &scene.model;
    let mut last = Vec::new();
    let mut observer = Frames(|f: &Frame<'_>| {
        if let Ok(fields) = f.model.element_fields(f.state) {
            last = drape_io::results::PlySummary::of(
                f.model,
                &f.state.x,
                &fields,
                f.contact.and_then(|c| c.plies),
            );
        }
    });
    let mut state = model.initial_state();
    let start = std::time::Instant::now();
    Explicit::new(model, scene.settings.clone())
        .expect("driver")
        .run(&mut state, &mut observer)
        .expect("run");
    (last, start.elapsed().as_secs_f64())
}

/// The two-ply hemisphere [0/90 + ±45] (`scenes/hemisphere-stack.toml`,
/// 24 × 24 cells) at μ_ply = 0, 0.2, 0.5, 1: a table of each ply's
/// largest shear, the top ply's largest slip on the bottom one and each
/// ply's wrinkle indicator; then a four-ply [0/45/90/−45] run and a one-ply
/// run of the same scene, timed in this process on the same threads.
///
/// Checks: every run completes (a failed run panics the case); the top
/// ply slips less on the bottom one at μ_ply = 1 than at 0 (the issue's
/// "the inter-ply slip falls as μ_ply grows", end points only: the slip
/// accumulates the to and fro of a dynamic run as well).
fn hemisphere_friction() -> Vec<Check> {
    let mut table = String::from(
        "| μ_ply | max shear 0/90 (°) | max shear ±45 (°) | top ply's max slip (mm) | waviness 0/90 (°) | waviness ±45 (°) | wrinkle area 0/90 / ±45 (mm²) | run (s) |\n|---|---|---|---|---|---|---|---|\n",
    );
    let mut slips = Vec::new();
    for mu in [0.0, 0.2, 0.5, 1.0] {
        let (p, seconds) = stack_run(&[("p0", 0.0), ("p45", 45.0)], mu);
        table.push_str(&format!(
            "| {mu} | {:.2} | {:.2} | {:.2} | {:.1} | {:.1} | {:.0} / {:.0} | {seconds:.1} |\n",
            p[0].max_shear_deg,
            p[1].max_shear_deg,
            p[1].max_slip_mm,
            p[0].max_waviness_deg,
            p[1].max_waviness_deg,
            p[0].wrinkle_area_mm2,
            p[1].wrinkle_area_mm2,
        ));
        slips.push(p[1].max_slip_mm);
    }
    let (_, one) = stack_run(&[("p0", 0.0)], 0.2);
    let (four, four_s) = stack_run(
        &[("p0", 0.0), ("p45", 45.0), ("p90", 90.0), ("m45", -45.0)],
        0.2,
    );
    let shears: Vec<String> = four
        .iter()
        .map(|p| format!("{} {:.2}°", p.name, p.max_shear_deg))
        .collect();
    note(format!(
        "Two-ply hemisphere [0/90 + ±45], 24 × 24 cells, yarn bending on in every ply (the preset's rigidity), {} threads (a shared, loaded machine: times are indicative):\n\n{table}\nFour plies [0/45/90/−45] at μ_ply = 0.2: completed in {four_s:.1} s against {one:.1} s for one ply ({:.1}×); max shear per ply {}.",
        rayon::current_num_threads(),
        four_s / one,
        shears.join(", ")
    ));
    vec![Check::abs(
        "top ply's largest slip at μ_ply = 1 below that at μ_ply = 0 (1 = yes)",
        1.0,
        f64::from(u8::from(slips[3] < slips[0])),
        0.0,
    )]
}

/// One output frame of a run: its time, each element's shear angle
/// (degrees) and centroid, and the punch's displacement.
struct ShearFrame {
    time: f64,
    shear: Vec<f64>,
    centroid: Vec<Vector3<f64>>,
    punch: f64,
}

/// A run's frames and its plies' element ranges and thicknesses.
struct ShearRun {
    frames: Vec<ShearFrame>,
    plies: Vec<std::ops::Range<usize>>,
    thickness: Vec<f64>,
}

impl ShearRun {
    fn elements(&self) -> usize {
        self.frames[0].shear.len()
    }
}

/// Runs the scene `text` (read as if from `path`) to its end.
fn shear_run(text: &str, path: &std::path::Path) -> ShearRun {
    let (run, error) = try_shear_run(text, path);
    if let Some(error) = error {
        panic!("run: {error}");
    }
    run
}

/// Runs the scene `text` (read as if from `path`) until it ends or stops
/// on an error: the frames so far and the error, if any.
fn try_shear_run(text: &str, path: &std::path::Path) -> (ShearRun, Option<String>) {
    let scene = drape_io::scene::Scene::parse(text, path, &[]).expect("scene");
    let model = &scene.model;
    let mut frames = Vec::new();
    let mut observer = Frames(|f: &Frame<'_>| {
        let fields = f.model.element_fields(f.state).expect("fields");
        frames.push(ShearFrame {
            time: f.state.time,
            shear: fields.shear.iter().map(|g| g.to_degrees()).collect(),
            centroid: fields.centroid,
            punch: f.model.tools[0]
                .prescribed_displacement(f.state.time)
                .expect("a moving punch"),
        });
    });
    let mut state = model.initial_state();
    let error = Explicit::new(model, scene.settings.clone())
        .expect("driver")
        .run(&mut state, &mut observer)
        .err()
        .map(|e| format!("{e:?}"));
    let run = ShearRun {
        frames,
        plies: model.plies.iter().map(|p| p.elements.clone()).collect(),
        thickness: model.plies.iter().map(|p| p.thickness).collect(),
    };
    (run, error)
}

/// Root mean square and largest magnitude of `a − b` over `elements`.
fn rms_max(a: &[f64], b: &[f64], elements: impl Iterator<Item = (usize, usize)>) -> (f64, f64) {
    let (mut sum, mut max, mut n) = (0.0, 0.0f64, 0usize);
    for (i, j) in elements {
        let d = a[i] - b[j];
        sum += d * d;
        max = max.max(d.abs());
        n += 1;
    }
    ((sum / n.max(1) as f64).sqrt(), max)
}

/// The two-ply hemisphere [0/90 + ±45] (`scenes/hemisphere-stack.toml`,
/// 24 × 24 cells, yarn bending on as the preset gives it) at μ_ply = 0
/// against each ply formed alone on a mould offset by the other ply's
/// thickness: the bottom ply (it alone touches the punch; nothing lies
/// under it) on the same punch, the top one on a frictionless punch (the
/// bottom ply's face at μ_ply = 0) whose radius is the bottom ply's
/// thickness larger (same pole: the top ply's blank starts
/// one mean thickness higher in the stack, so the pair is the same,
/// translated). The tools' contact offset in a stack is its largest half
/// thickness: both plies have the same thickness here, so it is each
/// ply's own. Same mesh per ply, element by element: the RMS of the
/// difference of the shear angle over the ply's elements, per frame, and
/// split into the elements on the punch's dome at that frame (within 1 mm
/// of the sphere the ply lies on, above its equator: where the rigid punch
/// alone sets each ply's shape, so only friction could couple the plies)
/// and the rest (the flanges, where the plies hang on each other and
/// share one shape whatever μ_ply). Beside it, each ply alone against
/// itself on a punch 1 µm larger: the scene's own sensitivity, the floor
/// under which no comparison of runs of it can go.
///
/// Other scenes measured (2026-11-28, not kept): the 0/90 ply alone
/// formed 13× slower (13 s, past the driver's quasi-static bound of 9 s)
/// still folds in its flanges (6380 mm² wavier than 45°) and repeats
/// itself to 0.78° RMS only; the whole case at 40 × 40 cells (the
/// single-ply scenes' mesh, where a ply alone does not fold) has floors
/// of 1.39° and 0.96° and differences of 3.32° and 1.63°. Neither makes
/// the comparison sharper, so the case keeps the shipped 24 × 24.
///
/// What couples the plies at μ_ply = 0 (measured 2026-11-30, runs not
/// kept in the case). Before t ≈ 0.35–0.4 s each ply alone repeats itself
/// to 0.05° RMS, and there the stack differs from the single runs by
/// 1.17° (0/90) and 1.50° (±45) RMS off the dome, 0.43° and 0.93° on it
/// (t = 0.4 s). With the punch frictionless in every run too, so that no
/// ply's pressure on the other changes a friction force: 1.23° / 1.47°
/// off, 0.40° / 1.14° on. With gravity off in every run: 1.35° / 1.54°
/// off, 0.39° / 0.51° on. Neither is the coupling. What is left is the
/// normal contact itself: from t ≈ 0.2 s (0.23–0.28° RMS, the single runs
/// repeating to 0.000°) the flanges, which alone hang and fold
/// differently (a 0/90 and a ±45 lattice), may not pass through each
/// other, so where they touch they share one shape, and the dome's shear,
/// drawn in from the flanges, follows. That is the mechanics of a stack,
/// not a fault of the ply contact: a bound on a whole ply's shear holds
/// only where tools set both plies' shapes everywhere (what
/// [`held::held_frictionless`] tried; its die's opening leaves the stack
/// free, and it folds there).
///
/// So the case also forms two equal plies, 0/90 on 0/90, at μ_ply = 0:
/// alone, each hangs and folds as the other, and what the stack differs by
/// is what the ply contact itself adds (the faces' sag included: a node of
/// one ply resting on the chords of the other's faces, not on the offset
/// sphere). Measured 2026-11-30: 0.06° and 0.08° RMS from the single runs
/// at t = 0.4 s, 0.15° at t = 0.45 s (the last frame at which those repeat
/// themselves to 0.05°), where the [0/90 + ±45] stack differs by 1.1° and
/// 1.4°; 0.59° and 0.87° at the end, against floors of 0.46° and 0.82°.
///
/// Checks: the bound, each ply's RMS at the end ≤ 0.5°; and for
/// the equal plies the same bound at the last frame at which both single
/// runs repeat themselves within [`REPEATS`] (after it no comparison of
/// runs of this scene resolves 0.5°).
fn hemisphere_frictionless() -> Vec<Check> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let path = root.join("scenes/hemisphere-stack.toml");
    let text = std::fs::read_to_string(&path).expect("scene");
    let mu_line =
        "friction = 0.2                            # Coulomb μ between neighbouring plies";
    assert!(text.contains(mu_line), "the shipped stack scene changed");
    let stack = shear_run(&text.replace(mu_line, "friction = 0"), &path);
    // One ply: [fabric] alone, with yarn bending as each ply of the stack
    // has it (the preset's rigidity, on by default).
    let head = &text[..text.find("\n[stack]\n").expect("[stack]") + 1];
    let tail = &text[text.find("[[tools]]").expect("tools")..];
    assert!(
        !text.lines().any(|l| l.trim_start().starts_with("bending")),
        "the shipped stack scene sets bending"
    );
    let fabric = head.to_owned();
    let radius = "radius = 120,";
    assert!(
        tail.contains(radius) && tail.contains("pole = [0, 0, -0.2]"),
        "the shipped stack scene's punch changed"
    );
    let bottom = shear_run(&format!("{fabric}{tail}"), &path);
    let top_fabric = fabric.replacen("orientation_deg = 0 ", "orientation_deg = 45 ", 1);
    assert_ne!(top_fabric, fabric);
    let h0 = stack.thickness[0];
    // The top ply's mould is the bottom ply's face, frictionless at
    // μ_ply = 0: its punch has no friction.
    let punch_friction = "friction = 0.1                            # Coulomb μ between the punch and the ply it touches";
    assert!(
        tail.contains(punch_friction),
        "the shipped stack scene's punch friction changed"
    );
    let top_tail = tail.replacen(punch_friction, "friction = 0", 1);
    // A ply alone (`fabric`) on the tools `tail` with the punch's radius
    // `radius_mm`.
    let alone = |fabric: &str, tail: &str, radius_mm: f64| {
        shear_run(
            &format!(
                "{fabric}{}",
                tail.replacen(radius, &format!("radius = {radius_mm},"), 1)
            ),
            &path,
        )
    };
    let top = alone(&top_fabric, &top_tail, 120.0 + h0);
    // The noise floor: each ply alone again on its punch 1 µm larger.
    let floors = [
        alone(&fabric, tail, 120.0 + 1e-3),
        alone(&top_fabric, &top_tail, 120.0 + h0 + 1e-3),
    ];
    let mixed = compare_frames(
        &stack,
        [&bottom, &top],
        [&floors[0], &floors[1]],
        h0,
        ["0/90", "±45"],
    );
    // The same stack of two equal plies (0/90 on 0/90): alone, each hangs
    // and folds as the other, so what is left is what the ply contact
    // itself does at μ_ply = 0. Its bottom ply alone is the run above.
    let ply_45 = "orientation_deg = 45";
    assert_eq!(
        text.matches(ply_45).count(),
        1,
        "the shipped stack scene's plies changed"
    );
    let equal_stack = shear_run(
        &text
            .replace(mu_line, "friction = 0")
            .replacen(ply_45, "orientation_deg = 0", 1),
        &path,
    );
    let top_equal = alone(&fabric, &top_tail, 120.0 + h0);
    let floor_equal = alone(&fabric, &top_tail, 120.0 + h0 + 1e-3);
    let equal = compare_frames(
        &equal_stack,
        [&bottom, &top_equal],
        [&floors[0], &floor_equal],
        h0,
        ["0/90 bottom", "0/90 top"],
    );
    let (t_equal, rms_equal) = equal
        .repeatable
        .map(|r| (r.time, r.whole))
        .expect("the single runs repeat themselves at the start");
    note(format!(
        "Two-ply hemisphere [0/90 + ±45] at μ_ply = 0 against each ply alone (24 × 24 cells, the shipped stack scene, yarn bending on in every run as the preset's rigidity gives it; the top ply alone on a frictionless punch {h0} mm larger in radius, as the bottom ply's face is to it at μ_ply = 0): the shear difference per element over time, on the punch's dome and off it (the flanges, where the plies hang on each other: there they share one shape at any μ_ply, so only the dome tests that no friction couples them), and beside it that of each ply alone against itself on a punch 1 µm larger (the scene's own sensitivity)\n\n{}\n{}\n\nThe same with two equal plies, 0/90 on 0/90 (the top one alone on the same frictionless punch): each ply alone hangs and folds as the other, so this measures what the ply contact itself adds at μ_ply = 0\n\n{}\n{}",
        mixed.table, mixed.summary, equal.table, equal.summary
    ));
    let end = mixed.end;
    vec![
        Check::abs(
            "RMS shear difference, 0/90 ply in the stack vs alone (°)",
            0.0,
            end[0],
            0.5,
        ),
        Check::abs(
            "RMS shear difference, ±45 ply in the stack vs alone (°)",
            0.0,
            end[1],
            0.5,
        ),
        Check::abs(
            format!(
                "two equal 0/90 plies: RMS shear difference of the bottom ply vs alone at t = {t_equal:.2} s, the last frame both repeat themselves (°)"
            ),
            0.0,
            rms_equal[0],
            0.5,
        ),
        Check::abs(
            format!(
                "two equal 0/90 plies: RMS shear difference of the top ply vs alone at t = {t_equal:.2} s (°)"
            ),
            0.0,
            rms_equal[1],
            0.5,
        ),
    ]
}

/// Each ply's shear in `stack` against its run alone (`singles`) and
/// that run against itself on a punch 1 µm larger (`floors`), frame by
/// frame (see [`hemisphere_frictionless`]).
struct FrameComparison {
    /// The per-frame table (every other frame and the last).
    table: String,
    /// What the table says at the end, in words.
    summary: String,
    /// Each ply's RMS at the end (°).
    end: [f64; 2],
    /// The last frame at which each ply alone repeats itself within
    /// [`REPEATS`].
    repeatable: Option<Repeatable>,
}

/// A frame at which each single run repeats itself (see
/// [`FrameComparison`]).
#[derive(Clone, Copy)]
struct Repeatable {
    time: f64,
    /// Each ply's RMS on the dome and off it (°).
    split: [(f64, f64); 2],
    /// Each ply's RMS over the whole ply (°).
    whole: [f64; 2],
}

/// Single runs closer to themselves than this (RMS, °) on a punch 1 µm
/// larger repeat themselves: what a stack differs from them by there is
/// no noise.
const REPEATS: f64 = 0.05;

fn compare_frames(
    stack: &ShearRun,
    singles: [&ShearRun; 2],
    floors: [&ShearRun; 2],
    h0: f64,
    names: [&str; 2],
) -> FrameComparison {
    for (p, single) in singles.iter().enumerate() {
        assert_eq!(single.elements(), stack.plies[p].len(), "ply {p}'s mesh");
        assert_eq!(single.frames.len(), stack.frames.len());
    }
    let [a, b] = names;
    let mut table = format!(
        "| t (s) | RMS Δγ {a} (°) | on the dome / off it (elements) | max \\|Δγ\\| {a} (°) | alone vs alone +1 µm, RMS {a} (°) | RMS Δγ {b} (°) | on the dome / off it (elements) | max \\|Δγ\\| {b} (°) | alone vs alone +1 µm, RMS {b} (°) |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut floor_end = [0.0; 2];
    let mut end = [0.0; 2];
    let mut dome_end = [(0.0, 0.0, 0usize); 2];
    let mut repeatable = None;
    let mut steady = true;
    for (k, frame) in stack.frames.iter().enumerate() {
        let mut row = format!("| {:.2} |", frame.time);
        let mut split = [(0.0, 0.0); 2];
        for (p, single) in singles.iter().enumerate() {
            let first = stack.plies[p].start;
            let n = single.elements();
            let alone = &single.frames[k];
            let (rms, max) = rms_max(&frame.shear, &alone.shear, (0..n).map(|e| (first + e, e)));
            // The dome of the sphere this ply lies on alone, where its
            // punch is now (the pole at −0.2 mm, risen by the stroke).
            let radius = 120.0 + [0.0, h0][p];
            let centre = Vector3::new(0.0, 0.0, -0.2 - radius + alone.punch);
            let sphere = radius + 0.5 * stack.thickness[p];
            let on: Vec<bool> = alone
                .centroid
                .iter()
                .map(|c| ((c - centre).norm() - sphere).abs() < 1.0 && c.z > centre.z - 1.0)
                .collect();
            let on = &on;
            let pick = |want: bool| {
                (0..n)
                    .filter(move |&e| on[e] == want)
                    .map(move |e| (first + e, e))
            };
            let (dome, dome_max) = rms_max(&frame.shear, &alone.shear, pick(true));
            let (flange, _) = rms_max(&frame.shear, &alone.shear, pick(false));
            let count = on.iter().filter(|&&o| o).count();
            let (floor, _) = rms_max(
                &floors[p].frames[k].shear,
                &alone.shear,
                (0..n).map(|e| (e, e)),
            );
            row.push_str(&format!(
                " {rms:.3} | {dome:.3} / {flange:.3} ({count} / {}) | {max:.2} | {floor:.3} |",
                n - count
            ));
            end[p] = rms;
            floor_end[p] = floor;
            dome_end[p] = (dome, dome_max, count);
            split[p] = (dome, flange);
            steady &= floor < REPEATS;
        }
        if steady {
            repeatable = Some(Repeatable {
                time: frame.time,
                split,
                whole: end,
            });
        }
        if k % 2 == 0 || k + 1 == stack.frames.len() {
            table.push_str(&row);
            table.push('\n');
        }
    }
    let floor = if floor_end.iter().all(|&f| f < 0.1) {
        "well under the issue's 0.5°: the comparison resolves it"
    } else if floor_end.iter().all(|&f| f < 0.5) {
        "under the issue's 0.5° but not far: the comparison resolves it only roughly"
    } else {
        "above the issue's 0.5°: on this scene the comparison cannot resolve 0.5°"
    };
    let before = match repeatable {
        Some(Repeatable {
            time: t,
            split: [(d0, f0), (d1, f1)],
            whole: [w0, w1],
        }) => format!(
            "Up to t = {t:.2} s each ply alone repeats itself within {REPEATS}° RMS, so what the stack differs by there is no noise: {w0:.3}° ({a}) and {w1:.3}° ({b}) over the ply, on the dome {d0:.3}° and {d1:.3}°, off it {f0:.3}° and {f1:.3}°. "
        ),
        None => String::new(),
    };
    let summary = format!(
        "At the end, on the dome: {a} RMS {:.3}° (largest {:.2}°, {} elements), {b} RMS {:.3}° (largest {:.2}°, {} elements). {before}The noise floor at the end, {:.3}° and {:.3}° RMS, is {floor}.",
        dome_end[0].0,
        dome_end[0].1,
        dome_end[0].2,
        dome_end[1].0,
        dome_end[1].1,
        dome_end[1].2,
        floor_end[0],
        floor_end[1]
    );
    FrameComparison {
        table,
        summary,
        end,
        repeatable,
    }
}
