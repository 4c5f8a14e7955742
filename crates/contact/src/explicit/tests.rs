use super::*;
use crate::surface::Surface;
use crate::tool::Amplitude;

fn floor(friction: f64) -> Tool {
    Tool {
        name: "floor".into(),
        surface: Surface::plane(Vector3::zeros(), Vector3::z()).unwrap(),
        motion: ToolMotion::Fixed,
        friction,
    }
}

fn settings(offset: f64) -> ContactSettings {
    ContactSettings {
        offset,
        ..ContactSettings::default()
    }
}

/// A pass that remembers its projections (and skips the nodes that
/// cannot have reached the tool) against one rebuilt every step (which
/// projects every candidate): nodes falling at different speeds onto a
/// rising sphere, some far, some arriving, some pressed in, must give
/// the same corrections, forces and statuses at every step, bit for bit.
#[test]
fn skipping_far_nodes_changes_nothing() {
    let ball = || Tool {
        name: "ball".into(),
        surface: Surface::sphere(Vector3::zeros(), 10.0).unwrap(),
        motion: ToolMotion::Displacement {
            direction: Vector3::z(),
            distance: 3.0,
            amplitude: Amplitude::Ramp { duration: 1.0 },
        },
        friction: 0.2,
    };
    let margin = ContactSettings {
        offset: 0.1,
        margin: 50.0,
        ..ContactSettings::default()
    };
    let n = 40;
    let mut x: Vec<Vector3<f64>> = (0..n)
        .map(|i| {
            let a = i as f64 * 0.37;
            Vector3::new(6.0 * a.cos(), 6.0 * a.sin(), 10.5 + 0.4 * i as f64)
        })
        .collect();
    let speed: Vec<f64> = (0..n).map(|i| 0.05 + 0.01 * (i % 7) as f64).collect();
    let mass = vec![1e-6; n];
    let movable = vec![true; n];
    let mut remembering = ExplicitContact::new(vec![ball()], n, margin);
    let mut tool_state = ToolState::default();
    let mut in_contact = 0;
    let dt = 0.01;
    for k in 1..=100 {
        let t_new = k as f64 * dt;
        let mut v: Vec<Vector3<f64>> = speed
            .iter()
            .map(|s| Vector3::new(0.0, 0.0, -s / dt))
            .collect();
        let mut x_pred: Vec<Vector3<f64>> = x.iter().zip(&v).map(|(p, w)| p + w * dt).collect();
        let (mut x_ref, mut v_ref) = (x_pred.clone(), v.clone());
        let mut fresh = ExplicitContact::new(vec![ball()], n, margin);
        fresh.tool_state[0] = tool_state;
        fresh.friction_dissipation = remembering.friction_dissipation;
        remembering
            .enforce(&mut x_pred, &mut v, &mass, &movable, t_new, dt)
            .unwrap();
        fresh
            .enforce(&mut x_ref, &mut v_ref, &mass, &movable, t_new, dt)
            .unwrap();
        assert_eq!(x_pred, x_ref, "positions at step {k}");
        assert_eq!(v, v_ref, "velocities at step {k}");
        assert_eq!(remembering.force, fresh.force, "forces at step {k}");
        assert_eq!(remembering.status, fresh.status, "statuses at step {k}");
        in_contact += remembering
            .status
            .iter()
            .filter(|s| **s != ContactStatus::Open)
            .count();
        tool_state = remembering.tool_state[0];
        x = x_pred;
    }
    // The nodes did arrive, and many projections were skipped.
    assert!(in_contact > 100, "{in_contact}");
    let skipped = remembering.scratch.projected[0]
        .iter()
        .filter(|p| !p.fresh)
        .count();
    assert!(skipped > 0);
}

/// The remembering pass against one rebuilt every step (no skipped
/// node, no warm start) on a moving open mesh: nodes far, arriving,
/// pressed, sliding across the triangles' edges, beside and over the
/// open rim, at different speeds (one of them passes behind the rim, a
/// contact fault). Corrections, forces, statuses and faults must be the
/// same at every step, bit for bit.
#[test]
fn skipping_and_warm_starts_on_an_open_mesh_change_nothing() {
    let sheet = || Tool {
        name: "sheet".into(),
        surface: crate::mesh_near::tests::bumpy_sheet(12, 5.0),
        motion: ToolMotion::Displacement {
            direction: Vector3::new(0.3, -0.2, 1.0).normalize(),
            distance: 4.0,
            amplitude: Amplitude::Ramp { duration: 2.0 },
        },
        friction: 0.2,
    };
    let height = |x: f64, y: f64| 3.0 * (x / 10.0).sin() * (y / 12.0).cos();
    let margin = ContactSettings {
        offset: 0.1,
        margin: 50.0,
        ..ContactSettings::default()
    };
    // A spiral of nodes over the sheet and out past its rim (at ±30),
    // at heights from 0.3 to 12 mm, some far above (40 mm).
    let n = 120;
    let mut x: Vec<Vector3<f64>> = (0..n)
        .map(|i| {
            let a = i as f64 * 0.7;
            let r = 1.0 + 0.3 * i as f64;
            let (px, py) = (r * a.cos(), r * a.sin());
            let h = if i % 5 == 0 {
                40.0
            } else {
                0.3 + 0.1 * (i % 17) as f64 * (1.0 + (i % 3) as f64)
            };
            Vector3::new(
                px,
                py,
                height(px.clamp(-30.0, 30.0), py.clamp(-30.0, 30.0)) + h,
            )
        })
        .collect();
    // Falling at 0.01 … 0.07 mm per step, sliding sideways at up to
    // 0.05 mm per step (a cell is 5 mm).
    let step_of = |i: usize| {
        Vector3::new(
            0.05 * ((i % 11) as f64 / 5.0 - 1.0),
            0.04 * ((i % 7) as f64 / 3.0 - 1.0),
            -(0.01 + 0.01 * (i % 7) as f64),
        )
    };
    let mass = vec![1e-6; n];
    let movable = vec![true; n];
    let mut remembering = ExplicitContact::new(vec![sheet()], n, margin);
    let mut tool_state = ToolState::default();
    let (mut in_contact, mut skipped, mut faults) = (0, 0, 0);
    let dt = 0.01;
    for k in 1..=300 {
        let t_new = k as f64 * dt;
        let mut v: Vec<Vector3<f64>> = (0..n).map(|i| step_of(i) / dt).collect();
        let mut x_pred: Vec<Vector3<f64>> = x.iter().zip(&v).map(|(p, w)| p + w * dt).collect();
        let (mut x_ref, mut v_ref) = (x_pred.clone(), v.clone());
        let mut fresh = ExplicitContact::new(vec![sheet()], n, margin);
        fresh.tool_state[0] = tool_state;
        fresh.friction_dissipation = remembering.friction_dissipation;
        let a = remembering.enforce(&mut x_pred, &mut v, &mass, &movable, t_new, dt);
        let b = fresh.enforce(&mut x_ref, &mut v_ref, &mass, &movable, t_new, dt);
        assert_eq!(a, b, "step {k}");
        faults += usize::from(a.is_err());
        assert_eq!(x_pred, x_ref, "positions at step {k}");
        assert_eq!(v, v_ref, "velocities at step {k}");
        assert_eq!(remembering.force, fresh.force, "forces at step {k}");
        assert_eq!(remembering.status, fresh.status, "statuses at step {k}");
        in_contact += remembering
            .status
            .iter()
            .filter(|s| **s != ContactStatus::Open)
            .count();
        skipped += remembering.scratch.projected[0]
            .iter()
            .filter(|p| !p.fresh)
            .count();
        tool_state = remembering.tool_state[0];
        x = x_pred;
    }
    // The nodes did arrive and slide, one crossed the cut behind the
    // rim, and many projections were skipped.
    assert!(faults >= 1, "{faults}");
    assert!(in_contact > 5_000, "{in_contact}");
    assert!(skipped > 5_000, "{skipped}");
    let sliding = remembering
        .status
        .iter()
        .filter(|s| **s == ContactStatus::Slip)
        .count();
    assert!(sliding > 10, "{sliding}");
}

/// A node going round an open mesh's rim, 5 mm from it (far beyond the
/// contact's reach), crosses the cut behind the rim: the pass that
/// skips far nodes must not skip it, and reports the same fault at the
/// same step as a pass that projects every node.
#[test]
fn a_far_node_rounding_an_open_rim_is_not_skipped() {
    let sheet = || Tool {
        name: "sheet".into(),
        surface: crate::mesh_near::tests::bumpy_sheet(12, 5.0),
        motion: ToolMotion::Fixed,
        friction: 0.0,
    };
    let rim = Vector3::new(30.0, 2.5, 3.0 * 3f64.sin() * (2.5f64 / 12.0).cos());
    let at = |deg: f64| {
        let a = deg.to_radians();
        rim + Vector3::new(a.cos(), 0.0, a.sin()) * 5.0
    };
    let mut remembering = ExplicitContact::new(vec![sheet()], 1, settings(0.1));
    let dt = 1e-3;
    let mut faulted = None;
    for k in 1..=100 {
        let deg = 60.0 - 2.0 * k as f64;
        let mut x = vec![at(deg)];
        let mut v = vec![(at(deg) - at(deg + 2.0)) / dt];
        let (mut x_ref, mut v_ref) = (x.clone(), v.clone());
        let mut fresh = ExplicitContact::new(vec![sheet()], 1, settings(0.1));
        let t = k as f64 * dt;
        let a = remembering.enforce(&mut x, &mut v, &[1e-6], &[true], t, dt);
        let b = fresh.enforce(&mut x_ref, &mut v_ref, &[1e-6], &[true], t, dt);
        assert_eq!(a, b, "step {k}");
        if let Err(fault) = a {
            assert!(matches!(fault.kind, FaultKind::GapJump { .. }), "{fault}");
            faulted = Some(deg);
            break;
        }
    }
    // Behind the rim, where the sheet's back normal points (106° below
    // the outward horizontal).
    let deg = faulted.expect("a fault");
    assert!((-110.0..-100.0).contains(&deg), "{deg}");
}

#[test]
fn the_force_is_the_one_of_the_velocity_update_for_any_step() {
    // A node at rest on the floor under an acceleration a: the predictor
    // moves it a·τ·Δt into the floor; whatever Δt and Δt_mean (the first
    // step has Δt_mean = Δt/2, the last one is shortened) and the
    // damping, the contact force is m·a.
    let (m, a, offset) = (2e-6, 5000.0, 0.1);
    for (dt, dt_mean, damping) in [(1e-4, 5e-5, 0.0), (3e-5, 6.5e-5, 0.0), (1e-4, 1e-4, 800.0)] {
        let mut contact = ExplicitContact::new(vec![floor(0.0)], 1, settings(offset));
        let c2 = 1.0 / (1.0 + 0.5 * damping * dt_mean);
        let mut v = vec![Vector3::new(0.0, 0.0, -a * dt_mean * c2)];
        let mut x = vec![Vector3::new(0.0, 0.0, offset) + v[0] * dt];
        let step = StepTimes {
            t_new: dt,
            dt,
            dt_mean,
            damping,
        };
        contact
            .enforce_step(&mut x, &mut v, &[m], &[true], &step)
            .unwrap();
        assert!(
            (contact.force[0].z - m * a).abs() < 1e-9 * m * a,
            "{dt} {dt_mean}: {}",
            contact.force[0].z
        );
        assert!((x[0].z - offset).abs() < 1e-15 && v[0].z.abs() < 1e-12);
    }
}

/// A frictionless holder: a plane at height `z` facing down, pushed
/// down by `force` (N), of `mass` (t).
fn pressing_plane(z: f64, force: f64, mass: f64) -> Tool {
    Tool {
        name: "holder".into(),
        surface: Surface::plane(Vector3::new(0.0, 0.0, z), -Vector3::z()).unwrap(),
        motion: ToolMotion::Force {
            direction: -Vector3::z(),
            force,
            amplitude: Amplitude::Constant,
            mass,
        },
        friction: 0.0,
    }
}

#[test]
fn a_holder_landing_on_the_fabric_gets_its_momentum_back_as_impulse() {
    // A force-driven holder moving down at v₀ lands on a node resting on
    // the floor and stops there in one step. The force sampled at that
    // step is far from F (the holder's momentum goes into it); the
    // impulse is what balances the holder's momentum: over the steps,
    // M·(v − v₀) = Σ F·Δt_mean − impulse.
    let (m, f, big_m, offset, dt) = (1e-6, 3.0, 1e-4, 0.1, 1e-5);
    let v0 = 1.0;
    let holder = pressing_plane(2.0 * offset + 2.5 * v0 * dt, f, big_m);
    let mut contact = ExplicitContact::new(vec![floor(0.0), holder], 1, settings(offset));
    contact.tool_state[1].velocity = v0;
    let mut x = vec![Vector3::new(0.0, 0.0, offset)];
    let mut v = vec![Vector3::zeros()];
    let mut largest: f64 = 0.0;
    let steps = 8;
    for step in 1..=steps {
        contact
            .enforce(&mut x, &mut v, &[m], &[true], step as f64 * dt, dt)
            .unwrap();
        largest = largest.max(contact.tool_force[1]);
    }
    let state = contact.tool_state[1];
    assert!(
        state.velocity.abs() < 1e-9,
        "the holder rests: {}",
        state.velocity
    );
    // M·v₀/Δt alone is 3⅓·F.
    assert!(largest > 4.0 * f, "the landing's sampled force {largest} N");
    let balance = big_m * (state.velocity - v0) - (f * steps as f64 * dt - state.impulse);
    assert!(
        balance.abs() < 1e-12 * big_m * v0,
        "momentum {} N·s, impulse {} N·s",
        big_m * (state.velocity - v0),
        state.impulse
    );
}

#[test]
fn a_node_pinched_by_a_force_driven_holder_is_held_between_both_tools() {
    // A node on the floor under a holder plane pushed down by F: the
    // holder's correction alone would push the node into the floor; the
    // floor's constraint joins the solve, both tools carry F and the
    // node and the holder stay where they are.
    let (m, f, big_m, offset, dt) = (1e-6, 3.0, 1e-4, 0.1, 1e-5);
    let holder = pressing_plane(2.0 * offset, f, big_m);
    let mut contact = ExplicitContact::new(vec![floor(0.0), holder], 1, settings(offset));
    let mut x = vec![Vector3::new(0.0, 0.0, offset)];
    let mut v = vec![Vector3::zeros()];
    for step in 1..=3 {
        contact
            .enforce(&mut x, &mut v, &[m], &[true], step as f64 * dt, dt)
            .unwrap();
        assert!((x[0].z - offset).abs() < 1e-12, "node at {}", x[0].z);
        assert!(contact.tool_state[1].displacement.abs() < 1e-12);
        assert!(
            (contact.tool_force[0] - f).abs() < 1e-9 * f,
            "{:?}",
            contact.tool_force
        );
        assert!(
            (contact.tool_force[1] - f).abs() < 1e-9 * f,
            "{:?}",
            contact.tool_force
        );
    }
}

#[test]
fn a_node_crossing_behind_an_open_rim_is_a_fault_not_pushed_out() {
    // A flat open ring facing down (the fabric below), its free inner
    // end at r = 95. A node 1 mm above the face's plane in the opening
    // drifts 1 µm outwards, across the cut behind the free end: its gap
    // jumps from +1 to −1 mm. Pushed out it would jump 1 mm down in one
    // step; the guard refuses the step instead.
    let ring = Tool {
        name: "ring".into(),
        surface: Surface::revolution(
            Vector3::zeros(),
            vec![crate::ProfileSegment::Line {
                from: [250.0, 0.0],
                to: [95.0, 0.0],
            }],
        )
        .unwrap(),
        motion: ToolMotion::Fixed,
        friction: 0.0,
    };
    let (dt, offset) = (1e-3, 0.1);
    let mut contact = ExplicitContact::new(vec![ring], 1, settings(offset));
    let v0 = Vector3::new(1.0, 0.0, 0.0);
    let mut x = vec![Vector3::new(95.0 - 0.5e-3, 0.0, 1.0) + v0 * dt];
    let mut v = vec![v0];
    let before = (x.clone(), v.clone());
    let fault = contact
        .enforce(&mut x, &mut v, &[1e-6], &[true], dt, dt)
        .unwrap_err();
    assert_eq!((fault.node, fault.tool), (0, 0));
    assert!((fault.gap + 1.0 + offset).abs() < 1e-9, "{}", fault.gap);
    assert!((fault.node_travel - 1e-3).abs() < 1e-12 && fault.tool_travel == 0.0);
    let FaultKind::GapJump { previous_gap } = fault.kind else {
        panic!("{fault:?}")
    };
    assert!((previous_gap - (1.0 - offset)).abs() < 1e-6);
    assert_eq!((x, v), before, "nothing is corrected");
    let message = fault.to_string();
    assert!(
        message.contains("node 0") && message.contains("`ring`"),
        "{message}"
    );
    // The same drift in front of the face (below it) is an ordinary
    // contact: the node is within its travel of the face.
    let mut x = vec![Vector3::new(120.0, 0.0, -offset + 0.5e-3)];
    let mut v = vec![Vector3::new(0.0, 0.0, 1.0)];
    assert!(
        contact
            .enforce(&mut x, &mut v, &[1e-6], &[true], 2.0 * dt, dt)
            .is_ok()
    );
    assert!((x[0].z + offset).abs() < 1e-12);
}

#[test]
fn a_tool_forced_through_the_fabric_in_one_step_is_a_fault() {
    // A plate coming down on a node at rest by 5 mm in one step, far
    // more than the fabric's thickness (0.2 mm): with the limit the
    // step is refused; without it the node would be thrown 5 mm.
    let plate = |limit: f64| {
        let tool = Tool {
            name: "plate".into(),
            surface: Surface::plane(Vector3::new(0.0, 0.0, 0.2), -Vector3::z()).unwrap(),
            motion: ToolMotion::Displacement {
                direction: -Vector3::z(),
                distance: 5.0,
                amplitude: Amplitude::Ramp { duration: 1e-3 },
            },
            friction: 0.0,
        };
        let settings = ContactSettings {
            max_travel: limit,
            ..settings(0.1)
        };
        ExplicitContact::new(vec![tool], 1, settings)
    };
    let (mut x, mut v) = (vec![Vector3::zeros()], vec![Vector3::zeros()]);
    let fault = plate(0.2)
        .enforce(&mut x, &mut v, &[1e-6], &[true], 1e-3, 1e-3)
        .unwrap_err();
    assert!(matches!(fault.kind, FaultKind::Overrun { limit } if limit == 0.2));
    assert!((fault.tool_travel - 5.0).abs() < 1e-12 && fault.node_travel == 0.0);
    assert!((fault.gap + 4.9).abs() < 1e-12);
    // The message says what a user can change.
    assert!(fault.to_string().contains("less mass scaling"), "{fault}");
    assert_eq!(x[0], Vector3::zeros());
    // Absorbed when nothing limits the travel.
    plate(f64::INFINITY)
        .enforce(&mut x, &mut v, &[1e-6], &[true], 1e-3, 1e-3)
        .unwrap();
    assert!((x[0].z + 4.9).abs() < 1e-12);
}

#[test]
fn a_node_thrown_into_a_resting_tool_is_told_apart_from_a_tool_forced_through() {
    // A fixed floor at z = 0 and a node that arrives 0.45 mm into it
    // after a step of 1 mm: the fabric threw it, the tool did not move.
    let settings = ContactSettings {
        max_travel: 0.5,
        ..settings(0.1)
    };
    let mut contact = ExplicitContact::new(vec![floor(0.0)], 1, settings);
    let dt = 1e-3;
    let mut x = vec![Vector3::new(0.0, 0.0, -0.45)];
    let mut v = vec![Vector3::new(0.0, 0.0, -1.0 / dt)];
    let fault = contact
        .enforce(&mut x, &mut v, &[1e-6], &[true], dt, dt)
        .unwrap_err();
    assert!(matches!(fault.kind, FaultKind::Overrun { limit } if limit == 0.5));
    assert!((fault.node_travel - 1.0).abs() < 1e-12 && fault.tool_travel == 0.0);
    let message = fault.to_string();
    assert!(message.contains("the fabric threw the node"), "{message}");
    assert!(!message.contains("forced through"), "{message}");
    // The tool-driven case keeps its advice (the test above).
}
