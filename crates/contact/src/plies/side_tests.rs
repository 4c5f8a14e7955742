//! The ply contact's sides: a node found inside a ply on the far side of
//! its mid-surface, away from the ply's free end (a fold came over it),
//! is put back on its side (the stacking side) by a shift of position, not
//! a kick. At the end the way out is through the end ([`super::end_tests`]).

use nalgebra::Vector3;

use super::PlyContact;

/// [`super::fixtures::quad_over_square`] with the upper ply's nodes 5
/// and 6 at x = 8, `hang` mm above the lower ply's mid-plane, 2 mm in
/// from its free edge x = 10.
fn edge(hang: f64) -> (Vec<Vector3<f64>>, PlyContact) {
    super::fixtures::quad_over_square([8.0, hang])
}

/// `steps` steps in which the (fixed) lower ply moves 0.01 mm along +x;
/// `x` and `v` after them.
fn sweep(x: &mut [Vector3<f64>], contact: &mut PlyContact, steps: usize) -> Vec<Vector3<f64>> {
    let mut v = vec![Vector3::zeros(); 8];
    let mass = vec![1.0; 8];
    let movable: Vec<bool> = (0..8).map(|i| i >= 4).collect();
    let mut force = vec![Vector3::zeros(); 8];
    for _ in 0..steps {
        for p in &mut x[..4] {
            p.x += 0.01;
        }
        super::fixtures::normal_pass(contact, x, &mut v, &mass, &movable, &mut [], &mut force);
    }
    v
}

#[test]
fn a_node_inside_the_ply_away_from_its_end_goes_back_on_top_without_a_kick() {
    // 0.05 mm below the lower ply's mid-plane, 2 mm in from its end: the
    // way back to its own side (0.35 mm) is shorter than out through the
    // end. Without the side rule the face that covers it finds it behind
    // its mid-surface and leaves it there, 0.35 mm inside the ply.
    let (mut x, mut c) = edge(-0.05);
    let v = sweep(&mut x, &mut c, 1);
    let overlap = c.max_overlap(&x);
    assert!(overlap < 1e-12, "{overlap}");
    for i in [5, 6] {
        assert!((x[i].z - 0.3).abs() < 1e-12, "node {i}: {}", x[i]);
        assert!((x[i].x - 8.0).abs() < 1e-12, "node {i}: {}", x[i]);
        // Moved 0.35 mm as a position, not a velocity (0.35 mm/ms).
        assert!(v[i].norm() < 1e-9, "node {i}: {}", v[i]);
    }
}

#[test]
fn a_node_clear_under_the_ply_is_left_there_and_put_back_on_top_once_inside() {
    // 0.5 mm below the mid-plane, 2 mm in from the end: clear of the
    // lower ply (0.3), so nothing touches it (another part of the ply, for
    // all the contact knows). Lifted into the ply, it is through it by
    // the stacking order and goes back on top, not out the nearer side
    // below.
    let (mut x, mut c) = edge(-0.5);
    let v = sweep(&mut x, &mut c, 30);
    assert_eq!(x[5].z, -0.5);
    assert!(v.iter().all(|v| *v == Vector3::zeros()));
    for i in [5, 6] {
        x[i].z = -0.2;
    }
    let v = sweep(&mut x, &mut c, 1);
    let overlap = c.max_overlap(&x);
    assert!(overlap < 1e-12, "{overlap}");
    for i in [5, 6] {
        assert!((x[i].z - 0.3).abs() < 1e-12, "node {i}: {}", x[i]);
        assert!(v[i].norm() < 1e-9, "node {i}: {}", v[i]);
    }
}
