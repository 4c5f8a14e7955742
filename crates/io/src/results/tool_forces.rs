//! `tool_forces.csv`: where each tool is and what force it puts on the
//! fabric at each output frame, the punch force–stroke curve of a deep
//! drawing and the holder force a blank carries. Not a contact-pressure
//! field: that is the VTU's `contact_force` per node.

use std::fmt::Write as _;

use drape_contact::ToolState;
use serde::{Deserialize, Serialize};

use super::{ResultsDir, ResultsError, fmt_f64};
use crate::finite::or_empty;

/// The tools at one output frame (the rows of `tool_forces.csv` of that
/// frame, one per tool).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ToolForceRow {
    /// Time (s).
    pub time: f64,
    /// Completed steps.
    pub step: u64,
    /// Each tool's state (displacement, velocity, impulse), in the scene's
    /// order.
    pub state: Vec<ToolState>,
    /// Each tool's contact force on the fabric at the frame (N): along the
    /// tool's axis for a moving tool, positive when it pushes the fabric
    /// the way it moves; the sum of the normal forces for a fixed one.
    pub force: Vec<f64>,
}

/// The header of `tool_forces.csv`.
pub const TOOL_FORCES_HEADER: &str =
    "time,step,tool,displacement_mm,velocity_mm_per_s,force_n,mean_force_n";

/// The CSV text of `rows` for the tools `names`: one line per frame and
/// tool; `mean_force_n` is the impulse since the frame before over the time
/// between them (empty at the first frame).
pub fn tool_forces_csv(names: &[&str], rows: &[ToolForceRow]) -> String {
    let mut csv = String::with_capacity(64 + rows.len() * names.len() * 80);
    csv.push_str(TOOL_FORCES_HEADER);
    csv.push('\n');
    let mut before: Option<&ToolForceRow> = None;
    for row in rows {
        for (t, name) in names.iter().enumerate() {
            let (Some(s), Some(f)) = (row.state.get(t), row.force.get(t)) else {
                continue;
            };
            // Like energy.csv, a value that is not a number leaves its
            // cell empty.
            let cell = |v: f64| or_empty(v, fmt_f64);
            let mean = before
                .and_then(|b| mean_force(b, row, t))
                .map_or_else(String::new, cell);
            let _ = writeln!(
                csv,
                "{},{},\"{}\",{},{},{},{mean}",
                fmt_f64(row.time),
                row.step,
                name.replace('"', "\"\""),
                cell(s.displacement),
                cell(s.velocity),
                cell(*f),
            );
        }
        before = Some(row);
    }
    csv
}

/// Tool `t`'s mean force between the frames `before` and `row`: its
/// impulse over their time apart (None for frames at one time).
fn mean_force(before: &ToolForceRow, row: &ToolForceRow, t: usize) -> Option<f64> {
    let dt = row.time - before.time;
    let di = row.state.get(t)?.impulse - before.state.get(t)?.impulse;
    (dt > 0.0).then(|| di / dt)
}

/// One tool over a run, for `summary.json`: its travel and the force it
/// put on the fabric, as means over the frame intervals.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ToolSummary {
    /// The tool's name.
    pub name: String,
    /// Its displacement along its axis at the last frame (mm).
    pub displacement_mm: f64,
    /// Its mean force over the last frame interval (N; the sampled force
    /// where there is one frame only).
    pub force_n: f64,
    /// The largest mean force over a frame interval (N) and the time at
    /// that interval's end (s).
    pub max_force_n: f64,
    /// See `max_force_n`.
    pub max_force_time_s: f64,
}

impl ToolSummary {
    /// Each tool of `names` over the frames `rows` (none without rows).
    pub fn of(names: &[&str], rows: &[ToolForceRow]) -> Vec<Self> {
        let Some(last) = rows.last() else {
            return Vec::new();
        };
        names
            .iter()
            .enumerate()
            .filter_map(|(t, name)| {
                let state = last.state.get(t)?;
                let mut summary = Self {
                    name: (*name).to_owned(),
                    displacement_mm: state.displacement,
                    force_n: *last.force.get(t)?,
                    max_force_n: 0.0,
                    max_force_time_s: last.time,
                };
                let means = rows
                    .windows(2)
                    .filter_map(|w| Some((w[1].time, mean_force(&w[0], &w[1], t)?)));
                let mut any = false;
                for (time, mean) in means {
                    if !any || mean.abs() > summary.max_force_n.abs() {
                        summary.max_force_n = mean;
                        summary.max_force_time_s = time;
                    }
                    summary.force_n = mean;
                    any = true;
                }
                if !any {
                    summary.max_force_n = summary.force_n;
                }
                Some(summary)
            })
            .collect()
    }
}

impl ResultsDir {
    /// Writes `tool_forces.csv` ([`tool_forces_csv`]); nothing without
    /// tools.
    pub fn write_tool_forces(
        &self,
        names: &[&str],
        rows: &[ToolForceRow],
    ) -> Result<(), ResultsError> {
        if names.is_empty() {
            return Ok(());
        }
        self.write_file("tool_forces.csv", tool_forces_csv(names, rows).as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mean_force_is_the_impulse_between_frames_over_their_time() {
        let state = |u: f64, impulse: f64| ToolState {
            displacement: u,
            velocity: 2.0,
            impulse,
        };
        let rows = [
            ToolForceRow {
                time: 0.0,
                step: 0,
                state: vec![state(0.0, 0.0), state(0.0, 0.0)],
                force: vec![0.0, 0.0],
            },
            ToolForceRow {
                time: 0.5,
                step: 10,
                state: vec![state(1.0, 3.0), state(0.0, 0.25)],
                force: vec![7.0, 0.4],
            },
        ];
        let csv = tool_forces_csv(&["punch", "a \"die\""], &rows);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], TOOL_FORCES_HEADER);
        assert_eq!(lines[1], "0,0,\"punch\",0,2,0,");
        assert_eq!(lines[3], "0.5,10,\"punch\",1,2,7,6");
        assert_eq!(lines[4], "0.5,10,\"a \"\"die\"\"\",0,2,0.4,0.5");
        assert_eq!(lines.len(), 5);
        let summary = ToolSummary::of(&["punch", "die"], &rows);
        assert_eq!(summary[0].force_n, 6.0);
        assert_eq!(
            (summary[0].max_force_n, summary[0].max_force_time_s),
            (6.0, 0.5)
        );
        assert_eq!(summary[0].displacement_mm, 1.0);
        assert_eq!(summary[1].force_n, 0.5);
    }

    #[test]
    fn a_tool_s_largest_force_is_its_largest_mean_between_frames() {
        let row = |time: f64, impulse: f64, force: f64| ToolForceRow {
            time,
            step: 0,
            state: vec![ToolState {
                displacement: time,
                velocity: 0.0,
                impulse,
            }],
            force: vec![force],
        };
        // Means 4, 10 (largest, though sampled at 1) and 2 N.
        let rows = [
            row(0.0, 0.0, 0.0),
            row(1.0, 4.0, 4.0),
            row(1.5, 9.0, 1.0),
            row(2.5, 11.0, 2.0),
        ];
        // A force that is not a number leaves its cells empty.
        let mut broken = rows.clone();
        broken[3].force[0] = f64::NAN;
        broken[3].state[0].impulse = f64::INFINITY;
        let csv = tool_forces_csv(&["punch"], &broken);
        assert_eq!(csv.lines().last(), Some("2.5,0,\"punch\",2.5,0,,"), "{csv}");
        let s = &ToolSummary::of(&["punch"], &rows)[0];
        assert_eq!((s.max_force_n, s.max_force_time_s), (10.0, 1.5));
        assert_eq!((s.force_n, s.displacement_mm), (2.0, 2.5));
        // One frame: its sampled force.
        let s = &ToolSummary::of(&["punch"], &rows[1..2])[0];
        assert_eq!((s.force_n, s.max_force_n), (4.0, 4.0));
        assert!(ToolSummary::of(&["punch"], &[]).is_empty());
    }
}
