//! `drape fit picture-frame`: a material card from a lab's picture-frame
//! curves (several labs or repeats at once), its plot and its residuals.
//!
//! Reads each CSV's first column as crosshead displacement (mm) or shear
//! angle (deg) and every further column as one curve; converts each point
//! to the energy-normalised shear force N = F_s·L_frame/L_fabric² (N/mm,
//! F_s = F/(2 cos θ), θ = 45° − γ/2), which does not depend on the frame's
//! size, and fits the `resin.shear_locking` polynomial τ_s(γ) = c₁γ + c₃γ³ …
//! through the energy balance of the pin-jointed frame:
//! F·dD = h·L_fabric²·τ_s·dγ, so h·τ_s = N·cos γ
//! ([`ShearLocking::fit_stresses`], weighted: each curve counts as a whole,
//! whatever its number of points, times its `--weights` value).
//!
//! What it is not: no correction for the frame's bending or the fabric's
//! yarn tension (a misaligned sample reads stiffer); the kinematics are
//! the ideal pin-jointed frame's.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use drape_constitutive::{Material, ShearLocking};

/// Input that cannot be read or fitted: the file, the line when there is
/// one, and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct FitInputError {
    /// The file (CSV or material card), or empty for an option.
    pub file: String,
    /// 1-based line.
    pub line: Option<usize>,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for FitInputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (self.file.is_empty(), self.line) {
            (true, _) => write!(f, "{}", self.message),
            (false, Some(l)) => write!(f, "{}: line {l}: {}", self.file, self.message),
            (false, None) => write!(f, "{}: {}", self.file, self.message),
        }
    }
}

impl std::error::Error for FitInputError {}

fn option_error(message: impl Into<String>) -> FitInputError {
    FitInputError {
        file: String::new(),
        line: None,
        message: message.into(),
    }
}

/// What the first column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Abscissa {
    /// Crosshead displacement, mm (the labs' raw form).
    Displacement,
    /// Shear angle, degrees.
    Angle,
}

/// What the force columns hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ForceKind {
    /// The crosshead (frame) force F, N.
    Frame,
    /// The shear force F_s = F/(2 cos θ), N.
    Shear,
    /// The normalised shear force F_s·L_frame/L_fabric², N/mm.
    Normalised,
}

/// One measured point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    /// 1-based line in its file.
    pub line: usize,
    /// Shear angle, degrees.
    pub gamma_deg: f64,
    /// The value read (units of its [`ForceKind`]).
    pub force: f64,
    /// The normalised shear force, N/mm.
    pub normalised: f64,
}

/// One measured curve (a column).
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// The column's name (or `FILE:column k`).
    pub name: String,
    /// Its file.
    pub file: String,
    /// Frame side, mm (NaN when not needed and not given).
    pub frame: f64,
    /// Fabric side, mm.
    pub fabric: f64,
    /// Relative weight of the whole curve.
    pub weight: f64,
    /// Its points with 0 < γ ≤ the fit's largest angle.
    pub points: Vec<Point>,
}

/// What `drape fit picture-frame` is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct PictureFrameOptions {
    /// The CSV files.
    pub inputs: Vec<PathBuf>,
    /// Frame side(s), mm: one for all files or one per file.
    pub frame: Vec<f64>,
    /// Fabric side(s), mm: one for all files or one per file.
    pub fabric: Vec<f64>,
    /// The first column is the shear angle in degrees (else the header
    /// decides, else displacement).
    pub angle: bool,
    /// What the force columns hold.
    pub force: ForceKind,
    /// Number of polynomial terms.
    pub terms: usize,
    /// Points beyond this shear angle (deg) are left out of the fit.
    pub max_angle: f64,
    /// One weight per curve (all files' columns in order), or empty.
    pub weights: Vec<f64>,
}

/// A fit and the curves it was fitted to.
#[derive(Debug, Clone, PartialEq)]
pub struct PictureFrameFit {
    /// The fitted law (MPa, γ in radians) for thickness `thickness`.
    pub law: ShearLocking,
    /// The thickness the law was divided by, mm.
    pub thickness: f64,
    /// The curves.
    pub curves: Vec<Curve>,
    /// Each curve's own fit, when it has enough points.
    pub own: Vec<Option<ShearLocking>>,
}

/// One file's columns: (line, x, [value per column or None]).
pub(crate) struct Table {
    pub(crate) names: Vec<String>,
    pub(crate) abscissa: Abscissa,
    pub(crate) rows: Vec<(usize, f64, Vec<Option<f64>>)>,
}

fn is_unit(field: &str) -> bool {
    let f = field
        .trim_matches(|c: char| c == '(' || c == ')' || c == '[' || c == ']')
        .to_ascii_lowercase();
    matches!(
        f.as_str(),
        "mm" | "m" | "in" | "n" | "kn" | "lbf" | "deg" | "°" | "rad" | "n/mm" | "s" | "min"
    )
}

/// Reads one CSV (comma, semicolon or whitespace separated; `#` comments
/// and blank lines skipped). The first line may name the columns; a
/// second line of units is refused (the units drape reads are fixed, so
/// a units line is named, not guessed at).
pub(crate) fn read_table(file: &str, text: &str, angle: bool) -> Result<Table, FitInputError> {
    let err = |line: usize, message: String| FitInputError {
        file: file.to_owned(),
        line: Some(line),
        message,
    };
    let mut names: Option<Vec<String>> = None;
    let mut rows: Vec<(usize, f64, Vec<Option<f64>>)> = Vec::new();
    let mut columns = 0;
    let mut seen_content = false;
    for (n, raw) in text.lines().enumerate() {
        let line_no = n + 1;
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = if line.contains(',') || line.contains(';') {
            line.split([',', ';']).map(str::trim).collect()
        } else {
            line.split_whitespace().collect()
        };
        let numeric = fields
            .iter()
            .all(|f| f.is_empty() || f.parse::<f64>().is_ok());
        if !numeric {
            if !seen_content {
                seen_content = true;
                columns = fields.len();
                names = Some(fields.iter().map(|f| f.to_string()).collect());
                continue;
            }
            if rows.is_empty() && fields.iter().all(|f| is_unit(f)) {
                return Err(err(
                    line_no,
                    format!(
                        "`{line}` is a line of units: drape reads the first column in mm \
                         (displacement) or degrees (shear angle, with --angle or a header naming \
                         degrees) and forces in N (or N/mm with --force normalised); remove this \
                         line, or put the units in the column names (`displacement_mm,force_N`)"
                    ),
                ));
            }
            let (k, bad) = fields
                .iter()
                .enumerate()
                .find(|(_, f)| !f.is_empty() && f.parse::<f64>().is_err())
                .expect("a non-numeric field");
            return Err(err(
                line_no,
                format!("column {}: `{bad}` is not a number", k + 1),
            ));
        }
        seen_content = true;
        if columns == 0 {
            columns = fields.len();
        }
        if fields.len() != columns {
            return Err(err(
                line_no,
                format!(
                    "{} fields where the file has {columns} columns",
                    fields.len()
                ),
            ));
        }
        if columns < 2 {
            return Err(err(
                line_no,
                "one column: expected displacement (or angle) and at least one force column"
                    .to_owned(),
            ));
        }
        let values: Vec<Option<f64>> = fields
            .iter()
            .map(|f| (!f.is_empty()).then(|| f.parse::<f64>().expect("checked")))
            .collect();
        for (k, v) in values.iter().enumerate() {
            if let Some(v) = v
                && !v.is_finite()
            {
                return Err(err(
                    line_no,
                    format!("column {}: `{}` is not a finite number", k + 1, fields[k]),
                ));
            }
        }
        let Some(x) = values[0] else {
            return Err(err(line_no, "column 1 is empty".to_owned()));
        };
        if let Some((prev_line, prev, _)) = rows.last()
            && x < *prev
        {
            return Err(err(
                line_no,
                format!(
                    "column 1 decreases ({x} after {prev} on line {prev_line}): a fit takes the \
                     loading branch only; cut the curve where the crosshead returns"
                ),
            ));
        }
        for (k, v) in values.iter().enumerate().skip(1) {
            if let Some(v) = v
                && *v < 0.0
            {
                return Err(err(
                    line_no,
                    format!(
                        "column {}: force {v} is negative: a picture frame pulls; tare the load \
                         cell (subtract the force read with the frame unloaded) before fitting",
                        k + 1
                    ),
                ));
            }
        }
        rows.push((line_no, x, values[1..].to_vec()));
    }
    let file_err = |message: String| FitInputError {
        file: file.to_owned(),
        line: None,
        message,
    };
    if rows.len() < 2 {
        return Err(file_err(format!(
            "{} data line{}: a fit needs a curve (at least two points)",
            rows.len(),
            if rows.len() == 1 { "" } else { "s" }
        )));
    }
    let names =
        names.unwrap_or_else(|| (0..columns).map(|k| format!("column {}", k + 1)).collect());
    let first = names[0].to_ascii_lowercase();
    let header_angle = first.contains("deg") || first.contains("angle") || first.contains('°');
    let header_disp = first.contains("mm") || first.contains("disp");
    if angle && header_disp && !header_angle {
        return Err(file_err(format!(
            "--angle says column 1 is the shear angle, but its header `{}` names a displacement",
            names[0]
        )));
    }
    let abscissa = if angle || header_angle {
        Abscissa::Angle
    } else {
        Abscissa::Displacement
    };
    Ok(Table {
        names: names[1..].to_vec(),
        abscissa,
        rows,
    })
}

/// Shear angle (degrees) of a picture frame of side `frame` (mm) at
/// crosshead displacement `d` (mm): cos θ = (√2·L + d)/(2L), γ = 90° − 2θ.
pub fn frame_angle_deg(d: f64, frame: f64) -> f64 {
    let c = (std::f64::consts::SQRT_2 * frame + d) / (2.0 * frame);
    90.0 - 2.0 * c.clamp(-1.0, 1.0).acos().to_degrees()
}

fn per_file(values: &[f64], files: usize, what: &str) -> Result<Vec<f64>, FitInputError> {
    if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
        return Err(option_error(format!(
            "--{what} {v}: expected a positive length in mm"
        )));
    }
    match values.len() {
        0 => Ok(vec![f64::NAN; files]),
        1 => Ok(vec![values[0]; files]),
        n if n == files => Ok(values.to_vec()),
        n => Err(option_error(format!(
            "--{what}: {n} values for {files} CSV files; give one for all or one per file"
        ))),
    }
}

/// Reads the curves of `options` (the text of each input given by `read`).
pub fn read_curves(
    options: &PictureFrameOptions,
    read: impl Fn(&Path) -> std::io::Result<String>,
) -> Result<Vec<Curve>, FitInputError> {
    let files = options.inputs.len();
    if files == 0 {
        return Err(option_error("give at least one CSV file"));
    }
    let frames = per_file(&options.frame, files, "frame")?;
    let fabrics = per_file(&options.fabric, files, "fabric")?;
    let mut curves = Vec::new();
    for (i, path) in options.inputs.iter().enumerate() {
        let file = path.display().to_string();
        let text = read(path).map_err(|e| FitInputError {
            file: file.clone(),
            line: None,
            message: e.to_string(),
        })?;
        let table = read_table(&file, &text, options.angle)?;
        let (frame, fabric) = (frames[i], fabrics[i]);
        let need = |what: &str, v: f64, why: &str| {
            if v.is_nan() {
                Err(FitInputError {
                    file: file.clone(),
                    line: None,
                    message: format!("give --{what} (mm): {why}"),
                })
            } else {
                Ok(())
            }
        };
        if table.abscissa == Abscissa::Displacement {
            need(
                "frame",
                frame,
                "column 1 is a displacement (use --angle if it is the shear angle)",
            )?;
        }
        if options.force != ForceKind::Normalised {
            need(
                "frame",
                frame,
                "the force is normalised by the frame's side",
            )?;
            need(
                "fabric",
                fabric,
                "the force is normalised by the fabric's side",
            )?;
        }
        for (k, name) in table.names.iter().enumerate() {
            let mut points = Vec::new();
            for (line, x, values) in &table.rows {
                let Some(force) = values[k] else { continue };
                let gamma_deg = match table.abscissa {
                    Abscissa::Angle => *x,
                    Abscissa::Displacement => {
                        let c = (std::f64::consts::SQRT_2 * frame + x) / (2.0 * frame);
                        if c >= 1.0 {
                            return Err(FitInputError {
                                file: file.clone(),
                                line: Some(*line),
                                message: format!(
                                    "displacement {x} mm is beyond what a {frame} mm frame can \
                                     reach ({} mm, the frame closed flat)",
                                    (2.0 - std::f64::consts::SQRT_2) * frame
                                ),
                            });
                        }
                        frame_angle_deg(*x, frame)
                    }
                };
                if gamma_deg <= 0.0 || gamma_deg > options.max_angle {
                    // γ = 0 carries nothing for an odd law; beyond the
                    // largest angle asked for is not fitted.
                    continue;
                }
                if gamma_deg >= 90.0 {
                    return Err(FitInputError {
                        file: file.clone(),
                        line: Some(*line),
                        message: format!("shear angle {gamma_deg}°: expected less than 90°"),
                    });
                }
                let theta = (45.0 - 0.5 * gamma_deg).to_radians();
                let normalised = match options.force {
                    ForceKind::Frame => force / (2.0 * theta.cos()) * frame / (fabric * fabric),
                    ForceKind::Shear => force * frame / (fabric * fabric),
                    ForceKind::Normalised => force,
                };
                points.push(Point {
                    line: *line,
                    gamma_deg,
                    force,
                    normalised,
                });
            }
            // Several files: the file's stem tells same-named columns apart.
            let name = if files > 1 {
                let stem = path
                    .file_stem()
                    .map_or_else(|| file.clone(), |s| s.to_string_lossy().into_owned());
                format!("{stem}:{name}")
            } else {
                name.clone()
            };
            curves.push(Curve {
                name,
                file: file.clone(),
                frame,
                fabric,
                weight: 1.0,
                points,
            });
        }
    }
    if !options.weights.is_empty() {
        if options.weights.len() != curves.len() {
            return Err(option_error(format!(
                "--weights: {} values for {} curves ({})",
                options.weights.len(),
                curves.len(),
                curves
                    .iter()
                    .map(|c| c.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        for (c, w) in curves.iter_mut().zip(&options.weights) {
            if !(w.is_finite() && *w >= 0.0) {
                return Err(option_error(format!(
                    "--weights {w}: expected a weight ≥ 0"
                )));
            }
            c.weight = *w;
        }
    }
    Ok(curves)
}

fn samples(curves: &[&Curve], thickness: f64) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    for c in curves {
        if c.points.is_empty() {
            continue;
        }
        let w = c.weight / c.points.len() as f64;
        for p in &c.points {
            let g = p.gamma_deg.to_radians();
            out.push([g, p.normalised * g.cos() / thickness, w]);
        }
    }
    out
}

/// Fits the law to `curves` for a fabric of thickness `thickness` (mm).
pub fn fit_curves(
    curves: Vec<Curve>,
    thickness: f64,
    terms: usize,
) -> Result<PictureFrameFit, FitInputError> {
    let all: Vec<&Curve> = curves.iter().collect();
    let law = ShearLocking::fit_stresses(&samples(&all, thickness), terms)
        .map_err(|e| option_error(format!("the fit failed: {e}")))?;
    let own = curves
        .iter()
        .map(|c| {
            (c.points.len() > terms)
                .then(|| ShearLocking::fit_stresses(&samples(&[c], thickness), terms).ok())
                .flatten()
        })
        .collect();
    Ok(PictureFrameFit {
        law,
        thickness,
        curves,
        own,
    })
}

impl PictureFrameFit {
    /// The fitted normalised shear force N(γ) = h·τ_s(γ)/cos γ (N/mm).
    pub fn normalised(&self, gamma_deg: f64) -> f64 {
        normalised(&self.law, self.thickness, gamma_deg)
    }

    /// Largest shear angle fitted, degrees.
    pub fn max_angle(&self) -> f64 {
        self.curves
            .iter()
            .flat_map(|c| c.points.iter().map(|p| p.gamma_deg))
            .fold(0.0, f64::max)
    }

    /// The residuals as CSV: one row per point.
    pub fn residuals_csv(&self) -> String {
        let mut s = String::from(
            "curve,file,line,shear_angle_deg,measured_N_per_mm,fitted_N_per_mm,residual_N_per_mm\n",
        );
        for c in &self.curves {
            for p in &c.points {
                let f = self.normalised(p.gamma_deg);
                let _ = writeln!(
                    s,
                    "{},{},{},{:.4},{:.6},{:.6},{:.6}",
                    csv_field(&c.name),
                    csv_field(&c.file),
                    p.line,
                    p.gamma_deg,
                    p.normalised,
                    f,
                    p.normalised - f
                );
            }
        }
        s
    }

    /// A short report: the law, and each curve's weight, RMS residual and
    /// own fit (the spread between curves).
    pub fn report(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "fitted τ_s(γ) = {} (MPa, γ in rad; h = {} mm), {} curves, {} points up to {:.1}°",
            polynomial(&self.law),
            self.thickness,
            self.curves.len(),
            self.curves.iter().map(|c| c.points.len()).sum::<usize>(),
            self.max_angle()
        );
        let w = self
            .curves
            .iter()
            .map(|c| c.name.chars().count())
            .max()
            .unwrap_or(0)
            .max(16);
        let _ = writeln!(
            s,
            "{:<w$} {:>6} {:>6} {:>12} {:>10}  own fit: N at 10°/20°/30°/40° (N/mm)",
            "curve", "points", "weight", "rms (N/mm)", "mean (%)"
        );
        for (c, own) in self.curves.iter().zip(&self.own) {
            let n = c.points.len().max(1) as f64;
            let rms = (c
                .points
                .iter()
                .map(|p| (p.normalised - self.normalised(p.gamma_deg)).powi(2))
                .sum::<f64>()
                / n)
                .sqrt();
            let mean = c
                .points
                .iter()
                .map(|p| p.normalised - self.normalised(p.gamma_deg))
                .sum::<f64>()
                / c.points
                    .iter()
                    .map(|p| self.normalised(p.gamma_deg))
                    .sum::<f64>()
                * 100.0;
            let own = own.as_ref().map_or_else(
                || "(too few points)".to_owned(),
                |l| {
                    [10.0, 20.0, 30.0, 40.0]
                        .map(|g| format!("{:.4}", normalised(l, self.thickness, g)))
                        .join(" / ")
                },
            );
            let _ = writeln!(
                s,
                "{:<w$} {:>6} {:>6} {:>12.5} {:>+10.1}  {own}",
                c.name,
                c.points.len(),
                c.weight,
                rms,
                mean
            );
        }
        let joint = [10.0, 20.0, 30.0, 40.0]
            .map(|g| format!("{:.4}", self.normalised(g)))
            .join(" / ");
        let _ = writeln!(s, "{:<w$} {:>37}  {joint}", "joint fit", "");
        s
    }
}

fn normalised(law: &ShearLocking, thickness: f64, gamma_deg: f64) -> f64 {
    let g = gamma_deg.to_radians();
    thickness * law.stress(g) / g.cos()
}

pub(crate) fn polynomial(law: &ShearLocking) -> String {
    law.coefficients
        .iter()
        .enumerate()
        .map(|(k, c)| match k {
            0 => format!("{c:.5e}·γ"),
            _ => format!("{c:+.5e}·γ^{}", 2 * k + 1),
        })
        .collect::<Vec<_>>()
        .join(" ")
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

/// The base material: a preset's name or a TOML card.
pub fn base_material(base: &str) -> Result<Material, FitInputError> {
    if base.ends_with(".toml") {
        let text = std::fs::read_to_string(base).map_err(|e| FitInputError {
            file: base.to_owned(),
            line: None,
            message: e.to_string(),
        })?;
        let m = toml::from_str::<Material>(&text).map_err(|e| FitInputError {
            file: base.to_owned(),
            line: None,
            message: e.to_string(),
        })?;
        m.validate().map_err(|e| FitInputError {
            file: base.to_owned(),
            line: None,
            message: e.to_string(),
        })?;
        Ok(m)
    } else {
        Material::preset(base).ok_or_else(|| {
            option_error(format!(
                "--material: unknown preset `{base}`: expected one of {} or a .toml card",
                drape_constitutive::PRESET_NAMES.join(", ")
            ))
        })
    }
}

/// The material card (TOML text): `base` with the fitted law.
pub fn card(base: &Material, fit: &PictureFrameFit, sources: &str) -> Result<String, String> {
    let mut material = base.clone();
    material.name = format!("{} (shear locking fitted from {sources})", material.name);
    material.resin.shear_locking = Some(fit.law.clone());
    material
        .validate()
        .map_err(|e| format!("the fitted law is not usable: {e}"))?;
    let body = toml::to_string(&material).map_err(|e| e.to_string())?;
    Ok(format!(
        "# Material card: picture-frame fit of {sources} ({} curves, {} points up to {:.1}°;\n\
         # h·τ_s = F_s·L_frame·cos γ/L_fabric² with h = {} mm), by `drape fit picture-frame`.\n{body}",
        fit.curves.len(),
        fit.curves.iter().map(|c| c.points.len()).sum::<usize>(),
        fit.max_angle(),
        material.thickness
    ))
}

/// The whole picture-frame fit of `options` on `base`: the fit and the
/// card's text.
pub fn picture_frame(
    options: &PictureFrameOptions,
    base: &Material,
) -> Result<(PictureFrameFit, String), FitInputError> {
    if options.terms == 0 {
        return Err(option_error("--terms must be at least 1"));
    }
    if options.max_angle.is_nan() || options.max_angle <= 0.0 {
        return Err(option_error(format!(
            "--max-angle {}: expected a shear angle in degrees above 0",
            options.max_angle
        )));
    }
    let curves = read_curves(options, |p| std::fs::read_to_string(p))?;
    if let Some(c) = curves.iter().find(|c| c.points.len() < 2) {
        return Err(FitInputError {
            file: c.file.clone(),
            line: None,
            message: format!(
                "curve `{}` has {} in (0°, {}°]: a fit needs a curve",
                c.name,
                if c.points.is_empty() {
                    "no point"
                } else {
                    "a single point"
                },
                options.max_angle
            ),
        });
    }
    let fit = fit_curves(curves, base.thickness, options.terms)?;
    let sources = options
        .inputs
        .iter()
        .map(|p| {
            p.file_name().map_or_else(
                || p.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            )
        })
        .collect::<Vec<_>>()
        .join(", ");
    let text = card(base, &fit, &sources).map_err(option_error)?;
    Ok((fit, text))
}

/// Writes the card to `out`, the plot beside it (`<out>.fit.png` with
/// the card's extension replaced) and the residuals (`.residuals.csv`);
/// returns the two extra paths.
pub fn write_outputs(
    out: &Path,
    fit: &PictureFrameFit,
    card: &str,
) -> Result<(PathBuf, PathBuf), String> {
    let plot = out.with_extension("fit.png");
    let residuals = out.with_extension("residuals.csv");
    let top = fit.max_angle().max(1.0);
    let fitted: Vec<(f64, f64)> = (0..=200)
        .map(|n| {
            let g = top * n as f64 / 200.0;
            (g, if n == 0 { 0.0 } else { fit.normalised(g) })
        })
        .collect();
    let measured: Vec<(String, Vec<(f64, f64)>)> = fit
        .curves
        .iter()
        .map(|c| {
            (
                c.name.clone(),
                c.points
                    .iter()
                    .map(|p| (p.gamma_deg, p.normalised))
                    .collect(),
            )
        })
        .collect();
    drape_io::results::write_fit_picture(
        &plot,
        "picture frame: measured and fitted",
        (
            "shear angle γ (deg)",
            "normalised shear force F_s·L_frame/L_fabric² (N/mm)",
        ),
        &measured,
        &fitted,
    )
    .map_err(|e| e.to_string())?;
    write_whole(&residuals, &fit.residuals_csv())?;
    write_whole(out, card)?;
    Ok((plot, residuals))
}

pub(crate) fn write_whole(path: &Path, text: &str) -> Result<(), String> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".partial");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, text)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_frame_kinematics_are_the_papers() {
        assert!(frame_angle_deg(0.0, 180.0).abs() < 1e-12);
        // d such that θ = 30°: cos 30° = (√2L + d)/(2L).
        let l = 250.0;
        let d = 2.0 * l * 30f64.to_radians().cos() - std::f64::consts::SQRT_2 * l;
        assert!((frame_angle_deg(d, l) - 30.0).abs() < 1e-10);
    }

    /// Curves of one law on frames of two sizes, given as frame force
    /// against displacement: the joint fit gives the law back, whatever
    /// the frames' sizes (the normalisation's point).
    #[test]
    fn two_frame_sizes_give_back_one_law() {
        let law = ShearLocking {
            coefficients: vec![0.004, 0.002, 0.03],
            friction: None,
        };
        let h = 1.2;
        let mut texts = Vec::new();
        for (frame, fabric) in [(180.0, 140.0), (250.0, 180.0)] {
            let mut t = String::from("displacement_mm,force_N\n");
            for n in 0..=40 {
                let d = 1.5 * n as f64;
                let g = frame_angle_deg(d, frame);
                let theta = (45.0 - 0.5 * g).to_radians();
                // F·L_frame·sin θ = h·L_fabric²·τ.
                let f = h * fabric * fabric * law.stress(g.to_radians()) / (frame * theta.sin());
                let _ = writeln!(t, "{d},{f:.9e}");
            }
            texts.push(t);
        }
        let options = PictureFrameOptions {
            inputs: vec!["a.csv".into(), "b.csv".into()],
            frame: vec![180.0, 250.0],
            fabric: vec![140.0, 180.0],
            angle: false,
            force: ForceKind::Frame,
            terms: 3,
            max_angle: 60.0,
            weights: vec![],
        };
        let curves = read_curves(&options, |p| {
            Ok(texts[usize::from(p.to_str() == Some("b.csv"))].clone())
        })
        .unwrap();
        assert_eq!(curves.len(), 2);
        let fit = fit_curves(curves, h, 3).unwrap();
        for (a, b) in fit.law.coefficients.iter().zip(&law.coefficients) {
            assert!((a - b).abs() < 1e-7 * b.abs().max(1e-3), "{a} vs {b}");
        }
        assert!(fit.report().contains("joint fit"));
    }
}
