//! The crimped fibre law.

use serde::{Deserialize, Serialize};

use crate::MaterialError;

/// Below this ε/ε_sh the closed forms lose digits to cancellation
/// (ε − ε_sh(1 − e^(−x)) ≈ ε·x/2); a Taylor series is exact to round-off.
const SERIES_BELOW: f64 = 1e-3;
/// The energy's closed form cancels more: its series runs further.
const ENERGY_SERIES_BELOW: f64 = 0.1;
/// The share of E_f below which a jump of the tangent at ε = 0 is not a
/// kink for the explicit driver (see [`FibreLaw::has_kink`]) **\[choice\]**:
/// 0.01. The branch of stiffness J then has a stable limit 1/√(J/E_f) ≥ 10
/// times the step E_f sets, where a bilinear oscillator's lowest resonance
/// band sits at 1/0.2 = 5 times (ARCHITECTURE.md, "Dashpots on kinked
/// yarns"). The presets' buckling yarns jump by 8.7e-4 (glass), 2.6e-3
/// (twintex) and 8.1e-3 (carbon) of E_f.
const KINK_SHARE: f64 = 0.01;

/// The most a yarn's truss is taken to shorten under confinement, as a
/// log strain (0.2, shortened by 18 %): a wall farther than
/// [`FibreLaw::confinement_reach`] is met only by a yarn shortened by
/// more, where a run has long warned that the ply gathers (yarns below
/// 95 % of their length) and its yarns are no longer those of a formed
/// ply. The
/// contact measures the walls within that reach at every step and takes
/// farther tools as no wall; a bound of a half cost the shipped deep
/// drawing 13 % more time for walls no yarn of it met.
pub const CONFINED_SHORTENING: f64 = 0.2;

/// The crimped yarn, hyperelastic in the log strain ε = ln λ (SPEC §4,
/// paper eq. 8–9 integrated in closed form):
///
/// - tension (ε > 0): τ = E_f·(ε − ε_sh·(1 − e^(−ε/ε_sh))), tangent
///   E_t = E_f·(1 − e^(−ε/ε_sh));
/// - compression (ε ≤ 0): τ = c_c·E_f·ε (SPEC §4; c_c = 0, the paper's
///   yarn, buckles at no cost), or, with a buckling stress σ_b > 0, the
///   crimped yarn as an imperfect column (beyond the paper, see
///   [`Self::buckling_stress`]): τ = −σ_b·(1 − 1/√(1 + x)), x = −ε/ε_sh.
///
/// τ is the Kirchhoff stress conjugate to ε per unit reference volume, so a
/// truss of section A₀ carries N = A₀·τ/λ and stores A₀·L₀·w(ε).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FibreLaw {
    /// E_f, the straightened yarn's modulus (MPa).
    pub modulus: f64,
    /// ε_sh, the crimp (undulation) strain over which the yarn straightens.
    /// Zero gives a linear fibre.
    pub crimp_strain: f64,
    /// c_c, the fraction of E_f carried in compression (0: yarns buckle).
    #[serde(default)]
    pub compression_factor: f64,
    /// σ_b (MPa, on the family's fibre section V_f·h/2), the stress a
    /// compressed yarn tends to as it buckles between its interlacings;
    /// 0 (the paper's yarn): it buckles at no cost.
    ///
    /// Why this form: a yarn segment of length L between two interlacings
    /// is a pinned column of bending rigidity EI, already bowed by its
    /// crimp into a half sine of amplitude a₀ whose arc length exceeds its
    /// chord by ε_sh = (π·a₀/2L)², the same crimp strain that the tension
    /// branch straightens. Under an end load P the bow grows to
    /// a = a₀/(1 − P/P_E) (the imperfect column), P_E = π²·EI/L², so the
    /// segment shortens by ε = −ε_sh·((a/a₀)² − 1) (the fibres' own
    /// shortening, P/(E_f·A), is four orders smaller and left out).
    /// Solved for the load: P/P_E = 1 − 1/√(1 + x), x = −ε/ε_sh, which
    /// starts at the tangent σ_b/(2ε_sh) and tends to the Euler stress
    /// σ_b = P_E/A from below (a buckled yarn keeps carrying its Euler
    /// load; it does not shorten for free). Per unit width of a family,
    /// EI = B·pitch and A = pitch·V_f·h/2, so σ_b = π²·B/(L²·V_f·h/2) from
    /// the fabric's bending rigidity B ([`crate::Material::bending_rigidity`]).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub buckling_stress: f64,
    /// L (mm), the yarn's free length between interlacings, the column of
    /// [`Self::buckling_stress`]; 0 (the default): not given, and a yarn
    /// between two tools buckles as a free one (as it does with L but
    /// σ_b = 0: no column to confine). With L > 0 and σ_b > 0
    /// the explicit driver confines the column by the free space the
    /// tools leave ([`Self::confined_stress_and_tangent`]).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub segment_length: f64,
}

fn is_zero(value: &f64) -> bool {
    *value == 0.0
}

impl FibreLaw {
    /// Below this ε/ε_sh the stress is its Taylor series (see
    /// [`Self::stress_and_tangent`]); public so that a batched evaluation
    /// of the law can switch where the scalar one does.
    pub const TENSION_SERIES_BELOW: f64 = SERIES_BELOW;

    /// The share of E_f a tangent jump at ε = 0 must reach to be a kink
    /// (see [`Self::has_kink`]).
    pub const KINK_SHARE: f64 = KINK_SHARE;

    /// A fibre with no compression stiffness, validated.
    pub fn new(modulus: f64, crimp_strain: f64) -> Result<Self, MaterialError> {
        let law = Self {
            modulus,
            crimp_strain,
            compression_factor: 0.0,
            buckling_stress: 0.0,
            segment_length: 0.0,
        };
        law.validate("fibre")?;
        Ok(law)
    }

    /// Checks every parameter; `path` prefixes the field names in the error.
    pub fn validate(&self, path: &str) -> Result<(), MaterialError> {
        MaterialError::check_positive(path, "modulus", self.modulus)?;
        MaterialError::check(
            path,
            "crimp_strain",
            self.crimp_strain,
            self.crimp_strain >= 0.0 && self.crimp_strain < 1.0,
            "a crimp strain in [0, 1)",
        )?;
        MaterialError::check(
            path,
            "compression_factor",
            self.compression_factor,
            (0.0..=1.0).contains(&self.compression_factor),
            "a fraction of the tensile modulus in [0, 1]",
        )?;
        MaterialError::check(
            path,
            "buckling_stress",
            self.buckling_stress,
            self.buckling_stress >= 0.0,
            "a stress >= 0 (MPa)",
        )?;
        MaterialError::check(
            path,
            "segment_length",
            self.segment_length,
            self.segment_length >= 0.0 && self.segment_length.is_finite(),
            "a length >= 0 (mm)",
        )?;
        if self.buckling_stress > 0.0 {
            // The column law needs the crimp as its imperfection, replaces
            // the linear compression branch, and must not raise the stable
            // step's modulus: its steepest tangent, σ_b/(2ε_sh) at ε = 0,
            // stays at most E_f.
            MaterialError::check(
                path,
                "crimp_strain",
                self.crimp_strain,
                self.crimp_strain > 0.0,
                "a crimp strain > 0 with buckling_stress (the crimp is the column's bow)",
            )?;
            MaterialError::check(
                path,
                "compression_factor",
                self.compression_factor,
                self.compression_factor == 0.0,
                "0 with buckling_stress (one compression law at a time)",
            )?;
            MaterialError::check(
                path,
                "buckling_stress",
                self.buckling_stress,
                self.buckling_stress <= 2.0 * self.crimp_strain * self.modulus,
                "at most 2·crimp_strain·modulus (its initial tangent σ_b/(2ε_sh) at most E_f)",
            )?;
        }
        Ok(())
    }

    /// The buckled column's stress and tangent at ε ≤ 0 (σ_b > 0, ε_sh > 0),
    /// written without cancellation: 1 − 1/√(1+x) = x/(√(1+x)·(1 + √(1+x))).
    /// Public so that a batched evaluation computes the same bits.
    #[inline]
    pub fn buckled_stress_and_tangent(&self, eps: f64) -> (f64, f64) {
        self.column(-eps / self.crimp_strain)
    }

    /// Whether a yarn between two tools is confined
    /// ([`Self::confined_stress_and_tangent`]): σ_b > 0 and L > 0.
    #[inline]
    pub fn confines(&self) -> bool {
        self.buckling_stress > 0.0 && self.segment_length > 0.0
    }

    /// The largest clearance (mm) whose wall a yarn shortened by at most
    /// [`CONFINED_SHORTENING`] (a log strain) can meet
    /// ([`Self::confined_stress_and_tangent`]): the bow reaches a wall at
    /// clearance c once the yarn is shortened by ε_sh·((1 + c/a₀)² − 1),
    /// so beyond a₀·(√(1 + 0.2/ε_sh) − 1) it is not met (1.02 mm for
    /// `glass-serge-4x3`). 0 for a law that confines nothing.
    pub fn confinement_reach(&self) -> f64 {
        if !self.confines() || self.crimp_strain <= 0.0 {
            return 0.0;
        }
        self.crimp_amplitude() * ((1.0 + CONFINED_SHORTENING / self.crimp_strain).sqrt() - 1.0)
    }

    /// a₀ = (2L/π)·√ε_sh (mm), the bow of the crimped segment: the half
    /// sine of amplitude a₀ over L is longer than its chord by ε_sh.
    #[inline]
    pub fn crimp_amplitude(&self) -> f64 {
        2.0 * self.segment_length / std::f64::consts::PI * self.crimp_strain.sqrt()
    }

    /// The stress and tangent of a yarn whose column may bow out by at most
    /// `clearance` (mm) beyond its crimp: the free space the tools leave it
    /// (infinite, or a law that [`Self::confines`] nothing: the free law,
    /// bit for bit).
    ///
    /// The segment of length L is the pinned column of
    /// [`Self::buckling_stress`], bowed by a₀ ([`Self::crimp_amplitude`]);
    /// its bow grows as a = a₀/√(1 + x), x = −ε/ε_sh, until it reaches the
    /// wall at a_m = a₀ + c, at x_c = (a_m/a₀)² − 1 (the bow grows by the
    /// free space c the tools leave over the ply's thickness, which
    /// already holds the crimp). Beyond, it is a column between two walls
    /// (Chai, J. Mech. Phys. Solids 46 (1998) 1155, "The post-buckling
    /// response of a bi-laterally constrained column"; Domokos, Holmes &
    /// Royce, J. Nonlinear Sci. 7 (1997) 281, "Constrained Euler
    /// buckling"): it cannot bow further, so it shortens by going to higher
    /// modes, each touching the walls. In mode n its n half sines of length
    /// L/n and amplitude a_m carry P_n = n²·P_E (the Euler load of a span
    /// L/n) and make the arc longer than the chord by n²·ε_a, ε_a =
    /// (π·a_m/2L)² (each span's excess π²a_m²/(4·L/n), n spans, over L).
    /// Eliminating n: P/P_E = (arc excess)/ε_a, so along the modes the load
    /// grows linearly with the shortening, by P_E per ε_a: the envelope
    /// through the mode points (Chai's load between two modes rises and
    /// snaps back about it, which a smeared yarn does not resolve). The law
    /// continues the free column from its load at the wall, τ_c, with that
    /// slope: τ = τ_c + k·(ε − ε_c), ε_c = −x_c·ε_sh, and, in series, the
    /// fibres' own compliance 1/E_f, which the free column leaves out (four
    /// orders below the bow's) but which is what a yarn with no room to
    /// bow has left: 1/k = ε_a/σ_b + 1/E_f. So k < E_f at any clearance
    /// (the stable step is still E_f's), the stress is continuous in ε and
    /// in c (as c → ∞, x_c → ∞: the free law), and the tangent jumps at ε_c
    /// from the free column's σ_b/(2ε_sh·(1 + x_c)^{3/2}) up to k.
    ///
    /// The clearance is taken from the tools' last gaps, fixed over a step:
    /// for a given c the law is hyperelastic ([`Self::confined_energy`]).
    #[inline]
    pub fn confined_stress_and_tangent(&self, eps: f64, clearance: f64) -> (f64, f64) {
        if eps > 0.0 || !self.confines() || clearance == f64::INFINITY {
            return self.stress_and_tangent(eps);
        }
        let (xc, eps_a) = self.wall(clearance);
        let sh = self.crimp_strain;
        let x = -eps / sh;
        if x <= xc {
            return self.buckled_stress_and_tangent(eps);
        }
        let (tau_c, _) = self.column(xc);
        let k = self.confined_tangent(eps_a);
        (tau_c + k * (eps + xc * sh), k)
    }

    /// [`Self::energy`] of the confined column
    /// ([`Self::confined_stress_and_tangent`]): the free column's energy at
    /// the wall plus the linear branch's, τ_c·d + k·d²/2, d = ε − ε_c.
    pub fn confined_energy(&self, eps: f64, clearance: f64) -> f64 {
        if eps > 0.0 || !self.confines() || clearance == f64::INFINITY {
            return self.energy(eps);
        }
        let (xc, eps_a) = self.wall(clearance);
        let sh = self.crimp_strain;
        if -eps / sh <= xc {
            return self.energy(eps);
        }
        let d = eps + xc * sh;
        let k = self.confined_tangent(eps_a);
        self.energy(-xc * sh) + self.column(xc).0 * d + 0.5 * k * d * d
    }

    /// W(ε, c_new) − W(ε, c_old) ([`Self::confined_energy`]): what the
    /// tools do to a yarn at strain ε when their gap moves its wall from
    /// `old` to `new` clearance. Zero unless the yarn is past the nearer
    /// of the two walls (cheap to ask of every yarn each step).
    pub fn confinement_energy_change(&self, eps: f64, old: f64, new: f64) -> f64 {
        if eps >= 0.0 || !self.confines() || old == new {
            return 0.0;
        }
        let x = -eps / self.crimp_strain;
        if x <= self.wall(old).0.min(self.wall(new).0) {
            return 0.0;
        }
        self.confined_energy(eps, new) - self.confined_energy(eps, old)
    }

    /// x_c, where the bow reaches the wall, and ε_a = (π·a_m/2L)² =
    /// ε_sh·(a_m/a₀)², for a clearance c (negative taken as 0).
    #[inline]
    fn wall(&self, clearance: f64) -> (f64, f64) {
        let ratio = 1.0 + clearance.max(0.0) / self.crimp_amplitude();
        let r2 = ratio * ratio;
        (r2 - 1.0, self.crimp_strain * r2)
    }

    /// The walled column's tangent k: 1/k = ε_a/σ_b + 1/E_f.
    #[inline]
    fn confined_tangent(&self, eps_a: f64) -> f64 {
        1.0 / (eps_a / self.buckling_stress + 1.0 / self.modulus)
    }

    /// The free column at x = −ε/ε_sh: see [`Self::buckled_stress_and_tangent`].
    #[inline]
    fn column(&self, x: f64) -> (f64, f64) {
        let sh = self.crimp_strain;
        let root = (1.0 + x).sqrt();
        let tau = -self.buckling_stress * x / (root * (1.0 + root));
        let tangent = self.buckling_stress / (2.0 * sh * root * (1.0 + x));
        (tau, tangent)
    }

    /// The stress τ(ε) and the tangent dτ/dε.
    #[inline]
    pub fn stress_and_tangent(&self, eps: f64) -> (f64, f64) {
        let e = self.modulus;
        if eps <= 0.0 {
            if self.buckling_stress > 0.0 {
                return self.buckled_stress_and_tangent(eps);
            }
            let k = self.compression_factor * e;
            return (k * eps, k);
        }
        let sh = self.crimp_strain;
        if sh == 0.0 {
            return (e * eps, e);
        }
        let x = eps / sh;
        if x < SERIES_BELOW {
            // x − (1 − e^(−x)) = x²/2 − x³/6 + x⁴/24 − …
            let tau = e * sh * x * x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x / 120.0)));
            let tangent = e * x * (1.0 - x * (0.5 - x * (1.0 / 6.0 - x / 24.0)));
            (tau, tangent)
        } else {
            let straightened = -(-x).exp_m1(); // 1 − e^(−x)
            (e * (eps - sh * straightened), e * straightened)
        }
    }

    /// The confined stress ([`Self::confined_stress_and_tangent`]).
    #[inline]
    pub fn confined_stress(&self, eps: f64, clearance: f64) -> f64 {
        self.confined_stress_and_tangent(eps, clearance).0
    }

    /// The stress τ(ε).
    #[inline]
    pub fn stress(&self, eps: f64) -> f64 {
        self.stress_and_tangent(eps).0
    }

    /// The tangent modulus E_t = dτ/dε.
    #[inline]
    pub fn tangent(&self, eps: f64) -> f64 {
        self.stress_and_tangent(eps).1
    }

    /// The strain energy per unit reference volume, w(ε) = ∫₀^ε τ dε.
    #[inline]
    pub fn energy(&self, eps: f64) -> f64 {
        let e = self.modulus;
        if eps <= 0.0 {
            if self.buckling_stress > 0.0 {
                // w = σ_b·ε_sh·(x − 2(√(1+x) − 1)) = σ_b·ε_sh·x²/(1 + √(1+x))².
                let sh = self.crimp_strain;
                let x = -eps / sh;
                let d = 1.0 + (1.0 + x).sqrt();
                return self.buckling_stress * sh * x * x / (d * d);
            }
            return 0.5 * self.compression_factor * e * eps * eps;
        }
        let sh = self.crimp_strain;
        if sh == 0.0 {
            return 0.5 * e * eps * eps;
        }
        let x = eps / sh;
        // w = E_f·ε_sh²·(x²/2 − x + 1 − e^(−x)). The closed form cancels
        // like 6/x² in relative terms (worse than the stress's 2/x), so the
        // series Σₙ≥₃ (−1)ⁿ⁺¹xⁿ/n! is used further out, to x = 0.1, where 16
        // terms leave a remainder below 1e-20 relative.
        let bracket = if x < ENERGY_SERIES_BELOW {
            let mut term = x * x * x / 6.0;
            let mut sum = 0.0;
            for n in 3..19 {
                sum += term;
                term *= -x / f64::from(n + 1);
            }
            sum
        } else {
            0.5 * x * x - x - (-x).exp_m1()
        };
        e * sh * sh * bracket
    }

    /// The modulus that sets the stable time step: the largest tangent the
    /// law can reach, E_f (SPEC §7; the column's σ_b/(2ε_sh) is validated
    /// not to exceed it).
    #[inline]
    pub fn wave_modulus(&self) -> f64 {
        self.modulus
    }

    /// Whether the tangent jumps at ε = 0 by [`Self::KINK_SHARE`] of E_f or
    /// more: an uncrimped yarn (ε_sh = 0) that carries less in compression
    /// than in tension (c_c < 1) goes from E_f to c_c·E_f, a crimped one
    /// with c_c > 0 from 0 to c_c·E_f, a buckling one from 0 to
    /// σ_b/(2ε_sh), a confined one ([`Self::confines`]) at a closed gap
    /// from 0 to its walled tangent 1/(ε_sh/σ_b + 1/E_f). (A crimped yarn without compression stiffness has
    /// E_t = 0 on both sides: no jump.)
    ///
    /// Such a yarn switches between a taut and a slack stiffness as it
    /// crosses ε = 0, and central differences are not stable for such a
    /// switching system at every step below the linear limit 2/ω_max:
    /// resonance bands make it grow (drape-time damps the yarn's ringing).
    #[inline]
    pub fn has_kink(&self) -> bool {
        let taut = if self.crimp_strain == 0.0 {
            self.modulus
        } else {
            0.0
        };
        // A confined column's largest jump is at a closed gap (c = 0): from
        // the tension side's 0 at ε = 0 straight to the walled tangent,
        // which falls as c grows, while the free column's tangent at the
        // wall does not exceed its σ_b/(2ε_sh).
        let compressed = if self.confines() {
            self.confined_tangent(self.crimp_strain)
        } else {
            self.stress_and_tangent(0.0).1
        };
        (taut - compressed).abs() >= KINK_SHARE * self.modulus
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn carbon() -> FibreLaw {
        FibreLaw::new(230_000.0, 0.005).unwrap()
    }

    proptest! {
        #[test]
        fn stress_is_the_derivative_of_energy_and_tangent_of_stress(
            eps in -0.05f64..0.1,
            sh in prop_oneof![Just(0.0), 1e-4f64..0.02],
            cc in 0.0f64..1.0,
        ) {
            let law = FibreLaw { modulus: 75_000.0, crimp_strain: sh, compression_factor: cc, buckling_stress: 0.0, segment_length: 0.0 };
            // Stay off the kink at ε = 0 where the compression branch starts.
            prop_assume!(eps.abs() > 1e-5);
            let h = 1e-7 * eps.abs().max(1e-4);
            let d_energy = (law.energy(eps + h) - law.energy(eps - h)) / (2.0 * h);
            let d_stress = (law.stress(eps + h) - law.stress(eps - h)) / (2.0 * h);
            let (tau, tangent) = law.stress_and_tangent(eps);
            let scale = law.modulus * eps.abs();
            prop_assert!((d_energy - tau).abs() <= 1e-6 * scale, "dW/dε {d_energy} vs τ {tau}");
            prop_assert!((d_stress - tangent).abs() <= 1e-6 * law.modulus, "dτ/dε {d_stress} vs E_t {tangent}");
        }

        #[test]
        fn series_and_closed_form_meet(sh in 1e-4f64..0.02) {
            // Either side of the switch the two forms agree to round-off.
            let law = FibreLaw { modulus: 1.0, crimp_strain: sh, compression_factor: 0.0, buckling_stress: 0.0, segment_length: 0.0 };
            let below = SERIES_BELOW * sh * (1.0 - 1e-12);
            let above = SERIES_BELOW * sh * (1.0 + 1e-12);
            let (t0, k0) = law.stress_and_tangent(below);
            let (t1, k1) = law.stress_and_tangent(above);
            prop_assert!((t0 - t1).abs() <= 1e-8 * t1);
            prop_assert!((k0 - k1).abs() <= 1e-10 * k1);
            let (below, above) = (ENERGY_SERIES_BELOW * sh * (1.0 - 1e-12), ENERGY_SERIES_BELOW * sh * (1.0 + 1e-12));
            // w ∝ x³ here, so the points' 2e-12 apart in x differ by 6e-12 in w.
            prop_assert!((law.energy(below) - law.energy(above)).abs() <= 1e-11 * law.energy(above));
        }
    }

    #[test]
    fn straightened_yarn_has_the_full_modulus_and_a_crimped_one_none() {
        let law = carbon();
        // ε ≫ ε_sh: slope E_f, offset E_f·ε_sh.
        let eps = 40.0 * law.crimp_strain;
        assert!((law.tangent(eps) / law.modulus - 1.0).abs() < 1e-16 + (-40f64).exp());
        assert!((law.stress(eps) - law.modulus * (eps - law.crimp_strain)).abs() < 1e-9);
        // ε → 0: slope → 0 like E_f·ε/ε_sh.
        let x = 1e-9 / law.crimp_strain;
        // The next term of the series is −x/2 relative.
        assert!((law.tangent(1e-9) / (law.modulus * x) - 1.0).abs() <= 0.5 * x * (1.0 + 1e-9));
        assert_eq!(law.tangent(0.0), 0.0);
        assert_eq!(law.stress(-0.01), 0.0);
    }

    #[test]
    fn a_kink_is_a_jump_of_the_tangent_at_zero() {
        let h = 1e-12;
        for (sh, cc) in [
            (0.0, 0.0),
            (0.0, 0.5),
            (0.0, 1.0),
            (0.01, 0.0),
            (0.01, 0.3),
            (0.01, 0.02),
            (0.01, 0.005),
            (0.0, 0.995),
        ] {
            let law = FibreLaw {
                modulus: 1000.0,
                crimp_strain: sh,
                compression_factor: cc,
                buckling_stress: 0.0,
                segment_length: 0.0,
            };
            let jump = (law.tangent(h) - law.tangent(-h)).abs();
            assert_eq!(
                law.has_kink(),
                jump >= KINK_SHARE * law.modulus,
                "ε_sh {sh}, c_c {cc}: jump {jump}"
            );
        }
    }

    #[test]
    fn compression_option_is_linear() {
        let law = FibreLaw {
            compression_factor: 0.1,
            ..carbon()
        };
        assert_eq!(law.stress(-0.002), -0.1 * 230_000.0 * 0.002);
        assert_eq!(law.tangent(-0.002), 23_000.0);
    }

    /// The glass preset's yarn: σ_b = π²·B/(L²·V_f·h/2) with B = 0.465 N·mm,
    /// L = 4.55 mm, V_f·h/2 = 0.1425 mm.
    fn buckling_glass() -> FibreLaw {
        FibreLaw {
            buckling_stress: 1.556,
            ..FibreLaw::new(75_000.0, 0.012).unwrap()
        }
    }

    proptest! {
        #[test]
        fn buckling_stress_is_the_derivative_of_energy_and_tangent_of_stress(
            x in 1e-3f64..50.0,
            sh in 1e-3f64..0.05,
            sigma in 0.01f64..20.0,
        ) {
            let law = FibreLaw { buckling_stress: sigma, ..FibreLaw::new(75_000.0, sh).unwrap() };
            let eps = -x * sh;
            let h = 1e-6 * eps.abs();
            let d_energy = (law.energy(eps + h) - law.energy(eps - h)) / (2.0 * h);
            let d_stress = (law.stress(eps + h) - law.stress(eps - h)) / (2.0 * h);
            let (tau, tangent) = law.stress_and_tangent(eps);
            // Central differences: truncation ~h²·w''' and round-off
            // ~ε_mach·w/h, both below 1e-7 of the scale here.
            prop_assert!((d_energy - tau).abs() <= 1e-7 * sigma, "dW/dε {d_energy} vs τ {tau}");
            prop_assert!(
                (d_stress - tangent).abs() <= 1e-6 * tangent,
                "dτ/dε {d_stress} vs E_t {tangent}"
            );
            // Monotone, bounded by the Euler stress, and storing energy.
            prop_assert!(tau < 0.0 && tau > -sigma && tangent > 0.0 && law.energy(eps) > 0.0);
        }

        #[test]
        fn buckling_law_is_the_imperfect_column(r in 1e-6f64..0.999) {
            // A pinned column bowed by a₀ carries P = r·P_E at a bow
            // a = a₀/(1 − r); its chord shortens by ε_sh·((a/a₀)² − 1).
            let law = buckling_glass();
            let eps = -law.crimp_strain * ((1.0 - r).powi(-2) - 1.0);
            let tau = law.stress(eps);
            prop_assert!(
                (tau + r * law.buckling_stress).abs() <= 1e-12 * law.buckling_stress,
                "r {r}: τ {tau}"
            );
        }
    }

    #[test]
    fn buckling_law_values_and_limits() {
        let law = buckling_glass();
        let (s, sh) = (law.buckling_stress, law.crimp_strain);
        // x = 3: √(1 + x) = 2, so τ = −σ_b/2, E_t = σ_b/(16·ε_sh) and
        // w = σ_b·ε_sh·(3 − 2) exactly (to round-off).
        let (tau, tangent) = law.stress_and_tangent(-3.0 * sh);
        assert!((tau + 0.5 * s).abs() <= 1e-15 * s, "{tau}");
        assert!(
            (tangent - s / (16.0 * sh)).abs() <= 1e-15 * tangent,
            "{tangent}"
        );
        assert!((law.energy(-3.0 * sh) - s * sh).abs() <= 1e-15 * s * sh);
        // At ε = 0 the tangent is σ_b/(2ε_sh) (a jump from the tension
        // side's 0) and the stress and energy vanish.
        assert_eq!(law.stress_and_tangent(0.0), (0.0, s / (2.0 * sh)));
        assert_eq!(law.energy(0.0), 0.0);
        // A jump of 8.7e-4·E_f: too small to ring (no dashpots); the
        // largest jump allowed, E_f, is a kink.
        assert!(!law.has_kink());
        let edge = FibreLaw {
            buckling_stress: 2.0 * sh * law.modulus,
            ..law
        };
        assert!(edge.has_kink());
        let share = FibreLaw {
            buckling_stress: 2.0 * sh * law.modulus * KINK_SHARE,
            ..law
        };
        assert!(share.has_kink());
        let below = FibreLaw {
            buckling_stress: 2.0 * sh * law.modulus * KINK_SHARE * 0.99,
            ..law
        };
        assert!(!below.has_kink());
        // Near zero, no cancellation: w = σ_b·ε_sh·x²/4·(1 − x/2 + …).
        let x = 1e-9;
        let w = law.energy(-x * sh);
        assert!((w / (s * sh * x * x / 4.0) - 1.0).abs() <= 1e-8, "{w}");
        let tau = law.stress(-x * sh);
        assert!((tau / (-s * x / 2.0) - 1.0).abs() <= 1e-8, "{tau}");
        // Far into compression it carries the Euler stress, not more:
        // 1 − 1/√(1 + x) at x = 9999 is 0.99.
        assert!((law.stress(-9999.0 * sh) / -s - 0.99).abs() <= 1e-12);
        // Tension is the crimped law's, untouched.
        let plain = FibreLaw::new(75_000.0, 0.012).unwrap();
        for eps in [1e-7, 1e-3, 0.02] {
            assert_eq!(law.stress_and_tangent(eps), plain.stress_and_tangent(eps));
            assert_eq!(law.energy(eps), plain.energy(eps));
        }
    }

    #[test]
    fn buckling_parameters_are_checked_and_named() {
        let field = |law: FibreLaw| law.validate("fibre").unwrap_err().field;
        let glass = buckling_glass();
        glass.validate("fibre").unwrap();
        assert_eq!(
            field(FibreLaw {
                buckling_stress: -1.0,
                ..glass
            }),
            "fibre.buckling_stress"
        );
        assert_eq!(
            field(FibreLaw {
                buckling_stress: f64::NAN,
                ..glass
            }),
            "fibre.buckling_stress"
        );
        // No crimp, no bow: the column law has nothing to grow.
        assert_eq!(
            field(FibreLaw {
                crimp_strain: 0.0,
                ..glass
            }),
            "fibre.crimp_strain"
        );
        assert_eq!(
            field(FibreLaw {
                compression_factor: 0.1,
                ..glass
            }),
            "fibre.compression_factor"
        );
        // σ_b/(2ε_sh) = E_f is the largest allowed: the stable step stays E_f's.
        let edge = 2.0 * glass.crimp_strain * glass.modulus;
        FibreLaw {
            buckling_stress: edge,
            ..glass
        }
        .validate("fibre")
        .unwrap();
        assert_eq!(
            field(FibreLaw {
                buckling_stress: edge * (1.0 + 1e-12),
                ..glass
            }),
            "fibre.buckling_stress"
        );
    }

    /// The glass preset's yarn confined: L = 4.55 mm, so a₀ = 0.317 mm.
    fn confined_glass() -> FibreLaw {
        FibreLaw {
            segment_length: 10.0 / 2.2,
            ..buckling_glass()
        }
    }

    proptest! {
        #[test]
        fn confined_stress_is_the_derivative_of_energy_and_tangent_of_stress(
            x in 1e-3f64..60.0,
            sh in 1e-3f64..0.05,
            share in 0.01f64..1.0,
            length in 1.0f64..10.0,
            clearance in prop_oneof![Just(0.0), 1e-3f64..2.0],
        ) {
            let law = FibreLaw {
                buckling_stress: share * 2.0 * sh * 75_000.0,
                segment_length: length,
                ..FibreLaw::new(75_000.0, sh).unwrap()
            };
            let (xc, _) = law.wall(clearance);
            // Off the kink at the wall, where the tangent jumps.
            prop_assume!((x - xc).abs() > 1e-3 * (1.0 + xc));
            let eps = -x * sh;
            let h = 1e-6 * eps.abs().min((x - xc).abs() * sh);
            let w = |e| law.confined_energy(e, clearance);
            let tau = |e| law.confined_stress_and_tangent(e, clearance).0;
            let d_energy = (w(eps + h) - w(eps - h)) / (2.0 * h);
            let d_stress = (tau(eps + h) - tau(eps - h)) / (2.0 * h);
            let (t, k) = law.confined_stress_and_tangent(eps, clearance);
            // Round-off ~ε_mach·w/h over the stress scale |τ| + k·|ε|.
            let scale = t.abs() + k * eps.abs();
            prop_assert!((d_energy - t).abs() <= 1e-6 * scale, "dW/dε {d_energy} vs τ {t}");
            // Each τ(ε ± h) is off by a few ε_mach·scale (its own rounding,
            // and the argument's, ε_mach·|ε| times the slope k): the
            // difference quotient by up to 4·ε_mach·scale/h. Near the wall
            // h is 1e-6·|x − x_c|·ε_sh, so that can pass 1e-6·k (a draw at
            // 0.07 from x_c was 1.1e-6·k off: 0.55 of it); 1e-9·k is the
            // truncation, h²·τ'''/6, with room.
            let round_off = 4.0 * f64::EPSILON * scale / h;
            prop_assert!(
                (d_stress - k).abs() <= 1e-9 * k + round_off,
                "dτ/dε {d_stress} vs k {k} (round-off {round_off:e})"
            );
            // Monotone, storing energy, and the stable step still E_f's.
            prop_assert!(t < 0.0 && k > 0.0 && k < law.modulus && w(eps) > 0.0);
        }

        #[test]
        fn confinement_is_continuous_and_only_adds(
            x in 1e-3f64..60.0,
            c in 0.0f64..3.0,
            more in 1e-6f64..3.0,
        ) {
            let law = confined_glass();
            let free = law.stress(-x * law.crimp_strain);
            let (xc, _) = law.wall(c);
            // Either side of the wall the two branches meet (to round-off
            // of the stress there).
            let at = |x: f64| law.confined_stress_and_tangent(-x * law.crimp_strain, c).0;
            let (below, above) = (at(xc * (1.0 - 1e-12)), at(xc * (1.0 + 1e-12)));
            prop_assert!((below - above).abs() <= 1e-9 * law.buckling_stress, "{below} vs {above}");
            // Up to the wall, the free column bit for bit; beyond it, more
            // than the free column carries, and less with more room.
            let tau = at(x);
            if x <= xc {
                prop_assert_eq!(tau, free);
            } else {
                prop_assert!(tau < free);
            }
            prop_assert!(tau <= at_with(&law, x, c + more));
        }
    }

    proptest! {
        #[test]
        fn moving_a_wall_changes_the_energy_only_past_it(
            x in 0.0f64..60.0,
            old in prop_oneof![Just(f64::INFINITY), 0.0f64..3.0],
            new in prop_oneof![Just(f64::INFINITY), 0.0f64..3.0],
        ) {
            let law = confined_glass();
            let eps = -x * law.crimp_strain;
            let change = law.confinement_energy_change(eps, old, new);
            let exact = law.confined_energy(eps, new) - law.confined_energy(eps, old);
            prop_assert!((change - exact).abs() <= 1e-15 * law.confined_energy(eps, 0.0));
            // Closing in stores energy, opening gives it back.
            let stores = if new <= old { change >= 0.0 } else { change <= 0.0 };
            prop_assert!(stores, "{change} from {old} to {new}");
            if x <= law.wall(old).0.min(law.wall(new).0) {
                prop_assert_eq!(change, 0.0);
            }
        }
    }

    fn at_with(law: &FibreLaw, x: f64, c: f64) -> f64 {
        law.confined_stress_and_tangent(-x * law.crimp_strain, c).0
    }

    #[test]
    fn confined_column_follows_the_mode_envelope() {
        let law = confined_glass();
        let (s, sh) = (law.buckling_stress, law.crimp_strain);
        // a₀ = (2L/π)·√ε_sh.
        let a0 = law.crimp_amplitude();
        assert!((a0 - 2.0 * 4.545_454_545 / std::f64::consts::PI * 0.012f64.sqrt()).abs() < 1e-9);
        assert!((a0 - 0.3170).abs() < 1e-4, "{a0}");
        let c = 0.1;
        let a_m = a0 + c;
        let eps_a = (std::f64::consts::PI * a_m / (2.0 * law.segment_length)).powi(2);
        // Mode n touches both walls with arc excess n²·ε_a over the chord,
        // the crimp ε_sh of which is there unloaded: ε_n = ε_sh − n²·ε_a.
        // Between modes the load grows by σ_b per ε_a of shortening (P_n =
        // n²·P_E), less the fibres' compliance in series.
        let k = 1.0 / (eps_a / s + 1.0 / law.modulus);
        let tau = |n: f64| law.confined_stress_and_tangent(sh - n * n * eps_a, c).0;
        for n in 1..6 {
            let n = f64::from(n);
            let rise = tau(n) - tau(n + 1.0);
            let expected = k * (2.0 * n + 1.0) * eps_a;
            assert!(
                (rise - expected).abs() <= 1e-12 * expected,
                "n {n}: {rise} vs {expected}"
            );
            // k·ε_a = σ_b less the fibres' share: 1 − k·ε_a/σ_b =
            // 1/(1 + ε_a·E_f/σ_b) = 1.0e-3 here.
            let share = 1.0 - k * eps_a / s;
            assert!(
                (share * (1.0 + eps_a * law.modulus / s) - 1.0).abs() < 1e-9,
                "{share}"
            );
            assert!((share - 1.0e-3).abs() < 0.05e-3, "{share}");
        }
        // At the wall (mode 1) the free imperfect column's load,
        // P/P_E = 1 − a₀/a_m.
        let at_wall = tau(1.0);
        assert!(
            (at_wall + s * (1.0 - a0 / a_m)).abs() <= 1e-12 * s,
            "{at_wall}"
        );
        // The numbers the docs quote (glass, c = 0.1 mm): the wall at 0.88 %
        // shortening, k = 74.9 MPa, 12.4 MPa at 17 % (free: 1.16 MPa).
        let (xc, _) = law.wall(c);
        assert!((xc * sh - 0.00877).abs() < 1e-5, "{}", xc * sh);
        assert!((k - 74.86).abs() < 0.01, "{k}");
        let at17 = law.confined_stress(-0.17, c);
        assert!((at17 + 12.44).abs() < 0.01, "{at17}");
        assert!(
            (law.stress(-0.17) + 1.16).abs() < 0.01,
            "{}",
            law.stress(-0.17)
        );
    }

    #[test]
    fn unconfined_laws_and_far_tools_give_the_free_law() {
        let law = confined_glass();
        for eps in [-0.3, -0.01, -1e-7, 0.0, 1e-7, 0.02] {
            let free = (law.stress_and_tangent(eps), law.energy(eps));
            assert_eq!(
                (
                    law.confined_stress_and_tangent(eps, f64::INFINITY),
                    law.confined_energy(eps, f64::INFINITY)
                ),
                free
            );
            // Tension is never confined.
            if eps > 0.0 {
                assert_eq!(
                    law.confined_stress_and_tangent(eps, 0.0),
                    law.stress_and_tangent(eps)
                );
            }
            // Without L, or without σ_b, nothing is confined.
            let plain = buckling_glass();
            assert_eq!(
                plain.confined_stress_and_tangent(eps, 0.0),
                plain.stress_and_tangent(eps)
            );
        }
        // Far but finite tools: the wall is past any strain a yarn reaches.
        assert_eq!(law.confined_stress(-0.5, 100.0), law.stress(-0.5));
    }

    /// A wall at the confinement reach is met at a log strain of
    /// −`CONFINED_SHORTENING`, not before: up to it the yarn is free, and
    /// past it walled (a stiffer column than the free one).
    #[test]
    fn a_wall_at_the_confinement_reach_is_met_at_the_shortening_bound() {
        let law = confined_glass();
        let c = law.confinement_reach();
        assert!((c - 1.015).abs() < 1e-3, "{c}");
        let bound = -CONFINED_SHORTENING;
        assert!((law.wall(c).0 * law.crimp_strain - CONFINED_SHORTENING).abs() < 1e-12);
        for eps in [-0.01, -0.1, 0.999 * bound] {
            assert_eq!(law.confined_stress(eps, c), law.stress(eps), "{eps}");
        }
        let past = 1.05 * bound;
        assert!(law.confined_stress(past, c) < law.stress(past));
        assert_eq!(buckling_glass().confinement_reach(), 0.0);
    }

    #[test]
    fn a_closed_gap_is_a_kink_only_past_the_share() {
        // Glass closed: from 0 to 1/(ε_sh/σ_b + 1/E_f) = 129.4 MPa, 1.7e-3·E_f.
        let law = confined_glass();
        assert!(!law.has_kink());
        let k0 = law.confined_stress_and_tangent(-1e-9, 0.0).1;
        assert!(
            (k0 / law.modulus - 1.7259e-3).abs() < 1e-7,
            "{}",
            k0 / law.modulus
        );
        // The carbon preset's column (σ_b 18.6 MPa, ε_sh 0.005) would jump
        // by 1.6 % of E_f: a kink.
        let carbon = FibreLaw {
            buckling_stress: 18.6,
            segment_length: 4.0,
            ..FibreLaw::new(230_000.0, 0.005).unwrap()
        };
        assert!(carbon.has_kink());
        assert!(
            !FibreLaw {
                segment_length: 0.0,
                ..carbon
            }
            .has_kink()
        );
        // The largest σ_b allowed, closed: k < E_f still.
        let edge = FibreLaw {
            buckling_stress: 2.0 * law.crimp_strain * law.modulus,
            ..law
        };
        let k = edge.confined_stress_and_tangent(-1e-3, 0.0).1;
        assert!(
            k < law.modulus && (k / law.modulus - 2.0 / 3.0).abs() < 1e-12,
            "{k}"
        );
    }

    #[test]
    fn segment_length_is_checked_and_named() {
        let field = |law: FibreLaw| law.validate("fibre").unwrap_err().field;
        confined_glass().validate("fibre").unwrap();
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(
                field(FibreLaw {
                    segment_length: bad,
                    ..confined_glass()
                }),
                "fibre.segment_length"
            );
        }
        // A column length without a column is valid and confines nothing
        // (`yarn_buckling = false` drops σ_b and keeps the preset's L).
        let bare = FibreLaw {
            segment_length: 4.0,
            ..FibreLaw::new(75_000.0, 0.012).unwrap()
        };
        bare.validate("fibre").unwrap();
        assert!(!bare.confines());
        let text = toml::to_string(&confined_glass()).unwrap();
        assert!(text.contains("segment_length"), "{text}");
        let back: FibreLaw = toml::from_str(&text).unwrap();
        assert_eq!(back, confined_glass());
    }

    #[test]
    fn a_law_without_buckling_writes_no_key() {
        // Cards written before the key read and write the same text.
        let text = toml::to_string(&FibreLaw::new(75_000.0, 0.012).unwrap()).unwrap();
        assert!(!text.contains("buckling"), "{text}");
        let back: FibreLaw = toml::from_str(&toml::to_string(&buckling_glass()).unwrap()).unwrap();
        assert_eq!(back, buckling_glass());
    }

    #[test]
    fn invalid_parameters_are_named() {
        let err = FibreLaw::new(-1.0, 0.01).unwrap_err();
        assert_eq!(err.field, "fibre.modulus");
        let err = FibreLaw::new(1.0, -0.01).unwrap_err();
        assert_eq!(err.field, "fibre.crimp_strain");
        assert!(err.to_string().contains("crimp strain"), "{err}");
        let err = FibreLaw::new(f64::NAN, 0.01).unwrap_err();
        assert_eq!(err.field, "fibre.modulus");
    }
}
