//! End-to-end checks of the explicit driver on small blanks: determinism
//! across thread counts, a free oscillation's energy, a diverging run's
//! diagnosis, mass scaling. The full-size validation cases (picture frame,
//! bias extension, uniaxial tension) live in `cargo xtask validate`.

use drape_constitutive::Material;
use drape_elements::{BendingBatch, yarn_triplets};
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{Amplitude, BoundaryCondition, Model, Motion, NodalLoad, State};
use drape_time::{
    Control, DriverState, Explicit, ExplicitSettings, Frame, NoObserver, Observer, Progress,
    RunError,
};
use nalgebra::Vector3;

fn blank(
    cells: [usize; 2],
    element: ElementKind,
    fibres: FibreRepresentation,
    theta: f64,
) -> RectangleBlank {
    RectangleBlank {
        width: 10.0 * cells[0] as f64,
        height: 10.0 * cells[1] as f64,
        center: Vector3::zeros(),
        orientation_deg: theta,
        element,
        meshing: Meshing::Cells(cells),
        fibres,
    }
}

/// A square blank, clamped on the left, its right edge pulled up and
/// sideways: every kind of element pass and a prescribed motion.
fn pulled(cells: usize, element: ElementKind, fibres: FibreRepresentation) -> Model {
    let theta = if fibres == FibreRepresentation::Embedded {
        30.0
    } else {
        0.0
    };
    let mut model = Model::from_blank(
        &blank([cells, cells], element, fibres, theta),
        &Material::preset("carbon-prepreg-2x2").unwrap(),
    )
    .unwrap();
    model.boundary.push(BoundaryCondition::fixed(
        model.node_set("left").unwrap().to_vec(),
    ));
    model.boundary.push(BoundaryCondition {
        nodes: model.node_set("right").unwrap().to_vec(),
        components: [true, true, true],
        motion: Motion::Displacement {
            value: Vector3::new(0.5, 3.0, 4.0),
            amplitude: Amplitude::SmoothStep { duration: 2e-4 },
        },
    });
    model.gravity = Vector3::new(0.0, 0.0, -9810.0);
    model
}

fn run_with_threads(model: &Model, threads: usize, settings: ExplicitSettings) -> State {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut state = model.initial_state();
        Explicit::new(model, settings)
            .unwrap()
            .run(&mut state, &mut NoObserver)
            .unwrap();
        state
    })
}

#[test]
fn positions_are_bit_identical_on_one_and_two_threads() {
    // Large enough that rayon splits the element passes (1 640 trusses a
    // family in pieces of 1 024, 1 600 quads in pieces of 256) and, with
    // trusses, runs them beside the membranes.
    for (element, fibres) in [
        (ElementKind::Quad, FibreRepresentation::Trusses),
        (ElementKind::Triangle, FibreRepresentation::Embedded),
    ] {
        let model = pulled(40, element, fibres);
        let settings = ExplicitSettings {
            end_time: 1e-4,
            frames: 2,
            ..ExplicitSettings::default()
        };
        let one = run_with_threads(&model, 1, settings.clone());
        let two = run_with_threads(&model, 2, settings);
        assert!(one.step > 20);
        let bits = |s: &State| -> Vec<u64> {
            s.x.iter()
                .flat_map(|p| p.iter().map(|v| v.to_bits()))
                .collect()
        };
        assert_eq!(bits(&one), bits(&two), "{element:?}/{fibres:?}");
        assert_eq!(one.history, two.history);
    }
}

/// Records the energies at every frame.
#[derive(Default)]
struct EnergyLog {
    total: Vec<f64>,
    balance: Vec<f64>,
    strain: Vec<f64>,
}

impl Observer for EnergyLog {
    fn frame(&mut self, frame: &Frame<'_>) {
        self.total.push(frame.energy.kinetic + frame.energy.strain);
        self.balance.push(frame.energy.balance_error);
        self.strain.push(frame.energy.strain);
    }
}

#[test]
fn undamped_free_oscillation_keeps_its_energy() {
    // A free glass blank with trusses, set breathing by an initial velocity
    // field with no net momentum, for 10⁵ steps.
    let model = Model::from_blank(
        &blank([4, 4], ElementKind::Quad, FibreRepresentation::Trusses, 0.0),
        &Material::preset("glass-serge-4x3").unwrap(),
    )
    .unwrap();
    let mut state = model.initial_state();
    for (v, x) in state.v.iter_mut().zip(&model.x0) {
        *v = Vector3::new(x.x, 0.5 * x.y, 0.0) * 2.0;
    }
    let mut log = EnergyLog::default();
    let settings = ExplicitSettings {
        end_time: 1.0,
        max_steps: Some(100_000),
        frames: 4000,
        ..ExplicitSettings::default()
    };
    let mut driver = Explicit::new(&model, settings).unwrap();
    // Half the stable step: central differences conserve a nearby energy,
    // and the measured one oscillates by O((ω·Δt)²) about it, ~1e-3 at 0.9.
    let dt = 0.5 * driver.stable_time_step(&model.x0);
    let settings = ExplicitSettings {
        end_time: 100_000.0 * dt,
        time_step: Some(dt),
        frames: 400,
        ..ExplicitSettings::default()
    };
    driver = Explicit::new(&model, settings).unwrap();
    let summary = driver.run(&mut state, &mut log).unwrap();
    assert_eq!(summary.steps, 100_000);
    let peak = log.total.iter().cloned().fold(0.0, f64::max);
    let drift = log
        .total
        .iter()
        .map(|e| (e - log.total[0]).abs())
        .fold(0.0, f64::max);
    let balance = log.balance.iter().map(|e| e.abs()).fold(0.0, f64::max);
    // The fibres were loaded: the energy went through the elements.
    assert!(log.strain.iter().cloned().fold(0.0, f64::max) > 0.2 * peak);
    assert!(
        drift < 1e-3 * peak,
        "K + U drifted by {drift:e} of {peak:e}"
    );
    assert!(
        balance < 1e-3 * peak,
        "balance error {balance:e} of {peak:e}"
    );
    // Bounded, not drifting: the last quarter is no worse than twice the first.
    let quarter = log.total.len() / 4;
    let worst = |r: &[f64]| {
        r.iter()
            .map(|e| (e - log.total[0]).abs())
            .fold(0.0, f64::max)
    };
    assert!(worst(&log.total[3 * quarter..]) < 2.0 * worst(&log.total[1..quarter]));
}

#[test]
fn an_exploding_run_stops_with_a_diagnosis_and_keeps_the_last_frame() {
    // A load of 10⁹ N on the top edge's midpoint tears the blank apart
    // within a few frames.
    let mut model = pulled(6, ElementKind::Quad, FibreRepresentation::Trusses);
    let midpoint = model.node_set("edge_midpoints").unwrap()[3];
    model.loads.push(NodalLoad {
        nodes: vec![midpoint],
        force: Vector3::new(0.0, 0.0, 1e9),
        amplitude: Amplitude::Ramp { duration: 1e-3 },
    });
    let mut state = model.initial_state();
    let settings = ExplicitSettings {
        end_time: 1e-3,
        frames: 50,
        ..ExplicitSettings::default()
    };
    struct Times(Vec<f64>);
    impl Observer for Times {
        fn frame(&mut self, frame: &Frame<'_>) {
            self.0.push(frame.state.time);
        }
    }
    let mut frames = Times(Vec::new());
    let err = Explicit::new(&model, settings)
        .unwrap()
        .run(&mut state, &mut frames)
        .unwrap_err();
    let text = err.to_string();
    let (step, time) = err.step_and_time().unwrap();
    assert!(text.starts_with(&format!("step {step}, t = ")), "{text}");
    assert!(
        matches!(
            &err,
            RunError::Unstable { .. } | RunError::Element { .. } | RunError::NonFinite { .. }
        ),
        "{text}"
    );
    // The state is the last frame the observer got, which passed.
    assert!(state.time < time);
    assert_eq!(Some(&state.time), frames.0.last(), "{text}");
    assert!(state.x.iter().all(|p| p.iter().all(|v| v.is_finite())));
}

#[test]
fn an_observer_can_stop_the_run() {
    // Progress is reported every 100 ms of wall time: the first
    // checkpoint (step 100) waits that long, so the report comes a step
    // later however fast the machine (a release build otherwise ran this
    // model ~32 000 steps, past where it turns unstable, before the first
    // report).
    struct StopAt(u64);
    impl Observer for StopAt {
        fn checkpoint(&mut self, _state: &State, _driver: &DriverState) {
            std::thread::sleep(std::time::Duration::from_millis(110));
        }
        fn progress(&mut self, p: &Progress) -> Control {
            if p.step >= self.0 {
                Control::Stop
            } else {
                Control::Continue
            }
        }
    }
    let model = pulled(4, ElementKind::Quad, FibreRepresentation::Trusses);
    let mut state = model.initial_state();
    let settings = ExplicitSettings {
        end_time: 10.0,
        checkpoint_every: Some(100),
        ..ExplicitSettings::default()
    };
    let summary = Explicit::new(&model, settings)
        .unwrap()
        .run(&mut state, &mut StopAt(1))
        .unwrap();
    assert!(summary.stopped);
    assert!(state.time < 10.0);
    assert!(summary.steps <= 200, "stopped at step {}", summary.steps);
}

#[test]
fn mass_scaling_reaches_its_target_and_reports_the_added_mass() {
    let model = pulled(8, ElementKind::Quad, FibreRepresentation::Trusses);
    let plain = Explicit::new(&model, ExplicitSettings::default()).unwrap();
    let dt = plain.stable_time_step(&model.x0);
    let scaled = Explicit::new(
        &model,
        ExplicitSettings {
            mass_scaling: Some(4.0 * dt),
            end_time: 20.0 * dt,
            ..ExplicitSettings::default()
        },
    )
    .unwrap();
    let dt_scaled = scaled.stable_time_step(&model.x0);
    assert!(
        dt_scaled >= 4.0 * dt * (1.0 - 1e-12),
        "{dt_scaled:e} vs {:e}",
        4.0 * dt
    );
    let mut state = model.initial_state();
    let mut scaled = scaled;
    let summary = scaled.run(&mut state, &mut NoObserver).unwrap();
    let mass: f64 = model.mass.iter().sum();
    // Uniform elements all ask for 16× their mass.
    assert!(
        (summary.added_mass - 15.0 * mass).abs() < 1e-9 * mass,
        "{}",
        summary.added_mass / mass
    );
}

#[test]
fn mass_scaling_weighs_down_only_the_nodes_whose_bending_is_too_fast() {
    // A 20 × 1 strip of 10 mm cells with stiff yarn bending on the warp
    // triplets around its first interior station only (3 stations, 12.5 %
    // of the mass): those govern the step. The target is a tenth of every
    // other element's step, so only the triplets ask for mass. Soft yarns
    // and resin keep the other steps long (the paper's yarn: a buckling
    // stress is bounded by the crimp and this modulus).
    let mut material = Material::paper_preset("glass-serge-4x3").unwrap();
    material.fibre.modulus = 20.0;
    material.resin.young = 2.0;
    let mut model = Model::from_blank(
        &blank(
            [20, 1],
            ElementKind::Quad,
            FibreRepresentation::Trusses,
            0.0,
        ),
        &material,
    )
    .unwrap();
    let others = Explicit::new(&model, ExplicitSettings::default())
        .unwrap()
        .stable_time_step(&model.x0);
    let x_min = model.x0.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
    let mut edges = Vec::new();
    let mut area = vec![0.0; model.node_count()];
    for b in &model.membranes {
        for e in 0..b.len() {
            let nodes = b.element_nodes(e);
            for (k, &a) in nodes.iter().enumerate() {
                edges.push([a, nodes[(k + 1) % nodes.len()]]);
            }
            for (&n, a) in nodes.iter().zip(b.nodal_areas(e)) {
                area[n as usize] += a;
            }
        }
    }
    let triplets: Vec<_> = yarn_triplets(&model.x0, &edges, [Vector3::x(), Vector3::y()])
        .into_iter()
        .filter(|t| t.family == 0 && model.x0[t.nodes[1] as usize].x < x_min + 15.0)
        .collect();
    assert_eq!(triplets.len(), 2);
    model
        .bending
        .push(BendingBatch::new(&model.x0, &triplets, &area, [1e7, 1e7]).unwrap());
    let bent = Explicit::new(&model, ExplicitSettings::default())
        .unwrap()
        .stable_time_step(&model.x0);
    let target = 0.1 * others;
    // What scaling every node alike would need.
    let uniform = (target / bent).powi(2);
    assert!(uniform > 50.0, "bending does not govern: {uniform}");
    let scaled = Explicit::new(
        &model,
        ExplicitSettings {
            mass_scaling: Some(target),
            ..ExplicitSettings::default()
        },
    )
    .unwrap();
    let dt = scaled.stable_time_step(&model.x0);
    assert!(dt >= target * (1.0 - 1e-12), "{dt:e} vs {target:e}");
    // The triplets' nodes take at most `uniform` each (a triplet's own
    // step is above the combined one), the others at most the last
    // uniform factor, 1 + 1 % here: ≤ 0.125·uniform + 0.01 of the mass,
    // where scaling all nodes would add (uniform − 1) of it.
    let mass: f64 = model.mass.iter().sum();
    let added = scaled.added_mass() / mass;
    assert!(
        added < 0.13 * uniform && added > 0.05 * uniform,
        "added {added} of the mass, uniform scaling needs ×{uniform}"
    );
}

/// Keeps the last checkpoint handed over.
#[derive(Default)]
struct Keep(Option<(State, drape_time::DriverState)>);
impl Observer for Keep {
    fn checkpoint(&mut self, state: &State, driver: &drape_time::DriverState) {
        self.0 = Some((state.clone(), driver.clone()));
    }
}

#[test]
fn a_run_resumed_from_a_checkpoint_ends_bit_for_bit_where_an_uninterrupted_one_does() {
    // Viscoelastic resin, gravity, a prescribed pull, a floor with friction
    // and mass scaling: every piece of carried state.
    let mut model = pulled(6, ElementKind::Quad, FibreRepresentation::Trusses);
    model.tools.push(drape_contact::Tool {
        name: "floor".into(),
        surface: drape_contact::Surface::plane(Vector3::new(0.0, 0.0, -0.5), Vector3::z()).unwrap(),
        motion: drape_contact::ToolMotion::Fixed,
        friction: 0.3,
    });
    let settings = ExplicitSettings {
        end_time: 4e-4,
        frames: 4,
        mass_scaling: Some(2e-6),
        ..ExplicitSettings::default()
    };
    let mut straight = model.initial_state();
    Explicit::new(&model, settings.clone())
        .unwrap()
        .run(&mut straight, &mut NoObserver)
        .unwrap();

    let mut first = model.initial_state();
    let mut keep = Keep::default();
    let stopped = ExplicitSettings {
        checkpoint_every: Some(37),
        max_steps: Some(100),
        ..settings.clone()
    };
    let summary = Explicit::new(&model, stopped)
        .unwrap()
        .run(&mut first, &mut keep)
        .unwrap();
    assert!(summary.stopped);
    let (mut state, driver) = keep.0.expect("a checkpoint");
    assert_eq!(state.step, 74);
    let mut resumed = Explicit::new(&model, settings).unwrap();
    resumed.resume_from(driver);
    resumed.run(&mut state, &mut NoObserver).unwrap();
    assert_eq!(state.step, straight.step);
    let bits = |s: &State| -> Vec<u64> {
        s.x.iter()
            .flat_map(|p| p.iter().map(|v| v.to_bits()))
            .collect()
    };
    assert_eq!(bits(&state), bits(&straight));
    assert_eq!(state.history, straight.history);
}

#[test]
fn a_run_failing_in_the_membrane_pass_reports_its_last_frame_whole() {
    // Every node held but the top row's, which moves down onto the row
    // below by the end: the top row of quads (the last elements, so the
    // other lane blocks have already advanced their history in place when
    // they fail) is flattened at the last step.
    let mut model = Model::from_blank(
        &blank([8, 8], ElementKind::Quad, FibreRepresentation::Trusses, 0.0),
        &Material::preset("carbon-prepreg-2x2").unwrap(),
    )
    .unwrap();
    let top = model.node_set("top").unwrap().to_vec();
    let held: Vec<u32> = (0..model.node_count() as u32)
        .filter(|n| !top.contains(n))
        .collect();
    model.boundary.push(BoundaryCondition::fixed(held));
    let end_time = 2e-4;
    model.boundary.push(BoundaryCondition {
        nodes: top,
        components: [true, true, true],
        motion: Motion::Displacement {
            value: Vector3::new(5.0, -10.0, 0.0),
            amplitude: Amplitude::Ramp { duration: end_time },
        },
    });
    let settings = ExplicitSettings {
        end_time,
        frames: 10,
        ..ExplicitSettings::default()
    };
    #[derive(Default)]
    struct LastFrame(Option<State>);
    impl Observer for LastFrame {
        fn frame(&mut self, frame: &Frame<'_>) {
            self.0 = Some(frame.state.clone());
        }
    }
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut state = model.initial_state();
        let mut last = LastFrame::default();
        let err = pool
            .install(|| {
                Explicit::new(&model, settings.clone())
                    .unwrap()
                    .run(&mut state, &mut last)
            })
            .unwrap_err();
        let RunError::Element {
            step, batch, error, ..
        } = &err
        else {
            panic!("{err}");
        };
        assert!(batch.starts_with("membrane"), "{err}");
        assert!(error.element >= 56, "{err}");
        // What the run reports is the last frame, history and all (not the
        // failed step's half-advanced history with the frame's positions).
        let frame = last.0.unwrap();
        assert!(frame.step > 0 && frame.step < *step, "{err}");
        assert_eq!(state.step, frame.step);
        assert_eq!(state.time.to_bits(), frame.time.to_bits());
        assert_eq!(state.x, frame.x);
        assert_eq!(state.v, frame.v);
        assert_eq!(state.history, frame.history);
        assert_ne!(state.history, model.initial_state().history);
    }
}
