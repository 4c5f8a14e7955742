//! Tests of the ply pass: the narrow phase's closest points, the normal
//! and friction solves on small stacks.

use super::fixtures::normal_pass;
use super::*;

/// Two unit squares (two triangles each) 0.9 apart with offsets of 0.5
/// each: every node 0.1 mm inside.
fn two_squares(dz: f64) -> (Vec<Vector3<f64>>, PlyContact) {
    let sq = |z: f64| {
        [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].map(|[x, y]| Vector3::new(x, y, z))
    };
    let mut x = sq(0.0).to_vec();
    x.extend(sq(dz));
    let layer = |first| fixtures::square_layer(first, 0.5);
    let contact = PlyContact::new(
        vec![layer(0), layer(4)],
        &[PlyInterface {
            lower: 0,
            upper: 1,
            friction: 0.5,
        }],
        vec![0.25; 8],
        1.0,
    );
    (x, contact)
}

#[test]
fn closest_point_weights_reproduce_the_point() {
    let (a, b, c) = (
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(2.0, 0.0, 0.0),
        Vector3::new(0.0, 1.0, 0.5),
    );
    for p in [
        Vector3::new(0.3, 0.2, 1.0),
        Vector3::new(-1.0, -1.0, 0.0),
        Vector3::new(3.0, 0.1, 0.0),
        Vector3::new(1.0, 1.0, 0.0),
        Vector3::new(-0.5, 0.5, 0.2),
    ] {
        let (q, w) = closest_on_triangle(&p, &a, &b, &c);
        let back = a * w[0] + b * w[1] + c * w[2];
        assert!((q - back).norm() < 1e-14);
        assert!(w.iter().all(|&w| (-1e-15..=1.0 + 1e-15).contains(&w)));
        // No point of the triangle (a grid of them) is closer.
        for i in 0..=20 {
            for j in 0..=(20 - i) {
                let r = a + (b - a) * (i as f64 / 20.0) + (c - a) * (j as f64 / 20.0);
                assert!((p - r).norm() >= (p - q).norm() - 1e-12);
            }
        }
    }
}

#[test]
fn overlapping_plies_are_pushed_apart_by_mass() {
    let (mut x, mut contact) = two_squares(0.9);
    let mut v = vec![Vector3::zeros(); 8];
    // The lower ply three times heavier: it moves a quarter of 0.1.
    let mut mass = vec![3.0; 4];
    mass.extend([1.0; 4]);
    let mut force = vec![Vector3::zeros(); 8];
    let step = normal_pass(
        &mut contact,
        &mut x,
        &mut v,
        &mass,
        &[true; 8],
        &mut [],
        &mut force,
    );
    // To the solve's tolerance of the 0.1 mm violation, less the rows'
    // give: each row is alone (a node on a node), so its push is
    // 1/(1 + κ) of the rigid row's and it ends κ/(1 + κ) of 0.1 inside.
    let tolerance = NORMAL_TOLERANCE * 0.1;
    let kappa = NORMAL_COMPLIANCE;
    assert!(step.active > 0 && step.residual <= tolerance);
    for i in 0..4 {
        let (lower, upper) = (-0.025 / (1.0 + kappa), 0.9 + 0.075 / (1.0 + kappa));
        assert!((x[i].z - lower).abs() < tolerance, "{}", x[i].z);
        assert!((x[i + 4].z - upper).abs() < tolerance, "{}", x[i + 4].z);
    }
    // (Every node is a corner of its square, on the free outline, where
    // the overlap measure counts nothing: the positions say it.)
    let give = 0.1 * kappa / (1.0 + kappa);
    for i in 0..4 {
        let overlap = 1.0 - (x[i + 4].z - x[i].z);
        assert!((overlap - give).abs() < 2.0 * tolerance, "{overlap}");
    }
    // Equal and opposite forces.
    let total: Vector3<f64> = force.iter().sum();
    assert!(total.norm() < 1e-9 * force[4].norm());
}

#[test]
fn nodes_on_nodes_make_one_row_per_pair_with_the_deeper_gap() {
    // `passes` steps on one configuration; the first step's rows.
    let solve = |raise: f64, passes: usize| {
        let (mut x, mut contact) = two_squares(0.9);
        // Rigid rows, so that what one step leaves is the pairing's alone.
        contact.compliance = 0.0;
        x[6].z += raise;
        let mut v = vec![Vector3::zeros(); 8];
        let mass = vec![1.0; 8];
        let mut force = vec![Vector3::zeros(); 8];
        let mut first = None;
        for _ in 0..passes {
            let step = normal_pass(
                &mut contact,
                &mut x,
                &mut v,
                &mass,
                &[true; 8],
                &mut [],
                &mut force,
            );
            if first.is_none() {
                let rows: Vec<(u32, u32)> = contact
                    .constraints
                    .iter()
                    .map(|c| (c.slave, c.slip_node))
                    .collect();
                first = Some((step, rows));
            }
        }
        let (step, mut rows) = first.expect("a pass");
        rows.sort_unstable();
        (step, rows, contact.max_overlap(&x))
    };
    // Flat: four pairs, one row each (the two searches would make
    // eight), the upper node's where the gaps tie.
    let (step, rows, overlap) = solve(0.0, 1);
    assert_eq!(step.active, 4);
    assert_eq!(rows, [(4, 4), (5, 5), (6, 6), (7, 7)]);
    assert!(overlap < 1e-9, "{overlap}");
    // One upper corner raised: both upper faces tilt, so each lower
    // node is nearer them than its upper node is to the flat lower
    // faces; the lower nodes' rows are kept, their slip counted for
    // the upper node of each pair. The upper nodes' gaps follow to
    // first order: what one step leaves of them is of the order of
    // the correction (0.1 mm) times the tilt squared (≤ 0.02 rad
    // along the diagonal), and the next step, where they are the
    // deeper, takes it up.
    let (step, rows, overlap) = solve(0.01, 1);
    assert_eq!(step.active, 4);
    assert_eq!(rows, [(0, 4), (1, 5), (2, 6), (3, 7)]);
    assert!(overlap < 0.1 * 0.02 * 0.02, "{overlap}");
    let (_, _, overlap) = solve(0.01, 2);
    assert!(overlap < 1e-8, "{overlap}");
}

/// Unit masses with the lower ply's nodes fixed, and zeroed forces, for
/// [`two_squares`].
fn lower_fixed() -> (Vec<f64>, Vec<bool>, Vec<Vector3<f64>>) {
    (
        vec![1.0; 8],
        (0..8).map(|i| i >= 4).collect(),
        vec![Vector3::zeros(); 8],
    )
}

#[test]
fn a_repeated_step_starts_from_the_last_forces() {
    // The lower ply fixed, the upper pushed 0.1 mm into it twice: the
    // second solve starts from the first one's multipliers, which are
    // its answer, and stops after the sweep that finds nothing to do.
    let (mut x, mut contact) = two_squares(0.9);
    // Rigid rows: a compliant row's second answer differs from its first
    // by the give the first left (a_compliant_row_gives_and_takes_it_back).
    contact.compliance = 0.0;
    let mut v = vec![Vector3::zeros(); 8];
    let (mass, movable, mut force) = lower_fixed();
    let (dt, tau) = (1e-3, 1e-3);
    let first = normal_pass(
        &mut contact,
        &mut x,
        &mut v,
        &mass,
        &movable,
        &mut [],
        &mut force,
    );
    contact.friction(
        &mut x,
        &mut v,
        &mass,
        &movable,
        dt,
        tau,
        &mut [],
        &mut force,
    );
    assert!(first.sweeps > 1);
    for p in &mut x[4..] {
        p.z -= 0.1;
    }
    let second = normal_pass(
        &mut contact,
        &mut x,
        &mut v,
        &mass,
        &movable,
        &mut [],
        &mut force,
    );
    assert_eq!(second.sweeps, 1);
    // To the solve's tolerance of the 0.1 mm it started from.
    for p in &x[4..] {
        assert!((p.z - 1.0).abs() <= NORMAL_TOLERANCE * 0.1, "{}", p.z);
    }
    assert_eq!(contact.totals.steps, 2);
    assert_eq!(contact.totals.normal_capped, 0);
}

/// One normal pass of two plies at rest (unit masses, all movable) with
/// the lower ply's nodes 0..4 on a tool below them: the velocities and the
/// supports after it.
fn pass_on_tool(
    x: &mut [Vector3<f64>],
    contact: &mut PlyContact,
) -> (Vec<Vector3<f64>>, Vec<Support>) {
    let mut v = vec![Vector3::zeros(); 8];
    let mut force = vec![Vector3::zeros(); 8];
    let mut supports = fixtures::bottom_supports();
    normal_pass(
        contact,
        x,
        &mut v,
        &[1.0; 8],
        &[true; 8],
        &mut supports,
        &mut force,
    );
    (v, supports)
}

#[test]
fn a_supported_lower_ply_sends_the_push_to_the_upper() {
    let (mut x, mut contact) = two_squares(0.9);
    let (_, supports) = pass_on_tool(&mut x, &mut contact);
    // To the solve's tolerance of the 0.1 mm violation, less the ply
    // rows' give (the tool's supports are rigid). A row's give is κ times
    // what its push moves it with both its nodes free (μ/m, here 2μ), but
    // the tool holds the lower node, so the push moves the upper one by
    // μ: it goes up 1/(1 + 2κ) of the 0.1 mm.
    let tolerance = NORMAL_TOLERANCE * 0.1;
    let share = 1.0 / (1.0 + 2.0 * NORMAL_COMPLIANCE);
    for i in 0..4 {
        assert!(x[i].z.abs() < tolerance);
        assert!(
            (x[i + 4].z - 0.9 - 0.1 * share).abs() < tolerance,
            "{}",
            x[i + 4].z - 0.9 - 0.1 * share
        );
    }
    // The tool carries the whole push: Σν = Σμ of the ply constraints,
    // each of the four within the solve's tolerance (unit masses).
    let nu: f64 = supports.iter().map(|s| s.mu).sum();
    assert!((nu - 0.4 * share).abs() < 4.0 * tolerance, "{nu}");
}

#[test]
fn a_node_put_back_out_beside_a_tool_is_shifted_along_it_not_thrown() {
    // A small upper quad 0.05 mm behind the lower square's mid-plane
    // (inside it: put back out, 0.35 mm, as a shift of position), the
    // square on a tool. The square's share of the shift went into the
    // tool, whose support took it back as a velocity. The quad takes the
    // whole shift instead, and nothing moves after.
    let quad =
        [[4.0, 4.0], [6.0, 4.0], [6.0, 6.0], [4.0, 6.0]].map(|[a, b]| Vector3::new(a, b, -0.05));
    let (mut x, mut contact) = fixtures::on_square(quad);
    let (v, _) = pass_on_tool(&mut x, &mut contact);
    for i in 0..4 {
        assert_eq!(x[i].z, 0.0, "{}", x[i]);
        assert!((x[i + 4].z - 0.3).abs() < 1e-12, "{}", x[i + 4]);
    }
    for vi in &v {
        assert!(vi.norm() < 1e-9, "{vi}");
    }
}

#[test]
fn a_chain_of_plies_is_solved_to_the_stated_tolerance() {
    // Three unit squares 0.9 mm apart (offsets 1 mm: each interface
    // 0.1 mm inside), the bottom one on a tool, the middle one twice
    // as heavy: the tool holds the bottom, the middle moves 0.1 mm and
    // the top 0.2 mm, with multipliers (as mass × mm per node) 0.2 on
    // the upper interface, 0.4 on the lower and on the tool. Gauss–
    // Seidel takes this chain over many sweeps; it stops with every
    // gap within NORMAL_TOLERANCE of the 0.1 mm start.
    let sq = |z: f64| {
        [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].map(|[x, y]| Vector3::new(x, y, z))
    };
    let mut x: Vec<Vector3<f64>> = [0.0, 0.9, 1.8].iter().flat_map(|&z| sq(z)).collect();
    let layer = |first| fixtures::square_layer(first, 0.5);
    let interface = |lower, upper| PlyInterface {
        lower,
        upper,
        friction: 0.0,
    };
    let mut contact = PlyContact::new(
        vec![layer(0), layer(4), layer(8)],
        &[interface(0, 1), interface(1, 2)],
        vec![0.25; 12],
        1.0,
    );
    // Rigid rows: the chain's exact answer is the one above.
    contact.compliance = 0.0;
    let mut v = vec![Vector3::zeros(); 12];
    let mut mass = vec![1.0; 12];
    mass[4..8].fill(2.0);
    let mut force = vec![Vector3::zeros(); 12];
    let mut supports = fixtures::bottom_supports();
    let step = normal_pass(
        &mut contact,
        &mut x,
        &mut v,
        &mass,
        &[true; 12],
        &mut supports,
        &mut force,
    );
    let tolerance = NORMAL_TOLERANCE * 0.1;
    assert_eq!(step.active, 8);
    assert!(step.sweeps > 5, "{}", step.sweeps);
    assert!(step.residual <= tolerance, "{}", step.residual);
    assert_eq!(contact.totals.normal_capped, 0);
    // Flat plies: the linearised gaps are the gaps. Each is within the
    // tolerance; a position errs by at most the two gaps below it.
    assert!(
        contact.max_overlap(&x) <= tolerance,
        "{}",
        contact.max_overlap(&x)
    );
    for i in 0..4 {
        assert!(x[i].z.abs() <= tolerance, "{}", x[i].z);
        assert!(
            (x[i + 4].z - 1.0).abs() <= 2.0 * tolerance,
            "{}",
            x[i + 4].z
        );
        assert!(
            (x[i + 8].z - 2.0).abs() <= 3.0 * tolerance,
            "{}",
            x[i + 8].z
        );
    }
    // The tool's multipliers carry both plies' push: 0.4 per node, to
    // the masses (1 + 2 + 1) times the gaps' tolerance.
    for s in &supports {
        assert!((s.mu - 0.4).abs() <= 4.0 * tolerance, "{}", s.mu);
    }
    let upper: Vec<f64> = contact
        .constraints
        .iter()
        .filter(|c| c.slave >= 8 || c.masters.iter().all(|&m| m >= 8))
        .map(|c| c.mu)
        .collect();
    assert_eq!(upper.len(), 4);
    for mu in upper {
        assert!((mu - 0.2).abs() <= 4.0 * tolerance, "{mu}");
    }
}

#[test]
fn friction_sticks_below_the_cone_and_slides_on_it() {
    for (speed, sticks) in [(1e-3, true), (1000.0, false)] {
        let (mut x, mut contact) = two_squares(0.9);
        let mut v = vec![Vector3::zeros(); 8];
        for vi in &mut v[4..] {
            vi.x = speed;
        }
        let mass = vec![1.0; 8];
        let fixed: Vec<bool> = (0..8).map(|i| i >= 4).collect();
        let mut force = vec![Vector3::zeros(); 8];
        let (dt, tau) = (1e-3, 1e-3);
        normal_pass(
            &mut contact,
            &mut x,
            &mut v,
            &mass,
            &fixed,
            &mut [],
            &mut force,
        );
        let normal: f64 = force[4..].iter().map(|f| f.z).sum();
        contact.friction(&mut x, &mut v, &mass, &fixed, dt, tau, &mut [], &mut force);
        let tangential: f64 = force[4..].iter().map(|f| f.x).sum();
        if sticks {
            assert!(v[4..].iter().all(|v| v.x.abs() < 1e-12));
            assert!(-tangential < 0.5 * normal);
        } else {
            assert!((-tangential - 0.5 * normal).abs() < 1e-9 * normal);
            assert!(contact.slip[4] > 0.0 && contact.friction_dissipation > 0.0);
        }
    }
}

#[test]
fn a_compliant_row_gives_and_takes_it_back() {
    // A row alone (a node on a node, unit masses, the lower ply fixed)
    // pushed 0.1 mm in: its push is 1/(1 + κ) of the rigid row's, so it
    // ends κ/(1 + κ) of the 0.1 mm inside; each pass after, with nothing
    // pushing, takes the same share of what is left.
    let (mut x, mut contact) = two_squares(0.9);
    let mut v = vec![Vector3::zeros(); 8];
    let (mass, movable, mut force) = lower_fixed();
    let kappa = NORMAL_COMPLIANCE;
    let keeps = kappa / (1.0 + kappa);
    let mut left = 0.1;
    for pass in 0..4 {
        normal_pass(
            &mut contact,
            &mut x,
            &mut v,
            &mass,
            &movable,
            &mut [],
            &mut force,
        );
        left *= keeps;
        // The solve stops when its last update is within its tolerance
        // of the step's violation; over-relaxed, the error it leaves is
        // within twice that.
        let start = if pass == 0 { 0.1 } else { left / keeps };
        let tolerance = 2.0 * NORMAL_TOLERANCE * start;
        for p in &x[4..] {
            let inside = 1.0 - p.z;
            assert!(
                (inside - left).abs() <= tolerance,
                "pass {pass}: {inside} {left} {tolerance}"
            );
        }
        for p in &x[..4] {
            assert_eq!(p.z, 0.0);
        }
    }
}

#[test]
fn a_shortened_step_keeps_the_rows_give() {
    // The upper ply pushed down on the fixed lower one by a steady
    // acceleration a: at rest, each row holds it κ·a·Δt² inside. A
    // step 1000 times shorter (a run's last, landing on its end time)
    // keeps that give, as a spring would, instead of taking it back at
    // once and throwing the ply off at κ·a·Δt²/Δt' (2.5 mm/s here).
    let (mut x, mut contact) = two_squares(1.0);
    let (mass, movable, mut force) = lower_fixed();
    let a = 100.0;
    let give = NORMAL_COMPLIANCE * a * 1e-6;
    for (k, dt) in [1e-3; 6].into_iter().chain([1e-6]).enumerate() {
        // The predictor of the push over the step, and its velocity.
        let mut v = vec![Vector3::zeros(); 8];
        for i in 4..8 {
            x[i].z -= a * dt * dt;
            v[i].z = -a * dt;
        }
        contact.normal(
            &mut x,
            &mut v,
            &mass,
            &movable,
            dt,
            dt,
            &mut [],
            &mut [],
            &mut force,
        );
        // Each step takes all but κ/(1 + κ) of what the last left of
        // the settling: by the fifth it is 1e-8 of the give.
        if k < 5 {
            continue;
        }
        // The give to the long steps' solve tolerance of their violation
        // (the short step keeps what they left); the short step's motion
        // to its own.
        let long = 2.0 * NORMAL_TOLERANCE * (give + a * 1e-6);
        let own = 2.0 * NORMAL_TOLERANCE * (give + a * dt * dt);
        for i in 4..8 {
            let inside = 1.0 - x[i].z;
            assert!(
                (inside - give).abs() <= long,
                "step {k}: {inside} of {give}"
            );
            assert!(v[i].z.abs() * dt <= own, "step {k}: {} mm/s", v[i].z);
        }
    }
}

/// A dormant row joins the solve once the corrections so far close it by
/// more than the tolerance, in its order, with records that no sweep may
/// pass over; one they leave open, or close by less, waits.
#[test]
fn a_dormant_row_closed_by_the_solve_joins_it() {
    let row = |slave: u32, gap: f64| Constraint {
        slave,
        masters: [0, 1, 2],
        w: [0.5, 0.25, 0.25],
        normal: Vector3::z(),
        gap,
        mu: 0.0,
        mass: 1.0,
        inv: [1.0; 4],
        slip_node: slave,
        search: 0,
        shift: 0.0,
        compliance: 0.0,
    };
    // The face's nodes pushed up by 2e-3 mm (node 1 by 1e-3 more), the
    // slaves not at all: each row closes by 2.25e-3 mm.
    let mut dx = vec![Vector3::zeros(); 6];
    dx[0].z = 2e-3;
    dx[1].z = 3e-3;
    dx[2].z = 2e-3;
    let mut dormant = vec![row(3, 2.2e-3), row(4, 2.3e-3), row(5, 1e-3)];
    let mut rows = vec![row(3, -1e-3)];
    let (mut seen, mut last) = (vec![0.5], vec![0.25]);
    let tolerance = 1e-5;
    assert!(wake(
        &mut dormant,
        &mut rows,
        &dx,
        tolerance,
        &mut seen,
        &mut last
    ));
    // 2.2e-3 − 2.25e-3 and 1e-3 − 2.25e-3 are closed, 2.3e-3 is not.
    let slaves = |r: &[Constraint]| r.iter().map(|c| c.slave).collect::<Vec<_>>();
    assert_eq!(slaves(&rows), [3, 3, 5]);
    assert_eq!(slaves(&dormant), [4]);
    assert_eq!(seen, [0.5, f64::NEG_INFINITY, f64::NEG_INFINITY]);
    assert_eq!(last, [0.25, 0.0, 0.0]);
    // Within the tolerance: not closed.
    let mut dormant = vec![row(3, 2.25e-3 - 0.5 * tolerance)];
    assert!(!wake(
        &mut dormant,
        &mut rows,
        &dx,
        tolerance,
        &mut seen,
        &mut last
    ));
    assert_eq!(rows.len(), 3);
}
