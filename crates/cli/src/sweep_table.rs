//! A sweep's points and its results table and picture, shared by the
//! local sweep and the collection of a Slurm sweep (`slurm.rs`), so that
//! both write `sweep.csv` and `sweep.png` by the same code from the same
//! summaries. Not for running anything.

use std::path::Path;

use anyhow::{Context, Result};
use drape_io::finite::or_empty;
use drape_io::results::{PlySummary, Summary, SweepAxis, SweepRun, write_sweep_picture};

use crate::parse_sets;

/// The columns of each ply of a laminate, after the tools' forces, each
/// named `<ply>_<column>`.
const PLY_COLUMNS: [&str; 3] = ["max_shear_deg", "max_waviness_deg", "max_slip_mm"];

/// A swept key and its values, in the order given.
pub type Axis = (String, Vec<String>);

/// One point of a sweep: a value for each key.
pub type Point = Vec<(String, String)>;

/// The axes of `--set KEY=V1,V2,…` and every combination of their values,
/// the last key varying fastest (run_000, run_001, … in this order).
pub fn points(set: &[String]) -> Result<(Vec<Axis>, Vec<Point>)> {
    let axes: Vec<Axis> = parse_sets(set)?
        .into_iter()
        .map(|(k, v)| (k, values(&v)))
        .collect();
    let mut combos: Vec<Point> = vec![Vec::new()];
    for (key, values) in &axes {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                values.iter().map(move |v| {
                    let mut c = c.clone();
                    c.push((key.clone(), v.clone()));
                    c
                })
            })
            .collect();
    }
    Ok((axes, combos))
}

/// The values of one `--set` list: split at the commas outside brackets
/// and quotes, so that a vector key takes vectors
/// (`fabric.blank.cells=[10,10],[20,20]` is two values).
fn values(list: &str) -> Vec<String> {
    let mut out = Vec::new();
    let (mut depth, mut quoted, mut start) = (0_i32, false, 0);
    for (i, c) in list.char_indices() {
        match c {
            '"' => quoted = !quoted,
            '[' if !quoted => depth += 1,
            ']' if !quoted => depth -= 1,
            ',' if !quoted && depth == 0 => {
                out.push(list[start..i].trim().to_owned());
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push(list[start..].trim().to_owned());
    out
}

/// The name of point `i`'s run folder.
pub fn run_name(i: usize) -> String {
    format!("run_{i:03}")
}

/// Writes `sweep.csv` and `sweep.png` into `out`: a row per point, its
/// summary's measures or, where it has none, the error in words. Returns
/// the table and whether a point failed (or has no summary).
pub fn write(
    out: &Path,
    axes: &[Axis],
    combos: &[Point],
    reports: &[Result<Summary, String>],
) -> Result<(String, bool)> {
    let mut table = String::from("run");
    for (key, _) in axes {
        table.push(',');
        table.push_str(key);
    }
    // Each tool's largest mean force (a deep drawing's punch force), by
    // the tools of the first run that has a summary (every point is the
    // same scene), before the last column, which the table's reader
    // checks to tell a whole header from a cut one.
    let first = reports.iter().find_map(|r| r.as_ref().ok());
    let tools: Vec<String> = first
        .map(|s| s.tools.iter().map(|t| t.name.replace(',', ";")).collect())
        .unwrap_or_default();
    // A laminate's plies (from two on), by the same first summary: what
    // a sweep of the ply–ply friction is for, each ply's shear, wrinkle
    // indicator and slip on the ply below.
    let plies: Vec<String> = first
        .filter(|s| s.plies.len() > 1)
        .map(|s| s.plies.iter().map(|p| p.name.replace(',', ";")).collect())
        .unwrap_or_default();
    let (last, measures) = drape::sweep_check::MEASURE_COLUMNS
        .split_last()
        .expect("columns");
    for column in measures {
        table.push(',');
        table.push_str(column);
    }
    for tool in &tools {
        table.push_str(&format!(",{tool}_max_force_n"));
    }
    for ply in &plies {
        for column in PLY_COLUMNS {
            table.push_str(&format!(",{ply}_{column}"));
        }
    }
    table.push(',');
    table.push_str(last);
    table.push('\n');
    let mut failed = false;
    for (i, (combo, report)) in combos.iter().zip(reports).enumerate() {
        table.push_str(&run_name(i));
        for (_, v) in combo {
            // A vector value's commas would shift the columns: `;` in
            // the table ([10;10]), the value itself in the point's scene.
            table.push(',');
            table.push_str(&v.replace(',', ";"));
        }
        match report {
            Ok(s) => {
                failed |= s.status == "failed";
                // A value a run has not (an imported blank's draw-in,
                // embedded fibres' truss force) is left empty, not NaN.
                let cell = |v: f64, digits: usize| or_empty(v, |v| format!("{v:.digits$}"));
                let balance = or_empty(s.energy.balance_error, |v| format!("{v:.3e}"));
                let forces: String = tools
                    .iter()
                    .map(|name| {
                        let force = s
                            .tools
                            .iter()
                            .find(|t| t.name.replace(',', ";") == *name)
                            .map_or(f64::NAN, |t| t.max_force_n);
                        format!(",{}", cell(force, 1))
                    })
                    .collect();
                let ply_cells: String = plies
                    .iter()
                    .map(|name| {
                        let ply = s.plies.iter().find(|p| p.name.replace(',', ";") == *name);
                        let value = |f: fn(&PlySummary) -> f64| ply.map_or(f64::NAN, f);
                        format!(
                            ",{},{},{}",
                            cell(value(|p| p.max_shear_deg), 4),
                            cell(value(|p| p.max_waviness_deg), 4),
                            cell(value(|p| p.max_slip_mm), 4)
                        )
                    })
                    .collect();
                table.push_str(&format!(
                    ",{},{},{},{},{},{},{balance},{},{},{},{}{forces}{ply_cells},{}\n",
                    s.status,
                    cell(s.max_shear_deg, 4),
                    cell(s.draw_in_mm.dx, 4),
                    cell(s.draw_in_mm.dy, 4),
                    cell(s.draw_in_mm.dd, 4),
                    cell(s.max_fibre_tension_n, 3),
                    s.run.steps,
                    cell(s.run.wall_s, 2),
                    cell(s.peak.max_shear_deg, 4),
                    cell(s.peak.max_shear_time_s, 6),
                    cell(s.max_fibre_tension_n_per_mm, 5)
                ));
            }
            Err(e) => {
                failed = true;
                table.push_str(&format!(
                    ",error: {}{}\n",
                    e.replace([',', '\n'], ";"),
                    ",".repeat(measures.len() + tools.len() + plies.len() * PLY_COLUMNS.len())
                ));
            }
        }
    }
    let path = out.join("sweep.csv");
    drape_io::atomic::write(&path, table.as_bytes())
        .with_context(|| format!("writing {}", path.display()))?;
    // A key given one value is a setting, not a swept parameter: the
    // picture has a column per key with more than one value (the first key
    // when none has).
    let mut drawn: Vec<usize> = (0..axes.len()).filter(|&k| axes[k].1.len() > 1).collect();
    if drawn.is_empty() {
        drawn.push(0);
    }
    let sweep_axes: Vec<SweepAxis> = drawn
        .iter()
        .map(|&k| SweepAxis {
            key: axes[k].0.clone(),
            values: axes[k].1.clone(),
        })
        .collect();
    let runs: Vec<SweepRun> = combos
        .iter()
        .zip(reports)
        .map(|(combo, report)| {
            let s = report.as_ref().ok();
            let value = |f: fn(&Summary) -> f64| s.map_or(f64::NAN, f);
            SweepRun {
                values: drawn.iter().map(|&k| combo[k].1.clone()).collect(),
                max_shear_deg: value(|s| s.max_shear_deg),
                draw_in_dx_mm: value(|s| s.draw_in_mm.dx),
                draw_in_dd_mm: value(|s| s.draw_in_mm.dd),
            }
        })
        .collect();
    let picture = out.join("sweep.png");
    write_sweep_picture(&picture, &sweep_axes, &runs)
        .with_context(|| format!("writing {}", picture.display()))?;
    Ok((table, failed))
}

#[cfg(test)]
mod tests {
    use super::values;

    #[test]
    fn vectors_and_quoted_commas_are_one_value() {
        assert_eq!(values("0, 0.1,0.2"), ["0", "0.1", "0.2"]);
        assert_eq!(values("[10,10],[20, 20]"), ["[10,10]", "[20, 20]"]);
        assert_eq!(values("[[1,2],[3,4]]"), ["[[1,2],[3,4]]"]);
        assert_eq!(values("\"a,b\",c"), ["\"a,b\"", "c"]);
    }
}
