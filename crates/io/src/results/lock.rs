//! One run per output folder: an advisory lock on a hidden file in it
//! (`.drape.lock`), held while the run writes, so that a second run into
//! the same folder is refused instead of mixing its frames and summary with
//! the first's.
//!
//! The lock is the operating system's (`flock` on Unix, `LockFileEx` on
//! Windows, through `std::fs::File::try_lock`): it goes with the process,
//! so a run that is killed leaves no stale lock, only the (harmless) file.
//! The file holds the holder's process id, for the message.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{ErrorKind, Read, Seek, Write};
use std::path::Path;

use super::ResultsError;

/// The lock file's name in an output folder.
pub const LOCK_FILE: &str = ".drape.lock";

/// Retries, 10 ms apart, before a held lock is reported busy.
const LOCK_RETRIES: usize = 50;

/// A claim on an output folder, held until dropped.
#[derive(Debug)]
pub struct OutputLock {
    _file: Option<File>,
}

impl OutputLock {
    /// Creates `dir` if needed and takes its lock. Another process holding
    /// it is an error of kind [`ErrorKind::ResourceBusy`] naming `dir` and
    /// the holder's process id. On a file system without locks the folder
    /// is used unlocked.
    pub fn acquire(dir: &Path) -> Result<Self, ResultsError> {
        let at = |source| ResultsError {
            path: dir.to_owned(),
            source,
        };
        std::fs::create_dir_all(dir).map_err(at)?;
        let path = dir.join(LOCK_FILE);
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(at)?;
        // A lock just released can still be held for a moment by a child
        // process forked (by another thread of the same program) before it
        // closed the inherited descriptor at exec: retry briefly before
        // calling the folder busy.
        let mut attempt = file.try_lock();
        for _ in 0..LOCK_RETRIES {
            if !matches!(attempt, Err(TryLockError::WouldBlock)) {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
            attempt = file.try_lock();
        }
        match attempt {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let mut holder = String::new();
                let _ = file.read_to_string(&mut holder);
                let who = holder
                    .trim()
                    .parse::<u32>()
                    .map(|pid| format!(" (process {pid})"))
                    .unwrap_or_default();
                return Err(at(std::io::Error::new(
                    ErrorKind::ResourceBusy,
                    format!("another drape run{who} is writing into this folder"),
                )));
            }
            Err(TryLockError::Error(e)) if e.kind() == ErrorKind::Unsupported => {
                return Ok(Self { _file: None });
            }
            Err(TryLockError::Error(e)) => return Err(at(e)),
        }
        // Who holds it, for a second run's message; not needed for the lock.
        let _ = file
            .set_len(0)
            .and_then(|()| file.rewind())
            .and_then(|()| write!(file, "{}", std::process::id()))
            .and_then(|()| file.flush());
        Ok(Self { _file: Some(file) })
    }
}
