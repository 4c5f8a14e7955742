//! The resin: plane-stress hypo-elasticity in the rotated frame with an
//! optional Prony relaxation of the in-plane shear.

use nalgebra::{Matrix2, Matrix3};
use serde::{Deserialize, Serialize};

use crate::{MaterialError, ShearLocking};

/// One term of the Prony series G(t) = G₀·(1 − Σ g_k·(1 − e^(−t/τ_k)))
/// (Abaqus convention).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PronyTerm {
    /// g_k, the relative shear modulus this term relaxes.
    pub g: f64,
    /// τ_k, its relaxation time (s).
    pub tau: f64,
}

/// The resin of the bi-component element: isotropic plane-stress
/// hypo-elasticity τ̄ₙ₊₁ = τ̄ₙ + C:Δε̄ in the Green–Naghdi frame (SPEC §4),
/// with the in-plane shear optionally relaxed by a Prony series.
///
/// History per integration point, beside τ̄: nothing for an elastic resin;
/// for a viscoelastic one `history_len()` = 1 + K values, the instantaneous
/// (unrelaxed) shear stress s₀ followed by the K Prony stresses q_k.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ResinLaw {
    /// E_m, Young's modulus (MPa).
    pub young: f64,
    /// ν_m, Poisson's ratio.
    pub poisson: f64,
    /// Prony terms of the in-plane shear; empty for an elastic resin.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub prony: Vec<PronyTerm>,
    /// An optional non-linear shear law of the fabric (shear locking),
    /// superposed on the membrane: see [`ShearLocking`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_locking: Option<ShearLocking>,
}

/// φ(x) = (1 − e^(−x))/x, the exact weight of a linear ramp over one step
/// of x relaxation times; φ(0) = 1 (a jump).
#[inline]
fn ramp_weight(x: f64) -> f64 {
    if x < 1e-8 {
        1.0 - 0.5 * x
    } else {
        -(-x).exp_m1() / x
    }
}

impl ResinLaw {
    /// An elastic resin, validated.
    pub fn elastic(young: f64, poisson: f64) -> Result<Self, MaterialError> {
        let law = Self {
            young,
            poisson,
            prony: Vec::new(),
            shear_locking: None,
        };
        law.validate("resin")?;
        Ok(law)
    }

    /// Checks every parameter; `path` prefixes the field names in the error.
    pub fn validate(&self, path: &str) -> Result<(), MaterialError> {
        MaterialError::check_positive(path, "young", self.young)?;
        MaterialError::check(
            path,
            "poisson",
            self.poisson,
            self.poisson > -1.0 && self.poisson < 0.5,
            "a Poisson's ratio in the open interval (−1, 0.5)",
        )?;
        let mut sum = 0.0;
        for (k, term) in self.prony.iter().enumerate() {
            let here = format!("prony[{k}]");
            let prefix = if path.is_empty() {
                here
            } else {
                format!("{path}.{here}")
            };
            MaterialError::check(
                &prefix,
                "g",
                term.g,
                term.g >= 0.0 && term.g < 1.0,
                "a relative modulus g_k in [0, 1)",
            )?;
            MaterialError::check_positive(&prefix, "tau", term.tau)?;
            sum += term.g;
        }
        MaterialError::check(
            path,
            "prony",
            sum,
            sum < 1.0,
            "Prony weights g_k summing to less than 1 (the long-term modulus must stay positive)",
        )?;
        match &self.shear_locking {
            Some(law) => law.validate(&if path.is_empty() {
                "shear_locking".to_owned()
            } else {
                format!("{path}.shear_locking")
            }),
            None => Ok(()),
        }
    }

    /// Whether the shear relaxes (any Prony term).
    #[inline]
    pub fn is_viscoelastic(&self) -> bool {
        !self.prony.is_empty()
    }

    /// History values per integration point beside τ̄: 0 when elastic, else
    /// 1 + K (s₀ and the q_k).
    #[inline]
    pub fn history_len(&self) -> usize {
        if self.prony.is_empty() {
            0
        } else {
            1 + self.prony.len()
        }
    }

    /// The instantaneous shear modulus G₀ = E/(2(1 + ν)).
    #[inline]
    pub fn shear_modulus(&self) -> f64 {
        self.young / (2.0 * (1.0 + self.poisson))
    }

    /// The long-term shear modulus G₀·(1 − Σg_k).
    pub fn long_term_shear_modulus(&self) -> f64 {
        self.shear_modulus() * (1.0 - self.prony.iter().map(|t| t.g).sum::<f64>())
    }

    /// The relaxation modulus G(t) after a unit step of shear strain.
    pub fn relaxation_modulus(&self, t: f64) -> f64 {
        let relaxed: f64 = self
            .prony
            .iter()
            .map(|p| p.g * -(-t / p.tau).exp_m1())
            .sum();
        self.shear_modulus() * (1.0 - relaxed)
    }

    /// The instantaneous plane-stress matrix in Voigt form
    /// [τ₁₁, τ₂₂, τ₁₂] = C·[ε₁₁, ε₂₂, 2ε₁₂].
    pub fn plane_stress_matrix(&self) -> Matrix3<f64> {
        let (e, nu) = (self.young, self.poisson);
        let k = e / (1.0 - nu * nu);
        Matrix3::new(
            k,
            k * nu,
            0.0,
            k * nu,
            k,
            0.0,
            0.0,
            0.0,
            self.shear_modulus(),
        )
    }

    /// The shear modulus the update applies over a step of `dt` to a shear
    /// increment: ∂τ̄₁₂/∂(2Δε̄₁₂) = G₀·(1 − Σg_k + Σ g_k·φ(Δt/τ_k)).
    pub fn algorithmic_shear_modulus(&self, dt: f64) -> f64 {
        let g0 = self.shear_modulus();
        let weights: f64 = self
            .prony
            .iter()
            .map(|p| p.g * (ramp_weight(dt / p.tau) - 1.0))
            .sum();
        g0 * (1.0 + weights)
    }

    /// The consistent tangent ∂τ̄ₙ₊₁/∂Δε̄ of [`Self::update_stress`] over a
    /// step `dt`, in the Voigt form of [`Self::plane_stress_matrix`].
    pub fn algorithmic_matrix(&self, dt: f64) -> Matrix3<f64> {
        let mut c = self.plane_stress_matrix();
        c[(2, 2)] = self.algorithmic_shear_modulus(dt);
        c
    }

    /// The elastic update of the normal components τ̄₁₁, τ̄₂₂.
    #[inline]
    fn update_normal(&self, tau_bar: &mut Matrix2<f64>, d_eps: &Matrix2<f64>) {
        let nu = self.poisson;
        let k = self.wave_modulus();
        let (d11, d22) = (d_eps[(0, 0)], d_eps[(1, 1)]);
        tau_bar[(0, 0)] += k * (d11 + nu * d22);
        tau_bar[(1, 1)] += k * (nu * d11 + d22);
    }

    /// Advances the rotated stress τ̄ (symmetric, in the reference local
    /// frame) by the rotated strain increment Δε̄ over a step `dt`.
    ///
    /// `history` holds the point's [s₀, q₁ … q_K] (length
    /// [`Self::history_len`], empty for an elastic resin). The normal
    /// components are elastic; the shear relaxes with the recursive update
    /// of SPEC §4, exact for a strain that varies linearly over the step
    /// (and for a jump, `dt = 0`).
    #[inline]
    pub fn update_stress(
        &self,
        tau_bar: &mut Matrix2<f64>,
        history: &mut [f64],
        d_eps: &Matrix2<f64>,
        dt: f64,
    ) {
        let factors = self.prony.iter().map(|p| {
            let x = dt / p.tau;
            ((-x).exp(), p.g * ramp_weight(x))
        });
        self.advance(tau_bar, history, d_eps, factors);
    }

    /// (e^(−Δt/τₖ), gₖ·φ(Δt/τₖ)) of each Prony term for a step `dt`.
    pub fn prony_factors(&self, dt: f64, out: &mut [(f64, f64)]) {
        for (o, p) in out.iter_mut().zip(&self.prony) {
            let x = dt / p.tau;
            *o = ((-x).exp(), p.g * ramp_weight(x));
        }
    }

    /// [`Self::update_stress`] with the step's Prony factors precomputed
    /// by [`Self::prony_factors`]: they depend on Δt only, so a batch
    /// computes them once per step instead of at every point.
    #[inline]
    pub fn update_stress_with(
        &self,
        tau_bar: &mut Matrix2<f64>,
        history: &mut [f64],
        d_eps: &Matrix2<f64>,
        factors: &[(f64, f64)],
    ) {
        debug_assert_eq!(factors.len(), self.prony.len());
        self.advance(tau_bar, history, d_eps, factors.iter().copied());
    }

    /// The update with each Prony term's (decay, weight) from `factors`.
    #[inline]
    fn advance(
        &self,
        tau_bar: &mut Matrix2<f64>,
        history: &mut [f64],
        d_eps: &Matrix2<f64>,
        factors: impl Iterator<Item = (f64, f64)>,
    ) {
        self.update_normal(tau_bar, d_eps);
        let d_gamma = d_eps[(0, 1)] + d_eps[(1, 0)];
        let d_s0 = self.shear_modulus() * d_gamma;
        let shear = if self.prony.is_empty() {
            tau_bar[(0, 1)] + d_s0
        } else {
            debug_assert_eq!(history.len(), 1 + self.prony.len());
            let (s0, q) = history.split_first_mut().expect("viscoelastic history");
            *s0 += d_s0;
            let mut long_term = 1.0;
            let mut relaxing = 0.0;
            for ((qk, (decay, weight)), p) in q.iter_mut().zip(factors).zip(&self.prony) {
                *qk = decay * *qk + weight * d_s0;
                long_term -= p.g;
                relaxing += *qk;
            }
            long_term * *s0 + relaxing
        };
        tau_bar[(0, 1)] = shear;
        tau_bar[(1, 0)] = shear;
    }

    /// The stress [`Self::update_stress`] would reach, without writing the
    /// history: for trial states (a Newton iteration, a finite difference).
    pub fn stress_after(
        &self,
        tau_bar: &Matrix2<f64>,
        history: &[f64],
        d_eps: &Matrix2<f64>,
        dt: f64,
    ) -> Matrix2<f64> {
        let mut tau = *tau_bar;
        self.update_normal(&mut tau, d_eps);
        if self.prony.is_empty() {
            let shear = tau[(0, 1)] + self.shear_modulus() * (d_eps[(0, 1)] + d_eps[(1, 0)]);
            tau[(0, 1)] = shear;
            tau[(1, 0)] = shear;
            return tau;
        }
        // Only the shear depends on the history: run the update with the
        // history's s₀ and q_k on the stack, term by term.
        let d_s0 = self.shear_modulus() * (d_eps[(0, 1)] + d_eps[(1, 0)]);
        let mut shear = 0.0;
        let mut long_term = 1.0;
        for (qk, p) in history[1..].iter().zip(&self.prony) {
            let x = dt / p.tau;
            shear += (-x).exp() * qk + p.g * ramp_weight(x) * d_s0;
            long_term -= p.g;
        }
        shear += long_term * (history[0] + d_s0);
        tau[(0, 1)] = shear;
        tau[(1, 0)] = shear;
        tau
    }

    /// The elastic energy per unit reference volume stored at stress τ̄ with
    /// the Prony `history`: ½τ̄ₙ:C⁻¹:τ̄ₙ for the normal part, and for the
    /// shear ½(1 − Σg)·s₀²/G₀ + Σ q_k²/(2·g_k·G₀), the energy of the Maxwell
    /// springs (½τ̄₁₂²/G₀ when elastic). What the resin has taken beyond this
    /// was dissipated by relaxation.
    pub fn stored_energy(&self, tau_bar: &Matrix2<f64>, history: &[f64]) -> f64 {
        let (e, nu) = (self.young, self.poisson);
        let (t11, t22) = (tau_bar[(0, 0)], tau_bar[(1, 1)]);
        // The compliance of plane stress: ε₁₁ = (τ₁₁ − ν τ₂₂)/E, …
        let normal = 0.5 * (t11 * t11 + t22 * t22 - 2.0 * nu * t11 * t22) / e;
        let g0 = self.shear_modulus();
        let shear = match history.split_first() {
            None => 0.5 * tau_bar[(0, 1)] * tau_bar[(0, 1)] / g0,
            Some((s0, q)) => {
                let sum_g: f64 = self.prony.iter().map(|p| p.g).sum();
                let springs: f64 = q
                    .iter()
                    .zip(&self.prony)
                    .filter(|(_, p)| p.g > 0.0)
                    .map(|(qk, p)| qk * qk / p.g)
                    .sum();
                0.5 * ((1.0 - sum_g) * s0 * s0 + springs) / g0
            }
        };
        normal + shear
    }

    /// The through-thickness stretch λ₃ of the resin for an area stretch
    /// J = det U, from plane stress: dε₃ = −ν/(1 − ν)·(dε₁₁ + dε₂₂),
    /// integrated as λ₃ = J^(−ν/(1−ν)) **[choice: the elastic relation is used
    /// also when the shear relaxes, since only the shear relaxes]**.
    #[inline]
    pub fn thickness_stretch(&self, area_stretch: f64) -> f64 {
        area_stretch.powf(-self.poisson / (1.0 - self.poisson))
    }

    /// The plane-stress P-wave modulus E/(1 − ν²) that sets the resin's
    /// stable time step.
    #[inline]
    pub fn wave_modulus(&self) -> f64 {
        self.young / (1.0 - self.poisson * self.poisson)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn prony_resin() -> ResinLaw {
        ResinLaw {
            young: 45.0,
            poisson: 0.45,
            prony: vec![
                PronyTerm { g: 0.2, tau: 0.01 },
                PronyTerm { g: 0.3, tau: 1.0 },
                PronyTerm { g: 0.1, tau: 100.0 },
            ],
            shear_locking: None,
        }
    }

    fn shear(gamma_half: f64) -> Matrix2<f64> {
        Matrix2::new(0.0, gamma_half, gamma_half, 0.0)
    }

    proptest! {
        #[test]
        fn step_strain_relaxes_exactly_at_any_step_size(
            gamma in 1e-4f64..0.1,
            dt in 1e-4f64..50.0,
            steps in 1usize..200,
        ) {
            let law = prony_resin();
            let mut tau = Matrix2::zeros();
            let mut h = vec![0.0; law.history_len()];
            // The jump happens in no time, then the strain is held.
            law.update_stress(&mut tau, &mut h, &shear(gamma / 2.0), 0.0);
            for _ in 0..steps {
                law.update_stress(&mut tau, &mut h, &Matrix2::zeros(), dt);
            }
            let t = dt * steps as f64;
            let exact = law.relaxation_modulus(t) * gamma;
            prop_assert!((tau[(0, 1)] - exact).abs() <= 1e-13 * law.shear_modulus() * gamma,
                "t = {t}: {} vs {exact}", tau[(0, 1)]);
            prop_assert_eq!(tau[(0, 1)], tau[(1, 0)]);
        }

        #[test]
        fn constant_rate_matches_the_hereditary_integral_at_any_step_size(
            rate in 1e-3f64..1.0,
            dt in 1e-4f64..2.0,
            steps in 1usize..200,
        ) {
            let law = prony_resin();
            let mut tau = Matrix2::zeros();
            let mut h = vec![0.0; law.history_len()];
            for _ in 0..steps {
                law.update_stress(&mut tau, &mut h, &shear(rate * dt / 2.0), dt);
            }
            let t = dt * steps as f64;
            // ∫₀ᵗ G(t − s)·γ̇ ds for γ̇ constant.
            let g: f64 = law.prony.iter().map(|p| p.g).sum();
            let exact = law.shear_modulus() * rate
                * ((1.0 - g) * t + law.prony.iter().map(|p| p.g * p.tau * -(-t / p.tau).exp_m1()).sum::<f64>());
            prop_assert!((tau[(0, 1)] - exact).abs() <= 1e-12 * law.shear_modulus() * rate * t,
                "{} vs {exact}", tau[(0, 1)]);
        }

        #[test]
        fn algorithmic_tangent_is_the_derivative_of_the_update(
            e11 in -0.01f64..0.01, e22 in -0.01f64..0.01, e12 in -0.01f64..0.01,
            dt in 0.0f64..10.0,
            q0 in -1.0f64..1.0,
        ) {
            let law = prony_resin();
            let base_tau = Matrix2::new(0.3, -0.2, -0.2, 0.1);
            let base_h = vec![0.5, q0, -0.3 * q0, 0.1];
            let d = Matrix2::new(e11, e12, e12, e22);
            let update = |d: &Matrix2<f64>| {
                let (mut t, mut h) = (base_tau, base_h.clone());
                law.update_stress(&mut t, &mut h, d, dt);
                nalgebra::Vector3::new(t[(0, 0)], t[(1, 1)], t[(0, 1)])
            };
            let c = law.algorithmic_matrix(dt);
            // The update is affine in Δε̄, so a finite difference is exact up to round-off.
            let dirs = [Matrix2::new(1.0, 0.0, 0.0, 0.0), Matrix2::new(0.0, 0.0, 0.0, 1.0), Matrix2::new(0.0, 0.5, 0.5, 0.0)];
            for (j, dir) in dirs.iter().enumerate() {
                let h = 1e-4;
                let fd = (update(&(d + dir * h)) - update(&(d - dir * h))) / (2.0 * h);
                prop_assert!((fd - c.column(j)).norm() <= 1e-8 * c.norm());
            }
        }
    }

    #[test]
    fn trial_stress_equals_the_committed_update() {
        for law in [prony_resin(), ResinLaw::elastic(30.0, 0.41).unwrap()] {
            let tau0 = Matrix2::new(0.3, -0.2, -0.2, 0.1);
            let mut h = vec![0.5, 0.1, -0.03, 0.1];
            h.truncate(law.history_len());
            let d = Matrix2::new(1e-3, -4e-4, -4e-4, 2e-4);
            let trial = law.stress_after(&tau0, &h, &d, 0.3);
            let mut tau = tau0;
            law.update_stress(&mut tau, &mut h, &d, 0.3);
            assert!((trial - tau).norm() <= 1e-15 * tau.norm());
        }
    }

    #[test]
    fn precomputed_prony_factors_give_the_same_update_bit_for_bit() {
        let law = prony_resin();
        let d = Matrix2::new(1e-3, -4e-4, -4e-4, 2e-4);
        let (mut a, mut b) = (
            Matrix2::new(0.3, -0.2, -0.2, 0.1),
            Matrix2::new(0.3, -0.2, -0.2, 0.1),
        );
        let (mut ha, mut hb) = (vec![0.5, 0.1, -0.03, 0.1], vec![0.5, 0.1, -0.03, 0.1]);
        let mut factors = vec![(0.0, 0.0); law.prony.len()];
        law.prony_factors(0.37, &mut factors);
        law.update_stress(&mut a, &mut ha, &d, 0.37);
        law.update_stress_with(&mut b, &mut hb, &d, &factors);
        assert_eq!(a, b);
        assert_eq!(ha, hb);
    }

    #[test]
    fn elastic_resin_skips_history_and_uses_plane_stress() {
        let law = ResinLaw::elastic(30.0, 0.41).unwrap();
        assert_eq!(law.history_len(), 0);
        assert!(!law.is_viscoelastic());
        let mut tau = Matrix2::zeros();
        let d = Matrix2::new(1e-3, 2e-4, 2e-4, -5e-4);
        law.update_stress(&mut tau, &mut [], &d, 1.0);
        let c = law.plane_stress_matrix();
        let expected = c * nalgebra::Vector3::new(1e-3, -5e-4, 4e-4);
        assert!((tau[(0, 0)] - expected[0]).abs() < 1e-15);
        assert!((tau[(1, 1)] - expected[1]).abs() < 1e-15);
        assert!((tau[(0, 1)] - expected[2]).abs() < 1e-15);
        // Uniaxial stress: τ₂₂ = 0 when ε₂₂ = −ν ε₁₁, and τ₁₁ = E ε₁₁.
        let mut tau = Matrix2::zeros();
        law.update_stress(
            &mut tau,
            &mut [],
            &Matrix2::new(1e-3, 0.0, 0.0, -0.41e-3),
            1.0,
        );
        assert!(tau[(1, 1)].abs() < 1e-15);
        assert!((tau[(0, 0)] - 30.0e-3).abs() < 1e-15);
    }

    #[test]
    fn instantaneous_and_long_term_moduli() {
        let law = prony_resin();
        let g0 = 45.0 / 2.9;
        assert!((law.shear_modulus() - g0).abs() < 1e-14);
        assert!((law.relaxation_modulus(0.0) - g0).abs() < 1e-14);
        assert!((law.long_term_shear_modulus() - 0.4 * g0).abs() < 1e-14);
        assert!((law.relaxation_modulus(1e6) - 0.4 * g0).abs() < 1e-13);
        assert_eq!(law.algorithmic_shear_modulus(0.0), g0);
        // A very slow step sees only the long-term modulus.
        assert!((law.algorithmic_shear_modulus(1e12) - 0.4 * g0).abs() < 1e-9);
    }

    #[test]
    fn stored_energy_is_the_work_of_an_elastic_path_and_drops_by_relaxation() {
        // Elastic: the work of a proportional path equals the stored energy.
        let law = ResinLaw::elastic(30.0, 0.3).unwrap();
        let total = Matrix2::new(2e-3, 1e-3, 1e-3, -1e-3);
        let (mut tau, mut work) = (Matrix2::zeros(), 0.0);
        let n = 1000;
        for _ in 0..n {
            let before = tau;
            law.update_stress(&mut tau, &mut [], &(total / n as f64), 0.0);
            work += ((before + tau) * 0.5)
                .component_mul(&(total / n as f64))
                .sum();
        }
        assert!((law.stored_energy(&tau, &[]) - work).abs() < 1e-12 * work);
        // Viscoelastic: a held shear loses stored energy to the dashpots.
        let law = prony_resin();
        let mut tau = Matrix2::zeros();
        let mut h = vec![0.0; law.history_len()];
        law.update_stress(&mut tau, &mut h, &shear(0.005), 0.0);
        let g0 = law.shear_modulus();
        let e0 = law.stored_energy(&tau, &h);
        assert!((e0 - 0.5 * g0 * 0.01 * 0.01).abs() < 1e-15);
        law.update_stress(&mut tau, &mut h, &Matrix2::zeros(), 1.0);
        assert!(law.stored_energy(&tau, &h) < e0);
    }

    #[test]
    fn thickness_follows_plane_stress() {
        let law = ResinLaw::elastic(30.0, 0.25).unwrap();
        // ν/(1 − ν) = 1/3.
        assert!((law.thickness_stretch(8.0) - 0.5).abs() < 1e-15);
        assert_eq!(law.thickness_stretch(1.0), 1.0);
    }

    #[test]
    fn invalid_parameters_are_named() {
        let bad = |law: ResinLaw, field: &str| {
            let err = law.validate("resin").unwrap_err();
            assert_eq!(err.field, field, "{err}");
        };
        let ok = prony_resin();
        bad(
            ResinLaw {
                young: 0.0,
                ..ok.clone()
            },
            "resin.young",
        );
        bad(
            ResinLaw {
                poisson: 0.5,
                ..ok.clone()
            },
            "resin.poisson",
        );
        bad(
            ResinLaw {
                poisson: -1.0,
                ..ok.clone()
            },
            "resin.poisson",
        );
        let mut l = ok.clone();
        l.prony[1].tau = 0.0;
        bad(l, "resin.prony[1].tau");
        let mut l = ok.clone();
        l.prony[2].g = -0.1;
        bad(l, "resin.prony[2].g");
        let mut l = ok.clone();
        l.prony[2].g = 0.5;
        bad(l, "resin.prony");
        assert!(ok.validate("resin").is_ok());
    }
}
