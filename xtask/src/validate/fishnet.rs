//! Validation of kinematic draping (drape-fishnet).
//!
//! - `fishnet/chebyshev-sphere` (quick): the net on a sphere against the
//!   analytic Chebyshev net. With orthogonal geodesic generators through
//!   the pole the shear at arc lengths (u, v) is γ(uv/R²), (zγ′)′ = cos γ,
//!   γ(0) = 0 (derived in drape-fishnet's crate docs), integrated here by
//!   RK4 from its series. The diagonal profile of ever finer nets, its
//!   largest error and the observed order of convergence in the cell size.
//! - `fishnet/hemisphere-mechanical-vs-kinematic` (full: a forming run of
//!   tens of seconds): `scenes/hemisphere-conform.toml` (no friction, a
//!   resin of 1 % of the prepreg's stiffness, the fabric pressed onto the
//!   paper's hemisphere by a body force) run both ways through the facade
//!   (`drape::compare_scene`, what `drape compare` runs); the difference of
//!   the diagonal and median profiles where the formed fabric lies on the
//!   mould.

use std::path::Path;

use drape_contact::Surface;
use drape_fishnet::{Net, NetSpec};
use drape_model::blank::BlankFrame;
use nalgebra::Vector3;

use super::{Case, Check};

/// The cases of this module.
pub const CASES: &[Case] = &[
    Case {
        name: "fishnet/chebyshev-sphere",
        quick: true,
        run: chebyshev_sphere,
    },
    Case {
        name: "fishnet/hemisphere-mechanical-vs-kinematic",
        quick: false,
        run: hemisphere_mechanical_vs_kinematic,
    },
];

/// γ(z) of the Chebyshev net on a sphere: (zγ′)′ = cos γ, γ(0) = 0, odd in
/// z. From z₀ = 1e-3 (series γ = z − z³/18, zγ′ = z − z³/6, truncation
/// 1e-17) by RK4 in 4000 steps: about 1e-13 rad for |z| ≤ 2.
fn chebyshev_shear(z: f64) -> f64 {
    if z == 0.0 {
        return 0.0;
    }
    let (sign, z) = (z.signum(), z.abs());
    let z0 = z.min(1e-3);
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

/// The hemisphere's radius (mm), the paper's.
const R: f64 = 120.0;

/// A square 0/90 net of `width` and cells of `d` seeded over the pole.
fn net_on_sphere(width: f64, d: f64) -> Net {
    let sphere = Surface::sphere(Vector3::new(0.0, 0.0, -R), R).expect("sphere");
    let spec = NetSpec {
        outline: BlankFrame {
            center: Vector3::new(0.0, 0.0, 1.0),
            width,
            height: width,
        },
        seed: [0.0, 0.0],
        orientation_deg: 0.0,
        spacing: [d, d],
        direction: -Vector3::z(),
        warp_curve: None,
        weft_curve: None,
    };
    Net::drape(&sphere, &spec).expect("the net drapes")
}

fn chebyshev_sphere() -> Vec<Check> {
    let mut checks = Vec::new();
    // The whole diagonal profile of a fine net: a 240 mm square blank of
    // 1.5 mm cells whose corners reach u = v = R, where γ = 54°; the
    // diagonal cells (k, k) are centred at u = v = (k + ½)·d.
    let (width, d) = (2.0 * R, 1.5);
    let net = net_on_sphere(width, d);
    let half = (width / d / 2.0).round() as i32;
    let mut worst = if net.stats().draped_cells == (2 * half * 2 * half) as usize {
        0.0f64
    } else {
        f64::NAN
    };
    for k in -half..half {
        let s = (f64::from(k) + 0.5) * d;
        let reference = chebyshev_shear(s * s / (R * R)).to_degrees();
        let computed = net.cell(k, k).map_or(f64::NAN, |c| c.shear.to_degrees());
        worst = worst.max((computed - reference).abs());
        if [-half, -half / 2, half / 4, half - 1].contains(&k) {
            checks.push(Check::abs(
                format!("γ on the diagonal at u = v = {s:.2} mm, {d} mm cells (°)"),
                reference,
                computed,
                0.1,
            ));
        }
    }
    checks.push(Check::abs(
        format!(
            "largest |γ − γ_Chebyshev| over the {} diagonal cells, {d} mm cells (°)",
            2 * half
        ),
        0.0,
        worst,
        0.1,
    ));
    // The order in the cell size at fixed points u = v = s of the diagonal:
    // nets whose cell (n, n) is centred there, d = s/(n + ½).
    for s in [60.0, 110.0] {
        let reference = chebyshev_shear(s * s / (R * R));
        let errors: Vec<(f64, f64)> = [10usize, 20, 40, 80]
            .iter()
            .map(|&n| {
                let d = s / (n as f64 + 0.5);
                let net = net_on_sphere(2.0 * (n as f64 + 1.0) * d, d);
                let computed = net.cell(n as i32, n as i32).map_or(f64::NAN, |c| c.shear);
                (d, (computed - reference).abs().to_degrees())
            })
            .collect();
        for pair in errors.windows(2) {
            let ((d0, e0), (d1, e1)) = (pair[0], pair[1]);
            checks.push(Check::abs(
                format!(
                    "observed order at u = v = {s} mm (γ = {:.2}°), cells {d0:.3} → {d1:.3} mm (error {e0:.3e}° → {e1:.3e}°)",
                    reference.to_degrees()
                ),
                2.0,
                (e0 / e1).ln() / (d0 / d1).ln(),
                0.1,
            ));
        }
    }
    checks
}

fn hemisphere_mechanical_vs_kinematic() -> Vec<Check> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives inside the workspace");
    let scene =
        drape_io::scene::Scene::from_file(&root.join("scenes/hemisphere-conform.toml"), &[])
            .expect("the scene loads");
    let out = super::target_dir(root)
        .join("validation")
        .join("hemisphere-conform");
    let report = drape::compare_scene(&scene, &out, &mut |_| drape::RunControl::Continue)
        .expect("both runs write their results");
    let s = &report.comparison.summary;
    let run = &report.mechanical.summary;
    // The run must have come to rest on the mould for the comparison to
    // mean anything.
    let mut checks = vec![Check::abs(
        format!(
            "forming run completed and at rest: E_kin/E_int at the end ({})",
            run.status
        ),
        0.0,
        if run.status == "completed" {
            run.energy.kinetic_to_internal
        } else {
            f64::NAN
        },
        1e-3,
    )];
    // Where the formed fabric lies on the mould the two answers are the
    // same Chebyshev net (by symmetry the run's central yarns are the
    // geodesic generators), up to the yarn stretch under the pressing
    // (≈ 0.2 %, which moves γ ≈ uv/R² by ≈ 0.4 % of itself: 0.26° at 65°)
    // and the resin's 1 % share of the shear resistance: 0.5°.
    for (name, d) in [("diagonal", &s.diagonal), ("median", &s.median)] {
        checks.push(Check::abs(
            format!(
                "{name}: largest |γ_run − γ_net| on the mould ({} of {} elements) (°)",
                d.points_on_mould, d.points
            ),
            0.0,
            if d.points_on_mould > 0 {
                d.max_abs_on_mould_deg
            } else {
                f64::NAN
            },
            0.5,
        ));
        checks.push(Check::abs(
            format!("{name}: rms of γ_run − γ_net on the mould (°)"),
            0.0,
            if d.points_on_mould > 0 {
                d.rms_on_mould_deg
            } else {
                f64::NAN
            },
            0.2,
        ));
    }
    checks
}
