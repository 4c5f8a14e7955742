//! The implicit driver's round-off floor: the residual and correction
//! below which Newton cannot go in f64, so that the convergence test does
//! not ask for less (it would fail on any increment small enough).
//!
//! Why there is a floor. The residual r = f_ext − f_int(x) − M·ā(x) − …
//! is evaluated at positions known to one ulp, eps·|x|. One ulp of x moves
//! r by K̂·eps·|x|, with K̂ = M·(1 − α_m)/(β·h²) + K (the Newton matrix):
//! the inertia term grows as 1/h², so a small enough increment (many
//! frames, a small `max_increment`, the cutbacks themselves) puts the
//! floor above `force_tolerance` times the force scale, every correction
//! below an ulp, and the increment failed whatever its size below that
//! (measured: "residual 2.4e-2 N (force scale 2.4e-2 N), last correction
//! 3e-16 mm" at the last cutback). On top of that, each component is a
//! sum of rounded terms, each off by half an ulp of the largest force.
//!
//! The factor. A component of r sums the inertia's four terms (x, xₙ,
//! h·vₙ, h²·aₙ cancel in ā), the external, slip and constraint forces and
//! up to eight element contributions (four quads, four trusses at an
//! interior node; springs and bending add a few): about sixteen rounded
//! terms, and the iterate itself is off by up to an ulp from the last
//! correction's rounding. [`ROUND_OFF`] = 16 bounds that sum of
//! half-ulps with a margin of two; it is far below any tolerance a user
//! sets (16·eps = 3.6e-15).
//!
//! The criterion accepts only both together: the residual within the
//! floor and the last correction within [`ROUND_OFF`] ulps of the
//! coordinates (Newton has stopped moving anything that f64 can hold). A
//! stalled Newton with a residual above the floor is not accepted, nor a
//! residual at the floor while the iterate still moves.
//!
//! Not here: the convergence test itself (`implicit.rs`), which also asks
//! for the contact and friction conditions whichever way the forces pass.

/// Ulps (of the coordinates and of the forces) a converged residual may
/// be off by in f64; see the module's derivation.
pub const ROUND_OFF: f64 = 16.0;

/// The smallest residual and correction Newton can reach at an iterate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoundOffFloor {
    /// Largest residual component round-off can leave (N).
    pub force: f64,
    /// Largest correction component that is round-off (mm).
    pub displacement: f64,
}

impl RoundOffFloor {
    /// The floor for a Newton matrix whose largest diagonal entry is
    /// `stiffness` (N/mm, inertia term included), coordinates up to
    /// `coordinate` in magnitude (mm), and forces up to `forces` (N).
    pub fn new(stiffness: f64, coordinate: f64, forces: f64) -> Self {
        let ulp = ROUND_OFF * f64::EPSILON;
        Self {
            force: ulp * (stiffness * coordinate + forces),
            displacement: ulp * coordinate,
        }
    }

    /// Whether a residual (N) and the correction that led to it (mm) are
    /// both at the floor.
    pub fn reached(&self, residual: f64, correction: f64) -> bool {
        residual <= self.force && correction <= self.displacement
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A node of 1e-6 t in an increment of 1e-6 s (inertia term
    /// m/(β·h²) = 4e6 N/mm with β = ¼), at 100 mm from the origin, forces
    /// of 1e-2 N: one ulp of x is 1.4e-14 mm, worth 5.7e-8 N, above a
    /// force tolerance of 1e-6 × 1e-2 N.
    fn floor() -> RoundOffFloor {
        let stiffness = 1e-6 / (0.25 * 1e-12);
        RoundOffFloor::new(stiffness, 100.0, 1e-2)
    }

    #[test]
    fn a_residual_of_a_few_ulps_of_the_position_is_at_the_floor() {
        let f = floor();
        let ulp_x = 100.0 * f64::EPSILON;
        let one_ulp = 4e6 * ulp_x;
        // The floor sits above what the 1e-6 tolerance asks for here.
        assert!(one_ulp > 1e-6 * 1e-2, "{one_ulp:e}");
        assert!(f.reached(4.0 * one_ulp, ulp_x));
        assert!(f.reached(0.0, 0.0));
    }

    /// A stalled Newton (no correction) with a residual a thousand times
    /// the floor, or a residual at the floor while the iterate still moves
    /// by more than round-off, is not converged.
    #[test]
    fn an_unconverged_state_is_not_at_the_floor() {
        let f = floor();
        assert!(!f.reached(1e3 * f.force, 0.0));
        assert!(!f.reached(1.01 * f.force, 0.0));
        assert!(!f.reached(0.0, 1e3 * f.displacement));
        // Relative to the forces: 1e-10 of 1e-2 N is well above the floor
        // of a stiff-free, far-from-tiny increment.
        let loose = RoundOffFloor::new(1.0, 100.0, 1e-2);
        assert!(!loose.reached(1e-12, 0.0), "{loose:?}");
    }
}
