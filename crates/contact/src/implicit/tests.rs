use super::*;
use crate::surface::Surface;
use crate::tool::Amplitude;
use nalgebra::{DMatrix, DVector, Matrix3};

const OFFSET: f64 = 0.1;

/// A 10 ms increment of the trapezoidal rule (β = ¼, γ = ½, no Bossak
/// shift), the tests' time step.
const TRAPEZOIDAL_STEP: Increment = Increment {
    t_new: 0.01,
    h: 0.01,
    beta: 0.25,
    gamma: 0.5,
    alpha_m: 0.0,
};

fn plane(name: &str, z: f64, up: bool, friction: f64, motion: ToolMotion) -> Tool {
    let normal = if up { Vector3::z() } else { -Vector3::z() };
    Tool {
        name: name.into(),
        surface: Surface::plane(Vector3::new(0.0, 0.0, z), normal).unwrap(),
        motion,
        friction,
    }
}

/// A symmetric positive definite K of size n, coupling every dof.
fn stiffness(n: usize, seed: u64) -> DMatrix<f64> {
    let mut state = seed;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let b = DMatrix::from_fn(n, n, |_, _| next());
    &b.transpose() * &b + DMatrix::identity(n, n) * 0.5
}

/// The reference: the saddle-point system [K̃ −Cᵀ; C D] (D the rows'
/// compliances, zero but for regularised stick rows) solved directly
/// for every subset of closed normal rows (tangential rows always
/// closed), keeping the one that satisfies the complementarity
/// conditions. K̃ includes the tool unknowns.
fn direct(
    k: &DMatrix<f64>,
    rhs: &DVector<f64>,
    c: &[(DVector<f64>, f64, bool, f64)],
) -> (DVector<f64>, Vec<f64>) {
    let normals: Vec<usize> = (0..c.len()).filter(|&i| c[i].2).collect();
    let n = k.nrows();
    let mut found = None;
    for mask in 0u32..(1 << normals.len()) {
        let closed: Vec<usize> = (0..c.len())
            .filter(|&i| {
                !c[i].2 || mask & (1 << normals.iter().position(|&j| j == i).unwrap()) != 0
            })
            .collect();
        let m = closed.len();
        let mut a = DMatrix::zeros(n + m, n + m);
        a.view_mut((0, 0), (n, n)).copy_from(k);
        let mut b = DVector::zeros(n + m);
        b.rows_mut(0, n).copy_from(rhs);
        for (j, &i) in closed.iter().enumerate() {
            for q in 0..n {
                a[(q, n + j)] = -c[i].0[q];
                a[(n + j, q)] = c[i].0[q];
            }
            b[n + j] = -c[i].1;
            a[(n + j, n + j)] = c[i].3;
        }
        // Dependent rows (a node between two tools and the holder on
        // it closed together) have no unique multipliers: skip them.
        let sv = a.clone().svd(false, false).singular_values;
        if sv.min() <= 1e-12 * sv.max() {
            continue;
        }
        let sol = a.lu().solve(&b).expect("regular saddle point");
        let dx = sol.rows(0, n).into_owned();
        let mut lambda = vec![0.0; c.len()];
        for (j, &i) in closed.iter().enumerate() {
            lambda[i] = sol[n + j];
        }
        let ok = normals.iter().all(|&i| {
            let gap = c[i].0.dot(&dx) + c[i].1;
            lambda[i] >= -1e-12 && gap >= -1e-12
        });
        if ok {
            assert!(found.is_none(), "two active sets satisfy the conditions");
            found = Some((dx, lambda));
        }
    }
    found.expect("an active set")
}

/// Five nodes over a floor (some inside it) and, optionally, a
/// force-driven holder over two of them; some pairs sticking from a
/// last increment. Compares the condensed solution with the direct
/// one. With `springs`, the regularised stick rows are springs in K̂
/// (the driver's way, [`ImplicitContact::set_springs_in_tangent`]);
/// the reference keeps them as rows.
fn compare(
    with_holder: bool,
    friction: f64,
    elastic_slip: f64,
    seed: u64,
    preconditioned: bool,
    springs: bool,
) {
    let heights = [0.01, -0.02, 0.0, 0.05, -0.01];
    let x: Vec<Vector3<f64>> = heights
        .iter()
        .enumerate()
        .map(|(i, h)| Vector3::new(i as f64, 0.3 * i as f64, OFFSET + h))
        .collect();
    let nodes = x.len();
    let mut tools = vec![plane("floor", 0.0, true, friction, ToolMotion::Fixed)];
    let (mass, force) = (1e-4, 3.0);
    if with_holder {
        tools.push(plane(
            "holder",
            2.0 * OFFSET + 0.03,
            false,
            0.0,
            ToolMotion::Force {
                direction: -Vector3::z(),
                force,
                amplitude: Amplitude::Constant,
                mass,
            },
        ));
    }
    let settings = ImplicitContactSettings {
        offset: OFFSET,
        margin: 0.5,
        tolerance: 1e-13,
        max_iterations: 1000,
        elastic_slip,
        square_friction_leans: false,
    };
    let mut contact = ImplicitContact::new(tools.clone(), nodes, settings);
    contact.set_springs_in_tangent(springs);
    // Nodes 0 and 2 stuck at the last increment, with a tangential
    // force (where a regularised stick's spring starts).
    let stick_n = Vector3::new(0.1, -0.05, 0.0);
    let carried: Vec<CarriedPair> = [0u32, 2]
        .iter()
        .map(|&node| CarriedPair {
            tool: 0,
            node,
            lambda: 1.0,
            stick: stick_n.into(),
            slip_direction: [0.0; 3],
            friction: Friction::Stick,
        })
        .collect();
    contact.restore(
        carried,
        &vec![ToolState::default(); tools.len()],
        &vec![0.0; tools.len()],
        0.0,
    );
    let inc = TRAPEZOIDAL_STEP;
    contact.begin(&x, &[true; 5], inc);
    // Slip of the last increment: the nodes moved from x_n.
    let x_n: Vec<Vector3<f64>> = x
        .iter()
        .enumerate()
        .map(|(i, p)| p - Vector3::new(0.002 * i as f64, -0.001, 0.0))
        .collect();
    contact.linearise(&x, &x_n);
    let n = 3 * nodes;
    let k = stiffness(n, seed);
    let mut r: Vec<f64> = (0..n)
        .map(|i| ((i * 37 + 11) % 17) as f64 * 0.3 - 2.4)
        .collect();
    // Node 3 pulled up hard: its unconstrained solution leaves the
    // floor, so its contact must stay open.
    r[3 * 3 + 2] = 50.0;
    // K̂ factorised with the springs in it, as the driver does.
    let mut k_solved = k.clone();
    let mut spring_count = 0;
    contact.add_spring_stiffness(|i, b| {
        spring_count += 1;
        let mut view = k_solved.view_mut((3 * i, 3 * i), (3, 3));
        view += b;
    });
    let regularised = friction > 0.0 && elastic_slip > 0.0;
    assert_eq!(
        spring_count,
        if springs && regularised { 4 } else { 0 },
        "two stuck nodes, two tangential springs each"
    );
    let chol = k_solved.clone().cholesky().unwrap();
    let mut solves = 0usize;
    let mut solve = |w: &mut [f64]| {
        solves += 1;
        let z = chol.solve(&DVector::from_column_slice(w));
        w.copy_from_slice(z.as_slice());
    };
    let mut dx = vec![0.0; n];
    let block = |i: usize| Matrix3::from_fn(|a, b| k_solved[(3 * i + a, 3 * i + b)]);
    let before = contact.solve_totals();
    let stats = if preconditioned {
        contact.solve_preconditioned(&r, &mut solve, Some(&block), &mut dx)
    } else {
        contact.solve(&r, &mut solve, &mut dx)
    }
    .unwrap();
    assert_eq!(
        stats.iterations + 1,
        solves,
        "one solve per product, plus K̂⁻¹·r"
    );
    let totals = contact.solve_totals();
    assert_eq!(
        (
            totals.iterations - before.iterations,
            totals.cg_steps - before.cg_steps
        ),
        (stats.iterations, stats.cg_steps),
        "the run's totals add this solve's counts"
    );
    // The direct reference, with the tool unknowns appended.
    let free_tools: Vec<usize> = (0..tools.len())
        .filter(|&t| tools[t].is_force_driven())
        .collect();
    let big = n + free_tools.len();
    let mut kt = DMatrix::zeros(big, big);
    kt.view_mut((0, 0), (n, n)).copy_from(&k);
    let mut rhs = DVector::zeros(big);
    rhs.rows_mut(0, n)
        .copy_from(&DVector::from_column_slice(&r));
    for (j, _) in free_tools.iter().enumerate() {
        kt[(n + j, n + j)] = mass * inc.mass_factor();
        rhs[n + j] = force;
    }
    let mut rows: Vec<(DVector<f64>, f64, bool, f64)> = Vec::new();
    let mut owners = Vec::new();
    for (t, tool) in tools.iter().enumerate() {
        for (i, p) in x.iter().enumerate() {
            let q = tool.project(p, 0.0);
            if q.gap - OFFSET >= settings.margin {
                continue;
            }
            let mut row = DVector::zeros(big);
            for c in 0..3 {
                row[3 * i + c] = q.normal[c];
            }
            if let Some(j) = free_tools.iter().position(|&f| f == t) {
                row[n + j] = -q.normal.dot(&tool.motion.direction());
            }
            rows.push((row, q.gap - OFFSET, true, 0.0));
            owners.push((t, i, None));
            if friction > 0.0 && t == 0 && (i == 0 || i == 2) {
                let s = x[i] - x_n[i];
                // t·(s + Δx) + (λ_t − t·f_n)/k_t = 0, k_t = μ·λ_N/δ
                // with the carried λ_N = 1.
                let compliance = elastic_slip / friction;
                for (k, e) in [Vector3::x(), Vector3::y()].iter().enumerate() {
                    let mut row = DVector::zeros(big);
                    for c in 0..3 {
                        row[3 * i + c] = e[c];
                    }
                    let target = e.dot(&s) - compliance * e.dot(&stick_n);
                    rows.push((row, target, false, compliance));
                    owners.push((t, i, Some(k)));
                }
            }
        }
    }
    let (dx_ref, lambda_ref) = direct(&kt, &rhs, &rows);
    let scale = dx_ref.amax();
    for q in 0..n {
        assert!(
            (dx[q] - dx_ref[q]).abs() <= 1e-8 * scale,
            "Δx[{q}]: {} vs {}",
            dx[q],
            dx_ref[q]
        );
    }
    for (j, &t) in free_tools.iter().enumerate() {
        assert!((contact.tool_step[t] - dx_ref[n + j]).abs() <= 1e-8 * scale);
    }
    let lscale = lambda_ref.iter().fold(0.0f64, |m, l| m.max(l.abs()));
    let mut open = 0;
    for (k, &(t, i, tangent)) in owners.iter().enumerate() {
        let pair = contact
            .pairs
            .iter()
            .find(|p| p.tool as usize == t && p.node as usize == i)
            .expect("pair");
        let computed = match tangent {
            None => pair.lambda,
            Some(c) => pair.stick[c],
        };
        assert!(
            (computed - lambda_ref[k]).abs() <= 1e-8 * lscale,
            "λ of ({t}, {i}, {tangent:?}): {computed} vs {}",
            lambda_ref[k]
        );
        if tangent.is_none() && lambda_ref[k] == 0.0 {
            open += 1;
            assert_eq!(pair.lambda, 0.0);
        }
    }
    if with_holder {
        let held = owners
            .iter()
            .zip(&lambda_ref)
            .any(|(o, l)| o.0 == 1 && *l > 0.0);
        assert!(held, "the holder rests on a node");
    }
    if friction > 0.0 {
        let stuck = owners
            .iter()
            .zip(&lambda_ref)
            .any(|(o, l)| o.2.is_some() && l.abs() > 0.0);
        assert!(stuck, "a stick row carries a force");
    }
    // Node 3's floor contact is open in both.
    let k3 = owners.iter().position(|o| *o == (0, 3, None)).unwrap();
    assert_eq!(lambda_ref[k3], 0.0);
    assert!(open >= 1);
}

/// A node pressed on a floor with μ = 0.3, slipping at tₙ with its
/// friction force along +x, has moved `dx` along x in the increment.
/// Returns the pass after `update_friction(reversal)` and the number
/// of changes.
fn slipping_node(dx: f64, reversal: f64) -> (ImplicitContact, usize) {
    slipping_node_regularised(Vector3::new(dx, 0.0, 0.0), reversal, 0.0)
}

/// [`slipping_node`] moved by `d` in the floor's plane, with a
/// regularised stick of `elastic_slip` (mm; 0: rigid).
fn slipping_node_regularised(
    d: Vector3<f64>,
    reversal: f64,
    elastic_slip: f64,
) -> (ImplicitContact, usize) {
    let (mut contact, x) =
        pressed_on_floor([0.0; 3], [1.0, 0.0, 0.0], Friction::Slip, d, elastic_slip);
    let changes = contact.update_friction(&x, reversal);
    (contact, changes)
}

/// A node pressed with 2 N on a floor with μ = 0.3, carried from tₙ
/// with `stick` force, `slip_direction` and `friction`, moved by `d` in
/// the increment: the pass begun and linearised there (regularised
/// stick of `elastic_slip`, mm; 0: rigid), and the positions.
fn pressed_on_floor(
    stick: [f64; 3],
    slip_direction: [f64; 3],
    friction: Friction,
    d: Vector3<f64>,
    elastic_slip: f64,
) -> (ImplicitContact, Vec<Vector3<f64>>) {
    let floor = plane("floor", 0.0, true, 0.3, ToolMotion::Fixed);
    let settings = ImplicitContactSettings {
        offset: OFFSET,
        margin: 0.5,
        tolerance: 1e-13,
        max_iterations: 100,
        elastic_slip,
        square_friction_leans: false,
    };
    let mut contact = ImplicitContact::new(vec![floor], 1, settings);
    let carried = vec![CarriedPair {
        tool: 0,
        node: 0,
        lambda: 2.0,
        stick,
        slip_direction,
        friction,
    }];
    contact.restore(carried, &[ToolState::default()], &[0.0], 0.0);
    let x_n = vec![Vector3::new(0.0, 0.0, OFFSET)];
    let x = vec![x_n[0] + d];
    contact.begin(&x, &[true], TRAPEZOIDAL_STEP);
    contact.linearise(&x, &x_n);
    (contact, x)
}

#[test]
fn a_settled_slip_sticks_again_only_beyond_the_band() {
    // Running along its friction force by 1e-3 mm reverses the slip
    // when no band is given...
    let (contact, changes) = slipping_node(1e-3, 0.0);
    assert_eq!(changes, 1);
    assert_eq!(contact.pairs[0].friction, Friction::Stick);
    // ...sticking from tₙ: the stick rows would pull it back.
    assert_eq!(contact.pairs[0].anchor, Vector3::new(0.0, 0.0, OFFSET));
    // Within a band of 2e-3 mm it keeps slipping.
    let (contact, changes) = slipping_node(1e-3, 2e-3);
    assert_eq!(changes, 0);
    assert_eq!(contact.pairs[0].friction, Friction::Slip);
    // Beyond a band of 5e-4 mm it sticks, from tₙ.
    let (contact, changes) = slipping_node(1e-3, 5e-4);
    assert_eq!(changes, 1);
    assert_eq!(contact.pairs[0].friction, Friction::Stick);
    assert_eq!(contact.pairs[0].anchor, Vector3::new(0.0, 0.0, OFFSET));
    // Moving against its friction force is no reversal, band or not.
    for band in [0.0, 5e-4] {
        let (contact, changes) = slipping_node(-1e-3, band);
        assert_eq!(changes, 0);
        assert_eq!(contact.pairs[0].friction, Friction::Slip);
    }
}

#[test]
fn a_regularised_slip_follows_its_trial_force() {
    // μ·λ_N = 0.6 N along +x at tₙ, k_t = μ·λ_N/δ = 60 N/mm: the
    // trial force is 0.6·x̂ − 60·d.
    let delta = 1e-2;
    let x = Vector3::x();
    let cases = [
        // Sliding on (against its friction force): stays slipping.
        (x * -1e-3, Friction::Slip, Some(x)),
        // Back by 1e-3 mm: 0.54 N, inside the cone: sticks, with
        // its anchor at tₙ (the spring holds 0.54 N there).
        (x * 1e-3, Friction::Stick, None),
        // Back by 3e-2 mm: −1.2 N, beyond the cone the other way:
        // slides back.
        (x * 3e-2, Friction::Slip, Some(-x)),
        // Sideways by 5e-3 mm: (0.6, −0.3) N, 0.67 N > 0.6 N: slips
        // along the trial force.
        (
            Vector3::y() * 5e-3,
            Friction::Slip,
            Some(Vector3::new(0.6, -0.3, 0.0).normalize()),
        ),
    ];
    for (d, friction, direction) in cases {
        let (contact, changes) = slipping_node_regularised(d, 0.0, delta);
        let pair = &contact.pairs[0];
        assert_eq!(pair.friction, friction, "{d:?}");
        assert_eq!(changes, usize::from(friction == Friction::Stick), "{d:?}");
        if let Some(dir) = direction {
            assert!((pair.slip_direction - dir).norm() <= 1e-12, "{d:?}");
        } else {
            assert_eq!(pair.anchor, Vector3::new(0.0, 0.0, OFFSET));
        }
    }
    // Rigid stick (δ = 0): the same sideways slip keeps sliding along
    // the carried direction (no reversal along it).
    let (contact, changes) = slipping_node_regularised(Vector3::y() * 5e-3, 0.0, 0.0);
    assert_eq!((changes, contact.pairs[0].friction), (0, Friction::Slip));
    assert_eq!(contact.pairs[0].slip_direction, x);
}

#[test]
fn a_pair_pressed_again_slides_at_once_when_its_spring_is_beyond_the_cone() {
    // Pressed since tₙ with 2 N (μ = 0.3: cone 0.6 N), sticking there
    // with 0.3 N along +x; it lifted off in an iteration and is pressed
    // again (no stick rows in the last solve). δ = 1e-2 mm: k_t = 60
    // N/mm, trial force (0.3, 0, 0) − 60·d.
    let x = Vector3::x();
    let cases = [
        // 5e-3 mm sideways: (0.3, −0.3) N, inside: the next solve
        // holds it.
        (Vector3::y() * 5e-3, Friction::Stick, None),
        // 2e-2 mm sideways: (0.3, −1.2) N, beyond: it slides along it
        // at once (stick rows would pull it with twice the cone).
        (
            Vector3::y() * 2e-2,
            Friction::Slip,
            Some(Vector3::new(0.3, -1.2, 0.0).normalize()),
        ),
        // 2e-2 mm back along x: −0.9 N, beyond the other way.
        (x * 2e-2, Friction::Slip, Some(-x)),
    ];
    for (d, friction, direction) in cases {
        for elastic_slip in [1e-2, 0.0] {
            let (mut contact, x) =
                pressed_on_floor([0.3, 0.0, 0.0], [0.0; 3], Friction::Stick, d, elastic_slip);
            assert!(contact.pairs[0].stick_rows);
            // As the solve after a lift-off leaves it.
            contact.pairs[0].stick_rows = false;
            contact.pairs[0].stick = Vector3::zeros();
            let changes = contact.update_friction(&x, 0.0);
            let pair = &contact.pairs[0];
            assert_eq!(changes, 1, "{d:?}");
            assert_eq!(
                pair.anchor,
                Vector3::new(0.0, 0.0, OFFSET),
                "{d:?}: anchored at tₙ"
            );
            if elastic_slip == 0.0 {
                // Rigid stick: the stick rows decide after the solve.
                assert_eq!(pair.friction, Friction::Stick, "{d:?}");
                continue;
            }
            assert_eq!(pair.friction, friction, "{d:?}");
            if let Some(dir) = direction {
                assert!((pair.slip_direction - dir).norm() <= 1e-12, "{d:?}");
            }
        }
    }
}

#[test]
fn the_stick_spring_is_the_cone_over_the_elastic_slip_or_above_the_inertia() {
    // TRAPEZOIDAL_STEP: m·(1 − α_m)/(β·h²) = 4e4·m.
    let inc = Some(TRAPEZOIDAL_STEP);
    assert_eq!(stick_stiffness(0.6, 1e-2, None, inc), 60.0);
    assert_eq!(stick_stiffness(0.6, 1e-2, Some(1e-6), inc), 60.0);
    let heavy = stick_stiffness(0.6, 1e-2, Some(1e-4), inc);
    assert!((heavy - STICK_OVER_INERTIA * 4.0).abs() <= 1e-9 * heavy);
    // Capped at μ·λ_N/1e-4 mm, whatever the elastic slip (to the
    // division's rounding: 0.6/1e-4 is 6 000 less an ulp).
    let cap: f64 = 0.6 / 1e-4;
    assert!((cap - 6000.0).abs() <= 1e-12 * 6000.0);
    assert_eq!(stick_stiffness(0.6, 1e-2, Some(1.0), inc), cap);
    assert_eq!(stick_stiffness(0.6, 1e-3, Some(1.0), inc), cap);
    // Never softer than μ·λ_N/δ.
    assert_eq!(stick_stiffness(0.6, 1e-5, Some(1.0), inc), 0.6 / 1e-5);
}

/// Nodes pinched between a floor and a force-driven holder pressed
/// with `force` (N): each node's two rows ±n carry the clamping force,
/// which cancels in Cᵀλ to a rounding error ε·F. Returns the solve's
/// outcome, Δx, the holder's step and the SVD reference (Δx, step).
#[allow(clippy::type_complexity)]
fn pinched(force: f64, seed: u64) -> (Result<SolveStats, SolveError>, Vec<f64>, f64, DVector<f64>) {
    let nodes = 6;
    // A slot tilted off the axes, so that ±n do not cancel exactly in
    // floating point; the holder moves along its normal.
    let normal = Vector3::new(0.3, -0.2, 1.0).normalize();
    let x: Vec<Vector3<f64>> = (0..nodes)
        .map(|i| {
            let p = Vector3::new(i as f64, 0.5 * (i % 2) as f64, 0.0);
            p - normal * normal.dot(&p) + normal * OFFSET
        })
        .collect();
    let mass = 1e-3;
    let tool = |name: &str, at: f64, n: Vector3<f64>, motion| Tool {
        name: name.into(),
        surface: Surface::plane(normal * at, n).unwrap(),
        motion,
        friction: 0.0,
    };
    let tools = vec![
        tool("die", 0.0, normal, ToolMotion::Fixed),
        tool(
            "holder",
            2.0 * OFFSET,
            -normal,
            ToolMotion::Force {
                direction: -normal,
                force,
                amplitude: Amplitude::Constant,
                mass,
            },
        ),
    ];
    let settings = ImplicitContactSettings {
        offset: OFFSET,
        margin: 0.5,
        tolerance: 1e-13,
        max_iterations: 1000,
        elastic_slip: 0.0,
        square_friction_leans: false,
    };
    let mut contact = ImplicitContact::new(tools.clone(), nodes, settings);
    let inc = TRAPEZOIDAL_STEP;
    contact.begin(&x, &[true; 6], inc);
    contact.linearise(&x, &x);
    let n = 3 * nodes;
    let k = stiffness(n, seed);
    let r: Vec<f64> = (0..n)
        .map(|i| ((i * 37 + 11) % 17) as f64 * 0.3 - 2.4)
        .collect();
    let chol = k.clone().cholesky().unwrap();
    let mut solve = |w: &mut [f64]| {
        let z = chol.solve(&DVector::from_column_slice(w));
        w.copy_from_slice(z.as_slice());
    };
    let block = |i: usize| Matrix3::from_fn(|a, b| k[(3 * i + a, 3 * i + b)]);
    let mut dx = vec![0.0; n];
    let solved = contact.solve_preconditioned(&r, &mut solve, Some(&block), &mut dx);
    // Reference: every row closed (the holder presses every node onto
    // the die), [K̃ −Cᵀ; C 0]·(Δx, Δd, λ) = (r, F, −g) by SVD; Δx and
    // Δd are unique, the λ of the pinched pairs are not.
    let big = n + 1;
    let m = 2 * nodes;
    let mut a = DMatrix::zeros(big + m, big + m);
    a.view_mut((0, 0), (n, n)).copy_from(&k);
    a[(n, n)] = mass * inc.mass_factor();
    let mut b = DVector::zeros(big + m);
    b.rows_mut(0, n).copy_from(&DVector::from_column_slice(&r));
    b[n] = force;
    for i in 0..nodes {
        for (j, (sign, tool)) in [(1.0, 0usize), (-1.0, 1)].iter().enumerate() {
            let row = big + 2 * i + j;
            let q = tools[*tool].project(&x[i], 0.0);
            for c in 0..3 {
                a[(row, 3 * i + c)] = *sign * normal[c];
                a[(3 * i + c, row)] = -*sign * normal[c];
            }
            if *tool == 1 {
                // The holder row: −n·a = −1 on its displacement.
                a[(row, n)] = -1.0;
                a[(n, row)] = 1.0;
            }
            b[row] = -(q.gap - OFFSET);
        }
    }
    let reference = a.svd(true, true).solve(&b, 1e-12).unwrap();
    let step = contact.tool_step[1];
    (solved, dx, step, reference.rows(0, big).into_owned())
}

#[test]
fn a_pinched_solve_stops_at_its_round_off_and_equals_the_reference() {
    for seed in 1..=3 {
        // A clamping force small enough that 1e-13 mm is above the
        // round-off: the tolerance decides.
        let (solved, dx, step, reference) = pinched(100.0, seed);
        let stats = solved.expect("converges");
        assert!(!stats.at_roundoff, "seed {seed}: {stats:?}");
        for q in 0..dx.len() {
            assert!(
                (dx[q] - reference[q]).abs() <= 1e-10,
                "seed {seed} Δx[{q}]: {} vs {}",
                dx[q],
                reference[q]
            );
        }
        assert!((step - reference[dx.len()]).abs() <= 1e-10);
        // 1e7 N: ε·A_kk·F is about 1e-9 mm, above the tolerance; the
        // solve stops at the floor (it ran out of products before)
        // with Δx within that floor's order of the reference.
        let (solved, dx, step, reference) = pinched(1e7, seed);
        let stats = solved.expect("stops at the round-off floor");
        assert!(stats.at_roundoff, "seed {seed}: {stats:?}");
        assert!(stats.residual > 1e-13, "seed {seed}: {stats:?}");
        // Both answers are accurate to the round-off floor ε·A_kk·F at
        // most (the SVD's own error is ε·‖K⁻¹‖·F): within the floor of
        // the largest compliance and a node's clamping force 2F/6.
        let k = stiffness(dx.len(), seed);
        let compliance = k.try_inverse().unwrap().diagonal().amax();
        let floor = ROUNDOFF * f64::EPSILON * compliance * 2.0 * 1e7 / 6.0;
        assert!(stats.residual <= floor, "seed {seed}: {stats:?} {floor:e}");
        for q in 0..dx.len() {
            assert!(
                (dx[q] - reference[q]).abs() <= floor,
                "seed {seed} Δx[{q}]: {} vs {}",
                dx[q],
                reference[q]
            );
        }
        assert!((step - reference[dx.len()]).abs() <= floor);
    }
}

#[test]
fn the_condensed_solve_equals_the_direct_saddle_point_solve() {
    // Unpreconditioned, and with the rows scaled by the diagonal of A
    // estimated from K̂'s nodal blocks (the driver's).
    for pre in [false, true] {
        for seed in 1..=4 {
            compare(false, 0.0, 0.0, seed, pre, false);
            compare(false, 0.3, 0.0, seed, pre, false);
            compare(true, 0.0, 0.0, seed, pre, false);
            compare(true, 0.3, 0.0, seed, pre, false);
            // A regularised stick: its rows' compliance δ/(μ·λ_N) on
            // A's diagonal and the carried force in their targets;
            // or (the driver's way) springs k_t in K̂ and their forces
            // at the iterate in the right-hand side. A rigid stick
            // has no spring: the flag must leave its rows alone.
            for springs in [false, true] {
                compare(false, 0.3, 0.05, seed, pre, springs);
                compare(true, 0.3, 0.05, seed, pre, springs);
            }
            compare(true, 0.3, 0.0, seed, pre, true);
        }
    }
}

/// A node between two planes whose normals lean the same way by θ
/// (a floor's (θ, 0, 1) and a roof's (θ, 0, −1), 1 + cos = 2θ²): within
/// [`PINCH`] of opposite the two pairs' normals come out exactly opposite,
/// along n₁ − n₂, and are marked squared where they were not within
/// [`FLAT`]; a frictionless wedge of 0.01 rad is left as it is. With
/// friction μ on both faces a wedge is squared while its lean from opposite
/// (2θ) is inside their friction, sin 2θ < 2μ: θ = 0.01 and 0.09 at
/// μ = 0.1 (sin 2θ = 0.18), not θ = 0.12 (0.24); only for the active-set
/// solver ([`ImplicitContactSettings::square_friction_leans`]).
#[test]
fn a_pinch_whose_normals_lean_alike_is_squared() {
    let pinch_with = |theta: f64, friction: f64, square_friction_leans: bool| {
        let face = |z: f64, up: f64| Tool {
            name: format!("face{z}"),
            surface: Surface::plane(
                Vector3::new(0.0, 0.0, z),
                Vector3::new(theta, 0.0, up).normalize(),
            )
            .unwrap(),
            motion: ToolMotion::Fixed,
            friction,
        };
        let settings = ImplicitContactSettings {
            offset: OFFSET,
            margin: 0.5,
            square_friction_leans,
            ..ImplicitContactSettings::default()
        };
        let tools = vec![face(-OFFSET, 1.0), face(OFFSET, -1.0)];
        let mut contact = ImplicitContact::new(tools, 1, settings);
        let x = vec![Vector3::new(0.3, 0.0, 0.0)];
        contact.begin(&x, &[true], TRAPEZOIDAL_STEP);
        contact.linearise(&x, &x);
        assert_eq!(contact.pairs.len(), 2, "θ = {theta}");
        let (a, b) = (&contact.pairs[0], &contact.pairs[1]);
        assert_eq!(a.squared, b.squared, "θ = {theta}");
        (a.normal, b.normal, a.squared)
    };
    let pinch = |theta: f64| pinch_with(theta, 0.0, true);
    // Flat (2θ² = 0, 2e-10 < FLAT) and leaning (3.2e-7 < PINCH).
    for (theta, marked) in [(0.0, false), (1e-5, false), (4e-4, true)] {
        let (a, b, squared) = pinch(theta);
        assert_eq!((a, b), (Vector3::z(), -Vector3::z()), "θ = {theta}");
        assert_eq!(squared, marked, "θ = {theta}");
    }
    // A wedge: 2e-4 > PINCH.
    let (a, b, squared) = pinch(0.01);
    assert!(
        (a - Vector3::new(0.01, 0.0, 1.0).normalize()).norm() < 1e-15,
        "{a}"
    );
    assert!(
        (b - Vector3::new(0.01, 0.0, -1.0).normalize()).norm() < 1e-15,
        "{b}"
    );
    assert!(!squared);
    // With friction: inside the two faces' friction (sin 2θ < 0.2),
    // squared and marked; outside it, left.
    for theta in [0.01, 0.09] {
        let (a, b, squared) = pinch_with(theta, 0.1, true);
        assert!((a - Vector3::z()).norm() < 1e-15, "θ = {theta}: {a}");
        assert!((b + Vector3::z()).norm() < 1e-15, "θ = {theta}: {b}");
        assert!(squared, "θ = {theta}");
    }
    let (a, b, squared) = pinch_with(0.12, 0.1, true);
    assert!(
        (a - Vector3::new(0.12, 0.0, 1.0).normalize()).norm() < 1e-15,
        "{a}"
    );
    assert!(
        (b - Vector3::new(0.12, 0.0, -1.0).normalize()).norm() < 1e-15,
        "{b}"
    );
    assert!(!squared);
    // The condensed solver's pass leaves the lean.
    let (a, _, squared) = pinch_with(0.01, 0.1, false);
    assert!(
        (a - Vector3::new(0.01, 0.0, 1.0).normalize()).norm() < 1e-15,
        "{a}"
    );
    assert!(!squared);
}

proptest::proptest! {
    /// The clamp's sharing moves multipliers only along the pinched
    /// nodes' null space: each node's net force λ_d − λ_h and the holder's
    /// total Σλ_h are kept (to round-off); where some share keeps every
    /// row pressed no multiplier is left negative; and the shares are
    /// max(w·p, λ_h − λ_d) for one pressure p (the nodes above their
    /// least share all at w·p).
    #[test]
    fn the_clamp_sharing_keeps_each_node_s_net_force_and_the_clamp(
        nets in proptest::collection::vec(-20.0f64..20.0, 2..12),
        masses in proptest::collection::vec(0.5f64..2.0, 12),
        clamp in 1.0f64..100.0,
    ) {
        let n = nets.len();
        let holder = plane(
            "holder",
            OFFSET,
            false,
            0.1,
            ToolMotion::Force {
                direction: -Vector3::z(),
                force: clamp,
                amplitude: Amplitude::Constant,
                mass: 1.0,
            },
        );
        let die = plane("die", -OFFSET, true, 0.1, ToolMotion::Fixed);
        let settings = ImplicitContactSettings {
            offset: OFFSET,
            margin: 0.5,
            ..ImplicitContactSettings::default()
        };
        let mut contact = ImplicitContact::new(vec![die, holder], n, settings);
        contact.set_mass(&masses[..n]);
        let x: Vec<_> = (0..n).map(|i| Vector3::new(i as f64, 0.0, 0.0)).collect();
        contact.begin(&x, &vec![true; n], TRAPEZOIDAL_STEP);
        contact.linearise(&x, &x);
        proptest::prop_assert_eq!(contact.pairs.len(), 2 * n);
        // The system's own split: the clamp on the holder in proportion
        // to the node index, the die rows from each node's net force.
        let weights: f64 = (1..=n).map(|i| i as f64).sum();
        for (i, net) in nets.iter().enumerate() {
            let h = clamp * (i + 1) as f64 / weights;
            contact.pairs[n + i].multiplier = h;
            contact.pairs[i].multiplier = h + net;
            for k in [i, n + i] {
                contact.pairs[k].active = true;
                contact.pairs[k].lambda = contact.pairs[k].multiplier.max(0.0);
            }
        }
        let before: Vec<f64> = contact.pairs.iter().map(|p| p.multiplier).collect();
        contact.share_clamp();
        let after: Vec<f64> = contact.pairs.iter().map(|p| p.multiplier).collect();
        let tol = 1e-12 * (clamp + 20.0);
        let mut total = 0.0;
        for i in 0..n {
            let net = after[i] - after[n + i];
            proptest::prop_assert!((net - nets[i]).abs() <= tol, "node {i}: {net} against {}", nets[i]);
            total += after[n + i];
        }
        proptest::prop_assert!((total - clamp).abs() <= tol, "clamp {total} against {clamp}");
        let least: Vec<f64> = nets.iter().map(|&d| (-d).max(0.0)).collect();
        if least.iter().sum::<f64>() <= clamp {
            proptest::prop_assert!(after.iter().all(|&l| l >= -tol), "{after:?}");
            // One pressure for the nodes above their least share.
            let pressures: Vec<f64> = (0..n)
                .filter(|&i| after[n + i] > least[i] + tol)
                .map(|i| after[n + i] / masses[i])
                .collect();
            for p in &pressures {
                proptest::prop_assert!((p - pressures[0]).abs() <= 1e-9 * pressures[0], "{pressures:?}");
            }
            for i in 0..n {
                proptest::prop_assert!(
                    after[n + i] >= least[i] - tol,
                    "node {i}: share {} under its least {}",
                    after[n + i],
                    least[i]
                );
                if after[n + i] > least[i] + tol {
                    // At w·p, which is not below its least share.
                    proptest::prop_assert!(pressures[0] * masses[i] >= least[i] - tol);
                } else if !pressures.is_empty() {
                    // Bound: w·p is not above its least share.
                    proptest::prop_assert!(pressures[0] * masses[i] <= least[i] + tol);
                }
            }
        } else {
            proptest::prop_assert_eq!(&after, &before);
        }
    }
}
