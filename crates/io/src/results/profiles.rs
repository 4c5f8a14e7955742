//! A laminate's shear profiles ply by ply: the rows of its `profiles.csv`
//! and its `profiles_<ply>.png`. One ply's are written by
//! [`super::ResultsDir::write_profiles`] and `write_pictures` themselves,
//! unchanged; this module is only what a stack adds.

use std::fmt::Write as _;
use std::path::Path;

use drape_model::stack::PlyProfiles;

use super::{PlyPicture, ResultsError, fmt_f64, pictures, ply_picture_of, write_png};

/// `profiles.csv` of a laminate: header `ply,line,distance_mm,shear_deg`,
/// each ply (bottom to top) its diagonal then its median, each sorted by
/// signed initial distance from its blank's centre.
pub(super) fn ply_csv(plies: &[PlyProfiles]) -> String {
    let mut csv = String::from("ply,line,distance_mm,shear_deg\n");
    for ply in plies {
        for (line, points) in [("diagonal", &ply.diagonal), ("median", &ply.median)] {
            for p in points {
                let _ = writeln!(
                    csv,
                    "{},{line},{},{}",
                    ply.name,
                    fmt_f64(p.distance),
                    fmt_f64(p.shear_deg)
                );
            }
        }
    }
    csv
}

/// Writes `profiles_<ply>.png` into `dir` for each of `plies`, at `time`.
pub(super) fn write_ply_pictures(
    dir: &Path,
    plies: &[PlyProfiles],
    time: f64,
) -> Result<(), ResultsError> {
    for ply in plies {
        let path = dir.join(ply_picture_of(PlyPicture::Profiles, &ply.name));
        write_png(
            &path,
            pictures::profiles_of(&ply.diagonal, &ply.median, time, Some(&ply.name)),
        )?;
    }
    Ok(())
}
