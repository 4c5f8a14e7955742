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
pub const CASES: &[Case] = &[Case {
    name: "cao2008/picture-frame",
    quick: true,
    run: picture_frame,
}];

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
