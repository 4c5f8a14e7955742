//! A diagnosis aid, not an output: with `DRAPE_NEWTON_TRACE=FILE` in the
//! environment the implicit driver records every Newton iteration (every
//! attempt, cut ones included) and writes them to FILE as CSV at the end
//! of the run. What it is for: telling why an increment needs the
//! iterations it does (contact rows entering and leaving, pairs switching
//! between stick and slip, or a residual that falls only linearly with
//! the states settled). Nothing is written without the variable, and a
//! file that cannot be written is reported on stderr, never fails the
//! run.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::NewtonRecord;

/// The environment variable naming the trace file.
pub(super) const VARIABLE: &str = "DRAPE_NEWTON_TRACE";

/// The trace file, when asked for.
pub(super) fn path() -> Option<PathBuf> {
    std::env::var_os(VARIABLE)
        .filter(|p| !p.is_empty())
        .map(PathBuf::from)
}

/// Writes `record` to `path` (whole: to a sibling file, then renamed).
pub(super) fn write(path: &Path, record: &[NewtonRecord]) {
    let partial = path.with_extension("csv.partial");
    let written = std::fs::File::create(&partial).and_then(|file| {
        let mut out = std::io::BufWriter::new(file);
        writeln!(
            out,
            "increment,h,iteration,residual,scale,correction,active_changes,friction_changes,\
             sticking,slipping,slip_lag,worst_contact,penetration,stick_slip,imbalance,\
             step_cosine,step_ratio,step_taken"
        )?;
        for r in record {
            writeln!(
                out,
                "{},{:e},{},{:e},{:e},{:e},{},{},{},{},{:e},{},{:e},{:e},{:e},{},{},{}",
                r.increment,
                r.h,
                r.iteration,
                r.residual,
                r.scale,
                r.correction,
                r.active_changes,
                r.friction_changes,
                r.sticking,
                r.slipping,
                r.slip_lag,
                r.worst_contact,
                r.penetration,
                r.stick_slip,
                r.imbalance,
                r.step_cosine,
                r.step_ratio,
                r.step_taken
            )?;
        }
        out.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        std::fs::rename(&partial, path)
    });
    if let Err(e) = written {
        eprintln!("{VARIABLE}: could not write {}: {e}", path.display());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(iteration: usize, residual: f64) -> NewtonRecord {
        NewtonRecord {
            increment: 3,
            iteration,
            residual,
            scale: 2.0,
            correction: 0.5,
            active_changes: 4,
            friction_changes: 5,
            sticking: 6,
            slipping: 7,
            slip_lag: 0.25,
            worst_contact: 2,
            penetration: 1e-12,
            stick_slip: 0.0,
            imbalance: 0.0,
            h: 1e-3,
            step_cosine: -0.5,
            step_ratio: 0.75,
            step_taken: 1.0,
        }
    }

    /// One line per record under a header naming every column, and the
    /// values as written (the trace is read by scripts).
    #[test]
    fn writes_a_header_and_a_line_per_iteration() {
        let dir = std::env::temp_dir().join(format!("drape-trace-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("newton.csv");
        write(&path, &[record(0, 1.5), record(1, 3e-9)]);
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3, "{text}");
        let header: Vec<&str> = lines[0].split(',').collect();
        let second: Vec<&str> = lines[2].split(',').collect();
        assert_eq!(header.len(), 18);
        assert_eq!(second.len(), header.len());
        let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
        assert_eq!(second[column("iteration")], "1");
        assert_eq!(second[column("residual")].parse::<f64>().unwrap(), 3e-9);
        assert_eq!(second[column("slipping")], "7");
        assert_eq!(second[column("worst_contact")], "2");
        assert_eq!(second[column("step_cosine")].parse::<f64>().unwrap(), -0.5);
        assert!(!path.with_extension("csv.partial").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
