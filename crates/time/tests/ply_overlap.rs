//! The explicit driver's check that a laminate's plies are not inside
//! each other: a node of the top ply pushed into the bottom ply by a
//! prescribed displacement, which the ply contact cannot undo, stops the
//! run at the first energy check past the tolerance, naming the plies,
//! the node and where, with the frames before it kept; pushed less, the
//! run completes and reports the depth it reached. A run stopped so
//! keeps the step profile of the steps it took.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use drape_contact::ContactPhase;
use drape_model::stack::PlyModel;
use drape_model::{Amplitude, BoundaryCondition, Model, Motion, State};
use drape_time::{
    Explicit, ExplicitSettings, Frame, Observer, Pass, RunError, ply_overlap_tolerance,
};
use nalgebra::Vector3;

mod common;
use common::{glass, glass_ply, glass_ply_mapped};

/// Two 40 mm glass plies of 10 mm quads, the bottom one held, the top
/// one's centre node moved down by `push` mm along a ramp over 0.01 s;
/// the centre node.
fn pushed(push: f64) -> (Model, u32) {
    let h = glass().thickness;
    let ply = |name: &str| glass_ply(name, Vector3::new(0.0, 0.0, 0.5 * h), 4);
    pushed_plies([ply("bottom"), ply("top")], push)
}

/// [`pushed`] of the plies `plies` (bottom, top), each a 5 × 5-node
/// lattice with a node at x = y = 0.
fn pushed_plies(plies: [PlyModel; 2], push: f64) -> (Model, u32) {
    let mut model = Model::stack(plies.into()).expect("stack");
    let bottom: Vec<u32> = model.plies[0].nodes.clone().collect();
    model.boundary.push(BoundaryCondition::fixed(bottom));
    let centre = model.plies[1]
        .nodes
        .clone()
        .find(|&i| model.x0[i as usize].xy().norm() < 1e-9)
        .expect("a node at the centre");
    model.boundary.push(BoundaryCondition {
        nodes: vec![centre],
        components: [false, false, true],
        motion: Motion::Displacement {
            value: Vector3::new(0.0, 0.0, -push),
            amplitude: Amplitude::Ramp { duration: 0.01 },
        },
    });
    (model, centre)
}

/// Two glass plies of 10 mm quads side by side, the bottom one 40 mm
/// square, the top one 40 × 30 mm (its corners off the bottom one's
/// outline when it is under it), the bottom one
/// held and the top one 2·h below it (past the offset h: the two are not
/// in contact) and 2.25 mm to its right, moved 10 mm to the left over
/// 0.01 s, so that its left edge slides under the bottom ply's right
/// edge, 0.25 mm under it at the check of 2.5 ms.
fn slid_under() -> Model {
    let h = glass().thickness;
    // The stack lifts the top ply by h.
    let mut model = Model::stack(vec![
        glass_ply("bottom", Vector3::new(0.0, 0.0, 0.5 * h), 4),
        glass_ply("top", Vector3::new(42.25, 0.0, -2.5 * h), 3),
    ])
    .expect("stack");
    let bottom: Vec<u32> = model.plies[0].nodes.clone().collect();
    model.boundary.push(BoundaryCondition::fixed(bottom));
    model.boundary.push(BoundaryCondition {
        nodes: model.plies[1].nodes.clone().collect(),
        components: [true, true, true],
        motion: Motion::Displacement {
            value: Vector3::new(-10.0, 0.0, 0.0),
            amplitude: Amplitude::Ramp { duration: 0.01 },
        },
    });
    model
}

/// The times of the published frames.
struct Times(Vec<f64>);
impl Observer for Times {
    fn frame(&mut self, frame: &Frame<'_>) {
        self.0.push(frame.state.time);
    }
}

fn settings() -> ExplicitSettings {
    ExplicitSettings {
        end_time: 0.01,
        frames: 20,
        ..ExplicitSettings::default()
    }
}

#[test]
fn a_ply_pushed_through_its_neighbour_stops_the_run_naming_it() {
    let h = glass().thickness;
    // The centre node's depth is 1.5·h·t/0.01: 0.075·h at the frame of
    // t = 0.5 ms, 0.15·h at the check of 1 ms, past the tolerance of a
    // tenth of the thickness (the quads' hundredth, 0.1 mm, is larger).
    let (model, centre) = pushed(1.5 * h);
    let tolerance = ply_overlap_tolerance(&model);
    assert_eq!(tolerance, 0.1 * h);
    let (error, state, times, dt) = run_until_stopped(&model);
    let RunError::PlyOverlap {
        time,
        overlap,
        tolerance: told,
        ref ply,
        ref into,
        node,
        at,
        ..
    } = error
    else {
        panic!("{error}");
    };
    assert_eq!((&**ply, &**into, node), ("top", "bottom", centre as usize));
    assert_eq!(told, tolerance);
    // At the first check after 1 ms (a step may end past it).
    assert!((0.001..0.001 + 1.01 * dt).contains(&time), "{time}");
    assert!((overlap - 150.0 * h * time).abs() < 1e-9 * h, "{overlap}");
    assert!(
        (at[2] - (1.5 * h - 150.0 * h * time)).abs() < 1e-9,
        "{at:?}"
    );
    let message = error.to_string();
    for word in [
        "node",
        "`top`",
        "inside ply `bottom`",
        "tolerance",
        "hold the stack more",
    ] {
        assert!(message.contains(word), "{message}");
    }
    // Flat faces: nothing to refine.
    assert!(!message.contains("too coarse"), "{message}");
    // Frames 0 and 0.5 ms were published; the state is the last of them.
    assert_eq!(times.len(), 2, "{times:?}");
    assert_eq!(state.time, times[1]);
}

/// The plies of [`pushed`] wrapped round a cylinder of radius 25 mm about
/// the y axis, the bottom ply's mid-surface on it and the top one's h
/// outside it, the same axis: their 10 mm faces sag L²/8R = 0.5 mm under
/// their nodes, more than half the 0.57 mm between the plies. The stop
/// says so, and what faces would do (√(4·R·h) ≈ 7.6 mm).
#[test]
fn a_ply_pushed_through_a_coarse_bend_is_told_to_refine_there() {
    let h = glass().thickness;
    let radius = 25.0;
    // Each ply's mesh wrapped before its model is built (the elements'
    // rest shape is the wrapped one), `out` from the cylinder, its pole at
    // z = h/2 as [`pushed`]'s plies: the stack lifts the top one by h
    // along the bottom one's mean normal (+z), onto the same axis.
    let wrapped = |name: &str, out: f64| {
        let r = radius + out;
        glass_ply_mapped(name, Vector3::zeros(), 4, |x| {
            // The bottom ply's angles: the top one's nodes straight out.
            let t = x.x / radius;
            Vector3::new(r * t.sin(), x.y, r * t.cos() - r + 0.5 * h)
        })
    };
    let (mut model, centre) = pushed_plies([wrapped("bottom", 0.0), wrapped("top", h)], 1.5 * h);
    // The rest of the top ply held too, and the pushed node along the
    // axis and across: only its push moves anything (a wrapped ply let go
    // springs about on the coarse bend).
    let top: Vec<u32> = model.plies[1]
        .nodes
        .clone()
        .filter(|&i| i != centre)
        .collect();
    model.boundary.push(BoundaryCondition::fixed(top));
    model.boundary.push(BoundaryCondition {
        nodes: vec![centre],
        components: [true, true, false],
        motion: Motion::Displacement {
            value: Vector3::zeros(),
            amplitude: Amplitude::Ramp { duration: 0.01 },
        },
    });
    let (error, ..) = run_until_stopped(&model);
    let RunError::PlyOverlap { ref into, .. } = error else {
        panic!("{error}");
    };
    let message = error.to_string();
    // Which ply's faces the deepest node is measured against depends on
    // round-off (the two are as deep); either bends with the cylinder.
    for word in [
        &format!("ply `{into}`'s faces there are too coarse for its bend"),
        "refine the blank where it wraps that bend",
    ] {
        assert!(message.contains(word), "{message}");
    }
    // The radius and the faces' size it gives: about the cylinder's
    // (the top ply's mid-surface lies at 25.57 mm, the dent bends it a
    // little more) and √(4·R·h) ≈ 7.6 mm.
    let number_after = |key: &str| -> f64 {
        let rest = &message[message.find(key).expect(key) + key.len()..];
        rest.split_whitespace()
            .next()
            .expect("a number")
            .parse()
            .expect("a number")
    };
    let r = number_after("a bend of radius");
    assert!((24.0..28.0).contains(&r), "{message}");
    let faces = number_after("(faces of at most");
    assert!(((4.0 * r * h).sqrt() - faces).abs() < 0.06, "{message}");
    assert!(!message.contains("hold the stack more"), "{message}");
}

#[test]
fn a_free_edge_slid_under_its_neighbour_stops_the_run() {
    // How the four-ply hemisphere's flapping free edges went through their
    // neighbours (a `m45` corner node 1.07 mm behind `p90`'s corner face
    // at t = 0.28 s, its own neighbours above it): from beside the
    // neighbour's free edge to behind its face by more than the offset,
    // which the check took for a fold and let the run complete. The
    // contact now holds a node out of the end there; this one's motion
    // is prescribed, and the check stops the run.
    let h = glass().thickness;
    let model = slid_under();
    let (error, state, times, dt) = run_until_stopped(&model);
    let RunError::PlyOverlap {
        time,
        overlap,
        ref ply,
        ref into,
        node,
        at,
        ..
    } = error
    else {
        panic!("{error}");
    };
    assert_eq!((&**ply, &**into), ("top", "bottom"));
    // A node of the top ply's left edge (x = 22.25 at the start), at the
    // first check after the edge passes x = 20 at 2.25 ms.
    assert!((model.x0[node][0] - 22.25).abs() < 1e-9, "{node}");
    assert!((0.0025..0.0025 + 1.01 * dt).contains(&time), "{time}");
    assert!((at[0] - (22.25 - 1000.0 * time)).abs() < 1e-9, "{at:?}");
    // 2·h behind the bottom's mid-surface, and in past its free end
    // (x = 20) by less than the way back to its side (the offset h and
    // those 2·h): inside by what it is past the end, the way the contact
    // puts a node out there (it cannot move this one: its motion is
    // prescribed).
    assert!(20.0 - at[0] < 3.0 * h, "{at:?}");
    assert!((overlap - (20.0 - at[0])).abs() < 1e-9, "{overlap}");
    assert!((at[2] + 1.5 * h).abs() < 1e-9, "{at:?}");
    let message = error.to_string();
    for word in ["`top`", "inside ply `bottom`"] {
        assert!(message.contains(word), "{message}");
    }
    assert_eq!(state.time, *times.last().expect("frames"));
}

/// Runs `model` until the driver stops it: the error, the state it kept,
/// the times of the frames it published and the stable step.
fn run_until_stopped(model: &Model) -> (RunError, State, Vec<f64>, f64) {
    let mut state = model.initial_state();
    let mut times = Times(Vec::new());
    let mut driver = Explicit::new(model, settings()).expect("driver");
    let dt = driver.stable_time_step(&model.x0);
    let error = driver.run(&mut state, &mut times).expect_err("stopped");
    (error, state, times.0, dt)
}

/// A profile clock that advances by a microsecond at each reading: every
/// timed interval is at least one tick, whatever the machine's load.
fn ticks() -> Duration {
    static TICKS: AtomicU64 = AtomicU64::new(0);
    Duration::from_micros(TICKS.fetch_add(1, Ordering::Relaxed))
}

#[test]
fn a_run_stopped_by_a_ply_overlap_keeps_its_step_profile() {
    let h = glass().thickness;
    let (model, _) = pushed(1.5 * h);
    let mut state = model.initial_state();
    let mut driver = Explicit::new(&model, settings()).expect("driver");
    driver.enable_profile(ticks);
    let error = driver
        .run(&mut state, &mut Times(Vec::new()))
        .expect_err("stopped");
    let RunError::PlyOverlap { step, .. } = error else {
        panic!("{error}");
    };
    let profile = driver.profile().expect("profiled");
    // Every step up to the check that stopped it, from the start.
    assert!(step > 10, "{step}");
    assert_eq!(profile.steps, step);
    assert!(profile.step_time() > Duration::ZERO);
    // The ply pass's phase is in it, within the contact pass, within the
    // steps' time.
    let plies = profile.contact_time(ContactPhase::Plies);
    assert!(plies > Duration::ZERO);
    assert!(plies <= profile.time(Pass::Contact));
    let passes: Duration = Pass::ALL.iter().map(|&p| profile.time(p)).sum();
    assert!(passes <= profile.total, "{passes:?} > {:?}", profile.total);
}

#[test]
fn a_ply_pushed_within_the_tolerance_completes_and_reports_its_peak() {
    let h = glass().thickness;
    let (model, _) = pushed(0.05 * h);
    let mut state = model.initial_state();
    let mut driver = Explicit::new(&model, settings()).expect("driver");
    let summary = driver
        .run(&mut state, &mut Times(Vec::new()))
        .expect("completes");
    // Past the 1 % of the thickness a formed laminate is held to: the run
    // warns where (flat plies: no word of their bend).
    let warned: Vec<&String> = summary
        .warnings
        .iter()
        .filter(|w| w.starts_with("the plies were inside each other"))
        .collect();
    assert_eq!(warned.len(), 1, "{:?}", summary.warnings);
    for word in [
        "5.0 % of the thinnest ply's",
        "ply `top`",
        "in ply `bottom`",
    ] {
        assert!(warned[0].contains(word), "{}", warned[0]);
    }
    assert!(!warned[0].contains("too coarse"), "{}", warned[0]);
    let peaks = driver
        .contact()
        .and_then(|c| c.plies())
        .expect("plies")
        .overlap_peaks();
    // The centre node at the end: 0.05·h deep.
    assert_eq!(peaks.len(), 1);
    assert!((peaks[0] - 0.05 * h).abs() < 1e-9 * h, "{peaks:?}");
}
