//! The ply contact at a ply's free end: a node of the neighbouring ply
//! may hang beside the end, on either side, but never gets round it over
//! (or under) the face, whether it moves or the end comes over it; and a
//! node that comes up beside the end into the ply's edge is not thrown.

use nalgebra::Vector3;

use super::{NORMAL_TOLERANCE, PlyContact};

/// [`super::fixtures::quad_over_square`]: the upper ply's nodes 5 and 6
/// at `far` (x, z), the lower ply's free end at x = 10.
fn plies(far: [f64; 2]) -> (Vec<Vector3<f64>>, PlyContact) {
    super::fixtures::quad_over_square(far)
}

const DT: f64 = 1e-3;

/// One step of the explicit predictor and the ply pass: every movable
/// node (the upper ply's 5 and 6) moves at `drive` (mm/s) from where the
/// last step left it, the lower ply (fixed) by `end` (mm); `v` after the
/// pass.
fn step(
    x: &mut [Vector3<f64>],
    contact: &mut PlyContact,
    drive: Vector3<f64>,
    end: f64,
) -> Vec<Vector3<f64>> {
    let mut v = vec![Vector3::zeros(); 8];
    for i in [5, 6] {
        v[i] = drive;
        x[i] += drive * DT;
    }
    for p in &mut x[..4] {
        p.x += end;
        // (The lower ply's velocity, as the driver would set it.)
    }
    for vi in &mut v[..4] {
        vi.x = end / DT;
    }
    let mass = vec![1.0; 8];
    let movable: Vec<bool> = (0..8).map(|i| i == 5 || i == 6).collect();
    let mut force = vec![Vector3::zeros(); 8];
    contact.normal(
        x,
        &mut v,
        &mass,
        &movable,
        DT,
        DT,
        &mut [],
        &mut [],
        &mut force,
    );
    v
}

#[test]
fn a_node_driven_round_the_free_end_stays_beside_it() {
    // The four-ply hemisphere's `p45` node 1017 at t = 0.68 s: beside
    // `p90`'s free edge, 0.5 mm out, it went past the mid-plane to the far
    // side and crossed the end plane 2 mm behind it, where the faces took
    // it for another part of the ply (a fold) and let it in. Here: from
    // 0.5 mm beside the end on its own side, driven down to 1 mm behind
    // the mid-plane (within the broad phase's reach of the fixture's 1 mm
    // margin), then in, at 0.1 mm a step.
    let (mut x, mut c) = plies([10.5, 0.3]);
    for _ in 0..13 {
        step(&mut x, &mut c, Vector3::new(0.0, 0.0, -100.0), 0.0);
        // Beside the end: nothing touches it.
        assert!(x[5].x == 10.5, "{}", x[5]);
    }
    assert!((x[5].z + 1.0).abs() < 1e-9, "{}", x[5]);
    for k in 0..30 {
        let v = step(&mut x, &mut c, Vector3::new(-100.0, 0.0, 0.0), 0.0);
        for i in [5, 6] {
            // Stopped at the end plane, to the solve's tolerance (of a
            // step's 0.1 mm), its motion in stopped there (an inelastic
            // impact, not a throw), its depth kept.
            let tolerance = NORMAL_TOLERANCE * 0.1;
            assert!(x[i].x >= 10.0 - tolerance, "step {k}, node {i}: {}", x[i]);
            assert!((x[i].z + 1.0).abs() < 1e-9, "step {k}, node {i}: {}", x[i]);
            if k >= 5 {
                assert!((x[i].x - 10.0).abs() < tolerance, "step {k}: {}", x[i]);
                assert!(
                    v[i].x.abs() < tolerance / DT,
                    "step {k}, node {i}: {}",
                    v[i]
                );
            }
        }
        // Out of the end to the solve's tolerance of the step's 0.1 mm.
        assert!(c.max_overlap(&x) <= NORMAL_TOLERANCE * 0.1, "step {k}");
    }
}

#[test]
fn a_free_end_coming_over_a_node_behind_it_pushes_it_along() {
    // The lower ply's end moving out 0.01 mm a step towards the upper
    // ply's nodes hanging beside it behind its mid-plane, in its
    // thickness (0.05 mm behind) and below it (1 mm): the end pushes them
    // ahead, at its speed, instead of passing over them (the deeper one
    // was left under the ply, 1.3 mm inside it by the overlap measure;
    // the shallow one put on top through the ply's thickness).
    for depth in [-0.05, -1.0] {
        let (mut x, mut c) = plies([10.2, depth]);
        for k in 0..40 {
            let v = step(&mut x, &mut c, Vector3::zeros(), 0.01);
            let end = x[1].x;
            for i in [5, 6] {
                assert_eq!(x[i].z, depth, "step {k}: {}", x[i]);
                assert!(
                    x[i].x >= end - NORMAL_TOLERANCE * 0.01,
                    "step {k}: {} behind {end}",
                    x[i]
                );
                if end > 10.2 {
                    // Pushed: at the end, moving with it, to the solve's
                    // tolerance of the step's 0.01 mm.
                    let tolerance = NORMAL_TOLERANCE * 0.01;
                    assert!((x[i].x - end).abs() < tolerance, "step {k}: {}", x[i]);
                    assert!((v[i].x - 10.0).abs() < tolerance / DT, "step {k}: {}", v[i]);
                }
            }
            assert!(
                c.max_overlap(&x) <= NORMAL_TOLERANCE * 0.01,
                "depth {depth}, step {k}"
            );
        }
    }
}

#[test]
fn a_node_coming_up_beside_the_end_is_shifted_not_thrown() {
    // 0.1 mm beside the end (within the offset, where the ply's face
    // holds a node on its own side), 0.05 mm behind the mid-plane, coming
    // up at 0.02 mm a step: past the mid-plane it is 0.28 mm inside the
    // face's hold, of which the step brought 0.02. The rest goes as a
    // shift of position: it leaves the step at the velocity it came with
    // stopped, not at 0.28 mm/ms (the old kick, which set the free edges
    // of the four-ply hemisphere flapping).
    let (mut x, mut c) = plies([10.1, -0.05]);
    let drive = Vector3::new(0.0, 0.0, 20.0);
    for _ in 0..2 {
        step(&mut x, &mut c, drive, 0.0);
        assert!(x[5].z < 0.0 && x[5].x == 10.1, "{}", x[5]);
    }
    let v = step(&mut x, &mut c, drive, 0.0);
    for i in [5, 6] {
        assert!((x[i].z - 0.3).abs() < 1e-9, "{}", x[i]);
        // Its velocity as it came (it moved away from the face, so the
        // step brought none of the violation).
        assert!((v[i] - drive).norm() < 1e-9, "{}", v[i]);
    }
}

#[test]
fn a_node_level_with_the_end_is_shifted_not_thrown() {
    // 0.1 mm beside the end, on the end's mid-plane but for 1e-9 mm
    // (the sign of a height that round-off decides), at rest: put on top
    // of the end as a shift of position, at rest still. Read as a node
    // resting on the edge, it was thrown up at 0.3 mm/ms.
    let (mut x, mut c) = plies([10.1, 1e-9]);
    let v = step(&mut x, &mut c, Vector3::zeros(), 0.0);
    for i in [5, 6] {
        assert!((x[i].z - 0.3).abs() < 1e-9, "{}", x[i]);
        assert!(v[i].norm() < 1e-9, "{}", v[i]);
    }
}

#[test]
fn a_node_come_in_through_the_end_is_shifted_not_thrown() {
    // 0.4 mm beside the end (clear of it), 0.02 mm over the mid-plane,
    // driven in at 0.5 mm a step: over the face, 0.28 mm inside its hold,
    // none of which the step's motion (along the face) brought. It goes
    // on top as a shift of position, its velocity as it came; as a
    // velocity it left at 280 mm/s upwards.
    let (mut x, mut c) = plies([10.4, 0.02]);
    let drive = Vector3::new(-500.0, 0.0, 0.0);
    let v = step(&mut x, &mut c, drive, 0.0);
    for i in [5, 6] {
        assert!((x[i].z - 0.3).abs() < 1e-9, "{}", x[i]);
        assert!((v[i] - drive).norm() < 1e-9, "{}", v[i]);
    }
}

#[test]
fn a_node_level_with_the_mid_plane_at_the_end_is_at_the_end_either_side() {
    // The two plies drawn under a fixed holder at t = 0.45 s: a `p45`
    // node on the die, level with `p0`'s mid-plane, held at `p0`'s end
    // plane by the end's row to 7.6e-5 mm. Its height over the mid-plane
    // is round-off of either sign; the overlap measure read it 0.5699 mm
    // inside (the offset) on the near side, and the run stopped.
    for height in [1e-12, -1e-12] {
        let (x, mut c) = plies([10.0 - 1e-4, height]);
        let overlap = c.record_overlap(&x).map_or(0.0, |o| o.depth);
        assert!(
            (overlap - 1e-4).abs() < 1e-9,
            "at {height} mm: {overlap} mm inside"
        );
    }
    // In front and clear of the end, the depth is the one below the
    // offset, as before.
    let (x, mut c) = plies([9.0, 0.2]);
    let overlap = c.record_overlap(&x).map_or(0.0, |o| o.depth);
    assert!((overlap - 0.1).abs() < 1e-9, "{overlap}");
}
