//! The ply pass gives the same bits whatever the thread count: its
//! narrow phase runs the searches side by side and each in tasks, so a
//! stack large enough to split is passed on pools of one, two and three
//! threads and everything it writes is compared bit for bit.

use nalgebra::Vector3;

use super::{PlyContact, PlyInterface, PlyLayer};

/// Nodes per side of each ply's grid: 25 × 25 = 625 slave nodes per
/// search, more than two tasks of [`super::NODES_PER_TASK`].
const SIDE: u32 = 25;

/// Three 24 × 24 mm plies of unit cells (quads split in two), 0.3 mm
/// thick, 0.28 mm apart (0.02 mm inside each other) under a bump that
/// varies the depth, the middle ply shifted by a third of a cell so its
/// nodes are not over the others'.
fn stack() -> (Vec<Vector3<f64>>, PlyContact) {
    let mut x = Vec::new();
    let mut layers = Vec::new();
    for ply in 0..3u32 {
        let first = x.len() as u32;
        let shift = if ply == 1 { 1.0 / 3.0 } else { 0.0 };
        for j in 0..SIDE {
            for i in 0..SIDE {
                let (px, py) = (f64::from(i) + shift, f64::from(j) + shift);
                let bump = 0.01 * ((0.3 * px).sin() * (0.2 * py).cos());
                x.push(Vector3::new(px, py, 0.28 * f64::from(ply) + bump));
            }
        }
        let mut faces = Vec::new();
        for j in 0..SIDE - 1 {
            for i in 0..SIDE - 1 {
                let n = first + j * SIDE + i;
                faces.push([n, n + 1, n + SIDE + 1]);
                faces.push([n, n + SIDE + 1, n + SIDE]);
            }
        }
        layers.push(PlyLayer {
            first_node: first,
            node_count: SIDE * SIDE,
            faces,
            half_thickness: 0.15,
        });
    }
    let interface = |lower, upper| PlyInterface {
        lower,
        upper,
        friction: 0.3,
    };
    let n = x.len();
    let contact = PlyContact::new(
        layers,
        &[interface(0, 1), interface(1, 2)],
        vec![1.0; n],
        1.0,
    );
    (x, contact)
}

/// Bits of a list of vectors.
fn bits(v: &[Vector3<f64>]) -> Vec<[u64; 3]> {
    v.iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

/// What the pass leaves, as bits: positions, velocities, forces, and the
/// slip, pressure and dissipation.
type Outcome = (Vec<[u64; 3]>, Vec<[u64; 3]>, Vec<[u64; 3]>, Vec<u64>);

/// Ten steps on a pool of `threads`: the top ply sliding along x and
/// pressed down, the bottom ply fixed.
fn run(threads: usize) -> Outcome {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let (mut x, mut contact) = stack();
        let n = x.len();
        let top = 2 * (SIDE * SIDE) as usize;
        let mut v = vec![Vector3::zeros(); n];
        for vi in &mut v[top..] {
            *vi = Vector3::new(0.5, 0.0, -0.2);
        }
        let mass = vec![1e-3; n];
        let movable: Vec<bool> = (0..n).map(|i| i >= (SIDE * SIDE) as usize).collect();
        let mut force = vec![Vector3::zeros(); n];
        let (dt, tau) = (1e-3, 1e-3);
        let mut active = 0;
        for _ in 0..10 {
            for (p, vi) in x.iter_mut().zip(&v) {
                *p += vi * dt;
            }
            force.iter_mut().for_each(|f| *f = Vector3::zeros());
            let step = contact.normal(
                &mut x,
                &mut v,
                &mass,
                &movable,
                dt,
                tau,
                &mut [],
                &mut [],
                &mut force,
            );
            active = active.max(step.active);
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
        }
        // Both interfaces in contact over much of the plies, or the test
        // would compare little.
        assert!(active > 500, "{active}");
        let mut scalars: Vec<u64> = contact.slip.iter().map(|s| s.to_bits()).collect();
        scalars.extend(contact.pressure.iter().map(|p| p.to_bits()));
        scalars.push(contact.friction_dissipation.to_bits());
        (bits(&x), bits(&v), bits(&force), scalars)
    })
}

#[test]
fn a_stack_gives_the_same_bits_on_one_two_and_three_threads() {
    let one = run(1);
    assert!(one.3.iter().any(|&s| f64::from_bits(s) > 0.0));
    assert!(run(2) == one, "two threads differ from one");
    assert!(run(3) == one, "three threads differ from one");
}
