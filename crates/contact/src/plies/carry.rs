//! What the ply pass carries from one step to the next, for a checkpoint:
//! a run resumed from it ends bit for bit where the uninterrupted run
//! does. The solves start from the last step's forces (warm starts), the
//! broad phase's candidate lists are those of the positions it was last
//! built at (their order breaks the narrow phase's ties), and the slip,
//! the friction's work, the overlap's peaks and the solves' totals are
//! sums over the run.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::{PlyContact, PlyOverlap, PlyTotals, Warm};

/// The ply pass's state between steps ([`PlyContact::carry`],
/// [`PlyContact::restore`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlyCarry {
    /// Passes so far.
    pub pass: u64,
    /// The positions the broad phase was last built at (mm).
    pub reference_x: Vec<Vector3<f64>>,
    /// Per search (two per interface), each slave node's last normal force
    /// (N), tangential force (N) and the pass they are of.
    pub warm: Vec<Vec<(f64, Vector3<f64>, u64)>>,
    /// Each node's accumulated slip on the ply below (mm).
    pub slip: Vec<f64>,
    /// Friction dissipated between plies so far (mJ).
    pub friction_dissipation: f64,
    /// Each interface's largest overlap at the checks so far (mm).
    pub overlap_peak: Vec<f64>,
    /// The solves' sums so far.
    pub totals: PlyTotals,
    /// The step the rows' give is set at (Δt·τ, s²); 0 in a checkpoint
    /// written before the rows gave.
    #[serde(default)]
    pub spring_step: f64,
    /// The deepest overlap at the checks so far; none in a checkpoint
    /// written before it was kept.
    #[serde(default)]
    pub worst_overlap: Option<PlyOverlap>,
}

impl PlyContact {
    /// What the pass carries to its next step.
    pub fn carry(&self) -> PlyCarry {
        PlyCarry {
            pass: self.pass,
            reference_x: self.reference_x.clone(),
            warm: self
                .searches
                .iter()
                .map(|s| {
                    s.warm
                        .iter()
                        .map(|w| (w.normal, w.tangential, w.pass))
                        .collect()
                })
                .collect(),
            slip: self.slip.clone(),
            friction_dissipation: self.friction_dissipation,
            overlap_peak: self.overlap_peak.clone(),
            totals: self.totals,
            spring_step: self.spring_step,
            worst_overlap: self.worst_overlap,
        }
    }

    /// Takes up `carry` (of a pass over the same plies): the next step is
    /// the one the carrying pass would have taken. A carry of other plies
    /// (another node count or stack) is refused with what differs.
    pub fn restore(&mut self, carry: &PlyCarry) -> Result<(), String> {
        let n = self.slip.len();
        let counts: Vec<usize> = self.searches.iter().map(|s| s.warm.len()).collect();
        let carried: Vec<usize> = carry.warm.iter().map(Vec::len).collect();
        if carry.slip.len() != n
            || !(carry.reference_x.is_empty() || carry.reference_x.len() == n)
            || counts != carried
            || carry.overlap_peak.len() != self.overlap_peak.len()
        {
            return Err(format!(
                "the ply contact's carried state is of another stack ({} nodes, searches of {carried:?} nodes; this one: {n} nodes, {counts:?})",
                carry.slip.len()
            ));
        }
        self.pass = carry.pass;
        self.spring_step = carry.spring_step;
        // The candidate lists of those positions, in their order: rebuilt
        // at the next step's positions they could list a node's faces in
        // another order and a tie go the other way.
        self.reference_x.clear();
        if !carry.reference_x.is_empty() {
            self.refresh(&carry.reference_x);
        }
        for (s, w) in self.searches.iter_mut().zip(&carry.warm) {
            for (to, &(normal, tangential, pass)) in s.warm.iter_mut().zip(w) {
                *to = Warm {
                    normal,
                    tangential,
                    pass,
                };
            }
        }
        self.slip.clone_from(&carry.slip);
        self.friction_dissipation = carry.friction_dissipation;
        self.overlap_peak.clone_from(&carry.overlap_peak);
        self.worst_overlap = carry.worst_overlap;
        self.totals = carry.totals;
        Ok(())
    }
}
