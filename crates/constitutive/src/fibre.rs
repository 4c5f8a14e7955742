//! The crimped fibre law.

use serde::{Deserialize, Serialize};

use crate::MaterialError;

/// Below this ε/ε_sh the closed forms lose digits to cancellation
/// (ε − ε_sh(1 − e^(−x)) ≈ ε·x/2); a Taylor series is exact to round-off.
const SERIES_BELOW: f64 = 1e-3;
/// The energy's closed form cancels more: its series runs further.
const ENERGY_SERIES_BELOW: f64 = 0.1;

/// The crimped yarn, hyperelastic in the log strain ε = ln λ (SPEC §4,
/// paper eq. 8–9 integrated in closed form):
///
/// - tension (ε > 0): τ = E_f·(ε − ε_sh·(1 − e^(−ε/ε_sh))), tangent
///   E_t = E_f·(1 − e^(−ε/ε_sh));
/// - compression (ε ≤ 0): τ = c_c·E_f·ε.
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
}

impl FibreLaw {
    /// Below this ε/ε_sh the stress is its Taylor series (see
    /// [`Self::stress_and_tangent`]); public so that a batched evaluation
    /// of the law can switch where the scalar one does.
    pub const TENSION_SERIES_BELOW: f64 = SERIES_BELOW;

    /// A fibre with no compression stiffness, validated.
    pub fn new(modulus: f64, crimp_strain: f64) -> Result<Self, MaterialError> {
        let law = Self {
            modulus,
            crimp_strain,
            compression_factor: 0.0,
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
        )
    }

    /// The stress τ(ε) and the tangent dτ/dε.
    #[inline]
    pub fn stress_and_tangent(&self, eps: f64) -> (f64, f64) {
        let e = self.modulus;
        if eps <= 0.0 {
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
    /// law can reach, E_f (SPEC §7).
    #[inline]
    pub fn wave_modulus(&self) -> f64 {
        self.modulus
    }

    /// Whether the tangent jumps at ε = 0: an uncrimped yarn (ε_sh = 0)
    /// that carries less in compression than in tension (c_c < 1) goes
    /// from E_f to c_c·E_f, a crimped one with c_c > 0 from 0 to c_c·E_f.
    /// (A crimped yarn without compression stiffness has E_t = 0 on both
    /// sides: no jump.)
    ///
    /// Such a yarn switches between a taut and a slack stiffness as it
    /// crosses ε = 0, and central differences are not stable for such a
    /// switching system at every step below the linear limit 2/ω_max:
    /// resonance bands make it grow (drape-time damps the yarn's ringing).
    #[inline]
    pub fn has_kink(&self) -> bool {
        if self.crimp_strain == 0.0 {
            self.compression_factor < 1.0
        } else {
            self.compression_factor > 0.0
        }
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
            let law = FibreLaw { modulus: 75_000.0, crimp_strain: sh, compression_factor: cc };
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
            let law = FibreLaw { modulus: 1.0, crimp_strain: sh, compression_factor: 0.0 };
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
        for (sh, cc) in [(0.0, 0.0), (0.0, 0.5), (0.0, 1.0), (0.01, 0.0), (0.01, 0.3)] {
            let law = FibreLaw {
                modulus: 1000.0,
                crimp_strain: sh,
                compression_factor: cc,
            };
            let jump = (law.tangent(h) - law.tangent(-h)).abs();
            assert_eq!(
                law.has_kink(),
                jump > 1.0,
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
