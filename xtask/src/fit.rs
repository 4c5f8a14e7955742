//! `cargo xtask fit-shear`: a shear-locking law from a picture-frame curve,
//! written as a material card a scene can use (`fabric.material = { … }`,
//! or pasted into a scene file).
//!
//! The procedure: a CSV of `shear angle (deg), frame force (N)` (the form
//! labs publish), the frame's side L and the base material (a preset name
//! or a TOML card) whose thickness h converts force to stress,
//! τ_s = F·sin(π/4 − γ/2)/(h·L); an odd polynomial of `--terms` terms
//! fitted by weighted least squares (`ShearLocking::fit_stresses`); the base
//! material with `resin.shear_locking` set, printed or written to `--out`.
//!
//! Kept for scripts that call it: the user command is `drape fit
//! picture-frame` (different frame and fabric sizes, displacement input,
//! several curves, plot and residuals), and this task runs its code.

use std::path::PathBuf;

/// Parsed arguments.
#[derive(Debug, PartialEq)]
pub struct Options {
    csv: PathBuf,
    side: f64,
    base: String,
    terms: usize,
    out: Option<PathBuf>,
}

impl Options {
    /// `CSV --side L --material PRESET|card.toml [--terms N] [--out FILE]`.
    pub fn parse(args: &[String]) -> Result<Self, String> {
        let mut csv = None;
        let (mut side, mut base, mut terms, mut out) = (None, None, 3, None);
        let mut it = args.iter();
        while let Some(a) = it.next() {
            let mut value = |name: &str| {
                it.next()
                    .cloned()
                    .ok_or_else(|| format!("`{name}` needs a value"))
            };
            match a.as_str() {
                "--side" => {
                    let v = value("--side")?;
                    side = Some(v.parse::<f64>().map_err(|_| {
                        format!("--side `{v}`: expected the frame's side length in mm")
                    })?);
                }
                "--material" => base = Some(value("--material")?),
                "--terms" => {
                    let v = value("--terms")?;
                    terms = v.parse().map_err(|_| {
                        format!("--terms `{v}`: expected a number of terms (1, 2, 3…)")
                    })?;
                }
                "--out" => out = Some(PathBuf::from(value("--out")?)),
                f if f.starts_with("--") => return Err(format!("unknown option `{f}`")),
                f if csv.is_none() => csv = Some(PathBuf::from(f)),
                f => return Err(format!("unexpected argument `{f}`")),
            }
        }
        Ok(Self {
            csv: csv.ok_or("fit-shear needs the picture-frame CSV")?,
            side: side.ok_or("fit-shear needs `--side L` (mm)")?,
            base: base.ok_or("fit-shear needs `--material PRESET|card.toml`")?,
            terms,
            out,
        })
    }
}

/// The material card: the base material with the fitted law, by the same
/// code as `drape fit picture-frame --angle` (frame and fabric of side L).
pub fn card(options: &Options) -> Result<String, String> {
    let base = drape::fit::base_material(&options.base).map_err(|e| e.to_string())?;
    let fit_options = drape::fit::PictureFrameOptions {
        inputs: vec![options.csv.clone()],
        frame: vec![options.side],
        fabric: vec![options.side],
        angle: true,
        force: drape::fit::ForceKind::Frame,
        terms: options.terms,
        max_angle: 90.0,
        weights: vec![],
    };
    let (_, card) = drape::fit::picture_frame(&fit_options, &base).map_err(|e| e.to_string())?;
    Ok(card)
}

/// Runs the task: prints the card, or writes it to `--out` whole.
pub fn main(options: &Options) -> std::process::ExitCode {
    match card(options) {
        Ok(text) => match &options.out {
            None => {
                print!("{text}");
                std::process::ExitCode::SUCCESS
            }
            Some(out) => {
                let tmp = out.with_extension("toml.partial");
                match std::fs::write(&tmp, &text).and_then(|()| std::fs::rename(&tmp, out)) {
                    Ok(()) => std::process::ExitCode::SUCCESS,
                    Err(e) => {
                        eprintln!("error: {}: {e}", out.display());
                        std::process::ExitCode::FAILURE
                    }
                }
            }
        },
        Err(message) => {
            eprintln!("error: {message}");
            std::process::ExitCode::from(2)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drape_constitutive::{Material, ShearLocking};

    #[test]
    fn a_published_style_curve_becomes_a_card_with_its_law() {
        let law = ShearLocking {
            coefficients: vec![0.03, 0.05, 0.8],
            friction: None,
        };
        let glass = Material::preset("glass-serge-4x3").unwrap();
        let dir = std::env::temp_dir().join(format!("drape-fit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let csv = dir.join("frame.csv");
        let mut text = String::from("angle_deg,force_N\n");
        for n in 1..=25 {
            let deg = 2.5 * n as f64;
            text += &format!(
                "{deg},{:.5e}\n",
                law.frame_force(deg.to_radians(), 145.0, glass.thickness)
            );
        }
        std::fs::write(&csv, text).unwrap();
        let args: Vec<String> = [
            csv.to_str().unwrap(),
            "--side",
            "145",
            "--material",
            "glass-serge-4x3",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let card = card(&Options::parse(&args).unwrap()).unwrap();
        let back: Material = toml::from_str(&card).unwrap();
        let fitted = back.resin.shear_locking.unwrap().coefficients;
        for (a, b) in fitted.iter().zip(&law.coefficients) {
            assert!((a - b).abs() < 1e-4, "{fitted:?}");
        }
        assert_eq!(back.fibre, glass.fibre);
        let bad = Options::parse(&["x.csv".to_owned(), "--side".to_owned(), "ten".to_owned()]);
        assert!(bad.unwrap_err().contains("--side `ten`"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
