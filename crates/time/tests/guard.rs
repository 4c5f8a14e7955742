//! The instability guard and the start-up checks: each check fires on the
//! case it is for, with a message that names what is wrong, and stays
//! quiet on a sound run.

use drape_constitutive::Material;
use drape_contact::{Surface, Tool, ToolMotion};
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{Amplitude, BoundaryCondition, Model, Motion};
use drape_time::guard::{Guard, energy_floor, relative_balance_error};
use drape_time::{
    Energies, Explicit, ExplicitSettings, Frame, GuardSettings, Instability, NoObserver, Observer,
    RunError,
};
use nalgebra::Vector3;

/// A 60 × 40 mm glass blank, 6 × 4 quads, fibres as trusses, in z = 0.
fn blank() -> Model {
    let blank = RectangleBlank {
        width: 60.0,
        height: 40.0,
        center: Vector3::zeros(),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells([6, 4]),
        fibres: FibreRepresentation::Trusses,
    };
    Model::from_blank(&blank, &Material::preset("glass-serge-4x3").unwrap()).unwrap()
}

/// The blank clamped on the left, its right edge pulled 2 mm along x by a
/// smooth step over `duration`.
fn pulled(duration: f64) -> Model {
    let mut model = blank();
    model.boundary.push(BoundaryCondition::fixed(
        model.node_set("left").unwrap().to_vec(),
    ));
    model.boundary.push(BoundaryCondition {
        nodes: model.node_set("right").unwrap().to_vec(),
        components: [true, true, true],
        motion: Motion::Displacement {
            value: Vector3::new(2.0, 0.0, 0.0),
            amplitude: Amplitude::SmoothStep { duration },
        },
    });
    model
}

fn setup_error(model: &Model, settings: ExplicitSettings) -> String {
    match Explicit::new(model, settings) {
        Err(RunError::Setup(reason)) => reason,
        Err(other) => panic!("not a set-up error: {other}"),
        Ok(_) => panic!("accepted"),
    }
}

#[test]
fn a_forced_step_above_the_stable_one_is_refused_and_one_below_runs() {
    let model = pulled(2e-3);
    let settings = |time_step| ExplicitSettings {
        end_time: 2e-3,
        time_step,
        ..ExplicitSettings::default()
    };
    // The stable step at safety factor 1: the default's over 0.9.
    let chosen = Explicit::new(&model, settings(None))
        .unwrap()
        .stable_time_step(&model.x0);
    let stable = chosen / 0.9;
    let reason = setup_error(&model, settings(Some(1.2 * stable)));
    assert!(
        reason.contains("1.200× the stable time step") && reason.contains("diverge"),
        "{reason}"
    );
    let mut state = model.initial_state();
    let summary = Explicit::new(&model, settings(Some(0.99 * stable)))
        .unwrap()
        .run(&mut state, &mut NoObserver)
        .unwrap();
    assert!(summary.energy.relative_error() < 1e-6, "{summary:?}");
    assert!(summary.warnings.is_empty(), "{:?}", summary.warnings);
}

#[test]
fn the_energy_floor_is_a_microstrain_of_the_blank_and_silences_noise() {
    let model = blank();
    let glass = Material::preset("glass-serge-4x3").unwrap();
    // A·ε²·(E_f·t_f + E_m·h_m/(1 − ν_m)), A = 2400 mm², ε = 1e-6.
    let t_f = 0.5 * 0.5 * 0.57;
    let h_m = 0.5 * 0.57;
    let expected = 2400.0 * 1e-12 * (75_000.0 * t_f + 30.0 * h_m / (1.0 - 0.41));
    assert_eq!(glass.family_thickness(), t_f);
    assert!((energy_floor(&model) / expected - 1.0).abs() < 1e-12);

    // A blank on which nothing acts: its energies are round-off, and so is
    // their balance; against the floor the error is nil.
    let mut state = model.initial_state();
    for v in &mut state.v {
        *v = Vector3::new(1e-9, 0.0, 0.0);
    }
    let summary = Explicit::new(
        &model,
        ExplicitSettings {
            end_time: 1e-4,
            ..ExplicitSettings::default()
        },
    )
    .unwrap()
    .run(&mut state, &mut NoObserver)
    .unwrap();
    let e = summary.energy;
    assert!(e.kinetic < 1e-20, "{e:?}");
    assert!(
        relative_balance_error(&e, energy_floor(&model)) < 1e-9,
        "{e:?}"
    );
    // Energies above the floor are measured against themselves.
    let real = Energies {
        internal_work: 10.0,
        boundary_work: 10.1,
        balance_error: -0.1,
        ..Energies::default()
    };
    assert!((relative_balance_error(&real, energy_floor(&model)) - 0.1 / 10.1).abs() < 1e-15);
}

#[test]
fn a_prescribed_start_from_rest_does_its_kinetic_energy_in_work() {
    // A clamp that starts at once at 100 mm/s: at the first step its
    // inertia works over the mean velocity of the half step, so the
    // balance closes from the first step on (it was off by ½mv² before).
    let mut model = blank();
    model.boundary.push(BoundaryCondition {
        nodes: model.node_set("right").unwrap().to_vec(),
        components: [true, true, true],
        motion: Motion::Velocity {
            value: Vector3::new(100.0, 0.0, 0.0),
            amplitude: Amplitude::Constant,
        },
    });
    struct First(Option<Energies>);
    impl Observer for First {
        fn frame(&mut self, frame: &Frame<'_>) {
            if frame.index == 1 {
                self.0 = Some(*frame.energy);
            }
        }
    }
    let dt = Explicit::new(&model, ExplicitSettings::default())
        .unwrap()
        .stable_time_step(&model.x0);
    let mut first = First(None);
    let mut state = model.initial_state();
    let mut explicit = Explicit::new(
        &model,
        ExplicitSettings {
            end_time: 10.0 * dt,
            frames: 10,
            ..ExplicitSettings::default()
        },
    )
    .unwrap();
    explicit.run(&mut state, &mut first).unwrap();
    let e = first.0.unwrap();
    assert!(e.kinetic > 0.0);
    assert!(
        e.balance_error.abs() < 1e-5 * e.kinetic,
        "balance {:e} of kinetic {:e}",
        e.balance_error,
        e.kinetic
    );
}

#[test]
fn the_scenes_speed_and_reach_come_from_its_motions() {
    let t = 0.01;
    let mut model = pulled(t);
    model.gravity = Vector3::new(0.0, 0.0, -9810.0);
    let guard = Guard::new(&model, GuardSettings::default(), 2.0 * t);
    // Peak speed of a smooth step: 15/8·d/T = 375 mm/s; gravity's |g|·T is
    // 196 mm/s; the blank's diagonal per run time 3606 mm/s: the largest.
    let diagonal = (60.0f64 * 60.0 + 40.0 * 40.0).sqrt();
    assert!((guard.speed_scale() - diagonal / (2.0 * t)).abs() < 1e-9);
    // Reach: diagonal + 2 mm of pull + ½|g|T².
    let reach = diagonal + 2.0 + 0.5 * 9810.0 * 4.0 * t * t;
    assert!((guard.reach() - reach).abs() < 1e-9, "{}", guard.reach());
    // With the motion 100 times faster, the smooth step sets the speed.
    let fast = pulled(t / 100.0);
    let guard = Guard::new(&fast, GuardSettings::default(), 2.0 * t);
    assert!(
        (guard.speed_scale() / (1.875 * 2.0 / (t / 100.0)) - 1.0).abs() < 1e-3,
        "{}",
        guard.speed_scale()
    );

    // A node 101 × the speed is unstable, one at 99 × is not; a node past
    // the reach is out; nodes whose motion is all prescribed are skipped.
    let mut guard = Guard::new(&model, GuardSettings::default(), 2.0 * t);
    let state = model.initial_state();
    guard.begin(&state);
    let (x, mut v) = (state.x.clone(), state.v.clone());
    let movable = vec![true; x.len()];
    let scale = guard.speed_scale();
    v[7] = Vector3::new(0.0, 99.0 * scale, 0.0);
    assert_eq!(guard.nodes(&x, &v, &movable), Ok(()));
    v[7] = Vector3::new(0.0, 101.0 * scale, 0.0);
    match guard.nodes(&x, &v, &movable) {
        Err(Instability::Speed { node: 7, .. }) => {}
        other => panic!("{other:?}"),
    }
    let mut fixed = movable.clone();
    fixed[7] = false;
    assert_eq!(guard.nodes(&x, &v, &fixed), Ok(()));
    v[7] = Vector3::zeros();
    let mut far = x.clone();
    far[3].z = -(guard.reach() + 1.0);
    match guard.nodes(&far, &v, &movable) {
        Err(Instability::Outside {
            node: 3, beyond, ..
        }) => assert!((beyond - 1.0).abs() < 1e-9),
        other => panic!("{other:?}"),
    }
}

#[test]
fn the_lowest_offending_node_is_named_on_any_thread_count() {
    // Enough nodes that the check runs in several pieces (8 192 nodes
    // each): offenders in the second and third piece, the lower named.
    let model = pulled(0.01);
    let mut guard = Guard::new(&model, GuardSettings::default(), 0.02);
    let state = model.initial_state();
    guard.begin(&state);
    let n = 3 * 8192 + 5;
    let x: Vec<_> = (0..n).map(|i| state.x[i % state.x.len()]).collect();
    let mut v = vec![Vector3::zeros(); n];
    let movable = vec![true; n];
    v[20_000] = Vector3::new(0.0, 0.0, 200.0 * guard.speed_scale());
    v[9_000] = v[20_000];
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        match pool.install(|| guard.nodes(&x, &v, &movable)) {
            Err(Instability::Speed { node: 9_000, .. }) => {}
            other => panic!("{threads} threads: {other:?}"),
        }
    }
}

#[test]
fn a_scene_declared_quasi_static_stops_when_inertia_dominates() {
    // The right edge pulled 2 mm in 0.1 ms, then held, with the run going
    // on: the blank rings, its kinetic energy comparable to its strain.
    let model = pulled(1e-4);
    let settings = |ratio| ExplicitSettings {
        end_time: 4e-4,
        frames: 40,
        guard: GuardSettings {
            max_kinetic_ratio: ratio,
            ..GuardSettings::default()
        },
        ..ExplicitSettings::default()
    };
    let mut state = model.initial_state();
    Explicit::new(&model, settings(None))
        .unwrap()
        .run(&mut state, &mut NoObserver)
        .unwrap();
    let mut state = model.initial_state();
    let err = Explicit::new(&model, settings(Some(0.01)))
        .unwrap()
        .run(&mut state, &mut NoObserver)
        .unwrap_err();
    assert!(
        matches!(
            err,
            RunError::Unstable {
                what: Instability::NotQuasiStatic { .. },
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("declared quasi-static"), "{err}");
}

fn with_tool(mut model: Model, surface: Surface, motion: ToolMotion) -> Model {
    model.tools.push(Tool {
        name: "holder".into(),
        surface,
        motion,
        friction: 0.0,
    });
    model
}

fn holder_force(force: f64, mass: f64) -> ToolMotion {
    ToolMotion::Force {
        direction: Vector3::new(0.0, 0.0, -1.0),
        force,
        amplitude: Amplitude::Constant,
        mass,
    }
}

#[test]
fn start_up_checks_name_the_tool_and_the_nodes() {
    let settings = || ExplicitSettings {
        end_time: 1e-4,
        ..ExplicitSettings::default()
    };
    // A plane 1 mm above the blank whose fabric side is above: the whole
    // blank starts inside it.
    let inside = with_tool(
        blank(),
        Surface::plane(Vector3::new(0.0, 0.0, 1.0), Vector3::z()).unwrap(),
        ToolMotion::Fixed,
    );
    let reason = setup_error(&inside, settings());
    assert!(
        reason.contains("starts inside tool `holder`")
            && reason.contains("35 nodes (0, 1, 2, 3, 4, …)"),
        "{reason}"
    );
    assert!(reason.contains("up to 1.0000 mm"), "{reason}");

    // A plane 0.1 mm below the blank (half thickness 0.285 mm): a warning
    // that names it, and the run goes on.
    let close = with_tool(
        blank(),
        Surface::plane(Vector3::new(0.0, 0.0, -0.1), Vector3::z()).unwrap(),
        ToolMotion::Fixed,
    );
    let explicit = Explicit::new(&close, settings()).unwrap();
    let w = explicit.warnings().join("\n");
    assert!(
        w.contains("35 nodes (0, 1, 2, 3, 4, …) of the blank start closer to tool `holder`"),
        "{w}"
    );
    assert!(
        w.contains("the run moves the blank 0.1850 mm along (0.000, 0.000, 1.000)"),
        "{w}"
    );

    // A holder above the blank pushed by 1e15 N, or by 1e4 N with a mass of
    // 1e-9 t, would cross the fabric in one step.
    let ring = Surface::sphere(Vector3::new(0.0, 0.0, 10.3), 10.0).unwrap();
    for (force, mass) in [(1e15, 1e-3), (1e4, 1e-9)] {
        let model = with_tool(blank(), ring.clone(), holder_force(force, mass));
        let reason = setup_error(&model, settings());
        assert!(
            reason.contains("force-driven tool `holder` would travel")
                && reason.contains("pass through the blank in one step"),
            "{reason}"
        );
    }
    // The same holder with a sound force is accepted silently.
    let model = with_tool(blank(), ring, holder_force(10.0, 1e-3));
    assert!(
        Explicit::new(&model, settings())
            .unwrap()
            .warnings()
            .is_empty()
    );
}

/// A sphere (R = 50 mm) whose top touches the blank's centre, 0.185 mm
/// short of the glass's half thickness: the run translates the blank
/// that far up before its first step, stress-free, and forms on. Left to
/// the first step, the centre node was thrown off at 9 m/s and the energy
/// guard stopped such runs (the shipped hemisphere with its pole at the
/// blank: at t = 0.01 s). A blank held by a boundary condition is not
/// moved, and the warning says why. Both drivers.
#[test]
fn a_blank_that_starts_on_a_tool_is_moved_off_it_as_a_whole() {
    let touching = || {
        let mut model = with_tool(
            blank(),
            Surface::sphere(Vector3::new(0.0, 0.0, -50.0 - 0.1), 50.0).unwrap(),
            ToolMotion::Fixed,
        );
        model.gravity = Vector3::new(0.0, 0.0, -9810.0);
        model
    };
    let model = touching();
    let lift = model.contact_offset - 0.1;
    let settings = ExplicitSettings {
        end_time: 2e-3,
        ..ExplicitSettings::default()
    };
    let mut explicit = Explicit::new(&model, settings.clone()).unwrap();
    let w = explicit.warnings().join("\n");
    assert!(
        w.contains(&format!(
            "the run moves the blank {lift:.4} mm along (0.000, 0.000, 1.000)"
        )),
        "{w}"
    );
    let mut frames = Vec::new();
    let mut record = Frames(|f: &Frame<'_>| frames.push((f.state.x.clone(), f.energy.kinetic)));
    let mut state = model.initial_state();
    explicit.run(&mut state, &mut record).unwrap();
    // The first frame is the translated blank, at rest.
    let (x, kinetic) = &frames[0];
    for (a, b) in x.iter().zip(&model.x0) {
        assert!(
            (a - b - Vector3::new(0.0, 0.0, lift)).norm() < 1e-12,
            "{a} from {b}"
        );
    }
    assert_eq!(*kinetic, 0.0);
    // Nothing thrown: falling on the sphere under gravity for 2 ms, no
    // node faster than 0.1 m/s (9 m/s when the first step pushed it out).
    let fastest = state.v.iter().map(|v| v.norm()).fold(0.0, f64::max);
    assert!(fastest < 100.0, "{fastest} mm/s");

    let mut implicit = drape_time::Implicit::new(
        &model,
        drape_time::ImplicitSettings {
            end_time: 2e-3,
            frames: 1,
            ..drape_time::ImplicitSettings::default()
        },
    )
    .unwrap();
    let mut first = None;
    let mut record = Frames(|f: &Frame<'_>| {
        first.get_or_insert_with(|| (f.state.x.clone(), f.state.v.clone()));
    });
    let mut state = model.initial_state();
    implicit.run(&mut state, &mut record).unwrap();
    let (x, v) = first.expect("a first frame");
    for (a, b) in x.iter().zip(&model.x0) {
        assert!(
            (a - b - Vector3::new(0.0, 0.0, lift)).norm() < 1e-12,
            "{a} from {b}"
        );
    }
    assert!(v.iter().all(|v| *v == Vector3::zeros()));

    // Held by a boundary condition: not moved, and said.
    let mut held = touching();
    held.boundary.push(BoundaryCondition::fixed(
        held.node_set("left").unwrap().to_vec(),
    ));
    let explicit = Explicit::new(&held, settings).unwrap();
    let w = explicit.warnings().join("\n");
    assert!(
        w.contains("because boundary conditions hold nodes of it"),
        "{w}"
    );
}

/// Calls a closure with every frame.
struct Frames<F: FnMut(&Frame<'_>)>(F);
impl<F: FnMut(&Frame<'_>)> Observer for Frames<F> {
    fn frame(&mut self, frame: &Frame<'_>) {
        (self.0)(frame)
    }
}

#[test]
fn a_force_driven_tool_beside_the_blank_is_reported_and_stopped_when_it_flies_off() {
    // A sphere beside the blank, pushed down: nothing lies in its path.
    let beside = Surface::sphere(Vector3::new(100.0, 0.0, 5.0), 4.0).unwrap();
    let model = with_tool(pulled(1e-3), beside, holder_force(1.0, 1e-3));
    let settings = |end_time| ExplicitSettings {
        end_time,
        ..ExplicitSettings::default()
    };
    let explicit = Explicit::new(&model, settings(1e-3)).unwrap();
    assert!(
        explicit.warnings()[0].contains("force-driven tool `holder` moves along (0, 0, -1)")
            && explicit.warnings()[0].contains("will never touch the blank"),
        "{:?}",
        explicit.warnings()
    );
    // 1 N on 1 kg: it falls ½·1000·t² mm, 0.5 µm in 1 ms; the run ends
    // saying it never touched anything.
    let mut state = model.initial_state();
    let summary = Explicit::new(&model, settings(1e-3))
        .unwrap()
        .run(&mut state, &mut NoObserver)
        .unwrap();
    assert!(
        summary
            .warnings
            .iter()
            .any(|w| w.contains("`holder` never touched the blank")),
        "{:?}",
        summary.warnings
    );
    // 2000 N for 0.2 s: it falls 4·10⁴ mm, beyond any reach of the blank.
    let model = with_tool(
        pulled(1e-3),
        Surface::sphere(Vector3::new(100.0, 0.0, 5.0), 4.0).unwrap(),
        holder_force(2000.0, 1e-3),
    );
    let mut state = model.initial_state();
    let err = Explicit::new(
        &model,
        ExplicitSettings {
            max_steps: Some(200_000),
            ..settings(0.2)
        },
    )
    .unwrap()
    .run(&mut state, &mut NoObserver)
    .unwrap_err();
    assert!(
        matches!(&err, RunError::Unstable { what: Instability::ToolAway { tool, .. }, .. } if tool == "holder"),
        "{err}"
    );
}

#[test]
fn an_exponentially_growing_balance_error_stops_the_run_early() {
    let model = pulled(1e-3);
    let mut guard = Guard::new(&model, GuardSettings::default(), 1.0);
    let frame = |error: f64, work: f64| Energies {
        internal_work: work,
        boundary_work: work,
        balance_error: error,
        ..Energies::default()
    };
    // The bias extension that diverged: 3e-6, 1.3e-3, 0.08, 2.0 mJ of error
    // on 0.13, 5.6, 46, 238 mJ of work at 10, 20, 30, 40 % of the run.
    assert_eq!(guard.energy(&frame(3.2e-6, 0.13), 0.1), Ok(()));
    assert_eq!(guard.energy(&frame(1.3e-3, 5.6), 0.2), Ok(()));
    assert_eq!(guard.energy(&frame(0.08, 46.0), 0.3), Ok(()));
    match guard.energy(&frame(2.04, 238.0), 0.4) {
        Err(Instability::EnergyGrowth { growth, relative }) => {
            let r = [3.2e-6 / 0.13, 1.3e-3 / 5.6, 0.08 / 46.0, 2.04 / 238.0];
            for (k, g) in growth.iter().enumerate() {
                assert!((g / (r[k + 1] / r[k]) - 1.0).abs() < 1e-12, "{growth:?}");
            }
            assert!((relative - r[3]).abs() < 1e-15);
        }
        other => panic!("{other:?}"),
    }
    // The first check (of relative errors at 10 %, 20 %, … of the run)
    // that stops a fresh guard, and why.
    let first_stop = |errors: &[f64]| {
        let mut guard = Guard::new(&model, GuardSettings::default(), 1.0);
        errors.iter().enumerate().find_map(|(k, &error)| {
            guard
                .energy(&frame(error, 1.0), 0.1 * (k + 1) as f64)
                .err()
                .map(|e| (k, e))
        })
    };
    // An impact makes the error jump once: no steady growth.
    let impact = first_stop(&[1e-8, 2e-8, 3e-3, 3.1e-3, 3.3e-3, 3.2e-3]);
    assert_eq!(impact, None);
    // A first impact lifts the error from round-off to a finite one over
    // two checks (the tray's coarse run), then it falls: not a growth.
    let first = first_stop(&[1.9e-15, 3.1e-15, 2.9e-5, 5.47e-3, 1.5e-3, 1.2e-3]);
    assert_eq!(first, None);
    // The same rise from just above round-off that keeps growing stops.
    let growing = first_stop(&[1.9e-15, 3.1e-15, 2.9e-5, 5.47e-3, 1e-2, 2e-2]);
    assert!(
        matches!(growing, Some((5, Instability::EnergyGrowth { .. }))),
        "{growing:?}"
    );
    // A sound run's relative error wanders, and below 1e-3 its growth does
    // not count.
    let mut guard = Guard::new(&model, GuardSettings::default(), 1.0);
    // (The deep drawing's first frames, then a wander above 1e-3.)
    for (k, relative) in [
        1.6e-7, 1.2e-6, 1.3e-6, 1.7e-6, 7.8e-6, 2.8e-6, 1e-3, 2e-3, 1.5e-3, 3e-3, 2.5e-3,
    ]
    .into_iter()
    .enumerate()
    {
        let t = 0.05 * (k + 1) as f64;
        assert_eq!(
            guard.energy(&frame(relative * 100.0, 100.0), t),
            Ok(()),
            "{k}"
        );
    }
    // Above 5 % it stops at once.
    assert!(matches!(
        guard.energy(&frame(60.0, 1e3), 0.7),
        Err(Instability::EnergyBalance { .. })
    ));
}
