//! `drape fit`: the command line of the material fits (the fitting itself
//! is `drape::fit`).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Subcommand;
use drape::fit::{ForceKind, PictureFrameOptions};

/// The tests `drape fit` turns into a material card.
#[derive(Subcommand)]
pub enum FitTest {
    /// Fit the in-plane shear law (resin.shear_locking) to picture-frame
    /// curves: CSV files of crosshead displacement (mm) and force (N), one
    /// curve a column; several files and columns are fitted at once.
    PictureFrame {
        /// The CSV files (first column displacement in mm, or shear angle
        /// in degrees with --angle or a header naming degrees).
        #[arg(required = true)]
        csv: Vec<PathBuf>,
        /// Frame side L_frame, pin to pin (mm): one for all files, or one
        /// per file (comma-separated).
        #[arg(long, value_delimiter = ',')]
        frame: Vec<f64>,
        /// Fabric side L_fabric (mm), the sheared square: one for all
        /// files, or one per file.
        #[arg(long, value_delimiter = ',')]
        fabric: Vec<f64>,
        /// The first column is the shear angle in degrees.
        #[arg(long)]
        angle: bool,
        /// What the force columns are.
        #[arg(long, value_enum, default_value = "frame")]
        force: ForceKind,
        /// The base material: a preset name or a TOML card (its thickness
        /// turns the force into a stress).
        #[arg(long)]
        material: String,
        /// Number of terms of τ_s = c₁γ + c₃γ³ + … .
        #[arg(long, default_value_t = 3)]
        terms: usize,
        /// Leave out points beyond this shear angle (deg).
        #[arg(long, default_value_t = 60.0)]
        max_angle: f64,
        /// One weight per curve, in order (default: each curve counts once).
        #[arg(long, value_delimiter = ',')]
        weights: Vec<f64>,
        /// The material card to write; the plot (.fit.png) and the
        /// residuals (.residuals.csv) are written beside it.
        #[arg(long)]
        out: PathBuf,
    },
    /// Fit the in-plane shear law to bias-extension curves (clamp force
    /// against crosshead displacement): by drape's own bias-extension runs
    /// in the loop (inverse, the default) or by the ideal three-zone
    /// energy balance.
    BiasExtension {
        /// The CSV files (first column displacement in mm, then one force
        /// column in N per curve).
        #[arg(required = true)]
        csv: Vec<PathBuf>,
        /// Specimen length between the grips H (mm).
        #[arg(long)]
        height: f64,
        /// Specimen width W (mm), H ≥ 2W.
        #[arg(long)]
        width: f64,
        /// The base material: a preset name or a TOML card.
        #[arg(long)]
        material: String,
        /// Number of terms of τ_s = c₁γ + c₃γ³ + … .
        #[arg(long, default_value_t = 3)]
        terms: usize,
        /// Leave out points beyond this central shear angle (deg); 40 by
        /// default: the benchmark's curves fitted only to 30° give a law
        /// that softens beyond, which a card cannot hold.
        #[arg(long, default_value_t = 40.0)]
        max_angle: f64,
        /// The material card to write (plot and residuals beside it).
        #[arg(long)]
        out: PathBuf,
        /// `inverse`: Levenberg–Marquardt with drape's runs of the
        /// specimen in the loop, started from the three-zone fit (both
        /// reported); `three-zone`: the ideal balance only.
        #[arg(long, value_enum, default_value = "inverse")]
        method: drape::fit_bias::Method,
        /// Add the friction term τ_f·tanh(γ/γ_f) to the law (a dry
        /// fabric's early jump in force).
        #[arg(long)]
        friction: bool,
        /// One weight per curve, in order (default: each curve counts once).
        #[arg(long, value_delimiter = ',')]
        weights: Vec<f64>,
        /// Inverse: cell diagonals across the specimen's width in the runs
        /// (the length gets H/W times as many).
        #[arg(long, default_value_t = 10)]
        cells: usize,
        /// Inverse: run the fitted law again on twice the cells and report
        /// how much the force moves (the mesh's error).
        #[arg(long)]
        mesh_check: bool,
    },
}

/// Runs `drape fit …`; `bad` makes a bad-input error (exit 2).
pub fn run(test: FitTest, bad: fn(String) -> anyhow::Error) -> Result<ExitCode> {
    match test {
        FitTest::PictureFrame {
            csv,
            frame,
            fabric,
            angle,
            force,
            material,
            terms,
            max_angle,
            weights,
            out,
        } => {
            let base = drape::fit::base_material(&material).map_err(|e| bad(e.to_string()))?;
            let options = PictureFrameOptions {
                inputs: csv,
                frame,
                fabric,
                angle,
                force,
                terms,
                max_angle,
                weights,
            };
            let (fit, card) =
                drape::fit::picture_frame(&options, &base).map_err(|e| bad(e.to_string()))?;
            let (plot, residuals) = drape::fit::write_outputs(&out, &fit, &card)
                .map_err(|e| anyhow::anyhow!("writing the fit: {e}"))?;
            print!("{}", fit.report());
            println!(
                "wrote {} (material card), {} (plot), {} (residuals)",
                out.display(),
                plot.display(),
                residuals.display()
            );
            Ok(ExitCode::SUCCESS)
        }
        FitTest::BiasExtension {
            csv,
            height,
            width,
            material,
            terms,
            max_angle,
            out,
            method,
            friction,
            weights,
            cells,
            mesh_check,
        } => {
            let base = drape::fit::base_material(&material).map_err(|e| bad(e.to_string()))?;
            let specimen = drape::fit_bias::Specimen { height, width };
            let options = drape::fit_bias::BiasOptions {
                method,
                terms,
                friction,
                max_angle,
                weights,
                cells,
                mesh_check,
            };
            let report = drape::fit_bias::run(&csv, specimen, &base, &options, &out)
                .map_err(|e| bias_fit_error(e, bad))?;
            print!("{report}");
            println!(
                "wrote {} (material card), .fit.png and .residuals.csv beside it",
                out.display()
            );
            Ok(ExitCode::SUCCESS)
        }
    }
}

/// A bias-extension fit's error as the command reports it: bad input
/// through `bad` (exit 2); a fit that failed on good input (an inner
/// simulation, an unusable law, an output not written) as a failed run
/// (exit 1), so a sweep or a script can tell the two apart.
fn bias_fit_error(
    e: drape::fit_bias::BiasFitError,
    bad: fn(String) -> anyhow::Error,
) -> anyhow::Error {
    match e {
        drape::fit_bias::BiasFitError::Input(e) => bad(e.to_string()),
        failed => anyhow::anyhow!(failed),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drape::fit::FitInputError;
    use drape::fit_bias::BiasFitError;

    #[derive(Debug)]
    struct Bad;
    impl std::fmt::Display for Bad {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "bad")
        }
    }
    impl std::error::Error for Bad {}

    /// Only an input error takes the bad-input path.
    #[test]
    fn a_failed_fit_is_not_bad_input() {
        let bad: fn(String) -> anyhow::Error = |m| anyhow::Error::new(Bad).context(m);
        let input = bias_fit_error(
            BiasFitError::Input(FitInputError {
                file: "a.csv".into(),
                line: Some(3),
                message: "NaN".into(),
            }),
            bad,
        );
        assert!(input.downcast_ref::<Bad>().is_some());
        assert_eq!(input.to_string(), "a.csv: line 3: NaN");
        let failed = bias_fit_error(
            BiasFitError::Failed("the inverse fit failed: diverged".into()),
            bad,
        );
        assert!(failed.downcast_ref::<Bad>().is_none());
        assert_eq!(failed.to_string(), "the inverse fit failed: diverged");
    }
}
