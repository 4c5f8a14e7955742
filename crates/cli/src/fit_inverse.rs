//! `drape fit bias-extension --method inverse`: the shear law whose
//! simulated bias extension (drape's own runs, [`crate::bias_sim`])
//! reproduces the measured clamp force, by Levenberg–Marquardt
//! ([`crate::lm`]) on the law's parameters, started from the ideal
//! three-zone fit of the same form.
//!
//! The residuals are the same as the three-zone fit's (clamp force in N,
//! each curve weighted as a whole), so the two fits differ only by the
//! model in the loop: pin-jointed kinematics or a simulation with
//! extensible (crimped) yarns, yarn bending and zone borders smeared over
//! a cell. Runs are independent and each deterministic, so the
//! Jacobian's runs go in parallel and the fit does not depend on the
//! thread count.
//!
//! The law's parameters: the polynomial's coefficients, and with the
//! friction term τ_f and ln γ_f (γ_f > 0 by construction).

use std::fmt::Write as _;
use std::time::Instant;

use drape_constitutive::{Material, ShearLocking};
use nalgebra::DVector;
use rayon::prelude::*;

use crate::bias_sim::{SimCurve, VirtualTest};
use crate::fit_bias::{BiasCurve, Specimen};
use crate::lm::{LmOptions, LmResult, minimise};

/// The form of the law fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LawForm {
    /// Polynomial terms c₁γ + c₃γ³ + ….
    pub terms: usize,
    /// With the friction term τ_f·tanh(γ/γ_f).
    pub friction: bool,
}

impl LawForm {
    /// The law of parameter vector `p`.
    pub fn law(&self, p: &DVector<f64>) -> ShearLocking {
        ShearLocking {
            coefficients: p.iter().take(self.terms).copied().collect(),
            friction: self
                .friction
                .then(|| [p[self.terms], p[self.terms + 1].exp()]),
        }
    }

    /// The parameters of `law` (which has this form).
    pub fn params(&self, law: &ShearLocking) -> DVector<f64> {
        let mut p: Vec<f64> = law.coefficients.clone();
        p.resize(self.terms, 0.0);
        if self.friction {
            let [tau, g0] = law.friction.unwrap_or([0.0, 1f64.to_radians()]);
            p.push(tau);
            p.push(g0.ln());
        }
        DVector::from_vec(p)
    }
}

/// The measured points as the fit sees them: (curve, u, F, √weight).
fn points(curves: &[BiasCurve], weights: &[f64]) -> Vec<(usize, f64, f64, f64)> {
    let mut out = Vec::new();
    for (c, curve) in curves.iter().enumerate() {
        let w = weights.get(c).copied().unwrap_or(1.0) / curve.points.len().max(1) as f64;
        for &(_, u, f) in &curve.points {
            out.push((c, u, f, w.sqrt()));
        }
    }
    out
}

/// The three-zone fit of `form` to `curves` (the formula in the loop):
/// the linear fit of the polynomial, with the friction term the best of
/// a log-spaced γ_f from 0.1° to 10°, then refined by the same
/// Levenberg–Marquardt as the inverse fit.
pub fn three_zone(
    curves: &[BiasCurve],
    weights: &[f64],
    specimen: Specimen,
    thickness: f64,
    form: LawForm,
) -> Result<(ShearLocking, LmResult), String> {
    let pts = points(curves, weights);
    let model = |p: &DVector<f64>| -> Option<DVector<f64>> {
        let law = form.law(p);
        law.validate("").ok()?;
        Some(DVector::from_iterator(
            pts.len(),
            pts.iter()
                .map(|&(_, u, f, w)| w * (specimen.force(&law, thickness, u) - f)),
        ))
    };
    let poly = crate::fit_bias::fit_three_zone(curves.to_vec(), specimen, thickness, form.terms)
        .map_err(|e| e.to_string())?
        .law;
    let start = if form.friction {
        // For a fixed γ_f the force is linear in (c, τ_f): the weighted
        // linear fit for each γ_f of a log-spaced set from 0.1° to 10°,
        // the best valid one kept.
        let mut best: Option<(f64, DVector<f64>)> = None;
        for k in 0..=40 {
            let g0 = (0.1f64 * 100f64.powf(k as f64 / 40.0)).to_radians();
            let n = form.terms + 1;
            let basis = |j: usize, g: f64| {
                if j < form.terms {
                    g.powi(2 * j as i32 + 1)
                } else {
                    (g / g0).tanh()
                }
            };
            let mut a = nalgebra::DMatrix::zeros(pts.len(), n);
            let mut b = DVector::zeros(pts.len());
            for (r, &(_, u, f, w)) in pts.iter().enumerate() {
                let (g, sa, sb, dg) = specimen.zones_at(u);
                for j in 0..n {
                    a[(r, j)] =
                        w * thickness * dg * (sa * basis(j, g) + 0.5 * sb * basis(j, 0.5 * g));
                }
                b[r] = w * f;
            }
            let norms: Vec<f64> = (0..n).map(|j| a.column(j).norm().max(1e-300)).collect();
            for (j, nj) in norms.iter().enumerate() {
                a.column_mut(j).scale_mut(1.0 / nj);
            }
            let Ok(x) = a.svd(true, true).solve(&b, 1e-12) else {
                continue;
            };
            let mut p = DVector::from_fn(n + 1, |j, _| if j < n { x[j] / norms[j] } else { 0.0 });
            p[n] = g0.ln();
            if let Some(r) = model(&p) {
                let cost = r.norm_squared();
                if best.as_ref().is_none_or(|b| cost < b.0) {
                    best = Some((cost, p));
                }
            }
        }
        best.ok_or("no friction angle from 0.1° to 10° gives a valid law")?
            .1
    } else {
        form.params(&poly)
    };
    let scale = scales(&start, form);
    let r = minimise(
        start,
        &scale,
        LmOptions::default(),
        &mut |ps: &[DVector<f64>]| ps.iter().map(model).collect(),
    )?;
    Ok((form.law(&r.x), r))
}

/// Each parameter's scale: its size at the start, at least 1e-3 of the
/// largest coefficient (a coefficient that starts at 0 still moves), and
/// 1 for ln γ_f.
fn scales(p: &DVector<f64>, form: LawForm) -> DVector<f64> {
    let big = p
        .iter()
        .take(form.terms + usize::from(form.friction))
        .fold(0.0f64, |a, x| a.max(x.abs()))
        .max(1e-6);
    DVector::from_fn(p.len(), |i, _| {
        if form.friction && i == form.terms + 1 {
            1.0
        } else {
            p[i].abs().max(1e-3 * big)
        }
    })
}

/// What the inverse fit asks.
#[derive(Debug, Clone, PartialEq)]
pub struct InverseOptions {
    /// The law's form.
    pub form: LawForm,
    /// Cell diagonals across the specimen's width in the runs.
    pub cells: usize,
    /// Output spacing of the runs (mm).
    pub step: f64,
    /// One weight per curve (empty: each curve counts once).
    pub weights: Vec<f64>,
    /// Also run the fitted law on twice the cells (the mesh's error).
    pub mesh_check: bool,
}

/// The inverse fit and what it took.
#[derive(Debug, Clone, PartialEq)]
pub struct InverseFit {
    /// The fitted law.
    pub law: ShearLocking,
    /// Its standard errors (the parameters' spread the data allow).
    pub standard_errors: Option<Vec<f64>>,
    /// The three-zone fit of the same form (the start).
    pub three_zone: ShearLocking,
    /// The fitted law's run.
    pub curve: SimCurve,
    /// The curves.
    pub curves: Vec<BiasCurve>,
    /// The specimen.
    pub specimen: Specimen,
    /// The material's thickness (mm).
    pub thickness: f64,
    /// Levenberg–Marquardt iterations.
    pub iterations: usize,
    /// Simulations run by the inverse fit.
    pub simulations: usize,
    /// Why it stopped.
    pub stop: &'static str,
    /// Wall time of the inverse fit (s).
    pub seconds: f64,
    /// The test's mesh.
    pub test: VirtualTest,
    /// With the mesh check: the largest |F(2·cells) − F(cells)| over
    /// the points, as a fraction of the force there, and where (u, mm).
    pub mesh_error: Option<(f64, f64)>,
}

/// Fits the law of `options.form` to `curves` by simulation.
pub fn fit(
    curves: Vec<BiasCurve>,
    specimen: Specimen,
    base: &Material,
    options: &InverseOptions,
) -> Result<InverseFit, String> {
    let started = Instant::now();
    let (three, _) = three_zone(
        &curves,
        &options.weights,
        specimen,
        base.thickness,
        options.form,
    )?;
    let pts = points(&curves, &options.weights);
    let u_max = pts.iter().map(|p| p.1).fold(0.0, f64::max);
    let test = VirtualTest {
        specimen,
        cells: options.cells,
        u_max: (u_max / options.step).ceil() * options.step,
        step: options.step,
    };
    let form = options.form;
    let material = |p: &DVector<f64>| {
        let mut m = base.clone();
        m.resin.shear_locking = Some(form.law(p));
        m.validate().ok().map(|()| m)
    };
    let residuals = |curve: &SimCurve| {
        DVector::from_iterator(
            pts.len(),
            pts.iter().map(|&(_, u, f, w)| w * (curve.at(u) - f)),
        )
    };
    let start = form.params(&three);
    let scale = scales(&start, form);
    let mut runs = 0;
    let result = minimise(
        start,
        &scale,
        LmOptions {
            max_iterations: 15,
            x_tolerance: 1e-4,
            f_tolerance: 1e-6,
            fd_step: 1e-3,
        },
        &mut |ps: &[DVector<f64>]| {
            runs += ps.len();
            ps.par_iter()
                .map(|p| {
                    let m = material(p)?;
                    let c = test.run(&m).ok()?;
                    let r = residuals(&c);
                    r.iter().all(|v| v.is_finite()).then_some(r)
                })
                .collect()
        },
    )?;
    let law = form.law(&result.x);
    let fitted = material(&result.x).ok_or("the fitted law is not valid")?;
    let curve = test.run(&fitted)?;
    let mesh_error = if options.mesh_check {
        let fine = VirtualTest {
            cells: 2 * options.cells,
            ..test
        };
        let c = fine.run(&fitted)?;
        pts.iter()
            .map(|&(_, u, _, _)| ((c.at(u) - curve.at(u)).abs() / c.at(u).abs().max(1e-9), u))
            .fold(None, |a: Option<(f64, f64)>, x| match a {
                Some(b) if b.0 >= x.0 => Some(b),
                _ => Some(x),
            })
    } else {
        None
    };
    let standard_errors = result
        .standard_errors()
        .map(|s| s.iter().copied().collect());
    Ok(InverseFit {
        law,
        standard_errors,
        three_zone: three,
        curve,
        curves,
        specimen,
        thickness: base.thickness,
        iterations: result.iterations,
        simulations: runs + 1,
        stop: result.stop,
        seconds: started.elapsed().as_secs_f64(),
        test,
        mesh_error,
    })
}

fn describe(law: &ShearLocking) -> String {
    let mut s = crate::fit::polynomial(law);
    if let Some([tau, g0]) = law.friction {
        let _ = write!(s, " + {tau:.5e}·tanh(γ/{:.3}°)", g0.to_degrees());
    }
    s
}

impl InverseFit {
    /// The three-zone force of the three-zone law at `u`.
    pub fn three_zone_force(&self, u: f64) -> f64 {
        self.specimen.force(&self.three_zone, self.thickness, u)
    }

    /// The report: both laws, each curve's deviation from both, how far
    /// apart the laws are, what the fit took.
    pub fn report(&self) -> String {
        let mut s = String::new();
        let [nx, ny] = self.test.mesh();
        let _ = writeln!(
            s,
            "inverse fit τ_s(γ) = {} (MPa, γ in rad; h = {} mm)",
            describe(&self.law),
            self.thickness
        );
        if let Some(se) = &self.standard_errors {
            let _ = writeln!(
                s,
                "  standard errors of the parameters (coefficients…, τ_f, ln γ_f): {}",
                se.iter()
                    .map(|v| format!("{v:.2e}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        let _ = writeln!(
            s,
            "  {} simulations ({} × {} cells, {} increments each at the end), {} iterations, \
             {:.1} s; stopped: {}",
            self.simulations,
            nx,
            ny,
            self.curve.increments,
            self.iterations,
            self.seconds,
            self.stop
        );
        if let Some((e, u)) = self.mesh_error {
            let _ = writeln!(
                s,
                "  mesh: twice the cells moves the force by at most {:.2} % (at u = {u} mm)",
                100.0 * e
            );
        }
        let _ = writeln!(s, "three-zone fit τ_s(γ) = {}", describe(&self.three_zone));
        let _ = writeln!(
            s,
            "{:<28} {:>6} {:>14} {:>10} {:>14} {:>10}",
            "curve", "points", "inverse rms N", "mean %", "3-zone rms N", "mean %"
        );
        for c in &self.curves {
            let stats = |f: &dyn Fn(f64) -> f64| {
                let n = c.points.len().max(1) as f64;
                let rms = (c.points.iter().map(|p| (p.2 - f(p.1)).powi(2)).sum::<f64>() / n).sqrt();
                let mean = 100.0 * c.points.iter().map(|p| f(p.1) - p.2).sum::<f64>()
                    / c.points.iter().map(|p| p.2).sum::<f64>();
                (rms, mean)
            };
            let (ri, mi) = stats(&|u| self.curve.at(u));
            let (rt, mt) = stats(&|u| self.three_zone_force(u));
            let _ = writeln!(
                s,
                "{:<28} {:>6} {ri:>14.3} {mi:>+10.1} {rt:>14.3} {mt:>+10.1}",
                c.name,
                c.points.len()
            );
        }
        let _ = writeln!(s, "how far apart the laws are, τ_s (MPa):");
        for g in [5.0, 10.0, 20.0, 30.0, 40.0] {
            let r = f64::to_radians(g);
            let (a, b) = (self.law.stress(r), self.three_zone.stress(r));
            let _ = writeln!(
                s,
                "  γ = {g:>4}°: inverse {a:.5}, three-zone {b:.5} ({:+.1} %)",
                100.0 * (b - a) / a
            );
        }
        s
    }

    /// Residuals CSV: both fits at every point.
    pub fn residuals_csv(&self) -> String {
        let mut s = String::from(
            "curve,file,line,displacement_mm,central_shear_deg,measured_N,inverse_N,\
             inverse_residual_N,three_zone_N,three_zone_residual_N\n",
        );
        for c in &self.curves {
            for &(line, u, f) in &c.points {
                let g = self.specimen.gamma(u).unwrap_or(f64::NAN).to_degrees();
                let (a, b) = (self.curve.at(u), self.three_zone_force(u));
                let _ = writeln!(
                    s,
                    "{},{},{line},{u},{g:.4},{f},{a:.6},{:.6},{b:.6},{:.6}",
                    c.name,
                    c.file,
                    f - a,
                    f - b
                );
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three-zone curves of a known friction-form law (two curves, one
    /// weighted 0: it must not count) fit back to it to 1e-6 of each
    /// parameter, from the grid of γ_f and Levenberg–Marquardt.
    #[test]
    fn the_three_zone_fit_gives_back_a_friction_law() {
        let law = ShearLocking {
            coefficients: vec![0.007, 0.013],
            friction: Some([0.003, 1.3f64.to_radians()]),
        };
        let s = Specimen {
            height: 230.0,
            width: 115.0,
        };
        let h = 1.2;
        let curve = |name: &str, scale: f64| BiasCurve {
            name: name.into(),
            file: "x.csv".into(),
            points: (1..=40)
                .map(|n| (n, n as f64, scale * s.force(&law, h, n as f64)))
                .collect(),
        };
        let form = LawForm {
            terms: 2,
            friction: true,
        };
        let (fit, r) =
            three_zone(&[curve("a", 1.0), curve("b", 1.5)], &[1.0, 0.0], s, h, form).unwrap();
        let (p, q) = (form.params(&fit), form.params(&law));
        for k in 0..p.len() {
            assert!(
                (p[k] - q[k]).abs() < 1e-6 * q[k].abs(),
                "{fit:?} after {}",
                r.stop
            );
        }
    }
}
