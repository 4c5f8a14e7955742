//! Follower pressures in the drivers: Newton with the load's symmetric
//! stiffness, a zero pressure that changes nothing, and forces that do not
//! depend on the thread count. (The equilibrium T = p·R against the
//! analytic arc is `cargo xtask validate --filter pressure`.)

use drape_constitutive::Material;
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{Amplitude, BoundaryCondition, Model, Motion, PressureLoad};
use drape_time::{Explicit, ExplicitSettings, Implicit, ImplicitSettings, NoObserver};
use nalgebra::Vector3;

/// A carbon strip `cells` along x over 40 mm, clamped at both ends, held
/// in y (plane strain), stretched 1 % in 0.1 s and then inflated by
/// `pressure` (MPa) along +z, ramped up until 1 s.
fn inflated_strip(cells: [usize; 2], pressure: f64) -> Model {
    let blank = RectangleBlank {
        width: 40.0,
        height: 10.0,
        center: Vector3::zeros(),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells(cells),
        fibres: FibreRepresentation::Trusses,
    };
    let material = Material::preset("carbon-prepreg-2x2").unwrap();
    let mut model = Model::from_blank(&blank, &material).unwrap();
    let all: Vec<u32> = (0..model.node_count() as u32).collect();
    model.boundary.push(BoundaryCondition {
        nodes: all,
        components: [false, true, false],
        motion: Motion::Fixed,
    });
    model.boundary.push(BoundaryCondition::fixed(
        model.node_set("left").unwrap().to_vec(),
    ));
    // Stretched by 1 % over the first tenth of a second, so that the
    // membrane has tension (a flat, slack one has no stiffness across it),
    // then inflated.
    model.boundary.push(BoundaryCondition {
        nodes: model.node_set("right").unwrap().to_vec(),
        components: [true; 3],
        motion: Motion::Displacement {
            value: Vector3::new(0.4, 0.0, 0.0),
            amplitude: Amplitude::Ramp { duration: 0.1 },
        },
    });
    let load = PressureLoad::on_membranes(
        &model,
        None,
        false,
        pressure,
        Amplitude::Table {
            points: vec![[0.1, 0.0], [1.0, 1.0]],
        },
    );
    model.pressure.push(load);
    model
}

/// The strip inflated quasi-statically in 20 increments: every increment
/// converges at once, and quadratically, eₖ₊₁ ≤ 10·eₖ² down to round-off.
/// K̂ holds the symmetric part of the load stiffness; the skew part it
/// leaves out does not show here. (Without the load stiffness the same run
/// took 70 iterations instead of 55, converging linearly, 1e-8 → 1e-11 →
/// 1e-13, once the crown is up.)
#[test]
fn newton_converges_quadratically_on_an_inflated_strip() {
    let model = inflated_strip([8, 2], 0.05);
    let settings = ImplicitSettings {
        end_time: 1.0,
        frames: 1,
        initial_increment: Some(0.05),
        max_increment: Some(0.05),
        force_tolerance: 1e-12,
        displacement_tolerance: 1e-12,
        ..ImplicitSettings::default()
    };
    let mut driver = Implicit::new(&model, settings).unwrap();
    driver.record_newton();
    let mut state = model.initial_state();
    let summary = driver.run(&mut state, &mut NoObserver).unwrap();
    let totals = summary.implicit.unwrap();
    assert_eq!((summary.steps, totals.cutbacks), (20, 0));
    let record = driver.newton_record();
    let mut quadratic = 0;
    for increment in 1..=20 {
        let e: Vec<f64> = record
            .iter()
            .filter(|r| r.increment == increment)
            .map(|r| r.residual / r.scale)
            .collect();
        for w in e.windows(2) {
            if w[0] < 1e-2 && w[1] > 1e-12 {
                assert!(w[1] <= 10.0 * w[0] * w[0], "increment {increment}: {e:?}");
                quadratic += 1;
            }
        }
    }
    assert!(quadratic >= 3, "{record:?}");
    // Inflated along +z, the crown above the clamps.
    let crown = state
        .x
        .iter()
        .map(|x| x.z)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(crown > 0.1, "crown {crown}");
}

/// A pressure of zero adds zeros: the run equals the run without it, bit
/// for bit (the pass costs a scene that has none nothing but its check).
#[test]
fn a_zero_pressure_changes_nothing() {
    let with = inflated_strip([8, 2], 0.0);
    let mut without = with.clone();
    without.pressure.clear();
    // Something to move it: gravity across the strip.
    let settings = ExplicitSettings {
        end_time: 1e-3,
        frames: 1,
        ..ExplicitSettings::default()
    };
    let mut states = Vec::new();
    for model in [&with, &without] {
        let mut model = model.clone();
        model.gravity = Vector3::new(0.0, 0.0, -9810.0);
        let mut state = model.initial_state();
        Explicit::new(&model, settings.clone())
            .unwrap()
            .run(&mut state, &mut NoObserver)
            .unwrap();
        states.push(state);
    }
    assert!(states[0].x[20].z < 0.0);
    assert_eq!(states[0], states[1]);
}

/// The pressure's nodal sums are in a fixed order: 2 560 loaded quads (more
/// than one task's worth) give the same bits on one thread and on three.
#[test]
fn the_pressure_forces_do_not_depend_on_the_thread_count() {
    let mut model = inflated_strip([64, 40], 0.1);
    model.pressure[0].amplitude = Amplitude::Constant;
    let settings = ExplicitSettings {
        end_time: 1.0,
        max_steps: Some(30),
        frames: 0,
        ..ExplicitSettings::default()
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut state = model.initial_state();
            Explicit::new(&model, settings.clone())
                .unwrap()
                .run(&mut state, &mut NoObserver)
                .unwrap();
            state
        })
    };
    let (one, three) = (run(1), run(3));
    assert!(one.x.iter().any(|x| x.z > 0.0));
    assert_eq!(one, three);
}

/// A ply pressed flat onto a floor by a bag whose pressure ramps up stays
/// at rest, and its energy balance with it. The full-step kinetic energy
/// takes the next step's contact force as the part of the last one that
/// the node's other forces press it with: capped at the last force, it
/// fell behind the growing pressure by one step's increase, and read a
/// kinetic energy of up to 8e-7 mJ in a ply that does not move; with no
/// other energy in play, the guard's growth check stopped the run at
/// t = 4 ms (error ×52 over its last three checks).
#[test]
fn a_ply_pressed_onto_a_floor_by_a_ramped_bag_keeps_its_balance() {
    use drape_contact::{Surface, Tool, ToolMotion};
    let blank = RectangleBlank {
        width: 100.0,
        height: 100.0,
        center: Vector3::zeros(),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells([10, 10]),
        fibres: FibreRepresentation::Trusses,
    };
    let material = Material::preset("carbon-prepreg-2x2").unwrap();
    let h = material.thickness;
    let mut model = Model::from_blank(&blank, &material).unwrap();
    model.tools.push(Tool {
        name: "plate".into(),
        surface: Surface::plane(Vector3::new(0.0, 0.0, -0.5 * h), Vector3::z()).unwrap(),
        motion: ToolMotion::Fixed,
        friction: 0.2,
    });
    let load = PressureLoad::on_membranes(
        &model,
        None,
        true,
        0.1,
        Amplitude::SmoothStep { duration: 0.01 },
    );
    model.pressure.push(load);
    let settings = ExplicitSettings {
        end_time: 0.02,
        frames: 2,
        mass_scaling: Some(2e-5),
        ..ExplicitSettings::default()
    };
    /// The largest kinetic energy at the frames (mJ).
    struct Largest(f64);
    impl drape_time::Observer for Largest {
        fn frame(&mut self, frame: &drape_time::Frame<'_>) {
            self.0 = self.0.max(frame.energy.kinetic);
        }
    }
    let mut driver = Explicit::new(&model, settings).expect("driver");
    let mut state = model.initial_state();
    let mut largest = Largest(0.0);
    driver
        .run(&mut state, &mut largest)
        .expect("the run completes");
    // The pressure's work over one step's travel under it, F·a·Δt²
    // (1 000 N on 1e-4 mm or so), is the scale the error had.
    assert!(largest.0 < 1e-15, "kinetic energy {:e} mJ", largest.0);
}
