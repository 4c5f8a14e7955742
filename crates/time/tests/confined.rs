//! The explicit driver's confined yarns (crate `confinement`): a glass
//! strip pushed together between two facing planes, its yarns shortened
//! past the wall of their clearance. What the law itself does is tested in
//! drape-constitutive (`FibreLaw::confined_stress_and_tangent`); here, that
//! the driver feeds it: the tools' gaps change the run only when they are
//! close, the same bits on one and two threads, and a resumed run ends
//! where an uninterrupted one does.

use drape_constitutive::Material;
use drape_contact::{Surface, Tool, ToolMotion};
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{Amplitude, BoundaryCondition, Model, Motion, State};
use drape_time::{DriverState, Explicit, ExplicitSettings, NoObserver, Observer};
use nalgebra::Vector3;

/// A 60 × 60 mm glass blank (the preset: L = 4.55 mm, h = 0.57 mm),
/// clamped on the left, its right edge pushed 3 mm in (the x yarns 5 %
/// shorter), between a mould below and a punch above whose faces leave
/// `clearance` mm over the ply; `segment_length` replaces the preset's L.
fn squeezed(clearance: f64, segment_length: f64) -> Model {
    let mut material = Material::preset("glass-serge-4x3").unwrap();
    material.fibre.segment_length = segment_length;
    let blank = RectangleBlank {
        width: 60.0,
        height: 60.0,
        center: Vector3::zeros(),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells([6, 6]),
        fibres: FibreRepresentation::Trusses,
    };
    let mut model = Model::from_blank(&blank, &material).unwrap();
    model.boundary.push(BoundaryCondition::fixed(
        model.node_set("left").unwrap().to_vec(),
    ));
    model.boundary.push(BoundaryCondition {
        nodes: model.node_set("right").unwrap().to_vec(),
        components: [true, true, true],
        motion: Motion::Displacement {
            value: Vector3::new(-3.0, 0.0, 0.0),
            amplitude: Amplitude::SmoothStep { duration: 4e-4 },
        },
    });
    let face = model.contact_offset + 0.5 * clearance;
    for (name, z, normal) in [("mould", -face, 1.0), ("punch", face, -1.0)] {
        model.tools.push(Tool {
            name: name.into(),
            surface: Surface::plane(Vector3::new(0.0, 0.0, z), Vector3::z() * normal).unwrap(),
            motion: ToolMotion::Fixed,
            friction: 0.0,
        });
    }
    model
}

fn settings() -> ExplicitSettings {
    ExplicitSettings {
        end_time: 6e-4,
        frames: 2,
        mass_scaling: Some(2e-6),
        ..ExplicitSettings::default()
    }
}

fn run(model: &Model, threads: usize) -> State {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut state = model.initial_state();
        Explicit::new(model, settings())
            .unwrap()
            .run(&mut state, &mut NoObserver)
            .unwrap();
        state
    })
}

fn bits(s: &State) -> Vec<u64> {
    s.x.iter()
        .flat_map(|p| p.iter().map(|v| v.to_bits()))
        .collect()
}

#[test]
fn close_tools_confine_far_ones_do_not_and_threads_do_not_matter() {
    let length = Material::preset("glass-serge-4x3")
        .unwrap()
        .fibre
        .segment_length;
    assert!(length > 0.0);
    // 0.05 mm of room: the yarns' wall at 0.3 % shortening, passed.
    let close = run(&squeezed(0.05, length), 1);
    let free = run(&squeezed(0.05, 0.0), 1);
    assert_ne!(bits(&close), bits(&free), "confinement changed nothing");
    // Tools 100 mm apart: the free law, bit for bit.
    assert_eq!(
        bits(&run(&squeezed(100.0, length), 1)),
        bits(&run(&squeezed(100.0, 0.0), 1))
    );
    // One and two threads.
    assert_eq!(bits(&run(&squeezed(0.05, length), 2)), bits(&close));
}

/// Keeps the last checkpoint handed over.
#[derive(Default)]
struct Keep(Option<(State, DriverState)>);
impl Observer for Keep {
    fn checkpoint(&mut self, state: &State, driver: &DriverState) {
        self.0 = Some((state.clone(), driver.clone()));
    }
}

#[test]
fn a_confined_run_resumes_bit_for_bit() {
    let model = squeezed(
        0.05,
        Material::preset("glass-serge-4x3")
            .unwrap()
            .fibre
            .segment_length,
    );
    let straight = run(&model, 1);
    let mut first = model.initial_state();
    let mut keep = Keep::default();
    let stopped = ExplicitSettings {
        checkpoint_every: Some(40),
        max_steps: Some(130),
        ..settings()
    };
    assert!(
        Explicit::new(&model, stopped)
            .unwrap()
            .run(&mut first, &mut keep)
            .unwrap()
            .stopped
    );
    let (mut state, driver) = keep.0.expect("a checkpoint");
    // The clearances travel, through JSON as a checkpoint file has them
    // (no infinity there).
    assert!(driver.truss_clearance.iter().flatten().any(|c| *c < 1.0));
    let driver: DriverState =
        serde_json::from_slice(&serde_json::to_vec(&driver).unwrap()).unwrap();
    let mut resumed = Explicit::new(&model, settings()).unwrap();
    resumed.resume_from(driver);
    resumed.run(&mut state, &mut NoObserver).unwrap();
    assert_eq!(state.step, straight.step);
    assert_eq!(bits(&state), bits(&straight));
}

/// Keeps every frame's energies.
#[derive(Default)]
struct Energy(Vec<drape_time::Energies>);
impl Observer for Energy {
    fn frame(&mut self, frame: &drape_time::Frame<'_>) {
        self.0.push(*frame.energy);
    }
}

/// Tools that close on shortened yarns put energy into them (their wall
/// moves past the yarns' bow at fixed strain): booked as confinement work,
/// not shown as negative dissipation. The glass preset's resin is elastic,
/// so what the internal and confinement work do not store is the kinked
/// yarns' dashpots only, never negative.
#[test]
fn tools_closing_on_confined_yarns_do_work_that_the_balance_books() {
    let length = Material::preset("glass-serge-4x3")
        .unwrap()
        .fibre
        .segment_length;
    // 2 mm of room (the wall at 63 % shortening: free), closed to 0.05 mm
    // (the wall at 0.4 %) over the run while the strip is pushed 5 %.
    // Both close, so that the clamped edge stays between them.
    let mut model = squeezed(2.0, length);
    for (tool, up) in model.tools.iter_mut().zip([1.0, -1.0]) {
        tool.motion = ToolMotion::Displacement {
            direction: Vector3::z() * up,
            distance: 0.975,
            amplitude: Amplitude::SmoothStep { duration: 6e-4 },
        };
    }
    let mut seen = Energy::default();
    let mut state = model.initial_state();
    Explicit::new(
        &model,
        ExplicitSettings {
            frames: 12,
            ..settings()
        },
    )
    .unwrap()
    .run(&mut state, &mut seen)
    .unwrap();
    let last = seen.0.last().unwrap();
    assert!(
        last.confinement_work > 0.2 * last.strain,
        "confinement work {} of {} stored",
        last.confinement_work,
        last.strain
    );
    // The step's integration error leaves −1.0e-3 of the stored energy at
    // the end; unbooked, the confinement work would leave −0.29.
    for e in &seen.0 {
        assert!(
            e.viscous >= -5e-3 * e.strain,
            "negative dissipation {} (stored {}, internal work {}, confinement work {})",
            e.viscous,
            e.strain,
            e.internal_work,
            e.confinement_work
        );
    }
}
