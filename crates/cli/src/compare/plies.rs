//! `drape compare RUN_A RUN_B` of two laminates: ply by ply.
//!
//! A laminate's plies lie a fraction of a millimetre apart on one flat
//! blank, so a comparison of the whole would carry B's shear onto A's
//! elements from whichever ply happens to be nearest, and would draw the
//! plies over one another. Here each ply of A is compared with the ply of
//! B of the same name only (element by element when the two plies have
//! the same reference cells, else by closest point on B's ply), and each
//! gets its own picture and profile differences. Two plies are matched by
//! name, never by position: the same names on both sides or an error
//! naming the ply that is missing. What it is not: the one-ply
//! comparison, which [`super::compare_runs`] does as before.

use std::path::Path;

use drape_io::results::Summary;
use drape_io::results::read::VtuFrame;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::{CompareError, ProfileDifference};

/// The cell array of a laminate's frame naming each cell's ply.
const PLY_ARRAY: &str = "ply";

/// One run's plies: their names (bottom to top) and each one's cells.
#[derive(Debug, Clone)]
pub(super) struct RunPlies {
    /// Names, bottom to top.
    pub names: Vec<String>,
    /// Each ply's cells (indices into the frame's cells), in cell order.
    pub cells: Vec<Vec<usize>>,
}

/// The plies of the folder `dir` (its `summary` and last `frame`); None
/// for a run of one ply (no `ply` cell array).
pub(super) fn run_plies(
    dir: &Path,
    summary: &Summary,
    frame: &VtuFrame,
) -> Result<Option<RunPlies>, CompareError> {
    let Some(ply) = frame.cell_scalars(PLY_ARRAY) else {
        return Ok(None);
    };
    let names: Vec<String> = summary.plies.iter().map(|p| p.name.clone()).collect();
    let mut cells = vec![Vec::new(); names.len()];
    for (c, &p) in ply.iter().enumerate() {
        let slot = (p >= 0.0 && p.fract() == 0.0)
            .then_some(p as usize)
            .and_then(|p| cells.get_mut(p));
        match slot {
            Some(s) => s.push(c),
            None => {
                return Err(CompareError::Input(format!(
                    "{}: cell {c} of its last frame is of ply {p}, but summary.json names {} \
                     plies",
                    dir.display(),
                    names.len()
                )));
            }
        }
    }
    Ok(Some(RunPlies { names, cells }))
}

/// For each ply of A, in A's order, the index of B's ply of the same
/// name: both laminates with the same plies, or an error naming the
/// missing ply (or the run that is a single ply).
pub(super) fn match_plies(
    a: (&Path, Option<&RunPlies>),
    b: (&Path, Option<&RunPlies>),
) -> Result<Option<Vec<usize>>, CompareError> {
    let list = |p: &RunPlies| p.names.join(", ");
    let one = |dir: &Path, other: &Path, p: &RunPlies| {
        CompareError::Input(format!(
            "{} is a single ply but {} a laminate of plies {}: a laminate is compared ply by \
             ply, with a laminate of the same plies",
            dir.display(),
            other.display(),
            list(p)
        ))
    };
    match (a.1, b.1) {
        (None, None) => Ok(None),
        (Some(pa), None) => Err(one(b.0, a.0, pa)),
        (None, Some(pb)) => Err(one(a.0, b.0, pb)),
        (Some(pa), Some(pb)) => {
            let missing = |from: (&Path, &RunPlies), to: (&Path, &RunPlies)| {
                from.1
                    .names
                    .iter()
                    .find(|n| !to.1.names.contains(n))
                    .map(|n| {
                        CompareError::Input(format!(
                            "{}: no ply `{n}` (its plies: {}), which {} has: a laminate is \
                         compared ply by ply, by name",
                            to.0.display(),
                            list(to.1),
                            from.0.display()
                        ))
                    })
            };
            if let Some(e) = missing((a.0, pa), (b.0, pb)).or_else(|| missing((b.0, pb), (a.0, pa)))
            {
                return Err(e);
            }
            Ok(Some(
                pa.names
                    .iter()
                    .map(|n| pb.names.iter().position(|m| m == n).unwrap_or(0))
                    .collect(),
            ))
        }
    }
}

/// Whether A's cells `ca` and B's cells `cb` are the same reference
/// cells, one for one (points to 1e-9 of the blank's size).
pub(super) fn same_cells(
    a: (&VtuFrame, &[Vector3<f64>], &[usize]),
    b: (&VtuFrame, &[Vector3<f64>], &[usize]),
) -> bool {
    let (fa, a0, ca) = a;
    let (fb, b0, cb) = b;
    let size = a0.iter().map(|p| p.norm()).fold(1.0f64, f64::max);
    ca.len() == cb.len()
        && ca.iter().zip(cb).all(|(&i, &j)| {
            let (p, q) = (&fa.cells[i], &fb.cells[j]);
            p.len() == q.len()
                && p.iter()
                    .zip(q)
                    .all(|(&m, &n)| (a0[m as usize] - b0[n as usize]).norm() <= 1e-9 * size)
        })
}

/// One ply of both laminates in `comparison.json`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PlyDifference {
    /// Its name.
    pub name: String,
    /// Whether its cells are the same in both runs (compared element by
    /// element) or B's ply was carried onto A's by closest point.
    pub same_mesh: bool,
    /// Its elements in run A.
    pub elements: usize,
    /// Of those, elements with a value from both runs.
    pub compared: usize,
    /// Largest |γ_B − γ_A| on it (degrees).
    pub max_abs_difference_deg: f64,
    /// Where: run A's reference centroid of that element (mm).
    pub max_difference_at: [f64; 3],
    /// Root mean square of γ_B − γ_A on it (degrees).
    pub rms_difference_deg: f64,
    /// Mean of γ_B − γ_A on it (degrees).
    pub mean_difference_deg: f64,
    /// Its shear profiles (`profiles.csv`'s rows of the ply) compared
    /// point by point, as the one-ply `profiles`.
    #[serde(default)]
    pub profiles: Vec<ProfileDifference>,
}

impl PlyDifference {
    /// The differences of B's values `b_deg` from A's `ga` on A's
    /// elements `cells` (reference centroids `centroid0`).
    pub(super) fn of(
        name: &str,
        same_mesh: bool,
        cells: &[usize],
        ga: &[f64],
        b_deg: &[f64],
        centroid0: &[Vector3<f64>],
    ) -> Self {
        let mut d = PlyDifference {
            name: name.to_owned(),
            same_mesh,
            elements: cells.len(),
            ..PlyDifference::default()
        };
        let stats = super::Differences::of(cells.iter().map(|&e| (e, b_deg[e] - ga[e])));
        d.compared = stats.compared;
        d.max_abs_difference_deg = stats.max_abs;
        if let Some(e) = stats.max_at {
            d.max_difference_at = centroid0[e].into();
        }
        d.mean_difference_deg = stats.mean;
        d.rms_difference_deg = stats.rms;
        d
    }
}
