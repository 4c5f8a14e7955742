//! Validation of `drape-kinematics` (SPEC §3): the polar decomposition
//! against exact constructions and nalgebra's SVD, objectivity under rigid
//! rotations, the shear angle of pure shear (trellising), uniaxial stretch,
//! and the order of the midpoint strain-increment integration.
//!
//! Round-off budget: every sampled F has principal stretches in [0.5, 2]
//! (condition number ≤ 4), so a closed form of a handful of operations is
//! good to ~10⁻¹⁵; 10⁻¹³ is stated for those.
//!
//! nalgebra's SVD is the less accurate side of the SVD comparison: its own
//! backward error ‖F − W·Σ·Vᵀ‖ reaches ~2·10⁻¹² on these F. W·Vᵀ and V·Σ·Vᵀ
//! are the exact polar factors of W·Σ·Vᵀ, so by first-order perturbation of
//! the polar decomposition (‖ΔR‖ ≤ ‖ΔF‖/σ₂, ‖ΔU‖ ≤ √2·‖ΔF‖, Frobenius)
//! the agreement is checked against twice those bounds of the SVD's own
//! measured error, plus drape's 10⁻¹³; the SVD's error itself is bounded
//! at 10⁻¹¹ so that the comparison stays meaningful.

use drape_constitutive::Material;
use drape_kinematics::{
    Matrix2, Matrix3x2, Vector2, Vector3, fibre_stretch, first_piola, polar_decomposition,
    rotated_strain_increment, shear_angle, truss_stretch,
};
use nalgebra::{Matrix3, Rotation3, Unit, UnitQuaternion};

use super::{Case, Check, Rng};

/// This crate's cases.
pub const CASES: &[Case] = &[
    Case {
        name: "kinematics/polar-decomposition",
        quick: true,
        run: polar,
    },
    Case {
        name: "kinematics/rigid-rotation",
        quick: true,
        run: rigid_rotation,
    },
    Case {
        name: "kinematics/pure-shear",
        quick: true,
        run: pure_shear,
    },
    Case {
        name: "kinematics/uniaxial-stretch",
        quick: true,
        run: uniaxial,
    },
    Case {
        name: "kinematics/strain-increment-order",
        quick: true,
        run: strain_increment_order,
    },
];

const ROUND_OFF: f64 = 1e-13;
/// The largest backward error of the reference SVD that keeps the
/// comparison with it meaningful.
const SVD_RESIDUAL: f64 = 1e-11;
const SAMPLES: usize = 2000;

/// The reference local plane embedded in 3D: columns e_x, e_y.
fn embed() -> Matrix3x2<f64> {
    Matrix3x2::new(1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
}

fn rot2(phi: f64) -> Matrix2<f64> {
    let (s, c) = phi.sin_cos();
    Matrix2::new(c, -s, s, c)
}

/// A uniformly random rotation (normalised quaternion of a sample of the
/// unit ball, rejecting the tiny ones whose direction is noise).
fn random_rotation(rng: &mut Rng) -> Matrix3<f64> {
    loop {
        let q = nalgebra::Quaternion::new(
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        );
        let n = q.norm();
        if n > 0.1 && n <= 1.0 {
            return *UnitQuaternion::from_quaternion(q)
                .to_rotation_matrix()
                .matrix();
        }
    }
}

/// A well-conditioned F with its exact polar factors: F = Q·E·U with
/// U = P·diag(λ₁, λ₂)·Pᵀ, λ in [0.5, 2]. Any rank-2 3×2 F with those
/// principal stretches is of this form, and then R = Q·E exactly.
struct Sample {
    f: Matrix3x2<f64>,
    r: Matrix3x2<f64>,
    u: Matrix2<f64>,
    q: Matrix3<f64>,
}

fn sample(rng: &mut Rng) -> Sample {
    let (l1, l2) = (rng.uniform(0.5, 2.0), rng.uniform(0.5, 2.0));
    let p = rot2(rng.uniform(-std::f64::consts::PI, std::f64::consts::PI));
    let u = p * Matrix2::new(l1, 0.0, 0.0, l2) * p.transpose();
    let q = random_rotation(rng);
    let r = q * embed();
    Sample { f: r * u, r, u, q }
}

fn polar() -> Vec<Check> {
    let mut rng = Rng::new(0x5eed_0001);
    let (mut residual, mut orthonormality, mut r_exact, mut u_exact) = (0f64, 0f64, 0f64, 0f64);
    let (mut r_svd, mut u_svd, mut svd_residual, mut normal, mut inverse) =
        (0f64, 0f64, 0f64, 0f64, 0f64);
    for _ in 0..SAMPLES {
        let s = sample(&mut rng);
        let p = polar_decomposition(&s.f).expect("well-conditioned F");
        residual = residual.max((s.f - p.r * p.u).norm() / s.f.norm());
        orthonormality = orthonormality.max((p.r.tr_mul(&p.r) - Matrix2::identity()).norm());
        r_exact = r_exact.max((p.r - s.r).norm());
        u_exact = u_exact.max((p.u - s.u).norm() / s.u.norm());
        inverse = inverse.max((p.u * p.u_inv - Matrix2::identity()).norm());
        normal = normal.max((p.normal() - s.q * Vector3::z()).norm());
        // The polar factors from the SVD F = W·Σ·Vᵀ: R = W·Vᵀ, U = V·Σ·Vᵀ.
        let svd = s.f.svd(true, true);
        let (w, vt) = (svd.u.expect("W"), svd.v_t.expect("Vᵀ"));
        let sigma = Matrix2::from_diagonal(&svd.singular_values);
        let backward = (s.f - w * sigma * vt).norm();
        svd_residual = svd_residual.max(backward / s.f.norm());
        let sigma_min = svd.singular_values.min();
        let r_bound = ROUND_OFF + 2.0 * backward / sigma_min;
        r_svd = r_svd.max((p.r - w * vt).norm() / r_bound);
        let u_from_svd = vt.transpose() * sigma * vt;
        let u_bound = ROUND_OFF * p.u.norm() + 2.0 * std::f64::consts::SQRT_2 * backward;
        u_svd = u_svd.max((p.u - u_from_svd).norm() / u_bound);
    }
    let n = SAMPLES;
    vec![
        Check::abs(
            format!("max ‖F − R·U‖/‖F‖, {n} random F"),
            0.0,
            residual,
            ROUND_OFF,
        ),
        Check::abs(
            format!("max ‖RᵀR − I‖, {n} random F"),
            0.0,
            orthonormality,
            ROUND_OFF,
        ),
        Check::abs(
            format!("max ‖R − R_exact‖, {n} random F"),
            0.0,
            r_exact,
            ROUND_OFF,
        ),
        Check::abs(
            format!("max ‖U − U_exact‖/‖U‖, {n} random F"),
            0.0,
            u_exact,
            ROUND_OFF,
        ),
        Check::abs(
            format!("max ‖U·U⁻¹ − I‖, {n} random F"),
            0.0,
            inverse,
            ROUND_OFF,
        ),
        Check::abs(
            format!("max ‖r₁×r₂ − Q·e_z‖, {n} random F"),
            0.0,
            normal,
            ROUND_OFF,
        ),
        Check::abs(
            format!("SVD: max ‖F − W·Σ·Vᵀ‖/‖F‖ (reference's own error), {n} F"),
            0.0,
            svd_residual,
            SVD_RESIDUAL,
        ),
        Check::abs(
            format!("SVD: max ‖R − W·Vᵀ‖ ÷ (2‖ΔF_svd‖/σ₂ + 10⁻¹³) ≤ 1, {n} F"),
            0.0,
            r_svd,
            1.0,
        ),
        Check::abs(
            format!("SVD: max ‖U − V·Σ·Vᵀ‖ ÷ (2√2‖ΔF_svd‖ + 10⁻¹³‖U‖) ≤ 1, {n} F"),
            0.0,
            u_svd,
            1.0,
        ),
    ]
}

fn rigid_rotation() -> Vec<Check> {
    let mut rng = Rng::new(0x5eed_0002);
    let resin = Material::preset("glass-serge-4x3").expect("preset").resin;
    let (mut du, mut d_eps, mut dr, mut dp) = (0f64, 0f64, 0f64, 0f64);
    let (mut u_identity, mut d_eps_rigid, mut d_tau) = (0f64, 0f64, 0f64);
    for _ in 0..SAMPLES {
        let s = sample(&mut rng);
        let q = random_rotation(&mut rng);
        let before = polar_decomposition(&s.f).expect("well-conditioned F");
        let after = polar_decomposition(&(q * s.f)).expect("well-conditioned F");
        du = du.max((after.u - before.u).norm() / before.u.norm());
        let increment = rotated_strain_increment(&before.u, &after.u);
        d_eps = d_eps.max(increment.norm());
        dr = dr.max((after.r - q * before.r).norm());
        let (t11, t22, t12) = (
            rng.uniform(-10.0, 10.0),
            rng.uniform(-10.0, 10.0),
            rng.uniform(-10.0, 10.0),
        );
        let tau = Matrix2::new(t11, t12, t12, t22);
        let p0 = first_piola(&before.r, &tau, &before.u_inv);
        let p1 = first_piola(&after.r, &tau, &after.u_inv);
        dp = dp.max((p1 - q * p0).norm() / p0.norm());
        // The resin sees the increment of the rotation: its stress must not move.
        let mut tau_next = tau;
        resin.update_stress(&mut tau_next, &mut [], &increment, 1e-3);
        d_tau = d_tau.max((tau_next - tau).norm() / resin.young);

        // A rigid rotation of the reference state.
        let rigid = polar_decomposition(&(q * embed())).expect("rotation");
        u_identity = u_identity.max((rigid.u - Matrix2::identity()).norm());
        d_eps_rigid =
            d_eps_rigid.max(rotated_strain_increment(&Matrix2::identity(), &rigid.u).norm());
    }
    let n = SAMPLES;
    vec![
        Check::abs(
            format!("max ‖U − I‖, F = Q·E, {n} random Q"),
            0.0,
            u_identity,
            ROUND_OFF,
        ),
        Check::abs(
            format!("max ‖Δε̄(I → Q·E)‖, {n} random Q"),
            0.0,
            d_eps_rigid,
            ROUND_OFF,
        ),
        Check::abs(
            format!("max ‖U(QF) − U(F)‖/‖U‖, {n} F, Q"),
            0.0,
            du,
            ROUND_OFF,
        ),
        Check::abs(format!("max ‖Δε̄(F → QF)‖, {n} F, Q"), 0.0, d_eps, ROUND_OFF),
        Check::abs(
            format!("max ‖Δτ̄‖/E_m, resin over F → QF, {n}"),
            0.0,
            d_tau,
            ROUND_OFF,
        ),
        Check::abs(
            format!("max ‖R(QF) − Q·R(F)‖, {n} F, Q"),
            0.0,
            dr,
            ROUND_OFF,
        ),
        Check::abs(
            format!("max ‖P(QF) − Q·P(F)‖/‖P‖, same τ̄, {n}"),
            0.0,
            dp,
            ROUND_OFF,
        ),
    ]
}

/// Closed forms of a few operations on O(1) values: a few ulps.
const FEW_ULPS: f64 = 1e-14;

fn pure_shear() -> Vec<Check> {
    let mut checks = Vec::new();
    for deg in [10.0f64, 30.0, 50.0, 60.0] {
        let gamma = deg.to_radians();
        // Trellising of a pin-jointed net: both yarns rotate by γ/2 towards
        // each other without stretching.
        let (s, c) = (gamma / 2.0).sin_cos();
        let f = Matrix3x2::new(c, s, s, c, 0.0, 0.0);
        let warp = fibre_stretch(&f, &Vector2::x()).expect("warp");
        let weft = fibre_stretch(&f, &Vector2::y()).expect("weft");
        let got = shear_angle(
            &warp.direction,
            &weft.direction,
            std::f64::consts::FRAC_PI_2,
        );
        checks.push(Check::rel(
            format!("γ (°), pure shear {deg}°"),
            deg,
            got.to_degrees(),
            FEW_ULPS,
        ));
        checks.push(Check::abs(
            format!("λ warp, pure shear {deg}°"),
            1.0,
            warp.stretch,
            FEW_ULPS,
        ));
        checks.push(Check::abs(
            format!("λ weft, pure shear {deg}°"),
            1.0,
            weft.stretch,
            FEW_ULPS,
        ));
    }
    checks
}

fn uniaxial() -> Vec<Check> {
    let mut checks = Vec::new();
    // ε is checked absolutely: near λ = 1, ln λ is ill-conditioned relatively
    // (a 1-ulp error in the truss length is 10⁻¹³ of ln 1.001).
    for lambda in [0.7f64, 1.001, 1.3, 2.5] {
        let f = Matrix3x2::new(lambda, 0.0, 0.0, 1.0, 0.0, 0.0);
        let warp = fibre_stretch(&f, &Vector2::x()).expect("warp");
        let weft = fibre_stretch(&f, &Vector2::y()).expect("weft");
        let u = polar_decomposition(&f).expect("stretch").u;
        // A truss of length 3 along an oblique direction, away from the origin.
        let dir = Vector3::new(1.0, -2.0, 2.0) / 3.0;
        let x1 = Vector3::new(1.0, 2.0, 3.0);
        let truss = truss_stretch(&x1, &(x1 + dir * (3.0 * lambda)), 3.0).expect("truss");
        let gamma = shear_angle(
            &warp.direction,
            &weft.direction,
            std::f64::consts::FRAC_PI_2,
        );
        checks.extend([
            Check::rel(
                format!("λ warp, λ = {lambda}"),
                lambda,
                warp.stretch,
                FEW_ULPS,
            ),
            Check::abs(
                format!("ε = ln λ warp, λ = {lambda}"),
                lambda.ln(),
                warp.log_strain,
                FEW_ULPS,
            ),
            Check::abs(format!("λ weft, λ = {lambda}"), 1.0, weft.stretch, FEW_ULPS),
            Check::rel(format!("U₁₁, λ = {lambda}"), lambda, u[(0, 0)], FEW_ULPS),
            Check::abs(format!("U₁₂, λ = {lambda}"), 0.0, u[(0, 1)], FEW_ULPS),
            Check::abs(format!("U₂₂, λ = {lambda}"), 1.0, u[(1, 1)], FEW_ULPS),
            Check::abs(format!("γ (rad), λ = {lambda}"), 0.0, gamma, FEW_ULPS),
            Check::rel(
                format!("λ truss, λ = {lambda}"),
                lambda,
                truss.stretch,
                FEW_ULPS,
            ),
            Check::abs(
                format!("ε = ln λ truss, λ = {lambda}"),
                lambda.ln(),
                truss.log_strain,
                FEW_ULPS,
            ),
        ]);
    }
    checks
}

/// Σ Δε̄₁₁ over `n` equal stretch increments from 1 to `lambda`, with the
/// body turning through `turn` radians about an oblique axis on the way
/// (0: no rotation), and the largest |Δε̄₁₂|, |Δε̄₂₂| met.
fn integrate_stretch(lambda: f64, n: usize, turn: f64) -> (f64, f64) {
    let axis = Unit::new_normalize(Vector3::new(1.0, 2.0, -0.5));
    let state = |k: usize| {
        let s = k as f64 / n as f64;
        let stretch = Matrix2::new(1.0 + (lambda - 1.0) * s, 0.0, 0.0, 1.0);
        let f = Rotation3::from_axis_angle(&axis, turn * s).matrix() * embed() * stretch;
        polar_decomposition(&f).expect("stretch").u
    };
    let (mut sum, mut off) = (0.0, 0f64);
    let mut u_n = state(0);
    for k in 1..=n {
        let u = state(k);
        let d = rotated_strain_increment(&u_n, &u);
        sum += d[(0, 0)];
        off = off.max(d[(0, 1)].abs()).max(d[(1, 1)].abs());
        u_n = u;
    }
    (sum, off)
}

fn strain_increment_order() -> Vec<Check> {
    let lambda = 1.5f64;
    let exact = lambda.ln();
    let ns = [10usize, 20, 40, 80, 160, 320, 640];
    let errors: Vec<f64> = ns
        .iter()
        .map(|&n| exact - integrate_stretch(lambda, n, 0.0).0)
        .collect();
    let mut checks = Vec::new();
    // Per step the midpoint rule gives 2u for ln r = 2 atanh u,
    // u = h/(2 l_mid): the error is h³/(12 l³) + O(h⁵); summed,
    // e_n = h²(1 − λ⁻²)/24 + O(h⁴) with h = (λ − 1)/n. So the observed order
    // is 2 + O(h²) (≤ 0.01 off from n = 10 on), and n²·e_n tends to
    // (λ − 1)²(1 − λ⁻²)/24 with an O(h²) ≈ 10⁻⁶ relative deviation at n = 640.
    for (i, pair) in errors.windows(2).enumerate() {
        let order = (pair[0] / pair[1]).log2();
        checks.push(Check::abs(
            format!("observed order, n = {} → {}", ns[i], ns[i + 1]),
            2.0,
            order,
            0.01,
        ));
    }
    let n = *ns.last().expect("n");
    let coefficient = (lambda - 1.0).powi(2) * (1.0 - lambda.powi(-2)) / 24.0;
    checks.push(Check::rel(
        format!("n²·(ln λ − Σ Δε̄₁₁), n = {n}"),
        coefficient,
        (n * n) as f64 * errors[errors.len() - 1],
        1e-4,
    ));
    let (sum, _) = integrate_stretch(lambda, n, 0.0);
    checks.push(Check::abs(
        format!("Σ Δε̄₁₁ → ln {lambda}, n = {n}"),
        exact,
        sum,
        1e-7,
    ));
    // The same path while the body turns 90°: the rotated increments must
    // not see the rotation, up to round-off accumulated over n steps.
    let (turning, off) = integrate_stretch(lambda, n, std::f64::consts::FRAC_PI_2);
    checks.push(Check::abs(
        format!("Σ Δε̄₁₁ turning 90° − not turning, n = {n}"),
        0.0,
        turning - sum,
        1e-12,
    ));
    checks.push(Check::abs(
        format!("max |Δε̄₁₂|, |Δε̄₂₂| turning 90°, n = {n}"),
        0.0,
        off,
        FEW_ULPS,
    ));
    checks
}
