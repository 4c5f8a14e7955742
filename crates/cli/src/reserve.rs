//! A summary even on a full disk: a run claims the room for its
//! `summary.json` before it starts (a hidden file of [`RESERVE_BYTES`],
//! `.summary.reserve`), and gives it back just before it writes the
//! summary, so the summary fits where the frames, pictures or CSV files
//! filled the disk. A write that fails on a full disk is recorded in the
//! summary (status "failed", the reason saying "disk full"), and `drape
//! inspect` tells such a run from one that was killed: a killed run leaves
//! its reserve and no summary.
//!
//! Not here: writing the files themselves (drape-io's `ResultsDir`, whole
//! or not at all).

use std::io::{ErrorKind, Write};
use std::path::{Path, PathBuf};

use drape_io::results::ResultsError;

/// The room kept for the summary: 64 KiB, ten times a summary with a
/// dozen long warnings (the shipped scenes' are 3 to 5 KiB).
pub const RESERVE_BYTES: usize = 64 * 1024;

/// The reserve's file name in a results folder.
pub const RESERVE_NAME: &str = ".summary.reserve";

/// The room claimed for a run's summary, given back by [`Self::release`].
pub struct SummaryReserve {
    path: PathBuf,
}

impl SummaryReserve {
    /// Claims [`RESERVE_BYTES`] in the results folder `dir` (written and
    /// synced, so the file system has allocated them). A disk without that
    /// room is an error naming the folder.
    pub fn claim(dir: &Path) -> Result<Self, ResultsError> {
        let path = dir.join(RESERVE_NAME);
        let written = (|| {
            let mut file = std::fs::File::create(&path)?;
            file.write_all(&[0u8; RESERVE_BYTES])?;
            file.sync_all()
        })();
        match written {
            Ok(()) => Ok(Self { path }),
            Err(source) => {
                let _ = std::fs::remove_file(&path);
                Err(ResultsError { path, source })
            }
        }
    }

    /// Gives the room back, just before the summary is written.
    pub fn release(self) {}
}

/// A run that returns early (an error before it ran) gives the room back
/// too; only a killed process leaves it.
impl Drop for SummaryReserve {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Whether `e` is the disk (or the user's quota) being full.
pub fn is_disk_full(e: &ResultsError) -> bool {
    matches!(
        e.source.kind(),
        ErrorKind::StorageFull | ErrorKind::QuotaExceeded
    )
}

/// The summary's reason for a run whose results could not all be
/// written: "disk full" first where that is why.
pub fn write_failure(e: &ResultsError) -> String {
    if is_disk_full(e) {
        format!(
            "disk full: writing {} failed ({}); the files written before are whole, the rest \
             is missing. Free space (or give another --out) and run again",
            e.path.display(),
            e.source
        )
    } else {
        format!(
            "writing {} failed ({}); the files written before are whole, the rest is missing",
            e.path.display(),
            e.source
        )
    }
}

/// Why the results folder `dir` has no summary, when a run started there
/// (its reserve is there): still running (it holds the folder's lock), or
/// killed. None when no run left a reserve.
pub fn unfinished(dir: &Path) -> Option<String> {
    if !dir.join(RESERVE_NAME).is_file() {
        return None;
    }
    Some(match drape_io::results::OutputLock::acquire(dir) {
        Err(e) if e.source.kind() == ErrorKind::ResourceBusy => {
            "a run is writing here now: its summary comes when it ends".to_owned()
        }
        _ => "a run started here and was killed (or its machine stopped) before it wrote a \
              summary (a run that fills the disk still writes one, saying \"disk full\"); the \
              frames it wrote are whole"
            .to_owned(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reserve_takes_its_room_and_gives_it_back() {
        let dir = std::env::temp_dir().join(format!("drape-reserve-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let reserve = SummaryReserve::claim(&dir).unwrap();
        let path = dir.join(RESERVE_NAME);
        assert_eq!(
            std::fs::metadata(&path).unwrap().len(),
            RESERVE_BYTES as u64
        );
        reserve.release();
        assert!(!path.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_full_disk_is_named_in_the_reason() {
        let full = ResultsError {
            path: PathBuf::from("out/frames/frame_00003.vtu"),
            source: std::io::Error::from(ErrorKind::StorageFull),
        };
        assert!(write_failure(&full).starts_with("disk full: writing out/frames/frame_00003.vtu"));
        let denied = ResultsError {
            path: PathBuf::from("out/energy.csv"),
            source: std::io::Error::from(ErrorKind::PermissionDenied),
        };
        assert!(!write_failure(&denied).contains("disk full"));
    }
}
