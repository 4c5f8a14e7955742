//! The paper's two experiments beside drape (El Hami, Radi, Cherouat
//! 2009; /work/shared/reference, §5.1 Table 2 and §5.2 Table 4), the
//! hemisphere's holding, and the hemisphere's mesh convergence.
//!
//! - `paper/hemisphere-table2`: the laying-up on the hemisphere at
//!   μ = 0, 0.1, 0.2, 0.5 for 0/90 and ±45 fibres; the maximum shear beside
//!   the experiment and the paper's simulation, with both errors, and the
//!   shear profiles like the paper's Fig. 7 (PNG).
//! - `paper/deep-drawing-table4`: the deep drawing's draw-in DX, DY, DD at
//!   μ = 0.01, 0.1, 0.2, 0.4, the same way, and the profiles like Fig. 12.
//! - `paper/hemisphere-holding`: the shipped point springs against a frame
//!   of springs distributed along the blank's edge (`per_length`), over
//!   their stiffness: the maximum shear anywhere and away from the holding.
//! - `paper/mesh-convergence`: the hemisphere at 10×10 … 80×80 (160×160 in
//!   full mode; `DRAPE_CONVERGENCE_MAX_CELLS=80` stops at 80×80) with the
//!   observed order and the Richardson extrapolation.
//!
//! Every case is also quick: under `--quick` it runs a coarse version
//! (20×20 cells, the hemisphere's mass-scaling step doubled with the cell
//! size) whose checks are the runs' health only, since a coarse mesh is not
//! the paper's. What each full-mode check asserts, and why, is written
//! beside it. The runs go through `scenes.rs`'s [`Run`] and
//! [`execute_all`] (the shipped scene files changed only by `--set`-style
//! overrides). The PNGs go to `<target>/validation/paper/`.
//!
//! Not for: the speed of these runs (`cargo xtask bench`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use drape_io::results::write_profile_comparison;
use drape_model::measures::ProfilePoint;

use super::scenes::{
    AWAY_FROM_HOLDING_MM, Orientation, Outcome, Run, execute_all, friction, mesh, run_table,
    stroke_checks,
};
use super::{Case, Check, note, quick_mode};

/// The cases of this module.
pub const CASES: &[Case] = &[
    Case {
        name: "paper/hemisphere-table2",
        quick: true,
        run: hemisphere_table_2,
    },
    Case {
        name: "paper/deep-drawing-table4",
        quick: true,
        run: deep_drawing_table_4,
    },
    Case {
        name: "paper/hemisphere-holding",
        quick: true,
        run: hemisphere_holding,
    },
    Case {
        name: "paper/mesh-convergence",
        quick: true,
        run: mesh_convergence,
    },
];

/// The shipped hemisphere's mesh and mass-scaling step (a test checks
/// that they are the scene files').
const HEMISPHERE_CELLS: usize = 40;
const HEMISPHERE_MASS_SCALING_DT: f64 = 2e-5;

/// The hemisphere at `cells`×`cells` with the mass-scaling step in
/// proportion to the cell size, so every mesh carries the same added mass
/// per area: the stable step of a membrane is ∝ h·√(ρ/E), so a step ∝ h
/// needs the same ρ at every h, and a finer mesh solves the same
/// (mass-scaled) problem instead of a heavier one.
fn hemisphere_mesh(cells: usize) -> Vec<(&'static str, String)> {
    let dt = HEMISPHERE_MASS_SCALING_DT * HEMISPHERE_CELLS as f64 / cells as f64;
    vec![
        ("fabric.blank.cells", format!("[{cells}, {cells}]")),
        ("simulation.mass_scaling_dt", format!("{dt:e}")),
    ]
}

/// The mesh of this mode: 20×20 under `--quick`, the shipped 40×40 else.
fn hemisphere_cells() -> usize {
    if quick_mode() { 20 } else { HEMISPHERE_CELLS }
}

fn hemisphere_run(
    orientation: Orientation,
    label: impl Into<String>,
    overrides: &[(&str, String)],
) -> Run {
    let mut all = hemisphere_mesh(hemisphere_cells());
    all.extend(overrides.iter().cloned());
    Run::of(orientation.scene("hemisphere"), orientation, label, &all)
}

/// Where the PNGs go.
fn pictures_dir() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace");
    super::target_dir(root).join("validation").join("paper")
}

/// Writes one PNG of profiles (the paper's Figs. 7 and 12) and returns a
/// line for the report naming it.
fn profile_picture(file: &str, title: &str, curves: &[(String, &[ProfilePoint])]) -> String {
    let dir = pictures_dir();
    let path = dir.join(file);
    let written = std::fs::create_dir_all(&dir)
        .map_err(|e| e.to_string())
        .and_then(|()| write_profile_comparison(&path, title, curves).map_err(|e| e.to_string()));
    match written {
        Ok(()) => format!("Profiles: `{}`.", path.display()),
        Err(e) => panic!("could not write {}: {e}", path.display()),
    }
}

/// The checks every hemisphere run must pass: it reaches the end time with
/// the punch at its full stroke and the energy balance closes to 1e-3 of
/// the largest energy. (Not E_kin/E_int < 1e-3 as for the deep drawing:
/// the shipped hemisphere ends at 1.4e-3 with its hanging skirt still
/// swinging, which the summary reports.)
fn hemisphere_checks(o: &Outcome) -> Vec<Check> {
    let mut checks = stroke_checks(o);
    checks.truncate(3);
    checks
}

/// The paper's Table 2 (maximum shear, degrees): (orientation, experiment,
/// simulation at μ = 0, 0.1, 0.2, 0.5).
const TABLE_2: [(Orientation, f64, [f64; 4]); 2] = [
    (Orientation::ZeroNinety, 31.0, [29.12, 29.85, 27.7, 25.247]),
    (
        Orientation::PlusMinus45,
        28.0,
        [30.57, 29.72, 25.22, 23.501],
    ),
];
const TABLE_2_FRICTIONS: [f64; 4] = [0.0, 0.1, 0.2, 0.5];

/// The paper's largest |simulation − experiment| of an orientation's row:
/// the accuracy its authors reached with their own undocumented choices.
fn paper_error_band(paper: &[f64], experiment: f64) -> f64 {
    paper
        .iter()
        .map(|p| (p - experiment).abs())
        .fold(0.0, f64::max)
}

fn hemisphere_table_2() -> Vec<Check> {
    // Quick: the two extreme frictions only.
    let frictions: &[f64] = if quick_mode() {
        &[0.0, 0.5]
    } else {
        &TABLE_2_FRICTIONS
    };
    let mut runs = Vec::new();
    for (orientation, _, _) in TABLE_2 {
        for &mu in frictions {
            runs.push(hemisphere_run(
                orientation,
                format!("μ = {mu}"),
                &[("tools.0.friction", mu.to_string())],
            ));
        }
    }
    let outcomes = execute_all(&runs);
    let mut checks: Vec<Check> = outcomes.iter().flat_map(hemisphere_checks).collect();
    let cells = hemisphere_cells();
    let mut text = format!(
        "Table 2 of the paper (maximum shear angle, degrees) beside drape, {cells}×{cells} cells, \
         the shipped scenes (8 point springs of 1 N/mm) with the friction changed. \"Away\" is the \
         largest shear more than {AWAY_FROM_HOLDING_MM} mm (in the flat blank) from every spring's \
         node. Errors against the experiment.\n\n\
         | fibres | μ | exp. | paper | drape, anywhere | drape, away | paper − exp. | drape − exp. (anywhere) | drape − exp. (away) |\n\
         |---|--:|--:|--:|--:|--:|--:|--:|--:|\n"
    );
    for (orientation, experiment, paper) in TABLE_2 {
        let band = paper_error_band(&paper, experiment);
        for (k, mu) in TABLE_2_FRICTIONS.into_iter().enumerate() {
            let Some(o) = outcomes
                .iter()
                .find(|o| o.run.orientation == orientation && o.run.label == format!("μ = {mu}"))
            else {
                continue;
            };
            let _ = writeln!(
                text,
                "| {} | {mu} | {experiment} | {} | {:.2} | {:.2} | {:+.2} | {:+.2} | {:+.2} |",
                orientation.label(),
                paper[k],
                o.max_shear_deg,
                o.max_shear_away_deg,
                paper[k] - experiment,
                o.max_shear_deg - experiment,
                o.max_shear_away_deg - experiment,
            );
            // The experiment is the truth; the paper's spread over μ is the
            // accuracy reached with its own undocumented choices (springs,
            // tool mesh). Table 2's measure is the maximum anywhere. A
            // coarse mesh is not the paper's, so only full mode asserts it.
            if !quick_mode() {
                checks.push(Check::abs(
                    format!(
                        "{} μ = {mu}: max shear (°) within the paper's own error band of the experiment",
                        orientation.label()
                    ),
                    experiment,
                    o.max_shear_deg,
                    band,
                ));
            }
        }
    }
    text.push_str(
        "\nSource: El Hami, Radi, Cherouat (2009), Table 2; the experiment is one test per \
         orientation (no friction given), so the table has no experimental trend with μ.\n\n\
         Why drape and the paper differ, by undocumented choice: the holding (the paper's 24 \
         nonlinear springs are not described; drape's 8 linear ones are stretched about 200 mm \
         by the 300 mm stroke, so their force, and the shear, follow their stiffness: the \
         sensitivity rows are `paper/hemisphere-holding`); the mesh (the maximum is not converged \
         at 40×40, see `paper/mesh-convergence`); the tool is documented (r = 120 mm) but its \
         faceting (1600 rigid elements in the paper, an exact sphere here) is not a free choice; \
         the shear law is the carbon preset's (Table 1) resin in both. With point springs the \
         maximum anywhere sits beside a spring (anywhere > away), where Table 2 cannot tell \
         whether the paper's did.\n\n",
    );
    for (orientation, line, file) in [
        (
            Orientation::ZeroNinety,
            "diagonal",
            "hemisphere-0-90-diagonal.png",
        ),
        (
            Orientation::PlusMinus45,
            "median",
            "hemisphere-45-median.png",
        ),
    ] {
        let curves: Vec<(String, &[ProfilePoint])> = frictions
            .iter()
            .map(|mu| {
                let o = find(&outcomes, orientation, &format!("μ = {mu}"));
                (format!("μ = {mu}"), o.profile(line))
            })
            .collect();
        let title = format!(
            "Hemisphere {}: shear along the {line} (paper Fig. 7), {cells}×{cells}",
            orientation.label()
        );
        text.push_str(&profile_picture(file, &title, &curves));
        text.push('\n');
    }
    text.push('\n');
    text.push_str(&run_table(&outcomes));
    note(text);
    checks
}

fn find<'a>(outcomes: &'a [Outcome], orientation: Orientation, label: &str) -> &'a Outcome {
    outcomes
        .iter()
        .find(|o| o.run.orientation == orientation && o.run.label == label)
        .unwrap_or_else(|| panic!("no run {} {label}", orientation.label()))
}

/// The paper's Table 4: (orientation, quantity, experiment, simulation at
/// μ = 0.01, 0.1, 0.2, 0.4). DY equals DX in every entry.
const TABLE_4: [(Orientation, &str, f64, [f64; 4]); 4] = [
    (
        Orientation::ZeroNinety,
        "DX = DY",
        44.0,
        [43.8, 42.3, 41.0, 40.2],
    ),
    (Orientation::ZeroNinety, "DD", 10.0, [9.6, 8.7, 8.64, 8.33]),
    (
        Orientation::PlusMinus45,
        "DX = DY",
        10.0,
        [8.3, 8.3, 8.3, 8.21],
    ),
    (
        Orientation::PlusMinus45,
        "DD",
        42.0,
        [38.3, 38.3, 38.3, 37.38],
    ),
];

const TABLE_4_FRICTIONS: [f64; 4] = [0.01, 0.1, 0.2, 0.4];

/// The friction the paper states for its deep drawing (§5.2).
const TABLE_4_PAPER_MU: f64 = 0.1;

/// Table 4: full mode at the shipped mesh (40×40 quads), all four
/// frictions; quick mode at 20×20, μ = 0.01 and 0.2. Not 0.4 in quick
/// mode: at 20×20 the 0/90 run stops at t = 0.398 s with a contact fault
/// (a node under the die's fillet moves 0.5701 mm in one step, beyond the
/// 0.57 mm the contact resolves), which 40×40 does not show; that is a
/// finding about coarse meshes at high friction, reported, not a CI guard.
fn deep_drawing_table_4() -> Vec<Check> {
    let (frictions, cells): (&[f64], usize) = if quick_mode() {
        (&[0.01, 0.2], 20)
    } else {
        (&TABLE_4_FRICTIONS, 40)
    };
    let mut runs = Vec::new();
    for orientation in Orientation::BOTH {
        for &mu in frictions {
            let mut overrides = friction(mu);
            overrides.extend(mesh(cells, "quad"));
            runs.push(Run::new(orientation, format!("μ = {mu}"), &overrides));
        }
    }
    let outcomes = execute_all(&runs);
    let mut checks: Vec<Check> = outcomes.iter().flat_map(stroke_checks).collect();
    // The band: the paper's largest error at the friction it states.
    let k_paper = TABLE_4_FRICTIONS
        .iter()
        .position(|&m| m == TABLE_4_PAPER_MU)
        .expect("the paper's μ is in the table");
    let band = TABLE_4
        .iter()
        .map(|(_, _, exp, paper)| (paper[k_paper] - exp).abs())
        .fold(0.0, f64::max);
    let mut text = format!(
        "Table 4 of the paper (draw-in, mm) beside drape, {cells}×{cells} quads, trusses, the \
         shipped scenes with the friction of all three tools changed. Errors against the \
         experiment.\n\n\
         | fibres | draw-in | exp. | μ | paper | drape | paper − exp. | drape − exp. |\n\
         |---|---|--:|--:|--:|--:|--:|--:|\n"
    );
    for (orientation, quantity, exp, paper) in TABLE_4 {
        for (k, mu) in TABLE_4_FRICTIONS.into_iter().enumerate() {
            let Some(o) = outcomes
                .iter()
                .find(|o| o.run.orientation == orientation && o.run.label == format!("μ = {mu}"))
            else {
                continue;
            };
            let drape = if quantity == "DD" {
                o.draw_in.dd
            } else {
                o.draw_in.dx
            };
            let _ = writeln!(
                text,
                "| {} | {quantity} | {exp} | {mu} | {} | {drape:.2} | {:+.2} | {:+.2} |",
                orientation.label(),
                paper[k],
                paper[k] - exp,
                drape - exp
            );
            // At the friction the paper states (μ = 0.1), drape is asked to
            // be as close to the experiment as the paper's worst column
            // there (3.7 mm, ±45 DD): the paper's own accuracy with its own
            // undocumented tools. Only in full mode (the shipped mesh).
            if !quick_mode() && mu == TABLE_4_PAPER_MU {
                checks.push(Check::abs(
                    format!(
                        "{} μ = {mu}: {quantity} (mm) within the paper's error band ({band} mm) of the experiment",
                        orientation.label()
                    ),
                    exp,
                    drape,
                    band,
                ));
            }
        }
    }
    text.push_str(
        "\nSource: El Hami, Radi, Cherouat (2009), Table 4 (one experiment per orientation). \
         Where drape misses by more than the paper: the ±45 DX (the tool radii and holder force \
         move it by < 2 mm, see `scenes/deep-drawing-sensitivity`; the resin's linear shear law \
         without locking is the likelier cause) and 0/90 DD at μ = 0.01.\n\n",
    );
    for (orientation, line, file) in [
        (
            Orientation::ZeroNinety,
            "diagonal",
            "deep-drawing-0-90-diagonal.png",
        ),
        (
            Orientation::PlusMinus45,
            "median",
            "deep-drawing-45-median.png",
        ),
    ] {
        let curves: Vec<(String, &[ProfilePoint])> = outcomes
            .iter()
            .filter(|o| o.run.orientation == orientation)
            .map(|o| (o.run.label.clone(), o.profile(line)))
            .collect();
        let title = format!(
            "Deep drawing {}: shear along the {line} (paper Fig. 12), {cells}×{cells}",
            orientation.label()
        );
        text.push_str(&profile_picture(file, &title, &curves));
        text.push('\n');
    }
    text.push('\n');
    text.push_str(&run_table(&outcomes));
    note(text);
    checks
}

/// The blank's outline length of the shipped hemisphere (mm): a frame of
/// edge springs with the same total stiffness as the 8 point springs has
/// 8·k / 1400 N/mm per mm of edge.
const HEMISPHERE_OUTLINE_MM: f64 = 4.0 * 350.0;

/// Point springs against edge springs of the same total stiffness, over
/// the stiffness, 0/90 at μ = 0.1.
fn hemisphere_holding() -> Vec<Check> {
    let stiffnesses: &[f64] = if quick_mode() {
        &[0.5, 2.0]
    } else {
        &[0.5, 1.0, 2.0, 5.0]
    };
    let o = Orientation::ZeroNinety;
    let mut runs = Vec::new();
    for &k in stiffnesses {
        runs.push(hemisphere_run(
            o,
            format!("8 point springs, {k} N/mm each"),
            &[("springs.0.stiffness", k.to_string())],
        ));
        let per_mm = 8.0 * k / HEMISPHERE_OUTLINE_MM;
        runs.push(hemisphere_run(
            o,
            format!(
                "edge springs, {per_mm:.3e} N/mm per mm (total {} N/mm)",
                8.0 * k
            ),
            &[
                ("springs.0.nodes", "\"boundary\"".into()),
                ("springs.0.per_length", "true".into()),
                ("springs.0.stiffness", format!("{per_mm:e}")),
            ],
        ));
    }
    let outcomes = execute_all(&runs);
    let mut checks: Vec<Check> = outcomes.iter().flat_map(hemisphere_checks).collect();
    // The edge frame's claim: the largest shear is not made by the holding,
    // i.e. it lies outside the holding's neighbourhood (the two maxima are
    // the same element's, so equal to the bit).
    for o in outcomes.iter().filter(|o| o.run.label.starts_with("edge")) {
        checks.push(Check::abs(
            format!(
                "{}: max shear away from the edge (°) = max anywhere",
                o.run.name()
            ),
            o.max_shear_deg,
            o.max_shear_away_deg,
            0.0,
        ));
    }
    let cells = hemisphere_cells();
    let mut text = format!(
        "Holding of the hemisphere (0/90, μ = 0.1, {cells}×{cells}): the shipped 8 point springs \
         against a frame of springs along the whole edge (`per_length = true` on the set \
         `boundary`) with the same total stiffness. \"Away\" leaves out the elements within \
         {AWAY_FROM_HOLDING_MM} mm of a held node (for the edge frame: a band along the edge). \
         The paper: 29.85°; the experiment 31°.\n\n\
         | holding | max shear anywhere | max shear away | DX | DD |\n\
         |---|--:|--:|--:|--:|\n"
    );
    for o in &outcomes {
        let _ = writeln!(
            text,
            "| {} | {:.2} | {:.2} | {:.2} | {:.2} |",
            o.run.label, o.max_shear_deg, o.max_shear_away_deg, o.draw_in.dx, o.draw_in.dd
        );
    }
    let curves: Vec<(String, &[ProfilePoint])> = outcomes
        .iter()
        .map(|o| (o.run.label.clone(), o.profile_diagonal.as_slice()))
        .collect();
    text.push('\n');
    text.push_str(&profile_picture(
        "hemisphere-holding-diagonal.png",
        &format!("Hemisphere 0/90, μ = 0.1: shear along the diagonal by holding, {cells}×{cells}"),
        &curves,
    ));
    text.push_str("\n\n");
    text.push_str(&run_table(&outcomes));
    note(text);
    checks
}

/// One scalar of the mesh-convergence table.
struct Measure {
    name: &'static str,
    of: fn(&Outcome) -> f64,
}

/// The mean |γ| along the diagonal within `reach` mm of the centre, by the
/// trapezoidal rule over the mean curve (elements at equal distances
/// averaged): a profile as one number that converges like the field.
fn diagonal_mean(o: &Outcome, reach: f64) -> f64 {
    let curve = mean_curve(&o.profile_diagonal);
    let inside: Vec<(f64, f64)> = curve.into_iter().filter(|p| p.0.abs() <= reach).collect();
    let (mut area, mut span) = (0.0, 0.0);
    for w in inside.windows(2) {
        let h = w[1].0 - w[0].0;
        area += 0.5 * h * (w[0].1 + w[1].1);
        span += h;
    }
    if span > 0.0 { area / span } else { f64::NAN }
}

/// |γ| along the diagonal at distance `d`, linear between element centroids.
fn diagonal_at(o: &Outcome, d: f64) -> f64 {
    let curve = mean_curve(&o.profile_diagonal);
    curve
        .windows(2)
        .find(|w| w[0].0 <= d && d <= w[1].0)
        .map_or(f64::NAN, |w| {
            let t = (d - w[0].0) / (w[1].0 - w[0].0);
            w[0].1 + t * (w[1].1 - w[0].1)
        })
}

/// (distance, |γ|) averaged over elements at equal distance, sorted.
fn mean_curve(points: &[ProfilePoint]) -> Vec<(f64, f64)> {
    let mut curve: Vec<(f64, f64, usize)> = Vec::new();
    for p in points {
        match curve.last_mut() {
            Some((d, sum, n)) if (p.distance - *d).abs() <= 1e-9 * d.abs().max(1.0) => {
                *sum += p.shear_deg.abs();
                *n += 1;
            }
            _ => curve.push((p.distance, p.shear_deg.abs(), 1)),
        }
    }
    curve
        .into_iter()
        .map(|(d, s, n)| (d, s / n as f64))
        .collect()
}

const MEASURES: [Measure; 7] = [
    Measure {
        name: "max shear anywhere (°)",
        of: |o| o.max_shear_deg,
    },
    Measure {
        name: "max shear away from the springs (°)",
        of: |o| o.max_shear_away_deg,
    },
    Measure {
        name: "diagonal |γ| at d = 100 mm (°)",
        of: |o| diagonal_at(o, 100.0),
    },
    Measure {
        name: "diagonal |γ| at d = 200 mm (°)",
        of: |o| diagonal_at(o, 200.0),
    },
    Measure {
        name: "diagonal mean |γ|, |d| ≤ 200 mm (°)",
        of: |o| diagonal_mean(o, 200.0),
    },
    Measure {
        name: "DX (mm)",
        of: |o| o.draw_in.dx,
    },
    Measure {
        name: "DD (mm)",
        of: |o| o.draw_in.dd,
    },
];

/// Observed order and Richardson extrapolation from three values on meshes
/// refined by 2 (coarse, medium, fine): p = log2((f_c − f_m)/(f_m − f_f)),
/// f* = f_f + (f_f − f_m)/(2^p − 1). None when the differences do not keep
/// their sign (no asymptotic range) or vanish.
fn richardson(coarse: f64, medium: f64, fine: f64) -> Option<(f64, f64)> {
    let ratio = (coarse - medium) / (medium - fine);
    if !(ratio.is_finite() && ratio > 0.0) || ratio == 1.0 {
        return None;
    }
    let p = ratio.log2();
    Some((p, fine + (fine - medium) / (2f64.powf(p) - 1.0)))
}

/// The hemisphere (0/90, μ = 0.1, the shipped point springs) on meshes
/// refined by 2, the mass-scaling step ∝ the cell size (see
/// [`hemisphere_mesh`]).
fn mesh_convergence() -> Vec<Check> {
    // DRAPE_CONVERGENCE_MAX_CELLS caps the finest mesh of full mode: the
    // 160×160 run alone is about 2·10⁵ steps of 25 600 quads, over 20 min
    // of CPU, which a shared machine may not afford.
    let cap = std::env::var("DRAPE_CONVERGENCE_MAX_CELLS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(usize::MAX);
    let all: &[usize] = if quick_mode() {
        &[10, 20]
    } else {
        &[10, 20, 40, 80, 160]
    };
    let meshes: Vec<usize> = all.iter().copied().filter(|&n| n <= cap).collect();
    let o = Orientation::ZeroNinety;
    let runs: Vec<Run> = meshes
        .iter()
        .map(|&n| {
            Run::of(
                o.scene("hemisphere"),
                o,
                format!("{n}×{n}"),
                &hemisphere_mesh(n),
            )
        })
        .collect();
    let outcomes = execute_all(&runs);
    let mut checks: Vec<Check> = outcomes.iter().flat_map(hemisphere_checks).collect();
    let mut text = String::from(
        "Mesh convergence of the hemisphere (0/90, μ = 0.1, 8 point springs of 1 N/mm), the \
         mass-scaling step ∝ the cell size (2e-5 s at 40×40). Order and extrapolation by \
         Richardson from the three finest meshes (refinement ratio 2).\n\n| measure |",
    );
    for o in &outcomes {
        let _ = write!(text, " {} |", o.run.label);
    }
    text.push_str(" observed order | extrapolated |\n|---|");
    for _ in 0..outcomes.len() + 2 {
        text.push_str("--:|");
    }
    text.push('\n');
    for m in &MEASURES {
        let values: Vec<f64> = outcomes.iter().map(m.of).collect();
        let _ = write!(text, "| {} |", m.name);
        for v in &values {
            let _ = write!(text, " {v:.3} |");
        }
        let fit = match values[..] {
            [.., c, md, f] if values.len() >= 3 => richardson(c, md, f),
            _ => None,
        };
        match fit {
            Some((p, x)) => {
                let _ = writeln!(text, " {p:.2} | {x:.3} |");
            }
            None => text.push_str(" — | — |\n"),
        }
        // What the shipped mesh is worth: its draw-ins within 1 mm (the
        // resolution of the paper's measured draw-ins, Table 4) of the
        // finest mesh's. Asked of the draw-ins only (smooth, global
        // measures); the maxima are reported, not asked: with point springs
        // the largest shear sits beside a point load, whose neighbourhood
        // does not converge. A ratio of successive changes is not asked
        // either: the draw-in changes by hundredths of a millimetre from
        // 20×20 on, where the state of the still-swinging skirt at the end
        // (E_kin/E_int ≈ 1e-3), not the mesh, decides the ratio.
        let shipped = meshes.iter().position(|&n| n == HEMISPHERE_CELLS);
        if let (Some(k), true) = (shipped, m.name.starts_with('D')) {
            let finest = values.len() - 1;
            if finest > k {
                checks.push(Check::abs(
                    format!(
                        "{}: {}×{} (shipped) vs {} (finest)",
                        m.name, HEMISPHERE_CELLS, HEMISPHERE_CELLS, outcomes[finest].run.label
                    ),
                    values[finest],
                    values[k],
                    1.0,
                ));
            }
        }
    }
    text.push('\n');
    text.push_str(&run_table(&outcomes));
    note(text);
    checks
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn richardson_recovers_a_known_order_and_limit() {
        // f(h) = 3 + 2·h² at h = 4, 2, 1.
        let (p, x) = richardson(35.0, 11.0, 5.0).unwrap();
        assert!((p - 2.0).abs() < 1e-12, "{p}");
        assert!((x - 3.0).abs() < 1e-12, "{x}");
        // Oscillating differences have no order.
        assert!(richardson(1.0, 2.0, 1.5).is_none());
        assert!(richardson(1.0, 1.0, 1.0).is_none());
    }

    #[test]
    fn the_hemisphere_constants_are_the_shipped_scenes() {
        for orientation in [Orientation::ZeroNinety, Orientation::PlusMinus45] {
            let path = orientation.scene("hemisphere");
            let spec = drape_io::scene::Scene::from_file(&path, &[]).unwrap().spec;
            assert_eq!(
                spec.fabric.blank.cells,
                Some([HEMISPHERE_CELLS; 2]),
                "{}",
                path.display()
            );
            assert_eq!(
                spec.simulation.mass_scaling_dt,
                Some(HEMISPHERE_MASS_SCALING_DT),
                "{}",
                path.display()
            );
        }
    }

    #[test]
    fn the_paper_error_bands_are_the_largest_paper_errors() {
        assert!((paper_error_band(&TABLE_2[0].2, TABLE_2[0].1) - 5.753).abs() < 1e-12);
        assert!((paper_error_band(&TABLE_2[1].2, TABLE_2[1].1) - 4.499).abs() < 1e-12);
    }
}
