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
    Case {
        name: "cao2008/bias-extension-inverse",
        quick: true,
        run: bias_extension_inverse,
    },
    Case {
        name: "cao2008/bias-extension-picture-frame-law",
        quick: true,
        run: bias_extension_frame_law,
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

/// The benchmark's 230 × 115 mm bias-extension curves (their file and
/// text), the specimen and the `twintex-plain` preset: what the three
/// bias-extension cases start from.
struct BiasData {
    path: PathBuf,
    text: String,
    specimen: drape::fit_bias::Specimen,
    preset: drape_constitutive::Material,
}

fn bias_data() -> BiasData {
    let path = data("bias_extension_plain_230x115_force.csv");
    let text = std::fs::read_to_string(&path).expect("the benchmark's data are in the repository");
    BiasData {
        path,
        text,
        specimen: drape::fit_bias::Specimen {
            height: 230.0,
            width: 115.0,
        },
        preset: drape_constitutive::Material::preset("twintex-plain").expect("preset"),
    }
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
    use drape::fit_bias::{fit_three_zone, read_bias_curves};
    let BiasData {
        path,
        text,
        specimen,
        preset,
    } = bias_data();
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

/// The digitised curves' reading accuracy in force (N), from the data's
/// README ("≈ 0.05 N"): where the three labs agree more closely than
/// that (±1 % near 10°), the range cannot be read tighter.
const READ_ACCURACY_N: f64 = 0.05;

/// Cell diagonals across the specimen's width: 10 (20 × 10 cells, about
/// 0.8 s a run) in the quick mode, 20 in full (about 6.5 s). The force
/// converges at first order: with the inverse fit's law, 10 → 20 cells
/// raises it by 0.7 % at 10°, 1.3 % at 22° and 1.6 % at 29°.
fn bias_cells() -> usize {
    if super::quick_mode() { 10 } else { 20 }
}

/// (u, γ°, the labs' forces) of the 230 × 115 data with 0 < γ ≤ 30°.
fn bias_rows(text: &str, specimen: drape::fit_bias::Specimen) -> Vec<(f64, f64, Vec<f64>)> {
    text.lines()
        .skip(1)
        .filter_map(|line| {
            let v: Vec<f64> = line
                .split(',')
                .filter_map(|f| f.trim().parse().ok())
                .collect();
            let g = specimen.gamma(v[0])?.to_degrees();
            (g > 0.0 && g <= BIAS_CHECKED && v.len() == 4).then(|| (v[0], g, v[1..].to_vec()))
        })
        .collect()
}

fn range(v: &[f64]) -> (f64, f64) {
    v.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        })
}

/// `cao2008/bias-extension-inverse` (issue case 2): the law fitted by
/// `drape fit bias-extension --method inverse --friction --terms 2` (drape's
/// own runs of the 230 × 115 specimen in the loop, the three labs at
/// once, to 40°) must reproduce the labs' clamp force within their range
/// (min..max), widened by the curves' reading accuracy, at every
/// displacement up to 30° of central shear. The table says where the fit
/// is strictly inside the range. Two polynomial terms with the friction
/// term: with three, the fit's c₅ goes negative and the law softens
/// beyond the data until the card's check (tangent ≥ 0 to 85°) stops it.
fn bias_extension_inverse() -> Vec<Check> {
    use drape::fit_bias::read_bias_curves;
    use drape::fit_inverse::{InverseOptions, LawForm, fit};
    let BiasData {
        path,
        text,
        specimen,
        preset: base,
    } = bias_data();
    let curves =
        read_bias_curves(std::slice::from_ref(&path), specimen, MAX_ANGLE).expect("readable");
    let options = InverseOptions {
        form: LawForm {
            terms: 2,
            friction: true,
        },
        cells: bias_cells(),
        step: 1.0,
        weights: vec![],
        mesh_check: !super::quick_mode(),
    };
    let fit = fit(curves, specimen, &base, &options).expect("the inverse fit succeeds");
    let mut checks = Vec::new();
    let [nx, ny] = fit.test.mesh();
    let mut table = format!(
        "Bias extension 230 × 115 mm, three labs: the law fitted by simulation (`drape fit \
         bias-extension --method inverse --friction --terms 2`, {nx} × {ny} cells, to 40°) against \
         the labs' clamp force (N); {} simulations, {} iterations, {:.1} s wall. The three-zone \
         fit of the same form, by the ideal balance, beside it.\n\n\
         | u (mm) | γ (deg) | min | median | max | inverse fit | − median | in range | \
         three-zone fit | − median |\n|---:|---:|---:|---:|---:|---:|---:|:---:|---:|---:|\n",
        fit.simulations, fit.iterations, fit.seconds
    );
    let mut strict = 0;
    let rows = bias_rows(&text, specimen);
    for (u, g, labs) in &rows {
        let (lo, hi) = range(labs);
        let mid = median(labs);
        let f = fit.curve.at(*u);
        let t = fit.three_zone_force(*u);
        let room = if f >= mid { hi - mid } else { mid - lo };
        checks.push(Check::abs(
            format!(
                "clamp force at u = {u} mm (γ = {g:.1}°), N: inverse fit vs the labs' median, within \
                 their range [{lo:.3}, {hi:.3}] ± {READ_ACCURACY_N} N"
            ),
            mid,
            f,
            room + READ_ACCURACY_N,
        ));
        let inside = (lo..=hi).contains(&f);
        strict += usize::from(inside);
        let _ = writeln!(
            table,
            "| {u} | {g:.1} | {lo:.3} | {mid:.3} | {hi:.3} | {f:.3} | {:+.1} % | {} | {t:.3} | {:+.1} % |",
            100.0 * (f - mid) / mid,
            if inside { "yes" } else { "no" },
            100.0 * (t - mid) / mid
        );
    }
    let _ = write!(
        table,
        "\nStrictly inside the labs' range: {strict} of {}.\n\n```\n{}```\n",
        rows.len(),
        fit.report()
    );
    note(table);
    checks
}

/// `cao2008/bias-extension-picture-frame-law` (issue case 3): drape's run
/// of the 230 × 115 bias extension with the picture-frame law
/// (`twintex-plain`), against the labs' clamp force. Its error is
/// reported, not checked: the frames store 2–4 times the bias
/// extension's energy per area at the same shear, whatever the model
/// (see the note). Checked: the run is quasi-static (the fixed grip
/// holds what the moving one pulls, within 0.1 %) and, with the law
/// the frames give, within 3 % of the three-zone balance of the same law
/// (the idealisation the frames' normalisation shares).
fn bias_extension_frame_law() -> Vec<Check> {
    use drape::bias_sim::VirtualTest;
    let BiasData {
        path,
        text,
        specimen,
        preset: base,
    } = bias_data();
    let law = base
        .resin
        .shear_locking
        .clone()
        .expect("twintex-plain has its law");
    let test = VirtualTest {
        specimen,
        cells: bias_cells(),
        u_max: 25.0,
        step: 1.0,
    };
    let curve = test.run(&base).expect("the run completes");
    let [nx, ny] = test.mesh();
    let mut checks = Vec::new();
    let mut table = format!(
        "Bias extension 230 × 115 mm predicted by drape's run ({nx} × {ny} cells) with the \
         picture-frame law (`twintex-plain`), against the labs' clamp force (N).\n\n\
         | u (mm) | γ (deg) | median | simulated | error | three-zone balance | sim/balance |\n\
         |---:|---:|---:|---:|---:|---:|---:|\n"
    );
    let mut errors = Vec::new();
    let scale = curve.force.iter().fold(0.0f64, |a, f| a.max(f.abs()));
    for (u, g, labs) in bias_rows(&text, specimen) {
        let mid = median(&labs);
        let f = curve.at(u);
        let k = curve
            .u
            .iter()
            .position(|&x| (x - u).abs() < 1e-9)
            .expect("an output at u");
        let t = specimen.force(&law, base.thickness, u);
        checks.push(Check::abs(
            format!(
                "u = {u} mm: fixed grip's force against the pulled grip's (quasi-static: within \
                 0.1 % of the run's largest force), N"
            ),
            curve.force[k],
            curve.held[k],
            1e-3 * scale,
        ));
        if g >= 5.0 {
            checks.push(Check::rel(
                format!("u = {u} mm (γ = {g:.1}°): simulated force against the three-zone balance of the same law, N"),
                t,
                f,
                0.03,
            ));
        }
        errors.push((u, 100.0 * (f - mid) / mid));
        let _ = writeln!(
            table,
            "| {u} | {g:.1} | {mid:.3} | {f:.3} | {:+.0} % | {t:.3} | {:.3} |",
            100.0 * (f - mid) / mid,
            f / t
        );
    }
    let at = |u: f64| errors.iter().find(|e| e.0 == u).map_or(f64::NAN, |e| e.1);
    let (lo, hi) = range(&errors.iter().map(|e| e.1).collect::<Vec<_>>());
    // The energy per area each test gives at the same shear: the frames'
    // law against the bias extension's own (its three-zone fit of the
    // inverse fit's form, computed here; case 2 puts the inverse fit
    // 4–16 % below it).
    let curves =
        drape::fit_bias::read_bias_curves(std::slice::from_ref(&path), specimen, MAX_ANGLE)
            .expect("readable");
    let form = drape::fit_inverse::LawForm {
        terms: 2,
        friction: true,
    };
    let (bias, _) =
        drape::fit_inverse::three_zone(&curves, &[], specimen, base.thickness, form).expect("fit");
    let ratio = |g: f64| law.energy(g.to_radians()) / bias.energy(g.to_radians());
    // The labs' own curves in the benchmark's normalisation, both per unit
    // area (`Specimen::normalised` is the frames' F_s·L_frame/L_fabric² for
    // one law, tested): the bias median against the frames' median.
    let all = bias_rows(&text, specimen);
    let median_curve = |u: f64| {
        let mut prev = (0.0, 0.0);
        for (x, _, labs) in &all {
            let m = median(labs);
            if *x >= u {
                return prev.1 + (u - prev.0) / (x - prev.0) * (m - prev.1);
            }
            prev = (*x, m);
        }
        f64::NAN
    };
    let frames_text = std::fs::read_to_string(data("picture_frame_plain_normalised.csv"))
        .expect("the benchmark's data are in the repository");
    let frames = lab_rows(&frames_text);
    let _ = write!(
        table,
        "\nThe labs' own curves in the benchmark's energy normalisation (N/mm, per unit area on \
         both sides):\n\n| γ (deg) | bias extension, median curve | picture frames, median | \
         frames / bias |\n|---:|---:|---:|---:|\n"
    );
    for g in [10.0, 20.0, 27.5] {
        let b = specimen.normalised(&median_curve, f64::to_radians(g));
        let f = frames
            .iter()
            .find(|(a, _)| (*a - g).abs() < 1e-9)
            .map_or(f64::NAN, |(_, v)| median(v));
        let _ = writeln!(table, "| {g} | {b:.4} | {f:.4} | {:.1} |", f / b);
    }
    let _ = write!(
        table,
        "\nThe picture-frame law's error against the labs' median is {lo:+.0} % to {hi:+.0} % up to \
         30°: under by 2°, over from 4° on ({:+.0} % at 10.5°, {:+.0} % at 28.8°). It is not the model: drape's run and the three-zone balance of the same law agree \
         within a few per cent (column sim/balance). Nor the normalisation: both sides are the \
         energy per unit reference area h·∫τ dγ (the frames' F_s·L_frame/L_fabric² is that \
         energy's rate per unit area over cos γ, and the bias extension's three-zone balance \
         counts the zones' areas; the benchmark's own bias normalisation of a three-zone curve is the \
         frames' normalised force, h·τ_s/cos γ, to 1e-9: `fit_bias` tests it), and a per-length \
         normalisation of the frames would change them by L_fabric/L_frame = 0.65–0.98, not by 3. \
         The labs' own curves, normalised alike (table above), differ by 2.8–3.7×, and at the same \
         shear the frames' law stores {:.1}× (10°), {:.1}× (20°), {:.1}× (30°) the energy per \
         area of the bias extension's fit: the two tests disagree about the fabric itself. Likely \
         causes, not checked here: a frame's clamps pre-tension and bend the yarns (a slightly \
         misaligned sample reads stiffer), while a bias specimen's yarns can slip at the crossovers.\n",
        at(10.0),
        at(25.0),
        ratio(10.0),
        ratio(20.0),
        ratio(30.0)
    );
    note(table);
    checks
}
