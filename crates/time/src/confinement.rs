//! Yarns confined between two tools (explicit driver): after each step's
//! contact pass, every truss of a batch whose law confines
//! (`FibreLaw::confines` in drape-constitutive) gets the free space its
//! nodes have between two facing tools
//! ([`ExplicitContact::clearance_into`]), which the next force pass's
//! yarns may bow out into (`FibreLaw::confined_stress_and_tangent`).
//!
//! Not here: the law, the gaps' geometry. The implicit driver does not
//! confine (its Newton tangent would have to carry the clearance's
//! dependence on the contact set).
//!
//! Nor does a follower pressure (a vacuum bag) with one tool, by choice,
//! from what the pressure does to the bow: a segment pressed onto its tool
//! by p, bowing away from it by a half sine a over L against its crimp a₀
//! (Rayleigh–Ritz, per unit width, P_E = π²B/L²), is in equilibrium at
//! P_E·(a − a₀) − P·a + 4pL²/π³ = 0, so a = (a₀ − a_p)/(1 − P/P_E) with
//! a_p = 4pL⁴/(π⁵B). For the glass preset under a full vacuum (0.1 MPa,
//! L = 4.55 mm, B = 0.465 N·mm) a_p = 1.2 mm, past a₀ = 0.317 mm: the bag
//! holds the segment flat on the tool while P < P_E, and past P_E the bow
//! that opens is a blister whose load falls as it grows (the bag yields).
//! There is no wall for the column to climb; the bag at most lifts the
//! load at which a segment bows out to the perfect column's P_E, which the
//! free law tends to anyway.

use drape_contact::{ExplicitContact, Nearest};
use drape_model::Model;
use nalgebra::Vector3;

/// The clearance a checkpoint stores for "no wall": JSON has no infinity.
const NO_WALL_STORED: f64 = f64::MAX;

/// The driver's scratch for the clearances, sized once.
#[derive(Debug, Clone, Default)]
pub(crate) struct Confinement {
    nearest: Vec<Nearest>,
    node: Vec<f64>,
}

impl Confinement {
    /// Whether a run of `model` confines any yarn: a batch whose law
    /// confines, and two tools to confine it between.
    pub fn applies(model: &Model) -> bool {
        model.tools.len() >= 2 && model.trusses.iter().any(|b| b.law.confines())
    }

    /// The largest clearance any confined yarn of `model` can meet (mm;
    /// 0 where none is confined): the contact projects every node within
    /// it of a tool at every step, and no farther tool is a wall
    /// ([`drape_contact::ContactSettings::clearance_reach`]).
    pub fn reach(model: &Model) -> f64 {
        if !Self::applies(model) {
            return 0.0;
        }
        model
            .trusses
            .iter()
            .map(|b| b.law.confinement_reach())
            .fold(0.0, f64::max)
    }

    /// Per truss batch, every truss free (infinite clearance) for the
    /// batches whose law confines, none for the others: the force pass's
    /// `truss_clearance` before the first contact pass.
    pub fn free(model: &Model) -> Vec<Vec<f64>> {
        model
            .trusses
            .iter()
            .map(|b| {
                if b.law.confines() {
                    vec![f64::INFINITY; b.len()]
                } else {
                    Vec::new()
                }
            })
            .collect()
    }

    /// Each confining batch's trusses' clearances into `truss`, from the
    /// contact pass's last gaps: a truss has the larger room of its two
    /// nodes (the less confined end: a segment bows where it has room).
    ///
    /// Returns the energy the tools put into the yarns at positions `x` by
    /// moving their walls (mJ, [`crate::Energies::confinement_work`]): a
    /// yarn's stored energy depends on its clearance, and the contact's
    /// nodal forces do not carry the walls' push on its bow, so without it
    /// that energy would show as negative dissipation.
    pub fn update(
        &mut self,
        model: &Model,
        contact: &ExplicitContact,
        x: &[Vector3<f64>],
        truss: &mut [Vec<f64>],
    ) -> f64 {
        self.node.resize(model.node_count(), f64::INFINITY);
        contact.clearance_into(&mut self.nearest, &mut self.node);
        let mut work = 0.0;
        for (b, out) in model.trusses.iter().zip(truss) {
            for (e, (c, &[i, j])) in out.iter_mut().zip(&b.nodes).enumerate() {
                let new = self.node[i as usize].max(self.node[j as usize]);
                // A truss that cannot be measured fails the next force
                // pass, which says so; it has no energy to book here.
                work += b.element_confinement_work(e, x, *c, new).unwrap_or(0.0);
                *c = new;
            }
        }
        work
    }

    /// The clearances as a checkpoint stores them (no infinity in JSON).
    pub fn stored(truss: &[Vec<f64>]) -> Vec<Vec<f64>> {
        truss
            .iter()
            .map(|b| b.iter().map(|&c| c.min(NO_WALL_STORED)).collect())
            .collect()
    }

    /// The clearances back from a checkpoint into `truss` (same shape, or
    /// left free: a checkpoint written before clearances were carried).
    pub fn restore(stored: &[Vec<f64>], truss: &mut [Vec<f64>]) {
        if stored.len() != truss.len()
            || stored.iter().zip(&*truss).any(|(s, t)| s.len() != t.len())
        {
            return;
        }
        for (s, t) in stored.iter().zip(truss) {
            for (s, t) in s.iter().zip(t) {
                *t = if *s >= NO_WALL_STORED {
                    f64::INFINITY
                } else {
                    *s
                };
            }
        }
    }
}
