//! The net on a sphere against the analytic Chebyshev net (see the crate
//! docs for the derivation): with orthogonal geodesic generators through
//! the pole, the shear at arc lengths (u, v) is γ(uv/R²), where
//! (z γ′)′ = cos γ, γ(0) = 0. The reference is integrated here, by RK4 from
//! the series γ = z − z³/18 near 0, independently of the crate.

use drape_contact::Surface;
use drape_fishnet::{Net, NetSpec};
use drape_model::blank::BlankFrame;
use nalgebra::Vector3;

/// γ(z) of the Chebyshev net on a sphere, to about 1e-13 rad for |z| ≤ 2.
fn chebyshev_shear(z: f64) -> f64 {
    if z == 0.0 {
        return 0.0;
    }
    // Odd in z.
    let (sign, z) = (z.signum(), z.abs());
    let z0 = z.min(1e-3);
    // γ = z − z³/18 + O(z⁵), w = zγ′ = z − z³/6 + O(z⁵).
    let mut y = [z0 - z0.powi(3) / 18.0, z0 - z0.powi(3) / 6.0];
    let f = |t: f64, y: [f64; 2]| [y[1] / t, y[0].cos()];
    let n = 4000;
    let h = (z - z0) / n as f64;
    let mut t = z0;
    for _ in 0..n {
        let k1 = f(t, y);
        let k2 = f(
            t + h / 2.0,
            [y[0] + h / 2.0 * k1[0], y[1] + h / 2.0 * k1[1]],
        );
        let k3 = f(
            t + h / 2.0,
            [y[0] + h / 2.0 * k2[0], y[1] + h / 2.0 * k2[1]],
        );
        let k4 = f(t + h, [y[0] + h * k3[0], y[1] + h * k3[1]]);
        for k in 0..2 {
            y[k] += h / 6.0 * (k1[k] + 2.0 * k2[k] + 2.0 * k3[k] + k4[k]);
        }
        t += h;
    }
    sign * y[0]
}

const R: f64 = 100.0;

fn sphere() -> Surface {
    Surface::sphere(Vector3::new(0.0, 0.0, -R), R).unwrap()
}

/// A square 0/90 blank of `cells` cells of side `d` around the pole.
fn spec(cells: usize, d: f64) -> NetSpec {
    NetSpec {
        outline: BlankFrame {
            center: Vector3::new(0.0, 0.0, 5.0),
            width: cells as f64 * d,
            height: cells as f64 * d,
        },
        seed: [0.0, 0.0],
        orientation_deg: 0.0,
        spacing: [d, d],
        direction: -Vector3::z(),
        warp_curve: None,
        weft_curve: None,
    }
}

#[test]
fn the_reference_solves_its_equation() {
    // Series near 0 (25·c₅ = 7/72 from cos γ = 1 − z²/2 + 7z⁴/72 + …), and
    // (zγ′)′ − cos γ by finite differences elsewhere.
    let z: f64 = 1e-2;
    let series = z - z.powi(3) / 18.0 + 7.0 * z.powi(5) / 1800.0;
    assert!(
        (chebyshev_shear(z) - series).abs() < 1e-15,
        "{}",
        chebyshev_shear(z) - series
    );
    assert_eq!(chebyshev_shear(-0.7), -chebyshev_shear(0.7));
    for z in [0.1, 0.5, 1.0, 1.5] {
        let h = 1e-3;
        let w = |z: f64| z * (chebyshev_shear(z + h) - chebyshev_shear(z - h)) / (2.0 * h);
        let residual = (w(z + h) - w(z - h)) / (2.0 * h) - chebyshev_shear(z).cos();
        assert!(residual.abs() < 1e-5, "z = {z}: residual {residual}");
    }
}

#[test]
fn the_diagonal_converges_to_the_chebyshev_net_at_second_order() {
    // The diagonal cell (n, n) centred at u = v = 60 mm on nets ever finer.
    let s = 60.0;
    let reference = chebyshev_shear(s * s / (R * R));
    let mut errors = Vec::new();
    for n in [5, 10, 20, 40] {
        let d = s / (n as f64 + 0.5);
        let net = Net::drape(&sphere(), &spec(2 * n + 2, d)).unwrap();
        let cell = net
            .cell(n as i32, n as i32)
            .expect("the diagonal cell is draped");
        errors.push((cell.shear - reference).abs());
        // By symmetry the other quadrants hold the same shear, its sign
        // that of i·j.
        let mirror = net.cell(-(n as i32) - 1, n as i32).unwrap();
        assert!(
            (mirror.shear + cell.shear).abs() < 1e-9,
            "{} vs {}",
            mirror.shear,
            cell.shear
        );
        let opposite = net.cell(-(n as i32) - 1, -(n as i32) - 1).unwrap();
        assert!((opposite.shear - cell.shear).abs() < 1e-9);
    }
    // Order from each halving of the cell.
    let orders: Vec<f64> = errors.windows(2).map(|e| (e[0] / e[1]).log2()).collect();
    for p in &orders {
        assert!(
            (p - 2.0).abs() < 0.15,
            "errors {errors:?}, orders {orders:?}"
        );
    }
    // On the finest net, far inside 0.1°.
    assert!(errors[3].to_degrees() < 1e-3, "{errors:?}");
}

#[test]
fn every_yarn_segment_keeps_its_length_and_every_crossing_lies_on_the_mould() {
    let d = 4.0;
    let net = Net::drape(&sphere(), &spec(50, d)).unwrap();
    let stats = net.stats();
    assert_eq!(stats.draped_cells, 2500);
    assert_eq!(stats.missed, 0);
    for c in net.cells() {
        let [i, j] = c.index;
        let p = |a, b| net.node(a, b).unwrap();
        for (a, b) in [
            (p(i, j), p(i + 1, j)),
            (p(i, j + 1), p(i + 1, j + 1)),
            (p(i, j), p(i, j + 1)),
            (p(i + 1, j), p(i + 1, j + 1)),
        ] {
            assert!(((a - b).norm() - d).abs() < 1e-9 * d);
        }
        for x in [p(i, j), p(i + 1, j + 1)] {
            assert!(((x - Vector3::new(0.0, 0.0, -R)).norm() - R).abs() < 1e-9 * d);
        }
        assert!((c.stretch[0] - 1.0).abs() < 1e-9 && (c.stretch[1] - 1.0).abs() < 1e-9);
    }
    // About 4 closest-point queries per crossing.
    let per_crossing = stats.queries as f64 / stats.placed as f64;
    assert!(per_crossing < 6.0, "{per_crossing} queries per crossing");
}

#[test]
fn the_generators_are_great_circles_with_chords_of_one_cell() {
    let d = 5.0;
    let net = Net::drape(&sphere(), &spec(30, d)).unwrap();
    let centre = Vector3::new(0.0, 0.0, -R);
    let step = 2.0 * (d / (2.0 * R)).asin();
    for k in -15..=15 {
        let a = step * f64::from(k);
        let warp = net.node(k, 0).unwrap();
        let weft = net.node(0, k).unwrap();
        let expect_warp = centre + Vector3::new(a.sin(), 0.0, a.cos()) * R;
        let expect_weft = centre + Vector3::new(0.0, a.sin(), a.cos()) * R;
        assert!((warp - expect_warp).norm() < 1e-8, "{k}: {warp:?}");
        assert!((weft - expect_weft).norm() < 1e-8, "{k}: {weft:?}");
    }
}
