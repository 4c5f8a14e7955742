//! Two results folders side by side: `drape compare RUN_A RUN_B`.
//!
//! [`compare_runs`] reads both folders' summaries and last frames, puts
//! their measures side by side and compares their shear element by
//! element on run A's mesh, drawn flat at A's reference positions:
//!
//! - when both runs have the same mesh (the same cells and reference
//!   points), element by element;
//! - otherwise B's shear is carried onto A's elements by closest point on
//!   B's reference surface ([`drape_io::results::mapping::SurfaceField`]):
//!   at each of A's reference centroids, B's shear interpolated between
//!   its nodal means, or B's element value where A's centroid is the
//!   centroid of one of B's elements (the same cells numbered otherwise,
//!   such as a kinematic net drawn on the run's own grid). An element of A farther from B's blank than half B's
//!   typical element size has no value (B's blank does not reach there).
//!
//! The shear profiles along the blank's diagonal and median
//! (`profiles.csv`) are compared point by point where both runs sampled
//! them at the same distances (the same rectangular blank and cells): the
//! RMS of their difference along the diagonal is the measure the
//! implicit/explicit agreement cases of `cargo xtask validate` check.
//!
//! Two laminates compare ply by ply, by name ([`plies`]): each ply's
//! shear, profiles and picture (`comparison_<ply>.png` in place of
//! `comparison.png`), and `comparison.csv` with a `ply` column.
//!
//! Any two folders compare: two forming runs of one scene with different
//! settings (a sweep's runs), two meshes of one part, a forming run and a
//! kinematic drape (`drape kinematic`), whose nets are drawn on the flat
//! blank too.

use std::fmt::Write as _;
use std::path::Path;

use drape_io::results::mapping::SurfaceField;
use drape_io::results::read::{VtuFrame, read_last_frame, read_summary};
use drape_io::results::{MapPanel, ResultsError, Summary, write_flat_maps_of};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

mod plies;
pub use plies::PlyDifference;

/// What stops a comparison of two folders.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// A folder cannot be read as a run's results (bad input).
    #[error("{0}")]
    Input(String),
    /// Writing the comparison failed.
    #[error(transparent)]
    Results(#[from] ResultsError),
    /// Nothing could be compared; `comparison.json` says so with this
    /// reason.
    #[error("{0}")]
    Failed(String),
}

/// The files a comparison writes into its folder.
const COMPARISON_FILES: [&str; 3] = ["comparison.json", "comparison.csv", "comparison.png"];

/// Removes an earlier comparison's files from `out` (the caller holds the
/// folder), and the files named in `more`, so that a comparison that fails
/// cannot leave one that looks like its own.
pub(crate) fn clear_comparison(out: &Path, more: &[&str]) -> Result<(), ResultsError> {
    // An earlier comparison of laminates drew one picture per ply.
    let per_ply: Vec<String> = std::fs::read_dir(out)
        .into_iter()
        .flatten()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with("comparison_") && n.ends_with(".png"))
        .collect();
    let per_ply = per_ply.iter().map(String::as_str);
    for name in COMPARISON_FILES
        .iter()
        .copied()
        .chain(more.iter().copied())
        .chain(per_ply)
    {
        let path = out.join(name);
        match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(ResultsError { path, source: e });
            }
            _ => {}
        }
    }
    Ok(())
}

/// Writes `summary` as `out/comparison.json`, whole or not at all.
pub(crate) fn write_json(out: &Path, summary: &impl Serialize) -> Result<(), ResultsError> {
    let path = out.join("comparison.json");
    let mut json = serde_json::to_vec_pretty(summary).map_err(|e| ResultsError {
        path: path.clone(),
        source: e.into(),
    })?;
    json.push(b'\n');
    drape_io::atomic::write(&path, &json).map_err(|source| ResultsError { path, source })
}

/// One measure of both runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeasureRow {
    /// What it is.
    pub name: String,
    /// Its unit.
    pub unit: String,
    /// Run A's value (null when it has none).
    pub a: Option<f64>,
    /// Run B's value.
    pub b: Option<f64>,
    /// A count (steps): printed as an integer.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub count: bool,
}

impl MeasureRow {
    /// `v` as the console shows this measure: a count as an integer
    /// ("52794", not "52794.00000"), anything else with five decimals; "—"
    /// for no value.
    pub fn show(&self, v: Option<f64>) -> String {
        match v {
            None => "—".to_owned(),
            Some(v) if self.count => format!("{v:.0}"),
            Some(v) => format!("{v:.5}"),
        }
    }
}

/// The measures that count something, shown as integers.
const COUNTS: [&str; 1] = ["steps"];

/// `comparison.json` of two results folders.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RunComparisonSummary {
    /// `completed`, or `failed` when no element could be compared (the
    /// reason says why; the differences are then meaningless).
    #[serde(default)]
    pub status: String,
    /// Why it failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// Run A's folder.
    pub run_a: String,
    /// Run B's folder.
    pub run_b: String,
    /// Run A's status.
    pub status_a: String,
    /// Run B's status.
    pub status_b: String,
    /// The measures side by side.
    pub measures: Vec<MeasureRow>,
    /// Whether both runs have the same mesh (compared element by element)
    /// or B was carried onto A's mesh by closest point.
    pub same_mesh: bool,
    /// Elements of run A.
    pub elements: usize,
    /// Of those, elements with a value from both runs: at least one, or
    /// the comparison failed.
    pub compared: usize,
    /// `compared` over `elements`.
    #[serde(default)]
    pub compared_fraction: f64,
    /// Largest |γ_B − γ_A| (degrees).
    pub max_abs_difference_deg: f64,
    /// Where: run A's reference centroid of that element (mm).
    pub max_difference_at: [f64; 3],
    /// Root mean square of γ_B − γ_A (degrees).
    pub rms_difference_deg: f64,
    /// Mean of γ_B − γ_A (degrees).
    pub mean_difference_deg: f64,
    /// The shear profiles both runs sampled at the same distances (empty
    /// for two laminates: each ply's are in `plies`).
    #[serde(default)]
    pub profiles: Vec<ProfileDifference>,
    /// Two laminates: each ply of A with B's ply of the same name, A's
    /// order (empty for one ply).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub plies: Vec<PlyDifference>,
}

/// One shear profile of `profiles.csv` (signed γ against the initial
/// distance from the blank's centre) of both runs, point by point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProfileDifference {
    /// The line: `diagonal` or `median`.
    pub line: String,
    /// Points compared.
    pub points: usize,
    /// Root mean square of γ_B − γ_A along the line (degrees).
    pub rms_difference_deg: f64,
    /// Largest |γ_B − γ_A| along the line (degrees).
    pub max_abs_difference_deg: f64,
}

/// Two runs compared.
#[derive(Debug, Clone)]
pub struct RunComparison {
    /// The summary written to `comparison.json`.
    pub summary: RunComparisonSummary,
    /// Run A's summary.
    pub a: Summary,
    /// Run B's summary.
    pub b: Summary,
    /// Per element of run A: γ of A (degrees).
    pub a_deg: Vec<f64>,
    /// γ of B at the same material point (degrees; NaN where B has none).
    pub b_deg: Vec<f64>,
    /// A's reference centroids.
    pub centroid0: Vec<Vector3<f64>>,
}

/// A finite value, or None (JSON null).
fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// The measures of both summaries, side by side.
fn measures(a: &Summary, b: &Summary) -> Vec<MeasureRow> {
    type Get = fn(&Summary) -> f64;
    let rows: [(&str, &str, Get); 15] = [
        ("time reached", "s", |s| s.time),
        ("largest |shear| at the end", "deg", |s| s.max_shear_deg),
        ("largest |shear| over the run", "deg", |s| {
            s.peak.max_shear_deg
        }),
        ("time of that peak", "s", |s| s.peak.max_shear_time_s),
        ("draw-in DX", "mm", |s| s.draw_in_mm.dx),
        ("draw-in DY", "mm", |s| s.draw_in_mm.dy),
        ("draw-in DD", "mm", |s| s.draw_in_mm.dd),
        ("largest yarn tension at the end", "N/mm", |s| {
            s.max_fibre_tension_n_per_mm
        }),
        ("largest yarn tension over the run", "N/mm", |s| {
            s.peak.max_fibre_tension_n_per_mm
        }),
        ("largest truss force at the end", "N", |s| {
            s.max_fibre_tension_n
        }),
        ("area above the locking angle", "mm²", |s| {
            s.area_above_locking_mm2
        }),
        ("energy balance error", "", |s| s.energy.balance_error),
        ("E_kin/E_int at the end", "", |s| {
            s.energy.kinetic_to_internal
        }),
        ("steps", "", |s| s.run.steps as f64),
        ("wall time", "s", |s| s.run.wall_s),
    ];
    rows.iter()
        .map(|(name, unit, get)| MeasureRow {
            name: (*name).to_owned(),
            unit: (*unit).to_owned(),
            a: finite(get(a)),
            b: finite(get(b)),
            count: COUNTS.contains(name),
        })
        .collect()
}

/// The reference mesh and shear (degrees) of a frame.
fn shear_of(frame: &VtuFrame, dir: &Path) -> Result<Vec<f64>, CompareError> {
    frame
        .cell_scalars("shear_angle_deg")
        .map(<[f64]>::to_vec)
        .ok_or_else(|| {
            CompareError::Input(format!(
                "{}: its last frame has no shear_angle_deg",
                dir.display()
            ))
        })
}

/// Whether two frames have the same reference mesh (cells and points to
/// 1e-9 of the blank's size).
fn same_mesh(a: &VtuFrame, a0: &[Vector3<f64>], b: &VtuFrame, b0: &[Vector3<f64>]) -> bool {
    if a.cells != b.cells || a0.len() != b0.len() {
        return false;
    }
    let size = a0.iter().map(|p| p.norm()).fold(1.0f64, f64::max);
    a0.iter()
        .zip(b0)
        .all(|(p, q)| (p - q).norm() <= 1e-9 * size)
}

/// One row of `profiles.csv`: (ply, line, distance, γ), the ply empty
/// for one ply's file.
type ProfileRow = (String, String, f64, f64);

/// A folder's `profiles.csv` as rows; an empty list when the folder has
/// none (a run without a rectangular blank writes only the header; a
/// kinematic drape's folder has no file). A laminate's file (header
/// `ply,line,...`) has a ply name first.
fn read_profiles(dir: &Path) -> Result<Vec<ProfileRow>, CompareError> {
    let path = dir.join("profiles.csv");
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Ok(Vec::new());
    };
    let laminate = text.starts_with("ply,");
    let mut rows = Vec::new();
    for (k, line) in text.lines().enumerate().skip(1) {
        let fields: Vec<&str> = line.split(',').collect();
        let number = |s: &str| s.trim().parse::<f64>().ok().filter(|v| v.is_finite());
        let row = match (laminate, fields.as_slice()) {
            (false, [name, d, g]) => number(d)
                .zip(number(g))
                .map(|(d, g)| (String::new(), (*name).to_owned(), d, g)),
            (true, [ply, name, d, g]) => number(d)
                .zip(number(g))
                .map(|(d, g)| ((*ply).to_owned(), (*name).to_owned(), d, g)),
            _ => None,
        };
        match row {
            Some(row) => rows.push(row),
            None if laminate => {
                return Err(CompareError::Input(format!(
                    "{} line {}: expected a ply name, a line name and two finite numbers \
                     (ply,line,distance_mm,shear_deg), found {line:?}",
                    path.display(),
                    k + 1
                )));
            }
            None => {
                return Err(CompareError::Input(format!(
                    "{} line {}: expected a line name and two finite numbers \
                     (line,distance_mm,shear_deg), found {line:?}",
                    path.display(),
                    k + 1
                )));
            }
        }
    }
    Ok(rows)
}

/// The rows of `rows` of the ply `ply` ("" for one ply's file) as (line,
/// distance, γ).
fn ply_rows(rows: &[ProfileRow], ply: &str) -> Vec<(String, f64, f64)> {
    rows.iter()
        .filter(|r| r.0 == ply)
        .map(|r| (r.1.clone(), r.2, r.3))
        .collect()
}

/// The profiles of A and B compared line by line, where both sampled a
/// line at the same distances (to 1e-6 mm per mm).
fn profile_differences(
    a: &[(String, f64, f64)],
    b: &[(String, f64, f64)],
) -> Vec<ProfileDifference> {
    let mut lines: Vec<&str> = Vec::new();
    for (name, _, _) in a {
        if !lines.contains(&name.as_str()) {
            lines.push(name);
        }
    }
    let points = |rows: &[(String, f64, f64)], line: &str| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|r| r.0 == line)
            .map(|r| (r.1, r.2))
            .collect()
    };
    lines
        .into_iter()
        .filter_map(|line| {
            let (pa, pb) = (points(a, line), points(b, line));
            let same = pa.len() == pb.len()
                && pa
                    .iter()
                    .zip(&pb)
                    .all(|(p, q)| (p.0 - q.0).abs() <= 1e-6 * p.0.abs().max(1.0));
            if pa.is_empty() || !same {
                return None;
            }
            let d: Vec<f64> = pa.iter().zip(&pb).map(|(p, q)| q.1 - p.1).collect();
            Some(ProfileDifference {
                line: line.to_owned(),
                points: d.len(),
                rms_difference_deg: (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt(),
                max_abs_difference_deg: d.iter().fold(0.0f64, |m, x| m.max(x.abs())),
            })
        })
        .collect()
}

/// Compares the results folders `a` and `b` and writes into `out`
/// (created if needed) `comparison.json` ([`RunComparisonSummary`]),
/// `comparison.csv` (per element of A: reference centroid, γ_A, γ_B and
/// γ_B − γ_A) and `comparison.png` (A's |γ|, B's |γ| on one colour scale
/// and |γ|_B − |γ|_A, on A's flat blank).
pub fn compare_runs(a: &Path, b: &Path, out: &Path) -> Result<RunComparison, CompareError> {
    let input = CompareError::Input;
    let (sa, sb) = (
        read_summary(a).map_err(input)?,
        read_summary(b).map_err(input)?,
    );
    let (fa, fb) = (
        read_last_frame(a).map_err(input)?,
        read_last_frame(b).map_err(input)?,
    );
    let (a0, b0) = (fa.reference_points(), fb.reference_points());
    let (ga, gb) = (shear_of(&fa, a)?, shear_of(&fb, b)?);
    if ga.len() != fa.cells.len() || gb.len() != fb.cells.len() {
        return Err(input(format!(
            "{} or {}: a shear array does not match its cells",
            a.display(),
            b.display()
        )));
    }
    let centroid = |points: &[Vector3<f64>], cell: &[u32]| {
        cell.iter()
            .map(|&n| points[n as usize])
            .sum::<Vector3<f64>>()
            / cell.len() as f64
    };
    let centroid0: Vec<Vector3<f64>> = fa.cells.iter().map(|c| centroid(&a0, c)).collect();
    let (pa, pb) = (
        plies::run_plies(a, &sa, &fa)?,
        plies::run_plies(b, &sb, &fb)?,
    );
    let (ra, rb) = (read_profiles(a)?, read_profiles(b)?);
    let mut ply_differences = Vec::new();
    // Each of A's elements' ply, for a laminate's table.
    let mut ply_of = Vec::new();
    let (b_deg, same) = match (
        plies::match_plies((a, pa.as_ref()), (b, pb.as_ref()))?,
        &pa,
        &pb,
    ) {
        (Some(matched), Some(pa), Some(pb)) => {
            let mut b_deg = vec![f64::NAN; ga.len()];
            ply_of = vec![""; ga.len()];
            let mut all_same = true;
            for (k, &j) in matched.iter().enumerate() {
                let (ca, cb) = (&pa.cells[k], &pb.cells[j]);
                let same = plies::same_cells((&fa, &a0, ca), (&fb, &b0, cb));
                if same {
                    for (&i, &m) in ca.iter().zip(cb) {
                        b_deg[i] = gb[m];
                    }
                } else {
                    let cells: Vec<Vec<u32>> = cb.iter().map(|&c| fb.cells[c].clone()).collect();
                    let values: Vec<f64> = cb.iter().map(|&c| gb[c]).collect();
                    let at: Vec<Vector3<f64>> = ca.iter().map(|&c| centroid0[c]).collect();
                    for (&i, v) in ca.iter().zip(carried(&b0, &cells, &values, &at, b)?) {
                        b_deg[i] = v;
                    }
                }
                all_same &= same;
                let name = &pa.names[k];
                ca.iter().for_each(|&i| ply_of[i] = name.as_str());
                let mut d = PlyDifference::of(name, same, ca, &ga, &b_deg, &centroid0);
                d.profiles = profile_differences(&ply_rows(&ra, name), &ply_rows(&rb, name));
                ply_differences.push(d);
            }
            (b_deg, all_same)
        }
        _ => {
            let same = same_mesh(&fa, &a0, &fb, &b0);
            let b_deg = if same {
                gb.clone()
            } else {
                carried(&b0, &fb.cells, &gb, &centroid0, b)?
            };
            (b_deg, same)
        }
    };
    let mut summary = RunComparisonSummary {
        run_a: a.display().to_string(),
        run_b: b.display().to_string(),
        status_a: sa.status.clone(),
        status_b: sb.status.clone(),
        measures: measures(&sa, &sb),
        profiles: if ply_differences.is_empty() {
            profile_differences(&ply_rows(&ra, ""), &ply_rows(&rb, ""))
        } else {
            Vec::new()
        },
        plies: ply_differences,
        same_mesh: same,
        elements: ga.len(),
        ..RunComparisonSummary::default()
    };
    let stats = Differences::of(ga.iter().zip(&b_deg).map(|(x, y)| y - x).enumerate());
    summary.compared = stats.compared;
    summary.max_abs_difference_deg = stats.max_abs;
    if let Some(e) = stats.max_at {
        summary.max_difference_at = centroid0[e].into();
    }
    summary.mean_difference_deg = stats.mean;
    summary.rms_difference_deg = stats.rms;
    summary.compared_fraction = summary.compared as f64 / summary.elements.max(1) as f64;

    std::fs::create_dir_all(out).map_err(|source| ResultsError {
        path: out.to_owned(),
        source,
    })?;
    clear_comparison(out, &[])?;
    if let Some(reason) = nothing_compared(&summary, same, gb.len()) {
        summary.status = "failed".to_owned();
        summary.reason = Some(reason.clone());
        write_json(out, &summary)?;
        return Err(CompareError::Failed(reason));
    }
    summary.status = "completed".to_owned();
    let at = |name: &str| {
        let path = out.join(name);
        move |source| ResultsError { path, source }
    };
    // No NaN in a table: a value that cannot be had is an empty field.
    let number = |v: f64| drape_io::finite::or_empty(v, |v| v.to_string());
    let mut csv = String::from("element,x0_mm,y0_mm,z0_mm,a_deg,b_deg,difference_deg\n");
    if !ply_of.is_empty() {
        csv.insert_str(0, "ply,");
    }
    for (e, c) in centroid0.iter().enumerate() {
        if let Some(ply) = ply_of.get(e) {
            let _ = write!(csv, "{ply},");
        }
        let _ = writeln!(
            csv,
            "{e},{},{},{},{},{},{}",
            number(c.x),
            number(c.y),
            number(c.z),
            number(ga[e]),
            number(b_deg[e]),
            number(b_deg[e] - ga[e])
        );
    }
    drape_io::atomic::write(&out.join("comparison.csv"), csv.as_bytes())
        .map_err(at("comparison.csv"))?;
    let magnitude = |v: &[f64]| -> Vec<f64> { v.iter().map(|g| g.abs()).collect() };
    let (ma, mb) = (magnitude(&ga), magnitude(&b_deg));
    let difference: Vec<f64> = ma.iter().zip(&mb).map(|(x, y)| y - x).collect();
    let shared = ma
        .iter()
        .chain(&mb)
        .filter(|v| v.is_finite())
        .fold(0.0f64, |m, &v| m.max(v));
    let name = |p: &Path| {
        p.file_name().map_or_else(
            || p.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        )
    };
    // The three panels of A's elements `cells` (all for one ply), titled
    // with `ply` (a laminate's).
    let picture = |file: &str, cells: &[usize], ply: &str| {
        let pick = |v: &[f64]| -> Vec<f64> { cells.iter().map(|&e| v[e]).collect() };
        let (ma, mb, difference) = (pick(&ma), pick(&mb), pick(&difference));
        let cells: Vec<Vec<u32>> = cells.iter().map(|&e| fa.cells[e].clone()).collect();
        write_flat_maps_of(
            &out.join(file),
            &a0,
            &cells,
            &[
                MapPanel {
                    title: format!("A: {} ({}): |γ|{ply}", name(a), sa.status),
                    values: &ma,
                    label: "|γ| (deg)".into(),
                    signed: false,
                    scale: Some(shared),
                    range: None,
                },
                MapPanel {
                    title: format!("B: {} ({}): |γ|{ply}", name(b), sb.status),
                    values: &mb,
                    label: "|γ| (deg)".into(),
                    signed: false,
                    scale: Some(shared),
                    range: None,
                },
                MapPanel {
                    title: format!("Difference: |γ| B − |γ| A{ply}"),
                    values: &difference,
                    label: "difference (deg)".into(),
                    signed: true,
                    scale: None,
                    range: None,
                },
            ],
        )
    };
    match &pa {
        // A laminate one ply per picture, on the laminate's colour scale:
        // on one flat blank the top ply would hide the others.
        Some(pa) if !summary.plies.is_empty() => {
            for (name, cells) in pa.names.iter().zip(&pa.cells) {
                picture(
                    &format!("comparison_{name}.png"),
                    cells,
                    &format!(", ply {name}"),
                )?;
            }
        }
        _ => picture("comparison.png", &(0..ga.len()).collect::<Vec<_>>(), "")?,
    }
    write_json(out, &summary)?;
    Ok(RunComparison {
        summary,
        a: sa,
        b: sb,
        a_deg: ga,
        b_deg,
        centroid0,
    })
}

/// B's values `values` on its cells `cells` (reference points `b0`)
/// carried to the points `at` by closest point on B's reference surface:
/// NaN farther than half B's typical element size (B's blank does not
/// reach there). `b` names B's folder in an error.
fn carried(
    b0: &[Vector3<f64>],
    cells: &[Vec<u32>],
    values: &[f64],
    at: &[Vector3<f64>],
    b: &Path,
) -> Result<Vec<f64>, CompareError> {
    let field = SurfaceField::new(b0, cells, &[values.to_vec()])
        .map_err(|e| CompareError::Input(format!("{}: {e}", b.display())))?;
    let area: f64 = cells
        .iter()
        .map(|c| {
            let p = |k: usize| b0[c[k] as usize];
            if c.len() == 4 {
                0.5 * (p(2) - p(0)).cross(&(p(3) - p(1))).norm()
            } else {
                0.5 * (p(1) - p(0)).cross(&(p(2) - p(0))).norm()
            }
        })
        .sum();
    let reach = 0.5 * (area / cells.len().max(1) as f64).sqrt();
    Ok(at
        .iter()
        .map(|c| {
            let s = field.sample(c);
            if s.distance <= reach {
                s.values[0]
            } else {
                f64::NAN
            }
        })
        .collect())
}

/// Why a comparison compared nothing, for the whole or for a ply of a
/// laminate (`b_elements`: B's element count): "0 of N compared, largest
/// difference 0°" would read as agreement.
fn nothing_compared(
    summary: &RunComparisonSummary,
    same_mesh: bool,
    b_elements: usize,
) -> Option<String> {
    if summary.compared > 0 {
        return summary.plies.iter().find(|p| p.compared == 0).map(|p| {
            format!(
                "no element of ply `{}` compared: none of its {} elements in A has a finite \
                 shear in both runs and lies within half an element of B's ply `{}`",
                p.name, p.elements, p.name
            )
        });
    }
    Some(if same_mesh {
        format!(
            "no element compared: the two runs share their mesh, but none of its {} elements \
             has a finite shear in both",
            summary.elements
        )
    } else {
        format!(
            "no element compared: none of A's {} elements lies within half an element of B's \
             blank ({b_elements} elements): the two blanks do not overlap (placed apart, or not \
             the same part)",
            summary.elements
        )
    })
}

/// The largest, mean and RMS of element differences, those that are not
/// finite (an element B does not cover) left out.
pub(crate) struct Differences {
    pub compared: usize,
    pub max_abs: f64,
    /// The element of the largest (none when every difference is 0).
    pub max_at: Option<usize>,
    pub mean: f64,
    pub rms: f64,
}

impl Differences {
    /// Of (element, difference) pairs.
    pub fn of(differences: impl Iterator<Item = (usize, f64)>) -> Self {
        let mut d = Self {
            compared: 0,
            max_abs: 0.0,
            max_at: None,
            mean: 0.0,
            rms: 0.0,
        };
        let (mut sum, mut sum2) = (0.0, 0.0);
        for (e, x) in differences {
            if !x.is_finite() {
                continue;
            }
            d.compared += 1;
            sum += x;
            sum2 += x * x;
            if x.abs() > d.max_abs {
                d.max_abs = x.abs();
                d.max_at = Some(e);
            }
        }
        let n = d.compared.max(1) as f64;
        d.mean = sum / n;
        d.rms = (sum2 / n).sqrt();
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ply_with_nothing_compared_fails_the_comparison_naming_it() {
        let ply = |name: &str, compared| plies::PlyDifference {
            name: name.to_owned(),
            elements: 16,
            compared,
            ..plies::PlyDifference::default()
        };
        let mut summary = RunComparisonSummary {
            elements: 32,
            compared: 16,
            plies: vec![ply("p0", 16), ply("p45", 0)],
            ..RunComparisonSummary::default()
        };
        let reason = nothing_compared(&summary, true, 32).expect("a ply compared nothing");
        assert!(reason.contains("ply `p45`"), "{reason}");
        summary.plies[1].compared = 16;
        summary.compared = 32;
        assert_eq!(nothing_compared(&summary, true, 32), None);
        summary.plies.clear();
        summary.compared = 0;
        let reason = nothing_compared(&summary, false, 20).expect("nothing compared");
        assert!(reason.contains("(20 elements)"), "{reason}");
    }

    #[test]
    fn step_counts_show_as_integers_and_measures_with_decimals() {
        let mut a = Summary::default();
        a.run.steps = 52794;
        a.time = 0.25;
        let mut b = a.clone();
        b.run.steps = 52800;
        let rows = measures(&a, &b);
        let steps = rows.iter().find(|m| m.name == "steps").unwrap();
        assert!(steps.count);
        assert_eq!(steps.show(steps.a), "52794");
        assert_eq!(steps.show(steps.a.zip(steps.b).map(|(a, b)| b - a)), "6");
        let time = rows.iter().find(|m| m.name == "time reached").unwrap();
        assert!(!time.count);
        assert_eq!(time.show(time.a), "0.25000");
        assert_eq!(time.show(None), "—");
        // Only counts are marked.
        assert_eq!(rows.iter().filter(|m| m.count).count(), COUNTS.len());
    }
}
