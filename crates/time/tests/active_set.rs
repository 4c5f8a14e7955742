//! The active-set contact solver (`contact_solver = "active_set"`): its
//! Newton step against the condensed solver's on one linearisation, its
//! convergence once the active set has settled, and whole runs of both
//! solvers against each other and the analytic answers.

use drape_constitutive::Material;
use drape_contact::{
    Amplitude, ImplicitContact, ImplicitContactSettings, Increment, Surface, SystemRow, Tool,
    ToolMotion,
};
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{BoundaryCondition, Model, Motion};
use drape_time::saddle::SaddleSystem;
use drape_time::tangent::SparseTangent;
use drape_time::{
    ContactSolver, Frame, Implicit, ImplicitSettings, NoObserver, Observer, RunSummary,
};
use nalgebra::{Matrix3, Vector3};

const G: f64 = 9810.0;

fn glass() -> Material {
    Material::preset("glass-serge-4x3").unwrap()
}

fn blank_model(side: [f64; 2], cells: [usize; 2], z: f64) -> Model {
    let blank = RectangleBlank {
        width: side[0],
        height: side[1],
        center: Vector3::new(0.0, 0.0, z),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells(cells),
        fibres: FibreRepresentation::Trusses,
    };
    Model::from_blank(&blank, &glass()).unwrap()
}

fn plane(name: &str, z: f64, up: bool, friction: f64, motion: ToolMotion) -> Tool {
    let normal = if up { Vector3::z() } else { -Vector3::z() };
    Tool {
        name: name.into(),
        surface: Surface::plane(Vector3::new(0.0, 0.0, z), normal).unwrap(),
        motion,
        friction,
    }
}

const STEP: Increment = Increment {
    t_new: 1e-3,
    h: 1e-3,
    beta: 0.25,
    gamma: 0.5,
    alpha_m: 0.0,
};

/// One linearisation: the model (its tools), the iterate, the tangent
/// assembled there with the springs, the residual, the contact pass
/// linearised (after one condensed solve and return mapping, so that
/// pressed pairs have their stick rows).
struct Problem {
    model: Model,
    tangent: SparseTangent,
    fixed: Vec<bool>,
    contact: ImplicitContact,
    r: Vec<f64>,
}

/// A blank of `cells` (6 × 4 in most tests) over a floor (and, with
/// `holder`, under a force-driven holder that pinches it), its nodes a
/// little in and out of the tools, pushed down and sideways.
fn problem_with(friction: f64, elastic_slip: f64, holder: bool, cells: [usize; 2]) -> Problem {
    let h = glass().thickness;
    let mut model = blank_model([30.0, 20.0], cells, 0.5 * h);
    model
        .tools
        .push(plane("floor", 0.0, true, friction, ToolMotion::Fixed));
    if holder {
        model.tools.push(plane(
            "holder",
            h,
            false,
            friction,
            ToolMotion::Force {
                direction: -Vector3::z(),
                force: 5.0,
                amplitude: Amplitude::SmoothStep { duration: 1e-3 },
                mass: 1e-4,
            },
        ));
    }
    let n = model.node_count();
    // Nodes up to 2 µm into or out of the floor (and the holder).
    let x: Vec<Vector3<f64>> = model
        .x0
        .iter()
        .enumerate()
        .map(|(i, p)| p + Vector3::new(0.0, 0.0, 2e-3 * (1.7 * i as f64).sin()))
        .collect();
    let fixed = vec![false; 3 * n];
    let mut tangent = SparseTangent::new(&model, fixed.clone()).unwrap();
    let state = model.initial_state();
    let mut contact = ImplicitContact::new(
        model.tools.clone(),
        n,
        ImplicitContactSettings {
            offset: model.contact_offset,
            margin: 1.0,
            tolerance: 1e-13,
            max_iterations: 20_000,
            elastic_slip,
            square_friction_leans: false,
        },
    );
    contact.set_mass(&model.mass);
    contact.set_springs_in_tangent(true);
    contact.begin(&x, &vec![true; n], STEP);
    contact.linearise(&x, &model.x0);
    // Down everywhere (some nodes pulled up), sideways on one edge.
    let r: Vec<f64> = (0..n)
        .flat_map(|i| {
            let s = (0.9 * i as f64).cos();
            [0.02 * s.max(0.0), 0.01, -0.05 * s]
        })
        .collect();
    let assemble = |tangent: &mut SparseTangent, contact: &ImplicitContact| {
        tangent
            .assemble(
                &model,
                &x,
                &state.history,
                STEP.h,
                &model.mass,
                STEP.mass_factor(),
            )
            .unwrap();
        contact.add_spring_stiffness(|i, b| tangent.add_node_block(i, b));
    };
    // A first condensed solve and the return mapping give the pressed
    // pairs their stick rows (or springs).
    assemble(&mut tangent, &contact);
    tangent.factorise().unwrap();
    let mut dx = vec![0.0; 3 * n];
    contact
        .solve(&r, &mut |w: &mut [f64]| tangent.solve(w), &mut dx)
        .unwrap();
    contact.update_friction(&x, 0.0);
    contact.linearise(&x, &model.x0);
    assemble(&mut tangent, &contact);
    Problem {
        model,
        tangent,
        fixed,
        contact,
        r,
    }
}

/// The condensed step: (Δx, the tools' Δd read back through a unit
/// apply, nodal constraint forces Cᵀλ, λ_N per pair).
fn condensed(p: &mut Problem) -> (Vec<f64>, Vec<Vector3<f64>>, Vec<f64>) {
    let n = p.model.node_count();
    p.tangent.factorise().unwrap();
    let tangent = &mut p.tangent;
    let blocks: Vec<Matrix3<f64>> = (0..n)
        .map(|i| Matrix3::from_fn(|a, b| tangent.entry(3 * i + a, 3 * i + b)))
        .collect();
    let mut dx = vec![0.0; 3 * n];
    p.contact
        .solve_preconditioned(
            &p.r,
            &mut |w: &mut [f64]| tangent.solve(w),
            Some(&|i: usize| blocks[i]),
            &mut dx,
        )
        .unwrap();
    let mut f = vec![Vector3::zeros(); n];
    p.contact.add_constraint_forces(&mut f);
    let lambda = p.contact.normal_forces().map(|(_, _, l)| l).collect();
    (dx, f, lambda)
}

/// The active-set steps on the same linearisation, each deciding the set
/// from the last one's linearised gaps, until the set stays: the
/// condensed solve's problem solved by a primal–dual active-set
/// iteration. Returns what [`condensed`] does and the systems solved.
fn active_set(p: &mut Problem) -> (Vec<f64>, Vec<Vector3<f64>>, Vec<f64>, usize) {
    let n = p.model.node_count();
    let mut saddle = SaddleSystem::new();
    let mut rows: Vec<SystemRow> = Vec::new();
    let (mut lambda, mut steps) = (Vec::new(), Vec::new());
    let mut dx = vec![0.0; 3 * n];
    let mut systems = 0;
    let tangent = &p.tangent;
    let block = |i: usize| Matrix3::from_fn(|a, b| tangent.entry(3 * i + a, 3 * i + b));
    for round in 0..30 {
        p.contact.active_set_rows(&block, true, &mut rows);
        saddle
            .factorise(tangent, &p.fixed, &p.contact, &rows)
            .unwrap();
        let mut rhs = p.r.clone();
        p.contact.add_spring_forces(&mut rhs);
        let left = saddle.solve(
            &rhs,
            &p.fixed,
            &p.contact,
            &rows,
            1e-13,
            &mut dx,
            &mut lambda,
            &mut steps,
        );
        assert!(left <= 1e-13, "rows hold to {left:e} mm");
        systems += 1;
        let stats = p.contact.finish_active_set(&rows, &lambda, &steps, &dx);
        if round > 0 && stats.active_changes == 0 {
            break;
        }
    }
    let mut f = vec![Vector3::zeros(); n];
    p.contact.add_constraint_forces(&mut f);
    let lambda = p.contact.normal_forces().map(|(_, _, l)| l).collect();
    (dx, f, lambda, systems)
}

fn largest(v: impl Iterator<Item = f64>) -> f64 {
    v.fold(0.0, |m, x| m.max(x.abs()))
}

fn assert_same_step(friction: f64, elastic_slip: f64, holder: bool, compare_lambda: bool) {
    assert_same_step_with(friction, elastic_slip, holder, compare_lambda, [6, 4]);
}

fn assert_same_step_with(
    friction: f64,
    elastic_slip: f64,
    holder: bool,
    compare_lambda: bool,
    cells: [usize; 2],
) {
    let mut a = problem_with(friction, elastic_slip, holder, cells);
    let mut b = problem_with(friction, elastic_slip, holder, cells);
    let (dx_c, f_c, l_c) = condensed(&mut a);
    let (dx_a, f_a, l_a, systems) = active_set(&mut b);
    let what = format!("μ = {friction}, δ = {elastic_slip}, holder {holder}");
    assert!(systems < 30, "{what}: the active set did not settle");
    // Some pairs pressed, some not: the sets are not trivial.
    let pressed = l_c.iter().filter(|&&l| l > 0.0).count();
    assert!(
        pressed > 3 && (holder || pressed < l_c.len()),
        "{what}: {pressed} of {}",
        l_c.len()
    );
    let scale = largest(dx_c.iter().copied());
    let diff = largest(dx_c.iter().zip(&dx_a).map(|(x, y)| x - y));
    assert!(
        diff <= 1e-8 * scale,
        "{what}: Δx differs by {diff:e} of {scale:e}"
    );
    let scale = largest(f_c.iter().map(|f| f.amax()));
    let diff = largest(f_c.iter().zip(&f_a).map(|(x, y)| (x - y).amax()));
    assert!(
        diff <= 1e-8 * scale,
        "{what}: Cᵀλ differs by {diff:e} of {scale:e}"
    );
    if compare_lambda {
        let scale = largest(l_c.iter().copied());
        let diff = largest(l_c.iter().zip(&l_a).map(|(x, y)| x - y));
        assert!(
            diff <= 1e-8 * scale,
            "{what}: λ differs by {diff:e} of {scale:e}"
        );
    }
}

/// On one linearisation, the active-set iteration ends at the condensed
/// solve's step: Δx, λ_N and the stick forces (Cᵀλ) to 1e-8 of their
/// largest, frictionless, with rigid stick rows (equalities in the
/// system) and with regularised stick springs (in K̂).
#[test]
fn the_active_set_step_equals_the_condensed_step() {
    assert_same_step(0.0, 0.0, false, true);
    assert_same_step(0.3, 0.0, false, true);
    assert_same_step(0.3, 1e-3, false, true);
}

/// Pinched between the floor and a force-driven holder, how the clamping
/// force is shared by a node's two rows is indeterminate (the condensed
/// operator is singular there); the step itself is not: Δx and the nodal
/// contact forces agree to 1e-8.
#[test]
fn a_pinched_step_equals_the_condensed_step() {
    assert_same_step(0.0, 0.0, true, false);
    assert_same_step(0.2, 1e-3, true, false);
}

/// A blank of 31 × 31 nodes is large enough for the saddle system to take
/// A's Cholesky in two halves on two threads (`SplitCholesky`): the step
/// is the condensed solve's all the same. (Pinched under the holder at
/// this size the set does not settle on one linearisation within the
/// rounds the comparison allows, with or without the halves.)
#[test]
fn a_large_blank_steps_as_the_condensed_solve() {
    assert_same_step_with(0.0, 0.0, false, true, [30, 30]);
    assert_same_step_with(0.3, 1e-3, false, true, [30, 30]);
}

fn run_with(
    model: &Model,
    solver: ContactSolver,
    end: f64,
    observer: &mut dyn Observer,
) -> (drape_model::State, RunSummary) {
    let settings = ImplicitSettings {
        end_time: end,
        frames: 4,
        contact_solver: solver,
        ..ImplicitSettings::default()
    };
    let mut driver = Implicit::new(model, settings).unwrap();
    driver.record_newton();
    let mut state = model.initial_state();
    let summary = driver.run(&mut state, observer).unwrap();
    (state, summary)
}

/// A glass blank of `size` (mm) and `cells` 0.01 mm above a floor
/// (μ = 0.4) with gravity tilted 20° from its normal, and that angle.
fn on_tilted_floor(size: [f64; 2], cells: [usize; 2]) -> (Model, f64) {
    let h = glass().thickness;
    let mut model = blank_model(size, cells, 0.5 * h + 0.01);
    let a = 20f64.to_radians();
    model.gravity = Vector3::new(a.sin(), 0.0, -a.cos()) * G;
    model
        .tools
        .push(plane("floor", 0.0, true, 0.4, ToolMotion::Fixed));
    (model, a)
}

/// A blank dropped onto a floor under gravity with friction, tilted: both
/// solvers reach the same state (positions to 1e-6 mm) and the floor
/// carries the weight.
#[test]
fn both_solvers_land_a_blank_on_a_tilted_floor_alike() {
    let (model, a) = on_tilted_floor([20.0, 20.0], [4, 4]);
    let weight: f64 = model.mass.iter().sum::<f64>() * G * a.cos();
    let mut forces = Vec::new();
    let (x_c, _) = run_with(&model, ContactSolver::Condensed, 0.02, &mut NoObserver);
    let mut observer = Frames(|fr: &Frame<'_>| {
        forces.push(fr.contact.unwrap().tool_force[0]);
    });
    let (x_a, summary) = run_with(&model, ContactSolver::ActiveSet, 0.02, &mut observer);
    let last = *forces.last().unwrap();
    assert!((last - weight).abs() < 1e-6 * weight, "{last} vs {weight}");
    let diff = x_c
        .x
        .iter()
        .zip(&x_a.x)
        .map(|(p, q)| (p - q).amax())
        .fold(0.0, f64::max);
    assert!(diff < 1e-6, "positions differ by {diff:e} mm");
    let totals = summary.implicit.unwrap();
    assert!(totals.factorisations > 0);
}

/// Calls a closure with every frame.
struct Frames<F: FnMut(&Frame<'_>)>(F);
impl<F: FnMut(&Frame<'_>)> Observer for Frames<F> {
    fn frame(&mut self, frame: &Frame<'_>) {
        (self.0)(frame)
    }
}

/// Once the active set has settled, Newton converges quadratically: a
/// strip on a floor under gravity, pulled along and lifted at one end so
/// that its nodes leave the floor one by one (frictionless), every three
/// iterations of an increment whose steps changed no row show an order
/// log(r₂/r₁)/log(r₁/r₀) of at least 1.6 (measured: about 2; a linear
/// rate gives 1), from 1e-1 of the force scale down to 1e-9 (above the
/// residual's round-off).
#[test]
fn newton_converges_quadratically_once_the_active_set_has_settled() {
    let h = glass().thickness;
    let mut model = blank_model([40.0, 10.0], [8, 2], 0.5 * h);
    model.gravity = Vector3::new(0.0, 0.0, -G);
    model
        .tools
        .push(plane("floor", 0.0, true, 0.0, ToolMotion::Fixed));
    // Pulled along and lifted at one end: nodes leave the floor one by
    // one.
    let pulled = model.node_set("right").unwrap().to_vec();
    model.boundary.push(BoundaryCondition {
        nodes: pulled,
        components: [true; 3],
        motion: Motion::Velocity {
            value: Vector3::new(30.0, 0.0, 400.0),
            amplitude: drape_model::Amplitude::Constant,
        },
    });
    let settings = ImplicitSettings {
        end_time: 0.01,
        frames: 2,
        force_tolerance: 1e-10,
        contact_solver: ContactSolver::ActiveSet,
        ..ImplicitSettings::default()
    };
    let mut driver = Implicit::new(&model, settings).unwrap();
    driver.record_newton();
    let mut state = model.initial_state();
    driver.run(&mut state, &mut NoObserver).unwrap();
    let record = driver.newton_record();
    let changed = record.iter().filter(|r| r.active_changes > 0).count();
    assert!(changed > 0, "the active set never changed");
    // The floor of the residual's round-off here is ~3e-11 of the scale.
    let mut checked = 0;
    for w in record.windows(3) {
        let same = w.iter().all(|r| r.increment == w[0].increment);
        let settled = w[1].active_changes == 0 && w[2].active_changes == 0;
        if !same || !settled || w[0].iteration == 0 {
            continue;
        }
        let [r0, r1, r2] = [w[0], w[1], w[2]].map(|r| r.residual / r.scale);
        if r0 < 1e-1 && r2 > 1e-9 {
            let order = (r2 / r1).ln() / (r1 / r0).ln();
            assert!(
                order >= 1.6,
                "increment {}: {r0:e} → {r1:e} → {r2:e}: order {order:.2}",
                w[0].increment
            );
            checked += 1;
        }
    }
    assert!(checked > 0, "no iterations to check: {record:?}");
}

/// A 60 × 20 mm strip pinched between a floor and a force-driven holder
/// (F = 2 000 N, μ = 0.2 on both faces), drawn out at one end at
/// 200 mm/s: once every node slides, the pulled edge carries the
/// friction of both faces, 2·μ·F (the pull along x is steady, so no
/// inertia). How the clamp is shared among the pinched nodes is
/// indeterminate, and each node's friction cone is μ times its share:
/// when every system picked its own least-squares share, the shares
/// jumped between Newton iterations, nodes at the cone's edge flipped
/// between stick and slip in turn, and the active-set run stopped at
/// t = 0.012 s (increment 2e-10 s, 11 friction-chatter cutbacks) where
/// the condensed one completes in 39 increments. Both solvers must
/// complete, with no friction-chatter cutback, carry the pull (the
/// boundary's work over the second half of the run over the distance
/// drawn) to 1e-6, and close the energy balance up to the Newton
/// residual's work (to 1e-13 of the largest energy).
#[test]
fn a_strip_drawn_through_a_pinch_settles() {
    let h = glass().thickness;
    let (force, mu) = (2000.0, 0.2);
    let mut model = blank_model([60.0, 20.0], [12, 4], 0.0);
    model
        .tools
        .push(plane("floor", -0.5 * h, true, mu, ToolMotion::Fixed));
    model.tools.push(plane(
        "holder",
        0.5 * h,
        false,
        mu,
        ToolMotion::Force {
            direction: -Vector3::z(),
            force,
            amplitude: Amplitude::Ramp { duration: 0.01 },
            mass: 1e-3,
        },
    ));
    let (speed, end) = (200.0, 0.05);
    let pulled = model.node_set("right").unwrap().to_vec();
    model.boundary.push(BoundaryCondition {
        nodes: pulled.clone(),
        components: [true, false, false],
        motion: Motion::Velocity {
            value: Vector3::new(speed, 0.0, 0.0),
            amplitude: drape_model::Amplitude::Constant,
        },
    });
    for solver in [ContactSolver::Condensed, ContactSolver::ActiveSet] {
        // The boundary's work at each frame (N·mm): over the last frame
        // interval it is the pull times the distance drawn.
        let mut work = Vec::new();
        let mut reaction = Vec::new();
        let mut impulse = Vec::new();
        let mut unexplained: f64 = 0.0;
        let mut observer = Frames(|fr: &Frame<'_>| {
            work.push(fr.energy.boundary_work);
            let e = fr.energy;
            let scale = [e.kinetic, e.internal_work, e.boundary_work, e.contact_work]
                .into_iter()
                .fold(0.0_f64, |m, w| m.max(w.abs()));
            unexplained = unexplained.max((e.balance_error - e.residual_work).abs() / scale);
            let tools = fr.contact.unwrap().tool_state;
            impulse.push((fr.state.time, [tools[0].impulse, tools[1].impulse]));
            reaction.push(
                pulled
                    .iter()
                    .map(|&n| fr.reactions[n as usize].x)
                    .sum::<f64>(),
            );
        });
        let settings = ImplicitSettings {
            end_time: end,
            frames: 2,
            contact_solver: solver,
            ..ImplicitSettings::default()
        };
        let mut driver = Implicit::new(&model, settings).unwrap();
        let mut state = model.initial_state();
        let summary = driver.run(&mut state, &mut observer);
        let summary = summary.unwrap_or_else(|e| panic!("{solver:?}: {e}"));
        assert!(!summary.stopped, "{solver:?} stopped");
        let totals = summary.implicit.unwrap();
        assert_eq!(totals.cutback_reasons.friction_chatter, 0, "{solver:?}");
        // Every force's work is in the balance (the pull's, the pinch's
        // friction, the holder's, the inertia's): what is left is the
        // work of the residual each increment was accepted with.
        assert!(
            unexplained < 1e-13,
            "{solver:?}: balance error beyond the Newton residual's work {unexplained:e}"
        );
        let [.., before, last] = work[..] else {
            panic!("{solver:?}: {} frames", work.len());
        };
        let pull = (last - before) / (speed * 0.5 * end);
        let expected = 2.0 * mu * force;
        assert!(
            (pull - expected).abs() < 1e-6 * expected,
            "{solver:?}: pull {pull} N against 2μF = {expected} N"
        );
        // The pulled edge is pinched too: its reaction carries the friction
        // there (it read 663 N while the reactions left the contact out).
        let last = *reaction.last().unwrap();
        assert!(
            (last - expected).abs() < 1e-6 * expected,
            "{solver:?}: reaction {last} N against 2μF = {expected} N"
        );
        // The clamped holder and the floor each carry F over the last frame
        // interval, by their impulses.
        let [.., (t0, i0), (t1, i1)] = impulse[..] else {
            panic!("{solver:?}: {} frames", impulse.len());
        };
        for k in 0..2 {
            let mean = (i1[k] - i0[k]) / (t1 - t0);
            assert!(
                (mean - force).abs() < 1e-6 * force,
                "{solver:?}: tool {k} carried {mean} N"
            );
        }
    }
}

/// The implicit driver's assembly, residual and contact pass run on the
/// run's rayon threads: a 40 × 40 blank (n ≈ 8 000 unknowns in its
/// saddle-point system) landing on a tilted floor with friction ends with
/// the same bits on one thread and on two.
#[test]
fn an_active_set_run_is_bit_identical_on_one_and_two_threads() {
    let (model, _) = on_tilted_floor([200.0, 200.0], [40, 40]);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let settings = ImplicitSettings {
                end_time: 0.01,
                frames: 1,
                initial_increment: Some(0.002),
                max_increment: Some(0.002),
                contact_solver: ContactSolver::ActiveSet,
                ..ImplicitSettings::default()
            };
            let mut driver = Implicit::new(&model, settings).unwrap();
            let mut state = model.initial_state();
            let summary = driver.run(&mut state, &mut NoObserver).unwrap();
            (state, summary.implicit.unwrap())
        })
    };
    let (one, totals_one) = run(1);
    let (two, totals_two) = run(2);
    // It landed: rows entered the active set, with friction.
    assert!(totals_one.factorisations >= 5, "{totals_one:?}");
    assert!(totals_one.active_set_changes > 0, "{totals_one:?}");
    assert_eq!(totals_one.factorisations, totals_two.factorisations);
    let bits = |s: &drape_model::State| -> Vec<u64> {
        s.x.iter()
            .flat_map(|p| p.iter().map(|v| v.to_bits()))
            .collect()
    };
    assert_eq!(bits(&one), bits(&two));
}

/// A strip pinched between a floor and a force-driven holder (F = 200 N,
/// about 4.2 N a node) with one interior node pulled up by 10 N: the
/// holder must press that node by more than its share of the clamp, or
/// the floor's row there would pull (λ < 0). With every pinched node
/// given the same share, the floor row of the lifted node came out
/// negative, left the active set, came back pressed at the next
/// iteration, and so on (the hemisphere-ring's failure, from t ≈ 0.41 s).
/// The run must complete without a cutback, with the holder carrying F.
#[test]
fn a_node_lifted_inside_a_pinch_takes_more_than_its_share() {
    let h = glass().thickness;
    let force = 200.0;
    let mut model = blank_model([60.0, 20.0], [12, 4], 0.0);
    model
        .tools
        .push(plane("floor", -0.5 * h, true, 0.2, ToolMotion::Fixed));
    model.tools.push(plane(
        "holder",
        0.5 * h,
        false,
        0.2,
        ToolMotion::Force {
            direction: -Vector3::z(),
            force,
            amplitude: Amplitude::Ramp { duration: 0.01 },
            mass: 1e-3,
        },
    ));
    // An interior node: row 2 of 5, column 6 of 13.
    let lifted = 2 * 13 + 6;
    model.loads.push(drape_model::NodalLoad {
        nodes: vec![lifted],
        force: Vector3::new(0.0, 0.0, 10.0),
        amplitude: drape_model::Amplitude::Ramp { duration: 0.01 },
    });
    let mut impulse = Vec::new();
    let mut observer = Frames(|fr: &Frame<'_>| {
        impulse.push((fr.state.time, fr.contact.unwrap().tool_state[1].impulse));
    });
    let settings = ImplicitSettings {
        end_time: 0.03,
        frames: 3,
        contact_solver: ContactSolver::ActiveSet,
        ..ImplicitSettings::default()
    };
    let mut driver = Implicit::new(&model, settings).unwrap();
    let mut state = model.initial_state();
    let summary = driver.run(&mut state, &mut observer).unwrap();
    assert!(!summary.stopped);
    let totals = summary.implicit.unwrap();
    assert_eq!(totals.cutbacks, 0, "{totals:?}");
    let [.., (t0, i0), (t1, i1)] = impulse[..] else {
        panic!("{} frames", impulse.len());
    };
    let mean = (i1 - i0) / (t1 - t0);
    assert!(
        (mean - force).abs() < 1e-6 * force,
        "the holder carried {mean} N"
    );
}
