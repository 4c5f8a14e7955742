//! Validation of yarn bending (beyond the paper): a strip rolled onto a
//! cylinder against B·L·W/(2R²), and Peirce's cantilever — a strip
//! overhanging a table edge under its own weight — against the heavy
//! elastica, solved here by shooting, and against Peirce's formula.
//!
//! The references never call drape's bending code: the elastica is
//! integrated below with its own Runge–Kutta scheme.

use drape_constitutive::Material;
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{BoundaryCondition, Model};
use drape_time::{Explicit, ExplicitSettings, Frame, Observer};
use nalgebra::Vector3;

use super::{Case, Check};

/// The cases of this module.
pub const CASES: &[Case] = &[
    Case {
        name: "bending/rolled-cylinder",
        quick: true,
        run: rolled_cylinder,
    },
    Case {
        name: "bending/peirce-cantilever-quick",
        quick: true,
        run: cantilever_quick,
    },
    Case {
        name: "bending/peirce-cantilever",
        quick: false,
        run: cantilever_full,
    },
];

/// g (mm/s²).
const GRAVITY: f64 = 9810.0;

/// The glass preset with its (assumed) bending rigidity.
fn glass() -> Material {
    Material::preset("glass-serge-4x3").expect("preset")
}

fn strip(length: f64, width: f64, x_min: f64, cells: [usize; 2]) -> RectangleBlank {
    RectangleBlank {
        width: length,
        height: width,
        center: Vector3::new(x_min + 0.5 * length, 0.0, 0.0),
        orientation_deg: 0.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells(cells),
        fibres: FibreRepresentation::Trusses,
    }
}

/// A 100 × 20 mm glass strip (0/90 trusses, 2 mm cells) rolled without
/// stretch onto a cylinder of radius R about y, warp round the cylinder:
/// E = B·L·W/(2R²) with B the warp rigidity; the discrete curvature
/// 2·tan(φ/2)/ℓ̄ exceeds 1/R by (ℓ/R)²/12, the energy by (ℓ/R)²/6: 0.11 %
/// on R = 25 mm. A rigid motion of the flat strip stores nothing.
fn rolled_cylinder() -> Vec<Check> {
    let material = glass();
    let b = material.bending_rigidity.expect("preset rigidity")[0];
    let (length, width) = (100.0, 20.0);
    let mut model =
        Model::from_blank(&strip(length, width, 0.0, [50, 10]), &material).expect("model");
    model
        .add_yarn_bending(Vector3::x(), Vector3::z(), [b, 3.0 * b])
        .expect("bending");
    let mut checks = Vec::new();
    for r in [25.0, 60.0, 200.0] {
        let x: Vec<_> = model
            .x0
            .iter()
            .map(|p| {
                let a = p.x / r;
                Vector3::new(r * a.sin(), p.y, r * (1.0 - a.cos()))
            })
            .collect();
        checks.push(Check::rel(
            format!("bending energy on R = {r} mm (N·mm)"),
            b * length * width / (2.0 * r * r),
            model.bending_energy(&x).expect("energy"),
            0.01,
        ));
    }
    let (s, c) = 0.8f64.sin_cos();
    let moved: Vec<_> = model
        .x0
        .iter()
        .map(|p| Vector3::new(c * p.x - s * p.z + 3.0, p.y - 7.0, s * p.x + c * p.z + 11.0))
        .collect();
    checks.push(Check::abs(
        "bending energy after a rigid motion (N·mm)",
        0.0,
        model.bending_energy(&moved).expect("energy"),
        1e-15,
    ));
    checks
}

/// The heavy cantilever elastica in units of the bending length
/// c = (B/w)^(1/3): ψ'' = −(λ − s)·cos ψ on [0, λ], λ = l/c, ψ(0) = 0
/// (clamped level), ψ'(λ) = 0 (free tip), ψ the slope below the
/// horizontal. Shooting on ψ'(0) by bisection, classical RK4 with 4000
/// steps; returns the chord angle θ = atan(y_tip/x_tip) (radians).
pub fn elastica_tip_angle(lambda: f64) -> f64 {
    let steps = 4000;
    let h = lambda / steps as f64;
    // State: ψ, ψ', x, y.
    let rhs = |s: f64, y: [f64; 4]| -> [f64; 4] {
        [y[1], -(lambda - s) * y[0].cos(), y[0].cos(), y[0].sin()]
    };
    let shoot = |k0: f64| -> [f64; 4] {
        let mut y = [0.0, k0, 0.0, 0.0];
        for n in 0..steps {
            let s = n as f64 * h;
            let k1 = rhs(s, y);
            let add = |y: [f64; 4], k: [f64; 4], f: f64| std::array::from_fn(|i| y[i] + f * k[i]);
            let k2 = rhs(s + 0.5 * h, add(y, k1, 0.5 * h));
            let k3 = rhs(s + 0.5 * h, add(y, k2, 0.5 * h));
            let k4 = rhs(s + h, add(y, k3, h));
            for i in 0..4 {
                y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        y
    };
    // ψ'(λ) grows with ψ'(0): negative at 0, positive at the linear
    // beam's λ²/2 doubled (gravity's moment only falls as the strip droops).
    let (mut lo, mut hi) = (0.0, lambda * lambda);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if shoot(mid)[1] < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let y = shoot(0.5 * (lo + hi));
    (y[3] / y[2]).atan()
}

/// Peirce's bending length from an overhang `l` and its chord angle θ:
/// c = l·(cos(θ/2)/(8·tan θ))^(1/3).
fn peirce_length(l: f64, theta: f64) -> f64 {
    l * ((0.5 * theta).cos() / (8.0 * theta.tan())).cbrt()
}

/// The strip material of the cantilever: the glass preset with straight,
/// soft yarns and a soft resin. The elastica is inextensible; what the
/// yarns' stiffness adds is only run time (the step follows the axial
/// waves, the settling the slow bending mode): at E_f = 20 MPa the strip
/// stretches ≤ 3e-4 under its weight, which moves the tip angle by less
/// than 1e-3 of itself.
fn cantilever_material() -> Material {
    let mut m = glass();
    m.fibre.modulus = 20.0;
    m.fibre.crimp_strain = 0.0;
    m.fibre.compression_factor = 1.0;
    m.fibre.buckling_stress = 0.0;
    m.resin.young = 2.0;
    m
}

/// Records the tip's chord angle at each frame, and the last energies.
struct Tip {
    nodes: Vec<u32>,
    angles: Vec<f64>,
    energy: drape_time::Energies,
}

impl Observer for Tip {
    fn frame(&mut self, frame: &Frame<'_>) {
        let n = self.nodes.len() as f64;
        let p = self
            .nodes
            .iter()
            .map(|&i| frame.state.x[i as usize])
            .sum::<Vector3<f64>>()
            / n;
        self.angles.push((-p.z / p.x).atan());
        self.energy = *frame.energy;
    }
}

/// A 10 mm wide strip of `cantilever_material` with `cells` cells over
/// the overhang `l` and two more on the table (held: the table's weight on
/// the strip clamps it level at the edge x = 0), under gravity, settled by
/// mass-proportional damping at twice the linear first mode's frequency
/// (critical for that mode). Returns the chord angle at the end, its
/// change over the last 20 % of the run (how settled it is) and the
/// energies at the end.
fn cantilever_angle(l: f64, cells: usize) -> (f64, f64, drape_time::Energies) {
    let material = cantilever_material();
    let b = material.bending_rigidity.expect("rigidity")[0];
    let cell = l / cells as f64;
    let blank = strip(l + 2.0 * cell, 10.0, -2.0 * cell, [cells + 2, 1]);
    let mut model = Model::from_blank(&blank, &material).expect("model");
    model.gravity = Vector3::new(0.0, 0.0, -GRAVITY);
    let table: Vec<u32> = (0..model.node_count() as u32)
        .filter(|&i| model.x0[i as usize].x <= 1e-9 * l)
        .collect();
    let tip: Vec<u32> = (0..model.node_count() as u32)
        .filter(|&i| model.x0[i as usize].x >= l * (1.0 - 1e-9))
        .collect();
    model.boundary.push(BoundaryCondition::fixed(table));
    model
        .add_yarn_bending(Vector3::x(), Vector3::z(), [b, b])
        .expect("bending");
    let rho_h = material.density * material.thickness;
    let omega1 = 3.516 * (b / rho_h).sqrt() / (l * l);
    let settings = ExplicitSettings {
        end_time: 14.0 / omega1,
        frames: 10,
        damping: 2.0 * omega1,
        ..ExplicitSettings::default()
    };
    let mut state = model.initial_state();
    let mut observer = Tip {
        nodes: tip,
        angles: Vec::new(),
        energy: drape_time::Energies::default(),
    };
    Explicit::new(&model, settings)
        .expect("driver")
        .run(&mut state, &mut observer)
        .expect("run");
    let a = &observer.angles;
    let last = a[a.len() - 1];
    (last, (last - a[a.len() - 3]).abs(), observer.energy)
}

/// Checks of one overhang: drape's chord angle on `meshes` against the
/// elastica (2 %), the error falling with the mesh, how settled the run
/// is, and Peirce's formula applied to drape's angle against the bending
/// length B/w the strip was given.
fn cantilever_checks(overhangs_c: &[f64], meshes: &[usize]) -> Vec<Check> {
    let material = cantilever_material();
    let b = material.bending_rigidity.expect("rigidity")[0];
    let w = material.density * material.thickness * GRAVITY;
    let c = (b / w).cbrt();
    let mut checks = Vec::new();
    for &lc in overhangs_c {
        let l = lc * c;
        let exact = elastica_tip_angle(lc);
        let mut errors = Vec::new();
        let mut drifts = Vec::new();
        for &cells in meshes {
            let (theta, drift, energy) = cantilever_angle(l, cells);
            drifts.push(drift);
            // Elastic strip, no dashpots: the internal forces' work is
            // stored, the bending triplets' included (their energy is
            // ~all of it), up to the O(Δt²) of the work's quadrature.
            checks.push(Check::rel(
                format!("stored energy vs work of the internal forces, {cells} cells (N·mm)"),
                energy.internal_work,
                energy.strain,
                1e-4,
            ));
            checks.push(Check::abs(
                format!("energy balance error / largest term, {cells} cells"),
                0.0,
                energy.relative_error(),
                1e-4,
            ));
            errors.push((theta - exact).abs());
            checks.push(Check::rel(
                format!(
                    "chord angle, overhang {l:.1} mm = {lc}c, {cells} cells (deg; drift {:.1e}°)",
                    drift.to_degrees()
                ),
                exact.to_degrees(),
                theta.to_degrees(),
                0.02,
            ));
            checks.push(Check::abs(
                format!("settled: angle change over the last 20 % of the run, {cells} cells (deg)"),
                0.0,
                drift.to_degrees(),
                2e-3 * exact.to_degrees(),
            ));
            if cells == *meshes.last().expect("meshes") {
                // Peirce's formula is itself a fit of the elastica near his
                // design angle (41.5°); beyond 45° it departs from it (3.9 %
                // in c at 57°, the inaccuracy Lammens et al. 2014 report), so
                // there it is compared with itself applied to the elastica.
                if exact.to_degrees() <= 45.0 {
                    checks.push(Check::rel(
                        format!(
                            "Peirce's c from drape's angle, overhang {lc}c, {cells} cells (mm)"
                        ),
                        c,
                        peirce_length(l, theta),
                        0.02,
                    ));
                } else {
                    checks.push(Check::rel(
                        format!(
                            "Peirce's c from drape's angle vs from the elastica's, overhang {lc}c \
                             (mm; the formula's own error there {:+.1} %)",
                            100.0 * (peirce_length(l, exact) / c - 1.0)
                        ),
                        peirce_length(l, exact),
                        peirce_length(l, theta),
                        0.02,
                    ));
                }
            }
        }
        // The mesh error is O(h²) until it meets the floor of the strip's
        // stretch and its residual motion (the run's `drift`, ~1e-4 of the
        // angle). On the finest pair, if its fine error is still above the
        // fine run's drift, the observed order log₂(e_coarse/e_fine) must be
        // 2 ± 0.3: the residual motion, up to that error, and the O(h⁴)
        // term still visible at 2.5c on 20 cells (ratio 0.31 there, 0.52
        // on 10 → 20) move it by up to ~0.2. A pair at the floor is checked
        // to stay below it. Coarser pairs are checked to fall only: at 2c
        // the O(h²) term changes sign between 10 and 20 cells, at 2.5c the
        // 10-cell mesh is not yet asymptotic.
        let last = meshes.len() - 1;
        for (k, (pair, cells)) in errors.windows(2).zip(&meshes[1..]).enumerate() {
            let (e_coarse, e_fine) = (pair[0], pair[1]);
            let floor = drifts[k + 1];
            if e_fine <= floor {
                checks.push(Check::abs(
                    format!(
                        "error at {cells} cells, {lc}c, at the floor (deg; within twice the run's drift)"
                    ),
                    0.0,
                    e_fine.to_degrees(),
                    2.0 * floor.to_degrees(),
                ));
            } else if k + 1 == last {
                checks.push(Check::abs(
                    format!(
                        "observed order {} → {cells} cells at {lc}c (errors {:.2e}° → {:.2e}°)",
                        meshes[k],
                        e_coarse.to_degrees(),
                        e_fine.to_degrees()
                    ),
                    2.0,
                    (e_coarse / e_fine).log2(),
                    0.3,
                ));
            } else {
                checks.push(Check::abs(
                    format!(
                        "error ratio {cells} cells / {} at {lc}c (falls; h² gives 0.25)",
                        meshes[k]
                    ),
                    0.5,
                    e_fine / e_coarse,
                    0.5,
                ));
            }
        }
    }
    checks
}

fn cantilever_quick() -> Vec<Check> {
    cantilever_checks(&[1.0], &[8, 16])
}

fn cantilever_full() -> Vec<Check> {
    cantilever_checks(&[1.0, 1.5, 2.0, 2.5], &[10, 20, 40, 80])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elastica_small_deflection_and_peirces_design_point() {
        // Small overhang: the linear beam, tip deflection λ⁴/8, chord λ³/8.
        let t = elastica_tip_angle(0.2);
        assert!((t - 0.2f64.powi(3) / 8.0).abs() < 1e-3 * t, "{t}");
        // Peirce's formula at his design angle θ ≈ 41.5° gives l ≈ 2c.
        let theta = elastica_tip_angle(2.0);
        assert!(
            (peirce_length(2.0, theta) - 1.0).abs() < 0.03,
            "{}",
            theta.to_degrees()
        );
    }
}
