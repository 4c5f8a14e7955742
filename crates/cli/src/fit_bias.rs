//! `drape fit bias-extension`: reading the curves, the ideal three-zone
//! balance, and the command's card, plot and residuals for either method
//! (the inverse fit by simulation is [`crate::fit_inverse`]).
//!
//! A specimen H long between the grips and W wide (H ≥ 2W), yarns at ±45°:
//! zone A (area W·(H − 3W/2)) shears by γ, zones B (area W²) by γ/2, the
//! zones at the grips (W²/2) not at all; cos θ = (D + u)/(√2·D) with
//! D = H − W, γ = 90° − 2θ, so dγ/du = √2/(D·sin θ) and
//! F·du = h·[S_A·τ_s(γ) + S_B·τ_s(γ/2)/2]·dγ — linear in the law's
//! coefficients, fitted by weighted least squares.
//!
//! What the balance is not: a model of yarn stretch, yarn bending at the
//! zones' borders or the borders' width, which drape's runs carry (on the
//! benchmark the three-zone law comes out 4–16 % above the inverse one);
//! nor of yarn slip, which neither models.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use drape_constitutive::{Material, ShearLocking};
use nalgebra::{DMatrix, DVector};

use crate::fit::{Abscissa, FitInputError, read_table, write_whole};

/// One measured curve: its name and (line, displacement mm, force N).
#[derive(Debug, Clone, PartialEq)]
pub struct BiasCurve {
    /// Column name.
    pub name: String,
    /// Its file.
    pub file: String,
    /// (line, u, F) with 0 < γ(u) ≤ the largest angle.
    pub points: Vec<(usize, f64, f64)>,
}

/// A bias-extension specimen: length between the grips and width (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Specimen {
    /// H, mm.
    pub height: f64,
    /// W, mm.
    pub width: f64,
}

impl Specimen {
    fn d(&self) -> f64 {
        self.height - self.width
    }

    /// Central-zone shear angle (radians) at displacement `u` (mm), or
    /// None beyond the ideal kinematics' reach.
    pub fn gamma(&self, u: f64) -> Option<f64> {
        let c = (self.d() + u) / (std::f64::consts::SQRT_2 * self.d());
        (c < 1.0).then(|| std::f64::consts::FRAC_PI_2 - 2.0 * c.acos())
    }

    /// The ideal three-zone clamp force (N) of `law` on thickness `h`.
    pub fn force(&self, law: &ShearLocking, h: f64, u: f64) -> f64 {
        let Some(g) = self.gamma(u) else {
            return f64::NAN;
        };
        let (sa, sb, dg) = self.zones(u);
        h * (sa * law.stress(g) + 0.5 * sb * law.stress(0.5 * g)) * dg
    }

    /// The crosshead displacement (mm) at central shear `gamma` (rad).
    pub fn displacement(&self, gamma: f64) -> f64 {
        let theta = 0.5 * (std::f64::consts::FRAC_PI_2 - gamma);
        std::f64::consts::SQRT_2 * self.d() * theta.cos() - self.d()
    }

    /// The normalised shear force F_sh(γ) (N/mm) of a clamp-force curve
    /// `force(u)`, by the benchmark's energy normalisation (Harrison,
    /// Launay; Cao et al. 2008): F_sh(γ) = [(H/W − 1)·F·(cos(γ/2) −
    /// sin(γ/2)) − W·F_sh(γ/2)·cos(γ/2)] / ((2H − 3W)·cos γ), recursive
    /// in γ/2 down to 1e-8 rad, linear below. It is the picture frame's F_s·L_frame/L_fabric²
    /// for the same fabric: both are h·τ_s(γ)/cos γ (tested).
    pub fn normalised(&self, force: &dyn Fn(f64) -> f64, gamma: f64) -> f64 {
        let (h, w) = (self.height, self.width);
        let f = force(self.displacement(gamma));
        if gamma < 1e-8 {
            // Any smooth odd law is linear there: F_sh(γ/2) = F_sh(γ)/2.
            return (h / w - 1.0) * f / (2.0 * h - 2.5 * w);
        }
        let half = self.normalised(force, 0.5 * gamma);
        ((h / w - 1.0) * f * ((0.5 * gamma).cos() - (0.5 * gamma).sin())
            - w * half * (0.5 * gamma).cos())
            / ((2.0 * h - 3.0 * w) * gamma.cos())
    }

    /// (γ, S_A, S_B, dγ/du) at `u` (γ NaN beyond the kinematics).
    pub fn zones_at(&self, u: f64) -> (f64, f64, f64, f64) {
        let (sa, sb, dg) = self.zones(u);
        (self.gamma(u).unwrap_or(f64::NAN), sa, sb, dg)
    }

    /// (S_A, S_B, dγ/du).
    fn zones(&self, u: f64) -> (f64, f64, f64) {
        let (w, d) = (self.width, self.d());
        let theta = ((d + u) / (std::f64::consts::SQRT_2 * d))
            .clamp(-1.0, 1.0)
            .acos();
        (
            w * (self.height - 1.5 * w),
            w * w,
            std::f64::consts::SQRT_2 / (d * theta.sin()),
        )
    }
}

/// The three-zone fit and its curves.
#[derive(Debug, Clone, PartialEq)]
pub struct BiasFit {
    /// The law (MPa, γ in rad).
    pub law: ShearLocking,
    /// The thickness, mm.
    pub thickness: f64,
    /// The specimen.
    pub specimen: Specimen,
    /// The curves.
    pub curves: Vec<BiasCurve>,
}

/// Reads the curves of `files` (first column displacement, mm) keeping
/// the points with 0 < γ ≤ `max_angle_deg`.
pub fn read_bias_curves(
    files: &[PathBuf],
    specimen: Specimen,
    max_angle_deg: f64,
) -> Result<Vec<BiasCurve>, FitInputError> {
    let mut curves = Vec::new();
    for path in files {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| FitInputError {
            file: file.clone(),
            line: None,
            message: e.to_string(),
        })?;
        let table = read_table(&file, &text, false)?;
        if table.abscissa == Abscissa::Angle {
            return Err(FitInputError {
                file,
                line: None,
                message: "column 1 names an angle: a bias-extension fit reads the crosshead \
                          displacement (mm)"
                    .to_owned(),
            });
        }
        for (k, name) in table.names.iter().enumerate() {
            let mut points = Vec::new();
            for (line, u, values) in &table.rows {
                let Some(f) = values[k] else { continue };
                let Some(g) = specimen.gamma(*u) else {
                    return Err(FitInputError {
                        file: file.clone(),
                        line: Some(*line),
                        message: format!(
                            "displacement {u} mm is beyond the ideal kinematics of a {} × {} mm \
                             specimen",
                            specimen.height, specimen.width
                        ),
                    });
                };
                if g > 0.0 && g.to_degrees() <= max_angle_deg {
                    points.push((*line, *u, f));
                }
            }
            let name = if files.len() > 1 {
                let stem = path
                    .file_stem()
                    .map_or_else(|| file.clone(), |s| s.to_string_lossy().into_owned());
                format!("{stem}:{name}")
            } else {
                name.clone()
            };
            curves.push(BiasCurve {
                name,
                file: file.clone(),
                points,
            });
        }
    }
    Ok(curves)
}

/// Fits `terms` coefficients to `curves` (each curve weighted as a whole).
pub fn fit_three_zone(
    curves: Vec<BiasCurve>,
    specimen: Specimen,
    thickness: f64,
    terms: usize,
) -> Result<BiasFit, FitInputError> {
    let rows: usize = curves.iter().map(|c| c.points.len()).sum();
    if terms == 0 || rows < terms {
        return Err(FitInputError {
            file: String::new(),
            line: None,
            message: format!("{rows} points cannot determine {terms} coefficients"),
        });
    }
    let mut a = DMatrix::zeros(rows, terms);
    let mut b = DVector::zeros(rows);
    let mut r = 0;
    for c in &curves {
        let w = (1.0 / c.points.len() as f64).sqrt();
        for &(_, u, f) in &c.points {
            let g = specimen.gamma(u).expect("checked on reading");
            let (sa, sb, dg) = specimen.zones(u);
            for k in 0..terms {
                let p = 2 * k as i32 + 1;
                a[(r, k)] = w * thickness * dg * (sa * g.powi(p) + 0.5 * sb * (0.5 * g).powi(p));
            }
            b[r] = w * f;
            r += 1;
        }
    }
    // Columns scaled to unit norm so the SVD sees comparable magnitudes.
    let norms: Vec<f64> = (0..terms).map(|k| a.column(k).norm().max(1e-300)).collect();
    for (k, n) in norms.iter().enumerate() {
        a.column_mut(k).scale_mut(1.0 / n);
    }
    let x = a
        .svd(true, true)
        .solve(&b, 1e-12)
        .map_err(|e| FitInputError {
            file: String::new(),
            line: None,
            message: format!("least squares failed: {e}"),
        })?;
    let law = ShearLocking {
        coefficients: (0..terms).map(|k| x[k] / norms[k]).collect(),
        friction: None,
    };
    Ok(BiasFit {
        law,
        thickness,
        specimen,
        curves,
    })
}

impl BiasFit {
    /// The fitted force at `u`, N.
    pub fn force(&self, u: f64) -> f64 {
        self.specimen.force(&self.law, self.thickness, u)
    }

    /// Report: the law and each curve's RMS and mean deviation.
    pub fn report(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "three-zone fit τ_s(γ) = {:?} (MPa, γ in rad; h = {} mm; {} × {} mm specimen)",
            self.law.coefficients, self.thickness, self.specimen.height, self.specimen.width
        );
        for c in &self.curves {
            let n = c.points.len().max(1) as f64;
            let rms = (c
                .points
                .iter()
                .map(|&(_, u, f)| (f - self.force(u)).powi(2))
                .sum::<f64>()
                / n)
                .sqrt();
            let _ = writeln!(
                s,
                "{:<24} {:>4} points, rms {rms:.3} N",
                c.name,
                c.points.len()
            );
        }
        s
    }

    /// Residuals CSV.
    pub fn residuals_csv(&self) -> String {
        let mut s = String::from(
            "curve,file,line,displacement_mm,central_shear_deg,measured_N,fitted_N,residual_N\n",
        );
        for c in &self.curves {
            for &(line, u, f) in &c.points {
                let g = self.specimen.gamma(u).unwrap_or(f64::NAN).to_degrees();
                let m = self.force(u);
                let _ = writeln!(
                    s,
                    "{},{},{line},{u},{g:.4},{f},{m:.6},{:.6}",
                    c.name,
                    c.file,
                    f - m
                );
            }
        }
        s
    }
}

/// How the bias-extension law is fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// drape's own bias-extension runs in the loop (Levenberg–Marquardt).
    Inverse,
    /// The ideal three-zone energy balance only.
    ThreeZone,
}

/// What `drape fit bias-extension` is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct BiasOptions {
    /// The method.
    pub method: Method,
    /// Polynomial terms.
    pub terms: usize,
    /// With the friction term τ_f·tanh(γ/γ_f).
    pub friction: bool,
    /// Points beyond this central shear (deg) are left out.
    pub max_angle: f64,
    /// One weight per curve, or empty.
    pub weights: Vec<f64>,
    /// Inverse: cell diagonals across the width.
    pub cells: usize,
    /// Inverse: also run the fitted law on twice the cells.
    pub mesh_check: bool,
}

/// Runs the fit and writes card, plot and residuals beside `out`;
/// returns the report.
pub fn run(
    files: &[PathBuf],
    specimen: Specimen,
    base: &Material,
    options: &BiasOptions,
    out: &Path,
) -> Result<String, BiasFitError> {
    let bad = |m: String| {
        BiasFitError::Input(FitInputError {
            file: String::new(),
            line: None,
            message: m,
        })
    };
    if !(specimen.width > 0.0 && specimen.height >= 2.0 * specimen.width) {
        return Err(bad(format!(
            "--height {} --width {}: a bias-extension specimen needs H ≥ 2W > 0 (three zones)",
            specimen.height, specimen.width
        )));
    }
    if options.terms == 0 {
        return Err(bad("--terms must be at least 1".to_owned()));
    }
    if options.cells == 0 {
        return Err(bad("--cells must be at least 1".to_owned()));
    }
    if options.method == Method::Inverse {
        // Checked here, not by the first simulation: a mesh the options
        // cannot make is bad input (exit 2), not a failed fit. Twice the
        // cells (--mesh-check) are square when these are.
        crate::bias_sim::VirtualTest {
            specimen,
            cells: options.cells,
            u_max: 1.0,
            step: 1.0,
        }
        .check_mesh()
        .map_err(|e| bad(format!("--cells {}: {e}", options.cells)))?;
    }
    let max_angle_deg = options.max_angle;
    let curves = read_bias_curves(files, specimen, max_angle_deg)?;
    if let Some(c) = curves.iter().find(|c| c.points.len() < 2) {
        return Err(BiasFitError::Input(FitInputError {
            file: c.file.clone(),
            line: None,
            message: format!(
                "curve `{}` has {} point(s) with 0 < γ ≤ {max_angle_deg}°: a fit needs a curve",
                c.name,
                c.points.len()
            ),
        }));
    }
    if !options.weights.is_empty() {
        if options.weights.len() != curves.len() {
            return Err(bad(format!(
                "--weights: {} values for {} curves",
                options.weights.len(),
                curves.len()
            )));
        }
        if let Some(w) = options
            .weights
            .iter()
            .find(|w| !(w.is_finite() && **w >= 0.0))
        {
            return Err(bad(format!("--weights {w}: expected a weight ≥ 0")));
        }
    }
    let form = crate::fit_inverse::LawForm {
        terms: options.terms,
        friction: options.friction,
    };
    let (law, fitted, report, residuals, what) = match options.method {
        Method::ThreeZone => {
            let (law, _) = crate::fit_inverse::three_zone(
                &curves,
                &options.weights,
                specimen,
                base.thickness,
                form,
            )
            .map_err(bad)?;
            let fit = BiasFit {
                law: law.clone(),
                thickness: base.thickness,
                specimen,
                curves: curves.clone(),
            };
            let umax = curves
                .iter()
                .flat_map(|c| c.points.iter().map(|p| p.1))
                .fold(0.0, f64::max);
            let fitted: Vec<(f64, f64)> = (1..=200)
                .map(|n| {
                    let u = umax * n as f64 / 200.0;
                    (u, fit.force(u))
                })
                .collect();
            (
                law,
                fitted,
                fit.report(),
                fit.residuals_csv(),
                "ideal three-zone",
            )
        }
        Method::Inverse => {
            let fit = crate::fit_inverse::fit(
                curves.clone(),
                specimen,
                base,
                &crate::fit_inverse::InverseOptions {
                    form,
                    cells: options.cells,
                    step: 1.0,
                    weights: options.weights.clone(),
                    mesh_check: options.mesh_check,
                },
            )
            .map_err(|e| BiasFitError::Failed(format!("the inverse fit failed: {e}")))?;
            let fitted = fit
                .curve
                .u
                .iter()
                .copied()
                .zip(fit.curve.force.iter().copied())
                .collect();
            (
                fit.law.clone(),
                fitted,
                fit.report(),
                fit.residuals_csv(),
                "inverse (simulated)",
            )
        }
    };
    let mut material = base.clone();
    material.name = format!("{} (shear law, {what} bias-extension fit)", material.name);
    material.resin.shear_locking = Some(law);
    material
        .validate()
        .map_err(|e| BiasFitError::Failed(format!("the fitted law is not usable: {e}")))?;
    let failed = |e: String| BiasFitError::Failed(e);
    let body = toml::to_string(&material).map_err(|e| failed(e.to_string()))?;
    let card = format!(
        "# Material card: {what} bias-extension fit ({} × {} mm, to {max_angle_deg}° of \
         central shear), by `drape fit bias-extension`.\n{body}",
        specimen.height, specimen.width
    );
    let measured: Vec<(String, Vec<(f64, f64)>)> = curves
        .iter()
        .map(|c| {
            (
                c.name.clone(),
                c.points.iter().map(|p| (p.1, p.2)).collect(),
            )
        })
        .collect();
    let plot = out.with_extension("fit.png");
    drape_io::results::write_fit_picture(
        &plot,
        &format!("bias extension: measured and {what} fit"),
        ("crosshead displacement (mm)", "clamp force (N)"),
        &measured,
        &fitted,
    )
    .map_err(|e| failed(e.to_string()))?;
    write_whole(&out.with_extension("residuals.csv"), &residuals).map_err(failed)?;
    write_whole(out, &card).map_err(failed)?;
    Ok(report)
}

/// Why a bias-extension fit stopped: the input (exit 2), or a fit that
/// failed on good input (an inner simulation that did not complete, a
/// law the least squares left unusable, an output it could not write:
/// exit 1, as a failed run).
#[derive(Debug)]
pub enum BiasFitError {
    /// A file, a line or an option is wrong.
    Input(FitInputError),
    /// The fit could not be done on this input.
    Failed(String),
}

impl From<FitInputError> for BiasFitError {
    fn from(e: FitInputError) -> Self {
        Self::Input(e)
    }
}

impl std::fmt::Display for BiasFitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Input(e) => write!(f, "{e}"),
            Self::Failed(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for BiasFitError {}

#[cfg(test)]
mod tests {
    use super::*;

    /// The benchmark's normalisation of the three-zone force is the
    /// frame's normalised force of the same law, h·τ_s/cos γ: the two
    /// tests are compared per unit area on both sides (to 1e-9).
    #[test]
    fn the_benchmarks_bias_normalisation_is_the_frames() {
        let law = ShearLocking {
            coefficients: vec![0.0766, -0.1217, 0.3107],
            friction: Some([0.003, 0.02]),
        };
        let s = Specimen {
            height: 230.0,
            width: 115.0,
        };
        let h = 1.2;
        for g in [5.0f64, 10.0, 20.0, 30.0] {
            let g = g.to_radians();
            assert!((s.gamma(s.displacement(g)).unwrap() - g).abs() < 1e-12);
            let n = s.normalised(&|u| s.force(&law, h, u), g);
            let frame = h * law.stress(g) / g.cos();
            assert!((n - frame).abs() < 1e-9 * frame, "{n} vs {frame}");
        }
    }

    /// The three-zone force of a known law, sampled, fits back to it; and
    /// the force is the derivative of the zones' energy (finite difference
    /// of h·[S_A·w(γ) + S_B·w(γ/2)] in u).
    #[test]
    fn the_three_zone_force_is_the_energys_derivative_and_fits_back() {
        let law = ShearLocking {
            coefficients: vec![0.01, 0.02, 0.3],
            friction: None,
        };
        let s = Specimen {
            height: 230.0,
            width: 115.0,
        };
        let h = 1.2;
        let energy = |u: f64| {
            let g = s.gamma(u).unwrap();
            let (sa, sb, _) = s.zones(u);
            h * (sa * law.energy(g) + sb * law.energy(0.5 * g))
        };
        for u in [5.0, 20.0, 40.0] {
            let e = 1e-5;
            let fd = (energy(u + e) - energy(u - e)) / (2.0 * e);
            let f = s.force(&law, h, u);
            assert!((fd - f).abs() < 1e-7 * f.abs(), "{fd} vs {f}");
        }
        let points = (1..=40)
            .map(|n| (n, n as f64, s.force(&law, h, n as f64)))
            .collect();
        let curves = vec![BiasCurve {
            name: "x".into(),
            file: "x.csv".into(),
            points,
        }];
        let fit = fit_three_zone(curves, s, h, 3).unwrap();
        for (a, b) in fit.law.coefficients.iter().zip(&law.coefficients) {
            assert!((a - b).abs() < 1e-9 * b.abs().max(1e-2), "{a} vs {b}");
        }
    }
}
