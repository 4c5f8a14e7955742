//! A non-linear in-plane shear law (shear locking), and its fit from a
//! picture-frame test (SPEC §4 "Beyond the paper").
//!
//! A woven fabric shears freely until its yarns jam against each other
//! (the locking angle, typically 40–60°), then stiffens steeply. Labs
//! publish this as a picture-frame curve, frame force against shear angle,
//! usually fitted by an odd polynomial. drape takes the law in that form:
//!
//! τ_s(γ) = c₁·γ + c₃·γ³ + c₅·γ⁵ + …  (MPa, γ in radians),
//!
//! the shear stress that does work on the shear angle: the fabric stores
//! h·w(γ) per unit reference area, w(γ) = ∫₀^γ τ_s dγ, h the fabric's
//! thickness. It is hyperelastic in γ (no history), superposed on the
//! resin's hypo-elastic membrane, so the resin's own linear shear still
//! acts: a card fitted from a test of the whole fabric should give the
//! resin a small modulus, or accept it as a small linear addition.
//!
//! Picture frame of side L: the frame's diagonal D = 2L·cos(π/4 − γ/2)
//! grows by dD = L·sin(π/4 − γ/2)·dγ, so the frame force
//! F(γ) = h·L·τ_s(γ)/sin(π/4 − γ/2) (energy balance, ideal pin-jointed
//! kinematics). [`ShearLocking::fit_picture_frame`] inverts this and fits
//! the coefficients by linear least squares.
//!
//! What it is not: no rate dependence (the resin's Prony series does that),
//! no coupling with yarn tension.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::MaterialError;

/// Largest shear angle (radians) at which a law must still stiffen:
/// 85°, beyond any fabric's locking angle.
const CHECKED_RANGE: f64 = 85.0 * std::f64::consts::PI / 180.0;

/// The non-linear in-plane shear law τ_s(γ) = Σₖ cₖ·γ^(2k+1), plus an
/// optional friction term τ_f·tanh(γ/γ_f).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShearLocking {
    /// [c₁, c₃, c₅, …] (MPa, γ in radians).
    pub coefficients: Vec<f64>,
    /// The friction term τ_f·tanh(γ/γ_f), [τ_f (MPa), γ_f (rad)], or none.
    ///
    /// Why: a dry fabric's bias-extension force jumps to about 1 N within
    /// 5° and then rises slowly (the benchmark's Twintex, Cao et al. 2008):
    /// the yarns' crossovers resist rotation by friction before the yarns
    /// turn at all. No odd polynomial through zero follows that shape (the
    /// three-zone fit misses the labs' range at 21 of 25 points up to 30°);
    /// a stiff start that saturates at τ_f after a few γ_f does. It is
    /// elastic (energy τ_f·γ_f·ln cosh(γ/γ_f)), so it holds for loading,
    /// not for the hysteresis of true friction on unloading.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<[f64; 2]>,
}

/// A picture-frame curve that cannot be read or fitted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FitError {
    /// A line of the CSV is not two numbers.
    #[error("line {line}: {message}")]
    Line {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The data cannot determine the law.
    #[error("{0}")]
    Data(String),
}

impl ShearLocking {
    /// A polynomial law without the friction term.
    pub fn polynomial(coefficients: Vec<f64>) -> Self {
        Self {
            coefficients,
            friction: None,
        }
    }

    /// τ_s(γ) (MPa).
    #[inline]
    pub fn stress(&self, gamma: f64) -> f64 {
        let g2 = gamma * gamma;
        let poly = self
            .coefficients
            .iter()
            .rev()
            .fold(0.0, |acc, c| acc * g2 + c)
            * gamma;
        match self.friction {
            Some([tau, g0]) => poly + tau * (gamma / g0).tanh(),
            None => poly,
        }
    }

    /// dτ_s/dγ (MPa).
    #[inline]
    pub fn tangent(&self, gamma: f64) -> f64 {
        let g2 = gamma * gamma;
        let mut power = 1.0;
        let mut sum = 0.0;
        for (k, c) in self.coefficients.iter().enumerate() {
            sum += (2 * k + 1) as f64 * c * power;
            power *= g2;
        }
        match self.friction {
            Some([tau, g0]) => {
                let t = (gamma / g0).tanh();
                sum + tau / g0 * (1.0 - t * t)
            }
            None => sum,
        }
    }

    /// w(γ) = ∫₀^γ τ_s dγ (MPa = N·mm/mm³).
    #[inline]
    pub fn energy(&self, gamma: f64) -> f64 {
        let g2 = gamma * gamma;
        let mut power = g2;
        let mut sum = 0.0;
        for (k, c) in self.coefficients.iter().enumerate() {
            sum += c * power / (2 * k + 2) as f64;
            power *= g2;
        }
        match self.friction {
            // ln cosh x = |x| + ln(1 + e^(−2|x|)) − ln 2, without overflow.
            Some([tau, g0]) => {
                let x = (gamma / g0).abs();
                sum + tau * g0 * (x + (-2.0 * x).exp().ln_1p() - std::f64::consts::LN_2)
            }
            None => sum,
        }
    }

    /// The picture-frame force F = h·L·τ_s(γ)/sin(π/4 − γ/2) (N) of a
    /// frame of side `side` on a fabric of thickness `thickness`.
    pub fn frame_force(&self, gamma: f64, side: f64, thickness: f64) -> f64 {
        thickness * side * self.stress(gamma) / (std::f64::consts::FRAC_PI_4 - 0.5 * gamma).sin()
    }

    /// Checks the law: at least one finite coefficient, and a tangent
    /// dτ_s/dγ ≥ 0 from 0 to 85° (a softening fabric would make the
    /// membrane unstable).
    pub fn validate(&self, path: &str) -> Result<(), MaterialError> {
        let field = |f: &str| {
            if path.is_empty() {
                f.to_owned()
            } else {
                format!("{path}.{f}")
            }
        };
        if self.coefficients.is_empty() {
            return Err(MaterialError {
                field: field("coefficients"),
                value: 0.0,
                expected: "at least one coefficient [c₁, c₃, …] (MPa)",
            });
        }
        for (k, c) in self.coefficients.iter().enumerate() {
            MaterialError::check(
                path,
                &format!("coefficients[{k}]"),
                *c,
                true,
                "a finite coefficient (MPa)",
            )?;
        }
        if let Some([tau, g0]) = self.friction {
            MaterialError::check(
                path,
                "friction[0]",
                tau,
                tau >= 0.0,
                "a friction stress τ_f ≥ 0 (MPa)",
            )?;
            MaterialError::check_positive(path, "friction[1]", g0)?;
        }
        for n in 0..=170 {
            let gamma = CHECKED_RANGE * n as f64 / 170.0;
            let t = self.tangent(gamma);
            if t.is_nan() || t < 0.0 {
                return Err(MaterialError {
                    field: field("coefficients"),
                    value: t,
                    expected: "a law whose tangent dτ/dγ stays ≥ 0 from 0 to 85° (the value is the \
                               tangent where it first fails)",
                });
            }
        }
        Ok(())
    }

    /// Reads a picture-frame curve: one `shear angle (degrees), force (N)`
    /// pair per line, comma- or whitespace-separated; blank lines, `#`
    /// comments and a first line that is not numeric (a header) are
    /// skipped.
    pub fn read_picture_frame_csv(text: &str) -> Result<Vec<[f64; 2]>, FitError> {
        let mut points = Vec::new();
        for (n, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let fields: Vec<&str> = line
                .split(|c: char| c == ',' || c == ';' || c.is_whitespace())
                .filter(|f| !f.is_empty())
                .collect();
            let numbers: Result<Vec<f64>, _> = fields.iter().map(|f| f.parse::<f64>()).collect();
            match numbers {
                Ok(v) if v.len() == 2 && v.iter().all(|x| x.is_finite()) => {
                    points.push([v[0], v[1]])
                }
                Err(_) if points.is_empty() && n == 0 => continue,
                _ => {
                    return Err(FitError::Line {
                        line: n + 1,
                        message: format!(
                            "expected `shear angle (deg), force (N)`, two finite numbers; found `{line}`"
                        ),
                    });
                }
            }
        }
        Ok(points)
    }

    /// Fits `terms` coefficients [c₁, c₃, …] to a picture-frame curve
    /// `points` = [shear angle (degrees), frame force (N)] of a frame of
    /// side `side` (mm) on a fabric of thickness `thickness` (mm): each
    /// point gives τ_s(γ) = F·sin(π/4 − γ/2)/(h·L), and the odd polynomial
    /// is the linear least-squares fit of those stresses (by SVD).
    pub fn fit_picture_frame(
        points: &[[f64; 2]],
        side: f64,
        thickness: f64,
        terms: usize,
    ) -> Result<Self, FitError> {
        if !(side > 0.0 && side.is_finite() && thickness > 0.0 && thickness.is_finite()) {
            return Err(FitError::Data(format!(
                "the frame side ({side}) and the fabric thickness ({thickness}) must be positive"
            )));
        }
        if terms == 0 || points.len() < terms {
            return Err(FitError::Data(format!(
                "{} points cannot determine {terms} coefficients: give more points than terms",
                points.len()
            )));
        }
        if let Some((i, p)) = points
            .iter()
            .enumerate()
            .find(|(_, p)| !(p[0] > 0.0 && p[0] < 90.0))
        {
            return Err(FitError::Data(format!(
                "point {} has shear angle {}°: expected an angle in (0°, 90°)",
                i + 1,
                p[0]
            )));
        }
        let samples: Vec<[f64; 3]> = points
            .iter()
            .map(|p| {
                let gamma = p[0].to_radians();
                let tau =
                    p[1] * (std::f64::consts::FRAC_PI_4 - 0.5 * gamma).sin() / (thickness * side);
                [gamma, tau, 1.0]
            })
            .collect();
        Self::fit_stresses(&samples, terms)
    }

    /// Fits `terms` coefficients [c₁, c₃, …] to `samples` = [γ (radians),
    /// τ_s (MPa), weight ≥ 0] by weighted linear least squares (by SVD):
    /// each sample's residual counts with the square root of its weight,
    /// so a weight is how many equal points the sample stands for. The
    /// common core of every fit from a test (picture frame with any
    /// frame and fabric sizes, several curves at once).
    pub fn fit_stresses(samples: &[[f64; 3]], terms: usize) -> Result<Self, FitError> {
        let used = samples.iter().filter(|s| s[2] > 0.0).count();
        if terms == 0 || used < terms {
            return Err(FitError::Data(format!(
                "{used} points cannot determine {terms} coefficients: give more points than terms"
            )));
        }
        if let Some(s) = samples
            .iter()
            .find(|s| !(s.iter().all(|v| v.is_finite()) && s[0] > 0.0 && s[2] >= 0.0))
        {
            return Err(FitError::Data(format!(
                "sample (γ = {} rad, τ = {} MPa, weight {}): expected finite values, γ > 0 \
                 and a weight ≥ 0",
                s[0], s[1], s[2]
            )));
        }
        let rows = samples.len();
        let mut a = DMatrix::zeros(rows, terms);
        let mut b = DVector::zeros(rows);
        // Scale columns so the SVD sees comparable magnitudes.
        let gamma_max = samples.iter().map(|s| s[0]).fold(0.0, f64::max);
        for (r, s) in samples.iter().enumerate() {
            let w = s[2].sqrt();
            b[r] = w * s[1];
            for k in 0..terms {
                a[(r, k)] = w * (s[0] / gamma_max).powi(2 * k as i32 + 1);
            }
        }
        let svd = a.svd(true, true);
        let x = svd
            .solve(&b, 1e-12)
            .map_err(|e| FitError::Data(format!("least squares failed: {e}")))?;
        let coefficients = (0..terms)
            .map(|k| x[k] / gamma_max.powi(2 * k as i32 + 1))
            .collect();
        Ok(Self::polynomial(coefficients))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law() -> ShearLocking {
        // A published-style curve: soft to ~40°, locking beyond.
        ShearLocking {
            coefficients: vec![0.02, -0.01, 0.12],
            friction: None,
        }
    }

    #[test]
    fn tangent_and_energy_are_the_derivative_and_integral_of_the_stress() {
        let l = law();
        for gamma in [0.0, 0.2, 0.7, 1.1] {
            let h = 1e-6;
            let fd = (l.stress(gamma + h) - l.stress(gamma - h)) / (2.0 * h);
            assert!(
                (fd - l.tangent(gamma)).abs() < 1e-8,
                "{fd} vs {}",
                l.tangent(gamma)
            );
            let fd = (l.energy(gamma + h) - l.energy(gamma - h)) / (2.0 * h);
            assert!((fd - l.stress(gamma)).abs() < 1e-8);
        }
        // τ = 0.02γ − 0.01γ³ + 0.12γ⁵ at γ = 0.5.
        let s = 0.02 * 0.5 - 0.01 * 0.125 + 0.12 * 0.03125;
        assert!((l.stress(0.5) - s).abs() < 1e-16);
        l.validate("resin.shear_locking").unwrap();
    }

    /// The friction term's tangent and energy are its stress's derivative
    /// and integral, from γ = 0 to far past γ_f (where ln cosh must not
    /// overflow), and it is odd.
    #[test]
    fn the_friction_term_is_consistent() {
        let mut l = law();
        l.friction = Some([0.003, 0.02]);
        l.validate("x").unwrap();
        for gamma in [0.0, 0.01, 0.02, 0.05, 0.7, 30.0] {
            let h = 1e-7;
            let fd = (l.stress(gamma + h) - l.stress(gamma - h)) / (2.0 * h);
            let t = l.tangent(gamma);
            assert!(
                (fd - t).abs() < 1e-6 * t.abs().max(1.0),
                "{gamma}: {fd} vs {t}"
            );
            let fd = (l.energy(gamma + h) - l.energy(gamma - h)) / (2.0 * h);
            let s = l.stress(gamma);
            assert!(
                (fd - s).abs() < 1e-6 * s.abs().max(1.0),
                "{gamma}: {fd} vs {s}"
            );
            assert_eq!(l.stress(-gamma), -l.stress(gamma));
        }
        // Far past γ_f the term is τ_f: τ(0.7) − polynomial = 0.003.
        let poly = ShearLocking::polynomial(l.coefficients.clone());
        assert!((l.stress(0.7) - poly.stress(0.7) - 0.003).abs() < 1e-15);
        assert!(l.energy(0.0).abs() < 1e-18);
        let mut bad = l.clone();
        bad.friction = Some([-1e-3, 0.02]);
        assert_eq!(bad.validate("r").unwrap_err().field, "r.friction[0]");
        bad.friction = Some([1e-3, 0.0]);
        assert_eq!(bad.validate("r").unwrap_err().field, "r.friction[1]");
    }

    #[test]
    fn a_softening_or_empty_law_is_refused_by_field() {
        let soft = ShearLocking {
            coefficients: vec![0.02, -0.1],
            friction: None,
        };
        let err = soft.validate("resin.shear_locking").unwrap_err();
        assert_eq!(err.field, "resin.shear_locking.coefficients");
        let empty = ShearLocking {
            coefficients: vec![],
            friction: None,
        };
        assert!(empty.validate("x").is_err());
        let nan = ShearLocking {
            coefficients: vec![f64::NAN],
            friction: None,
        };
        assert_eq!(nan.validate("r").unwrap_err().field, "r.coefficients[0]");
    }

    /// A curve in the form labs publish (force every 2° to 60° on a
    /// 150 mm frame, four significant digits) gives back its law.
    #[test]
    fn the_fit_of_a_published_style_curve_returns_its_parameters() {
        let l = law();
        let (side, h) = (150.0, 0.57);
        let mut csv = String::from("shear angle (deg), force (N)\n");
        for n in 1..=30 {
            let deg = 2.0 * n as f64;
            let f = l.frame_force(f64::to_radians(deg), side, h);
            csv.push_str(&format!("{deg}, {f:.4e}\n"));
        }
        let points = ShearLocking::read_picture_frame_csv(&csv).unwrap();
        assert_eq!(points.len(), 30);
        let fit = ShearLocking::fit_picture_frame(&points, side, h, 3).unwrap();
        for (a, b) in fit.coefficients.iter().zip(&l.coefficients) {
            // Four digits of force: the coefficients to about 1e-3 of c₅.
            assert!(
                (a - b).abs() < 2e-4,
                "{:?} vs {:?}",
                fit.coefficients,
                l.coefficients
            );
        }
        // Exact data: exact parameters.
        let exact: Vec<[f64; 2]> = (1..=30)
            .map(|n| {
                let deg = 2.0 * n as f64;
                [deg, l.frame_force(deg.to_radians(), side, h)]
            })
            .collect();
        let fit = ShearLocking::fit_picture_frame(&exact, side, h, 3).unwrap();
        for (a, b) in fit.coefficients.iter().zip(&l.coefficients) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
    }

    #[test]
    fn bad_curves_name_the_line_or_the_problem() {
        let err = ShearLocking::read_picture_frame_csv("gamma,F\n10, 1.0\n20, x\n").unwrap_err();
        assert_eq!(
            err.to_string(),
            "line 3: expected `shear angle (deg), force (N)`, two finite numbers; found `20, x`"
        );
        assert!(ShearLocking::read_picture_frame_csv("10, 1, 2\n").is_err());
        let few = [[10.0, 1.0], [20.0, 2.0]];
        assert!(ShearLocking::fit_picture_frame(&few, 150.0, 0.5, 3).is_err());
        let wide = [[10.0, 1.0], [95.0, 2.0], [30.0, 3.0]];
        assert!(ShearLocking::fit_picture_frame(&wide, 150.0, 0.5, 1).is_err());
    }

    /// Two curves of different laws: equal weights fit between them, a
    /// weight of 3 on one pulls the fit to the weighted mean of the two
    /// (a one-term law is linear in c₁, so the weighted fit is exactly the
    /// weighted mean of the two single fits); a zero weight removes a curve.
    #[test]
    fn weights_count_as_repeated_points() {
        let g: Vec<f64> = (1..=10).map(|n| 0.05 * n as f64).collect();
        let mut samples = Vec::new();
        for &x in &g {
            samples.push([x, 0.02 * x, 3.0]);
            samples.push([x, 0.06 * x, 1.0]);
        }
        let fit = ShearLocking::fit_stresses(&samples, 1).unwrap();
        assert!((fit.coefficients[0] - 0.03).abs() < 1e-14, "{fit:?}");
        for s in samples.iter_mut().filter(|s| s[2] == 1.0) {
            s[2] = 0.0;
        }
        let fit = ShearLocking::fit_stresses(&samples, 1).unwrap();
        assert!((fit.coefficients[0] - 0.02).abs() < 1e-14, "{fit:?}");
        assert!(ShearLocking::fit_stresses(&[[0.1, f64::NAN, 1.0]], 1).is_err());
    }
}
