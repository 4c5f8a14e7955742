//! Validation against the woven-fabric benchmark of Cao et al. 2008
//! (Composites A 39, 1037–1053): the plain-weave Twintex tested by six to
//! seven labs. The data, digitised from the paper's figures, are in
//! `tests/data/cao2008/` (its README says what each file is).
//!
//! `cao2008/picture-frame`: the law `drape fit picture-frame` fits to the
//! labs' energy-normalised curves (all labs at once, each curve weighted
//! as a whole) must reproduce the labs' median within the labs' own range
//! (min..max across labs) at every angle of the data up to 40°. The
//! reference side is the data alone (median, min, max per angle); the
//! computed side is `drape::fit`, the user command's code.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::{Case, Check, note};

/// The cases of this module.
pub const CASES: &[Case] = &[
    Case {
        name: "cao2008/picture-frame",
        quick: true,
        run: picture_frame,
    },
    // Not in CI: it fails (21 of 25 points outside the labs' range), a
    // true result kept visible until the inverse fit replaces it.
    Case {
        name: "cao2008/bias-extension-three-zone",
        quick: false,
        run: bias_extension,
    },
];

/// The largest central shear angle checked on the bias extension (deg):
/// the paper trusts crosshead-based angles up to about 30°.
const BIAS_CHECKED: f64 = 30.0;

/// The largest shear angle fitted and checked (deg): the benchmark's labs
/// mostly stop near 40°, where locking begins.
const MAX_ANGLE: f64 = 40.0;

fn data(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/cao2008")
        .join(file)
}

/// (angle, the labs' values at it) from the normalised CSV, 0 < γ ≤ 40°.
fn lab_rows(text: &str) -> Vec<(f64, Vec<f64>)> {
    text.lines()
        .skip(1)
        .filter_map(|line| {
            let mut fields = line.split(',');
            let angle: f64 = fields.next()?.trim().parse().ok()?;
            let values = fields.filter_map(|f| f.trim().parse().ok()).collect();
            (angle > 0.0 && angle <= MAX_ANGLE).then_some((angle, values))
        })
        .collect()
}

fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn picture_frame() -> Vec<Check> {
    let path = data("picture_frame_plain_normalised.csv");
    let text = std::fs::read_to_string(&path).expect("the benchmark's data are in the repository");
    let base = drape_constitutive::Material::preset("twintex-plain").expect("preset");
    let options = drape::fit::PictureFrameOptions {
        inputs: vec![path],
        frame: vec![],
        fabric: vec![],
        angle: true,
        force: drape::fit::ForceKind::Normalised,
        terms: 3,
        max_angle: MAX_ANGLE,
        weights: vec![],
    };
    let (fit, _) = drape::fit::picture_frame(&options, &base).expect("the fit succeeds");
    let mut checks = Vec::new();
    let mut table = String::from(
        "Picture frame, plain weave: the joint fit (3 terms, 7 curves, to 40°) against the labs' \
         normalised shear force F_s·L_frame/L_fabric² (N/mm).\n\n\
         | γ (deg) | labs | min | median | max | fit | fit − median | in range |\n\
         |---:|---:|---:|---:|---:|---:|---:|:---:|\n",
    );
    for (angle, values) in lab_rows(&text) {
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let mid = median(&values);
        let f = fit.normalised(angle);
        // Within [min, max] ⇔ |f − median| ≤ the distance from the median
        // to the range's end on f's side.
        let room = if f >= mid { hi - mid } else { mid - lo };
        checks.push(Check::abs(
            format!(
                "N at {angle}° (N/mm): fit vs the labs' median, within their range [{lo:.4}, {hi:.4}]"
            ),
            mid,
            f,
            room,
        ));
        let _ = writeln!(
            table,
            "| {angle} | {} | {lo:.4} | {mid:.4} | {hi:.4} | {f:.4} | {:+.1} % | {} |",
            values.len(),
            100.0 * (f - mid) / mid,
            if (lo..=hi).contains(&f) { "yes" } else { "no" }
        );
    }
    let _ = write!(
        table,
        "\nPer curve (rms and mean deviation from the joint fit; each curve's own 3-term fit at 10/20/30/40°):\n\n```\n{}```\n",
        fit.report()
    );
    note(table);
    checks
}

/// `cao2008/bias-extension-three-zone`: whether the law fitted to the
/// three labs' 230 × 115 mm curves by the ideal three-zone balance (to
/// 40°, see `drape fit bias-extension`) reproduces the labs' median clamp
/// force within their range up to 30° of central shear; and, reported
/// beside it, the force the picture-frame-fitted law (`twintex-plain`)
/// predicts for this test by the same balance, with its error against
/// the median. It does not: the measured force rises steeply to about
/// 1 N by 5° and then nearly linearly, a shape no odd polynomial through
/// zero follows (the fit is 7–74 % low below 11°, up to 10 % high between
/// 13° and 22°); the checks stay as they are, failing, until a better
/// form or the inverse fit by simulation passes them.
fn bias_extension() -> Vec<Check> {
    use drape::fit_bias::{Specimen, fit_three_zone, read_bias_curves};
    let path = data("bias_extension_plain_230x115_force.csv");
    let text = std::fs::read_to_string(&path).expect("the benchmark's data are in the repository");
    let specimen = Specimen {
        height: 230.0,
        width: 115.0,
    };
    let preset = drape_constitutive::Material::preset("twintex-plain").expect("preset");
    let h = preset.thickness;
    let curves = read_bias_curves(std::slice::from_ref(&path), specimen, 40.0).expect("readable");
    let fit = fit_three_zone(curves, specimen, h, 3).expect("the fit succeeds");
    let frame_law = preset
        .resin
        .shear_locking
        .expect("twintex-plain has its law");
    let mut checks = Vec::new();
    let mut table = String::from(
        "Bias extension 230 × 115 mm, three labs: the three-zone fit (3 terms, to 40°) and the \
         picture-frame law's prediction by the same balance, against the labs' clamp force (N).\n\n\
         | u (mm) | γ (deg) | min | median | max | three-zone fit | fit − median | in range | \
         picture-frame law | its error |\n|---:|---:|---:|---:|---:|---:|---:|:---:|---:|---:|\n",
    );
    for line in text.lines().skip(1) {
        let v: Vec<f64> = line
            .split(',')
            .filter_map(|f| f.trim().parse().ok())
            .collect();
        let (u, labs) = (v[0], &v[1..]);
        let Some(g) = specimen.gamma(u) else { continue };
        let g = g.to_degrees();
        if g <= 0.0 || g > BIAS_CHECKED || labs.len() < 3 {
            continue;
        }
        let (lo, hi) = labs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        let mid = median(labs);
        let f = fit.force(u);
        let room = if f >= mid { hi - mid } else { mid - lo };
        checks.push(Check::abs(
            format!("clamp force at u = {u} mm (γ = {g:.1}°), N: three-zone fit vs the labs' median, within their range [{lo:.3}, {hi:.3}]"),
            mid,
            f,
            room,
        ));
        let p = specimen.force(&frame_law, h, u);
        let _ = writeln!(
            table,
            "| {u} | {g:.1} | {lo:.3} | {mid:.3} | {hi:.3} | {f:.3} | {:+.1} % | {} | {p:.3} | {:+.0} % |",
            100.0 * (f - mid) / mid,
            if (lo..=hi).contains(&f) { "yes" } else { "no" },
            100.0 * (p - mid) / mid
        );
    }
    let _ = write!(
        table,
        "\nThree-zone law: {:?} (MPa, γ in rad, h = {h} mm); picture-frame law (`twintex-plain`): \
         {:?}.\n",
        fit.law.coefficients, frame_law.coefficients
    );
    note(table);
    checks
}
