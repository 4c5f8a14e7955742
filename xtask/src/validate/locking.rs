//! Validation of the shear-locking law (beyond the paper): the picture
//! frame run with and without the law, whose frame forces must differ by
//! the law's own picture-frame curve F(γ) = h·L·τ_s(γ)/sin(π/4 − γ/2),
//! derived here from the coefficients, never from drape's law.

use std::f64::consts::{FRAC_PI_4, SQRT_2};

use drape_constitutive::{Material, ShearLocking};
use drape_time::{Explicit, ExplicitSettings, Frame, Observer};
use nalgebra::Vector3;

use super::{Case, Check};

/// The cases of this module.
pub const CASES: &[Case] = &[Case {
    name: "locking/picture-frame",
    quick: true,
    run: picture_frame,
}];

/// A published-style law: nearly free to ~35°, locking beyond
/// (τ_s = 0.01γ + 0.02γ³ + 0.9γ⁵ MPa).
const LAW: [f64; 3] = [0.01, 0.02, 0.9];

fn smooth_step(xi: f64) -> f64 {
    let xi = xi.clamp(0.0, 1.0);
    xi * xi * xi * (10.0 - 15.0 * xi + 6.0 * xi * xi)
}

struct Frames<F: FnMut(&Frame<'_>)>(F);
impl<F: FnMut(&Frame<'_>)> Observer for Frames<F> {
    fn frame(&mut self, frame: &Frame<'_>) {
        (self.0)(frame)
    }
}

/// The frame force (N) of a 100 mm picture frame on `material` sheared to
/// 60° in 0.05 s, at each of 6 frames: [(γ, F)].
fn frame_forces(material: &Material) -> Vec<(f64, f64)> {
    let (side, gamma_max, duration) = (100.0, 60f64.to_radians(), 0.05);
    let model = super::explicit::picture_frame_model(material, side, 10, gamma_max, duration);
    let pin = Vector3::new(-side / 2.0, -side / 2.0, 0.0);
    let gamma_at = move |t: f64| gamma_max * smooth_step(t / duration);
    let mut samples = Vec::new();
    let mut observer = Frames(|f: &Frame<'_>| {
        if f.index == 0 {
            return;
        }
        let gamma = gamma_at(f.state.time);
        // Frame force along the diagonal by virtual work of the reactions.
        let (s, c) = (gamma / 2.0).sin_cos();
        let (da, db) = (
            Vector3::new(-s, c, 0.0) * 0.5,
            Vector3::new(c, -s, 0.0) * 0.5,
        );
        let power: f64 = (0..f.model.node_count())
            .map(|i| {
                let d = f.model.x0[i] - pin;
                f.reactions[i].dot(&(da * d.x + db * d.y))
            })
            .sum();
        samples.push((gamma, power / (side / SQRT_2 * (c - s))));
    });
    let settings = ExplicitSettings {
        end_time: duration,
        frames: 6,
        ..ExplicitSettings::default()
    };
    let mut state = model.initial_state();
    Explicit::new(&model, settings)
        .expect("driver")
        .run(&mut state, &mut observer)
        .expect("run");
    samples
}

/// Picture frame with the locking law: F_with − F_without against the
/// law's picture-frame curve, 1 %, from 20° on (below, the law's force is
/// a few mN and the difference is the dynamics' noise).
fn picture_frame() -> Vec<Check> {
    let plain = Material::paper_preset("glass-serge-4x3").expect("preset");
    let mut locking = plain.clone();
    locking.resin.shear_locking = Some(ShearLocking {
        coefficients: LAW.to_vec(),
        friction: None,
    });
    let (with, without) = (frame_forces(&locking), frame_forces(&plain));
    let (side, h) = (100.0, plain.thickness);
    let mut checks = Vec::new();
    for (&(gamma, f1), &(_, f0)) in with.iter().zip(&without) {
        let deg = gamma.to_degrees();
        if deg < 20.0 {
            continue;
        }
        let tau = LAW[0] * gamma + LAW[1] * gamma.powi(3) + LAW[2] * gamma.powi(5);
        let reference = h * side * tau / (FRAC_PI_4 - 0.5 * gamma).sin();
        checks.push(Check::rel(
            format!("frame force of the law at γ = {deg:.1}° (N; total {f1:.2} N)"),
            reference,
            f1 - f0,
            0.01,
        ));
    }
    checks
}
