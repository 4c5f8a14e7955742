//! Validation of rigid-tool contact through the explicit driver (SPEC §6):
//! a blank on an incline (Coulomb stick and slide), the capstan equation
//! on a strip wrapped round a fixed cylinder, no penetration and the force
//! balance at rest on every tool kind, and a strip pinched between a die
//! and a force-driven holder (the coupled normal solve).
//!
//! References come from closed formulas evaluated here (g(sin α − μ cos α),
//! e^(μθ), 2μF, the applied loads), never from the contact crate.

use std::f64::consts::PI;

use drape_constitutive::Material;
use drape_contact::{ContactStatus, ProfileSegment, Surface};
use drape_elements::{FabricSection, MembraneBatch};
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{
    Amplitude, BoundaryCondition, Model, Motion, NodalLoad, State, Tool, ToolMotion,
};
use drape_time::{Explicit, ExplicitSettings, Frame, Implicit, ImplicitSettings, Observer};
use nalgebra::{Matrix3, Vector3};

use super::{Case, Check};

/// The cases of this module.
pub const CASES: &[Case] = &[
    Case {
        name: "contact/incline",
        quick: true,
        run: incline,
    },
    Case {
        name: "contact/capstan",
        quick: true,
        run: capstan,
    },
    Case {
        name: "contact/no-penetration",
        quick: true,
        run: no_penetration,
    },
    Case {
        name: "contact/pinching",
        quick: true,
        run: pinching,
    },
];

/// Gravity (mm/s²).
const G: f64 = 9810.0;

/// The paper's glass (its yarns buckle at no cost): these cases check the
/// driver against closed forms, not the presets' compression law.
fn glass() -> Material {
    Material::paper_preset("glass-serge-4x3").expect("preset")
}

/// Collects whatever a case wants from each frame.
struct Frames<F: FnMut(&Frame<'_>)>(F);
impl<F: FnMut(&Frame<'_>)> Observer for Frames<F> {
    fn frame(&mut self, frame: &Frame<'_>) {
        (self.0)(frame)
    }
}

/// Which driver a case runs with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Driver {
    /// Central differences.
    Explicit,
    /// Newton increments with the condensed contact solve, default
    /// settings (end time, frames and damping from the explicit ones).
    Implicit,
    /// The same with the active-set contact solver
    /// (`simulation.contact_solver = "active_set"`).
    ImplicitActiveSet,
}

/// Runs `model` from its initial state with `driver` and returns the end
/// state.
pub(super) fn run(
    driver: Driver,
    model: &Model,
    settings: ExplicitSettings,
    observer: &mut dyn Observer,
) -> State {
    let mut state = model.initial_state();
    match driver {
        Driver::Explicit => {
            Explicit::new(model, settings)
                .expect("driver")
                .run(&mut state, observer)
                .expect("run");
        }
        Driver::Implicit | Driver::ImplicitActiveSet => {
            let implicit = ImplicitSettings {
                end_time: settings.end_time,
                frames: settings.frames,
                damping: settings.damping,
                guard: settings.guard.clone(),
                contact_solver: if driver == Driver::ImplicitActiveSet {
                    drape_time::ContactSolver::ActiveSet
                } else {
                    drape_time::ContactSolver::Condensed
                },
                ..ImplicitSettings::default()
            };
            Implicit::new(model, implicit)
                .expect("driver")
                .run(&mut state, observer)
                .expect("run");
        }
    }
    state
}

fn tool(name: &str, surface: Surface, friction: f64) -> Tool {
    Tool {
        name: name.into(),
        surface,
        motion: ToolMotion::Fixed,
        friction,
    }
}

/// Largest penetration of the fabric's surface into any tool at a frame:
/// max over nodes of (offset − gap), 0 when every node is clear.
fn penetration(frame: &Frame<'_>) -> f64 {
    let contact = frame.contact.expect("tools");
    let offset = frame.model.contact_offset;
    let mut worst = 0.0f64;
    for (tool, state) in contact.tools.iter().zip(contact.tool_state) {
        for x in &frame.state.x {
            worst = worst.max(offset - tool.project(x, state.displacement).gap);
        }
    }
    worst
}

/// A blank on a plane tilted by α about y (the fabric and the plane both
/// rotated, gravity straight down), Coulomb friction μ. Sliding: every node
/// carries the same gravity and friction per unit mass, so the blank moves
/// rigidly with a = g(sin α − μ cos α) and central differences integrate
/// the constant acceleration exactly; sticking (tan α ≤ μ): it stays put.
///
/// Tolerances: the slide to 1e-6 relative (exact integration; what is left
/// is round-off over ~10⁴ steps), a sticking blank's slide to 1e-9 mm, the
/// penetration to 1e-9 of the thickness (the plane's correction is exact).
fn incline() -> Vec<Check> {
    incline_with(Driver::Explicit)
}

/// [`incline`] with either driver.
pub fn incline_with(driver: Driver) -> Vec<Check> {
    let time = 0.02;
    let pairs = [
        (10.0, 0.3),
        (15.0, 0.3),
        (0.3f64.atan().to_degrees(), 0.3),
        (20.0, 0.3),
        (30.0, 0.3),
        (25.0, 0.5),
        (30.0, 0.5),
        (45.0, 0.5),
        (10.0, 0.0),
    ];
    let mut checks = Vec::new();
    for (alpha_deg, mu) in pairs {
        let (moved, pen, h) = incline_run(driver, alpha_deg, mu, time);
        let a = alpha_deg.to_radians();
        let label = format!("α = {alpha_deg:.2}°, μ = {mu}");
        // The friction angle itself (the third pair) counts as sticking,
        // whatever round-off does to tan(atan μ): both references are 0.
        if a.tan() <= mu + 1e-15 {
            // Sticking: the friction force balances the slope exactly each
            // step, so the blank moves only by round-off.
            checks.push(Check::abs(
                format!("{label} (tan α ≤ μ): mean slide (mm)"),
                0.0,
                moved,
                1e-9,
            ));
        } else {
            let reference = 0.5 * G * (a.sin() - mu * a.cos()) * time * time;
            checks.push(Check::rel(
                format!("{label}: slide ½·g(sin α − μ cos α)·t² (mm)"),
                reference,
                moved,
                1e-6,
            ));
        }
        checks.push(Check::abs(
            format!("{label}: largest penetration / thickness"),
            0.0,
            pen / h,
            1e-9,
        ));
    }
    checks
}

/// Mean displacement down the slope after `time`, largest penetration over
/// the frames, thickness.
fn incline_run(driver: Driver, alpha_deg: f64, mu: f64, time: f64) -> (f64, f64, f64) {
    let material = glass();
    let h = material.thickness;
    let blank = RectangleBlank {
        width: 20.0,
        height: 20.0,
        center: Vector3::new(0.0, 0.0, 0.5 * h),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells([2, 2]),
        fibres: FibreRepresentation::Trusses,
    };
    // Rotation about y taking z to the plane's normal and x down the slope.
    let a = alpha_deg.to_radians();
    let (s, c) = a.sin_cos();
    let rot = Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c);
    let mut mesh = blank.mesh().expect("mesh");
    for x in &mut mesh.x0 {
        *x = rot * *x;
    }
    mesh.warp = rot * mesh.warp;
    let mut model =
        Model::from_mesh(&mesh, &material, FibreRepresentation::Trusses).expect("model");
    model.gravity = Vector3::new(0.0, 0.0, -G);
    let normal = rot * Vector3::z();
    model.tools.push(tool(
        "slope",
        Surface::plane(Vector3::zeros(), normal).expect("plane"),
        mu,
    ));
    let mut pen = 0.0f64;
    let mut observer = Frames(|f: &Frame<'_>| pen = pen.max(penetration(f)));
    let settings = ExplicitSettings {
        end_time: time,
        frames: 20,
        ..ExplicitSettings::default()
    };
    let state = run(driver, &model, settings, &mut observer);
    let downhill = rot * Vector3::x();
    let moved = state
        .x
        .iter()
        .zip(&model.x0)
        .map(|(x, x0)| (x - x0).dot(&downhill))
        .sum::<f64>()
        / model.node_count() as f64;
    (moved, pen, h)
}

/// A glass strip of `cells` quads (along, across), `length` × `width` mm,
/// whose reference is bent: the node at arc length s ∈ [0, length] along the
/// strip and y ∈ [−width/2, width/2] across it sits at `place(s, y)`, and
/// each element's warp is `along(s)` at its centre. Trusses, masses and node
/// sets as `Model::from_blank` builds them for the flat strip ("left" is
/// s = 0, "right" s = length, "median_y" s = length/2); the truss sections
/// are the flat strip widths.
fn bent_strip(
    cells: [usize; 2],
    length: f64,
    width: f64,
    place: &dyn Fn(f64, f64) -> Vector3<f64>,
    along: &dyn Fn(f64) -> Vector3<f64>,
) -> Model {
    let material = glass();
    let blank = RectangleBlank {
        width: length,
        height: width,
        center: Vector3::new(0.5 * length, 0.0, 0.0),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells(cells),
        fibres: FibreRepresentation::Trusses,
    };
    let mesh = blank.mesh().expect("mesh");
    let x0: Vec<Vector3<f64>> = mesh.x0.iter().map(|p| place(p.x, p.y)).collect();
    let warp: Vec<Vector3<f64>> = mesh
        .quads
        .iter()
        .map(|q| along(q.iter().map(|&n| mesh.x0[n as usize].x).sum::<f64>() / 4.0))
        .collect();
    let section = FabricSection::new(material.clone(), false);
    let membranes =
        vec![MembraneBatch::quads(section, &x0, mesh.quads.clone(), &warp).expect("quads")];
    let trusses = Model::truss_batches(&mesh.trusses, &mesh.x0, &x0, &material).expect("trusses");
    let mass = Model::lumped_mass(x0.len(), &membranes);
    Model {
        x0,
        mass,
        trusses,
        membranes,
        node_sets: mesh.node_sets,
        contact_offset: 0.5 * material.thickness,
        ..Model::default()
    }
}

/// Capstan: a 10 mm wide glass strip wrapped by θ round a fixed vertical
/// cylinder (a surface of revolution, one line of its profile), held at one
/// end by a constant load T₁ along its leg and pulled slowly at the other.
/// Once the whole wrap slides, the pulled end's force T₂ = T₁·e^(μθ).
///
/// The strip's reference is already wrapped: 20 mm straight, an arc of
/// radius ρ = R + h/2 (the mid-surface half a thickness off the cylinder),
/// 20 mm straight, nodes every 2 mm, β = π/16 apart on the arc. Two effects
/// move the simulated ratio off e^(μθ), both evaluated in closed form here:
/// - node-to-surface contact turns the tension by β at each arc node (β/2
///   at the two tangent points), so the discrete ratio is
///   Π (1 + μ tan β_k/2)/(1 − μ tan β_k/2), above e^(μθ) by ≈ (1 + μ²)·β²/12
///   of μθ (0.15–0.3 %);
/// - the damping α that settles the run drags the sliding strip with
///   q = α·ρ_A·W·V per unit length: T grows by q·L on a leg and obeys
///   dT/dφ = μT + qρ on the arc (0.07 %).
///
/// Checks per (θ, μ): the mean ratio over the sliding window against e^(μθ)
/// within 1 % and against the discrete ratio with drag within 0.3 % (what
/// is left: the frames' scatter of the damped sliding, ≈ 0.1 %), the worst
/// frame against e^(μθ) within 1 %, and every touching node slipping.
fn capstan() -> Vec<Check> {
    capstan_with(Driver::Explicit)
}

/// [`capstan`] with either driver.
pub fn capstan_with(driver: Driver) -> Vec<Check> {
    let mut checks = Vec::new();
    for (theta_deg, mu) in [(90.0, 0.3), (180.0, 0.2), (180.0, 0.3)] {
        let run = capstan_run(driver, theta_deg, mu);
        let theta = f64::to_radians(theta_deg);
        let exact = (mu * theta).exp();
        let label = format!("θ = {theta_deg}°, μ = {mu}");
        // The discrete polygon: β at the interior arc nodes, β/2 at the ends.
        let beta = PI / 16.0;
        let turns = (theta / beta).round() as i32;
        let ratio = |b: f64| {
            let x = mu * (0.5 * b).tan();
            (1.0 + x) / (1.0 - x)
        };
        let discrete = ratio(beta).powi(turns - 1) * ratio(0.5 * beta).powi(2);
        // Drag of the damping on the legs and the arc.
        let q = run.damping * run.areal_density * run.width * run.speed;
        let (rho, t1) = (run.rho, run.t1);
        let arc_in = t1 + q * run.legs[0];
        let drag_factor =
            ((arc_in + q * rho / mu) * exact - q * rho / mu + q * run.legs[1]) / (t1 * exact);
        let refined = discrete * drag_factor;
        let n = run.samples.len() as f64;
        let mean = run.samples.iter().map(|s| s.1).sum::<f64>() / n;
        let worst = run
            .samples
            .iter()
            .map(|s| s.1)
            .max_by(|a, b| (a - exact).abs().total_cmp(&(b - exact).abs()))
            .expect("samples");
        checks.push(Check::rel(
            format!("{label}: mean T₂/T₁ sliding vs e^(μθ)"),
            exact,
            mean,
            0.01,
        ));
        checks.push(Check::rel(
            format!("{label}: mean T₂/T₁ vs discrete wrap × damping drag"),
            refined,
            mean,
            0.003,
        ));
        checks.push(Check::rel(
            format!(
                "{label}: worst frame T₂/T₁ vs e^(μθ) ({} frames)",
                run.samples.len()
            ),
            exact,
            worst,
            0.01,
        ));
        checks.push(Check::abs(
            format!("{label}: slipping / touching nodes, fewest over the frames"),
            1.0,
            run.slipping_fraction,
            0.0,
        ));
    }
    checks
}

/// What a capstan run measured and the parameters its references need.
struct CapstanRun {
    /// (time, T₂/T₁) over the sliding window.
    samples: Vec<(f64, f64)>,
    /// Fewest slipping/touching nodes over the window.
    slipping_fraction: f64,
    t1: f64,
    speed: f64,
    damping: f64,
    areal_density: f64,
    width: f64,
    rho: f64,
    /// Damped length of the held and the pulled leg: the pulled nodes'
    /// half cell is carried by their constraint.
    legs: [f64; 2],
}

fn capstan_run(driver: Driver, theta_deg: f64, mu: f64) -> CapstanRun {
    let material = glass();
    let h = material.thickness;
    let (ds, width, leg) = (2.0, 10.0, 20.0);
    let beta = PI / 16.0;
    let theta = theta_deg.to_radians();
    let arc_cells = (theta / beta).round() as usize;
    let rho = ds / beta;
    let leg_cells = (leg / ds).round() as usize;
    let cells = 2 * leg_cells + arc_cells;
    let (phi_a, phi_b) = (-0.5 * theta, 0.5 * theta);
    let point = move |phi: f64| Vector3::new(rho * phi.cos(), rho * phi.sin(), 0.0);
    let tangent = |phi: f64| Vector3::new(-phi.sin(), phi.cos(), 0.0);
    let (s_a, s_b) = (leg_cells as f64 * ds, (leg_cells + arc_cells) as f64 * ds);
    // Centreline point and tangent at arc length s: leg, arc, leg.
    let centreline = move |s: f64| -> (Vector3<f64>, Vector3<f64>) {
        if s <= s_a {
            (point(phi_a) - tangent(phi_a) * (s_a - s), tangent(phi_a))
        } else if s >= s_b {
            (point(phi_b) + tangent(phi_b) * (s - s_b), tangent(phi_b))
        } else {
            let phi = phi_a + (s - s_a) / rho;
            (point(phi), tangent(phi))
        }
    };
    let mut model = bent_strip(
        [cells, 2],
        cells as f64 * ds,
        width,
        &|s, y| centreline(s).0 + Vector3::new(0.0, 0.0, y),
        &|s| centreline(s).1,
    );
    model.tools.push(tool(
        "cylinder",
        Surface::revolution(
            Vector3::zeros(),
            vec![ProfileSegment::Line {
                from: [rho - 0.5 * h, 50.0],
                to: [rho - 0.5 * h, -50.0],
            }],
        )
        .expect("cylinder"),
        mu,
    ));
    let held = model.node_set("left").expect("set").to_vec();
    let pulled = model.node_set("right").expect("set").to_vec();
    let (t1, speed, damping) = (5.0, 10.0, 1000.0);
    let (t_load, t_ramp, end) = (2e-3, 2e-3, 16e-3);
    model.loads.push(NodalLoad {
        nodes: held.clone(),
        force: -tangent(phi_a) * (t1 / held.len() as f64),
        amplitude: Amplitude::SmoothStep { duration: t_load },
    });
    let pull = tangent(phi_b);
    model.boundary.push(BoundaryCondition {
        nodes: pulled.clone(),
        components: [true; 3],
        motion: Motion::Velocity {
            value: pull * speed,
            amplitude: Amplitude::Table {
                points: vec![[0.0, 0.0], [t_load, 0.0], [t_load + t_ramp, 1.0]],
            },
        },
    });
    let mut samples = Vec::new();
    let mut slipping_fraction = 1.0f64;
    let mut observer = Frames(|f: &Frame<'_>| {
        if f.state.time < 0.6 * end {
            return;
        }
        let t2: f64 = pulled
            .iter()
            .map(|&n| f.reactions[n as usize].dot(&pull))
            .sum();
        samples.push((f.state.time, t2 / t1));
        let status = &f.contact.expect("tools").status;
        let touching = status.iter().filter(|s| **s != ContactStatus::Open).count();
        let slipping = status.iter().filter(|s| **s == ContactStatus::Slip).count();
        slipping_fraction = slipping_fraction.min(slipping as f64 / touching.max(1) as f64);
    });
    let settings = ExplicitSettings {
        end_time: end,
        frames: 32,
        damping,
        ..ExplicitSettings::default()
    };
    run(driver, &model, settings, &mut observer);
    CapstanRun {
        samples,
        slipping_fraction,
        t1,
        speed,
        damping,
        areal_density: material.areal_density(),
        width,
        rho,
        legs: [leg, leg - 0.5 * ds],
    }
}

/// What a run to rest reports.
struct Rest {
    /// Largest penetration over the frames (mm).
    penetration: f64,
    /// Σ contact force on the fabric at the end (N).
    contact: Vector3<f64>,
    /// Σ applied force: loads and weight (N).
    applied: Vector3<f64>,
    /// Where the nodes touching a tool at the end are.
    touching: Vec<Vector3<f64>>,
}

/// Runs `model` (constant loads) to `end` with mass-proportional damping,
/// recording the penetration at every frame and the force balance at the end.
fn settle(driver: Driver, model: &Model, end: f64, damping: f64) -> Rest {
    // The applied force, from the model's data alone.
    let mut applied = model.gravity * model.mass.iter().sum::<f64>();
    for load in &model.loads {
        applied += load.force * load.nodes.len() as f64;
    }
    let mut rest = Rest {
        penetration: 0.0,
        contact: Vector3::zeros(),
        applied,
        touching: Vec::new(),
    };
    let mut observer = Frames(|f: &Frame<'_>| {
        rest.penetration = rest.penetration.max(penetration(f));
        let contact = f.contact.expect("tools");
        rest.contact = contact.force.iter().sum();
        rest.touching = (contact.tool_of.iter().zip(&f.state.x))
            .filter(|(t, _)| **t != u32::MAX)
            .map(|(_, x)| *x)
            .collect();
    });
    let settings = ExplicitSettings {
        end_time: end,
        frames: 100,
        damping,
        ..ExplicitSettings::default()
    };
    run(driver, model, settings, &mut observer);
    rest
}

fn blank_model(side: [f64; 2], cells: [usize; 2], center: Vector3<f64>) -> Model {
    let blank = RectangleBlank {
        width: side[0],
        height: side[1],
        center,
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells(cells),
        fibres: FibreRepresentation::Trusses,
    };
    Model::from_blank(&blank, &glass()).expect("model")
}

/// No penetration and the force balance at rest, one blank per tool kind,
/// all with gravity:
///
/// - plane: a 40 mm square dropped from 0.5 mm onto a floor with μ = 0.5,
///   every node loaded by (0.2, 0.1, −1) mN: it lands and sticks (the
///   tangential load is below μ times the normal one);
/// - sphere R = 40: a 40 mm square laid on its pole, every node pushed down
///   by 0.1 N, μ = 0.3: it wraps the cap;
/// - hemispherical punch R = 20 on a shank (a revolution profile of an arc
///   and a line): a 10 mm wide strip laid over the cap and down the shank
///   on both sides, its ends pulled down by 1 N and in by 0.2 N, μ = 0.2;
/// - a die (revolution profile: wall, fillet R 5, top face) with an opening
///   of radius 20: a 10 mm wide strip across the opening, laid over both
///   fillets by 30° into a V, its middle pushed down by 1 N, its ends held
///   on the top face by 5 N each with μ = 0.3.
///
/// The strips start in their wrapped shape (the path's nodes half a
/// thickness off the profile at y = 0; off the centre line the die's
/// opening curves away and a node that would sit too near is moved out
/// along the normal), so that they come to rest within the run.
///
/// Checks: the fabric's mid-surface never comes nearer a tool than half the
/// thickness, to 1e-6 of the thickness (the correction puts a node back on
/// the offset surface exactly for these analytic surfaces; what is left is
/// round-off and the coupled solve's 1e-9 mm tolerance), and at rest the
/// total contact force balances the applied loads and weight to 1e-3 of
/// their size.
fn no_penetration() -> Vec<Check> {
    no_penetration_with(Driver::Explicit)
}

/// [`no_penetration`] with either driver.
pub fn no_penetration_with(driver: Driver) -> Vec<Check> {
    let h = glass().thickness;
    let offset = 0.5 * h;
    let gravity = Vector3::new(0.0, 0.0, -G);
    // Name, model, end time, damping, where on the tool a node touches.
    type Region = Box<dyn Fn(&Vector3<f64>) -> &'static str>;
    let mut cases: Vec<(&str, Model, f64, f64, Region)> = Vec::new();

    let mut plane = blank_model([40.0, 40.0], [4, 4], Vector3::new(0.0, 0.0, offset + 0.5));
    plane.tools.push(tool(
        "floor",
        Surface::plane(Vector3::zeros(), Vector3::z()).expect("plane"),
        0.5,
    ));
    plane.loads.push(NodalLoad {
        nodes: plane.node_set("all").expect("set").to_vec(),
        force: Vector3::new(0.2, 0.1, -1.0) * 1e-3,
        amplitude: Amplitude::Constant,
    });
    cases.push(("plane", plane, 0.015, 500.0, Box::new(|_| "face")));

    let mut sphere = blank_model([40.0, 40.0], [8, 8], Vector3::new(0.0, 0.0, offset));
    sphere.tools.push(tool(
        "sphere",
        Surface::sphere(Vector3::new(0.0, 0.0, -40.0), 40.0).expect("sphere"),
        0.3,
    ));
    sphere.loads.push(NodalLoad {
        nodes: sphere.node_set("all").expect("set").to_vec(),
        force: Vector3::new(0.0, 0.0, -0.1),
        amplitude: Amplitude::Constant,
    });
    cases.push(("sphere", sphere, 0.01, 2000.0, Box::new(|_| "sphere")));

    // The strip over the punch: arc length s from one end, the pole at the
    // middle; ψ = angle from the pole on the cap, then straight down.
    let (radius, shank) = (20.0, 40.0);
    let rho = radius + offset;
    let (length, cells) = (100.0, 25);
    let punch_path = move |s: f64| -> (Vector3<f64>, Vector3<f64>) {
        let u = s - 0.5 * length;
        let cap = 0.5 * PI * rho;
        let centre = Vector3::new(0.0, 0.0, -radius);
        if u.abs() <= cap {
            let psi = u / rho;
            (
                centre + Vector3::new(rho * psi.sin(), 0.0, rho * psi.cos()),
                Vector3::new(psi.cos(), 0.0, -psi.sin()),
            )
        } else {
            let side = u.signum();
            (
                centre + Vector3::new(side * rho, 0.0, -(u.abs() - cap)),
                Vector3::new(0.0, 0.0, -side),
            )
        }
    };
    let mut punch = bent_strip(
        [cells, 2],
        length,
        10.0,
        &|s, y| punch_path(s).0 + Vector3::new(0.0, y, 0.0),
        &|s| punch_path(s).1,
    );
    punch.tools.push(tool(
        "punch",
        Surface::hemispherical_punch(Vector3::zeros(), radius, shank).expect("punch"),
        0.2,
    ));
    for (end, inward) in [("left", 1.0), ("right", -1.0)] {
        let nodes = punch.node_set(end).expect("set").to_vec();
        punch.loads.push(NodalLoad {
            force: Vector3::new(0.2 * inward, 0.0, -1.0) / nodes.len() as f64,
            nodes,
            amplitude: Amplitude::Constant,
        });
    }
    cases.push((
        "hemispherical punch",
        punch,
        0.01,
        2000.0,
        Box::new(move |x| if x.z > -radius { "cap" } else { "shank" }),
    ));

    // The strip across the die: flat on the top face, over the fillet by
    // φ₀, straight down to the middle; x along the strip, s from one end.
    let (opening, fillet, phi0) = (20.0, 5.0, 30f64.to_radians());
    let die_surface = Surface::revolution(
        Vector3::zeros(),
        vec![
            ProfileSegment::Line {
                from: [opening, -40.0],
                to: [opening, -fillet],
            },
            ProfileSegment::Arc {
                center: [opening + fillet, -fillet],
                radius: fillet,
                from_deg: 180.0,
                to_deg: 90.0,
            },
            ProfileSegment::Line {
                from: [opening + fillet, 0.0],
                to: [100.0, 0.0],
            },
        ],
    )
    .expect("die");
    let rf = fillet + offset;
    let (length, cells) = (80.0, 32);
    // Distances from the middle along the strip where the line meets the
    // fillet and where the fillet meets the top face.
    let line = (opening + fillet - rf * phi0.sin()) / phi0.cos();
    let on_top = line + rf * phi0;
    let die_path = move |s: f64| -> (Vector3<f64>, Vector3<f64>) {
        let u = s - 0.5 * length;
        let (side, d) = (u.signum(), u.abs());
        let (r, z, dr, dz) = if d <= line {
            (
                d * phi0.cos(),
                -fillet + rf * phi0.cos() - (line - d) * phi0.sin(),
                phi0.cos(),
                phi0.sin(),
            )
        } else if d <= on_top {
            let a = phi0 - (d - line) / rf;
            (
                opening + fillet - rf * a.sin(),
                -fillet + rf * a.cos(),
                a.cos(),
                a.sin(),
            )
        } else {
            (opening + fillet + (d - on_top), offset, 1.0, 0.0)
        };
        (
            Vector3::new(side * r, 0.0, z),
            Vector3::new(side * dr, 0.0, dz),
        )
    };
    let snap = |p: Vector3<f64>| {
        let q = die_surface.project(&p);
        if q.gap < offset {
            p + q.normal * (offset - q.gap)
        } else {
            p
        }
    };
    let mut die = bent_strip(
        [cells, 2],
        length,
        10.0,
        &|s, y| snap(die_path(s).0 + Vector3::new(0.0, y, 0.0)),
        &|s| die_path(s).1,
    );
    die.tools.push(tool("die", die_surface.clone(), 0.3));
    let middle = die.node_set("median_y").expect("set").to_vec();
    die.loads.push(NodalLoad {
        force: Vector3::new(0.0, 0.0, -1.0 / middle.len() as f64),
        nodes: middle,
        amplitude: Amplitude::Constant,
    });
    for end in ["left", "right"] {
        let nodes = die.node_set(end).expect("set").to_vec();
        die.loads.push(NodalLoad {
            force: Vector3::new(0.0, 0.0, -5.0 / nodes.len() as f64),
            nodes,
            amplitude: Amplitude::Constant,
        });
    }
    cases.push((
        "die with opening and fillet",
        die,
        0.01,
        2000.0,
        Box::new(move |x| {
            if x.x.hypot(x.y) >= opening + fillet {
                "top face"
            } else {
                "fillet"
            }
        }),
    ));

    let mut checks = Vec::new();
    for (name, mut model, end, damping, region) in cases {
        model.gravity = gravity;
        let rest = settle(driver, &model, end, damping);
        // Touching nodes by region, in order of first appearance.
        let mut counts: Vec<(&str, usize)> = Vec::new();
        for x in &rest.touching {
            let r = region(x);
            match counts.iter_mut().find(|c| c.0 == r) {
                Some(c) => c.1 += 1,
                None => counts.push((r, 1)),
            }
        }
        let counts: Vec<String> = counts
            .iter()
            .map(|(r, n)| format!("{n} on the {r}"))
            .collect();
        checks.push(Check::abs(
            format!("{name}: largest penetration / thickness"),
            0.0,
            rest.penetration / h,
            1e-6,
        ));
        checks.push(Check::abs(
            format!(
                "{name}: |Σ contact force + applied| / |applied| at rest (nodes touching: {})",
                counts.join(", ")
            ),
            0.0,
            (rest.contact + rest.applied).norm() / rest.applied.norm(),
            1e-3,
        ));
    }
    checks
}

/// Pinching: a 60 × 10 mm glass strip between a fixed lower die (the plane
/// z = 0) and a blank holder (the plane z = h, a rigid body free along z
/// pushed down by F), Coulomb friction μ on both, no gravity. The right end
/// is then pulled along the strip at a constant speed: the pull force grows
/// while the strip sticks and plateaus at 2μF, the friction of both tools,
/// once it slides. Every strip node touches two tools and the holder
/// couples them all: this is the projected-CG solve of the coupled normal
/// constraints.
///
/// Checks: the die's and the holder's normal forces equal F (to 1e-3, the
/// coupled solve's tolerance is 1e-9 mm of gap), the holder rests on the
/// strip (its displacement stays 0 to 1e-6 mm: the fabric is rigid through
/// its thickness), the pull force never exceeds 2μF by more than 1 % and
/// its mean over the sliding window is 2μF within 1 % (the pulled strip
/// also carries the damping drag α·m·V, 0.02 % of it, and the strip's
/// elastic vibration), every touching node slipping there.
fn pinching() -> Vec<Check> {
    pinching_with(Driver::Explicit)
}

/// [`pinching`] with either driver.
pub fn pinching_with(driver: Driver) -> Vec<Check> {
    let (f, mu, speed, damping) = (10.0, 0.2, 20.0, 200.0);
    let (t_clamp, t_ramp, end) = (2e-3, 1e-3, 12e-3);
    let h = glass().thickness;
    let mut model = blank_model([60.0, 10.0], [12, 2], Vector3::new(0.0, 0.0, 0.5 * h));
    model.tools.push(tool(
        "die",
        Surface::plane(Vector3::zeros(), Vector3::z()).expect("plane"),
        mu,
    ));
    model.tools.push(Tool {
        name: "holder".into(),
        surface: Surface::plane(Vector3::new(0.0, 0.0, h), -Vector3::z()).expect("plane"),
        motion: ToolMotion::Force {
            direction: -Vector3::z(),
            force: f,
            amplitude: Amplitude::SmoothStep { duration: t_clamp },
            mass: 1e-5,
        },
        friction: mu,
    });
    let pulled = model.node_set("right").expect("set").to_vec();
    model.boundary.push(BoundaryCondition {
        nodes: pulled.clone(),
        components: [true; 3],
        motion: Motion::Velocity {
            value: Vector3::new(speed, 0.0, 0.0),
            amplitude: Amplitude::Table {
                points: vec![[0.0, 0.0], [t_clamp, 0.0], [t_clamp + t_ramp, 1.0]],
            },
        },
    });
    let mut frames: Vec<PinchFrame> = Vec::new();
    let mut observer = Frames(|fr: &Frame<'_>| {
        if fr.state.time < t_clamp {
            return;
        }
        let contact = fr.contact.expect("tools");
        let touching = contact
            .status
            .iter()
            .filter(|s| **s != ContactStatus::Open)
            .count();
        let slipping = contact
            .status
            .iter()
            .filter(|s| **s == ContactStatus::Slip)
            .count();
        frames.push(PinchFrame {
            time: fr.state.time,
            pull: pulled.iter().map(|&n| fr.reactions[n as usize].x).sum(),
            die: contact.tool_force[0],
            holder: contact.tool_force[1],
            holder_displacement: contact.tool_state[1].displacement,
            slipping: slipping as f64 / touching.max(1) as f64,
        });
    });
    let settings = ExplicitSettings {
        end_time: end,
        frames: 48,
        damping,
        ..ExplicitSettings::default()
    };
    run(driver, &model, settings, &mut observer);
    let plateau = 2.0 * mu * f;
    // Sliding: the second half of the pull.
    let window: Vec<&PinchFrame> = frames
        .iter()
        .filter(|fr| fr.time >= 0.5 * (t_clamp + end))
        .collect();
    let mean = |k: fn(&PinchFrame) -> f64| {
        window.iter().map(|fr| k(fr)).sum::<f64>() / window.len() as f64
    };
    let largest_pull = frames.iter().map(|fr| fr.pull).fold(f64::MIN, f64::max);
    let holder_drift = frames
        .iter()
        .map(|fr| fr.holder_displacement.abs())
        .fold(0.0, f64::max);
    let slipping = window.iter().map(|fr| fr.slipping).fold(1.0, f64::min);
    vec![
        Check::rel(
            "die normal force, mean over the sliding window (N)",
            f,
            mean(|fr| fr.die),
            1e-3,
        ),
        Check::rel(
            "holder normal force, mean over the sliding window (N)",
            f,
            mean(|fr| fr.holder),
            1e-3,
        ),
        Check::abs(
            "largest |holder displacement| once clamped (mm)",
            0.0,
            holder_drift,
            1e-6,
        ),
        Check::abs(
            "excess of the largest pull force over 2μF, / 2μF",
            0.0,
            (largest_pull / plateau - 1.0).max(0.0),
            0.01,
        ),
        Check::rel(
            format!(
                "pull force 2μF, mean over {} sliding frames (N)",
                window.len()
            ),
            plateau,
            mean(|fr| fr.pull),
            0.01,
        ),
        Check::abs(
            "slipping / touching nodes, fewest over the sliding frames",
            1.0,
            slipping,
            0.0,
        ),
    ]
}

/// What the pinching case records at a frame once the holder is on.
struct PinchFrame {
    time: f64,
    /// Pull force on the strip's end (N).
    pull: f64,
    /// Normal force of the die and of the holder on the strip (N).
    die: f64,
    holder: f64,
    /// The holder's displacement along its axis (mm).
    holder_displacement: f64,
    /// Slipping / touching nodes.
    slipping: f64,
}
