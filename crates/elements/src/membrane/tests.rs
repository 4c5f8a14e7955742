use super::*;
use crate::TrussBatch;
use crate::test_support::{assert_tangent_matches, random_rotation};
use drape_constitutive::FibreLaw;

fn carbon() -> Material {
    Material::preset("carbon-prepreg-2x2").unwrap()
}

fn glass() -> Material {
    Material::preset("glass-serge-4x3").unwrap()
}

/// A single element of each shape on a slightly non-planar, distorted
/// reference, with the warp at 30° to x.
fn single(
    shape: MembraneShape,
    material: Material,
    embedded: bool,
) -> (MembraneBatch, Vec<Vector3<f64>>) {
    let section = FabricSection::new(material, embedded);
    let warp = [Vector3::new(
        30f64.to_radians().cos(),
        30f64.to_radians().sin(),
        0.0,
    )];
    match shape {
        MembraneShape::Triangle => {
            let x0 = vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(5.0, 0.4, 0.1),
                Vector3::new(1.0, 4.5, -0.2),
            ];
            (
                MembraneBatch::triangles(section, &x0, vec![[0, 1, 2]], &warp).unwrap(),
                x0,
            )
        }
        MembraneShape::Quad => {
            let x0 = vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(5.0, 0.4, 0.2),
                Vector3::new(5.6, 4.8, -0.1),
                Vector3::new(-0.3, 4.2, 0.1),
            ];
            (
                MembraneBatch::quads(section, &x0, vec![[0, 1, 2, 3]], &warp).unwrap(),
                x0,
            )
        }
    }
}

/// x = Q·(A·X) + c with A a 3×3 in-plane-ish stretch: a general deformed state.
fn deform(x0: &[Vector3<f64>], a: &nalgebra::Matrix3<f64>, seed: u64) -> Vec<Vector3<f64>> {
    let q = random_rotation(seed);
    x0.iter()
        .enumerate()
        .map(|(i, p)| {
            q * (a * p) + Vector3::new(1.0, -2.0, 0.5) + Vector3::new(0.0, 0.0, 0.05 * i as f64)
        })
        .collect()
}

fn force(b: &MembraneBatch, x: &[Vector3<f64>], h: &[f64], dt: f64) -> Vec<Vector3<f64>> {
    let mut out = vec![0.0; h.len()];
    let mut f = vec![Vector3::zeros(); b.shape().nodes()];
    b.element_force(0, x, h, &mut out, dt, &mut f).unwrap();
    f
}

/// The history after one step from the reference state to `x`.
fn step_to(b: &MembraneBatch, x: &[Vector3<f64>], dt: f64) -> Vec<f64> {
    let h0 = b.initial_history();
    let mut h1 = h0.clone();
    let mut f = vec![Vector3::zeros(); b.shape().nodes()];
    b.element_force(0, x, &h0, &mut h1, dt, &mut f).unwrap();
    h1
}

#[test]
fn tangent_matches_finite_differences_for_every_kind() {
    // Stretch states: fibres stretched, one family compressed, both compressed.
    let stretches = [
        nalgebra::Matrix3::new(1.02, 0.05, 0.0, 0.03, 1.01, 0.0, 0.0, 0.0, 1.0),
        nalgebra::Matrix3::new(1.03, 0.2, 0.0, -0.1, 0.96, 0.0, 0.0, 0.0, 1.0),
        nalgebra::Matrix3::new(0.97, 0.3, 0.0, 0.25, 0.95, 0.0, 0.0, 0.0, 1.0),
    ];
    let mut seed = 0;
    for shape in [MembraneShape::Triangle, MembraneShape::Quad] {
        for material in [carbon(), glass()] {
            for embedded in [false, true] {
                let (b, x0) = single(shape, material.clone(), embedded);
                let nodes: Vec<usize> = (0..shape.nodes()).collect();
                for a in &stretches {
                    seed += 1;
                    // A committed state that is not the reference, then a trial step from it.
                    let h1 = step_to(&b, &deform(&x0, &(a * 0.99), seed), 0.01);
                    let x2 = deform(&x0, a, seed + 100);
                    let dt = 0.37;
                    let mut k = DMatrix::zeros(3 * shape.nodes(), 3 * shape.nodes());
                    b.element_tangent(0, &x2, &h1, dt, &mut k).unwrap();
                    assert_tangent_matches(&k, &x2, |x| force(&b, x, &h1, dt), &nodes);
                }
            }
        }
    }
}

#[test]
fn rigid_motion_rotates_forces_and_undeformed_is_force_free() {
    for shape in [MembraneShape::Triangle, MembraneShape::Quad] {
        let (b, x0) = single(shape, carbon(), true);
        let a = nalgebra::Matrix3::new(1.02, 0.15, 0.0, 0.1, 0.98, 0.0, 0.0, 0.0, 1.0);
        let x1 = deform(&x0, &a, 3);
        let h1 = step_to(&b, &x1, 0.0);
        let f1 = force(&b, &x1, &h1, 0.0);
        let q = random_rotation(11);
        let c = Vector3::new(-40.0, 7.0, 3.0);
        let x2: Vec<_> = x1.iter().map(|p| q * p + c).collect();
        let f2 = force(&b, &x2, &h1, 0.0);
        let scale = f1.iter().map(|f| f.norm()).fold(0.0, f64::max);
        assert!(scale > 1.0);
        // Undeformed, the forces vanish to round-off.
        let f0 = force(&b, &x0, &b.initial_history(), 0.1);
        assert!(f0.iter().all(|f| f.norm() < 1e-12 * scale), "{f0:?}");
        for (a, b) in f1.iter().zip(&f2) {
            assert!((q * a - b).norm() < 1e-12 * scale, "{a} vs {b}");
        }
        // The history does not change under a rigid motion either.
        let mut h2 = h1.clone();
        let mut f = vec![Vector3::zeros(); shape.nodes()];
        b.element_force(0, &x2, &h1, &mut h2, 0.0, &mut f).unwrap();
        for (u, v) in h1.iter().zip(&h2) {
            assert!((u - v).abs() < 1e-12 * (1.0 + u.abs()));
        }
    }
}

/// A 3×3 patch of distorted quads (or 18 triangles) in the xy plane on
/// [0, 3]², with the inner nodes moved off the grid.
fn patch(shape: MembraneShape, embedded: bool) -> (MembraneBatch, Vec<Vector3<f64>>, Vec<usize>) {
    let mut x0 = Vec::new();
    let mut inner = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            let mut p = Vector3::new(i as f64, j as f64, 0.0);
            if (1..3).contains(&i) && (1..3).contains(&j) {
                p += Vector3::new(
                    0.23 * (i as f64 - 1.4),
                    -0.17 * (j as f64 - 1.6) + 0.1 * i as f64,
                    0.0,
                );
                inner.push(x0.len());
            }
            x0.push(p);
        }
    }
    let id = |i: usize, j: usize| (j * 4 + i) as u32;
    let mut quads = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            quads.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let section = FabricSection::new(carbon(), embedded);
    let warp_dir = Vector3::new(0.6, 0.8, 0.0);
    let b = match shape {
        MembraneShape::Quad => {
            let warp = vec![warp_dir; quads.len()];
            MembraneBatch::quads(section, &x0, quads, &warp).unwrap()
        }
        MembraneShape::Triangle => {
            let tris: Vec<[u32; 3]> = quads
                .iter()
                .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
                .collect();
            let warp = vec![warp_dir; tris.len()];
            MembraneBatch::triangles(section, &x0, tris, &warp).unwrap()
        }
    };
    (b, x0, inner)
}

#[test]
fn patch_test_uniform_strain_gives_uniform_stress() {
    for shape in [MembraneShape::Triangle, MembraneShape::Quad] {
        for embedded in [false, true] {
            let (b, x0, inner) = patch(shape, embedded);
            let a = nalgebra::Matrix3::new(1.05, 0.12, 0.0, 0.04, 0.97, 0.0, 0.0, 0.0, 1.0);
            let x: Vec<_> = x0.iter().map(|p| a * p).collect();
            let h0 = b.initial_history();
            let mut h1 = h0.clone();
            let mut slots = vec![Vector3::zeros(); b.len() * shape.nodes()];
            b.forces_into(&x, &h0, &mut h1, 0.01, &mut slots).unwrap();
            // Every point's history (U and τ̄ in fibre axes) is the same.
            let stride = b.history_stride();
            let h1 = b.history_to_element_major(&h1);
            let first = &h1[..stride];
            let scale = first.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for point in h1.chunks(stride) {
                for (u, v) in point.iter().zip(first) {
                    assert!((u - v).abs() <= 1e-13 * scale, "{shape:?}: {u} vs {v}");
                }
            }
            // Inner nodes are in equilibrium.
            let mut net = vec![Vector3::zeros(); x.len()];
            for e in 0..b.len() {
                for (k, &n) in b.element_nodes(e).iter().enumerate() {
                    net[n as usize] += slots[e * shape.nodes() + k];
                }
            }
            let f_scale = net.iter().map(|f| f.norm()).fold(0.0, f64::max);
            for &n in &inner {
                assert!(
                    net[n].norm() <= 1e-12 * f_scale,
                    "{shape:?}: node {n} has {}",
                    net[n]
                );
            }
        }
    }
}

#[test]
fn embedded_fibres_equal_trusses_on_an_aligned_patch() {
    // A 4×3 grid of 2.5 × 2 cells aligned with the fibres, stretched
    // uniformly: the fibre part of the embedded membrane (with minus without
    // fibres) equals the trusses' forces, with A₀ = t_f·s (half on the edges).
    let material = carbon();
    let (nx, ny, dx, dy) = (4usize, 3usize, 2.5, 2.0);
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let x0: Vec<_> = (0..=ny)
        .flat_map(|j| (0..=nx).map(move |i| Vector3::new(i as f64 * dx, j as f64 * dy, 0.0)))
        .collect();
    let quads: Vec<[u32; 4]> = (0..ny)
        .flat_map(|j| {
            (0..nx).map(move |i| [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)])
        })
        .collect();
    let warp = vec![Vector3::x(); quads.len()];
    let with = MembraneBatch::quads(
        FabricSection::new(material.clone(), true),
        &x0,
        quads.clone(),
        &warp,
    )
    .unwrap();
    let without = MembraneBatch::quads(
        FabricSection::new(material.clone(), false),
        &x0,
        quads,
        &warp,
    )
    .unwrap();
    let t_f = material.family_thickness();
    let (mut nodes, mut section) = (Vec::new(), Vec::new());
    for j in 0..=ny {
        for i in 0..nx {
            nodes.push([id(i, j), id(i + 1, j)]);
            section.push(t_f * dy * if j == 0 || j == ny { 0.5 } else { 1.0 });
        }
    }
    for i in 0..=nx {
        for j in 0..ny {
            nodes.push([id(i, j), id(i, j + 1)]);
            section.push(t_f * dx * if i == 0 || i == nx { 0.5 } else { 1.0 });
        }
    }
    let trusses = TrussBatch::new(material.fibre, &x0, nodes, section).unwrap();

    let x: Vec<_> = x0
        .iter()
        .map(|p| Vector3::new(1.013 * p.x, 1.021 * p.y, 0.0))
        .collect();
    let gather = |slots: &[Vector3<f64>], conn: &dyn Fn(usize) -> Vec<u32>, per: usize| {
        let mut net = vec![Vector3::zeros(); x.len()];
        for (s, f) in slots.iter().enumerate() {
            net[conn(s / per)[s % per] as usize] += f;
        }
        net
    };
    let membrane_net = |b: &MembraneBatch| {
        let h0 = b.initial_history();
        let mut h1 = h0.clone();
        let mut slots = vec![Vector3::zeros(); 4 * b.len()];
        b.forces_into(&x, &h0, &mut h1, 0.0, &mut slots).unwrap();
        gather(&slots, &|e| b.element_nodes(e).to_vec(), 4)
    };
    let (fw, fo) = (membrane_net(&with), membrane_net(&without));
    let mut slots = vec![Vector3::zeros(); 2 * trusses.len()];
    trusses.forces_into(&x, &mut slots).unwrap();
    let ft = gather(&slots, &|e| trusses.nodes[e].to_vec(), 2);
    let scale = ft.iter().map(|f| f.norm()).fold(0.0, f64::max);
    assert!(scale > 1.0);
    for n in 0..x.len() {
        let fibre_part = fw[n] - fo[n];
        assert!(
            (fibre_part - ft[n]).norm() <= 1e-10 * scale,
            "node {n}: {fibre_part} vs {}",
            ft[n]
        );
    }
}

#[test]
fn stable_time_step_bounds_the_element_frequency() {
    // Element eigenvalue inequality: the global ω_max is at most the largest
    // element's, so Δt ≤ 2/ω_max(element, lumped mass) is sufficient.
    // Linear in tension and compression: at the reference ε = ±round-off,
    // and a yarn that buckles would have no stiffness on one side.
    let linear = Material {
        fibre: FibreLaw {
            compression_factor: 1.0,
            ..FibreLaw::new(230_000.0, 0.0).unwrap()
        },
        ..carbon()
    };
    for shape in [MembraneShape::Triangle, MembraneShape::Quad] {
        for embedded in [false, true] {
            let (b, x0) = single(shape, linear.clone(), embedded);
            let n = 3 * shape.nodes();
            let mut k = DMatrix::zeros(n, n);
            b.element_tangent(0, &x0, &b.initial_history(), 0.0, &mut k)
                .unwrap();
            let rho_h = linear.areal_density();
            let mut m_inv_sqrt = DMatrix::zeros(n, n);
            for (a, area) in b.nodal_areas(0).iter().enumerate() {
                for j in 0..3 {
                    m_inv_sqrt[(3 * a + j, 3 * a + j)] = 1.0 / (rho_h * area).sqrt();
                }
            }
            let sym = &m_inv_sqrt * (&k + k.transpose()) * 0.5 * &m_inv_sqrt;
            let omega_max = sym.symmetric_eigenvalues().max().sqrt();
            let dt = b.element_stable_time_step(0, &x0);
            let exact = 2.0 / omega_max;
            assert!(
                dt <= exact,
                "{shape:?} embedded={embedded}: estimate {dt:e} > 2/ω {exact:e}"
            );
            assert!(
                dt >= 0.6 * exact,
                "{shape:?} embedded={embedded}: estimate {dt:e} ≪ 2/ω {exact:e}"
            );
        }
    }
}

/// Largest deviation of the total energy of a free triangle (embedded linear
/// fibres, glass resin) released from a stretched state and integrated by
/// central differences with `fraction` of its stable step for `periods`
/// periods of its fastest mode, relative to the initial energy.
fn free_oscillation_energy_error(fraction: f64, periods: f64) -> f64 {
    let linear = Material {
        fibre: FibreLaw {
            compression_factor: 1.0,
            ..FibreLaw::new(75_000.0, 0.0).unwrap()
        },
        ..glass()
    };
    let (b, x0) = single(MembraneShape::Triangle, linear.clone(), true);
    let mass: Vec<f64> = b
        .nodal_areas(0)
        .iter()
        .map(|a| a * linear.areal_density())
        .collect();
    let mut x: Vec<_> = x0
        .iter()
        .map(|p| Vector3::new(1.002 * p.x, 0.999 * p.y, p.z))
        .collect();
    let mut v = vec![Vector3::zeros(); 3];
    let dt_stable = b.element_stable_time_step(0, &x0);
    let dt = fraction * dt_stable;
    // The stable step is 2/ω_max at best, so a period is at least π·dt_stable.
    let steps = (periods * std::f64::consts::PI * dt_stable / dt) as usize;
    let (mut h, mut h_next) = (b.initial_history(), b.initial_history());
    let mut f = vec![Vector3::zeros(); 3];
    b.element_force(0, &x, &h, &mut h_next, dt, &mut f).unwrap();
    std::mem::swap(&mut h, &mut h_next);
    let energy = |x: &[Vector3<f64>], v: &[Vector3<f64>], h: &[f64]| {
        let kinetic: f64 = v
            .iter()
            .zip(&mass)
            .map(|(v, m)| 0.5 * m * v.norm_squared())
            .sum();
        kinetic + b.element_energy(0, x, h).unwrap()
    };
    let e0 = energy(&x, &v, &h);
    let mut worst = 0.0f64;
    for step in 0..steps {
        // Half-step velocities, then positions, then forces at the new positions.
        for a in 0..3 {
            v[a] -= f[a] / mass[a] * (if step == 0 { 0.5 } else { 1.0 }) * dt;
            x[a] += v[a] * dt;
        }
        b.element_force(0, &x, &h, &mut h_next, dt, &mut f).unwrap();
        std::mem::swap(&mut h, &mut h_next);
        // Synchronise velocities to the full step for the kinetic energy.
        let v_full: Vec<_> = (0..3).map(|a| v[a] - f[a] / mass[a] * 0.5 * dt).collect();
        worst = worst.max((energy(&x, &v_full, &h) - e0).abs());
    }
    worst / e0
}

#[test]
fn free_element_keeps_its_energy() {
    // Central differences conserve a nearby energy: the measured one
    // oscillates by O((ω·Δt)²) without drift. Over 200 periods the error is
    // small and falls with the square of the step, so the element adds no
    // error of its own.
    let coarse = free_oscillation_energy_error(0.05, 200.0);
    let fine = free_oscillation_energy_error(0.025, 200.0);
    assert!(fine < 1e-3, "energy error {fine:e}");
    let order = (coarse / fine).log2();
    assert!(
        (order - 2.0).abs() < 0.2,
        "energy error order {order} ({coarse:e}, {fine:e})"
    );
}

/// A row of three unit quads along x (nodes 0–3 at y = 0, 4–7 at y = 1),
/// warp along x.
fn quad_row() -> (MembraneBatch, Vec<Vector3<f64>>) {
    let x0: Vec<_> = (0..8)
        .map(|i| Vector3::new((i % 4) as f64, (i / 4) as f64, 0.0))
        .collect();
    let nodes = vec![[0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6]];
    let batch = MembraneBatch::quads(
        FabricSection::new(glass(), false),
        &x0,
        nodes,
        &[Vector3::x(); 3],
    )
    .unwrap();
    (batch, x0)
}

fn forces_error(batch: &MembraneBatch, x: &[Vector3<f64>]) -> ElementError {
    let h = batch.initial_history();
    let mut out = h.clone();
    let mut slots = vec![Vector3::zeros(); 4 * batch.len()];
    batch
        .forces_into(x, &h, &mut out, 1e-5, &mut slots)
        .unwrap_err()
}

#[test]
fn a_degenerate_element_says_whether_it_folded_or_collapsed() {
    let (batch, x0) = quad_row();
    // The last quad squeezed to 1e-9 of its width, its free edge pushed
    // just past the shared one: turned over onto its neighbour.
    let mut x = x0.clone();
    x[3].x = 2.0 - 1e-9;
    x[7].x = 2.0 - 1e-9;
    let e = forces_error(&batch, &x);
    assert_eq!(e.element, 2);
    let KinematicsError::DegenerateMembrane(d) = e.cause else {
        panic!("{e}")
    };
    assert_eq!((d.inverted, d.folded), (Some(false), Some(true)), "{e}");
    assert!((d.stretches[0] - 1.0).abs() < 1e-9 && (d.stretches[1] - 1e-9).abs() < 1e-15);
    let message = e.to_string();
    assert!(
        message.contains("folded") && message.contains("element 2"),
        "{message}"
    );
    // Squeezed the same amount without turning over: collapsed.
    x[3].x = 2.0 + 1e-9;
    x[7].x = 2.0 + 1e-9;
    let e = forces_error(&batch, &x);
    let KinematicsError::DegenerateMembrane(d) = e.cause else {
        panic!("{e}")
    };
    assert_eq!((d.inverted, d.folded), (Some(false), Some(false)), "{e}");
    assert!(e.to_string().contains("collapsed"), "{e}");
    // Pulled 1e9 times its length: over-stretched.
    let mut x = x0.clone();
    x[3].x = 2.0 + 1e9;
    x[7].x = 2.0 + 1e9;
    let e = forces_error(&batch, &x);
    assert!(e.to_string().contains("over-stretched"), "{e}");
}

#[test]
fn a_quad_turned_inside_out_about_a_corner_is_inverted() {
    // The middle quad's corner 6 pulled across its diagonal to (1.2, 0.2):
    // the Gauss point next to it turns over, the others do not. (Judged
    // directly: such a point is not degenerate.)
    let (batch, x0) = quad_row();
    let mut x = x0.clone();
    x[6] = Vector3::new(1.2, 0.2, 0.0);
    let z: Vec<f64> = (0..4).map(|p| batch.weighted_normal(1, p, &x).z).collect();
    let p = z.iter().position(|&n| n < 0.0).expect("a turned point");
    assert!(z.iter().filter(|&&n| n > 0.0).count() >= 2, "{z:?}");
    let error = ElementError {
        element: 1,
        point: p,
        cause: KinematicsError::DegenerateMembrane(drape_kinematics::Degeneracy::from_invariants(
            1e-20, 1.0,
        )),
    };
    let KinematicsError::DegenerateMembrane(d) = batch.diagnose(error, &x).cause else {
        unreachable!()
    };
    assert_eq!(d.inverted, Some(true));
    // Other errors pass through unchanged.
    let other = ElementError {
        element: 1,
        point: 0,
        cause: KinematicsError::NonFinite { what: "F" },
    };
    assert_eq!(batch.diagnose(other, &x), other);
}

#[test]
fn output_fibre_directions_are_the_deformed_yarns() {
    // Under a uniform deformation x = A·X every element of the distorted
    // patch carries its yarns to A·N/|A·N|, and their angle closes by the
    // shear angle it reports.
    let a = nalgebra::Matrix3::new(1.05, 0.32, 0.0, 0.04, 0.97, 0.0, 0.1, -0.2, 1.0);
    let (warp, weft) = (Vector3::new(0.6, 0.8, 0.0), Vector3::new(-0.8, 0.6, 0.0));
    for shape in [MembraneShape::Triangle, MembraneShape::Quad] {
        let (b, x0, _) = patch(shape, true);
        let x: Vec<_> = x0.iter().map(|p| a * p).collect();
        let h = b.initial_history();
        for e in 0..b.len() {
            let o = b.element_output(e, &x, &b.element_history(&h, e)).unwrap();
            let [w, f] = o.fibre_direction;
            assert!(
                (w - (a * warp).normalize()).norm() < 1e-13,
                "{shape:?} {e}: {w}"
            );
            assert!(
                (f - (a * weft).normalize()).norm() < 1e-13,
                "{shape:?} {e}: {f}"
            );
            let angle = w.cross(&f).norm().atan2(w.dot(&f));
            assert!((std::f64::consts::FRAC_PI_2 - angle - o.shear_angle).abs() < 1e-13);
        }
    }
}

#[test]
fn output_fibre_directions_show_the_output_shear_under_a_varying_deformation() {
    // x = X + a bending, shearing field: the shear varies over each quad,
    // so its four points' directions and shears differ.
    let map = |p: &Vector3<f64>| {
        Vector3::new(
            p.x + 0.02 * p.x * p.y,
            p.y + 0.3 * p.x + 0.015 * p.x * p.x,
            0.01 * (p.x * p.x + p.y * p.y),
        )
    };
    let (warp, weft) = (Vector3::new(0.6, 0.8, 0.0), Vector3::new(-0.8, 0.6, 0.0));
    for shape in [MembraneShape::Triangle, MembraneShape::Quad] {
        let (b, x0, _) = patch(shape, true);
        let x: Vec<_> = x0.iter().map(map).collect();
        let h = b.initial_history();
        for e in 0..b.len() {
            let o = b.element_output(e, &x, &b.element_history(&h, e)).unwrap();
            let [w, f] = o.fibre_direction;
            assert!((w.norm() - 1.0).abs() < 1e-14 && (f.norm() - 1.0).abs() < 1e-14);
            let angle = w.cross(&f).norm().atan2(w.dot(&f));
            assert!(
                (std::f64::consts::FRAC_PI_2 - angle - o.shear_angle).abs() < 1e-13,
                "{shape:?} {e}: angle {angle}, shear {}",
                o.shear_angle
            );
            // And they are the yarns of the element: the mapped yarn
            // directions at its centroid, to the variation over it.
            let nodes = b.element_nodes(e);
            let c =
                nodes.iter().map(|&n| x0[n as usize]).sum::<Vector3<f64>>() / nodes.len() as f64;
            let yarn = |n: Vector3<f64>| (map(&(c + n * 1e-6)) - map(&(c - n * 1e-6))).normalize();
            for (got, n) in [(w, warp), (f, weft)] {
                let off = got.dot(&yarn(n)).clamp(-1.0, 1.0).acos().to_degrees();
                assert!(
                    off < 1.0,
                    "{shape:?} {e}: {off}° from the yarn at the centroid"
                );
            }
        }
    }
}
/// A 4 × 3 grid of resin-only quads (11 elements: two blocks of lanes and a
/// scalar tail of 3) on a wavy, distorted reference, with the warp at 20°.
fn lane_grid(material: Material) -> (MembraneBatch, Vec<Vector3<f64>>) {
    let (nx, ny) = (5usize, 4usize);
    let x0: Vec<Vector3<f64>> = (0..ny)
        .flat_map(|j| {
            (0..nx).map(move |i| {
                let (x, y) = (4.0 * i as f64, 3.5 * j as f64);
                Vector3::new(
                    x + 0.3 * (y * 0.7).sin(),
                    y + 0.2 * (x * 0.5).cos(),
                    0.1 * (x + y).sin(),
                )
            })
        })
        .collect();
    let mut quads = Vec::new();
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let n = (j * nx + i) as u32;
            quads.push([n, n + 1, n + 1 + nx as u32, n + nx as u32]);
        }
    }
    quads.pop();
    let warp =
        vec![Vector3::new(20f64.to_radians().cos(), 20f64.to_radians().sin(), 0.0); quads.len()];
    let batch =
        MembraneBatch::quads(FabricSection::new(material, false), &x0, quads, &warp).unwrap();
    (batch, x0)
}

/// The scalar path of the whole batch, element by element, with the same
/// step factors as `forces_into`: the slots, and the new history element
/// after element (as `history_to_element_major` gives a batch's).
fn scalar_forces(
    b: &MembraneBatch,
    x: &[Vector3<f64>],
    h_in: &[f64],
    dt: f64,
) -> Result<(Vec<Vector3<f64>>, Vec<f64>), ElementError> {
    let (nn, eh) = (4, b.element_history_len());
    let mut table = [(0.0, 0.0); 8];
    let resin = &b.section.material.resin;
    resin.prony_factors(dt, &mut table);
    let step = Step {
        dt,
        prony: &table[..resin.prony.len()],
    };
    let mut slots = vec![Vector3::zeros(); nn * b.len()];
    let mut h_out = vec![f64::NAN; h_in.len()];
    for e in 0..b.len() {
        b.element_force_with(
            e,
            x,
            Some(&b.element_history(h_in, e)),
            &mut h_out[e * eh..(e + 1) * eh],
            step,
            &mut slots[e * nn..(e + 1) * nn],
        )?;
    }
    Ok((slots, h_out))
}

#[test]
fn quad_lanes_equal_the_scalar_path_bit_for_bit() {
    for material in [carbon(), glass()] {
        let (b, x0) = lane_grid(material);
        assert!(b.lanes.as_ref().is_some_and(|l| l.blocks() == 2));
        let mut h = b.initial_history();
        // Three steps of a growing, rotating, shearing motion, so that U,
        // τ̄ and the Prony history are all non-trivial.
        for step in 1..=3 {
            let s = step as f64;
            let a = nalgebra::Matrix3::new(
                1.0 + 0.01 * s,
                0.03 * s,
                0.0,
                -0.01 * s,
                1.0 - 0.004 * s,
                0.0,
                0.002 * s,
                0.001,
                1.0,
            );
            let x = deform(&x0, &a, step);
            let dt = 1e-3 * s;
            let (expected, expected_h) = scalar_forces(&b, &x, &h, dt).unwrap();
            let mut slots = vec![Vector3::zeros(); 4 * b.len()];
            let mut h_out = vec![f64::NAN; h.len()];
            b.forces_into(&x, &h, &mut h_out, dt, &mut slots).unwrap();
            // The blocks really ran on the lanes (no fallback).
            let (eh, lanes) = (b.element_history_len(), b.lanes.as_ref().unwrap());
            let (mut f, mut out) = ([Vector3::zeros(); 16], vec![0.0; 4 * eh]);
            let resin = ResinStep {
                wave_modulus: b.section.material.resin.wave_modulus(),
                poisson: b.section.material.resin.poisson,
                shear_modulus: b.section.material.resin.shear_modulus(),
                long_term: 1.0,
                thickness: b.section.material.resin_thickness(),
                prony: &[(0.5, 0.1); 6][..b.section.material.resin.prony.len()],
            };
            assert!(lanes.block_forces(
                1,
                &b.nodes[16..32],
                &x,
                Some(&h[4 * eh..8 * eh]),
                &mut out,
                b.stride,
                &resin,
                &mut f
            ));
            // The baseline build of the kernel gives the dispatched one's
            // bits (on a processor with AVX2 the dispatch takes the other).
            let (mut f_base, mut out_base) = ([Vector3::zeros(); 16], vec![0.0; 4 * eh]);
            assert!(lanes.block_forces_lanes(
                1,
                &b.nodes[16..32],
                &x,
                Some(&h[4 * eh..8 * eh]),
                &mut out_base,
                b.stride,
                &resin,
                &mut f_base
            ));
            assert_eq!(f, f_base);
            assert!(same_bits(&out, &out_base));
            // And in place, over the committed values.
            let (mut f_in_place, mut in_place) =
                ([Vector3::zeros(); 16], h[4 * eh..8 * eh].to_vec());
            assert!(lanes.block_forces(
                1,
                &b.nodes[16..32],
                &x,
                None,
                &mut in_place,
                b.stride,
                &resin,
                &mut f_in_place
            ));
            assert_eq!(f, f_in_place);
            assert!(same_bits(&out, &in_place));
            // A block with a quad squeezed onto a line writes nothing.
            let mut collapsed = x.clone();
            let nodes = b.element_nodes(7).to_vec();
            let (p, q) = (x[nodes[0] as usize], x[nodes[1] as usize]);
            for (k, &n) in nodes.iter().enumerate() {
                collapsed[n as usize] = p + (q - p) * (k as f64 * 0.3);
            }
            let mut untouched = h[4 * eh..8 * eh].to_vec();
            let mut f_none = [Vector3::new(7.0, 7.0, 7.0); 16];
            assert!(!lanes.block_forces(
                1,
                &b.nodes[16..32],
                &collapsed,
                None,
                &mut untouched,
                b.stride,
                &resin,
                &mut f_none
            ));
            assert_eq!(untouched, h[4 * eh..8 * eh]);
            assert!(f_none.iter().all(|v| *v == Vector3::new(7.0, 7.0, 7.0)));
            // Stated round-off: none. The lanes do the scalar operations in
            // the scalar order, without fused multiply-adds.
            for (e, (f, g)) in slots.iter().zip(&expected).enumerate() {
                assert_eq!(f, g, "slot {e}, step {step}");
                assert!(f.norm() > 0.0);
            }
            let h_elements = b.history_to_element_major(&h_out);
            for (k, (v, w)) in h_elements.iter().zip(&expected_h).enumerate() {
                assert_eq!(v.to_bits(), w.to_bits(), "history value {k}, step {step}");
            }
            h = h_out;
        }
    }
}

#[test]
fn updating_the_history_in_place_gives_the_bits_of_a_second_array() {
    // Lane blocks with and without Prony terms, the scalar path (embedded
    // fibres), triangles: each over three steps of a general motion.
    let (lanes_carbon, x0) = lane_grid(carbon());
    let (lanes_glass, _) = lane_grid(glass());
    let quads: Vec<[u32; 4]> = lanes_carbon
        .nodes
        .chunks_exact(4)
        .map(|q| [q[0], q[1], q[2], q[3]])
        .collect();
    let triangles: Vec<[u32; 3]> = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    let warp = |n: usize| vec![Vector3::new(0.8, 0.6, 0.0); n];
    let embedded = MembraneBatch::quads(
        FabricSection::new(carbon(), true),
        &x0,
        quads.clone(),
        &warp(quads.len()),
    )
    .unwrap();
    let tri = MembraneBatch::triangles(
        FabricSection::new(glass(), false),
        &x0,
        triangles.clone(),
        &warp(triangles.len()),
    )
    .unwrap();
    assert!(embedded.lanes.is_none() && tri.lanes.is_none());
    for b in [&lanes_carbon, &lanes_glass, &embedded, &tri] {
        let mut h = b.initial_history();
        for step in 1..=3u64 {
            let s = step as f64;
            let a = nalgebra::Matrix3::new(
                1.0 + 0.02 * s,
                0.04 * s,
                0.0,
                -0.01 * s,
                1.0 - 0.006 * s,
                0.0,
                0.002 * s,
                0.001,
                1.0,
            );
            let x = deform(&x0, &a, step);
            let dt = 2e-3 * s;
            let nn = b.shape().nodes();
            let (mut expected, mut expected_h) = (
                vec![Vector3::zeros(); nn * b.len()],
                vec![f64::NAN; h.len()],
            );
            b.forces_into(&x, &h, &mut expected_h, dt, &mut expected)
                .unwrap();
            let mut slots = vec![Vector3::zeros(); nn * b.len()];
            b.forces_in_place(&x, &mut h, dt, &mut slots).unwrap();
            // Stated round-off: none.
            assert_eq!(slots, expected, "{:?}, step {step}", b.shape());
            for (k, (v, w)) in h.iter().zip(&expected_h).enumerate() {
                assert_eq!(v.to_bits(), w.to_bits(), "history value {k}, step {step}");
            }
            assert!(h.iter().zip(&b.initial_history()).any(|(v, w)| v != w));
        }
    }
    // A degenerate element (in a lane block, then in the scalar tail) is
    // named and diagnosed as from a second array.
    for e in [5, 9] {
        let mut x = x0.clone();
        let nodes = lanes_carbon.element_nodes(e).to_vec();
        let (p, q) = (x[nodes[0] as usize], x[nodes[1] as usize]);
        for (k, &n) in nodes.iter().enumerate() {
            x[n as usize] = p + (q - p) * (k as f64 * 0.3);
        }
        let h = lanes_carbon.initial_history();
        let mut slots = vec![Vector3::zeros(); 4 * lanes_carbon.len()];
        let expected = lanes_carbon
            .forces_into(&x, &h, &mut h.clone(), 1e-3, &mut slots)
            .unwrap_err();
        let err = lanes_carbon
            .forces_in_place(&x, &mut h.clone(), 1e-3, &mut slots)
            .unwrap_err();
        assert_eq!(err, expected);
        assert_eq!(err.element, e);
    }
}

#[test]
fn lane_stable_steps_equal_the_scalar_estimate_bit_for_bit() {
    use crate::quad_lanes::{StepBound, block_stable_steps_lanes};
    for material in [carbon(), glass()] {
        let (b, x0) = lane_grid(material);
        let lanes = b.lanes.as_ref().unwrap();
        let bound = StepBound {
            kappa: b.stiffness_bound(),
            rho_h: b.section.material.areal_density(),
            gauss: GAUSS,
        };
        let scale: Vec<f64> = (0..b.len()).map(|e| 1.0 + 0.37 * e as f64).collect();
        for seed in 0..6u64 {
            let s = seed as f64;
            let a = nalgebra::Matrix3::new(
                1.0 + 0.05 * s,
                0.2 * (s - 2.0),
                0.01,
                -0.03 * s,
                1.0 - 0.04 * s,
                0.02,
                0.01 * s,
                -0.02,
                1.0,
            );
            let mut x = deform(&x0, &a, seed);
            // Seed 4: a quad of the first block squeezed flat (0 there);
            // seed 5: a NaN in the second block (0 too).
            if seed == 4 {
                let nodes = b.element_nodes(1).to_vec();
                let (p, q) = (x[nodes[0] as usize], x[nodes[1] as usize]);
                for (k, &n) in nodes.iter().enumerate() {
                    x[n as usize] = p + (q - p) * (k as f64 * 0.3);
                }
            }
            if seed == 5 {
                x[b.element_nodes(6)[2] as usize].y = f64::NAN;
            }
            let mut zeros = 0;
            for blk in 0..lanes.blocks() {
                let r = blk * 16..(blk + 1) * 16;
                for kernel in [
                    lanes.block_stable_steps(
                        &b.nodes[r.clone()],
                        &x,
                        &b.nodal_area[r.clone()],
                        bound,
                    ),
                    block_stable_steps_lanes(&b.nodes[r.clone()], &x, &b.nodal_area[r], bound),
                ] {
                    for (k, dt) in kernel.iter().enumerate() {
                        let e = blk * 4 + k;
                        let expected = b.element_stable_time_step(e, &x);
                        assert_eq!(dt.to_bits(), expected.to_bits(), "element {e}, seed {seed}");
                        zeros += usize::from(*dt == 0.0);
                    }
                }
            }
            assert_eq!(zeros > 0, seed >= 4, "seed {seed}: {zeros} zeros");
            let expected = (0..b.len())
                .map(|e| b.element_stable_time_step(e, &x) * scale[e])
                .fold(f64::INFINITY, f64::min);
            let got = b.min_scaled_stable_time_step(&x, &scale);
            assert_eq!(got.to_bits(), expected.to_bits(), "seed {seed}");
        }
    }
}

#[test]
fn a_degenerate_quad_in_a_block_is_named_and_diagnosed_as_on_the_scalar_path() {
    let (b, x0) = lane_grid(carbon());
    let h = b.initial_history();
    // Collapse element 5 (in the second block) onto a line.
    let mut x = x0.clone();
    let nodes = b.element_nodes(5).to_vec();
    let (p, q) = (x[nodes[0] as usize], x[nodes[1] as usize]);
    for (k, &n) in nodes.iter().enumerate() {
        x[n as usize] = p + (q - p) * (k as f64 * 0.3);
    }
    let expected = b.diagnose(scalar_forces(&b, &x, &h, 1e-3).unwrap_err(), &x);
    let mut slots = vec![Vector3::zeros(); 4 * b.len()];
    let mut h_out = h.clone();
    let err = b
        .forces_into(&x, &h, &mut h_out, 1e-3, &mut slots)
        .unwrap_err();
    assert_eq!(err, expected);
    // A NaN in the scalar tail (element 9) is named too.
    let mut x = x0;
    x[b.element_nodes(9)[2] as usize].x = f64::NAN;
    let err = b
        .forces_into(&x, &h, &mut h_out, 1e-3, &mut slots)
        .unwrap_err();
    assert_eq!(
        err,
        b.diagnose(scalar_forces(&b, &x, &h, 1e-3).unwrap_err(), &x)
    );
    assert_eq!(err.element, 9);
}

/// Glass with a stiff shear-locking law (locking past ~40°).
fn locking_glass() -> Material {
    let mut m = glass();
    m.resin.shear_locking = Some(drape_constitutive::ShearLocking {
        coefficients: vec![0.05, 0.0, 3.0],
        friction: None,
    });
    m.validate().unwrap();
    m
}

/// In-plane stretches that shear the fibres by 15–50°.
fn shearing() -> [nalgebra::Matrix3<f64>; 3] {
    [
        nalgebra::Matrix3::new(1.0, 0.25, 0.0, 0.05, 1.0, 0.0, 0.0, 0.0, 1.0),
        nalgebra::Matrix3::new(1.02, 0.5, 0.0, 0.3, 0.99, 0.0, 0.0, 0.0, 1.0),
        nalgebra::Matrix3::new(0.98, -0.6, 0.0, -0.4, 1.01, 0.0, 0.0, 0.0, 1.0),
    ]
}

#[test]
fn shear_locking_tangent_matches_finite_differences() {
    let mut seed = 500;
    for shape in [MembraneShape::Triangle, MembraneShape::Quad] {
        for embedded in [false, true] {
            let (b, x0) = single(shape, locking_glass(), embedded);
            let nodes: Vec<usize> = (0..shape.nodes()).collect();
            for a in &shearing() {
                seed += 1;
                let h1 = step_to(&b, &deform(&x0, &(a * 0.99), seed), 0.01);
                let x2 = deform(&x0, a, seed + 100);
                let mut k = DMatrix::zeros(3 * shape.nodes(), 3 * shape.nodes());
                b.element_tangent(0, &x2, &h1, 0.2, &mut k).unwrap();
                assert_tangent_matches(&k, &x2, |x| force(&b, x, &h1, 0.2), &nodes);
            }
        }
    }
}

#[test]
fn shear_locking_force_is_the_gradient_of_its_energy() {
    // Same history with and without the law: the force difference is the
    // law's, and must be ∂(h·w(γ)·A)/∂x; it rotates with a rigid motion.
    for shape in [MembraneShape::Triangle, MembraneShape::Quad] {
        // Fibres as trusses: their large energy would drown the law's in
        // the finite difference.
        let (with, x0) = single(shape, locking_glass(), false);
        let (without, _) = single(shape, glass(), false);
        let x = deform(&x0, &shearing()[1], 9);
        let h = with.initial_history();
        let law_force: Vec<_> = force(&with, &x, &h, 0.0)
            .iter()
            .zip(force(&without, &x, &h, 0.0))
            .map(|(a, b)| a - b)
            .collect();
        let law_energy = |x: &[Vector3<f64>]| {
            with.element_energy(0, x, &h).unwrap() - without.element_energy(0, x, &h).unwrap()
        };
        assert!(law_energy(&x) > 0.0);
        let scale = law_force.iter().map(|f| f.amax()).fold(0.0, f64::max);
        let step = 1e-6;
        for n in 0..shape.nodes() {
            for c in 0..3 {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[n][c] += step;
                xm[n][c] -= step;
                let fd = (law_energy(&xp) - law_energy(&xm)) / (2.0 * step);
                assert!(
                    (fd - law_force[n][c]).abs() < 1e-6 * scale,
                    "{shape:?} node {n}: {fd} vs {}",
                    law_force[n][c]
                );
            }
        }
        let q = random_rotation(4);
        let xr: Vec<_> = x.iter().map(|p| q * p).collect();
        for (a, b) in force(&with, &x, &h, 0.0)
            .iter()
            .zip(force(&with, &xr, &h, 0.0))
        {
            assert!((q * a - b).norm() < 1e-10 * scale);
        }
    }
}

#[test]
fn a_membrane_without_the_law_is_unchanged_and_with_it_stiffer() {
    let (with, x0) = single(MembraneShape::Quad, locking_glass(), false);
    let (without, _) = single(MembraneShape::Quad, glass(), false);
    let x = deform(&x0, &shearing()[1], 2);
    // Undeformed: no stress from the law beyond round-off.
    let h = with.initial_history();
    for (a, b) in force(&with, &x0, &h, 0.1)
        .iter()
        .zip(force(&without, &x0, &h, 0.1))
    {
        assert!((a - b).norm() < 1e-13, "{a} vs {b}");
    }
    // Sheared ~45°: the law stiffens and shortens the step.
    assert!(with.element_stable_time_step(0, &x) < without.element_stable_time_step(0, &x));
}

#[test]
fn a_batch_with_the_locking_law_feels_it_in_every_element() {
    // Quads with the law stay off the lanes (which carry the paper's resin
    // only): the batch's forces are the per-element ones, law included.
    let (with, x0) = lane_grid(locking_glass());
    let (without, _) = lane_grid(glass());
    assert!(with.lanes.is_none() && without.lanes.is_some());
    let x = deform(&x0, &shearing()[1], 3);
    let h = with.initial_history();
    let (expected, _) = scalar_forces(&with, &x, &h, 1e-3).unwrap();
    let (plain, _) = scalar_forces(&without, &x, &h, 1e-3).unwrap();
    let mut slots = vec![Vector3::zeros(); 4 * with.len()];
    let mut h_out = h.clone();
    with.forces_into(&x, &h, &mut h_out, 1e-3, &mut slots)
        .unwrap();
    for (e, ((f, g), p)) in slots.iter().zip(&expected).zip(&plain).enumerate() {
        assert_eq!(f, g, "slot {e}");
        assert!(
            (f - p).norm() > 1e-6 * p.norm(),
            "slot {e}: no law in the force"
        );
    }
}

#[test]
fn lane_blocks_keep_history_value_major_behind_the_element_accessor() {
    let (b, _) = lane_grid(carbon());
    let (eh, stride) = (b.element_history_len(), b.history_stride());
    assert_eq!((b.blocked, eh), (8, 4 * stride));
    // Every element starts at U = I, τ̄ = 0, whatever its storage.
    let h0 = b.initial_history();
    for e in 0..b.len() {
        let h = b.element_history(&h0, e);
        for p in 0..4 {
            let point = &h[p * stride..(p + 1) * stride];
            assert_eq!(point[..2], [1.0, 1.0], "element {e} point {p}");
            assert!(point[2..].iter().all(|&v| v == 0.0));
        }
    }
    // Distinct values element after element: the batch keeps value i of
    // point p of element e (in a block) at (e/4)·4·eh + (p·stride + i)·4 + e%4,
    // and the tail (elements 8..11) element after element.
    let values: Vec<f64> = (0..b.len() * eh).map(|k| k as f64).collect();
    let h = b.history_from_element_major(&values);
    for e in 0..b.len() {
        for p in 0..4 {
            for i in 0..stride {
                let at = if e < 8 {
                    (e / 4) * 4 * eh + (p * stride + i) * 4 + e % 4
                } else {
                    e * eh + p * stride + i
                };
                assert_eq!(h[at], values[e * eh + p * stride + i], "{e} {p} {i}");
            }
        }
        assert_eq!(*b.element_history(&h, e), values[e * eh..(e + 1) * eh]);
    }
    assert_eq!(b.history_to_element_major(&h), values);
    // Writing one element leaves the others as they were.
    let mut written = h.clone();
    b.set_element_history(&mut written, 5, &vec![-1.0; eh]);
    for e in 0..b.len() {
        let expected = if e == 5 {
            vec![-1.0; eh]
        } else {
            values[e * eh..(e + 1) * eh].to_vec()
        };
        assert_eq!(*b.element_history(&written, e), expected, "element {e}");
    }
}

/// Whether `a` and `b` hold the same values bit for bit.
fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

#[test]
fn the_tensile_part_of_a_stress_keeps_its_positive_principal_values() {
    for (a, b, c) in [
        (3.0, 1.0, 0.5),
        (3.0, -1.0, 0.5),
        (-3.0, 1.0, 2.5),
        (-3.0, -1.0, 0.5),
        (0.0, 0.0, 1.0),
        (2.0, 2.0, 0.0),
    ] {
        let tau = Matrix2::new(a, c, c, b);
        let expected = {
            let se = tau.symmetric_eigen();
            let mut m = Matrix2::<f64>::zeros();
            for k in 0..2 {
                let n = se.eigenvectors.column(k);
                m += n * n.transpose() * f64::max(se.eigenvalues[k], 0.0);
            }
            m
        };
        let got = tensile_part(&tau);
        assert!(
            (got - expected).amax() <= 1e-14 * tau.amax(),
            "{tau}: {got} vs {expected}"
        );
    }
}

/// The resin's stress (τ̄, local frame) at each point after a trial step.
fn point_stresses(b: &MembraneBatch, x: &[Vector3<f64>], h: &[f64], dt: f64) -> Vec<Matrix2<f64>> {
    let mut out = vec![0.0; h.len()];
    let mut f = vec![Vector3::zeros(); b.shape().nodes()];
    b.element_force(0, x, h, &mut out, dt, &mut f).unwrap();
    (0..b.shape().points())
        .map(|p| sym_from(&out[p * b.stride + 3..p * b.stride + 6]))
        .collect()
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]

    /// The tension-field tangent of a resin membrane (the yarns as
    /// trusses) is positive semi-definite in any state, and equals the
    /// exact tangent bit for bit where every point's resin is in tension;
    /// the exact one is indefinite where the resin is compressed enough
    /// (counted: the property would hold trivially if it never were).
    #[test]
    fn the_tension_field_tangent_is_positive_semidefinite_and_exact_in_tension(
        quad in proptest::bool::ANY,
        a11 in 0.9..1.1f64, a22 in 0.9..1.1f64, a12 in -0.3..0.3f64, a21 in -0.3..0.3f64,
        committed in 0.0..1.0f64, seed in 0u64..1000,
    ) {
        let shape = if quad { MembraneShape::Quad } else { MembraneShape::Triangle };
        let (b, x0) = single(shape, carbon(), false);
        let a = nalgebra::Matrix3::new(a11, a12, 0.0, a21, a22, 0.0, 0.0, 0.0, 1.0);
        // A committed state part of the way there, then the trial state.
        let partial = nalgebra::Matrix3::identity() * (1.0 - committed) + a * committed;
        let h1 = step_to(&b, &deform(&x0, &partial, seed), 0.01);
        let x2 = deform(&x0, &a, seed + 1);
        let dt = 0.37;
        let d = 3 * shape.nodes();
        let (mut exact, mut field) = (DMatrix::zeros(d, d), DMatrix::zeros(d, d));
        b.element_tangent_with(0, &x2, &h1, dt, MembraneTangent::Exact, &mut exact).unwrap();
        b.element_tangent_with(0, &x2, &h1, dt, MembraneTangent::TensionField, &mut field)
            .unwrap();
        let sym = |k: &DMatrix<f64>| (k + k.transpose()) * 0.5;
        let lowest = |k: &DMatrix<f64>| {
            let e = sym(k).symmetric_eigenvalues();
            e.min() / e.max()
        };
        // Rigid motions are null vectors: zero to round-off.
        proptest::prop_assert!(lowest(&field) >= -1e-12, "tension field: {:e}", lowest(&field));
        let tension = point_stresses(&b, &x2, &h1, dt)
            .iter()
            .all(|t| t.symmetric_eigenvalues().min() >= 0.0);
        if tension {
            proptest::prop_assert_eq!(&field, &exact);
        } else {
            proptest::prop_assert!(field != exact);
        }
        // The scaled compression: 0 is the tension field, 1 the exact
        // tangent (to round-off: τ⁺ + (τ − τ⁺) is τ to the last bits).
        let mut scaled = DMatrix::zeros(d, d);
        b.element_tangent_with(0, &x2, &h1, dt, MembraneTangent::CompressionScaled(0.0), &mut scaled)
            .unwrap();
        proptest::prop_assert_eq!(&scaled, &field);
        b.element_tangent_with(0, &x2, &h1, dt, MembraneTangent::CompressionScaled(1.0), &mut scaled)
            .unwrap();
        proptest::prop_assert!((&scaled - &exact).amax() <= 1e-12 * exact.amax());
    }
}

#[test]
fn the_exact_tangent_of_a_compressed_resin_membrane_is_indefinite() {
    // Biaxial compression: the negative geometric stiffness out of plane
    // that the tension field removes.
    for shape in [MembraneShape::Triangle, MembraneShape::Quad] {
        let (b, x0) = single(shape, carbon(), false);
        let a = nalgebra::Matrix3::new(0.98, 0.0, 0.0, 0.0, 0.97, 0.0, 0.0, 0.0, 1.0);
        let x2 = deform(&x0, &a, 5);
        let h0 = b.initial_history();
        let d = 3 * shape.nodes();
        let (mut exact, mut field) = (DMatrix::zeros(d, d), DMatrix::zeros(d, d));
        b.element_tangent_with(0, &x2, &h0, 0.1, MembraneTangent::Exact, &mut exact)
            .unwrap();
        b.element_tangent_with(0, &x2, &h0, 0.1, MembraneTangent::TensionField, &mut field)
            .unwrap();
        let lowest = |k: &DMatrix<f64>| {
            let e = ((k + k.transpose()) * 0.5).symmetric_eigenvalues();
            e.min() / e.max()
        };
        assert!(lowest(&exact) < -1e-3, "{shape:?}: {:e}", lowest(&exact));
        assert!(lowest(&field) >= -1e-12, "{shape:?}: {:e}", lowest(&field));
    }
}

#[test]
fn the_tangent_after_the_forces_is_the_tangent_bit_for_bit() {
    // The forces' new history at x holds the stress the tangent would
    // update again: read from it, the matrix is the same, on the lanes'
    // blocks and on the scalar tail, with Prony history (carbon) and
    // without (glass), for every kind of membrane tangent.
    for material in [carbon(), glass()] {
        let (b, x0) = lane_grid(material);
        let a = nalgebra::Matrix3::new(0.98, 0.04, 0.0, -0.02, 0.97, 0.0, 0.003, 0.001, 1.0);
        let mut h = b.initial_history();
        let mut slots = vec![Vector3::zeros(); 4 * b.len()];
        let mut h_half = vec![f64::NAN; h.len()];
        b.forces_into(
            &deform(&x0, &(a * 0.995), 3),
            &h,
            &mut h_half,
            2e-3,
            &mut slots,
        )
        .unwrap();
        h = h_half;
        let x = deform(&x0, &a, 4);
        let dt = 3e-3;
        let mut h_next = vec![f64::NAN; h.len()];
        b.forces_into(&x, &h, &mut h_next, dt, &mut slots).unwrap();
        let mut compressed = 0;
        for kind in [
            MembraneTangent::Exact,
            MembraneTangent::TensionField,
            MembraneTangent::CompressionScaled(0.3),
        ] {
            for e in 0..b.len() {
                let (mut k, mut k_after) = (DMatrix::zeros(12, 12), DMatrix::zeros(12, 12));
                let committed = b.element_history(&h, e);
                b.element_tangent_with(e, &x, &committed, dt, kind, &mut k)
                    .unwrap();
                b.element_tangent_after_forces(
                    e,
                    &x,
                    &committed,
                    &b.element_history(&h_next, e),
                    dt,
                    kind,
                    &mut k_after,
                )
                .unwrap();
                assert!(
                    same_bits(k.as_slice(), k_after.as_slice()),
                    "{kind:?}, element {e}"
                );
                if kind != MembraneTangent::Exact {
                    continue;
                }
                // The committed stress would give another matrix: the
                // comparison sees which one was read.
                let mut other = DMatrix::zeros(12, 12);
                b.element_tangent_after_forces(e, &x, &committed, &committed, dt, kind, &mut other)
                    .unwrap();
                assert!(other != k, "element {e}");
                b.element_tangent_with(
                    e,
                    &x,
                    &committed,
                    dt,
                    MembraneTangent::TensionField,
                    &mut other,
                )
                .unwrap();
                compressed += usize::from(other != k);
            }
        }
        // Some points are compressed, so the kinds differ.
        assert!(compressed > 0);
    }
}
